/* The root grid every octant lives on: root cubes of one side from an
 * origin, and the finest lattice (2^MX_MAX_LEVEL cells per root side) the
 * Morton keys count on. Built by kernels/grid.c (the published rule). */
#ifndef MX_SOA_GRID_H
#define MX_SOA_GRID_H

#include <stdint.h>

#include "base/morton.h"

typedef struct {
  double origin[3]; /* lowest corner of the grid */
  double side;      /* side of a root cube */
  double unit;      /* side of a finest-lattice cell: side / 2^MX_MAX_LEVEL */
  int dims[3];      /* root cubes per axis */
} mx_grid;

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
