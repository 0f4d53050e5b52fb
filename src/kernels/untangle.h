/* Untangling and local smoothing after the shrink: the nodes of the
 * elements whose J_ENS is below a target move, one at a time, to the best of
 * a few points between their position and the centroid of their neighbours,
 * when that raises the worst J_ENS of the elements around them. A boundary
 * node (outside: on the surface) moves to the closest surface point of each
 * such point, so the boundary stays on the surface. This is what makes elements inverted by the shrink valid again
 * (the repair by refinement of the 2021 paper remains the fallback). */
#ifndef MX_UNTANGLE_H
#define MX_UNTANGLE_H

#include <stddef.h>
#include <stdint.h>

#include "geom/distance.h"
#include "soa/mesh.h"

/* q_target: elements below it are worked on; sweeps: passes over the work
 * set. The work nodes are coloured so that no two nodes of one element
 * share a colour (priorities hashed from the nodes' lattice keys); a sweep takes the
 * colours in turn and the nodes of one colour in parallel (their moves touch
 * disjoint elements): deterministic, whatever the threads. *moved: node
 * moves accepted. */
int mx_untangle(mx_mesh *M, const uint8_t *states, const mx_surface_index *S,
                    double q_target, int sweeps, size_t *moved);

/* The same with options: axis_moves (0 to 3) adds trial points along the
 * axes, both ways, at that many of the lengths a quarter, a tenth and a
 * twenty-fifth of the mean distance to the node's neighbours, to those
 * towards the centroid; movable (NULL: all)
 * limits the work set; region_of (NULL: none) keeps an inside node v where
 * region_of(region_ctx, x) is region[v] (several materials), asked only
 * beyond clearance_of(region_ctx, x) (NULL: always) of where the node was:
 * the distance from x within which region_of cannot change; a boundary
 * node too, unless its region is MX_REGION_NONE, by surface_region_of. */
#define MX_REGION_NONE UINT16_MAX
typedef struct {
  double q_target;
  int sweeps;
  int axis_moves;
  const uint8_t *movable;
  int (*region_of)(const void *ctx, const double x[3]);
  const void *region_ctx;
  const uint16_t *region;
  double (*clearance_of)(const void *ctx, const double x[3]);
  int (*surface_region_of)(const void *ctx, const double x[3]);
} mx_untangle_opts;
int mx_untangle_with(mx_mesh *M, const uint8_t *states, const mx_surface_index *S,
                     const mx_untangle_opts *o, size_t *moved);

#endif
