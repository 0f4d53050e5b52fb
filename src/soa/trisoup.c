/* The triangle soup: growth, concatenation, removal and bounding box. */
#include "soa/trisoup.h"

#include <string.h>

#include "base/common.h"

void mx_trisoup_free(mx_trisoup *s) {
  if (!s) return;
  mx_free(s->x);
  mx_free(s->y);
  mx_free(s->z);
  mx_free(s->tri);
  mx_free(s->shell);
  mx_free(s->face);
  mx_free(s->run);
  memset(s, 0, sizeof *s);
}

/* Geometric growth so that repeated small reservations stay amortised O(1). */
static size_t grown(size_t cap, size_t need) {
  size_t c = cap + cap / 2;
  if (c < 16) c = 16;
  return c > need ? c : need;
}

/* p grown to n items of the given size, or NULL (p is then untouched, so
 * the soup stays consistent). */
static void *resize(void *p, size_t n, size_t item) {
  if (n > SIZE_MAX / item) {
    mx_error(NULL, 0, "out of memory (array of %zu items)", n);
    return NULL;
  }
  return mx_realloc(p, n * item);
}

static int reserve_vertices(mx_trisoup *s, size_t nv) {
  if (nv <= s->cap_v) return MX_OK;
  if (nv > (size_t)UINT32_MAX) {
    mx_error(NULL, 0, "too many vertices (%zu): indices are 32-bit", nv);
    return MX_EINPUT;
  }
  size_t cap = grown(s->cap_v, nv);
  if (cap > (size_t)UINT32_MAX) cap = (size_t)UINT32_MAX;
  double *x = resize(s->x, cap, sizeof *x);
  if (!x) return MX_ENOMEM;
  s->x = x;
  double *y = resize(s->y, cap, sizeof *y);
  if (!y) return MX_ENOMEM;
  s->y = y;
  double *z = resize(s->z, cap, sizeof *z);
  if (!z) return MX_ENOMEM;
  s->z = z;
  s->cap_v = cap;
  return MX_OK;
}

static int reserve_triangles(mx_trisoup *s, size_t nt) {
  if (nt <= s->cap_t) return MX_OK;
  if (nt > SIZE_MAX / (3 * sizeof(uint32_t))) {
    mx_error(NULL, 0, "too many triangles (%zu)", nt);
    return MX_EINPUT;
  }
  size_t cap = grown(s->cap_t, nt);
  uint32_t *tri = resize(s->tri, 3 * cap, sizeof *tri);
  if (!tri) return MX_ENOMEM;
  s->tri = tri;
  uint16_t *shell = resize(s->shell, cap, sizeof *shell);
  if (!shell) return MX_ENOMEM;
  s->shell = shell;
  uint32_t *face = resize(s->face, cap, sizeof *face);
  if (!face) return MX_ENOMEM;
  s->face = face;
  /* a soup filled directly (tri and nt) has one face a triangle */
  for (size_t t = s->cap_t; t < cap; t++) face[t] = t < UINT32_MAX ? (uint32_t)t : UINT32_MAX;
  s->cap_t = cap;
  return MX_OK;
}

int mx_trisoup_reserve(mx_trisoup *s, size_t nv, size_t nt) {
  MX_CHECK(reserve_vertices(s, nv));
  return reserve_triangles(s, nt);
}

int mx_trisoup_append(mx_trisoup *dst, const mx_trisoup *src) {
  if (dst->nshells == UINT16_MAX) {
    mx_error(NULL, 0, "too many input surfaces (at most %d)", UINT16_MAX);
    return MX_EINPUT;
  }
  if (src->nv > (size_t)UINT32_MAX - dst->nv) {
    mx_error(NULL, 0, "too many vertices in total: indices are 32-bit");
    return MX_EINPUT;
  }
  MX_CHECK(mx_trisoup_reserve(dst, dst->nv + src->nv, dst->nt + src->nt));
  if (src->nv > 0) {
    size_t bytes = src->nv * sizeof(double);
    memcpy(dst->x + dst->nv, src->x, bytes);
    memcpy(dst->y + dst->nv, src->y, bytes);
    memcpy(dst->z + dst->nv, src->z, bytes);
  }
  uint32_t off = (uint32_t)dst->nv;
  for (size_t i = 0; i < 3 * src->nt; i++)
    dst->tri[3 * dst->nt + i] = src->tri[i] + off;
  for (size_t i = 0; i < src->nt; i++) dst->shell[dst->nt + i] = dst->nshells;
  if (src->nt > 0) memcpy(dst->face + dst->nt, src->face, src->nt * sizeof *src->face);
  MX_CHECK(mx_trisoup_append_runs(dst, src));
  dst->nv += src->nv;
  dst->nt += src->nt;
  dst->nshells++;
  return MX_OK;
}

/* All vertices count, used or not. An empty soup gives lo = hi = 0. */
void mx_trisoup_bbox(const mx_trisoup *s, double lo[3], double hi[3]) {
  if (s->nv == 0) {
    for (int d = 0; d < 3; d++) lo[d] = hi[d] = 0.0;
    return;
  }
  const double *c[3] = {s->x, s->y, s->z};
  for (int d = 0; d < 3; d++) {
    double mn = c[d][0], mx = c[d][0];
    for (size_t i = 1; i < s->nv; i++) {
      double v = c[d][i];
      mn = v < mn ? v : mn;
      mx = v > mx ? v : mx;
    }
    lo[d] = mn;
    hi[d] = mx;
  }
}

int mx_trisoup_add_face_triangle(mx_trisoup *s, uint32_t a, uint32_t b, uint32_t c,
                                 uint32_t face) {
  if (s->nt >= s->cap_t) MX_CHECK(mx_trisoup_reserve(s, 0, s->nt + 1));
  uint32_t *t = s->tri + 3 * s->nt;
  t[0] = a;
  t[1] = b;
  t[2] = c;
  s->face[s->nt] = face;
  s->shell[s->nt++] = 0;
  return MX_OK;
}

int mx_trisoup_add_triangle(mx_trisoup *s, uint32_t a, uint32_t b, uint32_t c) {
  const uint32_t face = s->nt < UINT32_MAX ? (uint32_t)s->nt : UINT32_MAX;
  return mx_trisoup_add_face_triangle(s, a, b, c, face);
}

size_t mx_trisoup_remove_if(mx_trisoup *s, int (*drop)(const mx_trisoup *s, size_t t, void *ctx),
                            void *ctx) {
  size_t kept = 0, r = 0;
  for (size_t i = 0; i < s->nt; i++) {
    for (; r < s->nrun && s->run[r].t0 <= i; r++) s->run[r].t0 = (uint32_t)kept;
    if (drop(s, i, ctx)) continue;
    if (kept != i) {
      memmove(s->tri + 3 * kept, s->tri + 3 * i, 3 * sizeof *s->tri);
      s->shell[kept] = s->shell[i];
      s->face[kept] = s->face[i];
    }
    kept++;
  }
  for (; r < s->nrun; r++) s->run[r].t0 = (uint32_t)kept;
  mx_trisoup_drop_empty_runs(s);
  const size_t removed = s->nt - kept;
  s->nt = kept;
  return removed;
}

int mx_trisoup_set_vertex(mx_trisoup *s, size_t i, const double c[3]) {
  if (i >= s->cap_v) MX_CHECK(mx_trisoup_reserve(s, i + 1, 0));
  s->x[i] = c[0];
  s->y[i] = c[1];
  s->z[i] = c[2];
  if (s->nv < i + 1) s->nv = i + 1;
  return MX_OK;
}
