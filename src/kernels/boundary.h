/* The boundary stage (Lobos & Gonzalez 2015, Algorithm 1, lines 11-14).
 * Here: the inside/outside state of every node (mx_node_states),
 * "remove close to boundary" (mx_move_close_nodes; the elements it leaves
 * outside go with the surface patterns) and "shrink to boundary"
 * (mx_shrink_to_boundary). The surface
 * patterns and the staircase are in kernels/surface_patterns.h; the whole
 * stage in kernels/boundary_stage.h. */
#ifndef MX_BOUNDARY_H
#define MX_BOUNDARY_H

#include <stddef.h>
#include <stdint.h>

#include "geom/distance.h"
#include "soa/tree.h"
#include "soa/mesh.h"

/* A node's state: outside the domain (and, after the boundary stage, on
 * the surface), or inside; MX_NODE_ON is an inside node that
 * mx_node_states located and found on the surface or within
 * MX_NODE_ON_UNITS finest lattice spacings of it (flat parts of the input
 * in lattice planes; JSON boundary.on_surface). The nodes of leaves
 * meeting no triangle are inside without a query, so an inside node on
 * the surface may be MX_NODE_INSIDE (a triangle in the plane of a leaf's
 * face can fall in the rounding gap between the boxes): the boundary tags
 * do not rely on MX_NODE_ON (mesher/output.c). Inside is bit 0
 * (mx_node_inside): where inside matters (patterns, close nodes, the
 * splice's check of the shared nodes), MX_NODE_ON is inside. */
enum { MX_NODE_OUTSIDE = 0, MX_NODE_INSIDE = 1, MX_NODE_ON = 3 };
#define MX_NODE_ON_UNITS 1e-3
static inline int mx_node_inside(uint8_t s) { return s & 1; }

/* One state per node of the transition mesh M (built from `leaves`), shared
 * by every element using the node. Nodes of a leaf that meets no triangle of
 * the domain are inside without a query (the leaf's closed box lies inside
 * the domain); every other node is located once with the surface index of
 * the domain (angle-weighted pseudonormals, or the generalized winding number
 * for a surface that is not closed), the inside ones found on the surface
 * MX_NODE_ON. *queries receives the number of located nodes. */
int mx_node_states(const mx_tree *tr, const uint32_t *leaves,
                   const mx_mesh *M, const mx_surface_index *S,
                   uint8_t *states, size_t *queries);

/* Line 11 of Algorithm 1 (2015 paper), "remove close to boundary": every
 * inside node of a surface element (one with inside and outside nodes) whose
 * closest point on the surface lies within `ratio` (0.3 in the paper) of the
 * average length of its incident element edges moves onto that point and
 * becomes an outside node; all moves are decided on the positions before any
 * of them (states updated). The elements left with no inside node are
 * removed by the surface patterns (kernels/surface_patterns.h) in their
 * pass. With moved_flags NULL, J_ENS is
 * recomputed here; otherwise *moved_flags receives (mx_alloc) one byte per
 * node, 1 where it moved, and the caller recomputes. MX_ECANCELED leaves
 * some nodes moved (the caller drops the mesh, as for any failure). */
int mx_move_close_nodes(mx_mesh *M, uint8_t *states, const mx_surface_index *S,
                        double ratio, size_t *moved, uint8_t **moved_flags);

/* Line 13 of Algorithm 1, "shrink outside nodes": every outside node moves
 * to its closest point among the domain triangles met by the leaves whose
 * elements use it (ties: the lowest triangle id); then J_ENS is recomputed
 * for the elements that moved and those whose J_ENS is NaN (the surface
 * patterns' new and changed elements). Deterministic. *moved receives the number of
 * nodes moved. */
int mx_shrink_to_boundary(const mx_tree *tr, const uint32_t *leaves,
                          mx_mesh *M, const uint8_t *states, size_t *moved);

#endif
