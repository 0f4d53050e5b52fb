/* mixoct: the independent mesh checker (definitions in check.h): the
 * passes, one file each (check_passes.h), run in order on a plain mesh
 * (soa/mesh_data.h) and, optionally, the input surface:
 *  1. validity: J_ENS of every element (check_validity.c);
 *  2. duplicate nodes: a hash of the exact coordinates
 *     (check_duplicates.c);
 *  3. face matching: uses and orientation of every face, quad centres
 *     (check_faces.c);
 *  4. hanging nodes at edge midpoints (check_hanging.c);
 *  5. the closed boundary (check_boundary.c) and the boundary tags
 *     (check_tags.c);
 *  6. geometric hanging nodes (check_contacts.c);
 *  7. with a surface: the enclosed volume (check_volume.c), with cell
 *     labels the regions of the labels and of the elements (check_labels.c,
 *     check_regions.c; a surface of several files, touching inputs: the
 *     regions of its pieces, check_pieces.c), and
 *  8. the distance of the boundary and interface nodes to it, and with a
 *     closed surface between it and the mesh's skin both ways
 *     (check_distance.c).
 * It depends on base/, soa/ and geom/ (J_ENS) only, never on the mesher.
 * Coordinates enter the grids as (x/2 - lo/2) / (extent/2): finite for any
 * finite input (extents up to 2 * DBL_MAX, down to 1e-300).
 * A face is named by its slot 6 * cell + local face, so ncells is limited to
 * (2^32 - 1) / 6. */
#include "verify/check.h"

#include "verify/check_passes.h"

#include "soa/mesh.h"

const char *const mx_check_elem_kind_name[MX_CK_ELEM_KINDS] = {
    "invalid",           "degenerate",          "faces_overshared",
    "faces_misoriented", "quad_vs_triangles",   "open_boundary_edges",
    "hanging_nodes",     "geometric_hanging_nodes"};
const char *const mx_check_node_kind_name[MX_CK_NODE_KINDS] = {
    "unused_nodes", "duplicate_nodes", "hanging_nodes",
    "geometric_hanging_nodes", "boundary_off_surface"};

void mx_check_defaults(mx_check_options *o) {
  o->degenerate_below = 1e-6;
  o->hang_tol = 1e-9;
  o->volume_tol = 0.0; /* chosen from the mesh */
  o->volume_tol_auto = 0;
  o->boundary_tol = 1e-6;
}

static int validate(const mx_mesh_data *m) {
  if (m->nnodes >= UINT32_MAX || m->ncells > UINT32_MAX / 6) {
    mx_error(NULL, 0,
             "check: %zu nodes and %zu cells: at most %u nodes and %u cells "
             "can be checked",
             m->nnodes, m->ncells, UINT32_MAX - 1, UINT32_MAX / 6);
    return MX_EINPUT;
  }
  size_t bad = SIZE_MAX;
#pragma omp parallel for schedule(static) reduction(min : bad) \
    if (m->ncells > SMALL)
  for (size_t c = 0; c < m->ncells; c++) {
    if (m->type[c] > MX_HEX) {
      if (c < bad) bad = c;
      continue;
    }
    for (int j = 0; j < mx_cell_nodes[m->type[c]]; j++)
      if (m->conn[8 * c + (size_t)j] >= m->nnodes && c < bad) bad = c;
  }
  if (bad != SIZE_MAX) {
    mx_error(NULL, 0,
             "check: cell %zu has a bad type (%d) or a node index out of "
             "range (%zu nodes)",
             bad, m->type[bad], m->nnodes);
    return MX_EINPUT;
  }
#pragma omp parallel for schedule(static) reduction(min : bad) \
    if (m->nnodes > 65536)
  for (size_t i = 0; i < 3 * m->nnodes; i++)
    if (!isfinite(m->xyz[i]) && i < bad) bad = i;
  if (bad != SIZE_MAX) {
    mx_error(NULL, 0, "check: node %zu has a coordinate that is not finite",
             bad / 3);
    return MX_EINPUT;
  }
  if (m->nfaces && (!m->face_nn || !m->face_conn || !m->face_tag ||
                    m->nfaces >= UINT32_MAX)) {
    mx_error(NULL, 0, "check: %zu tagged faces without their arrays, or too "
             "many", m->nfaces);
    return MX_EINPUT;
  }
#pragma omp parallel for schedule(static) reduction(min : bad) \
    if (m->nfaces > SMALL)
  for (size_t f = 0; f < m->nfaces; f++) {
    const int n = m->face_nn[f];
    if (n != 3 && n != 4) {
      if (f < bad) bad = f;
      continue;
    }
    for (int j = 0; j < n; j++)
      if (m->face_conn[4 * f + (size_t)j] >= m->nnodes && f < bad) bad = f;
  }
  if (bad != SIZE_MAX) {
    mx_error(NULL, 0,
             "check: tagged face %zu has %d nodes (3 or 4) or a node index "
             "out of range (%zu nodes)",
             bad, m->face_nn[bad], m->nnodes);
    return MX_EINPUT;
  }
  return MX_OK;
}

typedef struct {
  uint8_t *flags, *ef;
  chash H;
  faces F;
  uint32_t *other; /* with cell labels: the slot across each face */
  uint32_t *skin;  /* with a surface: the boundary and interface faces */
  size_t nskin;
  double *node_d2; /* with a closed surface: the skin nodes' squared distances */
} work;

static void work_free(work *w) {
  mx_free(w->flags);
  mx_free(w->ef);
  mx_free(w->H.slot);
  mx_free(w->H.seg);
  faces_free(&w->F);
  mx_free(w->other);
  mx_free(w->skin);
  mx_free(w->node_d2);
  memset(w, 0, sizeof *w);
}

/* The first MX_CHECK_LIST ids of each kind, and the first geometric
 * hanging nodes with where they lie. */
static void collect_lists(const mx_mesh_data *m, const work *w,
                          mx_check_report *r) {
  for (size_t c = 0; c < m->ncells; c++) {
    const uint8_t f = w->ef[c];
    if (!f) continue;
    for (int k = 0; k < MX_CK_ELEM_KINDS; k++) {
      mx_check_ids *l = &r->elem_ids[k];
      if ((f >> k & 1) && l->n < MX_CHECK_LIST) l->id[l->n++] = (uint32_t)c;
    }
  }
  const int closed = r->has_surface && r->surface_open_edges == 0;
  for (size_t v = 0; v < m->nnodes; v++) {
    const uint8_t f = w->flags[v];
    mx_check_ids *io = &r->interface_off_ids;
    if (closed && (f & F_IOFF) && io->n < MX_CHECK_LIST) io->id[io->n++] = (uint32_t)v;
    if ((f & (F_USED | F_DUP | F_HANG | F_GHANG | F_OFF)) == F_USED) continue;
    const int kind[MX_CK_NODE_KINDS] = {!(f & F_USED), (f & F_DUP) != 0,
                                        (f & F_HANG) != 0, (f & F_GHANG) != 0,
                                        closed && (f & F_OFF)};
    for (int k = 0; k < MX_CK_NODE_KINDS; k++) {
      mx_check_ids *l = &r->node_ids[k];
      if (kind[k] && l->n < MX_CHECK_LIST) l->id[l->n++] = (uint32_t)v;
    }
  }
}

/* A closed surface of several files (touching inputs: check_pieces.c):
 * the volume is the union of its pieces with cell labels (materials), the
 * points of odd nesting depth without (nested pieces are holes); the area
 * that sets the volume tolerance leaves out the triangles two files share,
 * the labels are judged against the pieces' regions. */
static int several_files(const mx_mesh_data *m, const mx_trisoup *surface,
                         const mx_check_options *o, mx_check_report *r) {
  uint8_t *shared = mx_alloc(surface->nt + 1);
  if (!shared) return MX_ENOMEM;
  ck_pieces P;
  int st = mx_ck_shared_triangles(surface, shared, &r->shared_triangles);
  if (!st) st = mx_ck_pieces_build(&P, surface);
  if (st) {
    mx_free(shared);
    return st;
  }
  r->surface_pieces = P.n;
  r->surface_volume = m->cell_tag ? P.union_volume : P.parity_volume;
  r->volume_error = r->surface_volume > 0.0
                        ? (r->volume - r->surface_volume) / r->surface_volume
                        : NAN;
  if (m->cell_tag) st = mx_ck_label_regions(m, surface, &P, r);
  mx_ck_pieces_free(&P);
  if (!st) {
    mx_ck_volume_verdict(m, surface, shared, o, r);
    if (m->cell_tag) mx_ck_label_verdict(r);
  }
  mx_free(shared);
  return st;
}

/* Whether face slot s is in the mesh's skin, the faces the surface should
 * bound: those used by one element and, with cell labels, those between
 * two labels (from the smaller slot). other: mx_ck_label_pass's. */
static int in_skin(const mx_mesh_data *m, const faces *F, const uint32_t *other, size_t s) {
  if (F->use[s] == 1) return 1;
  return other && other[s] != UINT32_MAX && other[s] > s &&
         m->cell_tag[s / 6] != m->cell_tag[other[s] / 6];
}

/* The skin's face slots, ascending. */
static int skin_faces(const mx_mesh_data *m, const faces *F, const uint32_t *other, work *w) {
  const size_t nslots = 6 * m->ncells;
  size_t n = 0;
  for (size_t s = 0; s < nslots; s++) n += (size_t)in_skin(m, F, other, s);
  w->skin = mx_alloc((n + 1) * sizeof *w->skin);
  if (!w->skin) return MX_ENOMEM;
  w->nskin = n;
  n = 0;
  for (size_t s = 0; s < nslots; s++)
    if (in_skin(m, F, other, s)) w->skin[n++] = (uint32_t)s;
  return MX_OK;
}

/* Pass 7 and 8: against the surface. */
static int surface_passes(const mx_mesh_data *m, const mx_trisoup *surface,
                          const mx_check_options *o, mx_check_report *r, uint8_t *flags,
                          work *w) {
  r->has_surface = 1;
  r->surface_files = mx_ck_surface_files(surface);
  MX_CHECK(mx_ck_surface_volume(surface, r));
  if (!r->surface_open_edges) { /* the skin nodes' distances kept for the skin's */
    w->node_d2 = mx_alloc((m->nnodes + 1) * sizeof *w->node_d2);
    if (!w->node_d2) return MX_ENOMEM;
  }
  MX_CHECK(mx_ck_surface_distance(m, surface, flags, o->boundary_tol, w->node_d2, r));
  if (!r->surface_open_edges)
    MX_CHECK(mx_ck_two_sided_distance(m, surface, w->skin, w->nskin, w->node_d2, r));
  if (r->surface_open_edges) { /* an open surface: indicative only */
    r->boundary_off_surface = 0;
    r->interface_off_surface = 0;
    return MX_OK;
  }
  if (r->surface_files > 1) return several_files(m, surface, o, r);
  if (m->cell_tag) MX_CHECK(mx_ck_label_regions(m, surface, NULL, r));
  mx_ck_volume_verdict(m, surface, NULL, o, r);
  if (m->cell_tag) mx_ck_label_verdict(r);
  return MX_OK;
}

static int check_body(const mx_mesh_data *m, const mx_trisoup *surface,
                      const mx_check_options *o, mx_check_report *r,
                      mx_check_tags *tags, work *w) {
  const size_t nn = m->nnodes;
  w->flags = mx_calloc(nn + 1);
  w->ef = mx_calloc(m->ncells + 1);
  if (!w->flags || !w->ef) return MX_ENOMEM;
  uint8_t *flags = w->flags;
  MX_CHECK(mx_ck_element_pass(m, flags, w->ef, o->degenerate_below, r));
  size_t unused = 0;
#pragma omp parallel for schedule(static) reduction(+ : unused) \
    if (nn > SMALL)
  for (size_t v = 0; v < nn; v++) unused += !(flags[v] & F_USED);
  r->unused_nodes = unused;
  chash *H = &w->H;
  MX_CHECK(mx_ck_chash_build(H, m, &r->duplicate_nodes));
  if (r->duplicate_nodes) { /* which: those that are not the smallest id */
#pragma omp parallel for schedule(static) if (nn > SMALL)
    for (size_t v = 0; v < nn; v++)
      if (chash_find(H, m->xyz + 3 * v) != (int64_t)v) flags[v] |= F_DUP;
  }
  MX_CHECK(mx_ck_faces_bucket(m, &w->F));
  face_counts fc;
  MX_CHECK(mx_ck_faces_match(m, &w->F, H, flags, w->ef, &fc));
  r->faces_interior = fc.interior;
  r->faces_boundary = fc.boundary;
  r->faces_overshared = fc.overshared;
  r->faces_misoriented = fc.misoriented;
  mx_ck_edge_midpoints(m, H, flags, w->ef);
  size_t hang = 0;
#pragma omp parallel for schedule(static) reduction(+ : hang) \
    if (nn > SMALL)
  for (size_t v = 0; v < nn; v++) hang += (flags[v] & F_HANG) != 0;
  r->hanging_nodes = hang;
  MX_CHECK(mx_ck_boundary_pass(m, &w->F, flags, w->ef, fc.boundary, r));
  MX_CHECK(mx_ck_tag_pass(m, &w->F, r, tags));
  mx_ck_boundary_flags(m, flags, r);
  if (m->cell_tag) {
    w->other = mx_alloc((6 * m->ncells + 1) * sizeof *w->other);
    if (!w->other) return MX_ENOMEM;
  }
  MX_CHECK(mx_ck_label_pass(m, &w->F, flags, w->other, r));
  MX_CHECK(mx_ck_label_boundaries(m, &w->F, w->other, r));
  if (surface) MX_CHECK(skin_faces(m, &w->F, w->other, w));
  mx_free(w->other);
  w->other = NULL;
  mx_free(H->slot); /* memory for the next passes */
  mx_free(H->seg);
  H->slot = H->seg = NULL;
  mx_free(w->F.slot);
  mx_free(w->F.end);
  w->F.slot = NULL;
  w->F.end = NULL;
  MX_CHECK(mx_ck_geometric_pass(m, &w->F, &H->U, flags, w->ef, o->hang_tol, r));
  faces_free(&w->F);
  memset(&w->F, 0, sizeof w->F);
  if (surface) MX_CHECK(surface_passes(m, surface, o, r, flags, w));
  collect_lists(m, w, r);
  return MX_OK;
}

void mx_check_tags_free(mx_check_tags *tags) {
  if (!tags) return;
  mx_free(tags->face_tags);
  mx_free(tags->node_tags);
  mx_free(tags->names);
  memset(tags, 0, sizeof *tags);
}

int mx_check_mesh_tags(const mx_mesh_data *m, const mx_trisoup *surface,
                       const mx_check_options *opt, mx_check_report *r,
                       mx_check_tags *tags) {
  memset(r, 0, sizeof *r);
  if (tags) memset(tags, 0, sizeof *tags);
  mx_check_options o;
  mx_check_defaults(&o);
  if (opt) o = *opt;
  r->opt = o;
  r->surface_volume = r->volume_error = r->boundary_max_dist = NAN;
  r->interface_max_dist = NAN;
  r->surface_diagonal = r->mesh_sample_spacing = r->surface_sample_spacing = NAN;
  r->mesh_to_surface_max = r->mesh_to_surface_mean = NAN;
  r->surface_to_mesh_max = r->surface_to_mesh_mean = NAN;
  for (int a = 0; a < 3; a++) r->across_interface.at[a] = r->off_label_region.at[a] = NAN;
  r->jens_min = r->jens_mean = NAN;
  MX_CHECK(validate(m));
  r->nodes = m->nnodes;
  r->elements = m->ncells;
  r->empty = m->nnodes == 0 || m->ncells == 0;
  work w;
  memset(&w, 0, sizeof w);
  const int st = check_body(m, surface, &o, r, tags, &w);
  work_free(&w);
  if (st != MX_OK) return st;
  r->defects = r->empty + r->invalid + r->degenerate + r->faces_overshared +
               r->faces_misoriented + r->quad_vs_triangles +
               r->open_boundary_edges + r->hanging_nodes +
               r->geometric_hanging_nodes + r->unused_nodes +
               r->duplicate_nodes + r->volume_off + r->boundary_off_surface +
               r->tagged_not_boundary + r->boundary_untagged + r->boundary_flags_off +
               r->labels_off + r->labels_open +
               r->interface_off_surface + r->across_interface.n + r->off_label_region.n;
  return MX_OK;
}

int mx_check_mesh_opt(const mx_mesh_data *m, const mx_trisoup *surface,
                      const mx_check_options *opt, mx_check_report *r) {
  return mx_check_mesh_tags(m, surface, opt, r, NULL);
}

int mx_check_mesh(const mx_mesh_data *m, const mx_trisoup *surface,
                  mx_check_report *r) {
  return mx_check_mesh_opt(m, surface, NULL, r);
}
