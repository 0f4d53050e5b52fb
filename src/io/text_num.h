/* mixoct: numbers as ASCII text, for the mesh writers' chunk fill
 * functions (see mx_afile_emit in io/atomic_file.h).
 *
 * Each function writes at out, without a terminating NUL (and, but for
 * mx_put_xyz_lines, without a separator), and returns the number of bytes
 * written. They allocate nothing, use no locale and no global state beyond
 * a table built once, so they can be called from any number of threads at
 * once.
 *
 *   mx_put_u64     decimal digits of v, at most MX_U64_CHARS bytes
 *   mx_put_i64     '-' and the digits when v < 0, at most MX_I64_CHARS
 *   mx_put_double  a double that reads back bit-exactly (strtod, or any
 *                  correctly rounding reader): 17 significant digits, or 15
 *                  when those read back to the same double, trailing zeros
 *                  dropped; at most MX_DOUBLE_CHARS bytes. The 15-digit form
 *                  is only tried where one double operation decides it
 *                  exactly (about 1e-8 <= |x| < 1e37): outside, 17 digits
 *                  ("-2.5000000000000001e+300"). The layout is the
 *                  one of "%g": fixed notation for decimal exponents -4 to
 *                  16 ("0.1", "-0.0001234", "1234567.5",
 *                  "10000000000000000"), otherwise "d.ddde+XX" with at
 *                  least two exponent digits ("1e+22", "-2.5e-07",
 *                  "4.9406564584124654e-324"); "0" and "-0" for zeros,
 *                  "inf", "-inf", "nan", "-nan" otherwise.
 *   mx_put_e8      x exactly as printf's "%+1.8E" writes it in the C locale
 *                  ("+1.25000000E-03"), at most MX_E8_CHARS bytes: the
 *                  published restart file's and M3D/MVM layout
 *   mx_put_xyz_lines  the points [begin, end) of xyz (3 doubles a point) as
 *                  lines "x y z\n" of mx_put_double numbers, at most
 *                  MX_XYZ_LINE_MAX bytes a point
 *
 * MX_NUM_MAX bounds one number plus a separator: a fill function writing k
 * numbers with one blank or newline after each needs k * MX_NUM_MAX bytes. */
#ifndef MX_TEXT_NUM_H
#define MX_TEXT_NUM_H

#include <stddef.h>
#include <stdint.h>

enum {
  MX_U64_CHARS = 20,    /* 18446744073709551615 */
  MX_I64_CHARS = 20,    /* -9223372036854775808 */
  MX_DOUBLE_CHARS = 24, /* "-d.dddddddddddddddde-308"; fixed forms <= 23 */
  MX_E8_CHARS = 16,     /* "%+1.8E": "+d.ddddddddE+ddd" */
  MX_NUM_MAX = 26,      /* any of the above with a separator, rounded up */
  MX_XYZ_LINE_MAX = 3 * (MX_DOUBLE_CHARS + 1), /* "x y z\n" */
};

size_t mx_put_u64(char *out, uint64_t v);
size_t mx_put_i64(char *out, int64_t v);
size_t mx_put_double(char *out, double x);
size_t mx_put_e8(char *out, double x);
size_t mx_put_xyz_lines(char *out, const double *xyz, size_t begin,
                        size_t end);

#endif
