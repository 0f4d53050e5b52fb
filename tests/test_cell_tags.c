/* Each cell's label as the mesh readers give it (mx_mesh_data.cell_tag,
 * several materials, issue 26): Gmsh volume physical tags (src/io/read_msh.c),
 * the VTK and VTU cell field "material" (read_vtk.c, read_vtu.c, and the
 * pieces of a .pvtu, read_pvtu.c), Medit element references
 * (read_medit.c).
 *
 * Derived, not recorded:
 *  - the demo surface meshed with params.materials at the transition stage
 *    (two materials: 1 inside, 0 outside), written by the library in every
 *    format and variant (ASCII and binary .msh and .vtk, .vtu, .mesh,
 *    .meshb), an ASCII .vtu written here (Int32, UInt8, Float64 and Float32
 *    labels) and a .pvtu of two pieces; each read back, its cells matched
 *    to the mesher's by their node sets: the label of each is the mesher's
 *    material (.vtk, .vtu, .pvtu) or the physical volume / reference the
 *    writers give it (material m >= 1: m; 0, outside the inputs: the
 *    number after the last material);
 *  - the same mesh without materials, at the transition and full stages,
 *    in every format: no labels (NULL);
 *  - hand-made .msh files: element tags out of their blocks' order (the
 *    labels follow the cells), physical tags, entities without one, no
 *    $Entities, one volume or one physical volume only (NULL); Medit
 *    references all equal (NULL) or not; VTK labels in a FIELD;
 *  - bad labels (wrong count, components, type, a fraction, out of range)
 *    fail with MX_EINPUT and a message naming the file and the line or
 *    byte. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "check.h"
#include "file_util.h"
#include "io/pvtu.h"
#include "io/read_mesh.h"
#include "mixoct.h"
#include "soa/mesh.h"
#include "soa/mesh_data.h"

static char tmpdir[64];

static const char *tpath(const char *name) {
  static char buf[8][256];
  static int k = 0;
  k = (k + 1) % 8;
  snprintf(buf[k], sizeof buf[k], "%s/%s", tmpdir, name);
  return buf[k];
}

static void write_text(const char *path, const char *s) { write_bytes_file(path, s, strlen(s)); }

/* ---- cells as node sets ---------------------------------------------------- */

/* A cell: its nodes ascending (UINT32_MAX past its count), its label. */
typedef struct {
  uint32_t k[8];
  int32_t lab;
} keyed;

static int keyed_cmp(const void *pa, const void *pb) {
  const keyed *a = pa, *b = pb;
  for (int j = 0; j < 8; j++)
    if (a->k[j] != b->k[j]) return a->k[j] < b->k[j] ? -1 : 1;
  return (a->lab > b->lab) - (a->lab < b->lab);
}

static int u32_cmp(const void *pa, const void *pb) {
  const uint32_t a = *(const uint32_t *)pa, b = *(const uint32_t *)pb;
  return (a > b) - (a < b);
}

/* The cells with their labels, sorted (by node set, then label). */
static keyed *keyed_cells(size_t nc, const uint8_t *type, const uint32_t *conn,
                          const int32_t *lab) {
  keyed *k = malloc((nc + 1) * sizeof *k);
  for (size_t c = 0; c < nc; c++) {
    const int n = mx_cell_nodes[type[c]];
    for (int j = 0; j < 8; j++) k[c].k[j] = j < n ? conn[8 * c + (size_t)j] : UINT32_MAX;
    qsort(k[c].k, (size_t)n, sizeof *k[c].k, u32_cmp);
    k[c].lab = lab[c];
  }
  qsort(k, nc, sizeof *k, keyed_cmp);
  return k;
}

/* Whether m's cells carry the labels `want` gives the cells of `ref`
 * (matched by their node sets; m's nodes must be ref's, in its order).
 * Prints the first difference. */
static int same_labels(const char *what, const mx_mesh_data *m, size_t nn, const double *xyz,
                       size_t nc, const uint8_t *type, const uint32_t *conn, const int32_t *want) {
  if (!m->cell_tag || m->ncells != nc || m->nnodes != nn ||
      memcmp(m->xyz, xyz, 3 * nn * sizeof *xyz) != 0) {
    fprintf(stderr, "%s: cell_tag %s, %zu cells (want %zu), %zu nodes (want %zu)%s\n", what,
            m->cell_tag ? "set" : "NULL", m->ncells, nc, m->nnodes, nn,
            m->nnodes == nn && memcmp(m->xyz, xyz, 3 * nn * sizeof *xyz) ? ", other points" : "");
    return 0;
  }
  keyed *a = keyed_cells(nc, type, conn, want);
  keyed *b = keyed_cells(m->ncells, m->type, m->conn, m->cell_tag);
  size_t bad = SIZE_MAX;
  for (size_t c = 0; c < nc && bad == SIZE_MAX; c++)
    if (keyed_cmp(a + c, b + c) != 0) bad = c;
  if (bad != SIZE_MAX)
    fprintf(stderr,
            "%s: sorted cell %zu: nodes %u %u %u %u label %d, want nodes %u %u %u %u label %d\n",
            what, bad, b[bad].k[0], b[bad].k[1], b[bad].k[2], b[bad].k[3], b[bad].lab, a[bad].k[0],
            a[bad].k[1], a[bad].k[2], a[bad].k[3], a[bad].lab);
  free(a);
  free(b);
  return bad == SIZE_MAX;
}

/* ---- reading with the message kept ----------------------------------------- */

static char captured[4096];

static int read_captured(const char *path, mx_mesh_data *m) {
  const char *errf = tpath("stderr.txt");
  capture_stderr_begin(errf);
  const int st = mx_read_mesh(path, m);
  capture_stderr_end(errf, captured, sizeof captured);
  return st;
}

/* Reading the file p fails with MX_EINPUT, leaves no cells nor labels, and
 * prints a message holding "<p><want>". */
static void expect_error_file(const char *p, const char *want) {
  mx_mesh_data m;
  const int st = read_captured(p, &m);
  char full[512];
  snprintf(full, sizeof full, "%s%s", p, want);
  CHECK(st == MX_EINPUT);
  CHECK(m.cell_tag == NULL && m.conn == NULL);
  if (!strstr(captured, full)) fprintf(stderr, "expected '%s' in: %s\n", full, captured);
  CHECK(strstr(captured, full) != NULL);
  printf("%s %s", st == MX_EINPUT && strstr(captured, full) ? "ok  " : "FAIL", captured);
}

/* The same for text written to tmpdir/name. */
static void expect_error(const char *name, const char *text, const char *want) {
  const char *p = tpath(name);
  write_text(p, text);
  expect_error_file(p, want);
}

/* Reads text (written to name): MX_OK, ncells cells, and cell_tag NULL
 * (want NULL) or equal to want, in the cells' order. */
static void expect_labels(const char *name, const char *text, size_t ncells, const int32_t *want) {
  const char *p = tpath(name);
  write_text(p, text);
  mx_mesh_data m;
  const int st = read_captured(p, &m);
  int ok = st == MX_OK && m.ncells == ncells && !m.cell_tag == !want;
  for (size_t c = 0; ok && want && c < ncells; c++) ok = m.cell_tag[c] == want[c];
  if (!ok) {
    fprintf(stderr, "%s: status %d, %zu cells, cell_tag %s:", name, st, m.ncells,
            m.cell_tag ? "" : "NULL");
    for (size_t c = 0; m.cell_tag && c < m.ncells; c++) fprintf(stderr, " %d", m.cell_tag[c]);
    fprintf(stderr, "\n%s", captured);
  }
  CHECK(ok);
  printf("%s %s\n", ok ? "ok  " : "FAIL", name);
  mx_mesh_data_free(&m);
}

/* ---- an ASCII .vtu written here -------------------------------------------- */

/* m as an ASCII VTU whose CellData holds `cell_data` (DataArray elements)
 * verbatim. */
static void write_vtu_ascii(const char *path, const mx_mesh_data *m, const char *cell_data) {
  FILE *f = fopen(path, "w");
  fprintf(f,
          "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" "
          "byte_order=\"LittleEndian\">\n<UnstructuredGrid>\n"
          "<Piece NumberOfPoints=\"%zu\" NumberOfCells=\"%zu\">\n"
          "<Points>\n<DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">\n",
          m->nnodes, m->ncells);
  for (size_t i = 0; i < 3 * m->nnodes; i++) fprintf(f, "%.17g\n", m->xyz[i]);
  fprintf(f,
          "</DataArray>\n</Points>\n<CellData>\n%s</CellData>\n<Cells>\n"
          "<DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n",
          cell_data);
  for (size_t c = 0; c < m->ncells; c++) {
    const int t = m->type[c];
    for (int j = 0; j < mx_cell_nodes[t]; j++)
      fprintf(f, " %u", m->conn[8 * c + (size_t)mx_vtk_order[t][j]]);
    fprintf(f, "\n");
  }
  fprintf(f, "</DataArray>\n<DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n");
  size_t off = 0;
  for (size_t c = 0; c < m->ncells; c++)
    fprintf(f, "%zu\n", off += (size_t)mx_cell_nodes[m->type[c]]);
  fprintf(f, "</DataArray>\n<DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">\n");
  for (size_t c = 0; c < m->ncells; c++) fprintf(f, "%d\n", mx_vtk_cell_type[m->type[c]]);
  fprintf(f, "</DataArray>\n</Cells>\n</Piece>\n</UnstructuredGrid>\n</VTKFile>\n");
  fclose(f);
}

/* A DataArray "material" of the given type (extra: more attributes) with
 * the n values lab[i] + frac (printed with %g: whole numbers without a
 * point); the caller frees it. */
static char *material_array(const char *type, const char *extra, size_t n, const int32_t *lab,
                            double frac) {
  size_t cap = 256 + 24 * n;
  char *s = malloc(cap);
  size_t w = (size_t)snprintf(
      s, cap, "<DataArray type=\"%s\" Name=\"material\"%s format=\"ascii\">\n", type, extra);
  for (size_t c = 0; c < n; c++) w += (size_t)snprintf(s + w, cap - w, "%g\n", lab[c] + frac);
  snprintf(s + w, cap - w, "</DataArray>\n");
  return s;
}

/* ---- the mesher's two materials, through every writer --------------------- */

static mx_mesher *demo_mesher(int materials, int stage) {
  mx_params p;
  mx_params_default(&p);
  p.surface_level = 3;
  p.stage = stage;
  p.materials = materials;
  mx_mesher *m = mx_mesher_new(&p);
  CHECK(mx_mesher_add_demo_surface(m) == MX_OK);
  CHECK(mx_mesher_mesh(m) == MX_OK);
  return m;
}

static const struct {
  const char *name;
  int ascii;
  int body; /* labelled by body (physical volume, reference), else by material */
} formats[] = {{"m_ascii.msh", 1, 1},  {"m_binary.msh", 0, 1}, {"m_ascii.vtk", 1, 0},
               {"m_binary.vtk", 0, 0}, {"m.vtu", 0, 0},        {"m.mesh", 1, 1},
               {"m.meshb", 0, 1}};
enum { NFORMATS = sizeof formats / sizeof formats[0] };

static void test_written(void) {
  mx_mesher *M = demo_mesher(1, MX_STAGE_TRANSITION);
  mx_mesh_arrays a;
  CHECK(mx_mesher_mesh_arrays(M, &a) == MX_OK);
  CHECK(a.material != NULL);
  if (!a.material) {
    mx_mesher_free(M);
    return;
  }
  const size_t nc = a.nelements;
  int32_t *mat = malloc((nc + 1) * sizeof *mat), *body = malloc((nc + 1) * sizeof *body);
  int32_t nmat = 0;
  size_t count[2] = {0, 0};
  for (size_t c = 0; c < nc; c++) {
    mat[c] = a.material[c];
    if (mat[c] > nmat) nmat = mat[c];
    count[mat[c] != 0]++;
  }
  for (size_t c = 0; c < nc; c++) body[c] = mat[c] ? mat[c] : nmat + 1;
  printf(
      "demo -s 3, transition, materials: %zu elements (%zu outside, %zu inside), %d material(s)\n",
      nc, count[0], count[1], nmat);
  CHECK(count[0] > 0 && count[1] > 0); /* two labels: cell_tag is expected everywhere */
  for (int f = 0; f < NFORMATS; f++) {
    const char *p = tpath(formats[f].name);
    CHECK(mx_mesher_write(M, p, formats[f].ascii) == MX_OK);
    mx_mesh_data m;
    const int st = read_captured(p, &m);
    CHECK(st == MX_OK);
    const int ok = st == MX_OK && same_labels(formats[f].name, &m, a.nnodes, a.xyz, nc, a.type,
                                              a.conn, formats[f].body ? body : mat);
    CHECK(ok);
    printf("%s %-14s %zu cells labelled as the mesher's %s\n", ok ? "ok  " : "FAIL",
           formats[f].name, m.ncells, formats[f].body ? "bodies" : "materials");
    mx_mesh_data_free(&m);
  }
  /* The .vtu again, as ASCII written here: integer and float labels. */
  mx_mesh_data v;
  CHECK(mx_read_mesh(tpath("m.vtu"), &v) == MX_OK);
  if (v.cell_tag && v.ncells == nc) {
    static const char *const types[] = {"Int32", "UInt8", "Float64", "Float32", "Int64"};
    for (int t = 0; t < 5; t++) {
      char *arr = material_array(types[t], "", nc, v.cell_tag, 0.0);
      char name[64];
      snprintf(name, sizeof name, "ascii_%s.vtu", types[t]);
      const char *p = tpath(name);
      write_vtu_ascii(p, &v, arr);
      free(arr);
      mx_mesh_data m;
      const int st = read_captured(p, &m);
      const int ok = st == MX_OK && same_labels(name, &m, a.nnodes, a.xyz, nc, a.type, a.conn, mat);
      CHECK(ok);
      printf("%s %-14s ASCII %s labels\n", ok ? "ok  " : "FAIL", name, types[t]);
      mx_mesh_data_free(&m);
    }
    /* A .pvtu of two pieces (each with every node, GlobalNodeId the node's
     * number), the material an Int32 cell field in each. */
    const size_t half = nc / 2;
    for (int k = 0; k < 2; k++) {
      const size_t c0 = k ? half : 0, c1 = k ? nc : half;
      uint64_t *gid = malloc((v.nnodes + 1) * sizeof *gid);
      for (size_t i = 0; i < v.nnodes; i++) gid[i] = i;
      const mx_field fd = {.name = "material", .is_double = 0, .ivalues = v.cell_tag + c0};
      mx_mesh_view pv = {.nnodes = v.nnodes,
                         .xyz = v.xyz,
                         .ncells = c1 - c0,
                         .type = v.type + c0,
                         .conn = v.conn + 8 * c0,
                         .ncell_fields = 1,
                         .cell_fields = &fd};
      char piece[64];
      snprintf(piece, sizeof piece, "two_%d.vtu", k);
      CHECK(mx_write_vtu_piece(tpath(piece), &pv, gid) == MX_OK);
      if (k == 0) CHECK(mx_write_pvtu_master(tpath("two.pvtu"), 2, &pv, 1) == MX_OK);
      free(gid);
    }
    mx_mesh_data m;
    const int st = read_captured(tpath("two.pvtu"), &m);
    const int ok =
        st == MX_OK && same_labels("two.pvtu", &m, a.nnodes, a.xyz, nc, a.type, a.conn, mat);
    CHECK(ok);
    printf("%s two.pvtu       two pieces, labels concatenated\n", ok ? "ok  " : "FAIL");
    mx_mesh_data_free(&m);
    /* Bad labels in the ASCII .vtu: the line named. */
    char *arr = material_array("Float64", "", nc, v.cell_tag, 0.5);
    write_vtu_ascii(tpath("half.vtu"), &v, arr);
    free(arr);
    const long first = 11 + 3 * (long)v.nnodes; /* the first label's line */
    char want[128];
    snprintf(want, sizeof want, ":%ld: error: material: value 0 (%g) is not a whole number", first,
             v.cell_tag[0] + 0.5);
    expect_error_file(tpath("half.vtu"), want);
    arr = material_array("Int32", "", nc - 1, v.cell_tag, 0.0);
    write_vtu_ascii(tpath("short.vtu"), &v, arr);
    free(arr);
    snprintf(want, sizeof want, ":%ld: error: material: expected %zu values, found %zu",
             first + (long)nc - 1, nc, nc - 1);
    expect_error_file(tpath("short.vtu"), want);
    int32_t *pairs = malloc(2 * nc * sizeof *pairs);
    for (size_t c = 0; c < 2 * nc; c++) pairs[c] = v.cell_tag[c / 2];
    arr = material_array("Int32", " NumberOfComponents=\"2\"", 2 * nc, pairs, 0.0);
    free(pairs);
    write_vtu_ascii(tpath("two.vtu"), &v, arr);
    free(arr);
    snprintf(want, sizeof want, ":%ld: error: material: 2 components, expected 1", first - 1);
    expect_error_file(tpath("two.vtu"), want);
    /* Appended: the material block one value short (its byte count one
     * value smaller), the byte named. */
    size_t len = 0;
    char *buf = slurp(tpath("m.vtu"), &len);
    const char *da = strstr(buf, "Name=\"material\"");
    const char *tag = da ? da : buf, *ty, *of;
    while (tag > buf && *tag != '<') tag--;
    ty = strstr(tag, "type=\"");
    of = strstr(tag, "offset=\"");
    const char *us = strstr(buf, "<AppendedData");
    us = us ? strchr(us, '_') : NULL;
    CHECK(da && ty && of && us);
    if (da && ty && of && us) {
      const size_t esize = strncmp(ty + 6, "UInt8", 5) == 0   ? 1
                           : strncmp(ty + 6, "Int32", 5) == 0 ? 4
                                                              : 0;
      CHECK(esize > 0);
      const size_t at = (size_t)(us + 1 - buf) + strtoull(of + 8, NULL, 10);
      uint64_t bytes;
      memcpy(&bytes, buf + at, 8);
      CHECK(bytes == esize * nc);
      bytes -= esize;
      memcpy(buf + at, &bytes, 8);
      write_bytes_file(tpath("cut.vtu"), buf, len);
      snprintf(want, sizeof want, ": error: material: %zu values, expected %zu (at byte %zu)",
               nc - 1, nc, at);
      expect_error_file(tpath("cut.vtu"), want);
    }
    free(buf);
  }
  mx_mesh_data_free(&v);
  free(mat);
  free(body);
  mx_mesher_free(M);
}

/* Without materials, no format gives labels (one body, one reference). */
static void test_unlabelled(void) {
  for (int stage = MX_STAGE_TRANSITION; stage <= MX_STAGE_FULL; stage++) {
    mx_mesher *M = demo_mesher(0, stage);
    for (int f = 0; f < NFORMATS; f++) {
      const char *p = tpath(formats[f].name);
      CHECK(mx_mesher_write(M, p, formats[f].ascii) == MX_OK);
      mx_mesh_data m;
      const int st = read_captured(p, &m);
      const int ok = st == MX_OK && m.ncells > 0 && m.cell_tag == NULL;
      CHECK(ok);
      printf("%s %-14s %s stage, no materials: no labels\n", ok ? "ok  " : "FAIL", formats[f].name,
             stage == MX_STAGE_FULL ? "full" : "transition");
      mx_mesh_data_free(&m);
    }
    mx_mesher_free(M);
  }
}

/* ---- hand-made files --------------------------------------------------------- */

/* Three tetrahedra on five nodes in MSH 4.1: entities, then elements tagged
 * 3 and 1 in a block of entity E1 and 2 in a block of entity E2 (the
 * reader sorts them by tag: 1, 2, 3). */
static char *msh3(const char *entities, long e1, long e2) {
  static char buf[2048];
  snprintf(
      buf, sizeof buf,
      "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n%s"
      "$Nodes\n1 5 1 5\n3 1 0 5\n1\n2\n3\n4\n5\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n1 1 1\n$EndNodes\n"
      "$Elements\n2 3 1 3\n3 %ld 4 2\n3 1 2 3 4\n1 1 2 3 5\n3 %ld 4 1\n2 2 3 4 5\n$EndElements\n",
      entities, e1, e2);
  return buf;
}

static void test_msh(void) {
  /* Element tag 1 (nodes 1 2 3 5) and 3 (1 2 3 4) in entity 7, 2 in 9. */
  static const uint32_t cells[3][4] = {{0, 1, 2, 4}, {1, 2, 3, 4}, {0, 1, 2, 3}};
  {
    mx_mesh_data m;
    const char *p = tpath("order.msh");
    write_text(
        p,
        msh3("$Entities\n0 0 0 2\n7 0 0 0 1 1 1 1 30 0\n9 0 0 0 1 1 1 0 0\n$EndEntities\n", 7, 9));
    CHECK(mx_read_mesh(p, &m) == MX_OK);
    CHECK(m.ncells == 3);
    for (size_t c = 0; c < 3 && m.ncells == 3; c++)
      for (int j = 0; j < 4; j++) CHECK(m.conn[8 * c + (size_t)j] == cells[c][j]);
    mx_mesh_data_free(&m);
  }
  /* Entity 7 in physical volume 30, entity 9 in none: its own tag. */
  expect_labels(
      "phys.msh",
      msh3("$Entities\n0 0 0 2\n7 0 0 0 1 1 1 1 30 0\n9 0 0 0 1 1 1 0 0\n$EndEntities\n", 7, 9), 3,
      (const int32_t[]){30, 9, 30});
  /* The first physical tag of several; the binary variant is the writers'. */
  expect_labels(
      "phys2.msh",
      msh3("$Entities\n0 0 0 2\n7 0 0 0 1 1 1 2 -4 5 0\n9 0 0 0 1 1 1 1 6 0\n$EndEntities\n", 7, 9),
      3, (const int32_t[]){-4, 6, -4});
  /* No physical tags, no $Entities: the entity tags. */
  expect_labels(
      "ent.msh",
      msh3("$Entities\n0 0 0 2\n7 0 0 0 1 1 1 0 0\n9 0 0 0 1 1 1 0 0\n$EndEntities\n", 7, 9), 3,
      (const int32_t[]){7, 9, 7});
  expect_labels("noent.msh", msh3("", 7, 9), 3, (const int32_t[]){7, 9, 7});
  /* A block's entity missing from $Entities: its tag. */
  expect_labels("missing.msh",
                msh3("$Entities\n0 0 0 1\n7 0 0 0 1 1 1 1 30 0\n$EndEntities\n", 7, 9), 3,
                (const int32_t[]){30, 9, 30});
  /* One label for every element: no labels. */
  expect_labels("one.msh", msh3("$Entities\n0 0 0 1\n7 0 0 0 1 1 1 0 0\n$EndEntities\n", 7, 7), 3,
                NULL);
  expect_labels("one_noent.msh", msh3("", 7, 7), 3, NULL);
  expect_labels(
      "onephys.msh",
      msh3("$Entities\n0 0 0 2\n7 0 0 0 1 1 1 1 5 0\n9 0 0 0 1 1 1 1 5 0\n$EndEntities\n", 7, 9), 3,
      NULL);
  expect_labels("onephys1.msh",
                msh3("$Entities\n0 0 0 1\n7 0 0 0 1 1 1 1 1 0\n$EndEntities\n", 7, 7), 3, NULL);
  /* Labels out of the range of int32. */
  expect_error("big_phys.msh",
               msh3("$Entities\n0 0 0 1\n7 0 0 0 1 1 1 1 3000000000 0\n$EndEntities\n", 7, 9),
               ":6: error: $Entities: volume tag 3000000000 is out of range");
  expect_error("big_ent.msh", msh3("", 7, 3000000000L),
               ":23: error: $Elements block: entity tag 3000000000 is out of range");
}

static void test_medit(void) {
  static const char head[] =
      "MeshVersionFormatted 2\nDimension 3\nVertices\n5\n"
      "0 0 0 0\n1 0 0 0\n0 1 0 0\n0 0 1 0\n1 1 1 0\n";
  char buf[1024];
  snprintf(buf, sizeof buf, "%sTetrahedra\n2\n1 2 3 4 3\n2 3 4 5 5\nEnd\n", head);
  expect_labels("refs.mesh", buf, 2, (const int32_t[]){3, 5});
  snprintf(buf, sizeof buf, "%sTetrahedra\n1\n1 2 3 4 -2\nPyramids\n1\n1 2 5 3 4 7\nEnd\n", head);
  expect_labels("refs2.mesh", buf, 2, (const int32_t[]){-2, 7});
  snprintf(buf, sizeof buf, "%sTetrahedra\n2\n1 2 3 4 4\n2 3 4 5 4\nEnd\n", head);
  expect_labels("same.mesh", buf, 2, NULL);
  /* A reference out of range matters only when they differ. */
  snprintf(buf, sizeof buf, "%sTetrahedra\n2\n1 2 3 4 3000000000\n2 3 4 5 3000000000\nEnd\n", head);
  expect_labels("samebig.mesh", buf, 2, NULL);
  snprintf(buf, sizeof buf, "%sTetrahedra\n2\n1 2 3 4 1\n2 3 4 5 3000000000\nEnd\n", head);
  expect_error("big.mesh", buf, ":13: error: element reference 3000000000 is out of range");
}

/* ---- legacy VTK ------------------------------------------------------------- */

static const char vtk_two[] =
    "# vtk DataFile Version 3.0\nt\nASCII\nDATASET UNSTRUCTURED_GRID\n"
    "POINTS 5 double\n0 0 0 1 0 0 0 1 0 0 0 1 1 1 1\nCELLS 2 10\n4 0 1 2 3\n4 1 2 3 4\n"
    "CELL_TYPES 2\n10 10\n";

static void test_vtk(void) {
  char buf[1024];
  /* After other attributes, as SCALARS (float whole numbers) or in a FIELD. */
  snprintf(buf, sizeof buf,
           "%sCELL_DATA 2\nSCALARS level int 1\nLOOKUP_TABLE default\n1 2\n"
           "SCALARS material float 1\nLOOKUP_TABLE default\n4 -1\nPOINT_DATA 5\n"
           "SCALARS surface_tag int\nLOOKUP_TABLE default\n0 0 0 0 0\n",
           vtk_two);
  expect_labels("scalars.vtk", buf, 2, (const int32_t[]){4, -1});
  snprintf(
      buf, sizeof buf,
      "%sCELL_DATA 2\nFIELD FieldData 2\nx 1 2 double\n0.5 1\nmaterial 1 2 unsigned_char\n9 3\n",
      vtk_two);
  expect_labels("field.vtk", buf, 2, (const int32_t[]){9, 3});
  snprintf(buf, sizeof buf, "%sCELL_DATA 2\nSCALARS body int 1\nLOOKUP_TABLE default\n1 2\n",
           vtk_two);
  expect_labels("nolabel.vtk", buf, 2, NULL);
  /* a point field named material is not a cell label */
  snprintf(buf, sizeof buf,
           "%sPOINT_DATA 5\nSCALARS material int 1\nLOOKUP_TABLE default\n1 2 3 4 5\n", vtk_two);
  expect_labels("pointmat.vtk", buf, 2, NULL);
  /* Bad labels: the line named. */
  snprintf(buf, sizeof buf,
           "%sCELL_DATA 2\nSCALARS material double 1\nLOOKUP_TABLE default\n1 2.5\n", vtk_two);
  expect_error("frac.vtk", buf, ":15: error: material: value 1 (2.5) is not a whole number");
  snprintf(buf, sizeof buf, "%sCELL_DATA 3\nSCALARS material int 1\nLOOKUP_TABLE default\n1 2 3\n",
           vtk_two);
  expect_error("count.vtk", buf, ":13: error: material: 3 values for 2 cells");
  snprintf(buf, sizeof buf, "%sCELL_DATA 2\nSCALARS material int 1\nLOOKUP_TABLE default\n1\n",
           vtk_two);
  expect_error("few.vtk", buf, ":16: error: material: expected 2 values, found 1");
  snprintf(buf, sizeof buf,
           "%sCELL_DATA 2\nSCALARS material int 3\nLOOKUP_TABLE default\n1 2 3 4 5 6\n", vtk_two);
  expect_error("comp.vtk", buf, ":13: error: material: 3 components, expected 1");
  snprintf(buf, sizeof buf, "%sCELL_DATA 2\nSCALARS material string 1\nLOOKUP_TABLE default\na b\n",
           vtk_two);
  expect_error("type.vtk", buf, ":13: error: material: type 'string' is not a number type");
  snprintf(buf, sizeof buf,
           "%sCELL_DATA 2\nSCALARS material long 1\nLOOKUP_TABLE default\n1 3000000000\n", vtk_two);
  expect_error("range.vtk", buf, ":15: error: material: value 1 is out of range");
  snprintf(buf, sizeof buf,
           "%sCELL_DATA 2\nSCALARS material int 1\nLOOKUP_TABLE default\n1 2\n"
           "FIELD f 1\nmaterial 1 2 int\n1 2\n",
           vtk_two);
  expect_error("twice.vtk", buf, ":17: error: material given twice");
  /* Binary: the byte of the value named. */
  {
    unsigned char bin[1024];
    size_t n = 0;
#define PUT(s) (memcpy(bin + n, s, strlen(s)), n += strlen(s))
    PUT("# vtk DataFile Version 3.0\nt\nBINARY\nDATASET UNSTRUCTURED_GRID\nPOINTS 4 double\n");
    static const double pts[12] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
    for (int i = 0; i < 12; i++) {
      uint64_t b;
      memcpy(&b, &pts[i], 8);
      for (int k = 7; k >= 0; k--) bin[n++] = (unsigned char)(b >> (8 * k));
    }
    PUT("\nCELLS 1 5\n");
    static const int32_t cl[5] = {4, 0, 1, 2, 3};
    for (int i = 0; i < 5; i++)
      for (int k = 3; k >= 0; k--) bin[n++] = (unsigned char)((uint32_t)cl[i] >> (8 * k));
    PUT("\nCELL_TYPES 1\n");
    bin[n++] = 0, bin[n++] = 0, bin[n++] = 0, bin[n++] = 10;
    PUT("\nCELL_DATA 1\nSCALARS material double 1\nLOOKUP_TABLE default\n");
    const size_t at = n;
    const double half = 2.5;
    uint64_t b;
    memcpy(&b, &half, 8);
    for (int k = 7; k >= 0; k--) bin[n++] = (unsigned char)(b >> (8 * k));
    PUT("\n");
#undef PUT
    const char *p = tpath("frac_binary.vtk");
    write_bytes_file(p, bin, n);
    char want[128];
    snprintf(want, sizeof want,
             ": error: material: value 0 (2.5) is not a whole number in the range of "
             "32-bit integers (at byte %zu)",
             at);
    expect_error_file(p, want);
    /* the same with 2.0: read */
    const double two = 2.0;
    memcpy(&b, &two, 8);
    for (int k = 7; k >= 0; k--) bin[at + 7 - (size_t)k] = (unsigned char)(b >> (8 * k));
    write_bytes_file(p, bin, n);
    mx_mesh_data m;
    CHECK(mx_read_mesh(p, &m) == MX_OK);
    CHECK(m.ncells == 1 && m.cell_tag && m.cell_tag[0] == 2);
    mx_mesh_data_free(&m);
  }
}

static void remove_tmpdir(void) {
  remove_dir_files(tmpdir);
  rmdir(tmpdir);
}

int main(void) {
  snprintf(tmpdir, sizeof tmpdir, "/tmp/mx_cell_tags_XXXXXX");
  if (!mkdtemp(tmpdir)) {
    perror("mkdtemp");
    return 2;
  }
  test_written();
  test_unlabelled();
  test_msh();
  test_medit();
  test_vtk();
  remove_tmpdir();
  return TEST_DONE();
}
