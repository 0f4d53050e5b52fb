/* Pass 2 of the checker, duplicate nodes: every node goes into an
 * open-addressing hash of its exact coordinates (check_passes.h), cut into
 * segments by a coarse grid over the nodes' box for locality; insertion is
 * lock-free (compare-and-swap), the smallest id kept per point, and a node
 * whose point is already there is a duplicate. The hash then serves the
 * exact hanging-node lookups (check_faces.c, check_hanging.c). */
#include "verify/check_passes.h"

#include "base/scan.h"

static void chash_box(chash *H, const mx_mesh_data *m) {
  double lo[3] = {INFINITY, INFINITY, INFINITY};
  double hi[3] = {-INFINITY, -INFINITY, -INFINITY};
  double lx = lo[0], ly = lo[1], lz = lo[2], hx = hi[0], hy = hi[1],
         hz = hi[2];
#pragma omp parallel for schedule(static) if (m->nnodes > 65536) \
    reduction(min : lx, ly, lz) reduction(max : hx, hy, hz)
  for (size_t n = 0; n < m->nnodes; n++) {
    const double *q = m->xyz + 3 * n;
    lx = mx_min(lx, q[0]);
    ly = mx_min(ly, q[1]);
    lz = mx_min(lz, q[2]);
    hx = mx_max(hx, q[0]);
    hy = mx_max(hy, q[1]);
    hz = mx_max(hz, q[2]);
  }
  if (m->nnodes == 0) lx = ly = lz = hx = hy = hz = 0.0;
  H->lo[0] = lx;
  H->lo[1] = ly;
  H->lo[2] = lz;
  H->hi[0] = hx;
  H->hi[1] = hy;
  H->hi[2] = hz;
  ubox_init(&H->U, H->lo, H->hi);
  double h = 1.0;
  H->d[0] = H->d[1] = H->d[2] = 1;
  if (H->U.ok) /* relative extents: cells of side h (a fraction of the box) */
    mx_ck_cell_grid(H->U.ext, (double)m->nnodes / 8.0, 2048, &h, H->d);
  H->scale = 1.0 / h;
  if (!H->U.ok || !isfinite(H->scale)) {
    H->d[0] = H->d[1] = H->d[2] = 1;
    H->scale = 0.0;
  }
}

/* Inserts every node; *dups receives the number of nodes whose point was
 * already there (duplicates). */
int mx_ck_chash_build(chash *H, const mx_mesh_data *m, size_t *dups) {
  H->xyz = m->xyz;
  chash_box(H, m);
  const size_t ncells = (size_t)H->d[0] * H->d[1] * H->d[2];
  H->seg = mx_calloc((ncells + 1) * sizeof *H->seg);
  if (!H->seg) return MX_ENOMEM;
#pragma omp parallel for schedule(static) if (m->nnodes > 65536)
  for (size_t n = 0; n < m->nnodes; n++) {
    const int64_t c = chash_cell(H, m->xyz + 3 * n);
    if (c >= 0) __atomic_fetch_add(&H->seg[c], 1, __ATOMIC_RELAXED);
  }
#pragma omp parallel for schedule(static) if (ncells > 65536)
  for (size_t c = 0; c < ncells; c++) {
    uint64_t size = H->seg[c] ? 4 : 0;
    while (size && size < 4 * H->seg[c]) size *= 2;
    H->seg[c] = size;
  }
  const uint64_t total = mx_scan_u64(H->seg, ncells + 1);
  H->slot = mx_calloc((size_t)total * sizeof *H->slot + 8);
  if (!H->slot) return MX_ENOMEM;
  size_t d = 0;
#pragma omp parallel for schedule(static) reduction(+ : d) \
    if (m->nnodes > 65536)
  for (size_t n = 0; n < m->nnodes; n++) {
    const double *q = m->xyz + 3 * n;
    cprobe p;
    if (!chash_probe(H, q, &p)) continue; /* not finite */
    const uint64_t mine = (p.h >> 32) << 32 | (uint64_t)(n + 1);
    for (uint64_t i = p.h & p.mask;; i = (i + 1) & p.mask) {
      uint64_t *slot = &H->slot[p.base + i];
      uint64_t e = __atomic_load_n(slot, __ATOMIC_ACQUIRE);
      if (!e) {
        if (__atomic_compare_exchange_n(slot, &e, mine, 0, __ATOMIC_ACQ_REL,
                                        __ATOMIC_ACQUIRE))
          break;
        /* e now holds what another thread stored: examine it below. */
      }
      if ((e >> 32) == (p.h >> 32) &&
          same_point(m->xyz + 3 * (size_t)((uint32_t)e - 1), q)) {
        d++;
        /* Keep the smallest id for this point. */
        while ((uint32_t)e - 1 > n &&
               !__atomic_compare_exchange_n(slot, &e, mine, 0,
                                            __ATOMIC_ACQ_REL,
                                            __ATOMIC_ACQUIRE)) {
        }
        break;
      }
    }
  }
  *dups = d;
  return MX_OK;
}
