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
#include "kernels/leaves.h"
#include "soa/mesh.h"
#include "io/write_mesh.h"
#include "io/cell_order.h"

/* What the writers' view needs beyond the mesh's own arrays, computed
 * once per mesh (issue 31 item 4) and kept in m->rec->written until the
 * mesh changes (mx_written_forget): the written order, the boundary faces
 * with their tags, the bodies, the per-node tags; with materials the
 * material field and the pairs of materials met. The names of the groups
 * come from the inputs' names and are made again by each call
 * (prepare), so that a name set after the mesh is still the one written.
 * Its size: 4 bytes per cell for the order and 4 for the bodies (4 more
 * with materials), 4 per node, and per boundary face its nodes, source,
 * tag and pair (28 bytes a triangle, 36 a quadrilateral). */
struct mx_written {
  /* the mesh it was made for: a safety net under mx_written_forget */
  const void *conn, *xyz, *type, *mat, *states;
  size_t ncells, nnodes;
  int stage, ndomain, nmaterials, have_mix;
  uint32_t *order;
  int tagged;
  mx_boundary_faces bf;
  int32_t *cell_body, *body_tag, *node_tag;
  int32_t *material; /* materials: the cell field (0: outside every shell) */
  int nbodies, ntags; /* bodies written as groups (0: none, over 64) */
  int nbodies_all;    /* every body found */
  size_t off;         /* faces on no input */
  /* materials: the bodies (one per material, and the outside), the pairs
   * of bodies met in order of first face (tags 2, 3, ...), more than 63 */
  int nbm, npairs, over;
  int32_t pa[63], pb[63];
  int32_t body_physical[66];
};

static void written_free(mx_written *W) {
  if (!W) return;
  mx_boundary_faces_free(&W->bf);
  mx_free(W->order);
  mx_free(W->cell_body);
  mx_free(W->body_tag);
  mx_free(W->node_tag);
  mx_free(W->material);
  mx_free(W);
}

void mx_written_forget(mx_mesher *m) { mx_written_release(m); }

void mx_written_release(const mx_mesher *m) {
  written_free(m->rec->written);
  m->rec->written = NULL;
}

/* The mesh's identity as the cache records it. */
static void written_stamp(const mx_mesher *m, mx_written *W) {
  const mx_mesh *M = &m->M;
  W->conn = M->conn, W->xyz = M->xyz, W->type = M->type, W->mat = M->material;
  W->states = m->states;
  W->ncells = M->ncells, W->nnodes = M->nnodes;
  W->stage = m->mesh_stage, W->ndomain = m->ndomain, W->nmaterials = m->nmaterials;
  W->have_mix = m->have_mix;
}

static int written_fits(const mx_mesher *m, const mx_written *W) {
  mx_written now;
  written_stamp(m, &now);
  return W->conn == now.conn && W->xyz == now.xyz && W->type == now.type &&
         W->mat == now.mat && W->states == now.states && W->ncells == now.ncells &&
         W->nnodes == now.nnodes && W->stage == now.stage && W->ndomain == now.ndomain &&
         W->nmaterials == now.nmaterials && W->have_mix == now.have_mix;
}

/* The view of the mesh's own arrays, as the extraction reads it. */
static mx_mesh_view mesh_view(const mx_mesh *M) {
  return (mx_mesh_view){.nnodes = M->nnodes, .xyz = M->xyz, .ncells = M->ncells,
                        .type = M->type, .conn = M->conn};
}

/* A full-stage mesh of surfaces with one material, whose boundary flags
 * can be made exact from its boundary faces (with materials and label
 * images the outside nodes are the interfaces' too: their flags stay). */
static int plain_full(const mx_mesher *m) {
  return m->states && m->mesh_stage == MX_STAGE_FULL && !m->p.materials && !m->image_lattice &&
         !m->IF.npasses;
}

int mx_boundary_candidates(const mx_mesher *m, uint8_t *near) {
  const mx_mesh *M = &m->M;
  /* The boundary faces lie on the surface: their nodes are outside nodes
   * (projected) or lattice nodes on the surface, which belong to leaves
   * meeting the input (a leaf meeting none has its closed box inside the
   * domain; mx_leaves_meeting: also those touching a triangle in one of
   * their faces' planes that their lists missed by rounding). (The inside
   * nodes the node states find on the surface, MX_NODE_ON, are not
   * enough: a node of a leaf meeting no triangle is taken inside without a
   * query, and a triangle lying in the plane of a leaf's face can fall in
   * the rounding gap between the boxes: the L of tests/tag_faces_test.sh,
   * re-meshed from its restart file, left 52 boundary faces untagged with
   * them against 19 with the leaves' lists alone and none with this.) */
  uint8_t *leaf_meets = mx_alloc(m->nleaves + 1);
  if (!leaf_meets) return MX_ENOMEM;
  if (mx_leaves_meeting(&m->B.tree, m->leaves, m->nleaves, leaf_meets)) {
    mx_free(leaf_meets);
    return MX_ENOMEM;
  }
  memset(near, 0, M->nnodes);
#pragma omp parallel for schedule(static)
  for (size_t c = 0; c < M->ncells; c++) {
    const uint32_t *row = M->conn + 8 * c;
    const int meets = leaf_meets[M->leaf[c]];
    for (int k = 0; k < mx_cell_nodes[M->type[c]]; k++)
      if (meets || (m->states && m->states[row[k]] == MX_NODE_OUTSIDE))
        __atomic_store_n(&near[row[k]], 1, __ATOMIC_RELAXED);
  }
  mx_free(leaf_meets);
  return MX_OK;
}

/* The nodes of the plain full-stage mesh's boundary faces bf into m->bnd,
 * which then is exact. */
static void set_boundary_flags(const mx_mesher *m, const mx_boundary_faces *bf) {
  if (!plain_full(m) || !m->bnd) return;
  memset(m->bnd, 0, m->M.nnodes);
  for (size_t i = 0; i < 3 * bf->ntri; i++) m->bnd[bf->tri[i]] = 1;
  for (size_t i = 0; i < 4 * bf->nquad; i++) m->bnd[bf->quad[i]] = 1;
  m->rec->bnd_exact = 1;
}

/* The boundary faces of the full-stage mesh into *bf, found among the
 * faces whose nodes are all in a mask: the nodes on the boundary when they
 * are known (rec->bnd_exact), else those that can be
 * (mx_boundary_candidates); the faces found make the flags exact. */
static int boundary_faces(const mx_mesher *m, mx_boundary_faces *bf) {
  const mx_mesh_view v = mesh_view(&m->M);
  uint8_t *near = NULL;
  if (!m->rec->bnd_exact) {
    near = mx_alloc(m->M.nnodes + 1);
    if (!near) return MX_ENOMEM;
    const int st = mx_boundary_candidates(m, near);
    if (st) {
      mx_free(near);
      return st;
    }
  }
  const int st = mx_boundary_faces_extract_masked(&v, near ? near : m->bnd, bf);
  mx_free(near);
  MX_CHECK(st);
  set_boundary_flags(m, bf);
  return MX_OK;
}

int mx_boundary_flags_exact(const mx_mesher *m) {
  if (m->rec->bnd_exact || !plain_full(m) || !m->bnd) return MX_OK;
  mx_boundary_faces bf;
  MX_CHECK(boundary_faces(m, &bf));
  mx_boundary_faces_free(&bf);
  return MX_OK;
}

static int make_tags(const mx_mesher *m, mx_written *T) {
  const mx_mesh *M = &m->M;
  const mx_mesh_view v = mesh_view(M);
  MX_CHECK(boundary_faces(m, &T->bf));
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
  MX_CHECK(mx_boundary_tags(&v, &in, &T->bf, T->cell_body, &T->nbodies_all, &T->body_tag,
                            &T->off));
  mx_boundary_node_tags(&T->bf, M->nnodes, T->node_tag);
  T->ntags = m->ndomain + (T->off > 0);
  T->nbodies = T->nbodies_all > 64 ? 0 : T->nbodies_all; /* named groups for 64 at most */
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
 * (the material field stays). The names: material_names. */
static int make_material_tags(const mx_mesher *m, mx_written *T) {
  const mx_mesh *M = &m->M;
  const mx_mesh_view v = mesh_view(M);
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
  MX_CHECK(mx_interface_faces_extract(&v, T->cell_body, bf));
  bf->tri_tag = mx_alloc((bf->ntri + 1) * sizeof *bf->tri_tag);
  bf->quad_tag = mx_alloc((bf->nquad + 1) * sizeof *bf->quad_tag);
  if (!bf->tri_tag || !bf->quad_tag) return MX_ENOMEM;
  /* the pairs met, in order of first face: tags 2, 3, ... */
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
      while (k < npairs && !(T->pa[k] == a && T->pb[k] == b)) k++;
      if (k == npairs && npairs < 63) {
        T->pa[k] = a;
        T->pb[k] = b;
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
  T->nbm = nmat + outside;
  T->npairs = npairs;
  T->over = over;
  T->nbodies = T->nbm <= 64 && !over ? T->nbm : 0;
  T->ntags = ntags;
  return MX_OK;
}

/* The cached part for the mesh as it is now (made at the first call after
 * a change). */
static int written_get(const mx_mesher *m, const mx_written **out) {
  mx_written *W = m->rec->written;
  if (W && written_fits(m, W)) {
    *out = W;
    return MX_OK;
  }
  written_free(W);
  m->rec->written = NULL;
  W = mx_calloc(sizeof *W);
  if (!W) return MX_ENOMEM;
  const mx_mesh *M = &m->M;
  written_stamp(m, W);
  W->tagged = (m->mesh_stage == MX_STAGE_FULL && m->ndomain > 0) || M->material;
  W->order = mx_alloc((M->ncells + 1) * sizeof *W->order);
  int st = W->order ? MX_OK : MX_ENOMEM;
  if (!st && !W->tagged) st = mx_cells_by_type(M->type, M->ncells, W->order, NULL);
  if (!st && W->tagged) st = M->material ? make_material_tags(m, W) : make_tags(m, W);
  if (!st && W->tagged)
    st = mx_cells_in_order(M->type, W->cell_body, W->nbodies, M->ncells, W->order);
  if (st) {
    written_free(W);
    return st;
  }
  m->rec->written = W;
  *out = W;
  return MX_OK;
}

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

/* The view the writers get, and what it points to: the cached arrays
 * (W, the mesher's) and per call the names, fields and size field. */
typedef struct {
  const mx_written *W;
  char *names[2 * 66];
  const char *tag_names[66], *body_names[66];
  mx_field f[6], pf[2];
  mx_mesh_view v;
  double *size; /* a size field's: each cell's target size */
} prepared;

static void release(prepared *P) {
  for (size_t i = 0; i < sizeof P->names / sizeof *P->names; i++) mx_free(P->names[i]);
  mx_free(P->size);
}

/* The names of the surface groups (one per input, "on no input") and of
 * the bodies (after their smallest tag's input). */
static int input_names(const mx_mesher *m, prepared *P) {
  const mx_written *W = P->W;
  int k = 0;
  for (int t = 0; t < m->ndomain; t++)
    P->tag_names[t] = P->names[k++] = tag_name(m->domain_name[t], "");
  if (W->off > 0) P->tag_names[m->ndomain] = P->names[k++] = tag_name("on no input", "");
  const int nb = W->nbodies_all < 64 ? W->nbodies_all : 64;
  for (int b = 0; b < nb; b++) {
    const int t = W->body_tag[b];
    char suffix[32];
    snprintf(suffix, sizeof suffix, " volume %d", b + 1);
    P->body_names[b] = P->names[k++] =
        tag_name(t >= 1 && t <= m->ndomain ? m->domain_name[t - 1] : "mesh", suffix);
  }
  for (int i = 0; i < k; i++)
    if (!P->names[i]) return MX_ENOMEM;
  return MX_OK;
}

/* Materials: the bodies after their materials, the tags "boundary" and
 * "interface A | B". */
static int material_names(const mx_mesher *m, prepared *P) {
  const mx_written *W = P->W;
  const int nmat = m->nmaterials;
  int k = 0;
  char name[256], na[120], nb2[120];
  for (int b = 1; b <= W->nbm && b <= 64; b++) {
    if (b > nmat)
      snprintf(name, sizeof name, "outside the inputs");
    else
      MX_CHECK(mx_material_name(m, b, name, sizeof name));
    P->body_names[b - 1] = P->names[k++] = tag_name(name, "");
  }
  P->tag_names[0] = P->names[k++] = tag_name("boundary", "");
  for (int p = 0; p < W->npairs; p++) {
    if (W->pa[p] > nmat) snprintf(na, sizeof na, "outside");
    else MX_CHECK(mx_material_name(m, W->pa[p], na, sizeof na));
    if (W->pb[p] > nmat) snprintf(nb2, sizeof nb2, "outside");
    else MX_CHECK(mx_material_name(m, W->pb[p], nb2, sizeof nb2));
    snprintf(name, sizeof name, "interface %s | %s", na, nb2);
    P->tag_names[1 + p] = P->names[k++] = tag_name(name, "");
  }
  for (int i = 0; i < k; i++)
    if (!P->names[i]) return MX_ENOMEM;
  return MX_OK;
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
  MX_CHECK(written_get(m, &P->W));
  const mx_written *W = P->W;
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
                        .order = W->order};
  if (!W->tagged) return add_size_field(m, P);
  MX_CHECK(W->material ? material_names(m, P) : input_names(m, P));
  P->f[3] = (mx_field){.name = "body", .is_double = 0, .ivalues = W->cell_body};
  P->pf[1] = (mx_field){.name = "surface_tag", .is_double = 0, .ivalues = W->node_tag};
  P->v.ncell_fields = 4;
  if (W->material) {
    P->f[4] = (mx_field){.name = "material", .is_double = 0, .ivalues = W->material};
    P->v.ncell_fields = 5;
  }
  P->v.npoint_fields = 2;
  P->v.bfaces = &W->bf;
  P->v.ntags = W->ntags;
  P->v.tag_names = P->tag_names;
  P->v.cell_body = W->cell_body;
  P->v.nbodies = W->nbodies;
  P->v.body_names = P->body_names;
  if (W->material) P->v.body_physical = W->body_physical;
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
