/* Helpers shared by the octree tests: in-memory surfaces, a builder run, and
 * an independent balance checker (it does not use the library's neighbour or
 * touch code). */
#ifndef MX_TEST_OCTREE_UTIL_H
#define MX_TEST_OCTREE_UTIL_H

#include <omp.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "base/common.h"
#include "kernels/refine.h"
#include "kernels/closures.h"
#include "kernels/edges_lazy.h"
#include "kernels/refine_list.h"
#include "base/morton.h"
#include "soa/trisoup.h"
#include "io/read_surface.h"

/* Append an axis-aligned box surface (12 triangles, outward) to s. */
static void add_box(mx_trisoup *s, const double lo[3], const double hi[3],
                    int inward) {
  mx_trisoup b;
  memset(&b, 0, sizeof b);
  mx_trisoup_reserve(&b, 8, 12);
  for (int i = 0; i < 8; i++) {
    b.x[i] = (i & 1) ? hi[0] : lo[0];
    b.y[i] = (i & 2) ? hi[1] : lo[1];
    b.z[i] = (i & 4) ? hi[2] : lo[2];
  }
  static const uint32_t f[12][3] = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6},
                                    {0, 1, 4}, {1, 5, 4}, {2, 6, 3}, {3, 6, 7},
                                    {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  for (int t = 0; t < 12; t++)
    for (int k = 0; k < 3; k++)
      b.tri[3 * t + k] = f[t][inward ? 2 - k : k];
  b.nv = 8;
  b.nt = 12;
  mx_trisoup_append(s, &b);
  mx_trisoup_free(&b);
}

/* Read a surface of ../shared/data (test_data_dir); 0 with "SKIP ..."
 * printed when it is not there. */
static inline int load_shared_surface(const char *name, mx_trisoup *s) {
  char probe[256], path[1400];
  snprintf(probe, sizeof probe, "surfaces/%s", name);
  const char *dir = test_data_dir(probe);
  if (dir) {
    snprintf(path, sizeof path, "%s/%s", dir, probe);
    memset(s, 0, sizeof *s);
    return mx_read_surface(path, s) == MX_OK && mx_trisoup_check(s, path, NULL) == MX_OK;
  }
  TEST_DATA_MISSING("../shared/data/surfaces/%s not found", name);
  return 0;
}

/* nb random boxes inside [blo, bhi] of relative widths in [wmin, wmin+wr]
 * with levels lmin .. lmin+lr-1, from the generator state *seed. */
static inline void random_boxes(uint64_t *seed, const double blo[3],
                                const double bhi[3], int nb, double wmin,
                                double wr, int lmin, int lr,
                                mx_box_region *boxes) {
  for (int b = 0; b < nb; b++) {
    for (int a = 0; a < 3; a++) {
      *seed = *seed * 6364136223846793005ULL + 1442695040888963407ULL;
      const double u = (double)(*seed >> 11) / 9007199254740992.0;
      *seed = *seed * 6364136223846793005ULL + 1442695040888963407ULL;
      const double w = wmin + wr * (double)(*seed >> 11) / 9007199254740992.0;
      const double c = blo[a] + u * (bhi[a] - blo[a]);
      boxes[b].lo[a] = c - 0.5 * w * (bhi[a] - blo[a]);
      boxes[b].hi[a] = c + 0.5 * w * (bhi[a] - blo[a]);
    }
    boxes[b].level = lmin + (int)((*seed >> 40) % (uint64_t)lr);
  }
}

/* The unit cube (side 1, centred at 0) with a cube hole of side 0.3. */
static inline void cube_with_hole(mx_trisoup *s) {
  const double lo[3] = {-0.5, -0.5, -0.5}, hi[3] = {0.5, 0.5, 0.5};
  const double ilo[3] = {-0.15, -0.15, -0.15}, ihi[3] = {0.15, 0.15, 0.15};
  memset(s, 0, sizeof *s);
  add_box(s, lo, hi, 0);
  add_box(s, ilo, ihi, 1);
}

static inline mx_requests no_requests(void) {
  mx_requests r;
  memset(&r, 0, sizeof r);
  r.s_level = -1;
  r.a_level = -1;
  return r;
}

typedef struct {
  size_t leaves;
  uint64_t hash;
  int balanced; /* 1 if the independent checker found no defect */
} run_result;

/* Independent checker: a hash set of the leaves (key, level); for every leaf
 * and each of its 18 face/edge directions, the same-size cell across is
 * looked up with its ancestors: the leaf containing it must not be two or
 * more levels coarser. Also: no leaf contains another leaf. */
typedef struct {
  uint64_t *k;
  size_t cap;
} leafset;

/* (key, level) as one word: the anchor with the bit just below the octant's
 * own bits set (levels < MX_MAX_LEVEL); never 0. */
static uint64_t ls_word(uint64_t key, int level) {
  return key | (1ULL << (3 * (MX_MAX_LEVEL - level) - 1));
}
static size_t ls_slot(const leafset *s, uint64_t w) {
  uint64_t h = w * 0x9E3779B97F4A7C15ULL;
  return (size_t)(h >> 20) & (s->cap - 1);
}
static void ls_add(leafset *s, uint64_t key, int level) {
  uint64_t w = ls_word(key, level);
  size_t i = ls_slot(s, w);
  while (s->k[i] && s->k[i] != w) i = (i + 1) & (s->cap - 1);
  s->k[i] = w;
}
static int ls_has(const leafset *s, uint64_t key, int level) {
  uint64_t w = ls_word(key, level);
  size_t i = ls_slot(s, w);
  while (s->k[i]) {
    if (s->k[i] == w) return 1;
    i = (i + 1) & (s->cap - 1);
  }
  return 0;
}

static inline int check_balance(const mx_builder *B, const uint32_t *leaves,
                         size_t n) {
  const mx_octree *T = &B->tree.oct;
  leafset s;
  s.cap = 1024;
  while (s.cap < 4 * n) s.cap *= 2;
  s.k = calloc(s.cap, sizeof *s.k);
  for (size_t i = 0; i < n; i++) ls_add(&s, T->key[leaves[i]], T->level[leaves[i]]);
  int defects = 0;
  for (size_t i = 0; i < n && defects < 10; i++) {
    const uint64_t key = T->key[leaves[i]];
    const int l = T->level[leaves[i]];
    uint32_t c[3];
    mx_morton_decode(key, c);
    /* No ancestor of a leaf is a leaf. */
    for (int m = l - 1; m >= 0; m--) {
      uint32_t sz = mx_octant_size(m);
      if (ls_has(&s, mx_morton_encode(c[0] & ~(sz - 1), c[1] & ~(sz - 1),
                                      c[2] & ~(sz - 1)), m)) {
        fprintf(stderr, "leaf (%d) inside another leaf (%d)\n", l, m);
        defects++;
      }
    }
    const int64_t sz = mx_octant_size(l);
    for (int dx = -1; dx <= 1; dx++)
      for (int dy = -1; dy <= 1; dy++)
        for (int dz = -1; dz <= 1; dz++) {
          int nz = (dx != 0) + (dy != 0) + (dz != 0);
          if (nz == 0 || nz == 3) continue; /* corners do not count */
          int64_t p[3] = {c[0] + dx * sz, c[1] + dy * sz, c[2] + dz * sz};
          int out = 0;
          for (int a = 0; a < 3; a++)
            if (p[a] < 0 || p[a] >= ((int64_t)B->tree.grid.dims[a] << MX_MAX_LEVEL))
              out = 1;
          if (out) continue;
          for (int m = l; m >= 0; m--) {
            uint32_t ms = mx_octant_size(m);
            uint64_t k = mx_morton_encode((uint32_t)p[0] & ~(ms - 1),
                                          (uint32_t)p[1] & ~(ms - 1),
                                          (uint32_t)p[2] & ~(ms - 1));
            if (ls_has(&s, k, m)) {
              if (m < l - 1) {
                fprintf(stderr, "unbalanced: leaf level %d next to %d\n", l, m);
                defects++;
              }
              break;
            }
          }
        }
  }
  free(s.k);
  return defects == 0;
}

/* Build with the given requests; use_edges selects the balance. */
static inline run_result run_build(const mx_trisoup *soup, uint32_t nt_domain,
                            const uint32_t *region_t0, const mx_requests *req,
                            int use_edges, int threads) {
  run_result r = {0, 0, 0};
  omp_set_num_threads(threads);
  mx_builder B;
  uint32_t rt0[2] = {nt_domain, nt_domain};
  if (!region_t0) region_t0 = rt0;
  if (mx_builder_init(&B, soup, nt_domain, region_t0, req, use_edges, NULL) ||
      mx_build_roots(&B)) {
    mx_builder_free(&B);
    return r;
  }
  int st = use_edges ? mx_refine_balanced(&B) : mx_refine_unbalanced(&B);
  if (!st && !use_edges) st = mx_balance_recursive(&B);
  if (!st) st = mx_resolve_closures(&B);
  uint32_t *leaves = NULL;
  size_t n = 0;
  if (!st && !mx_leaves(&B.tree, &leaves, &n)) {
    r.leaves = n;
    r.hash = mx_leaves_hash(&B.tree, leaves, n);
    r.balanced = check_balance(&B, leaves, n);
  }
  mx_free(leaves);
  mx_builder_free(&B);
  return r;
}

#endif
