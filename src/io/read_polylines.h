/* The reader of explicit feature polylines (src/io/read_polylines.c), the
 * ridges and corners a mesh should keep given as lines rather than found on
 * a surface (issue 29, item 1).
 *
 * Format (CGAL's .polylines.txt): one polyline a line,
 *   n x1 y1 z1 x2 y2 z2 ... xn yn zn
 * with n >= 2 points; blank lines and lines starting with '#' are skipped
 * ('#' after the numbers starts a comment too). A polyline whose last point
 * equals its first is closed (a loop; 3 distinct points or more).
 *
 * The lines are welded where their points have equal coordinates, and the
 * corners are: the ends of open polylines where no other polyline goes on
 * (a point with one segment at it), the points where three segments or more
 * meet (three polyline ends, or a polyline's end on another's interior
 * point), and the points with two segments at them (an interior point, or
 * two polyline ends) where the line turns by more than angle_deg from
 * straight. Two polylines whose ends meet without a corner there are one
 * line through that point. The result (geom/features.h, mx_feature_lines)
 * runs corner to corner: polylines split at their interior corners, joined
 * where they meet without one; a loop with a corner on it becomes an open
 * line from that corner back to it; a loop without one stays a loop.
 * Order: geom/feature_walk.h, the points numbered as they first appear in
 * the file (a file of open polylines meeting only at corners comes back
 * line for line, in the file's order and direction).
 *
 * Errors (one message "FILE:LINE: ...", MX_EINPUT, *L left empty): a count
 * that is not an integer or below 2, a count more than the line can hold
 * (checked before anything is allocated for it), missing numbers, numbers
 * beyond the count, numbers that are not finite, a point repeating the one
 * before it, a closed polyline of fewer than 3 distinct points, a file with
 * no polyline, an angle not in [0, 180]. */
#ifndef MX_READ_POLYLINES_H
#define MX_READ_POLYLINES_H

#include "geom/feature_walk.h"

/* MX_OK, MX_EINPUT, MX_ENOMEM; free *L with mx_feature_lines_free (or
 * mx_feature_lines_walk_free of geom/feature_walk.h). */
int mx_read_polylines(const char *path, double angle_deg, mx_feature_lines *L);

#endif
