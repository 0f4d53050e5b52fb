/* Edge infos where and when they are needed (re-meshing: Jaillet & Lobos
 * 2021, section 4.2):
 *
 * mx_raise_edge_levels      edge infos for every octant of levels that were
 *                           not kept (the finest level of a run keeps none)
 * mx_edges_ensure           edge infos at such levels only around the
 *                           octants a refinement splits
 * mx_edges_release/restore  freed between two meshings, registered again
 *                           by the next step that splits or looks edges up
 *
 * The octree's octants stay where they are (indices do not move); new
 * octants are appended. */
#ifndef MX_EDGES_LAZY_H
#define MX_EDGES_LAZY_H

#include "kernels/builder.h"

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
/* B->tree.root_of: the root octant of each root cube, built once. MX_OK or
 * MX_EINPUT (memory). */
int mx_build_root_map(mx_builder *B);

/* The deepest octant holding the level-`level` cell of key k, no deeper
 * than that level (MX_NONE outside the octree; needs B->tree.root_of). */
uint32_t mx_covering_octant(const mx_builder *B, uint64_t key, int level);

#endif
