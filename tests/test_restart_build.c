/* The restart file a mesher writes (src/mesher/restart_octree.c) against
 * its definition, computed here the plain way: the nodes are all corners of
 * all stored octants, sorted by Morton key and unique; the edges are all 12
 * edges of all stored octants, per (level, axis), sorted and unique, each
 * with its ends and the node at its middle (0 when there is none) found by
 * binary search; the octants are the leaves in order with their 8 corners
 * in the published order. The writer emits each corner and edge once per
 * family and looks the nodes up by hashing: this catches any corner, edge
 * or id it gets wrong. Cases: the demo surface (octants dropped outside the
 * domain: parents with some children missing), with a level everywhere,
 * and an octree stage only; for 1 and 2 threads. */
#include "check.h"
#include "base/common.h"
#include "io/restart.h"
#include "mesher/mesher.h"
#include "mesher/mesher_impl.h"
#include "mixoct.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static int cmp_u64(const void *a, const void *b) {
  const uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
  return x < y ? -1 : x > y;
}

static size_t unique(uint64_t *k, size_t n) {
  qsort(k, n, sizeof *k, cmp_u64);
  size_t w = 0;
  for (size_t i = 0; i < n; i++)
    if (w == 0 || k[i] != k[w - 1]) k[w++] = k[i];
  return w;
}

static long find(const uint64_t *v, size_t n, uint64_t key) {
  size_t lo = 0, hi = n;
  while (lo < hi) {
    const size_t mid = (lo + hi) / 2;
    if (v[mid] < key) lo = mid + 1;
    else hi = mid;
  }
  return lo < n && v[lo] == key ? (long)lo : -1;
}

static uint64_t point(const uint32_t p[3], uint32_t dx, uint32_t dy, uint32_t dz) {
  return mx_morton_encode(p[0] + dx, p[1] + dy, p[2] + dz);
}

/* The published corner order as (x, y, z) bits. */
static const uint8_t corner_xyz[8][3] = {{0, 0, 0}, {0, 0, 1}, {1, 0, 1}, {1, 0, 0},
                                         {0, 1, 0}, {0, 1, 1}, {1, 1, 1}, {1, 1, 0}};

static void check_file(const mx_mesher *m, const char *path) {
  mx_restart r;
  CHECK(mx_restart_read(path, &r) == MX_OK);
  const mx_octree *T = &m->B.tree.oct;
  uint64_t *v = malloc(8 * T->n * sizeof *v);
  for (size_t o = 0; o < T->n; o++) {
    uint32_t p[3];
    mx_morton_decode(T->key[o], p);
    const uint32_t s = mx_octant_size(T->level[o]);
    for (int c = 0; c < 8; c++) v[8 * o + c] = point(p, (c & 1) * s, ((c >> 1) & 1) * s, (c >> 2) * s);
  }
  const size_t nv = unique(v, 8 * T->n);
  CHECK(r.nv == nv);
  /* coordinates: the lattice point's, through the grid, to the 9 digits kept */
  size_t bad_xyz = 0;
  for (size_t i = 0; i < nv && i < r.nv; i++) {
    uint32_t p[3];
    mx_morton_decode(v[i], p);
    for (int a = 0; a < 3; a++) { /* the file keeps 9 digits ("%+1.8E") */
      const double x = m->B.tree.grid.origin[a] + (double)p[a] * m->B.tree.grid.unit;
      bad_xyz += !(fabs(r.xyz[3 * i + a] - x) <= 5.0000001e-9 * fabs(x));
    }
  }
  CHECK(bad_xyz == 0);
  /* edges, level by level, axis by axis */
  uint64_t *ek = malloc(4 * T->n * sizeof *ek);
  size_t row = 0, bad_edge = 0;
  for (int l = 0; l <= MX_MAX_LEVEL; l++)
    for (int a = 0; a < 3; a++) {
      size_t n = 0;
      const uint32_t s = mx_octant_size(l);
      for (size_t o = 0; o < T->n; o++) {
        if (T->level[o] != l) continue;
        uint32_t p[3];
        mx_morton_decode(T->key[o], p);
        for (int j = 0; j < 4; j++) {
          uint32_t q[3] = {p[0], p[1], p[2]};
          q[(a + 1) % 3] += (uint32_t)(j & 1) * s;
          q[(a + 2) % 3] += (uint32_t)(j >> 1) * s;
          ek[n++] = point(q, 0, 0, 0);
        }
      }
      n = unique(ek, n);
      for (size_t i = 0; i < n; i++, row++) {
        if (row >= r.ne) {
          bad_edge++;
          continue;
        }
        uint32_t p[3], q[3], h[3];
        mx_morton_decode(ek[i], p);
        memcpy(q, p, sizeof q);
        memcpy(h, p, sizeof h);
        q[a] += s;
        h[a] += s / 2;
        const long ia = find(v, nv, ek[i]), ib = find(v, nv, point(q, 0, 0, 0));
        const long im = s > 1 ? find(v, nv, point(h, 0, 0, 0)) : -1;
        const uint32_t *e = r.edge + 3 * row;
        bad_edge += ia < 0 || ib < 0 || e[0] != (uint32_t)ia || e[1] != (uint32_t)ib ||
                    e[2] != (uint32_t)(im < 0 ? 0 : im);
      }
    }
  CHECK(row == r.ne && bad_edge == 0);
  /* octants: the leaves with their corners */
  CHECK(r.no == m->nleaves);
  size_t bad_oct = 0;
  for (size_t i = 0; i < r.no && i < m->nleaves; i++) {
    const uint32_t o = m->leaves[i];
    uint32_t p[3];
    mx_morton_decode(T->key[o], p);
    const uint32_t s = mx_octant_size(T->level[o]);
    for (int c = 0; c < 8; c++) {
      const long id = find(v, nv, point(p, corner_xyz[c][0] * s, corner_xyz[c][1] * s,
                                         corner_xyz[c][2] * s));
      bad_oct += id < 0 || r.oct_node[8 * i + c] != (uint32_t)id;
    }
    bad_oct += r.oct_level[i] != T->level[o];
  }
  CHECK(bad_oct == 0);
  printf("%s: %zu nodes, %zu edges, %zu octants (of %zu stored); %zu/%zu/%zu wrong\n", path,
         r.nv, r.ne, r.no, T->n, bad_xyz, bad_edge, bad_oct);
  free(ek);
  free(v);
  mx_restart_free(&r);
}

static void run(int s, int a, int stage, int threads, const char *name) {
  mx_params p;
  mx_params_default(&p);
  p.surface_level = s;
  p.all_level = a;
  p.stage = stage;
  p.threads = threads;
  mx_mesher *m = mx_mesher_new(&p);
  CHECK(m && mx_mesher_add_demo_surface(m) == MX_OK);
  CHECK(mx_mesher_mesh(m) == MX_OK);
  CHECK(mx_mesher_save_restart(m, name) == MX_OK);
  check_file(m, name);
  mx_mesher_free(m);
}

int main(void) {
  run(4, -1, MX_STAGE_FULL, 2, "rb_demo4.oct");
  run(5, 2, MX_STAGE_TRANSITION, 2, "rb_demo5.oct");
  run(5, 2, MX_STAGE_TRANSITION, 1, "rb_demo5_1.oct");
  run(3, 3, MX_STAGE_FULL, 1, "rb_demo3.oct");
  return TEST_DONE();
}
