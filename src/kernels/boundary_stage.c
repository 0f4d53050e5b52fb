#include "base/cancel.h"
#include "kernels/boundary_stage.h"

#include <string.h>

#include "soa/mesh.h"

#include "base/common.h"
#include "kernels/mesh_edit.h"
#include "kernels/smooth.h"
#include "kernels/staircase.h"
#include "kernels/untangle.h"

static int piece_of(const void *ctx, const double x[3]) {
  return mx_interfaces_piece(ctx, x);
}

static int surface_piece_of(const void *ctx, const double x[3]) {
  return mx_interfaces_surface_piece(ctx, x);
}

static double clearance_of(const void *ctx, const double x[3]) {
  return mx_interfaces_clearance(ctx, x);
}

int mx_boundary_stage(const mx_tree *tr, const uint32_t *leaves,
                      const mx_surface_index *S, mx_mesh *M,
                      const mx_interfaces *I, double close_ratio, double staircase_q,
                      int smooth_rounds, int keep_unused, mx_boundary_stats *stats,
                      uint8_t **states_out) {
  memset(stats, 0, sizeof *stats);
  uint8_t *states = mx_alloc(M->nnodes + 1);
  if (!states) return MX_ENOMEM;
  uint8_t *moved = NULL;
  double t = mx_wtime();
  int st = mx_node_states(tr, leaves, M, S, states, &stats->located);
  double t1 = mx_wtime();
  mx_mem_mark("b.states");
  size_t on = 0;
#pragma omp parallel for schedule(static) reduction(+ : on)
  for (size_t v = 0; v < M->nnodes; v++) on += states[v] == MX_NODE_ON;
  stats->on_surface = on;
  stats->t_states = t1 - t;
  if (!st) st = mx_cancel_check(); /* between the steps: base/cancel.h */
  if (!st)
    st = mx_move_close_nodes(M, states, S, close_ratio, &stats->moved_close, &moved);
  t = mx_wtime();
  mx_mem_mark("b.close");
  stats->t_close = t - t1;
  if (!st) st = mx_cancel_check();
  mx_optional opt;
  memset(&opt, 0, sizeof opt);
  if (!st) st = mx_surface_patterns(M, &states, moved, &opt, &stats->sp, keep_unused && !I);
  mx_free(moved);
  stats->removed = stats->sp.removed;
  t1 = mx_wtime();
  mx_mem_mark("b.patterns");
  stats->t_patterns = t1 - t;
  if (!st) st = mx_cancel_check();
  if (!st) st = mx_shrink_to_boundary(tr, leaves, M, states, &stats->shrunk);
  t = mx_wtime();
  mx_mem_mark("b.shrink");
  stats->t_shrink = t - t1;
  if (!st) st = mx_cancel_check();
  t1 = t;
  uint16_t *piece = NULL; /* with interfaces: each node's piece, kept by the untangling */
  uint8_t *movable = NULL; /* and the nodes it may move: not those on an interface */
  if (!st && I) {
    st = mx_interface_stage(tr, leaves, S, I, M, &states, MX_CLEAVE_ALPHA, &piece, &movable,
                            &stats->ifs);
    t = mx_wtime();
    mx_mem_mark("b.interfaces");
    stats->t_interfaces = t - t1;
    t1 = t;
    /* the nodes on the outer boundary move on it (the domain's index), the
     * free ones in their piece; those on an interface stay (their shell is
     * not the domain's surface) */
    for (size_t v = 0; !st && movable && v < M->nnodes; v++) movable[v] = !movable[v];
    /* the outer boundary's nodes: the piece their surface bounds, which
     * they keep (they slide on the boundary, not across an interface) */
#pragma omp parallel for schedule(dynamic, 1024)
    for (size_t v = 0; v < M->nnodes; v++)
      if (!st && movable && movable[v] && piece[v] == MX_REGION_ON)
        piece[v] = (uint16_t)mx_interfaces_surface_piece(I, M->xyz + 3 * v);
  }
  if (!st) stats->inverted = M->invalid; /* counted by the shrink */
  if (!st && piece) {
    const mx_untangle_opts o = {staircase_q, 20, 0, movable, piece_of, I, piece, clearance_of,
                                surface_piece_of};
    st = mx_untangle_with(M, states, S, &o, &stats->smoothed);
  } else if (!st) {
    st = mx_untangle(M, states, S, staircase_q, 20, &stats->smoothed);
  }
  t = mx_wtime();
  mx_mem_mark("b.untangle");
  stats->t_smooth = t - t1;
  /* the smoothing: every neighbourhood's worst element raised, never
   * lowered; not with interfaces (their pieces' nodes would need the
   * untangling's region tests) */
  if (!st && !piece) { /* (0 rounds: only the figures) */
    const mx_smooth_opts so = {smooth_rounds, MX_SMOOTH_TARGET, NULL};
    st = mx_smooth(M, states, S, &so, &stats->smoothing);
    mx_mem_mark("b.smooth");
    t = mx_wtime();
  }
  mx_free(piece);
  mx_free(movable);
  const int staircase = !st && staircase_q < 1.0;
  if (staircase) st = mx_staircase(M, &opt, staircase_q, &stats->sp);
  stats->t_staircase = mx_wtime() - t;
  mx_optional_free(&opt);
  if (states_out && !st) {
    *states_out = states;
    states = NULL;
  }
  mx_free(states);
  if (!st && !staircase) mx_mesh_summarize(M); /* (the staircase's last step is one) */
  return st;
}
