/* mixoct: the independent mesh checker (definitions in check.h).
 *
 * Passes, each parallel:
 *  1. elements: J_ENS, volume, counts per type, used nodes;
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
 *  6. with a surface: enclosed volume and the distance of the boundary
 *     nodes to the triangles through a uniform grid of triangle boxes.
 * A face is named by its slot 6 * cell + local face, so ncells is limited to
 * (2^32 - 1) / 6. */
#include "kernels/check.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "common.h"
#include "kernels/quality.h"
#include "soa/mesh.h"
#include "soa/scan.h"

enum { CHUNK = 16384, F_USED = 1, F_HANG = 2, F_BND = 4 };

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
 * dimensions wider than a cell, at most maxdim per axis. Sets h and d. */
static void cell_grid(const double ext[3], double target, int maxdim,
                      double *h_out, int d[3]) {
  double mext = mx_max(ext[0], mx_max(ext[1], ext[2]));
  if (!(mext > 0.0) || !isfinite(mext)) { /* one point, or no range */
    d[0] = d[1] = d[2] = 1;
    *h_out = mext > 0.0 ? INFINITY : 1.0;
    return;
  }
  if (target < 1.0) target = 1.0;
  double h = 0.0;
  for (int it = 0; it < 4; it++) {
    double prod = 1.0;
    int k = 0;
    for (int a = 0; a < 3; a++)
      if (ext[a] > h) {
        prod *= ext[a];
        k++;
      }
    if (k == 0) {
      prod = mext;
      k = 1;
    }
    h = pow(prod / target, 1.0 / k);
  }
  for (int a = 0; a < 3; a++) {
    double n = ceil(ext[a] / h);
    d[a] = n < 1.0 ? 1 : n > maxdim ? maxdim : (int)n;
  }
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
  double lo[3], hi[3], inv_h;
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
    const double f = floor((q[a] - H->lo[a]) * H->inv_h);
    const int i = f > (double)(H->d[a] - 1) ? H->d[a] - 1 : (int)f;
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
  double ext[3], h;
  for (int a = 0; a < 3; a++) ext[a] = H->hi[a] - H->lo[a];
  cell_grid(ext, (double)m->nnodes / 8.0, 2048, &h, H->d);
  H->inv_h = 1.0 / h;
  if (!isfinite(H->inv_h)) { /* extents beyond the double range */
    H->d[0] = H->d[1] = H->d[2] = 1;
    H->inv_h = 0.0;
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
 * verts. */
static inline void mark_hanging(uint8_t *flags, int64_t id,
                                const uint32_t *verts, int n) {
  if (id < 0 || !(flag_get(&flags[id]) & F_USED)) return;
  for (int k = 0; k < n; k++)
    if (verts[k] == (uint32_t)id) return;
  flag_or(&flags[id], F_HANG);
}

static inline void midpoint(const double *a, const double *b, double q[3]) {
  for (int x = 0; x < 3; x++) q[x] = (a[x] + b[x]) * 0.5;
}

/* ---- pass 1: elements ---------------------------------------------------- */

typedef struct {
  double vol, jsum, jmin;
  size_t invalid, by[4];
} elem_acc;

static int element_pass(const mx_mesh_data *m, uint8_t *flags,
                        mx_check_report *r) {
  const size_t nc = m->ncells, nchunks = (nc + CHUNK - 1) / CHUNK;
  elem_acc *acc = mx_alloc((nchunks + 1) * sizeof *acc);
  if (!acc) return MX_EINPUT;
#pragma omp parallel for schedule(dynamic, 1)
  for (size_t k = 0; k < nchunks; k++) {
    elem_acc a = {0.0, 0.0, INFINITY, 0, {0, 0, 0, 0}};
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
      const double q = mx_jens(t, (const double(*)[3])p);
      a.vol += mx_element_volume(t, (const double(*)[3])p);
      a.jsum += q;
      if (q < a.jmin) a.jmin = q;
      if (!(q > 0.0)) a.invalid++;
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
#pragma omp parallel for schedule(static)
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
#pragma omp parallel for schedule(static)
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
                       uint8_t *flags, face_counts *fc) {
  size_t interior = 0, boundary = 0, over = 0, mis = 0;
  int oom = 0;
#pragma omp parallel reduction(+ : interior, boundary, over, mis)
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
          if (!opposite(m, k[i].slot, k[i + 1].slot)) mis++;
        } else {
          over++;
        }
        if ((k[i].hi >> 32) == 4) { /* quad: its centre */
          uint32_t fv[4] = {0, 0, 0, 0};
          face_verts(m, k[i].slot, fv);
          const double *p[4];
          for (int x = 0; x < 4; x++) p[x] = m->xyz + 3 * (size_t)fv[x];
          double q1[3], q2[3];
          midpoint(p[0], p[2], q1);
          midpoint(p[1], p[3], q2);
          mark_hanging(flags, chash_find(H, q1), fv, 4);
          if (!same_point(q1, q2)) mark_hanging(flags, chash_find(H, q2), fv, 4);
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

/* Whether the triangle a-b-c is a face used by exactly one element. */
static int boundary_triangle(const mx_mesh_data *m, const faces *F,
                             uint32_t a, uint32_t b, uint32_t c) {
  uint32_t v[4] = {a, b, c, 0};
  sort4(v, 3);
  const fkey want = key_of(3, v, 0);
  uint64_t lo = bucket_begin(F, v[0]), hi = F->end[v[0]];
  while (lo < hi) { /* first entry not below want */
    const uint64_t mid = lo + (hi - lo) / 2;
    const fkey k = slot_key(m, F->slot[mid]);
    if (key_cmp(&k, &want) < 0)
      lo = mid + 1;
    else
      hi = mid;
  }
  if (lo == F->end[v[0]]) return 0;
  const fkey k = slot_key(m, F->slot[lo]);
  return key_cmp(&k, &want) == 0 && F->use[F->slot[lo]] == 1;
}

/* ---- pass 4: edge midpoints ---------------------------------------------- */

static void edge_midpoints(const mx_mesh_data *m, const chash *H,
                           uint8_t *flags) {
#pragma omp parallel for schedule(dynamic, 4096)
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
    for (int e = 0; e < ne; e++)
      if (live[e])
        mark_hanging(flags, chash_lookup(H, q[e], &p[e]), row,
                     mx_cell_nodes[t]);
  }
}

/* ---- pass 5: boundary ---------------------------------------------------- */

static int boundary_pass(const mx_mesh_data *m, const faces *F,
                         uint8_t *flags, size_t nbnd, mx_check_report *r) {
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
#pragma omp parallel for schedule(dynamic, 1024) reduction(+ : qvt)
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
         boundary_triangle(m, F, v[1], v[2], v[3])))
      qvt++;
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
  mx_free(bnd);
  mx_free(ek);
  return st;
}

/* ---- pass 6: the surface ------------------------------------------------- */

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

static int surface_pass(const mx_mesh_data *m, const mx_trisoup *s,
                        const uint8_t *flags, mx_check_report *r) {
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
#pragma omp parallel for schedule(static)
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
#pragma omp parallel reduction(max : worst)
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
    }
    mx_free(stamp);
  }
  tgrid_free(&g);
  mx_free(bn);
  if (oom) return MX_EINPUT;
  r->boundary_max_dist = sqrt(worst) / sqrt(diag2);
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
#pragma omp parallel for schedule(static) reduction(min : bad)
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
  return MX_OK;
}

static int check_body(const mx_mesh_data *m, const mx_trisoup *surface,
                      mx_check_report *r, uint8_t *flags, chash *H,
                      faces *F) {
  MX_CHECK(element_pass(m, flags, r));
  size_t unused = 0;
#pragma omp parallel for schedule(static) reduction(+ : unused)
  for (size_t v = 0; v < m->nnodes; v++) unused += !(flags[v] & F_USED);
  r->unused_nodes = unused;
  MX_CHECK(chash_build(H, m, &r->duplicate_nodes));
  MX_CHECK(faces_bucket(m, F));
  face_counts fc;
  MX_CHECK(faces_match(m, F, H, flags, &fc));
  r->faces_interior = fc.interior;
  r->faces_boundary = fc.boundary;
  r->faces_overshared = fc.overshared;
  r->faces_misoriented = fc.misoriented;
  edge_midpoints(m, H, flags);
  size_t hang = 0;
#pragma omp parallel for schedule(static) reduction(+ : hang)
  for (size_t v = 0; v < m->nnodes; v++) hang += (flags[v] & F_HANG) != 0;
  r->hanging_nodes = hang;
  MX_CHECK(boundary_pass(m, F, flags, fc.boundary, r));
  if (surface) MX_CHECK(surface_pass(m, surface, flags, r));
  return MX_OK;
}

int mx_check_mesh(const mx_mesh_data *m, const mx_trisoup *surface,
                  mx_check_report *r) {
  memset(r, 0, sizeof *r);
  r->surface_volume = r->volume_error = r->boundary_max_dist = NAN;
  r->jens_min = r->jens_mean = NAN;
  MX_CHECK(validate(m));
  r->nodes = m->nnodes;
  r->elements = m->ncells;
  uint8_t *flags = mx_calloc(m->nnodes + 1);
  chash H;
  memset(&H, 0, sizeof H);
  faces F = {0};
  int st = flags ? check_body(m, surface, r, flags, &H, &F) : MX_EINPUT;
  faces_free(&F);
  mx_free(H.slot);
  mx_free(H.seg);
  mx_free(flags);
  if (st != MX_OK) return st;
  r->defects = r->invalid + r->faces_overshared + r->faces_misoriented +
               r->quad_vs_triangles + r->open_boundary_edges +
               r->hanging_nodes + r->unused_nodes + r->duplicate_nodes;
  return MX_OK;
}
