/* Polygon faces split into triangles by ear clipping in their plane; see
 * polygon_split.h for the rules. */
#include "io/polygon_split.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "base/common.h"
#include "geom/orient2d.h"

#define NONE UINT32_MAX
#define PLANAR_TOL 1e-3                 /* of the polygon's size */
#define MAX_TESTS ((uint64_t)1 << 27)   /* point-in-triangle tests a face (~1 s) */

struct mx_queued_face {
  size_t start, k; /* its corners: qv[start, start + k) */
  mx_face_at at;
};

void mx_polysplit_init(mx_polysplit *ps, const char *path) {
  memset(ps, 0, sizeof *ps);
  ps->path = path;
}

void mx_polysplit_free(mx_polysplit *ps) {
  mx_free(ps->v);
  mx_free(ps->qv);
  mx_free(ps->q);
  mx_free(ps->work);
  const char *path = ps->path;
  mx_polysplit_init(ps, path);
}

/* p grown to hold `need` items of `item` bytes (capacity *cap), or NULL
 * (p untouched). */
static void *grown(void *p, size_t *cap, size_t need, size_t item) {
  if (need <= *cap) return p;
  size_t c = *cap < 16 ? 16 : *cap;
  while (c < need && c <= SIZE_MAX / 2 / item) c *= 2;
  if (c < need || c > SIZE_MAX / item) {
    mx_error(NULL, 0, "out of memory (a face of %zu corners)", need);
    return NULL;
  }
  void *q = mx_realloc(p, c * item);
  if (q) *cap = c;
  return q;
}

int mx_polysplit_grow(mx_polysplit *ps) {
  uint32_t *v = grown(ps->v, &ps->cap_v, ps->nv + 1, sizeof *v);
  if (!v) return MX_ENOMEM;
  ps->v = v;
  return MX_OK;
}

void mx_polysplit_defer(mx_polysplit *ps) { ps->defer = 1; }

/* ---- messages ------------------------------------------------------------ */

/* " (byte offset N)" for a face of a binary file, else "". */
static const char *byte_at(const mx_face_at *at, char buf[48]) {
  buf[0] = '\0';
  if (at->byte >= 0) snprintf(buf, 48, " (byte offset %lld)", (long long)at->byte);
  return buf;
}

static void note(mx_face_note *n, const mx_face_at *at, double worst) {
  if (n->count++ == 0) n->first = *at;
  if (worst > n->worst) n->worst = worst;
}

static void warn(const mx_polysplit *ps, const mx_face_note *n, const char *what,
                 const char *plural) {
  if (!n->count) return;
  char b[48], more[96] = "";
  if (n->count > 1) snprintf(more, sizeof more, " (%zu faces %s)", n->count, plural);
  mx_warning(ps->path, n->first.line, "face %llu%s %s%s",
             (unsigned long long)n->first.face, byte_at(&n->first, b), what, more);
}

static int refuse(const mx_polysplit *ps, const mx_face_at *at, size_t k, const char *why) {
  char b[48];
  mx_error(ps->path, at->line, "face %llu%s: a polygon of %zu corners %s",
           (unsigned long long)at->face, byte_at(at, b), k, why);
  return MX_EINPUT;
}

/* ---- scratch ------------------------------------------------------------- */

typedef struct {
  uint32_t *idx;     /* the corners, repeats in a row dropped */
  double *xy;        /* their projections */
  uint64_t *key;     /* (corner << 32 | position), sorted: repeats */
  uint32_t *rank;    /* position -> group of equal corners */
  int32_t *onstack;  /* group -> stack position, or -1 */
  uint32_t *stack;
  uint32_t *order;   /* the loops' positions, one loop after the other */
  uint32_t *len;     /* the loops' lengths */
  uint32_t *prev, *next, *eprev, *enext; /* a loop; its ears */
  uint32_t *reflex;  /* nodes reflex or flat when listed */
  int8_t *cls;       /* node: 1 convex, 0 flat, -1 reflex, 2 clipped */
  uint8_t *listed, *ear;
} scratch;

static int scratch_for(mx_polysplit *ps, size_t m, scratch *w) {
  const size_t bytes = m * (2 * sizeof(double) + sizeof(uint64_t)) +
                       (11 * m + 1) * sizeof(uint32_t) + 3 * m + 64;
  unsigned char *p = grown(ps->work, &ps->cap_work, bytes, 1);
  if (!p) return MX_ENOMEM;
  ps->work = p;
  w->xy = (double *)p;
  w->key = (uint64_t *)(w->xy + 2 * m);
  uint32_t *u = (uint32_t *)(w->key + m);
  w->idx = u;
  w->rank = u + m;
  w->onstack = (int32_t *)(u + 2 * m);
  w->stack = u + 3 * m;
  w->order = u + 4 * m;
  w->len = u + 5 * m;
  w->prev = u + 6 * m;
  w->next = u + 7 * m;
  w->eprev = u + 8 * m;
  w->enext = u + 9 * m;
  w->reflex = u + 10 * m;
  unsigned char *b = (unsigned char *)(u + 11 * m + 1);
  w->cls = (int8_t *)b;
  w->listed = b + m;
  w->ear = b + 2 * m;
  return MX_OK;
}

/* ---- the plane ----------------------------------------------------------- */

/* The Newell normal of the polygon (corners idx[0..m)), the largest
 * distance of a corner to its mean plane and its size (largest distance of
 * a corner to the centroid). */
static void plane(const mx_trisoup *s, const uint32_t *idx, size_t m, double n[3],
                  double *dev, double *size) {
  const double *X[3] = {s->x, s->y, s->z};
  double o[3], c[3] = {0, 0, 0};
  for (int d = 0; d < 3; d++) o[d] = X[d][idx[0]];
  n[0] = n[1] = n[2] = 0.0;
  for (size_t i = 0; i < m; i++) {
    const uint32_t a = idx[i], b = idx[i + 1 < m ? i + 1 : 0];
    double p[3], q[3];
    for (int d = 0; d < 3; d++) {
      p[d] = X[d][a] - o[d];
      q[d] = X[d][b] - o[d];
      c[d] += p[d];
    }
    n[0] += (p[1] - q[1]) * (p[2] + q[2]);
    n[1] += (p[2] - q[2]) * (p[0] + q[0]);
    n[2] += (p[0] - q[0]) * (p[1] + q[1]);
  }
  for (int d = 0; d < 3; d++) c[d] /= (double)m;
  const double len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
  *dev = *size = 0.0;
  for (size_t i = 0; i < m; i++) {
    double r[3], h = 0.0, r2 = 0.0;
    for (int d = 0; d < 3; d++) {
      r[d] = X[d][idx[i]] - o[d] - c[d];
      h += r[d] * n[d];
      r2 += r[d] * r[d];
    }
    if (len > 0.0 && fabs(h) / len > *dev) *dev = fabs(h) / len;
    if (r2 > *size) *size = r2;
  }
  *size = sqrt(*size);
}

/* Projection along axis ax (coordinates ax + 1, ax + 2 cyclically: the
 * turning sense of the polygon there is the sign of n[ax]). */
static void project(const mx_trisoup *s, const uint32_t *idx, size_t m, int ax, double *xy) {
  const double *X[3] = {s->x, s->y, s->z};
  const double *xi = X[(ax + 1) % 3], *xj = X[(ax + 2) % 3];
  for (size_t p = 0; p < m; p++) {
    xy[2 * p] = xi[idx[p]];
    xy[2 * p + 1] = xj[idx[p]];
  }
}

/* Whether every corner of the polygon is collinear with its neighbours in
 * the projection along ax. */
static int flat(const mx_trisoup *s, const uint32_t *idx, size_t m, int ax) {
  const double *X[3] = {s->x, s->y, s->z};
  const double *xi = X[(ax + 1) % 3], *xj = X[(ax + 2) % 3];
  for (size_t i = 0; i < m; i++) {
    const uint32_t a = idx[i ? i - 1 : m - 1], b = idx[i], c = idx[i + 1 < m ? i + 1 : 0];
    const double pa[2] = {xi[a], xj[a]}, pb[2] = {xi[b], xj[b]}, pc[2] = {xi[c], xj[c]};
    if (mx_orient2d(pa, pb, pc) != 0) return 0;
  }
  return 1;
}

/* ---- loops at repeated corners -------------------------------------------- */

static int cmp_u64(const void *a, const void *b) {
  const uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
  return (x > y) - (x < y);
}

static void sort_keys(uint64_t *k, size_t m) {
  if (m > 32) {
    qsort(k, m, sizeof *k, cmp_u64);
    return;
  }
  for (size_t i = 1; i < m; i++) {
    const uint64_t x = k[i];
    size_t j = i;
    for (; j > 0 && k[j - 1] > x; j--) k[j] = k[j - 1];
    k[j] = x;
  }
}

/* The polygon idx[0..m) as loops without a repeated corner: walking it, a
 * corner met again closes the loop since its first visit, which is taken
 * out (order, len). Returns the number of loops. */
static size_t loops(scratch *w, size_t m) {
  for (size_t p = 0; p < m; p++) w->key[p] = (uint64_t)w->idx[p] << 32 | p;
  sort_keys(w->key, m);
  int repeats = 0;
  uint32_t g = 0;
  for (size_t r = 0; r < m; r++) {
    if (r > 0 && (w->key[r] >> 32) == (w->key[r - 1] >> 32))
      repeats = 1;
    else if (r > 0)
      g++;
    w->rank[(uint32_t)w->key[r]] = g;
    w->onstack[g] = -1;
  }
  if (!repeats) {
    for (size_t p = 0; p < m; p++) w->order[p] = (uint32_t)p;
    w->len[0] = (uint32_t)m;
    return 1;
  }
  size_t top = 0, out = 0, nl = 0;
  for (size_t p = 0; p < m; p++) {
    const uint32_t r = w->rank[p];
    if (w->onstack[r] < 0) {
      w->onstack[r] = (int32_t)top;
      w->stack[top++] = (uint32_t)p;
      continue;
    }
    const size_t j = (size_t)w->onstack[r];
    for (size_t i = j; i < top; i++) w->order[out++] = w->stack[i];
    for (size_t i = j + 1; i < top; i++) w->onstack[w->rank[w->stack[i]]] = -1;
    w->len[nl++] = (uint32_t)(top - j);
    top = j + 1;
  }
  for (size_t i = 0; i < top; i++) w->order[out++] = w->stack[i];
  w->len[nl++] = (uint32_t)top;
  return nl;
}

/* The turning sense of a loop (positions P[0..L)) in the projection: the
 * exact turn at its lowest corner, else the sign of its area; 0 when flat. */
static int loop_sign(const double *xy, const uint32_t *P, size_t L) {
  size_t lo = 0;
  for (size_t i = 1; i < L; i++) {
    const double *a = xy + 2 * (size_t)P[i], *b = xy + 2 * (size_t)P[lo];
    if (a[0] < b[0] || (a[0] == b[0] && a[1] < b[1])) lo = i;
  }
  const double *pa = xy + 2 * (size_t)P[lo ? lo - 1 : L - 1], *pb = xy + 2 * (size_t)P[lo],
               *pc = xy + 2 * (size_t)P[lo + 1 < L ? lo + 1 : 0];
  const int o = mx_orient2d(pa, pb, pc);
  if (o) return o;
  const double *q = xy + 2 * (size_t)P[0];
  double area = 0.0;
  for (size_t i = 1; i + 1 < L; i++) {
    const double *u = xy + 2 * (size_t)P[i], *v = xy + 2 * (size_t)P[i + 1];
    area += (u[0] - q[0]) * (v[1] - q[1]) - (u[1] - q[1]) * (v[0] - q[0]);
  }
  return (area > 0) - (area < 0);
}

/* Whether two edges of the loop that are not neighbours meet (closed
 * segments, exact): the loop crosses or touches itself. Tested up to 64
 * corners (a larger loop that crosses itself has no ear left, or makes
 * triangles that cross, which the input check names). */
static int meets_itself(const double *xy, const uint32_t *P, size_t L) {
  if (L > 64) return 0;
  for (size_t i = 0; i + 2 < L; i++) {
    const double *a = xy + 2 * (size_t)P[i], *b = xy + 2 * (size_t)P[i + 1];
    for (size_t j = i + 2; j < L; j++) {
      if (i == 0 && j == L - 1) continue; /* neighbours across the end */
      const double *c = xy + 2 * (size_t)P[j], *d = xy + 2 * (size_t)P[j + 1 < L ? j + 1 : 0];
      int apart = 0;
      for (int k = 0; k < 2 && !apart; k++)
        apart = fmax(a[k], b[k]) < fmin(c[k], d[k]) || fmax(c[k], d[k]) < fmin(a[k], b[k]);
      if (apart) continue; /* the boxes: collinear segments that meet overlap there */
      const int o1 = mx_orient2d(a, b, c), o2 = mx_orient2d(a, b, d);
      const int o3 = mx_orient2d(c, d, a), o4 = mx_orient2d(c, d, b);
      if (o1 * o2 <= 0 && o3 * o4 <= 0) return 1;
    }
  }
  return 0;
}

/* ---- ear clipping ---------------------------------------------------------- */

typedef struct {
  scratch *w;
  const uint32_t *P; /* node -> position */
  int sg;            /* the loop's sense: a convex corner turns this way */
  size_t nreflex;    /* entries of w->reflex, some no longer reflex */
  uint64_t tests;
} clipper;

static inline const double *pt(const clipper *c, uint32_t node) {
  return c->w->xy + 2 * (size_t)c->P[node];
}

static inline int same(const double *a, const double *b) { return a[0] == b[0] && a[1] == b[1]; }

/* Node i's class; a reflex or flat node goes on the list (once: an entry
 * whose node turned convex stays, skipped, so the list holds at most L). */
static void classify(clipper *c, uint32_t i) {
  scratch *w = c->w;
  const int o = c->sg * mx_orient2d(pt(c, w->prev[i]), pt(c, i), pt(c, w->next[i]));
  w->cls[i] = (int8_t)o;
  if (o > 0 || w->listed[i]) return;
  w->reflex[c->nreflex++] = i;
  w->listed[i] = 1;
}

/* Whether node i is an ear: strictly convex, and no reflex or flat corner
 * in the closed triangle (prev, i, next) but copies of prev and next. */
static int is_ear(clipper *c, uint32_t i) {
  scratch *w = c->w;
  if (w->cls[i] != 1) return 0;
  const uint32_t ia = w->prev[i], ic = w->next[i];
  const double *a = pt(c, ia), *b = pt(c, i), *d = pt(c, ic);
  const int sg = c->sg;
  const double lx = fmin(a[0], fmin(b[0], d[0])), hx = fmax(a[0], fmax(b[0], d[0]));
  const double ly = fmin(a[1], fmin(b[1], d[1])), hy = fmax(a[1], fmax(b[1], d[1]));
  c->tests += c->nreflex;
  for (size_t k = 0; k < c->nreflex; k++) {
    const uint32_t r = w->reflex[k];
    const double *p = pt(c, r);
    if (p[0] < lx || p[0] > hx || p[1] < ly || p[1] > hy) continue; /* off its box */
    if (w->cls[r] > 0 || r == ia || r == ic) continue;
    if (same(p, a) || same(p, d)) continue;
    if (sg * mx_orient2d(a, b, p) >= 0 && sg * mx_orient2d(b, d, p) >= 0 &&
        sg * mx_orient2d(d, a, p) >= 0)
      return 0;
  }
  return 1;
}

/* The ears: a circular list in polygon order (eprev, enext). */
static uint32_t ear_unlink(scratch *w, uint32_t x, uint32_t *gap) {
  w->ear[x] = 0;
  const uint32_t nx = w->enext[x] == x ? NONE : w->enext[x];
  if (nx != NONE) {
    w->enext[w->eprev[x]] = nx;
    w->eprev[nx] = w->eprev[x];
  }
  if (*gap == x) *gap = nx;
  return nx;
}

static void ear_insert_before(scratch *w, uint32_t x, uint32_t y) {
  w->ear[x] = 1;
  if (y == NONE) {
    w->enext[x] = w->eprev[x] = x;
    return;
  }
  const uint32_t p = w->eprev[y];
  w->enext[p] = x;
  w->eprev[x] = p;
  w->enext[x] = y;
  w->eprev[y] = x;
}

/* Node x got a new neighbour: its class and ear status again, the ear list
 * kept in polygon order (a new ear goes before `before`). */
static void refresh(clipper *c, uint32_t x, uint32_t before, uint32_t *gap) {
  classify(c, x);
  const int e = is_ear(c, x);
  if (c->w->ear[x] && !e) ear_unlink(c->w, x, gap);
  if (!c->w->ear[x] && e) ear_insert_before(c->w, x, before);
}

static int add(mx_trisoup *s, const scratch *w, const uint32_t *P, uint32_t a, uint32_t b,
               uint32_t c, uint32_t face, size_t *made) {
  ++*made;
  return mx_trisoup_add_face_triangle(s, w->idx[P[a]], w->idx[P[b]], w->idx[P[c]], face);
}

static inline const double *pt3(const scratch *w, const uint32_t *P, uint32_t node) {
  return w->xy + 2 * (size_t)P[node];
}

static int too_large(const mx_polysplit *ps, const mx_face_at *at, size_t L) {
  return refuse(ps, at, L, "is too large and too tangled (reflex corners) to split into "
                           "triangles here: split it into smaller faces");
}

/* Clips the loop P[0..L) (L >= 3) of sense sg into triangles. */
static int clip(mx_polysplit *ps, mx_trisoup *s, scratch *w, const uint32_t *P, size_t L,
                int sg, const mx_face_at *at, size_t *made) {
  const uint32_t face = at->face < UINT32_MAX ? (uint32_t)at->face : UINT32_MAX;
  if (L == 3) /* a flat one makes no triangle */
    return mx_orient2d(pt3(w, P, 0), pt3(w, P, 1), pt3(w, P, 2)) ? add(s, w, P, 0, 1, 2, face, made)
                                                                 : MX_OK;
  clipper c = {w, P, sg, 0, 0};
  const uint32_t n0 = (uint32_t)L;
  for (uint32_t i = 0; i < n0; i++) {
    w->prev[i] = i ? i - 1 : n0 - 1;
    w->next[i] = i + 1 < n0 ? i + 1 : 0;
    w->listed[i] = w->ear[i] = 0;
  }
  int any = 0;
  for (uint32_t i = 0; i < n0; i++) {
    classify(&c, i);
    any |= w->cls[i] != 0;
  }
  if (!any) return MX_OK; /* a flat loop: no area, no triangle */
  /* the ears found, then about two tests a clip: 3 L r in all */
  if ((uint64_t)L * c.nreflex > MAX_TESTS / 4) return too_large(ps, at, L);
  uint32_t first = NONE, last = NONE;
  for (uint32_t i = 0; i < n0; i++) {
    if (!is_ear(&c, i)) continue;
    if (first == NONE)
      first = i;
    else
      w->enext[last] = i, w->eprev[i] = last;
    w->ear[i] = 1;
    last = i;
  }
  if (first != NONE) w->enext[last] = first, w->eprev[first] = last;
  uint32_t cur = NONE; /* the first ear from node 1 on: the fan when convex */
  for (uint32_t k = 1; k <= n0 && cur == NONE; k++)
    if (w->ear[k % n0]) cur = k % n0;
  uint32_t end = 1;
  for (size_t n = L; n > 3;) {
    if (c.tests > MAX_TESTS) return too_large(ps, at, L);
    if (cur == NONE)
      return refuse(ps, at, L, "crosses itself (seen along its mean normal): it cannot "
                               "be split into triangles; fix the face");
    const uint32_t a = w->prev[cur], b = cur, d = w->next[cur];
    MX_CHECK(add(s, w, P, a, b, d, face, made));
    w->next[a] = d;
    w->prev[d] = a;
    w->cls[b] = 2;
    n--;
    uint32_t gap = NONE;
    gap = ear_unlink(w, b, &gap);
    end = d;
    if (n == 3) break;
    refresh(&c, d, gap, &gap);
    refresh(&c, a, w->ear[d] ? d : gap, &gap);
    cur = w->ear[d] ? d : gap != NONE ? gap : w->ear[a] ? a : NONE;
  }
  return add(s, w, P, w->prev[end], end, w->next[end], face, made);
}

/* ---- one face ---------------------------------------------------------------- */

/* Four distinct corners turning strictly the way of the face at each one:
 * a convex quadrilateral (four turns of one sign cannot wind twice), whose
 * split is the fan from corner 0, as clip makes it. */
static int convex_quad(const scratch *w, int sense) {
  const uint32_t *v = w->idx;
  if (v[0] == v[2] || v[1] == v[3]) return 0; /* v[i] != v[i + 1] already */
  for (int i = 0; i < 4; i++)
    if (mx_orient2d(w->xy + 2 * ((i + 3) % 4), w->xy + 2 * i, w->xy + 2 * ((i + 1) % 4)) != sense)
      return 0;
  return 1;
}

static inline int same_point(const mx_trisoup *s, uint32_t a, uint32_t b) {
  return a == b || (s->x[a] == s->x[b] && s->y[a] == s->y[b] && s->z[a] == s->z[b]);
}

static int split_polygon(mx_polysplit *ps, mx_trisoup *s, const uint32_t *v, size_t k,
                         const mx_face_at *at) {
  scratch w;
  MX_CHECK(scratch_for(ps, k, &w));
  size_t m = 0; /* repeats in a row dropped (same index, or same point) */
  for (size_t i = 0; i < k; i++)
    if (m == 0 || !same_point(s, v[i], w.idx[m - 1])) w.idx[m++] = v[i];
  while (m > 1 && same_point(s, w.idx[m - 1], w.idx[0])) m--;
  int repeated = m < k;
  size_t made = 0;
  double n[3] = {0, 0, 0}, dev = 0, size = 0;
  if (m >= 3) plane(s, w.idx, m, n, &dev, &size);
  int ax = 0; /* the axis of projection */
  for (int d = 1; d < 3; d++)
    if (fabs(n[d]) > fabs(n[ax])) ax = d;
  if (n[ax] == 0.0) /* no vector area: one where the polygon is not flat */
    for (ax = 0; ax < 3 && m >= 3 && flat(s, w.idx, m, ax);) ax++;
  if (m < 3 || ax == 3) { /* collinear corners */
    note(&ps->zero_area, at, 0.0);
    return MX_OK;
  }
  project(s, w.idx, m, ax, w.xy);
  if (dev > PLANAR_TOL * size) note(&ps->nonplanar, at, dev / size);
  const int sense = n[ax] > 0 ? 1 : -1; /* n[ax] = 0: a crossing, refused */
  if (m == 4 && convex_quad(&w, sense)) { /* most polygons: what clip gives, sooner */
    const uint32_t face = at->face < UINT32_MAX ? (uint32_t)at->face : UINT32_MAX;
    MX_CHECK(mx_trisoup_add_face_triangle(s, w.idx[0], w.idx[1], w.idx[2], face));
    MX_CHECK(mx_trisoup_add_face_triangle(s, w.idx[0], w.idx[2], w.idx[3], face));
    if (repeated) note(&ps->repeated, at, 0.0);
    return MX_OK;
  }
  const size_t nl = loops(&w, m);
  for (size_t l = 0, off = 0; l < nl; off += w.len[l++]) {
    const uint32_t *P = w.order + off;
    const size_t L = w.len[l];
    if (nl > 1) repeated = 1;
    if (L < 3) continue; /* an edge there and back */
    const int sg = loop_sign(w.xy, P, L);
    if (sg == 0) continue;
    if (meets_itself(w.xy, P, L))
      return refuse(ps, at, k, "crosses or touches itself (seen along its mean normal): it "
                               "cannot be split into triangles; fix the face");
    if (nl > 1 && sg != sense)
      return refuse(ps, at, k, "comes back to a corner and turns the other way there (a "
                               "hole bridged by repeated corners, or a crossing): it cannot "
                               "be split into triangles; fix the face");
    MX_CHECK(clip(ps, s, &w, P, L, sg, at, &made));
  }
  if (made == 0)
    note(&ps->zero_area, at, 0.0);
  else if (repeated)
    note(&ps->repeated, at, 0.0);
  return MX_OK;
}

static int split_face(mx_polysplit *ps, mx_trisoup *s, const uint32_t *v, size_t k,
                      const mx_face_at *at) {
  const uint32_t face = at->face < UINT32_MAX ? (uint32_t)at->face : UINT32_MAX;
  MX_CHECK(mx_trisoup_note_line(s, s->nt, face, at->line));
  if (k == 3) return mx_trisoup_add_face_triangle(s, v[0], v[1], v[2], face);
  return split_polygon(ps, s, v, k, at);
}

int mx_polysplit_face(mx_polysplit *ps, mx_trisoup *s, mx_face_at at) {
  const size_t k = ps->nv;
  ps->nv = 0;
  if (!ps->defer) return split_face(ps, s, ps->v, k, &at);
  uint32_t *qv = grown(ps->qv, &ps->cap_qv, ps->nqv + k, sizeof *qv);
  if (!qv) return MX_ENOMEM;
  ps->qv = qv;
  struct mx_queued_face *q = grown(ps->q, &ps->cap_q, ps->nq + 1, sizeof *q);
  if (!q) return MX_ENOMEM;
  ps->q = q;
  memcpy(qv + ps->nqv, ps->v, k * sizeof *qv);
  q[ps->nq++] = (struct mx_queued_face){ps->nqv, k, at};
  ps->nqv += k;
  return MX_OK;
}

int mx_polysplit_triangle(mx_polysplit *ps, mx_trisoup *s, const uint32_t v[3], mx_face_at at) {
  if (!ps->defer) return split_face(ps, s, v, 3, &at);
  for (int j = 0; j < 3; j++) MX_CHECK(mx_polysplit_corner(ps, v[j]));
  return mx_polysplit_face(ps, s, at);
}

int mx_polysplit_finish(mx_polysplit *ps, mx_trisoup *s) {
  for (size_t i = 0; i < ps->nq; i++)
    MX_CHECK(split_face(ps, s, ps->qv + ps->q[i].start, ps->q[i].k, &ps->q[i].at));
  ps->nq = ps->nqv = 0;
  char what[160];
  snprintf(what, sizeof what,
           "is not planar (a corner is off its mean plane by %.2g%% of its size): "
           "split in its projection on that plane",
           100.0 * ps->nonplanar.worst);
  warn(ps, &ps->nonplanar, what, "are not planar");
  warn(ps, &ps->zero_area,
       "has no area (its corners are collinear or repeated): no triangle made for it",
       "have no area");
  warn(ps, &ps->repeated, "repeats a corner: split where it comes back to it", "repeat a corner");
  if (s->nt > 0 || ps->zero_area.count == 0) return MX_OK;
  mx_error(ps->path, 0, "no triangle: every face has no area");
  return MX_EINPUT;
}
