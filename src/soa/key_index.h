/* Lattice keys -> their place in a sorted key array, by hashing: a lookup
 * costs one cache miss at most (lookups of successive points overlap their
 * misses), where a search in the sorted array costs a chain of dependent
 * ones. The restart file's writer looks up the ends of every edge and the
 * corners of every leaf this way.
 *
 * mx_block_slot places keys by spatial blocks: the points of one block of
 * 4x4x4 lattice spacings land in one window (twice its size) of the table,
 * so points taken in Morton order touch a few windows at a time, and the
 * blocks themselves are spread by a mixing hash (the transition stage's
 * node hash). The key index mixes each key instead (mx_key_slot). */
#ifndef MX_KEY_INDEX_H
#define MX_KEY_INDEX_H

#include <stddef.h>
#include <stdint.h>

/* Home slot of a key in a table of cap slots; shift: the low key bits that
 * are zero for every key stored (3 per level below the finest lattice). */
static inline size_t mx_block_slot(uint64_t key, size_t cap, int shift) {
  const uint64_t k = key >> shift;
  uint64_t h = (k >> 6) * 0x9E3779B97F4A7C15ULL;
  h ^= h >> 31;
  const size_t base = (size_t)(((unsigned __int128)h * cap) >> 64);
  const size_t s = base + 2 * (size_t)(k & 63);
  return s >= cap ? s - cap : s;
}

/* Slot of a key in a table of cap slots: the key's lattice coordinates
 * mixed (a block placement, mx_block_slot, gave 13 extra probes per
 * insertion at load 0.58 on the cortex's restart nodes, its windows of
 * full blocks overlapping; a mixing hash about one, and the restart file
 * 0.5 s faster at -s 9). */
static inline size_t mx_key_slot(uint64_t key, size_t cap, int shift) {
  uint64_t h = (key >> shift) * 0x9E3779B97F4A7C15ULL;
  h ^= h >> 29;
  return (size_t)(((unsigned __int128)h * cap) >> 64);
}

typedef struct {
  uint32_t *slot;        /* a place in keys, or UINT32_MAX: empty */
  const uint64_t *keys;  /* the caller's, kept while the index is used */
  size_t cap;
  int shift;
} mx_key_index;

/* Index of the n (< 2^32) distinct keys, any order; a key's id is its
 * place in the array, which must outlive the index. 4 bytes a slot, at a
 * load of at most 0.7: the table is a fraction of the keys' size. In
 * parallel. MX_OK, or MX_ENOMEM (nothing to free then). */
int mx_key_index_build(mx_key_index *H, const uint64_t *keys, size_t n, int shift);
void mx_key_index_free(mx_key_index *H);

/* The id of key, or UINT32_MAX when it is not in the index. */
static inline uint32_t mx_key_index_find(const mx_key_index *H, uint64_t key) {
  size_t i = mx_key_slot(key, H->cap, H->shift);
  for (;;) {
    const uint32_t id = H->slot[i];
    if (id == UINT32_MAX || H->keys[id] == key) return id;
    i = i + 1 == H->cap ? 0 : i + 1;
  }
}

static inline void mx_key_index_prefetch(const mx_key_index *H, uint64_t key) {
  __builtin_prefetch(&H->slot[mx_key_slot(key, H->cap, H->shift)], 0);
}

#endif
