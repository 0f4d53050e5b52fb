#include "base/morton.h"

uint64_t mx_morton_neighbor(uint64_t key, int level, int dx, int dy, int dz,
                            const int dims[3]) {
  uint32_t c[3];
  mx_morton_decode(key, c);
  const int64_t s = mx_octant_size(level);
  const int d[3] = {dx, dy, dz};
  for (int a = 0; a < 3; a++) {
    int64_t v = (int64_t)c[a] + d[a] * s;
    int64_t limit = (int64_t)dims[a] << MX_MAX_LEVEL;
    if (v < 0 || v >= limit) return UINT64_MAX;
    c[a] = (uint32_t)v;
  }
  return mx_morton_encode(c[0], c[1], c[2]);
}
