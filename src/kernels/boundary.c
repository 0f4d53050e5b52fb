#include "kernels/boundary.h"

#include "common.h"
#include "soa/mesh.h"

int mx_node_states(const mx_builder *B, const uint32_t *leaves,
                   const mx_mesh_out *M, const mx_surface_index *S,
                   uint8_t *states, size_t *queries) {
  const mx_octree *T = &B->oct;
  enum { UNKNOWN = 2 };
#pragma omp parallel for schedule(static)
  for (size_t v = 0; v < M->nnodes; v++) states[v] = UNKNOWN;
  /* Elements of leaves that meet no domain triangle: all nodes inside. Two
   * threads may write the same value to a shared node: benign. */
#pragma omp parallel for schedule(static)
  for (size_t c = 0; c < M->ncells; c++) {
    if (T->flags[leaves[M->leaf[c]]] & MX_OCT_SURFACE) continue;
    const int nv = mx_cell_nodes[M->type[c]];
    for (int k = 0; k < nv; k++)
      __atomic_store_n(&states[M->conn[8 * c + k]], (uint8_t)MX_NODE_INSIDE,
                       __ATOMIC_RELAXED);
  }
  size_t q = 0;
#pragma omp parallel for schedule(dynamic, 4096) reduction(+ : q)
  for (size_t v = 0; v < M->nnodes; v++) {
    if (states[v] != UNKNOWN) continue;
    states[v] = mx_inside(S, M->xyz + 3 * v) ? MX_NODE_INSIDE : MX_NODE_OUTSIDE;
    q++;
  }
  *queries = q;
  return MX_OK;
}
