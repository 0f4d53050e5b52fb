/* mixoct: the pieces and the master of a parallel VTU mesh (io/pvtu.h).
 *
 * A piece is the 3D VTU writer's output (io/write_vtu.c) through its
 * extension point (io/vtu_common.h): the GlobalNodeId array and field
 * types that do not depend on the values. The master is a short XML file
 * built with the same header helpers. */
#include "io/pvtu.h"

#include <stdio.h>
#include <string.h>
#include <strings.h>

#include "base/common.h"
#include "io/atomic_file.h"
#include "io/vtu_common.h"

void mx_pvtu_piece_path(const char *pvtu_path, int piece, char *buf, size_t n) {
  if (n == 0) return;
  size_t len = strlen(pvtu_path);
  if (len >= 5 && strcasecmp(pvtu_path + len - 5, ".pvtu") == 0) len -= 5;
  const int w = snprintf(buf, n, "%.*s_%d.vtu", (int)len, pvtu_path, piece);
  if (w < 0 || (size_t)w >= n) buf[0] = '\0';
}

int mx_write_vtu_piece(const char *path, const mx_mesh_view *v, const uint64_t *global_id) {
  if (v && global_id) {
    /* Int64 in the file: an id from 2^63 on would read back negative */
    size_t bad = 0;
#pragma omp parallel for schedule(static) reduction(+ : bad) if (v->nnodes > 65536)
    for (size_t i = 0; i < v->nnodes; i++) bad += global_id[i] > (uint64_t)INT64_MAX;
    if (bad) {
      mx_error(path, 0, "internal error: %zu global node ids of 2^63 or more", bad);
      return MX_EINTERNAL;
    }
  }
  const mx_vtu_extra x = {MX_PVTU_GLOBAL_ID, global_id, 1};
  return mx_write_vtu_extra(path, v, &x);
}

static void p_arrays(mx_vtu_head *h, const char *tag, int nfields, const mx_field *fields,
                     int with_ids) {
  mx_vtu_printf(h, "    <%s>\n", tag);
  for (int i = 0; i < nfields; i++) {
    mx_vtu_printf(h, "      <PDataArray type=\"%s\" Name=\"", mx_vtu_fixed_type(&fields[i]));
    mx_vtu_escaped(h, fields[i].name);
    mx_vtu_printf(h, "\"/>\n");
  }
  if (with_ids)
    mx_vtu_printf(h, "      <PDataArray type=\"Int64\" Name=\"%s\"/>\n", MX_PVTU_GLOBAL_ID);
  mx_vtu_printf(h, "    </%s>\n", tag);
}

/* The master's text in h (h->failed on a failed allocation). */
static int master_text(mx_vtu_head *h, const char *pvtu_path, int npieces, const mx_mesh_view *v,
                       int with_global_id) {
  mx_vtu_printf(h, "<?xml version=\"1.0\"?>\n"
                   "<VTKFile type=\"PUnstructuredGrid\" version=\"1.0\" "
                   "byte_order=\"LittleEndian\" header_type=\"UInt64\">\n"
                   "  <PUnstructuredGrid GhostLevel=\"0\">\n");
  p_arrays(h, "PPointData", v->npoint_fields, v->point_fields, with_global_id);
  p_arrays(h, "PCellData", v->ncell_fields, v->cell_fields, 0);
  mx_vtu_printf(h, "    <PPoints>\n"
                   "      <PDataArray type=\"Float64\" Name=\"Points\" "
                   "NumberOfComponents=\"3\"/>\n"
                   "    </PPoints>\n");
  /* the pieces lie beside the master: their names without the directory */
  const size_t n = strlen(pvtu_path) + 32;
  char *piece = mx_alloc(n);
  if (!piece) return MX_ENOMEM;
  for (int i = 0; i < npieces; i++) {
    mx_pvtu_piece_path(pvtu_path, i, piece, n);
    const char *slash = strrchr(piece, '/');
    mx_vtu_printf(h, "    <Piece Source=\"");
    mx_vtu_escaped(h, slash ? slash + 1 : piece);
    mx_vtu_printf(h, "\"/>\n");
  }
  mx_free(piece);
  mx_vtu_printf(h, "  </PUnstructuredGrid>\n</VTKFile>\n");
  return h->failed ? MX_ENOMEM : MX_OK;
}

int mx_write_pvtu_master(const char *pvtu_path, int npieces, const mx_mesh_view *v,
                         int with_global_id) {
  if (!v || npieces < 1 || (v->npoint_fields > 0 && !v->point_fields) ||
      (v->ncell_fields > 0 && !v->cell_fields)) {
    mx_error(pvtu_path, 0, "internal error: %d pieces or incomplete fields", npieces);
    return MX_EINTERNAL;
  }
  mx_vtu_head h = {0};
  int st = master_text(&h, pvtu_path, npieces, v, with_global_id);
  if (st == MX_OK) {
    mx_afile f;
    st = mx_afile_open(&f, pvtu_path);
    if (st == MX_OK) st = mx_afile_finish(&f, mx_afile_write(&f, h.s, h.len));
  }
  mx_free(h.s);
  return st;
}
