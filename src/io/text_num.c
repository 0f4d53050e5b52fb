/* mixoct: numbers as ASCII text (see text_num.h). */
#include "io/text_num.h"

#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <string.h>

#ifndef __SIZEOF_INT128__
#error "mx_put_double needs a 128-bit integer type (unsigned __int128)"
#endif

/* ---- integers ------------------------------------------------------------ */

static const char digit_pairs[201] =
    "00010203040506070809101112131415161718192021222324252627282930313233343536"
    "37383940414243444546474849505152535455565758596061626364656667686970717273"
    "7475767778798081828384858687888990919293949596979899";

static const uint64_t pow10_u64[20] = {1ull,
                                       10ull,
                                       100ull,
                                       1000ull,
                                       10000ull,
                                       100000ull,
                                       1000000ull,
                                       10000000ull,
                                       100000000ull,
                                       1000000000ull,
                                       10000000000ull,
                                       100000000000ull,
                                       1000000000000ull,
                                       10000000000000ull,
                                       100000000000000ull,
                                       1000000000000000ull,
                                       10000000000000000ull,
                                       100000000000000000ull,
                                       1000000000000000000ull,
                                       10000000000000000000ull};

/* Digits of v >= 1: the bit length times log10(2) (1233 / 4096) is the count or
 * one too many. */
static inline size_t decimal_digits(uint64_t v) {
  const unsigned bits = 64u - (unsigned)__builtin_clzll(v | 1u);
  const unsigned t = (bits * 1233u) >> 12;
  return (size_t)t + 1u - (v < pow10_u64[t]);
}

/* The digits are written from the end, two at a time, straight to out. */
size_t mx_put_u64(char *out, uint64_t v) {
  if (v < 10u) {
    *out = (char)('0' + v);
    return 1;
  }
  const size_t n = decimal_digits(v);
  char *p = out + n;
  while (v > UINT32_MAX) {
    const unsigned r = (unsigned)(v % 100u);
    v /= 100u;
    p -= 2;
    memcpy(p, digit_pairs + 2 * r, 2);
  }
  uint32_t w = (uint32_t)v; /* 32-bit divisions from here */
  while (w >= 100u) {
    const unsigned r = w % 100u;
    w /= 100u;
    p -= 2;
    memcpy(p, digit_pairs + 2 * r, 2);
  }
  if (w >= 10u) memcpy(p - 2, digit_pairs + 2 * w, 2);
  else p[-1] = (char)('0' + w);
  return n;
}

/* x as printf's "%+1.8E" writes it, rounded as printf rounds (to nearest,
 * ties to even, on the exact binary value). For 1e-14 <= |x| < 1e9 the
 * 9 digits come from exact 128-bit integer arithmetic: x = m 2^e with
 * e < 0, D = round(m 10^k 2^e), 10^8 <= D < 10^9; anything else goes to
 * snprintf. Writes at most 16 bytes; returns how many. */
size_t mx_put_e8(char *out, double x) {
  double a = fabs(x);
  if (a >= 1e-14 && a < 1e9) {
    int e2;
    uint64_t m = (uint64_t)ldexp(frexp(a, &e2), 53);
    int shift = 53 - e2; /* a = m / 2^shift, 23 < shift < 100 */
    int d = (int)floor(log10(a));
    for (int tries = 0; tries < 3; tries++) {
      int k = 8 - d;
      if (k < 0 || k > 22) break;
      unsigned __int128 n = (unsigned __int128)m * pow10_u64[k < 19 ? k : 19];
      if (k > 19) n *= pow10_u64[k - 19];
      unsigned __int128 q = n >> shift;
      if (q >= 1000000000ull) {
        d++;
        continue;
      }
      uint64_t digits = (uint64_t)q;
      if (digits < 100000000ull) {
        d--;
        continue;
      }
      unsigned __int128 half = (unsigned __int128)1 << (shift - 1);
      unsigned __int128 rest = n & ((half << 1) - 1);
      if (rest > half || (rest == half && (digits & 1))) digits++;
      if (digits == 1000000000ull) { /* 9.99999999|5 -> 1.00000000E+(d+1) */
        digits = 100000000ull;
        d++;
      }
      char *o = out;
      *o++ = x < 0 ? '-' : '+';
      *o++ = (char)('0' + digits / 100000000ull);
      *o++ = '.';
      uint64_t low = digits % 100000000ull;
      for (int i = 7; i >= 0; i--, low /= 10) o[i] = (char)('0' + low % 10);
      o += 8;
      *o++ = 'E';
      *o++ = d < 0 ? '-' : '+';
      int ad = d < 0 ? -d : d;
      *o++ = (char)('0' + ad / 10);
      *o++ = (char)('0' + ad % 10);
      return (size_t)(o - out);
    }
  }
  /* the rest (and inf, nan) from snprintf, with '.' whatever the locale */
  char tmp[48];
  const int n = snprintf(tmp, sizeof tmp, "%+1.8E", x);
  if (n <= 0 || n > MX_E8_CHARS) return 0;
  for (int i = 0; i < n; i++) out[i] = tmp[i] >= '0' || tmp[i] == '+' || tmp[i] == '-' ? tmp[i] : '.';
  return (size_t)n;
}

size_t mx_put_i64(char *out, int64_t v) {
  if (v >= 0) return mx_put_u64(out, (uint64_t)v);
  out[0] = '-';
  return 1 + mx_put_u64(out + 1, (uint64_t)0 - (uint64_t)v);
}

/* ---- doubles -------------------------------------------------------------
 *
 * x = m * 2^e is scaled by a 64-bit approximation of 10^k (relative error
 * <= 2^-64) with an exact 128-bit product and rounded to the 17-digit
 * integer D = round(x * 10^k), 10^16 <= D < 10^17. The error is below
 * 0.5 + 10^17 * 2^-64 < 0.506 units of the 17th digit, and one such unit is
 * below 0.9008 ulp of x (2^53 / 10^16), so D * 10^-k lies within 0.456 ulp
 * of x: it reads back as x, like "%.17g". When D rounded to 15 digits reads
 * back as x too (checked exactly in double arithmetic: an integer below
 * 2^53 times or over an exact power of ten up to 10^22 is one correctly
 * rounded operation, what a correct strtod returns for that decimal) the
 * shorter form is written, so 0.1 comes out as "0.1". Only integer
 * arithmetic and that one check: no long double, no dependence on the
 * rounding mode beyond the default round-to-nearest. */

enum { POW10_MIN = -300, POW10_MAX = 350, BIG_LIMBS = 44, BIG_SHIFT = 1280 };

typedef struct {
  uint64_t mant; /* in [2^63, 2^64) */
  int exp2;      /* 10^k ~= mant * 2^exp2 */
} pow10_entry;

static pow10_entry pow10_table[POW10_MAX - POW10_MIN + 1];
static pthread_once_t pow10_once = PTHREAD_ONCE_INIT;
static atomic_int pow10_ready; /* set (release) once the table is built */

/* Little-endian 32-bit limbs; value = sum limb[i] * 2^(32 i). */
typedef struct {
  uint32_t limb[BIG_LIMBS];
} bignum;

static void big_mul10(bignum *b) {
  uint64_t carry = 0;
  for (int i = 0; i < BIG_LIMBS; i++) {
    uint64_t v = (uint64_t)b->limb[i] * 10 + carry;
    b->limb[i] = (uint32_t)v;
    carry = v >> 32;
  }
}

static void big_div10(bignum *b) {
  uint64_t rem = 0;
  for (int i = BIG_LIMBS - 1; i >= 0; i--) {
    uint64_t v = (rem << 32) | b->limb[i];
    b->limb[i] = (uint32_t)(v / 10);
    rem = v % 10;
  }
}

static int big_bit(const bignum *b, int i) {
  return i < 0 ? 0 : (int)((b->limb[i / 32] >> (i % 32)) & 1);
}

/* The top 64 bits of b, rounded to nearest; b ~= mant * 2^exp2. */
static pow10_entry big_top64(const bignum *b) {
  int top = 32 * BIG_LIMBS - 1;
  while (top > 0 && !big_bit(b, top)) top--;
  uint64_t mant = 0;
  for (int i = top; i > top - 64; i--)
    mant = (mant << 1) | (uint64_t)big_bit(b, i);
  int exp2 = top - 63;
  if (big_bit(b, top - 64)) {
    mant++;
    if (mant == 0) { /* carried out: 2^64 */
      mant = (uint64_t)1 << 63;
      exp2++;
    }
  }
  return (pow10_entry){mant, exp2};
}

/* 10^k for k >= 0 exactly; 10^-j as floor(2^BIG_SHIFT / 10^j) / 2^BIG_SHIFT,
 * whose truncation errors stay far below the 64 bits kept. */
static void pow10_init(void) {
  bignum b;
  memset(&b, 0, sizeof b);
  b.limb[0] = 1;
  for (int k = 0; k <= POW10_MAX; k++) {
    pow10_table[k - POW10_MIN] = big_top64(&b);
    big_mul10(&b);
  }
  memset(&b, 0, sizeof b);
  b.limb[BIG_SHIFT / 32] = 1;
  for (int j = 1; j <= -POW10_MIN; j++) {
    big_div10(&b);
    pow10_entry e = big_top64(&b);
    e.exp2 -= BIG_SHIFT;
    pow10_table[-j - POW10_MIN] = e;
  }
  atomic_store_explicit(&pow10_ready, 1, memory_order_release);
}

/* The table, built by the first caller; later calls cost one load. */
static inline void pow10_ensure(void) {
  if (!atomic_load_explicit(&pow10_ready, memory_order_acquire))
    pthread_once(&pow10_once, pow10_init);
}

/* round(m * 2^e * 10^k), for results below 2^64. */
static uint64_t scale_round(uint64_t m, int e, int k) {
  const pow10_entry *p = &pow10_table[k - POW10_MIN];
  unsigned __int128 prod = (unsigned __int128)m * p->mant;
  int shift = -(e + p->exp2); /* in [6, 127] for the k used here */
  uint64_t whole = (uint64_t)(prod >> shift);
  unsigned __int128 half = (unsigned __int128)1 << (shift - 1);
  unsigned __int128 rest = prod & ((half << 1) - 1);
  return whole + (rest >= half);
}

/* 17 significant digits of |x| (finite, non-zero): D and the decimal
 * exponent E of its first digit, x ~= D * 10^(E - 16). */
static uint64_t digits17(double x, int *E) {
  const uint64_t lo = 10000000000000000ull, hi = 100000000000000000ull;
  uint64_t bits;
  memcpy(&bits, &x, 8);
  int be = (int)((bits >> 52) & 0x7ff);
  uint64_t m = bits & (((uint64_t)1 << 52) - 1);
  int e = be ? be - 1075 : -1074;
  if (be) m |= (uint64_t)1 << 52;
  /* decimal exponent estimate from the binary one: off by at most one */
  int log2x = e + 63 - __builtin_clzll(m);
  int k = 16 - (int)floor(log2x * 0.30102999566398120);
  uint64_t d = scale_round(m, e, k);
  for (int tries = 0; tries < 3 && (d < lo || d >= hi); tries++) {
    k += d < lo ? 1 : -1;
    d = scale_round(m, e, k);
  }
  *E = 16 - k;
  return d;
}

/* Whether the decimal d * 10^p reads back as ax (exact when it applies). */
static int reads_back(uint64_t d, int p, double ax) {
  static const double p10[23] = {1e0,  1e1,  1e2,  1e3,  1e4,  1e5,  1e6,  1e7,
                                 1e8,  1e9,  1e10, 1e11, 1e12, 1e13, 1e14, 1e15,
                                 1e16, 1e17, 1e18, 1e19, 1e20, 1e21, 1e22};
  if (d >= ((uint64_t)1 << 53) || p > 22 || p < -22) return 0;
  double v = (double)d;
  return (p >= 0 ? v * p10[p] : v / p10[-p]) == ax;
}

/* Writes the ndig digits of d with decimal exponent E like "%g" does. */
static size_t put_decimal(char *out, uint64_t d, int ndig, int E) {
  char dig[MX_U64_CHARS];
  mx_put_u64(dig, d);
  size_t n = 0;
  if (E >= 0 && E < 17) {
    for (int i = 0; i <= E; i++) out[n++] = i < ndig ? dig[i] : '0';
    if (ndig > E + 1) out[n++] = '.';
    for (int i = E + 1; i < ndig; i++) out[n++] = dig[i];
  } else if (E < 0 && E >= -4) {
    out[n++] = '0';
    out[n++] = '.';
    for (int i = -1; i > E; i--) out[n++] = '0';
    for (int i = 0; i < ndig; i++) out[n++] = dig[i];
  } else {
    out[n++] = dig[0];
    if (ndig > 1) out[n++] = '.';
    for (int i = 1; i < ndig; i++) out[n++] = dig[i];
    out[n++] = 'e';
    out[n++] = E < 0 ? '-' : '+';
    if (E > -10 && E < 10) out[n++] = '0';
    n += mx_put_u64(out + n, (uint64_t)(E < 0 ? -E : E));
  }
  return n;
}

size_t mx_put_double(char *out, double x) {
  size_t n = 0;
  if (signbit(x)) out[n++] = '-';
  double ax = fabs(x);
  if (ax == 0.0 || !isfinite(ax)) {
    const char *s = ax == 0.0 ? "0" : isnan(ax) ? "nan" : "inf";
    memcpy(out + n, s, strlen(s));
    return n + strlen(s);
  }
  pow10_ensure();
  int E;
  uint64_t d = digits17(ax, &E);
  int ndig = 17;
  uint64_t d15 = (d + 50) / 100; /* 15 digits (16 if it rounded up) */
  int E15 = E + (d15 >= 1000000000000000ull);
  if (d15 >= 1000000000000000ull) d15 /= 10;
  if (reads_back(d15, E15 - 14, ax)) {
    d = d15;
    E = E15;
    ndig = 15;
  }
  while (ndig > 1 && d % 10 == 0) {
    d /= 10;
    ndig--;
  }
  return n + put_decimal(out + n, d, ndig, E);
}

size_t mx_put_xyz_lines(char *out, const double *xyz, size_t begin,
                        size_t end) {
  size_t n = 0;
  for (size_t i = begin; i < end; i++) {
    for (int d = 0; d < 3; d++) {
      n += mx_put_double(out + n, xyz[3 * i + d]);
      out[n++] = d < 2 ? ' ' : '\n';
    }
  }
  return n;
}
