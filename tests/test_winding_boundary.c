/* Tests of the boundary of the winding number's domain
 * (src/kernels/winding_boundary.c) and of the index with the orientation as
 * given (mx_surface_index_build_given, src/geom/distance.c), on boxes
 * built in code: touching (welded or not), overlapping (coplanar faces, or
 * crossing ones), nested with the inner box inward (a cavity); the kept
 * pieces' area and signed volume are those of the union, in either order of
 * the bodies, and the same for 1 and 2 threads. */
#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <string.h>

#include "check.h"
#include "base/common.h"
#include "geom/distance.h"
#include "geom/surface_defects.h"
#include "kernels/winding_boundary.h"
#include "soa/trisoup.h"

/* Faces of a box, corners i = x + 2y + 4z, counter-clockwise from outside. */
static const int box_faces[6][4] = {{0, 4, 6, 2}, {1, 3, 7, 5}, {0, 1, 5, 4},
                                    {2, 6, 7, 3}, {0, 2, 3, 1}, {4, 5, 7, 6}};

static uint32_t vertex(mx_trisoup *s, const double p[3], int weld) {
  if (weld)
    for (size_t i = 0; i < s->nv; i++)
      if (s->x[i] == p[0] && s->y[i] == p[1] && s->z[i] == p[2]) return (uint32_t)i;
  CHECK(mx_trisoup_set_vertex(s, s->nv, p) == MX_OK);
  return (uint32_t)(s->nv - 1);
}

/* The box [lo, lo + size] (12 triangles; inward when inward is set). */
static void add_box(mx_trisoup *s, const double lo[3], double size, int weld, int inward) {
  uint32_t v[8];
  for (int i = 0; i < 8; i++) {
    const double p[3] = {lo[0] + (i & 1 ? size : 0.0), lo[1] + (i & 2 ? size : 0.0),
                         lo[2] + (i & 4 ? size : 0.0)};
    v[i] = vertex(s, p, weld);
  }
  for (int f = 0; f < 6; f++) {
    const int *q = box_faces[f];
    const uint32_t a = v[q[0]], b = v[q[inward ? 3 : 1]], c = v[q[2]], d = v[q[inward ? 1 : 3]];
    CHECK(mx_trisoup_add_triangle(s, a, b, c) == MX_OK);
    CHECK(mx_trisoup_add_triangle(s, a, c, d) == MX_OK);
  }
}

static void measure(const mx_trisoup *s, double *vol, double *area) {
  *vol = *area = 0.0;
  for (size_t t = 0; t < s->nt; t++) {
    const uint32_t *v = s->tri + 3 * t;
    const double a[3] = {s->x[v[0]], s->y[v[0]], s->z[v[0]]};
    const double b[3] = {s->x[v[1]] - a[0], s->y[v[1]] - a[1], s->z[v[1]] - a[2]};
    const double c[3] = {s->x[v[2]] - a[0], s->y[v[2]] - a[1], s->z[v[2]] - a[2]};
    const double n[3] = {b[1] * c[2] - b[2] * c[1], b[2] * c[0] - b[0] * c[2],
                         b[0] * c[1] - b[1] * c[0]};
    *vol += (a[0] * n[0] + a[1] * n[1] + a[2] * n[2]) / 6.0;
    *area += 0.5 * sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
  }
}

typedef struct {
  double lo[3], size;
  int inward;
} box;

/* The bodies in the order given; checks the union's volume and area, the
 * winding number at probe (want_w), and returns the stats. */
static mx_winding_boundary_stats run(const char *what, const box *b, int nb, int weld,
                                     double want_vol, double want_area,
                                     const double probe[3], double want_w,
                                     mx_trisoup *keep) {
  mx_trisoup s, out;
  memset(&s, 0, sizeof s);
  memset(&out, 0, sizeof out);
  for (int i = 0; i < nb; i++) add_box(&s, b[i].lo, b[i].size, weld, b[i].inward);
  /* the pairs the cutting uses are the defect finder's */
  {
    mx_surface_defects r;
    uint64_t *pairs = NULL;
    size_t np = 0;
    CHECK(mx_surface_defects_find(&s, &r) == MX_OK);
    CHECK(mx_surface_meeting_pairs(&s, &pairs, &np) == MX_OK);
    CHECK(np == r.intersecting_pairs + r.crossing_pairs);
    for (size_t k = 0; k + 1 < np; k++) CHECK(pairs[k] < pairs[k + 1]);
    mx_free(pairs);
  }
  mx_surface_index W;
  CHECK(mx_surface_index_build_given(&W, &s, 0, (uint32_t)s.nt) == MX_OK);
  CHECK(W.closed == 0);
  const double w = mx_winding_number(&W, probe);
  mx_winding_boundary_stats st;
  memset(&st, 0, sizeof st);
  CHECK(mx_winding_boundary(&s, &W, &out, &st) == MX_OK);
  double vol, area;
  measure(&out, &vol, &area);
  printf("%-34s w %.6f  volume %.12g (%g)  area %.12g (%g)  pieces %zu kept %zu inside %zu "
         "copies %zu cut %zu\n", what, w, vol, want_vol, area, want_area, st.pieces, st.kept,
         st.inside, st.copies, st.cut);
  CHECK(fabs(w - want_w) < 1e-9);
  CHECK(fabs(vol - want_vol) < 1e-9);
  CHECK(fabs(area - want_area) < 1e-9);
  CHECK(fabs(st.area - want_area) < 1e-9);
  CHECK(st.capped == 0);
  CHECK(out.nshells == s.nshells);
  if (keep) {
    *keep = out;
  } else {
    mx_trisoup_free(&out);
  }
  mx_surface_index_free(&W);
  mx_trisoup_free(&s);
  return st;
}

/* The same bodies both ways round. */
static void both_orders(const char *what, box x, box y, int weld, double vol, double area,
                        const double probe[3], double w) {
  char name[64];
  const box xy[2] = {x, y}, yx[2] = {y, x};
  snprintf(name, sizeof name, "%s", what);
  run(name, xy, 2, weld, vol, area, probe, w, NULL);
  snprintf(name, sizeof name, "%s, reversed", what);
  run(name, yx, 2, weld, vol, area, probe, w, NULL);
}

int main(void) {
  const box A = {{0, 0, 0}, 1, 0}, B = {{1, 0, 0}, 1, 0}, C = {{0.5, 0.5, 0.5}, 1, 0},
            D = {{0.5, 0, 0}, 1, 0};
  const double in_b[3] = {1.5, 0.5, 0.5},
               both[3] = {0.75, 0.75, 0.75};
  /* touching along x = 1: the shared face is inside the union, dropped */
  both_orders("touching, welded", A, B, 1, 2.0, 10.0, in_b, 1.0);
  both_orders("touching, not welded", A, B, 0, 2.0, 10.0, in_b, 1.0);
  /* overlapping by half along x: faces y = 0, 1 and z = 0, 1 overlap
   * coplanar (kept once), x = 1 of A and x = 0.5 of D inside */
  both_orders("overlapping along x", A, D, 0, 1.5, 8.0, both, 2.0);
  /* overlapping by (0.5, 0.5, 0.5): faces cut in quarters, 3 of each
   * cube's inside the other */
  both_orders("overlapping corner", A, C, 0, 1.875, 10.5, both, 2.0);
  /* a cavity: the inner box inward stays a hole (orientation as given;
   * never flipped for its nesting) */
  {
    const box hollow[2] = {{{0, 0, 0}, 1, 0}, {{0.25, 0.25, 0.25}, 0.5, 1}};
    const double centre[3] = {0.5, 0.5, 0.5};
    run("cavity", hollow, 2, 0, 0.875, 7.5, centre, 0.0, NULL);
  }
  /* a box inside another, both outward: winding number 2, a union (the
   * inner box bounds nothing) */
  {
    const box nested[2] = {{{0, 0, 0}, 1, 0}, {{0.25, 0.25, 0.25}, 0.5, 0}};
    const double centre[3] = {0.5, 0.5, 0.5};
    mx_winding_boundary_stats st = run("nested, both outward", nested, 2, 0, 1.0, 6.0, centre,
                                       2.0, NULL);
    CHECK(st.inside == 12);
  }
  /* one box turned inside out: the domain empty, nothing kept */
  {
    const box out[1] = {{{0, 0, 0}, 1, 1}};
    const double centre[3] = {0.5, 0.5, 0.5};
    mx_winding_boundary_stats st = run("inside out", out, 1, 0, 0.0, 0.0, centre, -1.0, NULL);
    CHECK(st.kept == 0 && st.outside == 12);
  }
  /* 1 and 2 threads: the same output */
  {
    const box ac[2] = {A, C};
    mx_trisoup o1, o2;
    const int nth = omp_get_max_threads();
    omp_set_num_threads(1);
    run("corner, 1 thread", ac, 2, 0, 1.875, 10.5, both, 2.0, &o1);
    omp_set_num_threads(2);
    run("corner, 2 threads", ac, 2, 0, 1.875, 10.5, both, 2.0, &o2);
    omp_set_num_threads(nth);
    CHECK(o1.nv == o2.nv && o1.nt == o2.nt);
    if (o1.nv == o2.nv && o1.nt == o2.nt) {
      CHECK(memcmp(o1.x, o2.x, o1.nv * sizeof *o1.x) == 0);
      CHECK(memcmp(o1.tri, o2.tri, 3 * o1.nt * sizeof *o1.tri) == 0);
    }
    mx_trisoup_free(&o1);
    mx_trisoup_free(&o2);
  }
  return TEST_DONE();
}
