/* Leaves in the domain: count, levels, fingerprint and per-rank figures,
 * reduced over the ranks; and the leaves gathered on one rank. */
#include "mpi/p4est_leaves.h"

#include "base/common.h"
#include "kernels/refine.h"
#include "base/scan.h"

#include <string.h>

/* The single-process hash's parts (kernels/leaves.c): the same fingerprint. */
uint64_t mx_p4est_leaf_mix(uint64_t key, int level) { return mx_leaf_hash_term(key, level); }

uint64_t mx_p4est_hash_finish(uint64_t sum, uint64_t n) { return mx_leaf_hash_finish(sum, n); }

int mx_p4est_summarize(const mx_p4est_octree *P, mx_p4est_summary *s) {
  memset(s, 0, sizeof *s);
  p8est_t *p8 = P->p8;
  long long loc[MX_MAX_LEVEL + 1 + 4] = {0}; /* per level, then surface, quads, ... */
  long long *lev = loc, *other = loc + MX_MAX_LEVEL + 1;
  uint64_t hsum = 0;
  for (p4est_topidx_t t = p8->first_local_tree; t <= p8->last_local_tree; t++) {
    p8est_tree_t *tr = p8est_tree_array_index(p8->trees, t);
    for (size_t i = 0; i < tr->quadrants.elem_count; i++) {
      const p8est_quadrant_t *q = p8est_quadrant_array_index(&tr->quadrants, i);
      const mx_pq *d = q->p.user_data;
      if (!mx_pq_kept(d)) continue;
      lev[q->level]++;
      if (d->flags & MX_PQ_SURFACE) other[0]++;
      hsum += mx_p4est_leaf_mix(mx_p4est_key(P, t, q), q->level);
    }
  }
  long long leaves = 0;
  for (int l = 0; l <= MX_MAX_LEVEL; l++) leaves += lev[l];
  other[1] = (long long)p8->local_num_quadrants;
  other[2] = (long long)(P->ghost ? P->ghost->ghosts.elem_count : 0);
  long long glob[MX_MAX_LEVEL + 1 + 4];
  MPI_Allreduce(loc, glob, MX_MAX_LEVEL + 1 + 4, MPI_LONG_LONG, MPI_SUM, P->comm);
  memcpy(s->per_level, glob, sizeof s->per_level);
  for (int l = 0; l <= MX_MAX_LEVEL; l++) s->leaves += s->per_level[l];
  s->surface = glob[MX_MAX_LEVEL + 1];
  s->quadrants = glob[MX_MAX_LEVEL + 2];
  s->ghosts = glob[MX_MAX_LEVEL + 3];
  s->outside = s->quadrants - s->leaves;
  /* unsigned sums wrap around, as the single-process sum does */
  uint64_t hall = 0;
  MPI_Allreduce(&hsum, &hall, 1, MPI_UINT64_T, MPI_SUM, P->comm);
  s->hash = mx_p4est_hash_finish(hall, (uint64_t)s->leaves);
  long long cnt[4] = {(long long)P->split_requested, (long long)P->split_balance,
                      (long long)P->located, P->shipped_bytes},
            call[4];
  MPI_Allreduce(cnt, call, 4, MPI_LONG_LONG, MPI_SUM, P->comm);
  s->split_requested = call[0];
  s->split_balance = call[1];
  s->located = call[2];
  s->list_bytes = call[3];
  /* per rank: min and max (max of -x is -min) */
  long long mm[4] = {leaves, -leaves, other[1], -other[1]}, mmax[4];
  MPI_Allreduce(mm, mmax, 4, MPI_LONG_LONG, MPI_MAX, P->comm);
  s->leaves_max = mmax[0];
  s->leaves_min = -mmax[1];
  s->quadrants_max = mmax[2];
  s->quadrants_min = -mmax[3];
  const double rss = mx_peak_rss_mb();
  double dv[10] = {rss,           -rss,          P->t.refine,    -P->t.refine, P->t.balance,
                   -P->t.balance, P->t.partition, -P->t.partition, P->t.ghost,  -P->t.ghost},
         dmax[10];
  MPI_Allreduce(dv, dmax, 10, MPI_DOUBLE, MPI_MAX, P->comm);
  s->rss_max_mb = dmax[0];
  s->rss_min_mb = -dmax[1];
  s->tmax.refine = dmax[2];
  s->tmin.refine = -dmax[3];
  s->tmax.balance = dmax[4];
  s->tmin.balance = -dmax[5];
  s->tmax.partition = dmax[6];
  s->tmin.partition = -dmax[7];
  s->tmax.ghost = dmax[8];
  s->tmin.ghost = -dmax[9];
  return MX_OK;
}

int mx_p4est_gather_leaves(const mx_p4est_octree *P, int root, int all_quadrants,
                           uint64_t **keys, uint8_t **levels, uint8_t **kept, size_t *n) {
  *keys = NULL;
  *levels = NULL;
  if (kept) *kept = NULL;
  *n = 0;
  p8est_t *p8 = P->p8;
  /* local records of two words: the key, then level | kept << 8 */
  size_t nloc = 0;
  for (p4est_topidx_t t = p8->first_local_tree; t <= p8->last_local_tree; t++) {
    p8est_tree_t *tr = p8est_tree_array_index(p8->trees, t);
    for (size_t i = 0; i < tr->quadrants.elem_count; i++)
      nloc += all_quadrants ||
              mx_pq_kept(p8est_quadrant_array_index(&tr->quadrants, i)->p.user_data);
  }
  uint64_t *mine = mx_alloc((2 * nloc + 1) * sizeof *mine);
  int st = mine ? MX_OK : MX_ENOMEM, all = st;
  MPI_Allreduce(&st, &all, 1, MPI_INT, MPI_MAX, P->comm);
  if (all) {
    mx_free(mine);
    return all;
  }
  size_t w = 0;
  for (p4est_topidx_t t = p8->first_local_tree; t <= p8->last_local_tree; t++) {
    p8est_tree_t *tr = p8est_tree_array_index(p8->trees, t);
    for (size_t i = 0; i < tr->quadrants.elem_count; i++) {
      const p8est_quadrant_t *q = p8est_quadrant_array_index(&tr->quadrants, i);
      const int in = mx_pq_kept(q->p.user_data);
      if (!in && !all_quadrants) continue;
      mine[w++] = mx_p4est_key(P, t, q);
      mine[w++] = (uint64_t)q->level | (uint64_t)in << 8;
    }
  }
  /* counts in 64-bit words; MPI counts are int: fine below 2^30 leaves */
  int cnt = (int)(2 * nloc);
  int *counts = NULL, *displs = NULL;
  uint64_t *all_pairs = NULL;
  size_t total = 0;
  if (P->rank == root) {
    counts = mx_alloc(((size_t)P->size + 1) * sizeof *counts);
    displs = mx_alloc(((size_t)P->size + 1) * sizeof *displs);
    st = counts && displs ? MX_OK : MX_ENOMEM;
  }
  MPI_Gather(&cnt, 1, MPI_INT, counts, 1, MPI_INT, root, P->comm);
  if (P->rank == root && !st) {
    for (int r = 0; r < P->size; r++) {
      displs[r] = (int)total;
      total += (size_t)counts[r];
    }
    all_pairs = mx_alloc((total + 1) * sizeof *all_pairs);
    if (!all_pairs) st = MX_ENOMEM;
  }
  MPI_Allreduce(&st, &all, 1, MPI_INT, MPI_MAX, P->comm);
  if (!all)
    MPI_Gatherv(mine, cnt, MPI_UINT64_T, all_pairs, counts, displs, MPI_UINT64_T, root,
                P->comm);
  mx_free(mine);
  mx_free(counts);
  mx_free(displs);
  if (all || P->rank != root) {
    mx_free(all_pairs);
    return all;
  }
  /* sort by key (ranks hold consecutive Morton ranges per tree, but trees
   * are in p4est's order, not ours) */
  const size_t m = total / 2;
  uint64_t *k = mx_alloc((m + 1) * sizeof *k);
  uint32_t *idx = mx_alloc((m + 1) * sizeof *idx);
  uint8_t *lv = mx_alloc(m + 1), *in = kept ? mx_alloc(m + 1) : NULL;
  if (!k || !idx || !lv || (kept && !in)) st = MX_ENOMEM;
  for (size_t i = 0; !st && i < m; i++) {
    k[i] = all_pairs[2 * i];
    idx[i] = (uint32_t)i;
  }
  if (!st) st = mx_sort_u64(k, idx, m);
  for (size_t i = 0; !st && i < m; i++) {
    const uint64_t r = all_pairs[2 * idx[i] + 1];
    lv[i] = (uint8_t)(r & 255);
    if (in) in[i] = (uint8_t)(r >> 8);
  }
  mx_free(all_pairs);
  mx_free(idx);
  if (st) {
    mx_free(k);
    mx_free(lv);
    mx_free(in);
    return st;
  }
  *keys = k;
  *levels = lv;
  if (kept) *kept = in;
  *n = m;
  return MX_OK;
}
