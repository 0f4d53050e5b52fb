/* Sharp features of input surfaces (issue 29, item 1; src/geom/features.c).
 *
 * Derived, not recorded: a box split into n x n squares per face has 12
 * ridges (its edges) of 12 x n ridge edges and total length its edges'
 * sum, and 8 corners; the same box with every triangle's own vertices
 * (unwelded) gives the same; a regular tetrahedron (dihedral angle 70.5
 * degrees, normals 109.5 apart) has 6 ridges and 4 corners at 30 degrees
 * and none at 110; a sphere finely tessellated has none at 30 degrees; a
 * box at a threshold over 90 degrees has none. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "geom/feature_walk.h"
#include "soa/trisoup.h"
#include "test_shapes.h"

static void soup_of(const double *x, size_t nv, const uint32_t *t, size_t nt, int unweld,
                    mx_trisoup *s) {
  memset(s, 0, sizeof *s);
  CHECK(mx_trisoup_reserve(s, unweld ? 3 * nt : nv, nt) == MX_OK);
  if (unweld) {
    for (size_t i = 0; i < nt; i++)
      for (int k = 0; k < 3; k++) mx_trisoup_set_vertex(s, 3 * i + k, x + 3 * t[3 * i + k]);
    for (size_t i = 0; i < nt; i++)
      mx_trisoup_add_triangle(s, (uint32_t)(3 * i), (uint32_t)(3 * i + 1), (uint32_t)(3 * i + 2));
  } else {
    for (size_t i = 0; i < nv; i++) mx_trisoup_set_vertex(s, i, x + 3 * i);
    for (size_t i = 0; i < nt; i++) mx_trisoup_add_triangle(s, t[3 * i], t[3 * i + 1], t[3 * i + 2]);
  }
}

/* The lines of F: nlines open lines of npts points each, from a corner to
 * another, whose lengths add up to the ridges' length. */
static void check_lines(const mx_trisoup *s, const mx_features *F, size_t nlines, size_t npts) {
  mx_feature_lines L;
  CHECK(mx_feature_lines_of(s, F, &L) == MX_OK);
  CHECK(L.nlines == nlines && L.ncorners == F->ncorners);
  double len = 0.0;
  for (size_t i = 0; i < L.nlines; i++) {
    CHECK(!L.loop[i] && L.first[i + 1] - L.first[i] == npts);
    for (size_t p = L.first[i]; p + 1 < L.first[i + 1]; p++) {
      const double *a = L.xyz + 3 * p, *b = a + 3;
      len += sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) +
                  (a[2] - b[2]) * (a[2] - b[2]));
    }
    for (int end = 0; end < 2; end++) { /* a corner at each end */
      const double *e = L.xyz + 3 * (end ? L.first[i + 1] - 1 : L.first[i]);
      int found = 0;
      for (size_t c = 0; c < L.ncorners; c++)
        found |= e[0] == L.corner[3 * c] && e[1] == L.corner[3 * c + 1] &&
                 e[2] == L.corner[3 * c + 2];
      CHECK(found);
    }
  }
  CHECK(fabs(len - F->length) < 1e-9 * F->length);
  mx_feature_lines_free(&L);
}

int main(void) {
  mx_features F;
  mx_trisoup s;
  double *x;
  uint32_t *t;
  size_t nv, nt;
  const double lo[3] = {0, 0, 0}, hi[3] = {1, 2, 3};
  for (int unweld = 0; unweld < 2; unweld++) {
    box(lo, hi, 4, &x, &nv, &t, &nt);
    soup_of(x, nv, t, nt, unweld, &s);
    CHECK(mx_features_detect(&s, s.nt, 30.0, &F) == MX_OK);
    printf("box (unwelded %d): %zu ridge edges, %zu ridges, %zu corners, length %g\n", unweld,
           F.nedges, F.nridges, F.ncorners, F.length);
    CHECK(F.nedges == 12 * 4 && F.nridges == 12 && F.ncorners == 8);
    CHECK(fabs(F.length - 4 * (1 + 2 + 3)) < 1e-12);
    CHECK(F.npatches == 6);
    check_lines(&s, &F, 12, 5);
    mx_features_free(&F);
    CHECK(mx_features_detect(&s, s.nt, 95.0, &F) == MX_OK);
    CHECK(F.nedges == 0 && F.ncorners == 0 && F.nridges == 0);
    mx_features_free(&F);
    mx_trisoup_free(&s);
    free(x);
    free(t);
  }
  /* a regular tetrahedron */
  const double tx[12] = {1, 1, 1, 1, -1, -1, -1, 1, -1, -1, -1, 1};
  const uint32_t tt[12] = {0, 1, 2, 0, 3, 1, 0, 2, 3, 1, 3, 2};
  soup_of(tx, 4, tt, 4, 0, &s);
  CHECK(mx_features_detect(&s, s.nt, 30.0, &F) == MX_OK);
  CHECK(F.nedges == 6 && F.nridges == 6 && F.ncorners == 4);
  CHECK(fabs(F.length - 6 * sqrt(8.0)) < 1e-12);
  CHECK(F.npatches == 4);
  check_lines(&s, &F, 6, 2);
  mx_features_free(&F);
  CHECK(mx_features_detect(&s, s.nt, 110.0, &F) == MX_OK);
  CHECK(F.nedges == 0 && F.ncorners == 0);
  mx_features_free(&F);
  mx_trisoup_free(&s);
  /* a sphere */
  sphere(1.0, 48, &x, &nv, &t, &nt);
  soup_of(x, nv, t, nt, 0, &s);
  CHECK(mx_features_detect(&s, s.nt, 30.0, &F) == MX_OK);
  printf("sphere: %zu ridge edges, %zu corners\n", F.nedges, F.ncorners);
  CHECK(F.nedges == 0 && F.ncorners == 0);
  mx_features_free(&F);
  mx_trisoup_free(&s);
  free(x);
  free(t);
  return TEST_DONE();
}
