#include "base/cancel.h"
#include "kernels/transition.h"

#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

#include "base/common.h"
#include "geom/quality.h"
#include "patterns/lattice.h"
#include "patterns/lookup.h"
#include "soa/key_index.h"
#include "soa/mesh.h"

/* ---- the node mask ------------------------------------------------------ */

/* 1 when octant x (split) has a kept child touching the edge of slot s along
 * axis a (the octant lies on the + side along b = a+1 when s bit 0 is set,
 * along c = a+2 when bit 1 is). */
static int kept_child_on_edge(const mx_octree *T, uint32_t x, int a, int s) {
  const int b = (a + 1) % 3, c = (a + 2) % 3;
  const int cb = (s & 1) ? 0 : 1, cc = (s & 2) ? 0 : 1;
  for (int ca = 0; ca < 2; ca++)
    if ((T->kept[x] >> ((ca << a) | (cb << b) | (cc << c))) & 1) return 1;
  return 0;
}

/* The 27-bit node mask of leaf o before the body centre; *closure gets the
 * midpoints added by the closure. */
static uint32_t leaf_mask(const mx_tree *tr, uint32_t o, uint32_t *closure) {
  const mx_octree *T = &tr->oct;
  const int l = T->level[o];
  uint32_t mask = 0xffu;
  *closure = 0;
  if (l > mx_edge_top(tr)) return mask; /* no finer octant anywhere */
  uint32_t anchor[3];
  mx_octant_anchor(T->key[o], l, anchor);
  uint32_t across[6]; /* octant of level l across each face, or MX_NONE */
  for (int f = 0; f < 6; f++) across[f] = MX_NONE;
  /* One edge per axis runs along the parent's centre line: the octants
   * around it are the leaf's siblings, read from the parent, not looked up
   * (its edge infos hold the same octants: the kept children). */
  const uint32_t parent = l > 0 ? T->parent[o] : MX_NONE;
  const int cid = l > 0 ? mx_morton_child_id(T->key[o], l) : 0;
  for (int a = 0; a < 3; a++) {
    const mx_edge_table *E = &tr->edges.t[l][a];
    const int b = (a + 1) % 3, c = (a + 2) % 3;
    const int inner = parent == MX_NONE ? -1 : (1 - ((cid >> b) & 1)) | (1 - ((cid >> c) & 1)) << 1;
    for (int j = 0; j < 4; j++) {
      uint32_t slot[4];
      if (j == inner) {
        for (int s = 0; s < 4; s++)
          slot[s] = mx_octree_child(T, parent, (cid & (1 << a)) | (s & 1) << b | (s >> 1) << c);
      } else {
        const size_t e = mx_edge_find(E, mx_edge_key(anchor, a, j));
        if (e == SIZE_MAX) continue;
        memcpy(slot, E->e[e].slot, sizeof slot);
      }
      const int mine = mx_edge_slot(j);
      int split = 0;
      for (int s = 0; s < 4; s++) {
        const uint32_t x = slot[s];
        if (s == mine || x == MX_NONE) continue;
        /* the face neighbours: the slot differing in one bit */
        if (s == (mine ^ 1)) across[2 * ((a + 1) % 3) + ((mine & 1) ? 0 : 1)] = x;
        if (s == (mine ^ 2)) across[2 * ((a + 2) % 3) + ((mine & 2) ? 0 : 1)] = x;
        if ((T->flags[x] & MX_OCT_SPLIT) && kept_child_on_edge(T, x, a, s)) split = 1;
      }
      if (split) mask |= 1u << (8 + 4 * a + j);
    }
  }
  for (int f = 0; f < 6; f++) {
    const uint32_t x = across[f];
    if (x == MX_NONE || !(T->flags[x] & MX_OCT_SPLIT)) continue;
    const int a = f / 2, sd = f % 2;
    /* children of x touching the face: the low ones along a if x is on the
     * + side (sd = 1), else the high ones */
    const int want = sd ? 0 : 1;
    int any = 0;
    for (int c = 0; c < 8; c++)
      if (((c >> a) & 1) == want && ((T->kept[x] >> c) & 1)) any = 1;
    if (!any) continue;
    mask |= 1u << (20 + f);
    /* closure: the four edge midpoints of this face */
    const int u = (a + 1) % 3, v = (a + 2) % 3;
    const int m[4] = {8 + 4 * u + (0 | sd << 1), 8 + 4 * u + (1 | sd << 1),
                      8 + 4 * v + (sd | 0), 8 + 4 * v + (sd | 2)};
    for (int k = 0; k < 4; k++)
      if (!((mask >> m[k]) & 1)) {
        mask |= 1u << m[k];
        *closure |= 1u << m[k];
      }
  }
  return mask;
}

/* A midpoint added by the closure is a node of every leaf of that edge: the
 * other leaves of the same level around it (its edge infos) get it too.
 * (Closures are rare: they need a face neighbour split with some of its
 * children dropped outside the domain.) */
static int propagate_closures(const mx_tree *tr, const uint32_t *leaves,
                              size_t n, uint32_t *mask, const uint32_t *cbits) {
  const mx_octree *T = &tr->oct;
  uint32_t *pos = mx_alloc((T->n + 1) * sizeof *pos);
  if (!pos) return MX_ENOMEM;
#pragma omp parallel for schedule(static)
  for (size_t o = 0; o < T->n; o++) pos[o] = MX_NONE;
#pragma omp parallel for schedule(static)
  for (size_t i = 0; i < n; i++) pos[leaves[i]] = (uint32_t)i;
#pragma omp parallel for schedule(dynamic, 1024)
  for (size_t i = 0; i < n; i++) {
    if (!cbits[i]) continue;
    const uint32_t o = leaves[i];
    const int l = T->level[o];
    uint32_t anchor[3];
    mx_octant_anchor(T->key[o], l, anchor);
    for (uint32_t b = cbits[i]; b; b &= b - 1) {
      const int bit = __builtin_ctz(b), a = (bit - 8) / 4, j = (bit - 8) % 4;
      const mx_edge_table *E = &tr->edges.t[l][a];
      const size_t e = mx_edge_find(E, mx_edge_key(anchor, a, j));
      if (e == SIZE_MAX) continue;
      for (int s = 0; s < 4; s++) {
        const uint32_t x = E->e[e].slot[s];
        if (x == MX_NONE || x == o || (T->flags[x] & MX_OCT_SPLIT)) continue;
        if (pos[x] == MX_NONE) continue;
        __atomic_fetch_or(&mask[pos[x]], 1u << (8 + 4 * a + mx_edge_slot(s)),
                          __ATOMIC_RELAXED);
      }
    }
  }
  mx_free(pos);
  return MX_OK;
}

/* ---- concurrent node hash ----------------------------------------------- */

typedef struct {
  uint64_t kw;     /* lattice key + 1, 0 = empty */
  uint32_t owner;  /* 1 + the smallest leaf position using the node (0: none) */
  uint32_t id;
} node_entry;

/* Nodes are hashed by spatial blocks (mx_block_slot, soa/key_index.h):
 * leaves taken in Morton order touch a few windows of the table at a time. */
typedef struct {
  node_entry *e;
  size_t cap;
  int shift; /* low key bits that are zero for every node */
  int overflow;
} node_hash;

#define nh_slot(key, cap) mx_block_slot(key, cap, H->shift)
#define NH_KEPT UINT32_MAX

/* Insert key (home slot i) for the leaf at position owner - 1: the entry's
 * owner becomes the smaller of its owner and this one. Returns the owner it had (0: none)
 * when this call made `owner` the owner, else NH_KEPT (also when the table
 * overflows: H->overflow is set then). */
static uint32_t nh_insert(node_hash *H, uint64_t key, size_t i, uint32_t owner) {
  const uint64_t want = key + 1;
  for (size_t probe = 0;; probe++) {
    if (probe > 4096) {
      __atomic_store_n(&H->overflow, 1, __ATOMIC_RELAXED);
      return NH_KEPT;
    }
    uint64_t kw = __atomic_load_n(&H->e[i].kw, __ATOMIC_ACQUIRE);
    if (!kw) {
      uint64_t expected = 0;
      if (__atomic_compare_exchange_n(&H->e[i].kw, &expected, want, 0,
                                      __ATOMIC_ACQ_REL, __ATOMIC_ACQUIRE))
        kw = want;
      else
        kw = expected;
    }
    if (kw == want) {
      uint32_t cur = __atomic_load_n(&H->e[i].owner, __ATOMIC_RELAXED);
      while (cur == 0 || owner < cur)
        if (__atomic_compare_exchange_n(&H->e[i].owner, &cur, owner, 1,
                                        __ATOMIC_RELAXED, __ATOMIC_RELAXED))
          return cur;
      return NH_KEPT;
    }
    i = (i + 1 == H->cap) ? 0 : i + 1;
  }
}

/* The entry of key (home slot i; inserted by an earlier pass), or NULL. */
static inline node_entry *nh_find(const node_hash *H, uint64_t key, size_t i) {
  const uint64_t want = key + 1;
  for (size_t probe = 0; probe < H->cap; probe++) {
    if (H->e[i].kw == want) return &H->e[i];
    if (!H->e[i].kw) return NULL;
    i = (i + 1 == H->cap) ? 0 : i + 1;
  }
  return NULL;
}

int mx_transition_masks(const mx_tree *tr, const uint32_t *leaves, size_t n,
                        mx_leaf_masks *lm) {
  memset(lm, 0, sizeof *lm);
  if (tr->edges_released) {
    mx_error(NULL, 0, "internal: transition masks without edge infos");
    return MX_EINTERNAL;
  }
  const mx_octree *T = &tr->oct;
  /* the masks, then as many words of scratch: the closure bits here, the
   * points each leaf owns in mx_transition_build */
  uint32_t *mask = mx_alloc(2 * (n + 1) * sizeof *mask);
  int st = !mask ? MX_ENOMEM : MX_OK;
  size_t closures = 0;
  uint32_t *cbits = mask ? mask + n + 1 : NULL;
  if (!st) {
#pragma omp parallel for schedule(static) reduction(+ : closures)
    for (size_t i = 0; i < n; i++) {
      if (i + 4 < n) {
        const uint32_t ahead = leaves[i + 4];
        if (T->level[ahead] <= mx_edge_top(tr))
          mx_edges_prefetch_octant(&tr->edges, T->key[ahead], T->level[ahead]);
      }
      mask[i] = leaf_mask(tr, leaves[i], &cbits[i]);
      closures += (size_t)__builtin_popcount(cbits[i]);
    }
  }
  if (!st && closures) st = propagate_closures(tr, leaves, n, mask, cbits);
  if (st) {
    mx_free(mask);
    return st;
  }
  lm->mask = mask;
  lm->closures = closures;
  return MX_OK;
}

int mx_transition(const mx_tree *tr, const uint32_t *leaves, size_t n,
                  mx_mesh *out) {
  mx_leaf_masks lm;
  memset(out, 0, sizeof *out);
  MX_CHECK(mx_transition_masks(tr, leaves, n, &lm));
  return mx_transition_build(tr, leaves, n, &lm, out);
}

/* ---- the build: nodes and elements -------------------------------------- */

/* The leaves are cut into contiguous chunks (Morton ranges), one per thread,
 * the same chunks in every pass below: a thread walks its chunk in leaf
 * order and keeps running offsets (no per-leaf offset arrays, no prefix
 * sums over the leaves), and first touches the rows of the output arrays
 * it fills. Chunk c is [n c / nch, n (c + 1) / nch); a team smaller than
 * nch takes chunks t, t + T, ..., so any team covers them all. */
static inline size_t chunk_lo(size_t n, int nch, int c) {
  return (size_t)(((unsigned __int128)n * (unsigned)c) / (unsigned)nch);
}
#define FOR_CHUNKS(c, nch)                                                   \
  for (int c = omp_get_thread_num(); c < (nch); c += omp_get_num_threads())

/* The chunk holding leaf position j. */
static int chunk_of(size_t n, int nch, size_t j) {
  int c = (int)(((unsigned __int128)j * (unsigned)nch) / n);
  while (c + 1 < nch && chunk_lo(n, nch, c + 1) <= j) c++;
  while (c > 0 && chunk_lo(n, nch, c) > j) c--;
  return c;
}

/* Per chunk (two cache lines each; `lost` is written by other chunks). */
typedef struct {
  uint64_t claims;  /* points whose owner a leaf of the chunk became */
  uint64_t lost;    /* of those, taken over later by a leaf before the chunk */
  uint64_t cells, centres, bad, points, missing;
  uint64_t node0, cell0; /* the chunk's first node and element */
  uint64_t pad[7];
} chunk_sums;

/* Lattice keys of the points of a leaf: the anchor's key plus the point's
 * offset (0, h or 2h per axis, h half the side) added in Morton form
 * (mx_morton_add), the offsets being the Morton keys of the lattice
 * coordinates shifted by log2 h per axis: no decoding and encoding. */
typedef struct {
  uint64_t off[27]; /* mx_morton_encode of mx_lat_xyz */
} lattice_offsets;

static inline uint64_t point_key(const lattice_offsets *L, uint64_t key, int level, int p) {
  return mx_morton_add(key, L->off[p] << (3 * (MX_MAX_LEVEL - level - 1)));
}

/* The nodes are numbered by their owner, the first leaf in Morton order
 * using them: owners in leaf order, each owner's nodes in lattice order, so
 * the numbering does not depend on the thread count. The passes go over the
 * leaves in blocks: the keys and home slots of a block's points first, then
 * the hash accesses, each prefetched NH_AHEAD points ahead (one cache miss
 * at a time otherwise). */
enum { BLOCK = 64, NH_AHEAD = 96 };
typedef struct {
  uint64_t key[BLOCK * 27];
  size_t slot[BLOCK * 27];
  size_t n;
} point_batch;

/* The points of mask m of the octant (key, level), in lattice order,
 * appended to the batch. */
static inline void batch_add(point_batch *P, const node_hash *H, const lattice_offsets *L,
                             uint64_t key, int level, uint32_t m) {
  for (; m; m &= m - 1) {
    const uint64_t k = point_key(L, key, level, __builtin_ctz(m));
    P->key[P->n] = k;
    P->slot[P->n++] = nh_slot(k, H->cap);
  }
}

/* Prefetch the home slot of point j + NH_AHEAD (all of the first ones at
 * j = 0). */
static inline void batch_prefetch(const point_batch *P, const node_hash *H, size_t j) {
  if (j == 0)
    for (size_t q = 0; q < P->n && q < NH_AHEAD; q++) __builtin_prefetch(&H->e[P->slot[q]], 1);
  if (j + NH_AHEAD < P->n) __builtin_prefetch(&H->e[P->slot[j + NH_AHEAD]], 1);
}

/* Families: a run of consecutive leaves with the same parent (a root leaf
 * alone) shares most of its points (8 plain leaves: 64 points, 27 nodes),
 * so passes 1 and 3 take each point of a family once, in the parent's
 * frame: a 5x5x5 lattice of the leaves' half sides, where lattice point p
 * of child c is at position fp[c][p]. */
typedef struct {
  uint8_t fp[8][27];
  uint8_t lat[8][125]; /* the inverse: p, or 0xff when child c lacks it */
  uint64_t off[125];   /* Morton key of the position's coordinates (0..4) */
} family_frame;

static void family_frame_init(family_frame *F) {
  memset(F->lat, 0xff, sizeof F->lat);
  for (int c = 0; c < 8; c++)
    for (int p = 0; p < 27; p++) {
      const int x = 2 * (c & 1) + mx_lat_xyz[p][0], y = 2 * ((c >> 1) & 1) + mx_lat_xyz[p][1],
                z = 2 * (c >> 2) + mx_lat_xyz[p][2];
      F->fp[c][p] = (uint8_t)(x + 5 * y + 25 * z);
      F->lat[c][x + 5 * y + 25 * z] = (uint8_t)p;
    }
  for (int q = 0; q < 125; q++)
    F->off[q] = mx_morton_encode((uint32_t)(q % 5), (uint32_t)(q / 5 % 5), (uint32_t)(q / 25));
}

typedef struct {
  size_t first;
  int count, level;
  uint64_t key;       /* anchor of the parent (of the leaf, for a root) */
  uint8_t cid[8];     /* each member's child index (0 for a root) */
  uint64_t used[2];   /* positions some member's mask has */
  uint8_t user[125];  /* where used: the first member having it */
} family;

/* The family of leaves from position i on (not past hi); returns its end. */
static size_t family_at(const mx_octree *T, const uint32_t *leaves, const uint32_t *mask,
                        size_t i, size_t hi, const family_frame *F, family *f) {
  const uint32_t o = leaves[i];
  const int l = T->level[o];
  const uint32_t parent = l > 0 ? T->parent[o] : MX_NONE;
  f->first = i;
  f->level = l;
  f->key = l > 0 ? mx_morton_parent(T->key[o], l) : T->key[o];
  f->used[0] = f->used[1] = 0;
  int k = 0;
  for (size_t q = i; q < hi && k < 8; q++, k++) {
    const uint32_t x = leaves[q];
    if (q > i && (parent == MX_NONE || T->parent[x] != parent)) break;
    const int c = l > 0 ? mx_morton_child_id(T->key[x], l) : 0;
    f->cid[k] = (uint8_t)c;
    for (uint32_t m = mask[q]; m; m &= m - 1) {
      const int fp = F->fp[c][__builtin_ctz(m)];
      const uint64_t bit = 1ull << (fp & 63);
      if (!(f->used[fp >> 6] & bit)) {
        f->used[fp >> 6] |= bit;
        f->user[fp] = (uint8_t)k;
      }
    }
  }
  f->count = k;
  return i + (size_t)k;
}

/* The family's used positions (pos) and their keys and home slots (P). */
static inline void family_points(const family *f, const family_frame *F, const node_hash *H,
                                 point_batch *P, uint8_t *pos) {
  const int sh = 3 * (MX_MAX_LEVEL - f->level - 1);
  P->n = 0;
  for (int w = 0; w < 2; w++)
    for (uint64_t u = f->used[w]; u; u &= u - 1) {
      const int fp = 64 * w + __builtin_ctzll(u);
      const uint64_t k = mx_morton_add(f->key, F->off[fp] << sh);
      pos[P->n] = (uint8_t)fp;
      P->key[P->n] = k;
      P->slot[P->n++] = nh_slot(k, H->cap);
    }
}

/* Pass 0, chunk c: each leaf's class (its final mask gets the body centre
 * where the class uses it); the chunk's elements, points, centres, and
 * leaves whose mask no pattern has. */
static void pass_classes(size_t n, int nch, int c, uint32_t *mask, chunk_sums *S) {
  const size_t lo = chunk_lo(n, nch, c), hi = chunk_lo(n, nch, c + 1);
  uint64_t cells = 0, centres = 0, bad = 0, points = 0;
  for (size_t i = lo; i < hi; i++) {
    uint32_t m = mask[i];
    mx_pattern_ref r = mx_pattern_lookup((m >> 8) & ((1u << MX_CONFIG_BITS) - 1));
    if (r.cls == 0xffff) {
      bad++;
      r.cls = 0;
    }
    if (mx_pattern_has_centre(r.cls)) {
      m |= 1u << MX_LAT_CENTRE;
      centres++;
    }
    mask[i] = m;
    cells += (uint64_t)mx_pattern_classes[r.cls].count;
    points += (uint64_t)__builtin_popcount(m);
  }
  S[c].cells = cells;
  S[c].centres = centres;
  S[c].bad = bad;
  S[c].points = points;
}

/* Pass 1, chunk c: the points of each family inserted, each with the first
 * member using it as owner candidate; own[i] gets the points leaf i became
 * the owner of (a leaf of an earlier chunk may take some over later: that
 * chunk's `lost`). */
static void pass_insert(const mx_tree *tr, const uint32_t *leaves, size_t n, int nch, int c,
                        const family_frame *F, node_hash *H, const uint32_t *mask,
                        uint32_t *own, chunk_sums *S) {
  const mx_octree *T = &tr->oct;
  const size_t lo = chunk_lo(n, nch, c), hi = chunk_lo(n, nch, c + 1);
  uint64_t claims = 0;
  point_batch P;
  family f;
  uint8_t pos[125];
  for (size_t i = lo; i < hi && !__atomic_load_n(&H->overflow, __ATOMIC_RELAXED);) {
    const size_t next = family_at(T, leaves, mask, i, hi, F, &f);
    family_points(&f, F, H, &P, pos);
    uint32_t mine[8] = {0};
    for (size_t j = 0; j < P.n; j++) {
      batch_prefetch(&P, H, j);
      const int k = f.user[pos[j]];
      const uint32_t prev = nh_insert(H, P.key[j], P.slot[j], (uint32_t)(i + (size_t)k) + 1);
      if (prev == NH_KEPT) continue;
      mine[k] |= 1u << F->lat[f.cid[k]][pos[j]];
      claims++;
      if (prev) /* taken over from a leaf after this chunk */
        __atomic_fetch_add(&S[chunk_of(n, nch, prev - 1)].lost, 1, __ATOMIC_RELAXED);
    }
    for (int k = 0; k < f.count; k++) own[i + (size_t)k] = mine[k];
    i = next;
  }
  S[c].claims = claims;
}

/* Pass 2, chunk c: the chunk's nodes numbered from its first node, in leaf
 * order, their ids into the hash; own[i] loses the points an earlier leaf
 * took over. */
static void pass_number(const mx_tree *tr, const uint32_t *leaves, size_t n, int nch, int c,
                        const lattice_offsets *L, node_hash *H, uint32_t *own,
                        chunk_sums *S) {
  const mx_octree *T = &tr->oct;
  const size_t lo = chunk_lo(n, nch, c), hi = chunk_lo(n, nch, c + 1);
  uint64_t id = S[c].node0, missing = 0;
  point_batch P;
  for (size_t b = lo; b < hi; b += BLOCK) {
    const size_t end = b + BLOCK < hi ? b + BLOCK : hi;
    P.n = 0;
    for (size_t i = b; i < end; i++) {
      const uint32_t o = leaves[i];
      batch_add(&P, H, L, T->key[o], T->level[o], own[i]);
    }
    size_t j = 0;
    for (size_t i = b; i < end; i++) {
      uint32_t mine = own[i];
      for (uint32_t m = own[i]; m; m &= m - 1, j++) {
        batch_prefetch(&P, H, j);
        node_entry *e = nh_find(H, P.key[j], P.slot[j]);
        if (!e) {
          missing++;
        } else if (e->owner != i + 1) { /* taken over */
          mine &= ~(m & -m);
        } else {
          e->id = (uint32_t)id++;
        }
      }
      own[i] = mine;
    }
  }
  /* what pass 1 counted for the chunk (claims - lost) */
  if (id != S[c + 1].node0) missing++;
  S[c].missing += missing;
}

/* Pass 3, chunk c: the node ids of each family's points from the hash,
 * each leaf's in lattice order at the start of its own rows of conn (8
 * words per element: a leaf's elements have room for its points, checked
 * on the class table). Then the hash can go before the other mesh arrays
 * come: they take its memory. */
static void pass_gather(const mx_tree *tr, const uint32_t *leaves, size_t n, int nch, int c,
                        const family_frame *F, const node_hash *H, const uint32_t *mask,
                        chunk_sums *S, uint32_t *conn) {
  const mx_octree *T = &tr->oct;
  const size_t lo = chunk_lo(n, nch, c), hi = chunk_lo(n, nch, c + 1);
  size_t cell = S[c].cell0;
  uint64_t missing = 0;
  point_batch P;
  family f;
  uint8_t pos[125];
  uint32_t id[125];
  for (size_t i = lo; i < hi;) {
    const size_t next = family_at(T, leaves, mask, i, hi, F, &f);
    family_points(&f, F, H, &P, pos);
    for (size_t j = 0; j < P.n; j++) {
      batch_prefetch(&P, H, j);
      const node_entry *e = nh_find(H, P.key[j], P.slot[j]);
      if (e) id[pos[j]] = e->id;
      else missing++;
    }
    for (int k = 0; k < f.count; k++) {
      const uint32_t m = mask[i + (size_t)k];
      uint32_t *row = conn + 8 * cell;
      for (uint32_t r = m; r; r &= r - 1) *row++ = id[F->fp[f.cid[k]][__builtin_ctz(r)]];
      cell += mx_pattern_classes[mx_pattern_lookup((m >> 8) & ((1u << MX_CONFIG_BITS) - 1)).cls].count;
    }
    i = next;
  }
  if (cell != S[c + 1].cell0) missing++;
  S[c].missing += missing;
}

/* Pass 4, chunk c: the nodes the chunk's leaves own (keys, coordinates) and
 * the elements of its leaves, from the chunk's first node and element on;
 * by_type, invalid and the least J_ENS in *acc. */
typedef struct {
  uint64_t by_type[4], invalid;
  double jmin;
} elem_acc;

static void pass_elements(const mx_tree *tr, const uint32_t *leaves, size_t n, int nch, int c,
                          const lattice_offsets *L, const uint32_t *mask, const uint32_t *own,
                          chunk_sums *S, mx_mesh *out, elem_acc *acc) {
  const mx_octree *T = &tr->oct;
  const size_t lo = chunk_lo(n, nch, c), hi = chunk_lo(n, nch, c + 1);
  size_t cell = S[c].cell0;
  uint64_t node = S[c].node0, bad_id = 0;
  for (size_t i = lo; i < hi; i++) {
    const uint32_t o = leaves[i];
    const uint64_t key = T->key[o];
    const uint8_t level = T->level[o];
    const uint32_t m = mask[i];
    uint32_t id27[27] = {0}; /* patterns use mask points only (tested) */
    const uint32_t *ids = out->conn + 8 * cell; /* from pass 3, read before the rows */
    for (uint32_t r = m; r; r &= r - 1) {
      const int p = __builtin_ctz(r);
      id27[p] = *ids++;
      if (!((own[i] >> p) & 1)) continue;
      /* a node of this leaf (numbered by pass 2 in this order) */
      const uint64_t k = point_key(L, key, level, p);
      const uint32_t id = id27[p];
      out->nkey[id] = k;
      uint32_t x[3];
      mx_morton_decode(k, x);
      for (int a = 0; a < 3; a++)
        out->xyz[3 * (size_t)id + a] = tr->grid.origin[a] + (double)x[a] * tr->grid.unit;
      bad_id += id != node;
      node++;
    }
    mx_pattern_ref ref = mx_pattern_lookup((m >> 8) & ((1u << MX_CONFIG_BITS) - 1));
    const mx_pattern_class *pc = &mx_pattern_classes[ref.cls];
    const uint8_t *perm = mx_rot_perm[ref.rot];
    for (int e = 0; e < pc->count; e++, cell++) {
      const mx_pattern_elem *pe = &mx_pattern_elems[pc->first + e];
      const int nv = mx_cell_nodes[pe->type];
      uint32_t *row = out->conn + 8 * cell;
      for (int v = 0; v < 8; v++) row[v] = v < nv ? id27[perm[pe->v[v]]] : 0;
      out->type[cell] = pe->type;
      out->level[cell] = level;
      out->leaf[cell] = (uint32_t)i;
      /* the octant is a scaled, rotated unit cube: the pattern's J_ENS */
      const double jq = mx_pattern_elem_jens[pc->first + e];
      out->jens[cell] = (float)jq;
      acc->by_type[pe->type]++;
      if (mx_jens_invalid(jq)) acc->invalid++;
      if (jq < acc->jmin) acc->jmin = jq;
    }
  }
  if (bad_id || cell != S[c + 1].cell0 || node != S[c + 1].node0) S[c].missing++;
}

int mx_transition_build(const mx_tree *tr, const uint32_t *leaves, size_t n,
                        mx_leaf_masks *lm, mx_mesh *out) {
  memset(out, 0, sizeof *out);
  uint32_t *mask = lm->mask;
  const size_t closures = lm->closures;
  lm->mask = NULL;
  int st = mx_patterns_init();
  if (!st && !mask) st = MX_ENOMEM;
  /* pass 3 keeps a leaf's ids in its rows of conn: room in every class */
  for (int k = 0; !st && k < mx_pattern_nclasses; k++)
    if (__builtin_popcount(mx_pattern_classes[k].mask) > 8 * mx_pattern_classes[k].count) {
      mx_error(NULL, 0, "internal: pattern class %d has more points than element slots", k);
      st = MX_EINTERNAL;
    }
  const mx_octree *T = &tr->oct;
  /* the scratch half of the masks' allocation: the points each leaf owns */
  uint32_t *own = mask ? mask + n + 1 : NULL;
  int nch = omp_get_max_threads();
  if ((size_t)nch > n) nch = n ? (int)n : 1;
  chunk_sums *S = mx_alloc((size_t)(nch + 1) * sizeof *S);
  if (!st && !S) st = MX_ENOMEM;
  node_hash H = {NULL, 0, 0, 0};
  lattice_offsets L;
  for (int p = 0; p < 27; p++)
    L.off[p] = mx_morton_encode(mx_lat_xyz[p][0], mx_lat_xyz[p][1], mx_lat_xyz[p][2]);
  family_frame F;
  family_frame_init(&F);
  size_t points = 0;
  if (!st) {
    /* nodes lie on the lattice of midpoints of the finest leaves */
    int top = 0;
#pragma omp parallel for schedule(static) reduction(max : top)
    for (size_t i = 0; i < n; i++)
      if (T->level[leaves[i]] > top) top = T->level[leaves[i]];
    if (top >= MX_MAX_LEVEL) {
      mx_error(NULL, 0, "internal: a leaf at level %d has no midpoints", top);
      st = MX_EINTERNAL;
    }
    H.shift = 3 * (MX_MAX_LEVEL - top - 1);
  }
  if (!st) {
    memset(S, 0, (size_t)(nch + 1) * sizeof *S);
#pragma omp parallel
    FOR_CHUNKS(c, nch) pass_classes(n, nch, c, mask, S);
    uint64_t bad = 0;
    for (int c = 0; c < nch; c++) {
      bad += S[c].bad;
      points += S[c].points;
    }
    if (bad) {
      mx_error(NULL, 0, "internal: %zu leaves with an illegal node mask", (size_t)bad);
      st = MX_EINTERNAL;
    }
  }
  /* Pass 1 into a table of about 5 points per node in practice; a window
   * that fills doubles the table. */
  for (size_t cap = points / 3 + 4096; !st; cap *= 2) {
    if (cap > 8 * points + 8192) { /* a full table at 8x the points: keys collide */
      mx_error(NULL, 0, "internal: the node hash of %zu points does not fill", points);
      st = MX_EINTERNAL;
      break;
    }
    mx_free(H.e);
    H.cap = cap;
    H.overflow = 0;
    H.e = mx_alloc(cap * sizeof *H.e);
    mx_advise_random(H.e, cap * sizeof *H.e);
    if (!H.e) {
      st = MX_ENOMEM;
      break;
    }
    for (int c = 0; c <= nch; c++) S[c].claims = S[c].lost = 0;
    /* zeroed in parallel, in order: the pages fault here, not one at a time
     * in the random inserts */
#pragma omp parallel for schedule(static)
    for (size_t i = 0; i < cap; i++) memset(&H.e[i], 0, sizeof H.e[i]);
#pragma omp parallel
    FOR_CHUNKS(c, nch) pass_insert(tr, leaves, n, nch, c, &F, &H, mask, own, S);
    if (!H.overflow) break;
  }
  if (!st && H.cap >= UINT32_MAX) st = MX_EINPUT;
  if (!st) { /* each chunk's first node and element */
    uint64_t centres = 0, node = 0, cell = 0;
    for (int c = 0; c <= nch; c++) {
      S[c].node0 = node;
      S[c].cell0 = cell;
      if (c == nch) break;
      const uint64_t owned = S[c].claims - S[c].lost;
      centres += S[c].centres;
      node += owned;
      cell += S[c].cells;
    }
    out->nnodes = node;
    out->ncells = cell;
    out->centre_leaves = centres;
    if (node >= UINT32_MAX) st = MX_EINPUT; /* ids are 32-bit */
  }
  if (!st) st = mx_cancel_check(); /* base/cancel.h: between the passes */
  if (!st) {
#pragma omp parallel
    FOR_CHUNKS(c, nch) pass_number(tr, leaves, n, nch, c, &L, &H, own, S);
    out->conn = mx_alloc((8 * out->ncells + 1) * sizeof *out->conn);
    if (!out->conn) st = MX_ENOMEM;
  }
  if (!st) {
#pragma omp parallel
    FOR_CHUNKS(c, nch) pass_gather(tr, leaves, n, nch, c, &F, &H, mask, S, out->conn);
  }
  /* the hash's memory goes to the other mesh arrays */
  mx_free(H.e);
  H.e = NULL;
  if (!st) st = mx_cancel_check();
  if (!st) {
    out->xyz = mx_alloc((3 * out->nnodes + 1) * sizeof *out->xyz);
    out->nkey = mx_alloc((out->nnodes + 1) * sizeof *out->nkey);
    out->type = mx_alloc(out->ncells + 1);
    out->level = mx_alloc((out->ncells + 1) * sizeof *out->level);
    out->leaf = mx_alloc((out->ncells + 1) * sizeof *out->leaf);
    out->jens = mx_alloc((out->ncells + 1) * sizeof *out->jens);
    if (!out->xyz || !out->nkey || !out->type || !out->level || !out->leaf || !out->jens)
      st = MX_ENOMEM;
  }
  if (!st) {
    elem_acc *A = mx_alloc((size_t)nch * sizeof *A);
    if (!A) st = MX_ENOMEM;
    if (!st) {
      for (int c = 0; c < nch; c++) {
        memset(&A[c], 0, sizeof A[c]);
        A[c].jmin = INFINITY;
      }
#pragma omp parallel
      FOR_CHUNKS(c, nch) pass_elements(tr, leaves, n, nch, c, &L, mask, own, S, out, &A[c]);
      double jmin = INFINITY;
      uint64_t invalid = 0, missing = 0;
      for (int c = 0; c < nch; c++) {
        for (int t = 0; t < 4; t++) out->by_type[t] += A[c].by_type[t];
        invalid += A[c].invalid;
        if (A[c].jmin < jmin) jmin = A[c].jmin;
        missing += S[c].missing;
      }
      out->invalid = invalid;
      out->jens_min = out->ncells ? jmin : 1.0;
      out->closures = closures;
      if (missing) {
        mx_error(NULL, 0, "internal: the transition's node numbering does not add up");
        st = MX_EINTERNAL;
      }
    }
    mx_free(A);
  }
  mx_free(H.e);
  mx_free(S);
  mx_free(mask);
  if (st) mx_mesh_free(out);
  return st;
}
