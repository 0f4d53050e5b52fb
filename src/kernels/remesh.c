/* Refinement of an existing balanced octree (Jaillet & Lobos 2021,
 * Algorithm 3 and the steps of Algorithm 2 that follow it): see
 * kernels/remesh.h. */
#include "kernels/remesh.h"

#include "base/common.h"

#include <omp.h>
#include <string.h>

void mx_edges_release(mx_builder *B) {
  if (!B->use_edges || B->edges_released) return;
  B->released_edges = mx_edges_total(&B->edges);
  B->released_edge_bytes = mx_edges_bytes(&B->edges);
  mx_edges_free(&B->edges);
  mx_free(B->scratch_mask);
  mx_free(B->scratch_info);
  mx_free(B->scratch_off);
  B->scratch_mask = NULL;
  B->scratch_info = NULL;
  B->scratch_off = NULL;
  B->scratch_mask_cap = B->scratch_info_cap = B->scratch_off_cap = 0;
  B->edges_released = 1;
}

/* Register every octant of `level` that passes the filter (flag bits that
 * must be set, 0: all). */
static int register_level(mx_builder *B, int level, uint8_t need) {
  const mx_octree *T = &B->oct;
  size_t n = 0;
#pragma omp parallel for schedule(static) reduction(+ : n)
  for (size_t o = 0; o < T->n; o++) n += T->level[o] == level && (T->flags[o] & need) == need;
  if (n == 0) return MX_OK;
  MX_CHECK(mx_edges_reserve(&B->edges, level, 4 * n + 16));
  size_t created[3] = {0, 0, 0};
#pragma omp parallel
  {
    size_t mine[3] = {0, 0, 0};
#pragma omp for schedule(static)
    for (size_t o = 0; o < T->n; o++)
      if (T->level[o] == level && (T->flags[o] & need) == need)
        mx_edges_register(&B->edges, (uint32_t)o, T->key[o], level, mine);
#pragma omp critical
    for (int a = 0; a < 3; a++) created[a] += mine[a];
  }
  mx_edges_add_count(&B->edges, level, created);
  return MX_OK;
}

int mx_edges_restore(mx_builder *B) {
  if (!B->edges_released) return MX_OK;
  B->edges_released = 0;
  const int top = B->edge_levels < MX_MAX_LEVEL - 1 ? B->edge_levels : MX_MAX_LEVEL - 1;
  for (int l = 0; l <= top; l++) MX_CHECK(register_level(B, l, 0));
  for (int l = top + 1; l <= B->edge_lazy_top; l++)
    MX_CHECK(register_level(B, l, (uint8_t)MX_OCT_EDGES));
  return MX_OK;
}

int mx_raise_edge_levels(mx_builder *B, int levels) {
  if (!B->use_edges) return MX_OK;
  MX_CHECK(mx_edges_restore(B));
  if (levels > MX_MAX_LEVEL - 1) levels = MX_MAX_LEVEL - 1;
  for (int l = B->edge_levels + 1; l <= levels; l++)
    if (l >= 0) MX_CHECK(register_level(B, l, 0));
  if (levels > B->edge_levels) B->edge_levels = levels;
  return MX_OK;
}

static int build_root_map(mx_builder *B);

/* The deepest octant holding the level-`level` cell of key k, no deeper
 * than that level (MX_NONE outside the octree). */
static uint32_t covering_octant(const mx_builder *B, uint64_t key, int level) {
  const mx_octree *T = &B->oct;
  uint32_t c[3];
  mx_morton_decode(key, c);
  const int *d = B->grid.dims;
  uint32_t o = B->root_of[((size_t)(c[2] >> MX_MAX_LEVEL) * (size_t)d[1] +
                           (c[1] >> MX_MAX_LEVEL)) * (size_t)d[0] + (c[0] >> MX_MAX_LEVEL)];
  for (int l = 1; l <= level && o != MX_NONE && (T->flags[o] & MX_OCT_SPLIT); l++) {
    const uint32_t ch = mx_octree_child(T, o, mx_morton_child_id(key, l));
    if (ch == MX_NONE) return MX_NONE; /* a child outside the domain */
    o = ch;
  }
  return o;
}

/* The octant (key, level), or MX_NONE when the octree does not hold it. */
static uint32_t find_octant(const mx_builder *B, uint64_t key, int level) {
  const uint32_t o = covering_octant(B, key, level);
  return o != MX_NONE && B->oct.level[o] == level ? o : MX_NONE;
}

/* The face and edge neighbours: (dx, dy, dz) with one or two non-zero. */
static const int8_t near18[18][3] = {
    {-1, 0, 0}, {1, 0, 0},  {0, -1, 0}, {0, 1, 0},  {0, 0, -1}, {0, 0, 1},
    {-1, -1, 0}, {-1, 1, 0}, {1, -1, 0}, {1, 1, 0},  {-1, 0, -1}, {-1, 0, 1},
    {1, 0, -1},  {1, 0, 1},  {0, -1, -1}, {0, -1, 1}, {0, 1, -1},  {0, 1, 1}};

int mx_edges_ensure(mx_builder *B, const uint32_t *list, size_t n, int with_parents) {
  mx_octree *T = &B->oct;
  if (!B->use_edges || n == 0) return MX_OK;
  MX_CHECK(mx_edges_restore(B));
  MX_CHECK(build_root_map(B));
  /* up to 19 octants around each listed octant and each parent, taken once
   * (the flag, set atomically, says who registers) */
  enum { K = 38 };
  uint32_t *got = mx_alloc((K * n + 1) * sizeof *got);
  if (!got) return MX_ENOMEM;
  size_t count[2] = {0, 0};
#pragma omp parallel for schedule(static) reduction(+ : count[:2])
  for (size_t i = 0; i < n; i++) {
    uint32_t *g = got + K * i;
    for (int k = 0; k < K; k++) g[k] = MX_NONE;
    for (int up = 0; up < 1 + (with_parents != 0); up++) {
      const uint32_t o = up ? T->parent[list[i]] : list[i];
      if (o == MX_NONE || T->level[o] <= B->edge_levels) continue;
      const int l = T->level[o];
      for (int k = 0; k < 19; k++) {
        uint32_t x = o;
        if (k < 18) {
          const uint64_t nk = mx_morton_neighbor(T->key[o], l, near18[k][0], near18[k][1],
                                                 near18[k][2], B->grid.dims);
          x = nk == UINT64_MAX ? MX_NONE : find_octant(B, nk, l);
        }
        if (x == MX_NONE || (__atomic_load_n(&T->flags[x], __ATOMIC_RELAXED) & MX_OCT_EDGES))
          continue;
        if (__atomic_fetch_or(&T->flags[x], (uint8_t)MX_OCT_EDGES, __ATOMIC_RELAXED) &
            MX_OCT_EDGES)
          continue;
        g[19 * up + k] = x;
        count[up]++;
      }
    }
  }
  const int l0 = T->level[list[0]];
  int st = MX_OK;
  for (int up = 0; up < 2 && !st; up++)
    if (count[up]) st = mx_edges_reserve(&B->edges, l0 - up, 4 * count[up] + 16);
  if (!st) {
    size_t created[2][3] = {{0, 0, 0}, {0, 0, 0}};
#pragma omp parallel
    {
      size_t mine[2][3] = {{0, 0, 0}, {0, 0, 0}};
#pragma omp for schedule(static)
      for (size_t i = 0; i < K * n; i++) {
        const uint32_t x = got[i];
        if (x == MX_NONE) continue;
        const int up = (int)(i % K) >= 19;
        mx_edges_register(&B->edges, x, T->key[x], T->level[x], mine[up]);
      }
#pragma omp critical
      for (int up = 0; up < 2; up++)
        for (int a = 0; a < 3; a++) created[up][a] += mine[up][a];
    }
    for (int up = 0; up < 2; up++)
      if (count[up]) {
        mx_edges_add_count(&B->edges, l0 - up, created[up]);
        if (l0 - up > B->edge_lazy_top) B->edge_lazy_top = l0 - up;
      }
  }
  mx_free(got);
  return st;
}

/* ---- closures next to coarser leaves ---------------------------------- */


static int build_root_map(mx_builder *B) {
  if (B->root_of) return MX_OK;
  const mx_octree *T = &B->oct;
  const size_t nr = (size_t)B->grid.dims[0] * B->grid.dims[1] * B->grid.dims[2];
  B->root_of = mx_alloc((nr + 1) * sizeof *B->root_of);
  if (!B->root_of) return MX_ENOMEM;
  for (size_t r = 0; r < nr; r++) B->root_of[r] = MX_NONE;
  for (size_t o = 0; o < T->n; o++) {
    if (T->parent[o] != MX_NONE) continue;
    uint32_t c[3];
    mx_morton_decode(T->key[o], c);
    const int *d = B->grid.dims;
    B->root_of[((size_t)(c[2] >> MX_MAX_LEVEL) * (size_t)d[1] + (c[1] >> MX_MAX_LEVEL)) *
                   (size_t)d[0] + (c[0] >> MX_MAX_LEVEL)] = (uint32_t)o;
  }
  return MX_OK;
}

/* 1 if the split octant x has a kept child touching the segment of points
 * with coordinate `at` on axes (p, q) (each: 0 = low side of x, 1 = high). */
static int kept_on_edge(const mx_octree *T, uint32_t x, int p, int sp, int q, int sq) {
  for (int c = 0; c < 8; c++)
    if (((T->kept[x] >> c) & 1) && ((c >> p) & 1) == sp && ((c >> q) & 1) == sq) return 1;
  return 0;
}

/* The transition closes a face that has a centre (a finer neighbour across
 * it) but lacks some edge midpoints (that neighbour's children there were
 * dropped outside the domain) by adding them; every leaf of the same level
 * around such an edge takes the midpoint too. A coarser leaf along that
 * edge cannot: the midpoint would hang on its face (a T-junction). Such
 * coarser leaves are split here, with balance, until none is left. */
int mx_resolve_closures(mx_builder *B) {
  mx_octree *T = &B->oct;
  MX_CHECK(mx_edges_restore(B));
  MX_CHECK(build_root_map(B));
  const int top = mx_edge_top(B);
  for (int round = 0; round < 64; round++) {
    size_t n = 0, cap = 0;
    uint32_t *list = NULL;
    int st = MX_OK;
    /* split octants with children dropped, whose level has masks */
    for (size_t y = 0; y < T->n && !st; y++) {
      if (!(T->flags[y] & MX_OCT_SPLIT) || T->kept[y] == 0xff || T->level[y] > top) continue;
      const int l = T->level[y];
      for (int f = 0; f < 6; f++) {
        const int a = f / 2, sd = f % 2; /* face of y on the side sd of axis a */
        int dd[3] = {0, 0, 0};
        dd[a] = sd ? 1 : -1;
        const uint64_t xk = mx_morton_neighbor(T->key[y], l, dd[0], dd[1], dd[2], B->grid.dims);
        if (xk == UINT64_MAX) continue;
        const uint32_t x = covering_octant(B, xk, l);
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
            const uint64_t ck = mx_morton_neighbor(base, l, od[0], od[1], od[2], B->grid.dims);
            cells[k] = ck == UINT64_MAX ? MX_NONE : covering_octant(B, ck, l);
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
            if (T->flags[z] & MX_OCT_QUEUED) continue;
            T->flags[z] |= MX_OCT_QUEUED;
            if (n == cap) {
              cap = cap ? 2 * cap : 64;
              uint32_t *g = mx_realloc(list, cap * sizeof *g);
              if (!g) {
                st = MX_ENOMEM;
                break;
              }
              list = g;
            }
            list[n++] = z;
          }
        }
      }
    }
    for (size_t i = 0; i < n; i++) T->flags[list[i]] &= (uint8_t)~MX_OCT_QUEUED;
    if (st || n == 0) {
      mx_free(list);
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
      if (!st) st = B->use_edges ? mx_balance_drain(B, list, k) : mx_balance_recursive(B);
      /* the rest of the list is rebuilt next round */
      break;
    }
    mx_free(list);
    MX_CHECK(st);
  }
  mx_error(NULL, 0, "internal: closures next to coarser leaves still left after 64 rounds");
  return MX_EINTERNAL;
}

void mx_retarget_leaves(mx_builder *B) {
  mx_octree *T = &B->oct;
#pragma omp parallel for schedule(static)
  for (size_t o = 0; o < T->n; o++) {
    if (T->flags[o] & MX_OCT_SPLIT) continue;
    double lo[3], hi[3];
    mx_octant_box(&B->grid, T->key[o], T->level[o], lo, hi);
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
  mx_octree *T = &B->oct;
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
    if (!st && B->use_edges) st = mx_balance_drain(B, cand, nc);
    B->stats.t_balance += mx_wtime() - t1;
    prev = cand;
    nprev = nc;
    cand = NULL;
  }
  mx_free(prev);
  mx_free(cand);
  mx_free(want);
  if (!st && !B->use_edges) st = mx_balance_recursive(B);
  return st;
}

int mx_refine_list(mx_builder *B, const uint32_t *octs, size_t n) {
  mx_octree *T = &B->oct;
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
