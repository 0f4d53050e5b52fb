/* 2D transition patterns (STUB; to be replaced). */
#include <string.h>

#include "common.h"
#include "quad/quad.h"

void mx_qmesh_free(mx_qmesh *M) {
  mx_free(M->xy); mx_free(M->nkey); mx_free(M->type); mx_free(M->conn);
  mx_free(M->leaf); mx_free(M->level);
  memset(M, 0, sizeof *M);
}
int mx_qtransition(const mx_qtree *T, const uint32_t *leaves, size_t n, mx_qmesh *M) {
  (void)T; (void)leaves; (void)n; (void)M;
  return MX_EINTERNAL;
}
