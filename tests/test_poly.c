/* Tests of the 2D polylines (src/io/read_poly.c, src/quad/poly.c): the
 * shared polyline files read and checked with counts taken from the files,
 * orientation by nesting (signed areas), bad inputs refused with the right
 * line, inside/outside on known points and against a brute-force parity,
 * closest points against a brute-force loop, features, and the crossing
 * check at scale (clustered segments, any thread count). */
#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "check.h"
#include "base/common.h"
#include "quad/quad.h"
#include "io/read_poly.h"

static char tmpdir[64];
static char data[512]; /* .../polylines, "" when not found */

/* ---- messages ------------------------------------------------------------ */

static char last_msg[2048];
static int nerr, nwarn;

static void keep_message(void *user, int level, const char *text) {
  (void)user;
  if (level == MX_MSG_ERROR) nerr++;
  else nwarn++;
  snprintf(last_msg, sizeof last_msg, "%s", text);
}

static void msgs_reset(void) {
  last_msg[0] = '\0';
  nerr = nwarn = 0;
}

/* ---- files ---------------------------------------------------------------- */

static void tpath(char *buf, size_t n, const char *name) {
  snprintf(buf, n, "%s/%s", tmpdir, name);
}

static void write_text(const char *path, const char *text) {
  FILE *f = fopen(path, "wb");
  if (!f) {
    perror(path);
    exit(1);
  }
  fputs(text, f);
  fclose(f);
}

static void find_data(void) {
  const char *d = test_data_dir("polylines/box.poly");
  if (d)
    snprintf(data, sizeof data, "%s/polylines", d);
  else
    data[0] = '\0';
}

/* Reads data/name (any format) into P; 0 (SKIP printed) when absent. */
static int read_shared(const char *name, mx_poly *P) {
  char path[700];
  snprintf(path, sizeof path, "%s/%s", data, name);
  if (!data[0] || access(path, R_OK) != 0) {
    TEST_DATA_MISSING("%s: not found (set MIXOCT_DATA)", name);
    return 0;
  }
  msgs_reset();
  const int st = mx_read_poly_any(path, P);
  CHECK(st == MX_OK);
  if (st != MX_OK) printf("FAIL read %s: %s\n", name, last_msg);
  return st == MX_OK;
}

/* ---- independent geometry ------------------------------------------------- */

/* Twice the signed area of the segments whose start vertex is in [v0, v1). */
static double area2_of(const mx_poly *P, uint32_t v0, uint32_t v1) {
  double a = 0;
  for (size_t s = 0; s < P->ns; s++) {
    const uint32_t i = P->seg[2 * s], j = P->seg[2 * s + 1];
    if (i < v0 || i >= v1) continue;
    a += P->xy[2 * i] * P->xy[2 * j + 1] - P->xy[2 * j] * P->xy[2 * i + 1];
  }
  return a;
}

/* Every vertex starts exactly as many segments as it ends (consistent loops). */
static int loops_consistent(const mx_poly *P) {
  int *bal = calloc(P->nv, sizeof *bal);
  for (size_t s = 0; s < P->ns; s++) {
    bal[P->seg[2 * s]]++;
    bal[P->seg[2 * s + 1]]--;
  }
  int ok = 1;
  for (size_t v = 0; v < P->nv; v++) ok &= bal[v] == 0;
  free(bal);
  return ok;
}

/* The same formula as the library's (bit-identical distances). */
static double dist2(const double *a, const double *b, const double *p) {
  const double u0 = b[0] - a[0], u1 = b[1] - a[1], w0 = p[0] - a[0], w1 = p[1] - a[1];
  const double l2 = u0 * u0 + u1 * u1;
  double t = l2 > 0 ? (u0 * w0 + u1 * w1) / l2 : 0.0;
  t = t < 0 ? 0 : t > 1 ? 1 : t;
  const double q0 = a[0] + t * u0, q1 = a[1] + t * u1;
  const double d0 = p[0] - q0, d1 = p[1] - q1;
  return d0 * d0 + d1 * d1;
}

static double brute_closest(const mx_poly *P, const double *p, uint32_t *seg) {
  double best = INFINITY;
  *seg = UINT32_MAX;
  for (size_t s = 0; s < P->ns; s++) {
    const double d = dist2(P->xy + 2 * P->seg[2 * s], P->xy + 2 * P->seg[2 * s + 1], p);
    if (d < best) {
      best = d;
      *seg = (uint32_t)s;
    }
  }
  return best;
}

/* Classic crossing number over all segments (floating point). */
static int brute_inside(const mx_poly *P, const double *p) {
  int c = 0;
  for (size_t s = 0; s < P->ns; s++) {
    const double *a = P->xy + 2 * P->seg[2 * s], *b = P->xy + 2 * P->seg[2 * s + 1];
    if ((a[1] > p[1]) != (b[1] > p[1])) {
      const double x = a[0] + (p[1] - a[1]) * (b[0] - a[0]) / (b[1] - a[1]);
      if (x > p[0]) c ^= 1;
    }
  }
  return c;
}

static uint64_t rng = 88172645463325252ULL;
static double urand(void) {
  rng ^= rng << 13;
  rng ^= rng >> 7;
  rng ^= rng << 17;
  return (double)(rng >> 11) * (1.0 / 9007199254740992.0);
}

/* ---- polylines in memory -------------------------------------------------- */

typedef struct {
  mx_poly P;
  size_t capv, caps;
} builder;

static uint32_t add_vertex(builder *B, double x, double y) {
  if (B->P.nv == B->capv) {
    B->capv = B->capv ? 2 * B->capv : 64;
    B->P.xy = mx_realloc(B->P.xy, 2 * B->capv * sizeof(double));
  }
  B->P.xy[2 * B->P.nv] = x;
  B->P.xy[2 * B->P.nv + 1] = y;
  return (uint32_t)B->P.nv++;
}

static void add_segment(builder *B, uint32_t a, uint32_t b) {
  if (B->P.ns == B->caps) {
    B->caps = B->caps ? 2 * B->caps : 64;
    B->P.seg = mx_realloc(B->P.seg, 2 * B->caps * sizeof(uint32_t));
  }
  B->P.seg[2 * B->P.ns] = a;
  B->P.seg[2 * B->P.ns + 1] = b;
  B->P.ns++;
}

/* A closed regular n-gon (ccw or not) around (cx, cy), radius r. */
static void add_ngon(builder *B, int n, double cx, double cy, double r, int ccw, double phase) {
  const uint32_t v0 = (uint32_t)B->P.nv;
  for (int i = 0; i < n; i++) {
    const double t = phase + 2 * M_PI * i / n * (ccw ? 1 : -1);
    add_vertex(B, cx + r * cos(t), cy + r * sin(t));
  }
  for (int i = 0; i < n; i++) add_segment(B, v0 + (uint32_t)i, v0 + (uint32_t)((i + 1) % n));
}

static void add_rect(builder *B, double x0, double y0, double x1, double y1, int ccw) {
  const uint32_t a = add_vertex(B, x0, y0), b = add_vertex(B, x1, y0);
  const uint32_t c = add_vertex(B, x1, y1), d = add_vertex(B, x0, y1);
  if (ccw) {
    add_segment(B, a, b), add_segment(B, b, c), add_segment(B, c, d), add_segment(B, d, a);
  } else {
    add_segment(B, a, d), add_segment(B, d, c), add_segment(B, c, b), add_segment(B, b, a);
  }
}

static size_t count_features(const mx_poly *P) {
  uint32_t *f = NULL;
  size_t n = 0;
  CHECK(mx_poly_features(P, &f, &n) == MX_OK);
  for (size_t i = 1; i < n; i++) CHECK(f[i - 1] < f[i]);
  mx_free(f);
  return n;
}

/* ---- the shared files ------------------------------------------------------ */

typedef struct {
  const char *name;
  size_t nv, ns, nholes, nloops, features;
  double area; /* of the domain, NAN: not checked */
} file_case;

static void test_shared_files(void) {
  /* counts read off the files; loops: the closed polylines they hold (pie:
   * the outer rim and one inner loop, 94 + 27 segments) */
  const double hole = 0.5 * fabs((0.4 * 0.1 - 0.6 * 0.3) + (0.6 * 0.7 - 0.7 * 0.1) +
                                 (0.7 * 0.6 - 0.3 * 0.7) + (0.3 * 0.3 - 0.4 * 0.6));
  const file_case cases[] = {
      {"a.poly", 29, 29, 1, 2, 29, NAN},
      {"a_reg1.poly", 4, 4, 0, 1, 4, 0.5 * 0.2 * 0.27},
      {"bar.poly", 4, 4, 0, 1, 4, 7.9989 * 1.998},
      {"box.poly", 8, 8, 1, 2, 8, 9.0 - 1.0},
      {"lonso.poly", 12, 12, 1, 2, 12, NAN},
      {"pie.poly", 287, 121, 0, 2, 33, NAN},
      {"square_with_hole.off", 8, 8, 0, 2, 8, 1.0 - hole},
      {"unit_square.poly", 4, 4, 0, 1, 4, 1.0},
  };
  for (size_t k = 0; k < sizeof cases / sizeof *cases; k++) {
    const file_case *c = &cases[k];
    mx_poly P;
    if (!read_shared(c->name, &P)) continue;
    const int before = mx_test_failures;
    CHECK(P.nv == c->nv && P.ns == c->ns && P.nholes == c->nholes);
    CHECK(P.path && strstr(P.path, c->name));
    for (size_t s = 0; s < P.ns; s++) CHECK(P.line[s] > 0 && P.seg[2 * s] < P.nv);
    msgs_reset();
    CHECK(mx_poly_check_domain(&P) == MX_OK);
    CHECK(nerr == 0);
    CHECK(P.nloops == c->nloops);
    CHECK(loops_consistent(&P));
    if (!isnan(c->area)) CHECK(fabs(0.5 * area2_of(&P, 0, (uint32_t)P.nv) - c->area) < 1e-12);
    CHECK(0.5 * area2_of(&P, 0, (uint32_t)P.nv) > 0);
    CHECK(count_features(&P) == c->features);
    printf("%s %-22s nv %zu ns %zu holes %zu loops %zu area %.6f%s%s\n",
           mx_test_failures == before ? "ok  " : "FAIL", c->name, P.nv, P.ns, P.nholes, P.nloops,
           0.5 * area2_of(&P, 0, (uint32_t)P.nv), nwarn ? "  warning: " : "",
           nwarn ? last_msg : "");
    mx_poly_free(&P);
  }
}

/* box.poly: the outer loop (vertices 1-4) counter-clockwise, the hole (5-8)
 * clockwise; the lines of its segments; inside/outside. */
static void test_box(void) {
  mx_poly P;
  if (!read_shared("box.poly", &P)) return;
  CHECK(P.line[0] == 15 && P.line[7] == 22);
  CHECK(P.holes[0] == 1.5 && P.holes[1] == 1.5);
  CHECK(mx_poly_check_domain(&P) == MX_OK);
  CHECK(0.5 * area2_of(&P, 0, 4) == 9.0);
  CHECK(0.5 * area2_of(&P, 4, 8) == -1.0);
  mx_poly_index I;
  CHECK(mx_poly_index_build(&P, &I) == MX_OK);
  const struct {
    double x, y;
    int want;
  } pts[] = {
      {1.5, 1.5, 0}, {0.5, 0.5, 1}, {2.5, 1.5, 1}, {1.5, 2.7, 1}, {-1, 1, 0},  {4, 1, 0},
      {1.5, -1, 0},  {1.5, 4, 0},   {0.5, 1, 1},   {0.5, 2, 1},   {2.5, 1, 1}, {1.5, 1.0 / 3, 1},
      {1.5, 0, 2},   {0, 1.7, 2},   {1, 1.5, 2},   {3, 3, 2},     {1, 1, 2},   {2, 1.25, 2},
      {0.75, 3, 2},  {1.5, 2, 2},   {1.2, 1.1, 0}, {3.0 + 1e-9, 1, 0},
  };
  int bad = 0;
  for (size_t k = 0; k < sizeof pts / sizeof *pts; k++) {
    const double p[2] = {pts[k].x, pts[k].y};
    const int got = mx_poly_inside(&I, p);
    if (got != pts[k].want) {
      printf("FAIL inside(%g, %g) = %d, want %d\n", p[0], p[1], got, pts[k].want);
      bad++;
    }
  }
  CHECK(bad == 0);
  double q[2], d2;
  const double p[2] = {1.5, 1.4};
  CHECK(mx_poly_closest(&I, p, INFINITY, q, &d2) == 4); /* the hole's bottom, "7 5" */
  CHECK(q[0] == 1.5 && q[1] == 1.0 && fabs(d2 - 0.16) < 1e-15);
  CHECK(mx_poly_closest(&I, p, 0.39, q, &d2) == UINT32_MAX);
  CHECK(d2 == INFINITY);
  const double far[2] = {100, -50};
  CHECK(mx_poly_closest(&I, far, INFINITY, q, &d2) == 0 && q[0] == 3 && q[1] == 0);
  printf("%s box.poly orientation, inside, closest\n", bad ? "FAIL" : "ok  ");
  mx_poly_index_free(&I);
  mx_poly_free(&P);
}

/* ---- orientation by nesting -------------------------------------------------- */

static void test_orientation(void) {
  const int before = mx_test_failures;
  /* a clockwise square: turned, one warning */
  builder B = {0};
  add_rect(&B, 0, 0, 1, 1, 0);
  msgs_reset();
  CHECK(mx_poly_check_domain(&B.P) == MX_OK);
  CHECK(nwarn == 1 && nerr == 0 && B.P.nloops == 1);
  CHECK(area2_of(&B.P, 0, 4) == 2.0);
  mx_poly_free(&B.P);

  /* three nested squares all clockwise: depth 0 and 2 turned, depth 1 kept;
   * a fourth beside them, counter-clockwise, kept */
  builder C = {0};
  add_rect(&C, 0, 0, 10, 10, 0);
  add_rect(&C, 2, 2, 8, 8, 0);
  add_rect(&C, 4, 4, 6, 6, 0);
  add_rect(&C, 20, 0, 21, 1, 1);
  msgs_reset();
  CHECK(mx_poly_check_domain(&C.P) == MX_OK);
  CHECK(nwarn == 1 && C.P.nloops == 4);
  CHECK(strstr(last_msg, "2 of 4 loop(s) turned") != NULL);
  CHECK(area2_of(&C.P, 0, 4) == 200 && area2_of(&C.P, 4, 8) == -72);
  CHECK(area2_of(&C.P, 8, 12) == 8 && area2_of(&C.P, 12, 16) == 2);
  mx_poly_free(&C.P);

  /* segments of one loop given in both directions and shuffled */
  builder D = {0};
  for (int i = 0; i < 6; i++) add_vertex(&D, cos(i * M_PI / 3), sin(i * M_PI / 3));
  const uint32_t segs[6][2] = {{3, 2}, {0, 1}, {4, 5}, {3, 4}, {0, 5}, {2, 1}};
  for (int i = 0; i < 6; i++) add_segment(&D, segs[i][0], segs[i][1]);
  msgs_reset();
  CHECK(mx_poly_check_domain(&D.P) == MX_OK);
  CHECK(loops_consistent(&D.P) && D.P.nloops == 1 && nwarn == 1);
  CHECK(fabs(0.5 * area2_of(&D.P, 0, 6) - 1.5 * sqrt(3)) < 1e-12);
  mx_poly_free(&D.P);

  /* already right: no warning */
  builder E = {0};
  add_rect(&E, 0, 0, 3, 3, 1);
  add_rect(&E, 1, 1, 2, 2, 0);
  msgs_reset();
  CHECK(mx_poly_check_domain(&E.P) == MX_OK);
  CHECK(nwarn == 0 && E.P.nloops == 2);
  mx_poly_free(&E.P);
  printf("%s orientation by nesting\n", mx_test_failures == before ? "ok  " : "FAIL");
}

/* ---- bad inputs ---------------------------------------------------------------- */

/* Writes text to tmpdir/name; reading it (by extension) must fail, or, with
 * domain set, reading must work and the domain check fail: MX_EINPUT, one
 * error naming "path:line:" (line > 0), and needle (and needle2) in it. */
static void expect_fail(const char *name, const char *text, int domain, long line,
                        const char *needle, const char *needle2) {
  const int before = mx_test_failures;
  char path[128];
  tpath(path, sizeof path, name);
  write_text(path, text);
  mx_poly P;
  memset(&P, 0xab, sizeof P);
  msgs_reset();
  int st = mx_read_poly_any(path, &P);
  if (domain) {
    CHECK(st == MX_OK);
    if (st == MX_OK) {
      msgs_reset();
      st = mx_poly_check_domain(&P);
      mx_poly_free(&P);
    }
  } else {
    CHECK(P.nv == 0 && P.ns == 0 && P.xy == NULL && P.seg == NULL && P.path == NULL);
  }
  CHECK(st == MX_EINPUT);
  CHECK(nerr == 1);
  CHECK(strstr(last_msg, path) != NULL);
  if (line > 0) {
    char loc[200];
    snprintf(loc, sizeof loc, "%s:%ld:", path, line);
    CHECK(strstr(last_msg, loc) != NULL);
  }
  if (needle) CHECK(strstr(last_msg, needle) != NULL);
  if (needle2) CHECK(strstr(last_msg, needle2) != NULL);
  printf("%s %-24s %s\n", mx_test_failures == before ? "ok  " : "FAIL", name,
         last_msg[0] ? last_msg + strlen(tmpdir) + 1 : "(no message)");
}

#define SQUARE_V "4 2 0 0\n1 0 0\n2 1 0\n3 1 1\n4 0 1\n"

static void test_bad_geometry(void) {
  /* bow-tie: (0,0)-(1,1) crosses (1,0)-(0,1) */
  expect_fail("bowtie.poly",
              "4 2 0 0\n1 0 0\n2 1 1\n3 1 0\n4 0 1\n4 0\n1 1 2\n2 2 3\n3 3 4\n4 4 1\n0\n", 1, 7,
              "cross", "line 9");
  expect_fail("open.poly", SQUARE_V "3 0\n1 1 2\n2 2 3\n3 3 4\n0\n", 1, 7, "open polyline", NULL);
  /* T junction: a fifth vertex joined to a corner of the square */
  expect_fail("t_vertex.poly",
              "5 2 0 0\n1 0 0\n2 1 0\n3 1 1\n4 0 1\n5 -1 -1\n5 0\n1 1 2\n2 2 3\n3 3 4\n4 4 1\n"
              "5 5 1\n0\n",
              1, 8, "3 segments meet at (0, 0)", "line 12");
  /* T junction: a corner of one triangle on the side of another */
  expect_fail("t_side.poly",
              "6 2 0 0\n1 0 0\n2 2 0\n3 1 1\n4 1 0\n5 2 -1\n6 0 -1\n"
              "6 0\n1 1 2\n2 2 3\n3 3 1\n4 4 5\n5 5 6\n6 6 4\n0\n",
              1, 9, "touch", "line 12");
  /* two squares overlapping along x = 1, y in [0.5, 1]: their sides there
   * come first in each loop, so that pair is the lowest (the other side's
   * ends touch too) */
  expect_fail("overlap.poly",
              "8 2 0 0\n1 0 0\n2 1 0\n3 1 1\n4 0 1\n5 1 0.5\n6 2 0.5\n7 2 1.5\n8 1 1.5\n"
              "8 0\n1 2 3\n2 3 4\n3 4 1\n4 1 2\n5 8 5\n6 5 6\n7 6 7\n8 7 8\n0\n",
              1, 11, "overlap", "line 15");
  /* a loop folding back onto itself: (0,0) (2,0) (1,0) (1,1) */
  expect_fail("foldback.poly",
              "4 2 0 0\n1 0 0\n2 2 0\n3 1 0\n4 1 1\n4 0\n1 1 2\n2 2 3\n3 3 4\n4 4 1\n0\n", 1, 7,
              "overlap", "line 8");
  expect_fail("zero.poly", SQUARE_V "5 0\n1 1 2\n2 2 3\n3 3 3\n4 3 4\n5 4 1\n0\n", 1, 9,
              "zero-length", NULL);
  expect_fail("zero_xy.poly",
              "5 2 0 0\n1 0 0\n2 1 0\n3 1 1\n4 1 1\n5 0 1\n5 0\n1 1 2\n2 2 3\n3 3 4\n4 4 5\n"
              "5 5 1\n0\n",
              1, 10, "zero-length", NULL);
  expect_fail("huge.poly", "4 2 0 0\n1 0 0\n2 1e200 0\n3 1 1\n4 0 1\n4 0\n1 1 2\n2 2 3\n"
              "3 3 4\n4 4 1\n0\n", 1, 7, "beyond", NULL);
  expect_fail("twice.poly", "3 2 0 0\n1 0 0\n2 1 0\n3 0 1\n2 0\n1 1 2\n2 2 1\n0\n", 1, 6,
              "join the same two vertices", "line 7");
}

static void test_bad_text(void) {
  expect_fail("node_file.poly", "0 2 0 0\n4 0\n1 1 2\n2 2 3\n3 3 4\n4 4 1\n0\n", 0, 1, ".node",
              NULL);
  expect_fail("dim3.poly", "4 3 0 0\n", 0, 1, "dimension 3", NULL);
  expect_fail("markers2.poly", "4 2 0 2\n", 0, 1, "markers", NULL);
  expect_fail("few_vertices.poly", "5 2 0 0\n1 0 0\n2 1 0\n3 1 1\n4 0 1\n4 0\n1 1 2\n", 0, 6,
              "vertex number 4 where 5", NULL);
  expect_fail("many_segments.poly", SQUARE_V "5 0\n1 1 2\n2 2 3\n3 3 4\n4 4 1\n0\n", 0, 11,
              "missing segment endpoint", NULL);
  expect_fail("huge_count.poly", "400000000 2 0 0\n1 0 0\n", 0, 1, "more than the rest", NULL);
  expect_fail("no_holes.poly", SQUARE_V "4 0\n1 1 2\n2 2 3\n3 3 4\n4 4 1\n", 0, 11,
              "number of holes", NULL);
  expect_fail("holes_short.poly", SQUARE_V "4 0\n1 1 2\n2 2 3\n3 3 4\n4 4 1\n2\n1 0.5 0.5\n", 0,
              13, "1 of 2 holes", NULL);
  expect_fail("trailing.poly", SQUARE_V "4 0\n1 1 2\n2 2 3\n3 3 4\n4 4 1\n0\n0\n7 7 7\n", 0, 13,
              "more data", NULL);
  expect_fail("nan.poly", "4 2 0 0\n1 0 0\n2 nan 0\n3 1 1\n4 0 1\n", 0, 3, "finite", NULL);
  expect_fail("inf.poly", "4 2 0 0\n1 0 0\n2 1 0\n3 1 -inf\n4 0 1\n", 0, 4, "finite", NULL);
  expect_fail("overflow.poly", "4 2 0 0\n1 0 0\n2 1 0\n3 1 1\n4 1e999 1\n", 0, 5, "finite", NULL);
  expect_fail("not_number.poly", "4 2 0 0\n1 0 0\n2 1 zero\n", 0, 3, "not a number", NULL);
  expect_fail("range.poly", SQUARE_V "4 0\n1 1 2\n2 2 3\n3 3 5\n4 4 1\n0\n", 0, 9,
              "endpoint 5 out of range", NULL);
  expect_fail("range0.poly", "3 2 0 0\n0 0 0\n1 1 0\n2 0 1\n3 0\n0 0 1\n1 1 2\n2 2 3\n0\n", 0, 8,
              "endpoint 3 out of range (vertices 0 to 2)", NULL);
  expect_fail("first2.poly", "3 2 0 0\n2 0 0\n", 0, 2, "expected 0 or 1", NULL);
  expect_fail("attr_missing.poly", "3 2 1 1\n1 0 0 5\n", 0, 2, "missing", NULL);
  expect_fail("seg_marker.poly", SQUARE_V "4 1\n1 1 2 0\n2 2 3\n", 0, 8, "missing", NULL);
  expect_fail("regions_short.poly",
              SQUARE_V "4 0\n1 1 2\n2 2 3\n3 3 4\n4 4 1\n0\n2\n1 0.5 0.5 1 -1\n", 0, 14,
              "regional", NULL);
  expect_fail("empty.poly", "# nothing\n\n", 0, 0, "no content", NULL);
  expect_fail("no_segments.poly", SQUARE_V "0 0\n0\n", 0, 6, "0 segments", NULL);
  /* OFF */
  expect_fail("z.off", "OFF\n3 1 0\n0 0 0\n1 0 0.5\n0 1 0\n3 0 1 2\n", 0, 4, "z = 0.5", NULL);
  expect_fail("k2.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n2 0 1\n", 0, 6, "3 or more", NULL);
  expect_fail("idx.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n", 0, 6, "out of range",
              NULL);
  expect_fail("short.off", "OFF\n3 2 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", 0, 7, "1 of 2 faces",
              NULL);
  expect_fail("header.off", "OF\n3 1 0\n", 0, 1, "OFF", NULL);
  /* MDL */
  expect_fail("no_edges.mdl", "[Vertices, ARRAY1<POINT2D>]\n3\n0 0\n1 0\n0 1\n", 0, 0, "Edges",
              NULL);
  expect_fail("edge_range.mdl",
              "[Edges, ARRAY1<STRING>]\n3\n0 1\n1 7\n2 0\n[Vertices, ARRAY1<POINT2D>]\n3\n0 0\n1 0\n"
              "0 1\n",
              0, 4, "vertex index 7 out of range", NULL);
  expect_fail("z.mdl", "[Vertices, ARRAY1<POINT3D>]\n2\n0 0 0\n1 0 2\n", 0, 4, "z = 2", NULL);
  expect_fail("count.mdl", "[Vertices, ARRAY1<POINT2D>]\n3\n0 0\n1 0\n[Edges, ARRAY1<STRING>]\n",
              0, 5, "2 of 3 vertices", NULL);
  expect_fail("type.mdl", "[Vertices, ARRAY1<VECTOR3D>]\n1\n0 0 0\n", 0, 1, "POINT2D", NULL);
  expect_fail("square.svg", "<svg/>\n", 0, 0, "unknown 2D input format '.svg'", NULL);
}

/* Every proper prefix (by lines) of a good file is refused, every prefix by
 * bytes is refused or read sanely (never a crash). */
static void test_truncated(void) {
  const char *good = "# a square with a hole\n"
                     "8 2 1 1\n"
                     "1 0 0 0.5 1\n2 3 0 0.5 1\n3 3 3 0.5 1\n4 0 3 0.5 1\n"
                     "5 1 1 0 0\n6 2 1 0 0\n7 2 2 0 0\n8 1 2 0 0\n"
                     "8 1\n1 1 2 1\n2 2 3 1\n3 3 4 1\n4 4 1 1\n5 5 8 2\n6 8 7 2\n7 7 6 2\n8 6 5 2\n"
                     "1\n1 1.5 1.5\n";
  char path[128], buf[1024];
  tpath(path, sizeof path, "trunc.poly");
  int bad_lines = 0, bad_bytes = 0, lines = 0;
  const size_t len = strlen(good);
  for (size_t n = 0; n < len; n++) {
    memcpy(buf, good, n);
    buf[n] = '\0';
    write_text(path, buf);
    mx_poly P;
    msgs_reset();
    const int st = mx_read_poly(path, &P);
    if (n == 0 || good[n - 1] == '\n') { /* whole lines, not all */
      lines++;
      bad_lines += st != MX_EINPUT || nerr != 1;
    }
    if (st == MX_OK) {
      bad_bytes += P.nv != 8 || P.ns != 8 || P.nholes != 1 || mx_poly_check_domain(&P) != MX_OK;
      mx_poly_free(&P);
    } else {
      bad_bytes += st != MX_EINPUT || nerr != 1 || P.xy != NULL;
    }
  }
  write_text(path, good);
  mx_poly P;
  CHECK(mx_read_poly(path, &P) == MX_OK && P.nv == 8 && P.ns == 8);
  CHECK(mx_poly_check_domain(&P) == MX_OK && P.nloops == 2);
  mx_poly_free(&P);
  CHECK(bad_lines == 0 && bad_bytes == 0);
  printf("%s truncated files: %d line prefixes, %zu byte prefixes\n",
         bad_lines || bad_bytes ? "FAIL" : "ok  ", lines, len);
}

/* OFF, MDL (2D and 3D points, either section order, Segments) and .poly of
 * the same domain read the same. */
static void test_formats_agree(void) {
  const int before = mx_test_failures;
  char p_off[128], p_mdl[128], p_mdl3[128], p_poly[128];
  tpath(p_off, sizeof p_off, "swh.off");
  tpath(p_mdl, sizeof p_mdl, "swh.mdl");
  tpath(p_mdl3, sizeof p_mdl3, "swh3.MDL");
  tpath(p_poly, sizeof p_poly, "swh.poly");
  write_text(p_off, "OFF # comment\n8 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n0.4 0.3 0\n0.6 0.1 0\n"
                    "0.7 0.7 0\n0.3 0.6 0\n4  0 1 2 3\n\n4 7 6 5 4 255 0 0\n");
  write_text(p_mdl, "[Name, STRING]\nswh\n\n[Vertices, ARRAY1<POINT2D>]\n8\n0 0\n1 0\n1 1\n0 1\n"
                    "0.4 0.3\n0.6 0.1\n0.7 0.7\n0.3 0.6\n\n[Edges, ARRAY1<STRING>]\n8\n0 1\n1 2\n"
                    "2 3\n3 0\n7 6\n6 5\n5 4\n4 7\n");
  write_text(p_mdl3, "[Segments, ARRAY1<STRING>]\n8\n0 1\n1 2\n2 3\n3 0\n7 6\n6 5\n5 4\n4 7\n"
                     "[Normals, ARRAY1<VECTOR3D>]\n1\n0 0 1\n"
                     "[Vertices, ARRAY1<POINT3D>]\n8\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n"
                     "0.4 0.3 0\n0.6 0.1 0\n0.7 0.7 0\n0.3 0.6 -0\n");
  write_text(p_poly, "8 2\n0 0 0\n1 1 0\n2 1 1\n3 0 1\n4 0.4 0.3\n5 0.6 0.1\n6 0.7 0.7\n"
                     "7 0.3 0.6\n8\n0 0 1\n1 1 2\n2 2 3\n3 3 0\n4 7 6\n5 6 5\n6 5 4\n7 4 7\n0\n");
  mx_poly A, B, C, D;
  CHECK(mx_read_poly_any(p_off, &A) == MX_OK);
  CHECK(mx_read_poly_any(p_mdl, &B) == MX_OK);
  CHECK(mx_read_poly_any(p_mdl3, &C) == MX_OK);
  CHECK(mx_read_poly_any(p_poly, &D) == MX_OK);
  const mx_poly *all[] = {&B, &C, &D};
  for (int k = 0; k < 3; k++) {
    CHECK(all[k]->nv == 8 && all[k]->ns == 8);
    CHECK(memcmp(all[k]->xy, A.xy, 16 * sizeof(double)) == 0);
    CHECK(memcmp(all[k]->seg, A.seg, 16 * sizeof(uint32_t)) == 0);
  }
  CHECK(A.line[0] == 11 && A.line[3] == 11 && A.line[4] == 13 && A.line[7] == 13);
  CHECK(B.line[0] == 17 && C.line[7] == 10 && D.line[0] == 11);
  CHECK(A.seg[6] == 3 && A.seg[7] == 0 && A.seg[8] == 7 && A.seg[15] == 7);
  CHECK(mx_poly_check_domain(&A) == MX_OK && A.nloops == 2 && count_features(&A) == 8);
  mx_poly_free(&A);
  mx_poly_free(&B);
  mx_poly_free(&C);
  mx_poly_free(&D);
  printf("%s .off, .mdl (2D, 3D) and .poly read the same\n",
         mx_test_failures == before ? "ok  " : "FAIL");
}

/* ---- point location against brute force ------------------------------------- */

/* closed: inside is compared too (an open polyline has no inside). */
static void check_queries(const char *label, const mx_poly *P, int npts, int closed) {
  mx_poly_index I;
  CHECK(mx_poly_index_build(P, &I) == MX_OK);
  double lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY};
  for (size_t i = 0; i < 2 * P->ns; i++) /* the segments' box, as the index's */
    for (int d = 0; d < 2; d++) {
      lo[d] = fmin(lo[d], P->xy[2 * P->seg[i] + d]);
      hi[d] = fmax(hi[d], P->xy[2 * P->seg[i] + d]);
    }
  const double D = hypot(hi[0] - lo[0], hi[1] - lo[1]);
  int bad_d = 0, bad_in = 0, bad_r = 0, compared = 0;
  for (int k = 0; k < npts; k++) {
    double p[2];
    for (int d = 0; d < 2; d++) /* the box and a margin of half its size */
      p[d] = lo[d] - 0.5 * (hi[d] - lo[d]) + 2 * (hi[d] - lo[d]) * urand();
    if (k % 10 == 0) { /* on a segment, or near one */
      const size_t s = (size_t)(urand() * (double)P->ns);
      const double *a = P->xy + 2 * P->seg[2 * s], *b = P->xy + 2 * P->seg[2 * s + 1];
      const double t = urand();
      p[0] = a[0] + t * (b[0] - a[0]) + (k % 20 ? 0 : 1e-6 * D * (urand() - 0.5));
      p[1] = a[1] + t * (b[1] - a[1]);
    }
    uint32_t bs;
    const double bd = brute_closest(P, p, &bs);
    double q[2], d2;
    const uint32_t s = mx_poly_closest(&I, p, INFINITY, q, &d2);
    bad_d += s == UINT32_MAX || d2 != bd ||
             d2 != dist2(P->xy + 2 * P->seg[2 * s], P->xy + 2 * P->seg[2 * s + 1], p) ||
             (q[0] - p[0]) * (q[0] - p[0]) + (q[1] - p[1]) * (q[1] - p[1]) > d2 * (1 + 1e-12) + 1e-300;
    if (bd > 0) { /* rmax just below and just above the distance */
      bad_r += mx_poly_closest(&I, p, sqrt(bd) * (1 - 1e-9), q, &d2) != UINT32_MAX;
      bad_r += mx_poly_closest(&I, p, sqrt(bd) * (1 + 1e-9), q, &d2) == UINT32_MAX || d2 != bd;
    }
    const int in = mx_poly_inside(&I, p);
    if (bd <= 1e-24 * D * D) {
      bad_in += in != 2;
    } else if (closed && bd > 1e-18 * D * D) {
      compared++;
      bad_in += in != brute_inside(P, p);
    }
  }
  mx_poly_index_free(&I);
  CHECK(bad_d == 0 && bad_in == 0 && bad_r == 0);
  printf("%s %-20s %d points: closest (%d wrong), rmax (%d wrong), inside (%d of %d wrong)\n",
         bad_d || bad_in || bad_r ? "FAIL" : "ok  ", label, npts, bad_d, bad_r, bad_in, compared);
}

static void test_queries(void) {
  const char *names[] = {"pie.poly", "a.poly", "lonso.poly", "box.poly", "drawing.poly"};
  for (int k = 0; k < 5; k++) {
    mx_poly P;
    if (!read_shared(names[k], &P)) continue;
    if (k < 4) CHECK(mx_poly_check_domain(&P) == MX_OK);
    check_queries(names[k], &P, 3000, k < 4);
    mx_poly_free(&P);
  }
  builder B = {0}; /* many loops, a dense cluster, a long thin one */
  add_ngon(&B, 2000, 0, 0, 100, 1, 0.1);
  add_ngon(&B, 3000, 30, 30, 1e-3, 0, 0.2);
  for (int i = 0; i < 50; i++) add_rect(&B, -50 + 2 * i, -20, -49.5 + 2 * i, -19, 0);
  add_rect(&B, -60, 10, 60, 10.001, 0);
  msgs_reset();
  CHECK(mx_poly_check_domain(&B.P) == MX_OK && B.P.nloops == 53 && nwarn == 0);
  check_queries("clustered loops", &B.P, 4000, 1);
  mx_poly_index I; /* points around the tiny loop */
  CHECK(mx_poly_index_build(&B.P, &I) == MX_OK);
  int bad = 0;
  for (int k = 0; k < 2000; k++) {
    const double p[2] = {30 + 3e-3 * (urand() - 0.5), 30 + 3e-3 * (urand() - 0.5)};
    uint32_t bs;
    const double bd = brute_closest(&B.P, p, &bs);
    double q[2], d2;
    mx_poly_closest(&I, p, INFINITY, q, &d2);
    bad += d2 != bd;
    if (bd > 1e-20) bad += mx_poly_inside(&I, p) != brute_inside(&B.P, p);
  }
  CHECK(bad == 0);
  mx_poly_index_free(&I);
  mx_poly_free(&B.P);
  mx_poly E = {0}; /* no segments: nothing inside, nothing near */
  CHECK(mx_poly_index_build(&E, &I) == MX_OK);
  const double p[2] = {0, 0};
  double q[2], d2;
  CHECK(mx_poly_inside(&I, p) == 0 && mx_poly_closest(&I, p, INFINITY, q, &d2) == UINT32_MAX);
  mx_poly_index_free(&I);
}

/* ---- features --------------------------------------------------------------- */

static void test_features(void) {
  const int before = mx_test_failures;
  builder B = {0};
  add_ngon(&B, 400, 0, 0, 1, 1, 0); /* turns by 0.9 degrees */
  CHECK(count_features(&B.P) == 0);
  add_ngon(&B, 71, 5, 5, 1, 1, 0); /* turns by 5.07 degrees: 174.93 */
  CHECK(count_features(&B.P) == 71);
  add_ngon(&B, 73, 9, 9, 1, 0, 0); /* 4.93 degrees: 175.07, clockwise */
  CHECK(count_features(&B.P) == 71);
  mx_poly_free(&B.P);
  mx_poly P;
  if (read_shared("unit_square.poly", &P)) {
    uint32_t *f;
    size_t n;
    CHECK(mx_poly_features(&P, &f, &n) == MX_OK && n == 4);
    for (size_t i = 0; i < n; i++) CHECK(f[i] == i);
    mx_free(f);
    mx_poly_free(&P);
  }
  if (read_shared("square_with_hole.off", &P)) {
    CHECK(count_features(&P) == 8);
    mx_poly_free(&P);
  }
  if (read_shared("drawing.poly", &P)) { /* open: 1-2-3 and 4-5; only vertex 2 */
    uint32_t *f;
    size_t n;
    CHECK(P.nv == 5 && P.ns == 3 && P.nholes == 0 && P.line[2] == 13);
    CHECK(mx_poly_features(&P, &f, &n) == MX_OK && n == 1 && f[0] == 1);
    mx_free(f);
    msgs_reset();
    CHECK(mx_poly_check_domain(&P) == MX_EINPUT && strstr(last_msg, "open polyline"));
    mx_poly_free(&P);
  }
  printf("%s features\n", mx_test_failures == before ? "ok  " : "FAIL");
}

/* ---- the crossing check at scale --------------------------------------------- */

/* A star polygon {101/40} crosses itself everywhere: the pair reported is
 * the lowest crossing pair found by brute force, for any thread count. */
static int brute_cross(const double *a, const double *b, const double *c, const double *d) {
  const double o1 = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
  const double o2 = (b[0] - a[0]) * (d[1] - a[1]) - (b[1] - a[1]) * (d[0] - a[0]);
  const double o3 = (d[0] - c[0]) * (a[1] - c[1]) - (d[1] - c[1]) * (a[0] - c[0]);
  const double o4 = (d[0] - c[0]) * (b[1] - c[1]) - (d[1] - c[1]) * (b[0] - c[0]);
  return o1 * o2 < 0 && o3 * o4 < 0;
}

/* A 100k-gon with 400 counter-clockwise square holes (turned) and a 20k-gon
 * hole of radius 1e-4 (clustered in one cell of the coarse grid): valid, the
 * same result for 1 and 2 threads. */
static void test_scale(void) {
  const int before = mx_test_failures;
  uint32_t *seg1 = NULL;
  for (int threads = 1; threads <= 2; threads++) {
    omp_set_num_threads(threads);
    builder B = {0};
    add_ngon(&B, 100000, 0, 0, 1, 1, 0);
    for (int i = 0; i < 20; i++)
      for (int j = 0; j < 20; j++)
        add_rect(&B, -0.6 + 0.06 * i, -0.6 + 0.06 * j, -0.58 + 0.06 * i, -0.58 + 0.06 * j, 1);
    add_ngon(&B, 20000, 0.7, 0.1, 1e-4, 0, 0);
    msgs_reset();
    const double t0 = omp_get_wtime();
    CHECK(mx_poly_check_domain(&B.P) == MX_OK);
    const double t = omp_get_wtime() - t0;
    CHECK(B.P.nloops == 402 && nwarn == 1 && strstr(last_msg, "400 of 402 loop(s)"));
    const double want = 100000 * sin(2 * M_PI / 100000) - 400 * 2 * 0.0004 -
                        20000 * sin(2 * M_PI / 20000) * 1e-8;
    CHECK(fabs(area2_of(&B.P, 0, (uint32_t)B.P.nv) - want) < 1e-9);
    CHECK(loops_consistent(&B.P));
    if (!seg1) {
      seg1 = malloc(2 * B.P.ns * sizeof *seg1);
      memcpy(seg1, B.P.seg, 2 * B.P.ns * sizeof *seg1);
    } else {
      CHECK(memcmp(seg1, B.P.seg, 2 * B.P.ns * sizeof *seg1) == 0);
    }
    /* a triangle added whose base a-b crosses the tiny loop twice (its
     * other sides pass farther than the loop's radius): the pair reported is
     * the lowest tiny-loop segment crossing a-b (found by brute force) */
    const uint32_t a = add_vertex(&B, 0.7 - 2e-4, 0.10003), b = add_vertex(&B, 0.7 + 2e-4, 0.10003);
    const uint32_t c = add_vertex(&B, 0.7, 0.1003);
    add_segment(&B, a, b), add_segment(&B, b, c), add_segment(&B, c, a);
    size_t first = 0;
    for (size_t s = 101600; s < B.P.ns - 3 && !first; s++)
      if (brute_cross(B.P.xy + 2 * B.P.seg[2 * s], B.P.xy + 2 * B.P.seg[2 * s + 1], B.P.xy + 2 * a,
                      B.P.xy + 2 * b))
        first = s;
    msgs_reset();
    CHECK(mx_poly_check_domain(&B.P) == MX_EINPUT);
    char want_msg[96];
    snprintf(want_msg, sizeof want_msg, "segment %zu and segment %zu cross", first, B.P.ns - 3);
    CHECK(strstr(last_msg, want_msg) != NULL);
    printf("%s scale, %d thread(s): %zu segments checked in %.3f s; then: %s\n",
           mx_test_failures == before ? "ok  " : "FAIL", threads, B.P.ns - 3, t, last_msg);
    mx_poly_free(&B.P);
  }
  free(seg1);
  omp_set_num_threads(2);
}

static void test_star(void) {
  const int n = 101, k = 40, before = mx_test_failures;
  builder B = {0};
  for (int i = 0; i < n; i++) add_vertex(&B, cos(2 * M_PI * i / n), sin(2 * M_PI * i / n));
  for (int i = 0; i < n; i++) add_segment(&B, (uint32_t)(i * k % n), (uint32_t)((i + 1) * k % n));
  size_t s0 = 0, t0 = 0;
  for (size_t s = 0; s < B.P.ns && !t0; s++)
    for (size_t t = s + 1; t < B.P.ns && !t0; t++)
      if (brute_cross(B.P.xy + 2 * B.P.seg[2 * s], B.P.xy + 2 * B.P.seg[2 * s + 1],
                      B.P.xy + 2 * B.P.seg[2 * t], B.P.xy + 2 * B.P.seg[2 * t + 1]))
        s0 = s, t0 = t;
  char want[96];
  snprintf(want, sizeof want, "segment %zu and segment %zu cross", s0, t0);
  for (int threads = 1; threads <= 2; threads++) {
    omp_set_num_threads(threads);
    mx_poly P = B.P; /* the check may turn segments: a copy each time */
    P.seg = malloc(2 * P.ns * sizeof *P.seg);
    memcpy(P.seg, B.P.seg, 2 * P.ns * sizeof *P.seg);
    msgs_reset();
    CHECK(mx_poly_check_domain(&P) == MX_EINPUT);
    CHECK(strstr(last_msg, want) != NULL);
    free(P.seg);
  }
  printf("%s star polygon: %s\n", mx_test_failures == before ? "ok  " : "FAIL", last_msg);
  mx_poly_free(&B.P);
}

int main(void) {
  snprintf(tmpdir, sizeof tmpdir, "/tmp/mx_test_poly_XXXXXX");
  if (!mkdtemp(tmpdir)) {
    perror("mkdtemp");
    return 1;
  }
  mx_msg_fn = keep_message;
  find_data();
  test_shared_files();
  test_box();
  test_orientation();
  test_bad_geometry();
  test_bad_text();
  test_truncated();
  test_formats_agree();
  test_queries();
  test_features();
  test_scale();
  test_star();
  mx_msg_fn = NULL;
  char cmd[128];
  snprintf(cmd, sizeof cmd, "rm -rf %s", tmpdir);
  if (system(cmd) != 0) fprintf(stderr, "could not remove %s\n", tmpdir);
  return TEST_DONE();
}
