/* The 2D boundary step (Algorithm 2, steps 3-5) and the 2D quality measures,
 * on transition-like meshes built here (uniform grids of quads, and a
 * two-level grid whose coarse cells next to fine ones are fanned into
 * triangles), checked by an independent routine: orientation, every edge
 * used once or twice in opposite directions, boundary edges on the
 * polylines, no hanging node, area against the polygons'. */
#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "base/common.h"
#include "quad/quad.h"

#define PI 3.14159265358979323846

/* ---- polylines ------------------------------------------------------------ */

/* Loops of counts[l] vertices each, taken as given (outer counter-clockwise,
 * holes clockwise). */
static void make_poly(mx_poly *P, const double *xy, const size_t *counts, size_t nloops) {
  memset(P, 0, sizeof *P);
  for (size_t l = 0; l < nloops; l++) P->nv += counts[l];
  P->ns = P->nv;
  P->xy = mx_alloc(2 * P->nv * sizeof *P->xy);
  P->seg = mx_alloc(2 * P->ns * sizeof *P->seg);
  P->line = mx_calloc(P->ns * sizeof *P->line);
  memcpy(P->xy, xy, 2 * P->nv * sizeof *P->xy);
  for (size_t l = 0, o = 0; l < nloops; o += counts[l], l++)
    for (size_t i = 0; i < counts[l]; i++) {
      P->seg[2 * (o + i)] = (uint32_t)(o + i);
      P->seg[2 * (o + i) + 1] = (uint32_t)(o + (i + 1) % counts[l]);
    }
  P->nloops = nloops;
}

/* A regular n-gon (ccw > 0: counter-clockwise), appended to xy. */
static void ngon(double *xy, int n, double cx, double cy, double r, double phase, int ccw) {
  for (int i = 0; i < n; i++) {
    const double a = phase + (ccw ? 1 : -1) * 2 * PI * i / n;
    xy[2 * i] = cx + r * cos(a);
    xy[2 * i + 1] = cy + r * sin(a);
  }
}

static double poly_area(const mx_poly *P) {
  double s = 0;
  for (size_t i = 0; i < P->ns; i++) {
    const double *a = P->xy + 2 * P->seg[2 * i], *b = P->xy + 2 * P->seg[2 * i + 1];
    s += a[0] * b[1] - a[1] * b[0];
  }
  return 0.5 * s;
}

static double seg_dist(const double *p, const double *a, const double *b) {
  const double u[2] = {b[0] - a[0], b[1] - a[1]}, w[2] = {p[0] - a[0], p[1] - a[1]};
  double t = (u[0] * w[0] + u[1] * w[1]) / (u[0] * u[0] + u[1] * u[1]);
  t = t < 0 ? 0 : t > 1 ? 1 : t;
  return hypot(w[0] - t * u[0], w[1] - t * u[1]);
}

static double poly_dist(const mx_poly *P, const double *p) {
  double d = INFINITY;
  for (size_t i = 0; i < P->ns; i++)
    d = fmin(d, seg_dist(p, P->xy + 2 * P->seg[2 * i], P->xy + 2 * P->seg[2 * i + 1]));
  return d;
}

/* ---- meshes ----------------------------------------------------------------- */

static uint64_t morton2(uint32_t x, uint32_t y) {
  uint64_t k = 0;
  for (int b = 0; b < 32; b++) k |= (uint64_t)((x >> b) & 1) << (2 * b) | (uint64_t)((y >> b) & 1) << (2 * b + 1);
  return k;
}

/* Cells and nodes of a grid over [-0.5, 0.5]^2 on the lattice of level
 * `fine` (nodes made once per lattice point). */
typedef struct {
  mx_qmesh M;
  int fine;
  int32_t *id; /* per lattice point */
  size_t cap_n, cap_c, leaves;
} builder;

static void b_init(builder *b, int fine) {
  memset(b, 0, sizeof *b);
  b->fine = fine;
  const size_t np = ((size_t)1 << fine) + 1;
  b->id = malloc(np * np * sizeof *b->id);
  for (size_t i = 0; i < np * np; i++) b->id[i] = -1;
  b->cap_n = np * np;
  b->cap_c = 4 * (np - 1) * (np - 1);
  b->M.xy = mx_alloc(2 * b->cap_n * sizeof(double));
  b->M.nkey = mx_alloc(b->cap_n * sizeof(uint64_t));
  b->M.type = mx_alloc(b->cap_c);
  b->M.level = mx_alloc(b->cap_c);
  b->M.conn = mx_alloc(4 * b->cap_c * sizeof(uint32_t));
  b->M.leaf = mx_alloc(b->cap_c * sizeof(uint32_t));
}

static uint32_t b_node(builder *b, uint32_t i, uint32_t j) {
  const size_t np = ((size_t)1 << b->fine) + 1, at = (size_t)j * np + i;
  if (b->id[at] < 0) {
    const size_t v = b->M.nnodes++;
    const double h = ldexp(1.0, -b->fine);
    b->M.xy[2 * v] = -0.5 + i * h;
    b->M.xy[2 * v + 1] = -0.5 + j * h;
    b->M.nkey[v] = morton2(i << (MX_QMAX_LEVEL - b->fine), j << (MX_QMAX_LEVEL - b->fine));
    b->id[at] = (int32_t)v;
  }
  return (uint32_t)b->id[at];
}

static void b_cell(builder *b, int type, const uint32_t *v, int level) {
  const size_t c = b->M.ncells++;
  b->M.type[c] = (uint8_t)type;
  b->M.level[c] = (uint8_t)level;
  b->M.leaf[c] = (uint32_t)b->leaves - 1;
  for (int k = 0; k < 4; k++) b->M.conn[4 * c + k] = k < 3 || type == MX_QQUAD ? v[k] : UINT32_MAX;
}

static void b_done(builder *b, mx_qtree *T) {
  free(b->id);
  memset(T, 0, sizeof *T);
  T->grid.origin[0] = T->grid.origin[1] = -0.5;
  T->grid.side = 1.0;
  T->grid.unit = ldexp(1.0, -MX_QMAX_LEVEL);
  T->grid.dims[0] = T->grid.dims[1] = 1;
}

/* A uniform grid of quads of level L. */
static void uniform(mx_qmesh *M, mx_qtree *T, int L) {
  builder b;
  b_init(&b, L);
  const uint32_t n = 1u << L;
  for (uint32_t j = 0; j < n; j++)
    for (uint32_t i = 0; i < n; i++) {
      const uint32_t v[4] = {b_node(&b, i, j), b_node(&b, i + 1, j), b_node(&b, i + 1, j + 1),
                             b_node(&b, i, j + 1)};
      b.leaves++;
      b_cell(&b, MX_QQUAD, v, L);
    }
  b_done(&b, T);
  *M = b.M;
}

/* Level L, with the cells whose centre satisfies fine() split once; a coarse
 * cell with mid-nodes on two opposite sides is 2 quads, otherwise it is a
 * fan of triangles from its first mid-node (a conforming transition). */
static void two_level(mx_qmesh *M, mx_qtree *T, int L, int (*fine)(double, double)) {
  builder b;
  b_init(&b, L + 1);
  const int n = 1 << L;
  const double h = 1.0 / n;
  uint8_t *ref = calloc((size_t)n * n, 1);
  for (int j = 0; j < n; j++)
    for (int i = 0; i < n; i++) ref[j * n + i] = (uint8_t)fine(-0.5 + (i + 0.5) * h, -0.5 + (j + 0.5) * h);
  for (int j = 0; j < n; j++)
    for (int i = 0; i < n; i++) {
      const uint32_t x = 2 * (uint32_t)i, y = 2 * (uint32_t)j;
      if (ref[j * n + i]) {
        for (uint32_t q = 0; q < 4; q++) {
          const uint32_t a = x + (q & 1), c = y + (q >> 1);
          const uint32_t v[4] = {b_node(&b, a, c), b_node(&b, a + 1, c), b_node(&b, a + 1, c + 1),
                                 b_node(&b, a, c + 1)};
          b.leaves++;
          b_cell(&b, MX_QQUAD, v, L + 1);
        }
        continue;
      }
      const int nb[4][2] = {{i, j - 1}, {i + 1, j}, {i, j + 1}, {i - 1, j}};
      int mask = 0;
      for (int e = 0; e < 4; e++)
        if (nb[e][0] >= 0 && nb[e][0] < n && nb[e][1] >= 0 && nb[e][1] < n &&
            ref[nb[e][1] * n + nb[e][0]])
          mask |= 1 << e;
      const uint32_t corner[4][2] = {{x, y}, {x + 2, y}, {x + 2, y + 2}, {x, y + 2}};
      const uint32_t mid[4][2] = {{x + 1, y}, {x + 2, y + 1}, {x + 1, y + 2}, {x, y + 1}};
      b.leaves++;
      if (mask == 5 || mask == 10) {
        const int e = mask == 5 ? 0 : 1;
        const uint32_t m0 = b_node(&b, mid[e][0], mid[e][1]), m1 = b_node(&b, mid[e + 2][0], mid[e + 2][1]);
        const uint32_t c[4] = {b_node(&b, corner[e][0], corner[e][1]),
                               b_node(&b, corner[e + 1][0], corner[e + 1][1]),
                               b_node(&b, corner[(e + 2) & 3][0], corner[(e + 2) & 3][1]),
                               b_node(&b, corner[(e + 3) & 3][0], corner[(e + 3) & 3][1])};
        const uint32_t q0[4] = {c[0], m0, m1, c[3]}, q1[4] = {m0, c[1], c[2], m1};
        b_cell(&b, MX_QQUAD, q0, L);
        b_cell(&b, MX_QQUAD, q1, L);
        continue;
      }
      uint32_t p[8];
      int np = 0, s = -1;
      for (int e = 0; e < 4; e++) {
        p[np++] = b_node(&b, corner[e][0], corner[e][1]);
        if (mask >> e & 1) {
          if (s < 0) s = np;
          p[np++] = b_node(&b, mid[e][0], mid[e][1]);
        }
      }
      if (s < 0) {
        b_cell(&b, MX_QQUAD, p, L);
        continue;
      }
      for (int t = 1; t <= np - 2; t++) {
        const uint32_t v[3] = {p[s], p[(s + t) % np], p[(s + t + 1) % np]};
        b_cell(&b, MX_QTRI, v, L);
      }
    }
  free(ref);
  b_done(&b, T);
  *M = b.M;
}

/* ---- the independent check -------------------------------------------------- */

typedef struct {
  size_t inverted, bad_edges, boundary_edges, off_poly, hanging, unused;
  double area, worst_poly;
} report;

static int cmp_u64(const void *a, const void *b) {
  const uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
  return x < y ? -1 : x > y;
}

static int nverts(const mx_qmesh *M, size_t c) { return M->type[c] == MX_QQUAD ? 4 : 3; }

static report check_mesh(const mx_qmesh *M, const mx_poly *P) {
  report r = {0};
  uint64_t *e = malloc(4 * M->ncells * sizeof *e + 8);
  uint8_t *used = calloc(M->nnodes + 1, 1);
  size_t ne = 0;
  for (size_t c = 0; c < M->ncells; c++) {
    const uint32_t *v = M->conn + 4 * c;
    const int n = nverts(M, c);
    for (int k = 0; k < n; k++) {
      const double *p = M->xy + 2 * v[k], *a = M->xy + 2 * v[(k + 1) % n], *b = M->xy + 2 * v[(k + n - 1) % n];
      if ((a[0] - p[0]) * (b[1] - p[1]) - (a[1] - p[1]) * (b[0] - p[0]) <= 0) {
        r.inverted++;
        break;
      }
    }
    for (int k = 0; k < n; k++) {
      const uint32_t a = v[k], b = v[(k + 1) % n];
      used[a] = 1;
      /* undirected key, direction in bit 0 */
      e[ne++] = ((uint64_t)(a < b ? a : b) << 33) | ((uint64_t)(a < b ? b : a) << 1) | (a > b);
    }
    r.area += 0.5 * (n == 3 ? ((M->xy[2 * v[1]] - M->xy[2 * v[0]]) * (M->xy[2 * v[2] + 1] - M->xy[2 * v[0] + 1]) -
                               (M->xy[2 * v[1] + 1] - M->xy[2 * v[0] + 1]) * (M->xy[2 * v[2]] - M->xy[2 * v[0]]))
                            : ((M->xy[2 * v[2]] - M->xy[2 * v[0]]) * (M->xy[2 * v[3] + 1] - M->xy[2 * v[1] + 1]) -
                               (M->xy[2 * v[2] + 1] - M->xy[2 * v[0] + 1]) * (M->xy[2 * v[3]] - M->xy[2 * v[1]])));
  }
  for (size_t v = 0; v < M->nnodes; v++) r.unused += !used[v];
  qsort(e, ne, sizeof *e, cmp_u64);
  for (size_t i = 0, j; i < ne; i = j) {
    for (j = i + 1; j < ne && e[j] >> 1 == e[i] >> 1; j++) {}
    if (j - i > 2 || (j - i == 2 && (e[i] & 1) == (e[i + 1] & 1))) r.bad_edges++;
    if (j - i != 1) continue;
    r.boundary_edges++;
    const uint32_t a = (uint32_t)(e[i] >> 33), b = (uint32_t)((e[i] >> 1) & 0xffffffffu);
    const double da = poly_dist(P, M->xy + 2 * a), db = poly_dist(P, M->xy + 2 * b);
    r.worst_poly = fmax(r.worst_poly, fmax(da, db));
    r.off_poly += !(da < 1e-12) || !(db < 1e-12);
    const double *pa = M->xy + 2 * a, *pb = M->xy + 2 * b;
    const double len = hypot(pb[0] - pa[0], pb[1] - pa[1]);
    for (size_t v = 0; v < M->nnodes; v++)
      if (v != a && v != b && used[v] && seg_dist(M->xy + 2 * v, pa, pb) < 1e-9 * len) r.hanging++;
  }
  free(e);
  free(used);
  return r;
}

static int is_vertex(const mx_qmesh *M, const double *p) {
  for (size_t v = 0; v < M->nnodes; v++)
    if (M->xy[2 * v] == p[0] && M->xy[2 * v + 1] == p[1]) return 1;
  return 0;
}

/* Runs the boundary step on a copy of M with `threads` threads. */
static int run(const mx_poly *P, const mx_qtree *T, const mx_qmesh *M0, int threads, mx_qmesh *M,
               mx_qboundary_stats *st) {
  *M = *M0;
  M->xy = mx_alloc(2 * M0->nnodes * sizeof(double));
  M->nkey = mx_alloc(M0->nnodes * sizeof(uint64_t));
  M->type = mx_alloc(M0->ncells);
  M->level = mx_alloc(M0->ncells);
  M->conn = mx_alloc(4 * M0->ncells * sizeof(uint32_t));
  M->leaf = mx_alloc(M0->ncells * sizeof(uint32_t));
  memcpy(M->xy, M0->xy, 2 * M0->nnodes * sizeof(double));
  memcpy(M->nkey, M0->nkey, M0->nnodes * sizeof(uint64_t));
  memcpy(M->type, M0->type, M0->ncells);
  memcpy(M->level, M0->level, M0->ncells);
  memcpy(M->conn, M0->conn, 4 * M0->ncells * sizeof(uint32_t));
  memcpy(M->leaf, M0->leaf, M0->ncells * sizeof(uint32_t));
  mx_poly_index I;
  CHECK(mx_poly_index_build(P, &I) == MX_OK);
  omp_set_num_threads(threads);
  const int s = mx_qboundary(P, &I, T, NULL, 0.3, M, st);
  omp_set_num_threads(2);
  mx_poly_index_free(&I);
  return s;
}

static int same_mesh(const mx_qmesh *A, const mx_qmesh *B) {
  return A->nnodes == B->nnodes && A->ncells == B->ncells &&
         !memcmp(A->xy, B->xy, 2 * A->nnodes * sizeof(double)) &&
         !memcmp(A->nkey, B->nkey, A->nnodes * sizeof(uint64_t)) &&
         !memcmp(A->type, B->type, A->ncells) && !memcmp(A->level, B->level, A->ncells) &&
         !memcmp(A->conn, B->conn, 4 * A->ncells * sizeof(uint32_t)) &&
         !memcmp(A->leaf, B->leaf, A->ncells * sizeof(uint32_t));
}

/* The features of P as the paper defines them: vertices where the polyline
 * turns by 5 degrees or more. */
static size_t expected_features(const mx_poly *P) {
  size_t n = 0;
  for (size_t s = 0; s < P->ns; s++)
    for (size_t t = 0; t < P->ns; t++) {
      if (P->seg[2 * t] != P->seg[2 * s + 1]) continue;
      const double *a = P->xy + 2 * P->seg[2 * s], *b = P->xy + 2 * P->seg[2 * s + 1],
                   *c = P->xy + 2 * P->seg[2 * t + 1];
      const double u[2] = {b[0] - a[0], b[1] - a[1]}, w[2] = {c[0] - b[0], c[1] - b[1]};
      const double turn = fabs(atan2(u[0] * w[1] - u[1] * w[0], u[0] * w[0] + u[1] * w[1])) * 180 / PI;
      n += turn >= 5.0;
    }
  return n;
}

/* mx_poly_features (another step's file) as it answers now: whether it
 * reports the features this test expects; the feature assertions need it. */
static int features_reported(const mx_poly *P) {
  uint32_t *f = NULL;
  size_t n = 0;
  mx_poly_features(P, &f, &n);
  mx_free(f);
  const size_t e = expected_features(P);
  if (e && n != e) fprintf(stderr, "mx_poly_features reports %zu features, not %zu: not checked\n", n, e);
  return n == e;
}

/* The common assertions: valid, conforming, boundary on the polylines, no
 * hanging node, every node used, area within tol, levels kept, features as
 * vertices, the same mesh with 1 and 3 threads, the quality measure
 * agreeing with the check. The result in *out. */
static report domain_case(const char *name, const mx_poly *P, const mx_qmesh *M0, const mx_qtree *T,
                          double area_tol, mx_qboundary_stats *st, mx_qmesh *out) {
  mx_qmesh M, M3;
  mx_qboundary_stats s3;
  CHECK(run(P, T, M0, 1, &M, st) == MX_OK);
  CHECK(run(P, T, M0, 3, &M3, &s3) == MX_OK);
  CHECK(same_mesh(&M, &M3));
  CHECK(!memcmp(st, &s3, sizeof s3));
  const report r = check_mesh(&M, P);
  const double pa = poly_area(P);
  fprintf(stderr,
          "%s: %zu nodes %zu cells; features %zu close %zu removed %zu shrunk %zu patterned %zu "
          "inverted %zu; area %.6f of %.6f\n",
          name, M.nnodes, M.ncells, st->features, st->moved_close, st->removed, st->shrunk,
          st->patterned, st->inverted, r.area, pa);
  CHECK(M.ncells > 0);
  CHECK(r.inverted == 0);
  CHECK(r.bad_edges == 0);
  CHECK(r.off_poly == 0);
  CHECK(r.hanging == 0);
  CHECK(r.unused == 0);
  CHECK(fabs(r.area - pa) <= area_tol * pa);
  /* each cell keeps its leaf, and the leaf's level */
  uint8_t *lev = calloc(M0->ncells, 1);
  for (size_t c = 0; c < M0->ncells; c++) lev[M0->leaf[c]] = M0->level[c];
  for (size_t c = 0; c < M.ncells; c++) {
    CHECK(mx_qcell_sj(&M, c) > 0);
    CHECK(M.leaf[c] < M0->ncells && M.level[c] == lev[M.leaf[c]]);
  }
  free(lev);
  mx_qquality q;
  mx_qquality_measure(&M, &q);
  CHECK(q.count[0] + q.count[1] == M.ncells && q.invalid == 0);
  CHECK(fabs(q.area - r.area) < 1e-12);
  if (features_reported(P)) {
    uint32_t *f = NULL;
    size_t n = 0;
    mx_poly_features(P, &f, &n);
    for (size_t i = 0; i < n; i++) CHECK(is_vertex(&M, P->xy + 2 * f[i]));
    CHECK(st->features == n);
    mx_free(f);
  }
  mx_qmesh_free(&M3);
  *out = M;
  return r;
}

/* ---- the cases ------------------------------------------------------------------ */

static void test_quality(void) {
  double xy[] = {0, 0, 1, 0, 1, 1, 0, 1, 0.5, sqrt(3) / 2, 0, 1, sqrt(3), 0, 0, 1};
  uint32_t conn[] = {0, 1, 2, 3, 0, 1, 4, UINT32_MAX, 0, 1, 3, UINT32_MAX, 3, 2, 1, 0,
                     0, 6, 7, UINT32_MAX};
  uint8_t type[] = {MX_QQUAD, MX_QTRI, MX_QTRI, MX_QQUAD, MX_QTRI};
  mx_qmesh M = {.nnodes = 8, .ncells = 5, .xy = xy, .type = type, .conn = conn};
  CHECK(fabs(mx_qcell_sj(&M, 0) - 1) < 1e-12);                       /* unit square */
  CHECK(fabs(mx_qcell_sj(&M, 1) - 1) < 1e-12);                       /* equilateral */
  CHECK(fabs(mx_qcell_sj(&M, 2) - sin(PI / 4) / sin(PI / 3)) < 1e-12); /* right isoceles */
  CHECK(fabs(mx_qcell_sj(&M, 3) + 1) < 1e-12);                       /* clockwise square */
  CHECK(fabs(mx_qcell_min_angle(&M, 0) - 90) < 1e-9);
  CHECK(fabs(mx_qcell_min_angle(&M, 1) - 60) < 1e-9);
  CHECK(fabs(mx_qcell_min_angle(&M, 4) - 30) < 1e-9); /* 30-60-90 */
  CHECK(fabs(mx_qcell_sj(&M, 4) - sin(PI / 6) / sin(PI / 3)) < 1e-12);
  /* A dart (reflex corner): negative. */
  double dxy[] = {0, 0, 2, 0, 0.5, 0.5, 0, 2};
  uint32_t dconn[] = {0, 1, 2, 3};
  uint8_t dtype[] = {MX_QQUAD};
  mx_qmesh D = {.nnodes = 4, .ncells = 1, .xy = dxy, .type = dtype, .conn = dconn};
  CHECK(mx_qcell_sj(&D, 0) < 0);
  mx_qquality q;
  mx_qquality_measure(&M, &q);
  CHECK(q.count[0] == 3 && q.count[1] == 2);
  CHECK(q.invalid == 1);
  CHECK(fabs(q.min[1] + 1) < 1e-12 && fabs(q.max[1] - 1) < 1e-12 && fabs(q.mean[1]) < 1e-12);
  CHECK(fabs(q.max[0] - 1) < 1e-12);
  CHECK(fabs(q.mean[0] - (1 + sin(PI / 4) / sin(PI / 3) + sin(PI / 6) / sin(PI / 3)) / 3) < 1e-12);
  CHECK(fabs(q.min_angle - 30) < 1e-9);
  /* bins: -1 -> <0.03; 0.577 -> <0.6; 0.816 -> <=1; 1, 1 -> <=1 */
  CHECK(q.bins[0] == 1 && q.bins[3] == 1 && q.bins[5] == 3);
  /* areas: 1 + sqrt3/4 + 1/2 - 1 + sqrt3/2 */
  CHECK(fabs(q.area - (0.5 + 3 * sqrt(3) / 4)) < 1e-12);
}

/* A square on the grid lines: nothing moves, the quads inside stay. */
static void test_aligned_square(void) {
  const double xy[] = {-0.25, -0.25, 0.25, -0.25, 0.25, 0.25, -0.25, 0.25};
  const size_t cnt[] = {4};
  mx_poly P;
  make_poly(&P, xy, cnt, 1);
  mx_qmesh M0, M;
  mx_qtree T;
  uniform(&M0, &T, 6);
  mx_qboundary_stats st;
  const report r = domain_case("aligned square", &P, &M0, &T, 1e-15, &st, &M);
  CHECK(M.ncells == 32 * 32);
  CHECK(st.removed == 64 * 64 - 32 * 32);
  CHECK(st.moved_close == 0 && st.shrunk == 0 && st.patterned == 0 && st.inverted == 0);
  CHECK(r.area == 0.25);
  CHECK(r.boundary_edges == 4 * 32);
  for (size_t c = 0; c < M.ncells; c++) CHECK(M.type[c] == MX_QQUAD && M.level[c] == 6);
  /* nothing moved: every node keeps its lattice key, and sits on it */
  for (size_t v = 0; v < M.nnodes; v++) {
    CHECK(M.nkey[v] != MX_QNKEY_NONE);
    uint32_t x = 0, y = 0;
    for (int b = 0; b < 32; b++) {
      x |= (uint32_t)((M.nkey[v] >> (2 * b)) & 1) << b;
      y |= (uint32_t)((M.nkey[v] >> (2 * b + 1)) & 1) << b;
    }
    CHECK(M.xy[2 * v] == -0.5 + ldexp(x, -MX_QMAX_LEVEL));
    CHECK(M.xy[2 * v + 1] == -0.5 + ldexp(y, -MX_QMAX_LEVEL));
  }
  mx_qmesh_free(&M0);
  mx_qmesh_free(&M);
  mx_poly_free(&P);
}

static void test_disc(void) {
  double xy[400];
  ngon(xy, 200, 0, 0, 0.4, 0.013, 1);
  const size_t cnt[] = {200};
  mx_poly P;
  make_poly(&P, xy, cnt, 1);
  mx_qmesh M0, M;
  mx_qtree T;
  uniform(&M0, &T, 6);
  mx_qboundary_stats st;
  const report r = domain_case("disc", &P, &M0, &T, 0.005, &st, &M);
  CHECK(st.features == 0);
  CHECK(st.shrunk > 0 && st.removed > 0);
  /* the boundary is one closed loop of the 200-gon's size: its edges are
   * shorter than 2 cells' diagonals */
  CHECK(r.boundary_edges > 100);
  mx_qmesh_free(&M);
  mx_qmesh_free(&M0);
  mx_poly_free(&P);
}

static double fine_r;
static int near_circle_right(double x, double y) {
  return x > -0.05 && fabs(hypot(x, y) - fine_r) < 0.08;
}

/* The disc on a two-level mesh: fine cells along the right half of the
 * circle, coarse ones (and transitions) on the left half. */
static void test_disc_transitions(void) {
  double xy[400];
  ngon(xy, 200, 0.01, -0.02, 0.37, 0.2, 1);
  const size_t cnt[] = {200};
  mx_poly P;
  make_poly(&P, xy, cnt, 1);
  mx_qmesh M0, M;
  mx_qtree T;
  fine_r = 0.37;
  two_level(&M0, &T, 5, near_circle_right);
  size_t tri = 0;
  for (size_t c = 0; c < M0.ncells; c++) tri += M0.type[c] == MX_QTRI;
  CHECK(tri > 0);
  mx_qboundary_stats st;
  domain_case("disc, two levels", &P, &M0, &T, 0.01, &st, &M);
  mx_qmesh_free(&M);
  mx_qmesh_free(&M0);
  mx_poly_free(&P);
}

static void test_rotated_square(void) {
  double xy[8];
  ngon(xy, 4, 0.02, 0.01, 0.42, PI / 6 + PI / 4, 1); /* a square turned by 30 degrees */
  const size_t cnt[] = {4};
  mx_poly P;
  make_poly(&P, xy, cnt, 1);
  mx_qmesh M0, M;
  mx_qtree T;
  uniform(&M0, &T, 6);
  mx_qboundary_stats st;
  domain_case("rotated square", &P, &M0, &T, 0.01, &st, &M);
  mx_qmesh_free(&M);
  mx_qmesh_free(&M0);
  mx_poly_free(&P);
}

/* Squares on the grid lines but for a tenth of a cell (shrink, then two
 * tenths the other way (close projection): the ring of nodes next to the
 * polygon moves onto it, nothing else changes. Exact counts and areas. */
static void test_shifted_squares(void) {
  const double h = 1.0 / 64;
  for (int out = 0; out < 2; out++) {
    const double a = 0.25 + (out ? 0.2 : -0.1) * h;
    const double xy[] = {-a, -a, a, -a, a, a, -a, a};
    const size_t cnt[] = {4};
    mx_poly P;
    make_poly(&P, xy, cnt, 1);
    mx_qmesh M0, M;
    mx_qtree T;
    uniform(&M0, &T, 6);
    mx_qboundary_stats st;
    const report r = domain_case(out ? "square, 0.2 cell larger" : "square, 0.1 cell smaller", &P,
                                 &M0, &T, 1e-12, &st, &M);
    CHECK(M.ncells == 32 * 32 && st.removed == 64 * 64 - 32 * 32);
    for (size_t c = 0; c < M.ncells; c++) CHECK(M.type[c] == MX_QQUAD);
    CHECK(st.patterned == 0 && st.inverted == 0);
    CHECK(fabs(r.area - 4 * a * a) < 1e-14);
    CHECK(r.boundary_edges == 4 * 32);
    /* the ring of 4 * 32 nodes at +-0.25, the corners taken by the features */
    const size_t ring = 4 * 32 - (features_reported(&P) ? 4 : 0);
    CHECK(out ? st.moved_close == ring && st.shrunk == 0 : st.moved_close == 0 && st.shrunk == ring);
    size_t moved = 0;
    for (size_t v = 0; v < M.nnodes; v++) moved += M.nkey[v] == MX_QNKEY_NONE;
    CHECK(moved == 4 * 32);
    mx_qmesh_free(&M);
    mx_qmesh_free(&M0);
    mx_poly_free(&P);
  }
}

/* Fig. 8(b): a right triangle whose hypotenuse runs through grid nodes
 * (x + y = 0). Each cell it crosses has one inside node, two on the
 * hypotenuse and one outside, which the shrink puts at the middle of the
 * other two: a flat corner of that cell only, so the quad becomes the
 * triangle of the other three. 31 * 32 / 2 quads and 32 triangles, area
 * exact. */
static void test_flat_pattern(void) {
  const double xy[] = {-0.25, -0.25, 0.25, -0.25, -0.25, 0.25};
  const size_t cnt[] = {3};
  mx_poly P;
  make_poly(&P, xy, cnt, 1);
  mx_qmesh M0, M;
  mx_qtree T;
  uniform(&M0, &T, 6);
  mx_qboundary_stats st;
  const report r = domain_case("right triangle on the grid", &P, &M0, &T, 1e-14, &st, &M);
  size_t tri = 0;
  for (size_t c = 0; c < M.ncells; c++) tri += M.type[c] == MX_QTRI;
  CHECK(M.ncells == 31 * 32 / 2 + 32 && tri == 32);
  CHECK(st.shrunk == 32 && st.patterned == 32 && st.moved_close == 0 && st.inverted == 0);
  CHECK(st.removed == 64 * 64 - 31 * 32 / 2 - 32);
  CHECK(fabs(r.area - 0.125) < 1e-14);
  /* the 32 shrunk nodes left with the quads they cornered */
  CHECK(M.nnodes == 33 * 34 / 2);
  mx_qmesh_free(&M);
  mx_qmesh_free(&M0);
  mx_poly_free(&P);
}

/* Two features in one leaf: both would take its closest node. */
static void test_feature_conflict(void) {
  const double xy[] = {-0.3, -0.3, 0.001, -0.3, 0.002, -0.29, 0.003, -0.3, 0.3, -0.3, 0.3, 0.3, -0.3, 0.3};
  const size_t cnt[] = {7};
  mx_poly P;
  make_poly(&P, xy, cnt, 1);
  if (features_reported(&P)) {
    mx_qmesh M0, M;
    mx_qtree T;
    uniform(&M0, &T, 6);
    mx_qboundary_stats st;
    CHECK(run(&P, &T, &M0, 2, &M, &st) == MX_EINVALID);
    mx_qmesh_free(&M0);
    mx_qmesh_free(&M);
  }
  mx_poly_free(&P);
}

static int right_half(double x, double y) { return x > 0.02 + 0 * y; }

/* The rotated square and a triangle on a two-level mesh: transitions
 * (triangles) along x = 0.02 meet the boundary. */
static void test_two_level_features(void) {
  double sq[8];
  ngon(sq, 4, -0.01, 0.015, 0.41, PI / 6 + PI / 4 + 0.1, 1);
  const double tri[] = {-0.41, -0.33, 0.39, -0.12, -0.2, 0.4};
  const double *xy[2] = {sq, tri};
  const size_t cnt[2][1] = {{4}, {3}};
  for (int k = 0; k < 2; k++) {
    mx_poly P;
    make_poly(&P, xy[k], cnt[k], 1);
    mx_qmesh M0, M;
    mx_qtree T;
    two_level(&M0, &T, 5, right_half);
    mx_qboundary_stats st;
    domain_case(k ? "triangle, two levels" : "rotated square, two levels", &P, &M0, &T, 0.02, &st, &M);
    mx_qmesh_free(&M);
    mx_qmesh_free(&M0);
    mx_poly_free(&P);
  }
}

/* A triangle with angles of about 25, 65 and 90 degrees. */
static void test_triangle(void) {
  const double xy[] = {-0.4, -0.3, 0.43, -0.3, -0.4, 0.087};
  const size_t cnt[] = {3};
  mx_poly P;
  make_poly(&P, xy, cnt, 1);
  mx_qmesh M0, M;
  mx_qtree T;
  uniform(&M0, &T, 6);
  mx_qboundary_stats st;
  domain_case("triangle", &P, &M0, &T, 0.02, &st, &M);
  mx_qmesh_free(&M);
  mx_qmesh_free(&M0);
  mx_poly_free(&P);
}

/* A disc with an off-centre hole (clockwise); the hole's 60-gon turns by 6
 * degrees at each vertex: 60 features. */
static void test_hole(void) {
  double xy[2 * (120 + 60)];
  ngon(xy, 120, 0, 0, 0.42, 0, 1);
  ngon(xy + 240, 60, 0.08, -0.05, 0.17, 0.1, 0);
  const size_t cnt[] = {120, 60};
  mx_poly P;
  make_poly(&P, xy, cnt, 2);
  mx_qmesh M0, M;
  mx_qtree T;
  uniform(&M0, &T, 6);
  mx_qboundary_stats st;
  domain_case("hole", &P, &M0, &T, 0.01, &st, &M);
  mx_qmesh_free(&M);
  mx_qmesh_free(&M0);
  mx_poly_free(&P);
}

int main(void) {
  mx_quiet = 1;
  test_quality();
  test_aligned_square();
  test_disc();
  test_disc_transitions();
  test_rotated_square();
  test_triangle();
  test_hole();
  test_shifted_squares();
  test_flat_pattern();
  test_feature_conflict();
  test_two_level_features();
  return TEST_DONE();
}
