/* mixoct: choose the mesh writer from the output file's extension, and the
 * consistency check every writer runs before creating its file. */
#include <stdio.h>
#include <string.h>
#include <strings.h>

#include "base/common.h"
#include "io/atomic_file.h"
#include "io/pvtu.h"
#include "soa/mesh.h"

/* The extension of the last path component, "" when it has none. */
static const char *path_extension(const char *path) {
  const char *slash = strrchr(path, '/');
  const char *base = slash ? slash + 1 : path;
  const char *dot = strrchr(base, '.');
  return dot && dot != base ? dot : "";
}

int mx_write_mesh(const char *path, const mx_mesh_view *m, int ascii) {
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

/* ---- mesh view consistency ----------------------------------------------- */

/* Index of the first bad cell, or ncells. Parallel, deterministic answer. */
static size_t first_bad_cell(const mx_mesh_view *m) {
  size_t bad = m->ncells;
#pragma omp parallel for reduction(min    \
                                   : bad) \
    schedule(static) if (m->ncells > 65536)
  for (size_t c = 0; c < m->ncells; c++) {
    unsigned t = m->type[c];
    if (t > MX_HEX) {
      if (c < bad) bad = c;
      continue;
    }
    const uint32_t *row = m->conn + 8 * c;
    for (int j = 0; j < mx_cell_nodes[t]; j++) {
      if (row[j] >= m->nnodes && c < bad) bad = c;
    }
  }
  return bad;
}

static int report_bad_cell(const char *path, const mx_mesh_view *m, size_t c) {
  unsigned t = m->type[c];
  if (t > MX_HEX) {
    mx_error(path, 0, "internal error: cell %zu has invalid type %u", c, t);
    return MX_EINTERNAL;
  }
  mx_error(path, 0,
           "internal error: cell %zu references a node beyond the %zu nodes", c,
           m->nnodes);
  return MX_EINTERNAL;
}

static int check_fields(const char *path, int n, const mx_field *fields,
                        size_t count, const char *where) {
  if (n > 0 && !fields) {
    mx_error(path, 0, "internal error: %s fields missing", where);
    return MX_EINTERNAL;
  }
  for (int i = 0; i < n; i++) {
    const mx_field *fd = &fields[i];
    /* the source of the values: exactly one array of the written kind */
    const void *wide = fd->is_double ? (const void *)fd->dvalues : (const void *)fd->ivalues;
    const void *narrow =
        fd->is_double ? (const void *)fd->fvalues : (const void *)fd->u8values;
    if (!fd->name || !fd->name[0] || (count > 0 && !wide && !narrow)) {
      mx_error(path, 0, "internal error: %s field %d has no name or values",
               where, i);
      return MX_EINTERNAL;
    }
    if (wide && narrow) {
      mx_error(path, 0, "internal error: %s field %d has two sources of values", where, i);
      return MX_EINTERNAL;
    }
  }
  return MX_OK;
}

int mx_mesh_view_check(const char *path, const mx_mesh_view *m) {
  if (!m || (m->nnodes > 0 && !m->xyz) ||
      (m->ncells > 0 && (!m->type || !m->conn)) || m->ncell_fields < 0 ||
      m->npoint_fields < 0) {
    mx_error(path, 0, "internal error: incomplete mesh");
    return MX_EINTERNAL;
  }
  MX_CHECK(
      check_fields(path, m->ncell_fields, m->cell_fields, m->ncells, "cell"));
  MX_CHECK(check_fields(path, m->npoint_fields, m->point_fields, m->nnodes,
                        "point"));
  size_t bad = first_bad_cell(m);
  if (bad < m->ncells) return report_bad_cell(path, m, bad);
  return MX_OK;
}
