/* mixoct benchmark harness: runs `mixoct --json` on the cortex at -s 4..9
 * with both balances and 1 and 2 threads, and prints a table and one JSON
 * object with leaves, refine and balance seconds, peak RSS, and the ratios
 * (edges vs recursive, 2 threads vs 1, against the reference's figures);
 * then the transition stage, and the whole pipeline (--stage full) with
 * its node and element counts, quality and time against the reference.
 *
 * usage: mixoct-bench [--mixoct PATH] [--input cortex.off] [--levels 4-9]
 *                     [--repeat N] [--json-only]
 * Each configuration runs N times (default 3) and the fastest run is kept. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>

typedef struct {
  double leaves, refine, balance, transition, boundary, nodes, elements, rss, total;
  double invalid, below02, jens_min;
  char hash[32];
  int ok;
} result;

/* Reference (REFERENCE.md): refine+balance seconds and octants entering the
 * transition stage, published mesher, one thread. */
static const double ref_rb[10] = {0, 0, 0, 0, 0.063, 0.181, 0.743, 2.757, 11.64, 48.67};
static const double ref_leaves[10] = {0, 0, 0, 0, 2241, 10123, 43904, 183473, 751949, 3047636};

static double json_num(const char *s, const char *key) {
  char pat[64];
  snprintf(pat, sizeof pat, "\"%s\": ", key);
  const char *p = strstr(s, pat);
  return p ? atof(p + strlen(pat)) : -1.0;
}

static void json_str(const char *s, const char *key, char *out, size_t n) {
  char pat[64];
  snprintf(pat, sizeof pat, "\"%s\": \"", key);
  const char *p = strstr(s, pat);
  out[0] = 0;
  if (!p) return;
  p += strlen(pat);
  size_t i = 0;
  while (p[i] && p[i] != '"' && i + 1 < n) {
    out[i] = p[i];
    i++;
  }
  out[i] = 0;
}

static result run_once(const char *mixoct, const char *input, int level,
                       const char *balance, int threads, const char *stage) {
  result r;
  memset(&r, 0, sizeof r);
  char cmd[2048];
  snprintf(cmd, sizeof cmd, "'%s' -i '%s' -s %d --balance %s --threads %d "
           "--stage %s --json --quiet", mixoct, input, level, balance, threads, stage);
  FILE *p = popen(cmd, "r");
  if (!p) return r;
  char line[8192], last[8192] = "";
  while (fgets(line, sizeof line, p)) memcpy(last, line, sizeof line);
  int st = pclose(p);
  if (st != 0 || !strchr(last, '{')) return r;
  r.leaves = json_num(last, "leaves");
  const char *ph = strstr(last, "\"phases\"");
  if (!ph) return r;
  r.refine = json_num(ph, "refine");
  r.balance = json_num(ph, "balance");
  r.transition = json_num(ph, "transition");
  r.boundary = json_num(ph, "boundary");
  r.invalid = json_num(last, "invalid");
  r.below02 = json_num(last, "below_0.2");
  r.jens_min = json_num(last, "jens_min");
  r.nodes = json_num(last, "nodes");
  r.elements = json_num(last, "elements");
  r.rss = json_num(last, "peak_rss_mb");
  r.total = json_num(last, "total_s");
  json_str(last, "leaves_hash", r.hash, sizeof r.hash);
  r.ok = 1;
  return r;
}

static result run_best(const char *mixoct, const char *input, int level,
                       const char *balance, int threads, int repeat,
                       const char *stage) {
  result best;
  memset(&best, 0, sizeof best);
  for (int i = 0; i < repeat; i++) {
    result r = run_once(mixoct, input, level, balance, threads, stage);
    if (!r.ok) return r;
    if (!best.ok || (!strcmp(stage, "full") ? r.total < best.total
                                            : r.refine + r.balance + r.transition <
                                                  best.refine + best.balance + best.transition))
      best = r;
  }
  return best;
}

/* Reference: seconds of the transition patterns at RL9 (REFERENCE.md). */
static const double ref_transition9 = 21.3;
/* Reference final meshes (REFERENCE.md): nodes, elements, wall seconds
 * without the write (generation), peak RSS, elements with J_ENS < 0.2. */
static const double ref_nodes[10] = {0, 0, 0, 0, 2230, 10941, 49431, 211685, 877104, 3571742};
static const double ref_elements[10] = {0, 0, 0, 0, 5111, 26209, 119910, 518987, 2160418, 8811570};
static const double ref_gen_s[10] = {0, 0, 0, 0, 0.117, 0.369, 1.665, 7.157, 29.68, 128.99};
static const double ref_rss[10] = {0, 0, 0, 0, 13, 34, 121, 490, 1996, 8072};
static const double ref_below02[10] = {0, 0, 0, 0, 6, 17, 92, -1, -1, -1};

int main(int argc, char **argv) {
  const char *mixoct = "build/mixoct";
  const char *input = "../shared/data/surfaces/cortex.off";
  int lo = 4, hi = 9, repeat = 3, json_only = 0;
  for (int i = 1; i < argc; i++) {
    if (!strcmp(argv[i], "--mixoct") && i + 1 < argc) mixoct = argv[++i];
    else if (!strcmp(argv[i], "--input") && i + 1 < argc) input = argv[++i];
    else if (!strcmp(argv[i], "--levels") && i + 1 < argc) {
      if (sscanf(argv[++i], "%d-%d", &lo, &hi) != 2 || lo < 1 || hi > 9 || lo > hi) {
        fprintf(stderr, "mixoct-bench: --levels wants A-B within 1-9\n");
        return 2;
      }
    } else if (!strcmp(argv[i], "--repeat") && i + 1 < argc) repeat = atoi(argv[++i]);
    else if (!strcmp(argv[i], "--json-only")) json_only = 1;
    else {
      fprintf(stderr, "usage: mixoct-bench [--mixoct PATH] [--input FILE] "
                      "[--levels 4-9] [--repeat N] [--json-only]\n");
      return 2;
    }
  }
  if (repeat < 1) repeat = 1;
  const char *bal[2] = {"edges", "recursive"};
  result R[10][2][2]; /* level, balance, threads-1 */
  int fail = 0;
  if (!json_only) {
    printf("mixoct bench: %s, best of %d runs; rb = refine + balance seconds\n",
           input, repeat);
    printf("%3s %-9s %2s %10s %7s %9s %9s %9s %8s %8s %9s %9s\n", "RL", "balance",
           "th", "leaves", "vs ref", "refine s", "balance s", "rb s", "peak MB",
           "2t/1t", "rec/edges", "ref/this");
  }
  for (int l = lo; l <= hi; l++) {
    for (int b = 0; b < 2; b++)
      for (int t = 0; t < 2; t++) {
        R[l][b][t] = run_best(mixoct, input, l, bal[b], t + 1, repeat, "octree");
        if (!R[l][b][t].ok) {
          fprintf(stderr, "mixoct-bench: run failed: -s %d --balance %s --threads %d\n",
                  l, bal[b], t + 1);
          fail = 1;
        }
      }
    if (fail) break;
    const result *e1 = &R[l][0][0];
    int same = 1;
    for (int b = 0; b < 2; b++)
      for (int t = 0; t < 2; t++) same &= !strcmp(e1->hash, R[l][b][t].hash);
    if (!same) {
      fprintf(stderr, "mixoct-bench: leaves differ at -s %d\n", l);
      fail = 1;
    }
    if (json_only) continue;
    for (int b = 0; b < 2; b++)
      for (int t = 0; t < 2; t++) {
        const result *r = &R[l][b][t];
        const double rb = r->refine + r->balance;
        const double rb1 = R[l][b][0].refine + R[l][b][0].balance;
        const double rbe = R[l][0][t].refine + R[l][0][t].balance;
        char sp[16] = "", re[16] = "";
        if (t) snprintf(sp, sizeof sp, "%.2fx", rb1 / rb);
        if (b) snprintf(re, sizeof re, "%.2fx", rb / rbe);
        printf("%3d %-9s %2d %10.0f %+6.2f%% %9.3f %9.3f %9.3f %8.0f %8s %9s %8.1fx%s\n",
               l, bal[b], t + 1, r->leaves,
               100.0 * (r->leaves - ref_leaves[l]) / ref_leaves[l], r->refine,
               r->balance, rb, r->rss, sp, re, ref_rb[l] / rb,
               same ? "" : "  LEAVES DIFFER");
      }
  }
  if (fail) return 1;
  /* The transition stage (edge infos), 1 and 2 threads. */
  result X[10][2];
  if (!json_only)
    printf("\ntransition stage (conforming mesh of the octree), best of %d\n"
           "%3s %2s %10s %10s %12s %9s %8s %9s\n", repeat, "RL", "th", "nodes",
           "elements", "transition s", "2t/1t", "peak MB", "ref/this");
  for (int l = lo; l <= hi; l++)
    for (int t = 0; t < 2; t++) {
      X[l][t] = run_best(mixoct, input, l, "edges", t + 1, repeat, "transition");
      if (!X[l][t].ok) return 1;
      if (json_only) continue;
      char sp[16] = "", rf[16] = "";
      if (t) snprintf(sp, sizeof sp, "%.2fx", X[l][0].transition / X[l][1].transition);
      if (l == 9) snprintf(rf, sizeof rf, "%.1fx", ref_transition9 / X[l][t].transition);
      printf("%3d %2d %10.0f %10.0f %12.3f %9s %8.0f %9s\n", l, t + 1, X[l][t].nodes,
             X[l][t].elements, X[l][t].transition, sp, X[l][t].rss, rf);
    }
  /* The whole pipeline (--stage full, no output file), 2 threads. */
  result F[10];
  if (!json_only)
    printf("\nfull pipeline (domain mesh, no write), 2 threads, best of %d\n"
           "%3s %10s %7s %10s %7s %7s %6s %9s %10s %9s %8s %8s\n", repeat, "RL", "nodes",
           "vs ref", "elements", "vs ref", "invalid", "<0.2", "ref <0.2", "boundary s",
           "total s", "ref/this", "MB");
  for (int l = lo; l <= hi; l++) {
    F[l] = run_best(mixoct, input, l, "edges", 2, repeat, "full");
    if (!F[l].ok) return 1;
    if (json_only) continue;
    char rb[16] = "-";
    if (ref_below02[l] >= 0) snprintf(rb, sizeof rb, "%.0f", ref_below02[l]);
    printf("%3d %10.0f %+6.2f%% %10.0f %+6.2f%% %7.0f %6.0f %9s %10.3f %9.3f %7.1fx %8.0f\n", l,
           F[l].nodes, 100.0 * (F[l].nodes - ref_nodes[l]) / ref_nodes[l], F[l].elements,
           100.0 * (F[l].elements - ref_elements[l]) / ref_elements[l], F[l].invalid,
           F[l].below02, rb, F[l].boundary, F[l].total, ref_gen_s[l] / F[l].total, F[l].rss);
  }
  printf("{\"bench\": \"octree\", \"input\": \"%s\", \"repeat\": %d, \"full\": [", input, repeat);
  for (int l = lo; l <= hi; l++)
    printf("%s{\"rl\": %d, \"nodes\": %.0f, \"reference_nodes\": %.0f, \"elements\": %.0f, "
           "\"reference_elements\": %.0f, \"invalid\": %.0f, \"below_0.2\": %.0f, "
           "\"jens_min\": %.6f, \"boundary_s_2t\": %.6f, \"total_s_2t\": %.6f, "
           "\"reference_generation_s\": %.3f, \"peak_rss_mb\": %.1f, \"reference_rss_mb\": %.0f}",
           l > lo ? ", " : "", l, F[l].nodes, ref_nodes[l], F[l].elements, ref_elements[l],
           F[l].invalid, F[l].below02, F[l].jens_min, F[l].boundary, F[l].total, ref_gen_s[l],
           F[l].rss, ref_rss[l]);
  printf("], \"transition\": [");
  for (int l = lo; l <= hi; l++)
    printf("%s{\"rl\": %d, \"nodes\": %.0f, \"elements\": %.0f, \"transition_s_1t\": %.6f, "
           "\"transition_s_2t\": %.6f, \"peak_rss_mb_2t\": %.1f}", l > lo ? ", " : "", l,
           X[l][1].nodes, X[l][1].elements, X[l][0].transition, X[l][1].transition, X[l][1].rss);
  printf("], \"levels\": [");
  for (int l = lo; l <= hi; l++) {
    printf("%s{\"rl\": %d, \"leaves\": %.0f, \"reference_leaves\": %.0f, \"hash\": \"%s\", \"runs\": [",
           l > lo ? ", " : "", l, R[l][0][0].leaves, ref_leaves[l], R[l][0][0].hash);
    for (int b = 0; b < 2; b++)
      for (int t = 0; t < 2; t++) {
        const result *r = &R[l][b][t];
        printf("%s{\"balance\": \"%s\", \"threads\": %d, \"refine_s\": %.6f, "
               "\"balance_s\": %.6f, \"total_s\": %.6f, \"peak_rss_mb\": %.1f}",
               b || t ? ", " : "", bal[b], t + 1, r->refine, r->balance, r->total, r->rss);
      }
    double e2 = R[l][0][1].refine + R[l][0][1].balance;
    double e1 = R[l][0][0].refine + R[l][0][0].balance;
    double r1 = R[l][1][0].refine + R[l][1][0].balance;
    printf("], \"recursive_over_edges_1t\": %.3f, \"speedup_2t\": %.3f, "
           "\"reference_rb_s\": %.3f, \"reference_over_edges_2t\": %.2f}",
           r1 / e1, e1 / e2, ref_rb[l], ref_rb[l] / e2);
  }
  printf("]}\n");
  return 0;
}
