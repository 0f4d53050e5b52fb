/* Feature lines (src/geom/feature_walk.c): the type mx_feature_lines, and
 * the walk that turns edges between vertices, some of them corners, into
 * such lines, for the polylines reader (io/read_polylines.c) and for the
 * ridges found on a surface (mx_feature_lines_of).
 *
 * A vertex is a corner when flagged so or when its degree (edges at it) is
 * not 2: the ends of open chains and the junctions of three edges or more
 * are corners whatever the flags say. Every edge ends up in exactly one
 * line: the chains run from corner to corner, each walked from the end
 * reached first -- corners in vertex order, each corner's edges in edge
 * order --, the remaining edges close into loops (every vertex on them is
 * of degree 2 and no corner), each walked from its least vertex along the
 * lower of that vertex's two edges. The output depends only on the order of
 * the vertices and edges, never on the thread count. */
#ifndef MX_FEATURE_WALK_H
#define MX_FEATURE_WALK_H

#include <stddef.h>
#include <stdint.h>

#include "geom/features.h"

/* The features as lines, for placing them in a mesh and measuring how far
 * the mesh is from them: each line an ordered polyline from a corner to a
 * corner (its first and last points are corners), or a loop with no corner
 * on it (its last point joins its first; the first point is not repeated).
 * Found from a surface (mx_feature_lines_of) or read from a polylines file
 * (io/read_polylines.h). */
typedef struct {
  size_t nlines;
  size_t *first;  /* nlines + 1: line i is points first[i] .. first[i + 1] - 1 */
  double *xyz;    /* 3 per point */
  uint8_t *loop;  /* per line: 1 for a loop */
  size_t ncorners;
  double *corner; /* 3 per corner */
} mx_feature_lines;

/* The lines of F (found on s): each ridge chain walked from a corner, or
 * from its least vertex when it is a loop. MX_OK, MX_ENOMEM. */
int mx_feature_lines_of(const mx_trisoup *s, const mx_features *F, mx_feature_lines *L);
void mx_feature_lines_free(mx_feature_lines *L);

/* Vertex v at (x[stride v], y[stride v], z[stride v]) for v < nv; edge e
 * from edge[2 e] to edge[2 e + 1] (both < nv, different); corner: nv flags
 * (1 a corner) or NULL (only the degree decides). Fills *L (zeroed first;
 * the corners in vertex order). MX_OK, MX_ENOMEM, MX_EINPUT (an end out of
 * range or an edge from a vertex to itself; no message: the caller's data,
 * not a file). On failure *L is empty. */
int mx_feature_lines_walk(const double *x, const double *y, const double *z, size_t stride,
                          size_t nv, const uint32_t *edge, size_t ne, const uint8_t *corner,
                          mx_feature_lines *L);

/* Frees what mx_feature_lines_walk allocated (= mx_feature_lines_free). */
void mx_feature_lines_walk_free(mx_feature_lines *L);

#endif
