/* Elements split along quadrilateral diagonals (kernels/cell_split.h),
 * checked by the independent checker (verify/check.h): no invalid element,
 * conforming (no overshared, misoriented or open face), the volume kept,
 * the boundary as many triangles and quadrilaterals as the split faces
 * give; and the counts of each type the cones give. */
#include <math.h>
#include <string.h>

#include "check.h"
#include "kernels/boundary.h"
#include "kernels/cell_split.h"
#include "mixoct.h"
#include "soa/mesh.h"
#include "soa/mesh_data.h"
#include "verify/check.h"

static void add_node(mx_mesh *M, double x, double y, double z) {
  M->xyz[3 * M->nnodes] = x;
  M->xyz[3 * M->nnodes + 1] = y;
  M->xyz[3 * M->nnodes + 2] = z;
  M->nnodes++;
}

static void add_cell(mx_mesh *M, int type, const uint32_t *v) {
  for (int k = 0; k < 8; k++) M->conn[8 * M->ncells + k] = k < mx_cell_nodes[type] ? v[k] : UINT32_MAX;
  M->type[M->ncells] = (uint8_t)type;
  M->level[M->ncells] = 3;
  M->leaf[M->ncells] = (uint32_t)M->ncells;
  M->jens[M->ncells] = 1.0f;
  M->ncells++;
}

static mx_mesh make(size_t nn, size_t nc) {
  mx_mesh M;
  memset(&M, 0, sizeof M);
  M.xyz = mx_alloc(3 * nn * sizeof *M.xyz);
  M.type = mx_alloc(nc);
  M.conn = mx_alloc(8 * nc * sizeof *M.conn);
  M.level = mx_alloc(nc);
  M.leaf = mx_alloc(nc * sizeof *M.leaf);
  M.jens = mx_alloc(nc * sizeof *M.jens);
  return M;
}

static mx_check_report check(const mx_mesh *M) {
  mx_mesh_data d;
  memset(&d, 0, sizeof d);
  d.nnodes = M->nnodes;
  d.ncells = M->ncells;
  d.xyz = M->xyz;
  d.type = M->type;
  d.conn = mx_alloc(8 * M->ncells * sizeof *d.conn);
  for (size_t i = 0; i < 8 * M->ncells; i++) d.conn[i] = M->conn[i] == UINT32_MAX ? 0 : M->conn[i];
  mx_check_report r;
  CHECK(mx_check_mesh(&d, NULL, &r) == MX_OK);
  mx_free(d.conn);
  return r;
}

int main(void) {
  /* two unit cubes side by side (x), the first a little sheared so that
   * its faces are not planar */
  {
    mx_mesh M = make(12, 2);
    /* nodes: n(x, y, z) = x + 3 * (y + 2 * z) */
    for (int z = 0; z < 2; z++)
      for (int y = 0; y < 2; y++)
        for (int x = 0; x < 3; x++) add_node(&M, x, y, z);
#define N(x, y, z) ((uint32_t)((x) + 3 * ((y) + 2 * (z))))
    const uint32_t h0[8] = {N(0, 0, 0), N(1, 0, 0), N(1, 1, 0), N(0, 1, 0),
                            N(0, 0, 1), N(1, 0, 1), N(1, 1, 1), N(0, 1, 1)};
    const uint32_t h1[8] = {N(1, 0, 0), N(2, 0, 0), N(2, 1, 0), N(1, 1, 0),
                            N(1, 0, 1), N(2, 0, 1), N(2, 1, 1), N(1, 1, 1)};
    M.xyz[3 * N(0, 0, 1) + 2] = 1.2; /* non-planar faces */
    add_cell(&M, MX_HEX, h0);
    add_cell(&M, MX_HEX, h1);
    uint8_t *states = mx_calloc(M.nnodes);
    const mx_check_report r0 = check(&M);
    CHECK(r0.defects == 0 && r0.faces_boundary == 10);
    /* the first cube's bottom (face 0) and its x = 0 side (face 5) */
    const uint64_t req[2] = {mx_split_request(0, 0, 0), mx_split_request(0, 5, 1)};
    size_t centres = 0;
    CHECK(mx_mesh_split_quads(&M, &states, req, 2, &centres, NULL) == MX_OK);
    CHECK(centres == 1 && M.nnodes == 13 && states[12] == MX_NODE_INSIDE);
    size_t by[4] = {0, 0, 0, 0};
    for (size_t e = 0; e < M.ncells; e++) by[M.type[e]]++;
    CHECK(by[MX_TET] == 4 && by[MX_PYRAMID] == 4 && by[MX_HEX] == 1 && M.ncells == 9);
    const mx_check_report r = check(&M);
    CHECK(r.defects == 0 && r.invalid == 0 && r.degenerate == 0);
    CHECK(r.faces_overshared == 0 && r.faces_misoriented == 0 && r.open_boundary_edges == 0);
    CHECK(r.faces_boundary == 12); /* 8 quadrilaterals and 4 triangles */
    CHECK(fabs(r.volume - r0.volume) < 1e-12);
    for (size_t e = 0; e < M.ncells; e++) {
      CHECK(M.jens[e] > 0.0f);
      CHECK(M.leaf[e] == (e == 1 ? 1u : 0u) && M.level[e] == 3);
    }
    /* a triangle face is refused */
    CHECK(mx_mesh_split_quads(&M, &states, (const uint64_t[]){mx_split_request(0, 0, 0)}, 1, NULL, NULL) ==
          MX_EINPUT);
    mx_free(states);
    mx_mesh_free(&M);
  }
  /* split, then undone: the mesh as it was, node for node */
  {
    mx_mesh M = make(12, 2);
    for (int z = 0; z < 2; z++)
      for (int y = 0; y < 2; y++)
        for (int x = 0; x < 3; x++) add_node(&M, x, y, z);
    const uint32_t h0[8] = {N(0, 0, 0), N(1, 0, 0), N(1, 1, 0), N(0, 1, 0),
                            N(0, 0, 1), N(1, 0, 1), N(1, 1, 1), N(0, 1, 1)};
    const uint32_t h1[8] = {N(1, 0, 0), N(2, 0, 0), N(2, 1, 0), N(1, 1, 0),
                            N(1, 0, 1), N(2, 0, 1), N(2, 1, 1), N(1, 1, 1)};
    add_cell(&M, MX_HEX, h0);
    add_cell(&M, MX_HEX, h1);
    uint8_t *states = mx_calloc(M.nnodes);
    const uint64_t req[3] = {mx_split_request(0, 0, 0), mx_split_request(1, 0, 1),
                             mx_split_request(1, 1, 0)};
    mx_split_log log = {0, NULL, 0};
    CHECK(mx_mesh_split_quads(&M, &states, req, 3, NULL, &log) == MX_OK);
    CHECK(log.n == 2 && M.nnodes == 14 && M.ncells == 7 + 8);
    /* the second cube's split undone only: its centre (node 13) dropped */
    const uint8_t undo[2] = {0, 1};
    CHECK(mx_mesh_unsplit(&M, &states, &log, undo) == MX_OK);
    CHECK(M.nnodes == 13 && M.ncells == 7 + 1 && log.n == 0);
    CHECK(M.type[1] == MX_HEX && memcmp(M.conn + 8, h1, sizeof h1) == 0);
    const mx_check_report r = check(&M);
    CHECK(r.defects == 0 && fabs(r.volume - 2.0) < 1e-12);
    mx_split_log_free(&log);
    mx_free(states);
    mx_mesh_free(&M);
  }
  /* a pyramid whose base is split: two tetrahedra, no new node; a prism
   * with one side split: a centre, 2 + 2 tets and 2 pyramids */
  {
    mx_mesh M = make(11, 2);
    add_node(&M, 0, 0, 0);
    add_node(&M, 1, 0, 0);
    add_node(&M, 1, 1, 0);
    add_node(&M, 0, 1, 0);
    add_node(&M, 0.5, 0.5, 0.7);
    const uint32_t p[5] = {0, 1, 2, 3, 4};
    add_cell(&M, MX_PYRAMID, p);
    add_node(&M, 3, 0, 0);
    add_node(&M, 4, 0, 0);
    add_node(&M, 3, 1, 0);
    add_node(&M, 3, 0, 1);
    add_node(&M, 4, 0, 1);
    add_node(&M, 3, 1, 1);
    /* the prism's first triangle turns towards its second (mesh.h) */
    const uint32_t w[6] = {5, 6, 7, 8, 9, 10};
    add_cell(&M, MX_PRISM, w);
    const mx_check_report r0 = check(&M);
    CHECK(r0.defects == 0);
    uint8_t *states = mx_calloc(M.nnodes);
    const uint64_t req[2] = {mx_split_request(0, 0, 1), mx_split_request(1, 3, 0)};
    size_t centres = 0;
    CHECK(mx_mesh_split_quads(&M, &states, req, 2, &centres, NULL) == MX_OK);
    CHECK(centres == 1 && M.nnodes == 12);
    size_t by[4] = {0, 0, 0, 0};
    for (size_t e = 0; e < M.ncells; e++) by[M.type[e]]++;
    CHECK(by[MX_TET] == 2 + 4 && by[MX_PYRAMID] == 2 && M.ncells == 8);
    const mx_check_report r = check(&M);
    CHECK(r.defects == 0 && r.invalid == 0 && r.degenerate == 0);
    CHECK(r.faces_boundary == 4 + 2 + 6); /* pyramid: 4 + 2; prism: 2 + 2 + 2 */
    CHECK(fabs(r.volume - r0.volume) < 1e-12);
    mx_free(states);
    mx_mesh_free(&M);
  }
  if (mx_test_failures) return 1;
  printf("cell_split: ok\n");
  return 0;
}
