/* Sizes a surface asks for: curvature and thickness (geom/surface_sizes.h). */
#include "geom/surface_sizes.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "base/common.h"
#include "geom/bvh.h"

enum { KMAX = 128, EDGE_POINTS_MAX = 256 };
#define MAX_SAMPLES 16000000.0

void mx_point_sizes_free(mx_point_sizes *p) {
  mx_free(p->xyz);
  mx_free(p->h);
  mx_free(p->w);
  memset(p, 0, sizeof *p);
}

static int reserve(mx_point_sizes *p, size_t more) {
  if (p->n + more <= p->cap) return MX_OK;
  size_t cap = p->cap ? p->cap : 1024;
  while (cap < p->n + more) cap *= 2;
  double *x = mx_realloc(p->xyz, 3 * cap * sizeof *x);
  if (!x) return MX_ENOMEM;
  p->xyz = x;
  double *h = mx_realloc(p->h, cap * sizeof *h);
  if (!h) return MX_ENOMEM;
  p->h = h;
  double *w = mx_realloc(p->w, cap * sizeof *w);
  if (!w) return MX_ENOMEM;
  p->w = w;
  p->cap = cap;
  return MX_OK;
}

static void push(mx_point_sizes *p, const double x[3], double h, double w) {
  memcpy(p->xyz + 3 * p->n, x, 3 * sizeof *x);
  p->h[p->n] = h;
  p->w[p->n] = w;
  p->n++;
}

static double dot3(const double *a, const double *b) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

/* Segment [0, tmax) of the ray inside the box, from tmin. */
static int ray_box(const double o[3], const double inv[3], const double d[3], const double lo[3],
                   const double hi[3], double tmin, double tmax) {
  for (int a = 0; a < 3; a++) {
    if (d[a] == 0.0) {
      if (o[a] < lo[a] || o[a] > hi[a]) return 0;
      continue;
    }
    double t1 = (lo[a] - o[a]) * inv[a], t2 = (hi[a] - o[a]) * inv[a];
    if (t1 > t2) {
      const double s = t1;
      t1 = t2;
      t2 = s;
    }
    if (t1 > tmin) tmin = t1;
    if (t2 < tmax) tmax = t2;
    if (tmin > tmax) return 0;
  }
  return 1;
}

/* Moller-Trumbore: t of the ray's crossing of the triangle (INFINITY when
 * it misses). */
static double ray_triangle(const double o[3], const double d[3], const double *v) {
  double e1[3], e2[3], p[3], s[3], q[3];
  for (int a = 0; a < 3; a++) {
    e1[a] = v[3 + a] - v[a];
    e2[a] = v[6 + a] - v[a];
  }
  p[0] = d[1] * e2[2] - d[2] * e2[1];
  p[1] = d[2] * e2[0] - d[0] * e2[2];
  p[2] = d[0] * e2[1] - d[1] * e2[0];
  const double det = dot3(e1, p);
  if (det == 0.0 || !isfinite(det)) return INFINITY;
  const double inv = 1.0 / det;
  for (int a = 0; a < 3; a++) s[a] = o[a] - v[a];
  const double u = dot3(s, p) * inv;
  if (u < 0.0 || u > 1.0) return INFINITY;
  q[0] = s[1] * e1[2] - s[2] * e1[1];
  q[1] = s[2] * e1[0] - s[0] * e1[2];
  q[2] = s[0] * e1[1] - s[1] * e1[0];
  const double w = dot3(d, q) * inv;
  if (w < 0.0 || u + w > 1.0) return INFINITY;
  return dot3(e2, q) * inv;
}

double mx_ray_first_hit(const mx_surface_index *S, const double o[3], const double d[3],
                        double tmin, double tmax, uint32_t skip, uint32_t *slot) {
  *slot = UINT32_MAX;
  if (!S->nt || !S->nnodes) return INFINITY;
  const double inv[3] = {1.0 / d[0], 1.0 / d[1], 1.0 / d[2]};
  uint32_t stack[96];
  int top = 0;
  stack[top++] = 0;
  double best = tmax;
  while (top > 0) {
    const mx_bvh_node *nd = S->nodes + stack[--top];
    if (!ray_box(o, inv, d, nd->lo, nd->hi, tmin, best)) continue;
    if (nd->count) {
      for (uint32_t k = nd->first; k < nd->first + nd->count; k++) {
        if (k == skip) continue;
        const double t = ray_triangle(o, d, S->tv + 9 * (size_t)k);
        if (t > tmin && t < best) {
          best = t;
          *slot = k;
        }
      }
    } else if (top + 2 <= (int)(sizeof stack / sizeof *stack)) {
      stack[top++] = nd->first + 1;
      stack[top++] = nd->first;
    }
  }
  return *slot == UINT32_MAX ? INFINITY : best;
}

static double diagonal(const mx_surface_index *S) {
  if (!S->nnodes) return 0.0;
  double s = 0.0;
  for (int a = 0; a < 3; a++) {
    const double e = S->nodes[0].hi[a] - S->nodes[0].lo[a];
    s += e * e;
  }
  return sqrt(s);
}

/* ---- curvature ---- */

static int cmp_u64(const void *a, const void *b) {
  const uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
  return x < y ? -1 : x > y;
}

int mx_surface_curvature_sizes(const mx_surface_index *S, double theta, mx_point_sizes *out) {
  if (!(theta > 0.0) || !S->nt) return MX_OK;
  const size_t ne = 3 * (size_t)S->nt;
  /* (edge key, slot) pairs sorted: the edge's two vertices in the key's
   * high bits are not enough for 2^32 vertices, so sort 128-bit records */
  uint64_t *rec = mx_alloc(2 * ne * sizeof *rec);
  if (!rec) return MX_ENOMEM;
  const uint32_t *tri = S->soup->tri;
  for (uint32_t k = 0; k < S->nt; k++) {
    const uint32_t *t = tri + 3 * (size_t)S->tri_id[k];
    for (int e = 0; e < 3; e++) {
      uint32_t a = t[e], b = t[(e + 1) % 3];
      if (a > b) {
        const uint32_t s = a;
        a = b;
        b = s;
      }
      rec[2 * (3 * (size_t)k + e)] = (uint64_t)a << 32 | b;
      rec[2 * (3 * (size_t)k + e) + 1] = k;
    }
  }
  qsort(rec, ne, 2 * sizeof *rec, cmp_u64); /* by key (the slots are not used after) */
  int st = MX_OK;
  const double *x = S->soup->x, *y = S->soup->y, *z = S->soup->z;
  for (size_t i = 0; i < ne && !st;) {
    size_t j = i + 1;
    while (j < ne && rec[2 * j] == rec[2 * i]) j++;
    if (j - i == 2) {
      const uint32_t va = (uint32_t)(rec[2 * i] >> 32), vb = (uint32_t)rec[2 * i];
      const double pa[3] = {x[va], y[va], z[va]}, pb[3] = {x[vb], y[vb], z[vb]};
      const double e[3] = {pb[0] - pa[0], pb[1] - pa[1], pb[2] - pa[2]};
      const double len2 = dot3(e, e);
      /* the normal curvature along the edge seen from each end */
      const double *na = S->vn + 3 * (size_t)va, *nb = S->vn + 3 * (size_t)vb;
      const double la = sqrt(dot3(na, na)), lb = sqrt(dot3(nb, nb));
      const double kappa = ((la > 0.0 ? fabs(dot3(na, e)) / la : 0.0) +
                            (lb > 0.0 ? fabs(dot3(nb, e)) / lb : 0.0)) / len2;
      const double h = theta / kappa;
      if (len2 > 0.0 && h > 0.0 && isfinite(h)) {
        const double len = sqrt(len2);
        double mcount = ceil(len / h);
        if (mcount < 1.0) mcount = 1.0;
        if (mcount > EDGE_POINTS_MAX) mcount = EDGE_POINTS_MAX;
        const int m = (int)mcount;
        st = reserve(out, (size_t)m);
        for (int k = 0; k < m && !st; k++) {
          const double u = (k + 0.5) / m;
          const double p[3] = {pa[0] + u * (pb[0] - pa[0]), pa[1] + u * (pb[1] - pa[1]),
                               pa[2] + u * (pb[2] - pa[2])};
          push(out, p, h, len / m * h);
        }
      }
    }
    i = j;
  }
  mx_free(rec);
  return st;
}

/* ---- thickness ---- */

static double longest_edge(const double *v) {
  double m = 0.0;
  for (int e = 0; e < 3; e++) {
    const double *a = v + 3 * e, *b = v + 3 * ((e + 1) % 3);
    const double d[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    m = fmax(m, sqrt(dot3(d, d)));
  }
  return m;
}

static double tri_area(const double *v) {
  const double e1[3] = {v[3] - v[0], v[4] - v[1], v[5] - v[2]};
  const double e2[3] = {v[6] - v[0], v[7] - v[1], v[8] - v[2]};
  const double c[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                       e1[0] * e2[1] - e1[1] * e2[0]};
  return 0.5 * sqrt(dot3(c, c));
}

/* Sample s (0 .. k^2 - 1) of a triangle split k x k: the centroid of a
 * sub-triangle, as barycentric (u, v) of the edges a->b, a->c. */
static void sample_uv(int k, int s, double *u, double *v) {
  /* row i holds 2 (k - i) - 1 sub-triangles */
  int i = 0;
  while (s >= 2 * (k - i) - 1) {
    s -= 2 * (k - i) - 1;
    i++;
  }
  const int j = s / 2;
  const double o = (s & 1) ? 2.0 / 3.0 : 1.0 / 3.0;
  *u = (i + o) / k;
  *v = (j + o) / k;
}

/* The first hit of the ray from p along d (sign of the outward normal n:
 * -1 in, +1 out) if it meets a triangle facing the other way within 60
 * degrees: its distance, else INFINITY. */
static double across(const mx_surface_index *S, const double p[3], const double *n, double sgn,
                     uint32_t slot, double eps) {
  const double d[3] = {sgn * n[0], sgn * n[1], sgn * n[2]};
  uint32_t hit;
  const double t = mx_ray_first_hit(S, p, d, eps, INFINITY, slot, &hit);
  if (!isfinite(t)) return INFINITY;
  const double c = dot3(S->fn + 3 * (size_t)hit, d); /* leaving: > 0; entering: < 0 */
  return sgn * c <= -0.5 ? t : INFINITY;
}

/* Casts the rays of every triangle's k[t]^2 samples: tin, tout at off[t] ... */
static void cast(const mx_surface_index *S, const int *k, const size_t *off, double *tin,
                 double *tout, double eps) {
#pragma omp parallel for schedule(dynamic, 16)
  for (size_t t = 0; t < S->nt; t++) {
    const double *v = S->tv + 9 * t, *n = S->fn + 3 * t;
    for (int s = 0; s < k[t] * k[t]; s++) {
      double u, w;
      sample_uv(k[t], s, &u, &w);
      double p[3];
      for (int a = 0; a < 3; a++) p[a] = v[a] + u * (v[3 + a] - v[a]) + w * (v[6 + a] - v[a]);
      tin[off[t] + s] = across(S, p, n, -1.0, (uint32_t)t, eps);
      tout[off[t] + s] = across(S, p, n, 1.0, (uint32_t)t, eps);
    }
  }
}

static size_t offsets(const int *k, size_t nt, size_t *off) {
  size_t sum = 0;
  for (size_t t = 0; t < nt; t++) {
    off[t] = sum;
    sum += (size_t)k[t] * (size_t)k[t];
  }
  off[nt] = sum;
  return sum;
}

int mx_surface_thickness_sizes(const mx_surface_index *S, double nacross, double floor,
                               mx_point_sizes *out) {
  if (!(nacross >= 1.0) || !S->nt) return MX_OK;
  const size_t nt = S->nt;
  const double diag = diagonal(S), spacing = diag / 64.0, eps = 1e-9 * diag;
  if (!(floor > 0.0)) floor = diag / 256.0;
  int *k = mx_alloc(nt * sizeof *k);
  size_t *off = mx_alloc((nt + 1) * sizeof *off);
  if (!k || !off) {
    mx_free(k);
    mx_free(off);
    return MX_ENOMEM;
  }
  /* round 1: the spacing; round 2: finer where the thickness is below it */
  double total = 0.0;
  for (size_t t = 0; t < nt; t++) {
    const double c = ceil(longest_edge(S->tv + 9 * t) / spacing);
    k[t] = c < 1.0 ? 1 : c > KMAX ? KMAX : (int)c;
    total += (double)k[t] * k[t];
  }
  double *tin = NULL, *tout = NULL;
  int st = MX_OK;
  for (int round = 0; round < 2 && !st; round++) {
    if (total > MAX_SAMPLES) { /* a huge surface: fewer samples each */
      const double f = sqrt(MAX_SAMPLES / total);
      for (size_t t = 0; t < nt; t++) k[t] = k[t] * f < 1.0 ? 1 : (int)(k[t] * f);
    }
    const size_t ns = offsets(k, nt, off);
    mx_free(tin);
    mx_free(tout);
    tin = mx_alloc(ns * sizeof *tin);
    tout = mx_alloc(ns * sizeof *tout);
    if (!tin || !tout) {
      st = MX_ENOMEM;
      break;
    }
    cast(S, k, off, tin, tout, eps);
    if (round == 1) break;
    int again = 0;
    total = 0.0;
    for (size_t t = 0; t < nt; t++) {
      double least = INFINITY;
      for (size_t s = off[t]; s < off[t + 1]; s++) least = fmin(least, fmin(tin[s], tout[s]));
      const double want = fmax(least / nacross, floor), have = longest_edge(S->tv + 9 * t) / k[t];
      if (want < have && k[t] < KMAX) {
        const double c = ceil(longest_edge(S->tv + 9 * t) / want);
        k[t] = c > KMAX ? KMAX : (int)c;
        again = 1;
      }
      total += (double)k[t] * k[t];
    }
    if (!again) break;
  }
  const int m = (int)ceil(nacross) + 1;
  for (size_t t = 0; t < nt && !st; t++) {
    const double *v = S->tv + 9 * t, *n = S->fn + 3 * t;
    const double w = tri_area(v) / ((double)k[t] * k[t]);
    for (int s = 0; s < k[t] * k[t] && !st; s++) {
      const double ts[2] = {tin[off[t] + s], tout[off[t] + s]};
      if (!isfinite(ts[0]) && !isfinite(ts[1])) continue;
      double u, ww, p[3];
      sample_uv(k[t], s, &u, &ww);
      for (int a = 0; a < 3; a++) p[a] = v[a] + u * (v[3 + a] - v[a]) + ww * (v[6 + a] - v[a]);
      for (int side = 0; side < 2 && !st; side++) {
        if (!isfinite(ts[side])) continue;
        const double sg = side ? 1.0 : -1.0, h = fmax(ts[side] / nacross, floor);
        st = reserve(out, (size_t)m);
        for (int j = 0; j < m && !st; j++) {
          const double f = ts[side] * j / (m - 1);
          const double q[3] = {p[0] + sg * f * n[0], p[1] + sg * f * n[1], p[2] + sg * f * n[2]};
          push(out, q, h, w / m); /* the sample's area shared by its chord */
        }
      }
    }
  }
  mx_free(k);
  mx_free(off);
  mx_free(tin);
  mx_free(tout);
  return st;
}
