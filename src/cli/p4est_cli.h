/* The distributed path's command (src/cli/p4est_cmd.c: octree and report;
 * src/cli/p4est_mesh_cmd.c: mesh, verdict, outputs). MPI builds only. */
#ifndef MX_P4EST_CLI_H
#define MX_P4EST_CLI_H

#include "cli/cli.h"
#include "mpi/p4est_mesh.h"

typedef struct {
  mx_p4est_mesh D;
  uint64_t hash;   /* the mesh hash over every rank's elements (io/mesh_hash.h) */
  double t_mesh, t_write, t_total; /* this rank */
  /* reduced over the ranks by mx_p4est_mesh_reduce: [min, max] per rank */
  double leaves[2], cells[2], nodes[2], patch[2], sec[2], rss[2], shared[2], estimate[2];
  double phmax[7]; /* halo, tree, transition, boundary, exchange, mesh, write */
  long long sent_bytes, largest_message; /* sum, max */
} mx_p4est_mesh_report;

/* -o names only .pvtu or .msh (binary). Not collective. */
int mx_p4est_check_outputs(const mx_options *o);
/* Meshes, checks, writes. t0: when the run started (for t_total).
 * Collective; the same status on every rank. */
int mx_p4est_mesh_run(const mx_options *o, mx_p4est_octree *P, mx_mesher *m, double t0,
                      mx_p4est_mesh_report *rep);
/* The per-rank figures reduced (collective), then the "mesh" member of the
 * JSON report or the text lines (rank 0). */
void mx_p4est_mesh_reduce(const mx_p4est_octree *P, mx_p4est_mesh_report *rep);
void mx_p4est_mesh_json(const mx_p4est_mesh_report *rep);
void mx_p4est_mesh_text(const mx_p4est_mesh_report *rep);

#endif
