/* Tests of the parallel VTU output and of the mesh hash (io/pvtu.h) and of
 * reading a .pvtu back (io/read_mesh.h): the demo surface's mesh cut by
 * cell index ranges into 1, 2, 3 and 4 pieces (one of them empty), each
 * piece with its own node numbering (the nodes its cells use) and
 * GlobalNodeId = the node's index in the whole mesh, written as pieces and
 * a master, read back: the used nodes, the cells, their coordinates, the
 * point field surface_tag and the hash of the whole mesh; the same without
 * GlobalNodeId (points merged by coordinates). Errors: a missing piece,
 * pieces with different arrays, a GlobalNodeId with two positions (an
 * error message, no crash). The hash: one ulp moved changes it; cells
 * permuted, nodes renumbered, a cell's nodes rotated, -0.0 for 0.0 and
 * unused nodes do not.
 *
 * "test_pvtu --write DIR" writes DIR/mesh.vtu (the whole mesh, with
 * mx_write_vtu), DIR/mesh3.pvtu (3 pieces with GlobalNodeId) and
 * DIR/coords2.pvtu (2 pieces without) for tests/pvtu_check_test.sh. */
#include <math.h>
#include <omp.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "check.h"
#include "base/common.h"
#include "io/pvtu.h"
#include "io/read_mesh.h"
#include "mixoct.h"
#include "soa/mesh.h"

#define OUT_DIR "pvtu_out"
#include "file_util.h"
#include "io/write_mesh.h"

/* ---- the whole mesh ------------------------------------------------------ */

typedef struct {
  mx_mesher *mesher;
  mx_mesh_arrays a;
  int32_t *tag;  /* a point field of int32 values (surface_tag) */
  int32_t *part; /* a cell field of int32 values */
  mx_field cf[4], pf[2];
  mx_mesh_view v;
  size_t used; /* nodes some cell uses */
} whole;

static void whole_make(whole *w) {
  memset(w, 0, sizeof *w);
  mx_params p;
  mx_params_default(&p);
  p.surface_level = 4;
  w->mesher = mx_mesher_new(&p);
  if (!w->mesher || mx_mesher_add_demo_surface(w->mesher) != MX_OK ||
      mx_mesher_mesh(w->mesher) != MX_OK || mx_mesher_mesh_arrays(w->mesher, &w->a) != MX_OK) {
    fprintf(stderr, "test: the demo mesh failed\n");
    exit(2);
  }
  const mx_mesh_arrays *a = &w->a;
  w->tag = calloc(a->nnodes + 1, sizeof *w->tag);
  w->part = calloc(a->nelements + 1, sizeof *w->part);
  char *used = calloc(a->nnodes + 1, 1);
  if (!w->tag || !w->part || !used) exit(2);
  /* values above 255: mx_write_vtu would narrow fitting ones to UInt8 */
  for (size_t i = 0; i < a->nnodes; i++) w->tag[i] = a->boundary[i] ? 300 + (int32_t)(i % 3) : 0;
  for (size_t c = 0; c < a->nelements; c++) {
    w->part[c] = (int32_t)(c % 7);
    for (int j = 0; j < mx_cell_nodes[a->type[c]]; j++) used[a->conn[8 * c + (size_t)j]] = 1;
  }
  for (size_t i = 0; i < a->nnodes; i++) w->used += used[i];
  free(used);
  w->cf[0] = (mx_field){.name = "type", .is_double = 0, .u8values = a->type};
  w->cf[1] = (mx_field){.name = "level", .is_double = 0, .u8values = a->level};
  w->cf[2] = (mx_field){.name = "jens", .is_double = 1, .fvalues = a->jens};
  w->cf[3] = (mx_field){.name = "part", .is_double = 0, .ivalues = w->part};
  w->pf[0] = (mx_field){.name = "boundary", .is_double = 0, .u8values = a->boundary};
  w->pf[1] = (mx_field){.name = "surface_tag", .is_double = 0, .ivalues = w->tag};
  w->v = (mx_mesh_view){.nnodes = a->nnodes, .xyz = a->xyz, .ncells = a->nelements,
                        .type = a->type, .conn = a->conn, .ncell_fields = 4,
                        .cell_fields = w->cf, .npoint_fields = 2, .point_fields = w->pf};
}

static void whole_free(whole *w) {
  mx_mesher_free(w->mesher);
  free(w->tag);
  free(w->part);
}

/* ---- a piece: cells [c0, c1), the nodes they use numbered locally -------- */

typedef struct {
  size_t nnodes;
  double *xyz;
  uint32_t *conn;
  uint64_t *gid;
  uint8_t *bnd;
  int32_t *tag;
  mx_field cf[4], pf[2];
  mx_mesh_view v;
} piece;

/* The local numbers follow the global ones downwards when `reverse`, so
 * that a piece's numbering is not merely a restriction of the whole's. */
static void piece_make(piece *p, const whole *w, size_t c0, size_t c1, int reverse) {
  memset(p, 0, sizeof *p);
  const mx_mesh_arrays *a = &w->a;
  uint32_t *local = malloc((a->nnodes + 1) * sizeof *local);
  if (!local) exit(2);
  for (size_t i = 0; i < a->nnodes; i++) local[i] = UINT32_MAX;
  for (size_t c = c0; c < c1; c++)
    for (int j = 0; j < mx_cell_nodes[a->type[c]]; j++) local[a->conn[8 * c + (size_t)j]] = 0;
  for (size_t i = 0; i < a->nnodes; i++) p->nnodes += local[i] == 0;
  p->xyz = calloc(3 * p->nnodes + 1, sizeof *p->xyz);
  p->gid = calloc(p->nnodes + 1, sizeof *p->gid);
  p->bnd = calloc(p->nnodes + 1, 1);
  p->tag = calloc(p->nnodes + 1, sizeof *p->tag);
  p->conn = calloc(8 * (c1 - c0) + 1, sizeof *p->conn);
  if (!p->xyz || !p->gid || !p->bnd || !p->tag || !p->conn) exit(2);
  uint32_t k = 0;
  for (size_t s = 0; s < a->nnodes; s++) {
    const size_t i = reverse ? a->nnodes - 1 - s : s;
    if (local[i] == UINT32_MAX) continue;
    local[i] = k;
    memcpy(p->xyz + 3 * (size_t)k, a->xyz + 3 * i, 3 * sizeof(double));
    p->gid[k] = i;
    p->bnd[k] = a->boundary[i];
    p->tag[k] = w->tag[i];
    k++;
  }
  for (size_t c = c0; c < c1; c++)
    for (int j = 0; j < mx_cell_nodes[a->type[c]]; j++)
      p->conn[8 * (c - c0) + (size_t)j] = local[a->conn[8 * c + (size_t)j]];
  free(local);
  p->cf[0] = (mx_field){.name = "type", .is_double = 0, .u8values = a->type + c0};
  p->cf[1] = (mx_field){.name = "level", .is_double = 0, .u8values = a->level + c0};
  p->cf[2] = (mx_field){.name = "jens", .is_double = 1, .fvalues = a->jens + c0};
  p->cf[3] = (mx_field){.name = "part", .is_double = 0, .ivalues = w->part + c0};
  p->pf[0] = (mx_field){.name = "boundary", .is_double = 0, .u8values = p->bnd};
  p->pf[1] = (mx_field){.name = "surface_tag", .is_double = 0, .ivalues = p->tag};
  p->v = (mx_mesh_view){.nnodes = p->nnodes, .xyz = p->xyz, .ncells = c1 - c0,
                        .type = a->type + c0, .conn = p->conn, .ncell_fields = 4,
                        .cell_fields = p->cf, .npoint_fields = 2, .point_fields = p->pf};
}

static void piece_free(piece *p) {
  free(p->xyz);
  free(p->conn);
  free(p->gid);
  free(p->bnd);
  free(p->tag);
}

/* Cuts w into n pieces (piece `empty` has no cell, -1: none) and writes
 * them and the master; MX_OK when every file was written. */
static int write_parallel(const whole *w, const char *pvtu, int n, int empty, int with_gid) {
  int st = MX_OK;
  char path[512];
  const int full = n - (empty >= 0);
  piece first;
  int have_first = 0;
  for (int i = 0, k = 0; i < n; i++) {
    size_t c0 = w->v.ncells * (size_t)k / (size_t)full, c1 = c0;
    if (i != empty) c1 = w->v.ncells * (size_t)(++k) / (size_t)full;
    piece p;
    piece_make(&p, w, c0, c1, i % 2);
    mx_pvtu_piece_path(pvtu, i, path, sizeof path);
    if (mx_write_vtu_piece(path, &p.v, with_gid ? p.gid : NULL) != MX_OK) st = MX_EIO;
    if (!have_first) {
      first = p; /* its view points at its own field lists: at the copy's */
      first.v.cell_fields = first.cf;
      first.v.point_fields = first.pf;
      have_first = 1;
    } else {
      piece_free(&p);
    }
  }
  /* the master from any piece's view: only the fields' names and kinds */
  if (mx_write_pvtu_master(pvtu, n, &first.v, with_gid) != MX_OK) st = MX_EIO;
  piece_free(&first);
  return st;
}

/* ---- checks of a mesh read back ----------------------------------------- */

static int bits_equal(const double *a, const double *b) { return memcmp(a, b, 24) == 0; }

/* r (read from a .pvtu of w) holds w's used nodes and w's cells in order,
 * each at the same coordinates; with ids, the nodes numbered as w's used
 * nodes in order. */
static void check_reread(const whole *w, const mx_mesh_data *r, int with_gid, const char *what) {
  const mx_mesh_view *v = &w->v;
  CHECK(r->nnodes == w->used);
  CHECK(r->ncells == v->ncells);
  if (r->nnodes != w->used || r->ncells != v->ncells) {
    fprintf(stderr, "  %s: %zu nodes, %zu cells; expected %zu, %zu\n", what, r->nnodes,
            r->ncells, w->used, v->ncells);
    return;
  }
  const mx_mesh_view rv = mx_mesh_data_view(r);
  CHECK(mx_mesh_hash(&rv) == mx_mesh_hash(v));
  size_t bad_type = 0, bad_xyz = 0, bad_tag = 0, bad_order = 0;
  for (size_t c = 0; c < v->ncells; c++) {
    bad_type += r->type[c] != v->type[c];
    for (int j = 0; j < mx_cell_nodes[v->type[c]]; j++) {
      const uint32_t o = v->conn[8 * c + (size_t)j], n = r->conn[8 * c + (size_t)j];
      bad_xyz += !bits_equal(r->xyz + 3 * (size_t)n, v->xyz + 3 * (size_t)o);
      bad_tag += !r->node_tag || r->node_tag[n] != w->tag[o];
    }
  }
  if (with_gid) { /* numbered by id: the k-th used node of w */
    uint32_t *rank = calloc(v->nnodes + 1, sizeof *rank);
    char *used = calloc(v->nnodes + 1, 1);
    if (!rank || !used) exit(2);
    for (size_t c = 0; c < v->ncells; c++)
      for (int j = 0; j < mx_cell_nodes[v->type[c]]; j++) used[v->conn[8 * c + (size_t)j]] = 1;
    for (size_t i = 0, k = 0; i < v->nnodes; i++) rank[i] = used[i] ? (uint32_t)k++ : 0;
    for (size_t c = 0; c < v->ncells; c++)
      for (int j = 0; j < mx_cell_nodes[v->type[c]]; j++)
        bad_order += r->conn[8 * c + (size_t)j] != rank[v->conn[8 * c + (size_t)j]];
    free(rank);
    free(used);
  }
  CHECK(bad_type == 0);
  CHECK(bad_xyz == 0);
  CHECK(bad_tag == 0);
  CHECK(bad_order == 0);
  if (bad_type || bad_xyz || bad_tag || bad_order)
    fprintf(stderr, "  %s: %zu types, %zu coordinates, %zu tags, %zu numbers differ\n", what,
            bad_type, bad_xyz, bad_tag, bad_order);
}

static void test_round_trip(const whole *w) {
  static const struct {
    int n, empty;
  } cuts[] = {{1, -1}, {2, -1}, {3, -1}, {4, 2}};
  char pvtu[256];
  for (int with_gid = 1; with_gid >= 0; with_gid--)
    for (size_t k = 0; k < sizeof cuts / sizeof cuts[0]; k++) {
      snprintf(pvtu, sizeof pvtu, OUT_DIR "/cut%d_%s.pvtu", cuts[k].n, with_gid ? "gid" : "xyz");
      CHECK(write_parallel(w, pvtu, cuts[k].n, cuts[k].empty, with_gid) == MX_OK);
      mx_mesh_data r;
      const int st = mx_read_mesh(pvtu, &r);
      CHECK(st == MX_OK);
      if (st == MX_OK) check_reread(w, &r, with_gid, pvtu);
      mx_mesh_data_free(&r);
    }
}

/* The master names its pieces without the directory and declares the
 * arrays with the pieces' types (an int32 field Int32 even when its values
 * would fit UInt8). */
static void test_master_text(const whole *w) {
  const char *pvtu = OUT_DIR "/text.pvtu";
  CHECK(write_parallel(w, pvtu, 2, -1, 1) == MX_OK);
  char *m = slurp(pvtu, NULL), *p0 = slurp(OUT_DIR "/text_0.vtu", NULL);
  CHECK(m && p0);
  if (m && p0) {
    CHECK(strstr(m, "<VTKFile type=\"PUnstructuredGrid\""));
    CHECK(strstr(m, "<PUnstructuredGrid GhostLevel=\"0\">"));
    CHECK(strstr(m, "<PDataArray type=\"Int64\" Name=\"GlobalNodeId\"/>"));
    CHECK(strstr(m, "<PDataArray type=\"Int32\" Name=\"surface_tag\"/>"));
    CHECK(strstr(m, "<PDataArray type=\"Int32\" Name=\"part\"/>"));
    CHECK(strstr(m, "<PDataArray type=\"UInt8\" Name=\"level\"/>"));
    CHECK(strstr(m, "<PDataArray type=\"Float64\" Name=\"jens\"/>"));
    CHECK(strstr(m, "<PDataArray type=\"Float64\" Name=\"Points\" NumberOfComponents=\"3\"/>"));
    CHECK(strstr(m, "<Piece Source=\"text_0.vtu\"/>"));
    CHECK(strstr(m, "<Piece Source=\"text_1.vtu\"/>"));
    CHECK(!strstr(m, "text_2.vtu"));
    CHECK(strstr(p0, "<DataArray type=\"Int64\" Name=\"GlobalNodeId\""));
    CHECK(strstr(p0, "<DataArray type=\"Int32\" Name=\"part\""));
    CHECK(strstr(p0, "<DataArray type=\"Int32\" Name=\"surface_tag\""));
  }
  free(m);
  free(p0);
  /* mx_write_vtu itself is unchanged: the part values fit, so UInt8 */
  CHECK(mx_write_vtu(OUT_DIR "/plain.vtu", &w->v) == MX_OK);
  char *plain = slurp(OUT_DIR "/plain.vtu", NULL);
  CHECK(plain && strstr(plain, "<DataArray type=\"UInt8\" Name=\"part\""));
  CHECK(plain && !strstr(plain, "GlobalNodeId"));
  free(plain);
}

static void test_piece_path(void) {
  char b[64];
  mx_pvtu_piece_path("dir/sub/out.pvtu", 3, b, sizeof b);
  CHECK(strcmp(b, "dir/sub/out_3.vtu") == 0);
  mx_pvtu_piece_path("OUT.PVTU", 12, b, sizeof b);
  CHECK(strcmp(b, "OUT_12.vtu") == 0);
  mx_pvtu_piece_path("plain", 0, b, sizeof b);
  CHECK(strcmp(b, "plain_0.vtu") == 0);
  mx_pvtu_piece_path("a.b/c.pvtu", 7, b, sizeof b);
  CHECK(strcmp(b, "a.b/c_7.vtu") == 0);
  mx_pvtu_piece_path("dir/out.pvtu", 3, b, 10); /* does not fit: empty */
  CHECK(b[0] == '\0');
  mx_pvtu_piece_path("o.pvtu", 3, b, 8); /* "o_3.vtu" and its NUL: fits */
  CHECK(strcmp(b, "o_3.vtu") == 0);
}

/* A text file. */
static void put(const char *path, const char *text) {
  FILE *f = fopen(path, "w");
  CHECK(f != NULL);
  if (!f) return;
  fputs(text, f);
  fclose(f);
}

/* mx_read_mesh fails cleanly (MX_EINPUT, out empty). */
static void expect_error(const char *path, const char *what) {
  mx_mesh_data r;
  memset(&r, 0xab, sizeof r);
  const int st = mx_read_mesh(path, &r);
  CHECK(st == MX_EINPUT);
  CHECK(r.nnodes == 0 && r.ncells == 0 && !r.xyz && !r.conn && !r.node_tag);
  if (st != MX_EINPUT) fprintf(stderr, "  %s: status %d, expected an error\n", what, st);
  if (st == MX_OK) mx_mesh_data_free(&r);
}

static void test_errors(const whole *w) {
  /* a master naming one piece more than there are */
  CHECK(write_parallel(w, OUT_DIR "/miss.pvtu", 2, -1, 1) == MX_OK);
  piece p;
  piece_make(&p, w, 0, 10, 0);
  CHECK(mx_write_pvtu_master(OUT_DIR "/miss.pvtu", 3, &p.v, 1) == MX_OK);
  expect_error(OUT_DIR "/miss.pvtu", "a missing piece");
  /* pieces with and without GlobalNodeId */
  CHECK(mx_write_vtu_piece(OUT_DIR "/mixed_0.vtu", &p.v, p.gid) == MX_OK);
  CHECK(mx_write_vtu_piece(OUT_DIR "/mixed_1.vtu", &p.v, NULL) == MX_OK);
  CHECK(mx_write_pvtu_master(OUT_DIR "/mixed.pvtu", 2, &p.v, 1) == MX_OK);
  expect_error(OUT_DIR "/mixed.pvtu", "GlobalNodeId in one piece only");
  /* a cell field more in one piece */
  p.v.ncell_fields = 3;
  CHECK(mx_write_vtu_piece(OUT_DIR "/mixed_1.vtu", &p.v, p.gid) == MX_OK);
  expect_error(OUT_DIR "/mixed.pvtu", "a cell field in one piece only");
  p.v.ncell_fields = 4;
  /* one GlobalNodeId at two places: a node of cell 5, in both pieces */
  piece q;
  piece_make(&q, w, 5, 20, 0);
  const size_t shared = 3 * (size_t)q.conn[0];
  q.xyz[shared] = nextafter(q.xyz[shared], INFINITY);
  CHECK(mx_write_vtu_piece(OUT_DIR "/mixed_1.vtu", &q.v, q.gid) == MX_OK);
  expect_error(OUT_DIR "/mixed.pvtu", "one id at two places");
  /* without ids the same files are two nodes there: read fine */
  CHECK(mx_write_vtu_piece(OUT_DIR "/mixed_0.vtu", &p.v, NULL) == MX_OK);
  CHECK(mx_write_vtu_piece(OUT_DIR "/mixed_1.vtu", &q.v, NULL) == MX_OK);
  CHECK(mx_write_pvtu_master(OUT_DIR "/mixed.pvtu", 2, &p.v, 0) == MX_OK);
  mx_mesh_data r;
  CHECK(mx_read_mesh(OUT_DIR "/mixed.pvtu", &r) == MX_OK);
  /* cells 5..9 are in both pieces: their nodes merge but for the moved one */
  CHECK(r.ncells == 25);
  mx_mesh_data_free(&r);
  /* one surface_tag for a node in one piece, another in the other */
  q.xyz[shared] = w->a.xyz[3 * (size_t)q.gid[q.conn[0]]];
  q.tag[q.conn[0]] = 77;
  CHECK(mx_write_vtu_piece(OUT_DIR "/mixed_1.vtu", &q.v, NULL) == MX_OK);
  expect_error(OUT_DIR "/mixed.pvtu", "two surface_tags for a node");
  piece_free(&q);
  /* hand-written masters: no piece, no Source, a piece that is a .pvtu,
   * a piece in another format, a truncated master */
  put(OUT_DIR "/none.pvtu", "<VTKFile type=\"PUnstructuredGrid\" version=\"1.0\">\n"
                            "<PUnstructuredGrid GhostLevel=\"0\">\n</PUnstructuredGrid>\n"
                            "</VTKFile>\n");
  expect_error(OUT_DIR "/none.pvtu", "no piece");
  put(OUT_DIR "/nosrc.pvtu", "<VTKFile type=\"PUnstructuredGrid\" version=\"1.0\">\n"
                             "<PUnstructuredGrid GhostLevel=\"0\">\n<Piece/>\n"
                             "</PUnstructuredGrid>\n</VTKFile>\n");
  expect_error(OUT_DIR "/nosrc.pvtu", "no Source");
  put(OUT_DIR "/self.pvtu", "<VTKFile type=\"PUnstructuredGrid\" version=\"1.0\">\n"
                            "<PUnstructuredGrid GhostLevel=\"0\">\n<Piece Source=\"self.pvtu\"/>\n"
                            "</PUnstructuredGrid>\n</VTKFile>\n");
  expect_error(OUT_DIR "/self.pvtu", "a .pvtu as its own piece");
  put(OUT_DIR "/legacy.vtk", "# vtk DataFile Version 2.0\nx\nASCII\nDATASET UNSTRUCTURED_GRID\n"
                             "POINTS 0 double\nCELLS 0 0\nCELL_TYPES 0\n");
  put(OUT_DIR "/legacy.pvtu", "<VTKFile type=\"PUnstructuredGrid\" version=\"1.0\">\n"
                              "<PUnstructuredGrid GhostLevel=\"0\">\n"
                              "<Piece Source=\"legacy.vtk\"/>\n</PUnstructuredGrid>\n</VTKFile>\n");
  expect_error(OUT_DIR "/legacy.pvtu", "a legacy VTK piece");
  put(OUT_DIR "/cut.pvtu", "<VTKFile type=\"PUnstructuredGrid\" version=\"1.0\">\n"
                           "<PUnstructuredGrid GhostLevel=\"0\">\n<Piece Source=\"mixed_0.vt");
  expect_error(OUT_DIR "/cut.pvtu", "a truncated master");
  /* a piece in a subdirectory, its name with an entity: read fine */
  mkdir(OUT_DIR "/sub dir", 0777);
  CHECK(mx_write_vtu_piece(OUT_DIR "/sub dir/a&b.vtu", &p.v, p.gid) == MX_OK);
  put(OUT_DIR "/subdir.pvtu", "<VTKFile type=\"PUnstructuredGrid\" version=\"1.0\">\n"
                              "<PUnstructuredGrid GhostLevel=\"0\">\n"
                              "<Piece Source=\"sub dir/a&amp;b.vtu\"/>\n"
                              "</PUnstructuredGrid>\n</VTKFile>\n");
  CHECK(mx_read_mesh(OUT_DIR "/subdir.pvtu", &r) == MX_OK);
  CHECK(r.ncells == 10 && r.nnodes == p.nnodes);
  mx_mesh_data_free(&r);
  piece_free(&p);
  /* the writers refuse what they cannot write */
  const mx_mesh_view empty = {0};
  CHECK(mx_write_pvtu_master(OUT_DIR "/zero.pvtu", 0, &empty, 0) == MX_EINTERNAL);
  uint64_t big = (uint64_t)1 << 63;
  const double o[3] = {0, 0, 0};
  const mx_mesh_view one = {.nnodes = 1, .xyz = o};
  CHECK(mx_write_vtu_piece(OUT_DIR "/big.vtu", &one, &big) == MX_EINTERNAL);
  CHECK(access(OUT_DIR "/big.vtu", F_OK) != 0);
}

/* Without ids, points of one piece at one place stay distinct: the k-th
 * of each piece there are one node. Piece 0: a tetrahedron and a second
 * point at its corner 0 (unused); piece 1: a tetrahedron sharing corner 0
 * and its corner 1 twice (the second one unused). 5 + 5 points, corner 0
 * merged once: 9 nodes. */
static void test_duplicates(void) {
  const double x0[5 * 3] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0};
  const double x1[5 * 3] = {0, 0, 0, -1, 0, 0, 0, -1, 0, 0, 0, -1, -1, 0, 0};
  const uint32_t c[8] = {0, 1, 2, 3};
  const uint8_t t = MX_TET;
  const mx_mesh_view v0 = {.nnodes = 5, .xyz = x0, .ncells = 1, .type = &t, .conn = c};
  const mx_mesh_view v1 = {.nnodes = 5, .xyz = x1, .ncells = 1, .type = &t, .conn = c};
  const char *pvtu = OUT_DIR "/dup.pvtu";
  char path[256];
  mx_pvtu_piece_path(pvtu, 0, path, sizeof path);
  CHECK(mx_write_vtu_piece(path, &v0, NULL) == MX_OK);
  mx_pvtu_piece_path(pvtu, 1, path, sizeof path);
  CHECK(mx_write_vtu_piece(path, &v1, NULL) == MX_OK);
  CHECK(mx_write_pvtu_master(pvtu, 2, &v0, 0) == MX_OK);
  mx_mesh_data r;
  CHECK(mx_read_mesh(pvtu, &r) == MX_OK);
  CHECK(r.nnodes == 9 && r.ncells == 2);
  if (r.nnodes == 9 && r.ncells == 2) {
    /* first appearance: piece 0's five, then piece 1's but its corner 0 */
    CHECK(r.conn[8] == 0 && r.conn[9] == 5 && r.conn[10] == 6 && r.conn[11] == 7);
    CHECK(memcmp(r.xyz + 3 * 4, x0, 24) == 0 && memcmp(r.xyz + 3 * 8, x1 + 3, 24) == 0);
  }
  mx_mesh_data_free(&r);
}

/* ---- the hash ------------------------------------------------------------ */

/* The hash's definition (io/mesh_hash.c's head), written out here cell by
 * cell: the sorted coordinate bits chained through splitmix64's
 * finaliser; the cells' hashes summed. */
static uint64_t ref_mix(uint64_t z) {
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  return z ^ (z >> 31);
}

static int ref_triple_cmp(const void *a, const void *b) {
  const uint64_t *x = a, *y = b;
  for (int k = 0; k < 3; k++)
    if (x[k] != y[k]) return x[k] < y[k] ? -1 : 1;
  return 0;
}

static uint64_t ref_hash_sum(const mx_mesh_view *v) {
  const uint64_t golden = 0x9e3779b97f4a7c15ull;
  uint64_t sum = 0;
  for (size_t c = 0; c < v->ncells; c++) {
    const int n = mx_cell_nodes[v->type[c]];
    uint64_t t[8][3];
    for (int j = 0; j < n; j++)
      for (int a = 0; a < 3; a++) {
        const double d = v->xyz[3 * (size_t)v->conn[8 * c + (size_t)j] + (size_t)a];
        uint64_t b;
        memcpy(&b, &d, sizeof b);
        t[j][a] = (b << 1) == 0 ? 0 : b;
      }
    qsort(t, (size_t)n, sizeof t[0], ref_triple_cmp);
    uint64_t h = ref_mix(golden * (v->type[c] + 1u));
    for (int j = 0; j < n; j++)
      for (int a = 0; a < 3; a++) h = ref_mix((h ^ t[j][a]) + golden);
    sum += h;
  }
  return sum;
}

/* mx_mesh_hash_sum (cells hashed four at a time, side by side) against
 * the definition, for every remainder of the cell count by four. */
static void test_hash_definition(const whole *w) {
  mx_mesh_view m = w->v;
  const size_t nc = m.ncells;
  for (size_t drop = 0; drop < 4 && drop < nc; drop++) {
    m.ncells = nc - drop;
    CHECK(mx_mesh_hash_sum(&m) == ref_hash_sum(&m));
  }
}

static void test_hash(const whole *w) {
  test_hash_definition(w);
  const mx_mesh_view *v = &w->v;
  const uint64_t h = mx_mesh_hash(v);
  const size_t nn = v->nnodes, nc = v->ncells;
  double *xyz = malloc((3 * nn + 1) * sizeof *xyz);
  uint32_t *conn = malloc((8 * nc + 1) * sizeof *conn);
  uint8_t *type = malloc(nc + 1);
  if (!xyz || !conn || !type) exit(2);
  /* one ulp on one coordinate of a used node */
  memcpy(xyz, v->xyz, 3 * nn * sizeof *xyz);
  mx_mesh_view m = *v;
  m.xyz = xyz;
  const size_t k = 3 * (size_t)v->conn[8 * (nc / 2)] + 1;
  xyz[k] = nextafter(xyz[k], INFINITY);
  CHECK(mx_mesh_hash(&m) != h);
  xyz[k] = v->xyz[k];
  CHECK(mx_mesh_hash(&m) == h);
  /* cells reversed, nodes numbered backwards, each cell's nodes rotated */
  for (size_t i = 0; i < nn; i++) memcpy(xyz + 3 * (nn - 1 - i), v->xyz + 3 * i, 24);
  for (size_t c = 0; c < nc; c++) {
    const size_t d = nc - 1 - c;
    const int n = mx_cell_nodes[v->type[c]];
    type[d] = v->type[c];
    for (int j = 0; j < 8; j++) conn[8 * d + (size_t)j] = 0;
    for (int j = 0; j < n; j++)
      conn[8 * d + (size_t)((j + 1) % n)] = (uint32_t)(nn - 1 - v->conn[8 * c + (size_t)j]);
  }
  m = (mx_mesh_view){.nnodes = nn, .xyz = xyz, .ncells = nc, .type = type, .conn = conn};
  CHECK(mx_mesh_hash(&m) == h);
  /* the type counts: the same nodes as another type differ */
  const uint8_t t0 = type[0];
  type[0] = t0 == MX_HEX ? MX_PRISM : (uint8_t)(t0 + 1);
  CHECK(mx_mesh_hash(&m) != h);
  type[0] = t0;
  /* a cell less, or a cell twice, differ */
  m.ncells = nc - 1;
  CHECK(mx_mesh_hash(&m) != h);
  m.ncells = nc;
  /* the thread count does not enter: the cells four times over, enough
   * for the parallel sum, hashed by one thread and by several */
  uint32_t *conn4 = malloc((4 * 8 * nc + 1) * sizeof *conn4);
  uint8_t *type4 = malloc(4 * nc + 1);
  if (!conn4 || !type4) exit(2);
  for (int r = 0; r < 4; r++) {
    memcpy(conn4 + 8 * nc * (size_t)r, v->conn, 8 * nc * sizeof *conn4);
    memcpy(type4 + nc * (size_t)r, v->type, nc);
  }
  m = (mx_mesh_view){.nnodes = nn, .xyz = v->xyz, .ncells = 4 * nc, .type = type4,
                     .conn = conn4};
  const int threads = omp_get_max_threads();
  omp_set_num_threads(1);
  const uint64_t h1 = mx_mesh_hash(&m);
  omp_set_num_threads(threads > 1 ? threads : 3);
  CHECK(mx_mesh_hash(&m) == h1);
  omp_set_num_threads(threads);
  CHECK(h1 != h);
  free(conn4);
  free(type4);
  free(xyz);
  free(conn);
  free(type);
  /* -0.0 is 0.0; an unused node changes nothing */
  const double a[5 * 3] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 9, 9, 9};
  double b[5 * 3];
  memcpy(b, a, sizeof a);
  b[0] = -0.0;
  const uint32_t tc[8] = {0, 1, 2, 3};
  const uint8_t tt = MX_TET;
  mx_mesh_view ta = {.nnodes = 4, .xyz = a, .ncells = 1, .type = &tt, .conn = tc};
  mx_mesh_view tb = ta;
  tb.xyz = b;
  CHECK(mx_mesh_hash(&ta) == mx_mesh_hash(&tb));
  tb.nnodes = 5;
  CHECK(mx_mesh_hash(&ta) == mx_mesh_hash(&tb));
  b[3] = nextafter(1.0, 2.0);
  CHECK(mx_mesh_hash(&ta) != mx_mesh_hash(&tb));
  /* no cell: not 0, and not a one-cell mesh's */
  mx_mesh_view none = ta;
  none.ncells = 0;
  CHECK(mx_mesh_hash(&none) != mx_mesh_hash(&ta));
}

/* ---- main ---------------------------------------------------------------- */

static int write_files(const whole *w, const char *dir) {
  char path[1024];
  snprintf(path, sizeof path, "%s/mesh.vtu", dir);
  int st = mx_write_vtu(path, &w->v);
  snprintf(path, sizeof path, "%s/mesh3.pvtu", dir);
  if (st == MX_OK) st = write_parallel(w, path, 3, -1, 1);
  snprintf(path, sizeof path, "%s/coords2.pvtu", dir);
  if (st == MX_OK) st = write_parallel(w, path, 2, -1, 0);
  if (st != MX_OK) fprintf(stderr, "test_pvtu: writing to %s failed\n", dir);
  return st == MX_OK ? 0 : 1;
}

int main(int argc, char **argv) {
  whole w;
  whole_make(&w);
  if (argc == 3 && strcmp(argv[1], "--write") == 0) {
    const int rc = write_files(&w, argv[2]);
    whole_free(&w);
    return rc;
  }
  mkdir(OUT_DIR, 0777);
  CHECK(w.v.ncells > 1000 && w.used > 500);
  test_piece_path();
  test_hash(&w);
  test_round_trip(&w);
  test_duplicates();
  test_master_text(&w);
  test_errors(&w);
  whole_free(&w);
  return TEST_DONE();
}
