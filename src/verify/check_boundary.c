/* Pass 5 of the checker, the closed boundary: the faces used once (the
 * boundary faces) flag their nodes as boundary nodes (against which the
 * file's own flags, its point field boundary, are checked); a boundary quad both
 * of whose triangles along one diagonal are boundary faces too is a quad
 * against triangles; the edges of the boundary faces are sorted and
 * counted: an edge used an odd number of times leaves the boundary open
 * there, one used 4, 6... times is where two parts of the domain touch (not
 * manifold, still closed and conforming). */
#include "verify/check_passes.h"

#include "base/scan.h"

/* Whether the triangle a-b-c is a face used by exactly one element. */
static int boundary_triangle(const mx_mesh_data *m, const faces *F,
                             uint32_t a, uint32_t b, uint32_t c) {
  uint32_t v[4] = {a, b, c, 0};
  sort4(v, 3);
  const int64_t s = mx_ck_find_slot(m, F, v, 3);
  return s >= 0 && F->use[s] == 1;
}

/* The number of entries equal to key in the sorted k[0, n). */
static size_t count_equal(const uint64_t *k, size_t n, uint64_t key) {
  size_t lo = 0, hi = n;
  while (lo < hi) {
    const size_t mid = lo + (hi - lo) / 2;
    if (k[mid] < key)
      lo = mid + 1;
    else
      hi = mid;
  }
  size_t e = lo;
  while (e < n && k[e] == key) e++;
  return e - lo;
}

int mx_ck_boundary_pass(const mx_mesh_data *m, const faces *F,
                         uint8_t *flags, uint8_t *ef, size_t nbnd,
                         mx_check_report *r) {
  const size_t nslots = 6 * m->ncells;
  uint32_t *bnd = mx_alloc((nbnd + 1) * sizeof *bnd);
  uint64_t *ek = mx_alloc((4 * nbnd + 1) * sizeof *ek);
  if (!bnd || !ek) {
    mx_free(bnd);
    mx_free(ek);
    return MX_ENOMEM;
  }
  size_t nb = 0;
  for (size_t s = 0; s < nslots; s++)
    if (F->use[s] == 1 && nb < nbnd) bnd[nb++] = (uint32_t)s;
  size_t qvt = 0;
#pragma omp parallel for schedule(dynamic, 1024) reduction(+ : qvt) \
    if (nb > SMALL)
  for (size_t i = 0; i < nb; i++) {
    uint32_t v[4];
    const int n = face_verts(m, bnd[i], v);
    for (int x = 0; x < n; x++) {
      flag_or(&flags[v[x]], F_BND);
      const uint32_t a = v[x], b = v[(x + 1) % n];
      ek[4 * i + (size_t)x] = a < b ? (uint64_t)a << 32 | b
                                    : (uint64_t)b << 32 | a;
    }
    if (n == 3) {
      ek[4 * i + 3] = UINT64_MAX;
      continue;
    }
    if ((boundary_triangle(m, F, v[0], v[1], v[2]) &&
         boundary_triangle(m, F, v[0], v[2], v[3])) ||
        (boundary_triangle(m, F, v[0], v[1], v[3]) &&
         boundary_triangle(m, F, v[1], v[2], v[3]))) {
      qvt++;
      eflag(ef, bnd[i] / 6, MX_CK_QUAD_TRI);
    }
  }
  r->quad_vs_triangles = qvt;
  int st = mx_sort_u64(ek, NULL, 4 * nb);
  size_t open = 0, pinched = 0;
  for (size_t i = 0; st == MX_OK && i < 4 * nb && ek[i] != UINT64_MAX;) {
    size_t j = i + 1;
    while (j < 4 * nb && ek[j] == ek[i]) j++;
    /* An odd count leaves the boundary open; 4, 6... boundary faces meet
     * where two parts of the domain touch along an edge: closed, not
     * manifold, and conforming. */
    open += (j - i) % 2 != 0;
    pinched += (j - i) % 2 == 0 && j - i > 2;
    i = j;
  }
  r->open_boundary_edges = open;
  r->nonmanifold_edges = pinched;
  if (st == MX_OK && open) { /* the elements along the open edges */
#pragma omp parallel for schedule(dynamic, 1024) if (nb > SMALL)
    for (size_t i = 0; i < nb; i++) {
      uint32_t v[4];
      const int n = face_verts(m, bnd[i], v);
      for (int x = 0; x < n; x++) {
        const uint32_t a = v[x], b = v[(x + 1) % n];
        const uint64_t key = a < b ? (uint64_t)a << 32 | b
                                   : (uint64_t)b << 32 | a;
        if (count_equal(ek, 4 * nb, key) % 2) {
          eflag(ef, bnd[i] / 6, MX_CK_OPEN_EDGE);
          break;
        }
      }
    }
  }
  mx_free(bnd);
  mx_free(ek);
  return st;
}

/* A node whose flag in the file (the point field boundary) is not its
 * being a boundary node. */
static int flag_off(const mx_mesh_data *m, const uint8_t *flags, size_t v) {
  return (m->node_bnd[v] != 0) != ((flags[v] & F_BND) != 0);
}

void mx_ck_boundary_flags(const mx_mesh_data *m, const uint8_t *flags, mx_check_report *r) {
  if (!m->node_bnd || m->cell_tag) return; /* (with labels it flags interfaces too) */
  const size_t nn = m->nnodes;
  size_t off = 0;
#pragma omp parallel for schedule(static) reduction(+ : off) if (nn > SMALL)
  for (size_t v = 0; v < nn; v++) off += (size_t)flag_off(m, flags, v);
  r->has_boundary_flags = 1;
  r->boundary_flags_off = off;
  mx_check_ids *l = &r->boundary_flag_ids;
  for (size_t v = 0; v < nn && off && l->n < MX_CHECK_LIST; v++)
    if (flag_off(m, flags, v)) l->id[l->n++] = (uint32_t)v;
}
