#include "kernels/splice.h"

#include <omp.h>
#include <string.h>

#include "base/common.h"
#include "kernels/mesh_edit.h"
#include "geom/quality.h"
#include "soa/mesh.h"
#include "base/scan.h"

/* ---- leaves touching octants -------------------------------------------- */

typedef struct {
  uint32_t lo[3], hi[3]; /* closed, on the finest lattice */
} mx_lattice_box;

static int box_meets(const mx_octree *T, uint32_t o, const mx_lattice_box *b) {
  uint32_t a[3];
  mx_morton_decode(T->key[o], a);
  const uint32_t s = mx_octant_size(T->level[o]);
  for (int d = 0; d < 3; d++)
    if (a[d] > b->hi[d] || a[d] + s < b->lo[d]) return 0;
  return 1;
}

/* Mark the leaves under octant r meeting box b. */
static void mark_under(const mx_tree *tr, const uint32_t *pos, uint32_t r,
                       const mx_lattice_box *b, uint8_t *mark, uint8_t value) {
  const mx_octree *T = &tr->oct;
  uint32_t stack[8 * (MX_MAX_LEVEL + 2)];
  int top = 0;
  stack[top++] = r;
  while (top) {
    const uint32_t o = stack[--top];
    if (!(T->flags[o] & MX_OCT_SPLIT)) {
      const uint32_t p = pos[o];
      uint8_t zero = 0;
      if (p != MX_NONE && !__atomic_load_n(&mark[p], __ATOMIC_RELAXED))
        __atomic_compare_exchange_n(&mark[p], &zero, value, 0, __ATOMIC_RELAXED,
                                    __ATOMIC_RELAXED);
      continue;
    }
    for (int c = 7; c >= 0; c--) {
      const uint32_t ch = mx_octree_child(T, o, c);
      if (ch != MX_NONE && box_meets(T, ch, b)) stack[top++] = ch;
    }
  }
}

/* The 26 directions around an octant. */
static const int8_t dir26[26][3] = {
    {-1, -1, -1}, {0, -1, -1}, {1, -1, -1}, {-1, 0, -1}, {0, 0, -1}, {1, 0, -1}, {-1, 1, -1},
    {0, 1, -1},   {1, 1, -1},  {-1, -1, 0}, {0, -1, 0},  {1, -1, 0}, {-1, 0, 0}, {1, 0, 0},
    {-1, 1, 0},   {0, 1, 0},   {1, 1, 0},   {-1, -1, 1}, {0, -1, 1}, {1, -1, 1}, {-1, 0, 1},
    {0, 0, 1},    {1, 0, 1},   {-1, 1, 1},  {0, 1, 1},   {1, 1, 1}};

/* 1 if the octant x holds the lattice point of key k. */
static inline int holds_key(const mx_octree *T, uint32_t x, uint64_t k) {
  const int sh = 3 * (MX_MAX_LEVEL - T->level[x]);
  return (T->key[x] >> sh) == (k >> sh);
}

int mx_leaves_touching(const mx_tree *tr, const uint32_t *pos, const uint32_t *octs, size_t n,
                       uint8_t *mark, uint8_t value) {
  const mx_octree *T = &tr->oct;
  /* the roots are the first octants built */
  size_t nroots = 0;
  while (nroots < T->n && T->parent[nroots] == MX_NONE) nroots++;
#pragma omp parallel for schedule(dynamic, 256)
  for (size_t q = 0; q < n; q++) {
    const uint32_t o = octs[q];
    const int l = T->level[o];
    mx_lattice_box b;
    uint32_t a[3];
    mx_morton_decode(T->key[o], a);
    const uint32_t s = mx_octant_size(l);
    for (int d = 0; d < 3; d++) {
      b.lo[d] = a[d];
      b.hi[d] = a[d] + s;
    }
    mark_under(tr, pos, o, &b, mark, value); /* o itself, or what is under it */
    for (int d = 0; d < 26; d++) {
      const uint64_t nk = mx_morton_neighbor(T->key[o], l, dir26[d][0], dir26[d][1],
                                             dir26[d][2], tr->grid.dims);
      if (nk == UINT64_MAX) continue;
      /* up from o to an ancestor holding the neighbour cell, then down */
      uint32_t x = T->parent[o];
      while (x != MX_NONE && !holds_key(T, x, nk)) x = T->parent[x];
      if (x == MX_NONE) { /* another root cube */
        for (size_t r = 0; r < nroots && x == MX_NONE; r++)
          if (holds_key(T, (uint32_t)r, nk)) x = (uint32_t)r;
        if (x == MX_NONE) continue;
      }
      while (T->level[x] < l && (T->flags[x] & MX_OCT_SPLIT)) {
        const uint32_t ch = mx_octree_child(T, x, mx_morton_child_id(nk, T->level[x] + 1));
        if (ch == MX_NONE) break; /* a child outside the domain */
        x = ch;
      }
      if (holds_key(T, x, nk) && (T->level[x] == l || !(T->flags[x] & MX_OCT_SPLIT)))
        mark_under(tr, pos, x, &b, mark, value);
    }
  }
  return MX_OK;
}

/* ---- numbering by first use --------------------------------------------- */

/* newid[v] for v < nn: the rank of node v in the order of first use in
 * conn (UINT32_MAX when unused); *nused: the nodes used. The elements are
 * cut into one contiguous chunk per thread (at most FU_CHUNKS); each
 * thread walks its chunk in order with a bitmap of the nodes it has seen
 * (nn / 8 bytes: in cache where an array of first elements per node was
 * not) and flags, per element, the slots whose node it sees first (mask).
 * A node's first use in the whole mesh is its first in the earliest chunk
 * using it: the flags of a later chunk are cleared for the nodes some
 * earlier chunk has seen (the bitmaps turned into their prefix ORs). Then
 * the flags are counted per block of elements, prefix-summed and numbered
 * block by block, in slot order within an element: the same ranks for any
 * number of threads. */
enum { FU_CHUNKS = 32, FU_BLOCK = 1 << 14 };

/* The first element of chunk t of nch over nc elements. */
static inline size_t fu_lo(size_t nc, int nch, int t) {
  return (size_t)(((unsigned __int128)nc * (unsigned)t) / (unsigned)nch);
}

static int first_use_ids(const uint8_t *type, const uint32_t *conn, size_t nc, size_t nn,
                         uint32_t **newid_out, size_t *nused) {
  const size_t nb = (nc + FU_BLOCK - 1) / FU_BLOCK, words = nn / 64 + 1;
  int nch = omp_get_max_threads();
  nch = nch > FU_CHUNKS ? FU_CHUNKS : nch < 1 ? 1 : nch;
  if (nc < 4 * (size_t)FU_BLOCK) nch = 1;
  uint64_t *seen = mx_calloc((size_t)nch * words * sizeof *seen);
  uint8_t *mask = mx_alloc(nc + 1);
  uint64_t *cnt = mx_alloc((nb + 1) * sizeof *cnt);
  uint32_t *newid = mx_alloc((nn + 1) * sizeof *newid);
  if (!seen || !mask || !cnt || !newid) {
    mx_free(seen); mx_free(mask); mx_free(cnt); mx_free(newid);
    return MX_ENOMEM;
  }
  /* each chunk's first uses within it */
#pragma omp parallel for schedule(static, 1)
  for (int t = 0; t < nch; t++) {
    uint64_t *mine = seen + (size_t)t * words;
    for (size_t c = fu_lo(nc, nch, t); c < fu_lo(nc, nch, t + 1); c++) {
      unsigned m = 0;
      for (int k = 0; k < mx_cell_nodes[type[c]]; k++) {
        const uint32_t v = conn[8 * c + k];
        const uint64_t bit = 1ull << (v & 63);
        if (mine[v >> 6] & bit) continue;
        mine[v >> 6] |= bit;
        m |= 1u << k;
      }
      mask[c] = (uint8_t)m;
    }
  }
  /* seen[t] := the nodes chunks 0 .. t-1 use */
  if (nch > 1) {
#pragma omp parallel for schedule(static)
    for (size_t w = 0; w < words; w++) {
      uint64_t acc = 0;
      for (int t = 0; t < nch; t++) {
        const uint64_t x = seen[(size_t)t * words + w];
        seen[(size_t)t * words + w] = acc;
        acc |= x;
      }
    }
  }
  /* the flags of the nodes an earlier chunk used cleared; counted per block */
#pragma omp parallel for schedule(static)
  for (size_t b = 0; b < nb; b++) {
    const size_t c1 = (b + 1) * FU_BLOCK < nc ? (b + 1) * FU_BLOCK : nc;
    int t = 0;
    while (t + 1 < nch && fu_lo(nc, nch, t + 1) <= b * FU_BLOCK) t++;
    uint64_t n = 0;
    for (size_t c = b * FU_BLOCK; c < c1; c++) {
      while (t + 1 < nch && fu_lo(nc, nch, t + 1) <= c) t++;
      unsigned m = mask[c];
      if (t > 0 && m) {
        const uint64_t *before = seen + (size_t)t * words;
        for (unsigned r = m; r; r &= r - 1) {
          const int k = __builtin_ctz(r);
          const uint32_t v = conn[8 * c + k];
          if (before[v >> 6] >> (v & 63) & 1) m &= ~(1u << k);
        }
        mask[c] = (uint8_t)m;
      }
      n += (uint64_t)__builtin_popcount(m);
    }
    cnt[b] = n;
  }
  mx_free(seen);
  *nused = mx_scan_u64(cnt, nb);
#pragma omp parallel for schedule(static)
  for (size_t v = 0; v < nn; v++) newid[v] = UINT32_MAX;
#pragma omp parallel for schedule(static)
  for (size_t b = 0; b < nb; b++) {
    uint64_t id = cnt[b];
    for (size_t c = b * FU_BLOCK; c < nc && c < (b + 1) * FU_BLOCK; c++)
      for (unsigned r = mask[c]; r; r &= r - 1)
        newid[conn[8 * c + (size_t)__builtin_ctz(r)]] = (uint32_t)id++;
  }
  mx_free(mask);
  mx_free(cnt);
  *newid_out = newid;
  return MX_OK;
}

int mx_mesh_renumber_first_use(mx_mesh *M, uint8_t **states) {
  uint32_t *newid = NULL;
  size_t nu = 0;
  MX_CHECK(first_use_ids(M->type, M->conn, M->ncells, M->nnodes, &newid, &nu));
  const int st = mx_mesh_apply_node_ids(M, states, newid, nu);
  mx_free(newid);
  return st;
}

/* ---- splice ------------------------------------------------------------- */

/* Where each leaf's elements start and end in a mesh sorted by leaf. */
static int leaf_ranges(const mx_mesh *M, size_t nleaves, uint64_t **lo_out,
                       uint64_t **hi_out) {
  uint64_t *lo = mx_alloc((nleaves + 1) * sizeof *lo);
  uint64_t *hi = mx_alloc((nleaves + 1) * sizeof *hi);
  if (!lo || !hi) {
    mx_free(lo); mx_free(hi);
    return MX_ENOMEM;
  }
#pragma omp parallel for schedule(static)
  for (size_t l = 0; l < nleaves; l++) lo[l] = hi[l] = 0;
  const size_t n = M->ncells;
#pragma omp parallel for schedule(static)
  for (size_t c = 0; c < n; c++) {
    if (c == 0 || M->leaf[c] != M->leaf[c - 1]) lo[M->leaf[c]] = c;
    if (c + 1 == n || M->leaf[c] != M->leaf[c + 1]) hi[M->leaf[c]] = c + 1;
  }
  *lo_out = lo;
  *hi_out = hi;
  return MX_OK;
}

/* A small concurrent hash: lattice key -> node of the patch mesh. */
typedef struct {
  uint64_t *key; /* key + 1, 0: empty */
  uint32_t *val;
  size_t cap;    /* power of two */
} key_map;

static inline size_t km_slot(uint64_t k, size_t cap) {
  k ^= k >> 31;
  k *= 0x9e3779b97f4a7c15ull;
  return (size_t)(k >> 17) & (cap - 1);
}

static void km_insert(key_map *H, uint64_t k, uint32_t v) {
  for (size_t i = km_slot(k, H->cap);; i = (i + 1) & (H->cap - 1)) {
    uint64_t expected = 0;
    if (__atomic_compare_exchange_n(&H->key[i], &expected, k + 1, 0, __ATOMIC_ACQ_REL,
                                    __ATOMIC_ACQUIRE)) {
      __atomic_store_n(&H->val[i], v, __ATOMIC_RELEASE);
      return;
    }
    if (expected == k + 1) return; /* lattice keys are unique per mesh */
  }
}

static uint32_t km_find(const key_map *H, uint64_t k) {
  for (size_t i = km_slot(k, H->cap);; i = (i + 1) & (H->cap - 1)) {
    const uint64_t x = H->key[i];
    if (!x) return UINT32_MAX;
    if (x == k + 1) return H->val[i];
  }
}

int mx_mesh_splice(const mx_mesh *O, const uint8_t *ostates, size_t nold_leaves,
                   const mx_mesh *P, const uint8_t *pstates, size_t npatch_leaves,
                   const uint32_t *from_old, const uint32_t *from_patch, size_t nleaves,
                   mx_mesh *out, uint8_t **states_out, mx_splice_stats *stats) {
  memset(out, 0, sizeof *out);
  memset(stats, 0, sizeof *stats);
  *states_out = NULL;
  if (!O->nkey || !P->nkey) {
    mx_error(NULL, 0, "internal: splice without lattice keys");
    return MX_EINTERNAL;
  }
  uint64_t *olo = NULL, *ohi = NULL, *plo = NULL, *phi = NULL;
  uint64_t *off = mx_alloc((nleaves + 1) * sizeof *off);
  uint8_t *ouse = mx_calloc(O->nnodes + 1), *puse = mx_calloc(P->nnodes + 1);
  uint32_t *pmap = mx_alloc((P->nnodes + 1) * sizeof *pmap);
  key_map H = {NULL, NULL, 0};
  int st = (!off || !ouse || !puse || !pmap) ? MX_ENOMEM : MX_OK;
  if (!st) st = leaf_ranges(O, nold_leaves, &olo, &ohi);
  if (!st) st = leaf_ranges(P, npatch_leaves, &plo, &phi);
  /* 1. Elements per leaf, and the nodes each side keeps. */
  if (!st) {
#pragma omp parallel for schedule(static)
    for (size_t i = 0; i < nleaves; i++) {
      uint64_t n = 0;
      if (from_patch[i] != MX_NONE) {
        n = phi[from_patch[i]] - plo[from_patch[i]];
        for (uint64_t c = plo[from_patch[i]]; c < phi[from_patch[i]]; c++)
          for (int k = 0; k < mx_cell_nodes[P->type[c]]; k++) __atomic_store_n(&puse[P->conn[8 * c + k]], 1, __ATOMIC_RELAXED);
      } else if (from_old[i] != MX_NONE) {
        n = ohi[from_old[i]] - olo[from_old[i]];
        for (uint64_t c = olo[from_old[i]]; c < ohi[from_old[i]]; c++)
          for (int k = 0; k < mx_cell_nodes[O->type[c]]; k++) __atomic_store_n(&ouse[O->conn[8 * c + k]], 1, __ATOMIC_RELAXED);
      }
      off[i] = n;
    }
    out->ncells = mx_scan_u64(off, nleaves);
  }
  /* 2. Patch nodes on the lattice that the old elements kept also use: one
   * node, at its old place (the elements kept are not touched). */
  size_t npk = 0;
  if (!st) {
#pragma omp parallel for schedule(static) reduction(+ : npk)
    for (size_t w = 0; w < P->nnodes; w++) npk += puse[w] && P->nkey[w] != MX_NKEY_NONE;
    H.cap = 64;
    while (H.cap < 2 * npk + 64) H.cap *= 2;
    H.key = mx_calloc(H.cap * sizeof *H.key);
    H.val = mx_alloc(H.cap * sizeof *H.val);
    if (!H.key || !H.val) st = MX_ENOMEM;
  }
  size_t shared = 0, moved = 0;
  if (!st) {
#pragma omp parallel for schedule(static)
    for (size_t w = 0; w < P->nnodes; w++) {
      pmap[w] = MX_NONE;
      if (puse[w] && P->nkey[w] != MX_NKEY_NONE) km_insert(&H, P->nkey[w], (uint32_t)w);
    }
#pragma omp parallel for schedule(static) reduction(+ : shared, moved)
    for (size_t v = 0; v < O->nnodes; v++) {
      if (!ouse[v] || O->nkey[v] == MX_NKEY_NONE) continue;
      const uint32_t w = km_find(&H, O->nkey[v]);
      if (w == UINT32_MAX) continue;
      pmap[w] = (uint32_t)v;
      shared++;
      /* (inside or not: a restart file's states have no MX_NODE_ON, the
       * patch's have) */
      moved += memcmp(O->xyz + 3 * v, P->xyz + 3 * (size_t)w, 3 * sizeof(double)) != 0 ||
               (ostates[v] & 1) != (pstates[w] & 1);
    }
    stats->shared_nodes = shared;
    stats->shared_moved = moved;
  }
  /* 3. The elements, on provisional node ids: old v -> v, patch w -> its old
   * node or O->nnodes + w. */
  const size_t ntmp = O->nnodes + P->nnodes;
  if (!st) {
    const size_t nc = out->ncells;
    out->type = mx_alloc(nc + 1);
    out->conn = mx_alloc((8 * nc + 1) * sizeof *out->conn);
    out->level = mx_alloc((nc + 1) * sizeof *out->level);
    out->leaf = mx_alloc((nc + 1) * sizeof *out->leaf);
    out->jens = mx_alloc((nc + 1) * sizeof *out->jens);
    if (!out->type || !out->conn || !out->level || !out->leaf || !out->jens) st = MX_ENOMEM;
    if (ntmp >= UINT32_MAX) st = MX_EINPUT;
  }
  size_t kept = 0, patched = 0;
  if (!st) {
#pragma omp parallel for schedule(dynamic, 1024) reduction(+ : kept, patched)
    for (size_t i = 0; i < nleaves; i++) {
      const int patch = from_patch[i] != MX_NONE;
      const mx_mesh *S = patch ? P : O;
      uint64_t lo = 0, hi = 0;
      if (patch) {
        lo = plo[from_patch[i]];
        hi = phi[from_patch[i]];
      } else if (from_old[i] != MX_NONE) {
        lo = olo[from_old[i]];
        hi = ohi[from_old[i]];
      }
      uint64_t w = off[i];
      for (uint64_t c = lo; c < hi; c++, w++) {
        const int nv = mx_cell_nodes[S->type[c]];
        out->type[w] = S->type[c];
        out->level[w] = S->level[c];
        out->leaf[w] = (uint32_t)i;
        int remeasure = 0;
        for (int k = 0; k < 8; k++) {
          uint32_t v = S->conn[8 * c + k];
          if (k < nv && patch) {
            if (pmap[v] != MX_NONE) {
              remeasure |= memcmp(O->xyz + 3 * (size_t)pmap[v], P->xyz + 3 * (size_t)v,
                                  3 * sizeof(double)) != 0;
              v = pmap[v];
            } else {
              v = (uint32_t)(O->nnodes + v);
            }
          }
          out->conn[8 * w + k] = k < nv ? v : 0;
        }
        out->jens[w] = S->jens[c];
        if (remeasure) {
          double x[8][3];
          for (int k = 0; k < nv; k++) {
            const uint32_t v = out->conn[8 * w + k];
            const double *p = v < O->nnodes ? O->xyz + 3 * (size_t)v
                                            : P->xyz + 3 * (size_t)(v - O->nnodes);
            memcpy(x[k], p, sizeof x[k]);
          }
          out->jens[w] = (float)mx_jens(S->type[c], x);
        }
      }
      if (patch)
        patched += hi - lo;
      else
        kept += hi - lo;
    }
    stats->kept_cells = kept;
    stats->patch_cells = patched;
  }
  /* 4. Nodes by first use. */
  uint32_t *newid = NULL;
  size_t nu = 0;
  if (!st) st = first_use_ids(out->type, out->conn, out->ncells, ntmp, &newid, &nu);
  uint8_t *states = NULL;
  if (!st) {
    out->nnodes = nu;
    out->xyz = mx_alloc((3 * nu + 3) * sizeof *out->xyz);
    out->nkey = mx_alloc((nu + 1) * sizeof *out->nkey);
    states = mx_alloc(nu + 1);
    if (!out->xyz || !out->nkey || !states) st = MX_ENOMEM;
  }
  if (!st) {
#pragma omp parallel for schedule(static)
    for (size_t v = 0; v < ntmp; v++) {
      const uint32_t u = newid[v];
      if (u == UINT32_MAX) continue;
      const int old = v < O->nnodes;
      const size_t s = old ? v : v - O->nnodes;
      const mx_mesh *S = old ? O : P;
      memcpy(out->xyz + 3 * (size_t)u, S->xyz + 3 * s, 3 * sizeof(double));
      out->nkey[u] = S->nkey[s];
      states[u] = old ? ostates[s] : pstates[s];
    }
#pragma omp parallel for schedule(static)
    for (size_t c = 0; c < out->ncells; c++)
      for (int k = 0; k < mx_cell_nodes[out->type[c]]; k++)
        out->conn[8 * c + k] = newid[out->conn[8 * c + k]];
  }
  mx_free(newid);
  mx_free(olo); mx_free(ohi); mx_free(plo); mx_free(phi);
  mx_free(off); mx_free(ouse); mx_free(puse); mx_free(pmap);
  mx_free(H.key); mx_free(H.val);
  if (st) {
    mx_free(states);
    mx_mesh_free(out);
    return st;
  }
  *states_out = states;
  return MX_OK;
}
