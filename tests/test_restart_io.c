/* Tests of the restart file reader and writers (src/io/restart.h); the
 * element index lists are tests/test_element_list.c.
 *
 * - The published program's file c5.oct ($MIXOCT_DATA/remesh/c5.oct):
 *   counts, the corner order (every octant is an axis-aligned cube of side
 *   root / 2^level in the documented order), and our text writer gives it
 *   back byte for byte.
 * - Round trips text -> text, binary -> binary, text -> binary -> text:
 *   identical structs and identical bytes.
 * - The "%+1.8E" node format against printf on many values.
 * - Bad text files (truncated, wrong counts, bad numbers and indices, a
 *   quadtree file, trailing data, empty, missing, a directory) and bad
 *   binary files (every truncation, every flipped byte, lying sizes, wrong
 *   magic and version, checksummed but inconsistent data): each must fail
 *   with MX_EINPUT, an empty struct, and a message naming the file (and the
 *   line for text).
 * Exit status: 0, 1 on a failure, 77 (skip) when c5.oct is absent and all
 * else passed. */
#include <fcntl.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "check.h"
#include "file_util.h"
#include "base/common.h"
#include "io/restart.h"

static int npass;
#define T(cond)         \
  do {                  \
    int ok_ = !!(cond); \
    CHECK(ok_);         \
    npass += ok_;       \
  } while (0)

static char tmpdir[64] = "restart_io_XXXXXX";
static char captured[1 << 20];

/* ---- files and stderr capture ------------------------------------------ */

static void tpath(char *buf, size_t n, const char *name) {
  snprintf(buf, n, "%s/%s", tmpdir, name);
}

/* Writes len bytes of data to path (created or truncated). */
static void write_bytes(const char *path, const void *data, size_t len) {
  FILE *f = fopen(path, "wb");
  T(f != NULL);
  if (!f) return;
  T(fwrite(data, 1, len, f) == len);
  fclose(f);
}

/* stderr goes to tmpdir/stderr.txt until capture_end, which returns it. */
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

#define edit(text, line, repl) text_edit_line(text, (int)(line), repl)

/* The first n lines of text (malloc'd). */
static char *head(const char *text, long n) {
  const char *p = text;
  for (long l = 0; l < n && *p; l++) {
    const char *nl = strchr(p, '\n');
    p = nl ? nl + 1 : p + strlen(p);
  }
  return strndup(text, (size_t)(p - text));
}

/* ---- structs ------------------------------------------------------------ */

static int same_restart(const mx_restart *a, const mx_restart *b) {
  if (a->nv != b->nv || a->ne != b->ne || a->no != b->no) return 0;
  if (a->has_transform != b->has_transform) return 0;
  if (a->has_transform &&
      memcmp(a->transform, b->transform, sizeof a->transform) != 0)
    return 0;
  if (!a->nsub != !b->nsub) return 0;
  if (a->nsub && memcmp(a->nsub, b->nsub, 4 * a->no) != 0) return 0;
  size_t nt = a->oct_tri_off[a->no];
  return memcmp(a->xyz, b->xyz, 24 * a->nv) == 0 &&
         memcmp(a->edge, b->edge, 12 * a->ne) == 0 &&
         memcmp(a->oct_node, b->oct_node, 32 * a->no) == 0 &&
         memcmp(a->oct_level, b->oct_level, a->no) == 0 &&
         memcmp(a->oct_tri_off, b->oct_tri_off, 8 * (a->no + 1)) == 0 &&
         (nt == 0 || memcmp(a->oct_tri, b->oct_tri, 4 * nt) == 0);
}

/* Whether *r is all zeros, as a failed read must leave it. */
static int is_empty(const mx_restart *r) {
  static const mx_restart zero;
  return memcmp(r, &zero, sizeof zero) == 0;
}

/* A small octree: the 3x3x3 nodes of a cube split once, its 8 octants in
 * the documented corner order, the 54 grid edges and 3 split root edges,
 * some faces per octant, a transform and sub-element counts. Arrays are
 * malloc'ed (free with free_small). */
enum { SN = 27, SE = 57, SO = 8 };
static int nid(int i, int j, int k) { return i + 3 * j + 9 * k; }

/* The small octree described above. */
static mx_restart small_restart(void) {
  mx_restart r = {.nv = SN, .ne = SE, .no = SO, .has_transform = 1};
  r.xyz = malloc(24 * SN);
  r.edge = malloc(12 * SE);
  r.oct_node = malloc(32 * SO);
  r.oct_level = malloc(SO);
  r.oct_tri_off = malloc(8 * (SO + 1));
  r.oct_tri = malloc(4 * 3 * SO);
  r.nsub = malloc(4 * SO);
  for (int k = 0; k < 3; k++)
    for (int j = 0; j < 3; j++)
      for (int i = 0; i < 3; i++) {
        double *x = r.xyz + 3 * nid(i, j, k);
        x[0] = -1.25 + 10.5 * i, x[1] = 0.5 + 10.5 * j, x[2] = 1e3 + 10.5 * k;
      }
  size_t e = 0;
  for (int a = 0; a < 3; a++) /* axis */
    for (int u = 0; u < 3; u++)
      for (int v = 0; v < 3; v++)
        for (int w = 0; w < 2; w++) {
          int c0[3], c1[3];
          c0[a] = w, c1[a] = w + 1;
          c0[(a + 1) % 3] = c1[(a + 1) % 3] = u;
          c0[(a + 2) % 3] = c1[(a + 2) % 3] = v;
          r.edge[3 * e] = (uint32_t)nid(c0[0], c0[1], c0[2]);
          r.edge[3 * e + 1] = (uint32_t)nid(c1[0], c1[1], c1[2]);
          r.edge[3 * e++ + 2] = 0;
        }
  uint32_t split[3][3] = {{0, 2, 1}, {0, 6, 3}, {0, 18, 9}};
  memcpy(r.edge + 3 * e, split, sizeof split);
  static const int corner[8][3] = {{0, 0, 0}, {0, 0, 1}, {1, 0, 1}, {1, 0, 0},
                                   {0, 1, 0}, {0, 1, 1}, {1, 1, 1}, {1, 1, 0}};
  r.oct_tri_off[0] = 0;
  for (int o = 0; o < SO; o++) {
    int a = o & 1, b = (o >> 1) & 1, c = o >> 2;
    for (int q = 0; q < 8; q++)
      r.oct_node[8 * o + q] =
          (uint32_t)nid(a + corner[q][0], b + corner[q][1], c + corner[q][2]);
    r.oct_level[o] = 1;
    r.oct_tri_off[o + 1] = r.oct_tri_off[o] + (uint64_t)(o % 3);
    for (int j = 0; j < o % 3; j++)
      r.oct_tri[r.oct_tri_off[o] + j] = (uint32_t)(7 * o + j);
    r.nsub[o] = (uint32_t)(1 + o % 5);
  }
  static const double tr[6] = {1.5, -2.25, 0, 0, 0.125, 3};
  memcpy(r.transform, tr, sizeof tr);
  return r;
}

/* Frees what small_restart allocated. */
static void free_small(mx_restart *r) {
  free(r->xyz), free(r->edge), free(r->oct_node), free(r->oct_level);
  free(r->oct_tri_off), free(r->oct_tri), free(r->nsub);
}

/* ---- failure checks ----------------------------------------------------- */

/* mx_restart_read(path) must fail with MX_EINPUT, leave *r empty and print
 * one message naming the path, "path:line:" when line > 0, and needle. */
static void expect_fail(const char *path, long line, const char *needle,
                        const char *label) {
  int before = mx_test_failures;
  mx_restart r;
  memset(&r, 0xab, sizeof r); /* the reader must not rely on a zeroed r */
  capture_begin();
  double t0 = mx_wtime();
  int rc = mx_restart_read(path, &r);
  double dt = mx_wtime() - t0;
  const char *msg = capture_end();
  T(rc == MX_EINPUT);
  T(is_empty(&r));
  T(strstr(msg, path) != NULL);
  T(strstr(msg, "error") != NULL);
  T(dt < 1.0); /* fails fast */
  if (line > 0) {
    char loc[256];
    snprintf(loc, sizeof loc, "%s:%ld:", path, line);
    T(strstr(msg, loc) != NULL);
  }
  if (needle) T(strstr(msg, needle) != NULL);
  if (rc == MX_OK) mx_restart_free(&r);
  printf("%s %-22s %s", mx_test_failures == before ? "ok  " : "FAIL", label,
         msg[0] ? msg : "(no message)\n");
}

/* Writes text to tmpdir/name and expects the reader to fail on it. */
static void bad_text(const char *name, const char *text, long line,
                     const char *needle) {
  char path[128];
  tpath(path, sizeof path, name);
  write_bytes(path, text, strlen(text));
  expect_fail(path, line, needle, name);
}

/* The same, freeing text (made by edit or head). */
static void bad_edit(const char *name, char *text, long line,
                     const char *needle) {
  bad_text(name, text, line, needle);
  free(text);
}

/* Reads text from a file; it must equal want. */
static void good_text(const char *name, const char *text,
                      const mx_restart *want) {
  char path[128];
  tpath(path, sizeof path, name);
  write_bytes(path, text, strlen(text));
  mx_restart r;
  int rc = mx_restart_read(path, &r);
  T(rc == MX_OK);
  int eq = rc == MX_OK && same_restart(&r, want);
  T(eq);
  printf("%s %-22s read as expected\n", rc == MX_OK && eq ? "ok  " : "FAIL",
         name);
  if (rc == MX_OK) mx_restart_free(&r);
}

/* ---- the c5.oct file ---------------------------------------------------- */

/* Every octant is an axis-aligned cube in the documented corner order, of
 * side root / 2^level (9 significant digits: relative tolerance 1e-7). */
static int cube_ok(const mx_restart *r, size_t o, double root) {
  static const int corner[8][3] = {{0, 0, 0}, {0, 0, 1}, {1, 0, 1}, {1, 0, 0},
                                   {0, 1, 0}, {0, 1, 1}, {1, 1, 1}, {1, 1, 0}};
  const uint32_t *n = r->oct_node + 8 * o;
  double lo[3], hi[3];
  for (int a = 0; a < 3; a++) {
    lo[a] = hi[a] = r->xyz[3 * n[0] + a];
    for (int q = 1; q < 8; q++) {
      lo[a] = fmin(lo[a], r->xyz[3 * n[q] + a]);
      hi[a] = fmax(hi[a], r->xyz[3 * n[q] + a]);
    }
  }
  double side = root / (double)(1u << r->oct_level[o]), tol = 1e-7 * root;
  for (int a = 0; a < 3; a++)
    if (fabs(hi[a] - lo[a] - side) > tol) return 0;
  for (int q = 0; q < 8; q++)
    for (int a = 0; a < 3; a++) {
      double want = corner[q][a] ? hi[a] : lo[a];
      if (fabs(r->xyz[3 * n[q] + a] - want) > tol) return 0;
    }
  return 1;
}

/* c5.oct: counts, the first octant, cubes, round trips, timings. */
static void test_c5(const char *c5) {
  mx_restart r, t, b;
  double t0 = mx_wtime();
  int rc = mx_restart_read(c5, &r);
  double t_read = mx_wtime() - t0;
  T(rc == MX_OK);
  if (rc != MX_OK) return;
  T(r.nv == 20506 && r.ne == 81363 && r.no == 10123);
  T(r.has_transform && r.nsub != NULL);
  uint64_t sum = 0;
  int maxlevel = 0;
  for (size_t o = 0; o < r.no; o++) {
    sum += r.nsub ? r.nsub[o] : 0;
    if (r.oct_level[o] > maxlevel) maxlevel = r.oct_level[o];
  }
  T(sum == 26209);
  T(maxlevel == 5);
  /* the first octant as the file has it: line 1 + 1 + nv + 1 + ne + 2 */
  size_t len;
  char *text = slurp(c5, &len);
  T(text != NULL);
  if (text) {
    char *line = text;
    for (size_t l = 1; l < r.nv + r.ne + 5 && line; l++) {
      line = strchr(line, '\n');
      if (line) line++;
    }
    unsigned v[10] = {0};
    T(line && sscanf(line, "%u %u %u %u %u %u %u %u %u %u", &v[0], &v[1], &v[2],
                     &v[3], &v[4], &v[5], &v[6], &v[7], &v[8], &v[9]) == 10);
    T(v[0] == 8 && v[9] == r.oct_level[0]);
    for (int q = 0; q < 8; q++) T(r.oct_node[q] == v[q + 1]);
  }
  free(text);
  /* corner order: the root side from the first octant, then every octant */
  double root = 0;
  for (int a = 0; a < 3; a++) {
    double d =
        fabs(r.xyz[3 * r.oct_node[2] + a] - r.xyz[3 * r.oct_node[4] + a]);
    root = fmax(root, d * (double)(1u << r.oct_level[0]));
  }
  size_t cubes = 0;
  for (size_t o = 0; o < r.no; o++) cubes += (size_t)cube_ok(&r, o, root);
  T(cubes == r.no);
  printf(
      "c5.oct: %zu nodes, %zu edges, %zu octants, %llu sub-elements, "
      "max level %d, %zu/%zu octants are cubes in the documented order "
      "(root side %.6g)\n",
      r.nv, r.ne, r.no, (unsigned long long)sum, maxlevel, cubes, r.no, root);

  char p1[128], p2[128], p3[128], b1[128], b2[128];
  tpath(p1, sizeof p1, "c5_1.oct");
  tpath(p2, sizeof p2, "c5_2.oct");
  tpath(p3, sizeof p3, "c5_3.oct");
  tpath(b1, sizeof b1, "c5_1.octb");
  tpath(b2, sizeof b2, "c5_2.octb");
  t0 = mx_wtime();
  T(mx_restart_write_text(p1, &r) == MX_OK);
  double t_wtext = mx_wtime() - t0;
  T(files_equal(p1, c5)); /* the published layout, byte for byte */
  T(mx_restart_read(p1, &t) == MX_OK);
  T(same_restart(&r, &t));
  T(mx_restart_write_text(p2, &t) == MX_OK);
  T(files_equal(p1, p2));
  mx_restart_free(&t);

  t0 = mx_wtime();
  T(mx_restart_write_binary(b1, &r) == MX_OK);
  double t_wbin = mx_wtime() - t0;
  t0 = mx_wtime();
  rc = mx_restart_read(b1, &b);
  double t_rbin = mx_wtime() - t0;
  T(rc == MX_OK);
  if (rc == MX_OK) {
    T(same_restart(&r, &b));
    T(mx_restart_write_binary(b2, &b) == MX_OK);
    T(files_equal(b1, b2));
    T(mx_restart_write_text(p3, &b) == MX_OK); /* text -> binary -> text */
    T(files_equal(p1, p3));
    mx_restart_free(&b);
  }
  struct stat st;
  long long bsize = stat(b1, &st) == 0 ? (long long)st.st_size : -1;
  printf(
      "c5.oct: read text %.1f ms, write text %.1f ms, write binary %.1f "
      "ms, read binary %.1f ms (%lld bytes)\n",
      1e3 * t_read, 1e3 * t_wtext, 1e3 * t_wbin, 1e3 * t_rbin, bsize);
  mx_restart_free(&r);
}

/* ---- the node format against printf ------------------------------------- */

static uint64_t rng = 0x9E3779B97F4A7C15ull;
static uint64_t next_rand(void) {
  rng ^= rng << 13, rng ^= rng >> 7, rng ^= rng << 17;
  return rng;
}

/* Writes many coordinates (random magnitudes 1e-20..1e20, 9-digit ties,
 * powers of ten, 9.999999995-like carries) and compares each line with
 * printf's "%+1.8E  %+1.8E  %+1.8E". */
static void test_number_format(void) {
  enum { N = 200000 };
  mx_restart r = small_restart();
  double *xyz = malloc(24 * N), *keep = r.xyz;
  for (size_t i = 0; i < 3 * N; i++) {
    double x;
    switch (i % 6) {
      case 0: /* any magnitude */
        x = ldexp((double)(next_rand() >> 11), -53) *
            pow(10.0, (double)(next_rand() % 41) - 20.0);
        break;
      case 1: /* exact halves of a 9th digit: D.5 * 2^-j */
        x = ldexp((double)(100000000 + next_rand() % 900000000) + 0.5,
                  -(int)(next_rand() % 12));
        break;
      case 2: /* short decimals that round up across a power of ten */
        x = (9.99999999 + 1e-9 * (double)(next_rand() % 11)) *
            pow(10.0, (double)(next_rand() % 25) - 15.0);
        break;
      case 3: /* powers of ten and their neighbours */
        x = nextafter(pow(10.0, (double)(next_rand() % 30) - 15.0),
                      next_rand() & 1 ? 0.0 : 1e300);
        break;
      case 4: /* the published file's kind: up to ~300 with 9 digits */
        x = (double)(next_rand() % 1000000000) * 1e-6;
        break;
      default:
        x = (double)(int64_t)(next_rand() % 2000001) - 1e6;
    }
    xyz[i] = next_rand() & 1 ? -x : x;
  }
  xyz[0] = 0.0, xyz[1] = -0.0, xyz[2] = 1e-300, xyz[3] = -1e300;
  xyz[4] = 5e-324, xyz[5] = 123456788.5, xyz[6] = 12345678.25;
  xyz[7] = 999999999.5, xyz[8] = 99999999.95;
  r.xyz = xyz;
  r.nv = N;
  for (size_t i = 0; i < 8 * SO; i++) r.oct_node[i] %= N;
  char path[128];
  tpath(path, sizeof path, "numbers.oct");
  T(mx_restart_write_text(path, &r) == MX_OK);
  size_t len, bad = 0;
  char *text = slurp(path, &len), *line = text ? strchr(text, '\n') : NULL;
  T(line != NULL);
  for (size_t i = 0; line && i < N; i++) {
    line += i == 0 ? 2 : 1; /* the header's line, then a blank line */
    char want[128];
    int n = snprintf(want, sizeof want, "%+1.8E  %+1.8E  %+1.8E\n", xyz[3 * i],
                     xyz[3 * i + 1], xyz[3 * i + 2]);
    if (strncmp(line, want, (size_t)n) != 0 && bad++ < 5)
      printf("FAIL node %zu: want %s", i, want);
    line = strchr(line, '\n');
  }
  T(bad == 0);
  mx_restart back;
  T(mx_restart_read(path, &back) == MX_OK);
  size_t diff = 0; /* 9 digits: within half a unit of the 9th digit */
  for (size_t i = 0; i < 3 * N && back.xyz; i++)
    diff += fabs(back.xyz[i] - xyz[i]) > 5.000001e-9 * fabs(xyz[i]);
  T(diff == 0);
  printf(
      "%s node format: %d numbers as printf writes them, %zu differ; "
      "read back within 9 digits: %zu differ\n",
      bad || diff ? "FAIL" : "ok  ", 3 * N, bad, diff);
  mx_restart_free(&back);
  free(text);
  free(xyz);
  r.xyz = keep;
  free_small(&r);
}

/* ---- small files: round trips and tolerance ------------------------------ */

static char *small_text; /* the small restart as our writer writes it */
static long L_nodes, L_edges, L_octs, L_title, L_nsub; /* first lines */

static void test_small(void) {
  mx_restart s = small_restart(), r;
  char path[128], path2[128], bpath[128];
  tpath(path, sizeof path, "small.oct");
  tpath(path2, sizeof path2, "small2.oct");
  tpath(bpath, sizeof bpath, "small.octb");
  T(mx_restart_write_text(path, &s) == MX_OK);
  size_t len;
  small_text = slurp(path, &len);
  L_nodes = 3, L_edges = L_nodes + SN + 1, L_octs = L_edges + SE + 1;
  L_title = L_octs + 2 * SO + 1, L_nsub = L_title + 4;
  T(mx_restart_read(path, &r) == MX_OK && same_restart(&r, &s));
  mx_restart_free(&r);
  T(mx_restart_write_binary(bpath, &s) == MX_OK);
  T(mx_restart_read(bpath, &r) == MX_OK && same_restart(&r, &s));
  T(mx_restart_write_text(path2, &r) == MX_OK && files_equal(path, path2));
  mx_restart_free(&r);

  /* tolerance: comments, blank lines, tabs, CR LF, no final newline */
  char *t = edit(small_text, L_nodes, "\t-1.25E0 0.05e1 1000 # x y z\r");
  char *u = edit(t, 1, "# a comment\n\n  27\t57   8  \r\n#\n");
  free(t);
  u[strlen(u) - 1] = '\0';
  good_text("tolerant.oct", u, &s);
  free(u);
  /* sections: the title missing, the transform missing, nsub missing */
  t = edit(small_text, L_title, NULL);
  good_text("no_title.oct", t, &s);
  free(t);
  t = edit(small_text, L_title, NULL), u = edit(t, L_title, NULL), free(t);
  t = edit(u, L_title, NULL), free(u);
  s.has_transform = 0;
  good_text("no_transform.oct", t, &s);
  free(t);
  t = head(small_text, L_title - 2);
  uint32_t *ns = s.nsub;
  s.nsub = NULL;
  good_text("octants_only.oct", t, &s);
  free(t);
  s.has_transform = 1;
  t = head(small_text, L_title + 2);
  good_text("no_nsub.oct", t, &s);
  free(t);
  s.nsub = ns;
  t = edit(small_text, L_nsub, "1 2 3\n4\n\n5 1 2 3"); /* counts over lines */
  good_text("nsub_lines.oct", t, &s);
  free(t);
  /* the writer: no transform, no nsub */
  s.has_transform = 0;
  s.nsub = NULL;
  T(mx_restart_write_text(path, &s) == MX_OK);
  T(mx_restart_read(path, &r) == MX_OK && same_restart(&r, &s));
  mx_restart_free(&r);
  T(mx_restart_write_binary(bpath, &s) == MX_OK);
  T(mx_restart_read(bpath, &r) == MX_OK && same_restart(&r, &s));
  mx_restart_free(&r);
  s.nsub = ns;
  /* the writers refuse inconsistent data, leaving no file */
  s.oct_level[3] = 17;
  unlink(path);
  capture_begin();
  int a = mx_restart_write_text(path, &s),
      b = mx_restart_write_binary(path, &s);
  const char *msg = capture_end();
  T(a == MX_EINTERNAL && b == MX_EINTERNAL && access(path, F_OK) != 0);
  T(strstr(msg, "level 17") != NULL);
  s.oct_level[3] = 1;
  free_small(&s);
  printf("%s small files: round trips, tolerance, optional sections\n",
         mx_test_failures ? "FAIL" : "ok  ");
}

/* ---- bad text files ------------------------------------------------------ */

static void test_bad_text(void) {
  const char *s = small_text;
  char dir[128], buf[256];
  long o3 = L_octs + 6; /* octant 3, line 1 */
  bad_edit("header_only.oct", head(s, 1), 0,
           "truncated: expected 27 nodes, found 0");
  bad_edit("mid_nodes.oct", head(s, L_nodes + 9), 0,
           "truncated: expected 27 nodes, found 10");
  bad_edit("mid_edges.oct", head(s, L_edges + 19), 0,
           "truncated: expected 57 edges, found 20");
  bad_edit("mid_octants.oct", head(s, o3 - 1), 0,
           "truncated: expected 8 octants, found 3");
  bad_edit("half_octant.oct", head(s, o3), 0,
           "truncated: expected 8 octants, found 3 (the last one");
  char *t = head(s, L_nodes + 4);
  t[strlen(t) - 20] = '\0'; /* cut inside a node line */
  bad_edit("cut_line.oct", t, L_nodes + 4, "truncated?");
  bad_edit("no_header.oct", strdup("\n# nothing\n\n"), 0, "no content");
  bad_edit("header_word.oct", edit(s, 1, "27 57 eight"), 1, "'eight'");
  bad_edit("header_neg.oct", edit(s, 1, "27 -57 8"), 1, "negative");
  bad_edit("header_huge.oct",
           edit(s, 1, "27 57 123456789012345678901234567890"), 1, "too large");
  bad_edit("header_4.oct", edit(s, 1, "27 57 8 1"), 1, "more than the 3");
  bad_edit("header_nooct.oct", edit(s, 1, "27 57 0"), 1, "no octants");
  bad_edit("more_nodes.oct", edit(s, 1, "28 57 8"), 0, "header's counts");
  bad_edit("fewer_nodes.oct", edit(s, 1, "26 57 8"), L_edges - 2,
           "header's counts");
  bad_edit("more_edges.oct", edit(s, 1, "27 58 8"), L_octs, "header's counts");
  bad_edit("fewer_edges.oct", edit(s, 1, "27 56 8"), L_octs - 2,
           "header's counts");
  bad_edit("more_octants.oct", edit(s, 1, "27 57 9"), L_title,
           "truncated: expected 9 octants, found 8");
  bad_edit("fewer_octants.oct", edit(s, 1, "27 57 7"), L_title - 3,
           "more octants than the header declares");
  bad_edit("huge_nodes.oct", edit(s, 1, "4000000000 57 8"), L_octs,
           "header's counts");
  bad_edit("too_many_nodes.oct", edit(s, 1, "5000000000 57 8"), 1, "32-bit");
  bad_edit("node_words.oct", edit(s, L_nodes + 2, "1 2 abc"), L_nodes + 2,
           "'abc' is not a number");
  bad_edit("node_nan.oct", edit(s, L_nodes + 2, "1 nan 3"), L_nodes + 2,
           "'nan' is not a finite number");
  bad_edit("node_inf.oct", edit(s, L_nodes, "-inf 2 3"), L_nodes,
           "not a finite number");
  bad_edit("node_huge.oct", edit(s, L_nodes, "1e999 2 3"), L_nodes,
           "not a finite number");
  bad_edit("node_4.oct", edit(s, L_nodes + 5, "1 2 3 4"), L_nodes + 5,
           "more than 3 numbers");
  bad_edit("node_2.oct", edit(s, L_nodes + 5, "1 2"), L_nodes + 5,
           "expected 3 numbers, found 2");
  bad_edit("edge_range.oct", edit(s, L_edges + 3, "0 27 0"), L_edges + 3,
           "node index 27 out of range (27 nodes");
  bad_edit("edge_neg.oct", edit(s, L_edges + 3, "0 -3 0"), L_edges + 3,
           "'-3' is negative");
  bad_edit("edge_over.oct",
           edit(s, L_edges + 3, "0 123456789012345678901234567890 0"),
           L_edges + 3, "out of range");
  bad_edit("edge_real.oct", edit(s, L_edges + 3, "0 1.5 0"), L_edges + 3,
           "not an integer");
  bad_edit("edge_4.oct", edit(s, L_edges + 3, "0 1 0 5"), L_edges + 3,
           "more than 3 numbers");
  snprintf(buf, sizeof buf, "8 0 1 10 9 3 4 13 %d 1", SN);
  bad_edit("oct_range.oct", edit(s, o3, buf), o3, "out of range");
  bad_edit("oct_neg.oct", edit(s, o3, "8 0 1 10 9 3 4 13 -3 1"), o3,
           "negative");
  bad_edit("oct_level.oct", edit(s, o3, "8 0 1 10 9 3 4 13 12 17"), o3,
           "level 17 out of range");
  bad_edit("oct_quad.oct", edit(s, o3, "4 0 1 4 3 1"), o3,
           "a quadtree restart file; mixoct remeshes octrees only");
  bad_edit("node_2d.oct", edit(s, L_nodes, "1.5 2.5"), L_nodes,
           "a quadtree restart file");
  bad_edit("oct_6.oct", edit(s, o3, "6 0 1 4 3 1 2 1"), o3,
           "6 corner nodes, an octant has 8");
  bad_edit("oct_11.oct", edit(s, o3, "8 0 1 10 9 3 4 13 12 1 5"), o3,
           "more than '8 n0 .. n7 level'");
  bad_edit("oct_faces_few.oct", edit(s, o3 + 1, "3 4 5"), o3 + 1,
           "3 intersected faces announced, 2 listed");
  bad_edit("oct_faces_more.oct", edit(s, o3 + 1, "1 4 5"), o3 + 1,
           "more intersected faces listed than the 1 announced");
  bad_edit("oct_faces_huge.oct", edit(s, o3 + 1, "4000000000 4 5"), o3 + 1,
           "too short");
  bad_edit("oct_faces_neg.oct", edit(s, o3 + 1, "2 -4 5"), o3 + 1, "negative");
  bad_edit("title.oct", edit(s, L_title, "Geometric Transformation"), L_title,
           "'Geometric Transform'");
  bad_edit("transform_nan.oct", edit(s, L_title + 1, "0 nan 0"), L_title + 1,
           "not a finite number");
  bad_edit("transform_cut.oct", head(s, L_title + 1), 0,
           "the geometric transform needs 2 lines");
  bad_edit("nsub_few.oct", edit(s, L_nsub, "1 2 3"), 0,
           "expected 8 counts (one per octant), found 3");
  bad_edit("nsub_more.oct", edit(s, L_nsub, "1 2 3 4 5 1 2 3 4"), L_nsub,
           "unexpected data after the last section: '4'");
  bad_edit("nsub_neg.oct", edit(s, L_nsub, "1 2 3 -4 5 1 2 3"), L_nsub,
           "negative");
  bad_edit("nsub_big.oct", edit(s, L_nsub, "1 2 3 4294967296 5 1 2 3"), L_nsub,
           "out of range");
  size_t n = strlen(s);
  t = malloc(n + 32);
  snprintf(t, n + 32, "%sgarbage\n", s);
  bad_edit("trailing.oct", t, L_nsub + 1,
           "unexpected data after the last section: 'garbage'");
  bad_edit("binary_junk.oct", strdup("\x01\x02\x03 junk"), 1, "bad header");
  bad_text("empty.oct", "", 0, "empty file");
  bad_text("blank.oct", "  \n\n", 0, "no content");
  tpath(buf, sizeof buf, "missing.oct");
  expect_fail(buf, 0, "cannot open", "missing.oct");
  tpath(dir, sizeof dir, "adir.oct");
  mkdir(dir, 0700);
  expect_fail(dir, 0, "directory", "adir.oct");
  rmdir(dir);
}

/* ---- bad binary files ---------------------------------------------------- */

/* The documented checksum, written independently of the reader. */
static uint64_t doc_checksum(const uint8_t *p, size_t nwords) {
  uint64_t lane[4], x;
  for (int l = 0; l < 4; l++) lane[l] = 0x9E3779B97F4A7C15ull * (l + 1);
  for (size_t i = 0; i < nwords; i++) {
    uint64_t w;
    memcpy(&w, p + 8 * i, 8);
    uint64_t h = (lane[i % 4] ^ w) * 0xff51afd7ed558ccdull;
    lane[i % 4] = h ^ (h >> 32);
  }
  uint64_t ws[5] = {nwords, lane[0], lane[1], lane[2], lane[3]};
  x = 0x243F6A8885A308D3ull;
  for (int k = 0; k < 5; k++) {
    x = (x ^ ws[k]) * 0xff51afd7ed558ccdull;
    x ^= x >> 32;
  }
  return x;
}

/* A copy of bin with one edit at off (size bytes of v) and the checksum
 * recomputed: what a buggy writer could produce. Must fail with needle. */
static void bin_semantic(const uint8_t *bin, size_t len, size_t off,
                         const void *v, size_t size, const char *needle,
                         const char *label) {
  uint8_t *b = malloc(len);
  memcpy(b, bin, len);
  memcpy(b + off, v, size);
  uint64_t sum = doc_checksum(b, len / 8 - 1);
  memcpy(b + len - 8, &sum, 8);
  char path[128];
  tpath(path, sizeof path, label);
  write_bytes(path, b, len);
  expect_fail(path, 0, needle, label);
  free(b);
}

/* Prefixes, flipped bytes, lying sizes, magic, version, flags, checksum,
 * and checksummed files with bad data. */
static void test_bad_binary(void) {
  mx_restart s = small_restart(), r;
  char path[128];
  tpath(path, sizeof path, "small.octb");
  T(mx_restart_write_binary(path, &s) == MX_OK);
  size_t len;
  uint8_t *bin = (uint8_t *)slurp(path, &len);
  T(bin && len % 8 == 0);
  T(bin &&
    doc_checksum(bin, len / 8 - 1) == *(uint64_t *)(void *)(bin + len - 8));
  /* every prefix; every byte flipped (one bit, and all bits) */
  size_t fails = 0, truncs = 0, flips = 0;
  capture_begin();
  for (size_t k = 0; k < len; k++) {
    memset(&r, 0xab, sizeof r);
    int rc = mx_restart_parse("prefix", bin, k, &r);
    fails += rc == MX_EINPUT && is_empty(&r);
  }
  const char *msg = capture_end();
  for (const char *p = msg; (p = strstr(p, "truncated")); p++) truncs++;
  T(fails == len);
  T(truncs == len - 1); /* all but the empty one */
  size_t refused = 0;
  capture_begin();
  for (size_t k = 0; k < len; k++)
    for (int pass = 0; pass < 2; pass++) {
      bin[k] ^= pass ? 0xFF : 0x01;
      refused += mx_restart_parse("flipped", bin, len, &r) == MX_EINPUT;
      bin[k] ^= pass ? 0xFF : 0x01;
      flips++;
    }
  capture_end();
  T(refused == flips);
  T(mx_restart_parse("intact", bin, len, &r) == MX_OK);
  mx_restart_free(&r);
  printf(
      "%s binary: %zu prefixes refused (%zu say truncated), %zu/%zu "
      "flipped bytes refused (%zu-byte file)\n",
      fails == len && refused == flips ? "ok  " : "FAIL", fails, truncs,
      refused, flips, len);
  /* lying sizes: huge, overflowing; checked before any allocation */
  uint8_t *b = malloc(len);
  struct {
    size_t off;
    uint64_t v;
    const char *label, *needle;
  } lies[] = {{16, (uint64_t)1 << 60, "huge_nv.octb", "expected more than"},
              {32, (uint64_t)1 << 40, "huge_no.octb", "expected "},
              {40, ~(uint64_t)0, "huge_ntri.octb", "expected more than"},
              {24, 3, "small_ne.octb", "data after the end"}};
  double rss0 = mx_peak_rss_mb();
  for (size_t i = 0; i < sizeof lies / sizeof lies[0]; i++) {
    memcpy(b, bin, len);
    memcpy(b + lies[i].off, &lies[i].v, 8);
    tpath(path, sizeof path, lies[i].label);
    write_bytes(path, b, len);
    expect_fail(path, 0, lies[i].needle, lies[i].label);
  }
  T(mx_peak_rss_mb() - rss0 < 64);
  memcpy(b, bin, len);
  b[3] = 'Z';
  tpath(path, sizeof path, "magic.octb");
  write_bytes(path, b, len);
  expect_fail(path, 0, "not a mixoct binary restart file", "magic.octb");
  memcpy(b, bin, len);
  b[8] = 2;
  tpath(path, sizeof path, "version.octb");
  write_bytes(path, b, len);
  expect_fail(path, 0, "version 2, this mixoct reads version 1",
              "version.octb");
  memcpy(b, bin, len);
  b[12] |= 0x80;
  tpath(path, sizeof path, "flags.octb");
  write_bytes(path, b, len);
  expect_fail(path, 0, "unknown flags", "flags.octb");
  memcpy(b, bin, len);
  b[len / 2] ^= 0x10;
  tpath(path, sizeof path, "checksum.octb");
  write_bytes(path, b, len);
  expect_fail(path, 0, "corrupted: checksum mismatch", "checksum.octb");
  free(b);
  /* consistent checksum, inconsistent data */
  size_t o_xyz = 48, o_edge = o_xyz + 24 * SN, o_node = o_edge + 12 * SE + 4;
  size_t o_level = o_node + 32 * SO, o_count = o_level + 8;
  double nan = NAN;
  uint32_t big = SN, many = 100;
  uint8_t l17 = 17;
  bin_semantic(bin, len, o_xyz + 8, &nan, 8, "node 0: non-finite",
               "sem_nan.octb");
  bin_semantic(bin, len, o_edge + 4, &big, 4, "edge 0: node index 27 out",
               "sem_edge.octb");
  bin_semantic(bin, len, o_node + 32 * 5, &big, 4, "octant 5: node index",
               "sem_node.octb");
  bin_semantic(bin, len, o_level + 2, &l17, 1, "octant 2: level 17",
               "sem_level.octb");
  bin_semantic(bin, len, o_count + 4, &many, 4, "do not add up",
               "sem_count.octb");
  free(bin);
  free_small(&s);
}

/* ---- main ---------------------------------------------------------------- */

/* $MIXOCT_DATA, else ../shared/data beside the source root (found from
 * this file's path). */
/* Runs every group in a temporary folder under the working directory. */
int main(void) {
  if (!mkdtemp(tmpdir)) {
    perror("mkdtemp");
    return 1;
  }
  char c5[1200];
  const char *data = test_data_dir("remesh/c5.oct");
  snprintf(c5, sizeof c5, "%s/remesh/c5.oct", data ? data : MIXOCT_TEST_DATA);
  int have_c5 = data != NULL;
  if (have_c5)
    test_c5(c5);
  else
    TEST_DATA_MISSING("c5.oct: %s not found (set MIXOCT_DATA)", c5);
  test_number_format();
  test_small();
  test_bad_text();
  test_bad_binary();
  free(small_text);

  char cmd[128];
  snprintf(cmd, sizeof cmd, "rm -rf '%s'", tmpdir);
  if (system(cmd) != 0) fprintf(stderr, "could not remove %s\n", tmpdir);
  printf("restart io: %d checks passed, %d failed\n", npass, mx_test_failures);
  if (mx_test_failures) return 1;
  return have_c5 ? 0 : 77;
}
