/* Refinement and balance of the octree (Jaillet & Lobos 2021, Algorithm 1).
 *
 * mx_build_roots        the root grid, each root classified once
 * mx_refine_balanced    level-synchronous refinement of the `candidates`,
 *                       balancing with the edge infos after each level
 *                       (src/kernels/balance.c: mx_balance_drain)
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

#include "kernels/grid.h"
#include "geom/locate.h"
#include "kernels/requests.h"
#include "soa/edges.h"
#include "soa/octree.h"
#include "soa/trisoup.h"

typedef struct {
  size_t split_requested;  /* octants split because a request asked */
  size_t split_balance;    /* octants split to restore balance */
  size_t located;          /* ray-parity queries */
  size_t dropped;          /* children found outside and not stored */
  double t_refine, t_balance; /* seconds */
} mx_refine_stats;

typedef struct {
  const mx_trisoup *soup;
  uint32_t nt_domain;         /* triangles [0, nt_domain) bound the domain */
  uint8_t *tri_region;        /* per triangle: region index, 255 = domain */
  double *tri_xyz;            /* 9 coordinates per triangle */
  mx_locator loc_domain;
  mx_locator loc_region[MX_MAX_REGIONS];
  mx_requests req;
  mx_grid grid;
  mx_octree oct;
  mx_edges edges;
  int use_edges;              /* maintain edge infos while splitting */
  int edge_levels;            /* edge infos kept for levels <= this one */
  /* Deeper levels, reached by refining an existing octree, hold edge infos
   * only where needed (mx_edges_ensure, kernels/remesh.c): the octants split
   * there and their face and edge neighbours (flag MX_OCT_EDGES). The
   * deepest such level, -1 for none. */
  int edge_lazy_top;
  /* The edge infos were freed after the transition masks (mx_edges_release,
   * kernels/remesh.h) and are rebuilt when a split needs them; the counts
   * they had are kept for the summary. */
  int edges_released;
  size_t released_edges, released_edge_bytes;
  uint32_t *root_of;          /* root octant of each root cube (lazy) */
  mx_refine_stats stats;
  /* Optional (NULL by default): octants that must be split whatever the
   * requests ask, sorted (mx_octkeys_sort_unique); a restart file's octree
   * is rebuilt from the split ancestors of its leaves, and tests split
   * chosen leaves in a from-scratch run. Set after mx_builder_init, with
   * edge_levels raised to the deepest level split. */
  const uint64_t *split_keys[MX_MAX_LEVEL + 1]; /* per level, sorted */
  size_t nsplit[MX_MAX_LEVEL + 1];
  /* Optional, NULL by default: called by the level loop of
   * mx_refine_balanced / mx_refine_unbalanced before each level is created,
   * with that level (1..max_level) and the finest level asked; never from a
   * parallel region. Set it after mx_builder_init (which clears the
   * builder). The program uses it for its progress line. */
  void (*on_level)(void *user, int level, int max_level);
  void *on_level_user;

  /* scratch of mx_split_octants, grown on demand, reused */
  uint8_t *scratch_mask;
  size_t scratch_mask_cap;
  void *scratch_info;
  size_t scratch_info_cap;
  uint64_t *scratch_off;
  size_t scratch_off_cap;
} mx_builder;

/* soup: domain triangles first (nt_domain of them), then the triangles of
 * each region surface r in [region_t0[r], region_t0[r+1]). */
/* 1 when (key, level) is in the builder's split set. */
int mx_split_set_has(const mx_builder *B, uint64_t key, int level);

/* The deepest level whose octants can have edge infos (the transition looks
 * edges up for leaves up to this level). */
static inline int mx_edge_top(const mx_builder *B) {
  return B->edge_lazy_top > B->edge_levels ? B->edge_lazy_top : B->edge_levels;
}

int mx_builder_init(mx_builder *B, const mx_trisoup *soup, uint32_t nt_domain,
                    const uint32_t *region_t0, const mx_requests *req,
                    int use_edges, const char *name);
void mx_builder_free(mx_builder *B);

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

/* Leaves (src/kernels/leaves.c): indices of the octants not split, in index
 * order (deterministic); *out allocated with mx_alloc. */
int mx_leaves(const mx_builder *B, uint32_t **out, size_t *n);
/* Reorder leaves into Morton order of their anchors (unique among leaves),
 * the canonical order of every output. */
int mx_leaves_sorted(const mx_builder *B, uint32_t *leaves, size_t n);
/* Order-independent fingerprint of the set of (key, level) leaf pairs. */
uint64_t mx_leaves_hash(const mx_builder *B, const uint32_t *leaves, size_t n);
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
typedef struct {
  size_t nnodes, ncells;
  double *xyz;      /* 3 * nnodes */
  uint32_t *conn;   /* 8 * ncells */
  int32_t *level;   /* ncells */
} mx_hexmesh;
int mx_leaf_hex_mesh(const mx_builder *B, const uint32_t *leaves, size_t n,
                     mx_hexmesh *out);
void mx_hexmesh_free(mx_hexmesh *h);

#endif
