/* The recursive balance of the quadtree, the baseline of section 6.1: after
 * all the levels are refined, every leaf looks for its 4 edge neighbours of
 * its own level by descending the tree from the roots (the classic
 * neighbour search, no edge infos), and is split when one of them is split
 * into children that are split too (a quadrant two levels finer touches the
 * leaf). The caller splits what one pass finds and repeats until a pass
 * finds nothing.
 *
 * The rule is the one the edge infos apply while refining (qedges.c): a leaf
 * inside the domain is split when a split quadrant one level finer than it
 * touches one of its edges. Splitting only adds such quadrants, so the
 * closure does not depend on the order of the splits: both give the same
 * leaves. */
#include <string.h>

#include "base/common.h"
#include "quad/quad.h"
#include "base/scan.h"

/* Small loops run on one thread: a parallel region costs more than them. */
#define PAR(n) ((n) > 4096)

#define NONE UINT32_MAX

typedef struct {
  const mx_qtree *T;
  uint32_t *root; /* root quadrant of grid cell (i, j), i + dims[0] * j */
} search;

/* The quadrant of `level` anchored at lattice point (x, y), or the leaf
 * holding that point when it is coarser; NONE outside the grid. */
static uint32_t descend(const search *S, int64_t x, int64_t y, int level) {
  const mx_qtree *T = S->T;
  const int64_t nx = (int64_t)T->grid.dims[0] << MX_QMAX_LEVEL;
  const int64_t ny = (int64_t)T->grid.dims[1] << MX_QMAX_LEVEL;
  if (x < 0 || y < 0 || x >= nx || y >= ny) return NONE;
  uint32_t q = S->root[(x >> MX_QMAX_LEVEL) + T->grid.dims[0] * (y >> MX_QMAX_LEVEL)];
  while (T->level[q] < level && (T->flags[q] & MX_Q_SPLIT)) {
    const int b = MX_QMAX_LEVEL - T->level[q] - 1;
    q = T->child0[q] + (uint32_t)(((x >> b) & 1) | (((y >> b) & 1) << 1));
  }
  return q;
}

/* Edge e (0 bottom, 1 right, 2 top, 3 left): the neighbour's offset in
 * sizes, and its two children along the shared edge. */
static const int step[4][2] = {{0, -1}, {1, 0}, {0, 1}, {-1, 0}};
static const int facing[4][2] = {{2, 3}, {0, 2}, {0, 1}, {1, 3}};

static int must_split(const search *S, uint32_t q) {
  const mx_qtree *T = S->T;
  const int m = T->level[q];
  uint32_t x, y;
  mx_qkey_xy(T->key[q], &x, &y);
  const int64_t s = mx_qsize(m);
  for (int e = 0; e < 4; e++) {
    const uint32_t n = descend(S, x + step[e][0] * s, y + step[e][1] * s, m);
    if (n == NONE || T->level[n] != m || !(T->flags[n] & MX_Q_SPLIT)) continue;
    for (int k = 0; k < 2; k++)
      if (T->flags[T->child0[n] + (uint32_t)facing[e][k]] & MX_Q_SPLIT) return 1;
  }
  return 0;
}

int mx_qbalance_find(const mx_qtree *T, size_t nroots, uint32_t **out, size_t *n) {
  *out = NULL;
  *n = 0;
  search S = {T, mx_alloc((nroots + 1) * sizeof(uint32_t))};
  const size_t B = 4096, nb = (T->n + B - 1) / B;
  uint64_t *off = mx_alloc((nb + 1) * sizeof *off);
  uint8_t *hit = mx_alloc(T->n + 1);
  if (!S.root || !off || !hit) {
    mx_free(S.root), mx_free(off), mx_free(hit);
    return MX_ENOMEM;
  }
  for (uint32_t r = 0; r < nroots; r++) {
    uint32_t x, y;
    mx_qkey_xy(T->key[r], &x, &y);
    S.root[(x >> MX_QMAX_LEVEL) + T->grid.dims[0] * (y >> MX_QMAX_LEVEL)] = r;
  }
#pragma omp parallel for schedule(static) if (PAR(T->n))
  for (size_t b = 0; b < nb; b++) {
    uint64_t k = 0;
    for (size_t q = b * B; q < T->n && q < (b + 1) * B; q++) {
      hit[q] = !(T->flags[q] & (MX_Q_SPLIT | MX_Q_OUT)) && must_split(&S, (uint32_t)q);
      k += hit[q];
    }
    off[b] = k;
  }
  const size_t total = mx_scan_u64(off, nb);
  uint32_t *list = mx_alloc((total + 1) * sizeof *list);
  if (list) {
#pragma omp parallel for schedule(static) if (PAR(T->n))
    for (size_t b = 0; b < nb; b++) {
      uint64_t w = off[b];
      for (size_t q = b * B; q < T->n && q < (b + 1) * B; q++)
        if (hit[q]) list[w++] = (uint32_t)q;
    }
  }
  mx_free(S.root), mx_free(off), mx_free(hit);
  if (!list) return MX_ENOMEM;
  *out = list;
  *n = total;
  return MX_OK;
}
