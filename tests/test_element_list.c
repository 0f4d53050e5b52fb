/* Tests of the element index lists (src/io/element_list.h) and of the word
 * display of messages (mx_show_word, src/base/common.h).
 *
 * - mx_word_index on integers, whole reals in every spelling numpy and
 *   printf write, fractions, negatives, NaN and infinities, overflow at
 *   2^64, and words that are not numbers.
 * - mx_show_word: control bytes, backslashes, invalid and valid UTF-8, C1
 *   controls and long words come out printable and cut.
 * - Lists from memory and from files: numpy.savetxt output (default, and
 *   delimiter=','), "12.0", "1.2e+01", CR LF line ends, comments, a
 *   byte-order mark, and every refusal with its file, line and word;
 *   empty lists are read with a warning; missing files and directories
 *   are refused; the published list.txt gives 1,139 indices.
 * Exit status: 0, 1 on a failure. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "check.h"
#include "base/common.h"
#include "io/element_list.h"

/* ---- messages ----------------------------------------------------------- */

static char msgs[8192];
static int nerr, nwarn;

static void on_message(void *user, int kind, const char *text) {
  (void)user;
  nerr += kind == MX_MSG_ERROR;
  nwarn += kind == MX_MSG_WARNING;
  size_t n = strlen(msgs);
  snprintf(msgs + n, sizeof msgs - n, "%s\n", text);
}

static void clear(void) {
  msgs[0] = '\0';
  nerr = nwarn = 0;
}

/* ---- words ------------------------------------------------------------- */

static void word(const char *w, int code, uint64_t want) {
  uint64_t v = 12345;
  const int got = mx_word_index(w, strlen(w), &v);
  const int ok = got == code && v == (code == MX_WORD_INDEX ? want : 0);
  CHECK(ok);
  if (!ok)
    printf("FAIL word \"%s\": code %d value %llu, expected %d %llu\n", w, got,
           (unsigned long long)v, code, (unsigned long long)want);
}

static void test_words(void) {
  const int I = MX_WORD_INDEX, X = MX_WORD_NOT_NUMBER, F = MX_WORD_FRACTION,
            N = MX_WORD_NEGATIVE, L = MX_WORD_TOO_LARGE, U = MX_WORD_NOT_FINITE;
  /* integers */
  word("0", I, 0);
  word("12", I, 12);
  word("+12", I, 12);
  word("0012", I, 12);
  word("18446744073709551615", I, UINT64_MAX);
  word("18446744073709551616", L, 0);
  word("123456789012345678901234567890", L, 0);
  /* whole reals, as numpy.savetxt ("%.18e"), printf and people write them */
  word("1.000000000000000000e+00", I, 1);
  word("1.200000000000000000e+01", I, 12);
  word("2.620800000000000000e+04", I, 26208);
  word("0.000000000000000000e+00", I, 0);
  word("-0.000000000000000000e+00", I, 0);
  word("12.0", I, 12);
  word("12.", I, 12);
  word("1.2e+01", I, 12);
  word("1.2E1", I, 12);
  word("120e-1", I, 12);
  word(".12e2", I, 12);
  word("1e3", I, 1000);
  word("1e19", I, 10000000000000000000ull);
  word("1.8446744073709551615e19", I, UINT64_MAX);
  word("1e20", L, 0);
  word("1e999999999999999999999", L, 0);
  word("0e999999999999999999999", I, 0);
  word("9007199254740993.0", I, 9007199254740993ull); /* 2^53 + 1: exact */
  word("-0", I, 0);
  /* fractions, negatives, non-finite */
  word("12.5", F, 0);
  word("1.25e+01", F, 0);
  word("1e-1", F, 0);
  word("1e-999999999999999999999", F, 0);
  word("0.1", F, 0);
  word("-1", N, 0);
  word("-1.000000000000000000e+00", N, 0);
  word("-12.5", N, 0);
  word("nan", U, 0);
  word("NaN", U, 0);
  word("-inf", U, 0);
  word("+Infinity", U, 0);
  /* not numbers */
  word("", X, 0);
  word("abc", X, 0);
  word("+", X, 0);
  word("-", X, 0);
  word(".", X, 0);
  word("e5", X, 0);
  word("1e", X, 0);
  word("1e+", X, 0);
  word("1.2.3", X, 0);
  word("0x1f", X, 0);
  word("12abc", X, 0);
  word("1;2", X, 0);
  word("--1", X, 0);
  word("infinite", X, 0);
  word("nana", X, 0);
  word("1 2", X, 0); /* no separators inside a word */
}

/* ---- the word display of messages ---------------------------------------- */

static void shown(const char *w, size_t len, const char *want) {
  char out[MX_WORD_BUF];
  mx_show_word(w, len, out);
  const int ok = strcmp(out, want) == 0;
  CHECK(ok);
  if (!ok) printf("FAIL show: \"%s\", expected \"%s\"\n", out, want);
}

static void test_show(void) {
  shown("abc", 3, "abc");
  shown("a\tb\x1b[31m", 8, "a\\x09b\\x1b[31m");
  shown("a\0b", 3, "a\\x00b");
  shown("a\\b", 3, "a\\\\b");
  shown("\x7f", 1, "\\x7f");
  shown("caf\xc3\xa9", 5, "caf\xc3\xa9");                /* valid UTF-8 */
  shown("\xe2\x82\xac", 3, "\xe2\x82\xac");              /* euro sign */
  shown("\xf0\x9f\x98\x80", 4, "\xf0\x9f\x98\x80");      /* 4 bytes */
  shown("\xc3", 1, "\\xc3");                             /* cut sequence */
  shown("\xc3(", 2, "\\xc3(");
  shown("\xff\xfe", 2, "\\xff\\xfe");
  shown("\xc0\xaf", 2, "\\xc0\\xaf");                    /* overlong '/' */
  shown("\xed\xa0\x80", 3, "\\xed\\xa0\\x80");           /* a surrogate */
  shown("\xf4\x90\x80\x80", 4, "\\xf4\\x90\\x80\\x80");  /* > U+10FFFF */
  shown("\xc2\x9b", 2, "\\xc2\\x9b");                    /* C1 CSI */
  shown("\xc2\xa0", 2, "\xc2\xa0");                      /* no-break space */
  char longw[200], want[MX_WORD_BUF];
  memset(longw, 'x', sizeof longw);
  memset(want, 'x', MX_WORD_SHOW);
  strcpy(want + MX_WORD_SHOW, "...");
  shown(longw, sizeof longw, want);
  want[MX_WORD_SHOW] = '\0';
  shown(longw, MX_WORD_SHOW, want); /* exactly the limit: not cut */
  /* a character across the cut is left out whole */
  memcpy(longw + MX_WORD_SHOW - 1, "\xc3\xa9", 2);
  memset(want, 'x', MX_WORD_SHOW - 1);
  strcpy(want + MX_WORD_SHOW - 1, "...");
  shown(longw, sizeof longw, want);
  /* the worst case fills the buffer exactly */
  char ctl[100], out[MX_WORD_BUF];
  memset(ctl, 1, sizeof ctl);
  CHECK(strlen(mx_show_word(ctl, sizeof ctl, out)) == MX_WORD_BUF - 1);
}

/* ---- lists --------------------------------------------------------------- */

/* Parses text (len bytes; strlen when len is 0); expects n indices (want)
 * and `warnings` warnings, or, when line > 0, a refusal at that line whose
 * message holds needle. */
static void list_len(const char *what, const char *text, size_t len, uint64_t limit,
                     const uint64_t *want, size_t nwant, int warnings, long line,
                     const char *needle) {
  uint64_t *v = (uint64_t *)1;
  size_t n = 99;
  clear();
  const int rc = mx_parse_index_list("L.txt", text, len ? len : strlen(text), limit, &v, &n);
  int ok;
  if (line == 0) {
    ok = rc == MX_OK && v != NULL && n == nwant && nerr == 0 && nwarn == warnings &&
         (nwant == 0 || memcmp(v, want, nwant * sizeof *v) == 0);
  } else {
    char loc[64];
    snprintf(loc, sizeof loc, "L.txt:%ld: ", line);
    ok = rc == MX_EINPUT && v == NULL && n == 0 && nerr == 1 &&
         strncmp(msgs, loc, strlen(loc)) == 0 && strstr(msgs, needle) != NULL;
  }
  if (rc == MX_OK) mx_free(v);
  CHECK(ok);
  printf("%s %-26s %s", ok ? "ok  " : "FAIL", what, msgs[0] ? msgs : "read\n");
}

#define LIST(what, text, limit, ...)                                                     \
  do {                                                                                   \
    static const uint64_t w_[] = {__VA_ARGS__};                                          \
    list_len(what, text, 0, limit, w_, sizeof w_ / sizeof w_[0], 0, 0, NULL);            \
  } while (0)
#define REFUSED(what, text, limit, line, needle)                                         \
  list_len(what, text, 0, limit, NULL, 0, 0, line, needle)

static void test_lists(void) {
  /* numpy.savetxt(f, np.array([1, 5, 7])), and with delimiter=',' */
  LIST("numpy savetxt", "1.000000000000000000e+00\n5.000000000000000000e+00\n"
                        "7.000000000000000000e+00\n", 10, 1, 5, 7);
  LIST("numpy savetxt fmt=%d", "1\n5\n7\n", 10, 1, 5, 7);
  LIST("numpy delimiter=','", "1.000000000000000000e+00,5.000000000000000000e+00\n"
                              "7.000000000000000000e+00,0.000000000000000000e+00\n",
       10, 1, 5, 7, 0);
  LIST("numpy header", "# elements over the threshold\n3\n4\n", 10, 3, 4);
  LIST("12.0 and 1.2e+01", "12.0\n1.2e+01\n", 13, 12, 12);
  LIST("CR LF", "1\r\n2\r\n3\r\n", 10, 1, 2, 3);
  LIST("CR LF, no last line end", "1\r\n2", 10, 1, 2);
  LIST("comments", "1 # one\n#2\n  3#three\n# 4 5 6\n", 10, 1, 3);
  LIST("blanks and commas", " 1,\t2 ,3,,4\f5\v6\n", 10, 1, 2, 3, 4, 5, 6);
  LIST("byte-order mark", "\xef\xbb\xbf" "4\n", 10, 4);
  LIST("repeated", "2 2 2\n", 10, 2, 2, 2);
  LIST("last index", "9\n", 10, 9);
  /* empty lists: read, with a warning */
  list_len("empty", "", 0, 10, NULL, 0, 1, 0, NULL);
  list_len("blank", " \n\t\r\n", 0, 10, NULL, 0, 1, 0, NULL);
  list_len("comments only", "# nothing over the threshold\n", 0, 10, NULL, 0, 1, 0, NULL);
  /* refusals: file, line, word */
  REFUSED("abc", "1\n2\nabc\n", 10, 3, "\"abc\" is not an element index");
  REFUSED("a word in a line", "1 2 x3 4\n", 10, 1, "\"x3\" is not an element index");
  REFUSED("12.5", "1\n12.5\n", 20, 2, "element index \"12.5\" is not a whole number");
  REFUSED("-1", "1\n\n -1\n", 10, 3, "element index \"-1\" is negative");
  REFUSED("negative real", "-1.000000000000000000e+00\n", 10, 1, "is negative");
  REFUSED("out of range", "1 2\n3 10\n", 10, 2,
          "element index \"10\" is out of range: 10 elements, indices 0 to 9");
  REFUSED("out of range, real", "1.0e+01\n", 10, 1,
          "\"1.0e+01\" is out of range: 10 elements");
  REFUSED("no elements", "0\n", 0, 1, "out of range: there are no elements");
  REFUSED("overflow", "1\n123456789012345678901234567890\n", 10, 2, "out of range");
  REFUSED("overflow, no limit", "18446744073709551616\n", UINT64_MAX, 1,
          "too large (above 2^64 - 1)");
  REFUSED("nan", "nan\n", 10, 1, "\"nan\" is not a finite number");
  REFUSED("inf", "1\r\n-inf\r\n", 10, 2, "\"-inf\" is not a finite number");
  REFUSED("semicolons", "1;2;3\n", 10, 1, "\"1;2;3\" is not an element index");
  REFUSED("CR LF word", "1\r\nx\r\n", 10, 2, "\"x\" is not");
  REFUSED("control bytes", "1\n\x1b[2J\n", 10, 2, "\"\\x1b[2J\" is not");
  REFUSED("invalid UTF-8", "\xff\xfe" "1\n", 10, 1, "\"\\xff\\xfe1\" is not");
  list_len("NUL byte (6 bytes)", "1\n2\0003\n", 6, 10, NULL, 0, 0, 2, "\"2\\x003\" is not");
  char big[400];
  memset(big, '7', sizeof big - 2);
  big[10] = 'z';
  big[sizeof big - 2] = '\n';
  big[sizeof big - 1] = '\0';
  char needle[64] = "\"7777777777z";
  memset(needle + 12, '7', MX_WORD_SHOW - 11);
  strcpy(needle + MX_WORD_SHOW + 1, "...\" is not");
  REFUSED("long word cut", big, 10, 1, needle);
  /* a file name that is not UTF-8 is escaped in the message too */
  uint64_t *v;
  size_t n;
  clear();
  CHECK(mx_parse_index_list("L\xff\x1b.txt", "x\n", 2, 10, &v, &n) == MX_EINPUT);
  CHECK(strncmp(msgs, "L\\xff\\x1b.txt:1: \"x\"", 17) == 0);
  printf("%s %-26s %s", strncmp(msgs, "L\\xff\\x1b.txt:1: ", 14) == 0 ? "ok  " : "FAIL",
         "file name not UTF-8", msgs);
  /* a long list: the output grows past its first size */
  const size_t many = 5000;
  char *text = malloc(8 * many + 1), *p = text;
  for (size_t i = 0; i < many; i++) p += sprintf(p, "%zu\n", i % 977);
  clear();
  int rc = mx_parse_index_list("many", text, (size_t)(p - text), 977, &v, &n);
  int ok = rc == MX_OK && n == many;
  for (size_t i = 0; ok && i < n; i++) ok = v[i] == i % 977;
  CHECK(ok);
  printf("%s %-26s %zu indices\n", ok ? "ok  " : "FAIL", "5000 lines", n);
  if (rc == MX_OK) mx_free(v);
  free(text);
}

/* ---- files --------------------------------------------------------------- */

static void test_files(const char *dir, const char *data) {
  char path[4200];
  uint64_t *v;
  size_t n;
  snprintf(path, sizeof path, "%s/empty.txt", dir);
  FILE *f = fopen(path, "wb");
  CHECK(f != NULL);
  if (f) fclose(f);
  clear();
  int rc = mx_read_index_list(path, 10, &v, &n);
  CHECK(rc == MX_OK && n == 0 && v != NULL && nwarn == 1 && strstr(msgs, path));
  printf("%s empty file                 %s", rc == MX_OK && n == 0 ? "ok  " : "FAIL", msgs);
  if (rc == MX_OK) mx_free(v);
  snprintf(path, sizeof path, "%s/missing.txt", dir);
  clear();
  rc = mx_read_index_list(path, 10, &v, &n);
  CHECK(rc == MX_EINPUT && v == NULL && n == 0 && strstr(msgs, "cannot open"));
  printf("%s missing file               %s", rc == MX_EINPUT ? "ok  " : "FAIL", msgs);
  clear();
  rc = mx_read_index_list(dir, 10, &v, &n);
  CHECK(rc == MX_EINPUT && v == NULL && strstr(msgs, "directory"));
  printf("%s a directory                %s", rc == MX_EINPUT ? "ok  " : "FAIL", msgs);
  /* the public call, on a file */
  snprintf(path, sizeof path, "%s/np.txt", dir);
  f = fopen(path, "wb");
  CHECK(f != NULL);
  if (f) {
    fputs("3.000000000000000000e+00\n2.500000000000000000e+00\n", f);
    fclose(f);
  }
  clear();
  rc = mx_read_element_list(path, 10, &v, &n);
  CHECK(rc == MX_EINPUT && strstr(msgs, ":2: element index \"2.500000000000000000e+00\" is "
                                        "not a whole number"));
  printf("%s mx_read_element_list       %s", rc == MX_EINPUT ? "ok  " : "FAIL", msgs);
  snprintf(path, sizeof path, "%s/remesh/list.txt", data);
  if (access(path, R_OK) != 0) {
    TEST_DATA_MISSING("list.txt: %s not found (set MIXOCT_DATA)", path);
    return;
  }
  clear();
  rc = mx_read_element_list(path, 26209, &v, &n);
  const int ok = rc == MX_OK && n == 1139 && nerr == 0 && nwarn == 0 && v[0] == 6310;
  CHECK(ok);
  printf("%s list.txt: %zu element indices\n", ok ? "ok  " : "FAIL", n);
  if (rc == MX_OK) mx_free_array(v);
}

int main(void) {
  mx_msg_fn = on_message;
  char dir[] = "element_list_XXXXXX";
  if (!mkdtemp(dir)) {
    perror("mkdtemp");
    return 1;
  }
  const char *data = test_data_dir("remesh/c5.oct");
  if (!data) data = MIXOCT_TEST_DATA; /* the files' absence is said where they are read */
  test_words();
  test_show();
  test_lists();
  test_files(dir, data);
  char cmd[128];
  snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
  if (system(cmd) != 0) fprintf(stderr, "could not remove %s\n", dir);
  printf("element lists: %d failed\n", mx_test_failures);
  return TEST_DONE();
}
