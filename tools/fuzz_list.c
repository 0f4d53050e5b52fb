/* libFuzzer target for the element index lists (src/io/element_list.c) and
 * the word display of their messages (mx_show_word, src/base/common.c).
 *
 * Each input is parsed as a list (mx_parse_index_list) with a limit of 1000
 * and with none (UINT64_MAX), taken as one word (mx_word_index) and shown
 * (mx_show_word). Promises, any break aborts:
 *   - a list that parses has its indices below the limit, parses the same
 *     without a limit, and reads back the same when written one index a
 *     line; a list refused with the limit but not without one has an index
 *     >= 1000; a refused list gives NULL, 0 and exactly one error message;
 *   - every message is printable: no control byte, valid UTF-8 without C1
 *     controls (file names and words of the input are escaped);
 *   - a word read as an index below 2^53 is the double strtod reads (which
 *     rounds correctly, and such integers are exact); a word refused as
 *     not a number is not one strtod reads whole, but for the forms left
 *     out on purpose (hexadecimal, "nan(...)");
 *   - mx_show_word writes at most MX_WORD_BUF bytes, printable as above,
 *     and gives a short word of plain ASCII back as it is.
 *
 * Build and run: tools/fuzz.sh SECONDS list (seeds in tools/fuzz_seeds/list);
 * by hand, from the source root, once fuzz.sh has built its archive:
 *   clang -std=c17 -g -O1 -fsanitize=fuzzer,address,undefined -fopenmp \
 *     -D_GNU_SOURCE -Isrc -Iinclude tools/fuzz_list.c \
 *     build-fuzz/libmixoct_fuzz.a -lm -o fuzz_list
 * (a copy of src/base/common.c that escaped only C0 controls in messages, put
 * before the archive, aborts on the seeds: the byte 0xff of the name). */
#include <ctype.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "base/common.h"
#include "io/element_list.h"

#define REQUIRE(cond)                                                          \
  do {                                                                         \
    if (!(cond)) {                                                             \
      fprintf(stderr, "fuzz_list: %s:%d: broken promise: %s\n", __FILE__,      \
              __LINE__, #cond);                                                \
      abort();                                                                 \
    }                                                                          \
  } while (0)

enum { LIMIT = 1000 };

/* Valid UTF-8 without control bytes (C0, DEL, C1). */
static int printable(const char *s, size_t n) {
  const unsigned char *p = (const unsigned char *)s;
  for (size_t i = 0; i < n;) {
    const unsigned c = p[i];
    if (c < 0x20 || c == 0x7f) return 0;
    if (c < 0x80) {
      i++;
      continue;
    }
    size_t k = c >= 0xf0 ? 4 : c >= 0xe0 ? 3 : 2;
    if (c < 0xc2 || c > 0xf4 || i + k > n) return 0;
    uint32_t cp = c & (0x7f >> k);
    for (size_t j = 1; j < k; j++) {
      if ((p[i + j] & 0xc0) != 0x80) return 0;
      cp = cp << 6 | (p[i + j] & 0x3f);
    }
    const uint32_t least = k == 2 ? 0x80 : k == 3 ? 0x800 : 0x10000;
    if (cp < least || cp > 0x10ffff || (cp >= 0xd800 && cp <= 0xdfff) ||
        (cp >= 0x80 && cp <= 0x9f))
      return 0;
    i += k;
  }
  return 1;
}

static int nerrors, nwarnings;

static void on_message(void *user, int kind, const char *text) {
  (void)user;
  nerrors += kind == MX_MSG_ERROR;
  nwarnings += kind == MX_MSG_WARNING;
  REQUIRE(printable(text, strlen(text)));
}

int LLVMFuzzerInitialize(int *argc, char ***argv);
int LLVMFuzzerInitialize(int *argc, char ***argv) {
  (void)argc;
  (void)argv;
  mx_msg_fn = on_message;
  return 0;
}

/* Parses with the limit; checks the promises of a result. */
static int parse(const uint8_t *data, size_t size, uint64_t limit, uint64_t **v, size_t *n) {
  nerrors = nwarnings = 0;
  const int st = mx_parse_index_list("fuzz\x1b\xff.txt", data, size, limit, v, n);
  if (st == MX_OK) {
    REQUIRE(*v != NULL && nerrors == 0 && nwarnings == (*n == 0));
    for (size_t i = 0; i < *n; i++) REQUIRE((*v)[i] < limit);
  } else {
    REQUIRE(st == MX_EINPUT && *v == NULL && *n == 0 && nerrors == 1);
  }
  return st;
}

static void lists(const uint8_t *data, size_t size) {
  uint64_t *a, *b;
  size_t na, nb;
  const int sa = parse(data, size, LIMIT, &a, &na);
  const int sb = parse(data, size, UINT64_MAX, &b, &nb);
  if (sa == MX_OK) {
    REQUIRE(sb == MX_OK && na == nb && memcmp(a, b, na * sizeof *a) == 0);
    /* written one a line, read back */
    char *text = malloc(21 * na + 1), *p = text;
    REQUIRE(text != NULL);
    for (size_t i = 0; i < na; i++) p += sprintf(p, "%llu\n", (unsigned long long)a[i]);
    uint64_t *c;
    size_t nc;
    REQUIRE(parse((const uint8_t *)text, (size_t)(p - text), LIMIT, &c, &nc) == MX_OK);
    REQUIRE(nc == na && memcmp(a, c, na * sizeof *a) == 0);
    mx_free(c);
    free(text);
  } else if (sb == MX_OK) {
    int over = 0;
    for (size_t i = 0; i < nb; i++) over |= b[i] >= LIMIT;
    REQUIRE(over);
  }
  if (sa == MX_OK) mx_free(a);
  if (sb == MX_OK) mx_free(b);
}

static void one_word(const uint8_t *data, size_t size) {
  uint64_t v;
  const int code = mx_word_index((const char *)data, size, &v);
  REQUIRE(code >= MX_WORD_INDEX && code <= MX_WORD_TOO_LARGE);
  REQUIRE(code == MX_WORD_INDEX || v == 0);
  char *w = malloc(size + 1);
  REQUIRE(w != NULL);
  memcpy(w, data, size);
  w[size] = '\0';
  char *end;
  const double d = strtod(w, &end);
  /* strtod reads all of the word (and skips no leading blank: a word of
   * a list has none) */
  const int whole = size > 0 && end == w + size && !isspace((unsigned char)w[0]);
  if (code == MX_WORD_INDEX && v <= (UINT64_C(1) << 53)) REQUIRE(whole && d == (double)v);
  if (code == MX_WORD_NOT_NUMBER && whole) REQUIRE(strpbrk(w, "xX(") != NULL);
  if (code == MX_WORD_NOT_FINITE) REQUIRE(whole && !isfinite(d));
  if (code == MX_WORD_NEGATIVE) REQUIRE(whole && signbit(d));
  free(w);
}

static void show(const uint8_t *data, size_t size) {
  char out[MX_WORD_BUF + 1];
  out[MX_WORD_BUF] = 'G'; /* a guard: the buffer is MX_WORD_BUF bytes */
  REQUIRE(mx_show_word(data, size, out) == out);
  const size_t n = strlen(out);
  REQUIRE(n < MX_WORD_BUF && out[MX_WORD_BUF] == 'G');
  REQUIRE(printable(out, n));
  int plain = size <= MX_WORD_SHOW;
  for (size_t i = 0; plain && i < size; i++)
    plain = data[i] >= 0x20 && data[i] < 0x7f && data[i] != '\\';
  if (plain) REQUIRE(n == size && memcmp(out, data, size) == 0);
  if (size > MX_WORD_SHOW) REQUIRE(n >= 3 && memcmp(out + n - 3, "...", 3) == 0);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  lists(data, size);
  one_word(data, size);
  show(data, size);
  return 0;
}
