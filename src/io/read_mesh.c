/* mixoct: reading legacy VTK and VTU unstructured grids, Gmsh MSH 4.1,
 * Medit .mesh / .meshb, and the M3D, MVM and GetFEM text files (see
 * read_mesh.h).
 *
 * The file is mapped (or loaded) whole. MSH, Medit, M3D, MVM and GetFEM
 * are read in one pass with a cursor (text tokens, or binary values after a
 * bounds check); every count is checked against the bytes left before
 * anything is allocated for it. The VTK formats are first cut into "parts" that
 * point into the buffer (or into temporaries holding parsed ASCII values):
 * the points, the cells either as a count-prefixed list (legacy) or as
 * offsets + connectivity (VTU, legacy 5.x), and the cell types. One
 * assembly step then converts and validates them in parallel, and re-runs
 * the first failing item serially to print its message. Binary values are
 * only read after the block holding them was checked to lie in the file.
 * A .pvtu master has its VTU pieces read one by one and merged (read_pvtu). */
#include "io/read_mesh.h"

#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include "base/common.h"
#include "io/getfem_tables.h"
#include "io/text_scan.h"
#include "base/scan.h"

#define HOST_LE (__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__)

typedef enum {
  T_I8, T_U8, T_I16, T_U16, T_I32, T_U32, T_I64, T_U64, T_F32, T_F64, T_NONE
} vtype;
static const int vsize[T_NONE + 1] = {1, 1, 2, 2, 4, 4, 8, 8, 4, 8, 0};
static const char *const vtu_type_name[T_NONE] = {
    "Int8",  "UInt8",  "Int16",  "UInt16",  "Int32",
    "UInt32", "Int64", "UInt64", "Float32", "Float64"};

/* n values of type t, stored from data on (byte-swapped when swap). */
typedef struct {
  const unsigned char *data;
  size_t n;
  vtype t;
  int swap;
  const char *text; /* parsed from ASCII starting here (for messages) */
} rawarr;

enum { MAX_TMP = 8, MSG = 512 };

/* What a piece of a .pvtu gives besides its mesh (see read_pvtu). */
typedef struct {
  uint64_t *gid;               /* its GlobalNodeId (nnodes values), or NULL */
  uint64_t point_sig, cell_sig; /* its point and cell arrays (names, types) */
} piece_info;

typedef struct {
  const char *path, *buf, *end; /* the file, NUL-terminated at end */
  const char *bin_from;         /* binary data starts here (or NULL) */
  void *tmp[MAX_TMP];
  int ntmp;
  int planar; /* VTK triangles and quadrilaterals accepted (mx_read_mesh_planar) */
  piece_info *piece; /* reading a piece of a .pvtu: a VTU file only */
  int merged;        /* a .pvtu was read: its pieces' wedges are ours already */
} rd;

/* ---- messages ------------------------------------------------------------ */

static long line_of(const rd *r, const char *at) {
  long line = 1;
  const char *p = r->buf;
  while (p < at) {
    const char *nl = memchr(p, '\n', (size_t)(at - p));
    if (!nl) break;
    line++;
    p = nl + 1;
  }
  return line;
}

/* Prints the message with the line of `at` in a text part, its byte offset
 * in a binary part, nothing when at is NULL; returns MX_EINPUT. */
static int fail(const rd *r, const char *at, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
static int fail(const rd *r, const char *at, const char *fmt, ...) {
  char msg[MSG];
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(msg, sizeof msg, fmt, ap);
  va_end(ap);
  if (!at || at < r->buf || at > r->end)
    mx_error(r->path, 0, "%s", msg);
  else if (r->bin_from && at >= r->bin_from)
    mx_error(r->path, 0, "%s (at byte %zu)", msg, (size_t)(at - r->buf));
  else
    mx_error(r->path, line_of(r, at), "%s", msg);
  return MX_EINPUT;
}

static void *rd_alloc(rd *r, size_t bytes) {
  if (r->ntmp == MAX_TMP) {
    mx_error(r->path, 0, "internal error: too many temporaries");
    return NULL;
  }
  void *p = mx_alloc(bytes);
  if (p) r->tmp[r->ntmp++] = p;
  return p;
}

/* ---- raw values ---------------------------------------------------------- */

static inline uint64_t load_bits(const unsigned char *p, int size, int swap) {
  switch (size) {
    case 1:
      return p[0];
    case 2: {
      uint16_t v;
      memcpy(&v, p, 2);
      return swap ? __builtin_bswap16(v) : v;
    }
    case 4: {
      uint32_t v;
      memcpy(&v, p, 4);
      return swap ? __builtin_bswap32(v) : v;
    }
    default: {
      uint64_t v;
      memcpy(&v, p, 8);
      return swap ? __builtin_bswap64(v) : v;
    }
  }
}

/* Element i of an integer array; -1 for values beyond INT64_MAX. */
static inline int64_t raw_int(const rawarr *a, size_t i) {
  uint64_t b = load_bits(a->data + i * (size_t)vsize[a->t], vsize[a->t],
                         a->swap);
  switch (a->t) {
    case T_I8: return (int8_t)b;
    case T_I16: return (int16_t)b;
    case T_I32: return (int32_t)b;
    case T_I64: return (int64_t)b;
    case T_U64: return b > (uint64_t)INT64_MAX ? -1 : (int64_t)b;
    default: return (int64_t)b; /* U8, U16, U32 */
  }
}

static inline double raw_double(const rawarr *a, size_t i) {
  if (a->t == T_F32) {
    uint32_t b = (uint32_t)load_bits(a->data + 4 * i, 4, a->swap);
    float f;
    memcpy(&f, &b, 4);
    return f;
  }
  uint64_t b = load_bits(a->data + 8 * i, 8, a->swap);
  double d;
  memcpy(&d, &b, 8);
  return d;
}

static int is_float(vtype t) { return t == T_F32 || t == T_F64; }

static inline int is_ws(char c);
static const char *skip_ws(const char *p, const char *end);
static size_t tok_len(const char *p, const char *end);

/* Where element i lies in the file, for messages: in place, or found again
 * by counting the tokens of the ASCII text it was parsed from. */
static const char *arr_at(const rd *r, const rawarr *a, size_t i) {
  if (a->text) {
    const char *p = skip_ws(a->text, r->end);
    for (size_t k = 0; k < i && p < r->end; k++)
      p = skip_ws(p + tok_len(p, r->end), r->end);
    return p;
  }
  const char *p = (const char *)a->data;
  if (p < r->buf || p > r->end) return NULL;
  return p + i * (size_t)vsize[a->t];
}

/* ---- text ---------------------------------------------------------------- */

static inline int is_ws(char c) {
  return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\f' ||
         c == '\v';
}

static const char *skip_ws(const char *p, const char *end) {
  while (p < end && is_ws(*p)) p++;
  return p;
}

static size_t tok_len(const char *p, const char *end) {
  const char *q = p;
  while (q < end && *q && !is_ws(*q)) q++;
  return (size_t)(q - p);
}

static int tok_eq(const char *t, size_t n, const char *kw) {
  return strlen(kw) == n && strncasecmp(t, kw, n) == 0;
}

static int shown(size_t n) { return n > 40 ? 40 : (int)n; }

/* n blank-separated numbers (any line breaks) from *pp, stopping at end, at
 * a NUL or at `stop`. Into iv (integers) or dv (finite doubles). */
static int ascii_values(const rd *r, const char **pp, char stop, size_t n,
                        int64_t *iv, double *dv, const char *what) {
  const char *p = *pp, *end = r->end;
  for (size_t i = 0; i < n; i++) {
    p = skip_ws(p, end);
    if (p >= end || *p == '\0' || *p == stop)
      return fail(r, p,
                  "%s: expected %zu values, found %zu (truncated file or "
                  "wrong count)",
                  what, n, i);
    const char *e = dv ? mx_io_double(p, &dv[i]) : mx_io_int(p, &iv[i]);
    size_t tl = tok_len(p, end);
    if (stop) {
      const char *s = memchr(p, stop, tl);
      if (s) tl = (size_t)(s - p);
    }
    if (!e || e != p + tl)
      return fail(r, p, "%s: value %zu: '%.*s' is not %s", what, i,
                  shown(tl), p, dv ? "a number" : "an integer");
    if (dv && !isfinite(dv[i]))
      return fail(r, p, "%s: value %zu: '%.*s' is not a finite number", what,
                  i, shown(tl), p);
    p = e;
  }
  *pp = p;
  return MX_OK;
}

/* Parses values into a temporary and describes it as a host-order array. */
static int ascii_array(rd *r, const char **pp, char stop, size_t n,
                       int floats, rawarr *out, const char *what) {
  /* Each value takes at least two bytes: refuse absurd counts early. */
  if (n > (size_t)(r->end - *pp) / 2 + 1)
    return fail(r, *pp,
                "%s: %zu values announced but the file is too short "
                "(truncated file or wrong count)",
                what, n);
  void *v = rd_alloc(r, n * 8);
  if (!v) return MX_EINPUT;
  const char *text = *pp;
  MX_CHECK(ascii_values(r, pp, stop, n, floats ? NULL : v, floats ? v : NULL,
                        what));
  *out = (rawarr){v, n, floats ? T_F64 : T_I64, 0, text};
  return MX_OK;
}

/* ---- assembly ------------------------------------------------------------ */

typedef struct {
  size_t nnodes, ncells;
  rawarr pts; /* 3*nnodes floats */
  int list_form;
  uint8_t *nn;      /* list form: node count per cell (out->conn filled) */
  rawarr off, cn;   /* offsets form */
  int vtu_offsets;  /* 1: ncells end offsets; 0: ncells + 1 offsets from 0 */
  rawarr types;
} parts;

/* Cell types while assembling: ours (MX_TET .. MX_HEX) and, in a planar
 * read, VTK's triangle and quadrilateral (A_TRI, A_QUAD), which
 * planar_cells then turns into faces. */
enum { A_TRI = 4, A_QUAD = 5 };
static const int any_nodes[6] = {4, 5, 6, 8, 3, 4};

static int vtk_to_mx(int64_t code, int planar) {
  switch (code) {
    case 10: return MX_TET;
    case 14: return MX_PYRAMID;
    case 13: return MX_PRISM;
    case 12: return MX_HEX;
    case 5: return planar ? A_TRI : -1;
    case 9: return planar ? A_QUAD : -1;
    default: return -1;
  }
}

static const char *const type_word[6] = {"tetrahedron", "pyramid", "wedge",
                                         "hexahedron", "triangle",
                                         "quadrilateral"};

/* Cell c of the offsets form into row; 0 if fine, else 1 and (when msg is
 * not NULL) the reason. */
static int offset_cell(const parts *P, size_t c, int type, uint32_t *row,
                       char *msg) {
  int64_t s, e;
  if (P->vtu_offsets) {
    s = c ? raw_int(&P->off, c - 1) : 0;
    e = raw_int(&P->off, c);
  } else {
    s = raw_int(&P->off, c);
    e = raw_int(&P->off, c + 1);
  }
  const int64_t need = any_nodes[type];
  if (s < 0 || e < s || (uint64_t)e > P->cn.n) {
    if (msg)
      snprintf(msg, MSG,
               "cell %zu: offsets %lld..%lld are not an increasing range "
               "inside the %zu connectivity entries",
               c, (long long)s, (long long)e, P->cn.n);
    return 1;
  }
  if (e - s != need) {
    if (msg)
      snprintf(msg, MSG, "cell %zu (%s) has %lld nodes, expected %lld", c,
               type_word[type], (long long)(e - s), (long long)need);
    return 1;
  }
  for (int j = 0; j < 8; j++) row[j] = 0;
  for (int64_t j = 0; j < need; j++) {
    int64_t v = raw_int(&P->cn, (size_t)(s + j));
    if (v < 0 || v >= (int64_t)UINT32_MAX) {
      if (msg)
        snprintf(msg, MSG, "cell %zu: node index %lld out of range", c,
                 (long long)v);
      return 1;
    }
    row[j] = (uint32_t)v;
  }
  return 0;
}

/* A planar read: the triangles and quadrilaterals of a mesh that has no
 * volume cell and lies in the plane z = 0 become its faces (tag 0, the
 * file's node order), and ncells 0: a 2D mesh (io/read_qmesh.h). Both
 * kinds of cells in one file, or a 2D cell off the plane, are errors. */
static int planar_cells(rd *r, const parts *P, mx_mesh_data *out) {
  const size_t nc = out->ncells, nn = out->nnodes;
  size_t flat = SIZE_MAX, solid = SIZE_MAX, offz = SIZE_MAX;
#pragma omp parallel for schedule(static) reduction(min : flat, solid) \
    if (nc > 65536)
  for (size_t c = 0; c < nc; c++) {
    if (out->type[c] >= A_TRI) {
      if (c < flat) flat = c;
    } else if (c < solid) {
      solid = c;
    }
  }
  if (flat == SIZE_MAX) return MX_OK;
  if (solid != SIZE_MAX) {
    const size_t later = flat > solid ? flat : solid;
    return fail(r, arr_at(r, &P->types, later),
                "cell %zu is a %s and cell %zu a %s: a mesh is either 2D "
                "(triangles and quadrilaterals) or 3D (volume cells)",
                flat, type_word[out->type[flat]], solid,
                type_word[out->type[solid]]);
  }
#pragma omp parallel for schedule(static) reduction(min : offz) if (nn > 65536)
  for (size_t i = 0; i < nn; i++)
    if (out->xyz[3 * i + 2] != 0.0 && i < offz) offz = i;
  if (offz != SIZE_MAX)
    return fail(r, arr_at(r, &P->pts, 3 * offz + 2),
                "point %zu has z = %g: a mesh of triangles and "
                "quadrilaterals is read as a 2D mesh, in the plane z = 0",
                offz, out->xyz[3 * offz + 2]);
  out->face_nn = mx_alloc(nc + 1);
  out->face_conn = mx_alloc((4 * nc + 1) * sizeof *out->face_conn);
  out->face_tag = mx_calloc((nc + 1) * sizeof *out->face_tag);
  if (!out->face_nn || !out->face_conn || !out->face_tag) return MX_EINPUT;
#pragma omp parallel for schedule(static) if (nc > 65536)
  for (size_t c = 0; c < nc; c++) {
    const int k = any_nodes[out->type[c]];
    out->face_nn[c] = (uint8_t)k;
    for (int j = 0; j < 4; j++)
      out->face_conn[4 * c + (size_t)j] = j < k ? out->conn[8 * c + (size_t)j] : 0;
  }
  out->nfaces = nc;
  out->ncells = 0;
  mx_free(out->type);
  mx_free(out->conn);
  out->type = NULL;
  out->conn = NULL;
  return MX_OK;
}

static int assemble(rd *r, parts *P, mx_mesh_data *out) {
  const size_t nn = P->nnodes, nc = P->ncells;
  if (nn >= UINT32_MAX)
    return fail(r, NULL, "%zu points: at most %u are supported", nn,
                UINT32_MAX - 1);
  out->nnodes = nn;
  out->ncells = nc;
  /* Points. */
  out->xyz = mx_alloc(3 * nn * sizeof(double));
  if (!out->xyz) return MX_EINPUT;
  const rawarr *pa = &P->pts;
  size_t bad = SIZE_MAX;
  if (pa->t == T_F64 && !pa->swap) {
    memcpy(out->xyz, pa->data, 24 * nn);
  } else {
#pragma omp parallel for schedule(static) if (nn > 65536)
    for (size_t i = 0; i < 3 * nn; i++) out->xyz[i] = raw_double(pa, i);
  }
#pragma omp parallel for schedule(static) reduction(min : bad) if (nn > 65536)
  for (size_t i = 0; i < 3 * nn; i++)
    if (!isfinite(out->xyz[i]) && i < bad) bad = i;
  if (bad != SIZE_MAX)
    return fail(r, arr_at(r, pa, bad),
                "point %zu: coordinate %zu is not a finite number", bad / 3,
                bad % 3);
  /* Types. */
  out->type = mx_alloc(nc);
  if (!out->type) return MX_EINPUT;
#pragma omp parallel for schedule(static) reduction(min : bad) if (nc > 65536)
  for (size_t c = 0; c < nc; c++) {
    int t = vtk_to_mx(raw_int(&P->types, c), r->planar);
    out->type[c] = (uint8_t)(t < 0 ? 0 : t);
    if (t < 0 && c < bad) bad = c;
  }
  if (bad != SIZE_MAX)
    return fail(r, arr_at(r, &P->types, bad),
                "cell %zu has VTK type %lld: only tetrahedra (10), pyramids "
                "(14), wedges (13) and hexahedra (12)%s are supported",
                bad, (long long)raw_int(&P->types, bad),
                r->planar ? ", or triangles (5) and quadrilaterals (9) in "
                            "the plane z = 0 (a 2D mesh)," : "");
  /* Connectivity. */
  if (P->list_form) {
#pragma omp parallel for schedule(static) reduction(min : bad) if (nc > 65536)
    for (size_t c = 0; c < nc; c++)
      if (P->nn[c] != any_nodes[out->type[c]] && c < bad) bad = c;
    if (bad != SIZE_MAX)
      return fail(r, arr_at(r, &P->types, bad),
                  "cell %zu (%s) has %d nodes, expected %d", bad,
                  type_word[out->type[bad]], P->nn[bad],
                  any_nodes[out->type[bad]]);
  } else {
    out->conn = mx_alloc(8 * nc * sizeof(uint32_t));
    if (!out->conn) return MX_EINPUT;
#pragma omp parallel for schedule(static) reduction(min : bad) if (nc > 65536)
    for (size_t c = 0; c < nc; c++)
      if (offset_cell(P, c, out->type[c], out->conn + 8 * c, NULL) && c < bad)
        bad = c;
    if (bad != SIZE_MAX) {
      char msg[MSG];
      offset_cell(P, bad, out->type[bad], out->conn + 8 * bad, msg);
      return fail(r, arr_at(r, &P->off, bad), "%s", msg);
    }
    int64_t last = nc ? raw_int(&P->off, P->vtu_offsets ? nc - 1 : nc) : 0;
    if (!P->vtu_offsets && raw_int(&P->off, 0) != 0)
      return fail(r, NULL, "OFFSETS: the first offset is %lld, expected 0",
                  (long long)raw_int(&P->off, 0));
    if ((uint64_t)last != P->cn.n)
      return fail(r, NULL,
                  "the connectivity has %zu entries but the cells use %lld",
                  P->cn.n, (long long)last);
  }
  /* Node indices. */
#pragma omp parallel for schedule(static) reduction(min : bad) if (nc > 65536)
  for (size_t c = 0; c < nc; c++) {
    const uint32_t *row = out->conn + 8 * c;
    for (int j = 0; j < any_nodes[out->type[c]]; j++)
      if (row[j] >= nn && c < bad) bad = c;
  }
  if (bad != SIZE_MAX) {
    const uint32_t *row = out->conn + 8 * bad;
    uint32_t v = 0;
    for (int j = 0; j < any_nodes[out->type[bad]]; j++)
      if (row[j] >= nn) {
        v = row[j];
        break;
      }
    return fail(r, NULL,
                "cell %zu uses node %u, but there are %zu points (0-based "
                "indices)",
                bad, v, nn);
  }
  return r->planar ? planar_cells(r, P, out) : MX_OK;
}

/* The point field surface_tag from its raw values (one per node). */
static int node_tags_from(rd *r, const rawarr *a, mx_mesh_data *out) {
  const size_t n = out->nnodes;
  out->node_tag = mx_alloc((n + 1) * sizeof *out->node_tag);
  if (!out->node_tag) return MX_EINPUT;
  for (size_t i = 0; i < n; i++) {
    const int64_t v = raw_int(a, i);
    if (v < INT32_MIN || v > INT32_MAX || (a->t == T_U64 && v < 0))
      return fail(r, arr_at(r, a, i),
                  "surface_tag: value %zu is out of range (32-bit integers)",
                  i);
    out->node_tag[i] = (int32_t)v;
  }
  return MX_OK;
}

/* ---- legacy VTK ---------------------------------------------------------- */

typedef struct {
  rd *r;
  int binary, v5;
  const char *p;
  parts P;
  int have_points, have_cells, have_types;
  int have_node_tags;
  rawarr node_tags; /* the point field surface_tag */
  mx_mesh_data *out;
} legacy;

/* The next blank-separated token (may be empty at the end of the file). */
static const char *leg_token(legacy *L, size_t *n) {
  L->p = skip_ws(L->p, L->r->end);
  const char *t = L->p;
  *n = tok_len(t, L->r->end);
  L->p += *n;
  return t;
}

/* A count token: 1 and *v, or 0 (nothing printed) when it is not one. */
static int leg_count_q(legacy *L, size_t *v) {
  size_t n;
  const char *t = leg_token(L, &n);
  size_t x = 0;
  for (size_t i = 0; i < n; i++) {
    if (t[i] < '0' || t[i] > '9' || x > ((size_t)1 << 50)) return 0;
    x = 10 * x + (size_t)(t[i] - '0');
  }
  *v = x;
  return n > 0;
}

static int leg_count(legacy *L, size_t *v, const char *what) {
  const char *t = skip_ws(L->p, L->r->end);
  if (leg_count_q(L, v)) return MX_OK;
  const size_t n = tok_len(t, L->r->end);
  if (n == 0) return fail(L->r, t, "%s: missing count", what);
  return fail(L->r, t, "%s: bad count '%.*s'", what, shown(n), t);
}

/* Binary data starts after the newline that ends the section header. */
static int leg_data_start(legacy *L, const char *what) {
  if (!L->binary) return MX_OK;
  const char *p = L->p, *end = L->r->end;
  while (p < end && (*p == ' ' || *p == '\t' || *p == '\r')) p++;
  if (p < end && *p != '\n')
    return fail(L->r, p, "%s: unexpected '%.*s' after the section header",
                what, shown(tok_len(p, end)), p);
  L->p = p < end ? p + 1 : p;
  if (!L->r->bin_from) L->r->bin_from = L->p;
  return MX_OK;
}

static vtype legacy_type(const char *t, size_t n) {
  static const struct {
    const char *name;
    vtype t;
  } map[] = {{"float", T_F32},          {"double", T_F64},
             {"int", T_I32},            {"unsigned_int", T_U32},
             {"short", T_I16},          {"unsigned_short", T_U16},
             {"char", T_I8},            {"unsigned_char", T_U8},
             {"long", T_I64},           {"unsigned_long", T_U64},
             {"vtktypeint64", T_I64},   {"vtktypeuint64", T_U64},
             {"vtktypeint32", T_I32},   {"vtktypeuint32", T_U32},
             {"vtkIdType", T_I32}};
  for (size_t i = 0; i < sizeof map / sizeof map[0]; i++)
    if (tok_eq(t, n, map[i].name)) return map[i].t;
  return T_NONE;
}

/* n values of type t: in place (binary) or parsed (ASCII). */
static int leg_array(legacy *L, size_t n, vtype t, rawarr *out,
                     const char *what) {
  MX_CHECK(leg_data_start(L, what));
  if (!L->binary)
    return ascii_array(L->r, &L->p, 0, n, is_float(t), out, what);
  size_t left = (size_t)(L->r->end - L->p);
  if (n > left / (size_t)vsize[t])
    return fail(L->r, L->p,
                "%s: %zu values of %d bytes announced but only %zu bytes are "
                "left (truncated file or wrong count)",
                what, n, vsize[t], left);
  *out = (rawarr){(const unsigned char *)L->p, n, t, HOST_LE, NULL};
  L->p += n * (size_t)vsize[t];
  return MX_OK;
}

static int leg_points(legacy *L) {
  size_t n, tl;
  MX_CHECK(leg_count(L, &n, "POINTS"));
  const char *t = leg_token(L, &tl);
  vtype vt = legacy_type(t, tl);
  if (!is_float(vt))
    return fail(L->r, t,
                "POINTS: type '%.*s' is not supported (float or double)",
                shown(tl), t);
  if (L->have_points) return fail(L->r, t, "POINTS given twice");
  L->have_points = 1;
  L->P.nnodes = n;
  if (n >= UINT32_MAX)
    return fail(L->r, t, "POINTS: %zu points, at most %u are supported", n,
                UINT32_MAX - 1);
  return leg_array(L, 3 * n, vt, &L->P.pts, "POINTS");
}

/* One integer of the classic CELLS list. */
static inline int leg_int(legacy *L, int64_t *v, size_t cell) {
  if (L->binary) { /* bounds checked by the caller */
    *v = (int32_t)(uint32_t)load_bits((const unsigned char *)L->p, 4, HOST_LE);
    L->p += 4;
    return MX_OK;
  }
  const char *p = skip_ws(L->p, L->r->end);
  if (p >= L->r->end || !*p)
    return fail(L->r, p, "CELLS: unexpected end of file in cell %zu", cell);
  const char *e = mx_io_int(p, v);
  size_t tl = tok_len(p, L->r->end);
  if (!e || e != p + tl)
    return fail(L->r, p, "CELLS: cell %zu: '%.*s' is not an integer", cell,
                shown(tl), p);
  L->p = e;
  return MX_OK;
}

static int leg_cell_list(legacy *L, size_t size) {
  rd *r = L->r;
  const size_t nc = L->P.ncells;
  MX_CHECK(leg_data_start(L, "CELLS"));
  size_t left = (size_t)(r->end - L->p);
  if (L->binary ? size > left / 4 : size > left / 2 + 1)
    return fail(r, L->p,
                "CELLS: %zu values announced but the file is too short "
                "(truncated file or wrong count)",
                size);
  if (nc > size / 2) /* each cell takes its count and at least one node */
    return fail(r, L->p, "CELLS: %zu cells cannot fit in %zu values", nc,
                size);
  L->out->conn = mx_calloc(8 * nc * sizeof(uint32_t));
  L->P.nn = rd_alloc(r, nc);
  if (!L->out->conn || !L->P.nn) return MX_EINPUT;
  size_t used = 0;
  for (size_t c = 0; c < nc; c++) {
    const char *at = skip_ws(L->p, r->end);
    if (used >= size)
      return fail(r, at, "CELLS: the size %zu is used up before cell %zu",
                  size, c);
    int64_t k;
    MX_CHECK(leg_int(L, &k, c));
    if (k < 1 || k > 8)
      return fail(r, at,
                  "cell %zu has %lld nodes: only tetrahedra, pyramids, "
                  "wedges and hexahedra are supported",
                  c, (long long)k);
    if ((size_t)k > size - used - 1)
      return fail(r, at, "CELLS: cell %zu runs past the size %zu", c, size);
    uint32_t *row = L->out->conn + 8 * c;
    for (int64_t j = 0; j < k; j++) {
      at = skip_ws(L->p, r->end);
      int64_t v;
      MX_CHECK(leg_int(L, &v, c));
      if (v < 0 || v >= (int64_t)UINT32_MAX ||
          (L->have_points && (uint64_t)v >= L->P.nnodes))
        return fail(r, at,
                    "cell %zu: node index %lld out of range (%zu points, "
                    "0-based)",
                    c, (long long)v, L->P.nnodes);
      row[j] = (uint32_t)v;
    }
    L->P.nn[c] = (uint8_t)k;
    used += 1 + (size_t)k;
  }
  if (used != size)
    return fail(r, L->p, "CELLS: size %zu, but the cells use %zu values", size,
                used);
  L->P.list_form = 1;
  return MX_OK;
}

/* Version 5: CELLS noffsets nconn, then OFFSETS and CONNECTIVITY arrays. */
static int leg_cell_arrays(legacy *L, size_t noff, size_t nconn) {
  static const char *const kw[2] = {"OFFSETS", "CONNECTIVITY"};
  rawarr *dst[2] = {&L->P.off, &L->P.cn};
  const size_t n[2] = {noff, nconn};
  for (int i = 0; i < 2; i++) {
    size_t tl;
    const char *t = leg_token(L, &tl);
    if (!tok_eq(t, tl, kw[i]))
      return fail(L->r, t, "expected %s, found '%.*s'", kw[i], shown(tl), t);
    t = leg_token(L, &tl);
    vtype vt = legacy_type(t, tl);
    if (vt == T_NONE || is_float(vt))
      return fail(L->r, t, "%s: type '%.*s' is not an integer type", kw[i],
                  shown(tl), t);
    MX_CHECK(leg_array(L, n[i], vt, dst[i], kw[i]));
  }
  L->P.ncells = noff ? noff - 1 : 0;
  L->P.vtu_offsets = 0;
  if (noff == 0) { /* no cells at all */
    static const int64_t zero = 0;
    L->P.off = (rawarr){(const unsigned char *)&zero, 1, T_I64, 0, NULL};
  }
  return MX_OK;
}

static int leg_cells(legacy *L) {
  size_t a, b;
  const char *at = skip_ws(L->p, L->r->end);
  MX_CHECK(leg_count(L, &a, "CELLS"));
  MX_CHECK(leg_count(L, &b, "CELLS"));
  if (L->have_cells) return fail(L->r, at, "CELLS given twice");
  L->have_cells = 1;
  if (L->v5) return leg_cell_arrays(L, a, b);
  L->P.ncells = a;
  return leg_cell_list(L, b);
}

static int leg_types(legacy *L) {
  size_t n;
  const char *at = skip_ws(L->p, L->r->end);
  MX_CHECK(leg_count(L, &n, "CELL_TYPES"));
  if (!L->have_cells) return fail(L->r, at, "CELL_TYPES before CELLS");
  if (L->have_types) return fail(L->r, at, "CELL_TYPES given twice");
  if (n != L->P.ncells)
    return fail(L->r, at, "CELL_TYPES: %zu types for %zu cells", n,
                L->P.ncells);
  L->have_types = 1;
  return leg_array(L, n, T_I32, &L->P.types, "CELL_TYPES");
}

/* METADATA blocks end at the first empty line. */
static void leg_skip_metadata(legacy *L) {
  const char *p = L->p, *end = L->r->end;
  p = memchr(p, '\n', (size_t)(end - p));
  while (p && p < end) {
    const char *q = p + 1;
    while (q < end && (*q == ' ' || *q == '\t' || *q == '\r')) q++;
    if (q >= end || *q == '\n') {
      L->p = q;
      return;
    }
    p = memchr(q, '\n', (size_t)(end - q));
  }
  L->p = end;
}

/* FIELD name n, then n arrays "name ncomp ntuples type" + values. */
static int leg_skip_field(legacy *L) {
  size_t tl, narr;
  leg_token(L, &tl); /* the field's name */
  MX_CHECK(leg_count(L, &narr, "FIELD"));
  for (size_t i = 0; i < narr; i++) {
    const char *name = leg_token(L, &tl);
    if (tok_eq(name, tl, "NULL_ARRAY")) continue;
    size_t nc, nt;
    MX_CHECK(leg_count(L, &nc, "FIELD array"));
    MX_CHECK(leg_count(L, &nt, "FIELD array"));
    const char *t = leg_token(L, &tl);
    vtype vt = legacy_type(t, tl);
    if (vt == T_NONE)
      return fail(L->r, t, "FIELD array of type '%.*s' cannot be skipped",
                  shown(tl), t);
    if (nt && nc > SIZE_MAX / 16 / nt)
      return fail(L->r, t, "FIELD array: bad size");
    if (L->binary) {
      rawarr dummy;
      MX_CHECK(leg_array(L, nc * nt, vt, &dummy, "FIELD array"));
    } else {
      for (size_t k = 0; k < nc * nt; k++) {
        const char *v = leg_token(L, &tl);
        if (tl == 0)
          return fail(L->r, v, "FIELD array: unexpected end of file");
      }
    }
    const char *save = L->p;
    const char *kwd = leg_token(L, &tl);
    if (tok_eq(kwd, tl, "METADATA"))
      leg_skip_metadata(L);
    else
      L->p = save;
  }
  return MX_OK;
}

/* ---- legacy attributes: only the point field surface_tag is read ---------- */

/* Steps over n values of type t (binary: after the end of the header
 * line); 0, nothing printed, when they are not all there. */
static int leg_skip_values(legacy *L, size_t n, vtype t) {
  const char *p = L->p, *end = L->r->end;
  if (!L->binary) {
    for (size_t k = 0; k < n; k++) {
      size_t tl;
      leg_token(L, &tl);
      if (tl == 0) return 0;
    }
    return 1;
  }
  while (p < end && (*p == ' ' || *p == '\t' || *p == '\r')) p++;
  if (p >= end || *p != '\n') return 0;
  p++;
  if (n > (size_t)(end - p) / (size_t)vsize[t]) return 0;
  L->p = p + n * (size_t)vsize[t];
  return 1;
}

/* The values of surface_tag: n integers of type t for the points. */
static int leg_node_tags(legacy *L, const char *at, size_t n, vtype t) {
  if (L->have_node_tags) return fail(L->r, at, "surface_tag given twice");
  if (n != L->P.nnodes)
    return fail(L->r, at, "surface_tag: %zu values for %zu points", n,
                L->P.nnodes);
  L->have_node_tags = 1;
  return leg_array(L, n, t, &L->node_tags, "surface_tag");
}

/* Whether the attribute `name` of type t with ncomp components is the
 * point field surface_tag. */
static int is_surface_tag(int point, const char *name, size_t nl, vtype t,
                          size_t ncomp) {
  return point && ncomp == 1 && t != T_NONE && !is_float(t) &&
         tok_eq(name, nl, "surface_tag");
}

/* The attribute sections from the keyword t on (CELL_DATA n or POINT_DATA
 * n, then SCALARS, VECTORS, NORMALS, FIELD, METADATA): skipped but for
 * surface_tag. Any other keyword, or a malformed header, ends them
 * silently (they used to be ignored whole); surface_tag itself must be
 * well formed. */
static int leg_attributes(legacy *L, const char *t, size_t tl) {
  int point = 0;
  size_t count = 0;
  for (;; t = leg_token(L, &tl)) {
    if (tok_eq(t, tl, "CELL_DATA") || tok_eq(t, tl, "POINT_DATA")) {
      point = tok_eq(t, tl, "POINT_DATA");
      if (!leg_count_q(L, &count)) return MX_OK;
    } else if (tok_eq(t, tl, "SCALARS")) {
      size_t nl, yl, k = 1, ncomp = 1;
      const char *name = leg_token(L, &nl);
      const char *ty = leg_token(L, &yl);
      const vtype vt = legacy_type(ty, yl);
      if (vt == T_NONE) return MX_OK;
      const char *save = L->p, *q = L->p; /* a count on the same line */
      while (q < L->r->end && (*q == ' ' || *q == '\t')) q++;
      if (q < L->r->end && *q >= '0' && *q <= '9' && leg_count_q(L, &k) &&
          k >= 1 && k <= 4)
        ncomp = k;
      else
        L->p = save;
      save = L->p;
      const char *lt = leg_token(L, &k);
      if (tok_eq(lt, k, "LOOKUP_TABLE"))
        leg_token(L, &k);
      else
        L->p = save;
      if (is_surface_tag(point, name, nl, vt, ncomp)) {
        MX_CHECK(leg_node_tags(L, name, count, vt));
      } else if (count > SIZE_MAX / 16 / ncomp ||
                 !leg_skip_values(L, count * ncomp, vt)) {
        return MX_OK;
      }
    } else if (tok_eq(t, tl, "VECTORS") || tok_eq(t, tl, "NORMALS")) {
      size_t nl, yl;
      leg_token(L, &nl);
      const char *ty = leg_token(L, &yl);
      const vtype vt = legacy_type(ty, yl);
      if (vt == T_NONE || count > SIZE_MAX / 16 ||
          !leg_skip_values(L, 3 * count, vt))
        return MX_OK;
    } else if (tok_eq(t, tl, "FIELD")) {
      size_t nl, narr;
      leg_token(L, &nl); /* the field's name */
      if (!leg_count_q(L, &narr)) return MX_OK;
      for (size_t i = 0; i < narr; i++) {
        size_t nc, nt, yl;
        const char *name = leg_token(L, &nl);
        if (tok_eq(name, nl, "NULL_ARRAY")) continue;
        if (!leg_count_q(L, &nc) || !leg_count_q(L, &nt)) return MX_OK;
        const char *ty = leg_token(L, &yl);
        const vtype vt = legacy_type(ty, yl);
        if (vt == T_NONE) return MX_OK;
        if (is_surface_tag(point, name, nl, vt, nc)) {
          MX_CHECK(leg_node_tags(L, name, nt, vt));
        } else if ((nt && nc > SIZE_MAX / 16 / nt) ||
                   !leg_skip_values(L, nc * nt, vt)) {
          return MX_OK;
        }
        const char *save = L->p;
        const char *kwd = leg_token(L, &nl);
        if (tok_eq(kwd, nl, "METADATA"))
          leg_skip_metadata(L);
        else
          L->p = save;
      }
    } else if (tok_eq(t, tl, "METADATA")) {
      leg_skip_metadata(L);
    } else {
      return MX_OK; /* the end, or an attribute not read */
    }
  }
}

static int read_legacy(rd *r, mx_mesh_data *out) {
  legacy L;
  memset(&L, 0, sizeof L);
  L.r = r;
  L.out = out;
  const char *end = r->end;
  /* Line 1: "# vtk DataFile Version x.y". */
  const char *p = skip_ws(r->buf, end);
  static const char magic[] = "# vtk DataFile Version";
  const size_t ml = sizeof magic - 1;
  if ((size_t)(end - p) < ml || strncasecmp(p, magic, ml) != 0)
    return fail(r, p, "expected '%s x.y' on the first line", magic);
  const char *v = p + ml;
  while (v < end && (*v == ' ' || *v == '\t')) v++;
  int major = 0;
  while (v < end && *v >= '0' && *v <= '9' && major < 1000)
    major = 10 * major + (*v++ - '0');
  L.v5 = major >= 5;
  /* Line 2: the title; line 3: ASCII or BINARY. */
  const char *nl = memchr(p, '\n', (size_t)(end - p));
  nl = nl ? memchr(nl + 1, '\n', (size_t)(end - nl - 1)) : NULL;
  if (!nl) return fail(r, p, "truncated header (no title line)");
  L.p = nl + 1;
  size_t tl;
  const char *t = leg_token(&L, &tl);
  if (tok_eq(t, tl, "BINARY"))
    L.binary = 1;
  else if (!tok_eq(t, tl, "ASCII"))
    return fail(r, t, "expected ASCII or BINARY, found '%.*s'", shown(tl), t);
  t = leg_token(&L, &tl);
  if (!tok_eq(t, tl, "DATASET"))
    return fail(r, t, "expected DATASET, found '%.*s'", shown(tl), t);
  t = leg_token(&L, &tl);
  if (!tok_eq(t, tl, "UNSTRUCTURED_GRID"))
    return fail(r, t, "DATASET %.*s: only UNSTRUCTURED_GRID is supported",
                shown(tl), t);
  for (;;) {
    t = leg_token(&L, &tl);
    if (tl == 0) {
      if (t < end)
        return fail(r, t, "unexpected NUL byte (binary data in an ASCII "
                          "file, or a wrong count)");
      break;
    }
    if (tok_eq(t, tl, "POINTS")) {
      MX_CHECK(leg_points(&L));
    } else if (tok_eq(t, tl, "CELLS")) {
      MX_CHECK(leg_cells(&L));
    } else if (tok_eq(t, tl, "CELL_TYPES")) {
      MX_CHECK(leg_types(&L));
    } else if (tok_eq(t, tl, "FIELD")) {
      MX_CHECK(leg_skip_field(&L));
    } else if (tok_eq(t, tl, "METADATA")) {
      leg_skip_metadata(&L);
    } else if (tok_eq(t, tl, "CELL_DATA") || tok_eq(t, tl, "POINT_DATA")) {
      MX_CHECK(leg_attributes(&L, t, tl));
      break;
    } else {
      return fail(r, t, "unexpected '%.*s' (expected POINTS, CELLS or "
                  "CELL_TYPES)", shown(tl), t);
    }
  }
  if (!L.have_points) return fail(r, NULL, "no POINTS section");
  if (!L.have_cells) return fail(r, NULL, "no CELLS section");
  if (!L.have_types) return fail(r, NULL, "no CELL_TYPES section");
  MX_CHECK(assemble(r, &L.P, out));
  return L.have_node_tags ? node_tags_from(r, &L.node_tags, out) : MX_OK;
}

/* ---- VTU ----------------------------------------------------------------- */

typedef struct {
  const char *start, *name, *a, *ae, *after;
  size_t nlen;
  int closing, selfclose;
} xtag;

/* The next element tag at or after p; *found = 0 at the end. */
static int xml_next(const rd *r, const char *p, xtag *t, int *found) {
  const char *end = r->end;
  for (;;) {
    const char *lt = p < end ? memchr(p, '<', (size_t)(end - p)) : NULL;
    if (!lt) {
      *found = 0;
      return MX_OK;
    }
    size_t left = (size_t)(end - lt);
    if (left >= 2 && lt[1] == '?') {
      const char *q = memmem(lt, left, "?>", 2);
      if (!q) return fail(r, lt, "unterminated '<?'");
      p = q + 2;
      continue;
    }
    if (left >= 4 && memcmp(lt, "<!--", 4) == 0) {
      const char *q = memmem(lt, left, "-->", 3);
      if (!q) return fail(r, lt, "unterminated comment");
      p = q + 3;
      continue;
    }
    if (left >= 2 && lt[1] == '!') {
      const char *q = memchr(lt, '>', left);
      if (!q) return fail(r, lt, "unterminated '<!'");
      p = q + 1;
      continue;
    }
    t->start = lt;
    t->closing = left >= 2 && lt[1] == '/';
    t->name = lt + 1 + t->closing;
    const char *q = t->name;
    while (q < end && !is_ws(*q) && *q != '/' && *q != '>' && *q) q++;
    t->nlen = (size_t)(q - t->name);
    if (t->nlen == 0) return fail(r, lt, "malformed XML tag");
    t->a = q;
    char quote = 0;
    while (q < end && (quote || *q != '>')) {
      if (quote && *q == quote)
        quote = 0;
      else if (!quote && (*q == '"' || *q == '\''))
        quote = *q;
      q++;
    }
    if (q >= end)
      return fail(r, lt, "unterminated tag <%.*s", shown(t->nlen), t->name);
    t->selfclose = q[-1] == '/';
    t->ae = t->selfclose ? q - 1 : q;
    t->after = q + 1;
    *found = 1;
    return MX_OK;
  }
}

static int tag_is(const xtag *t, const char *name) {
  return t->nlen == strlen(name) && memcmp(t->name, name, t->nlen) == 0;
}

static int xml_attr(const xtag *t, const char *name, const char **v,
                    size_t *vn) {
  const char *p = t->a, *ae = t->ae;
  const size_t nl = strlen(name);
  while (p < ae) {
    while (p < ae && is_ws(*p)) p++;
    const char *ns = p;
    while (p < ae && *p != '=' && !is_ws(*p)) p++;
    size_t n = (size_t)(p - ns);
    while (p < ae && is_ws(*p)) p++;
    if (p >= ae || *p != '=') return 0;
    p++;
    while (p < ae && is_ws(*p)) p++;
    if (p >= ae || (*p != '"' && *p != '\'')) return 0;
    char q = *p++;
    const char *vs = p;
    while (p < ae && *p != q) p++;
    if (p >= ae) return 0;
    if (n == nl && memcmp(ns, name, n) == 0) {
      *v = vs;
      *vn = (size_t)(p - vs);
      return 1;
    }
    p++;
  }
  return 0;
}

static int attr_eq(const xtag *t, const char *name, const char *value) {
  const char *v;
  size_t n;
  return xml_attr(t, name, &v, &n) && n == strlen(value) &&
         memcmp(v, value, n) == 0;
}

/* A non-negative integer attribute; *v untouched when absent and optional. */
static int attr_size(const rd *r, const xtag *t, const char *name,
                     uint64_t *v, int required) {
  const char *s;
  size_t n;
  if (!xml_attr(t, name, &s, &n)) {
    if (!required) return MX_OK;
    return fail(r, t->start, "<%.*s> has no %s attribute", shown(t->nlen),
                t->name, name);
  }
  uint64_t x = 0;
  size_t i = 0;
  while (i < n && is_ws(s[i])) i++;
  if (i == n) return fail(r, s, "%s=\"\" is not a number", name);
  for (; i < n && !is_ws(s[i]); i++) {
    if (s[i] < '0' || s[i] > '9' || x > ((uint64_t)1 << 56))
      return fail(r, s, "%s=\"%.*s\" is not a valid count", name, shown(n),
                  s);
    x = 10 * x + (uint64_t)(s[i] - '0');
  }
  *v = x;
  return MX_OK;
}

typedef struct {
  int present, appended;
  vtype t;
  uint64_t ncomp, offset;
  const char *tag, *text;
} xarr;

static int parse_data_array(const rd *r, const xtag *t, xarr *x) {
  const char *v;
  size_t n;
  x->present = 1;
  x->tag = t->start;
  x->t = T_NONE;
  if (!xml_attr(t, "type", &v, &n))
    return fail(r, t->start, "<DataArray> has no type attribute");
  for (int k = 0; k < T_NONE; k++)
    if (n == strlen(vtu_type_name[k]) && memcmp(v, vtu_type_name[k], n) == 0)
      x->t = (vtype)k;
  if (x->t == T_NONE)
    return fail(r, t->start, "<DataArray> type \"%.*s\" is not supported",
                shown(n), v);
  x->ncomp = 1;
  MX_CHECK(attr_size(r, t, "NumberOfComponents", &x->ncomp, 0));
  if (!xml_attr(t, "format", &v, &n))
    return fail(r, t->start, "<DataArray> has no format attribute");
  if (n == 8 && memcmp(v, "appended", 8) == 0) {
    x->appended = 1;
    return attr_size(r, t, "offset", &x->offset, 1);
  }
  if (n == 5 && memcmp(v, "ascii", 5) == 0) {
    if (t->selfclose) return fail(r, t->start, "empty ascii <DataArray/>");
    x->text = t->after;
    return MX_OK;
  }
  return fail(r, t->start,
              "<DataArray> format \"%.*s\" is not supported (appended raw or "
              "ascii only)",
              shown(n), v);
}

typedef struct {
  int swap, hsize;
  const char *base; /* first byte after '_' */
} vtu_layout;

/* The values of x; want is the expected count (SIZE_MAX: any, appended
 * only). */
static int resolve(rd *r, const xarr *x, const vtu_layout *lay, size_t want,
                   rawarr *out, const char *what) {
  if (!x->appended) {
    const char *p = x->text;
    MX_CHECK(ascii_array(r, &p, '<', want, is_float(x->t), out, what));
    p = skip_ws(p, r->end);
    if (p < r->end && *p != '<')
      return fail(r, p, "%s: more than the %zu expected values", what, want);
    return MX_OK;
  }
  if (!lay->base)
    return fail(r, x->tag, "%s: format=\"appended\" without <AppendedData>",
                what);
  const size_t avail = (size_t)(r->end - lay->base);
  if (x->offset > avail || avail - x->offset < (size_t)lay->hsize)
    return fail(r, x->tag,
                "%s: appended offset %llu lies past the end of the file "
                "(truncated file?)",
                what, (unsigned long long)x->offset);
  const unsigned char *at = (const unsigned char *)lay->base + x->offset;
  uint64_t nbytes = load_bits(at, lay->hsize, lay->swap);
  const size_t room = avail - x->offset - (size_t)lay->hsize;
  const size_t es = (size_t)vsize[x->t];
  if (nbytes > room)
    return fail(r, (const char *)at,
                "%s: block of %llu bytes but only %zu are left (truncated "
                "file?)",
                what, (unsigned long long)nbytes, room);
  if (nbytes % es)
    return fail(r, (const char *)at,
                "%s: block of %llu bytes is not a whole number of %s values",
                what, (unsigned long long)nbytes, vtu_type_name[x->t]);
  size_t n = (size_t)nbytes / es;
  if (want != SIZE_MAX && n != want)
    return fail(r, (const char *)at, "%s: %zu values, expected %zu", what, n,
                want);
  *out = (rawarr){at + lay->hsize, n, x->t, lay->swap, NULL};
  return MX_OK;
}

static int read_pvtu(rd *r, const char *p, mx_mesh_data *out);

/* One point or cell array for a piece's signature (read_pvtu compares
 * them): a hash of its section, type and name, summed over the arrays. */
static uint64_t array_sig(const xtag *t) {
  const char *v;
  size_t n;
  uint64_t h = 0xcbf29ce484222325ull; /* FNV-1a, then a finaliser */
  for (int k = 0; k < 2; k++) {
    if (!xml_attr(t, k ? "Name" : "type", &v, &n)) n = 0;
    for (size_t i = 0; i < n; i++) h = (h ^ (unsigned char)v[i]) * 0x100000001b3ull;
    h = (h ^ 0x100) * 0x100000001b3ull;
  }
  h = (h ^ (h >> 30)) * 0xbf58476d1ce4e5b9ull;
  h = (h ^ (h >> 27)) * 0x94d049bb133111ebull;
  return h ^ (h >> 31);
}

/* A piece's GlobalNodeId (one non-negative integer per point). */
static int piece_ids(rd *r, const xarr *x, const vtu_layout *lay, size_t nnodes) {
  if (is_float(x->t) || x->ncomp != 1)
    return fail(r, x->tag, "GlobalNodeId: expected one component of an integer type");
  rawarr a;
  MX_CHECK(resolve(r, x, lay, nnodes, &a, "GlobalNodeId"));
  uint64_t *gid = mx_alloc((nnodes + 1) * sizeof *gid);
  if (!gid) return MX_EINPUT;
  r->piece->gid = gid;
  size_t bad = SIZE_MAX;
#pragma omp parallel for schedule(static) reduction(min : bad) if (nnodes > 65536)
  for (size_t i = 0; i < nnodes; i++) {
    const int64_t v = raw_int(&a, i);
    gid[i] = (uint64_t)v;
    if (v < 0 && i < bad) bad = i;
  }
  if (bad != SIZE_MAX)
    return fail(r, arr_at(r, &a, bad), "GlobalNodeId: value %zu is negative or too large",
                bad);
  return MX_OK;
}

/* Whether the file's last non-blank bytes are the closing tag: a file cut
 * short (also in its raw appended data) lacks it. */
static int xml_closed(const rd *r, const char *tag) {
  const char *e = r->end;
  while (e > r->buf && (e[-1] == ' ' || e[-1] == '\t' || e[-1] == '\n' || e[-1] == '\r')) e--;
  const size_t n = strlen(tag);
  return (size_t)(e - r->buf) >= n && memcmp(e - n, tag, n) == 0;
}

static int vtkfile_closed(const rd *r) {
  if (xml_closed(r, "</VTKFile>")) return MX_OK;
  return fail(r, NULL, "the file does not end with </VTKFile>: it is cut short (an "
                       "interrupted write or copy?)");
}

static int read_vtu(rd *r, mx_mesh_data *out) {
  const char *p = r->buf, *end = r->end;
  int seen = 0, pieces = 0, in_points = 0, in_cells = 0, in_pdata = 0, in_cdata = 0;
  vtu_layout lay = {0, 4, NULL};
  xarr pts = {0}, con = {0}, offs = {0}, typ = {0}, ntag = {0}, gidx = {0};
  uint64_t npts = 0, ncells = 0;
  const char *piece_tag = NULL;
  for (;;) {
    xtag t;
    int found;
    MX_CHECK(xml_next(r, p, &t, &found));
    if (!found) break;
    p = t.after;
    if (tag_is(&t, "VTKFile")) {
      if (t.closing) break;
      seen = 1;
      if (attr_eq(&t, "type", "PUnstructuredGrid")) {
        if (r->piece)
          return fail(r, t.start, "a piece of a .pvtu must be an UnstructuredGrid file, not "
                      "another PUnstructuredGrid");
        MX_CHECK(vtkfile_closed(r));
        return read_pvtu(r, t.after, out);
      }
      if (!attr_eq(&t, "type", "UnstructuredGrid"))
        return fail(r, t.start,
                    "not an UnstructuredGrid VTK XML file (type attribute)");
      const int big = attr_eq(&t, "byte_order", "BigEndian");
      lay.swap = big == HOST_LE;
      if (attr_eq(&t, "header_type", "UInt64"))
        lay.hsize = 8;
      else if (xml_attr(&t, "header_type", &(const char *){0}, &(size_t){0}) &&
               !attr_eq(&t, "header_type", "UInt32"))
        return fail(r, t.start, "header_type must be UInt32 or UInt64");
      const char *cv;
      size_t cn;
      if (xml_attr(&t, "compressor", &cv, &cn) && cn > 0)
        return fail(r, t.start,
                    "compressed data (%.*s) is not supported: write the file "
                    "uncompressed",
                    shown(cn), cv);
      MX_CHECK(vtkfile_closed(r));
    } else if (!seen) {
      return fail(r, t.start, "expected <VTKFile>, found <%.*s>",
                  shown(t.nlen), t.name);
    } else if (tag_is(&t, "Piece")) {
      if (t.closing) continue;
      if (++pieces > 1)
        return fail(r, t.start, "more than one <Piece> is not supported");
      piece_tag = t.start;
      MX_CHECK(attr_size(r, &t, "NumberOfPoints", &npts, 1));
      MX_CHECK(attr_size(r, &t, "NumberOfCells", &ncells, 1));
    } else if (tag_is(&t, "Points")) {
      in_points = !t.closing && !t.selfclose;
    } else if (tag_is(&t, "Cells")) {
      in_cells = !t.closing && !t.selfclose;
    } else if (tag_is(&t, "PointData")) {
      in_pdata = !t.closing && !t.selfclose;
    } else if (tag_is(&t, "CellData")) {
      in_cdata = !t.closing && !t.selfclose;
    } else if (tag_is(&t, "DataArray") && !t.closing) {
      xarr *x = NULL;
      if (r->piece && in_pdata) r->piece->point_sig += array_sig(&t);
      if (r->piece && in_cdata) r->piece->cell_sig += array_sig(&t);
      if (r->piece && in_pdata && attr_eq(&t, "Name", "GlobalNodeId")) {
        if (gidx.present) return fail(r, t.start, "GlobalNodeId given twice");
        x = &gidx;
      } else if (in_pdata && attr_eq(&t, "Name", "surface_tag")) {
        if (ntag.present)
          return fail(r, t.start, "surface_tag given twice");
        x = &ntag;
      } else if (in_points && !pts.present)
        x = &pts;
      else if (in_cells && attr_eq(&t, "Name", "connectivity"))
        x = &con;
      else if (in_cells && attr_eq(&t, "Name", "offsets"))
        x = &offs;
      else if (in_cells && attr_eq(&t, "Name", "types"))
        x = &typ;
      if (x) MX_CHECK(parse_data_array(r, &t, x));
    } else if (tag_is(&t, "AppendedData") && !t.closing) {
      if (!attr_eq(&t, "encoding", "raw"))
        return fail(r, t.start,
                    "<AppendedData> encoding must be \"raw\" (base64 is not "
                    "supported)");
      const char *q = skip_ws(t.after, end);
      if (q >= end || *q != '_')
        return fail(r, q, "expected '_' at the start of the appended data");
      lay.base = q + 1;
      r->bin_from = lay.base;
      break;
    }
  }
  if (!seen) return fail(r, NULL, "no <VTKFile> element");
  if (!pieces) return fail(r, NULL, "no <Piece> element");
  if (!pts.present) return fail(r, piece_tag, "no <Points> DataArray");
  if (!is_float(pts.t) || pts.ncomp != 3)
    return fail(r, pts.tag,
                "Points: expected Float32 or Float64 with "
                "NumberOfComponents=\"3\"");
  if (npts >= UINT32_MAX || ncells > SIZE_MAX / 64)
    return fail(r, piece_tag, "too many points or cells");
  parts P;
  memset(&P, 0, sizeof P);
  P.nnodes = (size_t)npts;
  P.ncells = (size_t)ncells;
  P.vtu_offsets = 1;
  MX_CHECK(resolve(r, &pts, &lay, 3 * P.nnodes, &P.pts, "Points"));
  static const int64_t zero = 0;
  const rawarr none = {(const unsigned char *)&zero, 0, T_I64, 0, NULL};
  P.off = P.cn = P.types = none;
  if (ncells > 0 || con.present || offs.present || typ.present) {
    const char *names[3] = {"offsets", "types", "connectivity"};
    xarr *xs[3] = {&offs, &typ, &con};
    for (int i = 0; i < 3; i++) {
      if (!xs[i]->present)
        return fail(r, piece_tag, "no <Cells> DataArray Name=\"%s\"",
                    names[i]);
      if (is_float(xs[i]->t) || xs[i]->ncomp != 1)
        return fail(r, xs[i]->tag,
                    "%s: expected one component of an integer type",
                    names[i]);
    }
    MX_CHECK(resolve(r, &offs, &lay, P.ncells, &P.off, "offsets"));
    MX_CHECK(resolve(r, &typ, &lay, P.ncells, &P.types, "types"));
    size_t want = SIZE_MAX;
    if (!con.appended) {
      int64_t last = P.ncells ? raw_int(&P.off, P.ncells - 1) : 0;
      if (last < 0 || (uint64_t)last > 8 * (uint64_t)P.ncells)
        return fail(r, offs.tag, "offsets: the last offset %lld is invalid",
                    (long long)last);
      want = (size_t)last;
    }
    MX_CHECK(resolve(r, &con, &lay, want, &P.cn, "connectivity"));
  }
  rawarr tags;
  const int with_tags = ntag.present && !is_float(ntag.t) && ntag.ncomp == 1;
  if (with_tags)
    MX_CHECK(resolve(r, &ntag, &lay, P.nnodes, &tags, "surface_tag"));
  MX_CHECK(assemble(r, &P, out));
  if (gidx.present) MX_CHECK(piece_ids(r, &gidx, &lay, P.nnodes));
  return with_tags ? node_tags_from(r, &tags, out) : MX_OK;
}

/* ---- parallel VTU (.pvtu) -------------------------------------------------
 *
 * The master names its pieces (<Piece Source="..."/>, relative to its own
 * directory unless absolute); each is read as a VTU file on its own
 * (read_file with a piece_info), all pieces must have the same point and
 * cell arrays (names and types), and the pieces are merged: with
 * GlobalNodeId in every piece, the points of one id are one node (their
 * coordinates must agree bitwise), the nodes numbered by id; without it,
 * points of different pieces with bitwise-equal coordinates are one node
 * (within a piece points stay distinct: the k-th point of a piece at some
 * place joins the k-th of each other piece there), numbered in the order
 * they first appear. Both merges sort 64-bit keys (the ids, or a hash of
 * the coordinates), so time and memory are O(total size). Cells (and the
 * faces of a planar read) are concatenated in piece order; surface_tag
 * follows the node and must agree between the pieces sharing it. */

static int read_file(const char *path, int planar, piece_info *piece, mx_mesh_data *out);

typedef struct {
  const char *tag; /* its <Piece> element in the master, for messages */
  char *path;
  mx_mesh_data m;
  piece_info info;
} pvtu_piece;

typedef struct {
  pvtu_piece *pc;
  size_t n, cap;
  size_t *poff;            /* n + 1: points before each piece */
  double *xyz;             /* every piece's points, in piece order */
  int32_t *tag;            /* their surface_tag, or NULL */
  uint64_t *gid;           /* their GlobalNodeId, or NULL */
  uint32_t *map, *node_rep; /* point -> merged node; node -> one of its points */
  size_t npoints, nnodes;
} pvtu;

static void pvtu_free(pvtu *V) {
  for (size_t i = 0; i < V->n; i++) {
    mx_free(V->pc[i].path);
    mx_mesh_data_free(&V->pc[i].m);
    mx_free(V->pc[i].info.gid);
  }
  mx_free(V->pc);
  mx_free(V->poff);
  mx_free(V->xyz);
  mx_free(V->tag);
  mx_free(V->gid);
  mx_free(V->map);
  mx_free(V->node_rep);
  memset(V, 0, sizeof *V);
}

/* The file a <Piece> names: its Source with the XML entities undone, after
 * the master's directory unless it is absolute. */
static int piece_path(const rd *r, const xtag *t, char **path) {
  const char *v;
  size_t n;
  if (!xml_attr(t, "Source", &v, &n))
    return fail(r, t->start, "<Piece> has no Source attribute");
  if (n == 0) return fail(r, t->start, "<Piece Source=\"\"> names no file");
  if (memchr(v, '\0', n)) return fail(r, t->start, "<Piece> Source has a NUL byte");
  const char *slash = strrchr(r->path, '/');
  const size_t dl = v[0] == '/' || !slash ? 0 : (size_t)(slash + 1 - r->path);
  char *s = mx_alloc(dl + n + 1);
  if (!s) return MX_EINPUT;
  memcpy(s, r->path, dl);
  static const char *const ent[5][2] = {
      {"&amp;", "&"}, {"&lt;", "<"}, {"&gt;", ">"}, {"&quot;", "\""}, {"&apos;", "'"}};
  size_t w = dl;
  for (size_t i = 0; i < n;) {
    int k = 0;
    while (k < 5 && !(v[i] == '&' && n - i >= strlen(ent[k][0]) &&
                      memcmp(v + i, ent[k][0], strlen(ent[k][0])) == 0))
      k++;
    if (k < 5) {
      s[w++] = ent[k][1][0];
      i += strlen(ent[k][0]);
    } else {
      s[w++] = v[i++];
    }
  }
  s[w] = '\0';
  *path = s;
  return MX_OK;
}

/* The <Piece> elements of the master, from p on. */
static int pvtu_list_pieces(rd *r, const char *p, pvtu *V) {
  int grid = 0;
  for (;;) {
    xtag t;
    int found;
    MX_CHECK(xml_next(r, p, &t, &found));
    if (!found) break;
    p = t.after;
    if (tag_is(&t, "VTKFile") && t.closing) break;
    if (tag_is(&t, "PUnstructuredGrid") && !t.closing) grid = 1;
    if (!tag_is(&t, "Piece") || t.closing) continue;
    if (V->n == V->cap) {
      const size_t cap = V->cap ? 2 * V->cap : 16;
      pvtu_piece *pc = mx_realloc(V->pc, cap * sizeof *pc);
      if (!pc) return MX_EINPUT;
      V->pc = pc;
      V->cap = cap;
    }
    pvtu_piece *pc = &V->pc[V->n];
    memset(pc, 0, sizeof *pc);
    pc->tag = t.start;
    V->n++;
    MX_CHECK(piece_path(r, &t, &pc->path));
  }
  if (!grid) return fail(r, NULL, "no <PUnstructuredGrid> element");
  if (!V->n) return fail(r, NULL, "no <Piece> element: a .pvtu needs at least one piece");
  return MX_OK;
}

/* Reads every piece and checks that they agree. */
static int pvtu_read_pieces(rd *r, pvtu *V) {
  int faces = 0, cells = 0;
  for (size_t i = 0; i < V->n; i++) {
    pvtu_piece *pc = &V->pc[i];
    struct stat sb;
    if (stat(pc->path, &sb) != 0)
      return fail(r, pc->tag, "piece %zu: cannot read '%s': %s", i, pc->path, strerror(errno));
    if (!S_ISREG(sb.st_mode)) /* a directory, a device: nothing to read, or no end */
      return fail(r, pc->tag, "piece %zu: '%s' is not a regular file", i, pc->path);
    if (read_file(pc->path, r->planar, &pc->info, &pc->m) != MX_OK)
      return fail(r, pc->tag, "piece %zu ('%s') could not be read", i, pc->path);
    const pvtu_piece *p0 = &V->pc[0];
    if (pc->info.point_sig != p0->info.point_sig || pc->info.cell_sig != p0->info.cell_sig)
      return fail(r, pc->tag,
                  "piece %zu ('%s'): its %s arrays (names or types) differ from those of "
                  "piece 0 ('%s')",
                  i, pc->path, pc->info.point_sig != p0->info.point_sig ? "point" : "cell",
                  p0->path);
    if (!pc->info.gid != !p0->info.gid || !pc->m.node_tag != !p0->m.node_tag)
      return fail(r, pc->tag, "piece %zu ('%s'): GlobalNodeId or surface_tag differ from "
                  "piece 0's", i, pc->path);
    faces |= pc->m.nfaces > 0;
    cells |= pc->m.ncells > 0;
    if (V->npoints + pc->m.nnodes >= UINT32_MAX)
      return fail(r, pc->tag, "the pieces have more than %u points together", UINT32_MAX - 1);
    V->npoints += pc->m.nnodes;
  }
  if (r->planar && faces && cells)
    return fail(r, NULL, "some pieces have volume cells, others triangles or quadrilaterals");
  return MX_OK;
}

/* The pieces' points one after the other (the pieces' own arrays freed). */
static int pvtu_gather_points(pvtu *V) {
  const size_t N = V->npoints;
  const int with_tag = V->pc[0].m.node_tag != NULL, with_gid = V->pc[0].info.gid != NULL;
  V->poff = mx_alloc((V->n + 1) * sizeof *V->poff);
  V->xyz = mx_alloc((3 * N + 1) * sizeof *V->xyz);
  if (with_tag) V->tag = mx_alloc((N + 1) * sizeof *V->tag);
  if (with_gid) V->gid = mx_alloc((N + 1) * sizeof *V->gid);
  if (!V->poff || !V->xyz || (with_tag && !V->tag) || (with_gid && !V->gid)) return MX_EINPUT;
  size_t at = 0;
  for (size_t i = 0; i < V->n; i++) {
    pvtu_piece *pc = &V->pc[i];
    const size_t n = pc->m.nnodes;
    V->poff[i] = at;
    if (n) memcpy(V->xyz + 3 * at, pc->m.xyz, 3 * n * sizeof *V->xyz);
    if (with_tag && n) memcpy(V->tag + at, pc->m.node_tag, n * sizeof *V->tag);
    if (with_gid && n) memcpy(V->gid + at, pc->info.gid, n * sizeof *V->gid);
    mx_free(pc->m.xyz);
    mx_free(pc->m.node_tag);
    mx_free(pc->info.gid);
    pc->m.xyz = NULL;
    pc->m.node_tag = NULL;
    pc->info.gid = NULL;
    at += n;
  }
  V->poff[V->n] = at;
  return MX_OK;
}

/* The piece point q belongs to. */
static size_t piece_of(const pvtu *V, size_t q) {
  size_t lo = 0, hi = V->n;
  while (hi - lo > 1) {
    const size_t mid = lo + (hi - lo) / 2;
    if (V->poff[mid] <= q)
      lo = mid;
    else
      hi = mid;
  }
  return lo;
}

static int same_point(const pvtu *V, size_t a, size_t b) {
  return memcmp(V->xyz + 3 * a, V->xyz + 3 * b, 3 * sizeof *V->xyz) == 0;
}

/* Points with one GlobalNodeId are one node, the nodes in id order. */
static int merge_by_ids(rd *r, pvtu *V, uint32_t *idx) {
  const size_t N = V->npoints;
  MX_CHECK(mx_sort_u64(V->gid, idx, N));
  size_t K = 0;
  for (size_t i = 0; i < N; i++) K += i == 0 || V->gid[i] != V->gid[i - 1];
  V->node_rep = mx_alloc((K + 1) * sizeof *V->node_rep);
  if (!V->node_rep) return MX_EINPUT;
  size_t k = 0;
  for (size_t i = 0; i < N; i++) {
    if (i == 0 || V->gid[i] != V->gid[i - 1]) {
      k = i == 0 ? 0 : k + 1;
      V->node_rep[k] = idx[i];
    } else if (!same_point(V, idx[i], V->node_rep[k])) {
      const size_t a = piece_of(V, V->node_rep[k]), b = piece_of(V, idx[i]);
      return fail(r, NULL,
                  "GlobalNodeId %llu has different coordinates in piece %zu ('%s', point %zu) "
                  "and piece %zu ('%s', point %zu)",
                  (unsigned long long)V->gid[i], a, V->pc[a].path,
                  (size_t)V->node_rep[k] - V->poff[a], b, V->pc[b].path,
                  (size_t)idx[i] - V->poff[b]);
    }
    V->map[idx[i]] = (uint32_t)k;
  }
  V->nnodes = K;
  return MX_OK;
}

typedef struct {
  uint64_t c[3];
  uint32_t q;
} coord_item;

static int coord_item_cmp(const void *pa, const void *pb) {
  const coord_item *a = pa, *b = pb;
  for (int k = 0; k < 3; k++)
    if (a->c[k] != b->c[k]) return a->c[k] < b->c[k] ? -1 : 1;
  return a->q < b->q ? -1 : a->q > b->q;
}

/* One group of points at one place, ascending: in map, each point's
 * representative (the k-th point of each piece there joins the k-th
 * point of the first piece having one). reps: room for n. */
static void coord_group(const pvtu *V, const uint32_t *g, size_t n, uint32_t *reps) {
  size_t nreps = 0, j = 0, cur = SIZE_MAX;
  for (size_t i = 0; i < n; i++) {
    const size_t pc = piece_of(V, g[i]);
    if (pc != cur) {
      cur = pc;
      j = 0;
    }
    if (j == nreps) reps[nreps++] = g[i];
    V->map[g[i]] = reps[j++];
  }
}

/* Points of different pieces with bitwise-equal coordinates are one node,
 * the nodes in the order they first appear. */
static int merge_by_coords(pvtu *V, uint32_t *idx) {
  const size_t N = V->npoints;
  uint64_t *key = mx_alloc((N + 1) * sizeof *key);
  if (!key) return MX_EINPUT;
#pragma omp parallel for schedule(static) if (N > 65536)
  for (size_t i = 0; i < N; i++) {
    uint64_t h = 0x9e3779b97f4a7c15ull;
    for (int a = 0; a < 3; a++) {
      uint64_t b;
      memcpy(&b, V->xyz + 3 * i + a, sizeof b);
      h = (h ^ b) * 0xbf58476d1ce4e5b9ull;
      h ^= h >> 31;
    }
    key[i] = h;
  }
  int st = mx_sort_u64(key, idx, N);
  uint32_t *reps = NULL;
  coord_item *items = NULL;
  size_t cap = 0;
  for (size_t s = 0, e; st == MX_OK && s < N; s = e) {
    e = s + 1;
    int one_place = 1;
    while (e < N && key[e] == key[s]) {
      one_place &= same_point(V, idx[e], idx[s]);
      e++;
    }
    const size_t n = e - s;
    if (n > cap) {
      cap = 2 * n;
      mx_free(reps);
      mx_free(items);
      reps = mx_alloc(cap * sizeof *reps);
      items = mx_alloc(cap * sizeof *items);
      if (!reps || !items) {
        st = MX_EINPUT;
        break;
      }
    }
    if (one_place) { /* the usual case: idx ascending within equal keys (stable sort) */
      coord_group(V, idx + s, n, reps);
      continue;
    }
    /* a hash collision: the places apart */
    for (size_t i = 0; i < n; i++) {
      memcpy(items[i].c, V->xyz + 3 * (size_t)idx[s + i], sizeof items[i].c);
      items[i].q = idx[s + i];
    }
    qsort(items, n, sizeof *items, coord_item_cmp);
    for (size_t a = 0, b; a < n; a = b) {
      for (b = a; b < n && memcmp(items[b].c, items[a].c, sizeof items[a].c) == 0; b++)
        idx[s + b] = items[b].q;
      coord_group(V, idx + s + a, b - a, reps);
    }
  }
  mx_free(key);
  mx_free(reps);
  mx_free(items);
  if (st != MX_OK) return st;
  /* number the representatives in point order; idx becomes their numbers */
#pragma omp parallel for schedule(static) if (N > 65536)
  for (size_t i = 0; i < N; i++) idx[i] = V->map[i] == i;
  V->nnodes = mx_scan_u32(idx, N);
  V->node_rep = mx_alloc((V->nnodes + 1) * sizeof *V->node_rep);
  if (!V->node_rep) return MX_EINPUT;
  for (size_t i = 0; i < N; i++) {
    const uint32_t rep = V->map[i]; /* <= i: its own number is still there */
    if (rep == i) V->node_rep[idx[i]] = (uint32_t)i;
    V->map[i] = idx[rep];
  }
  return MX_OK;
}

/* The merged nodes, cells and faces into out. */
static int pvtu_assemble(rd *r, pvtu *V, mx_mesh_data *out) {
  const size_t K = V->nnodes;
  out->nnodes = K;
  out->xyz = mx_alloc((3 * K + 1) * sizeof *out->xyz);
  if (!out->xyz) return MX_EINPUT;
#pragma omp parallel for schedule(static) if (K > 65536)
  for (size_t k = 0; k < K; k++)
    memcpy(out->xyz + 3 * k, V->xyz + 3 * (size_t)V->node_rep[k], 3 * sizeof *out->xyz);
  if (V->tag) {
    out->node_tag = mx_alloc((K + 1) * sizeof *out->node_tag);
    if (!out->node_tag) return MX_EINPUT;
#pragma omp parallel for schedule(static) if (K > 65536)
    for (size_t k = 0; k < K; k++) out->node_tag[k] = V->tag[V->node_rep[k]];
    size_t bad = SIZE_MAX;
#pragma omp parallel for schedule(static) reduction(min : bad) if (V->npoints > 65536)
    for (size_t q = 0; q < V->npoints; q++)
      if (V->tag[q] != out->node_tag[V->map[q]] && q < bad) bad = q;
    if (bad != SIZE_MAX) {
      const size_t b = piece_of(V, bad);
      return fail(r, NULL, "surface_tag of point %zu of piece %zu ('%s') differs from that of "
                  "the same node in another piece", bad - V->poff[b], b, V->pc[b].path);
    }
  }
  size_t C = 0, F = 0;
  for (size_t i = 0; i < V->n; i++) {
    C += V->pc[i].m.ncells;
    F += V->pc[i].m.nfaces;
  }
  out->ncells = C;
  out->type = mx_alloc(C + 1);
  out->conn = mx_alloc((8 * C + 1) * sizeof *out->conn);
  if (!out->type || !out->conn) return MX_EINPUT;
  if (F) {
    out->nfaces = F;
    out->face_nn = mx_alloc(F);
    out->face_conn = mx_alloc(4 * F * sizeof *out->face_conn);
    out->face_tag = mx_alloc(F * sizeof *out->face_tag);
    if (!out->face_nn || !out->face_conn || !out->face_tag) return MX_EINPUT;
  }
  size_t c0 = 0, f0 = 0;
  for (size_t i = 0; i < V->n; i++) {
    mx_mesh_data *m = &V->pc[i].m;
    const uint32_t *map = V->map + V->poff[i];
    const size_t nc = m->ncells, nf = m->nfaces;
    if (nc) memcpy(out->type + c0, m->type, nc);
#pragma omp parallel for schedule(static) if (nc > 65536)
    for (size_t c = 0; c < nc; c++) {
      const uint32_t *row = m->conn + 8 * c;
      uint32_t *to = out->conn + 8 * (c0 + c);
      const int nn = mx_cell_nodes[m->type[c]];
      for (int j = 0; j < 8; j++) to[j] = j < nn ? map[row[j]] : 0;
    }
    for (size_t f = 0; f < nf; f++) {
      out->face_nn[f0 + f] = m->face_nn[f];
      out->face_tag[f0 + f] = m->face_tag[f];
      for (int j = 0; j < 4; j++)
        out->face_conn[4 * (f0 + f) + (size_t)j] =
            j < m->face_nn[f] ? map[m->face_conn[4 * f + (size_t)j]] : 0;
    }
    c0 += nc;
    f0 += nf;
    mx_mesh_data_free(m);
  }
  return MX_OK;
}

static int read_pvtu(rd *r, const char *p, mx_mesh_data *out) {
  r->merged = 1; /* the pieces' wedges are in our order already */
  pvtu V;
  memset(&V, 0, sizeof V);
  int st = pvtu_list_pieces(r, p, &V);
  if (st == MX_OK) st = pvtu_read_pieces(r, &V);
  if (st == MX_OK) st = pvtu_gather_points(&V);
  uint32_t *idx = NULL;
  if (st == MX_OK) {
    V.map = mx_alloc((V.npoints + 1) * sizeof *V.map);
    idx = mx_alloc((V.npoints + 1) * sizeof *idx);
    if (!V.map || !idx) st = MX_EINPUT;
  }
  if (st == MX_OK) {
#pragma omp parallel for schedule(static) if (V.npoints > 65536)
    for (size_t i = 0; i < V.npoints; i++) idx[i] = (uint32_t)i;
    st = V.gid ? merge_by_ids(r, &V, idx) : merge_by_coords(&V, idx);
  }
  mx_free(idx);
  if (st == MX_OK) st = pvtu_assemble(r, &V, out);
  pvtu_free(&V);
  return st;
}

/* ---- text tokens and binary cursors (MSH, Medit) --------------------------
 *
 * Text: blank-separated tokens of the NUL-terminated buffer, parsed with the
 * shared scanners; a Medit comment ('#' to the end of the line) is a blank
 * when comments is set. Binary: a cursor p and the bytes left before end,
 * checked before every read. */

typedef struct {
  rd *r;
  const char *p;
  int comments; /* '#' starts a comment (Medit) */
  int swap;     /* binary: byte-swap */
} cur;

static const char *cur_skip(cur *c) {
  const char *p = c->p, *end = c->r->end;
  for (;;) {
    p = skip_ws(p, end);
    if (!c->comments || p >= end || *p != '#') break;
    const char *nl = memchr(p, '\n', (size_t)(end - p));
    p = nl ? nl + 1 : end;
  }
  c->p = p;
  return p;
}

/* The next token (length in *n, 0 at the end or at a NUL byte). */
static const char *cur_tok(cur *c, size_t *n) {
  const char *t = cur_skip(c);
  *n = tok_len(t, c->r->end);
  c->p = t + *n;
  return t;
}

static size_t cur_left(const cur *c) { return (size_t)(c->r->end - c->p); }

static int cur_int(cur *c, int64_t *v, const char *what) {
  size_t n;
  const char *t = cur_tok(c, &n);
  if (n == 0)
    return fail(c->r, t, "%s: unexpected end of file (truncated file or "
                "wrong count)", what);
  const char *e = mx_io_int(t, v);
  if (!e || e != t + n)
    return fail(c->r, t, "%s: '%.*s' is not an integer", what, shown(n), t);
  return MX_OK;
}

/* A count or tag: an integer >= 0 (>= 1 when positive). */
static int cur_count(cur *c, uint64_t *v, int positive, const char *what) {
  const char *at = cur_skip(c);
  int64_t x = 0;
  MX_CHECK(cur_int(c, &x, what));
  if (x < positive)
    return fail(c->r, at, "%s: %lld is out of range", what, (long long)x);
  *v = (uint64_t)x;
  return MX_OK;
}

static int cur_real(cur *c, double *v, const char *what) {
  size_t n;
  const char *t = cur_tok(c, &n);
  if (n == 0)
    return fail(c->r, t, "%s: unexpected end of file (truncated file or "
                "wrong count)", what);
  const char *e = mx_io_double(t, v);
  if (!e || e != t + n)
    return fail(c->r, t, "%s: '%.*s' is not a number", what, shown(n), t);
  if (!isfinite(*v))
    return fail(c->r, t, "%s: '%.*s' is not a finite number", what, shown(n),
                t);
  return MX_OK;
}

/* n bytes must be left; a message names what is short. */
static int cur_need(cur *c, uint64_t n, const char *what) {
  if (n > cur_left(c))
    return fail(c->r, c->p,
                "%s: %llu bytes needed but only %zu are left (truncated file "
                "or wrong count)",
                what, (unsigned long long)n, cur_left(c));
  return MX_OK;
}

static uint64_t bin_u(cur *c, int size) { /* bounds checked by the caller */
  const uint64_t v = load_bits((const unsigned char *)c->p, size, c->swap);
  c->p += size;
  return v;
}

static double bin_real(cur *c, int size) {
  const uint64_t b = bin_u(c, size);
  if (size == 4) {
    const uint32_t b4 = (uint32_t)b;
    float f;
    memcpy(&f, &b4, 4);
    return f;
  }
  double d;
  memcpy(&d, &b, 8);
  return d;
}

/* Grows the cells of out by n (n already checked against the file size). */
static int grow_cells(rd *r, mx_mesh_data *out, size_t n) {
  const size_t nc = out->ncells + n;
  if (nc > UINT32_MAX / 6)
    return fail(r, NULL, "more than %u volume elements", UINT32_MAX / 6);
  uint8_t *t = mx_realloc(out->type, nc + 1);
  if (!t) return MX_EINPUT;
  out->type = t;
  uint32_t *cn = mx_realloc(out->conn, (8 * nc + 1) * sizeof *cn);
  if (!cn) return MX_EINPUT;
  out->conn = cn;
  memset(out->conn + 8 * out->ncells, 0, 8 * n * sizeof *cn);
  return MX_OK;
}

/* ---- tagged faces and tag names ------------------------------------------ */

/* Room for n more tagged faces in out (capacity *cap, at least doubled; n
 * already checked against the file size). */
static int face_room(rd *r, mx_mesh_data *out, size_t *cap, size_t n) {
  if (n <= *cap - out->nfaces) return MX_OK;
  const size_t most = UINT32_MAX / 6;
  if (n > most - out->nfaces)
    return fail(r, NULL, "more than %zu boundary faces", most);
  size_t nc = *cap ? 2 * *cap : 1024;
  if (nc < out->nfaces + n) nc = out->nfaces + n;
  if (nc > most) nc = most;
  uint8_t *nn = mx_realloc(out->face_nn, nc);
  if (!nn) return MX_EINPUT;
  out->face_nn = nn;
  uint32_t *cn = mx_realloc(out->face_conn, 4 * nc * sizeof *cn);
  if (!cn) return MX_EINPUT;
  out->face_conn = cn;
  int32_t *tg = mx_realloc(out->face_tag, nc * sizeof *tg);
  if (!tg) return MX_EINPUT;
  out->face_tag = tg;
  *cap = nc;
  return MX_OK;
}

/* Appends a face (room made by face_room). */
static void add_face(mx_mesh_data *out, int nn, const uint32_t v[4],
                     int32_t tag) {
  const size_t f = out->nfaces++;
  out->face_nn[f] = (uint8_t)nn;
  for (int j = 0; j < 4; j++) out->face_conn[4 * f + (size_t)j] = j < nn ? v[j] : 0;
  out->face_tag[f] = tag;
}

/* A tag read as a 64-bit integer must fit an int32. */
static int tag_range(rd *r, const char *at, int64_t v, const char *what) {
  if (v < INT32_MIN || v > INT32_MAX)
    return fail(r, at, "%s %lld is out of range (32-bit integers)", what,
                (long long)v);
  return MX_OK;
}

/* Appends the name s[0, n) of tag (capacity *cap, doubled). */
static int add_name(mx_mesh_data *out, size_t *cap, int32_t tag,
                    const char *s, size_t n) {
  if (out->nnames == *cap) {
    const size_t nc = *cap ? 2 * *cap : 16;
    int32_t *t = mx_realloc(out->name_tag, nc * sizeof *t);
    if (!t) return MX_EINPUT;
    out->name_tag = t;
    char **nm = mx_realloc(out->name, nc * sizeof *nm);
    if (!nm) return MX_EINPUT;
    out->name = nm;
    *cap = nc;
  }
  char *c = mx_alloc(n + 1);
  if (!c) return MX_EINPUT;
  memcpy(c, s, n);
  c[n] = '\0';
  out->name_tag[out->nnames] = tag;
  out->name[out->nnames++] = c;
  return MX_OK;
}

/* The names sorted by tag, each tag once (the last name given to it). */
static int sort_names(mx_mesh_data *out) {
  const size_t n = out->nnames;
  if (n < 2) return MX_OK;
  uint64_t *k = mx_alloc(n * sizeof *k);
  int32_t *t = mx_alloc(n * sizeof *t);
  char **nm = mx_alloc(n * sizeof *nm);
  if (!k || !t || !nm) {
    mx_free(k);
    mx_free(t);
    mx_free(nm);
    return MX_EINPUT;
  }
  for (size_t i = 0; i < n; i++)
    k[i] = (uint64_t)((uint32_t)out->name_tag[i] ^ 0x80000000u) << 32 | i;
  int st = mx_sort_u64(k, NULL, n);
  size_t m = 0;
  for (size_t i = 0; st == MX_OK && i < n; i++) {
    const size_t at = (size_t)(uint32_t)k[i];
    if (i + 1 < n && k[i + 1] >> 32 == k[i] >> 32) { /* named again later */
      mx_free(out->name[at]);
      out->name[at] = NULL;
      continue;
    }
    t[m] = out->name_tag[at];
    nm[m++] = out->name[at];
  }
  if (st != MX_OK) {
    mx_free(k);
    mx_free(t);
    mx_free(nm);
    return st;
  }
  mx_free(k);
  mx_free(out->name_tag);
  mx_free(out->name);
  out->name_tag = t;
  out->name = nm;
  out->nnames = m;
  return MX_OK;
}

/* ---- Gmsh MSH 4.1 ---------------------------------------------------------
 *
 * $MeshFormat "4.1 0|1 8" (binary: then the int 1 in the writer's byte
 * order, which tells a swapped file), $Nodes, $Elements, $Entities and
 * $PhysicalNames are read; every other section ($NodeData...) is skipped up
 * to its $End line. $Entities: four counts (points, curves, surfaces,
 * volumes), then per entity its tag, its coordinates (points 3, others a
 * box of 6), a count and that many physical tags, and for all but points a
 * count and that many bounding entities (binary: counts size_t, tags int,
 * coordinates double). $PhysicalNames (ASCII in both variants): a count,
 * then lines "dim tag \"name\"". Nodes come in blocks: dim tag parametric n, n tags, then n
 * coordinate lines (x y z, + dim parametric values when parametric);
 * elements in blocks: dim tag type n, then n lines "tag node-tags...".
 * Binary files use size_t (the data size of the format line, 4 or 8 bytes)
 * for counts and tags, int for dimensions, entity tags and types, doubles
 * for coordinates. Tetrahedra (type 4), hexahedra (5), prisms (6) and
 * pyramids (7) are kept, in the order of their tags (mixoct writes tag =
 * index + 1); triangles (2) and quadrangles (3) of blocks of dimension 2
 * are the tagged faces, their tag their entity's (read_mesh.h), in file
 * order; points, lines and other triangles and quadrangles are skipped;
 * any other type is refused. Node orders are Gmsh's, which are
 * mixoct's (soa/mesh.h). Node tags are mapped to indices by a direct table
 * when they are dense, else by a sorted one. */

enum { MSH_TYPES = 32 };
/* nodes per Gmsh element type (0: unknown) */
static const int8_t msh_type_nodes[MSH_TYPES] = {
    0, 2, 3, 4, 4, 8, 6, 5, 3, 6, 9, 10, 27, 18, 14, 1,
    8, 20, 15, 13, 9, 10, 12, 15, 15, 21, 4, 5, 6, 20, 35, 56};

static int msh_volume_type(int64_t t) {
  switch (t) {
    case 4: return MX_TET;
    case 5: return MX_HEX;
    case 6: return MX_PRISM;
    case 7: return MX_PYRAMID;
    default: return -1;
  }
}

typedef struct {
  cur c;
  int binary, dsize;
  int have_nodes;
  size_t nnodes;
  uint64_t *ntag;   /* nnodes: tag of each node */
  uint64_t tmin, tmax;
  uint32_t *dense;  /* tag - tmin -> index + 1 (0: none), or NULL */
  uint64_t *sorted; /* or: tags sorted, with */
  uint32_t *sidx;   /* their indices */
  uint64_t *etag;   /* per volume element */
  int have_entities;
  size_t nsurf;
  int64_t *surf;    /* $Entities: per surface, its tag and its face tag */
  size_t fcap, ncap; /* capacities of out's faces and names */
  mx_mesh_data *out;
} msh;

/* Where the next value starts, for messages (text: after the blanks;
 * binary: here, blanks are data). */
static const char *msh_at(msh *M) {
  return M->binary ? M->c.p : cur_skip(&M->c);
}

static void msh_free(msh *M) {
  mx_free(M->ntag);
  mx_free(M->dense);
  mx_free(M->sorted);
  mx_free(M->sidx);
  mx_free(M->etag);
  mx_free(M->surf);
}

/* A size_t (binary) or a count (text). */
static int msh_size(msh *M, uint64_t *v, const char *what) {
  if (!M->binary) return cur_count(&M->c, v, 0, what);
  MX_CHECK(cur_need(&M->c, (uint64_t)M->dsize, what));
  *v = bin_u(&M->c, M->dsize);
  return MX_OK;
}

/* An int (binary) or an integer (text). */
static int msh_int(msh *M, int64_t *v, const char *what) {
  if (!M->binary) return cur_int(&M->c, v, what);
  MX_CHECK(cur_need(&M->c, 4, what));
  *v = (int32_t)(uint32_t)bin_u(&M->c, 4);
  return MX_OK;
}

/* The line "$End<name>" after a section (text and binary: the binary data
 * is followed by a newline). */
static int msh_end(msh *M, const char *name) {
  size_t n;
  const char *t = cur_tok(&M->c, &n);
  char want[64];
  snprintf(want, sizeof want, "$End%s", name);
  if (n != strlen(want) || memcmp(t, want, n) != 0)
    return fail(M->c.r, t, "expected %s, found '%.*s' (wrong count?)", want,
                shown(n), t);
  return MX_OK;
}

static int msh_format(msh *M) {
  rd *r = M->c.r;
  size_t n;
  const char *t = cur_tok(&M->c, &n);
  if (!tok_eq(t, n, "4.1"))
    return fail(r, t,
                "MSH version '%.*s' is not supported (4.1 only: gmsh "
                "-format msh41)",
                shown(n), t);
  int64_t ft = 0, ds = 0;
  MX_CHECK(cur_int(&M->c, &ft, "$MeshFormat file type"));
  MX_CHECK(cur_int(&M->c, &ds, "$MeshFormat data size"));
  if (ft != 0 && ft != 1)
    return fail(r, t, "$MeshFormat: file type %lld (0 ASCII, 1 binary)",
                (long long)ft);
  if (ds != 4 && ds != 8)
    return fail(r, t, "$MeshFormat: data size %lld (4 or 8)", (long long)ds);
  M->binary = ft == 1;
  M->dsize = (int)ds;
  if (M->binary) {
    const char *p = M->c.p, *end = r->end;
    while (p < end && (*p == ' ' || *p == '\r' || *p == '\t')) p++;
    if (p >= end || *p != '\n')
      return fail(r, p, "$MeshFormat: expected the end of the line");
    M->c.p = p + 1;
    r->bin_from = M->c.p;
    MX_CHECK(cur_need(&M->c, 4, "$MeshFormat: the binary one"));
    const uint32_t one = (uint32_t)bin_u(&M->c, 4);
    if (one == 1)
      M->c.swap = 0;
    else if (one == 0x01000000u)
      M->c.swap = 1;
    else
      return fail(r, M->c.p - 4,
                  "$MeshFormat: the binary 1 reads as %u (not a binary MSH "
                  "file?)",
                  one);
  }
  return msh_end(M, "MeshFormat");
}

static int msh_nodes(msh *M) {
  rd *r = M->c.r;
  if (M->have_nodes) return fail(r, M->c.p, "$Nodes given twice");
  M->have_nodes = 1;
  uint64_t nb = 0, nn = 0, tmin = 0, tmax = 0;
  const char *at = msh_at(M);
  MX_CHECK(msh_size(M, &nb, "$Nodes: number of blocks"));
  MX_CHECK(msh_size(M, &nn, "$Nodes: number of nodes"));
  MX_CHECK(msh_size(M, &tmin, "$Nodes: smallest tag"));
  MX_CHECK(msh_size(M, &tmax, "$Nodes: largest tag"));
  /* a node takes at least a tag and 3 doubles (binary), "1\n0 0 0\n" */
  const uint64_t least = M->binary ? (uint64_t)M->dsize + 24 : 8;
  if (nn >= UINT32_MAX || nn > cur_left(&M->c) / least + 1 ||
      nb > cur_left(&M->c) / 4 + 1)
    return fail(r, at,
                "$Nodes: %llu nodes in %llu blocks announced but the file "
                "is too short (truncated file or wrong count)",
                (unsigned long long)nn, (unsigned long long)nb);
  M->nnodes = (size_t)nn;
  M->out->nnodes = (size_t)nn;
  M->out->xyz = mx_alloc((3 * (size_t)nn + 1) * sizeof(double));
  M->ntag = mx_alloc(((size_t)nn + 1) * sizeof *M->ntag);
  if (!M->out->xyz || !M->ntag) return MX_EINPUT;
  size_t done = 0;
  for (uint64_t b = 0; b < nb; b++) {
    int64_t dim = 0, etag = 0, par = 0;
    uint64_t n = 0;
    at = msh_at(M);
    MX_CHECK(msh_int(M, &dim, "$Nodes block: entity dimension"));
    MX_CHECK(msh_int(M, &etag, "$Nodes block: entity tag"));
    MX_CHECK(msh_int(M, &par, "$Nodes block: parametric"));
    MX_CHECK(msh_size(M, &n, "$Nodes block: number of nodes"));
    if (dim < 0 || dim > 3 || (par != 0 && par != 1))
      return fail(r, at, "$Nodes block %llu: dimension %lld, parametric %lld",
                  (unsigned long long)b, (long long)dim, (long long)par);
    if (n > nn - done)
      return fail(r, at, "$Nodes block %llu: %llu nodes, more than announced",
                  (unsigned long long)b, (unsigned long long)n);
    const int ncoord = 3 + (par ? (int)dim : 0);
    if (M->binary)
      MX_CHECK(cur_need(&M->c, n * ((uint64_t)M->dsize + 8 * (uint64_t)ncoord),
                        "$Nodes block"));
    for (uint64_t i = 0; i < n; i++) {
      uint64_t tag = 0;
      if (M->binary)
        tag = bin_u(&M->c, M->dsize);
      else
        MX_CHECK(cur_count(&M->c, &tag, 1, "$Nodes: node tag"));
      if (tag < tmin || tag > tmax || tag == 0)
        return fail(r, M->c.p, "node tag %llu outside %llu..%llu",
                    (unsigned long long)tag, (unsigned long long)tmin,
                    (unsigned long long)tmax);
      M->ntag[done + i] = tag;
    }
    for (uint64_t i = 0; i < n; i++) {
      double *q = M->out->xyz + 3 * (done + i);
      for (int k = 0; k < ncoord; k++) {
        double v = 0.0;
        const char *vat = msh_at(M);
        if (M->binary)
          v = bin_real(&M->c, 8);
        else
          MX_CHECK(cur_real(&M->c, &v, "$Nodes: coordinate"));
        if (!isfinite(v))
          return fail(r, vat, "node %zu: coordinate %d is not a finite "
                      "number", done + (size_t)i, k);
        if (k < 3) q[k] = v;
      }
    }
    done += (size_t)n;
  }
  if (done != nn)
    return fail(r, M->c.p, "$Nodes: %zu nodes in the blocks, %llu announced",
                done, (unsigned long long)nn);
  M->tmin = tmin;
  M->tmax = tmax;
  /* the tag map */
  if (nn > 0 && tmax - tmin < 2 * nn + 1024) {
    const size_t span = (size_t)(tmax - tmin) + 1;
    M->dense = mx_calloc(span * sizeof *M->dense);
    if (!M->dense) return MX_EINPUT;
    for (size_t i = 0; i < nn; i++) {
      uint32_t *d = &M->dense[M->ntag[i] - tmin];
      if (*d)
        return fail(r, NULL, "node tag %llu appears twice",
                    (unsigned long long)M->ntag[i]);
      *d = (uint32_t)i + 1;
    }
  } else if (nn > 0) {
    M->sorted = mx_alloc((size_t)nn * sizeof *M->sorted);
    M->sidx = mx_alloc((size_t)nn * sizeof *M->sidx);
    if (!M->sorted || !M->sidx) return MX_EINPUT;
    for (size_t i = 0; i < nn; i++) {
      M->sorted[i] = M->ntag[i];
      M->sidx[i] = (uint32_t)i;
    }
    MX_CHECK(mx_sort_u64(M->sorted, M->sidx, (size_t)nn));
    for (size_t i = 1; i < nn; i++)
      if (M->sorted[i] == M->sorted[i - 1])
        return fail(r, NULL, "node tag %llu appears twice",
                    (unsigned long long)M->sorted[i]);
  }
  return msh_end(M, "Nodes");
}

/* The index of node tag t, or -1. */
static int64_t msh_node(const msh *M, uint64_t t) {
  if (t < M->tmin || t > M->tmax || M->nnodes == 0) return -1;
  if (M->dense) return (int64_t)M->dense[t - M->tmin] - 1;
  size_t lo = 0, hi = M->nnodes;
  while (lo < hi) {
    const size_t mid = lo + (hi - lo) / 2;
    if (M->sorted[mid] < t)
      lo = mid + 1;
    else
      hi = mid;
  }
  return lo < M->nnodes && M->sorted[lo] == t ? (int64_t)M->sidx[lo] : -1;
}

/* A double of $Entities (binary: no check of its value, it is not used). */
static int msh_real(msh *M, const char *what) {
  if (!M->binary) {
    double v;
    return cur_real(&M->c, &v, what);
  }
  MX_CHECK(cur_need(&M->c, 8, what));
  M->c.p += 8;
  return MX_OK;
}

static int surf_cmp(const void *a, const void *b) {
  const int64_t x = *(const int64_t *)a, y = *(const int64_t *)b;
  return (x > y) - (x < y);
}

static int msh_entities(msh *M) {
  rd *r = M->c.r;
  if (M->have_entities) return fail(r, M->c.p, "$Entities given twice");
  M->have_entities = 1;
  uint64_t n[4] = {0, 0, 0, 0};
  const char *at = msh_at(M);
  for (int d = 0; d < 4; d++)
    MX_CHECK(msh_size(M, &n[d], "$Entities: number of entities"));
  /* an entity takes at least a tag, 3 doubles and a count */
  const uint64_t least = M->binary ? 4 + 24 + (uint64_t)M->dsize : 8;
  for (int d = 0; d < 4; d++)
    if (n[d] > cur_left(&M->c) / least + 1)
      return fail(r, at,
                  "$Entities: %llu entities of dimension %d announced but "
                  "the file is too short (truncated file or wrong count)",
                  (unsigned long long)n[d], d);
  M->surf = mx_alloc((2 * (size_t)n[2] + 1) * sizeof *M->surf);
  if (!M->surf) return MX_EINPUT;
  for (int d = 0; d < 4; d++)
    for (uint64_t i = 0; i < n[d]; i++) {
      int64_t tag = 0, first = 0;
      uint64_t np = 0, nb = 0;
      at = msh_at(M);
      MX_CHECK(msh_int(M, &tag, "$Entities: entity tag"));
      for (int k = 0; k < (d ? 6 : 3); k++)
        MX_CHECK(msh_real(M, "$Entities: coordinate"));
      const char *pat = msh_at(M);
      MX_CHECK(msh_size(M, &np, "$Entities: number of physical tags"));
      if (np > cur_left(&M->c) / 2 + 1)
        return fail(r, pat, "$Entities: %llu physical tags announced but the "
                    "file is too short", (unsigned long long)np);
      for (uint64_t j = 0; j < np; j++) {
        int64_t ph = 0;
        MX_CHECK(msh_int(M, &ph, "$Entities: physical tag"));
        if (j == 0) first = ph;
      }
      if (d > 0) {
        pat = msh_at(M);
        MX_CHECK(msh_size(M, &nb, "$Entities: number of bounding entities"));
        if (nb > cur_left(&M->c) / 2 + 1)
          return fail(r, pat, "$Entities: %llu bounding entities announced "
                      "but the file is too short", (unsigned long long)nb);
        for (uint64_t j = 0; j < nb; j++) {
          int64_t b = 0;
          MX_CHECK(msh_int(M, &b, "$Entities: bounding entity"));
        }
      }
      if (d == 2) {
        const int64_t face_tag = np ? first : tag;
        MX_CHECK(tag_range(r, at, face_tag, "$Entities: surface tag"));
        M->surf[2 * i] = tag;
        M->surf[2 * i + 1] = face_tag;
      }
    }
  M->nsurf = (size_t)n[2];
  qsort(M->surf, M->nsurf, 2 * sizeof *M->surf, surf_cmp);
  return msh_end(M, "Entities");
}

/* $PhysicalNames: the names of dimension 2 (boundary tags) are kept. */
static int msh_names(msh *M) {
  rd *r = M->c.r;
  uint64_t n = 0;
  const char *at = cur_skip(&M->c);
  MX_CHECK(cur_count(&M->c, &n, 0, "$PhysicalNames: number of names"));
  if (n > cur_left(&M->c) / 8 + 1)
    return fail(r, at, "$PhysicalNames: %llu names announced but the file "
                "is too short (truncated file or wrong count)",
                (unsigned long long)n);
  for (uint64_t i = 0; i < n; i++) {
    int64_t dim = 0, tag = 0;
    at = cur_skip(&M->c);
    MX_CHECK(cur_int(&M->c, &dim, "$PhysicalNames: dimension"));
    MX_CHECK(cur_int(&M->c, &tag, "$PhysicalNames: physical tag"));
    const char *p = M->c.p, *end = r->end;
    const char *nl = memchr(p, '\n', (size_t)(end - p));
    if (!nl) nl = end;
    const char *q1 = memchr(p, '"', (size_t)(nl - p));
    const char *q2 = q1 ? memrchr(q1 + 1, '"', (size_t)(nl - q1 - 1)) : NULL;
    if (!q2)
      return fail(r, at, "$PhysicalNames: name %llu is not in double quotes",
                  (unsigned long long)i);
    M->c.p = nl;
    if (dim != 2) continue;
    MX_CHECK(tag_range(r, at, tag, "$PhysicalNames: physical tag"));
    MX_CHECK(add_name(M->out, &M->ncap, (int32_t)tag, q1 + 1,
                      (size_t)(q2 - q1 - 1)));
  }
  return msh_end(M, "PhysicalNames");
}

/* The faces' entity tags to their entities' physical tags. */
static void msh_face_tags(msh *M) {
  mx_mesh_data *out = M->out;
  for (size_t f = 0; f < out->nfaces && M->nsurf; f++) {
    const int64_t e = out->face_tag[f];
    size_t lo = 0, hi = M->nsurf;
    while (lo < hi) {
      const size_t mid = lo + (hi - lo) / 2;
      if (M->surf[2 * mid] < e)
        lo = mid + 1;
      else
        hi = mid;
    }
    if (lo < M->nsurf && M->surf[2 * lo] == e)
      out->face_tag[f] = (int32_t)M->surf[2 * lo + 1];
  }
}

static int msh_elements(msh *M) {
  rd *r = M->c.r;
  if (!M->have_nodes)
    return fail(r, M->c.p, "$Elements before $Nodes");
  if (M->etag) return fail(r, M->c.p, "$Elements given twice");
  uint64_t nb = 0, ne = 0, tmin = 0, tmax = 0;
  const char *at = msh_at(M);
  MX_CHECK(msh_size(M, &nb, "$Elements: number of blocks"));
  MX_CHECK(msh_size(M, &ne, "$Elements: number of elements"));
  MX_CHECK(msh_size(M, &tmin, "$Elements: smallest tag"));
  MX_CHECK(msh_size(M, &tmax, "$Elements: largest tag"));
  const uint64_t least = M->binary ? 2 * (uint64_t)M->dsize : 4;
  if (ne > cur_left(&M->c) / least + 1 || nb > cur_left(&M->c) / 4 + 1)
    return fail(r, at,
                "$Elements: %llu elements in %llu blocks announced but the "
                "file is too short (truncated file or wrong count)",
                (unsigned long long)ne, (unsigned long long)nb);
  M->etag = mx_alloc(sizeof *M->etag); /* grows with the cells */
  if (!M->etag) return MX_EINPUT;
  mx_mesh_data *out = M->out;
  uint64_t done = 0;
  for (uint64_t b = 0; b < nb; b++) {
    int64_t dim = 0, etag = 0, type = 0;
    uint64_t n = 0;
    at = msh_at(M);
    MX_CHECK(msh_int(M, &dim, "$Elements block: entity dimension"));
    MX_CHECK(msh_int(M, &etag, "$Elements block: entity tag"));
    MX_CHECK(msh_int(M, &type, "$Elements block: element type"));
    MX_CHECK(msh_size(M, &n, "$Elements block: number of elements"));
    if (n > ne - done)
      return fail(r, at,
                  "$Elements block %llu: %llu elements, more than announced",
                  (unsigned long long)b, (unsigned long long)n);
    const int vt = msh_volume_type(type);
    const int k = type > 0 && type < MSH_TYPES ? msh_type_nodes[type] : 0;
    const int skipped = type == 1 || type == 2 || type == 3 || type == 15;
    const int face = dim == 2 && (type == 2 || type == 3);
    if (k == 0 || (vt < 0 && !skipped))
      return fail(r, at,
                  "$Elements block %llu: element type %lld is not supported "
                  "(linear tetrahedra 4, hexahedra 5, prisms 6, pyramids 7; "
                  "points, lines, triangles and quadrangles are skipped)",
                  (unsigned long long)b, (long long)type);
    if (face) MX_CHECK(tag_range(r, at, etag, "$Elements block: entity tag"));
    const uint64_t line_bytes = (uint64_t)(k + 1) * (uint64_t)M->dsize;
    if (M->binary)
      MX_CHECK(cur_need(&M->c, n * line_bytes, "$Elements block"));
    else if (n > cur_left(&M->c) / (2 * (uint64_t)(k + 1)) + 1)
      return fail(r, at,
                  "$Elements block %llu: %llu elements announced but the "
                  "file is too short (truncated file or wrong count)",
                  (unsigned long long)b, (unsigned long long)n);
    const size_t c0 = out->ncells;
    if (vt >= 0) {
      MX_CHECK(grow_cells(r, out, (size_t)n));
      uint64_t *et = mx_realloc(M->etag, ((size_t)(c0 + n) + 1) *
                                             sizeof *M->etag);
      if (!et) return MX_EINPUT;
      M->etag = et;
    }
    if (face) MX_CHECK(face_room(r, out, &M->fcap, (size_t)n));
    for (uint64_t i = 0; i < n; i++) {
      uint64_t tag = 0;
      at = msh_at(M);
      if (M->binary)
        tag = bin_u(&M->c, M->dsize);
      else
        MX_CHECK(cur_count(&M->c, &tag, 1, "$Elements: element tag"));
      uint32_t fv[4] = {0, 0, 0, 0};
      uint32_t *row = vt >= 0 ? out->conn + 8 * (c0 + (size_t)i)
                      : face  ? fv
                              : NULL;
      for (int j = 0; j < k; j++) {
        uint64_t t = 0;
        const char *nat = msh_at(M);
        if (M->binary)
          t = bin_u(&M->c, M->dsize);
        else
          MX_CHECK(cur_count(&M->c, &t, 1, "$Elements: node tag"));
        if (!row) continue;
        const int64_t v = msh_node(M, t);
        if (v < 0)
          return fail(r, nat, "element %llu: node tag %llu is not a node",
                      (unsigned long long)tag, (unsigned long long)t);
        row[j] = (uint32_t)v;
      }
      if (face) /* the entity tag for now (msh_face_tags) */
        add_face(out, k, fv, (int32_t)etag);
      else if (row) {
        out->type[c0 + (size_t)i] = (uint8_t)vt;
        M->etag[c0 + (size_t)i] = tag;
      }
    }
    if (vt >= 0) out->ncells = c0 + (size_t)n;
    done += n;
  }
  if (done != ne)
    return fail(r, M->c.p,
                "$Elements: %llu elements in the blocks, %llu announced",
                (unsigned long long)done, (unsigned long long)ne);
  (void)tmin;
  (void)tmax;
  return msh_end(M, "Elements");
}

/* Volume elements in the order of their tags (unique). */
static int msh_order(msh *M) {
  mx_mesh_data *out = M->out;
  const size_t nc = out->ncells;
  int sorted = 1;
  for (size_t c = 1; c < nc && sorted; c++) sorted = M->etag[c - 1] < M->etag[c];
  if (sorted) return MX_OK;
  uint64_t *k = mx_alloc((nc + 1) * sizeof *k);
  uint32_t *idx = mx_alloc((nc + 1) * sizeof *idx);
  uint8_t *t = mx_alloc(nc + 1);
  uint32_t *cn = mx_alloc((8 * nc + 1) * sizeof *cn);
  int st = k && idx && t && cn ? MX_OK : MX_EINPUT;
  if (st == MX_OK) {
    for (size_t c = 0; c < nc; c++) {
      k[c] = M->etag[c];
      idx[c] = (uint32_t)c;
    }
    st = mx_sort_u64(k, idx, nc);
  }
  for (size_t c = 1; st == MX_OK && c < nc; c++)
    if (k[c] == k[c - 1])
      st = fail(M->c.r, NULL, "element tag %llu appears twice",
                (unsigned long long)k[c]);
  if (st == MX_OK) {
    for (size_t c = 0; c < nc; c++) {
      t[c] = out->type[idx[c]];
      memcpy(cn + 8 * c, out->conn + 8 * (size_t)idx[c], 8 * sizeof *cn);
    }
    mx_free(out->type);
    mx_free(out->conn);
    out->type = t;
    out->conn = cn;
    t = NULL;
    cn = NULL;
  }
  mx_free(k);
  mx_free(idx);
  mx_free(t);
  mx_free(cn);
  return st;
}

static int read_msh(rd *r, const char *p, mx_mesh_data *out) {
  msh M;
  memset(&M, 0, sizeof M);
  M.c.r = r;
  M.c.p = p;
  M.dsize = 8;
  M.out = out;
  int st = MX_OK, have_format = 0;
  for (;;) {
    size_t n;
    const char *t = cur_tok(&M.c, &n);
    if (n == 0) {
      if (t < r->end)
        st = fail(r, t, "unexpected NUL byte");
      break;
    }
    if (t[0] != '$') {
      st = fail(r, t, "expected a section ($Name), found '%.*s'", shown(n),
                t);
      break;
    }
    if (tok_eq(t, n, "$MeshFormat")) {
      st = msh_format(&M);
      have_format = 1;
    } else if (!have_format) {
      st = fail(r, t, "expected $MeshFormat first");
    } else if (tok_eq(t, n, "$PhysicalNames")) {
      st = msh_names(&M);
    } else if (tok_eq(t, n, "$Nodes") || tok_eq(t, n, "$Elements") ||
               tok_eq(t, n, "$Entities")) {
      if (M.binary) { /* the data starts after the end of the line */
        const char *q = M.c.p;
        while (q < r->end && (*q == ' ' || *q == '\t' || *q == '\r')) q++;
        if (q >= r->end || *q != '\n') {
          st = fail(r, q, "expected the end of the line after %.*s",
                    shown(n), t);
          break;
        }
        M.c.p = q + 1;
      }
      st = tok_eq(t, n, "$Nodes")      ? msh_nodes(&M)
           : tok_eq(t, n, "$Elements") ? msh_elements(&M)
                                       : msh_entities(&M);
    } else { /* skipped up to $End<name> at the start of a line */
      char want[80];
      snprintf(want, sizeof want, "\n$End%.*s", (int)(n > 60 ? 60 : n - 1),
               t + 1);
      const size_t wl = strlen(want);
      const char *q = memmem(M.c.p, cur_left(&M.c), want, wl);
      if (!q) {
        st = fail(r, t, "no %s after %.*s", want + 1, shown(n), t);
        break;
      }
      M.c.p = q + wl;
      if (M.c.p < r->end && !is_ws(*M.c.p) && *M.c.p)
        st = fail(r, q + 1, "expected %s", want + 1);
    }
    if (st != MX_OK) break;
  }
  if (st == MX_OK && !have_format) st = fail(r, NULL, "no $MeshFormat");
  if (st == MX_OK && !M.have_nodes) st = fail(r, NULL, "no $Nodes section");
  if (st == MX_OK && !M.etag) st = fail(r, NULL, "no $Elements section");
  if (st == MX_OK) st = msh_order(&M);
  if (st == MX_OK) msh_face_tags(&M);
  if (st == MX_OK) st = sort_names(out);
  msh_free(&M);
  return st;
}

/* ---- Medit .mesh / .meshb -------------------------------------------------
 *
 * ASCII: keywords (case-insensitive) followed by their data, '#' comments.
 * "MeshVersionFormatted v", "Dimension 3", "Vertices n" + n lines "x y z
 * ref", "Tetrahedra", "Pyramids", "Prisms", "Hexahedra" n + n lines of
 * 1-based vertex indices and a reference; "Triangles", "Quadrilaterals" the
 * same, kept as the tagged faces (tag: the reference); "End". Other
 * keywords (Edges, Corners, Normals...) are skipped up to the next word. Binary: int32 1 (byte order), int32 version 1..4, then blocks: int32
 * keyword code, the next block's position (int32 up to version 2, int64
 * from 3), for Dimension its int32 value, else the line count (int32 up to
 * version 3, int64 in 4) and the lines: reals float32 in version 1, float64
 * after; integers int32 up to version 3, int64 in 4. Unknown keywords are
 * skipped through their next position; "End" (54) stops. Node orders are
 * mixoct's (see io/write_medit.c); cells come grouped by keyword, in file
 * order. */

enum {
  MED_DIM = 3, MED_VERT = 4, MED_TRI = 6, MED_QUAD = 7, MED_TET = 8,
  MED_PRISM = 9, MED_HEX = 10, MED_PYR = 49, MED_END = 54
};

/* The node count of a face keyword, 0 for others. */
static int medit_face_nodes(int code) {
  return code == MED_TRI ? 3 : code == MED_QUAD ? 4 : 0;
}

static int medit_cell_type(int code) {
  switch (code) {
    case MED_TET: return MX_TET;
    case MED_PYR: return MX_PYRAMID;
    case MED_PRISM: return MX_PRISM;
    case MED_HEX: return MX_HEX;
    default: return -1;
  }
}

/* 1-based vertex indices of the cells and faces -> 0-based, checked. */
static int medit_indices(rd *r, mx_mesh_data *out) {
  for (size_t c = 0; c < out->ncells; c++) {
    uint32_t *row = out->conn + 8 * c;
    for (int j = 0; j < mx_cell_nodes[out->type[c]]; j++) {
      if (row[j] == 0 || row[j] > out->nnodes)
        return fail(r, NULL,
                    "element %zu: vertex %u out of range (%zu vertices, "
                    "1-based)",
                    c, row[j], out->nnodes);
      row[j]--;
    }
  }
  for (size_t f = 0; f < out->nfaces; f++) {
    uint32_t *row = out->face_conn + 4 * f;
    for (int j = 0; j < out->face_nn[f]; j++) {
      if (row[j] == 0 || row[j] > out->nnodes)
        return fail(r, NULL,
                    "%s %zu: vertex %u out of range (%zu vertices, 1-based)",
                    out->face_nn[f] == 3 ? "triangle" : "quadrilateral", f,
                    row[j], out->nnodes);
      row[j]--;
    }
  }
  return MX_OK;
}

static int medit_kw_type(const char *t, size_t n) {
  static const struct {
    const char *name;
    int code;
  } kw[] = {{"Dimension", MED_DIM}, {"Vertices", MED_VERT},
            {"Tetrahedra", MED_TET}, {"Prisms", MED_PRISM},
            {"Hexahedra", MED_HEX}, {"Pyramids", MED_PYR},
            {"Triangles", MED_TRI}, {"Quadrilaterals", MED_QUAD},
            {"End", MED_END}};
  for (size_t i = 0; i < sizeof kw / sizeof kw[0]; i++)
    if (tok_eq(t, n, kw[i].name)) return kw[i].code;
  return 0;
}

static int read_medit_ascii(rd *r, const char *p, mx_mesh_data *out) {
  cur c = {r, p, 1, 0};
  int have_vert = 0;
  size_t fcap = 0;
  for (;;) {
    size_t n;
    const char *t = cur_tok(&c, &n);
    if (n == 0) {
      if (t < r->end) return fail(r, t, "unexpected NUL byte");
      return fail(r, NULL, "no End (truncated file?)");
    }
    if (!((*t >= 'A' && *t <= 'Z') || (*t >= 'a' && *t <= 'z')))
      return fail(r, t, "expected a keyword, found '%.*s' (wrong count?)",
                  shown(n), t);
    const int code = medit_kw_type(t, n);
    if (code == MED_END) break;
    if (tok_eq(t, n, "MeshVersionFormatted")) {
      int64_t v = 0;
      MX_CHECK(cur_int(&c, &v, "MeshVersionFormatted"));
      if (v < 1 || v > 4)
        return fail(r, t, "MeshVersionFormatted %lld: the Medit format has versions 1 "
                          "to 4", (long long)v);
      continue;
    }
    if (code == MED_DIM) {
      int64_t d = 0;
      MX_CHECK(cur_int(&c, &d, "Dimension"));
      if (d != 3)
        return fail(r, t, "Dimension %lld: only 3D meshes are supported",
                    (long long)d);
      continue;
    }
    if (code == 0) { /* skipped: numbers up to the next word */
      for (;;) {
        const char *save = c.p;
        const char *s = cur_tok(&c, &n);
        if (n == 0 || (*s >= 'A' && *s <= 'Z') || (*s >= 'a' && *s <= 'z')) {
          c.p = save;
          break;
        }
      }
      continue;
    }
    uint64_t cnt = 0;
    const char *at = cur_skip(&c);
    MX_CHECK(cur_count(&c, &cnt, 0, "line count"));
    if (code == MED_VERT) {
      if (have_vert) return fail(r, t, "Vertices given twice");
      have_vert = 1;
      if (cnt >= UINT32_MAX || cnt > cur_left(&c) / 8 + 1)
        return fail(r, at,
                    "Vertices: %llu announced but the file is too short "
                    "(truncated file or wrong count)",
                    (unsigned long long)cnt);
      out->nnodes = (size_t)cnt;
      out->xyz = mx_alloc((3 * (size_t)cnt + 1) * sizeof(double));
      if (!out->xyz) return MX_EINPUT;
      for (size_t i = 0; i < cnt; i++) {
        for (int k = 0; k < 3; k++)
          MX_CHECK(cur_real(&c, &out->xyz[3 * i + (size_t)k], "vertex"));
        int64_t ref = 0;
        MX_CHECK(cur_int(&c, &ref, "vertex reference"));
      }
      continue;
    }
    if (medit_face_nodes(code)) {
      const int k = medit_face_nodes(code);
      if (cnt > cur_left(&c) / (2 * (uint64_t)(k + 1)) + 1)
        return fail(r, at,
                    "%.*s: %llu announced but the file is too short "
                    "(truncated file or wrong count)",
                    shown(n), t, (unsigned long long)cnt);
      MX_CHECK(face_room(r, out, &fcap, (size_t)cnt));
      for (size_t i = 0; i < cnt; i++) {
        uint32_t v[4] = {0, 0, 0, 0};
        int64_t ref = 0;
        for (int j = 0; j <= k; j++) {
          const char *vat = cur_skip(&c);
          int64_t x = 0;
          MX_CHECK(cur_int(&c, &x, "face"));
          if (j == k) {
            MX_CHECK(tag_range(r, vat, x, "reference"));
            ref = x;
          } else if (x < 1 || x >= (int64_t)UINT32_MAX) {
            return fail(r, vat, "%.*s %zu: vertex %lld out of range",
                        shown(n), t, i + 1, (long long)x);
          } else {
            v[j] = (uint32_t)x;
          }
        }
        add_face(out, k, v, (int32_t)ref);
      }
      continue;
    }
    const int vt = medit_cell_type(code);
    const int k = mx_cell_nodes[vt];
    if (cnt > cur_left(&c) / (2 * (uint64_t)(k + 1)) + 1)
      return fail(r, at,
                  "%.*s: %llu announced but the file is too short (truncated "
                  "file or wrong count)",
                  shown(n), t, (unsigned long long)cnt);
    const size_t c0 = out->ncells;
    MX_CHECK(grow_cells(r, out, (size_t)cnt));
    for (size_t i = 0; i < cnt; i++) {
      uint32_t *row = out->conn + 8 * (c0 + i);
      for (int j = 0; j <= k; j++) {
        const char *vat = cur_skip(&c);
        int64_t v = 0;
        MX_CHECK(cur_int(&c, &v, "element"));
        if (j == k) break; /* the reference */
        if (v < 1 || v >= (int64_t)UINT32_MAX)
          return fail(r, vat, "%.*s %zu: vertex %lld out of range",
                      shown(n), t, i + 1, (long long)v);
        row[j] = (uint32_t)v;
      }
      out->type[c0 + i] = (uint8_t)vt;
    }
    out->ncells = c0 + (size_t)cnt;
  }
  if (!have_vert) return fail(r, NULL, "no Vertices");
  return medit_indices(r, out);
}

static int read_meshb(rd *r, mx_mesh_data *out) {
  cur c = {r, r->buf, 0, 0};
  r->bin_from = r->buf;
  MX_CHECK(cur_need(&c, 8, "header"));
  const uint32_t one = (uint32_t)bin_u(&c, 4);
  c.swap = one != 1;
  const int ver = (int)(int32_t)(uint32_t)bin_u(&c, 4);
  if (ver < 1 || ver > 4)
    return fail(r, r->buf + 4, "version %d (1 to 4)", ver);
  const int pos_size = ver >= 3 ? 8 : 4, cnt_size = ver >= 4 ? 8 : 4,
            real_size = ver == 1 ? 4 : 8, int_size = ver >= 4 ? 8 : 4;
  int have_vert = 0;
  size_t fcap = 0;
  const size_t len = (size_t)(r->end - r->buf);
  for (;;) {
    if (cur_left(&c) == 0) return fail(r, NULL, "no End (truncated file?)");
    const char *at = c.p;
    MX_CHECK(cur_need(&c, 4 + (uint64_t)pos_size, "keyword"));
    const int code = (int)(int32_t)(uint32_t)bin_u(&c, 4);
    const uint64_t next = bin_u(&c, pos_size);
    if (code == MED_END) break;
    const size_t here = (size_t)(c.p - r->buf);
    if (next != 0 && (next <= here - 4 - (uint64_t)pos_size || next > len))
      return fail(r, at, "keyword %d: next position %llu is not after it "
                  "and inside the file",
                  code, (unsigned long long)next);
    if (code == MED_DIM) {
      MX_CHECK(cur_need(&c, 4, "Dimension"));
      const int d = (int)(int32_t)(uint32_t)bin_u(&c, 4);
      if (d != 3)
        return fail(r, at, "Dimension %d: only 3D meshes are supported", d);
    } else if (code == MED_VERT || medit_cell_type(code) >= 0 ||
               medit_face_nodes(code)) {
      MX_CHECK(cur_need(&c, (uint64_t)cnt_size, "line count"));
      const uint64_t cnt = bin_u(&c, cnt_size);
      const int vt = medit_cell_type(code), fk = medit_face_nodes(code);
      const uint64_t line =
          fk     ? (uint64_t)(fk + 1) * (uint64_t)int_size
          : vt < 0 ? 3 * (uint64_t)real_size + (uint64_t)int_size
                   : (uint64_t)(mx_cell_nodes[vt] + 1) * (uint64_t)int_size;
      if (cnt > cur_left(&c) / line)
        return fail(r, at,
                    "keyword %d: %llu lines of %llu bytes announced but "
                    "only %zu bytes are left (truncated file or wrong "
                    "count)",
                    code, (unsigned long long)cnt, (unsigned long long)line,
                    cur_left(&c));
      if (fk) {
        MX_CHECK(face_room(r, out, &fcap, (size_t)cnt));
        for (size_t i = 0; i < cnt; i++) {
          uint32_t v[4] = {0, 0, 0, 0};
          for (int j = 0; j <= fk; j++) {
            const uint64_t u = bin_u(&c, int_size);
            const int64_t sv = int_size == 4 ? (int32_t)(uint32_t)u
                                             : (int64_t)u;
            if (j == fk) {
              MX_CHECK(tag_range(r, c.p - int_size, sv, "reference"));
              add_face(out, fk, v, (int32_t)sv);
            } else if (sv < 1 || sv >= (int64_t)UINT32_MAX) {
              return fail(r, c.p - int_size,
                          "%s %zu: vertex %lld out of range",
                          fk == 3 ? "triangle" : "quadrilateral",
                          out->nfaces, (long long)sv);
            } else {
              v[j] = (uint32_t)sv;
            }
          }
        }
      } else if (vt < 0) {
        if (have_vert) return fail(r, at, "Vertices given twice");
        have_vert = 1;
        if (cnt >= UINT32_MAX) return fail(r, at, "too many vertices");
        out->nnodes = (size_t)cnt;
        out->xyz = mx_alloc((3 * (size_t)cnt + 1) * sizeof(double));
        if (!out->xyz) return MX_EINPUT;
        for (size_t i = 0; i < cnt; i++) {
          for (int k = 0; k < 3; k++) {
            const double v = bin_real(&c, real_size);
            if (!isfinite(v))
              return fail(r, c.p - real_size,
                          "vertex %zu: coordinate %d is not a finite number",
                          i + 1, k);
            out->xyz[3 * i + (size_t)k] = v;
          }
          c.p += int_size; /* reference */
        }
      } else {
        const int k = mx_cell_nodes[vt];
        const size_t c0 = out->ncells;
        MX_CHECK(grow_cells(r, out, (size_t)cnt));
        for (size_t i = 0; i < cnt; i++) {
          uint32_t *row = out->conn + 8 * (c0 + i);
          for (int j = 0; j < k; j++) {
            const uint64_t v = bin_u(&c, int_size);
            const int64_t sv = int_size == 4 ? (int32_t)(uint32_t)v
                                             : (int64_t)v;
            if (sv < 1 || sv >= (int64_t)UINT32_MAX)
              return fail(r, c.p - int_size,
                          "element %zu: vertex %lld out of range", c0 + i,
                          (long long)sv);
            row[j] = (uint32_t)sv;
          }
          c.p += int_size; /* reference */
          out->type[c0 + i] = (uint8_t)vt;
        }
        out->ncells = c0 + (size_t)cnt;
      }
    } else if (next == 0) {
      return fail(r, at, "keyword %d has no next position", code);
    }
    if (next != 0) {
      if (r->buf + next < c.p)
        return fail(r, at, "keyword %d: its data runs past the next block",
                    code);
      c.p = r->buf + next;
    }
  }
  if (!have_vert) return fail(r, NULL, "no Vertices");
  return medit_indices(r, out);
}

/* Whether the text at p starts with "MeshVersionFormatted" (after blanks
 * and '#' comments). */
static int is_medit_ascii(rd *r, const char *p) {
  cur c = {r, p, 1, 0};
  size_t n;
  const char *t = cur_tok(&c, &n);
  return tok_eq(t, n, "MeshVersionFormatted");
}

static int is_meshb(const rd *r) {
  if (r->end - r->buf < 8) return 0;
  uint32_t a, v;
  memcpy(&a, r->buf, 4);
  memcpy(&v, r->buf + 4, 4);
  if (a == 0x01000000u) v = __builtin_bswap32(v);
  return (a == 1 || a == 0x01000000u) && v >= 1 && v <= 4;
}

/* ---- M3D, MVM and GetFEM --------------------------------------------------
 *
 * Text tokens through the cursor (no comments), in the layouts the writers
 * write (io/write_m3d.c, io/write_getfem.c):
 *  - M3D, the published mesher's (REFERENCE.md, "Published output
 *    layouts"): "[Nodes, ARRAY1<STRING>]" N, N lines "1 x y z" (the leading
 *    integer is not used), "[Elements, ARRAY1<STRING>]" M, M lines
 *    "L i0 i1 ... a b c": L is T, P, R or H (4, 5, 6, 8 nodes), a b c three
 *    numbers (not used). mixoct's older layout is read too:
 *    "[Nodes, ARRAY1<POINT3D>]" N, N lines "x y z", "[Elements,
 *    ARRAY1<STRING>]" M, M lines "k i0 ..." with k the node count;
 *  - MVM: "MIXED" N M, N lines "x y z", M lines "L i0 i1 ...";
 *  - GetFEM: '%' comment lines, "BEGIN POINTS LIST", lines "POINT i x y z"
 *    with i = 0, 1, 2, ... in order ("POINT COUNT n" lines skipped), "END
 *    POINTS LIST", "BEGIN MESH STRUCTURE DESCRIPTION", lines "CONVEX i 'GT'
 *    n0 n1 ..." with i = 0, 1, 2, ... and GetFEM's geometric transformation
 *    ("CONVEX COUNT n" skipped), "END MESH STRUCTURE DESCRIPTION", then
 *    the regions (read_mesh.h: their faces are the tagged faces); what
 *    follows them is ignored.
 * Indices are 0-based and checked against the nodes read before them. Node
 * orders are mixoct's (prisms in Gmsh's order) but for GetFEM's pyramid and
 * hexahedron, which are reordered as io/write_getfem.c describes. Counts are
 * checked against the bytes left before anything is allocated; GetFEM's
 * items are not counted up front: its arrays grow with what was read. */

/* The next tokens must be the blank-separated words of `words`. */
static int cur_words(cur *c, const char *words, const char *what) {
  for (const char *w = words; *w;) {
    const size_t wl = strcspn(w, " ");
    size_t n;
    const char *t = cur_tok(c, &n);
    if (n == 0)
      return fail(c->r, t, "%s: expected '%s', found the end of the file "
                  "(truncated file?)", what, words);
    if (n != wl || strncasecmp(t, w, n) != 0)
      return fail(c->r, t, "%s: expected '%s', found '%.*s'", what, words,
                  shown(n), t);
    w += wl;
    while (*w == ' ') w++;
  }
  return MX_OK;
}

/* Nothing but blanks may follow the last element. */
static int cur_at_end(cur *c) {
  size_t n;
  const char *t = cur_tok(c, &n);
  if (n > 0)
    return fail(c->r, t, "unexpected '%.*s' after the last element (wrong "
                "count?)", shown(n), t);
  if (t < c->r->end) return fail(c->r, t, "unexpected NUL byte");
  return MX_OK;
}

/* A count of items of at least `tokens` tokens each: they must fit in the
 * bytes left (a token and a blank take two bytes at least). */
static int cur_item_count(cur *c, uint64_t *cnt, unsigned tokens,
                          const char *what) {
  const char *at = cur_skip(c);
  MX_CHECK(cur_count(c, cnt, 0, what));
  if (*cnt > cur_left(c) / (2 * (uint64_t)tokens) + 1)
    return fail(c->r, at,
                "%s: %llu announced but the file is too short (truncated "
                "file or wrong count)",
                what, (unsigned long long)*cnt);
  return MX_OK;
}

/* n nodes, "x y z" each, after an unused integer when `numbered`. */
static int cur_nodes(cur *c, mx_mesh_data *out, uint64_t n, int numbered) {
  if (n >= UINT32_MAX)
    return fail(c->r, NULL, "%llu nodes: at most %u are supported",
                (unsigned long long)n, UINT32_MAX - 1);
  out->xyz = mx_alloc((3 * (size_t)n + 1) * sizeof(double));
  if (!out->xyz) return MX_EINPUT;
  out->nnodes = (size_t)n;
  for (size_t i = 0; i < n; i++) {
    int64_t one = 0;
    if (numbered) MX_CHECK(cur_int(c, &one, "node"));
    for (int d = 0; d < 3; d++)
      MX_CHECK(cur_real(c, &out->xyz[3 * i + (size_t)d], "node coordinate"));
  }
  return MX_OK;
}

/* The type named by an element line's letter, -1 if none. */
static int letter_type(const char *t, size_t n) {
  if (n != 1) return -1;
  switch (*t) {
    case 'T': case 't': return MX_TET;
    case 'P': case 'p': return MX_PYRAMID;
    case 'R': case 'r': return MX_PRISM;
    case 'H': case 'h': return MX_HEX;
    default: return -1;
  }
}

/* The type with k nodes (mixoct's older M3D), -1 if none. */
static int node_count_type(int64_t k) {
  switch (k) {
    case 4: return MX_TET;
    case 5: return MX_PYRAMID;
    case 6: return MX_PRISM;
    case 8: return MX_HEX;
    default: return -1;
  }
}

/* The type word opening element line `cell`: a letter, or a node count
 * when counts is set. */
static int cur_cell_type(cur *c, int counts, size_t cell, int *type) {
  size_t n;
  const char *t = cur_tok(c, &n);
  if (n == 0)
    return fail(c->r, t, "element %zu: unexpected end of file (truncated "
                "file or wrong count)", cell);
  int64_t k = 0;
  const char *e = counts ? mx_io_int(t, &k) : NULL;
  *type = counts ? (e == t + n ? node_count_type(k) : -1) : letter_type(t, n);
  if (*type >= 0) return MX_OK;
  if (counts)
    return fail(c->r, t, "element %zu: '%.*s' is not a node count (4, 5, 6 "
                "or 8)", cell, shown(n), t);
  return fail(c->r, t, "element %zu: '%.*s' is not an element type (T, P, "
              "R or H)", cell, shown(n), t);
}

/* The node indices of cell `cell` of the given type, the j-th read into
 * slot perm[j] of its row (perm NULL: slot j). */
static int cur_cell_nodes(cur *c, mx_mesh_data *out, size_t cell, int type,
                          const int8_t *perm) {
  uint32_t *row = out->conn + 8 * cell;
  memset(row, 0, 8 * sizeof *row);
  for (int j = 0; j < mx_cell_nodes[type]; j++) {
    const char *at = cur_skip(c);
    int64_t v = 0;
    MX_CHECK(cur_int(c, &v, "element node"));
    if (v < 0 || (uint64_t)v >= out->nnodes)
      return fail(c->r, at,
                  "element %zu: node %lld out of range (%zu nodes, 0-based)",
                  cell, (long long)v, out->nnodes);
    row[perm ? perm[j] : j] = (uint32_t)v;
  }
  out->type[cell] = (uint8_t)type;
  return MX_OK;
}

/* M element lines "L i0 ..." (or "k i0 ..." when counts), followed by three
 * numbers when `tail`. */
static int cur_cells(cur *c, mx_mesh_data *out, uint64_t m, int counts,
                     int tail) {
  MX_CHECK(grow_cells(c->r, out, (size_t)m));
  for (size_t i = 0; i < m; i++) {
    int type = 0;
    MX_CHECK(cur_cell_type(c, counts, i, &type));
    MX_CHECK(cur_cell_nodes(c, out, i, type, NULL));
    for (int k = 0; k < 3 * tail; k++) {
      double v;
      MX_CHECK(cur_real(c, &v, "element value"));
    }
    out->ncells = i + 1;
  }
  return MX_OK;
}

static int read_m3d(rd *r, const char *p, mx_mesh_data *out) {
  cur c = {r, p, 0, 0};
  MX_CHECK(cur_words(&c, "[Nodes,", "M3D"));
  size_t n;
  const char *t = cur_tok(&c, &n);
  const int older = tok_eq(t, n, "ARRAY1<POINT3D>]");
  if (!older && !tok_eq(t, n, "ARRAY1<STRING>]"))
    return fail(r, t, "M3D: expected 'ARRAY1<STRING>]' after '[Nodes,', "
                "found '%.*s'", shown(n), t);
  uint64_t nn = 0, nc = 0;
  MX_CHECK(cur_item_count(&c, &nn, older ? 3 : 4, "node count"));
  MX_CHECK(cur_nodes(&c, out, nn, !older));
  MX_CHECK(cur_words(&c, "[Elements, ARRAY1<STRING>]", "M3D"));
  MX_CHECK(cur_item_count(&c, &nc, older ? 5 : 8, "element count"));
  MX_CHECK(cur_cells(&c, out, nc, older, !older));
  return cur_at_end(&c);
}

static int read_mvm(rd *r, const char *p, mx_mesh_data *out) {
  cur c = {r, p, 0, 0};
  MX_CHECK(cur_words(&c, "MIXED", "MVM"));
  uint64_t nn = 0, nc = 0;
  MX_CHECK(cur_item_count(&c, &nn, 3, "node count"));
  MX_CHECK(cur_item_count(&c, &nc, 5, "element count"));
  MX_CHECK(cur_nodes(&c, out, nn, 0));
  MX_CHECK(cur_cells(&c, out, nc, 0, 0));
  return cur_at_end(&c);
}

/* GetFEM's node j of each type is slot mx_getfem_node[t][j] of our row
 * (io/getfem_tables.h: the permutations are their own inverses). */
static int getfem_type(const char *t, size_t n) {
  for (int k = 0; k < 4; k++)
    if (tok_eq(t, n, mx_getfem_geotrans[k])) return k;
  return -1;
}

/* Past blank lines and '%' comment lines. */
static const char *skip_percent_lines(const rd *r, const char *p) {
  for (;;) {
    p = skip_ws(p, r->end);
    if (p >= r->end || *p != '%') return p;
    const char *nl = memchr(p, '\n', (size_t)(r->end - p));
    p = nl ? nl + 1 : r->end;
  }
}

/* Reads "KW i" at the start of a GetFEM item line, the keyword already
 * read: *item is 1 for the item numbered `want`, 0 for a "KW COUNT n" line
 * (skipped). */
static int getfem_item(cur *c, const char *kw, size_t want, int *item) {
  const char *save = c->p;
  size_t n;
  const char *t = cur_tok(c, &n);
  if (tok_eq(t, n, "COUNT")) {
    int64_t v = 0;
    *item = 0;
    return cur_int(c, &v, kw);
  }
  c->p = save;
  const char *at = cur_skip(c);
  int64_t i = 0;
  MX_CHECK(cur_int(c, &i, kw));
  if (i < 0 || (uint64_t)i != want)
    return fail(c->r, at, "%s %lld: expected %s %zu (numbered 0, 1, 2, ... "
                "in order)", kw, (long long)i, kw, want);
  *item = 1;
  return MX_OK;
}

/* The next GetFEM line keyword: 1 for kw, 0 for END (then `end_words`
 * must follow). */
static int getfem_next(cur *c, const char *kw, const char *end_words,
                       int *more) {
  size_t n;
  const char *t = cur_tok(c, &n);
  if (tok_eq(t, n, "END")) {
    *more = 0;
    return cur_words(c, end_words, "GetFEM");
  }
  if (!tok_eq(t, n, kw)) {
    if (n == 0)
      return fail(c->r, t, "GetFEM: expected %s or END %s, found the end of "
                  "the file (truncated file?)", kw, end_words);
    return fail(c->r, t, "GetFEM: expected %s or END %s, found '%.*s'", kw,
                end_words, shown(n), t);
  }
  *more = 1;
  return MX_OK;
}

/* Room for one more node (capacity *cap, doubled). */
static int reserve_node(rd *r, mx_mesh_data *out, size_t *cap) {
  if (out->nnodes < *cap) return MX_OK;
  if (out->nnodes >= UINT32_MAX - 1)
    return fail(r, NULL, "more than %u points", UINT32_MAX - 1);
  const size_t nc = *cap ? 2 * *cap : 1024;
  double *x = mx_realloc(out->xyz, 3 * nc * sizeof *x);
  if (!x) return MX_EINPUT;
  out->xyz = x;
  *cap = nc;
  return MX_OK;
}

/* Room for one more cell (capacity *cap, doubled). */
static int reserve_cell(rd *r, mx_mesh_data *out, size_t *cap) {
  if (out->ncells < *cap) return MX_OK;
  if (out->ncells >= UINT32_MAX / 6)
    return fail(r, NULL, "more than %u volume elements", UINT32_MAX / 6);
  const size_t nc = *cap ? 2 * *cap : 1024;
  uint8_t *t = mx_realloc(out->type, nc);
  if (!t) return MX_EINPUT;
  out->type = t;
  uint32_t *cn = mx_realloc(out->conn, 8 * nc * sizeof *cn);
  if (!cn) return MX_EINPUT;
  out->conn = cn;
  *cap = nc;
  return MX_OK;
}

static int getfem_points(cur *c, mx_mesh_data *out) {
  size_t cap = 0;
  for (;;) {
    int more = 0, item = 0;
    MX_CHECK(getfem_next(c, "POINT", "POINTS LIST", &more));
    if (!more) return MX_OK;
    MX_CHECK(getfem_item(c, "POINT", out->nnodes, &item));
    if (!item) continue;
    MX_CHECK(reserve_node(c->r, out, &cap));
    double *p = out->xyz + 3 * out->nnodes;
    for (int d = 0; d < 3; d++)
      MX_CHECK(cur_real(c, &p[d], "point coordinate"));
    out->nnodes++;
  }
}

static int getfem_convexes(cur *c, mx_mesh_data *out) {
  size_t cap = 0;
  for (;;) {
    int more = 0, item = 0;
    MX_CHECK(getfem_next(c, "CONVEX", "MESH STRUCTURE DESCRIPTION", &more));
    if (!more) return MX_OK;
    MX_CHECK(getfem_item(c, "CONVEX", out->ncells, &item));
    if (!item) continue;
    size_t n;
    const char *t = cur_tok(c, &n);
    const int type = getfem_type(t, n);
    if (n == 0)
      return fail(c->r, t, "convex %zu: unexpected end of file (truncated "
                  "file?)", out->ncells);
    if (type < 0)
      return fail(c->r, t, "convex %zu: %.*s is not a geometric "
                  "transformation mixoct reads ('GT_PK(3,1)', "
                  "'GT_PYRAMID(1)', 'GT_PRISM(3,1)', 'GT_QK(3,1)')",
                  out->ncells, shown(n), t);
    MX_CHECK(reserve_cell(c->r, out, &cap));
    MX_CHECK(cur_cell_nodes(c, out, out->ncells, type, mx_getfem_node[type]));
    out->ncells++;
  }
}

/* One item of a region: "cv/f" (a face: added with tag t) or "cv" (a
 * whole convex: skipped). */
static int getfem_region_item(cur *c, const char *it, size_t n, int32_t t,
                              mx_mesh_data *out, size_t *cap) {
  int64_t cv = 0, g = -1;
  const char *e = mx_io_int(it, &cv);
  const char *slash = e && e < it + n && *e == '/' ? e : NULL;
  if (slash) e = mx_io_int(slash + 1, &g);
  if (!e || e != it + n)
    return fail(c->r, it, "region %d: '%.*s' is not a convex number or "
                "convex/face", t, shown(n), it);
  if (cv < 0 || (uint64_t)cv >= out->ncells)
    return fail(c->r, it, "region %d: convex %lld out of range (%zu "
                "convexes, 0-based)", t, (long long)cv, out->ncells);
  if (!slash) return MX_OK;
  const int type = out->type[cv];
  const int f = g >= 0 ? mx_getfem_local_face(type, g) : -1;
  if (f < 0)
    return fail(c->r, it, "region %d: convex %lld (%s) has no face %lld",
                t, (long long)cv, mx_getfem_geotrans[type], (long long)g);
  MX_CHECK(face_room(c->r, out, cap, 1));
  const int8_t *fl = mx_cell_faces[type][f];
  const int k = fl[3] < 0 ? 3 : 4;
  uint32_t v[4] = {0, 0, 0, 0};
  for (int j = 0; j < k; j++) v[j] = out->conn[8 * (size_t)cv + (size_t)fl[j]];
  add_face(out, k, v, t);
  return MX_OK;
}

/* The regions after the convexes: "BEGIN REGION t", items, "END REGION t"
 * (BOUNDARY for REGION, as older GetFEM wrote). Anything else ends them. */
static int getfem_regions(cur *c, mx_mesh_data *out) {
  size_t cap = 0;
  for (;;) {
    const char *save = c->p;
    size_t n;
    const char *t = cur_tok(c, &n);
    if (!tok_eq(t, n, "BEGIN")) break;
    const char *w = cur_tok(c, &n);
    const int region = tok_eq(w, n, "REGION");
    if (!region && !tok_eq(w, n, "BOUNDARY")) {
      c->p = save;
      break;
    }
    const char *at = cur_skip(c);
    int64_t num = 0;
    MX_CHECK(cur_int(c, &num, "GetFEM region number"));
    if (num < 0 || num > INT32_MAX)
      return fail(c->r, at, "region number %lld is out of range (0 to %d)",
                  (long long)num, INT32_MAX);
    for (;;) {
      const char *it = cur_tok(c, &n);
      if (n == 0)
        return fail(c->r, it, "region %lld: no END %s (truncated file?)",
                    (long long)num, region ? "REGION" : "BOUNDARY");
      if (tok_eq(it, n, "END")) break;
      MX_CHECK(getfem_region_item(c, it, n, (int32_t)num, out, &cap));
    }
    MX_CHECK(cur_words(c, region ? "REGION" : "BOUNDARY", "GetFEM"));
    at = cur_skip(c);
    int64_t again = 0;
    MX_CHECK(cur_int(c, &again, "GetFEM region number"));
    if (again != num)
      return fail(c->r, at, "END REGION %lld closes region %lld",
                  (long long)again, (long long)num);
  }
  return MX_OK;
}

static int read_getfem(rd *r, const char *p, mx_mesh_data *out) {
  cur c = {r, skip_percent_lines(r, p), 0, 0};
  MX_CHECK(cur_words(&c, "BEGIN POINTS LIST", "GetFEM"));
  MX_CHECK(getfem_points(&c, out));
  MX_CHECK(cur_words(&c, "BEGIN MESH STRUCTURE DESCRIPTION", "GetFEM"));
  MX_CHECK(getfem_convexes(&c, out));
  return getfem_regions(&c, out);
}

/* Whether the first token at p (after blank lines, and '%' comment lines
 * when percent is set) is word. */
static int first_word_is(const rd *r, const char *p, int percent,
                         const char *word) {
  const char *t = percent ? skip_percent_lines(r, p) : skip_ws(p, r->end);
  return tok_eq(t, tok_len(t, r->end), word);
}

/* Whether the last path component ends with ext. */
static int has_extension(const char *path, const char *ext) {
  const size_t n = strlen(path), e = strlen(ext);
  return n > e && strcasecmp(path + n - e, ext) == 0;
}

/* The reader of the M3D, MVM and GetFEM files: chosen by content, else
 * by the extension (for a message in that format's terms). NULL if none. */
typedef int (*text_reader)(rd *, const char *, mx_mesh_data *);
static text_reader published_reader(const rd *r, const char *p) {
  if (first_word_is(r, p, 0, "[Nodes,")) return read_m3d;
  if (first_word_is(r, p, 0, "MIXED")) return read_mvm;
  if ((p < r->end && *p == '%') || first_word_is(r, p, 1, "BEGIN"))
    return read_getfem;
  if (has_extension(r->path, ".m3d")) return read_m3d;
  if (has_extension(r->path, ".mvm")) return read_mvm;
  if (has_extension(r->path, ".getfem")) return read_getfem;
  return NULL;
}

/* ---- entry points -------------------------------------------------------- */

/* A regular file whose size is not a multiple of the page size is mapped:
 * no copy, and the rest of its last page reads as zeros, so the text is
 * NUL-terminated like a loaded one. Anything else is loaded. *mapped
 * receives the mapping's length, or 0. */
static int load(const char *path, char **buf, size_t *len, size_t *mapped) {
  *mapped = 0;
  const long page = sysconf(_SC_PAGESIZE);
  int fd = open(path, O_RDONLY | O_CLOEXEC);
  if (fd >= 0) {
    struct stat st;
    if (fstat(fd, &st) == 0 && S_ISREG(st.st_mode) && st.st_size > 0 &&
        page > 0 && st.st_size % page != 0) {
      void *p = mmap(NULL, (size_t)st.st_size, PROT_READ,
                     MAP_PRIVATE | MAP_POPULATE, fd, 0);
      if (p != MAP_FAILED) {
        close(fd);
        *buf = p;
        *len = (size_t)st.st_size;
        *mapped = *len;
        return MX_OK;
      }
    }
    close(fd);
  }
  return mx_io_load(path, buf, len); /* and its messages */
}

/* A mesh file; with piece set, a piece of a .pvtu: a VTU file only, its
 * GlobalNodeId and array signatures in *piece (piece->gid freed on
 * failure). */
static int read_file(const char *path, int planar, piece_info *piece, mx_mesh_data *out) {
  memset(out, 0, sizeof *out);
  if (piece) memset(piece, 0, sizeof *piece);
  char *buf;
  size_t len, mapped;
  MX_CHECK(load(path, &buf, &len, &mapped));
  rd r;
  memset(&r, 0, sizeof r);
  r.path = path;
  r.buf = buf;
  r.end = buf + len;
  r.planar = planar;
  r.piece = piece;
  const char *p = r.buf;
  if (len >= 3 && memcmp(p, "\xEF\xBB\xBF", 3) == 0) p += 3; /* UTF-8 BOM */
  p = skip_ws(p, r.end);
  static const char magic[] = "# vtk DataFile", msh_magic[] = "$MeshFormat";
  int st, vtk = 0;
  if (piece && !(p < r.end && *p == '<')) {
    st = fail(&r, p, "a piece of a .pvtu must be a VTU file (VTK XML UnstructuredGrid)");
  } else if ((size_t)(r.end - p) >= sizeof magic - 1 &&
      strncasecmp(p, magic, sizeof magic - 1) == 0) {
    st = read_legacy(&r, out);
    vtk = 1;
  } else if (is_meshb(&r)) {
    st = read_meshb(&r, out);
  } else if (p < r.end && *p == '<') {
    st = read_vtu(&r, out);
    vtk = 1;
  } else if ((size_t)(r.end - p) >= sizeof msh_magic - 1 &&
             memcmp(p, msh_magic, sizeof msh_magic - 1) == 0) {
    st = read_msh(&r, p, out);
  } else if (is_medit_ascii(&r, p)) {
    st = read_medit_ascii(&r, p, out);
  } else if (published_reader(&r, p)) {
    st = published_reader(&r, p)(&r, p, out);
  } else {
    st = fail(&r, p,
              "unknown mesh format: expected legacy VTK ('# vtk DataFile "
              "Version'), VTK XML (.vtu), Gmsh MSH 4.1 ('$MeshFormat'), "
              "Medit ('MeshVersionFormatted', or a binary .meshb), M3D "
              "('[Nodes,'), MVM ('MIXED') or GetFEM ('BEGIN POINTS LIST')");
  }
  if (st == MX_OK && vtk && !r.merged) /* VTK wedges to our prism order (mesh.h) */
    for (size_t c = 0; c < out->ncells; c++)
      if (out->type[c] == MX_PRISM) {
        uint32_t row[8];
        memcpy(row, out->conn + 8 * c, sizeof row);
        for (int j = 0; j < 6; j++) out->conn[8 * c + j] = row[mx_vtk_order[MX_PRISM][j]];
      }
  for (int i = 0; i < r.ntmp; i++) mx_free(r.tmp[i]);
  if (mapped)
    munmap(buf, mapped);
  else
    mx_free(buf);
  if (st != MX_OK) {
    mx_mesh_data_free(out);
    if (piece) {
      mx_free(piece->gid);
      piece->gid = NULL;
    }
  }
  return st;
}

int mx_read_mesh(const char *path, mx_mesh_data *out) {
  return read_file(path, 0, NULL, out);
}

int mx_read_mesh_planar(const char *path, mx_mesh_data *out) {
  return read_file(path, 1, NULL, out);
}
