/* The bounding volume hierarchy over triangles: a binary tree in a flat
 * array (nodes[0] the root, the children of an internal node side by side),
 * built top-down by splitting the triangles at the median of their
 * centroids along the longest axis of the centroids' box, leaves of at most
 * MX_BVH_LEAF_MAX triangles; O(n log n), subtrees built as OpenMP tasks.
 * The tree's shape depends only on the triangle count: a node of m > 4
 * triangles gives floor(m / 2) to its left child. Used by the surface index
 * (geom/distance.h: closest points, winding number). */
#ifndef MX_BVH_H
#define MX_BVH_H

#include <stddef.h>
#include <stdint.h>

#define MX_BVH_LEAF_MAX 4

typedef struct {
  double lo[3], hi[3]; /* bounding box of the triangles below */
  uint32_t first;      /* leaf: first slot; internal: left child (right = first + 1) */
  uint32_t count;      /* leaf: 1..4 triangles; internal: 0 */
  uint32_t ntri;       /* triangles below */
  uint32_t pad_;
} mx_bvh_node;

/* Nodes of the tree of m >= 1 triangles. */
size_t mx_bvh_node_count(size_t m);

/* Builds the tree of the nt >= 1 triangles tri[3 t .. 3 t + 2] (vertex
 * indices into x, y, z) into nodes (mx_bvh_node_count(nt) of them). cen:
 * the centroids, cen[a * nt + t] for axis a. idx: nt entries in any order
 * on input (the triangles 0 .. nt-1), the triangle of each slot (the
 * tree's order) on output. The same tree for any thread count. */
void mx_bvh_build(mx_bvh_node *nodes, uint32_t *idx, const double *cen, uint32_t nt,
                  const uint32_t *tri, const double *x, const double *y,
                  const double *z);

#endif
