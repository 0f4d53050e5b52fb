/* Pass 8 of the checker, distance to the surface: every boundary node's
 * distance to the nearest surface triangle, through a uniform grid of the
 * triangles' boxes searched in rings of cells around the node's cell until
 * no triangle beyond them can be nearer; the largest, over the diagonal of
 * the surface's box, and the nodes beyond boundary_tol times it. The nodes
 * of the faces between two labels (F_IFACE: the interfaces between
 * materials, which lie on the surface's inner shells) the same way, apart. */
#include "verify/check_passes.h"

#include <stdlib.h>

#include "base/scan.h"

typedef struct {
  const mx_trisoup *s;
  double lo[3], h, inv_h;
  int d[3];
  uint64_t *start; /* cells + 1 */
  uint32_t *tri;
} tgrid;

static void tgrid_free(tgrid *g) {
  mx_free(g->start);
  mx_free(g->tri);
}

static inline int cell_coord(const tgrid *g, double x, int a) {
  double f = floor((x - g->lo[a]) * g->inv_h);
  if (!(f >= 0.0)) return 0;
  if (f > (double)(g->d[a] - 1)) return g->d[a] - 1;
  return (int)f;
}

static void tri_cells(const tgrid *g, size_t t, int lo[3], int hi[3]) {
  const mx_trisoup *s = g->s;
  const double *co[3] = {s->x, s->y, s->z};
  for (int a = 0; a < 3; a++) {
    double mn = INFINITY, mx = -INFINITY;
    for (int k = 0; k < 3; k++) {
      const double v = co[a][s->tri[3 * t + (size_t)k]];
      mn = mx_min(mn, v);
      mx = mx_max(mx, v);
    }
    lo[a] = cell_coord(g, mn, a);
    hi[a] = cell_coord(g, mx, a);
  }
}

static int tgrid_build(tgrid *g, const mx_trisoup *s, const double blo[3],
                       const double bhi[3]) {
  memset(g, 0, sizeof *g);
  g->s = s;
  double ext[3], mext = 0.0;
  for (int a = 0; a < 3; a++) mext = mx_max(mext, bhi[a] - blo[a]);
  const double pad = 1e-9 * mext;
  for (int a = 0; a < 3; a++) {
    g->lo[a] = blo[a] - pad;
    ext[a] = bhi[a] - blo[a] + 2 * pad;
  }
  double h;
  mx_ck_cell_grid(ext, (double)s->nt, 1024, &h, g->d);
  size_t ncells = (size_t)g->d[0] * g->d[1] * g->d[2];
  g->h = h;
  g->inv_h = 1.0 / h;
  g->start = mx_calloc((ncells + 1) * sizeof *g->start);
  if (!g->start) return MX_ENOMEM;
  for (size_t t = 0; t < s->nt; t++) {
    int lo[3], hi[3];
    tri_cells(g, t, lo, hi);
    for (int z = lo[2]; z <= hi[2]; z++)
      for (int y = lo[1]; y <= hi[1]; y++)
        for (int x = lo[0]; x <= hi[0]; x++)
          g->start[((size_t)z * g->d[1] + (size_t)y) * g->d[0] + (size_t)x]++;
  }
  const uint64_t total = mx_scan_u64(g->start, ncells + 1);
  g->tri = mx_alloc((size_t)total * sizeof *g->tri + 4);
  if (!g->tri) return MX_ENOMEM;
  for (size_t t = 0; t < s->nt; t++) {
    int lo[3], hi[3];
    tri_cells(g, t, lo, hi);
    for (int z = lo[2]; z <= hi[2]; z++)
      for (int y = lo[1]; y <= hi[1]; y++)
        for (int x = lo[0]; x <= hi[0]; x++)
          g->tri[g->start[((size_t)z * g->d[1] + (size_t)y) * g->d[0] +
                          (size_t)x]++] = (uint32_t)t;
  }
  /* start[i] is now the end of cell i: shift back. */
  memmove(g->start + 1, g->start, ncells * sizeof *g->start);
  g->start[0] = 0;
  return MX_OK;
}

static inline double box_d2(const double p[3], const double lo[3],
                            const double hi[3]) {
  double d2 = 0.0;
  for (int a = 0; a < 3; a++) {
    const double d = mx_max(mx_max(lo[a] - p[a], p[a] - hi[a]), 0.0);
    d2 += d * d;
  }
  return d2;
}

/* Squared distance from p to the nearest triangle: rings of cells around
 * p's (clamped) cell until every triangle not seen yet -- all lying in cells
 * outside the rings, so in one of the slabs beyond them -- is provably
 * farther than the best so far. stamp marks the triangles tested for this
 * query (id qid). */
static double tgrid_d2(const tgrid *g, const double p[3], uint32_t *stamp,
                       uint32_t qid) {
  const mx_trisoup *s = g->s;
  int c[3];
  for (int a = 0; a < 3; a++) c[a] = cell_coord(g, p[a], a);
  double glo[3], ghi[3];
  for (int a = 0; a < 3; a++) {
    glo[a] = g->lo[a];
    ghi[a] = g->lo[a] + g->d[a] * g->h;
  }
  double best = INFINITY;
  for (int r = 0;; r++) {
    int lo[3], hi[3];
    for (int a = 0; a < 3; a++) {
      lo[a] = c[a] - r < 0 ? 0 : c[a] - r;
      hi[a] = c[a] + r > g->d[a] - 1 ? g->d[a] - 1 : c[a] + r;
    }
    for (int z = lo[2]; z <= hi[2]; z++)
      for (int y = lo[1]; y <= hi[1]; y++)
        for (int x = lo[0]; x <= hi[0]; x++) {
          if (abs(x - c[0]) != r && abs(y - c[1]) != r && abs(z - c[2]) != r)
            continue; /* seen in an earlier ring */
          const size_t cell =
              ((size_t)z * g->d[1] + (size_t)y) * g->d[0] + (size_t)x;
          for (uint64_t i = g->start[cell]; i < g->start[cell + 1]; i++) {
            const uint32_t t = g->tri[i];
            if (stamp[t] == qid) continue;
            stamp[t] = qid;
            const uint32_t *v = s->tri + 3 * (size_t)t;
            double A[3] = {s->x[v[0]], s->y[v[0]], s->z[v[0]]};
            double B[3] = {s->x[v[1]], s->y[v[1]], s->z[v[1]]};
            double C[3] = {s->x[v[2]], s->y[v[2]], s->z[v[2]]};
            best = mx_min(best, mx_ck_point_triangle_d2(p, A, B, C));
          }
        }
    double bound = INFINITY;
    for (int a = 0; a < 3; a++) {
      double slo[3], shi[3];
      memcpy(slo, glo, sizeof slo);
      memcpy(shi, ghi, sizeof shi);
      if (lo[a] > 0) {
        shi[a] = g->lo[a] + lo[a] * g->h;
        bound = mx_min(bound, box_d2(p, slo, shi));
        shi[a] = ghi[a];
      }
      if (hi[a] < g->d[a] - 1) {
        slo[a] = g->lo[a] + (hi[a] + 1) * g->h;
        bound = mx_min(bound, box_d2(p, slo, shi));
      }
    }
    if (bound == INFINITY || bound >= best) return best;
  }
}

int mx_ck_surface_distance(const mx_mesh_data *m, const mx_trisoup *s,
                           uint8_t *flags, double tol, mx_check_report *r) {
  double lo[3], hi[3];
  mx_trisoup_bbox(s, lo, hi);
  double diag2 = 0.0;
  for (int a = 0; a < 3; a++) diag2 += (hi[a] - lo[a]) * (hi[a] - lo[a]);
  /* Distance of the boundary and interface nodes. */
  r->boundary_max_dist = NAN;
  r->interface_max_dist = NAN;
  if (s->nt == 0 || !(diag2 > 0.0)) return MX_OK;
  size_t nb = 0, nbnd = 0, ni = 0;
  for (size_t v = 0; v < m->nnodes; v++) {
    nb += (flags[v] & (F_BND | F_IFACE)) != 0;
    nbnd += (flags[v] & F_BND) != 0;
    ni += (flags[v] & F_IFACE) != 0;
  }
  r->interface_nodes = ni;
  if (nb == 0) return MX_OK;
  uint32_t *bn = mx_alloc(nb * sizeof *bn);
  tgrid g;
  int st = bn ? tgrid_build(&g, s, lo, hi) : MX_ENOMEM;
  if (st != MX_OK) {
    if (bn) tgrid_free(&g);
    mx_free(bn);
    return st;
  }
  nb = 0;
  for (size_t v = 0; v < m->nnodes; v++)
    if (flags[v] & (F_BND | F_IFACE)) bn[nb++] = (uint32_t)v;
  double worst = 0.0, iworst = 0.0;
  int oom = 0;
  size_t off = 0, ioff = 0;
  const double sdiag = sqrt(diag2);
#pragma omp parallel reduction(max : worst, iworst) reduction(+ : off, ioff) \
    if (nb > SMALL / 4)
  {
    uint32_t *stamp = mx_calloc(s->nt * sizeof *stamp);
    if (!stamp) {
#pragma omp atomic write
      oom = 1;
    }
#pragma omp for schedule(dynamic, 256)
    for (size_t i = 0; i < nb; i++) {
      if (!stamp) continue;
      const double d2 =
          tgrid_d2(&g, m->xyz + 3 * (size_t)bn[i], stamp, (uint32_t)i + 1);
      const uint8_t f = flag_get(&flags[bn[i]]);
      const int far = !(sqrt(d2) / sdiag <= tol);
      if (f & F_BND) {
        worst = mx_max(worst, d2);
        if (far) {
          flag_or(&flags[bn[i]], F_OFF);
          off++;
        }
      }
      if (f & F_IFACE) {
        iworst = mx_max(iworst, d2);
        if (far) {
          flag_or(&flags[bn[i]], F_IOFF);
          ioff++;
        }
      }
    }
    mx_free(stamp);
  }
  tgrid_free(&g);
  mx_free(bn);
  if (oom) return MX_ENOMEM;
  if (nbnd) r->boundary_max_dist = sqrt(worst) / sdiag;
  r->boundary_off_surface = off;
  if (ni) r->interface_max_dist = sqrt(iworst) / sdiag;
  r->interface_off_surface = ioff;
  return MX_OK;
}
