/* Declarations shared by the files of the 2D mesher's steps (src/quad/)
 * and nobody else; the interfaces are in quad.h. */
#ifndef MX_QINTERNAL_H
#define MX_QINTERNAL_H

#include <stddef.h>
#include <stdint.h>

#include "quad/quad.h"

/* ---- the band of the boundary step (qband.c) ------------------------------ */

/* The cells the boundary step (qboundary.c) may change, taken out of the
 * transition mesh M with the nodes they use, as a small mesh L of its own:
 * local ids ascend with the global ones (gcell, gnode), so that every
 * decision the step takes by id is the one it would take on M. Nodes of L
 * marked deep are inside nodes that no step moves (see qband.c). */
typedef struct {
  mx_qmesh L;       /* xy, type, conn (local ids), leaf, level; nkey NULL */
  uint32_t *gnode;  /* per node of L: its id in M */
  uint32_t *gcell;  /* per cell of L: its id in M */
  uint8_t *deep;    /* per node of L: 1 when deep */
  uint8_t *inside;  /* per node of L: 1 when a node of a clear leaf (mx_poly_inside: 1) */
  uint8_t *open;    /* per cell of L: its leaf is not clear (it may hold a feature) */
  uint8_t *act;     /* per cell of M: QBAND_* bits; NULL when the band is the whole mesh */
  size_t m, n;      /* cells and nodes of M */
} mx_qband;

enum { QBAND_OPEN = 1, QBAND_IN = 2 };

/* The band of M: the whole mesh when `whole` (or without the leaves). */
int mx_qband_extract(const mx_poly_index *I, const mx_qtree *T, const uint32_t *leaves, int whole,
                     const mx_qmesh *M, mx_qband *B);
/* Puts the band back into M and compacts it: cell c of L becomes 0 cells
 * (alive[c] == 0), 1, or 2 triangles along the diagonal from corner
 * split[c] - 1 (split[c] > 0); the other cells of M stay, in order; nodes
 * no cell uses go, the others keep their order; a node of L takes its
 * position in L, and loses its lattice key when (nf[v] & moved). */
int mx_qband_merge(mx_qband *B, const uint8_t *alive, const uint8_t *split, const uint8_t *nf,
                   uint8_t moved, mx_qmesh *M);
void mx_qband_free(mx_qband *B);

#endif
