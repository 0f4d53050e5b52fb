/* Discrete sources of a size field (issue 27: sizing/sources.h,
 * geom/surface_sizes.h) and the mesher following them:
 *  - the tree's box and point queries equal a brute-force minimum over
 *    every source, and the field holds the gradation: h(p) <= h(q) +
 *    (beta - 1) |p - q| for random pairs;
 *  - thickness: a plate 0.05 thick gives sources of size 0.025 (two
 *    across), and no source smaller; a gap of 0.04 between two boxes gives
 *    0.02 in it;
 *  - curvature: a sphere of radius 1 gives sizes near theta R;
 *  - the mesher: the thin plate at the coarsest level comes out two
 *    elements across (every element at most 0.75 of the thickness high,
 *    the volume within 2%, valid), where without --thickness it is one
 *    element across; the gap between two boxes stays open (no element
 *    spans it; each box's volume within 2%);
 *  - gradation on a function's control space, and bad parameters. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "geom/surface_sizes.h"
#include "mixoct.h"
#include "sizing/sources.h"
#include "soa/trisoup.h"
#include "test_shapes.h"

#include "check.h"

static double urand(unsigned *s) {
  *s = *s * 1103515245u + 12345u;
  return (double)((*s >> 8) & 0xffffff) / 16777216.0;
}

static void check_queries(void) {
  enum { N = 3000 };
  unsigned seed = 7;
  double *box = malloc(6 * N * sizeof *box), *h = malloc(N * sizeof *h);
  for (int i = 0; i < N; i++) {
    for (int a = 0; a < 3; a++) {
      box[6 * i + a] = urand(&seed);
      /* a third of them boxes, the rest points */
      box[6 * i + 3 + a] = box[6 * i + a] + (i % 3 == 0 ? 0.05 * urand(&seed) : 0.0);
    }
    h[i] = 0.001 + 0.1 * urand(&seed);
  }
  mx_size_sources *s;
  CHECK(mx_size_sources_build(box, h, NULL, NULL, N, 1.5, &s) == MX_OK);
  size_t differ = 0, lip = 0;
  for (int q = 0; q < 2000; q++) {
    double lo[3], hi[3], p[3], r[3];
    for (int a = 0; a < 3; a++) {
      lo[a] = 1.2 * urand(&seed) - 0.1;
      hi[a] = lo[a] + (q % 2 ? 0.2 * urand(&seed) : 0.0);
      p[a] = urand(&seed);
      r[a] = urand(&seed);
    }
    differ += mx_size_sources_min_box(s, lo, hi) != mx_size_sources_min_box_direct(s, lo, hi);
    const double hp = mx_size_sources_at(s, p), hr = mx_size_sources_at(s, r);
    const double d = sqrt((p[0] - r[0]) * (p[0] - r[0]) + (p[1] - r[1]) * (p[1] - r[1]) +
                          (p[2] - r[2]) * (p[2] - r[2]));
    lip += hp > hr + 0.5 * d + 1e-12;
  }
  CHECK(differ == 0 && lip == 0);
  /* a box query is the least over the box: never above a point query in it */
  const double lo[3] = {0.2, 0.2, 0.2}, hi[3] = {0.4, 0.4, 0.4}, mid[3] = {0.3, 0.3, 0.3};
  CHECK(mx_size_sources_min_box(s, lo, hi) <= mx_size_sources_at(s, mid));
  mx_size_sources_free(s);
  /* bad parameters */
  h[5] = NAN;
  CHECK(mx_size_sources_build(box, h, NULL, NULL, N, 1.5, &s) == MX_EINPUT && !s);
  h[5] = 0.1;
  CHECK(mx_size_sources_build(box, h, NULL, NULL, N, 1.0, &s) == MX_EINPUT && !s);
  CHECK(mx_size_sources_build(box, h, NULL, NULL, 0, 1.5, &s) == MX_EINPUT && !s);
  free(box);
  free(h);
  printf("sources: %d boxes and points, 2000 box and pair queries exact and graded\n", N);
}

/* An index of the boxes [lo_k, hi_k] as one surface. */
static void boxes_index(int nb, const double (*lo)[3], const double (*hi)[3], int n,
                        mx_trisoup *soup, mx_surface_index *S) {
  memset(soup, 0, sizeof *soup);
  for (int b = 0; b < nb; b++) {
    double *x;
    uint32_t *t;
    size_t nv, nt;
    box(lo[b], hi[b], n, &x, &nv, &t, &nt);
    const size_t v0 = soup->nv;
    for (size_t i = 0; i < nv; i++) CHECK(mx_trisoup_set_vertex(soup, v0 + i, x + 3 * i) == MX_OK);
    for (size_t i = 0; i < nt; i++) {
      CHECK(mx_trisoup_add_triangle(soup, (uint32_t)v0 + t[3 * i], (uint32_t)v0 + t[3 * i + 1],
                                    (uint32_t)v0 + t[3 * i + 2]) == MX_OK);
    }
    free(x);
    free(t);
  }
  CHECK(mx_surface_index_build(S, soup, 0, (uint32_t)soup->nt) == MX_OK);
}

static void check_thickness(void) {
  const double lo[2][3] = {{0, 0, 0}, {0, 0, 0.24}}, hi[2][3] = {{1, 1, 0.05}, {1, 1, 0.44}};
  mx_trisoup soup;
  mx_surface_index S;
  boxes_index(1, lo, hi, 2, &soup, &S);
  mx_point_sizes P;
  memset(&P, 0, sizeof P);
  CHECK(mx_surface_thickness_sizes(&S, 2.0, 0.0, &P) == MX_OK);
  double hmin = INFINITY;
  size_t at_half = 0;
  for (size_t i = 0; i < P.n; i++) {
    hmin = fmin(hmin, P.h[i]);
    at_half += fabs(P.h[i] - 0.025) < 1e-9;
  }
  CHECK(P.n > 0 && fabs(hmin - 0.025) < 1e-9 && at_half > P.n / 3);
  printf("thickness: plate 0.05: %zu sources, least %.6f (%zu at 0.025)\n", P.n, hmin, at_half);
  mx_point_sizes_free(&P);
  /* a floor: no size below it (the knife edges' guard) */
  CHECK(mx_surface_thickness_sizes(&S, 2.0, 0.03, &P) == MX_OK);
  hmin = INFINITY;
  for (size_t i = 0; i < P.n; i++) hmin = fmin(hmin, P.h[i]);
  CHECK(P.n > 0 && hmin == 0.03);
  mx_point_sizes_free(&P);
  mx_surface_index_free(&S);
  mx_trisoup_free(&soup);
  /* two boxes 0.2 thick, 0.04 apart: the gap's sources 0.02, the boxes' 0.1 */
  const double lo2[2][3] = {{0, 0, 0}, {0, 0, 0.24}}, hi2[2][3] = {{1, 1, 0.2}, {1, 1, 0.44}};
  boxes_index(2, lo2, hi2, 2, &soup, &S);
  CHECK(mx_surface_thickness_sizes(&S, 2.0, 0.0, &P) == MX_OK);
  size_t gap = 0, part = 0, other = 0;
  for (size_t i = 0; i < P.n; i++) {
    if (fabs(P.h[i] - 0.02) < 1e-9) gap++;
    else if (fabs(P.h[i] - 0.1) < 1e-9) part++;
    else other++;
    /* the gap's sources lie in the gap */
    if (fabs(P.h[i] - 0.02) < 1e-9) CHECK(P.xyz[3 * i + 2] >= 0.2 - 1e-9 && P.xyz[3 * i + 2] <= 0.24 + 1e-9);
  }
  CHECK(gap > 0 && part > 0);
  printf("thickness: gap 0.04 between two boxes: %zu sources of 0.02, %zu of 0.1, %zu else "
         "(across the sides)\n", gap, part, other);
  mx_point_sizes_free(&P);
  mx_surface_index_free(&S);
  mx_trisoup_free(&soup);
}

static void check_curvature(void) {
  double *x;
  uint32_t *t;
  size_t nv, nt;
  sphere(1.0, 24, &x, &nv, &t, &nt);
  mx_trisoup soup;
  memset(&soup, 0, sizeof soup);
  for (size_t i = 0; i < nv; i++) CHECK(mx_trisoup_set_vertex(&soup, i, x + 3 * i) == MX_OK);
  for (size_t i = 0; i < nt; i++)
    CHECK(mx_trisoup_add_triangle(&soup, t[3 * i], t[3 * i + 1], t[3 * i + 2]) == MX_OK);
  free(x);
  free(t);
  mx_surface_index S;
  CHECK(mx_surface_index_build(&S, &soup, 0, (uint32_t)soup.nt) == MX_OK);
  mx_point_sizes P;
  memset(&P, 0, sizeof P);
  const double theta = 10.0 * 3.14159265358979 / 180.0;
  CHECK(mx_surface_curvature_sizes(&S, theta, &P) == MX_OK);
  /* the median size within 10% of theta R (R = 1) */
  double *h = malloc(P.n * sizeof *h);
  memcpy(h, P.h, P.n * sizeof *h);
  for (size_t i = 1; i < P.n; i++)
    for (size_t j = i; j > 0 && h[j - 1] > h[j]; j--) {
      const double s = h[j];
      h[j] = h[j - 1];
      h[j - 1] = s;
    }
  const double med = P.n ? h[P.n / 2] : 0.0;
  CHECK(P.n > 0 && fabs(med - theta) < 0.1 * theta);
  printf("curvature: sphere R 1, 10 degrees: %zu sources, median size %.4f (theta R %.4f)\n",
         P.n, med, theta);
  free(h);
  mx_point_sizes_free(&P);
  mx_surface_index_free(&S);
  mx_trisoup_free(&soup);
}

static void quiet(void *user, int level, const char *text) {
  (void)user, (void)level, (void)text;
}

/* Meshes the boxes at the coarsest level with `elements` across (0: none);
 * the tallest element, the mesh's volume and whether it is valid. */
static int mesh_boxes(int nb, const double (*lo)[3], const double (*hi)[3], double elements,
                      double *zmax, double *vol, size_t *n, double zgap0, double zgap1,
                      size_t *across) {
  mx_params p;
  mx_params_default(&p);
  p.surface_level = 0;
  p.threads = 2;
  mx_mesher *m = mx_mesher_new(&p);
  mx_mesher_set_message_handler(m, quiet, NULL);
  for (int b = 0; b < nb; b++) {
    double *x;
    uint32_t *t;
    size_t nv, nt;
    box(lo[b], hi[b], 2, &x, &nv, &t, &nt);
    CHECK(mx_mesher_add_surface_arrays(m, "box", nv, x, nt, t) == MX_OK);
    free(x);
    free(t);
  }
  if (elements > 0) CHECK(mx_mesher_set_size_thickness(m, elements) == MX_OK);
  const int st = mx_mesher_mesh(m);
  *zmax = 0.0;
  *vol = 0.0;
  *n = 0;
  *across = 0;
  if (!st) {
    mx_mesh_arrays a;
    CHECK(mx_mesher_mesh_arrays(m, &a) == MX_OK);
    CHECK(a.invalid == 0 && a.jens_min > 0);
    *n = a.nelements;
    for (size_t c = 0; c < a.nelements; c++) {
      double z0 = INFINITY, z1 = -INFINITY;
      for (int k = 0; k < 8 && a.conn[8 * c + k] != UINT32_MAX; k++) {
        const double z = a.xyz[3 * (size_t)a.conn[8 * c + k] + 2];
        z0 = fmin(z0, z);
        z1 = fmax(z1, z);
      }
      *zmax = fmax(*zmax, z1 - z0);
      *vol += volume(&a, c);
      *across += z0 < zgap0 - 1e-9 && z1 > zgap1 + 1e-9;
    }
  }
  mx_mesher_free(m);
  return st;
}

static void check_mesher(void) {
  const double lo[1][3] = {{0, 0, 0}}, hi[1][3] = {{1, 1, 0.05}};
  double zmax, vol;
  size_t n, across;
  CHECK(mesh_boxes(1, lo, hi, 2.0, &zmax, &vol, &n, 0, 0, &across) == MX_OK);
  printf("plate 0.05 at level 0, --thickness 2: %zu elements, tallest %.4f, volume %.6f\n", n,
         zmax, vol);
  CHECK(zmax <= 0.75 * 0.05 && fabs(vol - 0.05) < 0.02 * 0.05);
  /* without it: one element across (the test can fail) */
  const int st = mesh_boxes(1, lo, hi, 0.0, &zmax, &vol, &n, 0, 0, &across);
  printf("plate without --thickness: status %d, %zu elements, tallest %.4f\n", st, n, zmax);
  CHECK(st != MX_OK || zmax > 0.75 * 0.05);
  /* the gap between two boxes stays open */
  const double lo2[2][3] = {{0, 0, 0}, {0, 0, 0.24}}, hi2[2][3] = {{1, 1, 0.2}, {1, 1, 0.44}};
  CHECK(mesh_boxes(2, lo2, hi2, 2.0, &zmax, &vol, &n, 0.2, 0.24, &across) == MX_OK);
  printf("two boxes 0.04 apart, --thickness 2: %zu elements, %zu across the gap, volume %.6f\n",
         n, across, vol);
  CHECK(across == 0 && fabs(vol - 0.4) < 0.02 * 0.4);
}

/* A mesher of the unit cube with the parameters p, quiet. */
static mx_mesher *unit_cube(const mx_params *p) {
  mx_mesher *m = mx_mesher_new(p);
  mx_mesher_set_message_handler(m, quiet, NULL);
  const double lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
  double *x;
  uint32_t *t;
  size_t nv, nt;
  box(lo, hi, 2, &x, &nv, &t, &nt);
  CHECK(mx_mesher_add_surface_arrays(m, "cube", nv, x, nt, t) == MX_OK);
  free(x);
  free(t);
  return m;
}

static mx_mesher *graded_cube(double beta) {
  mx_params p;
  mx_params_default(&p);
  p.stage = MX_STAGE_TRANSITION;
  mx_mesher *m = unit_cube(&p);
  CHECK(mx_mesher_set_size_expr(m, "min(0.5, 0.02 + 40*abs(x-0.5)^2)") == MX_OK);
  if (beta > 0) CHECK(mx_mesher_set_size_gradation(m, beta) == MX_OK);
  return m;
}

static void check_gradation(void) {
  /* a function field, steep away from the plane x = 0.5, graded with beta
   * 1.2: more leaves, and the leaves grow by at most 1.2 per their side
   * away from the plane (side <= 0.02 + 0.2 d + the octree's factor 2) */
  size_t n[2];
  for (int g = 0; g < 2; g++) {
    mx_mesher *m = graded_cube(g ? 1.2 : 0.0);
    CHECK(mx_mesher_mesh(m) == MX_OK);
    mx_mesh_arrays a;
    CHECK(mx_mesher_mesh_arrays(m, &a) == MX_OK);
    n[g] = a.nleaves;
    size_t over = 0;
    for (size_t c = 0; g && c < a.nelements; c++) {
      double x0 = INFINITY, x1 = -INFINITY;
      for (int k = 0; k < 8 && a.conn[8 * c + k] != UINT32_MAX; k++) {
        x0 = fmin(x0, a.xyz[3 * (size_t)a.conn[8 * c + k]]);
        x1 = fmax(x1, a.xyz[3 * (size_t)a.conn[8 * c + k]]);
      }
      const double d = x0 > 0.5 ? x0 - 0.5 : x1 < 0.5 ? 0.5 - x1 : 0.0;
      over += x1 - x0 > 1.35 * (0.02 + 0.2 * d) * 1.0001;
    }
    CHECK(over == 0);
    mx_mesher_free(m);
  }
  printf("gradation 1.2 on a function: %zu leaves against %zu without\n", n[1], n[0]);
  CHECK(n[1] > n[0]); /* a gentler growth: more leaves */
  mx_mesher *m = graded_cube(0.0);
  CHECK(mx_mesher_set_size_gradation(m, 1.0) == MX_EINPUT);
  CHECK(mx_mesher_set_size_thickness(m, 0.5) == MX_EINPUT);
  CHECK(mx_mesher_set_size_curvature(m, 200) == MX_EINPUT);
  const double pts[3] = {0.5, 0.5, 0.5}, hs[1] = {-1};
  CHECK(mx_mesher_set_size_points(m, pts, hs, 1, "test") == MX_EINPUT);
  const double far[3] = {50, 0.5, 0.5}, ok[1] = {0.1};
  CHECK(mx_mesher_set_size_points(m, far, ok, 1, "test") == MX_OK);
  CHECK(mx_mesher_mesh(m) == MX_EINPUT); /* outside the domain's box */
  mx_mesher_free(m);
}

/* A solver's size per element handed back: the elements left of x = 0.5
 * ask for 0.06, the others nothing finer than they are; the re-mesh
 * follows (the octree refined, not rebuilt). */
static void check_elements(void) {
  mx_params p;
  mx_params_default(&p);
  p.surface_level = 2;
  mx_mesher *m = unit_cube(&p);
  CHECK(mx_mesher_mesh(m) == MX_OK);
  mx_mesh_arrays a;
  CHECK(mx_mesher_mesh_arrays(m, &a) == MX_OK);
  const size_t n0 = a.nelements;
  double *h = malloc(n0 * sizeof *h);
  for (size_t c = 0; c < n0; c++) {
    double cx = 0.0;
    int k = 0;
    for (; k < 8 && a.conn[8 * c + k] != UINT32_MAX; k++) cx += a.xyz[3 * (size_t)a.conn[8 * c + k]];
    h[c] = cx / k < 0.5 ? 0.06 : 10.0;
  }
  CHECK(mx_mesher_set_size_elements(m, h, n0 - 1) == MX_EINPUT);
  CHECK(mx_mesher_set_size_elements(m, h, n0) == MX_OK);
  free(h);
  CHECK(mx_mesher_refine_elements(m, NULL, 0) == MX_OK);
  CHECK(mx_mesher_mesh_arrays(m, &a) == MX_OK);
  size_t big = 0;
  double wmax = 0.0;
  for (size_t c = 0; c < a.nelements; c++) {
    double x0 = INFINITY, x1 = -INFINITY;
    for (int k = 0; k < 8 && a.conn[8 * c + k] != UINT32_MAX; k++) {
      x0 = fmin(x0, a.xyz[3 * (size_t)a.conn[8 * c + k]]);
      x1 = fmax(x1, a.xyz[3 * (size_t)a.conn[8 * c + k]]);
    }
    if (x1 < 0.4) {
      big += x1 - x0 > 0.06 * 1.0001;
      wmax = fmax(wmax, x1 - x0);
    }
  }
  printf("size per element: %zu elements, then %zu; widest left of x = 0.4: %.4f\n", n0,
         a.nelements, wmax);
  CHECK(a.nelements > n0 && big == 0 && a.invalid == 0);
  mx_mesher_free(m);
}

int main(void) {
  mx_set_thread_message_handler(quiet, NULL);
  check_elements();
  check_queries();
  check_thickness();
  check_curvature();
  check_mesher();
  check_gradation();
  return mx_test_failures ? 1 : 0;
}
