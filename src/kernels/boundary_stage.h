/* The whole boundary stage (2015 paper, Algorithm 1, lines 11-14) on the
 * transition mesh: node states, remove close to boundary, surface patterns,
 * shrink to boundary, staircase reduction. Each step is one function of
 * kernels/boundary.h or kernels/surface_patterns.h; this file only chains
 * them and times them. */
#ifndef MX_BOUNDARY_STAGE_H
#define MX_BOUNDARY_STAGE_H

#include "kernels/boundary.h"
#include "kernels/interfaces.h"
#include "kernels/smooth.h"
#include "kernels/surface_patterns.h"

typedef struct {
  size_t located;        /* nodes located with the surface index */
  size_t on_surface;     /* of those, inside on the surface (MX_NODE_ON) */
  size_t moved_close;    /* inside nodes moved onto the surface (line 11) */
  size_t removed;        /* elements with no inside node removed */
  mx_surface_stats sp;   /* surface patterns and staircase */
  size_t shrunk;         /* outside nodes moved onto the surface (line 13) */
  size_t inverted;       /* elements with J_ENS < 1e-6 right after the shrink */
  size_t smoothed;       /* node moves by the untangling */
  mx_smooth_stats smoothing; /* the smoothing after it (kernels/smooth.h) */
  mx_interface_stats ifs; /* the interfaces between materials */
  double t_states, t_close, t_patterns, t_shrink, t_interfaces, t_smooth, t_staircase;
} mx_boundary_stats;

/* states_out (may be NULL) receives (mx_alloc) the final state of every
 * node: MX_NODE_OUTSIDE for the nodes on the surface.
 * close_ratio: the "remove close to boundary" distance, as a fraction of
 * the average length of a node's incident element edges. The 2015 paper
 * says 0.3 of the incident edges; the 2021 paper, 0.3 of the shortest octant
 * diagonal sharing the node, which is about 0.5 of the average element edge
 * here. MX_CLOSE_RATIO = 0.5 is the one that reproduces the published
 * mesher's node and element counts on the cortex (within 1% at -s 4..6,
 * against +10% for 0.3). staircase_q: 0.2 (the paper); it is also the
 * target of the untangling/smoothing step. M is edited in place.
 * I (NULL: none): the interfaces between nested materials, meshed after
 * the outer boundary's shrink and before the untangling
 * (kernels/interfaces.h). smooth_rounds: rounds of the smoothing after
 * the untangling (kernels/smooth.h), 0 none; not run with interfaces.
 * keep_unused: the nodes no element uses any more may stay (ignored with
 * interfaces), for a caller that numbers the nodes by first use next
 * (mx_surface_patterns). */
#define MX_CLOSE_RATIO 0.5
int mx_boundary_stage(const mx_tree *tr, const uint32_t *leaves,
                      const mx_surface_index *S, mx_mesh *M,
                      const mx_interfaces *I, double close_ratio, double staircase_q,
                      int smooth_rounds, int keep_unused, mx_boundary_stats *stats,
                      uint8_t **states_out);

#endif
