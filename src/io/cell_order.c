/* mixoct: the order cells are written in (issue 11): grouped by type, tetrahedra, pyramids,
 * prisms, hexahedra, and within a type in index order (the mesher's index order is the
 * leaves' Morton order), so that readers that make one block per run of a type (meshio, VTK,
 * Gmsh) see at most four blocks. Element lists for re-meshing refer to this order. */
#include <string.h>

#include "common.h"
#include "soa/mesh.h"

enum { CHUNK = 65536 };

int mx_cells_by_type(const uint8_t *type, size_t n, uint32_t *order, size_t first[5]) {
  const size_t nchunks = (n + CHUNK - 1) / CHUNK;
  size_t *cnt = mx_calloc((4 * nchunks + 1) * sizeof *cnt);
  if (!cnt) return MX_EINPUT;
#pragma omp parallel for schedule(static)
  for (size_t k = 0; k < nchunks; k++) {
    const size_t end = (k + 1) * CHUNK < n ? (k + 1) * CHUNK : n;
    for (size_t c = k * CHUNK; c < end; c++) cnt[4 * k + (type[c] & 3)]++;
  }
  /* exclusive scan, type-major: all chunks' tetrahedra first */
  size_t at = 0;
  for (int t = 0; t < 4; t++) {
    if (first) first[t] = at;
    for (size_t k = 0; k < nchunks; k++) {
      const size_t c = cnt[4 * k + (size_t)t];
      cnt[4 * k + (size_t)t] = at;
      at += c;
    }
  }
  if (first) first[4] = at;
#pragma omp parallel for schedule(static)
  for (size_t k = 0; k < nchunks; k++) {
    const size_t end = (k + 1) * CHUNK < n ? (k + 1) * CHUNK : n;
    size_t pos[4];
    memcpy(pos, cnt + 4 * k, sizeof pos);
    for (size_t c = k * CHUNK; c < end; c++) order[pos[type[c] & 3]++] = (uint32_t)c;
  }
  mx_free(cnt);
  return MX_OK;
}
