/* mixoct: element index lists (the rule is in element_list.h). */
#include "io/element_list.h"

#include "base/common.h"
#include "io/text_scan.h"

enum { FIRST_CAP = 1024 }; /* indices the output starts with room for */

/* Exponents saturate past this: beyond the length of any word, so the
 * verdict (too large, fraction) stays exact, and 10 * EXP_CAP + 9 fits. */
static const long long EXP_CAP = 100000000000000000LL;

static inline int is_digit(unsigned c) { return c - '0' < 10; }

/* Blanks and commas; '\n' and '#' are handled apart. */
static inline int is_sep(unsigned c) {
  return c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v' || c == ',';
}

/* [p, e) is one of the names of a non-finite value, in any case. */
static int non_finite(const char *p, const char *e) {
  static const char *const names[] = {"nan", "inf", "infinity"};
  for (int k = 0; k < 3; k++) {
    const char *q = p, *s = names[k];
    while (q < e && *s && (*q | 0x20) == *s) q++, s++;
    if (q == e && !*s) return 1;
  }
  return 0;
}

int mx_word_index(const char *w, size_t len, uint64_t *v) {
  *v = 0;
  const char *p = w, *const e = w + len;
  int neg = 0;
  if (p < e && (*p == '+' || *p == '-')) neg = *p++ == '-';
  if (non_finite(p, e)) return MX_WORD_NOT_FINITE;
  /* [i0, i1) the digits before the point, [f0, f1) those after it */
  const char *const i0 = p;
  while (p < e && is_digit((unsigned char)*p)) p++;
  const char *const i1 = p, *f0 = p, *f1 = p;
  if (p < e && *p == '.') {
    f0 = ++p;
    while (p < e && is_digit((unsigned char)*p)) p++;
    f1 = p;
  }
  if (i1 == i0 && f1 == f0) return MX_WORD_NOT_NUMBER; /* "", ".", "+" */
  long long exp = 0;
  if (p < e && (*p == 'e' || *p == 'E')) {
    int eneg = 0;
    if (++p < e && (*p == '+' || *p == '-')) eneg = *p++ == '-';
    const char *const x0 = p;
    for (; p < e && is_digit((unsigned char)*p); p++)
      if (exp < EXP_CAP) exp = 10 * exp + (*p - '0');
    if (p == x0) return MX_WORD_NOT_NUMBER; /* "1e", "1e+" */
    if (eneg) exp = -exp;
  }
  if (p != e) return MX_WORD_NOT_NUMBER;

  /* The digits d[0 .. nd): those before the point, then those after; the
   * value is d * 10^(exp - nf). Only d[a .. b], the first to the last
   * non-zero digit, matter. */
  const size_t ni = (size_t)(i1 - i0), nf = (size_t)(f1 - f0), nd = ni + nf;
#define DIGIT(k) ((unsigned)((k) < ni ? i0[(k)] : f0[(k) - ni]) - '0')
  size_t a = 0, b = nd;
  while (a < nd && DIGIT(a) == 0) a++;
  if (a == nd) return MX_WORD_INDEX; /* zero, whatever the sign, the exponent */
  if (neg) return MX_WORD_NEGATIVE;
  while (DIGIT(b - 1) == 0) b--;
  /* d[a .. b) times 10^scale, d[b - 1] != 0: whole if and only if scale >= 0 */
  const long long scale = exp - (long long)nf + (long long)(nd - b);
  if (scale < 0) return MX_WORD_FRACTION;
  if ((long long)(b - a) + scale > 20) return MX_WORD_TOO_LARGE;
  uint64_t x = 0;
  for (size_t k = a; k < b; k++) {
    const unsigned d = DIGIT(k);
    if (x > (UINT64_MAX - d) / 10) return MX_WORD_TOO_LARGE;
    x = 10 * x + d;
  }
#undef DIGIT
  for (long long k = 0; k < scale; k++) {
    if (x > UINT64_MAX / 10) return MX_WORD_TOO_LARGE;
    x *= 10;
  }
  *v = x;
  return MX_WORD_INDEX;
}

/* The message for the word [t, t + len) on line `line`: code is an
 * MX_WORD_ code, or MX_WORD_INDEX for an index v >= limit. */
static void refuse(const char *name, long line, const char *t, size_t len, int code,
                   uint64_t limit) {
  char w[MX_WORD_BUF];
  mx_show_word(t, len, w);
  const unsigned long long nel = (unsigned long long)limit;
  switch (code) {
  case MX_WORD_NOT_NUMBER:
    mx_error(name, line,
             "\"%s\" is not an element index (a whole number >= 0, as 12, 12.0 or "
             "1.2e+01; separators: blanks, commas; '#' starts a comment)", w);
    break;
  case MX_WORD_NOT_FINITE:
    mx_error(name, line, "\"%s\" is not a finite number: not an element index", w);
    break;
  case MX_WORD_NEGATIVE:
    mx_error(name, line, "element index \"%s\" is negative (indices start at 0)", w);
    break;
  case MX_WORD_FRACTION:
    mx_error(name, line, "element index \"%s\" is not a whole number", w);
    break;
  default: /* too large for 64 bits, or >= limit */
    if (limit == UINT64_MAX)
      mx_error(name, line, "element index \"%s\" is too large (above 2^64 - 1)", w);
    else if (limit == 0)
      mx_error(name, line, "element index \"%s\" is out of range: there are no elements", w);
    else
      mx_error(name, line,
               "element index \"%s\" is out of range: %llu elements, indices 0 to %llu",
               w, nel, nel - 1);
  }
}

int mx_parse_index_list(const char *name, const void *buf, size_t len, uint64_t limit,
                        uint64_t **out, size_t *n) {
  *out = NULL;
  *n = 0;
  const char *p = buf, *const end = p + len;
  if (len >= 3 && (unsigned char)p[0] == 0xef && (unsigned char)p[1] == 0xbb &&
      (unsigned char)p[2] == 0xbf)
    p += 3;
  uint64_t *a = mx_alloc(FIRST_CAP * sizeof *a);
  if (!a) return MX_ENOMEM;
  size_t k = 0, cap = FIRST_CAP;
  long line = 1;
  while (p < end) {
    const unsigned char c = (unsigned char)*p;
    if (c == '\n') {
      line++;
      p++;
    } else if (is_sep(c)) {
      p++;
    } else if (c == '#') {
      while (p < end && *p != '\n') p++;
    } else {
      const char *const t = p;
      while (p < end && !is_sep((unsigned char)*p) && *p != '\n' && *p != '#') p++;
      uint64_t v;
      const int code = mx_word_index(t, (size_t)(p - t), &v);
      if (code != MX_WORD_INDEX || v >= limit) {
        refuse(name, line, t, (size_t)(p - t), code, limit);
        mx_free(a);
        return MX_EINPUT;
      }
      if (k == cap) {
        uint64_t *b = mx_realloc(a, 2 * cap * sizeof *a);
        if (!b) {
          mx_free(a);
          return MX_ENOMEM;
        }
        a = b;
        cap *= 2;
      }
      a[k++] = v;
    }
  }
  if (k == 0)
    mx_warning(name, 0, "no element index in the list (an empty file, or only blanks and "
                        "comments): the list refines nothing");
  *out = a;
  *n = k;
  return MX_OK;
}

int mx_read_index_list(const char *path, uint64_t limit, uint64_t **out, size_t *n) {
  *out = NULL;
  *n = 0;
  char *buf;
  size_t len;
  MX_CHECK(mx_io_load_empty_ok(path, &buf, &len));
  const int st = mx_parse_index_list(path, buf, len, limit, out, n);
  mx_free(buf);
  return st;
}
