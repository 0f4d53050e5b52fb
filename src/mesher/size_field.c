/* The size field of the octree mesher (issue 27): the function source,
 * its bounds and control space shared with the quadtree mesher
 * (mesher/size_source.h), the discrete sources (curvature, thickness, size
 * maps, sizes per element, the gradation: sizing/sources.h), and the whole
 * field built over the domain's box when the octree is
 * (mx_mesher_size_space), read by the refinement requests
 * (kernels/requests.h). */
#include <math.h>
#include <string.h>

#include "base/common.h"
#include "geom/surface_sizes.h"
#include "io/read_sizemap.h"
#include "kernels/estimate.h"
#include "mesher/mesher_impl.h"
#include "sizing/cspace.h"
#include "sizing/sources.h"
#include "soa/mesh.h"

/* The built field (rebuilt with the octree when a source changes). */
static void drop_built(mx_mesher *m) {
  mx_cspace_free(m->size.cs);
  m->size.cs = NULL;
  mx_size_sources_free(m->size_src);
  m->size_src = NULL;
  memset(&m->size_F, 0, sizeof m->size_F);
}

void mx_mesher_size_free(mx_mesher *m) {
  drop_built(m);
  mx_size_source_free(&m->size);
  mx_free(m->size_map_box);
  mx_free(m->size_map_h);
  mx_free(m->size_map_name);
  m->size_map_box = m->size_map_h = NULL;
  m->size_map_name = NULL;
  m->size_map_n = 0;
}

int mx_mesher_set_size_function(mx_mesher *m, mx_size_fn f, void *user,
                                const mx_cspace_params *p) {
  mx_call c;
  mx_call_begin(m, &c);
  const int st = mx_size_source_set_function(&m->size, f, user, p);
  if (!st) drop_built(m);
  return mx_call_end(m, &c, st);
}

int mx_mesher_set_size_expr(mx_mesher *m, const char *text) {
  mx_call c;
  mx_call_begin(m, &c);
  const int st = mx_size_source_set_expr(&m->size, text);
  if (!st) drop_built(m);
  return mx_call_end(m, &c, st);
}

int mx_mesher_set_size_limits(mx_mesher *m, double hmin, double hmax) {
  mx_call c;
  mx_call_begin(m, &c);
  const int st = mx_size_source_set_limits(&m->size, hmin, hmax);
  if (!st) drop_built(m);
  return mx_call_end(m, &c, st);
}

int mx_mesher_set_size_curvature(mx_mesher *m, double degrees) {
  mx_call c;
  mx_call_begin(m, &c);
  int st = MX_OK;
  if (!(degrees >= 0.0 && degrees < 180.0)) {
    mx_error(NULL, 0, "size field: the curvature angle must be in (0, 180) degrees (0: none), "
                      "not %g", degrees);
    st = MX_EINPUT;
  }
  if (!st) {
    drop_built(m);
    m->size_curvature = degrees * (3.14159265358979323846 / 180.0);
  }
  return mx_call_end(m, &c, st);
}

int mx_mesher_set_size_thickness(mx_mesher *m, double elements) {
  mx_call c;
  mx_call_begin(m, &c);
  int st = MX_OK;
  if (!(elements == 0.0 || (elements >= 1.0 && elements <= 64.0))) {
    mx_error(NULL, 0, "size field: the elements across a part or a gap must be 1 to 64 "
                      "(0: none), not %g", elements);
    st = MX_EINPUT;
  }
  if (!st) {
    drop_built(m);
    m->size_thickness = elements;
  }
  return mx_call_end(m, &c, st);
}

int mx_mesher_set_size_gradation(mx_mesher *m, double beta) {
  mx_call c;
  mx_call_begin(m, &c);
  int st = MX_OK;
  if (!(beta == 0.0 || (beta > 1.0 && beta <= 100.0))) {
    mx_error(NULL, 0, "size field: the gradation is the largest ratio of neighbouring sizes, "
                      "above 1 and at most 100 (0: the default), not %g", beta);
    st = MX_EINPUT;
  }
  if (!st) {
    drop_built(m);
    m->size_gradation = beta;
  }
  return mx_call_end(m, &c, st);
}

/* The map of n boxes (6 each: lo, hi) with sizes h, copied. */
static int set_map(mx_mesher *m, const double *box, const double *h, size_t n,
                   const char *name) {
  int st = MX_OK;
  for (size_t i = 0; i < n && !st; i++) {
    const double *p = box + 6 * i;
    int ok = h[i] > 0.0 && h[i] < INFINITY;
    for (int a = 0; a < 6; a++) ok = ok && isfinite(p[a]);
    if (!ok) {
      mx_error(name, 0, "size map: point %zu (%g, %g, %g) has the size %g: sizes must be "
                        "finite and positive, points finite", i + 1, p[0], p[1], p[2], h[i]);
      st = MX_EINPUT;
    }
  }
  double *b2 = NULL, *h2 = NULL;
  char *nm = NULL;
  if (!st && n) {
    b2 = mx_alloc(6 * n * sizeof *b2);
    h2 = mx_alloc(n * sizeof *h2);
    nm = mx_strdup(name ? name : "size map");
    if (!b2 || !h2 || !nm) st = MX_ENOMEM;
  }
  if (!st) {
    if (n) {
      memcpy(b2, box, 6 * n * sizeof *b2);
      memcpy(h2, h, n * sizeof *h2);
    }
    drop_built(m);
    mx_free(m->size_map_box);
    mx_free(m->size_map_h);
    mx_free(m->size_map_name);
    m->size_map_box = b2;
    m->size_map_h = h2;
    m->size_map_name = nm;
    m->size_map_n = n;
    b2 = h2 = NULL;
    nm = NULL;
  }
  mx_free(b2);
  mx_free(h2);
  mx_free(nm);
  return st;
}

/* The map of n points (3 each) with sizes h: boxes of no extent. */
static int set_points(mx_mesher *m, const double *xyz, const double *h, size_t n,
                      const char *name) {
  double *box = mx_alloc((6 * n + 1) * sizeof *box);
  if (!box) return MX_ENOMEM;
  for (size_t i = 0; i < n; i++) {
    memcpy(box + 6 * i, xyz + 3 * i, 3 * sizeof *box);
    memcpy(box + 6 * i + 3, xyz + 3 * i, 3 * sizeof *box);
  }
  const int st = set_map(m, box, h, n, name);
  mx_free(box);
  return st;
}

int mx_mesher_set_size_points(mx_mesher *m, const double *xyz, const double *h, size_t n,
                              const char *name) {
  mx_call c;
  mx_call_begin(m, &c);
  return mx_call_end(m, &c, set_points(m, xyz, h, n, name));
}

int mx_mesher_set_size_map(mx_mesher *m, const char *path, const char *field) {
  mx_call c;
  mx_call_begin(m, &c);
  double *xyz = NULL, *h = NULL;
  size_t n = 0;
  int st = path ? mx_sizemap_read(path, field, &xyz, &h, &n) : MX_EINPUT;
  if (!st) st = set_points(m, xyz, h, n, path);
  if (!st) mx_mesher_note_read(m, path, 0);
  mx_free(xyz);
  mx_free(h);
  return mx_call_end(m, &c, st);
}

int mx_mesher_set_size_elements(mx_mesher *m, const double *h, size_t n) {
  mx_call c;
  mx_call_begin(m, &c);
  const mx_mesh *M = &m->M;
  const int have = m->mesh_stage >= MX_STAGE_TRANSITION;
  if (!have || n != M->ncells) {
    mx_error(NULL, 0, "size per element: %zu sizes for a mesh of %zu elements", n,
             have ? M->ncells : (size_t)0);
    return mx_call_end(m, &c, MX_EINPUT);
  }
  double *box = mx_alloc((6 * n + 1) * sizeof *box);
  if (!box) return mx_call_end(m, &c, MX_ENOMEM);
#pragma omp parallel for schedule(static)
  for (size_t e = 0; e < n; e++) {
    const int nv = mx_cell_nodes[M->type[e]];
    for (int a = 0; a < 3; a++) {
      double lo = INFINITY, hi = -INFINITY;
      for (int k = 0; k < nv; k++) {
        const double v = M->xyz[3 * (size_t)M->conn[8 * e + k] + a];
        lo = fmin(lo, v);
        hi = fmax(hi, v);
      }
      box[6 * e + a] = lo;
      box[6 * e + 3 + a] = hi;
    }
  }
  const int st = set_map(m, box, h, n, "size per element");
  mx_free(box);
  return mx_call_end(m, &c, st);
}

/* Whether the mesher has a size field at all. */
int mx_mesher_has_size(const mx_mesher *m) {
  return mx_size_source_given(&m->size) || m->size_curvature > 0.0 ||
         m->size_thickness > 0.0 || m->size_map_n;
}

/* The octree the field asks for, against the memory there is, before
 * refining (an octree refined to a tiny size would fill the machine
 * first): the control space's cells and the sources', the root about the
 * domain's largest extent, none finer than the deepest level. */
static int budget(mx_mesher *m, const double lo[3], const double hi[3]) {
  double root = 0.0;
  for (int a = 0; a < 3; a++) root = fmax(root, hi[a] - lo[a]);
  double hmin = INFINITY, at[3] = {0, 0, 0}, h2, at2[3];
  double cells = 0.0;
  if (m->size.cs) cells += mx_size_source_cells(&m->size, 3, root, MX_MAX_LEVEL - 1, &hmin, at);
  if (m->size_src) {
    const double floor = ldexp(root, -(MX_MAX_LEVEL - 1));
    cells += mx_size_sources_cells(m->size_src, fmax(floor, m->size.min), 0.7, &h2, at2);
    if (h2 < hmin) {
      hmin = fmax(h2, m->size.min);
      memcpy(at, at2, sizeof at);
    }
  }
  const double need = mx_estimate_bytes_leaves((size_t)fmin(cells, 1e18), m->domain.nt,
                                               m->p.stage);
  const double avail = mx_available_bytes();
  const double limit = m->p.max_memory_mb > 0 ? m->p.max_memory_mb * 1048576.0 : avail;
  const int st = mx_size_source_budget(&m->size, 3, cells, hmin, at, need, limit,
                                       m->p.max_memory_mb > 0, "--max-memory");
  if (st) drop_built(m);
  return st;
}

/* The sources from the input surface: an index of the domain's triangles
 * of its own (the mesher's is built later, with the policies of the
 * boundary stage), every shell outward when there are materials. */
static int surface_sources(mx_mesher *m, mx_point_sizes *P) {
  if (!(m->size_curvature > 0.0) && !(m->size_thickness > 0.0)) return MX_OK;
  mx_surface_index S;
  MX_CHECK(m->p.materials ? mx_surface_index_build_outward(&S, &m->soup, 0, m->nt_domain)
                          : mx_surface_index_build(&S, &m->soup, 0, m->nt_domain));
  int st = MX_OK;
  size_t n0 = P->n;
  if (m->size_curvature > 0.0) st = mx_surface_curvature_sizes(&S, m->size_curvature, P);
  m->size_src_curvature = P->n - n0;
  n0 = P->n;
  if (!st && m->size_thickness > 0.0) st = mx_surface_thickness_sizes(&S, m->size_thickness, m->size.min, P);
  m->size_src_thickness = P->n - n0;
  mx_surface_index_free(&S);
  return st;
}

/* The size map's boxes, which must lie in the domain's box (grown by a
 * twentieth of its diagonal): a map in other units or of another part is
 * refused rather than read as sizes far away. */
static int map_check(const mx_mesher *m, const double lo[3], const double hi[3]) {
  double diag = 0.0;
  for (int a = 0; a < 3; a++) diag += (hi[a] - lo[a]) * (hi[a] - lo[a]);
  const double g = 0.05 * sqrt(diag);
  for (size_t i = 0; i < m->size_map_n; i++) {
    const double *p = m->size_map_box + 6 * i;
    for (int a = 0; a < 3; a++)
      if (p[a] < lo[a] - g || p[3 + a] > hi[a] + g) {
        mx_error(m->size_map_name, 0, "size map: point %zu (%g, %g, %g) lies outside the "
                                      "domain's box [%g, %g] x [%g, %g] x [%g, %g] (grown by "
                                      "%g): another part, or other units?", i + 1, p[0], p[1],
                 p[2], lo[0], hi[0], lo[1], hi[1], lo[2], hi[2], g);
        return MX_EINPUT;
      }
  }
  return MX_OK;
}

/* The discrete sources' tree: the surface's, the map's, and with an
 * explicit gradation the leaves of the function's control space (which
 * the graded field then replaces: it is no larger anywhere). */
static int build_sources(mx_mesher *m, const double lo[3], const double hi[3]) {
  m->size_src_curvature = m->size_src_thickness = m->size_src_map = m->size_src_graded = 0;
  const int graded_cs = m->size_gradation > 0.0 && m->size.cs;
  if (!(m->size_curvature > 0.0) && !(m->size_thickness > 0.0) && !m->size_map_n && !graded_cs)
    return MX_OK;
  mx_point_sizes P;
  memset(&P, 0, sizeof P);
  int st = surface_sources(m, &P);
  if (!st) st = map_check(m, lo, hi);
  const size_t npts = P.n, nmap = m->size_map_n;
  const size_t nleaves = graded_cs ? mx_cspace_leaves(m->size.cs, NULL, NULL) : 0;
  const size_t n = npts + nmap + nleaves;
  double *box = NULL, *h = NULL, *w = NULL;
  uint8_t *dim = NULL;
  if (!st && n) {
    box = mx_alloc(6 * n * sizeof *box);
    h = mx_alloc(n * sizeof *h);
    w = mx_alloc(n * sizeof *w);
    dim = mx_alloc(n * sizeof *dim);
    if (!box || !h || !w || !dim) st = MX_ENOMEM;
  }
  if (!st && n) {
    for (size_t i = 0; i < npts; i++) { /* the surface's: points standing for an area */
      memcpy(box + 6 * i, P.xyz + 3 * i, 3 * sizeof *box);
      memcpy(box + 6 * i + 3, P.xyz + 3 * i, 3 * sizeof *box);
      h[i] = P.h[i];
      w[i] = P.w[i];
      dim[i] = 2;
    }
    /* the map's: each point an equal share of the box's volume, each box
     * its own volume */
    double vol = 1.0;
    for (int a = 0; a < 3; a++) vol *= hi[a] - lo[a];
    for (size_t i = 0; i < nmap; i++) {
      const double *b = m->size_map_box + 6 * i;
      memcpy(box + 6 * (npts + i), b, 6 * sizeof *box);
      h[npts + i] = m->size_map_h[i];
      const double bv = (b[3] - b[0]) * (b[4] - b[1]) * (b[5] - b[2]);
      w[npts + i] = bv > 0.0 ? bv : vol / (double)nmap;
      dim[npts + i] = 3;
    }
    m->size_src_map = nmap;
    if (nleaves) {
      const size_t o = npts + nmap;
      mx_cspace_leaves(m->size.cs, box + 6 * o, h + o);
      for (size_t i = o; i < n; i++) {
        const double *b = box + 6 * i;
        w[i] = (b[3] - b[0]) * (b[4] - b[1]) * (b[5] - b[2]);
        dim[i] = 3;
        if (m->size.min > 0.0 && h[i] < m->size.min) h[i] = m->size.min;
        if (m->size.max > 0.0 && h[i] > m->size.max) h[i] = m->size.max;
      }
      m->size_src_graded = nleaves;
    }
    const double beta = m->size_gradation > 0.0 ? m->size_gradation : 2.0;
    st = mx_size_sources_build(box, h, w, dim, n, beta, &m->size_src);
  }
  mx_free(box);
  mx_free(h);
  mx_free(w);
  mx_free(dim);
  mx_point_sizes_free(&P);
  return st;
}

int mx_mesher_size_space(mx_mesher *m) {
  if (!mx_mesher_has_size(m) || m->size.cs || m->size_src) return MX_OK;
  double lo[3], hi[3];
  if (m->image_lattice)
    mx_image_world_box(m, lo, hi); /* the domain soup is the image's box in voxels */
  else
    mx_trisoup_bbox(&m->domain, lo, hi);
  MX_CHECK(mx_size_source_build(&m->size, lo, hi, NULL, NULL));
  if (m->size.cs) { /* its box: the domain's, a flat axis widened */
    memcpy(lo, m->size.params.lo, sizeof lo);
    memcpy(hi, m->size.params.hi, sizeof hi);
  } else {
    for (int a = 0; a < 3; a++)
      if (!(hi[a] > lo[a])) {
        lo[a] -= 0.5;
        hi[a] += 0.5;
      }
  }
  const int st = build_sources(m, lo, hi);
  if (st) {
    drop_built(m);
    return st;
  }
  m->size_F.cs = m->size_src && m->size_src_graded ? NULL : m->size.cs;
  m->size_F.src = m->size_src;
  m->size_F.hmin = m->size.min;
  m->size_F.hmax = m->size.max;
  memcpy(m->size_F.lo, lo, sizeof lo);
  memcpy(m->size_F.hi, hi, sizeof hi);
  return budget(m, lo, hi);
}
