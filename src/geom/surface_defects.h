/* Defects of input surfaces: what makes a triangulated surface fail to
 * bound a well-defined inside.
 *
 * Edges (an edge is an unordered pair of vertex indices; the edge table of
 * geom/surface_topology.h, no per-edge allocation):
 *   boundary     used by one triangle only (the surface has a hole);
 *   non-manifold used by three triangles or more;
 *   misoriented  used by exactly two triangles that traverse it in the same
 *                direction (their normals disagree).
 * Triangles whose three points are exactly collinear (or that repeat a
 * vertex) are "degenerate": they are counted, take no part in the
 * intersection tests, and a repeated-vertex triangle none in the edges.
 *
 * Pairs of triangles that meet beyond what they share: two triangles
 * "intersect" when their intersection (as closed sets) is not exactly the
 * convex hull of their common vertices, the common vertices being those
 * with identical coordinates (so an unwelded copy of a vertex counts as
 * shared). So two triangles sharing an edge intersect only if they are
 * coplanar and on the same side of it (a fold-over); two sharing one
 * vertex only if they overlap somewhere else than at that point; two with
 * nothing in common as soon as they touch, at a single point or along an
 * edge (a vertex lying on another triangle, a T-junction, ...). Identical
 * triangles intersect. Pairs of one input (same mx_trisoup.shell) are
 * counted in intersecting_pairs, pairs of two inputs in crossing_pairs
 * (so a surface nested inside another is not a crossing, a surface
 * touching another is).
 *
 * Method. Broad phase (geom/bvh.h): a BVH over the triangles' boxes
 * (triangles sorted along a Morton curve of their box centres, split at the
 * highest differing bit, leaves of up to 4), traversed against itself
 * (pairs within a node = pairs within each child + pairs across the two
 * children; OpenMP tasks for the first levels); pairs whose closed boxes
 * meet (compared exactly) go to the narrow phase, the triangle of smaller
 * (Morton code, id) first. Narrow phase: exact signs only, no tolerance:
 * orient3d and orient2d in double behind a semi-static error bound
 * (Shewchuk's bound A) and, when that does not decide, exactly (each
 * difference of coordinates split into two doubles, each product made
 * exact with fma, the terms summed into a nonoverlapping expansion whose
 * largest component has the sign). Coplanar cases are decided in the
 * coordinate plane where the triangle's projection has nonzero (exact)
 * area. Triangles sharing a vertex v: if their planes differ, they cut the
 * planes' common line in [v, w1] and [v, w2] with w1 on the first one's
 * far edge and w2 on the second's, so they overlap beyond v iff a far edge
 * meets the other triangle; if coplanar, iff one of the four edges at v
 * points into the other triangle's angle. Sharing an edge: iff coplanar
 * with the other vertices on the same side. Results do not depend on the
 * thread count: counts are sums, the examples kept are the smallest ids.
 *
 * Cost: O(n log n) time, about 300 bytes per triangle of temporary memory
 * (freed before returning). Measured on the
 * development VM (2 cores, shared with other jobs, so CPU seconds): 6300
 * triangles (cortex.off) 5.5 ms, a 327680-triangle closed surface 0.15 to
 * 0.2 s of CPU in total. */
#ifndef MX_SURFACE_DEFECTS_H
#define MX_SURFACE_DEFECTS_H

#include <stddef.h>
#include <stdint.h>

#include "soa/trisoup.h"

#define MX_DEFECT_EXAMPLES 8

/* One defect, for messages. Triangle and vertex ids index the soup
 * (0-based, all inputs together); UINT32_MAX where not applicable. */
typedef struct {
  uint32_t tri;    /* the (smaller) triangle */
  uint32_t other;  /* pairs: the other triangle (tri < other); edges: a
                      second triangle using the edge, or UINT32_MAX */
  uint32_t v0, v1; /* edges: the edge's vertices, v0 < v1 */
  double p[3];     /* a point at the defect: edge midpoint, a point of (or
                      next to) the intersection, a degenerate triangle's
                      centroid */
} mx_defect_example;

typedef struct {
  size_t boundary_edges;       /* edges used by one triangle (open surface) */
  size_t nonmanifold_edges;    /* edges used by more than two triangles */
  size_t misoriented_edges;    /* edges used twice in the same direction */
  size_t intersecting_pairs;   /* pairs of triangles of one input that meet */
  size_t crossing_pairs;       /* pairs of triangles of two inputs that meet */
  size_t intersecting_bodies;  /* of intersecting_pairs, those whose two
                                  triangles are not connected through
                                  shared vertices (two bodies of one input
                                  file crossing each other) */
  size_t degenerate_triangles; /* zero area; not tested for intersection */
  /* The first min(count, MX_DEFECT_EXAMPLES) examples of each kind, in
   * increasing (tri, other, v0, v1). */
  mx_defect_example boundary[MX_DEFECT_EXAMPLES];
  mx_defect_example nonmanifold[MX_DEFECT_EXAMPLES];
  mx_defect_example misoriented[MX_DEFECT_EXAMPLES];
  mx_defect_example intersecting[MX_DEFECT_EXAMPLES];
  mx_defect_example crossing[MX_DEFECT_EXAMPLES];
  mx_defect_example degenerate[MX_DEFECT_EXAMPLES];
} mx_surface_defects;

/* Finds every defect above in the whole soup; *r is overwritten. MX_OK,
 * MX_ENOMEM, or MX_EINPUT (vertex index out of range, more than 2^30
 * triangles), with a message. Prints nothing else. */
int mx_surface_defects_find(const mx_trisoup *s, mx_surface_defects *r);

/* Every pair of triangles that meets (those counted in intersecting_pairs
 * and crossing_pairs above), as keys (smaller triangle << 32 | larger),
 * increasing; *pairs is allocated with mx_alloc (NULL when there is none).
 * The same for any thread count. MX_OK, MX_ENOMEM, or MX_EINPUT (bad
 * index). */
int mx_surface_meeting_pairs(const mx_trisoup *s, uint64_t **pairs, size_t *npairs);

/* Sum of all counts except intersecting_bodies (already in
 * intersecting_pairs): 0 for a clean surface. */
size_t mx_surface_defects_total(const mx_surface_defects *r);

/* Orients the soup in place (swaps two vertices of the triangles to flip).
 * Pieces: sets of triangles connected through edges used by exactly two
 * triangles. Within a piece the orientation is made consistent by a flood
 * fill from its smallest triangle; then a closed piece (each edge of its
 * triangles used by exactly two of its triangles) is turned outward
 * (positive enclosed volume), and a piece with boundary or non-manifold
 * edges is turned the way that flips fewer of its triangles. Every closed
 * piece ends outward, holes included: deciding holes by nesting is left to
 * the caller (the distance index does it by parity). A non-orientable piece
 * (a Moebius strip) keeps misoriented edges; mx_surface_defects_find counts
 * them afterwards. *flipped (may be NULL) receives the number of triangles
 * flipped. MX_OK, MX_ENOMEM, or MX_EINPUT (bad index). Deterministic,
 * idempotent. */
int mx_surface_orient(mx_trisoup *s, size_t *flipped);

/* One line ('\n'-terminated) per kind of defect present, with its count
 * and the first few examples (triangle numbers within their input, and
 * "of input K" when the soup holds several; points with %g), or
 * "no defects\n". Always NUL-terminated (truncated to n bytes). */
void mx_surface_defects_describe(const mx_surface_defects *r,
                                 const mx_trisoup *s, char *buf, size_t n);

#endif
