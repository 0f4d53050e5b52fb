/* Refinement of an existing balanced octree (Jaillet & Lobos 2021,
 * Algorithm 3 and the steps of Algorithm 2 that follow it): see
 * kernels/refine_list.h. */
#include "kernels/refine_list.h"

#include "base/common.h"
#include "kernels/closures.h"
#include "kernels/edges_lazy.h"

#include <omp.h>
#include <string.h>

void mx_retarget_leaves(mx_builder *B) {
  mx_octree *T = &B->tree.oct;
#pragma omp parallel for schedule(static)
  for (size_t o = 0; o < T->n; o++) {
    if (T->flags[o] & MX_OCT_SPLIT) continue;
    double lo[3], hi[3];
    mx_octant_box(&B->tree.grid, T->key[o], T->level[o], lo, hi);
    const int t = mx_target_level(&B->req, lo, hi, (T->flags[o] & MX_OCT_SURFACE) != 0,
                                  (unsigned)(T->rmeet[o] | T->rin[o]));
    T->target[o] = (uint8_t)(t > T->level[o] ? t : T->level[o]);
  }
}

/* Leaves of level l among list[0..n) that still ask for a split. */
static size_t keep_candidates(const mx_octree *T, uint32_t *list, size_t n,
                              int l) {
  size_t w = 0;
  for (size_t i = 0; i < n; i++) {
    const uint32_t o = list[i];
    if (T->level[o] == l && !(T->flags[o] & MX_OCT_SPLIT) && T->target[o] > l)
      list[w++] = o;
  }
  return w;
}

static int sweep_levels(mx_builder *B, int *done);

int mx_refine_leaves_to_target(mx_builder *B) {
  /* A sweep may split, for balance, octants of levels it has passed whose
   * children ask for more (only with a split set: requests are monotone,
   * a child never asks for more than its parent); sweep again then. */
  for (;;) {
    int done = 0;
    MX_CHECK(sweep_levels(B, &done));
    if (done) return mx_resolve_closures(B);
  }
}

static int sweep_levels(mx_builder *B, int *done) {
  mx_octree *T = &B->tree.oct;
  /* One pass: every leaf asking for more, in index order, and the deepest
   * level asked. */
  size_t n = 0;
  int maxt = 0;
#pragma omp parallel for schedule(static) reduction(+ : n) reduction(max : maxt)
  for (size_t o = 0; o < T->n; o++)
    if (!(T->flags[o] & MX_OCT_SPLIT) && T->target[o] > T->level[o]) {
      n++;
      if (T->target[o] > maxt) maxt = T->target[o];
    }
  if (n == 0) {
    *done = 1;
    return MX_OK;
  }
  if (maxt > MX_MAX_LEVEL) maxt = MX_MAX_LEVEL;
  /* no mx_raise_edge_levels: the splits below edge_levels register what
   * they need (mx_edges_ensure, from mx_split_octants) */
  uint32_t *want = mx_alloc((n + 1) * sizeof *want);
  if (!want) return MX_ENOMEM;
  size_t w = 0;
  for (size_t o = 0; o < T->n; o++)
    if (!(T->flags[o] & MX_OCT_SPLIT) && T->target[o] > T->level[o])
      want[w++] = (uint32_t)o;
  /* Level by level, as in Algorithm 1: the leaves of this level that ask
   * for a split (the old ones first, then the children of the previous
   * level's splits; indices ascend, siblings stay together), split, then
   * to_balance drained before the next level. */
  uint32_t *cand = NULL, *prev = NULL;
  size_t nprev = 0;
  int st = MX_OK;
  for (int l = 0; l < maxt && st == MX_OK; l++) {
    size_t nk = 0;
    for (size_t i = 0; i < nprev; i++) nk += (size_t)__builtin_popcount(T->kept[prev[i]]);
    cand = mx_alloc((n + nk + 1) * sizeof *cand);
    if (!cand) {
      st = MX_ENOMEM;
      break;
    }
    size_t nc = 0;
    for (size_t i = 0; i < n; i++)
      if (T->level[want[i]] == l) cand[nc++] = want[i];
    nc = keep_candidates(T, cand, nc, l);
    for (size_t i = 0; i < nprev; i++) {
      const uint32_t p = prev[i];
      const int k = __builtin_popcount(T->kept[p]);
      for (int j = 0; j < k; j++) {
        const uint32_t c = T->child0[p] + (uint32_t)j;
        if (T->target[c] > T->level[c] && !(T->flags[c] & MX_OCT_SPLIT))
          cand[nc++] = c;
      }
    }
    mx_free(prev);
    prev = NULL;
    nprev = 0;
    if (nc == 0) {
      mx_free(cand);
      cand = NULL;
      continue;
    }
    double t0 = mx_wtime();
    st = mx_split_octants(B, cand, nc, 0);
    double t1 = mx_wtime();
    B->stats.t_refine += t1 - t0;
    if (!st && B->tree.use_edges) st = mx_balance_drain(B, cand, nc);
    B->stats.t_balance += mx_wtime() - t1;
    prev = cand;
    nprev = nc;
    cand = NULL;
  }
  mx_free(prev);
  mx_free(cand);
  mx_free(want);
  if (!st && !B->tree.use_edges) st = mx_balance_recursive(B);
  return st;
}

int mx_refine_list(mx_builder *B, const uint32_t *octs, size_t n) {
  mx_octree *T = &B->tree.oct;
  for (size_t i = 0; i < n; i++) {
    const uint32_t o = octs[i];
    if (o >= T->n || (T->flags[o] & MX_OCT_SPLIT)) continue;
    if (T->level[o] >= MX_MAX_LEVEL - 1) { /* the lattice needs one level more */
      mx_error(NULL, 0, "cannot refine a leaf of level %d: %d is the finest level",
               T->level[o], MX_MAX_LEVEL - 1);
      return MX_EINPUT;
    }
    if (T->target[o] <= T->level[o]) T->target[o] = (uint8_t)(T->level[o] + 1);
  }
  return mx_refine_leaves_to_target(B);
}
