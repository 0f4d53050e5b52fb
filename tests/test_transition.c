/* The transition stage: conforming meshes of whole octrees, checked by the
 * independent checker (src/verify/check.c): no invalid element, faces
 * matched, closed boundary, no hanging node, the volume of the leaves; the
 * same mesh for 1, 2, 3 and 7 threads; nodes numbered in the order of the
 * leaves that first use them. */
#include <math.h>

#include "check.h"
#include "verify/check.h"
#include "kernels/transition.h"
#include "kernels/splice.h"
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

/* mx_mesh_renumber_first_use against its definition, written out serially:
 * a node's new id is its rank in the order of first use (element order,
 * then slot order), unused nodes dropped. A random mesh of mixed types
 * with local node ids (as the mesher's) and some nodes used by no element
 * or only far later; more elements than one chunk of the parallel passes
 * (16384 elements a block, a chunk per thread), for 1, 2, 3 and 7 threads. */
static void check_first_use(void) {
  const size_t nc = 300000, nn = 200000;
  uint64_t seed = 7;
  mx_mesh M0;
  memset(&M0, 0, sizeof M0);
  M0.ncells = nc;
  M0.nnodes = nn;
  M0.type = mx_alloc(nc);
  M0.conn = mx_alloc(8 * nc * sizeof *M0.conn);
  M0.xyz = mx_alloc(3 * nn * sizeof *M0.xyz);
  CHECK(M0.type && M0.conn && M0.xyz);
  for (size_t v = 0; v < 3 * nn; v++) M0.xyz[v] = (double)v;
  for (size_t c = 0; c < nc; c++) {
    seed = seed * 6364136223846793005ull + 1442695040888963407ull;
    const int t = (int)(seed >> 60) & 3;
    M0.type[c] = (uint8_t)t;
    const size_t base = c * (nn / 2) / nc; /* ids rise with the elements */
    for (int k = 0; k < 8; k++) {
      uint32_t v = 0;
      int fresh = 0;
      while (!fresh && k < mx_cell_nodes[t]) {
        seed = seed * 6364136223846793005ull + 1442695040888963407ull;
        /* mostly near base, sometimes anywhere (a late first use of an
         * early node, or an early use of a late one) */
        v = (seed >> 33) % 97 == 0 ? (uint32_t)((seed >> 13) % nn)
                                   : (uint32_t)((base + (seed >> 40) % 64) % nn);
        fresh = 1;
        for (int j = 0; j < k; j++) fresh &= M0.conn[8 * c + j] != v;
      }
      M0.conn[8 * c + k] = k < mx_cell_nodes[t] ? v : 0;
    }
  }
  /* the definition */
  uint32_t *want = malloc(nn * sizeof *want);
  CHECK(want != NULL);
  for (size_t v = 0; v < nn; v++) want[v] = UINT32_MAX;
  uint32_t next = 0;
  for (size_t c = 0; c < nc; c++)
    for (int k = 0; k < mx_cell_nodes[M0.type[c]]; k++)
      if (want[M0.conn[8 * c + k]] == UINT32_MAX) want[M0.conn[8 * c + k]] = next++;
  CHECK(next < nn); /* some nodes unused */
  const int threads[4] = {1, 2, 3, 7};
  for (int i = 0; i < 4; i++) {
    omp_set_num_threads(threads[i]);
    mx_mesh M = M0;
    M.type = mx_alloc(nc);
    M.conn = mx_alloc(8 * nc * sizeof *M.conn);
    M.xyz = mx_alloc(3 * nn * sizeof *M.xyz);
    CHECK(M.type && M.conn && M.xyz);
    memcpy(M.type, M0.type, nc);
    memcpy(M.conn, M0.conn, 8 * nc * sizeof *M.conn);
    memcpy(M.xyz, M0.xyz, 3 * nn * sizeof *M.xyz);
    uint8_t *states = mx_alloc(nn);
    CHECK(states != NULL);
    for (size_t v = 0; v < nn; v++) states[v] = (uint8_t)(v % 3);
    CHECK(mx_mesh_renumber_first_use(&M, &states) == MX_OK);
    CHECK(M.nnodes == next);
    size_t bad = 0;
    for (size_t c = 0; c < nc; c++)
      for (int k = 0; k < mx_cell_nodes[M.type[c]]; k++)
        bad += M.conn[8 * c + k] != want[M0.conn[8 * c + k]];
    for (size_t v = 0; v < nn; v++)
      if (want[v] != UINT32_MAX)
        bad += M.xyz[3 * (size_t)want[v]] != M0.xyz[3 * v] || states[want[v]] != v % 3;
    if (bad) fprintf(stderr, "first use, %d threads: %zu ids differ\n", threads[i], bad);
    CHECK(bad == 0);
    mx_free(states);
    mx_mesh_free(&M);
  }
  free(want);
  mx_mesh_free(&M0);
  omp_set_num_threads(2);
}

int main(void) {
  check_first_use();
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
