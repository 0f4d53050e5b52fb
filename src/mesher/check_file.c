/* mx_check_file (include/mixoct.h), what `mixoct check` runs: reads a
 * volume mesh (legacy VTK, VTU, Gmsh MSH 4.1, Medit .mesh/.meshb, GetFEM,
 * M3D, MVM) and, optionally, the surface it should fill -- one file, or
 * several (the inputs of a run, touching or nested: appended in order, each
 * triangle's shell naming its file, which the checker's regions need) --,
 * runs the independent checker (verify/check.h) and reports
 * (check_file_report.c).
 *
 * A 2D mesh (io/read_mesh.h: mx_read_mesh_dim; triangles and
 * quadrilaterals in the plane z = 0, as mesher2d writes them to .vtu, .vtk,
 * .msh and .off) is checked by quad/qcheck.c instead, against the polylines
 * of its domain when given (poly, or surface with a .poly, a 2D .off or a
 * .mdl): the same criteria as mesher2d's own check (see check_2d below) and
 * a report of its own. A 3D surface with a 2D mesh, or polylines (poly, a
 * .poly) with a 3D mesh, are usage errors (status 2).
 *
 * A 3D mesh's feature distances (issue 29, item 5; verify/check.h): the
 * ridges and corners found on the surface at the feature angle (default
 * 30 degrees; geom/features.h), or read from a polylines file
 * (io/read_polylines.h), measured against the mesh's boundary edges and
 * nodes; reported, and defects only with a feature tolerance.
 *
 * A 3D mesh's hash (io/pvtu.h: mx_mesh_hash; the same for any node
 * numbering and cell order, so for a mesh and its .pvtu pieces) is
 * reported with it. Returns the program's exit status: 0 no defect, 5
 * defects found (the mesher's "meshed, but the result breaks the contract
 * of exit 0"; 3 is the mesher's out of memory), 2 bad input or usage (the
 * message names the file), 1 internal failure. */
#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <string.h>
#include <strings.h>

#include "base/common.h"
#include "geom/feature_walk.h"
#include "geom/surface_defects.h"
#include "io/pvtu.h"
#include "io/read_mesh.h"
#include "io/read_poly.h"
#include "io/read_polylines.h"
#include "io/read_surface.h"
#include "mesher/check_file.h"
#include "mesher/mesher2d.h"
#include "soa/trisoup.h"

enum { EXIT_DEFECTS = 5, EXIT_USAGE = 2 };

void mx_check_params_default(mx_check_params *p) {
  mx_check_options o;
  mx_check_defaults(&o);
  memset(p, 0, sizeof *p);
  p->volume_tol = o.volume_tol;
  p->dist_tol = o.boundary_tol;
  p->feature_angle = 30.0;
}

/* ---- 2D meshes ------------------------------------------------------------
 *
 * The criteria of mesher2d's own check (src/cli/mesher2d.c): a 2D mesh is
 * conforming with no bad edge and no hanging node, valid when moreover no
 * cell is inverted (quad/qcheck.c) and, against a domain, no boundary node
 * lies off its polylines (farther than dist_tol of its diameter), every
 * feature is a vertex, V - E + F equals the domain's outer loops minus its
 * holes, and the area error is within volume_tol (default: half a layer
 * of cells along the polylines, 0.5 P h / A with h = sqrt(area / cells),
 * 5% at least, 25% at most). */

enum { Q_AREA_AUTO = 0 };

static int has_ext(const char *path, const char *ext) {
  const size_t n = strlen(path), e = strlen(ext);
  return n > e && strcasecmp(path + n - e, ext) == 0;
}

/* The polylines of a 2D mesh's domain, read and checked. */
static int read_domain(const char *path, const char *mesh, mx_poly *P) {
  memset(P, 0, sizeof *P);
  if (!has_ext(path, ".poly") && !has_ext(path, ".off") && !has_ext(path, ".mdl")) {
    mx_error(path, 0, "check: a 3D surface, but %s is a 2D mesh: give its domain's polylines "
             "(--poly FILE: .poly, or a 2D .off or .mdl)", mesh);
    return MX_EINPUT;
  }
  int st = mx_read_poly_any(path, P);
  if (st == MX_EINPUT)
    mx_error(path, 0, "check: %s is a 2D mesh: its domain must be closed polylines in the "
             "plane z = 0 (.poly, or a 2D .off or .mdl)", mesh);
  if (st == MX_OK) st = mx_poly_check_domain(P);
  return st;
}

static int unused_nodes(const mx_qmesh *M, size_t *n) {
  uint8_t *used = mx_calloc(M->nnodes + 1);
  if (!used) return MX_ENOMEM;
#pragma omp parallel for schedule(static) if (M->ncells > 65536)
  for (size_t c = 0; c < M->ncells; c++)
    for (int j = 0; j < (M->type[c] == MX_QQUAD ? 4 : 3); j++) {
#pragma omp atomic write
      used[M->conn[4 * c + (size_t)j]] = 1;
    }
  size_t k = 0;
#pragma omp parallel for schedule(static) reduction(+ : k) if (M->nnodes > 65536)
  for (size_t i = 0; i < M->nnodes; i++) k += !used[i];
  mx_free(used);
  *n = k;
  return MX_OK;
}

/* The checks and the verdict. */
static int check_2d(const mx_qmesh *M, const mx_poly *P, const char *domain, double area_tol,
                    double dist_tol, mx_check_file_2d *k) {
  memset(k, 0, sizeof *k);
  k->domain = domain;
  k->dist_tol = dist_tol;
  mx_qquality_measure(M, &k->q);
  MX_CHECK(unused_nodes(M, &k->unused_nodes));
  MX_CHECK(mx_qmesh_check(M, P, dist_tol, &k->c));
  const mx_qcheck_report *c = &k->c;
  k->empty = M->ncells == 0 || M->nnodes == 0;
  k->defects = k->empty + c->bad_edges + c->hanging + c->inverted;
  if (!P) return MX_OK;
  k->area_tol = area_tol;
  if (area_tol == Q_AREA_AUTO) {
    k->area_tol = mx_qarea_tolerance(P, c, M->ncells);
    k->area_tol_auto = 1;
  }
  k->topology_off = c->euler != c->domain_euler;
  k->area_off = !(c->area_error <= k->area_tol);
  k->defects += c->off_boundary + c->missing_features + k->topology_off + k->area_off;
  return MX_OK;
}

/* A 2D mesh's check and report: q is freed here. */
static int check_file_2d(const mx_check_params *p, mx_qmesh *q, const char *domain, double t0) {
  mx_poly P;
  memset(&P, 0, sizeof P);
  int st = domain ? read_domain(domain, p->mesh, &P) : MX_OK;
  const double t1 = mx_wtime();
  mx_check_file_2d k;
  if (st == MX_OK) st = check_2d(q, domain ? &P : NULL, domain, p->volume_tol, p->dist_tol, &k);
  const double t2 = mx_wtime();
  mx_poly_free(&P);
  if (st == MX_OK) {
    if (p->json)
      mx_check_file_json_2d(q, &k);
    else if (!p->quiet)
      mx_check_file_text_2d(p->mesh, q, &k, t1 - t0, t2 - t1);
    fflush(stdout);
  }
  mx_qmesh_free(q);
  if (st != MX_OK) return st == MX_EINPUT ? EXIT_USAGE : 1;
  return k.defects ? EXIT_DEFECTS : 0;
}

/* ---- 3D meshes ----------------------------------------------------------- */

/* The surface the mesh should fill, read and checked; inconsistently
 * oriented triangles turned over (as the mesher does), so that the
 * enclosed volume is the surface's. */
static int read_surface(const char *path, mx_trisoup *s) {
  int st = mx_read_surface(path, s);
  if (st == MX_OK) st = mx_trisoup_check(s, path, NULL);
  mx_surface_defects sd;
  if (st == MX_OK && mx_surface_defects_find(s, &sd) == MX_OK && sd.misoriented_edges &&
      !sd.boundary_edges && !sd.nonmanifold_edges) {
    size_t flipped = 0;
    st = mx_surface_orient(s, &flipped);
  }
  return st;
}

/* Several surface files, each read and checked as above, appended in
 * order into s: triangle t's shell is the number of its file. */
static int read_surfaces(const char *const *list, int n, mx_trisoup *s) {
  int st = MX_OK;
  for (int i = 0; i < n && st == MX_OK; i++) {
    mx_trisoup one;
    memset(&one, 0, sizeof one);
    st = read_surface(list[i], &one);
    if (st == MX_OK) {
      st = mx_trisoup_append(s, &one); /* its message says why it fails */
      if (st == MX_EINPUT) mx_error(list[i], 0, "check: this surface file not added");
    }
    mx_trisoup_free(&one);
  }
  return st;
}

/* The feature distances (issue 29, item 5): the lines read from the
 * polylines file p->features, or found on the surface s (NULL: none) at
 * p->feature_angle; measured against m's boundary (verify/check_features.c);
 * over the tolerance, defects. diag: the surface's (NAN: none). */
static int feature_distances(const mx_check_params *p, const mx_mesh_data *m,
                             const mx_trisoup *s, double diag, mx_check_file_features *f) {
  memset(f, 0, sizeof *f);
  f->file = p->features;
  f->angle = p->feature_angle;
  f->tol = p->feature_tol;
  if (!p->features && (!s || !(p->feature_angle > 0.0))) return MX_OK;
  if (!(p->feature_angle >= 0.0 && p->feature_angle < 180.0)) {
    mx_error(NULL, 0, "check: feature angle %g: expected 0 to 180 degrees (exclusive)",
             p->feature_angle);
    return MX_EINPUT;
  }
  mx_feature_lines L;
  memset(&L, 0, sizeof L);
  int st;
  if (p->features) {
    st = mx_read_polylines(p->features, p->feature_angle, &L);
  } else {
    mx_features F;
    st = mx_features_detect(s, s->nt, p->feature_angle, &F);
    if (st == MX_OK) {
      st = mx_feature_lines_of(s, &F, &L);
      mx_features_free(&F);
    }
  }
  if (st == MX_OK) st = mx_check_features_mesh(m, &L, &f->d);
  mx_feature_lines_free(&L);
  if (st != MX_OK) return st;
  f->measured = 1;
  f->diagonal = isfinite(diag) && diag > 0.0 ? diag : f->d.diagonal;
  if (f->tol > 0.0) /* infinite distances (no boundary) are off too */
    f->off = (f->d.ridge_dist > f->tol * f->diagonal) + (f->d.corner_dist > f->tol * f->diagonal);
  return MX_OK;
}

/* The check and report of the mesh read in m (freed here); the surface
 * files list[0 .. n). */
static int check_file_3d(const mx_check_params *p, const char *const *list, int n,
                         mx_mesh_data *m, double t0) {
  const char *surf = n ? list[0] : NULL;
  mx_trisoup s;
  memset(&s, 0, sizeof s);
  int st = n == 1 ? read_surface(surf, &s) : n > 1 ? read_surfaces(list, n, &s) : MX_OK;
  const double t1 = mx_wtime();
  mx_check_options opt;
  mx_check_defaults(&opt);
  opt.volume_tol = p->volume_tol;
  opt.boundary_tol = p->dist_tol;
  mx_check_report r;
  mx_check_tags tags;
  memset(&tags, 0, sizeof tags);
  if (st == MX_OK) st = mx_check_mesh_tags(m, surf ? &s : NULL, &opt, &r, &tags);
  mx_check_file_features f;
  double diag = NAN;
  if (st == MX_OK && surf) {
    double lo[3], hi[3];
    mx_trisoup_bbox(&s, lo, hi);
    diag = sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                (hi[2] - lo[2]) * (hi[2] - lo[2]));
  }
  if (st == MX_OK) st = feature_distances(p, m, surf ? &s : NULL, diag, &f);
  const mx_mesh_view hv = mx_mesh_data_view(m);
  const uint64_t hash = st == MX_OK ? mx_mesh_hash(&hv) : 0;
  const double t2 = mx_wtime();
  mx_mesh_data_free(m);
  mx_trisoup_free(&s);
  if (st != MX_OK) {
    mx_check_tags_free(&tags);
    return st == MX_EINPUT ? EXIT_USAGE : 1;
  }
  if (p->json)
    mx_check_file_json(&r, &tags, hash, &f);
  else if (!p->quiet)
    mx_check_file_text(p->mesh, list, n, &r, &tags, hash, &f, t1 - t0, t2 - t1);
  fflush(stdout);
  mx_check_tags_free(&tags);
  return r.defects + f.off ? EXIT_DEFECTS : 0;
}

/* ---- The call ------------------------------------------------------------ */

/* The file read; a 2D mesh and its domain, or a 3D mesh and its surface,
 * checked and reported. */
static int check_file(const mx_check_params *p) {
  const char *poly = p->poly;
  if (!p->mesh) {
    mx_error(NULL, 0, "check: no mesh file given");
    return EXIT_USAGE;
  }
  /* the surface files: one (surface) or several (surfaces) */
  const char *const *list = p->nsurfaces > 0 ? p->surfaces : p->surface ? &p->surface : NULL;
  const int nsurf = p->nsurfaces > 0 ? p->nsurfaces : p->surface ? 1 : 0;
  if (p->nsurfaces > 0 && p->surface) {
    mx_error(NULL, 0, "check: a surface and a list of surfaces both given: one or the other");
    return EXIT_USAGE;
  }
  for (int i = 0; i < nsurf; i++)
    if (!list[i]) {
      mx_error(NULL, 0, "check: surface file %d of %d not named", i + 1, nsurf);
      return EXIT_USAGE;
    }
  const char *surf = nsurf ? list[0] : NULL;
  if (poly && surf) {
    mx_error(NULL, 0, "check: --poly and --surface both given: one domain at most");
    return EXIT_USAGE;
  }
  const double t0 = mx_wtime();
  mx_mesh_data m;
  int dim = 3;
  int st = mx_read_mesh_dim(p->mesh, &m, &dim);
  if (st == MX_OK && dim == 2 && p->features) {
    mx_error(p->features, 0, "check: feature polylines, but %s is a 2D mesh (its features "
             "are checked against --poly)", p->mesh);
    mx_mesh_data_free(&m);
    return EXIT_USAGE;
  }
  if (st == MX_OK && dim == 2) {
    mx_qmesh q;
    memset(&q, 0, sizeof q);
    st = mx_qmesh_from_faces(&m, &q);
    mx_mesh_data_free(&m);
    if (st == MX_OK && nsurf > 1) {
      mx_error(list[1], 0, "check: %s is a 2D mesh: one domain (--poly FILE), not several "
               "surfaces", p->mesh);
      mx_qmesh_free(&q);
      return EXIT_USAGE;
    }
    if (st == MX_OK) return check_file_2d(p, &q, poly ? poly : surf, t0);
  }
  const char *polys = poly;
  for (int i = 0; i < nsurf && !polys; i++)
    if (has_ext(list[i], ".poly")) polys = list[i];
  if (st == MX_OK && polys) {
    mx_error(polys, 0, "check: polylines, but %s is a 3D mesh: give the closed "
             "surface it fills (--surface FILE: .off, .stl, .obj, .mdl, .ply)", p->mesh);
    mx_mesh_data_free(&m);
    return EXIT_USAGE;
  }
  if (st != MX_OK) {
    mx_mesh_data_free(&m); /* what a failed reader left, if anything */
    return st == MX_EINPUT ? EXIT_USAGE : 1;
  }
  return check_file_3d(p, list, nsurf, &m, t0);
}

int mx_check_file(const mx_check_params *p) {
  const int quiet = mx_quiet, threads = omp_get_max_threads();
  if (p->quiet) mx_quiet = 1;
  if (p->threads > 0) omp_set_num_threads(p->threads);
  const int status = check_file(p);
  if (p->threads > 0) omp_set_num_threads(threads);
  mx_quiet = quiet;
  return status;
}
