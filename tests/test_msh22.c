/* Reading Gmsh MSH 2.2 (src/io/read_msh22.c) and VTK files with volume and
 * boundary cells (src/io/vtk_cells.c), on files written here from the
 * formats' documentation: two tetrahedra listed out of element-tag order,
 * one with a physical tag and one with only an elementary tag, a boundary
 * triangle, a point and a line element; the same in binary in both byte
 * orders; broken files. What is read is compared with what was written:
 * the cells in tag order, labels physical-else-elementary, the triangle a
 * tagged face, the names of dimension 2. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "base/common.h"
#include "check.h"
#include "io/read_mesh.h"
#include "soa/mesh.h"

static const char *path_of(const char *name) {
  static char p[256];
  snprintf(p, sizeof p, "msh22_%s", name);
  return p;
}

static void write_bytes(const char *name, const void *b, size_t n) {
  FILE *f = fopen(path_of(name), "wb");
  if (!f || fwrite(b, 1, n, f) != n) abort();
  fclose(f);
}

static const char ascii22[] =
    "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n"
    "$PhysicalNames\n2\n2 5 \"bottom\"\n3 2 \"vol\"\n$EndPhysicalNames\n"
    "$Nodes\n5\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n5 1 1 1\n$EndNodes\n"
    "$Elements\n5\n"
    "1 15 2 0 1 1\n"             /* a point: skipped */
    "2 1 2 0 1 1 2\n"            /* a line: skipped */
    "3 2 2 5 20 1 2 3\n"         /* a triangle, physical 5 */
    "9 4 2 2 11 1 2 3 4\n"       /* tet tag 9, physical 2 */
    "7 4 2 0 12 2 3 4 5\n"       /* tet tag 7, no physical: elementary 12 */
    "$EndElements\n";

/* What every variant must read: tag 7 first. */
static void expect_mesh(const char *name) {
  mx_mesh_data m;
  const int st = mx_read_mesh(path_of(name), &m);
  CHECK(st == MX_OK);
  if (st != MX_OK) return;
  static const uint32_t rows[2][4] = {{1, 2, 3, 4}, {0, 1, 2, 3}};
  CHECK(m.nnodes == 5 && m.ncells == 2);
  if (m.nnodes == 5) CHECK(m.xyz[12] == 1 && m.xyz[13] == 1 && m.xyz[14] == 1 && m.xyz[3] == 1);
  for (size_t c = 0; c < m.ncells && c < 2; c++) {
    CHECK(m.type[c] == MX_TET);
    CHECK(memcmp(m.conn + 8 * c, rows[c], sizeof rows[c]) == 0);
  }
  CHECK(m.cell_tag && m.cell_tag[0] == 12 && m.cell_tag[1] == 2);
  CHECK(m.nfaces == 1);
  if (m.nfaces == 1)
    CHECK(m.face_nn[0] == 3 && m.face_conn[0] == 0 && m.face_conn[1] == 1 && m.face_conn[2] == 2 &&
          m.face_tag[0] == 5);
  CHECK(m.nnames == 1 && m.name_tag[0] == 5 && strcmp(m.name[0], "bottom") == 0);
  mx_mesh_data_free(&m);
}

/* ---- binary ------------------------------------------------------------------ */

typedef struct {
  unsigned char b[2048];
  size_t n;
  int swap;
} buf;

static void text(buf *B, const char *s) {
  memcpy(B->b + B->n, s, strlen(s));
  B->n += strlen(s);
}

static void i32(buf *B, int32_t v) {
  uint32_t u = (uint32_t)v;
  if (B->swap) u = __builtin_bswap32(u);
  memcpy(B->b + B->n, &u, 4);
  B->n += 4;
}

static void f64(buf *B, double d) {
  uint64_t u;
  memcpy(&u, &d, 8);
  if (B->swap) u = __builtin_bswap64(u);
  memcpy(B->b + B->n, &u, 8);
  B->n += 8;
}

static void ints(buf *B, int n, const int32_t *v) {
  for (int i = 0; i < n; i++) i32(B, v[i]);
}

static size_t binary22(buf *B, int swap) {
  B->n = 0;
  B->swap = swap;
  text(B, "$MeshFormat\n2.2 1 8\n");
  i32(B, 1);
  text(B, "\n$EndMeshFormat\n$PhysicalNames\n2\n2 5 \"bottom\"\n3 2 \"vol\"\n$EndPhysicalNames\n");
  text(B, "$Nodes\n5\n");
  static const double xyz[5][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 1, 1}};
  for (int i = 0; i < 5; i++) {
    i32(B, i + 1);
    for (int k = 0; k < 3; k++) f64(B, xyz[i][k]);
  }
  text(B, "\n$EndNodes\n$Elements\n5\n");
  /* blocks: type, count, ntags; then the elements */
  ints(B, 3, (const int32_t[]){15, 1, 2});
  ints(B, 4, (const int32_t[]){1, 0, 1, 1});
  ints(B, 3, (const int32_t[]){1, 1, 2});
  ints(B, 5, (const int32_t[]){2, 0, 1, 1, 2});
  ints(B, 3, (const int32_t[]){2, 1, 2});
  ints(B, 6, (const int32_t[]){3, 5, 20, 1, 2, 3});
  ints(B, 3, (const int32_t[]){4, 2, 2});
  ints(B, 7, (const int32_t[]){9, 2, 11, 1, 2, 3, 4});
  ints(B, 7, (const int32_t[]){7, 0, 12, 2, 3, 4, 5});
  text(B, "\n$EndElements\n");
  return B->n;
}

/* A file that must fail: MX_EINPUT, nothing returned. */
static void expect_fail(const char *name) {
  mx_mesh_data m;
  const int st = mx_read_mesh(path_of(name), &m);
  CHECK(st == MX_EINPUT);
  if (st == MX_OK) mx_mesh_data_free(&m);
}

static char *edited(const char *from, const char *to) {
  const char *at = strstr(ascii22, from);
  if (!at) abort();
  char *s = malloc(sizeof ascii22 + strlen(to));
  if (!s) abort();
  const size_t k = (size_t)(at - ascii22);
  memcpy(s, ascii22, k);
  strcpy(s + k, to);
  strcat(s, at + strlen(from));
  return s;
}

static void test_msh22(void) {
  write_bytes("ascii.msh", ascii22, sizeof ascii22 - 1);
  expect_mesh("ascii.msh");
  static buf B;
  for (int swap = 0; swap < 2; swap++) {
    const size_t n = binary22(&B, swap);
    write_bytes(swap ? "swapped.msh" : "binary.msh", B.b, n);
    expect_mesh(swap ? "swapped.msh" : "binary.msh");
    /* cut anywhere in the binary nodes and elements: refused */
    const size_t from = (size_t)((const unsigned char *)memmem(B.b, n, "$Nodes", 6) - B.b);
    for (size_t cut = from + 9; cut < n - 14; cut += 7) {
      write_bytes("cut.msh", B.b, cut);
      expect_fail("cut.msh");
    }
  }
  struct {
    const char *from, *to;
  } bad[] = {
      {"9 4 2 2 11 1 2 3 4", "9 8 2 2 11 1 2 3"},    /* a 3-node line: not supported */
      {"9 4 2 2 11 1 2 3 4", "9 4 2 2 11 1 2 3 6"},  /* node 6 does not exist */
      {"9 4 2 2 11 1 2 3 4", "9 4 -1 1 2 3 4"},      /* -1 tags */
      {"9 4 2 2 11 1 2 3 4", "9 4 2 2 11 1 2 3"},    /* a node short: count off */
      {"\n5\n1 0 0 0", "\n5000000\n1 0 0 0"},        /* more nodes than the file holds */
      {"$Elements\n5\n", "$Elements\n6\n"},           /* more elements than given */
      {"2.2 0 8", "2.2 0 4"},                         /* 2.2: doubles are 8 bytes */
      {"5 1 1 1\n", "5 1 1 1\n5 0 0 2\n"},            /* node count off */
      {"4 0 0 1\n", "4 0 0 1\n4 0 0 2\n"},            /* tag 4 twice (with count 6) */
  };
  for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
    char *s = edited(bad[i].from, bad[i].to);
    if (i == 8) { /* keep the count right so that only the repeated tag is wrong */
      char *t = strstr(s, "$Nodes\n5\n");
      t[7] = '6';
    }
    write_bytes("bad.msh", s, strlen(s));
    expect_fail("bad.msh");
    free(s);
  }
}

/* ---- VTK: volume cells with a triangle, a vertex and a line ------------------- */

static const char mixed_vtk[] =
    "# vtk DataFile Version 3.0\nm\nASCII\nDATASET UNSTRUCTURED_GRID\n"
    "POINTS 5 double\n0 0 0 1 0 0 0 1 0 0 0 1 1 1 1\n"
    "CELLS 5 19\n1 0\n2 0 1\n3 0 1 2\n4 0 1 2 3\n4 1 2 3 4\n"
    "CELL_TYPES 5\n1\n3\n5\n10\n10\n"
    "CELL_DATA 5\nSCALARS material int 1\nLOOKUP_TABLE default\n7 8 9 3 4\n";

static void test_vtk_mixed(void) {
  write_bytes("mixed.vtk", mixed_vtk, sizeof mixed_vtk - 1);
  for (int k = 0; k < 2; k++) {
    mx_mesh_data m;
    int dim = 0;
    const int st = k ? mx_read_mesh_dim(path_of("mixed.vtk"), &m, &dim) : mx_read_mesh(path_of("mixed.vtk"), &m);
    CHECK(st == MX_OK && (k == 0 || dim == 3));
    if (st != MX_OK) continue;
    CHECK(m.ncells == 2 && m.type[0] == MX_TET && m.type[1] == MX_TET);
    CHECK(m.conn[8] == 1 && m.conn[11] == 4);
    CHECK(m.cell_tag && m.cell_tag[0] == 3 && m.cell_tag[1] == 4);
    CHECK(m.nfaces == 1 && m.face_nn[0] == 3 && m.face_conn[2] == 2 && m.face_tag[0] == 9);
    mx_mesh_data_free(&m);
  }
  /* no volume cell: a line alone is refused, as before */
  static const char lines[] = "# vtk DataFile Version 3.0\nm\nASCII\nDATASET UNSTRUCTURED_GRID\n"
                              "POINTS 2 double\n0 0 0 1 0 0\nCELLS 1 3\n2 0 1\nCELL_TYPES 1\n3\n";
  write_bytes("line.vtk", lines, sizeof lines - 1);
  expect_fail("line.vtk");
}

/* Every allocation of a read made to fail in turn (the hook of
 * base/common.h): MX_ENOMEM, or MX_OK once past the last. */
static void test_alloc_failures(void) {
  const char *names[4] = {"ascii.msh", "binary.msh", "swapped.msh", "mixed.vtk"};
  for (int f = 0; f < 4; f++) {
    mx_mesh_data m;
    mx_alloc_fail_countdown(-1);
    int st = mx_read_mesh(path_of(names[f]), &m);
    const long n = mx_alloc_count();
    mx_alloc_fail_countdown(0);
    CHECK(st == MX_OK && n > 3);
    if (st == MX_OK) mx_mesh_data_free(&m);
    for (long k = 1; k <= n; k++) {
      mx_alloc_fail_countdown(k);
      st = mx_read_mesh(path_of(names[f]), &m);
      mx_alloc_fail_countdown(0);
      CHECK(st == MX_ENOMEM || st == MX_OK);
      if (st == MX_OK) mx_mesh_data_free(&m);
    }
  }
}

int main(void) {
  test_msh22();
  test_vtk_mixed();
  test_alloc_failures();
  return TEST_DONE();
}
