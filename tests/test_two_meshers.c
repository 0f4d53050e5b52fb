/* Two meshers used at the same time from two threads (issue 25): each
 * mesher's messages go to its own handler only, the quiet flag and the
 * thread count of one thread are not the other's, and each mesh is the
 * one the same calls give alone.
 *   A: the demo surface at -s 4, 2 threads; first an invalid request (a
 *      level out of range: one error message each time), made again and
 *      again while B meshes, then the mesh.
 *   B: an inside-out box at -s 5, 1 thread, quiet (mx_quiet on its thread):
 *      the warning that the surface was turned over is not given (alone and
 *      not quiet, B gets it).
 * Both run 6 times side by side, started together; then once more from
 * the two threads of an OpenMP team (A on thread 1: a caller that is itself
 * a worker of the user's team still gets its messages). */
#include "base/common.h"
#include "check.h"
#include "mesh_hash.h"
#include "mixoct.h"

#include <omp.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <string.h>

typedef struct {
  int errors, warnings;
  char first_error[256], first_warning[256];
  const char *who;
} msgs;

static void on_message(void *user, int level, const char *text) {
  msgs *g = user;
  if (level == MX_MSG_ERROR) {
    if (!g->errors++) snprintf(g->first_error, sizeof g->first_error, "%s", text);
  } else {
    if (!g->warnings++) snprintf(g->first_warning, sizeof g->first_warning, "%s", text);
  }
}

typedef struct {
  msgs g;
  uint64_t hash;
  int status, bad_status, threads_used, quiet, invalid;
} result;

static atomic_int b_done = 1; /* alone: one invalid request */

/* A: the demo, invalid requests first (until B is done) */
static void run_a(result *r) {
  memset(r, 0, sizeof *r);
  mx_params p;
  mx_params_default(&p);
  p.surface_level = 4;
  p.threads = 2;
  mx_mesher *m = mx_mesher_new(&p);
  if (!m) return;
  mx_mesher_set_message_handler(m, on_message, &r->g);
  do {
    const int st = mx_mesher_set_levels(m, 99, -1);
    if (!r->invalid++ || st != MX_EINPUT) r->bad_status = st;
  } while (!atomic_load(&b_done) && r->invalid < 1000000);
  r->status = mx_mesher_add_demo_surface(m);
  if (!r->status) r->status = mx_mesher_mesh(m);
  r->threads_used = mx_last_call_threads();
  r->hash = test_mesh_hash(m);
  r->quiet = mx_quiet;
  mx_mesher_free(m);
}

/* B: a box given inside out (turned over, with a warning) */
static void run_b(result *r, int quiet) {
  memset(r, 0, sizeof *r);
  static const double lo[3] = {0.1, 0.2, 0.05}, hi[3] = {1.3, 0.9, 1.1};
  double xyz[24];
  for (int v = 0; v < 8; v++)
    for (int a = 0; a < 3; a++) xyz[3 * v + a] = (v >> a) & 1 ? hi[a] : lo[a];
  /* the faces outward (vertex x + 2y + 4z), each split in two, then
   * every triangle reversed */
  static const int quad[6][4] = {{0, 4, 6, 2}, {1, 3, 7, 5}, {0, 1, 5, 4},
                                 {2, 6, 7, 3}, {0, 2, 3, 1}, {4, 5, 7, 6}};
  uint32_t tri[36];
  for (int f = 0; f < 6; f++) {
    const int *q = quad[f];
    const int t[2][3] = {{q[0], q[2], q[1]}, {q[0], q[3], q[2]}};
    for (int k = 0; k < 2; k++)
      for (int j = 0; j < 3; j++) tri[6 * f + 3 * k + j] = (uint32_t)t[k][j];
  }
  mx_quiet = quiet; /* this thread's */
  mx_params p;
  mx_params_default(&p);
  p.surface_level = 5;
  p.threads = 1;
  mx_mesher *m = mx_mesher_new(&p);
  if (!m) return;
  mx_mesher_set_message_handler(m, on_message, &r->g);
  r->status = mx_mesher_add_surface_arrays(m, "box", 8, xyz, 12, tri);
  if (!r->status) r->status = mx_mesher_mesh(m);
  r->threads_used = mx_last_call_threads();
  r->hash = test_mesh_hash(m);
  r->quiet = mx_quiet;
  mx_mesher_free(m);
  atomic_store(&b_done, 1);
}

static pthread_barrier_t start;
static result ra, rb;

static void *thread_a(void *arg) {
  (void)arg;
  pthread_barrier_wait(&start);
  run_a(&ra);
  return NULL;
}

static void *thread_b(void *arg) {
  (void)arg;
  pthread_barrier_wait(&start);
  run_b(&rb, 1);
  return NULL;
}

int main(void) {
  /* alone, on this thread */
  result a0, b0, bq;
  run_a(&a0);
  run_b(&b0, 0);
  run_b(&bq, 1);
  mx_quiet = 0;
  CHECK(a0.status == MX_OK && a0.hash != 0);
  CHECK(a0.bad_status == MX_EINPUT);
  CHECK(a0.g.errors == 1 && strstr(a0.g.first_error, "99"));
  CHECK(a0.threads_used == 2);
  CHECK(b0.status == MX_OK && b0.hash != 0);
  CHECK(b0.g.errors == 0 && b0.g.warnings >= 1 && strstr(b0.g.first_warning, "re-oriented"));
  CHECK(bq.g.warnings == 0 && bq.hash == b0.hash);
  CHECK(b0.threads_used == 1);
  printf("alone: A %d error(s) \"%s\", %d warning(s); B %d warning(s) \"%s\", quiet: %d\n",
         a0.g.errors, a0.g.first_error, a0.g.warnings, b0.g.warnings, b0.g.first_warning,
         bq.g.warnings);

  pthread_barrier_init(&start, NULL, 2);
  for (int round = 0; round < 6; round++) {
    atomic_store(&b_done, 0);
    pthread_t ta, tb;
    pthread_create(&ta, NULL, thread_a, NULL);
    pthread_create(&tb, NULL, thread_b, NULL);
    pthread_join(ta, NULL);
    pthread_join(tb, NULL);
    CHECK(ra.status == MX_OK && ra.hash == a0.hash);
    CHECK(ra.bad_status == MX_EINPUT);
    CHECK(ra.g.errors == ra.invalid && ra.g.warnings == a0.g.warnings);
    CHECK(strcmp(ra.g.first_error, a0.g.first_error) == 0);
    CHECK(ra.threads_used == 2 && ra.quiet == 0);
    CHECK(rb.status == MX_OK && rb.hash == b0.hash);
    CHECK(rb.g.errors == 0 && rb.g.warnings == 0); /* quiet, and none of A's */
    CHECK(rb.threads_used == 1 && rb.quiet == 1);
  }
  pthread_barrier_destroy(&start);
  CHECK(mx_quiet == 0); /* the threads' flags were theirs */
  printf("6 rounds of A and B side by side: the meshes alone, the messages their own "
         "(A's last round: %d invalid requests during B's calls)\n", ra.invalid);
  atomic_store(&b_done, 0);
  int team = 0;
#pragma omp parallel num_threads(2)
  {
#pragma omp single
    team = omp_get_num_threads();
    if (team == 2) {
      if (omp_get_thread_num() == 1) run_a(&ra);
      else run_b(&rb, 1);
    }
  }
  if (team == 2) {
    CHECK(ra.status == MX_OK && ra.hash == a0.hash);
    CHECK(ra.bad_status == MX_EINPUT && ra.g.errors == ra.invalid);
    CHECK(strcmp(ra.g.first_error, a0.g.first_error) == 0);
    CHECK(rb.status == MX_OK && rb.hash == b0.hash);
    CHECK(rb.g.errors == 0 && rb.g.warnings == 0);
    CHECK(ra.quiet == 0 && rb.quiet == 1);
    printf("from the two threads of an OpenMP team: the same\n");
  } else {
    printf("SKIP the OpenMP team of 2 (got %d thread)\n", team);
  }
  return TEST_DONE();
}
