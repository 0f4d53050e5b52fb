/* Octant/triangle intersection by separating axes (Akenine-Moller's 13 axes:
 * the 3 box normals, the triangle normal, the 9 cross products of box and
 * triangle edges). Boxes are closed: touching counts as meeting. */
#ifndef MX_INTERSECT_H
#define MX_INTERSECT_H

/* c: box centre, h: half sides, v: the triangle's 9 coordinates. */
int mx_tri_box_overlap(const double c[3], const double h[3], const double v[9]);

#endif
