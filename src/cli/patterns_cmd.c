/* `mixoct patterns [--json]`: statistics of the compiled transition-pattern
 * table (the rows of Table II of the 2015 paper), printed by the library
 * (src/patterns/patterns_report.c); here only the arguments. */
#include <stdio.h>
#include <string.h>

#include "cli.h"
#include "mixoct.h"

int mx_patterns_main(int argc, char **argv) {
  int json = 0;
  for (int i = 1; i < argc; i++) {
    if (strcmp(argv[i], "--json") == 0) {
      json = 1;
    } else if (strcmp(argv[i], "--help") == 0 || strcmp(argv[i], "-h") == 0) {
      printf("usage: mixoct patterns [--json]\n"
             "  the transition-pattern table: its classes (325 under rotation),\n"
             "  the sub-elements per type and the worst J_ENS of each class\n"
             "  --json    one JSON object instead of the table\n"
             "  -h, --help  this text\n");
      return MX_OK;
    } else {
      mx_error(NULL, 0, "patterns: unknown option '%s' (usage: mixoct patterns "
                        "[--json])", argv[i]);
      return MX_EINPUT;
    }
  }
  return mx_patterns_print(json);
}
