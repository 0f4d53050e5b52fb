/* The untangling step (kernels/untangle.h) on a 2x2x2 block of hexahedra
 * filling the cube [-1, 1]^3: the centre node is pushed through a corner of
 * the block so that elements are inverted, one boundary node is slid along
 * its face; the step must make every element valid again, keep every
 * boundary node on the cube's surface, leave the volume of the block
 * unchanged, and give the same positions on a second run. Also the test of
 * a node on the mesh's boundary (mx_on_mesh_boundary) on fans of
 * tetrahedra around a node, small (its nodes as bits) and large (more than
 * 64 nodes: the rows searched). */
#include <math.h>
#include <string.h>

#include "check.h"
#include "kernels/boundary.h"
#include "kernels/mesh_edit.h"
#include "geom/quality.h"
#include "kernels/node_work.h"
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

/* A closed fan of 2k tetrahedra around node 0: a ring of k nodes (1 .. k)
 * between two poles (k + 1, k + 2); `drop` (< 2k) tetrahedra left out. */
static void fan(mx_mesh *M, int k, int drop) {
  memset(M, 0, sizeof *M);
  M->nnodes = (size_t)k + 3;
  M->ncells = (size_t)(2 * k - drop);
  M->xyz = mx_calloc(3 * M->nnodes * sizeof(double));
  M->type = mx_alloc(M->ncells);
  M->conn = mx_calloc(8 * M->ncells * sizeof(uint32_t));
  size_t c = 0;
  for (int i = 0; i < k && M->type && M->conn; i++) {
    const uint32_t a = (uint32_t)(1 + i), b = (uint32_t)(1 + (i + 1) % k);
    const uint32_t t[2][4] = {{0, a, b, (uint32_t)k + 1}, {0, b, a, (uint32_t)k + 2}};
    for (int h = 0; h < 2; h++) {
      if (2 * i + h < drop) continue;
      M->type[c] = MX_TET;
      memcpy(M->conn + 8 * c, t[h], sizeof t[h]);
      c++;
    }
  }
}

/* mx_on_mesh_boundary of node v of M, from the incidence of every node */
static int on_boundary(const mx_mesh *M, uint32_t v) {
  uint8_t *all = mx_alloc(M->nnodes);
  memset(all, 1, M->nnodes);
  uint64_t *off = NULL;
  uint32_t *inc = NULL;
  CHECK(mx_mesh_incidence(M, all, &off, &inc) == MX_OK);
  const int b = mx_on_mesh_boundary(M, inc, off[v], off[v + 1], v);
  mx_free(off);
  mx_free(inc);
  mx_free(all);
  return b;
}

int main(void) {
  (void)no_requests;
  /* fans of 2 x 20 tetrahedra (23 nodes) and 2 x 80 (83 nodes, 160
   * elements): the centre is inside when the fan is closed, on the
   * boundary with one tetrahedron left out; a ring node is on it */
  for (int k = 20; k <= 80; k += 60) {
    mx_mesh F;
    fan(&F, k, 0);
    CHECK(on_boundary(&F, 0) == 0);
    CHECK(on_boundary(&F, 1) == 1);
    CHECK(on_boundary(&F, (uint32_t)k + 1) == 1);
    mx_mesh_free(&F);
    fan(&F, k, 1);
    CHECK(on_boundary(&F, 0) == 1);
    mx_mesh_free(&F);
  }
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
