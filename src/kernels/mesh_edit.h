/* Edits of the mixed mesh shared by the boundary steps: keep a subset of the
 * elements, drop the nodes no element uses, refresh the summary. Every edit
 * keeps the order of what remains (count, prefix sum, fill), so the result
 * does not depend on the thread count. */
#ifndef MX_MESH_EDIT_H
#define MX_MESH_EDIT_H

#include <stdint.h>

#include "soa/mesh.h"

/* Keep the elements c with keep[c] != 0, in order. */
int mx_mesh_keep_cells(mx_mesh *M, const uint8_t *keep);

/* The per-element arrays (type, level, conn, leaf, jens) reallocated for n
 * elements (a big array grows by remapping, not copying); ncells is left
 * as it is. MX_ENOMEM (the arrays that grew stay M's). */
int mx_mesh_grow_cells(mx_mesh *M, size_t n);

/* Renumber the nodes: node v becomes newid[v] (UINT32_MAX: dropped; the
 * others take the ids 0 .. nu-1); coordinates, lattice keys and *states
 * (may be NULL) follow, connectivity is rewritten. */
int mx_mesh_apply_node_ids(mx_mesh *M, uint8_t **states, const uint32_t *newid,
                           size_t nu);

/* Drop the nodes no element uses, renumbering the others in order; *states
 * (one byte per node, may be NULL) follows. When newid is not NULL it
 * receives (mx_alloc) the new id of every old node, UINT32_MAX if dropped. */
int mx_mesh_drop_unused_nodes(mx_mesh *M, uint8_t **states, uint32_t **newid);
/* The same with the nodes in use given: used[v] != 0 for each node an
 * element uses (a pass that writes the elements marks them on the way). */
int mx_mesh_drop_nodes(mx_mesh *M, uint8_t **states, const uint8_t *used,
                       uint32_t **newid);

/* The elements of each marked node (mark[v] != 0) in increasing order:
 * those of v are inc[off[v] .. off[v + 1]) (off: nnodes + 1 entries; an
 * unmarked node has none). Both allocated here (mx_alloc). MX_ENOMEM. */
int mx_mesh_incidence(const mx_mesh *M, const uint8_t *mark, uint64_t **off, uint32_t **inc);
/* The same, with the band: the elements with a marked node, in increasing
 * order (*band, *nband; when band is not NULL), and each entry's place in
 * it (pos[e]: inc[e] = band[pos[e]]; when pos is not NULL), so that a
 * value per element of the band can be kept beside the lists. */
int mx_mesh_incidence_band(const mx_mesh *M, const uint8_t *mark, uint64_t **off,
                           uint32_t **inc, uint32_t **band, size_t *nband, uint32_t **pos);

/* Recount by_type, invalid (J_ENS < 1e-6) and jens_min from M->jens. */
void mx_mesh_summarize(mx_mesh *M);

/* Recompute J_ENS of the elements with a node flagged in `moved` (all
 * elements when moved is NULL). */
void mx_mesh_update_jens(mx_mesh *M, const uint8_t *moved);

/* Elements grouped by leaf, in leaf order, keeping the order inside each
 * leaf (a stable counting sort; nothing moves when already grouped). */
int mx_mesh_sort_by_leaf(mx_mesh *M, size_t nleaves);

#endif
