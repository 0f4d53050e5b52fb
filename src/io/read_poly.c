/* Readers of 2D polylines into an mx_poly (quad/quad.h). Every error is one
 * message "FILE:LINE: ..." (mx_error) and MX_EINPUT; the poly is left empty.
 *
 * .poly (Triangle's format; '#' starts a comment, blank lines are skipped):
 *   <#vertices> <dimension, 2> [<#attributes> [<#boundary markers, 0|1>]]
 *   one line a vertex:   <vertex #> <x> <y> [attributes...] [marker]
 *   <#segments> [<#boundary markers, 0|1>]
 *   one line a segment:  <segment #> <endpoint> <endpoint> [marker]
 *   <#holes>
 *   one line a hole:     <hole #> <x> <y>
 *   optional: <#regions>, one line a region: <region #> <x> <y> [...] (ignored)
 * Vertices are numbered consecutively from the first one's number (0 or 1);
 * endpoints use those numbers. A .poly with 0 vertices (they would be in a
 * separate .node file) is refused. Values past the declared ones on a line
 * are ignored, as Triangle does.
 *
 * .off: "OFF", then "nv nf [ne]", nv lines "x y z" with z = 0, nf lines
 * "k i0 .. ik-1" (k >= 3, 0-based): each face is one closed polygon, its
 * segments i0->i1, .., ik-1->i0, in face order.
 *
 * .mdl (2D): sections headed "[Name, TYPE]", in any order:
 *   [Name, STRING]                 the next line: a name (ignored)
 *   [Vertices, ARRAY1<POINT2D>]    the count, then one "x y" a line
 *                                  (ARRAY1<POINT3D>: "x y z" with z = 0)
 *   [Edges, ARRAY1<STRING>]        the count, then one "a b" a line: a
 *                                  segment from vertex a to b (0-based);
 *                                  [Segments, ARRAY1<STRING>] is the same
 * Other ARRAY1 sections are skipped; there are no comments. */
#include <math.h>
#include <stdint.h>
#include <string.h>
#include <strings.h>

#include "base/common.h"
#include "io/off_header.h"
#include "io/read_poly.h"

#include "io/mdl_sections.h"
#include "io/text_scan.h"

typedef struct {
  const char *path, *p, *end; /* p: the current content line */
  long line;
  char comment; /* '#', or 0 for none (.mdl) */
} rd;

/* ---- scanning --------------------------------------------------------- */

/* Moves to the next content line; the file ending first is an error. */
static int next_item(rd *f, const char *what, size_t i, size_t n) {
  f->p = mx_io_next_line(f->p, f->end, &f->line);
  f->p = mx_io_content(f->p, f->end, &f->line, f->comment);
  if (f->p < f->end && (f->comment || *f->p != '[')) return MX_OK;
  mx_error(f->path, f->line,
           "unexpected %s: %zu of %zu %s read (truncated file or wrong count)",
           f->p < f->end ? "section header" : "end of file", i, n, what);
  return MX_EINPUT;
}

/* Moves to the next content line, which must exist: it holds `what`. */
static int next_section(rd *f, const char *what) {
  f->p = mx_io_next_line(f->p, f->end, &f->line);
  f->p = mx_io_content(f->p, f->end, &f->line, f->comment);
  if (f->p < f->end) return MX_OK;
  mx_error(f->path, f->line, "unexpected end of file: expected %s", what);
  return MX_EINPUT;
}

/* Whether another content line follows the current one (does not move). */
static int more_content(const rd *f) {
  long line = f->line;
  const char *p = mx_io_next_line(f->p, f->end, &line);
  return mx_io_content(p, f->end, &line, f->comment) < f->end;
}

/* An integer token at *q (blanks skipped first). */
static int int_token(rd *f, const char **q, int64_t *v, const char *what) {
  const char *s = mx_io_blank(*q);
  if (mx_io_eol(s, f->comment)) {
    mx_error(f->path, f->line, "missing %s", what);
    return MX_EINPUT;
  }
  const char *e = mx_io_int(s, v);
  if (!e || !mx_io_delim(e, f->comment)) {
    mx_error(f->path, f->line, "%s: '%.*s' is not an integer", what,
             mx_io_toklen(s, f->comment), s);
    return MX_EINPUT;
  }
  *q = e;
  return MX_OK;
}

/* A count in [0, max]; an absent optional one (dflt >= 0) reads as dflt. */
static int count_token(rd *f, const char **q, int64_t dflt, int64_t max, int64_t *v,
                       const char *what) {
  if (dflt >= 0 && mx_io_eol(mx_io_blank(*q), f->comment)) {
    *v = dflt;
    return MX_OK;
  }
  MX_CHECK(int_token(f, q, v, what));
  if (*v >= 0 && *v <= max) return MX_OK;
  mx_error(f->path, f->line, "%s: %lld is out of range (0 to %lld)", what, (long long)*v,
           (long long)max);
  return MX_EINPUT;
}

/* Nothing but blanks and a comment may follow on the line. */
static int line_done(rd *f, const char *q, const char *after) {
  const char *s = mx_io_blank(q);
  if (mx_io_eol(s, f->comment)) return MX_OK;
  mx_error(f->path, f->line, "unexpected '%.*s' after %s", mx_io_toklen(s, f->comment), s,
           after);
  return MX_EINPUT;
}

/* n items of at least min_bytes each must fit in the rest of the file: a
 * wrong count is refused before anything is allocated for it. */
static int fits(const rd *f, size_t n, size_t min_bytes, const char *what) {
  const size_t rest = (size_t)(f->end - f->p);
  if (n <= rest / min_bytes + 1) return MX_OK;
  mx_error(f->path, f->line,
           "%zu %s declared, more than the rest of the file can hold (wrong count or "
           "truncated file)",
           n, what);
  return MX_EINPUT;
}

/* ---- the poly --------------------------------------------------------- */

static int alloc_vertices(mx_poly *P, size_t nv) {
  P->xy = mx_alloc(2 * nv * sizeof *P->xy);
  if (!P->xy) return MX_ENOMEM;
  P->nv = nv;
  return MX_OK;
}

/* Room for n segments, keeping the first P->ns (capacity in *cap). */
static int reserve_segments(mx_poly *P, size_t *cap, size_t n) {
  if (n <= *cap) return MX_OK;
  size_t c = *cap ? 2 * *cap : 16;
  if (c < n) c = n;
  uint32_t *s = mx_realloc(P->seg, 2 * c * sizeof *s);
  if (!s) return MX_ENOMEM;
  P->seg = s;
  uint32_t *l = mx_realloc(P->line, c * sizeof *l);
  if (!l) return MX_ENOMEM;
  P->line = l;
  *cap = c;
  return MX_OK;
}

static int set_path(mx_poly *P, const char *path) {
  const size_t n = strlen(path) + 1;
  P->path = mx_alloc(n);
  if (!P->path) return MX_ENOMEM;
  memcpy(P->path, path, n);
  return MX_OK;
}

/* Loads the file and runs parse on it; on failure the poly is emptied. */
static int read_with(const char *path, mx_poly *P, char comment, int (*parse)(rd *, mx_poly *)) {
  memset(P, 0, sizeof *P);
  char *buf;
  size_t len;
  MX_CHECK(mx_io_load(path, &buf, &len));
  rd f = {path, buf, buf + len, 1, comment};
  int status = parse(&f, P);
  if (status == MX_OK) status = set_path(P, path);
  mx_free(buf);
  if (status != MX_OK) mx_poly_free(P);
  return status;
}

/* ---- .poly ------------------------------------------------------------ */

typedef struct {
  int64_t base;      /* the first vertex's number */
  int extra_v;       /* attributes and marker per vertex line */
  int extra_s;       /* marker per segment line */
} poly_counts;

/* `n` more numbers on the line (attributes, markers), which must be there. */
static int skip_numbers(rd *f, const char **q, int n, const char *what, int64_t item) {
  for (int k = 0; k < n; k++) {
    const char *s = mx_io_blank(*q);
    double v;
    const char *e = mx_io_eol(s, f->comment) ? NULL : mx_io_double(s, &v);
    if (!e || !mx_io_delim(e, f->comment)) {
      mx_error(f->path, f->line,
               "%s %lld: %d attribute/marker value(s) declared in the header, value %d is %s",
               what, (long long)item, n, k + 1, e || !mx_io_eol(s, f->comment) ? "not a number"
                                                                                : "missing");
      return MX_EINPUT;
    }
    *q = e;
  }
  return MX_OK;
}

static int poly_header(rd *f, mx_poly *P, poly_counts *c) {
  f->p = mx_io_content(f->p, f->end, &f->line, '#');
  if (f->p == f->end) {
    mx_error(f->path, f->line, "no content: expected '<#vertices> 2 <#attributes> <#markers>'");
    return MX_EINPUT;
  }
  const char *q = f->p;
  int64_t nv, dim, nattr, nmark;
  MX_CHECK(count_token(f, &q, -1, (int64_t)UINT32_MAX - 2, &nv, "number of vertices"));
  MX_CHECK(count_token(f, &q, 2, 1000000, &dim, "dimension"));
  MX_CHECK(count_token(f, &q, 0, 1000, &nattr, "number of vertex attributes"));
  MX_CHECK(count_token(f, &q, 0, 1, &nmark, "number of vertex boundary markers"));
  MX_CHECK(line_done(f, q, "the vertex counts"));
  if (nv == 0) {
    mx_error(f->path, f->line,
             "0 vertices: the vertices would be in a separate .node file, which is not "
             "read; list them in the .poly file");
    return MX_EINPUT;
  }
  if (dim != 2) {
    mx_error(f->path, f->line, "dimension %lld: a .poly file for this mesher is 2D",
             (long long)dim);
    return MX_EINPUT;
  }
  c->extra_v = (int)(nattr + nmark);
  MX_CHECK(fits(f, (size_t)nv, 5, "vertices"));
  return alloc_vertices(P, (size_t)nv);
}

static int poly_vertex(rd *f, mx_poly *P, poly_counts *c, size_t i) {
  const char *q = f->p;
  int64_t num;
  MX_CHECK(int_token(f, &q, &num, "vertex number"));
  if (i == 0 && num != 0 && num != 1) {
    mx_error(f->path, f->line, "the first vertex is numbered %lld: expected 0 or 1",
             (long long)num);
    return MX_EINPUT;
  }
  if (i == 0) c->base = num;
  if (num != c->base + (int64_t)i) {
    mx_error(f->path, f->line,
             "vertex number %lld where %lld was expected (vertices are numbered "
             "consecutively from the first)",
             (long long)num, (long long)(c->base + (int64_t)i));
    return MX_EINPUT;
  }
  MX_CHECK(mx_io_numbers(f->path, f->line, &q, '#', 2, P->xy + 2 * i, "vertex", (size_t)num));
  return skip_numbers(f, &q, c->extra_v, "vertex", num);
}

static int poly_segment_header(rd *f, mx_poly *P, poly_counts *c, size_t *ns_out) {
  MX_CHECK(next_section(f, "the segment counts '<#segments> <#markers>'"));
  const char *q = f->p;
  int64_t ns, nmark;
  MX_CHECK(count_token(f, &q, -1, (int64_t)UINT32_MAX - 1, &ns, "number of segments"));
  MX_CHECK(count_token(f, &q, 0, 1, &nmark, "number of segment boundary markers"));
  MX_CHECK(line_done(f, q, "the segment counts"));
  if (ns == 0) {
    mx_error(f->path, f->line, "0 segments: nothing to mesh");
    return MX_EINPUT;
  }
  c->extra_s = (int)nmark;
  MX_CHECK(fits(f, (size_t)ns, 5, "segments"));
  size_t cap = 0;
  *ns_out = (size_t)ns;
  return reserve_segments(P, &cap, (size_t)ns);
}

static int poly_segment(rd *f, mx_poly *P, const poly_counts *c, size_t i) {
  const char *q = f->p;
  int64_t num, v;
  MX_CHECK(int_token(f, &q, &num, "segment number"));
  for (int k = 0; k < 2; k++) {
    MX_CHECK(int_token(f, &q, &v, "segment endpoint"));
    if (v < c->base || v - c->base >= (int64_t)P->nv) {
      mx_error(f->path, f->line, "segment %lld: endpoint %lld out of range (vertices %lld to %lld)",
               (long long)num, (long long)v, (long long)c->base,
               (long long)(c->base + (int64_t)P->nv - 1));
      return MX_EINPUT;
    }
    P->seg[2 * i + (size_t)k] = (uint32_t)(v - c->base);
  }
  P->line[i] = (uint32_t)f->line;
  return skip_numbers(f, &q, c->extra_s, "segment", num);
}

/* "<#holes>" then the holes' points. */
static int poly_holes(rd *f, mx_poly *P) {
  MX_CHECK(next_section(f, "the number of holes"));
  const char *q = f->p;
  int64_t nh;
  MX_CHECK(count_token(f, &q, -1, (int64_t)UINT32_MAX, &nh, "number of holes"));
  MX_CHECK(line_done(f, q, "the number of holes"));
  MX_CHECK(fits(f, (size_t)nh, 5, "holes"));
  P->holes = mx_alloc(2 * (size_t)nh * sizeof *P->holes);
  if (!P->holes) return MX_ENOMEM;
  P->nholes = (size_t)nh;
  for (size_t i = 0; i < P->nholes; i++) {
    MX_CHECK(next_item(f, "holes", i, P->nholes));
    q = f->p;
    int64_t num;
    MX_CHECK(int_token(f, &q, &num, "hole number"));
    MX_CHECK(mx_io_numbers(f->path, f->line, &q, '#', 2, P->holes + 2 * i, "hole", (size_t)i));
  }
  return MX_OK;
}

/* The optional regional attributes: checked for shape, then ignored. */
static int poly_regions(rd *f) {
  if (!more_content(f)) return MX_OK;
  MX_CHECK(next_section(f, "the number of regions"));
  const char *q = f->p;
  int64_t nr;
  MX_CHECK(count_token(f, &q, -1, (int64_t)UINT32_MAX, &nr, "number of regional attributes"));
  MX_CHECK(line_done(f, q, "the number of regional attributes"));
  for (size_t i = 0; i < (size_t)nr; i++) {
    MX_CHECK(next_item(f, "regional attributes", i, (size_t)nr));
    q = f->p;
    int64_t num;
    double xy[2];
    MX_CHECK(int_token(f, &q, &num, "region number"));
    MX_CHECK(mx_io_numbers(f->path, f->line, &q, '#', 2, xy, "region", i));
  }
  return MX_OK;
}

/* After the last section only comments and blank lines. */
static int trailer(rd *f, const char *what) {
  if (!more_content(f)) return MX_OK;
  f->p = mx_io_next_line(f->p, f->end, &f->line);
  f->p = mx_io_content(f->p, f->end, &f->line, f->comment);
  mx_error(f->path, f->line, "more data after %s: wrong counts?", what);
  return MX_EINPUT;
}

static int parse_poly(rd *f, mx_poly *P) {
  poly_counts c = {0, 0, 0};
  size_t ns;
  MX_CHECK(poly_header(f, P, &c));
  for (size_t i = 0; i < P->nv; i++) {
    MX_CHECK(next_item(f, "vertices", i, P->nv));
    MX_CHECK(poly_vertex(f, P, &c, i));
  }
  MX_CHECK(poly_segment_header(f, P, &c, &ns));
  for (size_t i = 0; i < ns; i++) {
    MX_CHECK(next_item(f, "segments", i, ns));
    MX_CHECK(poly_segment(f, P, &c, i));
    P->ns = i + 1;
  }
  MX_CHECK(poly_holes(f, P));
  MX_CHECK(poly_regions(f));
  return trailer(f, "the holes and regional attributes");
}

int mx_read_poly(const char *path, mx_poly *P) { return read_with(path, P, '#', parse_poly); }

/* ---- .off ------------------------------------------------------------- */

static int off_header(rd *f, mx_poly *P, size_t *nf) {
  f->p = mx_io_content(f->p, f->end, &f->line, '#');
  const int n = f->p < f->end ? mx_io_toklen(f->p, '#') : 0;
  if (!mx_off_keyword(f->p, n)) {
    mx_error(f->path, f->line, "bad header: expected 'OFF', found '%.*s'", n, f->p);
    return MX_EINPUT;
  }
  const char *q = mx_io_blank(f->p + n);
  if (mx_io_eol(q, '#')) {
    MX_CHECK(next_section(f, "the counts 'nv nf ne'"));
    q = f->p;
  }
  int64_t nv, k;
  MX_CHECK(count_token(f, &q, -1, (int64_t)UINT32_MAX - 1, &nv, "number of vertices"));
  MX_CHECK(count_token(f, &q, -1, (int64_t)UINT32_MAX, &k, "number of faces"));
  if (nv == 0 || k == 0) {
    mx_error(f->path, f->line, "the header declares no %s", nv == 0 ? "vertices" : "faces");
    return MX_EINPUT;
  }
  *nf = (size_t)k;
  MX_CHECK(fits(f, (size_t)nv, 5, "vertices"));
  return alloc_vertices(P, (size_t)nv);
}

static int off_vertex(rd *f, mx_poly *P, size_t i) {
  double c[3];
  MX_CHECK(mx_io_numbers(f->path, f->line, &f->p, '#', 3, c, "vertex", i));
  if (c[2] != 0.0) {
    mx_error(f->path, f->line, "vertex %zu: z = %g, but a 2D OFF file has z = 0", i, c[2]);
    return MX_EINPUT;
  }
  P->xy[2 * i] = c[0];
  P->xy[2 * i + 1] = c[1];
  return MX_OK;
}

/* "k i0 .. ik-1": the closed polygon i0 -> i1 -> .. -> ik-1 -> i0. */
static int off_face(rd *f, mx_poly *P, size_t *cap, size_t i) {
  const char *q = f->p;
  int64_t k;
  MX_CHECK(int_token(f, &q, &k, "face vertex count"));
  if (k < 3 || k > (int64_t)UINT32_MAX) {
    mx_error(f->path, f->line, "face %zu: %lld vertices, a polygon needs 3 or more", i,
             (long long)k);
    return MX_EINPUT;
  }
  const size_t first = P->ns;
  for (int64_t j = 0; j < k; j++) {
    uint32_t v;
    MX_CHECK(mx_io_index(f->path, f->line, &q, '#', P->nv, &v, "face", i));
    MX_CHECK(reserve_segments(P, cap, P->ns + 1));
    P->seg[2 * P->ns] = v; /* its end is the next vertex, set below */
    if (j > 0) P->seg[2 * P->ns - 1] = v;
    P->line[P->ns++] = (uint32_t)f->line;
  }
  P->seg[2 * P->ns - 1] = P->seg[2 * first];
  return MX_OK;
}

static int parse_off(rd *f, mx_poly *P) {
  size_t nf, cap = 0;
  MX_CHECK(off_header(f, P, &nf));
  for (size_t i = 0; i < P->nv; i++) {
    MX_CHECK(next_item(f, "vertices", i, P->nv));
    MX_CHECK(off_vertex(f, P, i));
  }
  MX_CHECK(fits(f, nf, 7, "faces"));
  for (size_t i = 0; i < nf; i++) {
    MX_CHECK(next_item(f, "faces", i, nf));
    MX_CHECK(off_face(f, P, &cap, i));
  }
  return trailer(f, "the faces");
}

int mx_read_poly_off(const char *path, mx_poly *P) {
  return read_with(path, P, '#', parse_off);
}

/* ---- .mdl ------------------------------------------------------------- */

typedef struct {
  int have_vertices, have_edges;
  size_t cap; /* segments allocated */
} mdl_state;

/* The count line after an array header: below 2^32 - 1. */
static int mdl_count(rd *f, const mx_mdl_header *h, size_t *n) {
  return mx_mdl_count(f->path, &f->line, &f->p, f->end, h, (int64_t)UINT32_MAX - 1, n);
}

static int mdl_vertices(rd *f, mx_poly *P, const mx_mdl_header *h) {
  const int dim = mx_mdl_same(h->type, h->ntype, "ARRAY1<POINT2D>")   ? 2
                  : mx_mdl_same(h->type, h->ntype, "ARRAY1<POINT3D>") ? 3
                                                                      : 0;
  if (!dim) {
    mx_error(f->path, f->line, "[Vertices] section of type '%.*s': expected ARRAY1<POINT2D>",
             h->ntype, h->type);
    return MX_EINPUT;
  }
  size_t n;
  MX_CHECK(mdl_count(f, h, &n));
  MX_CHECK(fits(f, n, 3, "vertices"));
  MX_CHECK(alloc_vertices(P, n));
  for (size_t i = 0; i < n; i++) {
    MX_CHECK(next_item(f, "vertices", i, n));
    double c[3] = {0, 0, 0};
    MX_CHECK(mx_io_numbers(f->path, f->line, &f->p, 0, dim, c, "vertex", i));
    if (c[2] != 0.0) {
      mx_error(f->path, f->line, "vertex %zu: z = %g, but a 2D file has z = 0", i, c[2]);
      return MX_EINPUT;
    }
    memcpy(P->xy + 2 * i, c, 2 * sizeof *c);
  }
  return MX_OK;
}

/* Indices are checked against the vertex count at the end: the vertices
 * may come later. */
static int mdl_edges(rd *f, mx_poly *P, const mx_mdl_header *h, mdl_state *s) {
  size_t n;
  MX_CHECK(mdl_count(f, h, &n));
  MX_CHECK(fits(f, n, 3, "edges"));
  MX_CHECK(reserve_segments(P, &s->cap, n ? n : 1));
  for (size_t i = 0; i < n; i++) {
    MX_CHECK(next_item(f, "edges", i, n));
    for (int k = 0; k < 2; k++)
      MX_CHECK(mx_io_index(f->path, f->line, &f->p, 0, UINT32_MAX, &P->seg[2 * i + (size_t)k],
                           "edge", i));
    P->line[i] = (uint32_t)f->line;
    P->ns = i + 1;
  }
  return MX_OK;
}

static int mdl_skip(rd *f, const mx_mdl_header *h) {
  size_t n;
  MX_CHECK(mdl_count(f, h, &n));
  for (size_t i = 0; i < n; i++) MX_CHECK(next_item(f, "items", i, n));
  return MX_OK;
}

static int mdl_section(rd *f, mx_poly *P, mdl_state *s) {
  mx_mdl_header h;
  MX_CHECK(mx_mdl_parse_header(f->path, f->line, f->p, f->end, "[Vertices, ARRAY1<POINT2D>]",
                               &h));
  if (mx_mdl_same(h.name, h.nname, "Vertices")) {
    MX_CHECK(mx_mdl_once(f->path, f->line, &s->have_vertices, &h));
    return mdl_vertices(f, P, &h);
  }
  if (mx_mdl_is_array(&h)) {
    if (!mx_mdl_same(h.name, h.nname, "Edges") && !mx_mdl_same(h.name, h.nname, "Segments"))
      return mdl_skip(f, &h);
    MX_CHECK(mx_mdl_once(f->path, f->line, &s->have_edges, &h));
    return mdl_edges(f, P, &h, s);
  }
  return mx_mdl_non_array(f->path, &f->line, &f->p, f->end, &h);
}

static int parse_mdl(rd *f, mx_poly *P) {
  mdl_state s = {0, 0, 0};
  for (;;) {
    f->p = mx_io_content(f->p, f->end, &f->line, 0);
    if (f->p == f->end) break;
    MX_CHECK(mdl_section(f, P, &s));
    f->p = mx_io_next_line(f->p, f->end, &f->line);
  }
  if (!s.have_vertices || !s.have_edges) {
    mx_error(f->path, 0, "no [%s] section",
             s.have_vertices ? "Edges, ARRAY1<STRING>" : "Vertices, ARRAY1<POINT2D>");
    return MX_EINPUT;
  }
  if (P->nv == 0 || P->ns == 0) {
    mx_error(f->path, 0, "no %s", P->nv == 0 ? "vertices" : "edges");
    return MX_EINPUT;
  }
  for (size_t i = 0; i < 2 * P->ns; i++) {
    if (P->seg[i] < P->nv) continue;
    mx_error(f->path, P->line[i / 2], "edge %zu: vertex index %u out of range (%zu vertices, 0-based)",
             i / 2, P->seg[i], P->nv);
    return MX_EINPUT;
  }
  return MX_OK;
}

int mx_read_poly_mdl(const char *path, mx_poly *P) { return read_with(path, P, 0, parse_mdl); }

/* ---- by extension ------------------------------------------------------ */

int mx_read_poly_any(const char *path, mx_poly *P) {
  const char *slash = strrchr(path, '/');
  const char *dot = strrchr(slash ? slash + 1 : path, '.');
  const char *ext = dot ? dot : "";
  if (!strcasecmp(ext, ".poly")) return mx_read_poly(path, P);
  if (!strcasecmp(ext, ".off")) return mx_read_poly_off(path, P);
  if (!strcasecmp(ext, ".mdl")) return mx_read_poly_mdl(path, P);
  memset(P, 0, sizeof *P);
  mx_error(path, 0, "unknown 2D input format '%s': expected .poly, .off or .mdl", ext);
  return MX_EINPUT;
}
