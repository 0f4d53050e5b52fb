/* The interfaces between nested materials: see kernels/interfaces.h. */
#include "kernels/interfaces.h"

#include <string.h>

#include "base/common.h"
#include "kernels/boundary.h"
#include "kernels/mesh_edit.h"

enum { ON = MX_REGION_ON }; /* a node on a shell: no region */

int mx_interfaces_build(mx_interfaces *I, const mx_surface_index *S) {
  memset(I, 0, sizeof *I);
  uint32_t dmax = 0;
  for (uint32_t c = 0; S->shell_depth && c < S->nshells; c++)
    if (S->shell_depth[c] > dmax) dmax = S->shell_depth[c];
  I->deepest = (int)dmax + 1;
  if (I->deepest < 2) return MX_OK;
  I->soup = mx_calloc((size_t)(I->deepest + 1) * sizeof *I->soup);
  I->level = mx_calloc((size_t)(I->deepest + 1) * sizeof *I->level);
  if (!I->soup || !I->level) {
    mx_interfaces_free(I);
    return MX_ENOMEM;
  }
  const mx_trisoup *src = S->soup;
  int st = MX_OK;
  for (int k = 2; k <= I->deepest && !st; k++) {
    mx_trisoup *d = &I->soup[k];
    /* every vertex (their ids kept), the triangles of the shells at depth k - 1 */
    st = mx_trisoup_reserve(d, src->nv, 0);
    for (size_t v = 0; v < src->nv && !st; v++) {
      const double c[3] = {src->x[v], src->y[v], src->z[v]};
      st = mx_trisoup_set_vertex(d, v, c);
    }
    for (uint32_t i = 0; i < S->nt && !st; i++) {
      if (S->shell_depth[S->shell_of[i]] != (uint32_t)(k - 1)) continue;
      const uint32_t *t = src->tri + 3 * (size_t)S->tri_id[i];
      st = mx_trisoup_add_triangle(d, t[0], t[1], t[2]);
    }
    if (!st) st = mx_surface_index_build(&I->level[k], d, 0, (uint32_t)d->nt);
    if (st) st = st == MX_EINPUT ? MX_ENOMEM : st; /* reserve's "too large" */
  }
  if (st) mx_interfaces_free(I);
  return st;
}

void mx_interfaces_free(mx_interfaces *I) {
  for (int k = 2; I->level && k <= I->deepest; k++)
    if (I->level[k].nodes || I->level[k].tri_id) mx_surface_index_free(&I->level[k]);
  for (int k = 2; I->soup && k <= I->deepest; k++) mx_trisoup_free(&I->soup[k]);
  mx_free(I->level);
  mx_free(I->soup);
  memset(I, 0, sizeof *I);
}

/* The region of every node of M: ON for the nodes on a shell (state
 * outside), the leaf's for the nodes of a leaf meeting no triangle (one
 * query per leaf, at an element's centroid), a query per node otherwise. */
static int node_regions(const mx_tree *tr, const uint32_t *leaves, const mx_surface_index *S,
                        const mx_mesh *M, const uint8_t *states, uint16_t *depth,
                        size_t *located) {
  const size_t nn = M->nnodes, nc = M->ncells;
  enum { UNKNOWN = ON - 1 };
  size_t nl = 0;
  for (size_t c = 0; c < nc; c++)
    if (M->leaf[c] + (size_t)1 > nl) nl = M->leaf[c] + (size_t)1;
  int32_t *leaf_depth = mx_alloc((nl + 1) * sizeof *leaf_depth);
  if (!leaf_depth) return MX_ENOMEM;
#pragma omp parallel for schedule(static)
  for (size_t l = 0; l < nl; l++) leaf_depth[l] = -1;
#pragma omp parallel for schedule(static)
  for (size_t v = 0; v < nn; v++) depth[v] = states[v] == MX_NODE_OUTSIDE ? ON : UNKNOWN;
  /* nodes of leaves meeting no triangle: their leaf's region (the same
   * value from every such leaf: writes may race benignly) */
#pragma omp parallel for schedule(dynamic, 1024)
  for (size_t c = 0; c < nc; c++) {
    if (tr->oct.flags[leaves[M->leaf[c]]] & MX_OCT_SURFACE) continue;
    const uint32_t *row = M->conn + 8 * c;
    const int nv = mx_cell_nodes[M->type[c]];
    int32_t d = __atomic_load_n(&leaf_depth[M->leaf[c]], __ATOMIC_RELAXED);
    if (d < 0) {
      double p[3] = {0, 0, 0};
      for (int k = 0; k < nv; k++)
        for (int a = 0; a < 3; a++) p[a] += M->xyz[3 * (size_t)row[k] + a] / nv;
      d = mx_region_depth(S, p);
      if (d > ON - 2) d = ON - 2;
      __atomic_store_n(&leaf_depth[M->leaf[c]], d, __ATOMIC_RELAXED);
    }
    for (int k = 0; k < nv; k++)
      if (__atomic_load_n(&depth[row[k]], __ATOMIC_RELAXED) == UNKNOWN)
        __atomic_store_n(&depth[row[k]], (uint16_t)d, __ATOMIC_RELAXED);
  }
  mx_free(leaf_depth);
  size_t q = 0;
#pragma omp parallel for schedule(dynamic, 1024) reduction(+ : q)
  for (size_t v = 0; v < nn; v++) {
    if (depth[v] != UNKNOWN) continue;
    int d = mx_region_depth(S, M->xyz + 3 * v);
    depth[v] = (uint16_t)(d > ON - 2 ? ON - 2 : d);
    q++;
  }
  *located += q;
  return MX_OK;
}

int mx_interface_stage(const mx_tree *tr, const uint32_t *leaves, const mx_surface_index *S,
                       const mx_interfaces *I, mx_mesh *M, uint8_t **states,
                       double alpha, mx_interface_stats *stats) {
  memset(stats, 0, sizeof *stats);
  if (!I || I->deepest < 2) return MX_OK;
  uint16_t *depth = mx_alloc((M->nnodes + 1) * sizeof *depth);
  if (!depth) return MX_ENOMEM;
  int rc = node_regions(tr, leaves, S, M, *states, depth, &stats->located);
  for (int k = 2; k <= I->deepest && !rc; k++)
    rc = mx_cleave_interface(M, &depth, S, &I->level[k], k, alpha, &stats->cleave);
  if (!rc) {
    uint8_t *s2 = mx_realloc(*states, M->nnodes + 1);
    if (!s2) {
      rc = MX_ENOMEM;
    } else {
      *states = s2;
#pragma omp parallel for schedule(static)
      for (size_t v = 0; v < M->nnodes; v++)
        s2[v] = depth[v] == ON ? MX_NODE_OUTSIDE : MX_NODE_INSIDE;
    }
  }
  mx_free(depth);
  if (!rc) mx_mesh_summarize(M);
  return rc;
}
