/* Independent checks of a 2D mixed mesh (quad.h: mx_qmesh_check). Nothing
 * here calls the mesher's own passes: the edges come from the cell sides
 * gathered at their lower node (counted per chunk of cells and block of
 * node ids, each chunk writing into its own ranges, a round of blocks at a
 * time in a fixed room, then sorted per node within a block), the hanging
 * nodes from a grid over the used nodes (cells of about 1.5 typical edges,
 * crowded ones split further) that each edge looks into (their float
 * positions skip the nodes off its box, the exact test decides on the
 * others), orientation from each corner's cross product.
 *
 *   bad_edges         edges used by more than two cells, by two in the same
 *                     direction, or with both ends on one node
 *   hanging           nodes of some cell lying on an edge they are not an
 *                     end of: strictly inside it (a T-junction) or on one
 *                     of its ends (a duplicated node): non-conforming
 *   inverted          cells with a corner whose cross product of its two
 *                     edges (next minus this, previous minus this) is not
 *                     positive: clockwise, degenerate or non-convex
 *   off_boundary      with a domain: nodes of boundary edges (used by one
 *                     cell) farther than tol x the domain's diameter from
 *                     its polylines
 *   missing_features  with a domain: features (mx_poly_features) with no
 *                     mesh node within that distance
 *   edges, euler      the distinct edges (boundary_edges: used by one cell)
 *                     and V - E + F over the nodes used: for a valid mesh,
 *                     its components minus its holes; domain_euler, the
 *                     domain's outer loops minus its holes
 *   area, domain_area the cells' total signed area; the polylines' signed
 *                     area (the domain is checked, so oriented: outer loops
 *                     counter-clockwise, holes clockwise, and the signed sum
 *                     is the outer areas minus the holes'), area_error their
 *                     relative difference
 *
 * Every pass is parallel over cells, nodes or blocks of nodes; the counts
 * do not depend on the thread count (lists are sorted, flags only set), nor
 * the areas (summed in fixed blocks). */
#include <math.h>
#include <omp.h>
#include <stdint.h>
#include <string.h>

#include "base/common.h"
#include "quad/quad.h"
#include "base/scan.h"

/* The next and previous corner of a cell of nv corners (no division). */
static inline int nxt(int k, int nv) { return k + 1 == nv ? 0 : k + 1; }
static inline int prv(int k, int nv) { return k == 0 ? nv - 1 : k - 1; }

enum { AREA_BLOCK = 4096, PAR_MIN = 16384 }; /* fewer items: one thread */
#define HANG_EPS 1e-10 /* relative to the edge's length */
#define NODE_BLOCK 12  /* log2 of the node ids per block of the side buckets */
#define MAX_CHUNKS 64

typedef struct {
  size_t ne;        /* distinct edges */
  uint8_t *used;    /* per node: a corner of some cell */
  uint8_t *bnode;   /* per node: an end of a boundary edge */
  double lo[2], h, ih; /* the grid over the used nodes: origin, side, 1 / side */
  uint32_t gx, gy;
  uint32_t *goff;   /* per grid cell: the end of its list in gids (its start: the cell before's) */
  uint32_t *gids;
  float *gxy;       /* per entry of gids: its node's position from lo, rounded to float */
  double fm;        /* more than twice the rounding of those */
  size_t nsub;      /* grid cells with more than DENSE nodes, split in k x k */
  struct subgrid *sub;
  uint32_t *gsub;   /* per grid cell: its subgrid in sub (when there are any) */
  uint32_t *soff;   /* per sub-cell of those: the start of its entries (k k + 1 each) */
} qc_ctx;

/* A grid cell split further (a graded mesh's fine part in a cell sized
 * for the whole): its sub-cells' entries are consecutive, in order. */
#define DENSE 16
struct subgrid {
  uint32_t g, k, off; /* the cell, sub-cells per side, its offsets in soff */
  float x0, y0, inv;  /* the cell's corner from lo (float), k / its side */
};

static inline int qnv(const mx_qmesh *M, size_t c) { return M->type[c] == MX_QQUAD ? 4 : 3; }
static inline uint32_t beg(const uint32_t *off, size_t a) { return a ? off[a - 1] : 0; }
static inline void mark(uint8_t *flag, uint32_t i) { __atomic_store_n(&flag[i], 1, __ATOMIC_RELAXED); }

static void ctx_free(qc_ctx *x) {
  mx_free(x->used), mx_free(x->bnode), mx_free(x->goff), mx_free(x->gids), mx_free(x->gxy);
  mx_free(x->sub), mx_free(x->soff), mx_free(x->gsub);
  memset(x, 0, sizeof *x);
}

/* Types in range, node indices below nnodes, indices that fit the lists. */
static int structure_ok(const mx_qmesh *M) {
  if ((M->nnodes && !M->xy) || (M->ncells && (!M->type || !M->conn))) {
    mx_error(NULL, 0, "mesh check: incomplete 2D mesh");
    return MX_EINTERNAL;
  }
  if (M->ncells >= (size_t)1 << 30 || M->nnodes >= (size_t)1 << 31) {
    mx_error(NULL, 0, "mesh check: %zu cells, %zu nodes: too many for the checker", M->ncells,
             M->nnodes);
    return MX_EINPUT;
  }
  const size_t bad = mx_qmesh_bad_cell(M);
  if (bad == M->ncells) return MX_OK;
  mx_error(NULL, 0, "mesh check: cell %zu has a bad type or node index", bad);
  return MX_EINTERNAL;
}

/* The nodes some cell uses. */
static int mark_used(const mx_qmesh *M, qc_ctx *x) {
  x->used = mx_calloc(M->nnodes + 1);
  x->bnode = mx_calloc(M->nnodes + 1);
  if (!x->used || !x->bnode) return MX_ENOMEM;
#pragma omp parallel for schedule(static) if (M->ncells > PAR_MIN)
  for (size_t c = 0; c < M->ncells; c++)
    for (int k = 0; k < qnv(M, c); k++) mark(x->used, M->conn[4 * c + k]);
  return MX_OK;
}

/* V - E + F over the nodes some cell uses. */
static long euler(const mx_qmesh *M, const qc_ctx *x) {
  size_t nv = 0;
#pragma omp parallel for reduction(+ : nv) schedule(static) if (M->nnodes > PAR_MIN)
  for (size_t i = 0; i < M->nnodes; i++) nv += x->used[i];
  return (long)nv - (long)x->ne + (long)M->ncells;
}

/* ---- the grid over the nodes --------------------------------------------- */

static inline uint32_t grid_x(const qc_ctx *x, double px) {
  const double f = floor((px - x->lo[0]) * x->ih);
  return f <= 0 ? 0 : f >= (double)(x->gx - 1) ? x->gx - 1 : (uint32_t)f;
}
static inline uint32_t grid_y(const qc_ctx *x, double py) {
  const double f = floor((py - x->lo[1]) * x->ih);
  return f <= 0 ? 0 : f >= (double)(x->gy - 1) ? x->gy - 1 : (uint32_t)f;
}

/* The median length of the first side of up to 4095 cells spread over the
 * mesh (a typical edge where most edges are). */
static double typical_edge(const mx_qmesh *M) {
  enum { NS = 4095 };
  double l[NS];
  size_t k = 0;
  const size_t step = M->ncells / NS + 1;
  for (size_t c = 0; c < M->ncells && k < NS; c += step) {
    const double *a = M->xy + 2 * (size_t)M->conn[4 * c], *b = M->xy + 2 * (size_t)M->conn[4 * c + 1];
    l[k++] = hypot(b[0] - a[0], b[1] - a[1]);
  }
  if (!k) return 0.0;
  /* quickselect of the middle */
  size_t lo = 0, hi = k - 1, mid = k / 2;
  while (lo < hi) {
    const double piv = l[(lo + hi) / 2];
    size_t i = lo, j = hi;
    while (i <= j) {
      while (l[i] < piv) i++;
      while (l[j] > piv) j--;
      if (i <= j) {
        const double t = l[i];
        l[i] = l[j], l[j] = t;
        i++;
        if (j == 0) break;
        j--;
      }
    }
    if (mid <= j) hi = j;
    else if (mid >= i) lo = i;
    else break;
  }
  return l[mid];
}

/* Cells of 1.5 typical edges (a node or two a cell where most edges are,
 * whatever the grading), no more than about 4 cells per used node.
 * Returns the box's diagonal. */
static double grid_size(const mx_qmesh *M, qc_ctx *x) {
  double x0 = INFINITY, y0 = INFINITY, x1 = -INFINITY, y1 = -INFINITY;
  size_t nu = 0;
#pragma omp parallel for reduction(min : x0, y0) reduction(max : x1, y1) reduction(+ : nu) \
    schedule(static) if (M->nnodes > PAR_MIN)
  for (size_t i = 0; i < M->nnodes; i++) {
    x0 = mx_min(x0, M->xy[2 * i]), x1 = mx_max(x1, M->xy[2 * i]);
    y0 = mx_min(y0, M->xy[2 * i + 1]), y1 = mx_max(y1, M->xy[2 * i + 1]);
    nu += x->used[i];
  }
  if (M->nnodes == 0) x0 = y0 = x1 = y1 = 0.0;
  const double w = x1 - x0, t = y1 - y0, diag = sqrt(w * w + t * t);
  const double n = (double)(nu ? nu : 1);
  x->lo[0] = x0, x->lo[1] = y0;
  /* float positions from lo round by at most 2^-24 of the box's side */
  x->fm = ldexp(mx_max(w, t), -21);
  x->h = w * t > 0 ? mx_max(1.5 * typical_edge(M), 0.5 * sqrt(w * t / n))
                   : diag > 0 ? diag / n : 1.0;
  for (;;) {
    const double gx = floor(w / x->h) + 1, gy = floor(t / x->h) + 1;
    if (gx * gy <= 4.0 * n + 16.0) {
      x->gx = (uint32_t)gx, x->gy = (uint32_t)gy;
      x->ih = 1.0 / x->h;
      return diag;
    }
    x->h *= 1.5;
  }
}

/* Grid cell (i, j)'s place: tiles of 8 x 8 cells, row by row, the cells
 * of a tile row by row (neighbouring cells are near each other in memory,
 * as the nodes the passes go through in their order are in space). */
static inline size_t cell_at(const qc_ctx *x, uint32_t i, uint32_t j) {
  const size_t ntx = ((size_t)x->gx + 7) >> 3;
  return (((size_t)(j >> 3) * ntx + (i >> 3)) << 6) | (size_t)(j & 7) << 3 | (i & 7);
}
static inline size_t grid_cells(const qc_ctx *x) {
  return (((size_t)x->gx + 7) >> 3) * (((size_t)x->gy + 7) >> 3) << 6;
}

static inline size_t node_cell(const qc_ctx *x, const double *p) {
  return cell_at(x, grid_x(x, p[0]), grid_y(x, p[1]));
}

/* The used nodes of each grid cell (goff as off). */
static int grid_build(const mx_qmesh *M, qc_ctx *x) {
  const size_t ng = grid_cells(x), n = M->nnodes;
  uint32_t *goff = x->goff = mx_calloc((ng + 1) * sizeof *goff);
  if (!goff) return MX_ENOMEM;
#pragma omp parallel for schedule(static) if (n > PAR_MIN)
  for (size_t i = 0; i < n; i++)
    if (x->used[i]) __atomic_fetch_add(&goff[node_cell(x, M->xy + 2 * i)], 1, __ATOMIC_RELAXED);
  const uint64_t total = mx_scan_u32(goff, ng);
  x->gids = mx_alloc((total + 1) * sizeof *x->gids);
  x->gxy = mx_alloc((2 * total + 1) * sizeof *x->gxy);
  if (!x->gids || !x->gxy) return MX_ENOMEM;
#pragma omp parallel for schedule(static) if (n > PAR_MIN)
  for (size_t i = 0; i < n; i++)
    if (x->used[i]) {
      const double *p = M->xy + 2 * i;
      const uint32_t k = __atomic_fetch_add(&goff[node_cell(x, p)], 1, __ATOMIC_RELAXED);
      x->gids[k] = (uint32_t)i;
      x->gxy[2 * (size_t)k] = (float)(p[0] - x->lo[0]);
      x->gxy[2 * (size_t)k + 1] = (float)(p[1] - x->lo[1]);
    }
  return MX_OK;
}

/* The sub-cell of a float position along one side of a sub-grid. */
static inline uint32_t sub_of(float v, float v0, float inv, uint32_t k) {
  const float t = (v - v0) * inv;
  return !(t >= 1.0f) ? 0 : t >= (float)(k - 1) ? k - 1 : (uint32_t)t;
}

/* The dense grid cells split into k x k sub-cells (k^2 about half their
 * nodes), their entries sorted by sub-cell (a counting sort each). */
static int subgrid_build(qc_ctx *x) {
  /* the dense cells row by row: counted, then listed, in parallel */
  uint64_t *row = mx_alloc(((size_t)x->gy + 1) * sizeof *row);
  if (!row) return MX_ENOMEM;
#pragma omp parallel for schedule(static) if ((size_t)x->gx * x->gy > PAR_MIN)
  for (uint32_t j = 0; j < x->gy; j++) {
    uint64_t k = 0;
    for (uint32_t i = 0; i < x->gx; i++) {
      const size_t g = cell_at(x, i, j);
      k += x->goff[g] - beg(x->goff, g) > DENSE;
    }
    row[j] = k;
  }
  const size_t nd = (size_t)mx_scan_u64(row, x->gy);
  if (!nd) return mx_free(row), MX_OK;
  x->sub = mx_alloc(nd * sizeof *x->sub);
  uint64_t *size = mx_alloc((nd + 1) * sizeof *size);
  if (!x->sub || !size) return mx_free(row), mx_free(size), MX_ENOMEM;
  size_t big = 0;
#pragma omp parallel for schedule(static) reduction(max : big) \
    if ((size_t)x->gx * x->gy > PAR_MIN)
  for (uint32_t j = 0; j < x->gy; j++) {
    uint64_t d = row[j];
    for (uint32_t i = 0; i < x->gx; i++) {
      const size_t g = cell_at(x, i, j), c = x->goff[g] - beg(x->goff, g);
      if (c <= DENSE) continue;
      uint32_t k = (uint32_t)ceil(sqrt(0.5 * (double)c));
      if (k > 64) k = 64;
      x->sub[d] = (struct subgrid){(uint32_t)g, k, 0, (float)(i * x->h), (float)(j * x->h),
                                   (float)(k / x->h)};
      size[d++] = (uint64_t)k * k + 1;
      if (c > big) big = c;
    }
  }
  mx_free(row);
  const size_t pool = (size_t)mx_scan_u64(size, nd);
#pragma omp parallel for schedule(static) if (nd > PAR_MIN)
  for (size_t d = 0; d < nd; d++) x->sub[d].off = (uint32_t)size[d];
  mx_free(size);
  x->nsub = nd;
  const size_t ng = grid_cells(x);
  x->gsub = mx_alloc((ng + 1) * sizeof *x->gsub);
  if (!x->gsub) return MX_ENOMEM;
#pragma omp parallel for schedule(static) if (ng > PAR_MIN)
  for (size_t g = 0; g < ng; g++) x->gsub[g] = UINT32_MAX;
#pragma omp parallel for schedule(static) if (nd > PAR_MIN)
  for (size_t d = 0; d < nd; d++) x->gsub[x->sub[d].g] = (uint32_t)d;
  x->soff = mx_alloc((pool + 1) * sizeof *x->soff);
  int nt = nd > 16 ? omp_get_max_threads() : 1;
  if (nt > MAX_CHUNKS) nt = MAX_CHUNKS;
  uint32_t *tid = mx_alloc((size_t)nt * (big + 1) * sizeof *tid);
  float *txy = mx_alloc((size_t)nt * (2 * big + 1) * sizeof *txy);
  uint32_t *tsc = mx_alloc((size_t)nt * (big + 1) * sizeof *tsc);
  int st = x->soff && tid && txy && tsc ? MX_OK : MX_ENOMEM;
  if (st == MX_OK) {
#pragma omp parallel num_threads(nt)
    {
      const size_t o = (size_t)omp_get_thread_num() * (big + 1);
#pragma omp for schedule(dynamic, 16)
      for (size_t d = 0; d < nd; d++) {
        const struct subgrid *S = &x->sub[d];
        uint32_t *off = x->soff + S->off;
        const uint32_t b0 = beg(x->goff, S->g), c = x->goff[S->g] - b0, kk = S->k * S->k;
        memset(off, 0, (kk + 1) * sizeof *off);
        for (uint32_t e = 0; e < c; e++) {
          const float *q = x->gxy + 2 * (size_t)(b0 + e);
          tsc[o + e] = sub_of(q[1], S->y0, S->inv, S->k) * S->k + sub_of(q[0], S->x0, S->inv, S->k);
          off[tsc[o + e] + 1]++;
        }
        for (uint32_t t = 0; t < kk; t++) off[t + 1] += off[t];
        for (uint32_t e = 0; e < c; e++) {
          const uint32_t at = off[tsc[o + e]]++;
          tid[o + at] = x->gids[b0 + e];
          txy[2 * (o + at)] = x->gxy[2 * (size_t)(b0 + e)];
          txy[2 * (o + at) + 1] = x->gxy[2 * (size_t)(b0 + e) + 1];
        }
        /* off[t] is now the end of sub-cell t: shift back to starts */
        for (uint32_t t = kk; t > 0; t--) off[t] = off[t - 1] + b0;
        off[0] = b0;
        memcpy(x->gids + b0, tid + o, c * sizeof *tid);
        memcpy(x->gxy + 2 * (size_t)b0, txy + 2 * o, 2 * (size_t)c * sizeof *txy);
      }
    }
  }
  mx_free(tid), mx_free(txy), mx_free(tsc);
  return st;
}

/* ---- hanging nodes ------------------------------------------------------- */

/* Edge a-b as the test of points on it needs it. */
typedef struct {
  const double *a;
  double u[2], l2, lim; /* b - a, its squared length, (HANG_EPS l2)^2 */
} edge_test;

static inline edge_test edge_of(const double *a, const double *b) {
  edge_test e = {a, {b[0] - a[0], b[1] - a[1]}, 0.0, 0.0};
  e.l2 = e.u[0] * e.u[0] + e.u[1] * e.u[1];
  e.lim = HANG_EPS * HANG_EPS * e.l2 * e.l2;
  return e;
}

/* Point p lies on the closed edge (ends included: p is not one of its
 * nodes, so at an end it is a second node at the same place): within
 * HANG_EPS of its length from its line, between its ends. */
static inline int on_edge(const double *p, const edge_test *e) {
  const double w[2] = {p[0] - e->a[0], p[1] - e->a[1]};
  if (!(e->l2 > 0)) return w[0] == 0 && w[1] == 0;
  const double cr = e->u[0] * w[1] - e->u[1] * w[0];
  if (!(cr * cr <= e->lim)) return 0;
  const double t = (e->u[0] * w[0] + e->u[1] * w[1]) / e->l2;
  return t >= -HANG_EPS && t <= 1.0 + HANG_EPS;
}

/* The nodes of the grid cells the widened box of edge a-b covers that lie
 * on it (and are not a or b): marked. The box is widened (pad) so that a
 * node on the edge is in it, and in one of those cells; the nodes whose
 * float positions lie in it, widened by fm more, are tested. */
static void hang_on(const mx_qmesh *M, const qc_ctx *x, double pad, uint32_t a, uint32_t b,
                    uint8_t *hang) {
  const double *pa = M->xy + 2 * (size_t)a, *pb = M->xy + 2 * (size_t)b;
  const double lo[2] = {mx_min(pa[0], pb[0]) - pad, mx_min(pa[1], pb[1]) - pad};
  const double hi[2] = {mx_max(pa[0], pb[0]) + pad, mx_max(pa[1], pb[1]) + pad};
  const float f0 = (float)(lo[0] - x->lo[0] - x->fm), f1 = (float)(hi[0] - x->lo[0] + x->fm);
  const float f2 = (float)(lo[1] - x->lo[1] - x->fm), f3 = (float)(hi[1] - x->lo[1] + x->fm);
  const uint32_t c0 = grid_x(x, lo[0]), c1 = grid_x(x, hi[0]);
  const uint32_t c2 = grid_y(x, lo[1]), c3 = grid_y(x, hi[1]);
  const edge_test e = edge_of(pa, pb);
  const float *q = x->gxy;
  for (uint32_t gy = c2; gy <= c3; gy++)
    for (uint32_t gx = c0; gx <= c1; gx++) {
      const size_t g = cell_at(x, gx, gy);
      uint32_t k0 = beg(x->goff, g), k1 = x->goff[g], s0 = 0, s1 = 0, s2 = 0, s3 = 0, sk = 0;
      const uint32_t *so = NULL;
      if (k1 - k0 > DENSE) {
        const struct subgrid *S = &x->sub[x->gsub[g]];
        so = x->soff + S->off, sk = S->k;
        s0 = sub_of(f0, S->x0, S->inv, sk), s1 = sub_of(f1, S->x0, S->inv, sk);
        s2 = sub_of(f2, S->y0, S->inv, sk), s3 = sub_of(f3, S->y0, S->inv, sk);
      }
      for (uint32_t sy = s2; sy <= s3; sy++)
        for (uint32_t sx = s0; sx <= s1; sx++) {
          if (so) k0 = so[sy * sk + sx], k1 = so[sy * sk + sx + 1];
          for (uint32_t k = k0; k < k1; k++) {
            if (q[2 * k] < f0 || q[2 * k] > f1 || q[2 * k + 1] < f2 || q[2 * k + 1] > f3) continue;
            const uint32_t v = x->gids[k];
            if (v != a && v != b && on_edge(M->xy + 2 * (size_t)v, &e)) mark(hang, v);
          }
        }
    }
}

/* ---- edges --------------------------------------------------------------- */

static inline void cas(uint32_t *v, int i, int j) {
  const uint32_t x = v[i], y = v[j];
  v[i] = x < y ? x : y;
  v[j] = x < y ? y : x;
}

/* Sorts a[0, n): networks (no branches to mispredict) for the short lists
 * of a quadtree mesh's nodes, insertion, or a heapsort for a node shared by
 * many cells (no allocation). */
static void sort_u32(uint32_t *a, size_t n) {
  if (n <= 8) {
    uint32_t v[8];
    for (size_t i = 0; i < 8; i++) v[i] = i < n ? a[i] : UINT32_MAX;
    if (n <= 4) {
      cas(v, 0, 1); cas(v, 2, 3); cas(v, 0, 2); cas(v, 1, 3); cas(v, 1, 2);
    } else {
      cas(v, 0, 1); cas(v, 2, 3); cas(v, 4, 5); cas(v, 6, 7);
      cas(v, 0, 2); cas(v, 1, 3); cas(v, 4, 6); cas(v, 5, 7);
      cas(v, 1, 2); cas(v, 5, 6); cas(v, 0, 4); cas(v, 3, 7);
      cas(v, 1, 5); cas(v, 2, 6);
      cas(v, 1, 4); cas(v, 3, 6);
      cas(v, 2, 4); cas(v, 3, 5);
      cas(v, 3, 4);
    }
    for (size_t i = 0; i < n; i++) a[i] = v[i];
    return;
  }
  if (n <= 32) {
    for (size_t i = 1; i < n; i++)
      for (size_t j = i; j > 0 && a[j - 1] > a[j]; j--) {
        const uint32_t t = a[j];
        a[j] = a[j - 1];
        a[j - 1] = t;
      }
    return;
  }
  for (size_t k = n / 2; k-- > 0;)
    for (size_t i = k, c; (c = 2 * i + 1) < n; i = c) {
      if (c + 1 < n && a[c + 1] > a[c]) c++;
      if (a[i] >= a[c]) break;
      const uint32_t t = a[i];
      a[i] = a[c];
      a[c] = t;
    }
  for (size_t e = n; e-- > 1;) {
    uint32_t t = a[0];
    a[0] = a[e];
    a[e] = t;
    for (size_t i = 0, c; (c = 2 * i + 1) < e; i = c) {
      if (c + 1 < e && a[c + 1] > a[c]) c++;
      if (a[i] >= a[c]) break;
      t = a[i];
      a[i] = a[c];
      a[c] = t;
    }
  }
}

/* The ends of side s of cell c: lower, upper, and whether it runs up. */
static inline void side_of(const mx_qmesh *M, uint32_t cs, uint32_t *lo, uint32_t *hi, int *up) {
  const size_t c = cs >> 2;
  const int s = (int)(cs & 3), nv = qnv(M, c);
  const uint32_t a = M->conn[4 * c + s], b = M->conn[4 * c + nxt(s, nv)];
  *lo = a < b ? a : b, *hi = a < b ? b : a, *up = a < b;
}

/* Every side of every cell (4 c + s) bucketed by the block of node ids of
 * its lower end: chunks of cells count per block, then write into their
 * own ranges of each bucket; the buckets [q0, q1) of a round at a time, so
 * that the records take at most ROUND_BYTES. */
#define ROUND_BYTES ((size_t)32 << 20)
typedef struct {
  uint64_t *h;      /* per chunk and bucket: count, then where it writes */
  uint64_t *start;  /* per bucket: its first record in the round; nbk + 1 */
  uint32_t *rec;
  size_t nbk, big, cap; /* buckets, records of the largest, room in rec */
  int nk;
} buckets;

static int side_counts(const mx_qmesh *M, buckets *K) {
  const size_t m = M->ncells, nbk = (M->nnodes >> NODE_BLOCK) + 1;
  int nk = m > PAR_MIN ? omp_get_max_threads() : 1;
  if (nk > MAX_CHUNKS) nk = MAX_CHUNKS;
  K->nk = nk;
  K->nbk = nbk;
  K->h = mx_calloc((size_t)nk * nbk * sizeof *K->h);
  K->start = mx_alloc((nbk + 1) * sizeof *K->start);
  if (!K->h || !K->start) return MX_ENOMEM;
#pragma omp parallel for schedule(static, 1) num_threads(nk)
  for (int k = 0; k < nk; k++) {
    uint64_t *hk = K->h + (size_t)k * nbk;
    for (size_t c = m * (size_t)k / (size_t)nk; c < m * (size_t)(k + 1) / (size_t)nk; c++) {
      const uint32_t *r = M->conn + 4 * c;
      const int nv = qnv(M, c);
      for (int s = 0; s < nv; s++) {
        const uint32_t a = r[s], b = r[nxt(s, nv)];
        hk[(a < b ? a : b) >> NODE_BLOCK]++;
      }
    }
  }
  /* bucket sizes (in start), the largest, and the room a round needs */
  size_t tot = 0, big = 0, round = 0, cap = 0;
  for (size_t q = 0; q < nbk; q++) {
    size_t c = 0;
    for (int k = 0; k < nk; k++) c += K->h[(size_t)k * nbk + q];
    K->start[q] = c;
    tot += c;
    if (c > big) big = c;
    if ((round + c) * sizeof *K->rec > ROUND_BYTES && round) {
      if (round > cap) cap = round;
      round = 0;
    }
    round += c;
  }
  if (round > cap) cap = round;
  K->big = big;
  K->cap = cap;
  K->rec = mx_alloc((cap + 1) * sizeof *K->rec);
  return K->rec ? MX_OK : MX_ENOMEM;
}

/* The buckets from q0 on that fit the round's room; returns their end. */
static size_t side_round(const mx_qmesh *M, buckets *K, size_t q0) {
  const size_t m = M->ncells, nbk = K->nbk;
  const int nk = K->nk;
  size_t q1 = q0, tot = 0;
  uint64_t *size = K->start; /* sizes on entry, turned into starts */
  while (q1 < nbk && (tot + size[q1] <= K->cap || q1 == q0)) tot += size[q1++];
  /* chunk-major places within each bucket, buckets in order */
  uint64_t at = 0;
  for (size_t q = q0; q < q1; q++) {
    size[q] = at;
    for (int k = 0; k < nk; k++) {
      const uint64_t hk = K->h[(size_t)k * nbk + q];
      K->h[(size_t)k * nbk + q] = at;
      at += hk;
    }
  }
  size[q1] = at; /* the next round takes its sizes from h again */
#pragma omp parallel for schedule(static, 1) num_threads(nk)
  for (int k = 0; k < nk; k++) {
    uint64_t *hk = K->h + (size_t)k * nbk;
    for (size_t c = m * (size_t)k / (size_t)nk; c < m * (size_t)(k + 1) / (size_t)nk; c++) {
      const uint32_t *r = M->conn + 4 * c;
      const int nv = qnv(M, c);
      for (int s = 0; s < nv; s++) {
        const uint32_t a = r[s], b = r[nxt(s, nv)];
        const size_t q = (a < b ? a : b) >> NODE_BLOCK;
        if (q >= q0 && q < q1) K->rec[hk[q]++] = (uint32_t)(4 * c + (size_t)s);
      }
    }
  }
  return q1;
}

typedef struct {
  size_t bad, nb, ne;
} edge_counts;

/* The edges of the nodes of bucket q: per node, its sides sorted; a run of
 * one upper end is an edge: bad with both ends on one node, used more than
 * twice, or twice the same way; boundary when used once. Each edge marks
 * its boundary ends and the nodes hanging on it. */
static void bucket_edges(const mx_qmesh *M, const qc_ctx *x, const buckets *K, size_t q,
                         double pad, uint64_t *t8, uint32_t *t4, uint8_t *hang, edge_counts *ec) {
  uint32_t cnt[(1u << NODE_BLOCK) + 1];
  memset(cnt, 0, sizeof cnt);
  const uint64_t i0 = K->start[q], n = K->start[q + 1] - i0;
  for (uint64_t i = 0; i < n; i++) {
    uint32_t lo, hi;
    int up;
    side_of(M, K->rec[i0 + i], &lo, &hi, &up);
    const uint32_t j = lo & ((1u << NODE_BLOCK) - 1);
    t8[i] = (uint64_t)j << 32 | hi << 1 | (uint32_t)up;
    cnt[j]++;
  }
  uint32_t s = 0;
  for (uint32_t j = 0; j < 1u << NODE_BLOCK; j++) {
    const uint32_t c = cnt[j];
    cnt[j] = s;
    s += c;
  }
  for (uint64_t i = 0; i < n; i++) t4[cnt[t8[i] >> 32]++] = (uint32_t)t8[i];
  for (uint32_t j = 0; j < 1u << NODE_BLOCK; j++) {
    const uint32_t a = (uint32_t)(q << NODE_BLOCK) + j, b0 = beg(cnt, j), b1 = cnt[j];
    if (b0 == b1) continue;
    sort_u32(t4 + b0, b1 - b0);
    for (uint32_t i = b0, k; i < b1; i = k) {
      const uint32_t b = t4[i] >> 1;
      uint32_t up = 0;
      for (k = i; k < b1 && t4[k] >> 1 == b; k++) up += t4[k] & 1;
      const uint32_t len = k - i;
      const int kind = b == a || len > 2 ? 2 : len == 1 ? 1 : up == 1 ? 0 : 2;
      ec->ne++;
      ec->bad += kind == 2;
      ec->nb += kind == 1;
      if (kind == 1) mark(x->bnode, a), mark(x->bnode, b);
      hang_on(M, x, pad, a, b, hang);
    }
  }
}

/* The distinct edges (x->ne), bad_edges, boundary edges and their nodes,
 * and the hanging nodes, round after round of buckets. */
static int edges_pass(const mx_qmesh *M, qc_ctx *x, double pad, mx_qcheck_report *r) {
  buckets K = {0};
  int st = side_counts(M, &K);
  uint8_t *hang = st == MX_OK ? mx_calloc(M->nnodes + 1) : NULL;
  int nt = K.nbk > 1 ? omp_get_max_threads() : 1;
  if (nt > MAX_CHUNKS) nt = MAX_CHUNKS;
  uint64_t *t8 = st == MX_OK ? mx_alloc((size_t)nt * (K.big + 1) * sizeof *t8) : NULL;
  uint32_t *t4 = st == MX_OK ? mx_alloc((size_t)nt * (K.big + 1) * sizeof *t4) : NULL;
  if (st == MX_OK && (!hang || !t8 || !t4)) st = MX_ENOMEM;
  size_t bad = 0, nb = 0, ne = 0, h = 0;
  for (size_t q0 = 0; st == MX_OK && q0 < K.nbk;) {
    /* sizes of this round's buckets from the counts (start holds them) */
    for (size_t q = q0; q < K.nbk; q++) {
      uint64_t c = 0;
      for (int k = 0; k < K.nk; k++) c += K.h[(size_t)k * K.nbk + q];
      K.start[q] = c;
    }
    const size_t q1 = side_round(M, &K, q0);
#pragma omp parallel num_threads(nt) reduction(+ : bad, nb, ne)
    {
      edge_counts ec = {0, 0, 0};
      const size_t o = (size_t)omp_get_thread_num() * (K.big + 1);
#pragma omp for schedule(dynamic, 1)
      for (size_t q = q0; q < q1; q++) bucket_edges(M, x, &K, q, pad, t8 + o, t4 + o, hang, &ec);
      bad += ec.bad, nb += ec.nb, ne += ec.ne;
    }
    q0 = q1;
  }
  if (st == MX_OK) {
#pragma omp parallel for reduction(+ : h) schedule(static) if (M->nnodes > PAR_MIN)
    for (size_t i = 0; i < M->nnodes; i++) h += hang[i];
    x->ne = ne;
    r->bad_edges = bad;
    r->boundary_edges = nb;
    r->edges = ne;
    r->hanging = h;
  }
  mx_free(K.h), mx_free(K.start), mx_free(K.rec), mx_free(hang), mx_free(t8), mx_free(t4);
  return st;
}

/* ---- cells: orientation and area ----------------------------------------- */

/* Twice the signed area; *bad when a corner is not strictly convex. */
static double cell_area2(const mx_qmesh *M, size_t c, int *bad) {
  const uint32_t *r = M->conn + 4 * c;
  const int nv = qnv(M, c);
  double a2 = 0.0;
  *bad = 0;
  for (int j = 0; j < nv; j++) {
    const double *p = M->xy + 2 * (size_t)r[j];
    const double *n = M->xy + 2 * (size_t)r[nxt(j, nv)];
    const double *q = M->xy + 2 * (size_t)r[prv(j, nv)];
    const double cr = (n[0] - p[0]) * (q[1] - p[1]) - (n[1] - p[1]) * (q[0] - p[0]);
    if (!(cr > 0)) *bad = 1; /* NaN too */
    a2 += p[0] * n[1] - p[1] * n[0];
  }
  return a2;
}

static void cells_pass(const mx_qmesh *M, mx_qcheck_report *r) {
  const size_t nb = (M->ncells + AREA_BLOCK - 1) / AREA_BLOCK;
  size_t inv = 0;
  double area = 0.0;
  /* fixed blocks summed in order: the same total for any thread count */
#pragma omp parallel for reduction(+ : inv) ordered schedule(static, 1) if (nb > 16)
  for (size_t b = 0; b < nb; b++) {
    const size_t lo = b * AREA_BLOCK;
    const size_t hi = lo + AREA_BLOCK < M->ncells ? lo + AREA_BLOCK : M->ncells;
    double s = 0.0;
    for (size_t c = lo; c < hi; c++) {
      int bad;
      s += cell_area2(M, c, &bad);
      inv += (size_t)bad;
    }
#pragma omp ordered
    area += s;
  }
  r->inverted = inv;
  r->area = 0.5 * area;
}

/* ---- against the domain -------------------------------------------------- */

static double poly_area(const mx_poly *P) {
  double a2 = 0.0;
  for (size_t s = 0; s < P->ns; s++) {
    const double *a = P->xy + 2 * (size_t)P->seg[2 * s], *b = P->xy + 2 * (size_t)P->seg[2 * s + 1];
    a2 += a[0] * b[1] - a[1] * b[0];
  }
  return 0.5 * a2;
}

static double poly_diameter(const mx_poly *P) {
  double x0 = INFINITY, y0 = INFINITY, x1 = -INFINITY, y1 = -INFINITY;
  for (size_t i = 0; i < P->nv; i++) {
    x0 = mx_min(x0, P->xy[2 * i]), x1 = mx_max(x1, P->xy[2 * i]);
    y0 = mx_min(y0, P->xy[2 * i + 1]), y1 = mx_max(y1, P->xy[2 * i + 1]);
  }
  return P->nv ? sqrt((x1 - x0) * (x1 - x0) + (y1 - y0) * (y1 - y0)) : 0.0;
}

/* Outer loops (counter-clockwise) minus holes (clockwise): each loop
 * followed from segment to segment (in a checked domain every vertex
 * starts one segment), its signed area telling which it is. */
static int loops_euler(const mx_poly *P, long *out) {
  uint32_t *next = mx_alloc((P->nv + 1) * sizeof *next);
  uint8_t *seen = mx_calloc(P->nv + 1);
  long chi = 0;
  if (!next || !seen) {
    mx_free(next), mx_free(seen);
    return MX_ENOMEM;
  }
  for (size_t v = 0; v < P->nv; v++) next[v] = UINT32_MAX;
  for (size_t s = 0; s < P->ns; s++) next[P->seg[2 * s]] = P->seg[2 * s + 1];
  for (size_t v0 = 0; v0 < P->nv; v0++) {
    if (seen[v0] || next[v0] == UINT32_MAX) continue;
    double a2 = 0.0;
    for (uint32_t v = (uint32_t)v0; v != UINT32_MAX && !seen[v]; v = next[v]) {
      seen[v] = 1;
      if (next[v] == UINT32_MAX) break;
      const double *p = P->xy + 2 * (size_t)v, *q = P->xy + 2 * (size_t)next[v];
      a2 += p[0] * q[1] - p[1] * q[0];
    }
    chi += a2 > 0 ? 1 : a2 < 0 ? -1 : 0;
  }
  mx_free(next), mx_free(seen);
  *out = chi;
  return MX_OK;
}

/* A used node in the grid cells around f within d of it. */
static int node_near(const mx_qmesh *M, const qc_ctx *x, const double *f, double d) {
  if (!x->ne) return 0;
  const uint32_t i0 = grid_x(x, f[0] - d), i1 = grid_x(x, f[0] + d);
  const uint32_t j0 = grid_y(x, f[1] - d), j1 = grid_y(x, f[1] + d);
  for (uint32_t j = j0; j <= j1; j++)
    for (uint32_t i = i0; i <= i1; i++) {
      const size_t g = cell_at(x, i, j);
      for (uint32_t k = beg(x->goff, g); k < x->goff[g]; k++) {
        const double *p = M->xy + 2 * (size_t)x->gids[k];
        if (hypot(p[0] - f[0], p[1] - f[1]) <= d) return 1;
      }
    }
  return 0;
}

static int domain_pass(const mx_qmesh *M, const mx_poly *P, double tol, const qc_ctx *x,
                       mx_qcheck_report *r) {
  const double d = tol * poly_diameter(P);
  mx_poly_index I;
  MX_CHECK(mx_poly_index_build(P, &I));
  size_t off = 0;
#pragma omp parallel for reduction(+ : off) schedule(dynamic, 1024) \
    if (M->nnodes > PAR_MIN)
  for (size_t i = 0; i < M->nnodes; i++) {
    if (!x->bnode[i]) continue;
    double q[2], d2;
    off += mx_poly_closest(&I, M->xy + 2 * i, d, q, &d2) == UINT32_MAX;
  }
  mx_poly_index_free(&I);
  r->off_boundary = off;
  uint32_t *feat = NULL;
  size_t nf = 0;
  MX_CHECK(mx_poly_features(P, &feat, &nf));
  size_t miss = 0;
#pragma omp parallel for reduction(+ : miss) schedule(static) if (nf > 64)
  for (size_t k = 0; k < nf; k++) miss += !node_near(M, x, P->xy + 2 * (size_t)feat[k], d);
  mx_free(feat);
  r->missing_features = miss;
  r->domain_area = poly_area(P);
  MX_CHECK(loops_euler(P, &r->domain_euler));
  r->area_error = r->domain_area != 0.0 ? fabs(r->area - r->domain_area) / fabs(r->domain_area)
                                        : (r->area != 0.0 ? INFINITY : 0.0);
  return MX_OK;
}

int mx_qmesh_check(const mx_qmesh *M, const mx_poly *domain, double tol, mx_qcheck_report *r) {
  memset(r, 0, sizeof *r);
  MX_CHECK(structure_ok(M));
  qc_ctx x = {0};
  int st = mark_used(M, &x);
  double diag = 0.0;
  if (!st) diag = grid_size(M, &x);
  if (!st) st = grid_build(M, &x);
  if (!st) st = subgrid_build(&x);
  if (!st) st = edges_pass(M, &x, 1e-9 * diag, r);
  mx_mem_mark("qcheck.edges");
  if (!st) r->euler = euler(M, &x);
  if (!st) cells_pass(M, r);
  if (!st && domain) st = domain_pass(M, domain, tol, &x, r);
  ctx_free(&x);
  return st;
}
