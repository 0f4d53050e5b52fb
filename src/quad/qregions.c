/* The regions of nested loops (quad.h, mx_qregions): the loops of a checked
 * domain turned counter-clockwise, so that the winding number of a point is
 * the number of loops around it (its region), each loop's depth (the loops
 * around it), and the loops of some depths as a domain of their own.
 *
 * The winding number walks p's row of the index's grid to its nearer end,
 * as the domain's parity does (poly.c: ray_parity), but sums the crossings
 * with their sign: a counter-clockwise loop around p goes up on p's right
 * and down on its left. Decisions use the exact orientation predicate; a
 * point within the index's eps of a segment is on it. A loop's depth is the
 * winding number at its lowest-left vertex with its own segments left out
 * (loops of a checked domain neither cross nor touch). */
#include <math.h>
#include <string.h>

#include "base/common.h"
#include "geom/orient2d.h"
#include "quad/quad.h"

#define NONE UINT32_MAX

static inline const double *vtx(const mx_poly *P, uint32_t v) { return P->xy + 2 * (size_t)v; }

static inline uint32_t cell_of(double x, double lo, double h, uint32_t n) {
  const double t = (x - lo) / h;
  if (!(t >= 0.0)) return 0;
  if (t >= (double)n) return n - 1;
  return (uint32_t)t;
}

static double seg_dist2(const double *a, const double *b, const double *p) {
  const double u0 = b[0] - a[0], u1 = b[1] - a[1], w0 = p[0] - a[0], w1 = p[1] - a[1];
  const double l2 = u0 * u0 + u1 * u1;
  double t = l2 > 0 ? (u0 * w0 + u1 * w1) / l2 : 0.0;
  t = t < 0 ? 0 : t > 1 ? 1 : t;
  const double d0 = w0 - t * u0, d1 = w1 - t * u1;
  return d0 * d0 + d1 * d1;
}

/* The signed crossing of directed segment s with the ray from p along +x
 * (right) or -x, counted in the cell of the row where it crosses (so once
 * for a segment listed in several): +1 when a counter-clockwise loop's
 * segment there goes around p, -1 the other way, 0 no crossing here. */
static int crossing(const mx_poly_index *I, uint32_t s, const double *p, uint32_t cx, uint32_t c,
                    int right) {
  const mx_poly *P = I->P;
  const double *a = vtx(P, P->seg[2 * (size_t)s]), *b = vtx(P, P->seg[2 * (size_t)s + 1]);
  if ((a[1] > p[1]) == (b[1] > p[1])) return 0;
  const int up = b[1] > p[1];
  const double *lo = up ? a : b, *hi = up ? b : a;
  const int side = mx_orient2d(lo, hi, p); /* > 0: the crossing is right of p */
  if (right ? side <= 0 : side >= 0) return 0;
  const double xc = a[0] + (p[1] - a[1]) * (b[0] - a[0]) / (b[1] - a[1]);
  uint32_t home = cell_of(xc, I->lo[0], I->h, I->nx);
  if (right ? home < cx : home > cx) home = cx;
  if (home != c) return 0;
  return right == up ? 1 : -1;
}

/* The winding number of p (segments of loop `skip` left out when loop_of
 * is given); *on gets a segment within eps of p (NONE: none) when on is
 * not NULL, and then the sum is not finished. */
static long winding(const mx_poly_index *I, const double p[2], const uint32_t *loop_of,
                    uint32_t skip, uint32_t *on) {
  if (on) *on = NONE;
  if (!I->P || I->P->ns == 0) return 0;
  if (!(p[0] >= I->lo[0] && p[0] < I->lo[0] + I->nx * I->h && p[1] >= I->lo[1] &&
        p[1] < I->lo[1] + I->ny * I->h))
    return 0;
  const uint32_t cy = cell_of(p[1], I->lo[1], I->h, I->ny);
  const uint32_t cx = cell_of(p[0], I->lo[0], I->h, I->nx);
  const int right = I->nx - cx <= cx + 1;
  const uint32_t ncol = right ? I->nx - cx : cx + 1;
  const double eps2 = I->eps * I->eps;
  long w = 0;
  for (uint32_t k = 0; k < ncol; k++) {
    const uint32_t c = right ? cx + k : cx - k;
    const size_t cell = (size_t)cy * I->nx + c;
    for (uint32_t j = I->off[cell]; j < I->off[cell + 1]; j++) {
      const uint32_t s = I->ids[j];
      if (loop_of && loop_of[s] == skip) continue;
      if (on && k == 0 &&
          seg_dist2(vtx(I->P, I->P->seg[2 * (size_t)s]), vtx(I->P, I->P->seg[2 * (size_t)s + 1]),
                    p) <= eps2) {
        *on = s;
        return 0;
      }
      w += crossing(I, s, p, cx, c, right);
    }
  }
  return w;
}

void mx_qregions_free(mx_qregions *R) {
  mx_poly_index_free(&R->I);
  mx_poly_free(&R->all);
  mx_free(R->seg_depth);
  memset(R, 0, sizeof *R);
}

/* loop_of[s] for the segments of a checked domain (each vertex starts one
 * segment): loops numbered in order of their first segment. */
static size_t walk(const mx_poly *P, uint32_t *out, uint32_t *loop_of) {
  for (size_t v = 0; v < P->nv; v++) out[v] = NONE;
  for (size_t s = 0; s < P->ns; s++) out[P->seg[2 * s]] = (uint32_t)s, loop_of[s] = NONE;
  size_t L = 0;
  for (size_t s0 = 0; s0 < P->ns; s0++) {
    if (loop_of[s0] != NONE) continue;
    for (uint32_t s = (uint32_t)s0; s != NONE && loop_of[s] == NONE;
         s = out[P->seg[2 * (size_t)s + 1]])
      loop_of[s] = (uint32_t)L;
    L++;
  }
  return L;
}

int mx_qregions_build(const mx_poly *P, mx_qregions *R) {
  memset(R, 0, sizeof *R);
  const size_t nv = P->nv, ns = P->ns;
  uint32_t *out = mx_alloc((nv + 1) * sizeof *out);
  uint32_t *loop_of = mx_alloc((ns + 1) * sizeof *loop_of);
  mx_poly *A = &R->all;
  A->xy = mx_alloc((2 * nv + 1) * sizeof *A->xy);
  A->seg = mx_alloc((2 * ns + 1) * sizeof *A->seg);
  A->line = mx_alloc((ns + 1) * sizeof *A->line);
  A->path = mx_strdup(P->path ? P->path : "domain");
  R->seg_depth = mx_alloc((ns + 1) * sizeof *R->seg_depth);
  if (!out || !loop_of || !A->xy || !A->seg || !A->line || !A->path || !R->seg_depth) {
    mx_free(out), mx_free(loop_of);
    mx_qregions_free(R);
    return MX_ENOMEM;
  }
  A->nv = nv, A->ns = ns;
  memcpy(A->xy, P->xy, 2 * nv * sizeof *A->xy);
  memcpy(A->seg, P->seg, 2 * ns * sizeof *A->seg);
  for (size_t s = 0; s < ns; s++) A->line[s] = P->line ? P->line[s] : 0;
  const size_t nl = walk(P, out, loop_of);
  A->nloops = nl;
  /* each loop's lowest-left vertex: the turn there gives its orientation */
  uint32_t *low = mx_alloc((nl + 1) * sizeof *low);
  uint8_t *flip = mx_calloc(nl + 1);
  uint32_t *ldepth = mx_alloc((nl + 1) * sizeof *ldepth);
  int st = low && flip && ldepth ? MX_OK : MX_ENOMEM;
  if (st == MX_OK) {
    for (size_t L = 0; L < nl; L++) low[L] = NONE;
    for (size_t s = 0; s < ns; s++) {
      uint32_t *l = &low[loop_of[s]];
      const double *a = vtx(P, P->seg[2 * s]);
      if (*l == NONE) {
        *l = (uint32_t)s;
        continue;
      }
      const double *b = vtx(P, P->seg[2 * (size_t)*l]);
      if (a[0] < b[0] || (a[0] == b[0] && a[1] < b[1])) *l = (uint32_t)s;
    }
    /* the segment into a loop's lowest-left vertex: the one ending there */
    for (size_t s = 0; s < ns; s++) {
      const uint32_t L = loop_of[s], t = out[P->seg[2 * s + 1]];
      if (t == low[L]) {
        const double *in = vtx(P, P->seg[2 * s]), *v = vtx(P, P->seg[2 * s + 1]),
                     *w = vtx(P, P->seg[2 * (size_t)t + 1]);
        flip[L] = mx_orient2d(in, v, w) < 0;
      }
    }
    for (size_t s = 0; s < ns; s++)
      if (flip[loop_of[s]]) A->seg[2 * s] = P->seg[2 * s + 1], A->seg[2 * s + 1] = P->seg[2 * s];
    st = mx_poly_index_build(A, &R->I);
  }
  if (st == MX_OK) {
    uint32_t deepest = 0;
#pragma omp parallel for schedule(dynamic, 16) reduction(max : deepest)
    for (size_t L = 0; L < nl; L++) {
      const long w = winding(&R->I, vtx(P, P->seg[2 * (size_t)low[L]]), loop_of, (uint32_t)L, NULL);
      ldepth[L] = w > 0 ? (uint32_t)w : 0;
      deepest = ldepth[L] > deepest ? ldepth[L] : deepest;
    }
    for (size_t s = 0; s < ns; s++) R->seg_depth[s] = ldepth[loop_of[s]];
    R->deepest = deepest + 1;
  }
  mx_free(out), mx_free(loop_of), mx_free(low), mx_free(flip), mx_free(ldepth);
  if (st != MX_OK) mx_qregions_free(R);
  return st;
}

long mx_qregion_of(const mx_qregions *R, const double p[2], uint32_t *seg) {
  uint32_t on;
  const long w = winding(&R->I, p, NULL, 0, &on);
  if (seg) *seg = on;
  return on == NONE ? w : -1;
}

int mx_qregions_select(const mx_qregions *R, uint32_t lo, uint32_t hi, mx_poly *out) {
  memset(out, 0, sizeof *out);
  const mx_poly *A = &R->all;
  size_t ns = 0;
  for (size_t s = 0; s < A->ns; s++) ns += R->seg_depth[s] >= lo && R->seg_depth[s] <= hi;
  uint32_t *id = mx_alloc((A->nv + 1) * sizeof *id);
  out->seg = mx_alloc((2 * ns + 1) * sizeof *out->seg);
  out->line = mx_alloc((ns + 1) * sizeof *out->line);
  out->path = mx_strdup(A->path);
  if (!id || !out->seg || !out->line || !out->path) {
    mx_free(id);
    mx_poly_free(out);
    return MX_ENOMEM;
  }
  for (size_t v = 0; v < A->nv; v++) id[v] = NONE;
  size_t nv = 0, k = 0;
  for (size_t s = 0; s < A->ns; s++) {
    const uint32_t d = R->seg_depth[s];
    if (d < lo || d > hi) continue;
    /* every loop counter-clockwise in A: those at depth lo + 1 go back */
    const int back = d > lo;
    for (int e = 0; e < 2; e++) {
      const uint32_t v = A->seg[2 * s + (size_t)(back ? 1 - e : e)];
      if (id[v] == NONE) id[v] = (uint32_t)nv++;
      out->seg[2 * k + (size_t)e] = id[v];
    }
    out->line[k++] = A->line[s];
  }
  out->xy = mx_alloc((2 * nv + 1) * sizeof *out->xy);
  if (!out->xy) {
    mx_free(id);
    mx_poly_free(out);
    return MX_ENOMEM;
  }
  for (size_t v = 0; v < A->nv; v++)
    if (id[v] != NONE) {
      out->xy[2 * (size_t)id[v]] = A->xy[2 * v];
      out->xy[2 * (size_t)id[v] + 1] = A->xy[2 * v + 1];
    }
  out->nv = nv, out->ns = ns;
  size_t nl = 0;
  uint32_t *o2 = mx_alloc((nv + 1) * sizeof *o2), *l2 = mx_alloc((ns + 1) * sizeof *l2);
  if (!o2 || !l2) {
    mx_free(id), mx_free(o2), mx_free(l2);
    mx_poly_free(out);
    return MX_ENOMEM;
  }
  nl = walk(out, o2, l2);
  out->nloops = nl;
  mx_free(id), mx_free(o2), mx_free(l2);
  return MX_OK;
}
