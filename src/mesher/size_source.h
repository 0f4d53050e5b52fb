/* A mesher's size field (issue 27), shared by the octree mesher
 * (mesher/size_field.c) and the quadtree mesher (mesher/mesher2d_size.c):
 * its source (a C function, one of the paper's test functions F1..F5, an
 * expression), the bounds on its sizes (--size-min, --size-max), and the
 * control space built from them over a box (src/sizing/). The public calls
 * of both meshers are thin wrappers of these, so both check their
 * arguments alike and say the same things. */
#ifndef MX_SIZE_SOURCE_H
#define MX_SIZE_SOURCE_H

#include <stddef.h>

#include "mixoct.h"

struct mx_expr;

typedef struct {
  mx_size_fn fn;             /* the source; NULL: none (max > 0 alone is a field) */
  void *user;
  struct mx_expr *expr;      /* a source given as text: owned */
  mx_cspace_params params;   /* the control space's (its box set when built) */
  double min, max;           /* clamps of the field's sizes (0: none) */
  mx_cspace *cs;             /* built from the above; NULL until then */
} mx_size_source;

/* Everything freed, the source zeroed (no field). */
void mx_size_source_free(mx_size_source *s);
/* mx_mesher_set_size_function's work: p checked (NULL: the default, K_L
 * kd-tree split by s_S), the old source dropped. MX_EINPUT with a message. */
int mx_size_source_set_function(mx_size_source *s, mx_size_fn f, void *user,
                                const mx_cspace_params *p);
/* "F1".."F5" or an expression (MX_EINPUT with the column of a bad one). */
int mx_size_source_set_expr(mx_size_source *s, const char *text);
/* The bounds (0: none), checked: finite, not negative, not crossed. The
 * control space is built again with them. */
int mx_size_source_set_limits(mx_size_source *s, double hmin, double hmax);
/* Whether there is a field: a source, or the largest size alone. */
int mx_size_source_given(const mx_size_source *s);
/* The source's sizes at n points (3 a point), before the bounds: the
 * source's, or the largest size alone. */
void mx_size_source_eval(const mx_size_source *s, size_t n, const double *xyz, double *h);
/* The bounds applied to n points' sizes. */
void mx_size_source_clamp(const mx_size_source *s, size_t n, double *h);
/* s->cs over the box [lo, hi] (an axis of no extent widened to a slab of
 * side 1 about it), sampled from f(user), or with f NULL from the source
 * clamped to the bounds. Nothing to do without a field or with s->cs
 * built. MX_EINPUT (a size not finite and positive), MX_ENOMEM. */
int mx_size_source_build(mx_size_source *s, const double lo[3], const double hi[3], mx_size_fn f,
                         void *user);
/* The memory budget, before refining (a tree refined to a tiny size would
 * fill the machine first): the cells (dim 3: octants; 2: quadrants) the
 * field asks for, about the area or volume of each control-space leaf over
 * (0.7 h)^dim (a size h asks for a side in (h/2, h]), none finer than the
 * tree's deepest level (root / 2^max_level). *hmin, at: the least size and
 * where. */
double mx_size_source_cells(const mx_size_source *s, int dim, double root, int max_level,
                            double *hmin, double at[3]);
/* need bytes against limit (0 or less: no limit known): when over, the
 * message (naming the cells, the least size and where, the limit: the
 * user's when limit_given, else the machine's memory; limit_name: the
 * option that sets it, NULL: none) and MX_ENOMEM, the control space
 * freed. */
int mx_size_source_budget(mx_size_source *s, int dim, double cells, double hmin,
                          const double at[3], double need, double limit, int limit_given,
                          const char *limit_name);
/* The field at each of the points (the least of its three sizes): the cell
 * field target_size of both meshers' outputs. */
double mx_size_source_at(const mx_size_source *s, const double p[3]);

#endif
