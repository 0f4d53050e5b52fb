/* Surface topology of a triangle list: its edges with the triangles that
 * use them, and its shells with a consistent orientation.
 *
 * Half-edges. Triangle i of the list has the half-edges h = 3 i + k, from
 * its vertex k to its vertex (k + 1) mod 3; the list is either the triangles
 * of a vertex array (tri[3 i .. 3 i + 2]) or a reordering of them (order[i]
 * names the triangle of tri that is the list's triangle i), so that the
 * distance index can list its triangles in BVH order.
 *
 * Edges. An edge is an unordered pair of vertex indices; the edge table
 * lists the half-edges grouped by edge ("runs"), the edges in increasing
 * (smaller vertex, larger vertex) and each run in increasing h. It is made
 * by a counting sort on the smaller vertex and a sort of each bucket, O(n +
 * nv) plus the buckets' sorts. A run of length 1 is an open edge, of length 2 a manifold edge, of
 * 3 or more a non-manifold one; the two half-edges of a manifold edge agree
 * (the same orientation) when they run in opposite directions.
 *
 * Shells. A breadth-first search from the smallest unvisited triangle
 * through the edges (through the manifold edges only, or through every
 * edge) gives each triangle its shell and a flip bit relative to the
 * shell's seed: across a manifold edge the neighbour is flipped when it runs
 * the edge in the same direction, across a non-manifold edge it keeps its
 * given orientation. A manifold edge whose two triangles still disagree
 * once both are reached is a conflict (a non-orientable shell). Which way
 * each shell is finally turned (outward, by nesting, as given) is the
 * caller's. */
#ifndef MX_SURFACE_TOPOLOGY_H
#define MX_SURFACE_TOPOLOGY_H

#include <stddef.h>
#include <stdint.h>

typedef struct {
  const uint32_t *tri;   /* the vertex array */
  const uint32_t *order; /* NULL, or list triangle -> triangle of tri */
  uint32_t ntri;         /* triangles in the list */
  size_t n;              /* half-edges in the table */
  uint64_t *key;         /* n: (smaller vertex << 32) | larger, by runs */
  uint32_t *half;        /* n: the half-edge of each entry */
  uint32_t *first;       /* 3 ntri (with_first): the place of the start of
                            the run of half-edge h, UINT32_MAX if not listed */
} mx_edge_table;

/* Vertex k of list triangle i. */
static inline uint32_t mx_edge_vertex(const mx_edge_table *T, uint32_t i, int k) {
  return T->tri[3 * (size_t)(T->order ? T->order[i] : i) + k];
}
/* Start vertex of half-edge h. */
static inline uint32_t mx_half_start(const mx_edge_table *T, uint32_t h) {
  return mx_edge_vertex(T, h / 3, (int)(h % 3));
}
/* End of the run that starts at place j. */
static inline size_t mx_edge_run_end(const mx_edge_table *T, size_t j) {
  size_t e = j + 1;
  while (e < T->n && T->key[e] == T->key[j]) e++;
  return e;
}

/* The edge table of the list (vertex indices below nv); skip_repeats:
 * triangles that repeat a vertex are left out; with_first: fill T->first.
 * MX_OK or MX_ENOMEM. */
int mx_edge_table_build(mx_edge_table *T, const uint32_t *tri, const uint32_t *order,
                        uint32_t ntri, uint32_t nv, int skip_repeats, int with_first);
void mx_edge_table_free(mx_edge_table *T);

/* The edges of the triangles tri[0 .. 3 ntri) (vertices below nv) used by
 * other than exactly
 * two half-edges (open or non-manifold), counted from the buckets alone (no
 * table kept). MX_OK or MX_ENOMEM. */
int mx_edges_open(const uint32_t *tri, uint32_t ntri, uint32_t nv, size_t *open);

/* Shells of the list (needs T->first): shell[i] (UINT32_MAX for a
 * triangle left out of the table), flip[i] relative to the seed;
 * through_all: also join through the non-manifold edges. seed (may be
 * NULL) receives, allocated with mx_alloc, the first triangle of each
 * shell; conflicts (may be NULL) the manifold edges left disagreeing.
 * MX_OK or MX_ENOMEM. */
int mx_surface_shells(const mx_edge_table *T, int through_all, uint32_t *shell,
                      uint8_t *flip, uint32_t *nshells, uint32_t **seed,
                      size_t *conflicts);

#endif
