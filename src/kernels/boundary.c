#include "base/cancel.h"
#include "kernels/boundary.h"

#include "base/common.h"
#include "kernels/mesh_edit.h"
#include "geom/quality.h"
#include "soa/mesh.h"
#include "base/scan.h"

#include <math.h>
#include <string.h>

int mx_node_states(const mx_tree *tr, const uint32_t *leaves,
                   const mx_mesh *M, const mx_surface_index *S,
                   uint8_t *states, size_t *queries) {
  const mx_octree *T = &tr->oct;
  enum { UNKNOWN = 2 };
#pragma omp parallel for schedule(static)
  for (size_t v = 0; v < M->nnodes; v++) states[v] = UNKNOWN;
  /* Elements of leaves that meet no domain triangle: all nodes inside. Two
   * threads may write the same value to a shared node: benign. */
#pragma omp parallel for schedule(static)
  for (size_t c = 0; c < M->ncells; c++) {
    if (T->flags[leaves[M->leaf[c]]] & MX_OCT_SURFACE) continue;
    const int nv = mx_cell_nodes[M->type[c]];
    for (int k = 0; k < nv; k++)
      __atomic_store_n(&states[M->conn[8 * c + k]], (uint8_t)MX_NODE_INSIDE,
                       __ATOMIC_RELAXED);
  }
  /* the others located a run of node ids at a time (nodes are numbered
   * leaf by leaf: a run's unknown nodes lie near each other), by blocks
   * (mx_inside_block: the tree walked once a block) */
  enum { RUN = 2 * MX_BLOCK };
  const size_t nruns = (M->nnodes + RUN - 1) / RUN;
  size_t q = 0;
  const double near = MX_NODE_ON_UNITS * tr->grid.unit;
#pragma omp parallel for schedule(dynamic, 64) reduction(+ : q)
  for (size_t r = 0; r < nruns; r++) {
    uint32_t ids[RUN];
    uint8_t in[RUN], on[RUN];
    int n = 0;
    for (size_t v = r * RUN; v < M->nnodes && v < (r + 1) * RUN; v++)
      if (states[v] == UNKNOWN) ids[n++] = (uint32_t)v;
    mx_inside_block(S, M->xyz, ids, n, in, on, near * near);
    for (int i = 0; i < n; i++)
      states[ids[i]] = on[i] ? MX_NODE_ON : in[i] ? MX_NODE_INSIDE : MX_NODE_OUTSIDE;
    q += (size_t)n;
  }
  *queries = q;
  return MX_OK;
}



enum { COUNT_BITS = 12 };

/* llround(x) for 0 <= x < 2^52 without the library call: the integer part
 * (exact), then up when the fraction (exact: x less its integer part) is at
 * least one half. */
static inline uint64_t round_half_up(double x) {
  const uint64_t i = (uint64_t)x;
  return i + (uint64_t)(x - (double)i >= 0.5);
}
#define ONE_EDGE ((uint64_t)1 << (64 - COUNT_BITS))

int mx_move_close_nodes(mx_mesh *M, uint8_t *states, const mx_surface_index *S,
                        double ratio, size_t *moved, uint8_t **moved_flags) {
  const size_t nn = M->nnodes, nc = M->ncells;
  /* Candidates: inside nodes of surface elements. */
  uint8_t *cand = mx_calloc(nn + 1);
  /* per candidate, its edges' count (the top COUNT_BITS) and their
   * lengths' sum (fixed point, below), in one word: one atomic addition
   * an element and node. A node has at most a few hundred element edges
   * (8 leaves, a few dozen elements each): below 2^12; each length is at
   * most 2^40 units, so the sum stays below 2^52. */
  uint64_t *len = mx_calloc((nn + 1) * sizeof *len);
  if (!cand || !len) {
    mx_free(cand);
    mx_free(len);
    return MX_ENOMEM;
  }
#pragma omp parallel for schedule(static)
  for (size_t c = 0; c < nc; c++) {
    const uint32_t *v = M->conn + 8 * c;
    const int nv = mx_cell_nodes[M->type[c]];
    int in = 0;
    for (int k = 0; k < nv; k++) in += mx_node_inside(states[v[k]]);
    if (in == 0 || in == nv) continue;
    for (int k = 0; k < nv; k++)
      if (mx_node_inside(states[v[k]])) __atomic_store_n(&cand[v[k]], 1, __ATOMIC_RELAXED);
  }
  /* Average length of the element edges at each candidate, summed in fixed
   * point (integer additions: the same sums in any order, so the decisions
   * are the same for any thread count). */
  double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
#pragma omp parallel for schedule(static) reduction(min : lo[:3]) reduction(max : hi[:3])
  for (size_t v = 0; v < nn; v++)
    for (int x = 0; x < 3; x++) {
      lo[x] = fmin(lo[x], M->xyz[3 * v + x]);
      hi[x] = fmax(hi[x], M->xyz[3 * v + x]);
    }
  double diag = 0.0;
  for (int x = 0; x < 3 && nn; x++) diag += (hi[x] - lo[x]) * (hi[x] - lo[x]);
  const double unit = ldexp(sqrt(diag) + 1e-300, -40); /* 2^40 units per diagonal */
#pragma omp parallel for schedule(static)
  for (size_t c = 0; c < nc; c++) {
    const uint32_t *v = M->conn + 8 * c;
    const int t = M->type[c];
    /* the element's candidates as bits first: most elements have none;
     * then the sums per element and node, added once each */
    unsigned in = 0;
    for (int k = 0; k < mx_cell_nodes[t]; k++) in |= (unsigned)(cand[v[k]] != 0) << k;
    if (!in) continue;
    uint64_t acc[8] = {0, 0, 0, 0, 0, 0, 0, 0};
    for (int e = 0; e < mx_cell_nedges[t]; e++) {
      const int ka = mx_cell_edge[t][e][0], kb = mx_cell_edge[t][e][1];
      if (!((in >> ka | in >> kb) & 1u)) continue;
      const uint32_t a = v[ka], b = v[kb];
      double d2 = 0.0;
      for (int x = 0; x < 3; x++) {
        const double u = M->xyz[3 * (size_t)a + x] - M->xyz[3 * (size_t)b + x];
        d2 += u * u;
      }
      const uint64_t l = round_half_up(sqrt(d2) / unit) + ONE_EDGE;
      acc[ka] += in >> ka & 1u ? l : 0;
      acc[kb] += in >> kb & 1u ? l : 0;
    }
    for (int k = 0; k < mx_cell_nodes[t]; k++)
      if (in >> k & 1u) __atomic_fetch_add(&len[v[k]], acc[k], __ATOMIC_RELAXED);
  }
  /* Each candidate moved as soon as it is decided: a decision reads the
   * node's own position and the sums above only, so the moves of the
   * others do not change it (the same as deciding all on the old positions
   * first). The closest points by runs of node ids (nodes are numbered leaf
   * by leaf: a run's candidates lie near each other), a block at a time
   * (mx_closest_point_block). cand: 1 for a node that moved. */
  enum { RUN = 2 * MX_BLOCK };
  const size_t nruns = (nn + RUN - 1) / RUN;
  size_t nmoved = 0;
  atomic_int *cf = mx_cancel_flag; /* base/cancel.h: the longest loop */
#pragma omp parallel for schedule(dynamic, 16) reduction(+ : nmoved)
  for (size_t r = 0; r < nruns; r++) {
    if (mx_cancel_seen(cf)) continue;
    uint32_t ids[RUN];
    double rmax[RUN], dist[RUN], q[RUN][3];
    int n = 0;
    for (size_t v = r * RUN; v < nn && v < (r + 1) * RUN; v++) {
      const uint64_t cnt = len[v] >> (64 - COUNT_BITS);
      if (!cand[v] || !cnt) {
        cand[v] = 0;
        continue;
      }
      const double avg = (double)(len[v] & (ONE_EDGE - 1)) * unit / (double)cnt;
      rmax[n] = ratio * avg;
      ids[n++] = (uint32_t)v;
    }
    mx_closest_point_block(S, M->xyz, ids, n, rmax, dist, q);
    for (int i = 0; i < n; i++) {
      const uint32_t v = ids[i];
      if (dist[i] < rmax[i]) {
        memcpy(M->xyz + 3 * (size_t)v, q[i], sizeof q[i]);
        states[v] = MX_NODE_OUTSIDE;
        cand[v] = 1;
        nmoved++;
      } else {
        cand[v] = 0;
      }
    }
  }
  mx_free(len);
  if (mx_cancelled()) { /* (the caller drops the mesh: some nodes moved) */
    mx_free(cand);
    return MX_ECANCELED;
  }
  if (moved_flags) {
    *moved_flags = cand; /* the caller recomputes J_ENS */
  } else {
    mx_mesh_update_jens(M, cand);
    mx_free(cand);
  }
  *moved = nmoved;
  return MX_OK;
}

/* Distinct outside nodes of the elements [c0, c1) (one leaf's), in order of
 * first use. */
static int leaf_outside_nodes(const mx_mesh *M, size_t c0, size_t c1,
                              const uint8_t *states, uint32_t out[64]) {
  int n = 0;
  for (size_t c = c0; c < c1; c++)
    for (int k = 0; k < mx_cell_nodes[M->type[c]]; k++) {
      const uint32_t v = M->conn[8 * c + k];
      if (states[v] != MX_NODE_OUTSIDE) continue;
      int seen = 0;
      for (int j = 0; j < n && !seen; j++) seen = out[j] == v;
      if (!seen && n < 64) out[n++] = v;
    }
  return n;
}

/* Closest domain triangle of leaf o's list to p: squared distance, id. */
static double leaf_closest(const mx_tree *tr, uint32_t o, const double p[3],
                           uint32_t *tri) {
  const mx_octree *T = &tr->oct;
  double best = INFINITY, q[3];
  *tri = UINT32_MAX;
  for (uint32_t k = 0; k < T->tri_cnt[o]; k++) {
    const uint32_t t = T->tri_pool[T->tri_off[o] + k];
    if (t >= tr->nt_domain) continue;
    const double d2 = mx_closest_on_triangle(tr->tri_xyz + 9 * (size_t)t, p, q);
    if (d2 < best || (d2 == best && t < *tri)) {
      best = d2;
      *tri = t;
    }
  }
  return best;
}

static inline uint64_t dbits(double d) {
  uint64_t u;
  memcpy(&u, &d, sizeof u);
  return u; /* non-negative doubles order as their bits */
}

int mx_shrink_to_boundary(const mx_tree *tr, const uint32_t *leaves,
                          mx_mesh *M, const uint8_t *states, size_t *moved) {
  const size_t nn = M->nnodes, nc = M->ncells;
  /* Elements are in leaf order: each leaf's elements form one run. */
  uint64_t *run = mx_alloc((nc + 2) * sizeof *run);
  uint64_t *best = mx_alloc((nn + 1) * sizeof *best);
  uint32_t *btri = mx_alloc((nn + 1) * sizeof *btri);
  if (!run || !best || !btri) {
    mx_free(run); mx_free(best); mx_free(btri);
    return MX_ENOMEM;
  }
  /* the runs' starts: counted per block, prefix-summed, filled */
  enum { RB = 1 << 16 };
  const size_t nbk = (nc + RB - 1) / RB;
  uint64_t *boff = mx_alloc((nbk + 1) * sizeof *boff);
  if (!boff) {
    mx_free(run); mx_free(best); mx_free(btri);
    return MX_ENOMEM;
  }
#pragma omp parallel for schedule(static)
  for (size_t b = 0; b < nbk; b++) {
    uint64_t k = 0;
    for (size_t c = b * RB; c < nc && c < (b + 1) * RB; c++)
      k += c == 0 || M->leaf[c] != M->leaf[c - 1];
    boff[b] = k;
  }
  const size_t nr = (size_t)mx_scan_u64(boff, nbk);
#pragma omp parallel for schedule(static)
  for (size_t b = 0; b < nbk; b++) {
    uint64_t k = boff[b];
    for (size_t c = b * RB; c < nc && c < (b + 1) * RB; c++)
      if (c == 0 || M->leaf[c] != M->leaf[c - 1]) run[k++] = c;
  }
  mx_free(boff);
  run[nr] = nc;
#pragma omp parallel for schedule(static)
  for (size_t v = 0; v < nn; v++) {
    best[v] = UINT64_MAX;
    btri[v] = UINT32_MAX;
  }
  /* One pass over (leaf, outside node): the least (distance, triangle id),
   * compared and stored under a per-node spin lock (a node is shared by a
   * few leaves: the locks are hardly ever contended). */
  uint8_t *lock = mx_calloc(nn + 1);
  if (!lock) {
    mx_free(run); mx_free(best); mx_free(btri);
    return MX_ENOMEM;
  }
#pragma omp parallel for schedule(dynamic, 256)
  for (size_t r = 0; r < nr; r++) {
    const uint32_t o = leaves[M->leaf[run[r]]];
    if (!tr->oct.tri_cnt[o]) continue;
    uint32_t vs[64];
    const int k = leaf_outside_nodes(M, run[r], run[r + 1], states, vs);
    for (int j = 0; j < k; j++) {
      uint32_t t;
      const double d2 = leaf_closest(tr, o, M->xyz + 3 * (size_t)vs[j], &t);
      if (t == UINT32_MAX) continue;
      const uint64_t mine = dbits(d2);
      const uint32_t v = vs[j];
      while (__atomic_test_and_set(&lock[v], __ATOMIC_ACQUIRE)) {
      }
      if (mine < best[v] || (mine == best[v] && t < btri[v])) {
        best[v] = mine;
        btri[v] = t;
      }
      __atomic_clear(&lock[v], __ATOMIC_RELEASE);
    }
  }
  mx_free(lock);
  size_t nm = 0;
#pragma omp parallel for schedule(static) reduction(+ : nm)
  for (size_t v = 0; v < nn; v++) {
    if (btri[v] == UINT32_MAX) continue;
    double q[3], *x = M->xyz + 3 * v;
    mx_closest_on_triangle(tr->tri_xyz + 9 * (size_t)btri[v], x, q);
    nm++;
    if (q[0] == x[0] && q[1] == x[1] && q[2] == x[2]) { /* there already (a close node) */
      btri[v] = UINT32_MAX;
      continue;
    }
    memcpy(x, q, sizeof q);
  }
  /* J_ENS of the elements with a node that moved (btri[] left set) and of
   * those the surface patterns made or changed (NaN): the others' is that
   * of their positions already; the coordinates gathered for those only. */
  size_t invalid = 0;
  double jmin = INFINITY;
#pragma omp parallel for schedule(static) reduction(+ : invalid) reduction(min : jmin)
  for (size_t c = 0; c < nc; c++) {
    const int nv = mx_cell_nodes[M->type[c]];
    int out = 0;
    for (int k = 0; k < nv; k++) out |= btri[M->conn[8 * c + k]] != UINT32_MAX;
    if (out || isnan(M->jens[c])) {
      double x[8][3];
      for (int k = 0; k < nv; k++)
        memcpy(x[k], M->xyz + 3 * (size_t)M->conn[8 * c + k], sizeof x[k]);
      M->jens[c] = (float)mx_jens(M->type[c], x);
    }
    invalid += mx_jens_invalid(M->jens[c]);
    if (M->jens[c] < jmin) jmin = M->jens[c];
  }
  M->invalid = invalid;
  M->jens_min = nc ? jmin : 1.0;
  mx_free(run);
  mx_free(best);
  mx_free(btri);
  *moved = nm;
  return MX_OK;
}
