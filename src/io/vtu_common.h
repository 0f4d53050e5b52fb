/* The VTK XML UnstructuredGrid (.vtu) layout of io/write_vtu.c (3D and 2D
 * views) and the pieces of a .pvtu: version 1.0, UInt64
 * block headers, little-endian raw appended data.
 *
 * The XML header is collected in an mx_vtu_head: mx_vtu_begin (up to
 * <Piece>), the writer's own field sections with one mx_vtu_array a
 * DataArray, then mx_vtu_end (Points, Cells, the opening of AppendedData,
 * "_"), which writes it. Every DataArray is format="appended", its offset
 * the bytes of the blocks before it. The blocks follow in the order of
 * their DataArray elements, each its byte count as a UInt64 then its bytes
 * (mx_vtu_count, mx_vtu_block); mx_vtu_finish closes the file. */
#ifndef MX_VTU_COMMON_H
#define MX_VTU_COMMON_H

#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "io/atomic_file.h"
#include "soa/mesh.h"

#define MX_VTU_HOST_LE (__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__)

/* ---- little-endian stores ------------------------------------------------ */

static inline void mx_put_le32(char *out, uint32_t v) {
#if !MX_VTU_HOST_LE
  v = __builtin_bswap32(v);
#endif
  memcpy(out, &v, 4);
}

static inline void mx_put_le64(char *out, uint64_t v) {
#if !MX_VTU_HOST_LE
  v = __builtin_bswap64(v);
#endif
  memcpy(out, &v, 8);
}

static inline void mx_put_le_double(char *out, double d) {
  uint64_t v;
  memcpy(&v, &d, 8);
  mx_put_le64(out, v);
}

/* ---- the XML header ------------------------------------------------------ */

typedef struct {
  char *s; /* the text so far */
  size_t len, cap;
  int failed;      /* an allocation failed: mx_vtu_end returns MX_ENOMEM */
  uint64_t offset; /* of the next DataArray's block */
} mx_vtu_head;

void mx_vtu_printf(mx_vtu_head *h, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
/* The XML declaration, VTKFile, UnstructuredGrid and the Piece's start. */
void mx_vtu_begin(mx_vtu_head *h, size_t nnodes, size_t ncells);
/* Text with the XML special characters escaped (names in attribute
 * values; also the .pvtu master, io/write_pvtu.c). */
void mx_vtu_escaped(mx_vtu_head *h, const char *s);
/* One DataArray element (name XML-escaped, NumberOfComponents when
 * ncomp > 1) whose block holds `bytes` bytes. */
void mx_vtu_array(mx_vtu_head *h, const char *type, const char *name, int ncomp, uint64_t bytes);
/* Points (Float64 x y z) and Cells (connectivity of nconn indices and
 * offsets: Int64 when wide, else Int32; types: UInt8), the end of the XML
 * up to the appended data's "_"; writes the header to f and frees it. */
int mx_vtu_end(mx_afile *f, mx_vtu_head *h, size_t nnodes, size_t ncells, uint64_t nconn,
               int wide);

/* ---- the appended blocks ------------------------------------------------- */

/* A block's byte count. */
int mx_vtu_count(mx_afile *f, uint64_t bytes);
/* A block: its byte count, then n items of at most item_bytes each formatted
 * by fill (mx_afile_emit). */
int mx_vtu_block(mx_afile *f, uint64_t bytes, size_t n, size_t item_bytes, mx_afile_fill_fn fill,
                 const void *ctx);
/* The end of the appended data and of the file. */
int mx_vtu_finish(mx_afile *f);

/* ---- the 3D writer's extension point (io/write_vtu.c) ---------------------- */

/* What a piece of a parallel file (io/pvtu.h) adds to mx_write_vtu: an
 * Int64 point array named ids_name after the view's point fields (none when
 * ids is NULL), and, with fixed_types, integer fields typed by their source
 * alone (8-bit values UInt8, int32 values Int32): mx_write_vtu writes an
 * int32 field as UInt8 when its values fit, which differs between pieces,
 * and every piece must declare the types its .pvtu does. */
typedef struct {
  const char *ids_name;
  const uint64_t *ids;
  int fixed_types;
} mx_vtu_extra;

/* mx_write_vtu with the additions of x (NULL: none, the same bytes). */
int mx_write_vtu_extra(const char *path, const mx_mesh_view *m, const mx_vtu_extra *x);
/* The VTU type a field has with fixed_types: Float64, UInt8 or Int32. */
const char *mx_vtu_fixed_type(const mx_field *fd);

#endif
