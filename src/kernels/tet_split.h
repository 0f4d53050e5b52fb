/* The mixed mesh split into tetrahedra (issue 30, item 2: solvers that take
 * one cell type, dolfinx among them).
 *
 * Every quadrilateral face is cut by the diagonal through its node of the
 * smallest global index, the same from both sides, so the tetrahedra of two
 * neighbours meet on the same triangles (Dompierre, Labbe, Vallet &
 * Camarero 1999). Each element's boundary then is a fixed set of
 * triangles, and the element is cut into tetrahedra with exactly those
 * triangles on its boundary, trying in this order:
 *  - a hexahedron whose six diagonals join four alternate corners: the 5
 *    tetrahedra (four corners cut off, one in the middle);
 *  - the cone from one of its nodes (smallest global index first) over the
 *    boundary triangles that do not contain it, for a node whose
 *    quadrilateral faces are all cut through it: pyramid 2, prism 3,
 *    hexahedron 6 tetrahedra (the "pulling" triangulation; the node of the
 *    smallest index always qualifies, so a convex element never needs
 *    more);
 *  - the cone from a new node (a Steiner node) over all its boundary
 *    triangles: pyramid 6, prism 8, hexahedron 12; the node at the mean of
 *    the element's nodes, or when that does not do, at the point of the
 *    element's kernel farthest from the triangles' planes (a compass
 *    search; the kernel: the points that see every boundary triangle from
 *    inside).
 * The first candidate whose every tetrahedron is valid (J_ENS at least
 * MX_JENS_VALID, so a positive volume) is taken; an element with none (an
 * empty kernel: a thin prism whose two warped faces are cut along their
 * concave diagonals) makes the split fail (MX_EINVALID, the element named;
 * the mesher's repair rounds refine its leaf first,
 * mx_tet_split_flag_failures). A tetrahedron is kept.
 *
 * Per tetrahedron: its element's leaf, level and material; its own J_ENS.
 * Nodes: the mesh's, then the Steiner nodes in element order (lattice key
 * MX_NKEY_NONE). Counted per element, prefix sum, filled: parallel, O(n),
 * the same output for any thread count. */
#ifndef MX_TET_SPLIT_H
#define MX_TET_SPLIT_H

#include <stddef.h>
#include <stdint.h>

#include "soa/mesh.h"

typedef struct {
  size_t tets;         /* tetrahedra made */
  size_t steiner;      /* nodes added (elements coned to their mean) */
  size_t five;         /* hexahedra split into 5 */
  size_t by_type[4];   /* elements split, by type (tetrahedra: kept) */
  double seconds;
} mx_tet_split_stats;

/* T (zeroed first; free with mx_mesh_free) receives the tetrahedra of M
 * (left as it is). parent (may be NULL): *parent (mx_alloc) gets, per
 * tetrahedron, the index of its element in M. MX_OK, MX_ENOMEM,
 * MX_EINVALID (an element no candidate splits validly: message naming it),
 * MX_EINPUT (more than 2^32 nodes). */
int mx_mesh_split_tets(const mx_mesh *M, mx_mesh *T, uint32_t **parent,
                       mx_tet_split_stats *stats);

/* flag[c] set to 1 for each element of M that no candidate splits
 * validly (the others left as they are); returns their count. The repair
 * rounds refine their leaves (mesher/repair.c, with mx_params.tets). */
size_t mx_tet_split_flag_failures(const mx_mesh *M, uint8_t *flag);

#endif
