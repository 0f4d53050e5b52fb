/* Parallel exclusive prefix sums and a radix sort, the two primitives every
 * count-then-fill pass uses. */
#ifndef MX_SCAN_H
#define MX_SCAN_H

#include <stddef.h>
#include <stdint.h>

/* a[i] <- a[0] + ... + a[i-1]; returns the total. Parallel (OpenMP). */
uint64_t mx_scan_u64(uint64_t *a, size_t n);
/* The same on 32-bit counts whose total fits 32 bits (returned in 64). */
uint64_t mx_scan_u32(uint32_t *a, size_t n);

/* Sorts keys ascending (LSD radix, 11-bit digits, on the bits that vary); when vals is not
 * NULL it is permuted along. tmp arrays are allocated inside. MX_OK or
 * MX_EINPUT (out of memory). */
int mx_sort_u64(uint64_t *keys, uint32_t *vals, size_t n);
/* The same result (stable: equal keys keep their order) for keys mostly in
 * order already (made along the Morton order): the keys below the running
 * maximum are taken out, radix-sorted alone and merged back; the whole
 * radix sort when they are more than a quarter. vals may not be NULL. */
int mx_sort_u64_mostly_sorted(uint64_t *keys, uint32_t *vals, size_t n);

/* The first index of the sorted keys k[0 .. n) whose key is not below key
 * (n: none). */
static inline size_t mx_lower_u64(const uint64_t *k, size_t n, uint64_t key) {
  size_t lo = 0, hi = n;
  while (lo < hi) {
    const size_t mid = lo + (hi - lo) / 2;
    if (k[mid] < key) lo = mid + 1;
    else hi = mid;
  }
  return lo;
}

/* Sorts keys and drops repeats; returns how many are left (0 on failure,
 * *st the status). */
size_t mx_sort_unique_u64(uint64_t *keys, size_t n, int *st);
/* The index of key in the ascending keys v[0..n), or UINT32_MAX. */
uint32_t mx_find_u64(const uint64_t *v, size_t n, uint64_t key);
/* The same, searched outwards from *hint (doubling steps, then halving):
 * O(log d) reads for a key d places away from the hint, so a run of keys
 * that are near one another in Morton order (the corners of successive
 * leaves) costs a cache line or two each instead of a full search. *hint is
 * set to the key's place (its insertion place when absent) for the next
 * call; any start value is valid. */
uint32_t mx_find_u64_near(const uint64_t *v, size_t n, uint64_t key, size_t *hint);

#endif
