/* Corners onto nodes and ridges onto chains of boundary edges
 * (kernels/feature_graph.h, mx_fgraph_place_lines). */
#include "kernels/feature_graph.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "base/common.h"
#include "base/scan.h"

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
    const double e = mx_fg_dist3(x, y);
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
  mx_fgraph *G;
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
static size_t shortcut(const mx_fgraph *G, uint32_t *path, size_t k) {
  size_t n = 1;
  for (size_t i = 1; i < k; i++) {
    while (n >= 2 && mx_fgraph_edge(G, path[n - 2], path[i]) != UINT32_MAX) n--;
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
static size_t find_path(mx_fgraph *G, search *W, const double *p, size_t n, uint32_t a, uint32_t b,
                        int *nomem) {
  const double *X = G->M->xyz;
  /* the tube: boundary nodes within 2 cells of points every half cell */
  tube_ctx tc = {G, W->tube, 0, W->cap, 0};
  for (size_t i = 0; i + 1 < n; i++) {
    const double *u = p + 3 * i, *v = u + 3;
    const size_t steps = 1 + (size_t)(2.0 * mx_fg_dist3(u, v) / G->h);
    for (size_t s = 0; s <= steps; s++) {
      const double t = (double)s / (double)steps;
      const double x[3] = {u[0] + t * (v[0] - u[0]), u[1] + t * (v[1] - u[1]), u[2] + t * (v[2] - u[2])};
      mx_fgraph_cells_around(G, x, 2, tube_fn, &tc);
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
      const double len = mx_fg_dist3(X + 3 * (size_t)u, X + 3 * (size_t)w);
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
    const double l = mx_fg_dist3(p + 3 * i, p + 3 * i + 3);
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
static void mark_path(mx_fgraph *G, const uint32_t *path, size_t k) {
  for (size_t i = 0; i + 1 < k; i++) {
    const uint32_t e = mx_fgraph_edge(G, path[i], path[i + 1]);
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
/* The places t[1 .. k - 1) of a path's inner nodes along the polyline
 * p[0..n) moved onto its inner vertices: each vertex onto its nearest
 * node, when that stays well between the node's neighbours (a tenth of
 * each gap): the chain then turns where the line does, and
 * between two such nodes follows a straight stretch exactly (a curved
 * ridge's facets, when the mesh edges are shorter). The order is kept. */
static void snap_to_vertices(const double *p, size_t n, double *t, size_t k) {
  double s = 0.0;
  size_t i = 1;
  for (size_t j = 1; j + 1 < n && k > 2; j++) {
    s += mx_fg_dist3(p + 3 * (j - 1), p + 3 * j);
    while (i + 2 < k && t[i + 1] <= s) i++;
    /* the nearer of the inner nodes i and i + 1 around s */
    size_t b = i;
    if (i + 2 < k && fabs(t[i + 1] - s) < fabs(t[i] - s)) b = i + 1;
    const double lo = t[b - 1] + 0.1 * (t[b] - t[b - 1]), hi = t[b + 1] - 0.1 * (t[b + 1] - t[b]);
    if (s > lo && s < hi) t[b] = s;
  }
}

static int place_path(mx_fgraph *G, uint8_t *fixed, uint8_t *moved, const uint32_t *path, size_t k,
                      const double *p, size_t n, double *t, size_t *nodes) {
  double *X = G->M->xyz, total = 0.0;
  for (size_t i = 0; i + 1 < n; i++) total += mx_fg_dist3(p + 3 * i, p + 3 * i + 3);
  t[0] = 0.0;
  t[k - 1] = total;
  for (size_t i = 1; i + 1 < k; i++) {
    on_polyline(p, n, X + 3 * (size_t)path[i], NULL, t + i);
    const double gap = 0.2 * mx_fg_dist3(X + 3 * (size_t)path[i], X + 3 * (size_t)path[i - 1]);
    t[i] = fmax(t[i], t[i - 1] + gap);
  }
  for (size_t i = k - 1; i-- > 1;) {
    const double gap = 0.2 * mx_fg_dist3(X + 3 * (size_t)path[i], X + 3 * (size_t)path[i + 1]);
    t[i] = fmin(t[i], t[i + 1] - gap);
  }
  for (size_t i = 1; i < k; i++)
    if (!(t[i] > t[i - 1])) return 0;
  snap_to_vertices(p, n, t, k);
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
static uint32_t take_point(mx_fgraph *G, uint8_t *fixed, uint8_t *moved, const double *x) {
  const uint32_t v = mx_fgraph_nearest_free(G, x);
  if (v == UINT32_MAX || mx_fg_dist3(x, G->M->xyz + 3 * (size_t)v) > MX_FEATURE_REACH * G->h)
    return UINT32_MAX;
  memcpy(G->M->xyz + 3 * (size_t)v, x, 3 * sizeof *x);
  fixed[v] = 1;
  moved[v] = 1;
  return v;
}

static uint32_t taken_at(const uint64_t *key, const uint32_t *node, size_t n, const double *x);

typedef struct {
  const mx_fgraph *G;
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
static int star_score(const mx_fgraph *G, uint32_t v, const double *x, const double *dir, int nd) {
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
  const double d = mx_fg_dist3(c->x, c->G->M->xyz + 3 * (size_t)v);
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
static uint32_t take_corner(mx_fgraph *G, uint8_t *fixed, uint8_t *moved, const double *x,
                            const double *dir, int nd) {
  const uint32_t v0 = mx_fgraph_nearest_free(G, x);
  if (v0 == UINT32_MAX) return v0;
  const double d0 = mx_fg_dist3(x, G->M->xyz + 3 * (size_t)v0);
  if (d0 > MX_FEATURE_REACH * G->h) return UINT32_MAX; /* not this mesh's (a patch's) */
  corner_ctx c = {G, x, dir, nd, d0 + G->h, star_score(G, v0, x, dir, nd), d0, v0};
  if (c.best_score < nd) mx_fgraph_cells_around(G, x, 1 + (int64_t)(c.reach / G->h), corner_fn, &c);
  memcpy(G->M->xyz + 3 * (size_t)c.node, x, 3 * sizeof *x);
  fixed[c.node] = 1;
  moved[c.node] = 1;
  return c.node;
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
  /* the loops' halves placed (never taken back): their nodes, each path
   * ended by UINT32_MAX */
  uint32_t *loops;
  size_t nloops, loops_cap;
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

/* Line i's first (end 0) or last (end 1) point. */
static const double *line_end(const mx_feature_lines *L, size_t i, int end) {
  return L->xyz + 3 * (end ? L->first[i + 1] - 1 : L->first[i]);
}

/* A line's direction out of its end `end` (a unit vector). */
static void line_dir(const mx_feature_lines *L, size_t i, int end, double *d) {
  const double *p = line_end(L, i, end), *q = end ? p - 3 : p + 3;
  const double l = mx_fg_dist3(p, q);
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
      for (int end = 0; end < 2; end++) {
        const size_t k = corner_rank(ckey, nc, line_end(L, i, end));
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
  for (int end = 0; end < 2; end++) {
    const size_t k = corner_rank(ckey, L->ncorners, line_end(L, i, end));
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
      memcpy(o, line_end(L, j, e), 3 * sizeof *o);
      line_dir(L, j, e, o + 3);
    }
  }
  return MX_OK;
}

static int keep_loop(line_paths *lp, const uint32_t *path, size_t k) {
  if (lp->nloops + k + 1 > lp->loops_cap &&
      grow((void **)&lp->loops, &lp->loops_cap, 2 * (lp->nloops + k + 1), sizeof *lp->loops))
    return MX_ENOMEM;
  memcpy(lp->loops + lp->nloops, path, k * sizeof *path);
  lp->nloops += k;
  lp->loops[lp->nloops++] = UINT32_MAX;
  return MX_OK;
}

static int cmp_triple(const void *a, const void *b) {
  const uint32_t *x = a, *y = b;
  return (x[0] > y[0]) - (x[0] < y[0]);
}

/* The chains of the lines placed: each path's inner nodes with their
 * neighbours on it, sorted by node. */
static int chains(const line_paths *lp, const mx_feature_lines *L, mx_feature_chain *c) {
  size_t n = 0;
  for (size_t i = 0; i < L->nlines; i++)
    if (lp->ok[i] && lp->len[i] > 2) n += lp->len[i] - 2;
  n += lp->nloops;
  uint32_t *t = mx_alloc((3 * n + 3) * sizeof *t);
  if (!t) return MX_ENOMEM;
  size_t m = 0;
  for (size_t i = 0; i < L->nlines; i++) {
    if (!lp->ok[i]) continue;
    const uint32_t *p = lp->node + lp->at[i];
    for (size_t j = 1; j + 1 < lp->len[i]; j++, m++) {
      t[3 * m] = p[j];
      t[3 * m + 1] = p[j - 1];
      t[3 * m + 2] = p[j + 1];
    }
  }
  for (size_t j = 0; j < lp->nloops; j++) {
    if (lp->loops[j] == UINT32_MAX || j == 0 || lp->loops[j - 1] == UINT32_MAX ||
        j + 1 == lp->nloops || lp->loops[j + 1] == UINT32_MAX)
      continue; /* a path's ends: the points taken on the loop */
    t[3 * m] = lp->loops[j];
    t[3 * m + 1] = lp->loops[j - 1];
    t[3 * m + 2] = lp->loops[j + 1];
    m++;
  }
  qsort(t, m, 3 * sizeof *t, cmp_triple);
  c->n = m;
  c->node = mx_alloc((m + 1) * sizeof *c->node);
  c->prev = mx_alloc((m + 1) * sizeof *c->prev);
  c->next = mx_alloc((m + 1) * sizeof *c->next);
  int rc = c->node && c->prev && c->next ? MX_OK : MX_ENOMEM;
  for (size_t k = 0; k < m && !rc; k++) {
    c->node[k] = t[3 * k];
    c->prev[k] = t[3 * k + 1];
    c->next[k] = t[3 * k + 2];
  }
  mx_free(t);
  return rc;
}

void mx_feature_chain_free(mx_feature_chain *c) {
  mx_free(c->node);
  mx_free(c->prev);
  mx_free(c->next);
  memset(c, 0, sizeof *c);
}

/* Line i placed (open: between its corners' nodes; a loop: in two halves
 * from two points taken on it), its paths kept in lp. */
static int place_line(mx_fgraph *G, search *W, line_paths *lp, const mx_feature_lines *L, size_t i,
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
      if (ok && keep_loop(lp, W->path, k)) nomem = 1;
      memcpy(sub, p + 3 * mid, 3 * (n - mid) * sizeof *sub);
      memcpy(sub + 3 * (n - mid), p, 3 * sizeof *sub);
      k = ok && !nomem ? find_path(G, W, sub, n - mid + 1, b, a, &nomem) : 0;
      ok = ok && k >= 2 && place_path(G, fixed, moved, W->path, k, sub, n - mid + 1, W->t, &st->nodes);
      if (ok && keep_loop(lp, W->path, k)) nomem = 1;
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
static void unplace_line(mx_fgraph *G, line_paths *lp, size_t i, uint8_t *moved, const double *x0,
                         mx_feature_stats *st) {
  uint8_t *fixed = (uint8_t *)G->fixed;
  const uint32_t *path = lp->node + lp->at[i];
  const size_t k = lp->len[i];
  for (size_t j = 0; j + 1 < k; j++) {
    const uint32_t e = mx_fgraph_edge(G, path[j], path[j + 1]);
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


/* At each marked corner (cmark, by its node), its edges handed out as
 * exits to the lines out of it that are placed again (inredo): best
 * (line, edge) pairs first, within 60 degrees of the line's direction, one
 * edge a line (exit_of[w]: the line edge w is an exit for). */
static void hand_out_exits(const mx_fgraph *G, const line_paths *lp, const mx_feature_lines *L,
                           const uint32_t *cnode, const uint8_t *cmark, const uint8_t *inredo,
                           uint32_t *exit_of) {
  const mx_mesh *M = G->M;
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
}

/* The open lines missed tried again: every open line at a corner of a
 * missed one is taken back, each such corner's edges handed out as exits
 * (each line the free neighbour most along its direction, within 60
 * degrees, best pairs first), closed to the other lines, and the lines
 * placed again, the missed ones first. Kept when as many lines are placed
 * as before or more (another line missed is tried next); otherwise the
 * placement before is restored. Measured: on the tetrahedron, whose
 * corners have four edges, the first lines took the edges the last one
 * needed. */
static int retry_at_corners(mx_fgraph *G, search *W, line_paths *lp, const mx_feature_lines *L,
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
      const uint32_t c = taken_at(ckey, cnode, L->ncorners, line_end(L, i, end));
      if (c != UINT32_MAX) cmark[c] = 1;
    }
  }
  inredo = mx_calloc(L->nlines + 1);
  if (!inredo) {
    rc = MX_ENOMEM;
    goto out;
  }
  for (size_t r = 0; r < nr; r++) inredo[redo[r]] = 1;
  hand_out_exits(G, lp, L, cnode, cmark, inredo, exit_of);
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

int mx_fgraph_place_lines(mx_fgraph *G, const mx_feature_lines *L, int retries, uint8_t *moved,
                          mx_feature_stats *st, mx_feature_chain *chain) {
  mx_mesh *M = G->M;
  uint8_t *fixed = (uint8_t *)G->fixed;
  search W;
  memset(&W, 0, sizeof W);
  uint64_t *ckey = NULL;
  uint32_t *cnode = NULL;
  double *dir = NULL, *x0 = NULL;
  line_paths lp;
  memset(&lp, 0, sizeof lp);
  int rc = MX_OK;
  /* corners, and the node each took by the corner's coordinates */
  ckey = mx_alloc((L->ncorners + 1) * sizeof *ckey);
  cnode = mx_alloc((L->ncorners + 1) * sizeof *cnode);
  if (!ckey || !cnode) {
    rc = MX_ENOMEM;
    goto done;
  }
  /* the corners by their keys, and the line ends at each */
  for (size_t c = 0; c < L->ncorners; c++) {
    ckey[c] = point_key(L->corner + 3 * c);
    cnode[c] = (uint32_t)c;
  }
  if (mx_sort_u64(ckey, cnode, L->ncorners) || corner_lines(&lp, L, ckey)) {
    rc = MX_ENOMEM;
    goto done;
  }
  for (size_t k = 0; k < L->ncorners; k++) {
    /* its ridges' directions out of it */
    const uint32_t c = cnode[k], nd = lp.cl_off[k + 1] - lp.cl_off[k];
    double *dr = mx_realloc(dir, (3 * (size_t)nd + 3) * sizeof *dir);
    if (!dr) {
      rc = MX_ENOMEM;
      goto done;
    }
    dir = dr;
    for (uint32_t q = 0; q < nd; q++) {
      const uint32_t e = lp.cl[lp.cl_off[k] + q];
      line_dir(L, e / 2, (int)(e & 1), dir + 3 * (size_t)q);
    }
    cnode[k] = take_corner(G, fixed, moved, L->corner + 3 * (size_t)c, dir, (int)nd);
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
  lp.at = mx_calloc((L->nlines + 1) * sizeof *lp.at);
  lp.len = mx_calloc((L->nlines + 1) * sizeof *lp.len);
  lp.ok = mx_calloc(L->nlines + 1);
  if (!lp.at || !lp.len || !lp.ok) rc = MX_ENOMEM;
  for (size_t i = 0; i < L->nlines && !rc; i++) rc = place_line(G, &W, &lp, L, i, ckey, cnode, moved, st);
  for (int t = 0; t < retries && !rc && st->lines_missed; t++)
    rc = retry_at_corners(G, &W, &lp, L, ckey, cnode, moved, x0, st);
  if (!rc && chain) rc = chains(&lp, L, chain);
done:
  mx_free(W.tube);
  mx_free(W.cost);
  mx_free(W.d);
  mx_free(W.s);
  mx_free(W.prev);
  mx_free(W.heap);
  mx_free(W.pen);
  mx_free(W.path);
  mx_free(W.t);
  mx_free(lp.cl_off);
  mx_free(lp.cl);
  mx_free(lp.oth);
  mx_free(lp.at);
  mx_free(lp.len);
  mx_free(lp.node);
  mx_free(lp.ok);
  mx_free(lp.sub);
  mx_free(lp.loops);
  mx_free(ckey);
  mx_free(cnode);
  mx_free(dir);
  mx_free(x0);
  return rc;
}
