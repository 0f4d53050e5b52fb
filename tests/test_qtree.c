/* The quadtree (src/quad/qtree.c, qrefine.c, qedges.c, qbalance_recursive.c)
 * and the transition (qtransition.c): leaf and node counts derived by hand
 * on squares, balance checked by the independent check (and that check on
 * a hand-made unbalanced tree), the two balances giving the same leaves,
 * 1 and 2 threads giving the same tree and mesh, the 16 transition
 * patterns, and an edge count over whole meshes.
 *
 * `test_qtree --bench [level [threads]]` meshes the letter A at a_level 12
 * (or the level given) with 2 threads (or the number given) and prints the
 * time and peak memory (not a test). */
#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>

#include "check.h"
#include "base/common.h"
#include "quad/quad.h"
#include "io/read_poly.h"

/* ---- polylines --------------------------------------------------------- */

/* Closed loops from concatenated points (len[i] points each). */
static void poly_make(mx_poly *P, int nloops, const int *len, const double *pts) {
  memset(P, 0, sizeof *P);
  size_t n = 0;
  for (int i = 0; i < nloops; i++) n += (size_t)len[i];
  P->nv = P->ns = n;
  P->xy = mx_alloc(2 * n * sizeof *P->xy);
  P->seg = mx_alloc(2 * n * sizeof *P->seg);
  P->line = mx_alloc(n * sizeof *P->line);
  P->path = mx_alloc(16);
  strcpy(P->path, "test");
  memcpy(P->xy, pts, 2 * n * sizeof *P->xy);
  for (int i = 0, v0 = 0; i < nloops; v0 += len[i++])
    for (int k = 0; k < len[i]; k++) {
      P->seg[2 * (v0 + k)] = (uint32_t)(v0 + k);
      P->seg[2 * (v0 + k) + 1] = (uint32_t)(v0 + (k + 1) % len[i]);
      P->line[v0 + k] = (uint32_t)(v0 + k + 1);
    }
}

static void square(mx_poly *P, double lo, double hi) {
  const int len[1] = {4};
  const double p[8] = {lo, lo, hi, lo, hi, hi, lo, hi};
  poly_make(P, 1, len, p);
}

static void square_with_hole(mx_poly *P) {
  const int len[2] = {4, 4};
  const double p[16] = {0, 0, 1, 0, 1, 1, 0, 1, 0.25, 0.25, 0.25, 0.75, 0.75, 0.75, 0.75, 0.25};
  poly_make(P, 2, len, p);
}

/* A 7-pointed star around (0.5, 0.5). */
static void star(mx_poly *P) {
  double p[28];
  const int len[1] = {14};
  for (int k = 0; k < 14; k++) {
    const double a = 2 * M_PI * k / 14 + 0.1, r = (k & 1) ? 0.18 : 0.45;
    p[2 * k] = 0.5 + r * cos(a);
    p[2 * k + 1] = 0.5 + r * sin(a);
  }
  poly_make(P, 1, len, p);
}

/* ---- building ------------------------------------------------------------ */

typedef struct {
  mx_poly P;
  mx_poly_index I;
  int ok;
} domain;

static void domain_init(domain *D) {
  D->ok = mx_poly_check_domain(&D->P) == MX_OK && mx_poly_index_build(&D->P, &D->I) == MX_OK;
  CHECK(D->ok);
}

static void domain_free(domain *D) {
  mx_poly_index_free(&D->I);
  mx_poly_free(&D->P);
}

static int build(const domain *D, const mx_qrequests *R, int balance, int threads, mx_qtree *T,
                 mx_qstats *st) {
  omp_set_num_threads(threads);
  return mx_qtree_build(&D->P, &D->I, R, balance, T, st);
}

static size_t leaves_of(const mx_qtree *T, uint32_t **l) {
  size_t n = 0;
  CHECK(mx_qtree_leaves(T, l, &n) == MX_OK);
  return n;
}

/* Same leaves: keys and levels in Morton order. */
static int same_leaves(const mx_qtree *A, const mx_qtree *B) {
  uint32_t *la, *lb;
  const size_t na = leaves_of(A, &la), nb = leaves_of(B, &lb);
  int same = na == nb;
  for (size_t i = 0; same && i < na; i++)
    same = A->key[la[i]] == B->key[lb[i]] && A->level[la[i]] == B->level[lb[i]];
  mx_free(la);
  mx_free(lb);
  return same;
}

/* ---- an independent check of a 2D mesh ----------------------------------- */

static double cell_area(const mx_qmesh *M, size_t c) {
  const int k = M->type[c] == MX_QQUAD ? 4 : 3;
  double a = 0;
  for (int v = 0; v < k; v++) {
    const double *p = M->xy + 2 * (size_t)M->conn[4 * c + v];
    const double *q = M->xy + 2 * (size_t)M->conn[4 * c + (v + 1) % k];
    a += p[0] * q[1] - q[0] * p[1];
  }
  return 0.5 * a;
}

/* The leaf holding point p (descending from the roots), or UINT32_MAX
 * outside the grid. */
static uint32_t leaf_at(const mx_qtree *T, const double p[2]) {
  const double u = (p[0] - T->grid.origin[0]) / T->grid.unit;
  const double v = (p[1] - T->grid.origin[1]) / T->grid.unit;
  const double lim = (double)(1u << MX_QMAX_LEVEL);
  if (u < 0 || v < 0 || u >= T->grid.dims[0] * lim || v >= T->grid.dims[1] * lim) return UINT32_MAX;
  const uint32_t x = (uint32_t)u, y = (uint32_t)v;
  uint32_t q = UINT32_MAX;
  for (uint32_t r = 0; r < T->n && T->parent[r] == UINT32_MAX; r++) {
    uint32_t rx, ry;
    mx_qkey_xy(T->key[r], &rx, &ry);
    if (rx >> MX_QMAX_LEVEL == x >> MX_QMAX_LEVEL && ry >> MX_QMAX_LEVEL == y >> MX_QMAX_LEVEL)
      q = r;
  }
  while (T->flags[q] & MX_Q_SPLIT) {
    const int b = MX_QMAX_LEVEL - T->level[q] - 1;
    q = T->child0[q] + (((x >> b) & 1) | (((y >> b) & 1) << 1));
  }
  return q;
}

typedef struct {
  uint64_t key; /* min, max node */
  int dir;      /* +1 from min to max */
} dedge;

static int dedge_cmp(const void *a, const void *b) {
  const dedge *x = a, *y = b;
  return x->key < y->key ? -1 : x->key > y->key ? 1 : x->dir - y->dir;
}

static int u64_cmp(const void *a, const void *b) {
  const uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
  return x < y ? -1 : x > y;
}

/* Every cell counter-clockwise; every edge used twice in opposite
 * directions, or once with the outside (an outside leaf or no leaf) on its
 * right; cells' area = leaves' area; nodes distinct and on their keys.
 * Returns the number of defects. */
static size_t mesh_defects(const mx_qtree *T, const uint32_t *leaves, size_t nl,
                           const mx_qmesh *M) {
  size_t bad = 0, ne = 0;
  double area = 0, leaf_area = 0;
  dedge *E = malloc((4 * M->ncells + 1) * sizeof *E);
  for (size_t c = 0; c < M->ncells; c++) {
    const double a = cell_area(M, c);
    bad += !(a > 0);
    area += a;
    const int k = M->type[c] == MX_QQUAD ? 4 : 3;
    bad += k == 3 && M->conn[4 * c + 3] != UINT32_MAX;
    for (int v = 0; v < k; v++) {
      const uint32_t p = M->conn[4 * c + v], q = M->conn[4 * c + (v + 1) % k];
      bad += p >= M->nnodes || q >= M->nnodes;
      E[ne].key = (uint64_t)(p < q ? p : q) << 32 | (p < q ? q : p);
      E[ne++].dir = p < q ? 1 : -1;
    }
  }
  for (size_t i = 0; i < nl; i++) leaf_area += pow(ldexp(T->grid.side, -T->level[leaves[i]]), 2);
  bad += fabs(area - leaf_area) > 1e-12 * leaf_area;
  qsort(E, ne, sizeof *E, dedge_cmp);
  for (size_t i = 0; i < ne;) {
    size_t j = i;
    while (j < ne && E[j].key == E[i].key) j++;
    if (j - i == 2) {
      bad += E[i].dir == E[i + 1].dir;
    } else if (j - i == 1) {
      /* the point just right of the directed edge's middle is outside */
      const uint32_t a = (uint32_t)(E[i].key >> 32), b = (uint32_t)E[i].key;
      const uint32_t p = E[i].dir > 0 ? a : b, q = E[i].dir > 0 ? b : a;
      const double *P = M->xy + 2 * (size_t)p, *Q = M->xy + 2 * (size_t)q;
      const double eps = 1e-3 * T->grid.unit / hypot(Q[0] - P[0], Q[1] - P[1]);
      const double m[2] = {0.5 * (P[0] + Q[0]) + eps * (Q[1] - P[1]),
                           0.5 * (P[1] + Q[1]) - eps * (Q[0] - P[0])};
      const uint32_t l = leaf_at(T, m);
      bad += l != UINT32_MAX && !(T->flags[l] & MX_Q_OUT);
    } else {
      bad++;
    }
    i = j;
  }
  free(E);
  /* nodes: distinct keys, coordinates on them */
  uint64_t *k = malloc((M->nnodes + 1) * sizeof *k);
  for (size_t v = 0; v < M->nnodes; v++) {
    uint32_t x, y;
    mx_qkey_xy(M->nkey[v], &x, &y);
    bad += M->xy[2 * v] != T->grid.origin[0] + T->grid.unit * x;
    bad += M->xy[2 * v + 1] != T->grid.origin[1] + T->grid.unit * y;
    k[v] = M->nkey[v];
  }
  qsort(k, M->nnodes, sizeof *k, u64_cmp);
  for (size_t v = 1; v < M->nnodes; v++) bad += k[v] == k[v - 1];
  free(k);
  /* nodes numbered by their first leaf: that leaf's position never
   * decreases with the id, and every node is used */
  uint32_t *first = malloc((M->nnodes + 1) * sizeof *first);
  for (size_t v = 0; v < M->nnodes; v++) first[v] = UINT32_MAX;
  for (size_t c = 0; c < M->ncells; c++)
    for (int v = 0; v < 4; v++) {
      const uint32_t p = M->conn[4 * c + v];
      if (p != UINT32_MAX && M->leaf[c] < first[p]) first[p] = M->leaf[c];
    }
  for (size_t v = 0; v < M->nnodes; v++)
    bad += first[v] == UINT32_MAX || (v && first[v] < first[v - 1]);
  free(first);
  return bad;
}

/* Build, list the leaves, mesh, check the mesh; returns leaves (non-OUT). */
static size_t build_and_mesh(const domain *D, const mx_qrequests *R, int balance, mx_qtree *T,
                             mx_qmesh *M, mx_qstats *st) {
  CHECK(build(D, R, balance, 2, T, st) == MX_OK);
  uint32_t *l;
  const size_t n = leaves_of(T, &l);
  CHECK(mx_qtransition(T, l, n, M) == MX_OK);
  CHECK(mesh_defects(T, l, n, M) == 0);
  mx_free(l);
  return n;
}

/* ---- the tests ------------------------------------------------------------- */

/* a_level L on the unit square: the roots (side 1.01) reach 0.005 beyond
 * it, less than a quadrant of level <= 7, so every quadrant of level L
 * meets the square: (2^L)^2 quads, (2^L+1)^2 nodes, (4^L-1)/3 splits. */
/* The Morton keys: the shuffle against spreading bit by bit. */
static void test_keys(void) {
  for (uint32_t i = 0; i < 1000; i++) {
    const uint32_t x = i * 2654435761u, y = i * 40503u + 7;
    uint64_t k = 0;
    for (int b = 0; b < 32; b++)
      k |= (uint64_t)((x >> b) & 1) << (2 * b) | (uint64_t)((y >> b) & 1) << (2 * b + 1);
    uint32_t a, c;
    mx_qkey_xy(k, &a, &c);
    CHECK(mx_qkey(x, y) == k && a == x && c == y);
  }
}

static void test_square_all(void) {
  domain D;
  square(&D.P, 0, 1);
  domain_init(&D);
  for (int L = 1; L <= 6; L++)
    for (int bal = 0; bal < 2; bal++) {
      mx_qrequests R = {.a_level = L};
      mx_qtree T;
      mx_qmesh M;
      mx_qstats st;
      const size_t n = build_and_mesh(&D, &R, bal, &T, &M, &st);
      const size_t side = (size_t)1 << L;
      CHECK(n == side * side);
      CHECK(st.leaves == n);
      CHECK(st.splits == (side * side - 1) / 3 && st.balance_splits == 0);
      CHECK(M.ncells == side * side && M.nnodes == (side + 1) * (side + 1));
      for (size_t c = 0; c < M.ncells; c++) CHECK(M.type[c] == MX_QQUAD && M.level[c] == L);
      CHECK(mx_qtree_unbalanced(&T) == 0);
      mx_qmesh_free(&M);
      mx_qtree_free(&T);
    }
  domain_free(&D);
}

/* s_level L on the unit square: at each level k < L the ring of the
 * 4*2^k - 4 outermost quadrants (the only ones the square's sides cross:
 * they lie within 0.005 of the roots' boundary) is split, 1 root at level
 * 0. A ring's inner children are 2 bands away from the next ring's splits:
 * no balance split. Leaves: 1 + 3 * (number of splits). */
static void test_square_surface(void) {
  domain D;
  square(&D.P, 0, 1);
  domain_init(&D);
  for (int L = 1; L <= 6; L++) {
    size_t splits = 1;
    for (int k = 1; k < L; k++) splits += 4 * ((size_t)1 << k) - 4;
    for (int bal = 0; bal < 2; bal++) {
      mx_qrequests R = {.s_level = L};
      mx_qtree T;
      mx_qmesh M;
      mx_qstats st;
      const size_t n = build_and_mesh(&D, &R, bal, &T, &M, &st);
      CHECK(n == 1 + 3 * splits);
      CHECK(st.splits == splits && st.balance_splits == 0);
      /* the finest leaves: the children of the last ring split; those
       * meeting the square's sides: the ring of level L */
      size_t fine = 0, bound = 0;
      for (size_t q = 0; q < T.n; q++) {
        fine += !(T.flags[q] & MX_Q_SPLIT) && T.level[q] == L;
        bound += !(T.flags[q] & MX_Q_SPLIT) && (T.flags[q] & MX_Q_BOUND);
      }
      CHECK(fine == 4 * (L == 1 ? 1 : 4 * ((size_t)1 << (L - 1)) - 4));
      CHECK(bound == 4 * ((size_t)1 << L) - 4);
      mx_qmesh_free(&M);
      mx_qtree_free(&T);
    }
  }
  domain_free(&D);
}

/* The square with a square hole [0.25, 0.75]^2, a_level L: the level-L
 * quadrants wholly inside the hole are the m x m ones of index i with
 * x_lo(i) > 0.25 and x_hi(i) < 0.75 (closed: touching the hole's side
 * meets it); they and the coarser quadrants holding only them are outside.
 * Quads 4^L - m^2; nodes (2^L+1)^2 - (m-1)^2 (the block's inner corners). */
static void test_square_hole(void) {
  domain D;
  square_with_hole(&D.P);
  domain_init(&D);
  for (int L = 1; L <= 6; L++) {
    const double s = 1.01 / (1 << L);
    size_t m = 0;
    for (int i = 0; i < (1 << L); i++) {
      const double lo = -0.005 + i * s, hi = lo + s;
      CHECK(fabs(lo - 0.25) > 1e-6 && fabs(hi - 0.75) > 1e-6); /* no near tie */
      m += lo > 0.25 && hi < 0.75;
    }
    const size_t side = (size_t)1 << L, hole_nodes = m > 1 ? (m - 1) * (m - 1) : 0;
    mx_qrequests R = {.a_level = L};
    mx_qtree T;
    mx_qmesh M;
    mx_qstats st;
    const size_t n = build_and_mesh(&D, &R, MX_QBALANCE_EDGES, &T, &M, &st);
    CHECK(n == side * side - m * m);
    CHECK(M.ncells == n && M.nnodes == (side + 1) * (side + 1) - hole_nodes);
    size_t out = 0;
    for (size_t q = 0; q < T.n; q++) out += (T.flags[q] & MX_Q_OUT) != 0;
    CHECK((m > 0) == (out > 0));
    mx_qmesh_free(&M);
    mx_qtree_free(&T);
  }
  domain_free(&D);
}

static uint32_t rng_state = 12345;
static double rnd(void) {
  rng_state = rng_state * 1664525u + 1013904223u;
  return (rng_state >> 8) / 16777216.0;
}

/* Random small boxes at random levels: balanced, both balances agree, and
 * the mesh passes the edge check. */
static void test_random_boxes(void) {
  domain D;
  square(&D.P, 0, 1);
  domain_init(&D);
  for (int trial = 0; trial < 12; trial++) {
    mx_qbox box[6];
    const int nb = 1 + trial % 6;
    for (int b = 0; b < nb; b++) {
      const double x = rnd(), y = rnd(), w = 0.02 * rnd();
      box[b] = (mx_qbox){{x, y}, {x + w, y + w}, 3 + (int)(7 * rnd())};
    }
    mx_qrequests R = {.a_level = trial % 3, .nboxes = (size_t)nb, .boxes = box};
    mx_qtree A, B;
    mx_qmesh M;
    mx_qstats sa, sb;
    build_and_mesh(&D, &R, MX_QBALANCE_EDGES, &A, &M, &sa);
    CHECK(build(&D, &R, MX_QBALANCE_RECURSIVE, 1, &B, &sb) == MX_OK);
    CHECK(mx_qtree_unbalanced(&A) == 0 && mx_qtree_unbalanced(&B) == 0);
    CHECK(same_leaves(&A, &B));
    CHECK(sa.splits == sb.splits && sa.balance_splits == sb.balance_splits);
    if (trial == 11) CHECK(sa.balance_splits > 0); /* the balance did something */
    mx_qmesh_free(&M);
    mx_qtree_free(&A);
    mx_qtree_free(&B);
  }
  domain_free(&D);
}

/* A point-sized box at the finest usable level: the balance cascades over
 * 19 levels; level 20 is refused. */
static void test_deepest(void) {
  domain D;
  square(&D.P, 0, 1);
  domain_init(&D);
  mx_qbox box = {{0.3, 0.6}, {0.3, 0.6}, MX_QMAX_LEVEL - 1};
  mx_qrequests R = {.nboxes = 1, .boxes = &box};
  mx_qtree A, B;
  mx_qmesh M;
  mx_qstats st;
  build_and_mesh(&D, &R, MX_QBALANCE_EDGES, &A, &M, &st);
  CHECK(build(&D, &R, MX_QBALANCE_RECURSIVE, 2, &B, NULL) == MX_OK);
  CHECK(same_leaves(&A, &B) && mx_qtree_unbalanced(&A) == 0);
  const double p[2] = {0.3, 0.6};
  CHECK(A.level[leaf_at(&A, p)] == MX_QMAX_LEVEL - 1);
  CHECK(st.balance_splits > 0);
  mx_qmesh_free(&M);
  mx_qtree_free(&A);
  mx_qtree_free(&B);
  box.level = MX_QMAX_LEVEL;
  CHECK(build(&D, &R, MX_QBALANCE_EDGES, 1, &A, NULL) == MX_EINPUT);
  domain_free(&D);
}

/* The check itself on a hand-made unbalanced tree: the root split, its
 * child 0 split, and that one's child 3 split: the level-3 quadrants touch
 * the root's children 1 (its left edge) and 2 (its bottom edge), two levels
 * coarser: 2 unbalanced (leaf, edge) pairs. */
static void manual_split(mx_qtree *T, uint32_t p) {
  const uint32_t c0 = (uint32_t)T->n;
  for (int c = 0; c < 4; c++) {
    const uint32_t q = c0 + (uint32_t)c;
    T->level[q] = (uint8_t)(T->level[p] + 1);
    T->key[q] = T->key[p] | ((uint64_t)c << (2 * (MX_QMAX_LEVEL - T->level[q])));
    T->flags[q] = 0;
    T->parent[q] = p;
    T->child0[q] = UINT32_MAX;
  }
  T->child0[p] = c0;
  T->flags[p] |= MX_Q_SPLIT;
  T->n += 4;
}

static void test_unbalanced_check(void) {
  mx_qtree T;
  memset(&T, 0, sizeof T);
  const size_t cap = 16;
  T.key = mx_calloc(cap * sizeof *T.key);
  T.level = mx_calloc(cap);
  T.flags = mx_calloc(cap);
  T.parent = mx_calloc(cap * sizeof *T.parent);
  T.child0 = mx_calloc(cap * sizeof *T.child0);
  T.grid = (mx_qgrid){{0, 0}, 1.0, ldexp(1.0, -MX_QMAX_LEVEL), {1, 1}};
  T.n = 1;
  T.parent[0] = T.child0[0] = UINT32_MAX;
  CHECK(mx_qtree_unbalanced(&T) == 0);
  manual_split(&T, 0);
  manual_split(&T, 1);
  CHECK(mx_qtree_unbalanced(&T) == 0);
  manual_split(&T, 5 + 3);
  CHECK(mx_qtree_unbalanced(&T) == 2);
  T.flags[2] |= MX_Q_OUT; /* an outside leaf is not meshed: not counted */
  CHECK(mx_qtree_unbalanced(&T) == 1);
  mx_qtree_free(&T);
}

/* Every request kind on the star and the holed square: both balances give
 * the same leaves, balanced, and 1 and 2 threads the same tree and mesh. */
static void compare_modes_threads(const char *what, const domain *D, const mx_qrequests *R) {
  mx_qtree A, B, C;
  mx_qmesh MA, MC;
  mx_qstats sa, sb, sc;
  build_and_mesh(D, R, MX_QBALANCE_EDGES, &A, &MA, &sa);
  CHECK(build(D, R, MX_QBALANCE_RECURSIVE, 2, &B, &sb) == MX_OK);
  CHECK(same_leaves(&A, &B));
  CHECK(mx_qtree_unbalanced(&A) == 0 && mx_qtree_unbalanced(&B) == 0);
  CHECK(build(D, R, MX_QBALANCE_EDGES, 1, &C, &sc) == MX_OK);
  uint32_t *l;
  const size_t n = leaves_of(&C, &l);
  CHECK(mx_qtransition(&C, l, n, &MC) == MX_OK);
  mx_free(l);
  /* 1 thread against 2: the same quadrants and the same bytes */
  CHECK(A.n == C.n && A.seg_n == C.seg_n);
  if (A.n == C.n) {
    CHECK(memcmp(A.key, C.key, A.n * sizeof *A.key) == 0);
    CHECK(memcmp(A.flags, C.flags, A.n) == 0 && memcmp(A.target, C.target, A.n) == 0);
    CHECK(memcmp(A.seg_off, C.seg_off, A.n * sizeof *A.seg_off) == 0);
  }
  CHECK(MA.nnodes == MC.nnodes && MA.ncells == MC.ncells);
  if (MA.nnodes == MC.nnodes && MA.ncells == MC.ncells) {
    CHECK(memcmp(MA.xy, MC.xy, 2 * MA.nnodes * sizeof *MA.xy) == 0);
    CHECK(memcmp(MA.nkey, MC.nkey, MA.nnodes * sizeof *MA.nkey) == 0);
    CHECK(memcmp(MA.conn, MC.conn, 4 * MA.ncells * sizeof *MA.conn) == 0);
    CHECK(memcmp(MA.type, MC.type, MA.ncells) == 0);
    CHECK(memcmp(MA.leaf, MC.leaf, MA.ncells * sizeof *MA.leaf) == 0);
    CHECK(memcmp(MA.level, MC.level, MA.ncells) == 0);
  }
  printf("%-24s %7zu leaves %7zu cells %7zu nodes, %zu splits (%zu for balance)\n", what, sa.leaves,
         MA.ncells, MA.nnodes, sa.splits, sa.balance_splits);
  mx_qmesh_free(&MA);
  mx_qmesh_free(&MC);
  mx_qtree_free(&A);
  mx_qtree_free(&B);
  mx_qtree_free(&C);
}

static void test_requests(void) {
  domain S, H;
  star(&S.P);
  domain_init(&S);
  square_with_hole(&H.P);
  domain_init(&H);
  mx_qrequests R = {.s_level = 8, .a_level = 2};
  compare_modes_threads("star s8 a2", &S, &R);
  mx_qrequests R2 = {.s_level = 7};
  compare_modes_threads("holed square s7", &H, &R2);
  /* functions */
  const mx_qfun f[3] = {{MX_QFUN_CIRCLE, {0.5, 0.5, 0.3, 0}, 7},
                        {MX_QFUN_LINE, {0.2, 0.2, 1, 2}, 6},
                        {MX_QFUN_SINE, {0.1, 12, 0.3, 0.6}, 8}};
  mx_qrequests R3 = {.s_level = 4, .nfuns = 3, .funs = f};
  compare_modes_threads("holed square functions", &H, &R3);
  /* a region (a triangle) and a drawing (an open polyline) */
  mx_poly reg, dr;
  const int len[1] = {3};
  const double tp[6] = {0.1, 0.1, 0.6, 0.2, 0.3, 0.55};
  poly_make(&reg, 1, len, tp);
  CHECK(mx_poly_check_domain(&reg) == MX_OK);
  const double dp[6] = {0.05, 0.9, 0.5, 0.8, 0.95, 0.95};
  poly_make(&dr, 1, len, dp);
  dr.ns = 2; /* open: two segments */
  const int rl = 6, dl = 8;
  mx_qrequests R4 = {.s_level = 3, .nregions = 1, .regions = &reg, .region_level = &rl,
                     .ndrawings = 1, .drawings = &dr, .drawing_level = &dl};
  compare_modes_threads("star region drawing", &S, &R4);
  /* the region's inside is refined: a point deep in it (0.13 or more from
   * its sides) lies in a level-6 leaf */
  domain Q;
  square(&Q.P, 0, 1);
  domain_init(&Q);
  mx_qtree T;
  CHECK(build(&Q, &R4, MX_QBALANCE_EDGES, 2, &T, NULL) == MX_OK);
  domain_free(&Q);
  const double p[2] = {0.33, 0.28};
  const uint32_t q = leaf_at(&T, p);
  CHECK(q != UINT32_MAX && T.level[q] == 6);
  mx_qtree_free(&T);
  mx_poly_free(&reg);
  mx_poly_free(&dr);
  /* a level out of range is refused */
  mx_qrequests bad = {.s_level = MX_QMAX_LEVEL};
  mx_quiet = 1;
  CHECK(build(&S, &bad, MX_QBALANCE_EDGES, 1, &T, NULL) == MX_EINPUT);
  domain_free(&S);
  domain_free(&H);
}

/* The letter A (once the .poly reader exists). */
static void test_letter_a(void) {
  const char *dir = getenv("MIXOCT_DATA");
  char path[1024];
  snprintf(path, sizeof path, "%s/polylines/a.poly", dir ? dir : "../shared/data");
  domain D;
  mx_quiet = 1;
  if (mx_read_poly_any(path, &D.P) != MX_OK) {
    TEST_DATA_MISSING("the letter A: %s not read", path);
    return;
  }
  domain_init(&D);
  mx_qrequests R = {.s_level = 9, .a_level = 3};
  compare_modes_threads("A s9 a3", &D, &R);
  mx_qrequests R2 = {.a_level = 6};
  compare_modes_threads("A a6", &D, &R2);
  domain_free(&D);
}

/* Each of the 16 masks: the leaf (1,1) of a 4 x 4 level-2 grid, with the
 * neighbours of the mask's edges split (a tiny level-3 box at their
 * centres). Its cells: CCW, covering its area, the pattern's counts. */
static void test_masks(void) {
  domain D;
  square(&D.P, 0, 1);
  domain_init(&D);
  const int nb[4][2] = {{1, 0}, {2, 1}, {1, 2}, {0, 1}};
  static const int quads[16] = {1, 0, 0, 1, 0, 2, 1, 1, 0, 1, 2, 1, 1, 1, 1, 4};
  static const int tris[16] = {0, 3, 3, 2, 3, 0, 2, 3, 3, 2, 0, 3, 2, 3, 3, 0};
  mx_qgrid g;
  const double lo[2] = {0, 0}, hi[2] = {1, 1};
  CHECK(mx_qgrid_build(lo, hi, "test", &g) == MX_OK);
  const double s = g.side / 4;
  for (int m = 0; m < 16; m++) {
    mx_qbox box[4];
    size_t n = 0;
    for (int e = 0; e < 4; e++)
      if ((m >> e) & 1) {
        const double cx = g.origin[0] + (nb[e][0] + 0.5) * s;
        const double cy = g.origin[1] + (nb[e][1] + 0.5) * s;
        box[n++] = (mx_qbox){{cx - 1e-3, cy - 1e-3}, {cx + 1e-3, cy + 1e-3}, 3};
      }
    mx_qrequests R = {.a_level = 2, .nboxes = n, .boxes = box};
    mx_qtree T;
    mx_qmesh M;
    build_and_mesh(&D, &R, MX_QBALANCE_EDGES, &T, &M, NULL);
    uint32_t *l;
    const size_t nl = leaves_of(&T, &l);
    const uint64_t key = mx_qkey(1u << (MX_QMAX_LEVEL - 2), 1u << (MX_QMAX_LEVEL - 2));
    size_t pos = nl;
    for (size_t i = 0; i < nl; i++)
      if (T.key[l[i]] == key && T.level[l[i]] == 2) pos = i;
    CHECK(pos < nl);
    int nq = 0, nt = 0;
    double area = 0;
    uint32_t used[32];
    int nused = 0;
    for (size_t c = 0; c < M.ncells; c++) {
      if (M.leaf[c] != pos) continue;
      const double a = cell_area(&M, c);
      CHECK(a > 0);
      area += a;
      nq += M.type[c] == MX_QQUAD;
      nt += M.type[c] == MX_QTRI;
      for (int v = 0; v < (M.type[c] == MX_QQUAD ? 4 : 3); v++) {
        int seen = 0;
        for (int u = 0; u < nused; u++) seen |= used[u] == M.conn[4 * c + v];
        if (!seen) used[nused++] = M.conn[4 * c + v];
      }
    }
    CHECK(nq == quads[m] && nt == tris[m]);
    CHECK(fabs(area - s * s) < 1e-12);
    CHECK(nused == 4 + __builtin_popcount(m) + (m == 15));
    mx_free(l);
    mx_qmesh_free(&M);
    mx_qtree_free(&T);
  }
  domain_free(&D);
}

/* ---- the measurement ---------------------------------------------------------- */

static int bench(int level, int threads) {
  const char *dir = test_data_dir("polylines/a.poly");
  char path[1200];
  snprintf(path, sizeof path, "%s/polylines/a.poly", dir ? dir : MIXOCT_TEST_DATA);
  domain D;
  if (mx_read_poly_any(path, &D.P) != MX_OK) return 1;
  domain_init(&D);
  omp_set_num_threads(threads);
  mx_qrequests R = {.a_level = level};
  mx_qtree T;
  mx_qmesh M;
  mx_qstats st;
  uint32_t *l;
  size_t n;
  const double t0 = mx_wtime();
  int ok = mx_qtree_build(&D.P, &D.I, &R, MX_QBALANCE_EDGES, &T, &st) == MX_OK;
  const double t1 = mx_wtime();
  ok = ok && mx_qtree_leaves(&T, &l, &n) == MX_OK;
  const double t2 = mx_wtime();
  ok = ok && mx_qtransition(&T, l, n, &M) == MX_OK;
  const double t3 = mx_wtime();
  struct rusage ru;
  getrusage(RUSAGE_SELF, &ru);
  if (ok)
    printf("letter A a_level %d, %d threads: %zu quadrants, %zu leaves, %zu nodes, %zu cells; "
           "build %.3f s (refine %.3f, balance %.3f), leaves %.3f s, transition %.3f s, "
           "total %.3f s; peak RSS %.1f MB\n",
           level, threads, T.n, n, M.nnodes, M.ncells, t1 - t0, st.t_refine, st.t_balance, t2 - t1,
           t3 - t2, t3 - t0, ru.ru_maxrss / 1024.0);
  return ok ? 0 : 1;
}

int main(int argc, char **argv) {
  if (argc > 1 && !strcmp(argv[1], "--bench"))
    return bench(argc > 2 ? atoi(argv[2]) : 12, argc > 3 ? atoi(argv[3]) : 2);
  test_keys();
  test_square_all();
  test_square_surface();
  test_square_hole();
  test_unbalanced_check();
  test_random_boxes();
  test_deepest();
  test_requests();
  test_masks();
  test_letter_a();
  return TEST_DONE();
}
