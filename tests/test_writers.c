/* Tests of the mesh writers (legacy VTK binary/ASCII, VTU) and of the
 * atomic output file: files are parsed back with small independent readers
 * written here from the format specifications, failures (missing or
 * unwritable directory, full disk, file size limit) must leave nothing
 * behind, the bytes must not depend on the thread count, and the write
 * speed on a 1M-hexahedra grid is printed.
 * Run as "test_writers small" to skip the large meshes (for valgrind). */
#include <dirent.h>
#include <errno.h>
#include <math.h>
#include <omp.h>
#include <signal.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <unistd.h>

#include "check.h"
#include "base/common.h"
#include "io/atomic_file.h"
#include "soa/mesh.h"

#define OUT_DIR "writers_out"
#include "file_util.h"
#include "io/write_mesh.h"

/* ====================================================================== */
/* Test meshes                                                            */
/* ====================================================================== */

typedef struct {
  size_t nnodes, ncells;
  double *xyz;
  uint8_t *type;
  uint32_t *conn;
  int32_t *level, *tag;
  double *jens, *dist;
  mx_field cf[2], pf[2];
  mx_mesh_view v;
} fmesh;

static void fmesh_alloc(fmesh *t, size_t nnodes, size_t ncells) {
  memset(t, 0, sizeof *t);
  t->nnodes = nnodes;
  t->ncells = ncells;
  t->xyz = calloc(3 * nnodes + 1, sizeof(double));
  t->dist = calloc(nnodes + 1, sizeof(double));
  t->tag = calloc(nnodes + 1, sizeof(int32_t));
  t->type = calloc(ncells + 1, 1);
  t->conn = calloc(8 * ncells + 1, sizeof(uint32_t));
  t->level = calloc(ncells + 1, sizeof(int32_t));
  t->jens = calloc(ncells + 1, sizeof(double));
  if (!t->xyz || !t->dist || !t->tag || !t->type || !t->conn || !t->level ||
      !t->jens) {
    fprintf(stderr, "test: out of memory\n");
    exit(2);
  }
}

static void fmesh_view(fmesh *t) {
  t->cf[0] = (mx_field){.name = "level", .is_double = 0, .ivalues = t->level};
  t->cf[1] = (mx_field){.name = "jens", .is_double = 1, .dvalues = t->jens};
  t->pf[0] = (mx_field){.name = "dist", .is_double = 1, .dvalues = t->dist};
  t->pf[1] = (mx_field){.name = "tag", .is_double = 0, .ivalues = t->tag};
  t->v = (mx_mesh_view){.nnodes = t->nnodes, .xyz = t->xyz, .ncells = t->ncells,
                        .type = t->type, .conn = t->conn, .ncell_fields = 2,
                        .cell_fields = t->cf, .npoint_fields = 2, .point_fields = t->pf};
}

static void fmesh_free(fmesh *t) {
  free(t->xyz);
  free(t->dist);
  free(t->tag);
  free(t->type);
  free(t->conn);
  free(t->level);
  free(t->jens);
  memset(t, 0, sizeof *t);
}

static void fmesh_set_cell(fmesh *t, size_t c, int type, const uint32_t *nodes) {
  t->type[c] = (uint8_t)type;
  for (int j = 0; j < mx_cell_nodes[type]; j++) t->conn[8 * c + j] = nodes[j];
  for (int j = mx_cell_nodes[type]; j < 8; j++) t->conn[8 * c + j] = 0xdeadbeef;
}

/* A unit hexahedron, a prism on its x=1 face side, a pyramid on its top and
 * a tetrahedron, all sharing nodes; awkward coordinates and field values. */
static void small_mesh(fmesh *t) {
  static const double xyz[12][3] = {
      {0, 0, 0},
      {1, 0, 0},
      {1, 1, 0},
      {0, 1, 0},
      {0, 0, 1},
      {1, 0, 1},
      {1, 1, 1},
      {0, 1, 1},
      {2, 0, 0},
      {2, 0, 1},
      {0.5, 0.5, 1.0 + 1.0 / 3.0},
      {2.0000000000000004, -2.5e-7, 123456789.123}};
  fmesh_alloc(t, 12, 4);
  memcpy(t->xyz, xyz, sizeof xyz);
  t->xyz[3 * 3 + 1] = 0.1;
  t->xyz[3 * 7 + 2] = -1e-300;
  static const uint32_t hex[8] = {0, 1, 2, 3, 4, 5, 6, 7};
  static const uint32_t prism[6] = {1, 8, 2, 5, 9, 6};
  static const uint32_t pyr[5] = {4, 5, 6, 7, 10};
  static const uint32_t tet[4] = {5, 9, 6, 11};
  fmesh_set_cell(t, 0, MX_HEX, hex);
  fmesh_set_cell(t, 1, MX_PRISM, prism);
  fmesh_set_cell(t, 2, MX_PYRAMID, pyr);
  fmesh_set_cell(t, 3, MX_TET, tet);
  static const int32_t level[4] = {0, 1, -2, 2147483647};
  static const double jens[4] = {1.0, 0.5, 1.0 / 3.0, -1e-9};
  memcpy(t->level, level, sizeof level);
  memcpy(t->jens, jens, sizeof jens);
  for (size_t i = 0; i < 12; i++) {
    t->dist[i] = sqrt((double)i) - 1.5;
    t->tag[i] = (int32_t)(i * 1000003u) - 5000000;
  }
  fmesh_view(t);
}

static uint64_t rng_state = 0x9E3779B97F4A7C15ull;
static uint64_t rng_next(void) {
  rng_state ^= rng_state << 13;
  rng_state ^= rng_state >> 7;
  rng_state ^= rng_state << 17;
  return rng_state;
}

/* A double of random bits (finite), or of a "decimal-looking" kind. */
static double rng_double(void) {
  uint64_t r = rng_next();
  if (r % 3 == 0) return (double)(int64_t)(rng_next() % 2000001) / 1000.0 - 1e3;
  double d;
  do {
    uint64_t b = rng_next();
    memcpy(&d, &b, 8);
  } while (!isfinite(d));
  return d;
}

/* An n^3 grid of hexahedra over [-1.3, 1.3]^3; when mixed, some cells are
 * relabelled tet/pyramid/prism (format-valid, geometry irrelevant). */
static void grid_mesh(fmesh *t, size_t n, int mixed) {
  size_t np = n + 1;
  fmesh_alloc(t, np * np * np, n * n * n);
  double h = 2.6 / (double)n;
  for (size_t k = 0; k < np; k++)
    for (size_t j = 0; j < np; j++)
      for (size_t i = 0; i < np; i++) {
        size_t p = (k * np + j) * np + i;
        t->xyz[3 * p] = -1.3 + h * (double)i;
        t->xyz[3 * p + 1] = -1.3 + h * (double)j;
        t->xyz[3 * p + 2] = -1.3 + h * (double)k;
        t->dist[p] = rng_double();
        t->tag[p] = (int32_t)(uint32_t)rng_next();
      }
  for (size_t k = 0; k < n; k++)
    for (size_t j = 0; j < n; j++)
      for (size_t i = 0; i < n; i++) {
        size_t c = (k * n + j) * n + i;
        uint32_t b = (uint32_t)((k * np + j) * np + i);
        uint32_t sx = 1, sy = (uint32_t)np, sz = (uint32_t)(np * np);
        uint32_t nodes[8] = {
            b,      b + sx,      b + sx + sy,      b + sy,
            b + sz, b + sx + sz, b + sx + sy + sz, b + sy + sz};
        int type = mixed ? (int)(rng_next() % 4) : MX_HEX;
        fmesh_set_cell(t, c, type, nodes);
        t->level[c] = (int32_t)(c % 11) - 3;
        t->jens[c] = mixed ? rng_double() : 1.0 / (double)(c + 1);
      }
  fmesh_view(t);
}

/* ====================================================================== */
/* A mesh as read back                                                    */
/* ====================================================================== */

typedef struct {
  char name[256];
  int is_double, on_points;
  size_t n;
  double *d;
  int64_t *i;
} rfield;

typedef struct {
  size_t nnodes, ncells;
  double *xyz;
  size_t list_len;
  int64_t *list; /* legacy style: count, ids, count, ids, ... */
  int64_t *types;
  int nf;
  rfield f[8];
  int ok;
} rmesh;

static void rmesh_free(rmesh *r) {
  free(r->xyz);
  free(r->list);
  free(r->types);
  for (int k = 0; k < r->nf; k++) {
    free(r->f[k].d);
    free(r->f[k].i);
  }
  memset(r, 0, sizeof *r);
}

static rfield *rmesh_add_field(rmesh *r, const char *name, int is_double,
                               int on_points, size_t n) {
  if (r->nf >= 8) return NULL;
  rfield *f = &r->f[r->nf++];
  snprintf(f->name, sizeof f->name, "%s", name);
  f->is_double = is_double;
  f->on_points = on_points;
  f->n = n;
  if (is_double)
    f->d = calloc(n + 1, sizeof(double));
  else
    f->i = calloc(n + 1, sizeof(int64_t));
  return f;
}

static const rfield *rmesh_find(const rmesh *r, const char *name,
                                int on_points) {
  for (int k = 0; k < r->nf; k++) {
    if (!strcmp(r->f[k].name, name) && r->f[k].on_points == on_points)
      return &r->f[k];
  }
  return NULL;
}

static int same_bits(double a, double b) {
  return memcmp(&a, &b, 8) == 0;
}

static int compare_field(const rmesh *r, const mx_field *fd, size_t count,
                         int on_points) {
  const rfield *f = rmesh_find(r, fd->name, on_points);
  if (!f || f->is_double != fd->is_double || f->n != count) return 0;
  for (size_t i = 0; i < count; i++) {
    if (fd->is_double && !same_bits(f->d[i], mx_field_double(fd, i))) return 0;
    if (!fd->is_double && f->i[i] != mx_field_int(fd, i)) return 0;
  }
  return 1;
}

static int compare_cells(const rmesh *r, const mx_mesh_view *m) {
  size_t pos = 0;
  for (size_t c = 0; c < m->ncells; c++) {
    int nn = mx_cell_nodes[m->type[c]];
    if (r->types[c] != mx_vtk_cell_type[m->type[c]]) return 0;
    if (pos + 1 + (size_t)nn > r->list_len || r->list[pos] != nn) return 0;
    for (int j = 0; j < nn; j++) {
      if (r->list[pos + 1 + j] != (int64_t)m->conn[8 * c + (size_t)mx_vtk_order[m->type[c]][j]]) return 0;
    }
    pos += 1 + (size_t)nn;
  }
  return pos == r->list_len;
}

/* Everything bit-exact: coordinates, connectivity, types, fields. */
static int compare_mesh(const rmesh *r, const mx_mesh_view *m) {
  if (!r->ok || r->nnodes != m->nnodes || r->ncells != m->ncells) return 0;
  for (size_t i = 0; i < 3 * m->nnodes; i++) {
    if (!same_bits(r->xyz[i], m->xyz[i])) return 0;
  }
  if (!compare_cells(r, m)) return 0;
  if (r->nf != m->ncell_fields + m->npoint_fields) return 0;
  for (int k = 0; k < m->ncell_fields; k++) {
    if (!compare_field(r, &m->cell_fields[k], m->ncells, 0)) return 0;
  }
  for (int k = 0; k < m->npoint_fields; k++) {
    if (!compare_field(r, &m->point_fields[k], m->nnodes, 1)) return 0;
  }
  return 1;
}

/* ====================================================================== */
/* Legacy VTK reader (from the "VTK File Formats" specification)           */
/* ====================================================================== */

typedef struct {
  const char *p, *end;
  int binary;
} lcur;

static int l_line(lcur *c, char *out, size_t cap) {
  const char *nl = memchr(c->p, '\n', (size_t)(c->end - c->p));
  if (!nl) return 0;
  size_t n = (size_t)(nl - c->p);
  if (n >= cap) return 0;
  memcpy(out, c->p, n);
  out[n] = '\0';
  c->p = nl + 1;
  return 1;
}

static uint64_t load_be(const char *p, int bytes) {
  uint64_t v = 0;
  for (int k = 0; k < bytes; k++) v = (v << 8) | (unsigned char)p[k];
  return v;
}

static int l_double(lcur *c, double *out) {
  if (c->binary) {
    if (c->end - c->p < 8) return 0;
    uint64_t v = load_be(c->p, 8);
    memcpy(out, &v, 8);
    c->p += 8;
    return 1;
  }
  char *e;
  errno = 0;
  *out = strtod(c->p, &e);
  if (e == c->p) return 0;
  c->p = e;
  return 1;
}

static int l_int(lcur *c, int64_t *out) {
  if (c->binary) {
    if (c->end - c->p < 4) return 0;
    *out = (int32_t)(uint32_t)load_be(c->p, 4);
    c->p += 4;
    return 1;
  }
  char *e;
  *out = strtoll(c->p, &e, 10);
  if (e == c->p) return 0;
  c->p = e;
  return 1;
}

static void decode_name(const char *in, char *out) {
  while (*in) {
    unsigned v;
    if (in[0] == '%' && sscanf(in + 1, "%2x", &v) == 1) {
      *out++ = (char)v;
      in += 3;
    } else {
      *out++ = *in++;
    }
  }
  *out = '\0';
}

static int l_points(lcur *c, rmesh *r, const char *line) {
  size_t n;
  char type[32];
  if (sscanf(line, "POINTS %zu %31s", &n, type) != 2) return 0;
  if (strcmp(type, "double")) return 0;
  r->nnodes = n;
  r->xyz = calloc(3 * n + 1, sizeof(double));
  for (size_t i = 0; i < 3 * n; i++) {
    if (!l_double(c, &r->xyz[i])) return 0;
  }
  return 1;
}

static int l_cells(lcur *c, rmesh *r, const char *line) {
  size_t n, size;
  if (sscanf(line, "CELLS %zu %zu", &n, &size) != 2) return 0;
  r->ncells = n;
  r->list_len = size;
  r->list = calloc(size + 1, sizeof(int64_t));
  for (size_t i = 0; i < size; i++) {
    if (!l_int(c, &r->list[i])) return 0;
  }
  return 1;
}

static int l_types(lcur *c, rmesh *r, const char *line) {
  size_t n;
  if (sscanf(line, "CELL_TYPES %zu", &n) != 1 || n != r->ncells) return 0;
  r->types = calloc(n + 1, sizeof(int64_t));
  for (size_t i = 0; i < n; i++) {
    if (!l_int(c, &r->types[i])) return 0;
  }
  return 1;
}

static int l_scalars(lcur *c, rmesh *r, const char *line, int on_points,
                     size_t count) {
  char raw[256], name[256], type[32], lut[256];
  int ncomp;
  if (sscanf(line, "SCALARS %255s %31s %d", raw, type, &ncomp) != 3) return 0;
  if (ncomp != 1 || !l_line(c, lut, sizeof lut)) return 0;
  if (strcmp(lut, "LOOKUP_TABLE default")) return 0;
  int is_double = !strcmp(type, "double");
  if (!is_double && strcmp(type, "int")) return 0;
  decode_name(raw, name);
  rfield *f = rmesh_add_field(r, name, is_double, on_points, count);
  if (!f) return 0;
  for (size_t i = 0; i < count; i++) {
    if (is_double ? !l_double(c, &f->d[i]) : !l_int(c, &f->i[i])) return 0;
  }
  return 1;
}

static int l_section(lcur *c, rmesh *r, const char *line, int *on_points,
                     size_t *count) {
  if (!strncmp(line, "POINTS ", 7)) return l_points(c, r, line);
  if (!strncmp(line, "CELLS ", 6)) return l_cells(c, r, line);
  if (!strncmp(line, "CELL_TYPES ", 11)) return l_types(c, r, line);
  if (sscanf(line, "CELL_DATA %zu", count) == 1) {
    *on_points = 0;
    return *count == r->ncells;
  }
  if (sscanf(line, "POINT_DATA %zu", count) == 1) {
    *on_points = 1;
    return *count == r->nnodes;
  }
  if (!strncmp(line, "SCALARS ", 8) && *on_points >= 0)
    return l_scalars(c, r, line, *on_points, *count);
  return 0;
}

static int read_legacy(const char *path, rmesh *r, int expect_binary) {
  memset(r, 0, sizeof *r);
  size_t len;
  char *buf = slurp(path, &len);
  if (!buf) return 0;
  lcur c = {buf, buf + len, 0};
  char line[1024];
  int ok = l_line(&c, line, sizeof line) &&
           !strcmp(line, "# vtk DataFile Version 3.0") &&
           l_line(&c, line, sizeof line) && l_line(&c, line, sizeof line);
  if (ok) {
    c.binary = !strcmp(line, "BINARY");
    ok = (c.binary || !strcmp(line, "ASCII")) && c.binary == expect_binary;
  }
  ok = ok && l_line(&c, line, sizeof line) &&
       !strcmp(line, "DATASET UNSTRUCTURED_GRID");
  int on_points = -1;
  size_t count = 0;
  while (ok) {
    while (c.p < c.end && (*c.p == '\n' || *c.p == ' ')) c.p++;
    if (c.p == c.end) break;
    ok = l_line(&c, line, sizeof line) &&
         l_section(&c, r, line, &on_points, &count);
  }
  free(buf);
  r->ok = ok && r->list && r->types;
  if (r->ok && r->ncells == 0 && r->nnodes == 0) r->ok = 1;
  return r->ok;
}

/* ====================================================================== */
/* VTU reader (from the VTK XML file format specification)                */
/* ====================================================================== */

/* Value of attribute name inside the tag [tag, tag_end), "" if missing. */
static void xml_attr(const char *tag, const char *tag_end, const char *name,
                     char *out, size_t cap) {
  char key[64];
  snprintf(key, sizeof key, " %s=\"", name);
  out[0] = '\0';
  const char *p = tag;
  size_t klen = strlen(key);
  for (; p + klen < tag_end; p++) {
    if (memcmp(p, key, klen) == 0) {
      const char *v = p + klen, *q = memchr(v, '"', (size_t)(tag_end - v));
      if (!q || (size_t)(q - v) >= cap) return;
      memcpy(out, v, (size_t)(q - v));
      out[q - v] = '\0';
      return;
    }
  }
}

static const char *last_before(const char *buf, const char *pos,
                               const char *needle) {
  const char *best = NULL, *p = buf;
  while ((p = strstr(p, needle)) && p < pos) best = p++;
  return best;
}

/* Which section a DataArray at pos belongs to. */
static const char *xml_section(const char *buf, const char *pos) {
  static const char *names[4] = {"<PointData", "<CellData", "<Points>",
                                 "<Cells>"};
  const char *best = NULL, *which = "";
  for (int k = 0; k < 4; k++) {
    const char *p = last_before(buf, pos, names[k]);
    if (p && (!best || p > best)) {
      best = p;
      which = names[k];
    }
  }
  return which;
}

/* Replaces the five predefined XML entities in place. */
static void xml_unescape(char *s) {
  static const char *ent[5] = {"&amp;", "&lt;", "&gt;", "&quot;", "&apos;"};
  static const char chr[5] = {'&', '<', '>', '"', '\''};
  char *w = s;
  while (*s) {
    int k = 0;
    while (k < 5 && strncmp(s, ent[k], strlen(ent[k]))) k++;
    if (k < 5) {
      *w++ = chr[k];
      s += strlen(ent[k]);
    } else {
      *w++ = *s++;
    }
  }
  *w = '\0';
}

typedef struct {
  const char *data; /* first byte after the UInt64 count */
  uint64_t bytes;
  char type[32], name[256], section[16];
  int ncomp;
} vtu_array;

static uint64_t load_le64(const char *p) {
  uint64_t v = 0;
  for (int k = 7; k >= 0; k--) v = (v << 8) | (unsigned char)p[k];
  return v;
}

static int vtu_arrays(const char *buf, size_t len, const char *appended,
                      vtu_array *arr, int max, uint64_t *data_end) {
  const char *under = strchr(appended, '_');
  if (!under) return -1;
  const char *base = under + 1, *p = buf;
  int n = 0;
  *data_end = 0;
  while ((p = strstr(p, "<DataArray")) && p < appended && n < max) {
    const char *end = strstr(p, ">");
    vtu_array *a = &arr[n++];
    char tmp[64];
    xml_attr(p, end, "type", a->type, sizeof a->type);
    xml_attr(p, end, "Name", a->name, sizeof a->name);
    xml_unescape(a->name);
    snprintf(a->section, sizeof a->section, "%s", xml_section(buf, p));
    xml_attr(p, end, "NumberOfComponents", tmp, sizeof tmp);
    a->ncomp = tmp[0] ? atoi(tmp) : 1;
    xml_attr(p, end, "format", tmp, sizeof tmp);
    if (strcmp(tmp, "appended")) return -1;
    xml_attr(p, end, "offset", tmp, sizeof tmp);
    uint64_t off = strtoull(tmp, NULL, 10);
    if ((size_t)(base - buf) + off + 8 > len) return -1;
    a->bytes = load_le64(base + off);
    a->data = base + off + 8;
    uint64_t stop = (uint64_t)(a->data - buf) + a->bytes;
    if (stop > len) return -1;
    if (stop > *data_end) *data_end = stop;
    p = end;
  }
  return n;
}

static int vtu_header_ok(const char *buf, size_t *np, size_t *nc) {
  const char *v = strstr(buf, "<VTKFile"), *ve = v ? strchr(v, '>') : NULL;
  const char *pc = strstr(buf, "<Piece"), *pe = pc ? strchr(pc, '>') : NULL;
  if (!ve || !pe) return 0;
  char a[64], b[64], c[64], d[64];
  xml_attr(v, ve, "type", a, sizeof a);
  xml_attr(v, ve, "version", b, sizeof b);
  xml_attr(v, ve, "byte_order", c, sizeof c);
  xml_attr(v, ve, "header_type", d, sizeof d);
  if (strcmp(a, "UnstructuredGrid") || strcmp(b, "1.0") ||
      strcmp(c, "LittleEndian") || strcmp(d, "UInt64"))
    return 0;
  xml_attr(pc, pe, "NumberOfPoints", a, sizeof a);
  xml_attr(pc, pe, "NumberOfCells", b, sizeof b);
  if (!a[0] || !b[0]) return 0;
  *np = strtoull(a, NULL, 10);
  *nc = strtoull(b, NULL, 10);
  return 1;
}

static int vtu_take_points(rmesh *r, const vtu_array *a) {
  if (strcmp(a->type, "Float64") || a->ncomp != 3 ||
      a->bytes != 24 * (uint64_t)r->nnodes)
    return 0;
  r->xyz = calloc(3 * r->nnodes + 1, sizeof(double));
  memcpy(r->xyz, a->data, a->bytes);
  return 1;
}

static int vtu_take_field(rmesh *r, const vtu_array *a, int on_points) {
  size_t count = on_points ? r->nnodes : r->ncells;
  int is_double = !strcmp(a->type, "Float64");
  const int u8 = !strcmp(a->type, "UInt8"); /* integer fields within 0..255 */
  if (!is_double && !u8 && strcmp(a->type, "Int32")) return 0;
  if (a->ncomp != 1 || a->bytes != count * (is_double ? 8u : u8 ? 1u : 4u)) return 0;
  rfield *f = rmesh_add_field(r, a->name, is_double, on_points, count);
  if (!f) return 0;
  for (size_t i = 0; i < count; i++) {
    if (is_double) {
      memcpy(&f->d[i], a->data + 8 * i, 8);
    } else if (u8) {
      f->i[i] = (uint8_t)a->data[i];
    } else {
      int32_t v;
      memcpy(&v, a->data + 4 * i, 4);
      f->i[i] = v;
    }
  }
  return 1;
}

/* Builds the legacy-style list from connectivity + end offsets. */
static int vtu_take_cells(rmesh *r, const vtu_array *conn,
                          const vtu_array *offs, const vtu_array *types) {
  size_t nc = r->ncells;
  /* Int32 indices, or Int64 when Int32 cannot hold them */
  if (!conn || !offs || !types || strcmp(types->type, "UInt8") || types->bytes != nc ||
      strcmp(conn->type, offs->type) ||
      (strcmp(conn->type, "Int64") && strcmp(conn->type, "Int32")))
    return 0;
  const size_t w = strcmp(conn->type, "Int64") ? 4 : 8;
  if (offs->bytes != w * (uint64_t)nc) return 0;
  size_t nconn = conn->bytes / w;
  r->list_len = nconn + nc;
  r->list = calloc(r->list_len + 1, sizeof(int64_t));
  r->types = calloc(nc + 1, sizeof(int64_t));
  int64_t prev = 0;
  size_t pos = 0;
  for (size_t c = 0; c < nc; c++) {
    int64_t end;
    if (w == 8) {
      memcpy(&end, offs->data + 8 * c, 8);
    } else {
      int32_t e32;
      memcpy(&e32, offs->data + 4 * c, 4);
      end = e32;
    }
    if (end < prev || (uint64_t)end > nconn) return 0;
    r->list[pos++] = end - prev;
    for (int64_t k = prev; k < end; k++) {
      if (w == 8) {
        memcpy(&r->list[pos++], conn->data + 8 * k, 8);
      } else {
        int32_t v32;
        memcpy(&v32, conn->data + 4 * k, 4);
        r->list[pos++] = v32;
      }
    }
    prev = end;
    r->types[c] = (unsigned char)types->data[c];
  }
  return (uint64_t)prev == nconn;
}

static int vtu_fill(rmesh *r, const vtu_array *arr, int n) {
  const vtu_array *conn = NULL, *offs = NULL, *types = NULL;
  int have_points = 0;
  for (int k = 0; k < n; k++) {
    const vtu_array *a = &arr[k];
    if (!strcmp(a->section, "<Points>")) {
      if (!vtu_take_points(r, a)) return 0;
      have_points = 1;
    } else if (!strcmp(a->section, "<Cells>")) {
      if (!strcmp(a->name, "connectivity"))
        conn = a;
      else if (!strcmp(a->name, "offsets"))
        offs = a;
      else if (!strcmp(a->name, "types"))
        types = a;
    } else if (!vtu_take_field(r, a, !strcmp(a->section, "<PointData"))) {
      return 0;
    }
  }
  return have_points && vtu_take_cells(r, conn, offs, types);
}

static int read_vtu(const char *path, rmesh *r) {
  memset(r, 0, sizeof *r);
  size_t len;
  char *buf = slurp(path, &len);
  if (!buf) return 0;
  const char *app = strstr(buf, "<AppendedData encoding=\"raw\">");
  vtu_array arr[16];
  uint64_t data_end = 0;
  int n = -1;
  int ok = app && vtu_header_ok(buf, &r->nnodes, &r->ncells);
  if (ok) n = vtu_arrays(buf, len, app, arr, 16, &data_end);
  ok = ok && n >= 0 && vtu_fill(r, arr, n);
  static const char tail[] = "\n  </AppendedData>\n</VTKFile>\n";
  ok = ok && data_end + strlen(tail) == len &&
       memcmp(buf + data_end, tail, strlen(tail)) == 0;
  free(buf);
  r->ok = ok;
  return ok;
}

/* ====================================================================== */
/* Round trips                                                            */
/* ====================================================================== */

static int roundtrip_legacy(const fmesh *t, const char *name, int binary) {
  char path[512];
  path_in(path, sizeof path, name);
  int st = mx_write_vtk_legacy(path, &t->v, binary);
  CHECK(st == MX_OK);
  rmesh r;
  int ok = read_legacy(path, &r, binary);
  CHECK(ok);
  int same = compare_mesh(&r, &t->v);
  CHECK(same);
  rmesh_free(&r);
  return st == MX_OK && ok && same;
}

static int roundtrip_vtu(const fmesh *t, const char *name) {
  char path[512];
  path_in(path, sizeof path, name);
  int st = mx_write_vtu(path, &t->v);
  CHECK(st == MX_OK);
  rmesh r;
  int ok = read_vtu(path, &r);
  CHECK(ok);
  int same = compare_mesh(&r, &t->v);
  CHECK(same);
  rmesh_free(&r);
  return st == MX_OK && ok && same;
}

static void test_small_roundtrips(void) {
  fmesh t;
  small_mesh(&t);
  CHECK(roundtrip_legacy(&t, "small_bin.vtk", 1));
  CHECK(roundtrip_legacy(&t, "small_ascii.vtk", 0));
  CHECK(roundtrip_vtu(&t, "small.vtu"));
  CHECK(count_entries(OUT_DIR, "small") == 3); /* no temporaries left */
  /* a field name with blanks and XML/percent characters */
  t.cf[1].name = "j e%n<s>&\"";
  CHECK(roundtrip_legacy(&t, "names_bin.vtk", 1));
  CHECK(roundtrip_legacy(&t, "names_ascii.vtk", 0));
  CHECK(roundtrip_vtu(&t, "names.vtu"));
  /* no fields at all */
  t.v.ncell_fields = 0;
  t.v.npoint_fields = 0;
  CHECK(roundtrip_legacy(&t, "nofield.vtk", 1));
  CHECK(roundtrip_vtu(&t, "nofield.vtu"));
  fmesh_free(&t);
  printf(
      "small mixed mesh: legacy binary, legacy ASCII, VTU read back "
      "bit-exact\n");
}

static void test_empty_mesh(void) {
  fmesh t;
  fmesh_alloc(&t, 0, 0);
  fmesh_view(&t);
  CHECK(roundtrip_legacy(&t, "empty_bin.vtk", 1));
  CHECK(roundtrip_legacy(&t, "empty_ascii.vtk", 0));
  CHECK(roundtrip_vtu(&t, "empty.vtu"));
  fmesh_free(&t);
}

static void test_dispatch(void) {
  fmesh t;
  small_mesh(&t);
  char path[512];
  size_t len;
  path_in(path, sizeof path, "disp.VTK");
  CHECK(mx_write_mesh(path, &t.v, 0) == MX_OK);
  char *buf = slurp(path, &len);
  CHECK(buf && strstr(buf, "\nBINARY\n"));
  free(buf);
  path_in(path, sizeof path, "disp.Vtu");
  CHECK(mx_write_mesh(path, &t.v, 0) == MX_OK);
  rmesh r;
  CHECK(read_vtu(path, &r) && compare_mesh(&r, &t.v));
  rmesh_free(&r);
  fprintf(stderr, "(expected errors follow)\n");
  static const char *bad[] = {"disp.obj", "disp", "disp.vtk.gz", "vtk"};
  for (int k = 0; k < 4; k++) {
    path_in(path, sizeof path, bad[k]);
    CHECK(mx_write_mesh(path, &t.v, 0) == MX_EINPUT);
    CHECK(!exists(path));
  }
  CHECK(count_entries(OUT_DIR, "disp") == 2);
  /* an inconsistent mesh is refused before any file is created */
  t.conn[8 * 3 + 2] = 12;
  path_in(path, sizeof path, "badmesh.vtu");
  CHECK(mx_write_vtu(path, &t.v) == MX_EINTERNAL);
  t.conn[8 * 3 + 2] = 6;
  t.type[1] = 7;
  CHECK(mx_write_vtk_legacy(path, &t.v, 1) == MX_EINTERNAL);
  CHECK(count_entries(OUT_DIR, "badmesh") == 0);
  fmesh_free(&t);
}

/* ====================================================================== */
/* Failures leave nothing behind                                          */
/* ====================================================================== */

/* All three writers must fail with MX_EINPUT on path; dir (may be NULL)
 * must have no entry starting with prefix afterwards. */
static void expect_write_failure(const void *ctx, const char *path,
                                 const char *dir, const char *prefix) {
  const fmesh *t = ctx;
  CHECK(mx_write_vtk_legacy(path, &t->v, 1) == MX_EIO);
  CHECK(mx_write_vtk_legacy(path, &t->v, 0) == MX_EIO);
  CHECK(mx_write_vtu(path, &t->v) == MX_EIO);
  CHECK(mx_write_mesh(path, &t->v, 0) == MX_EIO);
  CHECK(!exists(path));
  if (dir) CHECK(count_entries(dir, prefix) <= 0);
}

static void test_unwritable(void) {
  fmesh t;
  small_mesh(&t);
  unwritable_places(expect_write_failure, &t, "writers", ".vtk", ".vtu");
  char path[512];
  /* the output path is a directory */
  path_in(path, sizeof path, "adir.vtk");
  CHECK(mkdir(path, 0755) == 0);
  CHECK(mx_write_vtk_legacy(path, &t.v, 1) == MX_EIO);
  CHECK(count_entries(OUT_DIR, "adir.vtk") == 1);
  fmesh_free(&t);
}

/* /dev/full: through a stream handed to mx_afile_from_stream, and as an
 * output path (an existing device is written in place, never replaced). */
static void test_full_disk(void) {
  if (!have_dev_full()) return;
  mx_afile f;
  FILE *fp = fopen("/dev/full", "wb");
  CHECK(fp != NULL);
  if (!fp) return;
  CHECK(mx_afile_from_stream(&f, fp, "/dev/full") == MX_OK);
  CHECK(mx_afile_write(&f, "small", 5) == MX_OK); /* still in the buffer */
  CHECK(mx_afile_commit(&f) == MX_EIO);        /* the flush: ENOSPC */
  mx_afile_abort(&f);                             /* harmless after */
  fp = fopen("/dev/full", "wb");
  CHECK(mx_afile_from_stream(&f, fp, "/dev/full") == MX_OK);
  /* the bytes go out in 8 MiB chunks written by a background thread: its
   * ENOSPC comes back by the time a third chunk is handed over */
  static char big[1 << 20];
  int wst = MX_OK, k = 0;
  while (wst == MX_OK && k < 64) wst = mx_afile_write(&f, big, sizeof big), k++;
  CHECK(wst == MX_EIO && k <= 3 * 8 + 1);
  CHECK(mx_afile_write(&f, big, 1) == MX_EIO); /* sticky */
  CHECK(mx_afile_commit(&f) == MX_EIO);
  mx_afile_abort(&f);
  fmesh t;
  small_mesh(&t);
  CHECK(mx_write_vtk_legacy("/dev/full", &t.v, 1) == MX_EIO);
  CHECK(mx_write_vtk_legacy("/dev/full", &t.v, 0) == MX_EIO);
  CHECK(mx_write_vtu("/dev/full", &t.v) == MX_EIO);
  CHECK(dev_full_intact());
  /* /dev/null as output works in place */
  struct stat st;
  CHECK(mx_write_vtu("/dev/null", &t.v) == MX_OK);
  CHECK(stat("/dev/null", &st) == 0 && S_ISCHR(st.st_mode));
  fmesh_free(&t);
}

/* A real failure in the middle of a regular temporary file: the file size
 * limit makes write() fail with EFBIG once the file passes 64 KiB. */
static void test_size_limit(void) {
  struct rlimit old, lim;
  if (getrlimit(RLIMIT_FSIZE, &old) != 0) return;
  fmesh t;
  grid_mesh(&t, 20, 1);
  char path[512];
  void (*prev)(int) = signal(SIGXFSZ, SIG_IGN);
  lim = old;
  lim.rlim_cur = 64 << 10;
  if (setrlimit(RLIMIT_FSIZE, &lim) != 0) {
    printf("SKIP file size limit: setrlimit failed\n");
  } else {
    path_in(path, sizeof path, "limited.vtk");
    int a = mx_write_vtk_legacy(path, &t.v, 1);
    int b = mx_write_vtk_legacy(path, &t.v, 0);
    path_in(path, sizeof path, "limited.vtu");
    int c = mx_write_vtu(path, &t.v);
    setrlimit(RLIMIT_FSIZE, &old);
    CHECK(a == MX_EIO && b == MX_EIO && c == MX_EIO);
    CHECK(count_entries(OUT_DIR, "limited") == 0);
  }
  signal(SIGXFSZ, prev);
  fmesh_free(&t);
}

/* Two writers of the same path from one process get distinct temporaries;
 * a stale temporary of ours is not clobbered. */
static void test_temp_names(void) {
  char path[512], stale[600];
  path_in(path, sizeof path, "tmpname.vtk");
  snprintf(stale, sizeof stale, "%s.tmp.%ld", path, (long)getpid());
  FILE *fp = fopen(stale, "w");
  CHECK(fp && fputs("stale", fp) >= 0 && fclose(fp) == 0);
  mx_afile a, b;
  CHECK(mx_afile_open(&a, path) == MX_OK);
  CHECK(mx_afile_open(&b, path) == MX_OK);
  CHECK(mx_afile_printf(&a, "first %d\n", 1) == MX_OK);
  CHECK(mx_afile_printf(&b, "second %d\n", 2) == MX_OK);
  CHECK(mx_afile_commit(&a) == MX_OK);
  mx_afile_abort(&b);
  size_t len;
  char *buf = slurp(path, &len);
  CHECK(buf && !strcmp(buf, "first 1\n"));
  free(buf);
  buf = slurp(stale, &len);
  CHECK(buf && !strcmp(buf, "stale"));
  free(buf);
  unlink(stale);
  CHECK(count_entries(OUT_DIR, "tmpname") == 1);
}

/* ====================================================================== */
/* Narrow field sources                                                   */
/* ====================================================================== */

/* The same values held two ways: int32/double arrays (wide) and the
 * mesher's kinds, uint8_t/float (narrow). Every field appears in both views
 * with the same name and written kind; "big" (values beyond 255, Int32 in
 * a VTU) is int32 in both. */
typedef struct {
  uint8_t *u8cell, *u8level, *u8bnd;
  float *fjens, *fdist;
  int32_t *icell, *ilevel, *ibnd, *big;
  double *djens, *ddist;
  mx_field wcf[4], ncf[4], wpf[2], npf[2];
  mx_mesh_view wide, narrow;
} nmesh;

/* A finite float of random bits (subnormals, -0 included) or a small
 * decimal-looking one. */
static float rng_float(void) {
  if (rng_next() % 3 == 0) return (float)((double)(int64_t)(rng_next() % 20001) / 1000.0 - 10.0);
  float x;
  do {
    const uint32_t b = (uint32_t)rng_next();
    memcpy(&x, &b, 4);
  } while (!isfinite(x));
  return x;
}

static void nmesh_make(nmesh *n, const fmesh *t) {
  memset(n, 0, sizeof *n);
  const size_t nc = t->ncells + 1, np = t->nnodes + 1;
  n->u8cell = calloc(nc, 1);
  n->u8level = calloc(nc, 1);
  n->u8bnd = calloc(np, 1);
  n->fjens = calloc(nc, sizeof(float));
  n->fdist = calloc(np, sizeof(float));
  n->icell = calloc(nc, sizeof(int32_t));
  n->ilevel = calloc(nc, sizeof(int32_t));
  n->ibnd = calloc(np, sizeof(int32_t));
  n->big = calloc(nc, sizeof(int32_t));
  n->djens = calloc(nc, sizeof(double));
  n->ddist = calloc(np, sizeof(double));
  if (!n->u8cell || !n->u8level || !n->u8bnd || !n->fjens || !n->fdist || !n->icell ||
      !n->ilevel || !n->ibnd || !n->big || !n->djens || !n->ddist) {
    fprintf(stderr, "test: out of memory\n");
    exit(2);
  }
  for (size_t c = 0; c < t->ncells; c++) {
    n->u8cell[c] = t->type[c];
    n->u8level[c] = (uint8_t)(c < 4 ? 255 - c : rng_next()); /* 255 .. 0 */
    n->fjens[c] = c == 0 ? -0.0f : c == 1 ? 1e-45f : c == 2 ? 3.4028235e38f : rng_float();
    n->big[c] = (int32_t)(uint32_t)rng_next();
  }
  for (size_t i = 0; i < t->nnodes; i++) {
    n->u8bnd[i] = (uint8_t)(rng_next() % 2);
    n->fdist[i] = rng_float();
  }
  /* the copies the mesher made before: the same values, wider */
  for (size_t c = 0; c < t->ncells; c++) {
    n->icell[c] = n->u8cell[c];
    n->ilevel[c] = n->u8level[c];
    n->djens[c] = n->fjens[c];
  }
  for (size_t i = 0; i < t->nnodes; i++) {
    n->ibnd[i] = n->u8bnd[i];
    n->ddist[i] = n->fdist[i];
  }
  n->wcf[0] = (mx_field){.name = "type", .is_double = 0, .ivalues = n->icell};
  n->wcf[1] = (mx_field){.name = "level", .is_double = 0, .ivalues = n->ilevel};
  n->wcf[2] = (mx_field){.name = "jens", .is_double = 1, .dvalues = n->djens};
  n->wcf[3] = (mx_field){.name = "big", .is_double = 0, .ivalues = n->big};
  n->ncf[0] = (mx_field){.name = "type", .is_double = 0, .u8values = n->u8cell};
  n->ncf[1] = (mx_field){.name = "level", .is_double = 0, .u8values = n->u8level};
  n->ncf[2] = (mx_field){.name = "jens", .is_double = 1, .fvalues = n->fjens};
  n->ncf[3] = n->wcf[3];
  n->wpf[0] = (mx_field){.name = "boundary", .is_double = 0, .ivalues = n->ibnd};
  n->wpf[1] = (mx_field){.name = "dist", .is_double = 1, .dvalues = n->ddist};
  n->npf[0] = (mx_field){.name = "boundary", .is_double = 0, .u8values = n->u8bnd};
  n->npf[1] = (mx_field){.name = "dist", .is_double = 1, .fvalues = n->fdist};
  n->wide = t->v;
  n->wide.ncell_fields = 4;
  n->wide.cell_fields = n->wcf;
  n->wide.npoint_fields = 2;
  n->wide.point_fields = n->wpf;
  n->narrow = n->wide;
  n->narrow.cell_fields = n->ncf;
  n->narrow.point_fields = n->npf;
}

static void nmesh_free(nmesh *n) {
  free(n->u8cell);
  free(n->u8level);
  free(n->u8bnd);
  free(n->fjens);
  free(n->fdist);
  free(n->icell);
  free(n->ilevel);
  free(n->ibnd);
  free(n->big);
  free(n->djens);
  free(n->ddist);
  memset(n, 0, sizeof *n);
}

/* Every format the dispatcher knows, each variant: the file written from
 * the wide view and from the narrow one must be the same bytes. */
static void narrow_same_bytes(const nmesh *n, const char *tag) {
  static const struct {
    const char *suffix;
    int ascii;
  } kinds[] = {{"_bin.vtk", 0}, {"_ascii.vtk", 1}, {".vtu", 0},  {"_bin.msh", 0},
               {"_ascii.msh", 1}, {".mesh", 0},    {".meshb", 0}, {".getfem", 0},
               {".m3d", 0},       {".mvm", 0}};
  for (size_t k = 0; k < sizeof kinds / sizeof *kinds; k++) {
    char a[512], b[512], name[128];
    snprintf(name, sizeof name, "narrow_%s_w%s", tag, kinds[k].suffix);
    path_in(a, sizeof a, name);
    snprintf(name, sizeof name, "narrow_%s_n%s", tag, kinds[k].suffix);
    path_in(b, sizeof b, name);
    const int sa = mx_write_mesh(a, &n->wide, kinds[k].ascii);
    const int sb = mx_write_mesh(b, &n->narrow, kinds[k].ascii);
    CHECK(sa == MX_OK && sb == MX_OK);
    const int same = files_equal(a, b);
    CHECK(same);
    if (!same) fprintf(stderr, "narrow sources: %s and %s differ\n", a, b);
    unlink(a);
    unlink(b);
  }
}

static void test_narrow_sources(void) {
  fmesh t;
  small_mesh(&t);
  nmesh n;
  nmesh_make(&n, &t);
  /* the narrow view reads back as the wide one (VTU: UInt8, Float64) */
  rmesh r;
  char path[512];
  path_in(path, sizeof path, "narrow_rt.vtu");
  CHECK(mx_write_vtu(path, &n.narrow) == MX_OK);
  CHECK(read_vtu(path, &r) && compare_mesh(&r, &n.wide) && compare_mesh(&r, &n.narrow));
  rmesh_free(&r);
  size_t len;
  char *buf = slurp(path, &len);
  CHECK(buf && strstr(buf, "<DataArray type=\"UInt8\" Name=\"level\"") &&
        strstr(buf, "<DataArray type=\"Float64\" Name=\"jens\"") &&
        strstr(buf, "<DataArray type=\"Int32\" Name=\"big\"") &&
        strstr(buf, "<DataArray type=\"UInt8\" Name=\"boundary\"") &&
        strstr(buf, "<DataArray type=\"Float64\" Name=\"dist\""));
  free(buf);
  unlink(path);
  path_in(path, sizeof path, "narrow_rt.vtk");
  CHECK(mx_write_vtk_legacy(path, &n.narrow, 0) == MX_OK);
  CHECK(read_legacy(path, &r, 0) && compare_mesh(&r, &n.wide));
  rmesh_free(&r);
  unlink(path);
  narrow_same_bytes(&n, "small");
  nmesh_free(&n);
  fmesh_free(&t);
  /* a mixed grid, cells in index order, then in a shuffled written order
   * (the fields gathered), with 1 and 3 threads */
  grid_mesh(&t, 14, 1);
  nmesh_make(&n, &t);
  narrow_same_bytes(&n, "grid");
  uint32_t *order = malloc((t.ncells + 1) * sizeof *order);
  CHECK(order != NULL);
  if (order) {
    for (size_t c = 0; c < t.ncells; c++) order[c] = (uint32_t)c;
    for (size_t c = t.ncells; c > 1; c--) {
      const size_t j = (size_t)(rng_next() % c);
      const uint32_t x = order[c - 1];
      order[c - 1] = order[j];
      order[j] = x;
    }
    n.wide.order = n.narrow.order = order;
    narrow_same_bytes(&n, "shuffled");
    const int saved = omp_get_max_threads();
    omp_set_num_threads(saved > 1 ? 1 : 3);
    narrow_same_bytes(&n, "threads");
    omp_set_num_threads(saved);
    free(order);
  }
  /* a field must have one source of values */
  nmesh_free(&n);
  fmesh_free(&t);
  small_mesh(&t);
  nmesh_make(&n, &t);
  n.ncf[1].ivalues = n.ilevel; /* and u8values */
  fprintf(stderr, "(expected errors follow)\n");
  path_in(path, sizeof path, "narrow_two.vtu");
  CHECK(mx_write_vtu(path, &n.narrow) == MX_EINTERNAL);
  n.ncf[1].ivalues = NULL;
  n.ncf[1].u8values = NULL;
  CHECK(mx_write_vtu(path, &n.narrow) == MX_EINTERNAL);
  CHECK(!exists(path));
  nmesh_free(&n);
  fmesh_free(&t);
  printf("narrow field sources (uint8, float): the same bytes as int32/double copies in every "
         "format\n");
}

/* ====================================================================== */
/* Thread-count invariance and speed                                      */
/* ====================================================================== */

static void write_all(const fmesh *t, const char *tag) {
  char a[512], b[512], c[512], name[128];
  snprintf(name, sizeof name, "inv_%s_bin.vtk", tag);
  path_in(a, sizeof a, name);
  snprintf(name, sizeof name, "inv_%s_ascii.vtk", tag);
  path_in(b, sizeof b, name);
  snprintf(name, sizeof name, "inv_%s.vtu", tag);
  path_in(c, sizeof c, name);
  CHECK(mx_write_vtk_legacy(a, &t->v, 1) == MX_OK);
  CHECK(mx_write_vtk_legacy(b, &t->v, 0) == MX_OK);
  CHECK(mx_write_vtu(c, &t->v) == MX_OK);
}

static void test_thread_invariance(void) {
  fmesh t;
  grid_mesh(&t, 60, 1);
  int saved = omp_get_max_threads();
  omp_set_num_threads(1);
  write_all(&t, "t1");
  omp_set_num_threads(5);
  write_all(&t, "t5");
  omp_set_num_threads(saved);
  static const char *kinds[3] = {"_bin.vtk", "_ascii.vtk", ".vtu"};
  for (int k = 0; k < 3; k++) {
    char a[512], b[512], name[128];
    snprintf(name, sizeof name, "inv_t1%s", kinds[k]);
    path_in(a, sizeof a, name);
    snprintf(name, sizeof name, "inv_t5%s", kinds[k]);
    path_in(b, sizeof b, name);
    CHECK(files_equal(a, b));
  }
  rmesh r;
  char path[512];
  path_in(path, sizeof path, "inv_t5_ascii.vtk");
  CHECK(read_legacy(path, &r, 0) && compare_mesh(&r, &t.v));
  rmesh_free(&r);
  path_in(path, sizeof path, "inv_t5.vtu");
  CHECK(read_vtu(path, &r) && compare_mesh(&r, &t.v));
  rmesh_free(&r);
  remove_dir_files(OUT_DIR);
  printf(
      "216000 mixed cells: identical bytes with 1 and 5 threads, ASCII "
      "doubles (random bits) read back bit-exact\n");
  fmesh_free(&t);
}

typedef int (*writer_fn)(const char *path, const fmesh *t);
static int w_bin(const char *p, const fmesh *t) {
  return mx_write_vtk_legacy(p, &t->v, 1);
}
static int w_ascii(const char *p, const fmesh *t) {
  return mx_write_vtk_legacy(p, &t->v, 0);
}
static int w_vtu(const char *p, const fmesh *t) {
  return mx_write_vtu(p, &t->v);
}

static void time_writer(const fmesh *t, const char *label, const char *name,
                        writer_fn fn, int binary_legacy) {
  char path[512];
  path_in(path, sizeof path, name);
  double t0 = mx_wtime();
  int st = fn(path, t);
  double dt = mx_wtime() - t0;
  CHECK(st == MX_OK);
  double mb = (double)file_size(path) / 1e6;
  printf(
      "speed: %-14s %zu cells %zu nodes: %7.1f MB in %6.3f s = %6.0f MB/s "
      "(%d threads)\n",
      label, t->ncells, t->nnodes, mb, dt, mb / dt, omp_get_max_threads());
  rmesh r;
  int ok = binary_legacy >= 0 ? read_legacy(path, &r, binary_legacy)
                              : read_vtu(path, &r);
  CHECK(ok && compare_mesh(&r, &t->v));
  rmesh_free(&r);
  unlink(path);
}

static void test_speed(void) {
  fmesh t;
  grid_mesh(&t, 100, 0);
  time_writer(&t, "legacy binary", "big_bin.vtk", w_bin, 1);
  time_writer(&t, "legacy ASCII", "big_ascii.vtk", w_ascii, 0);
  time_writer(&t, "VTU raw", "big.vtu", w_vtu, -1);
  fmesh_free(&t);
}

/* ====================================================================== */
/* External readers (python3 with vtk or meshio), when present            */
/* ====================================================================== */

static const char *py_script =
    "import sys\n"
    "def out(tag, npts, ncells, types, cells, level, jens, dist, tagf):\n"
    "    cs = 0\n"
    "    for ids in cells:\n"
    "        for j, v in enumerate(ids): cs += (j + 1) * int(v)\n"
    "    js = 0.0\n"
    "    for x in jens: js += float(x)\n"
    "    ds = 0.0\n"
    "    for x in dist: ds += float(x)\n"
    "    print('RESULT', tag, npts, ncells, sum(int(t) for t in types), cs,\n"
    "          sum(int(x) for x in level), repr(js), repr(ds),\n"
    "          sum(int(x) for x in tagf))\n"
    "def with_vtk(path, tag):\n"
    "    import vtk\n"
    "    if path.endswith('.vtu'):\n"
    "        r = vtk.vtkXMLUnstructuredGridReader()\n"
    "    else:\n"
    "        r = vtk.vtkUnstructuredGridReader(); r.ReadAllScalarsOn()\n"
    "    r.SetFileName(path); r.Update(); g = r.GetOutput()\n"
    "    cells = []; types = []\n"
    "    for i in range(g.GetNumberOfCells()):\n"
    "        ids = g.GetCell(i).GetPointIds()\n"
    "        cells.append([ids.GetId(j) for j in "
    "range(ids.GetNumberOfIds())])\n"
    "        types.append(g.GetCellType(i))\n"
    "    def arr(d, name):\n"
    "        a = d.GetArray(name)\n"
    "        return [a.GetValue(k) for k in range(a.GetNumberOfTuples())]\n"
    "    cd = g.GetCellData(); pd = g.GetPointData()\n"
    "    out(tag, g.GetNumberOfPoints(), g.GetNumberOfCells(), types, cells,\n"
    "        arr(cd, 'level'), arr(cd, 'jens'), arr(pd, 'dist'),\n"
    "        arr(pd, 'tag'))\n"
    "def with_meshio(path, tag):\n"
    "    import meshio\n"
    "    m = meshio.read(path)\n"
    "    ids = {'tetra': 10, 'pyramid': 14, 'wedge': 13, 'hexahedron': 12}\n"
    "    cells = []; types = []\n"
    "    for b in m.cells:\n"
    "        for row in b.data:\n"
    "            row = list(row)\n"
    "            if b.type == 'wedge':  # meshio flips VTK's wedge order\n"
    "                row = [row[k] for k in (0, 2, 1, 3, 5, 4)]\n"
    "            cells.append(row); types.append(ids[b.type])\n"
    "    cat = lambda name: [x for blk in m.cell_data[name] for x in blk]\n"
    "    out(tag, len(m.points), len(cells), types, cells, cat('level'),\n"
    "        cat('jens'), m.point_data['dist'], m.point_data['tag'])\n"
    "{'vtk': with_vtk, 'meshio': with_meshio}[sys.argv[1]](sys.argv[2],\n"
    "                                                     sys.argv[3])\n";

static void expected_result(const mx_mesh_view *m, char *out, size_t cap) {
  long long typesum = 0, cs = 0, levelsum = 0, tagsum = 0;
  double js = 0.0, ds = 0.0;
  for (size_t c = 0; c < m->ncells; c++) {
    typesum += mx_vtk_cell_type[m->type[c]];
    for (int j = 0; j < mx_cell_nodes[m->type[c]]; j++)
      cs += (long long)(j + 1) * m->conn[8 * c + (size_t)mx_vtk_order[m->type[c]][j]];
    levelsum += mx_field_int(&m->cell_fields[0], c);
    js += mx_field_double(&m->cell_fields[1], c);
  }
  for (size_t i = 0; i < m->nnodes; i++) {
    ds += mx_field_double(&m->point_fields[0], i);
    tagsum += mx_field_int(&m->point_fields[1], i);
  }
  snprintf(out, cap, "%zu %zu %lld %lld %lld %.17g %.17g %lld", m->nnodes,
           m->ncells, typesum, cs, levelsum, js, ds, tagsum);
}

/* Parses "RESULT tag npts ncells typesum cs levelsum js ds tagsum" and
 * renders it like expected_result (doubles compared through their bits). */
static int external_result(const char *file, char *out, size_t cap) {
  size_t len;
  char *buf = slurp(file, &len);
  if (!buf) return 0;
  char *line = strstr(buf, "RESULT ");
  char tag[64];
  size_t np, nc;
  long long ts, cs, ls, tg;
  double js, ds;
  int ok = line && sscanf(line,
                          "RESULT %63s %zu %zu %lld %lld %lld %lf %lf "
                          "%lld",
                          tag, &np, &nc, &ts, &cs, &ls, &js, &ds, &tg) == 9;
  if (ok)
    snprintf(out, cap, "%zu %zu %lld %lld %lld %.17g %.17g %lld", np, nc, ts,
             cs, ls, js, ds, tg);
  free(buf);
  return ok;
}

static const char *find_python(const char *module) {
  static const char *cands[2] = {"python3", "/usr/bin/python3"};
  char cmd[256];
  for (int k = 0; k < 2; k++) {
    snprintf(cmd, sizeof cmd, "%s -c 'import %s' >/dev/null 2>&1", cands[k],
             module);
    if (system(cmd) == 0) return cands[k];
  }
  return NULL;
}

static void run_external(const char *py, const char *backend, const char *path,
                         const char *expect) {
  char cmd[4096], outfile[512], got[512];
  path_in(outfile, sizeof outfile, "ext_result.txt");
  snprintf(cmd, sizeof cmd, "%s %s/reader.py %s %s %s > %s 2>&1", py, OUT_DIR,
           backend, path, backend, outfile);
  int rc = system(cmd);
  int ok = rc == 0 && external_result(outfile, got, sizeof got);
  CHECK(ok);
  if (ok) CHECK(strcmp(got, expect) == 0);
  if (!ok || strcmp(got, expect)) {
    size_t len;
    char *log = slurp(outfile, &len);
    fprintf(stderr, "external %s on %s: expected '%s'\n%s\n", backend, path,
            expect, log ? log : "(no output)");
    free(log);
  } else {
    printf("external reader %s: %s matches (%s)\n", backend, path, got);
  }
}

static void test_external(void) {
  const char *backends[2] = {"vtk", "meshio"};
  char script[512];
  path_in(script, sizeof script, "reader.py");
  FILE *fp = fopen(script, "w");
  CHECK(fp && fputs(py_script, fp) >= 0 && fclose(fp) == 0);
  fmesh t;
  small_mesh(&t);
  char expect[512];
  expected_result(&t.v, expect, sizeof expect);
  static const char *names[3] = {"ext_bin.vtk", "ext_ascii.vtk", "ext.vtu"};
  char paths[3][512];
  for (int k = 0; k < 3; k++) path_in(paths[k], sizeof paths[k], names[k]);
  CHECK(mx_write_vtk_legacy(paths[0], &t.v, 1) == MX_OK);
  CHECK(mx_write_vtk_legacy(paths[1], &t.v, 0) == MX_OK);
  CHECK(mx_write_vtu(paths[2], &t.v) == MX_OK);
  for (int b = 0; b < 2; b++) {
    const char *py = find_python(backends[b]);
    if (!py) {
      printf("SKIP external reader: python3 module '%s' not importable\n",
             backends[b]);
      continue;
    }
    for (int k = 0; k < 3; k++) run_external(py, backends[b], paths[k], expect);
  }
  fmesh_free(&t);
}

/* ====================================================================== */

int main(int argc, char **argv) {
  int small_only = argc > 1 && !strcmp(argv[1], "small");
  mkdir(OUT_DIR, 0755);
  remove_dir_files(OUT_DIR);
  test_small_roundtrips();
  test_empty_mesh();
  test_dispatch();
  test_unwritable();
  test_full_disk();
  test_size_limit();
  test_temp_names();
  test_narrow_sources();
  if (!small_only) {
    test_external();
    test_thread_invariance();
    test_speed();
  }
  remove_dir_files(OUT_DIR);
  int fails = TEST_DONE();
  printf("%d passed, %d failed\n", fails ? 0 : 1, fails ? 1 : 0);
  return fails;
}
