/* mixoct: an OFF file read as a 2D mesh (for mx_read_mesh_dim, see
 * read_mesh.h): "OFF" (or a variant whose extra per-vertex data is
 * ignored, as io/read_off.c), the counts, vertices with z = 0, faces of 3
 * or 4 vertices kept whole (io/read_off.c, the surface reader, splits them
 * into triangles) as the mesh's faces, tag 0, in the file's node order. */
#include <stdio.h>
#include <string.h>

#include "base/common.h"
#include "io/mesh_reader.h"
#include "io/off_header.h"
#include "io/text_scan.h"

typedef struct {
  const char *path, *p, *end; /* p: the current content line */
  long line;
} off_rd;

/* The next content line; an error if the file ends first. */
static int off_next(off_rd *f, const char *what, size_t i, size_t n) {
  return mx_off_next(f->path, &f->p, f->end, &f->line, what, i, n);
}

static int off_header(off_rd *f, size_t *nv, size_t *nf) {
  MX_CHECK(mx_off_counts(f->path, &f->p, f->end, &f->line, UINT32_MAX - 1, UINT32_MAX / 4, nv,
                         nf));
  /* counts checked against the bytes left before anything is allocated:
   * "0 0 0\n" at least per vertex, "3 0 1 2\n" per face */
  const size_t left = (size_t)(f->end - f->p);
  if ((uint64_t)*nv * 6 + (uint64_t)*nf * 8 > (uint64_t)left + 16) {
    mx_error(f->path, f->line,
             "%zu vertices and %zu faces announced but the file is too short (truncated file "
             "or wrong counts)",
             *nv, *nf);
    return MX_EINPUT;
  }
  return MX_OK;
}

static int off_vertex(off_rd *f, mx_mesh_data *q, size_t i) {
  double c[3];
  MX_CHECK(mx_io_numbers(f->path, f->line, &f->p, '#', 3, c, "vertex", i));
  if (c[2] != 0.0) {
    mx_error(f->path, f->line,
             "vertex %zu: z = %g: an OFF mesh is read as a 2D mesh, in the plane z = 0 (a 3D "
             "surface is not a mesh `mixoct check` reads)",
             i, c[2]);
    return MX_EINPUT;
  }
  q->xyz[3 * i] = c[0];
  q->xyz[3 * i + 1] = c[1];
  q->xyz[3 * i + 2] = 0.0;
  return MX_OK;
}

static int off_face(off_rd *f, mx_mesh_data *q, size_t c) {
  int64_t k;
  const char *s = mx_io_blank(f->p);
  const char *e = mx_io_int(s, &k);
  if (!e || !mx_io_delim(e, '#')) {
    mx_error(f->path, f->line, "face %zu: expected 'k i0 .. ik-1', found '%.*s'", c,
             mx_io_toklen(s, '#'), s);
    return MX_EINPUT;
  }
  if (k < 3 || k > 4) {
    mx_error(f->path, f->line,
             "face %zu has %lld vertices: a 2D mesh has triangles (3) and quadrilaterals (4)", c,
             (long long)k);
    return MX_EINPUT;
  }
  f->p = e;
  uint32_t *row = q->face_conn + 4 * c;
  row[3] = 0;
  for (int j = 0; j < (int)k; j++)
    MX_CHECK(mx_io_index(f->path, f->line, &f->p, '#', q->nnodes, &row[j], "face", c));
  q->face_nn[c] = (uint8_t)k;
  return MX_OK;
}

static int off_parse(off_rd *f, mx_mesh_data *q) {
  size_t nv = 0, nf = 0;
  MX_CHECK(off_header(f, &nv, &nf));
  q->xyz = mx_alloc((3 * nv + 1) * sizeof *q->xyz);
  q->face_nn = mx_alloc(nf + 1);
  q->face_conn = mx_alloc((4 * nf + 1) * sizeof *q->face_conn);
  q->face_tag = mx_calloc((nf + 1) * sizeof *q->face_tag);
  if (!q->xyz || !q->face_nn || !q->face_conn || !q->face_tag) return MX_ENOMEM;
  q->nnodes = nv;
  for (size_t i = 0; i < nv; i++) {
    MX_CHECK(off_next(f, "vertices", i, nv));
    MX_CHECK(off_vertex(f, q, i));
  }
  for (size_t c = 0; c < nf; c++) {
    MX_CHECK(off_next(f, "faces", c, nf));
    MX_CHECK(off_face(f, q, c));
    q->nfaces = c + 1;
  }
  f->p = mx_io_next_line(f->p, f->end, &f->line);
  f->p = mx_io_content(f->p, f->end, &f->line, '#');
  if (f->p == f->end) return MX_OK;
  mx_error(f->path, f->line,
           "more data than the header declares (%zu vertices, %zu faces): wrong counts?", nv, nf);
  return MX_EINPUT;
}

int mx_rd_off_plane(const char *path, mx_mesh_data *q) {
  memset(q, 0, sizeof *q);
  char *buf;
  size_t len;
  MX_CHECK(mx_io_load(path, &buf, &len));
  off_rd f = {path, buf, buf + len, 1};
  const int st = off_parse(&f, q);
  mx_free(buf);
  if (st != MX_OK) mx_mesh_data_free(q);
  return st;
}

/* Whether the file's first content token (after blanks and '#' comment
 * lines) is an OFF keyword; read from its first bytes only. */
int mx_rd_is_off(const char *path) {
  FILE *fp = fopen(path, "rb");
  if (!fp) return 0; /* the reader names the file */
  char buf[4096];
  const size_t n = fread(buf, 1, sizeof buf - 1, fp);
  fclose(fp);
  buf[n] = 0;
  const char *p = buf, *end = buf + n;
  for (;;) {
    while (p < end && (*p == ' ' || *p == '\t' || *p == '\r' || *p == '\n')) p++;
    if (p < end && *p == '#') {
      const char *nl = memchr(p, '\n', (size_t)(end - p));
      if (!nl) return 0;
      p = nl + 1;
      continue;
    }
    break;
  }
  int k = 0;
  while (p + k < end && p[k] && !strchr(" \t\r\n#", p[k])) k++;
  return mx_off_keyword(p, k);
}
