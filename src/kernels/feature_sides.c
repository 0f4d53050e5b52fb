/* The nodes beside a placed ridge onto their own side's face
 * (kernels/feature_graph.h, mx_fgraph_sides). */
#include "kernels/feature_graph.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "base/common.h"
#include "base/union_find.h"

typedef struct {
  mx_surface_index S;
  mx_trisoup sub; /* the patch's triangles over the soup's vertices */
  int built;
} patch_index;

/* The patches' triangles (CSR: patch p's are tri[off[p] .. off[p + 1]))
 * and a vertex map (nv entries, UINT32_MAX between builds), for building
 * a patch's index over its own vertices only. */
typedef struct {
  uint32_t *off, *tri, *vmap;
} patch_lists;

static int patch_lists_make(const mx_feature_input *in, patch_lists *pl) {
  pl->off = mx_calloc((in->npatches + 2) * sizeof *pl->off);
  pl->tri = mx_alloc((in->nt + 1) * sizeof *pl->tri);
  pl->vmap = mx_alloc((in->soup->nv + 1) * sizeof *pl->vmap);
  if (!pl->off || !pl->tri || !pl->vmap) return MX_ENOMEM;
  for (size_t t = 0; t < in->nt; t++) pl->off[in->patch[t] + 1]++;
  for (size_t p = 0; p < in->npatches; p++) pl->off[p + 1] += pl->off[p];
  for (size_t t = 0; t < in->nt; t++) pl->tri[pl->off[in->patch[t]]++] = (uint32_t)t;
  for (size_t p = in->npatches; p > 0; p--) pl->off[p] = pl->off[p - 1];
  pl->off[0] = 0;
  for (size_t v = 0; v < in->soup->nv; v++) pl->vmap[v] = UINT32_MAX;
  return MX_OK;
}

static void patch_lists_free(patch_lists *pl) {
  mx_free(pl->off);
  mx_free(pl->tri);
  mx_free(pl->vmap);
}

#define PATCH_DIRECT 4096 /* triangles a patch is searched without an index up to */

static int patch_closest(const mx_feature_input *in, patch_lists *pl, patch_index *pi,
                         uint32_t patch, const double *x, double *q) {
  patch_index *P = pi + patch;
  if (!P->built) {
    const mx_trisoup *S0 = in->soup;
    memset(&P->sub, 0, sizeof P->sub);
    int st = MX_OK;
    for (uint32_t k = pl->off[patch]; k < pl->off[patch + 1] && !st; k++) {
      uint32_t w[3];
      for (int c = 0; c < 3 && !st; c++) {
        const uint32_t v = S0->tri[3 * (size_t)pl->tri[k] + c];
        if (pl->vmap[v] == UINT32_MAX) {
          pl->vmap[v] = (uint32_t)P->sub.nv;
          const double y[3] = {S0->x[v], S0->y[v], S0->z[v]};
          st = mx_trisoup_set_vertex(&P->sub, P->sub.nv, y);
        }
        w[c] = pl->vmap[v];
      }
      if (!st) st = mx_trisoup_add_triangle(&P->sub, w[0], w[1], w[2]);
    }
    for (uint32_t k = pl->off[patch]; k < pl->off[patch + 1]; k++)
      for (int c = 0; c < 3; c++) pl->vmap[S0->tri[3 * (size_t)pl->tri[k] + c]] = UINT32_MAX;
    /* an index pays for itself on large patches only (building one has a
     * fixed cost of about 0.2 s: measured on 8 triangles) */
    if (!st && P->sub.nt > PATCH_DIRECT)
      st = mx_surface_index_build(&P->S, &P->sub, 0, (uint32_t)P->sub.nt);
    if (st) {
      mx_trisoup_free(&P->sub);
      return st;
    }
    P->built = 1;
  }
  if (P->sub.nt > PATCH_DIRECT) {
    mx_closest_point(&P->S, x, q, NULL, NULL);
    return MX_OK;
  }
  double best = INFINITY; /* a few triangles: each of them */
  for (size_t t = 0; t < P->sub.nt; t++) {
    double tri[9], y[3];
    for (int c = 0; c < 3; c++) {
      const uint32_t v = P->sub.tri[3 * t + c];
      tri[3 * c] = P->sub.x[v];
      tri[3 * c + 1] = P->sub.y[v];
      tri[3 * c + 2] = P->sub.z[v];
    }
    const double d = mx_closest_on_triangle(tri, x, y);
    if (d < best) {
      best = d;
      memcpy(q, y, sizeof y);
    }
  }
  return MX_OK;
}

static int cmp_u64(const void *a, const void *b) {
  const uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
  return (x > y) - (x < y);
}

/* The half of face f (a quadrilateral split along a line's diagonal: f
 * for the half with the node after the diagonal's first, nf + q for the
 * other) that has edge a-b (a == b: node a, off the diagonal); f itself
 * for a face not split. */
static uint32_t half_of(const mx_fgraph *G, uint32_t f, uint32_t a, uint32_t b) {
  if (f < G->bf.ntri) return f;
  const size_t q = f - G->bf.ntri;
  if (!G->qdiag[q]) return f;
  const uint32_t *p = G->bf.quad + 4 * q;
  const int s = G->qdiag[q] - 1; /* the diagonal p[s] - p[s + 2] */
  const uint32_t mid = p[s + 1]; /* the first half: p[s], p[s + 1], p[s + 2] */
  return a == mid || b == mid ? f : (uint32_t)(G->nf + q);
}

/* Each region's patch by its nodes' votes; nodes of a region closest to
 * another patch moved onto the region's. near[v]: the nodes looked at. */
int mx_fgraph_sides(mx_fgraph *G, const mx_feature_input *in, const mx_surface_index *S,
                    const uint8_t *near, uint8_t *moved, size_t *count) {
  mx_mesh *M = G->M;
  const size_t nf = G->nf, nh = nf + G->bf.nquad; /* faces, and second halves of split quads */
  uint32_t *up = mx_alloc((nh + 1) * sizeof *up), *np = mx_alloc((M->nnodes + 1) * sizeof *np);
  uint32_t *reg = mx_alloc((M->nnodes + 1) * sizeof *reg);
  uint64_t *vote = NULL;
  patch_index *pi = mx_calloc((in->npatches + 1) * sizeof *pi);
  patch_lists pl = {NULL, NULL, NULL}; /* made when a patch is first asked for */
  int st = up && np && reg && pi ? MX_OK : MX_ENOMEM;
  if (st) goto done;
  for (size_t f = 0; f < nh; f++) up[f] = (uint32_t)f;
  for (size_t e = 0; e < G->ne; e++)
    if (!G->eline[e]) {
      const uint32_t a = (uint32_t)(G->rkey[G->estart[e]] >> 32), b = (uint32_t)G->rkey[G->estart[e]];
      const uint32_t f0 = half_of(G, G->rface[G->estart[e]], a, b);
      for (uint32_t r = G->estart[e] + 1; r < G->estart[e + 1]; r++)
        mx_uf_join(up, f0, half_of(G, G->rface[r], a, b));
    }
  /* each near node's closest patch and region (UINT32_MAX - 1: two regions) */
  size_t nv = 0;
  for (size_t v = 0; v < M->nnodes; v++) {
    reg[v] = UINT32_MAX;
    np[v] = UINT32_MAX;
    if (near[v] && !G->fixed[v]) {
      uint32_t t;
      mx_closest_point(S, M->xyz + 3 * v, NULL, &t, NULL);
      np[v] = t < in->nt ? in->patch[t] : UINT32_MAX;
      nv++;
    }
  }
  for (size_t f = 0; f < nf; f++) {
    int k;
    const uint32_t *p = mx_fgraph_face(G, f, &k);
    for (int i = 0; i < k; i++) {
      if (np[p[i]] == UINT32_MAX) continue;
      /* a node of a split quadrilateral off the diagonal is in one half */
      const uint32_t h = k == 4 ? half_of(G, (uint32_t)f, p[i], p[i]) : (uint32_t)f;
      const uint32_t r = mx_uf_find(up, h);
      reg[p[i]] = reg[p[i]] == UINT32_MAX || reg[p[i]] == r ? r : UINT32_MAX - 1;
    }
  }
  /* the votes: (region, patch) pairs sorted, the longest run per region */
  vote = mx_alloc((nv + 1) * sizeof *vote);
  if (!vote) {
    st = MX_ENOMEM;
    goto done;
  }
  size_t n = 0;
  for (size_t v = 0; v < M->nnodes; v++)
    if (np[v] != UINT32_MAX && reg[v] < UINT32_MAX - 1) vote[n++] = (uint64_t)reg[v] << 32 | np[v];
  qsort(vote, n, sizeof *vote, cmp_u64);
  /* the winner of each region, in place at the region's face id (up[] of
   * roots is theirs: roots keep up[r] == r, so the winner goes to np-like
   * storage: reuse up[] only for roots after the last find) */
  uint32_t *win = mx_alloc((nh + 1) * sizeof *win);
  if (!win) {
    st = MX_ENOMEM;
    goto done;
  }
  for (size_t f = 0; f < nh; f++) win[f] = UINT32_MAX;
  for (size_t i = 0, best = 0; i < n;) {
    const uint32_t r = (uint32_t)(vote[i] >> 32);
    size_t j = i;
    best = 0;
    while (j < n && vote[j] >> 32 == r) {
      size_t l = j;
      while (l < n && vote[l] == vote[j]) l++;
      if (l - j > best) {
        best = l - j;
        win[r] = (uint32_t)vote[j];
      }
      j = l;
    }
    /* a clear winner only: two patches about even mean the region runs
     * round a line that was not placed, its sides unknown */
    if (3 * best < 2 * (j - i)) win[r] = UINT32_MAX;
    i = j;
  }
  for (size_t v = 0; v < M->nnodes && !st; v++) {
    if (np[v] == UINT32_MAX || reg[v] >= UINT32_MAX - 1) continue;
    const uint32_t want = win[reg[v]];
    if (want == UINT32_MAX || want == np[v]) continue;
    double q[3];
    if (!pl.off && (st = patch_lists_make(in, &pl))) break;
    st = patch_closest(in, &pl, pi, want, M->xyz + 3 * v, q);
    if (st) break;
    memcpy(M->xyz + 3 * v, q, sizeof q);
    moved[v] = 1;
    (*count)++;
  }
  mx_free(win);
done:
  for (size_t p = 0; pi && p < in->npatches; p++)
    if (pi[p].built) {
      if (pi[p].sub.nt > PATCH_DIRECT) mx_surface_index_free(&pi[p].S);
      mx_trisoup_free(&pi[p].sub);
    }
  mx_free(pi);
  patch_lists_free(&pl);
  mx_free(up);
  mx_free(np);
  mx_free(reg);
  mx_free(vote);
  return st;
}
