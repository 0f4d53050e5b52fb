/* The pieces of the materials' inputs (several materials, issue 26): the
 * regions a point can lie in, for the interfaces' stage
 * (kernels/interfaces.h), the cleaving (kernels/cleave.h) and the labels
 * (mesher/materials.c). */
#ifndef MX_PIECES_H
#define MX_PIECES_H

#include <stddef.h>
#include <stdint.h>

#include "geom/distance.h"
#include "soa/trisoup.h"

/* The pieces of the materials' inputs: each closed shell of each input file
 * is a piece, with its own index; a piece lies inside another (its parent,
 * the innermost containing it) or is a root. A point's piece is the
 * innermost containing it. The region (material index 1 ..) of a piece is
 * keyed by (depth, file): the first file at depth d gives region d + 1 (so
 * nested shells number their regions by depth, as the depth of one index
 * would), the other files at that depth get the next numbers after the
 * deepest. A piece is cleaved (an interface pass) when it is nested, or
 * shares triangles with another piece (touching inputs: two cubes glued on a
 * face); passes go by depth, then piece. */
typedef struct mx_interfaces_s {
  uint32_t npieces;
  int32_t *parent;         /* npieces: the parent piece, -1 for a root */
  uint16_t *depth;         /* npieces: 0 for a root */
  uint16_t *file;          /* npieces: the input file (the soup's shell id) */
  uint16_t *region;        /* npieces: region index, 1 .. nregions */
  uint32_t *pass;          /* npasses pieces to cleave, in order */
  uint32_t npasses;
  int nregions;
  mx_trisoup *soup;        /* npieces */
  mx_surface_index *index; /* npieces */
  /* npieces: the index of a touching piece's triangles shared with another
   * (its interface), NULL for the others (a nested piece's interface is
   * all of it) */
  mx_surface_index **iface;
  mx_trisoup *iface_soup;
} mx_interfaces;

/* The pieces of the triangles [0, nt) of src (soup shell ids: the files);
 * shared (NULL: none; one byte per triangle): 1 for the triangles two
 * files have in common. At most MX_MAX_PIECES pieces (MX_EINPUT, with a
 * message). MX_ENOMEM. */
enum { MX_MAX_PIECES = 1024 };
int mx_interfaces_build(mx_interfaces *I, const mx_trisoup *src, uint32_t nt,
                        const uint8_t *shared);
void mx_interfaces_free(mx_interfaces *I);
/* The innermost piece containing p, plus one; 0 outside every piece. */
int mx_interfaces_piece(const mx_interfaces *I, const double p[3]);
/* The piece (plus one) whose surface is nearest p: a point of the outer
 * boundary's own piece (the first at equal distances). */
int mx_interfaces_surface_piece(const mx_interfaces *I, const double p[3]);
/* The distance from p to the nearest piece's surface: within it, the
 * piece of a point is p's. */
double mx_interfaces_clearance(const mx_interfaces *I, const double p[3]);
/* 1 when piece q (a piece plus one, as above) lies in piece p's subtree. */
int mx_interfaces_within(const mx_interfaces *I, int q, uint32_t p);

#endif
