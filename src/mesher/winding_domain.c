/* --repair-input on an input with no well-defined inside (issue 10, issue
 * 23): the domain is where the generalized winding number of all the
 * inputs together, as oriented in their files, is above 1/2.
 *
 * m->WI indexes the input (m->domain) with its orientation as given
 * (geom/distance.h, mx_surface_index_build_given): it decides the side
 * of every point, the octants' and the nodes'. The domain triangles of the
 * soup are replaced by the boundary of that domain
 * (kernels/winding_boundary.h): the parts of the input inside the union of
 * overlapping or touching bodies bound nothing and neither refine the
 * octree nor attract nodes. The volume rule compares the mesh with the
 * domain's volume (mx_winding_domain_volume). */
#include "mesher/mesher_impl.h"

#include <math.h>
#include <string.h>

#include "kernels/grid.h"
#include "kernels/winding_boundary.h"

int mx_winding_domain(mx_mesher *m, mx_trisoup *boundary) {
  memset(boundary, 0, sizeof *boundary);
  MX_CHECK(mx_surface_index_build_given(&m->WI, &m->domain, 0, (uint32_t)m->domain.nt));
  m->have_winding = 1;
  mx_winding_boundary_stats *ws = &m->rec->S.winding;
  MX_CHECK(mx_winding_boundary(&m->domain, &m->WI, boundary, ws));
  if (ws->kept == 0) {
    mx_error(m->domain_name[0], 0, "the generalized winding number of the input is above 1/2 "
             "nowhere (or everywhere): no domain to mesh (--repair-input); is the input "
             "oriented inside out?");
    return MX_EINPUT;
  }
  m->winding_whole = ws->whole;
  /* the boundary's signed volume, about the centre of its box */
  const mx_trisoup *b = boundary;
  double lo[3], hi[3], o[3];
  mx_trisoup_bbox(b, lo, hi);
  for (int a = 0; a < 3; a++) o[a] = 0.5 * (lo[a] + hi[a]);
  double vol = 0.0;
  for (size_t t = 0; t < b->nt; t++) {
    const uint32_t *v = b->tri + 3 * t;
    const double p[3] = {b->x[v[0]] - o[0], b->y[v[0]] - o[1], b->z[v[0]] - o[2]};
    const double q[3] = {b->x[v[1]] - o[0], b->y[v[1]] - o[1], b->z[v[1]] - o[2]};
    const double r[3] = {b->x[v[2]] - o[0], b->y[v[2]] - o[1], b->z[v[2]] - o[2]};
    vol += p[0] * (q[1] * r[2] - q[2] * r[1]) - p[1] * (q[0] * r[2] - q[2] * r[0]) +
           p[2] * (q[0] * r[1] - q[1] * r[0]);
  }
  m->winding_volume = vol / 6.0;
  return MX_OK;
}

/* The volume of the winding number's domain: the boundary's signed volume
 * when the winding number takes only whole values (closed bodies, however
 * they overlap or touch); otherwise (holes: the domain's boundary also runs
 * where no triangle is) a quadrature over the leaves of the octree, a leaf
 * that meets the boundary counting for the share of its 8 octant centres
 * where the winding number is above 1/2, another for its whole volume (the
 * octree keeps only the leaves inside or on the boundary). Summed in the
 * leaves' order: the same for any thread count. */
double mx_winding_domain_volume(const mx_mesher *m) {
  if (m->winding_whole || !m->have_tree || !m->nleaves) return m->winding_volume;
  const mx_octree *T = &m->B.tree.oct;
  double *lv = mx_alloc((m->nleaves + 1) * sizeof *lv);
  if (!lv) return m->winding_volume;
#pragma omp parallel for schedule(dynamic, 256)
  for (size_t i = 0; i < m->nleaves; i++) {
    const uint32_t o = m->leaves[i];
    double lo[3], hi[3];
    mx_octant_box(&m->B.tree.grid, T->key[o], T->level[o], lo, hi);
    const double v = (hi[0] - lo[0]) * (hi[1] - lo[1]) * (hi[2] - lo[2]);
    if (!(T->flags[o] & MX_OCT_SURFACE)) {
      lv[i] = v;
      continue;
    }
    int in = 0;
    for (int c = 0; c < 8; c++) {
      double p[3];
      for (int a = 0; a < 3; a++)
        p[a] = lo[a] + (((c >> a) & 1) ? 0.75 : 0.25) * (hi[a] - lo[a]);
      in += mx_winding_number(&m->WI, p) > 0.5;
    }
    lv[i] = v * in / 8.0;
  }
  double s = 0.0;
  for (size_t i = 0; i < m->nleaves; i++) s += lv[i];
  mx_free(lv);
  return s;
}
