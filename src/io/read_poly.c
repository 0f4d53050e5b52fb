/* Readers of 2D polylines (STUB; to be replaced). */
#include "common.h"
#include "quad/quad.h"

int mx_read_poly(const char *path, mx_poly *P) {
  (void)P;
  mx_error(path, 0, "2D readers not written yet");
  return MX_EINPUT;
}
int mx_read_poly_off(const char *path, mx_poly *P) { return mx_read_poly(path, P); }
int mx_read_poly_mdl(const char *path, mx_poly *P) { return mx_read_poly(path, P); }
int mx_read_poly_any(const char *path, mx_poly *P) { return mx_read_poly(path, P); }
