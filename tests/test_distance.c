/* Distance, signed distance, winding number and inside/outside
 * (src/geom/distance.h) against analytic answers on boxes, against the
 * winding number on the demo surface, and against the ray-parity locator on
 * the cortex. Run with the argument "quick" for small counts (valgrind). */
#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <string.h>

#include "check.h"
#include "base/common.h"
#include "geom/distance.h"
#include "geom/locate.h"
#include "octree_util.h"
#include "soa/trisoup.h"
#include "io/demo_surface.h"

static int quick = 0;
static size_t scaled(size_t n) { return quick ? mx_max(n / 50, 200) : n; }

static uint64_t rng = 0x9E3779B97F4A7C15ULL;
static double uniform(double lo, double hi) {
  rng ^= rng << 13;
  rng ^= rng >> 7;
  rng ^= rng << 17;
  return lo + (hi - lo) * (double)(rng >> 11) / 9007199254740992.0;
}

typedef struct {
  double lo[3], hi[3];
} box;

/* Signed distance to one box: inside -(distance to the nearest face),
 * outside the Euclidean distance. */
static double box_sd(const box *b, const double p[3]) {
  double out2 = 0.0, in = INFINITY;
  int inside = 1;
  for (int a = 0; a < 3; a++) {
    if (p[a] < b->lo[a]) {
      out2 += (b->lo[a] - p[a]) * (b->lo[a] - p[a]);
      inside = 0;
    } else if (p[a] > b->hi[a]) {
      out2 += (p[a] - b->hi[a]) * (p[a] - b->hi[a]);
      inside = 0;
    } else {
      in = mx_min(in, mx_min(p[a] - b->lo[a], b->hi[a] - p[a]));
    }
  }
  return inside ? -in : sqrt(out2);
}

/* Domain of a set of disjoint-surfaced boxes by parity: signed distance to
 * the union of their surfaces, negative in the domain. */
static double boxes_sd(const box *b, int nb, const double p[3]) {
  double d = INFINITY;
  int depth = 0;
  for (int i = 0; i < nb; i++) {
    const double s = box_sd(&b[i], p);
    d = mx_min(d, fabs(s));
    if (s < 0.0) depth++;
  }
  return depth % 2 ? -d : d;
}

static void soup_of_boxes(mx_trisoup *s, const box *b, const int *inward,
                          int nb) {
  memset(s, 0, sizeof *s);
  for (int i = 0; i < nb; i++) add_box(s, b[i].lo, b[i].hi, inward[i]);
}

/* Random points in [lo-m, hi+m]^3 of the boxes' hull; signed distance to
 * within tol of the analytic one; inside and the winding number agree. */
static void check_boxes(const char *name, const box *b, int nb,
                        const mx_surface_index *S, size_t n, double tol) {
  double lo[3], hi[3];
  for (int a = 0; a < 3; a++) {
    lo[a] = b[0].lo[a];
    hi[a] = b[0].hi[a];
    for (int i = 1; i < nb; i++) {
      lo[a] = mx_min(lo[a], b[i].lo[a]);
      hi[a] = mx_max(hi[a], b[i].hi[a]);
    }
  }
  size_t bad_sd = 0, bad_in = 0, bad_w = 0;
  double worst = 0.0;
  for (size_t k = 0; k < n; k++) {
    double p[3];
    for (int a = 0; a < 3; a++) {
      const double m = 0.3 * (hi[a] - lo[a]);
      p[a] = uniform(lo[a] - m, hi[a] + m);
    }
    const double want = boxes_sd(b, nb, p), got = mx_signed_distance(S, p, NULL);
    const double err = fabs(want - got);
    worst = mx_max(worst, err);
    if (!(err <= tol)) bad_sd++;
    if (mx_inside(S, p) != (want <= 0.0)) bad_in++;
    if (fabs(want) > 1e-6 && k % 8 == 0) {
      const double w = mx_winding_number(S, p);
      if (!(fabs(w - (want < 0.0 ? 1.0 : 0.0)) < 1e-9)) bad_w++;
    }
  }
  printf("%s: %zu points, worst |sd error| %.2e, %zu bad sd, %zu bad inside, "
         "%zu bad winding\n", name, n, worst, bad_sd, bad_in, bad_w);
  CHECK(bad_sd == 0);
  CHECK(bad_in == 0);
  CHECK(bad_w == 0);
}

/* Independent point-triangle distance: the plane distance when the
 * projection falls inside, else the nearest of the three edges. */
static double seg_dist2(const double p[3], const double a[3], const double b[3]) {
  double ab[3], ap[3], l2 = 0.0, s = 0.0;
  for (int i = 0; i < 3; i++) {
    ab[i] = b[i] - a[i];
    ap[i] = p[i] - a[i];
    l2 += ab[i] * ab[i];
    s += ab[i] * ap[i];
  }
  const double t = l2 > 0.0 ? mx_min(1.0, mx_max(0.0, s / l2)) : 0.0;
  double d2 = 0.0;
  for (int i = 0; i < 3; i++) d2 += (ap[i] - t * ab[i]) * (ap[i] - t * ab[i]);
  return d2;
}
static double tri_dist(const double p[3], const double a[3], const double b[3],
                       const double c[3]) {
  const double *v[3] = {a, b, c};
  double e1[3], e2[3], n[3];
  for (int i = 0; i < 3; i++) {
    e1[i] = b[i] - a[i];
    e2[i] = c[i] - a[i];
  }
  n[0] = e1[1] * e2[2] - e1[2] * e2[1];
  n[1] = e1[2] * e2[0] - e1[0] * e2[2];
  n[2] = e1[0] * e2[1] - e1[1] * e2[0];
  const double nn = n[0] * n[0] + n[1] * n[1] + n[2] * n[2];
  if (nn > 0.0) {
    int inside = 1;
    for (int k = 0; k < 3 && inside; k++) {
      const double *u = v[k], *w = v[(k + 1) % 3];
      const double e[3] = {w[0] - u[0], w[1] - u[1], w[2] - u[2]};
      const double r[3] = {p[0] - u[0], p[1] - u[1], p[2] - u[2]};
      const double x[3] = {e[1] * r[2] - e[2] * r[1], e[2] * r[0] - e[0] * r[2],
                           e[0] * r[1] - e[1] * r[0]};
      if (x[0] * n[0] + x[1] * n[1] + x[2] * n[2] < 0.0) inside = 0;
    }
    if (inside) {
      const double h = (p[0] - a[0]) * n[0] + (p[1] - a[1]) * n[1] +
                       (p[2] - a[2]) * n[2];
      return fabs(h) / sqrt(nn);
    }
  }
  return sqrt(mx_min(seg_dist2(p, a, b),
                     mx_min(seg_dist2(p, b, c), seg_dist2(p, c, a))));
}
static double brute_dist(const mx_trisoup *s, uint32_t t0, uint32_t t1,
                         const double p[3]) {
  double d = INFINITY;
  for (uint32_t t = t0; t < t1; t++) {
    const uint32_t *v = s->tri + 3 * (size_t)t;
    const double a[3] = {s->x[v[0]], s->y[v[0]], s->z[v[0]]};
    const double b[3] = {s->x[v[1]], s->y[v[1]], s->z[v[1]]};
    const double c[3] = {s->x[v[2]], s->y[v[2]], s->z[v[2]]};
    d = mx_min(d, tri_dist(p, a, b, c));
  }
  return d;
}

/* The pruned descent (float bounds, hints) against a scan of every
 * triangle: points in the box, far away, and near the surface. */
static void check_against_brute(const char *name, const mx_trisoup *s,
                                const mx_surface_index *S, size_t n) {
  double lo[3], hi[3];
  mx_trisoup_bbox(s, lo, hi);
  size_t bad = 0;
  double worst = 0.0;
  for (size_t k = 0; k < n; k++) {
    double p[3];
    const int kind = (int)(k % 4);
    for (int a = 0; a < 3; a++) {
      const double w = hi[a] - lo[a];
      p[a] = kind == 0   ? uniform(lo[a] - w, hi[a] + w)
             : kind == 1 ? uniform(lo[a] - 100 * w, hi[a] + 100 * w)
                         : uniform(lo[a], hi[a]);
    }
    if (kind == 3) { /* near a random vertex */
      const size_t v = (size_t)uniform(0, (double)s->nv - 0.5);
      p[0] = s->x[v] + uniform(-1e-3, 1e-3) * (hi[0] - lo[0]);
      p[1] = s->y[v] + uniform(-1e-3, 1e-3) * (hi[1] - lo[1]);
      p[2] = s->z[v] + uniform(-1e-3, 1e-3) * (hi[2] - lo[2]);
    }
    const double want = brute_dist(s, S->t0, S->t1, p);
    double q[3];
    const double got = mx_closest_point(S, p, q, NULL, NULL);
    const double dq = sqrt((p[0] - q[0]) * (p[0] - q[0]) +
                           (p[1] - q[1]) * (p[1] - q[1]) +
                           (p[2] - q[2]) * (p[2] - q[2]));
    const double err = fabs(got - want) / (1.0 + want);
    worst = mx_max(worst, err);
    if (!(err < 1e-12) || !(fabs(dq - got) <= 1e-12 * (1.0 + got))) bad++;
  }
  printf("%s: closest point vs every triangle, %zu points: worst relative "
         "difference %.2e, %zu bad\n", name, n, worst, bad);
  CHECK(bad == 0);
}

static void test_unit_cube(void) {
  const box b = {{0, 0, 0}, {1, 1, 1}};
  const int inward = 0;
  mx_trisoup s;
  soup_of_boxes(&s, &b, &inward, 1);
  mx_surface_index S;
  CHECK(mx_surface_index_build(&S, &s, 0, (uint32_t)s.nt) == MX_OK);
  CHECK(S.closed == 1);
  CHECK(S.open_edges == 0);
  CHECK(S.nshells == 1);
  CHECK(S.nflipped == 0);
  CHECK(S.nreoriented == 0);
  /* Random points, most of them outside (face, edge and vertex regions). */
  size_t n = scaled(100000), nfeat[3] = {0, 0, 0}, bad_q = 0;
  for (size_t k = 0; k < n; k++) {
    double p[3], q[3], want_q[3];
    for (int a = 0; a < 3; a++) {
      p[a] = uniform(-1.0, 2.0);
      want_q[a] = mx_min(1.0, mx_max(0.0, p[a]));
    }
    uint32_t tri;
    int f;
    const double d = mx_closest_point(&S, p, q, &tri, &f);
    const double want = box_sd(&b, p);
    if (want > 0.0) {
      nfeat[f == MX_FEATURE_FACE ? 0 : f < MX_FEATURE_VERTEX ? 1 : 2]++;
      double e = 0.0;
      for (int a = 0; a < 3; a++) e = mx_max(e, fabs(q[a] - want_q[a]));
      if (!(e < 1e-12) || !(fabs(d - want) < 1e-12) || tri >= 12) bad_q++;
    }
  }
  printf("unit cube: closest features of outside points: %zu face, %zu "
         "edge, %zu vertex; %zu bad\n", nfeat[0], nfeat[1], nfeat[2], bad_q);
  CHECK(bad_q == 0);
  CHECK(nfeat[1] > n / 20);
  CHECK(nfeat[2] > n / 20);
  check_boxes("unit cube", &b, 1, &S, n, 1e-12);
  /* Grid positions aligned with the faces, edges and vertices (on the
   * surface too: 0). */
  size_t bad = 0;
  for (int i = 0; i <= 12; i++)
    for (int j = 0; j <= 12; j++)
      for (int k = 0; k <= 12; k++) {
        const double p[3] = {-1.0 + 0.25 * i, -1.0 + 0.25 * j, -1.0 + 0.25 * k};
        const double want = box_sd(&b, p), got = mx_signed_distance(&S, p, NULL);
        if (!(fabs(want - got) <= 1e-12)) {
          if (bad < 5)
            fprintf(stderr, "grid (%g %g %g): sd %.17g, want %.17g\n", p[0],
                    p[1], p[2], got, want);
          bad++;
        }
        if (mx_inside(&S, p) != (want <= 0.0)) bad++;
      }
  CHECK(bad == 0);
  /* Points within 1e-9 of the surface, near faces, edges and vertices. */
  bad = 0;
  for (size_t k = 0; k < n / 10; k++) {
    double p[3];
    for (int a = 0; a < 3; a++) {
      const double r = uniform(0.0, 1.0);
      p[a] = r < 0.25 ? 0.0 : r < 0.5 ? 1.0 : uniform(0.0, 1.0);
    }
    for (int a = 0; a < 3; a++) p[a] += uniform(-1e-9, 1e-9);
    const double want = box_sd(&b, p), got = mx_signed_distance(&S, p, NULL);
    if (!(fabs(want - got) <= 1e-12)) bad++;
  }
  printf("unit cube: %zu near-surface points, %zu bad\n", n / 10, bad);
  CHECK(bad == 0);
  /* Known features. */
  const double pv[3] = {2, 2, 2}, pe[3] = {2, 2, 0.5}, pf[3] = {0.3, 0.6, -1};
  int f;
  uint32_t t;
  mx_closest_point(&S, pv, NULL, &t, &f);
  CHECK(f >= MX_FEATURE_VERTEX);
  mx_closest_point(&S, pe, NULL, &t, &f);
  CHECK(f >= MX_FEATURE_EDGE && f < MX_FEATURE_VERTEX);
  CHECK(fabs(mx_closest_point(&S, pf, NULL, &t, &f) - 1.0) < 1e-15);
  CHECK(f == MX_FEATURE_FACE);
  CHECK(t < 2); /* the z = 0 face is triangles 0 and 1 */
  mx_surface_index_free(&S);
  mx_trisoup_free(&s);
}

static void test_demo_surface(void) {
  mx_trisoup s;
  memset(&s, 0, sizeof s);
  CHECK(mx_demo_surface(&s, 4) == MX_OK);
  mx_surface_index S;
  CHECK(mx_surface_index_build(&S, &s, 0, (uint32_t)s.nt) == MX_OK);
  CHECK(S.closed == 1);
  CHECK(S.nshells == 1);
  CHECK(S.nflipped == 0);
  CHECK(S.nreoriented == 0);
  double lo[3], hi[3];
  mx_trisoup_bbox(&s, lo, hi);
  size_t n = scaled(10000), bad_in = 0, bad_w = 0, bad_h = 0, nin = 0;
  double worst_h = 0.0;
  for (size_t k = 0; k < n; k++) {
    double p[3];
    for (int a = 0; a < 3; a++) {
      const double m = 0.1 * (hi[a] - lo[a]);
      p[a] = uniform(lo[a] - m, hi[a] + m);
    }
    const int in = mx_inside(&S, p);
    nin += (size_t)in;
    const double w = mx_winding_number(&S, p);
    if (in != (w > 0.5)) bad_in++;
    if (fabs(mx_signed_distance(&S, p, NULL)) > 1e-3 && !(fabs(w - in) < 1e-9))
      bad_w++;
    if (k % 10 == 0) {
      const double e = fabs(w - mx_winding_number_direct(&S, p));
      worst_h = mx_max(worst_h, e);
      if (!(e < 1e-10)) bad_h++;
    }
  }
  printf("demo surface (%zu triangles): %zu points (%zu inside), %zu inside "
         "!= winding, %zu winding not 0/1, hierarchical vs direct winding "
         "worst %.2e\n", s.nt, n, nin, bad_in, bad_w, worst_h);
  CHECK(nin > n / 10 && nin < n - n / 10);
  CHECK(bad_in == 0);
  CHECK(bad_w == 0);
  CHECK(bad_h == 0);
  check_against_brute("demo surface", &s, &S, scaled(4000));
  mx_surface_index_free(&S);

  /* Open: the first 10 triangles left out. The winding number through the
   * caps must equal the direct sum; the pseudonormal is not used. */
  CHECK(mx_surface_index_build(&S, &s, 10, (uint32_t)s.nt) == MX_OK);
  CHECK(S.closed == 0);
  CHECK(S.open_edges > 0);
  bad_h = 0;
  worst_h = 0.0;
  for (size_t k = 0; k < n / 5; k++) {
    double p[3];
    for (int a = 0; a < 3; a++) p[a] = uniform(lo[a] - 10, hi[a] + 10);
    const double w = mx_winding_number(&S, p);
    const double e = fabs(w - mx_winding_number_direct(&S, p));
    worst_h = mx_max(worst_h, e);
    if (!(e < 1e-10)) bad_h++;
    if ((mx_signed_distance(&S, p, NULL) < 0.0) != (w > 0.5)) bad_h++;
  }
  printf("demo surface, 10 triangles removed: %zu open edges, hierarchical "
         "vs direct winding worst %.2e\n", S.open_edges, worst_h);
  CHECK(bad_h == 0);
  mx_surface_index_free(&S);
  mx_trisoup_free(&s);
}

static void test_shells(void) {
  mx_trisoup s;
  mx_surface_index S;
  const size_t n = scaled(20000);
  {
    /* Cube in a cube, both outward: the inner one becomes a hole. */
    const box b[2] = {{{0, 0, 0}, {1, 1, 1}}, {{0.3, 0.25, 0.4}, {0.7, 0.6, 0.8}}};
    const int in[2] = {0, 0};
    soup_of_boxes(&s, b, in, 2);
    CHECK(mx_surface_index_build(&S, &s, 0, (uint32_t)s.nt) == MX_OK);
    CHECK(S.nshells == 2 && S.nflipped == 1 && S.closed);
    check_boxes("nested cubes (inner outward)", b, 2, &S, n, 1e-12);
    mx_surface_index_free(&S);
    mx_trisoup_free(&s);
  }
  {
    /* The same with the hole already inward: nothing flipped. */
    const box b[2] = {{{0, 0, 0}, {1, 1, 1}}, {{0.3, 0.25, 0.4}, {0.7, 0.6, 0.8}}};
    const int in[2] = {0, 1};
    soup_of_boxes(&s, b, in, 2);
    CHECK(mx_surface_index_build(&S, &s, 0, (uint32_t)s.nt) == MX_OK);
    CHECK(S.nshells == 2 && S.nflipped == 0);
    check_boxes("nested cubes (inner inward)", b, 2, &S, n, 1e-12);
    mx_surface_index_free(&S);
    mx_trisoup_free(&s);
  }
  {
    /* Island in a hole, outer shell inverted, plus a separate inverted body:
     * depths 0, 1, 2, 0: shells 0 and 1 and 3 are flipped. */
    const box b[4] = {{{0, 0, 0}, {1, 1, 1}},
                      {{0.2, 0.2, 0.2}, {0.8, 0.8, 0.8}},
                      {{0.35, 0.3, 0.4}, {0.6, 0.65, 0.55}},
                      {{1.5, 0.1, 0.2}, {2.0, 0.7, 0.5}}};
    const int in[4] = {1, 0, 0, 1};
    soup_of_boxes(&s, b, in, 4);
    CHECK(mx_surface_index_build(&S, &s, 0, (uint32_t)s.nt) == MX_OK);
    CHECK(S.nshells == 4 && S.nflipped == 3 && S.closed);
    check_boxes("island in a hole + separate body", b, 4, &S, n, 1e-12);
    mx_surface_index_free(&S);
    mx_trisoup_free(&s);
  }
  {
    /* One inverted cube. */
    const box b = {{-1, -2, -3}, {1, 0.5, 0}};
    const int in = 1;
    soup_of_boxes(&s, &b, &in, 1);
    CHECK(mx_surface_index_build(&S, &s, 0, (uint32_t)s.nt) == MX_OK);
    CHECK(S.nshells == 1 && S.nflipped == 1 && S.nreoriented == 0);
    check_boxes("inverted cube", &b, 1, &S, n, 1e-12);
    mx_surface_index_free(&S);
    mx_trisoup_free(&s);
  }
  for (int which = 0; which < 2; which++) {
    /* One triangle reversed (the BFS seed, or another): reoriented. */
    const box b = {{0, 0, 0}, {1, 1, 1}};
    const int in = 0;
    soup_of_boxes(&s, &b, &in, 1);
    uint32_t *t = s.tri + 3 * (which ? 7 : 0), tmp = t[1];
    t[1] = t[2];
    t[2] = tmp;
    CHECK(mx_surface_index_build(&S, &s, 0, (uint32_t)s.nt) == MX_OK);
    CHECK(S.nshells == 1 && S.nflipped == 0 && S.nreoriented == 1);
    CHECK(S.closed == 1 && S.conflict_edges == 0);
    check_boxes("cube with a reversed triangle", &b, 1, &S, n, 1e-12);
    mx_surface_index_free(&S);
    mx_trisoup_free(&s);
  }
}

static void test_open_cube(void) {
  /* Triangle 0 (half of the z = 0 face) left out: 3 open edges, the
   * winding number classifies the points farther than 0.3 from that face
   * (the missing triangle's solid angle is then below 2 pi). */
  const box b = {{0, 0, 0}, {1, 1, 1}};
  const int in = 0;
  mx_trisoup s;
  soup_of_boxes(&s, &b, &in, 1);
  mx_surface_index S;
  CHECK(mx_surface_index_build(&S, &s, 1, (uint32_t)s.nt) == MX_OK);
  CHECK(S.open_edges == 3);
  CHECK(S.nonmanifold_edges == 0);
  CHECK(S.closed == 0);
  CHECK(S.nshells == 1 && S.nflipped == 0);
  size_t n = scaled(20000), used = 0, bad = 0, bad_h = 0;
  for (size_t k = 0; k < n; k++) {
    double p[3];
    for (int a = 0; a < 3; a++) p[a] = uniform(-0.5, 1.5);
    const double dx = mx_max(0.0, mx_max(-p[0], p[0] - 1));
    const double dy = mx_max(0.0, mx_max(-p[1], p[1] - 1));
    if (dx * dx + dy * dy + p[2] * p[2] <= 0.09) continue;
    used++;
    const double want = box_sd(&b, p);
    if (fabs(want) < 1e-9) continue;
    if (mx_inside(&S, p) != (want < 0.0)) bad++;
    if ((mx_signed_distance(&S, p, NULL) < 0.0) != (want < 0.0)) bad++;
    if (!(fabs(mx_winding_number(&S, p) - mx_winding_number_direct(&S, p)) <
          1e-12))
      bad_h++;
  }
  printf("open cube: %zu open edges, %zu points classified, %zu bad\n",
         S.open_edges, used, bad);
  CHECK(bad == 0);
  CHECK(bad_h == 0);
  mx_surface_index_free(&S);
  mx_trisoup_free(&s);
}

static void test_scales(void) {
  /* Tiny and huge cubes: the float bounds are skipped (every triangle is
   * tested) where they would not be safe; the results stay exact. */
  const double sc[6] = {1e-35, 1e-20, 1e-12, 1e12, 1e20, 1e35};
  for (int i = 0; i < 6; i++) {
    const box b = {{-sc[i], 0, 0}, {sc[i], 2 * sc[i], 0.5 * sc[i]}};
    const int in = 0;
    mx_trisoup s;
    soup_of_boxes(&s, &b, &in, 1);
    mx_surface_index S;
    CHECK(mx_surface_index_build(&S, &s, 0, (uint32_t)s.nt) == MX_OK);
    size_t bad = 0;
    for (int k = 0; k < 2000; k++) {
      const double p[3] = {uniform(-2, 2) * sc[i], uniform(-1, 3) * sc[i],
                           uniform(-1, 1.5) * sc[i]};
      const double want = box_sd(&b, p), got = mx_signed_distance(&S, p, NULL);
      if (!(fabs(want - got) <= 1e-12 * sc[i])) bad++;
    }
    printf("cube of size %g: %zu bad\n", sc[i], bad);
    CHECK(bad == 0);
    mx_surface_index_free(&S);
    mx_trisoup_free(&s);
  }
}

static void test_cortex(void) {
  mx_trisoup s;
  if (!load_shared_surface("cortex.off", &s)) return;
  mx_surface_index S;
  double t = mx_wtime();
  CHECK(mx_surface_index_build(&S, &s, 0, (uint32_t)s.nt) == MX_OK);
  t = mx_wtime() - t;
  printf("cortex: %zu triangles, index built in %.1f ms: %u shells, %u "
         "flipped, %zu reoriented, %zu open edges, closed %d\n", s.nt,
         1e3 * t, S.nshells, S.nflipped, S.nreoriented, S.open_edges,
         S.closed);
  CHECK(S.closed == 1);
  mx_locator L;
  CHECK(mx_locator_build(&L, &s, 0, (uint32_t)s.nt) == MX_OK);
  double lo[3], hi[3];
  mx_trisoup_bbox(&s, lo, hi);
  const size_t n = scaled(100000);
  double *pts = malloc(3 * n * sizeof *pts);
  for (size_t k = 0; k < n; k++)
    for (int a = 0; a < 3; a++) {
      const double m = 0.05 * (hi[a] - lo[a]);
      pts[3 * k + a] = uniform(lo[a] - m, hi[a] + m);
    }
  size_t used = 0, bad = 0, bad_w = 0, nin = 0;
  for (size_t k = 0; k < n; k++) {
    const double *p = pts + 3 * k;
    const double d = mx_signed_distance(&S, p, NULL);
    if (fabs(d) <= 1e-6) continue;
    used++;
    const int in = mx_inside(&S, p);
    nin += (size_t)in;
    if (in != mx_locate(&L, p) || in != (d < 0.0)) bad++;
    if (k % 50 == 0 && (mx_winding_number(&S, p) > 0.5) != in) bad_w++;
  }
  printf("cortex: %zu points (%zu inside): %zu disagree with the ray-parity "
         "locator, %zu with the winding number\n", used, nin, bad, bad_w);
  CHECK(bad == 0);
  CHECK(bad_w == 0);
  CHECK(nin > used / 20);
  check_against_brute("cortex", &s, &S, scaled(4000));
  /* Speed: 1M signed distances, one thread, then all threads. */
  const size_t nq = quick ? 20000 : 1000000;
  double sum = 0.0;
  t = mx_wtime();
  for (size_t k = 0; k < nq; k++)
    sum += mx_signed_distance(&S, pts + 3 * (k % n), NULL);
  t = mx_wtime() - t;
  printf("cortex: %zu signed distances on one thread in %.3f s (%.0f ns "
         "each; checksum %.6g)\n", nq, t, 1e9 * t / (double)nq, sum);
  double sum2 = 0.0;
  t = mx_wtime();
#pragma omp parallel for reduction(+ : sum2) schedule(static)
  for (size_t k = 0; k < nq; k++)
    sum2 += mx_signed_distance(&S, pts + 3 * (k % n), NULL);
  t = mx_wtime() - t;
  printf("cortex: the same on %d threads in %.3f s\n", omp_get_max_threads(),
         t);
  CHECK(fabs(sum - sum2) <= 1e-9 * fabs(sum));
  const size_t nw = quick ? 200 : 20000;
  t = mx_wtime();
  for (size_t k = 0; k < nw; k++) sum += mx_winding_number(&S, pts + 3 * k);
  t = mx_wtime() - t;
  printf("cortex: %zu winding numbers in %.3f s (%.1f us each)\n", nw, t,
         1e6 * t / (double)nw);
  free(pts);
  mx_locator_free(&L);
  mx_surface_index_free(&S);
  mx_trisoup_free(&s);
}

/* The block queries (mx_inside_block, mx_closest_point_block) against the
 * single ones on the index S: clusters of 40 points (more than a block)
 * within `spread` of a point of the box lo..hi grown by 5 %, clusters of
 * points far apart (loose blocks), and points on lattice planes through the
 * box's middle (ties between triangles at the same distance, for the
 * cubes); rmax infinite, then about the distances. The same states, and
 * bit for bit the same distances and points below rmax. */
static void check_blocks(const char *name, const mx_surface_index *S, const double lo[3],
                         const double hi[3], double spread) {
  enum { C = 40, NCL = 400 };
  double *xyz = malloc(3 * C * sizeof *xyz);
  uint32_t ids[C];
  uint8_t in[C];
  double rmax[C], dist[C], q[C][3];
  size_t n = 0, in_bad = 0, d_bad = 0, below = 0;
  for (int cl = 0; cl < NCL; cl++) {
    const int kind = cl % 4; /* 0, 1: cluster; 2: far apart; 3: on middle planes */
    double c[3];
    for (int a = 0; a < 3; a++) {
      const double m = 0.05 * (hi[a] - lo[a]);
      c[a] = uniform(lo[a] - m, hi[a] + m);
    }
    for (int i = 0; i < C; i++) {
      ids[i] = (uint32_t)(C - 1 - i); /* (not in order: the ids name the points) */
      for (int a = 0; a < 3; a++) {
        const double m = 0.05 * (hi[a] - lo[a]);
        double x = kind == 2 ? uniform(lo[a] - m, hi[a] + m) : c[a] + uniform(-spread, spread);
        if (kind == 3 && a == i % 3) x = 0.5 * (lo[a] + hi[a]);
        xyz[3 * i + a] = x;
      }
    }
    for (int pass = 0; pass < 2; pass++) {
      for (int i = 0; i < C; i++)
        rmax[i] = pass == 0 ? INFINITY
                            : fabs(mx_signed_distance(S, xyz + 3 * (size_t)ids[i], NULL)) *
                                  (i % 2 ? 1.5 : 0.5);
      if (pass == 0) mx_inside_block(S, xyz, ids, C, in, NULL, 0.0);
      mx_closest_point_block(S, xyz, ids, C, rmax, dist, q);
      for (int i = 0; i < C; i++) {
        const double *p = xyz + 3 * (size_t)ids[i];
        if (pass == 0) in_bad += in[i] != (uint8_t)mx_inside(S, p);
        double q1[3];
        const double d1 = mx_closest_point_within(S, p, rmax[i], q1);
        if (d1 < rmax[i]) {
          below++;
          d_bad += memcmp(&d1, &dist[i], sizeof d1) != 0 || memcmp(q1, q[i], sizeof q1) != 0;
        } else {
          d_bad += dist[i] < rmax[i];
        }
        n++;
      }
    }
  }
  printf("%s: %zu block queries (%zu below rmax): %zu states and %zu closest points differ "
         "from the single queries\n", name, n, below, in_bad, d_bad);
  CHECK(in_bad == 0 && d_bad == 0 && below > n / 4);
  free(xyz);
}

static void test_blocks(void) {
  {
    const box b[2] = {{{0, 0, 0}, {1, 1, 1}}, {{0.3, 0.25, 0.4}, {0.7, 0.6, 0.8}}};
    const int in[2] = {0, 0};
    mx_trisoup s;
    mx_surface_index S;
    soup_of_boxes(&s, b, in, 1);
    CHECK(mx_surface_index_build(&S, &s, 0, (uint32_t)s.nt) == MX_OK);
    check_blocks("blocks, unit cube", &S, b[0].lo, b[0].hi, 0.05);
    mx_surface_index_free(&S);
    mx_trisoup_free(&s);
    soup_of_boxes(&s, b, in, 2);
    CHECK(mx_surface_index_build(&S, &s, 0, (uint32_t)s.nt) == MX_OK);
    check_blocks("blocks, nested cubes", &S, b[0].lo, b[0].hi, 0.05);
    mx_surface_index_free(&S);
    mx_trisoup_free(&s);
  }
  mx_trisoup s;
  if (!load_shared_surface("cortex.off", &s)) return;
  mx_surface_index S;
  CHECK(mx_surface_index_build(&S, &s, 0, (uint32_t)s.nt) == MX_OK);
  double lo[3], hi[3];
  mx_trisoup_bbox(&s, lo, hi);
  check_blocks("blocks, cortex", &S, lo, hi, 0.01 * (hi[0] - lo[0]));
  mx_surface_index_free(&S);
  mx_trisoup_free(&s);
}

static void test_empty(void) {
  mx_trisoup s;
  memset(&s, 0, sizeof s);
  const box b = {{0, 0, 0}, {1, 1, 1}};
  add_box(&s, b.lo, b.hi, 0);
  mx_surface_index S;
  CHECK(mx_surface_index_build(&S, &s, 5, 5) == MX_OK);
  const double p[3] = {0.5, 0.5, 0.5};
  CHECK(mx_inside(&S, p) == 0);
  CHECK(isinf(mx_signed_distance(&S, p, NULL)));
  CHECK(mx_winding_number(&S, p) == 0.0);
  mx_surface_index_free(&S);
  printf("expect an error message about a bad range:\n");
  fflush(stdout);
  CHECK(mx_surface_index_build(&S, &s, 5, 13) == MX_EINPUT);
  mx_trisoup_free(&s);
}

/* Nested shells turned outward (several materials, issue 26): three nested
 * boxes, one of them given inward, and a box beside the middle one inside
 * the outer one. Each shell's depth is the number of boxes around it; a
 * point's region depth the number of boxes it is in (direct count below);
 * the domain is the outer box whole (the nested boxes are not holes). */
static void test_region_depth(void) {
  static const double box[4][6] = {{0, 0, 0, 10, 10, 10},
                                   {2, 2, 2, 7, 8, 8},
                                   {4, 4, 4, 6, 6, 6},
                                   {8, 1, 1, 9.5, 3, 2}};
  mx_trisoup s;
  memset(&s, 0, sizeof s);
  for (int b = 0; b < 4; b++) add_box(&s, box[b], box[b] + 3, b == 1);
  mx_surface_index S;
  CHECK(mx_surface_index_build_outward(&S, &s, 0, (uint32_t)s.nt) == MX_OK);
  CHECK(S.nshells == 4);
  CHECK(S.closed == 0);
  /* the depth of each box's shell: boxes 1 and 3 inside box 0, 2 inside 1 */
  static const uint32_t want_depth[4] = {0, 1, 2, 1};
  for (uint32_t t = 0; t < S.nt; t++) {
    const uint32_t b = S.tri_id[t] / 12, c = S.shell_of[t];
    CHECK(S.shell_depth[c] == want_depth[b]);
  }
  uint64_t seed = 7;
  int wrong = 0, wrong_inside = 0;
  for (int i = 0; i < 4000; i++) {
    double p[3];
    for (int a = 0; a < 3; a++) {
      seed = seed * 6364136223846793005ull + 1442695040888963407ull;
      p[a] = -1.0 + 12.0 * (double)(seed >> 11) / 9007199254740992.0;
    }
    int n = 0, on = 0;
    for (int b = 0; b < 4; b++) {
      int in = 1;
      for (int a = 0; a < 3; a++) {
        in &= p[a] > box[b][a] && p[a] < box[b][3 + a];
        on |= fabs(p[a] - box[b][a]) < 1e-9 || fabs(p[a] - box[b][3 + a]) < 1e-9;
      }
      n += in;
    }
    if (on) continue;
    wrong += mx_region_depth(&S, p) != n;
    wrong_inside += mx_inside(&S, p) != (n > 0);
  }
  CHECK(wrong == 0);
  CHECK(wrong_inside == 0);
  /* the nesting index keeps its meaning: the middle box is a hole */
  mx_surface_index P;
  CHECK(mx_surface_index_build(&P, &s, 0, (uint32_t)s.nt) == MX_OK);
  const double in_middle[3] = {3, 3, 3}, in_inner[3] = {5, 5, 5};
  CHECK(mx_inside(&P, in_middle) == 0);
  CHECK(mx_inside(&P, in_inner) == 1);
  CHECK(mx_region_depth(&S, in_middle) == 2 && mx_region_depth(&S, in_inner) == 3);
  printf("region depth: 4 shells of depths 0 1 2 1, %d point(s) wrong, %d wrongly located\n",
         wrong, wrong_inside);
  mx_surface_index_free(&P);
  mx_surface_index_free(&S);
  mx_trisoup_free(&s);
}

int main(int argc, char **argv) {
  quick = argc > 1 && strcmp(argv[1], "quick") == 0;
  (void)no_requests; /* from octree_util.h, unused here */
  test_unit_cube();
  test_demo_surface();
  test_shells();
  test_region_depth();
  test_open_cube();
  test_empty();
  test_scales();
  test_cortex();
  test_blocks();
  return TEST_DONE();
}
