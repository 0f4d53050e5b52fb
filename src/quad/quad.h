/* The 2D mixed quadtree mesher (Jaillet & Lobos 2021, sections 3, 4 and
 * 6.1-6.3): closed polylines in, quadrilaterals and triangles out.
 *
 * The data flow, one file per step (src/quad/):
 *
 *   .poly/.off/.mdl --read (io/read_poly.c)--> mx_poly, checked (poly.c)
 *     --grid + refine + balance (qtree.c, qrefine.c, qedges.c)--> mx_qtree
 *     --transition (qtransition.c)--> mx_qmesh (conforming, whole grid)
 *     --boundary, Algorithm 2 (qboundary.c)--> mx_qmesh of the domain
 *     --quality (qquality.c), write (mesher/qmesh_output.c, through io), check (qcheck.c)
 *
 * The same machinery as 3D where the idea is the same: Morton keys on a
 * finest lattice (x in bit 0, y in bit 1), a level-synchronous refinement
 * with a `candidates` list, balance kept while refining through edge infos
 * (2 quadrants per edge, section 3.2), a recursive balance after refinement
 * as the baseline (both give the same leaves), transition patterns looked
 * up by a mask, nodes numbered in Morton order of their first leaf (output
 * identical for any thread count). Library errors are MX_* status codes;
 * messages go through mx_error / mx_warning (common.h). */
#ifndef MX_QUAD_H
#define MX_QUAD_H

#include <stddef.h>
#include <stdint.h>

#include "soa/mesh_data.h"
#include "soa/poly.h"

/* MX_QMAX_LEVEL (the lattice): soa/poly.h. */

/* ---- polylines (poly.c, io/read_poly.c) --------------------------------- */

/* The polylines (mx_poly) and refinement boxes (mx_qbox): soa/poly.h; their
 * readers: io/read_poly.h. */

/* A domain's checks: every vertex of a segment starts exactly one segment
 * and ends exactly one (closed polylines; a segment given backwards in a
 * loop is turned around), no zero-length segment, no two segments crossing
 * or overlapping (MX_EINPUT naming both segments' lines). Orientation from
 * nesting: a loop inside an even number of others is an outer boundary
 * (made counter-clockwise), else a hole (made clockwise); turning one is
 * reported as a warning. Sets nloops. */
int mx_poly_check_domain(mx_poly *P);

/* Point location against a checked domain: a uniform grid of segments
 * (about 4 segments per cell) answering inside/outside by crossings along
 * x (the row walked toward its nearer end: the same parity for closed
 * loops) and the closest point on the polylines. Read-only once built:
 * queries may run in parallel. */
typedef struct {
  const mx_poly *P;
  double lo[2], h;   /* grid origin and cell side */
  uint32_t nx, ny;
  uint32_t *off;     /* nx*ny+1 CSR offsets into ids */
  uint32_t *ids;     /* segment ids per cell */
  double eps;        /* 1e-12 of the domain's diameter: "on a segment" */
  double margin;     /* a segment is listed in every cell this close to it */
} mx_poly_index;

int mx_poly_index_build(const mx_poly *P, mx_poly_index *I);
void mx_poly_index_free(mx_poly_index *I);
/* 1 strictly inside, 0 outside; a point on a segment (within 1e-12 of the
 * domain's size) counts as on the boundary: returns 2. */
int mx_poly_inside(const mx_poly_index *I, const double p[2]);
/* The closest point of the polylines to p (q), its segment, and the squared
 * distance; searches no farther than rmax (INFINITY: anywhere). Returns
 * UINT32_MAX as the segment when nothing lies within rmax (then *d2 is
 * INFINITY and q is not written). Equally close segments: the lowest id. */
uint32_t mx_poly_closest(const mx_poly_index *I, const double p[2], double rmax, double q[2],
                         double *d2);
/* Features (section 4.1): vertices where the polyline turns by an angle
 * outside ]175, 185[ degrees, and vertices where more than two segments
 * meet (a drawing's junctions); an open polyline's ends are not. Writes
 * their vertex ids, ascending, to *out (allocated, mx_free). */
int mx_poly_features(const mx_poly *P, uint32_t **out, size_t *n);

/* ---- nested loops as regions (qregions.c) -------------------------------- */

/* The regions a checked domain's loops cut out (several materials): region
 * d of a point is the number of loops around it (0 outside the domain, 1
 * between an outer loop and the loops inside it, ...). `all` holds the
 * domain's loops (same vertices, same segment ids) each turned
 * counter-clockwise, so that its winding number is the region; I indexes
 * it. A loop at depth t (t loops around it) separates regions t and t + 1;
 * the outer loops are at depth 0. */
typedef struct {
  mx_poly all;
  mx_poly_index I;
  uint32_t *seg_depth; /* per segment: its loop's depth */
  uint32_t deepest;    /* the deepest region (1 + the deepest loop's depth) */
} mx_qregions;

int mx_qregions_build(const mx_poly *P, mx_qregions *R);
void mx_qregions_free(mx_qregions *R);
/* The region of p (>= 0), or -1 when p lies within the index's eps of a
 * segment (*seg: that segment of `all`, else UINT32_MAX; seg may be NULL). */
long mx_qregion_of(const mx_qregions *R, const double p[2], uint32_t *seg);
/* The loops at depths lo .. hi as a domain of their own (vertices
 * renumbered, lines kept, nloops set): those at depth lo counter-clockwise,
 * the deeper ones clockwise. For lo + 1 == hi: region hi's own boundary,
 * oriented as mx_poly_check_domain would. MX_ENOMEM. */
int mx_qregions_select(const mx_qregions *R, uint32_t lo, uint32_t hi, mx_poly *out);

/* ---- requests (qrefine.c) ------------------------------------------------ */

/* The functions of the "function" refinement: a quadrant is refined to the
 * level when the function's zero set crosses it (the signs at its corners
 * and centre differ, or the zero set is closer than half its diagonal). */
enum { MX_QFUN_CIRCLE = 1, MX_QFUN_LINE = 2, MX_QFUN_SINE = 3 };
typedef struct {
  int kind;
  double a[4]; /* circle: cx cy r; line: px py nx ny; sine: amp freq phase y0 */
  int level;
} mx_qfun;
/* The distance from (x, y) to the function's zero set: exact for the
 * circle and the line; for the sine a lower bound (|f| over its Lipschitz
 * constant), which like the distance grows by at most 1 per unit of
 * length. The size field's curve sources (mesher/mesher2d_size.c) read it;
 * the crossing test above uses the same bound. */
double mx_qfun_distance(const mx_qfun *f, double x, double y);

typedef struct {
  int s_level;             /* quadrants meeting the domain's polylines; 0 none */
  int a_level;             /* every quadrant of the domain; 0 none */
  size_t nboxes;
  const mx_qbox *boxes;
  size_t nregions;         /* region polylines: quadrants inside or crossing */
  const mx_poly *regions;
  const int *region_level;
  size_t ndrawings;        /* drawings: quadrants their segments cross */
  const mx_poly *drawings;
  const int *drawing_level;
  size_t nfuns;
  const mx_qfun *funs;
  /* A size field (issue 27; NULL: none): a quadrant is split while its
   * side exceeds the least size of the field over its box (the control
   * space's box query at z = 0, the field built over the domain's box
   * with a thin slab in z: mesher/mesher2d_size.c). */
  const mx_cspace *size_field;
  /* The leaves of an earlier quadtree (re-meshing from a restart file,
   * Algorithm 3): keep_key ascending (anchor keys), keep_level their
   * levels, plus one for the leaves listed for refinement. A quadrant is
   * refined to the highest keep_level of the kept leaves anchored in it, so
   * the earlier tree is rebuilt, its listed leaves split once, and balance
   * restored by the same passes as the other requests. */
  size_t nkeep;
  const uint64_t *keep_key;
  const uint8_t *keep_level;
} mx_qrequests;

/* ---- the quadtree (qtree.c, qedges.c, qrefine.c) ------------------------- */

enum {
  MX_Q_SPLIT = 1,   /* not a leaf any more */
  MX_Q_BOUND = 2,   /* meets a segment of the domain */
  MX_Q_OUT = 4,     /* a leaf wholly outside the domain (not meshed) */
  MX_Q_QUEUED = 8,  /* on the to_balance list */
};

/* Root squares of side `side` on a grid dims[0] x dims[1] from origin,
 * covering the domain's bounding box (the longest side is one root; the
 * other axis gets as many roots as it needs). A lattice unit is
 * side / 2^MX_QMAX_LEVEL. */
typedef struct {
  double origin[2], side, unit;
  uint32_t dims[2];
} mx_qgrid;

/* Quadrants: every quadrant ever made keeps its index; a split one keeps its
 * slot and its 4 children are contiguous from child0 (child c: bit 0 = +x,
 * bit 1 = +y). */
typedef struct {
  size_t n, cap;
  uint64_t *key;      /* 2D Morton key of the anchor on the finest lattice */
  uint8_t *level;
  uint8_t *flags;     /* MX_Q_* */
  uint8_t *target;    /* the level the requests ask for */
  uint32_t *parent;   /* UINT32_MAX for roots */
  uint32_t *child0;   /* UINT32_MAX while a leaf */
  uint32_t *seg_off;  /* CSR slice of seg_pool: the domain segments it meets */
  uint32_t *seg_cnt;
  uint32_t *seg_pool;
  size_t seg_n, seg_cap;
  mx_qgrid grid;
} mx_qtree;

enum { MX_QBALANCE_EDGES = 0, MX_QBALANCE_RECURSIVE = 1 };

typedef struct {
  size_t splits, balance_splits, leaves, edges;
  double t_refine, t_balance;
} mx_qstats;

/* Algorithm 1: the grid, then level by level the candidates the requests
 * want split, split, and (MX_QBALANCE_EDGES) the neighbours made unbalanced
 * found through the edge infos and split before the next level; or
 * (MX_QBALANCE_RECURSIVE) all levels first, then a recursive neighbour
 * search until no two edge-adjacent leaves differ by more than one level.
 * Leaves wholly outside the domain are flagged MX_Q_OUT. */
int mx_qtree_build(const mx_poly *domain, const mx_poly_index *I, const mx_qrequests *req,
                   int balance, mx_qtree *T, mx_qstats *stats);
void mx_qtree_free(mx_qtree *T);
/* The leaves not MX_Q_OUT, in Morton order (allocated). */
int mx_qtree_leaves(const mx_qtree *T, uint32_t **leaves, size_t *n);
/* Independent check: no two edge-adjacent leaves differ by more than one
 * level (a sort of the leaves' edges, not the edge infos). Returns the
 * number of unbalanced pairs. */
size_t mx_qtree_unbalanced(const mx_qtree *T);

/* Internal to the quadtree steps (qtree.c, qedges.c, qrefine.c,
 * qbalance_recursive.c, qtransition.c), declared here because those files
 * share them; other callers use the functions above. */

/* 2D Morton key of a lattice point (x in bit 0, y in bit 1) and back. */
static inline uint64_t mx_qspread(uint32_t v) {
  uint64_t x = v;
  x = (x | (x << 16)) & 0x0000FFFF0000FFFFULL;
  x = (x | (x << 8)) & 0x00FF00FF00FF00FFULL;
  x = (x | (x << 4)) & 0x0F0F0F0F0F0F0F0FULL;
  x = (x | (x << 2)) & 0x3333333333333333ULL;
  x = (x | (x << 1)) & 0x5555555555555555ULL;
  return x;
}
static inline uint32_t mx_qcompact(uint64_t x) {
  x &= 0x5555555555555555ULL;
  x = (x | (x >> 1)) & 0x3333333333333333ULL;
  x = (x | (x >> 2)) & 0x0F0F0F0F0F0F0F0FULL;
  x = (x | (x >> 4)) & 0x00FF00FF00FF00FFULL;
  x = (x | (x >> 8)) & 0x0000FFFF0000FFFFULL;
  x = (x | (x >> 16)) & 0x00000000FFFFFFFFULL;
  return (uint32_t)x;
}
/* Both coordinates at once: the perfect shuffle of (y << 32 | x) and its
 * inverse (Hacker's Delight, 7-2), half the work of two spreads. */
static inline uint64_t mx_qkey(uint32_t x, uint32_t y) {
  uint64_t k = (uint64_t)y << 32 | x, t;
  t = (k ^ (k >> 16)) & 0x00000000FFFF0000ULL, k ^= t ^ (t << 16);
  t = (k ^ (k >> 8)) & 0x0000FF000000FF00ULL, k ^= t ^ (t << 8);
  t = (k ^ (k >> 4)) & 0x00F000F000F000F0ULL, k ^= t ^ (t << 4);
  t = (k ^ (k >> 2)) & 0x0C0C0C0C0C0C0C0CULL, k ^= t ^ (t << 2);
  t = (k ^ (k >> 1)) & 0x2222222222222222ULL, k ^= t ^ (t << 1);
  return k;
}
static inline void mx_qkey_xy(uint64_t key, uint32_t *x, uint32_t *y) {
  uint64_t k = key, t;
  t = (k ^ (k >> 1)) & 0x2222222222222222ULL, k ^= t ^ (t << 1);
  t = (k ^ (k >> 2)) & 0x0C0C0C0C0C0C0C0CULL, k ^= t ^ (t << 2);
  t = (k ^ (k >> 4)) & 0x00F000F000F000F0ULL, k ^= t ^ (t << 4);
  t = (k ^ (k >> 8)) & 0x0000FF000000FF00ULL, k ^= t ^ (t << 8);
  t = (k ^ (k >> 16)) & 0x00000000FFFF0000ULL, k ^= t ^ (t << 16);
  *x = (uint32_t)k;
  *y = (uint32_t)(k >> 32);
}
/* Side of a quadrant of this level, in lattice units. */
static inline uint32_t mx_qsize(int level) { return 1u << (MX_QMAX_LEVEL - level); }

/* qtree.c: the root grid covering the box [lo, hi] (name: for messages). */
int mx_qgrid_build(const double lo[2], const double hi[2], const char *name, mx_qgrid *g);

/* qedges.c: the edge infos of section 3.2 (opaque). Edges of levels up to
 * `top` are kept: a quadrant of level l split needs those of level l-1. */
typedef struct mx_qedges mx_qedges;
int mx_qedges_new(int top, mx_qedges **E);
void mx_qedges_free(mx_qedges *E);
size_t mx_qedges_count(const mx_qedges *E);
/* Register the roots (quadrants 0..nroots-1) in their level-0 edges. */
int mx_qedges_add_roots(mx_qedges *E, const mx_qtree *T, size_t nroots);
/* Register the children of the just split quadrants `split` (all of one
 * level) in their edges. */
int mx_qedges_add_children(mx_qedges *E, const mx_qtree *T, const uint32_t *split, size_t n);
/* The leaves made unbalanced by the splits of `split` (all of one level l):
 * the leaves of level l-1 across their parents' edges, not MX_Q_OUT, not
 * already queued; flagged MX_Q_QUEUED, sorted by key (allocated). */
int mx_qedges_unbalanced(const mx_qedges *E, mx_qtree *T, const uint32_t *split, size_t n,
                         uint32_t **out, size_t *nout);

/* qbalance_recursive.c: the leaves (not MX_Q_OUT) that the classic
 * neighbour search (descending from the roots 0..nroots-1) finds next to a
 * split quadrant one level finer than them, by index (allocated). */
int mx_qbalance_find(const mx_qtree *T, size_t nroots, uint32_t **out, size_t *n);

/* ---- meshes (qtransition.c, qboundary.c) --------------------------------- */

enum { MX_QTRI = 0, MX_QQUAD = 1 };
#define MX_QNKEY_NONE UINT64_MAX

/* A 2D mixed mesh: counter-clockwise triangles and quadrilaterals. */
typedef struct {
  size_t nnodes, ncells;
  double *xy;        /* 2 per node */
  uint64_t *nkey;    /* lattice key per node (2D Morton on the finest lattice), or MX_QNKEY_NONE */
  uint8_t *type;     /* MX_QTRI / MX_QQUAD */
  uint32_t *conn;    /* 4 per cell; a triangle's 4th is UINT32_MAX */
  uint32_t *leaf;    /* position in the leaves array of the quadrant it came from */
  uint8_t *level;
} mx_qmesh;

void mx_qmesh_free(mx_qmesh *M);
/* The faces of a 2D mesh read by io (io/read_mesh.h: mx_read_mesh_dim) as
 * the cells of q, in the file's node order (m is left as it was;
 * quad/qmesh_faces.c). MX_OK or MX_ENOMEM. */
int mx_qmesh_from_faces(const mx_mesh_data *m, mx_qmesh *q);
/* The first cell with a bad type or a node index >= nnodes; ncells when
 * none (qquality.c). The writers and the check test this first. */
size_t mx_qmesh_bad_cell(const mx_qmesh *M);

/* Transition patterns (Fig. 4): a leaf's mask has bit e set when the
 * midpoint of its edge e (0 bottom, 1 right, 2 top, 3 left) is a node of a
 * finer neighbour. 0: one quad; one mid-node: 3 triangles; two on opposite
 * edges: 2 quads; two on adjacent edges: 1 quad and 2 triangles; three: 1
 * quad and 3 triangles; four: 4 quads around a centre node. Every node is
 * numbered by the first leaf (Morton order) that uses it. `leaves` must be
 * in Morton order, as mx_qtree_leaves gives them (the node ownership relies
 * on it); cell `leaf` fields are positions in it. */
int mx_qtransition(const mx_qtree *T, const uint32_t *leaves, size_t n, mx_qmesh *M);

/* Algorithm 2, steps 3-5, on the transition mesh: features (the closest
 * node of the leaf holding a feature moves onto it), projection of inside
 * nodes closer than close_ratio (0.3) of the shortest diagonal of the leaves
 * sharing them, removal of elements with no inside node, shrink of the
 * outside nodes onto the polylines, surface patterns by inside
 * configuration and node angles (Fig. 8: < 150 degrees counts as inside,
 * ]175, 185[ as flat). Features end as mesh vertices; no element is left
 * with a non-positive Jacobian (MX_EINVALID otherwise, naming where). */
typedef struct {
  size_t features, moved_close, removed, shrunk, patterned, inverted;
} mx_qboundary_stats;

int mx_qboundary(const mx_poly *P, const mx_poly_index *I, const mx_qtree *T,
                 const uint32_t *leaves, double close_ratio, mx_qmesh *M,
                 mx_qboundary_stats *stats);

/* ---- several materials (qcleave.c) ----------------------------------------- */

/* The loops nested in the outer ones as interfaces between materials, on
 * the mesh the boundary step fitted to the outer loops: the interfaces'
 * sharp vertices become nodes, nodes near an interface move onto it, the
 * cells a loop passes through are cut along its chords (new nodes where
 * it crosses an edge, shared by the cells on both sides), and the nodes
 * along the interfaces are smoothed (on an interface, along it). *region (allocated, one per cell) gets each cell's region (its
 * nesting depth, mx_qregion_of), 1 at least. MX_ENOMEM. */
typedef struct {
  size_t features;          /* the interfaces' sharp vertices */
  size_t features_moved;    /*   taken by a node moved onto them */
  size_t features_inserted; /*   made nodes of their own (cells fanned about them) */
  size_t features_missed;   /*   neither (in no cell, or two in one cell) */
  size_t warped;            /* nodes moved onto an interface */
  size_t crossings;         /* nodes made where an interface crosses an edge */
  size_t cut;               /* cells cut */
  size_t unresolved;        /* cells a loop meets in a way they cannot be cut along */
  size_t across;            /* cells left with free nodes in two regions */
  size_t smoothed;          /* moves of the smoothing along the interfaces */
} mx_qcleave_stats;

int mx_qcleave(mx_qmesh *M, const mx_qregions *R, uint16_t **region, mx_qcleave_stats *stats);

/* ---- quality (qquality.c) ------------------------------------------------ */

/* Scaled Jacobian of a cell: quad, the least over its corners of
 * cross(e1, e2) / (|e1| |e2|); triangle, the same at its corners divided by
 * sin(60 degrees) (an equilateral triangle is 1). Negative: inverted. */
double mx_qcell_sj(const mx_qmesh *M, size_t c);
/* The smallest interior angle of a cell, in degrees. */
double mx_qcell_min_angle(const mx_qmesh *M, size_t c);
/* The same measures on a polygon given by node ids v[0..nv) (nv 3 or 4) into
 * xy: the boundary step rates cells it has not written yet (a quad split
 * along a diagonal, a node dropped). mx_qangle_at: the interior angle at
 * corner k in [0, 360) degrees (over 180: reflex or inverted). */
double mx_qsj_nodes(const double *xy, const uint32_t *v, int nv);
double mx_qangle_at(const double *xy, const uint32_t *v, int nv, int k);

#define MX_QBINS 6
typedef struct {
  size_t count[2];          /* triangles, quads */
  double min[2], mean[2], max[2]; /* scaled Jacobian per type */
  double min_angle;         /* over all cells, degrees */
  size_t bins[MX_QBINS];    /* scaled Jacobian <0.03 <0.2 <0.4 <0.6 <0.8 <=1 */
  size_t invalid;           /* scaled Jacobian <= 0 */
  double area;              /* sum of the cells' areas */
} mx_qquality;

void mx_qquality_measure(const mx_qmesh *M, mx_qquality *q);

/* ---- checks (qcheck.c) ----------------------------------------------------- */

/* Writing: mesher/qmesh_output.h (through io's 2D mesh view). */

/* Independent checks of a 2D mesh: conformity (every edge used by one or two
 * cells, twice in opposite directions; no node lying inside another cell's
 * edge), orientation (every cell counter-clockwise, scaled Jacobian > 0),
 * when a domain is given: boundary edges on its polylines (within tol of the
 * domain's size), features as vertices, and the area against the polygons'
 * (relative difference). */
typedef struct {
  size_t bad_edges, hanging, inverted, off_boundary, missing_features;
  double area, domain_area, area_error;
  /* Added for mesher2d (the topology: a mesh that lost a thin part of the
   * domain, or split it, has another Euler characteristic): the distinct
   * edges, those used by one cell, V - E + F over the nodes used, and with
   * a domain its outer loops minus its holes (by orientation). */
  size_t edges, boundary_edges;
  long euler, domain_euler;
} mx_qcheck_report;

int mx_qmesh_check(const mx_qmesh *M, const mx_poly *domain, double tol, mx_qcheck_report *r);

#endif
