#include "kernels/mesh_edit.h"

#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

#include "base/common.h"
#include "geom/quality.h"
#include "soa/mesh.h"
#include "base/scan.h"

static int cmp_u32(const void *a, const void *b) {
  const uint32_t x = *(const uint32_t *)a, y = *(const uint32_t *)b;
  return (x > y) - (x < y);
}

/* Elements with a marked node, in increasing order: one pass over the
 * elements sets a bit per element (each block of IB elements its own
 * words), then the bits are counted per block, prefix-summed and listed. */
static int marked_cells(const mx_mesh *M, const uint8_t *mark, uint32_t **list, size_t *n) {
  const size_t nc = M->ncells;
  enum { IB = 1 << 14 };
  const size_t nb = (nc + IB - 1) / IB, nw = (nc + 63) / 64;
  uint64_t *boff = mx_alloc((nb + 1) * sizeof *boff);
  uint64_t *bits = mx_alloc((nw + 1) * sizeof *bits);
  if (!boff || !bits) {
    mx_free(boff);
    mx_free(bits);
    return MX_ENOMEM;
  }
#pragma omp parallel for schedule(static)
  for (size_t b = 0; b < nb; b++) {
    uint64_t k = 0;
    for (size_t w = b * (IB / 64); w < nw && w < (b + 1) * (IB / 64); w++) {
      uint64_t word = 0;
      for (size_t c = 64 * w; c < nc && c < 64 * (w + 1); c++) {
        int any = 0;
        for (int i = 0; i < mx_cell_nodes[M->type[c]]; i++) any |= mark[M->conn[8 * c + i]];
        word |= (uint64_t)(any != 0) << (c & 63);
      }
      bits[w] = word;
      k += (uint64_t)__builtin_popcountll(word);
    }
    boff[b] = k;
  }
  const uint64_t total = mx_scan_u64(boff, nb);
  uint32_t *cl = mx_alloc((total + 1) * sizeof *cl);
  if (!cl) {
    mx_free(boff);
    mx_free(bits);
    return MX_ENOMEM;
  }
#pragma omp parallel for schedule(static)
  for (size_t b = 0; b < nb; b++) {
    uint64_t k = boff[b];
    for (size_t w = b * (IB / 64); w < nw && w < (b + 1) * (IB / 64); w++)
      for (uint64_t word = bits[w]; word; word &= word - 1)
        cl[k++] = (uint32_t)(64 * w + (size_t)__builtin_ctzll(word));
  }
  mx_free(boff);
  mx_free(bits);
  *list = cl;
  *n = (size_t)total;
  return MX_OK;
}

int mx_mesh_incidence_band(const mx_mesh *M, const uint8_t *mark, uint64_t **off_out,
                           uint32_t **inc_out, uint32_t **band_out, size_t *nband,
                           uint32_t **pos_out) {
  const size_t nn = M->nnodes;
  *off_out = NULL;
  *inc_out = NULL;
  /* the elements of the marked nodes first (the band): the counts and the
   * fill walk those only */
  uint32_t *cl = NULL;
  size_t ncl = 0;
  int st = marked_cells(M, mark, &cl, &ncl);
  if (st) return st;
  uint64_t *off = mx_calloc((nn + 1) * sizeof *off);
  if (!off) {
    mx_free(cl);
    return MX_ENOMEM;
  }
  /* count, prefix sum, fill (off[v] the cursor: it ends at v's end, that
   * is v + 1's start, and moves up one place), then sort each list (the
   * fill order depends on the threads) */
#pragma omp parallel for schedule(static)
  for (size_t i = 0; i < ncl; i++) {
    const size_t c = cl[i];
    for (int k = 0; k < mx_cell_nodes[M->type[c]]; k++) {
      const uint32_t v = M->conn[8 * c + k];
      if (mark[v]) __atomic_fetch_add(&off[v], 1, __ATOMIC_RELAXED);
    }
  }
  const uint64_t total = mx_scan_u64(off, nn);
  off[nn] = total;
  /* the band positions when asked (the band is in element order: sorted
   * positions are sorted elements), else the elements */
  uint32_t *inc = mx_alloc((total + 1) * sizeof *inc);
  uint32_t *pos = pos_out ? mx_alloc((total + 1) * sizeof *pos) : NULL;
  if (!inc || (pos_out && !pos)) {
    mx_free(inc);
    mx_free(pos);
    mx_free(off);
    mx_free(cl);
    return MX_ENOMEM;
  }
  uint32_t *fill = pos ? pos : inc;
#pragma omp parallel for schedule(static)
  for (size_t i = 0; i < ncl; i++) {
    const size_t c = cl[i];
    for (int k = 0; k < mx_cell_nodes[M->type[c]]; k++) {
      const uint32_t v = M->conn[8 * c + k];
      if (mark[v])
        fill[__atomic_fetch_add(&off[v], 1, __ATOMIC_RELAXED)] = pos ? (uint32_t)i : (uint32_t)c;
    }
  }
  memmove(off + 1, off, nn * sizeof *off);
  off[0] = 0;
#pragma omp parallel for schedule(dynamic, 1024)
  for (size_t v = 0; v < nn; v++)
    if (off[v + 1] - off[v] > 1) qsort(fill + off[v], off[v + 1] - off[v], sizeof *fill, cmp_u32);
  if (pos) {
#pragma omp parallel for schedule(static)
    for (size_t e = 0; e < total; e++) inc[e] = cl[pos[e]];
  }
  if (band_out) {
    *band_out = cl;
    *nband = ncl;
  } else {
    mx_free(cl);
  }
  if (pos_out) *pos_out = pos;
  *off_out = off;
  *inc_out = inc;
  return MX_OK;
}

int mx_mesh_incidence(const mx_mesh *M, const uint8_t *mark, uint64_t **off_out,
                      uint32_t **inc_out) {
  return mx_mesh_incidence_band(M, mark, off_out, inc_out, NULL, NULL, NULL);
}

int mx_mesh_grow_cells(mx_mesh *M, size_t n) {
  uint8_t *type = mx_realloc(M->type, n + 1);
  if (type) M->type = type;
  uint8_t *level = type ? mx_realloc(M->level, n + 1) : NULL;
  if (level) M->level = level;
  uint32_t *conn = level ? mx_realloc(M->conn, (8 * n + 1) * sizeof *conn) : NULL;
  if (conn) M->conn = conn;
  uint32_t *leaf = conn ? mx_realloc(M->leaf, (n + 1) * sizeof *leaf) : NULL;
  if (leaf) M->leaf = leaf;
  float *jens = leaf ? mx_realloc(M->jens, (n + 1) * sizeof *jens) : NULL;
  if (jens) M->jens = jens;
  return jens ? MX_OK : MX_ENOMEM;
}

int mx_mesh_keep_cells(mx_mesh *M, const uint8_t *keep) {
  const size_t nc = M->ncells;
  uint64_t *dst = mx_alloc((nc + 1) * sizeof *dst);
  if (!dst) return MX_ENOMEM;
#pragma omp parallel for schedule(static)
  for (size_t c = 0; c < nc; c++) dst[c] = keep[c] != 0;
  const uint64_t nk = mx_scan_u64(dst, nc);
  uint8_t *type = mx_alloc(nk + 1);
  uint32_t *conn = mx_alloc((8 * nk + 1) * sizeof *conn);
  uint8_t *level = mx_alloc((nk + 1) * sizeof *level);
  uint32_t *leaf = mx_alloc((nk + 1) * sizeof *leaf);
  float *jens = mx_alloc((nk + 1) * sizeof *jens);
  if (!type || !conn || !level || !leaf || !jens) {
    mx_free(type); mx_free(conn); mx_free(level); mx_free(leaf); mx_free(jens);
    mx_free(dst);
    return MX_ENOMEM;
  }
#pragma omp parallel for schedule(static)
  for (size_t c = 0; c < nc; c++) {
    if (!keep[c]) continue;
    const uint64_t w = dst[c];
    type[w] = M->type[c];
    memcpy(conn + 8 * w, M->conn + 8 * c, 8 * sizeof *conn);
    level[w] = M->level[c];
    leaf[w] = M->leaf[c];
    jens[w] = M->jens[c];
  }
  mx_free(dst);
  mx_free(M->type); mx_free(M->conn); mx_free(M->level); mx_free(M->leaf); mx_free(M->jens);
  M->type = type; M->conn = conn; M->level = level; M->leaf = leaf; M->jens = jens;
  M->ncells = nk;
  return MX_OK;
}

int mx_mesh_apply_node_ids(mx_mesh *M, uint8_t **states, const uint32_t *newid,
                           size_t nu) {
  double *xyz = mx_alloc((3 * nu + 3) * sizeof *xyz);
  uint8_t *st2 = states ? mx_alloc(nu + 1) : NULL;
  uint64_t *nkey = M->nkey ? mx_alloc((nu + 1) * sizeof *nkey) : NULL;
  if (!xyz || (states && !st2) || (M->nkey && !nkey)) {
    mx_free(xyz); mx_free(st2); mx_free(nkey);
    return MX_ENOMEM;
  }
#pragma omp parallel for schedule(static)
  for (size_t v = 0; v < M->nnodes; v++) {
    const uint32_t w = newid[v];
    if (w == UINT32_MAX) continue;
    memcpy(xyz + 3 * (size_t)w, M->xyz + 3 * v, 3 * sizeof *xyz);
    if (st2) st2[w] = (*states)[v];
    if (nkey) nkey[w] = M->nkey[v];
  }
#pragma omp parallel for schedule(static)
  for (size_t c = 0; c < M->ncells; c++)
    for (int k = 0; k < mx_cell_nodes[M->type[c]]; k++)
      M->conn[8 * c + k] = newid[M->conn[8 * c + k]];
  mx_free(M->xyz);
  M->xyz = xyz;
  mx_free(M->nkey);
  M->nkey = nkey;
  M->nnodes = nu;
  if (states) {
    mx_free(*states);
    *states = st2;
  }
  return MX_OK;
}

/* mx_mesh_apply_node_ids for ids that keep the order (newid[v] <= v,
 * rising; mx_mesh_drop_unused_nodes): the node arrays are compacted in
 * place, front to back. Serial on purpose: a parallel pass
 * would write where another thread still reads, and the copy into fresh
 * arrays it replaces took 0.036 s on 1 thread but 0.10-0.17 s on 2 at
 * cortex -s 9 (the page faults of 86 MB of fresh memory taken by two
 * threads at once); this pass reads and writes memory already mapped. */
static void compact_nodes(mx_mesh *M, uint8_t **states, const uint32_t *newid, size_t nu) {
  uint8_t *st = states ? *states : NULL;
  for (size_t v = 0; v < M->nnodes; v++) {
    const uint32_t w = newid[v];
    if (w == UINT32_MAX || w == v) continue;
    memcpy(M->xyz + 3 * (size_t)w, M->xyz + 3 * v, 3 * sizeof *M->xyz);
    if (st) st[w] = st[v];
    if (M->nkey) M->nkey[w] = M->nkey[v];
  }
#pragma omp parallel for schedule(static)
  for (size_t c = 0; c < M->ncells; c++)
    for (int k = 0; k < mx_cell_nodes[M->type[c]]; k++)
      M->conn[8 * c + k] = newid[M->conn[8 * c + k]];
  M->nnodes = nu; /* the arrays keep their room (a later growth reallocates) */
}

int mx_mesh_drop_nodes(mx_mesh *M, uint8_t **states, const uint8_t *used,
                       uint32_t **newid_out) {
  const size_t nn = M->nnodes;
  uint64_t *id = mx_alloc((nn + 1) * sizeof *id);
  uint32_t *newid = mx_alloc((nn + 1) * sizeof *newid);
  if (!id || !newid) {
    mx_free(id); mx_free(newid);
    return MX_ENOMEM;
  }
#pragma omp parallel for schedule(static)
  for (size_t v = 0; v < nn; v++) {
    id[v] = used[v] != 0;
    newid[v] = used[v] ? 0 : UINT32_MAX;
  }
  const uint64_t nu = mx_scan_u64(id, nn); /* new ids, in order */
#pragma omp parallel for schedule(static)
  for (size_t v = 0; v < nn; v++)
    if (!newid[v]) newid[v] = (uint32_t)id[v];
  mx_free(id);
  compact_nodes(M, states, newid, (size_t)nu);
  if (!newid_out)
    mx_free(newid);
  else
    *newid_out = newid;
  return MX_OK;
}

int mx_mesh_drop_unused_nodes(mx_mesh *M, uint8_t **states, uint32_t **newid_out) {
  uint8_t *used = mx_calloc(M->nnodes + 1);
  if (!used) return MX_ENOMEM;
#pragma omp parallel for schedule(static)
  for (size_t c = 0; c < M->ncells; c++)
    for (int k = 0; k < mx_cell_nodes[M->type[c]]; k++)
      __atomic_store_n(&used[M->conn[8 * c + k]], 1, __ATOMIC_RELAXED);
  const int st = mx_mesh_drop_nodes(M, states, used, newid_out);
  mx_free(used);
  return st;
}

void mx_mesh_summarize(mx_mesh *M) {
  size_t bt[4] = {0, 0, 0, 0}, invalid = 0;
  double jmin = INFINITY;
#pragma omp parallel for schedule(static) reduction(+ : bt[:4], invalid) reduction(min : jmin)
  for (size_t c = 0; c < M->ncells; c++) {
    bt[M->type[c]]++;
    invalid += mx_jens_invalid(M->jens[c]);
    if (M->jens[c] < jmin) jmin = M->jens[c];
  }
  memcpy(M->by_type, bt, sizeof bt);
  M->invalid = invalid;
  M->jens_min = M->ncells ? jmin : 1.0;
}

void mx_mesh_update_jens(mx_mesh *M, const uint8_t *moved) {
#pragma omp parallel for schedule(static)
  for (size_t c = 0; c < M->ncells; c++) {
    const int nv = mx_cell_nodes[M->type[c]];
    int mv = moved == NULL;
    for (int k = 0; k < nv && !mv; k++) mv = moved[M->conn[8 * c + k]] != 0;
    if (!mv) continue;
    double x[8][3];
    for (int k = 0; k < nv; k++)
      memcpy(x[k], M->xyz + 3 * (size_t)M->conn[8 * c + k], sizeof x[k]);
    M->jens[c] = (float)mx_jens(M->type[c], x);
  }
}

static int cmp_u64(const void *a, const void *b) {
  const uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
  return (x > y) - (x < y);
}

/* Element c of src becomes element w of dst (the per-element arrays). */
static inline void cell_copy(mx_mesh *dst, size_t w, const mx_mesh *src, size_t c) {
  dst->type[w] = src->type[c];
  dst->level[w] = src->level[c];
  dst->leaf[w] = src->leaf[c];
  dst->jens[w] = src->jens[c];
  memcpy(dst->conn + 8 * w, src->conn + 8 * c, 8 * sizeof *dst->conn);
}

/* Per-element arrays for n elements, to hold elements aside. */
static int cells_alloc(mx_mesh *B, size_t n) {
  memset(B, 0, sizeof *B);
  B->type = mx_alloc(n + 1);
  B->level = mx_alloc(n + 1);
  B->leaf = mx_alloc((n + 1) * sizeof *B->leaf);
  B->jens = mx_alloc((n + 1) * sizeof *B->jens);
  B->conn = mx_alloc((8 * n + 1) * sizeof *B->conn);
  return B->type && B->level && B->leaf && B->jens && B->conn ? MX_OK : MX_ENOMEM;
}

/* When the elements are in leaf order but for a short tail (the staircase
 * appends the few elements it restores), the tail is sorted apart and merged
 * in place: no second copy of the mesh. Returns MX_OK, or 1 when the general
 * sort is needed. */
static int merge_short_tail(mx_mesh *M, size_t p) {
  const size_t n = M->ncells, k = n - p;
  if (k > 4096 || k > n / 16) return 1;
  /* The prefix moves in parallel chunks, each from its back: a chunk
   * writes at most k places past its end, into the next chunk's first k
   * elements, which that chunk saved before anyone wrote. */
  const size_t nch = 4 * (size_t)omp_get_max_threads();
  const size_t csz = (p + nch - 1) / nch;
  const size_t save = k < csz ? k : csz;
  uint64_t *ord = mx_alloc((k + 1) * sizeof *ord); /* leaf << 32 | element, then ins */
  mx_mesh tail, saved;
  memset(&saved, 0, sizeof saved);
  int st = cells_alloc(&tail, k);
  if (!st) st = cells_alloc(&saved, nch * save);
  if (!st && !ord) st = MX_ENOMEM;
  if (!st) {
    /* the tail in (leaf, index) order: stable by leaf */
    for (size_t i = 0; i < k; i++) ord[i] = (uint64_t)M->leaf[p + i] << 32 | (p + i);
    qsort(ord, k, sizeof *ord, cmp_u64);
    for (size_t i = 0; i < k; i++) cell_copy(&tail, i, M, (size_t)(ord[i] & 0xffffffffu));
    /* ins[t]: the prefix elements before tail element t (those of a leaf
     * up to its own: after the prefix's elements of the same leaf, as a
     * stable sort puts it); prefix element i moves right by the number of
     * tail elements with ins <= i, tail element t goes to ins[t] + t. */
    uint64_t *ins = ord;
    for (size_t t = 0; t < k; t++) {
      size_t lo = 0, hi = p;
      while (lo < hi) {
        const size_t mid = lo + (hi - lo) / 2;
        if (M->leaf[mid] <= tail.leaf[t]) lo = mid + 1;
        else hi = mid;
      }
      ins[t] = lo;
    }
#pragma omp parallel
    {
#pragma omp for schedule(static, 1)
      for (size_t c = 0; c < nch; c++) {
        const size_t cs = c * csz, ce = cs + csz < p ? cs + csz : p;
        for (size_t i = cs; i < ce && i < cs + save; i++) cell_copy(&saved, c * save + (i - cs), M, i);
      }
#pragma omp for schedule(static, 1)
      for (size_t c = 0; c < nch; c++) {
        const size_t cs = c * csz, ce = cs + csz < p ? cs + csz : p;
        if (cs >= ce) continue;
        size_t j = 0; /* tail elements with ins <= i */
        while (j < k && ins[j] <= ce - 1) j++;
        for (size_t i = ce; i-- > cs;) {
          while (j > 0 && ins[j - 1] > i) j--;
          if (j == 0) break; /* this element and those before it stay */
          if (i < cs + save) cell_copy(M, i + j, &saved, c * save + (i - cs));
          else cell_copy(M, i + j, M, i);
        }
      }
    }
    for (size_t t = 0; t < k; t++) cell_copy(M, ins[t] + t, &tail, t);
  }
  mx_free(ord);
  mx_mesh_free(&tail);
  mx_mesh_free(&saved);
  return st;
}

int mx_mesh_sort_by_leaf(mx_mesh *M, size_t nleaves) {
  const size_t n = M->ncells;
  size_t bad = 0, first = n;
#pragma omp parallel for schedule(static) reduction(+ : bad) reduction(min : first)
  for (size_t c = 1; c < n; c++)
    if (M->leaf[c] < M->leaf[c - 1]) {
      bad++;
      if (c < first) first = c;
    }
  if (bad == 0) return MX_OK;
  const int merged = merge_short_tail(M, first);
  if (merged != 1) return merged;
  uint64_t *start = mx_calloc((nleaves + 1) * sizeof *start);
  uint32_t *perm = mx_alloc((n + 1) * sizeof *perm);
  uint8_t *type = mx_alloc(n + 1);
  uint32_t *conn = mx_alloc((8 * n + 1) * sizeof *conn);
  uint8_t *level = mx_alloc((n + 1) * sizeof *level);
  uint32_t *leaf = mx_alloc((n + 1) * sizeof *leaf);
  float *jens = mx_alloc((n + 1) * sizeof *jens);
  if (!start || !perm || !type || !conn || !level || !leaf || !jens) {
    mx_free(start); mx_free(perm); mx_free(type); mx_free(conn);
    mx_free(level); mx_free(leaf); mx_free(jens);
    return MX_ENOMEM;
  }
  for (size_t c = 0; c < n; c++) start[M->leaf[c] + 1]++;
  for (size_t l = 0; l < nleaves; l++) start[l + 1] += start[l];
  for (size_t c = 0; c < n; c++) perm[start[M->leaf[c]]++] = (uint32_t)c;
#pragma omp parallel for schedule(static)
  for (size_t w = 0; w < n; w++) {
    const uint32_t c = perm[w];
    type[w] = M->type[c];
    memcpy(conn + 8 * w, M->conn + 8 * (size_t)c, 8 * sizeof *conn);
    level[w] = M->level[c];
    leaf[w] = M->leaf[c];
    jens[w] = M->jens[c];
  }
  mx_free(M->type); mx_free(M->conn); mx_free(M->level); mx_free(M->leaf); mx_free(M->jens);
  M->type = type; M->conn = conn; M->level = level; M->leaf = leaf; M->jens = jens;
  mx_free(start);
  mx_free(perm);
  return MX_OK;
}
