/* PLY surfaces (placeholder, being written). */
#include "common.h"
#include "soa/trisoup.h"

int mx_read_ply(const char *path, mx_trisoup *out) {
  (void)out;
  mx_error(path, 0, "PLY files are not read yet");
  return MX_EINPUT;
}
