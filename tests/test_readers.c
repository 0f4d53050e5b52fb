/* Tests of the surface readers, the soup helpers, the surface check, the
 * .reg reader and the demo surface. Bad inputs are written into a temporary
 * directory; each must fail with MX_EINPUT and one message on stderr naming
 * the file and, where it makes sense, the line ("FILE:LINE:"). */
#include <dirent.h>
#include <fcntl.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "check.h"
#include "file_util.h"
#include "base/common.h"
#include "soa/regions.h"
#include "soa/trisoup.h"
#include "io/read_surface.h"
#include "io/demo_surface.h"

#define SURF MIXOCT_TEST_DATA "/surfaces/"

typedef int (*reader_fn)(const char *path, mx_trisoup *out);

static char tmpdir[64];
static char captured[16384];

/* ---- files and stderr capture ----------------------------------------- */

static void tpath(char *buf, size_t n, const char *name) {
  snprintf(buf, n, "%s/%s", tmpdir, name);
}

#define write_bytes write_bytes_file

/* stderr goes to tmpdir/stderr.txt until capture_end, which returns it. */
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

/* ---- the failure check ------------------------------------------------ */

/* Reads path with rd; it must fail with MX_EINPUT, leave the soup empty,
 * and print a message naming the path, "path:line:" if line > 0, and
 * needle if not NULL. */
static void expect_fail(reader_fn rd, const char *path, long line,
                        const char *needle, const char *label) {
  int before = mx_test_failures;
  mx_trisoup s;
  memset(&s, 0xab, sizeof s); /* readers must not rely on a zeroed soup */
  capture_begin();
  int rc = rd(path, &s);
  const char *msg = capture_end();
  CHECK(rc == MX_EINPUT);
  CHECK(s.nv == 0 && s.nt == 0 && s.x == NULL && s.tri == NULL);
  CHECK(strstr(msg, path) != NULL);
  CHECK(strstr(msg, "error") != NULL);
  if (line > 0) {
    char loc[256];
    snprintf(loc, sizeof loc, "%s:%ld:", path, line);
    CHECK(strstr(msg, loc) != NULL);
  }
  if (needle) CHECK(strstr(msg, needle) != NULL);
  if (rc == MX_OK) mx_trisoup_free(&s);
  printf("%s %-28s %s", mx_test_failures == before ? "ok  " : "FAIL", label,
         msg[0] ? msg : "(no message)\n");
}

/* Writes text to tmpdir/name and expects rd to fail on it. */
static void bad_text(reader_fn rd, const char *name, const char *text,
                     long line, const char *needle) {
  char path[128];
  tpath(path, sizeof path, name);
  write_bytes(path, text, strlen(text));
  expect_fail(rd, path, line, needle, name);
}

/* The same, freeing a text made by edit() or cut(). */
static void bad_edit(reader_fn rd, const char *name, char *text, long line,
                     const char *needle) {
  bad_text(rd, name, text, line, needle);
  free(text);
}

/* Missing file, a directory, an empty file. */
static void bad_files(reader_fn rd, const char *ext) {
  char path[128], name[64];
  snprintf(name, sizeof name, "missing.%s", ext);
  tpath(path, sizeof path, name);
  expect_fail(rd, path, 0, "cannot open", name);
  snprintf(name, sizeof name, "dir.%s", ext);
  tpath(path, sizeof path, name);
  mkdir(path, 0700);
  expect_fail(rd, path, 0, "directory", name);
  rmdir(path);
  snprintf(name, sizeof name, "empty.%s", ext);
  bad_text(rd, name, "", 0, "empty");
}

/* ---- the reference tetrahedron ---------------------------------------- */

/* Exactly representable in float, so binary STL gives the same numbers. */
static const double TET_V[4][3] = {
    {0.5, -1.25, 2}, {3.5, -1.25, 2}, {0.5, 0.75, 2}, {0.5, -1.25, 4.25}};
static const uint32_t TET_T[4][3] = {
    {0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};

static const char *OFF_TET =
    "OFF\n"
    "4 4 0\n"
    "0.5 -1.25 2\n"
    "3.5 -1.25 2\n"
    "0.5 0.75 2\n"
    "0.5 -1.25 4.25\n"
    "3 0 2 1\n"
    "3 0 1 3\n"
    "3 0 3 2\n"
    "3 1 2 3\n";

/* Triangles before vertices, as the format allows. */
static const char *MDL_TET =
    "[Name, STRING]\n"              /* 1 */
    "tetra\n"                       /* 2 */
    "\n"                            /* 3 */
    "[Triangles, ARRAY1<STRING>]\n" /* 4 */
    "4\n"                           /* 5 */
    "0 2 1 0 0 0\n"                 /* 6 */
    "0 1 3 0 0 0\n"                 /* 7 */
    "0 3 2 0 0 0\n"                 /* 8 */
    "1 2 3 0 0 0\n"                 /* 9 */
    "\n"                            /* 10 */
    "[Normals, ARRAY1<VECTOR3D>]\n" /* 11 */
    "1\n"                           /* 12 */
    "1 0 0\n"                       /* 13 */
    "\n"                            /* 14 */
    "[Vertices, ARRAY1<POINT3D>]\n" /* 15 */
    "4\n"                           /* 16 */
    "0.5 -1.25 2\n"                 /* 17 */
    "3.5 -1.25 2\n"                 /* 18 */
    "0.5 0.75 2\n"                  /* 19 */
    "0.5 -1.25 4.25\n";             /* 20 */

static const char *OBJ_TET =
    "# a tetrahedron\n"         /* 1 */
    "o tet\n"                   /* 2 */
    "v 0.5 -1.25 2\n"           /* 3 */
    "v 3.5 -1.25 2\n"           /* 4 */
    "v 0.5 0.75 2\n"            /* 5 */
    "v 0.5 -1.25 4.25\n"        /* 6 */
    "vn 0 0 1\n"                /* 7 */
    "f 1 3 2\n"                 /* 8 */
    "f 1/1 2/2 4/4\n"           /* 9 */
    "f 1//1 4//1 3//1\n"        /* 10 */
    "f -3/1/1 -2/1/1 -1/1/1\n"; /* 11 */

/* ASCII STL of the tetrahedron: facet f spans lines 2+7f .. 8+7f, its
 * vertex k is on line 4+7f+k; "endsolid" is line 30. */
static char *stl_tet_text(void) {
  static const char *facet = "  facet normal 0 0 0\n    outer loop\n";
  static const char *close = "    endloop\n  endfacet\n";
  size_t cap = 4096, n = 0;
  char *t = malloc(cap);
  if (!t) abort();
  n += (size_t)snprintf(t + n, cap - n, "solid tet\n");
  for (int f = 0; f < 4; f++) {
    n += (size_t)snprintf(t + n, cap - n, "%s", facet);
    for (int k = 0; k < 3; k++) {
      const double *v = TET_V[TET_T[f][k]];
      n += (size_t)snprintf(t + n, cap - n, "      vertex %g %g %g\n", v[0],
                            v[1], v[2]);
    }
    n += (size_t)snprintf(t + n, cap - n, "%s", close);
  }
  snprintf(t + n, cap - n, "endsolid tet\n");
  return t;
}

static void put_float(unsigned char *p, double v) {
  float f = (float)v;
  memcpy(p, &f, 4); /* the test hosts are little-endian */
}

/* Binary STL: header starting with "solid" (must still be seen as binary),
 * count, facets. Returns the size. */
static size_t stl_binary(unsigned char *buf, const double (*v)[3],
                         const uint32_t (*t)[3], uint32_t n) {
  memset(buf, ' ', 80);
  memcpy(buf, "solid binary, not ascii", 23);
  memcpy(buf + 80, &n, 4);
  for (uint32_t f = 0; f < n; f++) {
    unsigned char *r = buf + 84 + 50 * f;
    memset(r, 0, 50);
    for (int k = 0; k < 3; k++)
      for (int d = 0; d < 3; d++)
        put_float(r + 12 + 12 * k + 4 * d, v[t[f][k]][d]);
  }
  return 84 + 50 * (size_t)n;
}

/* Vertex i of s equals some reference vertex exactly; triangles match the
 * reference ones up to rotation (same orientation). */
static int same_as_tet(const mx_trisoup *s) {
  if (s->nv != 4 || s->nt != 4) return 0;
  int map[4];
  for (size_t i = 0; i < 4; i++) {
    map[i] = -1;
    for (int j = 0; j < 4; j++)
      if (s->x[i] == TET_V[j][0] && s->y[i] == TET_V[j][1] &&
          s->z[i] == TET_V[j][2])
        map[i] = j;
    if (map[i] < 0) return 0;
  }
  for (size_t i = 0; i < 4; i++) {
    uint32_t a = map[s->tri[3 * i]], b = map[s->tri[3 * i + 1]],
             c = map[s->tri[3 * i + 2]];
    int found = 0;
    for (int f = 0; f < 4; f++)
      for (int r = 0; r < 3; r++)
        found |= TET_T[f][r] == a && TET_T[f][(r + 1) % 3] == b &&
                 TET_T[f][(r + 2) % 3] == c;
    if (!found) return 0;
  }
  return 1;
}

/* Reads path, which must give the reference tetrahedron, closed. */
static void expect_tet(reader_fn rd, const char *path, const char *label) {
  int before = mx_test_failures;
  mx_trisoup s;
  int rc = rd(path, &s);
  CHECK(rc == MX_OK);
  if (rc != MX_OK) return;
  CHECK(same_as_tet(&s));
  CHECK(s.nshells == 1 && s.shell[0] == 0 && s.shell[3] == 0);
  size_t open = 99;
  CHECK(mx_trisoup_check(&s, path, &open) == MX_OK);
  CHECK(open == 0);
  mx_trisoup_free(&s);
  printf("%s %-28s nv=4 nt=4 closed\n",
         mx_test_failures == before ? "ok  " : "FAIL", label);
}

static void good_text(reader_fn rd, const char *name, const char *text) {
  char path[128];
  tpath(path, sizeof path, name);
  write_bytes(path, text, strlen(text));
  expect_tet(rd, path, name);
}

/* ---- OFF -------------------------------------------------------------- */

static void test_off(void) {
  printf("-- OFF\n");
  good_text(mx_read_off, "tet.off", OFF_TET);
  good_text(mx_read_off, "tet_comments.off",
            "# comment first\nOFF 4 4 0 # counts on the header line\n"
            "0.5 -1.25 2\n\n# a comment line\n3.5 -1.25 2 # trailing\n"
            "0.5 0.75 2\n0.5 -1.25 4.25\n"
            "3 0 2 1  255 0 0\n3 0 1 3 1 1 1\n3 0 3 2\n3 1 2 3\n");
  bad_files(mx_read_off, "off");
  bad_text(mx_read_off, "blank.off", "\n  \n# only a comment\n", 0,
           "no 'OFF' header");
  bad_edit(mx_read_off, "header.off", edit(OFF_TET, 1, "OFX"), 1, "bad header");
  bad_edit(mx_read_off, "counts.off", edit(OFF_TET, 2, "4 four 0"), 2,
           "bad header");
  bad_text(mx_read_off, "nocounts.off", "OFF\n", 2, "missing counts");
  bad_edit(mx_read_off, "nofaces.off", edit(OFF_TET, 2, "4 0 0"), 2,
           "no faces");
  bad_edit(mx_read_off, "trunc_v.off", cut(OFF_TET, 6, 10), 6,
           "3 of 4 vertices");
  bad_edit(mx_read_off, "trunc_f.off", cut(OFF_TET, 10, 10), 10,
           "3 of 4 faces");
  bad_edit(mx_read_off, "more_f.off", edit(OFF_TET, 2, "4 3 0"), 10,
           "more data");
  bad_edit(mx_read_off, "nv_small.off", edit(OFF_TET, 2, "3 4 0"), 6, "face 0");
  bad_edit(mx_read_off, "nv_large.off", edit(OFF_TET, 2, "5 4 0"), 11,
           "3 of 4 faces");
  bad_edit(mx_read_off, "index.off", edit(OFF_TET, 9, "3 0 3 4"), 9,
           "out of range");
  bad_edit(mx_read_off, "negative.off", edit(OFF_TET, 7, "3 0 -1 1"), 7,
           "out of range");
  bad_edit(mx_read_off, "badindex.off", edit(OFF_TET, 8, "3 0 1.5 3"), 8,
           "bad vertex index");
  bad_edit(mx_read_off, "k2.off", edit(OFF_TET, 7, "2 0 2"), 7, "k >= 3");
  bad_edit(mx_read_off, "shortface.off", edit(OFF_TET, 7, "3 0 2"), 7,
           "missing vertex index");
  bad_edit(mx_read_off, "nan.off", edit(OFF_TET, 4, "nan -1.25 2"), 4,
           "not a finite number");
  bad_edit(mx_read_off, "inf.off", edit(OFF_TET, 5, "0.5 -inf 2"), 5,
           "not a finite number");
  bad_edit(mx_read_off, "huge.off", edit(OFF_TET, 6, "0.5 -1.25 1e999"), 6,
           "not a finite number");
  bad_edit(mx_read_off, "notnum.off", edit(OFF_TET, 3, "0.5x -1.25 2"), 3,
           "not a number");
  bad_edit(mx_read_off, "twocoord.off", edit(OFF_TET, 3, "0.5 -1.25"), 3,
           "expected 3 numbers");
}

static void test_off_polygons(void) {
  char path[128];
  tpath(path, sizeof path, "quad.off");
  const char *t =
      "OFF\n5 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n0.5 0.5 1\n"
      "4 0 1 2 3\n5 0 1 2 3 4 9 9 9\n";
  write_bytes(path, t, strlen(t));
  mx_trisoup s;
  CHECK(mx_read_off(path, &s) == MX_OK);
  CHECK(s.nv == 5 && s.nt == 5);
  /* the square as the fan from its first corner; the pentagon (the square
   * and the apex above its centre: not planar) by ear clipping in its
   * projection on z = 0, where the apex is a reflex corner */
  static const uint32_t want[15] = {0, 1, 2, 0, 2, 3, 2, 3,
                                    4, 4, 0, 1, 4, 1, 2};
  static const uint32_t faces[5] = {0, 0, 1, 1, 1};
  CHECK(s.nt == 5 && memcmp(s.tri, want, sizeof want) == 0);
  CHECK(memcmp(s.face, faces, sizeof faces) == 0);
  CHECK(mx_trisoup_line(&s, 0) == 8 && mx_trisoup_line(&s, 4) == 9);
  mx_trisoup_free(&s);
  printf("ok   quad.off                     polygons split in their plane\n");
}

/* ---- MDL -------------------------------------------------------------- */

static void test_mdl(void) {
  printf("-- MDL\n");
  good_text(mx_read_mdl, "tet.mdl", MDL_TET);
  char *crlf = malloc(2 * strlen(MDL_TET) + 1), *o = crlf;
  if (!crlf) abort();
  for (const char *p = MDL_TET; *p; p++) {
    if (*p == '\n') *o++ = '\r';
    *o++ = *p;
  }
  *o = '\0';
  good_text(mx_read_mdl, "tet_crlf.mdl", crlf);
  free(crlf);
  char *nonames = cut(MDL_TET, 1, 3);
  good_text(mx_read_mdl, "tet_nonames.mdl", nonames);
  free(nonames);
  bad_files(mx_read_mdl, "mdl");
  bad_edit(mx_read_mdl, "index.mdl", edit(MDL_TET, 8, "0 3 4 0 0 0"), 8,
           "out of range");
  bad_edit(mx_read_mdl, "negative.mdl", edit(MDL_TET, 7, "0 -1 3 0 0 0"), 7,
           "out of range");
  bad_edit(mx_read_mdl, "shorttri.mdl", edit(MDL_TET, 7, "0 1"), 7,
           "missing vertex index");
  bad_edit(mx_read_mdl, "trunc.mdl", cut(MDL_TET, 20, 20), 20,
           "3 of 4 vertices");
  bad_edit(mx_read_mdl, "count_big.mdl", edit(MDL_TET, 5, "5"), 11,
           "4 of 5 triangles");
  bad_edit(mx_read_mdl, "count_small.mdl", edit(MDL_TET, 5, "3"), 9,
           "section header");
  bad_edit(mx_read_mdl, "count_bad.mdl", edit(MDL_TET, 16, "four"), 16,
           "item count");
  bad_edit(mx_read_mdl, "header.mdl",
           edit(MDL_TET, 15, "[Vertices ARRAY1<POINT3D>]"), 15,
           "section header");
  bad_edit(mx_read_mdl, "type.mdl", edit(MDL_TET, 15, "[Vertices, FOO]"), 15,
           "unsupported type");
  bad_edit(mx_read_mdl, "nan.mdl", edit(MDL_TET, 18, "nan -1.25 2"), 18,
           "not a finite number");
  bad_edit(mx_read_mdl, "inf.mdl", edit(MDL_TET, 19, "0.5 inf 2"), 19,
           "not a finite number");
  bad_edit(mx_read_mdl, "huge.mdl", edit(MDL_TET, 20, "0.5 -1.25 -1e999"), 20,
           "not a finite number");
  bad_edit(mx_read_mdl, "twocoord.mdl", edit(MDL_TET, 17, "0.5 -1.25"), 17,
           "expected 3 numbers");
  bad_edit(mx_read_mdl, "novert.mdl", cut(MDL_TET, 15, 20), 0, "no [Vertices");
  bad_edit(mx_read_mdl, "notri.mdl", cut(MDL_TET, 4, 9), 0, "no [Triangles");
  char *notri = cut(MDL_TET, 6, 9);
  bad_edit(mx_read_mdl, "notri0.mdl", edit(notri, 5, "0"), 5, "empty");
  free(notri);
  char *dup = malloc(strlen(MDL_TET) * 2 + 2);
  if (!dup) abort();
  sprintf(dup, "%s\n%s", MDL_TET, MDL_TET);
  bad_text(mx_read_mdl, "duplicate.mdl", dup, 25, "duplicate");
  free(dup);
  bad_text(mx_read_mdl, "garbage.mdl", "hello\n", 1, "section header");
}

/* ---- STL -------------------------------------------------------------- */

static void test_stl_ascii(void) {
  printf("-- STL (ASCII)\n");
  char *t = stl_tet_text();
  good_text(mx_read_stl, "tet_ascii.stl", t);
  bad_files(mx_read_stl, "stl");
  bad_edit(mx_read_stl, "trunc.stl", cut(t, 27, 30), 27, "end of file");
  bad_edit(mx_read_stl, "noend.stl", cut(t, 30, 30), 30, "end of file");
  bad_edit(mx_read_stl, "twovert.stl", cut(t, 6, 6), 6,
           "expected 'vertex', found 'endloop'");
  bad_edit(mx_read_stl, "keyword.stl", edit(t, 3, "outer lop"), 3,
           "expected 'loop'");
  bad_edit(mx_read_stl, "facet.stl", edit(t, 9, "facett normal 0 0 1"), 9,
           "expected 'facet' or 'endsolid'");
  bad_edit(mx_read_stl, "nan.stl", edit(t, 12, "vertex 3.5 nan 2"), 12,
           "not a finite number");
  bad_edit(mx_read_stl, "inf.stl", edit(t, 19, "vertex inf -1.25 4.25"), 19,
           "not a finite number");
  bad_edit(mx_read_stl, "huge.stl", edit(t, 26, "vertex 0.5 1e999 2"), 26,
           "not a finite number");
  bad_edit(mx_read_stl, "twocoord.stl", edit(t, 5, "vertex 0.5 0.75"), 5,
           "expected 3 numbers");
  bad_text(mx_read_stl, "nofacet.stl", "solid x\nendsolid x\n", 0, "no facets");
  bad_text(mx_read_stl, "notstl.stl", "hello\n", 0, "neither");
  free(t);
}

static void test_stl_binary(void) {
  printf("-- STL (binary)\n");
  unsigned char buf[84 + 50 * 8];
  char path[128];
  size_t n = stl_binary(buf, TET_V, TET_T, 4);
  tpath(path, sizeof path, "tet_binary.stl");
  write_bytes(path, buf, n);
  expect_tet(mx_read_stl, path, "tet_binary.stl (merged)");

  tpath(path, sizeof path, "trunc_bin.stl");
  write_bytes(path, buf, n - 10);
  expect_fail(mx_read_stl, path, 0, "truncated", "trunc_bin.stl");
  memcpy(buf, "binary", 6); /* header not starting with "solid" */
  tpath(path, sizeof path, "trunc_bin2.stl");
  write_bytes(path, buf, n - 10);
  expect_fail(mx_read_stl, path, 0, "truncated", "trunc_bin2.stl");
  uint32_t five = 5;
  memcpy(buf + 80, &five, 4);
  tpath(path, sizeof path, "count_bin.stl");
  write_bytes(path, buf, n);
  expect_fail(mx_read_stl, path, 0, "declares 5 facets", "count_bin.stl");
  n = stl_binary(buf, TET_V, TET_T, 4);
  put_float(buf + 84 + 50 * 2 + 12 + 4, NAN);
  tpath(path, sizeof path, "nan_bin.stl");
  write_bytes(path, buf, n);
  expect_fail(mx_read_stl, path, 0, "facet 2", "nan_bin.stl");
  put_float(buf + 84 + 50 * 2 + 12 + 4, INFINITY);
  tpath(path, sizeof path, "inf_bin.stl");
  write_bytes(path, buf, n);
  expect_fail(mx_read_stl, path, 0, "not finite", "inf_bin.stl");
  n = stl_binary(buf, TET_V, TET_T, 0);
  tpath(path, sizeof path, "zero_bin.stl");
  write_bytes(path, buf, n);
  expect_fail(mx_read_stl, path, 0, "no facets", "zero_bin.stl");
  memset(buf, 0, 50);
  tpath(path, sizeof path, "short_bin.stl");
  write_bytes(path, buf, 50);
  expect_fail(mx_read_stl, path, 0, "at least 84", "short_bin.stl");
}

/* ---- OBJ -------------------------------------------------------------- */

static void test_obj(void) {
  printf("-- OBJ\n");
  good_text(mx_read_obj, "tet.obj", OBJ_TET);
  bad_files(mx_read_obj, "obj");
  bad_edit(mx_read_obj, "index.obj", edit(OBJ_TET, 8, "f 1 3 5"), 8,
           "out of range");
  bad_edit(mx_read_obj, "zero.obj", edit(OBJ_TET, 8, "f 0 1 2"), 8,
           "out of range");
  bad_edit(mx_read_obj, "negative.obj", edit(OBJ_TET, 11, "f -5 -1 -2"), 11,
           "out of range");
  bad_edit(mx_read_obj, "badref.obj", edit(OBJ_TET, 9, "f 1 x 2"), 9,
           "bad vertex reference");
  bad_edit(mx_read_obj, "twovert.obj", edit(OBJ_TET, 10, "f 1 2"), 10,
           "at least 3");
  bad_edit(mx_read_obj, "nan.obj", edit(OBJ_TET, 4, "v nan -1.25 2"), 4,
           "not a finite number");
  bad_edit(mx_read_obj, "inf.obj", edit(OBJ_TET, 5, "v 0.5 0.75 +inf"), 5,
           "not a finite number");
  bad_edit(mx_read_obj, "huge.obj", edit(OBJ_TET, 6, "v 1e999 -1.25 4.25"), 6,
           "not a finite number");
  bad_edit(mx_read_obj, "twocoord.obj", edit(OBJ_TET, 3, "v 0.5 -1.25"), 3,
           "expected 3 numbers");
  bad_edit(mx_read_obj, "nofaces.obj", cut(OBJ_TET, 8, 11), 0, "no faces");
}

static void test_obj_quad(void) {
  char path[128];
  tpath(path, sizeof path, "quad.obj");
  const char *t = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\ng quad\nf 1 2 3 4\n";
  write_bytes(path, t, strlen(t));
  mx_trisoup s;
  CHECK(mx_read_obj(path, &s) == MX_OK);
  static const uint32_t want[6] = {0, 1, 2, 0, 2, 3};
  CHECK(s.nv == 4 && s.nt == 2 && memcmp(s.tri, want, sizeof want) == 0);
  size_t open = 0;
  mx_quiet = 1;
  CHECK(mx_trisoup_check(&s, path, &open) == MX_OK && open == 4);
  mx_quiet = 0;
  mx_trisoup_free(&s);
  printf("ok   quad.obj                     quad fan-split into 2 triangles\n");
}

/* ---- dispatch --------------------------------------------------------- */

static void test_dispatch(void) {
  printf("-- mx_read_surface\n");
  char path[128];
  tpath(path, sizeof path, "TET.OFF");
  write_bytes(path, OFF_TET, strlen(OFF_TET));
  expect_tet(mx_read_surface, path, "TET.OFF (case-insensitive)");
  tpath(path, sizeof path, "tet.Obj");
  write_bytes(path, OBJ_TET, strlen(OBJ_TET));
  expect_tet(mx_read_surface, path, "tet.Obj");
  bad_text(mx_read_surface, "tet.xyz", OFF_TET, 0, "unknown surface format");
  bad_text(mx_read_surface, "noext", OFF_TET, 0, "unknown surface format");
}

/* ---- checks after reading --------------------------------------------- */

static int read_text(reader_fn rd, const char *name, const char *text,
                     mx_trisoup *s) {
  char path[128];
  tpath(path, sizeof path, name);
  write_bytes(path, text, strlen(text));
  return rd(path, s);
}

static void test_degenerate(void) {
  printf("-- degenerate and open surfaces\n");
  /* The tetrahedron plus a collinear triangle (4 is the midpoint of 0-1),
   * a repeated index, and a triangle through a duplicated vertex (5 = 2). */
  const char *t =
      "OFF\n6 7 0\n0.5 -1.25 2\n3.5 -1.25 2\n0.5 0.75 2\n0.5 -1.25 4.25\n"
      "2 -1.25 2\n0.5 0.75 2\n"
      "3 0 2 1\n3 0 1 4\n3 0 1 3\n3 3 3 1\n3 0 3 2\n3 2 5 3\n3 1 2 3\n";
  mx_trisoup s;
  CHECK(read_text(mx_read_off, "degenerate.off", t, &s) == MX_OK);
  CHECK(s.nt == 7);
  size_t open = 99;
  capture_begin();
  int rc = mx_trisoup_check(&s, "degenerate.off", &open);
  const char *msg = capture_end();
  CHECK(rc == MX_OK && s.nt == 4 && open == 0 && s.nv == 6);
  CHECK(strstr(msg, "removed 3 degenerate triangles") != NULL);
  CHECK(strstr(msg, "not closed") == NULL);
  static const uint32_t kept[12] = {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3};
  CHECK(memcmp(s.tri, kept, sizeof kept) == 0);
  mx_trisoup_free(&s);
  printf("degenerate.off: %s", msg);

  char *o = cut(OFF_TET, 10, 10), *o2 = edit(o, 2, "4 3 0"); /* no face 3 */
  CHECK(read_text(mx_read_off, "open.off", o2, &s) == MX_OK);
  free(o);
  free(o2);
  capture_begin();
  rc = mx_trisoup_check(&s, "open.off", &open);
  msg = capture_end();
  /* counted; the mesher's input policy refuses or repairs it, naming the
   * edges (tests/cli_test.sh, tests/test_surface_defects.c) */
  CHECK(rc == MX_OK && s.nt == 3 && open == 3);
  CHECK(strstr(msg, "not closed") == NULL);
  mx_trisoup_free(&s);
  printf("open.off: %s", msg);

  /* A fin on edge 0-1: that edge is used 3 times, 1-4 and 4-0 once. */
  const char *fin =
      "OFF\n5 5 0\n0.5 -1.25 2\n3.5 -1.25 2\n0.5 0.75 2\n"
      "0.5 -1.25 4.25\n2 -5 2\n"
      "3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n3 0 1 4\n";
  CHECK(read_text(mx_read_off, "fin.off", fin, &s) == MX_OK);
  capture_begin();
  rc = mx_trisoup_check(&s, "fin.off", &open);
  capture_end();
  CHECK(rc == MX_OK && open == 3);
  mx_trisoup_free(&s);

  const char *flat = "OFF\n3 2 0\n0 0 0\n1 0 0\n2 0 0\n3 0 1 2\n3 0 0 1\n";
  CHECK(read_text(mx_read_off, "flat.off", flat, &s) == MX_OK);
  capture_begin();
  rc = mx_trisoup_check(&s, "flat.off", &open);
  msg = capture_end();
  CHECK(rc == MX_EINPUT && s.nt == 0 && strstr(msg, "no triangles"));
  mx_trisoup_free(&s);
  printf("flat.off: %s", msg);
}

/* ---- soup helpers ----------------------------------------------------- */

static void test_soup(void) {
  printf("-- soup helpers\n");
  mx_trisoup a = {0}, b;
  CHECK(read_text(mx_read_off, "tet_a.off", OFF_TET, &b) == MX_OK);
  CHECK(mx_trisoup_append(&a, &b) == MX_OK);
  CHECK(mx_trisoup_append(&a, &b) == MX_OK);
  CHECK(a.nv == 8 && a.nt == 8 && a.nshells == 2);
  CHECK(a.shell[0] == 0 && a.shell[3] == 0 && a.shell[4] == 1 &&
        a.shell[7] == 1);
  CHECK(a.tri[12] == TET_T[0][0] + 4 && a.tri[23] == TET_T[3][2] + 4);
  double lo[3], hi[3];
  mx_trisoup_bbox(&a, lo, hi);
  CHECK(lo[0] == 0.5 && lo[1] == -1.25 && lo[2] == 2);
  CHECK(hi[0] == 3.5 && hi[1] == 0.75 && hi[2] == 4.25);
  size_t open = 99;
  CHECK(mx_trisoup_check(&a, NULL, &open) == MX_OK && open == 0);
  CHECK(mx_trisoup_reserve(&a, 1000, 2000) == MX_OK);
  CHECK(a.cap_v >= 1000 && a.cap_t >= 2000 && a.nv == 8 && a.x[7] == 0.5);
  mx_trisoup_free(&a);
  mx_trisoup_free(&b);
  CHECK(a.x == NULL && a.nv == 0 && a.cap_v == 0);
  mx_trisoup_free(&a); /* twice is harmless */
}

/* ---- .reg ------------------------------------------------------------- */

static const char *REG_GOOD =
    "n_regions 2\n"  /* 1 */
    "\n"             /* 2 */
    "0 0 0\n"        /* 3 */
    "300 100 170\n"  /* 4 */
    "\n"             /* 5 */
    "5\n"            /* 6 */
    "\n"             /* 7 */
    "-300 -300 0\n"  /* 8 */
    "300 300 88.5\n" /* 9 */
    "\n"             /* 10 */
    "6\n";           /* 11 */

/* Adapts mx_read_reg to the reader signature for expect_fail. */
static int read_reg_as_soup(const char *path, mx_trisoup *s) {
  mx_box_region *boxes = (mx_box_region *)1;
  size_t n = 7;
  memset(s, 0, sizeof *s);
  int rc = mx_read_reg(path, &boxes, &n);
  if (rc != MX_OK) CHECK(boxes == NULL && n == 0);
  mx_free(rc == MX_OK ? boxes : NULL);
  return rc;
}

static void check_reg_good(const char *path, double z1) {
  mx_box_region *b = NULL;
  size_t n = 0;
  CHECK(mx_read_reg(path, &b, &n) == MX_OK);
  CHECK(n == 2 && b != NULL);
  if (n == 2 && b) {
    CHECK(b[0].lo[0] == 0 && b[0].lo[1] == 0 && b[0].lo[2] == 0);
    CHECK(b[0].hi[0] == 300 && b[0].hi[1] == 100 && b[0].hi[2] == 170);
    CHECK(b[0].level == 5 && b[1].level == 6);
    CHECK(b[1].lo[0] == -300 && b[1].lo[1] == -300 && b[1].hi[2] == z1);
  }
  mx_free(b);
}

static void test_reg(void) {
  printf("-- .reg\n");
  char path[128];
  tpath(path, sizeof path, "good.reg");
  write_bytes(path, REG_GOOD, strlen(REG_GOOD));
  check_reg_good(path, 88.5);
  tpath(path, sizeof path, "oneline.reg");
  const char *one = "# regions\nn_regions 1 0 0 0 1 1 1 3 # the end\n";
  write_bytes(path, one, strlen(one));
  mx_box_region *b = NULL;
  size_t n = 0;
  CHECK(mx_read_reg(path, &b, &n) == MX_OK && n == 1 && b[0].level == 3 &&
        b[0].hi[2] == 1);
  mx_free(b);
  tpath(path, sizeof path, "zero.reg");
  write_bytes(path, "n_regions 0\n", 12);
  CHECK(mx_read_reg(path, &b, &n) == MX_OK && n == 0);
  mx_free(b);
  if (access(SURF "cortex.reg", R_OK) == 0) {
    check_reg_good(SURF "cortex.reg", 88);
    printf("ok   cortex.reg (2 regions)\n");
  } else {
    TEST_DATA_MISSING("%scortex.reg: not present", SURF);
  }
  bad_files(read_reg_as_soup, "reg");
  bad_edit(read_reg_as_soup, "keyword.reg", edit(REG_GOOD, 1, "regions 2"), 1,
           "n_regions");
  bad_edit(read_reg_as_soup, "count.reg", edit(REG_GOOD, 1, "n_regions x"), 1,
           "region count");
  bad_edit(read_reg_as_soup, "negcount.reg", edit(REG_GOOD, 1, "n_regions -1"),
           1, "region count");
  bad_edit(read_reg_as_soup, "trunc.reg", cut(REG_GOOD, 9, 11), 9,
           "region 2 of 2");
  bad_edit(read_reg_as_soup, "more.reg", edit(REG_GOOD, 1, "n_regions 1"), 8,
           "more data");
  bad_edit(read_reg_as_soup, "nan.reg", edit(REG_GOOD, 4, "300 nan 170"), 4,
           "not finite");
  bad_edit(read_reg_as_soup, "huge.reg", edit(REG_GOOD, 8, "-1e999 -300 0"), 8,
           "not finite");
  bad_edit(read_reg_as_soup, "word.reg", edit(REG_GOOD, 8, "-300 abc 0"), 8,
           "not a number");
  bad_edit(read_reg_as_soup, "lohi.reg", edit(REG_GOOD, 4, "300 -1 170"), 4,
           "min corner above max corner");
  bad_edit(read_reg_as_soup, "neglevel.reg", edit(REG_GOOD, 6, "-5"), 6,
           "out of range");
  bad_edit(read_reg_as_soup, "fraclevel.reg", edit(REG_GOOD, 11, "6.5"), 11,
           "not an integer");
}

/* ---- demo surface ----------------------------------------------------- */

/* 6 x the signed volume of the tetrahedron (o, a, b, c). */
static double tet6(const mx_trisoup *s, const uint32_t *t, const double o[3]) {
  double a[3], b[3], c[3];
  const double *X[3] = {s->x, s->y, s->z};
  for (int d = 0; d < 3; d++) {
    a[d] = X[d][t[0]] - o[d];
    b[d] = X[d][t[1]] - o[d];
    c[d] = X[d][t[2]] - o[d];
  }
  return a[0] * (b[1] * c[2] - b[2] * c[1]) -
         a[1] * (b[0] * c[2] - b[2] * c[0]) +
         a[2] * (b[0] * c[1] - b[1] * c[0]);
}

static void test_demo(void) {
  printf("-- demo surface\n");
  mx_trisoup s;
  CHECK(mx_demo_surface(&s, 4) == MX_OK);
  CHECK(s.nt == 5120 && s.nv == 2562 && s.nshells == 1);
  size_t open = 99;
  CHECK(mx_trisoup_check(&s, "demo", &open) == MX_OK);
  CHECK(s.nt == 5120 && open == 0);
  double c[3] = {0, 0, 0}, origin[3] = {0, 0, 0};
  for (size_t v = 0; v < s.nv; v++) {
    c[0] += s.x[v] / (double)s.nv;
    c[1] += s.y[v] / (double)s.nv;
    c[2] += s.z[v] / (double)s.nv;
  }
  double vol_o = 0, vol_c = 0, min_o = INFINITY, min_c = INFINITY;
  for (size_t i = 0; i < s.nt; i++) {
    double a = tet6(&s, s.tri + 3 * i, origin), b = tet6(&s, s.tri + 3 * i, c);
    vol_o += a / 6;
    vol_c += b / 6;
    min_o = fmin(min_o, a);
    min_c = fmin(min_c, b);
  }
  CHECK(vol_o > 0 && min_o > 0 && min_c > 0);
  CHECK(fabs(vol_o - vol_c) <= 1e-9 * vol_o);
  double lo[3], hi[3];
  mx_trisoup_bbox(&s, lo, hi);
  CHECK(hi[0] - lo[0] > 70 && hi[0] - lo[0] < 90);
  printf(
      "demo subdiv 4: nv=%zu nt=%zu open=%zu volume=%.1f size %.1f x %.1f x "
      "%.1f centroid (%.2f %.2f %.2f)\n",
      s.nv, s.nt, open, vol_o, hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2],
      c[0], c[1], c[2]);
  mx_trisoup_free(&s);
  CHECK(mx_demo_surface(&s, 0) == MX_OK && s.nt == 20 && s.nv == 12);
  mx_trisoup_free(&s);
  capture_begin();
  CHECK(mx_demo_surface(&s, -1) == MX_EINPUT && s.nt == 0);
  capture_end();
}

/* ---- the sample files ------------------------------------------------- */

typedef struct {
  const char *name;
  size_t nv, nt; /* from the file headers */
  int closed;    /* asserted to have 0 open edges */
} sample;

static void test_samples(void) {
  printf("-- sample surfaces in %s\n", SURF);
  static const sample files[] = {
      {"cortex.off", 3152, 6300, 1},
      {"cyl50.off", 102, 200, 1},
      {"hex.off", 8, 12, 1},
      {"hollow-coarse.off", 632, 1260, 1},
      {"suture.off", 2202, 4400, 1},
      {"femur.mdl", 1847, 3690, 1},
      {"fertilityRotated.mdl", 3296, 6604, 1},
      {"in_spher.mdl", 872, 1740, 1},
      {"outer_sphere.mdl", 872, 1740, 1},
      {"sein.mdl", 1248, 2492, 1},
  };
  for (size_t i = 0; i < sizeof files / sizeof *files; i++) {
    char path[256];
    snprintf(path, sizeof path, "%s%s", SURF, files[i].name);
    if (access(path, R_OK) != 0) {
      TEST_DATA_MISSING("%s: not present", path);
      continue;
    }
    mx_trisoup s;
    double t0 = mx_wtime();
    int rc = mx_read_surface(path, &s);
    double t1 = mx_wtime();
    CHECK(rc == MX_OK);
    if (rc != MX_OK) continue;
    CHECK(s.nv == files[i].nv && s.nt == files[i].nt);
    size_t nt = s.nt, open = 0;
    CHECK(mx_trisoup_check(&s, path, &open) == MX_OK);
    if (files[i].closed) CHECK(open == 0);
    double lo[3], hi[3];
    mx_trisoup_bbox(&s, lo, hi);
    printf(
        "%-22s nv=%zu nt=%zu degenerate=%zu open_edges=%zu read %.2f ms "
        "bbox [%g %g %g]-[%g %g %g]\n",
        files[i].name, s.nv, nt, nt - s.nt, open, 1e3 * (t1 - t0), lo[0], lo[1],
        lo[2], hi[0], hi[1], hi[2]);
    mx_trisoup_free(&s);
  }
}

/* ---- speed: large files written here ---------------------------------- */

static double file_mb(const char *path) {
  struct stat st;
  return stat(path, &st) == 0 ? (double)st.st_size / 1e6 : 0;
}

static void write_off(const char *path, const mx_trisoup *s) {
  FILE *f = fopen(path, "w");
  fprintf(f, "OFF\n%zu %zu 0\n", s->nv, s->nt);
  for (size_t v = 0; v < s->nv; v++)
    fprintf(f, "%.17g %.17g %.17g\n", s->x[v], s->y[v], s->z[v]);
  for (size_t t = 0; t < s->nt; t++)
    fprintf(f, "3 %u %u %u\n", s->tri[3 * t], s->tri[3 * t + 1],
            s->tri[3 * t + 2]);
  fclose(f);
}

static void write_stl_binary(const char *path, const mx_trisoup *s) {
  FILE *f = fopen(path, "wb");
  char header[80] = "mixoct test";
  uint32_t n = (uint32_t)s->nt;
  fwrite(header, 1, 80, f);
  fwrite(&n, 4, 1, f);
  for (size_t t = 0; t < s->nt; t++) {
    float r[12] = {0};
    for (int k = 0; k < 3; k++) {
      uint32_t v = s->tri[3 * t + k];
      r[3 + 3 * k] = (float)s->x[v];
      r[4 + 3 * k] = (float)s->y[v];
      r[5 + 3 * k] = (float)s->z[v];
    }
    uint16_t attr = 0;
    fwrite(r, 4, 12, f);
    fwrite(&attr, 2, 1, f);
  }
  fclose(f);
}

static void timed_read(reader_fn rd, const char *path, mx_trisoup *s,
                       const char *label) {
  double t0 = mx_wtime();
  CHECK(rd(path, s) == MX_OK);
  double dt = mx_wtime() - t0;
  printf(
      "speed: %-14s %8zu triangles, %6.1f MB in %7.1f ms: %6.1f MB/s, "
      "%5.2f M triangles/s\n",
      label, s->nt, file_mb(path), 1e3 * dt, file_mb(path) / dt,
      1e-6 * (double)s->nt / dt);
}

static void test_speed(void) {
  printf("-- reading speed\n");
  mx_trisoup demo, s;
  CHECK(mx_demo_surface(&demo, 7) == MX_OK);
  char path[128];
  tpath(path, sizeof path, "big.off");
  write_off(path, &demo);
  timed_read(mx_read_off, path, &s, "OFF");
  CHECK(s.nv == demo.nv && s.nt == demo.nt);
  CHECK(memcmp(s.x, demo.x, demo.nv * sizeof(double)) == 0);
  CHECK(memcmp(s.z, demo.z, demo.nv * sizeof(double)) == 0);
  CHECK(memcmp(s.tri, demo.tri, 3 * demo.nt * sizeof(uint32_t)) == 0);
  mx_trisoup_free(&s);
  unlink(path);
  tpath(path, sizeof path, "big.stl");
  write_stl_binary(path, &demo);
  timed_read(mx_read_stl, path, &s, "binary STL");
  CHECK(s.nv == demo.nv && s.nt == demo.nt);
  size_t open = 99;
  CHECK(mx_trisoup_check(&s, path, &open) == MX_OK && open == 0);
  mx_trisoup_free(&s);
  unlink(path);
  mx_trisoup_free(&demo);
  if (access(SURF "cortex.off", R_OK) != 0) {
    TEST_DATA_MISSING("%scortex.off: not present", SURF);
    return;
  }
  double best = INFINITY;
  for (int rep = 0; rep < 5; rep++) {
    double t0 = mx_wtime();
    CHECK(mx_read_off(SURF "cortex.off", &s) == MX_OK);
    best = fmin(best, mx_wtime() - t0);
    mx_trisoup_free(&s);
  }
  printf("speed: cortex.off (%.2f MB) read in %.2f ms (best of 5): %.1f MB/s\n",
         file_mb(SURF "cortex.off"), 1e3 * best,
         file_mb(SURF "cortex.off") / best);
}

/* ---- main ------------------------------------------------------------- */

static void remove_tmpdir(void) {
  remove_dir_files(tmpdir);
  rmdir(tmpdir);
}

int main(void) {
  strcpy(tmpdir, "/tmp/mixoct_readers_XXXXXX");
  if (!mkdtemp(tmpdir)) {
    perror("mkdtemp");
    return 1;
  }
  test_off();
  test_off_polygons();
  test_mdl();
  test_stl_ascii();
  test_stl_binary();
  test_obj();
  test_obj_quad();
  test_dispatch();
  test_degenerate();
  test_soup();
  test_reg();
  test_demo();
  test_samples();
  test_speed();
  remove_tmpdir();
  return TEST_DONE();
}
