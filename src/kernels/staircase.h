/* Line 14 of Algorithm 1 (2015 paper), "decrease staircase effect". */
#ifndef MX_STAIRCASE_H
#define MX_STAIRCASE_H

#include "kernels/surface_patterns.h"

/* Staircase reduction: put back the optional elements with J_ENS > q_min
 * (0.2 in the paper), computed at the current node positions (after the
 * shrink). They are appended to M. */
int mx_staircase(mx_mesh *M, const mx_optional *opt, double q_min,
                 mx_surface_stats *stats);

#endif
