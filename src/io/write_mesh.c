/* mixoct: choose the mesh writer from the output file's extension
 * (declared in io/write_mesh.h). */
#include <stdio.h>
#include <string.h>
#include <strings.h>

#include "base/common.h"
#include "io/pvtu.h"
#include "io/write_mesh.h"

/* The extension of the last path component, "" when it has none. */
static const char *path_extension(const char *path) {
  const char *slash = strrchr(path, '/');
  const char *base = slash ? slash + 1 : path;
  const char *dot = strrchr(base, '.');
  return dot && dot != base ? dot : "";
}

/* A 2D view: .vtu, .vtk, .msh, .off, .getfem, .m3d. */
static int write_plane(const char *path, const mx_mesh_view *m, int ascii) {
  const char *ext = path_extension(path);
  if (strcasecmp(ext, ".vtu") == 0) return mx_write_vtu(path, m);
  if (strcasecmp(ext, ".vtk") == 0) return mx_write_vtk_legacy(path, m, !ascii);
  if (strcasecmp(ext, ".msh") == 0) return mx_write_msh(path, m, !ascii);
  if (strcasecmp(ext, ".off") == 0) return mx_write_off(path, m);
  if (strcasecmp(ext, ".getfem") == 0) return mx_write_getfem(path, m);
  if (strcasecmp(ext, ".m3d") == 0) return mx_write_m3d(path, m);
  mx_error(path, 0, "unknown 2D output format (use .vtu, .vtk, .msh, .off, .getfem or .m3d)");
  return MX_EINPUT;
}

int mx_write_mesh(const char *path, const mx_mesh_view *m, int ascii) {
  if (mx_view_is_2d(m)) return write_plane(path, m, ascii);
  const char *ext = path_extension(path);
  if (strcasecmp(ext, ".vtk") == 0) return mx_write_vtk_legacy(path, m, !ascii);
  if (strcasecmp(ext, ".vtu") == 0) return mx_write_vtu(path, m);
  if (strcasecmp(ext, ".msh") == 0) return mx_write_msh(path, m, !ascii);
  if (strcasecmp(ext, ".mesh") == 0) return mx_write_medit(path, m, 0);
  if (strcasecmp(ext, ".meshb") == 0) return mx_write_medit(path, m, 1);
  if (strcasecmp(ext, ".getfem") == 0) return mx_write_getfem(path, m);
  if (strcasecmp(ext, ".m3d") == 0) return mx_write_m3d(path, m);
  if (strcasecmp(ext, ".mvm") == 0) return mx_write_mvm(path, m);
  if (strcasecmp(ext, ".pvtu") == 0) {
    /* one piece (the distributed path writes one per rank) */
    char piece[4096];
    mx_pvtu_piece_path(path, 0, piece, sizeof piece);
    MX_CHECK(mx_write_vtu_piece(piece, m, NULL));
    return mx_write_pvtu_master(path, 1, m, 0);
  }
  mx_error(path, 0,
           "unknown output format \"%s\" (use .vtk, .vtu, .pvtu, .msh, .mesh, .meshb, "
           ".getfem, .m3d or .mvm)",
           ext);
  return MX_EINPUT;
}

int mx_mesh_format_known(const char *path) {
  static const char *known[] = {".vtk",    ".vtu", ".pvtu", ".msh", ".mesh",
                                ".meshb",  ".getfem", ".m3d", ".mvm"};
  const char *ext = path_extension(path);
  for (size_t i = 0; i < sizeof known / sizeof *known; i++)
    if (strcasecmp(ext, known[i]) == 0) return 1;
  return 0;
}

int mx_boundary_format_known(const char *path) {
  static const char *known[] = {".vtu", ".stl", ".off", ".ply"};
  const char *ext = path ? path_extension(path) : "";
  for (size_t i = 0; i < sizeof known / sizeof *known; i++)
    if (strcasecmp(ext, known[i]) == 0) return 1;
  return 0;
}

int mx_plane_format_known(const char *path) {
  static const char *known[] = {".vtu", ".vtk", ".msh", ".off", ".getfem", ".m3d"};
  const char *ext = path_extension(path);
  for (size_t i = 0; i < sizeof known / sizeof *known; i++)
    if (strcasecmp(ext, known[i]) == 0) return 1;
  return 0;
}
