/* Distance, signed distance, winding number and inside/outside: see
 * distance.h for the methods and the orientation rule. */
#include "geom/distance.h"

#include "base/common.h"
#include "base/scan.h"
#include "geom/surface_topology.h"

#include <math.h>
#include <string.h>

#define LEAF_MAX 4
#define STACK_MAX 64          /* > depth of a BVH of 2^30 triangles + 1 */
#define TASK_MIN 16384        /* subtrees at least this big become tasks */
#define NO_CAP UINT32_MAX     /* cap_cnt of a node without a usable cap */
#define FOUR_PI 12.566370614359172953850573533118

/* ------------------------------------------------------------------------ */
/* Small vector helpers. */

static inline double dot3(const double a[3], const double b[3]) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}
static inline void sub3(const double a[3], const double b[3], double r[3]) {
  r[0] = a[0] - b[0];
  r[1] = a[1] - b[1];
  r[2] = a[2] - b[2];
}
static inline void cross3(const double a[3], const double b[3], double r[3]) {
  r[0] = a[1] * b[2] - a[2] * b[1];
  r[1] = a[2] * b[0] - a[0] * b[2];
  r[2] = a[0] * b[1] - a[1] * b[0];
}

/* Signed solid angle of the triangle (a, b, c) seen from p (van Oosterom &
 * Strackee): positive when p is behind the triangle, i.e. on the side
 * opposite to the normal (b - a) x (c - a). Exactly coplanar: 0. */
static inline double solid_angle(const double p[3], const double a[3],
                                 const double b[3], const double c[3]) {
  double u[3], v[3], w[3];
  sub3(a, p, u);
  sub3(b, p, v);
  sub3(c, p, w);
  const double lu = sqrt(dot3(u, u)), lv = sqrt(dot3(v, v)),
               lw = sqrt(dot3(w, w));
  double vw[3];
  cross3(v, w, vw);
  const double det = dot3(u, vw);
  if (det == 0.0) return 0.0;
  const double den =
      lu * lv * lw + dot3(u, v) * lw + dot3(v, w) * lu + dot3(w, u) * lv;
  return 2.0 * atan2(det, den);
}

/* Closest point of p on the segment a + t (b - a), t in [0, 1]; returns
 * the squared distance and sets *where to -1 (at a), 1 (at b) or 0. */
static inline double closest_on_segment(const double p[3], const double a[3],
                                        const double b[3], double q[3],
                                        int *where) {
  double ab[3], ap[3];
  sub3(b, a, ab);
  sub3(p, a, ap);
  const double l2 = dot3(ab, ab), s = dot3(ab, ap);
  double t;
  if (!(l2 > 0.0) || s <= 0.0) {
    t = 0.0;
    *where = -1;
  } else if (s >= l2) {
    t = 1.0;
    *where = 1;
  } else {
    t = s / l2;
    *where = 0;
  }
  for (int i = 0; i < 3; i++) q[i] = (t == 1.0) ? b[i] : a[i] + t * ab[i];
  double d[3];
  sub3(p, q, d);
  return dot3(d, d);
}

/* Closest point q of p on the triangle t = (a, b, c) (9 doubles), by the
 * Voronoi regions of its vertices, edges and face, decided with the
 * barycentric-coordinate signs of the projections; returns |p - q|^2 and the
 * MX_FEATURE_* code. */
static inline double closest_on_triangle(const double *t, const double p[3],
                                         double q[3], int *feat) {
  const double *a = t, *b = t + 3, *c = t + 6;
  double ab[3], ac[3], ap[3], d[3];
  sub3(b, a, ab);
  sub3(c, a, ac);
  sub3(p, a, ap);
  const double d1 = dot3(ab, ap), d2 = dot3(ac, ap);
  if (d1 <= 0.0 && d2 <= 0.0) { /* behind a along both edges */
    memcpy(q, a, 3 * sizeof *q);
    *feat = MX_FEATURE_VERTEX + 0;
    return dot3(ap, ap);
  }
  double bp[3];
  sub3(p, b, bp);
  const double d3 = dot3(ab, bp), d4 = dot3(ac, bp);
  if (d3 >= 0.0 && d4 <= d3) {
    memcpy(q, b, 3 * sizeof *q);
    *feat = MX_FEATURE_VERTEX + 1;
    return dot3(bp, bp);
  }
  const double vc = d1 * d4 - d3 * d2; /* area coordinate of c */
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {
    const double den = d1 - d3, s = den > 0.0 ? d1 / den : 0.0;
    for (int i = 0; i < 3; i++) q[i] = a[i] + s * ab[i];
    *feat = MX_FEATURE_EDGE + 0;
    sub3(p, q, d);
    return dot3(d, d);
  }
  double cp[3];
  sub3(p, c, cp);
  const double d5 = dot3(ab, cp), d6 = dot3(ac, cp);
  if (d6 >= 0.0 && d5 <= d6) {
    memcpy(q, c, 3 * sizeof *q);
    *feat = MX_FEATURE_VERTEX + 2;
    return dot3(cp, cp);
  }
  const double vb = d5 * d2 - d1 * d6; /* area coordinate of b */
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {
    const double den = d2 - d6, s = den > 0.0 ? d2 / den : 0.0;
    for (int i = 0; i < 3; i++) q[i] = a[i] + s * ac[i];
    *feat = MX_FEATURE_EDGE + 2;
    sub3(p, q, d);
    return dot3(d, d);
  }
  const double va = d3 * d6 - d5 * d4; /* area coordinate of a */
  const double e43 = d4 - d3, e56 = d5 - d6;
  if (va <= 0.0 && e43 >= 0.0 && e56 >= 0.0) {
    const double den = e43 + e56, s = den > 0.0 ? e43 / den : 0.0;
    for (int i = 0; i < 3; i++) q[i] = b[i] + s * (c[i] - b[i]);
    *feat = MX_FEATURE_EDGE + 1;
    sub3(p, q, d);
    return dot3(d, d);
  }
  const double den = va + vb + vc;
  if (den > 0.0) {
    const double v = vb / den, w = vc / den;
    for (int i = 0; i < 3; i++) q[i] = a[i] + v * ab[i] + w * ac[i];
    *feat = MX_FEATURE_FACE;
    sub3(p, q, d);
    return dot3(d, d);
  }
  /* Degenerate (zero-area) triangle: the best of its three edges. */
  double best = INFINITY;
  for (int k = 0; k < 3; k++) {
    double qk[3];
    int where;
    const double dk =
        closest_on_segment(p, t + 3 * k, t + 3 * ((k + 1) % 3), qk, &where);
    if (dk < best) {
      best = dk;
      memcpy(q, qk, sizeof qk);
      *feat = where == 0    ? MX_FEATURE_EDGE + k
              : where < 0   ? MX_FEATURE_VERTEX + k
                            : MX_FEATURE_VERTEX + (k + 1) % 3;
    }
  }
  return best;
}

static inline int box_outside(const mx_bvh_node *N, const double p[3]) {
  return p[0] < N->lo[0] || p[0] > N->hi[0] || p[1] < N->lo[1] ||
         p[1] > N->hi[1] || p[2] < N->lo[2] || p[2] > N->hi[2];
}

/* Single precision, rounded up (half extents of the float boxes). */
static inline float fmax_f(float a, float b) { return a > b ? a : b; }
static inline float round_up(double x) {
  float f = (float)x;
  if ((double)f < x) f = nextafterf(f, INFINITY);
  return f;
}

/* ------------------------------------------------------------------------ */
/* BVH build. */

/* Leaves of a subtree of m >= 1 triangles (a node of more than LEAF_MAX
 * gives floor(m/2) to the left child, the rest to the right); returns L(m)
 * and sets *next to L(m + 1), carried together so the recursion is a
 * chain of log2(m) calls. */
static size_t leaf_pair(size_t m, size_t *next) {
  if (m + 1 <= LEAF_MAX) {
    *next = 1;
    return 1;
  }
  if (m <= LEAF_MAX) { /* m == LEAF_MAX: m + 1 splits once more */
    size_t a, b;
    a = leaf_pair((m + 1) / 2, &b);
    *next = (m + 1) % 2 ? a + b : 2 * a;
    return 1;
  }
  size_t a, b; /* L(k), L(k + 1) */
  const size_t k = m / 2;
  a = leaf_pair(k, &b);
  if (m % 2 == 0) {
    *next = a + b;
    return 2 * a;
  }
  *next = 2 * b;
  return a + b;
}

static size_t node_count(size_t m) {
  size_t next;
  return 2 * leaf_pair(m, &next) - 1;
}

/* Reorders a[0..n) so that a[k] holds the element of rank k by key[a[.]],
 * smaller keys before, larger after (Hoare partitions, median of three). */
static void select_nth(uint32_t *a, int64_t n, int64_t k, const double *key) {
  int64_t lo = 0, hi = n - 1;
  while (hi > lo) {
    const int64_t mid = lo + (hi - lo) / 2;
    double x0 = key[a[lo]], x1 = key[a[mid]], x2 = key[a[hi]];
    const double x = mx_max(mx_min(x0, x1), mx_min(mx_max(x0, x1), x2));
    int64_t i = lo, j = hi;
    while (i <= j) {
      while (key[a[i]] < x) i++;
      while (key[a[j]] > x) j--;
      if (i <= j) {
        const uint32_t t = a[i];
        a[i] = a[j];
        a[j] = t;
        i++;
        j--;
      }
    }
    if (k <= j)
      hi = j;
    else if (k >= i)
      lo = i;
    else
      return;
  }
}

typedef struct {
  mx_surface_index *S;
  uint32_t *idx;      /* slot -> local triangle (soup triangle - t0) */
  const double *cen;  /* 3 nt centroids, SoA: cen[a * nt + t] */
} build_ctx;

static void build_node(const build_ctx *B, uint32_t node, uint32_t first,
                       uint32_t m, uint32_t base) {
  mx_surface_index *S = B->S;
  const mx_trisoup *s = S->soup;
  const double *co[3] = {s->x, s->y, s->z};
  mx_bvh_node *N = &S->nodes[node];
  double clo[3] = {INFINITY, INFINITY, INFINITY},
         chi[3] = {-INFINITY, -INFINITY, -INFINITY};
  for (int a = 0; a < 3; a++) {
    N->lo[a] = INFINITY;
    N->hi[a] = -INFINITY;
  }
  for (uint32_t i = first; i < first + m; i++) {
    const uint32_t t = B->idx[i];
    const uint32_t *v = s->tri + 3 * ((size_t)S->t0 + t);
    for (int a = 0; a < 3; a++) {
      for (int k = 0; k < 3; k++) {
        N->lo[a] = mx_min(N->lo[a], co[a][v[k]]);
        N->hi[a] = mx_max(N->hi[a], co[a][v[k]]);
      }
      const double c = B->cen[(size_t)a * S->nt + t];
      clo[a] = mx_min(clo[a], c);
      chi[a] = mx_max(chi[a], c);
    }
  }
  N->ntri = m;
  N->pad_ = 0;
  if (m <= LEAF_MAX) {
    N->first = first;
    N->count = m;
    return;
  }
  int axis = 0;
  for (int a = 1; a < 3; a++)
    if (chi[a] - clo[a] > chi[axis] - clo[axis]) axis = a;
  const uint32_t ml = m / 2;
  select_nth(B->idx + first, m, ml, B->cen + (size_t)axis * S->nt);
  N->first = base;
  N->count = 0;
  const uint32_t lbase = base + 2;
  const uint32_t rbase = lbase + (uint32_t)(node_count(ml) - 1);
#pragma omp task if (m >= TASK_MIN) default(none) firstprivate(B, base, first, ml, lbase)
  build_node(B, base, first, ml, lbase);
  build_node(B, base + 1, first + ml, m - ml, rbase);
}

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
    return MX_EINPUT;
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

/* ------------------------------------------------------------------------ */
/* Queries. */

/* Sorting keys: the bits of a non-negative float (ordered as the floats)
 * above a lane number. */
static inline uint64_t lane_key(float d, int lane) {
  uint32_t u;
  memcpy(&u, &d, sizeof u);
  return (uint64_t)u << 32 | (uint32_t)lane;
}
static inline float key_value(uint64_t k) {
  const uint32_t u = (uint32_t)(k >> 32);
  float d;
  memcpy(&d, &u, sizeof d);
  return d;
}
static inline void order2(uint64_t *a, uint64_t *b) {
  const uint64_t x = *a, y = *b;
  *a = x > y ? x : y;
  *b = x > y ? y : x;
}
/* Four keys in decreasing order, without branches. */
static inline void sort4_down(uint64_t k[4]) {
  order2(&k[0], &k[1]);
  order2(&k[2], &k[3]);
  order2(&k[0], &k[2]);
  order2(&k[1], &k[3]);
  order2(&k[1], &k[2]);
}

/* Closest point over all triangles: squared distance, slot and feature.
 * Descends the 4-wide BVH, nearest child first. A subtree or a triangle is
 * skipped when a lower bound of its squared distance, computed in single
 * precision (float boxes, leaf packs), is not below thr = (best + delta)^2,
 * best the smallest exact distance so far and delta a rounding allowance,
 * 2^-17 of the coordinates' magnitude, far above the float errors; the
 * exact test runs in double. */
double mx_closest_on_triangle(const double t[9], const double p[3], double q[3]) {
  int feat;
  return closest_on_triangle(t, p, q, &feat);
}

static double closest_slot(const mx_surface_index *S, const double p[3],
                           double q[3], uint32_t *slot, int *feat, double rmax) {
  double best = INFINITY, thr = INFINITY;
  if (!S->nt) return best;
  const double pm = mx_max(fabs(p[0]), mx_max(fabs(p[1]), fabs(p[2])));
  if (!(pm + S->coord_max < 1e15 && S->coord_max > 1e-15)) {
    /* Beyond the range where the float bounds (squared distances) are safe,
     * or NaN: every triangle. */
    for (uint32_t i = 0; i < S->nt; i++) {
      double qi[3];
      int f = MX_FEATURE_FACE;
      const double e = closest_on_triangle(S->tv + 9 * (size_t)i, p, qi, &f);
      if (e < best || i == 0) {
        best = e;
        memcpy(q, qi, sizeof qi);
        *slot = i;
        *feat = f;
      }
    }
    return best;
  }
  const double delta = 0x1p-17 * (pm + S->coord_max);
  const float px = (float)p[0], py = (float)p[1], pz = (float)p[2];
  if (S->hint) {
    size_t cell = 0;
    for (int a = 2; a >= 0; a--) {
      const double f = (p[a] - S->hint_lo[a]) * S->hint_inv[a];
      const int n = S->hint_n[a];
      const int c = !(f > 0.0) ? 0 : f >= n - 1 ? n - 1 : (int)f;
      cell = cell * (size_t)n + (size_t)c;
    }
    const uint32_t i = S->hint[cell];
    int f = MX_FEATURE_FACE;
    best = closest_on_triangle(S->tv + 9 * (size_t)i, p, q, &f);
    const double r = sqrt(best) + delta;
    thr = r * r;
    *slot = i;
    *feat = f;
    if (best == 0.0) return best;
  }
  if (rmax < INFINITY) { /* only a point within rmax is wanted */
    const double r = rmax + delta;
    thr = fmin(thr, r * r);
  }
  uint32_t stack[4 * STACK_MAX];
  uint8_t scnt[4 * STACK_MAX];
  float sd[4 * STACK_MAX];
  int sp = 0;
  stack[sp] = 0;
  scnt[sp] = 0;
  sd[sp++] = 0.0f;
  while (sp) {
    sp--;
    if (!(sd[sp] < thr)) continue;
    const uint32_t idx = stack[sp];
    const int cnt = scnt[sp];
    float d[4];
    uint64_t k[4];
    if (cnt) { /* a leaf: pack idx, lanes 0 .. cnt-1 */
      const mx_leaf_pack *P = &S->packs[idx];
#pragma omp simd
      for (int l = 0; l < 4; l++) {
        const float h = P->v[0][l] * px + P->v[1][l] * py + P->v[2][l] * pz -
                        P->v[3][l];
        const float g0 = P->v[4][l] * px + P->v[5][l] * py +
                         P->v[6][l] * pz - P->v[7][l];
        const float g1 = P->v[8][l] * px + P->v[9][l] * py +
                         P->v[10][l] * pz - P->v[11][l];
        const float g2 = P->v[12][l] * px + P->v[13][l] * py +
                         P->v[14][l] * pz - P->v[15][l];
        const float g = fmax_f(fmax_f(g0, g1), fmax_f(g2, 0.0f));
        d[l] = h * h + g * g;
      }
      for (int l = 0; l < 4; l++)
        k[l] = lane_key(l < cnt ? d[l] : INFINITY, l);
      sort4_down(k);
      const uint32_t first = S->leaf_first[idx];
      for (int j = 3; j >= 0 && key_value(k[j]) < thr; j--) {
        const uint32_t i = first + (uint32_t)k[j];
        double qi[3];
        int f = MX_FEATURE_FACE;
        const double e = closest_on_triangle(S->tv + 9 * (size_t)i, p, qi, &f);
        if (e < best) {
          best = e;
          const double r = sqrt(e) + delta;
          thr = r * r;
          memcpy(q, qi, sizeof qi);
          *slot = i;
          *feat = f;
        }
      }
      if (best == 0.0) break;
      continue;
    }
    const mx_bvh4_node *W = &S->wide[idx];
#pragma omp simd
    for (int c = 0; c < 4; c++) {
      const float dx = px - W->c[0][c], dy = py - W->c[1][c],
                  dz = pz - W->c[2][c];
      const float ux = W->a[0][c], uy = W->a[1][c], uz = W->a[2][c];
      const float vx = W->a[3][c], vy = W->a[4][c], vz = W->a[5][c];
      const float wx = uy * vz - uz * vy, wy = uz * vx - ux * vz,
                  wz = ux * vy - uy * vx;
      /* excess over the half extents; max(x, 0) = (x + |x|) / 2 exactly,
       * written so that the loop vectorizes */
      const float x0 = fabsf(ux * dx + uy * dy + uz * dz) - W->h[0][c];
      const float x1 = fabsf(vx * dx + vy * dy + vz * dz) - W->h[1][c];
      const float x2 = fabsf(wx * dx + wy * dy + wz * dz) - W->h[2][c];
      const float e0 = 0.5f * (x0 + fabsf(x0)), e1 = 0.5f * (x1 + fabsf(x1)),
                  e2 = 0.5f * (x2 + fabsf(x2));
      d[c] = e0 * e0 + e1 * e1 + e2 * e2;
    }
    for (int c = 0; c < 4; c++) k[c] = lane_key(d[c], c);
    sort4_down(k);
    /* Push the children within the bound, farthest first, so that the
     * nearest is popped next (unused children have infinite distance). */
    for (int j = 0; j < 4; j++) {
      const int c = (int)(uint32_t)k[j];
      stack[sp] = W->child[c];
      scnt[sp] = W->count[c];
      sd[sp] = d[c];
      sp += d[c] < thr;
    }
  }
  return best;
}

double mx_closest_point(const mx_surface_index *S, const double p[3],
                        double q[3], uint32_t *tri, int *feature) {
  double qq[3] = {INFINITY, INFINITY, INFINITY};
  uint32_t slot = 0;
  int f = MX_FEATURE_FACE;
  const double d2 = closest_slot(S, p, qq, &slot, &f, INFINITY);
  if (q) memcpy(q, qq, sizeof qq);
  if (tri) *tri = S->nt ? S->tri_id[slot] : UINT32_MAX;
  if (feature) *feature = f;
  return sqrt(d2);
}

double mx_closest_point_within(const mx_surface_index *S, const double p[3],
                               double rmax, double q[3]) {
  double qq[3] = {INFINITY, INFINITY, INFINITY};
  uint32_t slot = 0;
  int f = MX_FEATURE_FACE;
  const double d2 = closest_slot(S, p, qq, &slot, &f, rmax);
  if (q) memcpy(q, qq, sizeof qq);
  return sqrt(d2);
}

/* Winding number with per-slot signs ssign and cap weights capw; the slot
 * `skip` is left out (UINT32_MAX: none). Nodes whose box does not contain p
 * and that have a cap contribute through it. */
static double winding(const mx_surface_index *S, const double p[3],
                      const int8_t *ssign, const int32_t *capw,
                      uint32_t skip) {
  if (!S->nt) return 0.0;
  const mx_trisoup *s = S->soup;
  uint32_t stack[STACK_MAX];
  int sp = 0;
  stack[sp++] = 0;
  double sum = 0.0;
  while (sp) {
    const uint32_t n = stack[--sp];
    const mx_bvh_node *N = &S->nodes[n];
    if (N->count) {
      for (uint32_t i = N->first; i < N->first + N->count; i++) {
        if (i == skip) continue;
        const double *t = S->tv + 9 * (size_t)i;
        sum += ssign[i] * solid_angle(p, t, t + 3, t + 6);
      }
      continue;
    }
    if (S->cap_cnt[n] != NO_CAP && box_outside(N, p)) {
      const double o[3] = {0.5 * (N->lo[0] + N->hi[0]),
                           0.5 * (N->lo[1] + N->hi[1]),
                           0.5 * (N->lo[2] + N->hi[2])};
      const uint64_t j0 = S->cap_off[n], j1 = j0 + S->cap_cnt[n];
      for (uint64_t j = j0; j < j1; j++) {
        const uint32_t u = S->cap_u[j], v = S->cap_v[j];
        const double a[3] = {s->x[u], s->y[u], s->z[u]};
        const double b[3] = {s->x[v], s->y[v], s->z[v]};
        sum += capw[j] * solid_angle(p, o, a, b);
      }
      continue;
    }
    stack[sp++] = N->first;
    stack[sp++] = N->first + 1;
  }
  return sum / FOUR_PI;
}

double mx_winding_number(const mx_surface_index *S, const double p[3]) {
  return winding(S, p, S->tsign, S->cap_w, UINT32_MAX);
}

double mx_winding_number_direct(const mx_surface_index *S, const double p[3]) {
  double sum = 0.0;
  for (uint32_t i = 0; i < S->nt; i++) {
    const double *t = S->tv + 9 * (size_t)i;
    sum += S->tsign[i] * solid_angle(p, t, t + 3, t + 6);
  }
  return sum / FOUR_PI;
}

static const double *pseudonormal(const mx_surface_index *S, uint32_t slot,
                                  int feat) {
  if (feat == MX_FEATURE_FACE) return S->fn + 3 * (size_t)slot;
  if (feat < MX_FEATURE_VERTEX)
    return S->en + 9 * (size_t)slot + 3 * (size_t)(feat - MX_FEATURE_EDGE);
  const uint32_t v =
      S->soup->tri[3 * (size_t)S->tri_id[slot] + (feat - MX_FEATURE_VERTEX)];
  return S->vn + 3 * (size_t)v;
}

double mx_signed_distance(const mx_surface_index *S, const double p[3],
                          double q[3]) {
  double qq[3] = {INFINITY, INFINITY, INFINITY};
  uint32_t slot = 0;
  int f = MX_FEATURE_FACE;
  const double d2 = closest_slot(S, p, qq, &slot, &f, INFINITY);
  if (q) memcpy(q, qq, sizeof qq);
  if (d2 == 0.0) return 0.0;
  const double d = sqrt(d2);
  if (S->side) return mx_winding_number(S->side, p) > 0.5 ? -d : d;
  if (!S->nt) return d;
  if (S->closed) {
    const double *n = pseudonormal(S, slot, f);
    double r[3];
    sub3(p, qq, r);
    const double g = dot3(r, n);
    if (g > 0.0) return d;
    if (g < 0.0) return -d;
  }
  return mx_winding_number(S, p) > 0.5 ? -d : d;
}

int mx_inside(const mx_surface_index *S, const double p[3]) {
  if (S->side) return mx_winding_number(S->side, p) > 0.5;
  if (!S->closed) return mx_winding_number(S, p) > 0.5;
  return mx_signed_distance(S, p, NULL) <= 0.0;
}

/* ------------------------------------------------------------------------ */
/* Build: edges, shells, orientation, caps, pseudonormals. */

void mx_surface_index_free(mx_surface_index *S) {
  mx_free(S->nodes);
  mx_free(S->wide);
  mx_free(S->tri_id);
  mx_free(S->tv);
  mx_free(S->shell_of);
  mx_free(S->tsign);
  mx_free(S->packs);
  mx_free(S->hint);
  mx_free(S->leaf_first);
  mx_free(S->fn);
  mx_free(S->en);
  mx_free(S->vn);
  mx_free(S->cap_off);
  mx_free(S->cap_cnt);
  mx_free(S->cap_u);
  mx_free(S->cap_v);
  mx_free(S->cap_w);
  memset(S, 0, sizeof *S);
}

/* Vertex k of slot i and the next one around the triangle. */
static inline void slot_edge(const mx_surface_index *S, uint32_t i, int k,
                             uint32_t *va, uint32_t *vb) {
  const uint32_t *v = S->soup->tri + 3 * (size_t)S->tri_id[i];
  *va = v[k];
  *vb = v[(k + 1) % 3];
}

/* Growable list of boundary entries: key (lo << 32 | hi), weight (+w:
 * lo -> hi, -w: hi -> lo) and shell. */
typedef struct {
  uint64_t *k;
  int32_t *w;
  uint32_t *c;
  size_t n, cap;
} edge_list;

static int edge_list_reserve(edge_list *L, size_t n) {
  if (n <= L->cap) return MX_OK;
  size_t cap = L->cap ? L->cap : 256;
  while (cap < n) cap *= 2;
  uint64_t *k = mx_realloc(L->k, cap * sizeof *k);
  if (!k) return MX_EINPUT;
  L->k = k;
  int32_t *w = mx_realloc(L->w, cap * sizeof *w);
  if (!w) return MX_EINPUT;
  L->w = w;
  uint32_t *c = mx_realloc(L->c, cap * sizeof *c);
  if (!c) return MX_EINPUT;
  L->c = c;
  L->cap = cap;
  return MX_OK;
}

static void edge_list_free(edge_list *L) {
  mx_free(L->k);
  mx_free(L->w);
  mx_free(L->c);
}

typedef struct {
  mx_surface_index *S;
  const uint8_t *fix;
  edge_list scr;  /* lists of the nodes on the current path */
  edge_list keep; /* the caps kept */
  size_t budget;  /* at most this many entries kept */
} cap_ctx;

/* Boundary of node b, appended to the scratch list (sorted by key): a
 * leaf's from its triangles, an internal node's by merging its children's,
 * which it then replaces. Kept as the node's cap when it has at most half
 * as many edges as the node has triangles (and the budget allows). */
static int cap_node(cap_ctx *X, uint32_t b) {
  mx_surface_index *S = X->S;
  const mx_bvh_node *N = &S->nodes[b];
  edge_list *L = &X->scr;
  S->cap_cnt[b] = NO_CAP;
  S->cap_off[b] = 0;
  if (N->count) {
    MX_CHECK(edge_list_reserve(L, L->n + 3 * LEAF_MAX));
    const size_t s0 = L->n;
    uint64_t k[3 * LEAF_MAX];
    int32_t w[3 * LEAF_MAX];
    uint32_t c[3 * LEAF_MAX];
    int m = 0;
    for (uint32_t i = N->first; i < N->first + N->count; i++)
      for (int e = 0; e < 3; e++) {
        uint32_t a, bb;
        slot_edge(S, i, e, &a, &bb);
        if (a == bb) continue;
        const int up = (a < bb) ^ X->fix[i];
        const uint64_t key =
            a < bb ? (uint64_t)a << 32 | bb : (uint64_t)bb << 32 | a;
        int j = m++; /* insertion sort */
        while (j > 0 && k[j - 1] > key) {
          k[j] = k[j - 1];
          w[j] = w[j - 1];
          c[j] = c[j - 1];
          j--;
        }
        k[j] = key;
        w[j] = up ? 1 : -1;
        c[j] = S->shell_of[i];
      }
    size_t o = s0;
    for (int j = 0; j < m;) {
      int32_t sw = 0;
      int j2 = j;
      while (j2 < m && k[j2] == k[j]) sw += w[j2++];
      if (sw) {
        L->k[o] = k[j];
        L->w[o] = sw;
        L->c[o++] = c[j];
      }
      j = j2;
    }
    L->n = o;
    return MX_OK;
  }
  const size_t s0 = L->n;
  MX_CHECK(cap_node(X, N->first));
  const size_t s1 = L->n;
  MX_CHECK(cap_node(X, N->first + 1));
  const size_t s2 = L->n;
  MX_CHECK(edge_list_reserve(L, s2 + (s2 - s0)));
  size_t i = s0, j = s1, o = s2;
  while (i < s1 || j < s2) {
    if (j >= s2 || (i < s1 && L->k[i] < L->k[j])) {
      L->k[o] = L->k[i];
      L->w[o] = L->w[i];
      L->c[o++] = L->c[i++];
    } else if (i >= s1 || L->k[j] < L->k[i]) {
      L->k[o] = L->k[j];
      L->w[o] = L->w[j];
      L->c[o++] = L->c[j++];
    } else {
      const int32_t sw = L->w[i] + L->w[j];
      if (sw) {
        L->k[o] = L->k[i];
        L->w[o] = sw;
        L->c[o++] = L->c[i];
      }
      i++;
      j++;
    }
  }
  const size_t m = o - s2;
  memmove(L->k + s0, L->k + s2, m * sizeof *L->k);
  memmove(L->w + s0, L->w + s2, m * sizeof *L->w);
  memmove(L->c + s0, L->c + s2, m * sizeof *L->c);
  L->n = s0 + m;
  if (2 * m <= N->ntri && X->keep.n + m <= X->budget) {
    edge_list *K = &X->keep;
    MX_CHECK(edge_list_reserve(K, K->n + m));
    if (m) {
      memcpy(K->k + K->n, L->k + s0, m * sizeof *K->k);
      memcpy(K->w + K->n, L->w + s0, m * sizeof *K->w);
      memcpy(K->c + K->n, L->c + s0, m * sizeof *K->c);
    }
    S->cap_off[b] = K->n;
    S->cap_cnt[b] = (uint32_t)m;
    K->n += m;
  }
  return MX_OK;
}

/* The caps of the winding number (see distance.h): boundaries in the
 * consistent orientation of each shell (before the shells' flips, which
 * orient_shells applies); cap_shell receives the shell of each entry. At
 * most 2 nt + 64 entries are kept (in a pathological surface, such as
 * disconnected triangles, nodes keep none and queries descend, still
 * exact). */
static int build_caps(mx_surface_index *S, const uint8_t *fix,
                      uint32_t **cap_shell) {
  S->cap_off = mx_alloc((size_t)S->nnodes * sizeof *S->cap_off);
  S->cap_cnt = mx_alloc((size_t)S->nnodes * sizeof *S->cap_cnt);
  if (!S->cap_off || !S->cap_cnt) return MX_EINPUT;
  cap_ctx X;
  memset(&X, 0, sizeof X);
  X.S = S;
  X.fix = fix;
  X.budget = 2 * (size_t)S->nt + 64;
  int st = cap_node(&X, 0);
  const size_t n = X.keep.n;
  S->ncap = n;
  if (st == MX_OK) {
    S->cap_u = mx_alloc(n * sizeof *S->cap_u + 4);
    S->cap_v = mx_alloc(n * sizeof *S->cap_v + 4);
    S->cap_w = mx_alloc(n * sizeof *S->cap_w + 4);
    *cap_shell = mx_alloc(n * sizeof **cap_shell + 4);
    if (!S->cap_u || !S->cap_v || !S->cap_w || !*cap_shell) st = MX_EINPUT;
  }
  if (st == MX_OK)
    for (size_t j = 0; j < n; j++) {
      S->cap_u[j] = (uint32_t)(X.keep.k[j] >> 32);
      S->cap_v[j] = (uint32_t)X.keep.k[j];
      S->cap_w[j] = X.keep.w[j];
      (*cap_shell)[j] = X.keep.c[j];
    }
  edge_list_free(&X.scr);
  edge_list_free(&X.keep);
  return st;
}

/* Orientation of the shells (see distance.h): seeds' centroids, signed
 * volumes, nesting depths by the winding number, then the final signs. */
static int orient_shells(mx_surface_index *S, const uint8_t *fix,
                         const uint32_t *seed, const uint32_t *cap_shell, int given) {
  const uint32_t nt = S->nt, nc = S->nshells;
  const size_t ncap = S->ncap;
  double *rep = mx_alloc(3 * (size_t)nc * sizeof *rep + 8);
  double *vol = mx_calloc((size_t)nc * sizeof *vol + 8);
  int8_t *csign = mx_alloc((size_t)nc + 8);
  int8_t *ssign = mx_alloc((size_t)nt + 8);
  int32_t *capw = mx_alloc(ncap * sizeof *capw + 4);
  size_t *nflip = mx_calloc((size_t)nc * sizeof *nflip + 8);
  size_t *nsize = mx_calloc((size_t)nc * sizeof *nsize + 8);
  double *box = given ? mx_alloc(6 * (size_t)nc * sizeof *box + 8) : NULL;
  if (!rep || !vol || !csign || !ssign || !capw || !nflip || !nsize || (given && !box)) {
    mx_free(box);
    mx_free(rep);
    mx_free(vol);
    mx_free(csign);
    mx_free(ssign);
    mx_free(capw);
    mx_free(nflip);
    mx_free(nsize);
    return MX_EINPUT;
  }
  /* A point of each shell: the centroid of its seed triangle, clamped to
   * the triangle's box so that the BVH descends to the triangle; as given:
   * the centre of the shell's box (the same for any order of its
   * triangles). */
  for (uint32_t c = 0; c < nc; c++) {
    const double *t = S->tv + 9 * (size_t)seed[c];
    for (int a = 0; a < 3; a++) {
      const double lo = mx_min(t[a], mx_min(t[3 + a], t[6 + a]));
      const double hi = mx_max(t[a], mx_max(t[3 + a], t[6 + a]));
      rep[3 * c + a] = mx_min(hi, mx_max(lo, (t[a] + t[3 + a] + t[6 + a]) / 3.0));
    }
  }
  if (given) {
    for (uint32_t c = 0; c < nc; c++)
      for (int a = 0; a < 3; a++) {
        box[6 * c + a] = INFINITY;
        box[6 * c + 3 + a] = -INFINITY;
      }
    for (uint32_t i = 0; i < nt; i++) {
      double *b = box + 6 * (size_t)S->shell_of[i];
      for (int k = 0; k < 9; k++) {
        b[k % 3] = mx_min(b[k % 3], S->tv[9 * (size_t)i + k]);
        b[3 + k % 3] = mx_max(b[3 + k % 3], S->tv[9 * (size_t)i + k]);
      }
    }
    for (uint32_t c = 0; c < nc; c++)
      for (int a = 0; a < 3; a++) rep[3 * c + a] = 0.5 * (box[6 * c + a] + box[6 * c + 3 + a]);
    mx_free(box);
  }
  /* Signed volumes (6 times), relative to the shell's point. */
  for (uint32_t i = 0; i < nt; i++) {
    const uint32_t c = S->shell_of[i];
    const double *t = S->tv + 9 * (size_t)i, *o = rep + 3 * c;
    double a[3], b[3], d[3], bd[3];
    sub3(t, o, a);
    sub3(t + 3, o, b);
    sub3(t + 6, o, d);
    cross3(b, d, bd);
    const double v = dot3(a, bd);
    vol[c] += fix[i] ? -v : v;
  }
  for (uint32_t c = 0; c < nc; c++) csign[c] = vol[c] < 0.0 ? -1 : 1;
  if (given) {
    /* the way that keeps most triangles as given; ties: outward */
    for (uint32_t i = 0; i < nt; i++) {
      nsize[S->shell_of[i]]++;
      nflip[S->shell_of[i]] += fix[i];
    }
    for (uint32_t c = 0; c < nc; c++)
      if (2 * nflip[c] != nsize[c]) csign[c] = 2 * nflip[c] > nsize[c] ? -1 : 1;
    memset(nflip, 0, (size_t)nc * sizeof *nflip);
    memset(nsize, 0, (size_t)nc * sizeof *nsize);
  }
  /* Every shell outward, then the nesting depth of each. */
  for (uint32_t i = 0; i < nt; i++)
    ssign[i] = (int8_t)((fix[i] ? -1 : 1) * csign[S->shell_of[i]]);
  for (size_t j = 0; j < ncap; j++) capw[j] = S->cap_w[j] * csign[cap_shell[j]];
  if (nc > 1 && !given) {
#pragma omp parallel for schedule(dynamic, 1) if (nc > 8)
    for (uint32_t c = 0; c < nc; c++) {
      const double w = winding(S, rep + 3 * c, ssign, capw, seed[c]);
      /* w = depth + 1/2 */
      long depth = lround(w - 0.5);
      if (depth < 0) depth = 0;
      if (depth % 2) csign[c] = (int8_t)-csign[c];
    }
  }
  for (uint32_t i = 0; i < nt; i++) {
    const uint32_t c = S->shell_of[i];
    S->tsign[i] = (int8_t)((fix[i] ? -1 : 1) * csign[c]);
    nsize[c]++;
    if (S->tsign[i] < 0) nflip[c]++;
  }
  for (size_t j = 0; j < ncap; j++) S->cap_w[j] *= csign[cap_shell[j]];
  S->nflipped = 0;
  S->nreoriented = 0;
  for (uint32_t c = 0; c < nc; c++) {
    if (2 * nflip[c] > nsize[c]) {
      S->nflipped++;
      S->nreoriented += nsize[c] - nflip[c];
    } else {
      S->nreoriented += nflip[c];
    }
  }
  mx_free(rep);
  mx_free(vol);
  mx_free(csign);
  mx_free(ssign);
  mx_free(capw);
  mx_free(nflip);
  mx_free(nsize);
  return MX_OK;
}

/* Face normals, edge pseudonormals (sum of the normals of the faces of the
 * edge), vertex pseudonormals (angle-weighted sum). */
static int pseudonormals(mx_surface_index *S, const mx_edge_table *E) {
  const uint32_t nt = S->nt;
  const size_t nv = S->soup->nv;
#pragma omp parallel for schedule(static) if (nt > 10000)
  for (uint32_t i = 0; i < nt; i++) {
    const double *t = S->tv + 9 * (size_t)i;
    double ab[3], ac[3], n[3];
    sub3(t + 3, t, ab);
    sub3(t + 6, t, ac);
    cross3(ab, ac, n);
    const double l = sqrt(dot3(n, n));
    const double f = l > 0.0 ? S->tsign[i] / l : 0.0;
    for (int a = 0; a < 3; a++) S->fn[3 * (size_t)i + a] = f * n[a];
  }
#pragma omp parallel for schedule(static) if (nt > 10000)
  for (size_t j = 0; j < E->n; j++) {
    if (j && E->key[j] == E->key[j - 1]) continue;
    const size_t end = mx_edge_run_end(E, j);
    double n[3] = {0.0, 0.0, 0.0};
    for (size_t k = j; k < end; k++) {
      const double *f = S->fn + 3 * (size_t)(E->half[k] / 3);
      for (int a = 0; a < 3; a++) n[a] += f[a];
    }
    for (size_t k = j; k < end; k++)
      memcpy(S->en + 3 * (size_t)E->half[k], n, sizeof n);
  }
  S->vn = mx_calloc(3 * nv * sizeof *S->vn + 8);
  if (!S->vn) return MX_EINPUT;
  for (uint32_t i = 0; i < nt; i++) {
    const double *t = S->tv + 9 * (size_t)i, *f = S->fn + 3 * (size_t)i;
    const uint32_t *v = S->soup->tri + 3 * (size_t)S->tri_id[i];
    for (int k = 0; k < 3; k++) {
      double u[3], w[3], uw[3];
      sub3(t + 3 * ((k + 1) % 3), t + 3 * k, u);
      sub3(t + 3 * ((k + 2) % 3), t + 3 * k, w);
      cross3(u, w, uw);
      const double angle = atan2(sqrt(dot3(uw, uw)), dot3(u, w));
      for (int a = 0; a < 3; a++) S->vn[3 * (size_t)v[k] + a] += angle * f[a];
    }
  }
  return MX_OK;
}

/* The hint grid: about HINT_PER_TRI cells per triangle, cells about
 * cubic, each holding the triangle closest to its centre. */
#define HINT_PER_TRI 0.5
static int build_hints(mx_surface_index *S) {
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
  if (!hint) return MX_EINPUT;
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
    closest_slot(S, p, q, &slot, &f, INFINITY);
    hint[c] = slot;
  }
  S->hint = hint;
  return MX_OK;
}

static int index_build(mx_surface_index *S, const mx_trisoup *soup, uint32_t t0,
                       uint32_t t1, int given) {
  memset(S, 0, sizeof *S);
  if (t0 > t1 || t1 > soup->nt) {
    mx_error(NULL, 0, "surface index: triangle range [%u, %u) outside [0, %zu)",
             t0, t1, soup->nt);
    return MX_EINPUT;
  }
  if (t1 - t0 > (1u << 30)) {
    mx_error(NULL, 0, "surface index: %u triangles, at most 2^30 supported",
             t1 - t0);
    return MX_EINPUT;
  }
  S->soup = soup;
  S->t0 = t0;
  S->t1 = t1;
  S->nt = t1 - t0;
  S->closed = 1;
  const uint32_t nt = S->nt;
  if (!nt) return MX_OK;

  /* BVH over the centroids. */
  S->nnodes = (uint32_t)node_count(nt);
  S->nodes = mx_alloc((size_t)S->nnodes * sizeof *S->nodes);
  S->tri_id = mx_alloc((size_t)nt * sizeof *S->tri_id);
  S->tv = mx_alloc(9 * (size_t)nt * sizeof *S->tv);
  S->shell_of = mx_alloc((size_t)nt * sizeof *S->shell_of);
  S->tsign = mx_alloc((size_t)nt);
  S->fn = mx_alloc(3 * (size_t)nt * sizeof *S->fn);
  S->en = mx_alloc(9 * (size_t)nt * sizeof *S->en);
  double *cen = mx_alloc(3 * (size_t)nt * sizeof *cen);
  if (!S->nodes || !S->tri_id || !S->tv || !S->shell_of || !S->tsign ||
      !S->fn || !S->en || !cen) {
    mx_free(cen);
    mx_surface_index_free(S);
    return MX_EINPUT;
  }
#pragma omp parallel for schedule(static) if (nt > 10000)
  for (uint32_t t = 0; t < nt; t++) {
    const uint32_t *v = soup->tri + 3 * ((size_t)t0 + t);
    cen[t] = (soup->x[v[0]] + soup->x[v[1]] + soup->x[v[2]]) / 3.0;
    cen[(size_t)nt + t] = (soup->y[v[0]] + soup->y[v[1]] + soup->y[v[2]]) / 3.0;
    cen[2 * (size_t)nt + t] =
        (soup->z[v[0]] + soup->z[v[1]] + soup->z[v[2]]) / 3.0;
    S->tri_id[t] = t;
  }
  build_ctx B = {S, S->tri_id, cen};
#pragma omp parallel if (nt >= TASK_MIN)
#pragma omp single
  build_node(&B, 0, 0, nt, 1);
  mx_free(cen);
  S->wide = mx_alloc(((size_t)S->nnodes / 2 + 1) * sizeof *S->wide);
  S->packs = mx_alloc(((size_t)S->nnodes / 2 + 1) * sizeof *S->packs);
  S->leaf_first = mx_alloc(((size_t)S->nnodes / 2 + 1) * sizeof *S->leaf_first);
  if (!S->wide || !S->packs || !S->leaf_first) {
    mx_surface_index_free(S);
    return MX_EINPUT;
  }
#pragma omp parallel for schedule(static) if (nt > 10000)
  for (uint32_t i = 0; i < nt; i++) {
    S->tri_id[i] += t0;
    const uint32_t *v = soup->tri + 3 * (size_t)S->tri_id[i];
    double *t = S->tv + 9 * (size_t)i;
    for (int k = 0; k < 3; k++) {
      t[3 * k] = soup->x[v[k]];
      t[3 * k + 1] = soup->y[v[k]];
      t[3 * k + 2] = soup->z[v[k]];
    }
  }
  double cm = 0.0;
  for (size_t i = 0; i < 9 * (size_t)nt; i++) cm = mx_max(cm, fabs(S->tv[i]));
  S->coord_max = cm;
  double *obb = NULL;
  uint8_t *pack_count = mx_alloc((size_t)S->nnodes / 2 + 1);
  if (!pack_count || node_obbs(S, &obb) != MX_OK) {
    mx_free(pack_count);
    mx_surface_index_free(S);
    return MX_EINPUT;
  }
  collapse(S, obb, pack_count, 0);
  fill_packs(S, pack_count);
  mx_free(obb);
  mx_free(pack_count);

  /* Edges and shells. */
  mx_edge_table E;
  memset(&E, 0, sizeof E);
  uint8_t *fix = mx_alloc((size_t)nt + 8);
  uint32_t *seed = NULL, *cap_shell = NULL;
  int st = fix ? mx_edge_table_build(&E, soup->tri, S->tri_id, nt, 0, 1) : MX_ENOMEM;
  if (st == MX_OK) {
    size_t open = 0, nonman = 0;
    for (size_t j = 0; j < E.n;) {
      const size_t end = mx_edge_run_end(&E, j);
      if (end - j != 2) open++;
      if (end - j > 2) nonman++;
      j = end;
    }
    S->open_edges = open;
    S->nonmanifold_edges = nonman;
    st = mx_surface_shells(&E, 1, S->shell_of, fix, &S->nshells, &seed,
                           &S->conflict_edges);
  }
  if (st == MX_OK) {
    S->closed = S->open_edges == 0 && S->conflict_edges == 0;
    st = build_caps(S, fix, &cap_shell);
  }
  if (st == MX_OK) st = orient_shells(S, fix, seed, cap_shell, given);
  if (given) S->closed = 0;
  if (st == MX_OK) st = pseudonormals(S, &E);
  if (st == MX_OK) st = build_hints(S);
  mx_edge_table_free(&E);
  mx_free(fix);
  mx_free(seed);
  mx_free(cap_shell);
  if (st != MX_OK) mx_surface_index_free(S);
  return st;
}

int mx_surface_index_build(mx_surface_index *S, const mx_trisoup *soup,
                           uint32_t t0, uint32_t t1) {
  return index_build(S, soup, t0, t1, 0);
}

int mx_surface_index_build_given(mx_surface_index *S, const mx_trisoup *soup,
                                 uint32_t t0, uint32_t t1) {
  return index_build(S, soup, t0, t1, 1);
}
