/* What the writers share to write a 2D view (soa/mesh.h: dim 2): the cell
 * counts, and the text of a point "x y 0" and of a cell's node indices. */
#ifndef MX_PLANE_MESH_H
#define MX_PLANE_MESH_H

#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "io/text_num.h"
#include "soa/mesh.h"

enum { MX_XY0_MAX = 2 * MX_DOUBLE_CHARS + 4 }; /* "x y 0" and its end */

/* The quadrilaterals of a 2D view (in parallel above 65536 cells). */
size_t mx_plane_count_quads(const mx_mesh_view *m);

/* "x y 0" + end. */
static inline size_t mx_plane_put_xy0(char *o, const double *p, char end) {
  size_t n = mx_put_double(o, p[0]);
  o[n++] = ' ';
  n += mx_put_double(o + n, p[1]);
  memcpy(o + n, " 0", 2);
  n += 2;
  o[n++] = end;
  return n;
}

/* " v0 v1 ..." (each plus add). */
static inline size_t mx_plane_put_ids(char *o, const uint32_t *v, int n, uint64_t add) {
  size_t k = 0;
  for (int j = 0; j < n; j++) {
    o[k++] = ' ';
    k += mx_put_u64(o + k, (uint64_t)v[j] + add);
  }
  return k;
}

/* The boundary edges of a 2D view (used by one cell), as 4 * cell + side
 * (side s joins nodes s and s + 1 of the cell), in cell then side order
 * (src/io/boundary_edges.c). *out allocated; MX_OK or MX_ENOMEM. */
int mx_plane_boundary_edges(const mx_mesh_view *m, uint64_t **out, size_t *nb);
/* The edges between two bodies (body: per cell, 1 .. 255), each once, as
 * 4 * cell + side of its cell of the lower body, sorted by pair (lower,
 * higher body), then by cell and side; pair[i] = lower << 8 | higher
 * (src/io/boundary_edges.c). *out, *pair allocated; MX_OK or MX_ENOMEM. */
int mx_plane_interface_edges(const mx_mesh_view *m, const int32_t *body, uint64_t **out,
                             uint32_t **pair, size_t *n);

#endif
