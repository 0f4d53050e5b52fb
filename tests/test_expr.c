/* The size-field expressions (src/sizing/expr.h): values against the same
 * formulas in C, the block evaluation against the point one bit for bit,
 * the column and text of every kind of error, and random texts that must
 * compile or be refused, never crash. */
#include "check.h"
#include "base/common.h"
#include "sizing/expr.h"

#include <math.h>
#include <stdint.h>
#include <string.h>

/* ---- messages ---- */

static int n_msgs;
static char last_msg[4096];

static void keep(void *user, int level, const char *text) {
  (void)user, (void)level;
  n_msgs++;
  snprintf(last_msg, sizeof last_msg, "%s", text);
}

static uint64_t seed = 12345;
static uint64_t rnd(void) {
  seed = seed * 6364136223846793005ULL + 1442695040888963407ULL;
  return seed >> 33;
}
static double unif(double lo, double hi) { return lo + (hi - lo) * (double)rnd() / 2147483648.0; }

/* ---- values ---- */

typedef double (*cfn)(double x, double y, double z);
static double c0(double x, double y, double z) { (void)z; return 0.05 + 0.2 * sqrt(pow(x - 1, 2) + pow(y, 2)); }
static double c1(double x, double y, double z) { (void)y, (void)z; return -pow(x, 2); }
static double c2(double x, double y, double z) { (void)x, (void)y, (void)z; return 512; }
static double c3(double x, double y, double z) { (void)x, (void)y, (void)z; return -4; }
static double c4(double x, double y, double z) { return x - y - z; }
static double c5(double x, double y, double z) { (void)x, (void)y, (void)z; return 1; }
static double c6(double x, double y, double z) { return x / y / z; }
static double c7(double x, double y, double z) { return mx_min(mx_min(x, y), z); }
static double c8(double x, double y, double z) { return mx_max(mx_max(mx_max(x, y), z), 0.5); }
static double c9(double x, double y, double z) {
  return exp(-fabs(x)) * log(1 + pow(y, 2)) + sin(3.14159265358979323846 * z) -
         cos(2.71828182845904523536 * x);
}
static double c10(double x, double y, double z) { return 2 * x + 3 * y * z - z / 4; }
static double c11(double x, double y, double z) { (void)y, (void)z; return -pow(2, -x); }
static double c12(double x, double y, double z) { (void)z; return x - -y; }
static double c13(double x, double y, double z) { (void)z; return pow(fabs(x), pow(fabs(y), 0.5)); }
static double c14(double x, double y, double z) { return (x + y) * (y - z) / (1 + pow(z, 2)); }
static double c15(double x, double y, double z) { (void)z; return .5 + 1e-3 * x + 2.5E+4 * y - 3; }
static double c16(double x, double y, double z) { return sqrt(fabs(x * y * z)) + mx_min(x, 1) * mx_max(y, -1); }
static double c17(double x, double y, double z) { (void)y, (void)z; return -(-x); }
static double c18(double x, double y, double z) { (void)z; return -(x - y) * y; }
static double c19(double x, double y, double z) { return log(x) + sqrt(y) - z * z * z; }
static double c20(double x, double y, double z) { (void)y; return pow(x, 2) / 2 + pow(2, z) * 3; }

static const struct {
  const char *text;
  cfn f;
} cases[] = {
    {"0.05 + 0.2*sqrt((x-1)^2 + y^2)", c0},
    {"-x^2", c1},
    {"2^3^2", c2},
    {"1-2-3", c3},
    {"x-y-z", c4},
    {"8/4/2", c5},
    {"x/y/z", c6},
    {"min(x,y,z)", c7},
    {"max( x , y , z , 0.5 )", c8},
    {"exp(-abs(x)) * log(1 + y^2) + sin(pi*z) - cos(e*x)", c9},
    {"2*x + 3*y*z - z/4", c10},
    {"-2^-x", c11},
    {"+x - -y", c12},
    {"abs(x)^abs(y)^0.5", c13},
    {"(x+y)*(y-z)/(1+z^2)", c14},
    {".5 + 1e-3*x + 2.5E+4*y - 3", c15},
    {"sqrt(abs(x*y*z)) + min(x, 1) * max(y, -1)", c16},
    {"- - x", c17},
    {"\t-(x - y)\t*y ", c18},
    {"log(x) + sqrt(y) - z*z*z", c19},
    {"x^2/2 + 2^z*3", c20},
};
enum { NCASES = sizeof cases / sizeof cases[0] };

/* Equal, both NaN, or within a few ulps: libm's pow(a, 2) and the
 * compiler's a*a for the C side may round apart. */
static int close_to(double a, double b) {
  if (isnan(a) || isnan(b)) return isnan(a) && isnan(b);
  if (a == b) return 1;
  return fabs(a - b) <= 1e-14 * fmax(1, fabs(b));
}

static int same_bits(const double *a, const double *b, size_t n) {
  return memcmp(a, b, n * sizeof(double)) == 0;
}

/* eval_many against eval on n points, bit for bit */
static int many_matches(const mx_expr *e, size_t n) {
  double *xyz = malloc((3 * n + 1) * sizeof(double));
  double *h = malloc((n + 1) * sizeof(double)), *g = malloc((n + 1) * sizeof(double));
  for (size_t i = 0; i < 3 * n; i++) xyz[i] = unif(-2, 3);
  h[n] = 12345; /* must not be written */
  mx_expr_eval_many(e, n, xyz, h);
  for (size_t i = 0; i < n; i++) g[i] = mx_expr_eval(e, xyz + 3 * i);
  int ok = same_bits(h, g, n) && h[n] == 12345;
  free(xyz), free(h), free(g);
  return ok;
}

static void test_values(void) {
  for (int c = 0; c < NCASES; c++) {
    mx_expr *e = NULL;
    CHECK(mx_expr_compile(cases[c].text, "--size", &e) == MX_OK);
    if (!e) {
      fprintf(stderr, "  refused: %s\n", cases[c].text);
      continue;
    }
    CHECK(strcmp(mx_expr_text(e), cases[c].text) == 0);
    int bad = 0;
    for (int i = 0; i < 2000; i++) {
      const double p[3] = {unif(-2, 3), unif(-2, 3), unif(-2, 3)};
      const double v = mx_expr_eval(e, p), w = cases[c].f(p[0], p[1], p[2]);
      if (!close_to(v, w) && bad++ < 3)
        fprintf(stderr, "  %s at (%g %g %g): %.17g, C says %.17g\n", cases[c].text, p[0], p[1],
                p[2], v, w);
    }
    CHECK(bad == 0);
    CHECK(many_matches(e, 1000)); /* 15 blocks and a partial one of 40 */
    CHECK(many_matches(e, 0));
    CHECK(many_matches(e, 1));
    CHECK(many_matches(e, MX_EXPR_BLOCK));
    CHECK(many_matches(e, MX_EXPR_BLOCK + 1));
    mx_expr_free(e);
  }
  /* folded constants: the same operations as at run time */
  mx_expr *e = NULL;
  CHECK(mx_expr_compile("sin(1)^2 + cos(1)^2 - exp(log(3)) + 2^0.5", NULL, &e) == MX_OK);
  if (e) {
    const double p[3] = {0, 0, 0};
    volatile double one = 1, three = 3, half = 0.5; /* computed at run time */
    const double want = pow(sin(one), 2) + pow(cos(one), 2) - exp(log(three)) + pow(2, half);
    CHECK(mx_expr_eval(e, p) == want);
    mx_expr_free(e);
  }
  /* a long sum: the stack stays at two values */
  size_t n = 100000;
  char *t = malloc(2 * n);
  for (size_t i = 0; i < n - 1; i++) t[2 * i] = 'x', t[2 * i + 1] = '+';
  t[2 * n - 2] = '1', t[2 * n - 1] = '\0';
  CHECK(mx_expr_compile(t, "--size", &e) == MX_OK);
  if (e) {
    const double p[3] = {0.5, 0, 0};
    CHECK(mx_expr_eval(e, p) == 0.5 * (double)(n - 1) + 1);
    mx_expr_free(e);
  }
  free(t);
  /* numbers: the nearest double, any length */
  const char *nums[] = {"3", "0.5", ".5", "1e-3", "2.5E+4", "1.", "7e0",
                        "0.000000000000000000000000000000000000000000000000000000000000000000001",
                        "1e-400"};
  const double vals[] = {3, 0.5, .5, 1e-3, 2.5E+4, 1., 7, 1e-69, 0};
  for (size_t i = 0; i < sizeof nums / sizeof nums[0]; i++) {
    CHECK(mx_expr_compile(nums[i], NULL, &e) == MX_OK);
    if (!e) continue;
    const double p[3] = {0, 0, 0};
    CHECK(mx_expr_eval(e, p) == vals[i]);
    mx_expr_free(e);
  }
}

/* ---- errors ---- */

/* The message's column, the caret's place under the shown text, and a
 * check that the caret stands under the byte at that column (when the
 * text is shown whole and that byte is printable). */
static int compile_refused(const char *text, const char *what, int *column) {
  n_msgs = 0;
  last_msg[0] = '\0';
  mx_expr *e = (mx_expr *)&n_msgs; /* must become NULL */
  const int st = mx_expr_compile(text, what, &e);
  if (st != MX_EINPUT || e || n_msgs != 1) {
    if (e && st == MX_OK) mx_expr_free(e);
    return 0;
  }
  const char *c = strstr(last_msg, "column ");
  if (!c) return 0;
  *column = atoi(c + 7);
  const char *l1 = strchr(last_msg, '\n');
  const char *l2 = l1 ? strchr(l1 + 1, '\n') : NULL;
  if (!l2 || strncmp(l1 + 1, "  ", 2) || strncmp(l2 + 1, "  ", 2)) return 0;
  const char *caret = strchr(l2, '^');
  if (!caret || strchr(caret + 1, '\n')) return 0;
  const size_t at = (size_t)(caret - (l2 + 3)); /* place in the shown text */
  if (!text) text = ""; /* compiled as empty */
  const size_t len = strlen(text);
  const size_t shown = (size_t)(l2 - (l1 + 3));
  int plain = len < 60;
  for (size_t i = 0; i < len; i++)
    if (text[i] < 0x20 || text[i] >= 0x7f) plain = 0;
  if (plain) {
    if (shown != len || strncmp(l1 + 3, text, len) != 0) return 0;
    if ((size_t)*column - 1 != at) return 0;
  }
  return 1;
}

static void test_errors(void) {
  static const struct {
    const char *text;
    int column;
    const char *says;
  } bad[] = {
      {"", 1, "empty expression"},
      {"   ", 1, "empty expression"},
      {"0.05 + sqr(x)", 8, "unknown name 'sqr' (functions: exp log sqrt abs sin cos min max"},
      {"X + 1", 1, "unknown name 'X'"},
      {"x + Sqrt(y)", 5, "unknown name 'Sqrt'"},
      {"(1 + x", 1, "'(' is not closed (')' expected at the end, column 7)"},
      {"sqrt(x", 5, "the '(' of sqrt is not closed"},
      {"min(x, (y", 8, "'(' is not closed"},
      {"(1 2)", 4, "unexpected number '2' (an operator or the ')' of column 1 expected)"},
      {"sqrt(1 2)", 8, "unexpected number '2' in the arguments of sqrt"},
      {")", 1, "unexpected ')' where an operand was expected"},
      {"x + )", 5, "unexpected ')' where an operand was expected"},
      {"1 + 2)", 6, "')' without a '(' before it"},
      {"x y", 3, "name 'y' after a complete expression"},
      {"(x) (y)", 5, "'(' after a complete expression"},
      {"sqrt x", 1, "the function 'sqrt' needs parentheses: sqrt(...)"},
      {"1 + sqrt", 5, "the function 'sqrt' needs parentheses"},
      {"sqrt(1, 2)", 1, "sqrt takes one argument, not 2"},
      {"min(1)", 1, "min takes two or more arguments, not one"},
      {"1e999", 1, "the number '1e999' is too large (it overflows to infinity)"},
      {"x + 1e400", 5, "overflows to infinity"},
      {"x * / y", 5, "two operators in a row: '/' after '*'"},
      {"x ^ * y", 5, "two operators in a row: '*' after '^'"},
      {"max(1,)", 7, "empty argument 2 of max"},
      {"max(,1)", 5, "empty argument 1 of max"},
      {"sqrt()", 6, "sqrt() without an argument"},
      {"()", 2, "empty parentheses"},
      {"2x", 1, "malformed number '2x'"},
      {"1.5.2", 1, "malformed number '1.5.2'"},
      {"3 * 1e", 5, "malformed number '1e'"},
      {"x(1)", 2, "'x' is a variable, not a function"},
      {"pi (1)", 4, "'pi' is a constant, not a function"},
      {"x # y", 3, "unexpected character '#'"},
      {"x +", 4, "the expression ends after '+', where an operand was expected"},
      {"(* x)", 2, "unexpected '*' where an operand was expected"},
      {"x, y", 2, "',' after a complete expression"},
      {"x +\x01", 4, "unexpected character '\\x01'"},
  };
  for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
    int col = -1;
    const int ok = compile_refused(bad[i].text, "--size", &col);
    CHECK(ok);
    CHECK(col == bad[i].column);
    CHECK(strstr(last_msg, bad[i].says) != NULL);
    CHECK(strncmp(last_msg, "--size: column ", 15) == 0);
    if (!ok || col != bad[i].column || !strstr(last_msg, bad[i].says))
      fprintf(stderr, "  for \"%s\" (column %d expected): [%s]\n", bad[i].text, bad[i].column,
              last_msg);
  }
  /* the whole message, as issue 27 shows it */
  int col;
  CHECK(compile_refused("0.05 + sqr(x)", "--size", &col));
  CHECK(strcmp(last_msg,
               "--size: column 8: unknown name 'sqr' (functions: exp log sqrt abs sin cos min "
               "max; variables x y z; constants pi e)\n  0.05 + sqr(x)\n         ^") == 0);
  /* without a label; at the end; a control byte shown escaped, the caret
   * still under it */
  CHECK(compile_refused("1 +", NULL, &col) && strncmp(last_msg, "column 4: ", 10) == 0);
  CHECK(strstr(last_msg, "\n  1 +\n     ^") != NULL);
  CHECK(compile_refused("x\x01", NULL, &col) && col == 2);
  CHECK(strstr(last_msg, "\n  x\\x01\n   ^") != NULL);

  /* the stack: x+(x+(x+...)) holds one more x at each level */
  char t[4000];
  size_t l = 0;
  for (int i = 0; i < 70; i++) l += (size_t)sprintf(t + l, "x+(");
  l += (size_t)sprintf(t + l, "x");
  for (int i = 0; i < 70; i++) t[l++] = ')';
  t[l] = '\0';
  CHECK(compile_refused(t, "--size", &col) && col == 3 * 64 + 1);
  CHECK(strstr(last_msg, "more than 64 values at once") != NULL);
  /* ... but 63 levels compile, and with constants they fold away */
  l = 0;
  for (int i = 0; i < 63; i++) l += (size_t)sprintf(t + l, "x+(");
  l += (size_t)sprintf(t + l, "x");
  for (int i = 0; i < 63; i++) t[l++] = ')';
  t[l] = '\0';
  mx_expr *e = NULL;
  CHECK(mx_expr_compile(t, NULL, &e) == MX_OK);
  if (e) {
    const double p[3] = {1, 0, 0};
    CHECK(mx_expr_eval(e, p) == 64);
    CHECK(many_matches(e, 100));
  }
  mx_expr_free(e);
  l = 0;
  for (int i = 0; i < 200; i++) l += (size_t)sprintf(t + l, "1+(");
  l += (size_t)sprintf(t + l, "x");
  for (int i = 0; i < 200; i++) t[l++] = ')';
  t[l] = '\0';
  CHECK(mx_expr_compile(t, NULL, &e) == MX_EINPUT); /* 200 values before x */
  /* nesting: parentheses and signs bounded, not the C stack */
  l = 0;
  for (int i = 0; i < 300; i++) t[l++] = '(';
  t[l++] = 'x';
  for (int i = 0; i < 300; i++) t[l++] = ')';
  t[l] = '\0';
  CHECK(compile_refused(t, NULL, &col) && col == 257);
  CHECK(strstr(last_msg, "nested too deeply") != NULL);
  memset(t, '-', 3000);
  t[3000] = 'x', t[3001] = '\0';
  CHECK(compile_refused(t, NULL, &col) && strstr(last_msg, "nested too deeply"));
  /* a long text: a window around the column */
  memset(t, ' ', 3000);
  memcpy(t + 2000, "x y", 3);
  t[3000] = '\0';
  CHECK(compile_refused(t, NULL, &col) && col == 2003);
  CHECK(strstr(last_msg, "\n  ...") != NULL && strstr(last_msg, "x y") != NULL);
  CHECK(strlen(last_msg) < 400);
  /* NULL text: empty */
  CHECK(compile_refused(NULL, NULL, &col) && col == 1);

  /* out of memory at each allocation in turn: MX_ENOMEM, nothing leaks */
  const char *texts[] = {"sqrt(x) + 1",
                         "1.00000000000000000000000000000000000000000000000000000000000000000001*x"};
  for (int w = 0; w < 2; w++)
    for (long k = 1; k <= 8; k++) {
      mx_alloc_fail_countdown(k);
      e = NULL;
      const int st = mx_expr_compile(texts[w], NULL, &e);
      mx_alloc_fail_countdown(0);
      CHECK(st == MX_OK || st == MX_ENOMEM);
      CHECK((st == MX_OK) == (e != NULL));
      mx_expr_free(e);
    }
}

/* ---- random texts ---- */

static void try_text(const char *t, int *compiled, int *refused) {
  mx_expr *e = NULL;
  n_msgs = 0;
  const int st = mx_expr_compile(t, "--size", &e);
  CHECK(st == MX_OK || st == MX_EINPUT);
  if (st == MX_OK) {
    (*compiled)++;
    CHECK(e != NULL && n_msgs == 0);
    if (e) CHECK(many_matches(e, 70));
    mx_expr_free(e);
  } else if (st == MX_EINPUT) {
    (*refused)++;
    CHECK(e == NULL && n_msgs == 1 && strstr(last_msg, "column ") != NULL);
    int col;
    /* again, for the caret's place */
    CHECK(compile_refused(t, "--size", &col));
    CHECK(col >= 1 && (size_t)col <= strlen(t) + 1);
  }
}

static void test_random(void) {
  int compiled = 0, refused = 0;
  char t[200];
  for (int i = 0; i < 3000; i++) { /* bytes */
    const int n = (int)(rnd() % 40);
    for (int j = 0; j < n; j++) t[j] = (char)(1 + rnd() % 255);
    t[n] = '\0';
    try_text(t, &compiled, &refused);
  }
  static const char *const soup[] = {
      "x", "y", "z", "pi", "e", "1", "2.5", ".5", "1e3", "0", "+", "-", "*", "/", "^", "(",
      "(", ")", ")", ",", "sqrt(", "min(", "max(", "exp(", "log(", "abs(", "sin(", "cos(",
      " ", "\t", "+", "-", "*", "x", "y", "2"};
  const int nsoup = sizeof soup / sizeof soup[0];
  int soup_ok = 0;
  for (int i = 0; i < 5000; i++) { /* tokens */
    const int n = 1 + (int)(rnd() % 14);
    size_t l = 0;
    for (int j = 0; j < n; j++) {
      const char *w = soup[rnd() % (uint64_t)nsoup];
      memcpy(t + l, w, strlen(w));
      l += strlen(w);
    }
    t[l] = '\0';
    const int before = compiled;
    try_text(t, &compiled, &refused);
    soup_ok += compiled > before;
  }
  printf("random texts: %d compiled (%d of the token soups), %d refused\n", compiled, soup_ok,
         refused);
  CHECK(soup_ok > 100); /* the soups reach past the first token */
  CHECK(compiled + refused == 8000);
}

int main(void) {
  mx_set_thread_message_handler(keep, NULL);
  test_values();
  test_errors();
  test_random();
  return TEST_DONE();
}
