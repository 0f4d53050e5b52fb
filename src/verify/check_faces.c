/* Pass 3 of the checker, face matching (conformity): every face of every
 * element goes into the bucket of its smallest node (a counting sort), each
 * bucket is sorted by the remaining sorted node ids and then the face slot
 * (6 * element + local face), and runs of equal keys are the uses of a
 * face: used once, a boundary face; twice, an interior face, whose two
 * elements must run through it in opposite cyclic orders (else
 * misoriented); three times or more, overshared. Triangles and quads never
 * compare equal. The centre of every quad face is looked up in the
 * coordinate hash: a node there that is not one of the quad's is hanging.
 * Buckets stay sorted for the face lookups of later passes (find_slot). */
#include "verify/check_passes.h"

#include <stdlib.h>

#include "base/scan.h"

static int fkey_qcmp(const void *pa, const void *pb) {
  const fkey *a = pa, *b = pb;
  int c = key_cmp(a, b);
  if (c) return c;
  return (a->slot > b->slot) - (a->slot < b->slot);
}

static void sort_keys(fkey *k, size_t n) {
  if (n > 48) {
    qsort(k, n, sizeof *k, fkey_qcmp);
    return;
  }
  for (size_t i = 1; i < n; i++) {
    fkey x = k[i];
    size_t j = i;
    for (; j > 0 && fkey_qcmp(&k[j - 1], &x) > 0; j--) k[j] = k[j - 1];
    k[j] = x;
  }
}

/* Whether the two uses of a face run through it in opposite cyclic orders. */
static int opposite(const mx_mesh_data *m, uint32_t s1, uint32_t s2) {
  uint32_t a[4], b[4];
  const int n = face_verts(m, s1, a);
  face_verts(m, s2, b);
  int ia = 0, ib = 0;
  for (int k = 1; k < n; k++) {
    if (a[k] < a[ia]) ia = k;
    if (b[k] < b[ib]) ib = k;
  }
  for (int k = 1; k < n; k++)
    if (a[(ia + k) % n] != b[(ib + n - k) % n]) return 0;
  return 1;
}

int mx_ck_faces_bucket(const mx_mesh_data *m, faces *F) {
  const size_t nn = m->nnodes, nc = m->ncells;
  F->end = mx_calloc((nn + 1) * sizeof *F->end);
  F->use = mx_calloc(6 * nc + 1);
  if (!F->end || !F->use) return MX_ENOMEM;
#pragma omp parallel for schedule(static) if (nc > SMALL)
  for (size_t c = 0; c < nc; c++) {
    for (int j = 0; j < nfaces[m->type[c]]; j++) {
      uint32_t v[4];
      int n = face_verts(m, (uint32_t)(6 * c + (size_t)j), v);
      __atomic_fetch_add(&F->end[min_vertex(v, n)], 1, __ATOMIC_RELAXED);
    }
  }
  const uint64_t total = mx_scan_u64(F->end, nn);
  F->slot = mx_alloc((size_t)total * sizeof *F->slot + 4);
  if (!F->slot) return MX_ENOMEM;
#pragma omp parallel for schedule(static) if (nc > SMALL)
  for (size_t c = 0; c < nc; c++) {
    for (int j = 0; j < nfaces[m->type[c]]; j++) {
      const uint32_t s = (uint32_t)(6 * c + (size_t)j);
      uint32_t v[4];
      int n = face_verts(m, s, v);
      uint64_t at = __atomic_fetch_add(&F->end[min_vertex(v, n)], 1,
                                       __ATOMIC_RELAXED);
      F->slot[at] = s;
    }
  }
  return MX_OK; /* now end[v] is the end of bucket v, its start end[v-1] */
}

/* Sorts every bucket, records the uses of every slot, counts, and probes
 * the centres of quad faces. */
int mx_ck_faces_match(const mx_mesh_data *m, faces *F, const chash *H,
                       uint8_t *flags, uint8_t *ef, face_counts *fc) {
  size_t interior = 0, boundary = 0, over = 0, mis = 0;
  int oom = 0;
#pragma omp parallel reduction(+ : interior, boundary, over, mis) \
    if (m->nnodes > SMALL)
  {
    size_t cap = 64;
    fkey *k = mx_alloc(cap * sizeof *k);
    if (!k) {
#pragma omp atomic write
      oom = 1;
    }
#pragma omp for schedule(dynamic, 2048)
    for (size_t v = 0; v < m->nnodes; v++) {
      const uint64_t b = bucket_begin(F, v), n = F->end[v] - b;
      if (n == 0 || !k) continue;
      if (n > cap) {
        fkey *nk = mx_realloc(k, (size_t)n * sizeof *k);
        if (!nk) {
#pragma omp atomic write
          oom = 1;
          continue;
        }
        k = nk;
        cap = (size_t)n;
      }
      for (uint64_t i = 0; i < n; i++) k[i] = slot_key(m, F->slot[b + i]);
      sort_keys(k, (size_t)n);
      for (uint64_t i = 0; i < n; i++) F->slot[b + i] = k[i].slot;
      for (uint64_t i = 0; i < n;) {
        uint64_t j = i + 1;
        while (j < n && key_cmp(&k[j], &k[i]) == 0) j++;
        const uint64_t g = j - i;
        for (uint64_t x = i; x < j; x++)
          F->use[k[x].slot] = (uint8_t)(g < 255 ? g : 255);
        if (g == 1)
          boundary++;
        else if (g == 2) {
          interior++;
          if (!opposite(m, k[i].slot, k[i + 1].slot)) {
            mis++;
            eflag(ef, k[i].slot / 6, MX_CK_MISORIENTED);
            eflag(ef, k[i + 1].slot / 6, MX_CK_MISORIENTED);
          }
        } else {
          over++;
          for (uint64_t x = i; x < j; x++)
            eflag(ef, k[x].slot / 6, MX_CK_OVERSHARED);
        }
        if (H && (k[i].hi >> 32) == 4) { /* quad: its centre */
          uint32_t fv[4] = {0, 0, 0, 0};
          face_verts(m, k[i].slot, fv);
          const double *p[4];
          for (int x = 0; x < 4; x++) p[x] = m->xyz + 3 * (size_t)fv[x];
          double q1[3], q2[3];
          midpoint(p[0], p[2], q1);
          midpoint(p[1], p[3], q2);
          int hit = mark_hanging(flags, chash_find(H, q1), fv, 4);
          if (!same_point(q1, q2))
            hit |= mark_hanging(flags, chash_find(H, q2), fv, 4);
          if (hit)
            for (uint64_t x = i; x < j; x++)
              eflag(ef, k[x].slot / 6, MX_CK_HANGING);
        }
        i = j;
      }
    }
    mx_free(k);
  }
  if (oom) return MX_ENOMEM;
  fc->interior = interior;
  fc->boundary = boundary;
  fc->overshared = over;
  fc->misoriented = mis;
  return MX_OK;
}

/* The first slot (in its sorted bucket) of a face with the sorted nodes v
 * (n of them), or -1. */
/* The first position of bucket v[0] whose key is not below that of the
 * sorted face v (n nodes), and that key's wanted value. */
static uint64_t first_not_below(const mx_mesh_data *m, const faces *F, const uint32_t *v, int n,
                                fkey *want) {
  *want = key_of((uint32_t)n, v, 0);
  uint64_t lo = bucket_begin(F, v[0]), hi = F->end[v[0]];
  while (lo < hi) {
    const uint64_t mid = lo + (hi - lo) / 2;
    const fkey k = slot_key(m, F->slot[mid]);
    if (key_cmp(&k, want) < 0)
      lo = mid + 1;
    else
      hi = mid;
  }
  return lo;
}

/* The slot at position `at` of bucket v[0] when its key is want's, else -1. */
static int64_t slot_if(const mx_mesh_data *m, const faces *F, const uint32_t *v, uint64_t at,
                       const fkey *want) {
  if (at >= F->end[v[0]]) return -1;
  const fkey k = slot_key(m, F->slot[at]);
  return key_cmp(&k, want) == 0 ? (int64_t)F->slot[at] : -1;
}

int64_t mx_ck_find_second(const mx_mesh_data *m, const faces *F, const uint32_t *v, int n) {
  fkey want;
  const uint64_t at = first_not_below(m, F, v, n, &want);
  return slot_if(m, F, v, at + 1, &want);
}

void mx_ck_find_pair(const mx_mesh_data *m, const faces *F, const uint32_t *v, int n,
                     int64_t *first, int64_t *second) {
  fkey want;
  const uint64_t at = first_not_below(m, F, v, n, &want);
  *first = slot_if(m, F, v, at, &want);
  *second = *first < 0 ? -1 : slot_if(m, F, v, at + 1, &want);
}

int64_t mx_ck_find_slot(const mx_mesh_data *m, const faces *F,
                         const uint32_t *v, int n) {
  fkey want;
  const uint64_t at = first_not_below(m, F, v, n, &want);
  return slot_if(m, F, v, at, &want);
}
