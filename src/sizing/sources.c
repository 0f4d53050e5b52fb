/* Discrete sources of a size field and the mesher's whole field
 * (src/sizing/sources.h). */
#include "sizing/sources.h"

#include <math.h>
#include <string.h>

#include "base/common.h"

enum { LEAF_MAX = 8 };

static double centre(const double *box, uint32_t i, int a) {
  return 0.5 * (box[6 * i + a] + box[6 * i + 3 + a]);
}

/* Orders idx[lo, hi) so that idx[k] is the k-th by (centre along a, index)
 * with the smaller ones before it: a quickselect, deterministic. */
static void select_k(uint32_t *idx, size_t lo, size_t hi, size_t k, const double *box, int a) {
  while (hi - lo > 1) {
    const size_t mid = lo + (hi - lo) / 2;
    const uint32_t pv = idx[mid];
    const double pc = centre(box, pv, a);
    idx[mid] = idx[hi - 1];
    idx[hi - 1] = pv;
    size_t s = lo;
    for (size_t i = lo; i < hi - 1; i++) {
      const double c = centre(box, idx[i], a);
      if (c < pc || (c == pc && idx[i] < pv)) {
        const uint32_t t = idx[i];
        idx[i] = idx[s];
        idx[s++] = t;
      }
    }
    idx[hi - 1] = idx[s];
    idx[s] = pv;
    if (s == k) return;
    if (k < s) hi = s;
    else lo = s + 1;
  }
}

typedef struct {
  mx_size_sources *s;
  const double *box, *h;
  uint32_t *idx;
  size_t next; /* next free node */
} builder;

/* Fills node i with the sources idx[a, b). */
static void build_node(builder *B, size_t i, size_t a, size_t b) {
  mx_size_sources *s = B->s;
  double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
  double clo[3] = {INFINITY, INFINITY, INFINITY}, chi[3] = {-INFINITY, -INFINITY, -INFINITY};
  double m = INFINITY;
  for (size_t k = a; k < b; k++) {
    const uint32_t j = B->idx[k];
    for (int d = 0; d < 3; d++) {
      lo[d] = fmin(lo[d], B->box[6 * j + d]);
      hi[d] = fmax(hi[d], B->box[6 * j + 3 + d]);
      const double c = centre(B->box, j, d);
      clo[d] = fmin(clo[d], c);
      chi[d] = fmax(chi[d], c);
    }
    m = fmin(m, B->h[j]);
  }
  memcpy(s->nlo + 3 * i, lo, sizeof lo);
  memcpy(s->nhi + 3 * i, hi, sizeof hi);
  s->nmin[i] = m;
  if (b - a <= LEAF_MAX) {
    s->first[i] = (uint32_t)a;
    s->count[i] = (uint32_t)(b - a);
    return;
  }
  int ax = 0;
  for (int d = 1; d < 3; d++)
    if (chi[d] - clo[d] > chi[ax] - clo[ax]) ax = d;
  const size_t mid = a + (b - a) / 2;
  select_k(B->idx, a, b, mid, B->box, ax);
  const size_t c = B->next;
  B->next += 2;
  s->first[i] = (uint32_t)c;
  s->count[i] = 0;
  build_node(B, c, a, mid);
  build_node(B, c + 1, mid, b);
}

void mx_size_sources_free(mx_size_sources *s) {
  if (!s) return;
  mx_free(s->box);
  mx_free(s->h);
  mx_free(s->w);
  mx_free(s->dim);
  mx_free(s->nlo);
  mx_free(s->nhi);
  mx_free(s->nmin);
  mx_free(s->first);
  mx_free(s->count);
  mx_free(s);
}

int mx_size_sources_build(const double *box, const double *h, const double *w,
                          const uint8_t *dim, size_t n, double beta, mx_size_sources **out) {
  *out = NULL;
  if (!(beta > 1.0 && beta < INFINITY)) {
    mx_error(NULL, 0, "size field: the gradation must be a finite ratio above 1, not %g", beta);
    return MX_EINPUT;
  }
  if (n == 0 || n > UINT32_MAX / 2) {
    mx_error(NULL, 0, "size field: %zu sources (1 to %u)", n, UINT32_MAX / 2);
    return MX_EINPUT;
  }
  for (size_t i = 0; i < n; i++) {
    int ok = h[i] > 0.0 && h[i] < INFINITY;
    for (int d = 0; d < 3 && ok; d++)
      ok = isfinite(box[6 * i + d]) && isfinite(box[6 * i + 3 + d]) &&
           box[6 * i + d] <= box[6 * i + 3 + d];
    if (!ok) {
      mx_error(NULL, 0, "size field: source %zu at (%g, %g, %g) has size %g: sizes must be "
                        "finite and positive, at finite places", i, box[6 * i], box[6 * i + 1],
               box[6 * i + 2], h[i]);
      return MX_EINPUT;
    }
  }
  const double t0 = mx_wtime();
  mx_size_sources *s = mx_calloc(sizeof *s);
  if (!s) return MX_ENOMEM;
  s->n = n;
  s->slope = beta - 1.0;
  const size_t cap = 2 * ((n + LEAF_MAX - 1) / LEAF_MAX) * 2 + 1;
  uint32_t *idx = mx_alloc(n * sizeof *idx);
  s->box = mx_alloc(6 * n * sizeof *s->box);
  s->h = mx_alloc(n * sizeof *s->h);
  s->w = w ? mx_alloc(n * sizeof *s->w) : NULL;
  s->dim = w && dim ? mx_alloc(n * sizeof *s->dim) : NULL;
  s->nlo = mx_alloc(3 * cap * sizeof *s->nlo);
  s->nhi = mx_alloc(3 * cap * sizeof *s->nhi);
  s->nmin = mx_alloc(cap * sizeof *s->nmin);
  s->first = mx_alloc(cap * sizeof *s->first);
  s->count = mx_alloc(cap * sizeof *s->count);
  if (!idx || !s->box || !s->h || (w && !s->w) || (w && dim && !s->dim) || !s->nlo || !s->nhi || !s->nmin ||
      !s->first || !s->count) {
    mx_free(idx);
    mx_size_sources_free(s);
    return MX_ENOMEM;
  }
  for (size_t i = 0; i < n; i++) idx[i] = (uint32_t)i;
  builder B = {s, box, h, idx, 1};
  build_node(&B, 0, 0, n);
  s->nnodes = B.next;
  for (size_t k = 0; k < n; k++) {
    memcpy(s->box + 6 * k, box + 6 * (size_t)idx[k], 6 * sizeof *box);
    s->h[k] = h[idx[k]];
    if (w) s->w[k] = w[idx[k]];
    if (s->dim) s->dim[k] = dim[idx[k]];
  }
  mx_free(idx);
  s->seconds = mx_wtime() - t0;
  *out = s;
  return MX_OK;
}

/* Distance between the boxes [alo, ahi] and [blo, bhi]. */
static double box_dist(const double *alo, const double *ahi, const double *blo,
                       const double *bhi) {
  double s = 0.0;
  for (int d = 0; d < 3; d++) {
    const double g = fmax(0.0, fmax(alo[d] - bhi[d], blo[d] - ahi[d]));
    s += g * g;
  }
  return sqrt(s);
}

double mx_size_sources_min_box(const mx_size_sources *s, const double lo[3],
                               const double hi[3]) {
  if (!s || !s->n) return INFINITY;
  uint32_t stack[128];
  int top = 0;
  stack[top++] = 0;
  double best = INFINITY;
  while (top > 0) {
    const uint32_t i = stack[--top];
    if (s->nmin[i] + s->slope * box_dist(s->nlo + 3 * i, s->nhi + 3 * i, lo, hi) >= best)
      continue;
    if (s->count[i]) {
      for (uint32_t k = s->first[i]; k < s->first[i] + s->count[i]; k++) {
        const double *b = s->box + 6 * (size_t)k;
        const double v = s->h[k] + s->slope * box_dist(b, b + 3, lo, hi);
        if (v < best) best = v;
      }
      continue;
    }
    const uint32_t c = s->first[i];
    const double d0 = s->nmin[c] + s->slope * box_dist(s->nlo + 3 * c, s->nhi + 3 * c, lo, hi);
    const double d1 =
        s->nmin[c + 1] + s->slope * box_dist(s->nlo + 3 * (c + 1), s->nhi + 3 * (c + 1), lo, hi);
    /* the nearer child on top: visited first */
    if (d0 <= d1) {
      stack[top++] = c + 1;
      stack[top++] = c;
    } else {
      stack[top++] = c;
      stack[top++] = c + 1;
    }
  }
  return best;
}

double mx_size_sources_at(const mx_size_sources *s, const double p[3]) {
  return mx_size_sources_min_box(s, p, p);
}

double mx_size_sources_min_box_direct(const mx_size_sources *s, const double lo[3],
                                      const double hi[3]) {
  double best = INFINITY;
  for (size_t k = 0; s && k < s->n; k++) {
    const double *b = s->box + 6 * k;
    best = fmin(best, s->h[k] + s->slope * box_dist(b, b + 3, lo, hi));
  }
  return best;
}

double mx_size_sources_cells(const mx_size_sources *s, double floor, double f, double *hmin,
                             double at[3]) {
  double cells = 0.0, least = INFINITY;
  size_t where = 0;
  for (size_t k = 0; s && k < s->n; k++) {
    const double h = fmax(s->h[k], floor) * f;
    if (s->h[k] < least) {
      least = s->h[k];
      where = k;
    }
    double c = 1.0;
    if (s->w) c = fmax(1.0, s->dim && s->dim[k] == 3 ? s->w[k] / (h * h * h)
                                                     : s->w[k] / (h * h));
    cells += c;
  }
  *hmin = least;
  for (int d = 0; d < 3; d++) at[d] = s && s->n ? s->box[6 * where + d] : 0.0;
  return 3.0 * cells;
}

static double clamp(const mx_size_field *F, double h) {
  if (F->hmin > 0.0 && h < F->hmin) h = F->hmin;
  if (F->hmax > 0.0 && h > F->hmax) h = F->hmax;
  return h;
}

double mx_size_field_min_box(const mx_size_field *F, const double lo[3], const double hi[3]) {
  double h = INFINITY;
  if (F->cs) h = mx_cspace_min_box(F->cs, lo, hi);
  if (F->src) h = fmin(h, mx_size_sources_min_box(F->src, lo, hi));
  return clamp(F, h);
}

double mx_size_field_at(const mx_size_field *F, const double p[3]) {
  double h = INFINITY;
  if (F->cs) {
    double v[3];
    mx_cspace_query(F->cs, p, v);
    h = fmin(v[0], fmin(v[1], v[2]));
  }
  if (F->src) h = fmin(h, mx_size_sources_at(F->src, p));
  return clamp(F, h);
}
