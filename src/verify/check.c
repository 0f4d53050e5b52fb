/* mixoct: the independent mesh checker (definitions in check.h).
 *
 * Passes, each parallel:
 *  1. elements: J_ENS (invalid, degenerate), volume, counts per type, used
 *     nodes;
 *  2. nodes: an open-addressing hash of the exact coordinates, cut into
 *     segments by a coarse grid for locality (lock-free insertion with
 *     compare-and-swap, the smallest id kept per point), gives the
 *     duplicates and later the midpoint lookups;
 *  3. faces: every face goes into the bucket of its smallest node (a
 *     counting sort), each bucket is sorted by the remaining sorted node ids
 *     and then the face slot, and equal runs are the faces' uses. Buckets
 *     stay sorted for the triangle lookups of the quad-vs-triangles test;
 *  4. element edge midpoints and quad face centres against the hash;
 *  5. boundary faces: quads against triangles, edges sorted and counted;
 *     the tagged faces looked up in the buckets (the tags' counts: faces
 *     sorted by tag, each tag's edges sorted and counted);
 *  6. geometric hanging nodes: every element with a face used once goes, by
 *     its bounding box, into the cells it meets (at most 2 per axis) of the
 *     level of a multi-level grid whose cells are at least its size (cells
 *     of level l have side 2^-l of the nodes' box); each node of a face
 *     used once then looks at its own cell on every occupied level and
 *     tests the elements whose box holds it: O(n) lookups, O(n log n) for
 *     the sort of the cells;
 *  7. with a surface: enclosed volume, whether it is closed, and the
 *     distance of the boundary nodes to the triangles through a uniform
 *     grid of triangle boxes.
 * Coordinates enter the grids as (x/2 - lo/2) / (extent/2): finite for any
 * finite input (extents up to 2 * DBL_MAX, down to 1e-300).
 * A face is named by its slot 6 * cell + local face, so ncells is limited to
 * (2^32 - 1) / 6. */
#include "verify/check.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "base/common.h"
#include "geom/quality.h"
#include "soa/mesh.h"
#include "base/scan.h"

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
};

const char *const mx_check_elem_kind_name[MX_CK_ELEM_KINDS] = {
    "invalid",           "degenerate",          "faces_overshared",
    "faces_misoriented", "quad_vs_triangles",   "open_boundary_edges",
    "hanging_nodes",     "geometric_hanging_nodes"};
const char *const mx_check_node_kind_name[MX_CK_NODE_KINDS] = {
    "unused_nodes", "duplicate_nodes", "hanging_nodes",
    "geometric_hanging_nodes", "boundary_off_surface"};

void mx_check_defaults(mx_check_options *o) {
  o->degenerate_below = 1e-6;
  o->hang_tol = 1e-9;
  o->volume_tol = 0.0; /* chosen from the mesh */
  o->volume_tol_auto = 0;
  o->boundary_tol = 1e-6;
}

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

static const int8_t edge_tab[4][12][2] = {
    {{0, 1}, {1, 2}, {2, 0}, {0, 3}, {1, 3}, {2, 3}},
    {{0, 1}, {1, 2}, {2, 3}, {3, 0}, {0, 4}, {1, 4}, {2, 4}, {3, 4}},
    {{0, 1}, {1, 2}, {2, 0}, {3, 4}, {4, 5}, {5, 3}, {0, 3}, {1, 4}, {2, 5}},
    {{0, 1},
     {1, 2},
     {2, 3},
     {3, 0},
     {4, 5},
     {5, 6},
     {6, 7},
     {7, 4},
     {0, 4},
     {1, 5},
     {2, 6},
     {3, 7}}};
static const int nedges[4] = {6, 8, 9, 12};

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

static void ubox_init(ubox *U, const double lo[3], const double hi[3]) {
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

static int fkey_qcmp(const void *pa, const void *pb) {
  const fkey *a = pa, *b = pb;
  int c = key_cmp(a, b);
  if (c) return c;
  return (a->slot > b->slot) - (a->slot < b->slot);
}

static void sort_keys(fkey *k, size_t n) {
  if (n > 48) {
    qsort(k, n, sizeof *k, fkey_qcmp);
    return;
  }
  for (size_t i = 1; i < n; i++) {
    fkey x = k[i];
    size_t j = i;
    for (; j > 0 && fkey_qcmp(&k[j - 1], &x) > 0; j--) k[j] = k[j - 1];
    k[j] = x;
  }
}

/* Whether the two uses of a face run through it in opposite cyclic orders. */
static int opposite(const mx_mesh_data *m, uint32_t s1, uint32_t s2) {
  uint32_t a[4], b[4];
  const int n = face_verts(m, s1, a);
  face_verts(m, s2, b);
  int ia = 0, ib = 0;
  for (int k = 1; k < n; k++) {
    if (a[k] < a[ia]) ia = k;
    if (b[k] < b[ib]) ib = k;
  }
  for (int k = 1; k < n; k++)
    if (a[(ia + k) % n] != b[(ib + n - k) % n]) return 0;
  return 1;
}

/* ---- uniform cells ------------------------------------------------------- */

/* Cubic cells over a box of extents ext: about `target` of them over the
 * dimensions wider than a cell, at most maxdim per axis. Sets h and d.
 * Works on the extents relative to the largest, each at least 1 / maxdim,
 * so no product underflows (a box of extents 1 x 1e-300 x 1e-300 gets
 * cells along its long side only). */
static void cell_grid(const double ext[3], double target, int maxdim,
                      double *h_out, int d[3]) {
  double mext = mx_max(ext[0], mx_max(ext[1], ext[2]));
  if (!(mext > 0.0) || !isfinite(mext)) { /* one point, or no range */
    d[0] = d[1] = d[2] = 1;
    *h_out = mext > 0.0 ? INFINITY : 1.0;
    return;
  }
  if (!(target >= 1.0)) target = 1.0;
  const double floor_r = 1.0 / maxdim;
  double r[3];
  for (int a = 0; a < 3; a++) r[a] = mx_max(ext[a] / mext, floor_r);
  double h = 0.0;
  for (int it = 0; it < 4; it++) {
    double prod = 1.0;
    int k = 0;
    for (int a = 0; a < 3; a++)
      if (r[a] > h) {
        prod *= r[a];
        k++;
      }
    if (k == 0) {
      prod = 1.0;
      k = 1;
    }
    h = mx_max(pow(prod / target, 1.0 / k), floor_r);
  }
  for (int a = 0; a < 3; a++) {
    const double n = ceil(ext[a] / mext / h);
    d[a] = !(n >= 1.0) ? 1 : n > maxdim ? maxdim : (int)n;
  }
  h *= mext;
  for (int a = 0; a < 3; a++) h = mx_max(h, ext[a] / d[a]);
  *h_out = h;
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

static void chash_box(chash *H, const mx_mesh_data *m) {
  double lo[3] = {INFINITY, INFINITY, INFINITY};
  double hi[3] = {-INFINITY, -INFINITY, -INFINITY};
  double lx = lo[0], ly = lo[1], lz = lo[2], hx = hi[0], hy = hi[1],
         hz = hi[2];
#pragma omp parallel for schedule(static) if (m->nnodes > 65536) \
    reduction(min : lx, ly, lz) reduction(max : hx, hy, hz)
  for (size_t n = 0; n < m->nnodes; n++) {
    const double *q = m->xyz + 3 * n;
    lx = mx_min(lx, q[0]);
    ly = mx_min(ly, q[1]);
    lz = mx_min(lz, q[2]);
    hx = mx_max(hx, q[0]);
    hy = mx_max(hy, q[1]);
    hz = mx_max(hz, q[2]);
  }
  if (m->nnodes == 0) lx = ly = lz = hx = hy = hz = 0.0;
  H->lo[0] = lx;
  H->lo[1] = ly;
  H->lo[2] = lz;
  H->hi[0] = hx;
  H->hi[1] = hy;
  H->hi[2] = hz;
  ubox_init(&H->U, H->lo, H->hi);
  double h = 1.0;
  H->d[0] = H->d[1] = H->d[2] = 1;
  if (H->U.ok) /* relative extents: cells of side h (a fraction of the box) */
    cell_grid(H->U.ext, (double)m->nnodes / 8.0, 2048, &h, H->d);
  H->scale = 1.0 / h;
  if (!H->U.ok || !isfinite(H->scale)) {
    H->d[0] = H->d[1] = H->d[2] = 1;
    H->scale = 0.0;
  }
}

/* Inserts every node; *dups receives the number of nodes whose point was
 * already there (duplicates). */
static int chash_build(chash *H, const mx_mesh_data *m, size_t *dups) {
  H->xyz = m->xyz;
  chash_box(H, m);
  const size_t ncells = (size_t)H->d[0] * H->d[1] * H->d[2];
  H->seg = mx_calloc((ncells + 1) * sizeof *H->seg);
  if (!H->seg) return MX_EINPUT;
#pragma omp parallel for schedule(static) if (m->nnodes > 65536)
  for (size_t n = 0; n < m->nnodes; n++) {
    const int64_t c = chash_cell(H, m->xyz + 3 * n);
    if (c >= 0) __atomic_fetch_add(&H->seg[c], 1, __ATOMIC_RELAXED);
  }
#pragma omp parallel for schedule(static) if (ncells > 65536)
  for (size_t c = 0; c < ncells; c++) {
    uint64_t size = H->seg[c] ? 4 : 0;
    while (size && size < 4 * H->seg[c]) size *= 2;
    H->seg[c] = size;
  }
  const uint64_t total = mx_scan_u64(H->seg, ncells + 1);
  H->slot = mx_calloc((size_t)total * sizeof *H->slot + 8);
  if (!H->slot) return MX_EINPUT;
  size_t d = 0;
#pragma omp parallel for schedule(static) reduction(+ : d) \
    if (m->nnodes > 65536)
  for (size_t n = 0; n < m->nnodes; n++) {
    const double *q = m->xyz + 3 * n;
    cprobe p;
    if (!chash_probe(H, q, &p)) continue; /* not finite */
    const uint64_t mine = (p.h >> 32) << 32 | (uint64_t)(n + 1);
    for (uint64_t i = p.h & p.mask;; i = (i + 1) & p.mask) {
      uint64_t *slot = &H->slot[p.base + i];
      uint64_t e = __atomic_load_n(slot, __ATOMIC_ACQUIRE);
      if (!e) {
        if (__atomic_compare_exchange_n(slot, &e, mine, 0, __ATOMIC_ACQ_REL,
                                        __ATOMIC_ACQUIRE))
          break;
        /* e now holds what another thread stored: examine it below. */
      }
      if ((e >> 32) == (p.h >> 32) &&
          same_point(m->xyz + 3 * (size_t)((uint32_t)e - 1), q)) {
        d++;
        /* Keep the smallest id for this point. */
        while ((uint32_t)e - 1 > n &&
               !__atomic_compare_exchange_n(slot, &e, mine, 0,
                                            __ATOMIC_ACQ_REL,
                                            __ATOMIC_ACQUIRE)) {
        }
        break;
      }
    }
  }
  *dups = d;
  return MX_OK;
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

/* ---- pass 1: elements ---------------------------------------------------- */

typedef struct {
  double vol, jsum, jmin;
  size_t invalid, degenerate, by[4];
} elem_acc;

/* J_ENS is invariant under scaling: elements whose coordinates reach beyond
 * 2^400 or stay below 2^-400 (where squares and triple products would
 * overflow or underflow) are scaled by a power of two first, which is
 * exact. Others are evaluated as they are, so their J_ENS is bit-identical
 * to mx_jens's. */
static double jens_scaled(int t, double p[8][3]) {
  const int nn = mx_cell_nodes[t];
  double mx = 0.0;
  for (int j = 0; j < nn; j++)
    for (int a = 0; a < 3; a++) mx = mx_max(mx, fabs(p[j][a]));
  if (mx > 0x1p400 || (mx > 0.0 && mx < 0x1p-400)) {
    int e;
    frexp(mx, &e);
    double q[8][3];
    for (int j = 0; j < nn; j++)
      for (int a = 0; a < 3; a++) q[j][a] = ldexp(p[j][a], -e);
    return mx_jens(t, (const double(*)[3])q);
  }
  return mx_jens(t, (const double(*)[3])p);
}

static int element_pass(const mx_mesh_data *m, uint8_t *flags, uint8_t *ef,
                        double degen_below, mx_check_report *r) {
  const size_t nc = m->ncells, nchunks = (nc + CHUNK - 1) / CHUNK;
  elem_acc *acc = mx_alloc((nchunks + 1) * sizeof *acc);
  if (!acc) return MX_EINPUT;
#pragma omp parallel for schedule(dynamic, 1) if (nchunks > 1)
  for (size_t k = 0; k < nchunks; k++) {
    elem_acc a = {0.0, 0.0, INFINITY, 0, 0, {0, 0, 0, 0}};
    const size_t end = (k + 1) * CHUNK < nc ? (k + 1) * CHUNK : nc;
    for (size_t c = k * CHUNK; c < end; c++) {
      const int t = m->type[c], nn = mx_cell_nodes[t];
      const uint32_t *row = m->conn + 8 * c;
      double p[8][3];
      for (int j = 0; j < nn; j++) {
        memcpy(p[j], m->xyz + 3 * (size_t)row[j], sizeof p[j]);
        if (!(flag_get(&flags[row[j]]) & F_USED))
          flag_or(&flags[row[j]], F_USED);
      }
      const double q = jens_scaled(t, p);
      a.vol += mx_element_volume(t, (const double(*)[3])p);
      a.jsum += q;
      if (q < a.jmin) a.jmin = q;
      if (!(q > 0.0)) {
        a.invalid++;
        ef[c] |= 1u << MX_CK_INVALID; /* this pass alone writes ef */
      } else if (q < degen_below) {
        a.degenerate++;
        ef[c] |= 1u << MX_CK_DEGENERATE;
      }
      a.by[t]++;
    }
    acc[k] = a;
  }
  double vol = 0.0, jsum = 0.0, jmin = INFINITY;
  for (size_t k = 0; k < nchunks; k++) {
    vol += acc[k].vol;
    jsum += acc[k].jsum;
    if (acc[k].jmin < jmin) jmin = acc[k].jmin;
    r->invalid += acc[k].invalid;
    r->degenerate += acc[k].degenerate;
    for (int t = 0; t < 4; t++) r->by_type[t] += acc[k].by[t];
  }
  mx_free(acc);
  r->volume = vol;
  r->jens_min = nc ? jmin : NAN;
  r->jens_mean = nc ? jsum / (double)nc : NAN;
  return MX_OK;
}

/* ---- pass 3: faces ------------------------------------------------------- */

typedef struct {
  uint64_t *end;  /* nnodes: end of each node's bucket in slots */
  uint32_t *slot; /* face slots, bucket by bucket, sorted inside */
  uint8_t *use;   /* 6 * ncells: uses of each face slot's key (max 255) */
} faces;

static void faces_free(faces *F) {
  mx_free(F->end);
  mx_free(F->slot);
  mx_free(F->use);
}

static int faces_bucket(const mx_mesh_data *m, faces *F) {
  const size_t nn = m->nnodes, nc = m->ncells;
  F->end = mx_calloc((nn + 1) * sizeof *F->end);
  F->use = mx_calloc(6 * nc + 1);
  if (!F->end || !F->use) return MX_EINPUT;
#pragma omp parallel for schedule(static) if (nc > SMALL)
  for (size_t c = 0; c < nc; c++) {
    for (int j = 0; j < nfaces[m->type[c]]; j++) {
      uint32_t v[4];
      int n = face_verts(m, (uint32_t)(6 * c + (size_t)j), v);
      __atomic_fetch_add(&F->end[min_vertex(v, n)], 1, __ATOMIC_RELAXED);
    }
  }
  const uint64_t total = mx_scan_u64(F->end, nn);
  F->slot = mx_alloc((size_t)total * sizeof *F->slot + 4);
  if (!F->slot) return MX_EINPUT;
#pragma omp parallel for schedule(static) if (nc > SMALL)
  for (size_t c = 0; c < nc; c++) {
    for (int j = 0; j < nfaces[m->type[c]]; j++) {
      const uint32_t s = (uint32_t)(6 * c + (size_t)j);
      uint32_t v[4];
      int n = face_verts(m, s, v);
      uint64_t at = __atomic_fetch_add(&F->end[min_vertex(v, n)], 1,
                                       __ATOMIC_RELAXED);
      F->slot[at] = s;
    }
  }
  return MX_OK; /* now end[v] is the end of bucket v, its start end[v-1] */
}

static inline uint64_t bucket_begin(const faces *F, size_t v) {
  return v ? F->end[v - 1] : 0;
}

typedef struct {
  size_t interior, boundary, overshared, misoriented;
} face_counts;

/* Sorts every bucket, records the uses of every slot, counts, and probes
 * the centres of quad faces. */
static int faces_match(const mx_mesh_data *m, faces *F, const chash *H,
                       uint8_t *flags, uint8_t *ef, face_counts *fc) {
  size_t interior = 0, boundary = 0, over = 0, mis = 0;
  int oom = 0;
#pragma omp parallel reduction(+ : interior, boundary, over, mis) \
    if (m->nnodes > SMALL)
  {
    size_t cap = 64;
    fkey *k = mx_alloc(cap * sizeof *k);
    if (!k) {
#pragma omp atomic write
      oom = 1;
    }
#pragma omp for schedule(dynamic, 2048)
    for (size_t v = 0; v < m->nnodes; v++) {
      const uint64_t b = bucket_begin(F, v), n = F->end[v] - b;
      if (n == 0 || !k) continue;
      if (n > cap) {
        fkey *nk = mx_realloc(k, (size_t)n * sizeof *k);
        if (!nk) {
#pragma omp atomic write
          oom = 1;
          continue;
        }
        k = nk;
        cap = (size_t)n;
      }
      for (uint64_t i = 0; i < n; i++) k[i] = slot_key(m, F->slot[b + i]);
      sort_keys(k, (size_t)n);
      for (uint64_t i = 0; i < n; i++) F->slot[b + i] = k[i].slot;
      for (uint64_t i = 0; i < n;) {
        uint64_t j = i + 1;
        while (j < n && key_cmp(&k[j], &k[i]) == 0) j++;
        const uint64_t g = j - i;
        for (uint64_t x = i; x < j; x++)
          F->use[k[x].slot] = (uint8_t)(g < 255 ? g : 255);
        if (g == 1)
          boundary++;
        else if (g == 2) {
          interior++;
          if (!opposite(m, k[i].slot, k[i + 1].slot)) {
            mis++;
            eflag(ef, k[i].slot / 6, MX_CK_MISORIENTED);
            eflag(ef, k[i + 1].slot / 6, MX_CK_MISORIENTED);
          }
        } else {
          over++;
          for (uint64_t x = i; x < j; x++)
            eflag(ef, k[x].slot / 6, MX_CK_OVERSHARED);
        }
        if ((k[i].hi >> 32) == 4) { /* quad: its centre */
          uint32_t fv[4] = {0, 0, 0, 0};
          face_verts(m, k[i].slot, fv);
          const double *p[4];
          for (int x = 0; x < 4; x++) p[x] = m->xyz + 3 * (size_t)fv[x];
          double q1[3], q2[3];
          midpoint(p[0], p[2], q1);
          midpoint(p[1], p[3], q2);
          int hit = mark_hanging(flags, chash_find(H, q1), fv, 4);
          if (!same_point(q1, q2))
            hit |= mark_hanging(flags, chash_find(H, q2), fv, 4);
          if (hit)
            for (uint64_t x = i; x < j; x++)
              eflag(ef, k[x].slot / 6, MX_CK_HANGING);
        }
        i = j;
      }
    }
    mx_free(k);
  }
  if (oom) return MX_EINPUT;
  fc->interior = interior;
  fc->boundary = boundary;
  fc->overshared = over;
  fc->misoriented = mis;
  return MX_OK;
}

/* The first slot (in its sorted bucket) of a face with the sorted nodes v
 * (n of them), or -1. */
static int64_t find_slot(const mx_mesh_data *m, const faces *F,
                         const uint32_t *v, int n) {
  const fkey want = key_of((uint32_t)n, v, 0);
  uint64_t lo = bucket_begin(F, v[0]), hi = F->end[v[0]];
  while (lo < hi) { /* first entry not below want */
    const uint64_t mid = lo + (hi - lo) / 2;
    const fkey k = slot_key(m, F->slot[mid]);
    if (key_cmp(&k, &want) < 0)
      lo = mid + 1;
    else
      hi = mid;
  }
  if (lo == F->end[v[0]]) return -1;
  const fkey k = slot_key(m, F->slot[lo]);
  return key_cmp(&k, &want) == 0 ? (int64_t)F->slot[lo] : -1;
}

/* Whether the triangle a-b-c is a face used by exactly one element. */
static int boundary_triangle(const mx_mesh_data *m, const faces *F,
                             uint32_t a, uint32_t b, uint32_t c) {
  uint32_t v[4] = {a, b, c, 0};
  sort4(v, 3);
  const int64_t s = find_slot(m, F, v, 3);
  return s >= 0 && F->use[s] == 1;
}

/* ---- pass 4: edge midpoints ---------------------------------------------- */

static void edge_midpoints(const mx_mesh_data *m, const chash *H,
                           uint8_t *flags, uint8_t *ef) {
#pragma omp parallel for schedule(dynamic, 4096) if (m->ncells > SMALL)
  for (size_t c = 0; c < m->ncells; c++) {
    const int t = m->type[c], ne = nedges[t];
    const uint32_t *row = m->conn + 8 * c;
    double q[12][3];
    cprobe p[12];
    int live[12];
    for (int e = 0; e < ne; e++) {
      midpoint(m->xyz + 3 * (size_t)row[edge_tab[t][e][0]],
               m->xyz + 3 * (size_t)row[edge_tab[t][e][1]], q[e]);
      live[e] = chash_probe(H, q[e], &p[e]);
      if (live[e]) __builtin_prefetch(&H->slot[p[e].base + (p[e].h & p[e].mask)]);
    }
    int hit = 0;
    for (int e = 0; e < ne; e++)
      if (live[e])
        hit |= mark_hanging(flags, chash_lookup(H, q[e], &p[e]), row,
                            mx_cell_nodes[t]);
    if (hit) eflag(ef, c, MX_CK_HANGING);
  }
}

/* ---- pass 5: boundary ---------------------------------------------------- */

/* The number of entries equal to key in the sorted k[0, n). */
static size_t count_equal(const uint64_t *k, size_t n, uint64_t key) {
  size_t lo = 0, hi = n;
  while (lo < hi) {
    const size_t mid = lo + (hi - lo) / 2;
    if (k[mid] < key)
      lo = mid + 1;
    else
      hi = mid;
  }
  size_t e = lo;
  while (e < n && k[e] == key) e++;
  return e - lo;
}

static int boundary_pass(const mx_mesh_data *m, const faces *F,
                         uint8_t *flags, uint8_t *ef, size_t nbnd,
                         mx_check_report *r) {
  const size_t nslots = 6 * m->ncells;
  uint32_t *bnd = mx_alloc((nbnd + 1) * sizeof *bnd);
  uint64_t *ek = mx_alloc((4 * nbnd + 1) * sizeof *ek);
  if (!bnd || !ek) {
    mx_free(bnd);
    mx_free(ek);
    return MX_EINPUT;
  }
  size_t nb = 0;
  for (size_t s = 0; s < nslots; s++)
    if (F->use[s] == 1 && nb < nbnd) bnd[nb++] = (uint32_t)s;
  size_t qvt = 0;
#pragma omp parallel for schedule(dynamic, 1024) reduction(+ : qvt) \
    if (nb > SMALL)
  for (size_t i = 0; i < nb; i++) {
    uint32_t v[4];
    const int n = face_verts(m, bnd[i], v);
    for (int x = 0; x < n; x++) {
      flag_or(&flags[v[x]], F_BND);
      const uint32_t a = v[x], b = v[(x + 1) % n];
      ek[4 * i + (size_t)x] = a < b ? (uint64_t)a << 32 | b
                                    : (uint64_t)b << 32 | a;
    }
    if (n == 3) {
      ek[4 * i + 3] = UINT64_MAX;
      continue;
    }
    if ((boundary_triangle(m, F, v[0], v[1], v[2]) &&
         boundary_triangle(m, F, v[0], v[2], v[3])) ||
        (boundary_triangle(m, F, v[0], v[1], v[3]) &&
         boundary_triangle(m, F, v[1], v[2], v[3]))) {
      qvt++;
      eflag(ef, bnd[i] / 6, MX_CK_QUAD_TRI);
    }
  }
  r->quad_vs_triangles = qvt;
  int st = mx_sort_u64(ek, NULL, 4 * nb);
  size_t open = 0, pinched = 0;
  for (size_t i = 0; st == MX_OK && i < 4 * nb && ek[i] != UINT64_MAX;) {
    size_t j = i + 1;
    while (j < 4 * nb && ek[j] == ek[i]) j++;
    /* An odd count leaves the boundary open; 4, 6... boundary faces meet
     * where two parts of the domain touch along an edge: closed, not
     * manifold, and conforming. */
    open += (j - i) % 2 != 0;
    pinched += (j - i) % 2 == 0 && j - i > 2;
    i = j;
  }
  r->open_boundary_edges = open;
  r->nonmanifold_edges = pinched;
  if (st == MX_OK && open) { /* the elements along the open edges */
#pragma omp parallel for schedule(dynamic, 1024) if (nb > SMALL)
    for (size_t i = 0; i < nb; i++) {
      uint32_t v[4];
      const int n = face_verts(m, bnd[i], v);
      for (int x = 0; x < n; x++) {
        const uint32_t a = v[x], b = v[(x + 1) % n];
        const uint64_t key = a < b ? (uint64_t)a << 32 | b
                                   : (uint64_t)b << 32 | a;
        if (count_equal(ek, 4 * nb, key) % 2) {
          eflag(ef, bnd[i] / 6, MX_CK_OPEN_EDGE);
          break;
        }
      }
    }
  }
  mx_free(bnd);
  mx_free(ek);
  return st;
}

/* ---- pass 5b: boundary tags ----------------------------------------------- */

/* A sort key of tag t ordering tags as signed integers, with v below. */
static inline uint64_t tag_key(int32_t t, uint32_t v) {
  return (uint64_t)((uint32_t)t ^ 0x80000000u) << 32 | v;
}

static inline int32_t key_tag(uint64_t k) {
  return (int32_t)((uint32_t)(k >> 32) ^ 0x80000000u);
}

/* The names of m sorted by tag (keys as tag_key(tag, index)), or NULL. */
static int sorted_names(const mx_mesh_data *m, uint64_t **out) {
  *out = NULL;
  if (!m->nnames || !m->name || !m->name_tag || m->nnames >= UINT32_MAX)
    return MX_OK;
  uint64_t *k = mx_alloc(m->nnames * sizeof *k);
  if (!k) return MX_EINPUT;
  for (size_t i = 0; i < m->nnames; i++) k[i] = tag_key(m->name_tag[i], (uint32_t)i);
  const int st = mx_sort_u64(k, NULL, m->nnames);
  if (st != MX_OK) {
    mx_free(k);
    return st;
  }
  *out = k;
  return MX_OK;
}

/* The name of tag t (its first in the file), or NULL. */
static const char *tag_name(const mx_mesh_data *m, const uint64_t *k,
                            int32_t t) {
  if (!k) return NULL;
  size_t lo = 0, hi = m->nnames;
  const uint64_t want = tag_key(t, 0);
  while (lo < hi) {
    const size_t mid = lo + (hi - lo) / 2;
    if (k[mid] < want)
      lo = mid + 1;
    else
      hi = mid;
  }
  if (lo == m->nnames || key_tag(k[lo]) != t) return NULL;
  return m->name[(uint32_t)k[lo]];
}

/* Copies the names of the listed tags into tags->names. */
static int keep_names(mx_check_tag *list, size_t n, mx_check_tags *tags) {
  size_t total = 1;
  for (size_t i = 0; i < n; i++)
    if (list[i].name) total += strlen(list[i].name) + 1;
  char *buf = mx_alloc(total);
  if (!buf) return MX_EINPUT;
  size_t at = 0;
  for (size_t i = 0; i < n; i++) {
    if (!list[i].name) continue;
    const size_t l = strlen(list[i].name) + 1;
    memcpy(buf + at, list[i].name, l);
    list[i].name = buf + at;
    at += l;
  }
  tags->names = buf;
  return MX_OK;
}

/* The tags of the tagged faces, with their counts: faces sorted by tag,
 * then per tag its edges sorted and counted. bad[i]: face i is not a
 * boundary face. */
static int face_tag_list(const mx_mesh_data *m, const uint8_t *bad,
                         const uint64_t *names, mx_check_tag **out,
                         size_t *nout) {
  const size_t nf = m->nfaces;
  uint64_t *k = mx_alloc((nf + 1) * sizeof *k);
  uint64_t *ek = mx_alloc((4 * nf + 1) * sizeof *ek);
  if (!k || !ek) {
    mx_free(k);
    mx_free(ek);
    return MX_EINPUT;
  }
  for (size_t i = 0; i < nf; i++) k[i] = tag_key(m->face_tag[i], (uint32_t)i);
  int st = mx_sort_u64(k, NULL, nf);
  size_t nt = 0;
  for (size_t i = 0; st == MX_OK && i < nf; i++)
    nt += i == 0 || key_tag(k[i]) != key_tag(k[i - 1]);
  mx_check_tag *list = st == MX_OK ? mx_calloc((nt + 1) * sizeof *list) : NULL;
  if (st == MX_OK && !list) st = MX_EINPUT;
  size_t t = 0;
  for (size_t a = 0; st == MX_OK && a < nf; t++) {
    size_t b = a + 1;
    while (b < nf && key_tag(k[b]) == key_tag(k[a])) b++;
    mx_check_tag *g = &list[t];
    g->tag = key_tag(k[a]);
    g->name = tag_name(m, names, g->tag);
    size_t ne = 0;
    for (size_t x = a; x < b; x++) {
      const size_t f = (uint32_t)k[x];
      const int n = m->face_nn[f];
      const uint32_t *v = m->face_conn + 4 * f;
      g->triangles += n == 3;
      g->quads += n == 4;
      g->not_boundary += bad[f];
      for (int j = 0; j < n; j++) {
        const uint32_t p = v[j], q = v[(j + 1) % n];
        ek[ne++] = p < q ? (uint64_t)p << 32 | q : (uint64_t)q << 32 | p;
      }
    }
    st = mx_sort_u64(ek, NULL, ne);
    for (size_t i = 0; st == MX_OK && i < ne;) {
      size_t j = i + 1;
      while (j < ne && ek[j] == ek[i]) j++;
      g->open_edges += (j - i) % 2;
      i = j;
    }
    a = b;
  }
  mx_free(k);
  mx_free(ek);
  if (st != MX_OK) {
    mx_free(list);
    return st;
  }
  *out = list;
  *nout = nt;
  return MX_OK;
}

/* The values of the node tags but 0, with their node counts. */
static int node_tag_list(const mx_mesh_data *m, const uint64_t *names,
                         mx_check_tag **out, size_t *nout) {
  const size_t nn = m->nnodes;
  uint64_t *k = mx_alloc((nn + 1) * sizeof *k);
  if (!k) return MX_EINPUT;
#pragma omp parallel for schedule(static) if (nn > SMALL)
  for (size_t i = 0; i < nn; i++) k[i] = tag_key(m->node_tag[i], 0);
  int st = mx_sort_u64(k, NULL, nn);
  size_t nt = 0;
  for (size_t i = 0; st == MX_OK && i < nn; i++)
    nt += (i == 0 || k[i] != k[i - 1]) && key_tag(k[i]) != 0;
  mx_check_tag *list = st == MX_OK ? mx_calloc((nt + 1) * sizeof *list) : NULL;
  if (st == MX_OK && !list) st = MX_EINPUT;
  size_t t = 0;
  for (size_t a = 0; st == MX_OK && a < nn;) {
    size_t b = a + 1;
    while (b < nn && k[b] == k[a]) b++;
    if (key_tag(k[a]) != 0) {
      list[t].tag = key_tag(k[a]);
      list[t].name = tag_name(m, names, list[t].tag);
      list[t++].nodes = b - a;
    }
    a = b;
  }
  mx_free(k);
  if (st != MX_OK) {
    mx_free(list);
    return st;
  }
  *out = list;
  *nout = nt;
  return MX_OK;
}

/* Matches every tagged face with the faces of the elements (the buckets of
 * faces_match): the tagged faces that are not boundary faces, the boundary
 * faces no tagged face names; then, when tags is not NULL, the per-tag
 * lists. */
static int tag_pass(const mx_mesh_data *m, const faces *F,
                    mx_check_report *r, mx_check_tags *tags) {
  const size_t nf = m->nfaces, nslots = 6 * m->ncells;
  r->has_node_tags = m->node_tag != NULL;
  r->has_tagged_faces = nf > 0;
  r->tagged_faces = nf;
  if (!nf && !(tags && m->node_tag)) return MX_OK;
  uint8_t *named = mx_calloc(nslots + 1); /* boundary slot named by a face */
  uint8_t *bad = mx_alloc(nf + 1);       /* tagged face not a boundary face */
  if (!named || !bad) {
    mx_free(named);
    mx_free(bad);
    return MX_EINPUT;
  }
  size_t nb = 0;
#pragma omp parallel for schedule(dynamic, 1024) reduction(+ : nb) \
    if (nf > SMALL)
  for (size_t i = 0; i < nf; i++) {
    uint32_t v[4];
    const int n = m->face_nn[i];
    memcpy(v, m->face_conn + 4 * i, sizeof v);
    sort4(v, n);
    const int64_t s = find_slot(m, F, v, n);
    const int ok = s >= 0 && F->use[s] == 1;
    bad[i] = (uint8_t)!ok;
    nb += !ok;
    if (ok) __atomic_store_n(&named[s], 1, __ATOMIC_RELAXED);
  }
  r->tagged_not_boundary = nb;
  size_t un = 0;
  if (nf) {
#pragma omp parallel for schedule(static) reduction(+ : un) \
    if (nslots > SMALL)
    for (size_t s = 0; s < nslots; s++) un += F->use[s] == 1 && !named[s];
  }
  r->boundary_untagged = un;
  mx_check_ids *l = &r->not_boundary_ids;
  for (size_t i = 0; i < nf && nb && l->n < MX_CHECK_LIST; i++)
    if (bad[i]) l->id[l->n++] = (uint32_t)i;
  l = &r->untagged_ids;
  for (size_t s = 0; s < nslots && un && l->n < MX_CHECK_LIST; s++)
    if (F->use[s] == 1 && !named[s] &&
        (l->n == 0 || l->id[l->n - 1] != (uint32_t)(s / 6)))
      l->id[l->n++] = (uint32_t)(s / 6);
  mx_free(named);
  int st = MX_OK;
  if (tags) {
    uint64_t *names = NULL;
    st = sorted_names(m, &names);
    if (st == MX_OK && nf)
      st = face_tag_list(m, bad, names, &tags->face_tags, &tags->nface_tags);
    if (st == MX_OK && m->node_tag)
      st = node_tag_list(m, names, &tags->node_tags, &tags->nnode_tags);
    mx_free(names);
    mx_check_tag *all = NULL;
    const size_t n = tags->nface_tags + tags->nnode_tags;
    if (st == MX_OK && n) { /* both lists' names in one buffer */
      all = mx_alloc(n * sizeof *all);
      if (!all) st = MX_EINPUT;
    }
    if (all) {
      if (tags->nface_tags)
        memcpy(all, tags->face_tags, tags->nface_tags * sizeof *all);
      if (tags->nnode_tags)
        memcpy(all + tags->nface_tags, tags->node_tags,
               tags->nnode_tags * sizeof *all);
      st = keep_names(all, n, tags);
      for (size_t i = 0; st == MX_OK && i < tags->nface_tags; i++)
        tags->face_tags[i].name = all[i].name;
      for (size_t i = 0; st == MX_OK && i < tags->nnode_tags; i++)
        tags->node_tags[i].name = all[tags->nface_tags + i].name;
      mx_free(all);
    }
  }
  mx_free(bad);
  return st;
}

/* ---- pass 6: geometric hanging nodes --------------------------------------
 *
 * The elements to compare with go into a multi-level grid over the unit
 * coordinates (cells of level l have side 2^-l): each into every cell its
 * padded box meets on the level above the finest one whose cells are at
 * least as large as the box -- at most 2 per axis. A point in the box lies in one of those
 * cells (the cell of a coordinate is a monotonic function of it), so a
 * node looks at one cell per occupied level. Entries are sorted by cell
 * (radix sort); a hash of the cells gives their runs. Each entry keeps the
 * box in single precision, relative to its cell in units of the cell side
 * (rounded outwards), for a cheap first test. */

enum { GLEVELS = 21 }; /* 3 * 21 + 1 bits of key */

typedef struct {
  uint64_t key; /* 0: empty */
  uint32_t beg, end;
} gcell;

typedef struct {
  ubox U;
  double tol;
  uint32_t *elem; /* entries, sorted by cell */
  float *box;     /* 6 per entry */
  gcell *tab;
  uint64_t mask;
  uint32_t levels; /* bit l: some element at level l */
} ggrid;

static void ggrid_free(ggrid *g) {
  mx_free(g->elem);
  mx_free(g->box);
  mx_free(g->tab);
}

static inline uint64_t gkey(int lev, const uint32_t c[3]) {
  return (uint64_t)1 << (3 * lev) | (uint64_t)c[0] << (2 * lev) |
         (uint64_t)c[1] << lev | c[2];
}

static inline uint32_t gcoord(double u, int lev) {
  const double f = floor(u * (double)(1u << lev));
  const double top = (double)((1u << lev) - 1);
  if (!(f > 0.0)) return 0;
  return f > top ? (uint32_t)top : (uint32_t)f;
}

/* The padded unit box of element c and its level and low cell. */
static void elem_gbox(const mx_mesh_data *m, const ggrid *g, size_t c,
                      double lo[3], double hi[3], int *lev, uint32_t cell[3]) {
  const int nn = mx_cell_nodes[m->type[c]];
  const uint32_t *row = m->conn + 8 * c;
  for (int a = 0; a < 3; a++) {
    lo[a] = INFINITY;
    hi[a] = -INFINITY;
  }
  for (int j = 0; j < nn; j++) {
    const double *p = m->xyz + 3 * (size_t)row[j];
    for (int a = 0; a < 3; a++) {
      const double u = ucoord(&g->U, p[a], a);
      lo[a] = mx_min(lo[a], u);
      hi[a] = mx_max(hi[a], u);
    }
  }
  double size = 0.0;
  for (int a = 0; a < 3; a++) size = mx_max(size, hi[a] - lo[a]);
  /* the exact test's tolerance is tol * size (with rounding: 2x pad) */
  const double pad = 2.0 * g->tol * size + 0x1p-60;
  for (int a = 0; a < 3; a++) {
    lo[a] -= pad;
    hi[a] += pad;
  }
  const double span = (size + 2.0 * pad) * (1.0 + 1e-12);
  int l = GLEVELS;
  if (span > 0.0) {
    int e;
    const double f = frexp(span, &e); /* span = f 2^e, f in [0.5, 1) */
    l = f == 0.5 ? 1 - e : -e;        /* largest l with 2^-l >= span */
    l -= 2;
    l = l < 0 ? 0 : l > GLEVELS ? GLEVELS : l;
  }
  *lev = l;
  for (int a = 0; a < 3; a++) cell[a] = gcoord(lo[a], l);
}

/* x rounded to a float below (above) it: the nearest float is within half
 * a float ulp, less than |x| 2^-23 (+ a tiny term for x near 0). */
static inline float f_down(double x) {
  return (float)(x - fabs(x) * 0x1p-23 - 0x1p-100);
}

static inline float f_up(double x) {
  return (float)(x + fabs(x) * 0x1p-23 + 0x1p-100);
}

static inline uint64_t gslot_of(uint64_t key, uint64_t mask) {
  return mix64(key) & mask;
}

/* Files the n elements of list, each in every cell its box meets at its
 * level (at most 2 per axis). */
static int ggrid_build(ggrid *g, const mx_mesh_data *m, const ubox *U,
                       double tol, const uint32_t *list, size_t n) {
  memset(g, 0, sizeof *g);
  g->U = *U;
  g->tol = tol;
  uint64_t *off = mx_alloc((n + 1) * sizeof *off);
  double *ubx = mx_alloc((6 * n + 1) * sizeof *ubx); /* padded unit boxes */
  uint8_t *ulev = mx_alloc(n + 1);
  if (!off || !ubx || !ulev) {
    mx_free(off);
    mx_free(ubx);
    mx_free(ulev);
    return MX_EINPUT;
  }
  off[n] = 0;
  uint32_t levels = 0;
#pragma omp parallel for schedule(static) reduction(| : levels) \
    if (n > SMALL)
  for (size_t i = 0; i < n; i++) {
    double *lo = ubx + 6 * i, *hi = lo + 3;
    int lev;
    uint32_t c0[3];
    elem_gbox(m, g, list[i], lo, hi, &lev, c0);
    uint64_t k = 1;
    for (int a = 0; a < 3; a++) k *= gcoord(hi[a], lev) - c0[a] + 1;
    off[i] = k;
    ulev[i] = (uint8_t)lev;
    levels |= 1u << lev;
  }
  g->levels = levels;
  const uint64_t total = mx_scan_u64(off, n + 1);
  if (total >= UINT32_MAX) {
    mx_free(off);
    mx_free(ubx);
    mx_free(ulev);
    mx_error(NULL, 0, "check: too many boundary elements");
    return MX_EINPUT;
  }
  const size_t ne = (size_t)total;
  uint64_t *key = mx_alloc((ne + 1) * sizeof *key);
  uint32_t *idx = mx_alloc((ne + 1) * sizeof *idx);
  uint32_t *eel = mx_alloc((ne + 1) * sizeof *eel);
  float *ebox = mx_alloc((6 * ne + 1) * sizeof *ebox);
  g->elem = mx_alloc((ne + 1) * sizeof *g->elem);
  g->box = mx_alloc((6 * ne + 1) * sizeof *g->box);
  int st = key && idx && eel && ebox && g->elem && g->box ? MX_OK : MX_EINPUT;
  if (st == MX_OK) {
#pragma omp parallel for schedule(static) if (n > SMALL)
    for (size_t i = 0; i < n; i++) {
      const double *lo = ubx + 6 * i, *hi = lo + 3;
      const int lev = ulev[i];
      uint32_t c0[3], c1[3], c[3];
      for (int a = 0; a < 3; a++) {
        c0[a] = gcoord(lo[a], lev);
        c1[a] = gcoord(hi[a], lev);
      }
      const double sc = (double)(1u << lev);
      size_t k = (size_t)off[i];
      for (c[2] = c0[2]; c[2] <= c1[2]; c[2]++)
        for (c[1] = c0[1]; c[1] <= c1[1]; c[1]++)
          for (c[0] = c0[0]; c[0] <= c1[0]; c[0]++, k++) {
            key[k] = gkey(lev, c);
            idx[k] = (uint32_t)k;
            eel[k] = list[i];
            for (int a = 0; a < 3; a++) {
              ebox[6 * k + (size_t)a] = f_down(lo[a] * sc - (double)c[a]);
              ebox[6 * k + 3 + (size_t)a] = f_up(hi[a] * sc - (double)c[a]);
            }
          }
    }
    st = mx_sort_u64(key, idx, ne);
  }
  size_t runs = 0;
  if (st == MX_OK) {
    /* Boxes and elements in entry order; runs of equal keys: the cells. */
#pragma omp parallel for schedule(static) reduction(+ : runs) \
    if (ne > SMALL)
    for (size_t i = 0; i < ne; i++) {
      memcpy(g->box + 6 * i, ebox + 6 * (size_t)idx[i], 6 * sizeof *ebox);
      g->elem[i] = eel[idx[i]];
      runs += i == 0 || key[i] != key[i - 1];
    }
    uint64_t size = 16;
    while (size < 2 * (uint64_t)runs) size *= 2;
    g->mask = size - 1;
    g->tab = mx_calloc((size_t)size * sizeof *g->tab);
    if (!g->tab) st = MX_EINPUT;
  }
  if (st == MX_OK) {
#pragma omp parallel for schedule(static) if (ne > SMALL)
    for (size_t i = 0; i < ne; i++) {
      if (i > 0 && key[i] == key[i - 1]) continue;
      size_t j = i + 1;
      while (j < ne && key[j] == key[i]) j++;
      for (uint64_t h = gslot_of(key[i], g->mask);; h = (h + 1) & g->mask) {
        uint64_t e = 0;
        if (__atomic_compare_exchange_n(&g->tab[h].key, &e, key[i], 0,
                                        __ATOMIC_ACQ_REL, __ATOMIC_ACQUIRE)) {
          g->tab[h].beg = (uint32_t)i;
          g->tab[h].end = (uint32_t)j;
          break;
        }
      }
    }
  }
  mx_free(off);
  mx_free(ubx);
  mx_free(ulev);
  mx_free(key);
  mx_free(idx);
  mx_free(eel);
  mx_free(ebox);
  return st;
}

static inline const gcell *ggrid_find(const ggrid *g, uint64_t key) {
  for (uint64_t h = gslot_of(key, g->mask);; h = (h + 1) & g->mask) {
    const gcell *c = &g->tab[h];
    if (c->key == key) return c;
    if (c->key == 0) return NULL;
  }
}

static inline double dist2(const double a[3], const double b[3]) {
  const double x = a[0] - b[0], y = a[1] - b[1], z = a[2] - b[2];
  return x * x + y * y + z * z;
}

static double point_segment_d2(const double p[3], const double a[3],
                               const double b[3]) {
  double d[3], ap[3];
  for (int x = 0; x < 3; x++) {
    d[x] = b[x] - a[x];
    ap[x] = p[x] - a[x];
  }
  const double dd = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
  double t = dd > 0.0 ? (ap[0] * d[0] + ap[1] * d[1] + ap[2] * d[2]) / dd : 0.0;
  t = t < 0.0 ? 0.0 : t > 1.0 ? 1.0 : t;
  double e2 = 0.0;
  for (int x = 0; x < 3; x++) {
    const double e = ap[x] - t * d[x];
    e2 += e * e;
  }
  return e2;
}

static double point_triangle_d2(const double p[3], const double a[3],
                                const double b[3], const double c[3]);

/* Whether p is within d (d2 = d * d) of the triangle a-b-c: its box, its
 * plane, then the exact distance. */
static int near_triangle(const double p[3], const double *a, const double *b,
                         const double *c, double d, double d2) {
  for (int x = 0; x < 3; x++) {
    const double lo = mx_min(a[x], mx_min(b[x], c[x])),
                 hi = mx_max(a[x], mx_max(b[x], c[x]));
    if (p[x] < lo - d || p[x] > hi + d) return 0;
  }
  double u[3], v[3], n[3];
  for (int x = 0; x < 3; x++) {
    u[x] = b[x] - a[x];
    v[x] = c[x] - a[x];
  }
  n[0] = u[1] * v[2] - u[2] * v[1];
  n[1] = u[2] * v[0] - u[0] * v[2];
  n[2] = u[0] * v[1] - u[1] * v[0];
  const double nn = n[0] * n[0] + n[1] * n[1] + n[2] * n[2];
  const double h = n[0] * (p[0] - a[0]) + n[1] * (p[1] - a[1]) +
                   n[2] * (p[2] - a[2]);
  if (nn > 0.0 && h * h > 1.0000001 * d2 * nn) return 0;
  return point_triangle_d2(p, a, b, c) <= d2;
}

/* Where the point p of node v lies on element c: 0 (nowhere, or v is one
 * of its nodes, or p is exactly one of its nodes' points), else
 * MX_CK_ON_* << 6 | local (see mx_check_hang; an edge a-b as 8 * a + b).
 * Works in the element's own frame, scaled by a power of two to [0, 1). */
static int on_element(const mx_mesh_data *m, size_t c, uint32_t v,
                      const double p[3], double tol) {
  const int t = m->type[c], nn = mx_cell_nodes[t];
  const uint32_t *row = m->conn + 8 * c;
  for (int j = 0; j < nn; j++)
    if (row[j] == v) return 0;
  const double *P[8];
  double l2[3] = {INFINITY, INFINITY, INFINITY},
         h2[3] = {-INFINITY, -INFINITY, -INFINITY};
  for (int j = 0; j < nn; j++) {
    P[j] = m->xyz + 3 * (size_t)row[j];
    if (same_point(P[j], p)) return 0; /* a duplicate node */
    for (int a = 0; a < 3; a++) {
      l2[a] = mx_min(l2[a], 0.5 * P[j][a]);
      h2[a] = mx_max(h2[a], 0.5 * P[j][a]);
    }
  }
  double h = 0.0;
  for (int a = 0; a < 3; a++) h = mx_max(h, h2[a] - l2[a]);
  if (!(h > 0.0)) return 0;
  int ex;
  frexp(h, &ex);
  if (ex < -1000) return 0; /* below 1e-300: nothing to measure */
  const double sc = ldexp(1.0, -ex);
  double q[8][3], qp[3];
  for (int j = 0; j < nn; j++)
    for (int a = 0; a < 3; a++) q[j][a] = (0.5 * P[j][a] - l2[a]) * sc;
  for (int a = 0; a < 3; a++) qp[a] = (0.5 * p[a] - l2[a]) * sc;
  const double d = tol * h * sc, d2 = d * d;
  for (int f = 0; f < mx_cell_nfaces[t]; f++) {
    const int8_t *fl = mx_cell_faces[t][f];
    const int n = fl[3] < 0 ? 3 : 4;
    int hit;
    if (n == 3) {
      hit = near_triangle(qp, q[fl[0]], q[fl[1]], q[fl[2]], d, d2);
    } else {
      double mid[3], lo[3], hi[3];
      for (int a = 0; a < 3; a++) {
        mid[a] = 0.25 * (q[fl[0]][a] + q[fl[1]][a] + q[fl[2]][a] +
                         q[fl[3]][a]);
        lo[a] = mx_min(mx_min(q[fl[0]][a], q[fl[1]][a]),
                       mx_min(q[fl[2]][a], q[fl[3]][a]));
        hi[a] = mx_max(mx_max(q[fl[0]][a], q[fl[1]][a]),
                       mx_max(q[fl[2]][a], q[fl[3]][a]));
      }
      int inbox = 1;
      for (int a = 0; a < 3; a++)
        if (qp[a] < lo[a] - d || qp[a] > hi[a] + d) inbox = 0;
      hit = 0;
      for (int k = 0; inbox && !hit && k < 4; k++)
        hit = near_triangle(qp, q[fl[k]], q[fl[(k + 1) % 4]], mid, d, d2);
    }
    if (!hit) continue;
    for (int k = 0; k < n; k++)
      if (dist2(qp, q[fl[k]]) <= d2) return MX_CK_ON_VERTEX << 6 | fl[k];
    for (int k = 0; k < n; k++) {
      const int a = fl[k], b = fl[(k + 1) % n];
      if (point_segment_d2(qp, q[a], q[b]) <= d2)
        return MX_CK_ON_EDGE << 6 | (a < b ? 8 * a + b : 8 * b + a);
    }
    return MX_CK_ON_FACE << 6 | f;
  }
  return 0;
}

/* The smallest element node v lies on (where it lies in *where), or
 * UINT32_MAX; when ef is not NULL, flags every element it lies on. */
static uint32_t node_query(const ggrid *g, const mx_mesh_data *m, size_t v,
                           uint8_t *ef, int *where) {
  const double *p = m->xyz + 3 * v;
  double u[3];
  for (int a = 0; a < 3; a++) u[a] = ucoord(&g->U, p[a], a);
  uint32_t best = UINT32_MAX;
  *where = 0;
  /* The cells to look at, one per occupied level, their slots prefetched:
   * the probes are independent cache misses. */
  uint64_t keys[GLEVELS + 1];
  uint8_t klev[GLEVELS + 1];
  int nk = 0;
  for (int lev = 0; lev <= GLEVELS; lev++) {
    if (!(g->levels >> lev & 1)) continue;
    uint32_t c0[3];
    for (int a = 0; a < 3; a++) c0[a] = gcoord(u[a], lev);
    keys[nk] = gkey(lev, c0);
    klev[nk] = (uint8_t)lev;
    __builtin_prefetch(&g->tab[gslot_of(keys[nk], g->mask)]);
    nk++;
  }
  const gcell *found_c[GLEVELS + 1];
  for (int k = 0; k < nk; k++) {
    found_c[k] = ggrid_find(g, keys[k]);
    if (found_c[k]) __builtin_prefetch(g->box + 6 * (size_t)found_c[k]->beg);
  }
  for (int k = 0; k < nk; k++) {
    const gcell *gc = found_c[k];
    if (!gc) continue;
    const int lev = klev[k];
    const double s = (double)(1u << lev);
    double ps[3];
    for (int a = 0; a < 3; a++) { /* the cell's coordinates from its key */
      const uint32_t ca =
          (uint32_t)(keys[k] >> ((2 - a) * lev)) & ((1u << lev) - 1);
      ps[a] = u[a] * s - (double)ca;
    }
    for (uint32_t i = gc->beg; i < gc->end; i++) {
      const float *b = g->box + 6 * (size_t)i;
      if (ps[0] < b[0] || ps[0] > b[3] || ps[1] < b[1] || ps[1] > b[4] ||
          ps[2] < b[2] || ps[2] > b[5])
        continue;
      const uint32_t e = g->elem[i];
      const int w = on_element(m, e, (uint32_t)v, p, g->tol);
      if (!w) continue;
      if (ef) eflag(ef, e, MX_CK_GEOM_HANGING);
      if (e < best) {
        best = e;
        *where = w;
      }
    }
  }
  return best;
}

/* Compares the nodes of faces used by one element (that are not exact
 * hanging nodes) with the elements that have such a face (see check.h);
 * flags the nodes found (F_GHANG) and the elements they lie on, counts
 * the nodes, and tells where the first MX_CHECK_SHOWN lie. */
static int geometric_pass(const mx_mesh_data *m, const faces *F,
                          const ubox *U, uint8_t *flags, uint8_t *ef,
                          double tol, mx_check_report *r) {
  const size_t nc = m->ncells;
  if (nc == 0 || !U->ok || !(tol >= 0.0)) return MX_OK;
  /* the elements with a face used once, in index order */
  const size_t nchunks = (nc + CHUNK - 1) / CHUNK;
  uint64_t *cnt = mx_calloc((nchunks + 1) * sizeof *cnt);
  if (!cnt) return MX_EINPUT;
#pragma omp parallel for schedule(static) if (nchunks > 1)
  for (size_t k = 0; k < nchunks; k++) {
    const size_t end = (k + 1) * CHUNK < nc ? (k + 1) * CHUNK : nc;
    uint64_t c0 = 0;
    for (size_t c = k * CHUNK; c < end; c++)
      for (int j = 0; j < nfaces[m->type[c]]; j++)
        if (F->use[6 * c + (size_t)j] == 1) {
          c0++;
          break;
        }
    cnt[k] = c0;
  }
  const uint64_t nl = mx_scan_u64(cnt, nchunks + 1);
  uint32_t *list = mx_alloc((nl + 1) * sizeof *list);
  if (!list) {
    mx_free(cnt);
    return MX_EINPUT;
  }
#pragma omp parallel for schedule(static) if (nchunks > 1)
  for (size_t k = 0; k < nchunks; k++) {
    const size_t end = (k + 1) * CHUNK < nc ? (k + 1) * CHUNK : nc;
    uint64_t at = cnt[k];
    for (size_t c = k * CHUNK; c < end; c++)
      for (int j = 0; j < nfaces[m->type[c]]; j++)
        if (F->use[6 * c + (size_t)j] == 1) {
          list[at++] = (uint32_t)c;
          break;
        }
  }
  mx_free(cnt);
  ggrid g;
  int st = ggrid_build(&g, m, U, tol, list, (size_t)nl);
  mx_free(list);
  if (st != MX_OK) {
    ggrid_free(&g);
    return st;
  }
  size_t found = 0;
#pragma omp parallel for schedule(dynamic, 2048) reduction(+ : found) \
    if (m->nnodes > SMALL)
  for (size_t v = 0; v < m->nnodes; v++) {
    const uint8_t fl = flag_get(&flags[v]);
    if (!(fl & F_BND) || (fl & F_HANG)) continue;
    int where;
    if (node_query(&g, m, v, ef, &where) != UINT32_MAX) {
      flag_or(&flags[v], F_GHANG);
      found++;
    }
  }
  /* Where the first ones lie (asked again: rare). */
  for (size_t v = 0; v < m->nnodes && r->nshown < MX_CHECK_SHOWN && found;
       v++) {
    if (!(flags[v] & F_GHANG)) continue;
    int where = 0;
    const uint32_t e = node_query(&g, m, v, NULL, &where);
    mx_check_hang *h = &r->hang_at[r->nshown++];
    h->node = (uint32_t)v;
    h->element = e;
    h->on = where >> 6;
    h->local = where & 63;
    memcpy(h->xyz, m->xyz + 3 * v, sizeof h->xyz);
    const uint32_t *row = m->conn + 8 * (size_t)e;
    if (h->on == MX_CK_ON_VERTEX) {
      h->nverts = 1;
      h->verts[0] = row[h->local & 7];
    } else if (h->on == MX_CK_ON_EDGE) {
      h->nverts = 2;
      h->verts[0] = row[h->local >> 3];
      h->verts[1] = row[h->local & 7];
    } else {
      const int8_t *f = mx_cell_faces[m->type[e]][h->local];
      h->nverts = f[3] < 0 ? 3 : 4;
      for (int k = 0; k < h->nverts; k++) h->verts[k] = row[f[k]];
    }
  }
  ggrid_free(&g);
  r->geometric_hanging_nodes = found;
  return MX_OK;
}

/* The geometric hanging-node search alone (see check.h). */
int mx_check_contacts(const mx_mesh_data *m, const uint32_t *list, size_t n,
                      const uint8_t *node_sel, double tol, uint8_t *node_hit,
                      uint8_t *elem_hit, size_t *found) {
  *found = 0;
  if (n == 0 || m->nnodes == 0) return MX_OK;
  double lo[3] = {INFINITY, INFINITY, INFINITY},
         hi[3] = {-INFINITY, -INFINITY, -INFINITY};
  for (int a = 0; a < 3; a++) {
    double l = INFINITY, h = -INFINITY;
#pragma omp parallel for schedule(static) reduction(min : l) reduction(max : h) \
    if (m->nnodes > SMALL)
    for (size_t v = 0; v < m->nnodes; v++) {
      l = mx_min(l, m->xyz[3 * v + (size_t)a]);
      h = mx_max(h, m->xyz[3 * v + (size_t)a]);
    }
    lo[a] = l;
    hi[a] = h;
  }
  ubox U;
  ubox_init(&U, lo, hi);
  if (!U.ok) return MX_OK;
  ggrid g;
  int st = ggrid_build(&g, m, &U, tol, list, n);
  if (st != MX_OK) {
    ggrid_free(&g);
    return st;
  }
  size_t nf = 0;
#pragma omp parallel for schedule(dynamic, 2048) reduction(+ : nf) \
    if (m->nnodes > SMALL)
  for (size_t v = 0; v < m->nnodes; v++) {
    if (!node_sel[v]) continue;
    int where;
    if (node_query(&g, m, v, elem_hit, &where) != UINT32_MAX) {
      if (node_hit) node_hit[v] = 1;
      nf++;
    }
  }
  ggrid_free(&g);
  *found = nf;
  return MX_OK;
}

/* ---- pass 7: the surface ------------------------------------------------- */

/* Squared distance from p to the triangle a-b-c: the closest point lies in
 * the Voronoi region of a vertex, of an edge, or of the face, told apart by
 * the signs of dot products and of barycentric numerators. */
static double point_triangle_d2(const double p[3], const double a[3],
                                const double b[3], const double c[3]) {
  double ab[3], ac[3], ap[3], bp[3], cp[3];
  for (int x = 0; x < 3; x++) {
    ab[x] = b[x] - a[x];
    ac[x] = c[x] - a[x];
    ap[x] = p[x] - a[x];
    bp[x] = p[x] - b[x];
    cp[x] = p[x] - c[x];
  }
#define DOT(u, v) ((u)[0] * (v)[0] + (u)[1] * (v)[1] + (u)[2] * (v)[2])
  const double d1 = DOT(ab, ap), d2 = DOT(ac, ap);
  if (d1 <= 0.0 && d2 <= 0.0) return DOT(ap, ap);
  const double d3 = DOT(ab, bp), d4 = DOT(ac, bp);
  if (d3 >= 0.0 && d4 <= d3) return DOT(bp, bp);
  const double d5 = DOT(ab, cp), d6 = DOT(ac, cp);
  if (d6 >= 0.0 && d5 <= d6) return DOT(cp, cp);
  const double vc = d1 * d4 - d3 * d2, vb = d5 * d2 - d1 * d6,
               va = d3 * d6 - d5 * d4;
  double s, t; /* closest point a + s ab + t ac */
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {
    s = d1 / (d1 - d3);
    t = 0.0;
  } else if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {
    s = 0.0;
    t = d2 / (d2 - d6);
  } else if (va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0) {
    const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6)); /* along b-c */
    s = 1.0 - w;
    t = w;
  } else {
    const double den = va + vb + vc;
    if (!(den > 0.0)) { /* degenerate triangle: its vertices */
      return mx_min(DOT(ap, ap), mx_min(DOT(bp, bp), DOT(cp, cp)));
    }
    s = vb / den;
    t = vc / den;
  }
  double d[3];
  for (int x = 0; x < 3; x++) d[x] = ap[x] - s * ab[x] - t * ac[x];
  return DOT(d, d);
#undef DOT
}

typedef struct {
  const mx_trisoup *s;
  double lo[3], h, inv_h;
  int d[3];
  uint64_t *start; /* cells + 1 */
  uint32_t *tri;
} tgrid;

static void tgrid_free(tgrid *g) {
  mx_free(g->start);
  mx_free(g->tri);
}

static inline int cell_coord(const tgrid *g, double x, int a) {
  double f = floor((x - g->lo[a]) * g->inv_h);
  if (!(f >= 0.0)) return 0;
  if (f > (double)(g->d[a] - 1)) return g->d[a] - 1;
  return (int)f;
}

static void tri_cells(const tgrid *g, size_t t, int lo[3], int hi[3]) {
  const mx_trisoup *s = g->s;
  const double *co[3] = {s->x, s->y, s->z};
  for (int a = 0; a < 3; a++) {
    double mn = INFINITY, mx = -INFINITY;
    for (int k = 0; k < 3; k++) {
      const double v = co[a][s->tri[3 * t + (size_t)k]];
      mn = mx_min(mn, v);
      mx = mx_max(mx, v);
    }
    lo[a] = cell_coord(g, mn, a);
    hi[a] = cell_coord(g, mx, a);
  }
}

static int tgrid_build(tgrid *g, const mx_trisoup *s, const double blo[3],
                       const double bhi[3]) {
  memset(g, 0, sizeof *g);
  g->s = s;
  double ext[3], mext = 0.0;
  for (int a = 0; a < 3; a++) mext = mx_max(mext, bhi[a] - blo[a]);
  const double pad = 1e-9 * mext;
  for (int a = 0; a < 3; a++) {
    g->lo[a] = blo[a] - pad;
    ext[a] = bhi[a] - blo[a] + 2 * pad;
  }
  double h;
  cell_grid(ext, (double)s->nt, 1024, &h, g->d);
  size_t ncells = (size_t)g->d[0] * g->d[1] * g->d[2];
  g->h = h;
  g->inv_h = 1.0 / h;
  g->start = mx_calloc((ncells + 1) * sizeof *g->start);
  if (!g->start) return MX_EINPUT;
  for (size_t t = 0; t < s->nt; t++) {
    int lo[3], hi[3];
    tri_cells(g, t, lo, hi);
    for (int z = lo[2]; z <= hi[2]; z++)
      for (int y = lo[1]; y <= hi[1]; y++)
        for (int x = lo[0]; x <= hi[0]; x++)
          g->start[((size_t)z * g->d[1] + (size_t)y) * g->d[0] + (size_t)x]++;
  }
  const uint64_t total = mx_scan_u64(g->start, ncells + 1);
  g->tri = mx_alloc((size_t)total * sizeof *g->tri + 4);
  if (!g->tri) return MX_EINPUT;
  for (size_t t = 0; t < s->nt; t++) {
    int lo[3], hi[3];
    tri_cells(g, t, lo, hi);
    for (int z = lo[2]; z <= hi[2]; z++)
      for (int y = lo[1]; y <= hi[1]; y++)
        for (int x = lo[0]; x <= hi[0]; x++)
          g->tri[g->start[((size_t)z * g->d[1] + (size_t)y) * g->d[0] +
                          (size_t)x]++] = (uint32_t)t;
  }
  /* start[i] is now the end of cell i: shift back. */
  memmove(g->start + 1, g->start, ncells * sizeof *g->start);
  g->start[0] = 0;
  return MX_OK;
}

static inline double box_d2(const double p[3], const double lo[3],
                            const double hi[3]) {
  double d2 = 0.0;
  for (int a = 0; a < 3; a++) {
    const double d = mx_max(mx_max(lo[a] - p[a], p[a] - hi[a]), 0.0);
    d2 += d * d;
  }
  return d2;
}

/* Squared distance from p to the nearest triangle: rings of cells around
 * p's (clamped) cell until every triangle not seen yet -- all lying in cells
 * outside the rings, so in one of the slabs beyond them -- is provably
 * farther than the best so far. stamp marks the triangles tested for this
 * query (id qid). */
static double tgrid_d2(const tgrid *g, const double p[3], uint32_t *stamp,
                       uint32_t qid) {
  const mx_trisoup *s = g->s;
  int c[3];
  for (int a = 0; a < 3; a++) c[a] = cell_coord(g, p[a], a);
  double glo[3], ghi[3];
  for (int a = 0; a < 3; a++) {
    glo[a] = g->lo[a];
    ghi[a] = g->lo[a] + g->d[a] * g->h;
  }
  double best = INFINITY;
  for (int r = 0;; r++) {
    int lo[3], hi[3];
    for (int a = 0; a < 3; a++) {
      lo[a] = c[a] - r < 0 ? 0 : c[a] - r;
      hi[a] = c[a] + r > g->d[a] - 1 ? g->d[a] - 1 : c[a] + r;
    }
    for (int z = lo[2]; z <= hi[2]; z++)
      for (int y = lo[1]; y <= hi[1]; y++)
        for (int x = lo[0]; x <= hi[0]; x++) {
          if (abs(x - c[0]) != r && abs(y - c[1]) != r && abs(z - c[2]) != r)
            continue; /* seen in an earlier ring */
          const size_t cell =
              ((size_t)z * g->d[1] + (size_t)y) * g->d[0] + (size_t)x;
          for (uint64_t i = g->start[cell]; i < g->start[cell + 1]; i++) {
            const uint32_t t = g->tri[i];
            if (stamp[t] == qid) continue;
            stamp[t] = qid;
            const uint32_t *v = s->tri + 3 * (size_t)t;
            double A[3] = {s->x[v[0]], s->y[v[0]], s->z[v[0]]};
            double B[3] = {s->x[v[1]], s->y[v[1]], s->z[v[1]]};
            double C[3] = {s->x[v[2]], s->y[v[2]], s->z[v[2]]};
            best = mx_min(best, point_triangle_d2(p, A, B, C));
          }
        }
    double bound = INFINITY;
    for (int a = 0; a < 3; a++) {
      double slo[3], shi[3];
      memcpy(slo, glo, sizeof slo);
      memcpy(shi, ghi, sizeof shi);
      if (lo[a] > 0) {
        shi[a] = g->lo[a] + lo[a] * g->h;
        bound = mx_min(bound, box_d2(p, slo, shi));
        shi[a] = ghi[a];
      }
      if (hi[a] < g->d[a] - 1) {
        slo[a] = g->lo[a] + (hi[a] + 1) * g->h;
        bound = mx_min(bound, box_d2(p, slo, shi));
      }
    }
    if (bound == INFINITY || bound >= best) return best;
  }
}

/* Edges of the surface not used by exactly two of its triangles. */
static int surface_open(const mx_trisoup *s, size_t *open) {
  const size_t ne = 3 * s->nt;
  uint64_t *k = mx_alloc((ne + 1) * sizeof *k);
  if (!k) return MX_EINPUT;
#pragma omp parallel for schedule(static) if (s->nt > 65536)
  for (size_t t = 0; t < s->nt; t++)
    for (int x = 0; x < 3; x++) {
      const uint32_t a = s->tri[3 * t + (size_t)x],
                     b = s->tri[3 * t + (size_t)(x + 1) % 3];
      k[3 * t + (size_t)x] = a < b ? (uint64_t)a << 32 | b
                                   : (uint64_t)b << 32 | a;
    }
  const int st = mx_sort_u64(k, NULL, ne);
  size_t n = 0;
  for (size_t i = 0; st == MX_OK && i < ne;) {
    size_t j = i + 1;
    while (j < ne && k[j] == k[i]) j++;
    n += j - i != 2;
    i = j;
  }
  mx_free(k);
  *open = n;
  return st;
}

static int surface_pass(const mx_mesh_data *m, const mx_trisoup *s,
                        uint8_t *flags, double tol, mx_check_report *r) {
  MX_CHECK(surface_open(s, &r->surface_open_edges));
  double lo[3], hi[3];
  mx_trisoup_bbox(s, lo, hi);
  double ctr[3], diag2 = 0.0;
  for (int a = 0; a < 3; a++) {
    ctr[a] = 0.5 * (lo[a] + hi[a]);
    diag2 += (hi[a] - lo[a]) * (hi[a] - lo[a]);
  }
  /* Enclosed volume, in fixed chunks. */
  const size_t nchunks = (s->nt + CHUNK - 1) / CHUNK;
  double *part = mx_alloc((nchunks + 1) * sizeof *part);
  if (!part) return MX_EINPUT;
#pragma omp parallel for schedule(static) if (nchunks > 1)
  for (size_t k = 0; k < nchunks; k++) {
    double v = 0.0;
    const size_t end = (k + 1) * CHUNK < s->nt ? (k + 1) * CHUNK : s->nt;
    for (size_t t = k * CHUNK; t < end; t++) {
      const uint32_t *i = s->tri + 3 * t;
      double a[3] = {s->x[i[0]] - ctr[0], s->y[i[0]] - ctr[1],
                     s->z[i[0]] - ctr[2]};
      double b[3] = {s->x[i[1]] - ctr[0], s->y[i[1]] - ctr[1],
                     s->z[i[1]] - ctr[2]};
      double c[3] = {s->x[i[2]] - ctr[0], s->y[i[2]] - ctr[1],
                     s->z[i[2]] - ctr[2]};
      v += a[0] * (b[1] * c[2] - b[2] * c[1]) -
           a[1] * (b[0] * c[2] - b[2] * c[0]) +
           a[2] * (b[0] * c[1] - b[1] * c[0]);
    }
    part[k] = v;
  }
  double vol = 0.0;
  for (size_t k = 0; k < nchunks; k++) vol += part[k];
  mx_free(part);
  r->surface_volume = fabs(vol / 6.0);
  r->volume_error = r->surface_volume > 0.0
                        ? (r->volume - r->surface_volume) / r->surface_volume
                        : NAN;
  /* Distance of the boundary nodes. */
  r->boundary_max_dist = NAN;
  if (s->nt == 0 || !(diag2 > 0.0)) return MX_OK;
  size_t nb = 0;
  for (size_t v = 0; v < m->nnodes; v++) nb += (flags[v] & F_BND) != 0;
  if (nb == 0) return MX_OK;
  uint32_t *bn = mx_alloc(nb * sizeof *bn);
  tgrid g;
  int st = bn ? tgrid_build(&g, s, lo, hi) : MX_EINPUT;
  if (st != MX_OK) {
    if (bn) tgrid_free(&g);
    mx_free(bn);
    return st;
  }
  nb = 0;
  for (size_t v = 0; v < m->nnodes; v++)
    if (flags[v] & F_BND) bn[nb++] = (uint32_t)v;
  double worst = 0.0;
  int oom = 0;
  size_t off = 0;
  const double sdiag = sqrt(diag2);
#pragma omp parallel reduction(max : worst) reduction(+ : off) \
    if (nb > SMALL / 4)
  {
    uint32_t *stamp = mx_calloc(s->nt * sizeof *stamp);
    if (!stamp) {
#pragma omp atomic write
      oom = 1;
    }
#pragma omp for schedule(dynamic, 256)
    for (size_t i = 0; i < nb; i++) {
      if (!stamp) continue;
      const double d2 =
          tgrid_d2(&g, m->xyz + 3 * (size_t)bn[i], stamp, (uint32_t)i + 1);
      worst = mx_max(worst, d2);
      if (!(sqrt(d2) / sdiag <= tol)) {
        flag_or(&flags[bn[i]], F_OFF);
        off++;
      }
    }
    mx_free(stamp);
  }
  tgrid_free(&g);
  mx_free(bn);
  if (oom) return MX_EINPUT;
  r->boundary_max_dist = sqrt(worst) / sdiag;
  r->boundary_off_surface = off;
  return MX_OK;
}

/* ---- driver -------------------------------------------------------------- */

static int validate(const mx_mesh_data *m) {
  if (m->nnodes >= UINT32_MAX || m->ncells > UINT32_MAX / 6) {
    mx_error(NULL, 0,
             "check: %zu nodes and %zu cells: at most %u nodes and %u cells "
             "can be checked",
             m->nnodes, m->ncells, UINT32_MAX - 1, UINT32_MAX / 6);
    return MX_EINPUT;
  }
  size_t bad = SIZE_MAX;
#pragma omp parallel for schedule(static) reduction(min : bad) \
    if (m->ncells > SMALL)
  for (size_t c = 0; c < m->ncells; c++) {
    if (m->type[c] > MX_HEX) {
      if (c < bad) bad = c;
      continue;
    }
    for (int j = 0; j < mx_cell_nodes[m->type[c]]; j++)
      if (m->conn[8 * c + (size_t)j] >= m->nnodes && c < bad) bad = c;
  }
  if (bad != SIZE_MAX) {
    mx_error(NULL, 0,
             "check: cell %zu has a bad type (%d) or a node index out of "
             "range (%zu nodes)",
             bad, m->type[bad], m->nnodes);
    return MX_EINPUT;
  }
#pragma omp parallel for schedule(static) reduction(min : bad) \
    if (m->nnodes > 65536)
  for (size_t i = 0; i < 3 * m->nnodes; i++)
    if (!isfinite(m->xyz[i]) && i < bad) bad = i;
  if (bad != SIZE_MAX) {
    mx_error(NULL, 0, "check: node %zu has a coordinate that is not finite",
             bad / 3);
    return MX_EINPUT;
  }
  if (m->nfaces && (!m->face_nn || !m->face_conn || !m->face_tag ||
                    m->nfaces >= UINT32_MAX)) {
    mx_error(NULL, 0, "check: %zu tagged faces without their arrays, or too "
             "many", m->nfaces);
    return MX_EINPUT;
  }
#pragma omp parallel for schedule(static) reduction(min : bad) \
    if (m->nfaces > SMALL)
  for (size_t f = 0; f < m->nfaces; f++) {
    const int n = m->face_nn[f];
    if (n != 3 && n != 4) {
      if (f < bad) bad = f;
      continue;
    }
    for (int j = 0; j < n; j++)
      if (m->face_conn[4 * f + (size_t)j] >= m->nnodes && f < bad) bad = f;
  }
  if (bad != SIZE_MAX) {
    mx_error(NULL, 0,
             "check: tagged face %zu has %d nodes (3 or 4) or a node index "
             "out of range (%zu nodes)",
             bad, m->face_nn[bad], m->nnodes);
    return MX_EINPUT;
  }
  return MX_OK;
}

typedef struct {
  uint8_t *flags, *ef;
  chash H;
  faces F;
} work;

static void work_free(work *w) {
  mx_free(w->flags);
  mx_free(w->ef);
  mx_free(w->H.slot);
  mx_free(w->H.seg);
  faces_free(&w->F);
  memset(w, 0, sizeof *w);
}

/* The first MX_CHECK_LIST ids of each kind, and the first geometric
 * hanging nodes with where they lie. */
static void collect_lists(const mx_mesh_data *m, const work *w,
                          mx_check_report *r) {
  for (size_t c = 0; c < m->ncells; c++) {
    const uint8_t f = w->ef[c];
    if (!f) continue;
    for (int k = 0; k < MX_CK_ELEM_KINDS; k++) {
      mx_check_ids *l = &r->elem_ids[k];
      if ((f >> k & 1) && l->n < MX_CHECK_LIST) l->id[l->n++] = (uint32_t)c;
    }
  }
  const int closed = r->has_surface && r->surface_open_edges == 0;
  for (size_t v = 0; v < m->nnodes; v++) {
    const uint8_t f = w->flags[v];
    if ((f & (F_USED | F_DUP | F_HANG | F_GHANG | F_OFF)) == F_USED) continue;
    const int kind[MX_CK_NODE_KINDS] = {!(f & F_USED), (f & F_DUP) != 0,
                                        (f & F_HANG) != 0, (f & F_GHANG) != 0,
                                        closed && (f & F_OFF)};
    for (int k = 0; k < MX_CK_NODE_KINDS; k++) {
      mx_check_ids *l = &r->node_ids[k];
      if (kind[k] && l->n < MX_CHECK_LIST) l->id[l->n++] = (uint32_t)v;
    }
  }
}

static int check_body(const mx_mesh_data *m, const mx_trisoup *surface,
                      const mx_check_options *o, mx_check_report *r,
                      mx_check_tags *tags, work *w) {
  const size_t nn = m->nnodes;
  w->flags = mx_calloc(nn + 1);
  w->ef = mx_calloc(m->ncells + 1);
  if (!w->flags || !w->ef) return MX_EINPUT;
  uint8_t *flags = w->flags;
  MX_CHECK(element_pass(m, flags, w->ef, o->degenerate_below, r));
  size_t unused = 0;
#pragma omp parallel for schedule(static) reduction(+ : unused) \
    if (nn > SMALL)
  for (size_t v = 0; v < nn; v++) unused += !(flags[v] & F_USED);
  r->unused_nodes = unused;
  chash *H = &w->H;
  MX_CHECK(chash_build(H, m, &r->duplicate_nodes));
  if (r->duplicate_nodes) { /* which: those that are not the smallest id */
#pragma omp parallel for schedule(static) if (nn > SMALL)
    for (size_t v = 0; v < nn; v++)
      if (chash_find(H, m->xyz + 3 * v) != (int64_t)v) flags[v] |= F_DUP;
  }
  MX_CHECK(faces_bucket(m, &w->F));
  face_counts fc;
  MX_CHECK(faces_match(m, &w->F, H, flags, w->ef, &fc));
  r->faces_interior = fc.interior;
  r->faces_boundary = fc.boundary;
  r->faces_overshared = fc.overshared;
  r->faces_misoriented = fc.misoriented;
  edge_midpoints(m, H, flags, w->ef);
  size_t hang = 0;
#pragma omp parallel for schedule(static) reduction(+ : hang) \
    if (nn > SMALL)
  for (size_t v = 0; v < nn; v++) hang += (flags[v] & F_HANG) != 0;
  r->hanging_nodes = hang;
  MX_CHECK(boundary_pass(m, &w->F, flags, w->ef, fc.boundary, r));
  MX_CHECK(tag_pass(m, &w->F, r, tags));
  mx_free(H->slot); /* memory for the next passes */
  mx_free(H->seg);
  H->slot = H->seg = NULL;
  mx_free(w->F.slot);
  mx_free(w->F.end);
  w->F.slot = NULL;
  w->F.end = NULL;
  MX_CHECK(geometric_pass(m, &w->F, &H->U, flags, w->ef, o->hang_tol, r));
  faces_free(&w->F);
  memset(&w->F, 0, sizeof w->F);
  if (surface) {
    r->has_surface = 1;
    MX_CHECK(surface_pass(m, surface, flags, o->boundary_tol, r));
    if (r->surface_open_edges == 0) {
      double tol = o->volume_tol;
      if (!(tol > 0.0)) {
        /* a coarse mesh loses or gains up to about a layer of elements
         * along the surface: half of one is allowed, 5% at least */
        double area = 0.0;
        for (size_t t = 0; t < surface->nt; t++) {
          const uint32_t *v = surface->tri + 3 * t;
          const double ux = surface->x[v[1]] - surface->x[v[0]],
                       uy = surface->y[v[1]] - surface->y[v[0]],
                       uz = surface->z[v[1]] - surface->z[v[0]];
          const double wx = surface->x[v[2]] - surface->x[v[0]],
                       wy = surface->y[v[2]] - surface->y[v[0]],
                       wz = surface->z[v[2]] - surface->z[v[0]];
          const double cx = uy * wz - uz * wy, cy = uz * wx - ux * wz, cz = ux * wy - uy * wx;
          area += 0.5 * sqrt(cx * cx + cy * cy + cz * cz);
        }
        const double V = fabs(r->surface_volume);
        const double h = m->ncells ? cbrt(fabs(r->volume) / (double)m->ncells) : 0.0;
        tol = V > 0.0 ? fmax(0.05, 0.5 * area * h / V) : 0.05;
        r->opt.volume_tol = tol;
        r->opt.volume_tol_auto = 1;
      }
      r->volume_off = !(fabs(r->volume_error) <= tol);
    } else { /* an open surface: indicative only */
      r->boundary_off_surface = 0;
    }
  }
  collect_lists(m, w, r);
  return MX_OK;
}

void mx_check_tags_free(mx_check_tags *tags) {
  if (!tags) return;
  mx_free(tags->face_tags);
  mx_free(tags->node_tags);
  mx_free(tags->names);
  memset(tags, 0, sizeof *tags);
}

int mx_check_mesh_tags(const mx_mesh_data *m, const mx_trisoup *surface,
                       const mx_check_options *opt, mx_check_report *r,
                       mx_check_tags *tags) {
  memset(r, 0, sizeof *r);
  if (tags) memset(tags, 0, sizeof *tags);
  mx_check_options o;
  mx_check_defaults(&o);
  if (opt) o = *opt;
  r->opt = o;
  r->surface_volume = r->volume_error = r->boundary_max_dist = NAN;
  r->jens_min = r->jens_mean = NAN;
  MX_CHECK(validate(m));
  r->nodes = m->nnodes;
  r->elements = m->ncells;
  r->empty = m->nnodes == 0 || m->ncells == 0;
  work w;
  memset(&w, 0, sizeof w);
  const int st = check_body(m, surface, &o, r, tags, &w);
  work_free(&w);
  if (st != MX_OK) return st;
  r->defects = r->empty + r->invalid + r->degenerate + r->faces_overshared +
               r->faces_misoriented + r->quad_vs_triangles +
               r->open_boundary_edges + r->hanging_nodes +
               r->geometric_hanging_nodes + r->unused_nodes +
               r->duplicate_nodes + r->volume_off + r->boundary_off_surface +
               r->tagged_not_boundary + r->boundary_untagged;
  return MX_OK;
}

int mx_check_mesh_opt(const mx_mesh_data *m, const mx_trisoup *surface,
                      const mx_check_options *opt, mx_check_report *r) {
  return mx_check_mesh_tags(m, surface, opt, r, NULL);
}

int mx_check_mesh(const mx_mesh_data *m, const mx_trisoup *surface,
                  mx_check_report *r) {
  return mx_check_mesh_opt(m, surface, NULL, r);
}
