/* The whole boundary stage (2015 paper, Algorithm 1, lines 11-14) on the
 * transition mesh: node states, remove close to boundary, surface patterns,
 * shrink to boundary, staircase reduction. Each step is one function of
 * kernels/boundary.h or kernels/surface_patterns.h; this file only chains
 * them and times them. */
#ifndef MX_BOUNDARY_STAGE_H
#define MX_BOUNDARY_STAGE_H

#include "kernels/boundary.h"
#include "kernels/surface_patterns.h"

typedef struct {
  size_t located;        /* nodes located with the surface index */
  size_t moved_close;    /* inside nodes moved onto the surface (line 11) */
  size_t removed;        /* elements with no inside node removed */
  mx_surface_stats sp;   /* surface patterns and staircase */
  size_t shrunk;         /* outside nodes moved onto the surface (line 13) */
  double t_states, t_close, t_patterns, t_shrink, t_staircase;
} mx_boundary_stats;

/* close_ratio: 0.3 in the paper; staircase_q: 0.2. M is edited in place. */
int mx_boundary_stage(const mx_builder *B, const uint32_t *leaves,
                      const mx_surface_index *S, mx_mesh_out *M,
                      double close_ratio, double staircase_q,
                      mx_boundary_stats *stats);

#endif
