/* .reg reader: "n_regions N", then per region the min corner "x y z", the
 * max corner "x y z" and the refinement level, as whitespace-separated
 * tokens (any line layout); '#' starts a comment. */
#include <limits.h>
#include <math.h>
#include <stdint.h>
#include <string.h>
#include <strings.h>

#include "base/common.h"
#include "base/morton.h"
#include "soa/regions.h"

#include "io/text_scan.h"

/* the finest level a request may ask (MX_MAX_LEVEL - 1), as text */
#define MX_MAX_LEVEL_ASKED 15
#define MX_STR2(x) #x
#define MX_STR(x) MX_STR2(x)
_Static_assert(MX_MAX_LEVEL_ASKED == MX_MAX_LEVEL - 1, "keep the message in step");

typedef struct {
  const char *path, *p, *end; /* p: the next unread character */
  long line;
  size_t n;   /* declared count */
  size_t cap; /* boxes allocated */
  mx_box_region *boxes;
} reg_file;

/* Moves to the next token; error if the file ends first. */
static int next_token(reg_file *f, size_t region, const char *what) {
  f->p = mx_io_content(f->p, f->end, &f->line, '#');
  if (f->p < f->end) return MX_OK;
  mx_error(f->path, f->line,
           "unexpected end of file: region %zu of %zu has no %s (truncated "
           "file or wrong n_regions)",
           region + 1, f->n, what);
  return MX_EINPUT;
}

static int bad_token(const reg_file *f, size_t region, const char *what,
                     const char *problem) {
  mx_error(f->path, f->line, "region %zu: %s: '%.*s' %s", region + 1, what,
           mx_io_toklen(f->p, '#'), f->p, problem);
  return MX_EINPUT;
}

static int read_number(reg_file *f, size_t region, const char *what,
                       double *v) {
  MX_CHECK(next_token(f, region, what));
  const char *e = mx_io_double(f->p, v);
  if (!e || !mx_io_delim(e, '#'))
    return bad_token(f, region, what, "is not a number");
  if (!isfinite(*v)) return bad_token(f, region, what, "is not finite");
  f->p = e;
  return MX_OK;
}

static int read_level(reg_file *f, size_t region, int *level) {
  MX_CHECK(next_token(f, region, "level"));
  int64_t v;
  const char *e = mx_io_int(f->p, &v);
  if (!e || !mx_io_delim(e, '#'))
    return bad_token(f, region, "level", "is not an integer");
  if (v < 0 || v > MX_MAX_LEVEL - 1)
    return bad_token(f, region, "level", "is out of range (levels are 0 to "
                                          MX_STR(MX_MAX_LEVEL_ASKED) ", as for -s)");
  *level = (int)v;
  f->p = e;
  return MX_OK;
}

static int read_region(reg_file *f, size_t i, mx_box_region *b) {
  static const char *what[6] = {"min x", "min y", "min z",
                                "max x", "max y", "max z"};
  double c[6];
  for (int k = 0; k < 6; k++) MX_CHECK(read_number(f, i, what[k], &c[k]));
  for (int d = 0; d < 3; d++) {
    if (c[d] > c[3 + d]) {
      mx_error(f->path, f->line,
               "region %zu: min corner above max corner (%s %g > %g)", i + 1,
               what[d], c[d], c[3 + d]);
      return MX_EINPUT;
    }
    b->lo[d] = c[d];
    b->hi[d] = c[3 + d];
  }
  return read_level(f, i, &b->level);
}

static int read_count(reg_file *f) {
  f->p = mx_io_content(f->p, f->end, &f->line, '#');
  int n = f->p < f->end ? mx_io_toklen(f->p, '#') : 0;
  if (n != 9 || strncasecmp(f->p, "n_regions", 9) != 0) {
    mx_error(f->path, f->line, "expected 'n_regions N', found '%.*s'", n, f->p);
    return MX_EINPUT;
  }
  f->p = mx_io_content(f->p + 9, f->end, &f->line, '#');
  int64_t v;
  const char *e = f->p < f->end ? mx_io_int(f->p, &v) : NULL;
  if (!e || !mx_io_delim(e, '#') || v < 0 || v > INT32_MAX) {
    mx_error(f->path, f->line, "expected a region count after 'n_regions'");
    return MX_EINPUT;
  }
  f->n = (size_t)v;
  f->p = e;
  return MX_OK;
}

/* Room for box i; the first allocation is bounded by the file size (a
 * region takes at least 13 bytes) so a huge bogus count costs nothing. */
static int room(reg_file *f, size_t i) {
  if (i < f->cap && f->boxes) return MX_OK;
  size_t bound = (size_t)(f->end - f->p) / 13 + 1;
  size_t cap = f->boxes ? 2 * f->cap : (f->n < bound ? f->n : bound);
  if (cap > f->n) cap = f->n;
  if (cap == 0) cap = 1;
  mx_box_region *b = mx_realloc(f->boxes, cap * sizeof *b);
  if (!b) return MX_ENOMEM;
  f->boxes = b;
  f->cap = cap;
  return MX_OK;
}

static int parse_reg(reg_file *f) {
  MX_CHECK(read_count(f));
  MX_CHECK(room(f, 0));
  for (size_t i = 0; i < f->n; i++) {
    MX_CHECK(room(f, i));
    MX_CHECK(read_region(f, i, &f->boxes[i]));
  }
  f->p = mx_io_content(f->p, f->end, &f->line, '#');
  if (f->p == f->end) return MX_OK;
  mx_error(f->path, f->line,
           "more data than the %zu regions declared by n_regions: '%.*s'", f->n,
           mx_io_toklen(f->p, '#'), f->p);
  return MX_EINPUT;
}

int mx_read_reg(const char *path, mx_box_region **boxes, size_t *n) {
  *boxes = NULL;
  *n = 0;
  char *buf;
  size_t len;
  MX_CHECK(mx_io_load(path, &buf, &len));
  reg_file f = {path, buf, buf + len, 1, 0, 0, NULL};
  int status = parse_reg(&f);
  mx_free(buf);
  if (status != MX_OK) {
    mx_free(f.boxes);
    return status;
  }
  *boxes = f.boxes;
  *n = f.n;
  return MX_OK;
}
