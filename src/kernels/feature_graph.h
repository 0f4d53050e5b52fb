/* The boundary as a graph, for placing sharp features (internal to
 * kernels/feature_place.c and its parts):
 *
 *   feature_graph.c   the graph of the boundary faces near the features,
 *                     with a grid of its nodes;
 *   feature_lines.c   corners onto nodes, ridges onto chains of edges (the
 *                     searches, their second tries at crowded corners);
 *   feature_sides.c   the nodes beside a ridge onto their own side's face.
 *
 * Serial and deterministic: the corners and lines in their order. */
#ifndef MX_FEATURE_GRAPH_H
#define MX_FEATURE_GRAPH_H

#include <math.h>
#include <stddef.h>
#include <stdint.h>

#include "io/boundary_faces.h"
#include "geom/distance.h"
#include "kernels/feature_types.h"
#include "soa/mesh.h"

/* The boundary as a graph, with a grid of its nodes. */
typedef struct {
  mx_mesh *M;
  const uint8_t *fixed;
  mx_boundary_faces bf;
  size_t nf;             /* faces: triangles, then quadrilaterals */
  size_t nrun;           /* edge-face pairs, sorted by edge */
  uint64_t *rkey;        /* their edges (least node << 32 | other) */
  uint32_t *rface;       /* their faces */
  size_t ne;             /* distinct edges */
  uint32_t *estart;      /* ne + 1: edge e's pairs */
  uint8_t *eline;        /* per edge: on a placed line */
  uint8_t *qdiag;        /* per quadrilateral: 0, or 1 + the diagonal a line takes */
  size_t nsplit;         /* quadrilaterals with a diagonal taken */
  uint32_t *aoff, *adj, *aedge; /* per node: neighbours and the edges to them
                                 * (edge ne + 2 q + d: diagonal d of quad q) */
  size_t nb;             /* boundary nodes, sorted by grid cell */
  uint64_t *bkey;
  uint32_t *bnode;
  double lo[3], h;       /* the grid: cells of side h from lo */
  uint32_t *loc;         /* per node: its place in the current tube, or UINT32_MAX */
  const uint32_t *exit_of; /* NULL, or per node: the line whose corner exit it
                            * is (UINT32_MAX: none), closed to other lines */
  uint32_t line;          /* the line being placed */
} mx_fgraph;

/* A feature takes a node within this many mean boundary edges of it only
 * (the patch of a local re-mesh does not reach every feature). */
#define MX_FEATURE_REACH 4.0

static inline const uint32_t *mx_fgraph_face(const mx_fgraph *G, size_t f, int *n) {
  if (f < G->bf.ntri) {
    *n = 3;
    return G->bf.tri + 3 * f;
  }
  *n = 4;
  return G->bf.quad + 4 * (f - G->bf.ntri);
}

static inline double mx_fg_dist3(const double *a, const double *b) {
  return sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) +
              (a[2] - b[2]) * (a[2] - b[2]));
}

static inline uint64_t mx_fg_cell_key(int64_t i, int64_t j, int64_t k) {
  return (uint64_t)i << 42 | (uint64_t)j << 21 | (uint64_t)k;
}

static inline void mx_fg_cell_of(const mx_fgraph *G, const double *x, int64_t c[3]) {
  for (int a = 0; a < 3; a++) {
    const double t = floor((x[a] - G->lo[a]) / G->h);
    c[a] = t < 0 ? 0 : t > 2097151 ? 2097151 : (int64_t)t;
  }
}

/* mask[v] kept only for the nodes within about r of the lines or corners
 * of L (all those within 3 r / 4; none farther than 4 r): the region the
 * placement may touch when r is a few octants at the feature level.
 * Parallel, O(n log(length / r)). */
int mx_feature_near_nodes(const mx_feature_lines *L, double r, const double *xyz, size_t n,
                          uint8_t *mask);

/* The boundary faces whose nodes are all on the surface (states
 * MX_NODE_OUTSIDE) and, with near > 0, within that of the features (
 * mx_feature_near_nodes), and their graph; mask: nnodes bytes of work
 * space. G->M and G->fixed set by the caller. */
int mx_fgraph_open(mx_fgraph *G, const uint8_t *states, uint8_t *mask, const mx_feature_lines *L,
                   double near);
void mx_fgraph_free(mx_fgraph *G);
/* Calls fn(ctx, v) for the boundary nodes of the cells within ring k of x. */
void mx_fgraph_cells_around(const mx_fgraph *G, const double *x, int64_t k,
                            void (*fn)(void *ctx, uint32_t v), void *ctx);
/* The closest boundary node to x not fixed yet (UINT32_MAX: none). */
uint32_t mx_fgraph_nearest_free(const mx_fgraph *G, const double *x);
/* The edge from u to w (a diagonal only while its quadrilateral has none
 * taken), or UINT32_MAX. */
uint32_t mx_fgraph_edge(const mx_fgraph *G, uint32_t u, uint32_t w);

/* The corners onto nodes and the lines onto chains of edges
 * (feature_lines.c): fixed (G->fixed) and moved[] set for the nodes placed,
 * st's corner, line and node counts; *chain (NULL: not wanted) the chains
 * placed; at most `retries` tries again at the corners of lines missed. */
int mx_fgraph_place_lines(mx_fgraph *G, const mx_feature_lines *L, int retries, uint8_t *moved,
                          mx_feature_stats *st, mx_feature_chain *chain);
/* The nodes of mask beside the placed lines onto their side's patch
 * (feature_sides.c); *count: how many moved. */
int mx_fgraph_sides(mx_fgraph *G, const mx_feature_input *in, const mx_surface_index *S,
                    const uint8_t *mask, uint8_t *moved, size_t *count);

#endif
