/* Gmsh MSH element types and node orders of mixoct's cells, shared by the
 * serial writer (src/io/write_msh.c, whose header comment gives the rule:
 * the permutation is the identity for every type, kept as a table so the
 * rule is written in one place) and the MPI-IO writer
 * (src/mpi/write_msh_mpi.c), so both write the same connectivity. */
#ifndef MX_MSH_ORDER_H
#define MX_MSH_ORDER_H

#include <stdint.h>

/* Gmsh element type per mixoct type, and mixoct's node j of Gmsh's node k. */
static const int mx_msh_type[4] = {4, 7, 6, 5};
static const int8_t mx_msh_perm[4][8] = {{0, 1, 2, 3, 0, 0, 0, 0},
                                         {0, 1, 2, 3, 4, 0, 0, 0},
                                         {0, 1, 2, 3, 4, 5, 0, 0},
                                         {0, 1, 2, 3, 4, 5, 6, 7}};

#endif
