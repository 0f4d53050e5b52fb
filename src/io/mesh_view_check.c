/* The consistency check every mesh writer runs on its mesh view before
 * creating its file (declared in io/mesh_view_check.h). */
#include "io/mesh_view_check.h"

#include "base/common.h"

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

/* A 2D view: types triangle or quadrilateral, the nodes of each cell below
 * nnodes; the first bad cell is named. */
static int check_2d(const char *path, const mx_mesh_view *m) {
  if ((m->nnodes && !m->xyz) || (m->ncells && (!m->type || !m->conn))) {
    mx_error(path, 0, "internal error: incomplete 2D mesh");
    return MX_EINTERNAL;
  }
  size_t bad = m->ncells;
#pragma omp parallel for reduction(min : bad) schedule(static) if (m->ncells > 65536)
  for (size_t c = 0; c < m->ncells; c++) {
    int ok = m->type[c] <= MX_CELL_QUAD;
    const int nv = m->type[c] == MX_CELL_QUAD ? 4 : 3;
    for (int j = 0; ok && j < nv; j++) ok = m->conn[4 * c + j] < m->nnodes;
    if (!ok && c < bad) bad = c;
  }
  if (bad < m->ncells) {
    mx_error(path, 0, "internal error: cell %zu has a bad type or node index", bad);
    return MX_EINTERNAL;
  }
  if (m->cell_body && m->nbodies > 0) { /* bodies: each cell's among them, all named */
    if (!m->body_names || m->nbodies > 255) {
      mx_error(path, 0, "internal error: %d bodies without names or beyond 255", m->nbodies);
      return MX_EINTERNAL;
    }
#pragma omp parallel for reduction(min : bad) schedule(static) if (m->ncells > 65536)
    for (size_t c = 0; c < m->ncells; c++)
      if ((m->cell_body[c] < 1 || m->cell_body[c] > m->nbodies) && c < bad) bad = c;
    if (bad < m->ncells) {
      mx_error(path, 0, "internal error: cell %zu has body %d (of %d)", bad, m->cell_body[bad],
               m->nbodies);
      return MX_EINTERNAL;
    }
  }
  MX_CHECK(check_fields(path, m->ncell_fields, m->cell_fields, m->ncells, "cell"));
  return check_fields(path, m->npoint_fields, m->point_fields, m->nnodes, "point");
}

int mx_mesh_view_check(const char *path, const mx_mesh_view *m) {
  if (m && mx_view_is_2d(m)) return check_2d(path, m);
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
