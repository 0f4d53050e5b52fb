/* The distributed mesh written (src/mpi/p4est_mesh.h): a .pvtu with one
 * piece per rank, or one binary .msh written by every rank with MPI-IO; and
 * its hash over every rank's elements. */
#include "mpi/p4est_mesh.h"

#include "base/common.h"
#include "io/pvtu.h"
#include "mpi/exchange.h"
#include "mpi/write_msh_mpi.h"
#include "soa/mesh.h"

#include <stdio.h>
#include <string.h>

/* This rank's elements as the writers and the hash take them. */
static mx_mesh_view rank_view(const mx_mesh *M) {
  mx_mesh_view v;
  memset(&v, 0, sizeof v);
  v.nnodes = M->nnodes;
  v.xyz = M->xyz;
  v.ncells = M->ncells;
  v.type = M->type;
  v.conn = M->conn;
  return v;
}

uint64_t mx_p4est_mesh_hash(const mx_p4est_octree *P, const mx_p4est_mesh *D) {
  const mx_mesh_view v = rank_view(&D->M);
  uint64_t sum = mx_mesh_hash_sum(&v), all = 0;
  MPI_Allreduce(&sum, &all, 1, MPI_UINT64_T, MPI_SUM, P->comm);
  return mx_mesh_hash_finish(all, D->cells);
}

/* Every rank its piece, rank 0 the master: all of them or nothing. */
static int write_pvtu(const mx_p4est_octree *P, const mx_p4est_mesh *D, const char *path) {
  const mx_mesh *M = &D->M;
  mx_mesh_view v = rank_view(M);
  /* with several materials the field `material` (int32, as the
   * single-process .vtu writes it) */
  int32_t *mat = NULL;
  if (M->material) {
    mat = mx_alloc((M->ncells + 1) * sizeof *mat);
    for (size_t c = 0; mat && c < M->ncells; c++) mat[c] = M->material[c];
  }
  const mx_field cf[3] = {{.name = "level", .u8values = M->level},
                          {.name = "jens", .is_double = 1, .fvalues = M->jens},
                          {.name = "material", .ivalues = mat}};
  v.ncell_fields = mat ? 3 : 2;
  v.cell_fields = cf;
  char piece[4096];
  mx_pvtu_piece_path(path, P->rank, piece, sizeof piece);
  const int mine = M->material && !mat ? MX_ENOMEM : mx_write_vtu_piece(piece, &v, D->gid);
  int st = mx_mpi_agree(P->comm, mine);
  /* messages are printed by rank 0: name the first rank that failed */
  int who = mine ? P->rank : P->size, first = who;
  MPI_Allreduce(&who, &first, 1, MPI_INT, MPI_MIN, P->comm);
  if (first > 0 && first < P->size) {
    char other[4096];
    mx_pvtu_piece_path(path, first, other, sizeof other);
    mx_error(other, 0, "rank %d could not write its piece (see its file system)", first);
  }
  if (!st && P->rank == 0) st = mx_write_pvtu_master(path, P->size, &v, 1);
  mx_free(mat);
  st = mx_mpi_agree(P->comm, st);
  if (st && !mine) remove(piece);
  return st;
}

static int write_msh(const mx_p4est_octree *P, const mx_p4est_mesh *D, const char *path) {
  const mx_mesh *M = &D->M;
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
  /* several materials: a body per material, numbered and named as the
   * single-process .msh numbers and names them (mesher/output.c: the
   * body of a material is its region, 1 .. nmaterials) */
  int32_t *body = NULL, phys[64];
  const char *names[64];
  int st = MX_OK;
  if (M->material && D->nmaterials >= 1 && D->nmaterials <= 64) {
    body = mx_alloc((M->ncells + 1) * sizeof *body);
    if (!body) st = MX_ENOMEM;
    for (size_t c = 0; body && c < M->ncells; c++) {
      int b = 1;
      for (int d = 1; d <= D->nmaterials; d++)
        if (D->material_id[d] == M->material[c]) b = d;
      body[c] = b;
    }
    for (int d = 1; d <= D->nmaterials; d++) {
      phys[d - 1] = D->material_id[d];
      names[d - 1] = D->material_name[d];
    }
    dm.nbodies = D->nmaterials;
    dm.cell_body = body;
    dm.body_physical = phys;
    dm.body_names = names;
  }
  st = mx_mpi_agree(P->comm, st);
  if (!st) st = mx_write_msh_mpi(path, P->comm, &dm);
  mx_free(body);
  return st;
}

int mx_p4est_output_kind(const char *path) {
  const size_t n = strlen(path);
  if (n > 5 && strcmp(path + n - 5, ".pvtu") == 0) return 1;
  if (n > 4 && strcmp(path + n - 4, ".msh") == 0) return 2;
  return 0;
}

int mx_p4est_mesh_write(const mx_p4est_octree *P, const mx_p4est_mesh *D, const char *path) {
  switch (mx_p4est_output_kind(path)) {
    case 1: return write_pvtu(P, D, path);
    case 2: return write_msh(P, D, path);
    default:
      mx_error(path, 0, "the distributed mesh is written as .pvtu or .msh");
      return MX_EINPUT;
  }
}
