/* Algorithm 1 in 2D (Jaillet & Lobos 2021, section 3.1): the root grid,
 * then level by level the candidates the requests want split are split;
 * after each level's splits the neighbours they made unbalanced are split
 * (found through the edge infos, qedges.c; a split may push more) before the
 * next level. With MX_QBALANCE_RECURSIVE all levels are refined first, then
 * the classic neighbour search (qbalance_recursive.c) splits until balanced.
 *
 * A split quadrant's 4 children are made in one go: the domain segments
 * each meets (a CSR slice of the parent's: children test only their
 * parent's segments), likewise the segments of the region and drawing
 * requests, whether it lies outside the domain (MX_Q_OUT: no segment and its
 * centre outside), and its target level. Children of a list of splits are
 * numbered by the list's order (4 per split), their slices by prefix sums:
 * the tree is the same whatever the thread count. */
#include <math.h>
#include <string.h>

#include "base/common.h"
#include "quad/quad.h"
#include "base/scan.h"
#include "sizing/cspace.h"

/* Small loops run on one thread: a parallel region costs more than them. */
#define PAR(n) ((n) > 4096)

#define NONE UINT32_MAX

typedef struct {
  const mx_poly *dom;
  const mx_poly_index *I;
  const mx_qrequests *req;
  mx_qtree *T;
  double *dseg;     /* 4 per domain segment: ax ay bx by */
  size_t nrs;       /* request segments: the regions', then the drawings' */
  double *rseg;     /* 4 per request segment */
  uint8_t *rlev;    /* its request's level */
  uint32_t *rreg;   /* its region, NONE for a drawing */
  mx_poly_index *ridx;
  uint32_t *rq_off, *rq_cnt; /* per quadrant: CSR slice of rq_pool */
  uint8_t *rin;     /* per quadrant: highest level of the regions it lies inside */
  uint32_t *rq_pool;
  size_t rq_n, rq_cap, nroots;
  mx_qedges *E;
  mx_qstats st;
} qbuild;

/* ---- geometry ------------------------------------------------------------ */

static void qbox(const mx_qgrid *g, uint64_t key, int level, double lo[2], double hi[2]) {
  uint32_t x, y;
  mx_qkey_xy(key, &x, &y);
  const uint32_t s = mx_qsize(level);
  lo[0] = g->origin[0] + g->unit * (double)x;
  lo[1] = g->origin[1] + g->unit * (double)y;
  hi[0] = g->origin[0] + g->unit * (double)(x + s);
  hi[1] = g->origin[1] + g->unit * (double)(y + s);
}

/* Closed test: the segment meets the box unless their bounding boxes are
 * apart or the 4 corners lie strictly on one side of its line. */
static int seg_meets_box(const double *s, const double lo[2], const double hi[2]) {
  if (fmax(s[0], s[2]) < lo[0] || fmin(s[0], s[2]) > hi[0] || fmax(s[1], s[3]) < lo[1] ||
      fmin(s[1], s[3]) > hi[1])
    return 0;
  const double dx = s[2] - s[0], dy = s[3] - s[1];
  int pos = 0, neg = 0;
  for (int c = 0; c < 4; c++) {
    const double px = (c & 1) ? hi[0] : lo[0], py = (c & 2) ? hi[1] : lo[1];
    const double v = dx * (py - s[1]) - dy * (px - s[0]);
    pos += v > 0;
    neg += v < 0;
  }
  return pos < 4 && neg < 4;
}

static int box_meets_box(const double lo[2], const double hi[2], const mx_qbox *b) {
  return lo[0] <= b->hi[0] && hi[0] >= b->lo[0] && lo[1] <= b->hi[1] && hi[1] >= b->lo[1];
}

/* The zero set of f within half the box's diagonal of its centre (exact
 * distance for the circle and the line; for the sine a lower bound, |f| over
 * its Lipschitz constant), or a sign change at the corners and centre. The
 * distance test keeps the rule monotone: a child passes only if its parent
 * does. */
static double fun_value(const mx_qfun *f, double x, double y, double *dist) {
  const double *a = f->a;
  if (f->kind == MX_QFUN_CIRCLE) {
    const double r = hypot(x - a[0], y - a[1]);
    *dist = fabs(r - a[2]);
    return (r - a[2]) * (r + a[2]);
  }
  if (f->kind == MX_QFUN_LINE) {
    const double v = (x - a[0]) * a[2] + (y - a[1]) * a[3], n = hypot(a[2], a[3]);
    *dist = n > 0 ? fabs(v) / n : INFINITY;
    return v;
  }
  const double v = y - (a[3] + a[0] * sin(a[1] * x + a[2]));
  *dist = fabs(v) / sqrt(1.0 + a[0] * a[1] * a[0] * a[1]);
  return v;
}

double mx_qfun_distance(const mx_qfun *f, double x, double y) {
  double d;
  (void)fun_value(f, x, y, &d);
  return d;
}

static int fun_crosses(const mx_qfun *f, const double lo[2], const double hi[2]) {
  const double cx = 0.5 * (lo[0] + hi[0]), cy = 0.5 * (lo[1] + hi[1]);
  double d, dc;
  const double vc = fun_value(f, cx, cy, &dc);
  if (dc <= 0.5 * hypot(hi[0] - lo[0], hi[1] - lo[1])) return 1;
  for (int c = 0; c < 4; c++) {
    const double v = fun_value(f, (c & 1) ? hi[0] : lo[0], (c & 2) ? hi[1] : lo[1], &d);
    if (v == 0.0 || (v < 0) != (vc < 0)) return 1;
  }
  return 0;
}

/* ---- targets ------------------------------------------------------------- */

/* The level whose quadrants are no larger than the field's least size over
 * the box [lo, hi] (roots of side `root`); 0 without a field. */
static int field_level(const mx_qrequests *R, double root, const double lo[2],
                       const double hi[2]) {
  if (!R->size_field) return 0;
  const double blo[3] = {lo[0], lo[1], 0.0}, bhi[3] = {hi[0], hi[1], 0.0};
  return mx_cs_level(root, mx_cspace_min_box(R->size_field, blo, bhi), MX_QMAX_LEVEL - 1);
}

/* The highest level the kept leaves anchored in the quadrant (key, level)
 * ask for: a binary search for the first, then a walk over the quadrant's
 * key range (each kept leaf is walked once per level above it). */
static int keep_target(const mx_qrequests *R, uint64_t key, int level) {
  const uint64_t end = key + ((uint64_t)1 << (2 * (MX_QMAX_LEVEL - level)));
  size_t lo = 0, hi = R->nkeep;
  while (lo < hi) {
    const size_t mid = lo + (hi - lo) / 2;
    if (R->keep_key[mid] < key) lo = mid + 1;
    else hi = mid;
  }
  int t = 0;
  for (size_t i = lo; i < R->nkeep && R->keep_key[i] < end; i++)
    if (R->keep_level[i] > t) t = R->keep_level[i];
  return t;
}

/* The highest level the requests ask of quadrant q (its flags, slices and
 * rin already set), never above its parent's (the requests are monotone;
 * this makes it exact under rounding too, so no quadrant split for balance
 * ever has children the requests want split). */
static uint8_t target_of(const qbuild *B, uint32_t q, const double lo[2], const double hi[2]) {
  const mx_qtree *T = B->T;
  const mx_qrequests *R = B->req;
  if (T->flags[q] & MX_Q_OUT) return T->level[q];
  int t = R->a_level;
  if ((T->flags[q] & MX_Q_BOUND) && R->s_level > t) t = R->s_level;
  for (size_t b = 0; b < R->nboxes; b++)
    if (R->boxes[b].level > t && box_meets_box(lo, hi, &R->boxes[b])) t = R->boxes[b].level;
  if (B->nrs) {
    const uint32_t *s = B->rq_pool + B->rq_off[q];
    for (uint32_t i = 0; i < B->rq_cnt[q]; i++)
      if (B->rlev[s[i]] > t) t = B->rlev[s[i]];
  }
  if (B->rin && B->rin[q] > t) t = B->rin[q];
  for (size_t f = 0; f < R->nfuns; f++)
    if (R->funs[f].level > t && fun_crosses(&R->funs[f], lo, hi)) t = R->funs[f].level;
  const int fl = field_level(R, T->grid.side, lo, hi);
  if (fl > t) t = fl;
  if (R->nkeep) {
    const int k = keep_target(R, T->key[q], T->level[q]);
    if (k > t) t = k;
  }
  const uint32_t p = T->parent[q];
  if (p != NONE && t > T->target[p]) t = T->target[p];
  return (uint8_t)(t > T->level[q] ? t : T->level[q]);
}

/* ---- arrays -------------------------------------------------------------- */

static int grow(void **p, size_t n, size_t elem) {
  void *q = mx_realloc(*p, (n ? n : 1) * elem);
  if (!q) return MX_ENOMEM;
  *p = q;
  return MX_OK;
}

/* Room for `need` quadrants, in the tree and in the builder's arrays. */
static int reserve_quadrants(qbuild *B, size_t need) {
  mx_qtree *T = B->T;
  if (need <= T->cap) return MX_OK;
  size_t cap = T->cap + T->cap / 2;
  if (cap < need) cap = need;
  if (cap < 1024) cap = 1024;
  MX_CHECK(grow((void **)&T->key, cap, sizeof *T->key));
  MX_CHECK(grow((void **)&T->level, cap, 1));
  MX_CHECK(grow((void **)&T->flags, cap, 1));
  MX_CHECK(grow((void **)&T->target, cap, 1));
  MX_CHECK(grow((void **)&T->parent, cap, sizeof *T->parent));
  MX_CHECK(grow((void **)&T->child0, cap, sizeof *T->child0));
  MX_CHECK(grow((void **)&T->seg_off, cap, sizeof *T->seg_off));
  MX_CHECK(grow((void **)&T->seg_cnt, cap, sizeof *T->seg_cnt));
  if (B->nrs) {
    MX_CHECK(grow((void **)&B->rq_off, cap, sizeof *B->rq_off));
    MX_CHECK(grow((void **)&B->rq_cnt, cap, sizeof *B->rq_cnt));
  }
  if (B->ridx && B->nrs) MX_CHECK(grow((void **)&B->rin, cap, 1));
  T->cap = cap;
  return MX_OK;
}

/* Room for `extra` more ids in a pool whose offsets are 32-bit. */
static int reserve_pool(uint32_t **pool, size_t used, size_t *cap, size_t extra) {
  if (used + extra >= UINT32_MAX) {
    mx_error(NULL, 0, "too many segment crossings for the quadtree (%zu)", used + extra);
    return MX_EINPUT;
  }
  if (used + extra <= *cap) return MX_OK;
  size_t c = *cap + *cap / 2;
  if (c < used + extra) c = used + extra;
  MX_CHECK(grow((void **)pool, c, sizeof **pool));
  *cap = c;
  return MX_OK;
}

/* ---- one quadrant's side of the domain and of the regions ---------------- */

/* Which of the children in `need` (meeting no domain segment, their parent
 * meeting some) lie inside the domain: one point query per group of
 * edge-adjacent such children (they lie on the same side). */
static unsigned children_inside(const mx_poly_index *I, unsigned need, const double c[4][2]) {
  unsigned inside = 0, done = 0;
  for (int k = 0; k < 4; k++) {
    if (!((need >> k) & 1) || ((done >> k) & 1)) continue;
    unsigned group = 1u << k;
    for (int it = 0; it < 2; it++) /* a 2 x 2 block: two sweeps close it */
      for (int j = 0; j < 4; j++)
        if ((group >> j) & 1) group |= need & ((1u << (j ^ 1)) | (1u << (j ^ 2)));
    done |= group;
    if (mx_poly_inside(I, c[k]) != 0) inside |= group;
  }
  return inside;
}

/* rin of child q of p: p's, raised by the regions p crosses and q does not
 * cross but lies inside. p's slice is sorted, so a region's segments are a
 * run of it. */
static void child_regions(qbuild *B, uint32_t p, uint32_t q, const uint8_t *mask, int c,
                          const double ctr[2]) {
  uint8_t r = B->rin[p];
  const uint32_t *s = B->rq_pool + B->rq_off[p];
  for (uint32_t i = 0, n = B->rq_cnt[p]; i < n;) {
    const uint32_t reg = B->rreg[s[i]];
    int crossed = 0;
    uint32_t j = i;
    for (; j < n && B->rreg[s[j]] == reg; j++) crossed |= (mask[j] >> c) & 1;
    if (reg != NONE && !crossed && B->rlev[s[i]] > r && mx_poly_inside(&B->ridx[reg], ctr))
      r = B->rlev[s[i]];
    i = j;
  }
  B->rin[q] = r;
}

/* ---- splitting ------------------------------------------------------------ */

static void child_boxes(const mx_qtree *T, uint32_t p, double lo[4][2], double hi[4][2]) {
  const int l = T->level[p] + 1;
  for (int c = 0; c < 4; c++) {
    const uint64_t k = T->key[p] | ((uint64_t)c << (2 * (MX_QMAX_LEVEL - l)));
    qbox(&T->grid, k, l, lo[c], hi[c]);
  }
}

/* Per segment of a parent's slice, the mask of the children it meets;
 * returns the number of (child, segment) pairs. */
static uint64_t slice_masks(const double *seg, const uint32_t *slice, uint32_t n,
                            double lo[4][2], double hi[4][2], uint8_t *mask) {
  uint64_t total = 0;
  const double mx = hi[0][0], my = hi[0][1]; /* the parent's middle */
  for (uint32_t i = 0; i < n; i++) {
    const double *s = seg + 4 * (size_t)slice[i];
    unsigned cand = 0xf;
    if (fmin(s[0], s[2]) > mx) cand &= 0xa;
    if (fmax(s[0], s[2]) < mx) cand &= 0x5;
    if (fmin(s[1], s[3]) > my) cand &= 0xc;
    if (fmax(s[1], s[3]) < my) cand &= 0x3;
    uint8_t m = 0;
    for (int c = 0; c < 4; c++)
      if (((cand >> c) & 1) && seg_meets_box(s, lo[c], hi[c])) m |= (uint8_t)(1u << c);
    mask[i] = m;
    total += (uint64_t)__builtin_popcount(m);
  }
  return total;
}

/* The children's slices from the parent's and the masks, from pool[at]. */
static void slice_fill(const uint32_t *slice, uint32_t n, const uint8_t *mask, uint32_t *pool,
                       uint64_t at, uint32_t off[4], uint32_t cnt[4]) {
  for (int c = 0; c < 4; c++) {
    cnt[c] = 0;
    for (uint32_t i = 0; i < n; i++) cnt[c] += (mask[i] >> c) & 1;
  }
  for (int c = 0; c < 4; c++) {
    off[c] = (uint32_t)at;
    for (uint32_t i = 0; i < n; i++)
      if ((mask[i] >> c) & 1) pool[at++] = slice[i];
  }
}

typedef struct {
  uint64_t *moff, *roff; /* per split: offsets of its masks */
  uint64_t *doff, *qoff; /* per split: offsets of its children's slices */
  uint8_t *dmask, *rmask;
} split_scratch;

/* The 4 children of p (the i-th split) at child0 = base. */
static void make_children(qbuild *B, const split_scratch *S, size_t i, uint32_t p, uint32_t base) {
  mx_qtree *T = B->T;
  const int l = T->level[p] + 1;
  double lo[4][2], hi[4][2], ctr[4][2];
  child_boxes(T, p, lo, hi);
  uint32_t off[4], cnt[4], roff[4], rcnt[4];
  slice_fill(T->seg_pool + T->seg_off[p], T->seg_cnt[p], S->dmask + S->moff[i], T->seg_pool,
             S->doff[i], off, cnt);
  if (B->nrs)
    slice_fill(B->rq_pool + B->rq_off[p], B->rq_cnt[p], S->rmask + S->roff[i], B->rq_pool,
               S->qoff[i], roff, rcnt);
  unsigned need = 0;
  for (int c = 0; c < 4; c++) {
    const uint32_t q = base + (uint32_t)c;
    ctr[c][0] = 0.5 * (lo[c][0] + hi[c][0]);
    ctr[c][1] = 0.5 * (lo[c][1] + hi[c][1]);
    T->key[q] = T->key[p] | ((uint64_t)c << (2 * (MX_QMAX_LEVEL - l)));
    T->level[q] = (uint8_t)l;
    T->parent[q] = p;
    T->child0[q] = NONE;
    T->seg_off[q] = off[c];
    T->seg_cnt[q] = cnt[c];
    T->flags[q] = cnt[c] ? MX_Q_BOUND : 0;
    if (!cnt[c] && (T->flags[p] & MX_Q_BOUND)) need |= 1u << c;
    if (B->nrs) {
      B->rq_off[q] = roff[c];
      B->rq_cnt[q] = rcnt[c];
    }
  }
  const unsigned in = need ? children_inside(B->I, need, ctr) : 0;
  for (int c = 0; c < 4; c++) {
    const uint32_t q = base + (uint32_t)c;
    if (((need & ~in) >> c) & 1) T->flags[q] |= MX_Q_OUT;
    if (B->rin) {
      if (T->flags[q] & MX_Q_OUT) B->rin[q] = 0;
      else child_regions(B, p, q, S->rmask + S->roff[i], c, ctr[c]);
    }
    T->target[q] = target_of(B, q, lo[c], hi[c]);
  }
  T->child0[p] = base;
  T->flags[p] = (uint8_t)((T->flags[p] | MX_Q_SPLIT) & ~MX_Q_QUEUED);
}

/* Masks of the parents' slices, their counts and prefix sums. */
static int split_masks(qbuild *B, const uint32_t *list, size_t n, split_scratch *S) {
  mx_qtree *T = B->T;
#pragma omp parallel for schedule(static) if (PAR(n))
  for (size_t i = 0; i < n; i++) {
    S->moff[i] = T->seg_cnt[list[i]];
    S->roff[i] = B->nrs ? B->rq_cnt[list[i]] : 0;
  }
  const uint64_t nm = mx_scan_u64(S->moff, n), nr = mx_scan_u64(S->roff, n);
  S->dmask = mx_alloc(nm + 1);
  S->rmask = mx_alloc(nr + 1);
  if (!S->dmask || !S->rmask) return MX_ENOMEM;
#pragma omp parallel for schedule(dynamic, 256) if (PAR(n))
  for (size_t i = 0; i < n; i++) {
    const uint32_t p = list[i];
    double lo[4][2], hi[4][2];
    child_boxes(T, p, lo, hi);
    S->doff[i] = slice_masks(B->dseg, T->seg_pool + T->seg_off[p], T->seg_cnt[p], lo, hi,
                             S->dmask + S->moff[i]);
    S->qoff[i] = B->nrs ? slice_masks(B->rseg, B->rq_pool + B->rq_off[p], B->rq_cnt[p], lo,
                                      hi, S->rmask + S->roff[i])
                        : 0;
  }
  const uint64_t nd = mx_scan_u64(S->doff, n), nq = mx_scan_u64(S->qoff, n);
  const uint64_t d0 = T->seg_n, q0 = B->rq_n;
#pragma omp parallel for schedule(static) if (PAR(n))
  for (size_t i = 0; i < n; i++) {
    S->doff[i] += d0;
    S->qoff[i] += q0;
  }
  MX_CHECK(reserve_pool(&T->seg_pool, T->seg_n, &T->seg_cap, nd));
  MX_CHECK(reserve_pool(&B->rq_pool, B->rq_n, &B->rq_cap, nq));
  T->seg_n += nd;
  B->rq_n += nq;
  return MX_OK;
}

/* Split the leaves of `list` (children numbered in list order); with edge
 * infos, the list is of one level and the children are registered. */
static int split_list(qbuild *B, const uint32_t *list, size_t n, int for_balance) {
  if (n == 0) return MX_OK;
  mx_qtree *T = B->T;
  const size_t n0 = T->n;
  if (n0 + 4 * n >= UINT32_MAX) {
    mx_error(NULL, 0, "too many quadrants (%zu)", n0 + 4 * n);
    return MX_EINPUT;
  }
  MX_CHECK(reserve_quadrants(B, n0 + 4 * n));
  split_scratch S = {0};
  S.moff = mx_alloc(4 * (n + 1) * sizeof(uint64_t));
  int st = S.moff ? MX_OK : MX_ENOMEM;
  if (!st) {
    S.roff = S.moff + (n + 1);
    S.doff = S.roff + (n + 1);
    S.qoff = S.doff + (n + 1);
    st = split_masks(B, list, n, &S);
  }
  if (!st) {
#pragma omp parallel for schedule(dynamic, 256) if (PAR(n))
    for (size_t i = 0; i < n; i++) make_children(B, &S, i, list[i], (uint32_t)(n0 + 4 * i));
    T->n = n0 + 4 * n;
    B->st.splits += n;
    if (for_balance) B->st.balance_splits += n;
    if (B->E) st = mx_qedges_add_children(B->E, T, list, n);
  }
  mx_free(S.moff);
  mx_free(S.dmask);
  mx_free(S.rmask);
  return st;
}

/* ---- the roots ------------------------------------------------------------ */

/* The segments of seg[0..n) meeting the box, appended to the pool. */
static int root_slice(const double *seg, size_t n, const double lo[2], const double hi[2],
                      uint32_t **pool, size_t *used, size_t *cap, uint32_t *off, uint32_t *cnt) {
  MX_CHECK(reserve_pool(pool, *used, cap, n));
  *off = (uint32_t)*used;
  for (size_t s = 0; s < n; s++)
    if (seg_meets_box(seg + 4 * s, lo, hi)) (*pool)[(*used)++] = (uint32_t)s;
  *cnt = (uint32_t)(*used - *off);
  return MX_OK;
}

static int make_root(qbuild *B, uint32_t r, uint64_t key) {
  mx_qtree *T = B->T;
  double lo[2], hi[2];
  qbox(&T->grid, key, 0, lo, hi);
  const double ctr[2] = {0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1])};
  T->key[r] = key;
  T->level[r] = 0;
  T->parent[r] = T->child0[r] = NONE;
  MX_CHECK(root_slice(B->dseg, B->dom->ns, lo, hi, &T->seg_pool, &T->seg_n, &T->seg_cap,
                      &T->seg_off[r], &T->seg_cnt[r]));
  T->flags[r] = T->seg_cnt[r] ? MX_Q_BOUND : 0;
  if (!T->seg_cnt[r] && mx_poly_inside(B->I, ctr) == 0) T->flags[r] |= MX_Q_OUT;
  if (B->nrs)
    MX_CHECK(root_slice(B->rseg, B->nrs, lo, hi, &B->rq_pool, &B->rq_n, &B->rq_cap,
                        &B->rq_off[r], &B->rq_cnt[r]));
  if (B->rin) {
    B->rin[r] = 0;
    for (size_t g = 0; g < B->req->nregions; g++) {
      int crossed = 0;
      for (uint32_t i = 0; i < B->rq_cnt[r]; i++)
        crossed |= B->rreg[B->rq_pool[B->rq_off[r] + i]] == g;
      const int lev = B->req->region_level[g];
      if (!crossed && lev > B->rin[r] && mx_poly_inside(&B->ridx[g], ctr))
        B->rin[r] = (uint8_t)lev;
    }
  }
  T->target[r] = target_of(B, r, lo, hi);
  return MX_OK;
}

/* The roots, quadrants 0 .. nroots-1, in Morton order of their keys. */
static int make_roots(qbuild *B) {
  mx_qtree *T = B->T;
  const size_t nr = (size_t)T->grid.dims[0] * T->grid.dims[1];
  uint64_t *k = mx_alloc(nr * sizeof *k);
  if (!k) return MX_ENOMEM;
  for (uint32_t j = 0, m = 0; j < T->grid.dims[1]; j++)
    for (uint32_t i = 0; i < T->grid.dims[0]; i++)
      k[m++] = mx_qkey(i << MX_QMAX_LEVEL, j << MX_QMAX_LEVEL);
  int st = mx_sort_u64(k, NULL, nr);
  if (!st) st = reserve_quadrants(B, nr);
  for (size_t r = 0; !st && r < nr; r++) st = make_root(B, (uint32_t)r, k[r]);
  mx_free(k);
  if (st) return st;
  T->n = B->nroots = nr;
  return B->E ? mx_qedges_add_roots(B->E, T, nr) : MX_OK;
}

/* ---- requests and set-up --------------------------------------------------- */

static int check_level(int level, const char *what, size_t i) {
  if (level >= 0 && level <= MX_QMAX_LEVEL - 1) return MX_OK;
  mx_error(NULL, 0, "refinement level %d of %s %zu is out of range (0 to %d)", level, what, i,
           MX_QMAX_LEVEL - 1);
  return MX_EINPUT;
}

/* Checks every level; returns the highest in *max. */
static int request_levels(const mx_qrequests *R, int *max) {
  int m = 0;
#define LEVEL(v, what, i)                    \
  do {                                       \
    MX_CHECK(check_level((v), (what), (i))); \
    if ((v) > m) m = (v);                    \
  } while (0)
  LEVEL(R->s_level, "the surface request", (size_t)0);
  LEVEL(R->a_level, "the all request", (size_t)0);
  for (size_t i = 0; i < R->nboxes; i++) LEVEL(R->boxes[i].level, "box", i);
  for (size_t i = 0; i < R->nregions; i++) LEVEL(R->region_level[i], "region", i);
  for (size_t i = 0; i < R->ndrawings; i++) LEVEL(R->drawing_level[i], "drawing", i);
  for (size_t i = 0; i < R->nkeep; i++) LEVEL(R->keep_level[i], "kept leaf", i);
  for (size_t i = 0; i < R->nfuns; i++) {
    LEVEL(R->funs[i].level, "function", i);
    if (R->funs[i].kind < MX_QFUN_CIRCLE || R->funs[i].kind > MX_QFUN_SINE) {
      mx_error(NULL, 0, "function %zu: unknown kind %d", i, R->funs[i].kind);
      return MX_EINPUT;
    }
  }
#undef LEVEL
  *max = m;
  return MX_OK;
}

static void seg_coords(const mx_poly *P, size_t s, double *out) {
  const double *a = P->xy + 2 * (size_t)P->seg[2 * s], *b = P->xy + 2 * (size_t)P->seg[2 * s + 1];
  out[0] = a[0], out[1] = a[1], out[2] = b[0], out[3] = b[1];
}

/* The regions' and drawings' segments in one array, and the regions'
 * point-location indexes. */
static int request_segments(qbuild *B) {
  const mx_qrequests *R = B->req;
  size_t n = 0;
  for (size_t i = 0; i < R->nregions; i++) n += R->regions[i].ns;
  for (size_t i = 0; i < R->ndrawings; i++) n += R->drawings[i].ns;
  B->nrs = n;
  if (R->nregions) {
    B->ridx = mx_calloc(R->nregions * sizeof *B->ridx);
    if (!B->ridx) return MX_ENOMEM;
    for (size_t i = 0; i < R->nregions; i++)
      MX_CHECK(mx_poly_index_build(&R->regions[i], &B->ridx[i]));
  }
  if (!n) return MX_OK;
  B->rseg = mx_alloc(4 * n * sizeof *B->rseg);
  B->rlev = mx_alloc(n);
  B->rreg = mx_alloc(n * sizeof *B->rreg);
  if (!B->rseg || !B->rlev || !B->rreg) return MX_ENOMEM;
  size_t k = 0;
  for (size_t i = 0; i < R->nregions + R->ndrawings; i++) {
    const int reg = i < R->nregions;
    const mx_poly *P = reg ? &R->regions[i] : &R->drawings[i - R->nregions];
    const int lev = reg ? R->region_level[i] : R->drawing_level[i - R->nregions];
    for (size_t s = 0; s < P->ns; s++, k++) {
      seg_coords(P, s, B->rseg + 4 * k);
      B->rlev[k] = (uint8_t)lev;
      B->rreg[k] = reg ? (uint32_t)i : NONE;
    }
  }
  return MX_OK;
}

static int builder_init(qbuild *B, const mx_poly *dom, const mx_poly_index *I,
                        const mx_qrequests *req, mx_qtree *T, int balance, int maxlevel) {
  memset(B, 0, sizeof *B);
  B->dom = dom, B->I = I, B->req = req, B->T = T;
  double lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY};
  B->dseg = mx_alloc((4 * dom->ns + 1) * sizeof *B->dseg);
  if (!B->dseg) return MX_ENOMEM;
  for (size_t s = 0; s < dom->ns; s++) {
    seg_coords(dom, s, B->dseg + 4 * s);
    for (int a = 0; a < 2; a++) {
      lo[a] = fmin(lo[a], fmin(B->dseg[4 * s + a], B->dseg[4 * s + 2 + a]));
      hi[a] = fmax(hi[a], fmax(B->dseg[4 * s + a], B->dseg[4 * s + 2 + a]));
    }
  }
  MX_CHECK(mx_qgrid_build(lo, hi, dom->path, &T->grid));
  if (req->size_field) { /* the finest level the field asks for, over all the roots */
    const mx_qgrid *g = &T->grid;
    const double rlo[2] = {g->origin[0], g->origin[1]},
                 rhi[2] = {g->origin[0] + g->side * g->dims[0],
                           g->origin[1] + g->side * g->dims[1]};
    const int fl = field_level(req, g->side, rlo, rhi);
    if (fl > maxlevel) maxlevel = fl;
  }
  MX_CHECK(request_segments(B));
  if (balance == MX_QBALANCE_EDGES) MX_CHECK(mx_qedges_new(maxlevel - 2, &B->E));
  return MX_OK;
}

static void builder_free(qbuild *B) {
  mx_free(B->dseg);
  mx_free(B->rseg);
  mx_free(B->rlev);
  mx_free(B->rreg);
  for (size_t i = 0; B->ridx && i < B->req->nregions; i++) mx_poly_index_free(&B->ridx[i]);
  mx_free(B->ridx);
  mx_free(B->rq_off);
  mx_free(B->rq_cnt);
  mx_free(B->rin);
  mx_free(B->rq_pool);
  mx_qedges_free(B->E);
}

/* ---- Algorithm 1 ----------------------------------------------------------- */

/* The children of this level's candidates that the requests want split, in
 * candidate order then child order (Morton order when the candidates are). */
static int next_candidates(const mx_qtree *T, const uint32_t *cand, size_t n, uint32_t **out,
                           size_t *nout) {
  uint64_t *off = mx_alloc((n + 1) * sizeof *off);
  if (!off) return MX_ENOMEM;
#pragma omp parallel for schedule(static) if (PAR(n))
  for (size_t i = 0; i < n; i++) {
    uint64_t k = 0;
    for (uint32_t q = T->child0[cand[i]]; q < T->child0[cand[i]] + 4; q++)
      k += T->target[q] > T->level[q];
    off[i] = k;
  }
  const size_t total = mx_scan_u64(off, n);
  uint32_t *next = mx_alloc((total + 1) * sizeof *next);
  if (next) {
#pragma omp parallel for schedule(static) if (PAR(n))
    for (size_t i = 0; i < n; i++) {
      uint64_t w = off[i];
      for (uint32_t q = T->child0[cand[i]]; q < T->child0[cand[i]] + 4; q++)
        if (T->target[q] > T->level[q]) next[w++] = q;
    }
  }
  mx_free(off);
  *out = next;
  *nout = total;
  return next ? MX_OK : MX_ENOMEM;
}

/* Step 3: the leaves made unbalanced by the splits of `split`, split in
 * waves (wave j holds leaves j+1 levels coarser than the candidates) until
 * none is left. */
static int drain(qbuild *B, const uint32_t *split, size_t n) {
  uint32_t *wave;
  size_t nw;
  MX_CHECK(mx_qedges_unbalanced(B->E, B->T, split, n, &wave, &nw));
  int st = MX_OK;
  while (nw && !st) {
    st = split_list(B, wave, nw, 1);
    uint32_t *next = NULL;
    size_t nn = 0;
    if (!st) st = mx_qedges_unbalanced(B->E, B->T, wave, nw, &next, &nn);
    mx_free(wave);
    wave = next;
    nw = nn;
  }
  mx_free(wave);
  return st;
}

static int refine(qbuild *B) {
  mx_qtree *T = B->T;
  uint32_t *cand = mx_alloc((B->nroots + 1) * sizeof *cand);
  if (!cand) return MX_ENOMEM;
  size_t n = 0;
  for (uint32_t r = 0; r < B->nroots; r++)
    if (T->target[r] > 0) cand[n++] = r;
  int st = MX_OK;
  while (n && !st) {
    double t0 = mx_wtime();
    st = split_list(B, cand, n, 0);
    double t1 = mx_wtime();
    if (!st && B->E) st = drain(B, cand, n);
    double t2 = mx_wtime();
    uint32_t *next = NULL;
    size_t nn = 0;
    if (!st) st = next_candidates(T, cand, n, &next, &nn);
    B->st.t_refine += (t1 - t0) + (mx_wtime() - t2);
    B->st.t_balance += t2 - t1;
    mx_free(cand);
    cand = next;
    n = nn;
  }
  mx_free(cand);
  return st;
}

/* The baseline: after refining, the neighbour search until balanced. */
static int balance_recursive(qbuild *B) {
  const double t0 = mx_wtime();
  int st = MX_OK;
  for (;;) {
    uint32_t *list = NULL;
    size_t n = 0;
    st = mx_qbalance_find(B->T, B->nroots, &list, &n);
    if (!st) st = split_list(B, list, n, 1);
    mx_free(list);
    if (st || n == 0) break;
  }
  B->st.t_balance += mx_wtime() - t0;
  return st;
}

int mx_qtree_build(const mx_poly *domain, const mx_poly_index *I, const mx_qrequests *req,
                   int balance, mx_qtree *T, mx_qstats *stats) {
  memset(T, 0, sizeof *T);
  if (stats) memset(stats, 0, sizeof *stats);
  if (!domain || !I || !req || domain->ns == 0) {
    mx_error(domain ? domain->path : NULL, 0, "the domain has no segments");
    return MX_EINPUT;
  }
  if (balance != MX_QBALANCE_EDGES && balance != MX_QBALANCE_RECURSIVE) {
    mx_error(NULL, 0, "unknown balance mode %d", balance);
    return MX_EINPUT;
  }
  int maxlevel;
  MX_CHECK(request_levels(req, &maxlevel));
  qbuild B;
  int st = builder_init(&B, domain, I, req, T, balance, maxlevel);
  if (!st) st = make_roots(&B);
  if (!st) st = refine(&B);
  if (!st && balance == MX_QBALANCE_RECURSIVE) st = balance_recursive(&B);
  B.st.edges = mx_qedges_count(B.E);
  builder_free(&B);
  if (st) {
    mx_qtree_free(T);
    return st;
  }
  size_t leaves = 0;
#pragma omp parallel for schedule(static) reduction(+ : leaves) if (PAR(T->n))
  for (size_t q = 0; q < T->n; q++) leaves += !(T->flags[q] & (MX_Q_SPLIT | MX_Q_OUT));
  B.st.leaves = leaves;
  if (stats) *stats = B.st;
  return MX_OK;
}
