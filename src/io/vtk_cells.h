/* The cells of a VTK file (legacy or XML) as its reader found them, and the
 * one assembly step both VTK readers end with (src/io/vtk_cells.c). */
#ifndef MX_VTK_CELLS_H
#define MX_VTK_CELLS_H

#include "io/mesh_reader.h"

typedef struct {
  size_t nnodes, ncells;
  rawarr pts; /* 3*nnodes floats */
  int list_form;
  uint8_t *nn;      /* list form: node count per cell (out->conn filled) */
  rawarr off, cn;   /* offsets form */
  int vtu_offsets;  /* 1: ncells end offsets; 0: ncells + 1 offsets from 0 */
  rawarr types;
} parts;

/* Converts and validates the parts into out, in parallel, and re-runs the
 * first failing item serially for its message; in a planar read, 2D cells
 * become faces (read_mesh.h). */
int mx_rd_assemble(rd *r, parts *P, mx_mesh_data *out);
/* The point field surface_tag from its raw values (one per node). */
int mx_rd_node_tags(rd *r, const rawarr *a, mx_mesh_data *out);
/* The point field boundary from its raw values (one per node) into
 * out->node_bnd when every value is 0 or 1 (another field of that name is
 * not mixoct's: left out). */
int mx_rd_node_flags(const rawarr *a, mx_mesh_data *out);
/* The cell field material from its raw values (one per cell; integers, or
 * floats that are whole numbers, in the range of an int32) into cell_tag;
 * nothing when there is no cell (a planar read that made the cells faces,
 * a 2D mesh, has none left). */
int mx_rd_cell_tags(rd *r, const rawarr *a, mx_mesh_data *out);

#endif
