#include "kernels/untangle.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "base/common.h"
#include "kernels/boundary.h"
#include "kernels/mesh_edit.h"
#include "kernels/node_work.h"
#include "geom/quality.h"
#include "soa/mesh.h"

/* The worst J_ENS of the elements [e0, e1) of list inc at the current
 * positions, or any value <= floor once one element is there (a trial that
 * cannot win stops at its first element that bad); *first: the element
 * looked at first, which becomes the one that stopped it (the worst one
 * of a trial is often the next trial's). */
static double worst_above(const mx_mesh *M, const uint32_t *inc, size_t e0, size_t e1,
                          double floor, size_t *first) {
  double w = mx_cell_jens(M, inc[*first]);
  if (w <= floor) return w;
  for (size_t i = e0; i < e1; i++) {
    if (i == *first) continue;
    w = fmin(w, mx_cell_jens(M, inc[i]));
    if (w <= floor) {
      *first = i;
      return w;
    }
  }
  return w;
}

/* One move of work node v (index i): the best of a few points between its
 * position and the centroid of its neighbours, kept when it raises the worst
 * J_ENS of its elements; then their J_ENS and the marks of their nodes.
 * Touches only v's position and v's elements: nodes of one colour move at
 * once. Returns 1 when v moved. */
static int move_node(mx_mesh *M, const mx_surface_index *S, const mx_node_work *W,
                     double *jd, uint8_t *mark, uint32_t v, int on_surface,
                     const mx_untangle_opts *o, const double *x_init, double clear) {
  const uint32_t *inc = W->inc, *pos = W->pos;
  const uint64_t *off = W->off;
  static const double steps[] = {1.0, 0.5, 0.25, 0.125};
  static const double along[] = {0.25, 0.1, 0.04};
  const double q_target = o->q_target;
  const size_t e0 = off[v], e1 = off[v + 1];
  double *x = M->xyz + 3 * (size_t)v;
  const double w0 = mx_band_min(jd, pos, e0, e1); /* the worst */
  if (w0 >= q_target) return 0;
  /* centroid of the other nodes of the incident elements */
  double c[3] = {0.0, 0.0, 0.0};
  size_t n = 0;
  for (size_t e = e0; e < e1; e++) {
    const uint32_t *cv = M->conn + 8 * (size_t)inc[e];
    for (int k = 0; k < mx_cell_nodes[M->type[inc[e]]]; k++) {
      if (cv[k] == v) continue;
      for (int a = 0; a < 3; a++) c[a] += M->xyz[3 * (size_t)cv[k] + a];
      n++;
    }
  }
  if (!n) return 0;
  const double x0[3] = {x[0], x[1], x[2]};
  double h = 0.0; /* the mean distance to the other nodes, for the axis moves */
  if (o->axis_moves)
    for (size_t e = e0; e < e1; e++) {
      const uint32_t *cv = M->conn + 8 * (size_t)inc[e];
      for (int k = 0; k < mx_cell_nodes[M->type[inc[e]]]; k++) {
        if (cv[k] == v) continue;
        const double *y = M->xyz + 3 * (size_t)cv[k];
        h += sqrt((y[0] - x0[0]) * (y[0] - x0[0]) + (y[1] - x0[1]) * (y[1] - x0[1]) +
                  (y[2] - x0[2]) * (y[2] - x0[2])) / (double)n;
      }
    }
  const int nsteps = (int)(sizeof steps / sizeof *steps);
  const int nal = o->axis_moves > 3 ? 3 : o->axis_moves;
  const int ntrials = nsteps + 6 * nal;
  double best = w0, bx[3] = {x0[0], x0[1], x0[2]};
  size_t first = e0;
  for (int t = 0; t < ntrials; t++) {
    if (t < nsteps) {
      for (int a = 0; a < 3; a++) x[a] = x0[a] + steps[t] * (c[a] / (double)n - x0[a]);
    } else { /* along an axis, both ways, three lengths */
      const int d = (t - nsteps) % 6, l = (t - nsteps) / 6;
      memcpy(x, x0, sizeof x0);
      x[d / 2] += (d & 1 ? -1.0 : 1.0) * along[l] * h;
    }
    if (on_surface) { /* a boundary node stays on the surface */
      double q[3];
      mx_closest_point(S, x, q, NULL, NULL);
      memcpy(x, q, sizeof q);
    }
    /* the quality first: a trial that does not beat the best is dropped
     * before the region's query (the same trials win either way) */
    const double w = worst_above(M, inc, e0, e1, best + 1e-12, &first);
    if (!(w > best + 1e-12)) continue;
    if (on_surface) {
      /* and in its region when it has one (the outer boundary's nodes
       * between two materials) */
      if (o->surface_region_of && o->region[v] != MX_REGION_NONE &&
          o->surface_region_of(o->region_ctx, x) != o->region[v])
        continue;
    } else if (o->region_of) { /* an inside node stays in its region */
      /* (no query within the clearance of where it started: no shell there) */
      const double dx = x[0] - x_init[0], dy = x[1] - x_init[1], dz = x[2] - x_init[2];
      if (!(dx * dx + dy * dy + dz * dz < clear * clear) &&
          o->region_of(o->region_ctx, x) != o->region[v])
        continue;
    }
    best = w;
    memcpy(bx, x, sizeof bx);
  }
  memcpy(x, bx, sizeof bx);
  if (!(best > w0)) return 0;
  for (size_t e = e0; e < e1; e++) {
    jd[pos[e]] = mx_cell_jens(M, inc[e]);
    M->jens[inc[e]] = (float)jd[pos[e]];
    const uint32_t *cv = M->conn + 8 * (size_t)inc[e];
    for (int k = 0; k < mx_cell_nodes[M->type[inc[e]]]; k++)
      if (off[cv[k] + 1] > off[cv[k]]) /* in the work set */
        __atomic_store_n(&mark[cv[k]], 1, __ATOMIC_RELAXED);
  }
  return 1;
}

int mx_untangle(mx_mesh *M, const uint8_t *states, const mx_surface_index *S,
                    double q_target, int sweeps, size_t *moved) {
  const mx_untangle_opts o = {q_target, sweeps, 0, NULL, NULL, NULL, NULL, NULL, NULL};
  return mx_untangle_with(M, states, S, &o, moved);
}

int mx_untangle_with(mx_mesh *M, const uint8_t *states, const mx_surface_index *S,
                     const mx_untangle_opts *o, size_t *moved) {
  const size_t nn = M->nnodes, nc = M->ncells;
  const double q_target = o->q_target;
  const int sweeps = o->sweeps;
  *moved = 0;
  /* The work set: the nodes of the elements below the target. */
  uint8_t *mark = mx_calloc(nn + 1);
  if (!mark) return MX_ENOMEM;
  size_t bad = 0;
#pragma omp parallel for schedule(static) reduction(+ : bad)
  for (size_t c = 0; c < nc; c++) {
    if (M->jens[c] >= q_target) continue;
    bad++;
    for (int k = 0; k < mx_cell_nodes[M->type[c]]; k++) {
      const uint32_t v = M->conn[8 * c + k];
      if (!o->movable || o->movable[v]) __atomic_store_n(&mark[v], 1, __ATOMIC_RELAXED);
    }
  }
  if (!bad) {
    mx_free(mark);
    return MX_OK;
  }
  mx_node_work W;
  const int wst = mx_node_work_build(M, states, mark, 0, "untangling", &W);
  if (wst) {
    mx_free(mark);
    return wst;
  }
  const size_t nw = W.nw;
  const uint32_t *work = W.work, *byc = W.byc;
  const uint8_t *onsurf = W.onsurf;
  /* the band's J_ENS in double, at the current positions (the moves keep
   * them so): a node's worst is read, not computed again */
  double *jd = NULL;
  if (mx_node_work_band_jens(M, &W, &jd)) {
    mx_node_work_free(&W);
    mx_free(mark);
    return MX_ENOMEM;
  }
  /* With regions: where each free work node starts, and its clearance (the
   * distance within which no shell lies) */
  double *x_init = NULL, *clear = NULL;
  if (o->region_of) {
    x_init = mx_alloc((3 * nw + 3) * sizeof *x_init);
    clear = mx_alloc((nw + 1) * sizeof *clear);
    if (!x_init || !clear) {
      mx_free(x_init); mx_free(clear);
      mx_free(jd);
      mx_node_work_free(&W);
      mx_free(mark);
      return MX_ENOMEM;
    }
#pragma omp parallel for schedule(dynamic, 256)
    for (size_t i = 0; i < nw; i++) {
      const double *x = M->xyz + 3 * (size_t)work[i];
      memcpy(x_init + 3 * i, x, 3 * sizeof *x);
      clear[i] = onsurf[i] || !o->clearance_of ? 0.0 : o->clearance_of(o->region_ctx, x);
    }
  }
  /* mark[v] now means "v is in the work set and its neighbourhood changed
   * since it was last looked at". */
  size_t nm = 0;
  for (int s = 0; s < sweeps; s++) {
    size_t changed = 0;
    for (int c = 0; c < W.ncol; c++) {
      /* a small colour on one thread: no fork and barrier for a few nodes
       * (the same result: its nodes do not interact) */
#pragma omp parallel for schedule(dynamic, 32) reduction(+ : changed) \
    if (W.cstart[c + 1] - W.cstart[c] >= 64)
      for (size_t k = W.cstart[c]; k < W.cstart[c + 1]; k++) {
        const size_t i = byc[k];
        const uint32_t v = work[i];
        if (!__atomic_load_n(&mark[v], __ATOMIC_RELAXED)) continue;
        mark[v] = 0;
        changed += (size_t)move_node(M, S, &W, jd, mark, v, onsurf[i], o,
                                     x_init ? x_init + 3 * i : NULL, clear ? clear[i] : 0.0);
      }
    }
    nm += changed;
    if (!changed) break;
  }
  mx_free(x_init);
  mx_free(clear);
  mx_free(jd);
  mx_node_work_free(&W);
  mx_free(mark);
  *moved = nm;
  mx_mesh_summarize(M);
  return MX_OK;
}
