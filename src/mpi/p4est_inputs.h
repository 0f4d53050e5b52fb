/* The distributed octree's inputs from a mesher object: the surfaces and
 * requests added through the public API (readers, demo surface, levels,
 * boxes, region surfaces), set up as the single-process octree sets them
 * up (the soup: domain triangles, then each region's; mx_builder_init: the
 * root grid, the triangles' coordinates, the locators), on every rank. */
#ifndef MX_P4EST_INPUTS_H
#define MX_P4EST_INPUTS_H

#include "kernels/refine.h"
#include "mesher/mesher.h"

typedef struct {
  mx_trisoup soup;
  uint32_t nt_domain, region_t0[MX_MAX_REGIONS + 1];
  mx_builder B;
  int have_builder;
} mx_p4est_inputs;

/* m: surfaces and requests added, not meshed. The domain must be closed,
 * manifold and free of self-intersections (the single-process path's
 * policy without --repair-input; a misoriented input is fine, the ray
 * parity ignores orientation): MX_EINPUT with a message otherwise. */
int mx_p4est_inputs_init(mx_p4est_inputs *I, mx_mesher *m);
void mx_p4est_inputs_free(mx_p4est_inputs *I);

#endif
