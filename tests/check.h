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
#ifdef MIXOCT_TEST_DATA
#include <string.h>
#include <unistd.h>
/* The folder of the shared data (../shared/data next to the project):
 * MIXOCT_DATA from the environment when it holds `probe` (a path relative
 * to the folder, such as "surfaces/cortex.off"), else the folder meson
 * compiled in from the source tree (MIXOCT_TEST_DATA); NULL when neither
 * holds it (the caller then says TEST_DATA_MISSING). */
static inline const char *test_data_dir(const char *probe) {
  static char dir[400];
  const char *dirs[] = {getenv("MIXOCT_DATA"), MIXOCT_TEST_DATA};
  for (int i = 0; i < 2; i++) {
    if (!dirs[i] || !*dirs[i]) continue;
    char p[1200];
    snprintf(p, sizeof p, "%s/%s", dirs[i], probe);
    if (access(p, R_OK) == 0) {
      snprintf(dir, sizeof dir, "%s", dirs[i]);
      return dir;
    }
  }
  return NULL;
}
#endif
#define TEST_DONE()                                                         \
  (mx_test_failures ? (fprintf(stderr, "%d check(s) failed\n",              \
                               mx_test_failures), 1) : 0)
#endif
