/* `mpirun -n N mixoct -i SURF -s L --p4est [-o OUT.pvtu|OUT.msh] [--json]`:
 * the mesh part (src/mpi/p4est_mesh.h): each rank meshes its leaves, the
 * verdict over all ranks (exit 0 only for a valid mesh), the outputs, and
 * the report (rank 0: global counts, per-rank min/max). */
#include "cli/p4est_cli.h"

#include "common.h"
#include "io/pvtu.h"
#include "mesher/mesher_impl.h"
#include "mpi/exchange.h"
#include "mpi/write_msh_mpi.h"
#include "soa/mesh.h"

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

/* Exit 0 only for a mesh with no element left with J_ENS < 1e-6, no node
 * lying on an element it is not a node of, holding the input's volume. */
static int verdict(mx_mesher *m, const mx_p4est_mesh *D) {
  if (D->cells == 0) {
    mx_error(m->ndomain ? m->domain_name[0] : NULL, 0,
             "the mesh is empty: no element lies in the domain (%" PRIu64 " leaves); ask for "
             "finer levels (-s, -a, -b, -r)", D->leaves);
    return MX_EINPUT;
  }
  if (D->invalid) {
    mx_error(NULL, 0, "%" PRIu64 " element(s) with J_ENS < 1e-6 remain after %d repair "
             "round(s)", D->invalid, D->repair_rounds);
    return MX_EINVALID;
  }
  if (D->contact_cells) {
    mx_error(NULL, 0, "%" PRIu64 " element(s) where two parts of the boundary meet (a node "
             "on an element it is not a node of: a non-conforming mesh) after %d repair "
             "round(s); ask for finer levels there (-s, -b, -r)", D->contact_cells,
             D->repair_rounds);
    return MX_EINVALID;
  }
  return mx_volume_verdict(m, D->volume, (size_t)D->cells);
}

/* This rank's elements as the writers and the hash take them. */
static mx_mesh_view rank_view(const mx_mesh_out *M) {
  mx_mesh_view v;
  memset(&v, 0, sizeof v);
  v.nnodes = M->nnodes;
  v.xyz = M->xyz;
  v.ncells = M->ncells;
  v.type = M->type;
  v.conn = M->conn;
  return v;
}

static int write_outputs(const mx_options *o, const mx_p4est_octree *P, const mx_p4est_mesh *D) {
  const mx_mesh_out *M = &D->M;
  mx_mesh_view v = rank_view(M);
  const mx_field cf[2] = {{.name = "level", .u8values = M->level},
                          {.name = "jens", .is_double = 1, .fvalues = M->jens}};
  v.ncell_fields = 2;
  v.cell_fields = cf;
  int st = MX_OK;
  for (int k = 0; k < o->noutputs && !st; k++) {
    const char *path = o->outputs[k];
    const size_t n = strlen(path);
    if (n > 5 && strcmp(path + n - 5, ".pvtu") == 0) {
      char piece[4096];
      mx_pvtu_piece_path(path, P->rank, piece, sizeof piece);
      const int mine = mx_write_vtu_piece(piece, &v, D->gid);
      st = mx_mpi_agree(P->comm, mine);
      /* messages are printed by rank 0: name the first rank that failed */
      int who = mine ? P->rank : P->size, first = who;
      MPI_Allreduce(&who, &first, 1, MPI_INT, MPI_MIN, P->comm);
      if (first > 0 && first < P->size) {
        char other[4096];
        mx_pvtu_piece_path(path, first, other, sizeof other);
        mx_error(other, 0, "rank %d could not write its piece (see its file system)", first);
      }
      if (!st && P->rank == 0) st = mx_write_pvtu_master(path, P->size, &v, 1);
      st = mx_mpi_agree(P->comm, st);
      /* all pieces and the master, or nothing */
      if (st && !mine) remove(piece);
    } else {
      mx_dist_mesh dm;
      memset(&dm, 0, sizeof dm);
      dm.nnodes = M->nnodes;
      dm.xyz = M->xyz;
      dm.gid = D->gid;
      dm.owned = D->owned;
      dm.first_owned = D->first_owned;
      dm.nowned = D->nowned;
      dm.nglobal = D->nodes;
      dm.ncells = M->ncells;
      dm.type = M->type;
      dm.conn = M->conn;
      st = mx_write_msh_mpi(path, P->comm, &dm);
    }
  }
  return st;
}

int mx_p4est_check_outputs(const mx_options *o) {
  for (int k = 0; k < o->noutputs; k++) {
    const char *path = o->outputs[k];
    const size_t n = strlen(path);
    const int pvtu = n > 5 && strcmp(path + n - 5, ".pvtu") == 0;
    const int msh = n > 4 && strcmp(path + n - 4, ".msh") == 0;
    if (!pvtu && !msh) {
      mx_error(path, 0, "with --p4est the mesh is written as a parallel VTU (.pvtu, one "
                        "piece per rank) or one binary Gmsh file (.msh, MPI-IO)");
      return MX_EINPUT;
    }
    if (msh && o->ascii) {
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
  if (!st) {
    /* the hash `mixoct check` computes from a file, over every rank's
     * elements */
    const mx_mesh_view v = rank_view(&D->M);
    uint64_t sum = mx_mesh_hash_sum(&v), all = 0;
    MPI_Allreduce(&sum, &all, 1, MPI_UINT64_T, MPI_SUM, P->comm);
    rep->hash = mx_mesh_hash_finish(all, D->cells);
  }
  if (!st) st = mx_mpi_agree(P->comm, verdict(m, D));
  const double t2 = mx_wtime();
  if (!st) st = write_outputs(o, P, D);
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
