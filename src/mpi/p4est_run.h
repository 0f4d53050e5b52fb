/* The distributed path's run (include/mixoct.h: mx_p4est_run), in three
 * files: p4est_run.c sets up MPI and the mesher and chains the steps (the
 * octree, the comparison with the single-process octree, the mesh),
 * p4est_run_mesh.c meshes, checks and writes and reduces the per-rank
 * figures, p4est_run_report.c prints rank 0's report (text or JSON). */
#ifndef MX_P4EST_RUN_H
#define MX_P4EST_RUN_H

#include "mixoct.h"
#include "mpi/p4est_compare.h"
#include "mpi/p4est_leaves.h"
#include "mpi/p4est_mesh.h"

/* Rank 0's single-process octree of the same inputs against p4est's
 * (--p4est-compare). */
typedef struct {
  int compared;
  mx_leaf_diff d;          /* A: p4est's leaves in the domain, B: the single-process ones */
  mx_split_causes why;     /* why p4est split the single-process leaves it split */
  uint64_t hash;           /* mx_leaves_hash of the single-process leaves */
  double t_refine, t_balance; /* its seconds */
} mx_p4est_single;

typedef struct {
  mx_p4est_mesh D;
  uint64_t hash;   /* the mesh hash over every rank's elements (io/mesh_hash.h) */
  double t_mesh, t_write, t_total; /* this rank */
  /* reduced over the ranks by mx_p4est_mesh_reduce: [min, max] per rank */
  double leaves[2], cells[2], nodes[2], patch[2], sec[2], rss[2], shared[2], estimate[2];
  double phmax[7]; /* halo, tree, transition, boundary, exchange, mesh, write */
  long long sent_bytes, largest_message; /* sum, max */
} mx_p4est_mesh_report;

/* The outputs name only .pvtu or .msh (binary, so no ascii). Not
 * collective. */
int mx_p4est_check_outputs(const mx_p4est_run_params *p);
/* Meshes, checks, writes p's outputs. t0: when the run started (for
 * t_total). Collective; the same status on every rank. */
int mx_p4est_mesh_run(const mx_p4est_run_params *p, mx_p4est_octree *P, mx_mesher *m,
                      double t0, mx_p4est_mesh_report *rep);
/* The per-rank figures reduced over the ranks (collective). */
void mx_p4est_mesh_reduce(const mx_p4est_octree *P, mx_p4est_mesh_report *rep);

/* Rank 0's report on stdout: the octree (s), the comparison when made, the
 * mesh when built (NULL: --stage octree); text lines, or one JSON line with
 * p->json. t_setup, t_total: the slowest rank's seconds. */
void mx_p4est_report(const mx_p4est_run_params *p, const mx_p4est_octree *P,
                     const mx_p4est_summary *s, double t_setup, double t_total, int threads,
                     const mx_p4est_single *c, const mx_p4est_mesh_report *mesh);

#endif
