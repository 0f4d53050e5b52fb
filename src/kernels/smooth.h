/* Smoothing after the untangling (issue 29, item 4): each node of the work
 * set moves to the best of a few trial points (towards the centroid of its
 * neighbours; along the gradient of its worst element's J_ENS, bent away
 * from the gradients of the elements near their bound below) when that
 * raises the worst J_ENS of its elements. A boundary node (outside, or on
 * the mesh boundary) moves to the closest surface point of each trial, so
 * the boundary stays on the surface.
 *
 * The rule it keeps: no node's neighbourhood minimum (the least J_ENS of
 * the elements having it as a node, m(u)) ever decreases. Moving v changes
 * only v's elements; a trial is taken only when every element e of v keeps
 * J(e) >= max over the nodes w of e of m(w): then for every node u of e,
 * J(e) >= m(u), so m(u) cannot drop, not only m(v). m is kept exact
 * between colours (recomputed for the nodes of the changed elements), so
 * it only ever rises.
 *
 * The work set: the movable nodes whose neighbourhood minimum is below
 * q_target, coloured as in the untangling (no two nodes of one element
 * share a colour); a round takes the colours in turn, the nodes of one in
 * parallel, each move reading only what the colour does not change:
 * deterministic and the same for any thread count. A node is looked at
 * again only when its neighbourhood changed. */
#ifndef MX_SMOOTH_H
#define MX_SMOOTH_H

#include <stddef.h>
#include <stdint.h>

#include "geom/distance.h"
#include "soa/mesh.h"

typedef struct {
  int rounds;             /* sweeps over the work set; 0: nothing is done */
  double q_target;        /* nodes whose neighbourhood minimum is below it
                           * are worked on; > 1: every movable node */
  const uint8_t *movable; /* per node, 0: fixed (features, interfaces); NULL: all */
} mx_smooth_opts;

/* The target the boundary stage uses: on the cortex, 0.25 raised nothing
 * at -s 6 and -s 8, 0.35 +0.0003 at -s 8, 0.5 +0.0046 (one round).
 * bench/smooth_bench.sh, 2 threads, medians of 3 (-s 9: one run), --smooth
 * 1 against 0: J_ENS min +0.0013 / +0.0034 / +0.0046 / +0.0000 at -s 6 / 7
 * / 8 / 9 for 2.6x / 3.3x / 4.1x / 3.6x the wall time; 3 rounds gain no
 * more than 1. Hence off by default (mixoct.h, MX_SMOOTH_ROUNDS). */
#define MX_SMOOTH_TARGET 0.5

typedef struct {
  size_t work;            /* nodes in the work set */
  size_t moves;           /* accepted moves (a node may move in several rounds) */
  size_t moved;           /* distinct nodes moved */
  int rounds;             /* rounds run (fewer than asked when nothing moved) */
  double jens_min_before, jens_min_after; /* the mesh's least J_ENS */
  double seconds;
} mx_smooth_stats;

/* states: MX_NODE_* per node (outside: on the surface); S: the surface the
 * boundary nodes stay on. M's positions and J_ENS are updated in place
 * (jens_min, invalid refreshed). MX_ENOMEM, MX_EINPUT (too many colours). */
int mx_smooth(mx_mesh *M, const uint8_t *states, const mx_surface_index *S,
              const mx_smooth_opts *o, mx_smooth_stats *st);

#endif
