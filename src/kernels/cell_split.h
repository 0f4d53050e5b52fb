/* Elements split so that chosen quadrilateral faces become two triangles
 * (issue 29: a ridge that crosses a boundary quadrilateral along its
 * diagonal keeps it on element edges).
 *
 * An element with split faces becomes the cones from a new node at the
 * mean of its nodes over each of its faces: a tetrahedron over a triangle,
 * a pyramid over a quadrilateral kept whole, two tetrahedra over a split
 * one, the new node then moved to where the cones' least J_ENS is highest
 * (mx_mesh_best_point). A pyramid whose base alone is split needs no new
 * node: its apex is the cones' apex (two tetrahedra). The faces the element shares with its
 * neighbours are kept, so the mesh stays conforming. The new node is
 * inside (MX_NODE_INSIDE, off the lattice); the first cone takes the
 * element's place, the others are appended in the order of the requests,
 * with the element's leaf and level; J_ENS computed. Serial and in request
 * order: deterministic. */
#ifndef MX_CELL_SPLIT_H
#define MX_CELL_SPLIT_H

#include <stddef.h>
#include <stdint.h>

#include "soa/mesh.h"

/* A request: element << 8 | local face (mx_cell_faces) << 1 | diagonal
 * (0: the face's nodes 0 and 2, 1: nodes 1 and 3). */
static inline uint64_t mx_split_request(size_t cell, int face, int diagonal) {
  return (uint64_t)cell << 8 | (uint64_t)face << 1 | (uint64_t)(diagonal & 1);
}

/* What a split replaced, to undo it: the element (its index, type and
 * nodes), where its other cones went and its apex. */
typedef struct {
  uint32_t cell, first, apex; /* cones: cell, then first .. first + cones - 2 */
  uint8_t type, cones;
  uint32_t conn[8];
} mx_split_undo;

typedef struct {
  size_t n;
  mx_split_undo *job;
  size_t nodes_before; /* the mesh's nodes before the first split logged */
} mx_split_log;

/* req: n requests, sorted, of quadrilateral faces (one per face); *states
 * (one byte a node) grows with the nodes. *centres: new nodes (may be
 * NULL); log (may be NULL): the splits, appended (free with
 * mx_split_log_free). MX_OK, MX_ENOMEM, MX_EINPUT (a request for a
 * triangle or out of range). */
int mx_mesh_split_quads(mx_mesh *M, uint8_t **states, const uint64_t *req, size_t n,
                        size_t *centres, mx_split_log *log);

/* The splits of log with undo[i] != 0 undone, when they are the last ones
 * made (their cones and new nodes the mesh's last): each element back in
 * its first cone's place, the other cones and the new nodes dropped
 * (elements and nodes before them keep their indices); *states follows.
 * The log is emptied. MX_OK, MX_ENOMEM. */
int mx_mesh_unsplit(mx_mesh *M, uint8_t **states, mx_split_log *log, const uint8_t *undo);
void mx_split_log_free(mx_split_log *log);

/* Node v moved to where the least J_ENS of the elements cells[0 .. n)
 * (those having v as a node) is highest, from where it is: a compass
 * search, steps from a quarter of the elements' extent halved 12 times; their
 * J_ENS updated (M->jens). Used for the new node of a split (the mean of a
 * flattened boundary element's nodes is close to its flat side) and again
 * when nodes around it move. */
void mx_mesh_best_point(mx_mesh *M, uint32_t v, const uint32_t *cells, size_t n);

#endif
