/* Exact tests on pairs of triangles, for the self-intersection test of
 * geom/surface_defects.c: orient3d and orient2d with exact fallbacks, the
 * projection axis of a triangle, and whether two triangles meet beyond
 * their common vertices (see triangle_pair.h). */
#include "geom/triangle_pair.h"

#include <math.h>
#include <string.h>

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
static int triangle_axis(const double *P) {
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
int mx_triangles_meet(const double *P, const double *Q, const uint32_t *pv,
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


void mx_triangle_axes(const mx_trisoup *s, int8_t *axis) {
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
    axis[t] = (int8_t)triangle_axis(P);
  }
}
