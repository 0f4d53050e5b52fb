/* Sharp features placed in the mesh (issue 29, item 3), after the boundary
 * stage, on the mesh's boundary (the faces used by one element, all of
 * whose nodes are on the surface):
 *
 *  1. corners: each corner, in order, takes the closest boundary node not
 *     taken yet, which moves onto it;
 *  2. ridges: each line of mx_feature_lines runs from a corner's node to
 *     the other's (a loop: from the node of its first point to the node of
 *     its middle point and back on other nodes) along the boundary edges
 *     of least cost (Dijkstra over the boundary nodes within a tube around
 *     the line: an edge costs its length plus twice the distances of its
 *     ends to the line); the path's nodes move onto the line, each to its
 *     closest point, when their places along the line keep the path's
 *     order (else the line is counted as missed and nothing moves);
 *  3. sides: the boundary faces cut along the placed lines fall into
 *     regions; each region's patch (the surface cut along its ridges) is
 *     the one most of its nodes are closest to, and a node of the region
 *     closest to another patch moves to its closest point on the region's.
 *     A face then lies on one side of every ridge: none straddles one.
 *
 * The feature nodes are flagged in fixed[] (the untangling and smoothing
 * that follow leave them). J_ENS is updated for the elements of moved
 * nodes. Serial, in the order of the corners and lines: deterministic. */
#ifndef MX_FEATURE_PLACE_H
#define MX_FEATURE_PLACE_H

#include <stddef.h>
#include <stdint.h>

#include "geom/distance.h"
#include "geom/feature_walk.h"
#include "soa/mesh.h"
#include "soa/trisoup.h"

typedef struct {
  const mx_feature_lines *L;
  /* the surface's triangles [0, nt) of soup and their patches (patch NULL:
   * no side step, the lines were given rather than found) */
  const mx_trisoup *soup;
  size_t nt;
  const uint32_t *patch;
  size_t npatches;
} mx_feature_input;

typedef struct {
  size_t corners, corners_missed; /* corners placed; not (no node free near) */
  size_t lines, lines_missed;     /* lines followed by mesh edges; not */
  size_t nodes;                   /* nodes moved onto corners and lines */
  size_t sides;                   /* nodes moved onto their region's patch */
  size_t given_up;                /* nodes put back (mx_feature_give_up) */
  double seconds;
} mx_feature_stats;

/* states: MX_NODE_OUTSIDE for the nodes on the surface (boundary stage);
 * S: the surface's index; fixed: nnodes bytes, set here (1: a feature
 * node). MX_OK, MX_ENOMEM. */
int mx_feature_place(mx_mesh *M, const uint8_t *states, const mx_surface_index *S,
                     const mx_feature_input *in, uint8_t *fixed, mx_feature_stats *st);

/* The nodes of the elements the placement spoilt put back where they were
 * before it (before: 3 * nnodes; q_before: the elements' J_ENS then), until
 * none is left or none of its nodes moved: the features there are given up
 * rather than the mesh. Spoilt: invalid (J_ENS < MX_JENS_VALID), or below
 * floor and below its J_ENS before. *count: nodes put back. J_ENS and the
 * summary updated. MX_OK, MX_ENOMEM. */
int mx_feature_give_up(mx_mesh *M, const double *before, const float *q_before, double floor,
                       size_t *count);

#endif
