/* The transition stage: conforming meshes of whole octrees, checked by the
 * independent checker (src/verify/check.c): no invalid element, faces
 * matched, closed boundary, no hanging node, the volume of the leaves; the
 * same mesh for 1, 2, 3 and 7 threads; nodes numbered in the order of the
 * leaves that first use them. */
#include <math.h>

#include "check.h"
#include "verify/check.h"
#include "kernels/transition.h"
#include "soa/mesh.h"
#include "octree_util.h"
#include "io/demo_surface.h"
#include "io/write_mesh.h"

static int run_mesh(const mx_trisoup *s, uint32_t ntd, const uint32_t *rt0,
                    const mx_requests *req, int threads, mx_mesh *M,
                    double *leaf_volume) {
  omp_set_num_threads(threads);
  mx_builder B;
  uint32_t r0[2] = {ntd, ntd};
  if (!rt0) rt0 = r0;
  int st = mx_builder_init(&B, s, ntd, rt0, req, 1, NULL);
  if (!st) st = mx_build_roots(&B);
  if (!st) st = mx_refine_balanced(&B);
  if (!st) st = mx_resolve_closures(&B);
  uint32_t *leaves = NULL;
  size_t n = 0;
  if (!st) st = mx_leaves(&B.tree, &leaves, &n);
  if (!st) st = mx_leaves_sorted(&B.tree, leaves, n);
  if (!st) st = mx_transition(&B.tree, leaves, n, M);
  *leaf_volume = 0.0;
  for (size_t i = 0; !st && i < n; i++) {
    const double h = ldexp(B.tree.grid.side, -B.tree.oct.level[leaves[i]]);
    *leaf_volume += h * h * h;
  }
  mx_free(leaves);
  mx_builder_free(&B);
  return st;
}

static int cmp_u64(const void *a, const void *b) {
  const uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
  return (x > y) - (x < y);
}

/* Check one configuration; returns the element count. */
static size_t check_case(const char *what, const mx_trisoup *s, uint32_t ntd,
                         const uint32_t *rt0, const mx_requests *req) {
  mx_mesh A, C;
  double va = 0, vc = 0;
  CHECK(run_mesh(s, ntd, rt0, req, 1, &A, &va) == MX_OK);
  CHECK(run_mesh(s, ntd, rt0, req, 2, &C, &vc) == MX_OK);
  /* identical output for 1 and 2 threads */
  CHECK(A.nnodes == C.nnodes && A.ncells == C.ncells);
  if (A.nnodes == C.nnodes && A.ncells == C.ncells) {
    CHECK(memcmp(A.xyz, C.xyz, 3 * A.nnodes * sizeof *A.xyz) == 0);
    CHECK(memcmp(A.conn, C.conn, 8 * A.ncells * sizeof *A.conn) == 0);
    CHECK(memcmp(A.type, C.type, A.ncells) == 0);
  }
  /* 3 and 7 threads: the leaves cut into more ranges, families split at
   * their ends, owners taken over across them: the same mesh again */
  for (int t = 3; t <= 7; t += 4) {
    mx_mesh D;
    double vd = 0;
    CHECK(run_mesh(s, ntd, rt0, req, t, &D, &vd) == MX_OK);
    CHECK(D.nnodes == A.nnodes && D.ncells == A.ncells);
    if (D.nnodes == A.nnodes && D.ncells == A.ncells) {
      CHECK(memcmp(A.xyz, D.xyz, 3 * A.nnodes * sizeof *A.xyz) == 0);
      CHECK(memcmp(A.nkey, D.nkey, A.nnodes * sizeof *A.nkey) == 0);
      CHECK(memcmp(A.conn, D.conn, 8 * A.ncells * sizeof *A.conn) == 0);
      CHECK(memcmp(A.type, D.type, A.ncells) == 0);
    }
    mx_mesh_free(&D);
  }
  /* Nodes numbered by their owner, the first leaf using them, in leaf
   * order: the leaf whose element first names a node (elements come in
   * leaf order) never decreases with the node number; every node is used;
   * no two nodes share a lattice point. */
  {
    uint32_t *first = malloc((A.nnodes + 1) * sizeof *first);
    uint64_t *keys = malloc((A.nnodes + 1) * sizeof *keys);
    CHECK(first && keys);
    if (first && keys) {
      for (size_t v = 0; v < A.nnodes; v++) first[v] = UINT32_MAX;
      int sorted = 1;
      for (size_t c = 0; c < A.ncells; c++) {
        if (c && A.leaf[c] < A.leaf[c - 1]) sorted = 0;
        for (int k = 0; k < mx_cell_nodes[A.type[c]]; k++) {
          const uint32_t v = A.conn[8 * c + k];
          if (v < A.nnodes && first[v] == UINT32_MAX) first[v] = A.leaf[c];
        }
      }
      CHECK(sorted);
      size_t unused = 0, backwards = 0, same = 0;
      for (size_t v = 0; v < A.nnodes; v++) {
        unused += first[v] == UINT32_MAX;
        if (v && first[v] < first[v - 1]) backwards++;
      }
      CHECK(unused == 0 && backwards == 0);
      memcpy(keys, A.nkey, A.nnodes * sizeof *keys);
      qsort(keys, A.nnodes, sizeof *keys, cmp_u64);
      for (size_t v = 1; v < A.nnodes; v++) same += keys[v] == keys[v - 1];
      CHECK(same == 0);
    }
    free(first);
    free(keys);
  }
  mx_mesh_data m = {.nnodes = A.nnodes, .ncells = A.ncells, .xyz = A.xyz, .type = A.type,
                    .conn = A.conn};
  mx_check_report r;
  CHECK(mx_check_mesh(&m, NULL, &r) == MX_OK);
  printf("%-28s %8zu elements, %7zu nodes: defects %zu (open edges %zu, "
         "hanging %zu, overshared %zu, misoriented %zu, quad/tri %zu, invalid "
         "%zu), volume %.12g vs leaves %.12g\n", what, A.ncells, A.nnodes,
         r.defects, r.open_boundary_edges, r.hanging_nodes, r.faces_overshared,
         r.faces_misoriented, r.quad_vs_triangles, r.invalid, r.volume, va);
  CHECK(r.defects == 0);
  if (r.defects && getenv("MX_DUMP")) {
    char fn[128];
    snprintf(fn, sizeof fn, "/tmp/fail_%zu.vtu", A.ncells);
    mx_mesh_view v = {.nnodes = A.nnodes, .xyz = A.xyz, .ncells = A.ncells, .type = A.type, .conn = A.conn, .ncell_fields = 0, .cell_fields = NULL, .npoint_fields = 0, .point_fields = NULL};
    mx_write_vtu(fn, &v);
  }
  CHECK(fabs(r.volume - va) <= 1e-9 * va);
  CHECK(r.invalid == 0 && A.invalid == 0);
  const size_t ne = A.ncells;
  mx_mesh_free(&A);
  mx_mesh_free(&C);
  return ne;
}

int main(void) {
  const double lo[3] = {-0.5, -0.5, -0.5}, hi[3] = {0.5, 0.5, 0.5};
  mx_trisoup cube;
  memset(&cube, 0, sizeof cube);
  add_box(&cube, lo, hi, 0);
  char name[64];
  for (int k = 0; k <= 4; k++) {
    mx_requests r = no_requests();
    r.s_level = k;
    snprintf(name, sizeof name, "cube -s %d", k);
    check_case(name, &cube, 12, NULL, &r);
  }
  {
    mx_requests r = no_requests();
    r.a_level = 2;
    /* a uniform grid: 64 hexahedra, nothing else */
    CHECK(check_case("cube -a 2", &cube, 12, NULL, &r) == 64);
  }
  {
    mx_box_region box = {{0.01, 0.01, 0.01}, {0.02, 0.02, 0.02}, 4};
    mx_requests r = no_requests();
    r.boxes = &box;
    r.nboxes = 1;
    check_case("cube -b small box level 4", &cube, 12, NULL, &r);
  }
  {
    mx_trisoup s;
    cube_with_hole(&s);
    mx_requests r = no_requests();
    r.s_level = 4;
    check_case("cube with a hole -s 4", &s, (uint32_t)s.nt, NULL, &r);
    mx_trisoup_free(&s);
  }
  /* Random octrees on the demo surface. */
  {
    mx_trisoup demo;
    memset(&demo, 0, sizeof demo);
    CHECK(mx_demo_surface(&demo, 3) == MX_OK);
    double blo[3], bhi[3];
    mx_trisoup_bbox(&demo, blo, bhi);
    uint64_t seed = 11;
    for (int it = 0; it < 10; it++) {
      mx_box_region boxes[3];
      const int nb = 1 + it % 3;
      random_boxes(&seed, blo, bhi, nb, 0.05, 0.3, 3, 3, boxes);
      mx_requests r = no_requests();
      r.boxes = boxes;
      r.nboxes = (size_t)nb;
      r.s_level = 2 + it % 3;
      snprintf(name, sizeof name, "demo random %d", it);
      check_case(name, &demo, (uint32_t)demo.nt, NULL, &r);
    }
    mx_trisoup_free(&demo);
  }
  /* The cortex, where it is. */
  mx_trisoup s;
  if (load_shared_surface("cortex.off", &s)) {
    for (int k = 4; k <= 6; k++) {
      mx_requests r = no_requests();
      r.s_level = k;
      snprintf(name, sizeof name, "cortex -s %d", k);
      check_case(name, &s, (uint32_t)s.nt, NULL, &r);
    }
    mx_trisoup_free(&s);
  }
  mx_trisoup_free(&cube);
  return TEST_DONE();
}
