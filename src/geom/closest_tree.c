/* The 4-wide BVH of the closest-point queries (geom/distance.h): oriented
 * boxes of the binary nodes, two levels merged into one wide node, the
 * leaves' float planes (leaf packs), and the hint grid of starting
 * triangles. */
#include "geom/surface_index_impl.h"

#include <string.h>

#include "base/common.h"

/* The leaf packs: per triangle the unit normal n of (b - a) x (c - a) and
 * n . a, and for each edge k (vertex k to k+1) the unit in-plane outward
 * normal m_k = e_k x n and m_k . v_k. Then for any p, with h = n.p - n.a and
 * g_k = m_k.p - m_k.v_k, h^2 + max(0, g_0, g_1, g_2)^2 is at most the
 * squared distance to the triangle (p's projection is at least g_k from the
 * triangle), equal in the face and edge regions. A degenerate triangle gets
 * zeros: bound 0. */
static void fill_lane(mx_leaf_pack *P, int l, const double *t) {
  double e0[3], e1[3], n[3];
  sub3(t + 3, t, e0);
  sub3(t + 6, t, e1);
  cross3(e0, e1, n);
  const double ln = sqrt(dot3(n, n));
  double rec[16] = {0.0};
  if (ln > 0.0) {
    for (int a = 0; a < 3; a++) rec[a] = n[a] / ln;
    rec[3] = dot3(rec, t);
    for (int k = 0; k < 3; k++) {
      double e[3], m[3];
      sub3(t + 3 * ((k + 1) % 3), t + 3 * k, e);
      const double le = sqrt(dot3(e, e));
      if (!(le > 0.0)) continue;
      for (int a = 0; a < 3; a++) e[a] /= le;
      cross3(e, rec, m);
      for (int a = 0; a < 3; a++) rec[4 + 4 * k + a] = m[a];
      rec[7 + 4 * k] = dot3(m, t + 3 * k);
    }
  }
  for (int r = 0; r < 16; r++) P->v[r][l] = (float)rec[r];
}

/* Oriented bounding boxes of the binary nodes, 15 doubles each: centre,
 * three orthonormal axes, half extents. The frame: the area-weighted mean
 * normal of the node's triangles and, in its plane, the principal axes of
 * the vertices; kept if its box is smaller than the axis-aligned one (a
 * flat patch gets a thin box, much tighter than its AABB for points beside
 * it), else the coordinate axes. */
static void node_obb(const mx_surface_index *S, uint32_t n, uint32_t first,
                     double *o) {
  const mx_bvh_node *N = &S->nodes[n];
  const uint32_t m = N->ntri;
  double w[3] = {0.0, 0.0, 0.0};
  for (uint32_t i = first; i < first + m; i++) {
    const double *t = S->tv + 9 * (size_t)i;
    double e0[3], e1[3], nn[3];
    sub3(t + 3, t, e0);
    sub3(t + 6, t, e1);
    cross3(e0, e1, nn);
    for (int a = 0; a < 3; a++) w[a] += nn[a];
  }
  double R[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  const double lw = sqrt(dot3(w, w));
  if (lw > 0.0) {
    double z[3] = {w[0] / lw, w[1] / lw, w[2] / lw}, u[3], v[3];
    const double ref[3] = {fabs(z[0]) < 0.6 ? 1.0 : 0.0,
                           fabs(z[0]) < 0.6 ? 0.0 : 1.0, 0.0};
    cross3(z, ref, u);
    const double lu = sqrt(dot3(u, u));
    for (int a = 0; a < 3; a++) u[a] /= lu;
    cross3(z, u, v);
    /* principal axes of the vertices projected on (u, v) */
    double su = 0, sv = 0, suu = 0, suv = 0, svv = 0;
    for (uint32_t i = first; i < first + m; i++)
      for (int k = 0; k < 3; k++) {
        const double *x = S->tv + 9 * (size_t)i + 3 * k;
        const double pu = dot3(x, u), pv = dot3(x, v);
        su += pu;
        sv += pv;
        suu += pu * pu;
        suv += pu * pv;
        svv += pv * pv;
      }
    const double cnt = 3.0 * m, mu = su / cnt, mv = sv / cnt;
    const double cuu = suu / cnt - mu * mu, cuv = suv / cnt - mu * mv,
                 cvv = svv / cnt - mv * mv;
    const double th = 0.5 * atan2(2.0 * cuv, cuu - cvv);
    const double ct = cos(th), st = sin(th);
    double Q[3][3];
    for (int a = 0; a < 3; a++) {
      Q[0][a] = ct * u[a] + st * v[a];
      Q[1][a] = -st * u[a] + ct * v[a];
    }
    cross3(Q[0], Q[1], Q[2]); /* = z, up to rounding */
    double lo[3] = {INFINITY, INFINITY, INFINITY},
           hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (uint32_t i = first; i < first + m; i++)
      for (int k = 0; k < 9; k += 3)
        for (int r = 0; r < 3; r++) {
          const double x = dot3(Q[r], S->tv + 9 * (size_t)i + k);
          lo[r] = mx_min(lo[r], x);
          hi[r] = mx_max(hi[r], x);
        }
    const double vol_obb = (hi[0] - lo[0]) * (hi[1] - lo[1]) * (hi[2] - lo[2]);
    const double vol_aabb = (N->hi[0] - N->lo[0]) * (N->hi[1] - N->lo[1]) *
                            (N->hi[2] - N->lo[2]);
    if (vol_obb < vol_aabb) {
      memcpy(R, Q, sizeof R);
      double cl[3];
      for (int r = 0; r < 3; r++) {
        cl[r] = 0.5 * (lo[r] + hi[r]);
        o[12 + r] = 0.5 * (hi[r] - lo[r]);
      }
      for (int a = 0; a < 3; a++)
        o[a] = R[0][a] * cl[0] + R[1][a] * cl[1] + R[2][a] * cl[2];
      for (int r = 0; r < 3; r++) memcpy(o + 3 + 3 * r, R[r], sizeof R[r]);
      /* the centre was rounded: widen by its error */
      double cb[3];
      for (int r = 0; r < 3; r++) cb[r] = dot3(R[r], o);
      for (int r = 0; r < 3; r++) o[12 + r] += fabs(cb[r] - cl[r]);
      return;
    }
  }
  for (int a = 0; a < 3; a++) {
    o[a] = 0.5 * (N->lo[a] + N->hi[a]);
    o[12 + a] = 0.5 * (N->hi[a] - N->lo[a]);
    for (int r = 0; r < 3; r++) o[3 + 3 * r + a] = R[r][a];
  }
}

static int node_obbs(const mx_surface_index *S, double **out) {
  const uint32_t nn = S->nnodes;
  double *o = mx_alloc(15 * (size_t)nn * sizeof *o);
  uint32_t *start = mx_alloc((size_t)nn * sizeof *start);
  if (!o || !start) {
    mx_free(o);
    mx_free(start);
    return MX_ENOMEM;
  }
  start[0] = 0;
  for (uint32_t n = 0; n < nn; n++) { /* parents come before children */
    const mx_bvh_node *N = &S->nodes[n];
    if (N->count) continue;
    start[N->first] = start[n];
    start[N->first + 1] = start[n] + S->nodes[N->first].ntri;
  }
#pragma omp parallel for schedule(dynamic, 64) if (nn > 4000)
  for (uint32_t n = 0; n < nn; n++) node_obb(S, n, start[n], o + 15 * (size_t)n);
  mx_free(start);
  *out = o;
  return MX_OK;
}

/* Fill the leaf packs, in parallel; lanes beyond a leaf's triangles repeat
 * its first triangle. */
static void fill_packs(mx_surface_index *S, const uint8_t *pack_count) {
  const uint32_t np = S->npacks;
#pragma omp parallel for schedule(static) if (np > 2000)
  for (uint32_t k = 0; k < np; k++) {
    const uint32_t first = S->leaf_first[k];
    for (uint32_t l = 0; l < 4; l++)
      fill_lane(&S->packs[k], (int)l,
                S->tv + 9 * (size_t)(first + (l < pack_count[k] ? l : 0)));
  }
}

/* The 4-wide BVH for the closest-point queries: every wide node takes the
 * grandchildren of an internal binary node (or a child itself when it is a
 * leaf), so a wide node never holds more than 4 entries; obb: the boxes of
 * the binary nodes (see node_obbs); pack_count receives the slot count of
 * each leaf pack. Returns the wide index of node b. */
static uint32_t collapse(mx_surface_index *S, const double *obb,
                         uint8_t *pack_count, uint32_t b) {
  const uint32_t w = S->nwide++;
  uint32_t e[4];
  int m = 0;
  const mx_bvh_node *N = &S->nodes[b];
  if (N->count) {
    e[m++] = b; /* the root is a leaf */
  } else {
    for (uint32_t c = N->first; c < N->first + 2; c++) {
      const mx_bvh_node *C = &S->nodes[c];
      if (C->count) {
        e[m++] = c;
      } else {
        e[m++] = C->first;
        e[m++] = C->first + 1;
      }
    }
  }
  uint32_t child[4];
  uint8_t count[4];
  for (int j = 0; j < 4; j++) {
    if (j >= m) {
      child[j] = 0;
      count[j] = 0;
      continue;
    }
    const mx_bvh_node *E = &S->nodes[e[j]];
    count[j] = (uint8_t)E->count;
    if (E->count) { /* its pack is filled by fill_packs */
      child[j] = S->npacks++;
      S->leaf_first[child[j]] = E->first;
      pack_count[child[j]] = (uint8_t)E->count;
    } else {
      child[j] = collapse(S, obb, pack_count, e[j]);
    }
  }
  mx_bvh4_node *W = &S->wide[w];
  memset(W, 0, sizeof *W);
  for (int j = 0; j < 4; j++) {
    W->child[j] = child[j];
    W->count[j] = count[j];
    const double *o = j < m ? obb + 15 * (size_t)e[j] : NULL;
    for (int r = 0; r < 3; r++) {
      W->c[r][j] = o ? (float)o[r] : 0.0f;
      W->a[r][j] = o ? (float)o[3 + r] : 0.0f;
      W->a[3 + r][j] = o ? (float)o[6 + r] : 0.0f;
      W->h[r][j] = o ? round_up(o[12 + r]) : -INFINITY;
    }
  }
  return w;
}

int mx_index_wide_tree(mx_surface_index *S) {
  double *obb = NULL;
  uint8_t *pack_count = mx_alloc((size_t)S->nnodes / 2 + 1);
  if (!pack_count) return MX_ENOMEM;
  const int st = node_obbs(S, &obb);
  if (st != MX_OK) {
    mx_free(pack_count);
    return st;
  }
  collapse(S, obb, pack_count, 0);
  fill_packs(S, pack_count);
  mx_free(obb);
  mx_free(pack_count);
  return MX_OK;
}

/* The hint grid: about HINT_PER_TRI cells per triangle, cells about
 * cubic, each holding the triangle closest to its centre. */
#define HINT_PER_TRI 0.5
int mx_index_hints(mx_surface_index *S) {
  if (!(S->coord_max < 1e15 && S->coord_max > 1e-15)) return MX_OK;
  const mx_bvh_node *R = &S->nodes[0];
  double ext[3], vol = 1.0;
  for (int a = 0; a < 3; a++) {
    ext[a] = mx_max(R->hi[a] - R->lo[a], 1e-30 * (1.0 + S->coord_max));
    vol *= ext[a];
  }
  const double cells = mx_max(1.0, mx_min(HINT_PER_TRI * S->nt, 65536.0));
  const double h = cbrt(vol / cells);
  size_t total = 1;
  for (int a = 0; a < 3; a++) {
    double n = ceil(ext[a] / h);
    if (!(n >= 1.0)) n = 1.0;
    if (n > 1024.0) n = 1024.0;
    S->hint_n[a] = (int)n;
    S->hint_lo[a] = R->lo[a];
    S->hint_inv[a] = n / ext[a];
    total *= (size_t)S->hint_n[a];
  }
  uint32_t *hint = mx_alloc(total * sizeof *hint);
  if (!hint) return MX_ENOMEM;
#pragma omp parallel for schedule(dynamic, 256) if (total > 1000)
  for (size_t c = 0; c < total; c++) {
    const size_t i = c % (size_t)S->hint_n[0],
                 j = c / (size_t)S->hint_n[0] % (size_t)S->hint_n[1],
                 k = c / ((size_t)S->hint_n[0] * (size_t)S->hint_n[1]);
    const double p[3] = {S->hint_lo[0] + (i + 0.5) / S->hint_inv[0],
                         S->hint_lo[1] + (j + 0.5) / S->hint_inv[1],
                         S->hint_lo[2] + (k + 0.5) / S->hint_inv[2]};
    double q[3];
    uint32_t slot = 0;
    int f;
    mx_index_closest_slot(S, p, q, &slot, &f, INFINITY);
    hint[c] = slot;
  }
  S->hint = hint;
  return MX_OK;
}
