/* Surface topology: the edge table (half-edges grouped by edge) and the
 * shells with their consistent orientation; see surface_topology.h. */
#include "geom/surface_topology.h"

#include <stdlib.h>
#include <string.h>

#include "base/common.h"

#define NONE UINT32_MAX

static int cmp_u64(const void *a, const void *b) {
  const uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
  return (x > y) - (x < y);
}

static inline int repeats(const mx_edge_table *T, uint32_t i) {
  const uint32_t a = mx_edge_vertex(T, i, 0), b = mx_edge_vertex(T, i, 1),
                 c = mx_edge_vertex(T, i, 2);
  return a == b || b == c || a == c;
}

void mx_edge_table_free(mx_edge_table *T) {
  mx_free(T->key);
  mx_free(T->half);
  mx_free(T->first);
  T->key = NULL;
  T->half = NULL;
  T->first = NULL;
  T->n = 0;
}

/* The half-edges of T's list bucketed by their smaller vertex (bucket v:
 * [v ? end[v - 1] : 0, end[v]) for vertex v < nv), each
 * bucket sorted: entries (larger vertex << 32) | h in e (T->n of them). */
static int bucket_edges(mx_edge_table *T, uint32_t nv, int skip_repeats, uint64_t *e,
                        size_t **end_out) {
  const uint32_t ntri = T->ntri;
  const size_t nb = nv;
  size_t *end = mx_calloc((nb + 1) * sizeof *end);
  if (!end) return MX_ENOMEM;
  for (uint32_t i = 0; i < ntri; i++) {
    if (skip_repeats && repeats(T, i)) continue;
    for (int k = 0; k < 3; k++) {
      const uint32_t a = mx_edge_vertex(T, i, k), b = mx_edge_vertex(T, i, k == 2 ? 0 : k + 1);
      end[(a < b ? a : b) + 1]++;
    }
  }
  for (size_t v = 0; v < nb; v++) end[v + 1] += end[v];
  T->n = end[nb];
  for (uint32_t i = 0; i < ntri; i++) {
    if (skip_repeats && repeats(T, i)) continue;
    for (int k = 0; k < 3; k++) {
      const uint32_t a = mx_edge_vertex(T, i, k), b = mx_edge_vertex(T, i, k == 2 ? 0 : k + 1);
      const uint32_t lo = a < b ? a : b, hi = a < b ? b : a;
      e[end[lo]++] = (uint64_t)hi << 32 | (3 * i + (uint32_t)k);
    }
  }
  /* end[v] is now the end of bucket v */
#pragma omp parallel for schedule(dynamic, 4096) if (nb > 50000)
  for (size_t v = 0; v < nb; v++) {
    const size_t b0 = v ? end[v - 1] : 0, m = end[v] - b0;
    uint64_t *b = e + b0;
    if (m > 24) {
      qsort(b, m, sizeof *b, cmp_u64);
      continue;
    }
    for (size_t i = 1; i < m; i++) {
      const uint64_t x = b[i];
      size_t j = i;
      for (; j > 0 && b[j - 1] > x; j--) b[j] = b[j - 1];
      b[j] = x;
    }
  }
  *end_out = end;
  return MX_OK;
}

int mx_edge_table_build(mx_edge_table *T, const uint32_t *tri, const uint32_t *order,
                        uint32_t ntri, uint32_t nv, int skip_repeats, int with_first) {
  memset(T, 0, sizeof *T);
  T->tri = tri;
  T->order = order;
  T->ntri = ntri;
  const size_t nh = 3 * (size_t)ntri;
  T->key = mx_alloc((nh ? nh : 1) * sizeof *T->key);
  T->half = mx_alloc((nh ? nh : 1) * sizeof *T->half);
  T->first = with_first ? mx_alloc((nh ? nh : 1) * sizeof *T->first) : NULL;
  size_t *end = NULL;
  const size_t nb = nv;
  if (!T->key || !T->half || (with_first && !T->first) ||
      bucket_edges(T, nv, skip_repeats, T->key, &end) != MX_OK) {
    mx_edge_table_free(T);
    return MX_ENOMEM;
  }
  if (with_first && T->n < nh) memset(T->first, 0xff, nh * sizeof *T->first);
  /* split the entries into key and half, note the runs' starts */
  uint64_t *e = T->key;
#pragma omp parallel for schedule(dynamic, 4096) if (nb > 50000)
  for (size_t v = 0; v < nb; v++) {
    const size_t b0 = v ? end[v - 1] : 0;
    const uint64_t lo = (uint64_t)v << 32;
    size_t run = b0;
    for (size_t j = b0; j < end[v]; j++) {
      const uint32_t h = (uint32_t)e[j];
      T->half[j] = h;
      e[j] = lo | e[j] >> 32;
      if (j > b0 && e[j] != e[j - 1]) run = j;
      if (with_first) T->first[h] = (uint32_t)run;
    }
  }
  mx_free(end);
  return MX_OK;
}

int mx_edges_open(const uint32_t *tri, uint32_t ntri, uint32_t nv, size_t *open) {
  mx_edge_table T;
  memset(&T, 0, sizeof T);
  T.tri = tri;
  T.ntri = ntri;
  const size_t nh = 3 * (size_t)ntri;
  uint64_t *e = mx_alloc((nh ? nh : 1) * sizeof *e);
  size_t *end = NULL;
  const size_t nb = nv;
  if (!e || bucket_edges(&T, nv, 0, e, &end) != MX_OK) {
    mx_free(e);
    return MX_ENOMEM;
  }
  size_t bad = 0; /* serial: the bucketing dominates anyway */
  for (size_t v = 0; v < nb; v++) {
    const size_t b1 = end[v];
    for (size_t i = v ? end[v - 1] : 0; i < b1;) {
      size_t j = i + 1;
      while (j < b1 && (e[j] >> 32) == (e[i] >> 32)) j++;
      bad += j - i != 2;
      i = j;
    }
  }
  mx_free(e);
  mx_free(end);
  *open = bad;
  return MX_OK;
}

int mx_surface_shells(const mx_edge_table *T, int through_all, uint32_t *shell,
                      uint8_t *flip, uint32_t *nshells, uint32_t **seed_out,
                      size_t *conflicts_out) {
  const uint32_t nt = T->ntri;
  uint32_t *queue = mx_alloc((size_t)nt * sizeof *queue + 4);
  uint32_t *seed = seed_out ? mx_alloc((size_t)nt * sizeof *seed + 4) : NULL;
  if (!queue || (seed_out && !seed)) {
    mx_free(queue);
    mx_free(seed);
    return MX_ENOMEM;
  }
  for (uint32_t i = 0; i < nt; i++) shell[i] = NONE;
  uint32_t nc = 0;
  size_t conflicts = 0;
  for (uint32_t s0 = 0; s0 < nt; s0++) {
    if (shell[s0] != NONE || T->first[3 * (size_t)s0] == NONE) continue;
    const uint32_t c = nc++;
    if (seed) seed[c] = s0;
    shell[s0] = c;
    flip[s0] = 0;
    size_t qh = 0, qt = 0;
    queue[qt++] = s0;
    while (qh < qt) {
      const uint32_t t = queue[qh++];
      for (int k = 0; k < 3; k++) {
        const uint32_t h = 3 * t + (uint32_t)k;
        const size_t s = T->first[h], end = mx_edge_run_end(T, s);
        const int manifold = end - s == 2;
        if (!manifold && !through_all) continue;
        const uint32_t from = mx_half_start(T, h);
        for (size_t j = s; j < end; j++) {
          const uint32_t g = T->half[j], t2 = g / 3;
          if (t2 == t) continue;
          /* Two faces agree when they run through the edge in opposite
           * directions. Across other edges the input orientation is kept. */
          const uint8_t want =
              manifold ? (uint8_t)(flip[t] ^ (mx_half_start(T, g) == from)) : flip[t];
          if (shell[t2] == NONE) {
            shell[t2] = c;
            flip[t2] = want;
            queue[qt++] = t2;
          } else if (manifold && flip[t2] != want && t < t2) {
            conflicts++;
          }
        }
      }
    }
  }
  mx_free(queue);
  *nshells = nc;
  if (seed_out) *seed_out = seed;
  if (conflicts_out) *conflicts_out = conflicts;
  return MX_OK;
}
