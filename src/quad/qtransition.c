/* Transition patterns (Jaillet & Lobos 2021, Fig. 4): the conforming mixed
 * mesh of the leaves.
 *
 * A leaf's mask has bit e set when the midpoint of its edge e (0 bottom,
 * 1 right, 2 top, 3 left) is a corner of another leaf (a finer neighbour);
 * the mask picks one of 6 base patterns and a rotation. Nodes are the
 * leaves' corners (and the centres of 4-mid-node leaves), kept in a table of
 * blocks of lattice points with the quadrants around each that leaves
 * cover: a node is owned by the first leaf (in the given, Morton, order)
 * that uses it, which its coverage tells (owner_quadrant), and numbered
 * when its owner lists its nodes: the numbering does not depend on the
 * thread count. The leaves' keys and levels are gathered first (the passes
 * then read them in order), and the blocks' nodes are stored in the Morton
 * order of the blocks (the passes, going over the leaves in that order,
 * read and write ids near each other).
 *
 * The local nodes of a leaf, in half sizes: 0 (0,0), 1 (1,0), 2 (2,0),
 * 3 (2,1), 4 (2,2), 5 (1,2), 6 (0,2), 7 (0,1), 8 the centre (1,1). A turn
 * by 90 degrees counter-clockwise maps node k < 8 to k + 2 (mod 8) and bit e
 * to bit e + 1 (mod 4). */
#include <string.h>

#include "base/common.h"
#include "quad/quad.h"
#include "base/scan.h"

/* Small loops run on one thread: a parallel region costs more than them. */
#define PAR(n) ((n) > 4096)

#define NONE UINT32_MAX

static const int loc[9][2] = {{0, 0}, {1, 0}, {2, 0}, {2, 1}, {2, 2},
                              {1, 2}, {0, 2}, {0, 1}, {1, 1}};

typedef struct {
  int n;
  int8_t cell[4][4]; /* counter-clockwise; a triangle's 4th is -1 */
} pattern;

/* The base patterns. One mid-node: the fan from it (smallest angle 26.6
 * degrees; a fan from a far corner would have 18.4). Two on adjacent
 * edges (bottom, right): the corner between them cut off, a kite from the
 * opposite corner through both mid-nodes, and the half square left over:
 * all triangles are right isosceles (45 degrees; the other splits leave a
 * triangle of 26.6 or less); the kite's angles are 45 and 135. Three
 * (bottom, right, top): the half square without mid-nodes as a quad and 3
 * right isosceles triangles (45 degrees; the others give 26.6 or less).
 * Four: 4 quads around the centre. */
static const pattern base[6] = {
    {1, {{0, 2, 4, 6}}},
    {3, {{0, 1, 6, -1}, {1, 2, 4, -1}, {1, 4, 6, -1}}},
    {2, {{0, 1, 5, 6}, {1, 2, 4, 5}}},
    {3, {{0, 1, 3, 4}, {1, 2, 3, -1}, {4, 6, 0, -1}}},
    {4, {{0, 1, 5, 6}, {1, 2, 3, -1}, {3, 4, 5, -1}, {5, 1, 3, -1}}},
    {4, {{0, 1, 8, 7}, {1, 2, 3, 8}, {8, 3, 4, 5}, {7, 8, 5, 6}}},
};

/* mask -> base pattern and number of quarter turns */
static const uint8_t of_mask[16][2] = {{0, 0}, {1, 0}, {1, 1}, {3, 0}, {1, 2}, {2, 0},
                                       {3, 1}, {4, 0}, {1, 3}, {3, 3}, {2, 1}, {4, 3},
                                       {3, 2}, {4, 2}, {4, 1}, {5, 0}};

static int turn(int k, int r) { return k < 0 || k == 8 ? k : (k + 2 * r) & 7; }

/* The 16 patterns turned into place: the cells of mask m on local nodes. */
static void turn_patterns(pattern t[16]) {
  for (int m = 0; m < 16; m++) {
    const pattern *p = &base[of_mask[m][0]];
    t[m].n = p->n;
    for (int j = 0; j < p->n; j++)
      for (int v = 0; v < 4; v++) t[m].cell[j][v] = (int8_t)turn(p->cell[j][v], of_mask[m][1]);
  }
}

/* Local nodes a leaf of this mask uses: corners, its mid-nodes, the centre. */
static unsigned used_nodes(unsigned mask) {
  unsigned u = 0x55;
  for (int e = 0; e < 4; e++)
    if ((mask >> e) & 1) u |= 1u << (2 * e + 1);
  return mask == 15 ? u | 0x100 : u;
}

/* ---- the node table -------------------------------------------------------- */

/* Nodes lie on the lattice of the finest leaves (mid-nodes are corners of
 * finer leaves), grouped in blocks of 4 x 4 such lattice points. A hash
 * table of blocks (few: small, mostly in cache) holds, per point of a
 * block, the quadrants around it that leaves cover (bit 0 lower left, 1
 * lower right, 2 upper left, 3 upper right; a nibble per point): as a
 * corner (a point covered so is a node) and as the midpoint of an edge (a
 * leaf uses it when it is a node); and where the block's nodes start in
 * `id`. Leaves taken in Morton order visit a block many times in a row. */
typedef struct {
  uint64_t kw;     /* block + 1; 0 = empty */
  uint64_t corner; /* nibble (x & 3) + 4 (y & 3): covered by leaves with it as a corner */
  uint64_t mid;    /* ... with it as the midpoint of an edge */
  uint32_t off;    /* the block's first node in id */
} block;

enum { LL = 1, LR = 2, UL = 4, UR = 8 };

/* The quadrants around local node k that its leaf covers. */
static const uint8_t covers[9] = {UR, UL | UR, UL, LL | UL, LL, LL | LR, LR, LR | UR, 15};

typedef struct {
  block *b;
  size_t cap, count;
  uint32_t *id;  /* per node: its id */
  int shift;     /* lattice coordinate >> shift: on the finest leaves' lattice */
  int finest;    /* their level: their mid-nodes are off that lattice */
  int full;
} node_table;

/* The last block looked up of each parity class (bx & 1, by & 1): a leaf's
 * nodes span at most 2 x 2 neighbouring blocks, one of each class. While
 * covering, the bits for a block are gathered and written with one atomic
 * OR when the cursor leaves it. */
typedef struct {
  uint64_t blk[4];
  block *e[4];
  uint64_t corner[4], mid[4]; /* gathered, not yet written */
} cursor;

static void cursor_init(cursor *c) {
  for (int i = 0; i < 4; i++) {
    c->blk[i] = UINT64_MAX;
    c->e[i] = NULL;
    c->corner[i] = c->mid[i] = 0;
  }
}

static void flush(cursor *c, int p) {
  if (c->e[p] && c->corner[p]) __atomic_fetch_or(&c->e[p]->corner, c->corner[p], __ATOMIC_RELAXED);
  if (c->e[p] && c->mid[p]) __atomic_fetch_or(&c->e[p]->mid, c->mid[p], __ATOMIC_RELAXED);
  c->corner[p] = c->mid[p] = 0;
}

static inline size_t home(uint64_t blk, size_t cap) {
  uint64_t h = blk * 0x9E3779B97F4A7C15ULL;
  h ^= h >> 29;
  h *= 0xBF58476D1CE4E5B9ULL;
  h ^= h >> 32;
  return (size_t)(((unsigned __int128)h * cap) >> 64);
}

static block *find_block(const node_table *H, uint64_t blk) {
  for (size_t i = home(blk, H->cap);; i = i + 1 == H->cap ? 0 : i + 1) {
    const uint64_t kw = __atomic_load_n(&H->b[i].kw, __ATOMIC_ACQUIRE);
    if (kw == blk + 1) return &H->b[i];
    if (!kw) return NULL;
  }
}

/* Claims (or finds) the entry of blk; NULL when the table is full. */
static block *claim_block(node_table *H, uint64_t blk) {
  const uint64_t want = blk + 1;
  for (size_t i = home(blk, H->cap);; i = i + 1 == H->cap ? 0 : i + 1) {
    uint64_t kw = __atomic_load_n(&H->b[i].kw, __ATOMIC_ACQUIRE);
    if (!kw) {
      if (__atomic_load_n(&H->full, __ATOMIC_RELAXED)) return NULL;
      uint64_t expected = 0;
      if (__atomic_compare_exchange_n(&H->b[i].kw, &expected, want, 0, __ATOMIC_ACQ_REL,
                                      __ATOMIC_ACQUIRE)) {
        if (4 * __atomic_add_fetch(&H->count, 1, __ATOMIC_RELAXED) > 3 * H->cap)
          __atomic_store_n(&H->full, 1, __ATOMIC_RELAXED);
        return &H->b[i];
      }
      kw = expected;
    }
    if (kw == want) return &H->b[i];
  }
}

/* The block of point (fx, fy) of the finest leaves' lattice through the
 * cursor (claimed when `claim`), and the point's nibble in it; NULL when the
 * block does not exist. */
static inline __attribute__((always_inline)) block *block_at(node_table *H, cursor *c,
                                                              uint32_t fx, uint32_t fy,
                                                              int claim, int *nib, int *slot) {
  const uint64_t blk = (uint64_t)(fx >> 2) << 32 | (fy >> 2);
  const int p = (int)(((fx >> 2) & 1) | ((fy >> 1) & 2));
  if (blk != c->blk[p] || (!c->e[p] && claim)) {
    if (claim) flush(c, p);
    c->blk[p] = blk;
    c->e[p] = claim ? claim_block(H, blk) : find_block(H, blk);
  }
  *nib = 4 * (int)((fx & 3) | (fy & 3) << 2);
  *slot = p;
  return c->e[p];
}

/* Bit 4i set when nibble i is not 0. */
static inline uint64_t nonzero(uint64_t v) {
  v |= v >> 1;
  return (v | v >> 2) & 0x1111111111111111ULL;
}

/* The id word of the node at (fx, fy), which must exist. */
static uint32_t *node_id(node_table *H, cursor *c, uint32_t fx, uint32_t fy) {
  int nib, p;
  const block *e = block_at(H, c, fx, fy, 0, &nib, &p);
  return &H->id[e->off + (uint32_t)__builtin_popcountll(nonzero(e->corner) & ((1ULL << nib) - 1))];
}

/* A table of cap entries holding H's blocks (rehashed in parallel). */
static int resize(node_table *H, size_t cap) {
  block *b = mx_alloc(cap * sizeof *b);
  if (!b) return MX_ENOMEM;
#pragma omp parallel for schedule(static) if (PAR(cap))
  for (size_t i = 0; i < cap; i++) b[i] = (block){0, 0, 0, 0};
  node_table N = {.b = b, .cap = cap};
#pragma omp parallel for schedule(static) if (PAR(H->cap))
  for (size_t i = 0; i < H->cap; i++)
    if (H->b[i].kw) {
      block *e = claim_block(&N, H->b[i].kw - 1);
      e->corner = H->b[i].corner;
      e->mid = H->b[i].mid;
    }
  mx_free(H->b);
  H->b = b;
  H->cap = cap;
  H->full = 0;
  return MX_OK;
}

static void nt_free(node_table *H) {
  mx_free(H->b);
  mx_free(H->id);
  H->b = NULL;
  H->id = NULL;
}

/* A leaf on the finest leaves' lattice: its anchor and side (>= 1). */
typedef struct {
  uint32_t x, y, s;
} fleaf;

static inline __attribute__((always_inline)) fleaf leaf_at(const node_table *H, uint64_t key,
                                                           int level) {
  uint32_t x, y;
  mx_qkey_xy(key, &x, &y);
  return (fleaf){x >> H->shift, y >> H->shift, mx_qsize(level) >> H->shift};
}

/* Local node k of leaf f on that lattice (a mid-node only when s >= 2). */
#define NX(k) (f.x + ((uint32_t)loc[k][0] * f.s >> 1))
#define NY(k) (f.y + ((uint32_t)loc[k][1] * f.s >> 1))

/* Every leaf's corners and (but the finest's) edge midpoints with the
 * quadrants it covers, by chunks; a chunk that fills the table is done
 * again after the table doubled (covering a quadrant twice changes
 * nothing). */
static int cover(const uint64_t *key, const uint8_t *lev, size_t n, node_table *H) {
  const size_t chunk = 1 << 16;
  for (size_t lo = 0; lo < n;) {
    const size_t hi = n - lo < chunk ? n : lo + chunk;
#pragma omp parallel if (PAR(hi - lo))
    {
      cursor c;
      cursor_init(&c);
#pragma omp for schedule(static)
      for (size_t i = lo; i < hi; i++) {
        const fleaf f = leaf_at(H, key[i], lev[i]);
        const int step = lev[i] < H->finest ? 1 : 2;
        for (int k = 0; k < 8; k += step) {
          int nib, p;
          if (!block_at(H, &c, NX(k), NY(k), 1, &nib, &p)) continue;
          if (k & 1) c.mid[p] |= (uint64_t)covers[k] << nib;
          else c.corner[p] |= (uint64_t)covers[k] << nib;
        }
      }
      for (int p = 0; p < 4; p++) flush(&c, p);
    }
    if (H->full) MX_CHECK(resize(H, 2 * H->cap));
    else lo = hi;
  }
  return MX_OK;
}

/* Each block's place in id: a prefix sum of its node counts, the blocks
 * taken in Morton order (the passes go over the leaves in that order: the
 * ids they read and write are then near each other). */
static int place_blocks(node_table *H) {
  const size_t B = 4096, nb = (H->cap + B - 1) / B;
  uint64_t *off = mx_alloc((nb + 1) * sizeof *off);
  if (!off) return MX_ENOMEM;
#pragma omp parallel for schedule(static) if (PAR(H->cap))
  for (size_t j = 0; j < nb; j++) {
    uint64_t c = 0;
    for (size_t i = j * B; i < H->cap && i < (j + 1) * B; i++) c += H->b[i].kw != 0;
    off[j] = c;
  }
  const size_t nblk = (size_t)mx_scan_u64(off, nb);
  uint64_t *key = mx_alloc((nblk + 1) * sizeof *key);
  uint32_t *slot = mx_alloc((nblk + 1) * sizeof *slot);
  uint64_t *cnt = mx_alloc((nblk + 1) * sizeof *cnt);
  int st = key && slot && cnt ? MX_OK : MX_ENOMEM;
  if (st == MX_OK) {
#pragma omp parallel for schedule(static) if (PAR(H->cap))
    for (size_t j = 0; j < nb; j++) {
      uint64_t c = off[j];
      for (size_t i = j * B; i < H->cap && i < (j + 1) * B; i++) {
        const uint64_t kw = H->b[i].kw;
        if (!kw) continue;
        key[c] = mx_qkey((uint32_t)((kw - 1) >> 32), (uint32_t)(kw - 1));
        slot[c++] = (uint32_t)i;
      }
    }
    st = mx_sort_u64(key, slot, nblk);
  }
  if (st == MX_OK) {
#pragma omp parallel for schedule(static) if (PAR(nblk))
    for (size_t k = 0; k < nblk; k++)
      cnt[k] = (uint64_t)__builtin_popcountll(nonzero(H->b[slot[k]].corner));
    const uint64_t total = mx_scan_u64(cnt, nblk);
#pragma omp parallel for schedule(static) if (PAR(nblk))
    for (size_t k = 0; k < nblk; k++) H->b[slot[k]].off = (uint32_t)cnt[k];
    H->id = mx_alloc((total + 1) * sizeof *H->id);
    if (!H->id) st = MX_ENOMEM;
  }
  mx_free(off), mx_free(key), mx_free(slot), mx_free(cnt);
  return st;
}

/* The leaves' keys and levels, gathered in their order (the passes read
 * them sequentially, not scattered over the quadtree); the finest level;
 * whether they are in Morton order. */
static int gather_leaves(const mx_qtree *T, const uint32_t *leaves, size_t n, uint64_t *key,
                         uint8_t *lev, int *finest) {
  int fin = 0, unsorted = 0;
#pragma omp parallel for schedule(static) reduction(max : fin) reduction(| : unsorted) if (PAR(n))
  for (size_t i = 0; i < n; i++) {
    if (i + 16 < n) __builtin_prefetch(&T->key[leaves[i + 16]]);
    key[i] = T->key[leaves[i]];
    lev[i] = T->level[leaves[i]];
    if (lev[i] > fin) fin = lev[i];
    unsorted |= i > 0 && key[i] <= T->key[leaves[i - 1]];
  }
  if (unsorted) {
    mx_error(NULL, 0, "internal: the transition's leaves are not in Morton order");
    return MX_EINTERNAL;
  }
  *finest = fin;
  return MX_OK;
}

static int build_table(const uint64_t *key, const uint8_t *lev, size_t n, int finest,
                       node_table *H) {
  H->finest = finest;
  H->shift = MX_QMAX_LEVEL - finest;
  /* the blocks holding a leaf's anchor (those of a block are consecutive
   * in Morton order), times 4 for those holding only other nodes and a
   * table half full at most: few resizes, whatever the grading */
  const int sh = 2 * H->shift + 4;
  size_t runs = 0;
#pragma omp parallel for schedule(static) reduction(+ : runs) if (PAR(n))
  for (size_t i = 0; i < n; i++) runs += i == 0 || key[i] >> sh != key[i - 1] >> sh;
  MX_CHECK(resize(H, 4 * runs + 1024));
  MX_CHECK(cover(key, lev, n, H));
  return place_blocks(H);
}

/* ---- the passes -------------------------------------------------------------- */

/* The owner of node (x, y), the leaf of smallest key (= position) using it,
 * is the one covering its lower left quadrant; without it, the one of lower
 * right and upper left whose cell next to the node comes first in Morton
 * order (leaves are intervals of that order, also on the finest leaves'
 * lattice); then upper right. Returns the quadrant the owner covers. */
static unsigned owner_quadrant(unsigned cov, uint32_t x, uint32_t y) {
  if (cov & LL) return LL;
  if ((cov & (LR | UL)) == (LR | UL)) return mx_qkey(x, y - 1) < mx_qkey(x - 1, y) ? LR : UL;
  if (cov & LR) return LR;
  return cov & UL ? UL : UR;
}

/* The state of the passes over the leaves. They go by chunks of CHUNK
 * leaves, whose first node and cell come from a prefix sum over chunks
 * (within a chunk, leaf after leaf). */
#define CHUNK 512
typedef struct {
  const mx_qtree *T;
  const uint32_t *leaves;
  const uint64_t *key; /* per leaf (gathered) */
  const uint8_t *lev;
  size_t n, nchunks;
  node_table H;
  pattern pat[16];
  uint8_t *mask;    /* per leaf: its edge midpoints that are nodes */
  uint16_t *owned;  /* per leaf: the local nodes it owns */
  uint64_t *base;   /* per chunk: first node | first cell << 32 */
  mx_qmesh *M;
} pass;

/* Leaf i's mask and owned nodes; returns its nodes | cells << 32. */
static uint64_t classify_leaf(pass *X, cursor *c, size_t i) {
  const fleaf f = leaf_at(&X->H, X->key[i], X->lev[i]);
  const int step = X->lev[i] < X->H.finest ? 1 : 2;
  unsigned m = 0, own = 0;
  for (int k = 0; k < 8; k += step) {
    int nib, p;
    const block *e = block_at(&X->H, c, NX(k), NY(k), 0, &nib, &p);
    const unsigned cov = e ? (unsigned)(e->corner >> nib) & 15 : 0;
    if (!cov) continue; /* a midpoint that is no node */
    if (k & 1) m |= 1u << (k >> 1);
    if (owner_quadrant(cov | ((unsigned)(e->mid >> nib) & 15), NX(k), NY(k)) & covers[k])
      own |= 1u << k;
  }
  if (m == 15) own |= 0x100;
  X->mask[i] = (uint8_t)m;
  X->owned[i] = (uint16_t)own;
  return (uint64_t)__builtin_popcount(own) | ((uint64_t)X->pat[m].n << 32);
}

/* Leaf i's owned nodes from id on: their ids, coordinates and keys;
 * returns the next id. */
static uint32_t number_leaf(pass *X, cursor *c, size_t i, uint32_t id) {
  const mx_qgrid *g = &X->T->grid;
  const fleaf f = leaf_at(&X->H, X->key[i], X->lev[i]);
  const int sh = X->H.shift;
  for (unsigned o = X->owned[i]; o; o &= o - 1, id++) {
    const int k = __builtin_ctz(o);
    if (k < 8) *node_id(&X->H, c, NX(k), NY(k)) = id;
    X->M->nkey[id] = mx_qkey(NX(k) << sh, NY(k) << sh);
    X->M->xy[2 * (size_t)id] = g->origin[0] + g->unit * (double)(NX(k) << sh);
    X->M->xy[2 * (size_t)id + 1] = g->origin[1] + g->unit * (double)(NY(k) << sh);
  }
  return id;
}

/* Leaf i's cells (its pattern on its node ids), its nodes and cells
 * starting at off (nodes | cells << 32); returns where the next leaf's start. */
static uint64_t emit_leaf(pass *X, cursor *cu, size_t i, uint64_t off) {
  const unsigned mask = X->mask[i], owned = X->owned[i], use = used_nodes(mask);
  uint32_t id[9], next = (uint32_t)off;
  const fleaf f = leaf_at(&X->H, X->key[i], X->lev[i]);
  for (int k = 0; k < 9; k++) {
    if (!((use >> k) & 1)) continue;
    id[k] = ((owned >> k) & 1) ? next++ : *node_id(&X->H, cu, NX(k), NY(k));
  }
  const pattern *p = &X->pat[mask];
  mx_qmesh *M = X->M;
  size_t c = (size_t)(off >> 32);
  for (int j = 0; j < p->n; j++, c++) {
    const int tri = p->cell[j][3] < 0;
    for (int v = 0; v < 4; v++) M->conn[4 * c + v] = v == 3 && tri ? NONE : id[p->cell[j][v]];
    M->type[c] = tri ? MX_QTRI : MX_QQUAD;
    M->leaf[c] = (uint32_t)i;
    M->level[c] = X->lev[i];
  }
  return (uint64_t)next | (uint64_t)c << 32;
}

enum { CLASSIFY, NUMBER, EMIT };

/* One pass over the leaves, chunk by chunk. */
static void run_pass(pass *X, int what) {
#pragma omp parallel if (PAR(X->n))
  {
    cursor c;
    cursor_init(&c);
#pragma omp for schedule(static)
    for (size_t ch = 0; ch < X->nchunks; ch++) {
      const size_t lo = ch * CHUNK, hi = lo + CHUNK < X->n ? lo + CHUNK : X->n;
      uint64_t s = what == CLASSIFY ? 0 : X->base[ch];
      for (size_t i = lo; i < hi; i++) {
        if (what == CLASSIFY) s += classify_leaf(X, &c, i);
        else if (what == NUMBER) s = number_leaf(X, &c, i, (uint32_t)s);
        else s = emit_leaf(X, &c, i, s);
      }
      if (what == CLASSIFY) X->base[ch] = s;
    }
  }
}

static int mesh_alloc(mx_qmesh *M, size_t nn, size_t nc) {
  M->nnodes = nn;
  M->ncells = nc;
  M->xy = mx_alloc((2 * nn + 1) * sizeof *M->xy);
  M->nkey = mx_alloc((nn + 1) * sizeof *M->nkey);
  M->type = mx_alloc(nc + 1);
  M->conn = mx_alloc((4 * nc + 1) * sizeof *M->conn);
  M->leaf = mx_alloc((nc + 1) * sizeof *M->leaf);
  M->level = mx_alloc(nc + 1);
  return M->xy && M->nkey && M->type && M->conn && M->leaf && M->level ? MX_OK : MX_ENOMEM;
}

void mx_qmesh_free(mx_qmesh *M) {
  mx_free(M->xy);
  mx_free(M->nkey);
  mx_free(M->type);
  mx_free(M->conn);
  mx_free(M->leaf);
  mx_free(M->level);
  memset(M, 0, sizeof *M);
}

int mx_qtransition(const mx_qtree *T, const uint32_t *leaves, size_t n, mx_qmesh *M) {
  memset(M, 0, sizeof *M);
  if (n >= UINT32_MAX / 4) {
    mx_error(NULL, 0, "too many leaves for the transition (%zu)", n);
    return MX_EINPUT;
  }
  pass X = {.T = T, .leaves = leaves, .n = n, .nchunks = (n + CHUNK - 1) / CHUNK, .M = M};
  turn_patterns(X.pat);
  uint64_t *key = mx_alloc((n + 1) * sizeof *key);
  uint8_t *lev = mx_alloc(n + 1);
  X.key = key, X.lev = lev;
  X.mask = mx_alloc(n + 1);
  X.owned = mx_alloc((n + 1) * sizeof *X.owned);
  X.base = mx_alloc((X.nchunks + 1) * sizeof *X.base);
  int st = key && lev && X.mask && X.owned && X.base ? MX_OK : MX_ENOMEM, finest = 0;
  if (!st) st = gather_leaves(T, leaves, n, key, lev, &finest);
  if (!st) st = build_table(key, lev, n, finest, &X.H);
  if (!st) {
    run_pass(&X, CLASSIFY);
    const uint64_t total = mx_scan_u64(X.base, X.nchunks);
    st = mesh_alloc(M, (size_t)(total & 0xffffffffu), (size_t)(total >> 32));
  }
  if (!st) {
    run_pass(&X, NUMBER);
    run_pass(&X, EMIT);
  }
  nt_free(&X.H);
  mx_free(X.mask), mx_free(X.owned), mx_free(X.base), mx_free(key), mx_free(lev);
  if (st) mx_qmesh_free(M);
  return st;
}
