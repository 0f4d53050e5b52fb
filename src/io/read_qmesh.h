/* Reading 2D meshes (quad/quad.h: mx_qmesh) back from the files
 * io/write_qmesh.c writes, for `mixoct check`; a file is 2D or 3D by its
 * content:
 *
 *  - legacy VTK (ASCII or binary) and VTU: only triangles (VTK type 5) and
 *    quadrilaterals (9), every point with z = 0 (io/read_mesh.h:
 *    mx_read_mesh_planar);
 *  - Gmsh MSH 4.1 (ASCII or binary) and Medit: no volume element, the
 *    triangles (type 2) and quadrangles (3) of dimension 2 (the lines of the
 *    "boundary" group are skipped), every node with z = 0;
 *  - OFF ("OFF" first, as io/read_off.c's variants): faces of 3 or 4
 *    vertices, every vertex with z = 0 (else MX_EINPUT naming the line: an
 *    OFF file is only read as a 2D mesh here).
 * Any other file mx_read_mesh reads is 3D. The 2D cells keep the file's
 * node order (a clockwise cell stays clockwise: the checks see it); the
 * nodes are the file's; nkey, leaf and level are NULL. GetFEM and M3D 2D
 * files are not read (their 3D readers take 3 coordinates and volume
 * types).
 *
 * Bad files: MX_EINPUT after one message naming the file and the line (or
 * byte offset), as io/read_mesh.c does; nothing is left allocated. */
#ifndef MX_READ_QMESH_H
#define MX_READ_QMESH_H

#include "io/read_mesh.h"
#include "quad/quad.h"

/* Reads path: a 2D mesh into *q (*dim = 2, *m empty) or a 3D one into *m
 * (*dim = 3, *q empty). */
int mx_read_mesh_dim(const char *path, mx_mesh_data *m, mx_qmesh *q, int *dim);

/* A 2D mesh only: a 3D file is MX_EINPUT ("not a 2D mesh"). */
int mx_read_qmesh(const char *path, mx_qmesh *q);

#endif
