/* See load_limit.h. */
#include "mesher/load_limit.h"

#include <dirent.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

/* Recorded once, when the library is loaded: libgomp (loaded before us, a
 * dependency) read the same environment when it was loaded. A variable set
 * later changes nothing in libgomp, so it changes nothing here either. */
static int policy_chosen; /* OMP_WAIT_POLICY or GOMP_SPINCOUNT was set */
static int online_procs;  /* processors online (what /proc/loadavg counts on) */

__attribute__((constructor)) static void record_environment(void) {
  policy_chosen = getenv("OMP_WAIT_POLICY") != NULL || getenv("GOMP_SPINCOUNT") != NULL;
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

int mx_others_running(void) {
  int all = loadavg_running();
  if (all < 0) return -1;
  int own = own_running();
  if (own < 0) return -1;
  /* the two are read one after the other: a thread of ours may have
   * started running in between */
  return all > own ? all - own : 0;
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
  return mx_load_limit(requested, online_procs, mx_others_running());
}
