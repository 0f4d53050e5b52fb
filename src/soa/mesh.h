/* A mesh as plain arrays, the form every writer takes (a 2D mesh too: see
 * mx_mesh_view's dim). Cells are rows of 8
 * node indices (unused entries are ignored), with a type each. Node order
 * inside a cell follows VTK's convention for tetrahedra, pyramids and
 * hexahedra; for prisms it is Gmsh's (the triangle 0 1 2 turns, by the right
 * hand, towards the triangle 3 4 5), which VTK's wedge reverses (its 0 1 2
 * normal points away from 3 4 5): the VTK writers and reader go through
 * mx_vtk_order. */
#ifndef MX_MESH_H
#define MX_MESH_H

#include <stddef.h>
#include <stdint.h>

#include "mixoct.h" /* MX_TET, MX_PYRAMID, MX_PRISM, MX_HEX */
static const int mx_cell_nodes[4] = {4, 5, 6, 8};
/* The edges of each type (our node numbering), and their count. */
static const int8_t mx_cell_edge[4][12][2] = {
    {{0, 1}, {1, 2}, {2, 0}, {0, 3}, {1, 3}, {2, 3}},
    {{0, 1}, {1, 2}, {2, 3}, {3, 0}, {0, 4}, {1, 4}, {2, 4}, {3, 4}},
    {{0, 1}, {1, 2}, {2, 0}, {3, 4}, {4, 5}, {5, 3}, {0, 3}, {1, 4}, {2, 5}},
    {{0, 1}, {1, 2}, {2, 3}, {3, 0}, {4, 5}, {5, 6}, {6, 7}, {7, 4}, {0, 4},
     {1, 5}, {2, 6}, {3, 7}}};
static const int mx_cell_nedges[4] = {6, 8, 9, 12};
static const int mx_vtk_cell_type[4] = {10, 14, 13, 12};
/* Node j of a VTK cell is node mx_vtk_order[type][j] of ours (an
 * involution: the same table converts back). */
static const int8_t mx_vtk_order[4][8] = {{0, 1, 2, 3, 4, 5, 6, 7},
                                          {0, 1, 2, 3, 4, 5, 6, 7},
                                          {0, 2, 1, 3, 5, 4, 6, 7},
                                          {0, 1, 2, 3, 4, 5, 6, 7}};

/* Faces of each type in our node order, oriented outward (-1 ends a
 * triangle). The first face's right-hand normal points into the element. */
static const int mx_cell_nfaces[4] = {4, 5, 5, 6};
static const int8_t mx_cell_faces[4][6][4] = {
    {{0, 2, 1, -1}, {0, 1, 3, -1}, {1, 2, 3, -1}, {0, 3, 2, -1}},
    {{0, 3, 2, 1}, {0, 1, 4, -1}, {1, 2, 4, -1}, {2, 3, 4, -1}, {3, 0, 4, -1}},
    {{0, 2, 1, -1}, {3, 4, 5, -1}, {0, 1, 4, 3}, {1, 2, 5, 4}, {2, 0, 3, 5}},
    {{0, 3, 2, 1}, {4, 5, 6, 7}, {0, 1, 5, 4}, {1, 2, 6, 5}, {2, 3, 7, 6},
     {3, 0, 4, 7}}};

/* The mesh every stage from the transition to the writers edits (the
 * mixed mesh of the octree's leaves): structure of arrays, one row of 8
 * node indices per element. Read by the writers through mx_mesh_view
 * (below; src/mesher/output.c builds it). */
typedef struct {
  size_t nnodes, ncells;
  double *xyz;      /* 3 * nnodes */
  uint8_t *type;    /* ncells */
  uint32_t *conn;   /* 8 * ncells, VTK order */
  uint8_t *level;   /* level of the leaf each element comes from */
  uint32_t *leaf;   /* index (in the leaves list) of that leaf */
  float *jens;      /* J_ENS of each element (computed in double, kept in
                     * float: 4 bytes instead of 8 for every element) */
  uint16_t *material; /* per element: its material, for several materials
                       * (issue 26); NULL: one material. Always NULL today:
                       * the stages that edit elements (kernels/mesh_edit.h,
                       * surface patterns, staircase, splice) must carry it
                       * once something sets it. */
  uint64_t *nkey;   /* per node: its lattice key (mx_lattice_key), or
                     * MX_NKEY_NONE for a node off the lattice (an element
                     * centre of the surface patterns); kept by every edit */
  size_t closures;  /* face midpoints added by the closure */
  size_t centre_leaves; /* leaves whose pattern uses the body centre */
  size_t by_type[4];
  double jens_min;
  size_t invalid;   /* elements with J_ENS < 1e-6 */
} mx_mesh;
#define MX_NKEY_NONE UINT64_MAX
/* Frees every array and zeroes *m (src/soa/mesh.c). */
void mx_mesh_free(mx_mesh *m);

/* A cell or point field. is_double says how it is written: 0 as int32
 * (legacy VTK "int", VTU Int32 or UInt8 when every value fits, ...), 1 as
 * double. The values are read from one source array, which may be narrower
 * than the written type (the mesh's own 8-bit types and levels, its float
 * J_ENS): an int field has exactly one of ivalues / u8values, a double
 * field exactly one of dvalues / fvalues (the others NULL). Writers convert
 * value by value while formatting (mx_field_int, mx_field_double), so the
 * bytes of a file do not depend on the source kind. The narrow sources come
 * last: positional initialisers {name, is_double, ivalues, dvalues} leave
 * them NULL (-Wextra warns of the missing members there: designated
 * initialisers, {.name = ..., .u8values = ...}, do not). */
typedef struct {
  const char *name;
  int is_double;            /* 0: written as int32, 1: as double */
  const int32_t *ivalues;
  const double *dvalues;
  const uint8_t *u8values;  /* int field from 8-bit values */
  const float *fvalues;     /* double field from float values */
} mx_field;

/* Value i of an int field (is_double 0). */
static inline int32_t mx_field_int(const mx_field *f, size_t i) {
  return f->ivalues ? f->ivalues[i] : (int32_t)f->u8values[i];
}

/* Value i of a double field (is_double 1): a float source gives the double
 * of the float, exactly. */
static inline double mx_field_double(const mx_field *f, size_t i) {
  return f->dvalues ? f->dvalues[i] : (double)f->fvalues[i];
}

typedef struct {
  size_t nnodes;
  const double *xyz;      /* 3*nnodes, interleaved */
  size_t ncells;
  const uint8_t *type;    /* ncells, MX_TET .. MX_HEX */
  const uint32_t *conn;   /* 8*ncells */
  int ncell_fields;
  const mx_field *cell_fields;
  int npoint_fields;
  const mx_field *point_fields;
  /* Optional (all NULL / 0 in a plain view): the boundary faces of the mesh
   * with a tag each (see io/boundary_tags.h): boundary tag t (1..ntags) is
   * named tag_names[t - 1] (the input file it lies on); each cell's body
   * tag (1..nbodies) in cell_body, body b named body_names[b - 1]. */
  const uint32_t *order;  /* the cells in the order they are written (a
                           * permutation of 0..ncells-1), or NULL: in index
                           * order; see mx_view_cell */
  const struct mx_boundary_faces *bfaces;
  int ntags;
  const char *const *tag_names;
  const int32_t *cell_body;
  int nbodies;
  const char *const *body_names;
  const int32_t *body_physical; /* the number body b is written with
                                 * (body_physical[b - 1]: Gmsh physical
                                 * group, Medit reference); NULL: b */
  /* The dimension: 3 (or 0, as in a plain view) a volume mesh as above; 2
   * a planar mesh (mx_view_is_2d): xyz holds x y per node (written with
   * z = 0), type MX_CELL_TRI / MX_CELL_QUAD, conn 4 per cell (a triangle's
   * 4th entry unused), cells counter-clockwise and written in index order
   * (order, bfaces and tags unused). Bodies, when given (several
   * materials: cell_body, nbodies, body_names, body_physical), are the
   * .msh writer's surfaces and physical groups (with the edges between two
   * bodies as curves "interface A | B") and the .getfem writer's regions. */
  int dim;
} mx_mesh_view;

/* The cells of a 2D view (dim 2): counter-clockwise triangles and
 * quadrilaterals (the values of quad/quad.h's MX_QTRI and MX_QQUAD). */
enum { MX_CELL_TRI = 0, MX_CELL_QUAD = 1 };

/* Whether the view is of a 2D mesh. */
static inline int mx_view_is_2d(const mx_mesh_view *m) { return m->dim == 2; }

/* The node count of cell c of a 2D view. */
static inline int mx_view_nv2(const mx_mesh_view *m, size_t c) {
  return m->type[c] == MX_CELL_QUAD ? 4 : 3;
}

/* The index of the k-th cell written. */
static inline size_t mx_view_cell(const mx_mesh_view *m, size_t k) {
  return m->order ? m->order[k] : k;
}

#endif
