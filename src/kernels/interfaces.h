/* The interfaces between materials in the boundary stage (issue 26, item
 * 2). With --materials the regions are those of the inputs' pieces
 * (kernels/pieces.h): nested shells, and inputs touching on common faces.
 * The outer boundary goes through the 2015 paper's boundary stage as always
 * (kernels/boundary_stage.h): its surface patterns drop what lies outside,
 * and the shrink moves the outside nodes of what stays onto the surface. An
 * interface has two sides to keep, and a node moved across the elements of
 * one side turns them over, so each interface is cleaved instead
 * (kernels/cleave.h), one pass per piece, parents first: nodes close to it
 * onto it, the other elements it crosses split and cut along it.
 * Afterwards each element's nodes not on a shell lie in one region, and
 * the faces between two materials have all their nodes on the shell
 * between them. The untangling that follows (kernels/untangle.h) holds the
 * nodes on an interface there and the free ones in their piece. */
#ifndef MX_INTERFACES_H
#define MX_INTERFACES_H

#include <stddef.h>
#include <stdint.h>

#include "geom/distance.h"
#include "kernels/cleave.h"
#include "kernels/pieces.h"
#include "soa/mesh.h"
#include "soa/trisoup.h"
#include "soa/tree.h"

typedef struct {
  size_t located;         /* nodes whose region was queried */
  size_t nodes_before;    /* the mesh's nodes before (the new ones follow) */
  mx_cleave_stats cleave; /* summed over the interfaces */
} mx_interface_stats;

/* Every pass of I cleaved, on M after the outer boundary's shrink (tr,
 * leaves: the octree M was built from; S: the domain's surface). *states
 * (one per node, grown with the new nodes): on entry MX_NODE_OUTSIDE for
 * the nodes on the outer boundary, on return also for those on an
 * interface. piece_out (may be NULL) receives (mx_alloc) each node's piece
 * plus one (0 outside every piece, MX_REGION_ON on a shell), fixed_out (may
 * be NULL) 1 for the nodes on an interface (to stay there). M->jens is kept
 * up to date. MX_ENOMEM. */
int mx_interface_stage(const mx_tree *tr, const uint32_t *leaves, const mx_surface_index *S,
                       const mx_interfaces *I, mx_mesh *M, uint8_t **states, double alpha,
                       uint16_t **piece_out, uint8_t **fixed_out, mx_interface_stats *stats);

#endif
