/* The transition stage: every balanced leaf becomes the elements of its
 * transition pattern, giving a conforming mesh of the whole octree.
 *
 * 1. Node mask of each leaf (leaf_mask in transition.c): an edge midpoint is a node when
 *    a finer leaf has it as a corner, i.e. when an octant of the leaf's level
 *    around that edge (its edge infos) is split with a kept child along it; a
 *    face centre likewise from the octant across the face. Where a face has
 *    a centre but a neighbour's children were dropped outside the domain, the
 *    face's missing edge midpoints are added (closure), since a face centre
 *    comes with all four midpoints in the patterns.
 * 2. (class, rotation) from the precomputed table: O(1).
 * 3. Nodes: every lattice point a pattern uses is inserted in a concurrent
 *    hash with its owner, the first leaf (in Morton order) using it; node
 *    numbers follow the owners' Morton order whatever the thread count.
 * 4. Elements: filled in parallel, with J_ENS.
 * The passes of 2-4 cut the leaves into one Morton range per thread, the
 * same in every pass, and keep running offsets within it (no per-leaf
 * offset arrays); the hash is freed before most of the mesh is allocated,
 * which takes its memory (see mx_transition_build in transition.c). */
#ifndef MX_TRANSITION_H
#define MX_TRANSITION_H

#include <stddef.h>
#include <stdint.h>

#include "soa/tree.h"
#include "soa/mesh.h"


/* leaves: the balanced leaves, in Morton order (mx_leaves_sorted). */
int mx_transition(const mx_tree *tr, const uint32_t *leaves, size_t n,
                  mx_mesh *out);
/* The same in two steps, so that the caller can free the edge infos in
 * between (only step 1 reads them): the masks (with the closures), then
 * everything else; mx_transition_build takes over lm->mask (freed): n + 1
 * masks, then n + 1 words of scratch for the build, one allocation. */
typedef struct {
  uint32_t *mask;
  size_t closures;
} mx_leaf_masks;
int mx_transition_masks(const mx_tree *tr, const uint32_t *leaves, size_t n,
                        mx_leaf_masks *lm);
int mx_transition_build(const mx_tree *tr, const uint32_t *leaves, size_t n,
                        mx_leaf_masks *lm, mx_mesh *out);

#endif
