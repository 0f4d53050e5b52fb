/* The distributed octree (issue 14): the single-process mesher's requests
 * refining a p4est forest, one rank per part of the Morton curve.
 *
 * mx_p4est_build       brick connectivity = our root grid; roots
 *                      classified as mx_build_roots does; refinement level
 *                      by level (p8est_refine_ext, not recursive), the
 *                      children of each split classified in parallel
 *                      beforehand into a side table, as
 *                      mx_split_octants does (each child tests only its
 *                      parent's triangles, CSR slices in a pool of this
 *                      rank); 2:1 balance with P8EST_CONNECT_EDGE (faces and
 *                      edges, the rule of our Algorithm 1), the children of
 *                      each balance split classified in the replace
 *                      callback; partition along the Morton curve weighted
 *                      by the elements expected per quadrant, the triangle
 *                      lists travelling with their quadrants; the ghost
 *                      layer (P8EST_CONNECT_FULL) with the ghosts' data.
 *
 * p4est has no holes: quadrants outside the domain stay in the forest,
 * flagged neither MX_PQ_SURFACE nor MX_PQ_INSIDE, never split by a request
 * (only by the balance), and left out of the leaves reported
 * (p4est_leaves.c). The single-process octree drops them, so the balance
 * there never reaches across them: see p4est_compare.h for what that
 * changes.
 *
 * Files: p4est_classify.c (children of one split), p4est_refine.c (forest,
 * roots, refinement), p4est_balance.c, p4est_partition.c (partition, lists,
 * ghost), p4est_leaves.c (inside leaves, hash, per-rank figures),
 * p4est_compare.c (against the single-process leaves), p4est_inputs.c (the
 * builder from the mesher's inputs); the mesh on the forest: p4est_mesh.h
 * (p4est_mesh.c each rank's patch, p4est_halo.c the rings of other ranks'
 * leaves, p4est_nodes.c the shared nodes, p4est_output.c the files,
 * exchange.c the all-to-all),
 * write_msh_mpi.h (one Gmsh file from every rank); the run behind
 * mx_p4est_run (include/mixoct.h): p4est_run.h. Every function taking the
 * forest is collective over its communicator unless said otherwise. */
#ifndef MX_P4EST_OCTREE_H
#define MX_P4EST_OCTREE_H

#include <stddef.h>
#include <stdint.h>

#include <mpi.h>
#include <p8est.h>
#include <p8est_ghost.h>

#include "kernels/refine.h"

/* The data of one quadrant (p4est's user data, moved by the partition). */
typedef struct {
  uint64_t tri_off; /* its triangles: pool[tri_off, tri_off + tri_cnt) */
  uint32_t tri_cnt;
  uint8_t flags;    /* MX_PQ_* */
  uint8_t target;   /* level the requests ask for (kept quadrants) */
  uint8_t rmeet;    /* bit r: meets region surface r */
  uint8_t rin;      /* bit r: inside region surface r, meets none of it */
} mx_pq;

enum {
  MX_PQ_SURFACE = 1, /* meets a triangle of the domain surface */
  MX_PQ_INSIDE = 2,  /* inside the domain, meets none of its triangles */
};
/* In the domain (the single-process octree would store it). */
static inline int mx_pq_kept(const mx_pq *d) {
  return (d->flags & (MX_PQ_SURFACE | MX_PQ_INSIDE)) != 0;
}

typedef struct {
  /* Partition during the refinement, after a level, once the forest has at
   * least this many quadrants per rank (0: only after the balance). */
  long repartition_min;
  /* Partition weights: elements expected from a leaf (outside: none). */
  int weight_outside, weight_inside, weight_surface;
} mx_p4est_params;

void mx_p4est_params_default(mx_p4est_params *p);

typedef struct {
  double refine;    /* refinement (classification, p8est_refine_ext) */
  double balance;   /* p8est_balance_ext with the replace callback */
  double partition; /* every partition and the lists' transfer */
  double ghost;     /* ghost layer and the ghosts' data */
} mx_p4est_times;

typedef struct {
  MPI_Comm comm;
  int rank, size;
  const mx_builder *B;     /* grid, triangles, locators, requests */
  mx_p4est_params par;
  p8est_connectivity_t *conn;
  p8est_t *p8;
  p8est_ghost_t *ghost;
  mx_pq *ghost_data;       /* one per ghost (their tri_off: the owner's) */
  int32_t *tree_root;      /* per tree: the root cube (i, j, k) */
  /* this rank's triangle lists */
  uint32_t *pool;
  size_t pool_n, pool_cap;
  /* scratch of the replace callbacks and the level loop */
  uint8_t *mask;
  size_t mask_cap;
  void *side;              /* refine.c: the side table of one level */
  int level;               /* the level being refined */
  int max_level;           /* the deepest level asked */
  /* figures, this rank */
  mx_p4est_times t;
  size_t split_requested, split_balance, located, partitions;
  long long shipped;       /* quadrants moved by the partitions (global) */
  long long shipped_bytes; /* triangle-list bytes this rank sent */
  int status;              /* set by a callback that failed */
} mx_p4est_octree;

/* Builds the balanced, partitioned forest with its ghost layer. B: set up by
 * mx_builder_init (grid, triangles, locators, requests; no octree needed),
 * the same on every rank. MX_OK or an error (message given), the same on
 * every rank. */
int mx_p4est_build(mx_p4est_octree *P, const mx_builder *B, MPI_Comm comm,
                   const mx_p4est_params *par);
void mx_p4est_free(mx_p4est_octree *P);

/* The steps of mx_p4est_build, in order. */
int mx_p4est_new_forest(mx_p4est_octree *P);   /* p4est_refine.c */
int mx_p4est_refine(mx_p4est_octree *P);       /* p4est_refine.c */
int mx_p4est_balance(mx_p4est_octree *P);      /* p4est_balance.c */
/* weights: 0 for the refinement's (expected descendants), 1 for the mesh's
 * (expected elements). p4est_partition.c */
int mx_p4est_partition(mx_p4est_octree *P, int mesh_weights);
int mx_p4est_ghost(mx_p4est_octree *P);        /* p4est_partition.c */

/* Repair (as the single-process mx_repair): the leaves in the domain whose
 * keys are listed (sorted; each rank lists its own) split once, then the
 * balance, partition and ghost layer again. *nsplit: leaves split over all
 * ranks (0: nothing changed). p4est_refine.c */
int mx_p4est_refine_listed(mx_p4est_octree *P, const uint64_t *keys, size_t n,
                           long long *nsplit);

/* Room for n more pooled triangle ids (not collective). */
int mx_p4est_pool_reserve(mx_p4est_octree *P, size_t n);
int mx_p4est_mask_reserve(mx_p4est_octree *P, size_t n);

/* Morton key of a quadrant on our finest lattice, root offset included
 * (src/base/morton.h), from its tree's root cube and its coordinates. */
static inline uint64_t mx_p4est_key(const mx_p4est_octree *P, p4est_topidx_t t,
                                    const p8est_quadrant_t *q) {
  const int32_t *r = P->tree_root + 3 * (size_t)t;
  const int sh = P8EST_MAXLEVEL - MX_MAX_LEVEL;
  return mx_morton_encode(((uint32_t)r[0] << MX_MAX_LEVEL) | ((uint32_t)q->x >> sh),
                          ((uint32_t)r[1] << MX_MAX_LEVEL) | ((uint32_t)q->y >> sh),
                          ((uint32_t)r[2] << MX_MAX_LEVEL) | ((uint32_t)q->z >> sh));
}

/* ---- the children of one split (p4est_classify.c) ---------------------- */

/* What the classification of one quadrant's 8 children found: their data
 * (tri_off not set yet) and how many ray-parity queries it took. */
typedef struct {
  mx_pq child[8];
  uint32_t located;
} mx_pq_family;

/* Classifies the children of the quadrant (key, level) with data d and
 * triangles tris[0, d->tri_cnt): mask[i] gets the children that triangle i
 * meets. The same tests, in the same order, as the single-process split
 * (kernels/refine.c), so a child is kept, met and located identically.
 * Not collective; thread-safe. */
void mx_pq_classify(const mx_builder *B, uint64_t key, int level, const mx_pq *d,
                    const uint32_t *tris, uint8_t *mask, mx_pq_family *f);
/* Triangles of the kept children, in total. */
uint64_t mx_pq_family_tris(const mx_pq_family *f);
/* Writes the kept children's triangle lists at out (in child order, each in
 * its parent's order) and sets their tri_off from base (the pool offset of
 * out). */
void mx_pq_fill(mx_pq_family *f, const uint32_t *tris, uint32_t ntris, const uint8_t *mask,
                uint32_t *out, uint64_t base);

#endif
