/* The mesh step of a distributed run (mx_p4est_run): the outputs checked
 * before anything is built, then the library calls of src/mpi/p4est_mesh.h
 * in order (each rank meshes its leaves, the verdict over all ranks, the
 * outputs), and the per-rank figures reduced over the ranks for the
 * report. */
#include "mpi/p4est_run.h"

#include <string.h>

/* min and max of v over the ranks */
static void minmax(MPI_Comm comm, double v, double out[2]) {
  double a[2] = {v, -v}, b[2];
  MPI_Allreduce(a, b, 2, MPI_DOUBLE, MPI_MAX, comm);
  out[0] = -b[1];
  out[1] = b[0];
}

int mx_p4est_check_outputs(const mx_p4est_run_params *p) {
  for (int k = 0; k < p->noutputs; k++) {
    const char *path = p->outputs[k];
    const int kind = mx_p4est_output_kind(path);
    if (!kind) {
      mx_error(path, 0, "with --p4est the mesh is written as a parallel VTU (.pvtu, one "
                        "piece per rank) or one binary Gmsh file (.msh, MPI-IO)");
      return MX_EINPUT;
    }
    if (kind == 2 && p->ascii) {
      mx_error(path, 0, "with --p4est the .msh file is binary (--ascii is not offered)");
      return MX_EINPUT;
    }
  }
  return MX_OK;
}

int mx_p4est_mesh_run(const mx_p4est_run_params *p, mx_p4est_octree *P, mx_mesher *m,
                      double t0, mx_p4est_mesh_report *rep) {
  mx_p4est_mesh *D = &rep->D;
  memset(D, 0, sizeof *D);
  const double t1 = mx_wtime();
  int st = mx_p4est_mesh_build(P, m, D);
  rep->t_mesh = mx_wtime() - t1;
  if (!st) rep->hash = mx_p4est_mesh_hash(P, D);
  if (!st) st = mx_p4est_mesh_verdict(P, m, D);
  const double t2 = mx_wtime();
  for (int k = 0; k < p->noutputs && !st; k++) st = mx_p4est_mesh_write(P, D, p->outputs[k]);
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
