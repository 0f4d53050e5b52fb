/* The distributed octree's inputs from a mesher object: the surfaces and
 * requests added through the public API (readers, demo surface, levels,
 * boxes, region surfaces), set up as the single-process octree sets them
 * up (the mesher's own assembly of the soup; mx_builder_init: the root
 * grid, the triangles' coordinates, the locators), on every rank. */
#ifndef MX_P4EST_INPUTS_H
#define MX_P4EST_INPUTS_H

#include "kernels/refine.h"
#include "mesher/mesher.h"

typedef struct {
  mx_builder B; /* over m->soup: free it before the mesher */
  int have_builder;
} mx_p4est_inputs;

/* m: surfaces and requests added, not meshed. The inputs are assembled by
 * the mesher (mx_mesher_assemble_inputs: the single-process path's policy;
 * --repair-input is refused): MX_EINPUT with a message otherwise. */
int mx_p4est_inputs_init(mx_p4est_inputs *I, mx_mesher *m);
void mx_p4est_inputs_free(mx_p4est_inputs *I);

#endif
