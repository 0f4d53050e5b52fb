/* One mesh through the library, timed, as a C program linking libmixoct
 * sees it (issue 24, "threads that never hurt"): add the surface, mesh,
 * and print the seconds, the thread count the call ran with and a hash of
 * the mesh arrays (the same bytes for any thread count).
 *
 * usage: mixoct-lib-bench [-i FILE | --demo] [-s LEVEL] [--threads N]
 *                         [--repeat N] [--2d FILE.poly]
 * --threads N sets mx_params.threads (0, the default: OpenMP's default,
 * OMP_NUM_THREADS or one per processor, under the library's load limit).
 * Each repeat prints one line:
 *   seconds <total> mesh <mesh call> threads <n> hash <16 hex digits> */
#include "mixoct.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

/* weak: the bench also runs against a library from before the call existed
 * (then it prints threads -1) */
#pragma weak mx_last_call_threads

static double now(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static uint64_t fnv(uint64_t h, const void *p, size_t n) {
  const unsigned char *b = p;
  for (size_t i = 0; i < n; i++) h = (h ^ b[i]) * 1099511628211ull;
  return h;
}

static int run3d(const char *input, int level, int threads, uint64_t *hash, double *t_mesh) {
  mx_params p;
  mx_params_default(&p);
  p.surface_level = level;
  p.threads = threads;
  mx_mesher *m = mx_mesher_new(&p);
  if (!m) return MX_ENOMEM;
  int st = input ? mx_mesher_add_surface(m, input) : mx_mesher_add_demo_surface(m);
  double t0 = now();
  if (!st) st = mx_mesher_mesh(m);
  *t_mesh = now() - t0;
  mx_mesh_arrays a;
  if (!st) st = mx_mesher_mesh_arrays(m, &a);
  if (!st) {
    uint64_t h = 14695981039346656037ull;
    h = fnv(h, a.xyz, 3 * a.nnodes * sizeof *a.xyz);
    h = fnv(h, a.type, a.nelements);
    h = fnv(h, a.conn, 8 * a.nelements * sizeof *a.conn);
    *hash = h;
  }
  mx_mesher_free(m);
  return st;
}

static int run2d(const char *input, int level, int threads, uint64_t *hash, double *t_mesh) {
  mx_params2d p;
  mx_params2d_default(&p);
  p.surface_level = level;
  p.threads = threads;
  mx_mesher2d *m = mx_mesher2d_new(&p);
  if (!m) return MX_ENOMEM;
  int st = mx_mesher2d_set_domain(m, input);
  double t0 = now();
  if (!st) st = mx_mesher2d_mesh(m);
  *t_mesh = now() - t0;
  mx_mesh2d_arrays a;
  if (!st) st = mx_mesher2d_mesh_arrays(m, &a);
  if (!st) {
    uint64_t h = 14695981039346656037ull;
    h = fnv(h, a.xy, 2 * a.nnodes * sizeof *a.xy);
    h = fnv(h, a.type, a.ncells);
    h = fnv(h, a.conn, 4 * a.ncells * sizeof *a.conn);
    *hash = h;
  }
  mx_mesher2d_free(m);
  return st;
}

int main(int argc, char **argv) {
  const char *input = NULL, *poly = NULL;
  int level = 5, threads = 0, repeat = 1;
  for (int i = 1; i < argc; i++) {
    const char *a = argv[i];
    int more = i + 1 < argc;
    if (!strcmp(a, "-i") && more)
      input = argv[++i];
    else if (!strcmp(a, "--2d") && more)
      poly = argv[++i];
    else if (!strcmp(a, "--demo"))
      input = NULL;
    else if (!strcmp(a, "-s") && more)
      level = atoi(argv[++i]);
    else if (!strcmp(a, "--threads") && more)
      threads = atoi(argv[++i]);
    else if (!strcmp(a, "--repeat") && more)
      repeat = atoi(argv[++i]);
    else {
      fprintf(stderr, "usage: mixoct-lib-bench [-i FILE | --demo | --2d FILE.poly] "
                      "[-s LEVEL] [--threads N] [--repeat N]\n");
      return 2;
    }
  }
  for (int r = 0; r < repeat; r++) {
    uint64_t hash = 0;
    double t_mesh = 0, t0 = now();
    int st = poly ? run2d(poly, level, threads, &hash, &t_mesh)
                  : run3d(input, level, threads, &hash, &t_mesh);
    double t = now() - t0;
    if (st) {
      fprintf(stderr, "mixoct-lib-bench: %s\n", mx_status_string(st));
      return st;
    }
    printf("seconds %.4f mesh %.4f threads %d hash %016llx\n", t, t_mesh,
           mx_last_call_threads ? mx_last_call_threads() : -1, (unsigned long long)hash);
  }
  return 0;
}
