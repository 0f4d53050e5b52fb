/* PLY reader (Stanford polygon format): ASCII, binary little endian and
 * binary big endian. The header ("ply", "format ...", "element NAME COUNT",
 * "property TYPE NAME", "property list COUNTTYPE ITEMTYPE NAME",
 * "end_header"; "comment" and "obj_info" lines ignored; CRLF accepted)
 * declares the elements, stored in header order. Read: x, y, z of the
 * "vertex" element and the "vertex_indices" (or "vertex_index") list of the
 * "face" element, 0-based, polygons split into triangles in their plane
 * (io/polygon_split.c; after the vertices when the faces come first in the
 * file); triangles remember their face (from 0); every other property and
 * element is skipped. The counts are checked against the file size before
 * anything is allocated. In ASCII each item is one line; blank lines are
 * ignored, anything after the declared data is an error (as in OFF). In
 * binary, every read is bounds-checked; errors name the item and its byte
 * offset in the file; trailing blanks after the data are ignored. */
#include <math.h>
#include <stdint.h>
#include <string.h>

#include "base/common.h"
#include "soa/trisoup.h"

#include "io/bytes.h"
#include "io/polygon_split.h"
#include "io/text_scan.h"
#include "io/read_surface.h"

/* ---- types ------------------------------------------------------------ */

enum { T_CHAR, T_UCHAR, T_SHORT, T_USHORT, T_INT, T_UINT, T_FLOAT, T_DOUBLE,
       NTYPES };

static const char *const type_names[NTYPES][2] = {
    {"char", "int8"},   {"uchar", "uint8"},   {"short", "int16"},
    {"ushort", "uint16"}, {"int", "int32"},   {"uint", "uint32"},
    {"float", "float32"}, {"double", "float64"}};
static const uint8_t type_size[NTYPES] = {1, 1, 2, 2, 4, 4, 4, 8};

static int is_integer_type(int t) { return t != T_FLOAT && t != T_DOUBLE; }

enum { FMT_ASCII, FMT_LE, FMT_BE };
enum { EL_OTHER, EL_VERTEX, EL_FACE };
/* What a property is used for: coordinates 0..2, the face's vertex list. */
enum { ROLE_X, ROLE_Y, ROLE_Z, ROLE_INDICES, ROLE_SKIP };

typedef struct {
  const char *s;
  int n; /* length, at most INT_MAX / 2 */
} token;

typedef struct {
  token name;
  uint8_t list;       /* a list: count_type then count items of type */
  uint8_t type;       /* the scalar or list item type */
  uint8_t count_type; /* lists only */
  uint8_t role;
} ply_prop;

typedef struct {
  token name;
  uint64_t count;
  size_t first, nprops; /* its properties: prop[first, first + nprops) */
  long line;            /* of its "element" line */
  int kind;
  int has_list;
  uint64_t fixed; /* binary bytes of the scalars and list counts */
} ply_elem;

typedef struct {
  const char *path;
  const char *buf, *end; /* the file; buf[end - buf] is NUL */
  const char *p;         /* ASCII: the current line; binary: next byte */
  long line;
  int format;
  ply_elem *elem;
  size_t nelem, cap_elem;
  ply_prop *prop;
  size_t nprop, cap_prop;
  size_t nv, nf; /* declared vertex and face counts */
  mx_polysplit *split;
} ply_file;

/* ---- header tokens ---------------------------------------------------- */

static int is_space(char c) {
  return c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v';
}

/* Splits [s, e) into tokens; stores at most max, returns how many there are
 * (capped at max + 1). */
static int split(const char *s, const char *e, token *t, int max) {
  int n = 0;
  for (;;) {
    while (s < e && is_space(*s)) s++;
    if (s == e || n > max) return n;
    const char *b = s;
    while (s < e && !is_space(*s)) s++;
    if (n < max) {
      size_t len = (size_t)(s - b);
      t[n].s = b;
      t[n].n = len > 1000000 ? 1000000 : (int)len;
    }
    n++;
  }
}

static int tok_is(token t, const char *word) {
  size_t n = strlen(word);
  return (size_t)t.n == n && memcmp(t.s, word, n) == 0;
}

/* For messages: at most 40 characters of a token. */
static int shown(token t) { return t.n < 40 ? t.n : 40; }

static int type_of(token t) {
  for (int i = 0; i < NTYPES; i++)
    if (tok_is(t, type_names[i][0]) || tok_is(t, type_names[i][1])) return i;
  return -1;
}

/* ---- header ----------------------------------------------------------- */

static int header_error_type(ply_file *f, token t) {
  mx_error(f->path, f->line,
           "unknown property type '%.*s' (expected char uchar short ushort "
           "int uint float double, or int8 uint8 int16 uint16 int32 uint32 "
           "float32 float64)",
           shown(t), t.s);
  return MX_EINPUT;
}

static int grow(void **p, size_t *cap, size_t n, size_t item) {
  if (n < *cap) return MX_OK;
  size_t c = *cap ? 2 * *cap : 8;
  void *q = mx_realloc(*p, c * item);
  if (!q) return MX_ENOMEM;
  *p = q;
  *cap = c;
  return MX_OK;
}

static int parse_format(ply_file *f, const token *t, int n, int *seen) {
  if (*seen) {
    mx_error(f->path, f->line, "a second 'format' line");
    return MX_EINPUT;
  }
  *seen = 1;
  if (n == 3 && tok_is(t[1], "ascii")) f->format = FMT_ASCII;
  else if (n == 3 && tok_is(t[1], "binary_little_endian")) f->format = FMT_LE;
  else if (n == 3 && tok_is(t[1], "binary_big_endian")) f->format = FMT_BE;
  else {
    mx_error(f->path, f->line,
             "bad format line: expected 'format ascii 1.0', 'format "
             "binary_little_endian 1.0' or 'format binary_big_endian 1.0'");
    return MX_EINPUT;
  }
  if (!tok_is(t[2], "1.0") && !tok_is(t[2], "1")) {
    mx_error(f->path, f->line, "unsupported PLY version '%.*s' (1.0 expected)",
             shown(t[2]), t[2].s);
    return MX_EINPUT;
  }
  return MX_OK;
}

static int parse_element(ply_file *f, const token *t, int n) {
  if (n != 3) {
    mx_error(f->path, f->line, "bad element line: expected 'element NAME "
                               "COUNT'");
    return MX_EINPUT;
  }
  uint64_t count = 0;
  for (int i = 0; i < t[2].n; i++) {
    char c = t[2].s[i];
    if (c < '0' || c > '9') {
      mx_error(f->path, f->line,
               "bad count '%.*s' for element '%.*s' (a non-negative integer "
               "expected)",
               shown(t[2]), t[2].s, shown(t[1]), t[1].s);
      return MX_EINPUT;
    }
    if (count < ((uint64_t)1 << 56)) count = 10 * count + (uint64_t)(c - '0');
  }
  int kind = tok_is(t[1], "vertex") ? EL_VERTEX
             : tok_is(t[1], "face") ? EL_FACE
                                    : EL_OTHER;
  for (size_t i = 0; i < f->nelem && kind != EL_OTHER; i++)
    if (f->elem[i].kind == kind) {
      mx_error(f->path, f->line, "a second '%.*s' element (the first is on "
               "line %ld)", shown(t[1]), t[1].s, f->elem[i].line);
      return MX_EINPUT;
    }
  MX_CHECK(grow((void **)&f->elem, &f->cap_elem, f->nelem, sizeof *f->elem));
  ply_elem *e = &f->elem[f->nelem++];
  memset(e, 0, sizeof *e);
  e->name = t[1];
  e->count = count;
  e->first = f->nprop;
  e->line = f->line;
  e->kind = kind;
  return MX_OK;
}

/* The role of property p of element e; MX_EINPUT on a conflict. */
static int assign_role(ply_file *f, ply_elem *e, ply_prop *p) {
  p->role = ROLE_SKIP;
  int role = ROLE_SKIP;
  if (e->kind == EL_VERTEX && p->name.n == 1 && p->name.s[0] >= 'x' &&
      p->name.s[0] <= 'z')
    role = ROLE_X + (p->name.s[0] - 'x');
  if (e->kind == EL_FACE &&
      (tok_is(p->name, "vertex_indices") || tok_is(p->name, "vertex_index")))
    role = ROLE_INDICES;
  if (role == ROLE_SKIP) return MX_OK;
  for (size_t i = e->first; i < e->first + e->nprops; i++) {
    if (f->prop[i].role != role) continue;
    if (role == ROLE_INDICES) return MX_OK; /* the first list is used */
    mx_error(f->path, f->line, "a second vertex property '%.*s'", p->name.n,
             p->name.s);
    return MX_EINPUT;
  }
  if (role != ROLE_INDICES && p->list) {
    mx_error(f->path, f->line,
             "vertex property '%.*s' is a list (a number expected)", p->name.n,
             p->name.s);
    return MX_EINPUT;
  }
  if (role == ROLE_INDICES && !p->list) {
    mx_error(f->path, f->line,
             "face property '%.*s' is not a list (expected 'property list "
             "uchar int %.*s')",
             p->name.n, p->name.s, p->name.n, p->name.s);
    return MX_EINPUT;
  }
  if (role == ROLE_INDICES && !is_integer_type(p->type)) {
    mx_error(f->path, f->line,
             "face property '%.*s' holds %s values (vertex indices must be of "
             "an integer type)",
             p->name.n, p->name.s, type_names[p->type][0]);
    return MX_EINPUT;
  }
  p->role = (uint8_t)role;
  return MX_OK;
}

static int parse_property(ply_file *f, const token *t, int n) {
  if (f->nelem == 0) {
    mx_error(f->path, f->line, "a property before any 'element' line");
    return MX_EINPUT;
  }
  ply_elem *e = &f->elem[f->nelem - 1];
  ply_prop p;
  memset(&p, 0, sizeof p);
  if (n >= 2 && tok_is(t[1], "list")) {
    if (n != 5) {
      mx_error(f->path, f->line, "bad property line: expected 'property list "
                                 "COUNTTYPE ITEMTYPE NAME'");
      return MX_EINPUT;
    }
    int ct = type_of(t[2]), it = type_of(t[3]);
    if (ct < 0) return header_error_type(f, t[2]);
    if (it < 0) return header_error_type(f, t[3]);
    if (!is_integer_type(ct)) {
      mx_error(f->path, f->line,
               "list '%.*s' has a count of type %s (an integer type expected)",
               shown(t[4]), t[4].s, type_names[ct][0]);
      return MX_EINPUT;
    }
    p.list = 1;
    p.count_type = (uint8_t)ct;
    p.type = (uint8_t)it;
    p.name = t[4];
  } else {
    if (n != 3) {
      mx_error(f->path, f->line,
               "bad property line: expected 'property TYPE NAME'");
      return MX_EINPUT;
    }
    int ty = type_of(t[1]);
    if (ty < 0) return header_error_type(f, t[1]);
    p.type = (uint8_t)ty;
    p.name = t[2];
  }
  MX_CHECK(assign_role(f, e, &p));
  MX_CHECK(grow((void **)&f->prop, &f->cap_prop, f->nprop, sizeof *f->prop));
  f->prop[f->nprop++] = p;
  e->nprops++;
  e->has_list |= p.list;
  e->fixed += type_size[p.list ? p.count_type : p.type];
  return MX_OK;
}

/* One header line [s, e) (line f->line); *done set at "end_header". */
static int header_line(ply_file *f, const char *s, const char *e,
                       int *seen_format, int *done) {
  token t[6];
  int n = split(s, e, t, 5);
  if (n == 0) return MX_OK; /* a blank line */
  if (tok_is(t[0], "comment") || tok_is(t[0], "obj_info")) return MX_OK;
  if (tok_is(t[0], "format")) return parse_format(f, t, n, seen_format);
  if (tok_is(t[0], "element")) return parse_element(f, t, n);
  if (tok_is(t[0], "property")) return parse_property(f, t, n);
  if (tok_is(t[0], "end_header")) {
    if (n == 1) {
      *done = 1;
      return MX_OK;
    }
    mx_error(f->path, f->line, "bad header: text after 'end_header'");
    return MX_EINPUT;
  }
  mx_error(f->path, f->line,
           "bad header: unknown keyword '%.*s' (expected format, comment, "
           "obj_info, element, property or end_header)",
           shown(t[0]), t[0].s);
  return MX_EINPUT;
}

static int read_magic(ply_file *f) {
  const char *nl = memchr(f->buf, '\n', (size_t)(f->end - f->buf));
  const char *e = nl ? nl : f->end;
  token t[2];
  int n = split(f->buf, e, t, 1);
  if (n != 1 || !tok_is(t[0], "ply")) {
    token first = n > 0 ? t[0] : (token){"", 0};
    mx_error(f->path, 1,
             "not a PLY file: the first line must be 'ply', found '%.*s'",
             shown(first), first.s);
    return MX_EINPUT;
  }
  f->p = nl ? nl + 1 : f->end;
  f->line = 2;
  return MX_OK;
}

static int parse_header(ply_file *f) {
  MX_CHECK(read_magic(f));
  int seen_format = 0, done = 0;
  while (!done) {
    if (f->p == f->end) {
      mx_error(f->path, f->line,
               "no 'end_header' line: the header is incomplete (truncated "
               "file?)");
      return MX_EINPUT;
    }
    const char *nl = memchr(f->p, '\n', (size_t)(f->end - f->p));
    const char *e = nl ? nl : f->end;
    token t[2];
    if (!nl && (split(f->p, e, t, 1) != 1 || !tok_is(t[0], "end_header"))) {
      mx_error(f->path, f->line,
               "no 'end_header' line: the header is incomplete (truncated "
               "file?)");
      return MX_EINPUT;
    }
    MX_CHECK(header_line(f, f->p, e, &seen_format, &done));
    f->p = nl ? nl + 1 : f->end;
    if (!done) f->line++;
  }
  if (!seen_format) {
    mx_error(f->path, f->line, "no 'format' line in the header");
    return MX_EINPUT;
  }
  f->line++; /* the first line of ASCII data */
  return MX_OK;
}

/* ---- header checks ---------------------------------------------------- */

static const ply_elem *find_kind(const ply_file *f, int kind) {
  for (size_t i = 0; i < f->nelem; i++)
    if (f->elem[i].kind == kind) return &f->elem[i];
  return NULL;
}

static int has_role(const ply_file *f, const ply_elem *e, int role) {
  for (size_t i = e->first; i < e->first + e->nprops; i++)
    if (f->prop[i].role == role) return 1;
  return 0;
}

static int check_elements(ply_file *f) {
  const ply_elem *v = find_kind(f, EL_VERTEX), *fc = find_kind(f, EL_FACE);
  if (!v) {
    mx_error(f->path, f->line - 1, "no 'vertex' element in the header");
    return MX_EINPUT;
  }
  for (int r = ROLE_X; r <= ROLE_Z; r++)
    if (!has_role(f, v, r)) {
      mx_error(f->path, v->line, "the 'vertex' element has no '%c' property",
               'x' + r);
      return MX_EINPUT;
    }
  if (!fc) {
    mx_error(f->path, f->line - 1, "no 'face' element in the header");
    return MX_EINPUT;
  }
  if (!has_role(f, fc, ROLE_INDICES)) {
    mx_error(f->path, fc->line,
             "the 'face' element has no 'vertex_indices' (or 'vertex_index') "
             "list");
    return MX_EINPUT;
  }
  return MX_OK;
}

/* After the size check, so that a tiny file declaring huge counts gets the
 * clearer message. */
static int check_counts(ply_file *f) {
  const ply_elem *v = find_kind(f, EL_VERTEX), *fc = find_kind(f, EL_FACE);
  if (v->count > UINT32_MAX) {
    mx_error(f->path, v->line,
             "too many vertices (%llu): indices are 32-bit",
             (unsigned long long)v->count);
    return MX_EINPUT;
  }
  if (fc->count == 0) {
    mx_error(f->path, fc->line, "the header declares no faces");
    return MX_EINPUT;
  }
  f->nv = (size_t)v->count;
  f->nf = (size_t)fc->count; /* bounded by the file size (check_sizes) */
  return MX_OK;
}

/* The least number of bytes the items of e take: in binary, the scalars and
 * the list counts; in ASCII, a digit and a separator a scalar or count. */
static uint64_t min_item_bytes(const ply_file *f, const ply_elem *e) {
  return f->format == FMT_ASCII ? 2 * (uint64_t)e->nprops : e->fixed;
}

/* Before anything is allocated: the declared items must fit in the data. */
static int check_sizes(const ply_file *f) {
  uint64_t avail = (uint64_t)(f->end - f->p), need = 0;
  if (f->format == FMT_ASCII) avail++; /* no newline after the last item */
  for (size_t i = 0; i < f->nelem; i++) {
    const ply_elem *e = &f->elem[i];
    uint64_t per = min_item_bytes(f, e), bytes;
    if (__builtin_mul_overflow(e->count, per, &bytes) ||
        __builtin_add_overflow(need, bytes, &need) || need > avail) {
      mx_error(f->path, e->line,
               "the header declares %llu '%.*s' items (at least %llu bytes "
               "each in %s) but only %llu bytes of data follow the header: "
               "truncated file or wrong count",
               (unsigned long long)e->count, shown(e->name), e->name.s,
               (unsigned long long)per,
               f->format == FMT_ASCII ? "ASCII" : "binary",
               (unsigned long long)(f->end - f->p));
      return MX_EINPUT;
    }
  }
  return MX_OK;
}

/* ---- binary data ------------------------------------------------------ */

/* The value at b (in bounds) of an integer type. */
static inline int64_t bin_int(const unsigned char *b, int type, int big) {
  switch (type) {
  case T_CHAR: return (int8_t)b[0];
  case T_UCHAR: return b[0];
  case T_SHORT: return (int16_t)(uint16_t)mx_load_uint(b, 2, big);
  case T_USHORT: return (uint16_t)mx_load_uint(b, 2, big);
  case T_INT: return (int32_t)(uint32_t)mx_load_uint(b, 4, big);
  default: return (uint32_t)mx_load_uint(b, 4, big);
  }
}

static inline double bin_double(const unsigned char *b, int type, int big) {
  if (type == T_FLOAT) {
    uint32_t u = (uint32_t)mx_load_uint(b, 4, big);
    float v;
    memcpy(&v, &u, sizeof v);
    return (double)v;
  }
  if (type == T_DOUBLE) {
    uint64_t u = mx_load_uint(b, 8, big);
    double v;
    memcpy(&v, &u, sizeof v);
    return v;
  }
  return (double)bin_int(b, type, big);
}

typedef struct {
  ply_file *f;
  const ply_elem *e;
  const unsigned char *base, *p, *end;
  int big;
} bin_reader;

static size_t offset(const bin_reader *r, const unsigned char *at) {
  return (size_t)(at - r->base);
}

static int bin_truncated(const bin_reader *r, uint64_t i,
                         const unsigned char *item) {
  mx_error(r->f->path, 0,
           "%.*s %llu (byte offset %zu): the data ends inside it (%llu "
           "'%.*s' items declared): truncated file or wrong counts in the "
           "header",
           shown(r->e->name), r->e->name.s, (unsigned long long)i,
           offset(r, item), (unsigned long long)r->e->count,
           shown(r->e->name), r->e->name.s);
  return MX_EINPUT;
}

static int bin_vertex(const bin_reader *r, mx_trisoup *s, uint64_t i,
                      const unsigned char *item, const double c[3]) {
  for (int d = 0; d < 3; d++)
    if (!isfinite(c[d])) {
      mx_error(r->f->path, 0,
               "vertex %llu (byte offset %zu): coordinate %c is not a finite "
               "number",
               (unsigned long long)i, offset(r, item), 'x' + d);
      return MX_EINPUT;
    }
  s->x[i] = c[0];
  s->y[i] = c[1];
  s->z[i] = c[2];
  return MX_OK;
}

/* The face's k indices at b (in bounds). */
static int bin_face(const bin_reader *r, mx_trisoup *s, uint64_t i,
                    const unsigned char *item, const unsigned char *b,
                    int64_t k, int type) {
  if (k < 3) {
    mx_error(r->f->path, 0,
             "face %llu (byte offset %zu) has %lld vertices (at least 3 "
             "needed)",
             (unsigned long long)i, offset(r, item), (long long)k);
    return MX_EINPUT;
  }
  const int size = type_size[type];
  for (int64_t j = 0; j < k; j++, b += size) {
    int64_t v = bin_int(b, type, r->big);
    if (v < 0) {
      mx_error(r->f->path, 0,
               "face %llu (byte offset %zu): vertex index %lld out of range "
               "(negative)",
               (unsigned long long)i, offset(r, item), (long long)v);
      return MX_EINPUT;
    }
    if ((uint64_t)v >= r->f->nv) {
      mx_error(r->f->path, 0,
               "face %llu (byte offset %zu): vertex index %lld out of range "
               "(%zu vertices, 0-based)",
               (unsigned long long)i, offset(r, item), (long long)v,
               r->f->nv);
      return MX_EINPUT;
    }
    MX_CHECK(mx_polysplit_corner(r->f->split, (uint32_t)v));
  }
  return mx_polysplit_face(r->f->split, s, (mx_face_at){i, 0, (int64_t)offset(r, item)});
}

/* Items without lists: fixed size, so checked against the end once. */
static int bin_fixed(bin_reader *r, mx_trisoup *s) {
  const ply_elem *e = r->e;
  const uint64_t size = e->fixed;
  const uint64_t avail = (uint64_t)(r->end - r->p);
  if (e->count > avail / size)
    return bin_truncated(r, avail / size, r->p + avail / size * size);
  if (e->kind != EL_VERTEX) {
    r->p += e->count * size;
    return MX_OK;
  }
  size_t at[3] = {0, 0, 0}, off = 0;
  int type[3] = {0, 0, 0};
  for (size_t k = 0; k < e->nprops; k++) {
    const ply_prop *p = &r->f->prop[e->first + k];
    if (p->role <= ROLE_Z) {
      at[p->role] = off;
      type[p->role] = p->type;
    }
    off += type_size[p->type];
  }
  for (uint64_t i = 0; i < e->count; i++, r->p += size) {
    double c[3];
    for (int d = 0; d < 3; d++) c[d] = bin_double(r->p + at[d], type[d], r->big);
    MX_CHECK(bin_vertex(r, s, i, r->p, c));
  }
  return MX_OK;
}

/* Items with lists: every read checked. */
static int bin_items(bin_reader *r, mx_trisoup *s) {
  const ply_elem *e = r->e;
  const ply_prop *props = r->f->prop + e->first;
  const unsigned char *p = r->p, *end = r->end;
  for (uint64_t i = 0; i < e->count; i++) {
    const unsigned char *item = p;
    double c[3] = {0, 0, 0};
    for (size_t k = 0; k < e->nprops; k++) {
      const ply_prop *q = &props[k];
      if (!q->list) {
        if ((size_t)(end - p) < type_size[q->type])
          return bin_truncated(r, i, item);
        if (q->role <= ROLE_Z) c[q->role] = bin_double(p, q->type, r->big);
        p += type_size[q->type];
        continue;
      }
      if ((size_t)(end - p) < type_size[q->count_type])
        return bin_truncated(r, i, item);
      int64_t n = bin_int(p, q->count_type, r->big);
      p += type_size[q->count_type];
      if (n < 0) {
        mx_error(r->f->path, 0,
                 "%.*s %llu (byte offset %zu): list '%.*s' has a negative "
                 "length (%lld)",
                 shown(e->name), e->name.s, (unsigned long long)i,
                 offset(r, item), shown(q->name), q->name.s, (long long)n);
        return MX_EINPUT;
      }
      if ((uint64_t)n > (size_t)(end - p) / type_size[q->type])
        return bin_truncated(r, i, item);
      if (q->role == ROLE_INDICES)
        MX_CHECK(bin_face(r, s, i, item, p, n, q->type));
      p += (size_t)n * type_size[q->type];
    }
    if (e->kind == EL_VERTEX) MX_CHECK(bin_vertex(r, s, i, item, c));
  }
  r->p = p;
  return MX_OK;
}

static int read_binary(ply_file *f, mx_trisoup *s) {
  bin_reader r = {f, NULL, (const unsigned char *)f->buf,
                  (const unsigned char *)f->p, (const unsigned char *)f->end,
                  f->format == FMT_BE};
  for (size_t i = 0; i < f->nelem; i++) {
    r.e = &f->elem[i];
    if (r.e->nprops == 0 || r.e->count == 0) continue;
    if (!r.e->has_list)
      MX_CHECK(bin_fixed(&r, s));
    else
      MX_CHECK(bin_items(&r, s));
  }
  const unsigned char *q = r.p;
  while (q < r.end && (is_space((char)*q) || *q == '\n')) q++;
  if (q == r.end) return MX_OK;
  mx_error(f->path, 0,
           "%zu bytes after the last element (byte offset %zu): more data "
           "than the header declares: wrong counts?",
           (size_t)(r.end - r.p), offset(&r, r.p));
  return MX_EINPUT;
}

/* ---- ASCII data ------------------------------------------------------- */

/* Moves to the next content line; error if the file ends first. */
static int text_item(ply_file *f, const ply_elem *e, uint64_t i) {
  f->p = mx_io_content(f->p, f->end, &f->line, 0);
  if (f->p < f->end) return MX_OK;
  mx_error(f->path, f->line,
           "unexpected end of file: %llu of %llu '%.*s' items read "
           "(truncated file or wrong counts in the header)",
           (unsigned long long)i, (unsigned long long)e->count,
           shown(e->name), e->name.s);
  return MX_EINPUT;
}

/* The next number on the line at *q, which may not be missing. */
static int text_number(ply_file *f, const ply_elem *e, uint64_t i,
                       const ply_prop *p, const char **q, double *v) {
  const char *t = mx_io_blank(*q);
  if (mx_io_eol(t, 0)) {
    mx_error(f->path, f->line,
             "%.*s %llu: the line ends before property '%.*s' (fewer values "
             "than the header declares)",
             shown(e->name), e->name.s, (unsigned long long)i, shown(p->name),
             p->name.s);
    return MX_EINPUT;
  }
  const char *end = mx_io_double(t, v);
  if (!end || !mx_io_delim(end, 0)) {
    mx_error(f->path, f->line, "%.*s %llu: '%.*s' is not a number",
             shown(e->name), e->name.s, (unsigned long long)i,
             mx_io_toklen(t, 0), t);
    return MX_EINPUT;
  }
  *q = end;
  return MX_OK;
}

/* A list length: an integer >= 0. */
static int text_length(ply_file *f, const ply_elem *e, uint64_t i,
                       const ply_prop *p, const char **q, int64_t *n) {
  const char *t = mx_io_blank(*q);
  if (mx_io_eol(t, 0)) {
    mx_error(f->path, f->line,
             "%.*s %llu: the line ends before list '%.*s' (fewer values "
             "than the header declares)",
             shown(e->name), e->name.s, (unsigned long long)i, shown(p->name),
             p->name.s);
    return MX_EINPUT;
  }
  const char *end = mx_io_int(t, n);
  if (!end || !mx_io_delim(end, 0) || *n < 0) {
    mx_error(f->path, f->line,
             "%.*s %llu: bad length '%.*s' for list '%.*s' (an integer >= 0 "
             "expected)",
             shown(e->name), e->name.s, (unsigned long long)i,
             mx_io_toklen(t, 0), t, shown(p->name), p->name.s);
    return MX_EINPUT;
  }
  *q = end;
  return MX_OK;
}

static int text_face(ply_file *f, mx_trisoup *s, uint64_t i, const char **q,
                     int64_t k) {
  if (k < 3) {
    mx_error(f->path, f->line, "face %llu has %lld vertices (at least 3 "
             "needed)", (unsigned long long)i, (long long)k);
    return MX_EINPUT;
  }
  for (int64_t j = 0; j < k; j++) {
    uint32_t cur;
    MX_CHECK(mx_io_index(f->path, f->line, q, 0, f->nv, &cur, "face",
                         (size_t)i));
    MX_CHECK(mx_polysplit_corner(f->split, cur));
  }
  return mx_polysplit_face(f->split, s, (mx_face_at){i, f->line, -1});
}

static int text_vertex(ply_file *f, mx_trisoup *s, uint64_t i,
                       const char *const at[3], const double c[3]) {
  for (int d = 0; d < 3; d++)
    if (!isfinite(c[d])) {
      mx_error(f->path, f->line, "vertex %llu: '%.*s' is not a finite number",
               (unsigned long long)i, mx_io_toklen(at[d], 0), at[d]);
      return MX_EINPUT;
    }
  s->x[i] = c[0];
  s->y[i] = c[1];
  s->z[i] = c[2];
  return MX_OK;
}

/* One item: the line at f->p holds exactly the declared values. */
static int text_line(ply_file *f, const ply_elem *e, mx_trisoup *s,
                     uint64_t i) {
  const ply_prop *props = f->prop + e->first;
  const char *q = f->p, *at[3] = {q, q, q};
  double c[3] = {0, 0, 0}, v;
  for (size_t k = 0; k < e->nprops; k++) {
    const ply_prop *p = &props[k];
    if (!p->list) {
      if (p->role <= ROLE_Z) at[p->role] = mx_io_blank(q);
      MX_CHECK(text_number(f, e, i, p, &q, &v));
      if (p->role <= ROLE_Z) c[p->role] = v;
      continue;
    }
    int64_t n;
    MX_CHECK(text_length(f, e, i, p, &q, &n));
    if (p->role == ROLE_INDICES) {
      MX_CHECK(text_face(f, s, i, &q, n));
      continue;
    }
    for (int64_t j = 0; j < n; j++) MX_CHECK(text_number(f, e, i, p, &q, &v));
  }
  q = mx_io_blank(q);
  if (q < f->end && *q != '\n') {
    mx_error(f->path, f->line,
             "%.*s %llu: more values than the header declares ('%.*s')",
             shown(e->name), e->name.s, (unsigned long long)i,
             mx_io_toklen(q, 0), q);
    return MX_EINPUT;
  }
  if (e->kind == EL_VERTEX) MX_CHECK(text_vertex(f, s, i, at, c));
  f->p = mx_io_next_line(q, f->end, &f->line);
  return MX_OK;
}

static int read_ascii(ply_file *f, mx_trisoup *s) {
  for (size_t k = 0; k < f->nelem; k++) {
    const ply_elem *e = &f->elem[k];
    if (e->nprops == 0) continue;
    for (uint64_t i = 0; i < e->count; i++) {
      MX_CHECK(text_item(f, e, i));
      MX_CHECK(text_line(f, e, s, i));
    }
  }
  f->p = mx_io_content(f->p, f->end, &f->line, 0);
  if (f->p == f->end) return MX_OK;
  mx_error(f->path, f->line,
           "more data than the header declares (%zu vertices, %zu faces): "
           "wrong counts?",
           f->nv, f->nf);
  return MX_EINPUT;
}

/* ---- the reader ------------------------------------------------------- */

static int parse_ply(ply_file *f, mx_trisoup *s) {
  MX_CHECK(parse_header(f));
  MX_CHECK(check_elements(f));
  MX_CHECK(check_sizes(f));
  MX_CHECK(check_counts(f));
  MX_CHECK(mx_trisoup_reserve(s, f->nv, f->nf));
  /* faces before the vertices wait for their coordinates */
  if (find_kind(f, EL_FACE) < find_kind(f, EL_VERTEX)) mx_polysplit_defer(f->split);
  MX_CHECK(f->format == FMT_ASCII ? read_ascii(f, s) : read_binary(f, s));
  s->nv = f->nv;
  return mx_polysplit_finish(f->split, s);
}

int mx_read_ply(const char *path, mx_trisoup *out) {
  memset(out, 0, sizeof *out);
  char *buf;
  size_t len;
  MX_CHECK(mx_io_load(path, &buf, &len));
  ply_file f;
  memset(&f, 0, sizeof f);
  f.path = path;
  f.buf = buf;
  f.end = buf + len;
  f.p = buf;
  f.line = 1;
  out->nshells = 1;
  mx_polysplit split;
  mx_polysplit_init(&split, path);
  f.split = &split;
  int status = parse_ply(&f, out);
  mx_polysplit_free(&split);
  mx_free(f.elem);
  mx_free(f.prop);
  mx_free(buf);
  if (status != MX_OK) mx_trisoup_free(out);
  return status;
}
