/* The stages after refinement, chained once: see mesher/pipeline.h. */
#include "mesher/pipeline.h"

#include <math.h>
#include <string.h>

#include "kernels/smooth.h"
#include "kernels/untangle.h"

#include "base/common.h"
#include "kernels/edges_lazy.h"
#include "kernels/mesh_edit.h"
#include "kernels/transition.h"
#include "mesher/call.h"
#include "mesher/mesher_impl.h"
#include "base/cancel.h"

int mx_mesher_stage(const mx_mesher *m, const char *name) {
  mx_mem_mark(name);
  mx_call_recheck();
  if (m->progress.on_stage) m->progress.on_stage(m->progress.user, name);
  return mx_cancel_check(); /* after the hook: it may cancel */
}

int mx_mesher_index(mx_mesher *m) {
  if (m->have_index) return MX_OK;
  /* the boundary's pieces are oriented already (the domain behind): as
   * given, without the shells' nesting (pieces cut apart are shells of
   * their own, each a winding number query) */
  if (m->have_winding)
    MX_CHECK(mx_surface_index_build_given(&m->SI, &m->soup, 0, m->nt_domain));
  else if (m->p.materials) /* nested shells are materials, not holes */
    MX_CHECK(mx_surface_index_build_outward(&m->SI, &m->soup, 0, m->nt_domain));
  else
    MX_CHECK(mx_surface_index_build(&m->SI, &m->soup, 0, m->nt_domain));
  if (m->p.materials) { /* the pieces: the inputs as given, shared triangles included */
    const int st = m->material_src.nt
                       ? mx_interfaces_build(&m->IF, &m->material_src,
                                             (uint32_t)m->material_src.nt, m->material_shared)
                       : mx_interfaces_build(&m->IF, &m->soup, m->nt_domain, NULL);
    if (st) { /* built whole or not at all */
      mx_surface_index_free(&m->SI);
      return st;
    }
  }
  m->have_index = 1;
  if (m->p.repair_input) m->SI.closed = 0;
  if (m->have_winding) m->SI.side = &m->WI;
  return MX_OK;
}

int mx_pipeline_transition(mx_mesher *m, const uint32_t *leaves, size_t n, int release_edges,
                           mx_mesh *M) {
  MX_CHECK(mx_edges_restore(&m->B));
  mx_leaf_masks lm;
  MX_CHECK(mx_transition_masks(&m->B.tree, leaves, n, &lm));
  if (mx_cancelled()) { /* between the masks and the elements */
    mx_free(lm.mask);
    return MX_ECANCELED;
  }
  if (release_edges) mx_edges_release(&m->B);
  return mx_transition_build(&m->B.tree, leaves, n, &lm, M);
}

/* The least J_ENS a feature may leave an element at, unless the element
 * was worse before, and the J_ENS below which the untangling runs after
 * the placement. Measured:
 * at 0 or 0.05 the 35 ridges the cortex kept at 30 degrees lowered its
 * worst element from 0.099 to 0.033 or 0.071 at -s 5; the cortex keeps
 * none now (its ridges end in smooth surface: noise). On the OpenSCAD
 * corpus at -s 5, 0.05 against 0.1 (with the retries at corners): the
 * tetrahedron kept its lines at its 60 degree corners (their elements have
 * J_ENS 0.06), 11 closed parts exact instead of 10, median volume error
 * 0.021% against 0.059%. */
#define MX_FEATURE_FLOOR 0.05
#define MX_FEATURE_UNTANGLE_BELOW 0.1

/* The boundary the features are placed on: within NEAR_OCTANTS octants at
 * the feature level of them (mx_feature_near_nodes keeps all within 3/4 of
 * that: 6). Their boundary edges are no longer than an octant's diagonal
 * there; the placement reaches 5 mean edges from a line or corner. */
#define NEAR_OCTANTS 8.0

/* The tries again at the corners of the lines missed, on the whole mesh
 * only (a local re-mesh's patch cuts lines). Measured at -s 5: without
 * them in the patches text_on_cube (12 patches in 4 repair rounds) 2.20
 * -> 2.03 s and linear_extrude 1.04 -> 0.91 s, the same distances; the
 * tetrahedron at -s 6 places its sixth line on the second try. */
#define FEATURE_RETRIES 3

double mx_feature_reach(const mx_mesher *m) {
  const int base = m->feature_level > m->p.surface_level ? m->feature_level : m->p.surface_level;
  return base > 0 && m->B.req.root_side > 0 ? NEAR_OCTANTS * ldexp(m->B.req.root_side, -base) : 0.0;
}

/* The features placed on the boundary (kernels/feature_place.h), then the
 * elements they spoilt untangled with the feature nodes fixed; what stays
 * invalid gives its features up (mx_feature_give_up); then the smoothing
 * (--smooth N) of the inside nodes. */
static int features_active(const mx_mesher *m) {
  return m->have_features && !m->p.materials;
}

/* The nodes that may move after the placement (mx_alloc; NULL: out of
 * memory): all but the feature nodes; with states, the inside ones only. */
static uint8_t *movable_nodes(const mx_mesh *M, const uint8_t *fixed, const uint8_t *states) {
  uint8_t *mv = mx_alloc(M->nnodes + 1);
  if (mv)
    for (size_t v = 0; v < M->nnodes; v++)
      mv[v] = !fixed[v] && (!states || states[v] != MX_NODE_OUTSIDE);
  return mv;
}

/* movable[] kept only for the nodes of the elements with a node the
 * placement moved (or added: index nb and up): the others are as the
 * boundary stage left them, untangled already. Measured at -s 5: the
 * untangling after the placement on example023 0.33 -> 0.16 s, the same
 * worst J_ENS and distances on six corpus parts. */
static int near_moved(const mx_mesh *M, const double *before, size_t nb, uint8_t *movable) {
  uint8_t *touch = mx_calloc(M->nnodes + 1);
  if (!touch) return MX_ENOMEM;
  const int64_t nc = (int64_t)M->ncells;
#pragma omp parallel for schedule(static)
  for (int64_t c = 0; c < nc; c++) {
    const uint32_t *cn = M->conn + 8 * c;
    const int k = mx_cell_nodes[M->type[c]];
    int mv = 0;
    for (int i = 0; i < k && !mv; i++)
      mv = cn[i] >= nb || memcmp(M->xyz + 3 * (size_t)cn[i], before + 3 * (size_t)cn[i], 3 * sizeof *before) != 0;
    if (mv)
      for (int i = 0; i < k; i++) __atomic_store_n(&touch[cn[i]], 1, __ATOMIC_RELAXED);
  }
  for (size_t v = 0; v < M->nnodes; v++) movable[v] = movable[v] && touch[v];
  mx_free(touch);
  return MX_OK;
}

static int place_features(mx_mesher *m, mx_mesh *M, uint8_t **states_io, mx_boundary_stats *bs) {
  if (!features_active(m) || !*states_io) return MX_OK;
  const mx_features *F = &m->feat;
  const int whole = M == &m->M; /* not a local re-mesh's patch */
  /* lines from a file: no patches (theirs are the ridges found) */
  const mx_feature_input in = {&m->feat_lines, &m->soup, m->nt_domain,
                               m->feature_file ? NULL : F->patch, F->npatches, mx_feature_reach(m),
                               whole ? FEATURE_RETRIES : 0};
  uint8_t *fixed = mx_alloc(M->nnodes + 1);
  double *before = mx_alloc((3 * M->nnodes + 1) * sizeof *before);
  float *q_before = mx_alloc((M->ncells + 1) * sizeof *q_before);
  if (!fixed || !before || !q_before) {
    mx_free(fixed);
    mx_free(before);
    mx_free(q_before);
    return MX_ENOMEM;
  }
  memcpy(before, M->xyz, 3 * M->nnodes * sizeof *before);
  memcpy(q_before, M->jens, M->ncells * sizeof *q_before);
  /* the figures of the whole mesh's placement: a local re-mesh's patch
   * (the repair) places what of the features it holds, not reported (the
   * triple torus at -s 6 said "0 of 19 corners", its last patch's) */
  mx_feature_stats patch_figures;
  mx_feature_stats *fs = whole ? &m->rec->S.feature_place : &patch_figures;
  const size_t nb = M->nnodes, ncb = M->ncells;
  mx_split_log log = {0, NULL, 0};
  mx_feature_chain chain = {0, NULL, NULL, NULL};
  int st = mx_feature_place(M, states_io, &m->SI, &in, &fixed, fs, &log, &chain);
  const uint8_t *states = *states_io;
  const double t = mx_wtime();
  if (!st && (M->invalid || M->jens_min < MX_FEATURE_UNTANGLE_BELOW)) {
    uint8_t *movable = movable_nodes(M, fixed, NULL);
    st = movable ? near_moved(M, before, nb, movable) : MX_ENOMEM;
    const mx_untangle_opts o = {m->p.staircase_quality, 20, 0, movable, NULL, NULL, NULL, NULL, NULL};
    size_t moved = 0;
    if (!st) st = mx_untangle_with(M, states, &m->SI, &o, &moved);
    if (!st) mx_mesh_summarize(M);
    mx_free(movable);
  }
  if (!st) st = mx_feature_give_up(M, states_io, &log, fixed, &chain, before, nb, q_before, ncb,
                                   MX_FEATURE_FLOOR, fs);
  mx_split_log_free(&log);
  mx_feature_chain_free(&chain);
  states = *states_io;
  fs->seconds += mx_wtime() - t;
  if (!st && m->p.smooth_rounds > 0) {
    /* the smoothing, after the features: the inside nodes only, so the
     * boundary stays as placed (faces on their side of every ridge) */
    uint8_t *movable = movable_nodes(M, fixed, states);
    const mx_smooth_opts so = {m->p.smooth_rounds, MX_SMOOTH_TARGET, movable};
    st = movable ? mx_smooth(M, states, &m->SI, &so, &bs->smoothing) : MX_ENOMEM;
    mx_free(movable);
  }
  m->rec->S.features_kept = !st;
  mx_free(fixed);
  mx_free(before);
  mx_free(q_before);
  return st;
}

int mx_pipeline_boundary(mx_mesher *m, const uint32_t *leaves, size_t n, mx_mesh *M,
                         int first_use_next, uint8_t **states, mx_boundary_stats *bs) {
  if (!m->have_index) {
    MX_CHECK(mx_mesher_stage(m, "index"));
    MX_CHECK(mx_mesher_index(m));
    MX_CHECK(mx_mesher_stage(m, "boundary"));
  }
  MX_CHECK(mx_boundary_stage(&m->B.tree, leaves, &m->SI, M,
                             m->IF.npasses ? &m->IF : NULL, m->p.close_ratio,
                             m->p.staircase_quality,
                             features_active(m) ? 0 : m->p.smooth_rounds,
                             first_use_next && !features_active(m), bs, states));
  MX_CHECK(place_features(m, M, states, bs)); /* and the smoothing after them */
  return mx_mesh_sort_by_leaf(M, n);
}
