/* The halo of a rank: the leaves of other ranks within `rings` rings of
 * its own (ring 1: the leaves touching one of its leaves, ring k + 1: the
 * leaves touching ring k), counted through the leaves in the domain only,
 * as the single-process octree sees them (it stores no outside octant).
 *
 * Ring 1 comes from p4est's ghost layer (the ghosts in the domain: those
 * touching a leaf of this rank, and a few touching only one of its outside
 * quadrants, a harmless extra). Each further ring costs two all-to-all
 * exchanges: every leaf of the last ring goes to the ranks whose part of
 * the Morton curve meets one of the 26 same-size boxes around it
 * (p8est_comm_find_owner on the partition), which answer with their leaves
 * in the domain touching it (binary searches in their sorted keys). This is
 * p8est_ghost_expand's job, restricted to the leaves in the domain and
 * linear in the ring's size (p8est_ghost_expand took 0.25 s for its first
 * ring and 1.8 s for its fifth on the cortex at level 8 on 2 ranks).
 *
 * Collective over P->comm (mx_halo_expand). */
#ifndef MX_P4EST_HALO_H
#define MX_P4EST_HALO_H

#include "mpi/p4est_octree.h"

typedef struct {
  /* this rank's leaves in the domain, sorted by key, with their data in
   * the forest */
  uint64_t *lkey;
  uint8_t *llevel;
  const mx_pq **lpq;
  size_t nlocal;
  /* lkey's buckets: the keys with key >> bshift == b are at
   * [bucket[b], bucket[b + 1]) (nbucket + 1 entries): a search starts
   * there instead of in the whole array */
  uint32_t *bucket;
  size_t nbucket;
  int bshift;
  /* the halo: in the order found (ring by ring), ring r's leaves at
   * [ring_start[r], ring_start[r + 1]) for r = 1 .. rings */
  uint64_t *key;
  uint8_t *level;
  int32_t *owner;
  size_t n, cap;
  size_t ring_start[64];
  int rings;
  /* every key known (local and halo), sorted */
  uint64_t *known;
  size_t nknown;
  int32_t *root_tree;  /* root cube (i, j, k) -> p4est tree */
  long long sent_bytes, largest_message;
} mx_halo;

/* This rank's leaves and ring 1. Not collective. */
int mx_halo_init(const mx_p4est_octree *P, mx_halo *H);
/* Adds ring H->rings + 1. Collective. */
int mx_halo_expand(const mx_p4est_octree *P, mx_halo *H);
void mx_halo_free(mx_halo *H);

#endif
