/* The walk of geom/feature_walk.h: the edges at each vertex (a CSR built by
 * counting, each vertex's edges in edge order), the corners (flagged, or of
 * degree other than 2), then every chain walked from its first corner and
 * every loop from its least vertex. Linear in vertices plus edges; serial
 * (the lines of a part number in the thousands at most, and their order is
 * the walk's). */
#include "geom/feature_walk.h"

#include <string.h>

#include "base/common.h"

void mx_feature_lines_walk_free(mx_feature_lines *L) {
  mx_free(L->first);
  mx_free(L->xyz);
  mx_free(L->loop);
  mx_free(L->corner);
  memset(L, 0, sizeof *L);
}

typedef struct {
  const double *x, *y, *z;
  size_t stride;
  const uint32_t *edge;
  const size_t *off; /* nv + 1: the edges at vertex v are at[off[v] .. off[v + 1]) */
  const uint32_t *at;
  const uint8_t *stop; /* nv: a corner */
  uint8_t *used;       /* ne */
  mx_feature_lines *L;
  size_t np;           /* points written */
} walk;

static void put_point(walk *W, uint32_t v) {
  const size_t s = W->stride * v;
  double *p = W->L->xyz + 3 * W->np++;
  p[0] = W->x[s];
  p[1] = W->y[s];
  p[2] = W->z[s];
}

/* The other edge at v (of degree 2) than e. */
static uint32_t other_edge(const walk *W, uint32_t v, uint32_t e) {
  const uint32_t *a = W->at + W->off[v];
  return a[0] == e ? a[1] : a[0];
}

/* From v along e until a corner (a chain) or back at v (a loop): one line. */
static void walk_line(walk *W, uint32_t v, uint32_t e, int loop) {
  mx_feature_lines *L = W->L;
  L->first[L->nlines] = W->np;
  L->loop[L->nlines] = (uint8_t)loop;
  const uint32_t start = v;
  put_point(W, v);
  for (;;) {
    W->used[e] = 1;
    v = W->edge[2 * (size_t)e] == v ? W->edge[2 * (size_t)e + 1] : W->edge[2 * (size_t)e];
    if (loop && v == start) break; /* the first point is not repeated */
    put_point(W, v);
    if (W->stop[v]) break;
    e = other_edge(W, v, e);
  }
  L->nlines++;
}

static int walk_all(walk *W, size_t nv) {
  mx_feature_lines *L = W->L;
  for (size_t v = 0; v < nv; v++) { /* chains, from their first corner */
    if (!W->stop[v]) continue;
    for (size_t k = W->off[v]; k < W->off[v + 1]; k++)
      if (!W->used[W->at[k]]) walk_line(W, (uint32_t)v, W->at[k], 0);
  }
  for (size_t v = 0; v < nv; v++) { /* loops, from their least vertex */
    if (W->stop[v] || W->off[v + 1] == W->off[v] || W->used[W->at[W->off[v]]]) continue;
    walk_line(W, (uint32_t)v, W->at[W->off[v]], 1);
  }
  L->first[L->nlines] = W->np;
  size_t nc = 0;
  for (size_t v = 0; v < nv; v++) nc += W->stop[v] && W->off[v + 1] > W->off[v];
  L->corner = mx_alloc((3 * nc + 1) * sizeof *L->corner);
  if (!L->corner) return MX_ENOMEM;
  for (size_t v = 0; v < nv; v++) {
    if (!W->stop[v] || W->off[v + 1] == W->off[v]) continue;
    const size_t s = W->stride * v;
    double *c = L->corner + 3 * L->ncorners++;
    c[0] = W->x[s];
    c[1] = W->y[s];
    c[2] = W->z[s];
  }
  return MX_OK;
}

int mx_feature_lines_walk(const double *x, const double *y, const double *z, size_t stride,
                          size_t nv, const uint32_t *edge, size_t ne, const uint8_t *corner,
                          mx_feature_lines *L) {
  memset(L, 0, sizeof *L);
  if (ne >= UINT32_MAX) return MX_EINPUT;
  for (size_t e = 0; e < ne; e++)
    if (edge[2 * e] >= nv || edge[2 * e + 1] >= nv || edge[2 * e] == edge[2 * e + 1])
      return MX_EINPUT;
  size_t *off = mx_calloc((nv + 2) * sizeof *off);
  uint32_t *at = mx_alloc((2 * ne + 1) * sizeof *at);
  uint8_t *stop = mx_calloc(nv + 1), *used = mx_calloc(ne + 1);
  /* at most ne lines (each has an edge), ne + (lines) points */
  L->first = mx_alloc((ne + 2) * sizeof *L->first);
  L->loop = mx_calloc(ne + 1);
  L->xyz = mx_alloc((3 * 2 * ne + 3) * sizeof *L->xyz);
  int st = off && at && stop && used && L->first && L->loop && L->xyz ? MX_OK : MX_ENOMEM;
  if (st == MX_OK) {
    for (size_t k = 0; k < 2 * ne; k++) off[edge[k] + 2]++;
    for (size_t v = 0; v < nv; v++) off[v + 2] += off[v + 1];
    for (size_t k = 0; k < 2 * ne; k++) at[off[edge[k] + 1]++] = (uint32_t)(k / 2);
    /* now the edges at v are at[off[v] .. off[v + 1]), in edge order */
    for (size_t v = 0; v < nv; v++)
      stop[v] = (corner && corner[v]) || off[v + 1] - off[v] != 2;
    walk W = {x, y, z, stride, edge, off, at, stop, used, L, 0};
    st = walk_all(&W, nv);
  }
  mx_free(off);
  mx_free(at);
  mx_free(stop);
  mx_free(used);
  if (st != MX_OK) mx_feature_lines_walk_free(L);
  return st;
}

void mx_feature_lines_free(mx_feature_lines *L) { mx_feature_lines_walk_free(L); }

int mx_feature_lines_of(const mx_trisoup *s, const mx_features *F, mx_feature_lines *L) {
  uint8_t *corner = mx_calloc(s->nv + 1);
  if (!corner) return MX_ENOMEM;
  for (size_t c = 0; c < F->ncorners; c++) corner[F->corner[c]] = 1;
  const int st = mx_feature_lines_walk(s->x, s->y, s->z, 1, s->nv, F->edge, F->nedges, corner, L);
  mx_free(corner);
  return st;
}
