/* M3D writer: not written yet (issue 5). */
#include "common.h"
#include "soa/mesh.h"

int mx_write_m3d(const char *path, const mx_mesh_view *m) {
  (void)m;
  mx_error(path, 0, "the M3D writer is not available yet");
  return MX_EINPUT;
}
