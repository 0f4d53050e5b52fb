/* Several materials, first part (mesher/materials.h). The region of a
 * point is its nesting depth among the input's closed shells, which the
 * surface index built with every shell outward counts
 * (mx_surface_index_build_outward, mx_region_depth): 1 between the
 * outermost shell and the next, 2 inside two shells, ... and 0 outside
 * every shell. The transition stage's elements take the region of their
 * centroid; the interfaces are then made of element faces (a staircase
 * that the boundary stage will move onto the input surfaces). */
#include "mesher/materials.h"

#include <limits.h>

#include "base/common.h"
#include "mesher/pipeline.h"
#include "soa/mesh.h"

int mx_materials_allowed(const mx_mesher *m, const char *what) {
  if (!m->p.materials) return MX_OK;
  if (m->p.repair_input) {
    mx_error(NULL, 0, "materials: not with repair_input (--repair-input): the regions come "
                      "from closed shells that nest");
    return MX_EINPUT;
  }
  if (m->p.stage == MX_STAGE_FULL) {
    mx_error(NULL, 0, "materials (--materials): this version labels the elements of the "
                      "transition stage (--stage transition) by the region of their centroid; "
                      "interfaces moved onto the input surfaces (the full stage) are not built "
                      "yet");
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
  return MX_OK;
}
