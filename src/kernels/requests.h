/* Refinement requests and the level each octant asks for.
 *   -s RL  octants meeting the input surface
 *   -a RL  every octant of the domain
 *   -b reg boxes with levels (an octant overlapping a box's interior)
 *   -r S RL octants meeting region surface S or inside it
 *   --size  a size field (issue 27, src/sizing/): an octant is split while
 *          its side exceeds the field's least size over its box (the
 *          control space's box query: no small size slips between samples)
 * An octant asked by several requests takes the largest level. */
#ifndef MX_REQUESTS_H
#define MX_REQUESTS_H

#include <stddef.h>
#include <stdint.h>

#include "sizing/sources.h"
#include "soa/regions.h"

#include "mixoct.h" /* MX_MAX_REGIONS */

typedef struct {
  int s_level; /* -1 when absent */
  int a_level; /* -1 when absent */
  const mx_box_region *boxes;
  size_t nboxes;
  int nregions;
  int rlevel[MX_MAX_REGIONS];
  /* bit r: region r is refined where its triangles meet an octant only,
   * never inside (an interface between two materials: not closed) */
  unsigned meet_only;
  /* the size field (NULL: none: its control space, discrete sources and
   * clamps, sizing/sources.h) and the side of a root cube (set with the
   * grid: mx_builder_init; 0 before, when the field asks nothing) */
  const mx_size_field *size_field;
  double root_side;
} mx_requests;

/* Target level of the octant with world box [lo, hi]; surf: it meets the
 * domain surface; rmask: bit r set when it meets or is inside region r. */
int mx_target_level(const mx_requests *R, const double lo[3],
                    const double hi[3], int surf, unsigned rmask);
/* The largest level any request can ask for. */
int mx_max_requested_level(const mx_requests *R);

#endif
