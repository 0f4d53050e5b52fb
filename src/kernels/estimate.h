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

/* Estimated peak bytes of a run; stage 0: octree, 1: transition, 2: full.
 * The leaves estimated from the area are 1.1 to 1.4 times the leaves the
 * octree ends with on the shared surfaces, so this one errs on the safe
 * side: it refuses a run before anything is built. */
double mx_estimate_bytes(const mx_trisoup *soup, uint32_t nt_domain,
                         const uint32_t *region_t0, const mx_requests *req,
                         const mx_grid *g, int stage);
/* The memory this process may still use, in bytes: MemAvailable from
 * /proc/meminfo, or less when a memory cgroup (a batch job's --mem) leaves
 * less room; 0 when unknown. */
double mx_available_bytes(void);

/* The peak of a run from the leaves of its balanced octree: 6.6 MB + 600 B
 * per input triangle + 310 B per leaf + 96 B per leaf for the first 200,000
 * leaves (small runs keep more of what they free in the heap), full stage;
 * fitted on the shared surfaces at -s 4 to 10 (issue 12; the cortex: within
 * 10% from -s 5 to -s 10). Stage 0 (the leaves as hexahedra): 240 B per
 * leaf; stage 1: the full stage's. */
double mx_estimate_bytes_leaves(size_t leaves, size_t triangles, int stage);

#endif
