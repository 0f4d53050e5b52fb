/* Writing a 2D mesh (quad/quad.h: mx_qmesh) through io's writers: the mesh
 * as a 2D mesh view (soa/mesh.h, dim 2) with its cell fields
 * (src/mesher/qmesh_output.c). */
#ifndef MX_QMESH_OUTPUT_H
#define MX_QMESH_OUTPUT_H

#include "quad/quad.h"

/* By extension: .vtu (binary), .vtk (legacy), .msh (Gmsh 4.1: the cells,
 * and the boundary edges as lines in a physical group "boundary"), .off,
 * .getfem, .m3d (io/write_mesh.h: mx_write_mesh). Written to a temporary
 * name and renamed (io/atomic_file.h). Cell fields: type, level, sj (scaled
 * Jacobian). */
int mx_write_qmesh(const char *path, const mx_qmesh *M, int ascii);
/* Several materials: per cell its material's number (the cell field
 * "material") and its body 1 .. nbodies, each body's name and number
 * (the .msh writer's physical surfaces, the .getfem writer's regions).
 * T NULL: one material. target_size (NULL: none): a size field's value at
 * each cell, the cell field "target_size" (issue 27). */
typedef struct {
  const int32_t *material;
  const int32_t *body;
  int nbodies;
  const char *const *names;
  const int32_t *physical;
} mx_qmesh_tags;
int mx_write_qmesh_tagged(const char *path, const mx_qmesh *M, int ascii, const mx_qmesh_tags *T,
                          const double *target_size);
int mx_qmesh_format_known(const char *path);

#endif
