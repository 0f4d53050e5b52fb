/* Shapes and measures shared by the materials tests (test_materials.c,
 * test_material_interfaces.c): a UV sphere, an element's signed volume. */
#ifndef MX_TEST_SHAPES_H
#define MX_TEST_SHAPES_H

#include <math.h>
#include <stdint.h>
#include <stdlib.h>

#include "mixoct.h"
#include "soa/mesh.h"

/* A UV sphere of radius r: n rings, 2n segments, outward. */
static void sphere(double r, int n, double **xyz, size_t *nv, uint32_t **tri, size_t *nt) {
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
static double volume(const mx_mesh_arrays *a, size_t c) {
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
