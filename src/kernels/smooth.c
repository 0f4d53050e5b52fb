/* Smoothing that only raises neighbourhood minima (kernels/smooth.h). */
#include "kernels/smooth.h"

#include <math.h>
#include <string.h>

#include "base/common.h"
#include "kernels/mesh_edit.h"
#include "kernels/node_work.h"
#include "soa/mesh.h"

/* A node with more elements than this is left where it is (the per-node
 * arrays of a move live on the stack: no allocation in the sweep). Octree
 * meshes have at most a few dozen. */
enum { MAX_INC = 160 };

/* Elements within TIGHT of their floor bend the direction of a move; at
 * most MAX_GRAD - 1 of them. */
#define TIGHT 0.05
enum { MAX_GRAD = 9 };

/* Least improvement of a node's minimum worth a move. */
#define MIN_GAIN 1e-7

/* The trial points of a node: steps towards the centroid of its neighbours,
 * then steps along the gradient of its worst element's J_ENS (fractions of
 * the mean distance to the neighbours). */
static const double to_centroid[] = {1.0, 0.5, 0.25};
static const double along_grad[] = {0.1, 0.03, 0.01, 0.003, 0.001};

/* One move of work node v: the best trial point, taken when it raises the
 * least J_ENS of v's elements by MIN_GAIN and keeps every element e of v at
 * or above floor(e) = max of m over e's nodes. Writes v's position and its
 * elements' Jb (the band's J_ENS, W->pos: their places) and jens only: the
 * nodes of one colour move at once. Returns 1 when v moved. */
static int move_node(mx_mesh *M, const mx_surface_index *S, const mx_node_work *W,
                     const double *m, double *Jb, uint32_t v, int on_surface, double q_target) {
  const uint64_t *off = W->off;
  const uint32_t *inc = W->inc, *pos = W->pos + off[v];
  const uint64_t e0 = off[v];
  const int ne = (int)(off[v + 1] - e0);
  if (ne == 0 || ne > MAX_INC) return 0;
  const double m0 = m[v];
  if (!(m0 < q_target)) return 0;
  double floor_[MAX_INC], jn[MAX_INC], jbest[MAX_INC];
  double c[3] = {0.0, 0.0, 0.0};
  size_t n = 0;
  int kw = 0; /* the worst element */
  for (int k = 0; k < ne; k++) {
    const uint32_t e = inc[e0 + (uint64_t)k];
    const uint32_t *row = M->conn + 8 * (size_t)e;
    double f = -INFINITY;
    for (int j = 0; j < mx_cell_nodes[M->type[e]]; j++) {
      f = fmax(f, m[row[j]]);
      if (row[j] == v) continue;
      for (int a = 0; a < 3; a++) c[a] += M->xyz[3 * (size_t)row[j] + a];
      n++;
    }
    floor_[k] = f;
    if (Jb[pos[k]] < Jb[pos[kw]]) kw = k;
  }
  double *x = M->xyz + 3 * (size_t)v;
  const double x0[3] = {x[0], x[1], x[2]};
  for (int a = 0; a < 3; a++) c[a] /= (double)n;
  double h = 0.0; /* mean distance to the neighbours */
  for (int k = 0; k < ne; k++) {
    const uint32_t e = inc[e0 + (uint64_t)k];
    const uint32_t *row = M->conn + 8 * (size_t)e;
    for (int j = 0; j < mx_cell_nodes[M->type[e]]; j++) {
      if (row[j] == v) continue;
      const double *y = M->xyz + 3 * (size_t)row[j];
      h += sqrt((y[0] - x0[0]) * (y[0] - x0[0]) + (y[1] - x0[1]) * (y[1] - x0[1]) +
                (y[2] - x0[2]) * (y[2] - x0[2]));
    }
  }
  h /= (double)n;
  /* The direction: the gradient of the worst element's J_ENS at v, made
   * orthogonal to the gradients of the elements close to their floor that
   * it would lower (those would stop any step). Gradients by central
   * differences, for at most MAX_GRAD elements, the closest to their
   * bounds first. */
  double g[3] = {0.0, 0.0, 0.0};
  {
    /* the elements within TIGHT of their bound, then the MAX_GRAD - 1
     * closest first (a partial selection sort; ties: the list order) */
    int tight[MAX_INC], nt = 0;
    double slack[MAX_INC];
    for (int k = 0; k < ne; k++) {
      const double sl = Jb[pos[k]] - fmax(floor_[k], m0);
      if (k != kw && sl < TIGHT) tight[nt] = k, slack[nt++] = sl;
    }
    for (int i = 0; i < nt && i < MAX_GRAD - 1; i++) {
      int b = i;
      for (int j = i + 1; j < nt; j++)
        if (slack[j] < slack[b]) b = j;
      const int tk = tight[b];
      const double ts = slack[b];
      tight[b] = tight[i], slack[b] = slack[i];
      tight[i] = tk, slack[i] = ts;
    }
    if (nt > MAX_GRAD - 1) nt = MAX_GRAD - 1;
    double gt[MAX_GRAD][3];
    const double d = 1e-4 * h;
    for (int i = 0; i <= nt; i++) {
      const uint32_t e = inc[e0 + (uint64_t)(i == 0 ? kw : tight[i - 1])];
      double *gi = i == 0 ? g : gt[i - 1];
      for (int a = 0; a < 3; a++) {
        x[a] = x0[a] + d;
        const double jp = mx_cell_jens(M, e);
        x[a] = x0[a] - d;
        const double jm = mx_cell_jens(M, e);
        x[a] = x0[a];
        gi[a] = (jp - jm) / (2.0 * d);
      }
    }
    const double g0[3] = {g[0], g[1], g[2]};
    for (int it = 0; it < 3; it++)
      for (int i = 0; i < nt; i++) {
        const double *gi = gt[i];
        const double dot = g[0] * gi[0] + g[1] * gi[1] + g[2] * gi[2];
        const double nn = gi[0] * gi[0] + gi[1] * gi[1] + gi[2] * gi[2];
        if (dot < 0.0 && nn > 0.0)
          for (int a = 0; a < 3; a++) g[a] -= dot / nn * gi[a];
      }
    double gg = sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
    if (!(g[0] * g0[0] + g[1] * g0[1] + g[2] * g0[2] > 0.0)) gg = 0.0; /* no way up */
    for (int a = 0; a < 3; a++) g[a] = gg > 0.0 ? g[a] / gg : 0.0;
  }
  const int nc = (int)(sizeof to_centroid / sizeof *to_centroid);
  const int ng = (int)(sizeof along_grad / sizeof *along_grad);
  double best = m0, bx[3] = {x0[0], x0[1], x0[2]};
  int first = kw; /* the element that stopped the last trial: looked at first */
  const int ntrials = nc + (g[0] != 0.0 || g[1] != 0.0 || g[2] != 0.0 ? ng : 0);
  for (int t = 0; t < ntrials; t++) {
    for (int a = 0; a < 3; a++)
      x[a] = t < nc ? x0[a] + to_centroid[t] * (c[a] - x0[a]) : x0[a] + along_grad[t - nc] * h * g[a];
    if (on_surface) { /* a boundary node stays on the surface */
      double q[3];
      mx_closest_point(S, x, q, NULL, NULL);
      memcpy(x, q, sizeof q);
    }
    double w = INFINITY;
    int ok = 1;
    for (int i = 0; i < ne && ok; i++) {
      const int k = i == 0 ? first : (i <= first ? i - 1 : i);
      const double j = mx_cell_jens(M, inc[e0 + (uint64_t)k]);
      jn[k] = j;
      w = fmin(w, j);
      if (!(j >= floor_[k]) || !(j >= best + MIN_GAIN)) {
        ok = 0;
        first = k;
      }
    }
    if (!ok) continue;
    best = w;
    memcpy(bx, x, sizeof bx);
    memcpy(jbest, jn, (size_t)ne * sizeof *jn);
  }
  memcpy(x, bx, sizeof bx);
  if (best == m0) return 0;
  for (int k = 0; k < ne; k++) {
    Jb[pos[k]] = jbest[k];
    M->jens[inc[e0 + (uint64_t)k]] = (float)jbest[k];
  }
  return 1;
}

int mx_smooth(mx_mesh *M, const uint8_t *states, const mx_surface_index *S,
              const mx_smooth_opts *o, mx_smooth_stats *st) {
  const double t0 = mx_wtime();
  const size_t nn = M->nnodes, nc = M->ncells;
  memset(st, 0, sizeof *st);
  mx_mesh_summarize(M);
  st->jens_min_before = st->jens_min_after = M->jens_min;
  if (o->rounds <= 0 || !nc) {
    st->seconds = mx_wtime() - t0;
    return MX_OK;
  }
  /* the work set: the movable nodes of the elements below the target (J_ENS
   * in double: the mesh keeps floats) */
  const double q_target = o->q_target;
  uint8_t *mark = mx_calloc(nn + 1);
  if (!mark) return MX_ENOMEM;
  size_t bad = 0;
#pragma omp parallel for schedule(static) reduction(+ : bad)
  for (size_t c = 0; c < nc; c++) {
    if (!(mx_cell_jens(M, (uint32_t)c) < q_target)) continue;
    bad++;
    for (int k = 0; k < mx_cell_nodes[M->type[c]]; k++) {
      const uint32_t v = M->conn[8 * c + k];
      if (!o->movable || o->movable[v]) __atomic_store_n(&mark[v], 1, __ATOMIC_RELAXED);
    }
  }
  mx_node_work W;
  memset(&W, 0, sizeof W);
  int rc = bad ? mx_node_work_build(M, states, mark, 1, "smoothing", &W) : MX_OK;
  double *m = NULL, *Jb = NULL;
  uint8_t *moved = NULL, *ever = NULL;
  if (!rc && W.nw) {
    m = mx_alloc((nn + 1) * sizeof *m);
    moved = mx_calloc(W.nw + 1);
    ever = mx_calloc(W.nw + 1);
    rc = mx_node_work_band_jens(M, &W, &Jb); /* kept through the moves */
    if (!m || !moved || !ever) rc = MX_ENOMEM;
  }
  st->work = W.nw;
  if (!rc && W.nw) {
    /* m: the neighbourhood minima of every node with incidence (the work
     * nodes and the other nodes of their elements) */
#pragma omp parallel for schedule(dynamic, 4096)
    for (size_t v = 0; v < nn; v++) m[v] = mx_band_min(Jb, W.pos, W.off[v], W.off[v + 1]);
    /* mark[v]: v is a work node whose neighbourhood changed since it was
     * last looked at (all of them at first) */
    size_t moves = 0;
    for (int r = 0; r < o->rounds; r++) {
      size_t changed = 0;
      for (int c = 0; c < W.ncol; c++) {
        const size_t k0 = W.cstart[c], k1 = W.cstart[c + 1];
        /* the moves of one colour touch disjoint elements and read m, which
         * only the update below writes */
#pragma omp parallel for schedule(dynamic, 32) reduction(+ : changed) if (k1 - k0 >= 64)
        for (size_t k = k0; k < k1; k++) {
          const size_t i = W.byc[k];
          const uint32_t v = W.work[i];
          moved[i] = 0;
          if (!mark[v]) continue;
          mark[v] = 0;
          moved[i] = (uint8_t)move_node(M, S, &W, m, Jb, v, W.onsurf[i], q_target);
          changed += moved[i];
        }
        /* the minima of the nodes of the changed elements, from the new
         * J_ENS (two moved nodes sharing a neighbour store the same value) */
#pragma omp parallel for schedule(dynamic, 32) if (k1 - k0 >= 64)
        for (size_t k = k0; k < k1; k++) {
          const size_t i = W.byc[k];
          if (!moved[i]) continue;
          ever[i] = 1;
          const uint32_t v = W.work[i];
          for (uint64_t e = W.off[v]; e < W.off[v + 1]; e++) {
            const uint32_t *row = M->conn + 8 * (size_t)W.inc[e];
            for (int j = 0; j < mx_cell_nodes[M->type[W.inc[e]]]; j++) {
              const uint32_t w = row[j];
              double mw = mx_band_min(Jb, W.pos, W.off[w], W.off[w + 1]);
              __atomic_store(&m[w], &mw, __ATOMIC_RELAXED);
              __atomic_store_n(&mark[w], 1, __ATOMIC_RELAXED);
            }
          }
        }
      }
      st->rounds = r + 1;
      moves += changed;
      if (!changed) break;
    }
    st->moves = moves;
    size_t distinct = 0;
#pragma omp parallel for schedule(static) reduction(+ : distinct)
    for (size_t i = 0; i < W.nw; i++) distinct += ever[i];
    st->moved = distinct;
  }
  mx_free(ever);
  mx_free(moved);
  mx_free(m);
  mx_free(Jb);
  mx_node_work_free(&W);
  mx_free(mark);
  if (rc) return rc;
  mx_mesh_summarize(M);
  st->jens_min_after = M->jens_min;
  st->seconds = mx_wtime() - t0;
  return MX_OK;
}
