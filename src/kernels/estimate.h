/* Memory estimate before refining: the brief's "memory is a budget". The
 * number of leaves is estimated from the requests: about 3.2 A / h^2 for a
 * surface of area A refined to octants of side h (the cortex gives 2.1 at
 * level 4 rising to 2.85 at level 9), and V / h^3 for a volume V refined
 * everywhere (-a, boxes, region surfaces: their bounding volumes). Bytes per
 * leaf were measured on the cortex at level 9 (octree stage about 150,
 * transition stage about 410) and are taken with a margin. */
#ifndef MX_ESTIMATE_H
#define MX_ESTIMATE_H

#include <stddef.h>
#include <stdint.h>

#include "kernels/grid.h"
#include "kernels/requests.h"
#include "soa/trisoup.h"

/* Estimated peak bytes of a run; stage 0: octree, 1: transition, 2: full. */
double mx_estimate_bytes(const mx_trisoup *soup, uint32_t nt_domain,
                         const uint32_t *region_t0, const mx_requests *req,
                         const mx_grid *g, int stage);
/* The memory this process may still use, in bytes: MemAvailable from
 * /proc/meminfo, or less when a memory cgroup (a batch job's --mem) leaves
 * less room; 0 when unknown. */
double mx_available_bytes(void);

#endif
