#include "base/scan.h"

#include "base/common.h"

#include <omp.h>
#include <stdlib.h>
#include <string.h>

/* Entries of 64 or 32 bits (w32), summed in 64 bits: one body for both
 * widths (the branch on w32 is the same for every entry). */
static inline uint64_t get(const void *a, size_t i, int w32) {
  return w32 ? ((const uint32_t *)a)[i] : ((const uint64_t *)a)[i];
}
static inline void put(void *a, size_t i, int w32, uint64_t v) {
  if (w32) ((uint32_t *)a)[i] = (uint32_t)v;
  else ((uint64_t *)a)[i] = v;
}

static uint64_t scan(void *a, size_t n, int w32) {
  if (n < 65536) {
    uint64_t s = 0;
    for (size_t i = 0; i < n; i++) {
      const uint64_t v = get(a, i, w32);
      put(a, i, w32, s);
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
    for (size_t i = lo; i < hi; i++) s += get(a, i, w32);
    part[t + 1] = s;
#pragma omp barrier
#pragma omp single
    {
      for (int k = 0; k < T; k++) part[k + 1] += part[k];
      used = T;
    }
    s = part[t];
    for (size_t i = lo; i < hi; i++) {
      const uint64_t v = get(a, i, w32);
      put(a, i, w32, s);
      s += v;
    }
  }
  return part[used];
}

uint64_t mx_scan_u64(uint64_t *a, size_t n) { return scan(a, n, 0); }

uint64_t mx_scan_u32(uint32_t *a, size_t n) { return scan(a, n, 1); }

/* LSD radix sort, 8 bits a pass, skipping the bytes where all keys agree.
 * Each pass: per-thread histograms of contiguous slices, one prefix over
 * (digit, thread), then each thread scatters its slice: stable, so the
 * result does not depend on the thread count. */
/* 11-bit digits: a Morton key of some 36 varying bits (an octree to level
 * 9) takes 4 passes instead of 5, 25-35% faster on 24M keys than 8-bit
 * digits (measured); the 16 KB histogram of a thread stays in L1/L2. */
enum { RADIX_BITS = 11, RADIX = 1 << RADIX_BITS };

int mx_sort_u64(uint64_t *keys, uint32_t *vals, size_t n) {
  if (n < 2) return MX_OK;
  uint64_t all_or = 0, all_and = ~0ULL;
#pragma omp parallel for reduction(| : all_or) reduction(& : all_and) if (n >= 65536)
  for (size_t i = 0; i < n; i++) {
    all_or |= keys[i];
    all_and &= keys[i];
  }
  const uint64_t varying = all_or ^ all_and;
  uint64_t *k2 = mx_alloc(n * sizeof *k2);
  uint32_t *v2 = vals ? mx_alloc(n * sizeof *v2) : NULL;
  int nt = n < 65536 ? 1 : omp_get_max_threads();
  if (nt > 64) nt = 64;
  size_t(*hist)[RADIX] = mx_alloc((size_t)nt * sizeof *hist);
  if (!k2 || (vals && !v2) || !hist) {
    mx_free(k2);
    mx_free(v2);
    mx_free(hist);
    return MX_ENOMEM;
  }
  uint64_t *src = keys, *dst = k2;
  uint32_t *vsrc = vals, *vdst = v2;
  /* digits of RADIX_BITS bits from the lowest bit that varies (keys on a
   * coarse lattice have many low zero bits) */
  const int first = varying ? __builtin_ctzll(varying) : 64;
  for (int shift = first; shift < 64; shift += RADIX_BITS) {
    if (!((varying >> shift) & (RADIX - 1))) continue;
#pragma omp parallel num_threads(nt)
    {
      const int t = omp_get_thread_num(), T = omp_get_num_threads();
      const size_t lo = n * (size_t)t / (size_t)T, hi = n * (size_t)(t + 1) / (size_t)T;
      size_t *h = hist[t];
      memset(h, 0, RADIX * sizeof *h);
      for (size_t i = lo; i < hi; i++) h[(src[i] >> shift) & (RADIX - 1)]++;
#pragma omp barrier
#pragma omp single
      {
        size_t s = 0;
        for (int d = 0; d < RADIX; d++)
          for (int u = 0; u < T; u++) {
            const size_t c = hist[u][d];
            hist[u][d] = s;
            s += c;
          }
      }
      for (size_t i = lo; i < hi; i++) {
        const size_t d = h[(src[i] >> shift) & (RADIX - 1)]++;
        dst[d] = src[i];
        if (vals) vdst[d] = vsrc[i];
      }
    }
    uint64_t *tk = src;
    src = dst;
    dst = tk;
    uint32_t *tv = vsrc;
    vsrc = vdst;
    vdst = tv;
  }
  if (src != keys) {
    memcpy(keys, src, n * sizeof *keys);
    if (vals) memcpy(vals, vsrc, n * sizeof *vals);
  }
  mx_free(k2);
  mx_free(v2);
  mx_free(hist);
  return MX_OK;
}

int mx_sort_u64_mostly_sorted(uint64_t *keys, uint32_t *vals, size_t n) {
  if (n < 2) return MX_OK;
  /* the keys below the running maximum: counted, then taken out with
   * their positions (a serial pass each: the order is the point) */
  size_t nx = 0;
  uint64_t top = keys[0];
  for (size_t i = 1; i < n; i++) {
    if (keys[i] < top) nx++;
    else top = keys[i];
  }
  if (nx == 0) return MX_OK;
  if (nx > n / 4) return mx_sort_u64(keys, vals, n);
  uint64_t *xk = mx_alloc((nx + 1) * sizeof *xk);
  uint32_t *xp = mx_alloc((nx + 1) * sizeof *xp); /* their positions */
  uint64_t *mk = mx_alloc((n + 1) * sizeof *mk);
  uint32_t *mv = mx_alloc((n + 1) * sizeof *mv);
  if (!xk || !xp || !mk || !mv) {
    mx_free(xk); mx_free(xp); mx_free(mk); mx_free(mv);
    return MX_ENOMEM;
  }
  /* the rest (in order, with the positions) compacted into mk, mv */
  size_t nr = 0, j = 0;
  top = keys[0];
  for (size_t i = 0; i < n; i++) {
    if (i > 0 && keys[i] < top) {
      xk[j] = keys[i];
      xp[j++] = (uint32_t)i;
    } else {
      top = keys[i];
      mk[nr] = keys[i];
      mv[nr++] = (uint32_t)i;
    }
  }
  int st = mx_sort_u64(xk, xp, nx); /* stable: equal keys by position */
  if (st) {
    mx_free(xk); mx_free(xp); mx_free(mk); mx_free(mv);
    return st;
  }
  /* merged by (key, position): the order a stable sort gives; the values
   * gathered by position, from a copy (they are overwritten) */
  uint32_t *v0 = mx_alloc((n + 1) * sizeof *v0);
  if (!v0) {
    mx_free(xk); mx_free(xp); mx_free(mk); mx_free(mv);
    return MX_ENOMEM;
  }
  memcpy(v0, vals, n * sizeof *vals);
  size_t a = 0, b = 0;
  for (size_t o = 0; o < n; o++) {
    const int from_x =
        b < nx && (a == nr || xk[b] < mk[a] || (xk[b] == mk[a] && xp[b] < mv[a]));
    if (from_x) {
      keys[o] = xk[b];
      vals[o] = v0[xp[b++]];
    } else {
      keys[o] = mk[a];
      vals[o] = v0[mv[a++]];
    }
  }
  mx_free(xk); mx_free(xp); mx_free(mk); mx_free(mv); mx_free(v0);
  return MX_OK;
}

size_t mx_sort_unique_u64(uint64_t *k, size_t n, int *st) {
  *st = mx_sort_u64(k, NULL, n);
  if (*st || n == 0) return 0;
  size_t w = 1;
  for (size_t i = 1; i < n; i++)
    if (k[i] != k[w - 1]) k[w++] = k[i];
  return w;
}

uint32_t mx_find_u64(const uint64_t *v, size_t n, uint64_t key) {
  size_t lo = 0, hi = n;
  while (lo < hi) {
    const size_t mid = lo + (hi - lo) / 2;
    if (v[mid] < key) lo = mid + 1;
    else hi = mid;
  }
  return lo < n && v[lo] == key ? (uint32_t)lo : UINT32_MAX;
}

uint32_t mx_find_u64_near(const uint64_t *v, size_t n, uint64_t key, size_t *hint) {
  size_t lo, hi; /* the first place with v[place] >= key lies in [lo, hi] */
  size_t h = *hint < n ? *hint : n;
  if (h < n && v[h] < key) {
    size_t step = 1;
    lo = h + 1;
    hi = lo;
    while (hi < n && v[hi] < key) {
      lo = hi + 1;
      hi = n - hi > step ? hi + step : n;
      step *= 2;
    }
  } else {
    size_t step = 1;
    hi = h;
    lo = h;
    while (lo > 0 && v[lo - 1] >= key) {
      hi = lo - 1;
      lo = lo - 1 > step ? lo - 1 - step : 0;
      step *= 2;
    }
  }
  /* the first place in [lo, hi] without a branch per step: the place is
   * in [b, b + len] all along, and b[len] may be v[n], never read */
  const uint64_t *b = v + lo;
  for (size_t len = hi - lo; len > 1;) {
    const size_t half = len / 2;
    b = b[half] < key ? b + half : b;
    len -= half;
  }
  size_t at = (size_t)(b - v);
  if (hi > lo && *b < key) at++;
  *hint = at;
  return at < n && v[at] == key ? (uint32_t)at : UINT32_MAX;
}
