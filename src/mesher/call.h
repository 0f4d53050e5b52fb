/* One public call of a mesher object (3D mx_mesher, 2D mx_mesher2d): its
 * message collector installed as the library's handler and its thread count
 * set for the call's duration, then both restored and the status refined
 * (MX_EINPUT after a failed allocation becomes MX_ENOMEM). */
#ifndef MX_CALL_H
#define MX_CALL_H

#include "mixoct.h"

typedef struct {
  mx_message_fn fn;
  void *user;
  int threads;
} mx_call;

/* collect(user, ...) receives the call's messages; threads > 0 sets the
 * OpenMP thread count. */
void mx_call_enter(mx_call *c, mx_message_fn collect, void *user, int threads);
/* Returns the status to give the caller. */
int mx_call_leave(mx_call *c, int status);

#endif
