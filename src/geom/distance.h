/* Distance to a triangulated surface, signed distance and inside/outside,
 * for the triangles [t0, t1) of a soup.
 *
 * Methods: the sign of the distance comes from the angle-weighted
 * pseudonormal of the closest feature (Baerentzen & Aanaes 2005, "Signed
 * distance computation using the angle weighted pseudonormal"): if q is the
 * closest point of p on a closed, consistently oriented surface and n the
 * pseudonormal of the face, edge or vertex that contains q, then p is outside
 * iff (p - q) . n > 0. The face pseudonormal is the face normal, an edge's is
 * the sum of the normals of its two faces, a vertex's is the sum over its
 * faces of the face normal times the face's angle at the vertex.
 * Surfaces that are not closed are classified by the generalized winding
 * number (Jacobson, Kavan & Sorkine-Hornung 2013): the sum over the triangles
 * of their signed solid angles seen from p, over 4 pi (van Oosterom &
 * Strackee 1983 per triangle); 1 inside a closed surface, 0 outside, and a
 * smooth, robust vote in between for a surface with holes.
 *
 * Index. A BVH over the triangles (geom/bvh.h: flat array of nodes, top-down
 * median split on the longest axis of the centroids, leaves of <= 4
 * triangles, O(n log n), subtrees built as OpenMP tasks), the triangles' coordinates
 * copied in BVH order, the face normals, three edge pseudonormals per
 * triangle and one pseudonormal per vertex. The index points to the soup,
 * which must stay alive and unchanged while the index is used.
 *
 * Shells and orientation. The edges and shells are those of
 * geom/surface_topology.h.
 * A shell is a set of triangles connected through edges. Within a shell the
 * orientation is made consistent by propagation through the manifold edges
 * (used by exactly two triangles); a triangle that disagrees with its
 * neighbours is flipped ("reoriented"). Then every shell is oriented by the
 * rule:
 *
 *   the domain is the set of points of odd nesting depth (parity: a point
 *   inside one shell is in, inside two nested shells is in a hole, inside
 *   three is in an island in the hole, ...), and the normals of every shell
 *   point away from the domain.
 *
 * The nesting depth d of a shell is the number of other shells that contain
 * it, found with the winding number of a point of the shell (the centroid of
 * one of its triangles, that triangle left out) with respect to all the
 * shells, each temporarily oriented outward (positive signed volume): the sum
 * is d + 1/2. A shell of even depth is oriented outward (positive volume), a
 * shell of odd depth inward (a hole). Shells must not cross each other.
 * The flips are stored per triangle; the input soup is not modified.
 *
 * Queries only read the index: any number of threads may run them at once.
 * Closest point and signed distance use the same tree stored 4-wide (two
 * levels merged), whose children carry oriented bounding boxes (the frame
 * of the area-weighted mean normal and the principal axes, much tighter
 * than axis-aligned boxes beside flat patches) in single precision, and
 * whose leaves carry per triangle float planes that bound the distance from
 * below (exactly, up to rounding, in the face and edge regions). The
 * descent goes nearest child first, starting from the exact distance to a
 * hint triangle (the one closest to the centre of the query's cell in a
 * coarse uniform grid, about one cell per two triangles), and skips a child
 * or a triangle whose float lower bound is not below (best + delta)^2,
 * delta = 2^-17 of the coordinates' magnitude: far above the float rounding,
 * so the true closest triangle is never dropped; candidates are tested
 * exactly in double. Coordinates beyond 1e15 (squares would overflow
 * floats), or a surface within 1e-15 of the origin, fall back to testing
 * every triangle. Cost: O(log n) for points
 * near the surface; a point at distance d must look at the triangles within
 * about sqrt(d x triangle size) of its foot point, so far points cost more.
 * Measured (cortex, 6300 triangles, one core of the development VM): about
 * 0.5 us per point within 2 units of the surface, 1.2 us per point uniform
 * in the surface's box (1 million in about 1.2 s; linear in the threads).
 * The winding number is exact and hierarchical: a BVH node whose box does not
 * contain p contributes the same as the "cap" that closes its boundary
 * (a fan from the box centre over its oriented boundary edges; the node
 * plus the cap is a closed surface inside the box, whose winding number at p
 * is 0), which is used whenever the boundary has fewer edges than the node
 * has triangles: O(1) for p outside a closed surface's box, about
 * O(sqrt(n) log n) otherwise; O(n) in the worst case (a surface made of many
 * disconnected triangles). */
#ifndef MX_DISTANCE_H
#define MX_DISTANCE_H

#include <stddef.h>
#include <stdint.h>

#include "geom/bvh.h"
#include "soa/trisoup.h"

/* Feature of a triangle that holds a closest point: the face, edge k (from
 * the triangle's vertex k to vertex (k+1) mod 3, in the soup's order) or
 * vertex k (the soup's tri[3 t + k]). */
enum {
  MX_FEATURE_FACE = 0,
  MX_FEATURE_EDGE = 1,   /* + k, k = 0, 1, 2 */
  MX_FEATURE_VERTEX = 4, /* + k, k = 0, 1, 2 */
};

/* The same tree with two levels merged, for the closest-point queries:
 * for each of up to 4 children an oriented bounding box (centre c, first
 * two unit axes a0 and a1, the third a0 x a1, half extents h), in single
 * precision, side by side; a child is a wide node (count 0) or a leaf
 * (count 1..4 slots; child: its pack). Unused children: h = -inf. */
typedef struct {
  float c[3][4];
  float a[6][4]; /* a0 x y z, a1 x y z */
  float h[3][4];
  uint32_t child[4];
  uint8_t count[4];
  uint8_t pad_[44]; /* 256 bytes */
} mx_bvh4_node;

typedef struct {
  float v[16][4]; /* n, n.a, m0, m0.a, m1, m1.b, m2, m2.c (x y z w each) */
} mx_leaf_pack;

typedef struct mx_surface_index {
  const mx_trisoup *soup;
  uint32_t t0, t1, nt;  /* the triangles [t0, t1); nt = t1 - t0 */

  /* BVH: nodes[0] is the root; slots are the triangles in BVH order. */
  mx_bvh_node *nodes;
  uint32_t nnodes;
  mx_bvh4_node *wide; /* wide[0] is the root */
  uint32_t nwide;
  uint32_t *tri_id;   /* nt: soup triangle of each slot */
  double *tv;         /* 9 nt: the slot's vertex coordinates a, b, c */
  uint32_t *shell_of; /* nt: the shell (0 .. nshells-1) of each slot */
  int8_t *tsign;      /* nt: +1 kept, -1 flipped (orientation used) */
  /* Leaves of the wide BVH, 4 triangles side by side in single precision
   * (unused lanes repeat lane 0): for a lower bound of the distance, the
   * plane (unit normal, offset) and the three edge planes (unit in-plane
   * outward normals, offsets) of each triangle; leaf_first: first slot. */
  mx_leaf_pack *packs;
  uint32_t *leaf_first;
  uint32_t npacks;
  /* Hints: a uniform grid over the triangles' box, holding per cell the
   * slot of the triangle closest to the cell's centre; a query first tests
   * the hint of its cell (clamped to the grid), which gives a tight initial
   * bound for the descent. */
  uint32_t *hint;
  double hint_lo[3], hint_inv[3];
  int hint_n[3];
  double coord_max;   /* largest |coordinate| of the triangles */

  /* Pseudonormals (already for the orientation used). */
  double *fn; /* 3 nt: unit face normal per slot */
  double *en; /* 9 nt: pseudonormal of edge k of the slot at 9 i + 3 k */
  double *vn; /* 3 soup->nv: vertex pseudonormals (by soup vertex index) */

  /* Boundary of the triangles of each node, for the winding number caps:
   * node i owns cap_cnt[i] directed edges (cap_u, cap_v) with integer
   * multiplicities cap_w (orientation included), from cap_off[i]; kept
   * when at most half the node's triangle count, else cap_cnt UINT32_MAX. */
  uint64_t *cap_off;
  uint32_t *cap_cnt;
  uint32_t *cap_u, *cap_v;
  int32_t *cap_w;
  size_t ncap;

  /* Report. */
  size_t open_edges;        /* edges not used by exactly two triangles */
  size_t nonmanifold_edges; /* of which used by three or more */
  size_t conflict_edges;    /* manifold edges left inconsistently oriented
                               (non-orientable shell) */
  uint32_t nshells;         /* connected shells */
  uint32_t *shell_depth;    /* per shell: how many other shells enclose it
                               (0 for every shell as given, or for one) */
  uint32_t nflipped;        /* shells whose orientation was reversed */
  size_t nreoriented;       /* triangles flipped to agree with their shell */
  int closed;               /* 1: no open, non-manifold or conflicting edge;
                               the pseudonormal sign is used */
  int outward_closed;       /* built outward with nested shells that would be
                               closed: a point's depth and side from its
                               closest shell's pseudonormal (closest.c) */
  /* Set by the caller after the build (NULL by default): the side of a
   * point (mx_inside, the sign of mx_signed_distance) is then the winding
   * number of this other index above 1/2, closed or not (an index over the
   * boundary of a winding number's domain defers to the input's). */
  const struct mx_surface_index *side;
} mx_surface_index;

/* Build the index of the triangles [t0, t1) of soup. MX_OK, MX_ENOMEM, or
 * MX_EINPUT (bad range, more than 2^30 triangles). An empty range gives
 * an index for which every point is outside at infinite distance. */
int mx_surface_index_build(mx_surface_index *S, const mx_trisoup *soup,
                           uint32_t t0, uint32_t t1);
/* The same, with the triangles' orientation as given instead of the shell
 * rule above: within each shell the orientation is made consistent through
 * the manifold edges as above, then the shell is turned the way that keeps
 * most of its triangles as given (ties: positive signed volume about the
 * centre of the shell's box); shells are never flipped for their nesting.
 * The winding number is then the input's own (Jacobson et al.): 2 where
 * two bodies overlap, whatever the order of the triangles; closed is 0. For
 * --repair-input. */
int mx_surface_index_build_given(mx_surface_index *S, const mx_trisoup *soup,
                                 uint32_t t0, uint32_t t1);
/* The same with every shell turned outward (several materials, issue 26):
 * the winding number of a point counts the shells around it, its nesting
 * depth (mx_region_depth), and the domain (mx_inside, the sign of the
 * distance: winding number above 1/2) is the union of the outermost
 * shells' insides, the nested shells inside it not holes; closed is 0 when
 * a shell nests in another (no shell does: the same index as above). */
int mx_surface_index_build_outward(mx_surface_index *S, const mx_trisoup *soup,
                                   uint32_t t0, uint32_t t1);
/* Each shell's enclosed volume, signed as the index orients it (vol, nshells
 * values), and its area (area, nshells values, or NULL). */
void mx_surface_index_shell_volumes(const mx_surface_index *S, double *vol, double *area);
/* 1 when a shell of the index lies inside another (shell_depth > 0). */
int mx_surface_index_nested(const mx_surface_index *S);
/* Of an index built outward: the number of shells around p (0 outside
 * every shell); a point on a shell gets either side's count. */
int mx_region_depth(const mx_surface_index *S, const double p[3]);
void mx_surface_index_free(mx_surface_index *S);

/* Exact closest point q of p on the triangles (Voronoi regions of the
 * closest triangle); returns the distance |p - q|. tri receives the soup
 * triangle, feature the MX_FEATURE_* code of q on it; q, tri and feature may
 * be NULL. Ties go to the first triangle found. */
double mx_closest_point(const mx_surface_index *S, const double p[3],
                        double q[3], uint32_t *tri, int *feature);

/* The same, when only a point within rmax matters: the search prunes
 * everything farther. Returns the exact distance and q when the closest
 * point lies within rmax; otherwise a value >= rmax (q then unspecified). */
double mx_closest_point_within(const mx_surface_index *S, const double p[3],
                               double rmax, double q[3]);

/* Closest point q of p on one triangle t (its 9 coordinates); returns the
 * squared distance. */
double mx_closest_on_triangle(const double t[9], const double p[3], double q[3]);

/* Signed distance: negative inside the domain, 0 exactly on the surface.
 * Closed surfaces: sign of (p - q) . pseudonormal of the closest feature.
 * Surfaces that are not closed: sign from the winding number (> 1/2 inside).
 * q (may be NULL) receives the closest point. */
double mx_signed_distance(const mx_surface_index *S, const double p[3],
                          double q[3]);

/* Generalized winding number of p with respect to the oriented triangles:
 * ~1 in the domain, ~0 outside (exactly so, up to rounding, for closed
 * shells); hierarchical (see above). Points on the surface get an
 * unspecified value between. */
double mx_winding_number(const mx_surface_index *S, const double p[3]);
/* The same, summed over every triangle (O(n), for checking). */
double mx_winding_number_direct(const mx_surface_index *S, const double p[3]);

/* 1 if p is in the domain, 0 if not: the pseudonormal sign for a closed
 * surface, winding number > 1/2 otherwise. Points on the surface are in. */
int mx_inside(const mx_surface_index *S, const double p[3]);

/* Many points near each other at once, by blocks of up to MX_BLOCK: the
 * 4-wide tree walked once a block for the triangles near its box, then each
 * point against those (the same answers as the single queries: where two
 * triangles are at exactly the least distance, and for a block whose points
 * lie far apart, the single query is asked). mx_inside of the points
 * xyz + 3 ids[i], i < n, into inside[i] (0 or 1). on (may be NULL): on[i]
 * 1 for a point inside within distance sqrt(near2) of the surface (with a
 * surface that is not closed, or a side test of its own: every point
 * inside), else 0. */
#define MX_BLOCK 32
void mx_inside_block(const mx_surface_index *S, const double *xyz, const uint32_t *ids,
                     int n, uint8_t *inside, uint8_t *on, double near2);
/* mx_closest_point_within of the same points, with rmax[i] (NULL: no
 * bound): dist[i], and q[i] when dist[i] < rmax[i]. */
void mx_closest_point_block(const mx_surface_index *S, const double *xyz, const uint32_t *ids,
                            int n, const double *rmax, double *dist, double (*q)[3]);

#endif
