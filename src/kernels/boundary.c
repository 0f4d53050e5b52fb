#include "base/cancel.h"
#include "kernels/boundary.h"
#include "kernels/leaf_lists.h"

#include "base/common.h"
#include "kernels/mesh_edit.h"
#include "geom/quality.h"
#include "soa/mesh.h"
#include "base/scan.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

enum { COUNT_BITS = 12 };
#define ONE_EDGE ((uint64_t)1 << (64 - COUNT_BITS))
/* cand[] of the close nodes: a candidate, one that moves; with the marks
 * of kernels/leaf_lists.h (MX_LIST_LOCAL, MX_LIST_WIDE) */
enum { CAND = 1, MOVES = 2 };

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
   * their cover, the nearest of all (kernels/leaf_lists.h), the
   * pseudonormal rule tells the side from it (mx_inside_given_closest, the
   * index's arithmetic) without a query; the others are queried. */
  const int by_lists = !S->side && (S->closed || S->outward_closed) && S->nt && M->level &&
                       S->nt <= tr->nt_domain;
  mx_list_frame F;
  memset(&F, 0, sizeof F);
  if (by_lists) MX_CHECK(mx_list_frame_build(tr, M, &F));
  const double half = F.half;
  uint64_t *best = by_lists ? mx_alloc((nn + 1) * sizeof *best) : NULL;
  uint32_t *btri = by_lists ? mx_alloc((nn + 1) * sizeof *btri) : NULL;
  uint32_t *slot_of = by_lists ? mx_alloc(((size_t)tr->nt_domain + 1) * sizeof *slot_of) : NULL;
  uint8_t *tie = by_lists ? mx_alloc(nn + 1) : NULL;
  if (by_lists && (!best || !btri || !slot_of || !tie)) {
    mx_list_frame_free(&F);
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
        states[v] = (uint8_t)(UNKNOWN | mx_list_marks(&F, M->xyz + 3 * v));
    const int st = mx_leaf_list_closest(tr, leaves, M, states, MX_LIST_LOCAL, MX_LIST_LOCAL,
                                        best, btri, tie);
    if (st) {
      mx_list_frame_free(&F);
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
    if ((marks & MX_LIST_LOCAL) && btri[v] != UINT32_MAX && !tie[v] &&
        slot_of[btri[v]] != UINT32_MAX) {
      double d2;
      memcpy(&d2, &best[v], sizeof d2);
      if (sqrt(d2) < mx_list_cover(marks, half))
        in = mx_inside_given_closest(S, p, slot_of[btri[v]]);
    }
    if (in < 0) in = mx_inside(S, p);
    states[v] = in ? MX_NODE_INSIDE : MX_NODE_OUTSIDE;
    q++;
  }
  mx_free(best);
  mx_free(btri);
  mx_free(slot_of);
  mx_free(tie);
  mx_list_frame_free(&F);
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
      if (states[v[k]] == MX_NODE_INSIDE)
        __atomic_store_n(&cand[v[k]], (uint8_t)CAND, __ATOMIC_RELAXED);
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
  /* Where the lists of a candidate's leaves hold a triangle nearer than its
   * cover, the nearest of all (kernels/leaf_lists.h), without a query; where
   * they hold none, none is that near, and a radius within the cover moves
   * nothing. The others query the index within their radius. */
  if (!M->level) tr = NULL; /* no leaf levels: every candidate queries */
  mx_list_frame F;
  memset(&F, 0, sizeof F);
  if (tr && mx_list_frame_build(tr, M, &F)) {
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
    if (tr) cand[v] = (uint8_t)(CAND | mx_list_marks(&F, M->xyz + 3 * v));
    nlocal += (cand[v] & MX_LIST_LOCAL) != 0;
  }
  double *target = mx_alloc((3 * nn + 3) * sizeof *target);
  uint64_t *best = nlocal ? mx_alloc((nn + 1) * sizeof *best) : NULL;
  uint32_t *btri = nlocal ? mx_alloc((nn + 1) * sizeof *btri) : NULL;
  uint8_t *tie = nlocal ? mx_alloc(nn + 1) : NULL;
  int st = !target || (nlocal && (!best || !btri || !tie)) ? MX_ENOMEM : MX_OK;
  if (!st && nlocal)
    st = mx_leaf_list_closest(tr, leaves, M, cand, MX_LIST_LOCAL, MX_LIST_LOCAL, best, btri,
                              tie);
  mx_list_frame_free(&F);
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
    if ((cand[v] & MX_LIST_LOCAL) && !tie[v]) {
      const double cover = mx_list_cover(cand[v], half);
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
    st = mx_leaf_list_closest(tr, leaves, M, states, 0xff, MX_NODE_OUTSIDE, best, btri,
                              NULL);
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
