/* The mesh type's own routines (see soa/mesh.h). */
#include "soa/mesh.h"

#include <string.h>

#include "base/common.h"

void mx_mesh_free(mx_mesh *m) {
  mx_free(m->xyz);
  mx_free(m->type);
  mx_free(m->conn);
  mx_free(m->level);
  mx_free(m->leaf);
  mx_free(m->jens);
  mx_free(m->material);
  mx_free(m->nkey);
  memset(m, 0, sizeof *m);
}
