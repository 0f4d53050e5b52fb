#include "geom/locate.h"

#include "base/common.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

void mx_locator_free(mx_locator *L) {
  mx_free(L->cell_off);
  mx_free(L->cell_tri);
  memset(L, 0, sizeof *L);
}

static void cell_range(const mx_locator *L, double v, int axis, int *c) {
  double f = (v - L->lo[axis]) * L->inv[axis];
  int i = (int)floor(f);
  if (i < 0) i = 0;
  if (i >= L->n[axis]) i = L->n[axis] - 1;
  *c = i;
}

static void tri_cells(const mx_locator *L, uint32_t t, int c0[2], int c1[2]) {
  const mx_trisoup *s = L->soup;
  const uint32_t *v = s->tri + 3 * (size_t)t;
  const double *co[2] = {s->y, s->z};
  for (int a = 0; a < 2; a++) {
    double mn = mx_min(co[a][v[0]], mx_min(co[a][v[1]], co[a][v[2]]));
    double mx = mx_max(co[a][v[0]], mx_max(co[a][v[1]], co[a][v[2]]));
    cell_range(L, mn, a, &c0[a]);
    cell_range(L, mx, a, &c1[a]);
  }
}

int mx_locator_build(mx_locator *L, const mx_trisoup *soup, uint32_t t0,
                     uint32_t t1) {
  memset(L, 0, sizeof *L);
  L->soup = soup;
  L->t0 = t0;
  L->t1 = t1;
  double lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY};
  const double *co[2] = {soup->y, soup->z};
  for (uint32_t t = t0; t < t1; t++)
    for (int k = 0; k < 3; k++)
      for (int a = 0; a < 2; a++) {
        double v = co[a][soup->tri[3 * (size_t)t + k]];
        lo[a] = mx_min(lo[a], v);
        hi[a] = mx_max(hi[a], v);
      }
  size_t nt = t1 - t0;
  /* About 2 cells per triangle, shaped like the projected box. */
  double ext[2] = {mx_max(hi[0] - lo[0], 1e-300), mx_max(hi[1] - lo[1], 1e-300)};
  double cells = 2.0 * (double)(nt ? nt : 1);
  double k = sqrt(cells / (ext[0] * ext[1]));
  for (int a = 0; a < 2; a++) {
    int n = (int)ceil(k * ext[a]);
    if (n < 1) n = 1;
    if (n > 4096) n = 4096;
    L->n[a] = n;
    L->lo[a] = lo[a];
    L->inv[a] = (double)n / ext[a];
  }
  size_t ncell = (size_t)L->n[0] * (size_t)L->n[1];
  L->cell_off = mx_calloc((ncell + 1) * sizeof *L->cell_off);
  if (!L->cell_off) return MX_ENOMEM;
  for (uint32_t t = t0; t < t1; t++) {
    int c0[2], c1[2];
    tri_cells(L, t, c0, c1);
    for (int j = c0[1]; j <= c1[1]; j++)
      for (int i = c0[0]; i <= c1[0]; i++)
        L->cell_off[(size_t)j * L->n[0] + i + 1]++;
  }
  for (size_t c = 0; c < ncell; c++) L->cell_off[c + 1] += L->cell_off[c];
  L->cell_tri = mx_alloc((size_t)L->cell_off[ncell] * sizeof *L->cell_tri + 4);
  uint32_t *fill = mx_alloc(ncell * sizeof *fill + 4);
  if (!L->cell_tri || !fill) {
    mx_free(fill);
    return MX_ENOMEM;
  }
  memcpy(fill, L->cell_off, ncell * sizeof *fill);
  for (uint32_t t = t0; t < t1; t++) {
    int c0[2], c1[2];
    tri_cells(L, t, c0, c1);
    for (int j = c0[1]; j <= c1[1]; j++)
      for (int i = c0[0]; i <= c1[0]; i++)
        L->cell_tri[fill[(size_t)j * L->n[0] + i]++] = t;
  }
  mx_free(fill);
  return MX_OK;
}

/* Side of the query q = (qu, qv) of the projected edge from vertex a to vertex
 * b, evaluated with the lower vertex index first so that both triangles of an
 * edge compute the same number; zero is resolved by displacing q by
 * (eps, eps^2). Returns +1 (left of a->b) or -1. */
static inline int edge_side(const mx_trisoup *s, uint32_t a, uint32_t b,
                            double qu, double qv) {
  int flip = 0;
  if (a > b) {
    uint32_t t = a;
    a = b;
    b = t;
    flip = 1;
  }
  const double au = s->y[a], av = s->z[a], bu = s->y[b], bv = s->z[b];
  double d = (bu - au) * (qv - av) - (bv - av) * (qu - au);
  int sgn;
  if (d > 0.0)
    sgn = 1;
  else if (d < 0.0)
    sgn = -1;
  else if (bv != av) /* d/d(eps) = -(bv - av) */
    sgn = (bv - av) < 0.0 ? 1 : -1;
  else /* d/d(eps^2) = (bu - au); a != b in projection or degenerate */
    sgn = (bu - au) > 0.0 ? 1 : -1;
  return flip ? -sgn : sgn;
}

int mx_locate(const mx_locator *L, const double p[3]) {
  if (L->inside_fn) return L->inside_fn(L->inside_ctx, p);
  const mx_trisoup *s = L->soup;
  double f0 = (p[1] - L->lo[0]) * L->inv[0];
  double f1 = (p[2] - L->lo[1]) * L->inv[1];
  /* Queries beyond the projected box meet no triangle. */
  if (!(f0 >= 0.0 && f1 >= 0.0 && f0 <= L->n[0] && f1 <= L->n[1])) return 0;
  int i = (int)f0, j = (int)f1;
  if (i >= L->n[0]) i = L->n[0] - 1;
  if (j >= L->n[1]) j = L->n[1] - 1;
  const size_t c = (size_t)j * L->n[0] + i;
  int parity = 0;
  for (uint32_t k = L->cell_off[c]; k < L->cell_off[c + 1]; k++) {
    const uint32_t *v = s->tri + 3 * (size_t)L->cell_tri[k];
    int s0 = edge_side(s, v[0], v[1], p[1], p[2]);
    int s1 = edge_side(s, v[1], v[2], p[1], p[2]);
    if (s0 != s1) continue;
    int s2 = edge_side(s, v[2], v[0], p[1], p[2]);
    if (s0 != s2) continue;
    /* The ray's line crosses the triangle's plane at x; compare with p. */
    const double ax = s->x[v[0]], ay = s->y[v[0]], az = s->z[v[0]];
    const double e1[3] = {s->x[v[1]] - ax, s->y[v[1]] - ay, s->z[v[1]] - az};
    const double e2[3] = {s->x[v[2]] - ax, s->y[v[2]] - ay, s->z[v[2]] - az};
    const double n[3] = {e1[1] * e2[2] - e1[2] * e2[1],
                         e1[2] * e2[0] - e1[0] * e2[2],
                         e1[0] * e2[1] - e1[1] * e2[0]};
    /* n . (q - a) with q = (x, py, pz): sign of (x - p.x) equals the sign of
     * n.(q-a) - n.(p-a) over n.x; x > p.x iff -n.(p-a) / n.x > 0. */
    double g = n[0] * (p[0] - ax) + n[1] * (p[1] - ay) + n[2] * (p[2] - az);
    if (n[0] == 0.0) continue; /* edge-on: no perturbed ray crosses it */
    if ((g < 0.0) == (n[0] > 0.0)) parity ^= 1;
  }
  return parity;
}
