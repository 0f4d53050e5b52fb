/* mixoct: VTK XML UnstructuredGrid writer (.vtu), version 1.0, UInt64
 * headers, little-endian raw appended data (the layout and what it shares
 * with the 2D writer: io/vtu_common.h).
 *
 * On a little-endian host coordinates and fields are copied straight from
 * the mesh arrays into the output chunks; connectivity, offsets and types are converted in
 * parallel in place in them (io/atomic_file.h: a background thread writes
 * one chunk while the next is filled). mx_write_vtu_extra adds what a
 * piece of a .pvtu needs (io/vtu_common.h, io/write_pvtu.c).
 * A 2D view (soa/mesh.h: dim 2) is written by the section "a 2D view"
 * below. */
#include <stdint.h>
#include <string.h>

#include "base/common.h"
#include "io/atomic_file.h"
#include "io/plane_mesh.h"
#include "io/vtu_common.h"
#include "soa/mesh.h"
#include "base/scan.h"
#include "io/write_mesh.h"
#include "io/mesh_view_check.h"

enum { OFFSET_BLOCK = 4096 }; /* cells per precomputed offsets prefix */

typedef struct {
  const mx_mesh_view *m;
  const mx_field *fd;
  const uint64_t *block_start; /* nodes before cell k*OFFSET_BLOCK */
  int wide;                    /* Int64 connectivity and offsets, else Int32 */
  const uint32_t *order;       /* cell fields: the written order, or NULL */
} vtu_ctx;

/* The value index of the k-th item of a block (cell fields follow the
 * written order of the cells). */
static inline size_t item(const vtu_ctx *c, size_t k) { return c->order ? c->order[k] : k; }

/* ---- header -------------------------------------------------------------- */

static size_t conn_length(const mx_mesh_view *m) {
  size_t total = 0;
#pragma omp parallel for reduction(+ : total) schedule(static) \
    if (m->ncells > 65536)
  for (size_t c = 0; c < m->ncells; c++)
    total += (size_t)mx_cell_nodes[m->type[c]];
  return total;
}

/* An integer field whose values all lie in 0..255 is written as UInt8
 * (element types, levels, boundary flags: a quarter of the bytes); one read
 * from 8-bit values always is, as its int32 copy would be. */
static int fits_u8(const mx_field *fd, size_t count) {
  if (fd->is_double) return 0;
  if (!fd->ivalues) return 1;
  size_t out = 0;
#pragma omp parallel for reduction(+ : out) schedule(static) if (count > 65536)
  for (size_t i = 0; i < count; i++) out += (uint32_t)fd->ivalues[i] > 255u;
  return out == 0;
}

/* With fixed types (the pieces of a .pvtu, io/vtu_common.h) only an 8-bit
 * source is UInt8. */
static int narrow_u8(const mx_field *fd, size_t count, int fixed) {
  return fixed ? !fd->is_double && !fd->ivalues : fits_u8(fd, count);
}

const char *mx_vtu_fixed_type(const mx_field *fd) {
  return fd->is_double ? "Float64" : narrow_u8(fd, 0, 1) ? "UInt8" : "Int32";
}

/* The fields, then the Int64 ids when ids_name is not NULL. */
static void xml_fields(mx_vtu_head *h, const char *tag, int nfields, const mx_field *fields,
                       size_t count, int fixed, const char *ids_name) {
  mx_vtu_printf(h, "      <%s>\n", tag);
  for (int i = 0; i < nfields; i++) {
    const mx_field *fd = &fields[i];
    const int u8 = narrow_u8(fd, count, fixed);
    mx_vtu_array(h, fd->is_double ? "Float64" : u8 ? "UInt8" : "Int32", fd->name, 1,
                 (uint64_t)count * (fd->is_double ? 8 : u8 ? 1 : 4));
  }
  if (ids_name) mx_vtu_array(h, "Int64", ids_name, 1, 8 * (uint64_t)count);
  mx_vtu_printf(h, "      </%s>\n", tag);
}

/* Int64 indices only when Int32 cannot hold them (smaller, faster files). */
static int needs_wide(const mx_mesh_view *m, size_t nconn) {
  return nconn > (size_t)INT32_MAX || m->nnodes > (size_t)INT32_MAX;
}

static int xml_header(mx_afile *f, const mx_mesh_view *m, size_t nconn, const mx_vtu_extra *x) {
  mx_vtu_head h = {0};
  mx_vtu_begin(&h, m->nnodes, m->ncells);
  xml_fields(&h, "PointData", m->npoint_fields, m->point_fields, m->nnodes, x->fixed_types,
             x->ids ? x->ids_name : NULL);
  xml_fields(&h, "CellData", m->ncell_fields, m->cell_fields, m->ncells, x->fixed_types, NULL);
  return mx_vtu_end(f, &h, m->nnodes, m->ncells, nconn, needs_wide(m, nconn));
}

/* ---- appended blocks ----------------------------------------------------- */

#if !MX_VTU_HOST_LE
static size_t fill_doubles(const void *vctx, size_t b, size_t e, char *out) {
  const double *v = ((const vtu_ctx *)vctx)->fd->dvalues;
  size_t n = 0;
  for (size_t i = b; i < e; i++, n += 8) mx_put_le_double(out + n, v[i]);
  return n;
}
#endif

static size_t fill_conn(const void *vctx, size_t b, size_t e, char *out) {
  const vtu_ctx *ctx = vctx;
  const mx_mesh_view *m = ctx->m;
  size_t n = 0;
  for (size_t k = b; k < e; k++) {
    const size_t c = mx_view_cell(m, k);
    const uint32_t *row = m->conn + 8 * c;
    int nn = mx_cell_nodes[m->type[c]];
    const int8_t *ord = mx_vtk_order[m->type[c]];
    if (ctx->wide)
      for (int j = 0; j < nn; j++, n += 8) mx_put_le64(out + n, row[ord[j]]);
    else
      for (int j = 0; j < nn; j++, n += 4) mx_put_le32(out + n, row[ord[j]]);
  }
  return n;
}

static size_t fill_offsets(const void *vctx, size_t b, size_t e, char *out) {
  const vtu_ctx *ctx = vctx;
  const mx_mesh_view *m = ctx->m;
  size_t first = b / OFFSET_BLOCK * OFFSET_BLOCK;
  uint64_t end = ctx->block_start[b / OFFSET_BLOCK];
  for (size_t k = first; k < b; k++) end += (uint64_t)mx_cell_nodes[m->type[mx_view_cell(m, k)]];
  size_t n = 0;
  for (size_t k = b; k < e; k++) {
    end += (uint64_t)mx_cell_nodes[m->type[mx_view_cell(m, k)]];
    if (ctx->wide) {
      mx_put_le64(out + n, end);
      n += 8;
    } else {
      mx_put_le32(out + n, (uint32_t)end);
      n += 4;
    }
  }
  return n;
}

static size_t fill_types(const void *vctx, size_t b, size_t e, char *out) {
  const mx_mesh_view *m = ((const vtu_ctx *)vctx)->m;
  for (size_t k = b; k < e; k++)
    out[k - b] = (char)mx_vtk_cell_type[m->type[mx_view_cell(m, k)]];
  return e - b;
}

/* A block of doubles (ncomp per item): straight from memory when the host
 * is little-endian, converted otherwise. */
static int write_double_block(mx_afile *f, const double *v, size_t count) {
  MX_CHECK(mx_vtu_count(f, 8 * (uint64_t)count));
#if MX_VTU_HOST_LE
  return mx_afile_write(f, v, 8 * count);
#else
  mx_field fd = {"", 1, NULL, v};
  vtu_ctx ctx = {NULL, &fd, NULL, 0, NULL};
  return mx_afile_emit(f, count, 8, fill_doubles, &ctx);
#endif
}

static size_t fill_u8(const void *vctx, size_t b, size_t e, char *out) {
  const vtu_ctx *c = vctx;
  if (c->fd->u8values) {
    const uint8_t *v = c->fd->u8values;
    if (!c->order) {
      memcpy(out, v + b, e - b);
    } else {
      for (size_t i = b; i < e; i++) out[i - b] = (char)v[c->order[i]];
    }
    return e - b;
  }
  const int32_t *v = c->fd->ivalues;
  for (size_t i = b; i < e; i++) out[i - b] = (char)(uint8_t)v[item(c, i)];
  return e - b;
}

/* Fields in the written order of the cells (gathered), or read from a
 * narrower source (converted): item by item. */
static size_t fill_doubles_gather(const void *vctx, size_t b, size_t e, char *out) {
  const vtu_ctx *c = vctx;
  const mx_field *fd = c->fd;
  size_t n = 0;
  if (fd->dvalues) {
    for (size_t i = b; i < e; i++, n += 8) mx_put_le_double(out + n, fd->dvalues[item(c, i)]);
  } else {
    for (size_t i = b; i < e; i++, n += 8)
      mx_put_le_double(out + n, (double)fd->fvalues[item(c, i)]);
  }
  return n;
}

static size_t fill_ints_gather(const void *vctx, size_t b, size_t e, char *out) {
  const vtu_ctx *c = vctx;
  size_t n = 0;
  for (size_t i = b; i < e; i++, n += 4)
    mx_put_le32(out + n, (uint32_t)mx_field_int(c->fd, item(c, i)));
  return n;
}

/* Float64, UInt8 or Int32, as xml_fields declared it. Only an int32 or
 * double source in index order is copied straight from memory. */
static int write_field_block(mx_afile *f, const mx_field *fd, size_t count,
                             const uint32_t *order, int fixed) {
  vtu_ctx gctx = {NULL, fd, NULL, 0, order};
  if (fd->is_double && fd->dvalues && !order) return write_double_block(f, fd->dvalues, count);
  if (fd->is_double)
    return mx_vtu_block(f, 8 * (uint64_t)count, count, 8, fill_doubles_gather, &gctx);
  if (narrow_u8(fd, count, fixed))
    return mx_vtu_block(f, (uint64_t)count, count, 1, fill_u8, &gctx);
  MX_CHECK(mx_vtu_count(f, 4 * (uint64_t)count));
#if MX_VTU_HOST_LE
  if (!order) return mx_afile_write(f, fd->ivalues, 4 * count);
#endif
  return mx_afile_emit(f, count, 4, fill_ints_gather, &gctx);
}

static int write_fields(mx_afile *f, int nfields, const mx_field *fields,
                        size_t count, const uint32_t *order, int fixed) {
  for (int i = 0; i < nfields; i++) {
    MX_CHECK(write_field_block(f, &fields[i], count, order, fixed));
  }
  return MX_OK;
}

static size_t fill_ids(const void *vctx, size_t b, size_t e, char *out) {
  const uint64_t *ids = vctx;
  for (size_t i = b; i < e; i++) mx_put_le64(out + 8 * (i - b), ids[i]);
  return 8 * (e - b);
}

/* Nodes before the first cell of each OFFSET_BLOCK-cell block. */
static uint64_t *offset_block_starts(const mx_mesh_view *m) {
  size_t nblocks = m->ncells / OFFSET_BLOCK + 1;
  uint64_t *start = mx_alloc(nblocks * sizeof *start);
  if (!start) return NULL;
#pragma omp parallel for schedule(static) if (nblocks > 16)
  for (size_t k = 0; k < nblocks; k++) {
    size_t lo = k * OFFSET_BLOCK, hi = lo + OFFSET_BLOCK;
    if (hi > m->ncells) hi = m->ncells;
    uint64_t sum = 0;
    for (size_t c = lo; c < hi; c++) sum += (uint64_t)mx_cell_nodes[m->type[mx_view_cell(m, c)]];
    start[k] = sum;
  }
  mx_scan_u64(start, nblocks);
  return start;
}

static int write_cell_blocks(mx_afile *f, const mx_mesh_view *m, size_t nconn) {
  uint64_t *block_start = offset_block_starts(m);
  if (!block_start) return MX_ENOMEM;
  const int wide = needs_wide(m, nconn);
  const uint64_t isz = wide ? 8 : 4;
  vtu_ctx ctx = {m, NULL, block_start, wide, NULL};
  int st = mx_vtu_block(f, isz * (uint64_t)nconn, m->ncells, 64, fill_conn, &ctx);
  if (st == MX_OK)
    st = mx_vtu_block(f, isz * (uint64_t)m->ncells, m->ncells, 8, fill_offsets, &ctx);
  if (st == MX_OK) st = mx_vtu_block(f, (uint64_t)m->ncells, m->ncells, 1, fill_types, &ctx);
  mx_free(block_start);
  return st;
}

static int write_body(mx_afile *f, const mx_mesh_view *m, const mx_vtu_extra *x) {
  size_t nconn = conn_length(m);
  MX_CHECK(xml_header(f, m, nconn, x));
  MX_CHECK(write_fields(f, m->npoint_fields, m->point_fields, m->nnodes, NULL, x->fixed_types));
  if (x->ids)
    MX_CHECK(mx_vtu_block(f, 8 * (uint64_t)m->nnodes, m->nnodes, 8, fill_ids, x->ids));
  MX_CHECK(write_fields(f, m->ncell_fields, m->cell_fields, m->ncells, m->order,
                        x->fixed_types));
  MX_CHECK(write_double_block(f, m->xyz, 3 * m->nnodes));
  MX_CHECK(write_cell_blocks(f, m, nconn));
  return mx_vtu_finish(f);
}

/* ---- a 2D view (soa/mesh.h: dim 2) ---------------------------------------
 *
 * Points Float64 x y 0, cells VTK_TRIANGLE (5) / VTK_QUAD (9), Int32 or
 * Int64 indices as for 3D; each cell field Float64 (double), UInt8 (from
 * 8-bit values) or Int32, in index order. */

typedef struct {
  const mx_mesh_view *m;
  const mx_field *fd;
  int wide;                /* Int64 indices */
  const uint64_t *qbefore; /* quadrilaterals before each OFFSET_BLOCK cells */
} plane_ctx;

static int plane_field_size(const mx_field *fd) {
  return fd->is_double ? 8 : fd->u8values ? 1 : 4;
}

static size_t fill_plane_points(const void *v, size_t b, size_t e, char *o) {
  const double *xy = ((const plane_ctx *)v)->m->xyz;
  for (size_t i = b; i < e; i++) {
    char *p = o + 24 * (i - b);
    mx_put_le_double(p, xy[2 * i]);
    mx_put_le_double(p + 8, xy[2 * i + 1]);
    mx_put_le_double(p + 16, 0.0);
  }
  return 24 * (e - b);
}

static size_t fill_plane_conn(const void *v, size_t b, size_t e, char *o) {
  const plane_ctx *x = v;
  size_t n = 0;
  for (size_t c = b; c < e; c++)
    for (int j = 0; j < mx_view_nv2(x->m, c); j++) {
      if (x->wide) mx_put_le64(o + n, x->m->conn[4 * c + j]);
      else mx_put_le32(o + n, x->m->conn[4 * c + j]);
      n += x->wide ? 8 : 4;
    }
  return n;
}

/* The end of cell c's connectivity: 3 per cell plus one per quadrilateral. */
static size_t fill_plane_offsets(const void *v, size_t b, size_t e, char *o) {
  const plane_ctx *x = v;
  uint64_t q = x->qbefore[b / OFFSET_BLOCK];
  for (size_t c = b / OFFSET_BLOCK * OFFSET_BLOCK; c < b; c++)
    q += x->m->type[c] == MX_CELL_QUAD;
  size_t n = 0;
  for (size_t c = b; c < e; c++) {
    q += x->m->type[c] == MX_CELL_QUAD;
    const uint64_t end = 3 * (uint64_t)(c + 1) + q;
    if (x->wide) mx_put_le64(o + n, end);
    else mx_put_le32(o + n, (uint32_t)end);
    n += x->wide ? 8 : 4;
  }
  return n;
}

static size_t fill_plane_types(const void *v, size_t b, size_t e, char *o) {
  const plane_ctx *x = v;
  for (size_t c = b; c < e; c++) o[c - b] = x->m->type[c] == MX_CELL_QUAD ? 9 : 5;
  return e - b;
}

static size_t fill_plane_field(const void *v, size_t b, size_t e, char *o) {
  const plane_ctx *x = v;
  const mx_field *fd = x->fd;
  const int size = plane_field_size(fd);
  size_t n = 0;
  for (size_t c = b; c < e; c++, n += (size_t)size) {
    if (size == 8) mx_put_le_double(o + n, mx_field_double(fd, c));
    else if (size == 1) o[n] = (char)fd->u8values[c];
    else mx_put_le32(o + n, (uint32_t)mx_field_int(fd, c));
  }
  return n;
}

static int plane_header(mx_afile *f, const mx_mesh_view *m, uint64_t nconn, int wide) {
  mx_vtu_head h = {0};
  mx_vtu_begin(&h, m->nnodes, m->ncells);
  mx_vtu_printf(&h, "      <CellData>\n");
  for (int k = 0; k < m->ncell_fields; k++) {
    const mx_field *fd = &m->cell_fields[k];
    const int size = plane_field_size(fd);
    mx_vtu_array(&h, size == 8 ? "Float64" : size == 1 ? "UInt8" : "Int32", fd->name, 1,
                 (uint64_t)size * m->ncells);
  }
  mx_vtu_printf(&h, "      </CellData>\n");
  return mx_vtu_end(f, &h, m->nnodes, m->ncells, nconn, wide);
}

/* Quadrilaterals before each block of OFFSET_BLOCK cells (the offsets'
 * prefix). */
static uint64_t *plane_quads_before(const mx_mesh_view *m) {
  const size_t nb = m->ncells / OFFSET_BLOCK + 1;
  uint64_t *q = mx_alloc(nb * sizeof *q);
  if (!q) return NULL;
#pragma omp parallel for schedule(static) if (nb > 16)
  for (size_t k = 0; k < nb; k++) {
    const size_t lo = k * OFFSET_BLOCK,
                 hi = lo + OFFSET_BLOCK < m->ncells ? lo + OFFSET_BLOCK : m->ncells;
    uint64_t s = 0;
    for (size_t c = lo; c < hi; c++) s += m->type[c] == MX_CELL_QUAD;
    q[k] = s;
  }
  mx_scan_u64(q, nb);
  return q;
}

static int plane_blocks(mx_afile *f, const mx_mesh_view *m, uint64_t nconn, plane_ctx *x) {
  const uint64_t nc = m->ncells, isz = x->wide ? 8 : 4;
  for (int k = 0; k < m->ncell_fields; k++) {
    x->fd = &m->cell_fields[k];
    const int size = plane_field_size(x->fd);
    MX_CHECK(mx_vtu_block(f, (uint64_t)size * nc, m->ncells, (size_t)size, fill_plane_field, x));
  }
  MX_CHECK(mx_vtu_block(f, 24 * (uint64_t)m->nnodes, m->nnodes, 24, fill_plane_points, x));
  MX_CHECK(mx_vtu_block(f, isz * nconn, m->ncells, 4 * isz, fill_plane_conn, x));
  MX_CHECK(mx_vtu_block(f, isz * nc, m->ncells, isz, fill_plane_offsets, x));
  MX_CHECK(mx_vtu_block(f, nc, m->ncells, 1, fill_plane_types, x));
  return mx_vtu_finish(f);
}

static int write_plane_body(mx_afile *f, const mx_mesh_view *m) {
  const uint64_t nconn = 3 * (uint64_t)m->ncells + mx_plane_count_quads(m);
  plane_ctx x = {.m = m, .wide = nconn > (uint64_t)INT32_MAX};
  MX_CHECK(plane_header(f, m, nconn, x.wide));
  x.qbefore = plane_quads_before(m);
  if (!x.qbefore) return MX_ENOMEM;
  const int st = plane_blocks(f, m, nconn, &x);
  mx_free((void *)x.qbefore);
  return st;
}

int mx_write_vtu_extra(const char *path, const mx_mesh_view *m, const mx_vtu_extra *x) {
  static const mx_vtu_extra none = {NULL, NULL, 0};
  MX_CHECK(mx_mesh_view_check(path, m));
  mx_afile f;
  MX_CHECK(mx_afile_open(&f, path));
  if (mx_view_is_2d(m)) return mx_afile_finish(&f, write_plane_body(&f, m));
  return mx_afile_finish(&f, write_body(&f, m, x ? x : &none));
}

int mx_write_vtu(const char *path, const mx_mesh_view *m) {
  return mx_write_vtu_extra(path, m, NULL);
}
