/* Tests of the GetFEM (.getfem), M3D (.m3d) and MVM (.mvm) writers and of
 * their readers in mx_read_mesh (`mixoct check`).
 *
 * Written files are first read back by small readers written here from the
 * formats' descriptions (GetFEM's documentation for .getfem; REFERENCE.md,
 * "Published output layouts", for .m3d and .mvm), not with mixoct's code:
 *  - one reference element of each type per format, under an affine map with
 *    a positive determinant: positive volume in the format's convention
 *    (GetFEM: the Jacobian of the map from GetFEM's reference element, built
 *    from GetFEM's shape functions; M3D: mixoct's node order, VTK's but for
 *    the prism, Gmsh's), and the right volume; the VTK order read as
 *    GetFEM's would be wrong (negative check);
 *  - a small mixed mesh (hex, prism, pyramid, tet sharing nodes): counts,
 *    coordinates (bit for bit in GetFEM; to the 9 significant digits of
 *    "%+1.8E" in M3D and MVM), connectivity;
 *  - the M3D and MVM files of a tiny mesh line by line against the
 *    documented layout, and a view with a written order (mx_view_cell);
 *  - the same bytes for 1, 2 and 3 threads on a larger mesh;
 *  - /dev/full and a missing directory: MX_EIO, nothing left behind.
 * Then mx_read_mesh: round trips of the three formats (and mixoct's older
 * M3D layout); malformed files (truncated, counts beyond the file, indices
 * out of range, words for numbers, every prefix and random byte changes of
 * a valid file) are refused with MX_EINPUT and a message naming the file,
 * never a crash; and `mixoct check` on a .mvm written by `mixoct --demo`. */
#include <ctype.h>
#include <dirent.h>
#include <math.h>
#include <omp.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include "check.h"
#include "base/common.h"
#include "io/read_mesh.h"
#include "soa/mesh.h"

#define OUT_DIR "getfem_m3d_out"
#include "file_util.h"
#include "io/write_mesh.h"

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

/* Nodes of the letter of an M3D / MVM element line, -1 if none. */
static int letter_nodes(const char *t) {
  if (!t || strlen(t) != 1) return -1;
  switch (*t) {
  case 'T': return 4;
  case 'P': return 5;
  case 'R': return 6;
  case 'H': return 8;
  default: return -1;
  }
}

static int read_count(lexer *L, size_t *n) {
  const char *t = next_tok(L);
  char *end;
  *n = t ? strtoull(t, &end, 10) : 0;
  return t && *end == '\0' && *n < 100000000;
}

static int read_real(lexer *L, double *v) {
  const char *t = next_tok(L);
  char *end;
  *v = t ? strtod(t, &end) : 0.0;
  return t && *end == '\0';
}

/* n nodes "x y z", after a "1" when numbered. */
static int read_nodes(lexer *L, rmesh *r, int numbered) {
  r->xyz = malloc((3 * r->nnodes + 1) * sizeof(double));
  int ok = 1;
  for (size_t i = 0; ok && i < r->nnodes; i++) {
    if (numbered) {
      const char *t = next_tok(L);
      ok = t && !strcmp(t, "1");
    }
    for (int d = 0; ok && d < 3; d++) ok = read_real(L, &r->xyz[3 * i + d]);
  }
  return ok;
}

/* M element lines "L i0 ...", followed by "1000.0 0.45 1.0" when tail. */
static int read_letter_cells(lexer *L, rmesh *r, int tail) {
  r->nper = malloc((r->ncells + 1) * sizeof(int));
  r->conn = malloc((8 * r->ncells + 1) * sizeof(uint32_t));
  int ok = 1;
  for (size_t c = 0; ok && c < r->ncells; c++) {
    const int k = letter_nodes(next_tok(L));
    ok = k > 0;
    r->nper[c] = k;
    for (int j = 0; j < k && ok; j++) {
      const char *t = next_tok(L);
      char *end;
      unsigned long long v = t ? strtoull(t, &end, 10) : 0;
      ok = t && *end == '\0' && v < r->nnodes;
      r->conn[8 * c + j] = (uint32_t)v;
    }
    ok = ok && (!tail || expect_words(L, "1000.0 0.45 1.0"));
  }
  return ok;
}

/* M3D as REFERENCE.md describes it ("Published output layouts"). */
static int read_m3d(const char *path, rmesh *r) {
  memset(r, 0, sizeof *r);
  char *text = slurp(path, NULL);
  if (!text) return 0;
  lexer L = {text, {0}};
  int ok = expect_words(&L, "[Nodes, ARRAY1<STRING>]") && read_count(&L, &r->nnodes);
  ok = ok && read_nodes(&L, r, 1);
  ok = ok && expect_words(&L, "[Elements, ARRAY1<STRING>]") && read_count(&L, &r->ncells);
  ok = ok && read_letter_cells(&L, r, 1);
  ok = ok && next_tok(&L) == NULL;
  free(text);
  return ok;
}

/* MVM as REFERENCE.md describes it. */
static int read_mvm(const char *path, rmesh *r) {
  memset(r, 0, sizeof *r);
  char *text = slurp(path, NULL);
  if (!text) return 0;
  lexer L = {text, {0}};
  int ok = expect_words(&L, "MIXED") && read_count(&L, &r->nnodes) &&
           read_count(&L, &r->ncells);
  ok = ok && read_nodes(&L, r, 0);
  ok = ok && read_letter_cells(&L, r, 0);
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

/* The formats under test: writer, the reader of this file, extension. */
typedef int (*writer_fn)(const char *path, const mx_mesh_view *m);
typedef int (*rreader_fn)(const char *path, rmesh *r);
enum { F_GETFEM, F_M3D, F_MVM, NFORMATS };
static const struct {
  const char *ext;
  writer_fn write;
  rreader_fn read;
} formats[NFORMATS] = {{".getfem", mx_write_getfem, read_getfem},
                       {".m3d", mx_write_m3d, read_m3d},
                       {".mvm", mx_write_mvm, read_mvm}};

/* out = OUT_DIR/<stem><extension of format f>. */
static void path_fmt(char *out, size_t cap, const char *stem, int f) {
  char name[128];
  snprintf(name, sizeof name, "%s%s", stem, formats[f].ext);
  path_in(out, cap, name);
}

/* Equal to the 9 significant digits "%+1.8E" keeps. */
static int close_to(double got, double want) {
  return fabs(got - want) <= 1e-8 * fabs(want);
}

static void test_reference_m3d(void) {
  for (int f = F_M3D; f <= F_MVM; f++)
    for (int type = 0; type < 4; type++) {
      tmesh t;
      reference_mesh(&t, type);
      char path[256];
      path_fmt(path, sizeof path, "ref", f);
      CHECK(formats[f].write(path, &t.v) == MX_OK);
      rmesh r;
      int ok = formats[f].read(path, &r);
      CHECK(ok);
      if (ok) {
        const int k = mx_cell_nodes[type];
        CHECK(r.nnodes == (size_t)k && r.ncells == 1 && r.nper[0] == k);
        double p[8][3];
        for (int i = 0; i < k; i++)
          for (int a = 0; a < 3; a++) p[i][a] = r.xyz[3 * r.conn[i] + a];
        const double vol = vtk_volume(k, (const double(*)[3])p);
        const double want = ref_volume_vtk[type] * detA();
        printf("%-4s   %d nodes          volume %.15g (expected %.15g)\n",
               formats[f].ext + 1, k, vol, want);
        /* 9 digits of coordinates near 1e3: about 1e-6 of the volume */
        CHECK(vol > 0.0 && fabs(vol - want) < 1e-5 * want);
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

/* r (read by this file's readers) against t, cells in the order `order`
 * (NULL: index order). GetFEM: coordinates bit for bit, rows in GetFEM's
 * node order; M3D and MVM: coordinates to 9 digits, rows as stored. */
static void check_round_trip(const tmesh *t, const uint32_t *order, const rmesh *r, int f) {
  /* GetFEM's node k is VTK's node gorder[k] (independent restatement) */
  static const int gorder[4][8] = {{0, 1, 2, 3}, {0, 1, 3, 2, 4}, {0, 1, 2, 3, 4, 5},
                                   {0, 1, 3, 2, 4, 5, 7, 6}};
  CHECK(r->nnodes == t->nnodes && r->ncells == t->ncells);
  if (r->nnodes != t->nnodes || r->ncells != t->ncells) return;
  if (f == F_GETFEM) {
    CHECK(memcmp(r->xyz, t->xyz, 3 * t->nnodes * sizeof(double)) == 0);
  } else {
    size_t bad = 0;
    for (size_t i = 0; i < 3 * t->nnodes; i++) bad += !close_to(r->xyz[i], t->xyz[i]);
    CHECK(bad == 0);
  }
  for (size_t k = 0; k < t->ncells; k++) {
    const size_t c = order ? order[k] : k;
    const int type = t->type[c], n = mx_cell_nodes[type];
    CHECK(r->nper[k] == n);
    for (int j = 0; j < n && r->nper[k] == n; j++) {
      const uint32_t want = t->conn[8 * c + (f == F_GETFEM ? gorder[type][j] : j)];
      CHECK(r->conn[8 * k + j] == want);
    }
  }
}

static void test_small_round_trip(void) {
  tmesh t;
  small_mesh(&t);
  char path[256];
  rmesh r;
  path_fmt(path, sizeof path, "small", F_GETFEM);
  CHECK(mx_write_getfem(path, &t.v) == MX_OK);
  CHECK(read_getfem(path, &r));
  check_round_trip(&t, NULL, &r, F_GETFEM);
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
  for (int f = F_M3D; f <= F_MVM; f++) {
    path_fmt(path, sizeof path, "small", f);
    CHECK(formats[f].write(path, &t.v) == MX_OK);
    CHECK(formats[f].read(path, &r));
    check_round_trip(&t, NULL, &r, f);
    for (size_t c = 0; c < r.ncells && r.ncells == t.ncells; c++) {
      double p[8][3];
      for (int i = 0; i < r.nper[c]; i++)
        for (int a = 0; a < 3; a++) p[i][a] = r.xyz[3 * r.conn[8 * c + i] + a];
      CHECK(vtk_volume(r.nper[c], (const double(*)[3])p) > 0.0);
    }
    rmesh_free(&r);
  }
  CHECK(count_entries(OUT_DIR, "small") == NFORMATS); /* no temporaries left */
  /* empty mesh: valid files with no points and no convexes */
  tmesh e;
  tmesh_alloc(&e, 0, 0);
  for (int f = 0; f < NFORMATS; f++) {
    path_fmt(path, sizeof path, "empty", f);
    CHECK(formats[f].write(path, &e.v) == MX_OK);
    CHECK(formats[f].read(path, &r) && r.nnodes == 0 && r.ncells == 0);
    rmesh_free(&r);
  }
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
  for (int f = 0; f < NFORMATS; f++) {
    char *first = NULL;
    size_t first_len = 0;
    for (int th = 1; th <= 3; th++) {
      omp_set_num_threads(th);
      char path[256];
      path_fmt(path, sizeof path, "grid", f);
      CHECK(formats[f].write(path, &t.v) == MX_OK);
      size_t len;
      char *bytes = slurp(path, &len);
      CHECK(bytes != NULL);
      if (th == 1) {
        first = bytes;
        first_len = len;
        rmesh r;
        CHECK(formats[f].read(path, &r));
        check_round_trip(&t, NULL, &r, f);
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
    for (int f = 0; f < NFORMATS; f++) CHECK(formats[f].write("/dev/full", &t.v) == MX_EIO);
    CHECK(dev_full_intact());
  }
  char path[256];
  for (int f = 0; f < NFORMATS; f++) {
    path_fmt(path, sizeof path, "no/such/dir/x", f);
    CHECK(formats[f].write(path, &t.v) == MX_EIO);
  }
  CHECK(count_entries(OUT_DIR, "no") == 0);
  /* a bad node index is refused before any file is created */
  t.conn[8 * 3 + 2] = 99;
  for (int f = 0; f < NFORMATS; f++) {
    path_fmt(path, sizeof path, "bad", f);
    CHECK(formats[f].write(path, &t.v) == MX_EINTERNAL);
  }
  CHECK(count_entries(OUT_DIR, "bad") == 0);
  tmesh_free(&t);
}

/* ====================================================================== */
/* The documented layouts, line by line                                    */
/* ====================================================================== */

/* One element of each type (hexahedron, prism, pyramid, tetrahedron, in
 * that order) on 12 nodes with coordinates whose "%+1.8E" forms are known. */
static void tiny_mesh(tmesh *t) {
  static const double xyz[12][3] = {
      {0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1},
      {1, 1, 1}, {0, 1, 1}, {2, 0, 1e-300}, {2, 0, 1},
      {0.5, 0.5, 1.0 + 2.0 / 3.0}, {-2.5e-7, 0.1, 123456789.123}};
  tmesh_alloc(t, 12, 4);
  memcpy(t->xyz, xyz, sizeof xyz);
  static const uint32_t hex[8] = {0, 1, 2, 3, 4, 5, 6, 7};
  static const uint32_t prism[6] = {1, 8, 2, 5, 9, 6};
  static const uint32_t pyr[5] = {4, 5, 6, 7, 10};
  static const uint32_t tet[4] = {5, 9, 6, 11};
  set_cell(t, 0, MX_HEX, hex);
  set_cell(t, 1, MX_PRISM, prism);
  set_cell(t, 2, MX_PYRAMID, pyr);
  set_cell(t, 3, MX_TET, tet);
}

/* The coordinates of tiny_mesh as "%+1.8E" writes them. */
static const char *const tiny_xyz[12] = {
    "+0.00000000E+00 +0.00000000E+00 +0.00000000E+00",
    "+1.00000000E+00 +0.00000000E+00 +0.00000000E+00",
    "+1.00000000E+00 +1.00000000E+00 +0.00000000E+00",
    "+0.00000000E+00 +1.00000000E+00 +0.00000000E+00",
    "+0.00000000E+00 +0.00000000E+00 +1.00000000E+00",
    "+1.00000000E+00 +0.00000000E+00 +1.00000000E+00",
    "+1.00000000E+00 +1.00000000E+00 +1.00000000E+00",
    "+0.00000000E+00 +1.00000000E+00 +1.00000000E+00",
    "+2.00000000E+00 +0.00000000E+00 +1.00000000E-300",
    "+2.00000000E+00 +0.00000000E+00 +1.00000000E+00",
    "+5.00000000E-01 +5.00000000E-01 +1.66666667E+00",
    "-2.50000000E-07 +1.00000000E-01 +1.23456789E+08"};

/* Its elements, by type letter and 0-based indices. */
static const char *const tiny_cells[4] = {"H 0 1 2 3 4 5 6 7", "R 1 8 2 5 9 6",
                                          "P 4 5 6 7 10", "T 5 9 6 11"};

/* Compares the file at path with want line by line; prints the first
 * difference. */
static void check_lines(const char *path, const char *want) {
  char *got = slurp(path, NULL);
  CHECK(got != NULL);
  if (!got) return;
  const char *g = got, *w = want;
  for (int line = 1; *g || *w; line++) {
    const size_t gl = strcspn(g, "\n"), wl = strcspn(w, "\n");
    if (gl != wl || memcmp(g, w, gl) != 0 || (g[gl] == '\n') != (w[wl] == '\n')) {
      fprintf(stderr, "%s:%d: got '%.*s', expected '%.*s'\n", path, line, (int)gl, g,
              (int)wl, w);
      CHECK(0);
      break;
    }
    g += gl + (g[gl] == '\n');
    w += wl + (w[wl] == '\n');
  }
  free(got);
}

/* Appends to a growing text (exits when out of memory). */
static void cat(char **text, const char *part) {
  const size_t n = *text ? strlen(*text) : 0;
  char *t = realloc(*text, n + strlen(part) + 1);
  if (!t) exit(2);
  strcpy(t + n, part);
  *text = t;
}

static void test_layouts(void) {
  tmesh t;
  tiny_mesh(&t);
  char path[256], line[256];
  /* M3D */
  char *want = NULL;
  cat(&want, "[Nodes, ARRAY1<STRING>]\n12\n\n");
  for (int i = 0; i < 12; i++) {
    snprintf(line, sizeof line, "1 %s\n", tiny_xyz[i]);
    cat(&want, line);
  }
  cat(&want, "\n[Elements, ARRAY1<STRING>]\n4\n\n");
  for (int c = 0; c < 4; c++) {
    snprintf(line, sizeof line, "%s 1000.0 0.45 1.0\n", tiny_cells[c]);
    cat(&want, line);
  }
  path_fmt(path, sizeof path, "tiny", F_M3D);
  CHECK(mx_write_m3d(path, &t.v) == MX_OK);
  check_lines(path, want);
  free(want);
  /* MVM */
  want = NULL;
  cat(&want, "MIXED\n12 4\n\n");
  for (int i = 0; i < 12; i++) {
    snprintf(line, sizeof line, "%s\n", tiny_xyz[i]);
    cat(&want, line);
  }
  for (int c = 0; c < 4; c++) {
    snprintf(line, sizeof line, "%s\n", tiny_cells[c]);
    cat(&want, line);
  }
  path_fmt(path, sizeof path, "tiny", F_MVM);
  CHECK(mx_write_mvm(path, &t.v) == MX_OK);
  check_lines(path, want);
  free(want);
  /* through the dispatch, by extension */
  path_in(path, sizeof path, "tiny_dispatch.mvm");
  CHECK(mx_mesh_format_known(path) && mx_write_mesh(path, &t.v, 0) == MX_OK);
  char other[256];
  path_fmt(other, sizeof other, "tiny", F_MVM);
  CHECK(files_equal(path, other));
  path_in(path, sizeof path, "tiny_dispatch.M3D");
  CHECK(mx_mesh_format_known(path) && mx_write_mesh(path, &t.v, 0) == MX_OK);
  path_fmt(other, sizeof other, "tiny", F_M3D);
  CHECK(files_equal(path, other));
  tmesh_free(&t);
}

/* A view with a written order: the k-th element line is cell order[k]. */
static void test_written_order(void) {
  tmesh t;
  tiny_mesh(&t);
  static const uint32_t order[4] = {2, 0, 3, 1};
  mx_mesh_view v = t.v;
  v.order = order;
  for (int f = 0; f < NFORMATS; f++) {
    char path[256];
    path_fmt(path, sizeof path, "ordered", f);
    CHECK(formats[f].write(path, &v) == MX_OK);
    rmesh r;
    CHECK(formats[f].read(path, &r));
    check_round_trip(&t, order, &r, f);
    rmesh_free(&r);
  }
  /* the lines themselves */
  char path[256];
  path_fmt(path, sizeof path, "ordered", F_MVM);
  char *want = NULL, line[256];
  cat(&want, "MIXED\n12 4\n\n");
  for (int i = 0; i < 12; i++) {
    snprintf(line, sizeof line, "%s\n", tiny_xyz[i]);
    cat(&want, line);
  }
  for (int k = 0; k < 4; k++) {
    snprintf(line, sizeof line, "%s\n", tiny_cells[order[k]]);
    cat(&want, line);
  }
  check_lines(path, want);
  free(want);
  tmesh_free(&t);
}

/* ====================================================================== */
/* mx_read_mesh                                                           */
/* ====================================================================== */

static char last_msg[2048];
static int nmsg;

static void keep_message(void *user, int level, const char *text) {
  (void)user;
  (void)level;
  snprintf(last_msg, sizeof last_msg, "%s", text);
  nmsg++;
}

/* Messages go to last_msg while on. */
static void capture_messages(int on) {
  mx_msg_fn = on ? keep_message : NULL;
  last_msg[0] = '\0';
  nmsg = 0;
}

/* m against t (cells in the order `order`, NULL: index order); coordinates
 * bit for bit when exact, else to 9 digits. */
static void check_data(const mx_mesh_data *m, const tmesh *t, const uint32_t *order, int exact) {
  CHECK(m->nnodes == t->nnodes && m->ncells == t->ncells);
  if (m->nnodes != t->nnodes || m->ncells != t->ncells) return;
  size_t bad = 0;
  for (size_t i = 0; i < 3 * t->nnodes; i++)
    bad += exact ? memcmp(&m->xyz[i], &t->xyz[i], sizeof(double)) != 0
                 : !close_to(m->xyz[i], t->xyz[i]);
  CHECK(bad == 0);
  bad = 0;
  for (size_t k = 0; k < t->ncells; k++) {
    const size_t c = order ? order[k] : k;
    bad += m->type[k] != t->type[c];
    for (int j = 0; j < 8; j++)
      bad += m->conn[8 * k + j] != (j < mx_cell_nodes[t->type[c]] ? t->conn[8 * c + j] : 0);
  }
  CHECK(bad == 0);
}

/* Writes t (in the order `order`) in every format and reads it back with
 * mx_read_mesh. */
static void read_back_all(const tmesh *t, const uint32_t *order, const char *stem) {
  mx_mesh_view v = t->v;
  v.order = order;
  for (int f = 0; f < NFORMATS; f++) {
    char path[256];
    path_fmt(path, sizeof path, stem, f);
    CHECK(formats[f].write(path, &v) == MX_OK);
    mx_mesh_data m;
    const int st = mx_read_mesh(path, &m);
    if (st != MX_OK) fprintf(stderr, "%s: %s\n", path, last_msg);
    CHECK(st == MX_OK);
    if (st == MX_OK) check_data(&m, t, order, f == F_GETFEM);
    mx_mesh_data_free(&m);
  }
}

static void test_read_round_trips(void) {
  capture_messages(1);
  tmesh t;
  small_mesh(&t);
  read_back_all(&t, NULL, "rb_small");
  tmesh_free(&t);
  tiny_mesh(&t);
  static const uint32_t order[4] = {3, 1, 2, 0};
  read_back_all(&t, order, "rb_tiny");
  tmesh_free(&t);
  grid_mesh(&t, 10);
  read_back_all(&t, NULL, "rb_grid");
  tmesh_free(&t);
  tmesh_alloc(&t, 0, 0);
  read_back_all(&t, NULL, "rb_empty");
  tmesh_free(&t);
  capture_messages(0);
}

/* Writes text to OUT_DIR/name and reads it: MX_OK expected; returns the
 * mesh (free it). */
static mx_mesh_data read_text_ok(const char *name, const char *text) {
  char path[256];
  path_in(path, sizeof path, name);
  write_bytes_file(path, text, strlen(text));
  capture_messages(1);
  mx_mesh_data m;
  const int st = mx_read_mesh(path, &m);
  if (st != MX_OK) fprintf(stderr, "%s: %s\n", name, last_msg);
  CHECK(st == MX_OK);
  capture_messages(0);
  return m;
}

/* The layout mixoct wrote before, and GetFEM files as GetFEM writes them
 * (counts, a region after the mesh). */
static void test_read_other_layouts(void) {
  mx_mesh_data m = read_text_ok("older.m3d",
                                "[Nodes, ARRAY1<POINT3D>]\n5\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n"
                                "0.5 0.5 1\n\n[Elements, ARRAY1<STRING>]\n2\n5 0 1 2 3 4\n"
                                "4 0 1 3 4\n");
  static const uint32_t pyr[8] = {0, 1, 2, 3, 4, 0, 0, 0}, tet[8] = {0, 1, 3, 4, 0, 0, 0, 0};
  CHECK(m.nnodes == 5 && m.ncells == 2);
  if (m.ncells == 2) {
    CHECK(m.type[0] == MX_PYRAMID && m.type[1] == MX_TET);
    CHECK(memcmp(m.conn, pyr, sizeof pyr) == 0 && memcmp(m.conn + 8, tet, sizeof tet) == 0);
    CHECK(m.xyz[3 * 4 + 0] == 0.5 && m.xyz[3 * 4 + 2] == 1.0);
  }
  mx_mesh_data_free(&m);
  m = read_text_ok("gf.getfem",
                   "% GETFEM MESH FILE\n% GETFEM VERSION 5.4\n\n\n\nBEGIN POINTS LIST\n\n"
                   "  POINT COUNT 5\n  POINT  0  0  0  0\n  POINT  1  1  0  0\n"
                   "  POINT  2  0  1  0\n  POINT  3  1  1  0\n  POINT  4  0.5  0.5  1\n\n"
                   "END POINTS LIST\n\n\n\nBEGIN MESH STRUCTURE DESCRIPTION\n\n"
                   "CONVEX COUNT 1\n  CONVEX 0    'GT_PYRAMID(1)'      0  1  2  3  4\n\n"
                   "END MESH STRUCTURE DESCRIPTION\nBEGIN REGION 1\n0/0\nEND REGION 1\n");
  /* GetFEM's pyramid base 0 1 2 3 is tensor-ordered: ours is 0 1 3 2 */
  static const uint32_t gpyr[8] = {0, 1, 3, 2, 4, 0, 0, 0};
  CHECK(m.nnodes == 5 && m.ncells == 1);
  if (m.ncells == 1) CHECK(m.type[0] == MX_PYRAMID && memcmp(m.conn, gpyr, sizeof gpyr) == 0);
  mx_mesh_data_free(&m);
}

/* Writes len bytes to OUT_DIR/name and reads them: refused with MX_EINPUT,
 * an empty result and one message naming the file (and "FILE:line:" when
 * line > 0; containing `words` when not NULL). */
static void expect_refused_bytes(const char *name, const char *text, size_t len, long line,
                                 const char *words) {
  char path[256], prefix[300];
  path_in(path, sizeof path, name);
  write_bytes_file(path, text, len);
  capture_messages(1);
  mx_mesh_data m;
  const int st = mx_read_mesh(path, &m);
  printf("%-22s -> %s\n", name, last_msg);
  CHECK(st == MX_EINPUT);
  CHECK(m.nnodes == 0 && m.ncells == 0 && !m.xyz && !m.type && !m.conn);
  CHECK(nmsg == 1 && strncmp(last_msg, path, strlen(path)) == 0);
  if (line > 0) {
    snprintf(prefix, sizeof prefix, "%s:%ld: ", path, line);
    CHECK(strncmp(last_msg, prefix, strlen(prefix)) == 0);
  }
  if (words) CHECK(strstr(last_msg, words) != NULL);
  if (st != MX_EINPUT || (words && !strstr(last_msg, words)))
    fprintf(stderr, "%s: status %d, message '%s'\n", name, st, last_msg);
  capture_messages(0);
  mx_mesh_data_free(&m);
}

static void expect_refused(const char *name, const char *text, long line, const char *words) {
  expect_refused_bytes(name, text, strlen(text), line, words);
}

/* The tiny mesh written in format f, as text (free it). */
static char *tiny_text(int f) {
  tmesh t;
  tiny_mesh(&t);
  char path[256];
  path_fmt(path, sizeof path, "tiny_src", f);
  CHECK(formats[f].write(path, &t.v) == MX_OK);
  tmesh_free(&t);
  char *text = slurp(path, NULL);
  if (!text) exit(2);
  return text;
}

/* Refusals of text with line `line` replaced by repl. */
static void refused_edit(const char *name, const char *text, int line, const char *repl,
                         long want_line, const char *words) {
  char *e = text_edit_line(text, line, repl);
  expect_refused(name, e, want_line, words);
  free(e);
}

static void test_malformed_m3d(void) {
  char *m3d = tiny_text(F_M3D); /* lines 4-15 nodes, 20-23 elements */
  char *half = strdup(m3d);
  half[strlen(half) / 2] = '\0';
  expect_refused("trunc.m3d", half, 0, "truncated");
  free(half);
  refused_edit("big_nodes.m3d", m3d, 2, "1000000", 2, "too short");
  refused_edit("big_cells.m3d", m3d, 18, "99999999999999", 18, "too short");
  refused_edit("cells_more.m3d", m3d, 18, "5", 0, "truncated");
  refused_edit("index.m3d", m3d, 23, "T 5 9 6 12 1000.0 0.45 1.0", 23, "out of range");
  refused_edit("negative.m3d", m3d, 22, "P 4 5 6 -7 10 1000.0 0.45 1.0", 22, "out of range");
  refused_edit("word.m3d", m3d, 5, "1 +1.0E+00 abc +0.0E+00", 5, "not a number");
  refused_edit("nan.m3d", m3d, 6, "1 nan 0 0", 6, "finite");
  refused_edit("letter.m3d", m3d, 21, "Q 1 8 2 5 9 6 1000.0 0.45 1.0", 21, "element type");
  refused_edit("short_row.m3d", m3d, 20, "H 0 1 2 3 4 5 6 1000.0 0.45 1.0", 20, NULL);
  refused_edit("header.m3d", m3d, 1, "[Nodes, ARRAY1<FLOAT>]", 1, "ARRAY1<STRING>");
  refused_edit("elements.m3d", m3d, 17, "[Cells, ARRAY1<STRING>]", 17, "[Elements,");
  char *more = NULL;
  cat(&more, m3d);
  cat(&more, "T 0 1 2 3 1000.0 0.45 1.0\n");
  expect_refused("extra.m3d", more, 24, "after the last element");
  free(more);
  char *nul = strdup(m3d);
  nul[strstr(nul, "R 1") - nul + 2] = '\0';
  expect_refused_bytes("nul.m3d", nul, strlen(m3d), 21, NULL);
  free(nul);
  expect_refused("empty.m3d", "", 0, NULL);
  expect_refused("blank.m3d", "\n\n  \n", 0, NULL);
  /* the older layout's checks */
  expect_refused("older_k.m3d",
                 "[Nodes, ARRAY1<POINT3D>]\n4\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n\n"
                 "[Elements, ARRAY1<STRING>]\n1\n7 0 1 2 3\n",
                 10, "node count");
  free(m3d);
}

static void test_malformed_mvm(void) {
  char *mvm = tiny_text(F_MVM); /* lines 4-15 nodes, 16-19 elements */
  char *half = strdup(mvm);
  half[strlen(half) / 2] = '\0';
  expect_refused("trunc.mvm", half, 0, "truncated");
  free(half);
  refused_edit("big_nodes.mvm", mvm, 2, "100000000 4", 2, "too short");
  refused_edit("big_cells.mvm", mvm, 2, "12 100000000", 2, "too short");
  refused_edit("index.mvm", mvm, 19, "T 5 9 6 12", 19, "out of range");
  refused_edit("word.mvm", mvm, 7, "1 two 3", 7, "not a number");
  refused_edit("int.mvm", mvm, 17, "R 1 8 2 5 9 x6", 17, "not an integer");
  refused_edit("magic.mvm", mvm, 1, "MIXTE", 1, "MIXED");
  refused_edit("tail.mvm", mvm, 16, "H 0 1 2 3 4 5 6 7 1000.0 0.45 1.0", 0, NULL);
  expect_refused("empty.mvm", "", 0, NULL);
  expect_refused("blank.mvm", "\n \n", 0, "MIXED");
  free(mvm);
}

static void test_malformed_getfem(void) {
  char *gf = tiny_text(F_GETFEM);
  char *cut = strdup(gf);
  *strstr(cut, "END MESH") = '\0';
  expect_refused("unended.getfem", cut, 0, "truncated");
  free(cut);
  cut = strdup(gf);
  *strstr(cut, "  POINT  7") = '\0';
  expect_refused("trunc.getfem", cut, 0, "truncated");
  free(cut);
  /* the point and convex lines: 7-18 and 26-29 */
  refused_edit("number.getfem", gf, 9, "  POINT  5  0  0  0", 9, "in order");
  refused_edit("word.getfem", gf, 10, "  POINT  3  0  zero  0", 10, "not a number");
  refused_edit("index.getfem", gf, 29, "  CONVEX 3    'GT_PK(3,1)'       5 9 6 12", 29,
               "out of range");
  refused_edit("gt.getfem", gf, 28, "  CONVEX 2    'GT_PK(2,1)'       4 5 6", 28,
               "geometric transformation");
  refused_edit("begin.getfem", gf, 5, "BEGIN POINT LIST", 5, "BEGIN POINTS LIST");
  expect_refused("empty.getfem", "", 0, NULL);
  expect_refused("comments.getfem", "% GETFEM MESH FILE\n", 0, "BEGIN POINTS LIST");
  free(gf);
}

/* Every prefix, and random byte changes, of a valid file of each format:
 * MX_OK with indices in range, or MX_EINPUT; never anything else. */
static void test_damage(void) {
  capture_messages(1);
  uint64_t s = 0x2545F4914F6CDD1Dull;
  size_t refused = 0, read = 0;
  for (int f = 0; f < NFORMATS; f++) {
    char *text = tiny_text(f), path[256];
    const size_t len = strlen(text);
    path_fmt(path, sizeof path, "damaged", f);
    for (size_t trial = 0; trial < len + 400; trial++) {
      char *d = malloc(len + 1);
      memcpy(d, text, len + 1);
      size_t n = len;
      if (trial < len) {
        n = trial;
      } else {
        static const char bytes[] = "0123456789-+.eE \n\tTPRHx[]%'\0";
        for (int k = 0; k < 3; k++) {
          s ^= s << 13;
          s ^= s >> 7;
          s ^= s << 17;
          d[s % len] = bytes[(s >> 32) % (sizeof bytes - 1)];
        }
      }
      write_bytes_file(path, d, n);
      free(d);
      mx_mesh_data m;
      const int st = mx_read_mesh(path, &m);
      CHECK(st == MX_OK || st == MX_EINPUT);
      if (st == MX_OK) {
        read++;
        for (size_t c = 0; c < m.ncells; c++) {
          CHECK(m.type[c] <= MX_HEX);
          for (int j = 0; j < mx_cell_nodes[m.type[c]]; j++) CHECK(m.conn[8 * c + j] < m.nnodes);
        }
        for (size_t i = 0; i < 3 * m.nnodes; i++) CHECK(isfinite(m.xyz[i]));
      } else {
        refused++;
        CHECK(nmsg > 0);
      }
      nmsg = 0;
      mx_mesh_data_free(&m);
    }
    free(text);
  }
  printf("damaged files: %zu read, %zu refused\n", read, refused);
  capture_messages(0);
}

/* ====================================================================== */
/* The program                                                            */
/* ====================================================================== */

static char mixoct[4096];

static int run(const char *cmd) {
  const int st = system(cmd);
  return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}

/* `mixoct check` on the .mvm, .m3d and .getfem files of `mixoct --demo`. */
static void test_program(void) {
  if (access(mixoct, X_OK) != 0) {
    fprintf(stderr, "%s not found: build it first\n", mixoct);
    CHECK(0);
    return;
  }
  for (int f = 0; f < NFORMATS; f++) {
    char path[256], log[256], cmd[8192];
    path_fmt(path, sizeof path, "demo", f);
    path_in(log, sizeof log, "demo.log");
    snprintf(cmd, sizeof cmd, "'%s' --demo -s 3 -o '%s' --quiet > '%s' 2>&1", mixoct, path, log);
    const int made = run(cmd);
    CHECK(made == 0);
    snprintf(cmd, sizeof cmd, "'%s' check '%s' >> '%s' 2>&1", mixoct, path, log);
    const int checked = run(cmd);
    printf("mixoct --demo -s 3 -o %s: exit %d; mixoct check: exit %d\n", path, made, checked);
    CHECK(checked == 0);
    if (made || checked) {
      char *text = slurp(log, NULL);
      fprintf(stderr, "%s\n", text ? text : "(no log)");
      free(text);
    }
  }
}

int main(int argc, char **argv) {
  (void)argc;
  mkdir(OUT_DIR, 0755);
  remove_dir_files(OUT_DIR); /* the entry counts below need a clean folder */
  /* The program sits next to the tests directory of the build. */
  const char *slash = strrchr(argv[0], '/');
  if (slash)
    snprintf(mixoct, sizeof mixoct, "%.*s/../mixoct", (int)(slash - argv[0]), argv[0]);
  else
    snprintf(mixoct, sizeof mixoct, "../mixoct");
  test_reference_getfem();
  test_reference_m3d();
  test_small_round_trip();
  test_threads();
  test_failures();
  test_layouts();
  test_written_order();
  test_read_round_trips();
  test_read_other_layouts();
  test_malformed_m3d();
  test_malformed_mvm();
  test_malformed_getfem();
  test_damage();
  test_program();
  return TEST_DONE();
}
