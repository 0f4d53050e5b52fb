/* The root grid (the published mesher's rule, REFERENCE.md): cubes of side
 * 1.01 x the shortest side of the input's bounding box, laid out
 * symmetrically about the box centre on each axis. */
#ifndef MX_GRID_H
#define MX_GRID_H

#include <stdint.h>

#include "base/morton.h"

typedef struct {
  double origin[3]; /* lowest corner of the grid */
  double side;      /* side of a root cube */
  double unit;      /* side of a finest-lattice cell: side / 2^MX_MAX_LEVEL */
  int dims[3];      /* root cubes per axis */
} mx_grid;

/* MX_OK, or MX_EINPUT (with a message naming `name`, the input, may be
 * NULL) for an empty or flat box, coordinates out of range, or an input
 * thinner than the finest octant. An input too elongated for the published
 * rule (more than MX_MAX_ROOTS_PER_AXIS cubes of its shortest extent on an
 * axis) gets larger root cubes. */
int mx_grid_build(const double lo[3], const double hi[3], const char *name, mx_grid *g);

/* World box of the octant (key, level). Computed the same way everywhere so
 * neighbouring octants share bit-identical faces. */
static inline void mx_octant_box(const mx_grid *g, uint64_t key, int level,
                                 double lo[3], double hi[3]) {
  uint32_t c[3];
  mx_morton_decode(key, c);
  const uint32_t s = mx_octant_size(level);
  for (int a = 0; a < 3; a++) {
    lo[a] = g->origin[a] + (double)c[a] * g->unit;
    hi[a] = g->origin[a] + (double)(c[a] + s) * g->unit;
  }
}

#endif
