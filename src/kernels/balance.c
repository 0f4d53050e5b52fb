/* Balance while refining, with the edge infos (Jaillet & Lobos 2021,
 * Algorithm 1, steps 2 and 3).
 *
 * When an octant O of level l is split, a leaf M of level l-1 touching one of
 * its kept children (level l+1) is two levels coarser than that neighbour: it
 * goes on `to_balance`. (Children found outside the domain are not stored and
 * do not count; a child counts from its creation on, even once it is split
 * itself, which is what makes the result independent of the order of the
 * splits: see balance_recursive.c.) Such an M touches
 * O's parent P along a whole face or edge of P (same level, aligned), so M has
 * one of P's edges as its own, and the edge infos of P's 12 edges (level l-1)
 * list it. Leaves coarser than l-1 cannot touch O (the tree was balanced).
 * Splitting M may in turn unbalance leaves of level l-2, and so on: the list
 * is drained one level at a time, each wave in index order (deterministic). */
#include "kernels/refine.h"

#include "base/common.h"
#include "base/scan.h"

#include <omp.h>
#include <stdlib.h>
#include <string.h>

int mx_octants_touch(uint64_t ka, int la, uint64_t kb, int lb) {
  uint32_t a[3], b[3];
  mx_morton_decode(ka, a);
  mx_morton_decode(kb, b);
  const uint32_t sa = mx_octant_size(la), sb = mx_octant_size(lb);
  int open = 0;
  for (int d = 0; d < 3; d++) {
    const uint32_t a1 = a[d] + sa, b1 = b[d] + sb;
    if (a1 < b[d] || b1 < a[d]) return 0; /* apart */
    if (a[d] < b1 && b[d] < a1) open++;    /* overlap of positive length */
  }
  return open >= 1 && open < 3;
}

/* 1 when leaf m (level lm) touches a kept child of one of run[0..k). */
static int touches_kept_child(const mx_octree *T, const uint32_t *run,
                              size_t k, uint32_t m, int lm) {
  for (size_t i = 0; i < k; i++) {
    const uint32_t o = run[i];
    if (!mx_octants_touch(T->key[o], lm + 1, T->key[m], lm)) continue;
    const int nk = __builtin_popcount(T->kept[o]);
    for (int j = 0; j < nk; j++) {
      const uint32_t ch = T->child0[o] + (uint32_t)j;
      if (mx_octants_touch(T->key[ch], lm + 2, T->key[m], lm)) return 1;
    }
  }
  return 0;
}

/* Leaves of level l-1 touching a kept child of one of the just-split octants
 * run[0..k)
 * (level l, all children of the same parent P), pushed once each (the
 * MX_OCT_QUEUED flag) onto buf. P's 12 edges are looked up once per run. When
 * buf cannot grow, sets *oom and returns. */
static void find_unbalanced(mx_builder *B, const uint32_t *run, size_t k,
                            uint32_t **buf, size_t *n, size_t *cap, int *oom) {
  mx_octree *T = &B->tree.oct;
  const uint32_t p = T->parent[run[0]];
  if (p == MX_NONE) return;
  const int lp = T->level[p];
  uint32_t anchor[3];
  mx_octant_anchor(T->key[p], lp, anchor);
  mx_edges_prefetch_octant(&B->tree.edges, T->key[p], lp); /* 12 misses at once */
  for (int a = 0; a < 3; a++) {
    const mx_edge_table *E = &B->tree.edges.t[lp][a];
    for (int j = 0; j < 4; j++) {
      const size_t e = mx_edge_find(E, mx_edge_key(anchor, a, j));
      if (e == SIZE_MAX) continue;
      for (int s = 0; s < 4; s++) {
        const uint32_t m = __atomic_load_n(&E->e[e].slot[s], __ATOMIC_RELAXED);
        if (m == MX_NONE || m == p) continue;
        if (__atomic_load_n(&T->flags[m], __ATOMIC_RELAXED) &
            (MX_OCT_SPLIT | MX_OCT_QUEUED))
          continue;
        if (!touches_kept_child(T, run, k, m, lp)) continue;
        uint8_t old = __atomic_fetch_or(&T->flags[m], (uint8_t)MX_OCT_QUEUED,
                                        __ATOMIC_RELAXED);
        if (old & MX_OCT_QUEUED) continue;
        if (*n == *cap) {
          const size_t c2 = *cap ? 2 * *cap : 256;
          uint32_t *g = mx_realloc(*buf, c2 * sizeof *g);
          if (!g) { /* out of memory in a worker: told after the region */
            __atomic_store_n(oom, 1, __ATOMIC_RELAXED);
            return;
          }
          *buf = g;
          *cap = c2;
        }
        (*buf)[(*n)++] = m;
      }
    }
  }
}

static int cmp_u32(const void *a, const void *b) {
  uint32_t x = *(const uint32_t *)a, y = *(const uint32_t *)b;
  return (x > y) - (x < y);
}

int mx_balance_drain(mx_builder *B, const uint32_t *split, size_t n) {
  uint32_t *wave = NULL;
  const uint32_t *cur = split;
  size_t ncur = n;
  int st = MX_OK;
  while (ncur > 0 && st == MX_OK) {
    const int nth = omp_get_max_threads();
    uint32_t **bufs = mx_calloc((size_t)nth * sizeof *bufs);
    size_t *cnt = mx_calloc((size_t)nth * sizeof *cnt);
    size_t *cap = mx_calloc((size_t)nth * sizeof *cap);
    if (!bufs || !cnt || !cap) {
      mx_free(bufs);
      mx_free(cnt);
      mx_free(cap);
      st = MX_ENOMEM;
      break;
    }
    int oom = 0;
#pragma omp parallel
    {
      const int t = omp_get_thread_num();
      const uint32_t *par = B->tree.oct.parent;
#pragma omp for schedule(dynamic, 256)
      for (size_t i = 0; i < ncur; i++) {
        /* Runs of siblings (the lists are grouped by parent). */
        if (i > 0 && par[cur[i - 1]] == par[cur[i]]) continue;
        size_t k = 1;
        while (i + k < ncur && par[cur[i + k]] == par[cur[i]]) k++;
        find_unbalanced(B, cur + i, k, &bufs[t], &cnt[t], &cap[t], &oom);
      }
    }
    size_t total = 0;
    for (int t = 0; t < nth; t++) total += cnt[t];
    uint32_t *next = oom ? NULL : mx_alloc((total + 1) * sizeof *next);
    if (!next) st = MX_ENOMEM;
    size_t w = 0;
    for (int t = 0; t < nth; t++) {
      if (next && cnt[t]) memcpy(next + w, bufs[t], cnt[t] * sizeof *next);
      w += cnt[t];
      mx_free(bufs[t]);
    }
    mx_free(bufs);
    mx_free(cnt);
    mx_free(cap);
    if (st) break;
    qsort(next, total, sizeof *next, cmp_u32);
    st = mx_split_octants(B, next, total, 1);
    mx_free(wave);
    wave = next;
    cur = wave;
    ncur = total;
  }
  mx_free(wave);
  return st;
}
