/* Sharp features placed in the mesh (kernels/feature_place.h). */
#include "kernels/feature_place.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "base/common.h"
#include "base/scan.h"
#include "base/union_find.h"
#include "geom/quality.h"
#include "io/boundary_faces.h"
#include "kernels/boundary.h"
#include "kernels/cell_split.h"
#include "kernels/mesh_edit.h"

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
} graph;

static const uint32_t *face_nodes(const graph *G, size_t f, int *n) {
  if (f < G->bf.ntri) {
    *n = 3;
    return G->bf.tri + 3 * f;
  }
  *n = 4;
  return G->bf.quad + 4 * (f - G->bf.ntri);
}

static double dist3(const double *a, const double *b) {
  return sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) +
              (a[2] - b[2]) * (a[2] - b[2]));
}

static uint64_t cell_key(int64_t i, int64_t j, int64_t k) {
  return (uint64_t)i << 42 | (uint64_t)j << 21 | (uint64_t)k;
}

static void cell_of(const graph *G, const double *x, int64_t c[3]) {
  for (int a = 0; a < 3; a++) {
    const double t = floor((x[a] - G->lo[a]) / G->h);
    c[a] = t < 0 ? 0 : t > 2097151 ? 2097151 : (int64_t)t;
  }
}

static int graph_build(graph *G) {
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
    const uint32_t *p = face_nodes(G, f, &k);
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
      hsum += dist3(M->xyz + 3 * (size_t)a, M->xyz + 3 * (size_t)b);
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
      cell_of(G, M->xyz + 3 * v, c);
      G->bkey[nb] = cell_key(c[0], c[1], c[2]);
      G->bnode[nb++] = (uint32_t)v;
    }
  return mx_sort_u64(G->bkey, G->bnode, nb) ? MX_ENOMEM : MX_OK;
}

static void graph_free(graph *G) {
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
static void cells_around(const graph *G, const double *x, int64_t k,
                         void (*fn)(void *ctx, uint32_t v), void *ctx) {
  int64_t c[3];
  cell_of(G, x, c);
  for (int64_t i = c[0] - k; i <= c[0] + k; i++)
    for (int64_t j = c[1] - k; j <= c[1] + k; j++) {
      if (i < 0 || j < 0) continue;
      const int64_t k0 = c[2] - k < 0 ? 0 : c[2] - k;
      const uint64_t a = cell_key(i, j, k0), b = cell_key(i, j, c[2] + k) + 1;
      for (size_t p = mx_lower_u64(G->bkey, G->nb, a); p < G->nb && G->bkey[p] < b; p++)
        fn(ctx, G->bnode[p]);
    }
}

typedef struct {
  const graph *G;
  const double *x;
  double best;
  uint32_t node;
} nearest_ctx;

static void nearest_fn(void *ctx, uint32_t v) {
  nearest_ctx *c = ctx;
  if (c->G->fixed[v]) return;
  const double d = dist3(c->x, c->G->M->xyz + 3 * (size_t)v);
  if (d < c->best || (d == c->best && v < c->node)) {
    c->best = d;
    c->node = v;
  }
}

/* The closest boundary node to x not fixed yet (UINT32_MAX: none). */
static uint32_t nearest_free(const graph *G, const double *x) {
  nearest_ctx c = {G, x, INFINITY, UINT32_MAX};
  for (int64_t k = 1; k < (int64_t)1 << 22; k *= 2) {
    cells_around(G, x, k, nearest_fn, &c);
    if (c.best <= (double)k * G->h) break; /* nothing closer beyond ring k */
    if ((double)k * G->h > 1e3 * G->h * (double)(G->nb + 1)) break;
  }
  return c.node;
}

/* The edge from u to w (a diagonal only while its quadrilateral has none
 * taken), or UINT32_MAX. */
static uint32_t edge_between(const graph *G, uint32_t u, uint32_t w) {
  for (uint32_t k = G->aoff[u]; k < G->aoff[u + 1]; k++)
    if (G->adj[k] == w) {
      const uint32_t e = G->aedge[k];
      if (e < G->ne || !G->qdiag[(e - G->ne) / 2]) return e;
    }
  return UINT32_MAX;
}

/* A feature takes a node within this many mean boundary edges of it only
 * (the patch of a local re-mesh does not reach every feature). */
#define MX_FEATURE_REACH 4.0

/* ---- lines ------------------------------------------------------------- */

/* Closest point of x on the polyline p[0..n): the distance, the point q and
 * its arc length s from p[0]. */
static double on_polyline(const double *p, size_t n, const double *x, double *q, double *s) {
  double best = INFINITY, acc = 0.0;
  for (size_t i = 0; i + 1 < n; i++) {
    const double *a = p + 3 * i, *b = a + 3;
    const double d[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    const double l2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2], l = sqrt(l2);
    double t = l2 > 0 ? ((x[0] - a[0]) * d[0] + (x[1] - a[1]) * d[1] + (x[2] - a[2]) * d[2]) / l2 : 0;
    t = t < 0 ? 0 : t > 1 ? 1 : t;
    const double y[3] = {a[0] + t * d[0], a[1] + t * d[1], a[2] + t * d[2]};
    const double e = dist3(x, y);
    if (e < best) {
      best = e;
      if (q) memcpy(q, y, sizeof y);
      if (s) *s = acc + t * l;
    }
    acc += l;
  }
  return best;
}

typedef struct {
  graph *G;
  uint32_t *tube;
  size_t n, cap;
  int nomem;
} tube_ctx;

static void tube_fn(void *ctx, uint32_t v) {
  tube_ctx *c = ctx;
  if (c->G->loc[v] != UINT32_MAX || c->nomem) return;
  if (c->n == c->cap) {
    const size_t cap = c->cap ? 2 * c->cap : 256;
    uint32_t *t = mx_realloc(c->tube, cap * sizeof *t);
    if (!t) {
      c->nomem = 1;
      return;
    }
    c->tube = t;
    c->cap = cap;
  }
  c->G->loc[v] = (uint32_t)c->n;
  c->tube[c->n++] = v;
}

/* The work arrays of one search, grown as needed. */
typedef struct {
  uint32_t *tube;
  size_t cap;
  double *cost, *d, *s; /* per tube node: cost, distance to the line, place along it */
  double *pen;          /* per tube node: what it costs for being another line's */
  const double *oth;    /* the other lines at the ends' corners: corner, direction */
  int noth;
  uint32_t *prev, *heap;
  size_t wcap;
  uint32_t *path;
  double *t; /* per path node: its place along the line */
  size_t pcap, tcap;
} search;

static int grow(void **p, size_t *cap, size_t n, size_t size) {
  if (n <= *cap) return MX_OK;
  void *q = mx_realloc(*p, n * size);
  if (!q) return MX_ENOMEM;
  *p = q;
  *cap = n;
  return MX_OK;
}

static void heap_push(uint32_t *h, size_t *n, const double *key, uint32_t x) {
  size_t i = (*n)++;
  while (i > 0) {
    const size_t p = (i - 1) / 2;
    if (key[h[p]] < key[x] || (key[h[p]] == key[x] && h[p] < x)) break;
    h[i] = h[p];
    i = p;
  }
  h[i] = x;
}

static uint32_t heap_pop(uint32_t *h, size_t *n, const double *key) {
  const uint32_t top = h[0], x = h[--*n];
  size_t i = 0;
  for (;;) {
    size_t c = 2 * i + 1;
    if (c >= *n) break;
    if (c + 1 < *n && (key[h[c + 1]] < key[h[c]] || (key[h[c + 1]] == key[h[c]] && h[c + 1] < h[c])))
      c++;
    if (key[x] < key[h[c]] || (key[x] == key[h[c]] && x < h[c])) break;
    h[i] = h[c];
    i = c;
  }
  if (*n) h[i] = x;
  return top;
}

/* The path without the nodes whose two neighbours on it share an edge or
 * a quadrilateral's diagonal: three nodes of one face on a line would
 * flatten it (a triangle) or fold it (a quadrilateral, split along the
 * diagonal instead). Returns the new count. */
static size_t shortcut(const graph *G, uint32_t *path, size_t k) {
  size_t n = 1;
  for (size_t i = 1; i < k; i++) {
    while (n >= 2 && edge_between(G, path[n - 2], path[i]) != UINT32_MAX) n--;
    path[n++] = path[i];
  }
  return n;
}

/* How much closer x is to another line out of a corner at an end of the
 * one searched (W->oth: the line's first segment as a ray from the corner,
 * within OTHERS_REACH mean edges of it) than to this one (d): a path that
 * strays there walls the other line off where they converge (the
 * tetrahedron's corners: three lines 60 degrees apart). */
#define OTHERS_REACH 4.0
#define OTHERS_COST 4.0
static double others_closer(const search *W, double h, const double *x, double d) {
  double worst = 0.0;
  for (int o = 0; o < W->noth; o++) {
    const double *c = W->oth + 6 * o, *u = c + 3;
    const double r[3] = {x[0] - c[0], x[1] - c[1], x[2] - c[2]};
    const double r2 = r[0] * r[0] + r[1] * r[1] + r[2] * r[2];
    if (r2 > OTHERS_REACH * OTHERS_REACH * h * h) continue;
    const double t = r[0] * u[0] + r[1] * u[1] + r[2] * u[2];
    const double e = t <= 0.0 ? sqrt(r2) : sqrt(fmax(0.0, r2 - t * t));
    if (d - e > worst) worst = d - e;
  }
  return worst;
}

/* The path of boundary edges from node a to node b near the polyline
 * p[0..n) (a and b excepted, through nodes not fixed): its nodes a .. b in
 * W->path, their count returned (0: none). */
static size_t find_path(graph *G, search *W, const double *p, size_t n, uint32_t a, uint32_t b,
                        int *nomem) {
  const double *X = G->M->xyz;
  /* the tube: boundary nodes within 2 cells of points every half cell */
  tube_ctx tc = {G, W->tube, 0, W->cap, 0};
  for (size_t i = 0; i + 1 < n; i++) {
    const double *u = p + 3 * i, *v = u + 3;
    const size_t steps = 1 + (size_t)(2.0 * dist3(u, v) / G->h);
    for (size_t s = 0; s <= steps; s++) {
      const double t = (double)s / (double)steps;
      const double x[3] = {u[0] + t * (v[0] - u[0]), u[1] + t * (v[1] - u[1]), u[2] + t * (v[2] - u[2])};
      cells_around(G, x, 2, tube_fn, &tc);
    }
  }
  tube_fn(&tc, a);
  tube_fn(&tc, b);
  W->tube = tc.tube;
  W->cap = tc.cap;
  const size_t m = tc.n;
  size_t got = 0;
  if (tc.nomem || grow((void **)&W->cost, &W->wcap, m, sizeof *W->cost)) {
    *nomem = 1;
    goto out;
  }
  size_t hcap = 1; /* each directed edge pushes once at most */
  for (size_t i = 0; i < m; i++) hcap += G->aoff[W->tube[i] + 1] - G->aoff[W->tube[i]];
  {
    double *d = mx_realloc(W->d, (m + 1) * sizeof *W->d);
    if (d) W->d = d;
    double *sp = mx_realloc(W->s, (m + 1) * sizeof *W->s);
    if (sp) W->s = sp;
    uint32_t *pr = mx_realloc(W->prev, (m + 1) * sizeof *W->prev);
    if (pr) W->prev = pr;
    uint32_t *hp = mx_realloc(W->heap, hcap * sizeof *W->heap);
    if (hp) W->heap = hp;
    double *pn = mx_realloc(W->pen, (m + 1) * sizeof *W->pen);
    if (pn) W->pen = pn;
    if (!d || !sp || !pr || !hp || !pn) {
      *nomem = 1;
      goto out;
    }
  }
  for (size_t i = 0; i < m; i++) {
    W->cost[i] = INFINITY;
    W->prev[i] = UINT32_MAX;
    W->d[i] = on_polyline(p, n, X + 3 * (size_t)W->tube[i], NULL, W->s + i);
    W->pen[i] = OTHERS_COST * others_closer(W, G->h, X + 3 * (size_t)W->tube[i], W->d[i]);
  }
  size_t nh = 0;
  const uint32_t la = G->loc[a], lb = G->loc[b];
  W->cost[la] = 0.0;
  heap_push(W->heap, &nh, W->cost, la);
  while (nh) {
    const uint32_t i = heap_pop(W->heap, &nh, W->cost);
    if (i == lb) break;
    const uint32_t u = W->tube[i];
    for (uint32_t k = G->aoff[u]; k < G->aoff[u + 1]; k++) {
      const uint32_t w = G->adj[k], j = G->loc[w];
      if (j == UINT32_MAX || (G->fixed[w] && w != b)) continue;
      if (G->exit_of && G->exit_of[w] != UINT32_MAX && G->exit_of[w] != G->line) continue;
      if (G->aedge[k] >= G->ne) continue; /* diagonals: shortcut() only */
      /* forward mostly: a step may go back along the line by a quarter of
       * its length at most, and pays four times what it goes back
       * (place_path spreads the places along the line) */
      const double len = dist3(X + 3 * (size_t)u, X + 3 * (size_t)w);
      const double back = W->s[i] - W->s[j];
      if (back > 0.25 * len) continue;
      const double c = W->cost[i] + len + 2.0 * (W->d[i] + W->d[j]) + (back > 0 ? 4.0 * back : 0.0) + W->pen[j];
      if (c < W->cost[j]) {
        W->cost[j] = c;
        W->prev[j] = i;
        heap_push(W->heap, &nh, W->cost, j); /* stale entries are popped later, harmless */
      }
    }
  }
  if (W->cost[lb] < INFINITY) {
    size_t k = 0;
    for (uint32_t i = lb; i != UINT32_MAX; i = W->prev[i]) k++;
    if (grow((void **)&W->path, &W->pcap, k, sizeof *W->path) ||
        grow((void **)&W->t, &W->tcap, k, sizeof *W->t)) {
      *nomem = 1;
      goto out;
    }
    got = k;
    for (uint32_t i = lb; i != UINT32_MAX; i = W->prev[i]) W->path[--k] = W->tube[i];
    got = shortcut(G, W->path, got);
  }
out:
  for (size_t i = 0; i < m; i++) G->loc[W->tube[i]] = UINT32_MAX;
  return got;
}

/* The point at arc length t along the polyline p[0..n). */
static void at_arclength(const double *p, size_t n, double t, double *q) {
  for (size_t i = 0; i + 1 < n; i++) {
    const double l = dist3(p + 3 * i, p + 3 * i + 3);
    if (t <= l || i + 2 == n) {
      const double u = l > 0 ? fmin(1.0, fmax(0.0, t / l)) : 0.0;
      for (int a = 0; a < 3; a++) q[a] = p[3 * i + a] + u * (p[3 * i + 3 + a] - p[3 * i + a]);
      return;
    }
    t -= l;
  }
  memcpy(q, p, 3 * sizeof *q);
}

/* Marks the edges of a placed path (a diagonal: its quadrilateral, to be
 * split). */
static void mark_path(graph *G, const uint32_t *path, size_t k) {
  for (size_t i = 0; i + 1 < k; i++) {
    const uint32_t e = edge_between(G, path[i], path[i + 1]);
    if (e == UINT32_MAX) continue; /* cannot be: the path's edges exist */
    if (e < G->ne) G->eline[e] = 1;
    else {
      G->qdiag[(e - G->ne) / 2] = (uint8_t)(1 + (e - G->ne) % 2);
      G->nsplit++;
    }
  }
}

/* The path's nodes onto the polyline, in the path's order: each at its
 * closest point's arc length, raised to keep a fifth of its edge's length
 * past the one before and lowered to keep that short of the one after (a
 * path that steps sideways or back a little is spread along the line);
 * the path's edges marked. 1: placed, 0: not (no room on the line). */
static int place_path(graph *G, uint8_t *fixed, uint8_t *moved, const uint32_t *path, size_t k,
                      const double *p, size_t n, double *t, size_t *nodes) {
  double *X = G->M->xyz, total = 0.0;
  for (size_t i = 0; i + 1 < n; i++) total += dist3(p + 3 * i, p + 3 * i + 3);
  t[0] = 0.0;
  t[k - 1] = total;
  for (size_t i = 1; i + 1 < k; i++) {
    on_polyline(p, n, X + 3 * (size_t)path[i], NULL, t + i);
    const double gap = 0.2 * dist3(X + 3 * (size_t)path[i], X + 3 * (size_t)path[i - 1]);
    t[i] = fmax(t[i], t[i - 1] + gap);
  }
  for (size_t i = k - 1; i-- > 1;) {
    const double gap = 0.2 * dist3(X + 3 * (size_t)path[i], X + 3 * (size_t)path[i + 1]);
    t[i] = fmin(t[i], t[i + 1] - gap);
  }
  for (size_t i = 1; i < k; i++)
    if (!(t[i] > t[i - 1])) return 0;
  for (size_t i = 1; i + 1 < k; i++) {
    at_arclength(p, n, t[i], X + 3 * (size_t)path[i]);
    fixed[path[i]] = 1;
    moved[path[i]] = 1;
    (*nodes)++;
  }
  mark_path(G, path, k);
  return 1;
}

/* Places node v onto corner point x (taking it); 0 when no node is free. */
static uint32_t take_point(graph *G, uint8_t *fixed, uint8_t *moved, const double *x) {
  const uint32_t v = nearest_free(G, x);
  if (v == UINT32_MAX || dist3(x, G->M->xyz + 3 * (size_t)v) > MX_FEATURE_REACH * G->h)
    return UINT32_MAX;
  memcpy(G->M->xyz + 3 * (size_t)v, x, 3 * sizeof *x);
  fixed[v] = 1;
  moved[v] = 1;
  return v;
}

static uint32_t taken_at(const uint64_t *key, const uint32_t *node, size_t n, const double *x);

typedef struct {
  const graph *G;
  const double *x;
  const double *dir; /* nd unit directions of the ridges out of the corner */
  int nd;
  double reach;      /* candidates within this distance of x */
  int best_score;
  double best_d;
  uint32_t node;
} corner_ctx;

/* How many of the ridges out of x node v has an edge along (within 60
 * degrees) once moved to x. */
static int star_score(const graph *G, uint32_t v, const double *x, const double *dir, int nd) {
  const double *X = G->M->xyz;
  int score = 0;
  for (int r = 0; r < nd; r++) {
    int has = 0;
    for (uint32_t k = G->aoff[v]; k < G->aoff[v + 1] && !has; k++) {
      const double *w = X + 3 * (size_t)G->adj[k];
      const double u[3] = {w[0] - x[0], w[1] - x[1], w[2] - x[2]};
      const double l = sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
      has = l > 0 && (u[0] * dir[3 * r] + u[1] * dir[3 * r + 1] + u[2] * dir[3 * r + 2]) > 0.5 * l;
    }
    score += has;
  }
  return score;
}

static void corner_fn(void *ctx, uint32_t v) {
  corner_ctx *c = ctx;
  if (c->G->fixed[v]) return;
  const double d = dist3(c->x, c->G->M->xyz + 3 * (size_t)v);
  if (d > c->reach) return;
  const int sc = star_score(c->G, v, c->x, c->dir, c->nd);
  if (sc > c->best_score || (sc == c->best_score && (d < c->best_d || (d == c->best_d && v < c->node)))) {
    c->best_score = sc;
    c->best_d = d;
    c->node = v;
  }
}

/* The node corner x takes: among the free boundary nodes within a mean
 * edge of the closest one, the one whose edges go along most of the
 * corner's ridges (then the closest): a corner whose node has no edge
 * along one of its ridges cannot be left along it. Moved onto x. */
static uint32_t take_corner(graph *G, uint8_t *fixed, uint8_t *moved, const double *x,
                            const double *dir, int nd) {
  const uint32_t v0 = nearest_free(G, x);
  if (v0 == UINT32_MAX) return v0;
  const double d0 = dist3(x, G->M->xyz + 3 * (size_t)v0);
  if (d0 > MX_FEATURE_REACH * G->h) return UINT32_MAX; /* not this mesh's (a patch's) */
  corner_ctx c = {G, x, dir, nd, d0 + G->h, star_score(G, v0, x, dir, nd), d0, v0};
  if (c.best_score < nd) cells_around(G, x, 1 + (int64_t)(c.reach / G->h), corner_fn, &c);
  memcpy(G->M->xyz + 3 * (size_t)c.node, x, 3 * sizeof *x);
  fixed[c.node] = 1;
  moved[c.node] = 1;
  return c.node;
}

/* Each corner's ridge directions (unit vectors out of it along each open
 * line ending there): corner c's are dir[3 * off[c] ...  3 * off[c + 1]). */
static int corner_dirs(const mx_feature_lines *L, const uint64_t *ckey, const uint32_t *cidx,
                       uint32_t **off_out, double **dir_out) {
  uint32_t *off = mx_calloc((L->ncorners + 2) * sizeof *off);
  double *dir = mx_alloc((6 * L->nlines + 3) * sizeof *dir);
  if (!off || !dir) {
    mx_free(off);
    mx_free(dir);
    return MX_ENOMEM;
  }
  for (int pass = 0; pass < 2; pass++) {
    for (size_t i = 0; i < L->nlines; i++) {
      if (L->loop[i]) continue;
      const size_t f = L->first[i], np = L->first[i + 1] - f;
      for (int end = 0; end < 2; end++) {
        const double *p = L->xyz + 3 * (f + (end ? np - 1 : 0)), *q = end ? p - 3 : p + 3;
        const uint32_t c = taken_at(ckey, cidx, L->ncorners, p);
        if (c == UINT32_MAX) continue;
        if (pass == 0) {
          off[c + 1]++;
          continue;
        }
        const double l = dist3(p, q);
        double *d = dir + 3 * (size_t)off[c]++;
        for (int a = 0; a < 3; a++) d[a] = l > 0 ? (q[a] - p[a]) / l : 0.0;
      }
    }
    if (pass == 0)
      for (size_t c = 0; c < L->ncorners; c++) off[c + 1] += off[c];
  }
  for (size_t c = L->ncorners; c > 0; c--) off[c] = off[c - 1];
  off[0] = 0;
  *off_out = off;
  *dir_out = dir;
  return MX_OK;
}

/* A point's coordinates hashed (FNV-1a over their bits, -0 as 0). */
static uint64_t point_key(const double *x) {
  uint64_t h = 1469598103934665603u;
  for (int a = 0; a < 3; a++) {
    const double y = x[a] == 0.0 ? 0.0 : x[a];
    uint64_t u;
    memcpy(&u, &y, sizeof u);
    for (int b = 0; b < 8; b++) h = (h ^ (u >> (8 * b) & 255)) * 1099511628211u;
  }
  return h;
}

/* The node the corner at x took (keys sorted with their nodes), or
 * UINT32_MAX (no corner there, or it took none). */
static uint32_t taken_at(const uint64_t *key, const uint32_t *node, size_t n, const double *x) {
  const uint64_t k = point_key(x);
  uint32_t v = UINT32_MAX;
  for (size_t i = mx_lower_u64(key, n, k); i < n && key[i] == k && v == UINT32_MAX; i++) v = node[i];
  return v;
}

/* ---- the lines, and a second try at their corners ----------------------- */

/* The paths placed, line by line (line i's nodes are node[at[i] .. at[i]
 * + len[i]); none for a line missed or a loop), and whether each was
 * placed. */
typedef struct {
  uint32_t *at, *len, *node;
  size_t n, cap;
  uint8_t *ok;
  double *sub; /* a loop's second half */
  /* the open lines' ends at each corner (by its key's rank): line * 2 +
   * end in cl[cl_off[k] .. cl_off[k + 1]); the other lines at a line's
   * corners, for the search (search.oth) */
  uint32_t *cl_off, *cl;
  double *oth;
  size_t noth, oth_cap;
} line_paths;

static int keep_path(line_paths *lp, size_t i, const uint32_t *path, size_t k) {
  if (lp->n + k > lp->cap &&
      grow((void **)&lp->node, &lp->cap, lp->n + k > 2 * lp->cap ? lp->n + k : 2 * lp->cap, sizeof *lp->node))
    return MX_ENOMEM;
  memcpy(lp->node + lp->n, path, k * sizeof *path);
  lp->at[i] = (uint32_t)lp->n;
  lp->len[i] = (uint32_t)k;
  lp->n += k;
  return MX_OK;
}

/* A line's direction out of its end `end` (a unit vector). */
static void line_dir(const mx_feature_lines *L, size_t i, int end, double *d) {
  const size_t f = L->first[i], np = L->first[i + 1] - f;
  const double *p = L->xyz + 3 * (f + (end ? np - 1 : 0)), *q = end ? p - 3 : p + 3;
  const double l = dist3(p, q);
  for (int a = 0; a < 3; a++) d[a] = l > 0 ? (q[a] - p[a]) / l : 0.0;
}

/* The rank of the corner at x among the sorted keys (n: none). */
static size_t corner_rank(const uint64_t *ckey, size_t n, const double *x) {
  const uint64_t key = point_key(x);
  const size_t k = mx_lower_u64(ckey, n, key);
  return k < n && ckey[k] == key ? k : n;
}

/* lp->cl_off, lp->cl: the open lines' ends at each corner. */
static int corner_lines(line_paths *lp, const mx_feature_lines *L, const uint64_t *ckey) {
  const size_t nc = L->ncorners;
  lp->cl_off = mx_calloc((nc + 2) * sizeof *lp->cl_off);
  lp->cl = mx_alloc((2 * L->nlines + 1) * sizeof *lp->cl);
  if (!lp->cl_off || !lp->cl) return MX_ENOMEM;
  for (int pass = 0; pass < 2; pass++) {
    for (size_t i = 0; i < L->nlines; i++) {
      if (L->loop[i]) continue;
      const size_t f = L->first[i], np = L->first[i + 1] - f;
      for (int end = 0; end < 2; end++) {
        const size_t k = corner_rank(ckey, nc, L->xyz + 3 * (f + (end ? np - 1 : 0)));
        if (k == nc) continue;
        if (pass == 0) lp->cl_off[k + 2]++;
        else lp->cl[lp->cl_off[k + 1]++] = (uint32_t)(2 * i + (size_t)end);
      }
    }
    if (pass == 0)
      for (size_t k = 0; k < nc; k++) lp->cl_off[k + 2] += lp->cl_off[k + 1];
  }
  return MX_OK;
}

/* lp->oth: the other open lines at the corners at line i's ends, each as
 * its corner and its direction out of it. */
static int others_at_ends(line_paths *lp, const mx_feature_lines *L, size_t i, const uint64_t *ckey) {
  lp->noth = 0;
  if (!lp->cl) return MX_OK;
  const size_t f = L->first[i], np = L->first[i + 1] - f;
  for (int end = 0; end < 2; end++) {
    const size_t k = corner_rank(ckey, L->ncorners, L->xyz + 3 * (f + (end ? np - 1 : 0)));
    if (k == L->ncorners) continue;
    for (uint32_t q = lp->cl_off[k]; q < lp->cl_off[k + 1]; q++) {
      const size_t j = lp->cl[q] / 2;
      if (j == i) continue;
      if (lp->noth == lp->oth_cap) {
        const size_t cap = lp->oth_cap ? 2 * lp->oth_cap : 8;
        double *o = mx_realloc(lp->oth, 6 * cap * sizeof *o);
        if (!o) return MX_ENOMEM;
        lp->oth = o;
        lp->oth_cap = cap;
      }
      double *o = lp->oth + 6 * lp->noth++;
      const int e = (int)(lp->cl[q] & 1);
      memcpy(o, L->xyz + 3 * (L->first[j] + (e ? L->first[j + 1] - L->first[j] - 1 : 0)), 3 * sizeof *o);
      line_dir(L, j, e, o + 3);
    }
  }
  return MX_OK;
}

/* Line i placed (open: between its corners' nodes; a loop: in two halves
 * from two points taken on it), its paths kept in lp. */
static int place_line(graph *G, search *W, line_paths *lp, const mx_feature_lines *L, size_t i,
                      const uint64_t *ckey, const uint32_t *cnode, uint8_t *moved,
                      mx_feature_stats *st) {
  uint8_t *fixed = (uint8_t *)G->fixed;
  const double *p = L->xyz + 3 * L->first[i];
  const size_t n = L->first[i + 1] - L->first[i];
  int ok = 1, nomem = 0;
  G->line = (uint32_t)i;
  if (!L->loop[i]) {
    /* the nodes the corners at its ends took */
    const uint32_t ea = taken_at(ckey, cnode, L->ncorners, p);
    const uint32_t eb = taken_at(ckey, cnode, L->ncorners, p + 3 * (n - 1));
    if (others_at_ends(lp, L, i, ckey)) return MX_ENOMEM;
    W->oth = lp->oth;
    W->noth = (int)lp->noth;
    size_t k = ea != UINT32_MAX && eb != UINT32_MAX && ea != eb ? find_path(G, W, p, n, ea, eb, &nomem) : 0;
    W->noth = 0;
    ok = k >= 2 && place_path(G, fixed, moved, W->path, k, p, n, W->t, &st->nodes);
    if (ok && keep_path(lp, i, W->path, k)) nomem = 1;
  } else if (n >= 3) {
    const size_t mid = n / 2;
    double *sub = mx_realloc(lp->sub, 3 * (n - mid + 2) * sizeof *sub);
    if (!sub) return MX_ENOMEM;
    lp->sub = sub;
    const uint32_t a = take_point(G, fixed, moved, p);
    const uint32_t b = a == UINT32_MAX ? a : take_point(G, fixed, moved, p + 3 * mid);
    if (b == UINT32_MAX) ok = 0;
    else {
      st->nodes += 2;
      size_t k = find_path(G, W, p, mid + 1, a, b, &nomem);
      ok = k >= 2 && place_path(G, fixed, moved, W->path, k, p, mid + 1, W->t, &st->nodes);
      memcpy(sub, p + 3 * mid, 3 * (n - mid) * sizeof *sub);
      memcpy(sub + 3 * (n - mid), p, 3 * sizeof *sub);
      k = ok && !nomem ? find_path(G, W, sub, n - mid + 1, b, a, &nomem) : 0;
      ok = ok && k >= 2 && place_path(G, fixed, moved, W->path, k, sub, n - mid + 1, W->t, &st->nodes);
    }
  }
  if (nomem) return MX_ENOMEM;
  lp->ok[i] = (uint8_t)ok;
  if (ok) st->lines++;
  else st->lines_missed++;
  return MX_OK;
}

/* Line i's path taken back: its inner nodes to their places before (x0),
 * free again, its edges unmarked. */
static void unplace_line(graph *G, line_paths *lp, size_t i, uint8_t *moved, const double *x0,
                         mx_feature_stats *st) {
  uint8_t *fixed = (uint8_t *)G->fixed;
  const uint32_t *path = lp->node + lp->at[i];
  const size_t k = lp->len[i];
  for (size_t j = 0; j + 1 < k; j++) {
    const uint32_t e = edge_between(G, path[j], path[j + 1]);
    if (e == UINT32_MAX) continue;
    if (e < G->ne) G->eline[e] = 0;
    else {
      G->qdiag[(e - G->ne) / 2] = 0;
      G->nsplit--;
    }
  }
  for (size_t j = 1; j + 1 < k; j++) {
    const uint32_t v = path[j];
    memcpy(G->M->xyz + 3 * (size_t)v, x0 + 3 * (size_t)v, 3 * sizeof *x0);
    fixed[v] = 0;
    moved[v] = 0;
    st->nodes--;
  }
  lp->ok[i] = 0;
  lp->len[i] = 0;
  st->lines--;
}


/* The tries at the corners of the lines missed. Measured: the
 * tetrahedron at -s 5 places 4 of its 5 lines again on the first try
 * (another one is then missed: lines wall each other off where they
 * converge) and all 6 on the second. */
#define RETRIES 3

/* The open lines missed tried again: every open line at a corner of a
 * missed one is taken back, each such corner's edges handed out as exits
 * (each line the free neighbour most along its direction, within 60
 * degrees, best pairs first), closed to the other lines, and the lines
 * placed again, the missed ones first. Kept when as many lines are placed
 * as before or more (another line missed is tried next); otherwise the
 * placement before is restored. Measured: on the tetrahedron, whose
 * corners have four edges, the first lines took the edges the last one
 * needed. */
static int retry_at_corners(graph *G, search *W, line_paths *lp, const mx_feature_lines *L,
                            const uint64_t *ckey, const uint32_t *cnode, uint8_t *moved,
                            const double *x0, mx_feature_stats *st) {
  const mx_mesh *M = G->M;
  uint8_t *cmark = mx_calloc(M->nnodes + 1); /* the corners' nodes to open again */
  uint32_t *exit_of = mx_alloc((M->nnodes + 1) * sizeof *exit_of);
  uint32_t *redo = mx_alloc((L->nlines + 1) * sizeof *redo);
  int rc = cmark && exit_of && redo ? MX_OK : MX_ENOMEM;
  size_t nr = 0, before = 0, after = 0;
  uint32_t *old = NULL; /* the paths taken back, for a restore: line i's at old[at[i]] */
  uint32_t *old_at = NULL, *old_len = NULL;
  uint8_t *inredo = NULL; /* per line: placed again */
  if (rc) goto out;
  for (size_t i = 0; i < L->nlines; i++) {
    if (L->loop[i] || lp->ok[i]) continue;
    const double *p = L->xyz + 3 * L->first[i];
    const size_t n = L->first[i + 1] - L->first[i];
    const uint32_t ea = taken_at(ckey, cnode, L->ncorners, p);
    const uint32_t eb = taken_at(ckey, cnode, L->ncorners, p + 3 * (n - 1));
    if (ea == UINT32_MAX || eb == UINT32_MAX || ea == eb) continue;
    cmark[ea] = cmark[eb] = 1;
  }
  /* the lines to place again: the missed ones first */
  for (int pass = 0; pass < 2; pass++)
    for (size_t i = 0; i < L->nlines; i++) {
      if (L->loop[i] || (size_t)lp->ok[i] != (size_t)pass) continue;
      const double *p = L->xyz + 3 * L->first[i];
      const size_t n = L->first[i + 1] - L->first[i];
      const uint32_t ea = taken_at(ckey, cnode, L->ncorners, p);
      const uint32_t eb = taken_at(ckey, cnode, L->ncorners, p + 3 * (n - 1));
      if ((ea != UINT32_MAX && cmark[ea]) || (eb != UINT32_MAX && cmark[eb])) redo[nr++] = (uint32_t)i;
    }
  if (!nr) goto out;
  for (size_t r = 0; r < nr; r++) before += lp->ok[redo[r]];
  /* the placed ones taken back, their paths kept for a restore */
  size_t nold = 0;
  for (size_t r = 0; r < nr; r++) nold += lp->len[redo[r]];
  old = mx_alloc((nold + 1) * sizeof *old);
  old_at = mx_alloc((nr + 1) * sizeof *old_at);
  old_len = mx_alloc((nr + 1) * sizeof *old_len);
  if (!old || !old_at || !old_len) {
    rc = MX_ENOMEM;
    goto out;
  }
  nold = 0;
  for (size_t r = 0; r < nr; r++) {
    const uint32_t i = redo[r];
    old_at[r] = (uint32_t)nold;
    old_len[r] = lp->len[i];
    memcpy(old + nold, lp->node + lp->at[i], lp->len[i] * sizeof *old);
    nold += lp->len[i];
    if (lp->ok[i]) unplace_line(G, lp, i, moved, x0, st);
    else st->lines_missed--;
  }
  /* the exits, best (line, edge) pairs first */
  for (size_t v = 0; v < M->nnodes; v++) exit_of[v] = UINT32_MAX;
  for (size_t r = 0; r < nr; r++) { /* at both ends of every line placed again */
    const uint32_t i = redo[r];
    for (int end = 0; end < 2; end++) {
      const double *p = L->xyz + 3 * (L->first[i] + (end ? L->first[i + 1] - L->first[i] - 1 : 0));
      const uint32_t c = taken_at(ckey, cnode, L->ncorners, p);
      if (c != UINT32_MAX) cmark[c] = 1;
    }
  }
  inredo = mx_calloc(L->nlines + 1);
  if (!inredo) {
    rc = MX_ENOMEM;
    goto out;
  }
  for (size_t r = 0; r < nr; r++) inredo[redo[r]] = 1;
  for (size_t kc = 0; kc < L->ncorners; kc++) {
    const uint32_t v = cnode[kc];
    if (v == UINT32_MAX || !cmark[v]) continue;
    /* the lines out of v among those placed again, and their directions */
    for (;;) {
      double best = 0.5;
      uint32_t bi = UINT32_MAX, bw = UINT32_MAX;
      for (uint32_t q = lp->cl_off[kc]; q < lp->cl_off[kc + 1]; q++) {
        const uint32_t i = lp->cl[q] / 2;
        const int end = (int)(lp->cl[q] & 1);
        int has = 0;
        for (uint32_t k = G->aoff[v]; k < G->aoff[v + 1] && !has; k++) has = exit_of[G->adj[k]] == i;
        if (!inredo[i] || has) continue;
        double d[3];
        line_dir(L, i, end, d);
        for (uint32_t k = G->aoff[v]; k < G->aoff[v + 1]; k++) {
          const uint32_t w = G->adj[k];
          if (G->aedge[k] >= G->ne || G->fixed[w] || exit_of[w] != UINT32_MAX) continue;
          const double *xv = M->xyz + 3 * (size_t)v, *xw = M->xyz + 3 * (size_t)w;
          const double u[3] = {xw[0] - xv[0], xw[1] - xv[1], xw[2] - xv[2]};
          const double l = sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
          const double c = l > 0 ? (u[0] * d[0] + u[1] * d[1] + u[2] * d[2]) / l : -1.0;
          if (c > best || (c == best && bi != UINT32_MAX && (i < bi || (i == bi && w < bw)))) {
            best = c;
            bi = i;
            bw = w;
          }
        }
      }
      if (bi == UINT32_MAX) break;
      exit_of[bw] = bi;
    }
  }
  G->exit_of = exit_of;
  for (size_t r = 0; r < nr && !rc; r++) rc = place_line(G, W, lp, L, redo[r], ckey, cnode, moved, st);
  G->exit_of = NULL;
  if (rc) goto out;
  for (size_t r = 0; r < nr; r++) after += lp->ok[redo[r]];
  if (after >= before) goto out;
  /* fewer: the placement before back, path by path as it was made */
  for (size_t r = 0; r < nr; r++) {
    const uint32_t i = redo[r];
    if (lp->ok[i]) unplace_line(G, lp, i, moved, x0, st);
    else st->lines_missed--;
  }
  for (size_t r = 0; r < nr && !rc; r++) {
    const uint32_t i = redo[r];
    if (!old_len[r]) {
      st->lines_missed++;
      continue;
    }
    const double *p = L->xyz + 3 * L->first[i];
    const size_t n = L->first[i + 1] - L->first[i];
    if (grow((void **)&W->t, &W->tcap, old_len[r], sizeof *W->t)) rc = MX_ENOMEM;
    else if (place_path(G, (uint8_t *)G->fixed, moved, old + old_at[r], old_len[r], p, n, W->t, &st->nodes)) {
      lp->ok[i] = 1;
      st->lines++;
      rc = keep_path(lp, i, old + old_at[r], old_len[r]);
    } else
      st->lines_missed++; /* cannot be: the same path from the same places */
  }
out:
  mx_free(cmark);
  mx_free(exit_of);
  mx_free(redo);
  mx_free(old);
  mx_free(old_at);
  mx_free(old_len);
  mx_free(inredo);
  return rc;
}

/* ---- sides ------------------------------------------------------------- */

typedef struct {
  mx_surface_index S;
  mx_trisoup sub; /* the patch's triangles over the soup's vertices */
  int built;
} patch_index;

/* The patches' triangles (CSR: patch p's are tri[off[p] .. off[p + 1]))
 * and a vertex map (nv entries, UINT32_MAX between builds), for building
 * a patch's index over its own vertices only. */
typedef struct {
  uint32_t *off, *tri, *vmap;
} patch_lists;

static int patch_lists_make(const mx_feature_input *in, patch_lists *pl) {
  pl->off = mx_calloc((in->npatches + 2) * sizeof *pl->off);
  pl->tri = mx_alloc((in->nt + 1) * sizeof *pl->tri);
  pl->vmap = mx_alloc((in->soup->nv + 1) * sizeof *pl->vmap);
  if (!pl->off || !pl->tri || !pl->vmap) return MX_ENOMEM;
  for (size_t t = 0; t < in->nt; t++) pl->off[in->patch[t] + 1]++;
  for (size_t p = 0; p < in->npatches; p++) pl->off[p + 1] += pl->off[p];
  for (size_t t = 0; t < in->nt; t++) pl->tri[pl->off[in->patch[t]]++] = (uint32_t)t;
  for (size_t p = in->npatches; p > 0; p--) pl->off[p] = pl->off[p - 1];
  pl->off[0] = 0;
  for (size_t v = 0; v < in->soup->nv; v++) pl->vmap[v] = UINT32_MAX;
  return MX_OK;
}

static void patch_lists_free(patch_lists *pl) {
  mx_free(pl->off);
  mx_free(pl->tri);
  mx_free(pl->vmap);
}

#define PATCH_DIRECT 4096 /* triangles a patch is searched without an index up to */

static int patch_closest(const mx_feature_input *in, patch_lists *pl, patch_index *pi,
                         uint32_t patch, const double *x, double *q) {
  patch_index *P = pi + patch;
  if (!P->built) {
    const mx_trisoup *S0 = in->soup;
    memset(&P->sub, 0, sizeof P->sub);
    int st = MX_OK;
    for (uint32_t k = pl->off[patch]; k < pl->off[patch + 1] && !st; k++) {
      uint32_t w[3];
      for (int c = 0; c < 3 && !st; c++) {
        const uint32_t v = S0->tri[3 * (size_t)pl->tri[k] + c];
        if (pl->vmap[v] == UINT32_MAX) {
          pl->vmap[v] = (uint32_t)P->sub.nv;
          const double y[3] = {S0->x[v], S0->y[v], S0->z[v]};
          st = mx_trisoup_set_vertex(&P->sub, P->sub.nv, y);
        }
        w[c] = pl->vmap[v];
      }
      if (!st) st = mx_trisoup_add_triangle(&P->sub, w[0], w[1], w[2]);
    }
    for (uint32_t k = pl->off[patch]; k < pl->off[patch + 1]; k++)
      for (int c = 0; c < 3; c++) pl->vmap[S0->tri[3 * (size_t)pl->tri[k] + c]] = UINT32_MAX;
    /* an index pays for itself on large patches only (building one has a
     * fixed cost of about 0.2 s: measured on 8 triangles) */
    if (!st && P->sub.nt > PATCH_DIRECT)
      st = mx_surface_index_build(&P->S, &P->sub, 0, (uint32_t)P->sub.nt);
    if (st) {
      mx_trisoup_free(&P->sub);
      return st;
    }
    P->built = 1;
  }
  if (P->sub.nt > PATCH_DIRECT) {
    mx_closest_point(&P->S, x, q, NULL, NULL);
    return MX_OK;
  }
  double best = INFINITY; /* a few triangles: each of them */
  for (size_t t = 0; t < P->sub.nt; t++) {
    double tri[9], y[3];
    for (int c = 0; c < 3; c++) {
      const uint32_t v = P->sub.tri[3 * t + c];
      tri[3 * c] = P->sub.x[v];
      tri[3 * c + 1] = P->sub.y[v];
      tri[3 * c + 2] = P->sub.z[v];
    }
    const double d = mx_closest_on_triangle(tri, x, y);
    if (d < best) {
      best = d;
      memcpy(q, y, sizeof y);
    }
  }
  return MX_OK;
}

static int cmp_u64(const void *a, const void *b) {
  const uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
  return (x > y) - (x < y);
}

/* The half of face f (a quadrilateral split along a line's diagonal: f
 * for the half with the node after the diagonal's first, nf + q for the
 * other) that has edge a-b (a == b: node a, off the diagonal); f itself
 * for a face not split. */
static uint32_t half_of(const graph *G, uint32_t f, uint32_t a, uint32_t b) {
  if (f < G->bf.ntri) return f;
  const size_t q = f - G->bf.ntri;
  if (!G->qdiag[q]) return f;
  const uint32_t *p = G->bf.quad + 4 * q;
  const int s = G->qdiag[q] - 1; /* the diagonal p[s] - p[s + 2] */
  const uint32_t mid = p[s + 1]; /* the first half: p[s], p[s + 1], p[s + 2] */
  return a == mid || b == mid ? f : (uint32_t)(G->nf + q);
}

/* Each region's patch by its nodes' votes; nodes of a region closest to
 * another patch moved onto the region's. near[v]: the nodes looked at. */
static int sides(graph *G, const mx_feature_input *in, const mx_surface_index *S,
                 const uint8_t *near, uint8_t *moved, size_t *count) {
  mx_mesh *M = G->M;
  const size_t nf = G->nf, nh = nf + G->bf.nquad; /* faces, and second halves of split quads */
  uint32_t *up = mx_alloc((nh + 1) * sizeof *up), *np = mx_alloc((M->nnodes + 1) * sizeof *np);
  uint32_t *reg = mx_alloc((M->nnodes + 1) * sizeof *reg);
  uint64_t *vote = NULL;
  patch_index *pi = mx_calloc((in->npatches + 1) * sizeof *pi);
  patch_lists pl = {NULL, NULL, NULL}; /* made when a patch is first asked for */
  int st = up && np && reg && pi ? MX_OK : MX_ENOMEM;
  if (st) goto done;
  for (size_t f = 0; f < nh; f++) up[f] = (uint32_t)f;
  for (size_t e = 0; e < G->ne; e++)
    if (!G->eline[e]) {
      const uint32_t a = (uint32_t)(G->rkey[G->estart[e]] >> 32), b = (uint32_t)G->rkey[G->estart[e]];
      const uint32_t f0 = half_of(G, G->rface[G->estart[e]], a, b);
      for (uint32_t r = G->estart[e] + 1; r < G->estart[e + 1]; r++)
        mx_uf_join(up, f0, half_of(G, G->rface[r], a, b));
    }
  /* each near node's closest patch and region (UINT32_MAX - 1: two regions) */
  size_t nv = 0;
  for (size_t v = 0; v < M->nnodes; v++) {
    reg[v] = UINT32_MAX;
    np[v] = UINT32_MAX;
    if (near[v] && !G->fixed[v]) {
      uint32_t t;
      mx_closest_point(S, M->xyz + 3 * v, NULL, &t, NULL);
      np[v] = t < in->nt ? in->patch[t] : UINT32_MAX;
      nv++;
    }
  }
  for (size_t f = 0; f < nf; f++) {
    int k;
    const uint32_t *p = face_nodes(G, f, &k);
    for (int i = 0; i < k; i++) {
      if (np[p[i]] == UINT32_MAX) continue;
      /* a node of a split quadrilateral off the diagonal is in one half */
      const uint32_t h = k == 4 ? half_of(G, (uint32_t)f, p[i], p[i]) : (uint32_t)f;
      const uint32_t r = mx_uf_find(up, h);
      reg[p[i]] = reg[p[i]] == UINT32_MAX || reg[p[i]] == r ? r : UINT32_MAX - 1;
    }
  }
  /* the votes: (region, patch) pairs sorted, the longest run per region */
  vote = mx_alloc((nv + 1) * sizeof *vote);
  if (!vote) {
    st = MX_ENOMEM;
    goto done;
  }
  size_t n = 0;
  for (size_t v = 0; v < M->nnodes; v++)
    if (np[v] != UINT32_MAX && reg[v] < UINT32_MAX - 1) vote[n++] = (uint64_t)reg[v] << 32 | np[v];
  qsort(vote, n, sizeof *vote, cmp_u64);
  /* the winner of each region, in place at the region's face id (up[] of
   * roots is theirs: roots keep up[r] == r, so the winner goes to np-like
   * storage: reuse up[] only for roots after the last find) */
  uint32_t *win = mx_alloc((nh + 1) * sizeof *win);
  if (!win) {
    st = MX_ENOMEM;
    goto done;
  }
  for (size_t f = 0; f < nh; f++) win[f] = UINT32_MAX;
  for (size_t i = 0, best = 0; i < n;) {
    const uint32_t r = (uint32_t)(vote[i] >> 32);
    size_t j = i;
    best = 0;
    while (j < n && vote[j] >> 32 == r) {
      size_t l = j;
      while (l < n && vote[l] == vote[j]) l++;
      if (l - j > best) {
        best = l - j;
        win[r] = (uint32_t)vote[j];
      }
      j = l;
    }
    /* a clear winner only: two patches about even mean the region runs
     * round a line that was not placed, its sides unknown */
    if (3 * best < 2 * (j - i)) win[r] = UINT32_MAX;
    i = j;
  }
  for (size_t v = 0; v < M->nnodes && !st; v++) {
    if (np[v] == UINT32_MAX || reg[v] >= UINT32_MAX - 1) continue;
    const uint32_t want = win[reg[v]];
    if (want == UINT32_MAX || want == np[v]) continue;
    double q[3];
    if (!pl.off && (st = patch_lists_make(in, &pl))) break;
    st = patch_closest(in, &pl, pi, want, M->xyz + 3 * v, q);
    if (st) break;
    memcpy(M->xyz + 3 * v, q, sizeof q);
    moved[v] = 1;
    (*count)++;
  }
  mx_free(win);
done:
  for (size_t p = 0; pi && p < in->npatches; p++)
    if (pi[p].built) {
      if (pi[p].sub.nt > PATCH_DIRECT) mx_surface_index_free(&pi[p].S);
      mx_trisoup_free(&pi[p].sub);
    }
  mx_free(pi);
  patch_lists_free(&pl);
  mx_free(up);
  mx_free(np);
  mx_free(reg);
  mx_free(vote);
  return st;
}

/* ---- the pass ---------------------------------------------------------- */

/* The boundary faces (all of whose nodes are on the surface) and their
 * graph; mask: nnodes bytes of work space. */
/* A grid of cells of side r, centred on the origin (2^20 cells each way). */
static graph near_grid(double r) {
  graph g = {.h = r};
  for (int a = 0; a < 3; a++) g.lo[a] = -1048576.0 * r;
  return g;
}

/* The keys of the 27 cells around x's appended at k[m ..]; the new count. */
static size_t add_near(const graph *g, const double *x, uint64_t *k, size_t m) {
  int64_t c[3];
  cell_of(g, x, c);
  for (int64_t i = c[0] - 1; i <= c[0] + 1; i++)
    for (int64_t j = c[1] - 1; j <= c[1] + 1; j++)
      for (int64_t l = c[2] - 1; l <= c[2] + 1; l++)
        k[m++] = cell_key(i < 0 ? 0 : i, j < 0 ? 0 : j, l < 0 ? 0 : l);
  return m;
}

/* The cells of side r (keys as cell_key on near_grid(r)) within one cell
 * of the lines' points (taken every r / 2) and corners, sorted, unique:
 * a point within r of a line is in one of them. */
static int near_cells(const mx_feature_lines *L, double r, uint64_t **out, size_t *nout) {
  size_t n = 27 * L->ncorners, m = 0;
  for (size_t i = 0; i < L->nlines; i++)
    for (size_t j = L->first[i]; j + 1 < L->first[i + 1]; j++)
      n += 27 * (2 + (size_t)(2.0 * dist3(L->xyz + 3 * j, L->xyz + 3 * j + 3) / r));
  uint64_t *k = mx_alloc((n + 1) * sizeof *k);
  if (!k) return MX_ENOMEM;
  const graph g = near_grid(r);
  for (size_t c = 0; c < L->ncorners; c++) m = add_near(&g, L->corner + 3 * c, k, m);
  for (size_t i = 0; i < L->nlines; i++)
    for (size_t j = L->first[i]; j + 1 < L->first[i + 1]; j++) {
      const double *u = L->xyz + 3 * j, *v = u + 3;
      const size_t steps = 1 + (size_t)(2.0 * dist3(u, v) / r);
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
  const graph g = near_grid(r);
  const int64_t nn = (int64_t)n;
  #pragma omp parallel for schedule(static)
  for (int64_t v = 0; v < nn; v++)
    if (mask[v]) {
      int64_t c[3];
      cell_of(&g, xyz + 3 * v, c);
      const uint64_t key = cell_key(c[0], c[1], c[2]);
      const size_t at = mx_lower_u64(cells, nc, key);
      mask[v] = at < nc && cells[at] == key;
    }
  mx_free(cells);
  return MX_OK;
}

/* The graph of the boundary faces (with near > 0: those whose every node
 * is within reach of the features; a face shared by two elements still
 * shows in both, so the interior ones are not taken for boundary). */
static int graph_open(graph *G, const uint8_t *states, uint8_t *mask, const mx_feature_lines *L,
                      double near) {
  const mx_mesh *M = G->M;
  for (size_t v = 0; v < M->nnodes; v++) mask[v] = states[v] == MX_NODE_OUTSIDE;
  if (near > 0.0 && mx_feature_near_nodes(L, near, M->xyz, M->nnodes, mask)) return MX_ENOMEM;
  const mx_mesh_view view = {.nnodes = M->nnodes, .xyz = M->xyz, .ncells = M->ncells,
                             .type = M->type, .conn = M->conn};
  const int rc = mx_boundary_faces_extract_masked(&view, mask, &G->bf);
  return rc ? rc : graph_build(G);
}

/* The elements of the quadrilaterals whose diagonal a line took split
 * along it (kernels/cell_split.h); fixed[] and moved[] grown with the new
 * nodes (not feature nodes; their elements' J_ENS set by the split). */
static int split_quads(graph *G, uint8_t **states, uint8_t **fixed, uint8_t **moved,
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
                     mx_split_log *log) {
  memset(st, 0, sizeof *st);
  uint8_t *fixed = *fixed_io;
  memset(fixed, 0, M->nnodes);
  const double t0 = mx_wtime();
  const mx_feature_lines *L = in->L;
  if (!L || (!L->nlines && !L->ncorners) || !M->ncells) return MX_OK;
  graph G;
  memset(&G, 0, sizeof G);
  G.M = M;
  G.fixed = fixed;
  search W;
  memset(&W, 0, sizeof W);
  uint8_t *mask = mx_alloc(M->nnodes + 1), *moved = mx_calloc(M->nnodes + 1);
  uint64_t *ckey = NULL;
  uint32_t *cnode = NULL, *doff = NULL;
  double *dir = NULL, *x0 = NULL;
  line_paths lp;
  memset(&lp, 0, sizeof lp);
  int rc = mask && moved ? MX_OK : MX_ENOMEM;
  if (!rc) rc = graph_open(&G, *states, mask, L, in->near);
  if (rc) goto done;
  /* corners, and the node each took by the corner's coordinates */
  ckey = mx_alloc((L->ncorners + 1) * sizeof *ckey);
  cnode = mx_alloc((L->ncorners + 1) * sizeof *cnode);
  if (!ckey || !cnode) {
    rc = MX_ENOMEM;
    goto done;
  }
  /* first each corner's ridge directions, by the corners' keys */
  for (size_t c = 0; c < L->ncorners; c++) {
    ckey[c] = point_key(L->corner + 3 * c);
    cnode[c] = (uint32_t)c;
  }
  if (mx_sort_u64(ckey, cnode, L->ncorners) || corner_dirs(L, ckey, cnode, &doff, &dir)) {
    rc = MX_ENOMEM;
    goto done;
  }
  for (size_t k = 0; k < L->ncorners; k++) {
    const uint32_t c = cnode[k];
    cnode[k] = take_corner(&G, fixed, moved, L->corner + 3 * (size_t)c, dir + 3 * (size_t)doff[c],
                           (int)(doff[c + 1] - doff[c]));
    if (cnode[k] == UINT32_MAX) st->corners_missed++;
    else st->corners++;
  }
  st->nodes = st->corners;
  x0 = mx_alloc((3 * M->nnodes + 1) * sizeof *x0);
  if (!x0) {
    rc = MX_ENOMEM;
    goto done;
  }
  memcpy(x0, M->xyz, 3 * M->nnodes * sizeof *x0);
  /* lines: open ones between their corners' nodes, loops in two halves */
  if (!rc) rc = corner_lines(&lp, L, ckey);
  lp.at = mx_calloc((L->nlines + 1) * sizeof *lp.at);
  lp.len = mx_calloc((L->nlines + 1) * sizeof *lp.len);
  lp.ok = mx_calloc(L->nlines + 1);
  if (!lp.at || !lp.len || !lp.ok) rc = MX_ENOMEM;
  for (size_t i = 0; i < L->nlines && !rc; i++) rc = place_line(&G, &W, &lp, L, i, ckey, cnode, moved, st);
  for (int t = 0; t < RETRIES && !rc && st->lines_missed; t++)
    rc = retry_at_corners(&G, &W, &lp, L, ckey, cnode, moved, x0, st);
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
    rc = sides(&G, in, S, mask, moved, &st->sides);
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
  graph_free(&G);
  mx_free(W.tube);
  mx_free(W.cost);
  mx_free(W.d);
  mx_free(W.s);
  mx_free(W.prev);
  mx_free(W.heap);
  mx_free(W.pen);
  mx_free(lp.cl_off);
  mx_free(lp.cl);
  mx_free(lp.oth);
  mx_free(W.path);
  mx_free(W.t);
  mx_free(mask);
  mx_free(moved);
  mx_free(ckey);
  mx_free(cnode);
  mx_free(doff);
  mx_free(dir);
  mx_free(x0);
  mx_free(lp.at);
  mx_free(lp.len);
  mx_free(lp.node);
  mx_free(lp.ok);
  mx_free(lp.sub);
  st->seconds = mx_wtime() - t0;
  return rc;
}
