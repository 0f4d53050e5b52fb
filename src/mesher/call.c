/* See call.h. */
#include "mesher/call.h"

#include <omp.h>

#include "common.h"

void mx_call_enter(mx_call *c, mx_message_fn collect, void *user, int threads) {
  c->fn = mx_msg_fn;
  c->user = mx_msg_user;
  c->threads = omp_get_max_threads();
  mx_msg_fn = collect;
  mx_msg_user = user;
  mx_oom_seen = 0;
  if (threads > 0) omp_set_num_threads(threads);
}

int mx_call_leave(mx_call *c, int status) {
  status = mx_status_refine(status);
  mx_msg_fn = c->fn;
  mx_msg_user = c->user;
  omp_set_num_threads(c->threads);
  return status;
}
