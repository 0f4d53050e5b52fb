/* Refining an octree that is already balanced, for re-meshing (Jaillet &
 * Lobos 2021, section 4.2):
 *
 * mx_refine_list            Algorithm 3: the listed leaves are split once
 *                           (a leaf listed twice is split once), and their
 *                           unbalanced neighbours through the edge infos and
 *                           the to_balance list
 * mx_retarget_leaves        the level every leaf asks for under the current
 *                           requests (boxes, levels, region surfaces)
 * mx_refine_leaves_to_target  Algorithm 1 from the existing leaves: level
 *                           by level, split the leaves asking for more,
 *                           drain to_balance before the next level, then
 *                           the closures (kernels/closures.h)
 *
 * The octree's octants stay where they are (indices do not move); new
 * octants are appended. */
#ifndef MX_REFINE_LIST_H
#define MX_REFINE_LIST_H

#include "kernels/refine.h"

void mx_retarget_leaves(mx_builder *B);
int mx_refine_leaves_to_target(mx_builder *B);
/* octs: octant indices (leaves; octants no longer leaves are skipped). */
int mx_refine_list(mx_builder *B, const uint32_t *octs, size_t n);

#endif
