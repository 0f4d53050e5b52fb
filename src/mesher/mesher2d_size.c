/* The size field of the 2D mesher (issue 27; mesher2d --size EXPR|F1..F5,
 * --size-min, --size-max): the octree mesher's source and control space
 * (mesher/size_source.h, src/sizing/) over the domain's box, the z axis a
 * thin slab about z = 0 that the field does not vary along (the source is
 * asked at z = 0). The quadtree reads it through mx_qrequests.size_field:
 * a quadrant is split while its side exceeds the field's least size over
 * its box (quad/qrefine.c), with the other requests and the balance rule.
 *
 * The -f curves are sources of the field when there is one: a curve asked
 * at level RL asks for the side of level RL on it, s = root / 2^RL, and
 * s + d at distance d from it (slope 1: the size at most doubles over a
 * distance of itself, a gradation ratio of 2), the field the least of the
 * source and the curves, then bounded by --size-min / --size-max. The
 * quadrants a curve crosses are still given level RL by its request: the
 * same size on the curve, and exactly so, where the control space is only
 * within its tolerance (a K_L leaf holds the value at its centre). Without
 * a field the curves are requests only, as before. */
#include <math.h>
#include <string.h>

#include "base/common.h"
#include "mesher/mesher2d.h"
#include "sizing/cspace.h"

/* The slab's half-thickness, relative to the box's largest extent: thin
 * enough that no kd-tree rule ever splits along z (its longest-axis rule
 * would only after about 20 splits along each of x and y). */
#define SLAB 1e-6

int mx_mesher2d_set_size_function_(mx_mesher2d *m, mx_size_fn f, void *user,
                                   const mx_cspace_params *p) {
  return mx_size_source_set_function(&m->size, f, user, p);
}

int mx_mesher2d_set_size_expr_(mx_mesher2d *m, const char *text) {
  return mx_size_source_set_expr(&m->size, text);
}

int mx_mesher2d_set_size_limits_(mx_mesher2d *m, double hmin, double hmax) {
  return mx_size_source_set_limits(&m->size, hmin, hmax);
}

void mx_mesher2d_size_reset(mx_mesher2d *m) {
  mx_cspace_free(m->size.cs);
  m->size.cs = NULL;
}

void mx_mesher2d_size_free(mx_mesher2d *m) { mx_size_source_free(&m->size); }

/* ---- the field the control space samples ------------------------------------ */

typedef struct {
  const mx_mesher2d *m;
  double root; /* the quadtree's root side */
} field2d;

enum { CHUNK = 64 };

/* The source at (x, y, 0), lowered by the curves, bounded. A comparison,
 * not fmin: a size that is not a number stays one, for the control
 * space's check to name. */
static void sizes2d(void *user, size_t n, const double *xyz, double *h) {
  const field2d *F = user;
  const mx_mesher2d *m = F->m;
  double p[3 * CHUNK];
  for (size_t i0 = 0; i0 < n; i0 += CHUNK) {
    const size_t k = n - i0 < CHUNK ? n - i0 : CHUNK;
    double *hk = h + 3 * i0;
    for (size_t i = 0; i < k; i++) {
      p[3 * i] = xyz[3 * (i0 + i)];
      p[3 * i + 1] = xyz[3 * (i0 + i) + 1];
      p[3 * i + 2] = 0.0;
    }
    mx_size_source_eval(&m->size, k, p, hk);
    for (size_t f = 0; f < m->nfuns; f++) {
      const double s = ldexp(F->root, -m->funs[f].level);
      for (size_t i = 0; i < k; i++) {
        const double c = s + mx_qfun_distance(&m->funs[f], p[3 * i], p[3 * i + 1]);
        for (int a = 0; a < 3; a++)
          if (c < hk[3 * i + a]) hk[3 * i + a] = c;
      }
    }
    mx_size_source_clamp(&m->size, k, hk);
  }
}

int mx_mesher2d_size_space(mx_mesher2d *m, const mx_qgrid *g) {
  if (!mx_size_source_given(&m->size) || m->size.cs) return MX_OK;
  double lo2[2], hi2[2];
  mx_mesher2d_box(m, lo2, hi2);
  const double w = SLAB * fmax(hi2[0] - lo2[0], hi2[1] - lo2[1]);
  const double lo[3] = {lo2[0], lo2[1], -w}, hi[3] = {hi2[0], hi2[1], w};
  field2d F = {m, g->side};
  MX_CHECK(mx_size_source_build(&m->size, lo, hi, sizes2d, &F));
  m->size_cells = mx_size_source_cells(&m->size, 2, g->side, MX_QMAX_LEVEL - 1, &m->size_hmin,
                                       m->size_at);
  return MX_OK;
}

int mx_mesher2d_target_sizes(const mx_mesher2d *m, double **out) {
  *out = NULL;
  if (!m->size.cs) return MX_OK;
  const mx_qmesh *M = &m->M;
  double *t = mx_alloc((M->ncells + 1) * sizeof *t);
  if (!t) return MX_ENOMEM;
#pragma omp parallel for schedule(static) if (M->ncells > 16384)
  for (size_t c = 0; c < M->ncells; c++) {
    const int nv = M->type[c] == MX_QQUAD ? 4 : 3;
    double p[3] = {0.0, 0.0, 0.0};
    for (int k = 0; k < nv; k++)
      for (int a = 0; a < 2; a++) p[a] += M->xy[2 * (size_t)M->conn[4 * c + k] + a] / nv;
    t[c] = mx_size_source_at(&m->size, p);
  }
  *out = t;
  return MX_OK;
}
