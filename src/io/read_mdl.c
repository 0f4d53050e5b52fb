/* MDL reader. Sections, in any order, each headed "[Name, TYPE]":
 *   [Name, STRING]                 one line of text (ignored)
 *   [Normals, ARRAY1<VECTOR3D>]    count, then one "nx ny nz" a line (ignored)
 *   [Vertices, ARRAY1<POINT3D>]    count, then one "x y z" a line
 *   [Triangles, ARRAY1<STRING>]    count, then one "a b c na nb nc" a line
 * Indices are 0-based; the normal indices are ignored. Other ARRAY1
 * sections are skipped. Triangles may come before Vertices, so their range
 * is checked at the end. */
#include <stdint.h>
#include <string.h>

#include "base/common.h"
#include "soa/trisoup.h"

#include "io/mdl_sections.h"
#include "io/text_scan.h"
#include "io/read_surface.h"

typedef struct {
  const char *path, *p, *end; /* p: the current content line */
  long line;
  int have_vertices, have_triangles;
  const char *tri_start; /* the Triangles count line, to locate errors */
  long tri_line;
} mdl_file;

/* Moves to the next content line (blank lines skipped). */
static int next_item(mdl_file *f, const char *what, size_t i, size_t n) {
  f->p = mx_io_next_line(f->p, f->end, &f->line);
  f->p = mx_io_content(f->p, f->end, &f->line, 0);
  if (f->p < f->end && *f->p != '[') return MX_OK;
  mx_error(f->path, f->line,
           "unexpected %s: %zu of %zu %s read (truncated file or wrong count)",
           f->p < f->end ? "section header" : "end of file", i, n, what);
  return MX_EINPUT;
}

static size_t guess(const mdl_file *f, size_t n, size_t min_bytes) {
  size_t g = (size_t)(f->end - f->p) / min_bytes + 1;
  return n < g ? n : g;
}

static int read_vertices(mdl_file *f, mx_trisoup *s, size_t n) {
  MX_CHECK(mx_trisoup_reserve(s, guess(f, n, 6), 0));
  for (size_t i = 0; i < n; i++) {
    MX_CHECK(next_item(f, "vertices", i, n));
    double c[3];
    MX_CHECK(mx_io_numbers(f->path, f->line, &f->p, 0, 3, c, "vertex", i));
    MX_CHECK(mx_trisoup_set_vertex(s, i, c));
  }
  return MX_OK;
}

/* Indices are only checked against 2^32 here: the vertices may come later. */
static int read_triangles(mdl_file *f, mx_trisoup *s, size_t n) {
  f->tri_start = f->p;
  f->tri_line = f->line;
  MX_CHECK(mx_trisoup_reserve(s, 0, guess(f, n, 8)));
  for (size_t i = 0; i < n; i++) {
    MX_CHECK(next_item(f, "triangles", i, n));
    if (i >= s->cap_t) MX_CHECK(mx_trisoup_reserve(s, 0, i + 1));
    for (int k = 0; k < 3; k++)
      MX_CHECK(mx_io_index(f->path, f->line, &f->p, 0, UINT32_MAX,
                           &s->tri[3 * i + k], "triangle", i));
    s->shell[i] = 0;
    s->face[i] = (uint32_t)i;
    MX_CHECK(mx_trisoup_note_line(s, i, (uint32_t)i, f->line));
    s->nt = i + 1;
  }
  return MX_OK;
}

static int skip_items(mdl_file *f, size_t n) {
  for (size_t i = 0; i < n; i++) MX_CHECK(next_item(f, "items", i, n));
  return MX_OK;
}

static int read_array(mdl_file *f, const mx_mdl_header *h, mx_trisoup *s) {
  int vertices = mx_mdl_same(h->name, h->nname, "Vertices");
  int triangles = mx_mdl_same(h->name, h->nname, "Triangles");
  if (vertices) MX_CHECK(mx_mdl_once(f->path, f->line, &f->have_vertices, h));
  if (triangles) MX_CHECK(mx_mdl_once(f->path, f->line, &f->have_triangles, h));
  size_t n;
  MX_CHECK(mx_mdl_count(f->path, &f->line, &f->p, f->end, h, UINT32_MAX, &n));
  if (vertices) return read_vertices(f, s, n);
  if (triangles) return read_triangles(f, s, n);
  return skip_items(f, n); /* Normals and anything else */
}

static int read_section(mdl_file *f, mx_trisoup *s) {
  mx_mdl_header h;
  MX_CHECK(mx_mdl_parse_header(f->path, f->line, f->p, f->end, "[Vertices, ARRAY1<POINT3D>]",
                               &h));
  if (mx_mdl_is_array(&h)) return read_array(f, &h, s);
  return mx_mdl_non_array(f->path, &f->line, &f->p, f->end, &h);
}

/* The line of triangle i, found again by walking the section. */
static long triangle_line(const mdl_file *f, size_t i) {
  const char *p = f->tri_start;
  long line = f->tri_line;
  for (size_t k = 0; k <= i; k++) {
    p = mx_io_next_line(p, f->end, &line);
    p = mx_io_content(p, f->end, &line, 0);
  }
  return line;
}

static int check_indices(const mdl_file *f, const mx_trisoup *s) {
  for (size_t i = 0; i < s->nt; i++) {
    const uint32_t *t = s->tri + 3 * i;
    for (int k = 0; k < 3; k++) {
      if (t[k] < s->nv) continue;
      mx_error(f->path, triangle_line(f, i),
               "triangle %zu: vertex index %u out of range (%zu vertices, "
               "0-based)",
               i, t[k], s->nv);
      return MX_EINPUT;
    }
  }
  return MX_OK;
}

static int parse_mdl(mdl_file *f, mx_trisoup *s) {
  for (;;) {
    f->p = mx_io_content(f->p, f->end, &f->line, 0);
    if (f->p == f->end) break;
    MX_CHECK(read_section(f, s));
    f->p = mx_io_next_line(f->p, f->end, &f->line);
  }
  if (!f->have_vertices || !f->have_triangles) {
    mx_error(f->path, 0, "no [%s] section",
             f->have_vertices ? "Triangles, ARRAY1<STRING>"
                              : "Vertices, ARRAY1<POINT3D>");
    return MX_EINPUT;
  }
  if (s->nt == 0) {
    mx_error(f->path, f->tri_line, "the [Triangles] section is empty");
    return MX_EINPUT;
  }
  return check_indices(f, s);
}

int mx_read_mdl(const char *path, mx_trisoup *out) {
  memset(out, 0, sizeof *out);
  char *buf;
  size_t len;
  MX_CHECK(mx_io_load(path, &buf, &len));
  mdl_file f = {path, buf, buf + len, 1, 0, 0, NULL, 0};
  out->nshells = 1;
  int status = parse_mdl(&f, out);
  mx_free(buf);
  if (status != MX_OK) mx_trisoup_free(out);
  return status;
}
