/* One public call of a mesher object (3D mx_mesher, 2D mx_mesher2d): its
 * message collector installed as the calling thread's handler and its
 * thread count set for the call's duration (both are the calling thread's:
 * the handler is thread-local, omp_set_num_threads sets the thread's own
 * nthreads-var), then both restored. A call that fails with MX_ENOMEM and
 * said nothing (the allocation failed in a worker thread) says "out of
 * memory" (every allocation failure returns MX_ENOMEM where it happens). */
#ifndef MX_CALL_H
#define MX_CALL_H

#include <stdatomic.h>

#include "mixoct.h"

typedef struct {
  mx_message_fn fn;
  void *user;
  int threads;
  int outer_default; /* the enclosing call's, restored on leaving */
  unsigned long errors; /* mx_msg_errors on entering */
  atomic_int *cancel_prev; /* the enclosing call's cancel flag (base/cancel.h) */
  int level;            /* mx_msg_level on entering */
} mx_call;

/* collect(user, ...) receives the call's messages; threads > 0 sets the
 * OpenMP thread count, 0 leaves OpenMP's default under the load limit
 * (load_limit.h). */
void mx_call_enter(mx_call *c, mx_message_fn collect, void *user, int threads);
/* Between two stages of a call: the load limit measured again (when it
 * applies to the call), so that a call that started while other processes
 * were busy gets the processors back when they are done, and the other way
 * round. Outside parallel regions only. */
void mx_call_recheck(void);
/* Returns the status to give the caller. */
int mx_call_leave(mx_call *c, int status);

#endif
