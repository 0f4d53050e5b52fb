/* mixoct: Medit / Gamma Mesh Format writer, .mesh (ASCII) and .meshb
 * (binary), with the boundary triangles and quadrilaterals.
 *
 * Format (libMeshb documentation, "The libMeshb library", L. Marechal,
 * INRIA; keyword codes from enum GmfKwdCod in libmeshb7.h):
 *   - ASCII: "MeshVersionFormatted 2", "Dimension 3", then keywords, each
 *     followed by its number of lines and the lines; "End" closes the file.
 *     Vertices are "x y z ref"; elements are their 1-based vertex indices
 *     followed by a reference. Version 2 means double precision reals.
 *   - Binary: int32 1 (the endianness word, written natively), int32
 *     version, then keyword blocks: int32 keyword code, the absolute file
 *     position of the next block (int32 for versions 1-2, int64 from version
 *     3 on), int32 line count (Dimension has its int32 value instead), the
 *     lines as raw numbers (reals are float64 from version 2 on, integers
 *     int32 up to version 3), and a last block "End" with position 0.
 *     Version 2 is written, or version 3 when the file passes 2 GiB.
 *   - Codes used: Dimension 3, Vertices 4, Triangles 6, Quadrilaterals 7,
 *     Tetrahedra 8, Prisms 9, Hexahedra 10, Pyramids 49, End 54.
 *
 * Vertex order and orientation of the elements. Medit's convention is the
 * one of P.-L. George ("Generation automatique de maillages", Masson 1994,
 * p. 24, as restated in rheolef's reference-element pages): the trihedron
 * of the edges leaving vertex 0 is direct and every face seen from outside
 * is counter-clockwise:
 *   - tetrahedron: det(p1-p0, p2-p0, p3-p0) > 0 (Mmg, MMG5_orvol, reorients
 *     the others on reading);
 *   - prism: triangle 0-1-2, triangle 3-4-5 above it with 3 over 0,
 *     (01, 02, 03) direct (rheolef prism; NASA refine writes its prisms to
 *     .meshb unchanged and builds them so that 0-1-2 turns around 0-3);
 *   - pyramid: "square basis is 0-1-2-3 (oriented counter clockwise like
 *     trias) and top vertex is 4" (NASA refine, ref_export.c, which maps its
 *     UGRID pyramids to .meshb and to VTK by two permutations that differ
 *     only by a rotation of the base);
 *   - hexahedron: 0-1-2-3 bottom, 4-5-6-7 above them, (01, 03, 04) direct
 *     (libMeshb's Q1/Q2 hexahedron ordering: (0,0,0) (1,0,0) (1,1,0)
 *     (0,1,0) (0,0,1) ...).
 * The library's node orders (soa/mesh.h, whose outward face tables start
 * with 0-2-1, 0-3-2-1, 0-2-1 and 0-3-2-1: the base turns towards the rest
 * of the element) are these same orders with the same orientation, so
 * medit_order below is the identity; it is kept as a table so that the
 * correspondence stays explicit in one place.
 * Boundary faces (io/boundary_faces.h) are written oriented outward.
 *
 * References: vertices 0; elements and boundary faces 1. Medit references
 * are subdomain and boundary numbers (Mmg treats a face between elements of
 * different references as a boundary), so the octree level is not used.
 *
 * Every block is produced in parallel chunks by mx_afile_emit: the bytes do
 * not depend on the number of threads. ASCII reals are written with 17
 * significant digits (15 when those read back to the same double). */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "common.h"
#include "io/atomic_file.h"
#include "io/boundary_faces.h"
#include "soa/mesh.h"

enum {
  KW_DIMENSION = 3,
  KW_VERTICES = 4,
  KW_TRIANGLES = 6,
  KW_QUADRILATERALS = 7,
  KW_TETRAHEDRA = 8,
  KW_PRISMS = 9,
  KW_HEXAHEDRA = 10,
  KW_PYRAMIDS = 49,
  KW_END = 54,
  REAL_MAX_CHARS = 25, /* longest real written, with its separator */
  TYPE_CHUNK = 65536,  /* cells per chunk when grouping them by type */
};

static const int32_t VERTEX_REF = 0, ELEMENT_REF = 1, FACE_REF = 1;

/* medit_order[t][j]: the index in the library's row (soa/mesh.h) of Medit
 * vertex j of type t. */
static const int8_t medit_order[4][8] = {{0, 1, 2, 3},
                                         {0, 1, 2, 3, 4},
                                         {0, 1, 2, 3, 4, 5},
                                         {0, 1, 2, 3, 4, 5, 6, 7}};

static const char *const type_keyword_name[4] = {"Tetrahedra", "Pyramids",
                                                 "Prisms", "Hexahedra"};
static const int type_keyword_code[4] = {KW_TETRAHEDRA, KW_PYRAMIDS, KW_PRISMS,
                                         KW_HEXAHEDRA};

typedef struct {
  const mx_mesh_view *m;
  const uint32_t *cells; /* the cells of one type, in index order */
  int type;
  const uint32_t *faces; /* boundary faces of one size */
  int face_size;
} medit_ctx;

/* ---- numbers as text ------------------------------------------------------
 */

static size_t put_u64(char *out, uint64_t v) {
  char tmp[24];
  size_t n = 0;
  do {
    tmp[n++] = (char)('0' + v % 10);
    v /= 10;
  } while (v);
  for (size_t i = 0; i < n; i++) out[i] = tmp[n - 1 - i];
  return n;
}

static size_t put_i32(char *out, int32_t v) {
  if (v >= 0) return put_u64(out, (uint64_t)v);
  out[0] = '-';
  return 1 + put_u64(out + 1, (uint64_t)(-(int64_t)v));
}

/* 5^k for k <= 27 (5^27 < 2^63), and the exact doubles 10^k, k <= 22. */
static const uint64_t pow5[28] = {1ULL,
                                  5ULL,
                                  25ULL,
                                  125ULL,
                                  625ULL,
                                  3125ULL,
                                  15625ULL,
                                  78125ULL,
                                  390625ULL,
                                  1953125ULL,
                                  9765625ULL,
                                  48828125ULL,
                                  244140625ULL,
                                  1220703125ULL,
                                  6103515625ULL,
                                  30517578125ULL,
                                  152587890625ULL,
                                  762939453125ULL,
                                  3814697265625ULL,
                                  19073486328125ULL,
                                  95367431640625ULL,
                                  476837158203125ULL,
                                  2384185791015625ULL,
                                  11920928955078125ULL,
                                  59604644775390625ULL,
                                  298023223876953125ULL,
                                  1490116119384765625ULL,
                                  7450580596923828125ULL};
static const double pow10_d[23] = {
    1e0,  1e1,  1e2,  1e3,  1e4,  1e5,  1e6,  1e7,  1e8,  1e9,  1e10, 1e11,
    1e12, 1e13, 1e14, 1e15, 1e16, 1e17, 1e18, 1e19, 1e20, 1e21, 1e22};

/* round(ax * 10^k) exactly, for finite ax > 0, |k| <= 27 and a result
 * below 2^63. With ax = m 2^e and 10^k = 5^k 2^k the product is an
 * integer times a power of two: m 5^k (at most 116 bits) shifted, or, for
 * k < 0, m 2^(e+k) divided by 5^-k; both fit in 128 bits here. Halves
 * round up (they cannot occur in the division: 5^-k is odd). */
static uint64_t scaled_digits(double ax, int k) {
  uint64_t bits;
  memcpy(&bits, &ax, 8);
  const int be = (int)((bits >> 52) & 0x7ff);
  uint64_t m = bits & ((1ULL << 52) - 1);
  int e = -1074;
  if (be) {
    m |= 1ULL << 52;
    e = be - 1075;
  }
  if (k >= 0) {
    const unsigned __int128 p = (unsigned __int128)m * pow5[k];
    int s = e + k;
    if (s >= 0) return s >= 64 ? UINT64_MAX : (uint64_t)(p << s);
    s = -s;
    if (s > 120) return 0;
    const unsigned __int128 half = (unsigned __int128)1 << (s - 1);
    return (uint64_t)((p + half) >> s);
  }
  const uint64_t q = pow5[-k];
  const int s = e + k;
  if (s >= 0) {
    if (s > 70) return UINT64_MAX;
    const unsigned __int128 num = (unsigned __int128)m << s;
    return (uint64_t)((num + q / 2) / q);
  }
  if (-s > 60) return 0;
  const unsigned __int128 den = (unsigned __int128)q << -s;
  return (uint64_t)(((unsigned __int128)m + den / 2) / den);
}

/* The decimal digits[0..ndig) times 10^(E - ndig + 1), formatted like %g. */
static size_t put_digits(char *out, const char *dig, int ndig, int E) {
  size_t n = 0;
  if (E >= 0 && E < 17) {
    for (int i = 0; i <= E; i++) out[n++] = i < ndig ? dig[i] : '0';
    if (ndig > E + 1) {
      out[n++] = '.';
      for (int i = E + 1; i < ndig; i++) out[n++] = dig[i];
    }
  } else if (E < 0 && E >= -5) {
    out[n++] = '0';
    out[n++] = '.';
    for (int i = -1; i > E; i--) out[n++] = '0';
    for (int i = 0; i < ndig; i++) out[n++] = dig[i];
  } else {
    out[n++] = dig[0];
    if (ndig > 1) {
      out[n++] = '.';
      for (int i = 1; i < ndig; i++) out[n++] = dig[i];
    }
    out[n++] = 'e';
    out[n++] = E < 0 ? '-' : '+';
    int a = E < 0 ? -E : E;
    if (a < 10) out[n++] = '0';
    n += put_u64(out + n, (uint64_t)a);
  }
  return n;
}

/* Out of the tables' range: %.15g when it reads back, else %.17g. */
static size_t put_real_slow(char *out, double x) {
  char tmp[32];
  int n = snprintf(tmp, sizeof tmp, "%.15g", x);
  if (strtod(tmp, NULL) != x || !isfinite(x))
    n = snprintf(tmp, sizeof tmp, "%.17g", x);
  memcpy(out, tmp, (size_t)n);
  return (size_t)n;
}

/* A real that reads back to the same double, at most 24 characters.
 *
 * D = round(|x| * 10^(16-E)), computed exactly, has 17 digits and lies
 * within half a unit of its last digit from |x|; one such unit is below
 * 2^53 / 10^16 = 0.9008 ulp of x, so D * 10^(E-16) is within 0.46 ulp of x
 * and reads back as x. When
 * D rounded to 15 digits, times the power of ten, gives x in double
 * arithmetic (exact operands, one correctly rounded operation: what strtod
 * returns for that decimal), the 15 digits are written instead, so 0.1 is
 * "0.1". Out of the range of the tables, snprintf and strtod are used. */
static size_t put_real(char *out, double x) {
  if (x == 0.0) {
    out[0] = '0';
    return 1;
  }
  if (!isfinite(x)) return put_real_slow(out, x);
  size_t n = 0;
  if (x < 0) out[n++] = '-';
  const double ax = fabs(x);
  int e2;
  frexp(ax, &e2);                                     /* 2^(e2-1) <= ax */
  int E = (int)floor((e2 - 1) * 0.30102999566398120); /* <= floor(log10) */
  uint64_t D = 0;
  for (int tries = 0;; tries++) {
    const int k = 16 - E;
    if (k < -27 || k > 27 || tries == 3) return put_real_slow(out, x);
    D = scaled_digits(ax, k);
    if (D >= 100000000000000000ULL)
      E++;
    else if (D < 10000000000000000ULL)
      E--;
    else
      break;
  }
  /* try 15 digits */
  uint64_t D15 = (D + 50) / 100;
  int E15 = E;
  if (D15 >= 1000000000000000ULL) {
    D15 /= 10;
    E15++;
  }
  const int p = E15 - 14;
  int use15 = 0;
  if (p >= -22 && p <= 22) {
    const double v =
        p >= 0 ? (double)D15 * pow10_d[p] : (double)D15 / pow10_d[-p];
    use15 = v == ax;
  }
  char dig[20];
  int ndig;
  if (use15) {
    D = D15;
    E = E15;
    ndig = 15;
  } else {
    ndig = 17;
  }
  for (int i = ndig - 1; i >= 0; i--) {
    dig[i] = (char)('0' + D % 10);
    D /= 10;
  }
  while (ndig > 1 && dig[ndig - 1] == '0') ndig--;
  return n + put_digits(out + n, dig, ndig, E);
}

/* ---- fill functions --------------------------------------------------------
 */

static size_t fill_vertices_ascii(const void *vctx, size_t b, size_t e,
                                  char *out) {
  const double *xyz = ((const medit_ctx *)vctx)->m->xyz;
  size_t n = 0;
  for (size_t i = b; i < e; i++) {
    for (int d = 0; d < 3; d++) {
      n += put_real(out + n, xyz[3 * i + d]);
      out[n++] = ' ';
    }
    n += put_i32(out + n, VERTEX_REF);
    out[n++] = '\n';
  }
  return n;
}

static size_t fill_vertices_bin(const void *vctx, size_t b, size_t e,
                                char *out) {
  const double *xyz = ((const medit_ctx *)vctx)->m->xyz;
  size_t n = 0;
  for (size_t i = b; i < e; i++) {
    memcpy(out + n, xyz + 3 * i, 24);
    memcpy(out + n + 24, &VERTEX_REF, 4);
    n += 28;
  }
  return n;
}

static size_t fill_cells_ascii(const void *vctx, size_t b, size_t e,
                               char *out) {
  const medit_ctx *ctx = vctx;
  const int t = ctx->type, nv = mx_cell_nodes[t];
  size_t n = 0;
  for (size_t i = b; i < e; i++) {
    const uint32_t *row = ctx->m->conn + 8 * (size_t)ctx->cells[i];
    for (int j = 0; j < nv; j++) {
      n += put_u64(out + n, (uint64_t)row[medit_order[t][j]] + 1);
      out[n++] = ' ';
    }
    n += put_i32(out + n, ELEMENT_REF);
    out[n++] = '\n';
  }
  return n;
}

static size_t fill_cells_bin(const void *vctx, size_t b, size_t e, char *out) {
  const medit_ctx *ctx = vctx;
  const int t = ctx->type, nv = mx_cell_nodes[t];
  size_t n = 0;
  for (size_t i = b; i < e; i++) {
    const uint32_t *row = ctx->m->conn + 8 * (size_t)ctx->cells[i];
    for (int j = 0; j < nv; j++, n += 4) {
      const int32_t v = (int32_t)(row[medit_order[t][j]] + 1);
      memcpy(out + n, &v, 4);
    }
    memcpy(out + n, &ELEMENT_REF, 4);
    n += 4;
  }
  return n;
}

static size_t fill_faces_ascii(const void *vctx, size_t b, size_t e,
                               char *out) {
  const medit_ctx *ctx = vctx;
  const int k = ctx->face_size;
  size_t n = 0;
  for (size_t i = b; i < e; i++) {
    for (int j = 0; j < k; j++) {
      n += put_u64(out + n, (uint64_t)ctx->faces[(size_t)k * i + j] + 1);
      out[n++] = ' ';
    }
    n += put_i32(out + n, FACE_REF);
    out[n++] = '\n';
  }
  return n;
}

static size_t fill_faces_bin(const void *vctx, size_t b, size_t e, char *out) {
  const medit_ctx *ctx = vctx;
  const int k = ctx->face_size;
  size_t n = 0;
  for (size_t i = b; i < e; i++) {
    for (int j = 0; j < k; j++, n += 4) {
      const int32_t v = (int32_t)(ctx->faces[(size_t)k * i + j] + 1);
      memcpy(out + n, &v, 4);
    }
    memcpy(out + n, &FACE_REF, 4);
    n += 4;
  }
  return n;
}

/* ---- the cells grouped by type ----------------------------------------------
 */

/* cells = every cell index, those of type 0 first, then 1, 2, 3, each group
 * in index order; first[t] where group t starts, count[t] its size. */
static int cells_by_type(const mx_mesh_view *m, uint32_t **cells_out,
                         size_t first[4], size_t count[4]) {
  const size_t nc = m->ncells;
  const size_t nchunks = (nc + TYPE_CHUNK - 1) / TYPE_CHUNK;
  size_t *at = mx_calloc((4 * nchunks + 1) * sizeof *at);
  uint32_t *cells = mx_alloc((nc ? nc : 1) * sizeof *cells);
  if (!at || !cells) {
    mx_free(at);
    mx_free(cells);
    return MX_EINPUT;
  }
#pragma omp parallel for schedule(static)
  for (size_t k = 0; k < nchunks; k++) {
    const size_t c1 = (k + 1) * TYPE_CHUNK < nc ? (k + 1) * TYPE_CHUNK : nc;
    size_t cnt[4] = {0, 0, 0, 0};
    for (size_t c = k * TYPE_CHUNK; c < c1; c++) cnt[m->type[c]]++;
    for (int t = 0; t < 4; t++) at[4 * k + (size_t)t] = cnt[t];
  }
  size_t pos = 0;
  for (int t = 0; t < 4; t++) {
    first[t] = pos;
    for (size_t k = 0; k < nchunks; k++) {
      const size_t cnt = at[4 * k + (size_t)t];
      at[4 * k + (size_t)t] = pos;
      pos += cnt;
    }
    count[t] = pos - first[t];
  }
#pragma omp parallel for schedule(static)
  for (size_t k = 0; k < nchunks; k++) {
    const size_t c1 = (k + 1) * TYPE_CHUNK < nc ? (k + 1) * TYPE_CHUNK : nc;
    size_t p[4];
    for (int t = 0; t < 4; t++) p[t] = at[4 * k + (size_t)t];
    for (size_t c = k * TYPE_CHUNK; c < c1; c++)
      cells[p[m->type[c]]++] = (uint32_t)c;
  }
  mx_free(at);
  *cells_out = cells;
  return MX_OK;
}

/* ---- file layout ------------------------------------------------------------
 */

typedef struct {
  const mx_mesh_view *m;
  const mx_boundary_faces *bf;
  const uint32_t *cells;
  size_t first[4], count[4];
} medit_data;

/* The keywords written, in order, with their line counts and binary line
 * sizes (Vertices, the four volume types, Triangles, Quadrilaterals; empty
 * ones other than Vertices are skipped). */
typedef struct {
  int code;
  const char *name;
  size_t lines;
  size_t line_bytes;
} section;

static int list_sections(const medit_data *d, section s[7]) {
  int ns = 0;
  s[ns++] = (section){KW_VERTICES, "Vertices", d->m->nnodes, 3 * 8 + 4};
  for (int t = 0; t < 4; t++) {
    if (d->count[t] == 0) continue;
    s[ns++] = (section){type_keyword_code[t], type_keyword_name[t], d->count[t],
                        4 * (size_t)(mx_cell_nodes[t] + 1)};
  }
  if (d->bf->ntri)
    s[ns++] = (section){KW_TRIANGLES, "Triangles", d->bf->ntri, 4 * 4};
  if (d->bf->nquad)
    s[ns++] =
        (section){KW_QUADRILATERALS, "Quadrilaterals", d->bf->nquad, 5 * 4};
  return ns;
}

static int emit_section(mx_afile *f, const medit_data *d, const section *s,
                        int binary) {
  medit_ctx ctx = {d->m, NULL, 0, NULL, 0};
  switch (s->code) {
    case KW_VERTICES:
      return binary ? mx_afile_emit(f, s->lines, 28, fill_vertices_bin, &ctx)
                    : mx_afile_emit(f, s->lines, 3 * REAL_MAX_CHARS + 8,
                                    fill_vertices_ascii, &ctx);
    case KW_TRIANGLES:
    case KW_QUADRILATERALS:
      ctx.face_size = s->code == KW_TRIANGLES ? 3 : 4;
      ctx.faces = s->code == KW_TRIANGLES ? d->bf->tri : d->bf->quad;
      return binary
                 ? mx_afile_emit(f, s->lines, s->line_bytes, fill_faces_bin,
                                 &ctx)
                 : mx_afile_emit(f, s->lines, 5 * 12, fill_faces_ascii, &ctx);
    default:
      for (int t = 0; t < 4; t++) {
        if (type_keyword_code[t] != s->code) continue;
        ctx.type = t;
        ctx.cells = d->cells + d->first[t];
        return binary
                   ? mx_afile_emit(f, s->lines, s->line_bytes, fill_cells_bin,
                                   &ctx)
                   : mx_afile_emit(f, s->lines, 9 * 12, fill_cells_ascii, &ctx);
      }
      return MX_EINTERNAL;
  }
}

static int write_ascii(mx_afile *f, const medit_data *d) {
  section s[7];
  const int ns = list_sections(d, s);
  MX_CHECK(mx_afile_printf(f, "MeshVersionFormatted 2\n\nDimension 3\n"));
  for (int i = 0; i < ns; i++) {
    MX_CHECK(mx_afile_printf(f, "\n%s\n%zu\n", s[i].name, s[i].lines));
    MX_CHECK(emit_section(f, d, &s[i], 0));
  }
  return mx_afile_printf(f, "\nEnd\n");
}

static int put_header_int(mx_afile *f, int64_t v, int bytes) {
  if (bytes == 8) return mx_afile_write(f, &v, 8);
  const int32_t w = (int32_t)v;
  return mx_afile_write(f, &w, 4);
}

static int write_binary(mx_afile *f, const medit_data *d, const char *path) {
  section s[7];
  const int ns = list_sections(d, s);
  /* total size with 4-byte positions decides the version */
  uint64_t total = 8 + 12 + 8;
  for (int i = 0; i < ns; i++)
    total += 12 + (uint64_t)s[i].lines * s[i].line_bytes;
  const int version = total > (uint64_t)INT32_MAX ? 3 : 2;
  const int pos_bytes = version >= 3 ? 8 : 4;
  for (int i = 0; i < ns; i++) {
    if (s[i].lines > (size_t)INT32_MAX) {
      mx_error(path, 0, "%zu %s are too many for a Medit file (32-bit counts)",
               s[i].lines, s[i].name);
      return MX_EINPUT;
    }
  }
  const int32_t head[2] = {1, version};
  MX_CHECK(mx_afile_write(f, head, sizeof head));
  uint64_t pos = 8;
  const int32_t dim_code = KW_DIMENSION, dim = 3;
  pos += 4 + (uint64_t)pos_bytes + 4;
  MX_CHECK(mx_afile_write(f, &dim_code, 4));
  MX_CHECK(put_header_int(f, (int64_t)pos, pos_bytes));
  MX_CHECK(mx_afile_write(f, &dim, 4));
  for (int i = 0; i < ns; i++) {
    const int32_t code = s[i].code, lines = (int32_t)s[i].lines;
    pos += 4 + (uint64_t)pos_bytes + 4 + (uint64_t)s[i].lines * s[i].line_bytes;
    MX_CHECK(mx_afile_write(f, &code, 4));
    MX_CHECK(put_header_int(f, (int64_t)pos, pos_bytes));
    MX_CHECK(mx_afile_write(f, &lines, 4));
    MX_CHECK(emit_section(f, d, &s[i], 1));
  }
  const int32_t end_code = KW_END;
  MX_CHECK(mx_afile_write(f, &end_code, 4));
  return put_header_int(f, 0, pos_bytes);
}

int mx_write_medit(const char *path, const mx_mesh_view *m, int binary) {
  MX_CHECK(mx_mesh_view_check(path, m));
  if (m->nnodes >= (size_t)INT32_MAX) {
    mx_error(path, 0,
             "%zu nodes are too many for a Medit file (32-bit indices)",
             m->nnodes);
    return MX_EINPUT;
  }
  medit_data d;
  memset(&d, 0, sizeof d);
  d.m = m;
  mx_boundary_faces bf;
  int st = mx_boundary_faces_extract(m, &bf);
  if (st != MX_OK) {
    mx_error(path, 0, "cannot extract the boundary faces");
    return st;
  }
  d.bf = &bf;
  uint32_t *cells = NULL;
  st = cells_by_type(m, &cells, d.first, d.count);
  d.cells = cells;
  mx_afile f;
  if (st == MX_OK)
    st = mx_afile_open(&f, path);
  else
    mx_error(path, 0, "out of memory");
  if (st == MX_OK) {
    st = binary ? write_binary(&f, &d, path) : write_ascii(&f, &d);
    if (st == MX_OK)
      st = mx_afile_commit(&f);
    else
      mx_afile_abort(&f);
  }
  mx_free(cells);
  mx_boundary_faces_free(&bf);
  return st;
}
