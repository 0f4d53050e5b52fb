/* Refinement boxes of the 2D mesher (".reg2", the 3D .reg with 2D corners):
 *
 *   n_regions N
 *   xmin ymin xmax ymax level      N times; '#' comments anywhere
 *
 * Errors name the file and line (MX_EINPUT); a count the file cannot hold
 * allocates nothing. */
#include <math.h>
#include <stdio.h>
#include <strings.h>

#include "base/common.h"
#include "io/text_scan.h"
#include "io/read_poly.h"

typedef struct {
  const char *path, *p, *end;
  long line;
} scan;

static int scan_token(scan *s, const char *what, size_t box) {
  s->p = mx_io_content(s->p, s->end, &s->line, '#');
  if (s->p < s->end) return MX_OK;
  mx_error(s->path, s->line, "unexpected end of file: box %zu has no %s (truncated file or "
                             "wrong n_regions)", box + 1, what);
  return MX_EINPUT;
}

static int scan_number(scan *s, const char *what, size_t box, double *v) {
  MX_CHECK(scan_token(s, what, box));
  const char *e = mx_io_double(s->p, v);
  if (!e || !mx_io_delim(e, '#') || !isfinite(*v)) {
    mx_error(s->path, s->line, "box %zu: %s: '%.*s' is not a finite number", box + 1, what,
             mx_io_toklen(s->p, '#'), s->p);
    return MX_EINPUT;
  }
  s->p = e;
  return MX_OK;
}

static int read_box(scan *s, size_t i, mx_qbox *b) {
  static const char *what[5] = {"xmin", "ymin", "xmax", "ymax", "level"};
  double v[5];
  for (int k = 0; k < 5; k++) MX_CHECK(scan_number(s, what[k], i, &v[k]));
  if (v[0] > v[2] || v[1] > v[3]) {
    mx_error(s->path, s->line, "box %zu: min corner above max corner", i + 1);
    return MX_EINPUT;
  }
  if (v[4] != floor(v[4]) || v[4] < 0 || v[4] > MX_QMAX_LEVEL - 1) {
    mx_error(s->path, s->line, "box %zu: level %g is not an integer between 0 and %d", i + 1,
             v[4], MX_QMAX_LEVEL - 1);
    return MX_EINPUT;
  }
  *b = (mx_qbox){{v[0], v[1]}, {v[2], v[3]}, (int)v[4]};
  return MX_OK;
}

static int parse_boxes(scan *s, mx_qbox **boxes, size_t *n) {
  s->p = mx_io_content(s->p, s->end, &s->line, '#');
  const int tl = s->p < s->end ? mx_io_toklen(s->p, '#') : 0;
  if (tl != 9 || strncasecmp(s->p, "n_regions", 9) != 0) {
    mx_error(s->path, s->line, "expected 'n_regions N', found '%.*s'", tl, s->p);
    return MX_EINPUT;
  }
  s->p = mx_io_content(s->p + 9, s->end, &s->line, '#');
  int64_t count;
  const char *e = s->p < s->end ? mx_io_int(s->p, &count) : NULL;
  /* a box takes at least 10 bytes: a bogus count allocates nothing */
  if (!e || !mx_io_delim(e, '#') || count < 0 || count > (s->end - s->p) / 10 + 1) {
    mx_error(s->path, s->line, "expected a box count after 'n_regions'");
    return MX_EINPUT;
  }
  s->p = e;
  *boxes = mx_alloc(((size_t)count + 1) * sizeof **boxes);
  if (!*boxes) return MX_ENOMEM;
  *n = (size_t)count;
  for (size_t i = 0; i < *n; i++) MX_CHECK(read_box(s, i, &(*boxes)[i]));
  s->p = mx_io_content(s->p, s->end, &s->line, '#');
  if (s->p == s->end) return MX_OK;
  mx_error(s->path, s->line, "more data than the %zu boxes declared by n_regions: '%.*s'", *n,
           mx_io_toklen(s->p, '#'), s->p);
  return MX_EINPUT;
}

int mx_read_qboxes(const char *path, mx_qbox **boxes, size_t *n) {
  char *buf;
  size_t len;
  *boxes = NULL;
  *n = 0;
  MX_CHECK(mx_io_load(path, &buf, &len));
  scan s = {path, buf, buf + len, 1};
  const int st = parse_boxes(&s, boxes, n);
  mx_free(buf);
  return st;
}

