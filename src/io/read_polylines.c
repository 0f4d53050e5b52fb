/* The feature polylines reader (io/read_polylines.h): each content line
 * read into points and the segments between consecutive points (a closed
 * polyline without its repeated last point, its last segment back to the
 * first), then the points welded by their coordinates (a sort), the turn
 * at every point of two segments measured, and the lines walked from
 * corner to corner (geom/feature_walk.h). Every error is one message
 * naming the file and line (mx_error) and MX_EINPUT. */
#include "io/read_polylines.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "base/common.h"
#include "geom/feature_walk.h"
#include "io/text_scan.h"

typedef struct {
  const char *path, *p, *end; /* p: the current content line */
  long line;
  double *pt;    /* 3 per point read (closed polylines without their last) */
  size_t np, pcap;
  uint32_t *seg; /* 2 per segment: points */
  size_t ns, scap;
  size_t npoly;
} rd;

static void rd_free(rd *f) {
  mx_free(f->pt);
  mx_free(f->seg);
}

static int reserve(rd *f, size_t np, size_t ns) {
  if (np > f->pcap) {
    size_t c = f->pcap ? 2 * f->pcap : 256;
    if (c < np) c = np;
    double *p = mx_realloc(f->pt, 3 * c * sizeof *p);
    if (!p) return MX_ENOMEM;
    f->pt = p;
    f->pcap = c;
  }
  if (ns > f->scap) {
    size_t c = f->scap ? 2 * f->scap : 256;
    if (c < ns) c = ns;
    uint32_t *s = mx_realloc(f->seg, 2 * c * sizeof *s);
    if (!s) return MX_ENOMEM;
    f->seg = s;
    f->scap = c;
  }
  return MX_OK;
}

static int same_point(const double *a, const double *b) {
  return a[0] == b[0] && a[1] == b[1] && a[2] == b[2];
}

/* ---- one line: "n x1 y1 z1 ... xn yn zn" --------------------------------- */

static int read_count(rd *f, const char **q, int64_t *n) {
  const char *s = *q;
  const char *e = mx_io_int(s, n);
  if (!e || !mx_io_delim(e, '#')) {
    mx_error(f->path, f->line,
             "polyline %zu: expected the number of points, found '%.*s' (a line is "
             "'n x1 y1 z1 ... xn yn zn')", f->npoly, mx_io_toklen(s, '#'), s);
    return MX_EINPUT;
  }
  if (*n < 2) {
    mx_error(f->path, f->line, "polyline %zu: %lld points: a polyline needs 2 or more",
             f->npoly, (long long)*n);
    return MX_EINPUT;
  }
  /* every number takes a character and a blank before it: 6 a point */
  const char *nl = memchr(e, '\n', (size_t)(f->end - e));
  const size_t room = (size_t)((nl ? nl : f->end) - e) / 6;
  if ((uint64_t)*n > room) {
    mx_error(f->path, f->line,
             "polyline %zu: %lld points declared, but the line holds %zu at most (3 numbers "
             "a point): numbers missing or a wrong count", f->npoly, (long long)*n, room);
    return MX_EINPUT;
  }
  *q = e;
  return MX_OK;
}

static int read_polyline(rd *f) {
  f->npoly++;
  const char *q = f->p;
  int64_t n64;
  MX_CHECK(read_count(f, &q, &n64));
  const size_t n = (size_t)n64, first = f->np;
  if (f->np + n >= UINT32_MAX) {
    mx_error(f->path, f->line, "more than %u points in all: too many", UINT32_MAX - 1);
    return MX_EINPUT;
  }
  MX_CHECK(reserve(f, f->np + n, f->ns + n));
  char what[48];
  snprintf(what, sizeof what, "polyline %zu, point", f->npoly);
  for (size_t j = 0; j < n; j++) {
    double *c = f->pt + 3 * (first + j);
    MX_CHECK(mx_io_numbers(f->path, f->line, &q, '#', 3, c, what, j + 1));
    if (j > 0 && same_point(c, c - 3)) {
      mx_error(f->path, f->line,
               "polyline %zu: point %zu repeats point %zu (the same coordinates: a segment "
               "of length 0)", f->npoly, j + 1, j);
      return MX_EINPUT;
    }
  }
  const char *s = mx_io_blank(q);
  if (!mx_io_eol(s, '#')) {
    mx_error(f->path, f->line,
             "polyline %zu: '%.*s' after its %zu points (more numbers than the count says)",
             f->npoly, mx_io_toklen(s, '#'), s, n);
    return MX_EINPUT;
  }
  const int closed = same_point(f->pt + 3 * first, f->pt + 3 * (first + n - 1));
  if (closed && n < 4) {
    mx_error(f->path, f->line,
             "polyline %zu: closed (its last point is its first) with %zu distinct points: a "
             "loop needs 3 or more", f->npoly, n - 1);
    return MX_EINPUT;
  }
  const size_t kept = closed ? n - 1 : n;
  for (size_t j = 0; j + 1 < n; j++) {
    f->seg[2 * f->ns] = (uint32_t)(first + j);
    f->seg[2 * f->ns + 1] = (uint32_t)(closed && j + 2 == n ? first : first + j + 1);
    f->ns++;
  }
  f->np += kept;
  return MX_OK;
}

static int read_lines(rd *f) {
  for (;;) {
    f->p = mx_io_content(f->p, f->end, &f->line, '#');
    if (f->p >= f->end) break;
    MX_CHECK(read_polyline(f));
    f->p = mx_io_next_line(f->p, f->end, &f->line);
  }
  if (f->npoly == 0) {
    mx_error(f->path, 0, "no polyline: expected lines 'n x1 y1 z1 ... xn yn zn'");
    return MX_EINPUT;
  }
  return MX_OK;
}

/* ---- welding and corners ------------------------------------------------- */

typedef struct {
  double c[3];
  uint32_t i;
} keyed;

static int keyed_cmp(const void *pa, const void *pb) {
  const keyed *a = pa, *b = pb;
  for (int k = 0; k < 3; k++)
    if (a->c[k] != b->c[k]) return a->c[k] < b->c[k] ? -1 : 1;
  return (a->i > b->i) - (a->i < b->i);
}

/* vid[point]: the points with equal coordinates one vertex, numbered in
 * the order they first appear; their coordinates into xyz (3 per vertex). */
static int weld(const rd *f, uint32_t *vid, double *xyz, size_t *nv) {
  keyed *k = mx_alloc((f->np + 1) * sizeof *k);
  uint32_t *rep = mx_alloc((f->np + 1) * sizeof *rep);
  if (!k || !rep) {
    mx_free(k);
    mx_free(rep);
    return MX_ENOMEM;
  }
  for (size_t i = 0; i < f->np; i++) {
    memcpy(k[i].c, f->pt + 3 * i, sizeof k[i].c);
    k[i].i = (uint32_t)i;
  }
  qsort(k, f->np, sizeof *k, keyed_cmp);
  for (size_t i = 0; i < f->np; i++) /* the first point of each run of equals */
    rep[k[i].i] = i > 0 && same_point(k[i].c, k[i - 1].c) ? rep[k[i - 1].i] : k[i].i;
  size_t n = 0;
  for (size_t i = 0; i < f->np; i++) {
    if (rep[i] == i) {
      memcpy(xyz + 3 * n, f->pt + 3 * i, 3 * sizeof *xyz);
      vid[i] = (uint32_t)n++;
    } else {
      vid[i] = vid[rep[i]]; /* rep[i] < i: numbered already */
    }
  }
  *nv = n;
  mx_free(k);
  mx_free(rep);
  return MX_OK;
}

/* corner[v] = 1 where v has two segments turning by more than angle_deg
 * (the other degrees the walk makes corners itself). */
static int turn_corners(const double *xyz, size_t nv, const uint32_t *edge, size_t ne,
                        double angle_deg, uint8_t *corner) {
  uint32_t *nb = mx_alloc((2 * nv + 1) * sizeof *nb);
  uint8_t *deg = mx_calloc(nv + 1);
  if (!nb || !deg) {
    mx_free(nb);
    mx_free(deg);
    return MX_ENOMEM;
  }
  for (size_t e = 0; e < ne; e++)
    for (int s = 0; s < 2; s++) {
      const uint32_t v = edge[2 * e + (size_t)s], w = edge[2 * e + (size_t)(1 - s)];
      if (deg[v] < 2) nb[2 * (size_t)v + deg[v]] = w;
      if (deg[v] < 3) deg[v]++;
    }
  const double cos_max = cos(angle_deg * (M_PI / 180.0));
  for (size_t v = 0; v < nv; v++) {
    corner[v] = 0;
    if (deg[v] != 2) continue;
    const double *p = xyz + 3 * v, *a = xyz + 3 * (size_t)nb[2 * v],
                 *b = xyz + 3 * (size_t)nb[2 * v + 1];
    double d1[3], d2[3], dot = 0.0, l1 = 0.0, l2 = 0.0;
    for (int k = 0; k < 3; k++) {
      d1[k] = p[k] - a[k];
      d2[k] = b[k] - p[k];
      dot += d1[k] * d2[k];
      l1 += d1[k] * d1[k];
      l2 += d2[k] * d2[k];
    }
    /* the turn is the angle between d1 and d2: more than angle_deg when
     * its cosine is below cos(angle_deg) */
    const double c = dot / (sqrt(l1) * sqrt(l2));
    corner[v] = !(c >= cos_max) && angle_deg < 180.0;
  }
  mx_free(nb);
  mx_free(deg);
  return MX_OK;
}

static int build_lines(const rd *f, double angle_deg, mx_feature_lines *L) {
  uint32_t *vid = mx_alloc((f->np + 1) * sizeof *vid);
  double *xyz = mx_alloc((3 * f->np + 3) * sizeof *xyz);
  uint32_t *edge = mx_alloc((2 * f->ns + 2) * sizeof *edge);
  uint8_t *corner = mx_alloc(f->np + 1);
  size_t nv = 0;
  int st = vid && xyz && edge && corner ? MX_OK : MX_ENOMEM;
  if (st == MX_OK) st = weld(f, vid, xyz, &nv);
  if (st == MX_OK) {
    for (size_t k = 0; k < 2 * f->ns; k++) edge[k] = vid[f->seg[k]];
    st = turn_corners(xyz, nv, edge, f->ns, angle_deg, corner);
  }
  if (st == MX_OK)
    st = mx_feature_lines_walk(xyz, xyz + 1, xyz + 2, 3, nv, edge, f->ns, corner, L);
  mx_free(vid);
  mx_free(xyz);
  mx_free(edge);
  mx_free(corner);
  return st;
}

int mx_read_polylines(const char *path, double angle_deg, mx_feature_lines *L) {
  memset(L, 0, sizeof *L);
  if (!(angle_deg >= 0.0 && angle_deg <= 180.0)) {
    mx_error(path, 0, "feature polylines: angle %g: expected 0 to 180 degrees", angle_deg);
    return MX_EINPUT;
  }
  char *buf;
  size_t len;
  MX_CHECK(mx_io_load(path, &buf, &len));
  rd f;
  memset(&f, 0, sizeof f);
  f.path = path;
  f.p = buf;
  f.end = buf + len;
  f.line = 1;
  int st = read_lines(&f);
  mx_free(buf);
  if (st == MX_OK) {
    st = build_lines(&f, angle_deg, L);
    if (st == MX_EINPUT) { /* the walk refuses nothing a read gives it */
      mx_error(path, 0, "feature polylines: internal error building the lines");
      st = MX_EINTERNAL;
    }
  }
  rd_free(&f);
  return st;
}
