/* 2:1 balance of the forest across faces and edges (P8EST_CONNECT_EDGE:
 * the rule of Jaillet & Lobos's Algorithm 1, corners free), by p4est.
 *
 * p4est replaces a quadrant by a balanced subtree one family at a time,
 * top-down (the parent's data is valid during the call, the new families
 * below it get theirs from the call before), so the replace callback
 * classifies each family from its parent's triangles like a refinement
 * split does, appending the children's lists to the pool. Serial: p4est
 * calls it from one thread. */
#include "mpi/p4est_octree.h"

#include "base/common.h"
#include "soa/tree_valid.h"

#include <p8est_algorithms.h>
#include <p8est_bits.h>
#include <p8est_extended.h>
#include <p8est_ghost.h>

static void balance_replace(p8est_t *p8, p4est_topidx_t t, int nout, p8est_quadrant_t *out[],
                            int nin, p8est_quadrant_t *in[]) {
  mx_p4est_octree *P = p8->user_pointer;
  if (P->status) return;
  if (nout != 1 || nin != P8EST_CHILDREN) {
    P->status = MX_EINTERNAL;
    return;
  }
  const mx_pq *d = out[0]->p.user_data;
  if (mx_p4est_mask_reserve(P, (size_t)d->tri_cnt + 1)) {
    P->status = MX_ENOMEM;
    return;
  }
  mx_pq_family f;
  mx_pq_classify(P->B, mx_p4est_key(P, t, out[0]), out[0]->level, d, P->pool + d->tri_off,
                 P->mask, &f);
  P->located += f.located;
  const uint64_t n = mx_pq_family_tris(&f);
  if (mx_p4est_pool_reserve(P, n + 1)) { /* may move the pool: offsets stay */
    P->status = MX_ENOMEM;
    return;
  }
  mx_pq_fill(&f, P->pool + d->tri_off, d->tri_cnt, P->mask, P->pool + P->pool_n, P->pool_n);
  P->pool_n += n;
  for (int c = 0; c < P8EST_CHILDREN; c++)
    *(mx_pq *)in[c]->p.user_data = f.child[p8est_quadrant_child_id(in[c])];
  P->split_balance++;
}

int mx_p4est_balance(mx_p4est_octree *P) {
  const double t0 = mx_wtime();
  p8est_balance_ext(P->p8, P8EST_CONNECT_EDGE, NULL, balance_replace);
  int st = P->status, all = st;
  MPI_Allreduce(&st, &all, 1, MPI_INT, MPI_MAX, P->comm);
  /* debug builds (soa/tree_valid.h): p4est's own invariants, collective */
  if (MX_INVARIANTS && !all &&
      !(p8est_is_valid(P->p8) && p8est_is_balanced(P->p8, P8EST_CONNECT_EDGE))) {
    mx_error(NULL, 0, "internal: the forest is not valid and balanced after p8est_balance");
    all = MX_EINTERNAL;
  }
  P->t.balance += mx_wtime() - t0;
  return all;
}
