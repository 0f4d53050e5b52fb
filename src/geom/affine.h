/* A 3x4 affine map (x = A[0] u + A[1] v + A[2] w + A[3], y from A[4..7],
 * z from A[8..11]): a label image's voxel-to-world transform (issue 28). */
#ifndef MX_AFFINE_H
#define MX_AFFINE_H

#include <math.h>

/* The determinant of its linear part. */
static inline double mx_affine_det(const double A[12]) {
  return A[0] * (A[5] * A[10] - A[6] * A[9]) - A[1] * (A[4] * A[10] - A[6] * A[8]) +
         A[2] * (A[4] * A[9] - A[5] * A[8]);
}

/* The length of column a (the step of index a in the world). */
static inline double mx_affine_column(const double A[12], int a) {
  return sqrt(A[a] * A[a] + A[4 + a] * A[4 + a] + A[8 + a] * A[8 + a]);
}

/* 1 when its linear part is a rotation (or mirror) times one scale: shapes,
 * and J_ENS, do not change under it. */
static inline int mx_affine_similar(const double A[12]) {
  double n[3];
  for (int a = 0; a < 3; a++) n[a] = mx_affine_column(A, a);
  int similar = fabs(n[0] - n[1]) <= 1e-12 * n[0] && fabs(n[0] - n[2]) <= 1e-12 * n[0];
  for (int a = 0; a < 3 && similar; a++)
    for (int b = a + 1; b < 3; b++)
      similar &= fabs(A[a] * A[b] + A[4 + a] * A[4 + b] + A[8 + a] * A[8 + b]) <= 1e-12 * n[a] * n[b];
  return similar;
}

static inline void mx_affine_apply(const double A[12], const double u[3], double x[3]) {
  for (int r = 0; r < 3; r++)
    x[r] = A[4 * r] * u[0] + A[4 * r + 1] * u[1] + A[4 * r + 2] * u[2] + A[4 * r + 3];
}

/* The world's axis-aligned box around the image of [ulo, uhi]. */
static inline void mx_affine_box(const double A[12], const double ulo[3], const double uhi[3],
                                 double lo[3], double hi[3]) {
  for (int r = 0; r < 3; r++) {
    lo[r] = INFINITY;
    hi[r] = -INFINITY;
  }
  for (int c = 0; c < 8; c++) {
    const double u[3] = {(c & 1) ? uhi[0] : ulo[0], (c & 2) ? uhi[1] : ulo[1],
                         (c & 4) ? uhi[2] : ulo[2]};
    double x[3];
    mx_affine_apply(A, u, x);
    for (int r = 0; r < 3; r++) {
      lo[r] = fmin(lo[r], x[r]);
      hi[r] = fmax(hi[r], x[r]);
    }
  }
}

#endif
