/* Rank 0's report of a distributed run (mx_p4est_run): the leaves in the
 * domain and their hash (the one `mixoct --stage octree --json` prints as
 * leaves_hash, over the same set), the slowest rank's seconds per step,
 * per-rank min/max of leaves, quadrants and peak memory; the comparison
 * with the single-process octree (--p4est-compare); the mesh's global
 * counts and per-rank min/max. Text lines, or one JSON line. */
#include "mpi/p4est_run.h"

#include <inttypes.h>
#include <stdio.h>

static void print_levels(const size_t *n) {
  int first = 1;
  printf("{");
  for (int l = 0; l <= MX_MAX_LEVEL; l++)
    if (n[l]) {
      printf("%s\"%d\": %zu", first ? "" : ", ", l, n[l]);
      first = 0;
    }
  printf("}");
}

static void print_pair(const char *name, const double *v, int last) {
  printf("\"%s\": [%.6g, %.6g]%s", name, v[0], v[1], last ? "" : ", ");
}

/* A JSON string: quotes, backslashes and control characters escaped (the
 * material names come from file names). */
static void json_string(const char *t) {
  putchar('"');
  for (const unsigned char *p = (const unsigned char *)t; *p; p++) {
    if (*p == '"' || *p == '\\')
      printf("\\%c", *p);
    else if (*p < 0x20 || *p == 0x7f)
      printf("\\u%04x", *p);
    else
      putchar(*p);
  }
  putchar('"');
}

/* Several materials: per region its number, name, elements and volume
 * (summed over the ranks), and the elements across an interface. */
static void materials_json(const mx_p4est_mesh *D) {
  printf("\"materials\": {\"count\": %d, \"across_interfaces\": %" PRIu64 ", \"each\": [",
         D->nmaterials, D->across);
  for (int d = 1; d <= D->nmaterials && d <= 64; d++) {
    printf("%s{\"number\": %d, \"name\": ", d > 1 ? ", " : "", (int)D->material_id[d]);
    json_string(D->material_name[d]);
    printf(", \"elements\": %" PRIu64 ", \"volume\": %.17g}", D->material_cells[d],
           D->material_volume[d]);
  }
  printf("]}, ");
}

static void mesh_json(const mx_p4est_mesh_report *rep) {
  const mx_p4est_mesh *D = &rep->D;
  const double *phmax = rep->phmax;
  printf("\"mesh\": {\"leaves\": %" PRIu64 ", ", D->leaves);
  printf("\"nodes\": %" PRIu64 ", \"elements\": %" PRIu64 ", \"by_type\": {\"tet\": "
         "%" PRIu64 ", \"pyramid\": %" PRIu64 ", \"prism\": %" PRIu64 ", \"hex\": %" PRIu64
         "}, \"jens_min\": %.6g, \"invalid\": %" PRIu64 ", \"contact_elements\": %" PRIu64
         ", \"volume\": %.17g, \"mesh_hash\": \"%016" PRIx64 "\", \"halo_rings\": %d, "
         "\"attempts\": %d, \"differ_first_attempt\": %" PRIu64 ", \"repair_rounds\": %d, "
         "\"repaired_leaves\": %lld, \"exchanged_bytes\": %lld, "
         "\"largest_message_bytes\": %lld, ",
         D->nodes, D->cells, D->by_type[0], D->by_type[1], D->by_type[2], D->by_type[3],
         D->jens_min, D->invalid, D->contact_cells, D->volume, rep->hash, D->rings,
         D->attempts, D->differ_first, D->repair_rounds, D->repaired, rep->sent_bytes,
         rep->largest_message);
  if (D->nmaterials) materials_json(D);
  if (D->tree_checked) printf("\"tree_checked_leaves\": %" PRIu64 ", ", D->tree_checked);
  printf("\"phases_max\": {\"halo\": %.6f, \"tree\": %.6f, \"transition\": %.6f, "
         "\"boundary\": %.6f, \"exchange\": %.6f, \"mesh\": %.6f, \"write\": %.6f}, ",
         phmax[0], phmax[1], phmax[2], phmax[3], phmax[4], phmax[5], phmax[6]);
  printf("\"per_rank\": {");
  print_pair("leaves", rep->leaves, 0);
  print_pair("patch_leaves", rep->patch, 0);
  print_pair("elements", rep->cells, 0);
  print_pair("nodes", rep->nodes, 0);
  print_pair("shared_nodes", rep->shared, 0);
  print_pair("seconds", rep->sec, 0);
  print_pair("memory_estimate_mb", rep->estimate, 0);
  print_pair("peak_rss_mb", rep->rss, 1);
  printf("}}, ");
}

static void mesh_text(const mx_p4est_mesh_report *rep) {
  const mx_p4est_mesh *D = &rep->D;
  printf("  mesh: nodes %" PRIu64 ", elements %" PRIu64 " (tet %" PRIu64 ", pyramid %" PRIu64
         ", prism %" PRIu64 ", hex %" PRIu64 "), J_ENS min %.4f, hash %016" PRIx64 "\n",
         D->nodes, D->cells, D->by_type[0], D->by_type[1], D->by_type[2], D->by_type[3],
         D->jens_min, rep->hash);
  printf("  halo rings %d (attempts %d); slowest rank: mesh %.3f s, write %.3f s; per rank: "
         "elements %.0f..%.0f, peak memory %.1f..%.1f MB\n", D->rings, D->attempts,
         rep->phmax[5], rep->phmax[6], rep->cells[0], rep->cells[1], rep->rss[0],
         rep->rss[1]);
  if (!D->nmaterials) return;
  printf("  materials: %d; %" PRIu64 " element(s) across an interface\n", D->nmaterials,
         D->across);
  for (int d = 1; d <= D->nmaterials && d <= 64; d++)
    printf("    %d \"%s\": %" PRIu64 " elements, volume %.6g\n", (int)D->material_id[d],
           D->material_name[d], D->material_cells[d], D->material_volume[d]);
}

void mx_p4est_report(const mx_p4est_run_params *p, const mx_p4est_octree *P,
                     const mx_p4est_summary *s, double t_setup, double t_total, int threads,
                     const mx_p4est_single *c, const mx_p4est_mesh_report *mesh) {
  const int compared = c->compared;
  const mx_leaf_diff *d = &c->d;
  const mx_split_causes *why = &c->why;
  if (!p->json) {
    printf("p4est octree: %d rank(s) x %d thread(s), levels up to %d\n", P->size, threads,
           P->max_level);
    printf("  leaves in the domain %lld (hash %016" PRIx64 "), quadrants %lld, outside %lld\n",
           s->leaves, s->hash, s->quadrants, s->outside);
    printf("  seconds (slowest rank): setup %.3f refine %.3f balance %.3f partition %.3f "
           "ghost %.3f total %.3f\n",
           t_setup, s->tmax.refine, s->tmax.balance, s->tmax.partition, s->tmax.ghost, t_total);
    printf("  per rank: leaves %lld..%lld, quadrants %lld..%lld, peak memory %.1f..%.1f MB\n",
           s->leaves_min, s->leaves_max, s->quadrants_min, s->quadrants_max, s->rss_min_mb,
           s->rss_max_mb);
    if (compared)
      printf("  single-process: leaves %zu (hash %016" PRIx64 ") %s; only p4est %zu (finer %zu, "
             "coarser %zu), only single %zu (finer %zu, coarser %zu)\n",
             d->n_b, c->hash, d->only_a + d->only_b ? "differ" : "the same", d->only_a,
             d->a_finer, d->a_coarser, d->only_b, d->b_finer, d->b_coarser);
    if (compared && why->split)
      printf("  single-process leaves p4est split: %zu; p4est's balance reached them across "
             "the outside %zu, through such leaves %zu, otherwise %zu (+%zu unexplained)\n",
             why->split, why->by_outside, why->by_chain, why->by_common, why->unexplained);
    if (mesh) mesh_text(mesh);
    return;
  }
  size_t lv[MX_MAX_LEVEL + 1];
  for (int l = 0; l <= MX_MAX_LEVEL; l++) lv[l] = (size_t)s->per_level[l];
  printf("{\"p4est\": true, \"ranks\": %d, \"threads\": %d, \"max_level\": %d, "
         "\"leaves\": %lld, \"leaves_hash\": \"%016" PRIx64 "\", \"levels\": ",
         P->size, threads, P->max_level, s->leaves, s->hash);
  print_levels(lv);
  printf(", \"quadrants\": %lld, \"outside\": %lld, \"surface_leaves\": %lld, "
         "\"split_requested\": %lld, \"split_balance\": %lld, \"located\": %lld, "
         "\"ghosts\": %lld, \"partitions\": %zu, \"shipped\": %lld, "
         "\"shipped_list_bytes\": %lld, ",
         s->quadrants, s->outside, s->surface, s->split_requested, s->split_balance,
         s->located, s->ghosts, P->partitions, P->shipped, s->list_bytes);
  printf("\"phases\": {\"setup\": %.6f, \"refine\": %.6f, \"balance\": %.6f, "
         "\"partition\": %.6f, \"ghost\": %.6f}, ",
         t_setup, s->tmax.refine, s->tmax.balance, s->tmax.partition, s->tmax.ghost);
  printf("\"per_rank\": {\"leaves\": [%lld, %lld], \"quadrants\": [%lld, %lld], "
         "\"peak_rss_mb\": [%.1f, %.1f], \"refine_s\": [%.6f, %.6f], "
         "\"balance_s\": [%.6f, %.6f], \"partition_s\": [%.6f, %.6f], "
         "\"ghost_s\": [%.6f, %.6f]}, ",
         s->leaves_min, s->leaves_max, s->quadrants_min, s->quadrants_max, s->rss_min_mb,
         s->rss_max_mb, s->tmin.refine, s->tmax.refine, s->tmin.balance, s->tmax.balance,
         s->tmin.partition, s->tmax.partition, s->tmin.ghost, s->tmax.ghost);
  if (compared) {
    printf("\"compare\": {\"single_leaves\": %zu, \"single_hash\": \"%016" PRIx64 "\", "
           "\"equal\": %s, \"common\": %zu, \"only_p4est\": %zu, \"only_single\": %zu, "
           "\"p4est_finer\": %zu, \"p4est_coarser\": %zu, \"p4est_alone\": %zu, "
           "\"single_finer\": %zu, \"single_coarser\": %zu, \"single_alone\": %zu, "
           "\"only_p4est_levels\": ",
           d->n_b, c->hash, d->only_a + d->only_b ? "false" : "true", d->common, d->only_a,
           d->only_b, d->a_finer, d->a_coarser, d->a_alone, d->b_finer, d->b_coarser,
           d->b_alone);
    print_levels(d->only_a_level);
    printf(", \"only_single_levels\": ");
    print_levels(d->only_b_level);
    printf(", \"single_split_by_p4est\": {\"leaves\": %zu, \"by_outside\": %zu, "
           "\"by_chain\": %zu, \"by_common\": %zu, \"unexplained\": %zu}",
           why->split, why->by_outside, why->by_chain, why->by_common, why->unexplained);
    printf(", \"single_phases\": {\"refine\": %.6f, \"balance\": %.6f}}, ", c->t_refine,
           c->t_balance);
  }
  if (mesh) mesh_json(mesh);
  printf("\"valid\": %s, \"total_s\": %.6f, \"peak_rss_mb\": %.1f}\n",
         mesh ? "true" : "null", t_total, mesh ? mesh->rss[1] : s->rss_max_mb);
}
