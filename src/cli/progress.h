/* mixoct: progress of a run on stderr, for someone watching a terminal.
 *
 * One line, redrawn in place ("\r") by a helper thread at most ten times a
 * second (and once a second for the elapsed time), cleared by
 * mx_progress_done():
 *
 *   mixoct [ 41%] refine and balance: level 7 of 9   2.3 s
 *
 * Nothing is ever printed unless mx_progress_start() was asked for progress
 * AND stderr is a terminal: job scripts, pipes and tests see no difference.
 * The line is not drawn before the run is 0.25 s old, so quick runs never
 * flash it. The percentage is of the whole run, from fixed per-stage weights
 * (measured on the cortex) and, while refining, the level reached.
 *
 * Every function is cheap and safe to call when progress is off; none may be
 * called from inside an OpenMP parallel region. */
#ifndef MX_PROGRESS_H
#define MX_PROGRESS_H

/* want: the caller's wish (not --quiet, not --json); progress is on only if
 * isatty(2) too. stage: MX_STAGE_* (cli.h), the last stage that will run;
 * writes: an output will be written. Starts the helper thread. */
void mx_progress_start(int want, int stage, int writes);

/* Enter a stage: "read", "index", "grid", "refine", "balance",
 * "transition", "boundary", "quality" or "write" (the keys of the JSON
 * phases, plus "index", the surface index built after reading). */
void mx_progress_stage(const char *name);

/* Within "refine"/"balance": the level being created, of max_level. */
void mx_progress_level(int level, int max_level);

/* A repair round (refine again around invalid elements), 0 for the first. */
void mx_progress_round(int round);

/* A callback for mx_builder.on_level (kernels/refine.h). */
void mx_progress_on_level(void *user, int level, int max_level);

/* Stops the helper and clears the line; idempotent. Call it before printing
 * the summary on stdout (the same terminal). */
void mx_progress_done(void);

#endif
