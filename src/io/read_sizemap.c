/* mixoct: reading a size map (see read_sizemap.h): plain text lines
 * "x y z h", a view of a Gmsh .pos file, or one field of a VTK file read
 * by the VTK readers' field mode (io/vtk_fields.h: read_vtk.c,
 * read_vtu.c), a cell field's values put at the cells' centroids. */
#include "io/read_sizemap.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>
#include <strings.h>

#include "base/common.h"
#include "io/mesh_reader.h"
#include "io/text_scan.h"
#include "io/vtk_fields.h"

/* ---- the points read so far ------------------------------------------------ */

typedef struct {
  double *xyz, *h; /* 3 a point, 1 a point */
  size_t n, cap;
} smap;

static int smap_push(smap *m, const double p[3], double h) {
  if (m->n == m->cap) {
    const size_t cap = m->cap ? 2 * m->cap : 1024;
    double *x = mx_realloc(m->xyz, 3 * cap * sizeof *x);
    if (!x) return MX_ENOMEM;
    m->xyz = x;
    double *s = mx_realloc(m->h, cap * sizeof *s);
    if (!s) return MX_ENOMEM;
    m->h = s;
    m->cap = cap;
  }
  memcpy(m->xyz + 3 * m->n, p, 3 * sizeof *p);
  m->h[m->n++] = h;
  return MX_OK;
}

static void smap_free(smap *m) {
  mx_free(m->xyz);
  mx_free(m->h);
  *m = (smap){0};
}

/* The one rule for a size. */
static int size_ok(double h) { return isfinite(h) && h > 0; }

/* ---- plain text: x y z h a line ------------------------------------------- */

static int text_fail(const char *path, long line, const char *p, const char *what) {
  mx_error(path, line, "'%.*s' %s", mx_io_toklen(p, '#'), p, what);
  return MX_EINPUT;
}

static int text_lines(const char *path, const char *buf, size_t len, smap *m) {
  const char *end = buf + len;
  long line = 1;
  const char *nul = memchr(buf, '\0', len);
  if (nul) {
    for (const char *p = buf; (p = memchr(p, '\n', (size_t)(nul - p))); p++) line++;
    mx_error(path, line, "a NUL byte: not a text file (a size map in text is lines x y z h; "
                         "the extension names the format: .vtu, .vtp, .vtk, .pos or text)");
    return MX_EINPUT;
  }
  for (const char *p = buf; p < end; p = mx_io_next_line(p, end, &line)) {
    const char *q = mx_io_blank(p), *tok[4];
    double v[4];
    int k = 0;
    for (; !mx_io_eol(q, '#'); k++) {
      if (k == 4) {
        mx_error(path, line, "more than 4 numbers: a line is x y z h");
        return MX_EINPUT;
      }
      const char *e = mx_io_double(q, &v[k]);
      if (!e || !mx_io_delim(e, '#'))
        return text_fail(path, line, q, "is not a number (a line is x y z h, separated by blanks)");
      tok[k] = q;
      q = mx_io_blank(e);
    }
    if (k == 0) continue; /* a blank or comment line */
    if (k != 4) {
      mx_error(path, line, "%d numbers, expected 4: x y z h (2D lines x y h are not read: "
                           "give z = 0)", k);
      return MX_EINPUT;
    }
    for (int d = 0; d < 3; d++)
      if (!isfinite(v[d])) return text_fail(path, line, tok[d], "is not a finite coordinate");
    if (!size_ok(v[3]))
      return text_fail(path, line, tok[3], "is not a size: a size must be a finite number > 0");
    MX_CHECK(smap_push(m, v, v[3]));
  }
  return MX_OK;
}

static int read_text(const char *path, smap *m) {
  char *buf;
  size_t len;
  MX_CHECK(mx_io_load(path, &buf, &len));
  const int st = text_lines(path, buf, len, m);
  mx_free(buf);
  return st;
}

/* ---- Gmsh .pos, parsed format ---------------------------------------------- */

typedef struct {
  const char *path, *p, *end;
  long line; /* of p */
} pcur;

static int pos_fail(const pcur *c, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static int pos_fail(const pcur *c, const char *fmt, ...) {
  char msg[MSG];
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(msg, sizeof msg, fmt, ap);
  va_end(ap);
  mx_error(c->path, c->line, "%s", msg);
  return MX_EINPUT;
}

/* What is at the cursor, for messages. */
static const char *pos_found(const pcur *c, char *buf, size_t cap) {
  if (c->p >= c->end) return "the end of the file";
  size_t n = 1;
  while (n < 20 && c->p + n < c->end && !is_ws(c->p[n]) && c->p[n]) n++;
  snprintf(buf, cap, "'%s'", mx_show_word(c->p, n, (char[MX_WORD_BUF]){0}));
  return buf;
}

/* Past blanks and comments (// to the end of the line, C block comments). */
static int pos_skip(pcur *c) {
  const char *p = c->p, *end = c->end;
  for (;;) {
    while (p < end && is_ws(*p)) c->line += *p++ == '\n';
    if (end - p < 2 || p[0] != '/' || (p[1] != '/' && p[1] != '*')) break;
    if (p[1] == '/') {
      const char *nl = memchr(p, '\n', (size_t)(end - p));
      p = nl ? nl : end;
      continue;
    }
    const long open = c->line;
    const char *q = p + 2;
    while (end - q >= 2 && !(q[0] == '*' && q[1] == '/')) c->line += *q++ == '\n';
    if (end - q < 2) {
      c->p = p;
      c->line = open;
      return pos_fail(c, "comment '/*' never closed");
    }
    p = q + 2;
  }
  c->p = p;
  return MX_OK;
}

static int ident_start(char ch) {
  return (ch >= 'A' && ch <= 'Z') || (ch >= 'a' && ch <= 'z') || ch == '_';
}

static int ident_char(char ch) { return ident_start(ch) || (ch >= '0' && ch <= '9'); }

/* The identifier at the cursor (blanks skipped before): *n bytes, 0 if none. */
static int pos_ident(pcur *c, const char **s, size_t *n) {
  MX_CHECK(pos_skip(c));
  const char *p = c->p;
  *s = p;
  if (p < c->end && ident_start(*p))
    while (p < c->end && ident_char(*p)) p++;
  *n = (size_t)(p - *s);
  c->p = p;
  return MX_OK;
}

static int word_is(const char *s, size_t n, const char *w) {
  return n == strlen(w) && memcmp(s, w, n) == 0;
}

/* The string "..." at the cursor, its bytes between the quotes in *s, *n
 * (backslash escapes kept as written). */
static int pos_string(pcur *c, const char **s, size_t *n) {
  const long open = c->line;
  const char *p = c->p + 1, *end = c->end;
  *s = p;
  while (p < end && *p != '"') {
    if (*p == '\\' && end - p >= 2) p++;
    c->line += *p++ == '\n';
  }
  if (p >= end) {
    c->line = open;
    return pos_fail(c, "string never closed by '\"'");
  }
  *n = (size_t)(p - *s);
  c->p = p + 1;
  return MX_OK;
}

/* The character ch must come next. */
static int pos_expect(pcur *c, char ch, const char *what) {
  MX_CHECK(pos_skip(c));
  if (c->p < c->end && *c->p == ch) {
    c->p++;
    return MX_OK;
  }
  char buf[MX_WORD_BUF + 3];
  return pos_fail(c, "%s: expected '%c', found %s", what, ch, pos_found(c, buf, sizeof buf));
}

/* Past the next ';' outside brackets and strings. */
static int pos_skip_statement(pcur *c) {
  const long start = c->line;
  int depth = 0;
  for (;;) {
    MX_CHECK(pos_skip(c));
    if (c->p >= c->end) {
      c->line = start;
      return pos_fail(c, "statement not ended by ';'");
    }
    const char ch = *c->p;
    if (ch == '"') {
      const char *s;
      size_t n;
      MX_CHECK(pos_string(c, &s, &n));
      continue;
    }
    c->p++;
    if (ch == '(' || ch == '{' || ch == '[') {
      depth += depth < 1000000;
    } else if (ch == ')' || ch == '}' || ch == ']') {
      if (depth == 0) return pos_fail(c, "'%c' closes nothing", ch);
      depth--;
    } else if (ch == ';' && depth == 0) {
      return MX_OK;
    }
  }
}

/* Numbers separated by commas up to `close` (consumed): their count in *n,
 * the first `keep` of them in v, and their lines in line (when not NULL). */
static int pos_numbers(pcur *c, char close, size_t keep, double *v, long *line, size_t *n,
                       const char *what) {
  char buf[MX_WORD_BUF + 3];
  *n = 0;
  MX_CHECK(pos_skip(c));
  if (c->p < c->end && *c->p == close) {
    c->p++;
    return MX_OK;
  }
  for (;;) {
    MX_CHECK(pos_skip(c));
    double x = 0;
    const char *e = c->p < c->end ? mx_io_double(c->p, &x) : NULL;
    if (!e || (e < c->end && (ident_char(*e) || *e == '.')))
      return pos_fail(c, "%s: %s is not a number (only plain numbers are read)", what,
                      pos_found(c, buf, sizeof buf));
    if (*n < keep) {
      v[*n] = x;
      if (line) line[*n] = c->line;
    }
    ++*n;
    c->p = e;
    MX_CHECK(pos_skip(c));
    if (c->p < c->end && *c->p == ',') {
      c->p++;
    } else if (c->p < c->end && *c->p == close) {
      c->p++;
      return MX_OK;
    } else {
      return pos_fail(c, "%s: expected ',' or '%c', found %s", what, close,
                      pos_found(c, buf, sizeof buf));
    }
  }
}

/* The scalar elements and their nodes; a vector or tensor element is the
 * same name with V or T first. */
static const struct {
  const char *name;
  int nodes;
} pos_types[] = {{"SP", 1},  {"SL", 2},   {"ST", 3},   {"SQ", 4},   {"SS", 4},
                 {"SH", 8},  {"SI", 6},   {"SY", 5},   {"SL2", 3},  {"ST2", 6},
                 {"SQ2", 9}, {"SS2", 10}, {"SH2", 27}, {"SI2", 18}, {"SY2", 14}};
enum { POS_MAX_NODES = 27 };

/* The nodes of element `id` (il bytes) and its values' components a node
 * (1 scalar, 3 vector, 9 tensor); 0 nodes when it is none of them. */
static int pos_type(const char *id, size_t il, int *ncomp) {
  if (il < 2) return 0;
  *ncomp = id[0] == 'S' ? 1 : id[0] == 'V' ? 3 : id[0] == 'T' ? 9 : 0;
  for (size_t k = 0; *ncomp && k < sizeof pos_types / sizeof pos_types[0]; k++)
    if (word_is(id + 1, il - 1, pos_types[k].name + 1)) return pos_types[k].nodes;
  return 0;
}

typedef struct {
  const char *name; /* the view's, for messages */
  int chosen;       /* its points are read */
  size_t skipped;   /* vector and tensor elements */
  long skipped_line;
} pos_view_state;

/* One element "XY(coordinates){values};" after its name id; its nodes and
 * first time step's values become points when the view is chosen. */
static int pos_element(pcur *c, const char *id, size_t il, int nodes, int ncomp,
                       pos_view_state *vs, smap *m) {
  const long line = c->line;
  char what[MX_WORD_BUF + 64];
  snprintf(what, sizeof what, "view \"%s\": %.*s", vs->name, (int)il, id);
  double xyz[3 * POS_MAX_NODES], v[POS_MAX_NODES];
  long vline[POS_MAX_NODES];
  size_t nc, nv;
  MX_CHECK(pos_expect(c, '(', what));
  MX_CHECK(pos_numbers(c, ')', 3 * POS_MAX_NODES, xyz, NULL, &nc, what));
  if (nc != 3 * (size_t)nodes)
    return pos_fail(c, "%s: %zu coordinates, expected %d (x, y, z of each of its %d nodes)", what,
                    nc, 3 * nodes, nodes);
  MX_CHECK(pos_expect(c, '{', what));
  MX_CHECK(pos_numbers(c, '}', (size_t)nodes, v, vline, &nv, what));
  const size_t step = (size_t)nodes * (size_t)ncomp;
  if (nv == 0 || nv % step)
    return pos_fail(c, "%s: %zu values, expected a multiple of %zu (%d a node for each time step)",
                    what, nv, step, ncomp);
  MX_CHECK(pos_expect(c, ';', what));
  if (!vs->chosen) return MX_OK;
  if (ncomp != 1) {
    if (!vs->skipped++) vs->skipped_line = line;
    return MX_OK;
  }
  for (int j = 0; j < nodes; j++) {
    const double *p = xyz + 3 * j;
    if (!isfinite(p[0]) || !isfinite(p[1]) || !isfinite(p[2])) {
      mx_error(c->path, line, "%s: node %d (%g, %g, %g): the coordinates must be finite", what, j,
               p[0], p[1], p[2]);
      return MX_EINPUT;
    }
    if (!size_ok(v[j])) {
      mx_error(c->path, vline[j], "%s: node %d has size %g: a size must be a finite number > 0",
               what, j, v[j]);
      return MX_EINPUT;
    }
    MX_CHECK(smap_push(m, p, v[j]));
  }
  return MX_OK;
}

/* A view's elements, from its '{' to its '}' (and ';'). */
static int pos_view(pcur *c, pos_view_state *vs, smap *m) {
  char buf[MX_WORD_BUF + 3];
  MX_CHECK(pos_expect(c, '{', "after the view's name"));
  for (;;) {
    MX_CHECK(pos_skip(c));
    if (c->p < c->end && *c->p == '}') {
      c->p++;
      MX_CHECK(pos_skip(c));
      if (c->p < c->end && *c->p == ';') c->p++;
      break;
    }
    const char *id;
    size_t il;
    int ncomp = 0;
    MX_CHECK(pos_ident(c, &id, &il));
    if (il == 0)
      return pos_fail(c, "view \"%s\": expected an element such as ST(...){...}; or '}', found %s",
                      vs->name, pos_found(c, buf, sizeof buf));
    if (word_is(id, il, "T2") || word_is(id, il, "T3") || word_is(id, il, "TIME") ||
        word_is(id, il, "INTERPOLATION_SCHEME")) {
      MX_CHECK(pos_skip_statement(c));
      continue;
    }
    const int nodes = pos_type(id, il, &ncomp);
    if (nodes == 0)
      return pos_fail(c, "view \"%s\": unknown element '%s' (scalar elements: SP, SL, ST, SQ, "
                      "SS, SH, SI, SY and SL2 .. SY2)",
                      vs->name, mx_show_word(id, il, (char[MX_WORD_BUF]){0}));
    MX_CHECK(pos_element(c, id, il, nodes, ncomp, vs, m));
  }
  if (vs->chosen && vs->skipped)
    mx_warning(c->path, vs->skipped_line,
               "view \"%s\": %zu vector or tensor elements skipped: only scalar elements (SP, SL, "
               "ST, ...) give sizes",
               vs->name, vs->skipped);
  return MX_OK;
}

/* The views of the file up to the chosen one: the first named field, or
 * the first. */
static int pos_views(pcur *c, const char *field, smap *m) {
  char seen[400] = "", name[MX_WORD_BUF];
  size_t nviews = 0;
  for (;;) {
    MX_CHECK(pos_skip(c));
    if (c->p >= c->end) break;
    const char *id;
    size_t il;
    MX_CHECK(pos_ident(c, &id, &il));
    MX_CHECK(pos_skip(c));
    if (word_is(id, il, "View") && c->p < c->end && *c->p == '"') {
      const char *s = NULL;
      size_t sl = 0;
      MX_CHECK(pos_string(c, &s, &sl));
      pos_view_state vs = {mx_show_word(s, sl, name), !field || word_is(s, sl, field), 0, 0};
      const size_t used = strlen(seen);
      if (used + strlen(name) + 8 < sizeof seen)
        snprintf(seen + used, sizeof seen - used, "%s\"%s\"", nviews ? ", " : "", name);
      else if (used + 5 < sizeof seen && !strstr(seen, "..."))
        snprintf(seen + used, sizeof seen - used, ", ...");
      nviews++;
      MX_CHECK(pos_view(c, &vs, m));
      if (vs.chosen) return MX_OK;
    } else {
      MX_CHECK(pos_skip_statement(c)); /* anything else of a Gmsh script */
    }
  }
  c->line = 0;
  if (!nviews) return pos_fail(c, "no view: expected View \"name\" { ST(...){...}; ... };");
  return pos_fail(c, "no view named \"%s\" (views: %s)", field, seen);
}

static int read_pos(const char *path, const char *field, smap *m) {
  char *buf;
  size_t len;
  MX_CHECK(mx_io_load(path, &buf, &len));
  pcur c = {path, buf, buf + len, 1};
  const int st = pos_views(&c, field, m);
  mx_free(buf);
  return st;
}

/* ---- a field of a VTK file ------------------------------------------------- */

static const char *const size_names[] = {"size", "h", "target_size", "sizes"};

static int is_size_name(const rd_array *a) {
  for (size_t k = 0; k < sizeof size_names / sizeof size_names[0]; k++)
    if (a->nlen == strlen(size_names[k]) && strncasecmp(a->name, size_names[k], a->nlen) == 0)
      return 1;
  return 0;
}

/* The fields listed, for messages: "point fields: a, b (3 components);
 * cell fields: c". */
static void field_list(const rd_fields *f, char *out, size_t cap) {
  size_t w = 0;
  out[0] = '\0';
  for (int point = 1; point >= 0; point--) {
    int first = 1;
    for (size_t i = 0; i < f->narr && w + 8 < cap; i++) {
      const rd_array *a = &f->arr[i];
      if (a->point != point) continue;
      char name[MX_WORD_BUF], comps[32] = "";
      if (a->ncomp != 1) snprintf(comps, sizeof comps, " (%llu components)", (unsigned long long)a->ncomp);
      const int k = snprintf(out + w, cap - w, "%s%s'%s'%s", first ? (w ? "; " : "") : ", ",
                             first ? (point ? "point fields: " : "cell fields: ") : "",
                             a->nlen ? mx_show_word(a->name, a->nlen, name) : "", comps);
      first = 0;
      w = k < 0 || (size_t)k >= cap - w ? cap - 1 : w + (size_t)k;
    }
  }
  if (w == 0) snprintf(out, cap, "no point or cell field");
  if (f->stopped && w + 8 < cap) {
    const size_t n = tok_len(f->stopped, f->stopped + 40);
    char word[MX_WORD_BUF];
    snprintf(out + w, cap - w, "; the attributes from %s on were not read",
             mx_show_word(f->stopped, n, word));
  }
  if (w + 1 >= cap && cap > 4) memcpy(out + cap - 4, "...", 4);
}

/* The size field of a VTK file: vtk_fields.h's pick, by the rule of
 * read_sizemap.h. */
static int pick_field(const rd *r, const rd_fields *f, size_t *which) {
  const char *want = f->user;
  char list[480];
  if (want) {
    for (int point = 1; point >= 0; point--)
      for (size_t i = 0; i < f->narr; i++) {
        const rd_array *a = &f->arr[i];
        if (a->point != point || !word_is(a->name, a->nlen, want)) continue;
        if (a->ncomp != 1)
          return mx_rd_fail(r, a->at, "field '%s' has %llu components: a size field has 1", want,
                            (unsigned long long)a->ncomp);
        *which = i;
        return MX_OK;
      }
    field_list(f, list, sizeof list);
    return mx_rd_fail(r, NULL, "no field named '%s' (%s)", want, list);
  }
  for (int point = 1; point >= 0; point--)
    for (size_t i = 0; i < f->narr; i++)
      if (f->arr[i].point == point && f->arr[i].ncomp == 1 && is_size_name(&f->arr[i])) {
        *which = i;
        return MX_OK;
      }
  size_t np = 0, nc = 0, ip = 0, ic = 0;
  for (size_t i = 0; i < f->narr; i++) {
    if (f->arr[i].ncomp != 1) continue;
    if (f->arr[i].point && !np++) ip = i;
    if (!f->arr[i].point && !nc++) ic = i;
  }
  if (np == 1 || (np == 0 && nc == 1)) {
    *which = np ? ip : ic;
    return MX_OK;
  }
  field_list(f, list, sizeof list);
  if (np + nc == 0)
    return mx_rd_fail(r, NULL, "no field of one component to take the sizes from (%s)", list);
  return mx_rd_fail(r, NULL,
                    "%zu fields of one component, none named size, h, target_size or sizes: "
                    "name the one to read (%s)",
                    np + nc, list);
}

/* Value i of a field of any number type. */
static double raw_value(const rawarr *a, size_t i) {
  if (is_float(a->t)) return raw_double(a, i);
  if (a->t == T_U64) return (double)load_bits(a->data + 8 * i, 8, a->swap);
  return (double)raw_int(a, i);
}

/* The centroid of each cell of block c (its first cell is cell `first` of
 * the field) into out, 3 a cell. Offsets must increase, so the work is
 * bounded by the connectivity's length. */
static int block_centroids(rd *r, const rd_fields *f, const rd_cells *c, size_t first,
                           double *out) {
  size_t pos = 0; /* list form: the next cell's count */
  for (size_t k = 0; k < c->ncells; k++) {
    const rawarr *nodes;
    size_t s, e;
    if (c->list_form) {
      if (pos >= c->list.n)
        return mx_rd_fail(r, c->at, "cell %zu: the cell list ends before it", first + k);
      const int64_t cnt = raw_int(&c->list, pos);
      if (cnt < 1 || (uint64_t)cnt > c->list.n - pos - 1)
        return mx_rd_fail(r, mx_rd_arr_at(r, &c->list, pos),
                          "cell %zu: %lld nodes, but %zu values are left in the cell list",
                          first + k, (long long)cnt, c->list.n - pos - 1);
      s = pos + 1;
      e = s + (size_t)cnt;
      pos = e;
      nodes = &c->list;
    } else {
      const size_t j0 = c->vtu_offsets ? k : k + 1; /* the cell's end offset */
      if (j0 >= c->off.n) return mx_rd_fail(r, c->at, "cell %zu has no offset", first + k);
      const int64_t a = c->vtu_offsets ? (k ? raw_int(&c->off, k - 1) : 0) : raw_int(&c->off, k);
      const int64_t b = raw_int(&c->off, j0);
      if (a < 0 || b <= a || (uint64_t)b > c->cn.n)
        return mx_rd_fail(r, mx_rd_arr_at(r, &c->off, j0),
                          "cell %zu: offsets %lld..%lld are not a non-empty increasing range "
                          "inside the %zu connectivity entries",
                          first + k, (long long)a, (long long)b, c->cn.n);
      s = (size_t)a;
      e = (size_t)b;
      nodes = &c->cn;
    }
    double sum[3] = {0, 0, 0};
    for (size_t j = s; j < e; j++) {
      const int64_t v = raw_int(nodes, j);
      if (v < 0 || (uint64_t)v >= f->npts)
        return mx_rd_fail(r, mx_rd_arr_at(r, nodes, j),
                          "cell %zu: node %lld out of range (%zu points, 0-based)", first + k,
                          (long long)v, f->npts);
      for (int d = 0; d < 3; d++) sum[d] += raw_double(&f->pts, 3 * (size_t)v + (size_t)d);
    }
    for (int d = 0; d < 3; d++) out[3 * k + (size_t)d] = sum[d] / (double)(e - s);
  }
  if (c->list_form && pos != c->list.n)
    return mx_rd_fail(r, c->at, "the cell list has %zu values but its %zu cells use %zu",
                      c->list.n, c->ncells, pos);
  return MX_OK;
}

/* The points and sizes of the field picked: the points with a point
 * field, the cells' centroids with a cell field. */
static int field_points(rd *r, const rd_fields *f, smap *m) {
  const rd_array *a = &f->arr[f->which];
  char name[MX_WORD_BUF];
  mx_show_word(a->name, a->nlen, name);
  for (size_t i = 0; i < 3 * f->npts; i++) {
    const double x = raw_double(&f->pts, i);
    if (!isfinite(x))
      return mx_rd_fail(r, mx_rd_arr_at(r, &f->pts, i),
                        "point %zu: coordinate %zu is %g, not a finite number", i / 3, i % 3, x);
  }
  const size_t n = a->point ? f->npts : f->ncells;
  if (n == 0) return MX_OK; /* the caller says the map is empty */
  m->xyz = mx_alloc(3 * n * sizeof *m->xyz);
  m->h = mx_alloc(n * sizeof *m->h);
  if (!m->xyz || !m->h) return MX_ENOMEM;
  m->n = m->cap = n;
  for (size_t i = 0; i < n; i++) {
    m->h[i] = raw_value(&f->values, i);
    if (!size_ok(m->h[i]))
      return mx_rd_fail(r, mx_rd_arr_at(r, &f->values, i),
                        "field '%s': %s %zu has size %g: a size must be a finite number > 0",
                        name, a->point ? "point" : "cell", i, m->h[i]);
  }
  if (a->point) {
    for (size_t i = 0; i < 3 * n; i++) m->xyz[i] = raw_double(&f->pts, i);
    return MX_OK;
  }
  size_t first = 0;
  for (int b = 0; b < RD_MAX_BLOCKS; b++) {
    if (first + f->cells[b].ncells > n) /* the readers' counts add up to n */
      return mx_rd_fail(r, NULL, "more cells in the blocks than the field's %zu", n);
    MX_CHECK(block_centroids(r, f, &f->cells[b], first, m->xyz + 3 * first));
    first += f->cells[b].ncells;
  }
  if (first != n) return mx_rd_fail(r, NULL, "%zu cells for the field's %zu values", first, n);
  return MX_OK;
}

static int read_vtk(const char *path, const char *field, smap *m) {
  char *buf;
  size_t len;
  MX_CHECK(mx_io_load(path, &buf, &len));
  rd r;
  memset(&r, 0, sizeof r);
  r.path = path;
  r.buf = buf;
  r.end = buf + len;
  rd_fields *f = mx_calloc(sizeof *f);
  int st = MX_ENOMEM;
  if (f) {
    f->pick = pick_field;
    f->user = field;
    const char *p = skip_ws(r.buf, r.end);
    static const char magic[] = "# vtk DataFile";
    if (p < r.end && *p == '<')
      st = mx_rd_vtu_fields(&r, f);
    else if ((size_t)(r.end - p) >= sizeof magic - 1 && strncasecmp(p, magic, sizeof magic - 1) == 0)
      st = mx_rd_vtk_legacy_fields(&r, f);
    else
      st = mx_rd_fail(&r, p, "not a VTK file: expected '# vtk DataFile Version' (legacy VTK) or "
                      "'<VTKFile' (VTK XML)");
    if (st == MX_OK) st = field_points(&r, f, m);
  }
  for (int i = 0; i < r.ntmp; i++) mx_free(r.tmp[i]);
  mx_free(f);
  mx_free(buf);
  return st;
}

/* ---- the entry point ------------------------------------------------------- */

static int has_extension(const char *path, const char *ext) {
  const size_t n = strlen(path), e = strlen(ext);
  return n > e && strcasecmp(path + n - e, ext) == 0;
}

int mx_sizemap_read(const char *path, const char *field, double **xyz, double **h, size_t *n) {
  *xyz = NULL;
  *h = NULL;
  *n = 0;
  smap m = {0};
  int st;
  if (has_extension(path, ".vtu") || has_extension(path, ".vtp") || has_extension(path, ".vtk")) {
    st = read_vtk(path, field, &m);
  } else if (has_extension(path, ".pos")) {
    st = read_pos(path, field, &m);
  } else {
    if (field)
      mx_warning(path, 0, "the field name '%s' is not used: a size map in text has one size a line",
                 field);
    st = read_text(path, &m);
  }
  if (st == MX_OK && m.n == 0) {
    mx_error(path, 0, "no point: a size map needs at least one point with its size");
    st = MX_EINPUT;
  }
  if (st != MX_OK) {
    smap_free(&m);
    return st;
  }
  *xyz = m.xyz;
  *h = m.h;
  *n = m.n;
  return MX_OK;
}
