/* mixoct: restart files, text and binary (see restart.h for the formats).
 *
 * Reading loads the whole file and scans it in place with bounded,
 * hand-written number parsing (no NUL terminator is needed, so the same
 * code parses a fuzzer's buffer); nothing is allocated per line. Arrays are
 * sized from the header but never beyond what the file's length could hold,
 * so a lying header cannot cause a huge allocation. Writing goes through
 * the atomic-file helpers; text sections are formatted in parallel chunks
 * by mx_afile_emit. */
#include "io/restart.h"

#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <unistd.h>

#include "base/common.h"
#include "io/atomic_file.h"
#include "io/text_num.h"

#if __BYTE_ORDER__ != __ORDER_LITTLE_ENDIAN__
#error "the binary restart file is read and written as little-endian memory"
#endif

enum {
  BIN_VERSION = 1,
  BIN_HEADER = 48, /* magic, version, flags, nv, ne, no, ntri */
  BIN_TRANSFORM = 1u,
  BIN_NSUB = 2u,
  BIN_MESH = 4u,   /* a mesh section: 16 more header bytes (nodes, elements) */
  BIN_BYTYPE = 8u, /* element lists refer to the elements grouped by type */
  BIN_MATERIALS = 16u, /* written with several materials */
  TOK_SHOW = 40, /* at most this many characters of a token in messages */
};
static const uint8_t bin_magic[8] = {0x89, 'M', 'X', 'O', 'C', 'T', '\r', '\n'};

/* ---- loading ------------------------------------------------------------- */

/* Reads the whole file into *buf (mx_alloc'd, *len bytes). Missing files,
 * directories and read errors are reported, and so is an empty file unless
 * allow_empty. */
static int load_file(const char *path, int allow_empty, uint8_t **buf,
                     size_t *len) {
  *buf = NULL;
  *len = 0;
  int fd = open(path, O_RDONLY | O_CLOEXEC);
  if (fd < 0) {
    mx_error(path, 0, "cannot open: %s", strerror(errno));
    return MX_EINPUT;
  }
  struct stat st;
  int bad = fstat(fd, &st) != 0 ? errno : S_ISDIR(st.st_mode) ? EISDIR : 0;
  if (bad) {
    mx_error(path, 0, "cannot read: %s", strerror(bad));
    close(fd);
    return MX_EINPUT;
  }
  size_t cap = S_ISREG(st.st_mode) ? (size_t)st.st_size + 1 : (size_t)1 << 16;
  size_t n = 0;
  uint8_t *b = mx_alloc(cap);
  for (ssize_t got = 1; b && got != 0;) {
    if (n == cap) {
      uint8_t *nb = mx_realloc(b, 2 * cap);
      if (!nb) mx_free(b);
      b = nb;
      cap *= 2;
      if (!b) break;
    }
    got = read(fd, b + n, cap - n);
    if (got < 0 && errno == EINTR) continue;
    if (got < 0) {
      mx_error(path, 0, "cannot read: %s", strerror(errno));
      mx_free(b);
      close(fd);
      return MX_EINPUT;
    }
    n += (size_t)got;
  }
  close(fd);
  if (!b) return MX_ENOMEM; /* out of memory, already reported */
  if (n == 0 && !allow_empty) {
    mx_error(path, 0, "empty file (0 bytes): not a restart file");
    mx_free(b);
    return MX_EINPUT;
  }
  *buf = b;
  *len = n;
  return MX_OK;
}

/* ---- numbers ------------------------------------------------------------- */

/* Character classes: 1 blank, 2 end of a line's content ('\n', '#'). */
static const uint8_t char_class[256] = {
    [' '] = 1,  ['\t'] = 1, ['\r'] = 1, ['\f'] = 1,
    ['\v'] = 1, ['\n'] = 2, ['#'] = 2};
static inline int is_digit(char c) { return (unsigned)(c - '0') < 10; }
static inline int is_sp(char c) { return char_class[(uint8_t)c] == 1; }
static inline int is_delim(char c) { return char_class[(uint8_t)c] != 0; }
static inline int tok_show(const char *t, const char *e) {
  return e - t < TOK_SHOW ? (int)(e - t) : TOK_SHOW;
}

/* The token [t, e) as an unsigned decimal made of digits only: 1 and *v,
 * 2 if it overflows 64 bits (*v = UINT64_MAX), -1 for '-' and digits only
 * (negative), 0 otherwise (not a number). */
static int parse_uint(const char *t, const char *e, uint64_t *v) {
  const char *q = t + (t < e && *t == '-');
  if (q == e) return 0;
  uint64_t x = 0;
  int over = 0;
  for (const char *c = q; c < e; c++) {
    if (!is_digit(*c)) return 0;
    unsigned d = (unsigned)(*c - '0');
    if (x > (UINT64_MAX - d) / 10) over = 1;
    x = 10 * x + d;
  }
  if (q != t) return -1;
  *v = over ? UINT64_MAX : x;
  return over ? 2 : 1;
}

static const double pow10_exact[23] = {
    1e0,  1e1,  1e2,  1e3,  1e4,  1e5,  1e6,  1e7,  1e8,  1e9,  1e10, 1e11,
    1e12, 1e13, 1e14, 1e15, 1e16, 1e17, 1e18, 1e19, 1e20, 1e21, 1e22};

/* The exact fast path for a decimal number at t (before e): at most 19
 * significant digits, m <= 2^53 and a power of ten up to 22 give one
 * correctly rounded operation. Returns the end of the number, or NULL when
 * there is none or the fast path does not apply. */
static const char *fast_real(const char *t, const char *e, double *v) {
  const char *q = t;
  int neg = 0, nd = 0, e10 = 0, exact = 1;
  uint64_t m = 0;
  if (q < e && (*q == '+' || *q == '-')) neg = *q++ == '-';
  for (; q < e && is_digit(*q); q++, nd++) {
    if (m < 1000000000000000000ull) {
      m = 10 * m + (uint64_t)(*q - '0');
    } else {
      exact &= *q == '0';
      e10++;
    }
  }
  if (q < e && *q == '.') {
    for (q++; q < e && is_digit(*q); q++, nd++) {
      if (m < 1000000000000000000ull) {
        m = 10 * m + (uint64_t)(*q - '0');
        e10--;
      } else {
        exact &= *q == '0';
      }
    }
  }
  if (nd && q < e && (*q == 'e' || *q == 'E')) {
    const char *x = q + 1;
    int sign = 1, ex = 0;
    if (x < e && (*x == '+' || *x == '-')) sign = *x++ == '-' ? -1 : 1;
    const char *digits = x;
    for (; x < e && is_digit(*x); x++)
      if (ex < 100000) ex = 10 * ex + (*x - '0');
    if (x > digits) {
      e10 += sign * ex;
      q = x;
    }
  }
  if (!nd) return NULL;
  if (m == 0) {
    *v = neg ? -0.0 : 0.0;
    return q;
  }
  if (!exact || m > (1ull << 53) || e10 < -22 || e10 > 22) return NULL;
  double x = (double)m;
  x = e10 < 0 ? x / pow10_exact[-e10] : x * pow10_exact[e10];
  *v = neg ? -x : x;
  return q;
}

/* The token [t, e) as a real number: fast_real, else strtod on a copy.
 * Returns 0 if the whole token is not a number (non-finite values are
 * returned: callers check). */
static int parse_real(const char *t, const char *e, double *v) {
  if (fast_real(t, e, v) == e) return 1;
  char small[256], *tmp = small, *end;
  size_t n = (size_t)(e - t);
  if (n == 0) return 0;
  /* a long token ("%f" of 1e300 has 308 characters) goes to the heap */
  if (n >= sizeof small && !(tmp = mx_alloc(n + 1))) return 0;
  memcpy(tmp, t, n);
  tmp[n] = '\0';
  *v = strtod(tmp, &end);
  int ok = end == tmp + n;
  if (tmp != small) mx_free(tmp);
  return ok;
}

/* ---- struct helpers ------------------------------------------------------ */

void mx_restart_free(mx_restart *r) {
  mx_free(r->xyz);
  mx_free(r->edge);
  mx_free(r->oct_node);
  mx_free(r->oct_level);
  mx_free(r->oct_tri_off);
  mx_free(r->oct_tri);
  mx_free(r->nsub);
  mx_free(r->mesh_xyz);
  mx_free(r->mesh_nkey);
  mx_free(r->mesh_state);
  mx_free(r->mesh_type);
  mx_free(r->mesh_conn);
  mx_free(r->mesh_leaf);
  mx_free(r->mesh_jens);
  memset(r, 0, sizeof *r);
}

/* Allocates the fixed-size arrays for nv, ne, no entries (nsub when
 * with_nsub). Returns MX_ENOMEM when out of memory. */
static int alloc_arrays(mx_restart *r, size_t nv, size_t ne, size_t no,
                        int with_nsub) {
  r->xyz = mx_alloc(24 * nv);
  r->edge = mx_alloc(12 * ne);
  r->oct_node = mx_alloc(32 * no);
  r->oct_level = mx_alloc(no);
  r->oct_tri_off = mx_alloc(8 * (no + 1));
  if (with_nsub) r->nsub = mx_alloc(4 * no);
  if (!r->xyz || !r->edge || !r->oct_node || !r->oct_level || !r->oct_tri_off ||
      (with_nsub && !r->nsub))
    return MX_ENOMEM;
  r->oct_tri_off[0] = 0;
  return MX_OK;
}

/* The semantic checks shared by the binary reader and the writers: counts,
 * node indices < nv, levels, finite coordinates, CSR offsets. Reports the
 * first problem as "<what>: ..." and returns status, else MX_OK. */
static int check_restart(const char *name, const mx_restart *r, int status,
                         const char *what) {
#define BAD(...)                              \
  do {                                        \
    char msg_[256];                           \
    snprintf(msg_, sizeof msg_, __VA_ARGS__); \
    mx_error(name, 0, "%s: %s", what, msg_);  \
    return status;                            \
  } while (0)
  if (r->no == 0) BAD("no octants");
  if (r->nv > UINT32_MAX) BAD("%zu nodes: more than 32-bit indices", r->nv);
  if ((!r->xyz && !r->node_rows) || (!r->edge && !r->edge_rows) || (!r->oct_node && !r->oct_rows) ||
      !r->oct_level || !r->oct_tri_off || (r->oct_tri_off[r->no] > 0 && !r->oct_tri))
    BAD("missing arrays");
  /* the big arrays are counted in parallel; a serial pass finds the first
   * fault to report only when there is one */
  size_t bad = 0;
  const size_t nv = r->xyz ? r->nv : 0; /* else generated */
#pragma omp parallel for schedule(static) reduction(+ : bad) if (nv > 65536)
  for (size_t i = 0; i < 3 * nv; i++) bad += !isfinite(r->xyz[i]);
  for (size_t i = 0; bad && i < 3 * nv; i++)
    if (!isfinite(r->xyz[i])) BAD("node %zu: non-finite coordinate", i / 3);
  const size_t ne = r->edge ? r->ne : 0, no = r->oct_node ? r->no : 0; /* else generated */
#pragma omp parallel for schedule(static) reduction(+ : bad) if (ne > 65536)
  for (size_t i = 0; i < 3 * ne; i++) bad += r->edge[i] >= r->nv;
  for (size_t i = 0; bad && i < 3 * ne; i++)
    if (r->edge[i] >= r->nv)
      BAD("edge %zu: node index %u out of range (%zu nodes)", i / 3, r->edge[i],
          r->nv);
  if (r->dim != 0 && r->dim != 2 && r->dim != 3) BAD("dimension %d", r->dim);
  const size_t nc = r->dim == 2 ? 4 : 8;
#pragma omp parallel for schedule(static) reduction(+ : bad) if (no > 65536)
  for (size_t i = 0; i < nc * no; i++) bad += r->oct_node[8 * (i / nc) + i % nc] >= r->nv;
  for (size_t i = 0; bad && i < nc * no; i++)
    if (r->oct_node[8 * (i / nc) + i % nc] >= r->nv)
      BAD("octant %zu: node index %u out of range (%zu nodes)", i / nc,
          r->oct_node[8 * (i / nc) + i % nc], r->nv);
  if (r->oct_tri_off[0] != 0) BAD("face offsets do not start at 0");
  const int maxl = r->dim == 2 ? MX_RESTART_MAX_LEVEL2D : MX_RESTART_MAX_LEVEL;
  for (size_t i = 0; i < r->no; i++) {
    if (r->oct_level[i] > maxl)
      BAD("octant %zu: level %u out of range (0..%d)", i, r->oct_level[i], maxl);
    if (r->oct_tri_off[i + 1] < r->oct_tri_off[i] ||
        r->oct_tri_off[i + 1] - r->oct_tri_off[i] > UINT32_MAX)
      BAD("octant %zu: bad face offsets", i);
  }
  for (int i = 0; r->has_transform && i < 6; i++)
    if (!isfinite(r->transform[i])) BAD("non-finite geometric transform");
  return MX_OK;
#undef BAD
}

/* ---- text scanning ------------------------------------------------------- */

typedef struct {
  const char *name;
  const char *p, *end; /* p: the current position */
  long line;           /* the line of p, from 1 */
  int gap;             /* blank lines came before the current line */
  int first;           /* the current line is a section's first item */
} tscan;

/* Reports "NAME:LINE: <text>" and returns MX_EINPUT. Control characters
 * of quoted tokens (binary junk) are shown as '?'. */
static int terr(const tscan *s, const char *fmt, ...)
    __attribute__((format(printf, 2, 3)));
static int terr(const tscan *s, const char *fmt, ...) {
  char msg[512];
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(msg, sizeof msg, fmt, ap);
  va_end(ap);
  for (char *c = msg; *c; c++)
    if ((unsigned char)*c < 0x20 || *c == 0x7f) *c = '?';
  mx_error(s->name, s->line, "%s", msg);
  return MX_EINPUT;
}

/* Explains a line of the wrong shape, when a wrong count in the header or
 * a cut file would explain it. */
static const char *hint(const tscan *s) {
  if (!memchr(s->p, '\n', (size_t)(s->end - s->p)))
    return " (the file ends on this line: truncated?)";
  if (s->gap || s->first) return " (do the header's counts match the file?)";
  return "";
}

static inline void skip_sp(tscan *s) {
  while (s->p < s->end && is_sp(*s->p)) s->p++;
}

/* At the end of the current line's content (newline, comment, end). */
static inline int at_eol(tscan *s) {
  skip_sp(s);
  return s->p == s->end || *s->p == '\n' || *s->p == '#';
}

/* Moves to the first character of the next line with content, skipping the
 * rest of the current line, blank lines and comment lines; 0 at the end. */
static int next_line(tscan *s) {
  s->gap = 0;
  for (;;) {
    const char *nl = memchr(s->p, '\n', (size_t)(s->end - s->p));
    if (!nl) {
      s->p = s->end;
      return 0;
    }
    s->p = nl + 1;
    s->line++;
    skip_sp(s);
    if (s->p < s->end && *s->p != '\n' && *s->p != '#') return 1;
    if (s->p < s->end && *s->p == '\n') s->gap = 1;
  }
}

/* The next token of the current line ([returned, *e)), or NULL at its end;
 * s->p is left at the token. */
static inline const char *next_tok(tscan *s, const char **e) {
  *e = s->p;
  if (at_eol(s)) return NULL;
  const char *q = s->p;
  while (q < s->end && !is_delim(*q)) q++;
  *e = q;
  return s->p;
}

/* One unsigned integer <= max on the current line; messages name
 * "<what> <item>: <field>". */
static int get_uint(tscan *s, uint64_t max, uint64_t *v, const char *what,
                    size_t item, const char *field) {
  skip_sp(s);
  const char *q = s->p, *lim = s->end - q > 18 ? q + 18 : s->end;
  uint64_t x = 0;
  for (; q < lim && is_digit(*q); q++) x = 10 * x + (uint64_t)(*q - '0');
  if (q > s->p && x <= max && (q == s->end || is_delim(*q))) {
    *v = x; /* the common case: at most 18 digits, in range */
    s->p = q;
    return MX_OK;
  }
  const char *e, *t = next_tok(s, &e);
  if (!t) return terr(s, "%s %zu: missing %s%s", what, item, field, hint(s));
  int k = parse_uint(t, e, v);
  if (k < 0)
    return terr(s, "%s %zu: %s '%.*s' is negative", what, item, field,
                tok_show(t, e), t);
  if (k == 0)
    return terr(s, "%s %zu: %s '%.*s' is not an integer%s", what, item, field,
                tok_show(t, e), t, hint(s));
  if (*v > max)
    return terr(s, "%s %zu: %s %.*s out of range (at most %llu)", what, item,
                field, tok_show(t, e), t, (unsigned long long)max);
  s->p = e;
  return MX_OK;
}

/* One node index < nv. */
static int get_node(tscan *s, size_t nv, uint32_t *v, const char *what,
                    size_t item) {
  skip_sp(s);
  const char *t = s->p;
  uint64_t x;
  MX_CHECK(get_uint(s, UINT64_MAX, &x, what, item, "node index"));
  if (x >= nv)
    return terr(s, "%s %zu: node index %.*s out of range (%zu nodes, 0-based)",
                what, item, tok_show(t, s->p), t, nv);
  *v = (uint32_t)x;
  return MX_OK;
}

/* n finite reals on the current line, nothing after them. */
static int get_reals(tscan *s, int n, double *v, const char *what,
                     size_t item) {
  for (int k = 0; k < n; k++) {
    skip_sp(s);
    const char *q = fast_real(s->p, s->end, &v[k]);
    if (q && (q == s->end || is_delim(*q))) {
      s->p = q; /* the common case (finite by construction) */
      continue;
    }
    const char *e, *t = next_tok(s, &e);
    if (!t)
      return terr(s, "%s %zu: expected %d numbers, found %d%s", what, item, n,
                  k, hint(s));
    if (!parse_real(t, e, &v[k]))
      return terr(s, "%s %zu: '%.*s' is not a number%s", what, item,
                  tok_show(t, e), t, hint(s));
    if (!isfinite(v[k]))
      return terr(s, "%s %zu: '%.*s' is not a finite number", what, item,
                  tok_show(t, e), t);
    s->p = e;
  }
  if (!at_eol(s))
    return terr(s, "%s %zu: more than %d numbers%s", what, item, n, hint(s));
  return MX_OK;
}

/* "truncated: expected N <what>, found K" at the current line. */
static int truncated(const tscan *s, const char *what, size_t n, size_t k) {
  return terr(s, "truncated: expected %zu %s, found %zu", n, what, k);
}

/* How many items of min_bytes each (plus a separator) the rest of the file
 * could hold at most: arrays are never sized beyond that. */
static size_t fits(const tscan *s, size_t n, size_t min_bytes) {
  size_t most = ((size_t)(s->end - s->p) + 1) / min_bytes + 1;
  return n < most ? n : most;
}

/* ---- text reading -------------------------------------------------------- */

/* The header line "nodes edges octants", checked. */
static int text_header(tscan *s, mx_restart *r) {
  static const char *names[3] = {"nodes", "edges", "octants"};
  uint64_t c[3];
  for (int k = 0; k < 3; k++) {
    const char *e, *t = next_tok(s, &e);
    if (!t)
      return terr(s,
                  "bad header: expected 'nodes edges octants', missing "
                  "the number of %s",
                  names[k]);
    int ok = parse_uint(t, e, &c[k]);
    if (ok < 0)
      return terr(s, "bad header: the number of %s is negative (%.*s)",
                  names[k], tok_show(t, e), t);
    if (ok != 1 || c[k] > ((uint64_t)1 << 40))
      return terr(s,
                  "bad header: expected 'nodes edges octants', found "
                  "'%.*s' for the number of %s%s",
                  tok_show(t, e), t, names[k],
                  ok == 1 || ok == 2 ? " (too large)" : "");
    s->p = e;
  }
  if (!at_eol(s))
    return terr(s,
                "bad header: more than the 3 numbers 'nodes edges "
                "octants'");
  if (c[0] > UINT32_MAX)
    return terr(s, "%llu nodes: more than 32-bit indices allow",
                (unsigned long long)c[0]);
  if (c[2] == 0) return terr(s, "the header declares no octants");
  r->nv = (size_t)c[0];
  r->ne = (size_t)c[1];
  r->no = (size_t)c[2];
  return MX_OK;
}

/* The number of words on the current line. */
static int count_words_line(tscan s) {
  int n = 0;
  for (const char *e; next_tok(&s, &e); s.p = e) n++;
  return n;
}

/* nv lines "x y z" of finite numbers. */
static int text_nodes(tscan *s, mx_restart *r) {
  size_t cap = fits(s, r->nv, r->dim == 2 ? 4 : 6); /* "0 0 0\n", "0 0\n" */
  for (size_t i = 0; i < r->nv; i++) {
    if (i == cap || !next_line(s)) return truncated(s, "nodes", r->nv, i);
    s->first = i == 0;
    if (r->dim == 2) {
      if (i == 0 && count_words_line(*s) == 3)
        return terr(s,
                    "node 0: 3 coordinates: an octree restart file; "
                    "mesher2d remeshes quadtrees only (use mixoct -c)");
      MX_CHECK(get_reals(s, 2, r->xyz + 3 * i, "node", i));
      r->xyz[3 * i + 2] = 0.0;
      continue;
    }
    if (i == 0 && count_words_line(*s) == 2)
      return terr(s,
                  "node 0: 2 coordinates: a quadtree restart file; "
                  "mixoct remeshes octrees only");
    MX_CHECK(get_reals(s, 3, r->xyz + 3 * i, "node", i));
  }
  return MX_OK;
}

/* ne lines "a b mid" of node indices. */
static int text_edges(tscan *s, mx_restart *r) {
  size_t cap = fits(s, r->ne, 6); /* "0 0 0\n" */
  for (size_t i = 0; i < r->ne; i++) {
    if (i == cap || !next_line(s)) return truncated(s, "edges", r->ne, i);
    s->first = i == 0;
    for (int k = 0; k < 3; k++)
      MX_CHECK(get_node(s, r->nv, &r->edge[3 * i + k], "edge", i));
    if (!at_eol(s))
      return terr(s, "edge %zu: more than 3 numbers ('a b mid')%s", i, hint(s));
  }
  return MX_OK;
}

/* Makes room for n more face indices. */
static int grow_tri(tscan *s, mx_restart *r, size_t used, size_t n,
                    size_t *cap) {
  if (used + n <= *cap) return MX_OK;
  size_t want = 2 * *cap > used + n ? 2 * *cap : used + n;
  uint32_t *t = mx_realloc(r->oct_tri, 4 * want);
  if (!t) return terr(s, "out of memory");
  r->oct_tri = t;
  *cap = want;
  return MX_OK;
}

/* Quadrant i of a quadtree file: "4 n0 n1 n2 n3 level" (the count read). */
static int text_quadrant(tscan *s, mx_restart *r, size_t i, uint64_t k) {
  if (k == 8)
    return terr(s, "quadrant %zu: 8 corner nodes: an octree restart file; "
                   "mesher2d remeshes quadtrees only (use mixoct -c)", i);
  if (k != 4)
    return terr(s, "quadrant %zu: %llu corner nodes, a quadrant has 4%s", i,
                (unsigned long long)k, hint(s));
  for (int j = 0; j < 4; j++)
    MX_CHECK(get_node(s, r->nv, &r->oct_node[8 * i + j], "quadrant", i));
  for (int j = 4; j < 8; j++) r->oct_node[8 * i + j] = 0;
  MX_CHECK(get_uint(s, MX_RESTART_MAX_LEVEL2D, &k, "quadrant", i, "level"));
  r->oct_level[i] = (uint8_t)k;
  if (!at_eol(s))
    return terr(s, "quadrant %zu: more than '4 n0 .. n3 level'%s", i, hint(s));
  return MX_OK;
}

/* Octant i: "8 n0 .. n7 level", then "k f0 .. fk-1". */
static int text_octant(tscan *s, mx_restart *r, size_t i, size_t *tcap) {
  const char *e, *t;
  uint64_t k;
  if (!next_line(s)) return truncated(s, "octants", r->no, i);
  s->first = i == 0;
  t = next_tok(s, &e);
  int ok = parse_uint(t, e, &k);
  if (ok != 1) {
    if (e - t == 9 && strncasecmp(t, "Geometric", 9) == 0)
      return truncated(s, "octants", r->no, i);
    return terr(s, "octant %zu: expected '8 n0 .. n7 level', found '%.*s'%s", i,
                tok_show(t, e), t, hint(s));
  }
  if (r->dim == 2) {
    s->p = e;
    MX_CHECK(text_quadrant(s, r, i, k));
  } else if (k == 4)
    return terr(s,
                "octant %zu: 4 corner nodes: a quadtree restart file; "
                "mixoct remeshes octrees only",
                i);
  else if (k != 8)
    return terr(s, "octant %zu: %llu corner nodes, an octant has 8%s", i,
                (unsigned long long)k, hint(s));
  if (r->dim != 2) {
    s->p = e;
    for (int j = 0; j < 8; j++)
      MX_CHECK(get_node(s, r->nv, &r->oct_node[8 * i + j], "octant", i));
    MX_CHECK(get_uint(s, MX_RESTART_MAX_LEVEL, &k, "octant", i, "level"));
    r->oct_level[i] = (uint8_t)k;
    if (!at_eol(s))
      return terr(s, "octant %zu: more than '8 n0 .. n7 level'%s", i, hint(s));
  }
  s->first = 0;
  if (!next_line(s))
    return terr(s,
                "truncated: expected %zu octants, found %zu (the last "
                "one has no line of intersected faces)",
                r->no, i);
  MX_CHECK(get_uint(s, UINT32_MAX, &k, "octant", i, "face count"));
  size_t used = r->oct_tri_off[i];
  if (k > (size_t)(s->end - s->p) / 2)
    return terr(s,
                "octant %zu: %llu intersected faces announced, the file "
                "is too short to list them%s",
                i, (unsigned long long)k, hint(s));
  MX_CHECK(grow_tri(s, r, used, (size_t)k, tcap));
  for (uint64_t j = 0; j < k; j++) {
    uint64_t f;
    if (!next_tok(s, &e))
      return terr(s,
                  "octant %zu: %llu intersected faces announced, %llu "
                  "listed%s",
                  i, (unsigned long long)k, (unsigned long long)j, hint(s));
    MX_CHECK(get_uint(s, UINT32_MAX, &f, "octant", i, "face index"));
    r->oct_tri[used + j] = (uint32_t)f;
  }
  if (!at_eol(s))
    return terr(s,
                "octant %zu: more intersected faces listed than the %llu "
                "announced%s",
                i, (unsigned long long)k, hint(s));
  r->oct_tri_off[i + 1] = used + k;
  return MX_OK;
}

/* no octants of two lines each; oct_tri grows as the face lists come. */
static int text_octants(tscan *s, mx_restart *r) {
  /* "8 0 0 0 0 0 0 0 0 0\n0\n", "4 0 0 0 0 0\n0\n" */
  size_t cap = fits(s, r->no, r->dim == 2 ? 14 : 22);
  size_t tcap = 4 * cap + 16;
  if (tcap > (size_t)(s->end - s->p) / 2 + 16)
    tcap = (size_t)(s->end - s->p) / 2 + 16;
  r->oct_tri = mx_alloc(4 * tcap);
  if (!r->oct_tri) return terr(s, "out of memory");
  for (size_t i = 0; i < r->no; i++) {
    if (i == cap) return truncated(s, "octants", r->no, i);
    MX_CHECK(text_octant(s, r, i, &tcap));
  }
  return MX_OK;
}

/* Counts the words from s to the end; *ints: the first six are all plain
 * integers. */
static size_t count_words(tscan s, int *ints) {
  size_t n = 0;
  *ints = 1;
  do {
    const char *e, *t;
    while ((t = next_tok(&s, &e))) {
      uint64_t v;
      if (n < 6 && parse_uint(t, e, &v) != 1) *ints = 0;
      n++;
      s.p = e;
    }
  } while (next_line(&s));
  return n;
}

/* "Geometric Transform" and its two lines, then the sub-element counts,
 * each optional; then nothing but blanks and comments. At entry s is at the
 * end of the last octant's line. */
static int text_tail(tscan *s, mx_restart *r) {
  s->first = 0;
  if (!next_line(s)) return MX_OK;
  const char *e, *t = next_tok(s, &e);
  int transform, at_content = 1;
  if (e - t == 9 && strncasecmp(t, "Geometric", 9) == 0) {
    s->p = e;
    t = next_tok(s, &e);
    if (!t || e - t != 9 || strncasecmp(t, "Transform", 9) != 0)
      return terr(s, "expected the title 'Geometric Transform'");
    s->p = e;
    if (!at_eol(s))
      return terr(s, "unexpected text after 'Geometric Transform'");
    transform = 1;
    at_content = 0;
  } else {
    int ints;
    size_t n = count_words(*s, &ints);
    transform = n == r->no + 6 || (n == 6 && !(r->no == 6 && ints));
    if (!transform && n != r->no)
      return terr(s,
                  "after the %zu octants: expected the geometric "
                  "transform (6 numbers) and/or the %zu octant "
                  "sub-element counts, found %zu words%s",
                  r->no, r->no, n,
                  n > r->no ? " (more octants than the header declares?)" : "");
  }
  if (transform) {
    for (int k = 0; k < 2; k++) {
      if (!at_content && !next_line(s))
        return terr(s,
                    "truncated: the geometric transform needs 2 lines of "
                    "3 numbers, found %d",
                    k);
      at_content = 0;
      MX_CHECK(get_reals(s, 3, r->transform + 3 * k, "geometric transform line",
                         (size_t)k + 1));
    }
    r->has_transform = 1;
  }
  if (!at_content && !next_line(s)) return MX_OK;
  r->nsub = mx_alloc(4 * r->no);
  if (!r->nsub) return terr(s, "out of memory");
  for (size_t i = 0; i < r->no; i++) {
    uint64_t v;
    while (!next_tok(s, &e))
      if (!next_line(s))
        return terr(s,
                    "octant sub-elements: expected %zu counts (one per "
                    "octant), found %zu",
                    r->no, i);
    MX_CHECK(get_uint(s, UINT32_MAX, &v, "octant", i, "sub-element count"));
    r->nsub[i] = (uint32_t)v;
  }
  if ((t = next_tok(s, &e)) || (next_line(s) && (t = next_tok(s, &e))))
    return terr(s, "unexpected data after the last section: '%.*s'",
                tok_show(t, e), t);
  return MX_OK;
}

/* The text format: the sections in order, arrays sized by fits(). */
static int text_parse(const char *name, const char *buf, size_t len,
                      mx_restart *r) {
  tscan s = {name, buf, buf + len, 1, 0, 0};
  skip_sp(&s);
  if (s.p < s.end && (*s.p == '\n' || *s.p == '#')) next_line(&s);
  if (s.p == s.end)
    return terr(&s, "no content: expected the header 'nodes edges octants'");
  MX_CHECK(text_header(&s, r));
  size_t nv = fits(&s, r->nv, r->dim == 2 ? 4 : 6), ne = fits(&s, r->ne, 6);
  if (alloc_arrays(r, nv, ne, fits(&s, r->no, r->dim == 2 ? 14 : 22), 0) != MX_OK)
    return terr(&s, "out of memory");
  MX_CHECK(text_nodes(&s, r));
  MX_CHECK(text_edges(&s, r));
  MX_CHECK(text_octants(&s, r));
  return text_tail(&s, r);
}

/* ---- checksum ------------------------------------------------------------ */

/* Four lanes over the 8-byte words (word i goes to lane i % 4); each step
 * h = xorshift((h ^ w) * odd) is a bijection of h for a fixed w and of w for
 * a fixed h, so a change confined to one word always changes its lane, and
 * the final combination, also made of such steps, changes with it. */
typedef struct {
  uint64_t lane[4];
  uint64_t nwords;
} rs_hash;

static inline uint64_t hash_step(uint64_t h, uint64_t w) {
  h = (h ^ w) * 0xff51afd7ed558ccdull;
  return h ^ (h >> 32);
}

/* Distinct starting values of the lanes. */
static void hash_init(rs_hash *h) {
  for (int l = 0; l < 4; l++) h->lane[l] = 0x9E3779B97F4A7C15ull * (l + 1);
  h->nwords = 0;
}

/* Adds n words at p (any alignment), four lanes a step. */
static void hash_words(rs_hash *h, const uint8_t *p, size_t n) {
  size_t i = 0;
  uint64_t w;
  for (; i < n && (h->nwords & 3); i++, h->nwords++) {
    memcpy(&w, p + 8 * i, 8);
    h->lane[h->nwords & 3] = hash_step(h->lane[h->nwords & 3], w);
  }
  uint64_t l0 = h->lane[0], l1 = h->lane[1], l2 = h->lane[2], l3 = h->lane[3];
  for (; i + 4 <= n; i += 4) {
    uint64_t w4[4];
    memcpy(w4, p + 8 * i, 32);
    l0 = hash_step(l0, w4[0]);
    l1 = hash_step(l1, w4[1]);
    l2 = hash_step(l2, w4[2]);
    l3 = hash_step(l3, w4[3]);
    h->nwords += 4;
  }
  h->lane[0] = l0, h->lane[1] = l1, h->lane[2] = l2, h->lane[3] = l3;
  for (; i < n; i++, h->nwords++) {
    memcpy(&w, p + 8 * i, 8);
    h->lane[h->nwords & 3] = hash_step(h->lane[h->nwords & 3], w);
  }
}

/* The word count and the four lanes, combined. */
static uint64_t hash_final(const rs_hash *h) {
  uint64_t x = hash_step(0x243F6A8885A308D3ull, h->nwords);
  for (int l = 0; l < 4; l++) x = hash_step(x, h->lane[l]);
  return x;
}

/* ---- binary reading ------------------------------------------------------ */

static inline uint64_t rd64(const uint8_t *p) {
  uint64_t v;
  memcpy(&v, p, 8);
  return v;
}
static inline uint32_t rd32(const uint8_t *p) {
  uint32_t v;
  memcpy(&v, p, 4);
  return v;
}

/* *total += n * size rounded up to 8; returns 0 on overflow. */
static int add_section(uint64_t *total, uint64_t n, uint64_t size) {
  uint64_t b;
  if (__builtin_mul_overflow(n, size, &b) || b > UINT64_MAX - 7) return 0;
  return !__builtin_add_overflow(*total, (b + 7) & ~(uint64_t)7, total);
}

/* Copies n * size bytes at *p to dst and steps over the section. */
static void take(void *dst, const uint8_t **p, size_t n, size_t size) {
  if (n) memcpy(dst, *p, n * size);
  *p += (n * size + 7) & ~(size_t)7;
}

/* The mesh section against the octants: node ids in range, types known,
 * states 0 or 1, finite coordinates, elements grouped by octant as nsub
 * says. */
static int check_mesh(const char *name, const mx_restart *r, int status, const char *what) {
  static const int corners[4] = {4, 5, 6, 8}; /* nodes per element type */
  if (!r->has_mesh) return MX_OK;
  const char *bad = NULL;
  size_t at = 0;
  if (!r->nsub) bad = "a mesh without elements per octant";
  for (size_t v = 0; !bad && v < r->mesh_nn; v++) {
    at = v;
    if (r->mesh_state[v] > 1) bad = "a node state that is neither 0 nor 1";
    for (int a = 0; a < 3 && !bad; a++)
      if (!isfinite(r->mesh_xyz[3 * v + a])) bad = "a node coordinate that is not finite";
  }
  uint64_t c = 0;
  for (size_t i = 0; !bad && i < r->no; i++)
    for (uint32_t k = 0; !bad && k < r->nsub[i]; k++, c++) {
      at = (size_t)c;
      if (c >= r->mesh_nc) {
        bad = "more elements per octant than mesh elements";
        break;
      }
      if (r->mesh_leaf[c] != i) bad = "an element in another octant than nsub says";
      else if (r->mesh_type[c] > 3) bad = "an unknown element type";
      for (int j = 0; !bad && j < 8; j++) {
        const uint32_t v = r->mesh_conn[8 * c + (size_t)j];
        if (j < corners[r->mesh_type[c]] ? v >= r->mesh_nn : v != UINT32_MAX)
          bad = "an element node out of range";
      }
      if (!bad && !(r->mesh_jens[c] == r->mesh_jens[c])) bad = "an element quality that is NaN";
    }
  if (!bad && c != r->mesh_nc) bad = "fewer elements per octant than mesh elements";
  if (!bad) return MX_OK;
  mx_error(name, 0, "%s: %s (item %zu of the mesh section)", what, bad, at);
  return status;
}

/* The binary variant: magic, version, flags, the sizes against the length
 * (before any allocation), the checksum, then the arrays and their
 * semantic checks. */
static int bin_parse(const char *name, const uint8_t *b, size_t len,
                     mx_restart *r) {
  if (memcmp(b, bin_magic, len < 8 ? len : 8) != 0) {
    mx_error(name, 0, "not a mixoct binary restart file (bad magic bytes)");
    return MX_EINPUT;
  }
  if (len < BIN_HEADER) {
    mx_error(name, 0, "truncated: the header needs %d bytes, file has %zu",
             BIN_HEADER, len);
    return MX_EINPUT;
  }
  uint32_t version = rd32(b + 8), flags = rd32(b + 12);
  if (version != BIN_VERSION) {
    mx_error(name, 0, "version %u, this mixoct reads version %d", version,
             BIN_VERSION);
    return MX_EINPUT;
  }
  if (flags & ~(uint32_t)(BIN_TRANSFORM | BIN_NSUB | BIN_MESH | BIN_BYTYPE | BIN_MATERIALS)) {
    mx_error(name, 0, "corrupted: unknown flags 0x%x", flags);
    return MX_EINPUT;
  }
  const int with_mesh = (flags & BIN_MESH) != 0;
  if (with_mesh && len < BIN_HEADER + 16) {
    mx_error(name, 0, "truncated: the header needs %d bytes, file has %zu", BIN_HEADER + 16,
             len);
    return MX_EINPUT;
  }
  if (with_mesh && !(flags & BIN_NSUB)) {
    mx_error(name, 0, "corrupted: a mesh section without elements per octant");
    return MX_EINPUT;
  }
  uint64_t nv = rd64(b + 16), ne = rd64(b + 24), no = rd64(b + 32),
           ntri = rd64(b + 40), need = BIN_HEADER + 8 + (with_mesh ? 16 : 0);
  const uint64_t mnn = with_mesh ? rd64(b + 48) : 0, mnc = with_mesh ? rd64(b + 56) : 0;
  int ok = add_section(&need, nv, 24) && add_section(&need, ne, 12) &&
           add_section(&need, no, 32) && add_section(&need, no, 1) &&
           add_section(&need, no, 4) && add_section(&need, ntri, 4) &&
           add_section(&need, flags & BIN_TRANSFORM ? 6 : 0, 8) &&
           add_section(&need, flags & BIN_NSUB ? no : 0, 4) && add_section(&need, mnn, 24) &&
           add_section(&need, mnn, 8) && add_section(&need, mnn, 1) &&
           add_section(&need, mnc, 1) && add_section(&need, mnc, 32) &&
           add_section(&need, mnc, 4) && add_section(&need, mnc, 8) && mnn < UINT32_MAX;
  if (!ok || need > len) {
    mx_error(name, 0,
             "truncated: the header declares %llu nodes, %llu "
             "edges, %llu octants, %llu faces: expected %s%llu bytes, file "
             "has %zu",
             (unsigned long long)nv, (unsigned long long)ne,
             (unsigned long long)no, (unsigned long long)ntri,
             ok ? "" : "more than ", (unsigned long long)need, len);
    return MX_EINPUT;
  }
  if (need < len) {
    mx_error(name, 0,
             "corrupted: expected %llu bytes, file has %zu (data "
             "after the end)",
             (unsigned long long)need, len);
    return MX_EINPUT;
  }
  rs_hash h;
  hash_init(&h);
  hash_words(&h, b, (len - 8) / 8);
  if (hash_final(&h) != rd64(b + len - 8)) {
    mx_error(name, 0, "corrupted: checksum mismatch");
    return MX_EINPUT;
  }
  r->nv = (size_t)nv, r->ne = (size_t)ne, r->no = (size_t)no;
  r->has_transform = (flags & BIN_TRANSFORM) != 0;
  r->by_type = (flags & BIN_BYTYPE) != 0;
  r->materials = (flags & BIN_MATERIALS) != 0;
  uint32_t *count = mx_alloc(4 * no);
  int st = count ? alloc_arrays(r, r->nv, r->ne, r->no, flags & BIN_NSUB)
                 : MX_ENOMEM;
  if (st == MX_OK) r->oct_tri = mx_alloc(4 * ntri);
  if (st != MX_OK || !r->oct_tri) {
    mx_free(count);
    return MX_ENOMEM;
  }
  const uint8_t *p = b + BIN_HEADER + (with_mesh ? 16 : 0);
  take(r->xyz, &p, 3 * nv, 8);
  take(r->edge, &p, 3 * ne, 4);
  take(r->oct_node, &p, 8 * no, 4);
  take(r->oct_level, &p, no, 1);
  take(count, &p, no, 4);
  take(r->oct_tri, &p, ntri, 4);
  if (r->has_transform) take(r->transform, &p, 6, 8);
  if (r->nsub) take(r->nsub, &p, no, 4);
  if (with_mesh) {
    r->has_mesh = 1;
    r->mesh_nn = (size_t)mnn;
    r->mesh_nc = (size_t)mnc;
    r->mesh_xyz = mx_alloc(24 * mnn + 8);
    r->mesh_nkey = mx_alloc(8 * mnn + 8);
    r->mesh_state = mx_alloc(mnn + 8);
    r->mesh_type = mx_alloc(mnc + 8);
    r->mesh_conn = mx_alloc(32 * mnc + 8);
    r->mesh_leaf = mx_alloc(4 * mnc + 8);
    r->mesh_jens = mx_alloc(8 * mnc + 8);
    if (!r->mesh_xyz || !r->mesh_nkey || !r->mesh_state || !r->mesh_type || !r->mesh_conn ||
        !r->mesh_leaf || !r->mesh_jens) {
      mx_free(count);
      return MX_ENOMEM;
    }
    take(r->mesh_xyz, &p, 3 * mnn, 8);
    take(r->mesh_nkey, &p, mnn, 8);
    take(r->mesh_state, &p, mnn, 1);
    take(r->mesh_type, &p, mnc, 1);
    take(r->mesh_conn, &p, 8 * mnc, 4);
    take(r->mesh_leaf, &p, mnc, 4);
    take(r->mesh_jens, &p, mnc, 8);
  }
  size_t i = 0;
  for (; i < no && r->oct_tri_off[i] <= ntri; i++)
    r->oct_tri_off[i + 1] = r->oct_tri_off[i] + count[i];
  mx_free(count);
  if (i < no || r->oct_tri_off[no] != ntri) {
    mx_error(name, 0,
             "corrupted: the octants' face counts do not add up to "
             "the %llu of the header",
             (unsigned long long)ntri);
    return MX_EINPUT;
  }
  MX_CHECK(check_restart(name, r, MX_EINPUT, "corrupted"));
  return check_mesh(name, r, MX_EINPUT, "corrupted");
}

/* ---- reading: entry points ----------------------------------------------- */

/* Whether one of the last lines of the text starts with mark (the writer
 * puts MX_RESTART_BY_TYPE and MX_RESTART_MATERIALS last). */
static int text_mark(const char *buf, size_t len, const char *mark) {
  const size_t k = strlen(mark), tail = 4 * (sizeof MX_RESTART_BY_TYPE + sizeof MX_RESTART_MATERIALS);
  for (size_t i = len > tail ? len - tail : 0; i + k <= len; i++)
    if ((i == 0 || buf[i - 1] == '\n') && buf[i] == '#' && memcmp(buf + i, mark, k) == 0)
      return 1;
  return 0;
}

int mx_restart_parse(const char *name, const uint8_t *buf, size_t len,
                     mx_restart *r) {
  return mx_restart_parse_dim(name, buf, len, 3, r);
}

int mx_restart_parse_dim(const char *name, const uint8_t *buf, size_t len, int dim,
                     mx_restart *r) {
  memset(r, 0, sizeof *r);
  int st;
  if (len == 0) {
    mx_error(name, 0, "empty file (0 bytes): not a restart file");
    return MX_EINPUT;
  }
  if (dim == 2 && buf[0] == bin_magic[0]) {
    mx_error(name, 0, "a binary restart file: those are octree files (mixoct -c); "
                      "mesher2d reads the text quadtree form");
    return MX_EINPUT;
  }
  r->dim = dim == 2 ? 2 : 3;
  if (buf[0] == bin_magic[0])
    st = bin_parse(name, buf, len, r);
  else
    st = text_parse(name, (const char *)buf, len, r);
  if (st == MX_OK && buf[0] != bin_magic[0]) {
    r->by_type = text_mark((const char *)buf, len, MX_RESTART_BY_TYPE);
    r->materials = text_mark((const char *)buf, len, MX_RESTART_MATERIALS);
  }
  if (st != MX_OK) mx_restart_free(r);
  return st;
}

/* Loads the file and parses it from memory. */
int mx_restart_read(const char *path, mx_restart *r) { return mx_restart_read_dim(path, 3, r); }

int mx_restart_read_dim(const char *path, int dim, mx_restart *r) {
  memset(r, 0, sizeof *r);
  uint8_t *buf;
  size_t len;
  MX_CHECK(load_file(path, 0, &buf, &len));
  int st = mx_restart_parse_dim(path, buf, len, dim, r);
  mx_free(buf);
  return st;
}

#define BAD_DATA "internal error: bad restart data"

/* ---- text writing -------------------------------------------------------- */

/* Node coordinates are lattice values, each met on many nodes (a few
 * thousand distinct values per axis for millions of nodes): a small
 * direct-mapped memo of formatted values, keyed by the exact bits, makes
 * most of them a 16-byte copy. */
enum { E8_MEMO = 1024 };
typedef struct {
  uint64_t bits;
  char text[MX_E8_CHARS];
  uint32_t len; /* 0: empty */
} e8_memo;

/* x as mx_put_e8 writes it; may write up to MX_E8_CHARS bytes at out
 * whatever the length returned. */
static inline size_t put_e8_memo(char *out, double x, e8_memo *memo) {
  uint64_t bits;
  memcpy(&bits, &x, sizeof bits);
  e8_memo *m = &memo[(bits * 0x9E3779B97F4A7C15ULL) >> 54];
  if (m->len == 0 || m->bits != bits) {
    m->bits = bits;
    m->len = (uint32_t)mx_put_e8(m->text, x);
  }
  memcpy(out, m->text, MX_E8_CHARS);
  return m->len;
}

/* Fill functions of mx_afile_emit (items [b, e) of one section, in the
 * published layout; see the max_item_bytes given in text_body). */
enum { GEN_BLOCK = 256 }; /* rows made at a time by a generator */

static size_t fill_nodes(const void *ctx, size_t b, size_t e, char *out) {
  const mx_restart *r = ctx;
  const int nd = r->dim == 2 ? 2 : 3;
  e8_memo memo[E8_MEMO];
  for (int k = 0; k < E8_MEMO; k++) memo[k].len = 0;
  double made[3 * GEN_BLOCK];
  char *o = out;
  for (size_t i0 = b; i0 < e; i0 += GEN_BLOCK) {
    const size_t i1 = e - i0 < GEN_BLOCK ? e : i0 + GEN_BLOCK;
    const double *xyz = r->xyz ? r->xyz + 3 * i0 : made;
    if (!r->xyz) r->node_rows(r->gen, i0, i1, made);
    for (size_t i = 0; i < i1 - i0; i++) {
      for (int d = 0; d < nd; d++) {
        o += put_e8_memo(o, xyz[3 * i + d], memo);
        memcpy(o, d + 1 < nd ? "  " : "\n", d + 1 < nd ? 2 : 1);
        o += d + 1 < nd ? 2 : 1;
      }
    }
  }
  return (size_t)(o - out);
}

static size_t fill_edges(const void *ctx, size_t b, size_t e, char *out) {
  const mx_restart *r = ctx;
  uint32_t rows[3 * GEN_BLOCK];
  char *o = out;
  for (size_t i0 = b; i0 < e; i0 += GEN_BLOCK) {
    const size_t i1 = e - i0 < GEN_BLOCK ? e : i0 + GEN_BLOCK;
    const uint32_t *ed = r->edge ? r->edge + 3 * i0 : rows;
    if (!r->edge) r->edge_rows(r->gen, i0, i1, rows);
    for (size_t i = 0; i < 3 * (i1 - i0); i += 3) {
      o += mx_put_u64(o, ed[i]);
      *o++ = ' ';
      o += mx_put_u64(o, ed[i + 1]);
      *o++ = ' ';
      o += mx_put_u64(o, ed[i + 2]);
      *o++ = '\n';
    }
  }
  return (size_t)(o - out);
}

static size_t fill_octants(const void *ctx, size_t b, size_t e, char *out) {
  const mx_restart *r = ctx;
  uint32_t rows[8 * GEN_BLOCK];
  char *o = out;
  const int nc = r->dim == 2 ? 4 : 8;
  for (size_t i0 = b; i0 < e; i0 += GEN_BLOCK) {
    const size_t i1 = e - i0 < GEN_BLOCK ? e : i0 + GEN_BLOCK;
    const uint32_t *on = r->oct_node ? r->oct_node + 8 * i0 : rows;
    if (!r->oct_node) r->oct_rows(r->gen, i0, i1, rows);
    for (size_t i = i0; i < i1; i++, on += 8) {
      *o++ = (char)('0' + nc);
      for (int k = 0; k < nc; k++) {
        *o++ = ' ';
        o += mx_put_u64(o, on[k]);
      }
      *o++ = ' ';
      o += mx_put_u64(o, r->oct_level[i]);
      *o++ = '\n';
      o += mx_put_u64(o, r->oct_tri_off[i + 1] - r->oct_tri_off[i]);
      for (uint64_t j = r->oct_tri_off[i]; j < r->oct_tri_off[i + 1]; j++) {
        *o++ = ' ';
        o += mx_put_u64(o, r->oct_tri[j]);
      }
      *o++ = '\n';
    }
  }
  return (size_t)(o - out);
}

static size_t fill_nsub(const void *ctx, size_t b, size_t e, char *out) {
  const uint32_t *ns = ((const mx_restart *)ctx)->nsub;
  char *o = out;
  for (size_t i = b; i < e; i++) {
    o += mx_put_u64(o, ns[i]);
    *o++ = ' ';
  }
  return (size_t)(o - out);
}

/* The whole text file, section by section. */
static int text_body(mx_afile *f, const mx_restart *r) {
  uint64_t maxk = 0;
  for (size_t i = 0; i < r->no; i++)
    if (r->oct_tri_off[i + 1] - r->oct_tri_off[i] > maxk)
      maxk = r->oct_tri_off[i + 1] - r->oct_tri_off[i];
  MX_CHECK(mx_afile_printf(f, "%zu %zu %zu\n\n", r->nv, r->ne, r->no));
  MX_CHECK(mx_afile_emit(f, r->nv, 3 * MX_E8_CHARS + 5, fill_nodes, r));
  MX_CHECK(mx_afile_write(f, "\n", 1));
  MX_CHECK(mx_afile_emit(f, r->ne, 3 * 11, fill_edges, r));
  MX_CHECK(mx_afile_write(f, "\n", 1));
  MX_CHECK(mx_afile_emit(f, r->no, 9 * 11 + 4 + 11 * ((size_t)maxk + 1),
                         fill_octants, r));
  if (r->has_transform) {
    const double *t = r->transform;
    MX_CHECK(mx_afile_printf(f, "\nGeometric Transform\n%f %f %f\n%f %f %f\n",
                             t[0], t[1], t[2], t[3], t[4], t[5]));
  }
  if (r->nsub) {
    MX_CHECK(mx_afile_write(f, "\n", 1));
    MX_CHECK(mx_afile_emit(f, r->no, 11, fill_nsub, r));
    MX_CHECK(mx_afile_write(f, "\n", 1));
  }
  if (r->by_type) MX_CHECK(mx_afile_printf(f, "%s\n", MX_RESTART_BY_TYPE));
  if (r->materials) MX_CHECK(mx_afile_printf(f, "%s\n", MX_RESTART_MATERIALS));
  return MX_OK;
}

/* Checks the struct, then writes under a temporary name. */
int mx_restart_write_text(const char *path, const mx_restart *r) {
  MX_CHECK(check_restart(path, r, MX_EINTERNAL, BAD_DATA));
  mx_afile f;
  MX_CHECK(mx_afile_open(&f, path));
  return mx_afile_finish(&f, text_body(&f, r));
}

/* ---- binary writing ------------------------------------------------------ */

typedef struct {
  mx_afile f;
  rs_hash h;
  int status;
} bin_out;

/* Writes a section and pads it with zeros to a multiple of 8 bytes,
 * hashing both. */
static void bin_put(bin_out *o, const void *data, size_t bytes) {
  static const uint8_t zeros[8];
  if (o->status != MX_OK || bytes == 0) return;
  size_t whole = bytes / 8, rest = bytes % 8;
  hash_words(&o->h, data, whole);
  o->status = mx_afile_write(&o->f, data, bytes);
  if (rest && o->status == MX_OK) {
    uint8_t w[8] = {0};
    memcpy(w, (const uint8_t *)data + 8 * whole, rest);
    hash_words(&o->h, w, 1);
    o->status = mx_afile_write(&o->f, zeros, 8 - rest);
  }
}

/* Header, sections and checksum; count: the per-octant face counts. */
static int bin_body(bin_out *o, const mx_restart *r, const uint32_t *count) {
  uint8_t head[BIN_HEADER];
  uint32_t version = BIN_VERSION, flags = 0;
  uint64_t sizes[4] = {r->nv, r->ne, r->no, r->oct_tri_off[r->no]};
  if (r->has_transform) flags |= BIN_TRANSFORM;
  if (r->nsub) flags |= BIN_NSUB;
  if (r->has_mesh) flags |= BIN_MESH;
  if (r->by_type) flags |= BIN_BYTYPE;
  if (r->materials) flags |= BIN_MATERIALS;
  memcpy(head, bin_magic, 8);
  memcpy(head + 8, &version, 4);
  memcpy(head + 12, &flags, 4);
  memcpy(head + 16, sizes, 32);
  hash_init(&o->h);
  bin_put(o, head, sizeof head);
  if (r->has_mesh) {
    const uint64_t msz[2] = {r->mesh_nn, r->mesh_nc};
    bin_put(o, msz, sizeof msz);
  }
  bin_put(o, r->xyz, 24 * r->nv);
  bin_put(o, r->edge, 12 * r->ne);
  bin_put(o, r->oct_node, 32 * r->no);
  bin_put(o, r->oct_level, r->no);
  bin_put(o, count, 4 * r->no);
  bin_put(o, r->oct_tri, 4 * sizes[3]);
  if (r->has_transform) bin_put(o, r->transform, 48);
  if (r->nsub) bin_put(o, r->nsub, 4 * r->no);
  if (r->has_mesh) {
    bin_put(o, r->mesh_xyz, 24 * r->mesh_nn);
    bin_put(o, r->mesh_nkey, 8 * r->mesh_nn);
    bin_put(o, r->mesh_state, r->mesh_nn);
    bin_put(o, r->mesh_type, r->mesh_nc);
    bin_put(o, r->mesh_conn, 32 * r->mesh_nc);
    bin_put(o, r->mesh_leaf, 4 * r->mesh_nc);
    bin_put(o, r->mesh_jens, 8 * r->mesh_nc);
  }
  uint64_t sum = hash_final(&o->h);
  if (o->status == MX_OK) o->status = mx_afile_write(&o->f, &sum, 8);
  return o->status;
}

/* Checks the struct, then writes under a temporary name. */
int mx_restart_write_binary(const char *path, const mx_restart *r) {
  MX_CHECK(check_restart(path, r, MX_EINTERNAL, BAD_DATA));
  if (r->dim == 2) {
    mx_error(path, 0, "%s: a quadtree restart file is text only", BAD_DATA);
    return MX_EINTERNAL;
  }
  if (!r->xyz || !r->edge || !r->oct_node) {
    mx_error(path, 0, "%s: the binary writer takes stored rows, not generated ones", BAD_DATA);
    return MX_EINTERNAL;
  }
  MX_CHECK(check_mesh(path, r, MX_EINTERNAL, BAD_DATA));
  uint32_t *count = mx_alloc(4 * r->no);
  if (!count) return MX_ENOMEM;
  for (size_t i = 0; i < r->no; i++)
    count[i] = (uint32_t)(r->oct_tri_off[i + 1] - r->oct_tri_off[i]);
  bin_out o = {.status = MX_OK};
  int st = mx_afile_open(&o.f, path);
  if (st == MX_OK) st = mx_afile_finish(&o.f, bin_body(&o, r, count));
  mx_free(count);
  return st;
}
