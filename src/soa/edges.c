#include "soa/edges.h"

#include "base/common.h"

#include <stdlib.h>
#include <string.h>

/* Edges are hashed by spatial blocks: the 4x4x4 lattice positions of a block
 * share one window of the table, so octants taken in Morton order touch few
 * windows at a time; the blocks are spread over the table by a mixing hash. */
static inline size_t edge_hash(uint64_t key, size_t cap) {
  uint64_t h = (key >> 6) * 0x9E3779B97F4A7C15ULL;
  h ^= h >> 29;
  h *= 0xBF58476D1CE4E5B9ULL;
  h ^= h >> 32;
  /* a 4x4x4 block spread over twice its size: short probe runs */
  const size_t s = (size_t)(((unsigned __int128)h * cap) >> 64) + 2 * (size_t)(key & 63);
  return s >= cap ? s - cap : s;
}

void mx_edges_free(mx_edges *E) {
  for (int l = 0; l <= MX_MAX_LEVEL; l++)
    for (int a = 0; a < 3; a++) mx_free(E->t[l][a].e);
  memset(E, 0, sizeof *E);
}

/* Rehash one entry into a fresh table, many threads at once. */
static void put_concurrent(mx_edge_table *T, const mx_edge *src) {
  size_t i = edge_hash(src->kw - 1, T->cap);
  for (;;) {
    uint64_t expected = 0;
    if (__atomic_compare_exchange_n(&T->e[i].kw, &expected, src->kw, 0,
                                    __ATOMIC_ACQ_REL, __ATOMIC_RELAXED)) {
      memcpy(T->e[i].slot, src->slot, sizeof src->slot);
      return;
    }
    i = (i + 1 == T->cap) ? 0 : i + 1;
  }
}

static int table_grow(mx_edge_table *T, size_t need) {
  if ((double)need <= 0.75 * (double)T->cap) return MX_OK;
  size_t cap = (size_t)((double)need / 0.6) + 1024;
  if (cap < T->cap + T->cap / 2) cap = T->cap + T->cap / 2;
  mx_edge *e = mx_alloc(cap * sizeof *e);
  if (!e) return MX_ENOMEM;
#pragma omp parallel for schedule(static) if (cap > MX_PAR_MIN)
  for (size_t i = 0; i < cap; i++) {
    e[i].kw = 0;
    e[i].slot[0] = e[i].slot[1] = e[i].slot[2] = e[i].slot[3] = UINT32_MAX;
  }
  mx_edge_table nt = {e, cap, T->count};
#pragma omp parallel for schedule(static) if (T->cap > MX_PAR_MIN)
  for (size_t i = 0; i < T->cap; i++)
    if (T->e[i].kw) put_concurrent(&nt, &T->e[i]);
  mx_free(T->e);
  *T = nt;
  return MX_OK;
}

int mx_edges_reserve(mx_edges *E, int level, size_t extra) {
  for (int a = 0; a < 3; a++)
    MX_CHECK(table_grow(&E->t[level][a], E->t[level][a].count + extra));
  return MX_OK;
}

size_t mx_edge_find(const mx_edge_table *T, uint64_t key) {
  if (!T->cap) return SIZE_MAX;
  const uint64_t want = key + 1;
  size_t i = edge_hash(key, T->cap);
  for (;;) {
    uint64_t kw = __atomic_load_n(&T->e[i].kw, __ATOMIC_ACQUIRE);
    if (!kw) return SIZE_MAX;
    if (kw == want) return i;
    i = (i + 1 == T->cap) ? 0 : i + 1;
  }
}

void mx_edge_prefetch(const mx_edge_table *T, uint64_t key) {
  if (T->cap) __builtin_prefetch(&T->e[edge_hash(key, T->cap)], 0);
}

void mx_edges_prefetch_octant(const mx_edges *E, uint64_t key, int level) {
  uint32_t anchor[3];
  mx_octant_anchor(key, level, anchor);
  for (int a = 0; a < 3; a++)
    for (int j = 0; j < 4; j++) mx_edge_prefetch(&E->t[level][a], mx_edge_key(anchor, a, j));
}

/* Find or create, from the home slot i of key; *created is set to 1 when
 * this call claimed the entry. */
static size_t edge_insert_at(mx_edge_table *T, uint64_t key, size_t i, int *created) {
  const uint64_t want = key + 1;
  for (;;) {
    uint64_t kw = __atomic_load_n(&T->e[i].kw, __ATOMIC_ACQUIRE);
    if (!kw) {
      uint64_t expected = 0;
      if (__atomic_compare_exchange_n(&T->e[i].kw, &expected, want, 0,
                                      __ATOMIC_ACQ_REL, __ATOMIC_ACQUIRE)) {
        *created = 1;
        return i;
      }
      kw = expected;
    }
    if (kw == want) {
      *created = 0;
      return i;
    }
    i = (i + 1 == T->cap) ? 0 : i + 1;
  }
}

void mx_edges_register(mx_edges *E, uint32_t o, uint64_t key, int level,
                       size_t created[3]) {
  uint32_t anchor[3];
  mx_octant_anchor(key, level, anchor);
  /* the 12 home slots asked for at once, then found or created in order */
  uint64_t k[3][4];
  size_t home[3][4];
  for (int a = 0; a < 3; a++)
    for (int j = 0; j < 4; j++) {
      k[a][j] = mx_edge_key(anchor, a, j);
      home[a][j] = edge_hash(k[a][j], E->t[level][a].cap);
      __builtin_prefetch(&E->t[level][a].e[home[a][j]], 1);
    }
  for (int a = 0; a < 3; a++) {
    mx_edge_table *T = &E->t[level][a];
    for (int j = 0; j < 4; j++) {
      int fresh;
      const size_t i = edge_insert_at(T, k[a][j], home[a][j], &fresh);
      created[a] += (size_t)fresh;
      __atomic_store_n(&T->e[i].slot[mx_edge_slot(j)], o, __ATOMIC_RELAXED);
    }
  }
}

void mx_edges_add_count(mx_edges *E, int level, const size_t created[3]) {
  for (int a = 0; a < 3; a++) E->t[level][a].count += created[a];
}

size_t mx_edges_total(const mx_edges *E) {
  size_t n = 0;
  for (int l = 0; l <= MX_MAX_LEVEL; l++)
    for (int a = 0; a < 3; a++) n += E->t[l][a].count;
  return n;
}

size_t mx_edges_bytes(const mx_edges *E) {
  size_t n = 0;
  for (int l = 0; l <= MX_MAX_LEVEL; l++)
    for (int a = 0; a < 3; a++) n += E->t[l][a].cap * sizeof(mx_edge);
  return n;
}

/* The edges with a kept child of a split octant: their keys, the children
 * in their slots, and their home slots, which are asked for at once (each
 * is a cache miss in a large table: 54 of them overlap instead of
 * following each other; nothing is written). */
typedef struct {
  uint64_t key[54];
  size_t home[54];
  uint32_t who[54][4];
  int ne[3]; /* edges per axis, in key[] axis after axis */
  int level; /* of the split octant */
} children_edges;

static void children_prepare(const mx_edges *E, uint32_t child0, uint8_t kept, uint64_t key,
                             int level, children_edges *C) {
  /* Anchor of the parent on the children's lattice. */
  uint32_t A[3];
  mx_octant_anchor(key, level, A);
  for (int a = 0; a < 3; a++) A[a] <<= 1;
  uint32_t index[8];
  for (int c = 0, k = 0; c < 8; c++)
    index[c] = ((kept >> c) & 1) ? child0 + (uint32_t)k++ : UINT32_MAX;
  int n = 0;
  for (int a = 0; a < 3; a++) {
    const int b = (a + 1) % 3, d = (a + 2) % 3;
    const mx_edge_table *T = &E->t[level + 1][a];
    C->ne[a] = 0;
    for (int s = 0; s < 2; s++)
      for (int jb = 0; jb < 3; jb++)
        for (int jd = 0; jd < 3; jd++) {
          uint32_t *who = C->who[n];
          who[0] = who[1] = who[2] = who[3] = UINT32_MAX;
          int any = 0;
          for (int cb = jb - 1; cb <= jb; cb++)
            for (int cd = jd - 1; cd <= jd; cd++) {
              if (cb < 0 || cb > 1 || cd < 0 || cd > 1) continue;
              const int child = (s << a) | (cb << b) | (cd << d);
              if (index[child] == UINT32_MAX) continue;
              who[(cb == jb ? 1 : 0) | (cd == jd ? 2 : 0)] = index[child];
              any = 1;
            }
          if (!any) continue;
          uint32_t p[3] = {A[0], A[1], A[2]};
          p[a] += (uint32_t)s;
          p[b] += (uint32_t)jb;
          p[d] += (uint32_t)jd;
          C->key[n] = mx_morton_encode(p[0], p[1], p[2]);
          C->home[n] = edge_hash(C->key[n], T->cap);
          __builtin_prefetch(&T->e[C->home[n]], 1);
          n++;
          C->ne[a]++;
        }
  }
  C->level = level;
}

/* Those edges found or created, in order, their slots written. */
static void children_commit(mx_edges *E, const children_edges *C, size_t created[3]) {
  for (int a = 0, k = 0; a < 3; a++) {
    mx_edge_table *T = &E->t[C->level + 1][a];
    for (int q = 0; q < C->ne[a]; q++, k++) {
      int fresh;
      const size_t i = edge_insert_at(T, C->key[k], C->home[k], &fresh);
      created[a] += (size_t)fresh;
      for (int w = 0; w < 4; w++)
        if (C->who[k][w] != UINT32_MAX)
          __atomic_store_n(&T->e[i].slot[w], C->who[k][w], __ATOMIC_RELAXED);
    }
  }
}

void mx_edges_register_children(mx_edges *E, uint32_t child0, uint8_t kept,
                                uint64_t key, int level, size_t created[3]) {
  children_edges C;
  children_prepare(E, child0, kept, key, level, &C);
  children_commit(E, &C, created);
}
