/* The load limit of a library call (src/mesher/load_limit.h): the rule
 * min(requested, max(1, processors - others running)) on hand-made cases;
 * the measure of the others on this machine (readable, cheap); and a mesh
 * (3D: the demo surface, full stage; 2D: an L-shaped domain) made with the
 * limit on (MIXOCT_TEST_BUSY: as if other processes held all processors
 * but one) is the
 * same bytes as with the caller's 2 threads, which the limit leaves alone,
 * while mx_last_call_threads tells which count each call ran with. */
#include "check.h"
#include "mesh_hash.h"
#include "mesher/load_limit.h"
#include "mixoct.h"

#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

static double now(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static void test_rule(void) {
  CHECK(mx_load_limit(2, 2, 0) == 2);  /* a quiet machine: all */
  CHECK(mx_load_limit(2, 2, 1) == 1);  /* one core held by another job */
  CHECK(mx_load_limit(2, 2, 5) == 1);  /* never fewer than one */
  CHECK(mx_load_limit(8, 64, 60) == 4);
  CHECK(mx_load_limit(4, 64, 10) == 4); /* never more than asked */
  CHECK(mx_load_limit(1, 2, 0) == 1);
  CHECK(mx_load_limit(2, 2, -1) == 2); /* /proc unreadable: unchanged */
  CHECK(mx_load_limit(3, 0, 1) == 3);  /* processors unknown: unchanged */
}

/* Readable here (Linux); one measure is a few looks at most (0.75 ms of
 * pauses when other threads run), and calls that follow each other share
 * a measure for 0.1 s: well below a millisecond a call. */
static void test_measure(void) {
  double t = now();
  int others = mx_others_running();
  t = now() - t;
  CHECK(others >= 0);
  CHECK(t < 0.02); /* generous: the pauses may oversleep on a busy machine */
  const int n = 1000;
  double tc = now();
  for (int i = 0; i < n; i++) (void)mx_call_thread_count(2);
  tc = (now() - tc) / n;
  printf("mx_others_running: %d now, %.1f us; mx_call_thread_count %.2f us a call\n",
         others, 1e6 * t, 1e6 * tc);
  CHECK(tc < 1e-4);
}

/* The mesh arrays' hash; *threads: the count the mesh call ran with. */
static uint64_t mesh3d(int threads, int *used) {
  mx_params p;
  mx_params_default(&p);
  p.surface_level = 4;
  p.threads = threads;
  mx_mesher *m = mx_mesher_new(&p);
  CHECK(m != NULL);
  if (!m) return 0;
  CHECK(mx_mesher_add_demo_surface(m) == MX_OK);
  CHECK(mx_mesher_mesh(m) == MX_OK);
  *used = mx_last_call_threads();
  mx_mesh_arrays a;
  CHECK(mx_mesher_mesh_arrays(m, &a) == MX_OK);
  CHECK(a.nelements > 1000);
  const uint64_t h = test_mesh_hash(m);
  mx_mesher_free(m);
  return h;
}

static uint64_t mesh2d(int threads, int *used) {
  /* an L: [0,2]^2 less [1,2]^2, counter-clockwise */
  static const double xy[] = {0, 0, 2, 0, 2, 1, 1, 1, 1, 2, 0, 2};
  static const uint32_t seg[] = {0, 1, 1, 2, 2, 3, 3, 4, 4, 5, 5, 0};
  mx_params2d p;
  mx_params2d_default(&p);
  p.surface_level = 7;
  p.threads = threads;
  mx_mesher2d *m = mx_mesher2d_new(&p);
  CHECK(m != NULL);
  if (!m) return 0;
  CHECK(mx_mesher2d_set_domain_arrays(m, "L", 6, xy, 6, seg) == MX_OK);
  CHECK(mx_mesher2d_mesh(m) == MX_OK);
  *used = mx_last_call_threads();
  mx_mesh2d_arrays a;
  CHECK(mx_mesher2d_mesh_arrays(m, &a) == MX_OK);
  CHECK(a.ncells > 100);
  const uint64_t h = test_mesh2d_hash(m);
  mx_mesher2d_free(m);
  return h;
}

static void test_same_mesh(const char *what, uint64_t (*mesh)(int, int *)) {
  int used_busy = -1, used_free = -1, used_given = -1;
  const long online = sysconf(_SC_NPROCESSORS_ONLN);
  char busy_count[32];
  snprintf(busy_count, sizeof busy_count, "%ld", online > 1 ? online - 1 : 1);
  /* OpenMP's default is 2 (the limit's "requested"), whatever the machine */
  omp_set_num_threads(2);
  setenv("MIXOCT_TEST_BUSY", busy_count, 1); /* limit on: one processor free */
  uint64_t busy = mesh(0, &used_busy);
  /* limit on, nothing else running: all the processors */
  setenv("MIXOCT_TEST_BUSY", "0", 1);
  uint64_t quiet = mesh(0, &used_free);
  /* the caller's count wins over the limit */
  setenv("MIXOCT_TEST_BUSY", busy_count, 1);
  uint64_t given = mesh(2, &used_given);
  unsetenv("MIXOCT_TEST_BUSY");
  printf("%s: threads %d (busy), %d (quiet, %ld processors), %d (given); "
         "hashes %016llx %016llx %016llx\n", what, used_busy, used_free, online,
         used_given, (unsigned long long)busy, (unsigned long long)quiet,
         (unsigned long long)given);
  CHECK(used_busy == 1);
  CHECK(used_given == 2);
  CHECK(used_free == (online >= 2 ? 2 : 1));
  CHECK(busy == given);
  CHECK(quiet == given);
  CHECK(omp_get_max_threads() == 2); /* each call restored the count */
}

int main(void) {
  test_rule();
  test_measure();
  test_same_mesh("3D demo -s 4", mesh3d);
  test_same_mesh("2D L -s 7", mesh2d);
  return TEST_DONE();
}
