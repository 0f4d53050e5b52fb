/* mixoct: element index lists for re-meshing: the -l LIST of `mixoct
 * remesh`, `mixoct -c`, `mesher_roi -c` and `mesher2d -c`, and
 * mx_read_element_list of the library (and of the Python binding). One
 * rule for all of them:
 *
 *   - The published program's list is one index per line. Words are
 *     separated by blanks (space, tab, CR, FF, VT: CR LF line ends are
 *     fine), line ends and commas (numpy.savetxt(..., delimiter=',')); '#'
 *     starts a comment that runs to the end of the line (numpy.savetxt's
 *     header). A UTF-8 byte-order mark at the start is skipped.
 *   - Every word is an element index: 0-based, below the element count of
 *     the mesh the list refers to. It may be written as a decimal real
 *     whose value is a whole number: "12", "+12", "012", "12.0", "1.2e+01"
 *     and "1.200000000000000000e+01" (numpy.savetxt's default "%.18e") are
 *     all 12. The value is exact (decimal digits, no rounding through a
 *     double), so "9007199254740993.0" is 2^53 + 1.
 *   - Any other word is an error (MX_EINPUT, exit 2) naming the file, the
 *     line and the word (shown with mx_show_word): a word that is not a
 *     number ("abc", "0x1f", "1;2"), a fraction ("12.5"), a negative number
 *     ("-1"; "-0" is 0), NaN or infinity, a number above 2^64 - 1 or not
 *     below the element count. The first such word stops the reading.
 *   - An index may appear more than once (its leaf is split once).
 *   - An empty list (empty file, or only blanks and comments) is read, with
 *     a warning: nothing is refined by the list, the other requests still
 *     apply. A selection (the elements over an error threshold, say) may
 *     well be empty on the last round of an adaptive loop, where refusing
 *     would break the loop; the warning keeps a mistake (a script that
 *     wrote nothing) from passing silently.
 *
 * Nothing is allocated per word; a list of n indices is read in O(n). */
#ifndef MX_ELEMENT_LIST_H
#define MX_ELEMENT_LIST_H

#include <stddef.h>
#include <stdint.h>

/* What a word is, as an element index (mx_word_index). */
enum {
  MX_WORD_INDEX = 0,    /* a whole number, 0 .. 2^64 - 1: *v */
  MX_WORD_NOT_NUMBER,   /* not a decimal number */
  MX_WORD_NOT_FINITE,   /* nan, inf, infinity (any case, signed) */
  MX_WORD_NEGATIVE,     /* a number below 0 */
  MX_WORD_FRACTION,     /* a number >= 0 that is not a whole number */
  MX_WORD_TOO_LARGE,    /* a whole number above 2^64 - 1 */
};

/* The word [w, w + len) (no separators in it) as an element index: one of
 * the MX_WORD_ codes; *v is set for MX_WORD_INDEX (0 otherwise). */
int mx_word_index(const char *w, size_t len, uint64_t *v);

/* The list in buf (len bytes, no NUL needed), name used in messages; every
 * index must be < limit. *out is allocated with mx_alloc (never NULL on
 * success; NULL and *n = 0 on error). MX_OK, MX_EINPUT (one message), or
 * MX_ENOMEM. */
int mx_parse_index_list(const char *name, const void *buf, size_t len,
                        uint64_t limit, uint64_t **out, size_t *n);

/* The same from the file at path (missing, unreadable: MX_EINPUT; an empty
 * file is an empty list). */
int mx_read_index_list(const char *path, uint64_t limit, uint64_t **out,
                       size_t *n);

#endif
