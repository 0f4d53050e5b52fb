/* Node states of the boundary stage: against the analytic answer on a cube,
 * against the ray-parity locator on the cortex; nodes of leaves that meet no
 * triangle are inside without a query. */
#include <math.h>

#include "check.h"
#include "kernels/boundary.h"
#include "kernels/transition.h"
#include "kernels/mesh_edit.h"
#include "verify/check.h"
#include "geom/locate.h"
#include "geom/quality.h"
#include "soa/mesh.h"
#include "octree_util.h"

typedef struct {
  mx_builder B;
  uint32_t *leaves;
  size_t n;
  mx_mesh M;
} built;

static int build(const mx_trisoup *s, int level, built *b) {
  mx_requests r = no_requests();
  r.s_level = level;
  uint32_t rt0[2] = {(uint32_t)s->nt, (uint32_t)s->nt};
  int st = mx_builder_init(&b->B, s, (uint32_t)s->nt, rt0, &r, 1, NULL);
  if (!st) st = mx_build_roots(&b->B);
  if (!st) st = mx_refine_balanced(&b->B);
  if (!st) st = mx_resolve_closures(&b->B);
  if (!st) st = mx_leaves(&b->B.tree, &b->leaves, &b->n);
  if (!st) st = mx_leaves_sorted(&b->B.tree, b->leaves, b->n);
  if (!st) st = mx_transition(&b->B.tree, b->leaves, b->n, &b->M);
  return st;
}

static void release(built *b) {
  mx_mesh_free(&b->M);
  mx_free(b->leaves);
  mx_builder_free(&b->B);
}

/* Line 11 of Algorithm 1 (2015 paper) on its own, as the paper states it:
 * the close nodes moved (mx_move_close_nodes), then the elements left with
 * no inside node removed and the nodes no element uses dropped (the
 * pipeline removes them within the surface patterns' pass). */
static int remove_close_to_boundary(mx_mesh *M, uint8_t **states_io,
                                const mx_surface_index *S, double ratio,
                                size_t *moved, size_t *removed) {
  const size_t nc = M->ncells;
  MX_CHECK(mx_move_close_nodes(M, *states_io, S, ratio, moved, NULL));
  const uint8_t *states = *states_io;
  /* Remove the elements left with no inside node, then the nodes no
   * element uses. */
  uint8_t *keep = mx_alloc(nc + 1);
  if (!keep) return MX_ENOMEM;
#pragma omp parallel for schedule(static)
  for (size_t c = 0; c < nc; c++) {
    int in = 0;
    for (int k = 0; k < mx_cell_nodes[M->type[c]]; k++)
      in |= mx_node_inside(states[M->conn[8 * c + k]]);
    keep[c] = (uint8_t)in;
  }
  int st = mx_mesh_keep_cells(M, keep);
  mx_free(keep);
  if (!st) st = mx_mesh_drop_unused_nodes(M, states_io, NULL);
  if (st) return st;
  *removed = nc - M->ncells;
  mx_mesh_summarize(M);
  return MX_OK;
}

int main(void) {
  /* The unit cube at -s 4: every node's state is known analytically (the
   * grid never puts a node on the cube's faces: they lie 0.005 inside the
   * root). */
  {
    mx_trisoup cube;
    memset(&cube, 0, sizeof cube);
    const double lo[3] = {-0.5, -0.5, -0.5}, hi[3] = {0.5, 0.5, 0.5};
    add_box(&cube, lo, hi, 0);
    built b;
    CHECK(build(&cube, 4, &b) == MX_OK);
    mx_surface_index S;
    CHECK(mx_surface_index_build(&S, &cube, 0, (uint32_t)cube.nt) == MX_OK);
    uint8_t *st = mx_alloc(b.M.nnodes + 1);
    size_t q = 0;
    CHECK(mx_node_states(&b.B.tree, b.leaves, &b.M, &S, st, &q) == MX_OK);
    size_t wrong = 0, inside = 0;
    for (size_t v = 0; v < b.M.nnodes; v++) {
      const double *p = b.M.xyz + 3 * v;
      const int in = fabs(p[0]) < 0.5 && fabs(p[1]) < 0.5 && fabs(p[2]) < 0.5;
      wrong += in != mx_node_inside(st[v]);
      inside += in;
    }
    printf("cube -s 4: %zu nodes, %zu inside, %zu located, %zu wrong\n", b.M.nnodes,
           inside, q, wrong);
    CHECK(wrong == 0);
    CHECK(inside > 0 && inside < b.M.nnodes);
    CHECK(q < b.M.nnodes); /* the inside leaves' nodes were not located */
    mx_free(st);
    mx_surface_index_free(&S);
    release(&b);
    mx_trisoup_free(&cube);
  }
  /* The cortex at -s 5: the same answer as the ray-parity locator for nodes
   * not on the surface; every node of a leaf meeting no triangle inside. */
  mx_trisoup s;
  if (load_shared_surface("cortex.off", &s)) {
    built b;
    CHECK(build(&s, 5, &b) == MX_OK);
    mx_surface_index S;
    CHECK(mx_surface_index_build(&S, &s, 0, (uint32_t)s.nt) == MX_OK);
    mx_locator L;
    CHECK(mx_locator_build(&L, &s, 0, (uint32_t)s.nt) == MX_OK);
    uint8_t *st = mx_alloc(b.M.nnodes + 1);
    size_t q = 0;
    double t = mx_wtime();
    CHECK(mx_node_states(&b.B.tree, b.leaves, &b.M, &S, st, &q) == MX_OK);
    t = mx_wtime() - t;
    size_t wrong = 0, checked = 0, inside = 0;
    for (size_t v = 0; v < b.M.nnodes; v++) {
      double cp[3];
      const double *p = b.M.xyz + 3 * v;
      inside += mx_node_inside(st[v]);
      if (fabs(mx_signed_distance(&S, p, cp)) < 1e-9) continue;
      checked++;
      wrong += mx_locate(&L, p) != mx_node_inside(st[v]);
    }
    size_t bad_inherit = 0;
    for (size_t c = 0; c < b.M.ncells; c++) {
      if (b.B.tree.oct.flags[b.leaves[b.M.leaf[c]]] & MX_OCT_SURFACE) continue;
      for (int k = 0; k < mx_cell_nodes[b.M.type[c]]; k++)
        bad_inherit += !mx_node_inside(st[b.M.conn[8 * c + k]]);
    }
    printf("cortex -s 5: %zu nodes, %zu inside, %zu located in %.3f s, %zu compared, "
           "%zu disagree\n", b.M.nnodes, inside, q, t, checked, wrong);
    CHECK(wrong == 0 && bad_inherit == 0);
    CHECK(q < b.M.nnodes);
    mx_free(st);
    mx_locator_free(&L);
    mx_surface_index_free(&S);
    release(&b);
    mx_trisoup_free(&s);
  }
  /* Remove close to boundary on the cortex at -s 5, for 1 and 2 threads. */
  if (load_shared_surface("cortex.off", &s)) {
    mx_surface_index S;
    CHECK(mx_surface_index_build(&S, &s, 0, (uint32_t)s.nt) == MX_OK);
    double lo[3], hi[3];
    mx_trisoup_bbox(&s, lo, hi);
    const double diag = sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                             (hi[2] - lo[2]) * (hi[2] - lo[2]));
    mx_mesh keep[2];
    for (int th = 1; th <= 2; th++) {
      omp_set_num_threads(th);
      built b;
      CHECK(build(&s, 5, &b) == MX_OK);
      uint8_t *st = mx_alloc(b.M.nnodes + 1);
      size_t q = 0, moved = 0, removed = 0;
      CHECK(mx_node_states(&b.B.tree, b.leaves, &b.M, &S, st, &q) == MX_OK);
      size_t on0 = 0;
      for (size_t v = 0; v < b.M.nnodes; v++)
        on0 += fabs(mx_signed_distance(&S, b.M.xyz + 3 * v, NULL)) <= 1e-9 * diag;
      const size_t n0 = b.M.nnodes, c0 = b.M.ncells;
      CHECK(remove_close_to_boundary(&b.M, &st, &S, 0.3, &moved, &removed) == MX_OK);
      /* every element keeps an inside node; moved nodes are on the surface */
      size_t no_inside = 0, on1 = 0;
      for (size_t c = 0; c < b.M.ncells; c++) {
        int in = 0;
        for (int k = 0; k < mx_cell_nodes[b.M.type[c]]; k++)
          in += mx_node_inside(st[b.M.conn[8 * c + k]]);
        no_inside += in == 0;
      }
      for (size_t v = 0; v < b.M.nnodes; v++)
        on1 += fabs(mx_signed_distance(&S, b.M.xyz + 3 * v, NULL)) <= 1e-9 * diag;
      /* still conforming: removing whole elements and moving nodes keeps the
       * faces matched, nothing unused */
      mx_mesh_data m = {.nnodes = b.M.nnodes, .ncells = b.M.ncells, .xyz = b.M.xyz,
                        .type = b.M.type, .conn = b.M.conn};
      mx_check_report r;
      CHECK(mx_check_mesh(&m, NULL, &r) == MX_OK);
      printf("remove close (%d thread%s): %zu -> %zu nodes, %zu -> %zu elements, %zu moved, "
             "%zu removed, %zu on the surface, %zu invalid after moving\n", th, th > 1 ? "s" : "",
             n0, b.M.nnodes, c0, b.M.ncells, moved, removed, on1, r.invalid);
      CHECK(moved > 0 && removed > 0);
      CHECK(b.M.ncells == c0 - removed);
      CHECK(no_inside == 0);
      CHECK(on1 >= on0 && on1 - on0 <= moved);
      CHECK(r.faces_overshared == 0 && r.faces_misoriented == 0 && r.quad_vs_triangles == 0 &&
            r.open_boundary_edges == 0 && r.unused_nodes == 0);
      /* Shrink: every outside node onto the surface (within 1e-9 of the
       * bounding box's diagonal); inside nodes do not move. */
      double *before = mx_alloc(3 * b.M.nnodes * sizeof *before);
      memcpy(before, b.M.xyz, 3 * b.M.nnodes * sizeof *before);
      size_t shrunk = 0;
      CHECK(mx_shrink_to_boundary(&b.B.tree, b.leaves, &b.M, st, &shrunk) == MX_OK);
      size_t far = 0, outside = 0, inside_moved = 0;
      for (size_t v = 0; v < b.M.nnodes; v++) {
        if (st[v] == MX_NODE_OUTSIDE) {
          outside++;
          far += fabs(mx_signed_distance(&S, b.M.xyz + 3 * v, NULL)) > 1e-9 * diag;
        } else {
          inside_moved += memcmp(before + 3 * v, b.M.xyz + 3 * v, 3 * sizeof *before) != 0;
        }
      }
      mx_free(before);
      CHECK(mx_check_mesh(&m, &s, &r) == MX_OK);
      printf("shrink: %zu of %zu outside nodes moved, %zu off the surface; "
             "%zu invalid elements (no surface patterns yet), volume error %.4f%%, "
             "boundary distance %.2e\n", shrunk, outside, far, r.invalid,
             100.0 * r.volume_error, r.boundary_max_dist);
      CHECK(far == 0 && inside_moved == 0 && shrunk == outside);
      /* the J_ENS the shrink keeps (recomputed only where a node moved) is
       * every element's J_ENS from its positions */
      size_t stale = 0;
      for (size_t c = 0; c < b.M.ncells; c++) {
        double x[8][3];
        for (int k = 0; k < mx_cell_nodes[b.M.type[c]]; k++)
          memcpy(x[k], b.M.xyz + 3 * (size_t)b.M.conn[8 * c + k], sizeof x[k]);
        stale += b.M.jens[c] != (float)mx_jens(b.M.type[c], x);
      }
      printf("shrink: %zu element(s) with a stale J_ENS\n", stale);
      CHECK(stale == 0);
      keep[th - 1] = b.M;
      memset(&b.M, 0, sizeof b.M);
      mx_free(st);
      release(&b);
    }
    CHECK(keep[0].nnodes == keep[1].nnodes && keep[0].ncells == keep[1].ncells);
    if (keep[0].nnodes == keep[1].nnodes && keep[0].ncells == keep[1].ncells) {
      CHECK(memcmp(keep[0].xyz, keep[1].xyz, 3 * keep[0].nnodes * sizeof(double)) == 0);
      CHECK(memcmp(keep[0].conn, keep[1].conn, 8 * keep[0].ncells * sizeof(uint32_t)) == 0);
    }
    mx_mesh_free(&keep[0]);
    mx_mesh_free(&keep[1]);
    mx_surface_index_free(&S);
    mx_trisoup_free(&s);
  }
  return TEST_DONE();
}
