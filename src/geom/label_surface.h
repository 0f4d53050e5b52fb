/* The interfaces of a label image as one surface (issue 28,
 * src/geom/label_surface.c): every voxel face between two labels is a
 * quadrilateral of the lattice (a "voxel staircase"); its corners are then
 * relaxed towards the average of their neighbours on the surface (Taubin's
 * lambda|mu smoothing, which keeps the volume a Laplacian smoothing
 * shrinks), each corner kept within `clamp` voxel of where it was on every
 * axis so that no corner leaves the voxels around it and two interfaces a
 * voxel apart stay apart. Where three labels meet (a lattice edge of three
 * faces) the corners move along that junction only, and the ends of
 * junctions stay. Each quadrilateral becomes two triangles split by its
 * shorter diagonal. A triangle has two sides, each facing a label; a side
 * is kept for its label when it lies on an outer shell of a part of that
 * label (label not 0): the shells that bound holes are the outer shells of
 * what fills them.
 *
 * The image is the padded one of geom/label_fix.h (with its contacts
 * removed: every label's surface is then a manifold); A maps the unpadded
 * voxel centres to the world (read_image.h). */
#ifndef MX_LABEL_SURFACE_H
#define MX_LABEL_SURFACE_H

#include <stddef.h>
#include <stdint.h>

typedef struct {
  size_t nv, nt;
  double *xyz;    /* nv x 3, world */
  uint32_t *tri;  /* nt x 3; the normal points from label[2t] to label[2t+1] */
  int32_t *label; /* nt x 2 */
  uint8_t *keep;  /* nt: bit s set when side s is kept for label[2t+s] */
  int64_t *corner; /* nv: each vertex's padded corner, ascending */
  double *lat;     /* nv x 3: where the smoothing put it, in padded lattice
                    * coordinates (corner (i, j, k) is at (i, j, k)) */
  size_t junction_vertices, fixed_vertices;
  double max_move; /* the largest move of a corner, in voxels */
} mx_label_surface;

/* MX_OK, MX_ENOMEM. rounds: Taubin rounds (0: the voxel faces as they are). */
int mx_label_surface_build(const int32_t *lab, const int64_t n[3], const double A[12],
                           int rounds, double clamp, mx_label_surface *S);
void mx_label_surface_free(mx_label_surface *S);

#endif
