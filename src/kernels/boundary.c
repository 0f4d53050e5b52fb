#include "base/cancel.h"
#include "kernels/boundary.h"

#include "base/common.h"
#include "kernels/mesh_edit.h"
#include "geom/quality.h"
#include "soa/mesh.h"
#include "base/scan.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Elements are in leaf order: each leaf's elements form one run. The runs'
 * starts (mx_alloc, *nr of them, then nc), counted per block, prefix-summed,
 * filled; NULL when out of memory. */
static uint64_t *leaf_runs(const mx_mesh *M, size_t *nr_out) {
  const size_t nc = M->ncells;
  enum { RB = 1 << 16 };
  const size_t nbk = (nc + RB - 1) / RB;
  uint64_t *run = mx_alloc((nc + 2) * sizeof *run);
  uint64_t *boff = mx_alloc((nbk + 1) * sizeof *boff);
  if (!run || !boff) {
    mx_free(run);
    mx_free(boff);
    return NULL;
  }
#pragma omp parallel for schedule(static)
  for (size_t b = 0; b < nbk; b++) {
    uint64_t k = 0;
    for (size_t c = b * RB; c < nc && c < (b + 1) * RB; c++)
      k += c == 0 || M->leaf[c] != M->leaf[c - 1];
    boff[b] = k;
  }
  const size_t nr = (size_t)mx_scan_u64(boff, nbk);
#pragma omp parallel for schedule(static)
  for (size_t b = 0; b < nbk; b++) {
    uint64_t k = boff[b];
    for (size_t c = b * RB; c < nc && c < (b + 1) * RB; c++)
      if (c == 0 || M->leaf[c] != M->leaf[c - 1]) run[k++] = c;
  }
  mx_free(boff);
  run[nr] = nc;
  *nr_out = nr;
  return run;
}

/* Distinct nodes v of the elements [c0, c1) (one leaf's) with (sel[v] &
 * mask) == want, in order of first use. */
static int leaf_nodes(const mx_mesh *M, size_t c0, size_t c1, const uint8_t *sel,
                      uint8_t mask, uint8_t want, uint32_t out[64]) {
  int n = 0;
  for (size_t c = c0; c < c1; c++)
    for (int k = 0; k < mx_cell_nodes[M->type[c]]; k++) {
      const uint32_t v = M->conn[8 * c + k];
      if ((sel[v] & mask) != want) continue;
      int seen = 0;
      for (int j = 0; j < n && !seen; j++) seen = out[j] == v;
      if (!seen && n < 64) out[n++] = v;
    }
  return n;
}

static int same_point(const double a[3], const double b[3]) {
  return a[0] == b[0] && a[1] == b[1] && a[2] == b[2];
}

/* Closest domain triangle of leaf o's list to p: squared distance, id (the
 * lowest of those as near); *tied (when not NULL) 1 when two of them as
 * near give two points. */
static double leaf_closest(const mx_tree *tr, uint32_t o, const double p[3],
                           uint32_t *tri, int *tied) {
  const mx_octree *T = &tr->oct;
  double best = INFINITY, q[3], bq[3] = {0.0, 0.0, 0.0};
  int tie = 0;
  *tri = UINT32_MAX;
  for (uint32_t k = 0; k < T->tri_cnt[o]; k++) {
    const uint32_t t = T->tri_pool[T->tri_off[o] + k];
    if (t >= tr->nt_domain) continue;
    const double d2 = mx_closest_on_triangle(tr->tri_xyz + 9 * (size_t)t, p, q);
    if (d2 < best) {
      best = d2;
      *tri = t;
      memcpy(bq, q, sizeof bq);
      tie = 0;
    } else if (d2 == best) {
      tie |= !same_point(q, bq);
      if (t < *tri) {
        *tri = t;
        memcpy(bq, q, sizeof bq);
      }
    }
  }
  if (tied) *tied = tie;
  return best;
}

static inline uint64_t dbits(double d) {
  uint64_t u;
  memcpy(&u, &d, sizeof u);
  return u; /* non-negative doubles order as their bits */
}

/* For every node v with (sel[v] & mask) == want: btri[v] and best[v] (the
 * bits of the squared distance) of the least (squared distance, triangle
 * id) over the domain triangles of the leaves whose elements use v
 * (UINT32_MAX and UINT64_MAX when they list none; other nodes untouched);
 * tie[v] (when tie is not NULL) 1 when two of those triangles as near give
 * two points (the surface index might keep the other). One pass over
 * (leaf, node), compared and stored under a per-node spin lock (a node is
 * shared by a few leaves: the locks are hardly ever contended). */
static int leaf_list_closest(const mx_tree *tr, const uint32_t *leaves, const mx_mesh *M,
                             const uint8_t *sel, uint8_t mask, uint8_t want,
                             uint64_t *best, uint32_t *btri, uint8_t *tie) {
  const size_t nn = M->nnodes;
  size_t nr = 0;
  uint64_t *run = leaf_runs(M, &nr);
  uint8_t *lock = run ? mx_calloc(nn + 1) : NULL;
  if (!lock) {
    mx_free(run);
    return MX_ENOMEM;
  }
#pragma omp parallel for schedule(static)
  for (size_t v = 0; v < nn; v++)
    if ((sel[v] & mask) == want) {
      best[v] = UINT64_MAX;
      btri[v] = UINT32_MAX;
      if (tie) tie[v] = 0;
    }
#pragma omp parallel for schedule(dynamic, 256)
  for (size_t r = 0; r < nr; r++) {
    const uint32_t o = leaves[M->leaf[run[r]]];
    if (!tr->oct.tri_cnt[o]) continue;
    uint32_t vs[64];
    const int k = leaf_nodes(M, run[r], run[r + 1], sel, mask, want, vs);
    for (int j = 0; j < k; j++) {
      uint32_t t;
      int tied = 0;
      const double *p = M->xyz + 3 * (size_t)vs[j];
      const double d2 = leaf_closest(tr, o, p, &t, tie ? &tied : NULL);
      if (t == UINT32_MAX) continue;
      const uint64_t mine = dbits(d2);
      const uint32_t v = vs[j];
      while (__atomic_test_and_set(&lock[v], __ATOMIC_ACQUIRE)) {
      }
      const int better = mine < best[v], equal = mine == best[v];
      if (tie && equal && t != btri[v]) { /* as near as another leaf's */
        double q0[3], q1[3];
        mx_closest_on_triangle(tr->tri_xyz + 9 * (size_t)t, p, q0);
        mx_closest_on_triangle(tr->tri_xyz + 9 * (size_t)btri[v], p, q1);
        tied |= !same_point(q0, q1);
      }
      if (tie && (better || equal)) tie[v] = (uint8_t)(better ? tied : tie[v] | tied);
      if (better || (equal && t < btri[v])) {
        best[v] = mine;
        btri[v] = t;
      }
      __atomic_clear(&lock[v], __ATOMIC_RELEASE);
    }
  }
  mx_free(lock);
  mx_free(run);
  return MX_OK;
}

enum { COUNT_BITS = 12 };
#define ONE_EDGE ((uint64_t)1 << (64 - COUNT_BITS))
/* cand[] of the close nodes: a candidate, one searched in its leaves' lists
 * (LOCAL; WIDE when at a corner of the finest leaves' lattice), one that
 * moves */
enum { CAND = 1, MOVES = 2, LOCAL = 4, WIDE = 8 };

/* 1 when p lies on the lattice of step `step` from the grid's origin
 * (within a 50th of it, for the rounding of the positions). */
static int on_lattice(const mx_grid *g, const double p[3], double step) {
  for (int a = 0; a < 3; a++) {
    const double f = (p[a] - g->origin[a]) / step;
    if (!(fabs(f - nearbyint(f)) < 0.02)) return 0;
  }
  return 1;
}

/* The largest leaf level of M's elements (0 without levels). */
static int finest_level(const mx_mesh *M) {
  int lmax = 0;
  const size_t nc = M->level ? M->ncells : 0;
#pragma omp parallel for schedule(static) reduction(max : lmax)
  for (size_t c = 0; c < nc; c++) lmax = M->level[c] > lmax ? M->level[c] : lmax;
  return lmax;
}

/* What the triangle lists can be trusted with. The leaves' lists hold the
 * triangles meeting their closed boxes, but a box is tested as a centre and
 * half sides, whose rounding can leave a gap of an ulp between two
 * neighbours: a flat triangle lying in the plane between them (an input
 * face on a lattice plane: a CAD part's, the step of tests/features_test.sh)
 * is then in neither list. Any other triangle near a node crosses into the
 * inside of a leaf holding it and is listed. So the nodes within their cover
 * of such a plane (one per flat triangle and axis: the triangle's extent
 * along the axis below tol) query the index. */
typedef struct {
  const mx_grid *g;
  double half, tol;      /* the finest leaves' half side; flatness */
  double *plane[3];      /* per axis, the flat triangles' planes, sorted */
  size_t nplane[3];
} list_frame;

static int cmp_double(const void *a, const void *b) {
  const double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}

static void frame_free(list_frame *F) {
  for (int a = 0; a < 3; a++) mx_free(F->plane[a]);
  memset(F, 0, sizeof *F);
}

static int frame_build(const mx_tree *tr, const mx_mesh *M, list_frame *F) {
  memset(F, 0, sizeof *F);
  const mx_grid *g = &tr->grid;
  F->g = g;
  F->half = ldexp(g->side, -finest_level(M) - 1);
  double mag = 0.0;
  for (int a = 0; a < 3; a++)
    mag = fmax(mag, fabs(g->origin[a]) + g->side * (double)g->dims[a]);
  F->tol = 1e-9 * F->half + 1e-12 * mag;
  const uint32_t nt = tr->nt_domain;
  for (int a = 0; a < 3; a++) {
    F->plane[a] = mx_alloc(((size_t)nt + 1) * sizeof *F->plane[a]);
    if (!F->plane[a]) {
      frame_free(F);
      return MX_ENOMEM;
    }
  }
  for (uint32_t t = 0; t < nt; t++) {
    const double *v = tr->tri_xyz + 9 * (size_t)t;
    for (int a = 0; a < 3; a++) {
      const double lo = fmin(v[a], fmin(v[3 + a], v[6 + a]));
      const double hi = fmax(v[a], fmax(v[3 + a], v[6 + a]));
      if (hi - lo <= F->tol) F->plane[a][F->nplane[a]++] = 0.5 * (lo + hi);
    }
  }
  for (int a = 0; a < 3; a++) qsort(F->plane[a], F->nplane[a], sizeof *F->plane[a], cmp_double);
  return MX_OK;
}

/* 1 when a plane of c[0..n) (sorted) lies within r of x. */
static int near_plane(const double *c, size_t n, double x, double r) {
  size_t lo = 0, hi = n; /* the first plane at or above x - r */
  while (lo < hi) {
    const size_t mid = lo + (hi - lo) / 2;
    if (c[mid] < x - r) lo = mid + 1;
    else hi = mid;
  }
  return lo < n && c[lo] <= x + r;
}

static double cover_of(uint8_t marks, double half) {
  return marks & WIDE ? 1.8 * half : marks & LOCAL ? 0.9 * half : 0.0;
}

/* The lattice marks of a node at p: LOCAL at a node of the lattice of step
 * half, LOCAL | WIDE at a corner of the finest leaves' lattice, 0 elsewhere
 * or near a flat triangle's plane (list_frame). A node at LOCAL lies at half
 * or more from every leaf not holding it (their corners are on the lattice
 * of step 2 half), at 2 half with WIDE: the leaves holding it (those whose
 * elements use it, the mesh being conforming) cover the ball about it of
 * radius cover_of(marks) (0.9 of that). */
static uint8_t lattice_marks(const list_frame *F, const double p[3]) {
  const uint8_t m = on_lattice(F->g, p, 2.0 * F->half) ? LOCAL | WIDE
                    : on_lattice(F->g, p, F->half)     ? LOCAL
                                                       : 0;
  if (!m) return 0;
  const double reach = cover_of(m, F->half) + F->tol;
  for (int a = 0; a < 3; a++)
    if (near_plane(F->plane[a], F->nplane[a], p[a], reach)) return 0;
  return m;
}

int mx_node_states(const mx_tree *tr, const uint32_t *leaves,
                   const mx_mesh *M, const mx_surface_index *S,
                   uint8_t *states, size_t *queries) {
  const mx_octree *T = &tr->oct;
  const size_t nn = M->nnodes;
  enum { UNKNOWN = 2 };
#pragma omp parallel for schedule(static)
  for (size_t v = 0; v < nn; v++) states[v] = UNKNOWN;
  /* Elements of leaves that meet no domain triangle: all nodes inside. Two
   * threads may write the same value to a shared node: benign. */
#pragma omp parallel for schedule(static)
  for (size_t c = 0; c < M->ncells; c++) {
    if (T->flags[leaves[M->leaf[c]]] & MX_OCT_SURFACE) continue;
    const int nv = mx_cell_nodes[M->type[c]];
    for (int k = 0; k < nv; k++)
      __atomic_store_n(&states[M->conn[8 * c + k]], (uint8_t)MX_NODE_INSIDE,
                       __ATOMIC_RELAXED);
  }
  /* The others: where the lists of their leaves hold a triangle nearer than
   * their cover (lattice_marks), that is the nearest of all (the same
   * arithmetic as the surface index's: the soup's coordinates), and the
   * pseudonormal rule tells the side from it (mx_inside_given_closest)
   * without a query; the others are queried, and so are those whose lists
   * hold two triangles as near with two points (the index might keep
   * either). */
  const int by_lists = !S->side && (S->closed || S->outward_closed) && S->nt && M->level &&
                       S->nt <= tr->nt_domain;
  list_frame F;
  memset(&F, 0, sizeof F);
  if (by_lists) MX_CHECK(frame_build(tr, M, &F));
  const double half = F.half;
  uint64_t *best = by_lists ? mx_alloc((nn + 1) * sizeof *best) : NULL;
  uint32_t *btri = by_lists ? mx_alloc((nn + 1) * sizeof *btri) : NULL;
  uint32_t *slot_of = by_lists ? mx_alloc(((size_t)tr->nt_domain + 1) * sizeof *slot_of) : NULL;
  uint8_t *tie = by_lists ? mx_alloc(nn + 1) : NULL;
  if (by_lists && (!best || !btri || !slot_of || !tie)) {
    frame_free(&F);
    mx_free(best);
    mx_free(btri);
    mx_free(slot_of);
    mx_free(tie);
    return MX_ENOMEM;
  }
  if (by_lists) {
    for (uint32_t t = 0; t < tr->nt_domain; t++) slot_of[t] = UINT32_MAX;
    for (uint32_t i = 0; i < S->nt; i++)
      if (S->tri_id[i] < tr->nt_domain) slot_of[S->tri_id[i]] = i;
#pragma omp parallel for schedule(static)
    for (size_t v = 0; v < nn; v++)
      if (states[v] == UNKNOWN)
        states[v] = (uint8_t)(UNKNOWN | lattice_marks(&F, M->xyz + 3 * v));
    const int st = leaf_list_closest(tr, leaves, M, states, LOCAL, LOCAL, best, btri, tie);
    if (st) {
      frame_free(&F);
      mx_free(best);
      mx_free(btri);
      mx_free(slot_of);
      mx_free(tie);
      return st;
    }
  }
  size_t q = 0;
#pragma omp parallel for schedule(dynamic, 4096) reduction(+ : q)
  for (size_t v = 0; v < nn; v++) {
    const uint8_t marks = states[v];
    if ((marks & 3) != UNKNOWN) continue;
    const double *p = M->xyz + 3 * v;
    int in = -1;
    if ((marks & LOCAL) && btri[v] != UINT32_MAX && !tie[v] && slot_of[btri[v]] != UINT32_MAX) {
      double d2;
      memcpy(&d2, &best[v], sizeof d2);
      if (sqrt(d2) < cover_of(marks, half)) in = mx_inside_given_closest(S, p, slot_of[btri[v]]);
    }
    if (in < 0) in = mx_inside(S, p);
    states[v] = in ? MX_NODE_INSIDE : MX_NODE_OUTSIDE;
    q++;
  }
  mx_free(best);
  mx_free(btri);
  mx_free(slot_of);
  mx_free(tie);
  frame_free(&F);
  *queries = q;
  return MX_OK;
}

int mx_move_close_nodes(mx_mesh *M, uint8_t *states, const mx_surface_index *S,
                        double ratio, size_t *moved, uint8_t **moved_flags) {
  return mx_move_close_nodes_in(NULL, NULL, M, states, S, ratio, moved, moved_flags);
}

int mx_move_close_nodes_in(const mx_tree *tr, const uint32_t *leaves, mx_mesh *M,
                           uint8_t *states, const mx_surface_index *S, double ratio,
                           size_t *moved, uint8_t **moved_flags) {
  const size_t nn = M->nnodes, nc = M->ncells;
  /* Candidates: inside nodes of surface elements. */
  uint8_t *cand = mx_calloc(nn + 1);
  /* per candidate, its edges' count (the top COUNT_BITS) and their
   * lengths' sum (fixed point, below), in one word: one atomic addition
   * an element and node. A node has at most a few hundred element edges
   * (8 leaves, a few dozen elements each): below 2^12; each length is at
   * most 2^40 units, so the sum stays below 2^52. */
  uint64_t *len = mx_calloc((nn + 1) * sizeof *len);
  if (!cand || !len) {
    mx_free(cand);
    mx_free(len);
    return MX_ENOMEM;
  }
#pragma omp parallel for schedule(static)
  for (size_t c = 0; c < nc; c++) {
    const uint32_t *v = M->conn + 8 * c;
    const int nv = mx_cell_nodes[M->type[c]];
    int in = 0;
    for (int k = 0; k < nv; k++) in += states[v[k]] == MX_NODE_INSIDE;
    if (in == 0 || in == nv) continue;
    for (int k = 0; k < nv; k++)
      if (states[v[k]] == MX_NODE_INSIDE) __atomic_store_n(&cand[v[k]], (uint8_t)CAND, __ATOMIC_RELAXED);
  }
  /* Average length of the element edges at each candidate, summed in fixed
   * point (integer additions: the same sums in any order, so the decisions
   * are the same for any thread count). */
  double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
#pragma omp parallel for schedule(static) reduction(min : lo[:3]) reduction(max : hi[:3])
  for (size_t v = 0; v < nn; v++)
    for (int x = 0; x < 3; x++) {
      lo[x] = fmin(lo[x], M->xyz[3 * v + x]);
      hi[x] = fmax(hi[x], M->xyz[3 * v + x]);
    }
  double diag = 0.0;
  for (int x = 0; x < 3 && nn; x++) diag += (hi[x] - lo[x]) * (hi[x] - lo[x]);
  const double unit = ldexp(sqrt(diag) + 1e-300, -40); /* 2^40 units per diagonal */
#pragma omp parallel for schedule(static)
  for (size_t c = 0; c < nc; c++) {
    const uint32_t *v = M->conn + 8 * c;
    const int t = M->type[c];
    /* the element's candidates as bits first: most elements have none */
    unsigned in = 0;
    for (int k = 0; k < mx_cell_nodes[t]; k++) in |= (unsigned)(cand[v[k]] != 0) << k;
    if (!in) continue;
    uint64_t acc[8] = {0, 0, 0, 0, 0, 0, 0, 0};
    for (int e = 0; e < mx_cell_nedges[t]; e++) {
      const int ka = mx_cell_edge[t][e][0], kb = mx_cell_edge[t][e][1];
      if (!((in >> ka | in >> kb) & 1u)) continue;
      const uint32_t a = v[ka], b = v[kb];
      double d2 = 0.0; /* (the sums are per element first) */
      for (int x = 0; x < 3; x++) {
        const double u = M->xyz[3 * (size_t)a + x] - M->xyz[3 * (size_t)b + x];
        d2 += u * u;
      }
      const uint64_t l = (uint64_t)llround(sqrt(d2) / unit) + ONE_EDGE;
      acc[ka] += in >> ka & 1u ? l : 0;
      acc[kb] += in >> kb & 1u ? l : 0;
    }
    for (int k = 0; k < mx_cell_nodes[t]; k++)
      if (in >> k & 1u) __atomic_fetch_add(&len[v[k]], acc[k], __ATOMIC_RELAXED);
  }
  /* A candidate at a node of the lattice of the finest leaves' half side h
   * lies at h or more from every leaf not holding it (their corners are on
   * the lattice of side 2h), 2h at a corner of that lattice: the leaves
   * holding it (those whose elements use it: the mesh is conforming) cover
   * the ball of radius 0.9 h (1.8 h) about it, its cover. So where its
   * leaves' lists hold a triangle nearer than the cover (leaf_list_closest),
   * that is the nearest of all (the same arithmetic as the surface index:
   * the soup's coordinates, mx_closest_on_triangle), without a query; where
   * they hold none, none is nearer than the cover, and a radius within it
   * moves nothing. Two triangles as near with two points: a query (the
   * index might keep either). */
  if (!M->level) tr = NULL; /* no leaf levels: every candidate queries */
  list_frame F;
  memset(&F, 0, sizeof F);
  if (tr && frame_build(tr, M, &F)) {
    mx_free(cand);
    mx_free(len);
    return MX_ENOMEM;
  }
  const double half = F.half;
  size_t nlocal = 0;
#pragma omp parallel for schedule(static) reduction(+ : nlocal)
  for (size_t v = 0; v < nn; v++) {
    const uint64_t cnt = len[v] >> (64 - COUNT_BITS);
    if (!cand[v] || !cnt) {
      cand[v] = 0;
      continue;
    }
    if (tr) cand[v] = (uint8_t)(CAND | lattice_marks(&F, M->xyz + 3 * v));
    nlocal += (cand[v] & LOCAL) != 0;
  }
  double *target = mx_alloc((3 * nn + 3) * sizeof *target);
  uint64_t *best = nlocal ? mx_alloc((nn + 1) * sizeof *best) : NULL;
  uint32_t *btri = nlocal ? mx_alloc((nn + 1) * sizeof *btri) : NULL;
  uint8_t *tie = nlocal ? mx_alloc(nn + 1) : NULL;
  int st = !target || (nlocal && (!best || !btri || !tie)) ? MX_ENOMEM : MX_OK;
  if (!st && nlocal) st = leaf_list_closest(tr, leaves, M, cand, LOCAL, LOCAL, best, btri, tie);
  frame_free(&F);
  if (st) {
    mx_free(target);
    mx_free(best);
    mx_free(btri);
    mx_free(tie);
    mx_free(cand);
    mx_free(len);
    return st;
  }
  /* Decide on the old positions, then move. */
  size_t nmoved = 0;
  atomic_int *cf = mx_cancel_flag; /* base/cancel.h: the longest loop */
#pragma omp parallel for schedule(dynamic, 1024) reduction(+ : nmoved)
  for (size_t v = 0; v < nn; v++) {
    if (mx_cancel_seen(cf) || !cand[v]) continue;
    const uint64_t cnt = len[v] >> (64 - COUNT_BITS);
    const double r = ratio * ((double)(len[v] & (ONE_EDGE - 1)) * unit / (double)cnt);
    double *q = target + 3 * v;
    double d = INFINITY;
    int found = 0;
    if ((cand[v] & LOCAL) && !tie[v]) {
      const double cover = cover_of(cand[v], half);
      if (btri[v] != UINT32_MAX) {
        double d2;
        memcpy(&d2, &best[v], sizeof d2);
        d = sqrt(d2);
      }
      if (d < cover) { /* the nearest of all */
        found = 1;
        if (d < r) mx_closest_on_triangle(tr->tri_xyz + 9 * (size_t)btri[v], M->xyz + 3 * v, q);
      } else {
        found = r <= cover; /* none within r */
        d = INFINITY;
      }
    }
    if (!found) d = mx_closest_point_within(S, M->xyz + 3 * v, r, q);
    if (d < r) {
      cand[v] = MOVES;
      nmoved++;
    }
  }
  mx_free(best);
  mx_free(btri);
  mx_free(tie);
  mx_free(len);
  if (mx_cancelled()) { /* nothing moved yet */
    mx_free(target);
    mx_free(cand);
    return MX_ECANCELED;
  }
#pragma omp parallel for schedule(static)
  for (size_t v = 0; v < nn; v++) {
    if (cand[v] == MOVES) {
      memcpy(M->xyz + 3 * v, target + 3 * v, 3 * sizeof(double));
      states[v] = MX_NODE_OUTSIDE;
    }
    cand[v] = cand[v] == MOVES;
  }
  mx_free(target);
  if (moved_flags) {
    *moved_flags = cand; /* the caller recomputes J_ENS */
  } else {
    mx_mesh_update_jens(M, cand);
    mx_free(cand);
  }
  *moved = nmoved;
  return MX_OK;
}

int mx_shrink_to_boundary(const mx_tree *tr, const uint32_t *leaves,
                          mx_mesh *M, const uint8_t *states, size_t *moved) {
  const size_t nn = M->nnodes, nc = M->ncells;
  uint64_t *best = mx_alloc((nn + 1) * sizeof *best);
  uint32_t *btri = mx_alloc((nn + 1) * sizeof *btri);
  int st = best && btri ? MX_OK : MX_ENOMEM;
  if (!st) { /* the nodes not outside: no triangle */
#pragma omp parallel for schedule(static)
    for (size_t v = 0; v < nn; v++) btri[v] = UINT32_MAX;
    st = leaf_list_closest(tr, leaves, M, states, 0xff, MX_NODE_OUTSIDE, best, btri, NULL);
  }
  if (st) {
    mx_free(best);
    mx_free(btri);
    return st;
  }
  size_t nm = 0;
#pragma omp parallel for schedule(static) reduction(+ : nm)
  for (size_t v = 0; v < nn; v++) {
    if (btri[v] == UINT32_MAX) continue;
    double q[3], *x = M->xyz + 3 * v;
    mx_closest_on_triangle(tr->tri_xyz + 9 * (size_t)btri[v], x, q);
    nm++;
    if (q[0] == x[0] && q[1] == x[1] && q[2] == x[2]) { /* there already (a close node) */
      btri[v] = UINT32_MAX;
      continue;
    }
    memcpy(x, q, sizeof q);
  }
  /* J_ENS of the elements with a node that moved (btri[] left set): the
   * others' is that of their positions already. */
  size_t invalid = 0;
  double jmin = INFINITY;
#pragma omp parallel for schedule(static) reduction(+ : invalid) reduction(min : jmin)
  for (size_t c = 0; c < nc; c++) {
    const int nv = mx_cell_nodes[M->type[c]];
    int out = 0;
    for (int k = 0; k < nv; k++) out |= btri[M->conn[8 * c + k]] != UINT32_MAX;
    if (out) { /* the coordinates of those only */
      double x[8][3];
      for (int k = 0; k < nv; k++)
        memcpy(x[k], M->xyz + 3 * (size_t)M->conn[8 * c + k], sizeof x[k]);
      M->jens[c] = (float)mx_jens(M->type[c], x);
    }
    invalid += mx_jens_invalid(M->jens[c]);
    if (M->jens[c] < jmin) jmin = M->jens[c];
  }
  M->invalid = invalid;
  M->jens_min = nc ? jmin : 1.0;
  mx_free(best);
  mx_free(btri);
  *moved = nm;
  return MX_OK;
}
