/* Private to src/verify/: what the checker's passes share -- the flags
 * they set on nodes and elements, the faces of each element type, the unit
 * coordinates of the nodes' box, the face keys, the coordinate hash of the
 * nodes (built by check_duplicates.c) and the face buckets (check_faces.c)
 * that later passes look things up in -- and each pass's entry point. One
 * pass a file, each saying at its head what it checks and how;
 * verify/check.c runs them in order. Nothing here is public: the checker's
 * interface is verify/check.h. */
#ifndef MX_CHECK_PASSES_H
#define MX_CHECK_PASSES_H

#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "base/common.h"
#include "soa/mesh_data.h"
#include "soa/trisoup.h"
#include "verify/check.h"

enum {
  CHUNK = 16384,
  SMALL = 16384, /* fewer items: no parallel region (its cost would dominate) */
  /* node flags */
  F_USED = 1,
  F_HANG = 2,
  F_BND = 4,
  F_DUP = 8,
  F_GHANG = 16,
  F_OFF = 32,
  F_IFACE = 64, /* a node of a face between two labels */
  F_IOFF = 128, /* an interface node off the surface */
};

/* Faces of each element type, outward (the same as soa/mesh.h's). */
static const int8_t face_tab[4][6][4] = {
    {{0, 2, 1, -1}, {0, 1, 3, -1}, {1, 2, 3, -1}, {0, 3, 2, -1}},
    {{0, 3, 2, 1}, {0, 1, 4, -1}, {1, 2, 4, -1}, {2, 3, 4, -1}, {3, 0, 4, -1}},
    {{0, 2, 1, -1}, {3, 4, 5, -1}, {0, 1, 4, 3}, {1, 2, 5, 4}, {2, 0, 3, 5}},
    {{0, 3, 2, 1},
     {4, 5, 6, 7},
     {0, 1, 5, 4},
     {1, 2, 6, 5},
     {2, 3, 7, 6},
     {3, 0, 4, 7}}};
static const int nfaces[4] = {4, 5, 5, 6};

static inline void flag_or(uint8_t *f, uint8_t bits) {
  __atomic_fetch_or(f, bits, __ATOMIC_RELAXED);
}

static inline uint8_t flag_get(const uint8_t *f) {
  return __atomic_load_n(f, __ATOMIC_RELAXED);
}

/* Element flags: bit MX_CK_* per element. */
static inline void eflag(uint8_t *ef, size_t c, int kind) {
  const uint8_t bit = (uint8_t)(1u << kind);
  if (!(flag_get(&ef[c]) & bit)) flag_or(&ef[c], bit);
}

/* ---- unit coordinates ------------------------------------------------------
 *
 * u = (x/2 - lo/2) * inv with inv = 1 / (largest half extent): u is in
 * [0, 1] for the nodes' box, finite for any finite x, and a monotonic
 * function of x (each step is), so a point inside a box stays inside its
 * image. ok is 0 when the box is one point, or its extent is too small to
 * divide by (below about 1e-300). */
typedef struct {
  double lo2[3], inv, ext[3]; /* ext: the half extents times inv, in [0, 1] */
  int ok;
} ubox;

static inline void ubox_init(ubox *U, const double lo[3], const double hi[3]) {
  double m = 0.0;
  for (int a = 0; a < 3; a++) {
    U->lo2[a] = 0.5 * lo[a];
    m = mx_max(m, 0.5 * hi[a] - 0.5 * lo[a]);
  }
  U->inv = 1.0 / m;
  U->ok = m > 0.0 && isfinite(m) && isfinite(U->inv) && U->inv > 0.0;
  if (!U->ok) U->inv = 0.0;
  for (int a = 0; a < 3; a++)
    U->ext[a] = U->ok ? mx_min(1.0, (0.5 * hi[a] - U->lo2[a]) * U->inv) : 0.0;
}

static inline double ucoord(const ubox *U, double x, int a) {
  return (0.5 * x - U->lo2[a]) * U->inv;
}

/* ---- faces --------------------------------------------------------------- */

/* Nodes of face slot s in the element's (outward) cyclic order. */
static inline int face_verts(const mx_mesh_data *m, uint32_t s,
                             uint32_t v[4]) {
  const size_t c = s / 6;
  const int8_t *f = face_tab[m->type[c]][s % 6];
  const uint32_t *row = m->conn + 8 * c;
  v[0] = row[f[0]];
  v[1] = row[f[1]];
  v[2] = row[f[2]];
  if (f[3] < 0) return 3;
  v[3] = row[f[3]];
  return 4;
}

static inline void sort4(uint32_t *v, int n) {
  for (int i = 1; i < n; i++) {
    uint32_t x = v[i];
    int j = i;
    for (; j > 0 && v[j - 1] > x; j--) v[j] = v[j - 1];
    v[j] = x;
  }
}

static inline uint32_t min_vertex(const uint32_t *v, int n) {
  uint32_t x = v[0] < v[1] ? v[0] : v[1];
  x = x < v[2] ? x : v[2];
  if (n == 4) x = x < v[3] ? x : v[3];
  return x;
}

/* The sorted node set without its smallest node (the bucket), and the node
 * count: triangles and quads never compare equal. */
typedef struct {
  uint64_t hi, lo;
  uint32_t slot;
} fkey;

static inline fkey key_of(uint32_t n, const uint32_t *sorted, uint32_t slot) {
  fkey k;
  k.hi = ((uint64_t)n << 32) | sorted[1];
  k.lo = ((uint64_t)sorted[2] << 32) | (n == 4 ? sorted[3] : 0);
  k.slot = slot;
  return k;
}

static inline fkey slot_key(const mx_mesh_data *m, uint32_t s) {
  uint32_t v[4];
  int n = face_verts(m, s, v);
  sort4(v, n);
  return key_of((uint32_t)n, v, s);
}

static inline int key_cmp(const fkey *a, const fkey *b) {
  if (a->hi != b->hi) return a->hi < b->hi ? -1 : 1;
  if (a->lo != b->lo) return a->lo < b->lo ? -1 : 1;
  return 0;
}

/* Cubic cells over a box of extents ext: about `target` of them over the
 * dimensions wider than a cell, at most maxdim per axis (check_geometry.c). */
void mx_ck_cell_grid(const double ext[3], double target, int maxdim,
                     double *h_out, int d[3]);
/* Squared distance from p to the triangle a-b-c (check_geometry.c). */
double mx_ck_point_triangle_d2(const double p[3], const double a[3],
                               const double b[3], const double c[3]);

/* ---- triangles and their tree (check_geometry.c) -------------------------
 *
 * Triangles given as index triples into coordinates read with a stride:
 * vertex v is (x[stride v], y[stride v], z[stride v]) -- a surface's SoA
 * arrays (stride 1) or a mesh's interleaved xyz (stride 3). */
typedef struct {
  const double *x, *y, *z;
  size_t stride;
  const uint32_t *tri; /* 3 * nt */
  size_t nt;
} ck_tris;

static inline ck_tris ck_soup_tris(const mx_trisoup *s) {
  return (ck_tris){s->x, s->y, s->z, 1, s->tri, s->nt};
}

static inline void ck_tri_vertex(const ck_tris *T, size_t t, int k, double p[3]) {
  const size_t v = T->stride * T->tri[3 * t + (size_t)k];
  p[0] = T->x[v];
  p[1] = T->y[v];
  p[2] = T->z[v];
}

/* A tree of triangles (check_geometry.c): the triangles in the tree's
 * order, each as CK_TV numbers (its vertices, then its box: lo x y z, hi
 * x y z), and the nodes, node 1 the root, i's children 2i and 2i + 1 over
 * the two halves of its triangles; a leaf when it has CK_LEAF or fewer. */
enum { CK_LEAF = 8, CK_TV = 15 };
typedef struct {
  double box[6];
  uint32_t lo, hi; /* its triangles, [lo, hi) in the tree's order */
} ck_node;
typedef struct {
  size_t nt;
  double *tv;
  ck_node *node;
} ck_tree;

/* MX_OK or MX_ENOMEM (R then freed). */
int mx_ck_tree_build(ck_tree *R, const ck_tris *T);
void mx_ck_tree_free(ck_tree *R);
/* Squared distance from p to the nearest triangle when it is below
 * `below` (INFINITY: any), else `below`; INFINITY without triangles. */
double mx_ck_tree_d2(const ck_tree *R, const double p[3], double below);
/* The triangles (their places in the tree's order) whose boxes lie within
 * u of the box (lo x y z, hi x y z), into list; SIZE_MAX when more than
 * cap, or u is not finite. */
size_t mx_ck_tree_near_box(const ck_tree *R, const double box[6], double u, uint32_t *list,
                           size_t cap);

/* Squared distance from p to the box lo-hi (0 inside). */
static inline double ck_box_d2(const double p[3], const double lo[3], const double hi[3]) {
  double d2 = 0.0;
  for (int a = 0; a < 3; a++) {
    const double d = mx_max(mx_max(lo[a] - p[a], p[a] - hi[a]), 0.0);
    d2 += d * d;
  }
  return d2;
}

/* ---- coordinate hash -----------------------------------------------------
 *
 * Exact coordinates -> smallest node id. To keep lookups cache-friendly the
 * table is cut by a coarse uniform grid over the nodes' bounding box (about
 * 8 nodes per cell): each cell owns a segment of slots, a power of two at
 * least 4 times its node count, and points are hashed inside the segment of
 * their cell. Elements that are near in memory are near in space in the
 * meshes we write, so their lookups touch the same few segments. A point's
 * cell is a function of its coordinates alone, so equal points meet. */

typedef struct {
  uint64_t *slot; /* 0: empty, else fingerprint << 32 | (node + 1) */
  uint64_t *seg;  /* cells + 1: cell c owns slots [seg[c], seg[c + 1]) */
  double lo[3], hi[3]; /* the nodes' box */
  ubox U;
  double scale; /* cell coordinate: unit coordinate * scale */
  int d[3];
  const double *xyz;
} chash;

typedef struct {
  uint64_t base, mask, h;
} cprobe;

static inline uint64_t mix64(uint64_t x) {
  x ^= x >> 33;
  x *= 0xff51afd7ed558ccdull;
  x ^= x >> 33;
  x *= 0xc4ceb9fe1a85ec53ull;
  x ^= x >> 33;
  return x;
}

static inline uint64_t dbits(double x) {
  x += 0.0; /* -0.0 -> +0.0: equal coordinates hash alike */
  uint64_t b;
  memcpy(&b, &x, 8);
  return b;
}

static inline uint64_t coord_hash(const double q[3]) {
  return mix64(dbits(q[0]) + 0x9E3779B97F4A7C15ull * dbits(q[1]) +
               0xC2B2AE3D27D4EB4Full * mix64(dbits(q[2])));
}

static inline int same_point(const double *a, const double *b) {
  return a[0] == b[0] && a[1] == b[1] && a[2] == b[2];
}

/* The coarse cell of q, or -1 outside the nodes' box (no node there). */
static inline int64_t chash_cell(const chash *H, const double q[3]) {
  int64_t c = 0;
  for (int a = 2; a >= 0; a--) {
    if (!(q[a] >= H->lo[a] && q[a] <= H->hi[a])) return -1;
    const double f = floor(ucoord(&H->U, q[a], a) * H->scale);
    const int i = !(f > 0.0)                 ? 0
                  : f > (double)(H->d[a] - 1) ? H->d[a] - 1
                                              : (int)f;
    c = c * H->d[a] + i;
  }
  return c;
}

/* Where q would be: 0 if it cannot be in the table at all. */
static inline int chash_probe(const chash *H, const double q[3], cprobe *p) {
  const int64_t c = chash_cell(H, q);
  if (c < 0) return 0;
  p->base = H->seg[c];
  const uint64_t size = H->seg[c + 1] - p->base;
  if (size == 0) return 0;
  p->mask = size - 1;
  p->h = coord_hash(q);
  return 1;
}

/* The smallest node at exactly q, or -1. Most lookups miss: the first two
 * slots settle that without a hard-to-predict branch. */
static inline int64_t chash_lookup(const chash *H, const double q[3],
                                   const cprobe *p) {
  const uint32_t fp = (uint32_t)(p->h >> 32);
  const uint64_t *seg = H->slot + p->base, i0 = p->h & p->mask;
  const uint64_t e0 = seg[i0], e1 = seg[(i0 + 1) & p->mask];
  const int miss = (e0 == 0) | (((uint32_t)(e0 >> 32) != fp) & (e1 == 0));
  if (__builtin_expect(miss, 1)) return -1;
  for (uint64_t i = i0;; i = (i + 1) & p->mask) {
    const uint64_t e = H->slot[p->base + i];
    if (!e) return -1;
    if ((uint32_t)(e >> 32) == fp) {
      const uint32_t id = (uint32_t)e - 1;
      if (same_point(H->xyz + 3 * (size_t)id, q)) return id;
    }
  }
}

static inline int64_t chash_find(const chash *H, const double q[3]) {
  cprobe p;
  return chash_probe(H, q, &p) ? chash_lookup(H, q, &p) : -1;
}

/* Flags node id as hanging when it is used and not one of the n nodes in
 * verts; returns whether it did. */
static inline int mark_hanging(uint8_t *flags, int64_t id,
                               const uint32_t *verts, int n) {
  if (id < 0 || !(flag_get(&flags[id]) & F_USED)) return 0;
  for (int k = 0; k < n; k++)
    if (verts[k] == (uint32_t)id) return 0;
  flag_or(&flags[id], F_HANG);
  return 1;
}

static inline void midpoint(const double *a, const double *b, double q[3]) {
  for (int x = 0; x < 3; x++) q[x] = (a[x] + b[x]) * 0.5;
}

/* The face buckets of pass 3 (check_faces.c). */
typedef struct {
  uint64_t *end;  /* nnodes: end of each node's bucket in slots */
  uint32_t *slot; /* face slots, bucket by bucket, sorted inside */
  uint8_t *use;   /* 6 * ncells: uses of each face slot's key (max 255) */
} faces;

static inline void faces_free(faces *F) {
  mx_free(F->end);
  mx_free(F->slot);
  mx_free(F->use);
}

static inline uint64_t bucket_begin(const faces *F, size_t v) {
  return v ? F->end[v - 1] : 0;
}

typedef struct {
  size_t interior, boundary, overshared, misoriented;
} face_counts;

/* ---- the passes, in the order check.c runs them ------------------------- */

/* Validity (check_validity.c): J_ENS of every element (invalid,
 * degenerate), the volume, the counts per type; flags the used nodes. */
int mx_ck_element_pass(const mx_mesh_data *m, uint8_t *flags, uint8_t *ef,
                       double degen_below, mx_check_report *r);
/* Duplicate nodes (check_duplicates.c): every node into the coordinate
 * hash H; *dups: the nodes whose point was already there. */
int mx_ck_chash_build(chash *H, const mx_mesh_data *m, size_t *dups);
/* Face matching (check_faces.c): the faces into the buckets of their
 * smallest node, then matched: uses, orientation, the quad centres (H NULL:
 * the uses and orientation only, flags not read; check_features.c). */
int mx_ck_faces_bucket(const mx_mesh_data *m, faces *F);
int mx_ck_faces_match(const mx_mesh_data *m, faces *F, const chash *H,
                      uint8_t *flags, uint8_t *ef, face_counts *fc);
/* The second slot of the face with sorted nodes v (n of them), after the one
 * mx_ck_find_slot gives; -1 when the face has one use only. */
int64_t mx_ck_find_second(const mx_mesh_data *m, const faces *F, const uint32_t *v, int n);
/* Both at once (one search): *first as mx_ck_find_slot, *second as
 * mx_ck_find_second. */
void mx_ck_find_pair(const mx_mesh_data *m, const faces *F, const uint32_t *v, int n,
                     int64_t *first, int64_t *second);
/* The first slot of a face with the sorted nodes v (n of them), or -1. */
int64_t mx_ck_find_slot(const mx_mesh_data *m, const faces *F,
                        const uint32_t *v, int n);
/* Hanging nodes (check_hanging.c): nodes at an element's edge midpoints. */
void mx_ck_edge_midpoints(const mx_mesh_data *m, const chash *H,
                          uint8_t *flags, uint8_t *ef);
/* Closed boundary (check_boundary.c): quads against triangles, open and
 * non-manifold edges of the boundary faces; flags the boundary nodes. */
int mx_ck_boundary_pass(const mx_mesh_data *m, const faces *F, uint8_t *flags,
                        uint8_t *ef, size_t nbnd, mx_check_report *r);
/* The file's point field boundary (m->node_bnd; one material) against the
 * boundary nodes that pass flagged: boundary_flags_off and its first nodes
 * (check_boundary.c). */
void mx_ck_boundary_flags(const mx_mesh_data *m, const uint8_t *flags, mx_check_report *r);
/* Boundary tags (check_tags.c). */
/* check_labels.c: the labels' elements and volumes, the faces between two
 * labels (their nodes flagged F_IFACE); other (6 ncells): the slot across
 * each face slot used twice, UINT32_MAX for the others. */
int mx_ck_label_pass(const mx_mesh_data *m, const faces *F, uint8_t *flags, uint32_t *other,
                     mx_check_report *r);
/* Each label's boundary closed (labels_open) and its edges used more than
 * twice, from the faces that bound it (other: mx_ck_label_pass's). */
int mx_ck_label_boundaries(const mx_mesh_data *m, const faces *F, const uint32_t *other,
                           mx_check_report *r);
int mx_ck_tag_pass(const mx_mesh_data *m, const faces *F, mx_check_report *r,
                   mx_check_tags *tags);
/* Geometric hanging nodes (check_contacts.c). */
int mx_ck_geometric_pass(const mx_mesh_data *m, const faces *F, const ubox *U,
                         uint8_t *flags, uint8_t *ef, double tol,
                         mx_check_report *r);
/* A surface given as several files (check_pieces.c, whose head defines
 * the pieces and their regions): its pieces, the forest of their nesting,
 * and the regions they cut out. */
enum { MX_CK_MAX_PIECES = 4096 };
struct mx_surface_index;
typedef struct {
  uint32_t n;                      /* pieces */
  mx_trisoup *soup;                /* n: each piece's triangles */
  struct mx_surface_index *index;  /* n: over each soup, turned outward */
  double (*box)[6];                /* n: lo x y z, hi x y z */
  int32_t *parent;                 /* n: the innermost piece around it, -1 */
  uint32_t *depth;                 /* n: the pieces around it */
  uint16_t *file;                  /* n: its file (soa/trisoup.h shell) */
  int *region;                     /* n: the region inside it (>= 1) */
  double *volume;                  /* n: the volume it encloses */
  uint32_t *child_off, *child;     /* the children of piece p:
                                    * child[child_off[p + 1] .. child_off[p + 2]),
                                    * the roots at p = -1 */
  int nregions;                    /* regions 1 .. nregions (0: outside) */
  double *region_volume;           /* nregions + 1 */
  double union_volume;             /* the roots' volumes summed */
  double parity_volume;            /* the pieces' volumes, those at odd
                                    * depths subtracted (nested pieces as
                                    * holes) */
} ck_pieces;
/* The files of a surface: 1 + its largest shell (0 without triangles). */
uint32_t mx_ck_surface_files(const mx_trisoup *s);
/* MX_OK, MX_ENOMEM, or MX_EINPUT (message printed) beyond MX_CK_MAX_PIECES
 * pieces; P freed on failure. */
int mx_ck_pieces_build(ck_pieces *P, const mx_trisoup *s);
void mx_ck_pieces_free(ck_pieces *P);
/* p's region (0 outside every piece); whether p lies within `on` of a
 * piece's triangle. */
int mx_ck_pieces_region(const ck_pieces *P, const double p[3]);
int mx_ck_pieces_on(const ck_pieces *P, const double p[3], double on);
/* shared[t] (nt bytes) = 1 for the triangles whose three points are those
 * of a triangle of another file, *nshared of them. MX_OK or MX_ENOMEM. */
int mx_ck_shared_triangles(const mx_trisoup *s, uint8_t *shared, size_t *nshared);
/* How a point's region is told: from an index S built outward over a
 * surface of one file (the nesting depth), or from the pieces P of several
 * files (the other NULL). */
typedef struct {
  const struct mx_surface_index *S;
  const ck_pieces *P;
} ck_locate;
/* Regions (check_regions.c): each element's region in reg: the one its
 * centroid and its corners off the shells all lie in, -1 when none of them
 * is off the shells, -2 when they lie in two regions (across_interface). */
int mx_ck_element_regions(const mx_mesh_data *m, const mx_trisoup *surface,
                          const ck_locate *L, int16_t *reg, mx_check_report *r);
/* With a closed surface: the volume of each region it cuts out (its
 * shells' nesting; with several files, P's regions: check_pieces.c, NULL
 * with one file), each element's region (mx_ck_element_regions), each
 * label's region (where most of its elements lie) and volume error, the
 * elements in another region than their label's (off_label_region); the
 * whole mesh's volume then compared with the outermost shells' (several
 * files: the union of the pieces; surface_volume, volume_error). The
 * verdict (after the whole mesh's, which sets volume_tol): labels_off. */
int mx_ck_label_regions(const mx_mesh_data *m, const mx_trisoup *surface, const ck_pieces *P,
                        mx_check_report *r);
void mx_ck_label_verdict(mx_check_report *r);
/* The mean of cell c's nodes. */
static inline void mx_ck_centroid(const mx_mesh_data *m, size_t c, double g[3]) {
  const int nv = mx_cell_nodes[m->type[c]];
  g[0] = g[1] = g[2] = 0.0;
  for (int j = 0; j < nv; j++)
    for (int a = 0; a < 3; a++) g[a] += m->xyz[3 * (size_t)m->conn[8 * c + (size_t)j] + a] / nv;
}
/* Volume (check_volume.c): whether the surface is closed, the volume it
 * encloses, the mesh's volume error; then, with a closed surface, whether
 * that error is beyond the tolerance. */
int mx_ck_surface_volume(const mx_trisoup *s, mx_check_report *r);
/* skip (NULL: none): the triangles left out of the surface's area (those
 * two files share: interfaces, not the boundary). */
void mx_ck_volume_verdict(const mx_mesh_data *m, const mx_trisoup *s, const uint8_t *skip,
                          const mx_check_options *o, mx_check_report *r);
/* Distance to the surface (check_distance.c): of every boundary and
 * interface node, its square into node_d2[node] (NULL: not kept). */
int mx_ck_surface_distance(const mx_mesh_data *m, const mx_trisoup *s,
                           uint8_t *flags, double tol, double *node_d2, mx_check_report *r);
/* The distance between the mesh's skin -- the face slots skin[0, nskin):
 * its boundary faces and, with cell labels, its interface faces once -- and
 * a closed surface, both ways, sampled (check_distance.c; the definitions
 * in check.h); node_d2: mx_ck_surface_distance's. */
int mx_ck_two_sided_distance(const mx_mesh_data *m, const mx_trisoup *s, const uint32_t *skin,
                             size_t nskin, const double *node_d2, mx_check_report *r);

#endif
