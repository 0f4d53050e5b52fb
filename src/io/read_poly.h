/* The readers of the 2D mesher's inputs: polylines (src/io/read_poly.c)
 * and refinement boxes (src/io/read_qboxes.c). */
#ifndef MX_READ_POLY_H
#define MX_READ_POLY_H

#include <stddef.h>

#include "soa/poly.h"

/* Readers: .poly (Triangle's format: vertices, segments, holes; '#'
 * comments; indices from the first vertex number, 0 or 1), .off (each face a
 * closed polygon, z ignored, must be 0), and 2D .mdl. Bad input: MX_EINPUT
 * with a message naming the file and line. By extension: mx_read_poly_any. */
int mx_read_poly(const char *path, mx_poly *P);
int mx_read_poly_off(const char *path, mx_poly *P);
int mx_read_poly_mdl(const char *path, mx_poly *P);
int mx_read_poly_any(const char *path, mx_poly *P);
/* Refinement boxes (io/read_qboxes.c): 'n_regions N', then per box
 * 'xmin ymin xmax ymax level'; '#' comments. *boxes allocated (mx_free). */
int mx_read_qboxes(const char *path, mx_qbox **boxes, size_t *n);

#endif
