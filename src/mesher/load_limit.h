/* The load limit: how many threads a library call runs with when its caller
 * chose no count (mx_params.threads 0) and the environment chose no wait
 * policy (issue 24, "threads that never hurt").
 *
 * libgomp's default wait policy spins: a thread that reaches a barrier
 * first spins (about 300000 rounds, a few milliseconds) before it sleeps.
 * When another process holds a core, the scheduler gives that spinning
 * thread the time slice of the thread it waits for, at every barrier: 2
 * threads on this 2-core machine with one core busy are then 1.5-10x slower
 * than 1. With OMP_WAIT_POLICY=passive they are not, but libgomp reads the
 * policy once, when it is loaded, which is before any code of a program
 * linking libmixoct runs: the library cannot change it (the programs start
 * themselves again with it, src/cli/main.c; the Python binding sets it
 * before loading the library). What the library can do is not start more
 * threads than there are processors left free by the running threads of
 * other processes: min(requested, max(1, processors - others running)),
 * measured at the start of each call and again between its stages
 * (mx_call_recheck, call.h): /proc/loadavg's running count less this
 * process's running threads, a few tens of microseconds; when that sees
 * other threads, twice more within 0.75 ms, the fewest kept (a kernel
 * worker or a short command is gone by then: a quiet machine must not lose
 * a thread to them). Calls and stages within 0.1 s of a measure use it.
 *
 * Off when mx_params.threads > 0 (the caller's count wins) or when
 * OMP_WAIT_POLICY (active or passive: libgomp ignores other values) or
 * GOMP_SPINCOUNT was set when the library was loaded.
 * MIXOCT_TEST_BUSY=N (tests only): the limit applies whatever the policy,
 * as if N threads of other processes were running. */
#ifndef MX_LOAD_LIMIT_H
#define MX_LOAD_LIMIT_H

/* min(requested, max(1, procs - others)); others < 0 (not known) or
 * procs < 1: requested. A pure function. */
int mx_load_limit(int requested, int procs, int others);

/* Running threads of other processes now: the running count of
 * /proc/loadavg less this process's threads in state R (one of them is
 * the caller), the fewest of up to three looks within 0.75 ms; -1 when
 * /proc cannot be read. */
int mx_others_running(void);

/* The thread count for a call that asks for `requested` (OpenMP's
 * default): the load limit when it is on (see above), else requested. */
int mx_call_thread_count(int requested);

#endif
