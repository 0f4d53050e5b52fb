/* The quadtree and its restart file (Appendix A of Jaillet & Lobos 2021, the
 * quadtree form of io/restart.h): what is written is what Algorithm 3 needs
 * to start again from the balanced quadtree, and what is read becomes kept
 * leaves (mx_qrequests.keep_*): the next build makes the same tree, with the
 * listed quadrants split once and balance restored by the usual passes.
 *
 * Written: the leaves' corners as nodes (lattice points, sorted by Morton
 * key), every leaf edge once with its mid-node when a finer neighbour made
 * one (0 otherwise: node 0, the grid's lowest corner, is never a midpoint),
 * each leaf "4 n0 n1 n2 n3 level" (counter-clockwise from its lowest corner)
 * with the domain segments it meets, and the cells of each leaf in the
 * mesh's order. Read: each quadrant's corners back onto the lattice of the
 * domain's root grid, rounded to a multiple of the quadrant's side (the
 * file keeps 9 significant digits), checked there, and sorted. */
#include <math.h>
#include <string.h>

#include "common.h"
#include "io/restart.h"
#include "mesher/mesher2d.h"
#include "soa/scan.h"

/* Corner c (counter-clockwise from the lowest) of leaf q, as a lattice key. */
static uint64_t corner_key(const mx_qtree *T, uint32_t q, int c) {
  uint32_t x, y;
  mx_qkey_xy(T->key[q], &x, &y);
  const uint32_t s = mx_qsize(T->level[q]);
  return mx_qkey(x + (c == 1 || c == 2 ? s : 0), y + (c >= 2 ? s : 0));
}

static int nodes_of(const mx_mesher2d *m, mx_restart *r, uint64_t **keys) {
  const size_t n = m->nleaves;
  uint64_t *k = mx_alloc((4 * n + 1) * sizeof *k);
  if (!k) return MX_ENOMEM;
#pragma omp parallel for schedule(static) if (n > 16384)
  for (size_t i = 0; i < n; i++)
    for (int c = 0; c < 4; c++) k[4 * i + c] = corner_key(&m->T, m->leaves[i], c);
  int st;
  const size_t nv = mx_sort_unique_u64(k, 4 * n, &st);
  r->xyz = st ? NULL : mx_alloc((3 * nv + 1) * sizeof *r->xyz);
  if (!st && !r->xyz) st = MX_ENOMEM;
  if (st) {
    mx_free(k);
    return st;
  }
  const mx_qgrid *g = &m->T.grid;
#pragma omp parallel for schedule(static) if (nv > 16384)
  for (size_t v = 0; v < nv; v++) {
    uint32_t x, y;
    mx_qkey_xy(k[v], &x, &y);
    r->xyz[3 * v] = g->origin[0] + g->unit * (double)x;
    r->xyz[3 * v + 1] = g->origin[1] + g->unit * (double)y;
    r->xyz[3 * v + 2] = 0.0;
  }
  r->nv = nv;
  *keys = k;
  return MX_OK;
}

/* Every leaf edge once, "a b mid". */
static int edges_of(const mx_mesher2d *m, mx_restart *r, const uint64_t *vk) {
  const size_t n = m->nleaves, nv = r->nv;
  uint64_t *e = mx_alloc((4 * n + 1) * sizeof *e);
  if (!e) return MX_ENOMEM;
#pragma omp parallel for schedule(static) if (n > 16384)
  for (size_t i = 0; i < n; i++)
    for (int c = 0; c < 4; c++) {
      uint64_t a = mx_find_u64(vk, nv, corner_key(&m->T, m->leaves[i], c));
      uint64_t b = mx_find_u64(vk, nv, corner_key(&m->T, m->leaves[i], (c + 1) & 3));
      e[4 * i + c] = a < b ? a << 32 | b : b << 32 | a;
    }
  int st;
  const size_t ne = mx_sort_unique_u64(e, 4 * n, &st);
  r->edge = st ? NULL : mx_alloc((3 * ne + 1) * sizeof *r->edge);
  if (!st && !r->edge) st = MX_ENOMEM;
  if (!st) {
#pragma omp parallel for schedule(static) if (ne > 16384)
    for (size_t j = 0; j < ne; j++) {
      const uint32_t a = (uint32_t)(e[j] >> 32), b = (uint32_t)e[j];
      uint32_t xa, ya, xb, yb;
      mx_qkey_xy(vk[a], &xa, &ya);
      mx_qkey_xy(vk[b], &xb, &yb);
      const uint32_t mid = mx_find_u64(vk, nv, mx_qkey((xa + xb) / 2, (ya + yb) / 2));
      r->edge[3 * j] = a, r->edge[3 * j + 1] = b;
      r->edge[3 * j + 2] = mid == UINT32_MAX ? 0 : mid;
    }
    r->ne = ne;
  }
  mx_free(e);
  return st;
}

/* The leaves, their segments and their cells. */
static int cells_of(const mx_mesher2d *m, mx_restart *r, const uint64_t *vk) {
  const mx_qtree *T = &m->T;
  const size_t n = m->nleaves;
  r->oct_node = mx_alloc((8 * n + 1) * sizeof *r->oct_node);
  r->oct_level = mx_alloc(n + 1);
  r->oct_tri_off = mx_alloc((n + 1) * sizeof *r->oct_tri_off);
  r->nsub = mx_calloc((n + 1) * sizeof *r->nsub);
  if (!r->oct_node || !r->oct_level || !r->oct_tri_off || !r->nsub) return MX_ENOMEM;
  r->oct_tri_off[0] = 0;
  for (size_t i = 0; i < n; i++) r->oct_tri_off[i + 1] = r->oct_tri_off[i] + T->seg_cnt[m->leaves[i]];
  r->oct_tri = mx_alloc((r->oct_tri_off[n] + 1) * sizeof *r->oct_tri);
  if (!r->oct_tri) return MX_ENOMEM;
#pragma omp parallel for schedule(static) if (n > 16384)
  for (size_t i = 0; i < n; i++) {
    const uint32_t q = m->leaves[i];
    for (int c = 0; c < 4; c++) r->oct_node[8 * i + c] = mx_find_u64(vk, r->nv, corner_key(T, q, c));
    for (int c = 4; c < 8; c++) r->oct_node[8 * i + c] = 0;
    r->oct_level[i] = T->level[q];
    memcpy(r->oct_tri + r->oct_tri_off[i], T->seg_pool + T->seg_off[q],
           T->seg_cnt[q] * sizeof *r->oct_tri);
  }
  /* the cells, grouped by leaf in the leaves' order: what the element lists
   * of the written mesh refer to */
  for (size_t c = 0; c < m->M.ncells; c++) {
    if (c && m->M.leaf[c] < m->M.leaf[c - 1]) {
      mx_error(NULL, 0, "internal: cell %zu is out of its quadrant's order", c);
      return MX_EINTERNAL;
    }
    r->nsub[m->M.leaf[c]]++;
  }
  r->no = n;
  return MX_OK;
}

int mx_qrestart_from_mesher(const mx_mesher2d *m, mx_restart *r) {
  memset(r, 0, sizeof *r);
  r->dim = 2;
  uint64_t *vk = NULL;
  int st = nodes_of(m, r, &vk);
  if (!st) st = edges_of(m, r, vk);
  if (!st) st = cells_of(m, r, vk);
  mx_free(vk);
  if (st) mx_restart_free(r);
  return st;
}

/* ---- reading ------------------------------------------------------------------ */

/* Quadrant i's anchor key, checked: its corners span one side of its level
 * on each axis, its lowest corner is a multiple of that side inside the root
 * grid. */
static int quadrant_key(const mx_restart *r, const mx_qgrid *g, const char *name, size_t i,
                        uint64_t *key) {
  double lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY};
  for (int c = 0; c < 4; c++)
    for (int a = 0; a < 2; a++) {
      const double v = r->xyz[3 * (size_t)r->oct_node[8 * i + c] + a];
      lo[a] = fmin(lo[a], v), hi[a] = fmax(hi[a], v);
    }
  const int level = r->oct_level[i];
  if (level > MX_QMAX_LEVEL - 1) {
    mx_error(name, 0, "quadrant %zu: level %d beyond the finest (%d)", i, level, MX_QMAX_LEVEL - 1);
    return MX_EINPUT;
  }
  const double side = (double)mx_qsize(level);
  uint32_t xy[2];
  for (int a = 0; a < 2; a++) {
    const double u0 = (lo[a] - g->origin[a]) / g->unit, w = (hi[a] - lo[a]) / g->unit;
    const double s = nearbyint(u0 / side) * side;
    if (!(fabs(u0 - s) <= 0.25 * side && fabs(w - side) <= 0.25 * side && s >= 0 &&
          s + side <= (double)g->dims[a] * ldexp(1.0, MX_QMAX_LEVEL))) {
      mx_error(name, 0, "quadrant %zu (level %d, corners (%g, %g) to (%g, %g)) is not a "
               "quadrant of this domain's quadtree: was the file written for another domain?",
               i, level, lo[0], lo[1], hi[0], hi[1]);
      return MX_EINPUT;
    }
    xy[a] = (uint32_t)s;
  }
  *key = mx_qkey(xy[0], xy[1]);
  return MX_OK;
}

int mx_qrestart_to_keep(mx_mesher2d *m, const mx_restart *r) {
  const char *name = m->domain.path;
  mx_qgrid g;
  MX_CHECK(mx_mesher2d_grid(m, &g));
  const size_t n = r->no;
  m->keep_key = mx_alloc((n + 1) * sizeof *m->keep_key);
  m->keep_level = mx_alloc(n + 1);
  m->rs_nsub = mx_calloc((n + 1) * sizeof *m->rs_nsub);
  m->rs_pos = mx_alloc((n + 1) * sizeof *m->rs_pos);
  uint32_t *perm = mx_alloc((n + 1) * sizeof *perm);
  int st = m->keep_key && m->keep_level && m->rs_nsub && m->rs_pos && perm ? MX_OK : MX_ENOMEM;
  for (size_t i = 0; i < n && !st; i++) {
    st = quadrant_key(r, &g, name, i, &m->keep_key[i]);
    perm[i] = (uint32_t)i;
  }
  if (!st) st = mx_sort_u64(m->keep_key, perm, n);
  for (size_t j = 0; j < n && !st; j++) {
    m->keep_level[j] = r->oct_level[perm[j]];
    m->rs_pos[perm[j]] = (uint32_t)j;
    if (j && m->keep_key[j - 1] + ((uint64_t)1 << (2 * (MX_QMAX_LEVEL - m->keep_level[j - 1]))) >
                 m->keep_key[j]) {
      mx_error(name, 0, "quadrants %u and %u overlap: not the leaves of one quadtree",
               perm[j - 1], perm[j]);
      st = MX_EINPUT;
    }
  }
  mx_free(perm);
  if (st) return st;
  if (r->nsub) memcpy(m->rs_nsub, r->nsub, n * sizeof *m->rs_nsub);
  m->nkeep = m->rs_n = n;
  return MX_OK;
}
