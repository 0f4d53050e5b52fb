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
#include <omp.h>
#include <string.h>

#include "base/common.h"
#include "io/restart.h"
#include "mesher/mesher2d.h"
#include "base/scan.h"

/* ---- writing ------------------------------------------------------------------ */

/* The nodes and edges without sorting the corners and sides of every leaf.
 * The leaves come in Morton order, so their anchors (lowest corners) are
 * already sorted and distinct:
 *
 * - Nodes. A corner p of a leaf is the anchor of the leaf just above and to
 *   its right, unless that leaf is out of the domain or larger (p is then
 *   on its lower or left side: a hanging node, or a node on the upper or
 *   right border of the meshed region). So the nodes are the anchors plus
 *   the "extra" corners, those not found among the anchors, and only the
 *   extras are sorted. A point's node number is the count of anchors before
 *   it plus the count of extras before it (two sorted arrays, not merged
 *   into a third); a corner that is leaf j's anchor has leaf j's number.
 * - Edges. A leaf lists its lower and left sides, and its upper (right) side
 *   only when no leaf of its size is above it (to its right): otherwise that
 *   leaf lists the side as its lower (left) one. The lower and left sides
 *   start at the leaf's anchor, so leaf by leaf they come sorted by their
 *   lower node; only the upper and right sides listed are sorted, and each
 *   list gives the other's places (counts of the other's sides before).
 * - Mid-nodes. The midpoint of a lower or left side lies in the leaf's
 *   Morton range: the anchors before it are those of the leaf and the
 *   leaves before it, and it can only be an extra, one of the few extras in
 *   that range.
 *
 * Searches are mx_find_u64_near from a hint: the next leaf for a corner
 * among the anchors (its usual answer), else the last answer of the same
 * stream (one corner of successive leaves): nearby keys cost a cache line
 * or two. The passes share fixed slices of the leaves (the same in every
 * pass for any thread count), each with its own hints; a slice's counts
 * give its place in the lists it fills, which are then sorted: the output
 * does not depend on the thread count. */

#define PAR(n) ((n) > 16384)
enum { MAX_SLICES = 256 };
/* own[i]: corner c of leaf i (1 to 3) is an extra (bit c, EXTRA(c)); leaf
 * i lists its right side, its upper side */
#define EXTRA(c) (1u << (c))
enum { ANY_EXTRA = 14, OWN_RIGHT = 16, OWN_UP = 32 };

typedef struct {
  const mx_mesher2d *m;
  mx_restart *r;
  size_t n;            /* leaves */
  int nslices;
  uint64_t *anchor;    /* n: leaf i's anchor, ascending (kept in r->oct_tri_off,
                        * of the same size, until the segments are counted) */
  uint32_t *own;       /* n: the bits above (kept in r->nsub until the cells
                        * are counted) */
  uint64_t *extra;     /* the extra corners, ascending, distinct */
  size_t nextra;
  uint64_t *side;      /* the upper and right sides listed, a << 32 | b, ascending */
  uint32_t *side_at;   /* sorted along: the place where the side was listed */
  uint32_t *side_mid;  /* by that place: the side's mid-node, or where in
                        * oct_node to find it (side_ref), */
  uint32_t *side_ref;  /* UINT32_MAX when side_mid is the node */
  uint32_t *side_low;  /* and the count of lower and left sides before it */
  size_t nside;
  size_t cnt_extra[MAX_SLICES + 1], cnt_side[MAX_SLICES + 1];
} qwrite;

/* Slice s of nslices over [0, n). */
static void slice(size_t n, int s, int nslices, size_t *lo, size_t *hi) {
  *lo = n * (size_t)s / (size_t)nslices;
  *hi = n * (size_t)(s + 1) / (size_t)nslices;
}

/* Leaf i: anchor (x, y), side, and its corners counter-clockwise from the
 * anchor as lattice keys. */
static inline void corners(const qwrite *w, size_t i, uint32_t *x, uint32_t *y, uint32_t *s,
                           uint64_t k[4]) {
  mx_qkey_xy(w->anchor[i], x, y);
  *s = mx_qsize(w->r->oct_level[i]);
  k[0] = w->anchor[i];
  k[1] = mx_qkey(*x + *s, *y);
  k[2] = mx_qkey(*x + *s, *y + *s);
  k[3] = mx_qkey(*x, *y + *s);
}

/* Exclusive sums of per-slice counts; returns the total. */
static size_t slice_offsets(size_t *cnt, int nslices) {
  size_t total = 0;
  for (int s = 0; s < nslices; s++) {
    const size_t c = cnt[s];
    cnt[s] = total;
    total += c;
  }
  cnt[nslices] = total;
  return total;
}

/* The leaves' anchors and levels. */
static void leaf_keys(qwrite *w) {
  const mx_qtree *T = &w->m->T;
  const uint32_t *leaf = w->m->leaves;
#pragma omp parallel for schedule(static) if (PAR(w->n))
  for (size_t i = 0; i < w->n; i++) {
    w->anchor[i] = T->key[leaf[i]];
    w->r->oct_level[i] = T->level[leaf[i]];
  }
}

/* Corners 1 to 3 of each leaf among the anchors: oct_node[8 i + c] gets the
 * count of anchors before the corner (its leaf when it is an anchor), own[i]
 * the extra corners and the sides the leaf lists; per slice, the counts of
 * both. Corners 4 to 7 (none in 2D) are 0. */
static void find_anchors(qwrite *w) {
  const uint8_t *level = w->r->oct_level;
  uint32_t *on = w->r->oct_node;
#pragma omp parallel for schedule(static) if (PAR(w->n))
  for (int s = 0; s < w->nslices; s++) {
    size_t lo, hi, ne = 0, ns = 0;
    slice(w->n, s, w->nslices, &lo, &hi);
    for (size_t i = lo; i < hi; i++) {
      uint32_t x, y, side;
      uint64_t k[4];
      corners(w, i, &x, &y, &side, k);
      uint32_t f = OWN_RIGHT | OWN_UP;
      on[8 * i] = (uint32_t)i;
      /* corners 1 and 3 come after the anchor, corner 2 after both */
      size_t hint[4] = {0, i + 1, 0, i + 1};
      for (int c = 1; c < 4; c += 2) {
        const uint32_t j = mx_find_u64_near(w->anchor, w->n, k[c], &hint[c]);
        if (j == UINT32_MAX) f |= EXTRA(c), ne++;
        else if (level[j] == level[i]) f &= ~(uint32_t)(c == 1 ? OWN_RIGHT : OWN_UP);
      }
      hint[2] = hint[1] > hint[3] ? hint[1] : hint[3];
      if (mx_find_u64_near(w->anchor, w->n, k[2], &hint[2]) == UINT32_MAX) f |= EXTRA(2), ne++;
      for (int c = 1; c < 4; c++) on[8 * i + c] = (uint32_t)hint[c];
      for (int c = 4; c < 8; c++) on[8 * i + c] = 0;
      ns += !!(f & OWN_RIGHT) + !!(f & OWN_UP);
      w->own[i] = f;
    }
    w->cnt_extra[s] = ne;
    w->cnt_side[s] = ns;
  }
}

/* The extra corners, sorted, each once. */
static int collect_extras(qwrite *w) {
  const size_t total = slice_offsets(w->cnt_extra, w->nslices);
  w->extra = mx_alloc((total + 1) * sizeof *w->extra);
  if (!w->extra) return MX_ENOMEM;
#pragma omp parallel for schedule(static) if (PAR(w->n))
  for (int s = 0; s < w->nslices; s++) {
    size_t lo, hi, o = w->cnt_extra[s];
    slice(w->n, s, w->nslices, &lo, &hi);
    for (size_t i = lo; i < hi; i++) {
      if (!(w->own[i] & ANY_EXTRA)) continue;
      uint32_t x, y, side;
      uint64_t k[4];
      corners(w, i, &x, &y, &side, k);
      for (int c = 1; c < 4; c++)
        if (w->own[i] & EXTRA(c)) w->extra[o++] = k[c];
    }
  }
  int st;
  w->nextra = mx_sort_unique_u64(w->extra, total, &st);
  return st;
}

static void put_xyz(const qwrite *w, size_t v, uint64_t k) {
  const mx_qgrid *g = &w->m->T.grid;
  uint32_t x, y;
  mx_qkey_xy(k, &x, &y);
  w->r->xyz[3 * v] = g->origin[0] + g->unit * (double)x;
  w->r->xyz[3 * v + 1] = g->origin[1] + g->unit * (double)y;
  w->r->xyz[3 * v + 2] = 0.0;
}

/* Node number of lattice point k, or 0 when it is no node. */
static uint32_t node_of(const qwrite *w, uint64_t k, size_t *ha, size_t *he) {
  const uint32_t a = mx_find_u64_near(w->anchor, w->n, k, ha);
  const uint32_t e = mx_find_u64_near(w->extra, w->nextra, k, he);
  return a == UINT32_MAX && e == UINT32_MAX ? 0 : (uint32_t)(*ha + *he);
}

/* The mid-node of the side of leaf i (listed: no leaf of its size beyond
 * it) whose first corner c (1: the right side, 3: the upper one) is the
 * anchor of leaf j when is_anchor. Leaf j larger: the midpoint is inside
 * its side, no node; one level finer: it is leaf j's corner 4 - c, whose
 * number is in oct_node once all are numbered (*ref gets its place);
 * otherwise (j finer still, or out of the domain) it is searched for. */
static uint32_t side_mid(const qwrite *w, size_t i, int c, size_t j, int is_anchor, uint64_t m,
                         size_t *ha, size_t *he, uint32_t *ref) {
  const uint8_t *level = w->r->oct_level;
  *ref = UINT32_MAX;
  if (is_anchor && level[j] < level[i]) return 0;
  if (is_anchor && level[j] == level[i] + 1) {
    *ref = (uint32_t)(8 * j + 4 - (size_t)c);
    return 0;
  }
  return node_of(w, m, ha, he);
}

/* The count of lower and left sides (two a leaf, in the leaves' order, each
 * leaf's by upper end) before the side from corner ka to kb, ka having j
 * anchors before it (leaf j's anchor when is_anchor). */
static uint32_t low_sides_before(const qwrite *w, size_t j, int is_anchor, uint64_t kb) {
  size_t k = 2 * j;
  if (is_anchor) {
    uint32_t x, y, s;
    uint64_t c[4];
    corners(w, j, &x, &y, &s, c);
    k += (c[1] < kb) + (c[3] < kb);
  }
  return (uint32_t)k;
}

/* The node numbers of the corners (anchors first: a corner that is an
 * anchor takes that leaf's number), the nodes' coordinates, and the upper
 * and right sides the leaves list, with their mid-nodes, sorted. */
static int number_corners(qwrite *w) {
  mx_restart *r = w->r;
  uint32_t *on = r->oct_node;
  r->nv = w->n + w->nextra;
  r->xyz = mx_alloc((3 * r->nv + 1) * sizeof *r->xyz);
  w->nside = slice_offsets(w->cnt_side, w->nslices);
  w->side = mx_alloc((w->nside + 1) * sizeof *w->side);
  w->side_at = mx_alloc((w->nside + 1) * sizeof *w->side_at);
  w->side_mid = mx_alloc((w->nside + 1) * sizeof *w->side_mid);
  w->side_ref = mx_alloc((w->nside + 1) * sizeof *w->side_ref);
  w->side_low = mx_alloc((w->nside + 1) * sizeof *w->side_low);
  if (!r->xyz || !w->side || !w->side_at || !w->side_mid || !w->side_ref || !w->side_low)
    return MX_ENOMEM;
#pragma omp parallel if (PAR(w->n))
  {
#pragma omp for schedule(static)
    for (int s = 0; s < w->nslices; s++) {
      size_t lo, hi, he = 0;
      slice(w->n, s, w->nslices, &lo, &hi);
      for (size_t i = lo; i < hi; i++) {
        mx_find_u64_near(w->extra, w->nextra, w->anchor[i], &he);
        on[8 * i] = (uint32_t)(i + he);
        put_xyz(w, on[8 * i], w->anchor[i]);
      }
    }
#pragma omp for schedule(static)
    for (int s = 0; s < w->nslices; s++) {
      size_t lo, hi, o = w->cnt_side[s];
      slice(w->n, s, w->nslices, &lo, &hi);
      size_t he[4] = {0, 0, 0, 0}, hma[2] = {lo, lo}, hme[2] = {0, 0};
      for (size_t i = lo; i < hi; i++) {
        uint32_t x, y, side;
        uint64_t k[4];
        corners(w, i, &x, &y, &side, k);
        const uint32_t f = w->own[i], before[4] = {0, on[8 * i + 1], on[8 * i + 2], on[8 * i + 3]};
        for (int c = 1; c < 4; c++) {
          if (f & EXTRA(c)) {
            mx_find_u64_near(w->extra, w->nextra, k[c], &he[c]);
            on[8 * i + c] = before[c] + (uint32_t)he[c];
          } else {
            on[8 * i + c] = on[8 * (size_t)before[c]];
          }
        }
        if (f & OWN_RIGHT) {
          w->side[o] = (uint64_t)on[8 * i + 1] << 32 | on[8 * i + 2];
          w->side_at[o] = (uint32_t)o;
          w->side_mid[o] = side_mid(w, i, 1, before[1], !(f & EXTRA(1)),
                                    mx_qkey(x + side, y + side / 2), &hma[0], &hme[0],
                                    &w->side_ref[o]);
          w->side_low[o++] = low_sides_before(w, before[1], !(f & EXTRA(1)), k[2]);
        }
        if (f & OWN_UP) {
          w->side[o] = (uint64_t)on[8 * i + 3] << 32 | on[8 * i + 2];
          w->side_at[o] = (uint32_t)o;
          w->side_mid[o] = side_mid(w, i, 3, before[3], !(f & EXTRA(3)),
                                    mx_qkey(x + side / 2, y + side), &hma[1], &hme[1],
                                    &w->side_ref[o]);
          w->side_low[o++] = low_sides_before(w, before[3], !(f & EXTRA(3)), k[2]);
        }
      }
    }
  }
  /* the extras' coordinates: extra j is node j + (anchors before it) */
#pragma omp parallel for schedule(static) if (PAR(w->nextra))
  for (int s = 0; s < w->nslices; s++) {
    size_t lo, hi, ha = 0;
    slice(w->nextra, s, w->nslices, &lo, &hi);
    for (size_t j = lo; j < hi; j++) {
      mx_find_u64_near(w->anchor, w->n, w->extra[j], &ha);
      put_xyz(w, j + ha, w->extra[j]);
    }
  }
  return mx_sort_u64(w->side, w->side_at, w->nside);
}

static void put_edge(uint32_t *e, size_t j, uint32_t a, uint32_t b, uint32_t mid) {
  e[3 * j] = a, e[3 * j + 1] = b, e[3 * j + 2] = mid;
}

/* Every leaf side once, "a b mid", ascending: the lower and left sides
 * leaf by leaf, the listed upper and right ones where they fall among them. */
static int place_edges(qwrite *w) {
  mx_restart *r = w->r;
  const uint32_t *on = r->oct_node;
  r->ne = 2 * w->n + w->nside;
  r->edge = mx_alloc((3 * r->ne + 1) * sizeof *r->edge);
  if (!r->edge) return MX_ENOMEM;
#pragma omp parallel for schedule(static) if (PAR(w->n))
  for (int s = 0; s < w->nslices; s++) {
    size_t lo, hi, hs = 0;
    slice(w->n, s, w->nslices, &lo, &hi);
    for (size_t i = lo; i < hi; i++) {
      uint32_t x, y;
      mx_qkey_xy(w->anchor[i], &x, &y);
      const uint32_t side = mx_qsize(r->oct_level[i]), a = on[8 * i];
      /* mid-nodes: the extras in the leaf's Morton range (from the first
       * after its anchor: a - i of them come before) */
      const uint64_t mk[2] = {mx_qkey(x + side / 2, y), mx_qkey(x, y + side / 2)};
      const uint64_t range = (uint64_t)side * side;
      uint32_t b[2] = {on[8 * i + 1], on[8 * i + 3]}, mid[2] = {0, 0};
      for (size_t e = a - i; e < w->nextra && w->extra[e] - w->anchor[i] < range; e++)
        for (int t = 0; t < 2; t++)
          if (w->extra[e] == mk[t]) mid[t] = (uint32_t)(i + 1 + e);
      /* lower side then left side, or the other way round (by upper node),
       * each after the listed sides before it */
      mx_find_u64_near(w->side, w->nside, (uint64_t)a << 32, &hs);
      const int swap = b[1] < b[0];
      for (int t = 0; t < 2; t++) {
        const int u = t ^ swap;
        size_t k = hs;
        while (k < w->nside && w->side[k] < ((uint64_t)a << 32 | b[u])) k++;
        put_edge(r->edge, 2 * i + (size_t)t + k, a, b[u], mid[u]);
      }
    }
  }
#pragma omp parallel for schedule(static) if (PAR(w->nside))
  for (size_t j = 0; j < w->nside; j++) {
    const uint32_t o = w->side_at[j], ref = w->side_ref[o];
    put_edge(r->edge, j + w->side_low[o], (uint32_t)(w->side[j] >> 32), (uint32_t)w->side[j],
             ref == UINT32_MAX ? w->side_mid[o] : on[ref]);
  }
  return MX_OK;
}

/* The leaves' segments and the cells of each leaf (the mesh's cells are
 * grouped by leaf in the leaves' order: what the element lists of the
 * written mesh refer to). */
static int cells_of(qwrite *w) {
  const mx_qtree *T = &w->m->T;
  const mx_qmesh *M = &w->m->M;
  const uint32_t *leaf = w->m->leaves;
  mx_restart *r = w->r;
  const size_t n = w->n;
#pragma omp parallel for schedule(static) if (PAR(n))
  for (size_t i = 0; i < n; i++) {
    r->oct_tri_off[i] = T->seg_cnt[leaf[i]];
    r->nsub[i] = 0;
  }
  r->oct_tri_off[n] = mx_scan_u64(r->oct_tri_off, n);
  r->oct_tri = mx_alloc((r->oct_tri_off[n] + 1) * sizeof *r->oct_tri);
  if (!r->oct_tri) return MX_ENOMEM;
#pragma omp parallel for schedule(static) if (PAR(n))
  for (size_t i = 0; i < n; i++)
    memcpy(r->oct_tri + r->oct_tri_off[i], T->seg_pool + T->seg_off[leaf[i]],
           T->seg_cnt[leaf[i]] * sizeof *r->oct_tri);
  /* each run of cells of one leaf counted at its first cell */
  size_t bad = SIZE_MAX;
#pragma omp parallel for schedule(static) reduction(min : bad) if (PAR(M->ncells))
  for (size_t c = 0; c < M->ncells; c++) {
    if (c && M->leaf[c] == M->leaf[c - 1]) continue;
    if (c && M->leaf[c] < M->leaf[c - 1]) {
      bad = c < bad ? c : bad;
      continue;
    }
    size_t e = c + 1;
    while (e < M->ncells && M->leaf[e] == M->leaf[c]) e++;
    r->nsub[M->leaf[c]] = (uint32_t)(e - c);
  }
  if (bad != SIZE_MAX) {
    mx_error(NULL, 0, "internal: cell %zu is out of its quadrant's order", bad);
    return MX_EINTERNAL;
  }
  return MX_OK;
}

int mx_qrestart_from_mesher(const mx_mesher2d *m, mx_restart *r) {
  memset(r, 0, sizeof *r);
  r->dim = 2;
  const size_t n = m->nleaves;
  const int nt = omp_get_max_threads();
  qwrite w = {.m = m, .r = r, .n = n, .nslices = nt < 1 ? 1 : nt > MAX_SLICES ? MAX_SLICES : nt};
  r->no = n;
  r->oct_node = mx_alloc((8 * n + 1) * sizeof *r->oct_node);
  r->oct_level = mx_alloc(n + 1);
  r->oct_tri_off = mx_alloc((n + 1) * sizeof *r->oct_tri_off);
  r->nsub = mx_alloc((n + 1) * sizeof *r->nsub);
  w.anchor = r->oct_tri_off;
  w.own = r->nsub;
  int st = r->oct_node && r->oct_level && r->oct_tri_off && r->nsub ? MX_OK : MX_ENOMEM;
  if (!st) {
    leaf_keys(&w);
    find_anchors(&w);
    st = collect_extras(&w);
  }
  if (!st) st = number_corners(&w);
  if (!st) st = place_edges(&w);
  if (!st) st = cells_of(&w);
  mx_free(w.extra);
  mx_free(w.side);
  mx_free(w.side_at);
  mx_free(w.side_mid);
  mx_free(w.side_ref);
  mx_free(w.side_low);
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
