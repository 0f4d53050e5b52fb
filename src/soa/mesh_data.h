/* A volume mesh as read from a file (src/io/read_*.c): the type the
 * readers fill and `mixoct check` (src/verify/) takes, apart from the
 * mesher's own mesh (soa/mesh.h has the view the writers read). */
#ifndef MX_MESH_DATA_H
#define MX_MESH_DATA_H

#include <stddef.h>
#include <stdint.h>

#include "soa/mesh.h"

typedef struct {
  size_t nnodes, ncells;
  double *xyz;    /* 3*nnodes, interleaved */
  uint8_t *type;  /* ncells, MX_TET .. MX_HEX */
  uint32_t *conn; /* 8 per cell; entries past the type's node count are 0 */
  /* Tagged boundary faces, when the file has them (else 0 and NULL; see
   * "Boundary tags" above), in the file's order: */
  size_t nfaces;
  uint8_t *face_nn;    /* nfaces: 3 (triangle) or 4 (quadrilateral) */
  uint32_t *face_conn; /* 4 per face, 0-based; a triangle's 4th entry is 0 */
  int32_t *face_tag;   /* nfaces */
  /* Names of boundary tags, when the file has them (else 0 and NULL): tag
   * name_tag[i] is named name[i] (NUL-terminated); tags are unique. */
  size_t nnames;
  int32_t *name_tag;
  char **name;
  /* The point field surface_tag of a VTK or VTU file (nnodes values), or
   * NULL. */
  int32_t *node_tag;
  /* The point field boundary of a VTU file (mixoct's: 1 on the nodes of
   * the boundary faces), when all its values are 0 or 1; else NULL. */
  uint8_t *node_bnd;
  /* Each cell's label when the file gives one (several materials, issue
   * 26): the physical tag of a Gmsh volume entity, the cell field
   * "material" of a VTK or VTU file, a Medit element reference; ncells
   * values in the cells' order here, or NULL. */
  int32_t *cell_tag;
} mx_mesh_data;

/* Frees every array (the new fields too) and zeroes *m. */
void mx_mesh_data_free(mx_mesh_data *m);

/* A view for the writers (no fields). */
static inline mx_mesh_view mx_mesh_data_view(const mx_mesh_data *m) {
  mx_mesh_view v = {.nnodes = m->nnodes, .xyz = m->xyz, .ncells = m->ncells, .type = m->type, .conn = m->conn, .ncell_fields = 0, .cell_fields = NULL, .npoint_fields = 0, .point_fields = NULL};
  return v;
}

#endif
