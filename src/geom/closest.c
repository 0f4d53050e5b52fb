/* Closest points on the surface index (geom/distance.h): on one triangle
 * (Voronoi regions), over the index (descent of the 4-wide tree, nearest
 * child first, float lower bounds, exact tests in double), the signed
 * distance and inside/outside from the pseudonormals, and the
 * pseudonormals themselves. */
#include "geom/surface_index_impl.h"

#include <string.h>

#include "base/common.h"

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

double mx_closest_on_triangle(const double t[9], const double p[3], double q[3]) {
  int feat;
  return closest_on_triangle(t, p, q, &feat);
}

/* Float lower bounds of the squared distance from (px, py, pz): to the
 * triangles of leaf pack P (its four lanes), and to the four children's
 * oriented boxes of wide node W (0 inside; unused children infinite). */
static inline void pack_bounds(const mx_leaf_pack *P, float px, float py, float pz,
                               float d[4]) {
#pragma omp simd
  for (int l = 0; l < 4; l++) {
    const float h = P->v[0][l] * px + P->v[1][l] * py + P->v[2][l] * pz - P->v[3][l];
    const float g0 = P->v[4][l] * px + P->v[5][l] * py + P->v[6][l] * pz - P->v[7][l];
    const float g1 = P->v[8][l] * px + P->v[9][l] * py + P->v[10][l] * pz - P->v[11][l];
    const float g2 = P->v[12][l] * px + P->v[13][l] * py + P->v[14][l] * pz - P->v[15][l];
    const float g = fmax_f(fmax_f(g0, g1), fmax_f(g2, 0.0f));
    d[l] = h * h + g * g;
  }
}

static inline void node_bounds(const mx_bvh4_node *W, float px, float py, float pz,
                               float d[4]) {
#pragma omp simd
  for (int c = 0; c < 4; c++) {
    const float dx = px - W->c[0][c], dy = py - W->c[1][c], dz = pz - W->c[2][c];
    const float ux = W->a[0][c], uy = W->a[1][c], uz = W->a[2][c];
    const float vx = W->a[3][c], vy = W->a[4][c], vz = W->a[5][c];
    const float wx = uy * vz - uz * vy, wy = uz * vx - ux * vz, wz = ux * vy - uy * vx;
    /* excess over the half extents; max(x, 0) = (x + |x|) / 2 exactly,
     * written so that the loop vectorizes */
    const float x0 = fabsf(ux * dx + uy * dy + uz * dz) - W->h[0][c];
    const float x1 = fabsf(vx * dx + vy * dy + vz * dz) - W->h[1][c];
    const float x2 = fabsf(wx * dx + wy * dy + wz * dz) - W->h[2][c];
    const float e0 = 0.5f * (x0 + fabsf(x0)), e1 = 0.5f * (x1 + fabsf(x1)),
                e2 = 0.5f * (x2 + fabsf(x2));
    d[c] = e0 * e0 + e1 * e1 + e2 * e2;
  }
}

/* The float bounds are safe (squared distances in float range) for points
 * of this magnitude pm (their largest coordinate) and the index's triangles;
 * there, the allowance added to a distance before comparing bounds with it
 * (far above the float errors). */
static inline int float_bounds_safe(const mx_surface_index *S, double pm) {
  return pm + S->coord_max < 1e15 && S->coord_max > 1e-15;
}
static inline double bound_allowance(const mx_surface_index *S, double pm) {
  return 0x1p-17 * (pm + S->coord_max);
}

/* The hint grid's triangle for p (the index has a grid: S->hint). */
static inline uint32_t hint_slot(const mx_surface_index *S, const double p[3]) {
  size_t cell = 0;
  for (int a = 2; a >= 0; a--) {
    const double f = (p[a] - S->hint_lo[a]) * S->hint_inv[a];
    const int n = S->hint_n[a];
    const int c = !(f > 0.0) ? 0 : f >= n - 1 ? n - 1 : (int)f;
    cell = cell * (size_t)n + (size_t)c;
  }
  return S->hint[cell];
}

/* Closest point over all triangles: squared distance, slot and feature.
 * Descends the 4-wide BVH, nearest child first. A subtree or a triangle is
 * skipped when a lower bound of its squared distance, computed in single
 * precision (float boxes, leaf packs), is not below thr = (best + delta)^2,
 * best the smallest exact distance so far and delta a rounding allowance,
 * 2^-17 of the coordinates' magnitude, far above the float errors; the
 * exact test runs in double. */
double mx_index_closest_slot(const mx_surface_index *S, const double p[3],
                           double q[3], uint32_t *slot, int *feat, double rmax) {
  double best = INFINITY, thr = INFINITY;
  if (!S->nt) return best;
  const double pm = mx_max(fabs(p[0]), mx_max(fabs(p[1]), fabs(p[2])));
  if (!float_bounds_safe(S, pm)) {
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
  const double delta = bound_allowance(S, pm);
  const float px = (float)p[0], py = (float)p[1], pz = (float)p[2];
  if (S->hint) {
    const uint32_t i = hint_slot(S, p);
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
      pack_bounds(&S->packs[idx], px, py, pz, d);
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
    node_bounds(W, px, py, pz, d);
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
  const double d2 = mx_index_closest_slot(S, p, qq, &slot, &f, INFINITY);
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
  const double d2 = mx_index_closest_slot(S, p, qq, &slot, &f, rmax);
  if (q) memcpy(q, qq, sizeof qq);
  return sqrt(d2);
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

/* Which side of the closest feature (slot, f; closest point q) p lies on:
 * the dot product of p - q with the feature's pseudonormal (positive
 * outside, negative inside, 0 untold). */
static double side_of(const mx_surface_index *S, const double p[3], const double q[3],
                      uint32_t slot, int f) {
  const double *n = pseudonormal(S, slot, f);
  double r[3];
  sub3(p, q, r);
  return dot3(r, n);
}

/* An index built outward over closed, consistently oriented shells
 * (outward_closed): the nesting depth of p from its closest point, whose
 * shell c bounds p's region (the segment to it crosses no other shell):
 * c's depth, plus one when p lies inside c (the side of c's outward
 * pseudonormal). -1 when that side is not told (p on c, or at a right
 * angle to the pseudonormal): the caller counts with the winding number. */
static int depth_by_closest(const mx_surface_index *S, const double p[3], double *dist,
                            double q[3]) {
  double qq[3];
  uint32_t slot = 0;
  int f = MX_FEATURE_FACE;
  const double d2 = mx_index_closest_slot(S, p, qq, &slot, &f, INFINITY);
  if (dist) *dist = sqrt(d2);
  if (q) memcpy(q, qq, sizeof qq);
  if (d2 == 0.0) return -1;
  const double g = side_of(S, p, qq, slot, f);
  if (g == 0.0) return -1;
  return (int)S->shell_depth[S->shell_of[slot]] + (g < 0.0);
}

int mx_region_depth(const mx_surface_index *S, const double p[3]) {
  if (S->outward_closed && S->nt) {
    const int d = depth_by_closest(S, p, NULL, NULL);
    if (d >= 0) return d;
  }
  const long d = lround(mx_winding_number(S, p));
  return d < 0 ? 0 : (int)d;
}

/* The side of p from its closest point q (squared distance > 0, slot,
 * feature f) on an index with triangles and no side index: -1 inside, 1
 * outside. Closed shells built outward: the closest shell's depth, plus one
 * on its inner side (the pseudonormal's), inside from 1 on; a closed
 * surface: the pseudonormal's sign; else, or when that sign is 0, the
 * winding number. */
static int side_from_closest(const mx_surface_index *S, const double p[3],
                             const double q[3], uint32_t slot, int f) {
  if (S->outward_closed || S->closed) {
    const double g = side_of(S, p, q, slot, f);
    if (g != 0.0) {
      if (!S->outward_closed) return g < 0.0 ? -1 : 1;
      return (int)S->shell_depth[S->shell_of[slot]] + (g < 0.0) >= 1 ? -1 : 1;
    }
  }
  return mx_winding_number(S, p) > 0.5 ? -1 : 1;
}

double mx_signed_distance(const mx_surface_index *S, const double p[3],
                          double q[3]) {
  double qq[3] = {INFINITY, INFINITY, INFINITY};
  uint32_t slot = 0;
  int f = MX_FEATURE_FACE;
  const double d2 = mx_index_closest_slot(S, p, qq, &slot, &f, INFINITY);
  if (q) memcpy(q, qq, sizeof qq);
  if (d2 == 0.0) return 0.0;
  const double d = sqrt(d2);
  if (S->side) return mx_winding_number(S->side, p) > 0.5 ? -d : d;
  if (!S->nt) return d;
  return side_from_closest(S, p, qq, slot, f) < 0 ? -d : d;
}

int mx_inside(const mx_surface_index *S, const double p[3]) {
  if (S->side) return mx_winding_number(S->side, p) > 0.5;
  if (!S->closed && !S->outward_closed) return mx_winding_number(S, p) > 0.5;
  return mx_signed_distance(S, p, NULL) <= 0.0;
}

/* ---- many points at once ------------------------------------------------ */

enum { BLOCK_PACKS = 48 };

/* The closest points of the points xyz + 3 ids[i], i < n <= MX_BLOCK: the
 * squared distance d2[i], point q[i], slot and feature, the same as
 * mx_index_closest_slot's with rmax[i] (rmax NULL: infinite) whenever the
 * distance is below rmax[i] (otherwise d2[i] is not below rmax[i]^2 either).
 * The 4-wide tree is walked once for the block: the leaf packs with a
 * triangle within ub of the block's box (ub: the farthest of the points'
 * first bounds, their hints' distances or rmax), found from its centre
 * with ub + its half diagonal; then each point starts from its hint, as the
 * single query, and tests the packs' triangles whose float bound is below
 * its best so far plus the allowance, exactly. Where two triangles are at
 * exactly the least distance the single query decides which (the tree's
 * order); so does a block too loose for BLOCK_PACKS packs (its points far
 * apart) and a range where float bounds are not safe. */
static void closest_block(const mx_surface_index *S, const double *xyz, const uint32_t *ids,
                          int n, const double *rmax, double *d2, double (*q)[3],
                          uint32_t *slot, int *feat) {
  double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
  double pm = 0.0;
  for (int i = 0; i < n; i++) {
    const double *p = xyz + 3 * (size_t)ids[i];
    for (int a = 0; a < 3; a++) {
      lo[a] = fmin(lo[a], p[a]);
      hi[a] = fmax(hi[a], p[a]);
      pm = fmax(pm, fabs(p[a]));
    }
  }
  int alone = n < 2 || !S->hint || !float_bounds_safe(S, pm); /* one by one */
  const double delta = bound_allowance(S, pm);
  double ub = 0.0;
  for (int i = 0; i < n && !alone; i++) {
    const double *p = xyz + 3 * (size_t)ids[i];
    slot[i] = hint_slot(S, p);
    feat[i] = MX_FEATURE_FACE;
    d2[i] = closest_on_triangle(S->tv + 9 * (size_t)slot[i], p, q[i], &feat[i]);
    ub = fmax(ub, rmax ? fmin(sqrt(d2[i]), rmax[i]) : sqrt(d2[i]));
  }
  uint32_t pack[BLOCK_PACKS];
  uint8_t pcnt[BLOCK_PACKS]; /* their lanes in use */
  int np = 0;
  if (!alone) {
    double c[3], rb = 0.0;
    for (int a = 0; a < 3; a++) {
      c[a] = 0.5 * (lo[a] + hi[a]);
      rb += 0.25 * (hi[a] - lo[a]) * (hi[a] - lo[a]);
    }
    const double r = ub + sqrt(rb) + delta, thr = r * r;
    const float cx = (float)c[0], cy = (float)c[1], cz = (float)c[2];
    uint32_t stack[4 * STACK_MAX];
    uint8_t scnt[4 * STACK_MAX];
    int sp = 0;
    stack[sp] = 0;
    scnt[sp++] = 0;
    while (sp && !alone) {
      sp--;
      const uint32_t idx = stack[sp];
      float d[4];
      if (scnt[sp]) { /* a leaf pack: kept when a lane is near */
        pack_bounds(&S->packs[idx], cx, cy, cz, d);
        int near = 0;
        for (int l = 0; l < scnt[sp]; l++) near |= d[l] < thr;
        if (!near) continue;
        if (np == BLOCK_PACKS) {
          alone = 1;
        } else {
          pcnt[np] = scnt[sp];
          pack[np++] = idx;
        }
        continue;
      }
      const mx_bvh4_node *W = &S->wide[idx];
      node_bounds(W, cx, cy, cz, d);
      for (int k = 0; k < 4; k++) {
        stack[sp] = W->child[k];
        scnt[sp] = W->count[k];
        sp += d[k] < thr;
      }
    }
  }
  for (int i = 0; i < n; i++) {
    const double *p = xyz + 3 * (size_t)ids[i];
    const double rm = rmax ? rmax[i] : INFINITY;
    int tie = 0;
    if (!alone && d2[i] > 0.0) {
      const double r0 = fmin(sqrt(d2[i]), rm) + delta;
      double t = r0 * r0;
      const float px = (float)p[0], py = (float)p[1], pz = (float)p[2];
      for (int k = 0; k < np; k++) {
        float d[4];
        pack_bounds(&S->packs[pack[k]], px, py, pz, d);
        const uint32_t first = S->leaf_first[pack[k]];
        for (int l = 0; l < pcnt[k]; l++) {
          if (!(d[l] < t)) continue;
          const uint32_t sl = first + (uint32_t)l;
          double qi[3];
          int f = MX_FEATURE_FACE;
          const double e = closest_on_triangle(S->tv + 9 * (size_t)sl, p, qi, &f);
          if (e < d2[i]) {
            d2[i] = e;
            memcpy(q[i], qi, sizeof qi);
            slot[i] = sl;
            feat[i] = f;
            tie = 0;
            const double ri = fmin(sqrt(e), rm) + delta;
            t = ri * ri;
          } else if (e == d2[i] && sl != slot[i]) {
            tie = 1;
          }
        }
      }
    }
    if (alone || tie) d2[i] = mx_index_closest_slot(S, p, q[i], &slot[i], &feat[i], rm);
  }
}

/* mx_inside of each point, one by one */
static void inside_each(const mx_surface_index *S, const double *xyz, const uint32_t *ids,
                        int n, uint8_t *inside) {
  for (int i = 0; i < n; i++) inside[i] = (uint8_t)mx_inside(S, xyz + 3 * (size_t)ids[i]);
}

void mx_inside_block(const mx_surface_index *S, const double *xyz, const uint32_t *ids,
                     int n, uint8_t *inside, uint8_t *on, double near2) {
  if (n > MX_BLOCK) {
    for (int i = 0; i < n; i += MX_BLOCK)
      mx_inside_block(S, xyz, ids + i, n - i < MX_BLOCK ? n - i : MX_BLOCK, inside + i,
                      on ? on + i : NULL, near2);
    return;
  }
  if (S->side || (!S->closed && !S->outward_closed) || !S->nt) {
    inside_each(S, xyz, ids, n, inside);
    if (on) memcpy(on, inside, (size_t)n); /* no distance: every inside point */
    return;
  }
  double d2[MX_BLOCK], q[MX_BLOCK][3];
  uint32_t slot[MX_BLOCK];
  int feat[MX_BLOCK];
  closest_block(S, xyz, ids, n, NULL, d2, q, slot, feat);
  for (int i = 0; i < n; i++) /* (mx_inside: on the surface is in) */
    inside[i] = (uint8_t)(d2[i] == 0.0 ||
                          side_from_closest(S, xyz + 3 * (size_t)ids[i], q[i], slot[i],
                                            feat[i]) < 0);
  if (on)
    for (int i = 0; i < n; i++) on[i] = (uint8_t)(inside[i] && d2[i] <= near2);
}

void mx_closest_point_block(const mx_surface_index *S, const double *xyz, const uint32_t *ids,
                            int n, const double *rmax, double *dist, double (*q)[3]) {
  if (n > MX_BLOCK) {
    for (int i = 0; i < n; i += MX_BLOCK)
      mx_closest_point_block(S, xyz, ids + i, n - i < MX_BLOCK ? n - i : MX_BLOCK,
                             rmax ? rmax + i : NULL, dist + i, q + i);
    return;
  }
  uint32_t slot[MX_BLOCK];
  int feat[MX_BLOCK];
  if (!S->nt) {
    for (int i = 0; i < n; i++) dist[i] = INFINITY;
    return;
  }
  closest_block(S, xyz, ids, n, rmax, dist, q, slot, feat);
  for (int i = 0; i < n; i++) dist[i] = sqrt(dist[i]);
}

/* Face normals, edge pseudonormals (sum of the normals of the faces of the
 * edge), vertex pseudonormals (angle-weighted sum). */
int mx_index_pseudonormals(mx_surface_index *S, const mx_edge_table *E) {
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
  if (!S->vn) return MX_ENOMEM;
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
