/* Parallel VTU output (issue 14: one piece per MPI rank) and the mesh hash
 * that does not depend on how the mesh was cut into pieces.
 *
 * A parallel mesh "DIR/BASE.pvtu" is a master file naming its pieces
 * "BASE_0.vtu", "BASE_1.vtu", ... in DIR (mx_pvtu_piece_path). Each rank
 * writes its piece with mx_write_vtu_piece: its cells, the nodes they use
 * with a local numbering, and the point array GlobalNodeId (Int64, the
 * node's 0-based number in the whole mesh; a node on a piece boundary
 * appears in every piece using it, with the same id). One rank writes the
 * master with mx_write_pvtu_master. Every file appears whole or not at all
 * (io/atomic_file.h). mx_read_mesh (io/read_mesh.h) reads the .pvtu back
 * as one mesh, which is what `mixoct check X.pvtu` checks.
 *
 * Field types: a piece writes its fields as mx_write_vtu does, except that
 * an int32 field is always Int32 (mx_write_vtu narrows one whose values
 * fit to UInt8, and the values differ between pieces): Float64 for double
 * fields, UInt8 for 8-bit ones, Int32 for the others, the same in every
 * piece and in the master, which VTK's reader requires. */
#ifndef MX_PVTU_H
#define MX_PVTU_H

#include <stddef.h>
#include <stdint.h>

#include "soa/mesh.h"

/* mx_pvtu_piece_path (mixoct.h): the file of piece `piece` of pvtu_path,
 * "DIR/BASE_<piece>.vtu" for "DIR/BASE.pvtu" (the extension compared
 * without case; a path not ending in .pvtu gets "_<piece>.vtu" appended);
 * a name that does not fit leaves buf empty (n > 0), so that writing to it
 * fails instead of writing a truncated name. */

/* One piece: the view as mx_write_vtu writes it (fields typed as above),
 * plus, when global_id is not NULL, the point array GlobalNodeId (Int64,
 * v->nnodes values, each below 2^63). MX_OK, or the writers' statuses
 * (io/atomic_file.h; MX_EINTERNAL for an inconsistent view or an id out of
 * range). */
int mx_write_vtu_piece(const char *path, const mx_mesh_view *v, const uint64_t *global_id);

/* The master: a VTK PUnstructuredGrid naming the npieces files
 * mx_pvtu_piece_path gives (relative to the master's directory), declaring
 * the points (Float64, 3 components) and the point and cell arrays of the
 * pieces: v's fields (only their names and kinds are read; v may be any
 * rank's piece, even an empty one) and GlobalNodeId when with_global_id.
 * MX_OK, or the writers' statuses (MX_EINTERNAL for npieces < 1). */
int mx_write_pvtu_master(const char *pvtu_path, int npieces, const mx_mesh_view *v,
                         int with_global_id);

/* The name of the global id point array. */
#define MX_PVTU_GLOBAL_ID "GlobalNodeId"

/* A hash of the mesh as a set of cells, each cell its type and the set of
 * its nodes' coordinates (exact bits, -0.0 as 0.0): the same for any node
 * numbering, cell order, node order within a cell, and unused nodes, so the
 * same for a mesh and for the pieces of it a .pvtu holds once read back
 * (io/mesh_hash.c). Parallel (OpenMP); the result does not depend on the
 * thread count. */
uint64_t mx_mesh_hash(const mx_mesh_view *v);
/* The same in two steps, for a mesh held in parts (the ranks of a
 * distributed mesh): the parts' sums added (modulo 2^64), then finished
 * with the total cell count. */
uint64_t mx_mesh_hash_sum(const mx_mesh_view *v);
uint64_t mx_mesh_hash_finish(uint64_t sum, uint64_t ncells);

#endif
