/* Box refinement regions (.reg files): "n_regions N", then per region the
 * min corner x y z, the max corner x y z, and the refinement level. */
#ifndef MX_REGIONS_H
#define MX_REGIONS_H

#include <stddef.h>

typedef struct {
  double lo[3], hi[3];
  int level;
} mx_box_region;

/* Reads a .reg file. On success *boxes is allocated with mx_alloc (free with
 * mx_free) and *n set. Errors (missing file, bad count, truncated, NaN,
 * lo > hi, negative level) print FILE:LINE and return MX_EINPUT. */
int mx_read_reg(const char *path, mx_box_region **boxes, size_t *n);

#endif
