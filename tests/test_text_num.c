/* io/text_num: the integer and "%+1.8E" printers against printf, on the
 * places where digit counts, rounding and exponents change and on random
 * values. */
#include "io/text_num.h"

#include <float.h>
#include <inttypes.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

static int failures;
static void check_u64(uint64_t v) {
  char got[MX_U64_CHARS + 1], want[32];
  const size_t n = mx_put_u64(got, v);
  got[n] = '\0';
  snprintf(want, sizeof want, "%" PRIu64, v);
  if (strcmp(got, want) != 0 && failures++ < 20)
    fprintf(stderr, "mx_put_u64(%s) gave %s\n", want, got);
}

static void check_e8(double x) {
  char got[MX_E8_CHARS + 8], want[64];
  memset(got, '#', sizeof got);
  const size_t n = mx_put_e8(got, x);
  const int wn = snprintf(want, sizeof want, "%+1.8E", x);
  if ((n != (size_t)wn || memcmp(got, want, n) != 0 || n > MX_E8_CHARS) && failures++ < 20)
    fprintf(stderr, "mx_put_e8(%s) gave %.*s\n", want, (int)n, got);
}

static uint64_t rng = 0x243F6A8885A308D3ull;
static uint64_t next(void) {
  rng ^= rng << 13;
  rng ^= rng >> 7;
  rng ^= rng << 17;
  return rng;
}

int main(void) {
  uint64_t p = 1;
  check_u64(0);
  for (int k = 0; k < 20; k++, p *= 10) {
    check_u64(p - 1);
    check_u64(p);
    check_u64(p + 1);
  }
  check_u64(UINT32_MAX);
  check_u64((uint64_t)UINT32_MAX + 1);
  check_u64(UINT64_MAX);
  for (int i = 0; i < 1000000; i++) check_u64(next() >> (next() % 64));
  /* doubles: the fast path's ends, rounding at the 9th digit (ties on
   * exact binary values), exponents of one, two and three digits */
  const double special[] = {0.0, -0.0, 1.0, -1.0, 0.5, 1.5, 2.5, 1e-14, 9.9999999e-15, 1e9, 999999999.5,
                            9.999999995, 9.9999999949999, 1.000000005, 1.000000015, 0.1, 1.0 / 3,
                            123456789.0, 1e-300, 1e300, DBL_MIN, DBL_MAX, 4.9e-324, INFINITY,
                            -INFINITY, NAN, 2.85692e-01, 67.617746};
  for (size_t i = 0; i < sizeof special / sizeof special[0]; i++) {
    check_e8(special[i]);
    check_e8(-special[i]);
  }
  for (int i = 0; i < 1000000; i++) {
    double x;
    const uint64_t b = next();
    if (i % 3 == 0) memcpy(&x, &b, sizeof x); /* any bits */
    else if (i % 3 == 1) x = ldexp((double)(b >> 11), (int)(next() % 120) - 100); /* wide range */
    else x = (double)(b % 2000000000) / 1e8 * ((i & 8) ? -1 : 1); /* short decimals, ties */
    check_e8(x);
  }
  printf("%s\n", failures ? "FAIL" : "ok");
  return failures != 0;
}
