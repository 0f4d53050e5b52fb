/* The bounding volume hierarchy over triangles: a binary tree in a flat
 * array (nodes[0] the root, the children of an internal node side by side),
 * built top-down by splitting the triangles at the median of their
 * centroids along the longest axis of the centroids' box, leaves of at most
 * MX_BVH_LEAF_MAX triangles; O(n log n), subtrees built as OpenMP tasks.
 * The tree's shape depends only on the triangle count: a node of m > 4
 * triangles gives floor(m / 2) to its left child. Used by the surface index
 * (geom/distance.h: closest points, winding number).
 *
 * The broad phase of the self-intersection test (geom/surface_defects.c)
 * traverses a tree of the same nodes against itself; that tree is built
 * along a Morton curve instead, in O(n): the median split costs about as
 * much as the whole test on a large surface (327,680 triangles: 0.16 s for
 * the build against 0.14 to 0.2 s for the former test's build, traversal
 * and exact tests together, one thread). */
#ifndef MX_BVH_H
#define MX_BVH_H

#include <stddef.h>
#include <stdint.h>

#define MX_BVH_LEAF_MAX 4

typedef struct {
  double lo[3], hi[3]; /* bounding box of the triangles below */
  uint32_t first;      /* leaf: first slot; internal: left child (right = first + 1) */
  uint32_t count;      /* leaf: 1..4 triangles; internal: 0 */
  uint32_t ntri;       /* triangles (slots) below */
  uint32_t pad_;
} mx_bvh_node;

/* Nodes of the tree of m >= 1 triangles. */
size_t mx_bvh_node_count(size_t m);

/* Builds the tree of the nt >= 1 triangles tri[3 t .. 3 t + 2] (vertex
 * indices into x, y, z) into nodes (mx_bvh_node_count(nt) of them). cen:
 * the centroids, cen[a * nt + t] for axis a. idx: the triangles 0 .. nt-1
 * on input (their order decides the order of ties), the triangle of each
 * slot (the tree's order) on output. The same tree for any thread count. */
void mx_bvh_build(mx_bvh_node *nodes, uint32_t *idx, const double *cen, uint32_t nt,
                  const uint32_t *tri, const double *x, const double *y,
                  const double *z);

/* The tree of the broad phase, cheaper to build (O(n)). The slots are
 * items sorted along a Morton curve (mx_morton_sort30: 30-bit codes, ties by
 * item); each node is split at the highest bit where its first and last
 * codes differ (the middle when they do not), leaves of at most
 * MX_BVH_LEAF_MAX slots. code and box (6 per slot: lo, hi) are in slot
 * order; nodes needs 2 n entries. Returns the nodes used. */
uint32_t mx_bvh_build_morton(mx_bvh_node *nodes, const uint32_t *code, const double *box,
                             uint32_t n);

/* Sorts code[0..n) (values below 2^30) with order alongside, stably (ties
 * keep their order): an LSD radix sort, 3 passes of 10 bits. MX_OK or
 * MX_ENOMEM. */
int mx_morton_sort30(uint32_t *code, uint32_t *order, uint32_t n);

/* The traversal of the broad phase: geom/bvh_pairs.h. */

#endif
