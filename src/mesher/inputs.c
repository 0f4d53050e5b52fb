/* The mesher's inputs and requests (include/mixoct.h: surfaces, the demo,
 * region surfaces, boxes, levels) and their assembly, once, into the soup
 * the octree is built over (mx_mesher_assemble_inputs): the input policy
 * (defects refused, or the winding number's domain with --repair-input;
 * inconsistent orientation fixed), the domain's triangles first, then each
 * region's. The single-process mesher and the distributed path
 * (mpi/p4est_inputs.c) both take it. */
#include "mesher/materials.h"
#include "sizing/cspace.h"
#include "mesher/mesher_impl.h"

#include "io/demo_surface.h"
#include "io/read_surface.h"
#include "kernels/estimate.h"
#include "kernels/grid.h"
#include "kernels/mesh_edit.h"
#include "kernels/closures.h"
#include "kernels/edges_lazy.h"
#include "kernels/refine_list.h"
#include "kernels/splice.h"
#include "geom/surface_defects.h"
#include "soa/mesh.h"

#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---- inputs and requests ---------------------------------------------- */

static int refuse_after_build(const mx_mesher *m, const char *what) {
  if (!m->assembled) return MX_OK;
  mx_error(NULL, 0, "%s must be added before the first mesh", what);
  return MX_EINPUT;
}

int mx_mesher_add_domain(mx_mesher *m, mx_trisoup *s, const char *name) {
  MX_CHECK(refuse_after_build(m, "domain surfaces"));
  if (m->ndomain >= 64) {
    mx_error(name, 0, "too many input surfaces (at most 64)");
    return MX_EINPUT;
  }
  char *nm = mx_strdup(name);
  if (!nm) return MX_ENOMEM;
  int st = mx_trisoup_append(&m->domain, s);
  if (st) {
    mx_free(nm);
    return st;
  }
  m->domain_name[m->ndomain++] = nm;
  return MX_OK;
}

void mx_mesher_note_read(mx_mesher *m, const char *path, int restart) {
  const int cap = (int)(sizeof m->read_id / sizeof m->read_id[0]);
  mx_file_id id;
  if (m->nread == cap || !mx_file_id_of(path, &id)) return;
  for (int i = 0; i < m->nread; i++)
    if (m->read_id[i].dev == id.dev && m->read_id[i].ino == id.ino) {
      m->read_restart[i] &= (uint8_t)restart; /* an input in any other role */
      return;
    }
  m->read_id[m->nread] = id;
  m->read_restart[m->nread++] = (uint8_t)restart;
}

int mx_mesher_spares_inputs(const mx_mesher *m, const char *path, int restart_out) {
  mx_file_id id;
  if (!mx_file_id_of(path, &id)) return MX_OK; /* a new file */
  for (int i = 0; i < m->nread; i++) {
    if (m->read_id[i].dev != id.dev || m->read_id[i].ino != id.ino) continue;
    if (restart_out && m->read_restart[i]) return MX_OK; /* the re-meshing loop */
    mx_error(path, 0, "this file was read as an input of the mesh: writing it would "
                      "replace the input; nothing was written, choose another name");
    return MX_EINPUT;
  }
  return MX_OK;
}

/* What a message about the mesh as a whole names: the input file, or
 * "the inputs a, b" when there are several (cut with ", ..." past n bytes);
 * NULL without an input. */
const char *mx_inputs_label(const mx_mesher *m, char *buf, size_t n) {
  if (m->ndomain == 0 || n == 0) return NULL;
  if (m->ndomain == 1) return m->domain_name[0];
  size_t w = (size_t)snprintf(buf, n, "the inputs %s", m->domain_name[0]);
  for (int i = 1; i < m->ndomain && w < n; i++) {
    const size_t len = strlen(m->domain_name[i]);
    if (w + 2 + len + 5 >= n) { /* room for ", ..." */
      snprintf(buf + w, n - w, ", ...");
      break;
    }
    w += (size_t)snprintf(buf + w, n - w, ", %s", m->domain_name[i]);
  }
  return buf;
}

int mx_mesher_add_surface(mx_mesher *m, const char *path) {
  mx_call c;
  mx_call_begin(m, &c);
  mx_trisoup s;
  memset(&s, 0, sizeof s);
  const double t = mx_wtime();
  int st = path ? MX_OK : MX_EINPUT;
  if (!path) mx_error(NULL, 0, "no surface file given");
  if (!st && mx_is_label_image_path(path)) { /* a label image: its own inputs */
    st = mx_mesher_add_label_image(m, path, NULL);
    m->rec->S.ph.read += mx_wtime() - t;
    return mx_call_end(m, &c, st);
  }
  if (!st) st = mx_read_surface(path, &s);
  if (!st) st = mx_trisoup_check(&s, path, NULL);
  if (!st) st = mx_mesher_add_domain(m, &s, path);
  if (!st) mx_mesher_note_read(m, path, 0);
  mx_trisoup_free(&s);
  m->rec->S.ph.read += mx_wtime() - t;
  return mx_call_end(m, &c, st);
}

int mx_mesher_add_input(mx_mesher *m, const char *path, int material, const char *material_name,
                        int surface_level, int inside_level) {
  MX_CHECK(mx_mesher_add_surface(m, path));
  /* the input just added: the last one (after --demo too) */
  const int input = m->ndomain - 1;
  if (material) MX_CHECK(mx_mesher_set_material(m, input, material, material_name));
  if (surface_level || inside_level)
    MX_CHECK(mx_mesher_set_input_level(m, input, surface_level, inside_level));
  return MX_OK;
}

int mx_mesher_add_surface_arrays(mx_mesher *m, const char *name, size_t nv,
                                 const double *xyz, size_t nt,
                                 const uint32_t *tri) {
  mx_call c;
  mx_call_begin(m, &c);
  if (!name) name = "(arrays)";
  mx_trisoup s;
  memset(&s, 0, sizeof s);
  int st = MX_OK;
  if (nv == 0 || nt == 0 || !xyz || !tri) {
    mx_error(name, 0, "empty surface (%zu points, %zu triangles)", nv, nt);
    st = MX_EINPUT;
  }
  if (!st) st = mx_trisoup_reserve(&s, nv, nt);
  for (size_t i = 0; !st && i < nv; i++) {
    for (int a = 0; a < 3; a++)
      if (!(xyz[3 * i + a] == xyz[3 * i + a]) || xyz[3 * i + a] > 1e300 ||
          xyz[3 * i + a] < -1e300) {
        mx_error(name, 0, "point %zu: coordinate %d is not a finite number", i, a);
        st = MX_EINPUT;
        break;
      }
    if (!st) st = mx_trisoup_set_vertex(&s, i, xyz + 3 * i);
  }
  for (size_t t = 0; !st && t < nt; t++) {
    const uint32_t *v = tri + 3 * t;
    if (v[0] >= nv || v[1] >= nv || v[2] >= nv) {
      mx_error(name, 0, "triangle %zu: index out of range (%zu points)", t, nv);
      st = MX_EINPUT;
    } else {
      st = mx_trisoup_add_triangle(&s, v[0], v[1], v[2]);
    }
  }
  if (!st) st = mx_trisoup_check(&s, name, NULL);
  if (!st) st = mx_mesher_add_domain(m, &s, name);
  mx_trisoup_free(&s);
  return mx_call_end(m, &c, st);
}

int mx_mesher_add_demo_surface(mx_mesher *m) {
  mx_call c;
  mx_call_begin(m, &c);
  mx_trisoup s;
  memset(&s, 0, sizeof s);
  const double t = mx_wtime();
  int st = mx_demo_surface(&s, 4);
  if (!st) st = mx_mesher_add_domain(m, &s, "--demo");
  mx_trisoup_free(&s);
  m->rec->S.ph.read += mx_wtime() - t;
  return mx_call_end(m, &c, st);
}

static int check_level(const char *what, int level, int allow_none) {
  if ((allow_none && level == -1) || (level >= 0 && level <= MX_MAX_LEVEL - 1))
    return MX_OK;
  mx_error(NULL, 0, "%s level %d out of range (0..%d)", what, level, MX_MAX_LEVEL - 1);
  return MX_EINPUT;
}

int mx_mesher_add_region_surface(mx_mesher *m, const char *path, int level) {
  mx_call c;
  mx_call_begin(m, &c);
  int st = refuse_after_build(m, "region surfaces");
  if (!st) st = check_level("region surface", level, 0);
  if (!st && m->nregions >= MX_MAX_REGIONS) {
    mx_error(path, 0, "too many region surfaces (at most %d)", MX_MAX_REGIONS);
    st = MX_EINPUT;
  }
  if (!st) {
    const int r = m->nregions;
    memset(&m->region[r], 0, sizeof m->region[r]);
    st = mx_read_surface(path, &m->region[r]);
    if (!st) st = mx_trisoup_check(&m->region[r], path, NULL);
    char *name = st ? NULL : mx_strdup(path);
    if (!st && !name) st = MX_ENOMEM;
    if (!st) {
      mx_mesher_note_read(m, path, 0);
      m->region_name[r] = name;
      m->region_level[r] = level;
      m->nregions++;
    } else {
      mx_trisoup_free(&m->region[r]);
    }
  }
  return mx_call_end(m, &c, st);
}

static int push_box(mx_mesher *m, const mx_box_region *b) {
  mx_box_region *g = mx_realloc(m->boxes, (m->nboxes + 1) * sizeof *g);
  if (!g) return MX_ENOMEM;
  m->boxes = g;
  g[m->nboxes++] = *b;
  return MX_OK;
}

int mx_mesher_add_box(mx_mesher *m, const double lo[3], const double hi[3], int level) {
  mx_call c;
  mx_call_begin(m, &c);
  int st = check_level("box", level, 0);
  mx_box_region b;
  for (int a = 0; !st && a < 3; a++) {
    if (!(lo[a] <= hi[a])) {
      mx_error(NULL, 0, "box: min corner above max corner (or not a number) on axis %d", a);
      st = MX_EINPUT;
    }
    b.lo[a] = lo[a];
    b.hi[a] = hi[a];
  }
  b.level = level;
  if (!st) st = push_box(m, &b);
  return mx_call_end(m, &c, st);
}

int mx_mesher_read_boxes(mx_mesher *m, const char *path) {
  mx_call c;
  mx_call_begin(m, &c);
  mx_box_region *b = NULL;
  size_t n = 0;
  int st = mx_read_reg(path, &b, &n);
  for (size_t i = 0; !st && i < n; i++) st = push_box(m, &b[i]);
  if (!st) mx_mesher_note_read(m, path, 0);
  mx_free(b);
  return mx_call_end(m, &c, st);
}

int mx_mesher_set_levels(mx_mesher *m, int surface_level, int all_level) {
  mx_call c;
  mx_call_begin(m, &c);
  int st = check_level("surface", surface_level, 1);
  if (!st) st = check_level("all", all_level, 1);
  if (!st) {
    m->p.surface_level = surface_level;
    m->p.all_level = all_level;
  }
  return mx_call_end(m, &c, st);
}

/* The requests as the kernels take them (boxes point into m->boxes). */
mx_requests mx_mesher_requests(const mx_mesher *m) {
  mx_requests r;
  memset(&r, 0, sizeof r);
  r.s_level = m->p.surface_level;
  r.a_level = m->p.all_level;
  r.boxes = m->boxes;
  r.nboxes = m->nboxes;
  r.nregions = m->nregions;
  for (int i = 0; i < m->nregions; i++) r.rlevel[i] = m->region_level[i];
  r.meet_only = m->region_meet_only;
  if (m->size_F.cs || m->size_F.src) r.size_field = &m->size_F;
  return r;
}

int mx_mesher_set_input_level(mx_mesher *m, int input, int surface_level, int inside_level) {
  mx_call c;
  mx_call_begin(m, &c);
  int st = refuse_after_build(m, "input levels");
  if (!st && (input < 0 || input >= m->ndomain)) {
    mx_error(NULL, 0, "input level: no input %d (%d surface(s) added)", input, m->ndomain);
    st = MX_EINPUT;
  }
  if (!st) st = check_level("input surface", surface_level, 0);
  if (!st) st = check_level("input inside", inside_level, 0);
  if (!st) {
    m->input_slevel[input] = (int8_t)surface_level;
    m->input_ilevel[input] = (int8_t)inside_level;
  }
  return mx_call_end(m, &c, st);
}

/* The inputs given a level of their own (mx_mesher_set_input_level): each
 * level a region surface of the input's triangles (as given: src, shell
 * ids the inputs), refined where met for a surface level, where met or
 * inside for an inside level. */
static int input_level_regions(mx_mesher *m, const mx_trisoup *src) {
  for (int k = 0; k < m->ndomain && k < 64; k++)
    for (int inside = 0; inside < 2; inside++) {
      const int level = inside ? m->input_ilevel[k] : m->input_slevel[k];
      if (level <= 0) continue;
      if (m->nregions >= MX_MAX_REGIONS) {
        mx_error(m->domain_name[k], 0, "input level %d: the region surfaces' places (%d) "
                                       "are all taken", level, MX_MAX_REGIONS);
        return MX_EINPUT;
      }
      const int r = m->nregions;
      mx_trisoup *s = &m->region[r];
      memset(s, 0, sizeof *s);
      int st = MX_OK;
      for (size_t v = 0; v < src->nv && !st; v++) {
        const double c[3] = {src->x[v], src->y[v], src->z[v]};
        st = mx_trisoup_set_vertex(s, v, c);
      }
      for (size_t t = 0; t < src->nt && !st; t++)
        if (src->shell[t] == k)
          st = mx_trisoup_add_triangle(s, src->tri[3 * t], src->tri[3 * t + 1], src->tri[3 * t + 2]);
      char *name = st ? NULL : mx_strdup(m->domain_name[k]);
      if (!st && !name) st = MX_ENOMEM;
      if (st) {
        mx_trisoup_free(s);
        return st;
      }
      m->region_name[r] = name;
      m->region_level[r] = level;
      if (!inside) m->region_meet_only |= 1u << r;
      m->nregions++;
    }
  return MX_OK;
}

/* Domain then region triangles in one soup, checked once. */
/* The signed volume the triangles enclose (their orientation counts: holes
 * oriented inward subtract); *area (may be NULL) gets their area. */
double mx_enclosed_volume(const mx_trisoup *d, double *area) {
  double vol = 0.0, ar = 0.0;
  for (size_t t = 0; t < d->nt; t++) {
    const uint32_t *v = d->tri + 3 * t;
    const double a[3] = {d->x[v[0]], d->y[v[0]], d->z[v[0]]};
    const double b[3] = {d->x[v[1]], d->y[v[1]], d->z[v[1]]};
    const double c[3] = {d->x[v[2]], d->y[v[2]], d->z[v[2]]};
    vol += a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) +
           a[2] * (b[0] * c[1] - b[1] * c[0]);
    const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    const double w[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    const double x = u[1] * w[2] - u[2] * w[1], y = u[2] * w[0] - u[0] * w[2],
                 z = u[0] * w[1] - u[1] * w[0];
    ar += 0.5 * sqrt(x * x + y * y + z * z);
  }
  if (area) *area = ar;
  return vol / 6.0;
}

/* The input policy (issue 10): a closed, manifold domain is oriented
 * consistently and outward (a warning when triangles were flipped); one
 * with no well-defined inside (open or non-manifold edges, triangles that
 * cross, two inputs that cross) is refused naming the defects, or, with
 * params.repair_input, meshed where its generalized winding number is above
 * 1/2. */
static int input_policy(mx_mesher *m) {
  mx_trisoup *d = &m->domain;
  mx_surface_defects r;
  MX_CHECK(mx_surface_defects_find(d, &r));
  const char *first = m->domain_name[0];
  if (!r.boundary_edges && !r.nonmanifold_edges) {
    size_t flipped = 0;
    if (r.misoriented_edges) {
      /* each piece consistent and outward (a hole among them would need
       * its nesting: a warning says what was flipped) */
      MX_CHECK(mx_surface_orient(d, &flipped));
    } else {
      /* consistent: only a domain inside out (negative enclosed volume,
       * holes counted by their own orientation) is turned over */
      if (mx_enclosed_volume(d, NULL) < 0.0) {
        for (size_t t = 0; t < d->nt; t++) {
          const uint32_t tmp = d->tri[3 * t + 1];
          d->tri[3 * t + 1] = d->tri[3 * t + 2];
          d->tri[3 * t + 2] = tmp;
        }
        flipped = d->nt;
      }
    }
    if (flipped) {
      mx_warning(m->ndomain == 1 ? first : NULL, 0,
                 "%zu triangle(s) re-oriented: the surface%s inconsistently oriented or "
                 "inside out", flipped, m->ndomain == 1 ? " was" : "s were");
      MX_CHECK(mx_surface_defects_find(d, &r));
    }
    m->rec->S.reoriented = flipped;
  }
  const size_t bad = r.boundary_edges + r.nonmanifold_edges + r.misoriented_edges +
                     r.intersecting_pairs + r.crossing_pairs;
  if (!bad) return MX_OK;
  char what[4096];
  mx_surface_defects_describe(&r, d, what, sizeof what);
  /* the file of the first defect found */
  const mx_defect_example *ex = r.boundary_edges      ? &r.boundary[0]
                                : r.nonmanifold_edges ? &r.nonmanifold[0]
                                : r.misoriented_edges ? &r.misoriented[0]
                                : r.intersecting_pairs ? &r.intersecting[0]
                                                       : &r.crossing[0];
  const uint16_t sh = ex->tri < d->nt ? d->shell[ex->tri] : 0;
  const char *name = sh < m->ndomain ? m->domain_name[sh] : first;
  size_t n = strlen(what);
  while (n && what[n - 1] == '\n') what[--n] = '\0';
  for (char *c = what; *c; c++)
    if (*c == '\n') *c = ';'; /* one message line */
  if (!m->p.repair_input) {
    mx_error(name, 0, "the input has no well-defined inside, refused: %s. With "
                      "--repair-input (mx_params.repair_input) the domain is where the "
                      "generalized winding number of the input is above 1/2", what);
    return MX_EINPUT;
  }
  mx_warning(name, 0, "the input has no well-defined inside: %s. The domain is where its "
                      "generalized winding number is above 1/2 (--repair-input)", what);
  m->rec->S.input_repaired = 1;
  return MX_OK;
}

int mx_mesher_assemble_inputs(mx_mesher *m) {
  if (m->assembled) return MX_OK;
  if (m->ndomain == 0) {
    mx_error(NULL, 0, "no input surface: add one (-i FILE) or the demo (--demo)");
    return MX_EINPUT;
  }
  /* two inputs with a triangle in common are refused, but for the winding
   * number's domain (a face two touching bodies share bounds nothing) */
  int levels = 0;
  for (int k = 0; k < m->ndomain && k < 64; k++) levels |= m->input_slevel[k] | m->input_ilevel[k];
  if (levels) {
    /* the inputs' own levels, from their triangles as given (a copy: the
     * domain's soup may lose its common faces below) */
    mx_trisoup given;
    memset(&given, 0, sizeof given);
    int st = mx_trisoup_append(&given, &m->domain);
    if (!st) memcpy(given.shell, m->domain.shell, m->domain.nt * sizeof *given.shell);
    if (!st) st = input_level_regions(m, &given);
    mx_trisoup_free(&given);
    MX_CHECK(st);
  }
  if (m->p.materials && !m->p.repair_input) MX_CHECK(mx_materials_split_shared(m));
  if (!m->p.repair_input)
    MX_CHECK(mx_trisoup_check_shells(&m->domain, (uint32_t)m->domain.nt,
                                     (const char *const *)m->domain_name));
  {
    /* a box the grid refuses (flat, coordinates out of range, too thin) is
     * reported as such before the defects are looked for */
    double lo[3], hi[3];
    mx_grid g;
    mx_trisoup_bbox(&m->domain, lo, hi);
    MX_CHECK(mx_grid_build(lo, hi, m->domain_name[0], &g));
  }
  MX_CHECK(input_policy(m));
  if (m->rec->S.input_repaired) {
    /* the boundary of the winding number's domain instead of the input */
    mx_trisoup b;
    int st = mx_winding_domain(m, &b);
    if (!st) st = mx_trisoup_append(&m->soup, &b);
    if (!st) memcpy(m->soup.shell, b.shell, b.nt * sizeof *m->soup.shell);
    mx_trisoup_free(&b);
    MX_CHECK(st);
  } else {
    MX_CHECK(mx_trisoup_append(&m->soup, &m->domain));
    /* one shell per input file, as the readers gave them */
    memcpy(m->soup.shell, m->domain.shell, m->domain.nt * sizeof *m->soup.shell);
  }
  m->soup.nshells = m->domain.nshells;
  m->nt_domain = (uint32_t)m->soup.nt;
  for (int r = 0; r < m->nregions; r++) {
    m->region_t0[r] = (uint32_t)m->soup.nt;
    MX_CHECK(mx_trisoup_append(&m->soup, &m->region[r]));
  }
  m->region_t0[m->nregions] = (uint32_t)m->soup.nt;
  m->assembled = 1;
  return MX_OK;
}

