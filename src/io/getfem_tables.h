/* GetFEM's conventions for the four linear 3D types, shared by the writer
 * (io/write_getfem.c, which documents where they come from) and the reader
 * (io/read_mesh.c), so each is written once. Indexed by mixoct's type,
 * MX_TET .. MX_HEX. */
#ifndef MX_GETFEM_TABLES_H
#define MX_GETFEM_TABLES_H

#include <stdint.h>

/* GetFEM's geometric transformation of each type, quoted as in its files. */
static const char *const mx_getfem_geotrans[4] = {
    "'GT_PK(3,1)'", "'GT_PYRAMID(1)'", "'GT_PRISM(3,1)'", "'GT_QK(3,1)'"};

/* GetFEM's node k of each type is mixoct's (VTK's) node mx_getfem_node[t][k]
 * (-1: none). Each permutation is its own inverse: mixoct's node k is
 * GetFEM's node mx_getfem_node[t][k] too. */
static const int8_t mx_getfem_node[4][8] = {{0, 1, 2, 3, -1, -1, -1, -1},
                                            {0, 1, 3, 2, 4, -1, -1, -1},
                                            {0, 1, 2, 3, 4, 5, -1, -1},
                                            {0, 1, 3, 2, 4, 5, 7, 6}};

/* GetFEM's face number of mixoct's local face f (soa/mesh.h mx_cell_faces)
 * of each type (-1: none). */
static const int8_t mx_getfem_face[4][6] = {{3, 2, 0, 1, -1, -1},
                                            {0, 1, 2, 3, 4, -1},
                                            {4, 3, 2, 0, 1, -1},
                                            {5, 4, 3, 0, 2, 1}};

/* mixoct's local face of GetFEM's face g of type t (the inverse of
 * mx_getfem_face), or -1 when the type has no such face. */
static inline int mx_getfem_local_face(int t, int64_t g) {
  for (int f = 0; f < 6; f++)
    if (mx_getfem_face[t][f] >= 0 && mx_getfem_face[t][f] == g) return f;
  return -1;
}

#endif
