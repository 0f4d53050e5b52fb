/* Cleaving the mesh along one interface between two materials (issue 26,
 * item 2; the "warp then cut" of lattice cleaving, Bronson, Levine and
 * Whitaker 2014, on the mixed elements of the octree). The nodes on one
 * side of interface k are those of region k or deeper (side A), the others
 * not on a shell are side B, and the nodes on a shell have no side.
 *
 * 1. Warp: where the interface crosses an edge of an element (A at one
 *    end, B at the other) closer than alpha of its length to one end, that
 *    end moves onto the crossing (the nearest such crossing of the node).
 * 2. Split: every element still holding A and B nodes (a cut element) is
 *    split into tetrahedra about its centre (a pyramid about its apex),
 *    each quad face along the diagonal from its least node (by what the
 *    node is, mx_node_identity: not by its number); an element
 *    that shares a quad face with a cut element but is not cut itself is
 *    split about its centre too, into pyramids on its other quad faces and
 *    tetrahedra on the shared ones, so that both sides of every face agree.
 * 3. Cut: each tetrahedron with A and B nodes is cut along the interface:
 *    a node on every A-B edge where the interface crosses it (found on the
 *    edge, so the pieces are convex), shared by every element around the
 *    edge; the A part and the B part become a tetrahedron, a pyramid or a
 *    prism each (the cases: one node alone on its side, 2 + 2, and those
 *    with nodes on the shell).
 *
 * No element then holds A and B nodes, every face between an A element and
 * a B element has all its nodes on the interface, and the mesh stays
 * conforming. */
#ifndef MX_CLEAVE_H
#define MX_CLEAVE_H

#include <stddef.h>
#include <stdint.h>

#include "geom/distance.h"
#include "soa/mesh.h"

/* The warp's threshold: a crossing nearer an end than this fraction of the
 * edge moves the end onto it (lattice cleaving's alpha). */
#define MX_CLEAVE_ALPHA 0.2
/* A warp is kept when no element around the node drops below this J_ENS
 * (or below its own J_ENS before, when lower). */
#define MX_CLEAVE_FLOOR 0.2
/* The region of a node on a shell (it has none). */
#define MX_REGION_ON UINT16_MAX

typedef struct {
  size_t warped;     /* nodes moved onto the interface (step 1) */
  size_t cut;        /* elements split and cut (steps 2 and 3) */
  size_t neighbours; /* elements split about their centre for a shared face */
  size_t centres;    /* centres added */
  size_t cut_nodes;  /* nodes added on the interface (step 3) */
  size_t smoothed;   /* node moves of the smoothing after the cut */
  double t_warp, t_cut, t_smooth; /* seconds: step 1; steps 2 and 3 (the
                                   * cut nodes placed, J_ENS); the band's
                                   * smoothing after the cut */
} mx_cleave_stats;

/* Steps 1 to 3 for the pass of piece p of I (kernels/interfaces.h): side A
 * inside p, the interface p's surface. *piece: the piece value of every
 * node (MX_REGION_ON on a shell), grown with the new nodes; *outer: 1 for
 * the nodes on the outer boundary (Sd, the domain's surface) and on no
 * interface, grown with the new nodes (0) and cleared for those moved onto
 * the interface: such a node has the side it lies on, and a node the cut
 * puts between two of them, or one moved, goes where the interface meets
 * the boundary. M keeps its elements in their order, each replaced by its
 * pieces in place, with J_ENS. alpha in (0, 0.5). MX_ENOMEM. */
struct mx_interfaces_s;
int mx_cleave_interface(mx_mesh *M, uint16_t **piece, uint8_t **outer,
                        const struct mx_interfaces_s *I, uint32_t p, const mx_surface_index *Sd,
                        double alpha, mx_cleave_stats *stats);

#endif
