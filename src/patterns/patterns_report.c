/* `mixoct patterns` (include/mixoct.h: mx_patterns_print): the statistics
 * of the compiled transition-pattern table (the rows of Table II of the
 * 2015 paper): how many configurations are legal, how many rotation
 * classes and how many of them use the body centre, and the elements of
 * the patterns by type with their J_ENS, as text or one JSON line. */
#include <math.h>
#include <stdio.h>

#include "mixoct.h"
#include "patterns/lattice.h"
#include "patterns/lookup.h"

int mx_patterns_print(int json) {
  if (mx_patterns_init()) return MX_EINTERNAL;
  /* Class 0 is the plain hexahedron; the others are transition patterns. */
  int centre = 0, configs = 0;
  size_t count[4] = {0, 0, 0, 0};
  double worst[4] = {INFINITY, INFINITY, INFINITY, INFINITY}, sum[4] = {0, 0, 0, 0};
  for (int k = 1; k < mx_pattern_nclasses; k++) {
    const mx_pattern_class *c = &mx_pattern_classes[k];
    centre += mx_pattern_has_centre(k);
    for (int e = c->first; e < c->first + c->count; e++) {
      const int t = mx_pattern_elems[e].type;
      const double q = mx_pattern_elem_jens[e];
      count[t]++;
      sum[t] += q;
      if (q < worst[t]) worst[t] = q;
    }
  }
  for (uint32_t c = 0; c < (1u << MX_CONFIG_BITS); c++) configs += mx_config_valid(c);
  double w = INFINITY;
  for (int t = 0; t < 4; t++)
    if (count[t] && worst[t] < w) w = worst[t];
  static const char *name[4] = {"tet", "pyramid", "prism", "hex"};
  if (json) {
    printf("{\"configurations\": %d, \"classes\": %d, \"centre_classes\": %d, "
           "\"elements\": %zu, \"worst_jens\": %.4f, \"by_type\": {",
           configs, mx_pattern_nclasses - 1, centre,
           count[0] + count[1] + count[2] + count[3], w);
    for (int t = 0; t < 4; t++)
      printf("%s\"%s\": {\"count\": %zu, \"worst_jens\": %.4f, \"mean_jens\": %.4f}",
             t ? ", " : "", name[t], count[t], count[t] ? worst[t] : 0.0,
             count[t] ? sum[t] / (double)count[t] : 0.0);
    printf("}}\n");
  } else {
    printf("transition patterns: %d configurations, %d classes (+ the plain "
           "hexahedron), body centre in %d\n", configs, mx_pattern_nclasses - 1, centre);
    printf("  %-8s %8s %8s %8s\n", "type", "count", "worst", "mean");
    for (int t = 0; t < 4; t++)
      printf("  %-8s %8zu %8.3f %8.3f\n", name[t], count[t], count[t] ? worst[t] : 0.0,
             count[t] ? sum[t] / (double)count[t] : 0.0);
    printf("  worst J_ENS over the table: %.3f\n", w);
  }
  return MX_OK;
}
