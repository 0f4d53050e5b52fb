/* The root grid (the published mesher's rule, REFERENCE.md): cubes of side
 * 1.01 x the shortest side of the input's bounding box, laid out
 * symmetrically about the box centre on each axis. */
#ifndef MX_GRID_H
#define MX_GRID_H

#include <stdint.h>

#include "soa/grid.h"


/* MX_OK, or MX_EINPUT (with a message naming `name`, the input, may be
 * NULL) for an empty or flat box, coordinates out of range, or an input
 * thinner than the finest octant. An input too elongated for the published
 * rule (more than MX_MAX_ROOTS_PER_AXIS cubes of its shortest extent on an
 * axis) gets larger root cubes. */
int mx_grid_build(const double lo[3], const double hi[3], const char *name, mx_grid *g);

#endif
