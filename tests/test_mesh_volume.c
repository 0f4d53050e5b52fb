/* The mesh volume of the volume check (mesher.c: mx_mesh_volume), taken
 * from each element's node 0 with a box as its extents' product, against
 * volumes known in closed form and against the definition it keeps
 * (geom/quality.c: mx_element_volume, the divergence theorem from the
 * origin, each quadrilateral cut at its centroid).
 *
 * One element of each type far from the origin (corner at 1000 + 1/3:
 * from the origin the terms are near 1e9 and cancel), each alone in a
 * mesh; the expected volumes:
 * - tetrahedron (0,0,0) (2,0,0) (0,3,0) (0,0,5): 2 * 3 * 5 / 6 = 5;
 * - pyramid on the square of side 2 (z = 0), apex 3 above a point of it:
 *   4 * 3 / 3 = 4;
 * - prism: right triangle of legs 2 and 3 swept 4 along z: 3 * 4 = 12;
 * - box hexahedron 2 x 3 x 0.5: 3 (the product, exact);
 * - parallelepiped from the edges (2,0,0) (1,3,0) (0.5,1,4): the
 *   determinant 2 * 3 * 4 = 24 (planar faces: any centroid split gives it);
 * - a hexahedron with one warped face (node 6 raised): no closed form here,
 *   mx_element_volume's value on the same element moved to the origin,
 *   where its terms do not cancel.
 * The sum over a mesh of all of them is the sum of these. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "check.h"
#include "geom/quality.h"
#include "mesher/mesher_impl.h"
#include "soa/mesh.h"

enum { NEL = 6 };

static const double cube8[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0},
                                   {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};

/* The nodes of element k (relative to its corner) and its type. */
static int element(int k, double p[8][3]) {
  memset(p, 0, 8 * sizeof p[0]);
  switch (k) {
  case 0: {
    const double t[4][3] = {{0, 0, 0}, {2, 0, 0}, {0, 3, 0}, {0, 0, 5}};
    memcpy(p, t, sizeof t);
    return MX_TET;
  }
  case 1: {
    const double t[5][3] = {{0, 0, 0}, {2, 0, 0}, {2, 2, 0}, {0, 2, 0}, {0.5, 1.5, 3}};
    memcpy(p, t, sizeof t);
    return MX_PYRAMID;
  }
  case 2: {
    const double t[6][3] = {{0, 0, 0}, {2, 0, 0}, {0, 3, 0}, {0, 0, 4}, {2, 0, 4}, {0, 3, 4}};
    memcpy(p, t, sizeof t);
    return MX_PRISM;
  }
  case 3:
    for (int j = 0; j < 8; j++) {
      p[j][0] = 2 * cube8[j][0];
      p[j][1] = 3 * cube8[j][1];
      p[j][2] = 0.5 * cube8[j][2];
    }
    return MX_HEX;
  case 4:
    for (int j = 0; j < 8; j++)
      for (int a = 0; a < 3; a++) {
        const double e[3][3] = {{2, 0, 0}, {1, 3, 0}, {0.5, 1, 4}};
        p[j][a] = cube8[j][0] * e[0][a] + cube8[j][1] * e[1][a] + cube8[j][2] * e[2][a];
      }
    return MX_HEX;
  default:
    for (int j = 0; j < 8; j++)
      for (int a = 0; a < 3; a++) p[j][a] = cube8[j][a];
    p[6][2] = 1.4; /* the top and two sides warped */
    return MX_HEX;
  }
}

/* A mesh of the elements first..last, each with its own nodes, shifted by
 * off. */
static double mesh_volume(int first, int last, double off, double *xyz, uint8_t *type,
                          uint32_t *conn) {
  mx_mesh M;
  memset(&M, 0, sizeof M);
  size_t nn = 0;
  for (int k = first; k <= last; k++) {
    double p[8][3];
    const int t = element(k, p);
    type[M.ncells] = (uint8_t)t;
    for (int j = 0; j < 8; j++) conn[8 * M.ncells + (size_t)j] = UINT32_MAX;
    for (int j = 0; j < mx_cell_nodes[t]; j++) {
      for (int a = 0; a < 3; a++) xyz[3 * nn + (size_t)a] = p[j][a] + off;
      conn[8 * M.ncells + (size_t)j] = (uint32_t)nn++;
    }
    M.ncells++;
  }
  M.nnodes = nn;
  M.xyz = xyz;
  M.type = type;
  M.conn = conn;
  return mx_mesh_volume(&M);
}

int main(void) {
  double xyz[3 * 8 * NEL];
  uint8_t type[NEL];
  uint32_t conn[8 * NEL];
  const double off = 1000.0 + 1.0 / 3.0;
  double warped[8][3];
  const int tw = element(5, warped);
  const double vw = mx_element_volume(tw, (const double(*)[3])warped);
  const double want[NEL] = {5.0, 4.0, 12.0, 3.0, 24.0, vw};
  /* the warped hexahedron is not its box's 1.2: the test would not see a
   * box formula used for it */
  CHECK(fabs(vw - 1.2) > 1e-3);
  double sum = 0.0;
  for (int k = 0; k < NEL; k++) {
    const double v = mesh_volume(k, k, off, xyz, type, conn);
    const double tol = k == 3 ? 0.0 : 1e-13 * want[k];
    if (!(fabs(v - want[k]) <= tol))
      fprintf(stderr, "element %d: volume %.17g, expected %.17g\n", k, v, want[k]);
    CHECK(fabs(v - want[k]) <= tol);
    /* near the origin the definition agrees with the closed form too */
    double p[8][3];
    const int t = element(k, p);
    CHECK(fabs(mx_element_volume(t, (const double(*)[3])p) - want[k]) <= 1e-13 * want[k]);
    sum += want[k];
  }
  const double all = mesh_volume(0, NEL - 1, off, xyz, type, conn);
  CHECK(fabs(all - sum) <= 1e-13 * sum);
  /* a mirrored box (nodes 0-3 above 4-7) is negative, as its faces say */
  {
    mx_mesh M;
    memset(&M, 0, sizeof M);
    for (int j = 0; j < 8; j++) {
      for (int a = 0; a < 3; a++) xyz[3 * j + a] = off + cube8[(j + 4) % 8][a];
      conn[j] = (uint32_t)j;
    }
    type[0] = MX_HEX;
    M.ncells = 1;
    M.nnodes = 8;
    M.xyz = xyz;
    M.type = type;
    M.conn = conn;
    CHECK(mx_mesh_volume(&M) == -1.0);
  }
  return TEST_DONE();
}
