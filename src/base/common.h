/* mixoct: common definitions shared by every part of the library.
 * Status codes travel up through MX_CHECK, as in HXT: a function returns
 * MX_OK or an error code after printing one clear message on stderr. */
#ifndef MX_COMMON_H
#define MX_COMMON_H

#include <stddef.h>
#include <stdint.h>

#include "mixoct.h" /* mx_status, MX_CHECK, messages, the allocator */

/* mx_error, mx_warning (mixoct.h): messages go to stderr, prefixed
 * "mixoct: ". A message about a file names it and, when known (line > 0),
 * the line: "mixoct: FILE:LINE: text". */
/* mx_error for a message of several lines (an expression of the user's
 * and a caret under the column at fault, sizing/expr.c): newlines in file
 * or text are kept, where mx_error shows them as \x0a like any control
 * byte so that a file name cannot start a line of its own. So file must be
 * a label of the program's (an option's name), and the caller escapes any
 * text of the user's it shows, a newline in it included. */
void mx_error_lines(const char *file, long line, const char *fmt, ...) MX_PRINTF_(3, 4);
/* when set, warnings are not printed; per thread (see mx_msg_fn) */
extern _Thread_local int mx_quiet;

/* A word of an input file as a message may show it: bytes that are not
 * printable ASCII or part of a valid UTF-8 character (control bytes, C1
 * controls, invalid or cut sequences) and backslashes become \xNN and
 * \\; a word longer than MX_WORD_SHOW bytes is cut there (at a character
 * boundary) and "..." added. out must have MX_WORD_BUF bytes; returns out
 * (NUL-terminated). */
enum { MX_WORD_SHOW = 40, MX_WORD_BUF = 4 * MX_WORD_SHOW + 4 };
const char *mx_show_word(const void *word, size_t len, char *out);

/* Where messages go: NULL (the default) prints them on stderr as above;
 * otherwise fn(user, MX_MSG_ERROR or MX_MSG_WARNING, "FILE:LINE: text").
 * The handler, its user pointer and mx_quiet belong to the calling thread:
 * the mesher object installs its own for the duration of each call
 * (mesher/call.c), so two meshers used at once from two threads each get
 * their own messages. The worker threads of an OpenMP team do not see the
 * caller's: code inside a parallel region reports nothing itself but
 * returns a status (or what to say) that the region's caller reports after
 * it; an error still sent from a worker goes to stderr, a warning is dropped
 * (the worker does not know the caller's quiet flag), and an allocation
 * that fails there says nothing (the MX_ENOMEM it returns is reported by
 * the call, mx_call_leave). */
extern _Thread_local mx_message_fn mx_msg_fn;
extern _Thread_local void *mx_msg_user;
/* 1 on a worker thread of an OpenMP team started inside the calling
 * thread's call (at any level of nesting below mx_msg_level): a thread
 * that does not see the caller's handler. */
int mx_msg_worker(void);
/* The OpenMP nesting level of the calling thread when its call began (a
 * caller may itself be a thread of the user's team); set by mx_call_enter. */
extern _Thread_local int mx_msg_level;
/* Errors reported on this thread so far (mx_error): a call that returns
 * MX_ENOMEM with none reported says "out of memory" itself. */
extern _Thread_local unsigned long mx_msg_errors;

/* A parallel loop over fewer items than this, each of a few nanoseconds of
 * work, runs on one thread (`if (n > MX_PAR_MIN)`): starting a team and
 * its barrier cost about 5 us while the other threads spin, and about 50
 * us when they sleep (OMP_WAIT_POLICY=passive, which the programs and the
 * Python binding set) in this 2-core VM, about what 16384 such items take.
 * Small inputs and the coarse levels of any input run hundreds of such
 * loops (the letter A at -s 8: 140 of its 344 regions). */
enum { MX_PAR_MIN = 16384 };

/* Allocation in one place (the library and the programs use only these):
 * 64-byte aligned, zeroed on request. Failure returns NULL, after a message
 * "out of memory (asked for N bytes)" on the calling thread (none from a
 * worker thread, see mx_msg_fn); the caller returns MX_ENOMEM. */
/* mx_alloc, mx_calloc, mx_strdup, mx_free: mixoct.h. The same aligned to `align` (a power of two, a multiple of
 * sizeof(void *)): buffers for direct I/O. */
void *mx_alloc_aligned(size_t align, size_t bytes);
void *mx_realloc(void *p, size_t bytes);

/* Test hook (not in the public API; tests/test_alloc_fail.c): k > 0 makes
 * the k-th allocation from now (mx_alloc, mx_calloc, mx_realloc,
 * mx_strdup, in any thread) fail, once; k = 0 disables the failure. Either
 * way the count of allocations restarts at 0; mx_alloc_count tells it
 * (counting costs an atomic add per allocation only while the hook is
 * armed: mx_alloc_fail_countdown(-1) counts without failing). */
void mx_alloc_fail_countdown(long k);
long mx_alloc_count(void);
/* Bytes [0, to) of array p are no longer read: the whole pages among them,
 * from the one holding byte `from` (those before were given earlier), go
 * back to the system (they read as zeros after). A pass that copies an
 * array into a new one releases the old one's pages as it goes, so the two
 * are not both resident. */
void mx_release_range(void *p, size_t from, size_t to);
/* Array p of `bytes` bytes (from mx_alloc) is read and written at random
 * places (a hash table): when it is 16 MB or more, it asks for 2 MB pages,
 * whatever MX_HUGEPAGES says. One TLB entry then covers 512 times more of
 * it; the fault and clearing cost of 2 MB pages on these virtual machines
 * (see mx_alloc) is paid only here. The node hash of the transition, cortex
 * -s 10, 2 threads, 2 runs alternated: transition 6.1-7.1 s -> 5.4-5.5 s,
 * system time 7.8-9.3 s -> 6.4-7.2 s; at -s 9 within the noise. */
void mx_advise_random(void *p, size_t bytes);

/* min/max of doubles that compile to one instruction (no NaN handling:
 * inputs are checked finite when read). */
static inline double mx_min(double a, double b) { return a < b ? a : b; }
static inline double mx_max(double a, double b) { return a > b ? a : b; }

/* mx_wtime, mx_peak_rss_mb: mixoct.h */
/* With MX_MEMTRACE set in the environment: one stderr line with the
 * current and peak resident set and the wall clock, labelled (a debugging
 * aid for the memory budget; nothing otherwise). */
void mx_mem_mark(const char *label);

#endif
