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

/* meets[i] = 1 when leaf leaves[i] meets a triangle of the lists: its own
 * list is not empty, or it touches a domain triangle lying in the plane of
 * one of its faces (of its first ancestor's list that is not empty). The
 * lists are made with the boxes in floating point (kernels/refine.c), and a
 * triangle in a lattice plane (the flat faces of a CAD part, aligned with
 * the axes) can fall in the rounding gap of a box while a larger box
 * around it meets it: a leaf inside the domain whose face lies on the
 * surface then has no triangle (its nodes are taken inside without a
 * query; a boundary face of it would be missed). Only leaves with a face in
 * the plane of such a triangle are looked at (none for a curved input),
 * against their box grown by 1e-9 of its side. MX_ENOMEM or MX_OK. */
int mx_leaves_meeting(const mx_tree *tr, const uint32_t *leaves, size_t n, uint8_t *meets);

/* The leaves as hexahedra (the octree stage's output, hanging nodes and
 * all): nodes numbered in Morton order of their lattice points, corners in
 * VTK order, level per cell. */
int mx_leaf_hex_mesh(const mx_tree *tr, const uint32_t *leaves, size_t n, mx_mesh *out);

#endif
