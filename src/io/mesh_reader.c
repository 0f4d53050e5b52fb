/* The state every mesh reader shares (declared in io/mesh_reader.h): messages
 * with the line or byte offset of the failure, temporaries, where a value
 * lies in the file, ASCII value arrays, '%' comment lines. */
#include "io/mesh_reader.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include "base/common.h"
#include "io/text_scan.h"

static long line_of(const rd *r, const char *at) {
  long line = 1;
  const char *p = r->buf;
  while (p < at) {
    const char *nl = memchr(p, '\n', (size_t)(at - p));
    if (!nl) break;
    line++;
    p = nl + 1;
  }
  return line;
}
int mx_rd_fail(const rd *r, const char *at, const char *fmt, ...) {
  char msg[MSG];
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(msg, sizeof msg, fmt, ap);
  va_end(ap);
  if (!at || at < r->buf || at > r->end)
    mx_error(r->path, 0, "%s", msg);
  else if (r->bin_from && at >= r->bin_from)
    mx_error(r->path, 0, "%s (at byte %zu)", msg, (size_t)(at - r->buf));
  else
    mx_error(r->path, line_of(r, at), "%s", msg);
  return MX_EINPUT;
}

int mx_rd_alloc(rd *r, size_t bytes, void **out) {
  *out = NULL;
  if (r->ntmp == MAX_TMP) {
    mx_error(r->path, 0, "internal error: too many temporaries");
    return MX_EINTERNAL;
  }
  void *p = mx_alloc(bytes);
  if (!p) return MX_ENOMEM;
  r->tmp[r->ntmp++] = p;
  *out = p;
  return MX_OK;
}

/* Where element i lies in the file, for messages: in place, or found again
 * by counting the tokens of the ASCII text it was parsed from. */
const char *mx_rd_arr_at(const rd *r, const rawarr *a, size_t i) {
  if (a->text) {
    const char *p = skip_ws(a->text, r->end);
    for (size_t k = 0; k < i && p < r->end; k++)
      p = skip_ws(p + tok_len(p, r->end), r->end);
    return p;
  }
  const char *p = (const char *)a->data;
  if (p < r->buf || p > r->end) return NULL;
  return p + i * (size_t)vsize[a->t];
}

/* n blank-separated numbers (any line breaks) from *pp, stopping at end, at
 * a NUL or at `stop`. Into iv (integers) or dv (finite doubles). */
static int ascii_values(const rd *r, const char **pp, char stop, size_t n,
                        int64_t *iv, double *dv, const char *what) {
  const char *p = *pp, *end = r->end;
  for (size_t i = 0; i < n; i++) {
    p = skip_ws(p, end);
    if (p >= end || *p == '\0' || *p == stop)
      return mx_rd_fail(r, p,
                        "%s: expected %zu values, found %zu (truncated file or "
                        "wrong count)",
                        what, n, i);
    const char *e = dv ? mx_io_double(p, &dv[i]) : mx_io_int(p, &iv[i]);
    size_t tl = tok_len(p, end);
    if (stop) {
      const char *s = memchr(p, stop, tl);
      if (s) tl = (size_t)(s - p);
    }
    if (!e || e != p + tl)
      return mx_rd_fail(r, p, "%s: value %zu: '%.*s' is not %s", what, i,
                        shown(tl), p, dv ? "a number" : "an integer");
    if (dv && !isfinite(dv[i]))
      return mx_rd_fail(r, p, "%s: value %zu: '%.*s' is not a finite number", what,
                        i, shown(tl), p);
    p = e;
  }
  *pp = p;
  return MX_OK;
}

/* Parses values into a temporary and describes it as a host-order array. */
int mx_rd_ascii_array(rd *r, const char **pp, char stop, size_t n,
                      int floats, rawarr *out, const char *what) {
  /* Each value takes at least two bytes: refuse absurd counts early. */
  if (n > (size_t)(r->end - *pp) / 2 + 1)
    return mx_rd_fail(r, *pp,
                      "%s: %zu values announced but the file is too short "
                      "(truncated file or wrong count)",
                      what, n);
  void *v;
  MX_CHECK(mx_rd_alloc(r, n * 8, &v));
  const char *text = *pp;
  MX_CHECK(ascii_values(r, pp, stop, n, floats ? NULL : v, floats ? v : NULL,
                        what));
  *out = (rawarr){v, n, floats ? T_F64 : T_I64, 0, text};
  return MX_OK;
}

/* Past blank lines and '%' comment lines. */
const char *mx_rd_skip_percent_lines(const rd *r, const char *p) {
  for (;;) {
    p = skip_ws(p, r->end);
    if (p >= r->end || *p != '%') return p;
    const char *nl = memchr(p, '\n', (size_t)(r->end - p));
    p = nl ? nl + 1 : r->end;
  }
}
