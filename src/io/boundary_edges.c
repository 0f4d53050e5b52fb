/* The boundary edges of a 2D mesh (declared in io/plane_mesh.h): the sides
 * no other cell around their first node has; the 2D counterpart of
 * io/boundary_faces.c, for the MSH writer's lines. With bodies (several
 * materials), the edges between two bodies likewise. Also the
 * quadrilateral count the 2D writers size their output with. */
#include <string.h>

#include "base/common.h"
#include "base/scan.h"
#include "io/plane_mesh.h"

enum { PAR_MIN = 16384 }; /* fewer: one thread */

size_t mx_plane_count_quads(const mx_mesh_view *M) {
  size_t nq = 0;
#pragma omp parallel for reduction(+ : nq) schedule(static) if (M->ncells > 65536)
  for (size_t c = 0; c < M->ncells; c++) nq += M->type[c] == MX_CELL_QUAD;
  return nq;
}

/* Whether cell d has the edge {a, b} (either direction). */
static int cell_has_edge(const mx_mesh_view *M, size_t d, uint32_t a, uint32_t b) {
  const uint32_t *r = M->conn + 4 * d;
  const int nv = mx_view_nv2(M, d);
  for (int j = 0; j < nv; j++) {
    const uint32_t p = r[j], q = r[(j + 1) % nv];
    if ((p == a && q == b) || (p == b && q == a)) return 1;
  }
  return 0;
}

/* The cells around each node: CSR (off: nnodes + 1). The order inside a
 * node's list depends on the threads; only membership is asked of it. */
static int node_cells(const mx_mesh_view *M, uint64_t **off_out, uint32_t **ids_out) {
  uint64_t *off = mx_calloc((M->nnodes + 1) * sizeof *off);
  uint64_t *pos = mx_alloc((M->nnodes + 1) * sizeof *pos);
  uint32_t *ids = mx_alloc((4 * M->ncells + 1) * sizeof *ids);
  if (!off || !pos || !ids) {
    mx_free(off), mx_free(pos), mx_free(ids);
    return MX_ENOMEM;
  }
#pragma omp parallel for schedule(static) if (M->ncells > PAR_MIN)
  for (size_t c = 0; c < M->ncells; c++)
    for (int j = 0; j < mx_view_nv2(M, c); j++) {
#pragma omp atomic
      off[M->conn[4 * c + j]]++;
    }
  mx_scan_u64(off, M->nnodes + 1);
  memcpy(pos, off, (M->nnodes + 1) * sizeof *pos);
#pragma omp parallel for schedule(static) if (M->ncells > PAR_MIN)
  for (size_t c = 0; c < M->ncells; c++)
    for (int j = 0; j < mx_view_nv2(M, c); j++) {
      uint64_t k;
#pragma omp atomic capture
      k = pos[M->conn[4 * c + j]]++;
      ids[k] = (uint32_t)c;
    }
  mx_free(pos);
  *off_out = off;
  *ids_out = ids;
  return MX_OK;
}

/* Side s of cell c is a boundary edge: no other cell around its first node
 * has it. */
static int side_alone(const mx_mesh_view *M, const uint64_t *off, const uint32_t *ids, size_t c,
                      int s) {
  const int nv = mx_view_nv2(M, c);
  const uint32_t a = M->conn[4 * c + s], b = M->conn[4 * c + (s + 1) % nv];
  for (uint64_t k = off[a]; k < off[a + 1]; k++)
    if (ids[k] != c && cell_has_edge(M, ids[k], a, b)) return 0;
  return 1;
}

int mx_plane_boundary_edges(const mx_mesh_view *M, uint64_t **out, size_t *nb) {
  uint64_t *off, *cnt = mx_calloc((M->ncells + 1) * sizeof *cnt);
  uint32_t *ids;
  if (!cnt) return MX_ENOMEM;
  int st = node_cells(M, &off, &ids);
  if (st) {
    mx_free(cnt);
    return st;
  }
  uint8_t *mask = mx_alloc(M->ncells + 1);
  if (!mask) st = MX_ENOMEM;
  if (!st) {
#pragma omp parallel for schedule(static) if (M->ncells > PAR_MIN)
    for (size_t c = 0; c < M->ncells; c++) {
      uint8_t m = 0;
      for (int s = 0; s < mx_view_nv2(M, c); s++) m |= (uint8_t)(side_alone(M, off, ids, c, s) << s);
      mask[c] = m;
      cnt[c] = (uint64_t)__builtin_popcount(m);
    }
    *nb = (size_t)mx_scan_u64(cnt, M->ncells);
    *out = mx_alloc((*nb + 1) * sizeof **out);
    if (!*out) st = MX_ENOMEM;
  }
  if (!st) {
#pragma omp parallel for schedule(static) if (M->ncells > PAR_MIN)
    for (size_t c = 0; c < M->ncells; c++) {
      uint64_t k = cnt[c];
      for (int s = 0; s < 4; s++)
        if (mask[c] >> s & 1) (*out)[k++] = 4 * (uint64_t)c + (uint64_t)s;
    }
  }
  mx_free(mask), mx_free(cnt), mx_free(off), mx_free(ids);
  return st;
}

/* Side s of cell c is an interface edge: the cell across it has another
 * body, a higher one (each such edge listed once, from its lower body).
 * Returns that body, or 0. */
static int32_t side_across(const mx_mesh_view *M, const int32_t *body, const uint64_t *off,
                           const uint32_t *ids, size_t c, int s) {
  const int nv = mx_view_nv2(M, c);
  const uint32_t a = M->conn[4 * c + s], b = M->conn[4 * c + (s + 1) % nv];
  for (uint64_t k = off[a]; k < off[a + 1]; k++) {
    const size_t d = ids[k];
    if (d != c && body[d] > body[c] && cell_has_edge(M, d, a, b)) return body[d];
  }
  return 0;
}

int mx_plane_interface_edges(const mx_mesh_view *M, const int32_t *body, uint64_t **out,
                             uint32_t **pair, size_t *n) {
  *out = NULL, *pair = NULL, *n = 0;
  uint64_t *off, *cnt = mx_calloc((M->ncells + 1) * sizeof *cnt);
  uint32_t *ids;
  if (!cnt) return MX_ENOMEM;
  int st = node_cells(M, &off, &ids);
  if (st) {
    mx_free(cnt);
    return st;
  }
  int32_t *across = mx_alloc((4 * M->ncells + 1) * sizeof *across);
  if (!across) st = MX_ENOMEM;
  if (!st) {
#pragma omp parallel for schedule(static) if (M->ncells > PAR_MIN)
    for (size_t c = 0; c < M->ncells; c++) {
      uint64_t k = 0;
      for (int s = 0; s < 4; s++) {
        across[4 * c + s] = s < mx_view_nv2(M, c) ? side_across(M, body, off, ids, c, s) : 0;
        k += across[4 * c + s] != 0;
      }
      cnt[c] = k;
    }
    *n = (size_t)mx_scan_u64(cnt, M->ncells);
  }
  uint64_t *key = st ? NULL : mx_alloc((*n + 1) * sizeof *key);
  if (!st && !key) st = MX_ENOMEM;
  if (!st) { /* by pair (lower body, higher), then cell and side */
#pragma omp parallel for schedule(static) if (M->ncells > PAR_MIN)
    for (size_t c = 0; c < M->ncells; c++) {
      uint64_t k = cnt[c];
      for (int s = 0; s < 4; s++)
        if (across[4 * c + s])
          key[k++] = ((uint64_t)body[c] << 56) | ((uint64_t)(across[4 * c + s] & 0xff) << 48) |
                     (4 * (uint64_t)c + (uint64_t)s);
    }
    st = mx_sort_u64(key, NULL, *n) == MX_OK ? MX_OK : MX_ENOMEM;
  }
  if (!st) {
    *out = mx_alloc((*n + 1) * sizeof **out);
    *pair = mx_alloc((*n + 1) * sizeof **pair);
    if (!*out || !*pair) st = MX_ENOMEM;
  }
  if (!st) {
#pragma omp parallel for schedule(static) if (*n > PAR_MIN)
    for (size_t i = 0; i < *n; i++) {
      (*out)[i] = key[i] & ((1ULL << 48) - 1);
      (*pair)[i] = (uint32_t)(key[i] >> 48);
    }
  } else {
    mx_free(*out), mx_free(*pair);
    *out = NULL, *pair = NULL, *n = 0;
  }
  mx_free(key), mx_free(across), mx_free(cnt), mx_free(off), mx_free(ids);
  return st;
}
