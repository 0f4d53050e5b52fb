/* Surface reading: the reader chosen by the file's extension (declared in
 * io/read_surface.h). */
#include "io/read_surface.h"

#include <string.h>
#include <strings.h>

#include "base/common.h"

/* ---- dispatch --------------------------------------------------------- */

static const char *extension(const char *path) {
  const char *slash = strrchr(path, '/');
  const char *base = slash ? slash + 1 : path;
  const char *dot = strrchr(base, '.');
  return dot ? dot : "";
}

int mx_read_surface(const char *path, mx_trisoup *out) {
  memset(out, 0, sizeof *out);
  const char *ext = extension(path);
  if (!strcasecmp(ext, ".off")) return mx_read_off(path, out);
  if (!strcasecmp(ext, ".mdl")) return mx_read_mdl(path, out);
  if (!strcasecmp(ext, ".stl")) return mx_read_stl(path, out);
  if (!strcasecmp(ext, ".obj")) return mx_read_obj(path, out);
  if (!strcasecmp(ext, ".ply")) return mx_read_ply(path, out);
  mx_error(path, 0,
           "unknown surface format '%s': expected .off, .mdl, .stl, .obj or .ply",
           ext);
  return MX_EINPUT;
}
