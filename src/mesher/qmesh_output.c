/* A 2D mesh written through io's writers (declared in
 * mesher/qmesh_output.h): its 2D mesh view, with the cell fields "type"
 * (int), "level" (its quadrant's, 8-bit; 0 without levels) and "sj" (the
 * scaled Jacobian, mx_qcell_sj). The fields are only computed on a
 * consistent mesh: an inconsistent one goes to the writers without them,
 * and their check names the bad cell. With several materials, the cell
 * field "material" and the materials as the view's bodies; with a size
 * field, "target_size". */
#include "mesher/qmesh_output.h"

#include "base/common.h"
#include "io/write_mesh.h"
#include "soa/mesh.h"

enum { PAR_MIN = 16384 }; /* fewer: one thread */

static int consistent(const mx_qmesh *M) {
  if ((M->nnodes && !M->xy) || (M->ncells && (!M->type || !M->conn))) return 0;
  return mx_qmesh_bad_cell(M) == M->ncells;
}

int mx_write_qmesh_tagged(const char *path, const mx_qmesh *M, int ascii,
                          const mx_qmesh_tags *T, const double *target_size) {
  mx_mesh_view v = {.nnodes = M->nnodes, .xyz = M->xy, .ncells = M->ncells,
                    .type = M->type, .conn = M->conn, .dim = 2};
  if (!consistent(M)) return mx_write_mesh(path, &v, ascii);
  const size_t nc = M->ncells;
  int32_t *type = mx_alloc((nc + 1) * sizeof *type);
  uint8_t *level = M->level ? NULL : mx_calloc(nc + 1);
  double *sj = mx_alloc((nc + 1) * sizeof *sj);
  if (!type || (!M->level && !level) || !sj) {
    mx_free(type), mx_free(level), mx_free(sj);
    return MX_ENOMEM;
  }
#pragma omp parallel for schedule(static) if (nc > PAR_MIN)
  for (size_t c = 0; c < nc; c++) {
    type[c] = M->type[c];
    sj[c] = mx_qcell_sj(M, c);
  }
  mx_field fields[5] = {{.name = "type", .ivalues = type},
                        {.name = "level", .u8values = M->level ? M->level : level},
                        {.name = "sj", .is_double = 1, .dvalues = sj}};
  v.ncell_fields = 3;
  if (T) {
    fields[3] = (mx_field){.name = "material", .ivalues = T->material};
    v.ncell_fields = 4;
    v.cell_body = T->body;
    v.nbodies = T->nbodies;
    v.body_names = T->names;
    v.body_physical = T->physical;
  }
  if (target_size)
    fields[v.ncell_fields++] = (mx_field){.name = "target_size", .is_double = 1,
                                          .dvalues = target_size};
  v.cell_fields = fields;
  const int st = mx_write_mesh(path, &v, ascii);
  mx_free(type), mx_free(level), mx_free(sj);
  return st;
}

int mx_write_qmesh(const char *path, const mx_qmesh *M, int ascii) {
  return mx_write_qmesh_tagged(path, M, ascii, NULL, NULL);
}

int mx_qmesh_format_known(const char *path) { return mx_plane_format_known(path); }
