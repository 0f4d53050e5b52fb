/* The published original's balance, kept as the benchmark's baseline: refine
 * without edge infos, then balance at the very end by recursive neighbour
 * search in a pointer tree (the classic up-then-mirror-down walk). Every
 * octant looks at its 18 face and edge neighbours of its own size or larger;
 * a leaf neighbour more than one level coarser is split, its children are
 * queued, and the search is repeated until nothing changes. Serial, as the
 * original. It gives exactly the leaves of the default (tests check it).
 *
 * The rule both balances implement: a leaf must be split when an octant of
 * the domain two or more levels finer touches it along a face or an edge.
 * "Octant" means every octant ever created and kept, leaf or already split,
 * and children found outside the domain are never created. Balancing while
 * refining level by level sees each octant while it is still a leaf, so this
 * is what it computes; here, at the end, the split octants are checked as
 * well as the leaves. The rule only ever adds splits as the tree grows, so its
 * closure does not depend on the order of the splits. */
#include "kernels/refine.h"

#include "base/common.h"
#include "soa/tree_valid.h"

#include <stdlib.h>
#include <string.h>

typedef struct rnode {
  struct rnode *parent;
  struct rnode *child[8];
  uint32_t oct;
  uint8_t level, cid;
} rnode;

typedef struct {
  rnode **chunks;
  size_t nchunks, used; /* nodes used in the last chunk */
  rnode **roots;        /* dims[0]*dims[1]*dims[2], NULL where dropped */
  rnode **of_oct;       /* octant index -> node */
  size_t of_oct_cap;
  const mx_builder *B;
} rtree;

#define CHUNK 65536

static rnode *node_new(rtree *R) {
  if (R->nchunks == 0 || R->used == CHUNK) {
    rnode **c = mx_realloc(R->chunks, (R->nchunks + 1) * sizeof *c);
    if (!c) return NULL;
    R->chunks = c;
    R->chunks[R->nchunks] = mx_calloc(CHUNK * sizeof(rnode));
    if (!R->chunks[R->nchunks]) return NULL;
    R->nchunks++;
    R->used = 0;
  }
  return &R->chunks[R->nchunks - 1][R->used++];
}

static void rtree_free(rtree *R) {
  for (size_t i = 0; i < R->nchunks; i++) mx_free(R->chunks[i]);
  mx_free(R->chunks);
  mx_free(R->roots);
  mx_free(R->of_oct);
}

static int map_grow(rtree *R, size_t n) {
  if (n <= R->of_oct_cap) return MX_OK;
  size_t cap = R->of_oct_cap ? R->of_oct_cap : 1024;
  while (cap < n) cap *= 2;
  rnode **m = mx_realloc(R->of_oct, cap * sizeof *m);
  if (!m) return MX_ENOMEM;
  memset(m + R->of_oct_cap, 0, (cap - R->of_oct_cap) * sizeof *m);
  R->of_oct = m;
  R->of_oct_cap = cap;
  return MX_OK;
}

/* Attach nodes for the kept children of node p (already split in the SoA). */
static int attach_children(rtree *R, rnode *p) {
  const mx_octree *T = &R->B->tree.oct;
  for (int c = 0; c < 8; c++) {
    uint32_t ch = mx_octree_child(T, p->oct, c);
    if (ch == MX_NONE) continue;
    rnode *n = node_new(R);
    if (!n) return MX_ENOMEM;
    n->parent = p;
    n->oct = ch;
    n->level = (uint8_t)(p->level + 1);
    n->cid = (uint8_t)c;
    p->child[c] = n;
    MX_CHECK(map_grow(R, (size_t)ch + 1));
    R->of_oct[ch] = n;
  }
  return MX_OK;
}

static int is_leaf(const rtree *R, const rnode *n) {
  return !(R->B->tree.oct.flags[n->oct] & MX_OCT_SPLIT);
}

/* Neighbour of n in direction d (components in {-1,0,1}) of n's size or
 * larger: the deepest node of level <= n's level across that face or edge;
 * NULL where the domain has no octant. */
static rnode *neighbor(const rtree *R, const rnode *n, const int d[3]) {
  if (!n->parent) {
    const mx_grid *g = &R->B->tree.grid;
    uint32_t c[3];
    mx_morton_decode(R->B->tree.oct.key[n->oct], c);
    int p[3];
    for (int a = 0; a < 3; a++) {
      p[a] = (int)(c[a] >> MX_MAX_LEVEL) + d[a];
      if (p[a] < 0 || p[a] >= g->dims[a]) return NULL;
    }
    return R->roots[((size_t)p[2] * g->dims[1] + p[1]) * g->dims[0] + p[0]];
  }
  int leave[3] = {0, 0, 0}, any = 0, flip = 0;
  for (int a = 0; a < 3; a++) {
    if (!d[a]) continue;
    flip |= 1 << a;
    const int bit = (n->cid >> a) & 1;
    if ((d[a] > 0 && bit) || (d[a] < 0 && !bit)) {
      leave[a] = d[a];
      any = 1;
    }
  }
  const int t = n->cid ^ flip;
  if (!any) return n->parent->child[t];
  rnode *q = neighbor(R, n->parent, leave);
  if (!q || is_leaf(R, q)) return q;
  return q->child[t];
}

int mx_balance_recursive(mx_builder *B) {
  double t0 = mx_wtime();
  mx_octree *T = &B->tree.oct;
  rtree R;
  memset(&R, 0, sizeof R);
  R.B = B;
  const mx_grid *g = &B->tree.grid;
  const size_t nroot = (size_t)g->dims[0] * g->dims[1] * g->dims[2];
  R.roots = mx_calloc(nroot * sizeof *R.roots);
  int st = R.roots ? map_grow(&R, T->n) : MX_ENOMEM;
  /* Build the pointer tree from the refined octants (parents come first). */
  for (size_t o = 0; o < T->n && !st; o++) {
    if (T->parent[o] != MX_NONE) continue;
    rnode *n = node_new(&R);
    if (!n) {
      st = MX_ENOMEM;
      break;
    }
    n->oct = (uint32_t)o;
    uint32_t c[3];
    mx_morton_decode(T->key[o], c);
    R.roots[((size_t)(c[2] >> MX_MAX_LEVEL) * g->dims[1] +
             (c[1] >> MX_MAX_LEVEL)) * g->dims[0] + (c[0] >> MX_MAX_LEVEL)] = n;
    R.of_oct[o] = n;
  }
  for (size_t o = 0; o < T->n && !st; o++)
    if (T->flags[o] & MX_OCT_SPLIT) st = attach_children(&R, R.of_oct[o]);
  /* Worklist: every octant, leaf or split. */
  size_t cap = T->n + 16, top = 0;
  uint32_t *work = mx_alloc(cap * sizeof *work);
  if (!work) st = MX_ENOMEM;
  for (size_t o = T->n; o-- > 0 && !st;) work[top++] = (uint32_t)o;
  static const int dirs[18][3] = {
      {1, 0, 0},  {-1, 0, 0}, {0, 1, 0},  {0, -1, 0}, {0, 0, 1},  {0, 0, -1},
      {1, 1, 0},  {1, -1, 0}, {-1, 1, 0}, {-1, -1, 0}, {1, 0, 1}, {1, 0, -1},
      {-1, 0, 1}, {-1, 0, -1}, {0, 1, 1}, {0, 1, -1}, {0, -1, 1}, {0, -1, -1}};
  while (top > 0 && !st) {
    const uint32_t o = work[--top];
    const rnode *L = R.of_oct[o];
    for (int k = 0; k < 18 && !st; k++) {
      for (;;) {
        rnode *q = neighbor(&R, L, dirs[k]);
        if (!q || !is_leaf(&R, q) || q->level + 1 >= L->level) break;
        st = mx_split_octants(B, &q->oct, 1, 1);
        if (!st) st = map_grow(&R, T->n);
        if (!st) st = attach_children(&R, q);
        if (st) break;
        const int nk = __builtin_popcount(T->kept[q->oct]);
        if (top + (size_t)nk + 1 > cap) {
          cap = 2 * cap + 16;
          uint32_t *w = mx_realloc(work, cap * sizeof *w);
          if (!w) {
            st = MX_ENOMEM;
            break;
          }
          work = w;
        }
        for (int c = 0; c < nk; c++) work[top++] = T->child0[q->oct] + (uint32_t)c;
      }
    }
  }
  mx_free(work);
  rtree_free(&R);
  B->stats.t_balance += mx_wtime() - t0;
  if (!st) MX_TREE_INVARIANTS(&B->tree, MX_TREE_BALANCED, "the recursive balance");
  return st;
}
