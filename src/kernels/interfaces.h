/* The interfaces between nested materials in the boundary stage (issue 26,
 * item 2). With --materials the domain is the outermost shells' inside and
 * the shells nested in it bound regions: region k (nesting depth k) lies
 * inside k shells. The outer boundary goes through the 2015 paper's
 * boundary stage as always (kernels/boundary_stage.h): its surface patterns
 * drop what lies outside, and the shrink moves the outside nodes of what
 * stays onto the surface. An interface has two sides to keep, and a node
 * moved across the elements of one side turns them over, so the interfaces
 * are cleaved instead (kernels/cleave.h), from the outermost in (k = 2 ..
 * deepest): nodes close to the interface onto it, the other elements it
 * crosses split and cut along it. Afterwards each element's nodes not on a
 * shell lie in one region, and the faces between two materials have all
 * their nodes on the shell between them. The untangling that follows
 * (kernels/untangle.h) holds the nodes on a shell onto the shells. */
#ifndef MX_INTERFACES_H
#define MX_INTERFACES_H

#include <stddef.h>
#include <stdint.h>

#include "geom/distance.h"
#include "kernels/cleave.h"
#include "soa/mesh.h"
#include "soa/trisoup.h"
#include "soa/tree.h"

typedef struct {
  int deepest;             /* the deepest region; interfaces 2 .. deepest */
  mx_trisoup *soup;        /* deepest + 1 entries, [k] for k >= 2 */
  mx_surface_index *level; /* [k]: the shells around region k (depth k - 1) */
} mx_interfaces;

/* The interfaces of S, an index built outward (mx_surface_index_build_outward)
 * whose shells nest: one index per depth over the shells there. With no
 * shell nested, deepest = 1 and nothing is allocated. MX_ENOMEM. */
int mx_interfaces_build(mx_interfaces *I, const mx_surface_index *S);
void mx_interfaces_free(mx_interfaces *I);

typedef struct {
  size_t located;         /* nodes whose region was queried */
  mx_cleave_stats cleave; /* summed over the interfaces */
} mx_interface_stats;

/* Every interface of I cleaved, on M after the outer boundary's shrink (tr, leaves: the octree M was built from; S: the index
 * of every shell). *states (one per node, grown with the new centres): on
 * entry MX_NODE_OUTSIDE for the nodes on the outer boundary, on return
 * also for those on an interface; M->jens is kept up to date. MX_ENOMEM. */
int mx_interface_stage(const mx_tree *tr, const uint32_t *leaves, const mx_surface_index *S,
                       const mx_interfaces *I, mx_mesh *M, uint8_t **states,
                       double alpha, mx_interface_stats *stats);

#endif
