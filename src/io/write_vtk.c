/* mixoct: legacy VTK 3.0 writer (UNSTRUCTURED_GRID), binary or ASCII.
 *
 * Binary data is big-endian, as the legacy format requires. Numbers of both
 * kinds are produced in chunks, filled in parallel by mx_afile_emit, so the
 * file is the same byte for byte whatever the number of threads. ASCII
 * doubles are written with 17 significant digits, or 15 when those read
 * back to the same double (see mx_put_double in io/text_num.h).
 * A 2D view (soa/mesh.h: dim 2) is written by the section "a 2D view"
 * below. */
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "base/common.h"
#include "io/atomic_file.h"
#include "io/plane_mesh.h"
#include "io/text_num.h"
#include "soa/mesh.h"
#include "io/write_mesh.h"
#include "io/mesh_view_check.h"

enum { NAME_MAX_BYTES = 1024 };

typedef struct {
  const mx_mesh_view *m;
  const mx_field *fd;
  const uint32_t *order; /* fields: the written order of the cells, or NULL */
} vtk_ctx;

static inline size_t item(const vtk_ctx *c, size_t k) { return c->order ? c->order[k] : k; }

/* ---- big-endian stores --------------------------------------------------- */

static inline void put_be32(char *out, uint32_t v) {
#if __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__
  v = __builtin_bswap32(v);
#endif
  memcpy(out, &v, 4);
}

static inline void put_be64(char *out, uint64_t v) {
#if __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__
  v = __builtin_bswap64(v);
#endif
  memcpy(out, &v, 8);
}

static inline void put_be_double(char *out, double d) {
  uint64_t v;
  memcpy(&v, &d, 8);
  put_be64(out, v);
}

/* ---- fill functions: points ---------------------------------------------- */

static size_t fill_points_bin(const void *vctx, size_t b, size_t e, char *out) {
  const vtk_ctx *ctx = vctx;
  const double *xyz = ctx->m->xyz;
  size_t n = 0;
  for (size_t i = 3 * b; i < 3 * e; i++, n += 8) put_be_double(out + n, xyz[i]);
  return n;
}

static size_t fill_points_ascii(const void *vctx, size_t b, size_t e,
                                char *out) {
  return mx_put_xyz_lines(out, ((const vtk_ctx *)vctx)->m->xyz, b, e);
}

/* ---- cells --------------------------------------------------------------- */

static size_t fill_cells_bin(const void *vctx, size_t b, size_t e, char *out) {
  const mx_mesh_view *m = ((const vtk_ctx *)vctx)->m;
  size_t n = 0;
  for (size_t k = b; k < e; k++) {
    const size_t c = mx_view_cell(m, k);
    int nn = mx_cell_nodes[m->type[c]];
    const uint32_t *row = m->conn + 8 * c;
    put_be32(out + n, (uint32_t)nn);
    n += 4;
    const int8_t *ord = mx_vtk_order[m->type[c]];
    for (int j = 0; j < nn; j++, n += 4) put_be32(out + n, row[ord[j]]);
  }
  return n;
}

static size_t fill_cells_ascii(const void *vctx, size_t b, size_t e,
                               char *out) {
  const mx_mesh_view *m = ((const vtk_ctx *)vctx)->m;
  size_t n = 0;
  for (size_t k = b; k < e; k++) {
    const size_t c = mx_view_cell(m, k);
    int nn = mx_cell_nodes[m->type[c]];
    const uint32_t *row = m->conn + 8 * c;
    out[n++] = (char)('0' + nn);
    const int8_t *ord = mx_vtk_order[m->type[c]];
    for (int j = 0; j < nn; j++) {
      out[n++] = ' ';
      n += mx_put_u64(out + n, row[ord[j]]);
    }
    out[n++] = '\n';
  }
  return n;
}

static size_t fill_types_bin(const void *vctx, size_t b, size_t e, char *out) {
  const mx_mesh_view *m = ((const vtk_ctx *)vctx)->m;
  for (size_t k = b; k < e; k++) {
    put_be32(out + 4 * (k - b), (uint32_t)mx_vtk_cell_type[m->type[mx_view_cell(m, k)]]);
  }
  return 4 * (e - b);
}

static size_t fill_types_ascii(const void *vctx, size_t b, size_t e,
                               char *out) {
  const mx_mesh_view *m = ((const vtk_ctx *)vctx)->m;
  size_t n = 0;
  for (size_t k = b; k < e; k++) {
    n += mx_put_u64(out + n, (uint64_t)mx_vtk_cell_type[m->type[mx_view_cell(m, k)]]);
    out[n++] = '\n';
  }
  return n;
}

/* ---- fields -------------------------------------------------------------- */

/* Values are converted from the field's source (int32 or uint8, double or
 * float) as they are written: "int" and "double" whatever the source. */
static size_t fill_field_bin(const void *vctx, size_t b, size_t e, char *out) {
  const vtk_ctx *c = vctx;
  const mx_field *fd = c->fd;
  size_t n = 0;
  if (fd->is_double && fd->dvalues) {
    for (size_t i = b; i < e; i++, n += 8)
      put_be_double(out + n, fd->dvalues[item(c, i)]);
  } else if (fd->is_double) {
    for (size_t i = b; i < e; i++, n += 8)
      put_be_double(out + n, (double)fd->fvalues[item(c, i)]);
  } else if (fd->ivalues) {
    for (size_t i = b; i < e; i++, n += 4)
      put_be32(out + n, (uint32_t)fd->ivalues[item(c, i)]);
  } else {
    for (size_t i = b; i < e; i++, n += 4)
      put_be32(out + n, (uint32_t)fd->u8values[item(c, i)]);
  }
  return n;
}

static size_t fill_field_ascii(const void *vctx, size_t b, size_t e,
                               char *out) {
  const vtk_ctx *c = vctx;
  const mx_field *fd = c->fd;
  size_t n = 0;
  for (size_t i = b; i < e; i++) {
    if (fd->is_double)
      n += mx_put_double(out + n, mx_field_double(fd, item(c, i)));
    else
      n += mx_put_i64(out + n, mx_field_int(fd, item(c, i)));
    out[n++] = '\n';
  }
  return n;
}

/* ---- sections ------------------------------------------------------------ */

/* Legacy names are single tokens: blanks, '%' and non-printable bytes are
 * written as %XX, which VTK's reader decodes. */
static void encode_name(const char *name, char *out, size_t cap) {
  static const char hex[] = "0123456789ABCDEF";
  size_t n = 0;
  for (const unsigned char *p = (const unsigned char *)name; *p; p++) {
    if (n + 4 >= cap) break;
    if (*p <= ' ' || *p >= 127 || *p == '%') {
      out[n++] = '%';
      out[n++] = hex[*p >> 4];
      out[n++] = hex[*p & 15];
    } else {
      out[n++] = (char)*p;
    }
  }
  out[n] = '\0';
}

static int write_points(mx_afile *f, const vtk_ctx *ctx, int binary) {
  const mx_mesh_view *m = ctx->m;
  MX_CHECK(mx_afile_printf(f, "POINTS %zu double\n", m->nnodes));
  if (binary)
    MX_CHECK(mx_afile_emit(f, m->nnodes, 24, fill_points_bin, ctx));
  else
    MX_CHECK(
        mx_afile_emit(f, m->nnodes, MX_XYZ_LINE_MAX, fill_points_ascii, ctx));
  return binary ? mx_afile_write(f, "\n", 1) : MX_OK;
}

static size_t cells_list_size(const mx_mesh_view *m) {
  size_t total = 0;
#pragma omp parallel for reduction(+ : total) schedule(static) \
    if (m->ncells > 65536)
  for (size_t c = 0; c < m->ncells; c++) {
    total += 1 + (size_t)mx_cell_nodes[m->type[c]];
  }
  return total;
}

static int write_cells(mx_afile *f, const vtk_ctx *ctx, int binary) {
  const mx_mesh_view *m = ctx->m;
  MX_CHECK(
      mx_afile_printf(f, "CELLS %zu %zu\n", m->ncells, cells_list_size(m)));
  if (binary)
    MX_CHECK(mx_afile_emit(f, m->ncells, 36, fill_cells_bin, ctx));
  else
    MX_CHECK(mx_afile_emit(f, m->ncells, 2 + 8 * 11, fill_cells_ascii, ctx));
  if (binary) MX_CHECK(mx_afile_write(f, "\n", 1));
  MX_CHECK(mx_afile_printf(f, "CELL_TYPES %zu\n", m->ncells));
  if (binary)
    MX_CHECK(mx_afile_emit(f, m->ncells, 4, fill_types_bin, ctx));
  else
    MX_CHECK(mx_afile_emit(f, m->ncells, 4, fill_types_ascii, ctx));
  return binary ? mx_afile_write(f, "\n", 1) : MX_OK;
}

static int write_field(mx_afile *f, const mx_mesh_view *m, const mx_field *fd,
                       size_t count, const uint32_t *order, int binary) {
  char name[NAME_MAX_BYTES];
  encode_name(fd->name, name, sizeof name);
  MX_CHECK(mx_afile_printf(f, "SCALARS %s %s 1\nLOOKUP_TABLE default\n", name,
                           fd->is_double ? "double" : "int"));
  vtk_ctx ctx = {m, fd, order};
  size_t width = fd->is_double ? 8 : 4;
  if (binary)
    MX_CHECK(mx_afile_emit(f, count, width, fill_field_bin, &ctx));
  else
    MX_CHECK(mx_afile_emit(f, count, MX_NUM_MAX, fill_field_ascii, &ctx));
  return binary ? mx_afile_write(f, "\n", 1) : MX_OK;
}

static int write_fields(mx_afile *f, const mx_mesh_view *m, const char *kind,
                        int nfields, const mx_field *fields, size_t count,
                        const uint32_t *order, int binary) {
  if (nfields == 0) return MX_OK;
  MX_CHECK(mx_afile_printf(f, "%s %zu\n", kind, count));
  for (int i = 0; i < nfields; i++) {
    MX_CHECK(write_field(f, m, &fields[i], count, order, binary));
  }
  return MX_OK;
}

static int write_body(mx_afile *f, const mx_mesh_view *m, int binary) {
  vtk_ctx ctx = {m, NULL, NULL};
  MX_CHECK(mx_afile_printf(f,
                           "# vtk DataFile Version 3.0\nmixoct mesh\n%s\n"
                           "DATASET UNSTRUCTURED_GRID\n",
                           binary ? "BINARY" : "ASCII"));
  MX_CHECK(write_points(f, &ctx, binary));
  MX_CHECK(write_cells(f, &ctx, binary));
  MX_CHECK(write_fields(f, m, "CELL_DATA", m->ncell_fields, m->cell_fields,
                        m->ncells, m->order, binary));
  MX_CHECK(write_fields(f, m, "POINT_DATA", m->npoint_fields, m->point_fields,
                        m->nnodes, NULL, binary));
  return MX_OK;
}

/* ---- a 2D view (soa/mesh.h: dim 2) ---------------------------------------
 *
 * Points "x y 0", cells VTK_TRIANGLE (5) / VTK_QUAD (9), the cell fields as
 * "int" or "double" scalars under their own names, in index order. */

typedef struct {
  const mx_mesh_view *m;
  const mx_field *fd;
  int binary;
} plane_ctx;

static size_t fill_plane_points(const void *v, size_t b, size_t e, char *o) {
  const plane_ctx *x = v;
  size_t n = 0;
  for (size_t i = b; i < e; i++) {
    const double *p = x->m->xyz + 2 * i;
    if (!x->binary) {
      n += mx_plane_put_xy0(o + n, p, '\n');
      continue;
    }
    put_be_double(o + n, p[0]);
    put_be_double(o + n + 8, p[1]);
    put_be_double(o + n + 16, 0.0);
    n += 24;
  }
  return n;
}

static size_t fill_plane_cells(const void *v, size_t b, size_t e, char *o) {
  const plane_ctx *x = v;
  size_t n = 0;
  for (size_t c = b; c < e; c++) {
    const int nv = mx_view_nv2(x->m, c);
    const uint32_t *row = x->m->conn + 4 * c;
    if (!x->binary) {
      o[n++] = (char)('0' + nv);
      n += mx_plane_put_ids(o + n, row, nv, 0);
      o[n++] = '\n';
      continue;
    }
    put_be32(o + n, (uint32_t)nv);
    n += 4;
    for (int j = 0; j < nv; j++, n += 4) put_be32(o + n, row[j]);
  }
  return n;
}

static size_t fill_plane_types(const void *v, size_t b, size_t e, char *o) {
  const plane_ctx *x = v;
  size_t n = 0;
  for (size_t c = b; c < e; c++) {
    const uint32_t t = x->m->type[c] == MX_CELL_QUAD ? 9 : 5;
    if (x->binary) {
      put_be32(o + n, t);
      n += 4;
    } else {
      o[n++] = t == 9 ? '9' : '5';
      o[n++] = '\n';
    }
  }
  return n;
}

static size_t fill_plane_field(const void *v, size_t b, size_t e, char *o) {
  const plane_ctx *x = v;
  const mx_field *fd = x->fd;
  size_t n = 0;
  for (size_t c = b; c < e; c++) {
    if (x->binary && fd->is_double) {
      put_be_double(o + n, mx_field_double(fd, c));
      n += 8;
    } else if (x->binary) {
      put_be32(o + n, (uint32_t)mx_field_int(fd, c));
      n += 4;
    } else {
      n += fd->is_double ? mx_put_double(o + n, mx_field_double(fd, c))
                         : mx_put_i64(o + n, (int64_t)mx_field_int(fd, c));
      o[n++] = '\n';
    }
  }
  return n;
}

static int write_plane_body(mx_afile *f, const mx_mesh_view *m, int binary) {
  plane_ctx x = {.m = m, .binary = binary};
  const size_t nconn = 3 * m->ncells + mx_plane_count_quads(m);
  MX_CHECK(mx_afile_printf(f, "# vtk DataFile Version 3.0\nmixoct 2D mesh\n%s\n"
                              "DATASET UNSTRUCTURED_GRID\nPOINTS %zu double\n",
                           binary ? "BINARY" : "ASCII", m->nnodes));
  MX_CHECK(mx_afile_emit(f, m->nnodes, MX_XY0_MAX, fill_plane_points, &x));
  MX_CHECK(mx_afile_printf(f, "%sCELLS %zu %zu\n", binary ? "\n" : "", m->ncells,
                           m->ncells + nconn));
  MX_CHECK(mx_afile_emit(f, m->ncells, 2 + 4 * (MX_U64_CHARS + 1), fill_plane_cells, &x));
  MX_CHECK(mx_afile_printf(f, "%sCELL_TYPES %zu\n", binary ? "\n" : "", m->ncells));
  MX_CHECK(mx_afile_emit(f, m->ncells, 4, fill_plane_types, &x));
  MX_CHECK(mx_afile_printf(f, "%sCELL_DATA %zu\n", binary ? "\n" : "", m->ncells));
  for (int k = 0; k < m->ncell_fields; k++) {
    x.fd = &m->cell_fields[k];
    MX_CHECK(mx_afile_printf(f, "SCALARS %s %s 1\nLOOKUP_TABLE default\n", x.fd->name,
                             x.fd->is_double ? "double" : "int"));
    MX_CHECK(mx_afile_emit(f, m->ncells, MX_NUM_MAX, fill_plane_field, &x));
    if (binary) MX_CHECK(mx_afile_write(f, "\n", 1));
  }
  return MX_OK;
}

int mx_write_vtk_legacy(const char *path, const mx_mesh_view *m, int binary) {
  MX_CHECK(mx_mesh_view_check(path, m));
  if (mx_view_is_2d(m)) {
    mx_afile f;
    MX_CHECK(mx_afile_open(&f, path));
    return mx_afile_finish(&f, write_plane_body(&f, m, binary));
  }
  if (m->nnodes > (size_t)INT32_MAX) {
    mx_error(path, 0,
             "%zu nodes are too many for legacy VTK (32-bit ids): use .vtu",
             m->nnodes);
    return MX_EINPUT;
  }
  mx_afile f;
  MX_CHECK(mx_afile_open(&f, path));
  return mx_afile_finish(&f, write_body(&f, m, binary));
}
