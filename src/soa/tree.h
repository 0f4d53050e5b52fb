/* The tree every stage after refinement reads: the root grid, the octree
 * (soa/octree.h) and its edge infos (soa/edges.h), with the coordinates of
 * the triangles the octants' lists name. The refinement builder
 * (kernels/refine.h) owns one and fills it; the transition, the boundary
 * stage, the splice and the writers of the octree take it read-only and
 * never the builder. */
#ifndef MX_SOA_TREE_H
#define MX_SOA_TREE_H

#include <stddef.h>
#include <stdint.h>

#include "soa/edges.h"
#include "soa/grid.h"
#include "soa/octree.h"

typedef struct {
  mx_grid grid;
  mx_octree oct;
  mx_edges edges;
  int use_edges;              /* edge infos maintained while splitting */
  int edge_levels;            /* edge infos kept for levels <= this one */
  /* Deeper levels, reached by refining an existing octree, hold edge infos
   * only where needed (mx_edges_ensure, kernels/edges_lazy.h): the octants
   * split there and their face and edge neighbours (flag MX_OCT_EDGES). The
   * deepest such level, -1 for none. */
  int edge_lazy_top;
  /* The edge infos were freed after the transition masks (mx_edges_release,
   * kernels/edges_lazy.h) and are rebuilt when a split needs them; the
   * counts they had are kept for the summary. */
  int edges_released;
  size_t released_edges, released_edge_bytes;
  uint32_t *root_of;          /* root octant of each root cube (lazy) */
  double *tri_xyz;            /* 9 coordinates per triangle of the lists */
  uint32_t nt_domain;         /* triangles [0, nt_domain) bound the domain */
} mx_tree;

/* The deepest level whose octants can have edge infos (the transition looks
 * edges up for leaves up to this level). */
static inline int mx_edge_top(const mx_tree *t) {
  return t->edge_lazy_top > t->edge_levels ? t->edge_lazy_top : t->edge_levels;
}

#endif
