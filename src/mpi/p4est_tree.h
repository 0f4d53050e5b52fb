/* A rank's patch octree made straight from the patch's leaves (issue 31,
 * item 5), instead of refining again from their ancestors as split set.
 *
 * The patch (src/mpi/p4est_mesh.h) is this rank's leaves in the domain and
 * the halo's (p4est_halo.h). Each leaf already carries what the
 * single-process refinement would compute for it: its flags, regions and
 * triangle list (mx_pq, classified as kernels/refine.c classifies). This
 * rank's are in its forest; the halo's are asked of their owners in one
 * round (the keys out, the data and the triangle ids back: two
 * all-to-alls). Then the octree is laid out in O(n) passes over the leaves
 * sorted by key, level by level (at most MX_MAX_LEVEL + 1 passes):
 *
 * - the octants of level l are the distinct ancestors (key masked to level
 *   l) of the leaves of level >= l, in key order; a run of equal masked
 *   keys is one octant, so they come out sorted and unique;
 * - levels are stored one after the other, coarsest first: the children of
 *   an octant are then contiguous and in child order (soa/octree.h), and
 *   each octant finds its parent by a merge walk with the level above;
 * - a leaf's octant takes the leaf's data; a split octant is flagged
 *   MX_OCT_SPLIT, kept = its children present, and the surface flag and
 *   regions met of its children (the stages after the octree read neither
 *   on split octants);
 * - the edge infos of the levels that have split octants are registered
 *   family by family, as the refinement registers a split's children
 *   (mx_edges_register_children), the tables sized from the edges made so
 *   far rather than for the worst case.
 *
 * What differs from the octree rebuilt by refinement (mx_build_tree from
 * the split set): only octants outside the patch. That one also held the
 * siblings of the patch's outermost leaves and the leaves its balance and
 * closures made around them; here the patch ends at its leaves. Every leaf
 * of the patch but those of its outermost ring has all its touching leaves
 * in the patch, so its transition mask, and the mesh as far in as the rings
 * were chosen for, are the same (the shared nodes are compared across the
 * ranks, p4est_nodes.c, as before). MX_P4EST_CHECK_TREE=1 in the
 * environment builds both and compares the patch's leaves (levels, flags,
 * regions, triangle lists) before meshing: the tests' check. */
#ifndef MX_P4EST_TREE_H
#define MX_P4EST_TREE_H

#include "mesher/mesher.h"
#include "mpi/p4est_halo.h"
#include "mpi/p4est_octree.h"

/* The patch's leaves sorted by key, with their data: pq[i].tri_off indexes
 * tri (this rank's copy). */
typedef struct {
  uint64_t *key;
  uint8_t *level;
  int32_t *owner;
  mx_pq *pq;
  uint32_t *tri;
  size_t n, ncore, ntri;
} mx_patch_leaves;

/* This rank's leaves and the halo's, with the halo's data asked of their
 * owners. st: this rank's status so far (a failure is everyone's). *sent
 * and *largest as mx_exchange counts them. Collective. */
int mx_patch_leaves_get(const mx_p4est_octree *P, const mx_halo *H, int st, mx_patch_leaves *S,
                        long long *sent, long long *largest);
void mx_patch_leaves_free(mx_patch_leaves *S);

/* m's octree made from the leaves of S: m's builder set up over its inputs
 * (mx_builder_init, no requests), the octants, the leaf list (m->leaves:
 * S's leaves in their order). Not collective. */
int mx_patch_tree_build(mx_mesher *m, const mx_patch_leaves *S);

#endif
