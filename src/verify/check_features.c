/* Feature distances (definitions in check.h): the boundary edges of a mesh
 * (the faces used once, from the checker's own face matching,
 * check_faces.c, their edges sorted and made unique), a BVH over them
 * (geom/bvh.h, each edge a-b as the degenerate triangle a-b-b, over the
 * edges' nodes alone), then every segment of every feature line sampled
 * and every sample's distance to the nearest edge, every corner's to the
 * nearest edge node. An independent measurement: it sees the lines and the
 * mesh, nothing of how the mesh was made. */
#include <math.h>
#include <string.h>

#include "base/scan.h"
#include "geom/bvh.h"
#include "verify/check_passes.h"

enum { MIN_PARTS = 4, MAX_PARTS = 65536, STACK = 128 };

/* ---- the edges' tree ------------------------------------------------------ */

typedef struct {
  size_t nv, ne;
  double *x, *y, *z;  /* nv: the edges' nodes */
  uint32_t *node;     /* nv: their ids in the mesh */
  uint32_t *tri;      /* 3 ne: a, b, b (compact ids) */
  uint32_t *idx;      /* ne: slot -> edge */
  mx_bvh_node *bvh;
} etree;

static void etree_free(etree *T) {
  mx_free(T->x);
  mx_free(T->y);
  mx_free(T->z);
  mx_free(T->node);
  mx_free(T->tri);
  mx_free(T->idx);
  mx_free(T->bvh);
  memset(T, 0, sizeof *T);
}

static int etree_build(etree *T, const double *xyz, size_t nnodes, const uint32_t *edge,
                       size_t ne) {
  memset(T, 0, sizeof *T);
  uint32_t *map = mx_alloc((nnodes + 1) * sizeof *map);
  double *cen = mx_alloc((3 * ne + 1) * sizeof *cen);
  const size_t nmax = 2 * ne < nnodes ? 2 * ne : nnodes;
  T->x = mx_alloc((nmax + 1) * sizeof *T->x);
  T->y = mx_alloc((nmax + 1) * sizeof *T->y);
  T->z = mx_alloc((nmax + 1) * sizeof *T->z);
  T->node = mx_alloc((nmax + 1) * sizeof *T->node);
  T->tri = mx_alloc((3 * ne + 1) * sizeof *T->tri);
  T->idx = mx_alloc((ne + 1) * sizeof *T->idx);
  T->bvh = ne ? mx_alloc(mx_bvh_node_count(ne) * sizeof *T->bvh) : NULL;
  int st = map && cen && T->x && T->y && T->z && T->node && T->tri && T->idx && (T->bvh || !ne)
               ? MX_OK
               : MX_ENOMEM;
  if (st == MX_OK) {
    for (size_t v = 0; v < nnodes; v++) map[v] = UINT32_MAX;
    for (size_t e = 0; e < ne; e++) {
      uint32_t c[2];
      for (int k = 0; k < 2; k++) {
        const uint32_t v = edge[2 * e + (size_t)k];
        if (map[v] == UINT32_MAX) {
          map[v] = (uint32_t)T->nv;
          T->node[T->nv] = v;
          T->x[T->nv] = xyz[3 * (size_t)v];
          T->y[T->nv] = xyz[3 * (size_t)v + 1];
          T->z[T->nv] = xyz[3 * (size_t)v + 2];
          T->nv++;
        }
        c[k] = map[v];
      }
      T->tri[3 * e] = c[0];
      T->tri[3 * e + 1] = T->tri[3 * e + 2] = c[1];
      cen[e] = 0.5 * (T->x[c[0]] + T->x[c[1]]);
      cen[ne + e] = 0.5 * (T->y[c[0]] + T->y[c[1]]);
      cen[2 * ne + e] = 0.5 * (T->z[c[0]] + T->z[c[1]]);
      T->idx[e] = (uint32_t)e;
    }
    T->ne = ne;
    if (ne) mx_bvh_build(T->bvh, T->idx, cen, (uint32_t)ne, T->tri, T->x, T->y, T->z);
  }
  mx_free(map);
  mx_free(cen);
  if (st != MX_OK) etree_free(T);
  return st;
}

static inline void tnode(const etree *T, uint32_t v, double p[3]) {
  p[0] = T->x[v];
  p[1] = T->y[v];
  p[2] = T->z[v];
}

static double point_segment_d2(const double p[3], const double a[3], const double b[3]) {
  double ab[3], ap[3], l2 = 0.0, t = 0.0;
  for (int k = 0; k < 3; k++) {
    ab[k] = b[k] - a[k];
    ap[k] = p[k] - a[k];
    l2 += ab[k] * ab[k];
    t += ab[k] * ap[k];
  }
  t = l2 > 0.0 ? mx_min(mx_max(t / l2, 0.0), 1.0) : 0.0;
  double d2 = 0.0;
  for (int k = 0; k < 3; k++) {
    const double d = ap[k] - t * ab[k];
    d2 += d * d;
  }
  return d2;
}

static double point_d2(const double p[3], const double a[3]) {
  double d2 = 0.0;
  for (int k = 0; k < 3; k++) d2 += (p[k] - a[k]) * (p[k] - a[k]);
  return d2;
}

/* The nearest edge to p (*which: the edge) or, nodes set, the nearest
 * node of an edge (its compact id); the squared distance, INFINITY without
 * edges. */
static double nearest(const etree *T, const double p[3], int nodes, uint32_t *which) {
  double best = INFINITY;
  *which = UINT32_MAX;
  if (!T->ne) return best;
  uint32_t stack[STACK];
  int top = 0;
  stack[top++] = 0;
  while (top) {
    const mx_bvh_node *N = &T->bvh[stack[--top]];
    if (ck_box_d2(p, N->lo, N->hi) >= best) continue;
    if (N->count) {
      for (uint32_t s = N->first; s < N->first + N->count; s++) {
        const uint32_t e = T->idx[s];
        double a[3], b[3];
        tnode(T, T->tri[3 * (size_t)e], a);
        tnode(T, T->tri[3 * (size_t)e + 1], b);
        if (!nodes) {
          const double d2 = point_segment_d2(p, a, b);
          if (d2 < best) {
            best = d2;
            *which = e;
          }
          continue;
        }
        for (int k = 0; k < 2; k++) {
          const double d2 = point_d2(p, k ? b : a);
          if (d2 < best) {
            best = d2;
            *which = T->tri[3 * (size_t)e + (size_t)k];
          }
        }
      }
      continue;
    }
    const uint32_t c = N->first;
    const double d0 = ck_box_d2(p, T->bvh[c].lo, T->bvh[c].hi),
                 d1 = ck_box_d2(p, T->bvh[c + 1].lo, T->bvh[c + 1].hi);
    if (top + 2 > STACK) continue; /* deeper than any tree of < 2^32 edges */
    stack[top++] = d0 <= d1 ? c + 1 : c; /* the nearer child popped first */
    stack[top++] = d0 <= d1 ? c : c + 1;
  }
  return best;
}

static double edge_length(const etree *T, uint32_t e) {
  if (e == UINT32_MAX) return NAN;
  double a[3], b[3];
  tnode(T, T->tri[3 * (size_t)e], a);
  tnode(T, T->tri[3 * (size_t)e + 1], b);
  return sqrt(point_d2(a, b));
}

/* ---- sampling -------------------------------------------------------------- */

typedef struct {
  double d2;     /* the largest squared distance of the segment's samples */
  double at[3];  /* at its first sample */
  size_t inner;  /* samples between its ends */
  double length;
} seg_result;

/* Segment s of line i: points p -> q. */
static void sample_segment(const etree *T, const double *p, const double *q, seg_result *r) {
  uint32_t ep, eq;
  const double dp = nearest(T, p, 0, &ep), dq = nearest(T, q, 0, &eq);
  r->length = sqrt(point_d2(p, q));
  r->d2 = dp;
  memcpy(r->at, p, sizeof r->at);
  const double h = mx_min(edge_length(T, ep), edge_length(T, eq));
  double parts = h > 0.0 ? ceil(4.0 * r->length / h) : MIN_PARTS;
  if (!(parts >= MIN_PARTS)) parts = MIN_PARTS; /* NAN too */
  if (parts > MAX_PARTS) parts = MAX_PARTS;
  const int k = (int)parts;
  for (int j = 1; j < k; j++) {
    const double t = (double)j / k;
    double x[3];
    for (int a = 0; a < 3; a++) x[a] = p[a] + (q[a] - p[a]) * t;
    uint32_t e;
    const double d2 = nearest(T, x, 0, &e);
    if (d2 > r->d2) {
      r->d2 = d2;
      memcpy(r->at, x, sizeof r->at);
    }
  }
  if (dq > r->d2) {
    r->d2 = dq;
    memcpy(r->at, q, sizeof r->at);
  }
  r->inner = (size_t)(k - 1);
}

/* The segments of the lines: seg[2 s], seg[2 s + 1] points, line[s]. */
static size_t count_segments(const mx_feature_lines *L) {
  size_t n = 0;
  for (size_t i = 0; i < L->nlines; i++) {
    const size_t m = L->first[i + 1] - L->first[i];
    n += m < 2 ? 0 : L->loop[i] ? m : m - 1;
  }
  return n;
}

static int ridge_distance(const etree *T, const mx_feature_lines *L, mx_check_feature_dist *d) {
  const size_t ns = count_segments(L);
  size_t *seg = mx_alloc((2 * ns + 1) * sizeof *seg);
  size_t *line = mx_alloc((ns + 1) * sizeof *line);
  seg_result *res = mx_alloc((ns + 1) * sizeof *res);
  if (!seg || !line || !res) {
    mx_free(seg);
    mx_free(line);
    mx_free(res);
    return MX_ENOMEM;
  }
  size_t n = 0;
  for (size_t i = 0; i < L->nlines; i++) {
    const size_t a = L->first[i], b = L->first[i + 1];
    if (b - a < 2) continue;
    for (size_t j = a; j + 1 < b; j++, n++) {
      seg[2 * n] = j;
      seg[2 * n + 1] = j + 1;
      line[n] = i;
    }
    if (L->loop[i]) {
      seg[2 * n] = b - 1;
      seg[2 * n + 1] = a;
      line[n++] = i;
    }
  }
#pragma omp parallel for schedule(dynamic, 16) if (ns > 256)
  for (size_t s = 0; s < ns; s++)
    sample_segment(T, L->xyz + 3 * seg[2 * s], L->xyz + 3 * seg[2 * s + 1], &res[s]);
  double best = -1.0;
  d->samples = L->first[L->nlines];
  for (size_t s = 0; s < ns; s++) { /* the first of the largest, in line order */
    d->samples += res[s].inner;
    d->length += res[s].length;
    if (res[s].d2 > best) {
      best = res[s].d2;
      memcpy(d->ridge_at, res[s].at, sizeof d->ridge_at);
      d->ridge_line = line[s];
    }
  }
  if (ns) d->ridge_dist = sqrt(best);
  mx_free(seg);
  mx_free(line);
  mx_free(res);
  return MX_OK;
}

static void corner_distance(const etree *T, const mx_feature_lines *L,
                            mx_check_feature_dist *d) {
  double best = -1.0;
  for (size_t c = 0; c < L->ncorners; c++) {
    uint32_t v;
    const double d2 = nearest(T, L->corner + 3 * c, 1, &v);
    if (d2 > best) {
      best = d2;
      d->corner = c;
      memcpy(d->corner_at, L->corner + 3 * c, sizeof d->corner_at);
      d->corner_node = v == UINT32_MAX ? UINT32_MAX : T->node[v];
    }
  }
  if (L->ncorners) d->corner_dist = sqrt(best);
}

/* ---- the entries ------------------------------------------------------------ */

int mx_check_features(const mx_feature_lines *L, const double *xyz, size_t nnodes,
                      const uint32_t *edge, size_t nedges, mx_check_feature_dist *d) {
  memset(d, 0, sizeof *d);
  d->ridge_dist = d->corner_dist = d->diagonal = NAN;
  for (int a = 0; a < 3; a++) d->ridge_at[a] = d->corner_at[a] = NAN;
  d->corner_node = UINT32_MAX;
  d->lines = L->nlines;
  d->corners = L->ncorners;
  for (size_t i = 0; i < L->nlines; i++) d->loops += L->loop[i] != 0;
  if (nedges >= UINT32_MAX) {
    mx_error(NULL, 0, "feature distances: %zu boundary edges, more than %u", nedges,
             UINT32_MAX - 1);
    return MX_EINPUT;
  }
  double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
  for (size_t k = 0; k < 2 * nedges; k++) {
    const size_t v = edge[k];
    if (v >= nnodes) {
      mx_error(NULL, 0, "feature distances: edge %zu has node %zu, out of range (%zu nodes)",
               k / 2, v, nnodes);
      return MX_EINPUT;
    }
    for (int a = 0; a < 3; a++) {
      const double x = xyz[3 * v + (size_t)a];
      if (!isfinite(x)) {
        mx_error(NULL, 0, "feature distances: node %zu has a coordinate that is not finite",
                 v);
        return MX_EINPUT;
      }
      lo[a] = mx_min(lo[a], x);
      hi[a] = mx_max(hi[a], x);
    }
  }
  d->edges = nedges;
  if (nedges)
    d->diagonal = sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                       (hi[2] - lo[2]) * (hi[2] - lo[2]));
  etree T;
  MX_CHECK(etree_build(&T, xyz, nnodes, edge, nedges));
  const int st = ridge_distance(&T, L, d);
  if (st == MX_OK) corner_distance(&T, L, d);
  etree_free(&T);
  return st;
}

/* Like check.c's validation, what the face matching needs. */
static int mesh_ok(const mx_mesh_data *m) {
  if (m->nnodes >= UINT32_MAX || m->ncells > UINT32_MAX / 6) {
    mx_error(NULL, 0, "feature distances: %zu nodes and %zu cells: at most %u nodes and %u "
             "cells", m->nnodes, m->ncells, UINT32_MAX - 1, UINT32_MAX / 6);
    return MX_EINPUT;
  }
  for (size_t c = 0; c < m->ncells; c++) {
    int bad = m->type[c] > MX_HEX;
    for (int j = 0; !bad && j < mx_cell_nodes[m->type[c]]; j++)
      bad = m->conn[8 * c + (size_t)j] >= m->nnodes;
    if (bad) {
      mx_error(NULL, 0, "feature distances: cell %zu has a bad type (%d) or a node index out "
               "of range (%zu nodes)", c, m->type[c], m->nnodes);
      return MX_EINPUT;
    }
  }
  return MX_OK;
}

int mx_check_boundary_edges(const mx_mesh_data *m, uint32_t **edge, size_t *nedges) {
  *edge = NULL;
  *nedges = 0;
  MX_CHECK(mesh_ok(m));
  faces F;
  memset(&F, 0, sizeof F);
  uint8_t *ef = mx_calloc(m->ncells + 1);
  int st = ef ? mx_ck_faces_bucket(m, &F) : MX_ENOMEM;
  face_counts fc = {0, 0, 0, 0};
  if (st == MX_OK) st = mx_ck_faces_match(m, &F, NULL, NULL, ef, &fc);
  mx_free(ef);
  uint64_t *key = NULL;
  size_t nk = 0;
  if (st == MX_OK) {
    key = mx_alloc((4 * fc.boundary + 1) * sizeof *key);
    if (!key) st = MX_ENOMEM;
  }
  for (size_t s = 0; st == MX_OK && s < 6 * m->ncells; s++) {
    if (F.use[s] != 1 || nk + 4 > 4 * fc.boundary) continue;
    uint32_t v[4];
    const int n = face_verts(m, (uint32_t)s, v);
    for (int x = 0; x < n; x++) {
      const uint32_t a = v[x], b = v[(x + 1) % n];
      key[nk++] = a < b ? (uint64_t)a << 32 | b : (uint64_t)b << 32 | a;
    }
  }
  faces_free(&F);
  if (st == MX_OK) st = mx_sort_u64(key, NULL, nk);
  size_t nu = 0;
  for (size_t i = 0; st == MX_OK && i < nk; i++)
    if (i == 0 || key[i] != key[i - 1]) key[nu++] = key[i];
  uint32_t *e = st == MX_OK ? mx_alloc((2 * nu + 1) * sizeof *e) : NULL;
  if (st == MX_OK && !e) st = MX_ENOMEM;
  for (size_t i = 0; st == MX_OK && i < nu; i++) {
    e[2 * i] = (uint32_t)(key[i] >> 32);
    e[2 * i + 1] = (uint32_t)key[i];
  }
  mx_free(key);
  if (st != MX_OK) {
    mx_free(e);
    return st;
  }
  *edge = e;
  *nedges = nu;
  return MX_OK;
}

int mx_check_features_mesh(const mx_mesh_data *m, const mx_feature_lines *L,
                           mx_check_feature_dist *d) {
  uint32_t *edge;
  size_t ne;
  memset(d, 0, sizeof *d);
  d->ridge_dist = d->corner_dist = d->diagonal = NAN;
  MX_CHECK(mx_check_boundary_edges(m, &edge, &ne));
  const int st = mx_check_features(L, m->xyz, m->nnodes, edge, ne, d);
  mx_free(edge);
  return st;
}
