/* Sharp features of an input surface (issue 29, item 1; src/geom/features.c):
 * ridges are the edges whose two triangles' normals part by more than a
 * threshold angle (the dihedral angle departs from flat by more than it),
 * and the edges of one triangle or of three or more (open or non-manifold);
 * corners are the vertices where a ridge ends, where three ridge edges or
 * more meet, or where a ridge turns by more than the threshold. Vertices
 * are welded by their coordinates first (an unwelded copy of a vertex is
 * the same vertex). A ridge, as counted, is a chain of ridge edges from
 * corner to corner, or a loop without one. */
#ifndef MX_FEATURES_H
#define MX_FEATURES_H

#include <stddef.h>
#include <stdint.h>

#include "soa/trisoup.h"

typedef struct {
  size_t nedges;    /* ridge edges */
  uint32_t *edge;   /* 2 x nedges: their ends (the soup's first vertex of each weld) */
  size_t ncorners;
  uint32_t *corner; /* ncorners vertices, ascending */
  size_t nridges;   /* chains and loops */
  double length;    /* of all ridge edges */
} mx_features;

/* The features of triangles [0, nt) of s at angle_deg (0 < angle < 180).
 * MX_OK, MX_ENOMEM. */
int mx_features_detect(const mx_trisoup *s, size_t nt, double angle_deg, mx_features *F);
void mx_features_free(mx_features *F);

#endif
