/* mixoct: the program over the library (include/mixoct.h): read ->
 * grid -> refine/balance -> transition -> boundary (with repair of invalid
 * elements by list refinement) -> quality -> write; --stage stops earlier;
 * `-c FILE.oct [-l LIST]` re-meshes from a restart file. Exit codes: the
 * library's status (0 success, 1 internal failure, 2 bad input or usage,
 * 3 out of memory, 4 output failure, 5 invalid elements left). */
#include "cli.h"
#include "progress.h"
#include "mixoct.h"

#include <signal.h>
#include <sys/stat.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

/* What the run did, for the report (warnings, files written, outcome). */
static mx_run_info run_info;
static int quiet_warnings; /* --quiet: warnings kept for --json, not printed */

/* The mesher's messages: printed as before, warnings kept for --json. */
static void on_message(void *user, int level, const char *text) {
  mx_run_info *ri = user;
  if (level == MX_MSG_ERROR) {
    if (!ri->error[0]) snprintf(ri->error, sizeof ri->error, "%s", text);
    fprintf(stderr, "mixoct: error: %s\n", text);
    return;
  }
  if (ri->nwarnings < MX_RUN_WARNINGS) {
    ri->warnings[ri->nwarnings] = mx_strdup(text);
    if (ri->warnings[ri->nwarnings]) ri->nwarnings++;
  } else {
    ri->warnings_dropped++;
  }
  if (!quiet_warnings) fprintf(stderr, "mixoct: warning: %s\n", text);
}

/* Ctrl-C or a scheduler's time limit: no temporary output is left. */
static void on_signal(int sig) {
  mx_remove_temporaries();
  signal(sig, SIG_DFL);
  raise(sig);
}

/* Hooks of the mesher for the progress line. */
static void on_stage(void *user, const char *name) { (void)user, mx_progress_stage(name); }
static void on_round(void *user, int round) { (void)user, mx_progress_round(round); }

/* The mesher of a run: parameters, inputs and requests from the options. */
static int setup(const mx_options *o, mx_mesher **out) {
  mx_params p;
  mx_params_default(&p);
  p.surface_level = o->s_level;
  p.all_level = o->a_level;
  p.stage = o->stage;
  p.balance = o->balance;
  p.max_memory_mb = o->max_memory_mb;
  p.repair_input = o->repair_input;
  p.materials = o->materials;
  p.tets = o->tets;
  if (o->smooth_rounds >= 0) p.smooth_rounds = o->smooth_rounds;
  p.threads = o->threads; /* --threads N: N, whatever the load (mixoct.h) */
  mx_mesher *m = mx_mesher_new(&p);
  if (!m) return MX_ENOMEM; /* said by mx_alloc */
  *out = m;
  mx_mesher_set_message_handler(m, on_message, &run_info);
  const mx_progress hooks = {on_stage, mx_progress_on_level, on_round, NULL};
  mx_mesher_set_progress(m, &hooks);
  mx_mesher_release_edges_early(m, 1); /* one run: their memory goes to the mesh */
  mx_mesher_set_output_fields(m, o->fields); /* checked by the parser */
  mx_progress_stage("read");
  MX_CHECK(mx_mesher_set_image_params(m, &o->image));
  if (o->feature_angle >= 0.0) MX_CHECK(mx_mesher_set_feature_angle(m, o->feature_angle));
  if (o->feature_level > 0) MX_CHECK(mx_mesher_set_feature_level(m, o->feature_level));
  if (o->feature_file) MX_CHECK(mx_mesher_set_feature_file(m, o->feature_file));
  return mx_add_inputs(o, m);
}

/* The options' inputs and requests (the --p4est front passes the same
 * through mx_p4est_run_params to src/mpi/p4est_run.c). */
int mx_add_inputs(const mx_options *o, mx_mesher *m) {
  if (o->demo) MX_CHECK(mx_mesher_add_demo_surface(m));
  for (int i = 0; i < o->ninputs; i++)
    MX_CHECK(mx_mesher_add_input(m, o->inputs[i], o->material_id[i], o->material_name[i],
                                 o->input_slevel[i], o->input_ilevel[i]));
  for (int r = 0; r < o->nregion_surf; r++)
    MX_CHECK(mx_mesher_add_region_surface(m, o->region_surf[r], o->rlevel[r]));
  if (o->regions_file) MX_CHECK(mx_mesher_read_boxes(m, o->regions_file));
  if (o->size) {
    /* a file of that name: a size map; otherwise an expression or F1..F5 */
    struct stat sb;
    if (stat(o->size, &sb) == 0 && S_ISREG(sb.st_mode))
      MX_CHECK(mx_mesher_set_size_map(m, o->size, o->size_field));
    else
      MX_CHECK(mx_mesher_set_size_expr(m, o->size));
  }
  if (o->size_min > 0.0 || o->size_max > 0.0)
    MX_CHECK(mx_mesher_set_size_limits(m, o->size_min, o->size_max));
  if (o->curvature > 0.0) MX_CHECK(mx_mesher_set_size_curvature(m, o->curvature));
  if (o->thickness > 0.0) MX_CHECK(mx_mesher_set_size_thickness(m, o->thickness));
  if (o->gradation > 0.0) MX_CHECK(mx_mesher_set_size_gradation(m, o->gradation));
  return MX_OK;
}

static void written(const char *path) {
  mx_run_info *ri = &run_info;
  struct stat st;
  ri->outputs[ri->noutputs] = path;
  ri->bytes[ri->noutputs] = stat(path, &st) == 0 ? (long long)st.st_size : -1;
  ri->noutputs++;
}

/* Write every output, then the restart file when asked. */
static int write_outputs(const mx_options *o, mx_mesher *m) {
  for (int k = 0; k < o->noutputs; k++) {
    MX_CHECK(mx_mesher_write(m, o->outputs[k], o->ascii));
    written(o->outputs[k]);
  }
  if (o->boundary_out) {
    MX_CHECK(mx_mesher_write_boundary(m, o->boundary_out));
    written(o->boundary_out);
  }
  if (o->restart_out) {
    MX_CHECK(mx_mesher_save_restart(m, o->restart_out));
    written(o->restart_out);
  }
  run_info.dry_run = o->noutputs == 0 && !o->restart_out && !o->boundary_out;
  return MX_OK;
}

/* The machine, for the report. */
static char topology[256];

static void report(const mx_options *o, mx_mesher *m, double t_start) {
  run_info.total_s = mx_wtime() - t_start;
  run_info.wait_policy = mx_wait_policy_name();
  if (o->json) { /* hwloc's topology takes a few MB: not before the summary's peak */
    mx_topology_string(topology, sizeof topology);
    run_info.topology = topology;
  }
  mx_progress_done(); /* before the summary, on the same terminal */
  if (!o->quiet && !o->json) mx_mesher_print_report(m, &run_info, 0);
  if (o->json) mx_mesher_print_report(m, &run_info, 1);
}

int mx_run(const mx_options *o) {
  const double t_start = mx_wtime();
  mx_mesher *m = NULL;
  mx_progress_start(!o->quiet && !o->json, o->stage, o->output != NULL);
  int st = setup(o, &m);
  if (!st && o->restart_in) {
    st = mx_mesher_load_restart(m, o->restart_in);
    uint64_t *list = NULL;
    size_t n = 0;
    /* indices of the mesh written with the restart file */
    if (!st && o->list_in) st = mx_read_element_list(o->list_in, mx_mesher_restart_elements(m), &list, &n);
    if (!st) st = mx_mesher_refine_elements(m, list, n);
    mx_free_array(list);
  } else if (!st) {
    st = mx_mesher_mesh(m);
  }
  /* A mesh with invalid elements is written only when asked: exit 5. */
  if (!st || (st == MX_EINVALID && o->keep_invalid)) {
    const int wst = write_outputs(o, m);
    if (wst) st = wst;
  }
  run_info.status = st;
  /* exit 0's promise is the full stage's: an intermediate stage's mesh is
   * written as asked (exit 0) but not reported valid */
  run_info.valid = st == MX_OK && o->stage == MX_STAGE_FULL;
  run_info.stage = o->stage;
  if (m && (!st || st == MX_EINVALID)) {
    report(o, m, t_start);
  } else if (o->json) {
    mx_progress_done();
    mx_mesher_print_report(NULL, &run_info, 1); /* the outcome, even without a mesh */
  }
  mx_mesher_free(m);
  mx_progress_done();
  for (int k = 0; k < run_info.nwarnings; k++) mx_free(run_info.warnings[k]);
  return st;
}


/* OpenMP threads that wait for each other sleep instead of spinning
 * (issue 24): libgomp's default spins at every barrier, and when another
 * job holds a core the spinning thread steals the time slice of the thread
 * it waits for (two threads then 2-7x slower than one). libgomp reads
 * OMP_WAIT_POLICY once, when it is loaded, before main: so when the user
 * has not chosen a policy (OMP_WAIT_POLICY, GOMP_SPINCOUNT), the program
 * sets the passive one and starts itself again (same pid, same argv). Not
 * under valgrind (its preload is in LD_PRELOAD: the new image would run
 * without it). If the exec fails, the run goes on with the default. */
static void passive_wait_policy(char **argv) {
  if (getenv("OMP_WAIT_POLICY") || getenv("GOMP_SPINCOUNT")) return;
  const char *pre = getenv("LD_PRELOAD");
  if (pre && strstr(pre, "vgpreload")) return;
  if (setenv("OMP_WAIT_POLICY", "passive", 1) != 0) return;
  if (setenv("MIXOCT_WAIT_POLICY_SET", "1", 1) != 0) return;
  execv("/proc/self/exe", argv);
  unsetenv("OMP_WAIT_POLICY"); /* could not: as before */
  unsetenv("MIXOCT_WAIT_POLICY_SET");
}

const char *mx_wait_policy_name(void) {
  const char *p = getenv("OMP_WAIT_POLICY");
  if (!p) return getenv("GOMP_SPINCOUNT") ? "spincount" : "default";
  return getenv("MIXOCT_WAIT_POLICY_SET") ? "passive (set by mixoct)" : p;
}

int main(int argc, char **argv) {
  passive_wait_policy(argv);
  /* every message goes through on_message: --json keeps the warnings and
   * the first error */
  mx_set_thread_message_handler(on_message, &run_info);
  if (argc >= 2 && strcmp(argv[1], "check") == 0)
    return mx_check_main(argc - 1, argv + 1);
  if (argc >= 2 && strcmp(argv[1], "patterns") == 0)
    return mx_patterns_main(argc - 1, argv + 1);
  int remesh = argc >= 2 && strcmp(argv[1], "remesh") == 0;
  mx_heap_setup(); /* large arrays mapped on their own (mixoct.h) */
  const char *base = strrchr(argv[0], '/');
  if (strcmp(base ? base + 1 : argv[0], "mesher_roi") == 0)
    return mx_mesher_roi_main(argc, argv);
  if (strcmp(base ? base + 1 : argv[0], "mesher2d") == 0)
    return mx_mesher2d_main(argc, argv);
  for (int i = 1; i < argc; i++) /* the distributed octree (issue 14) */
    if (strcmp(argv[i], "--p4est") == 0) {
#ifdef MX_HAVE_MPI
      return mx_p4est_main(argc, argv);
#else
      mx_error(NULL, 0, "--p4est: this mixoct was built without MPI and p4est "
                        "(meson setup -Dmpi=enabled)");
      return MX_EINPUT;
#endif
    }
  mx_options o;
  int exit_now = 0;
  int st = remesh ? mx_parse_options(argc - 1, argv + 1, &o, &exit_now)
                  : mx_parse_options(argc, argv, &o, &exit_now);
  if (st) {
    if (!exit_now && argc > 1 && o.json) { /* the outcome as JSON all the same */
      run_info.status = st;
      mx_mesher_print_report(NULL, &run_info, 1);
    }
    return st;
  }
  if (remesh && !exit_now && !o.restart_in) {
    mx_error(NULL, 0, "remesh needs the restart file: -c FILE.oct (see mixoct --help)");
    return MX_EINPUT;
  }
  if (exit_now) return 0;
  quiet_warnings = o.quiet;
  if (o.threads > 0) omp_set_num_threads(o.threads);
  signal(SIGINT, on_signal);
  signal(SIGTERM, on_signal);
  signal(SIGHUP, on_signal);
  st = mx_run(&o);
  return st == MX_OK ? 0 : st;
}
