/* Writers of 2D meshes (STUB; to be replaced). */
#include "common.h"
#include "quad/quad.h"

int mx_write_qmesh(const char *path, const mx_qmesh *M, int ascii) {
  (void)M; (void)ascii;
  mx_error(path, 0, "2D writers not written yet");
  return MX_EINPUT;
}
int mx_qmesh_format_known(const char *path) { (void)path; return 0; }
