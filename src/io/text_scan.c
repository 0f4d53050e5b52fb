/* The tokenizer the readers share (declared in io/text_scan.h): loading a
 * whole file, stepping over blanks, lines and comments, fast decimal
 * numbers, and checked numbers and indices with messages that name the file
 * and line. */
#include "io/text_scan.h"

#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "base/common.h"

/* ---- loading ---------------------------------------------------------- */

/* The most an input file may hold: half the physical memory (a surface
 * file larger than that cannot be meshed here; a device that never ends,
 * like /dev/zero, is refused when it gets there). */
static size_t input_limit(void) {
  const long pages = sysconf(_SC_PHYS_PAGES), psize = sysconf(_SC_PAGESIZE);
  if (pages <= 0 || psize <= 0) return (size_t)1 << 34;
  return (size_t)pages / 2 * (size_t)psize;
}

static int too_large(const char *path, size_t limit) {
  mx_error(path, 0, "larger than %.0f MB, half the memory of this machine: not read (is "
                    "it a surface file?)", (double)limit / 1048576.0);
  return MX_EINPUT;
}

static int read_all(int fd, const char *path, char **buf, size_t *len,
                    size_t hint) {
  const size_t limit = input_limit();
  if (hint > limit) return too_large(path, limit);
  size_t cap = hint + 2, n = 0; /* room for the NUL and the read at EOF */
  char *b = mx_alloc(cap);
  if (!b) {
    mx_error(path, 0, "cannot load the file: out of memory");
    return MX_ENOMEM;
  }
  for (;;) {
    if (n + 1 >= cap) {
      if (n > limit) {
        mx_free(b);
        return too_large(path, limit);
      }
      char *nb = mx_realloc(b, 2 * cap);
      if (!nb) {
        mx_free(b);
        return MX_ENOMEM;
      }
      b = nb;
      cap *= 2;
    }
    ssize_t r = read(fd, b + n, cap - 1 - n);
    if (r == 0) break;
    if (r < 0 && errno == EINTR) continue;
    if (r < 0) {
      mx_error(path, 0, "cannot read: %s", strerror(errno));
      mx_free(b);
      return MX_EINPUT;
    }
    n += (size_t)r;
  }
  b[n] = '\0';
  /* a UTF-8 byte-order mark, as some Windows editors write, is not content */
  if (n >= 3 && (unsigned char)b[0] == 0xef && (unsigned char)b[1] == 0xbb &&
      (unsigned char)b[2] == 0xbf) {
    memmove(b, b + 3, n - 2);
    n -= 3;
  }
  *buf = b;
  *len = n;
  return MX_OK;
}

/* Reads the whole file into *buf (mx_alloc'd, NUL-terminated after *len
 * bytes). Missing, unreadable, directory and empty files are errors. */
static int load(const char *path, int allow_empty, char **buf, size_t *len) {
  *buf = NULL;
  *len = 0;
  int fd = open(path, O_RDONLY | O_CLOEXEC);
  if (fd < 0) {
    mx_error(path, 0, "cannot open: %s", strerror(errno));
    return MX_EINPUT;
  }
  struct stat st;
  if (fstat(fd, &st) != 0) {
    mx_error(path, 0, "cannot read: %s", strerror(errno));
    close(fd);
    return MX_EINPUT;
  }
  if (S_ISDIR(st.st_mode)) {
    mx_error(path, 0, "cannot read: is a directory");
    close(fd);
    return MX_EINPUT;
  }
  if (S_ISCHR(st.st_mode) || S_ISBLK(st.st_mode)) {
    mx_error(path, 0, "cannot read: a device, not a file");
    close(fd);
    return MX_EINPUT;
  }
  size_t hint = S_ISREG(st.st_mode) ? (size_t)st.st_size : 65536;
  int status = read_all(fd, path, buf, len, hint);
  close(fd);
  if (status == MX_OK && *len == 0 && !allow_empty) {
    mx_error(path, 0, "empty file");
    mx_free(*buf);
    *buf = NULL;
    return MX_EINPUT;
  }
  return status;
}

int mx_io_load(const char *path, char **buf, size_t *len) {
  return load(path, 0, buf, len);
}

int mx_io_load_empty_ok(const char *path, char **buf, size_t *len) {
  return load(path, 1, buf, len);
}

/* ---- lines and tokens ------------------------------------------------- */

static inline int is_blank(char c) {
  return c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v';
}

static inline int is_digit(char c) { return c >= '0' && c <= '9'; }

static inline const char *skip_blank(const char *p) {
  while (is_blank(*p)) p++;
  return p;
}

static inline int at_eol(const char *p, char comment) {
  return *p == '\n' || *p == '\0' || (comment && *p == comment);
}

static inline int at_delim(const char *p, char comment) {
  return is_blank(*p) || at_eol(p, comment);
}

/* Skips spaces and tabs, never a newline. */
const char *mx_io_blank(const char *p) { return skip_blank(p); }

/* At the end of a line's content: newline, end of buffer or a comment. */
int mx_io_eol(const char *p, char comment) { return at_eol(p, comment); }

/* True if a token may end here. */
int mx_io_delim(const char *p, char comment) { return at_delim(p, comment); }

/* The start of the next line, or end if there is none. */
const char *mx_io_next_line(const char *p, const char *end, long *line) {
  if (p >= end) return end;
  const char *nl = memchr(p, '\n', (size_t)(end - p));
  if (!nl) return end;
  ++*line;
  return nl + 1;
}

/* From the start of a line, skips blank and comment-only lines; returns the
 * first non-blank character of the next content line, or end. */
const char *mx_io_content(const char *p, const char *end, long *line,
                          char comment) {
  while (p < end) {
    p = skip_blank(p);
    if (p >= end) return end;
    if (*p != '\n' && !(comment && *p == comment)) return p;
    p = mx_io_next_line(p, end, line);
  }
  return end;
}

/* Length of the token at p (for messages), at most 40. */
int mx_io_toklen(const char *p, char comment) {
  int n = 0;
  while (n < 40 && !at_delim(p + n, comment)) n++;
  return n;
}

/* ---- numbers ---------------------------------------------------------- */

static const double pow10_exact[23] = {
    1e0,  1e1,  1e2,  1e3,  1e4,  1e5,  1e6,  1e7,  1e8,  1e9,  1e10, 1e11,
    1e12, 1e13, 1e14, 1e15, 1e16, 1e17, 1e18, 1e19, 1e20, 1e21, 1e22};

typedef struct {
  uint64_t m;  /* significant digits, at most 19 */
  int e10;     /* value = m * 10^e10 */
  int ndigits; /* digits seen in the mantissa */
  int exact;   /* no nonzero digit was dropped */
} decimal;

static const char *scan_digits(const char *q, decimal *d, int fraction) {
  for (; is_digit(*q); q++) {
    d->ndigits++;
    if (d->m < 1000000000000000000ull) { /* fewer than 19 digits so far */
      d->m = 10 * d->m + (uint64_t)(*q - '0');
      d->e10 -= fraction;
    } else {
      if (*q != '0') d->exact = 0;
      d->e10 += !fraction;
    }
  }
  return q;
}

static const char *scan_exponent(const char *q, decimal *d) {
  if (*q != 'e' && *q != 'E') return q;
  const char *r = q + 1;
  int sign = 1, e = 0;
  if (*r == '+' || *r == '-') sign = (*r++ == '-') ? -1 : 1;
  if (!is_digit(*r)) return q; /* "1e" is the number 1 followed by 'e' */
  for (; is_digit(*r); r++)
    if (e < 100000) e = 10 * e + (*r - '0');
  d->e10 += sign * e;
  return r;
}

/* Parses a decimal number at p. Common inputs take an exact fast path
 * (at most 19 digits, |m| < 2^53, |exponent| <= 22: one correctly rounded
 * operation); everything else, including nan and inf, goes to strtod.
 * Returns the end of the number, or NULL if there is none. The value may be
 * non-finite: callers check. */
const char *mx_io_double(const char *p, double *v) {
  if (at_delim(p, 0)) return NULL; /* strtod would skip a newline */
  const char *q = p;
  int neg = 0;
  if (*q == '+' || *q == '-') neg = (*q++ == '-');
  decimal d = {0, 0, 0, 1};
  q = scan_digits(q, &d, 0);
  if (*q == '.') q = scan_digits(q + 1, &d, 1);
  if (d.ndigits > 0) {
    q = scan_exponent(q, &d);
    if (d.m == 0) {
      *v = neg ? -0.0 : 0.0;
      return q;
    }
    if (d.exact && d.m <= (1ull << 53) && d.e10 >= -22 && d.e10 <= 22) {
      double x = (double)d.m;
      x = d.e10 < 0 ? x / pow10_exact[-d.e10] : x * pow10_exact[d.e10];
      *v = neg ? -x : x;
      return q;
    }
  }
  char *e;
  *v = strtod(p, &e);
  return e == p ? NULL : e;
}

/* Parses a decimal integer (optional sign); saturates far beyond 32 bits so
 * range checks reject it. NULL if there is no digit. */
const char *mx_io_int(const char *p, int64_t *v) {
  const char *q = p;
  int neg = 0;
  if (*q == '+' || *q == '-') neg = (*q++ == '-');
  if (!is_digit(*q)) return NULL;
  int64_t x = 0;
  for (; is_digit(*q); q++)
    if (x < ((int64_t)1 << 40)) x = 10 * x + (*q - '0');
  *v = neg ? -x : x;
  return q;
}

/* ---- checked fields on one line -------------------------------------- */

/* Parses n finite numbers from the current line at *p and advances *p.
 * Errors name the item, e.g. what = "vertex", item = 7. */
int mx_io_numbers(const char *path, long line, const char **p, char comment,
                  int n, double *out, const char *what, size_t item) {
  const char *q = *p;
  for (int k = 0; k < n; k++) {
    q = skip_blank(q);
    const char *e = mx_io_double(q, &out[k]);
    if (at_eol(q, comment)) {
      mx_error(path, line, "%s %zu: expected %d numbers, found %d", what, item,
               n, k);
      return MX_EINPUT;
    }
    if (!e || !at_delim(e, comment)) {
      mx_error(path, line, "%s %zu: '%.*s' is not a number", what, item,
               mx_io_toklen(q, comment), q);
      return MX_EINPUT;
    }
    if (!isfinite(out[k])) {
      mx_error(path, line, "%s %zu: '%.*s' is not a finite number", what, item,
               mx_io_toklen(q, comment), q);
      return MX_EINPUT;
    }
    q = e;
  }
  *p = q;
  return MX_OK;
}

/* Parses one 0-based vertex index < nv from the current line at *p. */
int mx_io_index(const char *path, long line, const char **p, char comment,
                size_t nv, uint32_t *idx, const char *what, size_t item) {
  const char *q = skip_blank(*p);
  int64_t v;
  const char *e = mx_io_int(q, &v);
  if (at_eol(q, comment)) {
    mx_error(path, line, "%s %zu: missing vertex index", what, item);
    return MX_EINPUT;
  }
  if (!e || !at_delim(e, comment)) {
    mx_error(path, line, "%s %zu: bad vertex index '%.*s'", what, item,
             mx_io_toklen(q, comment), q);
    return MX_EINPUT;
  }
  if (v < 0) {
    mx_error(path, line, "%s %zu: vertex index %.*s out of range (negative)",
             what, item, mx_io_toklen(q, comment), q);
    return MX_EINPUT;
  }
  if ((uint64_t)v >= nv) {
    mx_error(path, line,
             "%s %zu: vertex index %.*s out of range (%zu vertices, 0-based)",
             what, item, mx_io_toklen(q, comment), q, nv);
    return MX_EINPUT;
  }
  *idx = (uint32_t)v;
  *p = e;
  return MX_OK;
}
