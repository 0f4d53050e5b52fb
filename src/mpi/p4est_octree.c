/* mx_p4est_build: the steps of the distributed octree in order (see
 * p4est_octree.h). */
#include "mpi/p4est_octree.h"

#include "base/common.h"

#include <string.h>

#include <p8est_extended.h>

int mx_p4est_build(mx_p4est_octree *P, const mx_builder *B, MPI_Comm comm,
                   const mx_p4est_params *par) {
  memset(P, 0, sizeof *P);
  P->comm = comm;
  MPI_Comm_rank(comm, &P->rank);
  MPI_Comm_size(comm, &P->size);
  P->B = B;
  if (par)
    P->par = *par;
  else
    mx_p4est_params_default(&P->par);
  P->max_level = mx_max_requested_level(&B->req);
  if (P->max_level > P8EST_QMAXLEVEL) {
    mx_error(NULL, 0, "level %d is deeper than p4est allows (%d)", P->max_level,
             P8EST_QMAXLEVEL);
    return MX_EINPUT;
  }
  const double t0 = mx_wtime();
  MX_CHECK(mx_p4est_new_forest(P));
  P->t.refine += mx_wtime() - t0;
  MX_CHECK(mx_p4est_refine(P));
  MX_CHECK(mx_p4est_balance(P));
  MX_CHECK(mx_p4est_partition(P, 1));
  return mx_p4est_ghost(P);
}

void mx_p4est_free(mx_p4est_octree *P) {
  if (P->ghost) p8est_ghost_destroy(P->ghost);
  if (P->p8) p8est_destroy(P->p8);
  if (P->conn) p8est_connectivity_destroy(P->conn);
  mx_free(P->ghost_data);
  mx_free(P->tree_root);
  mx_free(P->pool);
  mx_free(P->mask);
  memset(P, 0, sizeof *P);
}
