/* mixoct: the OFF writer of 2D meshes (soa/mesh.h: a view of dim 2):
 * "OFF", the counts, the points "x y 0", one face per cell. A 3D mesh has no
 * OFF form (OFF is a surface format here). */
#include <stdint.h>
#include <string.h>

#include "base/common.h"
#include "io/atomic_file.h"
#include "io/mesh_view_check.h"
#include "io/plane_mesh.h"
#include "io/write_mesh.h"

typedef struct {
  const mx_mesh_view *M;
} plane_ctx;

static size_t fill_points(const void *v, size_t b, size_t e, char *o) {
  const plane_ctx *x = v;
  size_t n = 0;
  for (size_t i = b; i < e; i++) n += mx_plane_put_xy0(o + n, x->M->xyz + 2 * i, '\n');
  return n;
}

static size_t fill_faces(const void *v, size_t b, size_t e, char *o) {
  const plane_ctx *x = v;
  size_t n = 0;
  for (size_t c = b; c < e; c++) {
    const int nv = mx_view_nv2(x->M, c);
    o[n++] = (char)('0' + nv);
    n += mx_plane_put_ids(o + n, x->M->conn + 4 * c, nv, 0);
    o[n++] = '\n';
  }
  return n;
}

static int write_body(mx_afile *f, const mx_mesh_view *M) {
  plane_ctx x = {.M = M};
  MX_CHECK(mx_afile_printf(f, "OFF\n%zu %zu 0\n", M->nnodes, M->ncells));
  MX_CHECK(mx_afile_emit(f, M->nnodes, MX_XY0_MAX, fill_points, &x));
  return mx_afile_emit(f, M->ncells, 2 + 4 * (MX_U64_CHARS + 1), fill_faces, &x);
}

int mx_write_off(const char *path, const mx_mesh_view *m) {
  if (!mx_view_is_2d(m)) {
    mx_error(path, 0, "internal error: OFF is written for 2D meshes only");
    return MX_EINTERNAL;
  }
  MX_CHECK(mx_mesh_view_check(path, m));
  mx_afile f;
  MX_CHECK(mx_afile_open(&f, path));
  return mx_afile_finish(&f, write_body(&f, m));
}
