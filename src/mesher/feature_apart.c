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
#define RUN_MAX 16 /* samples a box covers at most */
#define APART_LINES 0 /* the lines' samples too (see above) */

typedef struct {
  double x[3];
  uint32_t line;   /* UINT32_MAX: a corner */
  uint32_t c0, c1; /* the line's corners (UINT32_MAX: none) */
} sample;

static int cmp_x(const void *a, const void *b) {
  const sample *p = a, *q = b;
  return (p->x[0] > q->x[0]) - (p->x[0] < q->x[0]);
}

static double dist3(const double *a, const double *b) {
  return sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) +
              (a[2] - b[2]) * (a[2] - b[2]));
}

/* The corner at x (exactly), or UINT32_MAX. */
static uint32_t corner_at(const mx_feature_lines *L, const double *x) {
  for (size_t c = 0; c < L->ncorners; c++)
    if (!memcmp(L->corner + 3 * c, x, 3 * sizeof *x)) return (uint32_t)c;
  return UINT32_MAX;
}

static int conflict(const sample *a, const sample *b) {
  if (a->line == UINT32_MAX || b->line == UINT32_MAX) /* corners: with corners only */
    return a->line == b->line && memcmp(a->x, b->x, sizeof a->x);
  if (a->line == b->line) return 0;
  return !((a->c0 != UINT32_MAX && (a->c0 == b->c0 || a->c0 == b->c1)) ||
           (a->c1 != UINT32_MAX && (a->c1 == b->c0 || a->c1 == b->c1)));
}

int mx_feature_apart_boxes(mx_mesher *m, double root_side) {
  mx_free(m->feature_boxes);
  m->feature_boxes = NULL;
  m->nfeature_boxes = 0;
  const mx_feature_lines *L = &m->feat_lines;
  const int base = m->feature_level > m->p.surface_level ? m->feature_level : m->p.surface_level;
  if (!m->have_features || base <= 0 || !(root_side > 0.0) || (!L->nlines && !L->ncorners))
    return MX_OK;
  const double step = 0.5 * ldexp(root_side, -base);
  /* the samples, counted then made */
  size_t n = L->ncorners;
  for (size_t i = 0; i < L->nlines && APART_LINES; i++) {
    const size_t np = L->first[i + 1] - L->first[i];
    for (size_t k = 0; k + 1 < np + (L->loop[i] ? 1 : 0); k++) {
      const double *a = L->xyz + 3 * (L->first[i] + k), *b = L->xyz + 3 * (L->first[i] + (k + 1) % np);
      n += 1 + (size_t)(dist3(a, b) / step);
    }
    n++;
  }
  sample *s = mx_alloc((n + 1) * sizeof *s);
  uint32_t *order = mx_alloc((n + 1) * sizeof *order);
  int8_t *want = mx_alloc(n + 1);
  if (!s || !order || !want) {
    mx_free(s);
    mx_free(order);
    mx_free(want);
    return MX_ENOMEM;
  }
  size_t k = 0;
  for (size_t c = 0; c < L->ncorners; c++) {
    memcpy(s[k].x, L->corner + 3 * c, sizeof s[k].x);
    s[k].line = s[k].c0 = s[k].c1 = UINT32_MAX;
    k++;
  }
  for (size_t i = 0; i < L->nlines && APART_LINES; i++) {
    const size_t f = L->first[i], np = L->first[i + 1] - f;
    const uint32_t c0 = L->loop[i] ? UINT32_MAX : corner_at(L, L->xyz + 3 * f);
    const uint32_t c1 = L->loop[i] ? UINT32_MAX : corner_at(L, L->xyz + 3 * (f + np - 1));
    for (size_t q = 0; q + 1 < np + (L->loop[i] ? 1 : 0); q++) {
      const double *a = L->xyz + 3 * (f + q), *b = L->xyz + 3 * (f + (q + 1) % np);
      const size_t parts = 1 + (size_t)(dist3(a, b) / step);
      for (size_t j = 0; j < parts; j++) {
        const double t = (double)j / (double)parts;
        for (int d = 0; d < 3; d++) s[k].x[d] = a[d] + t * (b[d] - a[d]);
        s[k].line = (uint32_t)i;
        s[k].c0 = c0;
        s[k].c1 = c1;
        k++;
      }
    }
    if (!L->loop[i]) { /* the last point */
      memcpy(s[k].x, L->xyz + 3 * (f + np - 1), sizeof s[k].x);
      s[k].line = (uint32_t)i;
      s[k].c0 = c0;
      s[k].c1 = c1;
      k++;
    }
  }
  n = k;
  /* each sample's nearest conflicting one, by x, and its level */
  sample *sorted = mx_alloc((n + 1) * sizeof *sorted);
  if (!sorted) {
    mx_free(s);
    mx_free(order);
    mx_free(want);
    return MX_ENOMEM;
  }
  memcpy(sorted, s, n * sizeof *s);
  qsort(sorted, n, sizeof *sorted, cmp_x);
  size_t nbox = 0;
  for (size_t i = 0; i < n; i++) {
    /* s[i] in sorted: found by a binary search on x, then scanned both ways */
    size_t lo = 0, hi = n;
    while (lo < hi) {
      const size_t mid = (lo + hi) / 2;
      if (sorted[mid].x[0] < s[i].x[0]) lo = mid + 1;
      else hi = mid;
    }
    double best = INFINITY;
    for (size_t j = lo; j < n && sorted[j].x[0] - s[i].x[0] < best; j++)
      if (conflict(&s[i], &sorted[j])) best = fmin(best, dist3(s[i].x, sorted[j].x));
    for (size_t j = lo; j-- > 0 && s[i].x[0] - sorted[j].x[0] < best;)
      if (conflict(&s[i], &sorted[j])) best = fmin(best, dist3(s[i].x, sorted[j].x));
    int level = base;
    while (level < base + APART_EXTRA && level < MX_MAX_LEVEL &&
           ldexp(root_side, -level) > FEATURE_SPACING * best)
      level++;
    want[i] = (int8_t)(level > base ? level : 0);
  }
  /* boxes: runs of one line's samples at one level, RUN_MAX at most */
  mx_box_region *b = mx_alloc((n + 1) * sizeof *b);
  if (!b) {
    mx_free(s);
    mx_free(order);
    mx_free(want);
    mx_free(sorted);
    return MX_ENOMEM;
  }
  for (size_t i = 0; i < n;) {
    if (!want[i]) {
      i++;
      continue;
    }
    size_t j = i + 1;
    while (j < n && j - i < RUN_MAX && want[j] == want[i] && s[j].line == s[i].line &&
           s[i].line != UINT32_MAX)
      j++;
    const double eps = 1e-3 * ldexp(root_side, -want[i]);
    mx_box_region *r = &b[nbox++];
    for (int d = 0; d < 3; d++) {
      r->lo[d] = INFINITY;
      r->hi[d] = -INFINITY;
    }
    for (size_t q = i; q < j; q++)
      for (int d = 0; d < 3; d++) {
        r->lo[d] = fmin(r->lo[d], s[q].x[d] - eps);
        r->hi[d] = fmax(r->hi[d], s[q].x[d] + eps);
      }
    r->level = want[i];
    i = j;
  }
  mx_free(s);
  mx_free(order);
  mx_free(want);
  mx_free(sorted);
  if (!nbox) {
    mx_free(b);
    return MX_OK;
  }
  /* the user's boxes first, then these */
  mx_box_region *all = mx_alloc((m->nboxes + nbox) * sizeof *all);
  if (!all) {
    mx_free(b);
    return MX_ENOMEM;
  }
  if (m->nboxes) memcpy(all, m->boxes, m->nboxes * sizeof *all);
  memcpy(all + m->nboxes, b, nbox * sizeof *b);
  mx_free(b);
  m->feature_boxes = all;
  m->nfeature_boxes = m->nboxes + nbox;
  m->rec->S.feature_apart_boxes = nbox;
  return MX_OK;
}
