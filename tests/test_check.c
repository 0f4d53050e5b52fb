/* Tests of the mesh reader (src/io/read_mesh.c), the independent checker
 * (src/verify/check.c) and `mixoct check` (src/mesher/check_file.c).
 *
 * Meshes are built by hand: one cube as a hexahedron, two prisms, six
 * tetrahedra, six pyramids; conforming blocks; and defects made on purpose
 * (inverted, duplicated and flipped elements, hanging nodes, a quad against
 * two triangles, duplicate and unused nodes). Round trips go through the
 * project's writers; truncated and corrupted files must fail cleanly.
 * Run as "test_check small" to skip the large meshes (for valgrind). */
#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include "check.h"
#include "base/common.h"
#include "file_util.h"
#include "io/read_mesh.h"
#include "kernels/boundary.h"
#include "verify/check.h"
#include "kernels/contacts.h"
#include "soa/mesh.h"
#include "soa/trisoup.h"
#include "io/read_surface.h"
#include "io/write_mesh.h"

static int small_only = 0;
static char tmpdir[64];
static char mixoct[4096];

/* ====================================================================== */
/* Building meshes                                                        */
/* ====================================================================== */

typedef struct {
  size_t nn, nc, capn, capc;
  double *xyz;
  uint8_t *type;
  uint32_t *conn;
} tm;

static void *xrealloc(void *p, size_t n) {
  void *q = realloc(p, n ? n : 1);
  if (!q) {
    fprintf(stderr, "test: out of memory\n");
    exit(2);
  }
  return q;
}

static uint32_t tm_add(tm *t, double x, double y, double z) {
  if (t->nn == t->capn) {
    t->capn = t->capn ? 2 * t->capn : 16;
    t->xyz = xrealloc(t->xyz, 3 * t->capn * sizeof(double));
  }
  t->xyz[3 * t->nn] = x;
  t->xyz[3 * t->nn + 1] = y;
  t->xyz[3 * t->nn + 2] = z;
  return (uint32_t)t->nn++;
}

/* The node at (x, y, z), added if there is none. */
static uint32_t tm_at(tm *t, double x, double y, double z) {
  for (size_t i = 0; i < t->nn; i++)
    if (t->xyz[3 * i] == x && t->xyz[3 * i + 1] == y && t->xyz[3 * i + 2] == z)
      return (uint32_t)i;
  return tm_add(t, x, y, z);
}

static void tm_cell(tm *t, int type, const uint32_t *v) {
  if (t->nc == t->capc) {
    t->capc = t->capc ? 2 * t->capc : 16;
    t->type = xrealloc(t->type, t->capc);
    t->conn = xrealloc(t->conn, 8 * t->capc * sizeof(uint32_t));
  }
  t->type[t->nc] = (uint8_t)type;
  for (int j = 0; j < 8; j++)
    t->conn[8 * t->nc + (size_t)j] = j < mx_cell_nodes[type] ? v[j] : 0;
  t->nc++;
}

/* Appends a copy of cell c (its row is copied before the arrays grow). */
static void tm_copy_cell(tm *t, size_t c) {
  uint32_t v[8];
  memcpy(v, t->conn + 8 * c, sizeof v);
  tm_cell(t, t->type[c], v);
}

static void tm_free(tm *t) {
  free(t->xyz);
  free(t->type);
  free(t->conn);
  memset(t, 0, sizeof *t);
}

static mx_mesh_data tm_data(const tm *t) {
  mx_mesh_data d = {.nnodes = t->nn, .ncells = t->nc, .xyz = t->xyz, .type = t->type,
                    .conn = t->conn};
  return d;
}

static mx_check_report check_tm(const tm *t, const mx_trisoup *s) {
  mx_mesh_data d = tm_data(t);
  mx_check_report r;
  int st = mx_check_mesh(&d, s, &r);
  CHECK(st == MX_OK);
  return r;
}

/* The same with a fixed volume tolerance (the default is chosen from the
 * mesh: half a layer of elements, far above 5 % for these few hexahedra). */
static mx_check_report check_tm_tol(const tm *t, const mx_trisoup *s, double vtol) {
  mx_mesh_data d = tm_data(t);
  mx_check_options o;
  mx_check_defaults(&o);
  o.volume_tol = vtol;
  mx_check_report r;
  CHECK(mx_check_mesh_opt(&d, s, &o, &r) == MX_OK);
  return r;
}

/* The 8 corners of a box in VTK hexahedron order. */
static void box_corners(tm *t, const double lo[3], const double hi[3],
                        uint32_t v[8]) {
  for (int k = 0; k < 8; k++) {
    const int bx = (k & 1) ^ ((k >> 1) & 1), by = (k >> 1) & 1, bz = k >> 2;
    v[k] = tm_at(t, bx ? hi[0] : lo[0], by ? hi[1] : lo[1],
                 bz ? hi[2] : lo[2]);
  }
}

static void box_hex(tm *t, double x0, double y0, double z0, double x1,
                    double y1, double z1) {
  const double lo[3] = {x0, y0, z0}, hi[3] = {x1, y1, z1};
  uint32_t v[8];
  box_corners(t, lo, hi, v);
  tm_cell(t, MX_HEX, v);
}

/* Kuhn's six tetrahedra along the diagonal lo -> hi, positively oriented. */
static void box_tets(tm *t, const double lo[3], const double hi[3]) {
  static const int perm[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2},
                                 {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  for (int p = 0; p < 6; p++) {
    double c[4][3];
    memcpy(c[0], lo, sizeof c[0]);
    memcpy(c[1], c[0], sizeof c[0]);
    c[1][perm[p][0]] = hi[perm[p][0]];
    memcpy(c[2], c[1], sizeof c[0]);
    c[2][perm[p][1]] = hi[perm[p][1]];
    memcpy(c[3], hi, sizeof c[0]);
    double e[3][3];
    for (int k = 0; k < 3; k++)
      for (int x = 0; x < 3; x++) e[k][x] = c[k + 1][x] - c[0][x];
    double det = e[0][0] * (e[1][1] * e[2][2] - e[1][2] * e[2][1]) -
                 e[0][1] * (e[1][0] * e[2][2] - e[1][2] * e[2][0]) +
                 e[0][2] * (e[1][0] * e[2][1] - e[1][1] * e[2][0]);
    if (det < 0) {
      double tmp[3];
      memcpy(tmp, c[1], sizeof tmp);
      memcpy(c[1], c[2], sizeof tmp);
      memcpy(c[2], tmp, sizeof tmp);
    }
    uint32_t v[4];
    for (int k = 0; k < 4; k++) v[k] = tm_at(t, c[k][0], c[k][1], c[k][2]);
    tm_cell(t, MX_TET, v);
  }
}

/* Two prisms along z, the square split along (x0,y0)-(x1,y1). */
static void box_prisms(tm *t, const double lo[3], const double hi[3]) {
  const double tri[2][3][2] = {
      {{lo[0], lo[1]}, {hi[0], lo[1]}, {hi[0], hi[1]}},
      {{lo[0], lo[1]}, {hi[0], hi[1]}, {lo[0], hi[1]}}};
  for (int p = 0; p < 2; p++) {
    uint32_t v[6];
    for (int k = 0; k < 3; k++) {
      v[k] = tm_at(t, tri[p][k][0], tri[p][k][1], lo[2]);
      v[k + 3] = tm_at(t, tri[p][k][0], tri[p][k][1], hi[2]);
    }
    tm_cell(t, MX_PRISM, v);
  }
}

/* Six pyramids from the faces of the box to its centre. */
static void box_pyramids(tm *t, const double lo[3], const double hi[3]) {
  static const int hex_f[6][4] = {{0, 3, 2, 1}, {4, 5, 6, 7}, {0, 1, 5, 4},
                                  {1, 2, 6, 5}, {2, 3, 7, 6}, {3, 0, 4, 7}};
  uint32_t c[8];
  box_corners(t, lo, hi, c);
  const uint32_t ctr = tm_at(t, 0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1]),
                             0.5 * (lo[2] + hi[2]));
  for (int f = 0; f < 6; f++) { /* base: the outward face reversed */
    uint32_t v[5] = {c[hex_f[f][0]], c[hex_f[f][3]], c[hex_f[f][2]],
                     c[hex_f[f][1]], ctr};
    tm_cell(t, MX_PYRAMID, v);
  }
}

/* An n^3 grid of hexahedra of side h from the origin; cell `skip` left out
 * (-1: none); nodes no cell uses are not created. */
static void grid_hexes(tm *t, size_t n, double h, long skip) {
  const size_t np = n + 1;
  uint32_t *id = xrealloc(NULL, np * np * np * sizeof *id);
  for (size_t i = 0; i < np * np * np; i++) id[i] = UINT32_MAX;
  for (size_t k = 0; k < n; k++)
    for (size_t j = 0; j < n; j++)
      for (size_t i = 0; i < n; i++) {
        if ((long)((k * n + j) * n + i) == skip) continue;
        uint32_t v[8];
        for (int c = 0; c < 8; c++) {
          const size_t bx = (size_t)((c & 1) ^ ((c >> 1) & 1)),
                       by = (size_t)((c >> 1) & 1), bz = (size_t)(c >> 2);
          const size_t g = ((k + bz) * np + j + by) * np + i + bx;
          if (id[g] == UINT32_MAX)
            id[g] = tm_add(t, h * (double)(i + bx), h * (double)(j + by),
                           h * (double)(k + bz));
          v[c] = id[g];
        }
        tm_cell(t, MX_HEX, v);
      }
  free(id);
}

static const double O[3] = {0, 0, 0}, I[3] = {1, 1, 1};

static int near(double a, double b, double tol) { return fabs(a - b) <= tol; }

/* ====================================================================== */
/* Valid meshes                                                           */
/* ====================================================================== */

static void expect_clean(const mx_check_report *r, double volume,
                         const char *what) {
  if (r->defects || !near(r->volume, volume, 1e-14) || !(r->jens_min > 0))
    fprintf(stderr, "%s: defects %zu volume %.17g jens_min %g\n", what,
            r->defects, r->volume, r->jens_min);
  CHECK(r->defects == 0);
  CHECK(r->invalid == 0);
  CHECK(r->faces_overshared == 0 && r->faces_misoriented == 0);
  CHECK(r->open_boundary_edges == 0 && r->quad_vs_triangles == 0);
  CHECK(r->hanging_nodes == 0 && r->unused_nodes == 0);
  CHECK(r->duplicate_nodes == 0);
  CHECK(r->empty == 0 && r->degenerate == 0 &&
        r->geometric_hanging_nodes == 0);
  CHECK(r->volume_off == 0 && r->boundary_off_surface == 0);
  for (int k = 0; k < MX_CK_ELEM_KINDS; k++) CHECK(r->elem_ids[k].n == 0);
  for (int k = 0; k < MX_CK_NODE_KINDS; k++) CHECK(r->node_ids[k].n == 0);
  CHECK(near(r->volume, volume, 1e-14));
  CHECK(r->jens_min > 0);
  CHECK(isnan(r->surface_volume) && isnan(r->volume_error) &&
        isnan(r->boundary_max_dist));
}

static void test_valid(void) {
  tm t = {0};
  /* One hexahedron. */
  box_hex(&t, 0, 0, 0, 1, 1, 1);
  mx_check_report r = check_tm(&t, NULL);
  expect_clean(&r, 1.0, "hex");
  CHECK(r.nodes == 8 && r.elements == 1 && r.by_type[MX_HEX] == 1);
  CHECK(r.faces_boundary == 6 && r.faces_interior == 0);
  CHECK(r.jens_min == 1.0 && r.jens_mean == 1.0);
  tm_free(&t);

  /* Two prisms. */
  box_prisms(&t, O, I);
  r = check_tm(&t, NULL);
  expect_clean(&r, 1.0, "prisms");
  CHECK(r.by_type[MX_PRISM] == 2 && r.nodes == 8);
  CHECK(r.faces_interior == 1 && r.faces_boundary == 8);
  tm_free(&t);

  /* Kuhn's six tetrahedra. */
  box_tets(&t, O, I);
  r = check_tm(&t, NULL);
  expect_clean(&r, 1.0, "tets");
  CHECK(r.by_type[MX_TET] == 6 && r.nodes == 8);
  CHECK(r.faces_interior == 6 && r.faces_boundary == 12);
  tm_free(&t);

  /* Six pyramids around the centre. */
  box_pyramids(&t, O, I);
  r = check_tm(&t, NULL);
  expect_clean(&r, 1.0, "pyramids");
  CHECK(r.by_type[MX_PYRAMID] == 6 && r.nodes == 9);
  CHECK(r.faces_interior == 12 && r.faces_boundary == 6);
  tm_free(&t);

  /* Mixed: a hexahedron, two prisms, six pyramids and six tetrahedra in a
   * row, sharing their square faces (the tetrahedra's diagonal differs
   * from the pyramids', so they get a box of their own, joined to the
   * prisms' by their x faces: the prisms' x=3 face is a quad, against the
   * tetrahedra's two triangles -- not allowed, hence the gap). */
  box_hex(&t, 0, 0, 0, 1, 1, 1);
  const double p0[3] = {1, 0, 0}, p1[3] = {2, 1, 1};
  box_prisms(&t, p0, p1);
  const double q0[3] = {2, 0, 0}, q1[3] = {3, 1, 1};
  box_pyramids(&t, q0, q1);
  const double s0[3] = {5, 0, 0}, s1[3] = {6, 1, 1};
  box_tets(&t, s0, s1);
  r = check_tm(&t, NULL);
  expect_clean(&r, 4.0, "mixed");
  CHECK(r.by_type[MX_HEX] == 1 && r.by_type[MX_PRISM] == 2 &&
        r.by_type[MX_PYRAMID] == 6 && r.by_type[MX_TET] == 6);
  CHECK(r.faces_interior == 1 + 1 + 1 + 12 + 6);
  tm_free(&t);

  /* A cube as two 1 x 1 x 0.5 hexahedra. */
  box_hex(&t, 0, 0, 0, 1, 1, 0.5);
  box_hex(&t, 0, 0, 0.5, 1, 1, 1);
  r = check_tm(&t, NULL);
  expect_clean(&r, 1.0, "two hexes");
  CHECK(r.faces_interior == 1 && r.faces_boundary == 10 && r.nodes == 12);
  tm_free(&t);

  /* A 2x2x2 block, full and with a corner missing (still closed). */
  grid_hexes(&t, 2, 0.5, -1);
  r = check_tm(&t, NULL);
  expect_clean(&r, 1.0, "2x2x2");
  CHECK(r.faces_interior == 12 && r.faces_boundary == 24 && r.nodes == 27);
  tm_free(&t);
  grid_hexes(&t, 2, 0.5, 7);
  r = check_tm(&t, NULL);
  expect_clean(&r, 0.875, "2x2x2 minus one");
  CHECK(r.volume == 0.875);
  CHECK(r.elements == 7 && r.nodes == 26);
  CHECK(r.faces_interior == 9 && r.faces_boundary == 24);
  tm_free(&t);

  /* Two cubes touching along one edge only (sharing its two nodes): the
   * boundary is closed and conforming, the shared edge is used by 4
   * boundary faces: non-manifold, not a defect. */
  box_hex(&t, 0, 0, 0, 1, 1, 1);
  box_hex(&t, 1, 1, 0, 2, 2, 1);
  r = check_tm(&t, NULL);
  CHECK(r.defects == 0 && r.nonmanifold_edges == 1 && r.open_boundary_edges == 0);
  CHECK(r.nodes == 14 && r.volume == 2.0);
  tm_free(&t);

  /* An empty mesh is a defect (never "OK"), with NAN qualities; nodes
   * without elements too (and the nodes are unused). */
  r = check_tm(&t, NULL);
  CHECK(r.defects == 1 && r.empty == 1 && r.elements == 0);
  CHECK(isnan(r.jens_min));
  tm_add(&t, 0, 0, 0);
  tm_add(&t, 1, 0, 0);
  r = check_tm(&t, NULL);
  CHECK(r.empty == 1 && r.unused_nodes == 2 && r.defects == 3);
  CHECK(r.node_ids[MX_CK_N_UNUSED].n == 2 &&
        r.node_ids[MX_CK_N_UNUSED].id[1] == 1);
  tm_free(&t);
}

/* ====================================================================== */
/* Defects                                                                */
/* ====================================================================== */

static void test_defects(void) {
  tm t = {0};
  /* An inverted tetrahedron. */
  uint32_t v[8] = {tm_add(&t, 0, 0, 0), tm_add(&t, 0, 1, 0),
                   tm_add(&t, 1, 0, 0), tm_add(&t, 0, 0, 1)};
  tm_cell(&t, MX_TET, v);
  mx_check_report r = check_tm(&t, NULL);
  CHECK(r.invalid == 1 && r.defects == 1);
  CHECK(r.jens_min < 0 && near(r.volume, -1.0 / 6.0, 1e-15));
  CHECK(r.faces_boundary == 4 && r.open_boundary_edges == 0);
  tm_free(&t);

  /* A duplicated element: its face against the other hexahedron is used
   * three times, its five other faces twice the same way round. */
  box_hex(&t, 0, 0, 0, 1, 1, 1);
  box_hex(&t, 0, 0, 1, 1, 1, 2);
  tm_copy_cell(&t, 0);
  r = check_tm(&t, NULL);
  CHECK(r.faces_overshared == 1);
  CHECK(r.faces_misoriented == 5);
  /* only the upper hexahedron's five faces are boundary faces: the four
   * edges around their open bottom are used once */
  CHECK(r.faces_boundary == 5 && r.open_boundary_edges == 4);
  CHECK(r.defects == 10);
  tm_free(&t);

  /* A hexahedron next to two of half its height: the two nodes in the
   * middle of its x=1 edges hang, and its x=1 face's top and bottom edges
   * are used by four boundary faces each (even: not open, but reported as
   * non-manifold; the hanging nodes are the defects). */
  box_hex(&t, 0, 0, 0, 1, 1, 1);
  box_hex(&t, 1, 0, 0, 2, 1, 0.5);
  box_hex(&t, 1, 0, 0.5, 2, 1, 1);
  r = check_tm(&t, NULL);
  CHECK(r.hanging_nodes == 2);
  CHECK(r.open_boundary_edges == 0 && r.nonmanifold_edges == 2);
  CHECK(r.faces_interior == 1);
  CHECK(r.defects == 2);
  tm_free(&t);

  /* Four small hexahedra against one face: the face centre hangs too. */
  box_hex(&t, 0, 0, 0, 1, 1, 1);
  box_hex(&t, 1, 0, 0, 1.5, 0.5, 0.5);
  box_hex(&t, 1, 0.5, 0, 1.5, 1, 0.5);
  box_hex(&t, 1, 0, 0.5, 1.5, 0.5, 1);
  box_hex(&t, 1, 0.5, 0.5, 1.5, 1, 1);
  r = check_tm(&t, NULL);
  CHECK(r.hanging_nodes == 5); /* 4 edge midpoints + the face centre */
  CHECK(r.defects > 0);
  tm_free(&t);

  /* A quad face against two triangles of tetrahedra. */
  box_hex(&t, 0, 0, 0, 1, 1, 1);
  const double a0[3] = {1, 0, 0}, a1[3] = {2, 1, 1};
  box_tets(&t, a0, a1);
  r = check_tm(&t, NULL);
  CHECK(r.quad_vs_triangles == 1);
  CHECK(r.open_boundary_edges == 0 && r.nonmanifold_edges == 4);
  CHECK(r.hanging_nodes == 0 && r.invalid == 0);
  CHECK(r.defects == 1);
  tm_free(&t);

  /* A flipped element: inverted, and its shared face has the same
   * orientation on both sides. */
  box_hex(&t, 0, 0, 0, 1, 1, 1);
  box_hex(&t, 0, 0, 1, 1, 1, 2);
  uint32_t *row = t.conn + 8;
  uint32_t flipped[8] = {row[4], row[5], row[6], row[7],
                         row[0], row[1], row[2], row[3]};
  memcpy(row, flipped, sizeof flipped);
  r = check_tm(&t, NULL);
  CHECK(r.faces_misoriented == 1 && r.invalid == 1);
  CHECK(r.faces_interior == 1);
  CHECK(r.defects == 2);
  CHECK(near(r.volume, 0.0, 1e-14));
  tm_free(&t);

  /* Duplicate and unused nodes. */
  box_hex(&t, 0, 0, 0, 1, 1, 1);
  tm_add(&t, 0, 0, 0);
  tm_add(&t, 5, 5, 5);
  tm_add(&t, -0.0, 0, 0); /* -0 equals 0 */
  r = check_tm(&t, NULL);
  CHECK(r.duplicate_nodes == 2 && r.unused_nodes == 3 && r.defects == 5);
  tm_free(&t);

  /* Two hexahedra that touch but do not share their nodes: two closed
   * boxes, four duplicate nodes. */
  box_hex(&t, 0, 0, 0, 1, 1, 1);
  size_t n0 = t.nn;
  box_hex(&t, 0, 0, 1, 1, 1, 2);
  for (int j = 0; j < 4; j++) { /* give the second its own bottom nodes */
    const uint32_t old = t.conn[8 + (size_t)j];
    t.conn[8 + (size_t)j] =
        tm_add(&t, t.xyz[3 * old], t.xyz[3 * old + 1], t.xyz[3 * old + 2]);
  }
  CHECK(t.nn == n0 + 8);
  r = check_tm(&t, NULL);
  CHECK(r.duplicate_nodes == 4 && r.faces_interior == 0 &&
        r.faces_boundary == 12 && r.open_boundary_edges == 0);
  CHECK(r.defects == 4);
  tm_free(&t);

  /* Degenerate: a hexahedron with a repeated node. */
  box_hex(&t, 0, 0, 0, 1, 1, 1);
  t.conn[6] = t.conn[5];
  tm_add(&t, 9, 9, 9);
  r = check_tm(&t, NULL);
  CHECK(r.invalid == 1 && r.defects >= 1);
  tm_free(&t);

  /* Bad input: a node index out of range is refused. */
  box_hex(&t, 0, 0, 0, 1, 1, 1);
  t.conn[3] = 99;
  mx_mesh_data d = tm_data(&t);
  fprintf(stderr, "(an error about cell 0 is expected)\n");
  CHECK(mx_check_mesh(&d, NULL, &r) == MX_EINPUT);
  tm_free(&t);
}

/* ====================================================================== */
/* Files                                                                  */
/* ====================================================================== */

static const char *tpath(const char *name) {
  static char buf[8][256];
  static int k = 0;
  k = (k + 1) % 8;
  snprintf(buf[k], sizeof buf[k], "%s/%s", tmpdir, name);
  return buf[k];
}

static void write_bytes(const char *path, const void *data, size_t n) {
  FILE *f = fopen(path, "wb");
  if (!f || fwrite(data, 1, n, f) != n) {
    fprintf(stderr, "test: cannot write %s\n", path);
    exit(2);
  }
  fclose(f);
}

static void write_text(const char *path, const char *s) {
  write_bytes(path, s, strlen(s));
}

/* Runs fn with stderr sent to a file; returns what was printed. */
static char *captured(int (*fn)(const char *, mx_mesh_data *),
                      const char *path, mx_mesh_data *out, int *status) {
  const char *errf = tpath("stderr.txt");
  fflush(stderr);
  int saved = dup(2);
  FILE *f = fopen(errf, "w");
  dup2(fileno(f), 2);
  *status = fn(path, out);
  fflush(stderr);
  dup2(saved, 2);
  close(saved);
  fclose(f);
  size_t n;
  return slurp(errf, &n);
}

static int same_mesh(const tm *a, const mx_mesh_data *b) {
  if (a->nn != b->nnodes || a->nc != b->ncells) return 0;
  if (memcmp(a->xyz, b->xyz, 3 * a->nn * sizeof(double))) return 0;
  for (size_t c = 0; c < a->nc; c++) {
    if (a->type[c] != b->type[c]) return 0;
    for (int j = 0; j < mx_cell_nodes[a->type[c]]; j++)
      if (a->conn[8 * c + (size_t)j] != b->conn[8 * c + (size_t)j]) return 0;
    for (int j = mx_cell_nodes[a->type[c]]; j < 8; j++)
      if (b->conn[8 * c + (size_t)j] != 0) return 0;
  }
  return 1;
}

/* The mixed mesh with awkward coordinates (bit-exact round trips). */
static void awkward_mesh(tm *t) {
  memset(t, 0, sizeof *t);
  box_hex(t, 0, 0, 0, 1, 1, 1);
  box_prisms(t, (const double[3]){1, 0, 0}, (const double[3]){2, 1, 1});
  box_pyramids(t, (const double[3]){2, 0, 0}, (const double[3]){3, 1, 1});
  box_tets(t, (const double[3]){5, 0, 0}, (const double[3]){6, 1, 1});
  uint64_t s = 0x9E3779B97F4A7C15ull;
  for (size_t i = 0; i < 3 * t->nn; i++) {
    s ^= s << 13;
    s ^= s >> 7;
    s ^= s << 17;
    t->xyz[i] = t->xyz[i] / 3.0 + (double)(s % 1000003) * 1e-13 - 1e-300;
  }
  t->xyz[0] = -0.0;
  t->xyz[1] = 1e300;
  t->xyz[2] = 4.9e-324;
}

static void test_round_trips(void) {
  tm t;
  awkward_mesh(&t);
  int32_t *cf = calloc(t.nc, sizeof *cf);
  double *pf = calloc(t.nn, sizeof *pf);
  for (size_t i = 0; i < t.nn; i++) pf[i] = (double)i / 7.0;
  mx_field cfield = {.name = "cell id", .ivalues = cf},
           pfield = {.name = "p", .is_double = 1, .dvalues = pf};
  mx_mesh_data d = tm_data(&t);
  mx_mesh_view v = mx_mesh_data_view(&d);
  mx_mesh_view vf = v;
  vf.ncell_fields = 1;
  vf.cell_fields = &cfield;
  vf.npoint_fields = 1;
  vf.point_fields = &pfield;
  const char *names[6] = {"a.vtu",     "a.vtk",      "a_ascii.vtk",
                          "f.vtu",     "f.vtk",      "f_ascii.vtk"};
  for (int k = 0; k < 6; k++) {
    const char *p = tpath(names[k]);
    const mx_mesh_view *w = k < 3 ? &v : &vf;
    int st = k % 3 == 0 ? mx_write_vtu(p, w)
                        : mx_write_vtk_legacy(p, w, k % 3 == 1);
    CHECK(st == MX_OK);
    mx_mesh_data back;
    st = mx_read_mesh(p, &back);
    CHECK(st == MX_OK);
    if (st == MX_OK) {
      if (!same_mesh(&t, &back)) fprintf(stderr, "round trip %s\n", p);
      CHECK(same_mesh(&t, &back));
      mx_mesh_data_free(&back);
    }
  }
  free(cf);
  free(pf);
  tm_free(&t);
  /* An empty mesh round-trips too. */
  mx_mesh_data empty = {.nnodes = 0};
  mx_mesh_view ev = mx_mesh_data_view(&empty);
  for (int k = 0; k < 3; k++) {
    const char *p = tpath(k == 0 ? "e.vtu" : k == 1 ? "e.vtk" : "ea.vtk");
    CHECK((k == 0 ? mx_write_vtu(p, &ev) : mx_write_vtk_legacy(p, &ev, k == 1))
          == MX_OK);
    mx_mesh_data back;
    CHECK(mx_read_mesh(p, &back) == MX_OK);
    CHECK(back.nnodes == 0 && back.ncells == 0);
    mx_mesh_data_free(&back);
  }
}

/* A VTU written here with other types: Float32 points, Int32 or UInt8
 * arrays, UInt32 headers, ascii or appended. */
static void write_vtu_variant(const char *path, const tm *t, int ascii,
                              int h64) {
  char *x = NULL;
  size_t xn = 0;
  FILE *f = open_memstream(&x, &xn);
  size_t nconn = 0;
  for (size_t c = 0; c < t->nc; c++) nconn += (size_t)mx_cell_nodes[t->type[c]];
  fprintf(f,
          "<?xml version=\"1.0\"?>\n<!-- a comment -->\n"
          "<VTKFile type='UnstructuredGrid' version=\"0.1\" "
          "byte_order=\"LittleEndian\"%s>\n<UnstructuredGrid>\n"
          "<Piece NumberOfPoints=\"%zu\" NumberOfCells=\"%zu\">\n",
          h64 ? " header_type=\"UInt64\"" : "", t->nn, t->nc);
  const size_t hs = h64 ? 8 : 4;
  size_t off = 0;
  const char *fmt = ascii ? "format=\"ascii\">" : "format=\"appended\" offset";
  fprintf(f, "<PointData><DataArray type=\"Float64\" Name=\"x\" %s", fmt);
  if (ascii) {
    for (size_t i = 0; i < t->nn; i++) fprintf(f, " %zu", i);
    fprintf(f, "</DataArray>");
  } else {
    fprintf(f, "=\"%zu\"/>", off);
    off += hs + 8 * t->nn;
  }
  fprintf(f, "</PointData>\n<Points>\n<DataArray type=\"Float32\" "
             "NumberOfComponents=\"3\" %s", fmt);
  if (ascii) {
    for (size_t i = 0; i < 3 * t->nn; i++) fprintf(f, "%g\n", t->xyz[i]);
    fprintf(f, "</DataArray>\n");
  } else {
    fprintf(f, "=\"%zu\"/>\n", off);
    off += hs + 12 * t->nn;
  }
  fprintf(f, "</Points>\n<Cells>\n");
  const char *arr[3] = {"connectivity", "offsets", "types"};
  const char *typ[3] = {"Int32", "UInt32", "UInt8"};
  const size_t cnt[3] = {nconn, t->nc, t->nc}, sz[3] = {4, 4, 1};
  for (int a = 0; a < 3; a++) {
    fprintf(f, "<DataArray type=\"%s\" Name=\"%s\" %s", typ[a], arr[a], fmt);
    if (ascii) {
      size_t end = 0;
      for (size_t c = 0; c < t->nc; c++) {
        const int nn = mx_cell_nodes[t->type[c]];
        if (a == 0)
          for (int j = 0; j < nn; j++) fprintf(f, " %u", t->conn[8 * c + mx_vtk_order[t->type[c]][j]]);
        end += (size_t)nn;
        if (a == 1) fprintf(f, " %zu", end);
        if (a == 2) fprintf(f, " %d", mx_vtk_cell_type[t->type[c]]);
      }
      fprintf(f, "\n</DataArray>\n");
    } else {
      fprintf(f, "=\"%zu\"/>\n", off);
      off += hs + sz[a] * cnt[a];
    }
  }
  fprintf(f, "</Cells>\n</Piece>\n</UnstructuredGrid>\n");
  if (!ascii) {
    fprintf(f, "<AppendedData encoding=\"raw\">\n _");
    uint64_t n8;
    uint32_t n4;
#define HEAD(bytes)                 \
  do {                              \
    n8 = (bytes);                   \
    n4 = (uint32_t)(bytes);         \
    if (h64)                        \
      fwrite(&n8, 8, 1, f);         \
    else                            \
      fwrite(&n4, 4, 1, f);         \
  } while (0)
    HEAD(8 * t->nn);
    for (size_t i = 0; i < t->nn; i++) {
      double v = (double)i;
      fwrite(&v, 8, 1, f);
    }
    HEAD(12 * t->nn);
    for (size_t i = 0; i < 3 * t->nn; i++) {
      float v = (float)t->xyz[i];
      fwrite(&v, 4, 1, f);
    }
    HEAD(4 * nconn);
    for (size_t c = 0; c < t->nc; c++)
      for (int j = 0; j < mx_cell_nodes[t->type[c]]; j++)
        fwrite(&t->conn[8 * c + mx_vtk_order[t->type[c]][j]], 4, 1, f);
    HEAD(4 * t->nc);
    uint32_t end = 0;
    for (size_t c = 0; c < t->nc; c++) {
      end += (uint32_t)mx_cell_nodes[t->type[c]];
      fwrite(&end, 4, 1, f);
    }
    HEAD(t->nc);
    for (size_t c = 0; c < t->nc; c++) {
      uint8_t ty = (uint8_t)mx_vtk_cell_type[t->type[c]];
      fwrite(&ty, 1, 1, f);
    }
#undef HEAD
    fprintf(f, "\n</AppendedData>\n");
  }
  fprintf(f, "</VTKFile>\n");
  fclose(f);
  write_bytes(path, x, xn);
  free(x);
}

static const char hand_legacy[] =
    "# vtk DataFile Version 3.0\n"
    "written by hand\n"
    "ASCII\n"
    "DATASET UNSTRUCTURED_GRID\n"
    "FIELD FieldData 1\n"
    "TIME 1 1 double\n"
    "0.5\n"
    "POINTS 8 float\n"
    "0 0 0 1 0 0 1 1 0 0 1 0\n"
    "0 0 1 1 0 1 1 1 1 0 1 1\n"
    "CELLS 1 9\n"
    "8 0 1 2 3 4 5 6 7\n"
    "CELL_TYPES 1\n"
    "12\n"
    "CELL_DATA 1\n"
    "SCALARS q double 1\n"
    "LOOKUP_TABLE default\n"
    "1\n";

static const char hand_v51[] =
    "# vtk DataFile Version 5.1\n"
    "vtk output\n"
    "ASCII\n"
    "DATASET UNSTRUCTURED_GRID\n"
    "POINTS 8 double\n"
    "0 0 0 1 0 0 1 1 0 0 1 0\n"
    "0 0 1 1 0 1 1 1 1 0 1 1\n"
    "METADATA\n"
    "INFORMATION 0\n"
    "\n"
    "CELLS 2 8\n"
    "OFFSETS vtktypeint64\n"
    "0 8\n"
    "CONNECTIVITY vtktypeint64\n"
    "0 1 2 3 4 5 6 7\n"
    "CELL_TYPES 1\n"
    "12\n";

/* Line 11 holds the bad type. */
static const char bad_type[] =
    "# vtk DataFile Version 3.0\n"
    "a triangle\n"
    "ASCII\n"
    "DATASET UNSTRUCTURED_GRID\n"
    "POINTS 3 double\n"
    "0 0 0 1 0 0 0 1 0\n"
    "CELLS 1 4\n"
    "3 0 1 2\n"
    "CELL_TYPES 1\n"
    "\n"
    "5\n";

static const char bad_index[] =
    "# vtk DataFile Version 3.0\n"
    "index out of range on line 8\n"
    "ASCII\n"
    "DATASET UNSTRUCTURED_GRID\n"
    "POINTS 4 double\n"
    "0 0 0 1 0 0 0 1 0 0 0 1\n"
    "CELLS 1 5\n"
    "4 0 1 2 4\n"
    "CELL_TYPES 1\n"
    "10\n";

static void expect_error(const char *name, const char *text,
                         const char *want) {
  const char *p = tpath(name);
  write_text(p, text);
  mx_mesh_data m;
  int st;
  char *err = captured(mx_read_mesh, p, &m, &st);
  CHECK(st == MX_EINPUT);
  CHECK(m.xyz == NULL && m.conn == NULL && m.nnodes == 0);
  char full[512];
  snprintf(full, sizeof full, "%s%s", p, want);
  if (!err || !strstr(err, full))
    fprintf(stderr, "expected '%s' in: %s\n", full, err ? err : "(null)");
  CHECK(err && strstr(err, full));
  free(err);
}

static void test_formats(void) {
  /* Hand-written legacy files, classic and version 5.1. */
  tm cube = {0};
  box_hex(&cube, 0, 0, 0, 1, 1, 1);
  const char *texts[2] = {hand_legacy, hand_v51};
  for (int k = 0; k < 2; k++) {
    const char *p = tpath(k ? "v51.vtk" : "hand.vtk");
    write_text(p, texts[k]);
    mx_mesh_data m;
    CHECK(mx_read_mesh(p, &m) == MX_OK);
    CHECK(same_mesh(&cube, &m));
    mx_mesh_data_free(&m);
  }
  /* VTU variants: ascii / appended, UInt32 / UInt64 headers. */
  tm t;
  memset(&t, 0, sizeof t);
  box_hex(&t, 0, 0, 0, 1, 1, 1);
  box_prisms(&t, (const double[3]){1, 0, 0}, (const double[3]){2, 1, 1});
  box_pyramids(&t, (const double[3]){2, 0, 0}, (const double[3]){3, 1, 1});
  box_tets(&t, (const double[3]){5, 0, 0}, (const double[3]){6, 1.5, 1});
  for (int v = 0; v < 4; v++) {
    const char *p = tpath("variant.vtu");
    write_vtu_variant(p, &t, v & 1, v >> 1);
    mx_mesh_data m;
    int st = mx_read_mesh(p, &m);
    CHECK(st == MX_OK);
    if (st == MX_OK) {
      CHECK(same_mesh(&t, &m));
      mx_mesh_data_free(&m);
    }
  }
  /* Errors name the file, and the line in text. */
  expect_error("bad_type.vtk", bad_type,
               ":11: error: cell 0 is a triangle and the file has no volume cell");
  expect_error("bad_index.vtk", bad_index, ":8: error: cell 0: node index 4");
  expect_error("garbage.vtk", "hello\n", ":1: error: unknown mesh format");
  expect_error("polydata.vtk",
               "# vtk DataFile Version 3.0\nx\nASCII\nDATASET POLYDATA\n",
               ":4: error: DATASET POLYDATA");
  expect_error("nan.vtk",
               "# vtk DataFile Version 3.0\nx\nASCII\nDATASET "
               "UNSTRUCTURED_GRID\nPOINTS 1 double\n0 nan 0\n",
               ":6: error: POINTS: value 1: 'nan' is not a finite number");
  expect_error("short.vtk",
               "# vtk DataFile Version 3.0\nx\nASCII\nDATASET "
               "UNSTRUCTURED_GRID\nPOINTS 3 double\n0 0 0\n1 1 1\n",
               ":5: error: POINTS: 9 values announced");
  expect_error("compressed.vtu",
               "<VTKFile type=\"UnstructuredGrid\" "
               "compressor=\"vtkZstdDataCompressor\">\n",
               ":1: error: compressor \"vtkZstdDataCompressor\" is not supported");
  /* Files ending in a number, around page-size multiples (mapped files
   * rely on the zeros after the end of the file; exact multiples are
   * copied). */
  const long page = sysconf(_SC_PAGESIZE);
  const long sizes[4] = {page - 1, page, page + 1, 2 * page};
  for (int k = 0; k < 4; k++) {
    const char *head =
        "# vtk DataFile Version 3.0\nx\nASCII\nDATASET UNSTRUCTURED_GRID\n"
        "POINTS 8 double\n0 0 0 1 0 0 1 1 0 0 1 0 0 0 1 1 0 1 1 1 1 0 1 1";
    const char *tail = "\nCELLS 1 9\n8 0 1 2 3 4 5 6 7\nCELL_TYPES 1\n12";
    const size_t hl = strlen(head), tl = strlen(tail);
    char *b = malloc((size_t)sizes[k] + 1);
    memcpy(b, head, hl);
    memset(b + hl, ' ', (size_t)sizes[k] - hl - tl);
    memcpy(b + sizes[k] - (long)tl, tail, tl);
    const char *p = tpath("page.vtk");
    write_bytes(p, b, (size_t)sizes[k]);
    free(b);
    mx_mesh_data pm;
    CHECK(mx_read_mesh(p, &pm) == MX_OK);
    CHECK(same_mesh(&cube, &pm));
    mx_mesh_data_free(&pm);
  }
  mx_mesh_data m;
  int st;
  char *err = captured(mx_read_mesh, tpath("missing.vtu"), &m, &st);
  CHECK(st == MX_EINPUT && err && strstr(err, "missing.vtu: error: cannot open"));
  free(err);
  tm_free(&t);
  tm_free(&cube);
}

static void group_by_type(const tm *t, tm *g);

/* Every prefix of a file, and many corrupted copies, must be read or
 * refused cleanly; whatever is read must be a valid mesh. */
static void test_damage(void) {
  tm t;
  awkward_mesh(&t);
  mx_mesh_data d = tm_data(&t);
  mx_mesh_view v = mx_mesh_data_view(&d);
  tm grouped; /* Medit's order */
  group_by_type(&t, &grouped);
  enum { NSRC = 7 };
  const char *src[NSRC] = {tpath("d.vtu"),    tpath("d.vtk"),
                           tpath("da.vtk"),   tpath("d.msh"),
                           tpath("da.msh"),   tpath("d.meshb"),
                           tpath("d.mesh")};
  const tm *want[NSRC] = {&t, &t, &t, &t, &t, &grouped, &grouped};
  CHECK(mx_write_vtu(src[0], &v) == MX_OK);
  CHECK(mx_write_vtk_legacy(src[1], &v, 1) == MX_OK);
  CHECK(mx_write_vtk_legacy(src[2], &v, 0) == MX_OK);
  CHECK(mx_write_msh(src[3], &v, 1) == MX_OK);
  CHECK(mx_write_msh(src[4], &v, 0) == MX_OK);
  CHECK(mx_write_medit(src[5], &v, 1) == MX_OK);
  CHECK(mx_write_medit(src[6], &v, 0) == MX_OK);
  const char *cut = tpath("cut.bin");
  fflush(stderr);
  int saved = dup(2); /* hundreds of expected messages: silence them */
  FILE *saved_err = fdopen(dup(saved), "w");
  FILE *null = fopen("/dev/null", "w");
  dup2(fileno(null), 2);
  size_t ok_prefix = 0, refused = 0;
  for (int k = 0; k < NSRC; k++) {
    size_t n;
    char *b = slurp(src[k], &n);
    CHECK(b != NULL);
    if (!b) continue;
    const size_t step = small_only ? 7 : 1;
    for (size_t len = 0; len < n; len += step) {
      write_bytes(cut, b, len);
      mx_mesh_data m;
      int st = mx_read_mesh(cut, &m);
      if (st == MX_OK) { /* only trailing bytes were lost */
        ok_prefix++;
        if (!same_mesh(want[k], &m))
          fprintf(saved_err, "%s: prefix of %zu bytes read as another mesh\n",
                  src[k], len);
        CHECK(same_mesh(want[k], &m));
        mx_mesh_data_free(&m);
      } else {
        refused++;
        CHECK(st == MX_EINPUT);
      }
    }
    uint64_t s = 88172645463325252ull + (uint64_t)k;
    const int trials = small_only ? 150 : 1500;
    for (int trial = 0; trial < trials; trial++) {
      char *c = malloc(n);
      memcpy(c, b, n);
      const int flips = 1 + trial % 4;
      for (int f = 0; f < flips; f++) {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        c[s % n] = (char)(s >> 40);
      }
      write_bytes(cut, c, n);
      free(c);
      mx_mesh_data m;
      int st = mx_read_mesh(cut, &m);
      CHECK(st == MX_OK || st == MX_EINPUT);
      if (st == MX_OK) {
        mx_check_report r;
        CHECK(mx_check_mesh(&m, NULL, &r) == MX_OK);
        mx_mesh_data_free(&m);
      }
    }
    free(b);
  }
  fflush(stderr);
  dup2(saved, 2);
  close(saved);
  fclose(null);
  fclose(saved_err);
  tm_free(&grouped);
  CHECK(refused > 0);
  printf("damaged files: %zu prefixes read whole, %zu refused\n", ok_prefix,
         refused);
  tm_free(&t);
}

/* ====================================================================== */
/* Surfaces                                                               */
/* ====================================================================== */

static const char cube_off[] =
    "OFF\n8 12 0\n"
    "0 0 0\n1 0 0\n0 1 0\n1 1 0\n0 0 1\n1 0 1\n0 1 1\n1 1 1\n"
    "3 0 2 1\n3 1 2 3\n3 4 5 6\n3 5 7 6\n3 0 1 4\n3 1 5 4\n"
    "3 2 6 3\n3 3 6 7\n3 0 4 2\n3 2 4 6\n3 1 3 5\n3 3 7 5\n";

/* The box [lo, lo + side]^3 with each face cut into k x k squares. */
static void fine_box(mx_trisoup *s, const double lo[3], double side, int k) {
  memset(s, 0, sizeof *s);
  for (int f = 0; f < 6; f++) {
    const int ax = f / 2, up = f % 2;
    const int u = (ax + 1) % 3, w = (ax + 2) % 3;
    for (int i = 0; i < k; i++)
      for (int j = 0; j < k; j++) {
        uint32_t id[4];
        for (int c = 0; c < 4; c++) {
          double p[3];
          p[ax] = lo[ax] + (up ? side : 0.0);
          p[u] = lo[u] + side * (i + (c == 1 || c == 2)) / k;
          p[w] = lo[w] + side * (j + (c >= 2)) / k;
          CHECK(mx_trisoup_reserve(s, s->nv + 1, s->nt + 2) == MX_OK);
          s->x[s->nv] = p[0];
          s->y[s->nv] = p[1];
          s->z[s->nv] = p[2];
          id[c] = (uint32_t)s->nv++;
        }
        /* u x w = ax: counter-clockwise seen from +ax is outward on top */
        if (up) {
          mx_trisoup_add_triangle(s, id[0], id[1], id[2]);
          mx_trisoup_add_triangle(s, id[0], id[2], id[3]);
        } else {
          mx_trisoup_add_triangle(s, id[0], id[2], id[1]);
          mx_trisoup_add_triangle(s, id[0], id[3], id[2]);
        }
      }
  }
}

/* Distance from p to the surface of the box [lo, hi]. */
static double box_surface_dist(const double p[3], const double lo[3],
                               const double hi[3]) {
  double out2 = 0.0, in = INFINITY;
  int inside = 1;
  for (int a = 0; a < 3; a++) {
    double d = fmax(fmax(lo[a] - p[a], p[a] - hi[a]), 0.0);
    if (d > 0) inside = 0;
    out2 += d * d;
    in = fmin(in, fmin(p[a] - lo[a], hi[a] - p[a]));
  }
  return inside ? in : sqrt(out2);
}

static void test_surface(void) {
  const char *off = tpath("cube.off");
  write_text(off, cube_off);
  mx_trisoup s;
  CHECK(mx_read_surface(off, &s) == MX_OK);
  CHECK(mx_trisoup_check(&s, off, NULL) == MX_OK);
  tm t = {0};
  box_hex(&t, 0, 0, 0, 1, 1, 1);
  mx_check_report r = check_tm(&t, &s);
  CHECK(r.defects == 0);
  CHECK(r.surface_volume == 1.0 && r.volume_error == 0.0);
  CHECK(r.boundary_max_dist == 0.0);
  tm_free(&t);
  /* The same surface against the cube as 6 tetrahedra and as pyramids. */
  box_tets(&t, O, I);
  r = check_tm(&t, &s);
  CHECK(near(r.volume_error, 0.0, 1e-15) && r.boundary_max_dist == 0.0);
  tm_free(&t);
  mx_trisoup_free(&s);

  /* A 10^3 grid of the unit cube against finer boxes, moved: the distance
   * must be what the box formula gives, inside and outside. */
  grid_hexes(&t, 10, 0.1, -1);
  const double shifts[3][3] = {
      {0, 0, 0}, {0.013, -0.021, 0.007}, {3.5, 0.25, -2}};
  const double sides[3] = {1.0, 1.1, 0.7};
  for (int k = 0; k < 3; k++) {
    fine_box(&s, shifts[k], sides[k], 8);
    CHECK(s.nt == 6 * 8 * 8 * 2);
    r = check_tm(&t, &s);
    double hi[3], want = 0.0;
    for (int a = 0; a < 3; a++) hi[a] = shifts[k][a] + sides[k];
    mx_check_report noshape = check_tm(&t, NULL);
    CHECK(noshape.faces_boundary == 600);
    /* the boundary nodes of the grid: those on its box's surface */
    for (size_t i = 0; i < t.nn; i++) {
      const double *p = t.xyz + 3 * i;
      int on = 0;
      for (int a = 0; a < 3; a++) on |= p[a] == 0.0 || p[a] == 1.0;
      if (on) want = fmax(want, box_surface_dist(p, shifts[k], hi));
    }
    const double diag = sqrt(3.0) * sides[k];
    CHECK(near(r.boundary_max_dist, want / diag, 1e-12));
    CHECK(near(r.surface_volume, pow(sides[k], 3), 1e-12));
    CHECK(near(r.volume_error, (1.0 - pow(sides[k], 3)) / pow(sides[k], 3),
               1e-12));
    if (!near(r.boundary_max_dist, want / diag, 1e-12))
      fprintf(stderr, "surface %d: distance %.17g, expected %.17g\n", k,
              r.boundary_max_dist, want / diag);
    mx_trisoup_free(&s);
  }
  tm_free(&t);
}

/* ====================================================================== */
/* Geometric checks: hanging nodes by position, degenerate elements,     */
/* empty meshes, the volume, extreme coordinates                          */
/* ====================================================================== */

/* The box [x0,x1]x[y0,y1]x[z0,z1] mapped by s * (x - c), as a
 * hexahedron. */
static void hex_s(tm *t, double s, double c, double x0, double y0,
                  double z0, double x1, double y1, double z1) {
  box_hex(t, s * (x0 - c), s * (y0 - c), s * (z0 - c), s * (x1 - c),
          s * (y1 - c), s * (z1 - c));
}

static int find_shown(const mx_check_report *r, int on) {
  for (size_t i = 0; i < r->nshown; i++)
    if (r->hang_at[i].on == on) return (int)i;
  return -1;
}

/* A hexahedron [0,1]^3 and, against its x = 1 face, the tetrahedra of the
 * cone from P (on that face) over the other five faces of the box
 * [1,2]x[0,1]x[0,1], each split into two triangles: P lies inside the
 * hexahedron's face, no face of it is shared. */
static void hex_and_cone(tm *t, const double P[3]) {
  box_hex(t, 0, 0, 0, 1, 1, 1);
  const double lo[3] = {1, 0, 0}, hi[3] = {2, 1, 1};
  uint32_t c[8];
  box_corners(t, lo, hi, c);
  const uint32_t p = tm_at(t, P[0], P[1], P[2]);
  static const int other[5][4] = {
      {0, 3, 2, 1}, {4, 5, 6, 7}, {0, 1, 5, 4}, {2, 3, 7, 6}, {1, 2, 6, 5}};
  for (int f = 0; f < 5; f++)
    for (int h = 0; h < 2; h++) {
      uint32_t v[4] = {c[other[f][0]], c[other[f][1 + h]],
                       c[other[f][2 + h]], p};
      double e[3][3];
      for (int k = 0; k < 3; k++)
        for (int x = 0; x < 3; x++)
          e[k][x] = t->xyz[3 * v[k + 1] + (size_t)x] - t->xyz[3 * v[0] + (size_t)x];
      const double det = e[0][0] * (e[1][1] * e[2][2] - e[1][2] * e[2][1]) -
                         e[0][1] * (e[1][0] * e[2][2] - e[1][2] * e[2][0]) +
                         e[0][2] * (e[1][0] * e[2][1] - e[1][1] * e[2][0]);
      if (det < 0) {
        const uint32_t x = v[1];
        v[1] = v[2];
        v[2] = x;
      }
      tm_cell(t, MX_TET, v);
    }
}

/* The mesher's own search (kernels/contacts.h) on the meshes of the
 * checker's test: it agrees with the checker where the nodes are surface
 * nodes, looks at nothing else, and leaves a conforming mesh alone. */
/* One root cube around the nodes, as the mesher's grid would be. */
static void grid_around(const double *xyz, size_t nn, mx_grid *G) {
  double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
  for (size_t v = 0; v < nn; v++)
    for (int a = 0; a < 3; a++) {
      lo[a] = fmin(lo[a], xyz[3 * v + (size_t)a]);
      hi[a] = fmax(hi[a], xyz[3 * v + (size_t)a]);
    }
  double side = 0.0;
  for (int a = 0; a < 3; a++) side = fmax(side, hi[a] - lo[a]);
  side = side > 0.0 ? 1.01 * side : 1.0;
  for (int a = 0; a < 3; a++) {
    G->origin[a] = 0.5 * (lo[a] + hi[a]) - 0.5 * side;
    G->dims[a] = 1;
  }
  G->side = side;
  G->unit = ldexp(side, -MX_MAX_LEVEL);
}

static size_t contacts_of(const tm *t, uint8_t state, uint8_t *eflag, mx_contacts *k) {
  uint8_t *st = xrealloc(NULL, t->nn + 1);
  memset(st, state, t->nn);
  mx_mesh M;
  memset(&M, 0, sizeof M);
  M.nnodes = t->nn;
  M.ncells = t->nc;
  M.xyz = t->xyz;
  M.type = t->type;
  M.conn = t->conn;
  mx_grid G;
  grid_around(t->xyz, t->nn, &G);
  CHECK(mx_find_contacts(&M, &G, st, eflag, k) == MX_OK);
  free(st);
  return k->nodes;
}

static void test_contacts(void) {
  mx_contacts k;
  /* the box against the hexahedron cut off its midpoint: 2 nodes on its
   * edges; the elements involved: the hexahedron and the two boxes */
  tm t = {0};
  box_hex(&t, 0, 0, 0, 1, 1, 1);
  box_hex(&t, 1, 0, 0, 2, 1, 1.0 / 3.0);
  box_hex(&t, 1, 0, 1.0 / 3.0, 2, 1, 1);
  uint8_t ef[3];
  CHECK(contacts_of(&t, MX_NODE_OUTSIDE, ef, &k) == 2);
  CHECK(k.elements == 3 && ef[0] == 1 && ef[1] == 1 && ef[2] == 1);
  CHECK(k.first_node < t.nn && k.first[0] == 1.0 && k.first[2] == 1.0 / 3.0);
  /* inside nodes are not looked at (the lattice is conforming there) */
  CHECK(contacts_of(&t, MX_NODE_INSIDE, ef, &k) == 0);
  CHECK(k.elements == 0 && ef[0] == 0 && ef[1] == 0 && ef[2] == 0);
  tm_free(&t);
  /* a node inside the face: the tetrahedra fanned from it */
  const double P[3] = {1, 0.3, 0.6};
  hex_and_cone(&t, P);
  CHECK(contacts_of(&t, MX_NODE_OUTSIDE, NULL, &k) == 1);
  CHECK(k.first[0] == 1 && k.first[1] == 0.3 && k.first[2] == 0.6);
  if (k.elements != 11) fprintf(stderr, "contacts: %zu elements\n", k.elements);
  CHECK(k.elements == 11);
  tm_free(&t);
  /* conforming: the midpoint cut split on both sides */
  box_hex(&t, 0, 0, 0, 1, 1, 0.5);
  box_hex(&t, 0, 0, 0.5, 1, 1, 1);
  box_hex(&t, 1, 0, 0, 2, 1, 0.5);
  box_hex(&t, 1, 0, 0.5, 2, 1, 1);
  CHECK(contacts_of(&t, MX_NODE_OUTSIDE, NULL, &k) == 0 && k.elements == 0);
  CHECK(k.first_node == UINT32_MAX);
  tm_free(&t);
}

static void test_geometric_hanging(void) {
  /* 1. The box next to the hexahedron cut at z = 1/3 (not the midpoint):
   * its two nodes at x = 1, z = 1/3 lie on two edges of hexahedron 0. At
   * unit scale, tiny (1e-110) and huge (coordinates from -1e308 to 1e308,
   * an extent beyond the double range) sizes. */
  const double scales[3] = {1.0, 1e-110, 1e308}, shifts[3] = {0, 0, 1};
  for (int k = 0; k < 3; k++) {
    tm t = {0};
    const double s = scales[k], o = shifts[k];
    hex_s(&t, s, o, 0, 0, 0, 1, 1, 1);
    hex_s(&t, s, o, 1, 0, 0, 2, 1, 1.0 / 3.0);
    hex_s(&t, s, o, 1, 0, 1.0 / 3.0, 2, 1, 1);
    mx_check_report r = check_tm(&t, NULL);
    if (r.geometric_hanging_nodes != 2)
      fprintf(stderr, "scale %g: %zu geometric hanging nodes, %zu defects\n",
              s, r.geometric_hanging_nodes, r.defects);
    CHECK(r.hanging_nodes == 0 && r.geometric_hanging_nodes == 2);
    CHECK(r.defects == 2 && r.invalid == 0 && r.degenerate == 0);
    CHECK(r.elem_ids[MX_CK_GEOM_HANGING].n == 1 &&
          r.elem_ids[MX_CK_GEOM_HANGING].id[0] == 0);
    CHECK(r.node_ids[MX_CK_N_GEOM_HANGING].n == 2);
    CHECK(r.nshown == 2);
    for (size_t i = 0; i < r.nshown && i < 2; i++) {
      const mx_check_hang *h = &r.hang_at[i];
      CHECK(h->on == MX_CK_ON_EDGE && h->element == 0 && h->nverts == 2);
      CHECK(h->node == r.node_ids[MX_CK_N_GEOM_HANGING].id[i]);
      CHECK(memcmp(h->xyz, t.xyz + 3 * h->node, sizeof h->xyz) == 0);
      /* the edge runs along z through the node */
      const double *a = t.xyz + 3 * h->verts[0], *b = t.xyz + 3 * h->verts[1];
      CHECK(a[0] == h->xyz[0] && b[0] == h->xyz[0] && a[1] == h->xyz[1] &&
            b[1] == h->xyz[1] && a[2] != b[2]);
    }
    tm_free(&t);
  }

  /* 2. Four hexahedra against the face, cut at y = 0.3 and z = 0.6: their
   * middle node lies inside the face (x = 1 is face 3 of a hexahedron in
   * soa/mesh.h), the four others on its edges. */
  {
    tm t = {0};
    box_hex(&t, 0, 0, 0, 1, 1, 1);
    const double ys[3] = {0, 0.3, 1}, zs[3] = {0, 0.6, 1};
    for (int j = 0; j < 2; j++)
      for (int i = 0; i < 2; i++)
        box_hex(&t, 1, ys[j], zs[i], 2, ys[j + 1], zs[i + 1]);
    mx_check_report r = check_tm(&t, NULL);
    CHECK(r.hanging_nodes == 0 && r.geometric_hanging_nodes == 5);
    CHECK(r.defects == 5);
    const int f = find_shown(&r, MX_CK_ON_FACE);
    CHECK(f >= 0);
    if (f >= 0) {
      const mx_check_hang *h = &r.hang_at[f];
      CHECK(h->element == 0 && h->local == 3 && h->nverts == 4);
      CHECK(h->xyz[0] == 1 && h->xyz[1] == 0.3 && h->xyz[2] == 0.6);
    }
    tm_free(&t);
  }

  /* 3. Split elements: tetrahedra fanned from a node P inside the face. */
  {
    tm t = {0};
    const double P[3] = {1, 0.3, 0.6};
    hex_and_cone(&t, P);
    mx_check_report r = check_tm(&t, NULL);
    CHECK(r.by_type[MX_TET] == 10 && r.invalid == 0);
    CHECK(near(r.volume, 2.0, 1e-14));
    CHECK(r.geometric_hanging_nodes == 1 && r.defects == 1);
    CHECK(r.open_boundary_edges == 0 && r.faces_overshared == 0);
    CHECK(r.nshown == 1 && r.hang_at[0].on == MX_CK_ON_FACE &&
          r.hang_at[0].element == 0);
    /* the same with P at the face centre: an exact hanging node, counted
     * once */
    tm_free(&t);
    const double C[3] = {1, 0.5, 0.5};
    hex_and_cone(&t, C);
    r = check_tm(&t, NULL);
    CHECK(r.hanging_nodes == 1 && r.geometric_hanging_nodes == 0);
    CHECK(r.defects == 1);
    tm_free(&t);
  }

  /* 4. Tolerance: off the midpoint by 5e-14 of the edge is on the edge;
   * the box moved 1e-6 away from the face is not on it; moved 1e-12 away,
   * its corners lie at (not exactly on) the hexahedron's vertices. */
  {
    tm t = {0};
    const double zc = 0.5 * (1.0 + 1e-13);
    box_hex(&t, 0, 0, 0, 1, 1, 1);
    box_hex(&t, 1, 0, 0, 2, 1, zc);
    box_hex(&t, 1, 0, zc, 2, 1, 1);
    mx_check_report r = check_tm(&t, NULL);
    CHECK(r.hanging_nodes == 0 && r.geometric_hanging_nodes == 2);
    tm_free(&t);
    box_hex(&t, 0, 0, 0, 1, 1, 1);
    box_hex(&t, 1 + 1e-6, 0, 0, 2, 1, 1.0 / 3.0);
    box_hex(&t, 1 + 1e-6, 0, 1.0 / 3.0, 2, 1, 1);
    r = check_tm(&t, NULL);
    CHECK(r.geometric_hanging_nodes == 0 && r.defects == 0);
    tm_free(&t);
    box_hex(&t, 0, 0, 0, 1, 1, 1);
    box_hex(&t, 1 + 1e-12, 0, 0, 2, 1, 1.0 / 3.0);
    box_hex(&t, 1 + 1e-12, 0, 1.0 / 3.0, 2, 1, 1);
    r = check_tm(&t, NULL);
    CHECK(r.geometric_hanging_nodes >= 6 && r.duplicate_nodes == 0);
    CHECK(find_shown(&r, MX_CK_ON_VERTEX) >= 0);
    tm_free(&t);
  }

  /* 5. A conforming graded-looking block (2x2x2 grid) with its nodes moved
   * a little: no false positive. */
  {
    tm t = {0};
    grid_hexes(&t, 3, 1.0 / 3.0, -1);
    for (size_t i = 0; i < 3 * t.nn; i++)
      t.xyz[i] += 0.01 * sin(7.0 * (double)i);
    mx_check_report r = check_tm(&t, NULL);
    CHECK(r.defects == 0 && r.geometric_hanging_nodes == 0);
    tm_free(&t);
  }
}

static void test_degenerate(void) {
  tm t = {0};
  /* A flat tetrahedron: J_ENS about 5e-16 > 0. */
  uint32_t v[8] = {tm_add(&t, 0, 0, 0), tm_add(&t, 1, 0, 0),
                   tm_add(&t, 0, 1, 0), tm_add(&t, 0.25, 0.25, 2e-16)};
  tm_cell(&t, MX_TET, v);
  mx_check_report r = check_tm(&t, NULL);
  if (!(r.jens_min > 0 && r.jens_min < 1e-12))
    fprintf(stderr, "flat tet: J_ENS %g\n", r.jens_min);
  CHECK(r.jens_min > 0 && r.jens_min < 1e-12);
  CHECK(r.degenerate == 1 && r.invalid == 0 && r.defects == 1);
  CHECK(r.elem_ids[MX_CK_DEGENERATE].n == 1 &&
        r.elem_ids[MX_CK_DEGENERATE].id[0] == 0);
  CHECK(r.elem_ids[MX_CK_INVALID].n == 0);
  /* a threshold of 0 accepts it */
  mx_check_options o;
  mx_check_defaults(&o);
  CHECK(o.degenerate_below == 1e-6);
  o.degenerate_below = 0.0;
  mx_mesh_data d = tm_data(&t);
  CHECK(mx_check_mesh_opt(&d, NULL, &o, &r) == MX_OK);
  CHECK(r.degenerate == 0 && r.defects == 0);
  tm_free(&t);

  /* A hexahedron whose node 1 lies on the segment from node 0 to node 2
   * (collinear), and one where it is off that segment by 1e-12: the first
   * invalid (J_ENS 0), the second degenerate or invalid. */
  for (int k = 0; k < 2; k++) {
    box_hex(&t, 0, 0, 0, 1, 1, 1);
    const uint32_t n1 = t.conn[1];
    t.xyz[3 * n1] = 0.5 + (k ? 1e-12 : 0.0);
    t.xyz[3 * n1 + 1] = 0.5 - (k ? 1e-12 : 0.0);
    r = check_tm(&t, NULL);
    CHECK(r.invalid + r.degenerate == 1 && r.defects == 1);
    if (k == 0) CHECK(r.invalid == 1 && r.jens_min == 0.0);
    tm_free(&t);
  }
  /* Nearly flat, but fine: a 1 x 1 x 1e-9 box (J_ENS is scale-free). */
  box_hex(&t, 0, 0, 0, 1, 1, 1e-9);
  r = check_tm(&t, NULL);
  CHECK(r.defects == 0 && r.jens_min == 1.0);
  tm_free(&t);
}

static void test_extreme_coordinates(void) {
  /* A 3^3 grid scaled to 1e-110, 1e-300, 1e300 and across [-1e308,
   * 1e308], plus one duplicate node: the hash of coordinates and the grids
   * work relative to the box (no overflow, no huge allocation). */
  const double scales[4] = {1e-110, 1e-300, 1e300, 1e308 / 1.5};
  const double shifts[4] = {0, 0, 0, 1.5};
  for (int k = 0; k < 4; k++) {
    tm t = {0};
    grid_hexes(&t, 3, 1.0, -1);
    for (size_t i = 0; i < 3 * t.nn; i++)
      t.xyz[i] = scales[k] * (t.xyz[i] - shifts[k]);
    mx_check_report r = check_tm(&t, NULL);
    if (r.defects) fprintf(stderr, "scale %g: %zu defects\n", scales[k], r.defects);
    CHECK(r.defects == 0 && r.elements == 27 && r.jens_min == 1.0);
    CHECK(r.faces_interior == 54 && r.faces_boundary == 54);
    tm_add(&t, t.xyz[3 * 13], t.xyz[3 * 13 + 1], t.xyz[3 * 13 + 2]);
    r = check_tm(&t, NULL);
    CHECK(r.duplicate_nodes == 1 && r.unused_nodes == 1 && r.defects == 2);
    CHECK(r.node_ids[MX_CK_N_DUPLICATE].n == 1 &&
          r.node_ids[MX_CK_N_DUPLICATE].id[0] == t.nn - 1);
    tm_free(&t);
  }
  /* Extents 2 x 1e-150 x 1e-150 (a thin box: cells along x only). */
  tm t = {0};
  box_hex(&t, 0, 0, 0, 1, 1e-150, 1e-150);
  box_hex(&t, 1, 0, 0, 2, 1e-150, 1e-150);
  mx_check_report r = check_tm(&t, NULL);
  CHECK(r.defects == 0 && r.faces_interior == 1);
  tm_free(&t);
  /* Not finite: refused. */
  box_hex(&t, 0, 0, 0, 1, 1, 1);
  t.xyz[4] = NAN;
  mx_mesh_data d = tm_data(&t);
  fprintf(stderr, "(an error about a coordinate that is not finite is "
                  "expected)\n");
  CHECK(mx_check_mesh(&d, NULL, &r) == MX_EINPUT);
  tm_free(&t);
}

static void test_volume(void) {
  const char *off = tpath("cube_v.off");
  write_text(off, cube_off);
  mx_trisoup s;
  CHECK(mx_read_off(off, &s) == MX_OK);
  /* 2 x 2 x 2 hexahedra squeezed to a height of 0.9: 10 % short, and the
   * middle node of the top 0.1 away (the others lie on the cube's sides). */
  tm t = {0};
  grid_hexes(&t, 2, 0.5, -1);
  for (size_t i = 0; i < t.nn; i++) t.xyz[3 * i + 2] *= 0.9;
  mx_check_report r = check_tm_tol(&t, &s, 0.05);
  CHECK(r.has_surface && r.surface_open_edges == 0);
  CHECK(near(r.volume_error, -0.1, 1e-12) && r.volume_off == 1);
  CHECK(r.boundary_off_surface == 1 && r.defects == 2);
  CHECK(near(r.boundary_max_dist, 0.1 / sqrt(3.0), 1e-12));
  CHECK(r.node_ids[MX_CK_N_OFF_SURFACE].n == 1);
  if (r.node_ids[MX_CK_N_OFF_SURFACE].n == 1) {
    const double *q = t.xyz + 3 * r.node_ids[MX_CK_N_OFF_SURFACE].id[0];
    CHECK(q[0] == 0.5 && q[1] == 0.5 && q[2] == 0.9);
  }
  /* looser tolerances accept it */
  mx_check_options o;
  mx_check_defaults(&o);
  CHECK(o.volume_tol == 0.0 && o.boundary_tol == 1e-6); /* 0: chosen from the mesh */
  o.volume_tol = 0.2;
  o.boundary_tol = 0.1;
  mx_mesh_data d = tm_data(&t);
  CHECK(mx_check_mesh_opt(&d, &s, &o, &r) == MX_OK);
  CHECK(r.volume_off == 0 && r.boundary_off_surface == 0 && r.defects == 0);
  CHECK(r.opt.volume_tol == 0.2);
  tm_free(&t);
  /* 1 % short: the volume passes, the distance does not. */
  grid_hexes(&t, 2, 0.5, -1);
  for (size_t i = 0; i < t.nn; i++) t.xyz[3 * i + 2] *= 0.99;
  r = check_tm_tol(&t, &s, 0.05);
  CHECK(r.volume_off == 0 && r.boundary_off_surface == 1 && r.defects == 1);
  tm_free(&t);
  /* 10 % too big, the other way. */
  box_hex(&t, 0, 0, 0, 1, 1, 1.1);
  r = check_tm_tol(&t, &s, 0.05);
  CHECK(r.volume_off == 1 && near(r.volume_error, 0.1, 1e-12));
  /* the default tolerance, half a layer of this one element: 0.5 x 6 x 1.1^(1/3) */
  r = check_tm(&t, &s);
  CHECK(r.opt.volume_tol_auto && near(r.opt.volume_tol, 3.0 * cbrt(1.1), 1e-9) && r.volume_off == 0);
  tm_free(&t);
  /* An open surface (one triangle less): reported, not a defect. */
  s.nt--;
  grid_hexes(&t, 2, 0.5, -1);
  for (size_t i = 0; i < t.nn; i++) t.xyz[3 * i + 2] *= 0.9;
  r = check_tm(&t, &s);
  CHECK(r.surface_open_edges == 3 && r.volume_off == 0 &&
        r.boundary_off_surface == 0 && r.defects == 0);
  CHECK(r.node_ids[MX_CK_N_OFF_SURFACE].n == 0);
  tm_free(&t);
  mx_trisoup_free(&s);
  /* An empty mesh with a surface: empty, and the volume is off. */
  CHECK(mx_read_off(off, &s) == MX_OK);
  r = check_tm(&t, &s);
  CHECK(r.empty == 1 && r.volume_off == 1 && r.defects == 2);
  mx_trisoup_free(&s);
}

/* Reads p with the messages captured; returns the status, *msg (free it). */
static int read_quietly(const char *p, mx_mesh_data *m, char **msg) {
  int st;
  *msg = captured(mx_read_mesh, p, m, &st);
  return st;
}

/* A file made of a text head and n raw bytes. */
static void write_head_bytes(const char *p, const char *head,
                             const void *bytes, size_t n) {
  size_t hl = strlen(head);
  char *b = malloc(hl + n + 1);
  memcpy(b, head, hl);
  if (n) memcpy(b + hl, bytes, n);
  write_bytes(p, b, hl + n);
  free(b);
}

static void test_huge_counts(void) {
  /* Counts far beyond what the file holds are refused before anything is
   * allocated, quickly, naming the count. */
  static const struct {
    const char *name, *text, *want;
  } cases[] = {
      {"cells.vtk",
       "# vtk DataFile Version 3.0\nx\nASCII\nDATASET UNSTRUCTURED_GRID\n"
       "POINTS 4 double\n0 0 0 1 0 0 0 1 0 0 0 1\nCELLS 1000000000 5\n"
       "4 0 1 2 3\nCELL_TYPES 1\n10\n",
       "CELLS"},
      {"cells_bin.vtk",
       "# vtk DataFile Version 3.0\nx\nBINARY\nDATASET UNSTRUCTURED_GRID\n"
       "CELLS 2000000000 5\n\0\0\0\4\0\0\0\0\0\0\0\1\0\0\0\2\0\0\0\3\n",
       "CELLS"},
      {"points.vtk",
       "# vtk DataFile Version 3.0\nx\nASCII\nDATASET UNSTRUCTURED_GRID\n"
       "POINTS 3000000000 double\n0 0 0\n",
       "POINTS"},
      {"points.vtu",
       "<VTKFile type=\"UnstructuredGrid\"><UnstructuredGrid><Piece "
       "NumberOfPoints=\"1000000000\" NumberOfCells=\"1000000000\">"
       "<Points><DataArray type=\"Float64\" NumberOfComponents=\"3\" "
       "format=\"ascii\">0 0 0</DataArray></Points></Piece>"
       "</UnstructuredGrid></VTKFile>\n",
       "Points"},
      {"nodes.msh",
       "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 2000000000 1 "
       "2000000000\n3 1 0 2000000000\n1\n0 0 0\n$EndNodes\n",
       "$Nodes"},
      {"elements.msh",
       "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 1 1 1\n3 1 0 1\n1\n"
       "0 0 0\n$EndNodes\n$Elements\n1 1000000000 1 1000000000\n"
       "3 1 4 1000000000\n1 1 1 1 1\n$EndElements\n",
       "$Elements"},
      {"vertices.mesh",
       "MeshVersionFormatted 2\nDimension 3\nVertices\n2000000000\n0 0 0 0\n"
       "End\n",
       "Vertices"},
      {"tets.mesh",
       "MeshVersionFormatted 2\nDimension 3\nVertices\n1\n0 0 0 0\n"
       "Tetrahedra\n1500000000\n1 1 1 1 0\nEnd\n",
       "Tetrahedra"},
  };
  const size_t lens[] = {0, 165, 0, 0, 0, 0, 0, 0};
  for (size_t k = 0; k < sizeof cases / sizeof cases[0]; k++) {
    const char *p = tpath(cases[k].name);
    if (lens[k])
      write_bytes(p, cases[k].text, lens[k]);
    else
      write_text(p, cases[k].text);
    mx_mesh_data m;
    char *msg;
    const double t0 = mx_wtime();
    const int st = read_quietly(p, &m, &msg);
    const double dt = mx_wtime() - t0;
    CHECK(st == MX_EINPUT && msg && strstr(msg, cases[k].want));
    CHECK(!(msg && strstr(msg, "memory"))); /* refused, not run out of memory */
    CHECK(dt < 1.0);
    if (st != MX_EINPUT || !msg || !strstr(msg, cases[k].want))
      fprintf(stderr, "%s: status %d, %s\n", cases[k].name, st,
              msg ? msg : "(no message)");
    CHECK(m.nnodes == 0 && m.ncells == 0 && !m.xyz && !m.conn);
    free(msg);
  }
  /* Binary MSH and Medit with huge counts. */
  {
    uint64_t head[4] = {1, 3000000000ull, 1, 3000000000ull};
    const char *p = tpath("nodes_bin.msh");
    char b[256];
    size_t n = 0;
    const char *h1 = "$MeshFormat\n4.1 1 8\n";
    memcpy(b, h1, strlen(h1));
    n += strlen(h1);
    const int32_t one = 1;
    memcpy(b + n, &one, 4);
    n += 4;
    const char *h2 = "\n$EndMeshFormat\n$Nodes\n";
    memcpy(b + n, h2, strlen(h2));
    n += strlen(h2);
    memcpy(b + n, head, sizeof head);
    n += sizeof head;
    memset(b + n, 0, 40);
    n += 40;
    write_bytes(p, b, n);
    mx_mesh_data m;
    char *msg;
    CHECK(read_quietly(p, &m, &msg) == MX_EINPUT && !(msg && strstr(msg, "memory")));
    CHECK(msg && strstr(msg, "$Nodes"));
    free(msg);
  }
  {
    int32_t w[12] = {1, 2, 3, 20, 3, 4, 0, 2000000000, 0, 0, 0, 0};
    const char *p = tpath("vertices.meshb");
    write_head_bytes(p, "", w, sizeof w);
    mx_mesh_data m;
    char *msg;
    CHECK(read_quietly(p, &m, &msg) == MX_EINPUT && !(msg && strstr(msg, "memory")));
    CHECK(msg && strstr(msg, "2000000000 lines"));
    free(msg);
  }
}

/* t's cells grouped by type, tetrahedra first (Medit's blocks). */
static void group_by_type(const tm *t, tm *g) {
  memset(g, 0, sizeof *g);
  for (size_t i = 0; i < t->nn; i++)
    tm_add(g, t->xyz[3 * i], t->xyz[3 * i + 1], t->xyz[3 * i + 2]);
  for (int ty = 0; ty < 4; ty++)
    for (size_t c = 0; c < t->nc; c++)
      if (t->type[c] == ty) tm_cell(g, ty, t->conn + 8 * c);
}

/* The mixed valid mesh of test_valid, with awkward coordinates of its own
 * (bit-exact round trips) but still valid. */
static void mixed_mesh(tm *t) {
  memset(t, 0, sizeof *t);
  box_hex(t, 0, 0, 0, 1, 1, 1);
  box_prisms(t, (const double[3]){1, 0, 0}, (const double[3]){2, 1, 1});
  box_pyramids(t, (const double[3]){2, 0, 0}, (const double[3]){3, 1, 1});
  box_tets(t, (const double[3]){5, 0, 0}, (const double[3]){6, 1, 1});
  for (size_t i = 0; i < 3 * t->nn; i++) t->xyz[i] = t->xyz[i] / 3.0 + 0.1;
}

static void test_msh_medit(void) {
  tm t, g, aw, awg;
  mixed_mesh(&t);
  group_by_type(&t, &g);
  awkward_mesh(&aw);
  group_by_type(&aw, &awg);
  for (int k = 0; k < 4; k++) {
    const char *p = tpath(k == 0   ? "m_bin.msh"
                          : k == 1 ? "m_ascii.msh"
                          : k == 2 ? "m.meshb"
                                   : "m.mesh");
    for (int which = 0; which < 2; which++) {
      const tm *src = which ? &aw : &t, *want = which ? &awg : &g;
      if (k < 2) want = src; /* MSH keeps the order through the tags */
      mx_mesh_data d = tm_data(src);
      mx_mesh_view v = mx_mesh_data_view(&d);
      const int st = k < 2 ? mx_write_msh(p, &v, k == 0)
                           : mx_write_medit(p, &v, k == 2);
      CHECK(st == MX_OK);
      mx_mesh_data m;
      const int rs = mx_read_mesh(p, &m);
      CHECK(rs == MX_OK);
      if (rs != MX_OK) continue;
      if (!same_mesh(want, &m)) fprintf(stderr, "round trip %s %d\n", p, which);
      CHECK(same_mesh(want, &m));
      if (!which) { /* the valid one checks OK, with the same volume */
        mx_check_report r;
        CHECK(mx_check_mesh(&m, NULL, &r) == MX_OK);
        CHECK(r.defects == 0 && near(r.volume, 4.0 / 27.0, 1e-14));
      }
      mx_mesh_data_free(&m);
    }
  }
  /* A mesh written by mixoct's writers with a defect keeps it. */
  {
    tm h = {0};
    box_hex(&h, 0, 0, 0, 1, 1, 1);
    box_hex(&h, 1, 0, 0, 2, 1, 1.0 / 3.0);
    box_hex(&h, 1, 0, 1.0 / 3.0, 2, 1, 1);
    mx_mesh_data d = tm_data(&h);
    mx_mesh_view v = mx_mesh_data_view(&d);
    const char *p = tpath("hang.meshb");
    CHECK(mx_write_medit(p, &v, 1) == MX_OK);
    mx_mesh_data m;
    CHECK(mx_read_mesh(p, &m) == MX_OK);
    mx_check_report r;
    CHECK(mx_check_mesh(&m, NULL, &r) == MX_OK);
    CHECK(r.geometric_hanging_nodes == 2 && r.defects == 2);
    mx_mesh_data_free(&m);
    tm_free(&h);
  }
  /* Hand-written files: Gmsh's own style (boundary triangles, a point, a
   * node block on a surface, sparse tags, elements out of tag order) and
   * Medit with comments and other keywords. */
  {
    const char *msh =
        "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n"
        "$Entities\n1 0 0 1\n1 0 0 0 0\n1 0 0 0 1 1 1 0 0\n$EndEntities\n"
        "$Nodes\n2 4 10 40\n"
        "0 1 0 1\n10\n0 0 0\n"
        "2 1 1 3\n20\n30\n40\n1 0 0 0.5 0.5\n0 1 0 0.5 0.5\n0 0 1 0.5 0.5\n"
        "$EndNodes\n"
        "$Elements\n3 3 1 9\n"
        "0 1 15 1\n1 10\n"
        "2 1 2 1\n5 10 30 20\n"
        "3 1 4 1\n9 10 20 30 40\n"
        "$EndElements\n$NodeData\n1\n\"x\"\n$EndNodeData\n";
    const char *p = tpath("gmsh.msh");
    write_text(p, msh);
    mx_mesh_data m;
    CHECK(mx_read_mesh(p, &m) == MX_OK);
    CHECK(m.nnodes == 4 && m.ncells == 1 && m.type && m.type[0] == MX_TET);
    if (m.ncells == 1)
      CHECK(m.conn[0] == 0 && m.conn[1] == 1 && m.conn[2] == 2 &&
            m.conn[3] == 3);
    /* the triangle is a tagged face; no surface in $Entities: its tag is
     * its entity's */
    CHECK(m.nfaces == 1 && m.face_nn[0] == 3 && m.face_tag[0] == 1);
    if (m.nfaces == 1)
      CHECK(m.face_conn[0] == 0 && m.face_conn[1] == 2 &&
            m.face_conn[2] == 1 && m.face_conn[3] == 0);
    mx_mesh_data_free(&m);
    const char *med =
        "# a comment\nMeshVersionFormatted 2\n\nDimension\n3\n"
        "Vertices\n4\n0 0 0 1\n1 0 0 1\n0 1 0 1\n0 0 1 1 # the apex\n"
        "Corners\n1\n1\nTriangles\n1\n1 3 2 7\n"
        "Tetrahedra\n1\n1 2 3 4 0\nNormals\n1\n0 0 1\nEnd\n";
    p = tpath("hand.mesh");
    write_text(p, med);
    CHECK(mx_read_mesh(p, &m) == MX_OK);
    CHECK(m.nnodes == 4 && m.ncells == 1 && m.type && m.type[0] == MX_TET);
    CHECK(m.nfaces == 1 && m.face_tag && m.face_tag[0] == 7);
    if (m.ncells == 1) { /* one boundary face of four is tagged */
      mx_check_report r;
      CHECK(mx_check_mesh(&m, NULL, &r) == MX_OK);
      CHECK(r.has_tagged_faces && r.tagged_faces == 1);
      CHECK(r.tagged_not_boundary == 0 && r.boundary_untagged == 3);
      CHECK(r.defects == 3 && r.untagged_ids.n == 1 &&
            r.untagged_ids.id[0] == 0);
    }
    mx_mesh_data_free(&m);
  }
  /* Errors name the file and the place. */
  expect_error("v3.msh", "$MeshFormat\n3.0 0 8\n$EndMeshFormat\n",
               ":2: error: MSH version '3.0' is not supported");
  expect_error("o2.msh",
               "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 1 1 1\n"
               "3 1 0 1\n1\n0 0 0\n$EndNodes\n$Elements\n1 1 1 1\n"
               "3 1 11 1\n1 1 1 1 1 1 1 1 1 1 1\n$EndElements\n",
               ":12: error: $Elements block 0: element type 11");
  expect_error("inf.mesh",
               "MeshVersionFormatted 2\nDimension 3\nVertices\n1\n0 inf 0 0\n"
               "End\n",
               ":5: error: vertex: 'inf' is not a finite number");
  expect_error("range.mesh",
               "MeshVersionFormatted 2\nDimension 3\nVertices\n1\n0 0 0 0\n"
               "Tetrahedra\n1\n1 2 1 1 0\nEnd\n",
               ": error: element 0: vertex 2 out of range");
  expect_error("noend.mesh",
               "MeshVersionFormatted 2\nDimension 3\nVertices\n1\n0 0 0 0\n",
               ": error: no End");
  tm_free(&t);
  tm_free(&g);
  tm_free(&aw);
  tm_free(&awg);
}

/* ====================================================================== */
/* Determinism, the program, speed                                        */
/* ====================================================================== */

static void test_threads(void) {
  tm t = {0};
  grid_hexes(&t, 24, 1.0 / 24, 100);
  box_hex(&t, 1, 0, 0, 2, 1, 0.5); /* a few defects too */
  box_hex(&t, 1, 0, 0.5, 2, 1, 1);
  tm_copy_cell(&t, 50);
  mx_trisoup s;
  fine_box(&s, (const double[3]){0.01, 0, 0}, 1.0, 5);
  const int maxt = omp_get_max_threads();
  mx_check_report r[3];
  for (int k = 0; k < 3; k++) {
    omp_set_num_threads(k == 0 ? 1 : k == 1 ? 2 : 7);
    r[k] = check_tm(&t, &s);
  }
  omp_set_num_threads(maxt);
  CHECK(memcmp(&r[0], &r[1], sizeof r[0]) == 0);
  CHECK(memcmp(&r[0], &r[2], sizeof r[0]) == 0);
  /* cell 50 lies on the z = 0 side: its five other faces are shared */
  CHECK(r[0].hanging_nodes > 0 && r[0].faces_overshared == 5);
  mx_trisoup_free(&s);
  tm_free(&t);
}

/* Runs a shell command; returns its exit code. */
static int run(const char *cmd) {
  int st = system(cmd);
  return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}

static void test_program(void) {
  if (access(mixoct, X_OK) != 0) {
    fprintf(stderr, "%s not found: program tests skipped\n", mixoct);
    CHECK(0);
    return;
  }
  tm t = {0};
  box_hex(&t, 0, 0, 0, 1, 1, 1);
  mx_mesh_data d = tm_data(&t);
  mx_mesh_view v = mx_mesh_data_view(&d);
  const char *good = tpath("good.vtu");
  CHECK(mx_write_vtu(good, &v) == MX_OK);
  const char *off = tpath("cube.off");
  write_text(off, cube_off);
  box_hex(&t, 0, 0, 1, 1, 1, 2);
  tm_copy_cell(&t, 0);
  d = tm_data(&t);
  v = mx_mesh_data_view(&d);
  const char *bad = tpath("bad.vtk");
  CHECK(mx_write_vtk_legacy(bad, &v, 1) == MX_OK);
  tm_free(&t);
  char cmd[8192];
  const char *out = tpath("out.txt");
  snprintf(cmd, sizeof cmd, "'%s' check '%s' > '%s' 2>&1", mixoct, good, out);
  CHECK(run(cmd) == 0);
  size_t n;
  char *txt = slurp(out, &n);
  CHECK(txt && strstr(txt, "OK, no defect"));
  free(txt);
  snprintf(cmd, sizeof cmd, "'%s' check '%s' --quiet > '%s' 2>&1", mixoct,
           bad, out);
  CHECK(run(cmd) == 5);
  txt = slurp(out, &n);
  CHECK(txt && n == 0);
  free(txt);
  snprintf(cmd, sizeof cmd, "'%s' check '%s' > /dev/null 2>&1", mixoct,
           tpath("nope.vtu"));
  CHECK(run(cmd) == 2);
  snprintf(cmd, sizeof cmd, "'%s' check > /dev/null 2>&1", mixoct);
  CHECK(run(cmd) == 2);
  snprintf(cmd, sizeof cmd, "'%s' check '%s' --bogus > /dev/null 2>&1",
           mixoct, good);
  CHECK(run(cmd) == 2);
  snprintf(cmd, sizeof cmd, "'%s' check '%s' --surface '%s' > /dev/null 2>&1",
           mixoct, good, tpath("nope.off"));
  CHECK(run(cmd) == 2);
  snprintf(cmd, sizeof cmd, "'%s' check --help > /dev/null", mixoct);
  CHECK(run(cmd) == 0);
  /* The message names the file. */
  snprintf(cmd, sizeof cmd, "'%s' check '%s' 2>&1 | grep -q 'nope.vtu'",
           mixoct, tpath("nope.vtu"));
  CHECK(run(cmd) == 0);
  if (run("python3 -c pass") != 0) {
    fprintf(stderr, "python3 not found: JSON not parsed\n");
    return;
  }
  snprintf(cmd, sizeof cmd,
           "'%s' check '%s' --json | tail -n 1 | python3 -c \"import json, "
           "sys; d = json.loads(sys.stdin.read()); "
           "assert d['defects'] == 0 and d['by_type']['hex'] == 1; "
           "assert d['volume'] == 1 and d['boundary_max_dist'] is None; "
           "assert d['surface_volume'] is None and d['faces_boundary'] == 6\"",
           mixoct, good);
  CHECK(run(cmd) == 0);
  snprintf(cmd, sizeof cmd,
           "'%s' check '%s' --surface '%s' --json | tail -n 1 | python3 -c "
           "\"import json, sys; d = json.loads(sys.stdin.read()); "
           "assert d['volume_error'] == 0 and d['boundary_max_dist'] == 0; "
           "assert d['surface_volume'] == 1\"",
           mixoct, good, off);
  CHECK(run(cmd) == 0);
  snprintf(cmd, sizeof cmd,
           "'%s' check '%s' --json | tail -n 1 | python3 -c \"import json, "
           "sys; d = json.loads(sys.stdin.read()); "
           "assert d['defects'] == 10 and d['faces_overshared'] == 1; "
           "assert set(d) == set('nodes elements by_type mesh_hash empty invalid "
           "degenerate jens_min jens_mean faces_interior faces_boundary "
           "faces_overshared faces_misoriented quad_vs_triangles "
           "open_boundary_edges nonmanifold_edges hanging_nodes "
           "geometric_hanging_nodes unused_nodes duplicate_nodes volume "
           "surface_volume volume_error boundary_max_dist "
           "hausdorff_mesh_to_surface_max hausdorff_mesh_to_surface_mean "
           "hausdorff_surface_to_mesh_max hausdorff_surface_to_mesh_mean "
           "hausdorff_mesh_to_surface_max_abs hausdorff_mesh_to_surface_mean_abs "
           "hausdorff_surface_to_mesh_max_abs hausdorff_surface_to_mesh_mean_abs "
           "surface_open_edges "
           "volume_off boundary_off_surface tolerances defective_elements "
           "defective_nodes geometric_hanging_at tagged_not_boundary "
           "boundary_untagged boundary_flags_off tagged_faces boundary_tags boundary_node_tags "
           "features defective_faces defects'.split()); "
           "assert d['boundary_tags'] == [] and d['tagged_faces'] == 0; "
           "assert d['features'] is None; "
           "e = d['defective_elements']; "
           "assert e['faces_overshared'] == [0, 1, 2], e; "
           "assert e['faces_misoriented'] == [0, 2], e; "
           "assert e['open_boundary_edges'] == [1], e\"",
           mixoct, bad);
  CHECK(run(cmd) == 0);
  /* tpath's buffers are reused: keep copies from here on */
  char offp[256], outp[256], emp[256], hang[256], shortm[256];
  snprintf(offp, sizeof offp, "%s", tpath("cube.off"));
  snprintf(outp, sizeof outp, "%s", tpath("out.txt"));
  snprintf(emp, sizeof emp, "%s", tpath("empty.vtu"));
  snprintf(hang, sizeof hang, "%s", tpath("hang.msh"));
  snprintf(shortm, sizeof shortm, "%s", tpath("short.mesh"));
  off = offp;
  out = outp;
  /* Strict JSON (no NaN or Infinity) for an empty mesh: a defect, nulls. */
  mx_mesh_data empty = {.nnodes = 0};
  mx_mesh_view ev = mx_mesh_data_view(&empty);
  CHECK(mx_write_vtu(emp, &ev) == MX_OK);
  static const char strict[] =
      "python3 -c \"import json, sys; "
      "bad = lambda c: (_ for _ in ()).throw(ValueError(c)); "
      "d = json.loads(sys.stdin.read().splitlines()[-1], "
      "parse_constant=bad); ";
  snprintf(cmd, sizeof cmd,
           "'%s' check '%s' --surface '%s' --json > '%s'; test $? = 5 && "
           "%s assert d['empty'] == 1 and d['volume_off'] == 1; "
           "assert d['jens_min'] is None and d['volume'] == 0; "
           "assert d['defects'] == 2\" < '%s'",
           mixoct, emp, off, out, strict, out);
  CHECK(run(cmd) == 0);
  /* A geometric hanging node: ids and where it lies; the text names it. */
  box_hex(&t, 0, 0, 0, 1, 1, 1);
  box_hex(&t, 1, 0, 0, 2, 1, 1.0 / 3.0);
  box_hex(&t, 1, 0, 1.0 / 3.0, 2, 1, 1);
  d = tm_data(&t);
  v = mx_mesh_data_view(&d);
  CHECK(mx_write_msh(hang, &v, 0) == MX_OK);
  tm_free(&t);
  snprintf(cmd, sizeof cmd,
           "'%s' check '%s' --json > '%s'; test $? = 5 && "
           "%s assert d['geometric_hanging_nodes'] == 2, d; "
           "assert d['defective_elements']['geometric_hanging_nodes'] == [0]; "
           "h = d['geometric_hanging_at']; "
           "assert len(h) == 2 and h[0]['on'] == 'edge', h; "
           "assert h[0]['element'] == 0 and len(h[0]['nodes_of']) == 2, h; "
           "assert abs(h[0]['xyz'][2] - 1 / 3) < 1e-15, h\" < '%s'",
           mixoct, hang, out, strict, out);
  CHECK(run(cmd) == 0);
  snprintf(cmd, sizeof cmd, "'%s' check '%s' > '%s' 2>&1", mixoct, hang,
           out);
  CHECK(run(cmd) == 5);
  txt = slurp(out, &n);
  CHECK(txt && strstr(txt, "geometric hanging nodes  2   <-- defect") &&
        strstr(txt, " on the edge ") && strstr(txt, "2 defects"));
  free(txt);
  /* --volume-tol: a mesh 10 %% short of the cube. */
  grid_hexes(&t, 2, 0.5, -1);
  for (size_t i = 0; i < t.nn; i++) t.xyz[3 * i + 2] *= 0.9;
  d = tm_data(&t);
  v = mx_mesh_data_view(&d);
  CHECK(mx_write_medit(shortm, &v, 0) == MX_OK);
  tm_free(&t);
  snprintf(cmd, sizeof cmd, "'%s' check '%s' --surface '%s' --volume-tol 0.05 > '%s' 2>&1",
           mixoct, shortm, off, out);
  CHECK(run(cmd) == 5);
  txt = slurp(out, &n);
  if (!txt || !strstr(txt, "volume off               1   <-- defect   "
                           "(|volume error| > 0.05)"))
    fprintf(stderr, "check of %s: %s\n", shortm, txt ? txt : "(nothing)");
  CHECK(txt && strstr(txt, "volume off               1   <-- defect   "
                           "(|volume error| > 0.05)"));
  free(txt);
  snprintf(cmd, sizeof cmd,
           "'%s' check '%s' --surface '%s' --volume-tol 0.2 --dist-tol 0.1 "
           "> '%s' 2>&1",
           mixoct, shortm, off, out);
  CHECK(run(cmd) == 0);
  txt = slurp(out, &n);
  CHECK(txt && strstr(txt, "OK, no defect") &&
        strstr(txt, "(|volume error| > 0.2)"));
  free(txt);
  snprintf(cmd, sizeof cmd, "'%s' check '%s' --volume-tol x > /dev/null 2>&1",
           mixoct, shortm);
  CHECK(run(cmd) == 2);
}

/* ====================================================================== */
/* Boundary tags (issue 11): the readers' tagged faces and node tags, the */
/* checker's tag counts and defects, `mixoct check` on mixoct's files     */
/* ====================================================================== */

/* Two unit cubes side by side (x from 0 to 2) as hexahedra, with Medit
 * Quadrilaterals for all their boundary faces but the one at x = 2, and for
 * the face they share at x = 1 (the 10th, index 9): a tagged face that is
 * interior and an untagged boundary face (of element 1). Tag 1 on the first
 * cube's faces, 2 on the second's. */
static const char bad_tags_mesh[] =
    "MeshVersionFormatted 2\nDimension 3\nVertices\n12\n"
    "0 0 0 0\n1 0 0 0\n2 0 0 0\n0 1 0 0\n1 1 0 0\n2 1 0 0\n"
    "0 0 1 0\n1 0 1 0\n2 0 1 0\n0 1 1 0\n1 1 1 0\n2 1 1 0\n"
    "Hexahedra\n2\n1 2 5 4 7 8 11 10 1\n2 3 6 5 8 9 12 11 1\n"
    "Quadrilaterals\n10\n"
    "1 4 10 7 1\n1 2 8 7 1\n4 5 11 10 1\n1 2 5 4 1\n7 8 11 10 1\n"
    "2 3 9 8 2\n5 6 12 11 2\n2 3 6 5 2\n8 9 12 11 2\n2 5 11 8 2\n"
    "End\n";

/* A tetrahedron in MSH 4.1 with three of its faces on surface entity 5
 * (physical tag 7, a name with quotes, a backslash, an e-acute and a byte
 * that is not UTF-8) and one on entity 6 (no physical tag: tag 6). */
static const char tagged_msh[] =
    "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n"
    "$PhysicalNames\n3\n2 7 \"outer \"q\" \\ \xc3\xa9\xff\"\n2 8 \"unused\"\n"
    "3 1 \"volume 1\"\n$EndPhysicalNames\n"
    "$Entities\n0 0 2 1\n5 0 0 0 1 1 1 1 7 0\n6 0 0 0 1 1 1 0 0\n"
    "1 0 0 0 1 1 1 1 1 2 5 -6\n$EndEntities\n"
    "$Nodes\n1 4 1 4\n3 1 0 4\n1\n2\n3\n4\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n"
    "$EndNodes\n"
    "$Elements\n3 5 1 5\n3 1 4 1\n1 1 2 3 4\n"
    "2 5 2 3\n2 1 3 2\n3 1 2 4\n4 2 3 4\n2 6 2 1\n5 1 4 3\n$EndElements\n";

/* Legacy VTK: attributes to step over, then the point field surface_tag. */
static const char tagged_vtk[] =
    "# vtk DataFile Version 3.0\nt\nASCII\nDATASET UNSTRUCTURED_GRID\n"
    "POINTS 4 double\n0 0 0 1 0 0 0 1 0 0 0 1\nCELLS 1 5\n4 0 1 2 3\n"
    "CELL_TYPES 1\n10\nCELL_DATA 1\nSCALARS body int 1\n"
    "LOOKUP_TABLE default\n1\nVECTORS v float\n1 2 3\nPOINT_DATA 4\n"
    "FIELD FieldData 1\nx 2 4 float\n0 0 0 0 0 0 0 0\n"
    "SCALARS surface_tag int\nLOOKUP_TABLE default\n3 0 3 -2\n";

/* A GetFEM tetrahedron followed by `regions`. */
static char *getfem_tet(const char *regions) {
  static char buf[1024];
  snprintf(buf, sizeof buf,
           "BEGIN POINTS LIST\nPOINT 0 0 0 0\nPOINT 1 1 0 0\nPOINT 2 0 1 0\n"
           "POINT 3 0 0 1\nEND POINTS LIST\nBEGIN MESH STRUCTURE DESCRIPTION\n"
           "CONVEX 0 'GT_PK(3,1)' 0 1 2 3\nEND MESH STRUCTURE DESCRIPTION\n%s",
           regions);
  return buf;
}

/* The checked tags of a mesh file (MX_OK or the reader's status). */
static int check_file_tags(const char *p, mx_check_report *r,
                           mx_check_tags *t) {
  mx_mesh_data m;
  memset(t, 0, sizeof *t);
  int st = mx_read_mesh(p, &m);
  if (st == MX_OK) st = mx_check_mesh_tags(&m, NULL, NULL, r, t);
  mx_mesh_data_free(&m);
  return st;
}

static void test_tag_readers(void) {
  /* MSH: faces of dimension 2 with their entities' physical tags, names. */
  const char *p = tpath("tagged.msh");
  write_text(p, tagged_msh);
  mx_mesh_data m;
  CHECK(mx_read_mesh(p, &m) == MX_OK);
  CHECK(m.ncells == 1 && m.nfaces == 4);
  if (m.nfaces == 4) {
    static const uint32_t want[4][3] = {{0, 2, 1}, {0, 1, 3}, {1, 2, 3}, {0, 3, 2}};
    for (int f = 0; f < 4; f++) {
      CHECK(m.face_nn[f] == 3 && m.face_tag[f] == (f < 3 ? 7 : 6));
      CHECK(m.face_conn[4 * f + 3] == 0);
      for (int j = 0; j < 3; j++) CHECK(m.face_conn[4 * f + j] == want[f][j]);
    }
  }
  CHECK(m.nnames == 2 && m.name_tag && m.name_tag[0] == 7 && m.name_tag[1] == 8);
  if (m.nnames == 2) {
    CHECK(strcmp(m.name[0], "outer \"q\" \\ \xc3\xa9\xff") == 0);
    CHECK(strcmp(m.name[1], "unused") == 0);
  }
  mx_check_report r;
  mx_check_tags t;
  CHECK(mx_check_mesh_tags(&m, NULL, NULL, &r, &t) == MX_OK);
  CHECK(r.defects == 0 && r.tagged_faces == 4 && r.faces_boundary == 4);
  CHECK(t.nface_tags == 2 && t.nnode_tags == 0);
  if (t.nface_tags == 2) {
    const mx_check_tag *a = &t.face_tags[0], *b = &t.face_tags[1];
    CHECK(a->tag == 6 && a->name == NULL && a->triangles == 1 && a->quads == 0);
    CHECK(a->open_edges == 3 && a->not_boundary == 0);
    CHECK(b->tag == 7 && b->name && strcmp(b->name, m.name[0]) == 0);
    CHECK(b->triangles == 3 && b->open_edges == 3);
  }
  mx_check_tags_free(&t);
  mx_mesh_data_free(&m);
  /* The same mesh without $Entities: the entity tags are the tags. */
  {
    char *txt = strdup(tagged_msh);
    char *a = strstr(txt, "$Entities"), *b = strstr(txt, "$Nodes");
    memmove(a, b, strlen(b) + 1);
    p = tpath("noent.msh");
    write_text(p, txt);
    free(txt);
    CHECK(mx_read_mesh(p, &m) == MX_OK);
    CHECK(m.nfaces == 4 && m.face_tag[0] == 5 && m.face_tag[3] == 6);
    mx_mesh_data_free(&m);
  }
  /* Medit: an interior tagged face and an untagged boundary face. */
  p = tpath("badtags.mesh");
  write_text(p, bad_tags_mesh);
  CHECK(check_file_tags(p, &r, &t) == MX_OK);
  CHECK(r.faces_boundary == 10 && r.tagged_faces == 10);
  CHECK(r.tagged_not_boundary == 1 && r.boundary_untagged == 1);
  CHECK(r.defects == 2);
  CHECK(r.not_boundary_ids.n == 1 && r.not_boundary_ids.id[0] == 9);
  CHECK(r.untagged_ids.n == 1 && r.untagged_ids.id[0] == 1);
  CHECK(t.nface_tags == 2);
  if (t.nface_tags == 2) {
    CHECK(t.face_tags[0].tag == 1 && t.face_tags[0].quads == 5);
    CHECK(t.face_tags[0].open_edges == 4 && t.face_tags[0].not_boundary == 0);
    CHECK(t.face_tags[1].tag == 2 && t.face_tags[1].quads == 5);
    CHECK(t.face_tags[1].open_edges == 4 && t.face_tags[1].not_boundary == 1);
  }
  mx_check_tags_free(&t);
  /* GetFEM regions: "cv/f" is a face in GetFEM's numbering, "cv" a whole
   * convex (skipped); faces of a hexahedron where the writer's table puts
   * them (GetFEM face 2k: coordinate k = 1, 2k + 1: coordinate k = 0). */
  {
    tm h = {0};
    box_hex(&h, 0, 0, 0, 1, 1, 1);
    mx_mesh_data d = tm_data(&h);
    mx_mesh_view v = mx_mesh_data_view(&d);
    p = tpath("regions.getfem");
    CHECK(mx_write_getfem(p, &v) == MX_OK);
    FILE *f = fopen(p, "a");
    fputs("BEGIN REGION 3\n 0/0 0/1 0 0/2\n0/3\nEND REGION 3\n"
          "BEGIN BOUNDARY 5\n0/4 0/5\nEND BOUNDARY 5\n",
          f);
    fclose(f);
    CHECK(mx_read_mesh(p, &m) == MX_OK);
    CHECK(m.nfaces == 6);
    for (size_t k = 0; k < m.nfaces && m.nfaces == 6; k++) {
      CHECK(m.face_nn[k] == 4 && m.face_tag[k] == (k < 4 ? 3 : 5));
      const int axis = (int)k / 2;
      const double at = k % 2 ? 0.0 : 1.0;
      for (int j = 0; j < 4; j++)
        CHECK(m.xyz[3 * m.face_conn[4 * k + j] + axis] == at);
    }
    mx_mesh_data_free(&m);
    tm_free(&h);
  }
  p = tpath("tet.getfem");
  write_text(p, getfem_tet("BEGIN REGION 0\n0/0 0/1 0/2 0/3\nEND REGION 0\n"
                           "% what follows the regions is ignored\n"));
  CHECK(check_file_tags(p, &r, &t) == MX_OK);
  CHECK(r.defects == 0 && r.tagged_faces == 4 && t.nface_tags == 1);
  if (t.nface_tags == 1)
    CHECK(t.face_tags[0].tag == 0 && t.face_tags[0].triangles == 4 &&
          t.face_tags[0].open_edges == 0);
  mx_check_tags_free(&t);
  /* VTK: the point field surface_tag after other attributes. */
  p = tpath("tagged.vtk");
  write_text(p, tagged_vtk);
  CHECK(mx_read_mesh(p, &m) == MX_OK);
  CHECK(m.node_tag && m.nfaces == 0);
  if (m.node_tag)
    CHECK(m.node_tag[0] == 3 && m.node_tag[1] == 0 && m.node_tag[2] == 3 &&
          m.node_tag[3] == -2);
  CHECK(mx_check_mesh_tags(&m, NULL, NULL, &r, &t) == MX_OK);
  CHECK(r.has_node_tags && !r.has_tagged_faces && r.defects == 0);
  CHECK(t.nnode_tags == 2 && t.nface_tags == 0);
  if (t.nnode_tags == 2)
    CHECK(t.node_tags[0].tag == -2 && t.node_tags[0].nodes == 1 &&
          t.node_tags[1].tag == 3 && t.node_tags[1].nodes == 2);
  mx_check_tags_free(&t);
  mx_mesh_data_free(&m);
  /* Errors name the file and the place. */
  expect_error("face.getfem", getfem_tet("BEGIN REGION 3\n0/4\nEND REGION 3\n"),
               ":11: error: region 3: convex 0 ('GT_PK(3,1)') has no face 4");
  expect_error("cv.getfem", getfem_tet("BEGIN REGION 3\n1/0\nEND REGION 3\n"),
               ":11: error: region 3: convex 1 out of range");
  expect_error("noend.getfem", getfem_tet("BEGIN REGION 3\n0/1\n"),
               ":12: error: region 3: no END REGION");
  expect_error("tri.mesh",
               "MeshVersionFormatted 2\nDimension 3\nVertices\n1\n0 0 0 0\n"
               "Triangles\n1\n1 1 9 3\nEnd\n",
               ": error: triangle 0: vertex 9 out of range (1 vertices");
  expect_error("ref.mesh",
               "MeshVersionFormatted 2\nDimension 3\nVertices\n1\n0 0 0 0\n"
               "Triangles\n1\n1 1 1 3000000000\nEnd\n",
               ":8: error: reference 3000000000 is out of range");
  expect_error("face.msh",
               "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 1 1 1\n"
               "3 1 0 1\n1\n0 0 0\n$EndNodes\n$Elements\n1 1 1 1\n"
               "2 1 2 1\n1 1 1 9\n$EndElements\n",
               ":13: error: element 1: node tag 9 is not a node");
  expect_error("name.msh",
               "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$PhysicalNames\n1\n"
               "2 1 name\n$EndPhysicalNames\n",
               ":6: error: $PhysicalNames: name 0 is not in double quotes");
  expect_error("tag.vtk",
               "# vtk DataFile Version 3.0\nt\nASCII\nDATASET UNSTRUCTURED_GRID\n"
               "POINTS 1 double\n0 0 0\nCELLS 0 0\nCELL_TYPES 0\nPOINT_DATA 1\n"
               "SCALARS surface_tag int 1\nLOOKUP_TABLE default\n\n",
               ":13: error: surface_tag: expected 1 values, found 0");
}

/* A sphere as OFF: the octahedron's faces cut into n x n triangles each,
 * their lattice points pushed onto the sphere of radius r about c; outward
 * oriented, or inward. */
static void write_sphere(const char *path, double r, const double c[3], int n,
                         int inward) {
  const int w = 2 * n + 1;
  int *id = malloc((size_t)w * w * w * sizeof *id);
  double *xyz = malloc((size_t)w * w * w * 3 * sizeof *xyz);
  int *tri = malloc((size_t)8 * n * n * 3 * sizeof *tri);
  for (int i = 0; i < w * w * w; i++) id[i] = -1;
  int nv = 0, nt = 0;
  for (int s = 0; s < 8; s++) {
    const int sx = s & 1 ? -1 : 1, sy = s & 2 ? -1 : 1, sz = s & 4 ? -1 : 1;
    const int flip = (sx * sy * sz < 0) != (inward != 0);
    int at[64][64];
    for (int i = 0; i <= n; i++)
      for (int j = 0; i + j <= n; j++) {
        const int L[3] = {sx * (n - i - j), sy * i, sz * j};
        int *slot = &id[((L[0] + n) * w + L[1] + n) * w + L[2] + n];
        if (*slot < 0) {
          const double len = sqrt((double)(L[0] * L[0] + L[1] * L[1] + L[2] * L[2]));
          for (int a = 0; a < 3; a++) xyz[3 * nv + a] = c[a] + r * L[a] / len;
          *slot = nv++;
        }
        at[i][j] = *slot;
      }
    for (int i = 0; i < n; i++)
      for (int j = 0; i + j < n; j++) {
        const int t1[3] = {at[i][j], at[i + 1][j], at[i][j + 1]};
        for (int k = 0; k < 3; k++) tri[3 * nt + k] = t1[flip && k ? 3 - k : k];
        nt++;
        if (i + j < n - 1) {
          const int t2[3] = {at[i + 1][j], at[i + 1][j + 1], at[i][j + 1]};
          for (int k = 0; k < 3; k++) tri[3 * nt + k] = t2[flip && k ? 3 - k : k];
          nt++;
        }
      }
  }
  FILE *f = fopen(path, "w");
  fprintf(f, "OFF\n%d %d 0\n", nv, nt);
  for (int i = 0; i < nv; i++)
    fprintf(f, "%.17g %.17g %.17g\n", xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]);
  for (int i = 0; i < nt; i++)
    fprintf(f, "3 %d %d %d\n", tri[3 * i], tri[3 * i + 1], tri[3 * i + 2]);
  fclose(f);
  free(id);
  free(xyz);
  free(tri);
}

/* `mixoct check --json` on mixoct's own files, parsed by python3: every
 * file of argv[3:] ("-" before the files that carry node tags) must report
 * the tags 1..n with the same counts, closed, no tag defect, and as many
 * tagged faces as boundary faces; argv[2]: the tag names expected in MSH
 * files (comma-separated). Prints one line per tag. */
static const char tags_py[] =
    "import json, subprocess, sys\n"
    "mixoct, names, files = sys.argv[1], sys.argv[2].split(','), sys.argv[3:]\n"
    "def check(path):\n"
    "    p = subprocess.run([mixoct, 'check', path, '--json'], capture_output=True)\n"
    "    assert p.returncode == 0, (path, p.returncode, p.stderr)\n"
    "    return json.loads(p.stdout.decode().splitlines()[-1])\n"
    "faces = nodes = None\n"
    "node_files = False\n"
    "for f in files:\n"
    "    if f == '-':\n"
    "        node_files = True\n"
    "        continue\n"
    "    d = check(f)\n"
    "    assert d['defects'] == 0 and d['tagged_not_boundary'] == 0, (f, d)\n"
    "    assert d['boundary_untagged'] == 0, (f, d)\n"
    "    if node_files:\n"
    "        assert d['boundary_tags'] == [] and d['tagged_faces'] == 0, f\n"
    "        got = [(t['tag'], t['nodes']) for t in d['boundary_node_tags']]\n"
    "        assert [t for t, n in got] == list(range(1, len(names) + 1)), (f, got)\n"
    "        assert nodes is None or got == nodes, (f, got, nodes)\n"
    "        nodes = got\n"
    "        print('%s: node tags %s' % (f.split('/')[-1], got))\n"
    "        continue\n"
    "    tags = d['boundary_tags']\n"
    "    got = [(t['tag'], t['triangles'], t['quads']) for t in tags]\n"
    "    assert [t[0] for t in got] == list(range(1, len(names) + 1)), (f, got)\n"
    "    assert all(t['open_edges'] == 0 and t['not_boundary'] == 0 for t in tags), (f, tags)\n"
    "    assert sum(t[1] + t[2] for t in got) == d['tagged_faces'] == d['faces_boundary'], (f, d)\n"
    "    want = names if f.endswith('.msh') else [None] * len(names)\n"
    "    assert [t['name'] for t in tags] == want, (f, tags)\n"
    "    assert faces is None or got == faces, (f, got, faces)\n"
    "    faces = got\n"
    "    for t in tags:\n"
    "        print('%s: tag %d %s: %d triangles, %d quads, open edges %d' % (f.split('/')[-1], t['tag'], t['name'], t['triangles'], t['quads'], t['open_edges']))\n";

/* The bad file and the MSH names through `mixoct check --json`. */
static const char bad_py[] =
    "import json, subprocess, sys\n"
    "mixoct, bad, named = sys.argv[1:4]\n"
    "p = subprocess.run([mixoct, 'check', bad, '--json'], capture_output=True)\n"
    "assert p.returncode == 5, p\n"
    "d = json.loads(p.stdout.decode().splitlines()[-1])\n"
    "assert d['tagged_not_boundary'] == 1 and d['boundary_untagged'] == 1, d\n"
    "assert d['defects'] == 2 and d['tagged_faces'] == 10, d\n"
    "assert d['defective_faces'] == {'tagged_not_boundary': [9]}, d\n"
    "assert d['defective_elements']['boundary_untagged'] == [1], d\n"
    "assert [(t['tag'], t['quads'], t['open_edges'], t['not_boundary']) for t in "
    "d['boundary_tags']] == [(1, 5, 4, 0), (2, 5, 4, 1)], d\n"
    "p = subprocess.run([mixoct, 'check', named, '--json'], capture_output=True)\n"
    "assert p.returncode == 0, p\n"
    "d = json.loads(p.stdout.decode('utf-8'), parse_constant=lambda c: 1 / 0)\n"
    "assert [t['name'] for t in d['boundary_tags']] == [None, 'outer \"q\" \\\\ \\u00e9\\ufffd'], d\n";

/* Meshes of one input and of three (a hollow ball: a sphere with a smaller
 * one inside it, inward; and a sphere beside them), written by mixoct in
 * every format with boundary tags, read back and checked: the same tags
 * with the same counts everywhere, every tag closed, every tagged face a
 * boundary face and every boundary face tagged. */
static void test_tags_program(void) {
  if (access(mixoct, X_OK) != 0) {
    fprintf(stderr, "%s not found: tag program tests skipped\n", mixoct);
    CHECK(0);
    return;
  }
  char sph[256], in[256], far[256];
  snprintf(sph, sizeof sph, "%s", tpath("ball.off"));
  snprintf(in, sizeof in, "%s", tpath("cavity.off"));
  snprintf(far, sizeof far, "%s", tpath("beside.off"));
  const double c[3] = {0.013, 0.021, -0.017}, c2[3] = {3.013, 0.021, -0.017};
  write_sphere(sph, 1.0, c, 8, 0);
  write_sphere(in, 0.5, c, 6, 1);
  write_sphere(far, 1.0, c2, 8, 0);
  static const char *const face_ext[] = {"msh", "mesh", "meshb", "getfem"};
  char cmd[8192];
  for (int three = 0; three < 2; three++) {
    char base[256], files[4096] = "", nfiles[1024] = "";
    snprintf(base, sizeof base, "%s", tpath(three ? "three" : "one"));
    int n = snprintf(cmd, sizeof cmd, "'%s' -i '%s'", mixoct, sph);
    if (three) n += snprintf(cmd + n, sizeof cmd - (size_t)n, " -i '%s' -i '%s'", in, far);
    n += snprintf(cmd + n, sizeof cmd - (size_t)n, " -s 4 --quiet");
    const int n0 = n;
    for (int k = 0; k < 4; k++) {
      n += snprintf(cmd + n, sizeof cmd - (size_t)n, " -o '%s.%s'", base, face_ext[k]);
      snprintf(files + strlen(files), sizeof files - strlen(files), " '%s.%s'", base,
               face_ext[k]);
    }
    n += snprintf(cmd + n, sizeof cmd - (size_t)n, " -o '%s.vtu' -o '%s.vtk'", base, base);
    snprintf(nfiles, sizeof nfiles, " '%s.vtu' '%s.vtk' '%s_a.vtk'", base, base, base);
    CHECK(run(cmd) == 0);
    snprintf(cmd + n0, sizeof cmd - (size_t)n0, " --ascii -o '%s_a.msh' -o '%s_a.vtk'", base,
             base);
    CHECK(run(cmd) == 0);
    snprintf(files + strlen(files), sizeof files - strlen(files), " '%s_a.msh'", base);
    /* Read back here: the same counts in every format. */
    const int ntags = three ? 3 : 1;
    size_t want[4][2] = {{0}};
    const char *names[3] = {"ball.off", "cavity.off", "beside.off"};
    for (int k = 0; k < 5; k++) {
      char p[300];
      snprintf(p, sizeof p, "%s%s.%s", base, k == 4 ? "_a" : "", k == 4 ? "msh" : face_ext[k]);
      mx_check_report r;
      mx_check_tags t;
      CHECK(check_file_tags(p, &r, &t) == MX_OK);
      CHECK(r.defects == 0 && r.tagged_not_boundary == 0 && r.boundary_untagged == 0);
      CHECK(r.tagged_faces == r.faces_boundary && r.faces_boundary > 0);
      CHECK(t.nface_tags == (size_t)ntags);
      size_t sum = 0;
      for (size_t i = 0; i < t.nface_tags && t.nface_tags == (size_t)ntags; i++) {
        const mx_check_tag *g = &t.face_tags[i];
        CHECK(g->tag == (int32_t)i + 1 && g->open_edges == 0 && g->not_boundary == 0);
        CHECK(g->triangles + g->quads > 0);
        if (k == 0) {
          want[i][0] = g->triangles;
          want[i][1] = g->quads;
        }
        CHECK(g->triangles == want[i][0] && g->quads == want[i][1]);
        if (k == 0 || k == 4)
          CHECK(g->name && strcmp(g->name, names[i]) == 0);
        else
          CHECK(g->name == NULL);
        sum += g->triangles + g->quads;
      }
      CHECK(sum == r.faces_boundary);
      mx_check_tags_free(&t);
    }
    if (run("python3 -c pass") != 0) {
      fprintf(stderr, "python3 not found: tags in JSON not checked\n");
      continue;
    }
    const char *py = tpath("tags.py");
    write_text(py, tags_py);
    snprintf(cmd, sizeof cmd, "python3 '%s' '%s' '%s' %s -%s", py, mixoct,
             three ? "ball.off,cavity.off,beside.off" : "ball.off", files, nfiles);
    CHECK(run(cmd) == 0);
  }
  if (run("python3 -c pass") != 0) return;
  char bad[256], named[256], py[256];
  snprintf(bad, sizeof bad, "%s", tpath("badtags.mesh"));
  snprintf(named, sizeof named, "%s", tpath("named.msh"));
  snprintf(py, sizeof py, "%s", tpath("bad.py"));
  write_text(bad, bad_tags_mesh);
  write_text(named, tagged_msh);
  write_text(py, bad_py);
  snprintf(cmd, sizeof cmd, "python3 '%s' '%s' '%s' '%s'", py, mixoct, bad, named);
  CHECK(run(cmd) == 0);
  /* The text report names the defects. */
  const char *out = tpath("tags.txt");
  snprintf(cmd, sizeof cmd, "'%s' check '%s' > '%s' 2>&1", mixoct, bad, out);
  CHECK(run(cmd) == 5);
  size_t len;
  char *txt = slurp(out, &len);
  CHECK(txt && strstr(txt, "boundary tags          2 tags, 10 faces (0 triangles, 10 "
                           "quadrilaterals)") &&
        strstr(txt, "    tag 2: 0 triangles, 5 quadrilaterals, 4 open edges (not "
                    "closed), 1 not on the boundary") &&
        strstr(txt, "tagged not boundary      1   <-- defect") &&
        strstr(txt, "boundary untagged        1   <-- defect"));
  free(txt);
}

/* Reading and checking an n^3 hexahedral grid written as VTU. */
static void test_speed(size_t n) {
  tm t = {0};
  grid_hexes(&t, n, 1.0 / (double)n, -1);
  mx_mesh_data d = tm_data(&t);
  mx_mesh_view v = mx_mesh_data_view(&d);
  const char *p = tpath("big.vtu");
  CHECK(mx_write_vtu(p, &v) == MX_OK);
  double t0 = mx_wtime();
  mx_mesh_data m;
  CHECK(mx_read_mesh(p, &m) == MX_OK);
  double t1 = mx_wtime();
  mx_check_report r;
  CHECK(mx_check_mesh(&m, NULL, &r) == MX_OK);
  double t2 = mx_wtime();
  CHECK(r.defects == 0 && r.elements == n * n * n);
  CHECK(r.faces_boundary == 6 * n * n);
  CHECK(r.faces_interior == 3 * n * n * (n - 1));
  CHECK(near(r.volume, 1.0, 1e-9));
  CHECK(same_mesh(&t, &m));
  printf("%zu^3 hexahedra (%zu cells, %zu nodes), %d threads: read VTU "
         "%.2f s, check %.2f s\n",
         n, r.elements, r.nodes, omp_get_max_threads(), t1 - t0, t2 - t1);
  mx_mesh_data_free(&m);
  tm_free(&t);
  remove(p);
}

int main(int argc, char **argv) {
  small_only = argc > 1 && strcmp(argv[1], "small") == 0;
  snprintf(tmpdir, sizeof tmpdir, "/tmp/mixoct_check_XXXXXX");
  if (!mkdtemp(tmpdir)) {
    perror("mkdtemp");
    return 2;
  }
  /* The program sits next to the tests directory of the build. */
  const char *slash = strrchr(argv[0], '/');
  if (slash)
    snprintf(mixoct, sizeof mixoct, "%.*s/../mixoct", (int)(slash - argv[0]),
             argv[0]);
  else
    snprintf(mixoct, sizeof mixoct, "../mixoct");
  test_valid();
  test_defects();
  test_round_trips();
  test_formats();
  test_damage();
  test_surface();
  test_geometric_hanging();
  test_contacts();
  test_degenerate();
  test_extreme_coordinates();
  test_volume();
  test_huge_counts();
  test_msh_medit();
  double t0 = mx_wtime();
  test_tag_readers();
  const double t_tags = mx_wtime() - t0;
  test_threads();
  test_program();
  t0 = mx_wtime();
  test_tags_program();
  printf("boundary tags: readers %.2f s, program %.2f s\n", t_tags, mx_wtime() - t0);
  if (!small_only) test_speed(100);
  char cmd[128];
  snprintf(cmd, sizeof cmd, "rm -rf '%s'", tmpdir);
  if (system(cmd) != 0) fprintf(stderr, "could not remove %s\n", tmpdir);
  return TEST_DONE();
}
