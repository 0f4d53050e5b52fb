/* Closures next to coarser leaves: the leaves a face closure of the
 * transition would leave with a hanging midpoint are split (with balance)
 * after every refinement. See kernels/closures.h. */
#include "kernels/closures.h"

#include "base/common.h"
#include "kernels/edges_lazy.h"
#include "soa/tree_valid.h"

#include <omp.h>
#include <string.h>

/* 1 if the split octant x has a kept child touching the segment of points
 * with coordinate `at` on axes (p, q) (each: 0 = low side of x, 1 = high). */
static int kept_on_edge(const mx_octree *T, uint32_t x, int p, int sp, int q, int sq) {
  for (int c = 0; c < 8; c++)
    if (((T->kept[x] >> c) & 1) && ((c >> p) & 1) == sp && ((c >> q) & 1) == sq) return 1;
  return 0;
}

/* The coarser leaves along the face edges of the split octant y (with
 * children dropped, at a level with masks) that would hang a closure's
 * midpoint, in the scan's order, into out (at most 6 faces x 4 edges x 2);
 * their count. Reads the octree only. */
static int closure_victims(const mx_builder *B, uint32_t y, uint32_t out[48]) {
  const mx_octree *T = &B->tree.oct;
  const int l = T->level[y];
  int n = 0;
  for (int f = 0; f < 6; f++) {
    const int a = f / 2, sd = f % 2; /* face of y on the side sd of axis a */
    int dd[3] = {0, 0, 0};
    dd[a] = sd ? 1 : -1;
    const uint64_t xk = mx_morton_neighbor(T->key[y], l, dd[0], dd[1], dd[2], B->tree.grid.dims);
    if (xk == UINT64_MAX) continue;
    const uint32_t x = mx_covering_octant(B, xk, l);
    if (x == MX_NONE || T->level[x] != l || (T->flags[x] & MX_OCT_SPLIT)) continue;
    /* y's children touching the face: bit a == sd */
    int any = 0;
    for (int c = 0; c < 8; c++) any |= ((T->kept[y] >> c) & 1) && ((c >> a) & 1) == sd;
    if (!any) continue;
    /* the 4 edges of the face: along u (at v = 0 or 1), along v (at u = 0 or 1) */
    const int ax[2] = {(a + 1) % 3, (a + 2) % 3};
    for (int e = 0; e < 4; e++) {
      const int other = ax[1 - e / 2], so = e % 2;
      if (kept_on_edge(T, y, a, sd, other, so)) continue; /* a natural midpoint */
      /* the two other cells around the edge: beyond `other`, on x's and y's side */
      int od[3] = {0, 0, 0};
      od[other] = so ? 1 : -1;
      int natural = 0;
      uint32_t cells[2];
      for (int k = 0; k < 2; k++) {
        const uint64_t base = k ? T->key[y] : xk;
        const uint64_t ck = mx_morton_neighbor(base, l, od[0], od[1], od[2], B->tree.grid.dims);
        cells[k] = ck == UINT64_MAX ? MX_NONE : mx_covering_octant(B, ck, l);
        const uint32_t z = cells[k];
        /* a split octant of level l there with a kept child on the edge */
        /* its children along the edge: towards the face plane on axis a
         * (y's side: bit sd; x's side: the other), towards x and y on
         * `other` */
        if (z != MX_NONE && T->level[z] == l && (T->flags[z] & MX_OCT_SPLIT) &&
            kept_on_edge(T, z, a, k ? sd : !sd, other, !so))
          natural = 1;
      }
      if (natural) continue;
      for (int k = 0; k < 2; k++) {
        const uint32_t z = cells[k];
        if (z == MX_NONE || T->level[z] >= l || (T->flags[z] & MX_OCT_SPLIT)) continue;
        out[n++] = z;
      }
    }
  }
  return n;
}

/* Appends v to the growing array (*a, *n, *cap); 0, or -1 when memory
 * runs out (the array is kept). */
static int push_u32(uint32_t **a, size_t *n, size_t *cap, uint32_t v) {
  if (*n == *cap) {
    const size_t c2 = *cap ? 2 * *cap : 64;
    uint32_t *g = mx_realloc(*a, c2 * sizeof *g);
    if (!g) return -1;
    *a = g;
    *cap = c2;
  }
  (*a)[(*n)++] = v;
  return 0;
}

/* The transition closes a face that has a centre (a finer neighbour across
 * it) but lacks some edge midpoints (that neighbour's children there were
 * dropped outside the domain) by adding them; every leaf of the same level
 * around such an edge takes the midpoint too. A coarser leaf along that
 * edge cannot: the midpoint would hang on its face (a T-junction). Such
 * coarser leaves are split here, with balance, until none is left. */
int mx_resolve_closures(mx_builder *B) {
  mx_octree *T = &B->tree.oct;
  MX_CHECK(mx_edges_restore(B));
  MX_CHECK(mx_build_root_map(B));
  const int top = mx_edge_top(&B->tree);
  const int nth = omp_get_max_threads();
  for (int round = 0; round < 64; round++) {
    /* split octants with children dropped, whose level has masks: their
     * victims found in parallel, each thread a contiguous range of octants
     * (so the threads' lists in turn are in octant order), then listed once
     * each in that order (the QUEUED flag) */
    uint32_t **found = mx_calloc((size_t)nth * sizeof *found);
    size_t *nfound = mx_calloc((size_t)nth * sizeof *nfound);
    int oom = !found || !nfound;
    if (!oom) {
#pragma omp parallel num_threads(nth)
      {
        const int t = omp_get_thread_num(), nt = omp_get_num_threads();
        const size_t y0 = T->n * (size_t)t / (size_t)nt, y1 = T->n * (size_t)(t + 1) / (size_t)nt;
        size_t cap = 0;
        uint32_t v[48];
        for (size_t y = y0; y < y1; y++) {
          if (!(T->flags[y] & MX_OCT_SPLIT) || T->kept[y] == 0xff || T->level[y] > top) continue;
          const int k = closure_victims(B, (uint32_t)y, v);
          for (int i = 0; i < k; i++)
            if (push_u32(&found[t], &nfound[t], &cap, v[i])) {
              __atomic_store_n(&oom, 1, __ATOMIC_RELAXED);
              y = y1 - 1;
              break;
            }
        }
      }
    }
    size_t n = 0, cap = 0;
    uint32_t *list = NULL;
    int st = oom ? MX_ENOMEM : MX_OK;
    for (int t = 0; t < nth && !st; t++)
      for (size_t i = 0; i < nfound[t] && !st; i++) {
        const uint32_t z = found[t][i];
        if (T->flags[z] & MX_OCT_QUEUED) continue;
        T->flags[z] |= MX_OCT_QUEUED;
        if (push_u32(&list, &n, &cap, z)) st = MX_ENOMEM;
      }
    for (int t = 0; found && t < nth; t++) mx_free(found[t]);
    mx_free(found);
    mx_free(nfound);
    for (size_t i = 0; i < n; i++) T->flags[list[i]] &= (uint8_t)~MX_OCT_QUEUED;
    if (st || n == 0) {
      mx_free(list);
      if (!st) MX_TREE_INVARIANTS(&B->tree, MX_TREE_BALANCED, "refinement and its closures");
      return st;
    }
    /* split them, coarsest first, one level at a time, with balance */
    for (int l = 0; l <= MX_MAX_LEVEL && !st; l++) {
      size_t k = 0;
      for (size_t i = 0; i < n; i++)
        if (T->level[list[i]] == l && !(T->flags[list[i]] & MX_OCT_SPLIT)) list[k++] = list[i];
      if (!k) {
        continue;
      }
      st = mx_split_octants(B, list, k, 1);
      if (!st) st = B->tree.use_edges ? mx_balance_drain(B, list, k) : mx_balance_recursive(B);
      /* the rest of the list is rebuilt next round */
      break;
    }
    mx_free(list);
    MX_CHECK(st);
  }
  mx_error(NULL, 0, "internal: closures next to coarser leaves still left after 64 rounds");
  return MX_EINTERNAL;
}
