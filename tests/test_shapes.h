/* Shapes and measures shared by the tests (test_materials.c,
 * test_material_interfaces.c, test_size_field.c): a UV sphere, a box, an
 * element's signed volume. */
#ifndef MX_TEST_SHAPES_H
#define MX_TEST_SHAPES_H

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "mixoct.h"
#include "soa/mesh.h"

/* A box [lo, hi], each face an n x n grid of quads split in two triangles
 * (the same split on both sides of a common face), outward. */
static inline void box(const double lo[3], const double hi[3], int n, double **xyz, size_t *nv,
                uint32_t **tri, size_t *nt) {
  const size_t per = (size_t)(n + 1) * (n + 1);
  double *x = malloc(6 * per * 3 * sizeof *x);
  uint32_t *t = malloc(6 * (size_t)n * n * 6 * sizeof *t);
  size_t k = 0, f = 0;
  for (int ax = 0; ax < 3; ax++)
    for (int side = 0; side < 2; side++) {
      const int u = (ax + 1) % 3, w = (ax + 2) % 3;
      uint32_t id[17][17]; /* the face's grid points: one vertex per position */
      for (int i = 0; i <= n; i++)
        for (int j = 0; j <= n; j++) {
          double p[3];
          p[ax] = side ? hi[ax] : lo[ax];
          p[u] = lo[u] + (hi[u] - lo[u]) * i / n;
          p[w] = lo[w] + (hi[w] - lo[w]) * j / n;
          size_t e = 0;
          while (e < k / 3 && memcmp(x + 3 * e, p, sizeof p)) e++;
          if (e == k / 3) x[k++] = p[0], x[k++] = p[1], x[k++] = p[2];
          id[i][j] = (uint32_t)e;
        }
      for (int i = 0; i < n; i++)
        for (int j = 0; j < n; j++) {
          const uint32_t a = id[i][j], b = id[i + 1][j], c = id[i + 1][j + 1], d = id[i][j + 1];
          /* (u, w, ax) is right-handed: a b c d turns about +ax */
          if (side)
            t[f++] = a, t[f++] = b, t[f++] = c, t[f++] = a, t[f++] = c, t[f++] = d;
          else
            t[f++] = a, t[f++] = c, t[f++] = b, t[f++] = a, t[f++] = d, t[f++] = c;
        }
    }
  *nv = k / 3;
  *nt = f / 3;
  *xyz = x;
  *tri = t;
}

/* A UV sphere of radius r: n rings, 2n segments, outward. */
static inline void sphere(double r, int n, double **xyz, size_t *nv, uint32_t **tri, size_t *nt) {
  const int m = 2 * n;
  *nv = 2 + (size_t)(n - 1) * m;
  *nt = 2 * (size_t)m * (n - 1);
  double *x = malloc(3 * *nv * sizeof *x);
  uint32_t *t = malloc(3 * *nt * sizeof *t);
  size_t k = 0;
  x[k++] = 0, x[k++] = 0, x[k++] = r;
  for (int i = 1; i < n; i++)
    for (int j = 0; j < m; j++) {
      const double th = M_PI * i / n, ph = 2 * M_PI * j / m;
      x[k++] = r * sin(th) * cos(ph), x[k++] = r * sin(th) * sin(ph), x[k++] = r * cos(th);
    }
  x[k++] = 0, x[k++] = 0, x[k++] = -r;
  size_t f = 0;
  const uint32_t last = (uint32_t)*nv - 1;
  for (int j = 0; j < m; j++)
    t[f++] = 0, t[f++] = (uint32_t)(1 + j), t[f++] = (uint32_t)(1 + (j + 1) % m);
  for (int i = 0; i < n - 2; i++)
    for (int j = 0; j < m; j++) {
      const uint32_t a = (uint32_t)(1 + i * m + j), b = (uint32_t)(1 + i * m + (j + 1) % m);
      t[f++] = a, t[f++] = a + (uint32_t)m, t[f++] = b + (uint32_t)m;
      t[f++] = a, t[f++] = b + (uint32_t)m, t[f++] = b;
    }
  const uint32_t base = (uint32_t)(1 + (n - 2) * m);
  for (int j = 0; j < m; j++)
    t[f++] = last, t[f++] = base + (uint32_t)((j + 1) % m), t[f++] = base + (uint32_t)j;
  *xyz = x;
  *tri = t;
}

/* Signed volume of element c (tetrahedra of its node fan from node 0 over
 * its faces' triangles, faces split at their centroid). */
static inline double volume(const mx_mesh_arrays *a, size_t c) {
  const int t = a->type[c];
  const uint32_t *row = a->conn + 8 * c;
  const double *o = a->xyz + 3 * (size_t)row[0];
  double v = 0;
  for (int f = 0; f < mx_cell_nfaces[t]; f++) {
    const int8_t *fv = mx_cell_faces[t][f];
    const int n = fv[3] < 0 ? 3 : 4;
    double cen[3] = {0, 0, 0};
    for (int k = 0; k < n; k++)
      for (int d = 0; d < 3; d++) cen[d] += a->xyz[3 * (size_t)row[fv[k]] + d] / n;
    for (int k = 0; k < n; k++) {
      const double *p = a->xyz + 3 * (size_t)row[fv[k]], *q = a->xyz + 3 * (size_t)row[fv[(k + 1) % n]];
      double u[3], w[3], z[3];
      for (int d = 0; d < 3; d++) u[d] = p[d] - o[d], w[d] = q[d] - o[d], z[d] = cen[d] - o[d];
      v += (u[0] * (w[1] * z[2] - w[2] * z[1]) - u[1] * (w[0] * z[2] - w[2] * z[0]) +
            u[2] * (w[0] * z[1] - w[1] * z[0])) / 6.0;
    }
  }
  return v;
}

#endif
