/* The control space's structures (issue 27; Jurczyk & Glut 2016, "Tree
 * structures for adaptive control space in 3D meshing"): the public calls
 * are in include/mixoct.h (mx_cspace_*); this header is the layout the
 * builders (kdtree.c, octree.c) and the queries (cspace.c) share.
 *
 * Everything is a structure of arrays, nodes numbered in the order they are
 * made (level by level, a level's nodes in the order of their parents), so
 * the same source gives the same arrays for any thread count.
 *
 * kd-trees: node i is a leaf when axis[i] == 3; otherwise it splits at
 * coord[i] along axis[i] into child[i] (below) and child[i] + 1 (above).
 * A leaf's value: K_L, the sizes h[3 val[i] ..] of its centre; K_V, the
 * sizes of its 8 corners, h[3 vid[8 val[i] + c] ..] for corner c = x + 2y
 * + 4z (x, y, z in {0, 1}), interpolated trilinearly. A query descends from
 * node 0 keeping its box (K_V needs it for the local coordinates).
 *
 * Octrees: the leaves alone, sorted by the Morton key of their lowest
 * corner on the lattice of 2^max_depth cells per axis (base/morton.h):
 * the leaf holding a point is the last one whose key is not above the
 * point's cell's key (the leaves tile the box in Morton order), found by a
 * binary search; its value h[3 i ..] is the sizes at its centre. The box
 * may be any rectangular box: a cell's sides follow the box's. */
#ifndef MX_SIZING_CSPACE_H
#define MX_SIZING_CSPACE_H

#include <stddef.h>
#include <stdint.h>

#include "mixoct.h"

enum { MX_KD_LEAF = 3 };

struct mx_cspace_s {
  int structure, split, ns, max_depth;
  double lo[3], hi[3], delta;
  /* kd-trees */
  size_t nnodes;
  uint8_t *axis;
  double *coord;
  uint32_t *child;
  uint32_t *val;      /* leaves: value index (K_L) or corner-list index (K_V) */
  uint32_t *vid;      /* K_V: 8 value indices per leaf */
  size_t nleaves;     /* kd: leaves (corner lists); octree: leaves */
  /* octrees */
  uint64_t *key;      /* sorted anchor keys */
  uint8_t *level;
  /* values: 3 sizes each */
  size_t nvalues;
  double *h;
  int depth, capped;
  double seconds;
};

/* Shared by the builders (cspace.c) */
/* Evaluates f at n points in parallel blocks, checking every size is
 * finite and positive (MX_EINPUT naming the first bad point otherwise). */
int mx_cs_eval(mx_size_fn f, void *user, size_t n, const double *xyz, double *h);
/* The parameters' checks of mx_cspace_build (box: the box's too), with a
 * message: MX_EINPUT. */
int mx_cs_params_check(const mx_cspace_params *p, int box);
/* Whether the n sizes (3 a point) are all finite and positive. */
int mx_cs_sizes_ok(const double *h, size_t n);
/* The message for a source that gave a size not finite and positive
 * somewhere in c's box: MX_EINPUT. */
int mx_cs_bad_sizes(const mx_cspace *c);
/* The sample points of a node box: the regular ns^3 grid on the closed box
 * (its corners included: where a leaf's constant value is farthest from a
 * monotone field; the centre too for an odd ns), x fastest. */
void mx_cs_samples(const double lo[3], const double hi[3], int ns, double *xyz);

/* About how many cubes (dim 3) of side f * max(h, floor) fill the field's
 * box, h the least size of each leaf (K_V: of its corners): what an octree
 * that follows the field would hold, for the memory estimate; dim 2: the
 * squares that fill its x-y face (a quadtree's; the z axis a slab the
 * field does not vary along). *hmin, *at: the least size and a point where
 * it is. */
double mx_cspace_cells(const mx_cspace *c, int dim, double floor, double f, double *hmin,
                       double at[3]);
/* The level of a tree of root side `root` whose cells are no larger than
 * the size h (side root / 2^level <= h, up to rounding), 0 to max_level;
 * max_level when h is not positive. The octree and the quadtree ask the
 * field's least size over a cell's box for this. */
int mx_cs_level(double root, double h, int max_level);
/* The structure's name as the reports print it: "K_L s_S", "K_V s_G",
 * "K_oL", "K_oLB". */
const char *mx_cs_structure_name(int structure, int split);
int mx_cs_build_kd(mx_cspace *c, mx_size_fn f, void *user);
int mx_cs_build_octree(mx_cspace *c, mx_size_fn f, void *user);
void mx_cs_query_kd(const mx_cspace *c, const double p[3], double h[3]);
void mx_cs_query_octree(const mx_cspace *c, const double p[3], double h[3]);
double mx_cs_min_box_kd(const mx_cspace *c, const double lo[3], const double hi[3]);
double mx_cs_min_box_octree(const mx_cspace *c, const double lo[3], const double hi[3]);
/* The leaves' boxes (6 each: lo, hi) and least sizes (K_V: of the
 * corners), into box and h when not NULL; returns how many. */
size_t mx_cs_leaves_kd(const mx_cspace *c, double *box, double *h);
size_t mx_cs_leaves_octree(const mx_cspace *c, double *box, double *h);
size_t mx_cspace_leaves(const mx_cspace *c, double *box, double *h);

#endif
