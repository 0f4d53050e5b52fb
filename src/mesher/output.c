/* The mixed mesh as the writers see it (issue 11): cells in the written
 * order (grouped by type, io/cell_order.c), the boundary faces tagged by the
 * input file they lie on and the cells by body (kernels/boundary_tags.h),
 * the cell fields type, level, jens and body, the point fields boundary and
 * surface_tag. Tags need the full stage (a boundary on the input); the
 * transition stage's mesh is written plain. */
#include <math.h>
#include <stdio.h>
#include <string.h>
#include <strings.h>

#include "kernels/boundary.h"
#include "kernels/boundary_tags.h"
#include "mesher/materials.h"
#include "mesher/mesher_impl.h"
#include "mesher/pipeline.h"

#include "kernels/edges_lazy.h"
#include "soa/mesh.h"
#include "io/write_mesh.h"
#include "io/cell_order.h"

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
  int32_t *material; /* materials: the cell field (0: outside every shell) */
  int nbodies, ntags;
  char *names[2 * 66];
  const char *tag_names[66], *body_names[66];
  int32_t body_physical[66];
} tags;

static void tags_free(tags *T) {
  mx_boundary_faces_free(&T->bf);
  mx_free(T->cell_body);
  mx_free(T->body_tag);
  mx_free(T->node_tag);
  mx_free(T->material);
  for (size_t i = 0; i < sizeof T->names / sizeof *T->names; i++) mx_free(T->names[i]);
}

static int make_tags(const mx_mesher *m, const mx_mesh_view *v, tags *T) {
  memset(T, 0, sizeof *T);
  const mx_mesh *M = &m->M;
  /* The boundary faces lie on the surface: their nodes are outside nodes
   * (projected) or lattice nodes on the surface, which belong to leaves
   * meeting the input (a leaf meeting none has its closed box inside the
   * domain). Only faces with all nodes such are matched. */
  uint8_t *near = mx_calloc(M->nnodes + 1);
  if (!near) return MX_ENOMEM;
  const mx_octree *O = &m->B.tree.oct;
#pragma omp parallel for schedule(static)
  for (size_t c = 0; c < M->ncells; c++) {
    const uint32_t *row = M->conn + 8 * c;
    const int meets = O->tri_cnt[m->leaves[M->leaf[c]]] > 0;
    for (int k = 0; k < mx_cell_nodes[M->type[c]]; k++)
      if (meets || (m->states && m->states[row[k]] == MX_NODE_OUTSIDE))
        __atomic_store_n(&near[row[k]], 1, __ATOMIC_RELAXED);
  }
  int st = mx_boundary_faces_extract_masked(v, near, &T->bf);
  mx_free(near);
  MX_CHECK(st);
  T->cell_body = mx_alloc((M->ncells + 1) * sizeof *T->cell_body);
  T->node_tag = mx_alloc((M->nnodes + 1) * sizeof *T->node_tag);
  if (!T->cell_body || !T->node_tag) return MX_ENOMEM;
  if (!m->have_index) { /* every full-stage mesh has it (mesher/pipeline.h) */
    mx_error(NULL, 0, "internal: boundary tags without the surface index");
    return MX_EINTERNAL;
  }
  const mx_tag_inputs in = {&m->B.tree, m->leaves, M->leaf, &m->soup, m->nt_domain,
                            m->ndomain, &m->SI, m->p.repair_input,
                            m->have_mix ? m->tet_parent : NULL, &m->Mmix};
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

/* The n faces of k nodes each (nodes, src, tag, pair arrays) ordered by
 * tag, in their order within a tag (a counting sort), as the writers want
 * them (kernels/boundary_tags.h). MX_ENOMEM. */
static int faces_by_tag(size_t n, int k, uint32_t *nodes, uint64_t *src, int32_t *tag,
                        int32_t *pair, int ntags) {
  size_t *at = mx_calloc(((size_t)ntags + 2) * sizeof *at);
  uint32_t *nn = mx_alloc(((size_t)k * n + 1) * sizeof *nn);
  uint64_t *ns = mx_alloc((n + 1) * sizeof *ns);
  int32_t *nt = mx_alloc((n + 1) * sizeof *nt), *np = mx_alloc((n + 1) * sizeof *np);
  const int st = at && nn && ns && nt && np ? MX_OK : MX_ENOMEM;
  if (!st) {
    for (size_t i = 0; i < n; i++) at[tag[i] + 1]++;
    for (int t = 1; t <= ntags + 1; t++) at[t] += at[t - 1];
    for (size_t i = 0; i < n; i++) {
      const size_t j = at[tag[i]]++;
      memcpy(nn + (size_t)k * j, nodes + (size_t)k * i, (size_t)k * sizeof *nn);
      ns[j] = src[i];
      nt[j] = tag[i];
      np[j] = pair[i];
    }
    memcpy(nodes, nn, (size_t)k * n * sizeof *nn);
    memcpy(src, ns, n * sizeof *ns);
    memcpy(tag, nt, n * sizeof *nt);
    memcpy(pair, np, n * sizeof *np);
  }
  mx_free(at);
  mx_free(nn);
  mx_free(ns);
  mx_free(nt);
  mx_free(np);
  return st;
}

/* With several materials (issue 26; the transition stage's mesh, labelled
 * by mesher/materials.c): each material a body, numbered by its depth
 * (material 0, outside every shell, the body after the deepest, "outside
 * the inputs"); the faces tagged 1 ("boundary") on the mesh's boundary and
 * one tag per pair of materials ("interface A-B") on the faces between
 * them, each such face written once, oriented out of the lower material
 * (io/boundary_faces.h). More than 64 materials or 63 pairs: no groups
 * (the material field stays). */
static int make_material_tags(const mx_mesher *m, const mx_mesh_view *v, tags *T) {
  memset(T, 0, sizeof *T);
  const mx_mesh *M = &m->M;
  const int nmat = m->nmaterials;
  T->material = mx_alloc((M->ncells + 1) * sizeof *T->material);
  T->cell_body = mx_alloc((M->ncells + 1) * sizeof *T->cell_body);
  T->node_tag = mx_alloc((M->nnodes + 1) * sizeof *T->node_tag);
  if (!T->material || !T->cell_body || !T->node_tag) return MX_ENOMEM;
  /* a cell's body: its material's depth (materials hold the numbers the
   * user gave, mesher/materials.c), the outside after the deepest */
  int outside = 0;
  for (size_t c = 0; c < M->ncells; c++) {
    const int id = M->material[c];
    int b = nmat + 1;
    for (int d = 1; d <= nmat && d <= 64 && id; d++)
      if (m->depth_material[d] == id) b = d;
    T->material[c] = id;
    T->cell_body[c] = b;
    outside |= b == nmat + 1;
  }
  int32_t top = 0;
  for (int d = 1; d <= nmat && d <= 64; d++) {
    T->body_physical[d - 1] = m->depth_material[d];
    top = m->depth_material[d] > top ? m->depth_material[d] : top;
  }
  if (nmat < 65) T->body_physical[nmat] = top + 1; /* outside the inputs */
  mx_boundary_faces *bf = &T->bf;
  MX_CHECK(mx_interface_faces_extract(v, T->cell_body, bf));
  bf->tri_tag = mx_alloc((bf->ntri + 1) * sizeof *bf->tri_tag);
  bf->quad_tag = mx_alloc((bf->nquad + 1) * sizeof *bf->quad_tag);
  if (!bf->tri_tag || !bf->quad_tag) return MX_ENOMEM;
  /* the pairs met, in order of first face: tags 2, 3, ... */
  int32_t pa[63], pb[63];
  int npairs = 0, over = 0;
  for (int q = 0; q < 2; q++) {
    const size_t n = q ? bf->nquad : bf->ntri;
    const uint64_t *src = q ? bf->quad_src : bf->tri_src;
    const int32_t *pair = q ? bf->quad_pair : bf->tri_pair;
    int32_t *tag = q ? bf->quad_tag : bf->tri_tag;
    for (size_t i = 0; i < n; i++) {
      if (!pair[i]) {
        tag[i] = 1;
        continue;
      }
      const int32_t a = T->cell_body[src[i] >> 3], b = pair[i];
      int k = 0;
      while (k < npairs && !(pa[k] == a && pb[k] == b)) k++;
      if (k == npairs && npairs < 63) {
        pa[k] = a;
        pb[k] = b;
        npairs++;
      } else if (k == npairs) {
        over = 1;
        k = 62;
      }
      tag[i] = 2 + k;
    }
  }
  const int ntags = 1 + npairs;
  MX_CHECK(faces_by_tag(bf->ntri, 3, bf->tri, bf->tri_src, bf->tri_tag, bf->tri_pair, ntags));
  MX_CHECK(faces_by_tag(bf->nquad, 4, bf->quad, bf->quad_src, bf->quad_tag, bf->quad_pair,
                        ntags));
  mx_boundary_node_tags(bf, M->nnodes, T->node_tag);
  const int nb = nmat + outside;
  int k = 0;
  char name[256], na[120], nb2[120];
  for (int b = 1; b <= nb && b <= 64; b++) {
    if (b > nmat)
      snprintf(name, sizeof name, "outside the inputs");
    else
      MX_CHECK(mx_material_name(m, b, name, sizeof name));
    T->body_names[b - 1] = T->names[k++] = tag_name(name, "");
  }
  T->tag_names[0] = T->names[k++] = tag_name("boundary", "");
  for (int p = 0; p < npairs; p++) {
    if (pa[p] > nmat) snprintf(na, sizeof na, "outside");
    else MX_CHECK(mx_material_name(m, pa[p], na, sizeof na));
    if (pb[p] > nmat) snprintf(nb2, sizeof nb2, "outside");
    else MX_CHECK(mx_material_name(m, pb[p], nb2, sizeof nb2));
    snprintf(name, sizeof name, "interface %s | %s", na, nb2);
    T->tag_names[1 + p] = T->names[k++] = tag_name(name, "");
  }
  for (int i = 0; i < k; i++)
    if (!T->names[i]) return MX_ENOMEM;
  T->nbodies = nb <= 64 && !over ? nb : 0;
  T->ntags = ntags;
  return MX_OK;
}

/* The view the writers get, and what it points to. */
typedef struct {
  uint32_t *order;
  tags T;
  mx_field f[6], pf[2];
  mx_mesh_view v;
  int tagged;
  double *size; /* a size field's: each cell's target size */
} prepared;

static void release(prepared *P) {
  tags_free(&P->T);
  mx_free(P->order);
  mx_free(P->size);
}

/* With a size field (issue 27): the cell field target_size, the least of
 * the field's sizes at the cell's centroid, to see the field in a viewer. */
static int add_size_field(const mx_mesher *m, prepared *P) {
  if (!m->size_F.cs && !m->size_F.src) return MX_OK;
  const mx_mesh *M = &m->M;
  P->size = mx_alloc((M->ncells + 1) * sizeof *P->size);
  if (!P->size) return MX_ENOMEM;
#pragma omp parallel for schedule(static)
  for (size_t c = 0; c < M->ncells; c++) {
    const int nv = mx_cell_nodes[M->type[c]];
    double p[3] = {0.0, 0.0, 0.0};
    for (int k = 0; k < nv; k++)
      for (int a = 0; a < 3; a++) p[a] += M->xyz[3 * (size_t)M->conn[8 * c + k] + a] / nv;
    P->size[c] = mx_size_field_at(&m->size_F, p);
  }
  P->f[P->v.ncell_fields++] = (mx_field){.name = "target_size", .is_double = 1,
                                         .dvalues = P->size};
  return MX_OK;
}

static int prepare(const mx_mesher *m, prepared *P) {
  memset(P, 0, sizeof *P);
  const mx_mesh *M = &m->M;
  P->order = mx_alloc((M->ncells + 1) * sizeof *P->order);
  if (!P->order) return MX_ENOMEM;
  /* The fields read the mesh's own arrays: 8-bit types, levels and
   * boundary flags, written as int32 (UInt8 in a VTU), float J_ENS written
   * as double; the writers convert value by value. */
  P->f[0] = (mx_field){.name = "type", .is_double = 0, .u8values = M->type};
  P->f[1] = (mx_field){.name = "level", .is_double = 0, .u8values = M->level};
  P->f[2] = (mx_field){.name = "jens", .is_double = 1, .fvalues = M->jens};
  P->pf[0] = (mx_field){.name = "boundary", .is_double = 0, .u8values = m->bnd};
  P->v = (mx_mesh_view){.nnodes = M->nnodes, .xyz = M->xyz, .ncells = M->ncells,
                        .type = M->type, .conn = M->conn, .ncell_fields = 3,
                        .cell_fields = P->f, .npoint_fields = 1, .point_fields = P->pf,
                        .order = P->order};
  P->tagged = (m->mesh_stage == MX_STAGE_FULL && m->ndomain > 0) || M->material;
  if (!P->tagged) {
    MX_CHECK(add_size_field(m, P));
    return mx_cells_by_type(M->type, M->ncells, P->order, NULL);
  }
  if (M->material)
    MX_CHECK(make_material_tags(m, &P->v, &P->T));
  else
    MX_CHECK(make_tags(m, &P->v, &P->T));
  MX_CHECK(mx_cells_in_order(M->type, P->T.cell_body, P->T.nbodies, M->ncells, P->order));
  P->f[3] = (mx_field){.name = "body", .is_double = 0, .ivalues = P->T.cell_body};
  P->pf[1] = (mx_field){.name = "surface_tag", .is_double = 0, .ivalues = P->T.node_tag};
  P->v.ncell_fields = 4;
  if (P->T.material) {
    P->f[4] = (mx_field){.name = "material", .is_double = 0, .ivalues = P->T.material};
    P->v.ncell_fields = 5;
  }
  P->v.npoint_fields = 2;
  P->v.bfaces = &P->T.bf;
  P->v.ntags = P->T.ntags;
  P->v.tag_names = P->T.tag_names;
  P->v.cell_body = P->T.cell_body;
  P->v.nbodies = P->T.nbodies;
  P->v.body_names = P->T.body_names;
  if (P->T.material) P->v.body_physical = P->T.body_physical;
  return add_size_field(m, P);
}

/* --fields: keep the fields asked for (mx_mesher_set_output_fields). A tag
 * field (surface_tag, body, material) stays where the format has no other
 * place for it (.vtu, .vtk, .pvtu); .msh and .mesh carry the tags as
 * physical groups and references. */
static int is_tag(const char *name) {
  return !strcmp(name, "surface_tag") || !strcmp(name, "body") || !strcmp(name, "material");
}

static int keep_field(const char *name, int which, int tags_as_fields) {
  if (which == MX_FIELDS_ALL) return 1;
  if (is_tag(name)) return tags_as_fields;
  return which == MX_FIELDS_QUALITY && !strcmp(name, "jens");
}

static void select_fields(mx_field *f, int *n, int which, int tags_as_fields) {
  int k = 0;
  for (int i = 0; i < *n; i++)
    if (keep_field(f[i].name, which, tags_as_fields)) f[k++] = f[i];
  *n = k;
}

int mx_write_mixed(const mx_mesher *m, const char *path, int ascii) {
  prepared P;
  int st = prepare(m, &P);
  if (!st && m->out_fields != MX_FIELDS_ALL) {
    const char *dot = strrchr(path, '.');
    const int tags_as_fields =
        dot && (!strcasecmp(dot, ".vtu") || !strcasecmp(dot, ".vtk") || !strcasecmp(dot, ".pvtu"));
    select_fields(P.f, &P.v.ncell_fields, m->out_fields, tags_as_fields);
    select_fields(P.pf, &P.v.npoint_fields, m->out_fields, tags_as_fields);
  }
  if (!st) st = mx_write_mesh(path, &P.v, ascii);
  release(&P);
  return st;
}

int mx_mesher_write_boundary(const mx_mesher *m, const char *path) {
  mx_call c;
  mx_call_begin(m, &c);
  const double t = mx_wtime();
  int st = MX_OK;
  const char *dot = path ? strrchr(path, '.') : NULL;
  const int vtu = dot && !strcasecmp(dot, ".vtu");
  if (!mx_boundary_format_known(path)) {
    mx_error(path, 0, "the boundary faces are written as .vtu, .stl, .off or .ply");
    st = MX_EINPUT;
  } else if (mx_mesher_spares_inputs(m, path, 0)) {
    st = MX_EINPUT; /* an input: refused, named */
  } else if (m->mesh_stage != MX_STAGE_FULL) {
    mx_error(path, 0, "the boundary faces are written for a full-stage mesh only");
    st = MX_EINPUT;
  }
  prepared P;
  memset(&P, 0, sizeof P);
  if (!st) st = prepare(m, &P);
  if (!st) st = vtu ? mx_write_boundary_vtu(path, &P.v) : mx_write_boundary_surface(path, &P.v);
  release(&P);
  m->rec->S.ph.write += mx_wtime() - t;
  return mx_call_end(m, &c, st);
}

int mx_with_written_view(const mx_mesher *m, int (*fn)(void *ctx, const mx_mesh_view *v),
                         void *ctx) {
  prepared P;
  memset(&P, 0, sizeof P);
  int st = prepare(m, &P);
  if (!st) st = fn(ctx, &P.v);
  release(&P);
  return st;
}

int mx_written_order(const mx_mesher *m, uint32_t *order) {
  const mx_mesh *M = &m->M;
  if (m->mesh_stage != MX_STAGE_FULL || m->ndomain == 0)
    return mx_cells_by_type(M->type, M->ncells, order, NULL);
  const mx_mesh_view v = {.nnodes = M->nnodes, .xyz = M->xyz, .ncells = M->ncells,
                          .type = M->type, .conn = M->conn};
  return mx_cells_written_order(&v, order);
}

int mx_mesher_written_order(const mx_mesher *m, uint32_t *order) {
  mx_call c; /* messages to the mesher's handler, not to stderr */
  mx_call_begin(m, &c);
  if (m->mesh_stage < MX_STAGE_TRANSITION) {
    mx_error(NULL, 0, "no mixed mesh: mesh first");
    return mx_call_end(m, &c, MX_EINPUT);
  }
  return mx_call_end(m, &c, mx_written_order(m, order));
}

static int write_octree(const mx_mesher *m, const char *path, int ascii) {
  if (!m->rec->have_hex) {
    MX_CHECK(mx_leaf_hex_mesh(&m->B.tree, m->leaves, m->nleaves, &m->rec->hex));
    m->rec->have_hex = 1;
  }
  m->rec->S.nodes = m->rec->hex.nnodes;
  m->rec->S.nodes_counted = 1;
  const mx_mesh *H = &m->rec->hex;
  mx_field level = {.name = "level", .u8values = H->level};
  mx_mesh_view v = {.nnodes = H->nnodes, .xyz = H->xyz, .ncells = H->ncells, .type = H->type, .conn = H->conn, .ncell_fields = 1, .cell_fields = &level, .npoint_fields = 0, .point_fields = NULL};
  return mx_write_mesh(path, &v, ascii);
}

int mx_mesher_write(const mx_mesher *m, const char *path, int ascii) {
  mx_call c;
  mx_call_begin(m, &c);
  const double t = mx_wtime();
  int st = MX_OK;
  if (!path || !mx_mesh_format_known(path)) {
    mx_error(path, 0, "unknown output format (use .vtk .vtu .msh .mesh .meshb "
                      ".getfem .m3d .mvm)");
    st = MX_EINPUT;
  } else if (mx_mesher_spares_inputs(m, path, 0)) {
    st = MX_EINPUT; /* an input: refused, named */
  } else if (m->mesh_stage == MX_STAGE_OCTREE) {
    st = write_octree(m, path, ascii);
  } else if (m->mesh_stage < 0) {
    mx_error(path, 0, "no mesh to write: call mx_mesher_mesh first");
    st = MX_EINPUT;
  } else {
    st = mx_mesher_stage(m, "write");
    if (!st) st = mx_write_mixed(m, path, ascii);
  }
  m->rec->S.ph.write += mx_wtime() - t;
  return mx_call_end(m, &c, st);
}
