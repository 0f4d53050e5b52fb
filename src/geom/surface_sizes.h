/* Sizes a surface asks for (issue 27: sources of the size field), as point
 * sources: places, sizes and the area each stands for, for
 * sizing/sources.h.
 *
 * Curvature: on every edge a-b shared by two triangles, the normal
 * curvature along it, kappa = (|n_a . e| + |n_b . e|) / |e|^2 with e = b - a
 * and n the vertex pseudonormals (exactly 1/R on a sphere of radius R,
 * whatever the triangles); an element spanning the angle theta of that
 * curve has the size theta / kappa. Each such edge gives points along it,
 * no farther apart than that size. A flat edge asks nothing; a sharp
 * crease asks for elements of about theta times the triangles' scale.
 *
 * Thickness (Hexotic's "geometric diameter"): from points spread over each
 * triangle, a ray into the domain (against the outward normal) and one out
 * of it; the first triangle the ray meets, if it faces the other way
 * within 60 degrees (the opposite side of a part, or of a gap: a crease
 * met at a grazing angle is not a thickness), is at the distance t, and the
 * chord gets points of size t / n along it, n + 1 of them: n elements
 * across. The points on a triangle are the centroids of its k x k
 * sub-triangles, k from the triangle's longest edge over a spacing (the
 * box's diagonal / 64), then again finer on the triangles whose thickness
 * is below that spacing (at most 128 x 128 per triangle, and no finer than
 * the floor). No size below the floor: where two faces meet at an acute
 * edge (a knife edge: a cone's rim, a sphere cut by a plane) the thickness
 * falls to zero towards the edge, and without a floor the octree would be
 * refined to its deepest level along it. Rays in
 * parallel, the output in triangle order (the same for any thread count).
 *
 * Both need the index's orientation to be outward (mx_surface_index_build
 * and its variants: fn). */
#ifndef MX_SURFACE_SIZES_H
#define MX_SURFACE_SIZES_H

#include <stddef.h>
#include <stdint.h>

#include "geom/distance.h"

typedef struct {
  size_t n, cap;
  double *xyz; /* 3 n */
  double *h;   /* n */
  double *w;   /* n: the area each point stands for */
} mx_point_sizes;

void mx_point_sizes_free(mx_point_sizes *p);

/* Appends the curvature sources of S for the angle theta (radians, > 0). */
int mx_surface_curvature_sizes(const mx_surface_index *S, double theta, mx_point_sizes *out);
/* Appends the thickness sources of S for n >= 1 elements across, no size
 * below floor (> 0; 0: the box's diagonal / 256). */
int mx_surface_thickness_sizes(const mx_surface_index *S, double n, double floor,
                               mx_point_sizes *out);

/* The first triangle of S met by the ray o + t d, tmin < t < tmax, other
 * than the slot skip (UINT32_MAX: none): returns t (INFINITY when none)
 * and its slot in *slot. */
double mx_ray_first_hit(const mx_surface_index *S, const double o[3], const double d[3],
                        double tmin, double tmax, uint32_t skip, uint32_t *slot);

#endif
