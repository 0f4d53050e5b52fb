/* The builder of the distributed octree from a mesher's inputs. */
#include "mpi/p4est_inputs.h"

#include "base/common.h"
#include "geom/surface_defects.h"
#include "mesher/mesher_impl.h"

#include <string.h>

int mx_p4est_inputs_init(mx_p4est_inputs *I, mx_mesher *m) {
  memset(I, 0, sizeof *I);
  if (m->ndomain == 0) {
    mx_error(NULL, 0, "no input surface: add one (-i FILE) or the demo (--demo)");
    return MX_EINPUT;
  }
  MX_CHECK(mx_trisoup_check_shells(&m->domain, (uint32_t)m->domain.nt,
                                   (const char *const *)m->domain_name));
  mx_surface_defects r;
  MX_CHECK(mx_surface_defects_find(&m->domain, &r));
  const size_t bad = r.boundary_edges + r.nonmanifold_edges + r.intersecting_pairs +
                     r.crossing_pairs;
  if (bad) {
    char what[4096];
    mx_surface_defects_describe(&r, &m->domain, what, sizeof what);
    for (char *c = what; *c; c++)
      if (*c == '\n') *c = ';';
    mx_error(m->domain_name[0], 0, "the input has no well-defined inside, refused by the "
                                   "distributed octree: %s", what);
    return MX_EINPUT;
  }
  /* domain triangles first, then each region's (as the mesher assembles) */
  MX_CHECK(mx_trisoup_append(&I->soup, &m->domain));
  I->nt_domain = (uint32_t)I->soup.nt;
  for (int k = 0; k < m->nregions; k++) {
    I->region_t0[k] = (uint32_t)I->soup.nt;
    MX_CHECK(mx_trisoup_append(&I->soup, &m->region[k]));
  }
  I->region_t0[m->nregions] = (uint32_t)I->soup.nt;
  const mx_requests req = mx_mesher_requests(m);
  I->have_builder = 1; /* mx_builder_free undoes a partial init too */
  return mx_builder_init(&I->B, &I->soup, I->nt_domain, I->region_t0, &req, 0,
                         m->domain_name[0]);
}

void mx_p4est_inputs_free(mx_p4est_inputs *I) {
  if (I->have_builder) mx_builder_free(&I->B);
  mx_trisoup_free(&I->soup);
  memset(I, 0, sizeof *I);
}
