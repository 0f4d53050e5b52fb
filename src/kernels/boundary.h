/* The boundary stage (Lobos & Gonzalez 2015, Algorithm 1, lines 11-14).
 * This file holds its first step so far: the inside/outside state of every
 * node. Still to come (issue 4): projection of inside nodes close to the
 * surface and removal of the elements left without an inside node, surface
 * patterns, shrinking outside nodes onto the surface, staircase reduction,
 * repair of invalid elements. */
#ifndef MX_BOUNDARY_H
#define MX_BOUNDARY_H

#include <stddef.h>
#include <stdint.h>

#include "kernels/distance.h"
#include "kernels/refine.h"
#include "kernels/transition.h"

enum { MX_NODE_OUTSIDE = 0, MX_NODE_INSIDE = 1 };

/* One state per node of the transition mesh M (built from `leaves`), shared
 * by every element using the node. Nodes of a leaf that meets no triangle of
 * the domain are inside without a query (the leaf's closed box lies inside
 * the domain); every other node is located once with the surface index of
 * the domain (angle-weighted pseudonormals, or the generalized winding number
 * for a surface that is not closed). *queries receives the number of
 * located nodes. */
int mx_node_states(const mx_builder *B, const uint32_t *leaves,
                   const mx_mesh_out *M, const mx_surface_index *S,
                   uint8_t *states, size_t *queries);

#endif
