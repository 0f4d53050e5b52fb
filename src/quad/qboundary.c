/* Algorithm 2, steps 3-5 (Jaillet & Lobos 2021, section 4.1), on the
 * transition mesh, one function per step (run() lists them in order):
 *   node states (inside / outside, on the polylines counting as outside);
 *   features: the closest node of the leaf holding each feature moves onto
 *     it, and keeps the cell that holds the domain's corner there;
 *   close inside nodes go onto the polylines; cells with no inside node go
 *     (but those holding a feature's corner, and those left inside the
 *     domain with their nodes on the polylines);
 *   shrink: the outside nodes go onto their closest point;
 *   surface patterns (Fig. 8) on the quads; slivers along the boundary and
 *     cells outside it dropped; then the mesh compacted.
 * The closest point is not always the right one near a corner, where the
 * shrink may put two nodes of a cell in the wrong order along the
 * polylines, or the two ends of a boundary edge on both sides of a reflex
 * corner; three local repairs follow the shrink: nodes sent onto a sharp
 * corner held by a feature go along its sides (off_corners), edges across a
 * notch get the corner (close_notches), and folded cells (or removed cells
 * folded between kept ones) lose their shortest edge (close_folds); nodes
 * that land on one point become one (merge_same).
 *
 * The steps run on the band of the transition mesh (qband.c): the cells
 * with a node that is not deep, deep nodes being inside nodes no step can
 * move; the others stay as they are. Local ids keep the global order, so
 * every decision by id is the one the whole mesh would give; when the band
 * cannot be trusted (a feature not in a leaf of its own, no leaves given,
 * a close radius of half a side or more) the band is the whole mesh. Once the close
 * nodes are placed, the passes go over the active cells only (cell_act):
 * those with a node not inside (or split), the others no later step
 * changes.
 *
 * Every pass is a loop over all nodes or all (active) cells whose decisions
 * read only what the previous pass wrote (or a short ordered loop over the
 * features), so the result is the same for any thread count. After each
 * step that moves nodes, cells with a scaled Jacobian <= 0 (below SJ_OK:
 * numerically flat) are split along a diagonal or get their nodes back
 * where they were (repair()), and counted in stats->inverted. */
#include <math.h>
#include <string.h>

#include "base/common.h"
#include "base/scan.h"
#include "quad/qinternal.h"

/* The next and previous corner of a cell of nv corners (no division). */
static inline int nxt(int k, int nv) { return k + 1 == nv ? 0 : k + 1; }
static inline int prv(int k, int nv) { return k == 0 ? nv - 1 : k - 1; }

/* Node flags. */
enum {
  N_IN = 1,       /* strictly inside the domain (counts for keeping a cell) */
  N_ONPOLY = 2,   /* on the polylines */
  N_FEATURE = 4,  /* holds a feature: never moves again */
  N_CLOSE = 8,    /* moved by the projection of close inside nodes */
  N_SHRUNK = 16,  /* moved by the shrink */
  N_MOVED = 32,   /* a feature that was not already where its node was */
  N_DEEP = 64,    /* inside, and no step moves it (qband.c): its cells outside the band */
};

/* The band could not be trusted (a feature not in a leaf of the band's):
 * the step starts again on the whole mesh. */
#define QB_WHOLE (-1)

#define FLAT_LO 175.0
#define INSIDE_ANGLE 150.0
#define SJ_OK 1e-6 /* the least scaled Jacobian of a valid cell (the mesher's contract) */

typedef struct {
  mx_qmesh *M;
  const mx_poly *P;
  const mx_poly_index *I;
  const mx_qgrid *g;
  size_t n, m;       /* nodes, cells of the transition mesh */
  uint8_t *nf;       /* N_* per node */
  double *xy0;       /* positions before the current step (a node left where it was) */
  uint8_t *alive;    /* per cell */
  uint8_t *split;    /* per quad: 0, or 1 + k: two triangles along the diagonal from corner k */
  uint8_t *ghost;    /* per cell: gone at the removal (its nodes may stay in others) */
  uint64_t *off;     /* node -> alive cells (CSR, cells ascending) */
  uint32_t *ids;
  size_t ids_cap;    /* entries ids holds room for */
  double tol;        /* "on the polylines": 1e-12 of the domain's size */
  size_t nfeat;      /* feature nodes, ascending, with the direction into the domain */
  uint64_t *fnode;   /*   that halves the domain's angle there, and their */
  double *fdir;      /*   polyline vertices; per polyline vertex, the ones */
  uint32_t *fvert;   /*   before and after it */
  uint32_t *vnb;
  const uint8_t *open; /* per cell: its leaf is in the band whole (qinternal.h) */
  uint32_t *acell;     /* from the removal on, the cells the passes go through */
  size_t nac;
  const uint8_t *deep;   /* per node: frozen (qinternal.h) */
  const uint8_t *inside; /* per node: a node of a clear leaf, inside */
  int band;            /* the mesh is a band of the transition mesh */
  mx_qboundary_stats *st;
} qb;

static int nv_of(const qb *B, size_t c) { return B->M->type[c] == MX_QQUAD ? 4 : 3; }

static double leaf_side(const qb *B, size_t c) { return ldexp(B->g->side, -B->M->level[c]); }

/* The cells the passes go through: all of them until the close nodes are
 * placed, then (active_cells) those with a node not inside, or split: the
 * others have all their nodes inside, where they were, and no later step
 * moves an inside node, drops or splits a cell with one (removal keeps it,
 * patterns, notches and folds act on nodes on the polylines, and such a
 * cell is valid): no later pass would change them. */
static inline size_t ncells_act(const qb *B) { return B->acell ? B->nac : B->m; }
static inline size_t cell_act(const qb *B, size_t i) { return B->acell ? B->acell[i] : i; }

/* ---- node -> cells ------------------------------------------------------- */

/* off and ids are kept between builds: the alive cells only lose corners,
 * so the first build's room suffices, and their pages are touched once. */
static int build_node_cells(qb *B) {
  const mx_qmesh *M = B->M;
  if (!B->off) B->off = mx_alloc((B->n + 1) * sizeof *B->off);
  uint64_t *off = B->off;
  if (!off) return MX_ENOMEM;
#pragma omp parallel for schedule(static) if (B->n > MX_PAR_MIN)
  for (size_t v = 0; v <= B->n; v++) off[v] = 0;
#pragma omp parallel for schedule(static) if (ncells_act(B) > MX_PAR_MIN)
  for (size_t i = 0; i < ncells_act(B); i++) {
    const size_t c = cell_act(B, i);
    if (B->alive[c])
      for (int k = 0; k < nv_of(B, c); k++)
        __atomic_fetch_add(&off[M->conn[4 * c + k]], 1, __ATOMIC_RELAXED);
  }
  const uint64_t tot = mx_scan_u64(off, B->n + 1);
  if (!B->ids || tot > B->ids_cap) {
    mx_free(B->ids);
    B->ids_cap = 0;
    if (!(B->ids = mx_alloc(tot * sizeof *B->ids + 1))) return MX_ENOMEM;
    B->ids_cap = tot;
  }
  uint32_t *ids = B->ids;
  /* not kept: it would add to the peak of the later steps */
  uint64_t *cur = mx_alloc(B->n * sizeof *cur + 1);
  if (!cur) return MX_ENOMEM;
#pragma omp parallel for schedule(static) if (B->n > MX_PAR_MIN)
  for (size_t v = 0; v < B->n; v++) cur[v] = off[v];
#pragma omp parallel for schedule(static) if (ncells_act(B) > MX_PAR_MIN)
  for (size_t i = 0; i < ncells_act(B); i++) {
    const size_t c = cell_act(B, i);
    if (B->alive[c])
      for (int k = 0; k < nv_of(B, c); k++)
        ids[__atomic_fetch_add(&cur[M->conn[4 * c + k]], 1, __ATOMIC_RELAXED)] = (uint32_t)c;
  }
  /* Sorted per node: the lists do not depend on which thread came first. */
#pragma omp parallel for schedule(dynamic, 4096)
  for (size_t v = 0; v < B->n; v++)
    for (uint64_t i = off[v] + 1; i < off[v + 1]; i++)
      for (uint64_t j = i; j > off[v] && ids[j - 1] > ids[j]; j--) {
        const uint32_t t = ids[j];
        ids[j] = ids[j - 1];
        ids[j - 1] = t;
      }
  mx_free(cur);
  return MX_OK;
}

static size_t ncells_at(const qb *B, size_t v) { return (size_t)(B->off[v + 1] - B->off[v]); }

/* ---- cell measures -------------------------------------------------------- */

static double split_sj(const double *xy, const uint32_t *v, int k) {
  const uint32_t a[3] = {v[k], v[(k + 1) & 3], v[(k + 2) & 3]};
  const uint32_t b[3] = {v[k], v[(k + 2) & 3], v[(k + 3) & 3]};
  return mx_min(mx_qsj_nodes(xy, a, 3), mx_qsj_nodes(xy, b, 3));
}

/* The scaled Jacobian of what cell c will be written as. */
static double cell_sj(const qb *B, size_t c) {
  const uint32_t *v = B->M->conn + 4 * c;
  if (B->split[c]) return split_sj(B->M->xy, v, B->split[c] - 1);
  return mx_qsj_nodes(B->M->xy, v, nv_of(B, c));
}

/* Sufficient for a scaled Jacobian > SJ_OK, without the square roots: every
 * corner's sine is over 2 SJ_OK (squared, well clear of the roundings). */
static int clearly_valid(const double *xy, const uint32_t *v, int nv) {
  for (int k = 0; k < nv; k++) {
    const double *p = xy + 2 * (size_t)v[k];
    const double *a = xy + 2 * (size_t)v[nxt(k, nv)], *b = xy + 2 * (size_t)v[prv(k, nv)];
    const double e1[2] = {a[0] - p[0], a[1] - p[1]}, e2[2] = {b[0] - p[0], b[1] - p[1]};
    const double x = e1[0] * e2[1] - e1[1] * e2[0];
    const double l2 = (e1[0] * e1[0] + e1[1] * e1[1]) * (e2[0] * e2[0] + e2[1] * e2[1]);
    if (!(x > 0 && x * x > 4 * SJ_OK * SJ_OK * l2)) return 0;
  }
  return 1;
}

/* cell_sj(B, c) > SJ_OK, the common case decided cheaply. */
static int cell_ok(const qb *B, size_t c) {
  if (!B->split[c] && clearly_valid(B->M->xy, B->M->conn + 4 * c, nv_of(B, c))) return 1;
  return cell_sj(B, c) > SJ_OK;
}

static void centroid(const qb *B, size_t c, double p[2]) {
  const int nv = nv_of(B, c);
  p[0] = p[1] = 0;
  for (int k = 0; k < nv; k++) {
    p[0] += B->M->xy[2 * (size_t)B->M->conn[4 * c + k]] / nv;
    p[1] += B->M->xy[2 * (size_t)B->M->conn[4 * c + k] + 1] / nv;
  }
}

/* The counter-clockwise angle from u to w in [0, 2 pi). */
static double ccw_angle(const double u[2], const double w[2]) {
  const double a = atan2(u[0] * w[1] - u[1] * w[0], u[0] * w[0] + u[1] * w[1]);
  return a < 0 ? a + 2 * M_PI : a;
}

/* Whether the cell's corner at feature node v holds the direction that
 * halves the domain's angle at the feature: that cell keeps the feature in
 * the mesh even when none of its nodes is inside (a sharp corner). */
static int holds_feature(const qb *B, size_t c, int k) {
  const uint32_t v = B->M->conn[4 * c + k];
  size_t lo = 0, hi = B->nfeat;
  while (lo < hi) {
    const size_t mid = lo + (hi - lo) / 2;
    if (B->fnode[mid] < v) lo = mid + 1; else hi = mid;
  }
  if (lo == B->nfeat || B->fnode[lo] != v) return 0;
  const int nv = nv_of(B, c);
  const double *p = B->M->xy + 2 * (size_t)v;
  const double *a = B->M->xy + 2 * (size_t)B->M->conn[4 * c + nxt(k, nv)];
  const double *b = B->M->xy + 2 * (size_t)B->M->conn[4 * c + prv(k, nv)];
  const double e1[2] = {a[0] - p[0], a[1] - p[1]}, e2[2] = {b[0] - p[0], b[1] - p[1]};
  return ccw_angle(e1, B->fdir + 2 * lo) <= ccw_angle(e1, e2);
}

/* Cells that will be in the mesh: before the removal, those with an inside
 * node, or holding a feature, or with a node on the polylines and their
 * centroid inside the domain (a cell whose inside nodes all went onto the
 * polylines is not outside); after it, the alive ones. */
static int stays(const qb *B, size_t c, int before_removal) {
  if (!B->alive[c]) return 0;
  if (!before_removal) return 1;
  const int nv = nv_of(B, c);
  int on = 0;
  for (int k = 0; k < nv; k++) {
    const uint8_t f = B->nf[B->M->conn[4 * c + k]];
    if ((f & N_IN) || ((f & N_FEATURE) && holds_feature(B, c, k))) return 1;
    on |= f & N_ONPOLY;
  }
  double p[2];
  centroid(B, c, p);
  return on && mx_poly_inside(B->I, p) == 1;
}

/* ---- repair --------------------------------------------------------------- */

/* The better diagonal of quad c, 1 + its corner, or 0 when neither gives two
 * valid triangles. */
static int best_split(const qb *B, size_t c) {
  const uint32_t *v = B->M->conn + 4 * c;
  const double s0 = split_sj(B->M->xy, v, 0), s1 = split_sj(B->M->xy, v, 1);
  if (mx_max(s0, s1) <= SJ_OK) return 0;
  return s1 > s0 ? 2 : 1;
}

/* Cells with a scaled Jacobian <= SJ_OK: a quad is split along the diagonal that
 * makes two valid triangles; otherwise its nodes moved by this step (flags
 * `undo`) go back where they were, and the step's count loses them. Repeats
 * until nothing changes (each round puts back at least one node). */
static int repair(qb *B, uint8_t undo, int before_removal, size_t *undone) {
  uint8_t *back = mx_calloc(B->n + 1);
  if (!back) return MX_ENOMEM;
  for (;;) {
    size_t fixed = 0, marked = 0;
#pragma omp parallel for schedule(dynamic, 1024) reduction(+ : fixed, marked)
    for (size_t i = 0; i < ncells_act(B); i++) {
      const size_t c = cell_act(B, i);
      if (!stays(B, c, before_removal) || cell_ok(B, c)) continue;
      if (B->M->type[c] == MX_QQUAD && (B->split[c] = (uint8_t)best_split(B, c))) {
        fixed++;
        continue;
      }
      size_t mk = 0;
      for (int k = 0; k < nv_of(B, c); k++) {
        const uint32_t v = B->M->conn[4 * c + k];
        if ((B->nf[v] & undo) && !(B->nf[v] & N_FEATURE))
          __atomic_store_n(&back[v], 1, __ATOMIC_RELAXED), mk++;
      }
      fixed += mk > 0, marked += mk;
    }
    B->st->inverted += fixed;
    if (!marked) break;
    size_t nb = 0;
#pragma omp parallel for schedule(static) reduction(+ : nb)
    for (size_t v = 0; v < B->n; v++) {
      if (!back[v]) continue;
      back[v] = 0;
      B->M->xy[2 * v] = B->xy0[2 * v];
      B->M->xy[2 * v + 1] = B->xy0[2 * v + 1];
      /* A close node put back is inside again; a shrunk one is off the
       * polylines again. */
      B->nf[v] = (uint8_t)((B->nf[v] & ~(undo | N_ONPOLY)) | ((undo & N_CLOSE) ? N_IN : 0));
      nb++;
    }
    *undone += nb;
  }
  mx_free(back);
  return MX_OK;
}

/* ---- projection ----------------------------------------------------------- */

/* The closest point of the polylines within rmax (a polyline vertex exactly
 * when it is within tol of one, so that two nodes sent to one vertex meet
 * exactly). 0 when nothing is that close. */
static int project(const qb *B, const double p[2], double rmax, double q[2], double *d2) {
  const uint32_t s = mx_poly_closest(B->I, p, rmax, q, d2);
  if (s == UINT32_MAX) return 0;
  for (int e = 0; e < 2; e++) {
    const double *a = B->P->xy + 2 * (size_t)B->P->seg[2 * (size_t)s + e];
    if (hypot(q[0] - a[0], q[1] - a[1]) <= B->tol) q[0] = a[0], q[1] = a[1];
  }
  return 1;
}

static void snapshot(qb *B) { memcpy(B->xy0, B->M->xy, 2 * B->n * sizeof *B->xy0); }

/* ---- step 3: states, features, close nodes, removal ------------------------ */

static void node_states(qb *B) {
#pragma omp parallel for schedule(dynamic, 1024)
  for (size_t v = 0; v < B->n; v++) {
    if (B->inside[v]) {
      B->nf[v] = (uint8_t)(N_IN | (B->deep[v] ? N_DEEP : 0));
      continue;
    }
    const int s = mx_poly_inside(B->I, B->M->xy + 2 * v);
    B->nf[v] = s == 1 ? N_IN : s == 2 ? N_ONPOLY : 0;
  }
}

/* A leaf as a sort key: its level and its position on that level's grid
 * (the centroid of any of its cells lies strictly inside it). */
static uint64_t leaf_key(int level, uint64_t ax, uint64_t ay) {
  return (uint64_t)level << 58 | ax << 29 | ay;
}

static uint64_t cell_leaf_key(const qb *B, size_t c) {
  double p[2];
  centroid(B, c, p);
  const double s = leaf_side(B, c);
  return leaf_key(B->M->level[c], (uint64_t)floor((p[0] - B->g->origin[0]) / s),
                  (uint64_t)floor((p[1] - B->g->origin[1]) / s));
}

/* Cell c with node v at f, as the polygon it becomes (a corner landing on
 * its neighbour merges with it): its corners in xy, their number returned
 * (under 3, or a quad folded onto itself: nothing left, 0). */
static int moved_cell(const qb *B, size_t c, uint32_t v, const double f[2], double xy[8]) {
  const int nv = nv_of(B, c);
  double p[8];
  for (int k = 0; k < nv; k++) {
    const uint32_t u = B->M->conn[4 * c + k];
    const double *q = u == v ? f : B->M->xy + 2 * (size_t)u;
    p[2 * k] = q[0], p[2 * k + 1] = q[1];
  }
  int n = 0;
  for (int k = 0; k < nv; k++) {
    const int l = nxt(k, nv);
    if (p[2 * k] != p[2 * l] || p[2 * k + 1] != p[2 * l + 1])
      xy[2 * n] = p[2 * k], xy[2 * n + 1] = p[2 * k + 1], n++;
  }
  if (n == 4 && ((xy[0] == xy[4] && xy[1] == xy[5]) || (xy[2] == xy[6] && xy[3] == xy[7]))) n = 0;
  return n < 3 ? 0 : n;
}

/* Whether node v can go onto f: every cell around it that may stay (one
 * with another inside node, or any when `all`) stays valid, a quad
 * possibly split. */
static int move_ok(const qb *B, uint32_t v, const double f[2], int all) {
  static const uint32_t loc[4] = {0, 1, 2, 3};
  for (uint64_t i = B->off[v]; i < B->off[v + 1]; i++) {
    const size_t c = B->ids[i];
    int keep = all;
    for (int k = 0; k < nv_of(B, c); k++) {
      const uint32_t u = B->M->conn[4 * c + k];
      keep |= u != v && (B->nf[u] & N_IN);
    }
    double xy[8];
    const int n = keep ? moved_cell(B, c, v, f, xy) : 0;
    if (!n || mx_qsj_nodes(xy, loc, n) > SJ_OK) continue;
    if (n == 4 && mx_max(split_sj(xy, loc, 0), split_sj(xy, loc, 1)) > SJ_OK) continue;
    return 0;
  }
  return 1;
}

/* The node of leaf [lo, hi) of the sorted cells that takes feature f: the
 * closest (the smaller id on a tie) unless moving it would invert a cell
 * that stays; then the next closest that would not (the closest if none). */
static uint32_t feature_target(const qb *B, const uint32_t *cid, size_t lo, size_t hi,
                               const double f[2]) {
  uint32_t prev = UINT32_MAX, first = UINT32_MAX;
  double pd = -1;
  for (;;) {
    uint32_t best = UINT32_MAX;
    double bd = INFINITY;
    for (size_t i = lo; i < hi; i++)
      for (int k = 0; k < nv_of(B, cid[i]); k++) {
        const uint32_t v = B->M->conn[4 * (size_t)cid[i] + k];
        const double d = hypot(B->M->xy[2 * (size_t)v] - f[0], B->M->xy[2 * (size_t)v + 1] - f[1]);
        const int after = d > pd || (d == pd && v > prev);
        if (after && (d < bd || (d == bd && v < best))) bd = d, best = v;
      }
    if (best == UINT32_MAX) return first;
    if (first == UINT32_MAX) first = best;
    if (move_ok(B, best, f, 0)) return best;
    pd = bd, prev = best;
  }
}

/* The keys of the leaves that may hold f, in the order they are tried:
 * level by level; a point on a leaf's left or bottom side may belong to the
 * leaf across, hence the nudged tries. UINT64_MAX for a try off the grid. */
#define FEATURE_TRIES (4 * (MX_QMAX_LEVEL + 1))
static void feature_keys(const qb *B, const double f[2], uint64_t *k) {
  const double lim = ldexp(1.0, 29);
  for (int t = 0; t < 4; t++)
    for (int l = 0; l <= MX_QMAX_LEVEL; l++) {
      const double s = ldexp(B->g->side, -l), e = 1e-6 * s;
      const double x = floor((f[0] - (t & 1 ? e : 0) - B->g->origin[0]) / s);
      const double y = floor((f[1] - (t & 2 ? e : 0) - B->g->origin[1]) / s);
      const int off = x < 0 || y < 0 || x >= lim || y >= lim;
      k[t * (MX_QMAX_LEVEL + 1) + l] = off ? UINT64_MAX : leaf_key(l, (uint64_t)x, (uint64_t)y);
    }
}

/* The node taking feature f, from the sorted cells of the candidate leaves.
 * *sure: the leaf is the one holding f itself and wholly in the mesh (in a
 * band, the whole mesh would have given the same). */
static uint32_t feature_node(const qb *B, const uint64_t *key, const uint32_t *cid, size_t m,
                             const double f[2], int *sure) {
  uint64_t k[FEATURE_TRIES];
  feature_keys(B, f, k);
  for (int t = 0; t < FEATURE_TRIES; t++) {
    if (k[t] == UINT64_MAX) continue;
    const size_t lo = mx_lower_u64(key, m, k[t]);
    if (lo == m || key[lo] != k[t]) continue;
    *sure = t <= MX_QMAX_LEVEL && B->open[cid[lo]];
    return feature_target(B, cid, lo, mx_lower_u64(key, m, k[t] + 1), f);
  }
  *sure = 0;
  return UINT32_MAX;
}

/* The direction into the domain halving its angle at vertex f (the domain
 * lies on the left of each segment); nb: the vertices before and after. */
static void bisector(const mx_poly *P, uint32_t f, const uint32_t *nb, double d[2]) {
  const double *p = P->xy + 2 * (size_t)f, *a = P->xy + 2 * (size_t)nb[2 * (size_t)f],
               *b = P->xy + 2 * (size_t)nb[2 * (size_t)f + 1];
  const double out[2] = {b[0] - p[0], b[1] - p[1]}, in[2] = {a[0] - p[0], a[1] - p[1]};
  const double h = 0.5 * ccw_angle(out, in), t = atan2(out[1], out[0]) + h;
  d[0] = cos(t);
  d[1] = sin(t);
}

/* The feature nodes in ascending order with their directions. */
static int feature_dirs(qb *B, const uint32_t *fv, const uint32_t *pick, size_t nfeat) {
  const mx_poly *P = B->P;
  uint32_t *nb = B->vnb = mx_alloc(2 * P->nv * sizeof *nb + 1);
  uint32_t *idx = mx_alloc(nfeat * sizeof *idx);
  B->fnode = mx_alloc(nfeat * sizeof *B->fnode);
  B->fdir = mx_alloc(2 * nfeat * sizeof *B->fdir);
  B->fvert = mx_alloc(nfeat * sizeof *B->fvert);
  if (!nb || !idx || !B->fnode || !B->fdir || !B->fvert) return mx_free(idx), MX_ENOMEM;
  for (size_t s = 0; s < P->ns; s++) {
    nb[2 * (size_t)P->seg[2 * s + 1]] = P->seg[2 * s];     /* before */
    nb[2 * (size_t)P->seg[2 * s] + 1] = P->seg[2 * s + 1]; /* after */
  }
  for (size_t i = 0; i < nfeat; i++) B->fnode[i] = pick[i], idx[i] = (uint32_t)i;
  int st = mx_sort_u64(B->fnode, idx, nfeat) == MX_OK ? MX_OK : MX_ENOMEM;
  for (size_t i = 0; st == MX_OK && i < nfeat; i++) {
    B->fvert[i] = fv[idx[i]];
    bisector(P, fv[idx[i]], nb, B->fdir + 2 * i);
  }
  B->nfeat = nfeat;
  mx_free(idx);
  return st;
}

/* Each feature takes the closest node of the leaf holding it, in the order
 * of the features (two taking one node is an error: too coarse there). */
static int take_features(qb *B, const uint32_t *fv, size_t nfeat, const uint32_t *pick) {
  for (size_t i = 0; i < nfeat; i++) {
    const double *f = B->P->xy + 2 * (size_t)fv[i];
    const uint32_t v = pick[i];
    if (v == UINT32_MAX) {
      mx_error(B->P->path, 0, "boundary: feature (%.17g, %.17g) lies in no quadrant of the mesh",
               f[0], f[1]);
      return MX_EINVALID;
    }
    if (B->nf[v] & N_FEATURE) {
      mx_error(B->P->path, 0,
               "boundary: features (%.17g, %.17g) and (%.17g, %.17g) would take the same "
               "node: the level is too coarse there",
               B->M->xy[2 * (size_t)v], B->M->xy[2 * (size_t)v + 1], f[0], f[1]);
      return MX_EINVALID;
    }
    double *p = B->M->xy + 2 * (size_t)v;
    B->nf[v] = N_FEATURE | N_ONPOLY | (p[0] != f[0] || p[1] != f[1] ? N_MOVED : 0);
    p[0] = f[0];
    p[1] = f[1];
  }
  B->st->features = nfeat;
  return MX_OK;
}

/* Whether k is one of the sorted candidate keys cand[0, nc). */
static int is_candidate(const uint64_t *cand, size_t nc, uint64_t k) {
  const size_t i = mx_lower_u64(cand, nc, k);
  return i < nc && cand[i] == k;
}

/* The cells of the leaves that may hold a feature, sorted by leaf key: only
 * those are ever looked up, so the other cells need not be sorted. Only
 * cells of open leaves are taken: a feature's node is sure to be the whole
 * mesh's only when found in one (feature_node). */
static int candidate_cells(const qb *B, const uint32_t *fv, size_t nfeat, uint64_t **key,
                           uint32_t **cid, size_t *m) {
  const size_t nc = nfeat * FEATURE_TRIES;
  uint64_t *cand = mx_alloc(nc * sizeof *cand + 1);
  uint32_t *cidx = mx_alloc(nc * sizeof *cidx + 1);
  uint64_t *pos = mx_alloc((B->m + 1) * sizeof *pos);
  if (!cand || !cidx || !pos) return mx_free(cand), mx_free(cidx), mx_free(pos), MX_ENOMEM;
  for (size_t i = 0; i < nfeat; i++) feature_keys(B, B->P->xy + 2 * (size_t)fv[i], cand + i * FEATURE_TRIES);
  int st = mx_sort_u64(cand, cidx, nc) == MX_OK ? MX_OK : MX_ENOMEM;
  mx_free(cidx);
  if (st == MX_OK) {
#pragma omp parallel for schedule(static)
    for (size_t c = 0; c < B->m; c++)
      pos[c] = B->open[c] && is_candidate(cand, nc, cell_leaf_key(B, c));
    pos[B->m] = 0;
    *m = mx_scan_u64(pos, B->m + 1);
    *key = mx_alloc(*m * sizeof **key + 1);
    *cid = mx_alloc(*m * sizeof **cid + 1);
    st = *key && *cid ? MX_OK : MX_ENOMEM;
  }
  if (st == MX_OK) {
#pragma omp parallel for schedule(static)
    for (size_t c = 0; c < B->m; c++)
      if (pos[c + 1] > pos[c]) (*key)[pos[c]] = cell_leaf_key(B, c), (*cid)[pos[c]] = (uint32_t)c;
    st = mx_sort_u64(*key, *cid, *m) == MX_OK ? MX_OK : MX_ENOMEM;
  }
  mx_free(cand), mx_free(pos);
  return st;
}

static int features(qb *B) {
  uint32_t *fv = NULL, *cid = NULL, *pick = NULL;
  uint64_t *key = NULL;
  size_t nfeat = 0, m = 0;
  int st = mx_poly_features(B->P, &fv, &nfeat);
  if (st != MX_OK || nfeat == 0) return mx_free(fv), st;
  pick = mx_alloc(nfeat * sizeof *pick);
  st = pick ? candidate_cells(B, fv, nfeat, &key, &cid, &m) : MX_ENOMEM;
  if (st == MX_OK) {
    int unsure = 0;
#pragma omp parallel for schedule(dynamic, 16) reduction(| : unsure)
    for (size_t i = 0; i < nfeat; i++) {
      int sure;
      pick[i] = feature_node(B, key, cid, m, B->P->xy + 2 * (size_t)fv[i], &sure);
      unsure |= !sure;
    }
    st = B->band && unsure ? QB_WHOLE : take_features(B, fv, nfeat, pick);
  }
  if (st == MX_OK) st = feature_dirs(B, fv, pick, nfeat);
  mx_free(fv), mx_free(cid), mx_free(pick), mx_free(key);
  if (st != MX_OK) return st;
  size_t none = 0;
  return repair(B, 0, 1, &none);
}

/* Inside nodes closer to the polylines than close_ratio times the shortest
 * diagonal of the leaves sharing them go onto their closest point. */
static int close_nodes(qb *B, double close_ratio) {
  snapshot(B);
  size_t moved = 0;
#pragma omp parallel for schedule(dynamic, 1024) reduction(+ : moved)
  for (size_t v = 0; v < B->n; v++) {
    if (!(B->nf[v] & N_IN) || (B->nf[v] & N_DEEP) || ncells_at(B, v) == 0) continue;
    double s = INFINITY, q[2], d2;
    for (uint64_t i = B->off[v]; i < B->off[v + 1]; i++) s = mx_min(s, leaf_side(B, B->ids[i]));
    const double r = close_ratio * s * sqrt(2.0);
    if (!project(B, B->M->xy + 2 * v, r, q, &d2) || !(d2 < r * r)) continue;
    B->M->xy[2 * v] = q[0];
    B->M->xy[2 * v + 1] = q[1];
    B->nf[v] = N_ONPOLY | N_CLOSE;
    moved++;
  }
  size_t undone = 0;
  MX_CHECK(repair(B, N_CLOSE, 1, &undone));
  B->st->moved_close = moved - undone;
  return MX_OK;
}

/* The cells with a node not inside, or split (cell_act), ascending. */
static int active_cells(qb *B) {
  const size_t nb = (B->m + 4095) / 4096;
  uint64_t *cnt = mx_alloc((nb + 1) * sizeof *cnt);
  if (!cnt) return MX_ENOMEM;
#pragma omp parallel for schedule(static)
  for (size_t b = 0; b < nb; b++) {
    uint64_t k = 0;
    for (size_t c = b * 4096; c < B->m && c < (b + 1) * 4096; c++) {
      int act = B->split[c] != 0;
      for (int j = 0; !act && j < nv_of(B, c); j++) act = !(B->nf[B->M->conn[4 * c + j]] & N_IN);
      k += (uint64_t)act;
    }
    cnt[b] = k;
  }
  B->nac = (size_t)mx_scan_u64(cnt, nb);
  if (!(B->acell = mx_alloc((B->nac + 1) * sizeof *B->acell))) return mx_free(cnt), MX_ENOMEM;
#pragma omp parallel for schedule(static)
  for (size_t b = 0; b < nb; b++) {
    uint64_t k = cnt[b];
    for (size_t c = b * 4096; c < B->m && c < (b + 1) * 4096; c++) {
      int act = B->split[c] != 0;
      for (int j = 0; !act && j < nv_of(B, c); j++) act = !(B->nf[B->M->conn[4 * c + j]] & N_IN);
      if (act) B->acell[k++] = (uint32_t)c;
    }
  }
  mx_free(cnt);
  return MX_OK;
}

static int remove_cells(qb *B) {
  MX_CHECK(active_cells(B));
  size_t removed = 0;
#pragma omp parallel for schedule(static) reduction(+ : removed)
  for (size_t i = 0; i < ncells_act(B); i++) {
    const size_t c = cell_act(B, i);
    B->alive[c] = (uint8_t)stays(B, c, 1);
    B->ghost[c] = !B->alive[c];
    removed += !B->alive[c];
  }
  B->st->removed = removed;
  return build_node_cells(B);
}

/* ---- step 4: shrink -------------------------------------------------------- */

/* The least scaled Jacobian of the alive cells around node v. */
static double sj_around(const qb *B, uint32_t v) {
  double s = INFINITY;
  for (uint64_t i = B->off[v]; i < B->off[v + 1]; i++)
    s = mx_min(s, mx_qsj_nodes(B->M->xy, B->M->conn + 4 * (size_t)B->ids[i], nv_of(B, B->ids[i])));
  return s;
}

/* Node v, sent onto the corner of feature i, goes along one of the
 * corner's two segments instead, as far from the corner as it was (at most
 * half the segment): the side that leaves its cells best; it stays on the
 * corner when neither leaves them valid. */
static void off_corner(qb *B, uint32_t v, size_t i) {
  const double *pw = B->P->xy + 2 * (size_t)B->fvert[i], *o = B->xy0 + 2 * (size_t)v;
  double *p = B->M->xy + 2 * (size_t)v, best = SJ_OK, bq[2] = {pw[0], pw[1]};
  for (int side = 0; side < 2; side++) {
    const double *pe = B->P->xy + 2 * (size_t)B->vnb[2 * (size_t)B->fvert[i] + side];
    const double l = hypot(pe[0] - pw[0], pe[1] - pw[1]);
    const double d = mx_min(hypot(o[0] - pw[0], o[1] - pw[1]), 0.5 * l) / l;
    p[0] = pw[0] + d * (pe[0] - pw[0]);
    p[1] = pw[1] + d * (pe[1] - pw[1]);
    const double s = sj_around(B, v);
    if (s > best) best = s, bq[0] = p[0], bq[1] = p[1];
  }
  p[0] = bq[0], p[1] = bq[1];
}

/* Nodes the shrink sent onto a sharp corner held by a feature node (they
 * lay in its outward cone) would collapse onto that node and take its cells
 * with them (an acute corner would lose its last cell): off_corner. They
 * are few, all around the feature nodes, taken in order. */
static void off_corners(qb *B) {
  for (size_t i = 0; i < B->nfeat; i++) {
    const uint32_t f = (uint32_t)B->fnode[i];
    const double *pf = B->M->xy + 2 * (size_t)f;
    for (uint64_t j = B->off[f]; j < B->off[f + 1]; j++)
      for (int k = 0; k < nv_of(B, B->ids[j]); k++) {
        const uint32_t v = B->M->conn[4 * (size_t)B->ids[j] + k];
        const double *p = B->M->xy + 2 * (size_t)v;
        if (v != f && (B->nf[v] & N_SHRUNK) && p[0] == pf[0] && p[1] == pf[1]) off_corner(B, v, i);
      }
  }
}

/* Every outside node of the kept cells not on the polylines yet goes onto
 * its closest point. */
static int shrink(qb *B) {
  snapshot(B);
  size_t moved = 0;
#pragma omp parallel for schedule(dynamic, 1024) reduction(+ : moved)
  for (size_t v = 0; v < B->n; v++) {
    if ((B->nf[v] & (N_IN | N_ONPOLY)) || ncells_at(B, v) == 0) continue;
    double q[2], d2;
    if (!project(B, B->M->xy + 2 * v, INFINITY, q, &d2)) continue;
    B->M->xy[2 * v] = q[0];
    B->M->xy[2 * v + 1] = q[1];
    B->nf[v] |= N_ONPOLY | N_SHRUNK;
    moved++;
  }
  B->st->shrunk = moved;
  off_corners(B);
  return MX_OK;
}

/* Nodes sent to the same point (a polyline vertex) become one: the smallest
 * id. The geometry does not change; cells that lose a corner become
 * triangles, or go when nothing is left of them. */
static uint64_t coord_hash(const double *p) {
  uint64_t a, b;
  memcpy(&a, p, 8);
  memcpy(&b, p + 1, 8);
  a ^= b * 0x9E3779B97F4A7C15ULL;
  return a ^ (a >> 29);
}

static void group_same(qb *B, const uint64_t *key, const uint32_t *id, size_t lo, size_t hi,
                       uint32_t *rep) {
  for (size_t i = lo; i < hi; i++)
    for (size_t j = lo; j < i; j++) {
      const double *a = B->M->xy + 2 * (size_t)id[i], *b = B->M->xy + 2 * (size_t)id[j];
      if (key[i] == key[j] && a[0] == b[0] && a[1] == b[1]) {
        const uint32_t r = rep[id[j]] < id[i] ? rep[id[j]] : id[i];
        rep[id[i]] = r;
        B->nf[r] |= B->nf[id[i]] & (N_FEATURE | N_MOVED);
        break;
      }
    }
}

/* Returns 0 when nothing is left of the cell. */
static int collapse_cell(qb *B, size_t c, const uint32_t *rep) {
  uint32_t *v = B->M->conn + 4 * c, w[4];
  const int nv = nv_of(B, c);
  int n = 0;
  for (int k = 0; k < nv; k++) {
    const uint32_t r = rep[v[k]];
    if (r != rep[v[nxt(k, nv)]]) w[n++] = r;
  }
  if (n < 3 || (n == 4 && (w[0] == w[2] || w[1] == w[3]))) return 0;
  for (int k = 0; k < 4; k++) v[k] = k < n ? w[k] : UINT32_MAX;
  B->M->type[c] = n == 4 ? MX_QQUAD : MX_QTRI;
  if (n == 3) B->split[c] = 0;
  return 1;
}

static int merge_same(qb *B) {
  uint64_t *pos = mx_alloc((B->n + 1) * sizeof *pos);
  uint32_t *rep = mx_alloc(B->n * sizeof *rep + 1);
  if (!pos || !rep) return mx_free(pos), mx_free(rep), MX_ENOMEM;
#pragma omp parallel for schedule(static)
  for (size_t v = 0; v < B->n; v++) {
    rep[v] = (uint32_t)v;
    pos[v] = (B->nf[v] & N_ONPOLY) && ncells_at(B, v) > 0;
  }
  pos[B->n] = 0;
  const size_t nb = mx_scan_u64(pos, B->n + 1);
  uint64_t *key = mx_alloc(nb * sizeof *key + 1);
  uint32_t *id = mx_alloc(nb * sizeof *id + 1);
  int st = key && id ? MX_OK : MX_ENOMEM;
  if (st == MX_OK) {
#pragma omp parallel for schedule(static)
    for (size_t v = 0; v < B->n; v++)
      if (pos[v + 1] > pos[v]) key[pos[v]] = coord_hash(B->M->xy + 2 * v), id[pos[v]] = (uint32_t)v;
    st = mx_sort_u64(key, id, nb) == MX_OK ? MX_OK : MX_ENOMEM;
  }
  size_t merged = 0;
  /* one group of equal keys per iteration that starts it: disjoint writes */
#pragma omp parallel for schedule(dynamic, 1024) reduction(+ : merged)
  for (size_t i = 0; i < (st == MX_OK ? nb : 0); i++) {
    if (i > 0 && key[i - 1] == key[i]) continue;
    size_t j = i + 1;
    while (j < nb && key[j] == key[i]) j++;
    if (j - i > 1) group_same(B, key, id, i, j, rep), merged++;
  }
  if (st == MX_OK && merged) {
#pragma omp parallel for schedule(static)
    for (size_t i = 0; i < ncells_act(B); i++) {
      const size_t c = cell_act(B, i);
      if (B->alive[c]) B->alive[c] = (uint8_t)collapse_cell(B, c, rep);
      else if (B->ghost[c]) B->ghost[c] = (uint8_t)collapse_cell(B, c, rep);
    }
    st = build_node_cells(B);
  }
  mx_free(pos), mx_free(rep), mx_free(key), mx_free(id);
  return st;
}

/* The edge of invalid cell c to close: two nodes on the polylines, one of
 * them moved there (and no feature); the shortest such. *s gets the node
 * that moves, *t the one it goes onto. 0 when there is none. */
static int fold_edge(const qb *B, size_t c, uint32_t *s, uint32_t *t) {
  const uint32_t *v = B->M->conn + 4 * c;
  const int nv = nv_of(B, c);
  double best = INFINITY;
  for (int k = 0; k < nv; k++) {
    uint32_t a = v[k], b = v[nxt(k, nv)];
    if (!(B->nf[a] & B->nf[b] & N_ONPOLY)) continue;
    const int ma = (B->nf[a] & (N_SHRUNK | N_CLOSE)) && !(B->nf[a] & N_FEATURE);
    const int mb = (B->nf[b] & (N_SHRUNK | N_CLOSE)) && !(B->nf[b] & N_FEATURE);
    if (!ma && !mb) continue;
    /* the shrunk one moves rather than a close one; then the larger id */
    if (!ma || (mb && ((B->nf[b] & N_SHRUNK) > (B->nf[a] & N_SHRUNK) ||
                       ((B->nf[b] & N_SHRUNK) == (B->nf[a] & N_SHRUNK) && b > a)))) {
      const uint32_t x = a;
      a = b, b = x;
    }
    const double l = hypot(B->M->xy[2 * (size_t)a] - B->M->xy[2 * (size_t)b],
                           B->M->xy[2 * (size_t)a + 1] - B->M->xy[2 * (size_t)b + 1]);
    if (l < best) best = l, *s = a, *t = b;
  }
  return best < INFINITY;
}

/* A cell gone at the removal whose nodes all stayed, on the polylines, and
 * that the shrink folded: the cells on its two sides now overlap (a part of
 * the domain thinner than the cells); closing it as a fold joins them. */
static int folded_ghost(const qb *B, size_t c) {
  if (!B->ghost[c]) return 0;
  const uint32_t *v = B->M->conn + 4 * c;
  const int nv = nv_of(B, c);
  for (int k = 0; k < nv; k++)
    if (!(B->nf[v[k]] & N_ONPOLY) || ncells_at(B, v[k]) == 0) return 0;
  return !(mx_qsj_nodes(B->M->xy, v, nv) > SJ_OK);
}

static void atomic_min_u32(uint32_t *p, uint32_t x) {
  uint32_t o = __atomic_load_n(p, __ATOMIC_RELAXED);
  while (x < o && !__atomic_compare_exchange_n(p, &o, x, 1, __ATOMIC_RELAXED, __ATOMIC_RELAXED)) {}
}

/* One round of closing folds: the shrink put two nodes of a cell on the
 * polylines in the wrong order (an invalid cell that no diagonal split
 * fixes, or a folded ghost); the moved one goes onto the other along their
 * edge (fold_edge) and merge_same makes them one node. */
static int fold_round(qb *B, uint32_t *want, uint8_t *go, int count, size_t *done) {
#pragma omp parallel for schedule(static)
  for (size_t v = 0; v < B->n; v++) want[v] = UINT32_MAX;
  size_t fixed = 0;
#pragma omp parallel for schedule(dynamic, 1024) reduction(+ : fixed)
  for (size_t i = 0; i < ncells_act(B); i++) {
    const size_t c = cell_act(B, i);
    uint32_t s = 0, t = 0;
    if (!B->alive[c] || cell_ok(B, c)) continue;
    if (B->M->type[c] == MX_QQUAD && (B->split[c] = (uint8_t)best_split(B, c))) fixed++;
    else if (fold_edge(B, c, &s, &t)) atomic_min_u32(&want[s], t);
  }
  B->st->inverted += count ? fixed : 0;
  /* the folded ghosts for the nodes no alive cell wants to move */
#pragma omp parallel for schedule(static)
  for (size_t v = 0; v < B->n; v++) go[v] = want[v] != UINT32_MAX;
#pragma omp parallel for schedule(dynamic, 1024)
  for (size_t i = 0; i < ncells_act(B); i++) {
    const size_t c = cell_act(B, i);
    uint32_t s = 0, t = 0;
    if (folded_ghost(B, c) && fold_edge(B, c, &s, &t) && !go[s]) atomic_min_u32(&want[s], t);
  }
  /* Decided on the positions before the round, then applied: a move that
   * would break another cell of its node is dropped; a node whose target
   * moves too waits for the next round (of two sent onto each other, the
   * larger id goes). */
#pragma omp parallel for schedule(dynamic, 1024)
  for (size_t v = 0; v < B->n; v++)
    if (want[v] != UINT32_MAX && !move_ok(B, (uint32_t)v, B->M->xy + 2 * (size_t)want[v], 1))
      want[v] = UINT32_MAX - 1;
#pragma omp parallel for schedule(static)
  for (size_t v = 0; v < B->n; v++) {
    const uint32_t t = want[v];
    go[v] = t < UINT32_MAX - 1 && (want[t] >= UINT32_MAX - 1 || (want[t] == v && v > t));
  }
  size_t moved = 0;
#pragma omp parallel for schedule(static) reduction(+ : moved)
  for (size_t v = 0; v < B->n; v++)
    if (go[v]) {
      B->M->xy[2 * v] = B->M->xy[2 * (size_t)want[v]];
      B->M->xy[2 * v + 1] = B->M->xy[2 * (size_t)want[v] + 1];
      moved++;
    }
  *done = moved;
  B->st->inverted += moved;
  return moved ? merge_same(B) : MX_OK;
}

/* Before the surface patterns, which decide every quad again, the splits
 * made here only let the folds be seen (not counted); after, they count. */
static int close_folds(qb *B, int count) {
  uint32_t *want = mx_alloc(B->n * sizeof *want + 1);
  uint8_t *go = mx_alloc(B->n + 1);
  size_t done = 1;
  int st = want && go ? MX_OK : MX_ENOMEM;
  for (int r = 0; r < 16 && done && st == MX_OK; r++) st = fold_round(B, want, go, count, &done);
  mx_free(want), mx_free(go);
  return st;
}

static int corner_of(const qb *B, size_t c, uint32_t v) {
  for (int k = 0; k < nv_of(B, c); k++)
    if (B->M->conn[4 * c + k] == v) return k;
  return -1;
}

/* The alive cells with edge a-b (either way). */
static size_t edge_cells(const qb *B, uint32_t a, uint32_t b) {
  size_t n = 0;
  for (uint64_t i = B->off[a]; i < B->off[a + 1]; i++) {
    const size_t c = B->ids[i];
    const int nv = nv_of(B, c), k = corner_of(B, c, a);
    n += B->M->conn[4 * c + nxt(k, nv)] == b || B->M->conn[4 * c + prv(k, nv)] == b;
  }
  return n;
}

/* The vertex of the polylines nearest to p among the ends of the segment
 * closest to it. */
static uint32_t near_vertex(const qb *B, const double p[2]) {
  double q[2], d2;
  const uint32_t s = mx_poly_closest(B->I, p, INFINITY, q, &d2);
  if (s == UINT32_MAX) return UINT32_MAX;
  const uint32_t a = B->P->seg[2 * (size_t)s], b = B->P->seg[2 * (size_t)s + 1];
  const double *pa = B->P->xy + 2 * (size_t)a, *pb = B->P->xy + 2 * (size_t)b;
  return hypot(pa[0] - p[0], pa[1] - p[1]) <= hypot(pb[0] - p[0], pb[1] - p[1]) ? a : b;
}

/* What the rounds of notch closing remember of each side of each active
 * cell: its ends when last measured (NONE2: never) and whether its middle
 * lay outside and far then; per node, the round (plus one) it last moved
 * in. A side whose ends are the same and did not move in the round before
 * has the same middle: its answer stands. */
#define NONE2 UINT64_MAX
typedef struct {
  uint64_t *ends;
  uint8_t *far, *moved;
  uint8_t round;
} notch_memo;

/* Boundary edge a-b cuts across a notch when its middle lies
 * outside the domain by more than a tenth of its length (its two nodes went
 * onto the two sides of a reflex corner): the moved one of the two nearer to
 * the corner goes onto it. Returns 1 with *s (node) and *t (vertex). The
 * side's slot j of the memo. */
static int notch_edge(const qb *B, uint32_t a, uint32_t b, uint32_t *s, uint32_t *t,
                      notch_memo *N, size_t j) {
  if (!(B->nf[a] & B->nf[b] & N_ONPOLY) || edge_cells(B, a, b) != 1) return 0;
  const double *pa = B->M->xy + 2 * (size_t)a, *pb = B->M->xy + 2 * (size_t)b;
  const double mid[2] = {0.5 * (pa[0] + pb[0]), 0.5 * (pa[1] + pb[1])};
  const uint64_t ends = (uint64_t)a << 32 | b;
  if (N->ends[j] != ends || N->moved[a] == N->round || N->moved[b] == N->round) {
    double q[2], d2;
    const double len = hypot(pb[0] - pa[0], pb[1] - pa[1]);
    N->far[j] = !(mx_poly_inside(B->I, mid) != 0 ||
                  mx_poly_closest(B->I, mid, 0.1 * len, q, &d2) != UINT32_MAX);
    N->ends[j] = ends;
  }
  if (!N->far[j]) return 0;
  const uint32_t v = near_vertex(B, mid);
  const double *pv = B->P->xy + 2 * (size_t)v;
  const int ma = (B->nf[a] & (N_SHRUNK | N_CLOSE)) && !(B->nf[a] & N_FEATURE);
  const int mb = (B->nf[b] & (N_SHRUNK | N_CLOSE)) && !(B->nf[b] & N_FEATURE);
  if (v == UINT32_MAX || (!ma && !mb)) return 0;
  const double da = hypot(pa[0] - pv[0], pa[1] - pv[1]), db = hypot(pb[0] - pv[0], pb[1] - pv[1]);
  *s = ma && (!mb || da < db || (da == db && a > b)) ? a : b;
  *t = v;
  return 1;
}

/* One round of notch closing (notch_edge); nodes sent onto a vertex that
 * holds a node become that node (merge_same). */
static int notch_round(qb *B, uint32_t *want, notch_memo *N, size_t *done) {
#pragma omp parallel for schedule(static)
  for (size_t v = 0; v < B->n; v++) want[v] = UINT32_MAX;
#pragma omp parallel for schedule(dynamic, 1024)
  for (size_t i = 0; i < ncells_act(B); i++) {
    const size_t c = cell_act(B, i);
    if (!B->alive[c]) continue;
    const int nv = nv_of(B, c);
    for (int k = 0; k < nv; k++) {
      uint32_t s, t;
      if (notch_edge(B, B->M->conn[4 * c + k], B->M->conn[4 * c + nxt(k, nv)], &s, &t, N,
                     4 * i + (size_t)k))
        atomic_min_u32(&want[s], t);
    }
  }
  /* decided on the positions before the round, then applied */
#pragma omp parallel for schedule(dynamic, 1024)
  for (size_t v = 0; v < B->n; v++)
    if (want[v] != UINT32_MAX && !move_ok(B, (uint32_t)v, B->P->xy + 2 * (size_t)want[v], 1))
      want[v] = UINT32_MAX;
  size_t moved = 0;
#pragma omp parallel for schedule(static) reduction(+ : moved)
  for (size_t v = 0; v < B->n; v++)
    if (want[v] != UINT32_MAX) {
      B->M->xy[2 * v] = B->P->xy[2 * (size_t)want[v]];
      B->M->xy[2 * v + 1] = B->P->xy[2 * (size_t)want[v] + 1];
      N->moved[v] = (uint8_t)(N->round + 1);
      moved++;
    }
  *done = moved;
  N->round++;
  return moved ? merge_same(B) : MX_OK;
}

static int close_notches(qb *B) {
  const size_t ns = 4 * ncells_act(B);
  uint32_t *want = mx_alloc(B->n * sizeof *want + 1);
  notch_memo N = {mx_alloc(ns * sizeof *N.ends + 1), mx_alloc(ns + 1), mx_calloc(B->n + 1), 0};
  int st = want && N.ends && N.far && N.moved ? MX_OK : MX_ENOMEM;
  if (st == MX_OK) {
#pragma omp parallel for schedule(static)
    for (size_t j = 0; j < ns; j++) N.ends[j] = NONE2;
  }
  size_t done = 1;
  for (int r = 0; r < 16 && done && st == MX_OK; r++) st = notch_round(B, want, &N, &done);
  mx_free(want), mx_free(N.ends), mx_free(N.far), mx_free(N.moved);
  return st;
}

/* ---- step 5: surface patterns ---------------------------------------------- */

/* The angle of the mesh at each node: the sum of its cells' angles (360
 * inside the mesh, the angle between its two boundary edges on it). */
static void node_angles(const qb *B, double *theta) {
#pragma omp parallel for schedule(dynamic, 1024)
  for (size_t v = 0; v < B->n; v++) {
    double a = 0;
    /* only read for the nodes not inside (quad_pattern) */
    for (uint64_t i = B->off[v]; i < (B->nf[v] & N_IN ? B->off[v] : B->off[v + 1]); i++) {
      const size_t c = B->ids[i];
      a += mx_qangle_at(B->M->xy, B->M->conn + 4 * c, nv_of(B, c), corner_of(B, c, (uint32_t)v));
    }
    theta[v] = a;
  }
}

/* The folded angle of triangle t at corner k: in [0, 180] whichever way
 * round the triangle goes. */
static double folded_angle(const double *xy, const uint32_t *t, int k) {
  const double g = mx_qangle_at(xy, t, 3, k);
  return g > 180.0 ? 360.0 - g : g;
}

/* A sliver: a triangle with an angle under 5 degrees (so also any with one
 * over 175: three nodes on a line). */
static int sliver(const double *xy, const uint32_t *t) {
  for (int k = 0; k < 3; k++)
    if (folded_angle(xy, t, k) < 180.0 - FLAT_LO) return 1;
  return 0;
}

/* Whether triangle t lies outside the domain (its centroid does). */
static int outside_tri(const qb *B, const uint32_t *t) {
  double p[2] = {0, 0};
  for (int k = 0; k < 3; k++)
    p[0] += B->M->xy[2 * (size_t)t[k]] / 3, p[1] += B->M->xy[2 * (size_t)t[k] + 1] / 3;
  return mx_poly_inside(B->I, p) == 0;
}

/* Corner k of quad v can go when it makes with its two neighbours, all on
 * the polylines, a triangle along the boundary. Either its node is this
 * quad's only (and no feature: it leaves the mesh) and that triangle is a
 * sliver or lies outside the domain (Fig. 8(b): a flat corner; or a node
 * shrunk past a reflex corner), or its corner is a spike (a node shrunk
 * past its neighbour: it stays in its other cells, on no edge of this
 * one). */
static int droppable(const qb *B, const uint32_t *v, int k) {
  const uint32_t t[3] = {v[(k + 3) & 3], v[k], v[(k + 1) & 3]};
  if (!(B->nf[t[0]] & B->nf[t[1]] & B->nf[t[2]] & N_ONPOLY)) return 0;
  if (ncells_at(B, v[k]) == 1)
    return !(B->nf[v[k]] & N_FEATURE) && (sliver(B->M->xy, t) || outside_tri(B, t));
  return folded_angle(B->M->xy, t, 1) < 180.0 - FLAT_LO;
}

/* Whether corner k of quad v may be over 90 degrees: a corner with both its
 * cross and dot products >= 0 is within [0, 90], under any bound used on it. */
static int obtuse_or_reflex(const double *xy, const uint32_t *v, int k) {
  const double *p = xy + 2 * (size_t)v[k];
  const double *a = xy + 2 * (size_t)v[(k + 1) & 3], *b = xy + 2 * (size_t)v[(k + 3) & 3];
  const double e1[2] = {a[0] - p[0], a[1] - p[1]}, e2[2] = {b[0] - p[0], b[1] - p[1]};
  return !(e1[0] * e2[1] - e1[1] * e2[0] >= 0 && e1[0] * e2[0] + e1[1] * e2[1] >= 0);
}

/* A quad (Fig. 8): a node counts as inside when it is, or when the mesh's
 * angle there is < 150 degrees. The quad changes when an outside corner is
 * >= 150 degrees, any corner >= 175, or a corner can be dropped: then a
 * droppable corner goes (the triangle of the other three, Fig. 8(b)), or
 * the quad is split along the diagonal from its widest corner (Fig. 8(e)).
 * Returns 1 when the quad changed. */
static int quad_pattern(qb *B, size_t c, const double *theta) {
  uint32_t *v = B->M->conn + 4 * c;
  const double *xy = B->M->xy;
  int drop = -1, wide = -1;
  double dsj = SJ_OK, wa = 0;
  for (int k = 0; k < 4; k++) {
    const double a = obtuse_or_reflex(xy, v, k) ? mx_qangle_at(xy, v, 4, k) : 0.0;
    const int in = (B->nf[v[k]] & N_IN) || theta[v[k]] < INSIDE_ANGLE;
    if (droppable(B, v, k)) {
      const uint32_t t[3] = {v[(k + 1) & 3], v[(k + 2) & 3], v[(k + 3) & 3]};
      const double s = mx_qsj_nodes(xy, t, 3);
      if (s > dsj) dsj = s, drop = k;
    }
    if (((!in && a >= INSIDE_ANGLE) || a >= FLAT_LO) && a > wa) wa = a, wide = k;
  }
  if (drop >= 0) {
    const uint32_t t[4] = {v[(drop + 1) & 3], v[(drop + 2) & 3], v[(drop + 3) & 3], UINT32_MAX};
    memcpy(v, t, sizeof t);
    B->M->type[c] = MX_QTRI;
    return 1;
  }
  if (wide < 0) return 0;
  const int k = wide & 1;
  if (split_sj(xy, v, k) > SJ_OK) B->split[c] = (uint8_t)(k + 1);
  else B->split[c] = (uint8_t)best_split(B, c);
  return B->split[c] != 0;
}

/* A sliver whose nodes all lie on the polylines goes when the side facing
 * its widest corner is on the mesh's boundary (so that the corner's node
 * hangs on no edge after) and no feature loses its last cell. */
static int tri_pattern(qb *B, size_t c) {
  const uint32_t *v = B->M->conn + 4 * c;
  if (!(B->nf[v[0]] & B->nf[v[1]] & B->nf[v[2]] & N_ONPOLY) || !sliver(B->M->xy, v)) return 0;
  int w = 0;
  for (int k = 0; k < 3; k++) {
    if ((B->nf[v[k]] & N_FEATURE) && ncells_at(B, v[k]) == 1) return 0;
    if (folded_angle(B->M->xy, v, k) > folded_angle(B->M->xy, v, w)) w = k;
  }
  if (edge_cells(B, v[(w + 1) % 3], v[(w + 2) % 3]) != 1) return 0;
  B->alive[c] = 0;
  return 1;
}

/* A cell whose nodes all lie on the polylines and whose centroid lies
 * outside the domain (a fold of the shrink along a reflex corner) goes,
 * unless a feature would lose its last cell. */
static int outside_cell(qb *B, size_t c) {
  const uint32_t *v = B->M->conn + 4 * c;
  const int nv = nv_of(B, c);
  for (int k = 0; k < nv; k++)
    if (!(B->nf[v[k]] & N_ONPOLY) || ((B->nf[v[k]] & N_FEATURE) && ncells_at(B, v[k]) == 1)) return 0;
  double p[2];
  centroid(B, c, p);
  if (mx_poly_inside(B->I, p) != 0) return 0;
  B->alive[c] = 0;
  return 1;
}

static int surface_patterns(qb *B) {
  double *theta = mx_alloc(B->n * sizeof *theta + 1);
  if (!theta) return MX_ENOMEM;
  node_angles(B, theta);
  size_t changed = 0;
#pragma omp parallel for schedule(dynamic, 1024) reduction(+ : changed)
  for (size_t i = 0; i < ncells_act(B); i++) {
    const size_t c = cell_act(B, i);
    if (!B->alive[c]) continue;
    B->split[c] = 0;
    if (outside_cell(B, c)) changed++;
    else changed += B->M->type[c] == MX_QQUAD ? quad_pattern(B, c, theta) : tri_pattern(B, c);
  }
  B->st->patterned = changed;
  mx_free(theta);
  return build_node_cells(B);
}

/* ---- the result -------------------------------------------------------------- */

static int first_invalid(const qb *B) {
  size_t bad = SIZE_MAX;
#pragma omp parallel for schedule(static) reduction(min : bad)
  for (size_t i = 0; i < ncells_act(B); i++) {
    const size_t c = cell_act(B, i);
    if (B->alive[c] && !cell_ok(B, c) && c < bad) bad = c;
  }
  if (bad == SIZE_MAX) return MX_OK;
  double p[2];
  centroid(B, bad, p);
  mx_error(B->P->path, 0,
           "boundary: the cell at (%.9g, %.9g) (level %d) has a scaled Jacobian of %g "
           "that no local repair makes positive",
           p[0], p[1], B->M->level[bad], cell_sj(B, bad));
  return MX_EINVALID;
}

/* ---- the steps in order ------------------------------------------------------- */

/* The steps in order on the band; the last repair (a shrunk node back
 * where it was: off the polylines) is for what the others left. Then the
 * band goes back into the mesh, compacted. */
static int run(qb *B, double close_ratio, mx_qband *band, mx_qmesh *M) {
  node_states(B);
  MX_CHECK(build_node_cells(B));
  MX_CHECK(features(B));
  MX_CHECK(close_nodes(B, close_ratio));
  MX_CHECK(remove_cells(B));
  MX_CHECK(shrink(B));
  MX_CHECK(merge_same(B));
  MX_CHECK(close_notches(B));
  MX_CHECK(close_folds(B, 0));
  MX_CHECK(surface_patterns(B));
  MX_CHECK(close_folds(B, 1));
  size_t undone = 0;
  MX_CHECK(repair(B, N_SHRUNK, 0, &undone));
  B->st->shrunk -= undone;
  MX_CHECK(first_invalid(B));
  mx_mem_mark("qboundary.run");
  return mx_qband_merge(band, B->alive, B->split, B->nf, N_MOVED | N_CLOSE | N_SHRUNK, M);
}

static double domain_size(const mx_poly *P) {
  double lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY};
  for (size_t i = 0; i < P->nv; i++)
    for (int a = 0; a < 2; a++) {
      lo[a] = mx_min(lo[a], P->xy[2 * i + a]);
      hi[a] = mx_max(hi[a], P->xy[2 * i + a]);
    }
  return P->nv ? hypot(hi[0] - lo[0], hi[1] - lo[1]) : 0;
}

/* Algorithm 2 on one band of M (or all of it). */
static int boundary_on(const mx_poly *P, const mx_poly_index *I, const mx_qtree *T,
                       double close_ratio, mx_qband *band, mx_qmesh *M, mx_qboundary_stats *st) {
  mx_qmesh *L = &band->L;
  qb B = {.M = L, .P = P, .I = I, .g = &T->grid, .n = L->nnodes, .m = L->ncells,
          .open = band->open, .deep = band->deep, .inside = band->inside, .band = band->act != NULL, .st = st};
  memset(B.st, 0, sizeof *B.st);
  B.tol = 1e-12 * domain_size(P);
  B.nf = mx_calloc(B.n + 1);
  B.xy0 = mx_alloc(2 * B.n * sizeof *B.xy0 + 1);
  B.alive = mx_alloc(B.m + 1);
  B.split = mx_calloc(B.m + 1);
  B.ghost = mx_calloc(B.m + 1);
  int st_ = B.nf && B.xy0 && B.alive && B.split && B.ghost ? MX_OK : MX_ENOMEM;
  if (st_ == MX_OK) {
    memset(B.alive, 1, B.m);
    st_ = run(&B, close_ratio, band, M);
  }
  mx_free(B.nf), mx_free(B.xy0), mx_free(B.alive), mx_free(B.split), mx_free(B.ghost);
  mx_free(B.off), mx_free(B.ids), mx_free(B.fnode), mx_free(B.fdir);
  mx_free(B.fvert), mx_free(B.vnb), mx_free(B.acell);
  return st_;
}

/* The band needs the leaves (the cells' quadrants) and a close ratio whose
 * radius stays under half a side (qband.c); else, or when the band cannot
 * be trusted, the whole mesh is the band. */
int mx_qboundary(const mx_poly *P, const mx_poly_index *I, const mx_qtree *T,
                 const uint32_t *leaves, double close_ratio, mx_qmesh *M,
                 mx_qboundary_stats *stats) {
  mx_qboundary_stats dummy;
  int whole = !leaves || !(close_ratio * sqrt(2.0) < 0.49);
  for (;;) {
    mx_qband band;
    int st = mx_qband_extract(I, T, leaves, whole, M, &band);
    mx_mem_mark("qboundary.band");
    if (st == MX_OK) st = boundary_on(P, I, T, close_ratio, &band, M, stats ? stats : &dummy);
    mx_qband_free(&band);
    if (st != QB_WHOLE) return st;
    whole = 1;
  }
}
