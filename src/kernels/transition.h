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
 *    hash with its owner, the first leaf (in Morton order) using it; owners
 *    count their nodes, a prefix sum gives the numbering, so node numbers
 *    follow the leaves' Morton order whatever the thread count.
 * 4. Elements: counted, prefix-summed, filled in parallel, with J_ENS. */
#ifndef MX_TRANSITION_H
#define MX_TRANSITION_H

#include <stddef.h>
#include <stdint.h>

#include "kernels/refine.h"

typedef struct {
  size_t nnodes, ncells;
  double *xyz;      /* 3 * nnodes */
  uint8_t *type;    /* ncells */
  uint32_t *conn;   /* 8 * ncells, VTK order */
  uint8_t *level;   /* level of the leaf each element comes from */
  uint32_t *leaf;   /* index (in the leaves list) of that leaf */
  float *jens;      /* J_ENS of each element (computed in double, kept in
                     * float: 4 bytes instead of 8 for every element) */
  uint64_t *nkey;   /* per node: its lattice key (mx_lattice_key), or
                     * MX_NKEY_NONE for a node off the lattice (an element
                     * centre of the surface patterns); kept by every edit */
  size_t closures;  /* face midpoints added by the closure */
  size_t centre_leaves; /* leaves whose pattern uses the body centre */
  size_t by_type[4];
  double jens_min;
  size_t invalid;   /* elements with J_ENS < 1e-6 */
} mx_mesh_out;
#define MX_NKEY_NONE UINT64_MAX

/* leaves: the balanced leaves, in Morton order (mx_leaves_sorted). */
int mx_transition(const mx_builder *B, const uint32_t *leaves, size_t n,
                  mx_mesh_out *out);
/* The same in two steps, so that the caller can free the edge infos in
 * between (only step 1 reads them): the masks (with the closures), then
 * everything else; mx_transition_build takes over lm->mask (freed). */
typedef struct {
  uint32_t *mask;
  size_t closures;
} mx_leaf_masks;
int mx_transition_masks(const mx_builder *B, const uint32_t *leaves, size_t n,
                        mx_leaf_masks *lm);
int mx_transition_build(const mx_builder *B, const uint32_t *leaves, size_t n,
                        mx_leaf_masks *lm, mx_mesh_out *out);
void mx_mesh_out_free(mx_mesh_out *m);

#endif
