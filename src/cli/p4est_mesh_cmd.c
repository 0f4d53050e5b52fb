/* `mpirun -n N mixoct -i SURF -s L --p4est [-o OUT.pvtu|OUT.msh] [--json]`:
 * the mesh part: the library calls (src/mpi/p4est_mesh.h: each rank meshes
 * its leaves, the verdict over all ranks, the outputs) in order, and the
 * report (rank 0: global counts, per-rank min/max). */
#include "cli/p4est_cli.h"

#include "base/common.h"

#include <inttypes.h>
#include <stdio.h>
#include <string.h>

/* min and max of v over the ranks */
static void minmax(MPI_Comm comm, double v, double out[2]) {
  double a[2] = {v, -v}, b[2];
  MPI_Allreduce(a, b, 2, MPI_DOUBLE, MPI_MAX, comm);
  out[0] = -b[1];
  out[1] = b[0];
}

int mx_p4est_check_outputs(const mx_options *o) {
  for (int k = 0; k < o->noutputs; k++) {
    const char *path = o->outputs[k];
    const int kind = mx_p4est_output_kind(path);
    if (!kind) {
      mx_error(path, 0, "with --p4est the mesh is written as a parallel VTU (.pvtu, one "
                        "piece per rank) or one binary Gmsh file (.msh, MPI-IO)");
      return MX_EINPUT;
    }
    if (kind == 2 && o->ascii) {
      mx_error(path, 0, "with --p4est the .msh file is binary (--ascii is not offered)");
      return MX_EINPUT;
    }
  }
  return MX_OK;
}

static void print_pair(const char *name, const double *v, int last) {
  printf("\"%s\": [%.6g, %.6g]%s", name, v[0], v[1], last ? "" : ", ");
}

int mx_p4est_mesh_run(const mx_options *o, mx_p4est_octree *P, mx_mesher *m, double t0,
                      mx_p4est_mesh_report *rep) {
  mx_p4est_mesh *D = &rep->D;
  memset(D, 0, sizeof *D);
  const double t1 = mx_wtime();
  int st = mx_p4est_mesh_build(P, m, D);
  rep->t_mesh = mx_wtime() - t1;
  if (!st) rep->hash = mx_p4est_mesh_hash(P, D);
  if (!st) st = mx_p4est_mesh_verdict(P, m, D);
  const double t2 = mx_wtime();
  for (int k = 0; k < o->noutputs && !st; k++) st = mx_p4est_mesh_write(P, D, o->outputs[k]);
  rep->t_write = mx_wtime() - t2;
  rep->t_total = mx_wtime() - t0;
  return st;
}

void mx_p4est_mesh_reduce(const mx_p4est_octree *P, mx_p4est_mesh_report *rep) {
  const mx_p4est_mesh *D = &rep->D;
  MPI_Comm c = P->comm;
  minmax(c, (double)D->core_leaves, rep->leaves);
  minmax(c, (double)D->M.ncells, rep->cells);
  minmax(c, (double)D->M.nnodes, rep->nodes);
  minmax(c, (double)D->patch_leaves, rep->patch);
  minmax(c, rep->t_total, rep->sec);
  minmax(c, mx_peak_rss_mb(), rep->rss);
  minmax(c, (double)D->shared_nodes, rep->shared);
  minmax(c, D->estimate_mb, rep->estimate);
  const double ph[7] = {D->t_halo, D->t_tree,    D->t_transition, D->t_boundary,
                        D->t_exchange, rep->t_mesh, rep->t_write};
  MPI_Allreduce(ph, rep->phmax, 7, MPI_DOUBLE, MPI_MAX, c);
  long long b = D->sent_bytes, big = D->largest_message;
  MPI_Allreduce(&b, &rep->sent_bytes, 1, MPI_LONG_LONG, MPI_SUM, c);
  MPI_Allreduce(&big, &rep->largest_message, 1, MPI_LONG_LONG, MPI_MAX, c);
}

void mx_p4est_mesh_json(const mx_p4est_mesh_report *rep) {
  const mx_p4est_mesh *D = &rep->D;
  const double *phmax = rep->phmax;
  printf("\"mesh\": {\"leaves\": %" PRIu64 ", ", D->leaves);
  printf("\"nodes\": %" PRIu64 ", \"elements\": %" PRIu64 ", \"by_type\": {\"tet\": "
         "%" PRIu64 ", \"pyramid\": %" PRIu64 ", \"prism\": %" PRIu64 ", \"hex\": %" PRIu64
         "}, \"jens_min\": %.6g, \"invalid\": %" PRIu64 ", \"contact_elements\": %" PRIu64
         ", \"volume\": %.17g, \"mesh_hash\": \"%016" PRIx64 "\", \"halo_rings\": %d, "
         "\"attempts\": %d, \"differ_first_attempt\": %" PRIu64 ", \"repair_rounds\": %d, "
         "\"repaired_leaves\": %lld, \"exchanged_bytes\": %lld, "
         "\"largest_message_bytes\": %lld, ",
         D->nodes, D->cells, D->by_type[0], D->by_type[1], D->by_type[2], D->by_type[3],
         D->jens_min, D->invalid, D->contact_cells, D->volume, rep->hash, D->rings,
         D->attempts, D->differ_first, D->repair_rounds, D->repaired, rep->sent_bytes,
         rep->largest_message);
  printf("\"phases_max\": {\"halo\": %.6f, \"tree\": %.6f, \"transition\": %.6f, "
         "\"boundary\": %.6f, \"exchange\": %.6f, \"mesh\": %.6f, \"write\": %.6f}, ",
         phmax[0], phmax[1], phmax[2], phmax[3], phmax[4], phmax[5], phmax[6]);
  printf("\"per_rank\": {");
  print_pair("leaves", rep->leaves, 0);
  print_pair("patch_leaves", rep->patch, 0);
  print_pair("elements", rep->cells, 0);
  print_pair("nodes", rep->nodes, 0);
  print_pair("shared_nodes", rep->shared, 0);
  print_pair("seconds", rep->sec, 0);
  print_pair("memory_estimate_mb", rep->estimate, 0);
  print_pair("peak_rss_mb", rep->rss, 1);
  printf("}}, ");
}

void mx_p4est_mesh_text(const mx_p4est_mesh_report *rep) {
  const mx_p4est_mesh *D = &rep->D;
  printf("  mesh: nodes %" PRIu64 ", elements %" PRIu64 " (tet %" PRIu64 ", pyramid %" PRIu64
         ", prism %" PRIu64 ", hex %" PRIu64 "), J_ENS min %.4f, hash %016" PRIx64 "\n",
         D->nodes, D->cells, D->by_type[0], D->by_type[1], D->by_type[2], D->by_type[3],
         D->jens_min, rep->hash);
  printf("  halo rings %d (attempts %d); slowest rank: mesh %.3f s, write %.3f s; per rank: "
         "elements %.0f..%.0f, peak memory %.1f..%.1f MB\n", D->rings, D->attempts,
         rep->phmax[5], rep->phmax[6], rep->cells[0], rep->cells[1], rep->rss[0],
         rep->rss[1]);
}
