/* Independent checks of a 2D mixed mesh (quad.h: mx_qmesh_check). Nothing
 * here calls the mesher's own passes: the edges come from a sort of the
 * cells' (min, max) node pairs, the hanging nodes from a uniform grid over
 * those edges, orientation from each corner's cross product.
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
 * Every pass is parallel over cells, edges or nodes; the counts do not
 * depend on the thread count, nor the areas (summed in fixed blocks). */
#include <math.h>
#include <stdint.h>
#include <string.h>

#include "common.h"
#include "quad/quad.h"
#include "soa/scan.h"

enum { AREA_BLOCK = 4096, PAR_MIN = 16384 }; /* fewer items: one thread */
#define HANG_EPS 1e-10 /* relative to the edge's length */

typedef struct {
  uint64_t *ekey;   /* the distinct edges, (min << 32) | max, sorted */
  size_t ne;
  uint8_t *used;    /* per node: a corner of some cell */
  uint8_t *bnode;   /* per node: an end of a boundary edge */
  double lo[2], h;  /* the grid over the edges */
  uint32_t gx, gy;
  uint64_t *goff;   /* gx * gy + 1 CSR offsets into gids */
  uint32_t *gids;   /* edge indices per grid cell */
} qc_ctx;

static inline int qnv(const mx_qmesh *M, size_t c) { return M->type[c] == MX_QQUAD ? 4 : 3; }
static inline uint32_t ekey_lo(uint64_t k) { return (uint32_t)(k >> 32); }
static inline uint32_t ekey_hi(uint64_t k) { return (uint32_t)k; }

static void ctx_free(qc_ctx *x) {
  mx_free(x->ekey), mx_free(x->used), mx_free(x->bnode), mx_free(x->goff), mx_free(x->gids);
  memset(x, 0, sizeof *x);
}

/* Types in range, node indices below nnodes, indices that fit the sort. */
static int structure_ok(const mx_qmesh *M) {
  if ((M->nnodes && !M->xy) || (M->ncells && (!M->type || !M->conn))) {
    mx_error(NULL, 0, "mesh check: incomplete 2D mesh");
    return MX_EINTERNAL;
  }
  if (M->ncells >= (size_t)1 << 30 || M->nnodes >= UINT32_MAX) {
    mx_error(NULL, 0, "mesh check: %zu cells, %zu nodes: too many for the checker", M->ncells,
             M->nnodes);
    return MX_EINPUT;
  }
  size_t bad = M->ncells;
#pragma omp parallel for reduction(min : bad) schedule(static) if (M->ncells > 65536)
  for (size_t c = 0; c < M->ncells; c++) {
    int ok = M->type[c] <= MX_QQUAD;
    for (int j = 0; ok && j < qnv(M, c); j++) ok = M->conn[4 * c + j] < M->nnodes;
    if (!ok && c < bad) bad = c;
  }
  if (bad == M->ncells) return MX_OK;
  mx_error(NULL, 0, "mesh check: cell %zu has a bad type or node index", bad);
  return MX_EINTERNAL;
}

/* ---- edges --------------------------------------------------------------- */

/* Every side of every cell as a key (4 slots a cell; a triangle's 4th is
 * UINT64_MAX, sorted last), its value 4 * cell + side; sorted. */
static int side_keys(const mx_qmesh *M, uint64_t **keys, uint32_t **vals) {
  const size_t n = 4 * M->ncells;
  *keys = mx_alloc((n + 1) * sizeof **keys);
  *vals = mx_alloc((n + 1) * sizeof **vals);
  if (!*keys || !*vals) return MX_ENOMEM;
#pragma omp parallel for schedule(static) if (M->ncells > PAR_MIN)
  for (size_t c = 0; c < M->ncells; c++) {
    const uint32_t *r = M->conn + 4 * c;
    const int nv = qnv(M, c);
    for (int s = 0; s < 4; s++) {
      const uint32_t a = r[s % nv], b = r[(s + 1) % nv];
      (*keys)[4 * c + s] = s < nv ? (uint64_t)(a < b ? a : b) << 32 | (a < b ? b : a) : UINT64_MAX;
      (*vals)[4 * c + s] = (uint32_t)(4 * c + (size_t)s);
    }
  }
  return mx_sort_u64(*keys, *vals, n) ? MX_ENOMEM : MX_OK;
}

/* Whether side v (4 * cell + side) runs from the lower node to the upper. */
static int side_up(const mx_qmesh *M, uint32_t v) {
  const size_t c = v >> 2;
  const int s = (int)(v & 3), nv = qnv(M, c);
  return M->conn[4 * c + s] < M->conn[4 * c + (s + 1) % nv];
}

/* One run of equal keys from slot i: 0 interior, 1 boundary, 2 bad. */
static int classify_run(const mx_qmesh *M, const uint64_t *k, const uint32_t *v, size_t i,
                        size_t n) {
  size_t len = 1;
  while (i + len < n && k[i + len] == k[i]) len++;
  if (ekey_lo(k[i]) == ekey_hi(k[i]) || len > 2) return 2;
  if (len == 1) return 1;
  return side_up(M, v[i]) == side_up(M, v[i + 1]) ? 2 : 0;
}

static inline void mark(uint8_t *flag, uint32_t i) {
#pragma omp atomic write
  flag[i] = 1;
}

/* The distinct edges (x->ekey), bad_edges, and the nodes used and on the
 * boundary. */
static int edges_pass(const mx_qmesh *M, qc_ctx *x, mx_qcheck_report *r) {
  uint64_t *k = NULL, *start = NULL;
  uint32_t *v = NULL;
  const size_t n = 4 * M->ncells;
  int st = side_keys(M, &k, &v);
  x->used = mx_calloc(M->nnodes + 1);
  x->bnode = mx_calloc(M->nnodes + 1);
  if (!st) start = mx_alloc((n + 1) * sizeof *start);
  if (!st && (!start || !x->used || !x->bnode)) st = MX_ENOMEM;
  if (!st) {
#pragma omp parallel for schedule(static) if (n > PAR_MIN)
    for (size_t i = 0; i < n; i++) start[i] = k[i] != UINT64_MAX && (i == 0 || k[i] != k[i - 1]);
    x->ne = (size_t)mx_scan_u64(start, n);
    x->ekey = mx_alloc((x->ne + 1) * sizeof *x->ekey);
    if (!x->ekey) st = MX_ENOMEM;
  }
  if (!st) {
    size_t bad = 0, nb = 0;
#pragma omp parallel for reduction(+ : bad, nb) schedule(static) if (n > PAR_MIN)
    for (size_t i = 0; i < n; i++) {
      if (k[i] == UINT64_MAX || (i > 0 && k[i] == k[i - 1])) continue;
      x->ekey[start[i]] = k[i];
      const int kind = classify_run(M, k, v, i, n);
      bad += kind == 2;
      nb += kind == 1;
      mark(x->used, ekey_lo(k[i])), mark(x->used, ekey_hi(k[i]));
      if (kind == 1) mark(x->bnode, ekey_lo(k[i])), mark(x->bnode, ekey_hi(k[i]));
    }
    r->bad_edges = bad;
    r->boundary_edges = nb;
    r->edges = x->ne;
  }
  mx_free(k), mx_free(v), mx_free(start);
  return st;
}

/* V - E + F over the nodes some cell uses. */
static long euler(const mx_qmesh *M, const qc_ctx *x) {
  size_t nv = 0;
#pragma omp parallel for reduction(+ : nv) schedule(static) if (M->nnodes > PAR_MIN)
  for (size_t i = 0; i < M->nnodes; i++) nv += x->used[i];
  return (long)nv - (long)x->ne + (long)M->ncells;
}

/* ---- the grid over the edges --------------------------------------------- */

static inline uint32_t grid_x(const qc_ctx *x, double px) {
  const double f = floor((px - x->lo[0]) / x->h);
  return f <= 0 ? 0 : f >= (double)(x->gx - 1) ? x->gx - 1 : (uint32_t)f;
}
static inline uint32_t grid_y(const qc_ctx *x, double py) {
  const double f = floor((py - x->lo[1]) / x->h);
  return f <= 0 ? 0 : f >= (double)(x->gy - 1) ? x->gy - 1 : (uint32_t)f;
}

/* The grid cells edge e's box (widened by pad) covers. */
static void edge_cells(const mx_qmesh *M, const qc_ctx *x, size_t e, double pad, uint32_t c[4]) {
  const double *a = M->xy + 2 * (size_t)ekey_lo(x->ekey[e]);
  const double *b = M->xy + 2 * (size_t)ekey_hi(x->ekey[e]);
  c[0] = grid_x(x, mx_min(a[0], b[0]) - pad), c[1] = grid_x(x, mx_max(a[0], b[0]) + pad);
  c[2] = grid_y(x, mx_min(a[1], b[1]) - pad), c[3] = grid_y(x, mx_max(a[1], b[1]) + pad);
}

/* Cells about twice the side a uniform mesh with these edges would have,
 * at most about 4 per edge. Returns the box's diagonal. */
static double grid_size(const mx_qmesh *M, qc_ctx *x) {
  double x0 = INFINITY, y0 = INFINITY, x1 = -INFINITY, y1 = -INFINITY;
#pragma omp parallel for reduction(min : x0, y0) reduction(max : x1, y1) schedule(static) \
    if (M->nnodes > PAR_MIN)
  for (size_t i = 0; i < M->nnodes; i++) {
    x0 = mx_min(x0, M->xy[2 * i]), x1 = mx_max(x1, M->xy[2 * i]);
    y0 = mx_min(y0, M->xy[2 * i + 1]), y1 = mx_max(y1, M->xy[2 * i + 1]);
  }
  if (M->nnodes == 0) x0 = y0 = x1 = y1 = 0.0;
  const double w = x1 - x0, t = y1 - y0, diag = sqrt(w * w + t * t);
  const double ne = (double)(x->ne ? x->ne : 1);
  x->lo[0] = x0, x->lo[1] = y0;
  x->h = w * t > 0 ? 2.0 * sqrt(w * t / ne) : diag > 0 ? diag / ne : 1.0;
  for (;;) {
    const double gx = floor(w / x->h) + 1, gy = floor(t / x->h) + 1;
    if (gx * gy <= 4.0 * ne + 16.0) {
      x->gx = (uint32_t)gx, x->gy = (uint32_t)gy;
      return diag;
    }
    x->h *= 1.5;
  }
}

static int grid_build(const mx_qmesh *M, qc_ctx *x, double pad) {
  const size_t ng = (size_t)x->gx * x->gy;
  x->goff = mx_calloc((ng + 1) * sizeof *x->goff);
  uint64_t *pos = mx_alloc((ng + 1) * sizeof *pos);
  if (!x->goff || !pos) {
    mx_free(pos);
    return MX_ENOMEM;
  }
#pragma omp parallel for schedule(static) if (x->ne > PAR_MIN)
  for (size_t e = 0; e < x->ne; e++) {
    uint32_t c[4];
    edge_cells(M, x, e, pad, c);
    for (uint32_t j = c[2]; j <= c[3]; j++)
      for (uint32_t i = c[0]; i <= c[1]; i++) {
#pragma omp atomic
        x->goff[(size_t)j * x->gx + i]++;
      }
  }
  const uint64_t total = mx_scan_u64(x->goff, ng + 1);
  memcpy(pos, x->goff, (ng + 1) * sizeof *pos);
  x->gids = mx_alloc((total + 1) * sizeof *x->gids);
  if (!x->gids) {
    mx_free(pos);
    return MX_ENOMEM;
  }
#pragma omp parallel for schedule(static) if (x->ne > PAR_MIN)
  for (size_t e = 0; e < x->ne; e++) {
    uint32_t c[4];
    edge_cells(M, x, e, pad, c);
    for (uint32_t j = c[2]; j <= c[3]; j++)
      for (uint32_t i = c[0]; i <= c[1]; i++) {
        uint64_t k;
#pragma omp atomic capture
        k = pos[(size_t)j * x->gx + i]++;
        x->gids[k] = (uint32_t)e;
      }
  }
  mx_free(pos);
  return MX_OK;
}

/* ---- hanging nodes ------------------------------------------------------- */

/* Point p lies on the closed edge (a, b) (ends included: p is not one of
 * its nodes, so at an end it is a second node at the same place). */
static int on_edge(const double *p, const double *a, const double *b) {
  const double u[2] = {b[0] - a[0], b[1] - a[1]}, w[2] = {p[0] - a[0], p[1] - a[1]};
  const double l2 = u[0] * u[0] + u[1] * u[1];
  if (!(l2 > 0)) return w[0] == 0 && w[1] == 0;
  const double t = (u[0] * w[0] + u[1] * w[1]) / l2, cr = u[0] * w[1] - u[1] * w[0];
  return t >= -HANG_EPS && t <= 1.0 + HANG_EPS && cr * cr <= HANG_EPS * HANG_EPS * l2 * l2;
}

static size_t hanging_pass(const mx_qmesh *M, const qc_ctx *x) {
  size_t hang = 0;
#pragma omp parallel for reduction(+ : hang) schedule(dynamic, 1024) \
    if (M->nnodes > PAR_MIN)
  for (size_t i = 0; i < M->nnodes; i++) {
    if (!x->used[i]) continue;
    const double *p = M->xy + 2 * i;
    const size_t g = (size_t)grid_y(x, p[1]) * x->gx + grid_x(x, p[0]);
    for (uint64_t k = x->goff[g]; k < x->goff[g + 1]; k++) {
      const uint64_t e = x->ekey[x->gids[k]];
      if (ekey_lo(e) == i || ekey_hi(e) == i) continue;
      if (on_edge(p, M->xy + 2 * (size_t)ekey_lo(e), M->xy + 2 * (size_t)ekey_hi(e))) {
        hang++;
        break;
      }
    }
  }
  return hang;
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
    const double *n = M->xy + 2 * (size_t)r[(j + 1) % nv];
    const double *q = M->xy + 2 * (size_t)r[(j + nv - 1) % nv];
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

/* A node of an edge in the grid cells around f within d of it. */
static int node_near(const mx_qmesh *M, const qc_ctx *x, const double *f, double d) {
  if (!x->ne) return 0;
  const uint32_t i0 = grid_x(x, f[0] - d), i1 = grid_x(x, f[0] + d);
  const uint32_t j0 = grid_y(x, f[1] - d), j1 = grid_y(x, f[1] + d);
  for (uint32_t j = j0; j <= j1; j++)
    for (uint32_t i = i0; i <= i1; i++) {
      const size_t g = (size_t)j * x->gx + i;
      for (uint64_t k = x->goff[g]; k < x->goff[g + 1]; k++) {
        const uint64_t e = x->ekey[x->gids[k]];
        for (int end = 0; end < 2; end++) {
          const double *p = M->xy + 2 * (size_t)(end ? ekey_hi(e) : ekey_lo(e));
          if (hypot(p[0] - f[0], p[1] - f[1]) <= d) return 1;
        }
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
  int st = edges_pass(M, &x, r);
  double diag = 0.0;
  if (!st) diag = grid_size(M, &x);
  /* the boxes are widened so that a node on an edge, or a feature within
   * the tolerance, finds the edge in its own grid cell */
  if (!st) st = grid_build(M, &x, 1e-9 * diag);
  if (!st) r->hanging = hanging_pass(M, &x);
  if (!st) r->euler = euler(M, &x);
  if (!st) cells_pass(M, r);
  if (!st && domain) st = domain_pass(M, domain, tol, &x, r);
  ctx_free(&x);
  return st;
}
