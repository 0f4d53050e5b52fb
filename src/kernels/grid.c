#include "kernels/grid.h"

#include "base/common.h"

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

int mx_grid_build(const double lo[3], const double hi[3], const char *name, mx_grid *g) {
  double ext[3], shortest = INFINITY, longest = 0.0;
  for (int a = 0; a < 3; a++) {
    ext[a] = hi[a] - lo[a];
    if (!(ext[a] > 0.0) || !isfinite(ext[a]) || !isfinite(lo[a]) || !isfinite(hi[a])) {
      mx_error(name, 0, "the input is flat or empty (bounding box extent %g on axis %c)",
               ext[a], "xyz"[a]);
      return MX_EINPUT;
    }
    if (ext[a] < shortest) shortest = ext[a];
    if (ext[a] > longest) longest = ext[a];
  }
  /* Coordinates far from 1 in size: the lattice (2^16 cells per root cube)
   * and the geometric predicates stay exact only within these bounds. */
  double big = 0.0;
  for (int a = 0; a < 3; a++) big = fmax(big, fmax(fabs(lo[a]), fabs(hi[a])));
  if (longest < 1e-100 || big > 1e100 || longest < 1e-12 * big) {
    mx_error(name, 0, "coordinates out of range: bounding box of size %g at distance up to "
                      "%g from the origin (mixoct meshes sizes between 1e-100 and 1e100, at "
                      "most 1e12 times smaller than their distance to the origin): rescale "
                      "or translate the surface", longest, big);
    return MX_EINPUT;
  }
  /* The published rule: roots of the shortest extent. An elongated input
   * (a beam, a vessel) would need more than MX_MAX_ROOTS_PER_AXIS of them on
   * its longest axis: the roots grow until that axis holds that many. */
  g->side = 1.01 * shortest;
  const double elongated = longest / (double)(MX_MAX_ROOTS_PER_AXIS - 2);
  if (g->side < elongated) g->side = 1.001 * elongated;
  g->unit = ldexp(g->side, -MX_MAX_LEVEL);
  /* the finest octant (level MX_MAX_LEVEL - 1) must fit across the input */
  const double finest = ldexp(g->side, -(MX_MAX_LEVEL - 1));
  if (shortest < finest) {
    mx_error(name, 0, "the input is too thin for its length: %g across on axis %c against "
                      "%g along its longest axis; the finest octant (%g) would not fit "
                      "across it", shortest, "xyz"[ext[0] == shortest ? 0 : ext[1] == shortest ? 1 : 2],
             longest, finest);
    return MX_EINPUT;
  }
  for (int a = 0; a < 3; a++) {
    const int n = cubes_on_axis(ext[a], g->side);
    if (n > MX_MAX_ROOTS_PER_AXIS) { /* cannot happen: the side was chosen for it */
      mx_error(name, 0, "internal: %d root cubes on axis %c (at most %d)", n, "xyz"[a],
               MX_MAX_ROOTS_PER_AXIS);
      return MX_EINTERNAL;
    }
    g->dims[a] = n;
    g->origin[a] = 0.5 * (lo[a] + hi[a]) - 0.5 * n * g->side;
  }
  return MX_OK;
}
