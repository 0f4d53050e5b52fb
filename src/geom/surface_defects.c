/* Defects of input surfaces: open, non-manifold and misoriented edges,
 * degenerate triangles, pairs of triangles that intersect; orientation.
 * See surface_defects.h for the definitions and the method. */
#include "geom/surface_defects.h"

#include <math.h>
#include <omp.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "base/union_find.h"
#include "base/common.h"
#include "base/morton.h"
#include "base/scan.h"
#include "geom/bvh.h"
#include "geom/surface_topology.h"

#define NEX MX_DEFECT_EXAMPLES
#define NONE UINT32_MAX

/* ==== exact signs ========================================================
 * Semi-static filters with Shewchuk's "A" error bounds (Adaptive precision
 * floating-point arithmetic and fast robust geometric predicates, 1997);
 * when they do not decide, the determinant is evaluated exactly: every
 * difference of coordinates is split into two doubles (hi + lo, exact),
 * each product of such parts is made exact with fma (two_prod), and the
 * terms are accumulated into a nonoverlapping expansion (grow), whose
 * largest component has the sign of the sum. Valid without overflow or
 * underflow (the readers refuse coordinates beyond 1e100 and below 1e-100
 * in size). */

static const double EPS = 0x1p-53;

static inline void two_sum(double a, double b, double *s, double *e) {
  double x = a + b, bv = x - a, av = x - bv;
  *s = x;
  *e = (a - av) + (b - bv);
}

static inline void two_prod(double a, double b, double *p, double *e) {
  double x = a * b;
  *p = x;
  *e = fma(a, b, -x);
}

/* h[0..n): nonoverlapping, increasing magnitude, no zeros. Adds b exactly;
 * returns the new length (at most n + 1). */
static int grow(double *h, int n, double b) {
  double q = b;
  int k = 0;
  for (int i = 0; i < n; i++) {
    double s, e;
    two_sum(q, h[i], &s, &e);
    q = s;
    if (e != 0.0) h[k++] = e;
  }
  if (q != 0.0) h[k++] = q;
  return k;
}

static inline int grow_nz(double *h, int n, double b) {
  return b != 0.0 ? grow(h, n, b) : n;
}

/* h += a * b * c exactly (at most 4 more components). */
static int add_prod3(double *h, int n, double a, double b, double c) {
  if (a == 0.0 || b == 0.0 || c == 0.0) return n;
  double p, q, r, t;
  two_prod(a, b, &p, &q);
  two_prod(p, c, &r, &t);
  n = grow_nz(h, n, t);
  n = grow(h, n, r);
  if (q != 0.0) {
    two_prod(q, c, &r, &t);
    n = grow_nz(h, n, t);
    n = grow(h, n, r);
  }
  return n;
}

/* h += a * b exactly. */
static int add_prod2(double *h, int n, double a, double b) {
  if (a == 0.0 || b == 0.0) return n;
  double p, q;
  two_prod(a, b, &p, &q);
  n = grow_nz(h, n, q);
  return grow(h, n, p);
}

static inline int exp_sign(const double *h, int n) {
  return n == 0 ? 0 : (h[n - 1] > 0.0 ? 1 : -1);
}

/* Sign of det[a - d; b - d; c - d], exactly. */
static __attribute__((noinline)) int orient3d_exact(const double *a,
                                                    const double *b,
                                                    const double *c,
                                                    const double *d) {
  const double *r[3] = {a, b, c};
  double m[3][3][2];
  for (int i = 0; i < 3; i++)
    for (int j = 0; j < 3; j++) two_sum(r[i][j], -d[j], &m[i][j][0], &m[i][j][1]);
  static const int perm[6][4] = {{0, 1, 2, 1},  {1, 2, 0, 1},  {2, 0, 1, 1},
                                 {0, 2, 1, -1}, {2, 1, 0, -1}, {1, 0, 2, -1}};
  double h[6 * 8 * 4 + 1];
  int n = 0;
  for (int p = 0; p < 6; p++)
    for (int u = 0; u < 2; u++) {
      double x = m[0][perm[p][0]][u];
      if (x == 0.0) continue;
      if (perm[p][3] < 0) x = -x;
      for (int v = 0; v < 2; v++) {
        double y = m[1][perm[p][1]][v];
        if (y == 0.0) continue;
        for (int w = 0; w < 2; w++) n = add_prod3(h, n, x, y, m[2][perm[p][2]][w]);
      }
    }
  return exp_sign(h, n);
}

/* +1, -1 or 0: the sign of det[a - d; b - d; c - d] (positive when d lies
 * below the plane of a, b, c seen counter-clockwise from above). */
static inline int orient3d(const double *a, const double *b, const double *c,
                           const double *d) {
  double adx = a[0] - d[0], bdx = b[0] - d[0], cdx = c[0] - d[0];
  double ady = a[1] - d[1], bdy = b[1] - d[1], cdy = c[1] - d[1];
  double adz = a[2] - d[2], bdz = b[2] - d[2], cdz = c[2] - d[2];
  double bdxcdy = bdx * cdy, cdxbdy = cdx * bdy;
  double cdxady = cdx * ady, adxcdy = adx * cdy;
  double adxbdy = adx * bdy, bdxady = bdx * ady;
  double det = adz * (bdxcdy - cdxbdy) + bdz * (cdxady - adxcdy) +
               cdz * (adxbdy - bdxady);
  double perm = (fabs(bdxcdy) + fabs(cdxbdy)) * fabs(adz) +
                (fabs(cdxady) + fabs(adxcdy)) * fabs(bdz) +
                (fabs(adxbdy) + fabs(bdxady)) * fabs(cdz);
  double err = (7.0 + 56.0 * EPS) * EPS * perm;
  if (det > err) return 1;
  if (-det > err) return -1;
  if (perm == 0.0) return 0; /* every product exactly zero */
  return orient3d_exact(a, b, c, d);
}

static __attribute__((noinline)) int orient2d_exact(int i, int j,
                                                    const double *a,
                                                    const double *b,
                                                    const double *c) {
  double acx[2], bcx[2], acy[2], bcy[2];
  two_sum(a[i], -c[i], &acx[0], &acx[1]);
  two_sum(b[i], -c[i], &bcx[0], &bcx[1]);
  two_sum(a[j], -c[j], &acy[0], &acy[1]);
  two_sum(b[j], -c[j], &bcy[0], &bcy[1]);
  double h[17];
  int n = 0;
  for (int u = 0; u < 2; u++)
    for (int v = 0; v < 2; v++) {
      n = add_prod2(h, n, acx[u], bcy[v]);
      n = add_prod2(h, n, -acy[u], bcx[v]);
    }
  return exp_sign(h, n);
}

/* Orientation of a, b, c projected along axis k (coordinates k+1, k+2
 * cyclically): for points of a plane whose normal has a nonzero k
 * component, the sign of the 3-D orientation about that normal, times a
 * fixed sign. */
static inline int orient2d(int k, const double *a, const double *b,
                           const double *c) {
  int i = k == 2 ? 0 : k + 1, j = k == 0 ? 2 : k - 1;
  double l = (a[i] - c[i]) * (b[j] - c[j]);
  double r = (a[j] - c[j]) * (b[i] - c[i]);
  double det = l - r;
  double err = (3.0 + 16.0 * EPS) * EPS * (fabs(l) + fabs(r));
  if (det > err) return 1;
  if (-det > err) return -1;
  if (l == 0.0 && r == 0.0) return 0;
  return orient2d_exact(i, j, a, b, c);
}

/* ==== triangle geometry ================================================== */

static inline void normal_of(const double *P, double n[3]) {
  double u[3], v[3];
  for (int a = 0; a < 3; a++) {
    u[a] = P[3 + a] - P[a];
    v[a] = P[6 + a] - P[a];
  }
  n[0] = u[1] * v[2] - u[2] * v[1];
  n[1] = u[2] * v[0] - u[0] * v[2];
  n[2] = u[0] * v[1] - u[1] * v[0];
}

/* An axis along which the triangle's projection has nonzero area (exactly),
 * the largest normal component first; -1 if the triangle is degenerate. */
static int drop_axis(const double *P) {
  double n[3];
  normal_of(P, n);
  int o[3] = {0, 1, 2};
  for (int i = 0; i < 3; i++)
    for (int j = i + 1; j < 3; j++)
      if (fabs(n[o[j]]) > fabs(n[o[i]])) {
        int t = o[i];
        o[i] = o[j];
        o[j] = t;
      }
  for (int i = 0; i < 3; i++)
    if (orient2d(o[i], P, P + 3, P + 6) != 0) return o[i];
  return -1;
}

static inline int same_pt(const double *a, const double *b) {
  return a[0] == b[0] && a[1] == b[1] && a[2] == b[2];
}

static inline void lerp(const double *a, const double *b, double t, double w[3]) {
  for (int k = 0; k < 3; k++) w[k] = a[k] + t * (b[k] - a[k]);
}

/* Lexicographic order of the coordinates (i, j) (a linear order along any
 * line of a plane that projects one-to-one along k). */
static inline int lex_less(int k, const double *a, const double *b) {
  int i = k == 2 ? 0 : k + 1, j = k == 0 ? 2 : k - 1;
  return a[i] < b[i] || (a[i] == b[i] && a[j] < b[j]);
}

/* Closed segments ab and cd of one plane (projection along k). */
static int seg_seg_2d(int k, const double *a, const double *b, const double *c,
                      const double *d, double w[3]) {
  int o1 = orient2d(k, a, b, c), o2 = orient2d(k, a, b, d);
  if (o1 * o2 > 0) return 0;
  int o3 = orient2d(k, c, d, a), o4 = orient2d(k, c, d, b);
  if (o3 * o4 > 0) return 0;
  if (o1 == 0 && o2 == 0) { /* collinear: intervals along the line */
    const double *a0 = a, *a1 = b, *c0 = c, *c1 = d;
    if (lex_less(k, a1, a0)) a0 = b, a1 = a;
    if (lex_less(k, c1, c0)) c0 = d, c1 = c;
    if (lex_less(k, a1, c0) || lex_less(k, c1, a0)) return 0;
    const double *lo = lex_less(k, a0, c0) ? c0 : a0;
    memcpy(w, lo, 3 * sizeof *w);
    return 1;
  }
  /* Crossing point, approximately: where ab meets the line cd. */
  int i = k == 2 ? 0 : k + 1, j = k == 0 ? 2 : k - 1;
  double ex = d[i] - c[i], ey = d[j] - c[j];
  double da = ex * (a[j] - c[j]) - ey * (a[i] - c[i]);
  double db = ex * (b[j] - c[j]) - ey * (b[i] - c[i]);
  double t = da != db ? da / (da - db) : 0.0;
  lerp(a, b, t < 0.0 ? 0.0 : t > 1.0 ? 1.0 : t, w);
  return 1;
}

/* p in the closed triangle T (same plane, projection along k). */
static int point_in_tri_2d(int k, const double *p, const double *T) {
  int s0 = orient2d(k, T, T + 3, p), s1 = orient2d(k, T + 3, T + 6, p);
  if (s0 * s1 < 0) return 0;
  int s2 = orient2d(k, T + 6, T, p);
  return !((s0 > 0 || s1 > 0 || s2 > 0) && (s0 < 0 || s1 < 0 || s2 < 0));
}

/* Closed segment ab against closed triangle T, all in one plane. */
static int seg_tri_2d(int k, const double *a, const double *b, const double *T,
                      double w[3]) {
  if (point_in_tri_2d(k, a, T)) {
    memcpy(w, a, 3 * sizeof *w);
    return 1;
  }
  if (point_in_tri_2d(k, b, T)) {
    memcpy(w, b, 3 * sizeof *w);
    return 1;
  }
  for (int e = 0; e < 3; e++)
    if (seg_seg_2d(k, a, b, T + 3 * e, T + 3 * ((e + 1) % 3), w)) return 1;
  return 0;
}

/* Two closed triangles of one plane. */
static int tri_tri_2d(int k, const double *P, const double *Q, double w[3]) {
  for (int e = 0; e < 3; e++)
    for (int f = 0; f < 3; f++)
      if (seg_seg_2d(k, P + 3 * e, P + 3 * ((e + 1) % 3), Q + 3 * f,
                     Q + 3 * ((f + 1) % 3), w))
        return 1;
  if (point_in_tri_2d(k, P, Q)) {
    memcpy(w, P, 3 * sizeof *w);
    return 1;
  }
  if (point_in_tri_2d(k, Q, P)) {
    memcpy(w, Q, 3 * sizeof *w);
    return 1;
  }
  return 0;
}

/* Closed segment ab against closed triangle T (kT: its projection axis),
 * oa and ob the sides of a and b (orient3d against T), not both strictly
 * on one side. */
static int seg_tri_3d(const double *a, const double *b, int oa, int ob,
                      const double *T, int kT, double w[3]) {
  if (oa == 0 && ob == 0) return seg_tri_2d(kT, a, b, T, w);
  int s0 = orient3d(a, b, T, T + 3);
  int s1 = orient3d(a, b, T + 3, T + 6);
  if (s0 * s1 < 0) return 0;
  int s2 = orient3d(a, b, T + 6, T);
  if ((s0 > 0 || s1 > 0 || s2 > 0) && (s0 < 0 || s1 < 0 || s2 < 0)) return 0;
  double n[3];
  normal_of(T, n);
  double da = 0.0, db = 0.0;
  for (int c = 0; c < 3; c++) {
    da += n[c] * (a[c] - T[c]);
    db += n[c] * (b[c] - T[c]);
  }
  double t = da != db ? da / (da - db) : 0.0;
  lerp(a, b, t < 0.0 ? 0.0 : t > 1.0 ? 1.0 : t, w);
  return 1;
}

/* The ray from v through x (x in the plane of v, c, d; projection along k)
 * lies in the closed wedge at v spanned by c and d (angle below pi). */
static int ray_in_wedge(int k, const double *v, const double *x,
                        const double *c, const double *d) {
  int s = orient2d(k, v, c, d);
  int s1 = orient2d(k, v, c, x);
  if (s1 != 0 && s1 != s) return 0;
  int s2 = orient2d(k, v, d, x);
  return s2 == 0 || s2 == -s;
}

/* Do the triangles P and Q (9 coordinates each, vertex ids pv and qv,
 * projection axes kp and kq; neither degenerate) meet beyond the convex
 * hull of their common vertices? w receives a point of (or next to) the
 * intersection. */
static int pair_meets(const double *P, const double *Q, const uint32_t *pv,
                      const uint32_t *qv, int kp, int kq, double w[3]) {
  int mp[3] = {-1, -1, -1}, ns = 0;
  for (int i = 0; i < 3; i++)
    for (int j = 0; j < 3; j++)
      if (pv[i] == qv[j] || same_pt(P + 3 * i, Q + 3 * j)) {
        mp[i] = j;
        ns++;
        break;
      }

  if (ns == 0) {
    int oq[3], op[3];
    for (int i = 0; i < 3; i++) oq[i] = orient3d(P, P + 3, P + 6, Q + 3 * i);
    if (oq[0] == oq[1] && oq[1] == oq[2] && oq[0] != 0) return 0;
    if (oq[0] == 0 && oq[1] == 0 && oq[2] == 0) return tri_tri_2d(kp, P, Q, w);
    for (int i = 0; i < 3; i++) op[i] = orient3d(Q, Q + 3, Q + 6, P + 3 * i);
    if (op[0] == op[1] && op[1] == op[2] && op[0] != 0) return 0;
    for (int e = 0; e < 3; e++) {
      int f = (e + 1) % 3;
      if (oq[e] * oq[f] <= 0 &&
          seg_tri_3d(Q + 3 * e, Q + 3 * f, oq[e], oq[f], P, kp, w))
        return 1;
    }
    for (int e = 0; e < 3; e++) {
      int f = (e + 1) % 3;
      if (op[e] * op[f] <= 0 &&
          seg_tri_3d(P + 3 * e, P + 3 * f, op[e], op[f], Q, kq, w))
        return 1;
    }
    return 0;
  }

  if (ns == 1) {
    int i0 = mp[0] >= 0 ? 0 : mp[1] >= 0 ? 1 : 2, j0 = mp[i0];
    const double *v = P + 3 * i0;
    const double *a = P + 3 * ((i0 + 1) % 3), *b = P + 3 * ((i0 + 2) % 3);
    const double *c = Q + 3 * ((j0 + 1) % 3), *d = Q + 3 * ((j0 + 2) % 3);
    int oc = orient3d(v, a, b, c), od = orient3d(v, a, b, d);
    if (oc * od > 0) return 0; /* Q meets P's plane at v only */
    int oa = orient3d(v, c, d, a), ob = orient3d(v, c, d, b);
    if (oa * ob > 0) return 0;
    if (oc != 0 || od != 0) {
      /* Two planes meeting along a line L through v: T1 and T2 cut L in
       * segments [v, w1] and [v, w2], w1 on ab (a and b included), w2 on
       * cd; they overlap beyond v iff w1 lies in T2 or w2 in T1. */
      return seg_tri_3d(a, b, oa, ob, Q, kq, w) ||
             seg_tri_3d(c, d, oc, od, P, kp, w);
    }
    /* Coplanar: two wedges at v (angles below pi) overlap beyond v iff
     * one of their four rays lies in the other. */
    const double *ray = NULL;
    if (ray_in_wedge(kp, v, a, c, d)) ray = a;
    else if (ray_in_wedge(kp, v, b, c, d)) ray = b;
    else if (ray_in_wedge(kp, v, c, a, b)) ray = c;
    else if (ray_in_wedge(kp, v, d, a, b)) ray = d;
    if (!ray) return 0;
    lerp(v, ray, 0.05, w);
    return 1;
  }

  if (ns == 2) {
    int i0 = mp[0] < 0 ? 1 : 0, i1 = mp[2] < 0 ? 1 : 2;
    int ia = 3 - i0 - i1, jb = 3 - mp[i0] - mp[i1];
    const double *u = P + 3 * i0, *x = P + 3 * i1;
    const double *a = P + 3 * ia, *b = Q + 3 * jb;
    if (orient3d(P, P + 3, P + 6, b) != 0) return 0;
    if (orient2d(kp, u, x, a) != orient2d(kp, u, x, b)) return 0;
    double m[3], q[3];
    for (int k = 0; k < 3; k++) {
      m[k] = 0.5 * (u[k] + x[k]);
      q[k] = 0.5 * (a[k] + b[k]);
    }
    lerp(m, q, 0.1, w);
    return 1;
  }

  for (int k = 0; k < 3; k++) w[k] = (P[k] + P[3 + k] + P[6 + k]) / 3.0;
  return 1; /* the same three points */
}


/* Per triangle: its projection axis, -1 when degenerate. */
static void projection_axes(const mx_trisoup *s, int8_t *axis) {
  const size_t nt = s->nt;
#pragma omp parallel for schedule(static) if (nt > 20000)
  for (size_t t = 0; t < nt; t++) {
    const uint32_t *v = s->tri + 3 * t;
    if (v[0] == v[1] || v[1] == v[2] || v[0] == v[2]) {
      axis[t] = -1;
      continue;
    }
    double P[9];
    for (int k = 0; k < 3; k++) {
      P[3 * k] = s->x[v[k]];
      P[3 * k + 1] = s->y[v[k]];
      P[3 * k + 2] = s->z[v[k]];
    }
    axis[t] = (int8_t)drop_axis(P);
  }
}

/* ==== examples =========================================================== */

static int ex_less(const mx_defect_example *a, const mx_defect_example *b) {
  if (a->tri != b->tri) return a->tri < b->tri;
  if (a->other != b->other) return a->other < b->other;
  if (a->v0 != b->v0) return a->v0 < b->v0;
  return a->v1 < b->v1;
}

/* Keeps the NEX smallest, sorted; *n is how many are stored. */
static void ex_add(mx_defect_example *arr, size_t *n, const mx_defect_example *e) {
  size_t m = *n;
  if (m == NEX && !ex_less(e, &arr[NEX - 1])) return;
  size_t i = m < NEX ? m : NEX - 1;
  while (i > 0 && ex_less(e, &arr[i - 1])) {
    arr[i] = arr[i - 1];
    i--;
  }
  arr[i] = *e;
  if (m < NEX) *n = m + 1;
}

static mx_defect_example edge_example(const mx_trisoup *s, uint32_t t,
                                      uint32_t other, uint32_t v0,
                                      uint32_t v1) {
  mx_defect_example e = {t, other, v0, v1, {0.5 * (s->x[v0] + s->x[v1]),
                                            0.5 * (s->y[v0] + s->y[v1]),
                                            0.5 * (s->z[v0] + s->z[v1])}};
  return e;
}

/* ==== edges ==============================================================
 * The edge table of geom/surface_topology.h over the soup's triangles,
 * those that repeat a vertex left out. */

static int indices_valid(const mx_trisoup *s) {
  if (s->nt > ((size_t)1 << 30)) {
    mx_error(NULL, 0, "surface check: too many triangles (%zu, at most 2^30)",
             s->nt);
    return MX_EINPUT;
  }
  for (size_t i = 0; i < 3 * s->nt; i++)
    if (s->tri[i] >= s->nv) {
      mx_error(NULL, 0, "surface check: triangle %zu uses vertex %u of %zu",
               i / 3, s->tri[i], s->nv);
      return MX_EINPUT;
    }
  return MX_OK;
}

typedef struct {
  size_t cnt[3]; /* boundary, nonmanifold, misoriented */
  size_t nex[3];
  mx_defect_example ex[3][NEX];
} edge_acc;

/* Runs starting in each chunk of this many entries of the table go to one
 * task. */
#define EDGE_CHUNK 16384

static int edge_defects(const mx_trisoup *s, const mx_edge_table *E,
                        mx_surface_defects *r) {
  const size_t n = E->n, nchunk = (n + EDGE_CHUNK - 1) / EDGE_CHUNK;
  const int nth = omp_get_max_threads();
  edge_acc *acc = mx_calloc((size_t)nth * sizeof *acc);
  if (!acc) return MX_ENOMEM;
#pragma omp parallel num_threads(nth) if (n > 150000)
  {
    edge_acc *A = &acc[omp_get_thread_num()];
#pragma omp for schedule(dynamic, 1)
    for (size_t ch = 0; ch < nchunk; ch++) {
      const size_t stop = mx_min((ch + 1) * EDGE_CHUNK, n);
      size_t i = ch * EDGE_CHUNK;
      while (i > 0 && i < stop && E->key[i] == E->key[i - 1]) i++;
      while (i < stop) {
        const size_t j = mx_edge_run_end(E, i);
        const uint32_t v = (uint32_t)(E->key[i] >> 32), w = (uint32_t)E->key[i];
        const uint32_t h0 = E->half[i], t0 = h0 / 3;
        const uint32_t t1 = j - i > 1 ? E->half[i + 1] / 3 : NONE;
        int kind = -1;
        if (j - i == 1)
          kind = 0;
        else if (j - i > 2)
          kind = 1;
        else if (s->tri[h0] == s->tri[E->half[i + 1]])
          kind = 2;
        if (kind >= 0) {
          A->cnt[kind]++;
          mx_defect_example x = edge_example(s, t0, t1, v, w);
          ex_add(A->ex[kind], &A->nex[kind], &x);
        }
        i = j;
      }
    }
  }
  size_t nex[3] = {0, 0, 0};
  mx_defect_example *dst[3] = {r->boundary, r->nonmanifold, r->misoriented};
  size_t *cnt[3] = {&r->boundary_edges, &r->nonmanifold_edges,
                    &r->misoriented_edges};
  for (int t = 0; t < nth; t++) {
    edge_acc *A = &acc[t];
    for (int k = 0; k < 3; k++) {
      *cnt[k] += A->cnt[k];
      for (size_t x = 0; x < A->nex[k]; x++) ex_add(dst[k], &nex[k], &A->ex[k][x]);
    }
  }
  mx_free(acc);
  return MX_OK;
}

/* Bodies: triangles connected through shared vertices (union-find over
 * the vertices); body[t] = the root of t's first vertex. */
static void bodies(const mx_trisoup *s, uint32_t *p, uint32_t *body) {
  for (size_t v = 0; v < s->nv; v++) p[v] = (uint32_t)v;
  for (size_t t = 0; t < s->nt; t++) {
    uint32_t a = mx_uf_find(p, s->tri[3 * t]);
    for (int k = 1; k < 3; k++) {
      uint32_t b = mx_uf_find(p, s->tri[3 * t + k]);
      if (a == b) continue;
      if (a < b) p[b] = a;
      else p[a] = b, a = b;
    }
  }
  for (size_t t = 0; t < s->nt; t++) body[t] = mx_uf_find(p, s->tri[3 * t]);
}

/* ==== broad phase ========================================================
 * The broad phase of geom/bvh.h: the Morton tree of the non-degenerate
 * triangles' boxes (mx_bvh_build_morton) traversed against itself
 * (mx_bvh_self_pairs). A pair of triangles reaches the narrow phase in slot
 * order, the one of smaller (Morton code of its box centre, id) first (the
 * point found at an intersection depends on the order). */

typedef struct {
  uint32_t n;         /* slots (non-degenerate triangles) */
  uint32_t *tid;      /* slot -> triangle */
  uint32_t *code;     /* Morton code per slot */
  double *tv;         /* 9 per slot */
  double *box;        /* 6 per slot: lo, hi */
  uint32_t *vid;      /* 3 per slot */
  int8_t *axis;       /* per slot */
  mx_bvh_node *nodes;
} bvh;

static void bvh_free(bvh *B) {
  mx_free(B->tid);
  mx_free(B->code);
  mx_free(B->tv);
  mx_free(B->box);
  mx_free(B->vid);
  mx_free(B->axis);
  mx_free(B->nodes);
  memset(B, 0, sizeof *B);
}

/* The slots: the non-degenerate triangles (axis_of[t] >= 0) sorted by
 * (Morton code of the box centre, id). */
static int bvh_build(bvh *B, const mx_trisoup *s, const int8_t *axis_of) {
  memset(B, 0, sizeof *B);
  size_t n = 0;
  for (size_t t = 0; t < s->nt; t++) n += axis_of[t] >= 0;
  B->n = (uint32_t)n;
  if (n == 0) return MX_OK;
  B->tid = mx_alloc(n * sizeof *B->tid);
  B->code = mx_alloc(n * sizeof *B->code);
  if (!B->tid || !B->code) {
    bvh_free(B);
    return MX_ENOMEM;
  }
  double lo[3] = {INFINITY, INFINITY, INFINITY};
  double hi[3] = {-INFINITY, -INFINITY, -INFINITY};
  n = 0;
  for (size_t t = 0; t < s->nt; t++) {
    if (axis_of[t] < 0) continue;
    B->tid[n++] = (uint32_t)t;
    for (int k = 0; k < 3; k++) {
      uint32_t v = s->tri[3 * t + k];
      double c[3] = {s->x[v], s->y[v], s->z[v]};
      for (int a = 0; a < 3; a++) {
        lo[a] = mx_min(lo[a], c[a]);
        hi[a] = mx_max(hi[a], c[a]);
      }
    }
  }
  double scale[3];
  for (int a = 0; a < 3; a++)
    scale[a] = hi[a] > lo[a] ? 1023.0 / (hi[a] - lo[a]) : 0.0;
#pragma omp parallel for schedule(static) if (n > 20000)
  for (size_t i = 0; i < n; i++) {
    const uint32_t *v = s->tri + 3 * (size_t)B->tid[i];
    const double *c[3] = {s->x, s->y, s->z};
    uint32_t q[3];
    for (int a = 0; a < 3; a++) {
      double m = mx_min(c[a][v[0]], mx_min(c[a][v[1]], c[a][v[2]]));
      double M = mx_max(c[a][v[0]], mx_max(c[a][v[1]], c[a][v[2]]));
      double f = (0.5 * (m + M) - lo[a]) * scale[a];
      q[a] = f <= 0.0 ? 0 : f >= 1023.0 ? 1023 : (uint32_t)f;
    }
    B->code[i] = (uint32_t)mx_morton_encode(q[2], q[1], q[0]); /* x highest */
  }
  if (mx_morton_sort30(B->code, B->tid, (uint32_t)n) != MX_OK) {
    bvh_free(B);
    return MX_ENOMEM;
  }
  B->tv = mx_alloc(9 * n * sizeof *B->tv);
  B->box = mx_alloc(6 * n * sizeof *B->box);
  B->vid = mx_alloc(3 * n * sizeof *B->vid);
  B->axis = mx_alloc(n);
  B->nodes = mx_alloc(2 * n * sizeof *B->nodes);
  if (!B->tv || !B->box || !B->vid || !B->axis || !B->nodes) {
    bvh_free(B);
    return MX_ENOMEM;
  }
#pragma omp parallel for schedule(static) if (n > 20000)
  for (size_t i = 0; i < n; i++) {
    const uint32_t t = B->tid[i];
    double *P = B->tv + 9 * i, *bx = B->box + 6 * i;
    for (int k = 0; k < 3; k++) {
      const uint32_t v = s->tri[3 * (size_t)t + k];
      B->vid[3 * i + k] = v;
      P[3 * k] = s->x[v];
      P[3 * k + 1] = s->y[v];
      P[3 * k + 2] = s->z[v];
    }
    for (int a = 0; a < 3; a++) {
      bx[a] = mx_min(P[a], mx_min(P[3 + a], P[6 + a]));
      bx[3 + a] = mx_max(P[a], mx_max(P[3 + a], P[6 + a]));
    }
    B->axis[i] = axis_of[t];
  }
  mx_bvh_build_morton(B->nodes, B->code, B->box, (uint32_t)n);
  return MX_OK;
}

/* ==== pairs ============================================================== */

typedef struct {
  size_t inter, cross, bodies;
  size_t nex[2];
  mx_defect_example ex[2][NEX];
  uint64_t *pairs; /* collecting (mx_surface_meeting_pairs): the pairs met */
  size_t npairs, cap;
  int oom;
  char pad_[64];
} pair_acc;

typedef struct {
  const bvh *B;
  const mx_trisoup *s;
  const uint32_t *body;
  pair_acc *acc; /* one per thread */
  int collect;   /* keep every pair met (acc->pairs) */
} pair_ctx;

/* Narrow phase on slots i < j whose boxes meet (the visit of
 * geom/bvh_pairs.h); not inline, so that pair_meets is inlined here. */
static void test_pair(void *ctx, uint32_t i, uint32_t j) {
  const pair_ctx *c = ctx;
  const bvh *B = c->B;
  double w[3];
  if (!pair_meets(B->tv + 9 * (size_t)i, B->tv + 9 * (size_t)j,
                  B->vid + 3 * (size_t)i, B->vid + 3 * (size_t)j, B->axis[i],
                  B->axis[j], w))
    return;
  pair_acc *A = &c->acc[omp_get_thread_num()];
  uint32_t ti = B->tid[i], tj = B->tid[j];
  if (c->collect) {
    if (A->npairs == A->cap) {
      const size_t cap = A->cap ? 2 * A->cap : 256;
      uint64_t *g = mx_realloc(A->pairs, cap * sizeof *g);
      if (!g) {
        A->oom = 1;
        return;
      }
      A->pairs = g;
      A->cap = cap;
    }
    A->pairs[A->npairs++] = ti < tj ? (uint64_t)ti << 32 | tj : (uint64_t)tj << 32 | ti;
    return;
  }
  mx_defect_example x = {ti < tj ? ti : tj, ti < tj ? tj : ti, NONE, NONE,
                         {w[0], w[1], w[2]}};
  const uint16_t *sh = c->s->shell;
  int kind = sh && sh[ti] != sh[tj];
  if (kind) A->cross++;
  else {
    A->inter++;
    if (c->body[ti] != c->body[tj]) A->bodies++;
  }
  ex_add(A->ex[kind], &A->nex[kind], &x);
}

#define MX_BVH_VISIT test_pair
#include "geom/bvh_pairs.h"

static int pair_defects(const bvh *B, const mx_trisoup *s, const uint32_t *body,
                        mx_surface_defects *r) {
  if (B->n < 2) return MX_OK;
  int nth = omp_get_max_threads();
  pair_acc *acc = mx_calloc((size_t)nth * sizeof *acc);
  if (!acc) return MX_ENOMEM;
  pair_ctx c = {B, s, body, acc, 0};
  mx_bvh_self_pairs(B->nodes, B->box, B->n, &c);
  size_t nex[2] = {0, 0};
  for (int t = 0; t < nth; t++) {
    pair_acc *A = &acc[t];
    r->intersecting_pairs += A->inter;
    r->crossing_pairs += A->cross;
    r->intersecting_bodies += A->bodies;
    for (size_t x = 0; x < A->nex[0]; x++) ex_add(r->intersecting, &nex[0], &A->ex[0][x]);
    for (size_t x = 0; x < A->nex[1]; x++) ex_add(r->crossing, &nex[1], &A->ex[1][x]);
  }
  mx_free(acc);
  return MX_OK;
}

/* ==== public ============================================================= */

int mx_surface_meeting_pairs(const mx_trisoup *s, uint64_t **pairs, size_t *npairs) {
  *pairs = NULL;
  *npairs = 0;
  if (s->nt < 2) return MX_OK;
  MX_CHECK(indices_valid(s));
  int8_t *axis = mx_alloc(s->nt);
  if (!axis) return MX_ENOMEM;
  projection_axes(s, axis);
  bvh B;
  int st = bvh_build(&B, s, axis);
  mx_free(axis);
  const int nth = omp_get_max_threads();
  pair_acc *acc = st ? NULL : mx_calloc((size_t)nth * sizeof *acc);
  if (!st && !acc) st = MX_ENOMEM;
  if (!st && B.n >= 2) {
    pair_ctx c = {&B, s, NULL, acc, 1};
    mx_bvh_self_pairs(B.nodes, B.box, B.n, &c);
  }
  size_t n = 0;
  for (int t = 0; acc && t < nth; t++) {
    n += acc[t].npairs;
    if (acc[t].oom) st = MX_ENOMEM;
  }
  uint64_t *all = st ? NULL : mx_alloc((n + 1) * sizeof *all);
  if (!st && !all) st = MX_ENOMEM;
  if (!st) {
    size_t k = 0;
    for (int t = 0; t < nth; t++) {
      if (acc[t].npairs) memcpy(all + k, acc[t].pairs, acc[t].npairs * sizeof *all);
      k += acc[t].npairs;
    }
    st = mx_sort_u64(all, NULL, n);
  }
  for (int t = 0; acc && t < nth; t++) mx_free(acc[t].pairs);
  mx_free(acc);
  bvh_free(&B);
  if (st) {
    mx_free(all);
    return st;
  }
  *pairs = all;
  *npairs = n;
  return MX_OK;
}

int mx_surface_defects_find(const mx_trisoup *s, mx_surface_defects *r) {
  memset(r, 0, sizeof *r);
  if (s->nt == 0) return MX_OK;
  MX_CHECK(indices_valid(s));
  const size_t nt = s->nt;
  int8_t *axis = mx_alloc(nt);
  uint32_t *body = mx_alloc(nt * sizeof *body);
  uint32_t *vroot = mx_alloc((s->nv ? s->nv : 1) * sizeof *vroot);
  mx_edge_table E;
  int st = axis && body && vroot ? mx_edge_table_build(&E, s->tri, NULL, (uint32_t)nt, (uint32_t)s->nv, 1, 0)
                                 : MX_ENOMEM;
  if (st == MX_OK) {
    st = edge_defects(s, &E, r);
    mx_edge_table_free(&E);
  }
  if (st != MX_OK) {
    mx_free(axis);
    mx_free(body);
    mx_free(vroot);
    return st;
  }
  bodies(s, vroot, body);
  mx_free(vroot);

  projection_axes(s, axis);
  size_t nex = 0;
  for (size_t t = 0; t < nt; t++) {
    if (axis[t] >= 0) continue;
    r->degenerate_triangles++;
    if (nex == NEX) continue;
    const uint32_t *v = s->tri + 3 * t;
    mx_defect_example x = {(uint32_t)t, NONE, NONE, NONE,
                           {(s->x[v[0]] + s->x[v[1]] + s->x[v[2]]) / 3.0,
                            (s->y[v[0]] + s->y[v[1]] + s->y[v[2]]) / 3.0,
                            (s->z[v[0]] + s->z[v[1]] + s->z[v[2]]) / 3.0}};
    ex_add(r->degenerate, &nex, &x);
  }

  bvh B;
  st = bvh_build(&B, s, axis);
  if (st == MX_OK) st = pair_defects(&B, s, body, r);
  bvh_free(&B);
  mx_free(axis);
  mx_free(body);
  return st;
}

size_t mx_surface_defects_total(const mx_surface_defects *r) {
  return r->boundary_edges + r->nonmanifold_edges + r->misoriented_edges +
         r->intersecting_pairs + r->crossing_pairs + r->degenerate_triangles;
}

int mx_surface_orient(mx_trisoup *s, size_t *flipped) {
  if (flipped) *flipped = 0;
  if (s->nt == 0) return MX_OK;
  MX_CHECK(indices_valid(s));
  const size_t nt = s->nt;
  mx_edge_table E;
  uint32_t *comp = mx_alloc(nt * sizeof *comp);
  uint8_t *flip = mx_calloc(nt);
  int st = comp && flip ? mx_edge_table_build(&E, s->tri, NULL, (uint32_t)nt, (uint32_t)s->nv, 1, 1) : MX_ENOMEM;
  if (st != MX_OK) {
    mx_free(comp);
    mx_free(flip);
    return st;
  }
  /* Pieces: shells through the manifold edges; flip[u] makes u agree with
   * the triangle it was reached from. */
  uint32_t ncomp = 0;
  st = mx_surface_shells(&E, 0, comp, flip, &ncomp, NULL, NULL);
  /* Per piece: open?, volume, size, flips so far. */
  uint8_t *open = NULL;
  double *vol = NULL;
  size_t *size = NULL;
  uint32_t *ref = NULL;
  if (st == MX_OK) {
    open = mx_calloc(ncomp ? ncomp : 1);
    vol = mx_calloc((ncomp ? ncomp : 1) * sizeof *vol);
    size = mx_calloc((ncomp ? ncomp : 1) * 2 * sizeof *size);
    ref = mx_alloc((ncomp ? ncomp : 1) * sizeof *ref);
    if (!open || !vol || !size || !ref) st = MX_ENOMEM;
  }
  if (st != MX_OK) goto done;
  for (size_t i = 0; i < E.n;) {
    const size_t j = mx_edge_run_end(&E, i);
    for (size_t a = i; a < j; a++) {
      uint32_t c = comp[E.half[a] / 3], uses = 0;
      for (size_t b = i; b < j; b++) uses += comp[E.half[b] / 3] == c;
      if (uses != 2) open[c] = 1;
    }
    i = j;
  }
  for (uint32_t c = 0; c < ncomp; c++) ref[c] = NONE;
  for (size_t t = 0; t < nt; t++) {
    uint32_t c = comp[t];
    if (c == NONE) continue;
    if (ref[c] == NONE) ref[c] = s->tri[3 * t];
    size[2 * c]++;
    size[2 * c + 1] += flip[t];
    const uint32_t *v = s->tri + 3 * t;
    double o[3] = {s->x[ref[c]], s->y[ref[c]], s->z[ref[c]]}, p[3][3];
    for (int k = 0; k < 3; k++) {
      p[k][0] = s->x[v[k]] - o[0];
      p[k][1] = s->y[v[k]] - o[1];
      p[k][2] = s->z[v[k]] - o[2];
    }
    double d = p[0][0] * (p[1][1] * p[2][2] - p[1][2] * p[2][1]) -
               p[0][1] * (p[1][0] * p[2][2] - p[1][2] * p[2][0]) +
               p[0][2] * (p[1][0] * p[2][1] - p[1][1] * p[2][0]);
    vol[c] += flip[t] ? -d : d;
  }
  size_t nflip = 0;
  for (size_t t = 0; t < nt; t++) {
    uint32_t c = comp[t];
    if (c == NONE) continue;
    uint8_t invert = open[c] ? 2 * size[2 * c + 1] > size[2 * c] : vol[c] < 0.0;
    if (!(flip[t] ^ invert)) continue;
    uint32_t *v = s->tri + 3 * t, x = v[1];
    v[1] = v[2];
    v[2] = x;
    nflip++;
  }
  if (flipped) *flipped = nflip;
done:
  mx_free(open);
  mx_free(vol);
  mx_free(size);
  mx_free(ref);
  mx_edge_table_free(&E);
  mx_free(comp);
  mx_free(flip);
  return st;
}

/* ==== messages =========================================================== */

typedef struct {
  char *p;
  size_t left;
} outbuf;

static void out(outbuf *o, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static void out(outbuf *o, const char *fmt, ...) {
  if (o->left <= 1) return;
  va_list ap;
  va_start(ap, fmt);
  int k = vsnprintf(o->p, o->left, fmt, ap);
  va_end(ap);
  if (k < 0) return;
  size_t m = (size_t)k < o->left - 1 ? (size_t)k : o->left - 1;
  o->p += m;
  o->left -= m;
}

/* "triangle T", "triangles T and U", "face F (triangle 2 of 4, line L)",
 * ... as the inputs' files number them (mx_trisoup_name), with "of input
 * K" when the soup holds several inputs. */
static void out_tris(outbuf *o, const mx_trisoup *s, uint32_t t, uint32_t u) {
  const int multi = s && s->nshells > 1;
  const unsigned it = s && s->shell && t < s->nt ? s->shell[t] : 0;
  char nt[128], nu[128];
  const int pt = mx_trisoup_name(s, t, nt, sizeof nt);
  if (u == NONE) {
    out(o, "%s", nt);
    if (multi) out(o, " of input %u", it);
    return;
  }
  const unsigned iu = s && s->shell && u < s->nt ? s->shell[u] : 0;
  const int pu = mx_trisoup_name(s, u, nu, sizeof nu);
  if (it != iu) {
    out(o, "%s of input %u and %s of input %u", nt, it, nu, iu);
    return;
  }
  /* "triangles 3 and 5" when both names are a word and a number */
  const char *sp = strchr(nt, ' ');
  if (!pt && !pu && sp && strncmp(nt, nu, (size_t)(sp - nt) + 1) == 0)
    out(o, "%.*ss %s and %s", (int)(sp - nt), nt, sp + 1, strchr(nu, ' ') + 1);
  else
    out(o, "%s and %s", nt, nu);
  if (multi) out(o, " of input %u", it);
}

#define SHOWN 3

static void out_examples(outbuf *o, const mx_trisoup *s,
                         const mx_defect_example *ex, size_t count) {
  size_t m = count < SHOWN ? count : SHOWN;
  out(o, ", e.g. ");
  for (size_t i = 0; i < m; i++) {
    if (i) out(o, "; ");
    if (ex[i].v0 != NONE) out(o, "edge of ");
    out_tris(o, s, ex[i].tri, ex[i].other);
    out(o, " at (%g, %g, %g)", ex[i].p[0], ex[i].p[1], ex[i].p[2]);
  }
  if (count > m) out(o, "; ...");
  out(o, "\n");
}

void mx_surface_defects_describe(const mx_surface_defects *r,
                                 const mx_trisoup *s, char *buf, size_t n) {
  if (n == 0) return;
  buf[0] = '\0';
  outbuf o = {buf, n};
  if (mx_surface_defects_total(r) == 0) {
    out(&o, "no defects\n");
    return;
  }
  size_t c;
  if ((c = r->boundary_edges)) {
    out(&o, "%zu open edge%s (used by one triangle only)", c, c == 1 ? "" : "s");
    out_examples(&o, s, r->boundary, c);
  }
  if ((c = r->nonmanifold_edges)) {
    out(&o, "%zu non-manifold edge%s (used by more than two triangles)", c,
        c == 1 ? "" : "s");
    out_examples(&o, s, r->nonmanifold, c);
  }
  if ((c = r->misoriented_edges)) {
    out(&o,
        "%zu misoriented edge%s (used twice in the same direction: the two "
        "triangles' normals disagree)",
        c, c == 1 ? "" : "s");
    out_examples(&o, s, r->misoriented, c);
  }
  if ((c = r->intersecting_pairs)) {
    out(&o, "%zu pair%s of triangles of one input intersect%s (self-intersection",
        c, c == 1 ? "" : "s", c == 1 ? "s" : "");
    if (r->intersecting_bodies)
      out(&o, "; %zu of them between separate bodies", r->intersecting_bodies);
    out(&o, ")");
    out_examples(&o, s, r->intersecting, c);
  }
  if ((c = r->crossing_pairs)) {
    out(&o, "%zu pair%s of triangles of two inputs meet%s (the inputs cross or touch)",
        c, c == 1 ? "" : "s", c == 1 ? "s" : "");
    out_examples(&o, s, r->crossing, c);
  }
  if ((c = r->degenerate_triangles)) {
    out(&o, "%zu degenerate triangle%s (zero area)", c, c == 1 ? "" : "s");
    out_examples(&o, s, r->degenerate, c);
  }
}
