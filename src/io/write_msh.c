/* mixoct: Gmsh MSH 4.1 writer, ASCII ("4.1 0 8") or binary ("4.1 1 8").
 *
 * Layout: $MeshFormat, $PhysicalNames (one volume group, tag 1, "domain"),
 * $Entities (one volume, tag 1, with its bounding box and that physical
 * group), $Nodes (one block on the volume holding every node, tags 1..N in
 * the mesh's order), $Elements (one block per element type present, in the
 * order tet, pyramid, prism, hex; an element's tag is its index in the
 * mesh + 1, so tags match the cell order of the other formats).
 *
 * Binary files use the host's byte order (the int 1 after the format line
 * lets a reader check it): counts and node/element tags are 8-byte size_t,
 * entity dimensions, tags and element types 4-byte int, coordinates 8-byte
 * doubles. $PhysicalNames is ASCII in both variants.
 *
 * Node order. Gmsh's reference elements (Gmsh manual, "Node ordering"):
 *   tet     (0,0,0) (1,0,0) (0,1,0) (0,0,1)
 *   pyramid (-1,-1,0) (1,-1,0) (1,1,0) (-1,1,0) (0,0,1)
 *   prism   (0,0,-1) (1,0,-1) (0,1,-1) (0,0,1) (1,0,1) (0,1,1)
 *   hex     (-1,-1,-1) (1,-1,-1) (1,1,-1) (-1,1,-1) then the same at z = 1
 * In each, the right-hand normal of the first face (0,1,2[,3]) points into
 * the element, towards the other nodes. mixoct's cells (VTK order, see
 * soa/mesh.h and kernels/quality.c) follow the same rule: the pyramid base
 * 0,1,2,3 turns counter-clockwise seen from the apex 4, the prism triangle
 * 0,1,2 counter-clockwise seen from 3,4,5. So the permutation below is the
 * identity for every type; it is kept as a table so the rule is written in
 * one place (tests/test_msh.c checks volumes in Gmsh's convention, and
 * tests/external_readers_test.sh Gmsh's own Jacobians). For prisms this is
 * the order of VTK's wedge parametric coordinates, not of the vtkWedge
 * documentation, which turns 0,1,2 the other way.
 *
 * Every large section is formatted (ASCII) or packed (binary) in parallel
 * chunks by mx_afile_emit: the bytes do not depend on the thread count.
 * ASCII doubles read back exactly (see put_double). */
#include <float.h>
#include <math.h>
#include <pthread.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "common.h"
#include "io/atomic_file.h"
#include "soa/mesh.h"

/* Gmsh element type per mixoct type, and mixoct's node j of Gmsh's node k. */
static const int msh_type[4] = {4, 7, 6, 5};
static const int8_t msh_perm[4][8] = {{0, 1, 2, 3, 0, 0, 0, 0},
                                      {0, 1, 2, 3, 4, 0, 0, 0},
                                      {0, 1, 2, 3, 4, 5, 0, 0},
                                      {0, 1, 2, 3, 4, 5, 6, 7}};

enum {
  U64_MAX_CHARS = 20,
  DBL_MAX_CHARS = 24, /* sign, 17 digits, "0.000" or "e-308" */
  ENTITY_TAG = 1,
  PHYSICAL_TAG = 1,
};

typedef struct {
  const mx_mesh_view *m;
  int type; /* element section: the mixoct type of this block */
} msh_ctx;

/* ---- ASCII integers -------------------------------------------------------- */

static const char digit_pairs[201] =
    "00010203040506070809101112131415161718192021222324252627282930313233343536"
    "37383940414243444546474849505152535455565758596061626364656667686970717273"
    "7475767778798081828384858687888990919293949596979899";

/* Decimal digits of v, no sign, no terminator; returns the length. */
static size_t put_u64(char *out, uint64_t v) {
  char tmp[U64_MAX_CHARS];
  size_t n = sizeof tmp;
  while (v >= 100) {
    unsigned r = (unsigned)(v % 100);
    v /= 100;
    n -= 2;
    memcpy(tmp + n, digit_pairs + 2 * r, 2);
  }
  if (v >= 10) {
    n -= 2;
    memcpy(tmp + n, digit_pairs + 2 * v, 2);
  } else {
    tmp[--n] = (char)('0' + v);
  }
  memcpy(out, tmp + n, sizeof tmp - n);
  return sizeof tmp - n;
}

/* ---- ASCII doubles ----------------------------------------------------------
 *
 * A finite x != 0 is m * 2^e (m < 2^53 an integer). A table holds 10^k for
 * |k| <= 350 as M * 2^B with M a 64-bit integer in [2^63, 2^64), rounded
 * from a 128-bit mantissa built by exact multiplications and divisions by
 * 10 (each step truncates 4 bits below the 124th, far under the 64 kept):
 * its relative error is at most 2^-64 (1 + 2^-50). The 17-digit integer
 * D = round(x * 10^k), 10^16 <= D < 10^17, is taken from the exact 128-bit
 * product m * M, so it lies within 0.5 + 10^17 * 2^-63.99 < 0.506 units of
 * its last digit from the true x * 10^k. One such unit is at most
 * 2^53 / 10^16 < 0.901 ulp of x, so D * 10^-k is within 0.456 ulp of x and
 * reads back as x. When the 15-digit rounding of D reads back as x too
 * (checked exactly: an integer below 2^53 times or over an exact power of
 * ten is one correctly rounded operation), that shorter form is written:
 * 0.1 is "0.1". Only integer arithmetic: no dependence on long double or
 * the rounding mode. Without a 128-bit integer type the C library's "%.17g"
 * is used. */

#ifdef __SIZEOF_INT128__
#define MSH_FAST_DOUBLES 1
typedef unsigned __int128 u128;
enum { P10_LIM = 350 };

typedef struct {
  uint64_t mant; /* in [2^63, 2^64) */
  int exp2;      /* 10^k ~= mant * 2^exp2 */
} p10_entry;

static p10_entry p10_table[2 * P10_LIM + 1]; /* index k + P10_LIM */
static pthread_once_t p10_once = PTHREAD_ONCE_INIT;

/* Shifts u left until its top bit is set, lowering *b to keep u * 2^b. */
static void normalize128(u128 *u, int *b) {
  while (!(*u >> 127)) {
    *u <<= 1;
    (*b)--;
  }
}

/* The top 64 bits of the normalised u * 2^b, rounded to nearest. */
static p10_entry round_top64(u128 u, int b) {
  uint64_t top = (uint64_t)(u >> 64);
  int exp2 = b + 64;
  if ((u >> 63) & 1) {
    top++;
    if (top == 0) { /* carried out of 64 bits: 2^64 */
      top = (uint64_t)1 << 63;
      exp2++;
    }
  }
  return (p10_entry){top, exp2};
}

static void p10_init(void) {
  u128 u = (u128)1 << 127; /* 1 = 2^127 * 2^-127 */
  int b = -127;
  for (int k = 0; k <= P10_LIM; k++) { /* u * 2^b ~= 10^k */
    p10_table[k + P10_LIM] = round_top64(u, b);
    u = (u >> 4) * 10; /* < 2^128; 10^k * 10 = (u / 16) * 10 * 2^(b + 4) */
    b += 4;
    normalize128(&u, &b);
  }
  u = (u128)1 << 127;
  b = -127;
  for (int k = 1; k <= P10_LIM; k++) { /* u * 2^b ~= 10^-k */
    u /= 10;
    normalize128(&u, &b);
    p10_table[P10_LIM - k] = round_top64(u, b);
  }
}

/* round(m * 2^e * 10^k); *ok = 0 when the shift is out of range. */
static uint64_t scaled_digits(uint64_t m, int e, int k, int *ok) {
  const p10_entry *p = &p10_table[k + P10_LIM];
  u128 prod = (u128)m * p->mant;
  int shift = -(e + p->exp2);
  if (shift < 1 || shift > 127) {
    *ok = 0;
    return 0;
  }
  return (uint64_t)(prod >> shift) + (uint64_t)((prod >> (shift - 1)) & 1);
}
#else
#define MSH_FAST_DOUBLES 0
#endif

static const double p10d[23] = {1e0,  1e1,  1e2,  1e3,  1e4,  1e5,
                                1e6,  1e7,  1e8,  1e9,  1e10, 1e11,
                                1e12, 1e13, 1e14, 1e15, 1e16, 1e17,
                                1e18, 1e19, 1e20, 1e21, 1e22};

/* Whether d * 10^p (d < 2^53, |p| <= 22) is exactly the double ax. */
static int decimal_is(uint64_t d, int p, double ax) {
  if (d >= ((uint64_t)1 << 53) || p > 22 || p < -22) return 0;
  double v = (double)d;
  return (p >= 0 ? v * p10d[p] : v / p10d[-p]) == ax;
}

/* The nd digits of d (first digit at decimal exponent E) in "%g" style. */
static size_t put_digits(char *out, uint64_t d, int nd, int E) {
  char dig[U64_MAX_CHARS];
  put_u64(dig, d);
  size_t n = 0;
  if (E >= -4 && E < 17) {
    if (E < 0) {
      out[n++] = '0';
      out[n++] = '.';
      for (int i = E + 1; i < 0; i++) out[n++] = '0';
      memcpy(out + n, dig, (size_t)nd);
      return n + (size_t)nd;
    }
    for (int i = 0; i <= E; i++) out[n++] = i < nd ? dig[i] : '0';
    if (nd > E + 1) {
      out[n++] = '.';
      memcpy(out + n, dig + E + 1, (size_t)(nd - E - 1));
      n += (size_t)(nd - E - 1);
    }
    return n;
  }
  out[n++] = dig[0];
  if (nd > 1) {
    out[n++] = '.';
    memcpy(out + n, dig + 1, (size_t)(nd - 1));
    n += (size_t)(nd - 1);
  }
  out[n++] = 'e';
  out[n++] = E < 0 ? '-' : '+';
  int ae = E < 0 ? -E : E;
  if (ae < 10) out[n++] = '0';
  return n + put_u64(out + n, (uint64_t)ae);
}

static size_t put_double_libc(char *out, double x) {
  char tmp[40];
  int len = snprintf(tmp, sizeof tmp, "%.17g", x);
  if (len < 0 || len > DBL_MAX_CHARS) len = 0;
  memcpy(out, tmp, (size_t)len);
  return (size_t)len;
}

/* A double that reads back bit-exactly; at most DBL_MAX_CHARS characters. */
static size_t put_double(char *out, double x) {
#if MSH_FAST_DOUBLES
  size_t n = 0;
  if (signbit(x)) out[n++] = '-';
  double ax = fabs(x);
  if (ax == 0.0 || !isfinite(ax)) {
    const char *s = ax == 0.0 ? "0" : isnan(ax) ? "nan" : "inf";
    size_t len = strlen(s);
    memcpy(out + n, s, len);
    return n + len;
  }
  const uint64_t lo = 10000000000000000ull, hi = 100000000000000000ull;
  uint64_t bits;
  memcpy(&bits, &ax, 8);
  int be = (int)(bits >> 52);
  uint64_t m = bits & (((uint64_t)1 << 52) - 1);
  int e = be ? be - 1075 : -1074;
  if (be) m |= (uint64_t)1 << 52;
  /* decimal exponent estimate from the binary one: off by at most one */
  int log2x = e + 63 - __builtin_clzll(m);
  int E = (int)floor(log2x * 0.30102999566398120);
  int ok = 1;
  uint64_t d = scaled_digits(m, e, 16 - E, &ok);
  for (int tries = 0; ok && tries < 2 && (d < lo || d >= hi); tries++) {
    E += d >= hi ? 1 : -1;
    d = scaled_digits(m, e, 16 - E, &ok);
  }
  if (!ok || d < lo || d >= hi) return put_double_libc(out, x); /* unreached */
  int nd = 17;
  uint64_t d15 = (d + 50) / 100;
  int E15 = E;
  if (d15 >= 1000000000000000ull) { /* 9.99..95 rounded up to 10.0 */
    d15 /= 10;
    E15++;
  }
  if (decimal_is(d15, E15 - 14, ax)) {
    d = d15;
    E = E15;
    nd = 15;
  }
  while (nd > 1 && d % 10 == 0) {
    d /= 10;
    nd--;
  }
  return n + put_digits(out + n, d, nd, E);
#else
  return put_double_libc(out, x);
#endif
}

/* ---- binary stores (host byte order) -------------------------------------- */

static inline void put_size(char *out, uint64_t v) { memcpy(out, &v, 8); }

/* ---- nodes ------------------------------------------------------------------ */

static size_t fill_node_tags_bin(const void *vctx, size_t b, size_t e,
                                 char *out) {
  (void)vctx;
  for (size_t i = b; i < e; i++) put_size(out + 8 * (i - b), (uint64_t)i + 1);
  return 8 * (e - b);
}

static size_t fill_node_tags_ascii(const void *vctx, size_t b, size_t e,
                                   char *out) {
  (void)vctx;
  size_t n = 0;
  for (size_t i = b; i < e; i++) {
    n += put_u64(out + n, (uint64_t)i + 1);
    out[n++] = '\n';
  }
  return n;
}

static size_t fill_coords_ascii(const void *vctx, size_t b, size_t e,
                                char *out) {
  const double *xyz = ((const msh_ctx *)vctx)->m->xyz;
  size_t n = 0;
  for (size_t i = b; i < e; i++) {
    for (int k = 0; k < 3; k++) {
      n += put_double(out + n, xyz[3 * i + k]);
      out[n++] = k < 2 ? ' ' : '\n';
    }
  }
  return n;
}

/* ---- elements: every cell is an item, the ones of other types write
 * nothing, so a block keeps the mesh's order within its type. -------------- */

static size_t fill_elements_bin(const void *vctx, size_t b, size_t e,
                                char *out) {
  const msh_ctx *ctx = vctx;
  const mx_mesh_view *m = ctx->m;
  const int t = ctx->type, nn = mx_cell_nodes[t];
  const int8_t *perm = msh_perm[t];
  size_t n = 0;
  for (size_t c = b; c < e; c++) {
    if (m->type[c] != t) continue;
    const uint32_t *row = m->conn + 8 * c;
    put_size(out + n, (uint64_t)c + 1);
    n += 8;
    for (int k = 0; k < nn; k++, n += 8)
      put_size(out + n, (uint64_t)row[perm[k]] + 1);
  }
  return n;
}

static size_t fill_elements_ascii(const void *vctx, size_t b, size_t e,
                                  char *out) {
  const msh_ctx *ctx = vctx;
  const mx_mesh_view *m = ctx->m;
  const int t = ctx->type, nn = mx_cell_nodes[t];
  const int8_t *perm = msh_perm[t];
  size_t n = 0;
  for (size_t c = b; c < e; c++) {
    if (m->type[c] != t) continue;
    const uint32_t *row = m->conn + 8 * c;
    n += put_u64(out + n, (uint64_t)c + 1);
    for (int k = 0; k < nn; k++) {
      out[n++] = ' ';
      n += put_u64(out + n, (uint64_t)row[perm[k]] + 1);
    }
    out[n++] = '\n';
  }
  return n;
}

/* ---- sections ---------------------------------------------------------------- */

static int write_bin(mx_afile *f, const void *p, size_t bytes) {
  return mx_afile_write(f, p, bytes);
}

static int write_bin_size(mx_afile *f, uint64_t v) {
  return write_bin(f, &v, 8);
}

static int write_bin_int(mx_afile *f, int v) {
  int32_t i = (int32_t)v;
  return write_bin(f, &i, 4);
}

static int write_header(mx_afile *f, int binary) {
  MX_CHECK(mx_afile_printf(f, "$MeshFormat\n4.1 %d 8\n", binary ? 1 : 0));
  if (binary) {
    MX_CHECK(write_bin_int(f, 1));
    MX_CHECK(mx_afile_write(f, "\n", 1));
  }
  return mx_afile_printf(f,
                         "$EndMeshFormat\n$PhysicalNames\n1\n3 %d \"domain\"\n"
                         "$EndPhysicalNames\n",
                         PHYSICAL_TAG);
}

/* Bounding box of the nodes (min/max are exact: any order gives the same). */
static void bounding_box(const mx_mesh_view *m, double box[6]) {
  double x0 = 0, y0 = 0, z0 = 0, x1 = 0, y1 = 0, z1 = 0;
  if (m->nnodes > 0) {
    x0 = x1 = m->xyz[0];
    y0 = y1 = m->xyz[1];
    z0 = z1 = m->xyz[2];
  }
#pragma omp parallel for reduction(min : x0, y0, z0) \
    reduction(max : x1, y1, z1) schedule(static) if (m->nnodes > 65536)
  for (size_t i = 0; i < m->nnodes; i++) {
    const double *p = m->xyz + 3 * i;
    x0 = p[0] < x0 ? p[0] : x0;
    y0 = p[1] < y0 ? p[1] : y0;
    z0 = p[2] < z0 ? p[2] : z0;
    x1 = p[0] > x1 ? p[0] : x1;
    y1 = p[1] > y1 ? p[1] : y1;
    z1 = p[2] > z1 ? p[2] : z1;
  }
  box[0] = x0, box[1] = y0, box[2] = z0;
  box[3] = x1, box[4] = y1, box[5] = z1;
}

/* One volume (dim 3, tag ENTITY_TAG) in physical group PHYSICAL_TAG, with no
 * bounding surfaces; no points, curves or surfaces. */
static int write_entities(mx_afile *f, const mx_mesh_view *m, int binary) {
  double box[6];
  bounding_box(m, box);
  MX_CHECK(mx_afile_printf(f, "$Entities\n"));
  if (binary) {
    for (int k = 0; k < 3; k++) MX_CHECK(write_bin_size(f, 0));
    MX_CHECK(write_bin_size(f, 1));
    MX_CHECK(write_bin_int(f, ENTITY_TAG));
    MX_CHECK(write_bin(f, box, sizeof box));
    MX_CHECK(write_bin_size(f, 1));
    MX_CHECK(write_bin_int(f, PHYSICAL_TAG));
    MX_CHECK(write_bin_size(f, 0));
    MX_CHECK(mx_afile_write(f, "\n", 1));
  } else {
    char line[6 * (DBL_MAX_CHARS + 1) + 64];
    size_t n = (size_t)snprintf(line, sizeof line, "0 0 0 1\n%d", ENTITY_TAG);
    for (int k = 0; k < 6; k++) {
      line[n++] = ' ';
      n += put_double(line + n, box[k]);
    }
    n += (size_t)snprintf(line + n, sizeof line - n, " 1 %d 0\n", PHYSICAL_TAG);
    MX_CHECK(mx_afile_write(f, line, n));
  }
  return mx_afile_printf(f, "$EndEntities\n");
}

static int write_nodes(mx_afile *f, const mx_mesh_view *m, int binary) {
  const size_t nn = m->nnodes;
  const size_t nblocks = nn > 0;
  const size_t tag_min = nn > 0, tag_max = nn;
  msh_ctx ctx = {m, 0};
  MX_CHECK(mx_afile_printf(f, "$Nodes\n"));
  if (binary) {
    const uint64_t head[4] = {nblocks, nn, tag_min, tag_max};
    MX_CHECK(write_bin(f, head, sizeof head));
    if (nblocks) {
      MX_CHECK(write_bin_int(f, 3));
      MX_CHECK(write_bin_int(f, ENTITY_TAG));
      MX_CHECK(write_bin_int(f, 0)); /* no parametric coordinates */
      MX_CHECK(write_bin_size(f, nn));
      MX_CHECK(mx_afile_emit(f, nn, 8, fill_node_tags_bin, &ctx));
      MX_CHECK(write_bin(f, m->xyz, 3 * nn * sizeof(double)));
    }
    MX_CHECK(mx_afile_write(f, "\n", 1));
  } else {
    MX_CHECK(mx_afile_printf(f, "%zu %zu %zu %zu\n", nblocks, nn, tag_min,
                             tag_max));
    if (nblocks) {
      MX_CHECK(mx_afile_printf(f, "3 %d 0 %zu\n", ENTITY_TAG, nn));
      MX_CHECK(mx_afile_emit(f, nn, U64_MAX_CHARS + 1, fill_node_tags_ascii,
                             &ctx));
      MX_CHECK(mx_afile_emit(f, nn, 3 * (DBL_MAX_CHARS + 1), fill_coords_ascii,
                             &ctx));
    }
  }
  return mx_afile_printf(f, "$EndNodes\n");
}

static void count_types(const mx_mesh_view *m, size_t count[4]) {
  size_t c0 = 0, c1 = 0, c2 = 0, c3 = 0;
#pragma omp parallel for reduction(+ : c0, c1, c2, c3) schedule(static) \
    if (m->ncells > 65536)
  for (size_t c = 0; c < m->ncells; c++) {
    switch (m->type[c]) {
      case MX_TET: c0++; break;
      case MX_PYRAMID: c1++; break;
      case MX_PRISM: c2++; break;
      default: c3++; break;
    }
  }
  count[0] = c0, count[1] = c1, count[2] = c2, count[3] = c3;
}

static int write_elements(mx_afile *f, const mx_mesh_view *m, int binary) {
  size_t count[4];
  count_types(m, count);
  size_t nblocks = 0;
  for (int t = 0; t < 4; t++) nblocks += count[t] > 0;
  const size_t ne = m->ncells, tag_min = ne > 0, tag_max = ne;
  MX_CHECK(mx_afile_printf(f, "$Elements\n"));
  if (binary) {
    const uint64_t head[4] = {nblocks, ne, tag_min, tag_max};
    MX_CHECK(write_bin(f, head, sizeof head));
  } else {
    MX_CHECK(mx_afile_printf(f, "%zu %zu %zu %zu\n", nblocks, ne, tag_min,
                             tag_max));
  }
  for (int t = 0; t < 4; t++) {
    if (count[t] == 0) continue;
    msh_ctx ctx = {m, t};
    size_t per_cell = (size_t)mx_cell_nodes[t] + 1;
    if (binary) {
      MX_CHECK(write_bin_int(f, 3));
      MX_CHECK(write_bin_int(f, ENTITY_TAG));
      MX_CHECK(write_bin_int(f, msh_type[t]));
      MX_CHECK(write_bin_size(f, count[t]));
      MX_CHECK(mx_afile_emit(f, ne, 8 * per_cell, fill_elements_bin, &ctx));
    } else {
      MX_CHECK(mx_afile_printf(f, "3 %d %d %zu\n", ENTITY_TAG, msh_type[t],
                               count[t]));
      MX_CHECK(mx_afile_emit(f, ne, (U64_MAX_CHARS + 1) * per_cell,
                             fill_elements_ascii, &ctx));
    }
  }
  if (binary) MX_CHECK(mx_afile_write(f, "\n", 1));
  return mx_afile_printf(f, "$EndElements\n");
}

static int write_body(mx_afile *f, const mx_mesh_view *m, int binary) {
  MX_CHECK(write_header(f, binary));
  MX_CHECK(write_entities(f, m, binary));
  MX_CHECK(write_nodes(f, m, binary));
  return write_elements(f, m, binary);
}

int mx_write_msh(const char *path, const mx_mesh_view *m, int binary) {
  MX_CHECK(mx_mesh_view_check(path, m));
#if MSH_FAST_DOUBLES
  if (!binary) pthread_once(&p10_once, p10_init);
#endif
  mx_afile f;
  MX_CHECK(mx_afile_open(&f, path));
  int status = write_body(&f, m, binary);
  if (status != MX_OK) {
    mx_afile_abort(&f);
    return status;
  }
  return mx_afile_commit(&f);
}
