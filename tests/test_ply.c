/* Tests of the PLY reader (src/io/read_ply.c). The PLY files are written
 * here, into a temporary directory, by a small writer that lays out the
 * same geometry as ASCII, binary little endian or binary big endian, with
 * any property types, extra properties and extra elements. Every good file
 * must give exactly the soup that mx_read_off gives for an OFF of the same
 * geometry; every bad one must fail with MX_EINPUT, leave the soup empty and
 * print one message naming the file and, for text, the line ("FILE:LINE:"),
 * for binary data, the item and its byte offset. */
#include <dirent.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "check.h"
#include "base/common.h"
#include "file_util.h"
#include "soa/trisoup.h"
#include "io/read_surface.h"
#include "io/demo_surface.h"

typedef int (*reader_fn)(const char *path, mx_trisoup *out);

static char tmpdir[64];
static char captured[16384];

/* ---- files and stderr capture ----------------------------------------- */

static void tpath(char *buf, size_t n, const char *name) {
  snprintf(buf, n, "%s/%s", tmpdir, name);
}

#define write_bytes write_bytes_file

static void capture_begin(void) {
  char path[128];
  tpath(path, sizeof path, "stderr.txt");
  capture_stderr_begin(path);
}

static const char *capture_end(void) {
  char path[128];
  tpath(path, sizeof path, "stderr.txt");
  return capture_stderr_end(path, captured, sizeof captured);
}

#define edit text_edit_line
#define cut text_cut_lines

/* ---- checks ----------------------------------------------------------- */

/* mx_read_ply on path must fail with MX_EINPUT, leave the soup empty, and
 * print one message naming the path, "path:line:" if line > 0, and needle
 * if not NULL. */
static void expect_fail_rd(reader_fn rd, const char *path, long line,
                           const char *needle, const char *label) {
  int before = mx_test_failures;
  mx_trisoup s;
  memset(&s, 0xab, sizeof s); /* the reader must not rely on a zeroed soup */
  capture_begin();
  int rc = rd(path, &s);
  const char *msg = capture_end();
  CHECK(rc == MX_EINPUT);
  CHECK(s.nv == 0 && s.nt == 0 && s.x == NULL && s.tri == NULL);
  CHECK(strstr(msg, path) != NULL);
  CHECK(strstr(msg, "error") != NULL);
  const char *second = strstr(msg, "mixoct:");
  CHECK(second && strstr(second + 1, "mixoct:") == NULL); /* one message */
  if (line > 0) {
    char loc[256];
    snprintf(loc, sizeof loc, "%s:%ld:", path, line);
    CHECK(strstr(msg, loc) != NULL);
  }
  if (needle) CHECK(strstr(msg, needle) != NULL);
  if (rc == MX_OK) mx_trisoup_free(&s);
  printf("%s %-24s %s", mx_test_failures == before ? "ok  " : "FAIL", label,
         msg[0] ? msg : "(no message)\n");
}

static void expect_fail(const char *path, long line, const char *needle,
                        const char *label) {
  expect_fail_rd(mx_read_ply, path, line, needle, label);
}

static void bad_bytes(const char *name, const void *data, size_t len,
                      long line, const char *needle) {
  char path[128];
  tpath(path, sizeof path, name);
  write_bytes(path, data, len);
  expect_fail(path, line, needle, name);
}

static void bad_text(const char *name, const char *text, long line,
                     const char *needle) {
  bad_bytes(name, text, strlen(text), line, needle);
}

static void bad_edit(const char *name, char *text, long line,
                     const char *needle) {
  bad_text(name, text, line, needle);
  free(text);
}

/* Both soups hold exactly the same numbers. */
static int same_soup(const mx_trisoup *a, const mx_trisoup *b) {
  if (a->nv != b->nv || a->nt != b->nt || a->nshells != b->nshells) return 0;
  size_t dv = a->nv * sizeof(double);
  return memcmp(a->x, b->x, dv) == 0 && memcmp(a->y, b->y, dv) == 0 &&
         memcmp(a->z, b->z, dv) == 0 &&
         memcmp(a->tri, b->tri, 3 * a->nt * sizeof(uint32_t)) == 0 &&
         memcmp(a->shell, b->shell, a->nt * sizeof(uint16_t)) == 0;
}

/* ---- geometry --------------------------------------------------------- */

typedef struct {
  size_t nv, nf;
  double (*v)[3];
  int *faces; /* k, i0 .. ik-1, face after face */
  size_t nidx;
} geom;

static void geom_free(geom *g) {
  free(g->v);
  free(g->faces);
  memset(g, 0, sizeof *g);
}

static geom geom_make(size_t nv, size_t nf, const double (*v)[3],
                      const int *faces, size_t nidx) {
  geom g = {nv, nf, malloc((nv + 1) * sizeof *g.v),
            malloc((nidx + 1) * sizeof(int)), nidx};
  if (!g.v || !g.faces) abort();
  if (nv) memcpy(g.v, v, nv * sizeof *v);
  memcpy(g.faces, faces, nidx * sizeof(int));
  return g;
}

/* Exactly representable in float, so every format gives the same numbers. */
static const double TET_V[4][3] = {
    {0.5, -1.25, 2}, {3.5, -1.25, 2}, {0.5, 0.75, 2}, {0.5, -1.25, 4.25}};
static const int TET_F[16] = {3, 0, 2, 1, 3, 0, 1, 3, 3, 0, 3, 2, 3, 1, 2, 3};

/* The cube as quads, vertex x + 2y + 4z, outward. */
static const int CUBE_F[30] = {4, 0, 2, 3, 1, 4, 4, 5, 7, 6, 4, 0, 1, 5, 4,
                               4, 2, 6, 7, 3, 4, 0, 4, 6, 2, 4, 1, 3, 7, 5};

enum { CHAR, UCHAR, SHORT, USHORT, INT, UINT, FLOAT, DOUBLE };
static const char *const TNAME[8] = {"char", "uchar", "short", "ushort",
                                     "int",  "uint",  "float", "double"};
static const char *const TALIAS[8] = {"int8",  "uint8",  "int16",   "uint16",
                                      "int32", "uint32", "float32", "float64"};
static const int TSIZE[8] = {1, 1, 2, 2, 4, 4, 4, 8};
static const int INTS[6] = {CHAR, UCHAR, SHORT, USHORT, INT, UINT};

/* Two values of each type, far apart in their bytes (both ends of the
 * range where it helps to see a byte-swapping mistake). */
static const double LOHI[8][2] = {
    {-100, 100},    {3, 250},         {-30000, 29999},
    {1000, 65000},  {-2000000000, 2000000001},
    {7, 4000000000.0}, {-1.25, 3.5e6}, {-0.1, 1e300}};

/* The cube with x of type xt, y of yt, z of zt. */
static geom cube(int xt, int yt, int zt) {
  double v[8][3];
  for (int i = 0; i < 8; i++) {
    v[i][0] = LOHI[xt][i & 1];
    v[i][1] = LOHI[yt][(i >> 1) & 1];
    v[i][2] = LOHI[zt][(i >> 2) & 1];
  }
  return geom_make(8, 6, (const double(*)[3])v, CUBE_F, 30);
}

/* OFF text of g (malloc'd). */
static char *off_text(const geom *g) {
  size_t cap = 256 + 80 * g->nv + 16 * g->nidx, n = 0;
  char *t = malloc(cap);
  if (!t) abort();
  n += (size_t)snprintf(t + n, cap - n, "OFF\n%zu %zu 0\n", g->nv, g->nf);
  for (size_t i = 0; i < g->nv; i++)
    n += (size_t)snprintf(t + n, cap - n, "%.17g %.17g %.17g\n", g->v[i][0],
                          g->v[i][1], g->v[i][2]);
  for (size_t i = 0; i < g->nidx;) {
    int k = g->faces[i++];
    n += (size_t)snprintf(t + n, cap - n, "%d", k);
    for (int j = 0; j < k; j++)
      n += (size_t)snprintf(t + n, cap - n, " %d", g->faces[i++]);
    n += (size_t)snprintf(t + n, cap - n, "\n");
  }
  return t;
}

/* mx_read_off of g, written to tmpdir/ref.off. */
static int read_off_of(const geom *g, mx_trisoup *s) {
  char path[128], *t = off_text(g);
  tpath(path, sizeof path, "ref.off");
  write_bytes(path, t, strlen(t));
  free(t);
  return mx_read_off(path, s);
}

/* ---- the PLY writer --------------------------------------------------- */

enum { ASCII, LE, BE };
static const char *const FMT[3] = {"ascii", "binary_little_endian",
                                   "binary_big_endian"};
static const char *const FMT_SHORT[3] = {"ascii", "LE", "BE"};

typedef struct {
  int fmt;
  int xt, yt, zt;   /* coordinate types */
  int ct, it;       /* face list: count and index types */
  int extras;       /* extra properties and elements */
  int face_first;   /* the face element before the vertex element */
  int aliases;      /* int8 ... float64 type names */
  int crlf;         /* 1: CRLF header, 2: CRLF everywhere (ASCII) */
  const char *list; /* the face list's name */
} layout;

static layout plain(int fmt) {
  return (layout){fmt, FLOAT, FLOAT, FLOAT, UCHAR, INT, 0, 0, 0, 0,
                  "vertex_indices"};
}

typedef struct {
  unsigned char *b;
  size_t n, cap;
  const layout *L;
  int fresh; /* ASCII: at the start of a line */
} pbuf;

static void pb_raw(pbuf *p, const void *d, size_t n) {
  if (p->n + n + 1 > p->cap) {
    p->cap = 2 * p->cap > p->n + n + 64 ? 2 * p->cap : p->n + n + 64;
    p->b = realloc(p->b, p->cap);
    if (!p->b) abort();
  }
  memcpy(p->b + p->n, d, n);
  p->n += n;
  p->b[p->n] = 0;
}

static void pb_str(pbuf *p, const char *s) { pb_raw(p, s, strlen(s)); }

/* One header line. */
static void pb_head(pbuf *p, const char *fmt, ...) {
  char line[256];
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(line, sizeof line, fmt, ap);
  va_end(ap);
  pb_str(p, line);
  pb_str(p, p->L->crlf ? "\r\n" : "\n");
}

static const char *tn(const pbuf *p, int t) {
  return p->L->aliases ? TALIAS[t] : TNAME[t];
}

/* One value of the given type (converted, as a writer would). */
static void pb_val(pbuf *p, int type, double v) {
  if (p->L->fmt == ASCII) {
    char t[64];
    if (type < FLOAT)
      snprintf(t, sizeof t, "%s%lld", p->fresh ? "" : " ", (long long)v);
    else
      snprintf(t, sizeof t, "%s%.17g", p->fresh ? "" : " ", v);
    pb_str(p, t);
    p->fresh = 0;
    return;
  }
  uint64_t u;
  if (type == FLOAT) {
    float f = (float)v;
    uint32_t w;
    memcpy(&w, &f, 4);
    u = w;
  } else if (type == DOUBLE) {
    memcpy(&u, &v, 8);
  } else {
    u = (uint64_t)(int64_t)v;
  }
  unsigned char b[8];
  int size = TSIZE[type];
  for (int i = 0; i < size; i++)
    b[p->L->fmt == LE ? i : size - 1 - i] = (unsigned char)(u >> (8 * i));
  pb_raw(p, b, (size_t)size);
}

static void pb_eol(pbuf *p) {
  if (p->L->fmt == ASCII) pb_str(p, p->L->crlf == 2 ? "\r\n" : "\n");
  p->fresh = 1;
}

static void head_vertex(pbuf *p, const geom *g) {
  const layout *L = p->L;
  pb_head(p, "element vertex %zu", g->nv);
  if (L->extras) pb_head(p, "property %s red", tn(p, UCHAR));
  pb_head(p, "property %s x", tn(p, L->xt));
  if (L->extras) pb_head(p, "property %s nx", tn(p, DOUBLE));
  pb_head(p, "property %s y", tn(p, L->yt));
  if (L->extras) pb_head(p, "property list %s %s uv", tn(p, UCHAR), tn(p, FLOAT));
  pb_head(p, "property %s z", tn(p, L->zt));
  if (L->extras) {
    pb_head(p, "property %s s", tn(p, SHORT));
    pb_head(p, "property %s confidence", tn(p, FLOAT));
  }
}

static void head_face(pbuf *p, const geom *g) {
  const layout *L = p->L;
  pb_head(p, "element face %zu", g->nf);
  if (L->extras) pb_head(p, "property %s flags", tn(p, INT));
  pb_head(p, "property list %s %s %s", tn(p, L->ct), tn(p, L->it), L->list);
  if (L->extras) {
    pb_head(p, "property list %s %s texcoord", tn(p, USHORT), tn(p, DOUBLE));
    pb_head(p, "property %s id", tn(p, UCHAR));
  }
}

static void data_vertex(pbuf *p, const geom *g) {
  const layout *L = p->L;
  for (size_t i = 0; i < g->nv; i++) {
    if (L->extras) pb_val(p, UCHAR, (double)(i * 10 % 256));
    pb_val(p, L->xt, g->v[i][0]);
    if (L->extras) pb_val(p, DOUBLE, -(double)i * 1e10 - 0.3);
    pb_val(p, L->yt, g->v[i][1]);
    if (L->extras) {
      pb_val(p, UCHAR, (double)(i % 3));
      for (size_t j = 0; j < i % 3; j++) pb_val(p, FLOAT, 0.25 * (double)j);
    }
    pb_val(p, L->zt, g->v[i][2]);
    if (L->extras) {
      pb_val(p, SHORT, -300.0 * (double)i);
      pb_val(p, FLOAT, 0.75);
    }
    pb_eol(p);
  }
}

static void data_face(pbuf *p, const geom *g) {
  const layout *L = p->L;
  const int *q = g->faces;
  for (size_t f = 0; f < g->nf; f++) {
    if (L->extras) pb_val(p, INT, -(double)f);
    int k = *q++;
    pb_val(p, L->ct, k);
    for (int j = 0; j < k; j++) pb_val(p, L->it, *q++);
    if (L->extras) {
      pb_val(p, USHORT, (double)(f % 4));
      for (size_t j = 0; j < f % 4; j++) pb_val(p, DOUBLE, 1.5e-5 * (double)j);
      pb_val(p, UCHAR, (double)f);
    }
    pb_eol(p);
  }
}

/* g laid out as L; the caller frees .b. */
static pbuf make_ply(const layout *L, const geom *g) {
  pbuf p = {NULL, 0, 0, L, 1};
  pb_head(&p, "ply");
  pb_head(&p, "format %s 1.0", FMT[L->fmt]);
  pb_head(&p, "comment written by test_ply");
  if (L->extras) {
    pb_head(&p, "obj_info an extra element before the vertices");
    pb_head(&p, "element material 2");
    pb_head(&p, "property %s ambient_red", tn(&p, UCHAR));
    pb_head(&p, "property list %s %s ids", tn(&p, UINT), tn(&p, INT));
    pb_head(&p, "property %s power", tn(&p, FLOAT));
  }
  if (L->face_first) head_face(&p, g);
  head_vertex(&p, g);
  if (!L->face_first) head_face(&p, g);
  if (L->extras) {
    pb_head(&p, "element edge 3");
    pb_head(&p, "property %s vertex1", tn(&p, INT));
    pb_head(&p, "property %s vertex2", tn(&p, INT));
    pb_head(&p, "property %s red", tn(&p, UCHAR));
  }
  pb_head(&p, "end_header");
  p.fresh = 1;
  if (L->extras) {
    const double ids[3] = {1, -2, 3};
    pb_val(&p, UCHAR, 7);
    pb_val(&p, UINT, 3);
    for (int j = 0; j < 3; j++) pb_val(&p, INT, ids[j]);
    pb_val(&p, FLOAT, 0.5);
    pb_eol(&p);
    pb_val(&p, UCHAR, 255);
    pb_val(&p, UINT, 0);
    pb_val(&p, FLOAT, 1.5);
    pb_eol(&p);
  }
  if (L->face_first) data_face(&p, g);
  data_vertex(&p, g);
  if (!L->face_first) data_face(&p, g);
  if (L->extras)
    for (int e = 0; e < 3; e++) {
      pb_val(&p, INT, 0);
      pb_val(&p, INT, 1);
      pb_val(&p, UCHAR, 9);
      pb_eol(&p);
    }
  return p;
}

/* Writes g as L to tmpdir/name; returns the header length in bytes. */
static size_t write_ply(const char *name, const layout *L, const geom *g,
                        char *path, size_t cap) {
  pbuf p = make_ply(L, g);
  tpath(path, cap, name);
  write_bytes(path, p.b, p.n);
  const char *h = strstr((const char *)p.b, "end_header");
  size_t header = h ? (size_t)(h - (const char *)p.b) + 10 + (L->crlf ? 2 : 1)
                    : 0;
  free(p.b);
  return header;
}

static void describe(const layout *L, char *buf, size_t n) {
  snprintf(buf, n, "%s x=%s y=%s z=%s list %s %s%s%s%s%s%s", FMT_SHORT[L->fmt],
           TNAME[L->xt], TNAME[L->yt], TNAME[L->zt], TNAME[L->ct],
           TNAME[L->it], L->extras ? ", extras" : "",
           L->face_first ? ", faces first" : "",
           L->aliases ? ", aliases" : "", L->crlf ? ", CRLF" : "",
           strcmp(L->list, "vertex_indices") ? ", vertex_index" : "");
}

/* g written as L and read back must equal the OFF reading of g. */
static void expect_same(const layout *L, const geom *g, const char *name) {
  int before = mx_test_failures;
  char path[128], what[256];
  write_ply(name, L, g, path, sizeof path);
  mx_trisoup ref, s;
  CHECK(read_off_of(g, &ref) == MX_OK);
  int rc = mx_read_ply(path, &s);
  CHECK(rc == MX_OK);
  if (rc == MX_OK) {
    CHECK(same_soup(&s, &ref));
    CHECK(s.nshells == 1 && s.nt > 0 && s.shell[0] == 0 &&
          s.shell[s.nt - 1] == 0);
    mx_trisoup_free(&s);
  }
  mx_trisoup_free(&ref);
  describe(L, what, sizeof what);
  printf("%s %-16s %s\n", mx_test_failures == before ? "ok  " : "FAIL", name,
         what);
}

/* ---- good files ------------------------------------------------------- */

static void test_formats(void) {
  printf("-- tetrahedron and cube in the three formats\n");
  geom tet = geom_make(4, 4, TET_V, TET_F, 16);
  geom cb = cube(FLOAT, FLOAT, FLOAT);
  for (int fmt = 0; fmt < 3; fmt++) {
    layout L = plain(fmt);
    char name[64];
    snprintf(name, sizeof name, "tet_%s.ply", FMT_SHORT[fmt]);
    expect_same(&L, &tet, name);
    snprintf(name, sizeof name, "cube_%s.ply", FMT_SHORT[fmt]);
    expect_same(&L, &cb, name);
  }
  /* the tetrahedron is closed, 4 triangles */
  char path[128];
  layout L = plain(BE);
  write_ply("tet_check.ply", &L, &tet, path, sizeof path);
  mx_trisoup s;
  CHECK(mx_read_ply(path, &s) == MX_OK);
  size_t open = 99;
  CHECK(s.nv == 4 && s.nt == 4);
  CHECK(mx_trisoup_check(&s, path, &open) == MX_OK && open == 0);
  mx_trisoup_free(&s);
  geom_free(&tet);
  geom_free(&cb);
}

/* Every coordinate type, list count and index type, both names of the
 * types, extra properties and elements, faces first, CRLF. */
static void test_types(void) {
  printf("-- property types, extras, element order\n");
  for (int fmt = 0; fmt < 3; fmt++)
    for (int t = 0; t < 8; t++) {
      layout L = {fmt,
                  t,
                  (t + 3) % 8,
                  (t + 6) % 8,
                  INTS[t % 6],
                  INTS[(t + 3) % 6],
                  t & 1,
                  (t >> 1) & 1,
                  (t >> 2) & 1,
                  t == 3 ? (fmt == ASCII ? 2 : 1) : 0,
                  t == 5 ? "vertex_index" : "vertex_indices"};
      geom g = cube(L.xt, L.yt, L.zt);
      char name[64];
      snprintf(name, sizeof name, "types_%s_%d.ply", FMT_SHORT[fmt], t);
      expect_same(&L, &g, name);
      geom_free(&g);
    }
  /* all extras with every format and both element orders */
  for (int fmt = 0; fmt < 3; fmt++)
    for (int ff = 0; ff < 2; ff++) {
      layout L = plain(fmt);
      L.extras = 1;
      L.face_first = ff;
      L.xt = DOUBLE;
      L.zt = SHORT;
      L.it = UINT;
      geom g = cube(DOUBLE, FLOAT, SHORT);
      char name[64];
      snprintf(name, sizeof name, "extras_%s_%d.ply", FMT_SHORT[fmt], ff);
      expect_same(&L, &g, name);
      geom_free(&g);
    }
}

static void test_polygons(void) {
  printf("-- polygons\n");
  static const double v[5][3] = {
      {0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0.5, 0.5, 1}};
  static const int faces[11] = {4, 0, 1, 2, 3, 5, 0, 1, 2, 3, 4};
  /* the square as a fan, the pentagon (not planar) by ear clipping in its
   * projection on z = 0 (io/polygon_split.c) */
  static const uint32_t want[15] = {0, 1, 2, 0, 2, 3, 2, 3,
                                    4, 4, 0, 1, 4, 1, 2};
  static const uint32_t face_of[5] = {0, 0, 1, 1, 1};
  geom g = geom_make(5, 2, v, faces, 11);
  for (int fmt = 0; fmt < 3; fmt++) {
    layout L = plain(fmt);
    char path[128], name[64];
    snprintf(name, sizeof name, "polygons_%s.ply", FMT_SHORT[fmt]);
    write_ply(name, &L, &g, path, sizeof path);
    mx_trisoup s;
    CHECK(mx_read_ply(path, &s) == MX_OK);
    CHECK(s.nv == 5 && s.nt == 5 && memcmp(s.tri, want, sizeof want) == 0);
    CHECK(memcmp(s.face, face_of, sizeof face_of) == 0);
    mx_trisoup_free(&s);
    printf("ok   %-16s quad and pentagon split into 5 triangles\n", name);
  }
  geom_free(&g);
}

/* Layout details of text files: comments anywhere in the header, blank
 * lines and spaces in the data, trailing blank lines; binary data followed
 * by a newline. */
static void test_text_details(void) {
  printf("-- text details\n");
  const char *t =
      "ply\n"
      "format ascii 1.0\n"
      "comment first\n"
      "element vertex 4\n"
      "comment between\n"
      "property float x\n"
      "property float y\n"
      "property float z\n"
      "obj_info in the middle\n"
      "element face 4\n"
      "property list uchar int vertex_indices\n"
      "end_header   \n"
      "  0.5 -1.25 2\n"
      "\n"
      "3.5\t-1.25 2  \n"
      "0.5 0.75 2\n"
      "0.5 -1.25 4.25\n"
      "3 0 2 1\n"
      "3 0 1 3\n"
      "3 0 3 2\n"
      "3 1 2 3\n"
      "\n  \n";
  geom tet = geom_make(4, 4, TET_V, TET_F, 16);
  mx_trisoup ref, s;
  CHECK(read_off_of(&tet, &ref) == MX_OK);
  char path[128];
  tpath(path, sizeof path, "details.ply");
  write_bytes(path, t, strlen(t));
  CHECK(mx_read_ply(path, &s) == MX_OK && same_soup(&s, &ref));
  mx_trisoup_free(&s);
  printf("ok   details.ply      comments, blanks, trailing blank lines\n");

  /* no newline after the last face */
  tpath(path, sizeof path, "nonewline.ply");
  write_bytes(path, t, strlen(t) - 5);
  CHECK(mx_read_ply(path, &s) == MX_OK && same_soup(&s, &ref));
  mx_trisoup_free(&s);
  printf("ok   nonewline.ply    no newline at the end\n");

  /* binary followed by a newline */
  layout L = plain(LE);
  pbuf p = make_ply(&L, &tet);
  pb_str(&p, "\n");
  tpath(path, sizeof path, "binnl.ply");
  write_bytes(path, p.b, p.n);
  CHECK(mx_read_ply(path, &s) == MX_OK && same_soup(&s, &ref));
  mx_trisoup_free(&s);
  printf("ok   binnl.ply        binary data followed by a newline\n");

  /* through the extension dispatch, case-insensitive */
  tpath(path, sizeof path, "TET.PLY");
  write_bytes(path, p.b, p.n - 1);
  CHECK(mx_read_surface(path, &s) == MX_OK && same_soup(&s, &ref));
  mx_trisoup_free(&s);
  printf("ok   TET.PLY          through mx_read_surface\n");
  free(p.b);
  mx_trisoup_free(&ref);
  geom_free(&tet);
}

/* ---- bad text files --------------------------------------------------- */

static const char *PLY_TET =
    "ply\n"                                    /* 1 */
    "format ascii 1.0\n"                       /* 2 */
    "comment made by hand\n"                   /* 3 */
    "element vertex 4\n"                       /* 4 */
    "property float x\n"                       /* 5 */
    "property float y\n"                       /* 6 */
    "property float z\n"                       /* 7 */
    "element face 4\n"                         /* 8 */
    "property list uchar int vertex_indices\n" /* 9 */
    "end_header\n"                             /* 10 */
    "0.5 -1.25 2\n"                            /* 11 */
    "3.5 -1.25 2\n"                            /* 12 */
    "0.5 0.75 2\n"                             /* 13 */
    "0.5 -1.25 4.25\n"                         /* 14 */
    "3 0 2 1\n"                                /* 15 */
    "3 0 1 3\n"                                /* 16 */
    "3 0 3 2\n"                                /* 17 */
    "3 1 2 3\n";                               /* 18 */

static void test_bad_header(void) {
  printf("-- bad headers\n");
  char path[128];
  tpath(path, sizeof path, "tet_hand.ply");
  write_bytes(path, PLY_TET, strlen(PLY_TET));
  mx_trisoup s;
  CHECK(mx_read_ply(path, &s) == MX_OK && s.nv == 4 && s.nt == 4);
  mx_trisoup_free(&s);

  tpath(path, sizeof path, "missing.ply");
  expect_fail(path, 0, "cannot open", "missing.ply");
  tpath(path, sizeof path, "dir.ply");
  mkdir(path, 0700);
  expect_fail(path, 0, "directory", "dir.ply");
  rmdir(path);
  bad_text("empty.ply", "", 0, "empty");
  bad_text("off.ply", "OFF\n4 4 0\n", 1, "not a PLY file");
  bad_text("justply.ply", "ply", 2, "no 'end_header'");
  bad_edit("magic.ply", edit(PLY_TET, 1, "plx"), 1, "not a PLY file");
  bad_edit("magic2.ply", edit(PLY_TET, 1, "ply ply"), 1, "not a PLY file");
  bad_edit("version.ply", edit(PLY_TET, 2, "format ascii 2.0"), 2,
           "version '2.0'");
  bad_edit("format.ply", edit(PLY_TET, 2, "format binary_middle_endian 1.0"),
           2, "bad format line");
  bad_edit("format2.ply", edit(PLY_TET, 2, "format ascii"), 2,
           "bad format line");
  bad_edit("noformat.ply", cut(PLY_TET, 2, 2), 9, "no 'format' line");
  bad_edit("twoformats.ply", edit(PLY_TET, 3, "format ascii 1.0"), 3,
           "second 'format'");
  bad_edit("keyword.ply", edit(PLY_TET, 3, "remark by hand"), 3,
           "unknown keyword 'remark'");
  bad_edit("type.ply", edit(PLY_TET, 6, "property float128 y"), 6,
           "unknown property type 'float128'");
  bad_edit("type2.ply", edit(PLY_TET, 9, "property list uchar integer "
                                         "vertex_indices"),
           9, "unknown property type 'integer'");
  bad_edit("proptokens.ply", edit(PLY_TET, 5, "property float"), 5,
           "bad property line");
  bad_edit("listtokens.ply", edit(PLY_TET, 9, "property list uchar int"), 9,
           "bad property line");
  bad_edit("elemtokens.ply", edit(PLY_TET, 4, "element vertex"), 4,
           "bad element line");
  bad_edit("countneg.ply", edit(PLY_TET, 4, "element vertex -4"), 4,
           "bad count '-4'");
  bad_edit("countword.ply", edit(PLY_TET, 8, "element face four"), 8,
           "bad count 'four'");
  bad_edit("before.ply", edit(PLY_TET, 4, "property float w\nelement vertex 4"),
           4, "before any 'element'");
  bad_edit("noend.ply", cut(PLY_TET, 10, 18), 10, "no 'end_header'");
  bad_edit("endtext.ply", edit(PLY_TET, 10, "end_header now"), 10,
           "after 'end_header'");
  bad_edit("floatcount.ply",
           edit(PLY_TET, 9, "property list float int vertex_indices"), 9,
           "count of type float");
  bad_edit("floatindex.ply",
           edit(PLY_TET, 9, "property list uchar double vertex_indices"), 9,
           "integer type");
  bad_edit("scalarlist.ply", edit(PLY_TET, 9, "property int vertex_indices"),
           9, "not a list");
  bad_edit("listx.ply", edit(PLY_TET, 5, "property list uchar float x"), 5,
           "'x' is a list");
  bad_edit("twox.ply", edit(PLY_TET, 6, "property float x"), 6,
           "second vertex property 'x'");
  bad_edit("noz.ply", cut(PLY_TET, 7, 7), 4, "no 'z' property");
  bad_edit("noy.ply", edit(PLY_TET, 6, "property float w"), 4,
           "no 'y' property");
  bad_edit("nolist.ply",
           edit(PLY_TET, 9, "property list uchar int indices"), 8,
           "no 'vertex_indices'");
  bad_edit("novertex.ply", edit(PLY_TET, 4, "element point 4"), 10,
           "no 'vertex' element");
  char *t = cut(PLY_TET, 15, 18);
  bad_edit("noface.ply", cut(t, 8, 9), 8, "no 'face' element");
  free(t);
  bad_edit("twofaces.ply",
           edit(PLY_TET, 10, "element face 0\nproperty list uchar int "
                             "vertex_indices\nend_header"),
           10, "second 'face' element (the first is on line 8)");
  bad_edit("zerofaces.ply", edit(PLY_TET, 8, "element face 0"), 8,
           "declares no faces");
  bad_edit("manyvertices.ply", edit(PLY_TET, 4, "element vertex 4294967296"),
           4, "4294967296 'vertex' items");
}

/* Counts that the file cannot hold are refused at once, before anything
 * is allocated: 10^12 vertices in a file of 200 bytes. */
static void test_huge_counts(void) {
  printf("-- huge counts\n");
  double t0 = mx_wtime();
  bad_edit("hugev.ply", edit(PLY_TET, 4, "element vertex 1000000000000"), 4,
           "1000000000000 'vertex' items");
  bad_edit("hugef.ply", edit(PLY_TET, 8, "element face 1000000000000"), 8,
           "1000000000000 'face' items");
  bad_edit("hugeother.ply",
           edit(PLY_TET, 10, "element junk 1000000000000\nproperty uchar "
                             "a\nend_header"),
           10, "'junk' items");
  bad_edit("overflow.ply",
           edit(PLY_TET, 10, "element junk 99999999999999999999999\nproperty "
                             "double a\nend_header"),
           10, "'junk' items");
  /* the same in binary: 12 bytes a vertex (three floats) */
  const char *bin =
      "ply\nformat binary_little_endian 1.0\nelement vertex 3000000000\n"
      "property float x\nproperty float y\nproperty float z\n"
      "element face 1\nproperty list uchar int vertex_indices\nend_header\n"
      "0123456789abcdef";
  bad_text("hugebin.ply", bin, 3, "at least 12 bytes each in binary");
  double dt = mx_wtime() - t0;
  CHECK(dt < 1.0);
  printf("huge counts refused in %.2f ms\n", 1e3 * dt);
  /* an element without properties takes no room, whatever its count */
  char *t = edit(PLY_TET, 10, "element nothing 1000000000000\nend_header");
  char path[128];
  tpath(path, sizeof path, "noprops.ply");
  write_bytes(path, t, strlen(t));
  free(t);
  mx_trisoup s;
  t0 = mx_wtime();
  CHECK(mx_read_ply(path, &s) == MX_OK && s.nt == 4);
  CHECK(mx_wtime() - t0 < 1.0);
  mx_trisoup_free(&s);
}

static void test_bad_text_data(void) {
  printf("-- bad ASCII data\n");
  bad_edit("trunc_f.ply", cut(PLY_TET, 18, 18), 18, "3 of 4 'face' items");
  /* cut after the first vertex, padded to pass the size check */
  char *c = cut(PLY_TET, 12, 18);
  bad_edit("trunc_v.ply",
           edit(c, 11, "0.5 -1.25 2                                      "),
           12, "1 of 4 'vertex' items");
  free(c);
  bad_edit("shortface.ply", edit(PLY_TET, 18, "3 1 2"), 18,
           "face 3: missing vertex index");
  bad_edit("index.ply", edit(PLY_TET, 17, "3 0 3 4"), 17,
           "vertex index 4 out of range (4 vertices");
  bad_edit("negative.ply", edit(PLY_TET, 16, "3 0 -1 1"), 16,
           "out of range (negative)");
  bad_edit("badindex.ply", edit(PLY_TET, 17, "3 0 1.5 3"), 17,
           "bad vertex index '1.5'");
  bad_edit("k2.ply", edit(PLY_TET, 16, "2 0 1 3"), 16,
           "face 1 has 2 vertices");
  bad_edit("k0.ply", edit(PLY_TET, 16, "0"), 16, "face 1 has 0 vertices");
  bad_edit("badlength.ply", edit(PLY_TET, 15, "x 0 2 1"), 15,
           "bad length 'x'");
  bad_edit("neglength.ply", edit(PLY_TET, 15, "-3 0 2 1"), 15,
           "bad length '-3'");
  bad_edit("nan.ply", edit(PLY_TET, 12, "nan -1.25 2"), 12,
           "vertex 1: 'nan' is not a finite number");
  bad_edit("inf.ply", edit(PLY_TET, 13, "0.5 -inf 2"), 13,
           "not a finite number");
  bad_edit("huge.ply", edit(PLY_TET, 14, "0.5 -1.25 1e999"), 14,
           "'1e999' is not a finite number");
  bad_edit("notnum.ply", edit(PLY_TET, 11, "0.5x -1.25 2"), 11,
           "'0.5x' is not a number");
  bad_edit("twocoord.ply", edit(PLY_TET, 11, "0.5 -1.25"), 11,
           "line ends before property 'z'");
  bad_edit("extra.ply", edit(PLY_TET, 12, "3.5 -1.25 2 7"), 12,
           "more values than the header declares ('7')");
  bad_edit("extraface.ply", edit(PLY_TET, 15, "3 0 2 1 255"), 15,
           "more values");
  char *more = malloc(strlen(PLY_TET) + 16);
  if (!more) abort();
  sprintf(more, "%s\n3 0 1 2\n", PLY_TET);
  bad_text("more.ply", more, 20, "more data than the header declares");
  free(more);
  /* a skipped list with a bad value or too few values */
  char *t = edit(PLY_TET, 9, "property list uchar int vertex_indices\n"
                             "property list uchar float uv");
  char *t2 = edit(t, 16, "3 0 2 1 2 0.5 zz");
  bad_edit("skiplist.ply", t2, 16, "face 0: 'zz' is not a number");
  t2 = edit(t, 16, "3 0 2 1 2 0.5");
  bad_edit("skipshort.ply", t2, 16, "line ends before property 'uv'");
  free(t);
}

/* ---- bad binary files ------------------------------------------------- */

static void put32(unsigned char *b, uint32_t v, int big) {
  for (int i = 0; i < 4; i++)
    b[big ? 3 - i : i] = (unsigned char)(v >> (8 * i));
}

static void test_bad_binary(void) {
  printf("-- bad binary data\n");
  geom tet = geom_make(4, 4, TET_V, TET_F, 16);
  for (int fmt = LE; fmt <= BE; fmt++) {
    int big = fmt == BE;
    layout L = plain(fmt);
    pbuf p = make_ply(&L, &tet);
    size_t h = (size_t)(strstr((char *)p.b, "end_header") - (char *)p.b) + 11;
    size_t face0 = h + 48; /* 4 vertices of 12 bytes; faces of 13 bytes */
    unsigned char *b = malloc(p.n + 16);
    if (!b) abort();
    char name[64], needle[128];
#define NAME(s) (snprintf(name, sizeof name, "%s_%s.ply", s, FMT_SHORT[fmt]), name)
#define RESET() memcpy(b, p.b, p.n)

    RESET();
    snprintf(needle, sizeof needle, "face 3 (byte offset %zu): the data ends",
             face0 + 39);
    bad_bytes(NAME("trunc"), b, p.n - 2, 0, needle);
    bad_bytes(NAME("trunc1"), b, p.n - 12, 0, "face 3");
    bad_bytes(NAME("trunc_header"), b, h - 5, 10, "no 'end_header'");
    bad_bytes(NAME("nodata"), b, h, 4, "only 0 bytes of data");
    put32(b + face0 + 13 + 1 + 8, 4, big);
    snprintf(needle, sizeof needle,
             "face 1 (byte offset %zu): vertex index 4 out of range (4 "
             "vertices",
             face0 + 13);
    bad_bytes(NAME("index"), b, p.n, 0, needle);
    put32(b + face0 + 13 + 1 + 8, (uint32_t)-1, big);
    bad_bytes(NAME("negative"), b, p.n, 0, "vertex index -1 out of range "
                                           "(negative)");
    RESET();
    b[face0 + 26] = 2;
    bad_bytes(NAME("k2"), b, p.n, 0, "face 2 (byte offset");
    RESET();
    float nan = NAN;
    uint32_t w;
    memcpy(&w, &nan, 4);
    put32(b + h + 12 * 2 + 4, w, big);
    snprintf(needle, sizeof needle,
             "vertex 2 (byte offset %zu): coordinate y is not a finite",
             h + 24);
    bad_bytes(NAME("nan"), b, p.n, 0, needle);
    float inf = -INFINITY;
    memcpy(&w, &inf, 4);
    RESET();
    put32(b + h + 12 * 3 + 8, w, big);
    bad_bytes(NAME("inf"), b, p.n, 0, "coordinate z is not a finite");
    RESET();
    memcpy(b + p.n, "xyz", 3);
    snprintf(needle, sizeof needle, "3 bytes after the last element (byte "
             "offset %zu)", p.n);
    bad_bytes(NAME("more"), b, p.n + 3, 0, needle);
    /* the other byte order: indices come out far too large */
    const char *from = big ? "big" : "little", *to = big ? "little" : "big";
    size_t at = (size_t)(strstr((char *)p.b, from) - (char *)p.b);
    memcpy(b, p.b, at);
    memcpy(b + at, to, strlen(to));
    size_t rest = p.n - at - strlen(from);
    memcpy(b + at + strlen(to), p.b + at + strlen(from), rest);
    bad_bytes(NAME("order"), b, at + strlen(to) + rest, 0, "out of range");
    free(b);
    free(p.b);
  }

  /* faces before vertices, data cut inside the last vertex */
  layout L = plain(LE);
  L.face_first = 1;
  pbuf p = make_ply(&L, &tet);
  bad_bytes("trunc_vertex_LE.ply", p.b, p.n - 1, 0,
            "vertex 3 (byte offset");
  free(p.b);

  /* skipped lists: negative and huge lengths */
  const char *head =
      "ply\nformat binary_big_endian 1.0\nelement junk 1\n"
      "property list int8 float a\nelement vertex 3\nproperty float x\n"
      "property float y\nproperty float z\nelement face 1\n"
      "property list uint8 uint32 vertex_indices\nend_header\n";
  unsigned char b[512];
  size_t h = strlen(head);
  memcpy(b, head, h);
  memset(b + h, 0, 200);
  b[h] = 0xff; /* -1 */
  char needle[128];
  snprintf(needle, sizeof needle,
           "junk 0 (byte offset %zu): list 'a' has a negative length (-1)", h);
  bad_bytes("neglist.ply", b, h + 1 + 36 + 13, 0, needle);
  char *u = strstr((char *)b, "int8");
  memcpy(u, "uint", 4);
  put32(b + h, 0xffffffffu, 1);
  bad_bytes("hugelist.ply", b, h + 4 + 36 + 13, 0, "junk 0 (byte offset");
  geom_free(&tet);
#undef NAME
#undef RESET
}

/* ---- speed ------------------------------------------------------------ */

static double file_mb(const char *path) {
  struct stat st;
  return stat(path, &st) == 0 ? (double)st.st_size / 1e6 : 0;
}

static void speed_one(const layout *L, const mx_trisoup *demo,
                      const char *name) {
  double (*v)[3] = malloc(demo->nv * sizeof *v);
  int *f = malloc(4 * demo->nt * sizeof(int));
  if (!v || !f) abort();
  for (size_t i = 0; i < demo->nv; i++) {
    v[i][0] = demo->x[i];
    v[i][1] = demo->y[i];
    v[i][2] = demo->z[i];
  }
  for (size_t t = 0; t < demo->nt; t++) {
    f[4 * t] = 3;
    for (int k = 0; k < 3; k++) f[4 * t + 1 + k] = (int)demo->tri[3 * t + k];
  }
  geom g = {demo->nv, demo->nt, v, f, 4 * demo->nt};
  char path[128];
  write_ply(name, L, &g, path, sizeof path);
  geom_free(&g);
  mx_trisoup s;
  double t0 = mx_wtime();
  int rc = mx_read_ply(path, &s);
  double dt = mx_wtime() - t0;
  CHECK(rc == MX_OK);
  if (rc != MX_OK) return;
  CHECK(s.nv == demo->nv && s.nt == demo->nt);
  CHECK(memcmp(s.x, demo->x, demo->nv * sizeof(double)) == 0);
  CHECK(memcmp(s.y, demo->y, demo->nv * sizeof(double)) == 0);
  CHECK(memcmp(s.z, demo->z, demo->nv * sizeof(double)) == 0);
  CHECK(memcmp(s.tri, demo->tri, 3 * demo->nt * sizeof(uint32_t)) == 0);
  printf("speed: %-12s %8zu triangles, %6.1f MB in %7.1f ms: %6.1f MB/s, "
         "%5.2f M triangles/s\n",
         name, s.nt, file_mb(path), 1e3 * dt, file_mb(path) / dt,
         1e-6 * (double)s.nt / dt);
  mx_trisoup_free(&s);
  unlink(path);
}

static void test_speed(void) {
  printf("-- reading speed\n");
  mx_trisoup demo;
  CHECK(mx_demo_surface(&demo, 7) == MX_OK);
  layout L = plain(ASCII);
  L.xt = L.yt = L.zt = DOUBLE;
  speed_one(&L, &demo, "big_ascii.ply");
  mx_trisoup_free(&demo);
  CHECK(mx_demo_surface(&demo, 8) == MX_OK);
  L.fmt = LE;
  speed_one(&L, &demo, "big_LE.ply");
  L.fmt = BE;
  L.it = UINT;
  speed_one(&L, &demo, "big_BE.ply");
  mx_trisoup_free(&demo);
}

/* ---- main ------------------------------------------------------------- */

int main(void) {
  strcpy(tmpdir, "/tmp/mixoct_ply_XXXXXX");
  if (!mkdtemp(tmpdir)) {
    perror("mkdtemp");
    return 1;
  }
  test_formats();
  test_types();
  test_polygons();
  test_text_details();
  test_bad_header();
  test_huge_counts();
  test_bad_text_data();
  test_bad_binary();
  test_speed();
  remove_dir_files(tmpdir);
  rmdir(tmpdir);
  return TEST_DONE();
}
