/* The 2D mesher's size field through the library (issue 27; the program's
 * side is tests/size2d_test.sh): the unit square [0, 1]^2, whose quadtree
 * has one root of side 1.01 (qtree.c: 1.01 x the longest extent), so a
 * cell of level L lies in a quadrant of side 1.01 / 2^L.
 *  - a C callback h = 0.03 + 0.1 y is asked at z = 0 only, and every
 *    quadrant is no larger than the least of h over its cell's corners (h
 *    is linear) within the control space's factor 1.31 (its K_L leaves
 *    hold the value at their centre, delta 0.5); the same leaves for the
 *    expression "0.03 + 0.1*y", for 1 and 2 threads, and with an octree
 *    control space (K_oLB);
 *  - a -f circle of level 6 with a field of 0.5: the cells it crosses (a
 *    corner on each side) are of level 6 or finer;
 *  - bad sources and bounds: MX_EINPUT; a field finer than memory or than
 *    params.max_memory_mb: MX_ENOMEM when meshing, and the mesher goes on
 *    with a field it can follow. */
#include <math.h>
#include <stdatomic.h>
#include <stdio.h>
#include <string.h>

#include "mixoct.h"

#include "check.h"

static const double square[8] = {0, 0, 1, 0, 1, 1, 0, 1};
static const uint32_t sides[8] = {0, 1, 1, 2, 2, 3, 3, 0};

static atomic_int off_plane; /* points asked with z != 0 */

static void field(void *user, size_t n, const double *xyz, double *h) {
  (void)user;
  for (size_t i = 0; i < n; i++) {
    if (xyz[3 * i + 2] != 0.0) atomic_fetch_add(&off_plane, 1);
    h[3 * i] = h[3 * i + 1] = h[3 * i + 2] = 0.03 + 0.1 * xyz[3 * i + 1];
  }
}

static void not_a_number(void *user, size_t n, const double *xyz, double *h) {
  (void)user, (void)xyz;
  for (size_t i = 0; i < 3 * n; i++) h[i] = NAN;
}

static void quiet(void *user, int level, const char *text) {
  (void)user, (void)level, (void)text;
}

static mx_mesher2d *unit_square(int threads, double max_memory_mb) {
  mx_params2d p;
  mx_params2d_default(&p);
  p.threads = threads;
  p.max_memory_mb = max_memory_mb;
  mx_mesher2d *m = mx_mesher2d_new(&p);
  mx_mesher2d_set_message_handler(m, quiet, NULL);
  CHECK(mx_mesher2d_set_domain_arrays(m, "square", 4, square, 4, sides) == MX_OK);
  return m;
}

/* Cells whose quadrant is larger than 1.31 x the least of 0.03 + 0.1 y at
 * their corners. */
static size_t too_large(const mx_mesh2d_arrays *a) {
  size_t bad = 0;
  for (size_t c = 0; c < a->ncells; c++) {
    double least = INFINITY;
    for (int k = 0; k < (a->type[c] ? 4 : 3); k++)
      least = fmin(least, 0.03 + 0.1 * a->xy[2 * (size_t)a->conn[4 * c + k] + 1]);
    bad += ldexp(1.01, -a->level[c]) > 1.31 * least;
  }
  return bad;
}

int main(void) {
  mx_mesh2d_arrays a;
  mx_mesher2d *m = unit_square(2, 0);
  CHECK(mx_mesher2d_set_size_function(m, field, NULL, NULL) == MX_OK);
  CHECK(mx_mesher2d_mesh(m) == MX_OK);
  CHECK(mx_mesher2d_mesh_arrays(m, &a) == MX_OK);
  CHECK(atomic_load(&off_plane) == 0);
  CHECK(too_large(&a) == 0);
  const size_t leaves = a.nleaves, cells = a.ncells;
  /* finer at y = 0 (h 0.03: level 6, side 0.0158, or 5 within the
   * tolerance) than above y = 0.9 (h 0.12 to 0.13: level 3, side 0.126,
   * where h is above it, else 4) */
  int lo_level = 99, hi_level = 0;
  for (size_t c = 0; c < a.ncells; c++) {
    double y = 0.0;
    for (int k = 0; k < (a.type[c] ? 4 : 3); k++) y += a.xy[2 * (size_t)a.conn[4 * c + k] + 1];
    y /= a.type[c] ? 4 : 3;
    if (y < 0.02 && a.level[c] < lo_level) lo_level = a.level[c];
    if (y > 0.9 && a.level[c] > hi_level) hi_level = a.level[c];
  }
  CHECK(lo_level >= 5 && hi_level >= 3 && hi_level <= 4);
  printf("h = 0.03 + 0.1 y: %zu leaves, %zu cells, levels %d+ at y = 0, up to %d at y > 0.9\n",
         leaves, cells, lo_level, hi_level);
  mx_mesher2d_free(m);

  m = unit_square(1, 0); /* the expression, one thread: the same leaves */
  CHECK(mx_mesher2d_set_size_expr(m, "0.03 + 0.1*y") == MX_OK);
  CHECK(mx_mesher2d_mesh(m) == MX_OK);
  CHECK(mx_mesher2d_mesh_arrays(m, &a) == MX_OK);
  CHECK(a.nleaves == leaves && a.ncells == cells);
  mx_mesher2d_free(m);

  m = unit_square(2, 0); /* an octree control space */
  mx_cspace_params q;
  mx_cspace_params_default(&q);
  q.structure = MX_CS_OCT_BALANCED;
  CHECK(mx_mesher2d_set_size_function(m, field, NULL, &q) == MX_OK);
  CHECK(mx_mesher2d_mesh(m) == MX_OK);
  CHECK(mx_mesher2d_mesh_arrays(m, &a) == MX_OK);
  CHECK(too_large(&a) == 0 && atomic_load(&off_plane) == 0);
  mx_mesher2d_free(m);

  /* a circle of level 6 (side 0.0158) as a source of a field of 0.5 */
  m = unit_square(2, 0);
  const double circle[3] = {0.5, 0.5, 0.3};
  CHECK(mx_mesher2d_add_function(m, "circle", circle, 3, 6) == MX_OK);
  CHECK(mx_mesher2d_set_size_expr(m, "0.5") == MX_OK);
  CHECK(mx_mesher2d_mesh(m) == MX_OK);
  CHECK(mx_mesher2d_mesh_arrays(m, &a) == MX_OK);
  size_t crossed = 0, coarse = 0;
  for (size_t c = 0; c < a.ncells; c++) {
    int in = 0, out = 0;
    for (int k = 0; k < (a.type[c] ? 4 : 3); k++) {
      const double *p = a.xy + 2 * (size_t)a.conn[4 * c + k];
      const double r = hypot(p[0] - 0.5, p[1] - 0.5);
      in |= r <= 0.3, out |= r >= 0.3;
    }
    crossed += in && out;
    coarse += in && out && a.level[c] < 6;
  }
  CHECK(crossed > 0 && coarse == 0);
  mx_mesher2d_free(m);

  /* bad sources and bounds */
  m = unit_square(2, 0);
  CHECK(mx_mesher2d_set_size_expr(m, "0.03 + 0.1*") == MX_EINPUT);
  CHECK(strstr(mx_mesher2d_last_error(m), "column 12") != NULL);
  CHECK(mx_mesher2d_set_size_expr(m, "F7(x)") == MX_EINPUT);
  CHECK(mx_mesher2d_set_size_limits(m, -1.0, 0.0) == MX_EINPUT);
  CHECK(mx_mesher2d_set_size_limits(m, 0.2, 0.1) == MX_EINPUT);
  CHECK(strstr(mx_mesher2d_last_error(m), "bad bounds") != NULL);
  mx_cspace_params bad = q;
  bad.delta = -1.0;
  CHECK(mx_mesher2d_set_size_function(m, field, NULL, &bad) == MX_EINPUT);
  CHECK(mx_mesher2d_set_size_function(m, not_a_number, NULL, NULL) == MX_OK);
  CHECK(mx_mesher2d_mesh(m) == MX_EINPUT);
  CHECK(strstr(mx_mesher2d_last_error(m), "finite and positive") != NULL);
  /* finer than memory, refused before refining; then a field it can follow */
  CHECK(mx_mesher2d_set_size_expr(m, "1e-7") == MX_OK);
  CHECK(mx_mesher2d_mesh(m) == MX_ENOMEM);
  CHECK(strstr(mx_mesher2d_last_error(m), "least size 1e-07") != NULL);
  CHECK(mx_mesher2d_set_size_expr(m, "0.1") == MX_OK);
  CHECK(mx_mesher2d_mesh(m) == MX_OK);
  CHECK(mx_mesher2d_mesh_arrays(m, &a) == MX_OK);
  CHECK(a.nleaves == 256); /* 16 x 16 quadrants of 1.01 / 16 */
  mx_mesher2d_free(m);
  /* 1e-3 asks for about 2 million quadrants (500 MB at 250 bytes each) */
  m = unit_square(2, 64.0);
  CHECK(mx_mesher2d_set_size_expr(m, "1e-3") == MX_OK);
  CHECK(mx_mesher2d_mesh(m) == MX_ENOMEM);
  CHECK(strstr(mx_mesher2d_last_error(m), "the limit is 64 MB") != NULL);
  mx_mesher2d_free(m);

  printf("%d failed\n", mx_test_failures);
  return mx_test_failures != 0;
}
