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
 *     order (else the line is counted as missed and nothing moves). The
 *     path may cross a boundary quadrilateral along its diagonal, and
 *     never keeps three nodes of one face (a node whose neighbours on the
 *     path share an edge or a diagonal is left out): three nodes of a face
 *     on a line would flatten a triangle or fold a quadrilateral;
 *  2b. the elements of the quadrilaterals a line crosses are split along
 *     the diagonal (kernels/cell_split.h: cones from a new node at their
 *     centre), so that the line runs on element edges;
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
#include "kernels/cell_split.h"
#include "kernels/feature_types.h"
#include "soa/mesh.h"


/* *states: MX_NODE_OUTSIDE for the nodes on the surface (boundary stage);
 * S: the surface's index; *fixed: nnodes bytes, set here (1: a feature
 * node). Both grow (mx_realloc) when elements are split (below), the
 * splits logged in *log (for mx_feature_give_up), the chains along the
 * ridges in *chain (mx_feature_chain_free). MX_OK, MX_ENOMEM. */
int mx_feature_place(mx_mesh *M, uint8_t **states, const mx_surface_index *S,
                     const mx_feature_input *in, uint8_t **fixed, mx_feature_stats *st,
                     mx_split_log *log, mx_feature_chain *chain);

/* (src/kernels/feature_give_up.c) The nodes of the elements the placement
 * spoilt put back where they were
 * before it (before: 3 * nb coordinates, for the nodes below nb: those
 * added since did not move; q_before: the J_ENS of the first ncb elements
 * then, the others' taken as 1), until none is left or none of its nodes
 * moved (first the nodes moved beside the features, then, when none is
 * left, the feature nodes: feature[v] != 0, may be NULL): the features
 * there are given up rather than the mesh. A feature node on a straight
 * stretch of its chain (chain, may be NULL) first slides along it, between
 * its neighbours, to where none of its elements is spoilt: it stays on
 * its ridge (fs->slid). A spoilt
 * element with a node of a split first has that node moved to its best
 * point (mx_mesh_best_point), and its inside nodes that are no feature
 * nodes (*states) moved to theirs when that leaves fewer of their
 * elements spoilt and spoils none; a split (log, may be NULL) whose cones are
 * still spoilt after all is undone and its element's nodes put back.
 * Spoilt: invalid (J_ENS < MX_JENS_VALID), or below floor and below its
 * J_ENS before. fs->given_up: nodes put back, fs->unsplit: splits
 * undone. J_ENS and the summary updated;
 * *states follows the nodes. MX_OK, MX_ENOMEM. */
int mx_feature_give_up(mx_mesh *M, uint8_t **states, mx_split_log *log, const uint8_t *feature,
                       const mx_feature_chain *chain, const double *before,
                       size_t nb, const float *q_before, size_t ncb, double floor,
                       mx_feature_stats *fs);

#endif
