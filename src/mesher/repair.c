/* The repair rounds of the full stage: see mx_repair below. */
#include "mesher/mesher_impl.h"
#include "mesher/pipeline.h"

#include "kernels/estimate.h"
#include "kernels/grid.h"
#include "kernels/mesh_edit.h"
#include "kernels/closures.h"
#include "kernels/edges_lazy.h"
#include "kernels/refine_list.h"
#include "kernels/splice.h"
#include "kernels/tet_split.h"
#include "geom/surface_defects.h"
#include "soa/mesh.h"

#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Repair (the 2021 paper, section 6): the leaves holding elements with
 * J_ENS < 1e-6, or elements a node lies on without being one of their nodes
 * (kernels/contacts.h: two sheets of the boundary meeting), are split once
 * by list refinement (Algorithm 3), and the octree is meshed again around
 * them (remesh_patch.c), up to repair_rounds times. m->rec->S.contacts holds the
 * contacts of the final mesh.
 *
 * When to go on: a round is worse when it does not lower the count of the
 * round before it; two worse rounds since the best one stop the repair (a
 * surface feature finer than any level, an input's hole: 17, 33, 45 ...).
 * Not "not below the best": a repair often gets worse before it gets
 * better, as the first split puts transition patterns at the surface where
 * the shrink inverts more than before (the triple torus of issue 23 at -s 6:
 * 2 defects, then 30, 10, 2, 0); judged against the best (2), 30 and 10
 * were two worse rounds and the repair stopped while it was converging. */
int mx_repair_go_on(int round, uint64_t defects, int max_rounds, mx_repair_progress *p) {
  if (defects == 0 || round >= max_rounds) return 0;
  const uint64_t before = p->last;
  p->last = defects;
  if (round == 0 || defects < p->best) {
    p->best = defects;
    p->worse = 0;
  } else if (defects >= before && ++p->worse >= 2) {
    return 0;
  }
  return 1;
}

int mx_repair(mx_mesher *m) {
  uint8_t *flag = NULL;
  mx_repair_progress progress = {0, 0, 0};
  for (int round = 0;; round++) {
    mx_free(flag);
    flag = mx_alloc(m->M.ncells + 1);
    if (!flag) return MX_ENOMEM;
    const double t = mx_wtime();
    int st = mx_mesher_stage(m, "verify"); /* MX_ECANCELED: cancelled */
    /* after a local re-mesh of a mesh without contacts: only around what
     * changed (kernels/contacts.h) */
    const double *region = m->changed_valid ? m->changed_box : NULL;
    m->changed_valid = 0;
    m->rec->S.contacts_local += region != NULL;
    if (!st)
      st = mx_find_contacts_in(&m->M, &m->B.tree.grid, m->states, region, flag,
                               &m->rec->S.contacts);
    m->contacts_clean = !st && m->rec->S.contacts.nodes == 0;
    m->clean_conn = m->M.conn;
    m->clean_ncells = m->M.ncells;
    /* --tets: elements no split into tetrahedra keeps valid (a prism with
     * two warped faces cut along their concave diagonals) are repaired too */
    const size_t unsplit = !st && m->p.tets ? mx_tet_split_flag_failures(&m->M, flag) : 0;
    m->rec->S.ph.verify += mx_wtime() - t;
    if (st) {
      mx_free(flag);
      return st;
    }
    if (!mx_repair_go_on(round, m->M.invalid + m->rec->S.contacts.nodes + unsplit,
                         m->p.repair_rounds, &progress))
      break;
    if (m->progress.on_round) m->progress.on_round(m->progress.user, round + 1);
    size_t n = 0;
    uint32_t *octs =
        mx_alloc((m->M.invalid + m->rec->S.contacts.elements + unsplit + 1) * sizeof *octs);
    if (!octs) {
      mx_free(flag);
      return MX_ENOMEM;
    }
    for (size_t c = 0; c < m->M.ncells; c++) {
      if (!mx_jens_invalid(m->M.jens[c]) && !flag[c]) continue;
      const uint32_t o = m->leaves[m->M.leaf[c]];
      if (m->B.tree.oct.level[o] < MX_MAX_LEVEL - 1) octs[n++] = o; /* else: as fine as can be */
    }
    if (n == 0) break;
    const size_t before = m->M.invalid;
    m->rec->S.contacts_repaired += m->rec->S.contacts.elements;
    st = mx_refine_list(&m->B, octs, n);
    mx_free(octs);
    if (!st) {
      m->rec->S.repaired += before;
      m->rec->S.repair_rounds++;
      st = mx_remesh_after_refine(m);
    }
    if (st) {
      mx_free(flag);
      return st;
    }
  }
  mx_free(flag);
  return MX_OK;
}
