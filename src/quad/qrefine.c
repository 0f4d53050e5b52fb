/* Algorithm 1 in 2D (STUB; to be replaced). */
#include "common.h"
#include "quad/quad.h"

int mx_qtree_build(const mx_poly *domain, const mx_poly_index *I, const mx_qrequests *req,
                   int balance, mx_qtree *T, mx_qstats *stats) {
  (void)domain; (void)I; (void)req; (void)balance; (void)T; (void)stats;
  return MX_EINTERNAL;
}
