/* See cancel.h. */
#include "base/cancel.h"

#include <stddef.h>

_Thread_local atomic_int *mx_cancel_flag = NULL;

atomic_int *mx_cancel_enter(atomic_int *flag) {
  atomic_int *previous = mx_cancel_flag;
  if (!previous && flag) atomic_store(flag, 0);
  if (flag) mx_cancel_flag = flag;
  return previous;
}

void mx_cancel_leave(atomic_int *previous) { mx_cancel_flag = previous; }
