/* The size map reader (src/io/read_sizemap.c, issue 27): small files of
 * every format written here, read back, and their points and sizes
 * compared with what was written:
 *  - plain text "x y z h" with comments and blank lines;
 *  - VTU, ascii and appended raw (Float64 and Float32 fields and points,
 *    UInt32 and UInt64 block headers), a point field picked by name or by
 *    the default rule, a cell field at the cells' centroids; a PolyData
 *    (.vtp) cell field over vertices, lines and polygons (VTK's order);
 *  - legacy VTK, ASCII and BINARY (big-endian), a point field (SCALARS,
 *    FIELD) and a cell field alone (list CELLS and 5.x OFFSETS), POLYDATA;
 *  - Gmsh .pos: SP, ST, SS, SH and second-order elements, comments, two
 *    time steps (the first read), several views (the first, or the one
 *    named), a vector element skipped with a warning.
 * The expected centroids are the nodes' sums divided by their count, in
 * the nodes' order, as the reader computes them: equal to the bit.
 * Bad inputs each give MX_EINPUT, no arrays, and one message naming the
 * file and, where there is one, the line ("FILE:LINE:") or the byte. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "check.h"
#include "file_util.h"
#include "io/read_sizemap.h"
#include "mixoct.h"

static char tmpdir[64];
static char captured[8192];

static const char *tpath(const char *name) {
  static char buf[8][256];
  static int k = 0;
  k = (k + 1) % 8;
  snprintf(buf[k], sizeof buf[k], "%s/%s", tmpdir, name);
  return buf[k];
}

static void write_text(const char *path, const char *s) { write_bytes_file(path, s, strlen(s)); }

static int read_captured(const char *path, const char *field, double **xyz, double **h,
                         size_t *n) {
  const char *errf = tpath("stderr.txt");
  capture_stderr_begin(errf);
  const int st = mx_sizemap_read(path, field, xyz, h, n);
  capture_stderr_end(errf, captured, sizeof captured);
  return st;
}

/* Reads path (field: NULL for the default): MX_OK and exactly the n points
 * and sizes wanted; a message holding warn when not NULL. */
static void expect_map(const char *path, const char *field, size_t n, const double *want_xyz,
                       const double *want_h, const char *warn) {
  double *xyz, *h;
  size_t got;
  const int st = read_captured(path, field, &xyz, &h, &got);
  int ok = st == MX_OK && got == n && xyz && h;
  for (size_t i = 0; ok && i < n; i++) {
    ok = h[i] == want_h[i];
    for (int d = 0; ok && d < 3; d++) ok = xyz[3 * i + (size_t)d] == want_xyz[3 * i + (size_t)d];
    if (!ok)
      fprintf(stderr, "point %zu: (%.17g %.17g %.17g) h %.17g, want (%.17g %.17g %.17g) h %.17g\n",
              i, xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2], h[i], want_xyz[3 * i],
              want_xyz[3 * i + 1], want_xyz[3 * i + 2], want_h[i]);
  }
  if (warn && !strstr(captured, warn)) {
    fprintf(stderr, "expected a warning holding '%s'\n", warn);
    ok = 0;
  }
  if (!warn && captured[0]) ok = 0; /* no message at all */
  if (!ok) fprintf(stderr, "%s: status %d, %zu points (want %zu)\n%s", path, st, got, n, captured);
  CHECK(ok);
  printf("%s %s%s%s\n", ok ? "ok  " : "FAIL", strrchr(path, '/') + 1, field ? " field " : "",
         field ? field : "");
  mx_free(xyz);
  mx_free(h);
}

/* Reading path fails with MX_EINPUT, no arrays, and a message holding
 * "<path>:<line>:" (line > 0) or "<path>:" and the needle. */
static void expect_fail(const char *path, const char *field, long line, const char *needle) {
  double *xyz = (double *)1, *h = (double *)1;
  size_t n = 1;
  const int st = read_captured(path, field, &xyz, &h, &n);
  char where[512];
  if (line > 0)
    snprintf(where, sizeof where, "%s:%ld:", path, line);
  else
    snprintf(where, sizeof where, "%s:", path);
  const int ok = st == MX_EINPUT && !xyz && !h && n == 0 && strstr(captured, where) &&
                 strstr(captured, "error") && (!needle || strstr(captured, needle));
  if (!ok)
    fprintf(stderr, "%s: status %d, expected MX_EINPUT with '%s' and '%s' in: %s\n", path, st,
            where, needle ? needle : "", captured);
  CHECK(ok);
  printf("%s %s", ok ? "ok  " : "FAIL", captured[0] ? captured : "(no message)\n");
}

/* text with its first `old` replaced by repl (malloc'ed). */
static char *replace(const char *text, const char *old, const char *repl) {
  const char *at = strstr(text, old);
  if (!at) abort();
  const size_t a = (size_t)(at - text), ol = strlen(old), rl = strlen(repl);
  char *out = malloc(strlen(text) - ol + rl + 1);
  if (!out) abort();
  memcpy(out, text, a);
  memcpy(out + a, repl, rl);
  strcpy(out + a + rl, at + ol);
  return out;
}

/* Writes text to tmpdir/name and expects it to fail. */
static void bad_text(const char *name, const char *text, const char *field, long line,
                     const char *needle) {
  const char *p = tpath(name);
  write_text(p, text);
  expect_fail(p, field, line, needle);
}

/* ---- bytes ------------------------------------------------------------------ */

typedef struct {
  char *b;
  size_t n, cap;
} bytes;

static void put(bytes *B, const void *p, size_t n) {
  if (B->n + n + 1 > B->cap) {
    B->cap = 2 * (B->n + n + 1024);
    B->b = realloc(B->b, B->cap);
    if (!B->b) abort();
  }
  memcpy(B->b + B->n, p, n);
  B->n += n;
}

static void puts_(bytes *B, const char *s) { put(B, s, strlen(s)); }

/* Host order (the VTU files say which), or big-endian (legacy BINARY). */
static void put_f64(bytes *B, double v) { put(B, &v, 8); }
static void put_f32(bytes *B, float v) { put(B, &v, 4); }
static void put_u32(bytes *B, uint32_t v) { put(B, &v, 4); }
static void put_u64(bytes *B, uint64_t v) { put(B, &v, 8); }

static void put_be(bytes *B, uint64_t v, int size) {
  unsigned char c[8];
  for (int i = 0; i < size; i++) c[i] = (unsigned char)(v >> (8 * (size - 1 - i)));
  put(B, c, (size_t)size);
}

static void put_be_f64(bytes *B, double d) {
  uint64_t v;
  memcpy(&v, &d, 8);
  put_be(B, v, 8);
}

static void put_be_f32(bytes *B, float f) {
  uint32_t v;
  memcpy(&v, &f, 4);
  put_be(B, v, 4);
}

static void write_out(const char *path, bytes *B) {
  write_bytes_file(path, B->b, B->n);
  free(B->b);
  *B = (bytes){0};
}

#define HOST_ORDER (__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__ ? "LittleEndian" : "BigEndian")

/* ---- the shared example: a tetrahedron and a triangle ---------------------- */

/* 5 points; cells: tetrahedron 0 1 2 3, triangle 1 2 4. Sizes exact in
 * float. */
static const double P5[15] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 1, 1};
static const double H5[5] = {0.125, 0.25, 0.5, 1, 2};
static const double HC[2] = {0.75, 1.5}; /* the cells' */
static const int CELLS[7] = {0, 1, 2, 3, 1, 2, 4};
static const int CELL_N[2] = {4, 3};

/* The centroids of cells (CELL_N nodes each from CELLS) of points P. */
static void centroids(const double *P, const int *cells, const int *cn, int nc, double *out) {
  for (int c = 0, k = 0; c < nc; k += cn[c++]) {
    double s[3] = {0, 0, 0};
    for (int j = 0; j < cn[c]; j++)
      for (int d = 0; d < 3; d++) s[d] += P[3 * cells[k + j] + d];
    for (int d = 0; d < 3; d++) out[3 * c + d] = s[d] / cn[c];
  }
}

/* ---- plain text ------------------------------------------------------------- */

static void test_text(void) {
  const char *p = tpath("map.txt");
  write_text(p,
             "# x y z h\n"
             "0 0 0 1\n"
             "\n"
             "   \t\n"
             "1.5 -2 3e1 0.25   # a comment\r\n"
             "# the last\n"
             "-1 -1 -1 1e-3");
  const double xyz3[9] = {0, 0, 0, 1.5, -2, 30, -1, -1, -1}, h3[3] = {1, 0.25, 1e-3};
  expect_map(p, NULL, 3, xyz3, h3, NULL);
  const char *q = tpath("map.xyzh"); /* any other extension is text */
  write_text(q, "1 2 3 4\n");
  const double x1[3] = {1, 2, 3}, h1[1] = {4};
  expect_map(q, NULL, 1, x1, h1, NULL);
  expect_map(q, "h", 1, x1, h1, "is not used"); /* a field name: a warning */

  bad_text("nan.txt", "0 0 0 1\n0 0 0 nan\n", NULL, 2, "'nan' is not a size");
  bad_text("neg.txt", "# c\n\n0 0 0 -0.5\n", NULL, 3, "'-0.5' is not a size");
  bad_text("zero.txt", "0 0 0 1\n1 1 1 0\n", NULL, 2, "'0' is not a size");
  bad_text("inf.txt", "0 0 0 inf\n", NULL, 1, "'inf' is not a size");
  bad_text("infxyz.txt", "0 0 0 1\n0 -inf 0 1\n", NULL, 2, "not a finite coordinate");
  bad_text("three.txt", "0 0 0 1\n\n1 2 0.5\n", NULL, 3, "3 numbers, expected 4");
  bad_text("five.txt", "0 0 0 1 2\n", NULL, 1, "more than 4 numbers");
  bad_text("word.txt", "0 0 0 1\n0 0 zero 1\n", NULL, 2, "'zero' is not a number");
  bad_text("comma.txt", "0,0,0,1\n", NULL, 1, "is not a number");
  write_bytes_file(tpath("nul.txt"), "0 0 0 1\n0 0\0 0 1\n", 16);
  expect_fail(tpath("nul.txt"), NULL, 2, "NUL byte");
  bad_text("comments.txt", "# nothing\n\n", NULL, 0, "no point");
  bad_text("empty.txt", "", NULL, 0, "empty");
  expect_fail(tpath("missing.txt"), NULL, 0, "cannot open");
}

/* ---- VTU -------------------------------------------------------------------- */

/* An ascii VTU: the 5 points and 2 cells, the point fields h (Float64) and
 * temp, the cell field err. */
static const char *VTU_ASCII =
    "<?xml version=\"1.0\"?>\n"
    "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\">\n"
    "<!-- a comment -->\n"
    "<UnstructuredGrid>\n"
    "<Piece NumberOfPoints=\"5\" NumberOfCells=\"2\">\n"
    "<PointData Scalars=\"temp\">\n"
    "<DataArray type=\"Float32\" Name=\"temp\" format=\"ascii\">300 301 302 303 304</DataArray>\n"
    "<DataArray type=\"Float64\" Name=\"vel\" NumberOfComponents=\"3\" format=\"ascii\">\n"
    "1 1 1 1 1 1 1 1 1 1 1 1 1 1 1</DataArray>\n"
    "<DataArray type=\"Float64\" Name=\"h\" format=\"ascii\">\n"
    "0.125 0.25 0.5 1 2\n"
    "</DataArray>\n"
    "</PointData>\n"
    "<CellData>\n"
    "<DataArray type=\"Float64\" Name=\"err\" format=\"ascii\">0.75 1.5</DataArray>\n"
    "<DataArray type=\"Int32\" Name=\"material\" format=\"ascii\">1 2</DataArray>\n"
    "</CellData>\n"
    "<Points>\n"
    "<DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">\n"
    "0 0 0 1 0 0 0 1 0\n0 0 1 1 1 1\n"
    "</DataArray>\n"
    "</Points>\n"
    "<Cells>\n"
    "<DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">0 1 2 3 1 2 4</DataArray>\n"
    "<DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">4 7</DataArray>\n"
    "<DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">10 5</DataArray>\n"
    "</Cells>\n"
    "</Piece>\n"
    "</UnstructuredGrid>\n"
    "</VTKFile>\n";

/* An appended raw VTU of the 5 points (Float32 when f32), the point
 * field `name` (H5; Float32 when f32) and the cell field "err" (HC), block
 * headers of hsize bytes (4 or 8); size 1 replaced by *bad_h when not NULL. */
static void write_vtu_raw(const char *path, const char *name, int f32, int hsize,
                          const double *bad_h) {
  const char *ft = f32 ? "Float32" : "Float64";
  const size_t fs = f32 ? 4 : 8, hs = (size_t)hsize;
  const size_t o_h = 0, o_err = o_h + hs + 5 * fs, o_pts = o_err + hs + 2 * 8,
               o_con = o_pts + hs + 15 * fs, o_off = o_con + hs + 7 * 4,
               o_typ = o_off + hs + 2 * 4;
  char head[4096];
  snprintf(head, sizeof head,
           "<?xml version=\"1.0\"?>\n"
           "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"%s\" "
           "header_type=\"%s\">\n"
           "  <UnstructuredGrid>\n"
           "    <Piece NumberOfPoints=\"5\" NumberOfCells=\"2\">\n"
           "      <PointData>\n"
           "        <DataArray type=\"%s\" Name=\"%s\" format=\"appended\" offset=\"%zu\"/>\n"
           "      </PointData>\n"
           "      <CellData>\n"
           "        <DataArray type=\"Float64\" Name=\"err\" format=\"appended\" offset=\"%zu\"/>\n"
           "      </CellData>\n"
           "      <Points>\n"
           "        <DataArray type=\"%s\" NumberOfComponents=\"3\" format=\"appended\" "
           "offset=\"%zu\"/>\n"
           "      </Points>\n"
           "      <Cells>\n"
           "        <DataArray type=\"Int32\" Name=\"connectivity\" format=\"appended\" "
           "offset=\"%zu\"/>\n"
           "        <DataArray type=\"Int32\" Name=\"offsets\" format=\"appended\" offset=\"%zu\"/>\n"
           "        <DataArray type=\"UInt8\" Name=\"types\" format=\"appended\" offset=\"%zu\"/>\n"
           "      </Cells>\n"
           "    </Piece>\n"
           "  </UnstructuredGrid>\n"
           "  <AppendedData encoding=\"raw\">\n   _",
           HOST_ORDER, hsize == 8 ? "UInt64" : "UInt32", ft, name, o_h, o_err, ft, o_pts, o_con,
           o_off, o_typ);
  bytes B = {0};
  puts_(&B, head);
#define BLOCK_HEAD(nb) (hsize == 8 ? put_u64(&B, (uint64_t)(nb)) : put_u32(&B, (uint32_t)(nb)))
  BLOCK_HEAD(5 * fs);
  for (int i = 0; i < 5; i++) {
    const double v = i == 1 && bad_h ? *bad_h : H5[i];
    f32 ? put_f32(&B, (float)v) : put_f64(&B, v);
  }
  BLOCK_HEAD(16);
  for (int i = 0; i < 2; i++) put_f64(&B, HC[i]);
  BLOCK_HEAD(15 * fs);
  for (int i = 0; i < 15; i++) f32 ? put_f32(&B, (float)P5[i]) : put_f64(&B, P5[i]);
  BLOCK_HEAD(28);
  for (int i = 0; i < 7; i++) put_u32(&B, (uint32_t)CELLS[i]);
  BLOCK_HEAD(8);
  put_u32(&B, 4);
  put_u32(&B, 7);
  BLOCK_HEAD(2);
  put(&B, "\x0a\x05", 2);
#undef BLOCK_HEAD
  puts_(&B, "\n  </AppendedData>\n</VTKFile>\n");
  write_out(path, &B);
}

/* A PolyData: 5 points, a vertex (4), a line (2 3), a triangle (0 1 2) and
 * a quadrilateral (0 1 4 3) given Polys before Lines and Verts in the file:
 * the cells are vertices, lines, polygons whatever the file's order. */
static const char *VTP_ASCII =
    "<VTKFile type=\"PolyData\" version=\"1.0\" byte_order=\"LittleEndian\">\n"
    "<PolyData>\n"
    "<Piece NumberOfPoints=\"5\" NumberOfVerts=\"1\" NumberOfLines=\"1\" NumberOfStrips=\"0\" "
    "NumberOfPolys=\"2\">\n"
    "<CellData><DataArray type=\"Int32\" Name=\"Size\" format=\"ascii\">10 20 30 40</DataArray>"
    "</CellData>\n"
    "<Points><DataArray type=\"Float32\" NumberOfComponents=\"3\" format=\"ascii\">\n"
    "0 0 0 1 0 0 0 1 0 0 0 1 1 1 1</DataArray></Points>\n"
    "<Polys>\n"
    "<DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">0 1 2 0 1 4 3</DataArray>\n"
    "<DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">3 7</DataArray>\n"
    "</Polys>\n"
    "<Lines>\n"
    "<DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">2 3</DataArray>\n"
    "<DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">2</DataArray>\n"
    "</Lines>\n"
    "<Verts>\n"
    "<DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">4</DataArray>\n"
    "<DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">1</DataArray>\n"
    "</Verts>\n"
    "</Piece>\n</PolyData>\n</VTKFile>\n";

static const int PD_CELLS[10] = {4, 2, 3, 0, 1, 2, 0, 1, 4, 3};
static const int PD_N[4] = {1, 2, 3, 4};
static const double PD_H[4] = {10, 20, 30, 40};

static void test_vtu(void) {
  double cen[6], pdc[12];
  centroids(P5, CELLS, CELL_N, 2, cen);
  centroids(P5, PD_CELLS, PD_N, 4, pdc);
  const double temp[5] = {300, 301, 302, 303, 304};
  const char *p = tpath("ascii.vtu");
  write_text(p, VTU_ASCII);
  expect_map(p, NULL, 5, P5, H5, NULL);   /* h: a size name */
  expect_map(p, "h", 5, P5, H5, NULL);
  expect_map(p, "temp", 5, P5, temp, NULL);
  expect_map(p, "err", 2, cen, HC, NULL); /* a cell field: the centroids */
  expect_fail(p, "vel", 8, "'vel' has 3 components");
  expect_fail(p, "H", 0, "no field named 'H' (point fields: 'temp', 'vel' (3 components), 'h'; "
                         "cell fields: 'err', 'material')");
  for (int hs = 4; hs <= 8; hs += 4)
    for (int f32 = 0; f32 <= 1; f32++) {
      char name[64];
      snprintf(name, sizeof name, "raw_%s_h%d.vtu", f32 ? "f32" : "f64", hs);
      write_vtu_raw(tpath(name), "target_size", f32, hs, NULL);
      expect_map(tpath(name), NULL, 5, P5, H5, NULL);
      expect_map(tpath(name), "err", 2, cen, HC, NULL);
    }
  const char *q = tpath("pd.vtp");
  write_text(q, VTP_ASCII);
  expect_map(q, NULL, 4, pdc, PD_H, NULL); /* Size: a size name in any case */

  /* errors */
  write_vtu_raw(tpath("zero.vtu"), "h", 0, 8, &(double){0.0});
  expect_fail(tpath("zero.vtu"), NULL, 0, "field 'h': point 1 has size 0");
  expect_fail(tpath("zero.vtu"), NULL, 0, "(at byte");
  write_vtu_raw(tpath("nan.vtu"), "h", 1, 4, &(double){NAN});
  expect_fail(tpath("nan.vtu"), NULL, 0, "point 1 has size nan");
  write_vtu_raw(tpath("inf.vtu"), "h", 0, 4, &(double){-INFINITY});
  expect_fail(tpath("inf.vtu"), NULL, 0, "point 1 has size -inf");
  write_vtu_raw(tpath("neg.vtu"), "h", 0, 4, &(double){-2});
  expect_fail(tpath("neg.vtu"), NULL, 0, "point 1 has size -2");
  /* the default: two point fields, neither a size name */
  write_vtu_raw(tpath("other.vtu"), "error", 0, 4, NULL);
  expect_map(tpath("other.vtu"), NULL, 5, P5, H5, NULL); /* one point field: it */
  char *two = text_edit_line(VTU_ASCII, 11, "0.125 0.25 0.5 1 2 </DataArray><DataArray "
                             "type=\"Float64\" Name=\"k\" format=\"ascii\">1 1 1 1 1");
  char *amb = replace(two, "Name=\"h\"", "Name=\"g\"");
  bad_text("ambiguous.vtu", amb, NULL, 0,
           "5 fields of one component, none named size, h, target_size or sizes: name the one "
           "to read (point fields: 'temp', 'vel' (3 components), 'g', 'k'; cell fields: 'err', "
           "'material')");
  free(two);
  free(amb);
  char *neg = text_edit_line(VTU_ASCII, 11, "0.125 0.25 -0.5 1 2");
  bad_text("neg_ascii.vtu", neg, NULL, 11, "point 2 has size -0.5");
  free(neg);
  char *nan = text_edit_line(VTU_ASCII, 11, "0.125 0.25 0.5\nNaN 2");
  bad_text("nan_ascii.vtu", nan, NULL, 12, "'NaN' is not a finite number");
  free(nan);
  char *few = text_edit_line(VTU_ASCII, 11, "0.125 0.25 0.5 1");
  bad_text("few_ascii.vtu", few, NULL, 12, "h: expected 5 values, found 4");
  free(few);
  /* truncated: the appended data cut short */
  write_vtu_raw(tpath("cut.vtu"), "h", 0, 8, NULL);
  size_t len = 0;
  char *all = slurp(tpath("cut.vtu"), &len);
  write_bytes_file(tpath("cut.vtu"), all, len - 60);
  expect_fail(tpath("cut.vtu"), NULL, 0, "cut short");
  /* cut in the points, but ending as a complete file would */
  bytes B = {0};
  put(&B, all, len - 200);
  puts_(&B, "\n  </AppendedData>\n</VTKFile>\n");
  write_out(tpath("cut2.vtu"), &B);
  expect_fail(tpath("cut2.vtu"), NULL, 0, "truncated file");
  free(all);
  /* counts far larger than the file */
  char *huge = text_edit_line(VTU_ASCII, 5, "<Piece NumberOfPoints=\"1000000000000\" NumberOfCells=\"2\">");
  bad_text("huge_points.vtu", huge, NULL, 19, "the file is too short");
  free(huge);
  huge = text_edit_line(VTU_ASCII, 5, "<Piece NumberOfPoints=\"5\" NumberOfCells=\"1000000000000\">");
  bad_text("huge_cells.vtu", huge, "err", 15, "the file is too short");
  free(huge);
  char *badnode = text_edit_line(VTU_ASCII, 25, "<DataArray type=\"Int64\" Name=\"connectivity\" "
                                 "format=\"ascii\">0 1 2 3 1 2 5</DataArray>");
  bad_text("badnode.vtu", badnode, "err", 25, "cell 1: node 5 out of range (5 points");
  free(badnode);
  char *b64 = text_edit_line(VTU_ASCII, 11, "AAAA");
  char *base64 = replace(b64, "Name=\"h\" format=\"ascii\"", "Name=\"h\" format=\"binary\"");
  /* format="binary" is base64 text: "AAAA" gives 3 bytes, not a 4-byte header */
  bad_text("base64.vtu", base64, NULL, 12, "the base64 text ends before its 4 bytes");
  free(b64);
  free(base64);
  bad_text("compressed.vtu",
           "<VTKFile type=\"UnstructuredGrid\" compressor=\"vtkZstdDataCompressor\">\n</VTKFile>\n",
           NULL, 1, "compressor \"vtkZstdDataCompressor\" is not supported");
  bad_text("pvtu.vtu", "<VTKFile type=\"PUnstructuredGrid\">\n</VTKFile>\n", NULL, 1,
           "not read here");
  bad_text("nofield.vtu",
           "<VTKFile type=\"UnstructuredGrid\">\n<UnstructuredGrid>\n"
           "<Piece NumberOfPoints=\"1\" NumberOfCells=\"0\">\n"
           "<Points><DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">0 0 0"
           "</DataArray></Points>\n</Piece></UnstructuredGrid>\n</VTKFile>\n",
           NULL, 0, "no field of one component to take the sizes from (no point or cell field)");
  bad_text("empty.vtu", "", NULL, 0, "empty file");
  bad_text("text.vtu", "0 0 0 1\n", NULL, 1, "not a VTK file");
}

/* ---- legacy VTK ------------------------------------------------------------- */

static void test_legacy(void) {
  double cen[6], pdc[12];
  centroids(P5, CELLS, CELL_N, 2, cen);
  centroids(P5, PD_CELLS, PD_N, 4, pdc);
  /* ASCII, classic CELLS list, a point field (SCALARS) and a cell field
   * (FIELD) */
  const char *ascii =
      "# vtk DataFile Version 3.0\n"
      "a size map\n"
      "ASCII\n"
      "DATASET UNSTRUCTURED_GRID\n"
      "POINTS 5 double\n"
      "0 0 0 1 0 0 0 1 0\n"
      "0 0 1 1 1 1\n"
      "CELLS 2 9\n"
      "4 0 1 2 3\n"
      "3 1 2 4\n"
      "CELL_TYPES 2\n"
      "10 5\n"
      "CELL_DATA 2\n"
      "FIELD FieldData 1\n"
      "err 1 2 double\n"
      "0.75 1.5\n"
      "POINT_DATA 5\n"
      "VECTORS vel double\n"
      "1 1 1 1 1 1 1 1 1 1 1 1 1 1 1\n"
      "SCALARS h double 1\n"
      "LOOKUP_TABLE default\n"
      "0.125 0.25 0.5\n"
      "1 2\n";
  const char *p = tpath("ascii.vtk");
  write_text(p, ascii);
  expect_map(p, NULL, 5, P5, H5, NULL);
  expect_map(p, "err", 2, cen, HC, NULL);
  char *neg = text_edit_line(ascii, 23, "1 -2");
  bad_text("neg.vtk", neg, NULL, 23, "field 'h': point 4 has size -2");
  free(neg);
  char *zero = text_edit_line(ascii, 16, "0 1.5");
  bad_text("zero_cell.vtk", zero, "err", 16, "field 'err': cell 0 has size 0");
  free(zero);
  char *inf = text_edit_line(ascii, 22, "0.125 inf 0.5");
  bad_text("inf.vtk", inf, NULL, 22, "'inf' is not a finite number");
  free(inf);
  char *w1 = text_edit_line(ascii, 15, "err 1 3 double");
  char *wrong = text_edit_line(w1, 16, "0.75 1.5 2");
  bad_text("count.vtk", wrong, "err", 15, "err: 3 values for 2 cells");
  free(w1);
  free(wrong);
  char *big = text_edit_line(ascii, 5, "POINTS 100000000 double");
  bad_text("huge.vtk", big, NULL, 5, "POINTS: 300000000 values announced but the file is too short");
  free(big);
  char *bigc = text_edit_line(ascii, 8, "CELLS 2 1000000000000");
  bad_text("huge_cells.vtk", bigc, "err", 8, "the file is too short");
  free(bigc);
  char *tensors = text_edit_line(ascii, 18, "TENSORS t double");
  bad_text("tensors.vtk", tensors, "h", 0,
           "no field named 'h' (cell fields: 'err'; the attributes from TENSORS on were not read)");
  free(tensors);

  /* ASCII 5.x, a cell field alone (SCALARS in CELL_DATA) */
  const char *v5 =
      "# vtk DataFile Version 5.1\n"
      "vtk output\n"
      "ASCII\n"
      "DATASET UNSTRUCTURED_GRID\n"
      "POINTS 5 float\n"
      "0 0 0 1 0 0 0 1 0 0 0 1 1 1 1\n"
      "CELLS 3 7\n"
      "OFFSETS vtktypeint64\n"
      "0 4 7\n"
      "CONNECTIVITY vtktypeint64\n"
      "0 1 2 3 1 2 4\n"
      "CELL_TYPES 2\n"
      "10\n5\n"
      "CELL_DATA 2\n"
      "SCALARS target_size float\n"
      "LOOKUP_TABLE default\n"
      "0.75 1.5\n";
  const char *q = tpath("v5_cells.vtk");
  write_text(q, v5);
  expect_map(q, NULL, 2, cen, HC, NULL);
  char *off = text_edit_line(v5, 9, "0 4 3");
  bad_text("offsets.vtk", off, NULL, 9, "cell 1: offsets 4..3 are not a non-empty increasing range");
  free(off);

  /* BINARY, big-endian: the classic list, a float point field, a double
   * cell field; then the same with a NaN, and cut short */
  for (int variant = 0; variant < 5; variant++) {
    bytes B = {0};
    puts_(&B, "# vtk DataFile Version 4.2\nbinary map\nBINARY\nDATASET UNSTRUCTURED_GRID\n");
    puts_(&B, variant == 3 ? "POINTS 100 double\n" : "POINTS 5 double\n");
    for (int i = 0; i < 15; i++) put_be_f64(&B, P5[i]);
    puts_(&B, "\nCELLS 2 9\n");
    for (int c = 0, k = 0; c < 2; k += CELL_N[c++]) {
      put_be(&B, (uint64_t)CELL_N[c], 4);
      for (int j = 0; j < CELL_N[c]; j++) put_be(&B, (uint64_t)CELLS[k + j], 4);
    }
    puts_(&B, "\nCELL_TYPES 2\n");
    put_be(&B, 10, 4);
    put_be(&B, 5, 4);
    puts_(&B, "\nCELL_DATA 2\nSCALARS err double\nLOOKUP_TABLE default\n");
    for (int c = 0; c < 2; c++) put_be_f64(&B, HC[c]);
    if (variant != 4) { /* 4: the cell field alone */
      puts_(&B, "\nPOINT_DATA 5\nSCALARS sizes float 1\nLOOKUP_TABLE default\n");
      for (int i = 0; i < 5; i++) put_be_f32(&B, i == 3 && variant == 1 ? NAN : (float)H5[i]);
    }
    puts_(&B, "\n");
    if (variant == 2) B.n -= 7; /* the sizes cut short */
    const char *b = tpath("binary.vtk");
    write_out(b, &B);
    if (variant == 0) {
      expect_map(b, NULL, 5, P5, H5, NULL);
      expect_map(b, "err", 2, cen, HC, NULL);
    } else if (variant == 1) {
      expect_fail(b, NULL, 0, "field 'sizes': point 3 has size nan");
    } else if (variant == 2) {
      expect_fail(b, NULL, 0, "sizes: 5 values of 4 bytes announced but only 14 bytes");
    } else if (variant == 3) { /* POINTS announcing more than there is */
      expect_fail(b, NULL, 0, "POINTS: 300 values of 8 bytes announced but only");
    } else {
      expect_map(b, NULL, 2, cen, HC, NULL);
    }
  }

  /* POLYDATA, ASCII, a cell field: vertices, lines, polygons */
  const char *pd =
      "# vtk DataFile Version 3.0\n"
      "poly\n"
      "ASCII\n"
      "DATASET POLYDATA\n"
      "POINTS 5 float\n"
      "0 0 0 1 0 0 0 1 0 0 0 1 1 1 1\n"
      "POLYGONS 2 9\n"
      "3 0 1 2\n"
      "4 0 1 4 3\n"
      "VERTICES 1 2\n"
      "1 4\n"
      "LINES 1 3\n"
      "2 2 3\n"
      "CELL_DATA 4\n"
      "SCALARS size int\n"
      "LOOKUP_TABLE default\n"
      "10 20 30 40\n";
  write_text(tpath("pd.vtk"), pd);
  expect_map(tpath("pd.vtk"), NULL, 4, pdc, PD_H, NULL);
  char *badlist = text_edit_line(pd, 9, "5 0 1 4 3");
  bad_text("badlist.vtk", badlist, NULL, 9, "cell 3: 5 nodes, but 4 values are left");
  free(badlist);
  bad_text("grid.vtk", "# vtk DataFile Version 3.0\nx\nASCII\nDATASET STRUCTURED_POINTS\n", NULL,
           4, "only UNSTRUCTURED_GRID and POLYDATA");
  bad_text("empty.vtk", "", NULL, 0, "empty file");
}

/* ---- Gmsh .pos -------------------------------------------------------------- */

static void test_pos(void) {
  const char *pos =
      "// a size map from a solver\n"
      "General.Terminal = 0; /* a statement outside the views */\n"
      "View \"h\" {\n"
      "SP(0.5, 0.5, 0.5){0.25};\n"
      "/* a triangle,\n   two time steps */\n"
      "ST(0,0,0, 1,0,0, 0,1,0){1,2,4, 9,9,9};\n"
      "VP(0,0,0){1,2,3};\n"
      "SS(0,0,0,1,0,0,0,1,0,0,0,1){0.5,0.5,0.5,0.5};\n"
      "SH(0,0,0, 1,0,0, 1,1,0, 0,1,0, 0,0,1, 1,0,1, 1,1,1, 0,1,1)\n"
      "  {1,2,3,4,5,6,7,8};\n"
      "T2(10,10,0){\"a label\"};\n"
      "};\n"
      "View \"error\" {\n"
      "SL(0,0,0,2,0,0){-1, 0};\n" /* not a size: never read as one */
      "SL2(0,0,0,2,0,0,1,0,0){1e-3,2e-3,3e-3};\n"
      "TIME{0};\n"
      "};\n";
  const char *p = tpath("map.pos");
  write_text(p, pos);
  const double xyz[3 * 16] = {0.5, 0.5, 0.5, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0,
                              0,   1,   0,   0, 0, 1, 0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0,
                              0,   0,   1,   1, 0, 1, 1, 1, 1, 0, 1, 1};
  const double h[16] = {0.25, 1, 2, 4, 0.5, 0.5, 0.5, 0.5, 1, 2, 3, 4, 5, 6, 7, 8};
  expect_map(p, NULL, 16, xyz, h, "view \"h\": 1 vector or tensor elements skipped");
  char *only = text_edit_line(pos, 15, "SL(0,0,0,2,0,0){1, 1};");
  write_text(tpath("second.pos"), only);
  free(only);
  const double xyz2[15] = {0, 0, 0, 2, 0, 0, 0, 0, 0, 2, 0, 0, 1, 0, 0};
  const double h2[5] = {1, 1, 1e-3, 2e-3, 3e-3};
  expect_map(tpath("second.pos"), "error", 5, xyz2, h2, NULL);
  expect_fail(p, "error", 15, "view \"error\": SL: node 0 has size -1");
  expect_fail(p, "u", 0, "no view named \"u\" (views: \"h\", \"error\")");

  char *e = text_edit_line(pos, 4, "SP(0.5, 0.5, 0.5){0};");
  bad_text("zero.pos", e, NULL, 4, "SP: node 0 has size 0");
  free(e);
  e = text_edit_line(pos, 7, "ST(0,0,0, 1,0,0, 0,1,0){1,\nNaN,4};");
  bad_text("nan.pos", e, NULL, 8, "ST: node 1 has size nan");
  free(e);
  e = text_edit_line(pos, 4, "SP(0.5, 0.5){1};");
  bad_text("coords.pos", e, NULL, 4, "SP: 2 coordinates, expected 3");
  free(e);
  e = text_edit_line(pos, 7, "ST(0,0,0, 1,0,0, 0,1,0){1,2,4,9};");
  bad_text("steps.pos", e, NULL, 7, "ST: 4 values, expected a multiple of 3 (1 a node for each time step)");
  free(e);
  e = text_edit_line(pos, 4, "SP(0.5, 0.5, sqrt(2)){1};");
  bad_text("expr.pos", e, NULL, 4, "is not a number");
  free(e);
  e = text_edit_line(pos, 4, "SX(0.5, 0.5, 0.5){1};");
  bad_text("unknown.pos", e, NULL, 4, "unknown element 'SX'");
  free(e);
  e = text_edit_line(pos, 4, "SP(0.5, 0.5, 0.5){1}");
  bad_text("semicolon.pos", e, NULL, 7, "expected ';', found 'ST(0,0,0,'");
  free(e);
  bad_text("comment.pos", "View \"a\" {\nSP(0,0,0){1};\n/* never\nclosed\n", NULL, 3,
           "comment '/*' never closed");
  bad_text("string.pos", "View \"a {\nSP(0,0,0){1};\n", NULL, 1, "string never closed");
  bad_text("noview.pos", "// nothing\n", NULL, 0, "no view");
  bad_text("novalue.pos", "View \"a\" { VP(0,0,0){1,2,3}; };\n", NULL, 0, "no point");
  bad_text("binary.pos", "View \"a\" {\n\x01\x02\x03", NULL, 2, "expected an element");
  bad_text("empty.pos", "", NULL, 0, "empty file");
}

int main(void) {
  snprintf(tmpdir, sizeof tmpdir, "/tmp/mx_sizemap_XXXXXX");
  if (!mkdtemp(tmpdir)) {
    perror("mkdtemp");
    return 2;
  }
  test_text();
  test_vtu();
  test_legacy();
  test_pos();
  remove_dir_files(tmpdir);
  rmdir(tmpdir);
  return TEST_DONE();
}
