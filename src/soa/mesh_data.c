#include "soa/mesh_data.h"

#include <string.h>

#include "base/common.h"

void mx_mesh_data_free(mx_mesh_data *m) {
  if (!m) return;
  mx_free(m->xyz);
  mx_free(m->type);
  mx_free(m->conn);
  mx_free(m->face_nn);
  mx_free(m->face_conn);
  mx_free(m->face_tag);
  for (size_t i = 0; m->name && i < m->nnames; i++) mx_free(m->name[i]);
  mx_free(m->name_tag);
  mx_free(m->name);
  mx_free(m->node_tag);
  mx_free(m->node_bnd);
  mx_free(m->cell_tag);
  memset(m, 0, sizeof *m);
}
