/* mx_mesher_detach_mesh_buffers, mx_mesher2d_detach_mesh_buffers
 * (include/mixoct.h): the arrays of the current mesh handed to the caller
 * (a binding whose views still point to them), the mesher going on with
 * copies, so that the next call that changes the mesh frees or edits the
 * copies and never the memory the views read. One copy of the mesh, made
 * only when asked for. */
#include <string.h>

#include "base/common.h"
#include "mesher/mesher.h"
#include "mesher/mesher_impl.h"
#include "mesher/mesher2d.h"

/* *p becomes a copy of its `bytes` (one more element's room, as the
 * mesher allocates); the original goes to old[(*k)++]. */
static int swap_copy(void **p, size_t bytes, size_t item, void **old, int *k) {
  if (!*p) return MX_OK;
  void *c = mx_alloc(bytes + item);
  if (!c) return MX_ENOMEM;
  if (bytes) memcpy(c, *p, bytes);
  old[(*k)++] = *p;
  *p = c;
  return MX_OK;
}

static int detach(void **slots[], const size_t bytes[], const size_t item[], int n,
                  void **old) {
  void **done[MX_DETACH_MAX]; /* the slots swapped, old[i] the original of done[i] */
  int k = 0;
  for (int i = 0; i < MX_DETACH_MAX; i++) old[i] = NULL;
  for (int i = 0; i < n; i++) {
    const int before = k;
    if (swap_copy(slots[i], bytes[i], item[i], old, &k)) {
      for (int j = 0; j < k; j++) { /* out of memory half way: undone */
        mx_free(*done[j]);
        *done[j] = old[j];
        old[j] = NULL;
      }
      return MX_ENOMEM;
    }
    if (k > before) done[before] = slots[i];
  }
  return MX_OK;
}

int mx_mesher_detach_mesh_buffers(mx_mesher *m, void *old[MX_DETACH_MAX]) {
  mx_written_forget(m); /* the writers' arrays go with the mesh */
  mx_mesh *M = &m->M;
  const size_t n = M->nnodes, e = M->ncells;
  void **slots[] = {(void **)&M->xyz,  (void **)&M->type,  (void **)&M->conn,
                    (void **)&M->level, (void **)&M->leaf, (void **)&M->jens,
                    (void **)&M->material, (void **)&m->bnd};
  const size_t item[] = {3 * sizeof(double), 1, 8 * sizeof(uint32_t), 1,
                         sizeof(uint32_t), sizeof(float), sizeof(uint16_t), 1};
  const size_t count[] = {n, e, e, e, e, e, e, n};
  size_t bytes[8];
  for (int i = 0; i < 8; i++) bytes[i] = count[i] * item[i];
  return detach(slots, bytes, item, 8, old);
}

int mx_mesher2d_detach_mesh_buffers(mx_mesher2d *m, void *old[MX_DETACH_MAX]) {
  mx_qmesh *M = &m->M;
  const size_t n = M->nnodes, e = M->ncells;
  void **slots[] = {(void **)&M->xy, (void **)&M->type, (void **)&M->conn,
                    (void **)&M->leaf, (void **)&M->level, (void **)&m->material};
  const size_t item[] = {2 * sizeof(double), 1, 4 * sizeof(uint32_t), sizeof(uint32_t), 1,
                         sizeof(uint16_t)};
  const size_t count[] = {n, e, e, e, e, e};
  size_t bytes[6];
  for (int i = 0; i < 6; i++) bytes[i] = count[i] * item[i];
  return detach(slots, bytes, item, 6, old);
}
