/* Several materials: the interfaces' nodes onto the shells
 * (mesher/materials.h, mx_snap_interfaces). */
#include <math.h>
#include <string.h>

#include "base/common.h"
#include "geom/quality.h"
#include "io/boundary_faces.h"
#include "kernels/boundary.h"
#include "mesher/materials.h"
#include "soa/mesh.h"

/* The nodes of the faces between two materials moved onto the shells: each
 * to its closest point, else half-way, when every element around it keeps
 * a J_ENS no lower than its own or the mesh's worst before (so the worst
 * never drops). In node order, one node after the other (deterministic;
 * work proportional to the interfaces). snapped[v] = MX_SNAPPED for the nodes
 * moved to the shells. A staircase's nodes brought to the interface, as the
 * node-shifting of geometry-adapted hexahedral meshes. */
int mx_snap_interfaces(mx_mesher *m, uint8_t *snapped, size_t *moved) {
  mx_mesh *M = &m->M;
  const size_t nn = M->nnodes, nc = M->ncells;
  *moved = 0;
  int32_t *label = mx_alloc((nc + 1) * sizeof *label);
  if (!label) return MX_ENOMEM;
  for (size_t c = 0; c < nc; c++) label[c] = M->material[c];
  const mx_mesh_view v = {.nnodes = nn, .xyz = M->xyz, .ncells = nc, .type = M->type,
                          .conn = M->conn};
  mx_boundary_faces bf;
  int st = mx_interface_faces_extract(&v, label, &bf);
  mx_free(label);
  MX_CHECK(st);
  /* the interface nodes (off the domain's boundary), compactly numbered */
  uint32_t *at = mx_alloc((nn + 1) * sizeof *at);
  if (!at) {
    mx_boundary_faces_free(&bf);
    return MX_ENOMEM;
  }
  for (size_t i = 0; i < nn; i++) at[i] = UINT32_MAX;
  size_t ni = 0;
  for (int q = 0; q < 2; q++) {
    const size_t n = q ? bf.nquad : bf.ntri;
    const int k = q ? 4 : 3;
    const uint32_t *f = q ? bf.quad : bf.tri;
    const int32_t *pair = q ? bf.quad_pair : bf.tri_pair;
    for (size_t i = 0; i < n; i++)
      for (int j = 0; pair[i] && j < k; j++) {
        const uint32_t w = f[(size_t)k * i + (size_t)j];
        if (at[w] == UINT32_MAX && !(m->states && m->states[w] == MX_NODE_OUTSIDE)) at[w] = 0;
      }
  }
  mx_boundary_faces_free(&bf);
  for (size_t i = 0; i < nn; i++)
    if (at[i] == 0) at[i] = (uint32_t)ni++;
    else at[i] = UINT32_MAX;
  /* their elements */
  uint64_t *off = mx_calloc((ni + 2) * sizeof *off);
  if (!off) {
    mx_free(at);
    return MX_ENOMEM;
  }
  for (size_t c = 0; c < nc; c++)
    for (int k = 0; k < mx_cell_nodes[M->type[c]]; k++) {
      const uint32_t j = at[M->conn[8 * c + k]];
      if (j != UINT32_MAX) off[j + 1]++;
    }
  for (size_t j = 0; j < ni; j++) off[j + 1] += off[j];
  uint32_t *inc = mx_alloc((off[ni] + 1) * sizeof *inc);
  uint64_t *fill = mx_alloc((ni + 1) * sizeof *fill);
  if (!inc || !fill) {
    mx_free(at), mx_free(off), mx_free(inc), mx_free(fill);
    return MX_ENOMEM;
  }
  memcpy(fill, off, ni * sizeof *fill);
  for (size_t c = 0; c < nc; c++)
    for (int k = 0; k < mx_cell_nodes[M->type[c]]; k++) {
      const uint32_t j = at[M->conn[8 * c + k]];
      if (j != UINT32_MAX) inc[fill[j]++] = (uint32_t)c;
    }
  mx_free(fill);
  const float worst = M->jens_min;
  size_t nm = 0;
  for (size_t w = 0; w < nn; w++) {
    const uint32_t j = at[w];
    if (j == UINT32_MAX) continue;
    double *x = M->xyz + 3 * w, x0[3], q[3];
    memcpy(x0, x, sizeof x0);
    mx_closest_point(&m->SI, x0, q, NULL, NULL);
    for (int attempt = 0; attempt < 2; attempt++) {
      for (int a = 0; a < 3; a++) x[a] = attempt ? 0.5 * (x0[a] + q[a]) : q[a];
      int ok = 1;
      for (uint64_t e = off[j]; e < off[j + 1] && ok; e++) {
        const uint32_t c = inc[e];
        double p[8][3];
        const int nv = mx_cell_nodes[M->type[c]];
        for (int k = 0; k < nv; k++)
          memcpy(p[k], M->xyz + 3 * (size_t)M->conn[8 * (size_t)c + k], sizeof p[k]);
        const double jn = mx_jens(M->type[c], (const double(*)[3])p);
        ok = jn >= fmin((double)M->jens[c], (double)worst);
      }
      if (!ok) continue;
      for (uint64_t e = off[j]; e < off[j + 1]; e++) { /* the new J_ENS */
        const uint32_t c = inc[e];
        double p[8][3];
        const int nv = mx_cell_nodes[M->type[c]];
        for (int k = 0; k < nv; k++)
          memcpy(p[k], M->xyz + 3 * (size_t)M->conn[8 * (size_t)c + k], sizeof p[k]);
        M->jens[c] = (float)mx_jens(M->type[c], (const double(*)[3])p);
      }
      if (attempt == 0) snapped[w] = MX_SNAPPED;
      nm++;
      goto next;
    }
    memcpy(x, x0, sizeof x0); /* neither: stays */
  next:;
  }
  mx_free(at);
  mx_free(off);
  mx_free(inc);
  *moved = nm;
  return MX_OK;
}
