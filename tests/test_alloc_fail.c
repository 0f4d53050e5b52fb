/* Allocation failures, in the spirit of SQLite's tests: a countdown
 * (mx_alloc_fail_countdown, src/base/common.h) makes the k-th allocation of
 * a small run fail, for every k of the run (counted first with the hook
 * counting only). Runs, through the public API (include/mixoct.h), with 2
 * threads, so that allocations of worker threads fail too:
 *   demo     the demo surface at -s 3, meshed (full stage);
 *   remesh   a re-mesh: elements of that mesh refined (the setup, made
 *            without failures, is not counted);
 *   2d       an L-shaped domain at -s 5 (mx_mesher2d);
 *   2dmat    a square with a quadrilateral inside at -s 4, two materials;
 *   vtu, msh the demo mesh written as .vtu, then as .msh, into an empty
 *            temporary directory (one mesher for all k).
 * Each k must give MX_ENOMEM with an error message through the mesher's
 * handler (or MX_OK when the run made fewer than k allocations: worker
 * threads' buffers make the count vary by a few), leave no file in the
 * directory (no temporary either), and leave the mesher usable: the failed
 * step run again without failure gives the reference result (the same
 * mesh, the same file bytes); the mesher is then freed. Leaks are found by
 * LeakSanitizer when the test is built with -fsanitize=address
 * (tests/alloc_fail_test.sh builds it so: the meson test `alloc_fail_asan`;
 * the plain build runs it as `alloc_fail`).
 *
 * Allocation points (2 threads, counted on this machine): demo 260, remesh
 * 141, 2d 239, vtu 35, msh 43 (a few more or fewer from run to run: the
 * worker threads' buffers). Every k of every run is tried (about 720 runs,
 * 16 s) unless MX_ALLOC_FAIL_STRIDE=s is set: then a run of more than 100
 * allocations tries its first and last 20 and every s-th k between (the
 * AddressSanitizer build, 3-8 times slower, runs with s = 3: about 340
 * runs; all k there take about 140 s on this machine under load, and find
 * nothing more).
 *
 * Output: one line per run (allocations, tried, statuses), and one line per
 * k whose status was not MX_ENOMEM, so that a site that still answers
 * otherwise is named by its k (run again with MX_ALLOC_FAIL_ONLY=run:k).
 *
 * Known on the branch that added this test (status25), in code other
 * branches convert at the same time (they go once those are merged):
 * demo k=28 gives MX_OK after the "out of memory" message
 * (kernels/surface_defects.c, edge_defects: a one-thread fallback when its
 * per-thread accumulators cannot be had); vtu and msh leak 64 bytes when
 * the name copy of io/atomic_file.c (mx_afile_open) succeeded and a later
 * allocation there failed (AddressSanitizer). */
#include "base/common.h"
#include "check.h"
#include "mesh_hash.h"
#include "mixoct.h"

#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

/* ---- messages ---------------------------------------------------------- */

typedef struct {
  int errors, warnings;
  char last[256];
} msgs;

static void on_message(void *user, int level, const char *text) {
  msgs *g = user;
  if (getenv("MX_ALLOC_FAIL_VERBOSE")) fprintf(stderr, "  message: %s\n", text);
  if (level == MX_MSG_ERROR) {
    g->errors++;
    snprintf(g->last, sizeof g->last, "%s", text);
  } else {
    g->warnings++;
  }
}

/* ---- the runs ---------------------------------------------------------- */

static char dir[256];
static const uint64_t ELEMENTS[] = {0, 17, 99, 250};
static uint64_t ref_vtu, ref_msh; /* the files' bytes */

static mx_mesher *demo_mesher(msgs *g) {
  mx_params p;
  mx_params_default(&p);
  p.surface_level = 3;
  p.threads = 2;
  mx_mesher *m = mx_mesher_new(&p);
  if (m) mx_mesher_set_message_handler(m, on_message, g);
  return m;
}

static uint64_t file_hash(const char *path) {
  FILE *f = fopen(path, "rb");
  if (!f) return 0;
  uint64_t h = TEST_FNV_START;
  char buf[65536];
  size_t n;
  while ((n = fread(buf, 1, sizeof buf, f)) > 0) h = test_fnv(h, buf, n);
  fclose(f);
  return h;
}

/* Entries of the temporary directory. */
static int dir_entries(void) {
  DIR *d = opendir(dir);
  if (!d) return -1;
  int n = 0;
  struct dirent *e;
  while ((e = readdir(d)))
    if (strcmp(e->d_name, ".") && strcmp(e->d_name, "..")) n++;
  closedir(d);
  return n;
}

/* A run: the setup (not counted: no failure), the step under the
 * countdown, then the check that the mesher goes on (no failure). Returns
 * the step's status; *again: the result of going on (0: it failed). */
typedef struct {
  const char *name;
  void *(*setup)(msgs *g);       /* NULL: the step makes its own mesher */
  int (*step)(void **obj, msgs *g);
  uint64_t (*go_on)(void *obj, msgs *g); /* after a failed step */
  void (*release)(void *obj);
  uint64_t ref; /* go_on's result after a successful step */
} run;

static void free3(void *o) { mx_mesher_free(o); }
static void free2(void *o) { mx_mesher2d_free(o); }

/* demo: mx_mesher_new .. mesh */
static int demo_step(void **obj, msgs *g) {
  mx_mesher *m = demo_mesher(g);
  *obj = m;
  if (!m) return MX_ENOMEM;
  int st = mx_mesher_add_demo_surface(m);
  if (!st) st = mx_mesher_mesh(m);
  return st;
}
static uint64_t demo_go_on(void *obj, msgs *g) {
  mx_mesher *m = obj ? obj : demo_mesher(g);
  if (!m) return 0;
  uint64_t h = 0;
  /* the surface is there unless its call failed (then it is not) */
  if (mx_mesher_mesh(m) == MX_OK ||
      (mx_mesher_add_demo_surface(m) == MX_OK && mx_mesher_mesh(m) == MX_OK))
    h = test_mesh_hash(m);
  if (m != obj) mx_mesher_free(m);
  return h;
}

/* materials: a cube of side 1 with a cube of side 0.4 inside, one input,
 * meshed with params.materials (the index built outward, the labels, the
 * interface nodes' moves) */
static int add_cubes(mx_mesher *m) {
  static const uint32_t f[12][3] = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6},
                                    {0, 1, 4}, {1, 5, 4}, {2, 6, 3}, {3, 6, 7},
                                    {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  double xyz[48];
  uint32_t tri[72];
  for (int b = 0; b < 2; b++) {
    const double lo = b ? 0.31 : 0.01, hi = b ? 0.69 : 0.99;
    for (int i = 0; i < 8; i++) {
      xyz[24 * b + 3 * i] = (i & 1) ? hi : lo;
      xyz[24 * b + 3 * i + 1] = (i & 2) ? hi : lo;
      xyz[24 * b + 3 * i + 2] = (i & 4) ? hi : lo;
    }
    for (int t = 0; t < 12; t++)
      for (int k = 0; k < 3; k++) tri[36 * b + 3 * t + k] = f[t][k] + 8u * (uint32_t)b;
  }
  return mx_mesher_add_surface_arrays(m, "cubes", 16, xyz, 24, tri);
}
static int cubes_step(void **obj, msgs *g) {
  mx_params p;
  mx_params_default(&p);
  p.surface_level = 3;
  p.threads = 2;
  p.materials = 1;
  mx_mesher *m = mx_mesher_new(&p);
  *obj = m;
  if (!m) return MX_ENOMEM;
  mx_mesher_set_message_handler(m, on_message, g);
  int st = add_cubes(m);
  if (!st) st = mx_mesher_mesh(m);
  return st;
}
static uint64_t cubes_hash(mx_mesher *m) {
  mx_mesh_arrays a;
  uint64_t h = test_mesh_hash(m);
  if (mx_mesher_mesh_arrays(m, &a) == MX_OK && a.material)
    h = test_fnv(h, a.material, a.nelements * sizeof *a.material);
  return h;
}
static uint64_t cubes_go_on(void *obj, msgs *g) {
  mx_mesher *m = obj;
  if (!m) { /* the mesher itself failed: a new one */
    void *o = NULL;
    const int st = cubes_step(&o, g);
    const uint64_t h = st ? 0 : cubes_hash(o);
    mx_mesher_free(o);
    return h;
  }
  /* the surface is there unless its call failed (then it is not) */
  if (mx_mesher_mesh(m) != MX_OK && (add_cubes(m) != MX_OK || mx_mesher_mesh(m) != MX_OK))
    return 0;
  return cubes_hash(m);
}

/* remesh: a meshed demo; refine four elements */
static void *meshed_demo(msgs *g) {
  mx_mesher *m = demo_mesher(g);
  if (!m) return NULL;
  if (mx_mesher_add_demo_surface(m) || mx_mesher_mesh(m)) {
    mx_mesher_free(m);
    return NULL;
  }
  return m;
}
static int remesh_step(void **obj, msgs *g) {
  (void)g;
  return mx_mesher_refine_elements(*obj, ELEMENTS, sizeof ELEMENTS / sizeof *ELEMENTS);
}
/* after a failed refinement: mesh again (the octree as far as it went),
 * then the refinement once more; a mesh comes out */
static uint64_t remesh_go_on(void *obj, msgs *g) {
  (void)g;
  mx_mesher *m = obj;
  const int st = mx_mesher_mesh(m);
  if (st != MX_OK) return 0;
  return test_mesh_hash(m) != 0;
}

/* 2d: an L at -s 5 */
static int l_step(void **obj, msgs *g) {
  static const double xy[] = {0, 0, 2, 0, 2, 1, 1, 1, 1, 2, 0, 2};
  static const uint32_t seg[] = {0, 1, 1, 2, 2, 3, 3, 4, 4, 5, 5, 0};
  mx_params2d p;
  mx_params2d_default(&p);
  p.surface_level = 5;
  p.threads = 2;
  mx_mesher2d *m = mx_mesher2d_new(&p);
  *obj = m;
  if (!m) return MX_ENOMEM;
  mx_mesher2d_set_message_handler(m, on_message, g);
  int st = mx_mesher2d_set_domain_arrays(m, "L", 6, xy, 6, seg);
  if (!st) st = mx_mesher2d_mesh(m);
  return st;
}
static uint64_t l_go_on(void *obj, msgs *g) {
  mx_mesher2d *m = obj;
  if (!m) {
    void *o = NULL;
    uint64_t h = l_step(&o, g) == MX_OK ? test_mesh2d_hash(o) : 0;
    mx_mesher2d_free(o);
    return h;
  }
  /* the domain may not be set when its call failed */
  if (mx_mesher2d_mesh(m) == MX_OK) return test_mesh2d_hash(m);
  static const double xy[] = {0, 0, 2, 0, 2, 1, 1, 1, 1, 2, 0, 2};
  static const uint32_t seg[] = {0, 1, 1, 2, 2, 3, 3, 4, 4, 5, 5, 0};
  if (mx_mesher2d_set_domain_arrays(m, "L", 6, xy, 6, seg) || mx_mesher2d_mesh(m)) return 0;
  return test_mesh2d_hash(m);
}

/* 2dmat: a square with a quadrilateral inside at -s 4, two materials
 * (mx_params2d.materials: regions, cleave, each material's check) */
static const double q_xy[] = {0, 0, 1, 0, 1, 1, 0, 1, 0.4, 0.3, 0.6, 0.1, 0.7, 0.7, 0.3, 0.6};
static const uint32_t q_seg[] = {0, 1, 1, 2, 2, 3, 3, 0, 7, 6, 6, 5, 5, 4, 4, 7};
static int q_inputs(mx_mesher2d *m) {
  int st = mx_mesher2d_set_material(m, 2, 7, "core");
  if (!st) st = mx_mesher2d_set_domain_arrays(m, "Q", 8, q_xy, 8, q_seg);
  return st;
}
static int q_step(void **obj, msgs *g) {
  mx_params2d p;
  mx_params2d_default(&p);
  p.surface_level = 4;
  p.threads = 2;
  p.materials = 1;
  mx_mesher2d *m = mx_mesher2d_new(&p);
  *obj = m;
  if (!m) return MX_ENOMEM;
  mx_mesher2d_set_message_handler(m, on_message, g);
  int st = q_inputs(m);
  if (!st) st = mx_mesher2d_mesh(m);
  return st;
}
static uint64_t q_hash(const mx_mesher2d *m) {
  mx_mesh2d_arrays a;
  uint64_t h = test_mesh2d_hash(m);
  if (h && mx_mesher2d_mesh_arrays(m, &a) == MX_OK && a.material)
    h = test_fnv(h, a.material, a.ncells * sizeof *a.material);
  return h;
}
static uint64_t q_go_on(void *obj, msgs *g) {
  mx_mesher2d *m = obj;
  if (!m) {
    void *o = NULL;
    uint64_t h = q_step(&o, g) == MX_OK ? q_hash(o) : 0;
    mx_mesher2d_free(o);
    return h;
  }
  if (mx_mesher2d_mesh(m) == MX_OK) return q_hash(m);
  /* the material or the domain may not be set when their call failed (a
   * domain set already is refused: then the mesh call is what failed) */
  if (q_inputs(m) != MX_OK && mx_mesher2d_set_material(m, 2, 7, "core") != MX_OK) return 0;
  return mx_mesher2d_mesh(m) == MX_OK ? q_hash(m) : 0;
}

/* vtu, msh: one meshed demo for all k */
static mx_mesher *shared_demo;
static void *get_shared(msgs *g) {
  mx_mesher_set_message_handler(shared_demo, on_message, g);
  return shared_demo;
}
static void keep(void *o) { (void)o; }
static char vtu_path[300], msh_path[300];
static int vtu_step(void **obj, msgs *g) {
  (void)g;
  return mx_mesher_write(*obj, vtu_path, 0);
}
static int msh_step(void **obj, msgs *g) {
  (void)g;
  return mx_mesher_write(*obj, msh_path, 0);
}
static uint64_t write_go_on(void *obj, const char *path) {
  if (mx_mesher_write(obj, path, 0) != MX_OK) return 0;
  const uint64_t h = file_hash(path);
  unlink(path);
  return h;
}
static uint64_t vtu_go_on(void *obj, msgs *g) {
  (void)g;
  return write_go_on(obj, vtu_path);
}
static uint64_t msh_go_on(void *obj, msgs *g) {
  (void)g;
  return write_go_on(obj, msh_path);
}

/* ---- the countdown ----------------------------------------------------- */

/* One k (0: count only). Returns the status; *n: the allocations made. */
static int try_k(run *r, long k, long *n, int verbose) {
  msgs g = {0, 0, ""};
  void *obj = r->setup ? r->setup(&g) : NULL;
  if (r->setup && !obj) {
    CHECK(!"setup");
    return MX_EINTERNAL;
  }
  memset(&g, 0, sizeof g);
  mx_alloc_fail_countdown(k ? k : -1);
  const int st = r->step(&obj, &g);
  *n = mx_alloc_count();
  mx_alloc_fail_countdown(0);
  const int fired = k > 0 && *n >= k;
  if (k == 0) {
    CHECK(st == MX_OK);
  } else if (fired) {
    if (st != MX_ENOMEM || g.errors == 0 || verbose)
      printf("%s: k=%ld: %s (%d), %d error message(s)%s%s\n", r->name, k,
             mx_status_string(st), st, g.errors, g.errors ? ": " : "", g.last);
    CHECK(st == MX_ENOMEM);
    CHECK(g.errors > 0 || !obj); /* the handler heard why (if there was one) */
  } else {
    CHECK(st == MX_OK);
  }
  CHECK(dir_entries() == 0 || (st == MX_OK && (r->step == vtu_step || r->step == msh_step)));
  if (st == MX_OK && (r->step == vtu_step || r->step == msh_step)) {
    CHECK(file_hash(r->step == vtu_step ? vtu_path : msh_path) ==
          (r->step == vtu_step ? ref_vtu : ref_msh));
    unlink(r->step == vtu_step ? vtu_path : msh_path);
  }
  /* going on */
  if (k == 0) {
    r->ref = r->go_on(obj, &g);
    CHECK(r->ref != 0);
  } else if (st != MX_OK) {
    const uint64_t h = r->go_on(obj, &g);
    if (h != r->ref) printf("%s: k=%ld: going on after the failure: %s\n", r->name, k,
                            h ? "another result" : "failed");
    CHECK(h == r->ref);
  }
  CHECK(dir_entries() == 0);
  r->release(obj);
  return st;
}

static void countdown(run *r, long stride, long only) {
  long n = 0;
  try_k(r, 0, &n, 0);
  if (only) {
    long m;
    try_k(r, only, &m, 1);
    return;
  }
  long tried = 0, nomem = 0, ok = 0, other = 0;
  for (long k = 1; k <= n + 2; k++) {
    if (stride > 1 && n > 100 && k > 20 && k < n - 20 && k % stride) continue;
    long m;
    const int st = try_k(r, k, &m, 0);
    tried++;
    if (st == MX_ENOMEM) nomem++;
    else if (st == MX_OK) ok++;
    else other++;
  }
  printf("%-6s %5ld allocations, %5ld k tried: %ld MX_ENOMEM, %ld MX_OK (past the last), "
         "%ld other\n",
         r->name, n, tried, nomem, ok, other);
  fflush(stdout);
}

int main(void) {
  if (getenv("MX_ALLOC_FAIL_VERBOSE")) setvbuf(stdout, NULL, _IONBF, 0);
  snprintf(dir, sizeof dir, "%s/mixoct-alloc-fail.XXXXXX", getenv("TMPDIR") ? getenv("TMPDIR") : "/tmp");
  if (!mkdtemp(dir)) {
    perror("mkdtemp");
    return 1;
  }
  snprintf(vtu_path, sizeof vtu_path, "%s/demo.vtu", dir);
  snprintf(msh_path, sizeof msh_path, "%s/demo.msh", dir);
  msgs g0 = {0, 0, ""};
  shared_demo = meshed_demo(&g0);
  CHECK(shared_demo != NULL);
  if (!shared_demo) return TEST_DONE();
  ref_vtu = write_go_on(shared_demo, vtu_path);
  ref_msh = write_go_on(shared_demo, msh_path);
  CHECK(ref_vtu && ref_msh);

  run runs[] = {
      {"demo", NULL, demo_step, demo_go_on, free3, 0},
      {"remesh", meshed_demo, remesh_step, remesh_go_on, free3, 0},
      {"2d", NULL, l_step, l_go_on, free2, 0},
      {"2dmat", NULL, q_step, q_go_on, free2, 0},
      {"materials", NULL, cubes_step, cubes_go_on, free3, 0},
      {"vtu", get_shared, vtu_step, vtu_go_on, keep, 0},
      {"msh", get_shared, msh_step, msh_go_on, keep, 0},
  };
  const char *s = getenv("MX_ALLOC_FAIL_STRIDE");
  const long stride = s ? atol(s) : 1;
  const char *only = getenv("MX_ALLOC_FAIL_ONLY"); /* run:k */
  for (size_t i = 0; i < sizeof runs / sizeof *runs; i++) {
    long k = 0;
    if (only) {
      const size_t l = strlen(runs[i].name);
      if (strncmp(only, runs[i].name, l) != 0 || only[l] != ':') continue;
      k = atol(only + l + 1);
    }
    countdown(&runs[i], stride, k);
  }
  mx_mesher_free(shared_demo);
  CHECK(dir_entries() == 0);
  rmdir(dir);
  return TEST_DONE();
}
