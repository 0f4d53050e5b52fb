/* Cleaving along an interface: see kernels/cleave.h. */
#include "kernels/cleave.h"

#include <math.h>
#include <string.h>

#include "base/common.h"
#include "geom/quality.h"
#include "kernels/boundary.h"
#include "kernels/colouring.h"
#include "kernels/pieces.h"
#include "kernels/mesh_edit.h"
#include "kernels/untangle.h"

enum { SIDE_ON = 0, SIDE_A = 1, SIDE_B = 2 };

static inline uint64_t dbits(double d) {
  uint64_t u;
  memcpy(&u, &d, sizeof u);
  return u; /* non-negative doubles order as their bits */
}

static double dist(const double *a, const double *b) {
  const double x = a[0] - b[0], y = a[1] - b[1], z = a[2] - b[2];
  return sqrt(x * x + y * y + z * z);
}

/* ---- growing arrays for the new elements and nodes ---- */

typedef struct {
  size_t n, cap;
  uint8_t *type, *level;
  uint32_t *conn, *leaf;
  float *jens;
} cells;

static int cells_push(cells *C, int type, const uint32_t *v, uint8_t level, uint32_t leaf,
                      float jens) {
  if (C->n == C->cap) {
    const size_t cap = C->cap ? 2 * C->cap : 1024;
    uint8_t *t = mx_realloc(C->type, cap);
    if (t) C->type = t;
    uint8_t *l = mx_realloc(C->level, cap);
    if (l) C->level = l;
    uint32_t *cn = mx_realloc(C->conn, 8 * cap * sizeof *cn);
    if (cn) C->conn = cn;
    uint32_t *lf = mx_realloc(C->leaf, cap * sizeof *lf);
    if (lf) C->leaf = lf;
    float *j = mx_realloc(C->jens, cap * sizeof *j);
    if (j) C->jens = j;
    if (!t || !l || !cn || !lf || !j) return MX_ENOMEM;
    C->cap = cap;
  }
  C->type[C->n] = (uint8_t)type;
  memset(C->conn + 8 * C->n, 0, 8 * sizeof *C->conn);
  memcpy(C->conn + 8 * C->n, v, (size_t)mx_cell_nodes[type] * sizeof *v);
  C->level[C->n] = level;
  C->leaf[C->n] = leaf;
  C->jens[C->n] = jens;
  C->n++;
  return MX_OK;
}

static void cells_free(cells *C) {
  mx_free(C->type);
  mx_free(C->level);
  mx_free(C->conn);
  mx_free(C->leaf);
  mx_free(C->jens);
}

/* The nodes added: positions, regions, and for the cut nodes the edge. */
typedef struct {
  size_t n, cap;
  double *xyz;
  uint16_t *depth;
  uint32_t *ea, *eb; /* cut node: its edge's A end and B end (UINT32_MAX: a centre) */
} added;

static int added_push(added *N, const double x[3], uint16_t d, uint32_t a, uint32_t b) {
  if (N->n == N->cap) {
    const size_t cap = N->cap ? 2 * N->cap : 1024;
    double *xyz = mx_realloc(N->xyz, 3 * cap * sizeof *xyz);
    if (xyz) N->xyz = xyz;
    uint16_t *dp = mx_realloc(N->depth, cap * sizeof *dp);
    if (dp) N->depth = dp;
    uint32_t *ea = mx_realloc(N->ea, cap * sizeof *ea);
    if (ea) N->ea = ea;
    uint32_t *eb = mx_realloc(N->eb, cap * sizeof *eb);
    if (eb) N->eb = eb;
    if (!xyz || !dp || !ea || !eb) return MX_ENOMEM;
    N->cap = cap;
  }
  memcpy(N->xyz + 3 * N->n, x, 3 * sizeof *x);
  N->depth[N->n] = d;
  N->ea[N->n] = a;
  N->eb[N->n] = b;
  N->n++;
  return MX_OK;
}

/* Open addressing: edge (lo, hi) -> its cut node, or quad face (4 sorted
 * ids folded) -> 1. */
typedef struct {
  size_t cap, n;
  uint64_t *key;
  uint64_t *key2;
  uint32_t *val;
} table;

static inline uint64_t mix64(uint64_t x) {
  x ^= x >> 33;
  x *= 0xff51afd7ed558ccdULL;
  x ^= x >> 33;
  x *= 0xc4ceb9fe1a85ec53ULL;
  x ^= x >> 33;
  return x;
}

static int table_init(table *T, size_t expect) {
  size_t cap = 1024;
  while (cap < 2 * expect + 2) cap *= 2;
  T->cap = cap;
  T->n = 0;
  T->key = mx_alloc(cap * sizeof *T->key);
  T->key2 = mx_alloc(cap * sizeof *T->key2);
  T->val = mx_alloc(cap * sizeof *T->val);
  if (!T->key || !T->key2 || !T->val) return MX_ENOMEM;
  for (size_t i = 0; i < cap; i++) T->key[i] = UINT64_MAX;
  return MX_OK;
}

static void table_free(table *T) {
  mx_free(T->key);
  mx_free(T->key2);
  mx_free(T->val);
  memset(T, 0, sizeof *T);
}

/* The slot of (k1, k2): found (*found 1) or the empty one to fill. */
static size_t table_slot(const table *T, uint64_t k1, uint64_t k2, int *found) {
  size_t i = (size_t)(mix64(k1 ^ mix64(k2)) & (T->cap - 1));
  while (T->key[i] != UINT64_MAX) {
    if (T->key[i] == k1 && T->key2[i] == k2) {
      *found = 1;
      return i;
    }
    i = (i + 1) & (T->cap - 1);
  }
  *found = 0;
  return i;
}

static int table_grow(table *T) {
  if (2 * (T->n + 1) < T->cap) return MX_OK;
  table B;
  if (table_init(&B, T->cap)) {
    table_free(&B);
    return MX_ENOMEM;
  }
  for (size_t i = 0; i < T->cap; i++) {
    if (T->key[i] == UINT64_MAX) continue;
    int f;
    const size_t s = table_slot(&B, T->key[i], T->key2[i], &f);
    B.key[s] = T->key[i];
    B.key2[s] = T->key2[i];
    B.val[s] = T->val[i];
  }
  B.n = T->n;
  table_free(T);
  *T = B;
  return MX_OK;
}

static void quad_key(const uint32_t *q, uint64_t *k1, uint64_t *k2) {
  uint32_t s[4] = {q[0], q[1], q[2], q[3]};
  for (int i = 1; i < 4; i++)
    for (int j = i; j > 0 && s[j - 1] > s[j]; j--) {
      const uint32_t x = s[j];
      s[j] = s[j - 1];
      s[j - 1] = x;
    }
  *k1 = (uint64_t)s[0] << 32 | s[1];
  *k2 = (uint64_t)s[2] << 32 | s[3];
}

/* ---- the state of one cleaving ---- */

typedef struct {
  mx_mesh *M;
  const mx_interfaces *I;
  uint32_t piece;    /* the pass: inside this piece is side A */
  const mx_surface_index *Sk; /* its index */
  const mx_surface_index *Si; /* its triangles on an interface (Sk when nested) */
  double hair;       /* within it of Sk: on it */
  const uint8_t *inA; /* per piece value (piece + 1): 1 when within the pass's piece */
  const mx_surface_index *Sd; /* the domain's surface (the outer boundary) */
  uint8_t *outer;    /* the old nodes on the outer boundary and no interface */
  uint8_t *side;     /* the old nodes' sides in this pass */
  uint8_t *rim;      /* per node (old, then new): on the interface and the outer boundary */
  double alpha;
  uint16_t *depth;   /* the old nodes' piece values (kernels/interfaces.h) */
  uint8_t *moved;    /* the old nodes warped */
  double *sd;        /* the old nodes' signed distances (nodes of cut elements) */
  table edges;       /* (lo, hi) -> cut node id */
  added N;           /* new nodes, ids from nn */
  cells C;
  size_t nn;
} cleaver;

/* The side of a piece value (a new node's). */
static inline int side_of(const cleaver *W, uint16_t d) {
  return d == MX_REGION_ON ? SIDE_ON : W->inA[d] ? SIDE_A : SIDE_B;
}

/* The side of node v: an old node's from W->side (a node on the outer
 * boundary has the side its position is on), a new node's from its piece. */
static inline int side_node(const cleaver *W, uint32_t v) {
  return v < W->nn ? W->side[v] : side_of(W, W->N.depth[v - W->nn]);
}

/* The distance from x to the interface, negative on side A (inside the
 * pass's piece, or on its own surface), positive on side B. */
static double iface_g(const cleaver *W, const double x[3]) {
  double q[3];
  const double d = mx_closest_point(W->Si, x, q, NULL, NULL);
  if (W->Si == W->Sk) return mx_signed_distance(W->Sk, x, NULL);
  return mx_signed_distance(W->Sk, x, NULL) > W->hair ? d : -d;
}

/* A point on the interface and the outer boundary near x (alternating
 * projections: the two surfaces cross there). */
static void rim_point(const cleaver *W, double x[3]) {
  double q[3];
  for (int it = 0; it < 24; it++) {
    mx_closest_point(W->Sd, x, q, NULL, NULL);
    mx_closest_point(W->Si, q, x, NULL, NULL);
    const double d = dist(x, q);
    if (d <= 1e-14 * (fabs(x[0]) + fabs(x[1]) + fabs(x[2]) + 1e-300)) break;
  }
}

/* Where the interface crosses the segment from p (side A, iface_g gp <= 0)
 * to q (side B, gq >= 0): the fraction t from p (Illinois iterations on
 * iface_g along the segment), x the point. */
static double crossing(const cleaver *W, const double *p, const double *q, double gp,
                       double gq, double x[3]) {
  double a = 0.0, b = 1.0, fa = gp < 0.0 ? gp : 0.0, fb = gq > 0.0 ? gq : 0.0;
  const double tol = 1e-13 * (dist(p, q) + 1e-300);
  double t = 0.5;
  if (fa == 0.0 && fb == 0.0) {
    t = 0.5;
  } else if (fa == 0.0) {
    t = 0.0;
  } else if (fb == 0.0) {
    t = 1.0;
  } else {
    int last = 0;
    for (int it = 0; it < 60; it++) {
      t = (a * fb - b * fa) / (fb - fa);
      if (!(t > a && t < b)) t = 0.5 * (a + b);
      double y[3];
      for (int i = 0; i < 3; i++) y[i] = p[i] + t * (q[i] - p[i]);
      const double ft = iface_g(W, y);
      if (fabs(ft) <= tol || b - a <= 1e-15) break;
      if (ft > 0.0) {
        b = t;
        fb = ft;
        if (last == 1) fa *= 0.5;
        last = 1;
      } else {
        a = t;
        fa = ft;
        if (last == -1) fb *= 0.5;
        last = -1;
      }
    }
  }
  for (int i = 0; i < 3; i++) x[i] = p[i] + t * (q[i] - p[i]);
  return t;
}

static double elem_jens(const mx_mesh *M, size_t c) {
  double x[8][3];
  const int nv = mx_cell_nodes[M->type[c]];
  for (int i = 0; i < nv; i++) memcpy(x[i], M->xyz + 3 * (size_t)M->conn[8 * c + i], sizeof x[i]);
  return mx_jens(M->type[c], (const double(*)[3])x);
}


static const double *node_xyz(const cleaver *W, uint32_t v) {
  return v < W->nn ? W->M->xyz + 3 * (size_t)v : W->N.xyz + 3 * (size_t)(v - W->nn);
}

/* Whether node a goes before node b: by lattice key (Morton order, as the
 * numbering of a whole mesh goes, but not a patch's), then, off the
 * lattice, by what they are, then (never for two lattice nodes) by number. */
static int before_node(const mx_mesh *M, uint32_t a, uint32_t b) {
  if (M->nkey && M->nkey[a] != M->nkey[b]) return M->nkey[a] < M->nkey[b];
  const uint64_t ia = mx_node_identity(M, a), ib = mx_node_identity(M, b);
  return ia != ib ? ia < ib : a < b;
}

/* The cut node of edge (a, b), a on side A and b on side B: made once. Its
 * position is found later (fill_cut_nodes). */
static int cut_node(cleaver *W, uint32_t a, uint32_t b, uint32_t *id) {
  if (table_grow(&W->edges)) return MX_ENOMEM;
  const uint64_t k1 = (uint64_t)(a < b ? a : b) << 32 | (a < b ? b : a);
  int found;
  const size_t s = table_slot(&W->edges, k1, 0, &found);
  if (found) {
    *id = W->edges.val[s];
    return MX_OK;
  }
  const double zero[3] = {0, 0, 0};
  MX_CHECK(added_push(&W->N, zero, MX_REGION_ON, a, b));
  *id = (uint32_t)(W->nn + W->N.n - 1);
  W->edges.key[s] = k1;
  W->edges.key2[s] = 0;
  W->edges.val[s] = *id;
  W->edges.n++;
  return MX_OK;
}

/* Even permutations of a tetrahedron putting vertex i last. */
static const int8_t last_even[4][4] = {{2, 1, 3, 0}, {0, 2, 3, 1}, {0, 3, 1, 2}, {0, 1, 2, 3}};

/* Piece of tetrahedron: written with its J_ENS (positions may still be
 * unknown for cut nodes: J_ENS is computed at the end). */
static int emit(cleaver *W, int type, const uint32_t *v, uint8_t level, uint32_t leaf) {
  return cells_push(&W->C, type, v, level, leaf, NAN);
}

/* Step 3 on the tetrahedron t (positively oriented). */
static int cut_tet(cleaver *W, const uint32_t t[4], uint8_t level, uint32_t leaf) {
  int s[4], na = 0, nb = 0;
  for (int i = 0; i < 4; i++) {
    s[i] = side_node(W, t[i]);
    na += s[i] == SIDE_A;
    nb += s[i] == SIDE_B;
  }
  if (!na || !nb) return emit(W, MX_TET, t, level, leaf);
  if (na == 2 && nb == 2) {
    int ia[2], ib[2], n1 = 0, n2 = 0;
    for (int i = 0; i < 4; i++) {
      if (s[i] == SIDE_A) ia[n1++] = i;
      else ib[n2++] = i;
    }
    /* (a1, a2, b1, b2) an even permutation of (0 1 2 3)? */
    const int perm[4] = {ia[0], ia[1], ib[0], ib[1]};
    int inv = 0;
    for (int i = 0; i < 4; i++)
      for (int j = i + 1; j < 4; j++) inv += perm[i] > perm[j];
    if (inv & 1) {
      const int x = ib[0];
      ib[0] = ib[1];
      ib[1] = x;
    }
    const uint32_t a1 = t[ia[0]], a2 = t[ia[1]], b1 = t[ib[0]], b2 = t[ib[1]];
    uint32_t c11, c12, c21, c22;
    MX_CHECK(cut_node(W, a1, b1, &c11));
    MX_CHECK(cut_node(W, a1, b2, &c12));
    MX_CHECK(cut_node(W, a2, b1, &c21));
    MX_CHECK(cut_node(W, a2, b2, &c22));
    const uint32_t pa[6] = {a1, c11, c12, a2, c21, c22};
    const uint32_t pb[6] = {b1, c11, c21, b2, c12, c22};
    MX_CHECK(emit(W, MX_PRISM, pa, level, leaf));
    return emit(W, MX_PRISM, pb, level, leaf);
  }
  /* one node alone on its side (the A one when one of each) */
  const int lone = na == 1 ? SIDE_A : SIDE_B;
  int ip = 0;
  while (s[ip] != lone) ip++;
  const int8_t *o = last_even[ip];
  const uint32_t p = t[o[3]];
  uint32_t x[3], y[3];
  int on = 0, jon = -1, joff = -1;
  for (int i = 0; i < 3; i++) {
    x[i] = t[o[i]];
    if (s[o[i]] == SIDE_ON) {
      y[i] = x[i];
      on++;
      jon = i;
    } else {
      joff = i;
      if (lone == SIDE_A) MX_CHECK(cut_node(W, p, x[i], &y[i]));
      else MX_CHECK(cut_node(W, x[i], p, &y[i]));
    }
  }
  const uint32_t tp[4] = {y[0], y[1], y[2], p};
  MX_CHECK(emit(W, MX_TET, tp, level, leaf));
  if (on == 0) {
    const uint32_t pr[6] = {x[0], x[1], x[2], y[0], y[1], y[2]};
    return emit(W, MX_PRISM, pr, level, leaf);
  }
  if (on == 1) {
    const int j = jon, j1 = (j + 1) % 3, j2 = (j + 2) % 3;
    const uint32_t py[5] = {x[j1], y[j1], y[j2], x[j2], x[j]};
    return emit(W, MX_PYRAMID, py, level, leaf);
  }
  const int j = joff;
  const uint32_t tt[4] = {x[j], x[(j + 1) % 3], x[(j + 2) % 3], y[j]};
  return emit(W, MX_TET, tt, level, leaf);
}

/* The tetrahedra (or the pyramid) on the outward face f of element row
 * about its centre c: a triangle gives one, a quad two (split along the
 * diagonal from its lowest node) when split, else a pyramid. */
static int face_pieces(cleaver *W, const uint32_t *row, const int8_t *f, uint32_t c, int split,
                       int cut, uint8_t level, uint32_t leaf) {
  if (f[3] < 0) {
    const uint32_t t[4] = {row[f[0]], row[f[2]], row[f[1]], c};
    return cut ? cut_tet(W, t, level, leaf) : emit(W, MX_TET, t, level, leaf);
  }
  const uint32_t q[4] = {row[f[0]], row[f[1]], row[f[2]], row[f[3]]};
  if (!split) {
    const uint32_t py[5] = {q[0], q[3], q[2], q[1], c};
    return emit(W, MX_PYRAMID, py, level, leaf);
  }
  int lo = 0; /* the least node by what it is: a neighbour's split agrees */
  for (int i = 1; i < 4; i++)
    if (before_node(W->M, q[i], q[lo])) lo = i;
  uint32_t t1[4], t2[4];
  if (lo == 0 || lo == 2) {
    const uint32_t a[4] = {q[0], q[2], q[1], c}, b[4] = {q[0], q[3], q[2], c};
    memcpy(t1, a, sizeof a);
    memcpy(t2, b, sizeof b);
  } else {
    const uint32_t a[4] = {q[1], q[3], q[2], c}, b[4] = {q[1], q[0], q[3], c};
    memcpy(t1, a, sizeof a);
    memcpy(t2, b, sizeof b);
  }
  if (cut) {
    MX_CHECK(cut_tet(W, t1, level, leaf));
    return cut_tet(W, t2, level, leaf);
  }
  MX_CHECK(emit(W, MX_TET, t1, level, leaf));
  return emit(W, MX_TET, t2, level, leaf);
}

/* Step 1: the nodes close to a crossing of their edges onto it. flag[v]
 * set for the nodes of the cut elements (1), the warped ones (2). */
static int warp(cleaver *W, uint8_t *flag, size_t *warped) {
  mx_mesh *M = W->M;
  const size_t nn = W->nn, nc = M->ncells;
  uint64_t *best = mx_alloc((nn + 1) * sizeof *best);
  uint32_t *bto = mx_alloc((nn + 1) * sizeof *bto);
  uint8_t *lock = mx_calloc(nn + 1);
  double *target = NULL;
  if (!best || !bto || !lock) {
    mx_free(best); mx_free(bto); mx_free(lock);
    return MX_ENOMEM;
  }
#pragma omp parallel for schedule(static)
  for (size_t c = 0; c < nc; c++) {
    const uint32_t *row = M->conn + 8 * c;
    const int nv = mx_cell_nodes[M->type[c]];
    int sides = 0;
    for (int i = 0; i < nv; i++) sides |= 1 << W->side[row[i]];
    if ((sides & 6) != 6) continue;
    for (int i = 0; i < nv; i++) __atomic_store_n(&flag[row[i]], 1, __ATOMIC_RELAXED);
  }
#pragma omp parallel for schedule(dynamic, 256)
  for (size_t v = 0; v < nn; v++) {
    best[v] = UINT64_MAX;
    bto[v] = UINT32_MAX;
    if (flag[v] && W->depth[v] != MX_REGION_ON)
      W->sd[v] = iface_g(W, M->xyz + 3 * v);
    else if (!W->outer[v])
      W->sd[v] = 0.0; /* (an outer node's is there: its side) */
  }
  /* each A-B pair of nodes of a cut element (an edge, or a diagonal that
   * the split may make an edge): its crossing (estimated from the two
   * signed distances) within alpha of an end is a candidate for that end */
#pragma omp parallel for schedule(static)
  for (size_t c = 0; c < nc; c++) {
    const uint32_t *row = M->conn + 8 * c;
    const int t = M->type[c];
    const int nv = mx_cell_nodes[t];
    if (!flag[row[0]]) continue; /* no cut element's */
    for (int e = 0; e < nv * nv; e++) {
      if (e / nv >= e % nv) continue;
      uint32_t a = row[e / nv], b = row[e % nv];
      int sa = W->side[a], sb = W->side[b];
      if (sa == SIDE_B && sb == SIDE_A) {
        const uint32_t x = a;
        a = b;
        b = x;
        sa = SIDE_A;
        sb = SIDE_B;
      }
      if (sa != SIDE_A || sb != SIDE_B) continue;
      const double ga = W->sd[a] < 0.0 ? -W->sd[a] : 0.0, gb = W->sd[b] > 0.0 ? W->sd[b] : 0.0;
      const double f = ga + gb > 0.0 ? ga / (ga + gb) : 0.5; /* from a */
      const double len = dist(M->xyz + 3 * (size_t)a, M->xyz + 3 * (size_t)b);
      uint32_t v = UINT32_MAX, other = UINT32_MAX;
      double d = 0.0;
      if (f < W->alpha) {
        v = a;
        other = b;
        d = f * len;
      } else if (1.0 - f < W->alpha) {
        v = b;
        other = a;
        d = (1.0 - f) * len;
      }
      if (v == UINT32_MAX) continue;
      const uint64_t mine = dbits(d);
      while (__atomic_test_and_set(&lock[v], __ATOMIC_ACQUIRE)) {
      }
      /* ties: the other end that is least, by what it is (not by its
       * number, which a rank's patch gives otherwise) */
      if (mine < best[v] ||
          (mine == best[v] && (bto[v] == UINT32_MAX || before_node(M, other, bto[v])))) {
        best[v] = mine;
        bto[v] = other;
      }
      __atomic_clear(&lock[v], __ATOMIC_RELEASE);
    }
  }
  mx_free(lock);
  mx_free(best);
  target = mx_alloc((3 * nn + 3) * sizeof *target);
  if (!target) {
    mx_free(bto);
    return MX_ENOMEM;
  }
  size_t n = 0;
#pragma omp parallel for schedule(dynamic, 256)
  for (size_t v = 0; v < nn; v++) {
    if (bto[v] == UINT32_MAX) continue;
    const uint32_t o = bto[v];
    const int va = W->side[v] == SIDE_A;
    const double *p = M->xyz + 3 * (va ? v : o), *q = M->xyz + 3 * (size_t)(va ? o : v);
    crossing(W, p, q, W->sd[va ? v : o], W->sd[va ? o : v], target + 3 * v);
    if (W->outer[v]) rim_point(W, target + 3 * v); /* it stays on the boundary */
  }
  /* the moves, each kept when no element around it drops below
   * min(floor, its J_ENS before): colour by colour (no two nodes of a
   * colour share an element), so that what is kept depends neither on the
   * numbering nor on the threads */
  uint8_t *mark = mx_alloc(nn + 1);
  uint64_t *off = NULL;
  uint32_t *inc = NULL, *work = NULL, *widx = NULL, *byc = NULL;
  int16_t *colour = NULL;
  size_t nw = 0;
  int st = mark ? MX_OK : MX_ENOMEM;
  if (!st) {
#pragma omp parallel for schedule(static)
    for (size_t v = 0; v < nn; v++) mark[v] = bto[v] != UINT32_MAX;
    st = mx_mesh_incidence(M, mark, &off, &inc);
  }
  for (size_t v = 0; v < nn && !st; v++) nw += mark[v];
  if (!st) {
    work = mx_alloc((nw + 1) * sizeof *work);
    widx = mx_alloc((nn + 1) * sizeof *widx);
    byc = mx_alloc((nw + 1) * sizeof *byc);
    colour = mx_alloc((nw + 1) * sizeof *colour);
    if (!work || !widx || !byc || !colour) st = MX_ENOMEM;
  }
  int ncol = 0;
  size_t cstart[MX_MAX_COLOURS + 1];
  if (!st) {
    size_t k = 0;
    for (size_t v = 0; v < nn; v++) {
      widx[v] = mark[v] ? (uint32_t)k : UINT32_MAX;
      if (mark[v]) work[k++] = (uint32_t)v;
    }
    ncol = mx_colour_nodes(M, inc, off, work, nw, widx, colour);
    if (ncol == -2) st = MX_ENOMEM;
    if (ncol == -1) {
      mx_error(NULL, 0, "more than %d colours in the cleaving", MX_MAX_COLOURS);
      st = MX_EINTERNAL;
    }
  }
  if (!st) {
    memset(cstart, 0, sizeof cstart);
    for (size_t i = 0; i < nw; i++) cstart[colour[i] + 1]++;
    for (int c = 0; c < ncol; c++) cstart[c + 1] += cstart[c];
    size_t fill[MX_MAX_COLOURS];
    memcpy(fill, cstart, sizeof fill);
    for (size_t i = 0; i < nw; i++) byc[fill[colour[i]]++] = work[i];
  }
  n = 0;
  for (int c = 0; c < ncol && !st; c++) {
#pragma omp parallel for schedule(dynamic, 32) reduction(+ : n) \
    if (cstart[c + 1] - cstart[c] >= 4096)
    for (size_t k = cstart[c]; k < cstart[c + 1]; k++) {
      const uint32_t v = byc[k];
      double *x = M->xyz + 3 * (size_t)v, x0[3];
      memcpy(x0, x, sizeof x0);
      double before[64];
      const uint64_t e0 = off[v], ne = off[v + 1] - e0 < 64 ? off[v + 1] - e0 : 64;
      for (uint64_t e = 0; e < ne; e++) before[e] = elem_jens(M, inc[e0 + e]);
      memcpy(x, target + 3 * (size_t)v, sizeof x0);
      int ok = off[v + 1] - e0 <= 64;
      for (uint64_t e = 0; e < ne && ok; e++)
        ok = elem_jens(M, inc[e0 + e]) >= fmin(MX_CLEAVE_FLOOR, before[e]);
      if (!ok) {
        memcpy(x, x0, sizeof x0);
        continue;
      }
      W->depth[v] = MX_REGION_ON;
      W->moved[v] = 1;
      W->rim[v] = W->outer[v];
      W->outer[v] = 0; /* on the interface now */
      W->side[v] = SIDE_ON;
      n++;
    }
  }
  mx_free(work);
  mx_free(widx);
  mx_free(byc);
  mx_free(colour);
  mx_free(mark);
  mx_free(off);
  mx_free(inc);
  mx_free(target);
  mx_free(bto);
  *warped += n;
  return st;
}

/* The centre of cut element row (a hexahedron or prism) and its region.
 * A centre nearer the interface than alpha of its distance to the nearest
 * node moves away from it to that distance, on its side: the tetrahedra
 * on the element's faces lying on the interface then keep a height. */
static uint16_t cut_centre(const cleaver *W, const uint32_t *row, int t, double x[3]) {
  const mx_mesh *M = W->M;
  const int nv = mx_cell_nodes[t];
  x[0] = x[1] = x[2] = 0.0;
  for (int i = 0; i < nv; i++)
    for (int a = 0; a < 3; a++) x[a] += M->xyz[3 * (size_t)row[i] + a] / nv;
  double near = INFINITY, q[3];
  for (int i = 0; i < nv; i++) near = fmin(near, dist(x, M->xyz + 3 * (size_t)row[i]));
  const double g = iface_g(W, x);
  mx_closest_point(W->Si, x, q, NULL, NULL);
  const double gap = dist(x, q);
  if (fabs(g) < W->alpha * near && gap > 0.0) {
    const double f = W->alpha * near / gap;
    for (int a = 0; a < 3; a++) x[a] = q[a] + f * (x[a] - q[a]);
  }
  int r = mx_interfaces_piece(W->I, x); /* on the side the signed distance says */
  if (g < 0.0 && !W->inA[r]) r = (int)W->piece + 1;
  if (g >= 0.0 && W->inA[r]) r = W->I->parent[W->piece] + 1;
  return (uint16_t)r;
}

/* Which quad faces of cut element row (centre region cd) are split into
 * triangles: those holding a node on a side other than the centre's (the
 * pyramid on the face would cross the interface); bit f for face f. */
static uint8_t split_faces(const cleaver *W, const uint32_t *row, int t, uint16_t cd) {
  const int cs = side_of(W, cd);
  uint8_t m = 0;
  for (int f = 0; f < mx_cell_nfaces[t]; f++) {
    const int8_t *fv = mx_cell_faces[t][f];
    if (fv[3] < 0) continue;
    int sides = 0;
    for (int i = 0; i < 4; i++) sides |= 1 << W->side[row[fv[i]]];
    sides &= (1 << SIDE_A) | (1 << SIDE_B);
    if (t == MX_PYRAMID || sides == ((1 << SIDE_A) | (1 << SIDE_B)) ||
        (sides & ~(1 << cs)))
      m |= (uint8_t)(1u << f);
  }
  return m;
}

static int cleave(cleaver *W, mx_cleave_stats *stats) {
  mx_mesh *M = W->M;
  const size_t nn = W->nn, nc = M->ncells;
  uint8_t *flag = mx_calloc(nn + 1);
  W->moved = mx_calloc(nn + 1);
  const double t0 = mx_wtime();
  int st = !flag || !W->moved ? MX_ENOMEM : warp(W, flag, &stats->warped);
  stats->t_warp += mx_wtime() - t0;
  if (st) {
    mx_free(flag);
    return st;
  }
  /* the cut elements (what 1), their centres and split faces; then the
   * neighbours sharing a split face (what 2) */
  uint8_t *what = mx_calloc(nc + 1);
  uint8_t *facemask = mx_calloc(nc + 1);
  uint32_t *slot = mx_alloc((nc + 1) * sizeof *slot);
  if (!what || !facemask || !slot) {
    mx_free(flag); mx_free(what); mx_free(facemask); mx_free(slot);
    return MX_ENOMEM;
  }
  size_t ncut = 0;
  for (size_t c = 0; c < nc; c++) { /* numbered in order */
    const uint32_t *row = M->conn + 8 * c;
    const int nv = mx_cell_nodes[M->type[c]];
    int sides = 0;
    for (int i = 0; i < nv; i++) sides |= 1 << W->side[row[i]];
    slot[c] = UINT32_MAX;
    if ((sides & 6) == 6) {
      what[c] = 1;
      slot[c] = (uint32_t)ncut++;
    }
  }
  double *cx = mx_alloc((3 * ncut + 3) * sizeof *cx);
  uint16_t *cd = mx_alloc((ncut + 1) * sizeof *cd);
  if (!cx || !cd) st = MX_ENOMEM;
#pragma omp parallel for schedule(dynamic, 64)
  for (size_t c = 0; c < nc; c++) {
    if (st || what[c] != 1) continue;
    const int t = M->type[c];
    const uint32_t *row = M->conn + 8 * c;
    const uint32_t i = slot[c];
    cd[i] = t == MX_HEX || t == MX_PRISM ? cut_centre(W, row, t, cx + 3 * (size_t)i)
                                          : t == MX_PYRAMID ? W->depth[row[4]] : 0;
    facemask[c] = t == MX_TET ? 0 : split_faces(W, row, t, cd[i]);
  }
  table faces;
  memset(&faces, 0, sizeof faces);
  if (!st) st = table_init(&faces, 6 * ncut);
  if (!st) st = table_init(&W->edges, 64 * ncut);
  for (size_t c = 0; c < nc && !st; c++) {
    if (what[c] != 1) continue;
    const int t = M->type[c];
    const uint32_t *row = M->conn + 8 * c;
    for (int f = 0; f < mx_cell_nfaces[t]; f++) {
      if (!((facemask[c] >> f) & 1)) continue;
      const int8_t *fv = mx_cell_faces[t][f];
      const uint32_t q[4] = {row[fv[0]], row[fv[1]], row[fv[2]], row[fv[3]]};
      uint64_t k1, k2;
      quad_key(q, &k1, &k2);
      int found;
      const size_t s = table_slot(&faces, k1, k2, &found);
      if (!found) {
        faces.key[s] = k1;
        faces.key2[s] = k2;
        faces.val[s] = 1;
        faces.n++;
      }
      for (int i = 0; i < 4; i++) flag[q[i]] |= 4; /* on a split quad face */
    }
  }
  size_t nnb = 0;
#pragma omp parallel for schedule(static) reduction(+ : nnb)
  for (size_t c = 0; c < nc; c++) {
    if (st || what[c]) continue;
    const int t = M->type[c];
    const uint32_t *row = M->conn + 8 * c;
    uint8_t m = 0;
    for (int f = 0; f < mx_cell_nfaces[t]; f++) {
      const int8_t *fv = mx_cell_faces[t][f];
      if (fv[3] < 0) continue;
      if (!(flag[row[fv[0]]] & flag[row[fv[1]]] & flag[row[fv[2]]] & flag[row[fv[3]]] & 4))
        continue;
      const uint32_t q[4] = {row[fv[0]], row[fv[1]], row[fv[2]], row[fv[3]]};
      uint64_t k1, k2;
      quad_key(q, &k1, &k2);
      int found;
      table_slot(&faces, k1, k2, &found);
      if (found) m |= (uint8_t)(1u << f);
    }
    if (m) {
      what[c] = 2;
      facemask[c] = m;
      nnb++;
    }
  }
  table_free(&faces);
  stats->cut += ncut;
  stats->neighbours += nnb;
  /* the pieces, element by element in order (new nodes numbered in that
   * order: the same for any thread count) */
  for (size_t c = 0; c < nc && !st; c++) {
    const int t = M->type[c];
    const uint32_t *row = M->conn + 8 * c;
    if (!what[c]) {
      st = cells_push(&W->C, t, row, M->level[c], M->leaf[c], M->jens[c]);
      continue;
    }
    const int cut = what[c] == 1;
    if (t == MX_TET) {
      st = cut_tet(W, row, M->level[c], M->leaf[c]);
      continue;
    }
    uint32_t centre = row[4]; /* a pyramid's apex */
    if (t == MX_HEX || t == MX_PRISM) {
      double x[3];
      uint16_t d;
      if (cut) {
        memcpy(x, cx + 3 * (size_t)slot[c], sizeof x);
        d = cd[slot[c]];
      } else { /* the element's side */
        const int nv = mx_cell_nodes[t];
        x[0] = x[1] = x[2] = 0.0;
        for (int i = 0; i < nv; i++)
          for (int a = 0; a < 3; a++) x[a] += M->xyz[3 * (size_t)row[i] + a] / nv;
        d = 0;
        for (int i = 0; i < nv; i++)
          if (W->depth[row[i]] != MX_REGION_ON) d = W->depth[row[i]];
        if (d == 0) d = (uint16_t)mx_interfaces_piece(W->I, x);
      }
      st = added_push(&W->N, x, d, UINT32_MAX, UINT32_MAX);
      if (st) break;
      centre = (uint32_t)(nn + W->N.n - 1);
      stats->centres++;
    }
    for (int f = 0; f < mx_cell_nfaces[t] && !st; f++) {
      if (t == MX_PYRAMID && f > 0) break; /* the apex is the centre */
      const int split = (facemask[c] >> f) & 1;
      st = face_pieces(W, row, mx_cell_faces[t][f], centre, split, cut, M->level[c],
                       M->leaf[c]);
    }
  }
  mx_free(cx);
  mx_free(cd);
  mx_free(slot);
  mx_free(what);
  mx_free(facemask);
  mx_free(flag);
  return st;
}

/* The cut nodes on their edges (in parallel: each its own), then the new
 * mesh in place of the old. */
static int finish(cleaver *W, mx_cleave_stats *stats) {
  mx_mesh *M = W->M;
  const size_t nn = W->nn, na = W->N.n;
  uint8_t *rim = mx_realloc(W->rim, nn + na + 1);
  if (!rim) return MX_ENOMEM;
  W->rim = rim;
  memset(rim + nn, 0, na);
  size_t ncut = 0;
#pragma omp parallel for schedule(dynamic, 64) reduction(+ : ncut)
  for (size_t i = 0; i < na; i++) {
    if (W->N.ea[i] == UINT32_MAX) continue;
    const uint32_t a = W->N.ea[i], b = W->N.eb[i];
    const double *p = node_xyz(W, a), *q = node_xyz(W, b);
    const double ga = a < nn ? W->sd[a] : iface_g(W, p);
    const double gb = b < nn ? W->sd[b] : iface_g(W, q);
    if (a < nn && b < nn && W->outer[a] && W->outer[b]) {
      /* both on the outer boundary: where the interface meets it, from the
       * estimate on the edge */
      const double da = fabs(ga), db = fabs(gb), f = da + db > 0 ? da / (da + db) : 0.5;
      double *x = W->N.xyz + 3 * i;
      for (int c = 0; c < 3; c++) x[c] = p[c] + f * (q[c] - p[c]);
      rim_point(W, x);
      W->rim[nn + i] = 1;
    } else {
      crossing(W, p, q, ga, gb, W->N.xyz + 3 * i);
    }
    ncut++;
  }
  stats->cut_nodes += ncut;
  double *xyz = mx_realloc(M->xyz, (3 * (nn + na) + 3) * sizeof *xyz);
  if (!xyz) return MX_ENOMEM;
  M->xyz = xyz;
  memcpy(M->xyz + 3 * nn, W->N.xyz, 3 * na * sizeof *xyz);
  if (M->nkey) {
    uint64_t *nk = mx_realloc(M->nkey, (nn + na + 1) * sizeof *nk);
    if (!nk) return MX_ENOMEM;
    M->nkey = nk;
    /* a cut node between two lattice nodes: a key from theirs (top bit set:
     * never a lattice key), so that the ranks of the distributed path and a
     * re-mesh's patch, which number nodes their own way, match it; a centre
     * stays off the lattice (one element's only) */
#pragma omp parallel for schedule(static)
    for (size_t i = 0; i < na; i++) {
      const uint32_t a = W->N.ea[i], b = W->N.eb[i];
      uint64_t k = MX_NKEY_NONE;
      if (a < nn && b < nn && nk[a] != MX_NKEY_NONE && nk[b] != MX_NKEY_NONE) {
        const uint64_t lo = nk[a] < nk[b] ? nk[a] : nk[b], hi = nk[a] ^ nk[b] ^ lo;
        k = (uint64_t)1 << 63 | mix64(mix64(lo) ^ hi) >> 1;
        if (k == MX_NKEY_NONE) k--;
      }
      nk[nn + i] = k;
    }
  }
  uint16_t *d2 = mx_realloc(W->depth, (nn + na + 1) * sizeof *d2);
  if (!d2) return MX_ENOMEM;
  W->depth = d2;
  uint8_t *o2 = mx_realloc(W->outer, nn + na + 1);
  if (!o2) return MX_ENOMEM;
  W->outer = o2;
  memset(o2 + nn, 0, na);
  memcpy(d2 + nn, W->N.depth, na * sizeof *d2);
  M->nnodes = nn + na;
  mx_free(M->type);
  mx_free(M->conn);
  mx_free(M->level);
  mx_free(M->leaf);
  mx_free(M->jens);
  M->type = W->C.type;
  M->conn = W->C.conn;
  M->level = W->C.level;
  M->leaf = W->C.leaf;
  M->jens = W->C.jens;
  M->ncells = W->C.n;
  memset(&W->C, 0, sizeof W->C);
  return MX_OK;
}

static int piece_of(const void *ctx, const double x[3]) {
  return mx_interfaces_piece(ctx, x);
}

static double clearance_of(const void *ctx, const double x[3]) {
  return mx_interfaces_clearance(ctx, x);
}

/* After the cut: the untangling (kernels/untangle.h, with moves along the
 * axes too) on the elements below the floor, moving the nodes of the band
 * the cleaving changed: the free ones (each kept in its region) and those
 * the cleaving put on the interface (kept on it); the nodes on other shells
 * stay. */
static int smooth_band(cleaver *W, size_t *moves) {
  mx_mesh *M = W->M;
  const size_t nn = M->nnodes, n0 = W->nn;
  uint8_t *states = mx_alloc(nn + 1), *movable = mx_alloc(nn + 1);
  if (!states || !movable) {
    mx_free(states);
    mx_free(movable);
    return MX_ENOMEM;
  }
  /* the band: the nodes of the elements with a node the cleaving made or
   * moved */
#pragma omp parallel for schedule(static)
  for (size_t v = 0; v < nn; v++) movable[v] = 0;
#pragma omp parallel for schedule(static)
  for (size_t c = 0; c < M->ncells; c++) {
    const uint32_t *row = M->conn + 8 * c;
    const int nv = mx_cell_nodes[M->type[c]];
    int band = 0;
    for (int i = 0; i < nv && !band; i++) band = row[i] >= n0 || W->moved[row[i]];
    if (band)
      for (int i = 0; i < nv; i++) __atomic_store_n(&movable[row[i]], 1, __ATOMIC_RELAXED);
  }
#pragma omp parallel for schedule(static)
  for (size_t v = 0; v < nn; v++) {
    const int on = W->depth[v] == MX_REGION_ON;
    states[v] = on ? MX_NODE_OUTSIDE : MX_NODE_INSIDE;
    movable[v] = movable[v] && !W->rim[v] && (!on || v >= n0 || W->moved[v]);
  }
  const mx_untangle_opts o = {MX_CLEAVE_FLOOR, 8, 3, movable, piece_of, W->I, W->depth, clearance_of, NULL};
  const int st = mx_untangle_with(M, states, W->Si, &o, moves);
  mx_free(states);
  mx_free(movable);
  return st;
}

int mx_cleave_interface(mx_mesh *M, uint16_t **piece, uint8_t **outer, const mx_interfaces *I,
                        uint32_t p, const mx_surface_index *Sd, double alpha,
                        mx_cleave_stats *stats) {
  cleaver W;
  memset(&W, 0, sizeof W);
  const size_t nn = M->nnodes;
  uint8_t *inA = mx_alloc(I->npieces + 2);
  W.side = mx_alloc(nn + 1);
  W.sd = mx_alloc((nn + 1) * sizeof *W.sd);
  W.rim = mx_calloc(nn + 1);
  if (!inA || !W.side || !W.sd || !W.rim) {
    mx_free(inA);
    mx_free(W.side);
    mx_free(W.sd);
    mx_free(W.rim);
    return MX_ENOMEM;
  }
  for (uint32_t q = 0; q <= I->npieces; q++) inA[q] = (uint8_t)mx_interfaces_within(I, (int)q, p);
  W.M = M;
  W.I = I;
  W.piece = p;
  W.Sk = &I->index[p];
  W.Si = I->iface[p] ? I->iface[p] : W.Sk;
  W.Sd = Sd;
  W.inA = inA;
  W.alpha = alpha;
  W.depth = *piece;
  W.outer = *outer;
  W.nn = nn;
  /* the sides: a free node's from its piece, a node of the outer boundary
   * (on no interface) from where it lies (on p's surface: inside p) */
  const double hair = 1e-12 * W.Sk->coord_max;
  W.hair = hair;
#pragma omp parallel for schedule(dynamic, 1024)
  for (size_t v = 0; v < nn; v++) {
    W.sd[v] = 0.0;
    if (W.depth[v] != MX_REGION_ON) {
      W.side[v] = (uint8_t)side_of(&W, W.depth[v]);
    } else if (W.outer[v]) {
      W.sd[v] = iface_g(&W, M->xyz + 3 * v);
      W.side[v] = W.sd[v] > 0.0 ? SIDE_B : SIDE_A; /* on p's own surface: p's */
    } else {
      W.side[v] = SIDE_ON;
    }
  }
  const double t0 = mx_wtime();
  int st = cleave(&W, stats);
  if (!st) st = finish(&W, stats);
  *piece = W.depth;
  *outer = W.outer;
  /* J_ENS of the pieces and of the elements with a warped node */
  if (!st) {
#pragma omp parallel for schedule(dynamic, 1024)
    for (size_t c = 0; c < M->ncells; c++) {
      const uint32_t *row = M->conn + 8 * c;
      const int nv = mx_cell_nodes[M->type[c]];
      int redo = isnan(M->jens[c]);
      for (int i = 0; i < nv && !redo; i++) redo = row[i] < W.nn && W.moved[row[i]];
      if (redo) {
        double x[8][3];
        for (int i = 0; i < nv; i++) memcpy(x[i], M->xyz + 3 * (size_t)row[i], sizeof x[i]);
        M->jens[c] = (float)mx_jens(M->type[c], (const double(*)[3])x);
      }
    }
    const double t1 = mx_wtime();
    stats->t_cut += t1 - t0;
    st = smooth_band(&W, &stats->smoothed);
    stats->t_smooth += mx_wtime() - t1;
    mx_mesh_summarize(M);
  }
  mx_free(W.moved);
  mx_free(W.sd);
  mx_free(W.side);
  mx_free(W.rim);
  table_free(&W.edges);
  mx_free(W.N.xyz);
  mx_free(W.N.depth);
  mx_free(W.N.ea);
  mx_free(W.N.eb);
  cells_free(&W.C);
  mx_free(inA);
  return st;
}
