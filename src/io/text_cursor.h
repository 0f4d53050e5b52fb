/* The cursor the MSH, Medit, M3D, MVM and GetFEM readers read with.
 *
 * Text: blank-separated tokens of the NUL-terminated buffer, parsed with the
 * shared scanners; a Medit comment ('#' to the end of the line) is a blank
 * when comments is set. Binary: a cursor p and the bytes left before end,
 * checked before every read. */
#ifndef MX_TEXT_CURSOR_H
#define MX_TEXT_CURSOR_H

#include <math.h>
#include <stdint.h>
#include <string.h>

#include "base/common.h"
#include "io/mesh_reader.h"
#include "io/text_scan.h"

typedef struct {
  rd *r;
  const char *p;
  int comments; /* '#' starts a comment (Medit) */
  int swap;     /* binary: byte-swap */
} cur;

static inline const char *cur_skip(cur *c) {
  const char *p = c->p, *end = c->r->end;
  for (;;) {
    p = skip_ws(p, end);
    if (!c->comments || p >= end || *p != '#') break;
    const char *nl = memchr(p, '\n', (size_t)(end - p));
    p = nl ? nl + 1 : end;
  }
  c->p = p;
  return p;
}

/* The next token (length in *n, 0 at the end or at a NUL byte). */
static inline const char *cur_tok(cur *c, size_t *n) {
  const char *t = cur_skip(c);
  *n = tok_len(t, c->r->end);
  c->p = t + *n;
  return t;
}

static inline size_t cur_left(const cur *c) { return (size_t)(c->r->end - c->p); }

static inline int cur_int(cur *c, int64_t *v, const char *what) {
  size_t n;
  const char *t = cur_tok(c, &n);
  if (n == 0)
    return mx_rd_fail(c->r, t, "%s: unexpected end of file (truncated file or "
                      "wrong count)", what);
  const char *e = mx_io_int(t, v);
  if (!e || e != t + n)
    return mx_rd_fail(c->r, t, "%s: '%.*s' is not an integer", what, shown(n), t);
  return MX_OK;
}

/* A count or tag: an integer >= 0 (>= 1 when positive). */
static inline int cur_count(cur *c, uint64_t *v, int positive, const char *what) {
  const char *at = cur_skip(c);
  int64_t x = 0;
  MX_CHECK(cur_int(c, &x, what));
  if (x < positive)
    return mx_rd_fail(c->r, at, "%s: %lld is out of range", what, (long long)x);
  *v = (uint64_t)x;
  return MX_OK;
}

static inline int cur_real(cur *c, double *v, const char *what) {
  size_t n;
  const char *t = cur_tok(c, &n);
  if (n == 0)
    return mx_rd_fail(c->r, t, "%s: unexpected end of file (truncated file or "
                      "wrong count)", what);
  const char *e = mx_io_double(t, v);
  if (!e || e != t + n)
    return mx_rd_fail(c->r, t, "%s: '%.*s' is not a number", what, shown(n), t);
  if (!isfinite(*v))
    return mx_rd_fail(c->r, t, "%s: '%.*s' is not a finite number", what, shown(n),
                      t);
  return MX_OK;
}

/* n bytes must be left; a message names what is short. */
static inline int cur_need(cur *c, uint64_t n, const char *what) {
  if (n > cur_left(c))
    return mx_rd_fail(c->r, c->p,
                      "%s: %llu bytes needed but only %zu are left (truncated file "
                      "or wrong count)",
                      what, (unsigned long long)n, cur_left(c));
  return MX_OK;
}

static inline uint64_t bin_u(cur *c, int size) { /* bounds checked by the caller */
  const uint64_t v = load_bits((const unsigned char *)c->p, size, c->swap);
  c->p += size;
  return v;
}

static inline double bin_real(cur *c, int size) {
  const uint64_t b = bin_u(c, size);
  if (size == 4) {
    const uint32_t b4 = (uint32_t)b;
    float f;
    memcpy(&f, &b4, 4);
    return f;
  }
  double d;
  memcpy(&d, &b, 8);
  return d;
}

/* Grows the cells of out by n (n already checked against the file size). */
int mx_rd_grow_cells(rd *r, mx_mesh_data *out, size_t n);
/* The next tokens must be the blank-separated words of `words`. */
int mx_rd_cur_words(cur *c, const char *words, const char *what);
/* The node indices of cell `cell` of the given type, the j-th read into
 * slot perm[j] of its row (perm NULL: slot j). */
int mx_rd_cur_cell_nodes(cur *c, mx_mesh_data *out, size_t cell, int type,
                         const int8_t *perm);

#endif
