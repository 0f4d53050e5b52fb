/* A label image made ready for its interfaces (geom/label_fix.h). The
 * passes walk face-connected parts breadth first from a queue of voxel
 * indices (32 bits: the caller refuses images of 2^32 padded voxels or
 * more), in index order, so the result does not depend on threads; the
 * contacts' detection runs in parallel, their repair in index order. */
#include <string.h>

#include "base/common.h"
#include "geom/label_fix.h"

static int64_t stride(const int64_t n[3], int a) {
  return a == 0 ? 1 : a == 1 ? n[0] : n[0] * n[1];
}

/* Whether voxel v is on the padding. */
static int on_pad(const int64_t n[3], int64_t v) {
  const int64_t i = v % n[0], j = (v / n[0]) % n[1], k = v / (n[0] * n[1]);
  return i == 0 || j == 0 || k == 0 || i == n[0] - 1 || j == n[1] - 1 || k == n[2] - 1;
}

/* The part of label lab[seed] around seed (not yet marked), breadth first
 * into q (marked as it goes); its size. Neighbours of the padding's voxels
 * outside the array are skipped. */
static size_t flood(const int32_t *lab, const int64_t n[3], uint8_t *mark, uint32_t *q,
                    int64_t seed) {
  const int32_t L = lab[seed];
  size_t head = 0, tail = 0;
  q[tail++] = (uint32_t)seed;
  mark[seed] = 1;
  const int64_t total = n[0] * n[1] * n[2];
  while (head < tail) {
    const int64_t v = q[head++];
    const int64_t c[3] = {v % n[0], (v / n[0]) % n[1], v / (n[0] * n[1])};
    for (int a = 0; a < 3; a++)
      for (int s = -1; s <= 1; s += 2) {
        if ((s < 0 && c[a] == 0) || (s > 0 && c[a] == n[a] - 1)) continue;
        const int64_t w = v + s * stride(n, a);
        if (w < 0 || w >= total || mark[w] || lab[w] != L) continue;
        mark[w] = 1;
        q[tail++] = (uint32_t)w;
      }
  }
  return tail;
}

/* The label the outside faces of the part q[0 .. len) meet most (ties: the
 * smaller label); L when none (the part fills the image). */
static int32_t most_met(const int32_t *lab, const int64_t n[3], const uint32_t *q, size_t len) {
  const int32_t L = lab[q[0]];
  enum { K = 16 };
  int32_t key[K];
  size_t cnt[K], nk = 0, other = 0;
  int32_t fallback = L;
  for (size_t t = 0; t < len; t++) {
    const int64_t v = q[t];
    const int64_t c[3] = {v % n[0], (v / n[0]) % n[1], v / (n[0] * n[1])};
    for (int a = 0; a < 3; a++)
      for (int s = -1; s <= 1; s += 2) {
        if ((s < 0 && c[a] == 0) || (s > 0 && c[a] == n[a] - 1)) continue;
        const int32_t M = lab[v + s * stride(n, a)];
        if (M == L) continue;
        size_t k = 0;
        while (k < nk && key[k] != M) k++;
        if (k == nk) {
          if (nk == K) { /* a part meeting more than 16 labels: rare */
            other++;
            if (fallback == L || M < fallback) fallback = M;
            continue;
          }
          key[nk] = M;
          cnt[nk++] = 0;
        }
        cnt[k]++;
      }
  }
  (void)other;
  if (nk == 0) return fallback;
  size_t best = 0;
  for (size_t k = 1; k < nk; k++)
    if (cnt[k] > cnt[best] || (cnt[k] == cnt[best] && key[k] < key[best])) best = k;
  return key[best];
}

int mx_labels_drop_islands(int32_t *lab, const int64_t n[3], size_t min_voxels,
                           mx_label_fix_stats *st) {
  if (min_voxels <= 1) return MX_OK;
  const int64_t total = n[0] * n[1] * n[2];
  uint8_t *mark = mx_calloc((size_t)total);
  uint32_t *q = mx_alloc((size_t)total * sizeof *q);
  if (!mark || !q) {
    mx_free(mark);
    mx_free(q);
    return MX_ENOMEM;
  }
  for (int64_t v = 0; v < total; v++) {
    if (mark[v] || on_pad(n, v)) continue;
    const size_t len = flood(lab, n, mark, q, v);
    if (len >= min_voxels) continue;
    /* the padding's background is never an island */
    int touches_pad = 0;
    for (size_t t = 0; t < len && !touches_pad; t++) touches_pad = on_pad(n, q[t]);
    if (touches_pad) continue;
    const int32_t M = most_met(lab, n, q, len);
    if (M == lab[v]) continue;
    for (size_t t = 0; t < len; t++) lab[q[t]] = M;
    st->island_voxels += len;
    st->islands++;
  }
  mx_free(mark);
  mx_free(q);
  return MX_OK;
}

/* ---- contacts ----------------------------------------------------------
 * The 8 voxels around a vertex, b = dx + 2 dy + 4 dz; face neighbours in
 * the block differ in one bit. */

/* The voxels of mask `in` (a byte of 8 bits) face-connected in the block. */
static int block_connected(unsigned in) {
  if (!in) return 1;
  unsigned seen = in & (~in + 1u), grow = seen; /* the lowest voxel */
  while (grow) {
    unsigned next = 0;
    for (int b = 0; b < 8; b++)
      if (grow & (1u << b))
        for (int a = 0; a < 3; a++) next |= 1u << (b ^ (1 << a));
    next &= in & ~seen;
    seen |= next;
    grow = next;
  }
  return seen == in;
}

/* The four voxels in turn around each of the vertex's 6 lattice edges
 * (the edge along axis a on the side s of the vertex). */
static const uint8_t ring[6][4] = {
    {0, 2, 6, 4}, {1, 3, 7, 5}, /* along x: dx = 0, 1 */
    {0, 1, 5, 4}, {2, 3, 7, 6}, /* along y */
    {0, 1, 3, 2}, {4, 5, 7, 6}, /* along z */
};

static int block_good(const int32_t l[8]) {
  int same = 1;
  for (int b = 1; b < 8 && same; b++) same = l[b] == l[0];
  if (same) return 1;
  for (int e = 0; e < 6; e++) {
    const uint8_t *r = ring[e];
    if (l[r[0]] != l[r[1]] && l[r[1]] != l[r[2]] && l[r[2]] != l[r[3]] && l[r[3]] != l[r[0]])
      return 0;
  }
  unsigned done = 0;
  for (int b = 0; b < 8; b++) {
    if (done & (1u << b)) continue;
    unsigned in = 0;
    for (int c = 0; c < 8; c++)
      if (l[c] == l[b]) in |= 1u << c;
    done |= in;
    if (!block_connected(in) || !block_connected(0xffu & ~in)) return 0;
  }
  return 1;
}

/* The block's voxel indices around the vertex at the far corner of voxel v
 * (the vertex (i+1, j+1, k+1) in corner terms). */
static void block_of(const int64_t n[3], int64_t v, int64_t idx[8]) {
  for (int b = 0; b < 8; b++)
    idx[b] = v + (b & 1) + ((b >> 1) & 1) * n[0] + ((b >> 2) & 1) * n[0] * n[1];
}

/* Relabel the block so it is good, raising labels only (rank: background
 * lowest, then the labels of more voxels below those of fewer, so a thin
 * layer wins where it is pierced and the repair ends: each voxel can only
 * climb). One voxel first (lowest rank first, then index), to the
 * highest-ranked of its in-block face neighbours' labels above its own that
 * makes the block good; failing that every voxel off the padding to the
 * block's highest-ranked label. Returns the voxels changed (the first into
 * *first). */
static int repair_block(int32_t *lab, const int64_t n[3], const uint32_t *rank, int64_t v,
                        int64_t *first) {
  int64_t idx[8];
  block_of(n, v, idx);
  int32_t l[8];
  int pad[8], order[8];
  for (int b = 0; b < 8; b++) {
    l[b] = lab[idx[b]];
    pad[b] = on_pad(n, idx[b]);
    order[b] = b;
  }
  for (int x = 1; x < 8; x++)
    for (int y = x; y > 0 && rank[l[order[y]]] < rank[l[order[y - 1]]]; y--) {
      const int t = order[y];
      order[y] = order[y - 1];
      order[y - 1] = t;
    }
  for (int o = 0; o < 8; o++) {
    const int b = order[o];
    if (pad[b]) continue;
    int32_t cand[3];
    int nc = 0;
    for (int a = 0; a < 3; a++) {
      const int32_t c = l[b ^ (1 << a)];
      if (rank[c] <= rank[l[b]]) continue;
      int dup = 0;
      for (int k = 0; k < nc; k++) dup |= cand[k] == c;
      if (!dup) cand[nc++] = c;
    }
    for (int x = 1; x < nc; x++) /* highest rank first */
      for (int y = x; y > 0 && rank[cand[y]] > rank[cand[y - 1]]; y--) {
        const int32_t t = cand[y];
        cand[y] = cand[y - 1];
        cand[y - 1] = t;
      }
    for (int k = 0; k < nc; k++) {
      const int32_t keep = l[b];
      l[b] = cand[k];
      if (block_good(l)) {
        lab[idx[b]] = cand[k];
        *first = idx[b];
        return 1;
      }
      l[b] = keep;
    }
  }
  int32_t best = l[0];
  for (int b = 1; b < 8; b++)
    if (rank[l[b]] > rank[best]) best = l[b];
  int changed = 0;
  for (int b = 0; b < 8; b++)
    if (!pad[b] && lab[idx[b]] != best) {
      if (!changed) *first = idx[b];
      lab[idx[b]] = best;
      changed++;
    }
  return changed;
}

int mx_labels_fix_contacts(int32_t *lab, const int64_t n[3], const uint64_t *count,
                           const char *name, mx_label_fix_stats *st) {
  st->contact_at[0] = st->contact_at[1] = st->contact_at[2] = -1;
  /* blocks: the vertex at the far corner of voxel (i, j, k), i < n0 - 1 ... */
  const int64_t nb0 = n[0] - 1, nb1 = n[1] - 1, nb2 = n[2] - 1;
  /* the labels present, most voxels first (ties: the smaller label first);
   * rank = place + 1, background 0 */
  int32_t order[64];
  int nl = 0;
  for (int32_t L = 1; L < 65536; L++) {
    if (!count[L]) continue;
    if (nl == 64) {
      mx_error(name, 0, "labels: more than 64 (merge or skip some)");
      return MX_EINPUT;
    }
    int y = nl++;
    for (; y > 0 && count[order[y - 1]] < count[L]; y--) order[y] = order[y - 1];
    order[y] = L;
  }
  size_t cap = 1024, nbad = 0;
  int64_t *bad = mx_alloc(cap * sizeof *bad);
  uint32_t *rank = mx_calloc(65536 * sizeof *rank);
  if (!bad || !rank) {
    mx_free(bad);
    mx_free(rank);
    return MX_ENOMEM;
  }
  for (int x = 0; x < nl; x++) rank[order[x]] = (uint32_t)x + 1;
  int st_ok = MX_OK;
  for (int round = 0;; round++) {
    nbad = 0;
    int oom = 0;
#pragma omp parallel
    {
      size_t lcap = 64, ln = 0;
      int64_t *loc = mx_alloc(lcap * sizeof *loc);
      if (!loc) {
#pragma omp atomic write
        oom = 1;
      }
#pragma omp for schedule(static) ordered
      for (int64_t k = 0; k < nb2; k++) {
        for (int64_t j = 0; j < nb1 && loc; j++)
          for (int64_t i = 0; i < nb0; i++) {
            const int64_t v = i + n[0] * (j + n[1] * k);
            int64_t idx[8];
            block_of(n, v, idx);
            int32_t l[8];
            for (int b = 0; b < 8; b++) l[b] = lab[idx[b]];
            if (block_good(l)) continue;
            if (ln == lcap) {
              int64_t *g = mx_realloc(loc, 2 * lcap * sizeof *loc);
              if (!g) {
#pragma omp atomic write
                oom = 1;
                break;
              }
              loc = g;
              lcap *= 2;
            }
            loc[ln++] = v;
          }
#pragma omp ordered
        {
          if (loc && nbad + ln > cap) {
            size_t c2 = cap;
            while (c2 < nbad + ln) c2 *= 2;
            int64_t *g = mx_realloc(bad, c2 * sizeof *bad);
            if (g) {
              bad = g;
              cap = c2;
            } else {
              oom = 1;
            }
          }
          if (loc && nbad + ln <= cap) {
            memcpy(bad + nbad, loc, ln * sizeof *loc);
            nbad += ln;
          }
          ln = 0;
        }
      }
      mx_free(loc);
    }
    if (oom) {
      st_ok = MX_ENOMEM;
      break;
    }
    if (nbad == 0) break;
    if (round == 64) {
      const int64_t v = bad[0];
      mx_error(name, 0, "labels: the contacts between labels around voxel (%lld, %lld, %lld) "
                        "could not be removed in 64 passes",
               (long long)(v % n[0]), (long long)((v / n[0]) % n[1]),
               (long long)(v / (n[0] * n[1])));
      st_ok = MX_EINPUT;
      break;
    }
    st->contact_rounds = round + 1;
    for (size_t t = 0; t < nbad; t++) {
      int64_t idx[8];
      block_of(n, bad[t], idx);
      int32_t l[8];
      for (int b = 0; b < 8; b++) l[b] = lab[idx[b]];
      if (block_good(l)) continue; /* mended by an earlier repair */
      int64_t first = -1;
      const int c = repair_block(lab, n, rank, bad[t], &first);
      if (c && st->contact_at[0] < 0 && first >= 0) {
        st->contact_at[0] = first % n[0] - 1;
        st->contact_at[1] = (first / n[0]) % n[1] - 1;
        st->contact_at[2] = first / (n[0] * n[1]) - 1;
      }
      st->contact_voxels += (size_t)c;
    }
  }
  mx_free(bad);
  mx_free(rank);
  return st_ok;
}
