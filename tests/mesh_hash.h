/* A hash of everything a mesher's arrays hold (include/mixoct.h), for the
 * tests that compare two runs that must give the same mesh (threads, two
 * meshers at once, a run after an allocation failure). */
#ifndef MX_TEST_MESH_HASH_H
#define MX_TEST_MESH_HASH_H
#include <stddef.h>
#include <stdint.h>

#include "mixoct.h"

/* FNV-1a over n bytes, from h (start: TEST_FNV_START). */
#define TEST_FNV_START 14695981039346656037ull
static inline uint64_t test_fnv(uint64_t h, const void *p, size_t n) {
  const unsigned char *b = p;
  for (size_t i = 0; i < n; i++) h = (h ^ b[i]) * 1099511628211ull;
  return h;
}

/* Nodes, types, connectivity, J_ENS, leaves and boundary flags; 0 when the
 * mesher has no mesh. */
static inline uint64_t test_mesh_hash(const mx_mesher *m) {
  mx_mesh_arrays a;
  if (mx_mesher_mesh_arrays(m, &a) != MX_OK) return 0;
  uint64_t h = TEST_FNV_START;
  h = test_fnv(h, a.xyz, 3 * a.nnodes * sizeof *a.xyz);
  h = test_fnv(h, a.type, a.nelements);
  h = test_fnv(h, a.conn, 8 * a.nelements * sizeof *a.conn);
  h = test_fnv(h, a.jens, a.nelements * sizeof *a.jens);
  h = test_fnv(h, a.leaf, a.nelements * sizeof *a.leaf);
  if (a.boundary) h = test_fnv(h, a.boundary, a.nnodes);
  return h;
}

/* The same in 2D: nodes, types, connectivity, leaves. */
static inline uint64_t test_mesh2d_hash(const mx_mesher2d *m) {
  mx_mesh2d_arrays a;
  if (mx_mesher2d_mesh_arrays(m, &a) != MX_OK) return 0;
  uint64_t h = TEST_FNV_START;
  h = test_fnv(h, a.xy, 2 * a.nnodes * sizeof *a.xy);
  h = test_fnv(h, a.type, a.ncells);
  h = test_fnv(h, a.conn, 4 * a.ncells * sizeof *a.conn);
  h = test_fnv(h, a.leaf, a.ncells * sizeof *a.leaf);
  return h;
}
#endif
