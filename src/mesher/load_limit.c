/* See load_limit.h. */
#include "mesher/load_limit.h"

#include <dirent.h>
#include <fcntl.h>
#include <stdatomic.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <time.h>
#include <unistd.h>

/* how long a measure serves (others_recent) */
#define FRESH_NS ((int64_t)100000000)

/* Recorded once, when the library is loaded: libgomp (loaded before us, a
 * dependency) read the same environment when it was loaded. A variable set
 * later changes nothing in libgomp, so it changes nothing here either. */
static int policy_chosen; /* OMP_WAIT_POLICY (a valid one) or GOMP_SPINCOUNT set */
static int online_procs;  /* processors online (what /proc/loadavg counts on) */

/* A value libgomp takes as a policy: "active" or "passive" in any case,
 * spaces around (it ignores anything else, and spins). */
static int names_policy(const char *v) {
  if (!v) return 0;
  while (*v == ' ' || *v == '\t') v++;
  size_t n = strncasecmp(v, "active", 6) == 0 ? 6 : strncasecmp(v, "passive", 7) == 0 ? 7 : 0;
  if (!n) return 0;
  for (v += n; *v == ' ' || *v == '\t'; v++) continue;
  return *v == 0;
}

__attribute__((constructor)) static void record_environment(void) {
  const char *spin = getenv("GOMP_SPINCOUNT");
  policy_chosen = names_policy(getenv("OMP_WAIT_POLICY")) || (spin && *spin);
  long n = sysconf(_SC_NPROCESSORS_ONLN);
  online_procs = n > 0 && n < 1 << 20 ? (int)n : 0;
}

int mx_load_limit(int requested, int procs, int others) {
  if (others < 0 || procs < 1) return requested;
  int free_procs = procs - others;
  if (free_procs < 1) free_procs = 1;
  return requested < free_procs ? requested : free_procs;
}

/* The file's first bytes (NUL-terminated) into buf; -1 if unreadable. */
static ssize_t read_head(const char *path, char *buf, size_t n) {
  int fd = open(path, O_RDONLY | O_CLOEXEC);
  if (fd < 0) return -1;
  ssize_t got = read(fd, buf, n - 1);
  close(fd);
  if (got < 0) return -1;
  buf[got] = 0;
  return got;
}

/* "0.52 0.58 0.59 3/102 4242": the 3. */
static int loadavg_running(void) {
  char buf[128];
  if (read_head("/proc/loadavg", buf, sizeof buf) <= 0) return -1;
  const char *p = buf;
  for (int field = 0; field < 3; field++) {
    p = strchr(p, ' ');
    if (!p) return -1;
    p++;
  }
  char *end;
  long r = strtol(p, &end, 10);
  return end != p && *end == '/' && r >= 0 && r < 1 << 24 ? (int)r : -1;
}

/* This process's threads in state R: "tid (comm) R ...", the state after
 * the last ')' (comm may hold one). -1 if the task folder cannot be read. */
static int own_running(void) {
  DIR *d = opendir("/proc/self/task");
  if (!d) return -1;
  int n = 0;
  struct dirent *e;
  char path[64], buf[256];
  while ((e = readdir(d)) != NULL) {
    if (e->d_name[0] < '0' || e->d_name[0] > '9') continue;
    snprintf(path, sizeof path, "/proc/self/task/%.20s/stat", e->d_name);
    if (read_head(path, buf, sizeof buf) <= 0) continue; /* it just ended */
    const char *close_paren = strrchr(buf, ')');
    if (close_paren && close_paren[1] == ' ' && close_paren[2] == 'R') n++;
  }
  closedir(d);
  return n;
}

/* One look: this process's threads in state R are read before and after
 * the running count, and the more of the two is ours (a thread of ours
 * that stops spinning, or wakes, while the count is read is still ours). */
static int look(void) {
  int own1 = own_running();
  int all = loadavg_running();
  int own2 = own_running();
  if (own1 < 0 || all < 0 || own2 < 0) return -1;
  int own = own1 > own2 ? own1 : own2;
  return all > own ? all - own : 0;
}

int mx_others_running(void) {
  /* A kernel worker or a short command runs for less than a millisecond
   * (on this machine, quiet, nearly 9 in 10 of them for less than 0.2 ms): when a
   * look sees other threads, look again 0.25 and 0.75 ms later and keep the
   * fewest. A quiet machine pays one look. */
  static const long pause_ns[] = {250000, 500000};
  int others = look();
  for (int k = 0; k < 2 && others > 0; k++) {
    struct timespec pause = {0, pause_ns[k]};
    nanosleep(&pause, NULL);
    int again = look();
    if (again >= 0 && again < others) others = again;
  }
  return others;
}

static int64_t now_ns(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (int64_t)ts.tv_sec * 1000000000 + ts.tv_nsec;
}

/* The last measure, shared by the process's threads: calls and stages that
 * follow each other within FRESH_NS use it (a stream of small calls reads
 * /proc at most every FRESH_NS). */
static _Atomic int64_t measured_at = INT64_MIN / 2;
static _Atomic int measured_others = -1;

static int others_recent(void) {
  const int64_t t = now_ns();
  if (t - atomic_load(&measured_at) < FRESH_NS) return atomic_load(&measured_others);
  int others = mx_others_running();
  atomic_store(&measured_others, others);
  atomic_store(&measured_at, now_ns());
  return others;
}

int mx_call_thread_count(int requested) {
  if (requested <= 1) return requested;
  const char *test = getenv("MIXOCT_TEST_BUSY");
  if (test && *test) {
    char *end;
    long busy = strtol(test, &end, 10);
    if (*end == 0 && busy >= 0 && busy < 1 << 24)
      return mx_load_limit(requested, online_procs, (int)busy);
  }
  if (policy_chosen) return requested;
  return mx_load_limit(requested, online_procs, others_recent());
}
