/* mixoct: 2D meshes read back (see read_qmesh.h). The VTK, VTU, MSH and
 * Medit files go through io/read_mesh.c's readers (one parser per format):
 * a 2D mesh comes back from them as faces with no volume cell and is
 * converted here; OFF, which read_mesh.c does not read, has its own small
 * parser below (faces kept whole: io/read_off.c splits them into triangles). */
#include "io/read_qmesh.h"

#include <stdio.h>
#include <string.h>

#include "base/common.h"
#include "io/text_scan.h"

enum { PAR_MIN = 65536 }; /* fewer items: one thread */

/* ---- from io/read_mesh.c's faces ----------------------------------------- */

/* Whether m is a 2D mesh: faces, no volume cell, every z = 0. */
static int planar_faces(const mx_mesh_data *m) {
  if (m->ncells || !m->nfaces) return 0;
  size_t off = 0;
#pragma omp parallel for schedule(static) reduction(+ : off) if (m->nnodes > PAR_MIN)
  for (size_t i = 0; i < m->nnodes; i++) off += m->xyz[3 * i + 2] != 0.0;
  return off == 0;
}

/* m's faces as the cells of q (m is left as it was). */
static int qmesh_from_faces(const mx_mesh_data *m, mx_qmesh *q) {
  memset(q, 0, sizeof *q);
  const size_t nn = m->nnodes, nc = m->nfaces;
  q->xy = mx_alloc((2 * nn + 1) * sizeof *q->xy);
  q->type = mx_alloc(nc + 1);
  q->conn = mx_alloc((4 * nc + 1) * sizeof *q->conn);
  if (!q->xy || !q->type || !q->conn) {
    mx_qmesh_free(q);
    return MX_ENOMEM;
  }
  q->nnodes = nn;
  q->ncells = nc;
#pragma omp parallel for schedule(static) if (nn > PAR_MIN)
  for (size_t i = 0; i < nn; i++) {
    q->xy[2 * i] = m->xyz[3 * i];
    q->xy[2 * i + 1] = m->xyz[3 * i + 1];
  }
#pragma omp parallel for schedule(static) if (nc > PAR_MIN)
  for (size_t c = 0; c < nc; c++) {
    const int k = m->face_nn[c];
    q->type[c] = k == 4 ? MX_QQUAD : MX_QTRI;
    for (int j = 0; j < 4; j++)
      q->conn[4 * c + (size_t)j] = j < k ? m->face_conn[4 * c + (size_t)j] : UINT32_MAX;
  }
  return MX_OK;
}

/* ---- OFF ------------------------------------------------------------------ */

typedef struct {
  const char *path, *p, *end; /* p: the current content line */
  long line;
} off_rd;

/* "OFF", or a variant whose extra per-vertex data is ignored (COFF, NOFF,
 * CNOFF, STOFF...), as io/read_off.c. */
static int off_keyword(const char *tok, int n) {
  if (n < 3 || memcmp(tok + n - 3, "OFF", 3) != 0) return 0;
  for (int i = 0; i < n - 3; i++)
    if (!strchr("CNST", tok[i])) return 0;
  return 1;
}

/* The next content line; an error if the file ends first. */
static int off_next(off_rd *f, const char *what, size_t i, size_t n) {
  f->p = mx_io_next_line(f->p, f->end, &f->line);
  f->p = mx_io_content(f->p, f->end, &f->line, '#');
  if (f->p < f->end) return MX_OK;
  mx_error(f->path, f->line,
           "unexpected end of file: %zu of %zu %s read (truncated file or wrong counts in "
           "the header)",
           i, n, what);
  return MX_EINPUT;
}

static int off_count(off_rd *f, const char **q, size_t max, size_t *v, const char *name) {
  int64_t x;
  const char *s = mx_io_blank(*q);
  const char *e = mx_io_int(s, &x);
  if (!e || !mx_io_delim(e, '#') || x < 0 || (uint64_t)x > max) {
    mx_error(f->path, f->line, "bad header: expected the counts 'nv nf ne', found '%.*s' for %s",
             mx_io_toklen(s, '#'), s, name);
    return MX_EINPUT;
  }
  *v = (size_t)x;
  *q = e;
  return MX_OK;
}

static int off_header(off_rd *f, size_t *nv, size_t *nf) {
  f->p = mx_io_content(f->p, f->end, &f->line, '#');
  const int n = f->p < f->end ? mx_io_toklen(f->p, '#') : 0;
  if (!off_keyword(f->p, n)) {
    mx_error(f->path, f->line, "bad header: expected 'OFF', found '%.*s'", n, f->p);
    return MX_EINPUT;
  }
  const char *q = mx_io_blank(f->p + n);
  if (mx_io_eol(q, '#')) {
    f->p = mx_io_next_line(q, f->end, &f->line);
    f->p = mx_io_content(f->p, f->end, &f->line, '#');
    if (f->p == f->end) {
      mx_error(f->path, f->line, "bad header: missing counts 'nv nf ne'");
      return MX_EINPUT;
    }
    q = f->p;
  }
  /* counts checked against the bytes left before anything is allocated:
   * "0 0 0\n" at least per vertex, "3 0 1 2\n" per face */
  const size_t left = (size_t)(f->end - f->p);
  MX_CHECK(off_count(f, &q, UINT32_MAX - 1, nv, "nv"));
  MX_CHECK(off_count(f, &q, UINT32_MAX / 4, nf, "nf"));
  if ((uint64_t)*nv * 6 + (uint64_t)*nf * 8 > (uint64_t)left + 16) {
    mx_error(f->path, f->line,
             "%zu vertices and %zu faces announced but the file is too short (truncated file "
             "or wrong counts)",
             *nv, *nf);
    return MX_EINPUT;
  }
  return MX_OK;
}

static int off_vertex(off_rd *f, mx_qmesh *q, size_t i) {
  double c[3];
  MX_CHECK(mx_io_numbers(f->path, f->line, &f->p, '#', 3, c, "vertex", i));
  if (c[2] != 0.0) {
    mx_error(f->path, f->line,
             "vertex %zu: z = %g: an OFF mesh is read as a 2D mesh, in the plane z = 0 (a 3D "
             "surface is not a mesh `mixoct check` reads)",
             i, c[2]);
    return MX_EINPUT;
  }
  q->xy[2 * i] = c[0];
  q->xy[2 * i + 1] = c[1];
  return MX_OK;
}

static int off_face(off_rd *f, mx_qmesh *q, size_t c) {
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
  uint32_t *row = q->conn + 4 * c;
  row[3] = UINT32_MAX;
  for (int j = 0; j < (int)k; j++)
    MX_CHECK(mx_io_index(f->path, f->line, &f->p, '#', q->nnodes, &row[j], "face", c));
  q->type[c] = k == 4 ? MX_QQUAD : MX_QTRI;
  return MX_OK;
}

static int off_parse(off_rd *f, mx_qmesh *q) {
  size_t nv = 0, nf = 0;
  MX_CHECK(off_header(f, &nv, &nf));
  q->xy = mx_alloc((2 * nv + 1) * sizeof *q->xy);
  q->type = mx_alloc(nf + 1);
  q->conn = mx_alloc((4 * nf + 1) * sizeof *q->conn);
  if (!q->xy || !q->type || !q->conn) return MX_ENOMEM;
  q->nnodes = nv;
  for (size_t i = 0; i < nv; i++) {
    MX_CHECK(off_next(f, "vertices", i, nv));
    MX_CHECK(off_vertex(f, q, i));
  }
  for (size_t c = 0; c < nf; c++) {
    MX_CHECK(off_next(f, "faces", c, nf));
    MX_CHECK(off_face(f, q, c));
    q->ncells = c + 1;
  }
  f->p = mx_io_next_line(f->p, f->end, &f->line);
  f->p = mx_io_content(f->p, f->end, &f->line, '#');
  if (f->p == f->end) return MX_OK;
  mx_error(f->path, f->line,
           "more data than the header declares (%zu vertices, %zu faces): wrong counts?", nv, nf);
  return MX_EINPUT;
}

static int read_off_2d(const char *path, mx_qmesh *q) {
  memset(q, 0, sizeof *q);
  char *buf;
  size_t len;
  MX_CHECK(mx_io_load(path, &buf, &len));
  off_rd f = {path, buf, buf + len, 1};
  const int st = off_parse(&f, q);
  mx_free(buf);
  if (st != MX_OK) mx_qmesh_free(q);
  return st;
}

/* Whether the file's first content token (after blanks and '#' comment
 * lines) is an OFF keyword; read from its first bytes only. */
static int is_off(const char *path) {
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
  return off_keyword(p, k);
}

/* ---- entry points ---------------------------------------------------------- */

int mx_read_mesh_dim(const char *path, mx_mesh_data *m, mx_qmesh *q, int *dim) {
  memset(m, 0, sizeof *m);
  memset(q, 0, sizeof *q);
  *dim = 3;
  if (is_off(path)) {
    MX_CHECK(read_off_2d(path, q));
    *dim = 2;
    return MX_OK;
  }
  MX_CHECK(mx_read_mesh_planar(path, m));
  if (!planar_faces(m)) return MX_OK;
  const int st = qmesh_from_faces(m, q);
  mx_mesh_data_free(m);
  if (st == MX_OK) *dim = 2;
  return st;
}

int mx_read_qmesh(const char *path, mx_qmesh *q) {
  mx_mesh_data m;
  int dim = 0;
  MX_CHECK(mx_read_mesh_dim(path, &m, q, &dim));
  if (dim == 2) return MX_OK;
  mx_mesh_data_free(&m);
  mx_error(path, 0, "not a 2D mesh: it has volume cells, or no triangle or quadrilateral in the "
           "plane z = 0");
  return MX_EINPUT;
}
