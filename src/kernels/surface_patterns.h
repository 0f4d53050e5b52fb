/* Line 12 of Algorithm 1 (2015 paper), "apply surface patterns" (line 14,
 * "decrease staircase effect", is kernels/staircase.h).
 *
 * The quad-face rule (Fig. 9): a quad face of an element whose four nodes
 * are not all on the same side is split along the diagonal holding more
 * outside nodes, and kept whole on a tie: one inside node, the diagonal
 * joins its two neighbours (the inside corner is cut off); three inside,
 * the diagonal goes through the outside node; two opposite inside, the
 * diagonal joins the two outside nodes; two adjacent, none or all inside,
 * the quad stays. The rule reads only the face's four states, so the two
 * elements sharing a face split it alike.
 *
 * Each pyramid, prism and hexahedron with both inside and outside nodes is
 * replaced by the tessellation of the generated table
 * (src/patterns/surface_table.c, tools/patterngen --surface) for its inside
 * mask; the sub-elements with no inside node are outside and dropped. They
 * are kept aside as the "optional" elements of the staircase reduction
 * (kernels/staircase.h). */
#ifndef MX_SURFACE_PATTERNS_H
#define MX_SURFACE_PATTERNS_H

#include <stddef.h>
#include <stdint.h>

#include "soa/mesh.h"

typedef struct {
  size_t n;
  uint8_t *type;
  uint32_t *conn;   /* 8 per element */
  uint32_t *leaf;
  uint8_t *level;
} mx_optional;

typedef struct {
  size_t removed;    /* elements with no inside node, removed */
  size_t patterned;  /* elements replaced by a surface pattern */
  size_t kept;       /* sub-elements kept */
  size_t optional;   /* sub-elements dropped (candidates for the staircase) */
  size_t centres;    /* element centres added (patterns that need one) */
  size_t in_place;   /* elements written over the elements already read, not
                        into new arrays (the rest: the mesh's start, copied) */
  size_t restored;   /* optional elements put back by the staircase step */
} mx_surface_stats;

/* The Fig. 9 rule for the quad (a b c d) with inside flags ia..id: 0 keep,
 * 1 diagonal a-c, 2 diagonal b-d. */
static inline int mx_surface_diagonal(int ia, int ib, int ic, int id) {
  const int oa = !ia + !ic, ob = !ib + !id;
  return oa > ob ? 1 : ob > oa ? 2 : 0;
}

/* Apply the surface patterns to M (elements stay in leaf order; the
 * elements with no inside node are removed on the way; the new
 * nodes, element centres, are appended and *states grows with them). The
 * dropped sub-elements whose nodes all remain in the mesh go to *opt
 * (allocated here, node ids of the final mesh). moved (may be NULL): nodes
 * moved since J_ENS was computed. The sub-elements, and the elements kept
 * as they are that use a moved node, get J_ENS NaN: the shrink, which
 * follows, measures them with its own (mx_shrink_to_boundary; M->invalid
 * and jens_min here count them invalid until then). The elements are written in place from the
 * end where the output lies right of the input (most of the mesh: the
 * patterns add elements), the rest into new arrays copied to their place;
 * MX_PATTERNS_COPY=1 in the environment copies all of it (for the tests,
 * which compare both). keep_unused: the nodes only removed elements used
 * stay (unused, ids unchanged; *opt keeps the dropped sub-elements whose
 * nodes some kept element uses) for a caller that numbers the nodes by
 * first use afterwards, which drops them (mx_mesh_renumber_first_use, the
 * splice): one pass over the elements and the node arrays less (cortex -s
 * 10: 0.76 s); 0: they go here, the others numbered down in order. */
int mx_surface_patterns(mx_mesh *M, uint8_t **states, const uint8_t *moved,
                        mx_optional *opt, mx_surface_stats *stats, int keep_unused);

void mx_optional_free(mx_optional *opt);

#endif
