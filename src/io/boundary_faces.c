/* mixoct: the faces used by exactly one element (see boundary_faces.h).
 *
 * Face slots are numbered 6 * element + local face. Three passes over the
 * slots: count the faces filed under each node (the smallest of the face's
 * nodes), fill the per-node lists (a CSR), then, node by node, sort the
 * short list by the sorted node tuple and record each face's multiplicity.
 * The multiplicities do not depend on the order the lists were filled in,
 * and the output is gathered element by element, so the result is the same
 * for any number of threads. */
#include "io/boundary_faces.h"

#include <stdlib.h>
#include <string.h>

#include "base/common.h"
#include "base/scan.h"

enum {
  SLOTS = 6,         /* face slots per element */
  OUT_CHUNK = 16384, /* elements per chunk of the gathering pass */
  SMALL_LIST = 48,   /* lists up to this size are insertion-sorted */
};

/* A face under its smallest node v0: hi = v1 << 32 | v2, lo = v3 << 32 |
 * slot, with v0 <= v1 <= v2 <= v3 its sorted nodes (v3 = UINT32_MAX for a
 * triangle). Ordering by (hi, lo) groups equal faces, then by slot. */
typedef struct {
  uint64_t hi, lo;
} face_key;

static inline int face_size(unsigned type, int f) {
  return mx_cell_faces[type][f][3] < 0 ? 3 : 4;
}

/* The nodes of face f of element c, in mx_cell_faces order; returns 3/4. */
static inline int face_nodes(const mx_mesh_view *m, size_t c, int f,
                             uint32_t out[4]) {
  const unsigned t = m->type[c];
  const int8_t *fv = mx_cell_faces[t][f];
  const uint32_t *row = m->conn + 8 * c;
  const int n = face_size(t, f);
  for (int j = 0; j < n; j++) out[j] = row[fv[j]];
  return n;
}

/* The faces of element c whose nodes are all in the mask, one bit per
 * local face (no mask: every face). */
static inline unsigned kept_faces(const mx_mesh_view *m, const uint8_t *mask, size_t c) {
  const unsigned t = m->type[c];
  const int nf = mx_cell_nfaces[t];
  if (!mask) return (1u << nf) - 1u;
  const uint32_t *row = m->conn + 8 * c;
  unsigned in = 0;
  for (int j = 0; j < mx_cell_nodes[t]; j++) in |= (unsigned)(mask[row[j]] != 0) << j;
  if (__builtin_popcount(in) < 3) return 0;
  unsigned kept = 0;
  for (int f = 0; f < nf; f++) {
    const int8_t *fv = mx_cell_faces[t][f];
    unsigned need = 0;
    for (int k = 0; k < 4 && fv[k] >= 0; k++) need |= 1u << fv[k];
    kept |= (unsigned)((in & need) == need) << f;
  }
  return kept;
}

static inline uint32_t face_min_node(const mx_mesh_view *m, size_t c, int f) {
  uint32_t v[4];
  const int n = face_nodes(m, c, f, v);
  uint32_t lo = v[0];
  for (int j = 1; j < n; j++) lo = v[j] < lo ? v[j] : lo;
  return lo;
}

static inline void order2(uint32_t *a, uint32_t *b) {
  const uint32_t x = *a, y = *b;
  *a = x < y ? x : y;
  *b = x < y ? y : x;
}

static inline face_key key_of_slot(const mx_mesh_view *m, uint32_t slot) {
  uint32_t v[4];
  if (face_nodes(m, slot / SLOTS, (int)(slot % SLOTS), v) == 3)
    v[3] = UINT32_MAX;
  /* a sorting network for four values */
  order2(&v[0], &v[1]);
  order2(&v[2], &v[3]);
  order2(&v[0], &v[2]);
  order2(&v[1], &v[3]);
  order2(&v[1], &v[2]);
  return (face_key){(uint64_t)v[1] << 32 | v[2], (uint64_t)v[3] << 32 | slot};
}

static inline int key_less(const face_key *a, const face_key *b) {
  return a->hi < b->hi || (a->hi == b->hi && a->lo < b->lo);
}

static inline int same_face(const face_key *a, const face_key *b) {
  return a->hi == b->hi && (a->lo >> 32) == (b->lo >> 32);
}

static void sift_down(face_key *k, size_t i, size_t n) {
  for (;;) {
    size_t c = 2 * i + 1;
    if (c >= n) return;
    if (c + 1 < n && key_less(&k[c], &k[c + 1])) c++;
    if (!key_less(&k[i], &k[c])) return;
    const face_key t = k[i];
    k[i] = k[c];
    k[c] = t;
    i = c;
  }
}

/* Insertion sort for the usual short lists, heap sort for long ones. */
static void sort_keys(face_key *k, size_t n) {
  if (n > SMALL_LIST) {
    for (size_t i = n / 2; i-- > 0;) sift_down(k, i, n);
    for (size_t e = n; e-- > 1;) {
      const face_key t = k[0];
      k[0] = k[e];
      k[e] = t;
      sift_down(k, 0, e);
    }
    return;
  }
  for (size_t i = 1; i < n; i++) {
    const face_key x = k[i];
    size_t j = i;
    while (j > 0 && key_less(&x, &k[j - 1])) {
      k[j] = k[j - 1];
      j--;
    }
    k[j] = x;
  }
}

static int too_large(const mx_mesh_view *m) {
  if (m->ncells > (size_t)(UINT32_MAX / SLOTS) || m->nnodes >= UINT32_MAX) {
    mx_error(NULL, 0,
             "%zu elements and %zu nodes are too many for the boundary "
             "extraction (at most %u elements)",
             m->ncells, m->nnodes, (unsigned)(UINT32_MAX / SLOTS));
    return 1;
  }
  return 0;
}

/* ---- pass 1 and 2: the faces filed under their smallest node ------------ */

/* On return (MX_OK) *list_out holds the kept face slots (kept_faces, also
 * set in fb: per element, its kept faces' bits), node v's being
 * list[end[v-1] .. end[v]) (end[-1] = 0); *end_out has nnodes entries.
 * The mask is read once per element, not once per face node; the second
 * pass reads only the elements with a kept face (cortex -s 9: 3.8 of 8.8
 * million). */
static int file_faces(const mx_mesh_view *m, const uint8_t *mask, uint8_t *fb,
                      uint64_t **end_out, uint32_t **list_out, size_t *nfaces) {
  const size_t nn = m->nnodes, nc = m->ncells;
  uint64_t *pos = mx_calloc((nn + 1) * sizeof *pos); /* cleared by every thread */
  if (!pos) return MX_ENOMEM;
#pragma omp parallel for schedule(static)
  for (size_t c = 0; c < nc; c++) {
    const unsigned kept = kept_faces(m, mask, c);
    fb[c] = (uint8_t)kept;
    for (unsigned b = kept; b; b &= b - 1) {
      const uint32_t v = face_min_node(m, c, __builtin_ctz(b));
#pragma omp atomic update
      pos[v]++;
    }
  }
  const uint64_t total = mx_scan_u64(pos, nn + 1);
  uint32_t *list = mx_alloc((total ? total : 1) * sizeof *list);
  if (!list) {
    mx_free(pos);
    return MX_ENOMEM;
  }
  /* pos[v] walks from the start of v's list to its end (= start of v+1) */
#pragma omp parallel for schedule(static)
  for (size_t c = 0; c < nc; c++) {
    for (unsigned b = fb[c]; b; b &= b - 1) {
      const int f = __builtin_ctz(b);
      const uint32_t v = face_min_node(m, c, f);
      uint64_t at;
#pragma omp atomic capture
      at = pos[v]++;
      list[at] = (uint32_t)(c * SLOTS + (size_t)f);
    }
  }
  *end_out = pos;
  *list_out = list;
  *nfaces = (size_t)total;
  return MX_OK;
}

/* ---- pass 3: multiplicity of every face ---------------------------------- */

/* gb: per element, one bit per local face that the gathering takes (a
 * face used once; with labels, an interface face on its lower label's
 * side); set with an atomic OR, as an element's faces are filed under
 * different nodes. other (labels only): the label on the other side of a
 * face taken, 0 for a boundary face. Nothing is written for the faces
 * used twice (most of them), and there is no array per face slot to
 * clear or fill. */
static inline void take(uint8_t *gb, uint32_t slot) {
  __atomic_fetch_or(&gb[slot / SLOTS], (uint8_t)(1u << (slot % SLOTS)), __ATOMIC_RELAXED);
}

/* The faces filed under each node compared by their sorted nodes: a face
 * used once is taken, and with labels (per element, or NULL) a face of two
 * elements of different labels on the lower label's side, with the other
 * label (see take). */
static int count_uses(const mx_mesh_view *m, const uint64_t *end,
                      const uint32_t *list, const int32_t *label, uint8_t *gb,
                      int32_t *other) {
  const size_t nn = m->nnodes;
  int failed = 0;
#pragma omp parallel
  {
    size_t cap = 64;
    face_key *keys = mx_alloc(cap * sizeof *keys);
    if (!keys) {
#pragma omp atomic write
      failed = 1;
    }
#pragma omp for schedule(dynamic, 4096)
    for (size_t v = 0; v < nn; v++) {
      if (!keys) continue;
      const uint64_t lo = v ? end[v - 1] : 0, hi = end[v];
      const size_t k = (size_t)(hi - lo);
      if (k == 0) continue;
      if (k > cap) {
        face_key *grown = mx_realloc(keys, k * sizeof *keys);
        if (!grown) {
          mx_free(keys);
          keys = NULL;
#pragma omp atomic write
          failed = 1;
          continue;
        }
        keys = grown;
        cap = k;
      }
      /* the elements are scattered: ask for all their rows first */
      for (size_t i = 0; i < k; i++) {
        const size_t c = list[lo + i] / SLOTS;
        __builtin_prefetch(m->type + c);
        __builtin_prefetch(m->conn + 8 * c);
      }
      for (size_t i = 0; i < k; i++) keys[i] = key_of_slot(m, list[lo + i]);
      sort_keys(keys, k);
      for (size_t i = 0; i < k;) {
        size_t j = i + 1;
        while (j < k && same_face(&keys[j], &keys[i])) j++;
        if (j - i == 1) {
          take(gb, (uint32_t)keys[i].lo);
          if (other) other[(uint32_t)keys[i].lo] = 0;
        } else if (label && j - i == 2) {
          const uint32_t s0 = (uint32_t)keys[i].lo, s1 = (uint32_t)keys[i + 1].lo;
          const int32_t l0 = label[s0 / SLOTS], l1 = label[s1 / SLOTS];
          if (l0 != l1) {
            const uint32_t keep = l0 < l1 ? s0 : s1;
            take(gb, keep);
            other[keep] = l0 < l1 ? l1 : l0;
          }
        }
        i = j;
      }
    }
    mx_free(keys);
  }
  return failed ? MX_ENOMEM : MX_OK; /* said by the call (mesher/call.h) */
}

/* ---- gathering, element by element ----------------------------------------
 */

/* The faces taken (gb), in element order. */
static int gather(const mx_mesh_view *m, const uint8_t *gb, const int32_t *other,
                  mx_boundary_faces *bf) {
  const size_t nc = m->ncells;
  const size_t nchunks = (nc + OUT_CHUNK - 1) / OUT_CHUNK;
  uint64_t *ntri = mx_calloc((nchunks + 1) * sizeof *ntri);
  uint64_t *nquad = mx_calloc((nchunks + 1) * sizeof *nquad);
  if (!ntri || !nquad) {
    mx_free(ntri);
    mx_free(nquad);
    return MX_ENOMEM;
  }
#pragma omp parallel for schedule(static)
  for (size_t k = 0; k < nchunks; k++) {
    const size_t c1 = (k + 1) * OUT_CHUNK < nc ? (k + 1) * OUT_CHUNK : nc;
    uint64_t a = 0, b = 0;
    for (size_t c = k * OUT_CHUNK; c < c1; c++) {
      if (!gb[c]) continue;
      const unsigned t = m->type[c];
      for (unsigned bits = gb[c]; bits; bits &= bits - 1) {
        if (face_size(t, __builtin_ctz(bits)) == 3)
          a++;
        else
          b++;
      }
    }
    ntri[k] = a;
    nquad[k] = b;
  }
  bf->ntri = (size_t)mx_scan_u64(ntri, nchunks + 1);
  bf->nquad = (size_t)mx_scan_u64(nquad, nchunks + 1);
  int st = MX_OK;
  if (bf->ntri) {
    bf->tri = mx_alloc(3 * bf->ntri * sizeof *bf->tri);
    bf->tri_src = mx_alloc(bf->ntri * sizeof *bf->tri_src);
    if (other) bf->tri_pair = mx_alloc(bf->ntri * sizeof *bf->tri_pair);
    if (!bf->tri || !bf->tri_src || (other && !bf->tri_pair)) st = MX_ENOMEM;
  }
  if (bf->nquad) {
    bf->quad = mx_alloc(4 * bf->nquad * sizeof *bf->quad);
    bf->quad_src = mx_alloc(bf->nquad * sizeof *bf->quad_src);
    if (other) bf->quad_pair = mx_alloc(bf->nquad * sizeof *bf->quad_pair);
    if (!bf->quad || !bf->quad_src || (other && !bf->quad_pair)) st = MX_ENOMEM;
  }
  if (st == MX_OK) {
#pragma omp parallel for schedule(static)
    for (size_t k = 0; k < nchunks; k++) {
      const size_t c1 = (k + 1) * OUT_CHUNK < nc ? (k + 1) * OUT_CHUNK : nc;
      uint64_t a = ntri[k], b = nquad[k];
      for (size_t c = k * OUT_CHUNK; c < c1; c++) {
        for (unsigned bits = gb[c]; bits; bits &= bits - 1) {
          const int f = __builtin_ctz(bits);
          const int32_t pair = other ? other[c * SLOTS + (size_t)f] : 0;
          uint32_t v[4];
          if (face_nodes(m, c, f, v) == 3) {
            memcpy(bf->tri + 3 * a, v, 3 * sizeof *v);
            if (bf->tri_pair) bf->tri_pair[a] = pair;
            bf->tri_src[a++] = 8 * (uint64_t)c + (uint64_t)f;
          } else {
            memcpy(bf->quad + 4 * b, v, 4 * sizeof *v);
            if (bf->quad_pair) bf->quad_pair[b] = pair;
            bf->quad_src[b++] = 8 * (uint64_t)c + (uint64_t)f;
          }
        }
      }
    }
  }
  mx_free(ntri);
  mx_free(nquad);
  return st;
}

/* ---- public -------------------------------------------------------------- */

void mx_boundary_faces_free(mx_boundary_faces *bf) {
  if (!bf) return;
  mx_free(bf->tri);
  mx_free(bf->quad);
  mx_free(bf->tri_src);
  mx_free(bf->quad_src);
  mx_free(bf->tri_tag);
  mx_free(bf->quad_tag);
  mx_free(bf->tri_pair);
  mx_free(bf->quad_pair);
  memset(bf, 0, sizeof *bf);
}

int mx_boundary_faces_extract(const mx_mesh_view *m, mx_boundary_faces *bf) {
  return mx_boundary_faces_extract_masked(m, NULL, bf);
}

static int extract(const mx_mesh_view *m, const uint8_t *mask, const int32_t *label,
                   mx_boundary_faces *bf) {
  memset(bf, 0, sizeof *bf);
  if (m->ncells == 0) return MX_OK;
  if (too_large(m)) return MX_EINPUT;
  uint64_t *end = NULL;
  uint32_t *list = NULL;
  size_t nfaces = 0;
  uint8_t *fb = mx_alloc(m->ncells);
  if (!fb) return MX_ENOMEM;
  int st = file_faces(m, mask, fb, &end, &list, &nfaces);
  /* fb again, as the faces taken (count_uses) */
  if (!st) {
#pragma omp parallel for schedule(static)
    for (size_t c = 0; c < m->ncells; c++) fb[c] = 0;
  }
  /* other is read for the faces taken only, all of which count_uses sets */
  int32_t *other = !st && label ? mx_alloc(m->ncells * SLOTS * sizeof *other) : NULL;
  if (!st) st = !label || other ? count_uses(m, end, list, label, fb, other) : MX_ENOMEM;
  mx_free(end);
  mx_free(list);
  if (st == MX_OK) st = gather(m, fb, other, bf);
  mx_free(fb);
  mx_free(other);
  if (st != MX_OK) mx_boundary_faces_free(bf);
  return st;
}

int mx_boundary_faces_extract_masked(const mx_mesh_view *m, const uint8_t *mask,
                                     mx_boundary_faces *bf) {
  return extract(m, mask, NULL, bf);
}

int mx_interface_faces_extract(const mx_mesh_view *m, const int32_t *label,
                               mx_boundary_faces *bf) {
  return extract(m, NULL, label, bf);
}

int mx_boundary_node_flags(const mx_mesh_view *m, int32_t *flags) {
  mx_boundary_faces bf;
  MX_CHECK(mx_boundary_faces_extract(m, &bf));
  memset(flags, 0, m->nnodes * sizeof *flags);
#pragma omp parallel for schedule(static)
  for (size_t i = 0; i < 3 * bf.ntri; i++) {
#pragma omp atomic write
    flags[bf.tri[i]] = 1;
  }
#pragma omp parallel for schedule(static)
  for (size_t i = 0; i < 4 * bf.nquad; i++) {
#pragma omp atomic write
    flags[bf.quad[i]] = 1;
  }
  mx_boundary_faces_free(&bf);
  return MX_OK;
}

int mx_boundary_nodes_number(const mx_boundary_faces *bf, size_t nnodes, mx_boundary_nodes *N) {
  memset(N, 0, sizeof *N);
  N->newid = mx_alloc((nnodes + 1) * sizeof *N->newid);
  if (!N->newid) return MX_ENOMEM;
  memset(N->newid, 0xff, nnodes * sizeof *N->newid);
  for (size_t i = 0; i < 3 * bf->ntri; i++) N->newid[bf->tri[i]] = 0;
  for (size_t i = 0; i < 4 * bf->nquad; i++) N->newid[bf->quad[i]] = 0;
  for (size_t v = 0; v < nnodes; v++)
    if (N->newid[v] == 0) N->newid[v] = (uint32_t)N->nused++;
  N->used = mx_alloc((N->nused + 1) * sizeof *N->used);
  if (!N->used) {
    mx_boundary_nodes_free(N);
    return MX_ENOMEM;
  }
  for (size_t v = 0; v < nnodes; v++)
    if (N->newid[v] != UINT32_MAX) N->used[N->newid[v]] = (uint32_t)v;
  return MX_OK;
}

void mx_boundary_nodes_free(mx_boundary_nodes *N) {
  mx_free(N->used);
  mx_free(N->newid);
  memset(N, 0, sizeof *N);
}
