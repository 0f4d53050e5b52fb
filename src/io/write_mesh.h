/* The mesh writers, one per format (src/io/write_*.c), each for 3D and 2D
 * views (soa/mesh.h: dim), and mx_write_mesh, which picks one from the
 * file's extension (src/io/write_mesh.c). */
#ifndef MX_WRITE_MESH_H
#define MX_WRITE_MESH_H

#include "soa/mesh.h"

/* Writers (src/io/write_*.c). The file is written under a temporary name in
 * the same directory and renamed at the end; on any failure (permission, full
 * disk) the temporary is removed, a message names the file, and MX_EINPUT is
 * returned. */
int mx_write_vtk_legacy(const char *path, const mx_mesh_view *m, int binary);
int mx_write_vtu(const char *path, const mx_mesh_view *m);
/* Gmsh MSH 4.1 (src/io/write_msh.c). */
int mx_write_msh(const char *path, const mx_mesh_view *m, int binary);
/* Medit .mesh (ASCII) / .meshb (binary), with the boundary triangles and
 * quadrilaterals (src/io/write_medit.c). */
int mx_write_medit(const char *path, const mx_mesh_view *m, int binary);
/* The published mesher's GetFEM and M3D files (src/io/write_getfem.c,
 * src/io/write_m3d.c). */
int mx_write_getfem(const char *path, const mx_mesh_view *m);
/* With several materials (view.body_physical), the .getfem file's region
 * of the convexes of material N is MX_GETFEM_MATERIAL_REGION + N (the
 * face regions keep the boundary tags' numbers, 1 .. ntags). */
enum { MX_GETFEM_MATERIAL_REGION = 1000 };
int mx_write_m3d(const char *path, const mx_mesh_view *m);
int mx_write_mvm(const char *path, const mx_mesh_view *m);
/* OFF, for a 2D view only (src/io/write_off.c). */
int mx_write_off(const char *path, const mx_mesh_view *m);
/* The boundary faces of the view (view.bfaces, with their tags) as a
 * surface VTU of their own (src/io/write_boundary.c). */
int mx_write_boundary_vtu(const char *path, const mx_mesh_view *m);
/* The same as a plain surface, by extension: binary STL (.stl, quads cut
 * in two), ASCII OFF (.off), binary PLY (.ply, with surface_tag and body)
 * (src/io/write_boundary_surface.c). */
int mx_write_boundary_surface(const char *path, const mx_mesh_view *m);
/* Dispatch on the extension: .vtk (legacy), .vtu, .msh, .mesh, .meshb,
 * .getfem, .m3d; ascii selects the ASCII variant where a format has both
 * (.vtk, .msh). A 2D view (soa/mesh.h: dim 2) goes to .vtu, .vtk, .msh,
 * .off, .getfem or .m3d. */
int mx_write_mesh(const char *path, const mx_mesh_view *m, int ascii);
/* mx_mesh_format_known, mx_plane_format_known (mixoct.h): whether the
 * extension of a path names a format mx_write_mesh knows for a 3D / 2D view. */

#endif
