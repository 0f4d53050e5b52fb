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

/* The pieces of the materials' inputs: each closed shell of each input file
 * is a piece, with its own index; a piece lies inside another (its parent,
 * the innermost containing it) or is a root. A point's piece is the
 * innermost containing it. The region (material index 1 ..) of a piece is
 * keyed by (depth, file): the first file at depth d gives region d + 1 (so
 * nested shells number their regions by depth, as the depth of one index
 * would), the other files at that depth get the next numbers after the
 * deepest. A piece is cleaved (an interface pass) when it is nested, or
 * shares triangles with another piece (touching inputs: two cubes glued on a
 * face); passes go by depth, then piece. */
typedef struct mx_interfaces_s {
  uint32_t npieces;
  int32_t *parent;         /* npieces: the parent piece, -1 for a root */
  uint16_t *depth;         /* npieces: 0 for a root */
  uint16_t *file;          /* npieces: the input file (the soup's shell id) */
  uint16_t *region;        /* npieces: region index, 1 .. nregions */
  uint32_t *pass;          /* npasses pieces to cleave, in order */
  uint32_t npasses;
  int nregions;
  mx_trisoup *soup;        /* npieces */
  mx_surface_index *index; /* npieces */
  /* npieces: the index of a touching piece's triangles shared with another
   * (its interface), NULL for the others (a nested piece's interface is
   * all of it) */
  mx_surface_index **iface;
  mx_trisoup *iface_soup;
} mx_interfaces;

/* The pieces of the triangles [0, nt) of src (soup shell ids: the files);
 * shared (NULL: none; one byte per triangle): 1 for the triangles two
 * files have in common. At most MX_MAX_PIECES pieces (MX_EINPUT, with a
 * message). MX_ENOMEM. */
enum { MX_MAX_PIECES = 1024 };
int mx_interfaces_build(mx_interfaces *I, const mx_trisoup *src, uint32_t nt,
                        const uint8_t *shared);
void mx_interfaces_free(mx_interfaces *I);
/* The innermost piece containing p, plus one; 0 outside every piece. */
int mx_interfaces_piece(const mx_interfaces *I, const double p[3]);
/* The piece (plus one) whose surface is nearest p: a point of the outer
 * boundary's own piece (the first at equal distances). */
int mx_interfaces_surface_piece(const mx_interfaces *I, const double p[3]);
/* The distance from p to the nearest piece's surface: within it, the
 * piece of a point is p's. */
double mx_interfaces_clearance(const mx_interfaces *I, const double p[3]);
/* 1 when piece q (a piece plus one, as above) lies in piece p's subtree. */
int mx_interfaces_within(const mx_interfaces *I, int q, uint32_t p);

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
