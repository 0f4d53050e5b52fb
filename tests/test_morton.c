/* Morton keys: round trips, parent/children, neighbours across root cubes. */
#include "check.h"
#include "base/morton.h"

#include <stdint.h>
#include <stdlib.h>

static uint32_t rnd21(uint64_t *s) {
  *s = *s * 6364136223846793005ULL + 1442695040888963407ULL;
  return (uint32_t)(*s >> 33) & 0x1fffff;
}

/* Reference interleave, bit by bit. */
static uint64_t slow_encode(uint32_t x, uint32_t y, uint32_t z) {
  uint64_t k = 0;
  for (int b = 0; b < 21; b++) {
    k |= (uint64_t)((x >> b) & 1) << (3 * b);
    k |= (uint64_t)((y >> b) & 1) << (3 * b + 1);
    k |= (uint64_t)((z >> b) & 1) << (3 * b + 2);
  }
  return k;
}

int main(void) {
  uint64_t seed = 42;
  for (int i = 0; i < 200000; i++) {
    uint32_t x = rnd21(&seed), y = rnd21(&seed), z = rnd21(&seed);
    uint64_t k = mx_morton_encode(x, y, z);
    CHECK(k == slow_encode(x, y, z));
    uint32_t c[3];
    mx_morton_decode(k, c);
    CHECK(c[0] == x && c[1] == y && c[2] == z);
  }
  CHECK(mx_morton_encode(0x1fffff, 0x1fffff, 0x1fffff) == (1ULL << 63) - 1);

  /* Parent and children: a child's parent is the octant; child ids. */
  for (int i = 0; i < 20000; i++) {
    int level = 1 + (int)(rnd21(&seed) % MX_MAX_LEVEL);
    uint32_t s = mx_octant_size(level);
    uint32_t x = (rnd21(&seed) % 31u) << MX_MAX_LEVEL | (rnd21(&seed) & 0xffff);
    uint32_t y = rnd21(&seed) & 0xffff, z = rnd21(&seed) & 0xffff;
    x -= x % s;
    y -= y % s;
    z -= z % s;
    uint64_t k = mx_morton_encode(x, y, z);
    uint64_t p = mx_morton_parent(k, level);
    uint32_t pc[3];
    mx_morton_decode(p, pc);
    CHECK(pc[0] == x - x % (2 * s) && pc[1] == y - y % (2 * s) &&
          pc[2] == z - z % (2 * s));
    int cid = mx_morton_child_id(k, level);
    CHECK(cid == (int)(((x / s) & 1) | ((y / s) & 1) << 1 | ((z / s) & 1) << 2));
    CHECK(mx_morton_child(p, level - 1, cid) == k);
    for (int c = 0; c < 8; c++) {
      uint64_t ch = mx_morton_child(p, level - 1, c);
      CHECK(mx_morton_parent(ch, level) == p);
      CHECK(mx_morton_child_id(ch, level) == c);
      CHECK((ch > p) == (c > 0)); /* children follow the parent in order */
    }
  }

  /* Neighbours, including across root cubes and off the grid. */
  const int dims[3] = {3, 2, 1};
  const int lvl = 2;
  const uint32_t s = mx_octant_size(lvl);
  /* Last octant of root (0,0,0) along x: its +x neighbour is in root (1,0,0). */
  uint64_t k = mx_morton_encode(3 * s, 0, 0);
  uint64_t n = mx_morton_neighbor(k, lvl, 1, 0, 0, dims);
  uint32_t c[3];
  mx_morton_decode(n, c);
  CHECK(c[0] == 4 * s && c[0] >> MX_MAX_LEVEL == 1 && c[1] == 0 && c[2] == 0);
  CHECK(mx_morton_neighbor(k, lvl, 0, -1, 0, dims) == UINT64_MAX);
  CHECK(mx_morton_neighbor(mx_morton_encode(0, 3 * s, 0), lvl, 0, 1, 0, dims) !=
        UINT64_MAX);
  CHECK(mx_morton_neighbor(mx_morton_encode(0, 7 * s, 0), lvl, 0, 1, 0, dims) ==
        UINT64_MAX);
  CHECK(mx_morton_neighbor(mx_morton_encode(0, 0, 3 * s), lvl, 0, 0, 1, dims) ==
        UINT64_MAX);
  /* Edge neighbour across two roots' boundaries. */
  n = mx_morton_neighbor(mx_morton_encode(3 * s, 3 * s, 0), lvl, 1, 1, 0, dims);
  mx_morton_decode(n, c);
  CHECK(c[0] == 4 * s && c[1] == 4 * s);
  /* Round trip of neighbours: going and coming back. */
  for (int i = 0; i < 10000; i++) {
    uint32_t p[3] = {(rnd21(&seed) % (3u << MX_MAX_LEVEL)) & ~(s - 1),
                     (rnd21(&seed) % (2u << MX_MAX_LEVEL)) & ~(s - 1),
                     (rnd21(&seed) % (1u << MX_MAX_LEVEL)) & ~(s - 1)};
    uint64_t a = mx_morton_encode(p[0], p[1], p[2]);
    int dx = (int)(rnd21(&seed) % 3) - 1, dy = (int)(rnd21(&seed) % 3) - 1,
        dz = (int)(rnd21(&seed) % 3) - 1;
    uint64_t b = mx_morton_neighbor(a, lvl, dx, dy, dz, dims);
    if (b != UINT64_MAX) CHECK(mx_morton_neighbor(b, lvl, -dx, -dy, -dz, dims) == a);
  }
  /* Sums of keys axis by axis, against decode, add, encode. */
  for (int i = 0; i < 10000; i++) {
    const uint32_t a[3] = {rnd21(&seed) >> 1, rnd21(&seed) >> 1, rnd21(&seed) >> 1};
    const uint32_t d[3] = {rnd21(&seed) >> (1 + i % 20), rnd21(&seed) >> (1 + i % 20), i % 3 ? 0 : rnd21(&seed) >> 1};
    CHECK(mx_morton_add(mx_morton_encode(a[0], a[1], a[2]), mx_morton_encode(d[0], d[1], d[2])) ==
          mx_morton_encode(a[0] + d[0], a[1] + d[1], a[2] + d[2]));
  }
  return TEST_DONE();
}
