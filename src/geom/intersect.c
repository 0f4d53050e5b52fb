#include "geom/intersect.h"

#include "base/common.h"

#include <math.h>

/* Projection interval of the triangle (vertices relative to the box centre)
 * on axis n, against the box's projection radius. */
static inline int separated(const double n[3], const double p0[3],
                            const double p1[3], const double p2[3],
                            const double h[3]) {
  double d0 = n[0] * p0[0] + n[1] * p0[1] + n[2] * p0[2];
  double d1 = n[0] * p1[0] + n[1] * p1[1] + n[2] * p1[2];
  double d2 = n[0] * p2[0] + n[1] * p2[1] + n[2] * p2[2];
  double mn = mx_min(d0, mx_min(d1, d2)), mx = mx_max(d0, mx_max(d1, d2));
  double r = h[0] * fabs(n[0]) + h[1] * fabs(n[1]) + h[2] * fabs(n[2]);
  return mn > r || mx < -r;
}

int mx_tri_box_overlap(const double c[3], const double h[3],
                       const double v[9]) {
  double p[3][3];
  for (int i = 0; i < 3; i++)
    for (int a = 0; a < 3; a++) p[i][a] = v[3 * i + a] - c[a];
  /* Box normals: the triangle's bounding box against the box. */
  for (int a = 0; a < 3; a++) {
    double mn = mx_min(p[0][a], mx_min(p[1][a], p[2][a]));
    double mx = mx_max(p[0][a], mx_max(p[1][a], p[2][a]));
    if (mn > h[a] || mx < -h[a]) return 0;
  }
  double e[3][3];
  for (int a = 0; a < 3; a++) {
    e[0][a] = p[1][a] - p[0][a];
    e[1][a] = p[2][a] - p[1][a];
    e[2][a] = p[0][a] - p[2][a];
  }
  /* Triangle normal. */
  double n[3] = {e[0][1] * e[1][2] - e[0][2] * e[1][1],
                 e[0][2] * e[1][0] - e[0][0] * e[1][2],
                 e[0][0] * e[1][1] - e[0][1] * e[1][0]};
  if (separated(n, p[0], p[1], p[2], h)) return 0;
  /* Cross products of the box axes with the triangle edges. */
  for (int i = 0; i < 3; i++) {
    const double ax[3][3] = {{0.0, -e[i][2], e[i][1]},
                             {e[i][2], 0.0, -e[i][0]},
                             {-e[i][1], e[i][0], 0.0}};
    for (int a = 0; a < 3; a++)
      if (separated(ax[a], p[0], p[1], p[2], h)) return 0;
  }
  return 1;
}
