#include "kernels/grid.h"

#include "common.h"

#include <math.h>

/* Number of cubes on one axis: extent/side = m * 2^e with m in [0.5, 1);
 * if m < 0.55 or m > 0.97 a cube is centred on the box centre (odd count),
 * otherwise a cube boundary lies at the centre (even count); cubes are added
 * on both sides until the extent is covered. */
static int cubes_on_axis(double extent, double side) {
  int e;
  double m = frexp(extent / side, &e);
  int odd = (m < 0.55 || m > 0.97);
  int n = odd ? 1 : 2;
  while ((double)n * side < extent) n += 2;
  return n;
}

int mx_grid_build(const double lo[3], const double hi[3], mx_grid *g) {
  double ext[3], shortest = INFINITY;
  for (int a = 0; a < 3; a++) {
    ext[a] = hi[a] - lo[a];
    if (!(ext[a] > 0.0) || !isfinite(ext[a])) {
      mx_error(NULL, 0, "the input is flat or empty (bounding box extent %g "
                        "on axis %c)", ext[a], "xyz"[a]);
      return MX_EINPUT;
    }
    if (ext[a] < shortest) shortest = ext[a];
  }
  g->side = 1.01 * shortest;
  g->unit = ldexp(g->side, -MX_MAX_LEVEL);
  for (int a = 0; a < 3; a++) {
    int n = cubes_on_axis(ext[a], g->side);
    if (n > MX_MAX_ROOTS_PER_AXIS) {
      mx_error(NULL, 0, "the input is too elongated: %d root cubes on axis %c "
                        "(at most %d)", n, "xyz"[a], MX_MAX_ROOTS_PER_AXIS);
      return MX_EINPUT;
    }
    g->dims[a] = n;
    g->origin[a] = 0.5 * (lo[a] + hi[a]) - 0.5 * n * g->side;
  }
  return MX_OK;
}
