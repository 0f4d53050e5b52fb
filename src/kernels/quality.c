#include "kernels/quality.h"

#include <math.h>
#include <stdlib.h>

#include "soa/mesh.h"

static const double K_TET = 0.70710678118654752440;
static const double K_PRISM = 0.86602540378443864676;

/* J_S at node i with neighbours a, b, c: (d_a x d_b) . d_c, unit vectors. */
static double js(const double (*p)[3], int i, int a, int b, int c) {
  double d[3][3];
  const int n[3] = {a, b, c};
  for (int k = 0; k < 3; k++) {
    double l = 0.0;
    for (int x = 0; x < 3; x++) {
      d[k][x] = p[n[k]][x] - p[i][x];
      l += d[k][x] * d[k][x];
    }
    l = sqrt(l);
    if (!(l > 0.0)) return -1.0; /* a collapsed edge: invalid */
    for (int x = 0; x < 3; x++) d[k][x] /= l;
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

double mx_jens_tet(const double p[4][3]) {
  static const int nb[4][3] = {{1, 2, 3}, {2, 0, 3}, {0, 1, 3}, {2, 1, 0}};
  double q[4];
  for (int i = 0; i < 4; i++) q[i] = ens(js(p, i, nb[i][0], nb[i][1], nb[i][2]), K_TET);
  return combine(q, 4);
}

double mx_jens_pyramid(const double p[5][3]) {
  static const int nb[4][3] = {{1, 3, 4}, {2, 0, 4}, {3, 1, 4}, {0, 2, 4}};
  double q[5];
  for (int i = 0; i < 4; i++) q[i] = ens(js(p, i, nb[i][0], nb[i][1], nb[i][2]), K_TET);
  /* Apex: the four tetrahedra of consecutive base nodes. */
  double best_pos = INFINITY, best_neg = -INFINITY;
  for (int i = 0; i < 4; i++) {
    double j = js(p, 4, (i + 2) % 4, (i + 1) % 4, i);
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
  static const int nb[6][3] = {{1, 2, 3}, {2, 0, 4}, {0, 1, 5},
                               {5, 4, 0}, {3, 5, 1}, {4, 3, 2}};
  double q[6];
  for (int i = 0; i < 6; i++) q[i] = ens(js(p, i, nb[i][0], nb[i][1], nb[i][2]), K_PRISM);
  return combine(q, 6);
}

double mx_jens_hex(const double p[8][3]) {
  static const int nb[8][3] = {{1, 3, 4}, {2, 0, 5}, {3, 1, 6}, {0, 2, 7},
                               {7, 5, 0}, {4, 6, 1}, {5, 7, 2}, {6, 4, 3}};
  double q[8];
  for (int i = 0; i < 8; i++) q[i] = ens(js(p, i, nb[i][0], nb[i][1], nb[i][2]), 1.0);
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

void mx_quality_tabulate(const uint8_t *type, const double *jens, size_t n,
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
  double *sum = calloc(4 * nch, sizeof *sum);
  if (!sum) return;
  size_t count[4] = {0}, bins[MX_QBINS] = {0}, invalid = 0, below = 0;
  double mn[4] = {INFINITY, INFINITY, INFINITY, INFINITY};
  double mx[4] = {-INFINITY, -INFINITY, -INFINITY, -INFINITY};
#pragma omp parallel for schedule(static) reduction(+ : count[:4], bins[:MX_QBINS], invalid, below) \
    reduction(min : mn[:4]) reduction(max : mx[:4])
  for (size_t c = 0; c < nch; c++) {
    const size_t hi = (c + 1) * chunk < n ? (c + 1) * chunk : n;
    for (size_t i = c * chunk; i < hi; i++) {
      const int t = type[i];
      const double v = jens[i];
      count[t]++;
      sum[4 * c + t] += v;
      if (v < mn[t]) mn[t] = v;
      if (v > mx[t]) mx[t] = v;
      int b = 0;
      while (b < MX_QBINS - 1 && !(v < mx_qbin_upper[b])) b++;
      bins[b]++;
      invalid += mx_jens_invalid(v);
      below += v < 0.2;
    }
  }
  for (int t = 0; t < 4; t++) {
    double s = 0.0;
    for (size_t c = 0; c < nch; c++) s += sum[4 * c + t];
    q->count[t] = count[t];
    q->min[t] = mn[t];
    q->max[t] = mx[t];
    q->mean[t] = count[t] ? s / (double)count[t] : 0.0;
    if (mn[t] < q->min_all) q->min_all = mn[t];
  }
  for (int b = 0; b < MX_QBINS; b++) q->bins[b] = bins[b];
  q->invalid = invalid;
  q->below_02 = below;
  free(sum);
}
