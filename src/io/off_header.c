/* The header of an OFF file (io/off_header.h). */
#include "io/off_header.h"

#include <stdint.h>
#include <string.h>

#include "base/common.h"
#include "io/text_scan.h"

int mx_off_keyword(const char *tok, int n) {
  if (n < 3 || memcmp(tok + n - 3, "OFF", 3) != 0) return 0;
  for (int i = 0; i < n - 3; i++)
    if (!strchr("CNST", tok[i])) return 0;
  return 1;
}

/* One count of the header, at most max. */
static int header_count(const char *path, long line, const char **q, size_t max, size_t *v,
                        const char *name) {
  int64_t x;
  const char *s = mx_io_blank(*q);
  const char *e = mx_io_int(s, &x);
  if (!e || !mx_io_delim(e, '#') || x < 0 || (uint64_t)x > max) {
    mx_error(path, line, "bad header: expected the counts 'nv nf ne', found '%.*s' for %s",
             mx_io_toklen(s, '#'), s, name);
    return MX_EINPUT;
  }
  *v = (size_t)x;
  *q = e;
  return MX_OK;
}

int mx_off_counts(const char *path, const char **p, const char *end, long *line,
                  size_t nv_max, size_t nf_max, size_t *nv, size_t *nf) {
  *p = mx_io_content(*p, end, line, '#');
  if (*p == end) {
    mx_error(path, *line, "no 'OFF' header: the file has no content");
    return MX_EINPUT;
  }
  const int n = mx_io_toklen(*p, '#');
  if (!mx_off_keyword(*p, n)) {
    mx_error(path, *line, "bad header: expected 'OFF', found '%.*s'", n, *p);
    return MX_EINPUT;
  }
  const char *q = mx_io_blank(*p + n);
  if (mx_io_eol(q, '#')) {
    *p = mx_io_next_line(q, end, line);
    *p = mx_io_content(*p, end, line, '#');
    if (*p == end) {
      mx_error(path, *line, "bad header: missing counts 'nv nf ne'");
      return MX_EINPUT;
    }
    q = *p;
  }
  MX_CHECK(header_count(path, *line, &q, nv_max, nv, "nv"));
  MX_CHECK(header_count(path, *line, &q, nf_max, nf, "nf"));
  return MX_OK;
}

int mx_off_next(const char *path, const char **p, const char *end, long *line, const char *what,
                size_t i, size_t n) {
  *p = mx_io_next_line(*p, end, line);
  *p = mx_io_content(*p, end, line, '#');
  if (*p < end) return MX_OK;
  mx_error(path, *line,
           "unexpected end of file: %zu of %zu %s read (truncated file or wrong counts in "
           "the header)",
           i, n, what);
  return MX_EINPUT;
}
