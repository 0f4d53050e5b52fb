/* A minimal test harness: CHECK(cond) counts failures and prints where. */
#ifndef MX_TEST_CHECK_H
#define MX_TEST_CHECK_H
#include <stdio.h>
#include <stdlib.h>
static int mx_test_failures = 0;
#define CHECK(cond)                                                         \
  do {                                                                      \
    if (!(cond)) {                                                          \
      fprintf(stderr, "%s:%d: CHECK failed: %s\n", __FILE__, __LINE__,      \
              #cond);                                                       \
      mx_test_failures++;                                                   \
    }                                                                       \
  } while (0)
/* Shared data that is not there (../shared/data, MIXOCT_DATA): a SKIP line,
 * or, when the environment variable CI is set, a failure, so that a CI run
 * never passes without the data. */
#define TEST_DATA_MISSING(...)                                              \
  do {                                                                      \
    const char *ci_ = getenv("CI");                                         \
    char what_[4608];                                                       \
    snprintf(what_, sizeof what_, __VA_ARGS__);                             \
    if (ci_ && *ci_) {                                                      \
      fprintf(stderr, "FAIL %s (CI is set: the data must be there)\n", what_); \
      mx_test_failures++;                                                   \
    } else {                                                                \
      printf("SKIP %s\n", what_);                                           \
    }                                                                       \
  } while (0)
#define TEST_DONE()                                                         \
  (mx_test_failures ? (fprintf(stderr, "%d check(s) failed\n",              \
                               mx_test_failures), 1) : 0)
#endif
