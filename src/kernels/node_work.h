/* What the node-moving passes share (the untangling, kernels/untangle.h,
 * and the smoothing, kernels/smooth.h): an element's J_ENS from the mesh's
 * positions, the set of nodes a pass works on with their elements, which
 * of them must stay on the surface, and their colours (two nodes of one
 * element never share one, so the nodes of a colour move at once, and the
 * result depends neither on the threads nor on the order). */
#ifndef MX_NODE_WORK_H
#define MX_NODE_WORK_H

#include <stddef.h>
#include <stdint.h>

#include "kernels/colouring.h"
#include "soa/mesh.h"

/* J_ENS of element c at the current positions (in double). */
double mx_cell_jens(const mx_mesh *M, uint32_t c);

/* 1 when node v lies on a face used by one element only: the mesh boundary.
 * inc[e0 .. e1): the elements of v. */
int mx_on_mesh_boundary(const mx_mesh *M, const uint32_t *inc, size_t e0, size_t e1,
                        uint32_t v);

typedef struct {
  uint64_t *off;   /* the elements of a node v with incidence: inc[off[v] .. off[v + 1]) */
  uint32_t *inc;
  uint32_t *band;  /* the elements of the lists, in increasing order (nband) */
  size_t nband;
  uint32_t *pos;   /* per list entry: its element's place in band */
  size_t nw;       /* the work nodes, in increasing id order */
  uint32_t *work;
  uint8_t *onsurf; /* per work index: the node stays on the surface (outside
                    * state, or inside but on the mesh boundary) */
  uint32_t *byc;   /* work indices grouped by colour, id order within one:
                    * colour c is byc[cstart[c] .. cstart[c + 1]) */
  size_t cstart[MX_MAX_COLOURS + 1];
  int ncol;
} mx_node_work;

/* The work set: the nodes with mark[v] != 0. Incidence for them, and with
 * ring != 0 also for every other node of their elements (whose
 * neighbourhoods the moves change). MX_ENOMEM; MX_EINPUT (with a message
 * naming `what`) for more than MX_MAX_COLOURS colours. On failure nothing
 * is left allocated. */
int mx_node_work_build(const mx_mesh *M, const uint8_t *states, const uint8_t *mark, int ring,
                       const char *what, mx_node_work *w);
void mx_node_work_free(mx_node_work *w);

/* The J_ENS of the band's elements in double at the current positions
 * (*jd: w->nband values, mx_alloc), kept beside the lists by the passes
 * that move nodes (jd[w->pos[e]] is entry e's element's). MX_ENOMEM. */
int mx_node_work_band_jens(const mx_mesh *M, const mx_node_work *w, double **jd);

/* The least of jd[pos[e]] over the list entries [e0, e1). */
static inline double mx_band_min(const double *jd, const uint32_t *pos, uint64_t e0,
                                 uint64_t e1) {
  double m = __builtin_inf();
  for (uint64_t e = e0; e < e1; e++) m = __builtin_fmin(m, jd[pos[e]]);
  return m;
}

#endif
