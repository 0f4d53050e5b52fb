/* STL reader, ASCII and binary. Binary (80-byte header, uint32 facet count,
 * 50 bytes a facet) is recognised by its exact size, even when the header
 * starts with "solid". Identical vertices are merged exactly (hash on the
 * coordinate bits, -0 taken as +0), so the surface comes out indexed and its
 * closedness can be checked. Facet normals are ignored. */
#include <math.h>
#include <stdint.h>
#include <string.h>
#include <strings.h>

#include "base/common.h"
#include "soa/trisoup.h"

#include "io/text_scan.h"
#include "io/read_surface.h"

/* ---- exact vertex merging --------------------------------------------- */

#define EMPTY UINT32_MAX

/* Open addressing; each slot keeps 32 bits of the hash next to the vertex
 * id, so a probe rarely has to fetch coordinates that do not match. */
typedef struct {
  uint32_t id, tag; /* id EMPTY: free slot */
} vertex_slot;

typedef struct {
  vertex_slot *slot;
  size_t mask; /* capacity - 1, capacity a power of two */
} vertex_map;

static uint64_t mix64(uint64_t h) {
  h ^= h >> 33;
  h *= 0xff51afd7ed558ccdull;
  h ^= h >> 33;
  h *= 0xc4ceb9fe1a85ec53ull;
  return h ^ (h >> 33);
}

static uint64_t bits(double v) {
  uint64_t b;
  memcpy(&b, &v, sizeof b);
  return b;
}

static uint64_t hash_xyz(double x, double y, double z) {
  return mix64(bits(x) ^ mix64(bits(y) ^ mix64(bits(z))));
}

static int map_init(vertex_map *m, size_t expected) {
  size_t cap = 64;
  while (cap < 2 * expected) cap *= 2;
  m->slot = mx_alloc(cap * sizeof *m->slot);
  if (!m->slot) return MX_ENOMEM;
  memset(m->slot, 0xff, cap * sizeof *m->slot);
  m->mask = cap - 1;
  return MX_OK;
}

static void map_put(vertex_map *m, uint64_t h, uint32_t id) {
  size_t i = (size_t)h & m->mask;
  while (m->slot[i].id != EMPTY) i = (i + 1) & m->mask;
  m->slot[i].id = id;
  m->slot[i].tag = (uint32_t)(h >> 32);
}

/* Doubles the table and re-inserts the vertices (all distinct). */
static int map_grow(vertex_map *m, const mx_trisoup *s) {
  mx_free(m->slot);
  MX_CHECK(map_init(m, m->mask + 1));
  for (size_t v = 0; v < s->nv; v++)
    map_put(m, hash_xyz(s->x[v], s->y[v], s->z[v]), (uint32_t)v);
  return MX_OK;
}

/* -0 and +0 are the same point. */
static double plus_zero(double v) { return v == 0 ? 0.0 : v; }

/* The id of vertex (x, y, z) with hash h, added to the soup if new. */
static int map_hashed(vertex_map *m, mx_trisoup *s, const double c[3],
                      uint64_t h, uint32_t *id) {
  uint32_t tag = (uint32_t)(h >> 32);
  size_t i = (size_t)h & m->mask;
  for (; m->slot[i].id != EMPTY; i = (i + 1) & m->mask) {
    uint32_t v = m->slot[i].id;
    if (m->slot[i].tag == tag && s->x[v] == c[0] && s->y[v] == c[1] &&
        s->z[v] == c[2]) {
      *id = v;
      return MX_OK;
    }
  }
  if (s->nv >= s->cap_v) MX_CHECK(mx_trisoup_reserve(s, s->nv + 1, 0));
  *id = (uint32_t)s->nv;
  m->slot[i].id = *id;
  m->slot[i].tag = tag;
  s->x[s->nv] = c[0];
  s->y[s->nv] = c[1];
  s->z[s->nv] = c[2];
  s->nv++;
  if (2 * s->nv > m->mask) MX_CHECK(map_grow(m, s));
  return MX_OK;
}

/* Facets are merged in blocks: all hashes first, with their table slots
 * prefetched, then the lookups, which otherwise wait on cache misses. */
#define BLOCK 16

typedef struct {
  double c[3 * BLOCK][3]; /* corners, three a facet, -0 taken as +0 */
  size_t n;               /* corners held */
} corner_block;

static int merge_block(vertex_map *m, mx_trisoup *s, corner_block *b) {
  uint64_t h[3 * BLOCK];
  for (size_t i = 0; i < b->n; i++) {
    h[i] = hash_xyz(b->c[i][0], b->c[i][1], b->c[i][2]);
    __builtin_prefetch(&m->slot[(size_t)h[i] & m->mask]);
  }
  for (size_t i = 0; i < b->n; i += 3) {
    uint32_t v[3];
    for (int k = 0; k < 3; k++)
      MX_CHECK(map_hashed(m, s, b->c[i + k], h[i + k], &v[k]));
    MX_CHECK(mx_trisoup_add_triangle(s, v[0], v[1], v[2]));
  }
  b->n = 0;
  return MX_OK;
}

/* ---- binary ----------------------------------------------------------- */

static uint32_t le32(const unsigned char *b) {
  return (uint32_t)b[0] | (uint32_t)b[1] << 8 | (uint32_t)b[2] << 16 |
         (uint32_t)b[3] << 24;
}

static double le_float(const unsigned char *b) {
  uint32_t u = le32(b);
  float f;
  memcpy(&f, &u, sizeof f);
  return (double)f;
}

static int binary_block(const char *path, const unsigned char *buf,
                        size_t first, size_t count, vertex_map *m,
                        mx_trisoup *s, corner_block *b) {
  for (size_t f = 0; f < count; f++) {
    const unsigned char *rec = buf + 84 + 50 * (first + f) + 12;
    for (int k = 0; k < 9; k++) {
      double v = le_float(rec + 4 * k);
      if (!isfinite(v)) {
        mx_error(path, 0, "binary STL facet %zu: vertex %d is not finite",
                 first + f, k / 3);
        return MX_EINPUT;
      }
      b->c[3 * f + k / 3][k % 3] = plus_zero(v);
    }
  }
  b->n = 3 * count;
  return merge_block(m, s, b);
}

static int read_binary(const char *path, const unsigned char *buf, size_t n,
                       mx_trisoup *s) {
  if (n == 0) {
    mx_error(path, 0, "binary STL with no facets");
    return MX_EINPUT;
  }
  vertex_map m;
  MX_CHECK(map_init(&m, n / 2 + 8));
  corner_block b;
  int status = mx_trisoup_reserve(s, n / 2 + 8, n);
  for (size_t i = 0; i < n && status == MX_OK; i += BLOCK)
    status =
        binary_block(path, buf, i, n - i < BLOCK ? n - i : BLOCK, &m, s, &b);
  mx_free(m.slot);
  return status;
}

/* ---- ASCII ------------------------------------------------------------ */

typedef struct {
  const char *path, *p, *end; /* p: the next unread character */
  long line;
  size_t nfacets;
  vertex_map map;
  corner_block block;
} stl_text;

/* The token at p is `word`, compared case-insensitively. */
static int is_word(const char *p, const char *word) {
  size_t i = 0;
  for (; word[i]; i++)
    if ((p[i] | 0x20) != word[i]) return 0; /* word is lower case */
  return mx_io_delim(p + i, 0);
}

/* Consumes the next token, which must be `word`. */
static int expect(stl_text *f, const char *word) {
  f->p = mx_io_content(f->p, f->end, &f->line, 0);
  if (f->p < f->end && is_word(f->p, word)) {
    f->p += strlen(word);
    return MX_OK;
  }
  if (f->p == f->end)
    mx_error(f->path, f->line,
             "unexpected end of file, expected '%s' (truncated file?)", word);
  else
    mx_error(f->path, f->line, "expected '%s', found '%.*s'", word,
             mx_io_toklen(f->p, 0), f->p);
  return MX_EINPUT;
}

static int ascii_facet(stl_text *f, mx_trisoup *s) {
  /* facet i becomes triangle i (merged in blocks, in order) */
  if (f->nfacets < UINT32_MAX)
    MX_CHECK(mx_trisoup_note_line(s, f->nfacets, (uint32_t)f->nfacets, f->line));
  MX_CHECK(expect(f, "normal"));
  f->p = mx_io_next_line(f->p, f->end, &f->line); /* normal ignored */
  MX_CHECK(expect(f, "outer"));
  MX_CHECK(expect(f, "loop"));
  corner_block *b = &f->block;
  for (int k = 0; k < 3; k++) {
    MX_CHECK(expect(f, "vertex"));
    double *c = b->c[b->n + (size_t)k];
    MX_CHECK(
        mx_io_numbers(f->path, f->line, &f->p, 0, 3, c, "facet", f->nfacets));
    for (int d = 0; d < 3; d++) c[d] = plus_zero(c[d]);
  }
  MX_CHECK(expect(f, "endloop"));
  MX_CHECK(expect(f, "endfacet"));
  f->nfacets++;
  b->n += 3;
  return b->n == 3 * BLOCK ? merge_block(&f->map, s, b) : MX_OK;
}

/* One "solid ... endsolid" block; f->p is just after "solid". */
static int ascii_solid(stl_text *f, mx_trisoup *s) {
  f->p = mx_io_next_line(f->p, f->end, &f->line); /* the name */
  for (;;) {
    f->p = mx_io_content(f->p, f->end, &f->line, 0);
    if (f->p < f->end && is_word(f->p, "endsolid")) {
      f->p = mx_io_next_line(f->p, f->end, &f->line);
      return MX_OK;
    }
    if (f->p < f->end && !is_word(f->p, "facet")) {
      mx_error(f->path, f->line, "expected 'facet' or 'endsolid', found '%.*s'",
               mx_io_toklen(f->p, 0), f->p);
      return MX_EINPUT;
    }
    MX_CHECK(expect(f, "facet"));
    MX_CHECK(ascii_facet(f, s));
  }
}

static int parse_ascii(stl_text *f, mx_trisoup *s) {
  MX_CHECK(expect(f, "solid"));
  for (;;) {
    MX_CHECK(ascii_solid(f, s));
    f->p = mx_io_content(f->p, f->end, &f->line, 0);
    if (f->p == f->end) break;
    MX_CHECK(expect(f, "solid"));
  }
  MX_CHECK(merge_block(&f->map, s, &f->block));
  if (s->nt > 0) return MX_OK;
  mx_error(f->path, f->line, "ASCII STL with no facets");
  return MX_EINPUT;
}

static int read_ascii(const char *path, const char *buf, size_t len,
                      mx_trisoup *s) {
  stl_text *f = mx_alloc(sizeof *f); /* the block is 1 kB: not on the stack */
  if (!f) return MX_ENOMEM;
  memset(f, 0, sizeof *f);
  f->path = path;
  f->p = buf;
  f->end = buf + len;
  f->line = 1;
  size_t guess = len / 250 + 8; /* about 250 bytes a facet, V ~ F / 2 */
  int status = map_init(&f->map, guess);
  if (status == MX_OK) status = mx_trisoup_reserve(s, guess, 2 * guess);
  if (status == MX_OK) status = parse_ascii(f, s);
  mx_free(f->map.slot);
  mx_free(f);
  return status;
}

/* ---- format detection ------------------------------------------------- */

/* Starts with "solid" and the beginning is plain text. */
static int looks_ascii(const char *buf, size_t len) {
  const char *p = buf;
  while (p < buf + len && (*p == '\n' || *p == ' ' || *p == '\t' || *p == '\r'))
    p++;
  if ((size_t)(buf + len - p) < 5 || strncasecmp(p, "solid", 5) != 0) return 0;
  size_t n = len < 4096 ? len : 4096;
  for (size_t i = 0; i < n; i++) {
    unsigned char c = (unsigned char)buf[i];
    if (c < 9 || (c > 13 && c < 32) || c == 127) return 0;
  }
  return 1;
}

static int parse_stl(const char *path, const char *buf, size_t len,
                     mx_trisoup *s) {
  const unsigned char *u = (const unsigned char *)buf;
  uint64_t n = len >= 84 ? le32(u + 80) : 0;
  if (len >= 84 && len == 84 + 50 * n)
    return read_binary(path, u, (size_t)n, s);
  if (looks_ascii(buf, len)) return read_ascii(path, buf, len, s);
  if (len < 84)
    mx_error(path, 0,
             "neither ASCII STL (no 'solid') nor binary STL (%zu bytes, "
             "at least 84 needed)",
             len);
  else
    mx_error(path, 0,
             "binary STL: the header declares %llu facets (%llu bytes) but "
             "the file has %zu bytes: truncated file or wrong count",
             (unsigned long long)n, (unsigned long long)(84 + 50 * n), len);
  return MX_EINPUT;
}

int mx_read_stl(const char *path, mx_trisoup *out) {
  memset(out, 0, sizeof *out);
  char *buf;
  size_t len;
  MX_CHECK(mx_io_load(path, &buf, &len));
  out->nshells = 1;
  int status = parse_stl(path, buf, len, out);
  mx_free(buf);
  if (status != MX_OK) mx_trisoup_free(out);
  return status;
}
