/* Polygon faces of surface files (io/polygon_split.c) and the face numbers
 * messages give (soa/trisoup_origin.c): closed polyhedra with non-convex
 * faces (an L-shaped prism, a notched cube, a star prism) and faces with
 * corners on straight runs read as closed surfaces with no defect and the
 * right volume; non-planar, degenerate, crossing and pinched faces are split,
 * warned about or refused naming the face and its line; defects are named by
 * face, triangle within the face and line, in OFF, OBJ and PLY alike. */
#include <dirent.h>
#include <fcntl.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "check.h"
#include "file_util.h"
#include "base/common.h"
#include "io/polygon_split.h"
#include "geom/surface_defects.h"
#include "soa/trisoup.h"
#include "io/read_surface.h"

static char tmpdir[64];
static char captured[16384];

static void tpath(char *buf, size_t n, const char *name) {
  snprintf(buf, n, "%s/%s", tmpdir, name);
}

static void capture_begin(void) {
  char path[128];
  tpath(path, sizeof path, "stderr.txt");
  capture_stderr_begin(path);
}

static const char *capture_end(void) {
  char path[128];
  tpath(path, sizeof path, "stderr.txt");
  return capture_stderr_end(path, captured, sizeof captured);
}

/* ---- a text under construction --------------------------------------------- */

typedef struct {
  char *s;
  size_t n, cap;
} text;

static void put(text *t, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static void put(text *t, const char *fmt, ...) {
  for (;;) {
    va_list ap;
    va_start(ap, fmt);
    int k = vsnprintf(t->s ? t->s + t->n : NULL, t->s ? t->cap - t->n : 0, fmt, ap);
    va_end(ap);
    if (t->s && (size_t)k < t->cap - t->n) {
      t->n += (size_t)k;
      return;
    }
    t->cap = 2 * (t->cap + (size_t)k + 64);
    t->s = realloc(t->s, t->cap);
    if (!t->s) abort();
  }
}

/* ---- fixtures ---------------------------------------------------------------- */

/* A prism: the profile xy[0..n) (counter-clockwise) from z = 0 to z = h, as
 * OFF: the bottom (the profile reversed, from its last corner: the fan from
 * there crosses the outside of a non-convex profile), the top, the sides. */
static text prism_off(const double (*xy)[2], int n, double h) {
  text t = {0};
  put(&t, "OFF\n%d %d 0\n", 2 * n, n + 2);
  for (int z = 0; z < 2; z++)
    for (int i = 0; i < n; i++) put(&t, "%.17g %.17g %.17g\n", xy[i][0], xy[i][1], z * h);
  put(&t, "%d", n);
  for (int i = n - 1; i >= 0; i--) put(&t, " %d", i);
  put(&t, "\n%d", n);
  for (int i = 0; i < n; i++) put(&t, " %d", n + i);
  put(&t, "\n");
  for (int i = 0; i < n; i++) {
    const int j = (i + 1) % n;
    put(&t, "4 %d %d %d %d\n", i, j, n + j, n + i);
  }
  return t;
}

static const double L_XY[6][2] = {{0, 0}, {2, 0}, {2, 1}, {1, 1}, {1, 2}, {0, 2}};
/* a cube of side 3 with a slot 1 wide and 1 deep across its top */
static const double U_XY[8][2] = {{0, 0}, {3, 0}, {3, 3}, {2, 3},
                                  {2, 2}, {1, 2}, {1, 3}, {0, 3}};

static double volume(const mx_trisoup *s) {
  double v = 0.0;
  for (size_t t = 0; t < s->nt; t++) {
    const uint32_t *c = s->tri + 3 * t;
    const double a[3] = {s->x[c[0]], s->y[c[0]], s->z[c[0]]};
    const double b[3] = {s->x[c[1]], s->y[c[1]], s->z[c[1]]};
    const double d[3] = {s->x[c[2]], s->y[c[2]], s->z[c[2]]};
    v += a[0] * (b[1] * d[2] - b[2] * d[1]) - a[1] * (b[0] * d[2] - b[2] * d[0]) +
         a[2] * (b[0] * d[1] - b[1] * d[0]);
  }
  return v / 6.0;
}

/* Triangles of zero area (exactly collinear corners). */
static size_t flat_triangles(const mx_trisoup *s) {
  size_t n = 0;
  for (size_t t = 0; t < s->nt; t++) {
    const uint32_t *c = s->tri + 3 * t;
    const double u[3] = {s->x[c[1]] - s->x[c[0]], s->y[c[1]] - s->y[c[0]],
                         s->z[c[1]] - s->z[c[0]]};
    const double w[3] = {s->x[c[2]] - s->x[c[0]], s->y[c[2]] - s->y[c[0]],
                         s->z[c[2]] - s->z[c[0]]};
    n += u[1] * w[2] - u[2] * w[1] == 0 && u[2] * w[0] - u[0] * w[2] == 0 &&
         u[0] * w[1] - u[1] * w[0] == 0;
  }
  return n;
}

/* Writes the text under name; reads it with rd (stderr captured into
 * captured). */
static int read_text(int (*rd)(const char *, mx_trisoup *), const char *name, const char *t,
                     size_t len, mx_trisoup *s, char *path, size_t npath) {
  tpath(path, npath, name);
  write_bytes_file(path, t, len);
  capture_begin();
  const int rc = rd(path, s);
  capture_end();
  return rc;
}

/* A closed surface with no defect of the given volume, made of nt triangles
 * none flat, whose faces are numbered from first in file order. */
static void expect_closed(const char *label, const mx_trisoup *s0, size_t nt, double vol,
                          uint32_t first) {
  const int before = mx_test_failures;
  mx_trisoup s = *s0;
  CHECK(s.nt == nt);
  CHECK(flat_triangles(&s) == 0);
  for (size_t t = 1; t < s.nt; t++) CHECK(s.face[t] == s.face[t - 1] || s.face[t] == s.face[t - 1] + 1);
  CHECK(s.nt == 0 || s.face[0] == first);
  mx_surface_defects r;
  CHECK(mx_surface_defects_find(&s, &r) == MX_OK);
  CHECK(mx_surface_defects_total(&r) == 0);
  CHECK(fabs(volume(&s) - vol) <= 1e-12 * fabs(vol));
  char d[1024];
  mx_surface_defects_describe(&r, &s, d, sizeof d);
  printf("%s %-26s %zu triangles, volume %.15g (%.15g), %s",
         mx_test_failures == before ? "ok  " : "FAIL", label, s.nt, volume(&s), vol, d);
}

/* ---- closed polyhedra with non-convex faces -------------------------------------- */

static void test_prisms(void) {
  printf("-- prisms with non-convex faces\n");
  char path[128];
  mx_trisoup s;
  text t = prism_off(L_XY, 6, 1.0);
  CHECK(read_text(mx_read_off, "lprism.off", t.s, t.n, &s, path, sizeof path) == MX_OK);
  CHECK(captured[0] == '\0'); /* planar faces, nothing to say */
  expect_closed("L prism (OFF)", &s, 2 * 4 + 6 * 2, 3.0, 0);
  size_t open = 9;
  CHECK(mx_trisoup_check(&s, path, &open) == MX_OK && open == 0 && s.nt == 20);
  mx_trisoup_free(&s);
  free(t.s);

  t = prism_off(U_XY, 8, 3.0);
  CHECK(read_text(mx_read_off, "notched.off", t.s, t.n, &s, path, sizeof path) == MX_OK);
  expect_closed("notched cube (OFF)", &s, 2 * 6 + 8 * 2, 8.0 * 3.0, 0);
  mx_trisoup_free(&s);
  free(t.s);

  /* a five-pointed star: 10 corners, 5 of them reflex */
  double star[10][2];
  const double R = 2.0, r = 0.8, pi = acos(-1.0);
  for (int i = 0; i < 10; i++) {
    const double a = pi / 2 + i * pi / 5, rad = i % 2 ? r : R;
    star[i][0] = rad * cos(a);
    star[i][1] = rad * sin(a);
  }
  t = prism_off((const double(*)[2])star, 10, 0.5);
  CHECK(read_text(mx_read_off, "star.off", t.s, t.n, &s, path, sizeof path) == MX_OK);
  double area = 0.0;
  for (int i = 0; i < 10; i++)
    area += 0.5 * (star[i][0] * star[(i + 1) % 10][1] - star[(i + 1) % 10][0] * star[i][1]);
  expect_closed("star prism (OFF)", &s, 2 * 8 + 10 * 2, 0.5 * area, 0);
  CHECK(fabs(area - 5 * R * r * sin(pi / 5)) < 1e-12);
  mx_trisoup_free(&s);
  free(t.s);
}

/* A cube of side 2 whose faces are octagons: the corners and the midpoints
 * of the edges, from a corner (a fan from there gives two flat triangles a
 * face). */
static void test_straight_runs(void) {
  printf("-- corners on straight runs\n");
  text t = {0};
  put(&t, "OFF\n26 6 0\n");
  for (int i = 0; i < 27; i++) {
    const int x = i % 3, y = i / 3 % 3, z = i / 9;
    if (i != 13) put(&t, "%d %d %d\n", x, y, z); /* not the centre */
  }
  /* grid point (x, y, z) -> vertex id (the centre 13 left out) */
#define G(x, y, z) ((x) + 3 * (y) + 9 * (z) - ((x) + 3 * (y) + 9 * (z) > 13))
  /* each face from a corner, counter-clockwise seen from outside */
  const int face[6][8][3] = {
      {{0, 0, 0}, {0, 1, 0}, {0, 2, 0}, {1, 2, 0}, {2, 2, 0}, {2, 1, 0}, {2, 0, 0}, {1, 0, 0}},
      {{0, 0, 2}, {1, 0, 2}, {2, 0, 2}, {2, 1, 2}, {2, 2, 2}, {1, 2, 2}, {0, 2, 2}, {0, 1, 2}},
      {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {2, 0, 1}, {2, 0, 2}, {1, 0, 2}, {0, 0, 2}, {0, 0, 1}},
      {{0, 2, 0}, {0, 2, 1}, {0, 2, 2}, {1, 2, 2}, {2, 2, 2}, {2, 2, 1}, {2, 2, 0}, {1, 2, 0}},
      {{0, 0, 0}, {0, 0, 1}, {0, 0, 2}, {0, 1, 2}, {0, 2, 2}, {0, 2, 1}, {0, 2, 0}, {0, 1, 0}},
      {{2, 0, 0}, {2, 1, 0}, {2, 2, 0}, {2, 2, 1}, {2, 2, 2}, {2, 1, 2}, {2, 0, 2}, {2, 0, 1}}};
  for (int f = 0; f < 6; f++) {
    put(&t, "8");
    for (int k = 0; k < 8; k++) put(&t, " %d", G(face[f][k][0], face[f][k][1], face[f][k][2]));
    put(&t, "\n");
  }
#undef G
  char path[128];
  mx_trisoup s;
  CHECK(read_text(mx_read_off, "octagons.off", t.s, t.n, &s, path, sizeof path) == MX_OK);
  CHECK(captured[0] == '\0');
  expect_closed("cube of octagons", &s, 6 * 6, 8.0, 0);
  size_t open = 9;
  capture_begin();
  CHECK(mx_trisoup_check(&s, path, &open) == MX_OK && open == 0 && s.nt == 36);
  CHECK(capture_end()[0] == '\0'); /* no degenerate triangle removed */
  mx_trisoup_free(&s);
  free(t.s);
}

/* A convex polygon of many corners: the fan from its first corner, in
 * linear time. */
static void test_large_convex(void) {
  const int k = 20000;
  text t = {0};
  put(&t, "OFF\n%d 1 0\n", k);
  const double pi = acos(-1.0);
  for (int i = 0; i < k; i++) put(&t, "%.17g %.17g 0\n", cos(2 * pi * i / k), sin(2 * pi * i / k));
  put(&t, "%d", k);
  for (int i = 0; i < k; i++) put(&t, " %d", i);
  put(&t, "\n");
  char path[128];
  mx_trisoup s;
  CHECK(read_text(mx_read_off, "disc.off", t.s, t.n, &s, path, sizeof path) == MX_OK);
  CHECK(s.nt == (size_t)k - 2 && flat_triangles(&s) == 0);
  int fan = 1;
  for (size_t i = 0; i < s.nt; i++)
    fan &= s.tri[3 * i] == 0 && s.tri[3 * i + 1] == i + 1 && s.tri[3 * i + 2] == i + 2 && s.face[i] == 0;
  CHECK(fan);
  printf("%s disc.off                   %d corners: the fan of %zu triangles\n", fan ? "ok  " : "FAIL", k,
         s.nt);
  mx_trisoup_free(&s);
  free(t.s);
}

/* Random simple polygons, straight to the splitter: star-shaped around the
 * origin (corners by increasing angle) on a small integer grid, so that
 * many corners lie on straight runs. Each must become k - 2 triangles, all
 * turning the polygon's way (none flat, none folded), whose areas add up to
 * the polygon's exactly (half-integers). */
static uint64_t rng = 88172645463325252ull;
static int rnd(int n) {
  rng ^= rng << 13;
  rng ^= rng >> 7;
  rng ^= rng << 17;
  return (int)(rng % (uint64_t)n);
}

static void test_random_simple(void) {
  int bad = 0, polygons = 0;
  size_t triangles = 0;
  for (int trial = 0; trial < 400; trial++) {
    /* corners: distinct directions from the origin, sorted by angle */
    int k = 4 + rnd(40), pts[64][2], n = 0;
    const int span = 3 + rnd(6);
    for (int tries = 0; n < k && tries < 2000; tries++) {
      const int x = rnd(2 * span + 1) - span, y = rnd(2 * span + 1) - span;
      if (x == 0 && y == 0) continue;
      int dup = 0; /* one corner a direction */
      for (int i = 0; i < n && !dup; i++)
        dup = pts[i][0] * y - pts[i][1] * x == 0 && pts[i][0] * x + pts[i][1] * y > 0;
      if (dup) continue;
      pts[n][0] = x;
      pts[n][1] = y;
      n++;
    }
    for (int i = 1; i < n; i++) /* by angle */
      for (int j = i; j > 0 && atan2(pts[j][1], pts[j][0]) < atan2(pts[j - 1][1], pts[j - 1][0]); j--) {
        int t[2] = {pts[j][0], pts[j][1]};
        pts[j][0] = pts[j - 1][0], pts[j][1] = pts[j - 1][1];
        pts[j - 1][0] = t[0], pts[j - 1][1] = t[1];
      }
    long twice = 0; /* twice the area */
    for (int i = 0; i < n; i++)
      twice += (long)pts[i][0] * pts[(i + 1) % n][1] - (long)pts[(i + 1) % n][0] * pts[i][1];
    int origin_inside = 1; /* star-shaped around the origin: each turn around it < pi */
    for (int i = 0; i < n; i++)
      origin_inside &= (long)pts[i][0] * pts[(i + 1) % n][1] - (long)pts[(i + 1) % n][0] * pts[i][1] > 0;
    if (n < 4 || !origin_inside) continue;
    /* a plane z = a x + b y (integers: planar exactly), the order either way */
    const int a = rnd(3) - 1, b = rnd(3) - 1, rev = rnd(2), first = rnd(n);
    mx_trisoup s = {0};
    mx_polysplit ps;
    mx_polysplit_init(&ps, "random");
    for (int i = 0; i < n; i++) {
      const double c[3] = {pts[i][0], pts[i][1], a * pts[i][0] + b * pts[i][1]};
      CHECK(mx_trisoup_set_vertex(&s, (size_t)i, c) == MX_OK);
    }
    for (int i = 0; i < n; i++) {
      const int j = (first + (rev ? n - i : i)) % n;
      CHECK(mx_polysplit_corner(&ps, (uint32_t)j) == MX_OK);
    }
    const int rc = mx_polysplit_face(&ps, &s, (mx_face_at){(uint64_t)trial, 0, -1});
    CHECK(rc == MX_OK && mx_polysplit_finish(&ps, &s) == MX_OK);
    mx_polysplit_free(&ps);
    long sum = 0;
    int ok = rc == MX_OK && s.nt == (size_t)n - 2;
    for (size_t t = 0; ok && t < s.nt; t++) {
      const uint32_t *v = s.tri + 3 * t;
      const long o = (long)(s.x[v[1]] - s.x[v[0]]) * (long)(s.y[v[2]] - s.y[v[0]]) -
                     (long)(s.y[v[1]] - s.y[v[0]]) * (long)(s.x[v[2]] - s.x[v[0]]);
      ok = rev ? o < 0 : o > 0;
      sum += rev ? -o : o;
    }
    ok = ok && sum == twice;
    bad += !ok;
    polygons++;
    triangles += s.nt;
    mx_trisoup_free(&s);
  }
  CHECK(bad == 0 && polygons > 200);
  printf("%s random simple polygons      %d of them, %zu triangles, %d wrong\n", bad ? "FAIL" : "ok  ",
         polygons, triangles, bad);
}

/* ---- faces that are not plain polygons ------------------------------------------- */

/* The unit cube as 6 quads, with one more face line `extra` (face 6, line
 * 17) and corner (1, 1, 1) moved to `top`. */
static text cube_quads(const char *top, const char *extra) {
  text t = {0};
  put(&t, "OFF\n8 %d 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n0 0 1\n1 0 1\n%s\n0 1 1\n", extra ? 7 : 6,
      top);
  put(&t, "4 0 3 2 1\n4 4 5 6 7\n4 0 1 5 4\n4 1 2 6 5\n4 2 3 7 6\n4 3 0 4 7\n");
  if (extra) put(&t, "%s\n", extra);
  return t;
}

static void test_nonplanar(void) {
  printf("-- non-planar faces\n");
  /* (1, 1, 1) raised to z = 1.5: the top (face 1, line 12) is not planar;
   * its fan from (0, 0, 1) is its split in the projection on z = 0 */
  text t = cube_quads("1 1 1.5", NULL);
  char path[128], want[256];
  mx_trisoup s;
  CHECK(read_text(mx_read_off, "raised.off", t.s, t.n, &s, path, sizeof path) == MX_OK);
  snprintf(want, sizeof want, "%s:12: warning: face 1 is not planar (a corner is off its mean plane by ",
           path);
  CHECK(strstr(captured, want) != NULL);
  CHECK(strstr(captured, "faces are not planar") == NULL); /* only one */
  printf("%s", captured);
  expect_closed("raised corner", &s, 12, 1.0 + 1.0 / 6.0, 0);
  CHECK(s.tri[6] == 4 && s.tri[7] == 5 && s.tri[8] == 6); /* the top: 4 5 6, 4 6 7 */
  mx_trisoup_free(&s);
  free(t.s);
  /* a planar cube says nothing */
  t = cube_quads("1 1 1", NULL);
  CHECK(read_text(mx_read_off, "cube.off", t.s, t.n, &s, path, sizeof path) == MX_OK);
  CHECK(captured[0] == '\0');
  expect_closed("cube of quads", &s, 12, 1.0, 0);
  mx_trisoup_free(&s);
  free(t.s);
}

/* Reads the text, which must be refused with "path:line: error: face F"
 * and needle. */
static void expect_refused(const char *name, const char *t, long line, unsigned face,
                           const char *needle) {
  char path[128], want[256];
  mx_trisoup s;
  memset(&s, 0, sizeof s);
  const int rc = read_text(mx_read_surface, name, t, strlen(t), &s, path, sizeof path);
  CHECK(rc == MX_EINPUT && s.nt == 0 && s.tri == NULL);
  snprintf(want, sizeof want, "%s:%ld: error: face %u", path, line, face);
  const int ok = rc == MX_EINPUT && strstr(captured, want) && strstr(captured, needle);
  CHECK(ok);
  printf("%s %-26s %s", ok ? "ok  " : "FAIL", name, captured);
}

static void test_refused(void) {
  printf("-- faces refused\n");
  /* the bottom as a bow tie: 0 2 1 3 crosses itself */
  text t = cube_quads("1 1 1", NULL);
  char *bow = text_edit_line(t.s, 11, "4 0 2 3 1");
  expect_refused("bowtie.off", bow, 11, 0, "a polygon of 4 corners crosses or touches itself");
  free(bow);
  /* an L-shaped hexagon whose corner 3 is pulled across its side 0-1 */
  const char *cross =
      "OFF\n6 1 0\n0 0 0\n2 0 0\n2 1 0\n1 -1 0\n1 2 0\n0 2 0\n6 0 1 2 3 4 5\n";
  expect_refused("crossing.off", cross, 9, 0, "crosses or touches itself");
  /* a square with a square hole, bridged by repeated corners 0 and 4 */
  const char *hole =
      "OFF\n8 1 0\n0 0 0\n3 0 0\n3 3 0\n0 3 0\n1 1 0\n1 2 0\n2 2 0\n2 1 0\n"
      "10 0 1 2 3 0 4 5 6 7 4\n";
  expect_refused("hole.off", hole, 11, 0, "turns the other way");
  free(t.s);
  /* a figure of eight of 101 corners (beyond the exact test of crossings):
   * no ear is left once the lobe turning the face's way is clipped */
  text e = {0};
  put(&e, "OFF\n101 1 0\n");
  for (int i = 0; i < 101; i++) {
    const double a = 2 * acos(-1.0) * i / 101;
    put(&e, "%.17g %.17g 0\n", sin(a), sin(a) * cos(a));
  }
  put(&e, "101");
  for (int i = 0; i < 101; i++) put(&e, " %d", i);
  put(&e, "\n");
  expect_refused("eight.off", e.s, 104, 0, "a polygon of 101 corners crosses itself");
  free(e.s);
  /* a comb of 30002 corners, 15000 of them reflex: beyond the 2^27 tests a
   * face may take, refused at once */
  text z = {0};
  const int N = 30000;
  put(&z, "OFF\n%d 1 0\n0 0 0\n%d 0 0\n", N + 2, N);
  for (int j = 0; j < N; j++) put(&z, "%d %d 0\n", N - j, 1 + j % 2);
  put(&z, "%d", N + 2);
  for (int i = 0; i < N + 2; i++) put(&z, " %d", i);
  put(&z, "\n");
  expect_refused("comb.off", z.s, N + 5, 0, "a polygon of 30002 corners is too large and too tangled");
  free(z.s);
  /* OBJ counts faces from 1 */
  const char *obj = "v 0 0 0\nv 1 1 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 3 4\n";
  expect_refused("bowtie.obj", obj, 6, 2, "crosses or touches itself");
}

static void test_degenerate(void) {
  printf("-- degenerate faces\n");
  /* face 0: the square with a corner repeated (twice in a row, and at the
   * end as the first); face 1: all corners on one line; face 2: two
   * triangles touching at corner 0 (a figure of eight); face 3: a spike
   * (edge 1-4 there and back) on a triangle */
  const char *t =
      "OFF\n7 4 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n2 2 0\n-1 -1 0\n3 3 0\n"
      "6 0 1 1 2 3 0\n4 0 2 4 6\n6 0 1 2 0 3 5\n5 0 1 4 1 2\n";
  char path[128];
  mx_trisoup s;
  CHECK(read_text(mx_read_off, "degenerate.off", t, strlen(t), &s, path, sizeof path) == MX_OK);
  printf("%s", captured);
  char want[256];
  snprintf(want, sizeof want,
           "%s:11: warning: face 1 has no area (its corners are collinear or repeated): no "
           "triangle made for it\n", path);
  CHECK(strstr(captured, want) != NULL);
  snprintf(want, sizeof want,
           "%s:10: warning: face 0 repeats a corner: split where it comes back to it (3 faces "
           "repeat a corner)\n", path);
  CHECK(strstr(captured, want) != NULL);
  static const uint32_t tri[] = {0, 1, 2, 0, 2, 3, 0, 1, 2, 0, 3, 5, 0, 1, 2};
  static const uint32_t face[] = {0, 0, 2, 2, 3};
  CHECK(s.nt == 5 && memcmp(s.tri, tri, sizeof tri) == 0 && memcmp(s.face, face, sizeof face) == 0);
  CHECK(flat_triangles(&s) == 0);
  CHECK(mx_trisoup_line(&s, 0) == 10 && mx_trisoup_line(&s, 2) == 12 && mx_trisoup_line(&s, 4) == 13);
  mx_trisoup_free(&s);
  /* no face with an area at all: refused (found by tools/fuzz.sh off) */
  const char *none = "OFF\n4 2 0\n0 0 0\n1 0 0\n2 0 0\n1 1 0\n4 0 1 2 1\n4 0 3 0 3\n";
  memset(&s, 0, sizeof s);
  CHECK(read_text(mx_read_off, "no_area.off", none, strlen(none), &s, path, sizeof path) == MX_EINPUT);
  CHECK(s.nt == 0 && s.tri == NULL);
  CHECK(strstr(captured, "error: no triangle: every face has no area") != NULL);
  CHECK(strstr(captured, "(2 faces have no area)") != NULL);
  printf("no_area.off: %s", captured);
}

/* ---- the names of triangles in messages -------------------------------------------- */

static void describe(const mx_trisoup *s, char *buf, size_t n) {
  mx_surface_defects r;
  CHECK(mx_surface_defects_find(s, &r) == MX_OK);
  mx_surface_defects_describe(&r, s, buf, n);
}

static void test_messages(void) {
  printf("-- defects named by face and line\n");
  /* the L prism without its top (line 16): its sides' top edges are open */
  text t = prism_off(L_XY, 6, 1.0);
  char *open = text_edit_line(t.s, 2, "12 7 0"), *open2 = text_edit_line(open, 16, NULL);
  char path[128], d[2048];
  mx_trisoup s;
  CHECK(read_text(mx_read_off, "lopen.off", open2, strlen(open2), &s, path, sizeof path) == MX_OK);
  describe(&s, d, sizeof d);
  printf("lopen.off: %s", d);
  /* side 0-1-7-6 is face 1 on line 16: the open edge 6-7 is its second
   * triangle's (0 7 6) */
  CHECK(strstr(d, "6 open edges (used by one triangle only), e.g. edge of face 1 (triangle 2 "
                  "of 2, line 16) at (1, 0, 1); edge of face 2 (triangle 2 of 2, line 17)") == d);
  mx_trisoup_free(&s);
  free(open);
  free(open2);
  free(t.s);

  /* a surface of triangles only: "triangle T (line L)" */
  const char *tet = "OFF\n4 3 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n";
  CHECK(read_text(mx_read_off, "tet_open.off", tet, strlen(tet), &s, path, sizeof path) == MX_OK);
  describe(&s, d, sizeof d);
  printf("tet_open.off: %s", d);
  CHECK(strstr(d, "3 open edges (used by one triangle only), e.g. edge of triangle 0 (line 7) at "
                  "(0.5, 0.5, 0); edge of triangle 1 (line 8)") == d);
  mx_trisoup_free(&s);

  /* two triangles of one file crossing: "triangles 0 (line 7) and ..." */
  const char *x = "OFF\n6 2 0\n0 0 0\n2 0 0\n0 2 0\n1 1 -1\n1 1 1\n0.5 0.5 0\n3 0 1 2\n3 3 4 5\n";
  CHECK(read_text(mx_read_off, "cross.off", x, strlen(x), &s, path, sizeof path) == MX_OK);
  describe(&s, d, sizeof d);
  printf("cross.off: %s", d);
  CHECK(strstr(d, "e.g. triangle 0 (line 9) and triangle 1 (line 10) at") != NULL);
  mx_trisoup_free(&s);

  /* the degenerate triangles removed: the first one named */
  const char *dg = "OFF\n4 5 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 0 3\n3 0 3 2\n"
                   "3 1 2 3\n";
  CHECK(read_text(mx_read_off, "degen.off", dg, strlen(dg), &s, path, sizeof path) == MX_OK);
  size_t nopen;
  capture_begin();
  CHECK(mx_trisoup_check(&s, path, &nopen) == MX_OK && s.nt == 4 && nopen == 0);
  const char *msg = capture_end();
  printf("degen.off: %s", msg);
  CHECK(strstr(msg, "removed 1 degenerate triangle (zero area or repeated vertex), the first: "
                    "triangle 2 (line 9)") != NULL);
  /* after the removal the lines still follow the faces */
  CHECK(mx_trisoup_line(&s, 2) == 10 && s.face[2] == 3 && mx_trisoup_line(&s, 3) == 11);
  mx_trisoup_free(&s);
}

/* The same faces from OBJ (faces before the vertices they use) and PLY
 * (ASCII with the faces first, binary). */
static void test_formats(void) {
  printf("-- OBJ and PLY\n");
  text off = prism_off(L_XY, 6, 1.0);
  char path[128];
  mx_trisoup ref, s;
  CHECK(read_text(mx_read_off, "l.off", off.s, off.n, &ref, path, sizeof path) == MX_OK);
  free(off.s);

  /* OBJ: faces first, vertices after (forward references) */
  text o = {0};
  put(&o, "# L prism\nf 6 5 4 3 2 1\nf 7 8 9 10 11 12\n");
  for (int i = 0; i < 6; i++) put(&o, "f %d %d %d %d\n", i + 1, (i + 1) % 6 + 1, (i + 1) % 6 + 7, i + 7);
  for (int z = 0; z < 2; z++)
    for (int i = 0; i < 6; i++) put(&o, "v %g %g %d\n", L_XY[i][0], L_XY[i][1], z);
  CHECK(read_text(mx_read_obj, "l.obj", o.s, o.n, &s, path, sizeof path) == MX_OK);
  CHECK(s.nt == ref.nt && memcmp(s.tri, ref.tri, 3 * ref.nt * sizeof *s.tri) == 0);
  int ok = s.nt == ref.nt;
  for (size_t i = 0; ok && i < s.nt; i++) ok = s.face[i] == ref.face[i] + 1;
  CHECK(ok);
  CHECK(mx_trisoup_line(&s, 0) == 2 && mx_trisoup_line(&s, s.nt - 1) == 9);
  char name[128];
  mx_trisoup_name(&s, 5, name, sizeof name);
  CHECK(strcmp(name, "face 2 (triangle 2 of 4, line 3)") == 0);
  printf("%s l.obj                      %zu triangles, the same as l.off; %s\n",
         mx_test_failures ? "?   " : "ok  ", s.nt, name);
  mx_trisoup_free(&s);
  free(o.s);

  /* PLY, ASCII, the face element first */
  text p = {0};
  put(&p, "ply\nformat ascii 1.0\nelement face 8\nproperty list uchar int vertex_indices\n"
          "element vertex 12\nproperty float x\nproperty float y\nproperty float z\nend_header\n");
  put(&p, "6 5 4 3 2 1 0\n6 6 7 8 9 10 11\n");
  for (int i = 0; i < 6; i++) put(&p, "4 %d %d %d %d\n", i, (i + 1) % 6, (i + 1) % 6 + 6, i + 6);
  for (int z = 0; z < 2; z++)
    for (int i = 0; i < 6; i++) put(&p, "%g %g %d\n", L_XY[i][0], L_XY[i][1], z);
  CHECK(read_text(mx_read_ply, "l.ply", p.s, p.n, &s, path, sizeof path) == MX_OK);
  CHECK(s.nt == ref.nt && memcmp(s.tri, ref.tri, 3 * ref.nt * sizeof *s.tri) == 0 &&
        memcmp(s.face, ref.face, ref.nt * sizeof *s.face) == 0);
  CHECK(mx_trisoup_line(&s, 0) == 10 && mx_trisoup_line(&s, s.nt - 1) == 17);
  expect_closed("L prism (PLY, faces first)", &s, 20, 3.0, 0);
  mx_trisoup_free(&s);
  free(p.s);

  /* PLY, binary little endian: a bow tie named with its byte offset */
  unsigned char b[512];
  const char *h = "ply\nformat binary_little_endian 1.0\nelement vertex 4\nproperty float x\n"
                  "property float y\nproperty float z\nelement face 2\n"
                  "property list uchar int vertex_indices\nend_header\n";
  size_t n = strlen(h);
  memcpy(b, h, n);
  const float v[4][3] = {{0, 0, 0}, {1, 1, 0}, {1, 0, 0}, {0, 1, 0}};
  memcpy(b + n, v, sizeof v);
  n += sizeof v;
  const size_t face1 = n + 13; /* after face 0: 1 + 3 * 4 bytes */
  const int32_t f0[3] = {0, 2, 1}, f1[4] = {0, 1, 2, 3};
  b[n++] = 3;
  memcpy(b + n, f0, sizeof f0);
  n += sizeof f0;
  b[n++] = 4;
  memcpy(b + n, f1, sizeof f1);
  n += sizeof f1;
  memset(&s, 0, sizeof s);
  CHECK(read_text(mx_read_ply, "bowtie.ply", (const char *)b, n, &s, path, sizeof path) == MX_EINPUT);
  char want[256];
  snprintf(want, sizeof want, "%s: error: face 1 (byte offset %zu): a polygon of 4 corners crosses",
           path, face1);
  CHECK(strstr(captured, want) != NULL);
  printf("%s bowtie.ply                 %s", strstr(captured, want) ? "ok  " : "FAIL", captured);
  mx_trisoup_free(&ref);
}

/* Faces and lines survive mx_trisoup_append and the removal of triangles. */
static void test_soup(void) {
  printf("-- faces and lines in the soup\n");
  text t = prism_off(L_XY, 6, 1.0);
  char path[128];
  mx_trisoup a, all = {0};
  CHECK(read_text(mx_read_off, "la.off", t.s, t.n, &a, path, sizeof path) == MX_OK);
  CHECK(mx_trisoup_append(&all, &a) == MX_OK);
  mx_trisoup arr = {0}; /* a soup made in memory: no lines */
  const double p[4][3] = {{5, 0, 0}, {6, 0, 0}, {5, 1, 0}, {5, 0, 1}};
  for (int i = 0; i < 4; i++) CHECK(mx_trisoup_set_vertex(&arr, i, p[i]) == MX_OK);
  CHECK(mx_trisoup_add_triangle(&arr, 0, 2, 1) == MX_OK && mx_trisoup_add_triangle(&arr, 0, 1, 3) == MX_OK);
  CHECK(mx_trisoup_append(&all, &arr) == MX_OK);
  CHECK(mx_trisoup_append(&all, &a) == MX_OK);
  CHECK(all.nt == 42 && all.nshells == 3);
  CHECK(mx_trisoup_line(&all, 0) == 15 && mx_trisoup_line(&all, 19) == 22);
  CHECK(mx_trisoup_line(&all, 20) == 0 && mx_trisoup_line(&all, 21) == 0 && all.face[21] == 1);
  CHECK(mx_trisoup_line(&all, 22) == 15 && mx_trisoup_line(&all, 41) == 22 && all.face[41] == 7);
  char name[128];
  mx_trisoup_name(&all, 21, name, sizeof name);
  CHECK(strcmp(name, "triangle 1") == 0);
  mx_trisoup_name(&all, 40, name, sizeof name);
  CHECK(strcmp(name, "face 7 (triangle 1 of 2, line 22)") == 0);
  mx_trisoup_free(&all);
  mx_trisoup_free(&arr);
  mx_trisoup_free(&a);
  free(t.s);
  printf("%s appended soups keep their faces and lines\n", mx_test_failures ? "?   " : "ok  ");
}

static void remove_tmpdir(void) {
  remove_dir_files(tmpdir);
  rmdir(tmpdir);
}

int main(void) {
  strcpy(tmpdir, "/tmp/mixoct_polygons_XXXXXX");
  if (!mkdtemp(tmpdir)) {
    perror("mkdtemp");
    return 1;
  }
  test_prisms();
  test_straight_runs();
  test_large_convex();
  test_random_simple();
  test_nonplanar();
  test_refused();
  test_degenerate();
  test_messages();
  test_formats();
  test_soup();
  remove_tmpdir();
  return TEST_DONE();
}
