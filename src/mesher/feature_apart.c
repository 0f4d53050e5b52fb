/* Features kept apart by the octree (issue 29, item 2): two features must
 * not claim one mesh node, so where two of them come closer than the
 * octants meeting them can separate, those octants are refined further.
 *
 * The corners only: a corner's distance to the nearest other corner asks
 * for the level whose octants are at most FEATURE_SPACING of it, as the 2D
 * mesher does (mesher2d.c), by a box around the corner. The levels are
 * capped at the surface (or feature) level plus APART_EXTRA: features
 * closer than that are left to the placement, which counts what it
 * misses. Measured on the OpenSCAD corpus at -s 5: sampling the ridges
 * too (points of two lines sharing no corner) and 3 levels more made 3,056
 * boxes and 64 times the elements on linear_extrude (engraved text, 20 s
 * against 0.2 s), for few more ridges followed. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "base/common.h"
#include "mesher/mesher_impl.h"

#define FEATURE_SPACING 0.5
#define APART_EXTRA 2

static int cmp_x(const void *a, const void *b) {
  const double *p = a, *q = b;
  return (p[0] > q[0]) - (p[0] < q[0]);
}

static double dist3(const double *a, const double *b) {
  return sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) +
              (a[2] - b[2]) * (a[2] - b[2]));
}

int mx_feature_apart_boxes(mx_mesher *m, double root_side) {
  mx_free(m->feature_boxes);
  m->feature_boxes = NULL;
  m->nfeature_boxes = 0;
  const mx_feature_lines *L = &m->feat_lines;
  const int base = m->feature_level > m->p.surface_level ? m->feature_level : m->p.surface_level;
  const size_t n = L->ncorners;
  if (!m->have_features || base <= 0 || !(root_side > 0.0) || n < 2) return MX_OK;
  /* the corners by x; each one's nearest other, scanning while |dx| < best */
  double *c = mx_alloc(3 * n * sizeof *c);
  mx_box_region *b = mx_alloc((m->nboxes + n) * sizeof *b);
  if (!c || !b) {
    mx_free(c);
    mx_free(b);
    return MX_ENOMEM;
  }
  memcpy(c, L->corner, 3 * n * sizeof *c);
  qsort(c, n, 3 * sizeof *c, cmp_x);
  if (m->nboxes) memcpy(b, m->boxes, m->nboxes * sizeof *b);
  size_t nb = m->nboxes;
  for (size_t i = 0; i < n; i++) {
    const double *x = c + 3 * i;
    double best = INFINITY;
    for (size_t j = i + 1; j < n && c[3 * j] - x[0] < best; j++) best = fmin(best, dist3(x, c + 3 * j));
    for (size_t j = i; j-- > 0 && x[0] - c[3 * j] < best;) best = fmin(best, dist3(x, c + 3 * j));
    int level = base;
    while (level < base + APART_EXTRA && level < MX_MAX_LEVEL &&
           ldexp(root_side, -level) > FEATURE_SPACING * best)
      level++;
    if (level == base) continue;
    const double eps = 1e-3 * ldexp(root_side, -level); /* a box inside the corner's octant */
    mx_box_region *r = &b[nb++];
    for (int d = 0; d < 3; d++) {
      r->lo[d] = x[d] - eps;
      r->hi[d] = x[d] + eps;
    }
    r->level = level;
  }
  mx_free(c);
  if (nb == m->nboxes) {
    mx_free(b);
    return MX_OK;
  }
  m->feature_boxes = b; /* the user's boxes first, then these */
  m->nfeature_boxes = nb;
  m->rec->S.feature_apart_boxes = nb - m->nboxes;
  return MX_OK;
}
