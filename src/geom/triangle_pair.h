/* Whether two triangles meet beyond what they share, decided with exact
 * signs only (no tolerance): orient3d and orient2d in double behind a
 * semi-static error bound (Shewchuk's bound A) and, when that does not
 * decide, exactly (each difference of coordinates split into two doubles,
 * each product made exact with fma, the terms summed into a nonoverlapping
 * expansion whose largest component has the sign). Coplanar cases are
 * decided in the coordinate plane where the triangle's projection has
 * nonzero (exact) area. The definitions ("meet", shared vertices) are those
 * of geom/surface_defects.h. */
#ifndef MX_TRIANGLE_PAIR_H
#define MX_TRIANGLE_PAIR_H

#include <stdint.h>

#include "soa/trisoup.h"

/* Per triangle of s, an axis along which it projects with nonzero area
 * (exactly), the largest normal component first; -1 if degenerate
 * (repeated vertex, or exactly collinear points). */
void mx_triangle_axes(const mx_trisoup *s, int8_t *axis);

/* Do the triangles P and Q (9 coordinates each, vertex ids pv and qv,
 * projection axes kp and kq from mx_triangle_axes; neither degenerate)
 * meet beyond the convex hull of their common vertices (same id or same
 * coordinates)? w receives a point of (or next to) the intersection; it
 * depends on which triangle is P. */
int mx_triangles_meet(const double *P, const double *Q, const uint32_t *pv,
                      const uint32_t *qv, int kp, int kq, double w[3]);

#endif
