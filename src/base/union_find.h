/* Union-find over uint32 ids (up[x] = x for a root), serial: find with
 * path halving, join hanging the larger root under the smaller (so each
 * set's root is its smallest id, whatever the order of the joins). */
#ifndef MX_UNION_FIND_H
#define MX_UNION_FIND_H

#include <stdint.h>

static inline uint32_t mx_uf_find(uint32_t *up, uint32_t x) {
  while (up[x] != x) {
    up[x] = up[up[x]];
    x = up[x];
  }
  return x;
}

static inline void mx_uf_join(uint32_t *up, uint32_t x, uint32_t y) {
  x = mx_uf_find(up, x);
  y = mx_uf_find(up, y);
  if (x != y) up[x > y ? x : y] = x < y ? x : y;
}

#endif
