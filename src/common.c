#include "common.h"

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <time.h>

int mx_quiet = 0;

static void vreport(const char *kind, const char *file, long line,
                    const char *fmt, va_list ap) {
  char msg[1024];
  vsnprintf(msg, sizeof msg, fmt, ap);
  if (file && line > 0)
    fprintf(stderr, "mixoct: %s:%ld: %s%s\n", file, line, kind, msg);
  else if (file)
    fprintf(stderr, "mixoct: %s: %s%s\n", file, kind, msg);
  else
    fprintf(stderr, "mixoct: %s%s\n", kind, msg);
}

void mx_error(const char *file, long line, const char *fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  vreport("error: ", file, line, fmt, ap);
  va_end(ap);
}

void mx_warning(const char *file, long line, const char *fmt, ...) {
  if (mx_quiet) return;
  va_list ap;
  va_start(ap, fmt);
  vreport("warning: ", file, line, fmt, ap);
  va_end(ap);
}

void *mx_alloc(size_t bytes) {
  if (bytes == 0) bytes = 1;
  size_t rounded = (bytes + 63) & ~(size_t)63;
  void *p = aligned_alloc(64, rounded);
  if (!p) mx_error(NULL, 0, "out of memory (asked for %zu bytes)", bytes);
  return p;
}

void *mx_calloc(size_t bytes) {
  void *p = mx_alloc(bytes);
  if (p) memset(p, 0, bytes);
  return p;
}

void *mx_realloc(void *p, size_t bytes) {
  void *q = realloc(p, bytes ? bytes : 1);
  if (!q) mx_error(NULL, 0, "out of memory (asked for %zu bytes)", bytes);
  return q;
}

void mx_free(void *p) { free(p); }

double mx_wtime(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

double mx_peak_rss_mb(void) {
  struct rusage ru;
  if (getrusage(RUSAGE_SELF, &ru) != 0) return 0.0;
  return (double)ru.ru_maxrss / 1024.0; /* ru_maxrss is in KiB on Linux */
}
