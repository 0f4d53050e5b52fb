/* Several materials, first part (mesher/materials.h). The region of a
 * point is its nesting depth among the input's closed shells, which the
 * surface index built with every shell outward counts
 * (mx_surface_index_build_outward, mx_region_depth): 1 between the
 * outermost shell and the next, 2 inside two shells, ... and 0 outside
 * every shell. The elements take the region of their centroid; the
 * interfaces are then made of element faces (a staircase at the octree's
 * resolution), whose nodes the full stage moves onto the shells where the
 * elements around allow (snap_interfaces), and the elements whose corners
 * still lie in two regions (both inside the outermost shell) are counted:
 * those across an interface. Cutting them by the surface patterns, as the
 * outer boundary is, is the part still to come (issue 26). */
#include "mesher/materials.h"

#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "base/common.h"
#include "io/boundary_faces.h"
#include "kernels/boundary.h"
#include "kernels/mesh_edit.h"
#include "mesher/mesher_impl.h"
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

static int material_numbers(mx_mesher *m, int deepest);
/* The nodes of the faces between two materials moved onto the shells: each
 * to its closest point, else half-way, when every element around it keeps
 * a J_ENS no lower than its own or the mesh's worst before (so the worst
 * never drops). In node order, one node after the other (deterministic;
 * work proportional to the interfaces). snapped[v] = SNAPPED for the nodes
 * moved to the shells. A staircase's nodes brought to the interface, as the
 * node-shifting of geometry-adapted hexahedral meshes. */
enum { SNAPPED = 2 };

static int snap_interfaces(mx_mesher *m, uint8_t *snapped, size_t *moved) {
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
      if (attempt == 0) snapped[w] = SNAPPED;
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


/* The region of each element and the elements across an interface. An
 * element of a leaf that meets no triangle lies in one region, its leaf's
 * (one query per leaf); elsewhere the regions of the element's nodes (one
 * query per node) give it when they agree, and its centroid when they do
 * not (those with nodes in two regions inside the outermost shell lie
 * across an interface). Nodes on the domain's boundary (full stage) tell
 * no region and are left out. With no shell
 * nested in another, the full stage's elements all lie in region 1. */
int mx_label_materials(mx_mesher *m) {
  enum { NONE = UINT16_MAX }; /* a node on the domain's boundary */
  mx_mesh *M = &m->M;
  if (!m->have_index) MX_CHECK(mx_mesher_index(m));
  const double t0 = mx_wtime();
  mx_free(M->material);
  M->material = mx_alloc((M->ncells + 1) * sizeof *M->material);
  if (!M->material) return MX_ENOMEM;
  const mx_surface_index *S = &m->SI;
  const size_t nc = M->ncells, nn = M->nnodes;
  if (m->mesh_stage == MX_STAGE_FULL && !mx_surface_index_nested(S)) {
    MX_CHECK(material_numbers(m, 1));
    for (size_t c = 0; c < nc; c++) M->material[c] = (uint16_t)m->depth_material[1];
    m->nmaterials = 1;
    m->rec->S.nmaterials = 1;
    m->rec->S.materials_across = 0;
    m->rec->S.t_materials = mx_wtime() - t0;
    return MX_OK;
  }
  const mx_octree *O = &m->B.tree.oct;
  int32_t *leaf_depth = mx_alloc((m->nleaves + 1) * sizeof *leaf_depth);
  uint16_t *depth = mx_alloc((nn + 1) * sizeof *depth);
  uint8_t *need = mx_calloc(nn + 1);
  if (!leaf_depth || !depth || !need) {
    mx_free(leaf_depth);
    mx_free(depth);
    mx_free(need);
    return MX_ENOMEM;
  }
  for (size_t l = 0; l < m->nleaves; l++) leaf_depth[l] = -1;
  const uint8_t *states = m->states;
  /* the nodes to locate: those of the elements in leaves meeting triangles */
#pragma omp parallel for schedule(static)
  for (size_t c = 0; c < nc; c++) {
    if (O->tri_cnt[m->leaves[M->leaf[c]]] == 0) continue;
    for (int k = 0; k < mx_cell_nodes[M->type[c]]; k++)
      __atomic_store_n(&need[M->conn[8 * c + k]], 1, __ATOMIC_RELAXED);
  }
#pragma omp parallel for schedule(dynamic, 1024)
  for (size_t v = 0; v < nn; v++) {
    int d = NONE;
    if (need[v] && !(states && states[v] == MX_NODE_OUTSIDE))
      d = mx_region_depth(S, M->xyz + 3 * v);
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
    if (O->tri_cnt[m->leaves[leaf]] == 0) { /* one region: the leaf's */
      d = __atomic_load_n(&leaf_depth[leaf], __ATOMIC_RELAXED);
      if (d < 0) {
        d = mx_region_depth(S, p);
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
      d = hi == lo ? hi : mx_region_depth(S, p);
    }
    if (d > UINT16_MAX - 1) d = UINT16_MAX - 1;
    M->material[c] = (uint16_t)d;
    if (d > deepest) deepest = d;
  }
  mx_free(leaf_depth);
  int st = material_numbers(m, deepest);
  for (size_t c = 0; !st && c < nc; c++) /* the numbers the user gave */
    if (M->material[c] >= 1 && M->material[c] <= 64)
      M->material[c] = (uint16_t)m->depth_material[M->material[c]];
  /* the full stage: the staircase's nodes onto the interfaces, where the
   * elements allow; they then tell no side */
  size_t snapped_nodes = 0;
  if (!st && m->mesh_stage == MX_STAGE_FULL) {
    st = snap_interfaces(m, need, &snapped_nodes);
    if (!st) mx_mesh_summarize(M);
  }
  /* the elements across an interface: nodes (not on a shell) in two
   * regions inside the outermost shell */
  size_t across = 0;
#pragma omp parallel for schedule(static) reduction(+ : across)
  for (size_t c = 0; c < nc; c++) {
    if (st || O->tri_cnt[m->leaves[M->leaf[c]]] == 0) continue;
    const uint32_t *row = M->conn + 8 * c;
    int lo = INT_MAX, hi = -1;
    for (int k = 0; k < mx_cell_nodes[M->type[c]]; k++) {
      const uint32_t w = row[k];
      if (depth[w] == NONE || need[w] == SNAPPED) continue;
      lo = depth[w] < lo ? depth[w] : lo;
      hi = depth[w] > hi ? depth[w] : hi;
    }
    across += hi > lo && lo >= 1;
  }
  mx_free(depth);
  mx_free(need);
  MX_CHECK(st);
  m->rec->S.materials_snapped = snapped_nodes;
  m->nmaterials = deepest;
  m->rec->S.nmaterials = deepest;
  m->rec->S.materials_across = across;
  m->rec->S.t_materials = mx_wtime() - t0;
  if (across)
    mx_warning(NULL, 0, "materials: %zu element(s) lie across an interface between two "
                        "materials (each takes the material of its centroid): in this version "
                        "the interfaces follow element faces, whose nodes move onto the input "
                        "surfaces only where the elements allow; finer levels (-s) shrink it",
               across);
  return MX_OK;
}

int mx_material_name(const mx_mesher *m, int d, char *buf, size_t n) {
  if (d >= 1 && d <= 64 && m->depth_material_name[d]) {
    snprintf(buf, n, "%s", m->depth_material_name[d]);
    return MX_OK;
  }
  snprintf(buf, n, "material %d", d >= 1 && d <= 64 ? m->depth_material[d] : d);
  const mx_surface_index *S = &m->SI;
  if (!m->have_index || d < 1 || !S->shell_depth) return MX_OK;
  /* the input files with a shell at depth d - 1; each file's depths */
  int file = -1, several = 0;
  for (uint32_t i = 0; i < S->nt && !several; i++) {
    if (S->shell_depth[S->shell_of[i]] != (uint32_t)(d - 1)) continue;
    const int f = m->soup.shell[S->tri_id[i]];
    if (file >= 0 && f != file) several = 1;
    file = f;
  }
  if (file < 0 || several || file >= m->ndomain) return MX_OK;
  for (uint32_t i = 0; i < S->nt; i++) /* that file's shells all at depth d - 1 */
    if (m->soup.shell[S->tri_id[i]] == file &&
        S->shell_depth[S->shell_of[i]] != (uint32_t)(d - 1))
      return MX_OK;
  const char *path = m->domain_name[file];
  const char *slash = strrchr(path, '/');
  const char *base = slash ? slash + 1 : path;
  while (*base == '-') base++; /* "--demo" */
  const char *dot = strrchr(base, '.');
  const int len = dot && dot > base ? (int)(dot - base) : (int)strlen(base);
  snprintf(buf, n, "%.*s", len, base);
  return MX_OK;
}

int mx_mesher_set_material(mx_mesher *m, int input, int number, const char *name) {
  mx_call c;
  mx_call_begin(m, &c);
  int st = MX_OK;
  if (input < 0 || input >= m->ndomain) {
    mx_error(NULL, 0, "material: no input %d (%d surface(s) added)", input, m->ndomain);
    st = MX_EINPUT;
  } else if (number < 1 || number > 65535) {
    mx_error(NULL, 0, "material: number %d for %s out of 1 .. 65535", number,
             m->domain_name[input]);
    st = MX_EINPUT;
  }
  char *copy = NULL;
  if (!st && name && !(copy = mx_strdup(name))) st = MX_ENOMEM;
  if (!st) {
    mx_free(m->input_material_name[input]);
    m->input_material_name[input] = copy;
    m->input_material[input] = number;
  }
  return mx_call_end(m, &c, st);
}

/* The numbers and names of the materials by depth (m->depth_material*):
 * the user's for the inputs given one, the depth otherwise. MX_EINPUT when
 * an input's shells nest at several depths, two inputs at one depth are
 * given different numbers, or two materials end with one number. */
static int material_numbers(mx_mesher *m, int deepest) {
  const mx_surface_index *S = &m->SI;
  for (int d = 0; d <= 64; d++) {
    m->depth_material[d] = d;
    m->depth_material_name[d] = NULL;
  }
  for (int k = 0; k < m->ndomain && k < 64; k++) {
    if (!m->input_material[k]) continue;
    int depth = -1;
    for (uint32_t i = 0; i < S->nt; i++) {
      if (m->soup.shell[S->tri_id[i]] != k) continue;
      const int e = (int)S->shell_depth[S->shell_of[i]];
      if (depth >= 0 && e != depth) {
        mx_error(m->domain_name[k], 0, "material %d: the shells of this input nest at "
                                       "several depths (%d and %d): the material inside it is "
                                       "not one region", m->input_material[k], depth, e);
        return MX_EINPUT;
      }
      depth = e;
    }
    const int d = depth + 1;
    if (d < 1 || d > 64) continue;
    if (m->depth_material[d] != d && m->depth_material[d] != m->input_material[k]) {
      mx_error(m->domain_name[k], 0, "material %d: this input bounds the same region depth as "
                                     "another input given material %d (regions at one depth "
                                     "are one material in this version)",
               m->input_material[k], m->depth_material[d]);
      return MX_EINPUT;
    }
    m->depth_material[d] = m->input_material[k];
    if (m->input_material_name[k]) m->depth_material_name[d] = m->input_material_name[k];
  }
  for (int a = 1; a <= deepest && a <= 64; a++)
    for (int b = a + 1; b <= deepest && b <= 64; b++)
      if (m->depth_material[a] == m->depth_material[b]) {
        mx_error(NULL, 0, "materials: the regions at depths %d and %d are both numbered %d; "
                          "give each its own number", a, b, m->depth_material[a]);
        return MX_EINPUT;
      }
  return MX_OK;
}

double mx_materials_domain_volume(const mx_mesher *m, double *area) {
  const mx_surface_index *S = &m->SI;
  double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
  for (size_t i = 0; i < 9 * (size_t)S->nt; i++) {
    lo[i % 3] = fmin(lo[i % 3], S->tv[i]);
    hi[i % 3] = fmax(hi[i % 3], S->tv[i]);
  }
  double o[3], v = 0.0, a = 0.0;
  for (int k = 0; k < 3; k++) o[k] = 0.5 * (lo[k] + hi[k]);
  for (uint32_t i = 0; i < S->nt; i++) {
    if (S->shell_depth && S->shell_depth[S->shell_of[i]] != 0) continue;
    const double *t = S->tv + 9 * (size_t)i;
    double p[3], q[3], r[3];
    for (int k = 0; k < 3; k++) p[k] = t[k] - o[k], q[k] = t[3 + k] - o[k], r[k] = t[6 + k] - o[k];
    v += S->tsign[i] * (p[0] * (q[1] * r[2] - q[2] * r[1]) - p[1] * (q[0] * r[2] - q[2] * r[0]) +
                        p[2] * (q[0] * r[1] - q[1] * r[0])) / 6.0;
    const double u[3] = {q[0] - p[0], q[1] - p[1], q[2] - p[2]};
    const double w[3] = {r[0] - p[0], r[1] - p[1], r[2] - p[2]};
    const double c[3] = {u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2],
                         u[0] * w[1] - u[1] * w[0]};
    a += 0.5 * sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
  }
  if (area) *area = a;
  return fabs(v);
}
