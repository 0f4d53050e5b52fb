/* The builder of the distributed octree from a mesher's inputs: the
 * mesher's own assembly (mesher/inputs.c: the same policy, the same soup),
 * then a builder over that soup. */
#include "mpi/p4est_inputs.h"

#include "base/common.h"
#include "mesher/mesher_impl.h"

#include <string.h>

int mx_p4est_inputs_init(mx_p4est_inputs *I, mx_mesher *m) {
  memset(I, 0, sizeof *I);
  if (m->p.repair_input) {
    mx_error(NULL, 0, "--p4est: no --repair-input (the distributed octree locates "
                      "octants by ray parity: it needs a closed, manifold input)");
    return MX_EINPUT;
  }
  MX_CHECK(mx_mesher_assemble_inputs(m));
  const mx_requests req = mx_mesher_requests(m);
  I->have_builder = 1; /* mx_builder_free undoes a partial init too */
  MX_CHECK(mx_builder_init(&I->B, &m->soup, m->nt_domain, m->region_t0, &req, 0,
                           m->domain_name[0]));
  /* with materials, nested shells are not holes: the single-process
   * octree's side of the domain (mx_build_tree) */
  return mx_mesher_domain_side(m, &I->B);
}

void mx_p4est_inputs_free(mx_p4est_inputs *I) {
  if (I->have_builder) mx_builder_free(&I->B);
  memset(I, 0, sizeof *I);
}
