/* The node-moving passes' shared work set (kernels/node_work.h). */
#include "kernels/node_work.h"

#include <string.h>

#include "base/common.h"
#include "base/scan.h"
#include "geom/quality.h"
#include "kernels/boundary.h"
#include "kernels/mesh_edit.h"

double mx_cell_jens(const mx_mesh *M, uint32_t c) {
  double x[8][3];
  const int nv = mx_cell_nodes[M->type[c]];
  for (int k = 0; k < nv; k++)
    memcpy(x[k], M->xyz + 3 * (size_t)M->conn[8 * (size_t)c + k], sizeof x[k]);
  return mx_jens(M->type[c], x);
}

/* Every element sharing a face through v is incident to v, so the incident
 * list [e0, e1) of `inc` is enough; a face counts as shared when another
 * incident element has all its nodes (in a conforming mesh without
 * overlaps, that is the same face). An inside node can lie on the boundary
 * (a lattice node exactly on a flat part of the surface); it must stay
 * there like a surface node.
 *
 * The test runs on the neighbourhood's nodes as bits: its distinct nodes
 * numbered (at most 64, in a small hash table), each element a 64-bit set,
 * a face shared when another element's set holds the face's; a larger
 * neighbourhood searches the other elements' rows instead. */
enum { NB_MAX_CELLS = 128, NB_HASH = 128 };

typedef struct {
  uint32_t key[NB_HASH]; /* node ids, UINT32_MAX: empty */
  uint8_t id[NB_HASH];   /* their numbers */
  uint64_t set[NB_MAX_CELLS];
} node_sets;

static inline unsigned ns_slot(const node_sets *S, uint32_t v) {
  unsigned h = (v * 2654435761u) >> 25; /* 7 bits */
  while (S->key[h] != UINT32_MAX && S->key[h] != v) h = (h + 1) & (NB_HASH - 1);
  return h;
}

/* The sets of the elements [e0, e1); 0 when the neighbourhood is too large. */
static int node_sets_build(const mx_mesh *M, const uint32_t *inc, size_t e0, size_t e1,
                           node_sets *S) {
  if (e1 - e0 > NB_MAX_CELLS) return 0;
  memset(S->key, 0xff, sizeof S->key);
  int nid = 0;
  for (size_t e = e0; e < e1; e++) {
    const uint32_t *row = M->conn + 8 * (size_t)inc[e];
    uint64_t m = 0;
    for (int k = 0; k < mx_cell_nodes[M->type[inc[e]]]; k++) {
      const unsigned h = ns_slot(S, row[k]);
      if (S->key[h] == UINT32_MAX) {
        if (nid == 64) return 0;
        S->key[h] = row[k];
        S->id[h] = (uint8_t)nid++;
      }
      m |= (uint64_t)1 << S->id[h];
    }
    S->set[e - e0] = m;
  }
  return 1;
}

/* Whether an element of [e0, e1) other than c holds the face fv (n nodes) of
 * c (row): with the sets when S is not NULL, else by the rows. */
static int face_shared(const mx_mesh *M, const uint32_t *inc, size_t e0, size_t e1,
                       uint32_t c, const uint32_t *row, const int8_t *fv, int n,
                       const node_sets *S) {
  if (S) {
    uint64_t fm = 0; /* the face's nodes as bits */
    for (int i = 0; i < n; i++) fm |= (uint64_t)1 << S->id[ns_slot(S, row[fv[i]])];
    for (size_t g = e0; g < e1; g++)
      if (inc[g] != c && (S->set[g - e0] & fm) == fm) return 1;
    return 0;
  }
  for (size_t g = e0; g < e1; g++) {
    const uint32_t d = inc[g];
    if (d == c) continue;
    const uint32_t *rd = M->conn + 8 * (size_t)d;
    const int nd = mx_cell_nodes[M->type[d]];
    int all = 1;
    for (int i = 0; i < n && all; i++) {
      const uint32_t w = row[fv[i]];
      int in = 0;
      for (int j = 0; j < nd; j++) in |= rd[j] == w;
      all = in;
    }
    if (all) return 1;
  }
  return 0;
}

int mx_on_mesh_boundary(const mx_mesh *M, const uint32_t *inc, size_t e0, size_t e1,
                        uint32_t v) {
  node_sets sets;
  const node_sets *S = node_sets_build(M, inc, e0, e1, &sets) ? &sets : NULL;
  for (size_t e = e0; e < e1; e++) {
    const uint32_t c = inc[e];
    const int t = M->type[c];
    const uint32_t *row = M->conn + 8 * (size_t)c;
    for (int f = 0; f < mx_cell_nfaces[t]; f++) {
      const int8_t *fv = mx_cell_faces[t][f];
      const int n = fv[3] < 0 ? 3 : 4;
      int has = 0;
      for (int i = 0; i < n; i++) has |= row[fv[i]] == v;
      if (has && !face_shared(M, inc, e0, e1, c, row, fv, n, S)) return 1;
    }
  }
  return 0;
}

int mx_node_work_band_jens(const mx_mesh *M, const mx_node_work *w, double **jd) {
  double *j = mx_alloc((w->nband + 1) * sizeof *j);
  *jd = j;
  if (!j) return MX_ENOMEM;
#pragma omp parallel for schedule(static)
  for (size_t i = 0; i < w->nband; i++) j[i] = mx_cell_jens(M, w->band[i]);
  return MX_OK;
}

void mx_node_work_free(mx_node_work *w) {
  mx_free(w->off);
  mx_free(w->inc);
  mx_free(w->band);
  mx_free(w->pos);
  mx_free(w->work);
  mx_free(w->onsurf);
  mx_free(w->byc);
  memset(w, 0, sizeof *w);
}

/* The marked nodes in id order: counted per block, prefix-summed, filled. */
static int marked_list(const uint8_t *mark, size_t nn, uint32_t **list, size_t *n) {
  size_t nw = 0;
#pragma omp parallel for schedule(static) reduction(+ : nw)
  for (size_t v = 0; v < nn; v++) nw += mark[v] != 0;
  uint32_t *work = mx_alloc((nw + 1) * sizeof *work);
  enum { WB = 1 << 16 };
  const size_t nb = (nn + WB - 1) / WB;
  uint64_t *boff = mx_alloc((nb + 1) * sizeof *boff);
  if (!work || !boff) {
    mx_free(work);
    mx_free(boff);
    return MX_ENOMEM;
  }
#pragma omp parallel for schedule(static)
  for (size_t b = 0; b < nb; b++) {
    uint64_t k = 0;
    for (size_t v = b * WB; v < nn && v < (b + 1) * WB; v++) k += mark[v] != 0;
    boff[b] = k;
  }
  mx_scan_u64(boff, nb);
#pragma omp parallel for schedule(static)
  for (size_t b = 0; b < nb; b++) {
    uint64_t k = boff[b];
    for (size_t v = b * WB; v < nn && v < (b + 1) * WB; v++)
      if (mark[v]) work[k++] = (uint32_t)v;
  }
  mx_free(boff);
  *list = work;
  *n = nw;
  return MX_OK;
}

int mx_node_work_build(const mx_mesh *M, const uint8_t *states, const uint8_t *mark, int ring,
                       const char *what, mx_node_work *w) {
  const size_t nn = M->nnodes, nc = M->ncells;
  memset(w, 0, sizeof *w);
  int st = MX_OK;
  if (ring) { /* incidence for the work nodes and the other nodes of their elements */
    uint8_t *im = mx_calloc(nn + 1);
    if (!im) return MX_ENOMEM;
#pragma omp parallel for schedule(static)
    for (size_t c = 0; c < nc; c++) {
      const int nv = mx_cell_nodes[M->type[c]];
      const uint32_t *row = M->conn + 8 * c;
      int any = 0;
      for (int k = 0; k < nv; k++) any |= mark[row[k]] != 0;
      if (any)
        for (int k = 0; k < nv; k++) __atomic_store_n(&im[row[k]], 1, __ATOMIC_RELAXED);
    }
    st = mx_mesh_incidence_band(M, im, &w->off, &w->inc, &w->band, &w->nband, &w->pos);
    mx_free(im);
  } else {
    st = mx_mesh_incidence_band(M, mark, &w->off, &w->inc, &w->band, &w->nband, &w->pos);
  }
  if (!st) st = marked_list(mark, nn, &w->work, &w->nw);
  const size_t nw = w->nw;
  if (!st && !(w->onsurf = mx_alloc(nw + 1))) st = MX_ENOMEM;
  if (st) {
    mx_node_work_free(w);
    return st;
  }
  /* Which work nodes stay on the surface: the outside ones, and the inside
   * ones on the mesh boundary (the topology does not change below). */
#pragma omp parallel for schedule(dynamic, 1024)
  for (size_t i = 0; i < nw; i++) {
    const uint32_t v = w->work[i];
    w->onsurf[i] = (uint8_t)(!mx_node_inside(states[v]) ||
                             mx_on_mesh_boundary(M, w->inc, w->off[v], w->off[v + 1], v));
  }
  /* Colours, and the work nodes grouped by colour, in id order within one. */
  uint32_t *widx = mx_alloc((nn + 1) * sizeof *widx);
  int16_t *colour = mx_alloc((nw + 1) * sizeof *colour);
  w->byc = mx_alloc((nw + 1) * sizeof *w->byc);
  int ncol = -2; /* -2: out of memory; -1: too many colours */
  if (widx && colour && w->byc) {
#pragma omp parallel for schedule(static)
    for (size_t v = 0; v < nn; v++) widx[v] = UINT32_MAX;
#pragma omp parallel for schedule(static)
    for (size_t i = 0; i < nw; i++) widx[w->work[i]] = (uint32_t)i;
    ncol = mx_colour_nodes(M, w->inc, w->off, w->work, nw, widx, colour);
  }
  mx_free(widx);
  if (ncol < 0) {
    mx_free(colour);
    mx_node_work_free(w);
    if (ncol == -2) return MX_ENOMEM;
    mx_error(NULL, 0, "more than %d colours in the %s", MX_MAX_COLOURS, what);
    return MX_EINPUT;
  }
  w->ncol = ncol;
  for (size_t i = 0; i < nw; i++) w->cstart[colour[i] + 1]++;
  for (int c = 0; c < ncol; c++) w->cstart[c + 1] += w->cstart[c];
  {
    size_t fill[MX_MAX_COLOURS];
    memcpy(fill, w->cstart, sizeof fill);
    for (size_t i = 0; i < nw; i++) w->byc[fill[colour[i]]++] = (uint32_t)i;
  }
  mx_free(colour);
  return MX_OK;
}
