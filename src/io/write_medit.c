/* Medit writer: not written yet (issue 5). */
#include "common.h"
#include "soa/mesh.h"

int mx_write_medit(const char *path, const mx_mesh_view *m, int binary) {
  (void)m;
  (void)binary;
  mx_error(path, 0, "the Medit writer is not available yet");
  return MX_EINPUT;
}
