/* The stages after refinement, chained once (src/mesher/pipeline.c), for
 * every path that meshes leaves of an octree:
 *
 *   the single-process mesher   the whole octree        (mesher.c)
 *   the local re-mesh           the patch of the leaves
 *                               around what was split   (remesh_patch.c)
 *   the distributed path        each rank's patch       (mpi/p4est_mesh.c)
 *
 * mx_pipeline_transition  the edge infos restored, each leaf's node mask
 *                         (then the edge infos released when asked: nothing
 *                         reads them again until the octree is split), the
 *                         transition patterns' elements;
 * mx_pipeline_boundary    the mesher's surface index (built once, here),
 *                         the boundary stage (kernels/boundary_stage.h),
 *                         the elements grouped by leaf; with
 *                         first_use_next (the caller numbers the nodes by
 *                         first use next: the whole mesh, the splice), the
 *                         nodes no element uses may stay
 *                         (mx_surface_patterns' keep_unused).
 *
 * leaves: octant indices of the mesher's tree, in Morton order. The
 * callers time the steps and keep the results. */
#ifndef MX_PIPELINE_H
#define MX_PIPELINE_H

#include <stddef.h>
#include <stdint.h>

#include "kernels/boundary_stage.h"
#include "mesher/mesher.h"

int mx_pipeline_transition(mx_mesher *m, const uint32_t *leaves, size_t n, int release_edges,
                           mx_mesh *M);
int mx_pipeline_boundary(mx_mesher *m, const uint32_t *leaves, size_t n, mx_mesh *M,
                         int first_use_next, uint8_t **states, mx_boundary_stats *bs);
/* The distance from the features within which their placement looks at
 * the boundary (mx_feature_input.near; 0: everywhere). */
double mx_feature_reach(const mx_mesher *m);
/* m->SI over the soup's domain triangles, built the first time it is
 * asked for and kept (the only place it is built): with --repair-input the
 * side of a point is the winding number's. */
int mx_mesher_index(mx_mesher *m);
/* The progress hook and the load limit between two stages (the
 * mesher's on_stage, mx_call_recheck). */
/* MX_ECANCELED when the call was cancelled (base/cancel.h), else MX_OK. */
int mx_mesher_stage(const mx_mesher *m, const char *name);

#endif
