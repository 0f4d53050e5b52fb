/* Binary numbers in files: the unsigned integer of `bytes` bytes (1 to 8)
 * at p, big-endian when big, else little-endian (binary PLY, the label
 * images' headers and voxels), and back (mx_store_le). */
#ifndef MX_BYTES_H
#define MX_BYTES_H

#include <stdint.h>

static inline uint64_t mx_load_uint(const unsigned char *p, int bytes, int big) {
  uint64_t x = 0;
  if (big)
    for (int b = 0; b < bytes; b++) x = x << 8 | p[b];
  else
    for (int b = bytes - 1; b >= 0; b--) x = x << 8 | p[b];
  return x;
}

/* The reverse: v's low `bytes` bytes at p, little-endian (binary STL and PLY
 * written by the boundary writer). */
static inline void mx_store_le(unsigned char *p, uint64_t v, int bytes) {
  for (int b = 0; b < bytes; b++, v >>= 8) p[b] = (unsigned char)(v & 0xff);
}

#endif
