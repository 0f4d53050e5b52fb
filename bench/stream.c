/* The machine's memory bandwidth, STREAM-style (McCalpin's four kernels,
 * here copy and triad), for the performance model of issue 12: the limit
 * the mesher's passes are compared against.
 *
 *   mixoct-stream [MB_PER_ARRAY] [REPEAT]
 *
 * Three arrays of doubles (default 256 MB each, far beyond the caches),
 * first touched by the threads that use them (static schedule, the same
 * split as the kernels); each kernel runs REPEAT times (default 10) with 1
 * thread and with every OpenMP thread, and the best time gives the
 * bandwidth, counting the bytes the kernel reads and writes (copy: 16
 * bytes an element, triad a = b + s c: 24; the write-allocate traffic is
 * not counted, as in STREAM). One table, then one JSON line. */
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>

static double best_of(int repeat, int threads, size_t n, double *a, const double *b,
                      const double *c, int triad) {
  double best = 1e300;
  for (int r = 0; r < repeat; r++) {
    const double t0 = omp_get_wtime();
    if (triad) {
#pragma omp parallel for schedule(static) num_threads(threads)
      for (size_t i = 0; i < n; i++) a[i] = b[i] + 3.0 * c[i];
    } else {
#pragma omp parallel for schedule(static) num_threads(threads)
      for (size_t i = 0; i < n; i++) a[i] = b[i];
    }
    const double t = omp_get_wtime() - t0;
    if (t < best) best = t;
  }
  return best;
}

int main(int argc, char **argv) {
  const double mb = argc > 1 ? atof(argv[1]) : 256.0;
  const int repeat = argc > 2 ? atoi(argv[2]) : 10;
  if (!(mb > 0.0) || repeat < 1) {
    fprintf(stderr, "usage: mixoct-stream [MB_PER_ARRAY] [REPEAT]\n");
    return 2;
  }
  const size_t n = (size_t)(mb * 1048576.0 / sizeof(double));
  double *a = malloc(n * sizeof *a), *b = malloc(n * sizeof *b), *c = malloc(n * sizeof *c);
  if (!a || !b || !c) {
    fprintf(stderr, "mixoct-stream: cannot allocate 3 x %.0f MB\n", mb);
    return 3;
  }
  const int tmax = omp_get_max_threads();
#pragma omp parallel for schedule(static)
  for (size_t i = 0; i < n; i++) {
    a[i] = 0.0;
    b[i] = 1.0;
    c[i] = 2.0;
  }
  const int threads[2] = {1, tmax};
  double gbs[2][2];
  for (int k = 0; k < 2; k++) {
    const double tc = best_of(repeat, threads[k], n, a, b, c, 0);
    const double tt = best_of(repeat, threads[k], n, a, b, c, 1);
    gbs[k][0] = 16.0 * (double)n / tc / 1e9;
    gbs[k][1] = 24.0 * (double)n / tt / 1e9;
  }
  /* a use of a, so the kernels are not optimized away */
  double check = 0.0;
  for (size_t i = 0; i < n; i += 4096) check += a[i];
  printf("memory bandwidth (best of %d, %.0f MB arrays)\n", repeat, mb);
  printf("  threads     copy GB/s    triad GB/s\n");
  for (int k = 0; k < 2; k++)
    printf("  %7d  %12.2f  %12.2f\n", threads[k], gbs[k][0], gbs[k][1]);
  printf("{\"array_mb\": %.0f, \"repeat\": %d, \"threads\": [%d, %d], \"copy_gbs\": [%.3f, %.3f], "
         "\"triad_gbs\": [%.3f, %.3f], \"check\": %.1f}\n",
         mb, repeat, threads[0], threads[1], gbs[0][0], gbs[1][0], gbs[0][1], gbs[1][1], check);
  free(a);
  free(b);
  free(c);
  return 0;
}
