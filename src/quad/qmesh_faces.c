/* A 2D mesh read by io (io/read_mesh.h: mx_read_mesh_dim, its triangles and
 * quadrilaterals as the faces, every z = 0) as an mx_qmesh (declared in
 * quad/quad.h). The cells keep the file's node order; nkey, leaf and level
 * are NULL. */
#include <string.h>

#include "base/common.h"
#include "quad/quad.h"

enum { PAR_MIN = 65536 }; /* fewer items: one thread */

/* m's faces as the cells of q (m is left as it was). */
int mx_qmesh_from_faces(const mx_mesh_data *m, mx_qmesh *q) {
  memset(q, 0, sizeof *q);
  const size_t nn = m->nnodes, nc = m->nfaces;
  q->xy = mx_alloc((2 * nn + 1) * sizeof *q->xy);
  q->type = mx_alloc(nc + 1);
  q->conn = mx_alloc((4 * nc + 1) * sizeof *q->conn);
  if (!q->xy || !q->type || !q->conn) {
    mx_qmesh_free(q);
    return MX_ENOMEM;
  }
  q->nnodes = nn;
  q->ncells = nc;
#pragma omp parallel for schedule(static) if (nn > PAR_MIN)
  for (size_t i = 0; i < nn; i++) {
    q->xy[2 * i] = m->xyz[3 * i];
    q->xy[2 * i + 1] = m->xyz[3 * i + 1];
  }
#pragma omp parallel for schedule(static) if (nc > PAR_MIN)
  for (size_t c = 0; c < nc; c++) {
    const int k = m->face_nn[c];
    q->type[c] = k == 4 ? MX_QQUAD : MX_QTRI;
    for (int j = 0; j < 4; j++)
      q->conn[4 * c + (size_t)j] = j < k ? m->face_conn[4 * c + (size_t)j] : UINT32_MAX;
  }
  return MX_OK;
}
