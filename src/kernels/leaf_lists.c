/* The nearest triangle of a node from its leaves' triangle lists: see
 * kernels/leaf_lists.h. */
#include "kernels/leaf_lists.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "base/common.h"
#include "base/scan.h"
#include "geom/distance.h"

/* Elements are in leaf order: each leaf's elements form one run. The runs'
 * starts (mx_alloc, *nr of them, then nc), counted per block, prefix-summed,
 * filled; NULL when out of memory. */
static uint64_t *leaf_runs(const mx_mesh *M, size_t *nr_out) {
  const size_t nc = M->ncells;
  enum { RB = 1 << 16 };
  const size_t nbk = (nc + RB - 1) / RB;
  uint64_t *run = mx_alloc((nc + 2) * sizeof *run);
  uint64_t *boff = mx_alloc((nbk + 1) * sizeof *boff);
  if (!run || !boff) {
    mx_free(run);
    mx_free(boff);
    return NULL;
  }
#pragma omp parallel for schedule(static)
  for (size_t b = 0; b < nbk; b++) {
    uint64_t k = 0;
    for (size_t c = b * RB; c < nc && c < (b + 1) * RB; c++)
      k += c == 0 || M->leaf[c] != M->leaf[c - 1];
    boff[b] = k;
  }
  const size_t nr = (size_t)mx_scan_u64(boff, nbk);
#pragma omp parallel for schedule(static)
  for (size_t b = 0; b < nbk; b++) {
    uint64_t k = boff[b];
    for (size_t c = b * RB; c < nc && c < (b + 1) * RB; c++)
      if (c == 0 || M->leaf[c] != M->leaf[c - 1]) run[k++] = c;
  }
  mx_free(boff);
  run[nr] = nc;
  *nr_out = nr;
  return run;
}

/* Distinct nodes v of the elements [c0, c1) (one leaf's) with (sel[v] &
 * mask) == want, in order of first use. */
static int leaf_nodes(const mx_mesh *M, size_t c0, size_t c1, const uint8_t *sel,
                      uint8_t mask, uint8_t want, uint32_t out[64]) {
  int n = 0;
  for (size_t c = c0; c < c1; c++)
    for (int k = 0; k < mx_cell_nodes[M->type[c]]; k++) {
      const uint32_t v = M->conn[8 * c + k];
      if ((sel[v] & mask) != want) continue;
      int seen = 0;
      for (int j = 0; j < n && !seen; j++) seen = out[j] == v;
      if (!seen && n < 64) out[n++] = v;
    }
  return n;
}

static int same_point(const double a[3], const double b[3]) {
  return a[0] == b[0] && a[1] == b[1] && a[2] == b[2];
}

/* Closest domain triangle of leaf o's list to p: squared distance, id (the
 * lowest of those as near); *tied (when not NULL) 1 when two of them as
 * near give two points. */
static double leaf_closest(const mx_tree *tr, uint32_t o, const double p[3],
                           uint32_t *tri, int *tied) {
  const mx_octree *T = &tr->oct;
  double best = INFINITY, q[3], bq[3] = {0.0, 0.0, 0.0};
  int tie = 0;
  *tri = UINT32_MAX;
  for (uint32_t k = 0; k < T->tri_cnt[o]; k++) {
    const uint32_t t = T->tri_pool[T->tri_off[o] + k];
    if (t >= tr->nt_domain) continue;
    const double d2 = mx_closest_on_triangle(tr->tri_xyz + 9 * (size_t)t, p, q);
    if (d2 < best) {
      best = d2;
      *tri = t;
      memcpy(bq, q, sizeof bq);
      tie = 0;
    } else if (d2 == best) {
      tie |= !same_point(q, bq);
      if (t < *tri) {
        *tri = t;
        memcpy(bq, q, sizeof bq);
      }
    }
  }
  if (tied) *tied = tie;
  return best;
}

static inline uint64_t dbits(double d) {
  uint64_t u;
  memcpy(&u, &d, sizeof u);
  return u; /* non-negative doubles order as their bits */
}

int mx_leaf_list_closest(const mx_tree *tr, const uint32_t *leaves, const mx_mesh *M,
                             const uint8_t *sel, uint8_t mask, uint8_t want,
                             uint64_t *best, uint32_t *btri, uint8_t *tie) {
  const size_t nn = M->nnodes;
  size_t nr = 0;
  uint64_t *run = leaf_runs(M, &nr);
  uint8_t *lock = run ? mx_calloc(nn + 1) : NULL;
  if (!lock) {
    mx_free(run);
    return MX_ENOMEM;
  }
#pragma omp parallel for schedule(static)
  for (size_t v = 0; v < nn; v++)
    if ((sel[v] & mask) == want) {
      best[v] = UINT64_MAX;
      btri[v] = UINT32_MAX;
      if (tie) tie[v] = 0;
    }
#pragma omp parallel for schedule(dynamic, 256)
  for (size_t r = 0; r < nr; r++) {
    const uint32_t o = leaves[M->leaf[run[r]]];
    if (!tr->oct.tri_cnt[o]) continue;
    uint32_t vs[64];
    const int k = leaf_nodes(M, run[r], run[r + 1], sel, mask, want, vs);
    for (int j = 0; j < k; j++) {
      uint32_t t;
      int tied = 0;
      const double *p = M->xyz + 3 * (size_t)vs[j];
      const double d2 = leaf_closest(tr, o, p, &t, tie ? &tied : NULL);
      if (t == UINT32_MAX) continue;
      const uint64_t mine = dbits(d2);
      const uint32_t v = vs[j];
      while (__atomic_test_and_set(&lock[v], __ATOMIC_ACQUIRE)) {
      }
      const int better = mine < best[v], equal = mine == best[v];
      if (tie && equal && t != btri[v]) { /* as near as another leaf's */
        double q0[3], q1[3];
        mx_closest_on_triangle(tr->tri_xyz + 9 * (size_t)t, p, q0);
        mx_closest_on_triangle(tr->tri_xyz + 9 * (size_t)btri[v], p, q1);
        tied |= !same_point(q0, q1);
      }
      if (tie && (better || equal)) tie[v] = (uint8_t)(better ? tied : tie[v] | tied);
      if (better || (equal && t < btri[v])) {
        best[v] = mine;
        btri[v] = t;
      }
      __atomic_clear(&lock[v], __ATOMIC_RELEASE);
    }
  }
  mx_free(lock);
  mx_free(run);
  return MX_OK;
}

/* 1 when p lies on the lattice of step `step` from the grid's origin
 * (within a 50th of it, for the rounding of the positions). */
static int on_lattice(const mx_grid *g, const double p[3], double step) {
  for (int a = 0; a < 3; a++) {
    const double f = (p[a] - g->origin[a]) / step;
    if (!(fabs(f - nearbyint(f)) < 0.02)) return 0;
  }
  return 1;
}

/* The largest leaf level of M's elements (0 without levels). */
static int finest_level(const mx_mesh *M) {
  int lmax = 0;
  const size_t nc = M->level ? M->ncells : 0;
#pragma omp parallel for schedule(static) reduction(max : lmax)
  for (size_t c = 0; c < nc; c++) lmax = M->level[c] > lmax ? M->level[c] : lmax;
  return lmax;
}


static int cmp_double(const void *a, const void *b) {
  const double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}

void mx_list_frame_free(mx_list_frame *F) {
  for (int a = 0; a < 3; a++) mx_free(F->plane[a]);
  memset(F, 0, sizeof *F);
}

int mx_list_frame_build(const mx_tree *tr, const mx_mesh *M, mx_list_frame *F) {
  memset(F, 0, sizeof *F);
  const mx_grid *g = &tr->grid;
  F->g = g;
  F->half = ldexp(g->side, -finest_level(M) - 1);
  double mag = 0.0;
  for (int a = 0; a < 3; a++)
    mag = fmax(mag, fabs(g->origin[a]) + g->side * (double)g->dims[a]);
  F->tol = 1e-9 * F->half + 1e-12 * mag;
  const uint32_t nt = tr->nt_domain;
  for (int a = 0; a < 3; a++) {
    F->plane[a] = mx_alloc(((size_t)nt + 1) * sizeof *F->plane[a]);
    if (!F->plane[a]) {
      mx_list_frame_free(F);
      return MX_ENOMEM;
    }
  }
  for (uint32_t t = 0; t < nt; t++) {
    const double *v = tr->tri_xyz + 9 * (size_t)t;
    for (int a = 0; a < 3; a++) {
      const double lo = fmin(v[a], fmin(v[3 + a], v[6 + a]));
      const double hi = fmax(v[a], fmax(v[3 + a], v[6 + a]));
      if (hi - lo <= F->tol) F->plane[a][F->nplane[a]++] = 0.5 * (lo + hi);
    }
  }
  for (int a = 0; a < 3; a++) qsort(F->plane[a], F->nplane[a], sizeof *F->plane[a], cmp_double);
  return MX_OK;
}

/* 1 when a plane of c[0..n) (sorted) lies within r of x. */
static int near_plane(const double *c, size_t n, double x, double r) {
  size_t lo = 0, hi = n; /* the first plane at or above x - r */
  while (lo < hi) {
    const size_t mid = lo + (hi - lo) / 2;
    if (c[mid] < x - r) lo = mid + 1;
    else hi = mid;
  }
  return lo < n && c[lo] <= x + r;
}

double mx_list_cover(uint8_t marks, double half) {
  return marks & MX_LIST_WIDE ? 1.8 * half : marks & MX_LIST_LOCAL ? 0.9 * half : 0.0;
}

uint8_t mx_list_marks(const mx_list_frame *F, const double p[3]) {
  const uint8_t m = on_lattice(F->g, p, 2.0 * F->half) ? MX_LIST_LOCAL | MX_LIST_WIDE
                    : on_lattice(F->g, p, F->half)     ? MX_LIST_LOCAL
                                                       : 0;
  if (!m) return 0;
  const double reach = mx_list_cover(m, F->half) + F->tol;
  for (int a = 0; a < 3; a++)
    if (near_plane(F->plane[a], F->nplane[a], p[a], reach)) return 0;
  return m;
}

