#include "kernels/smooth.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "common.h"
#include "kernels/boundary.h"
#include "kernels/mesh_edit.h"
#include "kernels/quality.h"
#include "soa/mesh.h"
#include "soa/scan.h"

static int cmp_u32(const void *a, const void *b) {
  const uint32_t x = *(const uint32_t *)a, y = *(const uint32_t *)b;
  return (x > y) - (x < y);
}

static double elem_jens(const mx_mesh_out *M, uint32_t c) {
  double x[8][3];
  const int nv = mx_cell_nodes[M->type[c]];
  for (int k = 0; k < nv; k++) memcpy(x[k], M->xyz + 3 * (size_t)M->conn[8 * (size_t)c + k], sizeof x[k]);
  return mx_jens(M->type[c], x);
}

/* 1 when node v lies on a face used by one element only: the mesh boundary.
 * Every element sharing a face through v is incident to v, so the incident
 * list [e0, e1) of `inc` is enough; a face counts as shared when another
 * incident element has all its nodes (in a conforming mesh without
 * overlaps, that is the same face). An inside node can lie on the boundary
 * (a lattice node exactly on a flat part of the surface); it must stay
 * there like a surface node. */
static int on_mesh_boundary(const mx_mesh_out *M, const uint32_t *inc, size_t e0, size_t e1,
                            uint32_t v) {
  for (size_t e = e0; e < e1; e++) {
    const uint32_t c = inc[e];
    const int t = M->type[c];
    const uint32_t *row = M->conn + 8 * (size_t)c;
    for (int f = 0; f < mx_cell_nfaces[t]; f++) {
      const int8_t *fv = mx_cell_faces[t][f];
      const int n = fv[3] < 0 ? 3 : 4;
      int has = 0;
      for (int i = 0; i < n; i++) has |= row[fv[i]] == v;
      if (!has) continue;
      int shared = 0;
      for (size_t g = e0; g < e1 && !shared; g++) {
        const uint32_t d = inc[g];
        if (d == c) continue;
        const uint32_t *rd = M->conn + 8 * (size_t)d;
        const int nd = mx_cell_nodes[M->type[d]];
        int all = 1;
        for (int i = 0; i < n && all; i++) {
          const uint32_t w = row[fv[i]];
          int in = 0;
          for (int j = 0; j < nd; j++) in |= rd[j] == w;
          all = in;
        }
        shared = all;
      }
      if (!shared) return 1;
    }
  }
  return 0;
}

/* Worst J_ENS of the elements [e0, e1) of list `inc`. */
static double worst_of(const mx_mesh_out *M, const uint32_t *inc, size_t e0, size_t e1) {
  double w = INFINITY;
  for (size_t i = e0; i < e1; i++) w = fmin(w, elem_jens(M, inc[i]));
  return w;
}

int mx_smooth_nodes(mx_mesh_out *M, const uint8_t *states, const mx_surface_index *S,
                    double q_target, int sweeps, size_t *moved) {
  const size_t nn = M->nnodes, nc = M->ncells;
  *moved = 0;
  /* The work set: the nodes of the elements below the target. */
  uint8_t *mark = mx_calloc(nn + 1);
  if (!mark) return MX_EINPUT;
  size_t bad = 0;
#pragma omp parallel for schedule(static) reduction(+ : bad)
  for (size_t c = 0; c < nc; c++) {
    if (M->jens[c] >= q_target) continue;
    bad++;
    for (int k = 0; k < mx_cell_nodes[M->type[c]]; k++) {
      const uint32_t v = M->conn[8 * c + k];
      __atomic_store_n(&mark[v], 1, __ATOMIC_RELAXED);
    }
  }
  if (!bad) {
    mx_free(mark);
    return MX_OK;
  }
  /* Incident elements of the marked nodes: count, prefix sum, fill, then
   * sort each list (the fill order depends on the threads). */
  uint64_t *off = mx_calloc((nn + 1) * sizeof *off);
  if (!off) {
    mx_free(mark);
    return MX_EINPUT;
  }
#pragma omp parallel for schedule(static)
  for (size_t c = 0; c < nc; c++)
    for (int k = 0; k < mx_cell_nodes[M->type[c]]; k++) {
      const uint32_t v = M->conn[8 * c + k];
      if (mark[v]) __atomic_fetch_add(&off[v], 1, __ATOMIC_RELAXED);
    }
  const uint64_t total = mx_scan_u64(off, nn);
  off[nn] = total;
  uint32_t *inc = mx_alloc((total + 1) * sizeof *inc);
  uint64_t *cur = mx_alloc((nn + 1) * sizeof *cur);
  size_t nw = 0;
  for (size_t v = 0; v < nn; v++) nw += mark[v];
  uint32_t *work = mx_alloc((nw + 1) * sizeof *work);
  if (!inc || !cur || !work) {
    mx_free(inc); mx_free(cur); mx_free(work); mx_free(off); mx_free(mark);
    return MX_EINPUT;
  }
  memcpy(cur, off, nn * sizeof *cur);
#pragma omp parallel for schedule(static)
  for (size_t c = 0; c < nc; c++)
    for (int k = 0; k < mx_cell_nodes[M->type[c]]; k++) {
      const uint32_t v = M->conn[8 * c + k];
      if (mark[v]) inc[__atomic_fetch_add(&cur[v], 1, __ATOMIC_RELAXED)] = (uint32_t)c;
    }
  nw = 0;
  for (size_t v = 0; v < nn; v++)
    if (mark[v]) {
      work[nw++] = (uint32_t)v;
      qsort(inc + off[v], off[v + 1] - off[v], sizeof *inc, cmp_u32);
    }
  mx_free(cur);
  /* Which work nodes stay on the surface: the outside ones, and the inside
   * ones on the mesh boundary (the topology does not change below). */
  uint8_t *onsurf = mx_alloc(nw + 1);
  if (!onsurf) {
    mx_free(inc); mx_free(work); mx_free(off); mx_free(mark);
    return MX_EINPUT;
  }
#pragma omp parallel for schedule(dynamic, 1024)
  for (size_t i = 0; i < nw; i++) {
    const uint32_t v = work[i];
    onsurf[i] = (uint8_t)(states[v] != MX_NODE_INSIDE ||
                          on_mesh_boundary(M, inc, off[v], off[v + 1], v));
  }
  /* mark[v] now means "v is in the work set and its neighbourhood changed
   * since it was last looked at". */
  /* Sweeps, one node at a time in id order. */
  static const double steps[] = {1.0, 0.5, 0.25, 0.125};
  size_t nm = 0;
  for (int s = 0; s < sweeps; s++) {
    size_t changed = 0;
    for (size_t i = 0; i < nw; i++) {
      const uint32_t v = work[i];
      if (!mark[v]) continue;
      mark[v] = 0;
      const size_t e0 = off[v], e1 = off[v + 1];
      double *x = M->xyz + 3 * (size_t)v;
      const double w0 = worst_of(M, inc, e0, e1);
      if (w0 >= q_target) continue;
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
      if (!n) continue;
      const double x0[3] = {x[0], x[1], x[2]};
      const int on_surface = onsurf[i];
      double best = w0, bx[3] = {x0[0], x0[1], x0[2]};
      for (size_t t = 0; t < sizeof steps / sizeof *steps; t++) {
        for (int a = 0; a < 3; a++) x[a] = x0[a] + steps[t] * (c[a] / (double)n - x0[a]);
        if (on_surface) { /* a boundary node stays on the surface */
          double q[3];
          mx_closest_point(S, x, q, NULL, NULL);
          memcpy(x, q, sizeof q);
        }
        const double w = worst_of(M, inc, e0, e1);
        if (w > best + 1e-12) {
          best = w;
          memcpy(bx, x, sizeof bx);
        }
      }
      memcpy(x, bx, sizeof bx);
      if (best > w0) {
        changed++;
        for (size_t e = e0; e < e1; e++) {
          M->jens[inc[e]] = elem_jens(M, inc[e]);
          const uint32_t *cv = M->conn + 8 * (size_t)inc[e];
          for (int k = 0; k < mx_cell_nodes[M->type[inc[e]]]; k++)
            if (off[cv[k] + 1] > off[cv[k]]) mark[cv[k]] = 1; /* in the work set */
        }
      }
    }
    nm += changed;
    if (!changed) break;
  }
  mx_free(onsurf);
  mx_free(inc);
  mx_free(off);
  mx_free(work);
  mx_free(mark);
  *moved = nm;
  mx_mesh_summarize(M);
  return MX_OK;
}
