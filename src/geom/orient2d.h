/* The exact orientation of three points of the plane, shared by the 2D
 * polylines (src/quad/poly.c) and the splitting of polygons into triangles
 * (src/io/polygon_split.c): a filtered double evaluation and, when that is
 * too close to call, the exact sign of the sum of its six products (each
 * split into two doubles by fma), summed as a nonoverlapping expansion
 * (Shewchuk's Grow-Expansion), whose sign is that of its largest, last
 * nonzero, component. Exact while the products neither overflow nor
 * underflow. */
#ifndef MX_ORIENT2D_H
#define MX_ORIENT2D_H

#include <math.h>

static inline void mx_two_sum(double a, double b, double *s, double *err) {
  const double x = a + b, bv = x - a, av = x - bv;
  *s = x;
  *err = (a - av) + (b - bv);
}

/* The sign of the exact sum of t[0..n), n <= 12. */
static inline int mx_expansion_sign(const double *t, int n) {
  double e[12];
  int m = 0;
  for (int i = 0; i < n; i++) {
    double q = t[i];
    for (int j = 0; j < m; j++) mx_two_sum(q, e[j], &q, &e[j]);
    e[m++] = q;
  }
  for (int j = m - 1; j >= 0; j--)
    if (e[j] != 0.0) return e[j] > 0.0 ? 1 : -1;
  return 0;
}

/* 1 when c lies left of a->b, -1 right of it, 0 on its line (a, b, c: x, y). */
static inline int mx_orient2d(const double *a, const double *b, const double *c) {
  const double l = (b[0] - a[0]) * (c[1] - a[1]), r = (b[1] - a[1]) * (c[0] - a[0]);
  const double det = l - r, bound = 3.3306690738754716e-16 * (fabs(l) + fabs(r));
  if (det > bound) return 1;
  if (-det > bound) return -1;
  /* det = bx cy - bx ay - ax cy - by cx + by ax + ay cx, exactly */
  const double f[6][2] = {{b[0], c[1]},  {-b[0], a[1]}, {-a[0], c[1]},
                          {-b[1], c[0]}, {b[1], a[0]},  {a[1], c[0]}};
  double t[12];
  for (int k = 0; k < 6; k++) {
    t[2 * k] = f[k][0] * f[k][1];
    t[2 * k + 1] = fma(f[k][0], f[k][1], -t[2 * k]);
    if (!isfinite(t[2 * k])) return (det > 0) - (det < 0); /* beyond exact reach */
  }
  return mx_expansion_sign(t, 12);
}

#endif
