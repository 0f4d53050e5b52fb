/* Several materials, first part (mesher/materials.h). The region of a
 * point is its nesting depth among the input's closed shells, which the
 * surface index built with every shell outward counts
 * (mx_surface_index_build_outward, mx_region_depth): 1 between the
 * outermost shell and the next, 2 inside two shells, ... and 0 outside
 * every shell. The elements take the region of their centroid; the
 * interfaces are then made of element faces (a staircase at the octree's
 * resolution, which a later version will move onto the input surfaces),
 * and the elements whose corners lie in two regions (both inside the
 * outermost shell) are counted: those across an interface. */
#include "mesher/materials.h"

#include <limits.h>

#include "base/common.h"
#include "kernels/boundary.h"
#include "mesher/pipeline.h"
#include "soa/mesh.h"

int mx_materials_allowed(const mx_mesher *m, const char *what) {
  if (!m->p.materials) return MX_OK;
  if (m->p.repair_input) {
    mx_error(NULL, 0, "materials: not with repair_input (--repair-input): the regions come "
                      "from closed shells that nest");
    return MX_EINPUT;
  }
  if (what) {
    mx_error(NULL, 0, "materials (--materials): %s is not offered yet with several materials "
                      "(the restart file does not keep them)", what);
    return MX_EINPUT;
  }
  return MX_OK;
}

int mx_label_materials(mx_mesher *m) {
  mx_mesh *M = &m->M;
  if (!m->have_index) MX_CHECK(mx_mesher_index(m));
  mx_free(M->material);
  M->material = mx_alloc((M->ncells + 1) * sizeof *M->material);
  if (!M->material) return MX_ENOMEM;
  const mx_surface_index *S = &m->SI;
  int deepest = 0;
#pragma omp parallel for schedule(dynamic, 1024) reduction(max : deepest)
  for (size_t c = 0; c < M->ncells; c++) {
    const int nv = mx_cell_nodes[M->type[c]];
    const uint32_t *row = M->conn + 8 * c;
    double p[3] = {0, 0, 0};
    for (int k = 0; k < nv; k++)
      for (int a = 0; a < 3; a++) p[a] += M->xyz[3 * (size_t)row[k] + a];
    for (int a = 0; a < 3; a++) p[a] /= nv;
    int d = mx_region_depth(S, p);
    if (d > UINT16_MAX - 1) d = UINT16_MAX - 1;
    M->material[c] = (uint16_t)d;
    if (d > deepest) deepest = d;
  }
  m->nmaterials = deepest;
  /* the elements across an interface: corners in two regions inside the
   * outermost shell (a node on the domain's boundary, or outside it, has
   * no inner region to tell) */
  const size_t nn = M->nnodes;
  uint16_t *depth = mx_alloc((nn + 1) * sizeof *depth);
  if (!depth) return MX_ENOMEM;
  const uint8_t *states = m->states;
#pragma omp parallel for schedule(dynamic, 1024)
  for (size_t v = 0; v < nn; v++) {
    int d = states && states[v] == MX_NODE_OUTSIDE ? 0 : mx_region_depth(S, M->xyz + 3 * v);
    depth[v] = (uint16_t)(d > UINT16_MAX ? UINT16_MAX : d);
  }
  size_t across = 0;
#pragma omp parallel for schedule(static) reduction(+ : across)
  for (size_t c = 0; c < M->ncells; c++) {
    const uint32_t *row = M->conn + 8 * c;
    int lo = UINT16_MAX, hi = 0;
    for (int k = 0; k < mx_cell_nodes[M->type[c]]; k++) {
      const int d = depth[row[k]];
      if (d == 0) continue;
      lo = d < lo ? d : lo;
      hi = d > hi ? d : hi;
    }
    across += hi > lo;
  }
  mx_free(depth);
  m->rec->S.nmaterials = deepest;
  m->rec->S.materials_across = across;
  if (across)
    mx_warning(NULL, 0, "materials: %zu element(s) lie across an interface between two "
                        "materials (each takes the material of its centroid): in this version "
                        "the interfaces follow element faces, a staircase at the octree's "
                        "resolution, not yet the input surfaces; finer levels (-s) shrink it",
               across);
  return MX_OK;
}
