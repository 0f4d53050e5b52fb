/* Independent checks of 2D meshes (STUB; to be replaced). */
#include <string.h>

#include "common.h"
#include "quad/quad.h"

int mx_qmesh_check(const mx_qmesh *M, const mx_poly *domain, double tol, mx_qcheck_report *r) {
  (void)M; (void)domain; (void)tol;
  memset(r, 0, sizeof *r);
  return MX_EINTERNAL;
}
