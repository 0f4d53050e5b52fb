/* The control space (issue 27, src/sizing/): every structure and split
 * rule on the paper's F3, F4, F5 and a smooth anisotropic field, checked
 * by routines of this file that share nothing with the queries:
 *  - the error against the function on a grid independent of the build's
 *    samples (irrational offsets): within delta for the leaf-valued
 *    structures (their samples include the corners, where a constant is
 *    farthest from a monotone field), within 1.25 delta for K_V (its
 *    interpolation is farthest between samples: F3's cone points);
 *  - queries equal to a brute-force search over all the leaves (their
 *    boxes rebuilt from the arrays, the trilinear weights recomputed);
 *  - box minima equal to the brute-force minimum over the leaves meeting
 *    the box, and never above a query inside it;
 *  - K_oLB: no two leaves sharing a face more than one level apart (all
 *    pairs);
 *  - the same arrays for 1 and 2 threads;
 *  - a field with a narrow dip between the gradient rules' face planes
 *    (min(0.05 + 0.2 |y - 0.5|, 0.0158 + |distance to a circle|), the 2D
 *    mesher's -f curve as a source): s_G and s_S reach delta (they split
 *    y into slivers to the depth cap before kdtree.c's MISSED rule);
 *  - bad sizes (NaN, 0, negative, infinite) and bad parameters: MX_EINPUT. */
#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "base/morton.h"
#include "mixoct.h"
#include "sizing/cspace.h"

#include "check.h"

/* a smooth anisotropic field on [0, 2] x [0, 1] x [0, 1] */
static void smooth(void *user, size_t n, const double *xyz, double *h) {
  (void)user;
  for (size_t i = 0; i < n; i++) {
    const double *p = xyz + 3 * i;
    h[3 * i] = 0.1 + 0.05 * sin(3.0 * p[0]) * cos(2.0 * p[1]);
    h[3 * i + 1] = 0.05 + 0.04 * p[2] * p[2];
    h[3 * i + 2] = 0.2 * exp(-p[0]);
  }
}

/* ---- brute force on the arrays ---- */

typedef struct {
  size_t n;
  double *lo, *hi; /* 3 a leaf */
  uint32_t *node;  /* kd: the leaf's node; octree: its index */
} boxes;

static void kd_boxes(const mx_cspace *c, boxes *B) {
  B->n = 0;
  B->lo = malloc(3 * c->nnodes * sizeof *B->lo);
  B->hi = malloc(3 * c->nnodes * sizeof *B->hi);
  B->node = malloc(c->nnodes * sizeof *B->node);
  double *slo = malloc(3 * c->nnodes * sizeof *slo), *shi = malloc(3 * c->nnodes * sizeof *shi);
  uint32_t *st = malloc(c->nnodes * sizeof *st);
  size_t top = 0;
  st[top] = 0;
  memcpy(slo, c->lo, 3 * sizeof *slo);
  memcpy(shi, c->hi, 3 * sizeof *shi);
  top++;
  while (top) {
    top--;
    const uint32_t i = st[top];
    double lo[3], hi[3];
    memcpy(lo, slo + 3 * top, sizeof lo);
    memcpy(hi, shi + 3 * top, sizeof hi);
    if (c->axis[i] == MX_KD_LEAF) {
      memcpy(B->lo + 3 * B->n, lo, sizeof lo);
      memcpy(B->hi + 3 * B->n, hi, sizeof hi);
      B->node[B->n++] = i;
      continue;
    }
    const int a = c->axis[i];
    for (int s = 0; s < 2; s++) {
      st[top] = c->child[i] + (uint32_t)s;
      memcpy(slo + 3 * top, lo, sizeof lo);
      memcpy(shi + 3 * top, hi, sizeof hi);
      if (s) slo[3 * top + a] = c->coord[i];
      else shi[3 * top + a] = c->coord[i];
      top++;
    }
  }
  free(slo);
  free(shi);
  free(st);
}

static void boxes_free(boxes *B) {
  free(B->lo);
  free(B->hi);
  free(B->node);
}

/* the value of leaf b at p, by the definition */
static void kd_value(const mx_cspace *c, const boxes *B, size_t b, const double p[3], double h[3]) {
  const uint32_t i = B->node[b];
  if (c->structure == MX_CS_KD_LEAF) {
    memcpy(h, c->h + 3 * (size_t)c->val[i], 3 * sizeof *h);
    return;
  }
  h[0] = h[1] = h[2] = 0.0;
  for (int k = 0; k < 8; k++) {
    double w = 1.0;
    for (int a = 0; a < 3; a++) {
      double t = (p[a] - B->lo[3 * b + a]) / (B->hi[3 * b + a] - B->lo[3 * b + a]);
      t = t < 0 ? 0 : t > 1 ? 1 : t;
      w *= (k >> a) & 1 ? t : 1.0 - t;
    }
    const double *v = c->h + 3 * (size_t)c->vid[8 * (size_t)c->val[i] + k];
    for (int a = 0; a < 3; a++) h[a] += w * v[a];
  }
}

/* the leaf holding p: below a split when p < coord (the query's rule), so
 * a leaf holds [lo, hi) but for the box's upper faces */
static size_t kd_find(const mx_cspace *c, const boxes *B, const double p[3]) {
  for (size_t b = 0; b < B->n; b++) {
    int in = 1;
    for (int a = 0; a < 3 && in; a++)
      in = p[a] >= B->lo[3 * b + a] && (p[a] < B->hi[3 * b + a] || B->hi[3 * b + a] == c->hi[a]);
    if (in) return b;
  }
  return SIZE_MAX;
}

static void oct_cell(const mx_cspace *c, const double p[3], uint32_t q[3]) {
  const double n = ldexp(1.0, c->max_depth);
  for (int a = 0; a < 3; a++) {
    double t = floor((p[a] - c->lo[a]) / (c->hi[a] - c->lo[a]) * n);
    q[a] = t < 0 ? 0 : t > n - 1 ? (uint32_t)n - 1 : (uint32_t)t;
  }
}

static int oct_holds(const mx_cspace *c, size_t i, const uint32_t q[3]) {
  uint32_t p[3];
  mx_morton_decode(c->key[i], p);
  const uint32_t side = 1u << (c->max_depth - c->level[i]);
  return q[0] - p[0] < side && q[1] - p[1] < side && q[2] - p[2] < side && q[0] >= p[0] &&
         q[1] >= p[1] && q[2] >= p[2];
}

/* ---- the checks of one structure ---- */

static void check_structure(const char *name, mx_size_fn f, const double lo[3],
                            const double hi[3], int structure, int split, double delta) {
  mx_cspace_params p;
  mx_cspace_params_default(&p);
  p.structure = structure;
  p.split = split;
  memcpy(p.lo, lo, 3 * sizeof *lo);
  memcpy(p.hi, hi, 3 * sizeof *hi);
  p.delta = delta;
  mx_cspace *c = NULL, *c1 = NULL;
  omp_set_num_threads(2);
  CHECK(mx_cspace_build(&p, f, NULL, &c) == MX_OK);
  omp_set_num_threads(1);
  CHECK(mx_cspace_build(&p, f, NULL, &c1) == MX_OK);
  omp_set_num_threads(2);
  if (!c || !c1) return;
  mx_cspace_info in;
  mx_cspace_info_get(c, &in);
  CHECK(in.capped == 0);
  const int kd = structure <= MX_CS_KD_VERTEX;
  /* 1 and 2 threads: the same arrays */
  CHECK(c->nvalues == c1->nvalues && c->nnodes == c1->nnodes && c->nleaves == c1->nleaves);
  if (c->nvalues == c1->nvalues)
    CHECK(memcmp(c->h, c1->h, 3 * c->nvalues * sizeof *c->h) == 0);
  if (kd && c->nnodes == c1->nnodes) {
    CHECK(memcmp(c->axis, c1->axis, c->nnodes) == 0);
    CHECK(memcmp(c->coord, c1->coord, c->nnodes * sizeof *c->coord) == 0);
  }
  if (!kd && c->nleaves == c1->nleaves)
    CHECK(memcmp(c->key, c1->key, c->nleaves * sizeof *c->key) == 0);
  /* the error on an independent grid; queries against brute force */
  boxes B = {0, NULL, NULL, NULL};
  if (kd) kd_boxes(c, &B);
  enum { G = 19 };
  double err = 0.0;
  size_t wrong = 0, nq = 0;
  for (int k = 0; k < G; k++)
    for (int j = 0; j < G; j++)
      for (int i = 0; i < G; i++) {
        const int ijk[3] = {i, j, k};
        double x[3], h[3], hf[3], hb[3];
        for (int a = 0; a < 3; a++)
          x[a] = lo[a] + (hi[a] - lo[a]) * ((double)ijk[a] + 0.41421356) / G;
        f(NULL, 1, x, hf);
        mx_cspace_query(c, x, h);
        err = fmax(err, mx_metric_nonconformity(hf, h));
        nq++;
        if (kd) {
          const size_t b = kd_find(c, &B, x);
          if (b == SIZE_MAX) {
            wrong++;
            continue;
          }
          kd_value(c, &B, b, x, hb);
          /* the same weights in another order: equal within rounding */
          for (int a = 0; a < 3; a++) wrong += fabs(hb[a] - h[a]) > 1e-12 * fabs(hb[a]);
        } else {
          uint32_t q[3];
          oct_cell(c, x, q);
          size_t hold = SIZE_MAX;
          for (size_t l = 0; l < c->nleaves && hold == SIZE_MAX; l++)
            if (oct_holds(c, l, q)) hold = l;
          wrong += hold == SIZE_MAX || memcmp(c->h + 3 * hold, h, sizeof h) != 0;
        }
      }
  CHECK(wrong == 0);
  const double allow = structure == MX_CS_KD_VERTEX ? 1.25 * delta : delta;
  CHECK(err <= allow);
  /* box minima */
  size_t bad_min = 0;
  for (int t = 0; t < 40; t++) {
    double blo[3], bhi[3];
    for (int a = 0; a < 3; a++) {
      const double u = fmod(0.618034 * (t + 1) * (a + 1.7), 1.0), v = fmod(0.414214 * (t + 3) * (a + 1.3), 1.0);
      blo[a] = lo[a] + (hi[a] - lo[a]) * fmin(u, v);
      bhi[a] = lo[a] + (hi[a] - lo[a]) * fmax(u, v);
    }
    const double got = mx_cspace_min_box(c, blo, bhi);
    double want = INFINITY;
    if (kd) {
      for (size_t b = 0; b < B.n; b++) {
        int meet = 1;
        for (int a = 0; a < 3 && meet; a++)
          meet = blo[a] < B.hi[3 * b + a] && bhi[a] >= B.lo[3 * b + a];
        if (!meet) continue;
        const uint32_t i = B.node[b];
        const int nv = structure == MX_CS_KD_LEAF ? 1 : 8;
        for (int k = 0; k < nv; k++) {
          const uint32_t v = nv == 1 ? c->val[i] : c->vid[8 * (size_t)c->val[i] + k];
          for (int a = 0; a < 3; a++) want = fmin(want, c->h[3 * (size_t)v + a]);
        }
      }
    } else {
      uint32_t qa[3], qb[3];
      oct_cell(c, blo, qa);
      oct_cell(c, bhi, qb);
      for (size_t l = 0; l < c->nleaves; l++) {
        uint32_t pp[3];
        mx_morton_decode(c->key[l], pp);
        const uint32_t side = 1u << (c->max_depth - c->level[l]);
        int meet = 1;
        for (int a = 0; a < 3 && meet; a++) meet = pp[a] <= qb[a] && pp[a] + side > qa[a];
        if (meet)
          for (int a = 0; a < 3; a++) want = fmin(want, c->h[3 * l + a]);
      }
    }
    bad_min += got != want;
    /* never above a query inside the box */
    double mid[3], h[3];
    for (int a = 0; a < 3; a++) mid[a] = 0.5 * (blo[a] + bhi[a]);
    mx_cspace_query(c, mid, h);
    bad_min += got > fmin(h[0], fmin(h[1], h[2]));
  }
  CHECK(bad_min == 0);
  /* K_oLB: leaves sharing a face at most one level apart */
  size_t unbalanced = 0;
  if (structure == MX_CS_OCT_BALANCED)
    for (size_t i = 0; i < c->nleaves; i++)
      for (size_t j = i + 1; j < c->nleaves; j++) {
        if (abs((int)c->level[i] - (int)c->level[j]) <= 1) continue;
        uint32_t a[3], b[3];
        mx_morton_decode(c->key[i], a);
        mx_morton_decode(c->key[j], b);
        const uint32_t sa = 1u << (c->max_depth - c->level[i]),
                       sb = 1u << (c->max_depth - c->level[j]);
        int touch = 0, overlap = 0;
        for (int d = 0; d < 3; d++) {
          if (a[d] + sa == b[d] || b[d] + sb == a[d]) touch++;
          else if (a[d] < b[d] + sb && b[d] < a[d] + sa) overlap++;
        }
        unbalanced += touch == 1 && overlap == 2;
      }
  CHECK(unbalanced == 0);
  printf("%-6s %-9s split %d delta %.2f: %7zu leaves %8.1f kB depth %2d error %.3f (<= %.3f), "
         "%zu queries\n", name,
         structure == MX_CS_KD_LEAF ? "K_L" : structure == MX_CS_KD_VERTEX ? "K_V"
         : structure == MX_CS_OCT_LEAF ? "K_oL" : "K_oLB",
         kd ? split : -1, delta, in.leaves, in.bytes / 1024.0, in.depth, err, allow, nq);
  if (kd) boxes_free(&B);
  mx_cspace_free(c);
  mx_cspace_free(c1);
}

/* the dip: a cone of slope 1 about the circle of radius 0.3 at (0.5, 0.5) */
static void dip(void *user, size_t n, const double *xyz, double *h) {
  (void)user;
  for (size_t i = 0; i < n; i++) {
    const double *p = xyz + 3 * i;
    const double v = 0.05 + 0.2 * fabs(p[1] - 0.5),
                 c = 1.01 / 64 + fabs(hypot(p[0] - 0.5, p[1] - 0.5) - 0.3);
    h[3 * i] = h[3 * i + 1] = h[3 * i + 2] = c < v ? c : v;
  }
}

static int bad_kind;
static void bad_field(void *user, size_t n, const double *xyz, double *h) {
  (void)user;
  for (size_t i = 0; i < n; i++) {
    const double *p = xyz + 3 * i;
    double v = 1.0;
    if (p[0] > 0.7 && p[1] > 0.7) v = bad_kind == 0 ? NAN : bad_kind == 1 ? 0.0 : bad_kind == 2 ? -1.0 : INFINITY;
    h[3 * i] = h[3 * i + 1] = h[3 * i + 2] = v + 0.5 * p[2];
  }
}

static void quiet(void *user, int level, const char *text) {
  (void)user, (void)level, (void)text;
}

int main(void) {
  const char *names[3] = {"F3", "F4", "F5"};
  for (int k = 0; k < 4; k++) {
    double lo[3] = {0, 0, 0}, hi[3] = {2, 1, 1};
    mx_size_fn f = k < 3 ? mx_size_builtin(names[k], lo, hi) : smooth;
    CHECK(f != NULL);
    for (int s = 0; s < 8; s++) {
      const int structure = s < 3 ? MX_CS_KD_LEAF : s < 6 ? MX_CS_KD_VERTEX
                                                          : s == 6 ? MX_CS_OCT_LEAF
                                                                   : MX_CS_OCT_BALANCED;
      /* F4 and F5 by octree at 0.5 take 50-70k leaves: the pairwise
       * balance check only on the smaller ones */
      if (k == 1 && structure >= MX_CS_OCT_LEAF) continue;
      if (k == 2 && structure >= MX_CS_OCT_LEAF) continue;
      check_structure(k < 3 ? names[k] : "smooth", f, lo, hi, structure, s < 6 ? s % 3 : 0,
                      k == 3 ? 0.1 : 0.5);
    }
  }
  for (int split = MX_SPLIT_GRADIENT; split <= MX_SPLIT_SUM; split++) {
    mx_cspace_params p;
    mx_cspace_params_default(&p);
    p.split = split;
    mx_cspace *c = NULL;
    CHECK(mx_cspace_build(&p, dip, NULL, &c) == MX_OK);
    mx_cspace_info in;
    if (c) mx_cspace_info_get(c, &in);
    CHECK(c && !in.capped && in.leaves < 10000);
    if (c) printf("dip, split %d: %zu leaves, depth %d\n", split, in.leaves, in.depth);
    mx_cspace_free(c);
  }
  CHECK(mx_size_builtin("F6", NULL, NULL) == NULL);
  /* bad sizes and parameters */
  mx_set_thread_message_handler(quiet, NULL);
  mx_cspace_params p;
  mx_cspace_params_default(&p);
  for (int s = 0; s < 4; s++)
    for (bad_kind = 0; bad_kind < 4; bad_kind++) {
      mx_cspace *c = NULL;
      p.structure = s;
      CHECK(mx_cspace_build(&p, bad_field, NULL, &c) == MX_EINPUT && c == NULL);
    }
  p.structure = 9;
  mx_cspace *c = NULL;
  CHECK(mx_cspace_build(&p, smooth, NULL, &c) == MX_EINPUT);
  mx_cspace_params_default(&p);
  p.delta = 0.0;
  CHECK(mx_cspace_build(&p, smooth, NULL, &c) == MX_EINPUT);
  mx_cspace_params_default(&p);
  p.hi[1] = p.lo[1];
  CHECK(mx_cspace_build(&p, smooth, NULL, &c) == MX_EINPUT);
  mx_cspace_params_default(&p);
  p.samples = 40;
  CHECK(mx_cspace_build(&p, smooth, NULL, &c) == MX_EINPUT);
  printf("%d failed\n", mx_test_failures);
  return mx_test_failures != 0;
}
