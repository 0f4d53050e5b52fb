/* mixoct: VTK XML UnstructuredGrid writer (.vtu), version 1.0, UInt64
 * headers, little-endian raw appended data (the layout and what it shares
 * with the 2D writer: io/vtu_common.h).
 *
 * On a little-endian host coordinates and fields are copied straight from
 * the mesh arrays into the output chunks; connectivity, offsets and types are converted in
 * parallel in place in them (io/atomic_file.h: a background thread writes
 * one chunk while the next is filled). mx_write_vtu_extra adds what a
 * piece of a .pvtu needs (io/vtu_common.h, io/write_pvtu.c). */
#include <stdint.h>
#include <string.h>

#include "base/common.h"
#include "io/atomic_file.h"
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

int mx_write_vtu_extra(const char *path, const mx_mesh_view *m, const mx_vtu_extra *x) {
  static const mx_vtu_extra none = {NULL, NULL, 0};
  MX_CHECK(mx_mesh_view_check(path, m));
  mx_afile f;
  MX_CHECK(mx_afile_open(&f, path));
  return mx_afile_finish(&f, write_body(&f, m, x ? x : &none));
}

int mx_write_vtu(const char *path, const mx_mesh_view *m) {
  return mx_write_vtu_extra(path, m, NULL);
}
