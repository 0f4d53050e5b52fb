#include "geom/quality.h"

#include <math.h>
#include <stdlib.h>

#include "soa/mesh.h"

static const double K_TET = 0.70710678118654752440;
static const double K_PRISM = 0.86602540378443864676;

/* Unit edge vectors of an element, each edge normalized once, as arrays
 * of components (the square roots and divisions of all edges at once, two
 * to a vector instruction): u_e = (p[b] - p[a]) / |p[b] - p[a]| for edge
 * e = (a, b); ok[e] 0 for a collapsed edge. The vector from b to a is -u_e
 * exactly (a - b = -(b - a), the same sum of squares, (-d) / l = -(d / l)),
 * so the values are those of normalizing from each end. */
enum { MAX_EDGES = 12 };
typedef struct {
  double x[MAX_EDGES], y[MAX_EDGES], z[MAX_EDGES];
  int ok[MAX_EDGES];
} unit_edges;

static inline void unit_vectors(const double (*p)[3], int type, unit_edges *U) {
  const int8_t(*ed)[2] = mx_cell_edge[type];
  const int ne = mx_cell_nedges[type];
  double dx[MAX_EDGES], dy[MAX_EDGES], dz[MAX_EDGES], l[MAX_EDGES];
  for (int e = 0; e < ne; e++) {
    dx[e] = p[ed[e][1]][0] - p[ed[e][0]][0];
    dy[e] = p[ed[e][1]][1] - p[ed[e][0]][1];
    dz[e] = p[ed[e][1]][2] - p[ed[e][0]][2];
  }
  for (int e = 0; e < ne; e++) l[e] = sqrt(dx[e] * dx[e] + dy[e] * dy[e] + dz[e] * dz[e]);
  for (int e = 0; e < ne; e++) {
    U->x[e] = dx[e] / l[e];
    U->y[e] = dy[e] / l[e];
    U->z[e] = dz[e] / l[e];
    U->ok[e] = l[e] > 0.0;
  }
}

/* J_S at a corner whose three neighbours are along edges r[0..2]: r = e + 1
 * for the edge's direction, -(e + 1) for the opposite one. (d_a x d_b) . d_c
 * of the unit vectors; -1 when an edge is collapsed (invalid). */
static inline double js(const unit_edges *U, const int8_t r[3]) {
  double d[3][3];
  for (int k = 0; k < 3; k++) {
    const int e = (r[k] > 0 ? r[k] : -r[k]) - 1;
    if (!U->ok[e]) return -1.0;
    const double s = r[k] > 0 ? 1.0 : -1.0; /* (exact: -u is u times -1) */
    d[k][0] = s * U->x[e];
    d[k][1] = s * U->y[e];
    d[k][2] = s * U->z[e];
  }
  const double cx = d[0][1] * d[1][2] - d[0][2] * d[1][1];
  const double cy = d[0][2] * d[1][0] - d[0][0] * d[1][2];
  const double cz = d[0][0] * d[1][1] - d[0][1] * d[1][0];
  return cx * d[2][0] + cy * d[2][1] + cz * d[2][2];
}

static double ens(double j, double k) {
  if (j > k) return (1.0 + k) - j;
  if (j < -k) return -(1.0 + k) - j;
  return j / k;
}

/* Least value if all positive, else the largest negative one. */
static double combine(const double *q, int n) {
  double mn = INFINITY, neg = -INFINITY;
  int any_neg = 0;
  for (int i = 0; i < n; i++) {
    if (q[i] < mn) mn = q[i];
    if (q[i] <= 0.0) {
      any_neg = 1;
      if (q[i] > neg) neg = q[i];
    }
  }
  return any_neg ? neg : mn;
}

/* Per type, each corner's three neighbours as edges of mx_cell_edge (e + 1
 * along edge e, -(e + 1) against it), in the order of the corner's
 * (d_a x d_b) . d_c. */
/* neighbours {1,2,3} {2,0,3} {0,1,3} {2,1,0} */
static const int8_t tet_cr[4][3] = {{1, -3, 4}, {2, -1, 5}, {3, -2, 6}, {-6, -5, -4}};
/* base neighbours {1,3,4} {2,0,4} {3,1,4} {0,2,4}; then the apex's four
 * tetrahedra of consecutive base nodes: {i+2, i+1, i} (mod 4) */
static const int8_t pyr_cr[8][3] = {{1, -4, 5},   {2, -1, 6},   {3, -2, 7},   {4, -3, 8},
                                    {-7, -6, -5}, {-8, -7, -6}, {-5, -8, -7}, {-6, -5, -8}};
/* neighbours {1,2,3} {2,0,4} {0,1,5} {5,4,0} {3,5,1} {4,3,2} */
static const int8_t pri_cr[6][3] = {{1, -3, 7},  {2, -1, 8}, {3, -2, 9},
                                    {-6, 4, -7}, {-4, 5, -8}, {-5, 6, -9}};
/* neighbours {1,3,4} {2,0,5} {3,1,6} {0,2,7} {7,5,0} {4,6,1} {5,7,2} {6,4,3} */
static const int8_t hex_cr[8][3] = {{1, -4, 9},   {2, -1, 10},  {3, -2, 11},  {4, -3, 12},
                                    {-8, 5, -9},  {-5, 6, -10}, {-6, 7, -11}, {-7, 8, -12}};

double mx_jens_tet(const double p[4][3]) {
  unit_edges U;
  unit_vectors(p, MX_TET, &U);
  double q[4];
  for (int i = 0; i < 4; i++) q[i] = ens(js(&U, tet_cr[i]), K_TET);
  return combine(q, 4);
}

double mx_jens_pyramid(const double p[5][3]) {
  unit_edges U;
  unit_vectors(p, MX_PYRAMID, &U);
  double q[5];
  for (int i = 0; i < 4; i++) q[i] = ens(js(&U, pyr_cr[i]), K_TET);
  /* Apex: the four tetrahedra of consecutive base nodes. */
  double best_pos = INFINITY, best_neg = -INFINITY;
  for (int i = 0; i < 4; i++) {
    const double j = js(&U, pyr_cr[4 + i]);
    if (j > 0.0) {
      if (j < best_pos) best_pos = j;
    } else if (j > best_neg) {
      best_neg = j;
    }
  }
  q[4] = ens(isfinite(best_pos) ? best_pos : best_neg, K_TET);
  return combine(q, 5);
}

double mx_jens_prism(const double p[6][3]) {
  unit_edges U;
  unit_vectors(p, MX_PRISM, &U);
  double q[6];
  for (int i = 0; i < 6; i++) q[i] = ens(js(&U, pri_cr[i]), K_PRISM);
  return combine(q, 6);
}

double mx_jens_hex(const double p[8][3]) {
  unit_edges U;
  unit_vectors(p, MX_HEX, &U);
  double q[8];
  for (int i = 0; i < 8; i++) q[i] = ens(js(&U, hex_cr[i]), 1.0);
  return combine(q, 8);
}

double mx_jens(int type, const double (*p)[3]) {
  switch (type) {
  case MX_TET: return mx_jens_tet(p);
  case MX_PYRAMID: return mx_jens_pyramid(p);
  case MX_PRISM: return mx_jens_prism(p);
  default: return mx_jens_hex(p);
  }
}

double mx_element_volume(int type, const double (*p)[3]) {
  const int8_t (*f)[4] = mx_cell_faces[type];
  const int nf = mx_cell_nfaces[type];
  /* Divergence theorem: V = 1/6 sum over outward triangles of a.(b x c). */
  double v = 0.0;
  for (int i = 0; i < nf; i++) {
    const int k = f[i][3] < 0 ? 3 : 4;
    double c[3] = {0, 0, 0};
    for (int j = 0; j < k; j++)
      for (int x = 0; x < 3; x++) c[x] += p[f[i][j]][x] / k;
    for (int j = 0; j < k; j++) {
      const double *a = p[f[i][j]], *b = p[f[i][(j + 1) % k]];
      if (k == 3 && j > 0) break; /* a triangle is its own triangulation */
      const double *t0 = k == 3 ? p[f[i][0]] : c;
      const double *t1 = k == 3 ? p[f[i][1]] : a;
      const double *t2 = k == 3 ? p[f[i][2]] : b;
      v += t0[0] * (t1[1] * t2[2] - t1[2] * t2[1]) -
           t0[1] * (t1[0] * t2[2] - t1[2] * t2[0]) +
           t0[2] * (t1[0] * t2[1] - t1[1] * t2[0]);
    }
  }
  return v / 6.0;
}

void mx_quality_tabulate(const uint8_t *type, const float *jens, size_t n,
                         mx_quality_table *q) {
  const size_t chunk = 65536, nch = (n + chunk - 1) / chunk;
  for (int t = 0; t < 4; t++) {
    q->count[t] = 0;
    q->min[t] = INFINITY;
    q->max[t] = -INFINITY;
    q->mean[t] = 0.0;
  }
  for (int b = 0; b < MX_QBINS; b++) q->bins[b] = 0;
  q->invalid = q->below_02 = 0;
  q->min_all = INFINITY;
  if (n == 0) return;
  /* chunk sums added in chunk order whatever the thread count, a group of
   * GROUP chunks at a time (no allocation: this cannot fail) */
  enum { GROUP = 256 };
  double sum[4 * GROUP];
  double s[4] = {0.0, 0.0, 0.0, 0.0};
  size_t count[4] = {0}, bins[MX_QBINS] = {0}, invalid = 0, below = 0;
  double mn[4] = {INFINITY, INFINITY, INFINITY, INFINITY};
  double mx[4] = {-INFINITY, -INFINITY, -INFINITY, -INFINITY};
  for (size_t g0 = 0; g0 < nch; g0 += GROUP) {
    const size_t ng = nch - g0 < GROUP ? nch - g0 : GROUP;
    for (size_t k = 0; k < 4 * ng; k++) sum[k] = 0.0;
#pragma omp parallel for schedule(static) reduction(+ : count[:4], bins[:MX_QBINS], invalid, below) \
    reduction(min : mn[:4]) reduction(max : mx[:4])
    for (size_t c = g0; c < g0 + ng; c++) {
      const size_t hi = (c + 1) * chunk < n ? (c + 1) * chunk : n;
      for (size_t i = c * chunk; i < hi; i++) {
        const int t = type[i];
        const double v = jens[i];
        count[t]++;
        sum[4 * (c - g0) + t] += v;
        if (v < mn[t]) mn[t] = v;
        if (v > mx[t]) mx[t] = v;
        int b = 0;
        while (b < MX_QBINS - 1 && !(v < mx_qbin_upper[b])) b++;
        bins[b]++;
        invalid += mx_jens_invalid(v);
        below += v < 0.2;
      }
    }
    for (int t = 0; t < 4; t++)
      for (size_t c = 0; c < ng; c++) s[t] += sum[4 * c + t];
  }
  for (int t = 0; t < 4; t++) {
    q->count[t] = count[t];
    q->min[t] = mn[t];
    q->max[t] = mx[t];
    q->mean[t] = count[t] ? s[t] / (double)count[t] : 0.0;
    if (mn[t] < q->min_all) q->min_all = mn[t];
  }
  for (int b = 0; b < MX_QBINS; b++) q->bins[b] = bins[b];
  q->invalid = invalid;
  q->below_02 = below;
}
