/* TEMPORARY (branch featio): weak stand-ins for mx_feature_lines_of and
 * mx_feature_lines_free (geom/features.h) until src/geom/features.c defines
 * them; its strong definitions replace these at link time, and this file
 * should then be deleted (and dropped from meson.build). They walk the
 * ridge edges with geom/feature_walk.c, which the real ones may use too. */
#include <string.h>

#include "base/common.h"
#include "geom/feature_walk.h"
#include "geom/features.h"

__attribute__((weak)) int mx_feature_lines_of(const mx_trisoup *s, const mx_features *F,
                                              mx_feature_lines *L) {
  memset(L, 0, sizeof *L);
  uint8_t *corner = mx_calloc(s->nv + 1);
  if (!corner) return MX_ENOMEM;
  for (size_t i = 0; i < F->ncorners; i++)
    if (F->corner[i] < s->nv) corner[F->corner[i]] = 1;
  int st = mx_feature_lines_walk(s->x, s->y, s->z, 1, s->nv, F->edge, F->nedges, corner, L);
  mx_free(corner);
  return st == MX_EINPUT ? MX_EINTERNAL : st;
}

__attribute__((weak)) void mx_feature_lines_free(mx_feature_lines *L) {
  mx_feature_lines_walk_free(L);
}
