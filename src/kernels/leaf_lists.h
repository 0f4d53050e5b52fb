/* The nearest triangle of a node from the triangle lists of its leaves,
 * where that is the nearest of all (issue 31: the boundary stage's node
 * states and close nodes without a query of the surface index where it
 * need not be asked; the shrink's rule, the nearest among its leaves'
 * lists, by definition).
 *
 * Why it is exact. The mesh's nodes lie on the lattice of half the finest
 * leaves' side h (corners, edge and face middles, centres of the patterns).
 * A leaf's corners lie on the lattice of step 2h, so a node at such a
 * lattice point lies at least h from every leaf not holding it, 2h when it
 * is itself a corner of the finest lattice. The leaves holding it are those
 * whose elements use it (the mesh is conforming), and they cover the ball
 * of radius 0.9 h (1.8 h) about it: its cover (mx_list_cover). A triangle
 * nearer than the cover meets that ball, crosses into one of those leaves
 * and is in its list, so the nearest listed triangle, when nearer than the
 * cover, is the nearest of all; and with none listed that near, none is.
 * The distances are those of the surface index (mx_closest_on_triangle on
 * the soup's coordinates in the soup's order, as the index keeps them).
 *
 * Two exceptions, where the caller asks the index instead. (1) Two
 * triangles exactly as near with two different points (the index keeps the
 * one it meets first, the lists the lowest id): the tie flag. (2) A flat
 * triangle in a lattice plane: the lists hold the triangles meeting the
 * closed boxes, but a box is tested as centre and half sides, whose
 * rounding can leave an ulp between two neighbours, and a triangle lying in
 * that plane is then in neither list (the step of tests/features_test.sh at
 * -s 5 lost 29 close moves so, leaving duplicate nodes). Any other triangle
 * near a node crosses into a leaf's inside. So a node within its cover of
 * the plane of a triangle flat along an axis (extent below tol) gets no
 * marks (mx_list_marks).
 *
 * Within a local re-mesh's patch or a rank's patch, the nodes of the patch's
 * border miss the leaves outside it, as their edge lengths and elements do:
 * those rings are not kept (remesh_patch.c, p4est_mesh.h). */
#ifndef MX_LEAF_LISTS_H
#define MX_LEAF_LISTS_H

#include <stddef.h>
#include <stdint.h>

#include "soa/mesh.h"
#include "soa/tree.h"

/* The marks of a node (bits, free in the callers' per-node bytes). */
enum { MX_LIST_LOCAL = 4, MX_LIST_WIDE = 8 };

typedef struct {
  const mx_grid *g;
  double half, tol;  /* the finest leaves' half side; flatness */
  double *plane[3];  /* per axis, the planes of the triangles flat along it, sorted */
  size_t nplane[3];
} mx_list_frame;

/* The frame of mesh M (its elements' leaf levels, M->level) made from the
 * octree tr. MX_OK or MX_ENOMEM. */
int mx_list_frame_build(const mx_tree *tr, const mx_mesh *M, mx_list_frame *F);
void mx_list_frame_free(mx_list_frame *F);
/* The marks of a node at p: MX_LIST_LOCAL on the lattice of step half,
 * with MX_LIST_WIDE at a corner of the finest leaves' lattice; 0 off the
 * lattice or within its cover of a flat triangle's plane. */
uint8_t mx_list_marks(const mx_list_frame *F, const double p[3]);
/* The radius about a node with these marks within which its leaves' lists
 * hold every triangle (0 without marks). */
double mx_list_cover(uint8_t marks, double half);

/* For every node v with (sel[v] & mask) == want: btri[v] and best[v] (the
 * bits of the squared distance) of the least (squared distance, triangle
 * id) over the domain triangles of the leaves whose elements use v
 * (UINT32_MAX and UINT64_MAX when they list none; other nodes untouched);
 * tie[v] (when tie is not NULL) 1 when two of those triangles as near give
 * two points. M's elements in leaf order (each leaf's a run). Parallel,
 * deterministic. MX_OK or MX_ENOMEM. */
int mx_leaf_list_closest(const mx_tree *tr, const uint32_t *leaves, const mx_mesh *M,
                         const uint8_t *sel, uint8_t mask, uint8_t want, uint64_t *best,
                         uint32_t *btri, uint8_t *tie);

#endif
