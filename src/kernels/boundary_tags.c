#include "kernels/boundary_tags.h"

#include <math.h>
#include <string.h>

#include "common.h"
#include "soa/octree.h"

/* The shell of the domain triangles leaf octant o meets when they all come
 * from one file; -1 when it meets none or several. */
static int leaf_shell(const mx_tag_inputs *in, uint32_t o) {
  const mx_octree *T = &in->B->oct;
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

/* Union-find over nodes, linking the larger root under the smaller, so the
 * root of every set is its smallest node whatever the thread count. */
static uint32_t uf_find(uint32_t *p, uint32_t a) {
  for (;;) {
    const uint32_t q = __atomic_load_n(&p[a], __ATOMIC_RELAXED);
    if (q == a) return a;
    const uint32_t r = __atomic_load_n(&p[q], __ATOMIC_RELAXED);
    if (r != q) __atomic_compare_exchange_n(&p[a], &(uint32_t){q}, r, 0, __ATOMIC_RELAXED,
                                            __ATOMIC_RELAXED);
    a = q;
  }
}

static void uf_union(uint32_t *p, uint32_t a, uint32_t b) {
  for (;;) {
    a = uf_find(p, a);
    b = uf_find(p, b);
    if (a == b) return;
    if (a < b) {
      const uint32_t t = a;
      a = b;
      b = t;
    }
    uint32_t expect = a;
    if (__atomic_compare_exchange_n(&p[a], &expect, b, 0, __ATOMIC_ACQ_REL, __ATOMIC_RELAXED))
      return;
  }
}

int mx_boundary_tags(const mx_mesh_view *v, const mx_tag_inputs *in, mx_boundary_faces *bf,
                     int32_t *cell_body, int *nbodies, int32_t **body_tag, size_t *off_input) {
  *nbodies = 0;
  *body_tag = NULL;
  *off_input = 0;
  const size_t nn = v->nnodes, nc = v->ncells;
  bf->tri_tag = mx_alloc((bf->ntri + 1) * sizeof *bf->tri_tag);
  bf->quad_tag = mx_alloc((bf->nquad + 1) * sizeof *bf->quad_tag);
  uint32_t *root = mx_alloc((nn + 1) * sizeof *root);
  if (!bf->tri_tag || !bf->quad_tag || !root) {
    mx_free(root);
    return MX_EINPUT;
  }
  double lo[3], hi[3];
  mx_trisoup_bbox(in->soup, lo, hi);
  const double off_tol =
      1e-6 * sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                  (hi[2] - lo[2]) * (hi[2] - lo[2]));
  size_t off = 0;
#pragma omp parallel for schedule(dynamic, 4096) reduction(+ : off)
  for (size_t i = 0; i < bf->ntri; i++) {
    bf->tri_tag[i] = face_tag(v, in, bf->tri + 3 * i, 3, (size_t)(bf->tri_src[i] >> 3), off_tol);
    off += bf->tri_tag[i] == in->nshells + 1;
  }
#pragma omp parallel for schedule(dynamic, 4096) reduction(+ : off)
  for (size_t i = 0; i < bf->nquad; i++) {
    bf->quad_tag[i] =
        face_tag(v, in, bf->quad + 4 * i, 4, (size_t)(bf->quad_src[i] >> 3), off_tol);
    off += bf->quad_tag[i] == in->nshells + 1;
  }
  *off_input = off;
  /* bodies: the components of the element-node graph */
#pragma omp parallel for schedule(static)
  for (size_t i = 0; i < nn; i++) root[i] = (uint32_t)i;
#pragma omp parallel for schedule(static)
  for (size_t c = 0; c < nc; c++) {
    const uint32_t *row = v->conn + 8 * c;
    for (int k = 1; k < mx_cell_nodes[v->type[c]]; k++) uf_union(root, row[0], row[k]);
  }
#pragma omp parallel for schedule(static)
  for (size_t i = 0; i < nn; i++) root[i] = uf_find(root, (uint32_t)i);
  /* each root's smallest boundary tag (kept in cell_body's place first:
   * per root node, through a node array) */
  int32_t *mint = mx_alloc((nn + 1) * sizeof *mint);
  if (!mint) {
    mx_free(root);
    return MX_EINPUT;
  }
#pragma omp parallel for schedule(static)
  for (size_t i = 0; i < nn; i++) mint[i] = INT32_MAX;
  for (size_t i = 0; i < bf->ntri; i++) {
    const uint32_t r = root[bf->tri[3 * i]];
    if (bf->tri_tag[i] < mint[r]) mint[r] = bf->tri_tag[i];
  }
  for (size_t i = 0; i < bf->nquad; i++) {
    const uint32_t r = root[bf->quad[4 * i]];
    if (bf->quad_tag[i] < mint[r]) mint[r] = bf->quad_tag[i];
  }
  /* number the bodies: roots in order of (smallest tag, root id) */
  size_t nroots = 0;
  for (size_t i = 0; i < nn; i++) nroots += root[i] == i && mint[i] != INT32_MAX;
  uint64_t *key = mx_alloc((nroots + 1) * sizeof *key);
  if (!key) {
    mx_free(mint);
    mx_free(root);
    return MX_EINPUT;
  }
  size_t k = 0;
  for (size_t i = 0; i < nn; i++)
    if (root[i] == i && mint[i] != INT32_MAX) key[k++] = (uint64_t)mint[i] << 32 | i;
  for (size_t i = 1; i < k; i++) /* few bodies: insertion sort */
    for (size_t j = i; j > 0 && key[j - 1] > key[j]; j--) {
      const uint64_t t = key[j];
      key[j] = key[j - 1];
      key[j - 1] = t;
    }
  int32_t *bt = mx_alloc((k + 1) * sizeof *bt);
  if (!bt) {
    mx_free(key);
    mx_free(mint);
    mx_free(root);
    return MX_EINPUT;
  }
  for (size_t b = 0; b < k; b++) bt[b] = (int32_t)(key[b] >> 32);
  *body_tag = bt;
  for (size_t i = 0; i < nn; i++) mint[i] = 0;
  for (size_t b = 0; b < k; b++) mint[(uint32_t)key[b]] = (int32_t)(b + 1);
#pragma omp parallel for schedule(static)
  for (size_t c = 0; c < nc; c++) cell_body[c] = mint[root[v->conn[8 * c]]];
  *nbodies = (int)k;
  mx_free(key);
  mx_free(mint);
  mx_free(root);
  return MX_OK;
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
