/* The mesher object (include/mixoct.h): inputs and requests, the stages of
 * the pipeline as calls, the mesh as arrays. Re-meshing is in remesh.c, the
 * restart file in restart_octree.c. */
#include "mesher/mesher_impl.h"

#include "kernels/splice.h"
#include "geom/surface_defects.h"

#include "io/boundary_faces.h"
#include "kernels/estimate.h"
#include "kernels/grid.h"
#include "kernels/mesh_edit.h"
#include "kernels/remesh.h"
#include "kernels/splice.h"
#include "soa/mesh.h"

#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---- calls, messages, status ------------------------------------------ */

static void collect_message(void *user, int level, const char *text) {
  mx_mesher *m = user;
  if (level == MX_MSG_ERROR && !m->last_error[0])
    snprintf(m->last_error, sizeof m->last_error, "%s", text);
  if (m->fn)
    m->fn(m->user, level, text);
  else if (level == MX_MSG_ERROR || !mx_quiet)
    fprintf(stderr, "mixoct: %s%s\n", level == MX_MSG_ERROR ? "error: " : "warning: ",
            text);
}

void mx_call_begin(mx_mesher *m, mx_call *c) {
  mx_call_enter(c, collect_message, m, m->p.threads);
  m->last_error[0] = 0;
}

int mx_call_end(mx_mesher *m, mx_call *c, int status) {
  (void)m;
  return mx_call_leave(c, status);
}

const char *mx_status_string(int status) {
  switch (status) {
    case MX_OK: return "success";
    case MX_EINTERNAL: return "internal failure";
    case MX_EINPUT: return "bad input";
    case MX_ENOMEM: return "out of memory";
    case MX_EIO: return "output failure";
    case MX_EINVALID: return "invalid mesh";
    default: return "unknown status";
  }
}

void mx_params_default(mx_params *p) {
  memset(p, 0, sizeof *p);
  p->surface_level = -1;
  p->all_level = -1;
  p->stage = MX_STAGE_FULL;
  p->balance = MX_BALANCE_EDGES;
  p->repair_rounds = 10;
}

mx_mesher *mx_mesher_new(const mx_params *p) {
  mx_mesher *m = calloc(1, sizeof *m);
  if (!m) return NULL;
  if (p)
    m->p = *p;
  else
    mx_params_default(&m->p);
  if (m->p.close_ratio <= 0) m->p.close_ratio = MX_CLOSE_RATIO;
  if (m->p.staircase_quality <= 0) m->p.staircase_quality = 0.2;
  if (m->p.repair_rounds < 0) m->p.repair_rounds = 0;
  m->mesh_stage = -1;
  return m;
}

void mx_mesh_clear(mx_mesher *m) {
  mx_mesh_out_free(&m->M);
  memset(&m->M, 0, sizeof m->M);
  mx_free(m->states);
  mx_free(m->bnd);
  m->states = m->bnd = NULL;
  if (m->have_hex) mx_hexmesh_free(&m->hex);
  m->have_hex = 0;
  m->mesh_stage = -1;
}

void mx_tree_clear(mx_mesher *m) {
  mx_mesh_clear(m);
  if (m->have_tree) mx_builder_free(&m->B);
  memset(&m->B, 0, sizeof m->B);
  mx_free(m->leaves);
  m->leaves = NULL;
  m->nleaves = 0;
  m->have_tree = 0;
  mx_free(m->file_leaf);
  m->file_leaf = NULL;
  m->file_nelem = 0;
}

void mx_mesher_free(mx_mesher *m) {
  if (!m) return;
  mx_tree_clear(m);
  if (m->have_index) mx_surface_index_free(&m->SI);
  if (m->have_winding) mx_surface_index_free(&m->WI);
  mx_trisoup_free(&m->domain);
  mx_trisoup_free(&m->soup);
  for (int i = 0; i < m->ndomain; i++) free(m->domain_name[i]);
  for (int r = 0; r < m->nregions; r++) {
    mx_trisoup_free(&m->region[r]);
    free(m->region_name[r]);
  }
  mx_free(m->boxes);
  for (int l = 0; l <= MX_MAX_LEVEL; l++) mx_free(m->split_keys[l]);
  free(m);
}

void mx_mesher_set_message_handler(mx_mesher *m, mx_message_fn fn, void *user) {
  m->fn = fn;
  m->user = user;
}

const char *mx_mesher_last_error(const mx_mesher *m) { return m->last_error; }

const mx_summary *mx_mesher_summary(const mx_mesher *m) { return &m->S; }

void mx_free_array(void *p) { mx_free(p); }

/* ---- inputs and requests ---------------------------------------------- */

static int refuse_after_build(const mx_mesher *m, const char *what) {
  if (!m->assembled) return MX_OK;
  mx_error(NULL, 0, "%s must be added before the first mesh", what);
  return MX_EINPUT;
}

static int add_domain(mx_mesher *m, mx_trisoup *s, const char *name) {
  MX_CHECK(refuse_after_build(m, "domain surfaces"));
  if (m->ndomain >= 64) {
    mx_error(name, 0, "too many input surfaces (at most 64)");
    return MX_EINPUT;
  }
  char *nm = strdup(name);
  if (!nm) return MX_ENOMEM;
  int st = mx_trisoup_append(&m->domain, s);
  if (st) {
    free(nm);
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
  if (!st) st = mx_read_surface(path, &s);
  if (!st) st = mx_trisoup_check(&s, path, NULL);
  if (!st) st = add_domain(m, &s, path);
  if (!st) mx_mesher_note_read(m, path, 0);
  mx_trisoup_free(&s);
  m->S.ph.read += mx_wtime() - t;
  return mx_call_end(m, &c, st);
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
  if (!st) st = add_domain(m, &s, name);
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
  if (!st) st = add_domain(m, &s, "--demo");
  mx_trisoup_free(&s);
  m->S.ph.read += mx_wtime() - t;
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
    if (!st) {
      mx_mesher_note_read(m, path, 0);
      m->region_name[r] = strdup(path);
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
  return r;
}

/* Domain then region triangles in one soup, checked once. */
/* The signed volume the triangles enclose (their orientation counts: holes
 * oriented inward subtract); *area (may be NULL) gets their area. */
static double enclosed_volume(const mx_trisoup *d, double *area) {
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
      if (enclosed_volume(d, NULL) < 0.0) {
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
    m->S.reoriented = flipped;
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
  m->S.input_repaired = 1;
  return MX_OK;
}

static int assemble_inputs(mx_mesher *m) {
  if (m->assembled) return MX_OK;
  if (m->ndomain == 0) {
    mx_error(NULL, 0, "no input surface: add one (-i FILE) or the demo (--demo)");
    return MX_EINPUT;
  }
  /* two inputs with a triangle in common are refused, but for the winding
   * number's domain (a face two touching bodies share bounds nothing) */
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
  if (m->S.input_repaired) {
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

/* ---- stages ------------------------------------------------------------ */

static void stage(const mx_mesher *m, const char *name) {
  mx_mem_mark(name);
  mx_call_recheck();
  if (m->on_stage) m->on_stage(name);
}

/* Refuse a run that cannot fit: the estimate (kernels/estimate.h) against
 * max_memory_mb, or else the memory available now. */
static int check_memory(mx_mesher *m, const mx_requests *req) {
  const double need = mx_estimate_bytes(&m->soup, m->nt_domain, m->region_t0, req,
                                        &m->B.grid, m->p.stage);
  m->S.memory_estimate_mb = m->S.memory_prior_mb = need / 1048576.0;
  const double avail = mx_available_bytes();
  const double limit = m->p.max_memory_mb > 0 ? m->p.max_memory_mb * 1048576.0 : avail;
  if (limit > 0.0 && need > limit) {
    mx_error(NULL, 0, "this run needs about %.0f MB (estimated from the surface "
                      "and the requested levels) but %s %.0f MB: lower the "
                      "levels or raise --max-memory", need / 1048576.0,
             m->p.max_memory_mb > 0 ? "--max-memory allows" : "the machine has",
             limit / 1048576.0);
    return MX_ENOMEM;
  }
  return MX_OK;
}

/* The same check once the octree is built, from its leaves (a closer
 * estimate: kernels/estimate.h), before the mesh is. */
static int check_memory_leaves(mx_mesher *m) {
  double need = mx_estimate_bytes_leaves(m->nleaves, m->soup.nt, m->p.stage);
  if (!m->release_edges) need += 90.0 * (double)m->nleaves; /* the edge infos kept */
  m->S.memory_estimate_mb = need / 1048576.0;
  const double avail = mx_available_bytes() + mx_peak_rss_mb() * 1048576.0;
  const double limit = m->p.max_memory_mb > 0 ? m->p.max_memory_mb * 1048576.0 : avail;
  if (limit > 0.0 && need > limit) {
    mx_error(NULL, 0, "this run needs about %.0f MB (estimated from the %zu leaves of "
                      "its octree) but %s %.0f MB: lower the levels or raise "
                      "--max-memory", need / 1048576.0, m->nleaves,
             m->p.max_memory_mb > 0 ? "--max-memory allows" : "the machine has",
             limit / 1048576.0);
    return MX_ENOMEM;
  }
  return MX_OK;
}

int mx_update_leaves(mx_mesher *m) {
  mx_free(m->leaves);
  m->leaves = NULL;
  MX_CHECK(mx_leaves(&m->B, &m->leaves, &m->nleaves));
  return mx_leaves_sorted(&m->B, m->leaves, m->nleaves);
}

static int winding_inside(const void *ctx, const double p[3]) {
  return mx_winding_number((const mx_surface_index *)ctx, p) > 0.5;
}

int mx_build_tree(mx_mesher *m) {
  mx_tree_clear(m);
  const double t0 = mx_wtime();
  stage(m, "grid");
  MX_CHECK(assemble_inputs(m));
  const mx_requests req = mx_mesher_requests(m);
  const int use_edges = m->p.balance == MX_BALANCE_EDGES;
  MX_CHECK(mx_builder_init(&m->B, &m->soup, m->nt_domain, m->region_t0, &req, use_edges,
                           m->ndomain ? m->domain_name[0] : NULL));
  m->have_tree = 1;
  m->B.on_level = m->on_level;
  if (m->p.repair_input) {
    /* the domain: where the generalized winding number is above 1/2, for
     * the octants (instead of the ray parity) and the nodes alike */
    MX_CHECK(mx_mesher_index(m));
    m->B.loc_domain.inside_fn = winding_inside;
    m->B.loc_domain.inside_ctx = m->have_winding ? &m->WI : &m->SI;
  }
  for (int l = 0; l <= MX_MAX_LEVEL; l++) {
    m->B.split_keys[l] = m->split_keys[l];
    m->B.nsplit[l] = m->nsplit[l];
    if (m->nsplit[l] && l > m->B.edge_levels) m->B.edge_levels = l;
  }
  MX_CHECK(check_memory(m, &req));
  MX_CHECK(mx_build_roots(&m->B));
  m->S.ph.grid += mx_wtime() - t0;
  stage(m, "refine");
  if (use_edges) {
    MX_CHECK(mx_refine_balanced(&m->B));
    /* with a split set, octants split for balance may have children that
     * must be split too (kernels/remesh.h) */
    {
      int any = 0;
      for (int l = 0; l <= MX_MAX_LEVEL; l++) any |= m->nsplit[l] != 0;
      if (any) MX_CHECK(mx_refine_leaves_to_target(&m->B));
    }
  } else {
    MX_CHECK(mx_refine_unbalanced(&m->B));
    stage(m, "balance");
    MX_CHECK(mx_balance_recursive(&m->B));
    MX_CHECK(mx_resolve_closures(&m->B));
  }
  m->S.ph.refine += m->B.stats.t_refine;
  m->S.ph.balance += m->B.stats.t_balance;
  m->S.max_level = mx_max_requested_level(&req);
  const double tl = mx_wtime();
  MX_CHECK(mx_update_leaves(m));
  m->S.ph.balance += mx_wtime() - tl; /* the leaf list: the octree's last step */
  return check_memory_leaves(m);
}

int mx_mesher_build_octree(mx_mesher *m) {
  mx_call c;
  mx_call_begin(m, &c);
  memset(&m->S, 0, sizeof m->S);
  int st = mx_build_tree(m);
  if (st) mx_tree_clear(m);
  else m->S.leaves = m->nleaves;
  return mx_call_end(m, &c, st);
}

/* Per node: 1 on the boundary (the surface nodes of the boundary stage, else
 * the nodes of faces used by one element). */
static int boundary_flags(mx_mesher *m) {
  const mx_mesh_out *M = &m->M;
  mx_free(m->bnd);
  m->bnd = mx_alloc(M->nnodes + 1);
  if (!m->bnd) return MX_ENOMEM;
  if (m->states) {
#pragma omp parallel for schedule(static)
    for (size_t i = 0; i < M->nnodes; i++) m->bnd[i] = m->states[i] == MX_NODE_OUTSIDE;
    return MX_OK;
  }
  int32_t *f = mx_alloc((M->nnodes + 1) * sizeof *f);
  if (!f) return MX_ENOMEM;
  mx_mesh_view v = {.nnodes = M->nnodes, .xyz = M->xyz, .ncells = M->ncells, .type = M->type, .conn = M->conn, .ncell_fields = 0, .cell_fields = NULL, .npoint_fields = 0, .point_fields = NULL};
  int st = mx_boundary_node_flags(&v, f);
#pragma omp parallel for schedule(static)
  for (size_t i = 0; i < M->nnodes; i++) m->bnd[i] = (uint8_t)f[i];
  mx_free(f);
  return st;
}

static void count_mesh(mx_mesher *m) {
  mx_summary *S = &m->S;
  mx_mesh_out *M = &m->M;
  /* rows padded with UINT32_MAX past each type's node count (the API's
   * promise; the kernels leave 0 or stale ids there) */
#pragma omp parallel for schedule(static)
  for (size_t c = 0; c < M->ncells; c++)
    for (int k = mx_cell_nodes[M->type[c]]; k < 8; k++) M->conn[8 * c + k] = UINT32_MAX;
  S->nodes = M->nnodes;
  S->nodes_counted = 1;
  S->elements = M->ncells;
  memcpy(S->by_type, M->by_type, sizeof S->by_type);
  S->jens_min = M->jens_min;
  S->invalid = M->invalid;
  S->closures = M->closures;
  S->centre_leaves = M->centre_leaves;
  S->mesh = 1;
  const double t = mx_wtime();
  stage(m, "quality");
  mx_quality_tabulate(M->type, M->jens, M->ncells, &S->quality);
  S->ph.quality += mx_wtime() - t;
}

static int transition(mx_mesher *m) {
  if (!m->have_tree) MX_CHECK(mx_build_tree(m));
  mx_mesh_clear(m);
  const double t = mx_wtime();
  stage(m, "transition");
  MX_CHECK(mx_edges_restore(&m->B));
  mx_leaf_masks lm;
  MX_CHECK(mx_transition_masks(&m->B, m->leaves, m->nleaves, &lm));
  /* nothing reads the edge infos again until the octree is split: their
   * memory goes to the mesh (rebuilt by the next split, kernels/remesh.h) */
  if (m->release_edges) mx_edges_release(&m->B);
  MX_CHECK(mx_transition_build(&m->B, m->leaves, m->nleaves, &lm, &m->M));
  m->mesh_stage = MX_STAGE_TRANSITION;
  m->S.ph.transition += mx_wtime() - t;
  return MX_OK;
}

int mx_mesher_transition(mx_mesher *m) {
  mx_call c;
  mx_call_begin(m, &c);
  int st = transition(m);
  if (!st) st = boundary_flags(m);
  if (!st) count_mesh(m);
  if (st) mx_mesh_clear(m);
  return mx_call_end(m, &c, st);
}

/* The boundary stage on the transition mesh, then elements grouped by leaf
 * (the restart file's element -> octant map). */
static int boundary_once(mx_mesher *m) {
  const double t = mx_wtime();
  stage(m, "boundary");
  if (!m->have_index) {
    stage(m, "index");
    MX_CHECK(mx_mesher_index(m));
    stage(m, "boundary");
  }
  mx_boundary_stats bs;
  MX_CHECK(mx_boundary_stage(&m->B, m->leaves, &m->SI, &m->M, m->p.close_ratio,
                             m->p.staircase_quality, &bs, &m->states));
  m->S.boundary = bs;
  m->S.full = 1;
  MX_CHECK(mx_mesh_sort_by_leaf(&m->M, m->nleaves));
  MX_CHECK(mx_mesh_renumber_first_use(&m->M, &m->states));
  m->mesh_stage = MX_STAGE_FULL;
  m->S.ph.boundary += mx_wtime() - t;
  return MX_OK;
}

/* Transition and boundary stage on the whole octree. */
int mx_mesh_full(mx_mesher *m) {
  MX_CHECK(transition(m));
  return boundary_once(m);
}

/* Repair (the 2021 paper, section 6): the leaves holding elements with
 * J_ENS < 1e-6, or elements a node lies on without being one of their nodes
 * (kernels/contacts.h: two sheets of the boundary meeting), are split once
 * by list refinement (Algorithm 3), and the octree is meshed again around
 * them (remesh_local.c), up to repair_rounds times. m->S.contacts holds the
 * contacts of the final mesh.
 *
 * When to go on: a round is worse when it does not lower the count of the
 * round before it; two worse rounds since the best one stop the repair (a
 * surface feature finer than any level, an input's hole: 17, 33, 45 ...).
 * Not "not below the best": a repair often gets worse before it gets
 * better, as the first split puts transition patterns at the surface where
 * the shrink inverts more than before (the triple torus of issue 23 at -s 6:
 * 2 defects, then 30, 10, 2, 0); judged against the best (2), 30 and 10
 * were two worse rounds and the repair stopped while it was converging. */
int mx_repair_go_on(int round, uint64_t defects, int max_rounds, mx_repair_progress *p) {
  if (defects == 0 || round >= max_rounds) return 0;
  const uint64_t before = p->last;
  p->last = defects;
  if (round == 0 || defects < p->best) {
    p->best = defects;
    p->worse = 0;
  } else if (defects >= before && ++p->worse >= 2) {
    return 0;
  }
  return 1;
}

int mx_repair(mx_mesher *m) {
  uint8_t *flag = NULL;
  mx_repair_progress progress = {0, 0, 0};
  for (int round = 0;; round++) {
    mx_free(flag);
    flag = mx_alloc(m->M.ncells + 1);
    if (!flag) return MX_ENOMEM;
    const double t = mx_wtime();
    stage(m, "verify");
    int st = mx_find_contacts(&m->M, m->states, flag, &m->S.contacts);
    m->S.ph.verify += mx_wtime() - t;
    if (st) {
      mx_free(flag);
      return st;
    }
    if (!mx_repair_go_on(round, m->M.invalid + m->S.contacts.nodes, m->p.repair_rounds,
                         &progress))
      break;
    if (m->on_round) m->on_round(round + 1);
    size_t n = 0;
    uint32_t *octs = mx_alloc((m->M.invalid + m->S.contacts.elements + 1) * sizeof *octs);
    if (!octs) {
      mx_free(flag);
      return MX_ENOMEM;
    }
    for (size_t c = 0; c < m->M.ncells; c++) {
      if (!mx_jens_invalid(m->M.jens[c]) && !flag[c]) continue;
      const uint32_t o = m->leaves[m->M.leaf[c]];
      if (m->B.oct.level[o] < MX_MAX_LEVEL - 1) octs[n++] = o; /* else: as fine as can be */
    }
    if (n == 0) break;
    const size_t before = m->M.invalid;
    m->S.contacts_repaired += m->S.contacts.elements;
    st = mx_refine_list(&m->B, octs, n);
    mx_free(octs);
    if (!st) {
      m->S.repaired += before;
      m->S.repair_rounds++;
      st = mx_remesh_after_refine(m);
    }
    if (st) {
      mx_free(flag);
      return st;
    }
  }
  mx_free(flag);
  return MX_OK;
}

/* The domain volume check of the full stage: a mesh that fills much more or
 * much less than the input encloses breaks the contract too (the levels are
 * too coarse for thin parts of the input, or the inside flooded). The
 * tolerance is the one of `mixoct check --surface`: half a layer of
 * elements along the surface, 5% at least. One closed input only (with
 * holes or several bodies the enclosed volume needs their nesting), or the
 * winding number's domain of --repair-input (its volume and boundary from
 * winding_domain.c, any number of inputs and bodies). The verdict takes the
 * volume vm and the count ncells of a mesh (a distributed mesh's sums over
 * its ranks). */
int mx_volume_verdict(mx_mesher *m, double vm, size_t ncells) {
  if (m->p.stage != MX_STAGE_FULL || !ncells) return MX_OK;
  double area = 0.0, vs;
  const char *what = "the input encloses";
  if (m->have_winding) {
    vs = mx_winding_domain_volume(m);
    area = m->S.winding.area;
    what = "the input's winding number domain holds (--repair-input)";
  } else {
    if (m->ndomain != 1 || m->p.repair_input) return MX_OK;
    const mx_trisoup *d = &m->domain;
    if (d->nshells > 1) return MX_OK;
    vs = fabs(enclosed_volume(d, &area));
  }
  if (!(vs > 0.0)) return MX_OK;
  const double h = cbrt(fabs(vm) / (double)ncells);
  const double tol = fmax(0.05, 0.5 * area * h / vs), err = (vm - vs) / vs;
  m->S.volume_error = err;
  if (fabs(err) <= tol) return MX_OK;
  char inputs[MX_INPUTS_LABEL];
  mx_error(mx_inputs_label(m, inputs, sizeof inputs), 0, "the mesh holds %.1f%% of the volume %s "
           "(%.4g against %.4g; tolerance %.1f%%: half a layer of elements along the "
           "surface): the levels are too coarse for thin parts of the input; ask for finer "
           "ones (-s, -a, -b, -r)", 100.0 * vm / vs, what, vm, vs, 100.0 * tol);
  return MX_EINVALID;
}

double mx_mesh_volume(const mx_mesh_out *M) {
  double vm = 0.0;
#pragma omp parallel for schedule(static) reduction(+ : vm)
  for (size_t c = 0; c < M->ncells; c++) {
    double p[8][3];
    const int nv = mx_cell_nodes[M->type[c]];
    for (int k = 0; k < nv; k++) memcpy(p[k], M->xyz + 3 * (size_t)M->conn[8 * c + k], sizeof p[k]);
    vm += mx_element_volume(M->type[c], (const double(*)[3])p);
  }
  return vm;
}

static int volume_check(mx_mesher *m) {
  if (m->p.stage != MX_STAGE_FULL || !m->M.ncells ||
      (!m->have_winding && (m->ndomain != 1 || m->p.repair_input)))
    return MX_OK;
  return mx_volume_verdict(m, mx_mesh_volume(&m->M), m->M.ncells);
}

/* Per-node flags, counts and quality of the mesh just made; MX_EINVALID
 * when elements with J_ENS < 1e-6 remain. */
int mx_mesh_finish(mx_mesher *m) {
  char inputs[MX_INPUTS_LABEL];
  const char *name = mx_inputs_label(m, inputs, sizeof inputs);
  if (m->M.ncells == 0) {
    mx_error(name, 0,
             "the mesh is empty: no element lies in the domain (%zu leaves); ask for finer "
             "levels (-s, -a, -b, -r)", m->nleaves);
    return MX_EINPUT;
  }
  /* the boundary flags and the volume check count as verification */
  const double t = mx_wtime();
  int st = boundary_flags(m);
  m->S.ph.verify += mx_wtime() - t;
  MX_CHECK(st);
  m->S.leaves = m->nleaves;
  count_mesh(m);
  if (m->M.invalid > 0) {
    mx_error(name, 0, "%zu element(s) with J_ENS < 1e-6 remain after %d repair round(s)",
             m->M.invalid, m->S.repair_rounds);
    return MX_EINVALID;
  }
  if (m->S.contacts.nodes > 0) {
    const mx_contacts *k = &m->S.contacts;
    mx_error(name, 0, "%zu node(s) lie on a face or an edge of an element they are not a "
             "node of (two parts of the boundary meet: a non-conforming mesh) after %d "
             "repair round(s); the first, node %u, at (%.17g, %.17g, %.17g); ask for finer "
             "levels there (-s, -b, -r)", k->nodes, m->S.repair_rounds, k->first_node,
             k->first[0], k->first[1], k->first[2]);
    return MX_EINVALID;
  }
  const double tv = mx_wtime();
  st = volume_check(m);
  m->S.ph.verify += mx_wtime() - tv;
  return st;
}

/* Mesh the current octree up to params.stage. */
int mx_mesh_stages(mx_mesher *m) {
  if (!m->have_tree) MX_CHECK(mx_build_tree(m));
  m->S.leaves = m->nleaves;
  if (m->p.stage == MX_STAGE_OCTREE) {
    mx_mesh_clear(m);
    m->mesh_stage = MX_STAGE_OCTREE;
    return MX_OK;
  }
  MX_CHECK(transition(m));
  if (m->p.stage == MX_STAGE_FULL) {
    MX_CHECK(boundary_once(m));
    MX_CHECK(mx_repair(m));
  }
  return mx_mesh_finish(m);
}

int mx_mesher_boundary(mx_mesher *m) {
  mx_call c;
  mx_call_begin(m, &c);
  int st = MX_OK;
  if (m->mesh_stage != MX_STAGE_TRANSITION) {
    mx_error(NULL, 0, "the boundary stage runs on the transition mesh: call "
                      "mx_mesher_transition first");
    st = MX_EINPUT;
  }
  if (!st) st = boundary_once(m);
  if (!st) st = mx_repair(m);
  if (!st) st = mx_mesh_finish(m);
  if (st && st != MX_EINVALID) mx_mesh_clear(m);
  return mx_call_end(m, &c, st);
}

void mx_fill_tree_stats(mx_mesher *m) {
  mx_summary *S = &m->S;
  if (!m->have_tree) return;
  S->leaves = m->nleaves;
  S->leaves_hash = mx_leaves_hash(&m->B, m->leaves, m->nleaves);
  S->octants = m->B.oct.n;
  S->edges = m->B.edges_released ? m->B.released_edges : mx_edges_total(&m->B.edges);
  S->edge_bytes =
      m->B.edges_released ? m->B.released_edge_bytes : mx_edges_bytes(&m->B.edges);
  S->located = m->B.stats.located;
  S->split_requested = m->B.stats.split_requested;
  S->split_balance = m->B.stats.split_balance;
  S->dropped = m->B.stats.dropped;
  S->threads = omp_get_max_threads();
  S->balance = m->p.balance;
}

int mx_mesher_mesh(mx_mesher *m) {
  mx_call c;
  mx_call_begin(m, &c);
  const double t0 = mx_wtime();
  const double read = m->S.ph.read, restart = m->S.t_restart;
  const int keep = m->have_tree; /* a restart file was read: keep its figures */
  if (!keep) {
    memset(&m->S, 0, sizeof m->S);
    m->S.ph.read = read;
  }
  m->S.t_restart = restart;
  int st = mx_mesh_stages(m);
  mx_fill_tree_stats(m);
  m->S.ph.total += mx_wtime() - t0;
  if (st && st != MX_EINVALID) mx_mesh_clear(m);
  return mx_call_end(m, &c, st);
}

/* ---- the mesh ---------------------------------------------------------- */

int mx_mesher_mesh_arrays(const mx_mesher *m, mx_mesh_arrays *a) {
  memset(a, 0, sizeof *a);
  if (m->mesh_stage < MX_STAGE_TRANSITION) {
    mx_call c;
    mx_call_begin((mx_mesher *)m, &c);
    mx_error(NULL, 0, "no mesh yet: call mx_mesher_mesh first");
    return mx_call_end((mx_mesher *)m, &c, MX_EINPUT);
  }
  const mx_mesh_out *M = &m->M;
  a->nnodes = M->nnodes;
  a->nelements = M->ncells;
  a->nleaves = m->nleaves;
  a->xyz = M->xyz;
  a->type = M->type;
  a->conn = M->conn;
  a->jens = M->jens;
  a->leaf = M->leaf;
  a->level = M->level;
  a->boundary = m->bnd;
  memcpy(a->by_type, M->by_type, sizeof a->by_type);
  a->jens_min = M->jens_min;
  a->invalid = M->invalid;
  return MX_OK;
}

static int write_octree(mx_mesher *m, const char *path, int ascii) {
  if (!m->have_hex) {
    if (m->release_edges) mx_edges_release(&m->B); /* not read by the hexahedra */
    MX_CHECK(mx_leaf_hex_mesh(&m->B, m->leaves, m->nleaves, &m->hex));
    m->have_hex = 1;
  }
  m->S.nodes = m->hex.nnodes;
  m->S.nodes_counted = 1;
  uint8_t *type = mx_alloc(m->nleaves + 1);
  if (!type) return MX_ENOMEM;
  memset(type, MX_HEX, m->nleaves);
  mx_field level = {.name = "level", .ivalues = m->hex.level};
  mx_mesh_view v = {.nnodes = m->hex.nnodes, .xyz = m->hex.xyz, .ncells = m->nleaves, .type = type, .conn = m->hex.conn, .ncell_fields = 1, .cell_fields = &level, .npoint_fields = 0, .point_fields = NULL};
  int st = mx_write_mesh(path, &v, ascii);
  mx_free(type);
  return st;
}

int mx_mesher_write(const mx_mesher *cm, const char *path, int ascii) {
  mx_mesher *m = (mx_mesher *)cm; /* the octree stage's hex mesh is cached */
  mx_call c;
  mx_call_begin(m, &c);
  const double t = mx_wtime();
  int st = MX_OK;
  if (!path || !mx_mesh_format_known(path)) {
    mx_error(path, 0, "unknown output format (use .vtk .vtu .msh .mesh .meshb "
                      ".getfem .m3d .mvm)");
    st = MX_EINPUT;
  } else if (mx_mesher_spares_inputs(m, path, 0)) {
    st = MX_EINPUT; /* an input: refused, named */
  } else if (m->mesh_stage == MX_STAGE_OCTREE) {
    st = write_octree(m, path, ascii);
  } else if (m->mesh_stage < 0) {
    mx_error(path, 0, "no mesh to write: call mx_mesher_mesh first");
    st = MX_EINPUT;
  } else {
    stage(m, "write");
    st = mx_write_mixed(m, path, ascii);
  }
  m->S.ph.write += mx_wtime() - t;
  return mx_call_end(m, &c, st);
}

void mx_mesher_stats(const mx_mesher *m, mx_stats *s) {
  const mx_summary *S = &m->S;
  memset(s, 0, sizeof *s);
  s->leaves = m->nleaves;
  s->octants = m->have_tree ? m->B.oct.n : 0;
  s->nodes = S->nodes;
  s->elements = S->elements;
  s->invalid = S->invalid;
  s->refined_listed = S->refined_listed;
  s->split_balance = m->have_tree ? m->B.stats.split_balance : 0;
  s->repaired = S->repaired;
  s->repair_rounds = S->repair_rounds;
  s->jens_min = S->jens_min;
  s->leaves_hash = m->have_tree ? mx_leaves_hash(&m->B, m->leaves, m->nleaves) : 0;
  s->t_read = S->ph.read;
  s->t_grid = S->ph.grid;
  s->t_refine = S->ph.refine;
  s->t_balance = S->ph.balance;
  s->t_transition = S->ph.transition;
  s->t_boundary = S->ph.boundary;
  s->t_quality = S->ph.quality;
  s->t_write = S->ph.write;
  s->t_restart = S->t_restart;
  s->remesh_local = S->local;
  s->remesh_patch_leaves = S->local ? S->patch_leaves : 0;
}
