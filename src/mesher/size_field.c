/* The size field of a mesher (issue 27): its source (a function, the
 * paper's test functions, an expression) and the control space built from
 * it over the domain's box when the octree is (mx_mesher_size_space), read
 * by the refinement requests (kernels/requests.h). */
#include <math.h>
#include <string.h>

#include "base/common.h"
#include "kernels/estimate.h"
#include "mesher/mesher_impl.h"
#include "sizing/cspace.h"
#include "sizing/expr.h"

/* The mesher's control space unless told otherwise: a K_L kd-tree split by
 * s_S (the smallest leaf-valued trees in bench/cspace_bench.c). */
static void default_params(mx_cspace_params *q) {
  mx_cspace_params_default(q);
  q->split = MX_SPLIT_SUM;
}

static void drop(mx_mesher *m) {
  mx_cspace_free(m->size_cs);
  m->size_cs = NULL;
  mx_expr_free(m->size_expr);
  m->size_expr = NULL;
  m->size_fn = NULL;
  m->size_user = NULL;
}

void mx_mesher_size_free(mx_mesher *m) { drop(m); }

int mx_mesher_set_size_function(mx_mesher *m, mx_size_fn f, void *user,
                                const mx_cspace_params *p) {
  mx_call c;
  mx_call_begin(m, &c);
  mx_cspace_params q;
  default_params(&q);
  if (p) q = *p;
  const int st = mx_cs_params_check(&q, 0);
  if (!st) {
    drop(m);
    m->size_fn = f;
    m->size_user = user;
    m->size_params = q;
  }
  return mx_call_end(m, &c, st);
}

/* An expression's sizes: the same along the three axes. */
static void expr_sizes(void *user, size_t n, const double *xyz, double *h) {
  mx_expr_eval_many((const mx_expr *)user, n, xyz, h);
  for (size_t i = n; i-- > 0;) h[3 * i] = h[3 * i + 1] = h[3 * i + 2] = h[i];
}

int mx_mesher_set_size_expr(mx_mesher *m, const char *text) {
  mx_call c;
  mx_call_begin(m, &c);
  mx_size_fn f = text ? mx_size_builtin(text, NULL, NULL) : NULL;
  mx_expr *e = NULL;
  int st = MX_OK;
  if (!f) st = mx_expr_compile(text, "size field", &e);
  if (!st) {
    mx_cspace_params q;
    default_params(&q);
    drop(m);
    m->size_fn = f ? f : expr_sizes;
    m->size_user = f ? NULL : e;
    m->size_expr = e;
    m->size_params = q;
  }
  return mx_call_end(m, &c, st);
}

int mx_mesher_set_size_limits(mx_mesher *m, double hmin, double hmax) {
  mx_call c;
  mx_call_begin(m, &c);
  int st = MX_OK;
  if (!(hmin >= 0.0) || !(hmax >= 0.0) || !isfinite(hmin) || !isfinite(hmax) ||
      (hmin > 0.0 && hmax > 0.0 && hmin > hmax)) {
    mx_error(NULL, 0, "size field: bad bounds (least %g, largest %g): finite, not negative, "
                      "the least not above the largest", hmin, hmax);
    st = MX_EINPUT;
  }
  if (!st) {
    mx_cspace_free(m->size_cs); /* rebuilt with the bounds */
    m->size_cs = NULL;
    m->size_min = hmin;
    m->size_max = hmax;
  }
  return mx_call_end(m, &c, st);
}

/* The source clamped to the bounds (the mesher is the user). */
static void clamped(void *user, size_t n, const double *xyz, double *h) {
  const mx_mesher *m = user;
  if (m->size_fn) {
    m->size_fn(m->size_user, n, xyz, h);
  } else {
    for (size_t i = 0; i < 3 * n; i++) h[i] = m->size_max;
  }
  for (size_t i = 0; i < 3 * n; i++) {
    if (m->size_min > 0.0 && h[i] < m->size_min) h[i] = m->size_min;
    if (m->size_max > 0.0 && h[i] > m->size_max) h[i] = m->size_max;
  }
}

/* The octree the field asks for, against the memory there is: before
 * refining (an octree refined to a tiny size would fill the machine
 * first). Octants of level L have side root / 2^L; the root about the
 * domain's largest extent; a size h asks for a side in (h/2, h], about
 * 0.7 h; none finer than the deepest level. */
static int budget(mx_mesher *m, const mx_cspace_params *q) {
  double root = 0.0;
  for (int a = 0; a < 3; a++) root = fmax(root, q->hi[a] - q->lo[a]);
  double hmin, at[3];
  const double floor = ldexp(root, -(MX_MAX_LEVEL - 1));
  const double cells = mx_cspace_cells(m->size_cs, floor, 0.7, &hmin, at);
  const double need = mx_estimate_bytes_leaves((size_t)fmin(cells, 1e18), m->domain.nt,
                                               m->p.stage);
  const double avail = mx_available_bytes();
  const double limit = m->p.max_memory_mb > 0 ? m->p.max_memory_mb * 1048576.0 : avail;
  if (limit > 0.0 && need > limit) {
    mx_error(NULL, 0, "the size field asks for about %.3g octants (its least size %.3g, at "
                      "(%.6g, %.6g, %.6g)): about %.0f MB, but %s %.0f MB; raise the sizes "
                      "(--size-min) or --max-memory", cells, hmin, at[0], at[1], at[2],
             need / 1048576.0, m->p.max_memory_mb > 0 ? "--max-memory allows" : "the machine has",
             limit / 1048576.0);
    mx_cspace_free(m->size_cs);
    m->size_cs = NULL;
    return MX_ENOMEM;
  }
  return MX_OK;
}

int mx_mesher_size_space(mx_mesher *m) {
  if ((!m->size_fn && !(m->size_max > 0.0)) || m->size_cs) return MX_OK;
  mx_cspace_params q = m->size_params;
  if (!m->size_fn) default_params(&q);
  mx_trisoup_bbox(&m->domain, q.lo, q.hi);
  for (int a = 0; a < 3; a++)
    if (!(q.hi[a] > q.lo[a])) { /* a flat domain: the field over a slab */
      q.lo[a] -= 0.5;
      q.hi[a] += 0.5;
    }
  if (!m->size_fn) m->size_params = q;
  MX_CHECK(m->size_min > 0.0 || m->size_max > 0.0
               ? mx_cspace_build(&q, clamped, m, &m->size_cs)
               : mx_cspace_build(&q, m->size_fn, m->size_user, &m->size_cs));
  return budget(m, &q);
}
