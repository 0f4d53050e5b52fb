/* The halo of a rank, ring by ring (src/mpi/p4est_halo.h). */
#include "mpi/p4est_halo.h"

#include "base/common.h"
#include "mpi/exchange.h"
#include "base/scan.h"

#include <string.h>

#include <p8est_bits.h>
#include <p8est_communication.h>

/* A leaf as sent: its key and level. */
typedef struct {
  uint64_t key;
  uint64_t level;
} leaf_rec;

void mx_halo_free(mx_halo *H) {
  mx_free(H->lkey);
  mx_free(H->llevel);
  mx_free((void *)H->lpq);
  mx_free(H->key);
  mx_free(H->level);
  mx_free(H->owner);
  mx_free(H->known);
  mx_free(H->root_tree);
  mx_free(H->bucket);
  memset(H, 0, sizeof *H);
}

static int halo_reserve(mx_halo *H, size_t n) {
  if (H->n + n <= H->cap) return MX_OK;
  size_t cap = H->cap ? H->cap : 1024;
  while (cap < H->n + n) cap *= 2;
  uint64_t *k = mx_realloc(H->key, cap * sizeof *k);
  if (!k) return MX_ENOMEM;
  H->key = k;
  uint8_t *l = mx_realloc(H->level, cap);
  if (!l) return MX_ENOMEM;
  H->level = l;
  int32_t *o = mx_realloc(H->owner, cap * sizeof *o);
  if (!o) return MX_ENOMEM;
  H->owner = o;
  H->cap = cap;
  return MX_OK;
}

/* known <- known U add (both sorted, disjoint). */
static int merge_known(mx_halo *H, const uint64_t *add, size_t n) {
  uint64_t *m = mx_alloc((H->nknown + n + 1) * sizeof *m);
  if (!m) return MX_ENOMEM;
  size_t i = 0, j = 0, k = 0;
  while (i < H->nknown || j < n)
    m[k++] = (j == n || (i < H->nknown && H->known[i] < add[j])) ? H->known[i++] : add[j++];
  mx_free(H->known);
  H->known = m;
  H->nknown = k;
  return MX_OK;
}

/* H->bucket over the sorted local keys: about one key a bucket (at most
 * 2^22 buckets), covering every key of the grid's lattice. */
static int buckets_build(const mx_p4est_octree *P, mx_halo *H) {
  const int *dims = P->B->tree.grid.dims;
  const uint64_t kmax =
      mx_morton_encode(((uint32_t)dims[0] << MX_MAX_LEVEL) - 1,
                       ((uint32_t)dims[1] << MX_MAX_LEVEL) - 1,
                       ((uint32_t)dims[2] << MX_MAX_LEVEL) - 1);
  size_t want = H->nlocal < ((size_t)1 << 22) ? H->nlocal : ((size_t)1 << 22);
  if (want < 1) want = 1;
  int sh = 0;
  while (sh < 63 && (kmax >> sh) + 1 > want) sh++;
  H->bshift = sh;
  H->nbucket = (size_t)(kmax >> sh) + 1;
  H->bucket = mx_alloc((H->nbucket + 1) * sizeof *H->bucket);
  if (!H->bucket) return MX_ENOMEM;
  size_t i = 0;
  for (size_t b = 0; b <= H->nbucket; b++) {
    while (i < H->nlocal && (H->lkey[i] >> sh) < b) i++;
    H->bucket[b] = (uint32_t)i;
  }
  return MX_OK;
}

int mx_halo_init(const mx_p4est_octree *P, mx_halo *H) {
  memset(H, 0, sizeof *H);
  p8est_t *p8 = P->p8;
  const p8est_ghost_t *G = P->ghost;
  const size_t nq = (size_t)p8->local_num_quadrants, ng = G->ghosts.elem_count;
  const int *dims = P->B->tree.grid.dims;
  const size_t nroots = (size_t)dims[0] * (size_t)dims[1] * (size_t)dims[2];
  H->lkey = mx_alloc((nq + 1) * sizeof *H->lkey);
  H->llevel = mx_alloc(nq + 1);
  H->lpq = mx_alloc((nq + 1) * sizeof *H->lpq);
  const mx_pq **pq = mx_alloc((nq + 1) * sizeof *pq);
  H->root_tree = mx_alloc((nroots + 1) * sizeof *H->root_tree);
  uint8_t *lev = mx_alloc(nq + 1);
  uint32_t *perm = mx_alloc((nq + 1) * sizeof *perm);
  int st = H->lkey && H->llevel && H->lpq && pq && H->root_tree && lev && perm ? MX_OK : MX_ENOMEM;
  if (!st) st = halo_reserve(H, ng + 1);
  size_t n = 0;
  for (p4est_topidx_t t = p8->first_local_tree; !st && t <= p8->last_local_tree; t++) {
    p8est_tree_t *tr = p8est_tree_array_index(p8->trees, t);
    for (size_t i = 0; i < tr->quadrants.elem_count; i++) {
      const p8est_quadrant_t *q = p8est_quadrant_array_index(&tr->quadrants, i);
      if (!mx_pq_kept(q->p.user_data)) continue;
      perm[n] = (uint32_t)n;
      pq[n] = q->p.user_data;
      lev[n] = (uint8_t)q->level;
      H->lkey[n++] = mx_p4est_key(P, t, q);
    }
  }
  if (!st) st = mx_sort_u64(H->lkey, perm, n);
  if (!st)
    for (size_t i = 0; i < n; i++) {
      H->llevel[i] = lev[perm[i]];
      H->lpq[i] = pq[perm[i]];
    }
  H->nlocal = n;
  if (!st) st = buckets_build(P, H);
  mx_free((void *)pq);
  mx_free(lev);
  mx_free(perm);
  if (!st) {
    for (size_t r = 0; r < nroots; r++) H->root_tree[r] = -1;
    for (p4est_topidx_t t = 0; t < P->conn->num_trees; t++) {
      const int32_t *c = P->tree_root + 3 * (size_t)t;
      H->root_tree[(size_t)c[0] + (size_t)dims[0] * ((size_t)c[1] + (size_t)dims[1] * (size_t)c[2])] =
          (int32_t)t;
    }
    /* ring 1: the ghosts in the domain */
    for (int r = 0; r < P->size; r++)
      for (p4est_locidx_t g = G->proc_offsets[r]; g < G->proc_offsets[r + 1]; g++) {
        if (!mx_pq_kept(&P->ghost_data[g])) continue;
        const p8est_quadrant_t *q =
            p8est_quadrant_array_index((sc_array_t *)&G->ghosts, (size_t)g);
        H->key[H->n] = mx_p4est_key(P, q->p.piggy3.which_tree, q);
        H->level[H->n] = (uint8_t)q->level;
        H->owner[H->n++] = r;
      }
    H->ring_start[1] = 0;
    H->ring_start[2] = H->n;
    H->rings = 1;
  }
  uint64_t *ring1 = NULL;
  if (!st) {
    ring1 = mx_alloc((H->n + 1) * sizeof *ring1);
    st = ring1 ? MX_OK : MX_ENOMEM;
  }
  if (!st) {
    memcpy(ring1, H->key, H->n * sizeof *ring1);
    st = mx_sort_u64(ring1, NULL, H->n);
  }
  if (!st) {
    H->known = mx_alloc((n + 1) * sizeof *H->known);
    st = H->known ? MX_OK : MX_ENOMEM;
  }
  if (!st) {
    memcpy(H->known, H->lkey, n * sizeof *H->known);
    H->nknown = n;
    st = merge_known(H, ring1, H->n);
  }
  mx_free(ring1);
  return st;
}

/* The box of (key, level) on the lattice: lowest corner and side. */
static void leaf_box(uint64_t key, int level, uint32_t c[3], uint32_t *s) {
  mx_morton_decode(key, c);
  *s = mx_octant_size(level);
}

/* The lowest corner of neighbour d (0..26, 13 the box itself) of the box
 * (c, s): the same-size box shifted by (d % 3 - 1, d / 3 % 3 - 1, d / 9 - 1)
 * sides; may lie outside the lattice. */
static void neighbour_box(const uint32_t c[3], uint32_t s, int d, int64_t nb[3]) {
  const int off[3] = {d % 3 - 1, d / 3 % 3 - 1, d / 9 - 1};
  for (int a = 0; a < 3; a++) nb[a] = (int64_t)c[a] + off[a] * (int64_t)s;
}

/* The ranks whose part of the curve meets the box at c (lattice) of the
 * given level: [*lo, *hi]; 0 when the box lies outside the root grid. */
static int box_owners(const mx_p4est_octree *P, const mx_halo *H, const int64_t c[3], int level,
                      int *lo, int *hi) {
  const int *dims = P->B->tree.grid.dims;
  int64_t root[3];
  for (int a = 0; a < 3; a++) {
    if (c[a] < 0 || c[a] >= (int64_t)dims[a] << MX_MAX_LEVEL) return 0;
    root[a] = c[a] >> MX_MAX_LEVEL;
  }
  const int32_t t =
      H->root_tree[root[0] + (int64_t)dims[0] * (root[1] + (int64_t)dims[1] * root[2])];
  if (t < 0) return 0;
  const int sh = P8EST_MAXLEVEL - MX_MAX_LEVEL;
  const int64_t mask = ((int64_t)1 << MX_MAX_LEVEL) - 1;
  p8est_quadrant_t q, last;
  memset(&q, 0, sizeof q);
  q.x = (p4est_qcoord_t)((c[0] & mask) << sh);
  q.y = (p4est_qcoord_t)((c[1] & mask) << sh);
  q.z = (p4est_qcoord_t)((c[2] & mask) << sh);
  q.level = (int8_t)level;
  p8est_quadrant_last_descendant(&q, &last, P8EST_QMAXLEVEL);
  *lo = p8est_comm_find_owner(P->p8, t, &q, P->rank);
  *hi = p8est_comm_find_owner(P->p8, t, &last, *lo);
  return 1;
}

static int touch(const uint32_t a[3], uint32_t sa, const uint32_t b[3], uint32_t sb) {
  for (int k = 0; k < 3; k++)
    if ((uint64_t)a[k] > (uint64_t)b[k] + sb || (uint64_t)b[k] > (uint64_t)a[k] + sa) return 0;
  return 1;
}

/* This rank's leaves meeting the box (bc, blevel), which touches the box
 * (c, s) of a leaf of another rank, and touching that box: appended to out
 * (indices into H->lkey; a coarse leaf may come more than once), at most
 * cap. Descends only into the children touching (c, s), so the work is in
 * the leaves found, not in the leaves the box holds. */
static size_t visit(const mx_halo *H, const uint32_t bc[3], int blevel, const uint32_t c[3],
                    uint32_t s, uint32_t *out, size_t n, size_t cap) {
  const uint64_t key = mx_morton_encode(bc[0], bc[1], bc[2]);
  const uint64_t vol = (uint64_t)1 << (3 * (MX_MAX_LEVEL - blevel));
  /* the first local key at or after key: in key's bucket, or the next
   * bucket's first */
  const size_t b = (size_t)(key >> H->bshift);
  size_t lo = b < H->nbucket ? H->bucket[b] : H->nlocal;
  size_t hi = b < H->nbucket ? H->bucket[b + 1] : H->nlocal;
  while (lo < hi) {
    const size_t mid = lo + (hi - lo) / 2;
    if (H->lkey[mid] < key) lo = mid + 1;
    else hi = mid;
  }
  /* a leaf holding the box: starting at its corner, or before */
  if (lo < H->nlocal && H->lkey[lo] == key && H->llevel[lo] <= blevel) {
    if (n < cap) out[n++] = (uint32_t)lo;
    return n;
  }
  if (lo > 0 && H->lkey[lo - 1] + ((uint64_t)1 << (3 * (MX_MAX_LEVEL - H->llevel[lo - 1]))) > key) {
    if (n < cap) out[n++] = (uint32_t)(lo - 1);
    return n;
  }
  if (lo == H->nlocal || H->lkey[lo] >= key + vol || blevel >= MX_MAX_LEVEL) return n;
  const uint32_t h = mx_octant_size(blevel + 1);
  for (int k = 0; k < 8; k++) {
    const uint32_t cc[3] = {bc[0] + (k & 1) * h, bc[1] + (k >> 1 & 1) * h, bc[2] + (k >> 2) * h};
    if (touch(cc, h, c, s)) n = visit(H, cc, blevel + 1, c, s, out, n, cap);
  }
  return n;
}

/* This rank's leaves touching the leaf (key, level) of another rank. */
static size_t local_touching(const mx_halo *H, uint64_t key, int level, uint32_t *out,
                             size_t cap) {
  uint32_t c[3], s;
  leaf_box(key, level, c, &s);
  size_t n = 0;
  for (int d = 0; d < 27; d++) {
    if (d == 13) continue; /* the leaf itself */
    int64_t nb[3];
    neighbour_box(c, s, d, nb);
    if (nb[0] < 0 || nb[1] < 0 || nb[2] < 0 || nb[0] > UINT32_MAX - s || nb[1] > UINT32_MAX - s ||
        nb[2] > UINT32_MAX - s)
      continue;
    const uint32_t bc[3] = {(uint32_t)nb[0], (uint32_t)nb[1], (uint32_t)nb[2]};
    n = visit(H, bc, level, c, s, out, n, cap);
  }
  return n;
}

int mx_halo_expand(const mx_p4est_octree *P, mx_halo *H) {
  const int R = P->size, me = P->rank;
  if (H->rings + 2 >= (int)(sizeof H->ring_start / sizeof *H->ring_start)) return MX_EINTERNAL;
  const size_t f0 = H->ring_start[H->rings], f1 = H->ring_start[H->rings + 1];
  /* 1. the last ring's leaves to the ranks owning a box around them */
  size_t cap = 8 * (f1 - f0) + 1, np = 0;
  uint64_t *pair = mx_alloc(cap * sizeof *pair);
  int st = pair ? MX_OK : MX_ENOMEM;
  for (size_t i = f0; !st && i < f1; i++) {
    uint32_t c[3], s;
    leaf_box(H->key[i], H->level[i], c, &s);
    for (int d = 0; d < 27 && !st; d++) {
      if (d == 13) continue;
      int64_t nb[3];
      neighbour_box(c, s, d, nb);
      int lo, hi;
      if (!box_owners(P, H, nb, H->level[i], &lo, &hi)) continue;
      for (int q = lo; q <= hi && !st; q++) {
        if (q == me) continue;
        if (np == cap) {
          cap *= 2;
          uint64_t *g = mx_realloc(pair, cap * sizeof *g);
          if (!g) {
            st = MX_ENOMEM;
            break;
          }
          pair = g;
        }
        pair[np++] = (uint64_t)(uint32_t)q << 32 | (uint32_t)(i - f0);
      }
    }
  }
  if (!st) np = mx_sort_unique_u64(pair, np, &st);
  leaf_rec *req = mx_alloc((np + 1) * sizeof *req);
  int *scount = mx_calloc((size_t)(R + 1) * sizeof *scount);
  if (!st && (!req || !scount)) st = MX_ENOMEM;
  for (size_t k = 0; !st && k < np; k++) {
    const size_t i = f0 + (uint32_t)pair[k];
    req[k].key = H->key[i];
    req[k].level = H->level[i];
    scount[pair[k] >> 32]++;
  }
  mx_free(pair);
  void *rv = NULL;
  int *rcount = NULL, *rdispl = NULL;
  st = mx_exchange(P->comm, st, sizeof *req, req, scount, &rv, &rcount, &rdispl, &H->sent_bytes,
                   &H->largest_message);
  mx_free(req);
  const leaf_rec *got = rv;
  /* 2. our leaves touching each, per asking rank, unique */
  size_t nans = 0, acap = 0;
  uint64_t *ans = NULL; /* (rank << 32 | local index) */
  uint32_t tmp[27 * 64];
  for (int q = 0; !st && q < R; q++)
    for (int k = 0; k < rcount[q] && !st; k++) {
      const leaf_rec *L = got + rdispl[q] + k;
      const size_t m = local_touching(H, L->key, (int)L->level, tmp, sizeof tmp / sizeof *tmp);
      if (nans + m > acap) {
        acap = 2 * (nans + m) + 1024;
        uint64_t *g = mx_realloc(ans, acap * sizeof *g);
        if (!g) {
          st = MX_ENOMEM;
          break;
        }
        ans = g;
      }
      for (size_t j = 0; j < m; j++) ans[nans++] = (uint64_t)(uint32_t)q << 32 | tmp[j];
    }
  mx_free(rv);
  mx_free(rcount);
  mx_free(rdispl);
  if (!st) nans = mx_sort_unique_u64(ans, nans, &st);
  leaf_rec *reply = mx_alloc((nans + 1) * sizeof *reply);
  if (!st && !reply) st = MX_ENOMEM;
  if (scount) memset(scount, 0, (size_t)R * sizeof *scount);
  for (size_t k = 0; !st && k < nans; k++) {
    const uint32_t i = (uint32_t)ans[k];
    reply[k].key = H->lkey[i];
    reply[k].level = H->llevel[i];
    scount[ans[k] >> 32]++;
  }
  mx_free(ans);
  st = mx_exchange(P->comm, st, sizeof *reply, reply, scount, &rv, &rcount, &rdispl,
                   &H->sent_bytes, &H->largest_message);
  mx_free(reply);
  mx_free(scount);
  got = rv;
  /* 3. the new ones: not known yet, each once */
  size_t nr = 0;
  for (int q = 0; !st && q < R; q++) nr += (size_t)rcount[q];
  uint64_t *nk = NULL;
  uint32_t *perm = NULL;
  int32_t *from = NULL;
  if (!st) {
    nk = mx_alloc((nr + 1) * sizeof *nk);
    perm = mx_alloc((nr + 1) * sizeof *perm);
    from = mx_alloc((nr + 1) * sizeof *from);
    if (!nk || !perm || !from) st = MX_ENOMEM;
  }
  if (!st) {
    size_t k = 0;
    for (int q = 0; q < R; q++)
      for (int j = 0; j < rcount[q]; j++, k++) {
        nk[k] = got[rdispl[q] + j].key;
        perm[k] = (uint32_t)k;
        from[k] = q;
      }
    st = mx_sort_u64(nk, perm, nr);
  }
  if (!st) st = halo_reserve(H, nr);
  size_t nnew = 0;
  if (!st) {
    for (size_t k = 0; k < nr; k++) {
      if (k && nk[k] == nk[k - 1]) continue;
      if (mx_find_u64(H->known, H->nknown, nk[k]) != UINT32_MAX) continue;
      H->key[H->n + nnew] = nk[k];
      H->level[H->n + nnew] = (uint8_t)got[perm[k]].level;
      H->owner[H->n + nnew] = from[perm[k]];
      nk[nnew++] = nk[k]; /* sorted, in place */
    }
    st = merge_known(H, nk, nnew);
  }
  if (!st) {
    H->n += nnew;
    H->rings++;
    H->ring_start[H->rings + 1] = H->n;
  }
  mx_free(nk);
  mx_free(perm);
  mx_free(from);
  mx_free(rv);
  mx_free(rcount);
  mx_free(rdispl);
  MPI_Allreduce(MPI_IN_PLACE, &st, 1, MPI_INT, MPI_MAX, P->comm);
  return st;
}
