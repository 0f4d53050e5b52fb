/* An independent mesh checker: it looks only at a plain mesh (nodes, cells
 * in VTK order) and, optionally, at the input surface -- never at the
 * octree that produced the mesh.
 *
 * Definitions (the counters marked * are defects):
 *  invalid*            elements whose J_ENS (kernels/quality.h) is <= 0 or
 *                      not a number;
 *  jens_min/mean       over all elements (NAN without elements);
 *  faces are matched by their sorted node ids, triangles and quads apart:
 *  faces_interior      faces used by exactly two elements;
 *  faces_boundary      faces used by exactly one element;
 *  faces_overshared*   faces used by three or more elements (counted once);
 *  faces_misoriented*  interior faces whose two elements do not see them
 *                      with opposite cyclic orders (same orientation, or a
 *                      different cycle through the same nodes);
 *  quad_vs_triangles*  boundary quads a-b-c-d such that both triangles of one
 *                      diagonal (a-b-c + a-c-d, or a-b-d + b-c-d) are also
 *                      boundary faces;
 *  nonmanifold_edges   distinct edges used by 4, 6... boundary faces: two
 *                      parts of the domain touching along an edge (closed
 *                      and conforming, reported, not a defect);
 *  open_boundary_edges* distinct edges of boundary faces that are used an odd
 *                      number of times (the boundary is not closed there);
 *  hanging_nodes*      used nodes lying exactly (bit-equal coordinates) at
 *                      the midpoint 0.5*(a+b) of an edge of an element they
 *                      are not a vertex of, or at the midpoint of a diagonal
 *                      of a quad face they are not a vertex of (its centre
 *                      when the quad is a parallelogram); each node counted
 *                      once;
 *  unused_nodes*       nodes no element refers to;
 *  duplicate_nodes*    nodes whose coordinates equal those of another node
 *                      (k equal nodes count k - 1);
 *  volume              sum of the signed mx_element_volume;
 *  surface_volume      |enclosed volume| of the surface (divergence theorem,
 *                      signed tetrahedra from the centre of its bounding box,
 *                      which for a closed surface equals the sum from the
 *                      origin but loses less to cancellation), NAN without;
 *  volume_error        (volume - surface_volume) / surface_volume, or NAN;
 *  boundary_max_dist   the largest distance from a node of a boundary face
 *                      to the nearest surface triangle, over the diagonal of
 *                      the surface's bounding box; NAN without surface.
 *  defects = invalid + every counter marked *.
 * Sums are formed in fixed chunks, so every number is the same whatever the
 * thread count. */
#ifndef MX_CHECK_MESH_H
#define MX_CHECK_MESH_H

#include <stddef.h>

#include "io/read_mesh.h"
#include "soa/trisoup.h"

typedef struct {
  size_t nodes, elements, by_type[4]; /* by_type indexed MX_TET .. MX_HEX */
  size_t invalid;
  double jens_min, jens_mean;
  size_t faces_interior, faces_boundary, faces_overshared, faces_misoriented,
      quad_vs_triangles, open_boundary_edges, nonmanifold_edges, hanging_nodes,
      unused_nodes,
      duplicate_nodes;
  double volume;
  double surface_volume;
  double volume_error;
  double boundary_max_dist;
  size_t defects;
} mx_check_report;

/* Fills *r. Returns MX_OK, or MX_EINPUT (message printed) for a mesh that
 * cannot be checked at all: a type out of range, a node index >= nnodes, or
 * more than 2^32 - 2 nodes or 715 million cells; also when out of memory. */
int mx_check_mesh(const mx_mesh_data *m, const mx_trisoup *surface,
                  mx_check_report *r);

#endif
