/* The input types of the 2D mesher: a set of polylines (mx_poly) and a
 * refinement box (mx_qbox), filled by io's readers (io/read_poly.h) and
 * used by quad/ (src/soa/poly.c: mx_poly_free). */
#ifndef MX_SOA_POLY_H
#define MX_SOA_POLY_H

#include <stddef.h>
#include <stdint.h>

#include "mixoct.h" /* MX_MAX_LEVEL2D */

/* The lattice: 2^MX_QMAX_LEVEL (2^28) units per root side, levels 0 to
 * MX_MAX_LEVEL2D (27, mixoct.h). */
#define MX_QMAX_LEVEL (MX_MAX_LEVEL2D + 1)

/* A set of polylines. For a domain every polyline is closed and oriented so
 * that the domain lies on the left of each segment (outer boundaries
 * counter-clockwise, holes clockwise: the outward normal is on the right).
 * A drawing's polylines may be open (they only drive refinement). */
typedef struct {
  size_t nv, ns;
  double *xy;        /* 2 per vertex */
  uint32_t *seg;     /* 2 per segment: from, to (vertex indices) */
  uint32_t *line;    /* per segment: the line of the input that defined it (messages) */
  size_t nholes;
  double *holes;     /* 2 per hole point (.poly); informative once oriented */
  size_t nloops;     /* closed polylines found by mx_poly_check_domain */
  char *path;        /* the file it came from (messages) */
} mx_poly;

void mx_poly_free(mx_poly *P);

/* A refinement box: [lo, hi] and the level asked inside it. */
typedef struct mx_qbox mx_qbox;
struct mx_qbox {
  double lo[2], hi[2];
  int level;
};

#endif
