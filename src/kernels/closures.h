/* Closures next to coarser leaves (the transition's face closure, see
 * kernels/transition.h). */
#ifndef MX_CLOSURES_H
#define MX_CLOSURES_H

#include "kernels/refine.h"

/* Splits (with balance) the leaves coarser than a face closure of the
 * transition next to them (a face centre whose neighbour's children were
 * dropped outside the domain adds edge midpoints that a coarser leaf along
 * the edge cannot take): called after every refinement of the octree. */
int mx_resolve_closures(mx_builder *B);

#endif
