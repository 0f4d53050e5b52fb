/* OFF reader: "OFF" header, counts "nv nf ne" (same line or next), nv lines
 * "x y z", nf lines "k i0 .. ik-1" (0-based; polygons, k > 3, split into
 * triangles in their plane by io/polygon_split.c; trailing values such as
 * colours ignored). '#' starts a comment anywhere. Triangles remember their
 * face (numbered from 0) and its line. */
#include <stdint.h>
#include <string.h>

#include "base/common.h"
#include "soa/trisoup.h"

#include "io/off_header.h"
#include "io/polygon_split.h"
#include "io/text_scan.h"
#include "io/read_surface.h"

typedef struct {
  const char *path, *p, *end; /* p: the current content line */
  long line;
  size_t nv, nf;
} off_file;

/* Moves to the next content line; error if the file ends first. */
static int next_item(off_file *f, const char *what, size_t i, size_t n) {
  return mx_off_next(f->path, &f->p, f->end, &f->line, what, i, n);
}

static int read_header(off_file *f) {
  MX_CHECK(mx_off_counts(f->path, &f->p, f->end, &f->line, UINT32_MAX, SIZE_MAX / 64, &f->nv,
                         &f->nf));
  if (f->nf == 0) {
    mx_error(f->path, f->line, "the header declares no faces");
    return MX_EINPUT;
  }
  return MX_OK;
}

static int read_vertices(off_file *f, mx_trisoup *s) {
  size_t guess = (size_t)(f->end - f->p) / 6 + 1; /* "0 0 0\n" at least */
  MX_CHECK(mx_trisoup_reserve(s, f->nv < guess ? f->nv : guess, 0));
  for (size_t i = 0; i < f->nv; i++) {
    MX_CHECK(next_item(f, "vertices", i, f->nv));
    double c[3];
    MX_CHECK(mx_io_numbers(f->path, f->line, &f->p, '#', 3, c, "vertex", i));
    MX_CHECK(mx_trisoup_set_vertex(s, i, c));
  }
  return MX_OK;
}

/* One face line "k i0 .. ik-1 [ignored]". */
static int read_face(off_file *f, mx_trisoup *s, mx_polysplit *ps, size_t i) {
  int64_t k;
  const char *e = mx_io_int(f->p, &k);
  if (!e || !mx_io_delim(e, '#') || k < 3) {
    mx_error(f->path, f->line,
             "face %zu: expected 'k i0 .. ik-1' with k >= 3, found '%.*s'", i,
             mx_io_toklen(f->p, '#'), f->p);
    return MX_EINPUT;
  }
  f->p = e;
  for (int64_t j = 0; j < k; j++) {
    uint32_t v;
    MX_CHECK(mx_io_index(f->path, f->line, &f->p, '#', f->nv, &v, "face", i));
    MX_CHECK(mx_polysplit_corner(ps, v));
  }
  return mx_polysplit_face(ps, s, (mx_face_at){i, f->line, -1});
}

static int read_faces(off_file *f, mx_trisoup *s) {
  size_t guess = (size_t)(f->end - f->p) / 8 + 1; /* "3 0 1 2\n" at least */
  MX_CHECK(mx_trisoup_reserve(s, 0, f->nf < guess ? f->nf : guess));
  mx_polysplit ps;
  mx_polysplit_init(&ps, f->path);
  int st = MX_OK;
  for (size_t i = 0; i < f->nf && st == MX_OK; i++) {
    st = next_item(f, "faces", i, f->nf);
    if (st == MX_OK) st = read_face(f, s, &ps, i);
  }
  if (st == MX_OK) st = mx_polysplit_finish(&ps, s);
  mx_polysplit_free(&ps);
  return st;
}

static int read_trailer(off_file *f) {
  f->p = mx_io_next_line(f->p, f->end, &f->line);
  f->p = mx_io_content(f->p, f->end, &f->line, '#');
  if (f->p == f->end) return MX_OK;
  mx_error(f->path, f->line,
           "more data than the header declares (%zu vertices, %zu faces): "
           "wrong counts?",
           f->nv, f->nf);
  return MX_EINPUT;
}

static int parse_off(off_file *f, mx_trisoup *s) {
  MX_CHECK(read_header(f));
  MX_CHECK(read_vertices(f, s));
  MX_CHECK(read_faces(f, s));
  return read_trailer(f);
}

int mx_read_off(const char *path, mx_trisoup *out) {
  memset(out, 0, sizeof *out);
  char *buf;
  size_t len;
  MX_CHECK(mx_io_load(path, &buf, &len));
  off_file f = {path, buf, buf + len, 1, 0, 0};
  out->nshells = 1;
  int status = parse_off(&f, out);
  mx_free(buf);
  if (status != MX_OK) mx_trisoup_free(out);
  return status;
}
