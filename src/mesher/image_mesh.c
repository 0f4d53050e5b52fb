/* A label image's mesh (issue 28; mesher_impl.h, mx_image_mesh_finish). The
 * octree was built on the image's lattice (mesher/image_input.c: every leaf
 * a block of one label, voxels at the interfaces), so the transition
 * stage's elements each lie in one label and every interface runs along
 * their faces. Here:
 *   1. each element takes its leaf's label (the voxel at the leaf's low
 *      corner), the background's elements go;
 *   2. the interfaces' corners smoothed (geom/label_surface.h): a node at
 *      such a lattice corner moves where the smoothing put it (within 0.35
 *      voxel on each axis), unless --voxel; where an element around a moved
 *      node would fall below J_ENS 0.1 (or half its unmoved value), the
 *      moves of its nodes are halved, six times, then undone until none is;
 *   3. the voxel units to the world by the image's transform (a mirror
 *      turns the elements' node order over);
 *   4. each label's volume against its voxels': off by more than half a
 *      voxel across its interface (its voxel faces) is a defect. */
#include <math.h>
#include <string.h>

#include "base/common.h"
#include "base/morton.h"
#include "geom/affine.h"
#include "geom/label_surface.h"
#include "geom/quality.h"
#include "kernels/boundary.h"
#include "kernels/mesh_edit.h"
#include "mesher/mesher_impl.h"

/* The label of each element's leaf; 0 outside the image. */
static int32_t leaf_label(const mx_mesher *m, uint32_t leaf) {
  const uint32_t o = m->leaves[leaf];
  uint32_t c[3];
  mx_morton_decode(m->B.tree.oct.key[o], c);
  const int64_t *n = m->image_n;
  int64_t v[3];
  for (int a = 0; a < 3; a++) {
    v[a] = (int64_t)(c[a] >> (MX_MAX_LEVEL - m->image_R));
    if (v[a] >= n[a] - 2) return 0;
  }
  return m->image_lab[(v[0] + 1) + n[0] * ((v[1] + 1) + n[1] * (v[2] + 1))];
}

/* The padded lattice corner a node (in voxel units) stands on: corner c is
 * at c - 1.5 on each axis; 0 when the node is on none. */
static int node_corner(const double *x, const int64_t n[3], int64_t c[3]) {
  for (int a = 0; a < 3; a++) {
    const double y = x[a] + 1.5;
    c[a] = (int64_t)y;
    if (!(y == (double)c[a] && c[a] >= 1 && c[a] < n[a])) return 0;
  }
  return 1;
}

static double cell_jens(const mx_mesh *M, size_t c, const double *xyz) {
  double p[8][3];
  const int nv = mx_cell_nodes[M->type[c]];
  for (int k = 0; k < nv; k++)
    for (int a = 0; a < 3; a++) p[k][a] = xyz[3 * (size_t)M->conn[8 * c + k] + a];
  return mx_jens(M->type[c], (const double(*)[3])p);
}

/* Nodes onto the smoothed interfaces, as far as the elements allow. */
static int move_nodes(mx_mesher *m, size_t *moved_out) {
  mx_mesh *M = &m->M;
  mx_label_surface S;
  MX_CHECK(mx_label_surface_build(m->image_lab, m->image_n, m->image_rounds, 0.35, &S));
  const size_t nn = M->nnodes;
  double *d = mx_calloc((3 * nn + 1) * sizeof *d);
  double *x = mx_alloc((3 * nn + 1) * sizeof *x);
  uint8_t *mv = mx_calloc(nn + 1);
  uint8_t *bad = mx_alloc(M->ncells + 1);
  float *j0 = NULL, *jb = NULL; /* per band element: the transition's J_ENS, the last measured */
  uint32_t *band = NULL;
  int st = d && x && mv && bad ? MX_OK : MX_ENOMEM;
  const int64_t *n = m->image_n;
  size_t moved = 0;
  if (st) {
    mx_label_surface_free(&S);
    goto done;
  }
#pragma omp parallel for schedule(static) reduction(+ : moved)
  for (size_t v = 0; v < nn; v++) {
    int64_t c[3];
    if (!node_corner(M->xyz + 3 * v, n, c)) continue;
    const int64_t id = c[0] + n[0] * (c[1] + n[1] * c[2]);
    size_t lo = 0, hi = S.nv;
    while (lo < hi) {
      const size_t mid = (lo + hi) / 2;
      if (S.corner[mid] < id)
        lo = mid + 1;
      else
        hi = mid;
    }
    if (lo == S.nv || S.corner[lo] != id) continue;
    for (int a = 0; a < 3; a++) d[3 * v + a] = S.lat[3 * lo + a] - (double)c[a];
    mv[v] = 1;
    moved++;
  }
  mx_label_surface_free(&S);
  /* the elements around a moved node, once */
  size_t nb = 0;
#pragma omp parallel for schedule(static) reduction(+ : nb)
  for (size_t c = 0; c < M->ncells; c++) {
    int any = 0;
    for (int q = 0; q < mx_cell_nodes[M->type[c]]; q++) any |= mv[M->conn[8 * c + q]];
    bad[c] = (uint8_t)any;
    nb += (size_t)any;
  }
  band = mx_alloc((nb + 1) * sizeof *band);
  j0 = mx_alloc((nb + 1) * sizeof *j0);
  jb = mx_alloc((nb + 1) * sizeof *jb);
  if (!band || !j0 || !jb) {
    st = MX_ENOMEM;
    goto done;
  }
  nb = 0;
  for (size_t c = 0; c < M->ncells; c++)
    if (bad[c]) band[nb++] = (uint32_t)c;
#pragma omp parallel for schedule(static)
  for (size_t b = 0; b < nb; b++) j0[b] = M->jens[band[b]]; /* the transition's */
  memcpy(x, M->xyz, 3 * nn * sizeof *x);
  /* halve the moves around elements that would be poor (six times), then
   * undo them until none is left (an undone move can leave a neighbour
   * poor: its turn next round; each round undoes at least one, so this
   * ends); each round measures again only the elements with a node just
   * changed (mv 2), the others keep their verdict */
  for (int round = 0;; round++) {
#pragma omp parallel for schedule(static)
    for (size_t v = 0; v < nn; v++)
      if (round == 0 ? mv[v] != 0 : mv[v] == 2)
        for (int a = 0; a < 3; a++) x[3 * v + a] = M->xyz[3 * v + a] + d[3 * v + a];
    size_t nbad = 0;
#pragma omp parallel for schedule(static) reduction(+ : nbad)
    for (size_t b = 0; b < nb; b++) {
      const size_t c = band[b];
      if (round > 0) {
        int changed = 0;
        for (int q = 0; q < mx_cell_nodes[M->type[c]] && !changed; q++)
          changed = mv[M->conn[8 * c + q]] == 2;
        if (!changed) {
          bad[b] = 0;
          continue;
        }
      }
      const double floor_q = j0[b] < 0.1f ? 0.5 * j0[b] : 0.1;
      const double q = cell_jens(M, c, x);
      bad[b] = q < floor_q;
      nbad += bad[b];
      jb[b] = (float)q;
    }
#pragma omp parallel for schedule(static)
    for (size_t v = 0; v < nn; v++) mv[v] = mv[v] ? 1 : 0;
    if (!nbad) break;
    const double f = round >= 6 ? 0.0 : 0.5;
    for (size_t b = 0; b < nb; b++) /* serial: nodes shared */
      if (bad[b]) {
        const size_t c = band[b];
        for (int q = 0; q < mx_cell_nodes[M->type[c]]; q++) {
          const uint32_t v = M->conn[8 * c + q];
          if (mv[v] == 1) {
            mv[v] = 2; /* once per round */
            for (int a = 0; a < 3; a++) d[3 * (size_t)v + a] *= f;
          }
        }
      }
  }
  /* the last round measured every element whose nodes it changed: the
   * positions and J_ENS (in voxel units) as they stand */
#pragma omp parallel for schedule(static)
  for (size_t b = 0; b < nb; b++) M->jens[band[b]] = jb[b];
  memcpy(M->xyz, x, 3 * nn * sizeof *x);
done:
  mx_free(band);
  mx_free(jb);
  mx_free(j0);
  mx_free(d);
  mx_free(x);
  mx_free(bad);
  mx_free(mv);
  if (!st) *moved_out = moved;
  return st;
}

/* Voxel units to the world; a mirror turns each element over. */
static void to_world(mx_mesher *m) {
  mx_mesh *M = &m->M;
  const double *A = m->image_A;
#pragma omp parallel for schedule(static)
  for (size_t v = 0; v < M->nnodes; v++) {
    const double u[3] = {M->xyz[3 * v], M->xyz[3 * v + 1], M->xyz[3 * v + 2]};
    mx_affine_apply(A, u, M->xyz + 3 * v);
  }
  if (mx_affine_det(A) > 0) return;
  /* the mirrored order of each type (tet 0 2 1 3, pyramid 0 3 2 1 4, prism
   * and hexahedron: the two end faces exchanged) */
  static const int8_t perm[4][8] = {{0, 2, 1, 3}, {0, 3, 2, 1, 4}, {3, 4, 5, 0, 1, 2},
                                    {4, 5, 6, 7, 0, 1, 2, 3}};
#pragma omp parallel for schedule(static)
  for (size_t c = 0; c < M->ncells; c++) {
    const int t = M->type[c], nv = mx_cell_nodes[t];
    const int ti = t == MX_TET ? 0 : t == MX_PYRAMID ? 1 : t == MX_PRISM ? 2 : 3;
    uint32_t o[8];
    for (int k = 0; k < nv; k++) o[k] = M->conn[8 * c + perm[ti][k]];
    memcpy(M->conn + 8 * c, o, (size_t)nv * sizeof *o);
  }
}

int mx_image_mesh_finish(mx_mesher *m) {
  const double t0 = mx_wtime();
  mx_mesh *M = &m->M;
  const int nl = m->image.nlabels;
  uint8_t *keep = mx_alloc(M->ncells + 1);
  uint16_t *mat = mx_alloc((M->ncells + 1) * sizeof *mat);
  if (!keep || !mat) {
    mx_free(keep);
    mx_free(mat);
    return MX_ENOMEM;
  }
#pragma omp parallel for schedule(static)
  for (size_t c = 0; c < M->ncells; c++) {
    const int32_t L = leaf_label(m, M->leaf[c]);
    keep[c] = L != 0;
    mat[c] = (uint16_t)L;
  }
  size_t k = 0;
  for (size_t c = 0; c < M->ncells; c++)
    if (keep[c]) mat[k++] = mat[c];
  int st = mx_mesh_keep_cells(M, keep);
  mx_free(keep);
  if (!st) st = mx_mesh_drop_unused_nodes(M, NULL, NULL);
  if (st) {
    mx_free(mat);
    return st;
  }
  mx_free(M->material);
  M->material = mat;
  /* the boundary nodes: lattice corners with background and a label among
   * their 8 voxels (every face between the two runs along voxel faces, and
   * its nodes are such corners) */
  mx_free(m->states);
  m->states = mx_alloc(M->nnodes + 1);
  if (!m->states) return MX_ENOMEM;
  {
    const int64_t *n = m->image_n;
    const int32_t *lab = m->image_lab;
#pragma omp parallel for schedule(static)
    for (size_t v = 0; v < M->nnodes; v++) {
      int64_t c[3];
      const int corner = node_corner(M->xyz + 3 * v, n, c);
      int zero = 0, label = 0;
      for (int b = 0; b < 8 && corner; b++) {
        const int32_t L = lab[(c[0] - 1 + (b & 1)) + n[0] * ((c[1] - 1 + ((b >> 1) & 1)) +
                                                              n[1] * (c[2] - 1 + (b >> 2)))];
        zero |= L == 0;
        label |= L != 0;
      }
      m->states[v] = zero && label ? MX_NODE_OUTSIDE : MX_NODE_INSIDE;
    }
  }
  size_t moved = 0;
  if (m->image_rounds > 0) MX_CHECK(move_nodes(m, &moved));
  to_world(m);
  /* J_ENS does not change under a similarity: the moves' rounds measured
   * the elements they moved; otherwise every element is measured again */
  if (!mx_affine_similar(m->image_A)) mx_mesh_update_jens(M, NULL);
  mx_mesh_summarize(M);
  m->nmaterials = nl;
  m->rec->S.nmaterials = nl;
  m->rec->S.materials_across = 0;
  m->image.moved = moved;
  /* each label's volume against its voxels' */
  double vol[64] = {0};
  uint8_t *slot = mx_calloc(65536); /* label -> its index */
  if (!slot) return MX_ENOMEM;
  for (int l = 0; l < nl; l++) slot[m->image.labels[l]] = (uint8_t)l;
#pragma omp parallel for schedule(static) reduction(+ : vol[:64])
  for (size_t c = 0; c < M->ncells; c++) {
    double p[8][3];
    const int nv = mx_cell_nodes[M->type[c]];
    for (int q = 0; q < nv; q++)
      for (int a = 0; a < 3; a++) p[q][a] = M->xyz[3 * (size_t)M->conn[8 * c + q] + a];
    vol[slot[M->material[c]]] += mx_element_volume(M->type[c], (const double(*)[3])p);
  }
  mx_free(slot);
  const double *A = m->image_A;
  const double vox = fabs(mx_affine_det(A));
  for (int l = 0; l < nl; l++) {
    m->image.volume[l] = vol[l];
    const double want = (double)m->image.voxels[l] * vox;
    const double band = 0.5 * (double)m->image.faces[l] * vox;
    if (fabs(vol[l] - want) > band) {
      mx_error(m->domain_name[0], 0, "label %d: the mesh holds %.6g against %.6g for its voxels, "
                                     "beyond half a voxel across its interface (%.6g)",
               (int)m->image.labels[l], vol[l], want, band);
      return MX_EINVALID;
    }
  }
  m->image.seconds_mesh = mx_wtime() - t0;
  m->rec->S.ph.boundary += m->image.seconds_mesh; /* the interfaces' stage */
  m->image.voxel_volume = vox;
  m->rec->S.image = &m->image;
  m->mesh_stage = MX_STAGE_FULL; /* the domain's mesh: its boundary and interfaces are final */
  m->rec->S.max_level = m->image_R;
  return MX_OK;
}
