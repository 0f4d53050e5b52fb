/* The binary BVH over triangles: the median-split build of the surface
 * index and the Morton build of the broad phase; see bvh.h. */
#include "geom/bvh.h"

#include <math.h>
#include <string.h>

#include "base/common.h"

#define LEAF_MAX MX_BVH_LEAF_MAX
#define TASK_MIN 16384 /* subtrees at least this big become tasks */

/* Leaves of a subtree of m >= 1 triangles (a node of more than LEAF_MAX
 * gives floor(m/2) to the left child, the rest to the right); returns L(m)
 * and sets *next to L(m + 1), carried together so the recursion is a
 * chain of log2(m) calls. */
static size_t leaf_pair(size_t m, size_t *next) {
  if (m + 1 <= LEAF_MAX) {
    *next = 1;
    return 1;
  }
  if (m <= LEAF_MAX) { /* m == LEAF_MAX: m + 1 splits once more */
    size_t a, b;
    a = leaf_pair((m + 1) / 2, &b);
    *next = (m + 1) % 2 ? a + b : 2 * a;
    return 1;
  }
  size_t a, b; /* L(k), L(k + 1) */
  const size_t k = m / 2;
  a = leaf_pair(k, &b);
  if (m % 2 == 0) {
    *next = a + b;
    return 2 * a;
  }
  *next = 2 * b;
  return a + b;
}

size_t mx_bvh_node_count(size_t m) {
  size_t next;
  return 2 * leaf_pair(m, &next) - 1;
}

/* Reorders a[0..n) so that a[k] holds the element of rank k by key[a[.]],
 * smaller keys before, larger after (Hoare partitions, median of three). */
static void select_nth(uint32_t *a, int64_t n, int64_t k, const double *key) {
  int64_t lo = 0, hi = n - 1;
  while (hi > lo) {
    const int64_t mid = lo + (hi - lo) / 2;
    double x0 = key[a[lo]], x1 = key[a[mid]], x2 = key[a[hi]];
    const double x = mx_max(mx_min(x0, x1), mx_min(mx_max(x0, x1), x2));
    int64_t i = lo, j = hi;
    while (i <= j) {
      while (key[a[i]] < x) i++;
      while (key[a[j]] > x) j--;
      if (i <= j) {
        const uint32_t t = a[i];
        a[i] = a[j];
        a[j] = t;
        i++;
        j--;
      }
    }
    if (k <= j)
      hi = j;
    else if (k >= i)
      lo = i;
    else
      return;
  }
}

typedef struct {
  mx_bvh_node *nodes;
  uint32_t *idx;      /* slot -> triangle */
  const double *cen;  /* 3 nt centroids, SoA: cen[a * nt + t] */
  uint32_t nt;
  const uint32_t *tri;
  const double *co[3];
} build_ctx;

static void build_node(const build_ctx *B, uint32_t node, uint32_t first,
                       uint32_t m, uint32_t base) {
  const double *const *co = B->co;
  mx_bvh_node *N = &B->nodes[node];
  double clo[3] = {INFINITY, INFINITY, INFINITY},
         chi[3] = {-INFINITY, -INFINITY, -INFINITY};
  for (int a = 0; a < 3; a++) {
    N->lo[a] = INFINITY;
    N->hi[a] = -INFINITY;
  }
  for (uint32_t i = first; i < first + m; i++) {
    const uint32_t t = B->idx[i];
    const uint32_t *v = B->tri + 3 * (size_t)t;
    for (int a = 0; a < 3; a++) {
      for (int k = 0; k < 3; k++) {
        N->lo[a] = mx_min(N->lo[a], co[a][v[k]]);
        N->hi[a] = mx_max(N->hi[a], co[a][v[k]]);
      }
      const double c = B->cen[(size_t)a * B->nt + t];
      clo[a] = mx_min(clo[a], c);
      chi[a] = mx_max(chi[a], c);
    }
  }
  N->ntri = m;
  N->pad_ = 0;
  if (m <= LEAF_MAX) {
    N->first = first;
    N->count = m;
    return;
  }
  int axis = 0;
  for (int a = 1; a < 3; a++)
    if (chi[a] - clo[a] > chi[axis] - clo[axis]) axis = a;
  const uint32_t ml = m / 2;
  select_nth(B->idx + first, m, ml, B->cen + (size_t)axis * B->nt);
  N->first = base;
  N->count = 0;
  const uint32_t lbase = base + 2;
  const uint32_t rbase = lbase + (uint32_t)(mx_bvh_node_count(ml) - 1);
#pragma omp task if (m >= TASK_MIN) default(none) firstprivate(B, base, first, ml, lbase)
  build_node(B, base, first, ml, lbase);
  build_node(B, base + 1, first + ml, m - ml, rbase);
}

void mx_bvh_build(mx_bvh_node *nodes, uint32_t *idx, const double *cen, uint32_t nt,
                  const uint32_t *tri, const double *x, const double *y,
                  const double *z) {
  build_ctx B = {nodes, idx, cen, nt, tri, {x, y, z}};
  const build_ctx *bp = &B;
#pragma omp parallel if (nt >= TASK_MIN) default(none) shared(bp, nt)
#pragma omp single
  build_node(bp, 0, 0, nt, 1);
}

/* ---- the Morton tree ---------------------------------------------------- */

/* The first place in [l, r) whose code has the highest bit where code[l]
 * and code[r - 1] differ (the middle when they are equal). */
static uint32_t split_at(const uint32_t *code, uint32_t l, uint32_t r) {
  uint32_t x = code[l] ^ code[r - 1];
  if (x == 0) return l + (r - l) / 2;
  uint32_t mask = 1u << (31 - __builtin_clz(x));
  uint32_t lo = l, hi = r - 1; /* code[lo] lacks the bit, code[hi] has it */
  while (hi - lo > 1) {
    uint32_t m = lo + (hi - lo) / 2;
    if (code[m] & mask) hi = m;
    else lo = m;
  }
  return hi;
}

typedef struct {
  mx_bvh_node *nodes;
  const uint32_t *code;
  const double *box;
  uint32_t nn;
} morton_ctx;

static void morton_node(morton_ctx *M, uint32_t id, uint32_t l, uint32_t r) {
  mx_bvh_node *nd = &M->nodes[id];
  nd->ntri = r - l;
  nd->pad_ = 0;
  if (r - l <= LEAF_MAX) {
    const double *box = M->box;
    nd->first = l;
    nd->count = r - l;
    for (int a = 0; a < 3; a++) {
      nd->lo[a] = box[6 * (size_t)l + a];
      nd->hi[a] = box[6 * (size_t)l + 3 + a];
    }
    for (uint32_t i = l + 1; i < r; i++)
      for (int a = 0; a < 3; a++) {
        nd->lo[a] = mx_min(nd->lo[a], box[6 * (size_t)i + a]);
        nd->hi[a] = mx_max(nd->hi[a], box[6 * (size_t)i + 3 + a]);
      }
    return;
  }
  const uint32_t mid = split_at(M->code, l, r), c = M->nn;
  M->nn += 2;
  nd->first = c;
  nd->count = 0;
  morton_node(M, c, l, mid);
  morton_node(M, c + 1, mid, r);
  const mx_bvh_node *L = &M->nodes[c], *R = &M->nodes[c + 1];
  nd = &M->nodes[id];
  for (int a = 0; a < 3; a++) {
    nd->lo[a] = mx_min(L->lo[a], R->lo[a]);
    nd->hi[a] = mx_max(L->hi[a], R->hi[a]);
  }
}

uint32_t mx_bvh_build_morton(mx_bvh_node *nodes, const uint32_t *code, const double *box,
                             uint32_t n) {
  morton_ctx M = {nodes, code, box, 1};
  morton_node(&M, 0, 0, n);
  return M.nn;
}

int mx_morton_sort30(uint32_t *code, uint32_t *order, uint32_t n) {
  uint32_t *k2 = mx_alloc(((size_t)n + 1) * sizeof *k2);
  uint32_t *o2 = mx_alloc(((size_t)n + 1) * sizeof *o2);
  if (!k2 || !o2) {
    mx_free(k2);
    mx_free(o2);
    return MX_ENOMEM;
  }
  uint32_t *src_k = code, *src_o = order, *dst_k = k2, *dst_o = o2;
  for (int pass = 0; pass < 3; pass++) {
    size_t cnt[1025] = {0};
    const int sh = 10 * pass;
    for (uint32_t i = 0; i < n; i++) cnt[((src_k[i] >> sh) & 1023) + 1]++;
    for (int b = 0; b < 1024; b++) cnt[b + 1] += cnt[b];
    for (uint32_t i = 0; i < n; i++) {
      const size_t d = cnt[(src_k[i] >> sh) & 1023]++;
      dst_k[d] = src_k[i];
      dst_o[d] = src_o[i];
    }
    uint32_t *tk = src_k, *to = src_o;
    src_k = dst_k, src_o = dst_o, dst_k = tk, dst_o = to;
  }
  /* after 3 passes the result is in k2, o2 */
  memcpy(code, src_k, (size_t)n * sizeof *code);
  memcpy(order, src_o, (size_t)n * sizeof *order);
  mx_free(k2);
  mx_free(o2);
  return MX_OK;
}

