/* The untangling step (kernels/untangle.h) on a 2x2x2 block of hexahedra
 * filling the cube [-1, 1]^3: the centre node is pushed through a corner of
 * the block so that elements are inverted, one boundary node is slid along
 * its face; the step must make every element valid again, keep every
 * boundary node on the cube's surface, leave the volume of the block
 * unchanged, and give the same positions on a second run. */
#include <math.h>
#include <string.h>

#include "check.h"
#include "kernels/boundary.h"
#include "kernels/mesh_edit.h"
#include "geom/quality.h"
#include "kernels/untangle.h"
#include "soa/mesh.h"
#include "octree_util.h"

static int id(int i, int j, int k) { return i + 3 * j + 9 * k; }

static void block(mx_mesh *M, uint8_t *states) {
  memset(M, 0, sizeof *M);
  M->nnodes = 27;
  M->ncells = 8;
  M->xyz = mx_alloc(3 * 27 * sizeof(double));
  M->type = mx_alloc(8);
  M->conn = mx_alloc(8 * 8 * sizeof(uint32_t));
  M->level = mx_alloc(8 * sizeof(int32_t));
  M->leaf = mx_alloc(8 * sizeof(uint32_t));
  M->jens = mx_alloc(8 * sizeof(double));
  for (int k = 0; k < 3; k++)
    for (int j = 0; j < 3; j++)
      for (int i = 0; i < 3; i++) {
        double *p = M->xyz + 3 * id(i, j, k);
        p[0] = i - 1.0;
        p[1] = j - 1.0;
        p[2] = k - 1.0;
        states[id(i, j, k)] = (i == 1 && j == 1 && k == 1) ? MX_NODE_INSIDE : MX_NODE_OUTSIDE;
      }
  int c = 0;
  for (int k = 0; k < 2; k++)
    for (int j = 0; j < 2; j++)
      for (int i = 0; i < 2; i++, c++) {
        const uint32_t v[8] = {id(i, j, k), id(i + 1, j, k), id(i + 1, j + 1, k), id(i, j + 1, k),
                               id(i, j, k + 1), id(i + 1, j, k + 1), id(i + 1, j + 1, k + 1),
                               id(i, j + 1, k + 1)};
        memcpy(M->conn + 8 * c, v, sizeof v);
        M->type[c] = MX_HEX;
        M->level[c] = 1;
        M->leaf[c] = (uint32_t)c;
      }
}

static double volume(const mx_mesh *M) {
  double v = 0.0;
  for (size_t c = 0; c < M->ncells; c++) {
    double x[8][3];
    for (int k = 0; k < 8; k++) memcpy(x[k], M->xyz + 3 * M->conn[8 * c + k], sizeof x[k]);
    v += mx_element_volume(M->type[c], x);
  }
  return v;
}

int main(void) {
  (void)no_requests;
  mx_trisoup cube;
  memset(&cube, 0, sizeof cube);
  const double lo[3] = {-1, -1, -1}, hi[3] = {1, 1, 1};
  add_box(&cube, lo, hi, 0);
  mx_surface_index S;
  CHECK(mx_surface_index_build(&S, &cube, 0, (uint32_t)cube.nt) == MX_OK);
  double first[27 * 3];
  for (int run = 0; run < 2; run++) {
    mx_mesh M;
    uint8_t states[27];
    block(&M, states);
    /* the centre goes past the corner (0.8, 0.8, 0.8): the hexahedra around
     * it fold; a face node slides on its face */
    M.xyz[3 * id(1, 1, 1) + 0] = 0.8;
    M.xyz[3 * id(1, 1, 1) + 1] = 0.8;
    M.xyz[3 * id(1, 1, 1) + 2] = 0.8;
    M.xyz[3 * id(1, 1, 0) + 0] = 0.7;
    mx_mesh_update_jens(&M, NULL);
    mx_mesh_summarize(&M);
    CHECK(M.invalid > 0);
    size_t moved = 0;
    CHECK(mx_untangle(&M, states, &S, 0.2, 20, &moved) == MX_OK);
    CHECK(moved > 0);
    mx_mesh_update_jens(&M, NULL); /* recomputed independently */
    mx_mesh_summarize(&M);
    printf("run %d: %zu moves, %zu invalid, J_ENS min %.3f, volume %.15f\n", run, moved,
           M.invalid, M.jens_min, volume(&M));
    CHECK(M.invalid == 0);
    CHECK(M.jens_min > 0.0);
    CHECK(fabs(volume(&M) - 8.0) < 1e-9);
    for (int v = 0; v < 27; v++) {
      if (states[v] == MX_NODE_INSIDE) continue;
      const double *p = M.xyz + 3 * v;
      const double m = fmax(fabs(p[0]), fmax(fabs(p[1]), fabs(p[2])));
      CHECK(fabs(m - 1.0) < 1e-12); /* still on the cube's surface */
    }
    if (run == 0) memcpy(first, M.xyz, sizeof first);
    else CHECK(memcmp(first, M.xyz, sizeof first) == 0);
    mx_mesh_free(&M);
  }
  mx_surface_index_free(&S);
  mx_trisoup_free(&cube);
  return TEST_DONE();
}
