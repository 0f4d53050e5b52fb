/* The quadtree: the root grid, the leaves in Morton order, the independent
 * balance check, and freeing. Refinement is in qrefine.c. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "base/common.h"
#include "quad/quad.h"
#include "base/scan.h"

/* Small loops run on one thread: a parallel region costs more than them. */
#define PAR(n) ((n) > 4096)

/* Roots of side 1.01 x the longest extent (the margin keeps every polyline
 * off the roots' boundary), as many per axis as the extent needs, centred
 * on the box. */
int mx_qgrid_build(const double lo[2], const double hi[2], const char *name, mx_qgrid *g) {
  memset(g, 0, sizeof *g);
  double ext[2], longest = 0.0, big = 0.0;
  for (int a = 0; a < 2; a++) {
    ext[a] = hi[a] - lo[a];
    if (!isfinite(lo[a]) || !isfinite(hi[a]) || !(ext[a] >= 0.0)) {
      mx_error(name, 0, "the domain's bounding box is empty or not finite");
      return MX_EINPUT;
    }
    longest = fmax(longest, ext[a]);
    big = fmax(big, fmax(fabs(lo[a]), fabs(hi[a])));
  }
  if (!(longest > 0.0) || longest < 1e-12 * big) {
    mx_error(name, 0, "the domain is flat or too small for its distance to the origin "
                      "(extent %g at distance %g)", longest, big);
    return MX_EINPUT;
  }
  g->side = 1.01 * longest;
  g->unit = ldexp(g->side, -MX_QMAX_LEVEL);
  for (int a = 0; a < 2; a++) {
    double n = ceil(ext[a] / g->side);
    if (n < 1.0) n = 1.0;
    if (n > 1024.0) { /* lattice coordinates must fit 32 bits */
      mx_error(name, 0, "internal: %g root squares on one axis", n);
      return MX_EINTERNAL;
    }
    g->dims[a] = (uint32_t)n;
    g->origin[a] = 0.5 * (lo[a] + hi[a]) - 0.5 * n * g->side;
  }
  return MX_OK;
}

void mx_qtree_free(mx_qtree *T) {
  mx_free(T->key);
  mx_free(T->level);
  mx_free(T->flags);
  mx_free(T->target);
  mx_free(T->parent);
  mx_free(T->child0);
  mx_free(T->seg_off);
  mx_free(T->seg_cnt);
  mx_free(T->seg_pool);
  memset(T, 0, sizeof *T);
}

static int is_leaf(const mx_qtree *T, size_t q) {
  return !(T->flags[q] & (MX_Q_SPLIT | MX_Q_OUT));
}

/* Count per block, prefix sum, fill, then sort by key: Morton order. The
 * leaves in the order they were made are often in Morton order already (a
 * uniform refinement splits each level in that order): then the count pass
 * sees it and there is nothing to sort. */
int mx_qtree_leaves(const mx_qtree *T, uint32_t **leaves, size_t *n) {
  *leaves = NULL;
  *n = 0;
  const size_t B = 4096, nb = (T->n + B - 1) / B;
  uint64_t *off = mx_alloc((nb + 1) * sizeof *off);
  uint64_t *first = mx_alloc((nb + 1) * sizeof *first), *last = mx_alloc((nb + 1) * sizeof *last);
  if (!off || !first || !last) {
    mx_free(off), mx_free(first), mx_free(last);
    return MX_ENOMEM;
  }
  int unsorted = 0;
#pragma omp parallel for schedule(static) reduction(| : unsorted) if (PAR(T->n))
  for (size_t b = 0; b < nb; b++) {
    uint64_t k = 0, prev = 0;
    for (size_t q = b * B; q < T->n && q < (b + 1) * B; q++) {
      if (!is_leaf(T, q)) continue;
      if (k == 0) first[b] = T->key[q];
      else unsorted |= T->key[q] <= prev;
      prev = T->key[q];
      k++;
    }
    off[b] = k;
    last[b] = prev;
  }
  for (size_t b = 0, p = SIZE_MAX; b < nb && !unsorted; b++) {
    if (!off[b]) continue;
    if (p != SIZE_MAX && first[b] <= last[p]) unsorted = 1;
    p = b;
  }
  mx_free(first), mx_free(last);
  const size_t total = mx_scan_u64(off, nb);
  uint32_t *l = mx_alloc((total + 1) * sizeof *l);
  uint64_t *k = unsorted ? mx_alloc((total + 1) * sizeof *k) : NULL;
  if (!l || (unsorted && !k)) {
    mx_free(off), mx_free(l), mx_free(k);
    return MX_ENOMEM;
  }
#pragma omp parallel for schedule(static) if (PAR(T->n))
  for (size_t b = 0; b < nb; b++) {
    uint64_t w = off[b];
    for (size_t q = b * B; q < T->n && q < (b + 1) * B; q++)
      if (is_leaf(T, q)) {
        l[w] = (uint32_t)q;
        if (k) k[w] = T->key[q];
        w++;
      }
  }
  mx_free(off);
  int st = k ? mx_sort_u64(k, l, total) : MX_OK;
  mx_free(k);
  if (st) {
    mx_free(l);
    return st;
  }
  *leaves = l;
  *n = total;
  return MX_OK;
}

/* ---- the independent balance check ------------------------------------- */

/* A leaf of level m is unbalanced along an edge when a leaf of level m+2 or
 * finer (outside ones included: they were made by a split) lies across it;
 * such a leaf has a corner at one of the edge's quarter points (1/4, 1/2,
 * 3/4), and no leaf on the other side has. So: the corners of all leaves,
 * sorted with the finest level at each, then 12 look-ups per leaf. */
typedef struct {
  uint64_t *key;
  uint8_t *lev; /* finest level of a leaf with that corner */
  size_t n;
} corner_set;

static int corners_build(const mx_qtree *T, corner_set *C) {
  memset(C, 0, sizeof *C);
  size_t nl = 0;
  for (size_t q = 0; q < T->n; q++) nl += !(T->flags[q] & MX_Q_SPLIT);
  uint64_t *k = mx_alloc((4 * nl + 1) * sizeof *k);
  uint32_t *v = mx_alloc((4 * nl + 1) * sizeof *v);
  C->lev = mx_alloc(4 * nl + 1);
  if (!k || !v || !C->lev) {
    mx_free(k), mx_free(v), mx_free(C->lev);
    return MX_ENOMEM;
  }
  size_t m = 0;
  for (size_t q = 0; q < T->n; q++) {
    if (T->flags[q] & MX_Q_SPLIT) continue;
    uint32_t x, y;
    mx_qkey_xy(T->key[q], &x, &y);
    const uint32_t s = mx_qsize(T->level[q]);
    for (int c = 0; c < 4; c++) {
      k[m] = mx_qkey(x + (c & 1) * s, y + (c >> 1) * s);
      v[m++] = T->level[q];
    }
  }
  int st = mx_sort_u64(k, v, m);
  size_t u = 0;
  for (size_t i = 0; !st && i < m; i++) {
    if (u > 0 && k[u - 1] == k[i]) {
      if (v[i] > C->lev[u - 1]) C->lev[u - 1] = (uint8_t)v[i];
      continue;
    }
    k[u] = k[i];
    C->lev[u++] = (uint8_t)v[i];
  }
  mx_free(v);
  C->key = k;
  C->n = u;
  if (st) {
    mx_free(C->key), mx_free(C->lev);
    memset(C, 0, sizeof *C);
  }
  return st;
}

static int corner_level(const corner_set *C, uint64_t key) {
  size_t lo = 0, hi = C->n;
  while (lo < hi) {
    const size_t mid = lo + (hi - lo) / 2;
    if (C->key[mid] < key) lo = mid + 1;
    else hi = mid;
  }
  return lo < C->n && C->key[lo] == key ? C->lev[lo] : -1;
}

/* Counts (leaf, edge) pairs with a leaf two or more levels finer across. */
size_t mx_qtree_unbalanced(const mx_qtree *T) {
  corner_set C;
  if (corners_build(T, &C)) return SIZE_MAX;
  /* edge e: start corner and direction (bottom, right, top, left) */
  static const int start[4][2] = {{0, 0}, {1, 0}, {0, 1}, {0, 0}};
  static const int dir[4][2] = {{1, 0}, {0, 1}, {1, 0}, {0, 1}};
  size_t bad = 0;
#pragma omp parallel for schedule(static) reduction(+ : bad) if (PAR(T->n))
  for (size_t q = 0; q < T->n; q++) {
    const int m = T->level[q];
    if (!is_leaf(T, q) || m + 2 > MX_QMAX_LEVEL) continue;
    uint32_t x, y;
    mx_qkey_xy(T->key[q], &x, &y);
    const uint32_t s = mx_qsize(m), h = s / 4;
    for (int e = 0; e < 4; e++) {
      int found = 0;
      for (uint32_t t = 1; t <= 3 && !found; t++) {
        const uint32_t px = x + (uint32_t)start[e][0] * s + (uint32_t)dir[e][0] * t * h;
        const uint32_t py = y + (uint32_t)start[e][1] * s + (uint32_t)dir[e][1] * t * h;
        found = corner_level(&C, mx_qkey(px, py)) >= m + 2;
      }
      bad += (size_t)found;
    }
  }
  mx_free(C.key);
  mx_free(C.lev);
  return bad;
}
