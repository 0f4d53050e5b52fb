/* The order cells are written in (src/io/cell_order.c). */
#ifndef MX_CELL_ORDER_H
#define MX_CELL_ORDER_H

#include <stddef.h>
#include <stdint.h>

#include "soa/mesh.h"

/* Bodies: the parts of the mesh connected through nodes, numbered 1.. by
 * their smallest node (cell_body: ncells values). mx_cells_in_order: the cells grouped by body
 * (body NULL: one), then by type (tetrahedra, pyramids, prisms,
 * hexahedra), in index order within a group. mx_cells_by_type: by type
 * alone, first (may be NULL) receiving where each type starts, first[4] =
 * n. mx_cells_written_order: the bodies, then mx_cells_in_order, the order
 * every mesh file of mixoct lists its cells in. MX_OK or MX_ENOMEM. */
int mx_cell_bodies(const mx_mesh_view *v, int32_t *cell_body, int *nbodies);
int mx_cells_in_order(const uint8_t *type, const int32_t *body, int nbodies, size_t n,
                      uint32_t *order);
int mx_cells_by_type(const uint8_t *type, size_t n, uint32_t *order, size_t first[5]);
int mx_cells_written_order(const mx_mesh_view *v, uint32_t *order);

#endif
