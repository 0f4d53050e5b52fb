/* The leaves of the distributed octree that lie in the domain (kept: they
 * meet the surface or lie inside), their fingerprint, and the per-rank
 * figures of a run. */
#ifndef MX_P4EST_LEAVES_H
#define MX_P4EST_LEAVES_H

#include "mpi/p4est_octree.h"

typedef struct {
  /* global */
  long long leaves;       /* leaves in the domain */
  long long quadrants;    /* every leaf of the forest, outside ones included */
  long long outside;      /* quadrants - leaves */
  long long surface;      /* leaves meeting the surface */
  long long per_level[MX_MAX_LEVEL + 1]; /* leaves in the domain per level */
  uint64_t hash;          /* as mx_leaves_hash over the same (key, level) set */
  long long ghosts;       /* ghost quadrants, summed over ranks */
  long long split_requested, split_balance, located;
  long long list_bytes;   /* triangle-list bytes the partitions sent */
  /* per rank */
  long long leaves_min, leaves_max, quadrants_min, quadrants_max;
  double rss_min_mb, rss_max_mb;
  mx_p4est_times tmax, tmin; /* seconds per step over the ranks */
} mx_p4est_summary;

/* Collective; every rank gets the summary. */
int mx_p4est_summarize(const mx_p4est_octree *P, mx_p4est_summary *s);

/* The leaves in the domain (all_quadrants: every leaf of the forest, and
 * *kept says which are in the domain; else kept may be NULL), gathered on
 * rank `root` sorted by key (Morton order): arrays allocated with mx_alloc
 * there, NULL elsewhere. Collective. */
int mx_p4est_gather_leaves(const mx_p4est_octree *P, int root, int all_quadrants,
                           uint64_t **keys, uint8_t **levels, uint8_t **kept, size_t *n);

/* The set hash of mx_leaves_hash: the sum over the leaves of
 * mix(mix(key) ^ level), finished with mix(sum ^ n). */
uint64_t mx_p4est_leaf_mix(uint64_t key, int level);
uint64_t mx_p4est_hash_finish(uint64_t sum, uint64_t n);

#endif
