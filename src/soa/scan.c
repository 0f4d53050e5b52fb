#include "soa/scan.h"

#include "common.h"

#include <omp.h>
#include <stdlib.h>
#include <string.h>

uint64_t mx_scan_u64(uint64_t *a, size_t n) {
  if (n < 65536) {
    uint64_t s = 0;
    for (size_t i = 0; i < n; i++) {
      uint64_t v = a[i];
      a[i] = s;
      s += v;
    }
    return s;
  }
  int nt = omp_get_max_threads();
  uint64_t part[257] = {0};
  int used = 1;
  if (nt > 256) nt = 256;
#pragma omp parallel num_threads(nt)
  {
    int t = omp_get_thread_num(), T = omp_get_num_threads();
    size_t lo = n * (size_t)t / (size_t)T, hi = n * (size_t)(t + 1) / (size_t)T;
    uint64_t s = 0;
    for (size_t i = lo; i < hi; i++) s += a[i];
    part[t + 1] = s;
#pragma omp barrier
#pragma omp single
    {
      for (int k = 0; k < T; k++) part[k + 1] += part[k];
      used = T;
    }
    s = part[t];
    for (size_t i = lo; i < hi; i++) {
      uint64_t v = a[i];
      a[i] = s;
      s += v;
    }
  }
  return part[used];
}

int mx_sort_u64(uint64_t *keys, uint32_t *vals, size_t n) {
  if (n < 2) return MX_OK;
  uint64_t all_or = 0, all_and = ~0ULL;
  for (size_t i = 0; i < n; i++) {
    all_or |= keys[i];
    all_and &= keys[i];
  }
  const uint64_t varying = all_or ^ all_and;
  uint64_t *k2 = mx_alloc(n * sizeof *k2);
  uint32_t *v2 = vals ? mx_alloc(n * sizeof *v2) : NULL;
  if (!k2 || (vals && !v2)) {
    mx_free(k2);
    mx_free(v2);
    return MX_EINPUT;
  }
  for (int shift = 0; shift < 64; shift += 8) {
    if (!((varying >> shift) & 0xff)) continue;
    size_t count[257] = {0};
    for (size_t i = 0; i < n; i++) count[((keys[i] >> shift) & 0xff) + 1]++;
    for (int b = 0; b < 256; b++) count[b + 1] += count[b];
    for (size_t i = 0; i < n; i++) {
      size_t d = count[(keys[i] >> shift) & 0xff]++;
      k2[d] = keys[i];
      if (vals) v2[d] = vals[i];
    }
    memcpy(keys, k2, n * sizeof *keys);
    if (vals) memcpy(vals, v2, n * sizeof *vals);
  }
  mx_free(k2);
  mx_free(v2);
  return MX_OK;
}
