#include "geom/quality.h"

#include <math.h>
#include <stdlib.h>

#include "soa/mesh.h"

static const double K_TET = 0.70710678118654752440;
static const double K_PRISM = 0.86602540378443864676;

/* Unit edge vectors of an element, each edge normalized once: u[i][j] is
 * the unit vector from node i to node j, ok[i][j] 0 for a collapsed edge.
 * u[j][i] = -u[i][j] holds exactly in floating point (a - b = -(b - a), the
 * same sum of squares, (-d) / l = -(d / l)), so the values are those of
 * normalizing from each end. */
typedef struct {
  double u[8][8][3];
  uint8_t ok[8][8];
} unit_edges;

static void add_edge(unit_edges *E, const double (*p)[3], int i, int j) {
  double d[3], l = 0.0;
  for (int x = 0; x < 3; x++) {
    d[x] = p[j][x] - p[i][x];
    l += d[x] * d[x];
  }
  l = sqrt(l);
  const int ok = l > 0.0;
  E->ok[i][j] = E->ok[j][i] = (uint8_t)ok;
  if (!ok) return;
  for (int x = 0; x < 3; x++) {
    E->u[i][j][x] = d[x] / l;
    E->u[j][i][x] = -E->u[i][j][x];
  }
}

/* J_S at node i with neighbours a, b, c: (d_a x d_b) . d_c, unit vectors;
 * -1 when an edge is collapsed (invalid). */
static double js(const unit_edges *E, int i, int a, int b, int c) {
  if (!E->ok[i][a] || !E->ok[i][b] || !E->ok[i][c]) return -1.0;
  const double *d0 = E->u[i][a], *d1 = E->u[i][b], *d2 = E->u[i][c];
  const double cx = d0[1] * d1[2] - d0[2] * d1[1];
  const double cy = d0[2] * d1[0] - d0[0] * d1[2];
  const double cz = d0[0] * d1[1] - d0[1] * d1[0];
  return cx * d2[0] + cy * d2[1] + cz * d2[2];
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

/* The corners' neighbour triples and the element's edges, per type. */
static void corners(const double (*p)[3], const int (*nb)[3], int n, const int (*edges)[2],
                    int ne, double k, double *q, unit_edges *E) {
  for (int e = 0; e < ne; e++) add_edge(E, p, edges[e][0], edges[e][1]);
  for (int i = 0; i < n; i++) q[i] = ens(js(E, i, nb[i][0], nb[i][1], nb[i][2]), k);
}

double mx_jens_tet(const double p[4][3]) {
  static const int nb[4][3] = {{1, 2, 3}, {2, 0, 3}, {0, 1, 3}, {2, 1, 0}};
  static const int ed[6][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};
  double q[4];
  unit_edges E;
  corners(p, nb, 4, ed, 6, K_TET, q, &E);
  return combine(q, 4);
}

double mx_jens_pyramid(const double p[5][3]) {
  static const int nb[4][3] = {{1, 3, 4}, {2, 0, 4}, {3, 1, 4}, {0, 2, 4}};
  static const int ed[8][2] = {{0, 1}, {1, 2}, {2, 3}, {3, 0},
                               {0, 4}, {1, 4}, {2, 4}, {3, 4}};
  double q[5];
  unit_edges E;
  corners(p, nb, 4, ed, 8, K_TET, q, &E);
  /* Apex: the four tetrahedra of consecutive base nodes. */
  double best_pos = INFINITY, best_neg = -INFINITY;
  for (int i = 0; i < 4; i++) {
    double j = js(&E, 4, (i + 2) % 4, (i + 1) % 4, i);
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
  static const int ed[9][2] = {{0, 1}, {1, 2}, {2, 0}, {3, 4}, {4, 5},
                               {5, 3}, {0, 3}, {1, 4}, {2, 5}};
  double q[6];
  unit_edges E;
  corners(p, nb, 6, ed, 9, K_PRISM, q, &E);
  return combine(q, 6);
}

double mx_jens_hex(const double p[8][3]) {
  static const int nb[8][3] = {{1, 3, 4}, {2, 0, 5}, {3, 1, 6}, {0, 2, 7},
                               {7, 5, 0}, {4, 6, 1}, {5, 7, 2}, {6, 4, 3}};
  static const int ed[12][2] = {{0, 1}, {1, 2}, {2, 3}, {3, 0}, {4, 5}, {5, 6},
                                {6, 7}, {7, 4}, {0, 4}, {1, 5}, {2, 6}, {3, 7}};
  double q[8];
  unit_edges E;
  corners(p, nb, 8, ed, 12, 1.0, q, &E);
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
