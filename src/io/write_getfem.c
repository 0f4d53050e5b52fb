/* GetFEM writer: not written yet (issue 5). */
#include "common.h"
#include "soa/mesh.h"

int mx_write_getfem(const char *path, const mx_mesh_view *m) {
  (void)m;
  mx_error(path, 0, "the GetFEM writer is not available yet");
  return MX_EINPUT;
}
