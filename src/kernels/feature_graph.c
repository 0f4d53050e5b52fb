/* The boundary's graph for the feature placement (kernels/feature_graph.h). */
#include "kernels/feature_graph.h"

#include <math.h>
#include <string.h>

#include "base/common.h"
#include "base/scan.h"
#include "io/boundary_faces.h"
#include "kernels/boundary.h"

static int graph_build(mx_fgraph *G) {
  mx_mesh *M = G->M;
  const size_t nf = G->nf = G->bf.ntri + G->bf.nquad;
  size_t n = 3 * G->bf.ntri + 4 * G->bf.nquad;
  G->nrun = n;
  G->rkey = mx_alloc((n + 1) * sizeof *G->rkey);
  G->rface = mx_alloc((n + 1) * sizeof *G->rface);
  G->aoff = mx_calloc((M->nnodes + 2) * sizeof *G->aoff);
  G->loc = mx_alloc((M->nnodes + 1) * sizeof *G->loc);
  if (!G->rkey || !G->rface || !G->aoff || !G->loc) return MX_ENOMEM;
  for (size_t v = 0; v < M->nnodes; v++) G->loc[v] = UINT32_MAX;
  size_t r = 0;
  for (size_t f = 0; f < nf; f++) {
    int k;
    const uint32_t *p = mx_fgraph_face(G, f, &k);
    for (int i = 0; i < k; i++) {
      uint32_t a = p[i], b = p[(i + 1) % k];
      if (a > b) {
        const uint32_t c = a;
        a = b;
        b = c;
      }
      G->rkey[r] = (uint64_t)a << 32 | b;
      G->rface[r++] = (uint32_t)f;
    }
  }
  if (mx_sort_u64(G->rkey, G->rface, n)) return MX_ENOMEM;
  size_t ne = 0;
  for (size_t i = 0; i < n; i++) ne += i == 0 || G->rkey[i] != G->rkey[i - 1];
  G->ne = ne;
  const size_t nq = G->bf.nquad;
  G->estart = mx_alloc((ne + 1) * sizeof *G->estart);
  G->eline = mx_calloc(ne + 1);
  G->qdiag = mx_calloc(nq + 1);
  G->adj = mx_alloc((2 * ne + 4 * nq + 1) * sizeof *G->adj);
  G->aedge = mx_alloc((2 * ne + 4 * nq + 1) * sizeof *G->aedge);
  if (!G->estart || !G->eline || !G->qdiag || !G->adj || !G->aedge) return MX_ENOMEM;
  G->nsplit = 0;
  for (size_t q = 0; q < nq; q++)
    for (int i = 0; i < 4; i++) G->aoff[G->bf.quad[4 * q + i] + 1]++;
  ne = 0;
  double hsum = 0.0;
  for (size_t i = 0; i < n; i++)
    if (i == 0 || G->rkey[i] != G->rkey[i - 1]) {
      G->estart[ne++] = (uint32_t)i;
      const uint32_t a = (uint32_t)(G->rkey[i] >> 32), b = (uint32_t)G->rkey[i];
      G->aoff[a + 1]++;
      G->aoff[b + 1]++;
      hsum += mx_fg_dist3(M->xyz + 3 * (size_t)a, M->xyz + 3 * (size_t)b);
    }
  G->estart[ne] = (uint32_t)n;
  for (size_t v = 0; v < M->nnodes; v++) G->aoff[v + 1] += G->aoff[v];
  uint32_t *fill = G->loc; /* borrowed as a cursor, put back below */
  for (size_t v = 0; v < M->nnodes; v++) fill[v] = G->aoff[v];
  for (size_t e = 0; e < ne; e++) {
    const uint64_t key = G->rkey[G->estart[e]];
    const uint32_t a = (uint32_t)(key >> 32), b = (uint32_t)key;
    G->adj[fill[a]] = b;
    G->aedge[fill[a]++] = (uint32_t)e;
    G->adj[fill[b]] = a;
    G->aedge[fill[b]++] = (uint32_t)e;
  }
  for (size_t q = 0; q < nq; q++)
    for (int i = 0; i < 4; i++) { /* diagonal i & 1 from node i to node i + 2 */
      const uint32_t a = G->bf.quad[4 * q + i], b = G->bf.quad[4 * q + (i + 2) % 4];
      G->adj[fill[a]] = b;
      G->aedge[fill[a]++] = (uint32_t)(ne + 2 * q + (i & 1));
    }
  for (size_t v = 0; v < M->nnodes; v++) G->loc[v] = UINT32_MAX;
  /* the grid: cells of the mean edge length over the boundary nodes' box */
  size_t nb = 0;
  for (size_t v = 0; v < M->nnodes; v++) nb += G->aoff[v + 1] > G->aoff[v];
  G->nb = nb;
  G->bkey = mx_alloc((nb + 1) * sizeof *G->bkey);
  G->bnode = mx_alloc((nb + 1) * sizeof *G->bnode);
  if (!G->bkey || !G->bnode) return MX_ENOMEM;
  G->h = ne ? hsum / (double)ne : 1.0;
  for (int a = 0; a < 3; a++) G->lo[a] = INFINITY;
  for (size_t v = 0; v < M->nnodes; v++)
    if (G->aoff[v + 1] > G->aoff[v])
      for (int a = 0; a < 3; a++) G->lo[a] = fmin(G->lo[a], M->xyz[3 * v + a]);
  nb = 0;
  for (size_t v = 0; v < M->nnodes; v++)
    if (G->aoff[v + 1] > G->aoff[v]) {
      int64_t c[3];
      mx_fg_cell_of(G, M->xyz + 3 * v, c);
      G->bkey[nb] = mx_fg_cell_key(c[0], c[1], c[2]);
      G->bnode[nb++] = (uint32_t)v;
    }
  return mx_sort_u64(G->bkey, G->bnode, nb) ? MX_ENOMEM : MX_OK;
}

void mx_fgraph_free(mx_fgraph *G) {
  mx_boundary_faces_free(&G->bf);
  mx_free(G->rkey);
  mx_free(G->rface);
  mx_free(G->estart);
  mx_free(G->eline);
  mx_free(G->qdiag);
  mx_free(G->aoff);
  mx_free(G->adj);
  mx_free(G->aedge);
  mx_free(G->bkey);
  mx_free(G->bnode);
  mx_free(G->loc);
}

/* Calls fn(ctx, v) for the boundary nodes of the cells within ring k of x. */
void mx_fgraph_cells_around(const mx_fgraph *G, const double *x, int64_t k,
                            void (*fn)(void *ctx, uint32_t v), void *ctx) {
  int64_t c[3];
  mx_fg_cell_of(G, x, c);
  for (int64_t i = c[0] - k; i <= c[0] + k; i++)
    for (int64_t j = c[1] - k; j <= c[1] + k; j++) {
      if (i < 0 || j < 0) continue;
      const int64_t k0 = c[2] - k < 0 ? 0 : c[2] - k;
      const uint64_t a = mx_fg_cell_key(i, j, k0), b = mx_fg_cell_key(i, j, c[2] + k) + 1;
      for (size_t p = mx_lower_u64(G->bkey, G->nb, a); p < G->nb && G->bkey[p] < b; p++)
        fn(ctx, G->bnode[p]);
    }
}

typedef struct {
  const mx_fgraph *G;
  const double *x;
  double best;
  uint32_t node;
} nearest_ctx;

static void nearest_fn(void *ctx, uint32_t v) {
  nearest_ctx *c = ctx;
  if (c->G->fixed[v]) return;
  const double d = mx_fg_dist3(c->x, c->G->M->xyz + 3 * (size_t)v);
  if (d < c->best || (d == c->best && v < c->node)) {
    c->best = d;
    c->node = v;
  }
}

/* The closest boundary node to x not fixed yet (UINT32_MAX: none). */
uint32_t mx_fgraph_nearest_free(const mx_fgraph *G, const double *x) {
  nearest_ctx c = {G, x, INFINITY, UINT32_MAX};
  for (int64_t k = 1; k < (int64_t)1 << 22; k *= 2) {
    mx_fgraph_cells_around(G, x, k, nearest_fn, &c);
    if (c.best <= (double)k * G->h) break; /* nothing closer beyond ring k */
    if ((double)k * G->h > 1e3 * G->h * (double)(G->nb + 1)) break;
  }
  return c.node;
}

/* The edge from u to w (a diagonal only while its quadrilateral has none
 * taken), or UINT32_MAX. */
uint32_t mx_fgraph_edge(const mx_fgraph *G, uint32_t u, uint32_t w) {
  for (uint32_t k = G->aoff[u]; k < G->aoff[u + 1]; k++)
    if (G->adj[k] == w) {
      const uint32_t e = G->aedge[k];
      if (e < G->ne || !G->qdiag[(e - G->ne) / 2]) return e;
    }
  return UINT32_MAX;
}

/* A grid of cells of side r, centred on the origin (2^20 cells each way). */
static mx_fgraph near_grid(double r) {
  mx_fgraph g = {.h = r};
  for (int a = 0; a < 3; a++) g.lo[a] = -1048576.0 * r;
  return g;
}

/* The keys of the 27 cells around x's appended at k[m ..]; the new count. */
static size_t add_near(const mx_fgraph *g, const double *x, uint64_t *k, size_t m) {
  int64_t c[3];
  mx_fg_cell_of(g, x, c);
  for (int64_t i = c[0] - 1; i <= c[0] + 1; i++)
    for (int64_t j = c[1] - 1; j <= c[1] + 1; j++)
      for (int64_t l = c[2] - 1; l <= c[2] + 1; l++)
        k[m++] = mx_fg_cell_key(i < 0 ? 0 : i, j < 0 ? 0 : j, l < 0 ? 0 : l);
  return m;
}

/* The cells of side r (keys as mx_fg_cell_key on near_grid(r)) within one cell
 * of the lines' points (taken every r / 2) and corners, sorted, unique:
 * a point within r of a line is in one of them. */
static int near_cells(const mx_feature_lines *L, double r, uint64_t **out, size_t *nout) {
  size_t n = 27 * L->ncorners, m = 0;
  for (size_t i = 0; i < L->nlines; i++)
    for (size_t j = L->first[i]; j + 1 < L->first[i + 1]; j++)
      n += 27 * (2 + (size_t)(2.0 * mx_fg_dist3(L->xyz + 3 * j, L->xyz + 3 * j + 3) / r));
  uint64_t *k = mx_alloc((n + 1) * sizeof *k);
  if (!k) return MX_ENOMEM;
  const mx_fgraph g = near_grid(r);
  for (size_t c = 0; c < L->ncorners; c++) m = add_near(&g, L->corner + 3 * c, k, m);
  for (size_t i = 0; i < L->nlines; i++)
    for (size_t j = L->first[i]; j + 1 < L->first[i + 1]; j++) {
      const double *u = L->xyz + 3 * j, *v = u + 3;
      const size_t steps = 1 + (size_t)(2.0 * mx_fg_dist3(u, v) / r);
      for (size_t s = 0; s <= steps; s++) {
        const double t = (double)s / (double)steps;
        const double x[3] = {u[0] + t * (v[0] - u[0]), u[1] + t * (v[1] - u[1]), u[2] + t * (v[2] - u[2])};
        m = add_near(&g, x, k, m);
      }
    }
  if (mx_sort_u64(k, NULL, m)) {
    mx_free(k);
    return MX_ENOMEM;
  }
  size_t u = 0;
  for (size_t i = 0; i < m; i++)
    if (!u || k[i] != k[u - 1]) k[u++] = k[i];
  *out = k;
  *nout = u;
  return MX_OK;
}

int mx_feature_near_nodes(const mx_feature_lines *L, double r, const double *xyz, size_t n,
                          uint8_t *mask) {
  uint64_t *cells = NULL;
  size_t nc = 0;
  if (near_cells(L, r, &cells, &nc)) return MX_ENOMEM;
  const mx_fgraph g = near_grid(r);
  const int64_t nn = (int64_t)n;
  #pragma omp parallel for schedule(static)
  for (int64_t v = 0; v < nn; v++)
    if (mask[v]) {
      int64_t c[3];
      mx_fg_cell_of(&g, xyz + 3 * v, c);
      const uint64_t key = mx_fg_cell_key(c[0], c[1], c[2]);
      const size_t at = mx_lower_u64(cells, nc, key);
      mask[v] = at < nc && cells[at] == key;
    }
  mx_free(cells);
  return MX_OK;
}

/* The graph of the boundary faces (with near > 0: those whose every node
 * is within reach of the features; a face shared by two elements still
 * shows in both, so the interior ones are not taken for boundary). */
int mx_fgraph_open(mx_fgraph *G, const uint8_t *states, uint8_t *mask, const mx_feature_lines *L,
                      double near) {
  const mx_mesh *M = G->M;
  for (size_t v = 0; v < M->nnodes; v++) mask[v] = states[v] == MX_NODE_OUTSIDE;
  if (near > 0.0 && mx_feature_near_nodes(L, near, M->xyz, M->nnodes, mask)) return MX_ENOMEM;
  const mx_mesh_view view = {.nnodes = M->nnodes, .xyz = M->xyz, .ncells = M->ncells,
                             .type = M->type, .conn = M->conn};
  const int rc = mx_boundary_faces_extract_masked(&view, mask, &G->bf);
  return rc ? rc : graph_build(G);
}
