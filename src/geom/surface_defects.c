/* Defects of input surfaces: open, non-manifold and misoriented edges,
 * degenerate triangles, pairs of triangles that intersect; orientation.
 * See surface_defects.h for the definitions and the method. */
#include "geom/surface_defects.h"

#include <math.h>
#include <omp.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "base/common.h"
#include "base/morton.h"
#include "base/scan.h"
#include "geom/bvh.h"
#include "geom/surface_topology.h"
#include "geom/triangle_pair.h"

#define NEX MX_DEFECT_EXAMPLES
#define NONE UINT32_MAX

/* ==== examples =========================================================== */

static int ex_less(const mx_defect_example *a, const mx_defect_example *b) {
  if (a->tri != b->tri) return a->tri < b->tri;
  if (a->other != b->other) return a->other < b->other;
  if (a->v0 != b->v0) return a->v0 < b->v0;
  return a->v1 < b->v1;
}

/* Keeps the NEX smallest, sorted; *n is how many are stored. */
static void ex_add(mx_defect_example *arr, size_t *n, const mx_defect_example *e) {
  size_t m = *n;
  if (m == NEX && !ex_less(e, &arr[NEX - 1])) return;
  size_t i = m < NEX ? m : NEX - 1;
  while (i > 0 && ex_less(e, &arr[i - 1])) {
    arr[i] = arr[i - 1];
    i--;
  }
  arr[i] = *e;
  if (m < NEX) *n = m + 1;
}

static mx_defect_example edge_example(const mx_trisoup *s, uint32_t t,
                                      uint32_t other, uint32_t v0,
                                      uint32_t v1) {
  mx_defect_example e = {t, other, v0, v1, {0.5 * (s->x[v0] + s->x[v1]),
                                            0.5 * (s->y[v0] + s->y[v1]),
                                            0.5 * (s->z[v0] + s->z[v1])}};
  return e;
}

/* ==== edges ==============================================================
 * The edge table of geom/surface_topology.h over the soup's triangles,
 * those that repeat a vertex left out. */

static int indices_valid(const mx_trisoup *s) {
  if (s->nt > ((size_t)1 << 30)) {
    mx_error(NULL, 0, "surface check: too many triangles (%zu, at most 2^30)",
             s->nt);
    return MX_EINPUT;
  }
  for (size_t i = 0; i < 3 * s->nt; i++)
    if (s->tri[i] >= s->nv) {
      mx_error(NULL, 0, "surface check: triangle %zu uses vertex %u of %zu",
               i / 3, s->tri[i], s->nv);
      return MX_EINPUT;
    }
  return MX_OK;
}

typedef struct {
  size_t cnt[3]; /* boundary, nonmanifold, misoriented */
  size_t nex[3];
  mx_defect_example ex[3][NEX];
} edge_acc;

/* Runs starting in each chunk of this many entries of the table go to one
 * task. */
#define EDGE_CHUNK 16384

static int edge_defects(const mx_trisoup *s, const mx_edge_table *E,
                        mx_surface_defects *r) {
  const size_t n = E->n, nchunk = (n + EDGE_CHUNK - 1) / EDGE_CHUNK;
  const int nth = omp_get_max_threads();
  edge_acc *acc = mx_calloc((size_t)nth * sizeof *acc);
  if (!acc) return MX_ENOMEM;
#pragma omp parallel num_threads(nth) if (n > 150000)
  {
    edge_acc *A = &acc[omp_get_thread_num()];
#pragma omp for schedule(dynamic, 1)
    for (size_t ch = 0; ch < nchunk; ch++) {
      const size_t stop = mx_min((ch + 1) * EDGE_CHUNK, n);
      size_t i = ch * EDGE_CHUNK;
      while (i > 0 && i < stop && E->key[i] == E->key[i - 1]) i++;
      while (i < stop) {
        const size_t j = mx_edge_run_end(E, i);
        const uint32_t v = (uint32_t)(E->key[i] >> 32), w = (uint32_t)E->key[i];
        const uint32_t h0 = E->half[i], t0 = h0 / 3;
        const uint32_t t1 = j - i > 1 ? E->half[i + 1] / 3 : NONE;
        int kind = -1;
        if (j - i == 1)
          kind = 0;
        else if (j - i > 2)
          kind = 1;
        else if (s->tri[h0] == s->tri[E->half[i + 1]])
          kind = 2;
        if (kind >= 0) {
          A->cnt[kind]++;
          mx_defect_example x = edge_example(s, t0, t1, v, w);
          ex_add(A->ex[kind], &A->nex[kind], &x);
        }
        i = j;
      }
    }
  }
  size_t nex[3] = {0, 0, 0};
  mx_defect_example *dst[3] = {r->boundary, r->nonmanifold, r->misoriented};
  size_t *cnt[3] = {&r->boundary_edges, &r->nonmanifold_edges,
                    &r->misoriented_edges};
  for (int t = 0; t < nth; t++) {
    edge_acc *A = &acc[t];
    for (int k = 0; k < 3; k++) {
      *cnt[k] += A->cnt[k];
      for (size_t x = 0; x < A->nex[k]; x++) ex_add(dst[k], &nex[k], &A->ex[k][x]);
    }
  }
  mx_free(acc);
  return MX_OK;
}

/* Bodies: triangles connected through shared vertices (union-find over
 * the vertices); body[t] = the root of t's first vertex. */
static uint32_t uf_find(uint32_t *p, uint32_t x) {
  while (p[x] != x) {
    p[x] = p[p[x]];
    x = p[x];
  }
  return x;
}

static void bodies(const mx_trisoup *s, uint32_t *p, uint32_t *body) {
  for (size_t v = 0; v < s->nv; v++) p[v] = (uint32_t)v;
  for (size_t t = 0; t < s->nt; t++) {
    uint32_t a = uf_find(p, s->tri[3 * t]);
    for (int k = 1; k < 3; k++) {
      uint32_t b = uf_find(p, s->tri[3 * t + k]);
      if (a == b) continue;
      if (a < b) p[b] = a;
      else p[a] = b, a = b;
    }
  }
  for (size_t t = 0; t < s->nt; t++) body[t] = uf_find(p, s->tri[3 * t]);
}

/* ==== broad phase ========================================================
 * The broad phase of geom/bvh.h: the Morton tree of the non-degenerate
 * triangles' boxes (mx_bvh_build_morton) traversed against itself
 * (mx_bvh_self_pairs). A pair of triangles reaches the narrow phase in slot
 * order, the one of smaller (Morton code of its box centre, id) first (the
 * point found at an intersection depends on the order). */

typedef struct {
  uint32_t n;         /* slots (non-degenerate triangles) */
  uint32_t *tid;      /* slot -> triangle */
  uint32_t *code;     /* Morton code per slot */
  double *tv;         /* 9 per slot */
  double *box;        /* 6 per slot: lo, hi */
  uint32_t *vid;      /* 3 per slot */
  int8_t *axis;       /* per slot */
  mx_bvh_node *nodes;
} bvh;

static void bvh_free(bvh *B) {
  mx_free(B->tid);
  mx_free(B->code);
  mx_free(B->tv);
  mx_free(B->box);
  mx_free(B->vid);
  mx_free(B->axis);
  mx_free(B->nodes);
  memset(B, 0, sizeof *B);
}

/* The slots: the non-degenerate triangles (axis_of[t] >= 0) sorted by
 * (Morton code of the box centre, id). */
static int bvh_build(bvh *B, const mx_trisoup *s, const int8_t *axis_of) {
  memset(B, 0, sizeof *B);
  size_t n = 0;
  for (size_t t = 0; t < s->nt; t++) n += axis_of[t] >= 0;
  B->n = (uint32_t)n;
  if (n == 0) return MX_OK;
  B->tid = mx_alloc(n * sizeof *B->tid);
  B->code = mx_alloc(n * sizeof *B->code);
  if (!B->tid || !B->code) {
    bvh_free(B);
    return MX_ENOMEM;
  }
  double lo[3] = {INFINITY, INFINITY, INFINITY};
  double hi[3] = {-INFINITY, -INFINITY, -INFINITY};
  n = 0;
  for (size_t t = 0; t < s->nt; t++) {
    if (axis_of[t] < 0) continue;
    B->tid[n++] = (uint32_t)t;
    for (int k = 0; k < 3; k++) {
      uint32_t v = s->tri[3 * t + k];
      double c[3] = {s->x[v], s->y[v], s->z[v]};
      for (int a = 0; a < 3; a++) {
        lo[a] = mx_min(lo[a], c[a]);
        hi[a] = mx_max(hi[a], c[a]);
      }
    }
  }
  double scale[3];
  for (int a = 0; a < 3; a++)
    scale[a] = hi[a] > lo[a] ? 1023.0 / (hi[a] - lo[a]) : 0.0;
#pragma omp parallel for schedule(static) if (n > 20000)
  for (size_t i = 0; i < n; i++) {
    const uint32_t *v = s->tri + 3 * (size_t)B->tid[i];
    const double *c[3] = {s->x, s->y, s->z};
    uint32_t q[3];
    for (int a = 0; a < 3; a++) {
      double m = mx_min(c[a][v[0]], mx_min(c[a][v[1]], c[a][v[2]]));
      double M = mx_max(c[a][v[0]], mx_max(c[a][v[1]], c[a][v[2]]));
      double f = (0.5 * (m + M) - lo[a]) * scale[a];
      q[a] = f <= 0.0 ? 0 : f >= 1023.0 ? 1023 : (uint32_t)f;
    }
    B->code[i] = (uint32_t)mx_morton_encode(q[2], q[1], q[0]); /* x highest */
  }
  if (mx_morton_sort30(B->code, B->tid, (uint32_t)n) != MX_OK) {
    bvh_free(B);
    return MX_ENOMEM;
  }
  B->tv = mx_alloc(9 * n * sizeof *B->tv);
  B->box = mx_alloc(6 * n * sizeof *B->box);
  B->vid = mx_alloc(3 * n * sizeof *B->vid);
  B->axis = mx_alloc(n);
  B->nodes = mx_alloc(2 * n * sizeof *B->nodes);
  if (!B->tv || !B->box || !B->vid || !B->axis || !B->nodes) {
    bvh_free(B);
    return MX_ENOMEM;
  }
#pragma omp parallel for schedule(static) if (n > 20000)
  for (size_t i = 0; i < n; i++) {
    const uint32_t t = B->tid[i];
    double *P = B->tv + 9 * i, *bx = B->box + 6 * i;
    for (int k = 0; k < 3; k++) {
      const uint32_t v = s->tri[3 * (size_t)t + k];
      B->vid[3 * i + k] = v;
      P[3 * k] = s->x[v];
      P[3 * k + 1] = s->y[v];
      P[3 * k + 2] = s->z[v];
    }
    for (int a = 0; a < 3; a++) {
      bx[a] = mx_min(P[a], mx_min(P[3 + a], P[6 + a]));
      bx[3 + a] = mx_max(P[a], mx_max(P[3 + a], P[6 + a]));
    }
    B->axis[i] = axis_of[t];
  }
  mx_bvh_build_morton(B->nodes, B->code, B->box, (uint32_t)n);
  return MX_OK;
}

/* ==== pairs ============================================================== */

typedef struct {
  size_t inter, cross, bodies;
  size_t nex[2];
  mx_defect_example ex[2][NEX];
  uint64_t *pairs; /* collecting (mx_surface_meeting_pairs): the pairs met */
  size_t npairs, cap;
  int oom;
  char pad_[64];
} pair_acc;

typedef struct {
  const bvh *B;
  const mx_trisoup *s;
  const uint32_t *body;
  pair_acc *acc; /* one per thread */
  int collect;   /* keep every pair met (acc->pairs) */
} pair_ctx;

/* Narrow phase on slots i < j whose boxes meet (the visit of
 * geom/bvh_pairs.h). */
static inline void test_pair(void *ctx, uint32_t i, uint32_t j) {
  const pair_ctx *c = ctx;
  const bvh *B = c->B;
  double w[3];
  if (!mx_triangles_meet(B->tv + 9 * (size_t)i, B->tv + 9 * (size_t)j,
                  B->vid + 3 * (size_t)i, B->vid + 3 * (size_t)j, B->axis[i],
                  B->axis[j], w))
    return;
  pair_acc *A = &c->acc[omp_get_thread_num()];
  uint32_t ti = B->tid[i], tj = B->tid[j];
  if (c->collect) {
    if (A->npairs == A->cap) {
      const size_t cap = A->cap ? 2 * A->cap : 256;
      uint64_t *g = mx_realloc(A->pairs, cap * sizeof *g);
      if (!g) {
        A->oom = 1;
        return;
      }
      A->pairs = g;
      A->cap = cap;
    }
    A->pairs[A->npairs++] = ti < tj ? (uint64_t)ti << 32 | tj : (uint64_t)tj << 32 | ti;
    return;
  }
  mx_defect_example x = {ti < tj ? ti : tj, ti < tj ? tj : ti, NONE, NONE,
                         {w[0], w[1], w[2]}};
  const uint16_t *sh = c->s->shell;
  int kind = sh && sh[ti] != sh[tj];
  if (kind) A->cross++;
  else {
    A->inter++;
    if (c->body[ti] != c->body[tj]) A->bodies++;
  }
  ex_add(A->ex[kind], &A->nex[kind], &x);
}

#define MX_BVH_VISIT test_pair
#include "geom/bvh_pairs.h"

static int pair_defects(const bvh *B, const mx_trisoup *s, const uint32_t *body,
                        mx_surface_defects *r) {
  if (B->n < 2) return MX_OK;
  int nth = omp_get_max_threads();
  pair_acc *acc = mx_calloc((size_t)nth * sizeof *acc);
  if (!acc) return MX_ENOMEM;
  pair_ctx c = {B, s, body, acc, 0};
  mx_bvh_self_pairs(B->nodes, B->box, B->n, &c);
  size_t nex[2] = {0, 0};
  for (int t = 0; t < nth; t++) {
    pair_acc *A = &acc[t];
    r->intersecting_pairs += A->inter;
    r->crossing_pairs += A->cross;
    r->intersecting_bodies += A->bodies;
    for (size_t x = 0; x < A->nex[0]; x++) ex_add(r->intersecting, &nex[0], &A->ex[0][x]);
    for (size_t x = 0; x < A->nex[1]; x++) ex_add(r->crossing, &nex[1], &A->ex[1][x]);
  }
  mx_free(acc);
  return MX_OK;
}

/* ==== public ============================================================= */

int mx_surface_meeting_pairs(const mx_trisoup *s, uint64_t **pairs, size_t *npairs) {
  *pairs = NULL;
  *npairs = 0;
  if (s->nt < 2) return MX_OK;
  MX_CHECK(indices_valid(s));
  int8_t *axis = mx_alloc(s->nt);
  if (!axis) return MX_ENOMEM;
  mx_triangle_axes(s, axis);
  bvh B;
  int st = bvh_build(&B, s, axis);
  mx_free(axis);
  const int nth = omp_get_max_threads();
  pair_acc *acc = st ? NULL : mx_calloc((size_t)nth * sizeof *acc);
  if (!st && !acc) st = MX_ENOMEM;
  if (!st && B.n >= 2) {
    pair_ctx c = {&B, s, NULL, acc, 1};
    mx_bvh_self_pairs(B.nodes, B.box, B.n, &c);
  }
  size_t n = 0;
  for (int t = 0; acc && t < nth; t++) {
    n += acc[t].npairs;
    if (acc[t].oom) st = MX_ENOMEM;
  }
  uint64_t *all = st ? NULL : mx_alloc((n + 1) * sizeof *all);
  if (!st && !all) st = MX_ENOMEM;
  if (!st) {
    size_t k = 0;
    for (int t = 0; t < nth; t++) {
      if (acc[t].npairs) memcpy(all + k, acc[t].pairs, acc[t].npairs * sizeof *all);
      k += acc[t].npairs;
    }
    st = mx_sort_u64(all, NULL, n);
  }
  for (int t = 0; acc && t < nth; t++) mx_free(acc[t].pairs);
  mx_free(acc);
  bvh_free(&B);
  if (st) {
    mx_free(all);
    return st;
  }
  *pairs = all;
  *npairs = n;
  return MX_OK;
}

int mx_surface_defects_find(const mx_trisoup *s, mx_surface_defects *r) {
  memset(r, 0, sizeof *r);
  if (s->nt == 0) return MX_OK;
  MX_CHECK(indices_valid(s));
  const size_t nt = s->nt;
  int8_t *axis = mx_alloc(nt);
  uint32_t *body = mx_alloc(nt * sizeof *body);
  uint32_t *vroot = mx_alloc((s->nv ? s->nv : 1) * sizeof *vroot);
  mx_edge_table E;
  int st = axis && body && vroot ? mx_edge_table_build(&E, s->tri, NULL, (uint32_t)nt, (uint32_t)s->nv, 1, 0)
                                 : MX_ENOMEM;
  if (st == MX_OK) {
    st = edge_defects(s, &E, r);
    mx_edge_table_free(&E);
  }
  if (st != MX_OK) {
    mx_free(axis);
    mx_free(body);
    mx_free(vroot);
    return st;
  }
  bodies(s, vroot, body);
  mx_free(vroot);

  mx_triangle_axes(s, axis);
  size_t nex = 0;
  for (size_t t = 0; t < nt; t++) {
    if (axis[t] >= 0) continue;
    r->degenerate_triangles++;
    if (nex == NEX) continue;
    const uint32_t *v = s->tri + 3 * t;
    mx_defect_example x = {(uint32_t)t, NONE, NONE, NONE,
                           {(s->x[v[0]] + s->x[v[1]] + s->x[v[2]]) / 3.0,
                            (s->y[v[0]] + s->y[v[1]] + s->y[v[2]]) / 3.0,
                            (s->z[v[0]] + s->z[v[1]] + s->z[v[2]]) / 3.0}};
    ex_add(r->degenerate, &nex, &x);
  }

  bvh B;
  st = bvh_build(&B, s, axis);
  if (st == MX_OK) st = pair_defects(&B, s, body, r);
  bvh_free(&B);
  mx_free(axis);
  mx_free(body);
  return st;
}

size_t mx_surface_defects_total(const mx_surface_defects *r) {
  return r->boundary_edges + r->nonmanifold_edges + r->misoriented_edges +
         r->intersecting_pairs + r->crossing_pairs + r->degenerate_triangles;
}

int mx_surface_orient(mx_trisoup *s, size_t *flipped) {
  if (flipped) *flipped = 0;
  if (s->nt == 0) return MX_OK;
  MX_CHECK(indices_valid(s));
  const size_t nt = s->nt;
  mx_edge_table E;
  uint32_t *comp = mx_alloc(nt * sizeof *comp);
  uint8_t *flip = mx_calloc(nt);
  int st = comp && flip ? mx_edge_table_build(&E, s->tri, NULL, (uint32_t)nt, (uint32_t)s->nv, 1, 1) : MX_ENOMEM;
  if (st != MX_OK) {
    mx_free(comp);
    mx_free(flip);
    return st;
  }
  /* Pieces: shells through the manifold edges; flip[u] makes u agree with
   * the triangle it was reached from. */
  uint32_t ncomp = 0;
  st = mx_surface_shells(&E, 0, comp, flip, &ncomp, NULL, NULL);
  /* Per piece: open?, volume, size, flips so far. */
  uint8_t *open = NULL;
  double *vol = NULL;
  size_t *size = NULL;
  uint32_t *ref = NULL;
  if (st == MX_OK) {
    open = mx_calloc(ncomp ? ncomp : 1);
    vol = mx_calloc((ncomp ? ncomp : 1) * sizeof *vol);
    size = mx_calloc((ncomp ? ncomp : 1) * 2 * sizeof *size);
    ref = mx_alloc((ncomp ? ncomp : 1) * sizeof *ref);
    if (!open || !vol || !size || !ref) st = MX_ENOMEM;
  }
  if (st != MX_OK) goto done;
  for (size_t i = 0; i < E.n;) {
    const size_t j = mx_edge_run_end(&E, i);
    for (size_t a = i; a < j; a++) {
      uint32_t c = comp[E.half[a] / 3], uses = 0;
      for (size_t b = i; b < j; b++) uses += comp[E.half[b] / 3] == c;
      if (uses != 2) open[c] = 1;
    }
    i = j;
  }
  for (uint32_t c = 0; c < ncomp; c++) ref[c] = NONE;
  for (size_t t = 0; t < nt; t++) {
    uint32_t c = comp[t];
    if (c == NONE) continue;
    if (ref[c] == NONE) ref[c] = s->tri[3 * t];
    size[2 * c]++;
    size[2 * c + 1] += flip[t];
    const uint32_t *v = s->tri + 3 * t;
    double o[3] = {s->x[ref[c]], s->y[ref[c]], s->z[ref[c]]}, p[3][3];
    for (int k = 0; k < 3; k++) {
      p[k][0] = s->x[v[k]] - o[0];
      p[k][1] = s->y[v[k]] - o[1];
      p[k][2] = s->z[v[k]] - o[2];
    }
    double d = p[0][0] * (p[1][1] * p[2][2] - p[1][2] * p[2][1]) -
               p[0][1] * (p[1][0] * p[2][2] - p[1][2] * p[2][0]) +
               p[0][2] * (p[1][0] * p[2][1] - p[1][1] * p[2][0]);
    vol[c] += flip[t] ? -d : d;
  }
  size_t nflip = 0;
  for (size_t t = 0; t < nt; t++) {
    uint32_t c = comp[t];
    if (c == NONE) continue;
    uint8_t invert = open[c] ? 2 * size[2 * c + 1] > size[2 * c] : vol[c] < 0.0;
    if (!(flip[t] ^ invert)) continue;
    uint32_t *v = s->tri + 3 * t, x = v[1];
    v[1] = v[2];
    v[2] = x;
    nflip++;
  }
  if (flipped) *flipped = nflip;
done:
  mx_free(open);
  mx_free(vol);
  mx_free(size);
  mx_free(ref);
  mx_edge_table_free(&E);
  mx_free(comp);
  mx_free(flip);
  return st;
}

/* ==== messages =========================================================== */

typedef struct {
  char *p;
  size_t left;
} outbuf;

static void out(outbuf *o, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static void out(outbuf *o, const char *fmt, ...) {
  if (o->left <= 1) return;
  va_list ap;
  va_start(ap, fmt);
  int k = vsnprintf(o->p, o->left, fmt, ap);
  va_end(ap);
  if (k < 0) return;
  size_t m = (size_t)k < o->left - 1 ? (size_t)k : o->left - 1;
  o->p += m;
  o->left -= m;
}

/* "triangle T", "triangles T and U", "face F (triangle 2 of 4, line L)",
 * ... as the inputs' files number them (mx_trisoup_name), with "of input
 * K" when the soup holds several inputs. */
static void out_tris(outbuf *o, const mx_trisoup *s, uint32_t t, uint32_t u) {
  const int multi = s && s->nshells > 1;
  const unsigned it = s && s->shell && t < s->nt ? s->shell[t] : 0;
  char nt[128], nu[128];
  const int pt = mx_trisoup_name(s, t, nt, sizeof nt);
  if (u == NONE) {
    out(o, "%s", nt);
    if (multi) out(o, " of input %u", it);
    return;
  }
  const unsigned iu = s && s->shell && u < s->nt ? s->shell[u] : 0;
  const int pu = mx_trisoup_name(s, u, nu, sizeof nu);
  if (it != iu) {
    out(o, "%s of input %u and %s of input %u", nt, it, nu, iu);
    return;
  }
  /* "triangles 3 and 5" when both names are a word and a number */
  const char *sp = strchr(nt, ' ');
  if (!pt && !pu && sp && strncmp(nt, nu, (size_t)(sp - nt) + 1) == 0)
    out(o, "%.*ss %s and %s", (int)(sp - nt), nt, sp + 1, strchr(nu, ' ') + 1);
  else
    out(o, "%s and %s", nt, nu);
  if (multi) out(o, " of input %u", it);
}

#define SHOWN 3

static void out_examples(outbuf *o, const mx_trisoup *s,
                         const mx_defect_example *ex, size_t count) {
  size_t m = count < SHOWN ? count : SHOWN;
  out(o, ", e.g. ");
  for (size_t i = 0; i < m; i++) {
    if (i) out(o, "; ");
    if (ex[i].v0 != NONE) out(o, "edge of ");
    out_tris(o, s, ex[i].tri, ex[i].other);
    out(o, " at (%g, %g, %g)", ex[i].p[0], ex[i].p[1], ex[i].p[2]);
  }
  if (count > m) out(o, "; ...");
  out(o, "\n");
}

void mx_surface_defects_describe(const mx_surface_defects *r,
                                 const mx_trisoup *s, char *buf, size_t n) {
  if (n == 0) return;
  buf[0] = '\0';
  outbuf o = {buf, n};
  if (mx_surface_defects_total(r) == 0) {
    out(&o, "no defects\n");
    return;
  }
  size_t c;
  if ((c = r->boundary_edges)) {
    out(&o, "%zu open edge%s (used by one triangle only)", c, c == 1 ? "" : "s");
    out_examples(&o, s, r->boundary, c);
  }
  if ((c = r->nonmanifold_edges)) {
    out(&o, "%zu non-manifold edge%s (used by more than two triangles)", c,
        c == 1 ? "" : "s");
    out_examples(&o, s, r->nonmanifold, c);
  }
  if ((c = r->misoriented_edges)) {
    out(&o,
        "%zu misoriented edge%s (used twice in the same direction: the two "
        "triangles' normals disagree)",
        c, c == 1 ? "" : "s");
    out_examples(&o, s, r->misoriented, c);
  }
  if ((c = r->intersecting_pairs)) {
    out(&o, "%zu pair%s of triangles of one input intersect%s (self-intersection",
        c, c == 1 ? "" : "s", c == 1 ? "s" : "");
    if (r->intersecting_bodies)
      out(&o, "; %zu of them between separate bodies", r->intersecting_bodies);
    out(&o, ")");
    out_examples(&o, s, r->intersecting, c);
  }
  if ((c = r->crossing_pairs)) {
    out(&o, "%zu pair%s of triangles of two inputs meet%s (the inputs cross or touch)",
        c, c == 1 ? "" : "s", c == 1 ? "s" : "");
    out_examples(&o, s, r->crossing, c);
  }
  if ((c = r->degenerate_triangles)) {
    out(&o, "%zu degenerate triangle%s (zero area)", c, c == 1 ? "" : "s");
    out_examples(&o, s, r->degenerate, c);
  }
}
