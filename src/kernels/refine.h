/* Refinement and balance of the octree (Jaillet & Lobos 2021, Algorithm 1).
 *
 * mx_build_roots        the root grid, each root classified once
 * mx_refine_balanced    level-synchronous refinement of the `candidates`,
 *                       balancing with the edge infos after each level
 *                       (src/kernels/balance.c: mx_balance_drain); then, as
 *                       after the recursive balance, the closures
 *                       (kernels/closures.h: mx_resolve_closures)
 * mx_refine_unbalanced  the same refinement without edge infos; then
 * mx_balance_recursive  the published original's balance at the end, by
 *                       recursive neighbour search in a pointer tree
 *                       (src/kernels/balance_recursive.c)
 *
 * Every split goes through mx_split_octants: children are classified in
 * parallel (each child tests only its parent's triangles, by separating
 * axes; a child that meets no triangle inherits its parent's side, or, if its
 * parent met the surface, is located once by ray parity), counted, prefix-
 * summed and filled; children outside the domain are never stored. */
#ifndef MX_REFINE_H
#define MX_REFINE_H

#include <stddef.h>
#include <stdint.h>

#include "kernels/builder.h"
#include "kernels/leaves.h"


int mx_build_roots(mx_builder *B);
int mx_refine_balanced(mx_builder *B);
int mx_refine_unbalanced(mx_builder *B);
int mx_balance_recursive(mx_builder *B);

/* Split the octants of `list` (all of one level, all leaves). With edge
 * infos on, registers the children's edges and marks the parents' edges. */
int mx_split_octants(mx_builder *B, const uint32_t *list, size_t n,
                     int for_balance);

/* Drain to_balance (src/kernels/balance.c): starting from the octants just
 * split (one level), push every coarser leaf that touches one of them and is
 * now two levels coarser than its children, split those, and repeat one level
 * coarser until nothing is left. */
int mx_balance_drain(mx_builder *B, const uint32_t *split, size_t n);


#endif
