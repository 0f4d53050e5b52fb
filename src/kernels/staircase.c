/* Line 14 of Algorithm 1 (2015 paper), "decrease staircase effect": the
 * optional sub-elements the surface patterns dropped (kernels/
 * surface_patterns.c) are put back where their J_ENS, at the node positions
 * after the shrink, is above a threshold. See kernels/staircase.h. */
#include "kernels/staircase.h"

#include <string.h>

#include "base/common.h"
#include "geom/quality.h"
#include "kernels/mesh_edit.h"
#include "soa/mesh.h"

int mx_staircase(mx_mesh *M, const mx_optional *opt, double q_min,
                 mx_surface_stats *stats) {
  uint8_t *ok = mx_alloc(opt->n + 1);
  double *q = mx_alloc((opt->n + 1) * sizeof *q);
  if (!ok || !q) {
    mx_free(ok);
    mx_free(q);
    return MX_ENOMEM;
  }
  size_t n = 0;
#pragma omp parallel for schedule(static) reduction(+ : n)
  for (size_t i = 0; i < opt->n; i++) {
    double x[8][3];
    const int ne = mx_cell_nodes[opt->type[i]];
    for (int k = 0; k < ne; k++) memcpy(x[k], M->xyz + 3 * (size_t)opt->conn[8 * i + k], sizeof x[k]);
    q[i] = mx_jens(opt->type[i], x);
    ok[i] = q[i] > q_min;
    n += ok[i];
  }
  const size_t nc = M->ncells, nt = nc + n;
  if (mx_mesh_grow_cells(M, nt)) {
    mx_free(ok);
    mx_free(q);
    return MX_ENOMEM;
  }
  size_t w = nc;
  for (size_t i = 0; i < opt->n; i++) {
    if (!ok[i]) continue;
    M->type[w] = opt->type[i];
    memcpy(M->conn + 8 * w, opt->conn + 8 * i, 8 * sizeof *M->conn);
    M->level[w] = opt->level[i];
    M->leaf[w] = opt->leaf[i];
    M->jens[w] = (float)q[i];
    w++;
  }
  M->ncells = nt;
  stats->restored = n;
  mx_free(ok);
  mx_free(q);
  mx_mesh_summarize(M);
  return MX_OK;
}
