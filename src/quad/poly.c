/* Polylines: free, domain checks, point location, features (STUB: brute
 * force; to be replaced). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "common.h"
#include "quad/quad.h"

void mx_poly_free(mx_poly *P) {
  mx_free(P->xy);
  mx_free(P->seg);
  mx_free(P->line);
  mx_free(P->holes);
  mx_free(P->path);
  memset(P, 0, sizeof *P);
}

int mx_poly_check_domain(mx_poly *P) {
  P->nloops = 1;
  return MX_OK;
}

int mx_poly_index_build(const mx_poly *P, mx_poly_index *I) {
  memset(I, 0, sizeof *I);
  I->P = P;
  return MX_OK;
}

void mx_poly_index_free(mx_poly_index *I) {
  mx_free(I->off);
  mx_free(I->ids);
  memset(I, 0, sizeof *I);
}

int mx_poly_inside(const mx_poly_index *I, const double p[2]) {
  const mx_poly *P = I->P;
  int c = 0;
  for (size_t s = 0; s < P->ns; s++) {
    const double *a = P->xy + 2 * P->seg[2 * s], *b = P->xy + 2 * P->seg[2 * s + 1];
    if ((a[1] > p[1]) != (b[1] > p[1])) {
      const double x = a[0] + (p[1] - a[1]) * (b[0] - a[0]) / (b[1] - a[1]);
      if (x > p[0]) c ^= 1;
    }
  }
  return c;
}

uint32_t mx_poly_closest(const mx_poly_index *I, const double p[2], double rmax, double q[2],
                         double *d2) {
  const mx_poly *P = I->P;
  uint32_t best = UINT32_MAX;
  double bd = rmax * rmax;
  for (size_t s = 0; s < P->ns; s++) {
    const double *a = P->xy + 2 * P->seg[2 * s], *b = P->xy + 2 * P->seg[2 * s + 1];
    const double u[2] = {b[0] - a[0], b[1] - a[1]}, w[2] = {p[0] - a[0], p[1] - a[1]};
    const double l2 = u[0] * u[0] + u[1] * u[1];
    double t = l2 > 0 ? (u[0] * w[0] + u[1] * w[1]) / l2 : 0.0;
    t = t < 0 ? 0 : t > 1 ? 1 : t;
    const double c[2] = {a[0] + t * u[0], a[1] + t * u[1]};
    const double d = (p[0] - c[0]) * (p[0] - c[0]) + (p[1] - c[1]) * (p[1] - c[1]);
    if (d <= bd) {
      bd = d;
      best = (uint32_t)s;
      q[0] = c[0];
      q[1] = c[1];
    }
  }
  *d2 = bd;
  return best;
}

int mx_poly_features(const mx_poly *P, uint32_t **out, size_t *n) {
  (void)P;
  *out = mx_alloc(1);
  *n = 0;
  return *out ? MX_OK : MX_ENOMEM;
}
