/* The octree's invariants, checked from its arrays alone: see
 * soa/tree_valid.h for what is checked and why that is enough. Each pass
 * runs in parallel and keeps the smallest index that breaks its rule; that
 * one is checked again serially to write the message, so the message does
 * not depend on the thread count. */
#include "soa/tree_valid.h"

#include "base/common.h"
#include "base/morton.h"
#include "base/scan.h"

#include <stdio.h>

static size_t runs;

size_t mx_tree_valid_runs(void) { return __atomic_load_n(&runs, __ATOMIC_RELAXED); }

enum { MSG = 256 };

static int broken(const char *where, const char *what) {
  mx_error(NULL, 0, "internal: octree invariant broken after %s: %s", where, what);
  return MX_EINTERNAL;
}

/* Key bits below an octant of this level (its Morton range is key + [0, 1 << 3(MAX-l))). */
static inline uint64_t below(int level) {
  return (1ULL << (3 * (MX_MAX_LEVEL - level))) - 1;
}

/* Root cube of a key, or SIZE_MAX outside the grid. */
static size_t root_cube(uint64_t key, const int dims[3]) {
  uint32_t c[3];
  mx_morton_decode(key, c);
  for (int a = 0; a < 3; a++)
    if ((c[a] >> MX_MAX_LEVEL) >= (uint32_t)dims[a]) return SIZE_MAX;
  return ((size_t)(c[2] >> MX_MAX_LEVEL) * (size_t)dims[1] + (c[1] >> MX_MAX_LEVEL)) *
             (size_t)dims[0] + (c[0] >> MX_MAX_LEVEL);
}

#define BAD(...)                                           \
  do {                                                     \
    if (msg) snprintf(msg, MSG, __VA_ARGS__);              \
    return 1;                                              \
  } while (0)

/* ---- (a) the forest ----------------------------------------------------- */

/* 1 when octant o breaks a rule of (a); msg (when not NULL) says which. */
static int octant_bad(const mx_octree *T, const int dims[3], const uint32_t *root_of, size_t o,
                      char *msg) {
  const int l = T->level[o];
  const uint64_t key = T->key[o];
  const uint32_t p = T->parent[o];
  if (l > MX_MAX_LEVEL) BAD("octant %zu has level %d (finest %d)", o, l, MX_MAX_LEVEL);
  if ((key & below(l)) || (key >> 63))
    BAD("octant %zu (level %d) has key %#llx, not on its level's lattice", o, l,
        (unsigned long long)key);
  const size_t cube = root_cube(key, dims);
  if (cube == SIZE_MAX)
    BAD("octant %zu (key %#llx) lies outside the root grid %dx%dx%d", o,
        (unsigned long long)key, dims[0], dims[1], dims[2]);
  if (p == MX_NONE) {
    if (l != 0) BAD("octant %zu has no parent but level %d", o, l);
    if (root_of[cube] != o)
      BAD("octants %u and %zu are both the root of cube %zu", root_of[cube], o, cube);
  } else {
    if (p >= o) BAD("octant %zu has parent %u, not stored before it", o, p);
    if (T->level[p] + 1 != l)
      BAD("octant %zu (level %d) has parent %u of level %d", o, l, p, T->level[p]);
    if (!(T->flags[p] & MX_OCT_SPLIT)) BAD("octant %zu has parent %u, not flagged split", o, p);
    if (mx_morton_parent(key, l) != T->key[p])
      BAD("octant %zu (key %#llx, level %d) is not inside its parent %u (key %#llx)", o,
          (unsigned long long)key, l, p, (unsigned long long)T->key[p]);
    const int c = mx_morton_child_id(key, l);
    if (!((T->kept[p] >> c) & 1))
      BAD("octant %zu is child %d of octant %u, whose kept mask %#x lacks it", o, c, p,
          T->kept[p]);
    if (mx_octree_child(T, p, c) != o)
      BAD("octant %zu is child %d of octant %u, whose slot holds octant %u", o, c, p,
          mx_octree_child(T, p, c));
  }
  if (!(T->flags[o] & MX_OCT_SPLIT)) {
    if (T->child0[o] != MX_NONE || T->kept[o] != 0)
      BAD("leaf %zu has children (first %u, kept mask %#x)", o, T->child0[o], T->kept[o]);
  } else if (T->kept[o] == 0) {
    if (T->child0[o] != MX_NONE)
      BAD("split octant %zu keeps no child but has first child %u", o, T->child0[o]);
  } else if (T->child0[o] == MX_NONE || T->child0[o] <= o ||
             (size_t)T->child0[o] + (size_t)__builtin_popcount(T->kept[o]) > T->n) {
    BAD("split octant %zu has its children at %u (%d kept) of %zu octants", o, T->child0[o],
        __builtin_popcount(T->kept[o]), T->n);
  }
  return 0;
}

static int check_forest(const mx_octree *T, const int dims[3], const char *where) {
  const size_t nroot = (size_t)dims[0] * (size_t)dims[1] * (size_t)dims[2];
  uint32_t *root_of = mx_alloc((nroot + 1) * sizeof *root_of);
  if (!root_of) return MX_ENOMEM;
  for (size_t r = 0; r < nroot; r++) root_of[r] = MX_NONE;
  for (size_t o = 0; o < T->n; o++) {
    if (T->parent[o] != MX_NONE || T->level[o] != 0) continue;
    const size_t cube = root_cube(T->key[o], dims);
    if (cube != SIZE_MAX && root_of[cube] == MX_NONE) root_of[cube] = (uint32_t)o;
  }
  size_t first = SIZE_MAX, kept = 0, nonroot = 0;
  const size_t n = T->n;
#pragma omp parallel for schedule(static) reduction(min : first) \
    reduction(+ : kept, nonroot) if (n > MX_PAR_MIN)
  for (size_t o = 0; o < n; o++) {
    if (octant_bad(T, dims, root_of, o, NULL) && o < first) first = o;
    if (T->flags[o] & MX_OCT_SPLIT) kept += (size_t)__builtin_popcount(T->kept[o]);
    nonroot += T->parent[o] != MX_NONE;
  }
  int st = MX_OK;
  char msg[MSG];
  if (first != SIZE_MAX) {
    octant_bad(T, dims, root_of, first, msg);
    st = broken(where, msg);
  } else if (kept != nonroot) {
    snprintf(msg, sizeof msg, "the split octants keep %zu children but %zu octants have a "
                              "parent", kept, nonroot);
    st = broken(where, msg);
  }
  mx_free(root_of);
  return st;
}

/* ---- (b) the leaves in Morton order ------------------------------------- */

/* 1 when leaf keys ka (level la) and kb (level lb), in this order, are not
 * strictly increasing or overlap. */
static inline int leaves_out_of_order(uint64_t ka, int la, uint64_t kb) {
  return kb <= ka || kb - ka <= below(la);
}

static int order_message(const mx_octree *T, uint32_t a, uint32_t b, const char *where) {
  char msg[MSG];
  snprintf(msg, sizeof msg,
           "leaves %u (key %#llx, level %d) and %u (key %#llx, level %d), in this order, %s",
           a, (unsigned long long)T->key[a], T->level[a], b, (unsigned long long)T->key[b],
           T->level[b], T->key[a] == T->key[b] ? "have the same key"
                        : T->key[b] < T->key[a] ? "are not in Morton order" : "overlap");
  return broken(where, msg);
}

/* The leaves sorted by key (*keys, *ids: mx_alloc), checked for (b). */
static int sorted_leaves(const mx_octree *T, uint64_t **keys, uint32_t **ids, size_t *nleaves,
                         const char *where) {
  size_t n = 0;
#pragma omp parallel for schedule(static) reduction(+ : n) if (T->n > MX_PAR_MIN)
  for (size_t o = 0; o < T->n; o++) n += !(T->flags[o] & MX_OCT_SPLIT);
  uint64_t *k = mx_alloc((n + 1) * sizeof *k);
  uint32_t *id = mx_alloc((n + 1) * sizeof *id);
  if (!k || !id) {
    mx_free(k);
    mx_free(id);
    return MX_ENOMEM;
  }
  for (size_t o = 0, w = 0; o < T->n; o++)
    if (!(T->flags[o] & MX_OCT_SPLIT)) {
      k[w] = T->key[o];
      id[w++] = (uint32_t)o;
    }
  int st = mx_sort_u64(k, id, n) ? MX_ENOMEM : MX_OK;
  size_t first = SIZE_MAX;
  if (!st) {
#pragma omp parallel for schedule(static) reduction(min : first) if (n > MX_PAR_MIN)
    for (size_t i = 1; i < n; i++)
      if (leaves_out_of_order(k[i - 1], T->level[id[i - 1]], k[i]) && i < first) first = i;
    if (first != SIZE_MAX) st = order_message(T, id[first - 1], id[first], where);
  }
  if (st) {
    mx_free(k);
    mx_free(id);
    return st;
  }
  *keys = k;
  *ids = id;
  *nleaves = n;
  return MX_OK;
}

int mx_leaves_valid(const mx_tree *t, const uint32_t *leaves, size_t n, const char *where) {
  const mx_octree *T = &t->oct;
  __atomic_fetch_add(&runs, 1, __ATOMIC_RELAXED);
  size_t count = 0, first = SIZE_MAX;
#pragma omp parallel for schedule(static) reduction(+ : count) if (T->n > MX_PAR_MIN)
  for (size_t o = 0; o < T->n; o++) count += !(T->flags[o] & MX_OCT_SPLIT);
#pragma omp parallel for schedule(static) reduction(min : first) if (n > MX_PAR_MIN)
  for (size_t i = 0; i < n; i++) {
    const uint32_t o = leaves[i];
    const int bad = o >= T->n || (T->flags[o] & MX_OCT_SPLIT) ||
                    (i > 0 && leaves_out_of_order(T->key[leaves[i - 1]],
                                                  T->level[leaves[i - 1]], T->key[o]));
    if (bad && i < first) first = i;
  }
  char msg[MSG];
  if (first != SIZE_MAX) {
    const uint32_t o = leaves[first];
    if (o < T->n && !(T->flags[o] & MX_OCT_SPLIT))
      return order_message(T, leaves[first - 1], o, where);
    snprintf(msg, sizeof msg, "entry %zu of the leaf list is octant %u, %s", first, o,
             o >= T->n ? "not stored" : "not a leaf");
    return broken(where, msg);
  }
  if (count != n) {
    snprintf(msg, sizeof msg, "the leaf list holds %zu leaves of %zu", n, count);
    return broken(where, msg);
  }
  return MX_OK;
}

/* ---- (c) the 2:1 balance across faces and edges ------------------------- */

/* The leaves' keys in a sparse table (load at most 1/4, so that a lookup of
 * a key not there, the common case, reads about one slot): slot -> place
 * in the sorted leaf arrays + 1, 0 empty. */
typedef struct {
  uint32_t *slot;
  const uint64_t *keys;
  size_t mask;
} leaf_table;

static inline size_t leaf_slot(uint64_t key, size_t mask) {
  uint64_t h = key * 0x9E3779B97F4A7C15ULL;
  h ^= h >> 32;
  return (size_t)h & mask;
}

static int leaf_table_build(leaf_table *H, const uint64_t *keys, size_t n) {
  size_t cap = 64;
  while (cap < 4 * n) cap *= 2;
  H->slot = mx_calloc(cap * sizeof *H->slot);
  if (!H->slot) return MX_ENOMEM;
  H->keys = keys;
  H->mask = cap - 1;
  for (size_t i = 0; i < n; i++) {
    size_t j = leaf_slot(keys[i], H->mask);
    while (H->slot[j]) j = (j + 1) & H->mask;
    H->slot[j] = (uint32_t)i + 1;
  }
  return MX_OK;
}

/* The place of key among the sorted leaves, or UINT32_MAX. */
static inline uint32_t leaf_table_find(const leaf_table *H, uint64_t key) {
  for (size_t j = leaf_slot(key, H->mask);; j = (j + 1) & H->mask) {
    const uint32_t i = H->slot[j];
    if (!i) return UINT32_MAX;
    if (H->keys[i - 1] == key) return i - 1;
  }
}

/* The face and edge neighbours: (dx, dy, dz) with one or two non-zero. */
static const int8_t near18[18][3] = {
    {-1, 0, 0},  {1, 0, 0},   {0, -1, 0}, {0, 1, 0},  {0, 0, -1},  {0, 0, 1},
    {-1, -1, 0}, {-1, 1, 0},  {1, -1, 0}, {1, 1, 0},  {-1, 0, -1}, {-1, 0, 1},
    {1, 0, -1},  {1, 0, 1},   {0, -1, -1}, {0, -1, 1}, {0, 1, -1},  {0, 1, 1}};

/* The leaf of level l-2 holding a face or edge neighbour cell of octant o
 * (level l), or MX_NONE; *dir its direction. Only the cells outside o's
 * own ancestor of level l-2 (split, so no leaf) are looked up: on each
 * axis a step of -1 leaves it from the ancestor's first quarter, +1 from
 * its last. */
static uint32_t coarse_neighbour(const mx_octree *T, const int dims[3], const leaf_table *H,
                                 const uint32_t *ids, size_t o, int *dir) {
  const int l = T->level[o];
  if (l < 2) return MX_NONE;
  uint32_t c[3];
  mx_morton_decode(T->key[o], c);
  const uint32_t s = mx_octant_size(l), up = ~(4 * s - 1);
  int leaves[3][3]; /* [axis][step + 1]: the step leaves the ancestor */
  for (int a = 0; a < 3; a++) {
    const uint32_t q = (c[a] >> (MX_MAX_LEVEL - l)) & 3;
    leaves[a][0] = q == 0 && c[a] > 0;
    leaves[a][1] = 0;
    leaves[a][2] = q == 3 && c[a] + s < ((uint32_t)dims[a] << MX_MAX_LEVEL);
  }
  for (int k = 0; k < 18; k++) {
    int out = 0;
    uint32_t n[3];
    for (int a = 0; a < 3; a++) {
      out |= leaves[a][near18[k][a] + 1];
      n[a] = (c[a] + (uint32_t)near18[k][a] * s) & up;
    }
    if (!out) continue;
    /* a step off the grid on another axis: no cell there */
    int off = 0;
    for (int a = 0; a < 3; a++)
      off |= (near18[k][a] < 0 && c[a] == 0) ||
             (near18[k][a] > 0 && c[a] + s >= ((uint32_t)dims[a] << MX_MAX_LEVEL));
    if (off) continue;
    const uint32_t i = leaf_table_find(H, mx_morton_encode(n[0], n[1], n[2]));
    if (i != UINT32_MAX && T->level[ids[i]] == l - 2) {
      *dir = k;
      return ids[i];
    }
  }
  return MX_NONE;
}

static int check_balance(const mx_octree *T, const int dims[3], const uint64_t *keys,
                         const uint32_t *ids, size_t nleaves, const char *where) {
  leaf_table H;
  MX_CHECK(leaf_table_build(&H, keys, nleaves));
  size_t first = SIZE_MAX;
  const size_t n = T->n;
#pragma omp parallel for schedule(static) reduction(min : first) if (n > MX_PAR_MIN / 16)
  for (size_t o = 0; o < n; o++) {
    int dir;
    if (coarse_neighbour(T, dims, &H, ids, o, &dir) != MX_NONE && o < first) first = o;
  }
  int st = MX_OK;
  if (first != SIZE_MAX) {
    int k = 0;
    const uint32_t leaf = coarse_neighbour(T, dims, &H, ids, first, &k);
    char msg[MSG];
    snprintf(msg, sizeof msg,
             "leaf %u (key %#llx, level %d) touches octant %zu (key %#llx, level %d) "
             "across (%d,%d,%d): two levels apart",
             leaf, (unsigned long long)T->key[leaf], T->level[leaf], first,
             (unsigned long long)T->key[first], T->level[first], near18[k][0], near18[k][1],
             near18[k][2]);
    st = broken(where, msg);
  }
  mx_free(H.slot);
  return st;
}

/* ---- (d) the edge infos ------------------------------------------------- */

typedef struct {
  const mx_octree *T;
  const mx_edges *E;
  int edge_levels, edge_lazy_top;
} edge_ctx;

/* Octant o may be in the edge infos / must be in them. */
static inline int edges_allowed(const edge_ctx *c, size_t o) {
  return c->T->level[o] <= c->edge_levels || (c->T->flags[o] & MX_OCT_EDGES);
}
static inline int edges_required(const edge_ctx *c, size_t o) {
  const int l = c->T->level[o];
  return (l <= c->edge_levels && l <= MX_MAX_LEVEL - 1) || (c->T->flags[o] & MX_OCT_EDGES);
}

/* 1 when entry i of the (level l, axis a) table breaks a rule of (d). */
static int entry_bad(const edge_ctx *c, int l, int a, size_t i, char *msg) {
  const mx_edge_table *E = &c->E->t[l][a];
  const mx_edge *e = &E->e[i];
  const uint64_t key = e->kw - 1;
  if (mx_edge_find(E, key) != i)
    BAD("edge %#llx (level %d, axis %d) at entry %zu is found at entry %lld",
        (unsigned long long)key, l, a, i,
        mx_edge_find(E, key) == SIZE_MAX ? -1LL : (long long)mx_edge_find(E, key));
  int any = 0;
  for (int s = 0; s < 4; s++) {
    const uint32_t o = e->slot[s];
    if (o == MX_NONE) continue;
    any = 1;
    if (o >= c->T->n)
      BAD("edge %#llx (level %d, axis %d) slot %d holds octant %u of %zu", (unsigned long long)key,
          l, a, s, o, c->T->n);
    if (c->T->level[o] != l || !edges_allowed(c, o))
      BAD("edge %#llx (level %d, axis %d) slot %d holds octant %u of level %d%s",
          (unsigned long long)key, l, a, s, o, c->T->level[o],
          c->T->level[o] == l ? ", which has no edge infos" : "");
    uint32_t anchor[3];
    mx_octant_anchor(c->T->key[o], l, anchor);
    if (mx_edge_key(anchor, a, 3 - s) != key)
      BAD("edge %#llx (level %d, axis %d) slot %d holds octant %u (key %#llx), which does not "
          "have it there", (unsigned long long)key, l, a, s, o,
          (unsigned long long)c->T->key[o]);
  }
  if (!any) BAD("edge %#llx (level %d, axis %d) has no octant", (unsigned long long)key, l, a);
  return 0;
}

/* 1 when octant o is flagged MX_OCT_EDGES beyond the levels the edge infos
 * are restored for, or (with lookups) missing from one of its 12 edges. */
static int registration_bad(const edge_ctx *c, size_t o, int lookups, char *msg) {
  const mx_octree *T = c->T;
  const int l = T->level[o];
  if ((T->flags[o] & MX_OCT_EDGES) && l > c->edge_levels && l > c->edge_lazy_top)
    BAD("octant %zu of level %d is flagged with edge infos, deeper than the deepest such "
        "level %d", o, l, c->edge_lazy_top);
  if (!lookups || !edges_required(c, o)) return 0;
  uint32_t anchor[3];
  mx_octant_anchor(T->key[o], l, anchor);
  for (int a = 0; a < 3; a++)
    for (int j = 0; j < 4; j++) {
      const mx_edge_table *E = &c->E->t[l][a];
      const uint64_t ek = mx_edge_key(anchor, a, j);
      const size_t i = mx_edge_find(E, ek);
      if (i == SIZE_MAX)
        BAD("octant %zu (key %#llx, level %d): its edge %d of axis %d (%#llx) has no info", o,
            (unsigned long long)T->key[o], l, j, a, (unsigned long long)ek);
      const uint32_t in = E->e[i].slot[mx_edge_slot(j)];
      if (in == MX_NONE)
        BAD("octant %zu (key %#llx, level %d): its edge %d of axis %d (%#llx) has its slot %d "
            "empty", o, (unsigned long long)T->key[o], l, j, a, (unsigned long long)ek,
            mx_edge_slot(j));
      if (in != o)
        BAD("octant %zu (key %#llx, level %d): its edge %d of axis %d (%#llx) holds octant %u "
            "in its slot %d", o, (unsigned long long)T->key[o], l, j, a, (unsigned long long)ek,
            in, mx_edge_slot(j));
    }
  return 0;
}

/* Every slot checked (entry_bad) and no key twice in a table, an octant
 * fills at most 12 slots, one per edge of its own; so the octants that
 * must be registered are, all 12 times each, exactly when the slots
 * holding them number 12 per such octant: counted, no lookup. Only when the
 * count is short are the octants looked up, for the message. */
static int check_edges(const edge_ctx *c, const char *where) {
  char msg[MSG];
  size_t filled = 0; /* slots holding an octant that must be registered */
  for (int l = 0; l <= MX_MAX_LEVEL; l++)
    for (int a = 0; a < 3; a++) {
      const mx_edge_table *E = &c->E->t[l][a];
      size_t used = 0, first = SIZE_MAX, req = 0;
      const size_t cap = E->cap;
#pragma omp parallel for schedule(static) reduction(+ : used, req) reduction(min : first) \
    if (cap > MX_PAR_MIN)
      for (size_t i = 0; i < cap; i++) {
        if (!E->e[i].kw) continue;
        used++;
        if (entry_bad(c, l, a, i, NULL)) {
          if (i < first) first = i;
          continue;
        }
        for (int q = 0; q < 4; q++)
          req += E->e[i].slot[q] != MX_NONE && edges_required(c, E->e[i].slot[q]);
      }
      if (first != SIZE_MAX) {
        entry_bad(c, l, a, first, msg);
        return broken(where, msg);
      }
      if (used != E->count) {
        snprintf(msg, sizeof msg, "the edge table of level %d, axis %d counts %zu edges but "
                                  "holds %zu", l, a, E->count, used);
        return broken(where, msg);
      }
      filled += req;
    }
  size_t first = SIZE_MAX, required = 0;
  const size_t n = c->T->n;
#pragma omp parallel for schedule(static) reduction(min : first) reduction(+ : required) \
    if (n > MX_PAR_MIN)
  for (size_t o = 0; o < n; o++) {
    if (registration_bad(c, o, 0, NULL) && o < first) first = o;
    required += edges_required(c, o);
  }
  if (first == SIZE_MAX && filled != 12 * required)
    for (size_t o = 0; o < n && first == SIZE_MAX; o++)
      if (registration_bad(c, o, 1, NULL)) first = o;
  if (first != SIZE_MAX) {
    registration_bad(c, first, 1, msg);
    return broken(where, msg);
  }
  if (filled != 12 * required) { /* cannot be, given the checks above */
    snprintf(msg, sizeof msg, "%zu octants must be in the edge infos, which hold them %zu "
                              "times (12 each)", required, filled);
    return broken(where, msg);
  }
  return MX_OK;
}

/* ------------------------------------------------------------------------ */

int mx_tree_valid(const mx_tree *t, int promise, const char *where) {
  __atomic_fetch_add(&runs, 1, __ATOMIC_RELAXED);
  const mx_octree *T = &t->oct;
  const int *dims = t->grid.dims;
  MX_CHECK(check_forest(T, dims, where));
  uint64_t *keys = NULL;
  uint32_t *ids = NULL;
  size_t nleaves = 0;
  MX_CHECK(sorted_leaves(T, &keys, &ids, &nleaves, where));
  int st = MX_OK;
  if (promise & MX_TREE_BALANCED) st = check_balance(T, dims, keys, ids, nleaves, where);
  mx_free(keys);
  mx_free(ids);
  if (!st && t->use_edges && !t->edges_released) {
    const edge_ctx c = {T, &t->edges, t->edge_levels, t->edge_lazy_top};
    st = check_edges(&c, where);
  }
  return st;
}
