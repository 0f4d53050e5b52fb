/* The band of the boundary step (qinternal.h): the cells Algorithm 2 may
 * change, taken out of the transition mesh and put back, so that its many
 * passes run over the few cells near the polylines, not the whole mesh.
 *
 * A leaf is clear when it meets no domain segment (not MX_Q_BOUND) and its
 * top quadrant (its ancestor meeting none whose parent meets some, or its
 * root) lies farther than 4 eps from every segment: no segment that could
 * come that close (those of the slice of the ancestor holding the top away
 * from its sides, else those the segment index lists around it) meets it
 * widened by 8 eps; once per top quadrant, the leaves being in Morton
 * order. A meshed leaf is not MX_Q_OUT, so a clear one lies inside the
 * domain, and mx_poly_inside answers 1 for each of its nodes (`inside`). A
 * node is deep when every cell around it comes from a clear leaf: the
 * leaves around it then cover a disc of half the least side of its cells
 * about it with no segment in it (it touches no leaf outside the domain:
 * both would meet the polylines), so it is no close node either (radius
 * close_ratio sqrt 2 side, under half a side). Every step of the boundary
 * moves only nodes on the polylines, close to them, outside, or the
 * feature nodes (nodes of the leaves holding the features, which meet the
 * segments: not clear), and changes only cells with such a node or without
 * an inside node: a cell whose nodes are all deep stays as it is (valid:
 * a transition pattern). The band is the cells with a node that is not
 * deep, with all their nodes (the deep ones frozen), so every node that
 * can move has all its cells in the band. It needs every node of M in some
 * cell (as the transition makes it), the leaves, and the quadtree's
 * parents and segment slices.
 *
 * Every pass is parallel over cells or nodes, its output placed by prefix
 * sums: the band does not depend on the thread count. The merge compacts
 * M in place by chunks (the kept cells and nodes keep their order; outputs
 * landing in the chunk before wait in a small buffer); only when band cells
 * split in two outnumber the removed ones before them do the cells get new
 * arrays. */
#include <math.h>
#include <omp.h>
#include <string.h>

#include "base/common.h"
#include "quad/qinternal.h"
#include "base/scan.h"

#define NONE UINT32_MAX
#define BLK 4096 /* cells per block of the counting passes */

static int nv_of(const mx_qmesh *M, size_t c) { return M->type[c] == MX_QQUAD ? 4 : 3; }

static size_t lower_bound32(const uint32_t *a, size_t n, uint32_t v) {
  size_t lo = 0, hi = n;
  while (lo < hi) {
    const size_t mid = lo + (hi - lo) / 2;
    if (a[mid] < v) lo = mid + 1; else hi = mid;
  }
  return lo;
}

void mx_qband_free(mx_qband *B) {
  mx_qmesh_free(&B->L);
  mx_free(B->gnode), mx_free(B->gcell), mx_free(B->deep), mx_free(B->inside), mx_free(B->open);
  mx_free(B->act);
  memset(B, 0, sizeof *B);
}

/* ---- clear leaves ---------------------------------------------------------- */

/* Per thread: the last leaf asked, and the key range of the last top
 * quadrant found (its descendants' keys) with its answer. */
typedef struct {
  const mx_poly_index *I;
  const mx_qtree *T;
  const uint32_t *leaves;
  uint32_t leaf;
  int leaf_clear;
  uint64_t top_lo, top_hi;
  int top_clear;
} clear_memo;

/* Closed test (as the quadtree's): segment a-b meets the box unless their
 * bounding boxes are apart or the box's 4 corners lie strictly on one side
 * of its line. */
static int seg_meets_box(const double *a, const double *b, const double lo[2],
                         const double hi[2]) {
  if (mx_max(a[0], b[0]) < lo[0] || mx_min(a[0], b[0]) > hi[0] || mx_max(a[1], b[1]) < lo[1] ||
      mx_min(a[1], b[1]) > hi[1])
    return 0;
  const double dx = b[0] - a[0], dy = b[1] - a[1];
  int pos = 0, neg = 0;
  for (int c = 0; c < 4; c++) {
    const double px = (c & 1) ? hi[0] : lo[0], py = (c & 2) ? hi[1] : lo[1];
    const double v = dx * (py - a[1]) - dy * (px - a[0]);
    pos += v > 0;
    neg += v < 0;
  }
  return pos < 4 && neg < 4;
}

static uint32_t index_cell(double x, double lo, double h, uint32_t n) {
  const double t = (x - lo) / h;
  if (!(t >= 0.0)) return 0;
  if (t >= (double)n) return n - 1;
  return (uint32_t)t;
}

/* The ancestor of q (not q) whose box holds q's away from its sides (a
 * segment meeting q widened by 8 eps meets that ancestor, so it is in the
 * ancestor's slice); NONE when q touches its root's sides. */
static uint32_t holding_ancestor(const mx_qtree *T, uint32_t q) {
  uint32_t x, y;
  mx_qkey_xy(T->key[q], &x, &y);
  const uint32_t s = mx_qsize(T->level[q]);
  for (uint32_t a = T->parent[q]; a != NONE; a = T->parent[a]) {
    uint32_t ax, ay;
    mx_qkey_xy(T->key[a], &ax, &ay);
    const uint32_t S = mx_qsize(T->level[a]);
    if (x != ax && y != ay && x + s != ax + S && y + s != ay + S) return a;
  }
  return NONE;
}

/* Quadrant q lies farther than 4 eps from every segment: no segment that
 * may come that close (those of the slice of the ancestor holding it, or
 * those the index lists in the cells it covers) meets it widened by 8 eps. */
static int far_from_segments(const clear_memo *C, uint32_t q) {
  const mx_qtree *T = C->T;
  const mx_poly_index *I = C->I;
  const mx_poly *P = I->P;
  if (!P || P->ns == 0) return 1;
  uint32_t x, y;
  mx_qkey_xy(T->key[q], &x, &y);
  const uint32_t s = mx_qsize(T->level[q]);
  const double d = 8.0 * I->eps;
  const double lo[2] = {T->grid.origin[0] + T->grid.unit * (double)x - d,
                        T->grid.origin[1] + T->grid.unit * (double)y - d};
  const double hi[2] = {T->grid.origin[0] + T->grid.unit * (double)(x + s) + d,
                        T->grid.origin[1] + T->grid.unit * (double)(y + s) + d};
#define MEETS(sg)                                                                   \
  seg_meets_box(P->xy + 2 * (size_t)P->seg[2 * (size_t)(sg)],                       \
                P->xy + 2 * (size_t)P->seg[2 * (size_t)(sg) + 1], lo, hi)
  const uint32_t a = holding_ancestor(T, q);
  if (a != NONE) {
    const uint32_t *sl = T->seg_pool + T->seg_off[a];
    for (uint32_t k = 0; k < T->seg_cnt[a]; k++)
      if (MEETS(sl[k])) return 0;
    return 1;
  }
  const uint32_t i0 = index_cell(lo[0], I->lo[0], I->h, I->nx);
  const uint32_t i1 = index_cell(hi[0], I->lo[0], I->h, I->nx);
  const uint32_t j0 = index_cell(lo[1], I->lo[1], I->h, I->ny);
  const uint32_t j1 = index_cell(hi[1], I->lo[1], I->h, I->ny);
  for (uint32_t j = j0; j <= j1; j++)
    for (uint32_t i = i0; i <= i1; i++) {
      const size_t cell = (size_t)j * I->nx + i;
      for (uint32_t k = I->off[cell]; k < I->off[cell + 1]; k++)
        if (MEETS(I->ids[k])) return 0;
    }
  return 1;
#undef MEETS
}

static int leaf_clear(clear_memo *C, uint32_t li) {
  if (li == C->leaf) return C->leaf_clear;
  const mx_qtree *T = C->T;
  uint32_t q = C->leaves[li];
  int r;
  if (T->flags[q] & MX_Q_BOUND) r = 0;
  else if (T->key[q] >= C->top_lo && T->key[q] < C->top_hi) r = C->top_clear;
  else {
    while (T->parent[q] != NONE && !(T->flags[T->parent[q]] & MX_Q_BOUND)) q = T->parent[q];
    C->top_lo = T->key[q];
    C->top_hi = T->key[q] + (1ULL << 2 * (MX_QMAX_LEVEL - T->level[q]));
    r = C->top_clear = far_from_segments(C, q);
  }
  C->leaf = li;
  C->leaf_clear = r;
  return r;
}

/* act[c] = QBAND_OPEN for the cells of leaves not clear, whose nodes are
 * not deep (nondeep). */
static void mark_open(const mx_poly_index *I, const mx_qtree *T, const uint32_t *leaves,
                      const mx_qmesh *M, uint8_t *act, uint8_t *nondeep) {
#pragma omp parallel
  {
    clear_memo C = {I, T, leaves, NONE, 0, 1, 0, 0};
#pragma omp for schedule(static)
    for (size_t c = 0; c < M->ncells; c++) {
      const int open = !leaf_clear(&C, M->leaf[c]);
      act[c] = (uint8_t)open;
      if (open)
        for (int k = 0; k < nv_of(M, c); k++)
          __atomic_store_n(&nondeep[M->conn[4 * c + k]], 1, __ATOMIC_RELAXED);
    }
  }
}

/* ---- the band ----------------------------------------------------------------- */

/* The cells with a node not deep (QBAND_IN), ascending. */
static int band_cells(const mx_qmesh *M, const uint8_t *nondeep, uint8_t *act, uint32_t **gcell,
                      size_t *ma) {
  const size_t m = M->ncells, nb = (m + BLK - 1) / BLK;
  uint64_t *cnt = mx_alloc((nb + 1) * sizeof *cnt);
  if (!cnt) return MX_ENOMEM;
#pragma omp parallel for schedule(static)
  for (size_t b = 0; b < nb; b++) {
    const size_t hi = (b + 1) * BLK < m ? (b + 1) * BLK : m;
    uint64_t k = 0;
    for (size_t c = b * BLK; c < hi; c++) {
      int in = act[c] & QBAND_OPEN;
      for (int j = 0; !in && j < nv_of(M, c); j++) in = nondeep[M->conn[4 * c + j]];
      if (in) act[c] |= QBAND_IN, k++;
    }
    cnt[b] = k;
  }
  *ma = mx_scan_u64(cnt, nb);
  uint32_t *g = *gcell = mx_alloc((*ma + 1) * sizeof *g);
  if (!g) return mx_free(cnt), MX_ENOMEM;
#pragma omp parallel for schedule(static)
  for (size_t b = 0; b < nb; b++) {
    const size_t hi = (b + 1) * BLK < m ? (b + 1) * BLK : m;
    uint64_t k = cnt[b];
    for (size_t c = b * BLK; c < hi; c++)
      if (act[c] & QBAND_IN) g[k++] = (uint32_t)c;
  }
  mx_free(cnt);
  return MX_OK;
}

/* The nodes of the band's cells, ascending: marked (bit 1 of mark), then
 * listed block by block. */
static int band_nodes(const mx_qmesh *M, const uint32_t *gcell, size_t ma, uint8_t *mark,
                      uint32_t **gnode, size_t *nl) {
  const size_t n = M->nnodes, nb = (n + BLK - 1) / BLK;
#pragma omp parallel for schedule(static)
  for (size_t i = 0; i < ma; i++)
    for (int j = 0; j < nv_of(M, gcell[i]); j++)
      __atomic_fetch_or(&mark[M->conn[4 * (size_t)gcell[i] + j]], 2, __ATOMIC_RELAXED);
  uint64_t *cnt = mx_alloc((nb + 1) * sizeof *cnt);
  if (!cnt) return MX_ENOMEM;
#pragma omp parallel for schedule(static)
  for (size_t b = 0; b < nb; b++) {
    uint64_t k = 0;
    for (size_t v = b * BLK; v < n && v < (b + 1) * BLK; v++) k += mark[v] >> 1 & 1;
    cnt[b] = k;
  }
  *nl = mx_scan_u64(cnt, nb);
  uint32_t *g = *gnode = mx_alloc((*nl + 1) * sizeof *g);
  if (!g) return mx_free(cnt), MX_ENOMEM;
#pragma omp parallel for schedule(static)
  for (size_t b = 0; b < nb; b++) {
    uint64_t k = cnt[b];
    for (size_t v = b * BLK; v < n && v < (b + 1) * BLK; v++)
      if (mark[v] & 2) g[k++] = (uint32_t)v;
  }
  mx_free(cnt);
  return MX_OK;
}

/* The position of v in a (ascending, holding it), searched from *at
 * outwards (the cells' nodes come near each other's). */
static uint32_t find_from(const uint32_t *a, size_t n, uint32_t v, size_t *at) {
  size_t lo, hi, step = 1, i = *at < n ? *at : n - 1;
  if (a[i] < v) {
    lo = i;
    while (i + step < n && a[i + step] < v) lo = i + step, step *= 2;
    hi = i + step < n ? i + step + 1 : n;
  } else {
    hi = i + 1;
    while (i >= step && a[i - step] >= v) hi = i - step + 1, step *= 2;
    lo = i >= step ? i - step : 0;
  }
  *at = lo + lower_bound32(a + lo, hi - lo, v);
  return (uint32_t)*at;
}

/* L: the band's cells on local node ids; deep, inside and open. */
static int band_mesh(const mx_qmesh *M, mx_qband *B, size_t ma, size_t nl, const uint8_t *nondeep) {
  mx_qmesh *L = &B->L;
  L->nnodes = nl;
  L->ncells = ma;
  L->xy = mx_alloc((2 * nl + 1) * sizeof *L->xy);
  L->type = mx_alloc(ma + 1);
  L->level = mx_alloc(ma + 1);
  L->leaf = mx_alloc((ma + 1) * sizeof *L->leaf);
  L->conn = mx_alloc((4 * ma + 1) * sizeof *L->conn);
  B->deep = mx_alloc(nl + 1);
  B->inside = mx_alloc(nl + 1);
  B->open = mx_alloc(ma + 1);
  if (!L->xy || !L->type || !L->level || !L->leaf || !L->conn || !B->deep || !B->inside ||
      !B->open)
    return MX_ENOMEM;
  const int whole = B->act == NULL;
#pragma omp parallel for schedule(static)
  for (size_t j = 0; j < nl; j++) {
    const size_t g = whole ? j : B->gnode[j];
    L->xy[2 * j] = M->xy[2 * g];
    L->xy[2 * j + 1] = M->xy[2 * g + 1];
    B->deep[j] = B->inside[j] = nondeep ? !(nondeep[g] & 1) : 0;
  }
#pragma omp parallel
  {
    size_t at = 0;
#pragma omp for schedule(static)
    for (size_t i = 0; i < ma; i++) {
      const size_t g = whole ? i : B->gcell[i];
      L->type[i] = M->type[g];
      L->level[i] = M->level[g];
      L->leaf[i] = M->leaf[g];
      B->open[i] = whole ? 1 : B->act[g] & QBAND_OPEN;
      for (int k = 0; k < 4; k++) {
        const uint32_t v = M->conn[4 * g + k];
        L->conn[4 * i + k] = whole || v == NONE ? v : find_from(B->gnode, nl, v, &at);
      }
    }
  }
  /* the nodes of clear leaves are inside */
#pragma omp parallel for schedule(static)
  for (size_t i = 0; i < ma; i++)
    if (!B->open[i])
      for (int k = 0; k < nv_of(L, i); k++)
        __atomic_store_n(&B->inside[L->conn[4 * i + k]], 1, __ATOMIC_RELAXED);
  return MX_OK;
}

static int whole_band(const mx_qmesh *M, mx_qband *B) {
  B->gcell = mx_alloc((M->ncells + 1) * sizeof *B->gcell);
  B->gnode = mx_alloc((M->nnodes + 1) * sizeof *B->gnode);
  if (!B->gcell || !B->gnode) return MX_ENOMEM;
#pragma omp parallel for schedule(static)
  for (size_t i = 0; i < M->ncells; i++) B->gcell[i] = (uint32_t)i;
#pragma omp parallel for schedule(static)
  for (size_t j = 0; j < M->nnodes; j++) B->gnode[j] = (uint32_t)j;
  return band_mesh(M, B, M->ncells, M->nnodes, NULL);
}

int mx_qband_extract(const mx_poly_index *I, const mx_qtree *T, const uint32_t *leaves, int whole,
                     const mx_qmesh *M, mx_qband *B) {
  memset(B, 0, sizeof *B);
  B->m = M->ncells;
  B->n = M->nnodes;
  if (M->ncells >= NONE || M->nnodes >= NONE) {
    mx_error(NULL, 0, "boundary: %zu cells, %zu nodes: too many", M->ncells, M->nnodes);
    return MX_EINPUT;
  }
  int st;
  if (whole || !leaves || !T) st = whole_band(M, B);
  else {
    uint8_t *nondeep = mx_calloc(B->n + 1);
    B->act = mx_alloc(B->m + 1);
    size_t ma = 0, nl = 0;
    st = nondeep && B->act ? MX_OK : MX_ENOMEM;
    if (st == MX_OK) {
      mark_open(I, T, leaves, M, B->act, nondeep);
      st = band_cells(M, nondeep, B->act, &B->gcell, &ma);
    }
    if (st == MX_OK) st = band_nodes(M, B->gcell, ma, nondeep, &B->gnode, &nl);
    if (st == MX_OK) st = band_mesh(M, B, ma, nl, nondeep);
    mx_free(nondeep);
  }
  if (st != MX_OK) mx_qband_free(B);
  return st;
}

/* ---- back into M ------------------------------------------------------------------ */

/* A node's new id: its id less the removed nodes before it (U ascending):
 * from a table of new ids when the removed nodes are many, else searched,
 * the last interval between two removed ones remembered. */
typedef struct {
  const uint32_t *U, *map;
  size_t nu, r;
  int64_t lo, hi; /* ids strictly between: r removed before */
} ranker;

static inline uint32_t renum(ranker *R, uint32_t v) {
  if (R->map) return R->map[v];
  if (!((int64_t)v > R->lo && (int64_t)v < R->hi)) {
    R->r = lower_bound32(R->U, R->nu, v);
    R->lo = R->r ? (int64_t)R->U[R->r - 1] : -1;
    R->hi = R->r < R->nu ? (int64_t)R->U[R->r] : INT64_MAX;
  }
  return v - (uint32_t)R->r;
}

/* The cells' arrays the merge writes: M's (in place) or new ones; cells
 * going before `lo` (the chunk's first source) wait in a buffer. */
typedef struct {
  uint8_t *type, *level;
  uint32_t *conn, *leaf;
} cellv;

typedef struct {
  cellv out, buf;
  int64_t lo, base; /* positions [base, lo) go to buf */
} sink;

static inline void put(sink *S, int64_t p, uint8_t type, uint8_t level, uint32_t leaf,
                       const uint32_t w[4]) {
  cellv *d = &S->out;
  if (p < S->lo) d = &S->buf, p -= S->base;
  d->type[p] = type;
  d->level[p] = level;
  d->leaf[p] = leaf;
  memcpy(d->conn + 4 * p, w, 4 * sizeof *w);
}

typedef struct {
  mx_qband *B;
  const uint8_t *alive, *split;
  const int64_t *S; /* per band cell: the cells gained before it (<= 0 in place) */
  const uint32_t *U, *map;
  size_t nu;
} merger;

/* Band cell i's outputs from position p: how many. */
static int emit_band(const merger *G, size_t i, ranker *R, sink *K, int64_t p) {
  if (!G->alive[i]) return 0;
  const mx_qmesh *L = &G->B->L;
  const uint32_t *v = L->conn + 4 * i;
  uint32_t g[4];
  for (int k = 0; k < 4; k++) g[k] = v[k] == NONE ? NONE : renum(R, G->B->gnode[v[k]]);
  if (!G->split[i]) {
    put(K, p, L->type[i], L->level[i], L->leaf[i], g);
    return 1;
  }
  const int k = G->split[i] - 1;
  for (int o = 0; o < 2; o++) {
    const uint32_t w[4] = {g[k], g[(k + 1 + o) & 3], g[(k + 2 + o) & 3], NONE};
    put(K, p + o, MX_QTRI, L->level[i], L->leaf[i], w);
  }
  return 2;
}

/* Source cells [lo, hi) of M into K. */
static void merge_chunk(const merger *G, const mx_qmesh *M, size_t lo, size_t hi, sink *K) {
  const mx_qband *B = G->B;
  ranker R = {G->U, G->map, G->nu, 0, 0, -1};
  size_t i = lower_bound32(B->gcell, B->L.ncells, (uint32_t)lo);
  int64_t p = (int64_t)lo + G->S[i];
  for (size_t c = lo; c < hi; c++) {
    if (i < B->L.ncells && B->gcell[i] == c) {
      p += emit_band(G, i++, &R, K, p);
      continue;
    }
    uint32_t w[4];
    for (int k = 0; k < 4; k++) {
      const uint32_t v = M->conn[4 * c + k];
      w[k] = v == NONE || !G->nu ? v : renum(&R, v);
    }
    put(K, p++, M->type[c], M->level[c], M->leaf[c], w);
  }
}

static void cellv_free(cellv *v) {
  mx_free(v->type), mx_free(v->level), mx_free(v->conn), mx_free(v->leaf);
}

static int cellv_alloc(cellv *v, size_t n) {
  v->type = mx_alloc(n + 1);
  v->level = mx_alloc(n + 1);
  v->conn = mx_alloc((4 * n + 1) * sizeof *v->conn);
  v->leaf = mx_alloc((n + 1) * sizeof *v->leaf);
  if (v->type && v->level && v->conn && v->leaf) return MX_OK;
  cellv_free(v);
  return MX_ENOMEM;
}

/* The cells: in place when no cell goes after where it was, else into new
 * arrays. Chunks of sources, one per thread; in place, a chunk's first
 * outputs land in the chunk before, which may not have read them yet: they
 * wait in a buffer until every chunk is done. */
static int merge_cells(const merger *G, int inplace, size_t mout, mx_qmesh *M) {
  const mx_qband *B = G->B;
  const size_t m = M->ncells, ma = B->L.ncells;
  int nk = m < 65536 ? 1 : omp_get_max_threads();
  if (nk > 64) nk = 64;
  /* chunk k: sources [lo[k], lo[k + 1]), outputs [base[k], base[k + 1]) */
  size_t lo[65], base[65], boff[65], total = 0;
  for (int k = 0; k <= nk; k++) {
    lo[k] = m * (size_t)k / (size_t)nk;
    base[k] = (size_t)((int64_t)lo[k] + G->S[lower_bound32(B->gcell, ma, (uint32_t)lo[k])]);
  }
  for (int k = 0; k < nk; k++) {
    boff[k] = total;
    total += inplace ? lo[k] - base[k] : 0;
  }
  cellv out = {M->type, M->level, M->conn, M->leaf}, buf = {0};
  if (!inplace && cellv_alloc(&out, mout) != MX_OK) return MX_ENOMEM;
  if (cellv_alloc(&buf, total) != MX_OK) {
    if (!inplace) cellv_free(&out);
    return MX_ENOMEM;
  }
#pragma omp parallel num_threads(nk)
  {
#pragma omp for schedule(static, 1)
    for (int k = 0; k < nk; k++) {
      sink K = {out,
                {buf.type + boff[k], buf.level + boff[k], buf.conn + 4 * boff[k],
                 buf.leaf + boff[k]},
                inplace ? (int64_t)lo[k] : INT64_MIN,
                (int64_t)base[k]};
      merge_chunk(G, M, lo[k], lo[k + 1], &K);
    }
#pragma omp for schedule(static, 1)
    for (int k = 0; k < nk; k++) {
      /* the outputs landing before the chunk's sources, all buffered */
      const size_t below = base[k + 1] < lo[k] ? base[k + 1] : lo[k];
      const size_t n = inplace && below > base[k] ? below - base[k] : 0;
      memcpy(out.type + base[k], buf.type + boff[k], n);
      memcpy(out.level + base[k], buf.level + boff[k], n);
      memcpy(out.leaf + base[k], buf.leaf + boff[k], n * sizeof *buf.leaf);
      memcpy(out.conn + 4 * base[k], buf.conn + 4 * boff[k], 4 * n * sizeof *buf.conn);
    }
  }
  cellv_free(&buf);
  if (!inplace) {
    cellv old = {M->type, M->level, M->conn, M->leaf};
    cellv_free(&old);
    M->type = out.type, M->level = out.level, M->conn = out.conn, M->leaf = out.leaf;
  }
  M->ncells = mout;
  return MX_OK;
}

/* Removes the elements at positions U[0, nu) (ascending) of the n elements
 * of es bytes at a, in place, the others in order: per chunk of sources,
 * the runs between removed ones moved down; those landing in the chunk
 * before wait in a buffer. */
static int remove_sorted(void *a, size_t es, size_t n, const uint32_t *U, size_t nu) {
  if (!nu) return MX_OK;
  char *arr = a;
  int nk = n < 65536 ? 1 : omp_get_max_threads();
  if (nk > 64) nk = 64;
  size_t lo[65], rk[65], boff[65], total = 0;
  for (int k = 0; k <= nk; k++) lo[k] = n * (size_t)k / (size_t)nk;
  for (int k = 0; k < nk; k++) {
    rk[k] = lower_bound32(U, nu, (uint32_t)lo[k]);
    boff[k] = total;
    total += rk[k];
  }
  char *buf = mx_alloc(total * es + 1);
  if (!buf) return MX_ENOMEM;
#pragma omp parallel num_threads(nk)
  {
#pragma omp for schedule(static, 1)
    for (int k = 0; k < nk; k++) {
      size_t r = rk[k], a0 = lo[k];
      const size_t D = lo[k] - rk[k];
      while (a0 < lo[k + 1]) {
        const size_t b = r < nu && U[r] < lo[k + 1] ? U[r] : lo[k + 1];
        /* the run [a0, b) goes to [a0 - r, b - r) */
        size_t s = a0, d = a0 - r;
        if (d < lo[k]) {
          const size_t len = (b - s) < lo[k] - d ? b - s : lo[k] - d;
          memcpy(buf + (boff[k] + d - D) * es, arr + s * es, len * es);
          s += len, d += len;
        }
        if (s < b) memmove(arr + d * es, arr + s * es, (b - s) * es);
        a0 = b + 1;
        if (b < lo[k + 1]) r++;
      }
    }
#pragma omp for schedule(static, 1)
    for (int k = 0; k < nk; k++) {
      /* the kept sources of the chunk, at most rk[k], fill [D, lo) first */
      const size_t D = lo[k] - rk[k];
      const size_t removed_in = lower_bound32(U, nu, (uint32_t)lo[k + 1]) - rk[k];
      const size_t kept = lo[k + 1] - lo[k] - removed_in;
      const size_t len = kept < rk[k] ? kept : rk[k];
      memcpy(arr + D * es, buf + boff[k] * es, len * es);
    }
  }
  mx_free(buf);
  return MX_OK;
}

/* Deep nodes of the band no alive band cell uses may be in cells outside
 * it (which stay): looked up there (seldom: a deep node's band cells do not
 * go but when a fold collapses one). */
static int deep_used(const mx_qband *B, const mx_qmesh *M, uint8_t *used) {
  if (!B->act) return MX_OK;
  size_t nw = 0;
  for (size_t j = 0; j < B->L.nnodes; j++) nw += B->deep[j] && !used[j];
  if (!nw) return MX_OK;
  uint32_t *w = mx_alloc(nw * sizeof *w + 1), *at = mx_alloc(nw * sizeof *at + 1);
  uint8_t *hit = mx_calloc(nw + 1);
  if (!w || !at || !hit) return mx_free(w), mx_free(at), mx_free(hit), MX_ENOMEM;
  nw = 0;
  for (size_t j = 0; j < B->L.nnodes; j++)
    if (B->deep[j] && !used[j]) w[nw] = B->gnode[j], at[nw++] = (uint32_t)j;
#pragma omp parallel for schedule(static)
  for (size_t c = 0; c < M->ncells; c++) {
    if (B->act[c] & QBAND_IN) continue;
    for (int k = 0; k < nv_of(M, c); k++) {
      const size_t i = lower_bound32(w, nw, M->conn[4 * c + k]);
      if (i < nw && w[i] == M->conn[4 * c + k]) __atomic_store_n(&hit[i], 1, __ATOMIC_RELAXED);
    }
  }
  for (size_t i = 0; i < nw; i++)
    if (hit[i]) used[at[i]] = 1;
  mx_free(w), mx_free(at), mx_free(hit);
  return MX_OK;
}

/* The nodes: the band's positions and keys written back, the unused ones
 * (U) removed. */
static int merge_nodes(const mx_qband *B, const uint8_t *nf, uint8_t moved, const uint32_t *U,
                       size_t nu, mx_qmesh *M) {
  const mx_qmesh *L = &B->L;
#pragma omp parallel for schedule(static)
  for (size_t j = 0; j < L->nnodes; j++) {
    const size_t g = B->gnode[j];
    M->xy[2 * g] = L->xy[2 * j];
    M->xy[2 * g + 1] = L->xy[2 * j + 1];
    if (M->nkey && (nf[j] & moved)) M->nkey[g] = MX_QNKEY_NONE;
  }
  MX_CHECK(remove_sorted(M->xy, 2 * sizeof *M->xy, M->nnodes, U, nu));
  if (M->nkey) MX_CHECK(remove_sorted(M->nkey, sizeof *M->nkey, M->nnodes, U, nu));
  M->nnodes -= nu;
  if (!M->nkey) {
    if (!(M->nkey = mx_alloc((M->nnodes + 1) * sizeof *M->nkey))) return MX_ENOMEM;
#pragma omp parallel for schedule(static)
    for (size_t v = 0; v < M->nnodes; v++) M->nkey[v] = MX_QNKEY_NONE;
  }
  return MX_OK;
}

/* The new id of every node (U removed), chunk by chunk of ids. */
static int new_ids(size_t n, const uint32_t *U, size_t nu, uint32_t **map) {
  uint32_t *m = *map = mx_alloc((n + 1) * sizeof *m);
  if (!m) return MX_ENOMEM;
  const size_t nb = (n + BLK - 1) / BLK;
#pragma omp parallel for schedule(static)
  for (size_t b = 0; b < nb; b++) {
    size_t r = lower_bound32(U, nu, (uint32_t)(b * BLK));
    for (size_t v = b * BLK; v < n && v < (b + 1) * BLK; v++) {
      while (r < nu && U[r] < v) r++;
      m[v] = (uint32_t)(v - r);
    }
  }
  return MX_OK;
}

int mx_qband_merge(mx_qband *B, const uint8_t *alive, const uint8_t *split, const uint8_t *nf,
                   uint8_t moved, mx_qmesh *M) {
  const mx_qmesh *L = &B->L;
  const size_t ma = L->ncells, nl = L->nnodes;
  uint8_t *used = mx_calloc(nl + 1);
  uint32_t *map = NULL;
  int64_t *S = mx_alloc((ma + 1) * sizeof *S);
  if (!used || !S) return mx_free(used), mx_free(S), MX_ENOMEM;
#pragma omp parallel for schedule(static)
  for (size_t i = 0; i < ma; i++)
    if (alive[i])
      for (int k = 0; k < nv_of(L, i); k++)
        __atomic_store_n(&used[L->conn[4 * i + k]], 1, __ATOMIC_RELAXED);
  /* the cells gained before each band cell; in place when never > 0 */
  int inplace = 1;
  S[0] = 0;
  for (size_t i = 0; i < ma; i++) {
    S[i + 1] = S[i] + (alive[i] ? (split[i] ? 2 : 1) : 0) - 1;
    inplace &= S[i + 1] <= 0;
  }
  int st = deep_used(B, M, used);
  size_t nu = 0;
  for (size_t j = 0; j < nl; j++) nu += !used[j];
  uint32_t *U = st == MX_OK ? mx_alloc(nu * sizeof *U + 1) : NULL;
  if (st == MX_OK && !U) st = MX_ENOMEM;
  if (st == MX_OK) {
    nu = 0;
    for (size_t j = 0; j < nl; j++)
      if (!used[j]) U[nu++] = B->gnode[j];
    if (nu && 64 * nu > M->nnodes) st = new_ids(M->nnodes, U, nu, &map);
  }
  if (st == MX_OK) {
    const merger G = {B, alive, split, S, U, map, nu};
    st = merge_cells(&G, inplace, (size_t)((int64_t)M->ncells + S[ma]), M);
  }
  if (st == MX_OK) st = merge_nodes(B, nf, moved, U, nu, M);
  mx_free(used), mx_free(S), mx_free(U), mx_free(map);
  return st;
}
