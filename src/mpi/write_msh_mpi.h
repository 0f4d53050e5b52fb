/* One Gmsh MSH 4.1 file (binary) from a mesh distributed over MPI ranks
 * (issue 14: `mpirun -n N mixoct ... --p4est`), written with MPI-IO so a
 * solver reads one file whatever the number of ranks. The bytes are those
 * src/io/write_msh.c writes for a plain binary mesh without boundary tags
 * and without cell fields (no $ElementData), given a view whose nodes are
 * in global-id order and whose cells are grouped by type (tetrahedra,
 * pyramids, prisms, hexahedra), each type rank 0's cells then rank 1's ...
 * in local order: element tags run 1..N through the file. With bodies
 * (several materials) a volume entity and physical group per body, the
 * cells grouped by body then type; the boundary and interface faces the
 * single-process writer adds as physical surfaces are not written. */
#ifndef MX_WRITE_MSH_MPI_H
#define MX_WRITE_MSH_MPI_H

#include <mpi.h>
#include <stddef.h>
#include <stdint.h>

/* One rank's part of a distributed mesh. Every node a local cell uses is a
 * local node; nodes on partition boundaries are local on several ranks with
 * the same global id, and owned (written) by exactly one of them. The owned
 * nodes' global ids on rank r are exactly the range [first_owned,
 * first_owned + nowned), ranges rising with the rank (an exclusive scan). */
typedef struct {
  size_t nnodes;           /* local nodes */
  const double *xyz;       /* 3 * nnodes */
  const uint64_t *gid;     /* 0-based global id per local node */
  const uint8_t *owned;    /* 1: this rank owns (writes) the node */
  uint64_t first_owned, nowned, nglobal; /* nglobal: nodes over all ranks */
  size_t ncells;
  const uint8_t *type;     /* MX_TET, MX_PYRAMID, MX_PRISM, MX_HEX (include/mixoct.h) */
  const uint32_t *conn;    /* 8 * ncells local node indices, mixoct's node order (src/soa/mesh.h) */
  /* bodies (several materials), as src/io/write_msh.c writes them: nbodies
   * 0, one volume "domain"; else 1..nbodies (at most 64) volume entities,
   * entity b in the physical group body_physical[b - 1] named
   * body_names[b - 1], cell c in body cell_body[c], the elements in one
   * block per (body, type), bodies in order, each block rank 0's cells then
   * rank 1's ... The same nbodies, numbers and names on every rank. */
  int nbodies;
  const int32_t *cell_body;
  const int32_t *body_physical;
  const char *const *body_names;
} mx_dist_mesh;

/* Collective. Writes a binary MSH 4.1 file, MPI-IO, every rank writing its
 * part at offsets from exclusive scans. MX_OK or MX_EINPUT (message naming
 * the file), the same on every rank; on failure no file is left.
 *
 * The input is checked first (every rank, then agreed): node counts and
 * owned flags against nowned, owned ids a permutation of the rank's range,
 * first_owned against the exclusive scan of nowned, nglobal against its
 * sum, ids below nglobal, types, connectivity below nnodes (< 2^32 local
 * nodes). The file goes to "<path>.tmp.<pid of rank 0>" (".<k>" appended if
 * taken) in the directory of path, created by rank 0, and rank 0 renames it
 * once every rank has written, synced and closed it; a symbolic link is
 * written through, an existing non-regular file (/dev/null) in place.
 * Messages come from rank 0 only, naming the lowest failing rank's first
 * problem. */
int mx_write_msh_mpi(const char *path, MPI_Comm comm, const mx_dist_mesh *D);

/* Bytes per rank per write call (default 16 MiB; at least one record per
 * call): memory stays bounded whatever the mesh size. Tests set it small so
 * the parts cross many chunks. */
extern size_t mx_write_msh_mpi_chunk;

#endif
