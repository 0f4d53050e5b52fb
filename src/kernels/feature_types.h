/* What the feature placement reads and reports (kernels/feature_place.h,
 * kernels/feature_graph.h). */
#ifndef MX_FEATURE_TYPES_H
#define MX_FEATURE_TYPES_H

#include <stddef.h>
#include <stdint.h>

#include "geom/feature_walk.h"
#include "soa/trisoup.h"

typedef struct {
  const mx_feature_lines *L;
  /* the surface's triangles [0, nt) of soup and their patches (patch NULL:
   * no side step, the lines were given rather than found) */
  const mx_trisoup *soup;
  size_t nt;
  const uint32_t *patch;
  size_t npatches;
  /* > 0: only the boundary within this distance of the lines and corners
   * is looked at (a few octants at the feature level: the placement moves
   * no node farther); 0: all of it */
  double near;
  /* the tries again at the corners of the lines missed (0: none; a local
   * re-mesh's patch, whose lines run out of it, takes none) */
  int retries;
} mx_feature_input;

typedef struct {
  size_t corners, corners_missed; /* corners placed; not (no node free near) */
  size_t lines, lines_missed;     /* lines followed by mesh edges; not */
  size_t nodes;                   /* nodes moved onto corners and lines */
  size_t sides;                   /* nodes moved onto their region's patch */
  size_t split;                   /* quadrilaterals split along a line */
  size_t unsplit;                 /* elements whose split was undone (give-up) */
  size_t given_up;                /* nodes put back (mx_feature_give_up) */
  size_t slid;                    /* feature nodes slid along their ridge instead */
  double seconds;
} mx_feature_stats;

/* The chains placed along the ridges: node[i]'s neighbours on its chain
 * are prev[i] and next[i] (sorted by node; the corners are not in it). */
typedef struct {
  size_t n;
  uint32_t *node, *prev, *next;
} mx_feature_chain;

void mx_feature_chain_free(mx_feature_chain *c);

#endif
