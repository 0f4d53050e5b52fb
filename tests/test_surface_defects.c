/* Tests of the surface defect finder and the orientation repair
 * (src/geom/surface_defects.c): surfaces built in code with known
 * defects (counts asserted exactly where they are known), exact touching
 * versus one-ulp misses, independence from the thread count, and the
 * shared sample surfaces when present. */
#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "check.h"
#include "base/common.h"
#include "geom/surface_defects.h"
#include "soa/trisoup.h"
#include "io/read_surface.h"
#include "io/demo_surface.h"

/* ---- building surfaces ----------------------------------------------- */

/* Vertex with these coordinates, reused if already present (welds). */
static uint32_t vtx(mx_trisoup *s, double x, double y, double z) {
  for (size_t i = 0; i < s->nv; i++)
    if (s->x[i] == x && s->y[i] == y && s->z[i] == z) return (uint32_t)i;
  const double c[3] = {x, y, z};
  CHECK(mx_trisoup_set_vertex(s, s->nv, c) == MX_OK);
  return (uint32_t)(s->nv - 1);
}

static void tri(mx_trisoup *s, uint32_t a, uint32_t b, uint32_t c) {
  CHECK(mx_trisoup_add_triangle(s, a, b, c) == MX_OK);
}

static void tri_pts(mx_trisoup *s, const double *a, const double *b,
                    const double *c) {
  tri(s, vtx(s, a[0], a[1], a[2]), vtx(s, b[0], b[1], b[2]),
      vtx(s, c[0], c[1], c[2]));
}

/* Faces of the unit cube, corners i = x + 2y + 4z, counter-clockwise seen
 * from outside; face f gives triangles (q0 q1 q2) and (q0 q2 q3). */
static const int cube_faces[6][4] = {{0, 4, 6, 2}, {1, 3, 7, 5}, {0, 1, 5, 4},
                                     {2, 6, 7, 3}, {0, 2, 3, 1}, {4, 5, 7, 6}};

/* The box [lo, hi] (12 triangles, outward), welded to the soup's vertices;
 * skip_face >= 0 leaves that face out. */
static void add_box(mx_trisoup *s, const double lo[3], const double hi[3],
                    int skip_face) {
  uint32_t v[8];
  for (int i = 0; i < 8; i++)
    v[i] = vtx(s, i & 1 ? hi[0] : lo[0], i & 2 ? hi[1] : lo[1],
               i & 4 ? hi[2] : lo[2]);
  for (int f = 0; f < 6; f++) {
    if (f == skip_face) continue;
    const int *q = cube_faces[f];
    tri(s, v[q[0]], v[q[1]], v[q[2]]);
    tri(s, v[q[0]], v[q[2]], v[q[3]]);
  }
}

static void flip_tri(mx_trisoup *s, size_t t) {
  uint32_t x = s->tri[3 * t + 1];
  s->tri[3 * t + 1] = s->tri[3 * t + 2];
  s->tri[3 * t + 2] = x;
}

/* Six times the enclosed volume (sum of det(a, b, c)). */
static double volume6(const mx_trisoup *s) {
  double v = 0.0;
  for (size_t t = 0; t < s->nt; t++) {
    const uint32_t *i = s->tri + 3 * t;
    double a[3] = {s->x[i[0]], s->y[i[0]], s->z[i[0]]};
    double b[3] = {s->x[i[1]], s->y[i[1]], s->z[i[1]]};
    double c[3] = {s->x[i[2]], s->y[i[2]], s->z[i[2]]};
    v += a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) +
         a[2] * (b[0] * c[1] - b[1] * c[0]);
  }
  return v;
}

/* A soup made of several, each its own input (shell). */
static void append_free(mx_trisoup *all, mx_trisoup *part) {
  CHECK(mx_trisoup_append(all, part) == MX_OK);
  mx_trisoup_free(part);
}

static void tetra(mx_trisoup *s, const double o[3], double h) {
  uint32_t a = vtx(s, o[0], o[1], o[2]), b = vtx(s, o[0] + h, o[1], o[2]);
  uint32_t c = vtx(s, o[0], o[1] + h, o[2]), d = vtx(s, o[0], o[1], o[2] + h);
  tri(s, a, c, b);
  tri(s, a, b, d);
  tri(s, a, d, c);
  tri(s, b, c, d);
}

/* Geodesic sphere: icosahedron 4-split `subdiv` times, on radius r, centre
 * o, outward. Midpoints are shared through an open-addressing table. */
static void icosphere(mx_trisoup *s, int subdiv, double r, const double o[3]) {
  const double p = 0.5 * (1.0 + sqrt(5.0));
  static const int f20[20][3] = {
      {0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
      {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
      {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
      {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  const double v12[12][3] = {{-1, p, 0}, {1, p, 0},  {-1, -p, 0}, {1, -p, 0},
                             {0, -1, p}, {0, 1, p},  {0, -1, -p}, {0, 1, -p},
                             {p, 0, -1}, {p, 0, 1},  {-p, 0, -1}, {-p, 0, 1}};
  mx_trisoup m = {0};
  for (int i = 0; i < 12; i++) CHECK(mx_trisoup_set_vertex(&m, i, v12[i]) == MX_OK);
  for (int f = 0; f < 20; f++) tri(&m, f20[f][0], f20[f][1], f20[f][2]);
  for (int l = 0; l < subdiv; l++) {
    size_t cap = 16;
    while (cap < 6 * m.nt) cap *= 2;
    uint64_t *key = malloc(cap * sizeof *key);
    uint32_t *val = malloc(cap * sizeof *val);
    for (size_t i = 0; i < cap; i++) key[i] = UINT64_MAX;
    mx_trisoup n = {0};
    for (size_t i = 0; i < m.nv; i++) {
      double c[3] = {m.x[i], m.y[i], m.z[i]};
      CHECK(mx_trisoup_set_vertex(&n, i, c) == MX_OK);
    }
    for (size_t t = 0; t < m.nt; t++) {
      uint32_t v[3], mid[3];
      for (int k = 0; k < 3; k++) v[k] = m.tri[3 * t + k];
      for (int k = 0; k < 3; k++) {
        uint32_t a = v[k], b = v[(k + 1) % 3];
        uint64_t kk = a < b ? (uint64_t)a << 32 | b : (uint64_t)b << 32 | a;
        size_t h = (size_t)((kk * 0x9e3779b97f4a7c15ull) >> 20) & (cap - 1);
        while (key[h] != UINT64_MAX && key[h] != kk) h = (h + 1) & (cap - 1);
        if (key[h] == UINT64_MAX) {
          double c[3] = {0.5 * (m.x[a] + m.x[b]), 0.5 * (m.y[a] + m.y[b]),
                         0.5 * (m.z[a] + m.z[b])};
          key[h] = kk;
          val[h] = (uint32_t)n.nv;
          CHECK(mx_trisoup_set_vertex(&n, n.nv, c) == MX_OK);
        }
        mid[k] = val[h];
      }
      tri(&n, v[0], mid[0], mid[2]);
      tri(&n, v[1], mid[1], mid[0]);
      tri(&n, v[2], mid[2], mid[1]);
      tri(&n, mid[0], mid[1], mid[2]);
    }
    free(key);
    free(val);
    mx_trisoup_free(&m);
    m = n;
  }
  uint32_t off = (uint32_t)s->nv;
  for (size_t i = 0; i < m.nv; i++) {
    double l = sqrt(m.x[i] * m.x[i] + m.y[i] * m.y[i] + m.z[i] * m.z[i]);
    double c[3] = {o[0] + r * m.x[i] / l, o[1] + r * m.y[i] / l,
                   o[2] + r * m.z[i] / l};
    CHECK(mx_trisoup_set_vertex(s, off + i, c) == MX_OK);
  }
  for (size_t t = 0; t < m.nt; t++)
    tri(s, off + m.tri[3 * t], off + m.tri[3 * t + 1], off + m.tri[3 * t + 2]);
  mx_trisoup_free(&m);
}

static mx_surface_defects find(const mx_trisoup *s) {
  mx_surface_defects r;
  CHECK(mx_surface_defects_find(s, &r) == MX_OK);
  return r;
}

static void show(const char *name, const mx_surface_defects *r,
                 const mx_trisoup *s) {
  char buf[2048];
  mx_surface_defects_describe(r, s, buf, sizeof buf);
  printf("-- %s (%zu triangles): %s", name, s->nt, buf);
}

static int only(const mx_surface_defects *r, size_t b, size_t nm, size_t mis,
                size_t in, size_t cr) {
  return r->boundary_edges == b && r->nonmanifold_edges == nm &&
         r->misoriented_edges == mis && r->intersecting_pairs == in &&
         r->crossing_pairs == cr && r->degenerate_triangles == 0;
}

static const double O[3] = {0, 0, 0}, ONE[3] = {1, 1, 1};

/* ---- tests ------------------------------------------------------------ */

static void test_cube(void) {
  mx_trisoup s = {0};
  add_box(&s, O, ONE, -1);
  CHECK(s.nt == 12 && s.nv == 8 && fabs(volume6(&s) - 6.0) < 1e-12);
  mx_surface_defects r = find(&s);
  show("closed cube", &r, &s);
  CHECK(only(&r, 0, 0, 0, 0, 0) && mx_surface_defects_total(&r) == 0);
  char buf[64];
  mx_surface_defects_describe(&r, &s, buf, sizeof buf);
  CHECK(strcmp(buf, "no defects\n") == 0);
  size_t fl = 99;
  CHECK(mx_surface_orient(&s, &fl) == MX_OK && fl == 0);
  mx_trisoup_free(&s);
}

static void test_open_cube(void) {
  mx_trisoup s = {0};
  add_box(&s, O, ONE, 5); /* no top: its 4 sides become open */
  mx_surface_defects r = find(&s);
  show("open cube", &r, &s);
  CHECK(only(&r, 4, 0, 0, 0, 0));
  /* Examples: 4 edges, sorted by triangle, midpoints on z = 1. */
  for (int i = 0; i < 4; i++) {
    CHECK(r.boundary[i].p[2] == 1.0 && r.boundary[i].v0 < r.boundary[i].v1);
    CHECK(r.boundary[i].other == UINT32_MAX);
    if (i) CHECK(r.boundary[i - 1].tri <= r.boundary[i].tri);
  }
  char buf[1024];
  mx_surface_defects_describe(&r, &s, buf, sizeof buf);
  CHECK(strncmp(buf, "4 open edges", 12) == 0 && strchr(buf, '\n') &&
        strchr(buf, '\n')[1] == '\0');
  /* Orientation of an open piece: the minority is flipped. */
  flip_tri(&s, 0);
  size_t fl = 0;
  CHECK(mx_surface_orient(&s, &fl) == MX_OK && fl == 1);
  r = find(&s);
  CHECK(only(&r, 4, 0, 0, 0, 0));
  /* All inside out: an open piece keeps its majority, so nothing flips
   * (the volume of an open surface means little). */
  for (size_t t = 0; t < s.nt; t++) flip_tri(&s, t);
  CHECK(mx_surface_orient(&s, &fl) == MX_OK && fl == 0);
  mx_trisoup_free(&s);
}

static void test_nonmanifold(void) {
  mx_trisoup s = {0};
  const double lo2[3] = {1, 1, 0}, hi2[3] = {2, 2, 1};
  add_box(&s, O, ONE, -1);
  add_box(&s, lo2, hi2, -1); /* shares the edge x = y = 1 */
  CHECK(s.nv == 14);
  mx_surface_defects r = find(&s);
  show("two cubes sharing an edge", &r, &s);
  CHECK(only(&r, 0, 1, 0, 0, 0));
  CHECK(r.nonmanifold[0].p[0] == 1.0 && r.nonmanifold[0].p[1] == 1.0 &&
        r.nonmanifold[0].p[2] == 0.5);
  /* Each cube is a closed piece of its own: orient leaves both alone, or
   * turns an inside-out one. */
  size_t fl = 99;
  CHECK(mx_surface_orient(&s, &fl) == MX_OK && fl == 0);
  for (size_t t = 12; t < 24; t++) flip_tri(&s, t);
  CHECK(mx_surface_orient(&s, &fl) == MX_OK && fl == 12);
  CHECK(fabs(volume6(&s) - 12.0) < 1e-12);
  mx_trisoup_free(&s);

  /* Three triangles on one edge: 1 non-manifold, 6 open edges. */
  const double a[3] = {0, 0, 0}, b[3] = {1, 0, 0}, c[3] = {0, 1, 0},
               d[3] = {0, 0, 1}, e[3] = {0, -1, 1};
  tri_pts(&s, a, b, c);
  tri_pts(&s, b, a, d);
  tri_pts(&s, b, a, e);
  r = find(&s);
  CHECK(only(&r, 6, 1, 0, 0, 0));
  CHECK(r.nonmanifold[0].tri == 0 && r.nonmanifold[0].other == 1);
  mx_trisoup_free(&s);
}

static void test_misoriented(void) {
  mx_trisoup s = {0};
  add_box(&s, O, ONE, -1);
  /* (0 4 6), (1 3 7), (0 1 5): no two share an edge. */
  flip_tri(&s, 0);
  flip_tri(&s, 2);
  flip_tri(&s, 4);
  mx_surface_defects r = find(&s);
  show("cube with 3 flipped triangles", &r, &s);
  CHECK(only(&r, 0, 0, 9, 0, 0));
  CHECK(r.misoriented[0].tri == 0);
  size_t fl = 0;
  CHECK(mx_surface_orient(&s, &fl) == MX_OK && fl == 3);
  r = find(&s);
  CHECK(only(&r, 0, 0, 0, 0, 0));
  CHECK(fabs(volume6(&s) - 6.0) < 1e-12);
  CHECK(mx_surface_orient(&s, &fl) == MX_OK && fl == 0); /* idempotent */

  /* Inside out: consistent, so no misoriented edge, but orient flips all. */
  for (size_t t = 0; t < s.nt; t++) flip_tri(&s, t);
  r = find(&s);
  CHECK(only(&r, 0, 0, 0, 0, 0));
  CHECK(volume6(&s) < 0);
  CHECK(mx_surface_orient(&s, &fl) == MX_OK && fl == 12);
  CHECK(fabs(volume6(&s) - 6.0) < 1e-12);
  mx_trisoup_free(&s);
}

/* A Moebius strip: non-orientable, so a misoriented edge stays. */
static void test_moebius(void) {
  mx_trisoup s = {0};
  const int n = 12;
  for (int i = 0; i < n; i++) {
    double t = 2 * M_PI * i / n;
    for (int side = -1; side <= 1; side += 2) {
      double w = 0.3 * side;
      double c[3] = {(1 + w * cos(t / 2)) * cos(t), (1 + w * cos(t / 2)) * sin(t),
                     w * sin(t / 2)};
      CHECK(mx_trisoup_set_vertex(&s, 2 * i + (side > 0), c) == MX_OK);
    }
  }
  for (int i = 0; i < n; i++) {
    uint32_t a = 2 * i, b = 2 * i + 1, c, d;
    if (i + 1 < n) c = 2 * i + 2, d = 2 * i + 3;
    else c = 1, d = 0; /* the half twist */
    tri(&s, a, c, b);
    tri(&s, b, c, d);
  }
  mx_surface_defects r = find(&s);
  show("Moebius strip", &r, &s);
  CHECK(r.boundary_edges == 2 * n && r.nonmanifold_edges == 0);
  CHECK(r.intersecting_pairs == 0);
  size_t fl;
  CHECK(mx_surface_orient(&s, &fl) == MX_OK);
  r = find(&s);
  CHECK(r.misoriented_edges == 1);
  mx_trisoup_free(&s);
}

static void test_tetrahedra(void) {
  mx_trisoup s = {0};
  const double o2[3] = {0.25, 0.25, 0.25};
  tetra(&s, O, 1.0);
  tetra(&s, o2, 1.0);
  mx_surface_defects r = find(&s);
  show("two overlapping tetrahedra, one input", &r, &s);
  CHECK(r.intersecting_pairs > 0 && r.crossing_pairs == 0);
  CHECK(r.intersecting_bodies == r.intersecting_pairs);
  CHECK(r.boundary_edges == 0 && r.nonmanifold_edges == 0 &&
        r.misoriented_edges == 0);
  /* Every example pairs a triangle of each tetrahedron, at a point of
   * both boxes. */
  size_t m = r.intersecting_pairs < MX_DEFECT_EXAMPLES ? r.intersecting_pairs
                                                       : MX_DEFECT_EXAMPLES;
  for (size_t i = 0; i < m; i++) {
    CHECK(r.intersecting[i].tri < 4 && r.intersecting[i].other >= 4);
    for (int k = 0; k < 3; k++)
      CHECK(r.intersecting[i].p[k] >= 0.25 - 1e-12 && r.intersecting[i].p[k] <= 1.0 + 1e-12);
    if (i) CHECK(r.intersecting[i - 1].tri <= r.intersecting[i].tri);
  }
  char buf[1024];
  mx_surface_defects_describe(&r, &s, buf, sizeof buf);
  CHECK(strstr(buf, "intersect") && strstr(buf, "between separate bodies"));
  mx_trisoup_free(&s);

  /* Apart: nothing. */
  const double o3[3] = {1.5, 0, 0};
  tetra(&s, O, 1.0);
  tetra(&s, o3, 1.0);
  r = find(&s);
  CHECK(only(&r, 0, 0, 0, 0, 0));
  mx_trisoup_free(&s);
}

static void test_shells(void) {
  mx_trisoup all = {0}, a = {0}, b = {0};
  const double lo[3] = {0.5, 0.5, 0.5}, hi[3] = {1.5, 1.5, 1.5};
  add_box(&a, O, ONE, -1);
  add_box(&b, lo, hi, -1);
  append_free(&all, &a);
  append_free(&all, &b);
  mx_surface_defects r = find(&all);
  show("two crossing cubes, two inputs", &r, &all);
  CHECK(r.crossing_pairs > 0 && r.intersecting_pairs == 0);
  CHECK(r.boundary_edges == 0 && r.misoriented_edges == 0);
  CHECK(r.crossing[0].tri < 12 && r.crossing[0].other >= 12);
  char buf[1024];
  mx_surface_defects_describe(&r, &all, buf, sizeof buf);
  CHECK(strstr(buf, "e.g. triangle 2 of input 0 and triangle 4 of input 1 at (1, 0.5, 0.5)"));
  mx_trisoup_free(&all);

  /* Nested: no crossing. */
  const double lo2[3] = {-1, -1, -1}, hi2[3] = {2, 2, 2};
  add_box(&a, O, ONE, -1);
  add_box(&b, lo2, hi2, -1);
  append_free(&all, &b);
  append_free(&all, &a);
  r = find(&all);
  show("cube inside a bigger cube, two inputs", &r, &all);
  CHECK(only(&r, 0, 0, 0, 0, 0));
  mx_trisoup_free(&all);

  /* Touching along a face from outside (the big cube's face is split
   * differently): the inputs touch, which counts. */
  const double lo3[3] = {1, 0, 0}, hi3[3] = {3, 2, 2};
  add_box(&a, O, ONE, -1);
  add_box(&b, lo3, hi3, -1);
  append_free(&all, &a);
  append_free(&all, &b);
  r = find(&all);
  CHECK(r.crossing_pairs > 0 && r.intersecting_pairs == 0);
  mx_trisoup_free(&all);

  /* The same cube twice (two inputs): every triangle lies on its copy;
   * its neighbours' copies share only an edge or a vertex with it. */
  add_box(&a, O, ONE, -1);
  add_box(&b, O, ONE, -1);
  for (size_t t = 0; t < 12; t++) flip_tri(&b, t);
  append_free(&all, &a);
  append_free(&all, &b);
  r = find(&all);
  CHECK(only(&r, 0, 0, 0, 0, 12));
  for (int i = 0; i < MX_DEFECT_EXAMPLES; i++)
    CHECK(r.crossing[i].tri == (uint32_t)i && r.crossing[i].other == (uint32_t)i + 12);
  mx_trisoup_free(&all);
}

/* Pairs of triangles sharing an edge or a vertex. */
static void test_adjacent(void) {
  mx_trisoup s = {0};
  const double a[3] = {0, 0, 0}, b[3] = {1, 0, 0}, c[3] = {0.5, 1, 0};
  const double d[3] = {0.3, 0.5, 0}, e[3] = {0.5, -1, 0}, f[3] = {0.5, 0.5, 1};

  tri_pts(&s, a, b, c);
  tri_pts(&s, b, a, d); /* coplanar, same side of ab: fold-over */
  mx_surface_defects r = find(&s);
  show("fold-over", &r, &s);
  CHECK(only(&r, 4, 0, 0, 1, 0));
  CHECK(r.intersecting[0].tri == 0 && r.intersecting[0].other == 1);
  CHECK(r.intersecting[0].p[2] == 0.0 && r.intersecting[0].p[1] > 0.0);
  char buf[1024];
  mx_surface_defects_describe(&r, &s, buf, sizeof buf);
  CHECK(strstr(buf, "\n1 pair of triangles of one input intersects "
                    "(self-intersection), e.g. triangles 0 and 1 at "
                    "(0.49, 0.075, 0)\n"));
  /* Truncation keeps the string terminated. */
  mx_surface_defects_describe(&r, &s, buf, 10);
  CHECK(strlen(buf) == 9);
  mx_trisoup_free(&s);

  tri_pts(&s, a, b, c);
  tri_pts(&s, b, a, e); /* coplanar, other side: fine */
  r = find(&s);
  CHECK(only(&r, 4, 0, 0, 0, 0));
  mx_trisoup_free(&s);

  tri_pts(&s, a, b, c);
  tri_pts(&s, b, a, f); /* a real fold (not coplanar), however sharp */
  r = find(&s);
  CHECK(only(&r, 4, 0, 0, 0, 0));
  mx_trisoup_free(&s);

  /* Sharing vertex v: the other triangle's far edge pierces the first. */
  const double v[3] = {0, 0, 0}, p[3] = {2, 0, 0}, q[3] = {0, 2, 0};
  const double c1[3] = {0.5, 0.5, -1}, d1[3] = {0.5, 0.5, 1};
  tri_pts(&s, v, p, q);
  tri_pts(&s, v, c1, d1);
  r = find(&s);
  show("neighbour through the interior", &r, &s);
  CHECK(r.intersecting_pairs == 1 && r.intersecting_bodies == 0);
  CHECK(fabs(r.intersecting[0].p[0] - 0.5) < 1e-12 &&
        fabs(r.intersecting[0].p[1] - 0.5) < 1e-12 &&
        fabs(r.intersecting[0].p[2]) < 1e-12);
  mx_trisoup_free(&s);

  /* Sharing v, crossing the first one's plane beside it: fine. */
  const double c2[3] = {-1, 0.5, -1}, d2[3] = {-1, 0.5, 1};
  tri_pts(&s, v, p, q);
  tri_pts(&s, v, c2, d2);
  r = find(&s);
  CHECK(r.intersecting_pairs == 0);
  mx_trisoup_free(&s);

  /* Sharing v, crossing the first one's plane along the segment from v
   * to the midpoint of its edge pq. */
  const double c3[3] = {1, 1, -1}, d3[3] = {1, 1, 1};
  tri_pts(&s, v, p, q);
  tri_pts(&s, v, c3, d3);
  r = find(&s);
  CHECK(r.intersecting_pairs == 1);
  mx_trisoup_free(&s);

  /* Sharing v, coplanar: wedges overlapping, disjoint, or sharing a ray. */
  const double w1[3] = {1, 1, 0}, w2[3] = {-1, 2, 0}, w3[3] = {-1, -1, 0};
  const double w4[3] = {1, -1, 0}, w5[3] = {3, 0, 0};
  tri_pts(&s, v, p, q);
  tri_pts(&s, v, w2, w1); /* overlaps the first around the ray (1, 1) */
  r = find(&s);
  CHECK(r.intersecting_pairs == 1);
  mx_trisoup_free(&s);
  tri_pts(&s, v, p, q);
  tri_pts(&s, v, w3, w4); /* only v in common */
  r = find(&s);
  CHECK(r.intersecting_pairs == 0);
  mx_trisoup_free(&s);
  tri_pts(&s, v, p, q);
  tri_pts(&s, v, w4, w5); /* edges v-p and v-w5 overlap */
  r = find(&s);
  CHECK(r.intersecting_pairs == 1);
  mx_trisoup_free(&s);

  /* Sharing v, an edge of the second lying in the first's plane and
   * inside it (the second stands on the first). */
  const double u1[3] = {0.5, 0.5, 0}, u2[3] = {0, 0, 1};
  tri_pts(&s, v, p, q);
  tri_pts(&s, v, u1, u2);
  r = find(&s);
  CHECK(r.intersecting_pairs == 1);
  mx_trisoup_free(&s);
  /* ... and standing outside it: fine. */
  const double u3[3] = {-0.5, -0.5, 0};
  tri_pts(&s, v, p, q);
  tri_pts(&s, v, u3, u2);
  r = find(&s);
  CHECK(r.intersecting_pairs == 0);
  mx_trisoup_free(&s);

  /* No vertex in common, coplanar, edges on one line: overlapping (1),
   * apart (0); and an edge of one crossing the other's plane inside it
   * while lying in that plane (a segment of the plane). */
  const double h0[3] = {0, 0, 0}, h1[3] = {2, 0, 0}, h2[3] = {0, 1, 0};
  const double k0[3] = {1, 0, 0}, k1[3] = {3, 0, 0}, k2[3] = {2, -1, 0};
  const double k3[3] = {2.5, 0, 0}, k4[3] = {4, 0, 0}, k5[3] = {1, -1, 0};
  const double k6[3] = {0.5, 0.25, 0}, k7[3] = {1, 0.25, 0}, k8[3] = {0.75, 0.25, 1};
  tri_pts(&s, h0, h1, h2);
  tri_pts(&s, k0, k1, k2);
  r = find(&s);
  CHECK(r.intersecting_pairs == 1);
  CHECK(r.intersecting[0].p[0] >= 1.0 && r.intersecting[0].p[0] <= 2.0 &&
        r.intersecting[0].p[1] == 0.0);
  mx_trisoup_free(&s);
  tri_pts(&s, h0, h1, h2);
  tri_pts(&s, k3, k4, k5);
  r = find(&s);
  CHECK(r.intersecting_pairs == 0);
  mx_trisoup_free(&s);
  tri_pts(&s, h0, h1, h2);
  tri_pts(&s, k6, k7, k8);
  r = find(&s);
  CHECK(r.intersecting_pairs == 1);
  mx_trisoup_free(&s);

  /* Coplanar, one inside the other (no edges crossing), in both orders
   * (same box centre, so the order of the ids is the order tested). */
  const double B0[3] = {0, 0, 0}, B1[3] = {4, 0, 0}, B2[3] = {2, 4, 0};
  const double S0[3] = {1.5, 1.5, 0}, S1[3] = {2.5, 1.5, 0}, S2[3] = {2, 2.5, 0};
  for (int order = 0; order < 2; order++) {
    if (order) tri_pts(&s, S0, S1, S2);
    tri_pts(&s, B0, B1, B2);
    if (!order) tri_pts(&s, S0, S1, S2);
    r = find(&s);
    CHECK(r.intersecting_pairs == 1);
    mx_trisoup_free(&s);
  }

  /* Duplicate triangle in one input, and an unwelded copy of a vertex
   * (shared by coordinates: not an intersection). */
  tri_pts(&s, a, b, c);
  tri_pts(&s, a, b, c);
  r = find(&s);
  CHECK(r.intersecting_pairs == 1 && r.nonmanifold_edges == 0 &&
        r.misoriented_edges == 3);
  mx_trisoup_free(&s);
  tri_pts(&s, a, b, c);
  {
    const double cc[3] = {a[0], a[1], a[2]};
    CHECK(mx_trisoup_set_vertex(&s, s.nv, cc) == MX_OK);
    uint32_t ia = (uint32_t)s.nv - 1, ie = vtx(&s, e[0], e[1], e[2]);
    uint32_t ib = vtx(&s, b[0], b[1], b[2]);
    tri(&s, ia, ie, ib);
  }
  r = find(&s);
  CHECK(r.intersecting_pairs == 0 && r.boundary_edges == 6);
  mx_trisoup_free(&s);
}

/* Exact signs: a triangle touching another's interior at one point, then
 * moved away or through by one ulp. The plane z = x + y holds exactly for
 * these dyadic coordinates, far from the origin. */
static void test_exact(void) {
  const double p0[3] = {1000.125, 2000.25, 3000.375};
  const double p1[3] = {1001.5, 2000.25, 3001.75};
  const double p2[3] = {1000.125, 2001.625, 3001.75};
  for (int dz = -1; dz <= 1; dz++) {
    double q0[3] = {1000.5, 2000.5, 3001.0};
    if (dz) q0[2] = nextafter(q0[2], dz > 0 ? INFINITY : -INFINITY);
    const double q1[3] = {q0[0], q0[1], q0[2] + 1.0};
    const double q2[3] = {q0[0] + 0.5, q0[1], q0[2] + 1.0};
    mx_trisoup s = {0};
    tri_pts(&s, p0, p1, p2);
    tri_pts(&s, q0, q1, q2);
    mx_surface_defects r = find(&s);
    CHECK(r.intersecting_pairs == (dz <= 0 ? 1u : 0u));
    mx_trisoup_free(&s);
  }
  mx_trisoup s = {0};
  mx_surface_defects r;
  /* Coplanar, disjoint by a hair: two triangles of the plane z = 0. */
  const double e0[3] = {0, 0, 0}, e1[3] = {1, 0, 0}, e2[3] = {0, 1, 0};
  const double f0[3] = {0.5, nextafter(0.5, 1.0), 0}, f1[3] = {1, 1, 0}, f2[3] = {2, 0.5, 0};
  tri_pts(&s, e0, e1, e2);
  tri_pts(&s, f0, f1, f2);
  r = find(&s);
  show("coplanar, apart by one ulp", &r, &s);
  CHECK(r.intersecting_pairs == 0);
  mx_trisoup_free(&s);
  const double g0[3] = {0.5, 0.5, 0};
  tri_pts(&s, e0, e1, e2);
  tri_pts(&s, g0, f1, f2);
  r = find(&s);
  CHECK(r.intersecting_pairs == 1);
  mx_trisoup_free(&s);
}

static void test_degenerate(void) {
  mx_trisoup s = {0};
  add_box(&s, O, ONE, -1);
  uint32_t a = vtx(&s, 0, 0, 0), b = vtx(&s, 1, 1, 1), c = vtx(&s, 0.5, 0.5, 0.5);
  tri(&s, a, b, c); /* collinear, through the cube */
  tri(&s, a, a, b); /* repeated vertex */
  mx_surface_defects r = find(&s);
  show("cube with two degenerate triangles", &r, &s);
  CHECK(r.degenerate_triangles == 2 && r.degenerate[0].tri == 12 &&
        r.degenerate[1].tri == 13);
  CHECK(r.intersecting_pairs == 0);
  mx_trisoup_free(&s);

  /* Out-of-range index: refused. */
  add_box(&s, O, ONE, -1);
  s.tri[5] = 100;
  mx_quiet = 1;
  CHECK(mx_surface_defects_find(&s, &r) == MX_EINPUT);
  CHECK(mx_surface_orient(&s, NULL) == MX_EINPUT);
  mx_quiet = 0;
  mx_trisoup_free(&s);
  /* Empty. */
  CHECK(mx_surface_defects_find(&s, &r) == MX_OK && mx_surface_defects_total(&r) == 0);
}

static void test_spheres(void) {
  mx_trisoup s = {0};
  icosphere(&s, 4, 1.0, O);
  CHECK(s.nt == 5120);
  mx_surface_defects r = find(&s);
  show("geodesic sphere", &r, &s);
  CHECK(only(&r, 0, 0, 0, 0, 0));
  CHECK(volume6(&s) > 0);
  /* A second sphere inside (nested: fine), then one crossing it. */
  mx_trisoup all = {0}, in = {0};
  const double c[3] = {0.1, 0.05, 0.0}, c2[3] = {1.2, 0.3, 0.1};
  icosphere(&in, 3, 0.5, c);
  CHECK(mx_trisoup_append(&all, &s) == MX_OK);
  append_free(&all, &in);
  r = find(&all);
  CHECK(only(&r, 0, 0, 0, 0, 0));
  icosphere(&in, 3, 0.5, c2);
  append_free(&all, &in);
  r = find(&all);
  show("sphere crossing two nested ones", &r, &all);
  CHECK(r.crossing_pairs > 0 && r.intersecting_pairs == 0);
  /* All in one input: then the crossing is a self-intersection between
   * bodies. */
  for (size_t t = 0; t < all.nt; t++) all.shell[t] = 0;
  mx_surface_defects r1 = find(&all);
  CHECK(r1.intersecting_pairs == r.crossing_pairs &&
        r1.intersecting_bodies == r1.intersecting_pairs && r1.crossing_pairs == 0);
  mx_trisoup_free(&all);
  mx_trisoup_free(&s);

  /* The demo surface (star-shaped, so clean), fine. */
  CHECK(mx_demo_surface(&s, 5) == MX_OK);
  r = find(&s);
  CHECK(only(&r, 0, 0, 0, 0, 0));
  mx_trisoup_free(&s);
}

/* Many random small tetrahedra, some overlapping, in two inputs: the
 * report must not depend on the thread count. */
static void test_threads(void) {
  mx_trisoup all = {0};
  uint64_t seed = 12345;
  for (int sh = 0; sh < 2; sh++) {
    mx_trisoup s = {0};
    for (int i = 0; i < 3000; i++) {
      double o[3];
      for (int k = 0; k < 3; k++) {
        seed = seed * 6364136223846793005ull + 1442695040888963407ull;
        o[k] = (double)(seed >> 11) * 0x1p-53 * 20.0;
      }
      tetra(&s, o, 0.6);
    }
    append_free(&all, &s);
  }
  /* A few flipped and an open one, so every kind has examples. */
  flip_tri(&all, 7);
  flip_tri(&all, 500);
  all.tri[3 * 901 + 1] = all.tri[3 * 901]; /* repeats a vertex */
  mx_surface_defects r1, rn;
  int nth = omp_get_max_threads();
  omp_set_num_threads(1);
  CHECK(mx_surface_defects_find(&all, &r1) == MX_OK);
  omp_set_num_threads(4);
  double t0 = mx_wtime();
  CHECK(mx_surface_defects_find(&all, &rn) == MX_OK);
  double t1 = mx_wtime();
  omp_set_num_threads(nth);
  show("random tetrahedra", &r1, &all);
  printf("   (%.1f ms with 4 threads)\n", 1e3 * (t1 - t0));
  CHECK(memcmp(&r1, &rn, sizeof r1) == 0);
  CHECK(r1.intersecting_pairs > 100 && r1.crossing_pairs > 100);
  CHECK(r1.misoriented_edges == 6 && r1.degenerate_triangles == 1);
  CHECK(r1.boundary_edges == 3 && r1.nonmanifold_edges == 0);
  mx_trisoup_free(&all);
}

/* The shared sample surfaces, when present: all clean, except that
 * in_spher.mdl and outer_sphere.mdl are the same sphere (identical
 * vertices, opposite orientation), so as two inputs every triangle lies on
 * its copy. */
static void test_samples(void) {
  const char *data = test_data_dir("surfaces/cortex.off");
  char dir[512];
  snprintf(dir, sizeof dir, "%s/surfaces", data ? data : MIXOCT_TEST_DATA);
  static const char *clean[] = {"cortex.off", "femur.mdl", "hex.off",
                                "cyl50.off", "sein.mdl", "fertilityRotated.mdl",
                                "hollow-coarse.off", "suture.off",
                                "in_spher.mdl", "outer_sphere.mdl"};
  mx_trisoup pair = {0};
  for (size_t i = 0; i < sizeof clean / sizeof *clean; i++) {
    char path[640];
    snprintf(path, sizeof path, "%s/%s", dir, clean[i]);
    if (access(path, R_OK) != 0) {
      TEST_DATA_MISSING("%s: not present", path);
      continue;
    }
    mx_trisoup s = {0};
    CHECK(mx_read_surface(path, &s) == MX_OK);
    CHECK(mx_trisoup_check(&s, path, NULL) == MX_OK);
    double t0 = mx_wtime();
    mx_surface_defects r = find(&s);
    double t1 = mx_wtime();
    printf("%-22s %6zu triangles  %6.2f ms  ", clean[i], s.nt, 1e3 * (t1 - t0));
    show(clean[i], &r, &s);
    CHECK(only(&r, 0, 0, 0, 0, 0));
    size_t fl = 99;
    CHECK(mx_surface_orient(&s, &fl) == MX_OK);
    /* in_spher.mdl is oriented inward: its normals point to the centre. */
    CHECK(fl == (strcmp(clean[i], "in_spher.mdl") ? 0 : s.nt));
    if (!strcmp(clean[i], "in_spher.mdl") || !strcmp(clean[i], "outer_sphere.mdl")) {
      mx_trisoup orig = {0};
      CHECK(mx_read_surface(path, &orig) == MX_OK);
      append_free(&pair, &orig);
    }
    mx_trisoup_free(&s);
  }
  if (pair.nshells == 2) {
    mx_surface_defects r = find(&pair);
    show("in_spher.mdl + outer_sphere.mdl", &r, &pair);
    CHECK(only(&r, 0, 0, 0, 0, pair.nt / 2));
  }
  mx_trisoup_free(&pair);
}

int main(void) {
  test_cube();
  test_open_cube();
  test_nonmanifold();
  test_misoriented();
  test_moebius();
  test_tetrahedra();
  test_shells();
  test_adjacent();
  test_exact();
  test_degenerate();
  test_spheres();
  test_threads();
  test_samples();
  return TEST_DONE();
}
