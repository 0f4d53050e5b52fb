/* Sharp features of an input surface (issue 29, item 1; src/geom/features.c):
 * ridges are the edges whose two triangles' normals part by more than a
 * threshold angle (the dihedral angle departs from flat by more than it),
 * and the edges of one triangle or of three or more (open or non-manifold);
 * corners are the vertices where a ridge ends, where three ridge edges or
 * more meet, or where a ridge turns by more than the threshold. Vertices
 * are welded by their coordinates first (an unwelded copy of a vertex is
 * the same vertex). A ridge, as counted, is a chain of ridge edges from
 * corner to corner, or a loop without one. Ridges by angle with a free end
 * (no other ridge meets it: the noise of a scanned or segmented surface,
 * not the edge of a part) are peeled off until none is left, and so are
 * the networks of ridges left whose length is below MX_FEATURE_MIN of the
 * surface's bounding box diagonal (clusters of noise edges); both counted.
 * The cortex of the papers: 526 ridge edges at 30 degrees, 42 after the
 * peeling. */
#ifndef MX_FEATURES_H
#define MX_FEATURES_H

#define MX_FEATURE_MIN 0.05

#include <stddef.h>
#include <stdint.h>

#include "soa/trisoup.h"

typedef struct {
  size_t nedges;    /* ridge edges */
  uint32_t *edge;   /* 2 x nedges: their ends (the soup's first vertex of each weld) */
  uint8_t *open;    /* per ridge edge: 1 when open or non-manifold (not by angle) */
  size_t dangling;  /* ridge edges dropped: free ends peeled, short networks */
  size_t ncorners;
  uint32_t *corner; /* ncorners vertices, ascending */
  size_t nridges;   /* chains and loops */
  double length;    /* of all ridge edges */
  size_t npatches;  /* the surface cut along its ridges: */
  uint32_t *patch;  /* per triangle of [0, nt), its patch 0..npatches-1 (numbered
                     * in the order of their first triangle) */
} mx_features;

/* The features of triangles [0, nt) of s at angle_deg (0 < angle < 180).
 * MX_OK, MX_ENOMEM. */
int mx_features_detect(const mx_trisoup *s, size_t nt, double angle_deg, mx_features *F);
void mx_features_free(mx_features *F);


#endif
