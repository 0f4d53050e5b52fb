/* Algorithm 2, steps 3-5, in 2D (STUB; to be replaced). */
#include "common.h"
#include "quad/quad.h"

int mx_qboundary(const mx_poly *P, const mx_poly_index *I, const mx_qtree *T,
                 const uint32_t *leaves, double close_ratio, mx_qmesh *M,
                 mx_qboundary_stats *stats) {
  (void)P; (void)I; (void)T; (void)leaves; (void)close_ratio; (void)M; (void)stats;
  return MX_EINTERNAL;
}
