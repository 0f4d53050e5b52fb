/* The interfaces between materials: see kernels/interfaces.h. */
#include "kernels/interfaces.h"

#include <string.h>

#include "base/common.h"
#include "kernels/boundary.h"
#include "kernels/mesh_edit.h"

enum { ON = MX_REGION_ON }; /* a node on a shell: no region */

/* The piece of every node of M: ON for the nodes on a shell (state
 * outside), the leaf's for the nodes of a leaf meeting no triangle (one
 * query per leaf, at an element's centroid), a query per node otherwise. */
static int node_pieces(const mx_tree *tr, const uint32_t *leaves, const mx_interfaces *I,
                       const mx_mesh *M, const uint8_t *states, uint16_t *piece,
                       size_t *located) {
  const size_t nn = M->nnodes, nc = M->ncells;
  enum { UNKNOWN = ON - 1 };
  size_t nl = 0;
  for (size_t c = 0; c < nc; c++)
    if (M->leaf[c] + (size_t)1 > nl) nl = M->leaf[c] + (size_t)1;
  int32_t *leaf_piece = mx_alloc((nl + 1) * sizeof *leaf_piece);
  if (!leaf_piece) return MX_ENOMEM;
#pragma omp parallel for schedule(static)
  for (size_t l = 0; l < nl; l++) leaf_piece[l] = -1;
#pragma omp parallel for schedule(static)
  for (size_t v = 0; v < nn; v++) piece[v] = states[v] == MX_NODE_OUTSIDE ? ON : UNKNOWN;
  /* nodes of leaves meeting no triangle (the domain's, the interfaces',
   * the region surfaces'): their leaf's piece (the same value from every
   * such leaf: writes may race benignly) */
#pragma omp parallel for schedule(dynamic, 1024)
  for (size_t c = 0; c < nc; c++) {
    if (tr->oct.tri_cnt[leaves[M->leaf[c]]]) continue;
    const uint32_t *row = M->conn + 8 * c;
    const int nv = mx_cell_nodes[M->type[c]];
    int32_t d = __atomic_load_n(&leaf_piece[M->leaf[c]], __ATOMIC_RELAXED);
    if (d < 0) {
      double p[3] = {0, 0, 0};
      for (int k = 0; k < nv; k++)
        for (int a = 0; a < 3; a++) p[a] += M->xyz[3 * (size_t)row[k] + a] / nv;
      d = mx_interfaces_piece(I, p);
      __atomic_store_n(&leaf_piece[M->leaf[c]], d, __ATOMIC_RELAXED);
    }
    for (int k = 0; k < nv; k++)
      if (__atomic_load_n(&piece[row[k]], __ATOMIC_RELAXED) == UNKNOWN)
        __atomic_store_n(&piece[row[k]], (uint16_t)d, __ATOMIC_RELAXED);
  }
  mx_free(leaf_piece);
  size_t q = 0;
#pragma omp parallel for schedule(dynamic, 1024) reduction(+ : q)
  for (size_t v = 0; v < nn; v++) {
    if (piece[v] != UNKNOWN) continue;
    piece[v] = (uint16_t)mx_interfaces_piece(I, M->xyz + 3 * v);
    q++;
  }
  *located += q;
  return MX_OK;
}

int mx_interface_stage(const mx_tree *tr, const uint32_t *leaves, const mx_surface_index *S,
                       const mx_interfaces *I, mx_mesh *M, uint8_t **states, double alpha,
                       uint16_t **piece_out, uint8_t **fixed_out, mx_interface_stats *stats) {
  memset(stats, 0, sizeof *stats);
  if (fixed_out) *fixed_out = NULL;
  stats->nodes_before = M->nnodes;
  if (piece_out) *piece_out = NULL;
  if (!I || !I->npasses) return MX_OK;
  uint16_t *piece = mx_alloc((M->nnodes + 1) * sizeof *piece);
  uint8_t *outer = mx_alloc(M->nnodes + 1);
  if (!piece || !outer) {
    mx_free(piece);
    mx_free(outer);
    return MX_ENOMEM;
  }
  for (size_t v = 0; v < M->nnodes; v++) outer[v] = (*states)[v] == MX_NODE_OUTSIDE;
  int rc = node_pieces(tr, leaves, I, M, *states, piece, &stats->located);
  for (uint32_t k = 0; k < I->npasses && !rc; k++)
    rc = mx_cleave_interface(M, &piece, &outer, I, I->pass[k], S, alpha, &stats->cleave);
  if (!rc) {
    uint8_t *s2 = mx_realloc(*states, M->nnodes + 1);
    if (!s2) {
      rc = MX_ENOMEM;
    } else {
      *states = s2;
#pragma omp parallel for schedule(static)
      for (size_t v = 0; v < M->nnodes; v++)
        s2[v] = piece[v] == ON ? MX_NODE_OUTSIDE : MX_NODE_INSIDE;
    }
  }
  if (!rc && fixed_out) { /* the nodes on an interface */
    for (size_t v = 0; v < M->nnodes; v++) outer[v] = piece[v] == ON && !outer[v];
    *fixed_out = outer;
    outer = NULL;
  }
  if (!rc && piece_out) {
    *piece_out = piece;
    piece = NULL;
  }
  mx_free(outer);
  mx_free(piece);
  if (!rc) mx_mesh_summarize(M);
  return rc;
}
