/* base/scan: the searches in sorted keys, against a plain linear scan; the
 * sort of keys mostly in order against the radix sort (the same keys and
 * values: both stable). */
#include "base/scan.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static int failures;
#define CHECK(c)                                                      \
  do {                                                                \
    if (!(c)) {                                                       \
      fprintf(stderr, "%s:%d: check failed: %s\n", __FILE__, __LINE__, #c); \
      failures++;                                                     \
    }                                                                 \
  } while (0)

static uint64_t rng = 88172645463325252ull;
static uint64_t next(void) {
  rng ^= rng << 13;
  rng ^= rng >> 7;
  rng ^= rng << 17;
  return rng;
}

/* the first place with v[place] >= key (n when none) */
static size_t lower(const uint64_t *v, size_t n, uint64_t key) {
  size_t i = 0;
  while (i < n && v[i] < key) i++;
  return i;
}

int main(void) {
  enum { N = 3000 };
  static uint64_t v[N];
  for (size_t n = 0; n <= N; n = n < 10 ? n + 1 : n * 3) {
    /* sorted, distinct, with gaps of varying size (clusters as in Morton) */
    uint64_t x = 5;
    for (size_t i = 0; i < n; i++) {
      x += 1 + (next() % 4 == 0 ? next() % 1000 : next() % 3);
      v[i] = x;
    }
    size_t hint = 0;
    for (int q = 0; q < 4000; q++) {
      /* keys present, absent, below and above all, near and far */
      uint64_t key = n && q % 3 ? v[next() % n] + (uint64_t)(q % 5 == 0) : next() % (x + 10);
      if (q % 7 == 0) hint = next(); /* any start value */
      const size_t at = lower(v, n, key);
      const uint32_t want = at < n && v[at] == key ? (uint32_t)at : UINT32_MAX;
      CHECK(mx_find_u64(v, n, key) == want);
      CHECK(mx_find_u64_near(v, n, key, &hint) == want);
      CHECK(hint == at);
    }
  }
  /* mostly in order: runs of equal keys rising, a share of them (none, a
   * few, a tenth, half: the whole radix sort) anywhere below; the values
   * the positions, so that a tie broken the other way shows */
  {
    enum { M = 200000 };
    uint64_t *a = malloc(M * sizeof *a), *b = malloc(M * sizeof *b);
    uint32_t *va = malloc(M * sizeof *va), *vb = malloc(M * sizeof *vb);
    const unsigned share[4] = {0, 1000, 10, 2};
    for (int k = 0; k < 4 && a && b && va && vb; k++)
      for (size_t n = 1; n <= M; n *= 7) {
        uint64_t x = 0;
        size_t out = 0;
        for (size_t i = 0; i < n; i++) {
          x += next() % 3 == 0;
          const int below = share[k] && next() % share[k] == 0 && x > 0;
          a[i] = below ? next() % x : x;
          out += below;
          va[i] = (uint32_t)i;
        }
        memcpy(b, a, n * sizeof *a);
        memcpy(vb, va, n * sizeof *va);
        CHECK(mx_sort_u64_mostly_sorted(a, va, n) == 0);
        CHECK(mx_sort_u64(b, vb, n) == 0);
        CHECK(memcmp(a, b, n * sizeof *a) == 0 && memcmp(va, vb, n * sizeof *va) == 0);
        if (n == 117649) printf("mostly sorted, 1 in %u below: %zu of %zu\n", share[k], out, n);
      }
    free(a);
    free(b);
    free(va);
    free(vb);
  }
  printf("%s\n", failures ? "FAIL" : "ok");
  return failures != 0;
}
