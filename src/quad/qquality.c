/* 2D cell quality: the scaled Jacobian and the smallest angle of a cell, and
 * their statistics over a mesh (quad.h). */
#include <math.h>
#include <string.h>
#ifdef __SSE2__
#include <emmintrin.h>
#endif

#include "base/common.h"
#include "quad/quad.h"

/* The next and previous corner of a cell of nv corners (no division). */
static inline int nxt(int k, int nv) { return k + 1 == nv ? 0 : k + 1; }
static inline int prv(int k, int nv) { return k == 0 ? nv - 1 : k - 1; }

#define SIN60 0.86602540378443864676
#define DEG (180.0 / 3.14159265358979323846)

/* Corner k of the polygon v[0..nv): the edges to the next and the previous
 * node; e1 x e2 > 0 for a counter-clockwise convex corner. */
static void corner_edges(const double *xy, const uint32_t *v, int nv, int k, double e1[2],
                         double e2[2]) {
  const double *p = xy + 2 * (size_t)v[k];
  const double *a = xy + 2 * (size_t)v[nxt(k, nv)];
  const double *b = xy + 2 * (size_t)v[prv(k, nv)];
  e1[0] = a[0] - p[0];
  e1[1] = a[1] - p[1];
  e2[0] = b[0] - p[0];
  e2[1] = b[1] - p[1];
}

/* Whether quad v is a rectangle with sides along the axes, its corners
 * sharing their coordinates exactly (the quadtree's squares): then every
 * corner has the same cross product and the same product of squared edge
 * lengths as corner 0 (differences of the same coordinates, up to exact
 * changes of sign, multiplied in another order), so the same measures. */
static inline int axis_rect(const double *xy, const uint32_t *v) {
  const double *p0 = xy + 2 * (size_t)v[0], *p1 = xy + 2 * (size_t)v[1];
  const double *p2 = xy + 2 * (size_t)v[2], *p3 = xy + 2 * (size_t)v[3];
  return (p0[1] == p1[1] && p1[0] == p2[0] && p2[1] == p3[1] && p3[0] == p0[0]) ||
         (p0[0] == p1[0] && p1[1] == p2[1] && p2[0] == p3[0] && p3[1] == p0[1]);
}

/* Per corner k: cross(e1, e2) / sqrt(|e1|^2 |e2|^2), 0 for a collapsed
 * corner; the corners independent of each other (the square roots and
 * divisions of a cell run side by side), the least taken in corner order;
 * an axis-parallel rectangle's corners all give corner 0's. */
double mx_qsj_nodes(const double *xy, const uint32_t *v, int nv) {
  const int nk = nv == 4 && axis_rect(xy, v) ? 1 : nv; /* the corners to measure */
  double cr[4], l2[4], s[4];
  for (int k = 0; k < nk; k++) {
    double e1[2], e2[2];
    corner_edges(xy, v, nv, k, e1, e2);
    cr[k] = e1[0] * e2[1] - e1[1] * e2[0];
    l2[k] = (e1[0] * e1[0] + e1[1] * e1[1]) * (e2[0] * e2[0] + e2[1] * e2[1]);
  }
  int k = 0;
#ifdef __SSE2__
  /* two corners at a time: IEEE square roots and divisions, the same values */
  for (; k + 1 < nk; k += 2) {
    const __m128d l = _mm_sqrt_pd(_mm_loadu_pd(l2 + k));
    const __m128d pos = _mm_cmpgt_pd(l, _mm_setzero_pd());
    const __m128d q = _mm_div_pd(_mm_loadu_pd(cr + k), _mm_or_pd(_mm_and_pd(pos, l),
                                                                  _mm_andnot_pd(pos, _mm_set1_pd(1.0))));
    _mm_storeu_pd(s + k, _mm_and_pd(pos, q));
  }
#endif
  for (; k < nk; k++) {
    const double l = sqrt(l2[k]);
    /* A zero-length edge is a collapsed cell: not valid. */
    const double q = cr[k] / (l > 0 ? l : 1.0);
    s[k] = l > 0 ? q : 0.0;
  }
  double sj = INFINITY;
  for (k = 0; k < nk; k++) sj = mx_min(sj, s[k]);
  return nv == 3 ? sj / SIN60 : sj;
}

double mx_qangle_at(const double *xy, const uint32_t *v, int nv, int k) {
  double e1[2], e2[2];
  corner_edges(xy, v, nv, k, e1, e2);
  const double a =
      atan2(e1[0] * e2[1] - e1[1] * e2[0], e1[0] * e2[0] + e1[1] * e2[1]) * DEG;
  return a < 0 ? a + 360.0 : a;
}

static int cell_nv(const mx_qmesh *M, size_t c) { return M->type[c] == MX_QQUAD ? 4 : 3; }

double mx_qcell_sj(const mx_qmesh *M, size_t c) {
  return mx_qsj_nodes(M->xy, M->conn + 4 * c, cell_nv(M, c));
}

double mx_qcell_min_angle(const mx_qmesh *M, size_t c) {
  const int nv = cell_nv(M, c);
  double a = INFINITY;
  for (int k = 0; k < nv; k++) a = mx_min(a, mx_qangle_at(M->xy, M->conn + 4 * c, nv, k));
  return a;
}

/* mx_qcell_min_angle without the atan2 of the corners strictly between 90
 * and 180 degrees (cross > 0, dot < 0): a cell cannot have all its corners
 * there (its turns would not close), so the least of the others, when it is
 * at most a right angle, is the least of all; otherwise all are measured.
 * The right corners of the grid's squares need no atan2 either. */
static double min_angle_fast(const mx_qmesh *M, size_t c, double right) {
  const int nv = cell_nv(M, c);
  const uint32_t *v = M->conn + 4 * c;
  double a = INFINITY;
  if (nv == 4 && axis_rect(M->xy, v)) {
    /* all corners as corner 0: a right angle when counter-clockwise */
    double e1[2], e2[2];
    corner_edges(M->xy, v, nv, 0, e1, e2);
    if (e1[0] * e2[1] - e1[1] * e2[0] > 0) return right;
  }
  for (int k = 0; k < nv; k++) {
    double e1[2], e2[2];
    corner_edges(M->xy, v, nv, k, e1, e2);
    const double cr = e1[0] * e2[1] - e1[1] * e2[0], dot = e1[0] * e2[0] + e1[1] * e2[1];
    if (cr > 0 && dot < 0) continue;
    /* atan2(y > 0, +-0) is exactly pi / 2: a right angle as measured */
    a = mx_min(a, cr > 0 && dot == 0 ? right : mx_qangle_at(M->xy, v, nv, k));
  }
  return a <= right ? a : mx_qcell_min_angle(M, c);
}

/* Signed area (shoelace): negative for a clockwise cell. */
static double cell_area(const mx_qmesh *M, size_t c) {
  const uint32_t *v = M->conn + 4 * c;
  const int nv = cell_nv(M, c);
  double s = 0;
  for (int k = 0; k < nv; k++) {
    const double *p = M->xy + 2 * (size_t)v[k], *q = M->xy + 2 * (size_t)v[nxt(k, nv)];
    s += p[0] * q[1] - p[1] * q[0];
  }
  return 0.5 * s;
}

static int sj_bin(double sj) {
  static const double up[MX_QBINS - 1] = {0.03, 0.2, 0.4, 0.6, 0.8};
  int b = 0;
  while (b < MX_QBINS - 1 && !(sj < up[b])) b++;
  return b;
}

/* The sums are taken per block of a fixed size, then over the blocks in
 * order: the same additions for any thread count (identical reports). */
#define QBLOCK 4096

void mx_qquality_measure(const mx_qmesh *M, mx_qquality *q) {
  memset(q, 0, sizeof *q);
  const size_t n = M->ncells, nb = (n + QBLOCK - 1) / QBLOCK;
  double mn0 = INFINITY, mn1 = INFINITY, mx0 = -INFINITY, mx1 = -INFINITY, amin = INFINITY;
  size_t c0 = 0, c1 = 0, inv = 0;
  size_t b0 = 0, b1 = 0, b2 = 0, b3 = 0, b4 = 0, b5 = 0;
  double s0 = 0, s1 = 0, area = 0;
  const double right = atan2(1.0, 0.0) * DEG; /* a right angle, as measured */
#pragma omp parallel for schedule(dynamic, 1) ordered reduction(min : mn0, mn1, amin) \
    reduction(max : mx0, mx1) reduction(+ : c0, c1, inv, b0, b1, b2, b3, b4, b5)
  for (size_t b = 0; b < nb; b++) {
    double ps0 = 0, ps1 = 0, pa = 0;
    const size_t hi = (b + 1) * QBLOCK < n ? (b + 1) * QBLOCK : n;
    for (size_t c = b * QBLOCK; c < hi; c++) {
      const double sj = mx_qcell_sj(M, c);
      if (M->type[c] == MX_QQUAD) {
        c1++, ps1 += sj, mn1 = mx_min(mn1, sj), mx1 = mx_max(mx1, sj);
      } else {
        c0++, ps0 += sj, mn0 = mx_min(mn0, sj), mx0 = mx_max(mx0, sj);
      }
      inv += !(sj > 0);
      amin = mx_min(amin, min_angle_fast(M, c, right));
      pa += cell_area(M, c);
      switch (sj_bin(sj)) {
        case 0: b0++; break;
        case 1: b1++; break;
        case 2: b2++; break;
        case 3: b3++; break;
        case 4: b4++; break;
        default: b5++; break;
      }
    }
#pragma omp ordered
    {
      s0 += ps0;
      s1 += ps1;
      area += pa;
    }
  }
  q->count[0] = c0;
  q->count[1] = c1;
  q->min[0] = c0 ? mn0 : 0;
  q->min[1] = c1 ? mn1 : 0;
  q->max[0] = c0 ? mx0 : 0;
  q->max[1] = c1 ? mx1 : 0;
  q->mean[0] = c0 ? s0 / (double)c0 : 0;
  q->mean[1] = c1 ? s1 / (double)c1 : 0;
  q->min_angle = n ? amin : 0;
  const size_t bins[MX_QBINS] = {b0, b1, b2, b3, b4, b5};
  memcpy(q->bins, bins, sizeof bins);
  q->invalid = inv;
  q->area = area;
}

size_t mx_qmesh_bad_cell(const mx_qmesh *M) {
  size_t bad = M->ncells;
#pragma omp parallel for reduction(min : bad) schedule(static) if (M->ncells > 65536)
  for (size_t c = 0; c < M->ncells; c++) {
    int ok = M->type[c] <= MX_QQUAD;
    const int nv = M->type[c] == MX_QQUAD ? 4 : 3;
    for (int j = 0; ok && j < nv; j++) ok = M->conn[4 * c + j] < M->nnodes;
    if (!ok && c < bad) bad = c;
  }
  return bad;
}
