#include "kernels/refine.h"

#include "common.h"
#include "soa/scan.h"

int mx_leaves_sorted(const mx_builder *B, uint32_t *leaves, size_t n) {
  uint64_t *k = mx_alloc((n + 1) * sizeof *k);
  if (!k) return MX_EINPUT;
#pragma omp parallel for schedule(static)
  for (size_t i = 0; i < n; i++) k[i] = B->oct.key[leaves[i]];
  int st = mx_sort_u64(k, leaves, n);
  mx_free(k);
  return st;
}

int mx_leaves(const mx_builder *B, uint32_t **out, size_t *n) {
  const mx_octree *T = &B->oct;
  size_t k = 0;
  for (size_t o = 0; o < T->n; o++) k += !(T->flags[o] & MX_OCT_SPLIT);
  uint32_t *l = mx_alloc((k + 1) * sizeof *l);
  if (!l) return MX_EINPUT;
  k = 0;
  for (size_t o = 0; o < T->n; o++)
    if (!(T->flags[o] & MX_OCT_SPLIT)) l[k++] = (uint32_t)o;
  *out = l;
  *n = k;
  return MX_OK;
}

static inline uint64_t mix64(uint64_t x) {
  x ^= x >> 30;
  x *= 0xbf58476d1ce4e5b9ULL;
  x ^= x >> 27;
  x *= 0x94d049bb133111ebULL;
  x ^= x >> 31;
  return x;
}

uint64_t mx_leaves_hash(const mx_builder *B, const uint32_t *leaves,
                        size_t n) {
  const mx_octree *T = &B->oct;
  uint64_t *k = mx_alloc((n + 1) * sizeof *k);
  if (!k) return 0;
  for (size_t i = 0; i < n; i++) k[i] = T->key[leaves[i]];
  /* Leaf keys are unique (two leaves never share an anchor), so sorting the
   * keys alone orders the (key, level) pairs; levels are folded in below. */
  uint32_t *lv = mx_alloc((n + 1) * sizeof *lv);
  if (!lv) {
    mx_free(k);
    return 0;
  }
  for (size_t i = 0; i < n; i++) lv[i] = T->level[leaves[i]];
  uint64_t h = 0x6a09e667f3bcc908ULL ^ n;
  if (mx_sort_u64(k, lv, n) == MX_OK)
    for (size_t i = 0; i < n; i++) h = mix64(h ^ mix64(k[i] * 32 + lv[i]));
  mx_free(k);
  mx_free(lv);
  return h;
}

int mx_leaf_hex_mesh(const mx_builder *B, const uint32_t *leaves, size_t n,
                     mx_hexmesh *out) {
  const mx_octree *T = &B->oct;
  const size_t m = 8 * n;
  uint64_t *k = mx_alloc((m + 1) * sizeof *k);
  uint32_t *slot = mx_alloc((m + 1) * sizeof *slot);
  out->conn = mx_alloc((m + 1) * sizeof *out->conn);
  out->level = mx_alloc((n + 1) * sizeof *out->level);
  out->xyz = NULL;
  if (!k || !slot || !out->conn || !out->level) goto oom;
  /* VTK hexahedron corner order. */
  static const int corner[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0},
                                   {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
#pragma omp parallel for schedule(static)
  for (size_t i = 0; i < n; i++) {
    uint32_t c[3];
    mx_morton_decode(T->key[leaves[i]], c);
    const uint32_t s = mx_octant_size(T->level[leaves[i]]);
    for (int j = 0; j < 8; j++) {
      k[8 * i + j] = mx_lattice_key(c[0] + s * corner[j][0],
                                    c[1] + s * corner[j][1],
                                    c[2] + s * corner[j][2]);
      slot[8 * i + j] = (uint32_t)(8 * i + j);
    }
    out->level[i] = T->level[leaves[i]];
  }
  if (mx_sort_u64(k, slot, m)) goto oom;
  /* Nodes numbered in Morton order of their lattice points. */
  size_t nn = 0;
  for (size_t i = 0; i < m; i++) {
    if (i > 0 && k[i] != k[i - 1]) nn++;
    out->conn[slot[i]] = (uint32_t)nn;
  }
  nn = m ? nn + 1 : 0;
  out->xyz = mx_alloc((3 * nn + 1) * sizeof *out->xyz);
  if (!out->xyz) goto oom;
  for (size_t i = 0, id = 0; i < m; i++) {
    if (i > 0 && k[i] == k[i - 1]) continue;
    uint32_t c[3];
    mx_morton_decode(k[i], c);
    for (int a = 0; a < 3; a++)
      out->xyz[3 * id + a] = B->grid.origin[a] + (double)c[a] * B->grid.unit;
    id++;
  }
  out->nnodes = nn;
  out->ncells = n;
  mx_free(k);
  mx_free(slot);
  return MX_OK;
oom:
  mx_free(k);
  mx_free(slot);
  mx_hexmesh_free(out);
  return MX_EINPUT;
}

void mx_hexmesh_free(mx_hexmesh *h) {
  mx_free(h->xyz);
  mx_free(h->conn);
  mx_free(h->level);
  h->xyz = NULL;
  h->conn = NULL;
  h->level = NULL;
}
