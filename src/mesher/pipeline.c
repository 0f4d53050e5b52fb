/* The stages after refinement, chained once: see mesher/pipeline.h. */
#include "mesher/pipeline.h"

#include "base/common.h"
#include "kernels/edges_lazy.h"
#include "kernels/mesh_edit.h"
#include "kernels/transition.h"
#include "mesher/call.h"
#include "mesher/mesher_impl.h"

void mx_mesher_stage(const mx_mesher *m, const char *name) {
  mx_mem_mark(name);
  mx_call_recheck();
  if (m->progress.on_stage) m->progress.on_stage(m->progress.user, name);
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
  if (release_edges) mx_edges_release(&m->B);
  return mx_transition_build(&m->B.tree, leaves, n, &lm, M);
}

int mx_pipeline_boundary(mx_mesher *m, const uint32_t *leaves, size_t n, mx_mesh *M,
                         uint8_t **states, mx_boundary_stats *bs) {
  if (!m->have_index) {
    mx_mesher_stage(m, "index");
    MX_CHECK(mx_mesher_index(m));
    mx_mesher_stage(m, "boundary");
  }
  MX_CHECK(mx_boundary_stage(&m->B.tree, leaves, &m->SI, M,
                             m->IF.npasses ? &m->IF : NULL, m->p.close_ratio,
                             m->p.staircase_quality, m->p.smooth_rounds, bs, states));
  return mx_mesh_sort_by_leaf(M, n);
}
