/* The distributed octree's leaves against the single-process octree's.
 *
 * Both refine the same octants by the same requests and classify every
 * child by the same tests, so they differ only through the balance and
 * what follows it:
 *  - the single-process octree drops the children outside the domain, and
 *    its balance (and the recursive baseline's) looks only at stored
 *    octants; p4est keeps every octant and balances across the outside
 *    ones too. A fine leaf can split an outside octant, which splits a leaf
 *    in the domain on the other side of a thin outside gap: p4est finer
 *    there.
 *  - the single-process octree then splits the coarser leaves next to a
 *    face whose finer neighbour lost children outside the domain
 *    (mx_resolve_closures, for the transition's face closures); p4est
 *    loses no children, so it has no such splits: single-process finer
 *    there.
 * Since p4est's balance sees a superset of the single-process balance's
 * constraints, a region is finer in p4est only by the first cause and finer
 * in the single-process octree only by the second. */
#ifndef MX_P4EST_COMPARE_H
#define MX_P4EST_COMPARE_H

#include <stddef.h>
#include <stdint.h>

#include "base/morton.h"

typedef struct {
  size_t n_a, n_b;        /* leaves of A (p4est) and B (single-process) */
  size_t common;          /* the same (key, level) in both */
  size_t only_a, only_b;
  /* only_a = a_finer + a_coarser + a_alone: an A-only leaf lies inside a
   * coarser B leaf, or contains B leaves, or overlaps none */
  size_t a_finer, a_coarser, a_alone;
  size_t b_finer, b_coarser, b_alone;
  size_t only_a_level[MX_MAX_LEVEL + 1], only_b_level[MX_MAX_LEVEL + 1];
} mx_leaf_diff;

/* ka/la and kb/lb: two sets of disjoint octants sorted by key. Not
 * collective. */
void mx_leaf_diff_compute(const uint64_t *ka, const uint8_t *la, size_t na,
                          const uint64_t *kb, const uint8_t *lb, size_t nb, mx_leaf_diff *d);

/* Why p4est split a single-process leaf X of level l (a B leaf containing
 * A leaves): its balance did, so some quadrant of the forest two levels
 * finer touches X across a face or an edge. Each such X is counted once,
 * by the first that holds: a quadrant outside the domain does
 * (by_outside: the balance reached across the outside); a leaf in the
 * domain that the single-process octree has coarser does (by_chain: the
 * same, one step further); a leaf both octrees have does (by_common: the
 * single-process balance missed it, a bug); none does (unexplained: p4est
 * split X for no balance reason, a bug). */
typedef struct {
  size_t split, by_outside, by_chain, by_common, unexplained;
} mx_split_causes;

/* qa/la/kept: every quadrant of the forest (kept: in the domain), sorted by
 * key; kb/lb: the single-process leaves, sorted; dims: the root grid. */
void mx_leaf_diff_causes(const uint64_t *qa, const uint8_t *la, const uint8_t *kept, size_t na,
                         const uint64_t *kb, const uint8_t *lb, size_t nb, const int dims[3],
                         mx_split_causes *c);

#endif
