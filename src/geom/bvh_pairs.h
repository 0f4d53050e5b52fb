/* The broad phase over a BVH of geom/bvh.h: the tree traversed against
 * itself (the pairs within a node are those within each child and those
 * across the two children; a pair of nodes whose boxes do not meet is
 * dropped whole), calling MX_BVH_VISIT(ctx, i, j) once for every pair of
 * slots i < j whose closed boxes meet (compared exactly), in no particular
 * order of the pairs; the first levels run as OpenMP tasks.
 *
 * A template: the includer defines MX_BVH_VISIT (a function or macro taking
 * void *ctx and two uint32_t slots) before including this header, which
 * defines the static function
 *   mx_bvh_self_pairs(nodes, box, nslots, ctx)
 * (box: 6 per slot, lo then hi), so that the visit is a direct call (a call
 * through a pointer per pair cost a few percent of the self-intersection
 * test). */
#ifndef MX_BVH_PAIRS_H
#define MX_BVH_PAIRS_H

#ifndef MX_BVH_VISIT
#error "define MX_BVH_VISIT(ctx, i, j) before including geom/bvh_pairs.h"
#endif

#include <stdint.h>

#include "geom/bvh.h"

/* Recursion levels below which the traversal spawns tasks. */
#define MX_BVH_TASK_DEPTH 10

typedef struct {
  const mx_bvh_node *nodes;
  const double *box;
  void *ctx;
} mx_bvh_pair_walk;

static inline int mx_bvh_nodes_meet(const mx_bvh_node *a, const mx_bvh_node *b) {
  return a->lo[0] <= b->hi[0] && b->lo[0] <= a->hi[0] && a->lo[1] <= b->hi[1] &&
         b->lo[1] <= a->hi[1] && a->lo[2] <= b->hi[2] && b->lo[2] <= a->hi[2];
}

static inline int mx_bvh_boxes_meet(const double *a, const double *b) {
  return a[0] <= b[3] && b[0] <= a[3] && a[1] <= b[4] && b[1] <= a[4] &&
         a[2] <= b[5] && b[2] <= a[5];
}

/* Pairs between the subtrees a and b (every slot of a before every slot of
 * b: a left child precedes its sibling, so the pairs come as i < j). */
static void mx_bvh_cross_nodes(const mx_bvh_pair_walk *W, uint32_t a, uint32_t b,
                               int depth) {
  const mx_bvh_node *A = &W->nodes[a], *N = &W->nodes[b];
  if (!mx_bvh_nodes_meet(A, N)) return;
  if (A->count && N->count) {
    const double *box = W->box;
    for (uint32_t i = A->first; i < A->first + A->count; i++)
      for (uint32_t j = N->first; j < N->first + N->count; j++)
        if (mx_bvh_boxes_meet(box + 6 * (size_t)i, box + 6 * (size_t)j))
          MX_BVH_VISIT(W->ctx, i, j);
    return;
  }
  uint32_t a0 = a, a1 = a, b0 = b, b1 = b;
  if (N->count || (!A->count && A->ntri >= N->ntri))
    a0 = A->first, a1 = A->first + 1;
  else
    b0 = N->first, b1 = N->first + 1;
  if (depth < MX_BVH_TASK_DEPTH) {
#pragma omp task default(none) firstprivate(W, a0, b0, depth)
    mx_bvh_cross_nodes(W, a0, b0, depth + 1);
    mx_bvh_cross_nodes(W, a1, b1, depth + 1);
  } else {
    mx_bvh_cross_nodes(W, a0, b0, depth + 1);
    mx_bvh_cross_nodes(W, a1, b1, depth + 1);
  }
}

/* Pairs within the subtree id. */
static void mx_bvh_self_node(const mx_bvh_pair_walk *W, uint32_t id, int depth) {
  const mx_bvh_node *N = &W->nodes[id];
  if (N->count) {
    const double *box = W->box;
    for (uint32_t i = N->first; i < N->first + N->count; i++)
      for (uint32_t j = i + 1; j < N->first + N->count; j++)
        if (mx_bvh_boxes_meet(box + 6 * (size_t)i, box + 6 * (size_t)j))
          MX_BVH_VISIT(W->ctx, i, j);
    return;
  }
  const uint32_t l = N->first, r = N->first + 1;
  if (depth < MX_BVH_TASK_DEPTH) {
#pragma omp task default(none) firstprivate(W, l, depth)
    mx_bvh_self_node(W, l, depth + 1);
#pragma omp task default(none) firstprivate(W, r, depth)
    mx_bvh_self_node(W, r, depth + 1);
    mx_bvh_cross_nodes(W, l, r, depth + 1);
  } else {
    mx_bvh_self_node(W, l, depth + 1);
    mx_bvh_self_node(W, r, depth + 1);
    mx_bvh_cross_nodes(W, l, r, depth + 1);
  }
}

/* Every pair of slots whose boxes meet, in a parallel region of
 * omp_get_max_threads() threads (one when nslots <= 256). */
static void mx_bvh_self_pairs(const mx_bvh_node *nodes, const double *box,
                              uint32_t nslots, void *ctx) {
  if (nslots < 2) return;
  const mx_bvh_pair_walk W = {nodes, box, ctx};
  const mx_bvh_pair_walk *wp = &W;
#pragma omp parallel if (nslots > 256) default(none) shared(wp)
#pragma omp single
  mx_bvh_self_node(wp, 0, 0);
}

#endif
