/* Cancellation (mx_mesher_cancel, mx_mesher2d_cancel): each mesher object
 * holds an atomic flag that any thread may set; a public call makes the
 * flag of its mesher the calling thread's (mx_cancel_enter) for its
 * duration, and the passes ask mx_cancelled() between their steps and
 * between the levels of their long loops, outside parallel regions (the
 * pointer is the calling thread's: an OpenMP worker sees none). A pass
 * that finds it set returns MX_ECANCELED at once; the call then frees what
 * it made, as for any other failure. */
#ifndef MX_CANCEL_H
#define MX_CANCEL_H

#include <stdatomic.h>

#include "mixoct.h"

extern _Thread_local atomic_int *mx_cancel_flag;

/* The calling thread's flag becomes `flag` (NULL: none); returns the one
 * it replaces, for mx_cancel_leave. The outermost call clears the flag: a
 * cancel asked for before a call started does not stop it. */
atomic_int *mx_cancel_enter(atomic_int *flag);
void mx_cancel_leave(atomic_int *previous);

static inline int mx_cancelled(void) {
  return mx_cancel_flag && atomic_load_explicit(mx_cancel_flag, memory_order_relaxed);
}
/* Inside a parallel loop (the workers have no flag of their own): read
 * the caller's pointer before the loop, `atomic_int *cf = mx_cancel_flag;`,
 * skip the iterations once mx_cancel_seen(cf), and return MX_ECANCELED
 * after the loop when mx_cancelled(). */
static inline int mx_cancel_seen(atomic_int *flag) {
  return flag && atomic_load_explicit(flag, memory_order_relaxed);
}
/* MX_ECANCELED when the calling thread's call was cancelled, else MX_OK. */
static inline int mx_cancel_check(void) { return mx_cancelled() ? MX_ECANCELED : MX_OK; }

#endif
