/* mixoct: legacy VTK 3.0 writer (UNSTRUCTURED_GRID), binary or ASCII.
 *
 * Binary data is big-endian, as the legacy format requires. Numbers of both
 * kinds are produced in chunks, filled in parallel by mx_afile_emit, so the
 * file is the same byte for byte whatever the number of threads. ASCII
 * doubles are written with 17 significant digits, or 15 when those read
 * back to the same double (see put_double). */
#include <math.h>
#include <pthread.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "common.h"
#include "io/atomic_file.h"
#include "soa/mesh.h"

enum {
  NUM_MAX = 26, /* longest ASCII number incl. separator: "%.17g" is <= 24 */
  NAME_MAX_BYTES = 1024,
};

typedef struct {
  const mx_mesh_view *m;
  const mx_field *fd;
} vtk_ctx;

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

/* ---- ASCII numbers ------------------------------------------------------- */

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

static size_t put_i64(char *out, int64_t v) {
  if (v >= 0) return put_u64(out, (uint64_t)v);
  out[0] = '-';
  return 1 + put_u64(out + 1, (uint64_t)0 - (uint64_t)v);
}

/* ---- ASCII doubles -----------------------------------------------------
 *
 * x = m * 2^e is scaled by a 64-bit approximation of 10^k (relative error
 * <= 2^-64) with an exact 128-bit product and rounded to the 17-digit
 * integer D = round(x * 10^k), 10^16 <= D < 10^17. The error is below
 * 0.5 + 10^17 * 2^-64 < 0.506 units of the 17th digit, and one such unit is
 * below 0.9008 ulp of x (2^53 / 10^16), so D * 10^-k lies within 0.456 ulp
 * of x: it reads back as x, like "%.17g". When D rounded to 15 digits reads
 * back as x too (checked exactly in double arithmetic) the shorter form is
 * written, so 0.1 comes out as "0.1". */

enum { POW10_MIN = -300, POW10_MAX = 350, BIG_LIMBS = 44, BIG_SHIFT = 1280 };

typedef struct {
  uint64_t mant; /* in [2^63, 2^64) */
  int exp2;      /* 10^k ~= mant * 2^exp2 */
} pow10_entry;

static pow10_entry pow10_table[POW10_MAX - POW10_MIN + 1];
static pthread_once_t pow10_once = PTHREAD_ONCE_INIT;

/* Little-endian 32-bit limbs; value = sum limb[i] * 2^(32 i). */
typedef struct {
  uint32_t limb[BIG_LIMBS];
} bignum;

static void big_mul10(bignum *b) {
  uint64_t carry = 0;
  for (int i = 0; i < BIG_LIMBS; i++) {
    uint64_t v = (uint64_t)b->limb[i] * 10 + carry;
    b->limb[i] = (uint32_t)v;
    carry = v >> 32;
  }
}

static void big_div10(bignum *b) {
  uint64_t rem = 0;
  for (int i = BIG_LIMBS - 1; i >= 0; i--) {
    uint64_t v = (rem << 32) | b->limb[i];
    b->limb[i] = (uint32_t)(v / 10);
    rem = v % 10;
  }
}

static int big_bit(const bignum *b, int i) {
  return i < 0 ? 0 : (int)((b->limb[i / 32] >> (i % 32)) & 1);
}

/* The top 64 bits of b, rounded to nearest; b ~= mant * 2^exp2. */
static pow10_entry big_top64(const bignum *b) {
  int top = 32 * BIG_LIMBS - 1;
  while (top > 0 && !big_bit(b, top)) top--;
  uint64_t mant = 0;
  for (int i = top; i > top - 64; i--)
    mant = (mant << 1) | (uint64_t)big_bit(b, i);
  int exp2 = top - 63;
  if (big_bit(b, top - 64)) {
    mant++;
    if (mant == 0) { /* carried out: 2^64 */
      mant = (uint64_t)1 << 63;
      exp2++;
    }
  }
  return (pow10_entry){mant, exp2};
}

/* 10^k for k >= 0 exactly; 10^-j as floor(2^BIG_SHIFT / 10^j) / 2^BIG_SHIFT,
 * whose truncation errors stay far below the 64 bits kept. */
static void pow10_init(void) {
  bignum b;
  memset(&b, 0, sizeof b);
  b.limb[0] = 1;
  for (int k = 0; k <= POW10_MAX; k++) {
    pow10_table[k - POW10_MIN] = big_top64(&b);
    big_mul10(&b);
  }
  memset(&b, 0, sizeof b);
  b.limb[BIG_SHIFT / 32] = 1;
  for (int j = 1; j <= -POW10_MIN; j++) {
    big_div10(&b);
    pow10_entry e = big_top64(&b);
    e.exp2 -= BIG_SHIFT;
    pow10_table[-j - POW10_MIN] = e;
  }
}

/* round(m * 2^e * 10^k), for results below 2^64. */
static uint64_t scale_round(uint64_t m, int e, int k) {
  const pow10_entry *p = &pow10_table[k - POW10_MIN];
  unsigned __int128 prod = (unsigned __int128)m * p->mant;
  int shift = -(e + p->exp2); /* in [6, 127] for the k used here */
  uint64_t whole = (uint64_t)(prod >> shift);
  unsigned __int128 half = (unsigned __int128)1 << (shift - 1);
  unsigned __int128 rest = prod & ((half << 1) - 1);
  return whole + (rest >= half);
}

/* 17 significant digits of |x| (finite, non-zero): D and the decimal
 * exponent E of its first digit, x ~= D * 10^(E - 16). */
static uint64_t digits17(double x, int *E) {
  const uint64_t lo = 10000000000000000ull, hi = 100000000000000000ull;
  uint64_t bits;
  memcpy(&bits, &x, 8);
  int be = (int)((bits >> 52) & 0x7ff);
  uint64_t m = bits & (((uint64_t)1 << 52) - 1);
  int e = be ? be - 1075 : -1074;
  if (be) m |= (uint64_t)1 << 52;
  int log2x = e + 63 - __builtin_clzll(m);
  int k = 16 - (int)floor(log2x * 0.30102999566398120);
  uint64_t d = scale_round(m, e, k);
  for (int tries = 0; tries < 3 && (d < lo || d >= hi); tries++) {
    k += d < lo ? 1 : -1;
    d = scale_round(m, e, k);
  }
  *E = 16 - k;
  return d;
}

/* Whether the decimal d * 10^p reads back as ax (exact when it applies). */
static int reads_back(uint64_t d, int p, double ax) {
  static const double p10[23] = {1e0,  1e1,  1e2,  1e3,  1e4,  1e5,  1e6,  1e7,
                                 1e8,  1e9,  1e10, 1e11, 1e12, 1e13, 1e14, 1e15,
                                 1e16, 1e17, 1e18, 1e19, 1e20, 1e21, 1e22};
  if (d >= ((uint64_t)1 << 53) || p > 22 || p < -22) return 0;
  double v = (double)d;
  return (p >= 0 ? v * p10[p] : v / p10[-p]) == ax;
}

/* Writes the ndig digits of d with decimal exponent E like "%g" does. */
static size_t put_decimal(char *out, uint64_t d, int ndig, int E) {
  char dig[24];
  put_u64(dig, d);
  size_t n = 0;
  if (E >= 0 && E < 17) {
    for (int i = 0; i <= E; i++) out[n++] = i < ndig ? dig[i] : '0';
    if (ndig > E + 1) out[n++] = '.';
    for (int i = E + 1; i < ndig; i++) out[n++] = dig[i];
  } else if (E < 0 && E >= -4) {
    out[n++] = '0';
    out[n++] = '.';
    for (int i = -1; i > E; i--) out[n++] = '0';
    for (int i = 0; i < ndig; i++) out[n++] = dig[i];
  } else {
    out[n++] = dig[0];
    if (ndig > 1) out[n++] = '.';
    for (int i = 1; i < ndig; i++) out[n++] = dig[i];
    out[n++] = 'e';
    out[n++] = E < 0 ? '-' : '+';
    if (E > -10 && E < 10) out[n++] = '0';
    n += put_u64(out + n, (uint64_t)(E < 0 ? -E : E));
  }
  return n;
}

/* A double that reads back bit-exactly, at most 24 characters. */
static size_t put_double(char *out, double x) {
  size_t n = 0;
  if (signbit(x)) out[n++] = '-';
  double ax = fabs(x);
  if (ax == 0.0 || !isfinite(ax)) {
    const char *s = ax == 0.0 ? "0" : isnan(ax) ? "nan" : "inf";
    memcpy(out + n, s, strlen(s));
    return n + strlen(s);
  }
  int E;
  uint64_t d = digits17(ax, &E);
  int ndig = 17;
  uint64_t d15 = (d + 50) / 100; /* 15 digits (16 if it rounded up) */
  int E15 = E + (d15 >= 1000000000000000ull);
  if (d15 >= 1000000000000000ull) d15 /= 10;
  if (reads_back(d15, E15 - 14, ax)) {
    d = d15;
    E = E15;
    ndig = 15;
  }
  while (ndig > 1 && d % 10 == 0) {
    d /= 10;
    ndig--;
  }
  return n + put_decimal(out + n, d, ndig, E);
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
  const vtk_ctx *ctx = vctx;
  const double *xyz = ctx->m->xyz;
  size_t n = 0;
  for (size_t i = b; i < e; i++) {
    for (int d = 0; d < 3; d++) {
      n += put_double(out + n, xyz[3 * i + d]);
      out[n++] = d < 2 ? ' ' : '\n';
    }
  }
  return n;
}

/* ---- cells --------------------------------------------------------------- */

static size_t fill_cells_bin(const void *vctx, size_t b, size_t e, char *out) {
  const mx_mesh_view *m = ((const vtk_ctx *)vctx)->m;
  size_t n = 0;
  for (size_t c = b; c < e; c++) {
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
  for (size_t c = b; c < e; c++) {
    int nn = mx_cell_nodes[m->type[c]];
    const uint32_t *row = m->conn + 8 * c;
    out[n++] = (char)('0' + nn);
    const int8_t *ord = mx_vtk_order[m->type[c]];
    for (int j = 0; j < nn; j++) {
      out[n++] = ' ';
      n += put_u64(out + n, row[ord[j]]);
    }
    out[n++] = '\n';
  }
  return n;
}

static size_t fill_types_bin(const void *vctx, size_t b, size_t e, char *out) {
  const mx_mesh_view *m = ((const vtk_ctx *)vctx)->m;
  for (size_t c = b; c < e; c++) {
    put_be32(out + 4 * (c - b), (uint32_t)mx_vtk_cell_type[m->type[c]]);
  }
  return 4 * (e - b);
}

static size_t fill_types_ascii(const void *vctx, size_t b, size_t e,
                               char *out) {
  const mx_mesh_view *m = ((const vtk_ctx *)vctx)->m;
  size_t n = 0;
  for (size_t c = b; c < e; c++) {
    n += put_u64(out + n, (uint64_t)mx_vtk_cell_type[m->type[c]]);
    out[n++] = '\n';
  }
  return n;
}

/* ---- fields -------------------------------------------------------------- */

static size_t fill_field_bin(const void *vctx, size_t b, size_t e, char *out) {
  const mx_field *fd = ((const vtk_ctx *)vctx)->fd;
  size_t n = 0;
  if (fd->is_double) {
    for (size_t i = b; i < e; i++, n += 8)
      put_be_double(out + n, fd->dvalues[i]);
  } else {
    for (size_t i = b; i < e; i++, n += 4)
      put_be32(out + n, (uint32_t)fd->ivalues[i]);
  }
  return n;
}

static size_t fill_field_ascii(const void *vctx, size_t b, size_t e,
                               char *out) {
  const mx_field *fd = ((const vtk_ctx *)vctx)->fd;
  size_t n = 0;
  for (size_t i = b; i < e; i++) {
    if (fd->is_double)
      n += put_double(out + n, fd->dvalues[i]);
    else
      n += put_i64(out + n, fd->ivalues[i]);
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
    MX_CHECK(mx_afile_emit(f, m->nnodes, 3 * NUM_MAX, fill_points_ascii, ctx));
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
                       size_t count, int binary) {
  char name[NAME_MAX_BYTES];
  encode_name(fd->name, name, sizeof name);
  MX_CHECK(mx_afile_printf(f, "SCALARS %s %s 1\nLOOKUP_TABLE default\n", name,
                           fd->is_double ? "double" : "int"));
  vtk_ctx ctx = {m, fd};
  size_t width = fd->is_double ? 8 : 4;
  if (binary)
    MX_CHECK(mx_afile_emit(f, count, width, fill_field_bin, &ctx));
  else
    MX_CHECK(mx_afile_emit(f, count, NUM_MAX, fill_field_ascii, &ctx));
  return binary ? mx_afile_write(f, "\n", 1) : MX_OK;
}

static int write_fields(mx_afile *f, const mx_mesh_view *m, const char *kind,
                        int nfields, const mx_field *fields, size_t count,
                        int binary) {
  if (nfields == 0) return MX_OK;
  MX_CHECK(mx_afile_printf(f, "%s %zu\n", kind, count));
  for (int i = 0; i < nfields; i++) {
    MX_CHECK(write_field(f, m, &fields[i], count, binary));
  }
  return MX_OK;
}

static int write_body(mx_afile *f, const mx_mesh_view *m, int binary) {
  vtk_ctx ctx = {m, NULL};
  MX_CHECK(mx_afile_printf(f,
                           "# vtk DataFile Version 3.0\nmixoct mesh\n%s\n"
                           "DATASET UNSTRUCTURED_GRID\n",
                           binary ? "BINARY" : "ASCII"));
  MX_CHECK(write_points(f, &ctx, binary));
  MX_CHECK(write_cells(f, &ctx, binary));
  MX_CHECK(write_fields(f, m, "CELL_DATA", m->ncell_fields, m->cell_fields,
                        m->ncells, binary));
  MX_CHECK(write_fields(f, m, "POINT_DATA", m->npoint_fields, m->point_fields,
                        m->nnodes, binary));
  return MX_OK;
}

int mx_write_vtk_legacy(const char *path, const mx_mesh_view *m, int binary) {
  MX_CHECK(mx_mesh_view_check(path, m));
  if (!binary) pthread_once(&pow10_once, pow10_init);
  if (m->nnodes > (size_t)INT32_MAX) {
    mx_error(path, 0,
             "%zu nodes are too many for legacy VTK (32-bit ids): use .vtu",
             m->nnodes);
    return MX_EINPUT;
  }
  mx_afile f;
  MX_CHECK(mx_afile_open(&f, path));
  int status = write_body(&f, m, binary);
  if (status != MX_OK) {
    mx_afile_abort(&f);
    return status;
  }
  return mx_afile_commit(&f);
}
