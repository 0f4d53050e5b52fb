/* A minimal test harness: CHECK(cond) counts failures and prints where. */
#ifndef MX_TEST_CHECK_H
#define MX_TEST_CHECK_H
#include <stdio.h>
static int mx_test_failures = 0;
#define CHECK(cond)                                                         \
  do {                                                                      \
    if (!(cond)) {                                                          \
      fprintf(stderr, "%s:%d: CHECK failed: %s\n", __FILE__, __LINE__,      \
              #cond);                                                       \
      mx_test_failures++;                                                   \
    }                                                                       \
  } while (0)
#define TEST_DONE()                                                         \
  (mx_test_failures ? (fprintf(stderr, "%d check(s) failed\n",              \
                               mx_test_failures), 1) : 0)
#endif
