/* J_ENS on reference elements with known values (2015 paper, section 3). */
#include <math.h>

#include "check.h"
#include "geom/quality.h"
#include "soa/mesh.h"

static int near(double a, double b) { return fabs(a - b) < 1e-12; }

/* J_ENS from its definition, corner by corner (2015 paper): at corner i
 * with neighbours a, b, c, J_S = (u_a x u_b) . u_c with u_x the unit vector
 * from i to x (normalized from i's end: (p_x - p_i) / |p_x - p_i|), -1 when
 * one is collapsed; scaled by k (J_S > k: 1 + k - J_S, J_S < -k: -(1 + k) -
 * J_S, else J_S / k); the least if all are positive, else the largest
 * negative one. The pyramid's apex: the least positive of its four corners
 * (consecutive base nodes), else their largest. mx_jens computes each edge
 * once and negates it for the other end: the same values. */
static double ref_js(const double (*p)[3], int i, int a, int b, int c) {
  double u[3][3];
  const int nb[3] = {a, b, c};
  for (int k = 0; k < 3; k++) {
    double l = 0.0;
    for (int x = 0; x < 3; x++) {
      u[k][x] = p[nb[k]][x] - p[i][x];
      l += u[k][x] * u[k][x];
    }
    l = sqrt(l);
    if (!(l > 0.0)) return -1.0;
    for (int x = 0; x < 3; x++) u[k][x] /= l;
  }
  const double cx = u[0][1] * u[1][2] - u[0][2] * u[1][1];
  const double cy = u[0][2] * u[1][0] - u[0][0] * u[1][2];
  const double cz = u[0][0] * u[1][1] - u[0][1] * u[1][0];
  return cx * u[2][0] + cy * u[2][1] + cz * u[2][2];
}

static double ref_scale(double j, double k) {
  return j > k ? (1.0 + k) - j : j < -k ? -(1.0 + k) - j : j / k;
}

static double ref_jens(int t, const double (*p)[3]) {
  static const int tet[4][3] = {{1, 2, 3}, {2, 0, 3}, {0, 1, 3}, {2, 1, 0}};
  static const int pyr[4][3] = {{1, 3, 4}, {2, 0, 4}, {3, 1, 4}, {0, 2, 4}};
  static const int pri[6][3] = {{1, 2, 3}, {2, 0, 4}, {0, 1, 5}, {5, 4, 0}, {3, 5, 1}, {4, 3, 2}};
  static const int hex[8][3] = {{1, 3, 4}, {2, 0, 5}, {3, 1, 6}, {0, 2, 7},
                                {7, 5, 0}, {4, 6, 1}, {5, 7, 2}, {6, 4, 3}};
  const int(*nb)[3] = t == MX_TET ? tet : t == MX_PYRAMID ? pyr : t == MX_PRISM ? pri : hex;
  const int n = t == MX_TET || t == MX_PYRAMID ? 4 : t == MX_PRISM ? 6 : 8;
  const double k = t == MX_HEX ? 1.0 : t == MX_PRISM ? sqrt(3.0) / 2.0 : sqrt(2.0) / 2.0;
  double q[9];
  for (int i = 0; i < n; i++) q[i] = ref_scale(ref_js(p, i, nb[i][0], nb[i][1], nb[i][2]), k);
  int m = n;
  if (t == MX_PYRAMID) {
    double pos = INFINITY, neg = -INFINITY;
    for (int i = 0; i < 4; i++) {
      const double j = ref_js(p, 4, (i + 2) % 4, (i + 1) % 4, i);
      if (j > 0.0)
        pos = fmin(pos, j);
      else if (j > neg)
        neg = j;
    }
    q[m++] = ref_scale(isfinite(pos) ? pos : neg, k);
  }
  double mn = INFINITY, worst_neg = -INFINITY;
  int any_neg = 0;
  for (int i = 0; i < m; i++) {
    mn = fmin(mn, q[i]);
    if (q[i] <= 0.0) {
      any_neg = 1;
      if (q[i] > worst_neg) worst_neg = q[i];
    }
  }
  return any_neg ? worst_neg : mn;
}

int main(void) {
  /* Unit cube hexahedron: J_S = 1 at every corner, k = 1: J_ENS 1. */
  const double hex[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0},
                            {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
  CHECK(near(mx_jens_hex(hex), 1.0));
  CHECK(near(mx_element_volume(MX_HEX, hex), 1.0));
  /* Inverted (top and bottom swapped): negative. */
  const double hinv[8][3] = {{0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1},
                             {0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  CHECK(mx_jens_hex(hinv) < 0.0);
  CHECK(near(mx_element_volume(MX_HEX, hinv), -1.0));
  /* Regular tetrahedron: J_S = sqrt(2)/2 = k at every node: J_ENS 1. */
  const double s = 1.0 / sqrt(2.0);
  const double reg[4][3] = {{1, 0, -s}, {-1, 0, -s}, {0, 1, s}, {0, -1, s}};
  double t[4][3];
  /* order it positively */
  const double o = ((reg[1][0] - reg[0][0]) * (reg[2][1] - reg[0][1]) -
                    (reg[1][1] - reg[0][1]) * (reg[2][0] - reg[0][0])) * (reg[3][2] - reg[0][2]) +
                   ((reg[1][1] - reg[0][1]) * (reg[2][2] - reg[0][2]) -
                    (reg[1][2] - reg[0][2]) * (reg[2][1] - reg[0][1])) * (reg[3][0] - reg[0][0]) +
                   ((reg[1][2] - reg[0][2]) * (reg[2][0] - reg[0][0]) -
                    (reg[1][0] - reg[0][0]) * (reg[2][2] - reg[0][2])) * (reg[3][1] - reg[0][1]);
  for (int i = 0; i < 4; i++)
    for (int a = 0; a < 3; a++) t[i][a] = reg[o > 0 ? i : (i == 2 ? 3 : i == 3 ? 2 : i)][a];
  CHECK(near(mx_jens_tet(t), 1.0));
  CHECK(mx_element_volume(MX_TET, t) > 0.0);
  /* Right-corner tetrahedron. */
  const double corner[4][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  /* J_S 1 at the corner and 1/2 at the other three nodes: J_ENS sqrt(2)/2. */
  CHECK(near(mx_jens_tet(corner), sqrt(2.0) / 2.0));
  CHECK(near(mx_element_volume(MX_TET, corner), 1.0 / 6.0));
  /* Flat tetrahedron: J_ENS 0 or below. */
  const double flat[4][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}};
  CHECK(mx_jens_tet(flat) <= 0.0);
  /* Equilateral prism (unit edges): J_S = sin 60 = k: J_ENS 1. */
  const double h3 = sqrt(3.0) / 2.0;
  const double pri[6][3] = {{0, 0, 0}, {1, 0, 0}, {0.5, h3, 0},
                            {0, 0, 1}, {1, 0, 1}, {0.5, h3, 1}};
  CHECK(near(mx_jens_prism(pri), 1.0));
  CHECK(near(mx_element_volume(MX_PRISM, pri), h3 / 2.0));
  /* Pyramid with all edges equal (height 1/sqrt 2): base J_S = k: J_ENS 1
   * at the base; the apex sees J_S = 1/sqrt2 * ... check it is positive and
   * the volume is base * h / 3. */
  const double pyr[5][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0.5, 0.5, s}};
  const double qp = mx_jens_pyramid(pyr);
  CHECK(qp > 0.0 && qp <= 1.0 + 1e-12);
  CHECK(near(mx_element_volume(MX_PYRAMID, pyr), s / 3.0));
  /* Apex below the base: invalid. */
  const double pdown[5][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0.5, 0.5, -s}};
  CHECK(mx_jens_pyramid(pdown) < 0.0);
  /* mx_jens against the definition on elements drawn around the unit cube's
   * corners (4 spreads), on lattice points (collapsed edges, flat corners)
   * and with a node doubled: the same values */
  {
    static const double cube[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0},
                                      {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
    uint64_t r = 0x9E3779B97F4A7C15ull;
    long differ = 0, invalid = 0, n = 0;
    for (int it = 0; it < 200000; it++) {
      const int t = it % 4, mode = (it / 4) % 6;
      const double spread[4] = {10.0, 0.3, 0.01, 1e-9};
      double p[8][3];
      for (int v = 0; v < 8; v++)
        for (int x = 0; x < 3; x++) {
          r = r * 6364136223846793005ull + 1442695040888963407ull;
          const double u = (double)(r >> 11) * 0x1p-53 - 0.5;
          p[v][x] = mode < 4 ? cube[v][x] + spread[mode] * u : floor(2.0 * cube[v][x] + 2.0 * u);
        }
      if (mode == 5) memcpy(p[1], p[0], sizeof p[0]);
      const double a = mx_jens(t, (const double(*)[3])p);
      const double b = ref_jens(t, (const double(*)[3])p);
      differ += !(a == b); /* (0 and -0 alike: a flat corner's sign of zero
                              depends on the end its edges are taken from) */
      invalid += mx_jens_invalid(a);
      n++;
    }
    printf("J_ENS: %ld elements against the definition, %ld differ, %ld invalid\n", n, differ,
           invalid);
    CHECK(differ == 0 && invalid > 0 && invalid < n);
  }
  /* The quality table: bins of Table IV, per-type min / max / mean. */
  {
    const uint8_t type[8] = {MX_TET, MX_TET, MX_PYRAMID, MX_PRISM, MX_HEX, MX_HEX, MX_TET, MX_TET};
    const float q[8] = {-0.5f, 0.01f, 0.1f, 0.3f, 0.5f, 1.0f, 0.7f, 0.2f};
    mx_quality_table t;
    mx_quality_tabulate(type, q, 8, &t);
    CHECK(t.bins[0] == 2 && t.bins[1] == 1 && t.bins[2] == 2 && t.bins[3] == 1 &&
          t.bins[4] == 1 && t.bins[5] == 1);
    CHECK(t.invalid == 1 && t.below_02 == 3);
    CHECK(t.count[MX_TET] == 4 && t.count[MX_HEX] == 2);
    /* the mesh keeps J_ENS in float: the values as stored */
    CHECK(near(t.min[MX_TET], -0.5) && near(t.max[MX_TET], (double)0.7f));
    CHECK(near(t.mean[MX_TET], (-0.5 + (double)0.01f + (double)0.7f + (double)0.2f) / 4.0));
    CHECK(near(t.mean[MX_HEX], 0.75) && near(t.min_all, -0.5));
  }
  return TEST_DONE();
}
