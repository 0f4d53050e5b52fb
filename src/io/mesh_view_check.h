/* The check of a mesh view before it is written (src/io/mesh_view_check.c). */
#ifndef MX_MESH_VIEW_CHECK_H
#define MX_MESH_VIEW_CHECK_H

#include "soa/mesh.h"

/* Shared by the mesh writers: checks that a mesh view is consistent (types
 * in range, node indices < nnodes, arrays and field values present; a 2D
 * view, soa/mesh.h, with its own types and 4 nodes per row). Prints
 * a message naming path and returns MX_EINTERNAL otherwise. */
int mx_mesh_view_check(const char *path, const mx_mesh_view *m);

#endif
