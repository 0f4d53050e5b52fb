/* mx_mesher_boundary_arrays (include/mixoct.h): the boundary faces, their
 * tags and the bodies of the mesh as arrays. The faces, tags and bodies
 * are those the writers get (mx_with_written_view: the `--boundary` file's
 * code path, mesher/output.c); this file only copies them out, into one
 * block the caller frees. */
#include <string.h>

#include "base/common.h"
#include "io/boundary_faces.h"
#include "mesher/mesher.h"
#include "mesher/mesher_impl.h"

typedef struct {
  mx_boundary_arrays *b;
} copy_ctx;

static const mx_field *cell_field(const mx_mesh_view *v, const char *name) {
  for (int i = 0; i < v->ncell_fields; i++)
    if (!strcmp(v->cell_fields[i].name, name)) return &v->cell_fields[i];
  return NULL;
}

static int copy_out(void *vctx, const mx_mesh_view *v) {
  mx_boundary_arrays *b = ((copy_ctx *)vctx)->b;
  const mx_boundary_faces *bf = v->bfaces;
  if (!bf || !v->cell_body) { /* no surface input (prepare's `tagged`) */
    mx_error(NULL, 0, "the boundary faces are given for a mesh of surface inputs only");
    return MX_EINPUT;
  }
  const mx_field *mat = cell_field(v, "material");
  const size_t nf = bf->ntri + bf->nquad, ne = v->ncells;
  b->nodes = mx_alloc((4 * nf + 1) * sizeof *b->nodes);
  b->tag = mx_alloc((nf + 1) * sizeof *b->tag);
  b->element = mx_alloc((nf + 1) * sizeof *b->element);
  b->local_face = mx_alloc(nf + 1);
  b->body = mx_alloc((ne + 1) * sizeof *b->body);
  if (mat && mat->ivalues) b->material = mx_alloc((ne + 1) * sizeof *b->material);
  if (!b->nodes || !b->tag || !b->element || !b->local_face || !b->body ||
      (mat && mat->ivalues && !b->material))
    return MX_ENOMEM;
  b->nfaces = nf;
  b->ntri = bf->ntri;
  b->nquad = bf->nquad;
  b->nelements = ne;
#pragma omp parallel for schedule(static)
  for (size_t i = 0; i < nf; i++) {
    const int tri = i < bf->ntri;
    const size_t j = tri ? i : i - bf->ntri;
    const uint32_t *f = tri ? bf->tri + 3 * j : bf->quad + 4 * j;
    const uint64_t src = tri ? bf->tri_src[j] : bf->quad_src[j];
    const int32_t *tags = tri ? bf->tri_tag : bf->quad_tag;
    for (int k = 0; k < 4; k++) b->nodes[4 * i + k] = k < (tri ? 3 : 4) ? f[k] : UINT32_MAX;
    b->tag[i] = tags ? tags[j] : 1; /* untagged: one surface (as the file) */
    b->element[i] = (uint32_t)(src >> 3);
    b->local_face[i] = (uint8_t)(src & 7);
  }
  int nbodies = 0;
  for (size_t c = 0; c < ne; c++) {
    b->body[c] = v->cell_body[c];
    if (v->cell_body[c] > nbodies) nbodies = v->cell_body[c];
  }
  if (b->material) memcpy(b->material, mat->ivalues, ne * sizeof *b->material);
  b->nbodies = nbodies;
  b->ntags = v->ntags;
  return MX_OK;
}

int mx_mesher_boundary_arrays(const mx_mesher *m, mx_boundary_arrays *b) {
  memset(b, 0, sizeof *b);
  mx_call c;
  mx_call_begin(m, &c);
  int st = MX_OK;
  if (m->mesh_stage != MX_STAGE_FULL) {
    mx_error(NULL, 0, "the boundary faces are given for a full-stage mesh only");
    st = MX_EINPUT;
  }
  copy_ctx ctx = {b};
  if (!st) st = mx_with_written_view(m, copy_out, &ctx);
  if (st) mx_boundary_arrays_free(b);
  return mx_call_end(m, &c, st);
}

void mx_boundary_arrays_free(mx_boundary_arrays *b) {
  if (!b) return;
  mx_free(b->nodes);
  mx_free(b->tag);
  mx_free(b->element);
  mx_free(b->local_face);
  mx_free(b->body);
  mx_free(b->material);
  memset(b, 0, sizeof *b);
}
