/* Edge infos where and when they are needed, for refining an octree that
 * is already balanced (re-meshing, Jaillet & Lobos 2021, section 4.2): the
 * finest level of a run keeps none, and between two meshings they are
 * released. See kernels/edges_lazy.h. */
#include "kernels/edges_lazy.h"

#include "base/common.h"

#include <omp.h>
#include <string.h>

void mx_edges_release(mx_builder *B) {
  if (!B->tree.use_edges || B->tree.edges_released) return;
  B->tree.released_edges = mx_edges_total(&B->tree.edges);
  B->tree.released_edge_bytes = mx_edges_bytes(&B->tree.edges);
  mx_edges_free(&B->tree.edges);
  mx_free(B->scratch_mask);
  mx_free(B->scratch_info);
  mx_free(B->scratch_off);
  B->scratch_mask = NULL;
  B->scratch_info = NULL;
  B->scratch_off = NULL;
  B->scratch_mask_cap = B->scratch_info_cap = B->scratch_off_cap = 0;
  B->tree.edges_released = 1;
}

/* Register every octant of `level` that passes the filter (flag bits that
 * must be set, 0: all). */
static int register_level(mx_builder *B, int level, uint8_t need) {
  const mx_octree *T = &B->tree.oct;
  size_t n = 0;
#pragma omp parallel for schedule(static) reduction(+ : n)
  for (size_t o = 0; o < T->n; o++) n += T->level[o] == level && (T->flags[o] & need) == need;
  if (n == 0) return MX_OK;
  MX_CHECK(mx_edges_reserve(&B->tree.edges, level, 4 * n + 16));
  size_t created[3] = {0, 0, 0};
#pragma omp parallel
  {
    size_t mine[3] = {0, 0, 0};
#pragma omp for schedule(static)
    for (size_t o = 0; o < T->n; o++)
      if (T->level[o] == level && (T->flags[o] & need) == need)
        mx_edges_register(&B->tree.edges, (uint32_t)o, T->key[o], level, mine);
#pragma omp critical
    for (int a = 0; a < 3; a++) created[a] += mine[a];
  }
  mx_edges_add_count(&B->tree.edges, level, created);
  return MX_OK;
}

int mx_edges_restore(mx_builder *B) {
  if (!B->tree.edges_released) return MX_OK;
  B->tree.edges_released = 0;
  const int top = B->tree.edge_levels < MX_MAX_LEVEL - 1 ? B->tree.edge_levels : MX_MAX_LEVEL - 1;
  for (int l = 0; l <= top; l++) MX_CHECK(register_level(B, l, 0));
  for (int l = top + 1; l <= B->tree.edge_lazy_top; l++)
    MX_CHECK(register_level(B, l, (uint8_t)MX_OCT_EDGES));
  return MX_OK;
}

int mx_raise_edge_levels(mx_builder *B, int levels) {
  if (!B->tree.use_edges) return MX_OK;
  MX_CHECK(mx_edges_restore(B));
  if (levels > MX_MAX_LEVEL - 1) levels = MX_MAX_LEVEL - 1;
  for (int l = B->tree.edge_levels + 1; l <= levels; l++)
    if (l >= 0) MX_CHECK(register_level(B, l, 0));
  if (levels > B->tree.edge_levels) B->tree.edge_levels = levels;
  return MX_OK;
}


/* The deepest octant holding the level-`level` cell of key k, no deeper
 * than that level (MX_NONE outside the octree). */
uint32_t mx_covering_octant(const mx_builder *B, uint64_t key, int level) {
  const mx_octree *T = &B->tree.oct;
  uint32_t c[3];
  mx_morton_decode(key, c);
  const int *d = B->tree.grid.dims;
  uint32_t o = B->tree.root_of[((size_t)(c[2] >> MX_MAX_LEVEL) * (size_t)d[1] +
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
  const uint32_t o = mx_covering_octant(B, key, level);
  return o != MX_NONE && B->tree.oct.level[o] == level ? o : MX_NONE;
}

/* The face and edge neighbours: (dx, dy, dz) with one or two non-zero. */
static const int8_t near18[18][3] = {
    {-1, 0, 0}, {1, 0, 0},  {0, -1, 0}, {0, 1, 0},  {0, 0, -1}, {0, 0, 1},
    {-1, -1, 0}, {-1, 1, 0}, {1, -1, 0}, {1, 1, 0},  {-1, 0, -1}, {-1, 0, 1},
    {1, 0, -1},  {1, 0, 1},  {0, -1, -1}, {0, -1, 1}, {0, 1, -1},  {0, 1, 1}};

int mx_edges_ensure(mx_builder *B, const uint32_t *list, size_t n, int with_parents) {
  mx_octree *T = &B->tree.oct;
  if (!B->tree.use_edges || n == 0) return MX_OK;
  MX_CHECK(mx_edges_restore(B));
  MX_CHECK(mx_build_root_map(B));
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
      if (o == MX_NONE || T->level[o] <= B->tree.edge_levels) continue;
      const int l = T->level[o];
      for (int k = 0; k < 19; k++) {
        uint32_t x = o;
        if (k < 18) {
          const uint64_t nk = mx_morton_neighbor(T->key[o], l, near18[k][0], near18[k][1],
                                                 near18[k][2], B->tree.grid.dims);
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
    if (count[up]) st = mx_edges_reserve(&B->tree.edges, l0 - up, 4 * count[up] + 16);
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
        mx_edges_register(&B->tree.edges, x, T->key[x], T->level[x], mine[up]);
      }
#pragma omp critical
      for (int up = 0; up < 2; up++)
        for (int a = 0; a < 3; a++) created[up][a] += mine[up][a];
    }
    for (int up = 0; up < 2; up++)
      if (count[up]) {
        mx_edges_add_count(&B->tree.edges, l0 - up, created[up]);
        if (l0 - up > B->tree.edge_lazy_top) B->tree.edge_lazy_top = l0 - up;
      }
  }
  mx_free(got);
  return st;
}



int mx_build_root_map(mx_builder *B) {
  if (B->tree.root_of) return MX_OK;
  const mx_octree *T = &B->tree.oct;
  const size_t nr = (size_t)B->tree.grid.dims[0] * B->tree.grid.dims[1] * B->tree.grid.dims[2];
  B->tree.root_of = mx_alloc((nr + 1) * sizeof *B->tree.root_of);
  if (!B->tree.root_of) return MX_ENOMEM;
  for (size_t r = 0; r < nr; r++) B->tree.root_of[r] = MX_NONE;
  for (size_t o = 0; o < T->n; o++) {
    if (T->parent[o] != MX_NONE) continue;
    uint32_t c[3];
    mx_morton_decode(T->key[o], c);
    const int *d = B->tree.grid.dims;
    B->tree.root_of[((size_t)(c[2] >> MX_MAX_LEVEL) * (size_t)d[1] + (c[1] >> MX_MAX_LEVEL)) *
                   (size_t)d[0] + (c[0] >> MX_MAX_LEVEL)] = (uint32_t)o;
  }
  return MX_OK;
}
