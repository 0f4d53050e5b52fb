/* Morton keys on the finest lattice.
 *
 * The root grid is at most 31 cubes per axis; each root cube spans
 * 2^MX_MAX_LEVEL lattice units. A lattice coordinate therefore fits in
 * MX_COORD_BITS = 21 bits, and a key interleaves the three coordinates
 * (x in bit 0, y in bit 1, z in bit 2, then x in bit 3, ...) into 63 bits.
 * An octant is keyed by its anchor (lowest corner) and its level; sorting
 * leaf keys gives Morton (z-curve) order across the whole grid. */
#ifndef MX_MORTON_H
#define MX_MORTON_H

#include <stdint.h>

#include "mixoct.h" /* MX_MAX_LEVEL */
#define MX_COORD_BITS 21
#define MX_MAX_ROOTS_PER_AXIS 31

/* Spread the low 21 bits of v so that bit i lands at bit 3*i. */
static inline uint64_t mx_morton_spread(uint64_t v) {
  v &= 0x1fffff;
  v = (v | (v << 32)) & 0x1f00000000ffffULL;
  v = (v | (v << 16)) & 0x1f0000ff0000ffULL;
  v = (v | (v << 8)) & 0x100f00f00f00f00fULL;
  v = (v | (v << 4)) & 0x10c30c30c30c30c3ULL;
  v = (v | (v << 2)) & 0x1249249249249249ULL;
  return v;
}

/* Inverse of mx_morton_spread. */
static inline uint32_t mx_morton_compact(uint64_t v) {
  v &= 0x1249249249249249ULL;
  v = (v ^ (v >> 2)) & 0x10c30c30c30c30c3ULL;
  v = (v ^ (v >> 4)) & 0x100f00f00f00f00fULL;
  v = (v ^ (v >> 8)) & 0x1f0000ff0000ffULL;
  v = (v ^ (v >> 16)) & 0x1f00000000ffffULL;
  v = (v ^ (v >> 32)) & 0x1fffffULL;
  return (uint32_t)v;
}

static inline uint64_t mx_morton_encode(uint32_t x, uint32_t y, uint32_t z) {
  return mx_morton_spread(x) | (mx_morton_spread(y) << 1) |
         (mx_morton_spread(z) << 2);
}

static inline void mx_morton_decode(uint64_t key, uint32_t c[3]) {
  c[0] = mx_morton_compact(key);
  c[1] = mx_morton_compact(key >> 1);
  c[2] = mx_morton_compact(key >> 2);
}

/* a + b of two Morton keys, axis by axis, without decoding them (the sum
 * of dilated integers: the bits of the other axes set to 1 carry through);
 * a carry out of an axis' top bit is lost. */
static inline uint64_t mx_morton_add(uint64_t a, uint64_t b) {
  const uint64_t x = 0x9249249249249249ULL, y = x << 1, z = x << 2;
  return (((a | ~x) + (b & x)) & x) | (((a | ~y) + (b & y)) & y) | (((a | ~z) + (b & z)) & z);
}

/* Side of an octant of this level, in lattice units. */
static inline uint32_t mx_octant_size(int level) {
  return 1u << (MX_MAX_LEVEL - level);
}

/* Anchor of the octant (key, level) on the lattice of its own level. */
static inline void mx_octant_anchor(uint64_t key, int level, uint32_t a[3]) {
  uint32_t c[3];
  mx_morton_decode(key, c);
  const int shift = MX_MAX_LEVEL - level;
  a[0] = c[0] >> shift;
  a[1] = c[1] >> shift;
  a[2] = c[2] >> shift;
}

/* Key of the parent of the octant (key, level >= 1): clear the bits below
 * the parent's size. */
static inline uint64_t mx_morton_parent(uint64_t key, int level) {
  int shift = 3 * (MX_MAX_LEVEL - level + 1);
  return key & ~((1ULL << shift) - 1);
}

/* Key of child c (0..7, bit 0 = +x, bit 1 = +y, bit 2 = +z) of the octant
 * (key, level). */
static inline uint64_t mx_morton_child(uint64_t key, int level, int c) {
  return key | ((uint64_t)c << (3 * (MX_MAX_LEVEL - level - 1)));
}

/* Which child of its parent the octant (key, level >= 1) is. */
static inline int mx_morton_child_id(uint64_t key, int level) {
  return (int)((key >> (3 * (MX_MAX_LEVEL - level))) & 7);
}

/* Key of the same-level neighbour displaced by (dx,dy,dz) in {-1,0,1} octant
 * sizes, or UINT64_MAX when it would leave the grid [0, dims[i] roots).
 * Works across root cubes. */
uint64_t mx_morton_neighbor(uint64_t key, int level, int dx, int dy, int dz,
                            const int dims[3]);

/* Lattice key of a node (a corner point on the finest lattice). Corner
 * coordinates reach dims*2^MX_MAX_LEVEL <= 31*2^16 < 2^21, so they fit. */
static inline uint64_t mx_lattice_key(uint32_t x, uint32_t y, uint32_t z) {
  return mx_morton_encode(x, y, z);
}

#endif
