/* Tests of the GetFEM (.getfem) and M3D (.m3d) writers. Files are read back
 * by small readers written here from the formats' descriptions (GetFEM's
 * documentation for .getfem; the layout documented in src/io/write_m3d.c for
 * .m3d, which is mixoct's own), not with mixoct's code:
 *  - one reference element of each type per format, under an affine map with
 *    a positive determinant: positive volume in the format's convention
 *    (GetFEM: the Jacobian of the map from GetFEM's reference element, built
 *    from GetFEM's shape functions; M3D: VTK's node order), and the right
 *    volume; the VTK order read as GetFEM's would be wrong (negative check);
 *  - a small mixed mesh (hex, prism, pyramid, tet sharing nodes): counts,
 *    coordinates bit for bit, connectivity;
 *  - the same bytes for 1, 2 and 3 threads on a larger mesh;
 *  - /dev/full and a missing directory: MX_EINPUT, nothing left behind. */
#include <ctype.h>
#include <dirent.h>
#include <math.h>
#include <omp.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "check.h"
#include "common.h"
#include "soa/mesh.h"

#define OUT_DIR "getfem_m3d_out"
#include "file_util.h"

/* ====================================================================== */
/* Readers                                                                */
/* ====================================================================== */

typedef struct {
  size_t nnodes, ncells;
  double *xyz;
  int *nper;      /* nodes per cell */
  uint32_t *conn; /* 8 per cell */
  char (*name)[32]; /* GetFEM: geometric transformation of each cell */
} rmesh;

static void rmesh_free(rmesh *r) {
  free(r->xyz);
  free(r->nper);
  free(r->conn);
  free(r->name);
  memset(r, 0, sizeof *r);
}

/* Whitespace-separated tokens; '%' starts a comment to the end of the line. */
typedef struct {
  const char *p;
  char tok[256];
} lexer;

static const char *next_tok(lexer *L) {
  for (;;) {
    while (*L->p && isspace((unsigned char)*L->p)) L->p++;
    if (*L->p == '%') {
      while (*L->p && *L->p != '\n') L->p++;
      continue;
    }
    break;
  }
  if (!*L->p) return NULL;
  size_t n = 0;
  while (*L->p && !isspace((unsigned char)*L->p) && n + 1 < sizeof L->tok) L->tok[n++] = *L->p++;
  L->tok[n] = '\0';
  return L->tok;
}

static int expect_words(lexer *L, const char *words) {
  char buf[128];
  snprintf(buf, sizeof buf, "%s", words);
  for (char *w = strtok(buf, " "); w; w = strtok(NULL, " ")) {
    const char *t = next_tok(L);
    if (!t || strcmp(t, w) != 0) return 0;
  }
  return 1;
}

static int getfem_nodes_of(const char *name) {
  if (!strcmp(name, "'GT_PK(3,1)'")) return 4;
  if (!strcmp(name, "'GT_PYRAMID(1)'")) return 5;
  if (!strcmp(name, "'GT_PRISM(3,1)'")) return 6;
  if (!strcmp(name, "'GT_QK(3,1)'")) return 8;
  return -1;
}

/* GetFEM mesh file: "POINT i x y z" between BEGIN/END POINTS LIST, "CONVEX i
 * 'GT' nodes..." between BEGIN/END MESH STRUCTURE DESCRIPTION; optional
 * "POINT COUNT n" / "CONVEX COUNT n". Indices must come as 0, 1, 2, ... */
static int read_getfem(const char *path, rmesh *r) {
  memset(r, 0, sizeof *r);
  char *text = slurp(path, NULL);
  if (!text) return 0;
  const char *begin = strstr(text, "BEGIN POINTS LIST");
  int ok = begin != NULL;
  lexer L = {begin ? begin : text, {0}};
  ok = ok && expect_words(&L, "BEGIN POINTS LIST");
  size_t cap = 16;
  r->xyz = malloc(3 * cap * sizeof(double));
  while (ok) {
    const char *t = next_tok(&L);
    if (!t) {
      ok = 0;
      break;
    }
    if (!strcmp(t, "END")) {
      ok = expect_words(&L, "POINTS LIST");
      break;
    }
    if (strcmp(t, "POINT") != 0) {
      ok = 0;
      break;
    }
    t = next_tok(&L);
    if (t && !strcmp(t, "COUNT")) {
      next_tok(&L);
      continue;
    }
    if (!t || strtoull(t, NULL, 10) != r->nnodes) {
      ok = 0;
      break;
    }
    if (r->nnodes == cap) {
      cap *= 2;
      r->xyz = realloc(r->xyz, 3 * cap * sizeof(double));
    }
    for (int d = 0; d < 3 && ok; d++) {
      t = next_tok(&L);
      char *end;
      r->xyz[3 * r->nnodes + d] = t ? strtod(t, &end) : 0.0;
      ok = t && *end == '\0';
    }
    r->nnodes++;
  }
  ok = ok && expect_words(&L, "BEGIN MESH STRUCTURE DESCRIPTION");
  cap = 16;
  r->nper = malloc(cap * sizeof(int));
  r->conn = malloc(8 * cap * sizeof(uint32_t));
  r->name = malloc(cap * sizeof *r->name);
  while (ok) {
    const char *t = next_tok(&L);
    if (!t) {
      ok = 0;
      break;
    }
    if (!strcmp(t, "END")) {
      ok = expect_words(&L, "MESH STRUCTURE DESCRIPTION");
      break;
    }
    if (strcmp(t, "CONVEX") != 0) {
      ok = 0;
      break;
    }
    t = next_tok(&L);
    if (t && !strcmp(t, "COUNT")) {
      next_tok(&L);
      continue;
    }
    if (!t || strtoull(t, NULL, 10) != r->ncells) {
      ok = 0;
      break;
    }
    if (r->ncells == cap) {
      cap *= 2;
      r->nper = realloc(r->nper, cap * sizeof(int));
      r->conn = realloc(r->conn, 8 * cap * sizeof(uint32_t));
      r->name = realloc(r->name, cap * sizeof *r->name);
    }
    t = next_tok(&L);
    int k = t ? getfem_nodes_of(t) : -1;
    if (k < 0) {
      ok = 0;
      break;
    }
    snprintf(r->name[r->ncells], sizeof r->name[0], "%s", t);
    r->nper[r->ncells] = k;
    for (int j = 0; j < k && ok; j++) {
      t = next_tok(&L);
      char *end;
      unsigned long long v = t ? strtoull(t, &end, 10) : 0;
      ok = t && *end == '\0' && v < r->nnodes;
      r->conn[8 * r->ncells + j] = (uint32_t)v;
    }
    r->ncells++;
  }
  ok = ok && next_tok(&L) == NULL; /* nothing after the end */
  free(text);
  return ok;
}

/* M3D as documented in src/io/write_m3d.c. */
static int read_m3d(const char *path, rmesh *r) {
  memset(r, 0, sizeof *r);
  char *text = slurp(path, NULL);
  if (!text) return 0;
  lexer L = {text, {0}};
  int ok = expect_words(&L, "[Nodes, ARRAY1<POINT3D>]");
  const char *t = ok ? next_tok(&L) : NULL;
  ok = t != NULL;
  r->nnodes = t ? strtoull(t, NULL, 10) : 0;
  r->xyz = malloc((3 * r->nnodes + 1) * sizeof(double));
  for (size_t i = 0; ok && i < 3 * r->nnodes; i++) {
    t = next_tok(&L);
    char *end;
    r->xyz[i] = t ? strtod(t, &end) : 0.0;
    ok = t && *end == '\0';
  }
  ok = ok && expect_words(&L, "[Elements, ARRAY1<STRING>]");
  t = ok ? next_tok(&L) : NULL;
  ok = ok && t != NULL;
  r->ncells = t ? strtoull(t, NULL, 10) : 0;
  r->nper = malloc((r->ncells + 1) * sizeof(int));
  r->conn = malloc((8 * r->ncells + 1) * sizeof(uint32_t));
  for (size_t c = 0; ok && c < r->ncells; c++) {
    t = next_tok(&L);
    int k = t ? atoi(t) : 0;
    ok = k == 4 || k == 5 || k == 6 || k == 8;
    r->nper[c] = k;
    for (int j = 0; j < k && ok; j++) {
      t = next_tok(&L);
      char *end;
      unsigned long long v = t ? strtoull(t, &end, 10) : 0;
      ok = t && *end == '\0' && v < r->nnodes;
      r->conn[8 * c + j] = (uint32_t)v;
    }
  }
  ok = ok && next_tok(&L) == NULL;
  free(text);
  return ok;
}

/* ====================================================================== */
/* Geometry in each format's convention                                   */
/* ====================================================================== */

static double det3(const double a[3], const double b[3], const double c[3]) {
  return a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) +
         a[2] * (b[0] * c[1] - b[1] * c[0]);
}

/* GetFEM's degree-1 shape functions on its reference elements (GetFEM
 * documentation: P1 on the simplex, tensor products for Q1 and the prism,
 * the rational P1 pyramid of appendix A). */
static void getfem_shape(int k, const double *r, double *phi) {
  const double x = r[0], y = r[1], z = r[2];
  switch (k) {
  case 4:
    phi[0] = 1 - x - y - z;
    phi[1] = x;
    phi[2] = y;
    phi[3] = z;
    break;
  case 5: {
    const double q = x * y / (1 - z);
    phi[0] = 0.25 * (1 - x - y - z + q);
    phi[1] = 0.25 * (1 + x - y - z - q);
    phi[2] = 0.25 * (1 - x + y - z - q);
    phi[3] = 0.25 * (1 + x + y - z + q);
    phi[4] = z;
    break;
  }
  case 6: {
    const double tri[3] = {1 - x - y, x, y}, seg[2] = {1 - z, z};
    for (int j = 0; j < 2; j++)
      for (int i = 0; i < 3; i++) phi[3 * j + i] = tri[i] * seg[j];
    break;
  }
  default: {
    const double s[3][2] = {{1 - x, x}, {1 - y, y}, {1 - z, z}};
    for (int c = 0; c < 2; c++)
      for (int b = 0; b < 2; b++)
        for (int a = 0; a < 2; a++) phi[4 * c + 2 * b + a] = s[0][a] * s[1][b] * s[2][c];
  }
  }
}

/* det of the Jacobian of x(r) = sum phi_i(r) p_i, by central differences
 * (exact up to rounding for these shape functions at interior points). */
static double getfem_jacobian(int k, const double (*p)[3], const double *r) {
  const double h = 1e-5;
  double J[3][3];
  for (int b = 0; b < 3; b++) {
    double rp[3] = {r[0], r[1], r[2]}, rm[3] = {r[0], r[1], r[2]};
    rp[b] += h;
    rm[b] -= h;
    double fp[8], fm[8];
    getfem_shape(k, rp, fp);
    getfem_shape(k, rm, fm);
    for (int a = 0; a < 3; a++) {
      double d = 0.0;
      for (int i = 0; i < k; i++) d += (fp[i] - fm[i]) * p[i][a];
      J[b][a] = d / (2 * h);
    }
  }
  return det3(J[0], J[1], J[2]);
}

/* Interior points of each GetFEM reference element: the centroid and one
 * near each vertex; ref_volume is the reference element's volume. */
static int getfem_points(int k, double (*pts)[3], double *ref_volume) {
  static const double tet[4][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  static const double pyr[5][3] = {{-1, -1, 0}, {1, -1, 0}, {-1, 1, 0}, {1, 1, 0}, {0, 0, 1}};
  static const double pri[6][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0},
                                   {0, 0, 1}, {1, 0, 1}, {0, 1, 1}};
  static const double hex[8][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0},
                                   {0, 0, 1}, {1, 0, 1}, {0, 1, 1}, {1, 1, 1}};
  const double(*v)[3] = k == 4 ? tet : k == 5 ? pyr : k == 6 ? pri : hex;
  *ref_volume = k == 4 ? 1.0 / 6 : k == 5 ? 4.0 / 3 : k == 6 ? 0.5 : 1.0;
  double c[3] = {0, 0, 0};
  for (int i = 0; i < k; i++)
    for (int a = 0; a < 3; a++) c[a] += v[i][a] / k;
  if (k == 5) c[2] = 0.25; /* the pyramid's centroid */
  for (int a = 0; a < 3; a++) pts[0][a] = c[a];
  for (int i = 0; i < k; i++)
    for (int a = 0; a < 3; a++) pts[1 + i][a] = 0.9 * v[i][a] + 0.1 * c[a];
  return 1 + k;
}

/* Signed volume in VTK's convention, by tetrahedra. */
static double vtk_volume(int k, const double (*p)[3]) {
  static const int tet[1][4] = {{0, 1, 2, 3}};
  static const int pyr[2][4] = {{0, 1, 2, 4}, {0, 2, 3, 4}};
  static const int pri[3][4] = {{0, 1, 2, 5}, {0, 1, 5, 4}, {0, 4, 5, 3}};
  static const int hex[6][4] = {{0, 1, 2, 6}, {0, 2, 3, 6}, {0, 3, 7, 6},
                                {0, 7, 4, 6}, {0, 4, 5, 6}, {0, 5, 1, 6}};
  const int(*T)[4] = k == 4 ? tet : k == 5 ? pyr : k == 6 ? pri : hex;
  const int n = k == 4 ? 1 : k == 5 ? 2 : k == 6 ? 3 : 6;
  double v = 0.0;
  for (int i = 0; i < n; i++) {
    double a[3], b[3], c[3];
    for (int x = 0; x < 3; x++) {
      a[x] = p[T[i][1]][x] - p[T[i][0]][x];
      b[x] = p[T[i][2]][x] - p[T[i][0]][x];
      c[x] = p[T[i][3]][x] - p[T[i][0]][x];
    }
    v += det3(a, b, c) / 6.0;
  }
  return v;
}

/* ====================================================================== */
/* Tests                                                                  */
/* ====================================================================== */

/* VTK-ordered reference elements (positive in VTK's convention), the volume
 * of each before the map. */
static const double ref_vtk[4][8][3] = {
    {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}},
    {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0.5, 0.5, 1}},
    {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {0, 1, 1}},
    {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}}};
static const double ref_volume_vtk[4] = {1.0 / 6, 1.0 / 3, 0.5, 1.0};

/* A general linear map with det = 3.105 > 0, and a translation. */
static const double A[3][3] = {{0, -2, 0.3}, {0.5, 0, 0}, {0, 0.7, 3}};
static const double Ab[3] = {10.25, -3.5, 1e3};

static double detA(void) { return det3(A[0], A[1], A[2]); }

static void map_point(const double *r, double *x) {
  for (int a = 0; a < 3; a++) x[a] = A[a][0] * r[0] + A[a][1] * r[1] + A[a][2] * r[2] + Ab[a];
}

static void reference_mesh(tmesh *t, int type) {
  const int k = mx_cell_nodes[type];
  tmesh_alloc(t, (size_t)k, 1);
  uint32_t nodes[8];
  /* nodes stored in reverse so that indices differ from local numbers */
  for (int i = 0; i < k; i++) {
    map_point(ref_vtk[type][i], t->xyz + 3 * (size_t)(k - 1 - i));
    nodes[i] = (uint32_t)(k - 1 - i);
  }
  set_cell(t, 0, type, nodes);
}

static void test_reference_getfem(void) {
  static const char *names[4] = {"'GT_PK(3,1)'", "'GT_PYRAMID(1)'", "'GT_PRISM(3,1)'",
                                 "'GT_QK(3,1)'"};
  for (int type = 0; type < 4; type++) {
    tmesh t;
    reference_mesh(&t, type);
    char path[256];
    path_in(path, sizeof path, "ref.getfem");
    CHECK(mx_write_getfem(path, &t.v) == MX_OK);
    rmesh r;
    int ok = read_getfem(path, &r);
    CHECK(ok);
    if (ok) {
      const int k = mx_cell_nodes[type];
      CHECK(r.nnodes == (size_t)k && r.ncells == 1 && r.nper[0] == k);
      CHECK(strcmp(r.name[0], names[type]) == 0);
      double p[8][3];
      for (int i = 0; i < k; i++)
        for (int a = 0; a < 3; a++) p[i][a] = r.xyz[3 * r.conn[i] + a];
      double pts[9][3], ref_volume;
      const int np = getfem_points(k, pts, &ref_volume);
      for (int i = 0; i < np; i++) {
        const double j = getfem_jacobian(k, (const double(*)[3])p, pts[i]);
        if (!(j > 0.0)) printf("type %d point %d: J = %g\n", type, i, j);
        CHECK(j > 0.0);
      }
      /* affine images: constant Jacobian, volume = J * reference volume */
      const double vol = getfem_jacobian(k, (const double(*)[3])p, pts[0]) * ref_volume;
      const double want = ref_volume_vtk[type] * detA();
      printf("getfem %-16s volume %.15g (expected %.15g)\n", names[type], vol, want);
      CHECK(fabs(vol - want) < 1e-7 * want);
      if (type == MX_HEX) {
        /* negative check: VTK's order read as GetFEM's twists the hex */
        double q[8][3];
        for (int i = 0; i < 8; i++)
          for (int a = 0; a < 3; a++) q[i][a] = t.xyz[3 * t.conn[i] + a];
        CHECK(!(getfem_jacobian(8, (const double(*)[3])q, pts[0]) > 1e-9));
      }
      if (type == MX_PYRAMID) {
        double q[5][3];
        for (int i = 0; i < 5; i++)
          for (int a = 0; a < 3; a++) q[i][a] = t.xyz[3 * t.conn[i] + a];
        CHECK(!(getfem_jacobian(5, (const double(*)[3])q, pts[0]) > 1e-9));
      }
    }
    rmesh_free(&r);
    tmesh_free(&t);
  }
}

static void test_reference_m3d(void) {
  for (int type = 0; type < 4; type++) {
    tmesh t;
    reference_mesh(&t, type);
    char path[256];
    path_in(path, sizeof path, "ref.m3d");
    CHECK(mx_write_m3d(path, &t.v) == MX_OK);
    rmesh r;
    int ok = read_m3d(path, &r);
    CHECK(ok);
    if (ok) {
      const int k = mx_cell_nodes[type];
      CHECK(r.nnodes == (size_t)k && r.ncells == 1 && r.nper[0] == k);
      double p[8][3];
      for (int i = 0; i < k; i++)
        for (int a = 0; a < 3; a++) p[i][a] = r.xyz[3 * r.conn[i] + a];
      const double vol = vtk_volume(k, (const double(*)[3])p);
      const double want = ref_volume_vtk[type] * detA();
      printf("m3d    %d nodes          volume %.15g (expected %.15g)\n", k, vol, want);
      CHECK(vol > 0.0 && fabs(vol - want) < 1e-9 * want);
    }
    rmesh_free(&r);
    tmesh_free(&t);
  }
}

/* A unit hexahedron, a prism beside it, a pyramid on top and a tetrahedron,
 * sharing nodes, all valid; awkward coordinates. */
static void small_mesh(tmesh *t) {
  static const double xyz[12][3] = {
      {0, 0, 0},   {1, 0, 0}, {1, 1, 0},   {0, 1, 0}, {0, 0, 1}, {1, 0, 1},
      {1, 1, 1},   {0, 1, 1}, {2, 0, 0},   {2, 0, 1}, {0.5, 0.5, 1.0 + 1.0 / 3.0},
      {2.0000000000000004, -2.5e-7, 123456789.123}};
  tmesh_alloc(t, 12, 4);
  memcpy(t->xyz, xyz, sizeof xyz);
  t->xyz[3 * 3 + 1] = 0.1;
  t->xyz[3 * 7 + 2] = 1.0 + 1e-13;
  t->xyz[3 * 8 + 2] = -1e-300;
  static const uint32_t hex[8] = {0, 1, 2, 3, 4, 5, 6, 7};
  static const uint32_t prism[6] = {1, 8, 2, 5, 9, 6};
  static const uint32_t pyr[5] = {4, 5, 6, 7, 10};
  static const uint32_t tet[4] = {5, 9, 6, 11};
  set_cell(t, 0, MX_HEX, hex);
  set_cell(t, 1, MX_PRISM, prism);
  set_cell(t, 2, MX_PYRAMID, pyr);
  set_cell(t, 3, MX_TET, tet);
}

static void check_round_trip(const tmesh *t, const rmesh *r, int getfem) {
  /* GetFEM's node k is VTK's node order[k] (independent restatement) */
  static const int order[4][8] = {{0, 1, 2, 3}, {0, 1, 3, 2, 4}, {0, 1, 2, 3, 4, 5},
                                  {0, 1, 3, 2, 4, 5, 7, 6}};
  CHECK(r->nnodes == t->nnodes && r->ncells == t->ncells);
  if (r->nnodes != t->nnodes || r->ncells != t->ncells) return;
  CHECK(memcmp(r->xyz, t->xyz, 3 * t->nnodes * sizeof(double)) == 0);
  for (size_t c = 0; c < t->ncells; c++) {
    const int type = t->type[c], k = mx_cell_nodes[type];
    CHECK(r->nper[c] == k);
    for (int j = 0; j < k; j++) {
      const uint32_t want = t->conn[8 * c + (getfem ? order[type][j] : j)];
      CHECK(r->conn[8 * c + j] == want);
    }
  }
}

static void test_small_round_trip(void) {
  tmesh t;
  small_mesh(&t);
  char path[256];
  rmesh r;
  path_in(path, sizeof path, "small.getfem");
  CHECK(mx_write_getfem(path, &t.v) == MX_OK);
  CHECK(read_getfem(path, &r));
  check_round_trip(&t, &r, 1);
  /* every element of the small mesh is valid: positive in GetFEM's terms */
  for (size_t c = 0; c < r.ncells && r.ncells == t.ncells; c++) {
    const int k = r.nper[c];
    double p[8][3], pts[9][3], rv;
    for (int i = 0; i < k; i++)
      for (int a = 0; a < 3; a++) p[i][a] = r.xyz[3 * r.conn[8 * c + i] + a];
    const int np = getfem_points(k, pts, &rv);
    for (int i = 0; i < np; i++) CHECK(getfem_jacobian(k, (const double(*)[3])p, pts[i]) > 0.0);
  }
  rmesh_free(&r);
  path_in(path, sizeof path, "small.m3d");
  CHECK(mx_write_m3d(path, &t.v) == MX_OK);
  CHECK(read_m3d(path, &r));
  check_round_trip(&t, &r, 0);
  for (size_t c = 0; c < r.ncells && r.ncells == t.ncells; c++) {
    double p[8][3];
    for (int i = 0; i < r.nper[c]; i++)
      for (int a = 0; a < 3; a++) p[i][a] = r.xyz[3 * r.conn[8 * c + i] + a];
    CHECK(vtk_volume(r.nper[c], (const double(*)[3])p) > 0.0);
  }
  rmesh_free(&r);
  CHECK(count_entries(OUT_DIR, "small") == 2); /* no temporaries left */
  /* empty mesh: valid files with no points and no convexes */
  tmesh e;
  tmesh_alloc(&e, 0, 0);
  path_in(path, sizeof path, "empty.getfem");
  CHECK(mx_write_getfem(path, &e.v) == MX_OK);
  CHECK(read_getfem(path, &r) && r.nnodes == 0 && r.ncells == 0);
  rmesh_free(&r);
  path_in(path, sizeof path, "empty.m3d");
  CHECK(mx_write_m3d(path, &e.v) == MX_OK);
  CHECK(read_m3d(path, &r) && r.nnodes == 0 && r.ncells == 0);
  rmesh_free(&r);
  tmesh_free(&e);
  tmesh_free(&t);
}

/* n^3 cells over a jittered grid, types cycling. */
static void grid_mesh(tmesh *t, size_t n) {
  const size_t np = n + 1;
  tmesh_alloc(t, np * np * np, n * n * n);
  uint64_t s = 0x9E3779B97F4A7C15ull;
  for (size_t i = 0; i < 3 * np * np * np; i++) {
    s ^= s << 13;
    s ^= s >> 7;
    s ^= s << 17;
    const size_t p = i / 3, d = i % 3;
    const size_t ijk[3] = {p % np, p / np % np, p / (np * np)};
    t->xyz[i] = (double)ijk[d] / 3.0 + (double)(s % 1000) * 1e-7;
  }
  for (size_t c = 0; c < n * n * n; c++) {
    const size_t i = c % n, j = c / n % n, k = c / (n * n);
    const uint32_t b = (uint32_t)((k * np + j) * np + i), sy = (uint32_t)np,
                   sz = (uint32_t)(np * np);
    const uint32_t nodes[8] = {b, b + 1, b + 1 + sy, b + sy, b + sz, b + 1 + sz, b + 1 + sy + sz,
                               b + sy + sz};
    set_cell(t, c, (int)(c % 4), nodes);
  }
}

static void test_threads(void) {
  tmesh t;
  grid_mesh(&t, 24); /* 13,824 cells, 15,625 nodes */
  const int saved = omp_get_max_threads();
  for (int f = 0; f < 2; f++) {
    char *first = NULL;
    size_t first_len = 0;
    for (int th = 1; th <= 3; th++) {
      omp_set_num_threads(th);
      char path[256];
      path_in(path, sizeof path, f ? "grid.m3d" : "grid.getfem");
      CHECK((f ? mx_write_m3d(path, &t.v) : mx_write_getfem(path, &t.v)) == MX_OK);
      size_t len;
      char *bytes = slurp(path, &len);
      CHECK(bytes != NULL);
      if (th == 1) {
        first = bytes;
        first_len = len;
        rmesh r;
        CHECK(f ? read_m3d(path, &r) : read_getfem(path, &r));
        check_round_trip(&t, &r, !f);
        rmesh_free(&r);
      } else {
        CHECK(bytes && len == first_len && memcmp(bytes, first, len) == 0);
        free(bytes);
      }
    }
    free(first);
  }
  omp_set_num_threads(saved);
  tmesh_free(&t);
}

static void test_failures(void) {
  tmesh t;
  small_mesh(&t);
  if (have_dev_full()) {
    CHECK(mx_write_getfem("/dev/full", &t.v) == MX_EIO);
    CHECK(mx_write_m3d("/dev/full", &t.v) == MX_EIO);
    CHECK(dev_full_intact());
  }
  char path[256];
  path_in(path, sizeof path, "no/such/dir/x.getfem");
  CHECK(mx_write_getfem(path, &t.v) == MX_EIO);
  path_in(path, sizeof path, "no/such/dir/x.m3d");
  CHECK(mx_write_m3d(path, &t.v) == MX_EIO);
  CHECK(count_entries(OUT_DIR, "no") == 0);
  /* a bad node index is refused before any file is created */
  t.conn[8 * 3 + 2] = 99;
  path_in(path, sizeof path, "bad.getfem");
  CHECK(mx_write_getfem(path, &t.v) == MX_EINTERNAL);
  path_in(path, sizeof path, "bad.m3d");
  CHECK(mx_write_m3d(path, &t.v) == MX_EINTERNAL);
  CHECK(count_entries(OUT_DIR, "bad") == 0);
  tmesh_free(&t);
}

int main(void) {
  mkdir(OUT_DIR, 0755);
  test_reference_getfem();
  test_reference_m3d();
  test_small_round_trip();
  test_threads();
  test_failures();
  return TEST_DONE();
}
