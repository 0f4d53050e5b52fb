/* Two leaf sets compared octant by octant (see p4est_compare.h). An octant
 * (k, l) covers the keys [k, k + 8^(MX_MAX_LEVEL - l)) of the finest
 * lattice, so with both sets sorted by key, the leaf of the other set
 * containing an octant is the last one at or before its key, and the leaves
 * it contains are those keyed inside its range. */
#include "mpi/p4est_compare.h"

#include <string.h>

#include "base/scan.h"

static uint64_t span(int level) { return 1ULL << (3 * (MX_MAX_LEVEL - level)); }

/* Index of the last key <= k, or n when none. */
static size_t last_at_or_before(const uint64_t *keys, size_t n, uint64_t k) {
  size_t lo = 0, hi = n;
  while (lo < hi) {
    const size_t mid = lo + (hi - lo) / 2;
    if (keys[mid] <= k) lo = mid + 1; else hi = mid;
  }
  return lo == 0 ? n : lo - 1;
}

/* How the X-only leaf (k, l) sits against the set Y. */
static void place(uint64_t k, int l, const uint64_t *ky, const uint8_t *ly, size_t ny,
                  size_t *finer, size_t *coarser, size_t *alone) {
  const size_t j = last_at_or_before(ky, ny, k);
  if (j < ny && ly[j] < l && k - ky[j] < span(ly[j])) {
    (*finer)++; /* inside a coarser Y leaf */
    return;
  }
  /* a Y leaf keyed inside (k, l)'s range */
  const size_t i = j < ny && ky[j] == k ? j : (j == ny ? 0 : j + 1);
  if (i < ny && ky[i] >= k && ky[i] - k < span(l))
    (*coarser)++;
  else
    (*alone)++;
}

void mx_leaf_diff_compute(const uint64_t *ka, const uint8_t *la, size_t na,
                          const uint64_t *kb, const uint8_t *lb, size_t nb, mx_leaf_diff *d) {
  memset(d, 0, sizeof *d);
  d->n_a = na;
  d->n_b = nb;
  size_t i = 0, j = 0;
  while (i < na || j < nb) {
    if (j == nb || (i < na && ka[i] < kb[j])) {
      d->only_a++;
      d->only_a_level[la[i]]++;
      place(ka[i], la[i], kb, lb, nb, &d->a_finer, &d->a_coarser, &d->a_alone);
      i++;
    } else if (i == na || kb[j] < ka[i]) {
      d->only_b++;
      d->only_b_level[lb[j]]++;
      place(kb[j], lb[j], ka, la, na, &d->b_finer, &d->b_coarser, &d->b_alone);
      j++;
    } else {
      if (la[i] == lb[j]) {
        d->common++;
      } else {
        d->only_a++;
        d->only_a_level[la[i]]++;
        d->only_b++;
        d->only_b_level[lb[j]]++;
        /* same anchor: the finer one lies inside the coarser one */
        if (la[i] > lb[j]) {
          d->a_finer++;
          d->b_coarser++;
        } else {
          d->a_coarser++;
          d->b_finer++;
        }
      }
      i++;
      j++;
    }
  }
}

/* 1 when the boxes of (ka, la) and (kb, lb) share a face or an edge (or
 * part of one): on every axis their intervals overlap or abut, and on at
 * least one they overlap over a length. */
static int touch(uint64_t ka, int la, uint64_t kb, int lb) {
  uint32_t a[3], b[3];
  mx_morton_decode(ka, a);
  mx_morton_decode(kb, b);
  const uint64_t sa = mx_octant_size(la), sb = mx_octant_size(lb);
  int overlap = 0;
  for (int x = 0; x < 3; x++) {
    const uint64_t a0 = a[x], a1 = a[x] + sa, b0 = b[x], b1 = b[x] + sb;
    if (a1 < b0 || b1 < a0) return 0;
    overlap += a0 < b1 && b0 < a1;
  }
  return overlap >= 1;
}

static int in_set(const uint64_t *keys, const uint8_t *lv, size_t n, uint64_t k, int l) {
  const size_t i = mx_lower_u64(keys, n, k);
  return i < n && keys[i] == k && lv[i] == l;
}

void mx_leaf_diff_causes(const uint64_t *qa, const uint8_t *la, const uint8_t *kept, size_t na,
                         const uint64_t *kb, const uint8_t *lb, size_t nb, const int dims[3],
                         mx_split_causes *c) {
  memset(c, 0, sizeof *c);
  for (size_t j = 0; j < nb; j++) {
    const uint64_t k = kb[j];
    const int l = lb[j];
    /* split in the forest: quadrants keyed inside X other than X itself */
    const size_t i0 = mx_lower_u64(qa, na, k);
    if (i0 >= na || qa[i0] != k || la[i0] <= l) continue; /* X, or inside a coarser one */
    c->split++;
    int why = 4; /* 1 outside, 2 chain, 3 common, 4 none: keep the smallest */
    for (int dz = -1; dz <= 1; dz++)
      for (int dy = -1; dy <= 1; dy++)
        for (int dx = -1; dx <= 1; dx++) {
          const int nz = (dx != 0) + (dy != 0) + (dz != 0);
          if (nz == 0 || nz == 3) continue; /* X itself, corners */
          const uint64_t n = mx_morton_neighbor(k, l, dx, dy, dz, dims);
          if (n == UINT64_MAX) continue;
          for (size_t i = mx_lower_u64(qa, na, n); i < na && qa[i] - n < span(l); i++) {
            if (la[i] < l + 2 || !touch(k, l, qa[i], la[i])) continue;
            int w = !kept[i] ? 1 : in_set(kb, lb, nb, qa[i], la[i]) ? 3 : 2;
            if (w < why) why = w;
          }
        }
    if (why == 1) c->by_outside++;
    else if (why == 2) c->by_chain++;
    else if (why == 3) c->by_common++;
    else c->unexplained++;
  }
}
