/* Several materials in the 2D mesher (mesher/mesher2d.h; issue 26): with
 * params.materials the loops nested in the outer ones are interfaces, not
 * holes. The regions of the domain's loops (quad/qregions.c) give the
 * outer loops, the domain the quadtree and the boundary step see, and the
 * interfaces, which refine the quadtree as the domain's polylines do (a
 * drawing at the surface level) and along which the boundary step's mesh
 * is cleaved (quad/qcleave.c). Each cell's region (its nesting depth) is
 * then its material, numbered and named by the user by depth or by
 * default ("material D", numbered D). The independent check runs on the
 * whole mesh against the outer loops, and on each material's cells
 * against that material's own loops (the outer ones around it, the inner
 * ones as its holes): conforming, every boundary edge (interfaces
 * included) on its loops, their features as nodes, the region's topology
 * and area. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "base/common.h"
#include "mesher/mesher2d.h"
#include "mesher/qmesh_output.h"

void mx_mesher2d_materials_free(mx_mesher2d *m) {
  mx_qregions_free(&m->nest);
  mx_poly_index_free(&m->outer_index);
  mx_poly_free(&m->outer);
  mx_poly_free(&m->interfaces);
  mx_free(m->material);
  mx_free(m->mat_report);
  m->material = NULL;
  m->mat_report = NULL;
  m->mat_ready = 0;
  m->nmaterials = 0;
}

void mx_mesher2d_materials_names_free(mx_mesher2d *m) {
  for (int d = 0; d <= MX_MAT2D_MAX; d++) {
    mx_free(m->mat_name[d]);
    m->mat_name[d] = NULL;
    m->mat_number[d] = 0;
  }
}

int mx_mesher2d_materials_prepare(mx_mesher2d *m) {
  if (m->mat_ready) return MX_OK;
  MX_CHECK(mx_qregions_build(&m->domain, &m->nest));
  const uint32_t deepest = m->nest.deepest;
  if (deepest > MX_MAT2D_MAX) {
    mx_error(m->domain.path, 0, "materials: the loops nest %u deep: at most %d materials",
             deepest, MX_MAT2D_MAX);
    mx_qregions_free(&m->nest);
    return MX_EINPUT;
  }
  int st = MX_OK;
  if (deepest > 1) {
    st = mx_qregions_select(&m->nest, 0, 0, &m->outer);
    if (!st) st = mx_poly_index_build(&m->outer, &m->outer_index);
    if (!st) st = mx_qregions_select(&m->nest, 1, deepest - 1, &m->interfaces);
  }
  if (st) {
    mx_mesher2d_materials_free(m);
    return st;
  }
  m->mat_ready = 1;
  return MX_OK;
}

int mx_mesher2d_nested(const mx_mesher2d *m) {
  return m->p.materials && m->mat_ready && m->nest.deepest > 1;
}

const mx_poly *mx_mesher2d_outer(const mx_mesher2d *m) {
  return mx_mesher2d_nested(m) ? &m->outer : &m->domain;
}

int mx_mesher2d_material_number(const mx_mesher2d *m, int d) {
  return d >= 1 && d <= MX_MAT2D_MAX && m->mat_number[d] ? m->mat_number[d] : d;
}

void mx_mesher2d_material_name(const mx_mesher2d *m, int d, char *buf, size_t n) {
  if (d >= 1 && d <= MX_MAT2D_MAX && m->mat_name[d]) snprintf(buf, n, "%s", m->mat_name[d]);
  else snprintf(buf, n, "material %d", mx_mesher2d_material_number(m, d));
}

int mx_mesher2d_set_material_(mx_mesher2d *m, int depth, int number, const char *name) {
  if (depth < 1 || depth > MX_MAT2D_MAX) {
    mx_error(NULL, 0, "material: depth %d out of 1 .. %d (1: the region inside the outer "
                      "loops, 2: inside the loops nested in them, ...)", depth, MX_MAT2D_MAX);
    return MX_EINPUT;
  }
  if (number < 1 || number > 65535) {
    mx_error(NULL, 0, "material: number %d for depth %d out of 1 .. 65535", number, depth);
    return MX_EINPUT;
  }
  char *copy = NULL;
  if (name && !(copy = mx_strdup(name))) return MX_ENOMEM;
  mx_free(m->mat_name[depth]);
  m->mat_name[depth] = copy;
  m->mat_number[depth] = number;
  return MX_OK;
}

/* Two regions given one number: refused when meshing. */
static int numbers_distinct(const mx_mesher2d *m) {
  for (int a = 1; a <= m->nmaterials; a++)
    for (int b = a + 1; b <= m->nmaterials; b++)
      if (mx_mesher2d_material_number(m, a) == mx_mesher2d_material_number(m, b)) {
        mx_error(NULL, 0, "materials: the regions at depths %d and %d are both numbered %d; "
                          "give each its own number", a, b, mx_mesher2d_material_number(m, a));
        return MX_EINPUT;
      }
  return MX_OK;
}

int mx_mesher2d_materials_label(mx_mesher2d *m) {
  mx_free(m->material);
  m->material = NULL;
  memset(&m->cs, 0, sizeof m->cs);
  const double t = mx_wtime();
  uint16_t *region = NULL;
  if (mx_mesher2d_nested(m)) {
    MX_CHECK(mx_qcleave(&m->M, &m->nest, &region, &m->cs));
  } else {
    region = mx_alloc((m->M.ncells + 1) * sizeof *region);
    if (!region) return MX_ENOMEM;
    for (size_t c = 0; c < m->M.ncells; c++) region[c] = 1;
  }
  int deepest = 1;
  for (size_t c = 0; c < m->M.ncells; c++) deepest = region[c] > deepest ? region[c] : deepest;
  m->nmaterials = deepest;
  m->material = region; /* depths now, numbers below */
  m->t_materials = mx_wtime() - t;
  MX_CHECK(numbers_distinct(m));
  int num[MX_MAT2D_MAX + 1];
  for (int d = 0; d <= MX_MAT2D_MAX; d++) num[d] = mx_mesher2d_material_number(m, d);
  for (size_t c = 0; c < m->M.ncells; c++)
    if (region[c] <= MX_MAT2D_MAX) region[c] = (uint16_t)num[region[c]];
  return MX_OK;
}

int mx_mesher2d_material_depth(const mx_mesher2d *m, int number) {
  for (int d = 1; d <= m->nmaterials; d++)
    if (mx_mesher2d_material_number(m, d) == number) return d;
  return 0;
}

/* The cells of material depth d as a mesh of their own (the nodes shared). */
static int material_cells(const mx_mesher2d *m, int d, mx_qmesh *S) {
  const mx_qmesh *M = &m->M;
  const int num = mx_mesher2d_material_number(m, d);
  size_t k = 0;
  for (size_t c = 0; c < M->ncells; c++) k += m->material[c] == num;
  memset(S, 0, sizeof *S);
  S->type = mx_alloc(k + 1);
  S->conn = mx_alloc((4 * k + 1) * sizeof *S->conn);
  if (!S->type || !S->conn) {
    mx_free(S->type), mx_free(S->conn);
    return MX_ENOMEM;
  }
  k = 0;
  for (size_t c = 0; c < M->ncells; c++) {
    if (m->material[c] != num) continue;
    S->type[k] = M->type[c];
    memcpy(S->conn + 4 * k, M->conn + 4 * c, 4 * sizeof *S->conn);
    k++;
  }
  S->ncells = k;
  S->nnodes = M->nnodes;
  S->xy = M->xy;
  return MX_OK;
}

int mx_mesher2d_materials_check(mx_mesher2d *m, double tol) {
  const int n = m->nmaterials;
  mx_free(m->mat_report);
  m->mat_report = mx_calloc((size_t)(n + 1) * sizeof *m->mat_report);
  if (!m->mat_report) return MX_ENOMEM;
  if (!mx_mesher2d_nested(m)) { /* one material: the whole mesh's check */
    m->mat_report[1].cr = m->cr;
    m->mat_report[1].cells = m->M.ncells;
    m->mat_report[1].area_tol = m->area_tol;
    return MX_OK;
  }
  const char *name = m->domain.path;
  for (int d = 1; d <= n; d++) {
    mx_mat2d_report *R = &m->mat_report[d];
    mx_poly P;
    MX_CHECK(mx_qregions_select(&m->nest, (uint32_t)d - 1, (uint32_t)d, &P));
    mx_qmesh S;
    int st = material_cells(m, d, &S);
    if (!st) {
      R->cells = S.ncells;
      st = S.ncells ? mx_qmesh_check(&S, &P, tol, &R->cr) : MX_OK;
      mx_free(S.type), mx_free(S.conn);
    }
    if (!st) R->area_tol = mx_qarea_tolerance(&P, &R->cr, R->cells);
    mx_poly_free(&P);
    MX_CHECK(st);
  }
  for (int d = 1; d <= n; d++) {
    const mx_mat2d_report *R = &m->mat_report[d];
    const mx_qcheck_report *c = &R->cr;
    char mn[128];
    mx_mesher2d_material_name(m, d, mn, sizeof mn);
    if (!R->cells) {
      mx_error(name, 0, "materials: no cell of %s (depth %d): the levels are too coarse for it",
               mn, d);
      return MX_EINVALID;
    }
    if (c->bad_edges || c->hanging || c->inverted) {
      mx_error(name, 0, "materials: the cells of %s are not a valid mesh: %zu bad edge(s), %zu "
               "hanging node(s), %zu inverted cell(s)", mn, c->bad_edges, c->hanging, c->inverted);
      return MX_EINVALID;
    }
    if (c->off_boundary || c->missing_features) {
      mx_error(name, 0, "materials: the boundary of %s is off its loops (interfaces included): "
               "%zu boundary node(s) off, %zu feature(s) not a node", mn, c->off_boundary,
               c->missing_features);
      return MX_EINVALID;
    }
    if (c->euler != c->domain_euler) {
      mx_error(name, 0, "materials: %s has another topology than its region: %ld component(s) "
               "minus hole(s) against %ld: the levels are too coarse there", mn, c->euler,
               c->domain_euler);
      return MX_EINVALID;
    }
    if (!(c->area_error <= R->area_tol)) {
      mx_error(name, 0, "materials: %s covers %.4g against its region's %.4g (%.1f%% off; "
               "tolerance %.1f%%)", mn, c->area, c->domain_area, 100.0 * c->area_error,
               100.0 * R->area_tol);
      return MX_EINVALID;
    }
  }
  if (m->cs.across) {
    mx_error(name, 0, "materials: %zu cell(s) have nodes in two regions (an edge crossing an "
                      "interface twice): the levels are too coarse there", m->cs.across);
    return MX_EINVALID;
  }
  return MX_OK;
}

int mx_mesher2d_write_materials(const mx_mesher2d *m, const char *path, int ascii,
                                const double *target_size) {
  const size_t nc = m->M.ncells;
  const int nb = m->nmaterials;
  int32_t *mat = mx_alloc((nc + 1) * sizeof *mat), *body = mx_alloc((nc + 1) * sizeof *body);
  int32_t phys[MX_MAT2D_MAX];
  char names[MX_MAT2D_MAX][128];
  const char *np[MX_MAT2D_MAX];
  if (!mat || !body) {
    mx_free(mat), mx_free(body);
    return MX_ENOMEM;
  }
  for (int d = 1; d <= nb; d++) {
    phys[d - 1] = mx_mesher2d_material_number(m, d);
    mx_mesher2d_material_name(m, d, names[d - 1], sizeof names[d - 1]);
    np[d - 1] = names[d - 1];
  }
  for (size_t c = 0; c < nc; c++) {
    mat[c] = m->material[c];
    int b = 1;
    while (b < nb && phys[b - 1] != mat[c]) b++;
    body[c] = b;
  }
  const mx_qmesh_tags T = {mat, body, nb, np, phys};
  const int st = mx_write_qmesh_tagged(path, &m->M, ascii, &T, target_size);
  mx_free(mat), mx_free(body);
  return st;
}
