#include "kernels/leaves.h"

#include "base/common.h"
#include "base/scan.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "geom/intersect.h"
#include "soa/grid.h"

int mx_leaves_sorted(const mx_tree *tr, uint32_t *leaves, size_t n) {
  uint64_t *k = mx_alloc((n + 1) * sizeof *k);
  if (!k) return MX_ENOMEM;
#pragma omp parallel for schedule(static)
  for (size_t i = 0; i < n; i++) k[i] = tr->oct.key[leaves[i]];
  int st = mx_sort_u64(k, leaves, n);
  mx_free(k);
  return st;
}

int mx_leaves(const mx_tree *tr, uint32_t **out, size_t *n) {
  const mx_octree *T = &tr->oct;
  const size_t nb = (T->n + 4095) / 4096; /* blocks of octants */
  uint64_t *off = mx_alloc((nb + 1) * sizeof *off);
  if (!off) return MX_ENOMEM;
#pragma omp parallel for schedule(static)
  for (size_t b = 0; b < nb; b++) {
    uint64_t k = 0;
    for (size_t o = 4096 * b; o < T->n && o < 4096 * (b + 1); o++)
      k += !(T->flags[o] & MX_OCT_SPLIT);
    off[b] = k;
  }
  const uint64_t total = mx_scan_u64(off, nb);
  uint32_t *l = mx_alloc((total + 1) * sizeof *l);
  if (!l) {
    mx_free(off);
    return MX_ENOMEM;
  }
#pragma omp parallel for schedule(static)
  for (size_t b = 0; b < nb; b++) {
    uint64_t w = off[b];
    for (size_t o = 4096 * b; o < T->n && o < 4096 * (b + 1); o++)
      if (!(T->flags[o] & MX_OCT_SPLIT)) l[w++] = (uint32_t)o;
  }
  mx_free(off);
  *out = l;
  *n = total;
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

uint64_t mx_leaf_hash_term(uint64_t key, int level) {
  return mix64(mix64(key) ^ (uint64_t)level);
}

uint64_t mx_leaf_hash_finish(uint64_t sum, uint64_t n) { return mix64(sum ^ n); }

uint64_t mx_leaves_hash(const mx_tree *tr, const uint32_t *leaves,
                        size_t n) {
  /* A set hash: the sum of a strong mix of each (key, level) pair. Leaf keys
   * are unique, so it fingerprints the set of leaves whatever their order,
   * with no sort, in parallel. */
  const mx_octree *T = &tr->oct;
  uint64_t h = 0;
#pragma omp parallel for schedule(static) reduction(+ : h)
  for (size_t i = 0; i < n; i++)
    h += mx_leaf_hash_term(T->key[leaves[i]], T->level[leaves[i]]);
  return mx_leaf_hash_finish(h, (uint64_t)n);
}

int mx_leaf_hex_mesh(const mx_tree *tr, const uint32_t *leaves, size_t n, mx_mesh *out) {
  memset(out, 0, sizeof *out);
  const mx_octree *T = &tr->oct;
  const size_t m = 8 * n;
  uint64_t *k = mx_alloc((m + 1) * sizeof *k);
  uint32_t *slot = mx_alloc((m + 1) * sizeof *slot);
  out->conn = mx_alloc((m + 1) * sizeof *out->conn);
  out->level = mx_alloc((n + 1) * sizeof *out->level);
  out->type = mx_alloc(n + 1);
  out->leaf = mx_alloc((n + 1) * sizeof *out->leaf);
  if (!k || !slot || !out->conn || !out->level || !out->type || !out->leaf) goto oom;
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
    out->type[i] = MX_HEX;
    out->leaf[i] = (uint32_t)i;
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
  out->nkey = mx_alloc((nn + 1) * sizeof *out->nkey);
  if (!out->xyz || !out->nkey) goto oom;
  for (size_t i = 0, id = 0; i < m; i++) {
    if (i > 0 && k[i] == k[i - 1]) continue;
    out->nkey[id] = k[i];
    uint32_t c[3];
    mx_morton_decode(k[i], c);
    for (int a = 0; a < 3; a++)
      out->xyz[3 * id + a] = tr->grid.origin[a] + (double)c[a] * tr->grid.unit;
    id++;
  }
  out->nnodes = nn;
  out->ncells = n;
  out->by_type[MX_HEX] = n;
  out->jens_min = n ? 1.0 : 0.0; /* cubes */
  mx_free(k);
  mx_free(slot);
  return MX_OK;
oom:
  mx_free(k);
  mx_free(slot);
  mx_mesh_free(out);
  return MX_ENOMEM;
}


/* Triangle v (9 coordinates) lies in the plane of a face of box [lo, hi],
 * within eps. */
static int in_face_plane(const double *v, const double lo[3], const double hi[3], double eps) {
  for (int a = 0; a < 3; a++)
    if (v[a] == v[3 + a] && v[a] == v[6 + a] &&
        (fabs(v[a] - lo[a]) <= eps || fabs(v[a] - hi[a]) <= eps))
      return 1;
  return 0;
}

static int cmp_double(const void *pa, const void *pb) {
  const double a = *(const double *)pa, b = *(const double *)pb;
  return (a > b) - (a < b);
}

/* Whether sorted values p[0..n) hold one within eps of x. */
static int near_value(const double *p, size_t n, double x, double eps) {
  size_t a = 0, b = n;
  while (a < b) { /* the first >= x - eps */
    const size_t c = a + (b - a) / 2;
    if (p[c] < x - eps) a = c + 1;
    else b = c;
  }
  return a < n && p[a] <= x + eps;
}

int mx_leaves_meeting(const mx_tree *tr, const uint32_t *leaves, size_t n, uint8_t *meets) {
  const mx_octree *T = &tr->oct;
  /* the axis planes holding a domain triangle, per axis, sorted (none for
   * a curved input: then the lists alone) */
  const size_t nt = tr->nt_domain;
  double *plane = mx_alloc((3 * nt + 1) * sizeof *plane); /* (pages touched: the flat ones) */
  if (!plane) return MX_ENOMEM;
  size_t np[3] = {0, 0, 0};
  double *pa[3] = {plane, plane, plane};
  size_t total = 0;
  for (int a = 0; a < 3; a++) {
    pa[a] = plane + total;
    for (size_t t = 0; t < nt; t++) {
      const double *v = tr->tri_xyz + 9 * t;
      if (v[a] == v[3 + a] && v[a] == v[6 + a]) pa[a][np[a]++] = v[a], total++;
    }
    qsort(pa[a], np[a], sizeof *pa[a], cmp_double);
  }
#pragma omp parallel for schedule(dynamic, 4096)
  for (size_t i = 0; i < n; i++) {
    const uint32_t o = leaves[i];
    int m = T->tri_cnt[o] > 0;
    if (!m && total) {
      double lo[3], hi[3];
      mx_octant_box(&tr->grid, T->key[o], T->level[o], lo, hi);
      const double eps = 1e-9 * (hi[0] - lo[0]);
      /* the faces lying in such a plane: bit 2a (low) and 2a + 1 (high) */
      unsigned touch = 0;
      for (int a = 0; a < 3; a++) {
        touch |= (unsigned)near_value(pa[a], np[a], lo[a], eps) << (2 * a);
        touch |= (unsigned)near_value(pa[a], np[a], hi[a], eps) << (2 * a + 1);
      }
      double c[3], h[3];
      for (int a = 0; a < 3; a++) {
        c[a] = 0.5 * (lo[a] + hi[a]);
        h[a] = 0.5 * (hi[a] - lo[a]) + eps;
      }
      /* the ancestors' lists, up to the first whose box holds each of those
       * planes inside (its list has their triangles there: the plane does
       * not pass along its faces); the ones between may have missed them
       * by rounding as the leaf did */
      for (uint32_t p = T->parent[o]; touch && !m && p != MX_NONE; p = T->parent[p]) {
        const uint32_t *tl = T->tri_pool + T->tri_off[p];
        for (uint32_t j = 0; j < T->tri_cnt[p] && !m; j++) {
          if (tl[j] >= nt) continue; /* a region surface's */
          const double *v = tr->tri_xyz + 9 * (size_t)tl[j];
          m = in_face_plane(v, lo, hi, eps) && mx_tri_box_overlap(c, h, v);
        }
        double plo[3], phi[3];
        mx_octant_box(&tr->grid, T->key[p], T->level[p], plo, phi);
        const double peps = 1e-9 * (phi[0] - plo[0]);
        int inside = 1;
        for (int a = 0; a < 3; a++) {
          if ((touch >> (2 * a) & 1) && !(plo[a] < lo[a] - peps)) inside = 0;
          if ((touch >> (2 * a + 1) & 1) && !(phi[a] > hi[a] + peps)) inside = 0;
        }
        if (inside) break;
      }
    }
    meets[i] = (uint8_t)m;
  }
  mx_free(plane);
  return MX_OK;
}
