/* Geometry that several passes of the checker use: cubic cells over a box
 * (the coordinate hash of check_duplicates.c, the triangle grid of
 * check_distance.c) and the squared distance from a point to a triangle
 * (check_contacts.c, check_distance.c). The checker's own, apart from
 * geom/distance.h's closest points, which the mesher uses. */
#include "verify/check_passes.h"

/* Cubic cells over a box of extents ext: about `target` of them over the
 * dimensions wider than a cell, at most maxdim per axis. Sets h and d.
 * Works on the extents relative to the largest, each at least 1 / maxdim,
 * so no product underflows (a box of extents 1 x 1e-300 x 1e-300 gets
 * cells along its long side only). */
void mx_ck_cell_grid(const double ext[3], double target, int maxdim,
                      double *h_out, int d[3]) {
  double mext = mx_max(ext[0], mx_max(ext[1], ext[2]));
  if (!(mext > 0.0) || !isfinite(mext)) { /* one point, or no range */
    d[0] = d[1] = d[2] = 1;
    *h_out = mext > 0.0 ? INFINITY : 1.0;
    return;
  }
  if (!(target >= 1.0)) target = 1.0;
  const double floor_r = 1.0 / maxdim;
  double r[3];
  for (int a = 0; a < 3; a++) r[a] = mx_max(ext[a] / mext, floor_r);
  double h = 0.0;
  for (int it = 0; it < 4; it++) {
    double prod = 1.0;
    int k = 0;
    for (int a = 0; a < 3; a++)
      if (r[a] > h) {
        prod *= r[a];
        k++;
      }
    if (k == 0) {
      prod = 1.0;
      k = 1;
    }
    h = mx_max(pow(prod / target, 1.0 / k), floor_r);
  }
  for (int a = 0; a < 3; a++) {
    const double n = ceil(ext[a] / mext / h);
    d[a] = !(n >= 1.0) ? 1 : n > maxdim ? maxdim : (int)n;
  }
  h *= mext;
  for (int a = 0; a < 3; a++) h = mx_max(h, ext[a] / d[a]);
  *h_out = h;
}

/* Squared distance from p to the triangle a-b-c: the closest point lies in
 * the Voronoi region of a vertex, of an edge, or of the face, told apart by
 * the signs of dot products and of barycentric numerators. */
double mx_ck_point_triangle_d2(const double p[3], const double a[3],
                                const double b[3], const double c[3]) {
  double ab[3], ac[3], ap[3], bp[3], cp[3];
  for (int x = 0; x < 3; x++) {
    ab[x] = b[x] - a[x];
    ac[x] = c[x] - a[x];
    ap[x] = p[x] - a[x];
    bp[x] = p[x] - b[x];
    cp[x] = p[x] - c[x];
  }
#define DOT(u, v) ((u)[0] * (v)[0] + (u)[1] * (v)[1] + (u)[2] * (v)[2])
  const double d1 = DOT(ab, ap), d2 = DOT(ac, ap);
  if (d1 <= 0.0 && d2 <= 0.0) return DOT(ap, ap);
  const double d3 = DOT(ab, bp), d4 = DOT(ac, bp);
  if (d3 >= 0.0 && d4 <= d3) return DOT(bp, bp);
  const double d5 = DOT(ab, cp), d6 = DOT(ac, cp);
  if (d6 >= 0.0 && d5 <= d6) return DOT(cp, cp);
  const double vc = d1 * d4 - d3 * d2, vb = d5 * d2 - d1 * d6,
               va = d3 * d6 - d5 * d4;
  double s, t; /* closest point a + s ab + t ac */
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {
    s = d1 / (d1 - d3);
    t = 0.0;
  } else if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {
    s = 0.0;
    t = d2 / (d2 - d6);
  } else if (va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0) {
    const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6)); /* along b-c */
    s = 1.0 - w;
    t = w;
  } else {
    const double den = va + vb + vc;
    if (!(den > 0.0)) { /* degenerate triangle: its vertices */
      return mx_min(DOT(ap, ap), mx_min(DOT(bp, bp), DOT(cp, cp)));
    }
    s = vb / den;
    t = vc / den;
  }
  double d[3];
  for (int x = 0; x < 3; x++) d[x] = ap[x] - s * ab[x] - t * ac[x];
  return DOT(d, d);
#undef DOT
}
