/* Sharp features placed in the mesh (kernels/feature_place.h): the pass,
 * over the parts of kernels/feature_graph.h, and the splits after it. */
#include "kernels/feature_place.h"

#include <string.h>

#include "base/common.h"
#include "kernels/cell_split.h"
#include "kernels/feature_graph.h"
#include "kernels/mesh_edit.h"

/* The elements of the quadrilaterals whose diagonal a line took split
 * along it (kernels/cell_split.h); fixed[] and moved[] grown with the new
 * nodes (not feature nodes; their elements' J_ENS set by the split). */
static int split_quads(mx_fgraph *G, uint8_t **states, uint8_t **fixed, uint8_t **moved,
                       mx_feature_stats *st, mx_split_log *log) {
  mx_mesh *M = G->M;
  const size_t n0 = M->nnodes;
  uint64_t *req = mx_alloc((G->nsplit + 1) * sizeof *req);
  if (!req) return MX_ENOMEM;
  size_t n = 0;
  for (size_t q = 0; q < G->bf.nquad; q++)
    if (G->qdiag[q]) {
      const uint64_t src = G->bf.quad_src[q]; /* 8 * element + face, in order */
      req[n++] = mx_split_request((size_t)(src >> 3), (int)(src & 7), G->qdiag[q] - 1);
    }
  int rc = mx_mesh_split_quads(M, states, req, n, NULL, log);
  mx_free(req);
  st->split += n;
  uint8_t *p[2] = {*fixed, *moved};
  for (int i = 0; i < 2 && !rc; i++) {
    uint8_t *q = mx_realloc(p[i], M->nnodes + 1);
    if (!q) rc = MX_ENOMEM;
    else {
      memset(q + n0, 0, M->nnodes - n0);
      p[i] = q;
    }
  }
  *fixed = p[0];
  *moved = p[1];
  return rc;
}

int mx_feature_place(mx_mesh *M, uint8_t **states, const mx_surface_index *S,
                     const mx_feature_input *in, uint8_t **fixed_io, mx_feature_stats *st,
                     mx_split_log *log, mx_feature_chain *chain) {
  memset(st, 0, sizeof *st);
  uint8_t *fixed = *fixed_io;
  memset(fixed, 0, M->nnodes);
  const double t0 = mx_wtime();
  const mx_feature_lines *L = in->L;
  if (!L || (!L->nlines && !L->ncorners) || !M->ncells) return MX_OK;
  mx_fgraph G;
  memset(&G, 0, sizeof G);
  G.M = M;
  G.fixed = fixed;
  uint8_t *mask = mx_alloc(M->nnodes + 1), *moved = mx_calloc(M->nnodes + 1);
  int rc = mask && moved ? MX_OK : MX_ENOMEM;
  if (!rc) rc = mx_fgraph_open(&G, *states, mask, L, in->near);
  if (rc) goto done;
  rc = mx_fgraph_place_lines(&G, L, in->retries, moved, st, chain);
  /* sides, near the placed lines (the nodes of the edges around theirs) */
  if (!rc && in->patch && in->npatches > 1) {
    memset(mask, 0, M->nnodes);
    for (size_t v = 0; v < M->nnodes; v++)
      if (fixed[v])
        for (uint32_t k = G.aoff[v]; k < G.aoff[v + 1]; k++) {
          const uint32_t w = G.adj[k];
          mask[w] = 1;
          for (uint32_t j = G.aoff[w]; j < G.aoff[w + 1]; j++) mask[G.adj[j]] = 1;
        }
    rc = mx_fgraph_sides(&G, in, S, mask, moved, &st->sides);
  }
  /* then the splits, once every node is where it goes */
  if (!rc && G.nsplit) {
    rc = split_quads(&G, states, fixed_io, &moved, st, log);
    fixed = *fixed_io;
  }
  if (!rc) {
    mx_mesh_update_jens(M, moved);
    mx_mesh_summarize(M);
  }
done:
  mx_fgraph_free(&G);
  mx_free(mask);
  mx_free(moved);
  st->seconds = mx_wtime() - t0;
  return rc;
}
