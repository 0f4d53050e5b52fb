/* The mixed mesh as the writers see it (issue 11): cells in the written
 * order (grouped by type, io/cell_order.c), the boundary faces tagged by the
 * input file they lie on and the cells by body (kernels/boundary_tags.h),
 * the cell fields type, level, jens and body, the point fields boundary and
 * surface_tag. Tags need the full stage (a boundary on the input); the
 * transition stage's mesh is written plain. */
#include <stdio.h>
#include <string.h>

#include "kernels/boundary_tags.h"
#include "mesher/mesher_impl.h"
#include "soa/mesh.h"

/* The last path component, quotes turned into apostrophes (a name inside
 * the quotes of Gmsh's $PhysicalNames). */
static char *tag_name(const char *path, const char *suffix) {
  const char *slash = strrchr(path, '/');
  const char *base = slash ? slash + 1 : path;
  while (*base == '-') base++; /* "--demo" */
  const size_t n = strlen(base) + strlen(suffix) + 1;
  char *s = mx_alloc(n);
  if (!s) return NULL;
  snprintf(s, n, "%s%s", base, suffix);
  for (char *p = s; *p; p++)
    if (*p == '"' || (unsigned char)*p < 32) *p = '\'';
  return s;
}

typedef struct {
  mx_boundary_faces bf;
  int32_t *cell_body, *body_tag, *node_tag;
  int nbodies, ntags;
  char *names[2 * 66];
  const char *tag_names[66], *body_names[66];
} tags;

static void tags_free(tags *T) {
  mx_boundary_faces_free(&T->bf);
  mx_free(T->cell_body);
  mx_free(T->body_tag);
  mx_free(T->node_tag);
  for (size_t i = 0; i < sizeof T->names / sizeof *T->names; i++) mx_free(T->names[i]);
}

static int make_tags(mx_mesher *m, const mx_mesh_view *v, tags *T) {
  memset(T, 0, sizeof *T);
  const mx_mesh_out *M = &m->M;
  MX_CHECK(mx_boundary_faces_extract(v, &T->bf));
  T->cell_body = mx_alloc((M->ncells + 1) * sizeof *T->cell_body);
  T->node_tag = mx_alloc((M->nnodes + 1) * sizeof *T->node_tag);
  if (!T->cell_body || !T->node_tag) return MX_ENOMEM;
  if (!m->have_index) {
    MX_CHECK(mx_surface_index_build(&m->SI, &m->soup, 0, m->nt_domain));
    m->have_index = 1;
  }
  const mx_tag_inputs in = {&m->B, m->leaves, M->leaf, &m->soup, m->nt_domain,
                            m->ndomain, &m->SI, m->p.repair_input};
  size_t off = 0;
  MX_CHECK(mx_boundary_tags(v, &in, &T->bf, T->cell_body, &T->nbodies, &T->body_tag, &off));
  mx_boundary_node_tags(&T->bf, M->nnodes, T->node_tag);
  T->ntags = m->ndomain + (off > 0);
  int k = 0;
  for (int t = 0; t < m->ndomain; t++) T->tag_names[t] = T->names[k++] = tag_name(m->domain_name[t], "");
  if (off > 0) T->tag_names[m->ndomain] = T->names[k++] = tag_name("on no input", "");
  const int nb = T->nbodies < 64 ? T->nbodies : 64;
  for (int b = 0; b < nb; b++) {
    const int t = T->body_tag[b];
    char suffix[32];
    snprintf(suffix, sizeof suffix, " volume %d", b + 1);
    T->body_names[b] = T->names[k++] =
        tag_name(t >= 1 && t <= m->ndomain ? m->domain_name[t - 1] : "mesh", suffix);
  }
  for (int i = 0; i < k; i++)
    if (!T->names[i]) return MX_ENOMEM;
  if (T->nbodies > 64) T->nbodies = 0; /* named groups for 64 bodies at most */
  return MX_OK;
}

int mx_write_mixed(mx_mesher *m, const char *path, int ascii) {
  const mx_mesh_out *M = &m->M;
  int32_t *type = mx_alloc((M->ncells + 1) * sizeof *type);
  int32_t *bnd = mx_alloc((M->nnodes + 1) * sizeof *bnd);
  uint32_t *order = mx_alloc((M->ncells + 1) * sizeof *order);
  tags T;
  memset(&T, 0, sizeof T);
  int st = type && bnd && order ? MX_OK : MX_ENOMEM;
  if (!st) st = mx_cells_by_type(M->type, M->ncells, order, NULL);
  if (!st) {
#pragma omp parallel for schedule(static)
    for (size_t i = 0; i < M->ncells; i++) type[i] = M->type[i];
#pragma omp parallel for schedule(static)
    for (size_t i = 0; i < M->nnodes; i++) bnd[i] = m->bnd[i];
  }
  mx_field f[4] = {{"type", 0, type, NULL},
                   {"level", 0, M->level, NULL},
                   {"jens", 1, NULL, M->jens},
                   {"body", 0, NULL, NULL}};
  mx_field pf[2] = {{"boundary", 0, bnd, NULL}, {"surface_tag", 0, NULL, NULL}};
  mx_mesh_view v = {.nnodes = M->nnodes, .xyz = M->xyz, .ncells = M->ncells,
                    .type = M->type, .conn = M->conn, .ncell_fields = 3,
                    .cell_fields = f, .npoint_fields = 1, .point_fields = pf};
  const int tagged = m->mesh_stage == MX_STAGE_FULL && m->ndomain > 0;
  if (!st && tagged) st = make_tags(m, &v, &T);
  if (!st && tagged) {
    f[3].ivalues = T.cell_body;
    pf[1].ivalues = T.node_tag;
    v.ncell_fields = 4;
    v.npoint_fields = 2;
    v.bfaces = &T.bf;
    v.ntags = T.ntags;
    v.tag_names = T.tag_names;
    v.cell_body = T.cell_body;
    v.nbodies = T.nbodies;
    v.body_names = T.body_names;
  }
  v.order = order;
  if (!st) st = mx_write_mesh(path, &v, ascii);
  tags_free(&T);
  mx_free(order);
  mx_free(type);
  mx_free(bnd);
  return st;
}

int mx_mesher_written_order(const mx_mesher *m, uint32_t *order) {
  if (m->mesh_stage < MX_STAGE_TRANSITION) {
    mx_error(NULL, 0, "no mixed mesh: mesh first");
    return MX_EINPUT;
  }
  return mx_cells_by_type(m->M.type, m->M.ncells, order, NULL);
}
