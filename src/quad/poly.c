/* Polylines (quad.h): the checks that make a set of closed polylines a
 * domain, the grid that locates points against it, and its features.
 *
 * Decisions that must be exact (do two segments meet, on which side of a
 * segment a point lies) go through one orientation predicate, exact
 * (geom/orient2d.h).
 *
 * The grid: square cells, about 4 segments a cell, each segment listed in
 * every cell within `margin` of it (so rounding never loses one), ids
 * sorted within a cell (one radix sort of (cell, segment) keys): the same
 * grid for any thread count. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "base/common.h"
#include "geom/orient2d.h"
#include "quad/quad.h"
#include "base/scan.h"

static inline const double *vtx(const mx_poly *P, uint32_t v) { return P->xy + 2 * (size_t)v; }
static inline const double *from(const mx_poly *P, uint32_t s) {
  return vtx(P, P->seg[2 * (size_t)s]);
}
static inline const double *to(const mx_poly *P, uint32_t s) {
  return vtx(P, P->seg[2 * (size_t)s + 1]);
}
static inline long seg_line(const mx_poly *P, uint32_t s) { return P->line ? (long)P->line[s] : 0; }

/* "line N" for messages, or "segment N" for a poly made in memory. */
static const char *seg_name(const mx_poly *P, uint32_t s, char buf[40]) {
  if (P->line) snprintf(buf, 40, "line %u", P->line[s]);
  else snprintf(buf, 40, "segment %u", s);
  return buf;
}

/* ---- the grid ----------------------------------------------------------- */

/* The cell of x along an axis of n cells of side h from lo, clamped. */
static inline uint32_t cell_of(double x, double lo, double h, uint32_t n) {
  const double t = (x - lo) / h;
  if (!(t >= 0.0)) return 0;
  if (t >= (double)n) return n - 1;
  return (uint32_t)t;
}

/* The y-range of segment a-b over x in [xl, xr] (within the segment's). */
static void y_range(const double *a, const double *b, double xl, double xr, double *y0,
                    double *y1) {
  const double lo = mx_min(a[1], b[1]), hi = mx_max(a[1], b[1]);
  *y0 = lo;
  *y1 = hi;
  if (a[0] == b[0]) return;
  const double s = (b[1] - a[1]) / (b[0] - a[0]);
  const double u = a[1] + (xl - a[0]) * s, v = a[1] + (xr - a[0]) * s;
  if (!isfinite(u) || !isfinite(v)) return;
  *y0 = mx_max(lo, mx_min(u, v));
  *y1 = mx_min(hi, mx_max(u, v));
}

/* The cells within G->margin of segment a-b, column by column: their
 * number, and the keys (cell << 32 | s) written to out when not NULL.
 * Cells past the grid's sides are clamped onto its border cells. */
static size_t cover(const mx_poly_index *G, const double *a, const double *b, uint32_t s,
                    uint64_t *out) {
  const double m = G->margin, h = G->h;
  const double x0 = mx_min(a[0], b[0]), x1 = mx_max(a[0], b[0]);
  const uint32_t c0 = cell_of(x0 - m, G->lo[0], h, G->nx);
  const uint32_t c1 = cell_of(x1 + m, G->lo[0], h, G->nx);
  size_t k = 0;
  for (uint32_t c = c0; c <= c1; c++) {
    const double cl = c == 0 ? -INFINITY : G->lo[0] + c * h - m;
    const double cr = c + 1 == G->nx ? INFINITY : G->lo[0] + (c + 1) * h + m;
    double xl = mx_max(cl, x0), xr = mx_min(cr, x1), y0, y1;
    if (xl > xr) { /* a column touched only within rounding */
      const double t = xl;
      xl = xr;
      xr = t;
    }
    y_range(a, b, xl, xr, &y0, &y1);
    const uint32_t r0 = cell_of(y0 - m, G->lo[1], h, G->ny);
    const uint32_t r1 = cell_of(y1 + m, G->lo[1], h, G->ny);
    for (uint32_t r = r0; r <= r1; r++, k++)
      if (out) out[k] = ((uint64_t)r * G->nx + c) << 32 | s;
  }
  return k;
}

static uint32_t axis_cells(double w, double h) {
  const double k = ceil(w / h);
  return k >= 1.0 ? (k < 1e9 ? (uint32_t)k : 1000000000u) : 1u;
}

/* G->off from the sorted keys: the cells between two keys' cells start at
 * the second (parallel: each boundary fills its own range). */
static void fill_offsets(mx_poly_index *G, const uint64_t *keys, size_t total) {
  const uint64_t ncell = (uint64_t)G->nx * G->ny;
#pragma omp parallel for schedule(static)
  for (size_t i = 0; i <= total; i++) {
    const uint64_t c = i < total ? keys[i] >> 32 : ncell;
    const uint64_t p = i > 0 ? (keys[i - 1] >> 32) + 1 : 0;
    for (uint64_t k = p; k <= c; k++) G->off[k] = (uint32_t)i;
    if (i < total) G->ids[i] = (uint32_t)keys[i];
  }
}

/* The cell side of a grid over a W x H box for n segments: about n / 4
 * square cells, at most n / 4 along either side. */
static double grid_side(double W, double H, size_t n) {
  const double cells = n > 4 ? (double)n / 4.0 : 1.0;
  const double h = mx_max(sqrt(W) * sqrt(H / cells), mx_max(W, H) / cells);
  return h > 0.0 ? h : 1.0;
}

/* A grid over the box [lo, hi] listing the segments sel[0..n) (when sel is
 * NULL: 0..n-1), cells of side near sqrt(area / (n / 4)), margin
 * 1e-9 h + tol. */
static int grid_build(const mx_poly *P, const uint32_t *sel, size_t n, const double lo[2],
                      const double hi[2], double tol, mx_poly_index *G) {
  memset(G, 0, sizeof *G);
  G->P = P;
  const double W = hi[0] - lo[0], H = hi[1] - lo[1], h = grid_side(W, H, n);
  G->lo[0] = lo[0];
  G->lo[1] = lo[1];
  G->h = h;
  G->nx = axis_cells(W, h);
  G->ny = axis_cells(H, h);
  G->margin = 1e-9 * h + tol;
  const size_t ncell = (size_t)G->nx * G->ny;
  uint64_t *start = mx_alloc((n + 1) * sizeof *start);
  G->off = mx_alloc((ncell + 1) * sizeof *G->off);
  if (!start || !G->off) {
    mx_free(start);
    return MX_ENOMEM;
  }
#pragma omp parallel for schedule(static)
  for (size_t i = 0; i < n; i++) {
    const uint32_t s = sel ? sel[i] : (uint32_t)i;
    start[i] = cover(G, from(P, s), to(P, s), s, NULL);
  }
  const uint64_t total = mx_scan_u64(start, n);
  uint64_t *keys = total < UINT32_MAX ? mx_alloc((total + 1) * sizeof *keys) : NULL;
  G->ids = keys ? mx_alloc((total + 1) * sizeof *G->ids) : NULL;
  if (!keys || !G->ids) {
    if (total >= UINT32_MAX) mx_error(P->path, 0, "the segment grid is too large (%llu entries)",
                                      (unsigned long long)total);
    mx_free(start);
    mx_free(keys);
    return MX_ENOMEM;
  }
#pragma omp parallel for schedule(static)
  for (size_t i = 0; i < n; i++) {
    const uint32_t s = sel ? sel[i] : (uint32_t)i;
    cover(G, from(P, s), to(P, s), s, keys + start[i]);
  }
  mx_free(start);
  int st = mx_sort_u64(keys, NULL, total) == MX_OK ? MX_OK : MX_ENOMEM;
  if (st == MX_OK) fill_offsets(G, keys, total);
  mx_free(keys);
  return st;
}

/* The bounding box of the segments' ends (zero without segments). */
static void seg_bbox(const mx_poly *P, double lo[2], double hi[2]) {
  double x0 = INFINITY, y0 = INFINITY, x1 = -INFINITY, y1 = -INFINITY;
#pragma omp parallel for reduction(min : x0, y0) reduction(max : x1, y1) schedule(static)
  for (size_t i = 0; i < 2 * P->ns; i++) {
    const double *p = vtx(P, P->seg[i]);
    x0 = mx_min(x0, p[0]);
    y0 = mx_min(y0, p[1]);
    x1 = mx_max(x1, p[0]);
    y1 = mx_max(y1, p[1]);
  }
  if (P->ns == 0) x0 = y0 = x1 = y1 = 0.0;
  lo[0] = x0;
  lo[1] = y0;
  hi[0] = x1;
  hi[1] = y1;
}

int mx_poly_index_build(const mx_poly *P, mx_poly_index *I) {
  double lo[2], hi[2];
  seg_bbox(P, lo, hi);
  const double eps = 1e-12 * hypot(hi[0] - lo[0], hi[1] - lo[1]);
  const double big = mx_max(mx_max(fabs(lo[0]), fabs(lo[1])), mx_max(fabs(hi[0]), fabs(hi[1])));
  const double tol = 4.0 * eps + 1e-14 * big; /* above the rounding of coordinates */
  for (int d = 0; d < 2; d++) {
    lo[d] -= tol;
    hi[d] += tol;
  }
  const int st = grid_build(P, NULL, P->ns, lo, hi, tol, I);
  I->eps = eps;
  if (st != MX_OK) mx_poly_index_free(I);
  return st;
}

void mx_poly_index_free(mx_poly_index *I) {
  mx_free(I->off);
  mx_free(I->ids);
  memset(I, 0, sizeof *I);
}

/* ---- point queries ------------------------------------------------------ */

/* Squared distance from p to the segment a-b; its closest point in q. */
static double seg_dist2(const double *a, const double *b, const double *p, double q[2]) {
  const double u0 = b[0] - a[0], u1 = b[1] - a[1], w0 = p[0] - a[0], w1 = p[1] - a[1];
  const double l2 = u0 * u0 + u1 * u1;
  double t = l2 > 0 ? (u0 * w0 + u1 * w1) / l2 : 0.0;
  t = t < 0 ? 0 : t > 1 ? 1 : t;
  q[0] = a[0] + t * u0;
  q[1] = a[1] + t * u1;
  const double d0 = p[0] - q[0], d1 = p[1] - q[1];
  return d0 * d0 + d1 * d1;
}

/* Whether segment s, met in cell column c of p's row, crosses the ray from
 * p along +x (right) or -x: the half-open rule (one end above p, the other
 * not), the crossing on that side of p (exact), and counted in one cell
 * only, the one of the crossing (not behind p's). */
static int counts_here(const mx_poly_index *I, uint32_t s, const double *p, uint32_t cx,
                       uint32_t c, int right) {
  const double *a = from(I->P, s), *b = to(I->P, s);
  if ((a[1] > p[1]) == (b[1] > p[1])) return 0;
  const double *lo = a[1] < b[1] ? a : b, *hi = a[1] < b[1] ? b : a;
  const int side = mx_orient2d(lo, hi, p); /* > 0: the crossing is right of p */
  if (right ? side <= 0 : side >= 0) return 0;
  const double xc = a[0] + (p[1] - a[1]) * (b[0] - a[0]) / (b[1] - a[1]);
  uint32_t home = cell_of(xc, I->lo[0], I->h, I->nx);
  if (right ? home < cx : home > cx) home = cx;
  return home == c;
}

/* The parity of the crossings of a ray from p along x, walking p's row of
 * cells to its nearer end (for closed loops both rays have the parity of
 * p's depth); the segments of loop `skip` are left out when loop_of is
 * given. With on_check, a segment within I->eps of p gives 2. */
static int ray_parity(const mx_poly_index *I, const double p[2], const uint32_t *loop_of,
                      uint32_t skip, int on_check) {
  if (!(p[0] >= I->lo[0] && p[0] < I->lo[0] + I->nx * I->h && p[1] >= I->lo[1] &&
        p[1] < I->lo[1] + I->ny * I->h))
    return 0; /* farther than eps from the segments' box */
  const uint32_t cy = cell_of(p[1], I->lo[1], I->h, I->ny);
  const uint32_t cx = cell_of(p[0], I->lo[0], I->h, I->nx);
  const int right = I->nx - cx <= cx + 1;
  const uint32_t ncol = right ? I->nx - cx : cx + 1;
  const double eps2 = I->eps * I->eps;
  int parity = 0;
  for (uint32_t k = 0; k < ncol; k++) {
    const uint32_t c = right ? cx + k : cx - k;
    const size_t cell = (size_t)cy * I->nx + c;
    for (uint32_t j = I->off[cell]; j < I->off[cell + 1]; j++) {
      const uint32_t s = I->ids[j];
      double q[2];
      if (on_check && k == 0 && seg_dist2(from(I->P, s), to(I->P, s), p, q) <= eps2) return 2;
      if (loop_of && loop_of[s] == skip) continue;
      parity ^= counts_here(I, s, p, cx, c, right);
    }
  }
  return parity;
}

int mx_poly_inside(const mx_poly_index *I, const double p[2]) {
  if (!I->P || I->P->ns == 0) return 0;
  return ray_parity(I, p, NULL, 0, 1);
}

static double rect_dist2(const double p[2], double x0, double y0, double x1, double y1) {
  const double dx = mx_max(mx_max(x0 - p[0], p[0] - x1), 0.0);
  const double dy = mx_max(mx_max(y0 - p[1], p[1] - y1), 0.0);
  return dx * dx + dy * dy;
}

/* A lower bound of the squared distance from p to the grid outside the
 * visited cells [b0, b1] x [b2, b3] (none when b0 > b1); INFINITY when
 * those are the whole grid. */
static double unvisited_dist2(const mx_poly_index *I, const double p[2], int64_t b0,
                              int64_t b1, int64_t b2, int64_t b3) {
  const double h = I->h, gx0 = I->lo[0], gy0 = I->lo[1];
  const double gx1 = gx0 + I->nx * h, gy1 = gy0 + I->ny * h;
  double d;
  if (b0 > b1) {
    d = rect_dist2(p, gx0, gy0, gx1, gy1);
  } else {
    if (b0 <= 0 && b2 <= 0 && b1 >= (int64_t)I->nx - 1 && b3 >= (int64_t)I->ny - 1) return INFINITY;
    const double x0 = gx0 + (double)b0 * h, x1 = gx0 + (double)(b1 + 1) * h;
    const double y0 = gy0 + (double)b2 * h, y1 = gy0 + (double)(b3 + 1) * h;
    d = INFINITY;
    if (b0 > 0) d = mx_min(d, rect_dist2(p, gx0, gy0, x0, gy1));
    if (b1 < (int64_t)I->nx - 1) d = mx_min(d, rect_dist2(p, x1, gy0, gx1, gy1));
    if (b2 > 0) d = mx_min(d, rect_dist2(p, x0, gy0, x1, y0));
    if (b3 < (int64_t)I->ny - 1) d = mx_min(d, rect_dist2(p, x0, y1, x1, gy1));
  }
  const double r = mx_max(sqrt(d) - I->margin, 0.0); /* cell sides are rounded */
  return r * r;
}

typedef struct {
  uint32_t seg;
  double d2, q[2];
} nearest;

static void visit_cell(const mx_poly_index *I, int64_t i, int64_t j, const double p[2],
                       nearest *n) {
  if (i < 0 || j < 0 || i >= (int64_t)I->nx || j >= (int64_t)I->ny) return;
  const size_t cell = (size_t)j * I->nx + (size_t)i;
  for (uint32_t k = I->off[cell]; k < I->off[cell + 1]; k++) {
    const uint32_t s = I->ids[k];
    double q[2];
    const double d = seg_dist2(from(I->P, s), to(I->P, s), p, q);
    if (d < n->d2 || (d == n->d2 && s < n->seg)) { /* ties: the lowest id */
      n->seg = s;
      n->d2 = d;
      n->q[0] = q[0];
      n->q[1] = q[1];
    }
  }
}

static void visit_ring(const mx_poly_index *I, int64_t cx, int64_t cy, int64_t r,
                       const double p[2], nearest *n) {
  if (r == 0) {
    visit_cell(I, cx, cy, p, n);
    return;
  }
  for (int64_t i = cx - r; i <= cx + r; i++) {
    visit_cell(I, i, cy - r, p, n);
    visit_cell(I, i, cy + r, p, n);
  }
  for (int64_t j = cy - r + 1; j <= cy + r - 1; j++) {
    visit_cell(I, cx - r, j, p, n);
    visit_cell(I, cx + r, j, p, n);
  }
}

uint32_t mx_poly_closest(const mx_poly_index *I, const double p[2], double rmax, double q[2],
                         double *d2) {
  nearest n = {UINT32_MAX, rmax * rmax, {0, 0}};
  if (!I->P || I->P->ns == 0 || !(rmax >= 0.0)) n.seg = UINT32_MAX, n.d2 = -1.0;
  const int64_t cx = cell_of(p[0], I->lo[0], I->h, I->nx);
  const int64_t cy = cell_of(p[1], I->lo[1], I->h, I->ny);
  for (int64_t r = 0; n.d2 >= 0.0; r++) {
    const double lb = unvisited_dist2(I, p, cx - r + 1, cx + r - 1, cy - r + 1, cy + r - 1);
    if (lb == INFINITY || lb > n.d2) break;
    visit_ring(I, cx, cy, r, p, &n);
  }
  if (n.seg == UINT32_MAX) {
    *d2 = INFINITY;
    return UINT32_MAX;
  }
  q[0] = n.q[0];
  q[1] = n.q[1];
  *d2 = n.d2;
  return n.seg;
}

/* ---- segments that meet ------------------------------------------------- */

enum { MEET_NONE, MEET_CROSS, MEET_TOUCH, MEET_OVERLAP, MEET_SAME };

static inline int sgn(double x) { return (x > 0) - (x < 0); }

/* Collinear segments a-b and c-d (a != b): apart, touching or overlapping. */
static int collinear_meet(const double *a, const double *b, const double *c, const double *d) {
  const int k = a[0] != b[0] ? 0 : 1;
  const double s0 = mx_min(a[k], b[k]), s1 = mx_max(a[k], b[k]);
  const double t0 = mx_min(c[k], d[k]), t1 = mx_max(c[k], d[k]);
  if (s1 < t0 || t1 < s0) return MEET_NONE;
  return s1 == t0 || t1 == s0 ? MEET_TOUCH : MEET_OVERLAP;
}

/* Segments sharing vertex o, their other ends p and q: they meet elsewhere
 * only when one folds back onto the other. */
static int adjacent_meet(const double *o, const double *p, const double *q) {
  if (mx_orient2d(o, p, q) != 0) return MEET_NONE;
  const int same = sgn(p[0] - o[0]) == sgn(q[0] - o[0]) && sgn(p[1] - o[1]) == sgn(q[1] - o[1]);
  return same ? MEET_OVERLAP : MEET_NONE;
}

/* How segments s and t meet, beyond the vertex they may share. */
static int meet(const mx_poly *P, uint32_t s, uint32_t t) {
  const uint32_t *e = P->seg + 2 * (size_t)s, *f = P->seg + 2 * (size_t)t;
  const int shared = (e[0] == f[0]) + (e[0] == f[1]) + (e[1] == f[0]) + (e[1] == f[1]);
  if (shared >= 2) return MEET_SAME;
  if (shared == 1) {
    const uint32_t v = e[0] == f[0] || e[0] == f[1] ? e[0] : e[1];
    return adjacent_meet(vtx(P, v), vtx(P, e[0] == v ? e[1] : e[0]),
                         vtx(P, f[0] == v ? f[1] : f[0]));
  }
  const double *a = vtx(P, e[0]), *b = vtx(P, e[1]), *c = vtx(P, f[0]), *d = vtx(P, f[1]);
  for (int k = 0; k < 2; k++)
    if (mx_max(a[k], b[k]) < mx_min(c[k], d[k]) || mx_max(c[k], d[k]) < mx_min(a[k], b[k]))
      return MEET_NONE;
  const int o1 = mx_orient2d(a, b, c), o2 = mx_orient2d(a, b, d), o3 = mx_orient2d(c, d, a), o4 = mx_orient2d(c, d, b);
  if (o1 * o2 > 0 || o3 * o4 > 0) return MEET_NONE;
  if (!o1 && !o2 && !o3 && !o4) return collinear_meet(a, b, c, d);
  return o1 * o2 < 0 && o3 * o4 < 0 ? MEET_CROSS : MEET_TOUCH;
}

static inline uint64_t pair_key(uint32_t s, uint32_t t) {
  return s < t ? (uint64_t)s << 32 | t : (uint64_t)t << 32 | s;
}

/* The lowest pair (key) of ids[0..n) that meet, if below best: all pairs. */
static uint64_t all_pairs(const mx_poly *P, const uint32_t *ids, size_t n, uint64_t best) {
  for (size_t i = 0; i + 1 < n; i++)
    for (size_t j = i + 1; j < n; j++) {
      const uint64_t key = pair_key(ids[i], ids[j]);
      if (key < best && meet(P, ids[i], ids[j]) != MEET_NONE) best = key;
    }
  return best;
}

typedef struct {
  double lo, hi;
  uint32_t s;
} span;

static int span_cmp(const void *a, const void *b) {
  const span *x = a, *y = b;
  if (x->lo != y->lo) return x->lo < y->lo ? -1 : 1;
  return (x->s > y->s) - (x->s < y->s);
}

/* The same by a sweep along the axis where the segments' extents are
 * shorter: only pairs whose extents overlap there are tested (a stack of
 * long parallel segments costs n log n, not n^2). */
static uint64_t brute_pairs(const mx_poly *P, const uint32_t *ids, size_t n, uint64_t best,
                            int *status) {
  if (n <= 16) return all_pairs(P, ids, n, best);
  span *v = mx_alloc(n * sizeof *v);
  if (!v) {
    *status = MX_ENOMEM;
    return best;
  }
  double len[2] = {0, 0};
  for (size_t i = 0; i < n; i++)
    for (int d = 0; d < 2; d++) len[d] += fabs(to(P, ids[i])[d] - from(P, ids[i])[d]);
  const int ax = len[1] < len[0];
  for (size_t i = 0; i < n; i++) {
    const double a = from(P, ids[i])[ax], b = to(P, ids[i])[ax];
    v[i] = (span){mx_min(a, b), mx_max(a, b), ids[i]};
  }
  qsort(v, n, sizeof *v, span_cmp);
  for (size_t i = 0; i + 1 < n; i++)
    for (size_t j = i + 1; j < n && v[j].lo <= v[i].hi; j++) {
      const uint64_t key = pair_key(v[i].s, v[j].s);
      if (key < best && meet(P, v[i].s, v[j].s) != MEET_NONE) best = key;
    }
  mx_free(v);
  return best;
}

/* The part of the box [lo, hi] that the segments ids[0..n) cover (in
 * place): a meeting point lies in both segments' boxes, and a cluster of
 * small segments gets a grid of its own size. */
static void fit_box(const mx_poly *P, const uint32_t *ids, size_t n, double lo[2], double hi[2]) {
  double a[2] = {INFINITY, INFINITY}, b[2] = {-INFINITY, -INFINITY};
  for (size_t i = 0; i < n; i++)
    for (int d = 0; d < 2; d++) {
      a[d] = mx_min(a[d], mx_min(from(P, ids[i])[d], to(P, ids[i])[d]));
      b[d] = mx_max(b[d], mx_max(from(P, ids[i])[d], to(P, ids[i])[d]));
    }
  for (int d = 0; d < 2; d++) {
    lo[d] = mx_max(lo[d], a[d]);
    hi[d] = mx_max(lo[d], mx_min(hi[d], b[d]));
  }
}

/* The same within the box [lo, hi], through a finer grid when the list is
 * long and the grid separates it (every pair meeting in the box shares the
 * finer cell where it meets). */
static uint64_t box_pairs(const mx_poly *P, const uint32_t *ids, size_t n, const double box_lo[2],
                          const double box_hi[2], double tol, int depth, uint64_t best,
                          int *status) {
  if (n <= 32 || depth >= 4) return brute_pairs(P, ids, n, best, status);
  double lo[2] = {box_lo[0], box_lo[1]}, hi[2] = {box_hi[0], box_hi[1]};
  fit_box(P, ids, n, lo, hi);
  const double W = hi[0] - lo[0], H = hi[1] - lo[1], h = grid_side(W, H, n);
  double cells = 0; /* about the cells the segments would fill */
  for (size_t i = 0; i < n; i++)
    cells += (mx_min(fabs(to(P, ids[i])[0] - from(P, ids[i])[0]), W) +
              mx_min(fabs(to(P, ids[i])[1] - from(P, ids[i])[1]), H)) / h + 1.0;
  if (!(cells <= 3.0 * (double)n)) return brute_pairs(P, ids, n, best, status);
  mx_poly_index G;
  const int st = grid_build(P, ids, n, lo, hi, tol, &G);
  if (st != MX_OK) {
    *status = st;
    mx_poly_index_free(&G);
    return best;
  }
  const size_t ncell = (size_t)G.nx * G.ny;
  size_t most = 0;
  for (size_t c = 0; c < ncell; c++)
    if (G.off[c + 1] - G.off[c] > most) most = G.off[c + 1] - G.off[c];
  /* one cell keeps most, or long segments fill many cells: the sweep does better */
  if (4 * most > 3 * n || G.off[ncell] > 3 * n) {
    mx_poly_index_free(&G);
    return brute_pairs(P, ids, n, best, status);
  }
  for (size_t c = 0; c < ncell; c++) {
    const double sl[2] = {G.lo[0] + (double)(c % G.nx) * G.h, G.lo[1] + (double)(c / G.nx) * G.h};
    const double sh[2] = {sl[0] + G.h, sl[1] + G.h};
    best = box_pairs(P, G.ids + G.off[c], G.off[c + 1] - G.off[c], sl, sh, tol, depth + 1, best,
                     status);
  }
  mx_poly_index_free(&G);
  return best;
}

static int report_meeting(const mx_poly *P, uint64_t key) {
  const uint32_t s = (uint32_t)(key >> 32), t = (uint32_t)key;
  static const char *what[] = {"", "cross", "touch", "overlap", "join the same two vertices"};
  char a[40], b[40];
  mx_error(P->path, seg_line(P, s), "the segments of %s and %s %s: a domain's polylines may "
           "meet only at the vertices they share", seg_name(P, s, a), seg_name(P, t, b),
           what[meet(P, s, t)]);
  return MX_EINPUT;
}

/* No two segments cross, touch, overlap or repeat: every cell of the index
 * tested (in parallel); the lowest meeting pair is reported, whatever the
 * thread count. */
static int check_meetings(const mx_poly *P, const mx_poly_index *I) {
  uint64_t best = UINT64_MAX;
  int status = MX_OK;
  const size_t ncell = (size_t)I->nx * I->ny;
#pragma omp parallel
  {
    uint64_t mine = UINT64_MAX;
    int st = MX_OK;
#pragma omp for schedule(dynamic, 64)
    for (size_t c = 0; c < ncell; c++) {
      const double lo[2] = {I->lo[0] + (double)(c % I->nx) * I->h,
                            I->lo[1] + (double)(c / I->nx) * I->h};
      const double hi[2] = {lo[0] + I->h, lo[1] + I->h};
      mine = box_pairs(P, I->ids + I->off[c], I->off[c + 1] - I->off[c], lo, hi, I->margin, 0,
                       mine, &st);
    }
#pragma omp critical(mx_poly_meetings)
    {
      if (mine < best) best = mine;
      if (st != MX_OK) status = st;
    }
  }
  if (status != MX_OK) return status;
  return best == UINT64_MAX ? MX_OK : report_meeting(P, best);
}

/* ---- closed loops ------------------------------------------------------- */

/* Coordinates this large would overflow the exact predicates' products. */
#define COORD_MAX 1e150

static int seg_bad(const mx_poly *P, size_t s) {
  const uint32_t *e = P->seg + 2 * s;
  if (e[0] >= P->nv || e[1] >= P->nv || e[0] == e[1]) return 1;
  const double *a = vtx(P, e[0]), *b = vtx(P, e[1]);
  for (int d = 0; d < 2; d++)
    if (!(fabs(a[d]) <= COORD_MAX && fabs(b[d]) <= COORD_MAX)) return 1;
  return a[0] == b[0] && a[1] == b[1];
}

/* Indices in range, coordinates in range, no segment of zero length (the
 * lowest bad one reported). */
static int check_lengths(const mx_poly *P) {
  size_t bad = SIZE_MAX;
#pragma omp parallel for reduction(min : bad) schedule(static)
  for (size_t s = 0; s < P->ns; s++)
    if (seg_bad(P, s)) bad = s < bad ? s : bad;
  if (bad == SIZE_MAX) return MX_OK;
  const uint32_t *e = P->seg + 2 * bad;
  const long line = seg_line(P, (uint32_t)bad);
  if (e[0] >= P->nv || e[1] >= P->nv) {
    mx_error(P->path, line, "segment %zu: vertex index out of range", bad);
  } else if (e[0] != e[1] && (vtx(P, e[0])[0] != vtx(P, e[1])[0] ||
                              vtx(P, e[0])[1] != vtx(P, e[1])[1])) {
    mx_error(P->path, line, "a coordinate of this segment is beyond %g in magnitude: not "
             "supported", COORD_MAX);
  } else {
    mx_error(P->path, line, "zero-length segment at (%g, %g)", vtx(P, e[0])[0], vtx(P, e[0])[1]);
  }
  return MX_EINPUT;
}

/* deg[v]: the segments using vertex v; inc[2v], inc[2v+1]: two of them. */
static void incidences(const mx_poly *P, uint32_t *deg, uint32_t *inc) {
#pragma omp parallel for schedule(static)
  for (size_t i = 0; i < 2 * P->ns; i++) {
    const uint32_t v = P->seg[i];
    uint32_t slot;
#pragma omp atomic capture
    slot = deg[v]++;
    if (slot < 2) inc[2 * (size_t)v + slot] = (uint32_t)(i / 2);
  }
}

/* Every used vertex is used by exactly two segments (lowest bad one reported). */
static int check_degrees(const mx_poly *P, const uint32_t *deg, const uint32_t *inc) {
  size_t bad = SIZE_MAX;
#pragma omp parallel for reduction(min : bad) schedule(static)
  for (size_t v = 0; v < P->nv; v++)
    if (deg[v] != 0 && deg[v] != 2 && v < bad) bad = v;
  if (bad == SIZE_MAX) return MX_OK;
  const double *x = vtx(P, (uint32_t)bad);
  char a[40], b[40], c[40];
  if (deg[bad] == 1) {
    mx_error(P->path, seg_line(P, inc[2 * bad]),
             "open polyline: no other segment than this one ends at (%g, %g) (a domain's "
             "polylines must be closed)", x[0], x[1]);
    return MX_EINPUT;
  }
  uint32_t first[3], k = 0; /* the first three, in input order */
  for (size_t i = 0; i < 2 * P->ns && k < 3; i++)
    if (P->seg[i] == bad) first[k++] = (uint32_t)(i / 2);
  mx_error(P->path, seg_line(P, first[0]),
           "%u segments meet at (%g, %g) (%s, %s, %s...): a domain's polylines must be "
           "simple closed loops", deg[bad], x[0], x[1], seg_name(P, first[0], a),
           seg_name(P, first[1], b), seg_name(P, first[2], c));
  return MX_EINPUT;
}

/* Walks the loops (a sequential walk, O(ns)): loop_of[s], the number of
 * loops, each segment turned to follow its loop's first segment; returns
 * how many were turned. */
static size_t walk_loops(mx_poly *P, const uint32_t *inc, uint32_t *loop_of, size_t *nloops) {
  size_t turned = 0, L = 0;
  for (size_t s0 = 0; s0 < P->ns; s0++) {
    if (loop_of[s0] != UINT32_MAX) continue;
    uint32_t s = (uint32_t)s0;
    do {
      loop_of[s] = (uint32_t)L;
      const uint32_t v = P->seg[2 * (size_t)s + 1];
      const uint32_t t = inc[2 * (size_t)v] == s ? inc[2 * (size_t)v + 1] : inc[2 * (size_t)v];
      if (P->seg[2 * (size_t)t] != v) {
        P->seg[2 * (size_t)t + 1] = P->seg[2 * (size_t)t];
        P->seg[2 * (size_t)t] = v;
        turned++;
      }
      s = t;
    } while (s != s0);
    L++;
  }
  *nloops = L;
  return turned;
}

/* ---- orientation -------------------------------------------------------- */

static inline int lower_left(const double *a, const double *b) {
  return a[0] < b[0] || (a[0] == b[0] && a[1] < b[1]);
}

/* Per loop, the segment leaving its lowest-left vertex (one pass). */
static void loop_corners(const mx_poly *P, const uint32_t *loop_of, uint32_t *low, size_t nl) {
  for (size_t L = 0; L < nl; L++) low[L] = UINT32_MAX;
  for (size_t s = 0; s < P->ns; s++) {
    uint32_t *l = &low[loop_of[s]];
    if (*l == UINT32_MAX || lower_left(from(P, (uint32_t)s), from(P, *l))) *l = (uint32_t)s;
  }
}

/* Turns the loops whose orientation disagrees with their nesting: at the
 * lowest-left vertex of a simple loop the turn gives its orientation
 * (exact); the crossings of the ray from there with the other loops give
 * the parity of its depth. One warning for all the turning done. */
static int orient_loops(mx_poly *P, const mx_poly_index *I, const uint32_t *inc,
                        const uint32_t *loop_of, size_t nl, size_t turned) {
  uint32_t *low = mx_alloc(nl * sizeof *low);
  uint8_t *flip = mx_alloc(nl);
  if (!low || !flip) {
    mx_free(low);
    mx_free(flip);
    return MX_ENOMEM;
  }
  loop_corners(P, loop_of, low, nl);
  size_t nflip = 0;
#pragma omp parallel for reduction(+ : nflip) schedule(dynamic, 16)
  for (size_t L = 0; L < nl; L++) {
    const uint32_t s = low[L], v = P->seg[2 * (size_t)s];
    const uint32_t in = inc[2 * (size_t)v] == s ? inc[2 * (size_t)v + 1] : inc[2 * (size_t)v];
    const int ccw = mx_orient2d(from(P, in), vtx(P, v), to(P, s)) > 0;
    const int hole = ray_parity(I, vtx(P, v), loop_of, (uint32_t)L, 0);
    flip[L] = (uint8_t)(ccw == hole);
    nflip += flip[L];
  }
  uint32_t first = UINT32_MAX;
  for (size_t L = 0; L < nl && first == UINT32_MAX; L++)
    if (flip[L]) first = low[L];
#pragma omp parallel for schedule(static)
  for (size_t s = 0; s < P->ns; s++) {
    if (!flip[loop_of[s]]) continue;
    const uint32_t t = P->seg[2 * s];
    P->seg[2 * s] = P->seg[2 * s + 1];
    P->seg[2 * s + 1] = t;
  }
  char name[40];
  if (nflip)
    mx_warning(P->path, 0, "%zu of %zu loop(s) turned around (the first: the one of %s), and %zu "
               "segment(s) turned to follow their loop: outer boundaries go counter-clockwise, "
               "holes clockwise", nflip, nl, seg_name(P, first, name), turned);
  else if (turned)
    mx_warning(P->path, 0, "%zu segment(s) turned to follow their loop", turned);
  mx_free(low);
  mx_free(flip);
  return MX_OK;
}

/* ---- the domain check --------------------------------------------------- */

static int check_loops(mx_poly *P, uint32_t *deg, uint32_t *inc, uint32_t *loop_of) {
  incidences(P, deg, inc);
  MX_CHECK(check_degrees(P, deg, inc));
  size_t nl;
  const size_t turned = walk_loops(P, inc, loop_of, &nl);
  mx_poly_index I;
  MX_CHECK(mx_poly_index_build(P, &I));
  int st = check_meetings(P, &I);
  if (st == MX_OK) st = orient_loops(P, &I, inc, loop_of, nl, turned);
  mx_poly_index_free(&I);
  if (st == MX_OK) P->nloops = nl;
  return st;
}

int mx_poly_check_domain(mx_poly *P) {
  P->nloops = 0;
  if (P->ns == 0 || P->ns >= UINT32_MAX || P->nv >= UINT32_MAX) {
    mx_error(P->path, 0, "%s", P->ns == 0 ? "no segments: nothing to mesh" : "too many segments");
    return MX_EINPUT;
  }
  MX_CHECK(check_lengths(P));
  uint32_t *deg = mx_calloc(P->nv * sizeof *deg);
  uint32_t *inc = mx_alloc(2 * P->nv * sizeof *inc);
  uint32_t *loop_of = mx_alloc(P->ns * sizeof *loop_of);
  int st = MX_ENOMEM;
  if (deg && inc && loop_of) {
    memset(loop_of, 0xff, P->ns * sizeof *loop_of);
    st = check_loops(P, deg, inc, loop_of);
  }
  mx_free(deg);
  mx_free(inc);
  mx_free(loop_of);
  return st;
}

/* ---- features (section 4.1) --------------------------------------------- */

/* The angle between the segments v-a and v-b is 175 degrees or less (the
 * turn is outside ]175, 185[ on either side). */
static int sharp(const double *v, const double *a, const double *b) {
  const double u0 = a[0] - v[0], u1 = a[1] - v[1], w0 = b[0] - v[0], w1 = b[1] - v[1];
  const double deg = atan2(fabs(u0 * w1 - u1 * w0), u0 * w0 + u1 * w1) * (180.0 / M_PI);
  return !(deg > 175.0);
}

/* A vertex with two segments is a feature when sharp; with more (a drawing's
 * junction) always; the ends of an open polyline never. */
int mx_poly_features(const mx_poly *P, uint32_t **out, size_t *n) {
  *out = NULL;
  *n = 0;
  uint32_t *deg = mx_calloc(P->nv * sizeof *deg), *nb = mx_alloc(2 * P->nv * sizeof *nb);
  uint8_t *flag = mx_alloc(P->nv);
  int st = deg && nb && flag ? MX_OK : MX_ENOMEM;
  if (st == MX_OK) {
#pragma omp parallel for schedule(static)
    for (size_t i = 0; i < 2 * P->ns; i++) {
      const uint32_t v = P->seg[i];
      uint32_t slot;
#pragma omp atomic capture
      slot = deg[v]++;
      if (slot < 2) nb[2 * (size_t)v + slot] = P->seg[i ^ 1]; /* the other end */
    }
#pragma omp parallel for schedule(static)
    for (size_t v = 0; v < P->nv; v++)
      flag[v] = deg[v] > 2 || (deg[v] == 2 && sharp(vtx(P, (uint32_t)v), vtx(P, nb[2 * v]),
                                                    vtx(P, nb[2 * v + 1])));
    size_t k = 0;
    for (size_t v = 0; v < P->nv; v++) k += flag[v];
    *out = mx_alloc((k ? k : 1) * sizeof **out);
    if (!*out) st = MX_ENOMEM;
    for (size_t v = 0; *out && v < P->nv; v++) /* ascending ids */
      if (flag[v]) (*out)[(*n)++] = (uint32_t)v;
  }
  mx_free(deg);
  mx_free(nb);
  mx_free(flag);
  return st;
}
