/* A mesher's size field (issue 27): the source, its bounds and the control
 * space built from them, shared by the octree and quadtree meshers
 * (mesher/size_source.h). */
#include "mesher/size_source.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "base/common.h"
#include "sizing/cspace.h"
#include "sizing/expr.h"

/* The meshers' control space unless told otherwise: a K_L kd-tree split by
 * s_S (the smallest leaf-valued trees in bench/cspace_bench.c). */
static void default_params(mx_cspace_params *q) {
  mx_cspace_params_default(q);
  q->split = MX_SPLIT_SUM;
}

/* The source dropped, the bounds kept. */
static void drop(mx_size_source *s) {
  mx_cspace_free(s->cs);
  s->cs = NULL;
  mx_expr_free(s->expr);
  s->expr = NULL;
  s->fn = NULL;
  s->user = NULL;
}

void mx_size_source_free(mx_size_source *s) {
  drop(s);
  memset(s, 0, sizeof *s);
}

int mx_size_source_set_function(mx_size_source *s, mx_size_fn f, void *user,
                                const mx_cspace_params *p) {
  mx_cspace_params q;
  default_params(&q);
  if (p) q = *p;
  MX_CHECK(mx_cs_params_check(&q, 0));
  drop(s);
  s->fn = f;
  s->user = user;
  s->params = q;
  return MX_OK;
}

/* An expression's sizes: the same along the three axes. */
static void expr_sizes(void *user, size_t n, const double *xyz, double *h) {
  mx_expr_eval_many((const mx_expr *)user, n, xyz, h);
  for (size_t i = n; i-- > 0;) h[3 * i] = h[3 * i + 1] = h[3 * i + 2] = h[i];
}

int mx_size_source_set_expr(mx_size_source *s, const char *text) {
  mx_size_fn f = text ? mx_size_builtin(text, NULL, NULL) : NULL;
  mx_expr *e = NULL;
  if (!f) MX_CHECK(mx_expr_compile(text, "size field", &e));
  mx_cspace_params q;
  default_params(&q);
  drop(s);
  s->fn = f ? f : expr_sizes;
  s->user = f ? NULL : e;
  s->expr = e;
  s->params = q;
  return MX_OK;
}

int mx_size_source_set_limits(mx_size_source *s, double hmin, double hmax) {
  if (!(hmin >= 0.0) || !(hmax >= 0.0) || !isfinite(hmin) || !isfinite(hmax) ||
      (hmin > 0.0 && hmax > 0.0 && hmin > hmax)) {
    mx_error(NULL, 0, "size field: bad bounds (least %g, largest %g): finite, not negative, "
                      "the least not above the largest", hmin, hmax);
    return MX_EINPUT;
  }
  mx_cspace_free(s->cs); /* rebuilt with the bounds */
  s->cs = NULL;
  s->min = hmin;
  s->max = hmax;
  return MX_OK;
}

int mx_size_source_given(const mx_size_source *s) { return s->fn || s->max > 0.0; }

void mx_size_source_eval(const mx_size_source *s, size_t n, const double *xyz, double *h) {
  if (s->fn) {
    s->fn(s->user, n, xyz, h);
  } else {
    for (size_t i = 0; i < 3 * n; i++) h[i] = s->max;
  }
}

void mx_size_source_clamp(const mx_size_source *s, size_t n, double *h) {
  for (size_t i = 0; i < 3 * n; i++) {
    if (s->min > 0.0 && h[i] < s->min) h[i] = s->min;
    if (s->max > 0.0 && h[i] > s->max) h[i] = s->max;
  }
}

/* The source clamped to the bounds (the source is the user). */
static void clamped(void *user, size_t n, const double *xyz, double *h) {
  const mx_size_source *s = user;
  mx_size_source_eval(s, n, xyz, h);
  mx_size_source_clamp(s, n, h);
}

int mx_size_source_build(mx_size_source *s, const double lo[3], const double hi[3], mx_size_fn f,
                         void *user) {
  if (!mx_size_source_given(s) || s->cs) return MX_OK;
  mx_cspace_params q = s->params;
  if (!s->fn) default_params(&q);
  for (int a = 0; a < 3; a++) {
    q.lo[a] = lo[a];
    q.hi[a] = hi[a];
    if (!(q.hi[a] > q.lo[a])) { /* a flat domain: the field over a slab */
      q.lo[a] -= 0.5;
      q.hi[a] += 0.5;
    }
  }
  s->params = q;
  return f ? mx_cspace_build(&q, f, user, &s->cs) : mx_cspace_build(&q, clamped, s, &s->cs);
}

double mx_size_source_cells(const mx_size_source *s, int dim, double root, int max_level,
                            double *hmin, double at[3]) {
  return mx_cspace_cells(s->cs, dim, ldexp(root, -max_level), 0.7, hmin, at);
}

int mx_size_source_budget(mx_size_source *s, int dim, double cells, double hmin,
                          const double at[3], double need, double limit, int limit_given,
                          const char *limit_name) {
  if (!(limit > 0.0) || !(need > limit)) return MX_OK;
  char where[128], who[64];
  if (dim == 2) snprintf(where, sizeof where, "%.6g, %.6g", at[0], at[1]);
  else snprintf(where, sizeof where, "%.6g, %.6g, %.6g", at[0], at[1], at[2]);
  if (limit_given && limit_name) snprintf(who, sizeof who, "%s allows", limit_name);
  else snprintf(who, sizeof who, "%s", limit_given ? "the limit is" : "the machine has");
  mx_error(NULL, 0, "the size field asks for about %.3g %s (its least size %.3g, at (%s)): "
                    "about %.0f MB, but %s %.0f MB; raise the sizes (--size-min)%s%s",
           cells, dim == 2 ? "quadrants" : "octants", hmin, where, need / 1048576.0, who,
           limit / 1048576.0, limit_name ? " or " : "", limit_name ? limit_name : "");
  mx_cspace_free(s->cs);
  s->cs = NULL;
  return MX_ENOMEM;
}

double mx_size_source_at(const mx_size_source *s, const double p[3]) {
  double h[3];
  mx_cspace_query(s->cs, p, h);
  return fmin(h[0], fmin(h[1], h[2]));
}
