/* A rank's patch octree straight from the patch's leaves
 * (src/mpi/p4est_tree.h). */
#include "mpi/p4est_tree.h"

#include "base/common.h"
#include "base/scan.h"
#include "kernels/edges_lazy.h"
#include "mesher/mesher_impl.h"
#include "mpi/exchange.h"

#include <string.h>

void mx_patch_leaves_free(mx_patch_leaves *S) {
  mx_free(S->key);
  mx_free(S->level);
  mx_free(S->owner);
  mx_free(S->pq);
  mx_free(S->tri);
  memset(S, 0, sizeof *S);
}

/* ---- the halo's data from its owners ------------------------------------ */

/* A leaf's data as sent back: its key (checked), triangle count, level and
 * mx_pq fields. */
typedef struct {
  uint64_t key;
  uint32_t tri_cnt;
  uint8_t level, flags, target, rmeet, rin, pad[3];
} leaf_data;

int mx_patch_leaves_get(const mx_p4est_octree *P, const mx_halo *H, int st, mx_patch_leaves *S,
                        long long *sent, long long *largest) {
  memset(S, 0, sizeof *S);
  const int R = P->size;
  /* this rank's leaves, sorted by key (the halo's) */
  const struct {
    const uint64_t *key;
    const mx_pq *const *pq;
    const uint8_t *level;
    size_t n;
  } L = {H->lkey, H->lpq, H->llevel, H->nlocal};
  /* 1. the halo's keys to their owners, grouped by owner (halo order
   * within each: the order the answers come back in) */
  const size_t nh = H->n;
  int *scount = mx_calloc((size_t)(R + 1) * sizeof *scount);
  size_t *first = mx_calloc((size_t)(R + 1) * sizeof *first);
  uint64_t *req = mx_alloc((nh + 1) * sizeof *req);
  uint32_t *slot = mx_alloc((nh + 1) * sizeof *slot); /* request -> halo index */
  if (!st && !(scount && first && req && slot)) st = MX_ENOMEM;
  if (!st) {
    for (size_t i = 0; i < nh; i++) scount[H->owner[i]]++;
    for (int r = 0; r < R; r++) first[r + 1] = first[r] + (size_t)scount[r];
    for (size_t i = 0; i < nh; i++) {
      const size_t k = first[H->owner[i]]++;
      req[k] = H->key[i];
      slot[k] = (uint32_t)i;
    }
  }
  void *rv = NULL;
  int *rcount = NULL, *rdispl = NULL;
  st = mx_exchange(P->comm, st, sizeof *req, req, scount, &rv, &rcount, &rdispl, sent, largest);
  mx_free(req);
  /* 2. the owners answer: each asked leaf's data, then its triangles */
  size_t nasked = 0;
  for (int r = 0; !st && r < R; r++) nasked += (size_t)rcount[r];
  leaf_data *ans = NULL;
  uint32_t *atri = NULL, *at = NULL; /* at: where each asked leaf is in L */
  int *tcount = NULL;
  if (!st) {
    ans = mx_alloc((nasked + 1) * sizeof *ans);
    at = mx_alloc((nasked + 1) * sizeof *at);
    tcount = mx_calloc((size_t)(R + 1) * sizeof *tcount);
    if (!ans || !at || !tcount) st = MX_ENOMEM;
  }
  uint64_t ntri_out = 0;
  const uint64_t *asked = rv;
  for (int r = 0; !st && r < R; r++)
    for (int k = rdispl[r]; k < rdispl[r] + rcount[r]; k++) {
      leaf_data *a = &ans[k];
      memset(a, 0, sizeof *a);
      a->key = asked[k];
      const uint32_t j = mx_find_u64(L.key, L.n, asked[k]);
      at[k] = j;
      if (j == UINT32_MAX) {
        a->level = 255; /* not ours: reported by the asking rank */
        continue;
      }
      const mx_pq *d = L.pq[j];
      a->level = L.level[j];
      a->flags = d->flags;
      a->target = d->target;
      a->rmeet = d->rmeet;
      a->rin = d->rin;
      a->tri_cnt = d->tri_cnt;
      tcount[r] += (int)d->tri_cnt;
      ntri_out += d->tri_cnt;
    }
  if (!st && ntri_out > (uint64_t)INT32_MAX) st = MX_ENOMEM;
  if (!st) {
    atri = mx_alloc((ntri_out + 1) * sizeof *atri);
    if (!atri) st = MX_ENOMEM;
  }
  if (!st) {
    size_t w = 0;
    for (size_t k = 0; k < nasked; k++) {
      if (ans[k].level == 255) continue;
      const mx_pq *d = L.pq[at[k]];
      memcpy(atri + w, P->pool + d->tri_off, (size_t)d->tri_cnt * sizeof *atri);
      w += d->tri_cnt;
    }
  }
  mx_free(rv);
  void *dv = NULL, *tv = NULL;
  int *dcount = NULL, *ddispl = NULL, *tc = NULL, *td = NULL;
  st = mx_exchange(P->comm, st, sizeof *ans, ans, rcount, &dv, &dcount, &ddispl, sent, largest);
  st = mx_exchange(P->comm, st, sizeof *atri, atri, tcount, &tv, &tc, &td, sent, largest);
  mx_free(ans);
  mx_free(at);
  mx_free(atri);
  mx_free(rcount);
  mx_free(rdispl);
  mx_free(tcount);
  /* 3. the patch: this rank's leaves and the halo's, sorted by key */
  const leaf_data *got = dv;
  const uint32_t *gtri = tv;
  const size_t n = L.n + nh;
  uint64_t *toff = NULL; /* per halo leaf: where its triangles start in gtri */
  uint64_t ntri = 0;
  if (!st) {
    toff = mx_alloc((nh + 1) * sizeof *toff);
    if (!toff) st = MX_ENOMEM;
  }
  for (size_t k = 0; !st && k < nh; k++) {
    /* the answers come back per owner in the order asked: request k */
    const leaf_data *g = &got[k];
    const size_t i = slot[k];
    if (g->level == 255 || g->key != H->key[i] || g->level != H->level[i]) {
      mx_error(NULL, 0, "internal: rank %d does not hold the leaf of key %llu level %d that "
                        "its halo names", H->owner[i], (unsigned long long)H->key[i],
               H->level[i]);
      st = MX_EINTERNAL;
      break;
    }
    toff[i] = ntri;
    ntri += g->tri_cnt;
  }
  /* the halo's triangles start where this rank's end */
  uint64_t nlocal_tri = 0;
  for (size_t j = 0; !st && j < L.n; j++) nlocal_tri += L.pq[j]->tri_cnt;
  uint32_t *perm = NULL;
  if (!st) {
    S->key = mx_alloc((n + 1) * sizeof *S->key);
    S->level = mx_alloc(n + 1);
    S->owner = mx_alloc((n + 1) * sizeof *S->owner);
    S->pq = mx_alloc((n + 1) * sizeof *S->pq);
    S->tri = mx_alloc((nlocal_tri + ntri + 1) * sizeof *S->tri);
    perm = mx_alloc((n + 1) * sizeof *perm);
    if (!S->key || !S->level || !S->owner || !S->pq || !S->tri || !perm) st = MX_ENOMEM;
  }
  mx_pq *pq = NULL;
  if (!st) {
    pq = mx_alloc((n + 1) * sizeof *pq);
    if (!pq) st = MX_ENOMEM;
  }
  if (!st) {
    /* the data in this rank's order (its leaves, then the halo's), the
     * triangles copied as they come */
    uint64_t w = 0;
    for (size_t j = 0; j < L.n; j++) {
      const mx_pq *d = L.pq[j];
      pq[j] = *d;
      pq[j].tri_off = w;
      memcpy(S->tri + w, P->pool + d->tri_off, (size_t)d->tri_cnt * sizeof *S->tri);
      w += d->tri_cnt;
    }
    if (ntri) memcpy(S->tri + w, gtri, ntri * sizeof *S->tri);
    for (size_t k = 0; k < nh; k++) {
      const leaf_data *g = &got[k];
      mx_pq *d = &pq[L.n + slot[k]];
      memset(d, 0, sizeof *d);
      d->tri_off = w + toff[slot[k]];
      d->tri_cnt = g->tri_cnt;
      d->flags = g->flags;
      d->target = g->target;
      d->rmeet = g->rmeet;
      d->rin = g->rin;
    }
    /* this rank's leaves come sorted: the halo's sorted (perm), then the
     * two merged (perm then indexes pq: this rank's, then the halo's) */
    memcpy(S->key, H->key, nh * sizeof *S->key);
    for (size_t k = 0; k < nh; k++) perm[k] = (uint32_t)k;
    st = mx_sort_u64(S->key, perm, nh);
  }
  if (!st) {
    uint64_t *hk = mx_alloc((nh + 1) * sizeof *hk);
    uint32_t *hp = mx_alloc((nh + 1) * sizeof *hp);
    if (!hk || !hp) st = MX_ENOMEM;
    if (!st) {
      memcpy(hk, S->key, nh * sizeof *hk);
      memcpy(hp, perm, nh * sizeof *hp);
      size_t i = 0, j = 0;
      for (size_t k = 0; k < n; k++)
        if (j == nh || (i < L.n && L.key[i] < hk[j])) {
          S->key[k] = L.key[i];
          perm[k] = (uint32_t)i++;
        } else {
          S->key[k] = hk[j];
          perm[k] = (uint32_t)(L.n + hp[j++]);
        }
    }
    mx_free(hk);
    mx_free(hp);
  }
  if (!st) {
    for (size_t i = 0; i < n; i++) {
      const size_t j = perm[i];
      S->level[i] = j < L.n ? L.level[j] : H->level[j - L.n];
      S->owner[i] = j < L.n ? P->rank : H->owner[j - L.n];
      S->pq[i] = pq[j];
    }
    S->n = n;
    S->ncore = L.n;
    S->ntri = nlocal_tri + ntri;
  }
  mx_free(pq);
  mx_free(perm);
  mx_free(toff);
  mx_free(dv);
  mx_free(dcount);
  mx_free(ddispl);
  mx_free(tv);
  mx_free(tc);
  mx_free(td);
  mx_free(scount);
  mx_free(first);
  mx_free(slot);
  if (st) mx_patch_leaves_free(S);
  return st;
}

/* ---- the octree --------------------------------------------------------- */

static inline uint64_t level_mask(int l) { return ~(uint64_t)0 << (3 * (MX_MAX_LEVEL - l)); }

/* The edge infos of level l + 1: the children of the split octants
 * [o0, o1) of level l (nchild of them), family by family. A family adds at
 * most 18 edges per axis, so each parallel chunk of families is given that
 * much room; the tables start at 1.5 edges per child and axis (the cortex's
 * patches have 1.3) and grow by what the families so far made per family,
 * instead of being sized for 4 per child (5x the memory to clear). */
static int register_families(mx_edges *E, const mx_octree *T, size_t o0, size_t o1, int l,
                             size_t nchild) {
  MX_CHECK(mx_edges_reserve(E, l + 1, nchild + nchild / 2 + 1024));
  for (size_t lo = o0; lo < o1;) {
    size_t room = SIZE_MAX, made = 0;
    for (int a = 0; a < 3; a++) {
      const mx_edge_table *t = &E->t[l + 1][a];
      const size_t lim = (size_t)(0.75 * (double)t->cap);
      const size_t r = lim > t->count ? lim - t->count : 0;
      if (r < room) room = r;
      if (t->count > made) made = t->count;
    }
    size_t chunk = room / 18;
    if (chunk > o1 - lo) chunk = o1 - lo;
    if (chunk < 1024 && chunk < o1 - lo) {
      const size_t done = lo - o0, rest = o1 - lo;
      const double rate = done ? (double)made / (double)done : 18.0;
      MX_CHECK(mx_edges_reserve(E, l + 1, (size_t)(1.25 * rate * (double)rest) + 18 * 1024));
      continue;
    }
    size_t created[3] = {0, 0, 0};
#pragma omp parallel
    {
      size_t mine[3] = {0, 0, 0};
#pragma omp for schedule(static)
      for (size_t o = lo; o < lo + chunk; o++)
        if (T->flags[o] & MX_OCT_SPLIT)
          mx_edges_register_children(E, T->child0[o], T->kept[o], T->key[o], l, mine);
#pragma omp critical
      for (int a = 0; a < 3; a++) created[a] += mine[a];
    }
    mx_edges_add_count(E, l + 1, created);
    lo += chunk;
  }
  return MX_OK;
}

int mx_patch_tree_build(mx_mesher *m, const mx_patch_leaves *S) {
  mx_tree_clear(m);
  MX_CHECK(mx_mesher_assemble_inputs(m));
  const mx_requests req = mx_mesher_requests(m); /* none: the caller cleared them */
  int st = mx_builder_init(&m->B, &m->soup, m->nt_domain, m->region_t0, &req, 1,
                           m->ndomain ? m->domain_name[0] : NULL);
  if (st) {
    mx_builder_free(&m->B);
    return st;
  }
  m->have_tree = 1;
  MX_CHECK(mx_mesher_domain_side(m, &m->B));
  const size_t n = S->n;
  int top = 0;
  for (size_t i = 0; i < n; i++)
    if (S->level[i] > top) top = S->level[i];
  /* octants per level: the distinct ancestors of the leaves as deep */
  size_t first[MX_MAX_LEVEL + 2];
  first[0] = 0;
  for (int l = 0; l <= top; l++) {
    const uint64_t mk = level_mask(l);
    size_t c = 0;
    uint64_t prev = 0;
    for (size_t i = 0; i < n; i++) {
      if (S->level[i] < l) continue;
      const uint64_t a = S->key[i] & mk;
      if (c == 0 || a != prev) c++;
      prev = a;
    }
    first[l + 1] = first[l] + c;
  }
  const size_t no = first[top + 1];
  if (no >= (size_t)MX_NONE) {
    mx_error(NULL, 0, "too many octants (more than 2^32)");
    return MX_EINPUT;
  }
  mx_octree *T = &m->B.tree.oct;
  MX_CHECK(mx_octree_reserve(T, no, S->ntri));
  uint32_t *leaves = mx_alloc((n + 1) * sizeof *leaves);
  if (!leaves) return MX_ENOMEM;
  /* each level in key order; a leaf's octant takes its data */
  for (int l = 0; l <= top; l++) {
    const uint64_t mk = level_mask(l);
    size_t o = first[l];
    int have = 0;
    for (size_t i = 0; i < n; i++) {
      if (S->level[i] < l) continue;
      const uint64_t a = S->key[i] & mk;
      if (have && a == T->key[o - 1]) continue;
      have = 1;
      T->key[o] = a;
      T->level[o] = (uint8_t)l;
      T->kept[o] = 0;
      T->parent[o] = MX_NONE;
      T->child0[o] = MX_NONE;
      if (S->level[i] == l) { /* the leaf itself (no leaf descends from it) */
        const mx_pq *d = &S->pq[i];
        T->flags[o] = (d->flags & MX_PQ_SURFACE) ? MX_OCT_SURFACE : 0;
        T->target[o] = d->target;
        T->rmeet[o] = d->rmeet;
        T->rin[o] = d->rin;
        T->tri_off[o] = d->tri_off;
        T->tri_cnt[o] = d->tri_cnt;
        leaves[i] = (uint32_t)o;
      } else {
        T->flags[o] = MX_OCT_SPLIT;
        T->target[o] = (uint8_t)(l + 1);
        T->rmeet[o] = T->rin[o] = 0;
        T->tri_off[o] = 0;
        T->tri_cnt[o] = 0;
      }
      o++;
    }
  }
  /* parents: a merge walk of each level with the one above; then the
   * split octants' surface flag and regions from their children, deepest
   * level first */
  for (int l = 1; l <= top; l++) {
    const uint64_t mk = level_mask(l - 1);
    size_t p = first[l - 1];
    for (size_t o = first[l]; o < first[l + 1]; o++) {
      const uint64_t a = T->key[o] & mk;
      while (T->key[p] != a) p++; /* every octant's parent is there */
      T->parent[o] = (uint32_t)p;
      if (T->child0[p] == MX_NONE) T->child0[p] = (uint32_t)o;
      T->kept[p] |= (uint8_t)(1u << mx_morton_child_id(T->key[o], l));
    }
  }
  for (int l = top; l >= 1; l--)
    for (size_t o = first[l]; o < first[l + 1]; o++) {
      const uint32_t p = T->parent[o];
      T->flags[p] |= T->flags[o] & MX_OCT_SURFACE;
      T->rmeet[p] |= T->rmeet[o];
    }
  T->n = no;
  if (S->ntri) memcpy(T->tri_pool, S->tri, S->ntri * sizeof *T->tri_pool);
  T->tri_n = S->ntri;
  m->leaves = leaves;
  m->nleaves = n;
  /* edge infos for every level with a split octant, as the refinement
   * keeps them: the roots', then each split octant's children's at once
   * (mx_edges_register_children: the 54 edges of a family looked up once
   * each), level by level, in key order */
  mx_tree *tr = &m->B.tree;
  tr->use_edges = 1;
  tr->edge_levels = top - 1;
  tr->edge_lazy_top = -1;
  if (top - 1 >= 0) {
    MX_CHECK(mx_edges_reserve(&tr->edges, 0, 4 * (first[1] - first[0]) + 16));
    size_t created[3] = {0, 0, 0};
    for (size_t o = first[0]; o < first[1]; o++)
      mx_edges_register(&tr->edges, (uint32_t)o, T->key[o], 0, created);
    mx_edges_add_count(&tr->edges, 0, created);
  }
  for (int l = 0; l + 1 <= top - 1; l++)
    MX_CHECK(register_families(&tr->edges, T, first[l], first[l + 1], l,
                               first[l + 2] - first[l + 1]));
  return MX_OK;
}
