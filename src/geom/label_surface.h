/* The interfaces of a label image smoothed (issue 28,
 * src/geom/label_surface.c). The voxel faces between two labels form one
 * surface of the lattice (a "voxel staircase"); its corners are relaxed
 * towards the average of their neighbours on it (Taubin's lambda|mu
 * smoothing, which keeps the volume a Laplacian smoothing shrinks), each
 * corner kept within `clamp` voxel of where it was on every axis, so no
 * corner leaves the voxels around it and two interfaces a voxel apart stay
 * apart. Where three labels or more meet (a lattice edge of three voxel
 * faces or four) the corners move along that junction only, and the ends
 * of junctions stay.
 *
 * The image is the padded one of geom/label_fix.h (n: its dims; corner
 * (i, j, k) is the lowest corner of voxel (i, j, k)), with its contacts
 * removed. */
#ifndef MX_LABEL_SURFACE_H
#define MX_LABEL_SURFACE_H

#include <stddef.h>
#include <stdint.h>

typedef struct {
  size_t nv;
  int64_t *corner; /* nv: the corners on an interface, ascending */
  double *lat;     /* nv x 3: where the smoothing put them, in lattice
                    * coordinates (corner (i, j, k) at (i, j, k)) */
  size_t junction_vertices, fixed_vertices;
  double max_move; /* the largest move on an axis, in voxels */
} mx_label_surface;

/* MX_OK, MX_ENOMEM. rounds: Taubin rounds (0: the corners as they are). */
int mx_label_surface_build(const int32_t *lab, const int64_t n[3], int rounds, double clamp,
                           mx_label_surface *S);
void mx_label_surface_free(mx_label_surface *S);

#endif
