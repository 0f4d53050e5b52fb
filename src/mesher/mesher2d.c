/* The 2D mixed quadtree mesher as library calls (include/mixoct.h,
 * mx_mesher2d_*): inputs and requests, the pipeline of Algorithm 2 with the
 * independent check of every mesh, list refinement (Algorithm 3), the
 * memory estimate, the writers. The steps themselves live in src/quad/
 * (one file each); the restart file's conversion in restart_quadtree.c. */
#include "base/cancel.h"
#include "mesher/mesher2d.h"

#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "base/common.h"
#include "io/restart.h"
#include "kernels/estimate.h"
#include "mesher/call.h"
#include "mesher/qmesh_output.h"
#include "io/read_poly.h"

/* The check's tolerances: boundary nodes within CHECK_TOL of the domain's
 * diameter from the polylines; the area within half a layer of cells along
 * the boundary, AREA_TOL at least (as the 3D volume check). */
#define CHECK_TOL 1e-6
#define AREA_TOL 0.05
#define AREA_TOL_MAX 0.25 /* beyond: the domain is not represented at all */
/* A feature's quadrant is at most this fraction of its distance d to the
 * nearest other feature: each feature takes a node of its own quadrant,
 * within side / sqrt 2 of it, so two features at distance D >= d (each
 * with its own d <= D) take nodes at least D - D / sqrt 2 > 0 apart. */
#define FEATURE_SPACING 0.5
/* Peak bytes per leaf, measured on the letter A at -a 8..12 (issue 13:
 * 693 MB for 3.85 M leaves), with a margin; and per input segment. */
#define BYTES_PER_LEAF 250.0
#define BYTES_FIXED 4e6

/* ---- calls and messages ---------------------------------------------------- */

static void collect_message(void *user, int level, const char *text) {
  mx_mesher2d_record *r = user;
  if (level == MX_MSG_ERROR && !r->last_error[0])
    snprintf(r->last_error, sizeof r->last_error, "%s", text);
  if (r->fn)
    r->fn(r->user, level, text);
  else if (level == MX_MSG_ERROR || !mx_quiet)
    fprintf(stderr, "mesher2d: %s%s\n", level == MX_MSG_ERROR ? "error: " : "warning: ", text);
}

/* One call: the mesher's handler installed (a const call, save or write,
 * too: the record is behind a pointer). */
#define CALL(m, expr)                                                   \
  do {                                                                  \
    mx_call c_;                                                         \
    mx_call_enter(&c_, collect_message, (m)->rec, (m)->p.threads);      \
    c_.cancel_prev = mx_cancel_enter((atomic_int *)&(m)->cancel);       \
    (m)->rec->last_error[0] = 0;                                        \
    int st_ = (expr);                                                   \
    mx_cancel_leave(c_.cancel_prev);                                    \
    if (st_ == MX_ECANCELED) mx_error(NULL, 0, "cancelled");            \
    return mx_call_leave(&c_, st_);                                     \
  } while (0)

void mx_params2d_default(mx_params2d *p) {
  memset(p, 0, sizeof *p);
  p->surface_level = -1; /* none, as in 3D */
  p->all_level = -1;
  p->balance = MX_BALANCE_EDGES;
  p->close_ratio = 0.3;
  p->feature_levels = 1;
}

mx_mesher2d *mx_mesher2d_new(const mx_params2d *p) {
  mx_mesher2d *m = mx_calloc(sizeof *m);
  if (!m) return NULL;
  m->rec = mx_calloc(sizeof *m->rec);
  if (!m->rec) {
    mx_free(m);
    return NULL;
  }
  if (p) m->p = *p;
  else mx_params2d_default(&m->p);
  if (!(m->p.close_ratio > 0)) m->p.close_ratio = 0.3;
  return m;
}

static void free_mesh(mx_mesher2d *m) {
  mx_qmesh_free(&m->M);
  mx_free(m->material);
  mx_free(m->mat_report);
  m->material = NULL;
  m->mat_report = NULL;
  m->nmaterials = 0;
  mx_free(m->leaves);
  m->leaves = NULL;
  m->nleaves = 0;
  mx_qtree_free(&m->T);
  m->meshed = m->checked = m->valid = 0;
}

static void free_keep(mx_mesher2d *m) {
  mx_free(m->keep_key);
  mx_free(m->keep_level);
  mx_free(m->rs_nsub);
  mx_free(m->rs_pos);
  m->keep_key = NULL, m->keep_level = NULL, m->rs_nsub = m->rs_pos = NULL;
  m->nkeep = m->rs_n = 0;
}

void mx_mesher2d_free(mx_mesher2d *m) {
  if (!m) return;
  free_mesh(m);
  free_keep(m);
  mx_mesher2d_materials_free(m);
  mx_mesher2d_materials_names_free(m);
  mx_poly_index_free(&m->index);
  mx_poly_free(&m->domain);
  for (size_t k = 0; k < m->nregions; k++) mx_poly_free(&m->regions[k]);
  for (size_t k = 0; k < m->ndrawings; k++) mx_poly_free(&m->drawings[k]);
  mx_free(m->regions);
  mx_free(m->drawings);
  mx_free(m->region_level);
  mx_free(m->drawing_level);
  mx_free(m->boxes);
  mx_free(m->funs);
  mx_mesher2d_size_free(m);
  mx_free(m->features);
  mx_free(m->rec);
  mx_free(m);
}

void mx_mesher2d_set_message_handler(mx_mesher2d *m, mx_message_fn fn, void *user) {
  m->rec->fn = fn;
  m->rec->user = user;
}

const char *mx_mesher2d_last_error(const mx_mesher2d *m) { return m->rec->last_error; }

/* ---- inputs and requests ------------------------------------------------------ */

static int level_ok(int level, const char *what) {
  if (level >= 0 && level <= MX_QMAX_LEVEL - 1) return MX_OK;
  mx_error(NULL, 0, "%s: level %d is out of range (0 to %d)", what, level, MX_QMAX_LEVEL - 1);
  return MX_EINPUT;
}

/* The domain read (or given), checked, indexed; its features listed. */
static int take_domain(mx_mesher2d *m) {
  MX_CHECK(mx_poly_check_domain(&m->domain));
  MX_CHECK(mx_poly_index_build(&m->domain, &m->index));
  MX_CHECK(mx_poly_features(&m->domain, &m->features, &m->nfeatures));
  m->has_domain = 1;
  return MX_OK;
}

static int domain_once(const mx_mesher2d *m) {
  if (!m->has_domain) return MX_OK;
  mx_error(NULL, 0, "the domain is already set (one domain per mesher)");
  return MX_EINPUT;
}

static int set_domain(mx_mesher2d *m, const char *path) {
  MX_CHECK(domain_once(m));
  const double t = mx_wtime();
  int st = mx_read_poly_any(path, &m->domain);
  if (!st) st = take_domain(m);
  if (st) {
    mx_poly_index_free(&m->index);
    mx_poly_free(&m->domain);
  }
  m->rec->t[M2_READ] += mx_wtime() - t;
  return st;
}

int mx_mesher2d_set_domain(mx_mesher2d *m, const char *path) { CALL(m, set_domain(m, path)); }

static int set_domain_arrays(mx_mesher2d *m, const char *name, size_t nv, const double *xy,
                             size_t ns, const uint32_t *seg) {
  MX_CHECK(domain_once(m));
  if (!xy || !seg || nv < 3 || ns < 3 || nv > UINT32_MAX || ns > UINT32_MAX) {
    mx_error(name, 0, "a domain needs at least 3 vertices and 3 segments");
    return MX_EINPUT;
  }
  mx_poly *P = &m->domain;
  memset(P, 0, sizeof *P);
  P->xy = mx_alloc(2 * nv * sizeof *P->xy);
  P->seg = mx_alloc(2 * ns * sizeof *P->seg);
  P->line = mx_alloc(ns * sizeof *P->line);
  P->path = mx_strdup(name ? name : "arrays");
  if (!P->xy || !P->seg || !P->line || !P->path) {
    mx_poly_free(P);
    return MX_ENOMEM;
  }
  P->nv = nv, P->ns = ns;
  for (size_t i = 0; i < 2 * nv; i++) P->xy[i] = xy[i];
  for (size_t s = 0; s < ns; s++) {
    P->seg[2 * s] = seg[2 * s], P->seg[2 * s + 1] = seg[2 * s + 1];
    P->line[s] = 0;
    if (seg[2 * s] >= nv || seg[2 * s + 1] >= nv) {
      mx_error(name, 0, "segment %zu: vertex index out of range (%zu vertices)", s, nv);
      mx_poly_free(P);
      return MX_EINPUT;
    }
  }
  const int st = take_domain(m);
  if (st) {
    mx_poly_index_free(&m->index);
    mx_poly_free(P);
  }
  return st;
}

int mx_mesher2d_set_domain_arrays(mx_mesher2d *m, const char *name, size_t nv, const double *xy,
                                  size_t ns, const uint32_t *seg) {
  CALL(m, set_domain_arrays(m, name, nv, xy, ns, seg));
}

static int set_levels(mx_mesher2d *m, int s, int a) {
  if (s != -1) MX_CHECK(level_ok(s, "the surface level")); /* -1: none */
  if (a != -1) MX_CHECK(level_ok(a, "the all level"));
  m->p.surface_level = s;
  m->p.all_level = a;
  return MX_OK;
}

int mx_mesher2d_set_levels(mx_mesher2d *m, int s, int a) { CALL(m, set_levels(m, s, a)); }

/* Room for one more item in an array of mx_alloc. */
static int grow(void **p, size_t n, size_t elem) {
  if (n & (n - 1)) return MX_OK; /* capacity: powers of two */
  void *q = mx_realloc(*p, (n ? 2 * n : 1) * elem);
  if (!q) return MX_ENOMEM;
  *p = q;
  return MX_OK;
}

static int add_box(mx_mesher2d *m, const double lo[2], const double hi[2], int level) {
  MX_CHECK(level_ok(level, "box"));
  if (!(isfinite(lo[0]) && isfinite(lo[1]) && isfinite(hi[0]) && isfinite(hi[1])) ||
      lo[0] > hi[0] || lo[1] > hi[1]) {
    mx_error(NULL, 0, "box: the corners must be finite, the first below the second");
    return MX_EINPUT;
  }
  MX_CHECK(grow((void **)&m->boxes, m->nboxes, sizeof *m->boxes));
  m->boxes[m->nboxes++] = (mx_qbox){{lo[0], lo[1]}, {hi[0], hi[1]}, level};
  return MX_OK;
}

int mx_mesher2d_add_box(mx_mesher2d *m, const double lo[2], const double hi[2], int level) {
  CALL(m, add_box(m, lo, hi, level));
}

static int read_boxes(mx_mesher2d *m, const char *path) {
  mx_qbox *b = NULL;
  size_t n = 0;
  int st = mx_read_qboxes(path, &b, &n);
  for (size_t i = 0; !st && i < n; i++) st = add_box(m, b[i].lo, b[i].hi, b[i].level);
  mx_free(b);
  return st;
}

int mx_mesher2d_read_boxes(mx_mesher2d *m, const char *path) { CALL(m, read_boxes(m, path)); }

/* A region (closed, checked as a domain) or a drawing (any segments). */
static int add_poly(mx_mesher2d *m, const char *path, int level, int region) {
  MX_CHECK(level_ok(level, region ? "region" : "drawing"));
  mx_poly **list = region ? &m->regions : &m->drawings;
  int **lev = region ? &m->region_level : &m->drawing_level;
  size_t *n = region ? &m->nregions : &m->ndrawings;
  MX_CHECK(grow((void **)list, *n, sizeof **list));
  MX_CHECK(grow((void **)lev, *n, sizeof **lev));
  mx_poly P;
  int st = mx_read_poly_any(path, &P);
  if (!st && region) st = mx_poly_check_domain(&P);
  if (st) {
    mx_poly_free(&P);
    return st;
  }
  (*list)[*n] = P;
  (*lev)[(*n)++] = level;
  return MX_OK;
}

int mx_mesher2d_add_region(mx_mesher2d *m, const char *path, int level) {
  CALL(m, add_poly(m, path, level, 1));
}

int mx_mesher2d_add_drawing(mx_mesher2d *m, const char *path, int level) {
  CALL(m, add_poly(m, path, level, 0));
}

/* The functions of the "function" refinement, by name. */
static const struct {
  const char *name;
  int kind;
  size_t nargs;
} fun_kinds[3] = {{"circle", MX_QFUN_CIRCLE, 3}, {"line", MX_QFUN_LINE, 4},
                  {"sine", MX_QFUN_SINE, 4}};

/* The index in fun_kinds of the function called name; 3 when none is. */
static int fun_kind(const char *name) {
  int k = 0;
  while (k < 3 && (!name || strcmp(name, fun_kinds[k].name) != 0)) k++;
  return k;
}

int mx_mesher2d_function_args(const char *name) {
  const int k = fun_kind(name);
  return k < 3 ? (int)fun_kinds[k].nargs : -1;
}

static int add_function(mx_mesher2d *m, const char *name, const double *args, size_t nargs,
                        int level) {
  const int k = fun_kind(name);
  if (k == 3) {
    mx_error(NULL, 0, "function: circle, line or sine, not '%s'", name ? name : "(null)");
    return MX_EINPUT;
  }
  if (nargs != fun_kinds[k].nargs) {
    mx_error(NULL, 0, "function %s takes %zu numbers, got %zu", name, fun_kinds[k].nargs, nargs);
    return MX_EINPUT;
  }
  MX_CHECK(level_ok(level, "function"));
  mx_qfun f = {.kind = fun_kinds[k].kind, .level = level};
  for (size_t a = 0; a < nargs; a++) {
    if (!isfinite(args[a])) {
      mx_error(NULL, 0, "function %s: argument %zu is not finite", name, a + 1);
      return MX_EINPUT;
    }
    f.a[a] = args[a];
  }
  if (f.kind == MX_QFUN_CIRCLE && !(f.a[2] > 0)) {
    mx_error(NULL, 0, "function circle: the radius must be positive");
    return MX_EINPUT;
  }
  if (f.kind == MX_QFUN_LINE && f.a[2] == 0 && f.a[3] == 0) {
    mx_error(NULL, 0, "function line: the normal must not be zero");
    return MX_EINPUT;
  }
  MX_CHECK(grow((void **)&m->funs, m->nfuns, sizeof *m->funs));
  m->funs[m->nfuns++] = f;
  mx_mesher2d_size_reset(m); /* a source of the field, when there is one */
  return MX_OK;
}

int mx_mesher2d_add_function(mx_mesher2d *m, const char *name, const double *args, size_t nargs,
                             int level) {
  CALL(m, add_function(m, name, args, nargs, level));
}

int mx_mesher2d_set_material(mx_mesher2d *m, int depth, int number, const char *name) {
  CALL(m, mx_mesher2d_set_material_(m, depth, number, name));
}

/* The size field: mesher2d_size.c. */
int mx_mesher2d_set_size_function(mx_mesher2d *m, mx_size_fn f, void *user,
                                  const mx_cspace_params *p) {
  CALL(m, mx_mesher2d_set_size_function_(m, f, user, p));
}

int mx_mesher2d_set_size_expr(mx_mesher2d *m, const char *text) {
  CALL(m, mx_mesher2d_set_size_expr_(m, text));
}

int mx_mesher2d_set_size_limits(mx_mesher2d *m, double hmin, double hmax) {
  CALL(m, mx_mesher2d_set_size_limits_(m, hmin, hmax));
}

/* ---- feature levels ------------------------------------------------------------ */

static int cmp_x(const void *a, const void *b) {
  const double *p = a, *q = b;
  return (p[0] > q[0]) - (p[0] < q[0]);
}

void mx_mesher2d_box(const mx_mesher2d *m, double lo[2], double hi[2]) {
  const mx_poly *P = &m->domain;
  lo[0] = lo[1] = INFINITY;
  hi[0] = hi[1] = -INFINITY;
  for (size_t s = 0; s < 2 * P->ns; s++)
    for (int a = 0; a < 2; a++) {
      lo[a] = fmin(lo[a], P->xy[2 * (size_t)P->seg[s] + a]);
      hi[a] = fmax(hi[a], P->xy[2 * (size_t)P->seg[s] + a]);
    }
}

int mx_mesher2d_grid(const mx_mesher2d *m, mx_qgrid *g) {
  double lo[2], hi[2];
  mx_mesher2d_box(m, lo, hi);
  return mx_qgrid_build(lo, hi, m->domain.path, g);
}

/* A degenerate box at each feature, at the level where its quadrant is at
 * most FEATURE_SPACING of the distance to its nearest other feature (the
 * features sorted by x, each scanning its neighbours while |dx| < best).
 * Appended to *boxes (a copy of the requests' boxes). */
static int feature_boxes(const mx_mesher2d *m, mx_qbox **boxes, size_t *nboxes) {
  const size_t nf = m->nfeatures;
  if (!m->p.feature_levels || nf < 2) return MX_OK;
  mx_qgrid g;
  MX_CHECK(mx_mesher2d_grid(m, &g));
  double *f = mx_alloc(3 * nf * sizeof *f); /* x, y, vertex */
  mx_qbox *b = mx_alloc((*nboxes + nf) * sizeof *b);
  if (!f || !b) {
    mx_free(f);
    mx_free(b);
    return MX_ENOMEM;
  }
  if (*nboxes) memcpy(b, *boxes, *nboxes * sizeof *b);
  for (size_t i = 0; i < nf; i++) {
    f[3 * i] = m->domain.xy[2 * (size_t)m->features[i]];
    f[3 * i + 1] = m->domain.xy[2 * (size_t)m->features[i] + 1];
    f[3 * i + 2] = (double)m->features[i];
  }
  qsort(f, nf, 3 * sizeof *f, cmp_x);
  int st = MX_OK;
  size_t n = *nboxes;
  for (size_t i = 0; i < nf && !st; i++) {
    double best = INFINITY;
    for (size_t j = i + 1; j < nf && f[3 * j] - f[3 * i] < best; j++)
      best = fmin(best, hypot(f[3 * j] - f[3 * i], f[3 * j + 1] - f[3 * i + 1]));
    for (size_t j = i; j-- > 0 && f[3 * i] - f[3 * j] < best;)
      best = fmin(best, hypot(f[3 * j] - f[3 * i], f[3 * j + 1] - f[3 * i + 1]));
    int level = 0;
    while (level < MX_QMAX_LEVEL && ldexp(g.side, -level) > FEATURE_SPACING * best) level++;
    if (level > MX_QMAX_LEVEL - 1) {
      mx_error(m->domain.path, 0, "feature vertex %.0f at (%g, %g) is %g from another: closer "
               "than the finest quadrant can separate", f[3 * i + 2] + 1, f[3 * i],
               f[3 * i + 1], best);
      st = MX_EINPUT;
    }
    b[n++] = (mx_qbox){{f[3 * i], f[3 * i + 1]}, {f[3 * i], f[3 * i + 1]}, level};
  }
  mx_free(f);
  if (st) {
    mx_free(b);
    return st;
  }
  *boxes = b;
  *nboxes = n;
  return MX_OK;
}

/* ---- memory ------------------------------------------------------------------------ */

static double poly_length(const mx_poly *P) {
  double l = 0.0;
  for (size_t s = 0; s < P->ns; s++) {
    const double *a = P->xy + 2 * (size_t)P->seg[2 * s], *b = P->xy + 2 * (size_t)P->seg[2 * s + 1];
    l += hypot(b[0] - a[0], b[1] - a[1]);
  }
  return l;
}

static double poly_area(const mx_poly *P) {
  double a = 0.0;
  for (size_t s = 0; s < P->ns; s++) {
    const double *p = P->xy + 2 * (size_t)P->seg[2 * s], *q = P->xy + 2 * (size_t)P->seg[2 * s + 1];
    a += p[0] * q[1] - q[0] * p[1];
  }
  return 0.5 * fabs(a);
}

/* Leaves the requests can make at most: area over the quadrant area for
 * -a, boxes and regions; 4 quadrants a side along lines (-s, drawings,
 * functions over the grid's width); the kept leaves. */
static double estimate_leaves(const mx_mesher2d *m, const mx_qgrid *g) {
  const double A = poly_area(&m->domain), L = poly_length(&m->domain);
#define H(l) ldexp(g->side, -(l))
  double n = 1.0 + 1.5 * (double)m->nkeep;
  if (m->p.all_level > 0) n += A / (H(m->p.all_level) * H(m->p.all_level));
  if (m->p.surface_level > 0) n += 4.0 * L / H(m->p.surface_level);
  for (size_t b = 0; b < m->nboxes; b++) {
    const mx_qbox *x = &m->boxes[b];
    const double w = fmin(x->hi[0] - x->lo[0], g->side) + H(x->level),
                 h = fmin(x->hi[1] - x->lo[1], g->side) + H(x->level);
    n += w * h / (H(x->level) * H(x->level));
  }
  for (size_t r = 0; r < m->nregions; r++)
    n += poly_area(&m->regions[r]) / (H(m->region_level[r]) * H(m->region_level[r])) +
         4.0 * poly_length(&m->regions[r]) / H(m->region_level[r]);
  for (size_t d = 0; d < m->ndrawings; d++)
    n += 4.0 * poly_length(&m->drawings[d]) / H(m->drawing_level[d]);
  for (size_t f = 0; f < m->nfuns; f++) n += 8.0 * g->side / H(m->funs[f].level);
#undef H
  return n;
}

/* With a size field, its control space is built first, and the quadrants
 * it asks for are refused alone (naming its least size and where) or
 * counted with the others. */
static int check_memory(mx_mesher2d *m) {
  mx_qgrid g;
  MX_CHECK(mx_mesher2d_grid(m, &g));
  const double room =
      m->p.max_memory_mb > 0 ? m->p.max_memory_mb * 1048576.0 : mx_available_bytes();
  double field = 0.0;
  if (mx_size_source_given(&m->size)) {
    MX_CHECK(mx_mesher2d_size_space(m, &g));
    field = m->size_cells;
    MX_CHECK(mx_size_source_budget(&m->size, 2, field, m->size_hmin, m->size_at,
                                   BYTES_FIXED + BYTES_PER_LEAF * field, room,
                                   m->p.max_memory_mb > 0, NULL));
  }
  const double bytes = BYTES_FIXED + BYTES_PER_LEAF * (estimate_leaves(m, &g) + field);
  m->estimate_mb = bytes / 1048576.0;
  if (room <= 0 || bytes <= room) return MX_OK;
  mx_error(m->domain.path, 0, "the requests would take about %.0f MB and %s %.0f MB: ask for "
           "lower levels or smaller regions", m->estimate_mb,
           m->p.max_memory_mb > 0 ? "the limit is" : "this machine has", room / 1048576.0);
  return MX_ENOMEM;
}

/* ---- the pipeline -------------------------------------------------------------------- */

double mx_qarea_tolerance(const mx_poly *P, const mx_qcheck_report *c, size_t ncells) {
  const double h = ncells ? sqrt(fabs(c->area) / (double)ncells) : 0.0;
  return fmin(fmax(AREA_TOL, 0.5 * poly_length(P) * h / fabs(c->domain_area)), AREA_TOL_MAX);
}

/* The independent check, and what it means: MX_EINVALID naming what failed. */
static int check_mesh(mx_mesher2d *m) {
  const char *name = m->domain.path;
  const mx_poly *dom = mx_mesher2d_outer(m);
  if (m->M.ncells == 0) {
    mx_error(name, 0, "the mesh is empty: no cell lies in the domain; ask for finer levels");
    return MX_EINPUT;
  }
  const double t = mx_wtime();
  const int st = mx_qmesh_check(&m->M, dom, CHECK_TOL, &m->cr);
  m->rec->t[M2_CHECK] = mx_wtime() - t;
  if (st == MX_EINTERNAL && !m->rec->last_error[0])
    mx_error(NULL, 0, "internal failure in the check stage");
  MX_CHECK(st);
  m->checked = 1;
  const mx_qcheck_report *c = &m->cr;
  m->area_tol = mx_qarea_tolerance(dom, c, m->M.ncells);
  if (m->p.materials && (m->cs.unresolved || m->cs.features_missed)) {
    mx_error(name, 0, "materials: %zu cell(s) that the interfaces meet could not be cut along "
             "them and %zu sharp vertex(es) of theirs found no node (a loop meets a cell more "
             "often than it can tell): ask for a finer level there", m->cs.unresolved,
             m->cs.features_missed);
    return MX_EINVALID;
  }
  if (c->bad_edges || c->hanging || c->inverted || m->q.invalid) {
    mx_error(name, 0, "the mesh is not valid: %zu bad edge(s), %zu hanging node(s), %zu "
             "inverted cell(s) (%zu with scaled Jacobian <= 0)", c->bad_edges, c->hanging,
             c->inverted, m->q.invalid);
    return MX_EINVALID;
  }
  if (c->off_boundary || c->missing_features) {
    mx_error(name, 0, "the mesh's boundary is off the polylines: %zu boundary node(s) off, "
             "%zu feature(s) not a vertex", c->off_boundary, c->missing_features);
    return MX_EINVALID;
  }
  if (c->euler != c->domain_euler) {
    mx_error(name, 0, "the mesh's topology differs from the domain's: %ld component(s) minus "
             "hole(s) against %ld: the levels are too coarse for thin parts of the domain",
             c->euler, c->domain_euler);
    return MX_EINVALID;
  }
  if (!(c->area_error <= m->area_tol)) {
    mx_error(name, 0, "the mesh covers %.4g against the domain's %.4g (%.1f%% off; tolerance "
             "%.1f%%): the levels are too coarse for thin parts of the domain", c->area,
             c->domain_area, 100.0 * c->area_error, 100.0 * m->area_tol);
    return MX_EINVALID;
  }
  if (m->p.materials) {
    const double t2 = mx_wtime();
    const int ms = mx_mesher2d_materials_check(m, CHECK_TOL);
    m->rec->t[M2_CHECK] += mx_wtime() - t2;
    if (ms == MX_EINTERNAL && !m->rec->last_error[0])
      mx_error(NULL, 0, "internal failure in the materials' check");
    MX_CHECK(ms);
  }
  m->valid = 1;
  return MX_OK;
}

/* After a stage: its status, and the thread count measured again for the
 * next one (call.h). */
static int stage(mx_mesher2d *m, int st, const char *name) {
  if (st == MX_EINTERNAL && !m->rec->last_error[0])
    mx_error(NULL, 0, "internal failure in the %s stage", name);
  mx_call_recheck();
  if (!st) st = mx_cancel_check(); /* base/cancel.h */
  return st;
}

int mx_mesher2d_run(mx_mesher2d *m) {
  if (!m->has_domain) {
    mx_error(NULL, 0, "no domain: set one first (mx_mesher2d_set_domain)");
    return MX_EINPUT;
  }
  free_mesh(m);
  for (int p = M2_REFINE; p < M2_NPH; p++) m->rec->t[p] = 0;
  m->t_materials = 0;
  MX_CHECK(check_memory(m));
  if (m->p.materials) MX_CHECK(mx_mesher2d_materials_prepare(m));
  /* with nested materials the quadtree and the boundary step see the
   * outer loops; the interfaces refine as the domain's polylines do */
  const int nested = mx_mesher2d_nested(m);
  const mx_poly *dom = nested ? &m->outer : &m->domain;
  const mx_poly_index *idx = nested ? &m->outer_index : &m->index;
  mx_poly *drawings = m->drawings;
  int *drawing_level = m->drawing_level;
  size_t ndrawings = m->ndrawings;
  if (nested && m->p.surface_level > 0) {
    drawings = mx_alloc((ndrawings + 1) * sizeof *drawings);
    drawing_level = mx_alloc((ndrawings + 1) * sizeof *drawing_level);
    if (!drawings || !drawing_level) {
      mx_free(drawings), mx_free(drawing_level);
      return MX_ENOMEM;
    }
    for (size_t k = 0; k < ndrawings; k++)
      drawings[k] = m->drawings[k], drawing_level[k] = m->drawing_level[k];
    drawings[ndrawings] = m->interfaces;
    drawing_level[ndrawings++] = m->p.surface_level;
  }
  mx_qbox *boxes = m->boxes;
  size_t nboxes = m->nboxes;
  int fst = feature_boxes(m, &boxes, &nboxes);
  if (fst) {
    if (drawings != m->drawings) mx_free(drawings), mx_free(drawing_level);
    return fst;
  }
  m->feature_boxes = nboxes - m->nboxes;
  const mx_qrequests req = {
      /* level 0 asks for nothing either: the quadtree's requests take 0 */
      .s_level = m->p.surface_level > 0 ? m->p.surface_level : 0,
      .a_level = m->p.all_level > 0 ? m->p.all_level : 0,
      .nboxes = nboxes, .boxes = boxes,
      .nregions = m->nregions, .regions = m->regions, .region_level = m->region_level,
      .ndrawings = ndrawings, .drawings = drawings, .drawing_level = drawing_level,
      .nfuns = m->nfuns, .funs = m->funs, .size_field = m->size.cs,
      .nkeep = m->nkeep, .keep_key = m->keep_key, .keep_level = m->keep_level};
  const int balance = m->p.balance == MX_BALANCE_RECURSIVE ? MX_QBALANCE_RECURSIVE
                                                           : MX_QBALANCE_EDGES;
  double t = mx_wtime();
  int st = mx_qtree_build(dom, idx, &req, balance, &m->T, &m->qs);
  if (boxes != m->boxes) mx_free(boxes);
  if (drawings != m->drawings) mx_free(drawings), mx_free(drawing_level);
  if (!st) st = mx_qtree_leaves(&m->T, &m->leaves, &m->nleaves);
  const double wall = mx_wtime() - t;
  m->rec->t[M2_BALANCE] = m->qs.t_balance;
  m->rec->t[M2_REFINE] = m->qs.t_refine > 0 ? wall - m->qs.t_balance : wall;
  MX_CHECK(stage(m, st, "refine"));
  t = mx_wtime();
  st = mx_qtransition(&m->T, m->leaves, m->nleaves, &m->M);
  m->rec->t[M2_TRANSITION] = mx_wtime() - t;
  MX_CHECK(stage(m, st, "transition"));
  t = mx_wtime();
  st = mx_qboundary(dom, idx, &m->T, m->leaves, m->p.close_ratio, &m->M, &m->bs);
  m->rec->t[M2_BOUNDARY] = mx_wtime() - t;
  MX_CHECK(stage(m, st, "boundary"));
  if (m->p.materials) {
    t = mx_wtime();
    st = mx_mesher2d_materials_label(m);
    m->rec->t[M2_BOUNDARY] += mx_wtime() - t;
    MX_CHECK(stage(m, st, "materials"));
  }
  m->meshed = 1;
  t = mx_wtime();
  mx_qquality_measure(&m->M, &m->q);
  m->rec->t[M2_QUALITY] = mx_wtime() - t;
  return check_mesh(m);
}

/* A failed build leaves no tree: the kept leaves stay for the next call. */
static int mesh(mx_mesher2d *m) {
  m->refined_listed = 0;
  return mx_mesher2d_run(m);
}

int mx_mesher2d_mesh(mx_mesher2d *m) { CALL(m, mesh(m)); }

void mx_mesher2d_cancel(mx_mesher2d *m) { atomic_store(&m->cancel, 1); }

/* ---- re-meshing ---------------------------------------------------------------------- */

/* keep := the current leaves (levels as they are). */
static int keep_current(mx_mesher2d *m) {
  const size_t n = m->nleaves;
  uint64_t *k = mx_alloc((n + 1) * sizeof *k);
  uint8_t *l = mx_alloc(n + 1);
  if (!k || !l) {
    mx_free(k);
    mx_free(l);
    return MX_ENOMEM;
  }
#pragma omp parallel for schedule(static) if (n > 65536)
  for (size_t i = 0; i < n; i++) {
    k[i] = m->T.key[m->leaves[i]];
    l[i] = m->T.level[m->leaves[i]];
  }
  free_keep(m);
  m->keep_key = k, m->keep_level = l, m->nkeep = n;
  return MX_OK;
}

/* The kept leaves of the listed elements, each raised one level once. */
static int mark_elements(mx_mesher2d *m, const uint64_t *el, size_t n, int from_restart) {
  uint8_t *raised = mx_calloc(m->nkeep + 1);
  uint64_t *first = from_restart ? mx_alloc((m->rs_n + 1) * sizeof *first) : NULL;
  if (!raised || (from_restart && !first)) {
    mx_free(raised);
    mx_free(first);
    return MX_ENOMEM;
  }
  size_t limit = m->M.ncells;
  if (from_restart) { /* element -> file quadrant: the first element of each */
    uint64_t s = 0;
    for (size_t i = 0; i < m->rs_n; i++) first[i] = s, s += m->rs_nsub[i];
    first[m->rs_n] = s;
    limit = (size_t)s;
  }
  int st = MX_OK;
  m->refined_listed = 0;
  for (size_t i = 0; i < n && !st; i++) {
    if (el[i] >= limit) {
      mx_error(NULL, 0, "element %llu of the list does not exist (the mesh has %zu)",
               (unsigned long long)el[i], limit);
      st = MX_EINPUT;
      break;
    }
    size_t k;
    if (from_restart) {
      size_t lo = 0, hi = m->rs_n; /* the last quadrant whose first element <= el */
      while (hi - lo > 1) {
        const size_t mid = lo + (hi - lo) / 2;
        if (first[mid] <= el[i]) lo = mid;
        else hi = mid;
      }
      k = m->rs_pos[lo];
    } else {
      k = m->M.leaf[el[i]];
    }
    if (raised[k]) continue;
    raised[k] = 1;
    if (m->keep_level[k] + 1 > MX_QMAX_LEVEL - 1) {
      mx_error(NULL, 0, "element %llu is in a quadrant of level %d, the finest: it cannot be "
               "refined", (unsigned long long)el[i], m->keep_level[k]);
      st = MX_EINPUT;
      break;
    }
    m->keep_level[k]++;
    m->refined_listed++;
  }
  mx_free(raised);
  mx_free(first);
  return st;
}

static int refine_elements(mx_mesher2d *m, const uint64_t *el, size_t n) {
  if (!m->has_domain) {
    mx_error(NULL, 0, "no domain: set one first (mx_mesher2d_set_domain)");
    return MX_EINPUT;
  }
  const int from_restart = !m->meshed && m->rs_n > 0;
  if (!from_restart && !m->meshed) {
    mx_error(NULL, 0, "no mesh to refine: mesh first or load a restart file");
    return MX_EINPUT;
  }
  if (!from_restart) MX_CHECK(keep_current(m));
  if (n && !el) return MX_EINPUT;
  MX_CHECK(mark_elements(m, el, n, from_restart));
  const size_t listed = m->refined_listed;
  const int st = mx_mesher2d_run(m);
  m->refined_listed = listed;
  return st;
}

int mx_mesher2d_refine_elements(mx_mesher2d *m, const uint64_t *el, size_t n) {
  CALL(m, refine_elements(m, el, n));
}

static int refine(mx_mesher2d *m) {
  if (m->meshed) MX_CHECK(keep_current(m));
  m->refined_listed = 0;
  return mx_mesher2d_run(m);
}

int mx_mesher2d_refine(mx_mesher2d *m) { CALL(m, refine(m)); }

static int save_restart(const mx_mesher2d *m, const char *path) {
  if (!m->meshed) {
    mx_error(path, 0, "no mesh to save the quadtree of");
    return MX_EINPUT;
  }
  const double t = mx_wtime();
  mx_restart r;
  int st = mx_qrestart_from_mesher(m, &r);
  if (!st) st = mx_restart_write_text(path, &r);
  mx_restart_free(&r);
  m->rec->t_restart += mx_wtime() - t;
  return st;
}

int mx_mesher2d_save_restart(const mx_mesher2d *m, const char *path) {
  CALL(m, save_restart(m, path));
}

static int load_restart(mx_mesher2d *m, const char *path) {
  if (!m->has_domain) {
    mx_error(path, 0, "set the domain before loading a restart file (its quadrants must lie "
                      "on the domain's quadtree)");
    return MX_EINPUT;
  }
  const double t = mx_wtime();
  mx_restart r;
  int st = mx_restart_read_dim(path, 2, &r);
  if (!st) {
    free_mesh(m);
    free_keep(m);
    st = mx_qrestart_to_keep(m, &r);
    if (st) free_keep(m);
  }
  mx_restart_free(&r);
  m->rec->t_restart = mx_wtime() - t;
  return st;
}

int mx_mesher2d_load_restart(mx_mesher2d *m, const char *path) { CALL(m, load_restart(m, path)); }

size_t mx_mesher2d_restart_elements(const mx_mesher2d *m) {
  size_t s = 0;
  for (size_t i = 0; m->rs_nsub && i < m->rs_n; i++) s += m->rs_nsub[i];
  return s;
}

/* ---- output and figures -------------------------------------------------------------- */

static int write_mesh(const mx_mesher2d *m, const char *path, int ascii) {
  if (!m->meshed) {
    mx_error(path, 0, "no mesh to write");
    return MX_EINPUT;
  }
  const double t = mx_wtime();
  double *size = NULL; /* with a size field: target_size */
  int st = mx_mesher2d_target_sizes(m, &size);
  if (!st)
    st = m->material ? mx_mesher2d_write_materials(m, path, ascii, size)
                     : mx_write_qmesh_tagged(path, &m->M, ascii, NULL, size);
  mx_free(size);
  m->rec->t[M2_WRITE] += mx_wtime() - t;
  return st;
}

int mx_mesher2d_write(const mx_mesher2d *m, const char *path, int ascii) {
  CALL(m, write_mesh(m, path, ascii));
}

int mx_mesher2d_mesh_arrays(const mx_mesher2d *m, mx_mesh2d_arrays *a) {
  memset(a, 0, sizeof *a);
  if (!m->meshed) return MX_EINPUT;
  a->nnodes = m->M.nnodes, a->ncells = m->M.ncells, a->nleaves = m->nleaves;
  a->xy = m->M.xy, a->type = m->M.type, a->conn = m->M.conn;
  a->leaf = m->M.leaf, a->level = m->M.level;
  a->material = m->material;
  return MX_OK;
}

void mx_mesher2d_stats(const mx_mesher2d *m, mx_stats2d *s) {
  memset(s, 0, sizeof *s);
  s->leaves = m->nleaves, s->quadrants = m->T.n;
  s->nodes = m->M.nnodes, s->cells = m->M.ncells;
  s->tris = m->q.count[0], s->quads = m->q.count[1], s->invalid = m->q.invalid;
  s->refined_listed = m->refined_listed;
  s->split_balance = m->qs.balance_splits;
  s->valid = m->valid;
  s->materials = m->material ? m->nmaterials : 0;
  s->sj_min = fmin(m->q.count[0] ? m->q.min[0] : 1, m->q.count[1] ? m->q.min[1] : 1);
  s->min_angle = m->q.min_angle;
  s->t_read = m->rec->t[M2_READ], s->t_refine = m->rec->t[M2_REFINE], s->t_balance = m->rec->t[M2_BALANCE];
  s->t_transition = m->rec->t[M2_TRANSITION], s->t_boundary = m->rec->t[M2_BOUNDARY];
  s->t_quality = m->rec->t[M2_QUALITY], s->t_check = m->rec->t[M2_CHECK], s->t_restart = m->rec->t_restart;
}
