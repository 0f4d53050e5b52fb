/* Lattice keys -> place in a sorted array: see soa/key_index.h. */
#include "soa/key_index.h"

#include "base/common.h"

int mx_key_index_build(mx_key_index *H, const uint64_t *keys, size_t n, int shift) {
  size_t cap = 64;
  while (10 * n > 7 * cap) cap *= 2;
  H->slot = mx_alloc(cap * sizeof *H->slot);
  H->keys = keys;
  H->cap = cap;
  H->shift = shift;
  if (!H->slot) return MX_ENOMEM;
  /* emptied by all the threads: the first touch of fresh pages costs most */
#pragma omp parallel for schedule(static) if (cap > 65536)
  for (size_t i = 0; i < cap; i++) H->slot[i] = UINT32_MAX;
  /* distinct keys: each claims a free slot with one compare-and-swap */
#pragma omp parallel for schedule(static) if (n > 65536)
  for (size_t k = 0; k < n; k++) {
    size_t i = mx_key_slot(keys[k], cap, shift);
    for (;;) {
      uint32_t expected = UINT32_MAX;
      if (__atomic_compare_exchange_n(&H->slot[i], &expected, (uint32_t)k, 0, __ATOMIC_RELAXED,
                                      __ATOMIC_RELAXED))
        break;
      i = i + 1 == cap ? 0 : i + 1;
    }
  }
  return MX_OK;
}

void mx_key_index_free(mx_key_index *H) {
  mx_free(H->slot);
  H->slot = NULL;
  H->cap = 0;
}
