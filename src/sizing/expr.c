#include "sizing/expr.h"

#include "base/common.h"

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* The instructions. A push puts one value on the stack, a unary one
 * replaces the top, a binary one replaces the top two (left below right)
 * by one. */
enum {
  OP_CONST, OP_X, OP_Y, OP_Z,                          /* push */
  OP_NEG, OP_EXP, OP_LOG, OP_SQRT, OP_ABS, OP_SIN, OP_COS, /* unary */
  OP_ADD, OP_SUB, OP_MUL, OP_DIV, OP_POW, OP_MIN, OP_MAX   /* binary */
};

static int is_push(int op) { return op <= OP_Z; }
static int is_unary(int op) { return op >= OP_NEG && op <= OP_COS; }

/* A struct of arrays: op[i] and, for OP_CONST, its value k[i]. */
struct mx_expr {
  size_t n;
  uint8_t *op;
  double *k;
  int depth; /* the deepest stack the program needs */
  char *text;
};

/* The one definition of each operation, for folding and for mx_expr_eval
 * (mx_expr_eval_many writes the same C expressions in its loops). */
static inline double apply1(int op, double a) {
  switch (op) {
  case OP_NEG: return -a;
  case OP_EXP: return exp(a);
  case OP_LOG: return log(a);
  case OP_SQRT: return sqrt(a);
  case OP_ABS: return fabs(a);
  case OP_SIN: return sin(a);
  default: return cos(a);
  }
}

static inline double apply2(int op, double a, double b) {
  switch (op) {
  case OP_ADD: return a + b;
  case OP_SUB: return a - b;
  case OP_MUL: return a * b;
  case OP_DIV: return a / b;
  case OP_POW: return pow(a, b);
  case OP_MIN: return mx_min(a, b);
  default: return mx_max(a, b);
  }
}

/* ---- compiling ---- */

enum { T_END, T_NUM, T_NAME, T_PLUS, T_MINUS, T_STAR, T_SLASH, T_CARET, T_LP, T_RP, T_COMMA };

enum { K_VAR, K_CONST, K_F1, K_FN };
static const struct {
  const char *name;
  int kind, op;
  double v;
} names[] = {
    {"x", K_VAR, OP_X, 0},           {"y", K_VAR, OP_Y, 0},
    {"z", K_VAR, OP_Z, 0},           {"pi", K_CONST, OP_CONST, 3.14159265358979323846},
    {"e", K_CONST, OP_CONST, 2.71828182845904523536},
    {"exp", K_F1, OP_EXP, 0},        {"log", K_F1, OP_LOG, 0},
    {"sqrt", K_F1, OP_SQRT, 0},      {"abs", K_F1, OP_ABS, 0},
    {"sin", K_F1, OP_SIN, 0},        {"cos", K_F1, OP_COS, 0},
    {"min", K_FN, OP_MIN, 0},        {"max", K_FN, OP_MAX, 0},
};
#define KNOWN_NAMES \
  "functions: exp log sqrt abs sin cos min max; variables x y z; constants pi e"

/* Calls of parse_unary open at once: every way down the grammar passes
 * through it, so this bounds the C stack a text of nested parentheses,
 * signs or powers may take. */
enum { MAX_NEST = 256 };

typedef struct {
  const char *s;
  size_t len;
  size_t pos;         /* where scanning goes on */
  int tok;            /* the current token, at [tpos, tpos + tlen) */
  size_t tpos, tlen;
  double num;         /* its value, a T_NUM */
  int prev;           /* the token before it (T_END at the start) */
  size_t prev_pos, prev_len;
  uint8_t *op;        /* the program so far, with each instruction's */
  double *k;          /* byte offset in the text (for the depth message) */
  size_t *at;
  size_t n;
  int nest;
  int failed;         /* 1: the first error, its offset and text; 2: out of memory */
  size_t epos;
  char emsg[512];
} parser;

static int fail(parser *P, size_t pos, const char *fmt, ...) MX_PRINTF_(3, 4);
static int fail(parser *P, size_t pos, const char *fmt, ...) {
  if (!P->failed) {
    P->failed = 1;
    P->epos = pos;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(P->emsg, sizeof P->emsg, fmt, ap);
    va_end(ap);
  }
  return -1;
}

static int is_digit(int c) { return c >= '0' && c <= '9'; }
static int is_name_start(int c) { return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || c == '_'; }
static int is_name_char(int c) { return is_name_start(c) || is_digit(c); }

/* [pos, pos + len) as a message shows it ('...' quoted, escaped, cut). */
static const char *word(const parser *P, size_t pos, size_t len, char out[MX_WORD_BUF]) {
  return mx_show_word(P->s + pos, len, out);
}

/* A token as a message names it: "number '2.5'", "name 'y'", "')'". */
static const char *describe(const parser *P, int tok, size_t pos, size_t len, char *out, size_t n) {
  char w[MX_WORD_BUF];
  if (tok == T_END) snprintf(out, n, "the end of the expression");
  else if (tok == T_NUM) snprintf(out, n, "number '%s'", word(P, pos, len, w));
  else if (tok == T_NAME) snprintf(out, n, "name '%s'", word(P, pos, len, w));
  else snprintf(out, n, "'%c'", P->s[pos]);
  return out;
}

/* Scans the next token. -1 (after fail) on a character that starts none,
 * a malformed number or one that overflows. */
static int next(parser *P) {
  P->prev = P->tok;
  P->prev_pos = P->tpos;
  P->prev_len = P->tlen;
  const char *s = P->s;
  size_t i = P->pos;
  while (i < P->len && (s[i] == ' ' || s[i] == '\t')) i++;
  P->tpos = i;
  if (i == P->len) {
    P->tok = T_END;
    P->tlen = 0;
    P->pos = i;
    return 0;
  }
  const int c = (unsigned char)s[i];
  if (is_digit(c) || (c == '.' && i + 1 < P->len && is_digit((unsigned char)s[i + 1]))) {
    size_t j = i;
    while (j < P->len && is_digit((unsigned char)s[j])) j++;
    if (j < P->len && s[j] == '.') {
      j++;
      while (j < P->len && is_digit((unsigned char)s[j])) j++;
    }
    if (j < P->len && (s[j] == 'e' || s[j] == 'E')) {
      size_t m = j + 1;
      if (m < P->len && (s[m] == '+' || s[m] == '-')) m++;
      if (m < P->len && is_digit((unsigned char)s[m])) {
        while (m < P->len && is_digit((unsigned char)s[m])) m++;
        j = m;
      }
    }
    /* a number runs into a name or another point: `2x`, `1e`, `1.5.2`,
     * `0x10` are typing slips, not products */
    if (j < P->len && (is_name_char((unsigned char)s[j]) || s[j] == '.')) {
      size_t m = j;
      while (m < P->len && (is_name_char((unsigned char)s[m]) || s[m] == '.')) m++;
      char w[MX_WORD_BUF];
      return fail(P, i, "malformed number '%s' (a product is written with '*': 2*x)",
                  word(P, i, m - i, w));
    }
    /* strtod on exactly the token: its grammar is wider (hex, inf, nan),
     * the scan above decided what the token is */
    char small[64], *buf = small;
    if (j - i >= sizeof small) {
      buf = mx_alloc(j - i + 1);
      if (!buf) { /* mx_alloc said it: no message of ours */
        P->failed = 2;
        return -1;
      }
    }
    memcpy(buf, s + i, j - i);
    buf[j - i] = '\0';
    errno = 0;
    char *end;
    const double v = strtod(buf, &end);
    const int over = errno == ERANGE && isinf(v);
    if (buf != small) mx_free(buf);
    if (over) {
      char w[MX_WORD_BUF];
      return fail(P, i, "the number '%s' is too large (it overflows to infinity)",
                  word(P, i, j - i, w));
    }
    P->tok = T_NUM;
    P->num = v;
    P->tlen = j - i;
    P->pos = j;
    return 0;
  }
  if (is_name_start(c)) {
    size_t j = i;
    while (j < P->len && is_name_char((unsigned char)s[j])) j++;
    P->tok = T_NAME;
    P->tlen = j - i;
    P->pos = j;
    return 0;
  }
  static const char ops[] = "+-*/^(),";
  static const int toks[] = {T_PLUS, T_MINUS, T_STAR, T_SLASH, T_CARET, T_LP, T_RP, T_COMMA};
  const char *o = c ? strchr(ops, c) : NULL;
  if (!o) {
    char w[MX_WORD_BUF];
    /* one character, UTF-8 or not, as mx_show_word shows it */
    size_t k = 1;
    if (c >= 0xc0)
      while (i + k < P->len && k < 4 && ((unsigned char)s[i + k] & 0xc0) == 0x80) k++;
    return fail(P, i, "unexpected character '%s'", word(P, i, k, w));
  }
  P->tok = toks[o - ops];
  P->tlen = 1;
  P->pos = i + 1;
  return 0;
}

/* Appends an instruction, folding it into the constants it applies to
 * (the same function as at run time, on the same values). */
static void emit(parser *P, int op, double k, size_t at) {
  if (is_unary(op) && P->n >= 1 && P->op[P->n - 1] == OP_CONST) {
    P->k[P->n - 1] = apply1(op, P->k[P->n - 1]);
    return;
  }
  /* the last two instructions both pushes: they are the two operands
   * (a sub-expression that leaves one value and ends in a push is that
   * push alone) */
  if (!is_push(op) && !is_unary(op) && P->n >= 2 && P->op[P->n - 1] == OP_CONST &&
      P->op[P->n - 2] == OP_CONST) {
    P->k[P->n - 2] = apply2(op, P->k[P->n - 2], P->k[P->n - 1]);
    P->n--;
    return;
  }
  /* never more instructions than tokens, so the arrays (one slot per
   * byte of text and one more) cannot overflow */
  P->op[P->n] = (uint8_t)op;
  P->k[P->n] = k;
  P->at[P->n] = at;
  P->n++;
}

static int parse_expr(parser *P);
static int parse_unary(parser *P);

static int is_operator(int tok) { return tok >= T_PLUS && tok <= T_CARET; }

/* Where an operand should start and none does. */
static int want_operand(parser *P) {
  char d[MX_WORD_BUF + 32], pd[MX_WORD_BUF + 32];
  if (P->tok == T_END) {
    if (P->prev == T_END) return fail(P, 0, "empty expression");
    return fail(P, P->tpos, "the expression ends after %s, where an operand was expected",
                describe(P, P->prev, P->prev_pos, P->prev_len, pd, sizeof pd));
  }
  if (is_operator(P->tok) && is_operator(P->prev))
    return fail(P, P->tpos, "two operators in a row: '%c' after '%c' (an operand was expected)",
                P->s[P->tpos], P->s[P->prev_pos]);
  return fail(P, P->tpos, "unexpected %s where an operand was expected",
              describe(P, P->tok, P->tpos, P->tlen, d, sizeof d));
}

/* A function's arguments, from its '(' to past its ')'. */
static int parse_call(parser *P, int f, size_t name_pos) {
  char d[MX_WORD_BUF + 32];
  const char *fname = names[f].name;
  if (P->tok != T_LP)
    return fail(P, name_pos, "the function '%s' needs parentheses: %s(...)", fname, fname);
  const size_t lp = P->tpos;
  if (next(P)) return -1;
  int count = 0;
  for (;;) {
    if (P->tok == T_RP || P->tok == T_COMMA) {
      if (count == 0 && P->tok == T_RP)
        return fail(P, P->tpos, "%s() without an argument", fname);
      return fail(P, P->tpos, "empty argument %d of %s", count + 1, fname);
    }
    if (parse_expr(P)) return -1;
    count++;
    if (names[f].kind == K_FN && count >= 2) emit(P, names[f].op, 0, name_pos);
    if (P->tok == T_RP) break;
    if (P->tok == T_COMMA) {
      if (next(P)) return -1;
      continue;
    }
    if (P->tok == T_END)
      return fail(P, lp, "the '(' of %s is not closed (')' expected at the end, column %zu)",
                  fname, P->len + 1);
    return fail(P, P->tpos, "unexpected %s in the arguments of %s (',' or ')' expected)",
                describe(P, P->tok, P->tpos, P->tlen, d, sizeof d), fname);
  }
  if (names[f].kind == K_F1 && count != 1)
    return fail(P, name_pos, "%s takes one argument, not %d", fname, count);
  if (names[f].kind == K_FN && count < 2)
    return fail(P, name_pos, "%s takes two or more arguments, not one", fname);
  if (names[f].kind == K_F1) emit(P, names[f].op, 0, name_pos);
  return next(P);
}

static int parse_primary(parser *P) {
  char w[MX_WORD_BUF], d[MX_WORD_BUF + 32];
  if (P->tok == T_NUM) {
    emit(P, OP_CONST, P->num, P->tpos);
    return next(P);
  }
  if (P->tok == T_LP) {
    const size_t lp = P->tpos;
    if (next(P)) return -1;
    if (P->tok == T_RP) return fail(P, P->tpos, "empty parentheses");
    if (parse_expr(P)) return -1;
    if (P->tok == T_END)
      return fail(P, lp, "'(' is not closed (')' expected at the end, column %zu)", P->len + 1);
    if (P->tok != T_RP)
      return fail(P, P->tpos, "unexpected %s (an operator or the ')' of column %zu expected)",
                  describe(P, P->tok, P->tpos, P->tlen, d, sizeof d), lp + 1);
    return next(P);
  }
  if (P->tok != T_NAME) return want_operand(P);
  const size_t pos = P->tpos, len = P->tlen;
  int f = -1;
  for (int i = 0; i < (int)(sizeof names / sizeof names[0]); i++)
    if (strlen(names[i].name) == len && memcmp(names[i].name, P->s + pos, len) == 0) f = i;
  if (f < 0)
    return fail(P, pos, "unknown name '%s' (" KNOWN_NAMES ")", word(P, pos, len, w));
  if (next(P)) return -1;
  if (names[f].kind == K_F1 || names[f].kind == K_FN) return parse_call(P, f, pos);
  if (P->tok == T_LP)
    return fail(P, P->tpos, "'%s' is a %s, not a function (an operator was expected before '(')",
                names[f].name, names[f].kind == K_VAR ? "variable" : "constant");
  emit(P, names[f].op, names[f].v, pos);
  return 0;
}

/* power := primary [ '^' unary ]: the exponent is a unary, which holds a
 * power in turn, so 2^3^2 is 2^(3^2) and 2^-1 is 2^(-1). */
static int parse_power(parser *P) {
  if (parse_primary(P)) return -1;
  if (P->tok != T_CARET) return 0;
  const size_t at = P->tpos;
  if (next(P) || parse_unary(P)) return -1;
  emit(P, OP_POW, 0, at);
  return 0;
}

/* unary := ('-' | '+') unary | power: below ^, so -x^2 is -(x^2). */
static int parse_unary(parser *P) {
  if (++P->nest > MAX_NEST)
    return fail(P, P->tpos, "nested too deeply (more than %d levels of parentheses, "
                "signs or powers)", MAX_NEST);
  int st;
  if (P->tok == T_MINUS || P->tok == T_PLUS) {
    const int neg = P->tok == T_MINUS;
    const size_t at = P->tpos;
    st = next(P) || parse_unary(P) ? -1 : 0;
    if (!st && neg) emit(P, OP_NEG, 0, at);
  } else {
    st = parse_power(P);
  }
  P->nest--;
  return st;
}

static int parse_term(parser *P) {
  if (parse_unary(P)) return -1;
  while (P->tok == T_STAR || P->tok == T_SLASH) {
    const int op = P->tok == T_STAR ? OP_MUL : OP_DIV;
    const size_t at = P->tpos;
    if (next(P) || parse_unary(P)) return -1;
    emit(P, op, 0, at);
  }
  return 0;
}

static int parse_expr(parser *P) {
  if (parse_term(P)) return -1;
  while (P->tok == T_PLUS || P->tok == T_MINUS) {
    const int op = P->tok == T_PLUS ? OP_ADD : OP_SUB;
    const size_t at = P->tpos;
    if (next(P) || parse_term(P)) return -1;
    emit(P, op, 0, at);
  }
  return 0;
}

/* The width a byte of the text takes shown: a blank or printable ASCII 1,
 * any other \xNN 4 (a tab is shown as a blank, keeping the caret in
 * place; a byte that is no ASCII is no token anyway). */
static size_t shown_width(unsigned char b) { return b == '\t' || (b >= 0x20 && b < 0x7f) ? 1 : 4; }

/* The text around byte pos, escaped, on one line, and a caret under pos:
 * at most about 80 columns (a window with "..." on a long text). line and
 * caret have room for 4 * 80 bytes. */
static void show_caret(const char *s, size_t len, size_t pos, char *line, char *caret) {
  enum { BEFORE = 36, WIDTH = 72 };
  size_t from = pos, w = 0;
  while (from > 0 && w + shown_width((unsigned char)s[from - 1]) <= BEFORE)
    w += shown_width((unsigned char)s[--from]);
  size_t l = 0, c = 0;
  if (from > 0) {
    memcpy(line, "...", 3);
    l = 3;
  }
  size_t i = from, shown = 0;
  for (; i < len && shown < WIDTH; i++) {
    const unsigned char b = (unsigned char)s[i];
    if (i == pos) c = l;
    if (b == '\t') line[l++] = ' ';
    else if (shown_width(b) == 1) line[l++] = (char)b;
    else l += (size_t)sprintf(line + l, "\\x%02x", b);
    shown += shown_width(b);
  }
  if (i == pos) c = l; /* at the end */
  if (i < len) {
    memcpy(line + l, "...", 3);
    l += 3;
  }
  line[l] = '\0';
  memset(caret, ' ', c);
  caret[c] = '^';
  caret[c + 1] = '\0';
}

int mx_expr_compile(const char *text, const char *what, mx_expr **out) {
  *out = NULL;
  if (!text) text = "";
  const size_t len = strlen(text);
  parser P = {.s = text, .len = len, .tok = T_END, .prev = T_END};
  P.op = mx_alloc(len + 1);
  P.k = mx_alloc((len + 1) * sizeof(double));
  P.at = mx_alloc((len + 1) * sizeof(size_t));
  if (!P.op || !P.k || !P.at) {
    mx_free(P.op), mx_free(P.k), mx_free(P.at);
    return MX_ENOMEM;
  }
  int depth = 0;
  if (!next(&P) && !parse_expr(&P) && P.tok != T_END) {
    char d[MX_WORD_BUF + 32];
    if (P.tok == T_RP) fail(&P, P.tpos, "')' without a '(' before it");
    else
      fail(&P, P.tpos, "%s after a complete expression (an operator or the end was expected)",
           describe(&P, P.tok, P.tpos, P.tlen, d, sizeof d));
  }
  if (!P.failed) { /* the stack the program needs, as folded */
    int t = 0;
    for (size_t i = 0; i < P.n && !P.failed; i++) {
      t += is_push(P.op[i]) ? 1 : is_unary(P.op[i]) ? 0 : -1;
      if (t > MX_EXPR_MAX_DEPTH)
        fail(&P, P.at[i], "the expression holds more than %d values at once here "
             "(too many sub-expressions nested on the right of operators)", MX_EXPR_MAX_DEPTH);
      if (t > depth) depth = t;
    }
  }
  if (P.failed == 2) { /* out of memory, said by mx_alloc */
    mx_free(P.op), mx_free(P.k), mx_free(P.at);
    return MX_ENOMEM;
  }
  if (P.failed) {
    char line[4 * 80 + 8], caret[4 * 80 + 8];
    show_caret(text, len, P.epos, line, caret);
    mx_error_lines(what, 0, "column %zu: %s\n  %s\n  %s", P.epos + 1, P.emsg, line, caret);
    mx_free(P.op), mx_free(P.k), mx_free(P.at);
    return MX_EINPUT;
  }
  mx_free(P.at);
  mx_expr *e = mx_calloc(sizeof *e);
  char *copy = mx_strdup(text);
  if (!e || !copy) {
    mx_free(P.op), mx_free(P.k), mx_free(e), mx_free(copy);
    return MX_ENOMEM;
  }
  e->n = P.n;
  e->op = P.op;
  e->k = P.k;
  e->depth = depth;
  e->text = copy;
  *out = e;
  return MX_OK;
}

void mx_expr_free(mx_expr *e) {
  if (!e) return;
  mx_free(e->op);
  mx_free(e->k);
  mx_free(e->text);
  mx_free(e);
}

const char *mx_expr_text(const mx_expr *e) { return e->text; }

/* ---- evaluating ---- */

double mx_expr_eval(const mx_expr *e, const double p[3]) {
  double s[MX_EXPR_MAX_DEPTH];
  int t = -1;
  for (size_t i = 0; i < e->n; i++) {
    const int op = e->op[i];
    switch (op) {
    case OP_CONST: s[++t] = e->k[i]; break;
    case OP_X: s[++t] = p[0]; break;
    case OP_Y: s[++t] = p[1]; break;
    case OP_Z: s[++t] = p[2]; break;
    case OP_NEG: case OP_EXP: case OP_LOG: case OP_SQRT:
    case OP_ABS: case OP_SIN: case OP_COS:
      s[t] = apply1(op, s[t]);
      break;
    default:
      t--;
      s[t] = apply2(op, s[t], s[t + 1]);
      break;
    }
  }
  return s[0];
}

/* One instruction over the m points of a block: a plain loop each, which
 * the compiler vectorizes where the operation has a vector instruction
 * (+ - * / sqrt abs neg min max; the others call libm point by point).
 * Each is the C expression apply1 / apply2 use, so the results agree. */
#define LOOP1(expr)                                                   \
  do {                                                                \
    double *restrict a_ = s[t];                                       \
    for (size_t j = 0; j < m; j++) { const double a = a_[j]; a_[j] = (expr); } \
  } while (0)
#define LOOP2(expr)                                                   \
  do {                                                                \
    t--;                                                              \
    double *restrict a_ = s[t];                                       \
    const double *restrict b_ = s[t + 1];                             \
    for (size_t j = 0; j < m; j++) {                                  \
      const double a = a_[j], b = b_[j];                              \
      a_[j] = (expr);                                                 \
    }                                                                 \
  } while (0)

void mx_expr_eval_many(const mx_expr *e, size_t n, const double *xyz, double *h) {
  double s[MX_EXPR_MAX_DEPTH][MX_EXPR_BLOCK];
  for (size_t first = 0; first < n; first += MX_EXPR_BLOCK) {
    const size_t m = n - first < MX_EXPR_BLOCK ? n - first : MX_EXPR_BLOCK;
    const double *p = xyz + 3 * first;
    int t = -1;
    for (size_t i = 0; i < e->n; i++) {
      switch (e->op[i]) {
      case OP_CONST: {
        const double k = e->k[i];
        t++;
        for (size_t j = 0; j < m; j++) s[t][j] = k;
        break;
      }
      case OP_X: case OP_Y: case OP_Z: {
        const int c = e->op[i] - OP_X;
        t++;
        for (size_t j = 0; j < m; j++) s[t][j] = p[3 * j + c];
        break;
      }
      case OP_NEG: LOOP1(-a); break;
      case OP_EXP: LOOP1(exp(a)); break;
      case OP_LOG: LOOP1(log(a)); break;
      case OP_SQRT: LOOP1(sqrt(a)); break;
      case OP_ABS: LOOP1(fabs(a)); break;
      case OP_SIN: LOOP1(sin(a)); break;
      case OP_COS: LOOP1(cos(a)); break;
      case OP_ADD: LOOP2(a + b); break;
      case OP_SUB: LOOP2(a - b); break;
      case OP_MUL: LOOP2(a * b); break;
      case OP_DIV: LOOP2(a / b); break;
      case OP_POW: LOOP2(pow(a, b)); break;
      case OP_MIN: LOOP2(mx_min(a, b)); break;
      default: LOOP2(mx_max(a, b)); break;
      }
    }
    memcpy(h + first, s[0], m * sizeof(double));
  }
}
