/* The built-in demo surface: an icosahedron, 4-split `subdiv` times with
 * shared midpoints, projected to the unit sphere and then pushed to the
 * radius r(u) = 40 (1 + d(u)), d a few low-order spherical harmonics (one of
 * them elongates it front to back). Since r > 0 everywhere, the surface is a
 * radial graph over the geodesic sphere: star-shaped around the origin, so it
 * cannot self-intersect, and every triangle keeps the outward
 * counter-clockwise orientation of the icosahedron. */
#include <math.h>
#include <stdint.h>
#include <string.h>

#include "base/common.h"
#include "soa/trisoup.h"
#include "io/demo_surface.h"

#define EMPTY_KEY UINT64_MAX

static void normalize(double *x, double *y, double *z) {
  double n = sqrt(*x * *x + *y * *y + *z * *z);
  *x /= n;
  *y /= n;
  *z /= n;
}

static double det3(const mx_trisoup *s, uint32_t a, uint32_t b, uint32_t c) {
  return s->x[a] * (s->y[b] * s->z[c] - s->z[b] * s->y[c]) -
         s->y[a] * (s->x[b] * s->z[c] - s->z[b] * s->x[c]) +
         s->z[a] * (s->x[b] * s->y[c] - s->y[b] * s->x[c]);
}

static double dist2(const mx_trisoup *s, uint32_t a, uint32_t b) {
  double dx = s->x[a] - s->x[b], dy = s->y[a] - s->y[b], dz = s->z[a] - s->z[b];
  return dx * dx + dy * dy + dz * dz;
}

/* The 12 vertices (0, +-1, +-phi) and cyclic permutations; the 20 faces
 * are the triples at mutual distance 2, oriented outward. */
static void icosahedron(mx_trisoup *s) {
  const double phi = 0.5 * (1.0 + sqrt(5.0));
  for (int i = 0; i < 12; i++) {
    double c[3], a = (i & 1) ? -1.0 : 1.0, b = (i & 2) ? -phi : phi;
    int k = i / 4; /* which coordinate is zero */
    c[k] = 0.0;
    c[(k + 1) % 3] = a;
    c[(k + 2) % 3] = b;
    s->x[i] = c[0];
    s->y[i] = c[1];
    s->z[i] = c[2];
  }
  s->nv = 12;
  s->nt = 0;
  for (uint32_t a = 0; a < 12; a++)
    for (uint32_t b = a + 1; b < 12; b++)
      for (uint32_t c = b + 1; c < 12; c++) {
        if (fabs(dist2(s, a, b) - 4) > 1e-9 ||
            fabs(dist2(s, b, c) - 4) > 1e-9 || fabs(dist2(s, a, c) - 4) > 1e-9)
          continue;
        int outward = det3(s, a, b, c) > 0;
        uint32_t *t = s->tri + 3 * s->nt;
        t[0] = a;
        t[1] = outward ? b : c;
        t[2] = outward ? c : b;
        s->shell[s->nt++] = 0;
      }
  for (uint32_t v = 0; v < 12; v++) normalize(&s->x[v], &s->y[v], &s->z[v]);
}

typedef struct {
  uint64_t *key; /* (lo << 32) | hi, or EMPTY_KEY */
  uint32_t *mid;
  size_t mask;
} edge_map;

static int edge_map_init(edge_map *m, size_t nedges) {
  size_t cap = 64;
  while (cap < 2 * nedges) cap *= 2;
  m->mask = cap - 1;
  m->key = mx_alloc(cap * sizeof *m->key);
  m->mid = mx_alloc(cap * sizeof *m->mid);
  if (!m->key || !m->mid) {
    mx_free(m->key);
    mx_free(m->mid);
    return MX_ENOMEM;
  }
  memset(m->key, 0xff, cap * sizeof *m->key);
  return MX_OK;
}

/* The midpoint vertex of edge ab (on the unit sphere), created once. */
static uint32_t midpoint(edge_map *m, mx_trisoup *s, uint32_t a, uint32_t b) {
  uint64_t key = a < b ? (uint64_t)a << 32 | b : (uint64_t)b << 32 | a;
  size_t h = (size_t)((key * 0x9e3779b97f4a7c15ull) >> 20) & m->mask;
  for (; m->key[h] != EMPTY_KEY; h = (h + 1) & m->mask)
    if (m->key[h] == key) return m->mid[h];
  uint32_t v = (uint32_t)s->nv++;
  s->x[v] = 0.5 * (s->x[a] + s->x[b]);
  s->y[v] = 0.5 * (s->y[a] + s->y[b]);
  s->z[v] = 0.5 * (s->z[a] + s->z[b]);
  normalize(&s->x[v], &s->y[v], &s->z[v]);
  m->key[h] = key;
  m->mid[h] = v;
  return v;
}

/* Each triangle abc becomes its centre (ab bc ca), kept in place, and three
 * corners appended; all keep abc's orientation. Capacity is reserved. */
static int subdivide(mx_trisoup *s) {
  size_t nt = s->nt;
  edge_map m;
  MX_CHECK(edge_map_init(&m, 3 * nt / 2));
  for (size_t i = 0; i < nt; i++) {
    uint32_t *t = s->tri + 3 * i;
    uint32_t a = t[0], b = t[1], c = t[2];
    uint32_t ab = midpoint(&m, s, a, b), bc = midpoint(&m, s, b, c),
             ca = midpoint(&m, s, c, a);
    const uint32_t add[9] = {a, ab, ca, ab, b, bc, ca, bc, c};
    memcpy(s->tri + 3 * (nt + 3 * i), add, sizeof add);
    t[0] = ab;
    t[1] = bc;
    t[2] = ca;
  }
  for (size_t i = nt; i < 4 * nt; i++) s->shell[i] = 0;
  s->nt = 4 * nt;
  mx_free(m.key);
  mx_free(m.mid);
  return MX_OK;
}

/* Relative displacement on the unit sphere: x is left-right, y front-back,
 * z up-down. Each term is a spherical harmonic written as a polynomial;
 * |d| < 0.25, so the radius stays within [30, 50]. */
static double displacement(double x, double y, double z) {
  double elongate = 0.12 * (y * y - 1.0 / 3.0);     /* l=2, along y */
  double flatten = -0.06 * (z * z - 1.0 / 3.0);     /* l=2, along z */
  double crown = 0.035 * 0.5 * z * (5 * z * z - 3); /* l=3, top vs bottom */
  double x2 = x * x, y2 = y * y;
  double lobes = 0.025 * (x2 * x2 - 6 * x2 * y2 + y2 * y2); /* l=4 */
  /* Re (x + iy)^6 is harmonic in the plane, so z times it is a solid
   * harmonic of degree 7. */
  double re6 = x2 * x2 * x2 - 15 * x2 * x2 * y2 + 15 * x2 * y2 * y2 -
               y2 * y2 * y2;
  double folds = 0.03 * z * re6; /* l=7 */
  return elongate + flatten + crown + lobes + folds;
}

static void displace(mx_trisoup *s) {
  for (size_t v = 0; v < s->nv; v++) {
    double r = 40.0 * (1.0 + displacement(s->x[v], s->y[v], s->z[v]));
    s->x[v] *= r;
    s->y[v] *= r;
    s->z[v] *= r;
  }
}

int mx_demo_surface(mx_trisoup *out, int subdiv) {
  memset(out, 0, sizeof *out);
  if (subdiv < 0 || subdiv > 10) {
    mx_error(NULL, 0, "demo surface: subdivision level %d not in [0, 10]",
             subdiv);
    return MX_EINPUT;
  }
  size_t pow4 = (size_t)1 << (2 * subdiv);
  int status = mx_trisoup_reserve(out, 10 * pow4 + 2, 20 * pow4);
  if (status == MX_OK) {
    out->nshells = 1;
    icosahedron(out);
    for (int k = 0; k < subdiv && status == MX_OK; k++) status = subdivide(out);
  }
  if (status != MX_OK) {
    mx_trisoup_free(out);
    return status;
  }
  displace(out);
  return MX_OK;
}
