/* mixoct: the progress line on stderr (see progress.h). The main thread only
 * records where the run is, under a mutex; a helper thread draws. */
#include "progress.h"

#include "cli.h"

#include <pthread.h>
#include <stdio.h>
#include <string.h>
#include <sys/ioctl.h>
#include <time.h>
#include <unistd.h>

enum {
  TICK_MS = 100,    /* at most ten redraws a second */
  FIRST_MS = 250,   /* nothing is drawn for runs shorter than this */
  LINE_MAX_ = 160,
};

/* The stages in the order they run, their share of a run (seconds per stage
 * of the cortex at -s 8 and 9 with a .vtu output, rounded) and the stages of
 * --stage they belong to. */
enum { IN_OCTREE = 1, IN_TRANSITION = 2, IN_FULL = 4, IN_ALL = 7, WRITES = 8 };
typedef struct {
  const char *key, *label;
  double weight;
  unsigned runs;
} stage_info;
static const stage_info stages[] = {
    {"read", "reading the surfaces", 1, IN_ALL},
    {"index", "surface index", 2, IN_FULL},
    {"grid", "root grid", 1, IN_ALL},
    {"refine", "refine and balance", 22, IN_ALL},
    {"balance", "balance (recursive)", 0, IN_ALL},
    {"transition", "transition patterns", 25, IN_TRANSITION | IN_FULL},
    {"boundary", "boundary", 38, IN_FULL},
    {"quality", "quality", 1, IN_TRANSITION | IN_FULL},
    {"write", "writing", 15, WRITES},
};
enum { NSTAGES = sizeof stages / sizeof stages[0] };

static struct {
  int on;
  pthread_t thread;
  pthread_mutex_t mu;
  pthread_cond_t cv;
  int stop;
  double t0;
  double start[NSTAGES], total; /* start of each stage's span, sum */
  int planned[NSTAGES];
  int stage;                    /* index into stages, -1 before the first */
  int level, max_level;         /* 0: no level to show */
  int round;
  unsigned version;             /* bumped on every change */
  int drawn_len;
} P = {.stage = -1};

static double now_s(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* Share of the current stage done: while refining, the levels created so
 * far, weighted 4^level (surface octants quadruple at each level). */
static double stage_fraction(void) {
  if (P.max_level <= 0 || P.level <= 0) return 0.0;
  double done = 0.0, all = 0.0, w = 1.0;
  for (int k = 1; k <= P.max_level; k++) {
    w *= 4.0;
    if (k < P.level) done += w;
    all += w;
  }
  return done / all;
}

static int terminal_width(void) {
  struct winsize ws;
  if (ioctl(STDERR_FILENO, TIOCGWINSZ, &ws) == 0 && ws.ws_col > 20)
    return ws.ws_col < LINE_MAX_ ? ws.ws_col : LINE_MAX_;
  return 80;
}

/* Called with the mutex held, from the helper only. */
static void draw(double elapsed) {
  char line[LINE_MAX_ + 1];
  int n;
  if (P.stage < 0) {
    n = snprintf(line, sizeof line, "mixoct  starting  %.1f s", elapsed);
  } else {
    const stage_info *s = &stages[P.stage];
    double pct = 100.0 * (P.start[P.stage] + s->weight * stage_fraction()) / P.total;
    if (pct > 99.0) pct = 99.0;
    char lev[48] = "", rnd[32] = "";
    if (P.level > 0 && P.max_level > 0)
      snprintf(lev, sizeof lev, ": level %d of %d", P.level, P.max_level);
    if (P.round > 0) snprintf(rnd, sizeof rnd, " (repair round %d)", P.round);
    n = snprintf(line, sizeof line, "mixoct [%3.0f%%] %s%s%s  %.1f s", pct,
                 s->label, lev, rnd, elapsed);
  }
  if (n < 0) return;
  const int width = terminal_width() - 1; /* never wrap: \r would not undo it */
  if (n > width) n = width;
  line[n] = '\0';
  const int pad = P.drawn_len > n ? P.drawn_len - n : 0;
  /* The cursor is left at the start of the line, so a message printed
   * meanwhile by the main thread starts on a clean column 0. */
  fprintf(stderr, "\r%s%*s\r", line, pad, "");
  fflush(stderr);
  P.drawn_len = n;
}

static void *helper(void *arg) {
  (void)arg;
  unsigned drawn_version = ~0u;
  long drawn_second = -1;
  pthread_mutex_lock(&P.mu);
  while (!P.stop) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    ts.tv_nsec += TICK_MS * 1000000L;
    if (ts.tv_nsec >= 1000000000L) {
      ts.tv_sec++;
      ts.tv_nsec -= 1000000000L;
    }
    pthread_cond_timedwait(&P.cv, &P.mu, &ts);
    if (P.stop) break;
    const double elapsed = now_s() - P.t0;
    if (elapsed * 1000.0 < FIRST_MS) continue;
    const long second = (long)elapsed;
    if (P.version == drawn_version && second == drawn_second) continue;
    draw(elapsed);
    drawn_version = P.version;
    drawn_second = second;
  }
  pthread_mutex_unlock(&P.mu);
  return NULL;
}

void mx_progress_start(int want, int stage, int writes) {
  if (P.on || !want || !isatty(STDERR_FILENO)) return;
  unsigned mask = stage == MX_STAGE_OCTREE       ? IN_OCTREE
                  : stage == MX_STAGE_TRANSITION ? IN_TRANSITION
                                                 : IN_FULL;
  if (writes) mask |= WRITES;
  P.total = 0.0;
  for (int i = 0; i < NSTAGES; i++) {
    P.planned[i] = (stages[i].runs & mask) != 0;
    P.start[i] = P.total;
    if (P.planned[i]) P.total += stages[i].weight;
  }
  P.stage = -1;
  P.level = P.max_level = P.round = 0;
  P.stop = 0;
  P.drawn_len = 0;
  P.t0 = now_s();
  pthread_condattr_t ca;
  if (pthread_mutex_init(&P.mu, NULL) != 0) return;
  if (pthread_condattr_init(&ca) != 0) goto no_cond;
  pthread_condattr_setclock(&ca, CLOCK_MONOTONIC);
  int ok = pthread_cond_init(&P.cv, &ca) == 0;
  pthread_condattr_destroy(&ca);
  if (!ok) goto no_cond;
  if (pthread_create(&P.thread, NULL, helper, NULL) != 0) {
    pthread_cond_destroy(&P.cv);
    goto no_cond;
  }
  P.on = 1;
  return;
no_cond:
  pthread_mutex_destroy(&P.mu); /* no progress: not worth a message */
}

void mx_progress_stage(const char *name) {
  if (!P.on) return;
  int s = -1;
  for (int i = 0; i < NSTAGES && s < 0; i++)
    if (strcmp(stages[i].key, name) == 0) s = i;
  if (s < 0) return;
  pthread_mutex_lock(&P.mu);
  P.stage = s;
  P.level = P.max_level = 0;
  P.version++;
  pthread_mutex_unlock(&P.mu);
}

void mx_progress_level(int level, int max_level) {
  if (!P.on) return;
  pthread_mutex_lock(&P.mu);
  P.level = level;
  P.max_level = max_level;
  P.version++;
  pthread_mutex_unlock(&P.mu);
}

void mx_progress_round(int round) {
  if (!P.on) return;
  pthread_mutex_lock(&P.mu);
  P.round = round;
  P.version++;
  pthread_mutex_unlock(&P.mu);
}

void mx_progress_on_level(void *user, int level, int max_level) {
  (void)user;
  mx_progress_level(level, max_level);
}

void mx_progress_done(void) {
  if (!P.on) return;
  pthread_mutex_lock(&P.mu);
  P.stop = 1;
  pthread_cond_signal(&P.cv);
  pthread_mutex_unlock(&P.mu);
  pthread_join(P.thread, NULL);
  if (P.drawn_len > 0) {
    fprintf(stderr, "\r%*s\r", P.drawn_len, "");
    fflush(stderr);
  }
  pthread_cond_destroy(&P.cv);
  pthread_mutex_destroy(&P.mu);
  P.on = 0;
}
