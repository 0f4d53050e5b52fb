/* See call.h. */
#include "mesher/call.h"

#include <omp.h>

#include "base/common.h"
#include "mesher/load_limit.h"

/* The calling thread's call: OpenMP's default count when the load limit
 * applies to the call (else 0), and the fewest threads a stage of its last
 * call ran with (mx_last_call_threads). */
static _Thread_local int call_default;
static _Thread_local int last_call_threads;

void mx_call_enter(mx_call *c, mx_message_fn collect, void *user, int threads) {
  c->fn = mx_msg_fn;
  c->user = mx_msg_user;
  c->threads = omp_get_max_threads();
  c->outer_default = call_default;
  mx_msg_fn = collect;
  mx_msg_user = user;
  c->errors = mx_msg_errors;
  c->level = mx_msg_level;
  mx_msg_level = omp_get_level(); /* the caller may be a thread of a team */
  /* the caller's count, else OpenMP's default under the load limit */
  call_default = threads > 0 ? 0 : c->threads;
  int n = threads > 0 ? threads : mx_call_thread_count(c->threads);
  if (n != c->threads) omp_set_num_threads(n);
  last_call_threads = n;
}

void mx_call_recheck(void) {
  if (call_default <= 1) return;
  int n = mx_call_thread_count(call_default);
  if (n != omp_get_max_threads()) omp_set_num_threads(n);
  if (n < last_call_threads) last_call_threads = n;
}

int mx_call_leave(mx_call *c, int status) {
  if (status == MX_ENOMEM && mx_msg_errors == c->errors) mx_error(NULL, 0, "out of memory");
  mx_msg_fn = c->fn;
  mx_msg_user = c->user;
  mx_msg_level = c->level;
  call_default = c->outer_default;
  omp_set_num_threads(c->threads);
  return status;
}

int mx_last_call_threads(void) { return last_call_threads; }
