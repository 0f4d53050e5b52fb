/* Discrete sources of a size field (issue 27): sizes given at points or on
 * boxes (the curvature and thickness of the input surface, a solver's size
 * map, the leaves of a control space being graded), and the field they
 * define with a gradation ratio beta:
 *
 *   h(x) = min_i ( h_i + (beta - 1) dist(x, B_i) )
 *
 * the largest field that holds every source's size on its box and grows by
 * at most beta from an element to its neighbour (slope beta - 1: the
 * paper's "inserting a discrete metric source" and "adjusting metric
 * gradation"; a point source is a box of zero extent). Stored as a kd-tree
 * over the sources (median splits along the longest axis, leaves of at
 * most 8 sources), each node keeping its sources' bounding box and least
 * size, so the least value over a box is a branch-and-bound descent: a node
 * is skipped when its least size plus the slope times its distance to the
 * box is not below the best found. Queries are exact, allocation-free and
 * read-only (parallel); the build is serial and deterministic.
 *
 * The whole field of the mesher (mx_size_field) is the minimum of the
 * control space of its function source and of these sources, clamped to
 * [hmin, hmax]. */
#ifndef MX_SIZING_SOURCES_H
#define MX_SIZING_SOURCES_H

#include <stddef.h>
#include <stdint.h>

#include "mixoct.h"

typedef struct mx_size_sources mx_size_sources;

struct mx_size_sources {
  size_t n;        /* sources */
  double slope;    /* beta - 1 > 0 */
  double *box;     /* 6 n: lo x y z, hi x y z of each source, in tree order */
  double *h;       /* n: sizes, in tree order */
  double *w;       /* n: measure (area or volume) for the estimate, or NULL */
  uint8_t *dim;    /* NULL, or n: 2 area, 3 volume */
  size_t nnodes;
  double *nlo, *nhi; /* 3 per node */
  double *nmin;      /* per node: least size below */
  uint32_t *first, *count; /* count 0: internal, children first, first + 1 */
  double seconds;
};

/* Builds the sources' tree from n >= 1 boxes (6 each: lo, hi; a point has
 * lo == hi) with sizes h (finite, > 0) and gradation ratio beta (> 1,
 * finite). w: each source's measure (area when dim[i] is 2, volume when 3),
 * for the memory estimate, or NULL (dim then unused). MX_OK, MX_EINPUT (message), MX_ENOMEM. */
int mx_size_sources_build(const double *box, const double *h, const double *w,
                          const uint8_t *dim, size_t n, double beta, mx_size_sources **out);
void mx_size_sources_free(mx_size_sources *s);
/* The least value of the field over [lo, hi] (INFINITY without sources). */
double mx_size_sources_min_box(const mx_size_sources *s, const double lo[3],
                               const double hi[3]);
/* The field at p. */
double mx_size_sources_at(const mx_size_sources *s, const double p[3]);
/* The same by brute force over every source (tests). */
double mx_size_sources_min_box_direct(const mx_size_sources *s, const double lo[3],
                                      const double hi[3]);
/* About how many cubes of side f * max(h, floor) the sources ask for:
 * each source's measure over the cube's face (dim 2) or volume (dim 3),
 * at least one; times 3 for the graded layers around them. *hmin, *at: the
 * least size and where. */
double mx_size_sources_cells(const mx_size_sources *s, double floor, double f, double *hmin,
                             double at[3]);

/* The mesher's field: the function's control space (or NULL) and the
 * discrete sources (or NULL), clamped to [hmin, hmax] (0: no clamp). */
typedef struct {
  const mx_cspace *cs;
  const mx_size_sources *src;
  double hmin, hmax;
  double lo[3], hi[3]; /* the box the field covers */
} mx_size_field;

double mx_size_field_min_box(const mx_size_field *F, const double lo[3], const double hi[3]);
double mx_size_field_at(const mx_size_field *F, const double p[3]);

#endif
