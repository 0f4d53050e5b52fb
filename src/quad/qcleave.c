/* The cleave of a 2D mesh along nested loops (quad.h, mx_qcleave): after
 * the boundary step has fitted the mesh to the outer loops, the loops
 * nested in them become interfaces between materials, and the cells are
 * cut along them so that none lies across one. In order:
 *
 *   regions     every node's region (mx_qregion_of), or the segment or
 *               loop vertex it lies on (within the index's eps: from then
 *               on it counts as lying exactly there);
 *   features    each sharp vertex of an interface (mx_poly_features) takes
 *               a corner of the cell holding it (the closest whose move
 *               leaves its cells no worse than FEATURE_SJ or as they were),
 *               or, when none may move, becomes a node of its own: the
 *               cell (and the one across, when it lies on a side) is
 *               fanned around it;
 *   warp        a free node of a cell an interface comes near goes onto
 *               the interface's closest point when that is within ALPHA of
 *               its shortest edge, else onto the nearest point where an
 *               interface meets one of its edges when that is within ALPHA
 *               of the edge's length, unless a cell around it would get
 *               worse than WARP_SJ or than it was (the moves are made
 *               together, then undone cell by cell until none is): no part
 *               of the cut is thinner than ALPHA of its cell;
 *   points      every point where an interface crosses the inside of an
 *               edge becomes a node, shared by the edge's two cells (keyed
 *               by the edge's ends and the segment, or the loop vertex, it
 *               comes from; its place computed on the segment);
 *   cut         in each cell, the points where a loop meets its boundary
 *               (those nodes, and its corners lying on the loop), taken in
 *               the order of the loop, come in pairs: where the loop goes
 *               in and where it next comes out (whether it goes in is
 *               decided by the exact orientation of the loop's next and
 *               previous vertices against the cell's sides). Each pair is
 *               a chord of the convex cell (the loop's vertices between
 *               are not sharp: the features are nodes); chords of disjoint
 *               loops do not cross, so they split the cell into convex
 *               parts, each written as triangles, or a quadrilateral where
 *               it has four corners and a scaled Jacobian of QUAD_SJ or
 *               more (see put_piece). A cell where the pairs do not match
 *               (a loop met more often than the cell can tell) is left
 *               whole and counted as unresolved;
 *   smooth      the nodes of the cells along the interfaces move to the
 *               mean of their cells' corners (or half-way) when that lifts
 *               the worst of their cells (see smooth).
 * Last, each cell's region: that of its free nodes, or of its centroid when
 * all its nodes lie on loops; a cell whose free nodes disagree counts as
 * across.
 *
 * Cells replaced keep their place (their parts in order, with the leaf and
 * level of the cell they came from); new nodes come after the others, in
 * the order of their keys (features: of their vertices). Every pass is a
 * loop over nodes or cells reading what the pass before wrote, or a short
 * ordered loop over the features: the result is the same for any thread
 * count. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "base/common.h"
#include "base/scan.h"
#include "geom/orient2d.h"
#include "quad/quad.h"

#define NONE UINT32_MAX
#define ALPHA 0.3       /* warp: a node this close to an interface, in its edges' lengths */
#define WARP_SJ 0.2     /* a warp never leaves a cell below this (or below what it was) */
#define FEATURE_SJ 0.05 /* the same for a node taking a feature */
#define QUAD_SJ 0.3     /* a part with four corners stays a quadrilateral from this */
#define SJ_OK 1e-6      /* the least scaled Jacobian of a valid cell */
#define MAXP 64         /* parts of one cell */
#define MAXE 48         /* points of one cell on the loops */
#define MAXS 256        /* interface segments near one cell */
#define SMOOTH_SWEEPS 3 /* rounds of smoothing along the interfaces */
#define SMOOTH_SJ 0.6   /* a node whose cells are all at least this good stays */

typedef struct {
  mx_qmesh *M;
  const mx_qregions *R;
  uint32_t *on_seg;  /* per node: the segment of `all` it lies on, or NONE */
  uint32_t *on_vert; /* per node: the loop vertex it lies on, or NONE */
  int32_t *reg;      /* per node: its region when free (on no loop), else -1 */
  uint64_t *off;     /* node -> cells (CSR, cells ascending) */
  uint32_t *ids;
  uint32_t *seg_loop, *seg_rank; /* per segment of `all`: its loop, its place in it */
  uint32_t *vin, *vout;          /* per vertex: the segments ending, starting there */
  mx_qcleave_stats *st;
} cl;

static inline int nv_of(const mx_qmesh *M, size_t c) { return M->type[c] == MX_QQUAD ? 4 : 3; }
static inline const double *pxy(const cl *C, uint32_t v) { return C->M->xy + 2 * (size_t)v; }
static inline const double *vxy(const cl *C, uint32_t w) { return C->R->all.xy + 2 * (size_t)w; }
static inline uint32_t seg_from(const cl *C, uint32_t s) { return C->R->all.seg[2 * (size_t)s]; }
static inline uint32_t seg_to(const cl *C, uint32_t s) { return C->R->all.seg[2 * (size_t)s + 1]; }
static inline int is_on(const cl *C, uint32_t v) {
  return C->on_seg[v] != NONE || C->on_vert[v] != NONE;
}

/* Node p lies on segment s (as recorded: exactly, whatever its rounding). */
static inline int on_s(const cl *C, uint32_t p, uint32_t s) {
  const uint32_t w = C->on_vert[p];
  return C->on_seg[p] == s || (w != NONE && (C->vout[w] == s || C->vin[w] == s));
}

static inline double cross3(const double *a, const double *b, const double *c) {
  return (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
}

static inline uint64_t edge_key(uint32_t a, uint32_t b) {
  return a < b ? (uint64_t)a << 32 | b : (uint64_t)b << 32 | a;
}

/* ---- the mesh's arrays ------------------------------------------------------ */

/* Room for nn nodes (the new ones' keys none, on nothing, region 0). */
static int grow_nodes(cl *C, size_t nn) {
  mx_qmesh *M = C->M;
  const size_t n0 = M->nnodes;
  double *xy = mx_realloc(M->xy, (2 * nn + 1) * sizeof *xy);
  if (xy) M->xy = xy;
  uint64_t *nk = M->nkey ? mx_realloc(M->nkey, (nn + 1) * sizeof *nk) : NULL;
  if (nk) M->nkey = nk;
  uint32_t *os = mx_realloc(C->on_seg, (nn + 1) * sizeof *os);
  if (os) C->on_seg = os;
  uint32_t *ov = mx_realloc(C->on_vert, (nn + 1) * sizeof *ov);
  if (ov) C->on_vert = ov;
  int32_t *reg = mx_realloc(C->reg, (nn + 1) * sizeof *reg);
  if (reg) C->reg = reg;
  if (!xy || (M->nkey && !nk) || !os || !ov || !reg) return MX_ENOMEM;
  for (size_t v = n0; v < nn; v++) {
    if (M->nkey) M->nkey[v] = MX_QNKEY_NONE;
    C->on_seg[v] = C->on_vert[v] = NONE;
    C->reg[v] = 0;
  }
  M->nnodes = nn;
  return MX_OK;
}

static int node_cells(cl *C) {
  const mx_qmesh *M = C->M;
  const size_t n = M->nnodes, m = M->ncells;
  mx_free(C->off), mx_free(C->ids);
  C->ids = NULL;
  C->off = mx_calloc((n + 2) * sizeof *C->off);
  if (!C->off) return MX_ENOMEM;
  for (size_t c = 0; c < m; c++)
    for (int k = 0; k < nv_of(M, c); k++) C->off[M->conn[4 * c + k] + 1]++;
  for (size_t v = 0; v < n; v++) C->off[v + 1] += C->off[v];
  C->ids = mx_alloc((C->off[n] + 1) * sizeof *C->ids);
  uint64_t *cur = mx_alloc((n + 1) * sizeof *cur);
  if (!C->ids || !cur) return mx_free(cur), MX_ENOMEM;
  memcpy(cur, C->off, n * sizeof *cur);
  for (size_t c = 0; c < m; c++) /* cells ascending per node */
    for (int k = 0; k < nv_of(M, c); k++) C->ids[cur[M->conn[4 * c + k]]++] = (uint32_t)c;
  mx_free(cur);
  return MX_OK;
}

/* The loops of `all`: each segment's loop and place in it, each vertex's
 * segments (a checked domain: every vertex used starts one, ends one). */
static int loops(cl *C) {
  const mx_poly *A = &C->R->all;
  C->seg_loop = mx_alloc((A->ns + 1) * sizeof *C->seg_loop);
  C->seg_rank = mx_alloc((A->ns + 1) * sizeof *C->seg_rank);
  C->vin = mx_alloc((A->nv + 1) * sizeof *C->vin);
  C->vout = mx_alloc((A->nv + 1) * sizeof *C->vout);
  if (!C->seg_loop || !C->seg_rank || !C->vin || !C->vout) return MX_ENOMEM;
  for (size_t v = 0; v < A->nv; v++) C->vin[v] = C->vout[v] = NONE;
  for (size_t s = 0; s < A->ns; s++) {
    C->vout[A->seg[2 * s]] = (uint32_t)s;
    C->vin[A->seg[2 * s + 1]] = (uint32_t)s;
    C->seg_loop[s] = NONE;
  }
  uint32_t L = 0;
  for (size_t s0 = 0; s0 < A->ns; s0++) {
    if (C->seg_loop[s0] != NONE) continue;
    uint32_t r = 0;
    for (uint32_t s = (uint32_t)s0; s != NONE && C->seg_loop[s] == NONE;
         s = C->vout[A->seg[2 * (size_t)s + 1]])
      C->seg_loop[s] = L, C->seg_rank[s] = r++;
    L++;
  }
  return MX_OK;
}

/* ---- what a cell becomes ------------------------------------------------------ */

/* Parts of a cell: corner lists of 3 or 4 nodes; bad: it could not be cut. */
typedef struct {
  int n, bad;
  uint32_t v[MAXP][4];
  uint8_t nv[MAXP];
} parts;

static double sj_ids(const cl *C, const uint32_t *v, int n) { return mx_qsj_nodes(C->M->xy, v, n); }

static void put(parts *P, const uint32_t *v, int n) {
  if (P->n == MAXP) {
    P->bad = 1;
    return;
  }
  for (int k = 0; k < 4; k++) P->v[P->n][k] = k < n ? v[k] : NONE;
  P->nv[P->n++] = (uint8_t)n;
}

/* A convex quadrilateral v: itself, or the two triangles of its better
 * diagonal. */
static void put_quad(const cl *C, const uint32_t *v, parts *P) {
  if (sj_ids(C, v, 4) >= QUAD_SJ) {
    put(P, v, 4);
    return;
  }
  double best = -INFINITY;
  int d = 0;
  for (int k = 0; k < 2; k++) {
    const uint32_t a[3] = {v[k], v[k + 1], v[(k + 2) & 3]};
    const uint32_t b[3] = {v[k], v[(k + 2) & 3], v[(k + 3) & 3]};
    const double s = mx_min(sj_ids(C, a, 3), sj_ids(C, b, 3));
    if (s > best) best = s, d = k;
  }
  const uint32_t a[3] = {v[d], v[d + 1], v[(d + 2) & 3]};
  const uint32_t b[3] = {v[d], v[(d + 2) & 3], v[(d + 3) & 3]};
  put(P, a, 3);
  put(P, b, 3);
}

/* A convex polygon v[0..n) (some corners may lie on the side between their
 * neighbours: points of the loops on a side) as parts: while it has more
 * than four corners, or a flat one, the ear of the best scaled Jacobian
 * whose diagonal passes through no other corner goes; then the
 * quadrilateral (put_quad) or the triangle. */
static void put_piece(const cl *C, const uint32_t *v0, int n, parts *P) {
  uint32_t v[2 * MAXE + 8];
  memcpy(v, v0, (size_t)n * sizeof *v);
  while (n > 3) {
    int flat = 0;
    for (int k = 0; k < n && !flat; k++)
      flat = mx_orient2d(pxy(C, v[(k + n - 1) % n]), pxy(C, v[k]), pxy(C, v[(k + 1) % n])) <= 0;
    if (n == 4 && !flat) {
      put_quad(C, v, P);
      return;
    }
    int best = -1;
    double bs = -INFINITY;
    for (int k = 0; k < n; k++) {
      const uint32_t t[3] = {v[(k + n - 1) % n], v[k], v[(k + 1) % n]};
      if (mx_orient2d(pxy(C, t[0]), pxy(C, t[1]), pxy(C, t[2])) <= 0) continue;
      int ok = 1;
      for (int j = 0; j < n && ok; j++)
        if (j != k && j != (k + n - 1) % n && j != (k + 1) % n)
          ok = mx_orient2d(pxy(C, t[2]), pxy(C, t[0]), pxy(C, v[j])) != 0;
      const double s = ok ? sj_ids(C, t, 3) : -INFINITY;
      if (ok && s > bs) bs = s, best = k;
    }
    if (best < 0) {
      P->bad = 1;
      return;
    }
    const uint32_t t[3] = {v[(best + n - 1) % n], v[best], v[(best + 1) % n]};
    put(P, t, 3);
    memmove(v + best, v + best + 1, (size_t)(n - best - 1) * sizeof *v);
    n--;
  }
  if (mx_orient2d(pxy(C, v[0]), pxy(C, v[1]), pxy(C, v[2])) > 0) put(P, v, 3);
  else P->bad = 1;
}

/* Rebuilds the cells: cell c becomes the parts fill(c) gives (itself when
 * it gives none, or when they are bad: counted in *bad). */
typedef void (*part_fn)(const cl *C, size_t c, const void *ctx, parts *P);

static int rebuild(cl *C, part_fn fill, const void *ctx, size_t *replaced, size_t *bad) {
  mx_qmesh *M = C->M;
  const size_t m = M->ncells;
  uint64_t *cnt = mx_alloc((m + 1) * sizeof *cnt);
  if (!cnt) return MX_ENOMEM;
  size_t rep = 0, nbad = 0;
#pragma omp parallel for schedule(dynamic, 1024) reduction(+ : rep, nbad)
  for (size_t c = 0; c < m; c++) {
    parts P;
    P.n = P.bad = 0;
    fill(C, c, ctx, &P);
    if (P.bad) P.n = 0;
    cnt[c] = P.n ? (uint64_t)P.n : 1;
    rep += P.n > 0;
    nbad += P.bad != 0;
  }
  *replaced = rep;
  if (bad) *bad = nbad;
  if (!rep) return mx_free(cnt), MX_OK;
  const size_t m2 = (size_t)mx_scan_u64(cnt, m);
  uint8_t *type = mx_alloc(m2 + 1), *level = mx_alloc(m2 + 1);
  uint32_t *conn = mx_alloc((4 * m2 + 1) * sizeof *conn), *leaf = mx_alloc((m2 + 1) * sizeof *leaf);
  if (!type || !level || !conn || !leaf) {
    mx_free(cnt), mx_free(type), mx_free(level), mx_free(conn), mx_free(leaf);
    return MX_ENOMEM;
  }
#pragma omp parallel for schedule(dynamic, 1024)
  for (size_t c = 0; c < m; c++) {
    parts P;
    P.n = P.bad = 0;
    fill(C, c, ctx, &P);
    if (P.bad) P.n = 0;
    size_t o = cnt[c];
    if (!P.n) {
      type[o] = M->type[c];
      memcpy(conn + 4 * o, M->conn + 4 * c, 4 * sizeof *conn);
      leaf[o] = M->leaf[c], level[o] = M->level[c];
      continue;
    }
    for (int i = 0; i < P.n; i++, o++) {
      type[o] = P.nv[i] == 4 ? MX_QQUAD : MX_QTRI;
      memcpy(conn + 4 * o, P.v[i], 4 * sizeof *conn);
      leaf[o] = M->leaf[c], level[o] = M->level[c];
    }
  }
  mx_free(cnt);
  mx_free(M->type), mx_free(M->conn), mx_free(M->leaf), mx_free(M->level);
  M->type = type, M->conn = conn, M->leaf = leaf, M->level = level;
  M->ncells = m2;
  return node_cells(C);
}

/* ---- node regions ------------------------------------------------------------------ */

/* Each node's region, or what it lies on: a loop vertex when it is one
 * exactly, else the segment found within eps. */
static void locate(cl *C, size_t v0, size_t v1) {
  const mx_qmesh *M = C->M;
#pragma omp parallel for schedule(dynamic, 1024) if (v1 - v0 > 4096)
  for (size_t v = v0; v < v1; v++) {
    uint32_t s;
    const double *p = M->xy + 2 * v;
    const long r = mx_qregion_of(C->R, p, &s);
    C->on_seg[v] = C->on_vert[v] = NONE;
    C->reg[v] = r < 0 ? -1 : (int32_t)(r > INT32_MAX ? INT32_MAX : r);
    if (r >= 0) continue;
    const uint32_t a = seg_from(C, s), b = seg_to(C, s);
    if (p[0] == vxy(C, a)[0] && p[1] == vxy(C, a)[1]) C->on_vert[v] = a;
    else if (p[0] == vxy(C, b)[0] && p[1] == vxy(C, b)[1]) C->on_vert[v] = b;
    else C->on_seg[v] = s;
  }
}

/* ---- the loops near a box ------------------------------------------------------------- */

static inline uint32_t grid_cell(double x, double lo, double h, uint32_t n) {
  const double s = (x - lo) / h;
  if (!(s >= 0.0)) return 0;
  if (s >= (double)n) return n - 1;
  return (uint32_t)s;
}

/* The interface segments (depth >= 1) whose boxes meet [lo, hi] (within
 * the index's margin), from the index's cells there, ascending, at most
 * MAXS (-1 beyond). */
static int near_segments(const cl *C, const double lo[2], const double hi[2], uint32_t *out) {
  const mx_poly_index *I = &C->R->I;
  const double mg = I->margin;
  const uint32_t i0 = grid_cell(lo[0] - mg, I->lo[0], I->h, I->nx);
  const uint32_t i1 = grid_cell(hi[0] + mg, I->lo[0], I->h, I->nx);
  const uint32_t j0 = grid_cell(lo[1] - mg, I->lo[1], I->h, I->ny);
  const uint32_t j1 = grid_cell(hi[1] + mg, I->lo[1], I->h, I->ny);
  int n = 0;
  for (uint32_t j = j0; j <= j1; j++)
    for (uint32_t i = i0; i <= i1; i++) {
      const size_t cell = (size_t)j * I->nx + i;
      for (uint32_t k = I->off[cell]; k < I->off[cell + 1]; k++) {
        const uint32_t s = I->ids[k];
        if (C->R->seg_depth[s] < 1) continue;
        const double *u = vxy(C, seg_from(C, s)), *w = vxy(C, seg_to(C, s));
        if (mx_max(u[0], w[0]) < lo[0] - mg || mx_min(u[0], w[0]) > hi[0] + mg ||
            mx_max(u[1], w[1]) < lo[1] - mg || mx_min(u[1], w[1]) > hi[1] + mg)
          continue; /* its box is apart from this one */
        int at = n;
        while (at > 0 && out[at - 1] > s) at--;
        if (at > 0 && out[at - 1] == s) continue;
        if (n == MAXS) return -1;
        memmove(out + at + 1, out + at, (size_t)(n - at) * sizeof *out);
        out[at] = s;
        n++;
      }
    }
  return n;
}

/* How segment s meets edge a-b (neither end lying on s): 0 not at all (or
 * only at an end, or along it), 1 crossing its inside, 2 through s's start
 * lying inside it (its end is the next segment's start, reported there).
 * o1, o2: the sides of s's ends (> 0 left of a-b). */
static int meets(const cl *C, uint32_t s, const double *pa, const double *pb, int *o1, int *o2) {
  const double *u = vxy(C, seg_from(C, s)), *w = vxy(C, seg_to(C, s));
  for (int d = 0; d < 2; d++)
    if (mx_max(u[d], w[d]) < mx_min(pa[d], pb[d]) || mx_min(u[d], w[d]) > mx_max(pa[d], pb[d]))
      return 0;
  *o1 = mx_orient2d(pa, pb, u);
  *o2 = mx_orient2d(pa, pb, w);
  if (*o1 * *o2 > 0 || (!*o1 && !*o2)) return 0;
  const int o3 = mx_orient2d(u, w, pa), o4 = mx_orient2d(u, w, pb);
  if (o3 * o4 >= 0) return 0; /* apart, or through an end of the edge */
  if (*o1 && *o2) return 1;
  return *o1 == 0 ? 2 : 0;
}

/* Where s crosses edge a-b, on s (the same point from either of the edge's
 * cells: the edge taken from its lower node). */
static void crossing_point(const cl *C, uint32_t s, uint32_t a, uint32_t b, double x[2]) {
  if (a > b) {
    const uint32_t t = a;
    a = b, b = t;
  }
  const double *pa = pxy(C, a), *pb = pxy(C, b);
  const double *u = vxy(C, seg_from(C, s)), *w = vxy(C, seg_to(C, s));
  const double c0 = cross3(pa, pb, u), c1 = cross3(pa, pb, w);
  double l = c0 != c1 ? c0 / (c0 - c1) : 0.0;
  l = l < 0 ? 0 : l > 1 ? 1 : l;
  x[0] = u[0] + l * (w[0] - u[0]);
  x[1] = u[1] + l * (w[1] - u[1]);
}

/* ---- moves ---------------------------------------------------------------------------- */

/* The least scaled Jacobian of the cells around v. */
static double sj_around(const cl *C, uint32_t v) {
  double s = INFINITY;
  for (uint64_t i = C->off[v]; i < C->off[v + 1]; i++) {
    const size_t c = C->ids[i];
    s = mx_min(s, sj_ids(C, C->M->conn + 4 * c, nv_of(C->M, c)));
  }
  return s;
}

/* Whether v may go to f: no cell around it below min(floor, as it was),
 * none invalid. */
static int move_ok(cl *C, uint32_t v, const double f[2], double floor_sj) {
  double *p = C->M->xy + 2 * (size_t)v;
  const double o[2] = {p[0], p[1]};
  const double before = sj_around(C, v);
  p[0] = f[0], p[1] = f[1];
  const double after = sj_around(C, v);
  p[0] = o[0], p[1] = o[1];
  return after > SJ_OK && after >= mx_min(before, floor_sj);
}

/* ---- features ----------------------------------------------------------------------------- */

typedef struct {
  double x, y;
  uint32_t vert, cell;
} feat;

static int feat_cmp(const void *a, const void *b) {
  const feat *p = a, *q = b;
  if (p->x != q->x) return p->x < q->x ? -1 : 1;
  return (p->vert > q->vert) - (p->vert < q->vert);
}

/* Whether f lies in cell c (sides included). */
static int in_cell(const cl *C, size_t c, const double f[2]) {
  const int nv = nv_of(C->M, c);
  for (int k = 0; k < nv; k++)
    if (mx_orient2d(pxy(C, C->M->conn[4 * c + k]), pxy(C, C->M->conn[4 * c + (k + 1) % nv]), f) < 0)
      return 0;
  return 1;
}

static void atomic_min_u32(uint32_t *p, uint32_t x) {
  uint32_t o = __atomic_load_n(p, __ATOMIC_RELAXED);
  while (x < o && !__atomic_compare_exchange_n(p, &o, x, 1, __ATOMIC_RELAXED, __ATOMIC_RELAXED)) {}
}

/* ctx: per cell, the feature node it is fanned about (NONE: kept); the
 * triangles of zero area (the node on one of its sides) left out. */
static void fill_fan(const cl *C, size_t c, const void *ctx, parts *P) {
  const uint32_t f = ((const uint32_t *)ctx)[c];
  if (f == NONE) return;
  const int nv = nv_of(C->M, c);
  const uint32_t *r = C->M->conn + 4 * c;
  for (int k = 0; k < nv; k++) {
    const uint32_t t[3] = {f, r[k], r[(k + 1) % nv]};
    if (mx_orient2d(pxy(C, t[0]), pxy(C, t[1]), pxy(C, t[2])) > 0) put(P, t, 3);
  }
}

/* The cell across side a-b of a cell (the one with side b-a), NONE when
 * the side is on the mesh's boundary. */
static uint32_t cell_across(const cl *C, uint32_t a, uint32_t b) {
  for (uint64_t i = C->off[b]; i < C->off[b + 1]; i++) {
    const size_t d = C->ids[i];
    const int n = nv_of(C->M, d);
    for (int q = 0; q < n; q++)
      if (C->M->conn[4 * d + q] == b && C->M->conn[4 * d + (q + 1) % n] == a) return (uint32_t)d;
  }
  return NONE;
}

static int features(cl *C) {
  const mx_qregions *R = C->R;
  const mx_poly *A = &R->all;
  uint32_t *fv = NULL;
  size_t nf = 0;
  MX_CHECK(mx_poly_features(A, &fv, &nf));
  size_t k = 0; /* the interfaces' features only, ascending */
  for (size_t i = 0; i < nf; i++)
    if (C->vout[fv[i]] != NONE && R->seg_depth[C->vout[fv[i]]] >= 1) fv[k++] = fv[i];
  nf = k;
  if (!nf) return mx_free(fv), MX_OK;
  mx_qmesh *M = C->M;
  feat *F = mx_alloc(nf * sizeof *F);
  uint32_t *where = mx_alloc(nf * sizeof *where);
  uint32_t *fan_at = mx_alloc((M->ncells + 1) * sizeof *fan_at);
  if (!F || !where || !fan_at) {
    mx_free(F), mx_free(where), mx_free(fan_at), mx_free(fv);
    return MX_ENOMEM;
  }
  for (size_t i = 0; i < nf; i++) F[i] = (feat){vxy(C, fv[i])[0], vxy(C, fv[i])[1], fv[i], NONE};
  qsort(F, nf, sizeof *F, feat_cmp);
  /* the cell holding each feature (the lowest) */
#pragma omp parallel for schedule(dynamic, 1024)
  for (size_t c = 0; c < M->ncells; c++) {
    double lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY};
    for (int j = 0; j < nv_of(M, c); j++)
      for (int a = 0; a < 2; a++) {
        lo[a] = mx_min(lo[a], pxy(C, M->conn[4 * c + j])[a]);
        hi[a] = mx_max(hi[a], pxy(C, M->conn[4 * c + j])[a]);
      }
    size_t a = 0, b = nf;
    while (a < b) {
      const size_t mid = a + (b - a) / 2;
      if (F[mid].x < lo[0]) a = mid + 1; else b = mid;
    }
    for (size_t i = a; i < nf && F[i].x <= hi[0]; i++) {
      const double f[2] = {F[i].x, F[i].y};
      if (f[1] >= lo[1] && f[1] <= hi[1] && in_cell(C, c, f))
        atomic_min_u32(&F[i].cell, (uint32_t)c);
    }
  }
  uint64_t *vk = mx_alloc((nf + 1) * sizeof *vk); /* back to the order of the vertices */
  if (!vk) {
    mx_free(F), mx_free(where), mx_free(fan_at), mx_free(fv);
    return MX_ENOMEM;
  }
  for (size_t j = 0; j < nf; j++) vk[j] = F[j].vert, where[j] = (uint32_t)j;
  int st = mx_sort_u64(vk, where, nf) == MX_OK ? MX_OK : MX_ENOMEM;
  mx_free(vk);
  for (size_t c = 0; c < M->ncells; c++) fan_at[c] = NONE;
  size_t ninsert = 0;
  for (size_t o = 0; st == MX_OK && o < nf; o++) {
    const feat *g = &F[where[o]];
    const double f[2] = {g->x, g->y};
    C->st->features++;
    if (g->cell == NONE) {
      C->st->features_missed++;
      continue;
    }
    const uint32_t *r = M->conn + 4 * (size_t)g->cell;
    const int nv = nv_of(M, g->cell);
    uint32_t cand[4];
    double dist[4];
    for (int j = 0; j < nv; j++) {
      cand[j] = r[j];
      dist[j] = hypot(pxy(C, r[j])[0] - f[0], pxy(C, r[j])[1] - f[1]);
    }
    for (int i = 1; i < nv; i++) /* closest first, then the lower id */
      for (int j = i; j > 0 && (dist[j - 1] > dist[j] ||
                                (dist[j - 1] == dist[j] && cand[j - 1] > cand[j]));
           j--) {
        const double d = dist[j];
        const uint32_t x = cand[j];
        dist[j] = dist[j - 1], cand[j] = cand[j - 1];
        dist[j - 1] = d, cand[j - 1] = x;
      }
    int done = 0;
    for (int j = 0; j < nv && !done; j++) {
      const uint32_t v = cand[j];
      if (dist[j] == 0.0) { /* a node there already */
        C->on_vert[v] = g->vert, C->on_seg[v] = NONE, C->reg[v] = -1;
        done = 1;
      } else if (!is_on(C, v) && move_ok(C, v, f, FEATURE_SJ)) {
        M->xy[2 * (size_t)v] = f[0], M->xy[2 * (size_t)v + 1] = f[1];
        if (M->nkey) M->nkey[v] = MX_QNKEY_NONE;
        C->on_vert[v] = g->vert, C->reg[v] = -1;
        C->st->features_moved++;
        done = 1;
      }
    }
    if (done) continue;
    /* a node of its own: this cell fanned, and the one across the side it
     * lies on, if any (both still whole) */
    uint32_t c2 = NONE;
    for (int j = 0; j < nv; j++)
      if (mx_orient2d(pxy(C, r[j]), pxy(C, r[(j + 1) % nv]), f) == 0)
        c2 = cell_across(C, r[j], r[(j + 1) % nv]);
    if (fan_at[g->cell] != NONE || (c2 != NONE && fan_at[c2] != NONE)) {
      C->st->features_missed++;
      continue;
    }
    const size_t v = M->nnodes;
    st = grow_nodes(C, v + 1);
    if (st != MX_OK) break;
    M->xy[2 * v] = f[0], M->xy[2 * v + 1] = f[1];
    C->on_vert[v] = g->vert, C->reg[v] = -1;
    fan_at[g->cell] = (uint32_t)v;
    if (c2 != NONE) fan_at[c2] = (uint32_t)v;
    ninsert++;
  }
  if (st == MX_OK && ninsert) {
    size_t rep;
    st = rebuild(C, fill_fan, fan_at, &rep, NULL);
    C->st->features_inserted = ninsert;
  }
  mx_free(fan_at), mx_free(where), mx_free(F), mx_free(fv);
  return st;
}

/* ---- warp ------------------------------------------------------------------------------------ */

/* The point nearest v where an interface meets the inside of one of its
 * edges, as a fraction of that edge's length: *s its segment, or *w the
 * loop vertex it is (NONE the other). INFINITY when none. */
static double nearest_crossing(const cl *C, uint32_t v, double x[2], uint32_t *s, uint32_t *w) {
  const mx_qmesh *M = C->M;
  double best = INFINITY;
  uint32_t segs[MAXS];
  for (uint64_t i = C->off[v]; i < C->off[v + 1]; i++) {
    const size_t c = C->ids[i];
    const int nv = nv_of(M, c);
    int k = 0;
    while (M->conn[4 * c + k] != v) k++;
    const uint32_t u = M->conn[4 * c + (k + 1) % nv]; /* each edge from v once: the one after */
    const double *pv = pxy(C, v), *pu = pxy(C, u);
    const double lo[2] = {mx_min(pv[0], pu[0]), mx_min(pv[1], pu[1])};
    const double hi[2] = {mx_max(pv[0], pu[0]), mx_max(pv[1], pu[1])};
    const int ns = near_segments(C, lo, hi, segs);
    const double l = hypot(pu[0] - pv[0], pu[1] - pv[1]);
    for (int j = 0; j < ns && l > 0; j++) {
      int o1, o2;
      const int how = on_s(C, u, segs[j]) ? 0 : meets(C, segs[j], pv, pu, &o1, &o2);
      if (!how) continue;
      double q[2];
      uint32_t qs = segs[j], qw = NONE;
      if (how == 2) {
        qw = seg_from(C, segs[j]), qs = NONE;
        q[0] = vxy(C, qw)[0], q[1] = vxy(C, qw)[1];
      } else {
        crossing_point(C, segs[j], v, u, q);
      }
      const double t = hypot(q[0] - pv[0], q[1] - pv[1]) / l;
      if (t < best) best = t, x[0] = q[0], x[1] = q[1], *s = qs, *w = qw;
    }
  }
  return best;
}

/* The closest point of the interfaces to v when it lies within ALPHA of
 * v's shortest edge (and no outer loop is closer): 1, with *s its segment
 * or *w the loop vertex it is. */
static int closest_point(const cl *C, uint32_t v, double x[2], uint32_t *s, uint32_t *w) {
  const mx_qmesh *M = C->M;
  const double *pv = pxy(C, v);
  double l = INFINITY;
  for (uint64_t i = C->off[v]; i < C->off[v + 1]; i++) {
    const size_t c = C->ids[i];
    const int nv = nv_of(M, c);
    for (int k = 0; k < nv; k++)
      if (M->conn[4 * c + k] == v) {
        const double *a = pxy(C, M->conn[4 * c + (k + 1) % nv]);
        const double *b = pxy(C, M->conn[4 * c + (k + nv - 1) % nv]);
        l = mx_min(l, mx_min(hypot(a[0] - pv[0], a[1] - pv[1]), hypot(b[0] - pv[0], b[1] - pv[1])));
      }
  }
  double d2;
  const uint32_t g = mx_poly_closest(&C->R->I, pv, ALPHA * l, x, &d2);
  if (g == NONE || C->R->seg_depth[g] < 1) return 0;
  *s = g, *w = NONE;
  for (int e = 0; e < 2; e++) { /* at a vertex: exactly there */
    const uint32_t u = e ? seg_to(C, g) : seg_from(C, g);
    if (x[0] == vxy(C, u)[0] && x[1] == vxy(C, u)[1]) *w = u, *s = NONE;
  }
  return 1;
}

/* Segment a-b meets the box [lo, hi] (closed): their boxes meet and the
 * box's corners are not all strictly on one side of its line. */
static int seg_meets_box(const double *a, const double *b, const double lo[2], const double hi[2]) {
  if (mx_max(a[0], b[0]) < lo[0] || mx_min(a[0], b[0]) > hi[0] || mx_max(a[1], b[1]) < lo[1] ||
      mx_min(a[1], b[1]) > hi[1])
    return 0;
  int pos = 0, neg = 0;
  for (int c = 0; c < 4; c++) {
    const double q[2] = {(c & 1) ? hi[0] : lo[0], (c & 2) ? hi[1] : lo[1]};
    const double v = cross3(a, b, q);
    pos += v > 0, neg += v < 0;
  }
  return pos < 4 && neg < 4;
}

/* Free nodes near a crossing go onto it; then, cell by cell, the moves that
 * leave a cell worse than WARP_SJ (or than it was) are undone. */
static int warp(cl *C) {
  mx_qmesh *M = C->M;
  const size_t n = M->nnodes, m = M->ncells;
  double *to = mx_alloc((2 * n + 1) * sizeof *to), *xy0 = mx_alloc((2 * n + 1) * sizeof *xy0);
  uint32_t *ts = mx_alloc((n + 1) * sizeof *ts), *tw = mx_alloc((n + 1) * sizeof *tw);
  uint8_t *go = mx_calloc(n + 1), *back = mx_calloc(n + 1);
  double *sj0 = mx_alloc((m + 1) * sizeof *sj0);
  if (!to || !xy0 || !ts || !tw || !go || !back || !sj0) {
    mx_free(to), mx_free(xy0), mx_free(ts), mx_free(tw), mx_free(go), mx_free(back), mx_free(sj0);
    return MX_ENOMEM;
  }
  /* the nodes of the cells an interface comes near, within ALPHA of their
   * size (go: 2) */
#pragma omp parallel for schedule(dynamic, 1024)
  for (size_t c = 0; c < m; c++) {
    const uint32_t *r = M->conn + 4 * c;
    const int nv = nv_of(M, c);
    double lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY};
    for (int k = 0; k < nv; k++)
      for (int a = 0; a < 2; a++)
        lo[a] = mx_min(lo[a], pxy(C, r[k])[a]), hi[a] = mx_max(hi[a], pxy(C, r[k])[a]);
    const double e = ALPHA * mx_max(hi[0] - lo[0], hi[1] - lo[1]);
    lo[0] -= e, lo[1] -= e, hi[0] += e, hi[1] += e;
    uint32_t segs[MAXS];
    const int ns = near_segments(C, lo, hi, segs);
    int near = ns < 0;
    for (int j = 0; j < ns && !near; j++)
      near = seg_meets_box(vxy(C, seg_from(C, segs[j])), vxy(C, seg_to(C, segs[j])), lo, hi);
    if (near)
      for (int k = 0; k < nv; k++) __atomic_store_n(&go[r[k]], 2, __ATOMIC_RELAXED);
  }
#pragma omp parallel for schedule(dynamic, 1024)
  for (size_t v = 0; v < n; v++) {
    const int near = go[v] == 2;
    go[v] = 0;
    if (!near || is_on(C, (uint32_t)v)) continue;
    double x[2];
    if (closest_point(C, (uint32_t)v, x, &ts[v], &tw[v]) ||
        nearest_crossing(C, (uint32_t)v, x, &ts[v], &tw[v]) < ALPHA) {
      go[v] = 1;
      to[2 * v] = x[0], to[2 * v + 1] = x[1];
    }
  }
#pragma omp parallel for schedule(static)
  for (size_t c = 0; c < m; c++) {
    const uint32_t *r = M->conn + 4 * c;
    const int nv = nv_of(M, c);
    int any = 0;
    for (int k = 0; k < nv; k++) any |= go[r[k]];
    sj0[c] = any ? sj_ids(C, r, nv) : 1.0;
  }
  memcpy(xy0, M->xy, 2 * n * sizeof *xy0);
  size_t moved = 0;
#pragma omp parallel for schedule(static) reduction(+ : moved)
  for (size_t v = 0; v < n; v++)
    if (go[v]) M->xy[2 * v] = to[2 * v], M->xy[2 * v + 1] = to[2 * v + 1], moved++;
  for (;;) { /* undo, cell by cell, until no cell is made worse */
    size_t marked = 0;
#pragma omp parallel for schedule(dynamic, 1024) reduction(+ : marked)
    for (size_t c = 0; c < m; c++) {
      const uint32_t *r = M->conn + 4 * c;
      const int nv = nv_of(M, c);
      int any = 0;
      for (int k = 0; k < nv; k++) any |= go[r[k]];
      if (!any) continue;
      const double s = sj_ids(C, r, nv);
      if (s > SJ_OK && s >= mx_min(sj0[c], WARP_SJ)) continue;
      for (int k = 0; k < nv; k++)
        if (go[r[k]]) __atomic_store_n(&back[r[k]], 1, __ATOMIC_RELAXED), marked++;
    }
    if (!marked) break;
    size_t undone = 0;
#pragma omp parallel for schedule(static) reduction(+ : undone)
    for (size_t v = 0; v < n; v++)
      if (back[v]) {
        back[v] = 0, go[v] = 0, undone++;
        M->xy[2 * v] = xy0[2 * v], M->xy[2 * v + 1] = xy0[2 * v + 1];
      }
    moved -= undone;
  }
#pragma omp parallel for schedule(static)
  for (size_t v = 0; v < n; v++)
    if (go[v]) {
      C->on_seg[v] = ts[v], C->on_vert[v] = tw[v], C->reg[v] = -1;
      if (M->nkey) M->nkey[v] = MX_QNKEY_NONE;
    }
  C->st->warped += moved;
  mx_free(to), mx_free(xy0), mx_free(ts), mx_free(tw), mx_free(go), mx_free(back), mx_free(sj0);
  return MX_OK;
}

/* ---- where the loops meet a cell ------------------------------------------------- */

enum { K_SEG = 0, K_VERT = 1 }; /* a point's key: (kind << 32) | segment or vertex */

typedef struct {
  double pos;   /* along its loop: the segment's place + the fraction along it */
  uint32_t loop;
  uint8_t bin, ain; /* the loop is inside the cell just before, just after */
  int at;       /* its corner k (0 .. nv-1), or nv + its point in pt[] */
} event;

typedef struct {
  int edge;     /* the side from corner `edge` */
  double t;     /* along it */
  uint64_t key;
} epoint;

typedef struct {
  int nv, nev, npt;
  uint32_t v[4];
  event ev[MAXE];
  epoint pt[MAXE];
} meeting;

/* Point q lies strictly inside corner k of the cell (left of both its
 * sides there). */
static int in_corner(const cl *C, const meeting *E, int k, const double *q) {
  const int n = E->nv;
  const double *p = pxy(C, E->v[k]);
  return mx_orient2d(p, pxy(C, E->v[(k + 1) % n]), q) > 0 &&
         mx_orient2d(pxy(C, E->v[(k + n - 1) % n]), p, q) > 0;
}

/* The fraction along s of node p's projection on it. */
static double along(const cl *C, uint32_t s, uint32_t p) {
  const double *u = vxy(C, seg_from(C, s)), *x = vxy(C, seg_to(C, s)), *q = pxy(C, p);
  const double d0 = x[0] - u[0], d1 = x[1] - u[1], L2 = d0 * d0 + d1 * d1;
  const double l = L2 > 0 ? ((q[0] - u[0]) * d0 + (q[1] - u[1]) * d1) / L2 : 0;
  return l < 0 ? 0 : l > 1 ? 1 : l;
}

/* Whether the loop through corner k (at fraction l of s, or at s's start
 * for a loop vertex) goes into the cell after it (ahead != 0, along s) or
 * came from inside before it (along s backwards): the far end of s lies
 * strictly inside the corner, unless the loop runs along a side of the
 * cell (the corner at its other end lies on s, ahead or behind as asked:
 * then it is on the boundary, not inside). */
static int toward(const cl *C, const meeting *E, int k, uint32_t s, double l, int ahead) {
  const int n = E->nv;
  const uint32_t p = E->v[k];
  for (int e = 0; e < 2; e++) {
    const uint32_t q = E->v[e ? (k + 1) % n : (k + n - 1) % n];
    if (!on_s(C, q, s)) continue;
    const uint32_t wq = C->on_vert[q];
    double lq;
    if (wq != NONE) lq = wq == seg_to(C, s) ? 1.0 : 0.0;
    else lq = along(C, s, q);
    const double lp = C->on_vert[p] != NONE ? (ahead ? 0.0 : 1.0) : l;
    if (ahead ? lq > lp : lq < lp) return 0;
  }
  return in_corner(C, E, k, vxy(C, ahead ? seg_to(C, s) : seg_from(C, s)));
}

static int add_event(meeting *E, double pos, uint32_t loop, int bin, int ain, int at) {
  if (E->nev == MAXE) return 0;
  E->ev[E->nev++] = (event){pos, loop, (uint8_t)bin, (uint8_t)ain, at};
  return 1;
}

/* The points where the interfaces meet cell c's boundary: its corners on
 * a loop, and where a segment (or a loop vertex) meets the inside of a
 * side. 0 when none, 1 some, -1 too many (or more segments near than
 * counted). */
static int cell_meeting(const cl *C, size_t c, meeting *E) {
  const mx_qmesh *M = C->M;
  const int nv = nv_of(M, c);
  E->nv = nv, E->nev = E->npt = 0;
  double lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY};
  for (int k = 0; k < nv; k++) {
    E->v[k] = M->conn[4 * c + k];
    for (int a = 0; a < 2; a++)
      lo[a] = mx_min(lo[a], pxy(C, E->v[k])[a]), hi[a] = mx_max(hi[a], pxy(C, E->v[k])[a]);
  }
  /* corners on a loop */
  for (int k = 0; k < nv; k++) {
    const uint32_t p = E->v[k], w = C->on_vert[p], s = C->on_seg[p];
    uint32_t sb, sa; /* the segments the loop comes along, leaves along */
    double l = 0;
    if (w != NONE) {
      sb = C->vin[w], sa = C->vout[w];
    } else if (s != NONE) {
      sb = sa = s;
      l = along(C, s, p);
    } else {
      continue;
    }
    if (C->R->seg_depth[sa] < 1) continue; /* an outer loop */
    const int bin = toward(C, E, k, sb, l, 0), ain = toward(C, E, k, sa, l, 1);
    if (!add_event(E, C->seg_rank[sa] + l, C->seg_loop[sa], bin, ain, k)) return -1;
  }
  uint32_t segs[MAXS];
  const int ns = near_segments(C, lo, hi, segs);
  if (ns < 0) return -1;
  for (int j = 0; j < ns; j++) {
    const uint32_t s = segs[j];
    for (int k = 0; k < nv; k++) {
      const uint32_t a = E->v[k], b = E->v[(k + 1) % nv];
      if (on_s(C, a, s) || on_s(C, b, s)) continue; /* met at that corner */
      const double *pa = pxy(C, a), *pb = pxy(C, b);
      int o1, o2;
      const int how = meets(C, s, pa, pb, &o1, &o2);
      if (!how) continue;
      const double *u = vxy(C, seg_from(C, s)), *w = vxy(C, seg_to(C, s));
      double t, pos;
      int bin;
      uint64_t key;
      if (how == 1) {
        const double c3 = cross3(u, w, pa), c4 = cross3(u, w, pb);
        t = c3 != c4 ? c3 / (c3 - c4) : 0.5;
        const double c0 = cross3(pa, pb, u), c1 = cross3(pa, pb, w);
        pos = C->seg_rank[s] + (c0 != c1 ? c0 / (c0 - c1) : 0.5);
        bin = o1 > 0;
        key = (uint64_t)K_SEG << 32 | s;
      } else { /* s's start on the side: the loop comes from the vertex before */
        const double d0 = pb[0] - pa[0], d1 = pb[1] - pa[1];
        t = ((u[0] - pa[0]) * d0 + (u[1] - pa[1]) * d1) / (d0 * d0 + d1 * d1);
        pos = C->seg_rank[s];
        bin = mx_orient2d(pa, pb, vxy(C, seg_from(C, C->vin[seg_from(C, s)]))) > 0;
        key = (uint64_t)K_VERT << 32 | seg_from(C, s);
      }
      if (E->npt == MAXE) return -1;
      E->pt[E->npt] = (epoint){k, t, key};
      if (!add_event(E, pos, C->seg_loop[s], bin, o2 > 0, nv + E->npt)) return -1;
      E->npt++;
    }
  }
  return E->nev > 0;
}

/* ---- the points' nodes -------------------------------------------------------------- */

typedef struct {
  uint64_t edge, key;
} ptkey;

static int ptkey_cmp(const void *a, const void *b) {
  const ptkey *p = a, *q = b;
  if (p->edge != q->edge) return p->edge < q->edge ? -1 : 1;
  return (p->key > q->key) - (p->key < q->key);
}

/* What the cut knows: the points' keys (sorted) and their first node; per
 * cell the slices of its events and points (CSR, ev_off and pt_off: m + 1
 * entries, empty for the cells the loops do not meet) and whether they
 * meet it (1) or could not be listed (2). */
typedef struct {
  const ptkey *pk;
  size_t np;
  uint32_t first;
  const uint8_t *hit;
  const uint64_t *ev_off, *pt_off;
  const event *ev;
  const epoint *pt;
} cut_ctx;

static uint32_t point_node(const cut_ctx *X, uint64_t edge, uint64_t key) {
  size_t lo = 0, hi = X->np;
  const ptkey k = {edge, key};
  while (lo < hi) {
    const size_t mid = lo + (hi - lo) / 2;
    if (ptkey_cmp(&X->pk[mid], &k) < 0) lo = mid + 1; else hi = mid;
  }
  return lo < X->np && !ptkey_cmp(&X->pk[lo], &k) ? X->first + (uint32_t)lo : NONE;
}

/* ---- the cut of one cell ------------------------------------------------------------ */

typedef struct {
  int i, j, parent;
} chord;

static int event_cmp(const event *a, const event *b) {
  if (a->loop != b->loop) return a->loop < b->loop ? -1 : 1;
  if (a->pos != b->pos) return a->pos < b->pos ? -1 : 1;
  return (a->at > b->at) - (a->at < b->at);
}

/* The parts of cell c cut along the loops' chords (none: kept). */
static void fill_cut(const cl *C, size_t c, const void *ctx, parts *P) {
  const cut_ctx *X = ctx;
  if (!X->hit[c]) return;
  if (X->hit[c] == 2) {
    P->bad = 1;
    return;
  }
  meeting E;
  E.nv = nv_of(C->M, c);
  for (int k = 0; k < E.nv; k++) E.v[k] = C->M->conn[4 * c + k];
  E.nev = (int)(X->ev_off[c + 1] - X->ev_off[c]);
  E.npt = (int)(X->pt_off[c + 1] - X->pt_off[c]);
  memcpy(E.ev, X->ev + X->ev_off[c], (size_t)E.nev * sizeof *E.ev);
  memcpy(E.pt, X->pt + X->pt_off[c], (size_t)E.npt * sizeof *E.pt);
  const int nv = E.nv;
  /* the boundary: corners and points along each side */
  uint32_t cyc[4 + MAXE];
  int side[4 + MAXE], pos_of[4 + MAXE], m = 0;
  for (int k = 0; k < nv; k++) {
    pos_of[k] = m, side[m] = -1 - k, cyc[m++] = E.v[k];
    int idx[MAXE], n = 0;
    for (int i = 0; i < E.npt; i++)
      if (E.pt[i].edge == k) {
        int at = n;
        while (at > 0) {
          const epoint *o = &E.pt[idx[at - 1]];
          if (o->t < E.pt[i].t || (o->t == E.pt[i].t && o->key < E.pt[i].key)) break;
          at--;
        }
        memmove(idx + at + 1, idx + at, (size_t)(n - at) * sizeof *idx);
        idx[at] = i, n++;
      }
    for (int q = 0; q < n; q++) {
      const uint32_t id = point_node(X, edge_key(E.v[k], E.v[(k + 1) % nv]), E.pt[idx[q]].key);
      if (id == NONE) {
        P->bad = 1;
        return;
      }
      pos_of[nv + idx[q]] = m, side[m] = k, cyc[m++] = id;
    }
  }
  /* the events of each loop in its order: in, then out, pairs */
  event ev[MAXE];
  memcpy(ev, E.ev, (size_t)E.nev * sizeof *ev);
  for (int i = 1; i < E.nev; i++)
    for (int j = i; j > 0 && event_cmp(&ev[j - 1], &ev[j]) > 0; j--) {
      const event t = ev[j];
      ev[j] = ev[j - 1], ev[j - 1] = t;
    }
  chord ch[MAXE];
  int nch = 0;
  for (int a = 0; a < E.nev;) {
    int b = a;
    while (b < E.nev && ev[b].loop == ev[a].loop) b++;
    for (int i = a; i < b; i++) {
      const event *e = &ev[i], *f = &ev[i + 1 < b ? i + 1 : a];
      if (e->ain != f->bin) {
        P->bad = 1;
        return;
      }
      if (!e->ain) continue;
      int x = pos_of[e->at], y = pos_of[f->at];
      if (x > y) {
        const int t = x;
        x = y, y = t;
      }
      /* along the boundary (one side holds both): no cut */
      const int sx = side[x], sy = side[y];
      const int kx0 = sx >= 0 ? sx : -1 - sx, kx1 = sx >= 0 ? sx : (-1 - sx + nv - 1) % nv;
      const int ky0 = sy >= 0 ? sy : -1 - sy, ky1 = sy >= 0 ? sy : (-1 - sy + nv - 1) % nv;
      if (x == y || kx0 == ky0 || kx0 == ky1 || kx1 == ky0 || kx1 == ky1) continue;
      ch[nch++] = (chord){x, y, -1};
    }
    a = b;
  }
  if (!nch) return;
  /* nested or apart, never crossing: the tree of the chords */
  for (int i = 1; i < nch; i++)
    for (int j = i;
         j > 0 && (ch[j - 1].i > ch[j].i || (ch[j - 1].i == ch[j].i && ch[j - 1].j < ch[j].j));
         j--) {
      const chord t = ch[j];
      ch[j] = ch[j - 1], ch[j - 1] = t;
    }
  int stack[MAXE], top = 0;
  for (int i = 0; i < nch; i++) {
    while (top > 0 && ch[stack[top - 1]].j <= ch[i].i) top--;
    if (top > 0) {
      const chord *o = &ch[stack[top - 1]];
      if (ch[i].j > o->j || (ch[i].i == o->i && ch[i].j == o->j)) {
        P->bad = 1;
        return;
      }
      ch[i].parent = stack[top - 1];
    }
    stack[top++] = i;
  }
  /* the parts: the whole boundary (-1) and each chord's side, less their
   * children's */
  for (int q = -1; q < nch; q++) {
    uint32_t poly[4 + MAXE];
    int n = 0, k = q < 0 ? 0 : ch[q].i;
    const int end = q < 0 ? m : ch[q].j;
    while (k < end || (q >= 0 && k == end)) {
      poly[n++] = cyc[k];
      if (q >= 0 && k == end) break;
      int jump = -1;
      for (int i = 0; i < nch && jump < 0; i++)
        if (ch[i].parent == q && ch[i].i == k) jump = ch[i].j;
      k = jump >= 0 ? jump : k + 1;
    }
    if (n < 3) {
      P->bad = 1;
      return;
    }
    put_piece(C, poly, n, P);
    if (P->bad) return;
  }
}

static int cut(cl *C) {
  mx_qmesh *M = C->M;
  const size_t m = M->ncells;
  /* which cells the loops meet, and how much */
  uint64_t *ev_off = mx_alloc((m + 1) * sizeof *ev_off);
  uint64_t *pt_off = mx_alloc((m + 1) * sizeof *pt_off);
  uint8_t *hit = mx_alloc(m + 1);
  if (!ev_off || !pt_off || !hit) return mx_free(ev_off), mx_free(pt_off), mx_free(hit), MX_ENOMEM;
#pragma omp parallel for schedule(dynamic, 1024)
  for (size_t c = 0; c < m; c++) {
    meeting E;
    const int got = cell_meeting(C, c, &E);
    hit[c] = got < 0 ? 2 : got > 0;
    ev_off[c] = got > 0 ? (uint64_t)E.nev : 0;
    pt_off[c] = got > 0 ? (uint64_t)E.npt : 0;
  }
  const size_t nev = (size_t)mx_scan_u64(ev_off, m), tot = (size_t)mx_scan_u64(pt_off, m);
  ev_off[m] = nev, pt_off[m] = tot;
  /* their events and points, kept; the points' keys, from every cell */
  event *ev = mx_alloc((nev + 1) * sizeof *ev);
  epoint *pt = mx_alloc((tot + 1) * sizeof *pt);
  ptkey *pk = mx_alloc((tot + 1) * sizeof *pk);
  int st = ev && pt && pk ? MX_OK : MX_ENOMEM;
  if (st == MX_OK) {
#pragma omp parallel for schedule(dynamic, 1024)
    for (size_t c = 0; c < m; c++) {
      meeting E;
      if (hit[c] != 1 || cell_meeting(C, c, &E) <= 0) continue;
      memcpy(ev + ev_off[c], E.ev, (size_t)E.nev * sizeof *ev);
      memcpy(pt + pt_off[c], E.pt, (size_t)E.npt * sizeof *pt);
      for (int i = 0; i < E.npt; i++)
        pk[pt_off[c] + (size_t)i] =
            (ptkey){edge_key(E.v[E.pt[i].edge], E.v[(E.pt[i].edge + 1) % E.nv]), E.pt[i].key};
    }
    qsort(pk, tot, sizeof *pk, ptkey_cmp);
  }
  size_t np = 0;
  for (size_t i = 0; st == MX_OK && i < tot; i++)
    if (!np || ptkey_cmp(&pk[np - 1], &pk[i])) pk[np++] = pk[i];
  const size_t n0 = M->nnodes;
  if (st == MX_OK) st = grow_nodes(C, n0 + np);
  if (st == MX_OK) {
#pragma omp parallel for schedule(static)
    for (size_t i = 0; i < np; i++) {
      const uint32_t id = (uint32_t)pk[i].key;
      const uint32_t a = (uint32_t)(pk[i].edge >> 32), b = (uint32_t)pk[i].edge;
      double *x = M->xy + 2 * (n0 + i);
      if (pk[i].key >> 32 == K_VERT) {
        x[0] = vxy(C, id)[0], x[1] = vxy(C, id)[1];
        C->on_vert[n0 + i] = id;
      } else {
        crossing_point(C, id, a, b, x);
        C->on_seg[n0 + i] = id;
      }
      C->reg[n0 + i] = -1;
    }
    C->st->crossings = np;
    const cut_ctx X = {pk, np, (uint32_t)n0, hit, ev_off, pt_off, ev, pt};
    size_t rep = 0, bad = 0;
    st = rebuild(C, fill_cut, &X, &rep, &bad);
    C->st->cut = rep;
    C->st->unresolved = bad;
  }
  mx_free(pk), mx_free(hit), mx_free(ev), mx_free(pt), mx_free(ev_off), mx_free(pt_off);
  return st;
}

/* ---- smoothing --------------------------------------------------------------------- */

/* The least scaled Jacobian of the cells around v with v at p. */
static double sj_at(cl *C, uint32_t v, const double p[2]) {
  double *q = C->M->xy + 2 * (size_t)v;
  const double o[2] = {q[0], q[1]};
  q[0] = p[0], q[1] = p[1];
  const double s = sj_around(C, v);
  q[0] = o[0], q[1] = o[1];
  return s;
}

/* The nodes of the cells along the interfaces move, one after the other in
 * the order of their ids (a sequential loop: the result does not depend on
 * the threads), SMOOTH_SWEEPS times, to the mean of the corners of their
 * cells, or half-way, when that raises the least scaled Jacobian around
 * them (below SMOOTH_SJ; above, they stay): free nodes anywhere (their
 * cells stay valid, so they stay in their region), nodes on an interface
 * segment along it (projected, kept inside the segment). Nodes on a loop
 * vertex or an outer loop stay. */
static int smooth(cl *C) {
  const mx_qmesh *M = C->M;
  const size_t n = M->nnodes;
  uint8_t *band = mx_calloc(n + 1);
  if (!band) return MX_ENOMEM;
  for (size_t v = 0; v < n; v++) {
    const uint32_t s = C->on_seg[v];
    if (!(s != NONE && C->R->seg_depth[s] >= 1) && C->on_vert[v] == NONE) continue;
    if (C->on_vert[v] != NONE && C->R->seg_depth[C->vout[C->on_vert[v]]] < 1) continue;
    for (uint64_t i = C->off[v]; i < C->off[v + 1]; i++) {
      const size_t c = C->ids[i];
      for (int k = 0; k < nv_of(M, c); k++) band[M->conn[4 * c + k]] = 1;
    }
  }
  size_t moved = 0;
  for (int sweep = 0; sweep < SMOOTH_SWEEPS; sweep++)
    for (size_t v = 0; v < n; v++) {
      if (!band[v] || C->on_vert[v] != NONE || C->off[v] == C->off[v + 1]) continue;
      const uint32_t s = C->on_seg[v];
      if (s != NONE && C->R->seg_depth[s] < 1) continue; /* on an outer loop */
      const double *p = pxy(C, (uint32_t)v);
      double best = sj_around(C, (uint32_t)v), to[2] = {p[0], p[1]};
      if (best >= SMOOTH_SJ) continue; /* its cells need nothing */
      double g[2] = {0, 0};
      int k = 0;
      for (uint64_t i = C->off[v]; i < C->off[v + 1]; i++) {
        const size_t c = C->ids[i];
        for (int j = 0; j < nv_of(M, c); j++) {
          const uint32_t u = M->conn[4 * c + j];
          if (u == v) continue;
          g[0] += pxy(C, u)[0], g[1] += pxy(C, u)[1], k++;
        }
      }
      g[0] /= k, g[1] /= k;
      for (int h = 0; h < 2; h++) {
        double q[2] = {h ? 0.5 * (p[0] + g[0]) : g[0], h ? 0.5 * (p[1] + g[1]) : g[1]};
        if (s != NONE) { /* along the segment, inside it */
          const double *a = vxy(C, seg_from(C, s)), *b = vxy(C, seg_to(C, s));
          const double d0 = b[0] - a[0], d1 = b[1] - a[1], l2 = d0 * d0 + d1 * d1;
          double l = ((q[0] - a[0]) * d0 + (q[1] - a[1]) * d1) / l2;
          l = l < 0.01 ? 0.01 : l > 0.99 ? 0.99 : l;
          q[0] = a[0] + l * d0, q[1] = a[1] + l * d1;
        }
        const double t = sj_at(C, (uint32_t)v, q);
        if (t > best + 1e-9) best = t, to[0] = q[0], to[1] = q[1];
      }
      if (to[0] != p[0] || to[1] != p[1]) {
        C->M->xy[2 * v] = to[0], C->M->xy[2 * v + 1] = to[1];
        if (M->nkey) M->nkey[v] = MX_QNKEY_NONE;
        moved++;
      }
    }
  C->st->smoothed = moved;
  mx_free(band);
  return MX_OK;
}

/* ---- regions of the cells ---------------------------------------------------------- */

static int label(cl *C, uint16_t **region) {
  const mx_qmesh *M = C->M;
  const size_t m = M->ncells;
  uint16_t *lab = mx_alloc((m + 1) * sizeof *lab);
  if (!lab) return MX_ENOMEM;
  size_t across = 0;
#pragma omp parallel for schedule(dynamic, 1024) reduction(+ : across)
  for (size_t c = 0; c < m; c++) {
    const uint32_t *r = M->conn + 4 * c;
    const int nv = nv_of(M, c);
    int32_t lo = INT32_MAX, hi = -1;
    for (int k = 0; k < nv; k++)
      if (C->reg[r[k]] >= 0) {
        lo = C->reg[r[k]] < lo ? C->reg[r[k]] : lo;
        hi = C->reg[r[k]] > hi ? C->reg[r[k]] : hi;
      }
    long d = hi;
    if (hi < 0 || lo != hi) { /* on loops only, or across: the centroid's */
      double p[2] = {0, 0};
      for (int k = 0; k < nv; k++) p[0] += pxy(C, r[k])[0] / nv, p[1] += pxy(C, r[k])[1] / nv;
      uint32_t s;
      d = mx_qregion_of(C->R, p, &s);
      if (d < 0) d = C->R->seg_depth[s] + 1;
      across += hi >= 0 && lo != hi;
    }
    if (d < 1) d = 1; /* the boundary step's cells are the domain's */
    lab[c] = (uint16_t)(d > UINT16_MAX ? UINT16_MAX : d);
  }
  C->st->across = across;
  *region = lab;
  return MX_OK;
}

int mx_qcleave(mx_qmesh *M, const mx_qregions *R, uint16_t **region, mx_qcleave_stats *stats) {
  memset(stats, 0, sizeof *stats);
  *region = NULL;
  cl C = {.M = M, .R = R, .st = stats};
  const size_t n = M->nnodes;
  C.on_seg = mx_alloc((n + 1) * sizeof *C.on_seg);
  C.on_vert = mx_alloc((n + 1) * sizeof *C.on_vert);
  C.reg = mx_alloc((n + 1) * sizeof *C.reg);
  int st = C.on_seg && C.on_vert && C.reg ? loops(&C) : MX_ENOMEM;
  if (st == MX_OK) {
    locate(&C, 0, n);
    st = node_cells(&C);
  }
  if (st == MX_OK && R->deepest > 1) st = features(&C);
  if (st == MX_OK && R->deepest > 1) st = warp(&C);
  if (st == MX_OK && R->deepest > 1) st = cut(&C);
  if (st == MX_OK && R->deepest > 1) st = smooth(&C);
  if (st == MX_OK) st = label(&C, region);
  mx_free(C.on_seg), mx_free(C.on_vert), mx_free(C.reg), mx_free(C.off), mx_free(C.ids);
  mx_free(C.seg_loop), mx_free(C.seg_rank), mx_free(C.vin), mx_free(C.vout);
  return st;
}
