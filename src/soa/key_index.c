/* Lattice keys -> place in a sorted array: see soa/key_index.h. */
#include "soa/key_index.h"

#include "common.h"

int mx_key_index_build(mx_key_index *H, const uint64_t *keys, size_t n, int shift) {
  /* load at most 1/2: short probe runs, and a lookup of an absent key (an
   * edge without a mid-node) meets an empty slot soon */
  size_t cap = 64;
  while (cap < 2 * n) cap *= 2;
  H->e = mx_alloc(cap * sizeof *H->e);
  H->cap = cap;
  H->shift = shift;
  if (!H->e) return MX_ENOMEM;
  /* zeroed by all the threads: the first touch of fresh pages costs most */
#pragma omp parallel for schedule(static) if (cap > 65536)
  for (size_t i = 0; i < cap; i++) H->e[i].kw = 0;
  /* distinct keys: each claims a free slot with one compare-and-swap */
#pragma omp parallel for schedule(static) if (n > 65536)
  for (size_t k = 0; k < n; k++) {
    size_t i = mx_block_slot(keys[k], cap, shift);
    for (;;) {
      uint64_t expected = 0;
      if (__atomic_compare_exchange_n(&H->e[i].kw, &expected, keys[k] + 1, 0, __ATOMIC_RELAXED,
                                      __ATOMIC_RELAXED)) {
        H->e[i].id = k;
        break;
      }
      i = i + 1 == cap ? 0 : i + 1;
    }
  }
  return MX_OK;
}

void mx_key_index_free(mx_key_index *H) {
  mx_free(H->e);
  H->e = NULL;
  H->cap = 0;
}
