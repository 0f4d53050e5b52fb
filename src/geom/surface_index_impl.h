/* Internal to the surface index (geom/distance.h), shared by the files
 * that build and query it: constants, small vector helpers, and the build
 * steps each file contributes (bvh.c the binary tree, closest_tree.c the
 * 4-wide tree and the hint grid, closest.c the queries and pseudonormals,
 * winding.c the winding number and its caps, distance.c the build). */
#ifndef MX_SURFACE_INDEX_IMPL_H
#define MX_SURFACE_INDEX_IMPL_H

#include <math.h>
#include <stdint.h>

#include "geom/bvh.h"
#include "geom/distance.h"
#include "geom/surface_topology.h"

#define LEAF_MAX MX_BVH_LEAF_MAX
#define STACK_MAX 64          /* > depth of a BVH of 2^30 triangles + 1 */
#define NO_CAP UINT32_MAX     /* cap_cnt of a node without a usable cap */
#define FOUR_PI 12.566370614359172953850573533118

/* ------------------------------------------------------------------------ */
/* Small vector helpers. */

static inline double dot3(const double a[3], const double b[3]) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}
static inline void sub3(const double a[3], const double b[3], double r[3]) {
  r[0] = a[0] - b[0];
  r[1] = a[1] - b[1];
  r[2] = a[2] - b[2];
}
static inline void cross3(const double a[3], const double b[3], double r[3]) {
  r[0] = a[1] * b[2] - a[2] * b[1];
  r[1] = a[2] * b[0] - a[0] * b[2];
  r[2] = a[0] * b[1] - a[1] * b[0];
}

static inline int box_outside(const mx_bvh_node *N, const double p[3]) {
  return p[0] < N->lo[0] || p[0] > N->hi[0] || p[1] < N->lo[1] ||
         p[1] > N->hi[1] || p[2] < N->lo[2] || p[2] > N->hi[2];
}

/* Single precision, rounded up (half extents of the float boxes). */
static inline float fmax_f(float a, float b) { return a > b ? a : b; }
static inline float round_up(double x) {
  float f = (float)x;
  if ((double)f < x) f = nextafterf(f, INFINITY);
  return f;
}

/* closest.c: closest point over all triangles (squared distance, slot and
 * feature; see there), and the face, edge and vertex pseudonormals. */
double mx_index_closest_slot(const mx_surface_index *S, const double p[3],
                             double q[3], uint32_t *slot, int *feat, double rmax);
int mx_index_pseudonormals(mx_surface_index *S, const mx_edge_table *E);

/* closest_tree.c: the 4-wide tree with its boxes and leaf packs (S->wide,
 * S->packs, S->leaf_first allocated by the caller), and the hint grid. */
int mx_index_wide_tree(mx_surface_index *S);
int mx_index_hints(mx_surface_index *S);

/* winding.c: the winding number with per-slot signs ssign and cap weights
 * capw, slot skip left out (UINT32_MAX: none); the caps, cap_shell
 * receiving the shell of each entry. */
double mx_index_winding(const mx_surface_index *S, const double p[3],
                        const int8_t *ssign, const int32_t *capw, uint32_t skip);
int mx_index_build_caps(mx_surface_index *S, const uint8_t *fix, uint32_t **cap_shell);

#endif
