/* Feature lines from a graph of feature edges (src/geom/feature_walk.c):
 * the walk that turns edges between vertices, some of them corners, into
 * the lines of geom/features.h (mx_feature_lines), for the polylines reader
 * (io/read_polylines.c) and for lines found on a surface.
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

/* Vertex v at (x[stride v], y[stride v], z[stride v]) for v < nv; edge e
 * from edge[2 e] to edge[2 e + 1] (both < nv, different); corner: nv flags
 * (1 a corner) or NULL (only the degree decides). Fills *L (zeroed first;
 * the corners in vertex order). MX_OK, MX_ENOMEM, MX_EINPUT (an end out of
 * range or an edge from a vertex to itself; no message: the caller's data,
 * not a file). On failure *L is empty. */
int mx_feature_lines_walk(const double *x, const double *y, const double *z, size_t stride,
                          size_t nv, const uint32_t *edge, size_t ne, const uint8_t *corner,
                          mx_feature_lines *L);

/* Frees what mx_feature_lines_walk allocated (the same as
 * mx_feature_lines_free of geom/features.h, for code that must not depend
 * on which file defines that). */
void mx_feature_lines_walk_free(mx_feature_lines *L);

#endif
