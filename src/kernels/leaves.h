/* The leaves of a tree (src/kernels/leaves.c): listed, in Morton order,
 * hashed, and as hexahedra (the octree stage's output). */
#ifndef MX_LEAVES_H
#define MX_LEAVES_H

#include <stddef.h>
#include <stdint.h>

#include "soa/mesh.h"
#include "soa/tree.h"

/* Indices of the octants not split, in index
 * order (deterministic); *out allocated with mx_alloc. */
int mx_leaves(const mx_tree *tr, uint32_t **out, size_t *n);
/* Reorder leaves into Morton order of their anchors (unique among leaves),
 * the canonical order of every output. */
int mx_leaves_sorted(const mx_tree *tr, uint32_t *leaves, size_t n);
/* Order-independent fingerprint of the set of (key, level) leaf pairs. */
uint64_t mx_leaves_hash(const mx_tree *tr, const uint32_t *leaves, size_t n);
/* Its parts, for leaves held elsewhere (the distributed octree, src/mpi/):
 * the hash is mx_leaf_hash_finish(sum of the terms, count). */
uint64_t mx_leaf_hash_term(uint64_t key, int level);
uint64_t mx_leaf_hash_finish(uint64_t sum, uint64_t n);
/* 1 when octants (ka, la) and (kb, lb) share a face or an edge, or part of
 * one (contact of dimension 1 or 2; corner contact does not count). */
int mx_octants_touch(uint64_t ka, int la, uint64_t kb, int lb);

/* The leaves as hexahedra (the octree stage's output, hanging nodes and
 * all): nodes numbered in Morton order of their lattice points, corners in
 * VTK order, level per cell. */
int mx_leaf_hex_mesh(const mx_tree *tr, const uint32_t *leaves, size_t n, mx_mesh *out);

#endif
