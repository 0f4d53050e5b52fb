/* Re-meshing benchmark (issue 9 targets), through the library:
 *
 * 1. The Table 1 scenario of the 2021 paper on the cortex (shared/data/remesh):
 *    initial -s 5 run written as ASCII VTK with its restart file; then
 *    re-meshing (read the restart file, refine the listed elements, mesh,
 *    write ASCII VTK) from the published c5.oct with its list.txt, and from
 *    our own restart file with the elements of our mesh that have a node in
 *    roi.box (the same rule that made list.txt).
 * 2. Cortex -s L (default 8): the elements with a node inside a box around
 *    roi.box's centre grown until it holds about 4% of the elements; their
 *    re-meshing in memory (mx_mesher_refine_elements) and from the binary
 *    restart file (read .octb, refine, mesh), against the initial run.
 *
 * 3. --choice (alone): the choice between a local and a full re-mesh
 *    (issue 31 item 3; src/mesher/remesh_patch.c, mx_remesh_local_pays): at
 *    each level of --levels (default 6,7,8), three lists on the cortex:
 *    "scattered" (50 elements spread over it: every (n/50)-th element, the
 *    elements being in Morton order), "cluster" (50 elements in a row of
 *    the Morton order: one small clustered spot) and "box" (the elements
 *    with a node in the box of part 2, about 4%: issue 9's in-memory
 *    scenario, 3.8% at -s 8), each re-meshed in memory with
 *    params.remesh_full -1 (local), 1 (full) and 0 (the choice), the modes
 *    alternated, each run on a mesher meshed just before it (its initial
 *    time taken in the same run). Per level and list: the medians, the
 *    ratios to the initial run, the patch; then the per-leaf costs of the
 *    re-mesh proper (mx_stats t_grid + t_transition + t_boundary: finding
 *    the patch, its stages and the splice, or the whole octree's): the full path's
 *    seconds per leaf, and the local path's fitted as
 *    t = per_leaf * leaves + per_patch_leaf * patch leaves (least squares
 *    over the three lists, the per-leaf part being the splice and the rings),
 *    from which the share of the leaves below which a patch pays.
 *
 * usage: mixoct-remesh-bench [--data DIR] [--level L] [--repeat N] [--out DIR]
 *        mixoct-remesh-bench --choice [--data DIR] [--levels 6,7,8] [--repeat N]
 * The heap is set up as the mixoct program sets it (src/cli/main.c; MX_HEAP
 * = heap or default as there).
 * Times are the median of N runs (default 3), in seconds; the last line is
 * one JSON object. */
#include "mixoct.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "bench_util.h"

static int cmp_d(const void *a, const void *b) {
  const double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}

/* the upper median (v[n / 2]), as this bench has always reported, not
 * bench_median's mean of the two middle values */
static double median(double *v, int n) {
  qsort(v, (size_t)n, sizeof *v, cmp_d);
  return v[n / 2];
}

static void die(mx_mesher *m, const char *what, int st) {
  fprintf(stderr, "remesh-bench: %s failed (%s): %s\n", what, mx_status_string(st),
          m ? mx_mesher_last_error(m) : "");
  exit(1);
}
#define RUN(m, call, what)              \
  do {                                  \
    int st_ = (call);                   \
    if (st_) die(m, what, st_);         \
  } while (0)

static mx_mesher *new_mesher(const char *surface, int level) {
  mx_params p;
  mx_params_default(&p);
  p.surface_level = level;
  mx_mesher *m = mx_mesher_new(&p);
  if (!m) die(NULL, "new", MX_ENOMEM);
  RUN(m, mx_mesher_add_surface(m, surface), "add_surface");
  return m;
}

/* Elements of m's mesh with a node inside [lo, hi]. */
static uint64_t *elements_in_box(const mx_mesher *m, const double lo[3], const double hi[3],
                                 size_t *n) {
  mx_mesh_arrays a;
  mx_mesher_mesh_arrays(m, &a);
  uint64_t *list = malloc((a.nelements + 1) * sizeof *list);
  static const int nn[4] = {4, 5, 6, 8};
  *n = 0;
  for (size_t c = 0; c < a.nelements; c++)
    for (int k = 0; k < nn[a.type[c]]; k++) {
      const double *p = a.xyz + 3 * (size_t)a.conn[8 * c + k];
      if (p[0] >= lo[0] && p[0] <= hi[0] && p[1] >= lo[1] && p[1] <= hi[1] &&
          p[2] >= lo[2] && p[2] <= hi[2]) {
        list[(*n)++] = c;
        break;
      }
    }
  return list;
}

/* Local re-mesh against a full one: same nodes and elements? */
typedef struct {
  int same_counts;
  size_t cells_differ;  /* type or connectivity */
  double max_move;      /* largest node position difference */
} mesh_diff;

static mesh_diff compare_meshes(const mx_mesher *x, const mx_mesher *y) {
  mx_mesh_arrays a, b;
  mx_mesher_mesh_arrays(x, &a);
  mx_mesher_mesh_arrays(y, &b);
  mesh_diff d = {a.nnodes == b.nnodes && a.nelements == b.nelements, 0, 0.0};
  if (!d.same_counts) return d;
  for (size_t c = 0; c < a.nelements; c++)
    d.cells_differ += a.type[c] != b.type[c] ||
                      memcmp(a.conn + 8 * c, b.conn + 8 * c, 8 * sizeof *a.conn) != 0;
  for (size_t v = 0; v < 3 * a.nnodes; v++) {
    const double e = fabs(a.xyz[v] - b.xyz[v]);
    if (e > d.max_move) d.max_move = e;
  }
  return d;
}

static void write_list(const char *path, const uint64_t *l, size_t n) {
  FILE *f = fopen(path, "w");
  for (size_t i = 0; i < n; i++) fprintf(f, "%llu\n", (unsigned long long)l[i]);
  fclose(f);
}

/* ---- 3. the choice between a local and a full re-mesh ----------------- */

static const char *const list_names[4] = {"scattered", "cluster", "box", "bigbox"};
static const int modes[3] = {-1, 1, 0}; /* params.remesh_full */

/* List k of m's mesh (see the head); box: the box of part 2 grown to hold
 * about 4% of the elements; bigbox: 12%. */
static uint64_t *choice_list(const mx_mesher *m, int k, const double blo[3], const double bhi[3],
                             size_t *n) {
  mx_mesh_arrays a;
  mx_mesher_mesh_arrays(m, &a);
  const size_t nc = a.nelements;
  if (k == 0 || k == 1) {
    uint64_t *l = malloc(50 * sizeof *l);
    *n = 0;
    for (size_t i = 0; i < 50 && i < nc; i++)
      l[(*n)++] = k == 0 ? (2 * i + 1) * (nc / 100) : nc / 2 + i;
    return l;
  }
  double c[3], h = 0.5 * (bhi[0] - blo[0]);
  for (int d = 0; d < 3; d++) c[d] = 0.5 * (blo[d] + bhi[d]);
  uint64_t *l = NULL;
  const double share = k == 2 ? 0.04 : 0.12;
  for (int it = 0; it < 40; it++) {
    double lo[3] = {c[0] - h, c[1] - h, c[2] - h}, hi[3] = {c[0] + h, c[1] + h, c[2] + h};
    free(l);
    l = elements_in_box(m, lo, hi, n);
    const double f = (double)*n / (double)nc;
    if (fabs(f - share) < 0.1 * share) break;
    h *= f > 0 ? pow(share / f, 1.0 / 3.0) : 2.0;
  }
  return l;
}

typedef struct {
  double t_init, t_remesh, t_mesh; /* t_mesh: finding the patch, transition, boundary */
  size_t leaves, patch, listed;
  int local, repair_rounds;
} choice_run;

static choice_run choice_once(const char *surface, int level, int list, int mode,
                              const double blo[3], const double bhi[3]) {
  choice_run r;
  memset(&r, 0, sizeof r);
  mx_params p;
  mx_params_default(&p);
  p.surface_level = level;
  p.remesh_full = modes[mode];
  double t0 = bench_now();
  mx_mesher *m = mx_mesher_new(&p);
  if (!m) die(NULL, "new", MX_ENOMEM);
  RUN(m, mx_mesher_add_surface(m, surface), "add_surface");
  RUN(m, mx_mesher_mesh(m), "mesh");
  r.t_init = bench_now() - t0;
  uint64_t *l = choice_list(m, list, blo, bhi, &r.listed);
  t0 = bench_now();
  RUN(m, mx_mesher_refine_elements(m, l, r.listed), "refine elements");
  r.t_remesh = bench_now() - t0;
  free(l);
  mx_stats s;
  mx_mesher_stats(m, &s);
  r.t_mesh = s.t_grid + s.t_transition + s.t_boundary;
  r.leaves = s.leaves;
  r.patch = s.remesh_patch_leaves;
  r.local = s.remesh_local;
  r.repair_rounds = s.repair_rounds;
  if (s.invalid) {
    fprintf(stderr, "remesh-bench: %zu invalid elements after the re-mesh\n", s.invalid);
    exit(1);
  }
  mx_mesher_free(m);
  return r;
}

static int choice_bench(const char *data, const char *levels, int repeat) {
  char surface[1024], box[1024];
  snprintf(surface, sizeof surface, "%s/surfaces/cortex.off", data);
  snprintf(box, sizeof box, "%s/remesh/roi.box", data);
  double blo[3], bhi[3];
  FILE *f = fopen(box, "r");
  if (!f || fscanf(f, "%lf %lf %lf %lf %lf %lf", &blo[0], &blo[1], &blo[2], &bhi[0], &bhi[1],
                   &bhi[2]) != 6) {
    fprintf(stderr, "remesh-bench: cannot read %s\n", box);
    return 1;
  }
  fclose(f);
  printf("choice between local and full re-meshing, cortex, median of %d (modes alternated; "
         "ratio: re-mesh / initial run of the same mesher, median of the ratios)\n", repeat);
  static char json[16384];
  size_t jn = 0;
  int first = 1;
  for (const char *q = levels; *q;) {
    const int level = atoi(q);
    while (*q && *q != ',') q++;
    if (*q == ',') q++;
    choice_run R[4][3][15];
    for (int r = 0; r < repeat; r++)
      for (int list = 0; list < 4; list++)
        for (int k = 0; k < 3; k++) {
          const int mode = (k + r + list) % 3; /* alternated */
          R[list][mode][r] = choice_once(surface, level, list, mode, blo, bhi);
        }
    /* the re-mesh proper per path: seconds without refinement and balance */
    double xp[4], xl[4], yl[4], full_per_leaf = 0;
    for (int list = 0; list < 4; list++) {
      double v[3][15], ratio[3][15], proper[3][15], init[45];
      int ni = 0;
      for (int mode = 0; mode < 3; mode++)
        for (int r = 0; r < repeat; r++) {
          const choice_run *c = &R[list][mode][r];
          v[mode][r] = c->t_remesh;
          ratio[mode][r] = c->t_remesh / c->t_init;
          proper[mode][r] = c->t_mesh;
          init[ni++] = c->t_init;
        }
      const choice_run *lo = &R[list][0][0], *fu = &R[list][1][0], *ch = &R[list][2][0];
      const double mi = median(init, ni);
      double med[3], rat[3], pro[3];
      for (int mode = 0; mode < 3; mode++) {
        med[mode] = median(v[mode], repeat);
        rat[mode] = median(ratio[mode], repeat);
        pro[mode] = median(proper[mode], repeat);
      }
      /* each repair round is one re-mesh more: a splice of the local path
       * (a patch of a few leaves), the whole octree on the full path */
      xp[list] = (double)lo->patch;
      xl[list] = (double)lo->leaves * (1 + lo->repair_rounds);
      yl[list] = pro[0];
      full_per_leaf += pro[1] / ((double)fu->leaves * (1 + fu->repair_rounds)) / 4.0;
      printf("-s %d %-9s: %zu elements listed, initial %.3f s; %zu leaves after; local: "
             "patch of %zu leaves (%.1f%%), %.3f s = %.1f%% (re-mesh proper %.3f s, %d repair "
             "round(s)); full: %.3f s = %.1f%% (proper %.3f s); choice: %s, %.3f s = %.1f%%; "
             "choice / full %.2f\n",
             level, list_names[list], lo->listed, mi, lo->leaves, lo->patch,
             100.0 * (double)lo->patch / (double)lo->leaves, med[0], 100 * rat[0], pro[0],
             lo->repair_rounds, med[1], 100 * rat[1], pro[1], ch->local ? "local" : "full",
             med[2], 100 * rat[2], med[2] / med[1]);
      fflush(stdout);
      if (jn < sizeof json)
        jn += (size_t)snprintf(json + jn, sizeof json - jn, "%s{\"level\": %d, \"list\": \"%s\", \"listed\": %zu, "
              "\"initial_s\": %.4f, \"leaves\": %zu, \"patch\": %zu, \"local_s\": %.4f, "
              "\"full_s\": %.4f, \"choice_s\": %.4f, \"choice_local\": %d, \"local_ratio\": "
              "%.4f, \"full_ratio\": %.4f, \"choice_ratio\": %.4f, \"local_proper_s\": %.4f, "
              "\"full_proper_s\": %.4f}", first ? "" : ", ", level, list_names[list],
              lo->listed, mi, lo->leaves, lo->patch, med[0], med[1], med[2], ch->local,
              rat[0], rat[1], rat[2], pro[0], pro[1]);
      first = 0;
    }
    /* t = a * leaves + b * patch, least squares over the lists of one spot
     * (scattered marks have their first patch refused at times: two
     * patches) */
    double sll = 0, slp = 0, spp = 0, sly = 0, spy = 0;
    for (int i = 1; i < 4; i++) {
      sll += xl[i] * xl[i];
      slp += xl[i] * xp[i];
      spp += xp[i] * xp[i];
      sly += xl[i] * yl[i];
      spy += xp[i] * yl[i];
    }
    const double det = sll * spp - slp * slp;
    const double a = det != 0 ? (sly * spp - spy * slp) / det : 0,
                 b = det != 0 ? (spy * sll - sly * slp) / det : 0;
    printf("-s %d cost per leaf (ns): full %.0f; local %.0f per leaf of the octree (splice, "
           "rings) + %.0f per patch leaf: a patch pays below %.1f%% of the leaves\n", level,
           1e9 * full_per_leaf, 1e9 * a, 1e9 * b,
           b > 0 ? 100.0 * (full_per_leaf - a) / b : 100.0);
    if (jn < sizeof json)
      jn += (size_t)snprintf(json + jn, sizeof json - jn, ", {\"level\": %d, "
                             "\"full_ns_per_leaf\": %.1f, \"local_ns_per_leaf\": %.1f, "
                             "\"local_ns_per_patch_leaf\": %.1f}", level, 1e9 * full_per_leaf,
                             1e9 * a, 1e9 * b);
  }
  printf("{\"choice\": [%s]}\n", json);
  return 0;
}

int main(int argc, char **argv) {
  mx_heap_setup(); /* as the mixoct program does */
  const char *data = "../shared/data", *out = "/tmp";
  int level = 8, repeat = 3, choice = 0;
  const char *levels = "6,7,8";
  for (int i = 1; i < argc; i++) {
    if (!strcmp(argv[i], "--data") && i + 1 < argc) data = argv[++i];
    else if (!strcmp(argv[i], "--choice")) choice = 1;
    else if (!strcmp(argv[i], "--levels") && i + 1 < argc) levels = argv[++i];
    else if (!strcmp(argv[i], "--level") && i + 1 < argc) level = atoi(argv[++i]);
    else if (!strcmp(argv[i], "--repeat") && i + 1 < argc) repeat = atoi(argv[++i]);
    else if (!strcmp(argv[i], "--out") && i + 1 < argc) out = argv[++i];
    else {
      fprintf(stderr, "usage: %s [--data DIR] [--level L] [--repeat N] [--out DIR]\n"
                      "       %s --choice [--data DIR] [--levels 6,7,8] [--repeat N]\n",
              argv[0], argv[0]);
      return 2;
    }
  }
  if (repeat < 1) repeat = 1;
  if (repeat > 15) repeat = 15;
  if (choice) return choice_bench(data, levels, repeat);
  char surface[1024], pub_oct[1024], pub_list[1024], box[1024];
  snprintf(surface, sizeof surface, "%s/surfaces/cortex.off", data);
  snprintf(pub_oct, sizeof pub_oct, "%s/remesh/c5.oct", data);
  snprintf(pub_list, sizeof pub_list, "%s/remesh/list.txt", data);
  snprintf(box, sizeof box, "%s/remesh/roi.box", data);
  double blo[3], bhi[3];
  {
    FILE *f = fopen(box, "r");
    if (!f || fscanf(f, "%lf %lf %lf %lf %lf %lf", &blo[0], &blo[1], &blo[2], &bhi[0],
                     &bhi[1], &bhi[2]) != 6) {
      fprintf(stderr, "remesh-bench: cannot read %s\n", box);
      return 1;
    }
    fclose(f);
  }
  char o_vtk[1200], o_oct[1200], o_list[1200], r_vtk[1200], b_oct[1200];
  snprintf(o_vtk, sizeof o_vtk, "%s/rb_c5.vtk", out);
  snprintf(o_oct, sizeof o_oct, "%s/rb_c5.oct", out);
  snprintf(o_list, sizeof o_list, "%s/rb_c5_list.txt", out);
  snprintf(r_vtk, sizeof r_vtk, "%s/rb_c5r.vtk", out);
  snprintf(b_oct, sizeof b_oct, "%s/rb_big.octb", out);

  /* ---- 1. Table 1 scenario at -s 5 ---------------------------------- */
  double t_init[15], t_pub[15], t_own[15];
  mx_stats s_init, s_pub, s_own;
  size_t n_own = 0;
  double pub_write = 0;
  for (int r = 0; r < repeat; r++) {
    double t0 = bench_now();
    mx_mesher *m = new_mesher(surface, 5);
    RUN(m, mx_mesher_mesh(m), "mesh -s 5");
    RUN(m, mx_mesher_write(m, o_vtk, 1), "write");
    RUN(m, mx_mesher_save_restart(m, o_oct), "save restart");
    t_init[r] = bench_now() - t0;
    mx_mesher_stats(m, &s_init);
    uint64_t *l = elements_in_box(m, blo, bhi, &n_own);
    write_list(o_list, l, n_own);
    free(l);
    mx_mesher_free(m);
  }
  for (int pass = 0; pass < 2; pass++)
    for (int r = 0; r < repeat; r++) {
      double t0 = bench_now();
      mx_mesher *m = new_mesher(surface, -1);
      RUN(m, mx_mesher_load_restart(m, pass ? o_oct : pub_oct), "load restart");
      uint64_t *l = NULL;
      size_t n = 0;
      RUN(m, mx_read_element_list(pass ? o_list : pub_list, UINT64_MAX, &l, &n), "list");
      RUN(m, mx_mesher_refine_elements(m, l, n), "refine elements");
      const double tw = bench_now();
      RUN(m, mx_mesher_write(m, r_vtk, 1), "write");
      if (!pass) pub_write = bench_now() - tw;
      (pass ? t_own : t_pub)[r] = bench_now() - t0;
      mx_mesher_stats(m, pass ? &s_own : &s_pub);
      mx_free_array(l);
      mx_mesher_free(m);
    }
  const double mi = median(t_init, repeat), mp = median(t_pub, repeat),
               mo = median(t_own, repeat);
  printf("Table 1 scenario, cortex -s 5 (median of %d; each includes reading the surface "
         "and writing ASCII VTK):\n", repeat);
  printf("  initial run (mesh, write .vtk, write .oct): %zu nodes, %zu elements, %.1f ms "
         "(published: 728 ms)\n", s_init.nodes, s_init.elements, 1e3 * mi);
  printf("  re-mesh from the published c5.oct + list.txt (1,139 elements): %zu nodes, %zu "
         "elements, %zu invalid, %.1f ms (published: 14,319 / 33,254, 637 ms): %.1fx "
         "faster\n", s_pub.nodes, s_pub.elements, s_pub.invalid, 1e3 * mp, 0.637 / mp);
  printf("    phases of the last re-mesh from c5.oct (ms): restart file %.1f, refine %.1f, "
         "balance %.1f, transition %.1f, boundary %.1f, quality %.1f; write %.1f\n",
         1e3 * s_pub.t_restart, 1e3 * s_pub.t_refine, 1e3 * s_pub.t_balance,
         1e3 * s_pub.t_transition, 1e3 * s_pub.t_boundary, 1e3 * s_pub.t_quality,
         1e3 * pub_write);
  printf("  re-mesh from our restart file + our %zu elements in roi.box: %zu nodes, %zu "
         "elements, %zu invalid, %.1f ms: %.1fx faster than the published re-mesh\n",
         n_own, s_own.nodes, s_own.elements, s_own.invalid, 1e3 * mo, 0.637 / mo);

  /* ---- 2. -s level: 4% of the elements ------------------------------ */
  double t_big[15], t_mem[15], t_bin[15], t_save = 0, list_lo[3] = {0, 0, 0},
                                                     list_hi[3] = {0, 0, 0};
  size_t n_big = 0;
  mx_stats s_big, s_mem, s_bin;
  double t_load[15];
  mesh_diff bin_diff = {0, 0, 0.0};
  for (int r = 0; r < repeat; r++) {
    double t0 = bench_now();
    mx_mesher *m = new_mesher(surface, level);
    RUN(m, mx_mesher_mesh(m), "mesh");
    t_big[r] = bench_now() - t0;
    mx_mesher_stats(m, &s_big);
    /* a box around roi.box's centre holding about 4% of the elements */
    double c[3], h = 0.5 * (bhi[0] - blo[0]);
    for (int a = 0; a < 3; a++) c[a] = 0.5 * (blo[a] + bhi[a]);
    uint64_t *l = NULL;
    for (int it = 0; it < 40; it++) {
      double lo[3] = {c[0] - h, c[1] - h, c[2] - h}, hi[3] = {c[0] + h, c[1] + h, c[2] + h};
      free(l);
      l = elements_in_box(m, lo, hi, &n_big);
      memcpy(list_lo, lo, sizeof lo);
      memcpy(list_hi, hi, sizeof hi);
      const double f = (double)n_big / (double)s_big.elements;
      if (fabs(f - 0.04) < 0.004) break;
      h *= f > 0 ? pow(0.04 / f, 1.0 / 3.0) : 2.0;
    }
    t0 = bench_now();
    RUN(m, mx_mesher_save_restart(m, b_oct), "save binary restart");
    t_save = bench_now() - t0;
    /* a mesher loaded from the file takes element indices in the files'
     * written order (mixoct.h), the in-memory one in its arrays' order: the
     * same elements, renumbered */
    uint64_t *lw = malloc((n_big + 1) * sizeof *lw);
    {
      uint32_t *order = malloc((s_big.elements + 1) * sizeof *order);
      uint64_t *pos = malloc((s_big.elements + 1) * sizeof *pos);
      if (!lw || !order || !pos || mx_mesher_written_order(m, order) != MX_OK) {
        fprintf(stderr, "remesh-bench: written order failed\n");
        return 1;
      }
      for (size_t k = 0; k < s_big.elements; k++) pos[order[k]] = k;
      for (size_t i = 0; i < n_big; i++) lw[i] = pos[l[i]];
      free(order);
      free(pos);
    }
    t0 = bench_now();
    RUN(m, mx_mesher_refine_elements(m, l, n_big), "refine in memory");
    t_mem[r] = bench_now() - t0;
    mx_mesher_stats(m, &s_mem);
    t0 = bench_now();
    mx_mesher *b = new_mesher(surface, -1);
    RUN(b, mx_mesher_load_restart(b, b_oct), "load binary restart");
    t_load[r] = bench_now() - t0;
    RUN(b, mx_mesher_refine_elements(b, lw, n_big), "refine from the binary restart");
    free(lw);
    t_bin[r] = bench_now() - t0;
    mx_mesher_stats(b, &s_bin);
    bin_diff = compare_meshes(m, b);
    mx_mesher_free(b);
    mx_mesher_free(m);
    free(l);
  }
  /* the local re-mesh against a full re-mesh of the same octree */
  mesh_diff diff;
  double t_full = 0;
  {
    mx_mesher *m = new_mesher(surface, level);
    RUN(m, mx_mesher_mesh(m), "mesh");
    mx_params p;
    mx_params_default(&p);
    p.surface_level = level;
    p.remesh_full = 1;
    mx_mesher *f = mx_mesher_new(&p);
    RUN(f, mx_mesher_add_surface(f, surface), "add_surface");
    RUN(f, mx_mesher_mesh(f), "mesh");
    uint64_t *l = elements_in_box(m, list_lo, list_hi, &n_big);
    RUN(m, mx_mesher_refine_elements(m, l, n_big), "local re-mesh");
    double t0 = bench_now();
    RUN(f, mx_mesher_refine_elements(f, l, n_big), "full re-mesh");
    t_full = bench_now() - t0;
    diff = compare_meshes(m, f);
    free(l);
    mx_mesher_free(m);
    mx_mesher_free(f);
  }
  const double mb = median(t_big, repeat), mm = median(t_mem, repeat),
               mbn = median(t_bin, repeat);
  printf("cortex -s %d: initial %zu nodes, %zu elements, %.3f s; %zu elements listed "
         "(%.1f%%)\n", level, s_big.nodes, s_big.elements, mb, n_big,
         100.0 * (double)n_big / (double)s_big.elements);
  printf("  re-mesh in memory: %.3f s = %.1f%% of the initial run (target 10%%); %zu nodes, "
         "%zu elements, %zu invalid\n", mm, 100 * mm / mb, s_mem.nodes, s_mem.elements,
         s_mem.invalid);
  printf("    phases of the last in-memory re-mesh (s): refine %.3f balance %.3f transition "
         "%.3f boundary %.3f quality %.3f; %zu leaves split by the list, %zu repaired in %d "
         "round(s); %s re-mesh: %zu of the %zu leaves meshed again (%.1f%%)\n",
         s_mem.t_refine, s_mem.t_balance, s_mem.t_transition, s_mem.t_boundary,
         s_mem.t_quality, s_mem.refined_listed, s_mem.repaired, s_mem.repair_rounds,
         s_mem.remesh_local ? "local" : "FULL", s_mem.remesh_patch_leaves, s_mem.leaves,
         100.0 * (double)s_mem.remesh_patch_leaves / (double)s_mem.leaves);
  printf("    phases of the initial run (s): refine %.3f balance %.3f transition %.3f boundary "
         "%.3f quality %.3f\n", s_big.t_refine, s_big.t_balance, s_big.t_transition,
         s_big.t_boundary, s_big.t_quality);
  printf("  full re-mesh of the same octree (params.remesh_full): %.3f s; local against full: "
         "%s, %zu element(s) differ, largest node position difference %.3g\n", t_full,
         diff.same_counts ? "same node and element counts" : "COUNTS DIFFER", diff.cells_differ,
         diff.max_move);
  const int same_bin = bin_diff.same_counts && !bin_diff.cells_differ && bin_diff.max_move == 0.0 &&
                       s_bin.leaves_hash == s_mem.leaves_hash;
  printf("  re-mesh from the binary restart file: %.3f s = %.1f%% (target 25%%), of which "
         "loading it %.3f s; the same mesh as in memory: %s; writing the .octb took %.3f s\n",
         mbn, 100 * mbn / mb, median(t_load, repeat), same_bin ? "yes" : "NO", t_save);
  printf("{\"c5\": {\"initial_ms\": %.2f, \"nodes\": %zu, \"elements\": %zu, "
         "\"remesh_published_ms\": %.2f, \"remesh_published_nodes\": %zu, "
         "\"remesh_published_elements\": %zu, \"remesh_published_invalid\": %zu, "
         "\"remesh_own_ms\": %.2f, \"remesh_own_nodes\": %zu, \"remesh_own_elements\": %zu}, "
         "\"big\": {\"level\": %d, \"initial_s\": %.4f, \"listed\": %zu, \"elements\": %zu, "
         "\"remesh_memory_s\": %.4f, \"remesh_binary_s\": %.4f, \"save_binary_s\": %.4f}}\n",
         1e3 * mi, s_init.nodes, s_init.elements, 1e3 * mp, s_pub.nodes, s_pub.elements,
         s_pub.invalid, 1e3 * mo, s_own.nodes, s_own.elements, level, mb, n_big,
         s_big.elements, mm, mbn, t_save);
  return 0;
}
