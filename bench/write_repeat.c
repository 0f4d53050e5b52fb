/* Writing alone, as a C program linking libmixoct sees it (issue 31 item 4):
 * one mesh, then mx_mesher_write called again and again on it, the formats
 * alternated, each call timed. The first call of all also makes what the
 * writers add to the mesh (written order, boundary faces and tags): a
 * library that keeps them (since issue 31) makes them once, so the later
 * calls time the writer itself; an older library makes them at every call.
 *
 * usage: mixoct-write-bench FILE LEVEL REPEAT DIR [THREADS]
 * Writes DIR/w.vtu and DIR/w.msh (binary) REPEAT times each, alternated
 * (the file of the call before removed first, untimed),
 * then prints per format the first call's seconds, the median of the
 * others and the file's bytes; and the ratio .msh / .vtu of the medians.
 * THREADS (default 0: the library's default) sets mx_params.threads. */
#include "mixoct.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "bench_util.h"

int main(int argc, char **argv) {
  if (argc < 5) {
    fprintf(stderr, "usage: %s FILE LEVEL REPEAT DIR [THREADS]\n", argv[0]);
    return 2;
  }
  const int level = atoi(argv[2]), repeat = atoi(argv[3]);
  if (repeat < 2 || repeat > 1000) {
    fprintf(stderr, "REPEAT: 2 to 1000\n");
    return 2;
  }
  mx_params p;
  mx_params_default(&p);
  p.surface_level = level;
  p.threads = argc > 5 ? atoi(argv[5]) : 0;
  mx_mesher *m = mx_mesher_new(&p);
  if (!m) return 3;
  int st = mx_mesher_add_surface(m, argv[1]);
  if (!st) st = mx_mesher_mesh(m);
  if (st) {
    fprintf(stderr, "mesh: status %d\n", st);
    mx_mesher_free(m);
    return 1;
  }
  const char *ext[2] = {"vtu", "msh"};
  char path[2][4096];
  double *t[2], first[2] = {0, 0};
  t[0] = calloc((size_t)repeat, sizeof(double));
  t[1] = calloc((size_t)repeat, sizeof(double));
  if (!t[0] || !t[1]) return 3;
  for (int f = 0; f < 2; f++) snprintf(path[f], sizeof path[f], "%s/w.%s", argv[4], ext[f]);
  for (int r = 0; r < repeat && !st; r++)
    for (int f = 0; f < 2 && !st; f++) {
      unlink(path[f]); /* not timed: freeing the file before is no part of writing */
      const double t0 = bench_now();
      st = mx_mesher_write(m, path[f], 0);
      const double dt = bench_now() - t0;
      if (r == 0) first[f] = dt;
      else t[f][r - 1] = dt;
    }
  if (st) {
    fprintf(stderr, "write: status %d\n", st);
    mx_mesher_free(m);
    return 1;
  }
  double med[2];
  for (int f = 0; f < 2; f++) {
    struct stat sb;
    med[f] = bench_median(t[f], repeat - 1);
    printf("%s: first %.3f s, then median %.3f s over %d; %.1f MB\n", ext[f], first[f], med[f],
           repeat - 1, stat(path[f], &sb) ? 0.0 : (double)sb.st_size / 1e6);
    free(t[f]);
  }
  printf("msh/vtu: first %.2f, then %.2f\n", first[1] / first[0], med[1] / med[0]);
  mx_mesher_free(m);
  return 0;
}
