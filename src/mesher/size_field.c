/* The size field of the octree mesher (issue 27): the public calls over
 * the shared source (mesher/size_source.h), and the control space built
 * from it over the domain's box when the octree is (mx_mesher_size_space),
 * read by the refinement requests (kernels/requests.h). */
#include <math.h>

#include "kernels/estimate.h"
#include "mesher/mesher_impl.h"

void mx_mesher_size_free(mx_mesher *m) { mx_size_source_free(&m->size); }

int mx_mesher_set_size_function(mx_mesher *m, mx_size_fn f, void *user,
                                const mx_cspace_params *p) {
  mx_call c;
  mx_call_begin(m, &c);
  return mx_call_end(m, &c, mx_size_source_set_function(&m->size, f, user, p));
}

int mx_mesher_set_size_expr(mx_mesher *m, const char *text) {
  mx_call c;
  mx_call_begin(m, &c);
  return mx_call_end(m, &c, mx_size_source_set_expr(&m->size, text));
}

int mx_mesher_set_size_limits(mx_mesher *m, double hmin, double hmax) {
  mx_call c;
  mx_call_begin(m, &c);
  return mx_call_end(m, &c, mx_size_source_set_limits(&m->size, hmin, hmax));
}

/* The octree the field asks for, against the memory there is: the root
 * about the domain's largest extent, none finer than the deepest level. */
static int budget(mx_mesher *m) {
  const mx_cspace_params *q = &m->size.params;
  double root = 0.0;
  for (int a = 0; a < 3; a++) root = fmax(root, q->hi[a] - q->lo[a]);
  double hmin, at[3];
  const double cells = mx_size_source_cells(&m->size, 3, root, MX_MAX_LEVEL - 1, &hmin, at);
  const double need = mx_estimate_bytes_leaves((size_t)fmin(cells, 1e18), m->domain.nt,
                                               m->p.stage);
  const double avail = mx_available_bytes();
  const double limit = m->p.max_memory_mb > 0 ? m->p.max_memory_mb * 1048576.0 : avail;
  return mx_size_source_budget(&m->size, 3, cells, hmin, at, need, limit,
                               m->p.max_memory_mb > 0, "--max-memory");
}

int mx_mesher_size_space(mx_mesher *m) {
  if (!mx_size_source_given(&m->size) || m->size.cs) return MX_OK;
  double lo[3], hi[3];
  mx_trisoup_bbox(&m->domain, lo, hi);
  MX_CHECK(mx_size_source_build(&m->size, lo, hi, NULL, NULL));
  return budget(m);
}
