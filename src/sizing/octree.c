/* The octrees K_oL and K_oLB of the control space (Jurczyk & Glut 2016,
 * sections 2.6 and 2.7; layout in src/sizing/cspace.h): leaves keyed by
 * the Morton key of their lowest corner, built level by level (a level's
 * leaves judged in parallel on their N_s^3 samples, split in order); for
 * K_oLB, leaves with a face neighbour more than one level finer are split
 * too, and the new leaves judged again, until both hold. */
#include "sizing/cspace.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "base/common.h"
#include "base/morton.h"

typedef struct {
  size_t n, cap;
  uint64_t *key;
  uint8_t *level;
  double *h;
} leaves;

static int leaves_reserve(leaves *L, size_t n) {
  if (n <= L->cap) return MX_OK;
  size_t cap = L->cap ? L->cap : 1024;
  while (cap < n) cap *= 2;
  uint64_t *k = mx_realloc(L->key, cap * sizeof *k);
  if (k) L->key = k;
  uint8_t *l = mx_realloc(L->level, cap);
  if (l) L->level = l;
  double *h = mx_realloc(L->h, 3 * cap * sizeof *h);
  if (h) L->h = h;
  if (!k || !l || !h) return MX_ENOMEM;
  L->cap = cap;
  return MX_OK;
}

static void leaves_free(leaves *L) {
  mx_free(L->key);
  mx_free(L->level);
  mx_free(L->h);
  memset(L, 0, sizeof *L);
}

/* The box of cell (key, level) on the lattice of 2^D cells per axis. */
static void cell_box(const mx_cspace *c, uint64_t key, int level, double lo[3], double hi[3]) {
  uint32_t p[3];
  mx_morton_decode(key, p);
  const double n = ldexp(1.0, c->max_depth), side = ldexp(1.0, c->max_depth - level);
  for (int a = 0; a < 3; a++) {
    const double w = c->hi[a] - c->lo[a];
    lo[a] = c->lo[a] + w * (double)p[a] / n;
    hi[a] = c->lo[a] + w * ((double)p[a] + side) / n;
  }
}

/* Whether leaf i (its value h) is farther than delta from f on its
 * samples. bad: a size not finite and positive. */
static int too_far(const mx_cspace *c, mx_size_fn f, void *user, const double lo[3],
                   const double hi[3], const double h[3], double *xyz, double *fh, int *bad) {
  const size_t n = (size_t)c->ns * c->ns * c->ns;
  mx_cs_samples(lo, hi, c->ns, xyz);
  f(user, n, xyz, fh);
  if (!mx_cs_sizes_ok(fh, n)) {
    *bad = 1;
    return 0;
  }
  for (size_t s = 0; s < n; s++)
    if (mx_metric_nonconformity(fh + 3 * s, h) > c->delta) return 1;
  return 0;
}

/* Splits the marked leaves of L (mark[i]) into their 8 children, appended
 * to out in order, values at their centres from f. */
static int split_marked(const mx_cspace *c, mx_size_fn f, void *user, const leaves *L,
                        const uint8_t *mark, leaves *out) {
  size_t ns = 0;
  for (size_t i = 0; i < L->n; i++) ns += mark[i];
  out->n = 0;
  MX_CHECK(leaves_reserve(out, 8 * ns + 1));
  double *pts = mx_alloc((24 * ns + 3) * sizeof *pts);
  if (!pts) return MX_ENOMEM;
  for (size_t i = 0; i < L->n; i++) {
    if (!mark[i]) continue;
    const int l = L->level[i] + 1;
    for (int k = 0; k < 8; k++) {
      uint32_t p[3];
      mx_morton_decode(L->key[i], p);
      const uint32_t half = 1u << (c->max_depth - l);
      const uint64_t ck = mx_morton_encode(p[0] + (k & 1 ? half : 0), p[1] + (k & 2 ? half : 0),
                                           p[2] + (k & 4 ? half : 0));
      out->key[out->n] = ck;
      out->level[out->n] = (uint8_t)l;
      double lo[3], hi[3];
      cell_box(c, ck, l, lo, hi);
      for (int a = 0; a < 3; a++) pts[3 * out->n + a] = 0.5 * (lo[a] + hi[a]);
      out->n++;
    }
  }
  const int st = mx_cs_eval(f, user, out->n, pts, out->h);
  mx_free(pts);
  return st;
}

/* Adapts the leaves of `work` (new, not yet judged) until each is within
 * delta or at the depth limit; the final ones are appended to done. */
static int adapt(mx_cspace *c, mx_size_fn f, void *user, leaves *work, leaves *done) {
  leaves next = {0, 0, NULL, NULL, NULL};
  uint8_t *mark = NULL;
  int st = MX_OK;
  while (work->n && !st) {
    mx_free(mark);
    mark = mx_calloc(work->n + 1);
    if (!mark) {
      st = MX_ENOMEM;
      break;
    }
    int bad = 0, cap = 0, nomem = 0;
    const size_t ns3 = (size_t)c->ns * c->ns * c->ns;
#pragma omp parallel reduction(| : bad, cap, nomem)
    {
      double *xyz = mx_alloc(6 * ns3 * sizeof *xyz);
      if (!xyz) nomem = 1;
#pragma omp for schedule(dynamic, 16)
      for (size_t i = 0; i < work->n; i++) {
        if (!xyz) continue;
        double lo[3], hi[3];
        cell_box(c, work->key[i], work->level[i], lo, hi);
        int b = 0;
        const int far = too_far(c, f, user, lo, hi, work->h + 3 * i, xyz, xyz + 3 * ns3, &b);
        bad |= b;
        if (far && work->level[i] >= c->max_depth) cap = 1;
        else if (far) mark[i] = 1;
      }
      mx_free(xyz);
    }
    if (nomem || bad) {
      st = nomem ? MX_ENOMEM : mx_cs_bad_sizes(c);
      break;
    }
    c->capped |= cap;
    size_t keep = 0;
    for (size_t i = 0; i < work->n; i++) keep += !mark[i];
    st = leaves_reserve(done, done->n + keep);
    for (size_t i = 0; !st && i < work->n; i++) {
      if (mark[i]) continue;
      done->key[done->n] = work->key[i];
      done->level[done->n] = work->level[i];
      memcpy(done->h + 3 * done->n, work->h + 3 * i, 3 * sizeof *done->h);
      done->n++;
      if (work->level[i] > c->depth) c->depth = work->level[i];
    }
    if (!st) st = split_marked(c, f, user, work, mark, &next);
    leaves t = *work;
    *work = next;
    next = t;
  }
  mx_free(mark);
  leaves_free(&next);
  return st;
}

static int by_key(const void *a, const void *b) {
  const uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
  return x < y ? -1 : x > y;
}

/* Sorts the leaves by key (a permutation through 64-bit pairs: the keys
 * are unique). */
static int sort_leaves(leaves *L) {
  uint64_t *pair = mx_alloc((2 * L->n + 2) * sizeof *pair);
  leaves S = {0, 0, NULL, NULL, NULL};
  int st = pair ? leaves_reserve(&S, L->n + 1) : MX_ENOMEM;
  if (st) {
    mx_free(pair);
    leaves_free(&S);
    return st;
  }
  for (size_t i = 0; i < L->n; i++) {
    pair[2 * i] = L->key[i];
    pair[2 * i + 1] = i;
  }
  qsort(pair, L->n, 2 * sizeof *pair, by_key);
  for (size_t i = 0; i < L->n; i++) {
    const size_t j = (size_t)pair[2 * i + 1];
    S.key[i] = L->key[j];
    S.level[i] = L->level[j];
    memcpy(S.h + 3 * i, L->h + 3 * j, 3 * sizeof *S.h);
  }
  S.n = L->n;
  mx_free(pair);
  leaves_free(L);
  *L = S;
  return MX_OK;
}

/* The index of the leaf holding lattice cell p (coordinates in range). */
static size_t find_leaf(const uint64_t *key, size_t n, const uint32_t p[3]) {
  const uint64_t k = mx_morton_encode(p[0], p[1], p[2]);
  size_t a = 0, b = n; /* the last key <= k */
  while (b - a > 1) {
    const size_t m = a + (b - a) / 2;
    if (key[m] <= k) a = m;
    else b = m;
  }
  return a;
}

/* Marks the leaves that a face neighbour more than one level finer forces
 * to split; returns how many. */
static size_t unbalanced(const mx_cspace *c, const leaves *L, uint8_t *mark) {
  const uint32_t n = 1u << c->max_depth;
  memset(mark, 0, L->n);
#pragma omp parallel for schedule(static)
  for (size_t i = 0; i < L->n; i++) {
    uint32_t p[3];
    mx_morton_decode(L->key[i], p);
    const uint32_t side = 1u << (c->max_depth - L->level[i]);
    for (int d = 0; d < 6; d++) {
      const int a = d / 2;
      uint32_t q[3] = {p[0], p[1], p[2]};
      if (d & 1) {
        if (p[a] + side >= n) continue;
        q[a] = p[a] + side;
      } else {
        if (p[a] == 0) continue;
        q[a] = p[a] - 1;
      }
      const size_t j = find_leaf(L->key, L->n, q);
      if (L->level[j] + 1 < L->level[i]) __atomic_store_n(&mark[j], 1, __ATOMIC_RELAXED);
    }
  }
  size_t m = 0;
  for (size_t i = 0; i < L->n; i++) m += mark[i];
  return m;
}

int mx_cs_build_octree(mx_cspace *c, mx_size_fn f, void *user) {
  leaves work = {0, 0, NULL, NULL, NULL}, done = {0, 0, NULL, NULL, NULL};
  int st = leaves_reserve(&work, 1);
  if (!st) {
    double p[3];
    for (int a = 0; a < 3; a++) p[a] = 0.5 * (c->lo[a] + c->hi[a]);
    work.key[0] = 0;
    work.level[0] = 0;
    work.n = 1;
    st = mx_cs_eval(f, user, 1, p, work.h);
  }
  if (!st) st = adapt(c, f, user, &work, &done);
  if (!st) st = sort_leaves(&done);
  /* K_oLB: split the leaves too coarse for a face neighbour, judge their
   * children, until none is */
  uint8_t *mark = NULL;
  while (!st && c->structure == MX_CS_OCT_BALANCED) {
    mx_free(mark);
    mark = mx_alloc(done.n + 1);
    if (!mark) {
      st = MX_ENOMEM;
      break;
    }
    if (!unbalanced(c, &done, mark)) break;
    st = split_marked(c, f, user, &done, mark, &work);
    size_t w = 0;
    for (size_t i = 0; !st && i < done.n; i++) {
      if (mark[i]) continue;
      done.key[w] = done.key[i];
      done.level[w] = done.level[i];
      memcpy(done.h + 3 * w, done.h + 3 * i, 3 * sizeof *done.h);
      w++;
    }
    done.n = w;
    if (!st) st = adapt(c, f, user, &work, &done);
    if (!st) st = sort_leaves(&done);
  }
  mx_free(mark);
  leaves_free(&work);
  if (st) {
    leaves_free(&done);
    return st;
  }
  c->key = done.key;
  c->level = done.level;
  c->h = done.h;
  c->nleaves = c->nvalues = done.n;
  return MX_OK;
}

/* The lattice cell of p (clamped into the box). */
static void cell_of(const mx_cspace *c, const double p[3], uint32_t q[3]) {
  const double n = ldexp(1.0, c->max_depth);
  for (int a = 0; a < 3; a++) {
    const double t = (p[a] - c->lo[a]) / (c->hi[a] - c->lo[a]) * n;
    q[a] = t <= 0.0 ? 0u : t >= n - 1.0 ? (uint32_t)n - 1u : (uint32_t)t;
  }
}

void mx_cs_query_octree(const mx_cspace *c, const double p[3], double h[3]) {
  uint32_t q[3];
  cell_of(c, p, q);
  const size_t i = find_leaf(c->key, c->nleaves, q);
  memcpy(h, c->h + 3 * i, 3 * sizeof *h);
}

double mx_cs_min_box_octree(const mx_cspace *c, const double lo[3], const double hi[3]) {
  uint32_t a[3], b[3];
  cell_of(c, lo, a);
  cell_of(c, hi, b);
  /* the leaves meeting the cells a..b: from the root down, a cell whose
   * anchor's leaf is at its level or coarser is that leaf */
  struct { uint32_t p[3]; int l; } stack[8 * 22];
  int top = 0;
  double best = INFINITY;
  stack[top].p[0] = stack[top].p[1] = stack[top].p[2] = 0;
  stack[top++].l = 0;
  while (top) {
    const uint32_t *p = stack[--top].p;
    const int l = stack[top].l;
    const uint32_t pp[3] = {p[0], p[1], p[2]};
    const size_t i = find_leaf(c->key, c->nleaves, pp);
    if (c->level[i] <= l) {
      for (int k = 0; k < 3; k++) best = fmin(best, c->h[3 * i + k]);
      continue;
    }
    const uint32_t half = 1u << (c->max_depth - l - 1);
    for (int k = 7; k >= 0; k--) {
      uint32_t q[3];
      int meet = 1;
      for (int d = 0; d < 3; d++) {
        q[d] = pp[d] + ((k >> d) & 1 ? half : 0);
        meet &= q[d] <= b[d] && q[d] + half > a[d];
      }
      if (!meet || top >= 8 * 22) continue;
      memcpy(stack[top].p, q, sizeof q);
      stack[top++].l = l + 1;
    }
  }
  return best;
}

size_t mx_cs_leaves_octree(const mx_cspace *c, double *box, double *h) {
  for (size_t i = 0; box && i < c->nleaves; i++) {
    cell_box(c, c->key[i], c->level[i], box + 6 * i, box + 6 * i + 3);
    h[i] = fmin(c->h[3 * i], fmin(c->h[3 * i + 1], c->h[3 * i + 2]));
  }
  return c->nleaves;
}
