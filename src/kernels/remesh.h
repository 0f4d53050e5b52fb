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
 *                           drain to_balance before the next level
 * mx_raise_edge_levels      edge infos for every octant of levels that were
 *                           not kept (the finest level of a run keeps none)
 * mx_edges_ensure           edge infos at such levels only around the
 *                           octants a refinement splits
 *
 * The octree's octants stay where they are (indices do not move); new
 * octants are appended. */
#ifndef MX_REMESH_H
#define MX_REMESH_H

#include "kernels/refine.h"

int mx_raise_edge_levels(mx_builder *B, int levels);
/* Memory between meshings: once the transition masks are known, nothing
 * reads the edge infos until the octree is split again, so
 * mx_edges_release frees them (and the split scratch), and
 * mx_edges_restore, called by every step that splits or looks edges up,
 * registers again the same octants (every octant of levels <= edge_levels,
 * and those flagged MX_OCT_EDGES deeper). MX_OK or MX_EINPUT (memory). */
void mx_edges_release(mx_builder *B);
int mx_edges_restore(mx_builder *B);
/* Edge infos, at levels deeper than edge_levels, for the octants list[0..n)
 * (one level; about to be split) and their face and edge neighbours of the
 * same level, and with_parents, for their parents and the parents'
 * neighbours: what the transition masks and the balance look up there.
 * Octants already registered are skipped (flag MX_OCT_EDGES). */
int mx_edges_ensure(mx_builder *B, const uint32_t *list, size_t n, int with_parents);
/* Splits (with balance) the leaves coarser than a face closure of the
 * transition next to them (a face centre whose neighbour's children were
 * dropped outside the domain adds edge midpoints that a coarser leaf along
 * the edge cannot take): called after every refinement of the octree. */
int mx_resolve_closures(mx_builder *B);
void mx_retarget_leaves(mx_builder *B);
int mx_refine_leaves_to_target(mx_builder *B);
/* octs: octant indices (leaves; octants no longer leaves are skipped). */
int mx_refine_list(mx_builder *B, const uint32_t *octs, size_t n);

#endif
