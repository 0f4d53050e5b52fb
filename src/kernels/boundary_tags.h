/* Tags for the boundary faces and the bodies of a mesh (issue 11), so a
 * solver can put a boundary condition on each input surface:
 *  - each boundary face (a face used by one element, io/boundary_faces.h)
 *    gets the tag s + 1 of the input file (shell s of the soup) it lies
 *    on: the shell of the domain triangles its element's leaf meets when
 *    they all come from one file, else the shell of the triangle closest
 *    to the face's centroid; with check_off set (a domain defined by the
 *    winding number, --repair-input), a face with a node farther than
 *    1e-6 of the input's diagonal from every triangle lies on no input and
 *    gets the tag nshells + 1;
 *  - each element gets the body tag of its connected component (elements
 *    sharing a node): bodies are numbered 1, 2, ... in the order of the
 *    smallest boundary tag on each (the first input file it touches), ties
 *    by the smallest node id.
 * Deterministic and parallel: O(faces + elements). */
#ifndef MX_BOUNDARY_TAGS_H
#define MX_BOUNDARY_TAGS_H

#include <stddef.h>
#include <stdint.h>

#include "io/boundary_faces.h"
#include "geom/distance.h"
#include "soa/tree.h"
#include "soa/mesh.h"

typedef struct {
  const mx_tree *tree;       /* the octree: each leaf's triangles */
  const uint32_t *leaves;    /* leaf index -> octant */
  const uint32_t *cell_leaf; /* per cell: its leaf index */
  const mx_trisoup *soup;    /* shell of each triangle */
  uint32_t nt_domain;        /* domain triangles: [0, nt_domain) */
  int nshells;               /* input files of the domain */
  const mx_surface_index *SI;/* the domain's triangles */
  int check_off;             /* faces may lie on no input (see above) */
  /* a mesh of tetrahedra cut from a mixed mesh (--tets, kernels/tet_split.h),
   * else NULL: per cell, its element in parent. A boundary triangle takes
   * the tag of the face of that element it lies in (a quadrilateral's two
   * triangles the quadrilateral's tag, found as above) */
  const uint32_t *cell_parent;
  const mx_mesh *parent;
} mx_tag_inputs;

/* bf: the boundary faces of v (mx_boundary_faces_extract); their tri_tag
 * and quad_tag are allocated and filled, and each list is reordered by tag
 * (stably: a tag's faces keep their order). cell_body: v->ncells values.
 * *nbodies: the number of bodies; *body_tag (allocated, mx_free): the
 * smallest boundary tag of each body (body b at [b - 1]); *off_input:
 * faces on no input. */
int mx_boundary_tags(const mx_mesh_view *v, const mx_tag_inputs *in, mx_boundary_faces *bf,
                     int32_t *cell_body, int *nbodies, int32_t **body_tag, size_t *off_input);

/* Per node: the smallest tag of the boundary faces using it, 0 for nodes on
 * none (the VTK/VTU point field "surface_tag"). */
void mx_boundary_node_tags(const mx_boundary_faces *bf, size_t nnodes, int32_t *tag);

#endif
