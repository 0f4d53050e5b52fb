/* Pass 7c of the checker, the elements' regions (several materials, issue
 * 26): with a closed surface whose shells may nest, a point's region is its
 * nesting depth, the number of shells around it, told by geom/distance.h on
 * an index with every shell turned outward -- mx_region_depth (the side of
 * the closest shell's pseudonormal, the winding number where that side is
 * not told), or mx_inside when no shell nests in another -- never by what
 * the mesher recorded; with a surface of several files (touching inputs),
 * the region of the innermost piece around it (check_pieces.c). A point
 * within boundary_tol times the surface's diagonal of a triangle is on a
 * shell, and has no region of its own.
 *
 * Each node off the shells gets its region once; then each element is
 * judged at its centroid (when off the shells) and at its corners off the
 * shells: all in one region, that is the element's; in two, the element
 * lies across an interface (a defect, across_interface). An element whose
 * every point is on a shell (a sliver flat on it) has no region. About two
 * closest-point queries per node and per element: O((nodes + elements) x
 * log(triangles)) for points near the shells, in parallel. */
#include "verify/check_passes.h"

#include "geom/distance.h"

enum { ON_SHELL = -1 };

/* p's region, or ON_SHELL. */
static int region_at(const ck_locate *L, const double p[3], double on) {
  if (L->P) { /* several files: the pieces' (check_pieces.c) */
    if (mx_ck_pieces_on(L->P, p, on)) return ON_SHELL;
    const int d = mx_ck_pieces_region(L->P, p);
    return d > INT16_MAX ? INT16_MAX : d;
  }
  const mx_surface_index *S = L->S;
  if (mx_closest_point_within(S, p, 2.0 * on, NULL) <= on) return ON_SHELL;
  const int d = S->outward_closed || !S->closed ? mx_region_depth(S, p) : mx_inside(S, p);
  return d > INT16_MAX ? INT16_MAX : d;
}

/* Element c's region from its centroid's and its corners' (nreg: the
 * nodes'), -1 when none is off the shells, -2 across an interface (two[]:
 * the first two regions met). */
static int element_region(const mx_mesh_data *m, const ck_locate *L, const int16_t *nreg,
                          size_t c, double on, int two[2]) {
  double g[3];
  mx_ck_centroid(m, c, g);
  int reg = region_at(L, g, on);
  for (int j = 0; j < mx_cell_nodes[m->type[c]]; j++) {
    const int d = nreg[m->conn[8 * c + (size_t)j]];
    if (d < 0) continue;
    if (reg < 0) {
      reg = d;
    } else if (d != reg) {
      two[0] = reg;
      two[1] = d;
      return -2;
    }
  }
  return reg < 0 ? -1 : reg;
}

int mx_ck_element_regions(const mx_mesh_data *m, const mx_trisoup *surface,
                          const ck_locate *L, int16_t *reg, mx_check_report *r) {
  double lo[3], hi[3], diag2 = 0.0;
  mx_trisoup_bbox(surface, lo, hi);
  for (int a = 0; a < 3; a++) diag2 += (hi[a] - lo[a]) * (hi[a] - lo[a]);
  const double on = r->opt.boundary_tol * sqrt(diag2);
  const size_t nn = m->nnodes, nc = m->ncells;
  int16_t *nreg = mx_alloc((nn + 1) * sizeof *nreg);
  if (!nreg) return MX_ENOMEM;
#pragma omp parallel for schedule(dynamic, 1024) if (nn > SMALL / 4)
  for (size_t v = 0; v < nn; v++) nreg[v] = (int16_t)region_at(L, m->xyz + 3 * v, on);
  size_t across = 0;
#pragma omp parallel for schedule(dynamic, 512) reduction(+ : across) if (nc > SMALL / 4)
  for (size_t c = 0; c < nc; c++) {
    int two[2];
    reg[c] = (int16_t)element_region(m, L, nreg, c, on, two);
    across += reg[c] == -2;
  }
  mx_check_elems_at *x = &r->across_interface;
  x->n = across;
  for (size_t c = 0; c < nc && across && x->ids.n < MX_CHECK_LIST; c++) {
    if (reg[c] != -2) continue;
    if (x->ids.n == 0) {
      element_region(m, L, nreg, c, on, x->region);
      mx_ck_centroid(m, c, x->at);
    }
    x->ids.id[x->ids.n++] = (uint32_t)c;
  }
  mx_free(nreg);
  r->has_regions = 1;
  return MX_OK;
}
