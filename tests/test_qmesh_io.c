/* Tests of the 2D mesh writers (io/write_mesh.h, through
 * mesher/qmesh_output.c) and of the independent 2D mesh check
 * (src/quad/qcheck.c).
 *
 * The mesh: the rectangle [0,2] x [0,1], its left half one quadrant cut
 * into the 3 triangles of the one-mid-node transition (the mid-node (1,0.5)
 * of its right edge), its right half 4 quadrants of half the size:
 *
 *    7-------8---9---10        11 nodes, 7 cells (3 triangles, 4 quads),
 *    | \  T1 |Q5 |Q6 |         17 edges (V - E + F = 1), 9 of them on the
 *    |T2 \   4---5---6         boundary (3 bottom, 2 right, 3 top, 1 left),
 *    |    /  |Q3 |Q4 |         area 2.
 *    | /  T0 |   |   |
 *    0-------1---2---3
 *
 * It is written in every format and read back by small readers written
 * here from the formats' documentation (legacy VTK ASCII and binary, Gmsh
 * MSH 4.1 ASCII and the binary $Nodes, the VTU header and appended blocks,
 * OFF, GetFEM, M3D). A larger structured mesh (squares, every other one cut
 * in two triangles) checks the boundary line count 4n, the same bytes for 1
 * and 3 threads, and the check on a mesh with tens of thousands of cells.
 * mx_qmesh_check must pass the mesh and catch, each in its counter, a
 * flipped cell, a duplicated cell, a hanging node and a missing cell. */
#include <math.h>
#include <omp.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "base/common.h"
#include "quad/quad.h"

#define OUT_DIR "qmesh_io_out"
#include "file_util.h"
#include "mesher/qmesh_output.h"

/* ---- the meshes ----------------------------------------------------------- */

enum { NN = 11, NC = 7, NBOUND = 9 };
static const double node_xy[NN][2] = {{0, 0}, {1, 0},   {1.5, 0},   {2, 0}, {1, 0.5}, {1.5, 0.5},
                                      {2, 0.5}, {0, 1}, {1, 1}, {1.5, 1}, {2, 1}};
static const int cell_nv[NC] = {3, 3, 3, 4, 4, 4, 4};
static const uint32_t cell_nodes[NC][4] = {{0, 1, 4, 0},  {4, 8, 7, 0},  {0, 4, 7, 0},
                                           {1, 2, 5, 4},  {2, 3, 6, 5},  {4, 5, 9, 8},
                                           {5, 6, 10, 9}};
/* The boundary edges, oriented as in their cell (the domain on the left). */
static const uint32_t bound_edges[NBOUND][2] = {{0, 1}, {1, 2}, {2, 3}, {3, 6}, {6, 10},
                                                {10, 9}, {9, 8}, {8, 7}, {7, 0}};

static void qmesh_alloc(mx_qmesh *M, size_t nn, size_t nc) {
  memset(M, 0, sizeof *M);
  M->nnodes = nn;
  M->ncells = nc;
  M->xy = mx_calloc((2 * nn + 1) * sizeof *M->xy);
  M->nkey = mx_calloc((nn + 1) * sizeof *M->nkey);
  M->type = mx_calloc(nc + 1);
  M->conn = mx_calloc((4 * nc + 1) * sizeof *M->conn);
  M->leaf = mx_calloc((nc + 1) * sizeof *M->leaf);
  M->level = mx_calloc(nc + 1);
  if (!M->xy || !M->nkey || !M->type || !M->conn || !M->leaf || !M->level) exit(2);
}

static void qset(mx_qmesh *M, size_t c, int nv, const uint32_t *v, int level) {
  M->type[c] = nv == 4 ? MX_QQUAD : MX_QTRI;
  for (int j = 0; j < 4; j++) M->conn[4 * c + j] = j < nv ? v[j] : UINT32_MAX;
  M->level[c] = (uint8_t)level;
}

/* The hand-built mesh, with room for `extra` more nodes and cells (nnodes
 * and ncells stay 11 and 7). */
static void small_mesh(mx_qmesh *M, size_t extra) {
  qmesh_alloc(M, NN + extra, NC + extra);
  M->nnodes = NN;
  M->ncells = NC;
  memcpy(M->xy, node_xy, sizeof node_xy);
  for (size_t c = 0; c < NC; c++) qset(M, c, cell_nv[c], cell_nodes[c], cell_nv[c] == 4);
}

/* n x n unit squares; square (i, j) with i + j odd is cut along its
 * diagonal into two counter-clockwise triangles. */
static void grid_mesh(mx_qmesh *M, uint32_t n) {
  size_t nc = 0;
  for (uint32_t j = 0; j < n; j++)
    for (uint32_t i = 0; i < n; i++) nc += (i + j) % 2 ? 2 : 1;
  qmesh_alloc(M, (size_t)(n + 1) * (n + 1), nc);
  for (uint32_t j = 0; j <= n; j++)
    for (uint32_t i = 0; i <= n; i++) {
      M->xy[2 * ((size_t)j * (n + 1) + i)] = i;
      M->xy[2 * ((size_t)j * (n + 1) + i) + 1] = j;
    }
  size_t c = 0;
  for (uint32_t j = 0; j < n; j++)
    for (uint32_t i = 0; i < n; i++) {
      const uint32_t a = j * (n + 1) + i, b = a + 1, d = a + n + 1, e = d + 1;
      if ((i + j) % 2 == 0) {
        qset(M, c++, 4, (const uint32_t[]){a, b, e, d}, 2);
      } else {
        qset(M, c++, 3, (const uint32_t[]){a, b, e}, 3);
        qset(M, c++, 3, (const uint32_t[]){a, e, d}, 3);
      }
    }
}

/* Square (i, j) of grid_mesh (a quad: i + j even) cut into 4 quads around
 * its centre, the neighbours left as they are. */
static void split_square(mx_qmesh *M, uint32_t n, uint32_t i, uint32_t j) {
  const uint32_t a = j * (n + 1) + i, b = a + 1, d = a + n + 1, e = d + 1;
  size_t c = 0;
  while (c < M->ncells && !(M->type[c] == MX_QQUAD && M->conn[4 * c] == a)) c++;
  CHECK(c < M->ncells);
  /* mid-edges m..m+3 (bottom, right, top, left), centre m+4 */
  const uint32_t m = (uint32_t)M->nnodes;
  M->xy = mx_realloc(M->xy, 2 * (M->nnodes + 5) * sizeof *M->xy);
  M->conn = mx_realloc(M->conn, 4 * (M->ncells + 3) * sizeof *M->conn);
  M->type = mx_realloc(M->type, M->ncells + 3);
  M->level = mx_realloc(M->level, M->ncells + 3);
  if (!M->xy || !M->conn || !M->type || !M->level) exit(2);
  const double x = i, y = j, p[5][2] = {{x + .5, y}, {x + 1, y + .5}, {x + .5, y + 1}, {x, y + .5},
                                        {x + .5, y + .5}};
  memcpy(M->xy + 2 * M->nnodes, p, sizeof p);
  M->nnodes += 5;
  qset(M, c, 4, (const uint32_t[]){a, m, m + 4, m + 3}, 3);
  qset(M, M->ncells, 4, (const uint32_t[]){m, b, m + 1, m + 4}, 3);
  qset(M, M->ncells + 1, 4, (const uint32_t[]){m + 4, m + 1, e, m + 2}, 3);
  qset(M, M->ncells + 2, 4, (const uint32_t[]){m + 3, m + 4, m + 2, d}, 3);
  M->ncells += 3;
}

/* The rectangle [0,2] x [0,1], counter-clockwise (a checked domain). */
static void rect_domain(mx_poly *P) {
  memset(P, 0, sizeof *P);
  static const double xy[8] = {0, 0, 2, 0, 2, 1, 0, 1};
  P->nv = P->ns = 4;
  P->xy = mx_alloc(sizeof xy);
  P->seg = mx_alloc(8 * sizeof *P->seg);
  P->line = mx_calloc(4 * sizeof *P->line);
  if (!P->xy || !P->seg || !P->line) exit(2);
  memcpy(P->xy, xy, sizeof xy);
  for (uint32_t s = 0; s < 4; s++) P->seg[2 * s] = s, P->seg[2 * s + 1] = (s + 1) % 4;
  P->nloops = 1;
}

/* ---- token reading ---------------------------------------------------------- */

typedef struct {
  const char *p;
} toks;

/* The next blank-separated token into buf ("" at the end). */
static const char *tok(toks *t, char *buf, size_t cap) {
  while (*t->p == ' ' || *t->p == '\n' || *t->p == '\t' || *t->p == '\r') t->p++;
  size_t n = 0;
  while (*t->p && *t->p != ' ' && *t->p != '\n' && *t->p != '\t' && *t->p != '\r') {
    if (n + 1 < cap) buf[n++] = *t->p;
    t->p++;
  }
  buf[n] = '\0';
  return buf;
}

static double num(toks *t) {
  char b[64];
  return strtod(tok(t, b, sizeof b), NULL);
}

static int is(toks *t, const char *word) {
  char b[128];
  return strcmp(tok(t, b, sizeof b), word) == 0;
}

static void path_of(char *out, const char *name) { snprintf(out, 512, "%s/%s", OUT_DIR, name); }

/* ---- legacy VTK -------------------------------------------------------------- */

static void read_vtk_ascii(const mx_qmesh *M) {
  char path[512];
  path_of(path, "small_ascii.vtk");
  char *text = slurp(path, NULL);
  CHECK(text != NULL);
  if (!text) return;
  CHECK(strncmp(text, "# vtk DataFile Version 3.0\n", 27) == 0);
  CHECK(strstr(text, "\nASCII\nDATASET UNSTRUCTURED_GRID\n") != NULL);
  toks t = {strstr(text, "POINTS")};
  CHECK(t.p && is(&t, "POINTS") && num(&t) == NN && is(&t, "double"));
  for (int i = 0; i < NN; i++) {
    CHECK(num(&t) == node_xy[i][0]);
    CHECK(num(&t) == node_xy[i][1]);
    CHECK(num(&t) == 0.0);
  }
  /* 7 cells, 7 counts + 3 x 3 + 4 x 4 indices */
  CHECK(is(&t, "CELLS") && num(&t) == NC && num(&t) == 32);
  for (int c = 0; c < NC; c++) {
    CHECK(num(&t) == cell_nv[c]);
    for (int j = 0; j < cell_nv[c]; j++) CHECK(num(&t) == cell_nodes[c][j]);
  }
  CHECK(is(&t, "CELL_TYPES") && num(&t) == NC);
  for (int c = 0; c < NC; c++) CHECK(num(&t) == (cell_nv[c] == 4 ? 9 : 5));
  CHECK(is(&t, "CELL_DATA") && num(&t) == NC);
  static const char *names[3] = {"type", "level", "sj"};
  for (int f = 0; f < 3; f++) {
    CHECK(is(&t, "SCALARS") && is(&t, names[f]) && is(&t, f == 2 ? "double" : "int"));
    CHECK(is(&t, "1") && is(&t, "LOOKUP_TABLE") && is(&t, "default"));
    for (int c = 0; c < NC; c++) {
      const double v = num(&t);
      const double want = f == 0 ? (cell_nv[c] == 4) : f == 1 ? M->level[c] : mx_qcell_sj(M, c);
      CHECK(v == want);
    }
  }
  char b[16];
  CHECK(tok(&t, b, sizeof b)[0] == '\0');
  free(text);
}

static uint32_t be32(const unsigned char *p) {
  return (uint32_t)p[0] << 24 | (uint32_t)p[1] << 16 | (uint32_t)p[2] << 8 | p[3];
}
static double be_double(const unsigned char *p) {
  uint64_t v = 0;
  for (int k = 0; k < 8; k++) v = v << 8 | p[k];
  double d;
  memcpy(&d, &v, 8);
  return d;
}

/* Binary: big-endian points, cells and types after their keywords. */
static void read_vtk_binary(void) {
  char path[512];
  path_of(path, "small_bin.vtk");
  size_t len = 0;
  char *text = slurp(path, &len);
  CHECK(text != NULL);
  if (!text) return;
  CHECK(strstr(text, "\nBINARY\n") != NULL);
  const char *h = strstr(text, "POINTS 11 double\n");
  CHECK(h != NULL);
  if (!h) return free(text);
  const unsigned char *p = (const unsigned char *)h + strlen("POINTS 11 double\n");
  for (int i = 0; i < NN; i++) {
    CHECK(be_double(p + 24 * i) == node_xy[i][0]);
    CHECK(be_double(p + 24 * i + 8) == node_xy[i][1]);
    CHECK(be_double(p + 24 * i + 16) == 0.0);
  }
  p += 24 * NN;
  CHECK(memcmp(p, "\nCELLS 7 32\n", 12) == 0);
  p += 12;
  for (int c = 0; c < NC; c++) {
    CHECK(be32(p) == (uint32_t)cell_nv[c]);
    for (int j = 0; j < cell_nv[c]; j++) CHECK(be32(p + 4 + 4 * j) == cell_nodes[c][j]);
    p += 4 + 4 * cell_nv[c];
  }
  CHECK(memcmp(p, "\nCELL_TYPES 7\n", 14) == 0);
  p += 14;
  for (int c = 0; c < NC; c++) CHECK(be32(p + 4 * c) == (cell_nv[c] == 4 ? 9u : 5u));
  p += 4 * NC;
  CHECK(memcmp(p, "\nCELL_DATA 7\n", 13) == 0);
  /* three fields: int, int, double, each with its two header lines and a
   * newline after the data */
  const size_t heads = strlen("SCALARS type int 1\nLOOKUP_TABLE default\n") +
                       strlen("SCALARS level int 1\nLOOKUP_TABLE default\n") +
                       strlen("SCALARS sj double 1\nLOOKUP_TABLE default\n");
  CHECK((const char *)p + 13 + heads + NC * (4 + 4 + 8) + 3 == text + len);
  free(text);
}

/* ---- MSH 4.1 ----------------------------------------------------------------- */

/* One element block's header; returns its count. */
static size_t msh_block(toks *t, int dim, int type) {
  CHECK(num(t) == dim && num(t) == 1 && num(t) == type);
  return (size_t)num(t);
}

static void read_msh_ascii(void) {
  char path[512];
  path_of(path, "small_ascii.msh");
  char *text = slurp(path, NULL);
  CHECK(text != NULL);
  if (!text) return;
  toks t = {text};
  CHECK(is(&t, "$MeshFormat") && is(&t, "4.1") && is(&t, "0") && is(&t, "8"));
  CHECK(is(&t, "$EndMeshFormat") && is(&t, "$PhysicalNames") && num(&t) == 2);
  CHECK(num(&t) == 2 && num(&t) == 1 && is(&t, "\"domain\""));
  CHECK(num(&t) == 1 && num(&t) == 2 && is(&t, "\"boundary\""));
  CHECK(is(&t, "$EndPhysicalNames") && is(&t, "$Entities"));
  CHECK(num(&t) == 0 && num(&t) == 1 && num(&t) == 1 && num(&t) == 0);
  /* curve then surface: tag, box (0 0 0 2 1 0), 1 physical tag, 0 bounds */
  for (int e = 0; e < 2; e++) {
    CHECK(num(&t) == 1);
    static const double box[6] = {0, 0, 0, 2, 1, 0};
    for (int k = 0; k < 6; k++) CHECK(num(&t) == box[k]);
    CHECK(num(&t) == 1 && num(&t) == (e == 0 ? 2 : 1) && num(&t) == 0);
  }
  CHECK(is(&t, "$EndEntities") && is(&t, "$Nodes"));
  CHECK(num(&t) == 1 && num(&t) == NN && num(&t) == 1 && num(&t) == NN);
  CHECK(num(&t) == 2 && num(&t) == 1 && num(&t) == 0 && num(&t) == NN);
  for (int i = 0; i < NN; i++) CHECK(num(&t) == i + 1);
  for (int i = 0; i < NN; i++)
    CHECK(num(&t) == node_xy[i][0] && num(&t) == node_xy[i][1] && num(&t) == 0);
  CHECK(is(&t, "$EndNodes") && is(&t, "$Elements"));
  /* 3 blocks: triangles, quads, lines; 7 cells + 9 lines */
  CHECK(num(&t) == 3 && num(&t) == NC + NBOUND && num(&t) == 1 && num(&t) == NC + NBOUND);
  for (int type = 2; type <= 3; type++) {
    CHECK(msh_block(&t, 2, type) == (type == 2 ? 3u : 4u));
    for (int c = 0; c < NC; c++) {
      if (cell_nv[c] != type + 1) continue;
      CHECK(num(&t) == c + 1);
      for (int j = 0; j < cell_nv[c]; j++) CHECK(num(&t) == cell_nodes[c][j] + 1);
    }
  }
  CHECK(msh_block(&t, 1, 1) == NBOUND);
  int seen[NBOUND] = {0};
  for (int i = 0; i < NBOUND; i++) {
    CHECK(num(&t) == NC + i + 1);
    const double a = num(&t) - 1, b = num(&t) - 1;
    for (int k = 0; k < NBOUND; k++) seen[k] += a == bound_edges[k][0] && b == bound_edges[k][1];
  }
  for (int k = 0; k < NBOUND; k++) CHECK(seen[k] == 1);
  CHECK(is(&t, "$EndElements"));
  /* three $ElementData, every element (a line carries its cell's value) */
  for (int f = 0; f < 3; f++) {
    CHECK(is(&t, "$ElementData") && num(&t) == 1);
    char b[32];
    tok(&t, b, sizeof b);
    CHECK(num(&t) == 1 && num(&t) == 0 && num(&t) == 3 && num(&t) == 0 && num(&t) == 1);
    CHECK(num(&t) == NC + NBOUND);
    for (int i = 0; i < 2 * (NC + NBOUND); i++) num(&t);
    CHECK(is(&t, "$EndElementData"));
  }
  char b[16];
  CHECK(tok(&t, b, sizeof b)[0] == '\0');
  free(text);
}

/* Binary: the byte-order int and the $Nodes section. */
static void read_msh_binary(void) {
  char path[512];
  path_of(path, "small_bin.msh");
  size_t len = 0;
  char *text = slurp(path, &len);
  CHECK(text != NULL);
  if (!text) return;
  CHECK(strncmp(text, "$MeshFormat\n4.1 1 8\n", 20) == 0);
  int32_t one;
  memcpy(&one, text + 20, 4);
  CHECK(one == 1);
  const char *p = memmem(text, len, "$Nodes\n", 7); /* binary before it */
  CHECK(p != NULL);
  if (!p) return free(text);
  p += 7;
  uint64_t head[4];
  memcpy(head, p, 32);
  CHECK(head[0] == 1 && head[1] == NN && head[2] == 1 && head[3] == NN);
  int32_t ent[3];
  memcpy(ent, p + 32, 12);
  CHECK(ent[0] == 2 && ent[1] == 1 && ent[2] == 0);
  uint64_t n;
  memcpy(&n, p + 44, 8);
  CHECK(n == NN);
  p += 52;
  for (uint64_t i = 0; i < NN; i++) {
    uint64_t tag;
    memcpy(&tag, p + 8 * i, 8);
    CHECK(tag == i + 1);
  }
  p += 8 * NN;
  for (int i = 0; i < NN; i++) {
    double c[3];
    memcpy(c, p + 24 * i, 24);
    CHECK(c[0] == node_xy[i][0] && c[1] == node_xy[i][1] && c[2] == 0);
  }
  CHECK(strncmp(p + 24 * NN, "\n$EndNodes\n$Elements\n", 21) == 0);
  free(text);
}

/* ---- VTU --------------------------------------------------------------------- */

static uint64_t le64(const unsigned char *p) {
  uint64_t v = 0;
  for (int k = 7; k >= 0; k--) v = v << 8 | p[k];
  return v;
}

static void read_vtu(void) {
  char path[512];
  path_of(path, "small.vtu");
  size_t len = 0;
  char *text = slurp(path, &len);
  CHECK(text != NULL);
  if (!text) return;
  CHECK(strstr(text, "<Piece NumberOfPoints=\"11\" NumberOfCells=\"7\">") != NULL);
  /* the blocks in DataArray order: type Int32, level UInt8, sj Float64,
   * points 3 x Float64, connectivity (25) and offsets Int32, types UInt8 */
  static const char *names[7] = {"type", "level", "sj", "Points", "connectivity", "offsets",
                                 "types"};
  static const uint64_t bytes[7] = {4 * NC, NC, 8 * NC, 24 * NN, 4 * 25, 4 * NC, NC};
  const char *start = strstr(text, "<AppendedData encoding=\"raw\">\n   _");
  CHECK(start != NULL);
  if (!start) return free(text);
  const unsigned char *base =
      (const unsigned char *)start + strlen("<AppendedData encoding=\"raw\">\n   _");
  uint64_t at = 0;
  for (int k = 0; k < 7; k++) {
    char attr[128];
    snprintf(attr, sizeof attr, "Name=\"%s\"", names[k]);
    const char *a = strstr(text, attr), *o = a ? strstr(a, "offset=\"") : NULL;
    CHECK(o != NULL);
    if (o) CHECK(strtoull(o + 8, NULL, 10) == at);
    CHECK(le64(base + at) == bytes[k]);
    if (k == 5) /* offsets: ends of the cells' connectivity */
      for (int c = 0, end = 0; c < NC; c++) {
        end += cell_nv[c];
        CHECK(le64(base + at + 8 + 4 * c) % (1ull << 32) == (uint64_t)end);
      }
    if (k == 6)
      for (int c = 0; c < NC; c++) CHECK(base[at + 8 + c] == (cell_nv[c] == 4 ? 9 : 5));
    at += 8 + bytes[k];
  }
  static const char tail[] = "\n  </AppendedData>\n</VTKFile>\n";
  CHECK((const char *)base + at + strlen(tail) == text + len);
  CHECK(memcmp(base + at, tail, strlen(tail)) == 0);
  free(text);
}

/* ---- OFF, GetFEM, M3D -------------------------------------------------------- */

static int count_lines(const char *text, const char *prefix) {
  int n = 0;
  for (const char *p = text; p && *p; p = strchr(p, '\n'), p = p ? p + 1 : NULL)
    n += strncmp(p, prefix, strlen(prefix)) == 0;
  return n;
}

static void read_others(void) {
  char path[512];
  path_of(path, "small.off");
  char *text = slurp(path, NULL);
  CHECK(text && count_lines(text, "") == 2 + NN + NC); /* OFF, counts, nodes, faces */
  CHECK(text && strncmp(text, "OFF\n11 7 0\n0 0 0\n1 0 0\n1.5 0 0\n", 31) == 0);
  CHECK(text && count_lines(text, "3 ") == 3 && count_lines(text, "4 ") == 4);
  CHECK(text && strstr(text, "\n4 1 2 5 4\n") != NULL);
  free(text);
  path_of(path, "small.getfem");
  text = slurp(path, NULL);
  CHECK(text && count_lines(text, "  POINT  ") == NN && count_lines(text, "  CONVEX ") == NC);
  CHECK(text && strstr(text, "  POINT  2  1.5  0\n") != NULL);
  /* quads in GetFEM's tensor order: ours 1 2 5 4 is 1 2 4 5 */
  CHECK(text && strstr(text, "  CONVEX 3    'GT_QK(2,1)'      1 2 4 5\n") != NULL);
  CHECK(text && strstr(text, "  CONVEX 0    'GT_PK(2,1)'      0 1 4\n") != NULL);
  free(text);
  path_of(path, "small.m3d");
  text = slurp(path, NULL);
  CHECK(text && count_lines(text, "1 +") == NN);
  CHECK(text && count_lines(text, "T ") == 3 && count_lines(text, "Q ") == 4);
  CHECK(text && strstr(text, "\nQ 5 6 10 9 1000.0 0.45 1.0\n") != NULL);
  CHECK(text && strstr(text, "\n1 +1.50000000E+00 +5.00000000E-01 +0.00000000E+00\n") != NULL);
  free(text);
}

static void test_writers(void) {
  mx_qmesh M;
  small_mesh(&M, 0);
  static const struct {
    const char *name;
    int ascii;
  } outs[] = {{"small.vtu", 0},       {"small_bin.vtk", 0}, {"small_ascii.vtk", 1},
              {"small_bin.msh", 0},   {"small_ascii.msh", 1}, {"small.off", 0},
              {"small.getfem", 0},    {"small.m3d", 0}};
  const int nout = (int)(sizeof outs / sizeof *outs);
  for (int k = 0; k < nout; k++) {
    char path[512];
    path_of(path, outs[k].name);
    CHECK(mx_qmesh_format_known(path));
    CHECK(mx_write_qmesh(path, &M, outs[k].ascii) == MX_OK);
  }
  CHECK(count_entries(OUT_DIR, "small") == nout); /* no temporaries left */
  read_vtk_ascii(&M);
  read_vtk_binary();
  read_msh_ascii();
  read_msh_binary();
  read_vtu();
  read_others();
  /* unknown format; a missing directory: refused, nothing left behind */
  CHECK(!mx_qmesh_format_known("x.stl") && !mx_qmesh_format_known("vtk") &&
        mx_qmesh_format_known("dir.d/X.VTU"));
  mx_quiet = 1;
  CHECK(mx_write_qmesh(OUT_DIR "/x.stl", &M, 0) == MX_EINPUT);
  CHECK(mx_write_qmesh(OUT_DIR "/no_such_dir/x.vtu", &M, 0) == MX_EIO);
  CHECK(mx_write_qmesh(OUT_DIR "/no_such_dir/x.msh", &M, 1) == MX_EIO);
  CHECK(!exists(OUT_DIR "/no_such_dir") && !exists(OUT_DIR "/x.stl"));
  CHECK(count_entries(OUT_DIR, "") == nout);
  mx_quiet = 0;
  mx_qmesh_free(&M);
}

/* The grid: boundary lines 4n in the MSH, same bytes for 1 and 3 threads. */
static void test_grid_files(void) {
  const uint32_t n = 120;
  mx_qmesh M;
  grid_mesh(&M, n);
  const char *names[4] = {"grid1.msh", "grid3.msh", "grid1.vtu", "grid3.vtu"};
  for (int k = 0; k < 4; k++) {
    char path[512];
    path_of(path, names[k]);
    omp_set_num_threads(k % 2 ? 3 : 1);
    CHECK(mx_write_qmesh(path, &M, 1) == MX_OK);
  }
  omp_set_num_threads(2);
  CHECK(files_equal(OUT_DIR "/grid1.msh", OUT_DIR "/grid3.msh"));
  CHECK(files_equal(OUT_DIR "/grid1.vtu", OUT_DIR "/grid3.vtu"));
  char *text = slurp(OUT_DIR "/grid1.msh", NULL);
  char head[64];
  snprintf(head, sizeof head, "\n1 1 1 %u\n", 4 * n);
  CHECK(text && strstr(text, head) != NULL);
  /* the lines block lists 4n lines: tags ncells+1 .. ncells+4n */
  char last[64];
  snprintf(last, sizeof last, "\n%zu ", M.ncells + 4 * (size_t)n);
  CHECK(text && strstr(text, last) != NULL);
  free(text);
  mx_qcheck_report r;
  CHECK(mx_qmesh_check(&M, NULL, 1e-9, &r) == MX_OK);
  CHECK(r.bad_edges == 0 && r.hanging == 0 && r.inverted == 0);
  CHECK(r.area == (double)n * n && r.euler == 1 && r.boundary_edges == 4 * n);
  /* square (60, 60) (a quad) split in 4 without touching its neighbours:
   * its 4 mid-edge nodes hang on the neighbours' edges */
  split_square(&M, n, 60, 60);
  CHECK(mx_qmesh_check(&M, NULL, 1e-9, &r) == MX_OK);
  CHECK(r.bad_edges == 0 && r.hanging == 4 && r.inverted == 0);
  CHECK(r.area == (double)n * n);
  /* + 5 nodes, + 12 edges (4 halves along the sides, 4 to the centre),
   * + 3 cells: each side a slit, a hole: 1 - 4 */
  CHECK(r.euler == -3);
  mx_qmesh_free(&M);
}

/* ---- the check --------------------------------------------------------------- */

static void expect(const mx_qcheck_report *r, size_t bad, size_t hang, size_t inv) {
  CHECK(r->bad_edges == bad);
  CHECK(r->hanging == hang);
  CHECK(r->inverted == inv);
}

static void test_check(void) {
  mx_poly P;
  rect_domain(&P);
  mx_qmesh M;
  mx_qcheck_report r;
  small_mesh(&M, 1);
  CHECK(mx_qmesh_check(&M, NULL, 1e-9, &r) == MX_OK);
  expect(&r, 0, 0, 0);
  CHECK(r.area == 2.0);
  CHECK(mx_qmesh_check(&M, &P, 1e-9, &r) == MX_OK);
  expect(&r, 0, 0, 0);
  CHECK(r.off_boundary == 0 && r.missing_features == 0);
  CHECK(r.domain_area == 2.0 && r.area_error == 0.0);
  CHECK(r.edges == 17 && r.boundary_edges == NBOUND && r.euler == 1 && r.domain_euler == 1);

  /* Q5 turned clockwise: inverted; its 3 interior edges now run the same
   * way as in their other cell (4-5 with Q3, 5-9 with Q6, 4-8 with T1) */
  qset(&M, 5, 4, (const uint32_t[]){4, 8, 9, 5}, 1);
  CHECK(mx_qmesh_check(&M, &P, 1e-9, &r) == MX_OK);
  expect(&r, 3, 0, 1);
  qset(&M, 5, 4, cell_nodes[5], 1);

  /* Q4 twice: 2-3, 3-6 used twice the same way, 6-5 and 5-2 three times */
  qset(&M, 7, 4, cell_nodes[4], 1);
  M.ncells = 8;
  CHECK(mx_qmesh_check(&M, &P, 1e-9, &r) == MX_OK);
  expect(&r, 4, 0, 0);
  CHECK(r.area == 2.25 && r.area_error == 0.125);
  M.ncells = 7;

  /* the left half as one quad without the transition: node 4 hangs on its
   * right edge 1-8; with the domain, 4 is an end of the boundary edges 1-4
   * and 4-8 and lies 1 away from the polylines */
  mx_qmesh H;
  small_mesh(&H, 0);
  qset(&H, 0, 4, (const uint32_t[]){0, 1, 8, 7}, 0);
  H.ncells = 5;
  for (size_t c = 1; c < 5; c++) qset(&H, c, 4, cell_nodes[c + 2], 1);
  CHECK(mx_qmesh_check(&H, NULL, 1e-9, &r) == MX_OK);
  expect(&r, 0, 1, 0);
  CHECK(r.area == 2.0);
  CHECK(r.edges == 16 && r.euler == 0); /* the slit along 1-4-8 */
  CHECK(mx_qmesh_check(&H, &P, 1e-9, &r) == MX_OK);
  CHECK(r.off_boundary == 1);
  mx_qmesh_free(&H);

  /* Q5 on a second node at the place of node 4: both nodes lie on the
   * other's edges (at their ends); no edge is used twice the same way */
  M.xy[2 * NN] = node_xy[4][0], M.xy[2 * NN + 1] = node_xy[4][1];
  M.nnodes = NN + 1;
  qset(&M, 5, 4, (const uint32_t[]){NN, 5, 9, 8}, 1);
  CHECK(mx_qmesh_check(&M, NULL, 1e-9, &r) == MX_OK);
  expect(&r, 0, 2, 0);
  qset(&M, 5, 4, cell_nodes[5], 1);
  M.nnodes = NN;

  /* Q5 missing: conforming still, but nodes 4 and 5 are now ends of
   * boundary edges and lie off the polylines; an eighth of the area gone */
  qset(&M, 5, 4, cell_nodes[6], 1);
  M.ncells = 6;
  CHECK(mx_qmesh_check(&M, NULL, 1e-9, &r) == MX_OK);
  expect(&r, 0, 0, 0);
  CHECK(mx_qmesh_check(&M, &P, 1e-9, &r) == MX_OK);
  expect(&r, 0, 0, 0);
  CHECK(r.off_boundary == 2 && r.missing_features == 0);
  CHECK(r.area == 1.75 && r.area_error == 0.125);
  /* a notch in the top side, not a hole: 11 - 16 + 6 */
  CHECK(r.edges == 16 && r.euler == 1 && r.domain_euler == 1);

  /* a node moved 0.01 off the bottom side: off the polylines at 1e-3 of the
   * diameter, on them at 1e-2 */
  M.ncells = 7;
  qset(&M, 5, 4, cell_nodes[5], 1);
  M.xy[2 * 2 + 1] = -0.01;
  CHECK(mx_qmesh_check(&M, &P, 1e-3, &r) == MX_OK);
  CHECK(r.off_boundary == 1);
  CHECK(mx_qmesh_check(&M, &P, 1e-2, &r) == MX_OK);
  CHECK(r.off_boundary == 0);
  mx_poly_free(&P);

  /* a domain with a hole: the square [0,3]^2 counter-clockwise, [1,2]^2
   * clockwise: one outer loop minus one hole, area 8 */
  static const double ring[16] = {0, 0, 3, 0, 3, 3, 0, 3, 1, 1, 1, 2, 2, 2, 2, 1};
  rect_domain(&P);
  P.xy = mx_realloc(P.xy, sizeof ring);
  P.seg = mx_realloc(P.seg, 16 * sizeof *P.seg);
  if (!P.xy || !P.seg) exit(2);
  memcpy(P.xy, ring, sizeof ring);
  P.nv = P.ns = 8;
  for (uint32_t s = 0; s < 8; s++) P.seg[2 * s] = s, P.seg[2 * s + 1] = s % 4 == 3 ? s - 3 : s + 1;
  P.nloops = 2;
  CHECK(mx_qmesh_check(&M, &P, 1e-9, &r) == MX_OK);
  CHECK(r.domain_euler == 0 && r.domain_area == 8.0);
  mx_qmesh_free(&M);
  mx_poly_free(&P);
}

int main(void) {
  mkdir(OUT_DIR, 0755);
  remove_dir_files(OUT_DIR); /* the entry counts need a clean folder */
  test_writers();
  test_grid_files();
  test_check();
  return TEST_DONE();
}
