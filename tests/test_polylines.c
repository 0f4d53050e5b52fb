/* The feature polylines reader (src/io/read_polylines.c): lines and
 * corners of small files whose answers follow from the definitions in
 * io/read_polylines.h -- a square loop (4 corners at 30 degrees, a loop
 * without corner at 100), open lines, T junctions (three ends meeting, an
 * end on another line's interior point), a straight line given as two
 * polylines that join (either direction), a square as four polylines --
 * and bad inputs refused with MX_EINPUT and a message naming the file and
 * the line. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "check.h"
#include "base/common.h"
#include "geom/feature_walk.h"
#include "io/read_polylines.h"

static char tmpdir[64];
static char last_msg[2048];
static int nerr;

static void keep_message(void *user, int level, const char *text) {
  (void)user;
  if (level == MX_MSG_ERROR) nerr++;
  snprintf(last_msg, sizeof last_msg, "%s", text);
}

/* mx_feature_lines_free may not be in the library yet (src/geom/features.c):
 * a local one. */
static void lines_free(mx_feature_lines *L) {
  mx_free(L->first);
  mx_free(L->xyz);
  mx_free(L->loop);
  mx_free(L->corner);
  memset(L, 0, sizeof *L);
}

static const char *write_file(const char *name, const char *text) {
  static char path[128];
  snprintf(path, sizeof path, "%s/%s", tmpdir, name);
  FILE *f = fopen(path, "wb");
  if (!f) {
    perror(path);
    exit(1);
  }
  fputs(text, f);
  fclose(f);
  return path;
}

static int read_text(const char *text, double angle, mx_feature_lines *L) {
  const char *path = write_file("t.polylines.txt", text);
  last_msg[0] = '\0';
  nerr = 0;
  const int st = mx_read_polylines(path, angle, L);
  if (st != MX_OK) printf("  refused: %s\n", last_msg);
  return st;
}

static size_t npoints(const mx_feature_lines *L, size_t i) {
  return L->first[i + 1] - L->first[i];
}

static const double *point(const mx_feature_lines *L, size_t i, size_t j) {
  return L->xyz + 3 * (L->first[i] + j);
}

static int at(const double *p, double x, double y, double z) {
  return p[0] == x && p[1] == y && p[2] == z;
}

static int has_corner(const mx_feature_lines *L, double x, double y, double z) {
  for (size_t c = 0; c < L->ncorners; c++)
    if (at(L->corner + 3 * c, x, y, z)) return 1;
  return 0;
}

/* Every line but loops starts and ends at a corner; loops have none. */
static void lines_end_at_corners(const mx_feature_lines *L) {
  for (size_t i = 0; i < L->nlines; i++) {
    const size_t n = npoints(L, i);
    CHECK(n >= 2);
    if (L->loop[i]) {
      for (size_t j = 0; j < n; j++) {
        const double *p = point(L, i, j);
        CHECK(!has_corner(L, p[0], p[1], p[2]));
      }
      continue;
    }
    const double *a = point(L, i, 0), *b = point(L, i, n - 1);
    CHECK(has_corner(L, a[0], a[1], a[2]) && has_corner(L, b[0], b[1], b[2]));
    for (size_t j = 1; j + 1 < n; j++) {
      const double *p = point(L, i, j);
      CHECK(!has_corner(L, p[0], p[1], p[2]));
    }
  }
}

static void show(const char *what, const mx_feature_lines *L) {
  printf("%s: %zu lines, %zu corners\n", what, L->nlines, L->ncorners);
  lines_end_at_corners(L);
}

static void square(void) {
  const char *text = "# a unit square, closed\n\n5 0 0 0 1 0 0 1 1 0 0 1 0 0 0 0\n";
  mx_feature_lines L;
  CHECK(read_text(text, 30.0, &L) == MX_OK);
  show("square at 30", &L);
  CHECK(L.nlines == 4 && L.ncorners == 4);
  for (size_t i = 0; i < L.nlines; i++) CHECK(npoints(&L, i) == 2 && !L.loop[i]);
  CHECK(at(point(&L, 0, 0), 0, 0, 0) && at(point(&L, 0, 1), 1, 0, 0)); /* the file's way */
  CHECK(has_corner(&L, 0, 0, 0) && has_corner(&L, 1, 0, 0) && has_corner(&L, 1, 1, 0) &&
        has_corner(&L, 0, 1, 0));
  lines_free(&L);
  CHECK(read_text(text, 100.0, &L) == MX_OK);
  show("square at 100", &L);
  CHECK(L.nlines == 1 && L.ncorners == 0 && L.loop[0] && npoints(&L, 0) == 4);
  CHECK(at(point(&L, 0, 0), 0, 0, 0) && at(point(&L, 0, 1), 1, 0, 0) &&
        at(point(&L, 0, 3), 0, 1, 0));
  lines_free(&L);
  /* the same square as four polylines, in any direction: joined at 100 */
  CHECK(read_text("2 0 0 0 1 0 0\n2 1 1 0 1 0 0\n2 1 1 0 0 1 0\n2 0 0 0 0 1 0\n", 100.0,
                  &L) == MX_OK);
  show("square of 4 polylines at 100", &L);
  CHECK(L.nlines == 1 && L.ncorners == 0 && L.loop[0] && npoints(&L, 0) == 4);
  lines_free(&L);
  CHECK(read_text("2 0 0 0 1 0 0\n2 1 1 0 1 0 0\n2 1 1 0 0 1 0\n2 0 0 0 0 1 0\n", 30.0,
                  &L) == MX_OK);
  CHECK(L.nlines == 4 && L.ncorners == 4);
  lines_free(&L);
  /* a loop with one corner: an open line from it back to it */
  CHECK(read_text("6 0 0 0 1 0 0 2 0.1 0 2 1 0 1 1 0 0 0 0\n", 50.0, &L) == MX_OK);
  show("loop with one sharp point at 50", &L);
  CHECK(L.ncorners >= 1);
  lines_free(&L);
}

static void open_lines(void) {
  mx_feature_lines L;
  CHECK(read_text("3 0 0 0 1 0 0 2 0.1 0   # a slight turn\n", 30.0, &L) == MX_OK);
  show("open line", &L);
  CHECK(L.nlines == 1 && L.ncorners == 2 && !L.loop[0] && npoints(&L, 0) == 3);
  CHECK(at(point(&L, 0, 0), 0, 0, 0) && at(point(&L, 0, 2), 2, 0.1, 0));
  CHECK(has_corner(&L, 0, 0, 0) && has_corner(&L, 2, 0.1, 0));
  lines_free(&L);
  /* a sharp interior turn splits it */
  CHECK(read_text("4 0 0 0 1 0 0 1 1 0 1 2 0.5\n", 30.0, &L) == MX_OK);
  show("open line turning at a right angle", &L);
  CHECK(L.nlines == 2 && L.ncorners == 3 && has_corner(&L, 1, 0, 0));
  CHECK(npoints(&L, 0) == 2 && npoints(&L, 1) == 3);
  lines_free(&L);
  /* angle 0: any turn is a corner; 180: none but the ends */
  CHECK(read_text("3 0 0 0 1 0 0 2 0.1 0\n", 0.0, &L) == MX_OK);
  CHECK(L.nlines == 2 && L.ncorners == 3);
  lines_free(&L);
  CHECK(read_text("4 0 0 0 1 0 0 0 1 0 1 1 0\n", 180.0, &L) == MX_OK);
  CHECK(L.nlines == 1 && L.ncorners == 2);
  lines_free(&L);
}

static void junctions(void) {
  mx_feature_lines L;
  /* three ends meeting */
  CHECK(read_text("2 -1 0 0 0 0 0\n2 0 0 0 1 0 0\n2 0 0 0 0 1 0\n", 30.0, &L) == MX_OK);
  show("T of three polylines", &L);
  CHECK(L.nlines == 3 && L.ncorners == 4 && has_corner(&L, 0, 0, 0));
  lines_free(&L);
  /* the stem ending on the bar's interior point: the bar split there */
  CHECK(read_text("3 -1 0 0 0 0 0 1 0 0\n2 0 1 0 0 0 0\n", 30.0, &L) == MX_OK);
  show("T, stem on the bar", &L);
  CHECK(L.nlines == 3 && L.ncorners == 4 && has_corner(&L, 0, 0, 0));
  lines_free(&L);
  /* a straight line as two polylines: one line, either direction */
  const char *two[2] = {"2 0 0 0 1 0 0\n2 1 0 0 2 0 0\n", "2 0 0 0 1 0 0\n\n2 2 0 0 1 0 0\n"};
  for (int k = 0; k < 2; k++) {
    CHECK(read_text(two[k], 30.0, &L) == MX_OK);
    show("straight line in two polylines", &L);
    CHECK(L.nlines == 1 && L.ncorners == 2 && npoints(&L, 0) == 3);
    CHECK(at(point(&L, 0, 0), 0, 0, 0) && at(point(&L, 0, 1), 1, 0, 0) &&
          at(point(&L, 0, 2), 2, 0, 0));
    lines_free(&L);
  }
  /* two polylines meeting at a right angle: a corner there, two lines */
  CHECK(read_text("2 0 0 0 1 0 0\n2 1 0 0 1 1 0\n", 30.0, &L) == MX_OK);
  CHECK(L.nlines == 2 && L.ncorners == 3);
  lines_free(&L);
}

/* A bad file: refused, with "FILE:LINE:" in the message. */
static void bad(const char *text, int line, const char *word) {
  mx_feature_lines L;
  memset(&L, 0x5a, sizeof L);
  const int st = read_text(text, 30.0, &L);
  char want[256];
  if (line > 0)
    snprintf(want, sizeof want, "%s/t.polylines.txt:%d:", tmpdir, line);
  else
    snprintf(want, sizeof want, "%s/t.polylines.txt: ", tmpdir);
  const int ok = st == MX_EINPUT && nerr == 1 && strstr(last_msg, want) &&
                 (!word || strstr(last_msg, word)) && L.nlines == 0 && !L.xyz && !L.first;
  if (!ok) printf("FAIL: expected line %d%s%s: status %d, '%s'\n", line, word ? " and " : "",
                  word ? word : "", st, last_msg);
  CHECK(ok);
}

static void bad_inputs(void) {
  const char *head = "# comment\n2 0 0 0 1 1 1\n";
  char text[512];
#define BAD(body, line, word)                        \
  do {                                               \
    snprintf(text, sizeof text, "%s%s", head, body); \
    bad(text, line, word);                           \
  } while (0)
  BAD("1 0 0 0\n", 3, "2 or more");                      /* n < 2 */
  BAD("-4 0 0 0 1 1 1\n", 3, "2 or more");               /* negative */
  BAD("x 0 0 0 1 1 1\n", 3, "number of points");         /* not a count */
  BAD("2.5 0 0 0 1 1 1\n", 3, "number of points");       /* not an integer */
  BAD("3 0 0 0 1 1 1\n", 3, "holds 2 at most");          /* numbers missing */
  BAD("2 0.000000 0 0 1 1\n", 3, "expected 3 numbers");  /* missing, long numbers */
  BAD("2 0 0 0 1 1 1 7\n", 3, "more numbers");           /* extra */
  BAD("2 0 0 0 1 nan 1\n", 3, "not a finite number");    /* NaN */
  BAD("2 0 0 0 1 1 inf\n", 3, "not a finite number");    /* infinity */
  BAD("2 0 0 0 1 1 1e999\n", 3, "not a finite number");  /* overflow */
  BAD("2 0 0 0 1 q 1\n", 3, "not a number");             /* not a number */
  BAD("3 0 0 0 1 1 1 1 1 1\n", 3, "repeats");            /* repeated point */
  BAD("3 0 0 0 1 1 1 0 0 0\n", 3, "loop needs 3");       /* a closed line of 2 points */
  BAD("\n\n99999999999 0 0 0\n", 5, "holds 1 at most");  /* absurd n */
  BAD("2000000000 0 0 0 1 1 1\n", 3, "holds 2 at most"); /* absurd n */
#undef BAD
  bad("# only comments\n\n   \n", 0, "no polyline");
  bad("", 0, "empty");
  mx_feature_lines L;
  const char *path = write_file("a.txt", "2 0 0 0 1 1 1\n");
  CHECK(mx_read_polylines(path, 200.0, &L) == MX_EINPUT && L.nlines == 0);
  CHECK(mx_read_polylines(path, NAN, &L) == MX_EINPUT);
  snprintf(text, sizeof text, "%s/missing.txt", tmpdir);
  CHECK(mx_read_polylines(text, 30.0, &L) == MX_EINPUT && L.nlines == 0);
}

int main(void) {
  snprintf(tmpdir, sizeof tmpdir, "/tmp/mx_polylines_XXXXXX");
  if (!mkdtemp(tmpdir)) {
    perror("mkdtemp");
    return 1;
  }
  mx_set_thread_message_handler(keep_message, NULL);
  square();
  open_lines();
  junctions();
  bad_inputs();
  char cmd[128];
  snprintf(cmd, sizeof cmd, "rm -rf %s", tmpdir);
  if (system(cmd) != 0) printf("could not remove %s\n", tmpdir);
  if (mx_test_failures) {
    printf("%d failures\n", mx_test_failures);
    return 1;
  }
  printf("all polylines tests passed\n");
  return 0;
}
