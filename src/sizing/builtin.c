/* The test functions F1..F5 of Jurczyk & Glut 2016 (section 3.1, eqs. 9 to
 * 13) as size sources, with their domains. F1 is written as printed there,
 * h = exp((x^2 + y^2 + z^2) / (2 * 0.1^2)); its trees depend only on how
 * fast log h changes, the same for the opposite sign. */
#include "sizing/cspace.h"

#include <math.h>
#include <string.h>

static void f1(void *user, size_t n, const double *xyz, double *h) {
  (void)user;
  for (size_t i = 0; i < n; i++) {
    const double *p = xyz + 3 * i;
    const double v = exp((p[0] * p[0] + p[1] * p[1] + p[2] * p[2]) / (2.0 * 0.1 * 0.1));
    h[3 * i] = h[3 * i + 1] = h[3 * i + 2] = v;
  }
}

static void f2(void *user, size_t n, const double *xyz, double *h) {
  (void)user;
  /* the line through A = (-1, -1, -0.5) and B = (0.5, 1, 0) */
  const double a[3] = {-1.0, -1.0, -0.5}, d[3] = {1.5, 2.0, 0.5};
  const double dd = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
  for (size_t i = 0; i < n; i++) {
    const double *p = xyz + 3 * i;
    const double w[3] = {p[0] - a[0], p[1] - a[1], p[2] - a[2]};
    const double t = (w[0] * d[0] + w[1] * d[1] + w[2] * d[2]) / dd;
    double l2 = 0.0;
    for (int k = 0; k < 3; k++) {
      const double e = w[k] - t * d[k];
      l2 += e * e;
    }
    const double v = l2 > 1e-10 ? l2 : 1e-10;
    h[3 * i] = h[3 * i + 1] = h[3 * i + 2] = v;
  }
}

static void f3(void *user, size_t n, const double *xyz, double *h) {
  (void)user;
  static const double P[3][3] = {{0.5, 0.5, 0.5}, {0.5, 0.5, -0.5}, {0.0, 0.0, 0.0}};
  for (size_t i = 0; i < n; i++) {
    const double *p = xyz + 3 * i;
    double m = 0.0;
    for (int k = 0; k < 3; k++) {
      const double x = p[0] - P[k][0], y = p[1] - P[k][1], z = p[2] - P[k][2];
      m += sqrt(x * x + y * y + z * z) / 3.0;
    }
    const double v = m > 1e-10 ? m : 1e-10;
    h[3 * i] = h[3 * i + 1] = h[3 * i + 2] = v;
  }
}

/* F4: y in [0, 2] 1 - 19y/40; (2, 4.5] 20^((2y - 9)/5); (4.5, 7]
 * 5^((9 - 2y)/5); (7, 9] 1/5 + 4/5 ((y - 7)/2)^4. */
static double f4y(double y) {
  if (y <= 2.0) return 1.0 - 19.0 * y / 40.0;
  if (y <= 4.5) return pow(20.0, (2.0 * y - 9.0) / 5.0);
  if (y <= 7.0) return pow(5.0, (9.0 - 2.0 * y) / 5.0);
  const double u = (y - 7.0) / 2.0;
  return 0.2 + 0.8 * u * u * u * u;
}

static void f4(void *user, size_t n, const double *xyz, double *h) {
  (void)user;
  for (size_t i = 0; i < n; i++) {
    const double v = f4y(xyz[3 * i + 1]);
    h[3 * i] = h[3 * i + 1] = h[3 * i + 2] = v;
  }
}

/* F5: h1 of x with breaks 2, 3.5, 5, 7 (exponents (2x - 7)/3, (7 - 2x)/3),
 * h2 = F4's of y, h3 of z with breaks 2, 5.5, 9, 11 ((2z - 11)/7). */
static double f5x(double x) {
  if (x <= 2.0) return 1.0 - 19.0 * x / 40.0;
  if (x <= 3.5) return pow(20.0, (2.0 * x - 7.0) / 3.0);
  if (x <= 5.0) return pow(5.0, (7.0 - 2.0 * x) / 3.0);
  const double u = (x - 5.0) / 2.0;
  return 0.2 + 0.8 * u * u * u * u;
}

static double f5z(double z) {
  if (z <= 2.0) return 1.0 - 19.0 * z / 40.0;
  if (z <= 5.5) return pow(20.0, (2.0 * z - 11.0) / 7.0);
  if (z <= 9.0) return pow(5.0, (11.0 - 2.0 * z) / 7.0);
  const double u = (z - 9.0) / 2.0;
  return 0.2 + 0.8 * u * u * u * u;
}

static void f5(void *user, size_t n, const double *xyz, double *h) {
  (void)user;
  for (size_t i = 0; i < n; i++) {
    h[3 * i] = f5x(xyz[3 * i]);
    h[3 * i + 1] = f4y(xyz[3 * i + 1]);
    h[3 * i + 2] = f5z(xyz[3 * i + 2]);
  }
}

mx_size_fn mx_size_builtin(const char *name, double lo[3], double hi[3]) {
  static const struct {
    const char *name;
    mx_size_fn f;
    double lo[3], hi[3];
  } T[5] = {{"F1", f1, {-1, -1, -1}, {1, 1, 1}},
            {"F2", f2, {-1, -1, -1}, {1, 1, 1}},
            {"F3", f3, {-1, -1, -1}, {1, 1, 1}},
            {"F4", f4, {0, 0, 0}, {9, 9, 9}},
            {"F5", f5, {0, 0, 0}, {7, 9, 11}}};
  for (int k = 0; name && k < 5; k++)
    if (strcmp(name, T[k].name) == 0) {
      if (lo) memcpy(lo, T[k].lo, sizeof T[k].lo);
      if (hi) memcpy(hi, T[k].hi, sizeof T[k].hi);
      return T[k].f;
    }
  return NULL;
}
