#include "cli/cli.h"

#include <inttypes.h>
#include <stdio.h>

void mx_print_json(const mx_summary *s) {
  char nodes[32] = "null";
  if (s->nodes_counted) snprintf(nodes, sizeof nodes, "%zu", s->nodes);
  char topo[256];
  mx_topology_string(topo, sizeof topo);
  const size_t elements = s->mesh ? s->elements : s->leaves;
  const size_t hex = s->mesh ? s->by_type[3] : s->leaves;
  printf("{\"leaves\": %zu, \"leaves_hash\": \"%016" PRIx64 "\", "
         "\"nodes\": %s, \"elements\": %zu, "
         "\"by_type\": {\"hex\": %zu, \"prism\": %zu, \"pyramid\": %zu, \"tet\": %zu}, "
         "\"stage\": \"%s\", \"balance\": \"%s\", \"max_level\": %d, "
         "\"octants\": %zu, \"edges\": %zu, \"edge_mb\": %.1f, "
         "\"located\": %zu, \"split_requested\": %zu, \"split_balance\": %zu, "
         "\"dropped\": %zu, \"centre_leaves\": %zu, \"closures\": %zu, "
         "\"phases\": {\"read\": %.6f, \"grid\": %.6f, \"refine\": %.6f, "
         "\"balance\": %.6f, \"transition\": %.6f, \"write\": %.6f}, "
         "\"total_s\": %.6f, \"peak_rss_mb\": %.1f, \"threads\": %d, "
         "\"jens_min\": %.6f, \"invalid\": %zu, \"topology\": \"%s\"}\n",
         s->leaves, s->leaves_hash, nodes, elements, hex,
         s->mesh ? s->by_type[2] : 0, s->mesh ? s->by_type[1] : 0,
         s->mesh ? s->by_type[0] : 0, s->mesh ? "transition" : "octree",
         s->balance ? "recursive" : "edges", s->max_level, s->octants, s->edges,
         (double)s->edge_bytes / 1048576.0, s->located, s->split_requested,
         s->split_balance, s->dropped, s->centre_leaves, s->closures, s->ph.read,
         s->ph.grid, s->ph.refine, s->ph.balance, s->ph.transition, s->ph.write,
         s->ph.total, s->peak_rss_mb, s->threads, s->mesh ? s->jens_min : 1.0,
         s->mesh ? s->invalid : 0, topo);
  fflush(stdout);
}

void mx_print_summary(const mx_summary *s) {
  printf("mixoct: %s (%s balance), %d thread(s)\n",
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
  }
  printf("  time (s)      read %.3f  grid %.3f  refine %.3f  balance %.3f  "
         "transition %.3f  write %.3f  total %.3f\n",
         s->ph.read, s->ph.grid, s->ph.refine, s->ph.balance, s->ph.transition,
         s->ph.write, s->ph.total);
  printf("  peak memory   %.0f MB\n", s->peak_rss_mb);
}
