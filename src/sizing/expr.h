/* An analytic size field h(x, y, z) given as text on the command line
 * (issue 27: `mixoct ... --size "0.05 + 0.2*sqrt((x-1)^2 + y^2)"`),
 * compiled once into a flat program for a stack machine and evaluated at
 * many points, from any number of threads at once.
 *
 * Grammar (blanks, that is spaces and tabs, may stand between any two
 * tokens; names are case-sensitive, lowercase):
 *
 *   expr    := term { ('+' | '-') term }          left-associative
 *   term    := unary { ('*' | '/') unary }        left-associative
 *   unary   := ('-' | '+') unary | power
 *   power   := primary [ '^' unary ]              right-associative
 *   primary := number | 'x' | 'y' | 'z' | 'pi' | 'e'
 *            | f1 '(' expr ')'                    f1: exp log sqrt abs sin cos
 *            | fn '(' expr ',' expr { ',' expr } ')'   fn: min max
 *            | '(' expr ')'
 *   number  := digits [ '.' [ digits ] ] [ exponent ]
 *            | '.' digits [ exponent ]
 *   exponent:= ('e' | 'E') [ '+' | '-' ] digits
 *
 * Precedence, loosest first: + and - (binary); * and /; unary - and +;
 * ^. So `-x^2` is -(x^2), `2^-1` is 2^(-1), `2^3^2` is 2^9, `1-2-3` is
 * (1-2)-3 and `8/4/2` is (8/4)/2; min(a, b, c) is min(min(a, b), c).
 * A number is its nearest double (strtod in the C locale, the library's
 * only one); one that overflows to infinity is refused. A number runs on
 * into nothing: `2x` and `1.5.2` are refused, not read as a product.
 *
 * The functions are those of the C library (pow for ^, fabs for abs); min
 * and max are `a < b ? a : b` and `a > b ? a : b`. Parts without a
 * variable are computed once at compile time with the same operations in
 * the same order, so a result does not depend on where it is computed. */
#ifndef MX_SIZING_EXPR_H
#define MX_SIZING_EXPR_H

#include <stddef.h>

/* The deepest stack a program may need (values held at once while it
 * runs): a longer chain of sub-expressions nested on the right of
 * operators is refused when compiled. mx_expr_eval_many keeps this many
 * rows of MX_EXPR_BLOCK doubles on the thread's stack (32 KiB). */
enum { MX_EXPR_MAX_DEPTH = 64, MX_EXPR_BLOCK = 64 };

typedef struct mx_expr mx_expr;

/* Compiles text. MX_OK and *out (free it with mx_expr_free); MX_EINPUT
 * after one message (mx_error_lines(what, 0, ...); what, such as
 * "--size", may be NULL) giving the 1-based column (in bytes) and what is
 * wrong, then the text with a caret under that column; MX_ENOMEM. *out is
 * NULL on failure. */
int mx_expr_compile(const char *text, const char *what, mx_expr **out);

/* h at p = (x, y, z). Allocates nothing, changes nothing: thread-safe. */
double mx_expr_eval(const mx_expr *e, const double p[3]);

/* h[i] at (xyz[3i], xyz[3i+1], xyz[3i+2]) for i < n: the program runs on
 * MX_EXPR_BLOCK points at a time, a loop over the points per instruction,
 * with the same results as mx_expr_eval bit for bit. Thread-safe. */
void mx_expr_eval_many(const mx_expr *e, size_t n, const double *xyz, double *h);

/* The text it was compiled from (its copy, valid until mx_expr_free). */
const char *mx_expr_text(const mx_expr *e);

void mx_expr_free(mx_expr *e);

#endif
