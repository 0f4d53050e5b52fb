/* The nodes on the partition boundary of the distributed mesh: which nodes
 * each rank shares with which, the agreement on their positions and states,
 * their global numbers (src/mpi/p4est_mesh.h says how). Collective over
 * P->comm except mx_shared_collect. */
#ifndef MX_P4EST_NODES_H
#define MX_P4EST_NODES_H

#include "mpi/p4est_mesh.h"

/* The nodes of this rank's elements that another rank's elements use: one
 * entry per (peer, node), grouped by peer (rising), by lattice key within
 * a peer, with the node's position and state as this rank computed them. */
typedef struct {
  size_t n;
  int32_t *peer;
  uint64_t *key;
  double *xyz;     /* 3 per entry */
  uint8_t *state;
  size_t unkeyed;  /* shared nodes without a lattice key (cannot be matched) */
} mx_shared;

/* From the patch mesh M (states per node; core[c]: element c is this
 * rank's; leaf_owner: the owner rank of each patch leaf, M->leaf indexing
 * it). Not collective. */
int mx_shared_collect(const mx_mesh *M, const uint8_t *states, const uint8_t *core,
                      const int32_t *leaf_owner, int rank, mx_shared *sh);
/* Sends each peer its list, compares what comes back; *differ: entries
 * that differ over all ranks. last: a difference is an error (message
 * naming the inputs and the first node, MX_EINVALID), else the caller
 * tries again. */
int mx_shared_agree(const mx_p4est_octree *P, mx_p4est_mesh *D, const mx_shared *sh, int last,
                    const char *inputs, size_t *differ);
/* Owners, global numbers (D->gid, D->owned, D->first_owned, D->nowned) of
 * D->M's nodes. */
int mx_shared_number(const mx_p4est_octree *P, mx_p4est_mesh *D, const mx_shared *sh);
void mx_shared_free(mx_shared *sh);

#endif
