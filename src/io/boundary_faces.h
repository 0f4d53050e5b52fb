/* mixoct: the boundary of a volume mesh, as the faces used by exactly one
 * element.
 *
 * Every face of every element (mx_cell_faces of soa/mesh.h) is filed
 * under its smallest node; each node's short list is sorted by the face's
 * sorted node tuple and runs of equal tuples give how many elements use the
 * face. A face used once is a boundary face: it is returned with the node
 * order of mx_cell_faces, so oriented outward of its element. Triangles and
 * quadrilaterals come in two lists, each ordered by element index and then
 * by local face index, so the result does not depend on the number of
 * threads. Work and memory are linear in the number of faces (about 4
 * bytes a face, 1 an element and 8 a node while it runs, and 4 per face
 * slot for the labels of mx_interface_faces_extract); every pass is
 * parallel.
 *
 * A triangle and a quadrilateral are never the same face, so a quadrilateral
 * facing two triangles (a non-conforming mesh) is a boundary face, and so
 * are the two triangles. A face used three times or more is not. */
#ifndef MX_BOUNDARY_FACES_H
#define MX_BOUNDARY_FACES_H

#include <stddef.h>
#include <stdint.h>

#include "soa/mesh.h"

typedef struct mx_boundary_faces {
  size_t ntri, nquad;
  uint32_t *tri;      /* 3 * ntri node indices, outward */
  uint32_t *quad;     /* 4 * nquad node indices, outward */
  uint64_t *tri_src;  /* per triangle: 8 * element + local face index */
  uint64_t *quad_src; /* per quadrilateral: the same */
  int32_t *tri_tag;   /* per triangle: its boundary tag (1..), or NULL */
  int32_t *quad_tag;  /* per quadrilateral: the same */
  /* mx_interface_faces_extract only: per face, the label of the element on
   * its other side (0: a boundary face, no other side) */
  int32_t *tri_pair, *quad_pair;
} mx_boundary_faces;

/* Fills *bf (zeroed first; free with mx_boundary_faces_free). The view must
 * be consistent (types in range, node indices below nnodes: see
 * mx_mesh_view_check); cells are limited to 2^32 / 6. Returns MX_OK, or
 * MX_ENOMEM when memory runs out, MX_EINPUT with a message when the mesh
 * is too large. */
int mx_boundary_faces_extract(const mx_mesh_view *m, mx_boundary_faces *bf);
/* The same among the faces whose nodes all have mask[node] != 0: the others
 * are taken as interior (the caller knows no boundary face has such a node:
 * the mesher's nodes far from the surface). Less work when the mask is
 * sparse. */
int mx_boundary_faces_extract_masked(const mx_mesh_view *m, const uint8_t *mask,
                                     mx_boundary_faces *bf);
/* The boundary faces and the interface faces of a mesh whose elements carry
 * labels (materials, issue 26; label per element): an interface face is a
 * face of two elements of different labels, listed once, oriented outward
 * of the element of the lower label (its source), with the other label in
 * tri_pair / quad_pair; boundary faces have pair 0. */
int mx_interface_faces_extract(const mx_mesh_view *m, const int32_t *label,
                               mx_boundary_faces *bf);
void mx_boundary_faces_free(mx_boundary_faces *bf);

/* The nodes the faces use, numbered in the mesh's order (the surface files
 * of the boundary list only those): used[0 .. nused) their mesh indices,
 * newid[mesh index] their number (UINT32_MAX: not on a face). */
typedef struct {
  size_t nused;
  uint32_t *used, *newid;
} mx_boundary_nodes;
int mx_boundary_nodes_number(const mx_boundary_faces *bf, size_t nnodes, mx_boundary_nodes *N);
void mx_boundary_nodes_free(mx_boundary_nodes *N);

/* flags[i] = 1 when node i lies on a boundary face, 0 otherwise (nnodes
 * values; the VTU point field "boundary"). MX_OK or MX_EINPUT as above. */
int mx_boundary_node_flags(const mx_mesh_view *m, int32_t *flags);

#endif
