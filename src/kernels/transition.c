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
#include "base/scan.h"

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
  for (int a = 0; a < 3; a++) {
    const mx_edge_table *E = &tr->edges.t[l][a];
    for (int j = 0; j < 4; j++) {
      const size_t e = mx_edge_find(E, mx_edge_key(anchor, a, j));
      if (e == SIZE_MAX) continue;
      const int mine = mx_edge_slot(j);
      int split = 0;
      for (int s = 0; s < 4; s++) {
        const uint32_t x = E->e[e].slot[s];
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

static size_t nh_insert(node_hash *H, uint64_t key, uint32_t owner) {
  const uint64_t want = key + 1;
  size_t i = nh_slot(key, H->cap);
  for (size_t probe = 0;; probe++) {
    if (probe > 4096) {
      H->overflow = 1;
      return 0;
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
      while ((cur == 0 || owner < cur) &&
             !__atomic_compare_exchange_n(&H->e[i].owner, &cur, owner, 1,
                                          __ATOMIC_RELAXED, __ATOMIC_RELAXED)) {
      }
      return i;
    }
    i = (i + 1 == H->cap) ? 0 : i + 1;
  }
}

/* Prefetch the node entries of the points a few leaves ahead: the passes
 * below walk the (leaf, point) slots in order and would otherwise wait on one
 * cache miss per point. */
#define NH_AHEAD 48
static inline void nh_prefetch(const node_hash *H, const uint32_t *slot,
                               uint64_t q, uint64_t total) {
  if (q + NH_AHEAD < total) __builtin_prefetch(&H->e[slot[q + NH_AHEAD]], 1);
}

/* Lattice keys of the points of mask m of the octant (key, level), in
 * lattice-index order; returns their number. */
static inline int leaf_points(uint64_t key, int level, uint32_t m,
                              uint64_t out[27]) {
  uint32_t c[3];
  mx_morton_decode(key, c);
  const uint32_t h = mx_octant_size(level) >> 1;
  int k = 0;
  for (; m; m &= m - 1) {
    const int i = __builtin_ctz(m);
    out[k++] = mx_lattice_key(c[0] + h * mx_lat_xyz[i][0],
                              c[1] + h * mx_lat_xyz[i][1],
                              c[2] + h * mx_lat_xyz[i][2]);
  }
  return k;
}

int mx_transition_masks(const mx_tree *tr, const uint32_t *leaves, size_t n,
                        mx_leaf_masks *lm) {
  memset(lm, 0, sizeof *lm);
  if (tr->edges_released) {
    mx_error(NULL, 0, "internal: transition masks without edge infos");
    return MX_EINTERNAL;
  }
  const mx_octree *T = &tr->oct;
  uint32_t *mask = mx_alloc((n + 1) * sizeof *mask);
  int st = !mask ? MX_ENOMEM : MX_OK;
  size_t closures = 0;
  uint32_t *cbits = mx_alloc((n + 1) * sizeof *cbits);
  if (!cbits) st = MX_ENOMEM;
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
  mx_free(cbits);
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

int mx_transition_build(const mx_tree *tr, const uint32_t *leaves, size_t n,
                        mx_leaf_masks *lm, mx_mesh *out) {
  memset(out, 0, sizeof *out);
  uint32_t *mask = lm->mask;
  const size_t closures = lm->closures;
  lm->mask = NULL;
  int st = mx_patterns_init();
  const mx_octree *T = &tr->oct;
  mx_pattern_ref *ref = mx_alloc((n + 1) * sizeof *ref);
  uint64_t *noff = mx_alloc((n + 1) * sizeof *noff);
  uint64_t *eoff = mx_alloc((n + 1) * sizeof *eoff);
  node_hash H = {NULL, 0, 0, 0};
  {
    /* nodes lie on the lattice of midpoints of the finest leaves */
    int top = 0;
    for (size_t i = 0; i < n; i++)
      if (T->level[leaves[i]] > top) top = T->level[leaves[i]];
    H.shift = 3 * (MX_MAX_LEVEL - top - 1);
  }
  if (!st && (!mask || !ref || !noff || !eoff)) st = MX_ENOMEM;
  size_t centres = 0, bad = 0, points = 0;
  if (!st) {
#pragma omp parallel for schedule(static) reduction(+ : centres, bad, points)
    for (size_t i = 0; i < n; i++) {
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
      ref[i] = r;
      points += (size_t)__builtin_popcount(m);
    }
    if (bad) {
      mx_error(NULL, 0, "internal: %zu leaves with an illegal node mask", bad);
      st = MX_EINTERNAL;
    }
  }
  /* Where each leaf's points start in the slot array. */
  uint64_t *poff = mx_alloc((n + 1) * sizeof *poff);
  uint32_t *slot = NULL;
  uint64_t npts = 0;
  if (!st && !poff) st = MX_ENOMEM;
  if (!st) {
#pragma omp parallel for schedule(static)
    for (size_t i = 0; i < n; i++) poff[i] = (uint64_t)__builtin_popcount(mask[i]);
    npts = mx_scan_u64(poff, n);
    slot = mx_alloc((npts + 1) * sizeof *slot);
    if (!slot) st = MX_ENOMEM;
  }
  /* Node hash: every point, with its owner (the first leaf using it); the
   * slot of each (leaf, point) is kept so later passes do not hash again. */
  /* about 5 points per node in practice; a full window doubles the table */
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
    if (!H.e) {
      st = MX_ENOMEM;
      break;
    }
    /* zeroed in parallel, in order: the pages fault here, not one at a time
     * in the random inserts */
#pragma omp parallel for schedule(static)
    for (size_t i = 0; i < cap; i++) memset(&H.e[i], 0, sizeof H.e[i]);
    /* In blocks of leaves: all keys first, their home slots prefetched, then
     * the inserts, which would otherwise wait on one cache miss at a time. */
#pragma omp parallel for schedule(dynamic, 16)
    for (size_t b = 0; b < n; b += 64) {
      const size_t end = b + 64 < n ? b + 64 : n;
      uint64_t pk[64 * 27];
      size_t np = 0;
      for (size_t i = b; i < end; i++) {
        const uint32_t o = leaves[i];
        np += (size_t)leaf_points(T->key[o], T->level[o], mask[i], pk + np);
      }
      for (size_t j = 0; j < np && j < 16; j++)
        __builtin_prefetch(&H.e[mx_block_slot(pk[j], H.cap, H.shift)], 1);
      size_t j = 0;
      for (size_t i = b; i < end; i++) {
        const int k = __builtin_popcount(mask[i]);
        for (int q = 0; q < k; q++, j++) {
          if (j + 16 < np) __builtin_prefetch(&H.e[mx_block_slot(pk[j + 16], H.cap, H.shift)], 1);
          slot[poff[i] + (uint64_t)q] = (uint32_t)nh_insert(&H, pk[j], (uint32_t)i + 1);
        }
      }
    }
    if (!H.overflow) break;
  }
  if (!st && H.cap >= UINT32_MAX) st = MX_EINPUT;
  if (!st) st = mx_cancel_check(); /* base/cancel.h: between the passes */
  /* Owners count their nodes; every leaf counts its elements. */
  if (!st) {
#pragma omp parallel for schedule(static)
    for (size_t i = 0; i < n; i++) {
      const int k = __builtin_popcount(mask[i]);
      uint64_t own = 0;
      for (int j = 0; j < k; j++) {
        nh_prefetch(&H, slot, poff[i] + (uint64_t)j, npts);
        own += H.e[slot[poff[i] + j]].owner == i + 1;
      }
      noff[i] = own;
      eoff[i] = mx_pattern_classes[ref[i].cls].count;
    }
    out->nnodes = mx_scan_u64(noff, n);
    out->ncells = mx_scan_u64(eoff, n);
    out->xyz = mx_alloc((3 * out->nnodes + 1) * sizeof *out->xyz);
    out->nkey = mx_alloc((out->nnodes + 1) * sizeof *out->nkey);
    if (!out->xyz || !out->nkey) st = MX_ENOMEM;
  }
  if (!st) st = mx_cancel_check();
  /* Number the nodes: owners in leaf order, points in lattice order. */
  if (!st) {
#pragma omp parallel for schedule(static)
    for (size_t i = 0; i < n; i++) {
      uint64_t id = noff[i];
      const uint32_t *s = slot + poff[i];
      int j = 0;
      for (uint32_t m = mask[i]; m; m &= m - 1, j++) {
        nh_prefetch(&H, slot, poff[i] + (uint64_t)j, npts);
        node_entry *e = &H.e[s[j]];
        if (e->owner != i + 1) continue;
        e->id = (uint32_t)id;
        out->nkey[id] = e->kw - 1;
        uint32_t c[3];
        mx_morton_decode(e->kw - 1, c);
        for (int a = 0; a < 3; a++)
          out->xyz[3 * id + a] = tr->grid.origin[a] + (double)c[a] * tr->grid.unit;
        id++;
      }
    }
    /* Each (leaf, point) slot becomes the point's node id, and the hash
     * goes before the element arrays come (it sets the stage's peak). */
#pragma omp parallel for schedule(static)
    for (size_t i = 0; i < n; i++) {
      uint32_t *s = slot + poff[i];
      const int k = __builtin_popcount(mask[i]);
      for (int j = 0; j < k; j++) {
        nh_prefetch(&H, slot, poff[i] + (uint64_t)j, npts);
        s[j] = H.e[s[j]].id;
      }
    }
    mx_free(H.e);
    H.e = NULL;
    out->type = mx_alloc(out->ncells + 1);
    out->conn = mx_alloc((8 * out->ncells + 1) * sizeof *out->conn);
    out->level = mx_alloc((out->ncells + 1) * sizeof *out->level);
    out->leaf = mx_alloc((out->ncells + 1) * sizeof *out->leaf);
    out->jens = mx_alloc((out->ncells + 1) * sizeof *out->jens);
    if (!out->type || !out->conn || !out->level || !out->leaf || !out->jens) st = MX_ENOMEM;
  }
  if (!st) st = mx_cancel_check();
  if (!st) {
    /* Elements. */
    size_t bt[4] = {0, 0, 0, 0}, invalid = 0;
    double jmin = INFINITY;
#pragma omp parallel for schedule(static) reduction(+ : invalid) reduction(min : jmin)
    for (size_t i = 0; i < n; i++) {
      const uint32_t o = leaves[i];
      const mx_pattern_class *pc = &mx_pattern_classes[ref[i].cls];
      const uint8_t *perm = mx_rot_perm[ref[i].rot];
      uint32_t id27[27] = {0}; /* patterns use mask points only (tested) */
      const uint32_t *s = slot + poff[i];
      int j = 0;
      for (uint32_t m = mask[i]; m; m &= m - 1, j++) id27[__builtin_ctz(m)] = s[j];
      for (int k = 0; k < pc->count; k++) {
        const mx_pattern_elem *pe = &mx_pattern_elems[pc->first + k];
        const size_t c = eoff[i] + (size_t)k;
        const int nv = mx_cell_nodes[pe->type];
        out->type[c] = pe->type;
        for (int v = 0; v < 8; v++) out->conn[8 * c + v] = v < nv ? id27[perm[pe->v[v]]] : 0;
        out->level[c] = T->level[o];
        out->leaf[c] = (uint32_t)i;
        /* the octant is a scaled, rotated unit cube: the pattern's J_ENS */
        const double q = mx_pattern_elem_jens[pc->first + k];
        out->jens[c] = (float)q;
        if (mx_jens_invalid(q)) invalid++;
        if (q < jmin) jmin = q;
      }
    }
#pragma omp parallel for schedule(static) reduction(+ : bt[:4])
    for (size_t c = 0; c < out->ncells; c++) bt[out->type[c]]++;
    memcpy(out->by_type, bt, sizeof bt);
    out->invalid = invalid;
    out->jens_min = out->ncells ? jmin : 1.0;
    out->closures = closures;
    out->centre_leaves = centres;
  }
  mx_free(poff);
  mx_free(slot);
  mx_free(H.e);
  mx_free(mask);
  mx_free(ref);
  mx_free(noff);
  mx_free(eoff);
  if (st) mx_mesh_free(out);
  return st;
}
