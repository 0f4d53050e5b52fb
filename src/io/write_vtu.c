/* mixoct: VTK XML UnstructuredGrid writer (.vtu), version 1.0, UInt64
 * headers, little-endian raw appended data.
 *
 * Every DataArray is format="appended"; the blocks follow "_" in
 * <AppendedData encoding="raw">, each preceded by its byte count as a
 * UInt64, in the order their DataArray elements appear. On a little-endian
 * host coordinates and fields are copied straight from the mesh arrays into
 * the output chunks; connectivity, offsets and types are converted in
 * parallel in place in them (io/atomic_file.h: a background thread writes
 * one chunk while the next is filled). */
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "common.h"
#include "io/atomic_file.h"
#include "soa/mesh.h"
#include "soa/scan.h"

#define VTU_HOST_LE (__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__)

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

/* ---- little-endian stores ------------------------------------------------ */

static inline void put_le32(char *out, uint32_t v) {
#if !VTU_HOST_LE
  v = __builtin_bswap32(v);
#endif
  memcpy(out, &v, 4);
}

static inline void put_le64(char *out, uint64_t v) {
#if !VTU_HOST_LE
  v = __builtin_bswap64(v);
#endif
  memcpy(out, &v, 8);
}

static inline void put_le_double(char *out, double d) {
  uint64_t v;
  memcpy(&v, &d, 8);
  put_le64(out, v);
}

/* ---- a growable string for the XML header -------------------------------- */

typedef struct {
  char *s;
  size_t len, cap;
  int failed;
} strbuf;

static void sb_grow(strbuf *b, size_t need) {
  if (b->failed || b->len + need + 1 <= b->cap) return;
  size_t cap = b->cap ? b->cap : 4096;
  while (cap < b->len + need + 1) cap *= 2;
  char *s = mx_realloc(b->s, cap);
  if (!s) {
    b->failed = 1;
    return;
  }
  b->s = s;
  b->cap = cap;
}

static void sb_printf(strbuf *b, const char *fmt, ...)
    __attribute__((format(printf, 2, 3)));
static void sb_printf(strbuf *b, const char *fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  int n = vsnprintf(NULL, 0, fmt, ap);
  va_end(ap);
  if (n < 0) {
    b->failed = 1;
    return;
  }
  sb_grow(b, (size_t)n);
  if (b->failed) return;
  va_start(ap, fmt);
  vsnprintf(b->s + b->len, (size_t)n + 1, fmt, ap);
  va_end(ap);
  b->len += (size_t)n;
}

/* Appends name with the XML special characters escaped. */
static void sb_xml_name(strbuf *b, const char *name) {
  for (const char *p = name; *p; p++) {
    switch (*p) {
      case '&':
        sb_printf(b, "&amp;");
        break;
      case '<':
        sb_printf(b, "&lt;");
        break;
      case '>':
        sb_printf(b, "&gt;");
        break;
      case '"':
        sb_printf(b, "&quot;");
        break;
      default:
        sb_printf(b, "%c", *p);
    }
  }
}

/* ---- header -------------------------------------------------------------- */

static size_t conn_length(const mx_mesh_view *m) {
  size_t total = 0;
#pragma omp parallel for reduction(+ : total) schedule(static) \
    if (m->ncells > 65536)
  for (size_t c = 0; c < m->ncells; c++)
    total += (size_t)mx_cell_nodes[m->type[c]];
  return total;
}

/* One DataArray element; advances *offset past its appended block. */
static void xml_array(strbuf *b, const char *type, const char *name, int ncomp,
                      uint64_t *offset, uint64_t data_bytes) {
  sb_printf(b, "        <DataArray type=\"%s\" Name=\"", type);
  sb_xml_name(b, name);
  sb_printf(b, "\"");
  if (ncomp > 1) sb_printf(b, " NumberOfComponents=\"%d\"", ncomp);
  sb_printf(b, " format=\"appended\" offset=\"%llu\"/>\n",
            (unsigned long long)*offset);
  *offset += 8 + data_bytes;
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

static void xml_fields(strbuf *b, const char *tag, int nfields,
                       const mx_field *fields, size_t count, uint64_t *offset) {
  sb_printf(b, "      <%s>\n", tag);
  for (int i = 0; i < nfields; i++) {
    const mx_field *fd = &fields[i];
    const int u8 = fits_u8(fd, count);
    xml_array(b, fd->is_double ? "Float64" : u8 ? "UInt8" : "Int32", fd->name, 1, offset,
              (uint64_t)count * (fd->is_double ? 8 : u8 ? 1 : 4));
  }
  sb_printf(b, "      </%s>\n", tag);
}

static size_t fill_u8(const void *vctx, size_t b, size_t e, char *out);

/* Int64 indices only when Int32 cannot hold them (smaller, faster files). */
static int needs_wide(const mx_mesh_view *m, size_t nconn) {
  return nconn > (size_t)INT32_MAX || m->nnodes > (size_t)INT32_MAX;
}

static void xml_header(strbuf *b, const mx_mesh_view *m, size_t nconn) {
  const int wide = needs_wide(m, nconn);
  uint64_t off = 0;
  sb_printf(b,
            "<?xml version=\"1.0\"?>\n"
            "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" "
            "byte_order=\"LittleEndian\" header_type=\"UInt64\">\n"
            "  <UnstructuredGrid>\n"
            "    <Piece NumberOfPoints=\"%zu\" NumberOfCells=\"%zu\">\n",
            m->nnodes, m->ncells);
  xml_fields(b, "PointData", m->npoint_fields, m->point_fields, m->nnodes,
             &off);
  xml_fields(b, "CellData", m->ncell_fields, m->cell_fields, m->ncells, &off);
  sb_printf(b, "      <Points>\n");
  xml_array(b, "Float64", "Points", 3, &off, 24 * (uint64_t)m->nnodes);
  sb_printf(b, "      </Points>\n      <Cells>\n");
  const char *it = wide ? "Int64" : "Int32";
  const uint64_t isz = wide ? 8 : 4;
  xml_array(b, it, "connectivity", 1, &off, isz * (uint64_t)nconn);
  xml_array(b, it, "offsets", 1, &off, isz * (uint64_t)m->ncells);
  xml_array(b, "UInt8", "types", 1, &off, (uint64_t)m->ncells);
  sb_printf(b,
            "      </Cells>\n    </Piece>\n  </UnstructuredGrid>\n"
            "  <AppendedData encoding=\"raw\">\n   _");
}

/* ---- appended blocks ----------------------------------------------------- */

#if !VTU_HOST_LE
static size_t fill_doubles(const void *vctx, size_t b, size_t e, char *out) {
  const double *v = ((const vtu_ctx *)vctx)->fd->dvalues;
  size_t n = 0;
  for (size_t i = b; i < e; i++, n += 8) put_le_double(out + n, v[i]);
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
      for (int j = 0; j < nn; j++, n += 8) put_le64(out + n, row[ord[j]]);
    else
      for (int j = 0; j < nn; j++, n += 4) put_le32(out + n, row[ord[j]]);
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
      put_le64(out + n, end);
      n += 8;
    } else {
      put_le32(out + n, (uint32_t)end);
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

static int write_count(mx_afile *f, uint64_t bytes) {
  char head[8];
  put_le64(head, bytes);
  return mx_afile_write(f, head, 8);
}

/* A block of doubles (ncomp per item): straight from memory when the host
 * is little-endian, converted otherwise. */
static int write_double_block(mx_afile *f, const double *v, size_t count) {
  MX_CHECK(write_count(f, 8 * (uint64_t)count));
#if VTU_HOST_LE
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
    for (size_t i = b; i < e; i++, n += 8) put_le_double(out + n, fd->dvalues[item(c, i)]);
  } else {
    for (size_t i = b; i < e; i++, n += 8)
      put_le_double(out + n, (double)fd->fvalues[item(c, i)]);
  }
  return n;
}

static size_t fill_ints_gather(const void *vctx, size_t b, size_t e, char *out) {
  const vtu_ctx *c = vctx;
  size_t n = 0;
  for (size_t i = b; i < e; i++, n += 4) put_le32(out + n, (uint32_t)mx_field_int(c->fd, item(c, i)));
  return n;
}

/* Float64, UInt8 or Int32, as xml_fields declared it. Only an int32 or
 * double source in index order is copied straight from memory. */
static int write_field_block(mx_afile *f, const mx_field *fd, size_t count,
                             const uint32_t *order) {
  vtu_ctx gctx = {NULL, fd, NULL, 0, order};
  if (fd->is_double && fd->dvalues && !order) return write_double_block(f, fd->dvalues, count);
  if (fd->is_double) {
    MX_CHECK(write_count(f, 8 * (uint64_t)count));
    return mx_afile_emit(f, count, 8, fill_doubles_gather, &gctx);
  }
  if (fits_u8(fd, count)) {
    MX_CHECK(write_count(f, (uint64_t)count));
    return mx_afile_emit(f, count, 1, fill_u8, &gctx);
  }
  MX_CHECK(write_count(f, 4 * (uint64_t)count));
#if VTU_HOST_LE
  if (!order) return mx_afile_write(f, fd->ivalues, 4 * count);
#endif
  return mx_afile_emit(f, count, 4, fill_ints_gather, &gctx);
}

static int write_fields(mx_afile *f, int nfields, const mx_field *fields,
                        size_t count, const uint32_t *order) {
  for (int i = 0; i < nfields; i++) {
    MX_CHECK(write_field_block(f, &fields[i], count, order));
  }
  return MX_OK;
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
  if (!block_start) return MX_EINPUT;
  const int wide = needs_wide(m, nconn);
  const uint64_t isz = wide ? 8 : 4;
  vtu_ctx ctx = {m, NULL, block_start, wide, NULL};
  int st = write_count(f, isz * (uint64_t)nconn);
  if (st == MX_OK) st = mx_afile_emit(f, m->ncells, 64, fill_conn, &ctx);
  if (st == MX_OK) st = write_count(f, isz * (uint64_t)m->ncells);
  if (st == MX_OK) st = mx_afile_emit(f, m->ncells, 8, fill_offsets, &ctx);
  if (st == MX_OK) st = write_count(f, (uint64_t)m->ncells);
  if (st == MX_OK) st = mx_afile_emit(f, m->ncells, 1, fill_types, &ctx);
  mx_free(block_start);
  return st;
}

static int write_body(mx_afile *f, const mx_mesh_view *m) {
  size_t nconn = conn_length(m);
  strbuf head = {0};
  xml_header(&head, m, nconn);
  int st = head.failed ? MX_EINPUT : mx_afile_write(f, head.s, head.len);
  mx_free(head.s);
  MX_CHECK(st);
  MX_CHECK(write_fields(f, m->npoint_fields, m->point_fields, m->nnodes, NULL));
  MX_CHECK(write_fields(f, m->ncell_fields, m->cell_fields, m->ncells, m->order));
  MX_CHECK(write_double_block(f, m->xyz, 3 * m->nnodes));
  MX_CHECK(write_cell_blocks(f, m, nconn));
  static const char tail[] = "\n  </AppendedData>\n</VTKFile>\n";
  return mx_afile_write(f, tail, sizeof tail - 1);
}

int mx_write_vtu(const char *path, const mx_mesh_view *m) {
  MX_CHECK(mx_mesh_view_check(path, m));
  mx_afile f;
  MX_CHECK(mx_afile_open(&f, path));
  return mx_afile_finish(&f, write_body(&f, m));
}
