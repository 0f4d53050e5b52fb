/* Several materials (mesher/materials.h). The region of a point is its
 * nesting depth among the input's closed shells, which the surface index
 * built with every shell outward counts (mx_surface_index_build_outward,
 * mx_region_depth): 1 between the outermost shell and the next, 2 inside
 * two shells, ... and 0 outside every shell. The full stage has cleaved
 * the mesh along every interface (kernels/interfaces.h), so the nodes of
 * an element that are not on a shell lie in one region, which is the
 * element's; here each element gets it, from fresh queries (its centroid's
 * when all its nodes are on shells), and the elements whose nodes still lie
 * in two regions are counted: those across an interface (none after the
 * full stage unless the untangling pulled a node across; the transition
 * stage's mesh, not cleaved, has them). */
#include "mesher/materials.h"

#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "base/common.h"
#include "kernels/boundary.h"
#include "kernels/mesh_edit.h"
#include "mesher/pipeline.h"
#include "soa/mesh.h"

int mx_materials_allowed(const mx_mesher *m, const char *what) {
  if (!m->p.materials) return MX_OK;
  if (m->p.repair_input) {
    mx_error(NULL, 0, "materials: not with repair_input (--repair-input): the regions come "
                      "from closed shells that nest");
    return MX_EINPUT;
  }
  (void)what; /* restart files and re-meshing: the materials come from the inputs */
  return MX_OK;
}

/* The region of each element and the elements across an interface. An
 * element of a leaf that meets no triangle lies in one region, its leaf's
 * (one query per leaf); elsewhere the regions of the element's nodes (one
 * query per node) give it when they agree, and its centroid when they do
 * not (those with nodes in two regions inside the outermost shell lie
 * across an interface). Nodes on the domain's boundary (full stage) tell
 * no region and are left out. With no shell
 * nested in another, the full stage's elements all lie in region 1. */
/* The region index of point p: its piece's (0 outside every piece). */
static int region_at(const mx_mesher *m, const double p[3]) {
  const int q = mx_interfaces_piece(&m->IF, p);
  return q ? m->IF.region[q - 1] : 0;
}

int mx_material_depths(mx_mesher *m, mx_mesh *M, const uint32_t *leaves, size_t nleaves,
                       const uint8_t *states, int stage, int *deepest_out, size_t *across_out,
                       double where[3]) {
  enum { NONE = UINT16_MAX }; /* a node on the domain's boundary */
  if (!m->have_index) MX_CHECK(mx_mesher_index(m));
  *deepest_out = 0;
  *across_out = 0;
  mx_free(M->material);
  M->material = mx_alloc((M->ncells + 1) * sizeof *M->material);
  if (!M->material) return MX_ENOMEM;
  const size_t nc = M->ncells, nn = M->nnodes;
  if (m->IF.nregions > 64) {
    mx_error(NULL, 0, "materials: %d regions (depths and input files), at most 64 in this "
                      "version", m->IF.nregions);
    return MX_EINPUT;
  }
  if (stage == MX_STAGE_FULL && m->IF.nregions <= 1) {
    for (size_t c = 0; c < nc; c++) M->material[c] = 1;
    *deepest_out = 1;
    return MX_OK;
  }
  const mx_octree *O = &m->B.tree.oct;
  int32_t *leaf_depth = mx_alloc((nleaves + 1) * sizeof *leaf_depth);
  uint16_t *depth = mx_alloc((nn + 1) * sizeof *depth);
  uint8_t *need = mx_calloc(nn + 1);
  if (!leaf_depth || !depth || !need) {
    mx_free(leaf_depth);
    mx_free(depth);
    mx_free(need);
    return MX_ENOMEM;
  }
  for (size_t l = 0; l < nleaves; l++) leaf_depth[l] = -1;
  /* the nodes to locate: those of the elements in leaves meeting triangles */
#pragma omp parallel for schedule(static)
  for (size_t c = 0; c < nc; c++) {
    if (O->tri_cnt[leaves[M->leaf[c]]] == 0) continue;
    for (int k = 0; k < mx_cell_nodes[M->type[c]]; k++)
      __atomic_store_n(&need[M->conn[8 * c + k]], 1, __ATOMIC_RELAXED);
  }
#pragma omp parallel for schedule(dynamic, 1024)
  for (size_t v = 0; v < nn; v++) {
    int d = NONE;
    if (need[v] && !(states && states[v] == MX_NODE_OUTSIDE))
      d = region_at(m, M->xyz + 3 * v);
    depth[v] = (uint16_t)(d > NONE ? NONE : d);
  }
  int deepest = 0;
#pragma omp parallel for schedule(dynamic, 1024) reduction(max : deepest)
  for (size_t c = 0; c < nc; c++) {
    const int nv = mx_cell_nodes[M->type[c]];
    const uint32_t *row = M->conn + 8 * c;
    const uint32_t leaf = M->leaf[c];
    double p[3] = {0, 0, 0};
    for (int k = 0; k < nv; k++)
      for (int a = 0; a < 3; a++) p[a] += M->xyz[3 * (size_t)row[k] + a] / nv;
    int d;
    if (O->tri_cnt[leaves[leaf]] == 0) { /* one region: the leaf's */
      d = __atomic_load_n(&leaf_depth[leaf], __ATOMIC_RELAXED);
      if (d < 0) {
        d = region_at(m, p);
        __atomic_store_n(&leaf_depth[leaf], d, __ATOMIC_RELAXED);
      }
    } else {
      int lo = INT_MAX, hi = -1;
      for (int k = 0; k < nv; k++) {
        const int g = depth[row[k]];
        if (g == NONE) continue; /* on the boundary */
        lo = g < lo ? g : lo;
        hi = g > hi ? g : hi;
      }
      d = hi == lo ? hi : region_at(m, p);
      /* the full stage's elements are the domain's: a few nodes the shrink
       * left just outside the outermost shell do not make one outside */
      if (d < 1 && stage == MX_STAGE_FULL) d = hi >= 1 ? hi : 1;
    }
    if (d > UINT16_MAX - 1) d = UINT16_MAX - 1;
    if (d < 1 && stage == MX_STAGE_FULL) d = 1;
    M->material[c] = (uint16_t)d;
    if (d > deepest) deepest = d;
  }
  mx_free(leaf_depth);
  /* the elements across an interface: nodes (not on a shell) in two
   * regions inside the outermost shell */
  size_t across = 0, first = SIZE_MAX;
#pragma omp parallel for schedule(static) reduction(+ : across) reduction(min : first)
  for (size_t c = 0; c < nc; c++) {
    if (O->tri_cnt[leaves[M->leaf[c]]] == 0) continue;
    const uint32_t *row = M->conn + 8 * c;
    int lo = INT_MAX, hi = -1;
    for (int k = 0; k < mx_cell_nodes[M->type[c]]; k++) {
      const uint32_t w = row[k];
      if (depth[w] == NONE) continue;
      lo = depth[w] < lo ? depth[w] : lo;
      hi = depth[w] > hi ? depth[w] : hi;
    }
    if (hi > lo && lo >= 1) {
      across++;
      first = c < first ? c : first;
    }
  }
  if (where && across) { /* the first one's centroid */
    const int nv = mx_cell_nodes[M->type[first]];
    where[0] = where[1] = where[2] = 0.0;
    for (int k = 0; k < nv; k++)
      for (int a = 0; a < 3; a++) where[a] += M->xyz[3 * (size_t)M->conn[8 * first + k] + a] / nv;
  }
  mx_free(depth);
  mx_free(need);
  *deepest_out = deepest;
  *across_out = across;
  return MX_OK;
}

int mx_material_relabel(mx_mesher *m, mx_mesh *M, int deepest) {
  MX_CHECK(mx_material_numbers(m, deepest));
  for (size_t c = 0; c < M->ncells; c++) /* the numbers the user gave */
    if (M->material[c] >= 1 && M->material[c] <= 64)
      M->material[c] = (uint16_t)m->depth_material[M->material[c]];
  return MX_OK;
}

int mx_label_materials(mx_mesher *m) {
  const double t0 = mx_wtime();
  int deepest = 0;
  size_t across = 0;
  double *where = m->rec->S.materials_across_at;
  MX_CHECK(mx_material_depths(m, &m->M, m->leaves, m->nleaves, m->states, m->mesh_stage,
                              &deepest, &across, where));
  MX_CHECK(mx_material_relabel(m, &m->M, deepest));
  m->nmaterials = deepest;
  m->rec->S.nmaterials = deepest;
  m->rec->S.materials_across = across;
  m->rec->S.t_materials = mx_wtime() - t0;
  /* the full stage's are a defect (mx_mesh_finish) */
  if (across && m->mesh_stage != MX_STAGE_FULL)
    mx_warning(NULL, 0, "materials: %zu element(s) lie across an interface between two "
                        "materials (each takes the material of its centroid): the transition "
                        "stage does not cut the elements along the interfaces", across);
  return MX_OK;
}

int mx_materials_domain_volume(const mx_mesher *m, double *volume, double *area) {
  const mx_surface_index *S = &m->SI;
  double *vol = mx_alloc(2 * ((size_t)S->nshells + 1) * sizeof *vol);
  if (!vol) return MX_ENOMEM;
  double *ar = vol + S->nshells + 1, v = 0.0, a = 0.0;
  mx_surface_index_shell_volumes(S, vol, ar);
  for (uint32_t c = 0; c < S->nshells; c++)
    if (!S->shell_depth || S->shell_depth[c] == 0) v += vol[c], a += ar[c];
  mx_free(vol);
  *volume = fabs(v);
  *area = a;
  return MX_OK;
}
