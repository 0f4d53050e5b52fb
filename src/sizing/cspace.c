/* The control space: parameters, the metric non-conformity, evaluation of a
 * source, and the calls of include/mixoct.h dispatched to the structures
 * (src/sizing/cspace.h). */
#include "sizing/cspace.h"

#include <math.h>
#include <string.h>

#include "base/common.h"
#include "base/morton.h"

void mx_cspace_params_default(mx_cspace_params *p) {
  memset(p, 0, sizeof *p);
  p->structure = MX_CS_KD_LEAF;
  p->split = MX_SPLIT_GRADIENT;
  p->hi[0] = p->hi[1] = p->hi[2] = 1.0;
  p->delta = 0.5;
  p->samples = 5;
}

double mx_metric_nonconformity(const double a[3], const double b[3]) {
  double s = 0.0;
  for (int i = 0; i < 3; i++) {
    const double r = a[i] / b[i], t = r - 1.0 / r, t2 = t * t;
    s += t2 * t2;
  }
  return sqrt(s);
}

void mx_cs_samples(const double lo[3], const double hi[3], int ns, double *xyz) {
  size_t w = 0;
  for (int k = 0; k < ns; k++)
    for (int j = 0; j < ns; j++)
      for (int i = 0; i < ns; i++) {
        const int ijk[3] = {i, j, k};
        for (int a = 0; a < 3; a++)
          xyz[w++] = ns == 1 ? 0.5 * (lo[a] + hi[a])
                             : lo[a] + (hi[a] - lo[a]) * (double)ijk[a] / (double)(ns - 1);
      }
}

int mx_cs_sizes_ok(const double *h, size_t n) {
  for (size_t i = 0; i < 3 * n; i++)
    if (!(h[i] > 0.0 && h[i] < INFINITY)) return 0;
  return 1;
}

int mx_cs_bad_sizes(const mx_cspace *c) {
  mx_error(NULL, 0, "size field: a size that is not finite and positive in the box "
                    "[%g, %g] x [%g, %g] x [%g, %g]", c->lo[0], c->hi[0], c->lo[1], c->hi[1],
           c->lo[2], c->hi[2]);
  return MX_EINPUT;
}

int mx_cs_eval(mx_size_fn f, void *user, size_t n, const double *xyz, double *h) {
  enum { BLOCK = 256 };
  const size_t nb = (n + BLOCK - 1) / BLOCK;
#pragma omp parallel for schedule(dynamic, 4) if (nb > 1)
  for (size_t b = 0; b < nb; b++) {
    const size_t i0 = b * BLOCK, m = n - i0 < BLOCK ? n - i0 : BLOCK;
    f(user, m, xyz + 3 * i0, h + 3 * i0);
  }
  size_t bad = SIZE_MAX;
#pragma omp parallel for schedule(static) reduction(min : bad) if (n > MX_PAR_MIN)
  for (size_t i = 0; i < 3 * n; i++)
    if (!(h[i] > 0.0 && h[i] < INFINITY) && i / 3 < bad) bad = i / 3;
  if (bad != SIZE_MAX) {
    const double *p = xyz + 3 * bad, *q = h + 3 * bad;
    mx_error(NULL, 0, "size field: the size at (%.9g, %.9g, %.9g) is (%g, %g, %g): sizes must "
                      "be finite and positive", p[0], p[1], p[2], q[0], q[1], q[2]);
    return MX_EINPUT;
  }
  return MX_OK;
}

int mx_cs_params_check(const mx_cspace_params *p, int box) {
  const int kd = p->structure == MX_CS_KD_LEAF || p->structure == MX_CS_KD_VERTEX;
  if (p->structure < MX_CS_KD_LEAF || p->structure > MX_CS_OCT_BALANCED ||
      (kd && (p->split < MX_SPLIT_LONGEST || p->split > MX_SPLIT_SUM))) {
    mx_error(NULL, 0, "size field: no structure %d with split rule %d", p->structure, p->split);
    return MX_EINPUT;
  }
  for (int a = 0; box && a < 3; a++)
    if (!(p->hi[a] > p->lo[a]) || !isfinite(p->lo[a]) || !isfinite(p->hi[a])) {
      mx_error(NULL, 0, "size field: an empty or infinite box ([%g, %g] along axis %d)",
               p->lo[a], p->hi[a], a);
      return MX_EINPUT;
    }
  if (!(p->delta > 0.0) || !isfinite(p->delta)) {
    mx_error(NULL, 0, "size field: the tolerance must be positive (%g)", p->delta);
    return MX_EINPUT;
  }
  const int ns = p->samples ? p->samples : 5;
  const int maxd = p->max_depth ? p->max_depth : kd ? 40 : 8;
  if (ns < 1 || ns > 16 || maxd < 0 || maxd > (kd ? 60 : 20)) {
    mx_error(NULL, 0, "size field: samples %d (1 to 16) or depth %d (up to %d) out of range",
             ns, maxd, kd ? 60 : 20);
    return MX_EINPUT;
  }
  return MX_OK;
}

int mx_cspace_build(const mx_cspace_params *p, mx_size_fn f, void *user, mx_cspace **out) {
  *out = NULL;
  if (!f) {
    mx_error(NULL, 0, "size field: no source function");
    return MX_EINPUT;
  }
  MX_CHECK(mx_cs_params_check(p, 1));
  const int kd = p->structure == MX_CS_KD_LEAF || p->structure == MX_CS_KD_VERTEX;
  const int ns = p->samples ? p->samples : 5;
  const int maxd = p->max_depth ? p->max_depth : kd ? 40 : 8;
  mx_cspace *c = mx_calloc(sizeof *c);
  if (!c) return MX_ENOMEM;
  c->structure = p->structure;
  c->split = kd ? p->split : MX_SPLIT_LONGEST;
  c->ns = ns;
  c->max_depth = maxd;
  c->delta = p->delta;
  memcpy(c->lo, p->lo, sizeof c->lo);
  memcpy(c->hi, p->hi, sizeof c->hi);
  const double t0 = mx_wtime();
  const int st = kd ? mx_cs_build_kd(c, f, user) : mx_cs_build_octree(c, f, user);
  c->seconds = mx_wtime() - t0;
  if (st) {
    mx_cspace_free(c);
    return st;
  }
  *out = c;
  return MX_OK;
}

int mx_cs_level(double root, double h, int max_level) {
  if (!(h > 0.0)) return max_level;
  const double t = ceil(log2(root / h) - 1e-9);
  return t <= 0.0 ? 0 : t >= max_level ? max_level : (int)t;
}

const char *mx_cs_structure_name(int structure, int split) {
  static const char *const kd[2][3] = {{"K_L s_L", "K_L s_G", "K_L s_S"},
                                       {"K_V s_L", "K_V s_G", "K_V s_S"}};
  if (structure == MX_CS_OCT_LEAF) return "K_oL";
  if (structure == MX_CS_OCT_BALANCED) return "K_oLB";
  return kd[structure == MX_CS_KD_VERTEX][split >= 0 && split <= 2 ? split : 0];
}

void mx_cspace_query(const mx_cspace *c, const double p[3], double h[3]) {
  if (c->structure <= MX_CS_KD_VERTEX) mx_cs_query_kd(c, p, h);
  else mx_cs_query_octree(c, p, h);
}

double mx_cspace_min_box(const mx_cspace *c, const double lo[3], const double hi[3]) {
  return c->structure <= MX_CS_KD_VERTEX ? mx_cs_min_box_kd(c, lo, hi)
                                         : mx_cs_min_box_octree(c, lo, hi);
}

void mx_cspace_info_get(const mx_cspace *c, mx_cspace_info *info) {
  memset(info, 0, sizeof *info);
  info->values = c->nvalues;
  info->depth = c->depth;
  info->capped = c->capped;
  info->seconds = c->seconds;
  info->bytes = sizeof *c + 24 * c->nvalues;
  if (c->structure <= MX_CS_KD_VERTEX) {
    info->nodes = c->nnodes;
    info->leaves = c->nleaves;
    /* axis 1, coord 8, child 4, val 4 a node; K_V 8 corner indices a leaf */
    info->bytes += 17 * c->nnodes + (c->vid ? 32 * c->nleaves : 0);
  } else {
    info->leaves = c->nleaves;
    info->nodes = c->nleaves + (c->nleaves - 1) / 7; /* a complete octree's */
    info->bytes += 9 * c->nleaves;
  }
}

void mx_cspace_free(mx_cspace *c) {
  if (!c) return;
  mx_free(c->axis);
  mx_free(c->coord);
  mx_free(c->child);
  mx_free(c->val);
  mx_free(c->vid);
  mx_free(c->key);
  mx_free(c->level);
  mx_free(c->h);
  mx_free(c);
}

/* One leaf's share of mx_cspace_cells. */
static void add_cells(int dim, const double lo[3], const double hi[3], double h, double floor,
                      double f, double *sum, double *hmin, double at[3]) {
  if (h < *hmin) {
    *hmin = h;
    for (int a = 0; a < 3; a++) at[a] = 0.5 * (lo[a] + hi[a]);
  }
  const double s = f * (h > floor ? h : floor);
  if (dim == 2) *sum += (hi[0] - lo[0]) * (hi[1] - lo[1]) / (s * s);
  else *sum += (hi[0] - lo[0]) * (hi[1] - lo[1]) * (hi[2] - lo[2]) / (s * s * s);
}

double mx_cspace_cells(const mx_cspace *c, int dim, double floor, double f, double *hmin,
                       double at[3]) {
  double sum = 0.0;
  *hmin = INFINITY;
  memcpy(at, c->lo, 3 * sizeof *at);
  if (c->structure > MX_CS_KD_VERTEX) {
    const double n = ldexp(1.0, c->max_depth);
    for (size_t i = 0; i < c->nleaves; i++) {
      uint32_t p[3];
      double lo[3], hi[3];
      mx_morton_decode(c->key[i], p);
      const double side = ldexp(1.0, c->max_depth - c->level[i]);
      for (int a = 0; a < 3; a++) {
        lo[a] = c->lo[a] + (c->hi[a] - c->lo[a]) * (double)p[a] / n;
        hi[a] = c->lo[a] + (c->hi[a] - c->lo[a]) * ((double)p[a] + side) / n;
      }
      const double *h = c->h + 3 * i;
      add_cells(dim, lo, hi, fmin(h[0], fmin(h[1], h[2])), floor, f, &sum, hmin, at);
    }
    return sum;
  }
  /* the kd-tree's leaves with their boxes: a walk with an explicit stack */
  struct {
    uint32_t node;
    double lo[3], hi[3];
  } st[128];
  int top = 0;
  st[0].node = 0;
  memcpy(st[0].lo, c->lo, sizeof st[0].lo);
  memcpy(st[0].hi, c->hi, sizeof st[0].hi);
  top = 1;
  while (top) {
    top--;
    const uint32_t i = st[top].node;
    double lo[3], hi[3];
    memcpy(lo, st[top].lo, sizeof lo);
    memcpy(hi, st[top].hi, sizeof hi);
    if (c->axis[i] == MX_KD_LEAF) {
      const int nv = c->structure == MX_CS_KD_LEAF ? 1 : 8;
      double h = INFINITY;
      for (int k = 0; k < nv; k++) {
        const uint32_t v = nv == 1 ? c->val[i] : c->vid[8 * (size_t)c->val[i] + k];
        for (int a = 0; a < 3; a++) h = fmin(h, c->h[3 * (size_t)v + a]);
      }
      add_cells(dim, lo, hi, h, floor, f, &sum, hmin, at);
      continue;
    }
    if (top + 2 > 128) continue; /* deeper than any build goes */
    const int a = c->axis[i];
    for (int s = 0; s < 2; s++) {
      st[top].node = c->child[i] + (uint32_t)s;
      memcpy(st[top].lo, lo, sizeof lo);
      memcpy(st[top].hi, hi, sizeof hi);
      if (s) st[top].lo[a] = c->coord[i];
      else st[top].hi[a] = c->coord[i];
      top++;
    }
  }
  return sum;
}

size_t mx_cspace_leaves(const mx_cspace *c, double *box, double *h) {
  const int kd = c->structure == MX_CS_KD_LEAF || c->structure == MX_CS_KD_VERTEX;
  return kd ? mx_cs_leaves_kd(c, box, h) : mx_cs_leaves_octree(c, box, h);
}
