/* The octree's invariants, checked in debug builds after every refinement
 * (as p4est's p4est_is_valid): what soa/octree.h and soa/edges.h promise,
 * checked from the arrays alone (no kernel's neighbour search, no edge
 * infos for the balance).
 *
 * What is checked (the first violation, in octant index order, is named in
 * one message "internal: octree invariant broken after WHERE: ..." and
 * MX_EINTERNAL returned):
 *
 * (a) complete: the stored octants form a forest over the root grid. A root
 *     (parent MX_NONE) has level 0, a key on the root lattice inside dims,
 *     and is the only root of its cube. Every other octant has level
 *     <= MX_MAX_LEVEL, a key aligned to its level, a parent of the level
 *     above with an index below its own, flagged MX_OCT_SPLIT, whose key is
 *     this key's parent key, whose kept bit for this child is set and whose
 *     child slot (child0 + popcount of the kept bits before it) is this
 *     octant. A leaf has child0 MX_NONE and kept 0; a split octant has
 *     child0 MX_NONE exactly when kept is 0 (all its children outside the
 *     domain) and its kept children inside the array. The octants that are
 *     not roots are as many as the kept bits of the split octants, so every
 *     kept bit holds exactly one stored child. Children found outside the
 *     domain are not stored: "complete" means every part of a root cube is
 *     either one leaf or a child that a split octant did not keep.
 * (b) sorted: the leaves (octants not MX_OCT_SPLIT), sorted by key, have
 *     strictly increasing keys and do not overlap: a leaf's Morton range
 *     [key, key + 8^(MX_MAX_LEVEL - level)) ends at or before the next
 *     key. A list the pipeline made (mx_leaves_sorted) must be exactly that:
 *     every leaf once, in that order (mx_leaves_valid).
 * (c) balanced (when promised): no leaf is two or more levels coarser than
 *     a stored octant (leaf or split) touching it along a face or an edge
 *     (mx_octants_touch, kernels/leaves.h; the rule of balance.c and
 *     balance_recursive.c). Found with a hash of the leaves' keys: for each
 *     octant of level l >= 2 and each of its 18 face and edge neighbour
 *     cells of level l, the cell's ancestor of level l-2 must not be a
 *     leaf. That exact level is enough: a leaf coarser still would hold the
 *     neighbour cell of the octant's parent too (the parent is split, so it
 *     is not inside the leaf), and the parent's own check finds it.
 * (d) edge infos (when live: on and not released): each table's count is
 *     its number of used entries; every used entry is found by
 *     mx_edge_find at its own place (no key twice, none lost off its probe
 *     run) and has at least one slot set; a slot q of the level-l, axis-a
 *     edge with key k holds an octant of level l that may have edge infos
 *     (level <= edge_levels, or flagged MX_OCT_EDGES) whose edge j = 3 - q
 *     of axis a has the key k (mx_edge_key); every octant that must have
 *     them (level <= min(edge_levels, MX_MAX_LEVEL - 1), or flagged
 *     MX_OCT_EDGES, the flag only at levels <= edge_lazy_top) is in all 12
 *     of its edges at its slot. The edge infos hold no mid-node: it is read
 *     from the octants in the slots when needed (soa/edges.h), so there is
 *     nothing more to keep consistent.
 *
 * Cost: O(n) in parallel: a radix sort of the leaf keys, one edge-table
 * lookup per edge (the registrations are counted, not looked up: see
 * check_edges), at most 18 hash lookups per octant for (c), most of them
 * skipped. About half the octree build's CPU time (the cortex at -s 7).
 * Never in a release build: see MX_INVARIANTS below. */
#ifndef MX_TREE_VALID_H
#define MX_TREE_VALID_H

#include <stddef.h>
#include <stdint.h>

#include "soa/tree.h"

/* MX_INVARIANTS: 1 where NDEBUG is not defined (meson's debug and
 * debugoptimized build types; the release build defines NDEBUG, b_ndebug
 * = if-release), or set on the compiler's command line (-DMX_INVARIANTS=1:
 * the test 'invariants' builds the refining files so). 0: the checks
 * compile to nothing. */
#ifndef MX_INVARIANTS
#ifdef NDEBUG
#define MX_INVARIANTS 0
#else
#define MX_INVARIANTS 1
#endif
#endif

/* What the caller promises about the octree it passes. */
enum {
  MX_TREE_BALANCED = 1, /* (c) holds */
};

/* The checks (a), (b), (c) when promise has MX_TREE_BALANCED, (d) when the
 * tree's edge infos are live (use_edges, not released), on the tree's
 * octree, root grid and edge infos. where: "after ..." for the message.
 * MX_OK, MX_EINTERNAL (message printed) or MX_ENOMEM. */
int mx_tree_valid(const mx_tree *t, int promise, const char *where);

/* (b) for a leaf list: leaves[0..n) is every leaf of t once, in strictly
 * increasing key order, none overlapping the next. */
int mx_leaves_valid(const mx_tree *t, const uint32_t *leaves, size_t n, const char *where);

/* How many checks ran in this process (a test makes sure its debug
 * variant really checks). */
size_t mx_tree_valid_runs(void);

/* The call lines in the kernels and the mesher; nothing at all when
 * MX_INVARIANTS is 0. */
#if MX_INVARIANTS
#define MX_TREE_INVARIANTS(t, promise, where) MX_CHECK(mx_tree_valid((t), (promise), (where)))
#define MX_LEAVES_INVARIANTS(t, leaves, n, where) \
  MX_CHECK(mx_leaves_valid((t), (leaves), (n), (where)))
#else
#define MX_TREE_INVARIANTS(t, promise, where) ((void)0)
#define MX_LEAVES_INVARIANTS(t, leaves, n, where) ((void)0)
#endif

#endif
