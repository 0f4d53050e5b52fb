/* mixoct: the order cells are written in (issue 11): grouped by body (the
 * connected parts of the mesh), then by type (tetrahedra, pyramids, prisms,
 * hexahedra), and within those in index order (the mesher's index order is
 * the leaves' Morton order). Readers that make one block per run of a type
 * (meshio, VTK, Gmsh) see at most four blocks a body, and the element tags
 * of a MSH file (its position in this order) rise through the file, as
 * meshio requires. Element lists for re-meshing refer to this order. */
#include <string.h>

#include "base/common.h"
#include "soa/mesh.h"
#include "io/cell_order.h"

enum { CHUNK = 65536 };

/* Union-find over nodes, linking the larger root under the smaller, so the
 * root of every set is its smallest node whatever the thread count. */
static uint32_t uf_find(uint32_t *p, uint32_t a) {
  for (;;) {
    const uint32_t q = __atomic_load_n(&p[a], __ATOMIC_RELAXED);
    if (q == a) return a;
    const uint32_t r = __atomic_load_n(&p[q], __ATOMIC_RELAXED);
    if (r != q) __atomic_compare_exchange_n(&p[a], &(uint32_t){q}, r, 0, __ATOMIC_RELAXED,
                                            __ATOMIC_RELAXED);
    a = q;
  }
}

/* Joins the set of a (a node of it) and the set of root b: the larger of
 * the two under the smaller (a CAS that the larger is still a root), until
 * they are one set; returns a node of the joined set. Every link goes from
 * a larger node to a smaller one, so there is never a cycle, even when a
 * is not a root: a set's root is its smallest node. */
static uint32_t uf_join(uint32_t *p, uint32_t a, uint32_t b) {
  while (a != b) {
    const uint32_t hi = a > b ? a : b, lo = a > b ? b : a;
    uint32_t expect = hi;
    if (__atomic_compare_exchange_n(&p[hi], &expect, lo, 0, __ATOMIC_ACQ_REL, __ATOMIC_RELAXED))
      return lo;
    a = uf_find(p, a);
    b = uf_find(p, b);
  }
  return a;
}

int mx_cell_bodies(const mx_mesh_view *v, int32_t *cell_body, int *nbodies) {
  const size_t nn = v->nnodes, nc = v->ncells;
  *nbodies = 0;
  uint32_t *root = mx_alloc((nn + 1) * sizeof *root);
  if (!root) return MX_ENOMEM;
#pragma omp parallel for schedule(static)
  for (size_t i = 0; i < nn; i++) root[i] = (uint32_t)i;
#pragma omp parallel for schedule(static)
  for (size_t c = 0; c < nc; c++) {
    const uint32_t *row = v->conn + 8 * c;
    /* the set of node 0 found once, then joined with each other node's */
    uint32_t a = uf_find(root, row[0]);
    for (int k = 1; k < mx_cell_nodes[v->type[c]]; k++) a = uf_join(root, a, uf_find(root, row[k]));
  }
#pragma omp parallel for schedule(static)
  for (size_t i = 0; i < nn; i++) root[i] = uf_find(root, (uint32_t)i);
  /* bodies numbered by their smallest node (nodes no cell uses: none) */
  int32_t *num = mx_calloc((nn + 1) * sizeof *num);
  if (!num) {
    mx_free(root);
    return MX_ENOMEM;
  }
#pragma omp parallel for schedule(static)
  for (size_t c = 0; c < nc; c++) __atomic_store_n(&num[root[v->conn[8 * c]]], 1, __ATOMIC_RELAXED);
  int32_t b = 0;
  for (size_t i = 0; i < nn; i++)
    if (num[i]) num[i] = ++b;
#pragma omp parallel for schedule(static)
  for (size_t c = 0; c < nc; c++) cell_body[c] = num[root[v->conn[8 * c]]];
  mx_free(num);
  mx_free(root);
  *nbodies = (int)b;
  return MX_OK;
}

int mx_cells_in_order(const uint8_t *type, const int32_t *body, int nbodies, size_t n,
                      uint32_t *order) {
  const size_t nkeys = 4 * (size_t)(body && nbodies > 0 ? nbodies : 1);
  const size_t nchunks = (n + CHUNK - 1) / CHUNK;
  size_t *cnt = mx_calloc((nkeys * nchunks + 1) * sizeof *cnt);
  if (!cnt) return MX_ENOMEM;
#define KEY(c) ((body && nbodies > 0 ? 4 * (size_t)(body[c] - 1) : 0) + (type[c] & 3u))
#pragma omp parallel for schedule(static)
  for (size_t k = 0; k < nchunks; k++) {
    const size_t end = (k + 1) * CHUNK < n ? (k + 1) * CHUNK : n;
    for (size_t c = k * CHUNK; c < end; c++) cnt[nkeys * k + KEY(c)]++;
  }
  /* exclusive scan, key-major: every chunk's cells of key 0 first */
  size_t at = 0;
  for (size_t q = 0; q < nkeys; q++)
    for (size_t k = 0; k < nchunks; k++) {
      const size_t c = cnt[nkeys * k + q];
      cnt[nkeys * k + q] = at;
      at += c;
    }
#pragma omp parallel for schedule(static)
  for (size_t k = 0; k < nchunks; k++) {
    const size_t end = (k + 1) * CHUNK < n ? (k + 1) * CHUNK : n;
    size_t *pos = cnt + nkeys * k;
    for (size_t c = k * CHUNK; c < end; c++) order[pos[KEY(c)]++] = (uint32_t)c;
  }
#undef KEY
  mx_free(cnt);
  return MX_OK;
}

int mx_cells_by_type(const uint8_t *type, size_t n, uint32_t *order, size_t first[5]) {
  MX_CHECK(mx_cells_in_order(type, NULL, 0, n, order));
  if (first) {
    size_t k = 0;
    for (int t = 0; t < 4; t++) {
      first[t] = k;
      while (k < n && type[order[k]] == t) k++;
    }
    first[4] = n;
  }
  return MX_OK;
}

int mx_cells_written_order(const mx_mesh_view *v, uint32_t *order) {
  int32_t *body = mx_alloc((v->ncells + 1) * sizeof *body);
  if (!body) return MX_ENOMEM;
  int nb = 0;
  int st = mx_cell_bodies(v, body, &nb);
  if (!st) st = mx_cells_in_order(v->type, body, nb, v->ncells, order);
  mx_free(body);
  return st;
}
