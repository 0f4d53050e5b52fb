/* Inside/outside of a point with respect to a set of closed triangulated
 * shells, by the parity of the crossings of a ray along +x.
 *
 * The triangles are binned by their (y, z) bounding boxes into a uniform 2D
 * grid, so a query tests only the triangles over its cell. Whether the ray
 * passes through a projected triangle is decided by three orientation tests
 * evaluated on each edge in a canonical direction (lower vertex index first),
 * so the two triangles of a shared edge get the same answer; an exact zero is
 * broken by simulation of simplicity (the query is displaced by
 * (0, eps, eps^2)), so a ray through an edge or a vertex counts exactly one
 * crossing for every sheet of a watertight surface. Nested shells are holes
 * and disjoint shells are separate bodies, by parity.
 *
 * Meant for points away from the surface (the centres of octants that meet no
 * triangle), where the crossing's abscissa is well conditioned. */
#ifndef MX_LOCATE_H
#define MX_LOCATE_H

#include <stddef.h>
#include <stdint.h>

#include "soa/trisoup.h"

typedef struct {
  const mx_trisoup *soup;
  uint32_t t0, t1;       /* the triangles [t0, t1) of the soup */
  double lo[2], inv[2];  /* grid origin (y, z) and 1/cell size */
  int n[2];              /* cells along y and z */
  uint32_t *cell_off;    /* n[0]*n[1] + 1 */
  uint32_t *cell_tri;
  /* Optional (NULL by default): decides instead of the ray parity, for an
   * input whose inside the parity does not define (open, self-intersecting:
   * the generalized winding number, --repair-input). */
  int (*inside_fn)(const void *ctx, const double p[3]);
  const void *inside_ctx;
} mx_locator;

int mx_locator_build(mx_locator *L, const mx_trisoup *soup, uint32_t t0,
                     uint32_t t1);
void mx_locator_free(mx_locator *L);
/* 1 if p is inside (odd number of crossings), 0 if outside. */
int mx_locate(const mx_locator *L, const double p[3]);

#endif
