#include "kernels/boundary_tags.h"

#include <math.h>
#include <string.h>

#include "base/common.h"
#include "soa/octree.h"
#include "io/cell_order.h"

/* The shell of the domain triangles leaf octant o meets when they all come
 * from one file; -1 when it meets none or several. */
static int leaf_shell(const mx_tag_inputs *in, uint32_t o) {
  const mx_octree *T = &in->tree->oct;
  const uint32_t *t = T->tri_pool + T->tri_off[o];
  int s = -1;
  for (uint32_t i = 0; i < T->tri_cnt[o]; i++) {
    if (t[i] >= in->nt_domain) continue; /* a region surface's */
    const int si = in->soup->shell[t[i]];
    if (s >= 0 && si != s) return -1;
    s = si;
  }
  return s;
}

/* The tag of the face with nodes f[0..n) of cell c. */
static int32_t face_tag(const mx_mesh_view *v, const mx_tag_inputs *in, const uint32_t *f, int n,
                        size_t c, double off_tol) {
  uint32_t pf[4];
  if (in->cell_parent && n == 3) { /* --tets: the face of the element it was cut from */
    const mx_mesh *P = in->parent;
    const size_t e = in->cell_parent[c];
    const uint32_t *row = P->conn + 8 * e;
    for (int j = 0; j < mx_cell_nfaces[P->type[e]]; j++) {
      const int8_t *q = mx_cell_faces[P->type[e]][j];
      const int nq = q[3] < 0 ? 3 : 4;
      int in_face = 0;
      for (int k = 0; k < 3; k++)
        for (int i = 0; i < nq; i++) in_face += f[k] == row[q[i]];
      if (in_face < 3) continue;
      for (int i = 0; i < nq; i++) pf[i] = row[q[i]];
      f = pf;
      n = nq;
      break;
    }
  }
  if (in->check_off)
    for (int k = 0; k < n; k++)
      if (!(mx_closest_point(in->SI, v->xyz + 3 * (size_t)f[k], NULL, NULL, NULL) <= off_tol))
        return in->nshells + 1;
  int s = leaf_shell(in, in->leaves[in->cell_leaf[c]]);
  if (s < 0) {
    double g[3] = {0.0, 0.0, 0.0};
    for (int k = 0; k < n; k++)
      for (int a = 0; a < 3; a++) g[a] += v->xyz[3 * (size_t)f[k] + a] / n;
    uint32_t t = UINT32_MAX;
    mx_closest_point(in->SI, g, NULL, &t, NULL);
    s = t < in->nt_domain ? in->soup->shell[t] : in->nshells;
  }
  return s + 1;
}

/* The faces of one list (nv nodes each) stably sorted by tag (counting
 * sort; tags 1..maxtag): a tag's faces become one run. */
static int sort_list(uint32_t *fv, uint64_t *src, int32_t *tag, size_t n, int nv, int maxtag) {
  if (!n) return MX_OK; /* the list may be NULL then */
  size_t i0 = 1;
  while (i0 < n && tag[i0 - 1] <= tag[i0]) i0++;
  if (i0 == n) return MX_OK; /* in order already (one input: one tag) */
  size_t *start = mx_calloc(((size_t)maxtag + 2) * sizeof *start);
  uint32_t *f2 = mx_alloc((nv * n + 1) * sizeof *f2);
  uint64_t *s2 = mx_alloc((n + 1) * sizeof *s2);
  int32_t *t2 = mx_alloc((n + 1) * sizeof *t2);
  int st = start && f2 && s2 && t2 ? MX_OK : MX_ENOMEM;
  if (!st) {
    for (size_t i = 0; i < n; i++) start[tag[i] + 1]++;
    for (int t = 1; t <= maxtag + 1; t++) start[t] += start[t - 1];
    for (size_t i = 0; i < n; i++) {
      const size_t j = start[tag[i]]++;
      memcpy(f2 + (size_t)nv * j, fv + (size_t)nv * i, (size_t)nv * sizeof *fv);
      s2[j] = src[i];
      t2[j] = tag[i];
    }
    memcpy(fv, f2, (size_t)nv * n * sizeof *fv);
    memcpy(src, s2, n * sizeof *src);
    memcpy(tag, t2, n * sizeof *tag);
  }
  mx_free(start);
  mx_free(f2);
  mx_free(s2);
  mx_free(t2);
  return st;
}

int mx_boundary_tags(const mx_mesh_view *v, const mx_tag_inputs *in, mx_boundary_faces *bf,
                     int32_t *cell_body, int *nbodies, int32_t **body_tag, size_t *off_input) {
  *nbodies = 0;
  *body_tag = NULL;
  *off_input = 0;
  bf->tri_tag = mx_alloc((bf->ntri + 1) * sizeof *bf->tri_tag);
  bf->quad_tag = mx_alloc((bf->nquad + 1) * sizeof *bf->quad_tag);
  if (!bf->tri_tag || !bf->quad_tag) return MX_ENOMEM;
  double lo[3], hi[3];
  mx_trisoup_bbox(in->soup, lo, hi);
  const double off_tol =
      1e-6 * sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                  (hi[2] - lo[2]) * (hi[2] - lo[2]));
  size_t off = 0;
  /* one input and no face off it: every face lies on input 1 (what
   * face_tag finds: the shell of a leaf's triangles or of the closest one
   * is that input's) */
  const int one = in->nshells == 1 && !in->check_off;
#pragma omp parallel for schedule(static) if (one)
  for (size_t i = 0; i < (one ? bf->ntri : 0); i++) bf->tri_tag[i] = 1;
#pragma omp parallel for schedule(static) if (one)
  for (size_t i = 0; i < (one ? bf->nquad : 0); i++) bf->quad_tag[i] = 1;
#pragma omp parallel for schedule(dynamic, 4096) reduction(+ : off)
  for (size_t i = 0; i < (one ? 0 : bf->ntri); i++) {
    bf->tri_tag[i] = face_tag(v, in, bf->tri + 3 * i, 3, (size_t)(bf->tri_src[i] >> 3), off_tol);
    off += bf->tri_tag[i] == in->nshells + 1;
  }
#pragma omp parallel for schedule(dynamic, 4096) reduction(+ : off)
  for (size_t i = 0; i < (one ? 0 : bf->nquad); i++) {
    bf->quad_tag[i] =
        face_tag(v, in, bf->quad + 4 * i, 4, (size_t)(bf->quad_src[i] >> 3), off_tol);
    off += bf->quad_tag[i] == in->nshells + 1;
  }
  *off_input = off;
  MX_CHECK(sort_list(bf->tri, bf->tri_src, bf->tri_tag, bf->ntri, 3, in->nshells + 1));
  MX_CHECK(sort_list(bf->quad, bf->quad_src, bf->quad_tag, bf->nquad, 4, in->nshells + 1));
  /* bodies (io/cell_order.c), each with its smallest boundary tag */
  int nb = 0;
  int st = mx_cell_bodies(v, cell_body, &nb);
  int32_t *bt = st ? NULL : mx_alloc(((size_t)nb + 1) * sizeof *bt);
  if (!st && !bt) st = MX_ENOMEM;
  if (!st) {
    for (int b = 0; b < nb; b++) bt[b] = INT32_MAX;
    for (size_t i = 0; i < bf->ntri; i++) {
      const int32_t b = cell_body[bf->tri_src[i] >> 3] - 1;
      if (b >= 0 && bf->tri_tag[i] < bt[b]) bt[b] = bf->tri_tag[i];
    }
    for (size_t i = 0; i < bf->nquad; i++) {
      const int32_t b = cell_body[bf->quad_src[i] >> 3] - 1;
      if (b >= 0 && bf->quad_tag[i] < bt[b]) bt[b] = bf->quad_tag[i];
    }
    *body_tag = bt;
    *nbodies = nb;
  }
  return st;
}

void mx_boundary_node_tags(const mx_boundary_faces *bf, size_t nnodes, int32_t *tag) {
  memset(tag, 0, nnodes * sizeof *tag);
  for (size_t i = 0; i < bf->ntri; i++)
    for (int k = 0; k < 3; k++) {
      int32_t *t = &tag[bf->tri[3 * i + (size_t)k]];
      if (*t == 0 || bf->tri_tag[i] < *t) *t = bf->tri_tag[i];
    }
  for (size_t i = 0; i < bf->nquad; i++)
    for (int k = 0; k < 4; k++) {
      int32_t *t = &tag[bf->quad[4 * i + (size_t)k]];
      if (*t == 0 || bf->quad_tag[i] < *t) *t = bf->quad_tag[i];
    }
}
