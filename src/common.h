/* mixoct: common definitions shared by every part of the library.
 * Status codes travel up through MX_CHECK, as in HXT: a function returns
 * MX_OK or an error code after printing one clear message on stderr. */
#ifndef MX_COMMON_H
#define MX_COMMON_H

#include <stddef.h>
#include <stdint.h>

enum {
  MX_OK = 0,
  MX_EINTERNAL = 1, /* a bug or an unexpected system failure */
  MX_EINPUT = 2,    /* bad input, bad usage, unwritable output, no memory */
};

#define MX_CHECK(expr)                                                        \
  do {                                                                        \
    int mx_status_ = (expr);                                                  \
    if (mx_status_ != MX_OK) return mx_status_;                               \
  } while (0)

/* Messages go to stderr, prefixed "mixoct: ". A message about a file names it
 * and, when known (line > 0), the line: "mixoct: FILE:LINE: text". */
void mx_error(const char *file, long line, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
void mx_warning(const char *file, long line, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
extern int mx_quiet; /* when set, warnings are not printed */

/* Allocation in one place: 64-byte aligned, zeroed on request. Failure prints
 * a message and returns NULL; callers return MX_EINPUT ("out of memory"). */
void *mx_alloc(size_t bytes);
void *mx_calloc(size_t bytes);
void *mx_realloc(void *p, size_t bytes);
void mx_free(void *p);

/* min/max of doubles that compile to one instruction (no NaN handling:
 * inputs are checked finite when read). */
static inline double mx_min(double a, double b) { return a < b ? a : b; }
static inline double mx_max(double a, double b) { return a > b ? a : b; }

double mx_wtime(void);        /* wall clock seconds */
double mx_peak_rss_mb(void);  /* peak resident set size of this process */

#endif
