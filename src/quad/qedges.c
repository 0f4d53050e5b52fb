/* Edge infos of the quadtree (Jaillet & Lobos 2021, section 3.2), and the
 * balance check they serve.
 *
 * One hash table per level and axis (0: edges along x, 1: along y), keyed by
 * the Morton key of the edge's lower end on that level's lattice. An info
 * has 2 slots: the quadrant of that level below (along x) or left (along y)
 * of the edge, and the one above or right (UINT32_MAX: none). Unlike the
 * paper, slots never hold coarser quadrants and there is no mid-node field:
 * a quadrant's coarser neighbours are found in its parent's edges, which is
 * all balancing needs (the transition finds mid-nodes from the leaves'
 * corners). Each slot has one possible writer and keys are claimed by
 * compare-and-swap, so many threads register children at once. Quadrants
 * outside the domain are not registered: they are never split. */
#include <string.h>

#include "base/common.h"
#include "quad/quad.h"
#include "base/scan.h"

/* Small loops run on one thread: a parallel region costs more than them. */
#define PAR(n) ((n) > 4096)

#define NONE UINT32_MAX

typedef struct {
  uint64_t *kw;   /* key + 1; 0 = empty */
  uint32_t *slot; /* 2 per entry */
  size_t cap, count;
} qtable;

struct mx_qedges {
  int top;
  qtable t[MX_QMAX_LEVEL][2];
};

/* Blocks of 4 x 4 lattice points share a window of the table, so quadrants
 * taken in Morton order touch few windows; blocks are spread by a mix. */
static inline size_t home(uint64_t key, size_t cap) {
  uint64_t h = (key >> 4) * 0x9E3779B97F4A7C15ULL;
  h ^= h >> 29;
  h *= 0xBF58476D1CE4E5B9ULL;
  h ^= h >> 32;
  const size_t s = (size_t)(((unsigned __int128)h * cap) >> 64) + 2 * (size_t)(key & 15);
  return s >= cap ? s - cap : s;
}

static size_t find(const qtable *T, uint64_t key) {
  if (!T->cap) return SIZE_MAX;
  for (size_t i = home(key, T->cap);; i = i + 1 == T->cap ? 0 : i + 1) {
    const uint64_t kw = __atomic_load_n(&T->kw[i], __ATOMIC_ACQUIRE);
    if (!kw) return SIZE_MAX;
    if (kw == key + 1) return i;
  }
}

/* Find or claim; *fresh = 1 when this call claimed the entry. */
static size_t insert(qtable *T, uint64_t key, int *fresh) {
  const uint64_t want = key + 1;
  for (size_t i = home(key, T->cap);; i = i + 1 == T->cap ? 0 : i + 1) {
    uint64_t kw = __atomic_load_n(&T->kw[i], __ATOMIC_ACQUIRE);
    if (!kw) {
      uint64_t expected = 0;
      if (__atomic_compare_exchange_n(&T->kw[i], &expected, want, 0, __ATOMIC_ACQ_REL,
                                      __ATOMIC_ACQUIRE)) {
        *fresh = 1;
        return i;
      }
      kw = expected;
    }
    if (kw == want) {
      *fresh = 0;
      return i;
    }
  }
}

static inline void put(qtable *T, uint64_t key, int side, uint32_t q, size_t *created) {
  int fresh;
  const size_t i = insert(T, key, &fresh);
  *created += (size_t)fresh;
  __atomic_store_n(&T->slot[2 * i + side], q, __ATOMIC_RELAXED);
}

/* Room for `need` entries at load <= 0.7; rehashed in parallel. */
static int reserve(qtable *T, size_t need) {
  if ((double)need <= 0.7 * (double)T->cap) return MX_OK;
  size_t cap = (size_t)((double)need / 0.5) + 1024;
  if (cap < T->cap + T->cap / 2) cap = T->cap + T->cap / 2;
  qtable N = {mx_alloc(cap * sizeof *N.kw), mx_alloc(2 * cap * sizeof *N.slot), cap, T->count};
  if (!N.kw || !N.slot) {
    mx_free(N.kw), mx_free(N.slot);
    return MX_ENOMEM;
  }
#pragma omp parallel for schedule(static) if (PAR(cap))
  for (size_t i = 0; i < cap; i++) {
    N.kw[i] = 0;
    N.slot[2 * i] = N.slot[2 * i + 1] = NONE;
  }
#pragma omp parallel for schedule(static) if (PAR(T->cap))
  for (size_t i = 0; i < T->cap; i++) {
    if (!T->kw[i]) continue;
    int fresh;
    const size_t j = insert(&N, T->kw[i] - 1, &fresh);
    N.slot[2 * j] = T->slot[2 * i];
    N.slot[2 * j + 1] = T->slot[2 * i + 1];
  }
  mx_free(T->kw);
  mx_free(T->slot);
  *T = N;
  return MX_OK;
}

int mx_qedges_new(int top, mx_qedges **E) {
  *E = mx_calloc(sizeof **E);
  if (!*E) return MX_ENOMEM;
  (*E)->top = top < MX_QMAX_LEVEL - 1 ? top : MX_QMAX_LEVEL - 1;
  return MX_OK;
}

void mx_qedges_free(mx_qedges *E) {
  if (!E) return;
  for (int l = 0; l < MX_QMAX_LEVEL; l++)
    for (int a = 0; a < 2; a++) {
      mx_free(E->t[l][a].kw);
      mx_free(E->t[l][a].slot);
    }
  mx_free(E);
}

size_t mx_qedges_count(const mx_qedges *E) {
  size_t n = 0;
  for (int l = 0; E && l < MX_QMAX_LEVEL; l++) n += E->t[l][0].count + E->t[l][1].count;
  return n;
}

/* Anchor of quadrant q on the lattice of its own level. */
static void anchor(const mx_qtree *T, uint32_t q, uint32_t *x, uint32_t *y) {
  mx_qkey_xy(T->key[q], x, y);
  *x >>= MX_QMAX_LEVEL - T->level[q];
  *y >>= MX_QMAX_LEVEL - T->level[q];
}

int mx_qedges_add_roots(mx_qedges *E, const mx_qtree *T, size_t nroots) {
  if (E->top < 0) return MX_OK;
  qtable *H = &E->t[0][0], *V = &E->t[0][1];
  MX_CHECK(reserve(H, H->count + 2 * nroots));
  MX_CHECK(reserve(V, V->count + 2 * nroots));
  for (uint32_t r = 0; r < nroots; r++) {
    if (T->flags[r] & MX_Q_OUT) continue;
    uint32_t x, y;
    anchor(T, r, &x, &y);
    put(H, mx_qkey(x, y), 1, r, &H->count);     /* its bottom: it is above */
    put(H, mx_qkey(x, y + 1), 0, r, &H->count); /* its top */
    put(V, mx_qkey(x, y), 1, r, &V->count);     /* its left: it is right */
    put(V, mx_qkey(x + 1, y), 0, r, &V->count); /* its right */
  }
  return MX_OK;
}

/* The 12 edges of level l+1 inside and around parent p, each looked up once
 * and given the slots of p's children (child c: bit 0 = +x, bit 1 = +y). */
static void register_children(qtable *H, qtable *V, const mx_qtree *T, uint32_t p,
                              size_t created[2]) {
  uint32_t x, y, who[2][2];
  anchor(T, p, &x, &y);
  x *= 2;
  y *= 2;
  for (int c = 0; c < 4; c++) {
    const uint32_t q = T->child0[p] + (uint32_t)c;
    who[c >> 1][c & 1] = (T->flags[q] & MX_Q_OUT) ? NONE : q;
  }
  for (int i = 0; i < 2; i++)
    for (int j = 0; j < 3; j++) {
      /* along x at (x+i, y+j): below is child (i, j-1), above (i, j) */
      const uint32_t below = j > 0 ? who[j - 1][i] : NONE, above = j < 2 ? who[j][i] : NONE;
      if (below != NONE) put(H, mx_qkey(x + i, y + j), 0, below, &created[0]);
      if (above != NONE) put(H, mx_qkey(x + i, y + j), 1, above, &created[0]);
      /* along y at (x+j, y+i): left is child (j-1, i), right (j, i) */
      const uint32_t left = j > 0 ? who[i][j - 1] : NONE, right = j < 2 ? who[i][j] : NONE;
      if (left != NONE) put(V, mx_qkey(x + j, y + i), 0, left, &created[1]);
      if (right != NONE) put(V, mx_qkey(x + j, y + i), 1, right, &created[1]);
    }
}

int mx_qedges_add_children(mx_qedges *E, const mx_qtree *T, const uint32_t *split, size_t n) {
  if (n == 0) return MX_OK;
  const int l = T->level[split[0]] + 1;
  if (l > E->top) return MX_OK; /* never looked at: no split reads them */
  qtable *H = &E->t[l][0], *V = &E->t[l][1];
  MX_CHECK(reserve(H, H->count + 6 * n));
  MX_CHECK(reserve(V, V->count + 6 * n));
  size_t ch = 0, cv = 0;
  int mixed = 0;
#pragma omp parallel for schedule(static) reduction(+ : ch, cv) reduction(| : mixed) \
    if (PAR(n))
  for (size_t i = 0; i < n; i++) {
    if (T->level[split[i]] + 1 != l) {
      mixed = 1;
      continue;
    }
    size_t c[2] = {0, 0};
    register_children(H, V, T, split[i], c);
    ch += c[0];
    cv += c[1];
  }
  H->count += ch;
  V->count += cv;
  if (mixed) {
    mx_error(NULL, 0, "internal: edge infos of splits of several levels at once");
    return MX_EINTERNAL;
  }
  return MX_OK;
}

/* The quadrant of level l-1 across the edge of q's parent that q lies on,
 * along x (axis 0, below or above) or y (axis 1, left or right). */
static uint32_t across(const mx_qedges *E, const mx_qtree *T, uint32_t q, int axis) {
  const uint32_t p = T->parent[q];
  const int c = (int)(q - T->child0[p]);
  const int hi = axis == 0 ? c >> 1 : c & 1;
  uint32_t x, y;
  anchor(T, p, &x, &y);
  if (hi) {
    if (axis == 0) y++;
    else x++;
  }
  const qtable *t = &E->t[T->level[p]][axis];
  const size_t i = find(t, mx_qkey(x, y));
  return i == SIZE_MAX ? NONE : t->slot[2 * i + (hi ? 1 : 0)];
}

/* Claims leaf x for the to_balance list (once, whoever gets there first;
 * the list is sorted afterwards, so the result does not depend on it). */
static int claim(mx_qtree *T, uint32_t x) {
  if (x == NONE) return 0;
  const uint8_t f = __atomic_load_n(&T->flags[x], __ATOMIC_RELAXED);
  if (f & (MX_Q_SPLIT | MX_Q_OUT | MX_Q_QUEUED)) return 0;
  return !(__atomic_fetch_or(&T->flags[x], MX_Q_QUEUED, __ATOMIC_RELAXED) & MX_Q_QUEUED);
}

int mx_qedges_unbalanced(const mx_qedges *E, mx_qtree *T, const uint32_t *split, size_t n,
                         uint32_t **out, size_t *nout) {
  *out = NULL;
  *nout = 0;
  uint32_t *cand = mx_alloc((2 * n + 1) * sizeof *cand);
  uint64_t *off = mx_alloc((n + 1) * sizeof *off);
  if (!cand || !off) {
    mx_free(cand), mx_free(off);
    return MX_ENOMEM;
  }
#pragma omp parallel for schedule(static) if (PAR(n))
  for (size_t i = 0; i < n; i++) {
    const uint32_t q = split[i];
    uint64_t k = 0;
    if (T->parent[q] != NONE && T->level[q] - 1 <= E->top)
      for (int axis = 0; axis < 2; axis++) {
        const uint32_t x = across(E, T, q, axis);
        if (claim(T, x)) cand[2 * i + k++] = x;
      }
    off[i] = k;
  }
  const size_t total = mx_scan_u64(off, n);
  uint32_t *list = mx_alloc((total + 1) * sizeof *list);
  uint64_t *key = mx_alloc((total + 1) * sizeof *key);
  int st = list && key ? MX_OK : MX_ENOMEM;
  if (!st) {
#pragma omp parallel for schedule(static) if (PAR(n))
    for (size_t i = 0; i < n; i++)
      for (uint64_t k = 0; k < (i + 1 < n ? off[i + 1] : total) - off[i]; k++) {
        list[off[i] + k] = cand[2 * i + k];
        key[off[i] + k] = T->key[cand[2 * i + k]];
      }
    st = mx_sort_u64(key, list, total);
  }
  mx_free(cand), mx_free(off), mx_free(key);
  if (st) {
    mx_free(list);
    return st;
  }
  *out = list;
  *nout = total;
  return MX_OK;
}
