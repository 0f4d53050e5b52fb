/* Local re-meshing (the 2021 paper, section 4.2: "only what changed is
 * re-meshed"): the pieces that let a refined octree be meshed again on a
 * patch of leaves around what was split, and the patch's elements spliced
 * into the previous mesh in place of the old ones.
 *
 * 1. mx_leaves_touching: the leaves touching a set of octants (a range
 *    query down the octree), from which the rings around what changed.
 * 2. mx_mesh_renumber_first_use: the canonical node numbering every mixed
 *    mesh of the full stage gets, from scratch or spliced: nodes numbered in
 *    the order of their first use in the element list (elements grouped by
 *    leaf in Morton order, nodes in each element's order). Two meshes with
 *    the same element list then have the same node numbers.
 * 3. mx_mesh_splice: the new mesh, leaf by leaf, from the old mesh (leaves
 *    not re-meshed) and the patch mesh (the core leaves); nodes shared with
 *    the old mesh are matched by lattice key and keep their old position. */
#ifndef MX_SPLICE_H
#define MX_SPLICE_H

#include <stddef.h>
#include <stdint.h>

#include "soa/tree.h"
#include "soa/mesh.h"

/* mark[i] = value, where it is 0, for every leaf meeting (touching or
 * inside) the closed box of one of the octants octs[0..n): i = pos[o] for
 * the leaf octant o (pos: the position of each octant in the leaf list,
 * MX_NONE if not in it). Each query starts from the smallest ancestor
 * holding the octant's neighbourhood. */
int mx_leaves_touching(const mx_tree *tr, const uint32_t *pos, const uint32_t *octs, size_t n,
                       uint8_t *mark, uint8_t value);

/* Renumber the nodes of M by first use (see above); *states (may be NULL)
 * and M->nkey follow; nodes no element uses are dropped. */
int mx_mesh_renumber_first_use(mx_mesh *M, uint8_t **states);

typedef struct {
  size_t kept_cells, patch_cells;  /* elements taken from each mesh */
  size_t shared_nodes;             /* patch nodes matched to old nodes */
  size_t shared_moved;             /* of which at a different position or state */
} mx_splice_stats;

/* The spliced mesh of nleaves leaves: leaf i's elements are those of patch
 * leaf from_patch[i] in P (sorted by leaf) when it is not MX_NONE, else
 * those of old leaf from_old[i] in O (sorted by leaf; MX_NONE: no element).
 * States of both meshes given per node; out and *states_out are allocated.
 * The J_ENS of patch elements using a shared node that moved is recomputed.
 * Nodes are numbered by first use. */
int mx_mesh_splice(const mx_mesh *O, const uint8_t *ostates, size_t nold_leaves,
                   const mx_mesh *P, const uint8_t *pstates, size_t npatch_leaves,
                   const uint32_t *from_old, const uint32_t *from_patch, size_t nleaves,
                   mx_mesh *out, uint8_t **states_out, mx_splice_stats *stats);

#endif
