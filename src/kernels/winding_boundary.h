/* The boundary of the domain of the generalized winding number
 * (--repair-input): the parts of the input triangles that separate a point
 * where the winding number is above 1/2 from one where it is below.
 *
 * Where two bodies overlap or touch, parts of their surfaces lie inside the
 * union (the faces of one cube inside the other, the face two touching
 * cubes share): the winding number is above 1/2 on both sides of them, so
 * they bound nothing and must not attract the nodes of the mesh. Each input
 * triangle T is cut by the planes of the triangles that meet it
 * (mx_surface_meeting_pairs; a coplanar one cuts T along its edges) into
 * convex pieces that no other triangle crosses, so the winding number on
 * either side of a piece is the same all over it: it is evaluated once, at
 * the piece's centroid moved by eps along T's normal, forward and back,
 * eps = 1/100 of the piece's inradius (2 area / perimeter). A piece is kept
 * when the two values lie on different sides of 1/2, turned so that the
 * domain lies behind it (the winding number above 1/2 behind); of coplanar
 * pieces lying on each other (the faces two overlapping cubes share), only
 * the one of the smallest triangle is kept. Triangles that nothing meets
 * are classified whole (their pieces: the triangle, its vertices kept);
 * when the winding number takes whole values, once per set of such
 * triangles connected through edges used by exactly two of them (the
 * sides of a triangle are those of its neighbour across such an edge).
 *
 * The pieces bound the domain: their signed volume is the domain's where
 * the winding number takes only the values 0, 1, 2, ... (every edge of the
 * input used as often in each direction: closed bodies, touching or
 * overlapping); with holes the domain's boundary also runs across them,
 * where no triangle is.
 *
 * Cutting stops at 256 pieces per triangle (then the rest is classified as
 * it stands; counted in capped). The result does not depend on the thread
 * count, and not on the order of the triangles except for which of two
 * coplanar copies is kept. */
#ifndef MX_WINDING_BOUNDARY_H
#define MX_WINDING_BOUNDARY_H

#include <stddef.h>
#include <stdint.h>

#include "geom/distance.h"
#include "soa/trisoup.h"

typedef struct {
  size_t cut;        /* input triangles cut into several pieces */
  size_t pieces;     /* convex pieces classified (whole triangles included) */
  size_t kept;       /* pieces on the boundary */
  size_t inside;     /* pieces with the domain on both sides, dropped */
  size_t outside;    /* pieces with the domain on neither side, dropped */
  size_t copies;     /* boundary pieces lying on a kept coplanar one, dropped */
  size_t turned;     /* kept pieces turned to have the domain behind */
  size_t capped;     /* triangles whose cutting stopped at the limit */
  double area;       /* area of the kept pieces */
  int whole;         /* 1: the winding number takes whole values only (every
                        edge of the input, its points compared by
                        coordinates, used as often in each direction as
                        oriented by the index): the kept pieces then bound
                        the domain exactly */
  size_t queries;    /* winding number evaluations */
} mx_winding_boundary_stats;

/* s: the input (shell per triangle); W: the index of its triangles
 * [0, s->nt) with the orientation as given (mx_surface_index_build_given).
 * out (empty on entry) receives s's vertices, then the new corners of the
 * cut pieces, and the kept pieces as triangles (convex pieces as fans), in
 * the order of their input triangles, each with its input's shell;
 * out->nshells = s->nshells. MX_OK or MX_EINPUT (out of memory). */
int mx_winding_boundary(const mx_trisoup *s, const mx_surface_index *W, mx_trisoup *out,
                        mx_winding_boundary_stats *st);

#endif
