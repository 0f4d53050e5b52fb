/* Wavefront OBJ reader: "v x y z [...]" and "f a b c ..." with 1-based,
 * negative (relative to the vertices read so far) and "a/b/c", "a//c",
 * "a/b" forms; polygons are split into triangles in their plane
 * (io/polygon_split.c); every other line is ignored. A first pass counts
 * the vertices, so positive indices may refer forward (the faces from the
 * first such one on are split once all vertices are read). Triangles
 * remember their face, numbered from 1 as OBJ counts, and its line. */
#include <stdint.h>
#include <string.h>

#include "base/common.h"
#include "soa/trisoup.h"

#include "io/polygon_split.h"
#include "io/text_scan.h"
#include "io/read_surface.h"

typedef struct {
  const char *path, *p, *end; /* p: the current content line */
  long line;
  size_t nv_total, nfaces;
} obj_file;

/* The keyword starting a content line: 'v', 'f', or 0 for anything else. */
static char keyword(const char *p) {
  if ((p[0] == 'v' || p[0] == 'f') && mx_io_delim(p + 1, '#')) return p[0];
  return 0;
}

/* First pass: counts "v" and "f" lines. */
static void count_lines(const char *buf, const char *end, size_t *nv,
                        size_t *nf) {
  long line = 1;
  *nv = *nf = 0;
  for (const char *p = mx_io_content(buf, end, &line, '#'); p < end;) {
    char k = keyword(p);
    *nv += k == 'v';
    *nf += k == 'f';
    p = mx_io_next_line(p, end, &line);
    p = mx_io_content(p, end, &line, '#');
  }
}

static int read_vertex(obj_file *f, mx_trisoup *s) {
  const char *q = f->p + 1;
  double c[3];
  MX_CHECK(mx_io_numbers(f->path, f->line, &q, '#', 3, c, "vertex", s->nv + 1));
  s->x[s->nv] = c[0];
  s->y[s->nv] = c[1];
  s->z[s->nv] = c[2];
  s->nv++;
  return MX_OK;
}

/* One "a", "a/b", "a//c" or "a/b/c" corner at *p: the 0-based vertex. */
static int read_corner(obj_file *f, const char **p, const mx_trisoup *s,
                       uint32_t *idx) {
  const char *q = *p;
  int64_t v;
  const char *e = mx_io_int(q, &v);
  if (e && *e == '/') /* texture and normal indices are ignored */
    while (!mx_io_delim(e, '#')) e++;
  if (!e || !mx_io_delim(e, '#')) {
    mx_error(f->path, f->line, "face %zu: bad vertex reference '%.*s'",
             f->nfaces + 1, mx_io_toklen(q, '#'), q);
    return MX_EINPUT;
  }
  int64_t i = v > 0 ? v - 1 : (int64_t)s->nv + v; /* 1-based or relative */
  if (v == 0 || i < 0 || (uint64_t)i >= f->nv_total) {
    mx_error(f->path, f->line,
             "face %zu: vertex index %.*s out of range (%zu vertices, "
             "1-based%s)",
             f->nfaces + 1, mx_io_toklen(q, '#'), q,
             v < 0 ? s->nv : f->nv_total,
             v < 0 ? ", relative to the vertices read so far" : "");
    return MX_EINPUT;
  }
  *idx = (uint32_t)i;
  *p = e;
  return MX_OK;
}

static int read_face(obj_file *f, mx_trisoup *s, mx_polysplit *ps) {
  const char *q = mx_io_blank(f->p + 1);
  uint32_t cur;
  size_t k = 0;
  for (; !mx_io_eol(q, '#'); k++, q = mx_io_blank(q)) {
    MX_CHECK(read_corner(f, &q, s, &cur));
    if (cur >= s->nv) mx_polysplit_defer(ps); /* its coordinates come later */
    MX_CHECK(mx_polysplit_corner(ps, cur));
  }
  if (k < 3) {
    mx_error(f->path, f->line, "face %zu has %zu vertices (at least 3 needed)",
             f->nfaces + 1, k);
    return MX_EINPUT;
  }
  f->nfaces++;
  return mx_polysplit_face(ps, s, (mx_face_at){f->nfaces, f->line, -1});
}

static int parse_obj(obj_file *f, mx_trisoup *s) {
  size_t nf;
  count_lines(f->p, f->end, &f->nv_total, &nf);
  if (nf == 0) {
    mx_error(f->path, 0, "no faces ('f' lines)");
    return MX_EINPUT;
  }
  if (f->nv_total > UINT32_MAX) {
    mx_error(f->path, 0, "too many vertices (%zu)", f->nv_total);
    return MX_EINPUT;
  }
  MX_CHECK(mx_trisoup_reserve(s, f->nv_total, nf));
  mx_polysplit ps;
  mx_polysplit_init(&ps, f->path);
  int st = MX_OK;
  for (f->p = mx_io_content(f->p, f->end, &f->line, '#'); f->p < f->end && st == MX_OK;) {
    char k = keyword(f->p);
    if (k == 'v') st = read_vertex(f, s);
    if (k == 'f') st = read_face(f, s, &ps);
    f->p = mx_io_next_line(f->p, f->end, &f->line);
    f->p = mx_io_content(f->p, f->end, &f->line, '#');
  }
  if (st == MX_OK) st = mx_polysplit_finish(&ps, s);
  mx_polysplit_free(&ps);
  return st;
}

int mx_read_obj(const char *path, mx_trisoup *out) {
  memset(out, 0, sizeof *out);
  char *buf;
  size_t len;
  MX_CHECK(mx_io_load(path, &buf, &len));
  obj_file f = {path, buf, buf + len, 1, 0, 0};
  out->nshells = 1;
  int status = parse_obj(&f, out);
  mx_free(buf);
  if (status != MX_OK) mx_trisoup_free(out);
  return status;
}
