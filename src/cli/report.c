#include "cli/cli.h"

#include <inttypes.h>
#include <stdio.h>

static const char *type_name[4] = {"tet", "pyramid", "prism", "hex"};

/* The quality table as JSON: histogram with the bins of Table IV of the 2015
 * paper, min / max / mean per type (Table V). */
static void quality_json(const mx_quality_table *q, char *buf, size_t n) {
  size_t w = (size_t)snprintf(buf, n,
      "{\"histogram\": {\"lt_0.03\": %zu, \"lt_0.2\": %zu, \"lt_0.4\": %zu, "
      "\"lt_0.6\": %zu, \"lt_0.8\": %zu, \"le_1\": %zu}, \"below_0.2\": %zu, "
      "\"by_type\": {", q->bins[0], q->bins[1], q->bins[2], q->bins[3],
      q->bins[4], q->bins[5], q->below_02);
  for (int t = 0; t < 4 && w < n; t++)
    w += (size_t)snprintf(buf + w, n - w,
        "%s\"%s\": {\"count\": %zu, \"min\": %.6f, \"max\": %.6f, \"mean\": %.6f}",
        t ? ", " : "", type_name[t], q->count[t], q->count[t] ? q->min[t] : 0.0,
        q->count[t] ? q->max[t] : 0.0, q->mean[t]);
  if (w < n) snprintf(buf + w, n - w, "}}");
}

void mx_print_json(const mx_summary *s) {
  char nodes[32] = "null";
  if (s->nodes_counted) snprintf(nodes, sizeof nodes, "%zu", s->nodes);
  char topo[256];
  mx_topology_string(topo, sizeof topo);
  const size_t elements = s->mesh ? s->elements : s->leaves;
  char qual[1024] = "null";
  if (s->mesh) quality_json(&s->quality, qual, sizeof qual);
  const size_t hex = s->mesh ? s->by_type[3] : s->leaves;
  char bnd[1024] = "";
  if (s->full) {
    const mx_boundary_stats *b = &s->boundary;
    snprintf(bnd, sizeof bnd,
             "\"boundary\": {\"located\": %zu, \"moved_close\": %zu, \"removed\": %zu, "
             "\"patterned\": %zu, \"sub_elements\": %zu, \"optional\": %zu, "
             "\"centres\": %zu, \"shrunk\": %zu, \"restored\": %zu, "
             "\"inverted_by_shrink\": %zu, \"repaired\": %zu, \"repair_rounds\": %d, "
             "\"seconds\": {\"states\": %.6f, \"close\": %.6f, \"patterns\": %.6f, "
             "\"shrink\": %.6f, \"smooth\": %.6f, \"staircase\": %.6f}, "
             "\"smoothed\": %zu}, ",
             b->located, b->moved_close, b->removed, b->sp.patterned, b->sp.kept,
             b->sp.optional, b->sp.centres, b->shrunk, b->sp.restored, b->inverted, s->repaired,
             s->repair_rounds, b->t_states, b->t_close, b->t_patterns, b->t_shrink,
             b->t_smooth, b->t_staircase, b->smoothed);
  }
  printf("{\"leaves\": %zu, \"leaves_hash\": \"%016" PRIx64 "\", "
         "\"nodes\": %s, \"elements\": %zu, "
         "\"by_type\": {\"hex\": %zu, \"prism\": %zu, \"pyramid\": %zu, \"tet\": %zu}, "
         "\"stage\": \"%s\", \"balance\": \"%s\", \"max_level\": %d, "
         "\"octants\": %zu, \"edges\": %zu, \"edge_mb\": %.1f, "
         "\"located\": %zu, \"split_requested\": %zu, \"split_balance\": %zu, "
         "\"dropped\": %zu, \"centre_leaves\": %zu, \"closures\": %zu, "
         "\"phases\": {\"read\": %.6f, \"grid\": %.6f, \"refine\": %.6f, "
         "\"balance\": %.6f, \"transition\": %.6f, \"boundary\": %.6f, "
         "\"quality\": %.6f, \"write\": %.6f}, "
         "\"total_s\": %.6f, \"peak_rss_mb\": %.1f, \"memory_estimate_mb\": %.1f, "
         "\"threads\": %d, "
         "\"jens_min\": %.6f, \"invalid\": %zu, \"quality\": %s, %s"
         "\"topology\": \"%s\"}\n",
         s->leaves, s->leaves_hash, nodes, elements, hex,
         s->mesh ? s->by_type[2] : 0, s->mesh ? s->by_type[1] : 0,
         s->mesh ? s->by_type[0] : 0, s->full ? "full" : s->mesh ? "transition" : "octree",
         s->balance ? "recursive" : "edges", s->max_level, s->octants, s->edges,
         (double)s->edge_bytes / 1048576.0, s->located, s->split_requested,
         s->split_balance, s->dropped, s->centre_leaves, s->closures, s->ph.read,
         s->ph.grid, s->ph.refine, s->ph.balance, s->ph.transition,
         s->ph.boundary, s->ph.quality, s->ph.write,
         s->ph.total, s->peak_rss_mb, s->memory_estimate_mb, s->threads,
         s->mesh ? s->jens_min : 1.0,
         s->mesh ? s->invalid : 0, qual, bnd, topo);
  fflush(stdout);
}

void mx_print_summary(const mx_summary *s) {
  printf("mixoct: %s (%s balance), %d thread(s)\n",
         s->full ? "mesh of the domain" :
         s->mesh ? "conforming mesh of the octree (transition stage)"
                 : "balanced octree",
         s->balance ? "recursive" : "edges", s->threads);
  printf("  leaves        %12zu   (octants created %zu, dropped outside %zu)\n",
         s->leaves, s->octants, s->dropped);
  printf("  splits        %12zu requested, %zu for balance\n",
         s->split_requested, s->split_balance);
  if (s->nodes_counted) printf("  nodes         %12zu\n", s->nodes);
  if (s->mesh) {
    printf("  elements      %12zu   (hex %zu, prism %zu, pyramid %zu, tet %zu)\n",
           s->elements, s->by_type[3], s->by_type[2], s->by_type[1], s->by_type[0]);
    printf("  J_ENS min     %12.3f   (%zu invalid; %zu leaves use the body centre)\n",
           s->jens_min, s->invalid, s->centre_leaves);
    const mx_quality_table *q = &s->quality;
    printf("  J_ENS bins    <0.03 %zu  <0.2 %zu  <0.4 %zu  <0.6 %zu  <0.8 %zu  <=1 %zu\n",
           q->bins[0], q->bins[1], q->bins[2], q->bins[3], q->bins[4], q->bins[5]);
    for (int t = 3; t >= 0; t--)
      if (q->count[t])
        printf("  %-8s      %12zu   J_ENS min %.3f  max %.3f  mean %.3f\n",
               type_name[t], q->count[t], q->min[t], q->max[t], q->mean[t]);
  }
  if (s->full) {
    const mx_boundary_stats *b = &s->boundary;
    printf("  boundary      %zu nodes located, %zu moved close, %zu elements removed,\n"
           "                %zu patterned into %zu (+%zu centres), %zu shrunk,\n"
           "                %zu inverted by the shrink, untangled with %zu node moves, "
           "%zu restored (staircase),\n"
           "                %zu invalid left for %d refinement round(s)\n",
           b->located, b->moved_close, b->removed, b->sp.patterned, b->sp.kept,
           b->sp.centres, b->shrunk, b->inverted, b->smoothed, b->sp.restored, s->repaired,
           s->repair_rounds);
  }
  printf("  time (s)      read %.3f  grid %.3f  refine %.3f  balance %.3f  "
         "transition %.3f  boundary %.3f  write %.3f  total %.3f\n",
         s->ph.read, s->ph.grid, s->ph.refine, s->ph.balance, s->ph.transition,
         s->ph.boundary, s->ph.write, s->ph.total);
  printf("  peak memory   %.0f MB\n", s->peak_rss_mb);
}
