/* Feature distances (src/verify/check_features.c), on answers that follow
 * from the definitions in verify/check.h: the unit cube meshed by n^3
 * hexahedra (and by 6 n^3 tetrahedra) has the cube's 12 edges among its
 * boundary edges and its 8 corners among its nodes: distances 0. The same
 * lines scaled by 0.9 about the centre lie 0.05 sqrt(2) from the nearest
 * cube edge at worst (and a corner 0.05 sqrt(3) from the cube's corner);
 * the boundary edges of the n^3 grid are 12 n (n + 1) per face pair
 * counted once: 6 faces x 2 n (n + 1) minus the 12 n edges two faces share.
 * The largest distance found is the same for 1 and 2 threads, and against
 * a brute force over all edges at the reported sample. */
#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "base/common.h"
#include "geom/feature_walk.h"
#include "verify/check.h"

/* The unit cube as n^3 hexahedra (tets: 6 tetrahedra each, Kuhn split). */
static void cube_mesh(int n, int tets, mx_mesh_data *m) {
  memset(m, 0, sizeof *m);
  const size_t nn = (size_t)(n + 1) * (n + 1) * (n + 1), nh = (size_t)n * n * n;
  m->nnodes = nn;
  m->ncells = tets ? 6 * nh : nh;
  m->xyz = mx_alloc(3 * nn * sizeof *m->xyz);
  m->type = mx_alloc(m->ncells);
  m->conn = mx_calloc(8 * m->ncells * sizeof *m->conn);
#define ID(i, j, k) ((uint32_t)(((size_t)(k) * (n + 1) + (size_t)(j)) * (n + 1) + (size_t)(i)))
  for (int k = 0; k <= n; k++)
    for (int j = 0; j <= n; j++)
      for (int i = 0; i <= n; i++) {
        double *p = m->xyz + 3 * (size_t)ID(i, j, k);
        p[0] = (double)i / n;
        p[1] = (double)j / n;
        p[2] = (double)k / n;
      }
  size_t c = 0;
  for (int k = 0; k < n; k++)
    for (int j = 0; j < n; j++)
      for (int i = 0; i < n; i++) {
        const uint32_t v[8] = {ID(i, j, k),         ID(i + 1, j, k),     ID(i + 1, j + 1, k),
                               ID(i, j + 1, k),     ID(i, j, k + 1),     ID(i + 1, j, k + 1),
                               ID(i + 1, j + 1, k + 1), ID(i, j + 1, k + 1)};
        if (!tets) {
          m->type[c] = MX_HEX;
          memcpy(m->conn + 8 * c++, v, sizeof v);
          continue;
        }
        /* Kuhn: the 6 paths 0 -> 6 along the axes, each a positive tet */
        static const int path[6][4] = {{0, 1, 2, 6}, {0, 2, 3, 6}, {0, 3, 7, 6},
                                       {0, 7, 4, 6}, {0, 4, 5, 6}, {0, 5, 1, 6}};
        for (int t = 0; t < 6; t++) {
          m->type[c] = MX_TET;
          uint32_t *r = m->conn + 8 * c++;
          for (int q = 0; q < 4; q++) r[q] = v[path[t][q]];
        }
      }
#undef ID
}

/* The cube's 12 edges as lines (scaled by s about the centre). */
static void cube_lines(double s, mx_feature_lines *L) {
  double x[24];
  for (int v = 0; v < 8; v++)
    for (int a = 0; a < 3; a++) x[3 * v + a] = 0.5 + s * (((v >> a) & 1) - 0.5);
  uint32_t e[24];
  int ne = 0;
  for (int v = 0; v < 8; v++)
    for (int a = 0; a < 3; a++)
      if (!((v >> a) & 1)) {
        e[2 * ne] = (uint32_t)v;
        e[2 * ne + 1] = (uint32_t)(v | 1 << a);
        ne++;
      }
  CHECK(mx_feature_lines_walk(x, x + 1, x + 2, 3, 8, e, 12, NULL, L) == MX_OK);
  CHECK(L->nlines == 12 && L->ncorners == 8);
}

static double seg_d2(const double *p, const double *a, const double *b) {
  double ab[3], ap[3], l2 = 0, t = 0, d2 = 0;
  for (int k = 0; k < 3; k++) {
    ab[k] = b[k] - a[k];
    ap[k] = p[k] - a[k];
    l2 += ab[k] * ab[k];
    t += ab[k] * ap[k];
  }
  t = l2 > 0 ? fmin(fmax(t / l2, 0), 1) : 0;
  for (int k = 0; k < 3; k++) d2 += (ap[k] - t * ab[k]) * (ap[k] - t * ab[k]);
  return d2;
}

int main(void) {
  for (int tets = 0; tets < 2; tets++) {
    const int n = 4;
    mx_mesh_data m;
    cube_mesh(n, tets, &m);
    uint32_t *edge;
    size_t ne;
    CHECK(mx_check_boundary_edges(&m, &edge, &ne) == MX_OK);
    /* hexahedra: 6 faces x 2 n (n + 1) grid edges, less the 12 n shared;
     * tetrahedra: and a diagonal in each of the 6 n^2 boundary squares */
    const size_t want = 12 * (size_t)n * (n + 1) - 12 * (size_t)n + (tets ? 6 * (size_t)n * n : 0);
    printf("cube %s n=%d: %zu boundary edges (expected %zu)\n", tets ? "tets" : "hexes", n, ne,
           want);
    CHECK(ne == want);
    mx_feature_lines L;
    cube_lines(1.0, &L);
    mx_check_feature_dist d;
    CHECK(mx_check_features_mesh(&m, &L, &d) == MX_OK);
    printf("  exact: ridge %g corner %g samples %zu length %g diagonal %g\n", d.ridge_dist,
           d.corner_dist, d.samples, d.length, d.diagonal);
    CHECK(d.ridge_dist == 0.0 && d.corner_dist == 0.0);
    CHECK(d.lines == 12 && d.corners == 8 && d.loops == 0 && fabs(d.length - 12.0) < 1e-12);
    CHECK(fabs(d.diagonal - sqrt(3.0)) < 1e-12 && d.edges == ne);
    /* 4 samples per mesh edge at least: 12 lines x n edges x 4 parts + ends */
    CHECK(d.samples >= 12 * (size_t)n * 4 + 12);
    mx_feature_lines_walk_free(&L);
    cube_lines(0.9, &L);
    double r1 = 0, c1 = 0;
    for (int threads = 1; threads <= 2; threads++) {
      omp_set_num_threads(threads);
      CHECK(mx_check_features(&L, m.xyz, m.nnodes, edge, ne, &d) == MX_OK);
      printf("  scaled, %d threads: ridge %.17g at (%g %g %g) line %zu, corner %.17g node %u\n",
             threads, d.ridge_dist, d.ridge_at[0], d.ridge_at[1], d.ridge_at[2], d.ridge_line,
             d.corner_dist, d.corner_node);
      CHECK(fabs(d.ridge_dist - 0.05 * sqrt(2.0)) < 1e-12);
      CHECK(fabs(d.corner_dist - 0.05 * sqrt(3.0)) < 1e-12);
      if (threads == 1) {
        r1 = d.ridge_dist;
        c1 = d.corner_dist;
      } else {
        CHECK(r1 == d.ridge_dist && c1 == d.corner_dist);
      }
    }
    /* brute force at the reported sample */
    double best = INFINITY;
    for (size_t e = 0; e < ne; e++)
      best = fmin(best, seg_d2(d.ridge_at, m.xyz + 3 * (size_t)edge[2 * e],
                               m.xyz + 3 * (size_t)edge[2 * e + 1]));
    CHECK(fabs(sqrt(best) - d.ridge_dist) < 1e-15);
    /* no boundary edges: infinite; no lines: NAN */
    CHECK(mx_check_features(&L, m.xyz, m.nnodes, edge, 0, &d) == MX_OK);
    CHECK(isinf(d.ridge_dist) && isinf(d.corner_dist));
    mx_feature_lines_walk_free(&L);
    mx_feature_lines E;
    memset(&E, 0, sizeof E);
    size_t zero = 0;
    E.first = &zero;
    CHECK(mx_check_features(&E, m.xyz, m.nnodes, edge, ne, &d) == MX_OK);
    CHECK(isnan(d.ridge_dist) && isnan(d.corner_dist) && d.samples == 0);
    /* a bad edge is refused */
    edge[1] = (uint32_t)m.nnodes;
    cube_lines(1.0, &L);
    CHECK(mx_check_features(&L, m.xyz, m.nnodes, edge, ne, &d) == MX_EINPUT);
    mx_feature_lines_walk_free(&L);
    mx_free(edge);
    mx_mesh_data_free(&m);
  }
  if (mx_test_failures) {
    printf("%d failures\n", mx_test_failures);
    return 1;
  }
  printf("all feature distance tests passed\n");
  return 0;
}
