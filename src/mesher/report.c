/* The report of a run of the mixoct program (mx_mesher_print_report,
 * include/mixoct.h): the summary printed after a run, or its --json line,
 * from the mesher's figures (mx_summary) and what the program did besides
 * meshing (mx_run_info: files written, warnings, outcome). */
#include "mesher/mesher.h"

#include <inttypes.h>
#include <omp.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "geom/quality.h"
#include "sizing/cspace.h"

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

/* A JSON string: quotes, backslashes and control characters escaped. */
static void json_string(FILE *f, const char *t) {
  fputc('"', f);
  for (const unsigned char *p = (const unsigned char *)(t ? t : ""); *p; p++) {
    if (*p == '"' || *p == '\\')
      fprintf(f, "\\%c", *p);
    else if (*p < 0x20 || *p == 0x7f)
      fprintf(f, "\\u%04x", *p);
    else
      fputc(*p, f);
  }
  fputc('"', f);
}

/* Non-finite numbers printed by printf (nan, -nan, inf, -inf) outside
 * strings become null: the line stays valid JSON whatever the values. A
 * new string (malloc; "nan" grows by one byte as "null"), NULL when memory
 * runs out. */
static char *json_finite(const char *b) {
  char *out = malloc(2 * strlen(b) + 1);
  if (!out) return NULL;
  int in_str = 0;
  char *w = out;
  for (const char *p = b; *p;) {
    if (in_str) {
      if (*p == '\\' && p[1]) {
        *w++ = *p++;
        *w++ = *p++;
        continue;
      }
      if (*p == '"') in_str = 0;
      *w++ = *p++;
      continue;
    }
    if (*p == '"') {
      in_str = 1;
      *w++ = *p++;
      continue;
    }
    const char *q = p + (*p == '-');
    if (!strncmp(q, "nan", 3) || !strncmp(q, "inf", 3)) {
      memcpy(w, "null", 4);
      w += 4;
      p = q + 3;
      if (!strncmp(p, "inity", 5)) p += 5;
      continue;
    }
    *w++ = *p++;
  }
  *w = '\0';
  return out;
}

/* The outcome: valid, exit code, error, warnings, files written. */
static void json_outcome(FILE *f, const mx_run_info *ri) {
  fprintf(f, "\"valid\": %s, \"exit_code\": %d, \"error\": ", ri->valid ? "true" : "false",
          ri->status);
  if (ri->error[0])
    json_string(f, ri->error);
  else
    fputs("null", f);
  fputs(", \"warnings\": [", f);
  for (int k = 0; k < ri->nwarnings; k++) {
    if (k) fputs(", ", f);
    json_string(f, ri->warnings[k]);
  }
  fprintf(f, "], \"warnings_dropped\": %zu, \"dry_run\": %s, \"outputs\": [",
          ri->warnings_dropped, ri->dry_run ? "true" : "false");
  for (int k = 0; k < ri->noutputs; k++) {
    fputs(k ? ", {\"path\": " : "{\"path\": ", f);
    json_string(f, ri->outputs[k]);
    fprintf(f, ", \"bytes\": %lld}", ri->bytes[k]);
  }
  fputs("]", f);
}

static void print_mesh_json(FILE *out, const mx_summary *s, const mx_run_info *ri);

/* --json: one line, always valid JSON (non-finite numbers are null); s may
 * be NULL when the run stopped before meshing. */
static void print_json(const mx_summary *s, const mx_run_info *ri) {
  char *buf = NULL;
  size_t len = 0;
  FILE *f = open_memstream(&buf, &len);
  if (!f) return;
  fputs("{", f);
  json_outcome(f, ri);
  if (s) {
    fprintf(f, ", \"defects\": {\"invalid_elements\": %zu, \"contact_nodes\": %zu}, ",
            s->mesh ? s->invalid : 0, s->mesh ? s->contacts.nodes : 0);
    print_mesh_json(f, s, ri);
  } else {
    fputs("}\n", f);
  }
  fclose(f);
  char *clean = json_finite(buf);
  fputs(clean ? clean : buf, stdout);
  fflush(stdout);
  free(clean);
  free(buf);
}

/* The mesh's figures, the rest of the object (from '"leaves"' to '}'). */
static void print_mesh_json(FILE *out, const mx_summary *s, const mx_run_info *ri) {
  char nodes[32] = "null";
  if (s->nodes_counted) snprintf(nodes, sizeof nodes, "%zu", s->nodes);
  const size_t elements = s->mesh ? s->elements : s->leaves;
  char qual[1024] = "null";
  if (s->mesh) quality_json(&s->quality, qual, sizeof qual);
  const size_t hex = s->mesh ? s->by_type[3] : s->leaves;
  char bnd[1024] = "";
  if (s->full) {
    const mx_boundary_stats *b = &s->boundary;
    snprintf(bnd, sizeof bnd,
             "\"boundary\": {\"located\": %zu, \"on_surface\": %zu, \"moved_close\": %zu, "
             "\"removed\": %zu, "
             "\"patterned\": %zu, \"sub_elements\": %zu, \"optional\": %zu, "
             "\"centres\": %zu, \"in_place\": %zu, \"shrunk\": %zu, \"restored\": %zu, "
             "\"inverted_by_shrink\": %zu, \"repaired\": %zu, \"repair_rounds\": %d, "
             "\"seconds\": {\"states\": %.6f, \"close\": %.6f, \"patterns\": %.6f, "
             "\"shrink\": %.6f, \"smooth\": %.6f, \"staircase\": %.6f}, "
             "\"smoothed\": %zu, \"smoothing\": {\"rounds\": %d, \"work\": %zu, "
             "\"moved\": %zu, \"moves\": %zu, \"jens_min_before\": %.6f, "
             "\"jens_min_after\": %.6f, \"seconds\": %.6f}}, ",
             b->located, b->on_surface, b->moved_close, b->removed, b->sp.patterned, b->sp.kept,
             b->sp.optional, b->sp.centres, b->sp.in_place, b->shrunk, b->sp.restored,
             b->inverted, s->repaired,
             s->repair_rounds, b->t_states, b->t_close, b->t_patterns, b->t_shrink,
             b->t_smooth, b->t_staircase, b->smoothed, b->smoothing.rounds, b->smoothing.work,
             b->smoothing.moved, b->smoothing.moves, b->smoothing.jens_min_before,
             b->smoothing.jens_min_after, b->smoothing.seconds);
  }
  char mat[1024] = "";
  if (s->nmaterials) {
    const mx_cleave_stats *cv = &s->boundary.ifs.cleave;
    snprintf(mat, sizeof mat,
             "\"materials\": {\"regions\": %d, \"across_interfaces\": %zu, \"shared_triangles\": %zu, "
             "\"interfaces\": {\"warped\": %zu, \"cut\": %zu, \"neighbours_split\": %zu, "
             "\"centres\": %zu, \"cut_nodes\": %zu, \"smoothed\": %zu, \"seconds\": %.6f, "
             "\"warp_s\": %.6f, \"cut_s\": %.6f, \"smooth_s\": %.6f}, "
             "\"seconds\": %.6f}, ",
             s->nmaterials, s->materials_across, s->materials_shared, cv->warped, cv->cut,
             cv->neighbours, cv->centres, cv->cut_nodes, cv->smoothed,
             s->boundary.t_interfaces, cv->t_warp, cv->t_cut, cv->t_smooth, s->t_materials);
  }
  if (s->size_field) {
    const size_t k = strlen(mat);
    snprintf(mat + k, sizeof mat - k,
             "\"size_field\": {\"structure\": \"%s\", \"leaves\": %zu, \"depth\": %d, "
             "\"capped\": %d, \"kb\": %.1f, \"seconds\": %.6f}, ",
             s->size_leaves ? mx_cs_structure_name(s->size_structure, s->size_split) : "none",
             s->size_leaves, s->size_depth, s->size_capped, s->size_kb, s->size_seconds);
    if (s->size_sources) { /* inside size_field: replace its closing "}, " */
      const size_t e = strlen(mat) - 3;
      snprintf(mat + e, sizeof mat - e,
               ", \"sources\": {\"count\": %zu, \"curvature\": %zu, \"thickness\": %zu, "
               "\"map\": %zu, \"graded_leaves\": %zu, \"gradation\": %.6g, \"kb\": %.1f, "
               "\"seconds\": %.6f}}, ",
               s->size_sources, s->size_curvature_n, s->size_thickness_n, s->size_map_n,
               s->size_graded_n, s->size_beta, s->size_src_kb, s->size_src_seconds);
    }
  }
  char feat[768] = "";
  const mx_feature_stats *fp = &s->feature_place;
  if (s->feature_angle > 0.0)
    snprintf(feat, sizeof feat,
             "\"features\": {\"angle\": %.6g, \"ridges\": %zu, \"edges\": %zu, "
             "\"corners\": %zu, \"length\": %.9g, \"dropped_edges\": %zu, \"noise\": %s, "
             "\"fallback\": %s, "
             "\"kept\": %s, \"corners_placed\": %zu, "
             "\"corners_missed\": %zu, \"lines_followed\": %zu, \"lines_missed\": %zu, "
             "\"nodes\": %zu, \"side_moves\": %zu, \"given_up\": %zu, \"slid\": %zu, \"quads_split\": %zu, "
             "\"splits_undone\": %zu, \"apart_boxes\": %zu, "
             "\"ridge_distance\": %.9g, \"corner_distance\": %.9g, "
             "\"seconds\": %.6f}, ",
             s->feature_angle, s->feature_ridges, s->feature_edges, s->feature_corners,
             s->feature_length, s->feature_dangling, s->feature_noise ? "true" : "false",
             s->feature_fallback ? "true" : "false",
             s->features_kept ? "true" : "false", fp->corners,
             fp->corners_missed, fp->lines, fp->lines_missed, fp->nodes, fp->sides, fp->given_up,
             fp->slid, fp->split, fp->unsplit, s->feature_apart_boxes, s->feature_measured ? s->feature_ridge_dist : NAN,
             s->feature_measured ? s->feature_corner_dist : NAN, s->feature_seconds + fp->seconds);
  char tets[512] = "";
  if (s->tets)
    snprintf(tets, sizeof tets,
             "\"tets\": {\"from\": %zu, \"from_by_type\": {\"hex\": %zu, \"prism\": %zu, "
             "\"pyramid\": %zu, \"tet\": %zu}, \"made\": %zu, \"steiner\": %zu, "
             "\"hex_five\": %zu, \"seconds\": %.6f, \"check_seconds\": %.6f, "
             "\"volume\": %.17g, \"volume_mixed\": %.17g, \"volume_mixed_fan\": %.17g}, ",
             s->tets_from, s->tets_from_by_type[3], s->tets_from_by_type[2],
             s->tets_from_by_type[1], s->tets_from_by_type[0], s->tets_made, s->tets_steiner,
             s->tets_five, s->t_tets, s->t_tets_check, s->tets_volume, s->tets_volume_mixed,
             s->tets_volume_fan);
  char img[12288] = "";
  if (s->image) {
    const mx_image_info *g = s->image;
    size_t w = (size_t)snprintf(
        img, sizeof img,
        "\"image\": {\"format\": \"%s\", \"dims\": [%lld, %lld, %lld], \"spacing\": [%.9g, "
        "%.9g, %.9g], \"oblique\": %s, \"rounded_voxels\": %zu, \"contact_voxels\": %zu, "
        "\"islands\": %zu, \"island_voxels\": %zu, \"moved_nodes\": %zu, \"seconds\": "
        "{\"labels\": %.6f, \"mesh\": %.6f}, \"labels\": [",
        g->format, (long long)g->dims[0], (long long)g->dims[1], (long long)g->dims[2],
        g->spacing[0], g->spacing[1], g->spacing[2], g->oblique ? "true" : "false", g->rounded,
        g->fix.contact_voxels, g->fix.islands, g->fix.island_voxels, g->moved, g->seconds,
        g->seconds_mesh);
    for (int l = 0; l < g->nlabels && w < sizeof img; l++) {
      const double want = (double)g->voxels[l] * g->voxel_volume;
      w += (size_t)snprintf(img + w, sizeof img - w,
                            "%s{\"label\": %d, \"name\": \"%s\", \"voxels\": %zu, "
                            "\"voxel_volume\": %.9g, \"volume\": %.9g, \"error\": %.6g}",
                            l ? ", " : "", (int)g->labels[l], g->names[l], g->voxels[l], want,
                            g->volume[l], want > 0 ? (g->volume[l] - want) / want : 0.0);
    }
    if (w < sizeof img) snprintf(img + w, sizeof img - w, "]}, ");
  }
  fprintf(out, "\"leaves\": %zu, \"leaves_hash\": \"%016" PRIx64 "\", "
         "\"nodes\": %s, \"elements\": %zu, "
         "\"by_type\": {\"hex\": %zu, \"prism\": %zu, \"pyramid\": %zu, \"tet\": %zu}, "
         "\"stage\": \"%s\", \"balance\": \"%s\", \"max_level\": %d, "
         "\"octants\": %zu, \"edges\": %zu, \"edge_mb\": %.1f, "
         "\"located\": %zu, \"split_requested\": %zu, \"split_balance\": %zu, "
         "\"dropped\": %zu, \"centre_leaves\": %zu, \"closures\": %zu, "
         "\"phases\": {\"read\": %.6f, \"grid\": %.6f, \"refine\": %.6f, "
         "\"balance\": %.6f, \"transition\": %.6f, \"boundary\": %.6f, \"verify\": %.6f, "
         "\"quality\": %.6f, \"write\": %.6f, \"restart\": %.6f}, "
         "\"refined_listed\": %zu, \"repaired\": %zu, \"repair_rounds\": %d, "
         "\"remesh_local\": %s, \"remesh_patch_leaves\": %zu, \"remesh_core_leaves\": %zu, "
         "\"contacts_searched_locally\": %zu, "
         "\"total_s\": %.6f, \"peak_rss_mb\": %.1f, \"memory_estimate_mb\": %.1f, "
         "\"memory_estimate_prior_mb\": %.1f, "
         "\"threads\": %d, \"wait_policy\": \"%s\", "
         "\"jens_min\": %.6f, \"invalid\": %zu, \"quality\": %s, %s%s%s%s%s"
         "\"topology\": \"%s\"}\n",
         s->leaves, s->leaves_hash, nodes, elements, hex,
         s->mesh ? s->by_type[2] : 0, s->mesh ? s->by_type[1] : 0,
         s->mesh ? s->by_type[0] : 0, s->full ? "full" : s->mesh ? "transition" : "octree",
         s->balance ? "recursive" : "edges", s->max_level, s->octants, s->edges,
         (double)s->edge_bytes / 1048576.0, s->located, s->split_requested,
         s->split_balance, s->dropped, s->centre_leaves, s->closures, s->ph.read,
         s->ph.grid, s->ph.refine, s->ph.balance, s->ph.transition,
         s->ph.boundary, s->ph.verify, s->ph.quality, s->ph.write, s->t_restart,
         s->refined_listed, s->repaired, s->repair_rounds, s->local ? "true" : "false",
         s->local ? s->patch_leaves : 0, s->local ? s->core_leaves : 0, s->contacts_local, s->ph.total, s->peak_rss_mb, s->memory_estimate_mb, s->memory_prior_mb, s->threads,
         ri->wait_policy ? ri->wait_policy : "default",
         s->mesh ? s->jens_min : 1.0,
         s->mesh ? s->invalid : 0, qual, bnd, mat, img, feat, tets, ri->topology ? ri->topology : "");
}

/* The summary printed after a run (unless --quiet or --json): what was
 * built, the J_ENS table (Tables IV and V of the 2015 paper), the boundary
 * steps, seconds per stage, peak memory. Labels in a 14-column margin. */
static void quality_summary(const mx_summary *s) {
  const mx_quality_table *q = &s->quality;
  printf("  J_ENS          %12s %9s %9s %9s\n", "count", "min", "mean", "max");
  for (int t = 3; t >= 0; t--)
    if (q->count[t])
      printf("    %-10s   %12zu %9.3f %9.3f %9.3f\n", type_name[t], q->count[t],
             q->min[t], q->mean[t], q->max[t]);
  printf("    %-10s   %12zu %9.3f   (%zu invalid: J_ENS < 1e-6; %zu below 0.2)\n",
         "all", s->elements, s->jens_min, s->invalid, q->below_02);
  static const char *bin_name[MX_QBINS] = {"<0.03", "<0.2", "<0.4",
                                           "<0.6",  "<0.8", "<=1"};
  printf("  J_ENS bins   ");
  for (int b = 0; b < MX_QBINS; b++) printf(" %10s", bin_name[b]);
  printf("\n    elements   ");
  for (int b = 0; b < MX_QBINS; b++) printf(" %10zu", q->bins[b]);
  printf("\n    share      ");
  for (int b = 0; b < MX_QBINS; b++) {
    const double pc = s->elements ? 100.0 * (double)q->bins[b] / (double)s->elements : 0.0;
    if (q->bins[b] > 0 && pc < 0.1)
      printf(" %10s", "<0.1%");
    else
      printf(" %9.1f%%", pc);
  }
  printf("\n");
}

static void print_summary(const mx_summary *s, const mx_run_info *ri) {
  printf("mixoct: %s; %d thread(s), %s balance, levels up to %d\n",
         s->image ? "mesh of the label image" : s->full ? "mesh of the domain" :
         s->mesh ? "conforming mesh of the whole octree (transition stage)"
                 : "balanced octree (octree stage)",
         s->threads, s->balance ? "recursive" : "edges", s->max_level);
  printf("  octree       %12zu leaves (%zu octants created, %zu outside dropped;\n"
         "               %12s %zu splits requested, %zu for balance)\n",
         s->leaves, s->octants, s->dropped, "", s->split_requested, s->split_balance);
  if (s->nodes_counted) printf("  nodes        %12zu\n", s->nodes);
  if (s->mesh) {
    printf("  elements     %12zu (hex %zu, prism %zu, pyramid %zu, tet %zu)\n",
           s->elements, s->by_type[3], s->by_type[2], s->by_type[1], s->by_type[0]);
    if (s->centre_leaves)
      printf("               %12s %zu leaves use their body centre\n", "",
             s->centre_leaves);
    if (s->tets)
      printf("  tetrahedra   %12s split from %zu elements (hex %zu, prism %zu, pyramid %zu, "
             "tet %zu): %zu hex in 5, %zu Steiner node(s); split %.3f s, checked %.3f s\n", "",
             s->tets_from, s->tets_from_by_type[3], s->tets_from_by_type[2],
             s->tets_from_by_type[1], s->tets_from_by_type[0], s->tets_five, s->tets_steiner,
             s->t_tets, s->t_tets_check);
    quality_summary(s);
  } else {
    printf("  elements     %12zu hexahedra (the leaves, hanging nodes kept)\n",
           s->leaves);
  }
  if (s->feature_angle > 0.0) {
    printf("  features     %12zu ridge(s) of %zu edges, %.6g long; %zu corner(s) (%s at %.4g "
           "degrees)\n",
           s->feature_ridges, s->feature_edges, s->feature_length, s->feature_corners,
           s->feature_file ? "read, corners" : "found", s->feature_angle);
    if (s->feature_dangling)
      printf("    dropped    %12zu ridge edge(s) ending in smooth surface or in networks "
             "under 5%% of the diagonal\n", s->feature_dangling);
    if (s->feature_fallback)
      printf("    not kept   %12s keeping them broke the mesh where the repair could not mend "
             "it: meshed without them\n", "");
    if (s->feature_noise)
      printf("    not kept   %12s most ridges end in smooth surface: a scanned or segmented "
             "surface's noise (--feature-angle DEG keeps what is left)\n", "");
    const mx_feature_stats *fp = &s->feature_place;
    if (s->features_kept)
      printf("    kept       %12zu of %zu corner(s), %zu of %zu line(s) followed by mesh edges; "
             "%zu node(s) on them, %zu moved to their side, %zu put back, %zu slid along "
             "their ridge (%.3f s)\n",
             fp->corners, fp->corners + fp->corners_missed, fp->lines,
             fp->lines + fp->lines_missed, fp->nodes, fp->sides, fp->given_up, fp->slid, fp->seconds);
    if (s->features_kept && fp->split)
      printf("    split      %12zu boundary quadrilateral(s) a line crosses along its diagonal: "
             "their elements split (%zu undone)\n", fp->split, fp->unsplit);
    if (s->feature_measured)
      printf("    distance   %12s ridges %.3g, corners %.3g of the diagonal (farthest ridge sample "
             "from a boundary edge, corner from a boundary node)\n", "",
             s->feature_ridge_dist, s->feature_corner_dist);
    if (s->feature_apart_boxes)
      printf("    apart      %12zu box(es) refining where features come closer than their "
             "octants\n", s->feature_apart_boxes);
  }
  if (s->image) {
    const mx_image_info *g = s->image;
    printf("  image        %s, %lld x %lld x %lld voxels of %.4g x %.4g x %.4g%s; %.3f s "
           "(labels), %.3f s (labels on the mesh, %zu nodes onto the interfaces)\n",
           g->format, (long long)g->dims[0], (long long)g->dims[1], (long long)g->dims[2],
           g->spacing[0], g->spacing[1], g->spacing[2], g->oblique ? ", oblique" : "",
           g->seconds, g->seconds_mesh, g->moved);
    if (g->fix.contact_voxels || g->fix.islands || g->rounded)
      printf("               %zu voxel(s) relabelled at contacts, %zu island(s) dropped (%zu "
             "voxels), %zu non-integer voxel(s) rounded\n",
             g->fix.contact_voxels, g->fix.islands, g->fix.island_voxels, g->rounded);
    printf("  labels          label      voxels       volume     voxels' volume    error  name\n");
    for (int l = 0; l < g->nlabels; l++) {
      const double want = (double)g->voxels[l] * g->voxel_volume;
      printf("               %8d %11zu %12.6g %18.6g %+7.2f%%  %s\n", (int)g->labels[l],
             g->voxels[l], g->volume[l], want,
             want > 0 ? 100.0 * (g->volume[l] - want) / want : 0.0, g->names[l]);
    }
  } else if (s->nmaterials) {
    const mx_cleave_stats *cv = &s->boundary.ifs.cleave;
    printf("  materials    %12d regions (by nesting depth and input); %zu element(s) across an "
           "interface\n", s->nmaterials, s->materials_across);
    if (s->materials_shared)
      printf("               %zu triangle(s) two inputs have in common: an interface\n",
             s->materials_shared);
    if (s->full && cv->cut + cv->warped)
      printf("               interfaces cleaved: %zu nodes moved onto them, %zu elements cut"
             " (%zu neighbours split),\n               %zu nodes added on them, %zu centres\n",
             cv->warped, cv->cut, cv->neighbours, cv->cut_nodes, cv->centres);
  }
  if (s->size_field) {
    if (s->size_leaves && !s->size_graded_n)
      printf("  size field   %12zu leaves of a %s control space (depth %d, %.0f kB, %.3f s)\n",
             s->size_leaves, mx_cs_structure_name(s->size_structure, s->size_split),
             s->size_depth, s->size_kb,
             s->size_seconds);
    if (s->size_sources)
      printf("  size field   %12zu sources (curvature %zu, thickness %zu, map %zu, graded "
             "leaves %zu), gradation %.3g; %.0f kB, %.3f s\n", s->size_sources,
             s->size_curvature_n, s->size_thickness_n, s->size_map_n, s->size_graded_n,
             s->size_beta, s->size_src_kb, s->size_src_seconds);
  }
  if (s->full) {
    const mx_boundary_stats *b = &s->boundary;
    printf("  boundary     %zu nodes located; %zu moved close, %zu shrunk onto the surface\n"
           "               %zu elements removed; %zu patterned (%zu elements after, +%zu centres)\n"
           "               %zu inverted by the shrink, untangled with %zu node moves;"
           " %zu restored (staircase)\n",
           b->located, b->moved_close, b->shrunk, b->removed, b->sp.patterned,
           b->sp.kept, b->sp.centres, b->inverted, b->smoothed, b->sp.restored);
    if (b->smoothing.rounds)
      printf("  smoothing    %zu nodes moved (%zu moves, %d round(s)); J_ENS min %.4f -> %.4f, "
             "%.3f s\n",
             b->smoothing.moved, b->smoothing.moves, b->smoothing.rounds,
             b->smoothing.jens_min_before, b->smoothing.jens_min_after, b->smoothing.seconds);
    if (s->repair_rounds)
      printf("               %zu invalid element(s) and %zu element(s) at contacts repaired "
             "by %d refinement round(s)\n",
             s->repaired, s->contacts_repaired, s->repair_rounds);
    if (s->local)
      printf("  re-meshed    locally: %zu leaves meshed again, the elements of %zu of them "
             "new\n               (the boundary figures above are the patch's)\n",
             s->patch_leaves, s->core_leaves);
  }
  /* Seconds per stage, only the stages that ran. */
  struct { const char *name; double t; int ran; } ph[] = {
      {"read", s->ph.read, 1},
      {"grid", s->ph.grid, 1},
      {"refine", s->ph.refine, 1},
      {"balance", s->ph.balance, 1},
      {"transition", s->ph.transition, s->mesh},
      {"boundary", s->ph.boundary, s->full},
      {"verify", s->ph.verify, s->full},
      {"quality", s->ph.quality, s->mesh},
      {"write", s->ph.write, s->ph.write > 0.0},
      {"restart", s->t_restart, s->t_restart > 0.0}, /* reading or writing */
  };
  printf("  time (s)     %12.3f total:", s->ph.total);
  int col = 0;
  for (size_t k = 0; k < sizeof ph / sizeof ph[0]; k++) {
    if (!ph[k].ran) continue;
    if (col == 4) printf("\n               %12s       ", "");
    printf(" %s %.3f", ph[k].name, ph[k].t);
    col++;
  }
  printf("\n");
  printf("  peak memory  %12.0f MB (estimated %.0f MB before meshing)\n",
         s->peak_rss_mb, s->memory_estimate_mb);
  for (int k = 0; k < ri->noutputs; k++) {
    const double b = (double)ri->bytes[k];
    printf("  written      %s (%.*f %s)\n", ri->outputs[k], b < 1e6 ? 1 : 1,
           b < 1e6 ? b / 1e3 : b / 1e6, b < 1e6 ? "kB" : "MB");
  }
  if (ri->dry_run) printf("  written      nothing: a dry run (give -o FILE to write the mesh)\n");
  if (ri->status == MX_OK && ri->stage == MX_STAGE_OCTREE)
    printf("  result       the octree stage only: the leaves as hexahedra, with hanging "
           "nodes (not a conforming mesh; --stage full for one)\n");
  else if (ri->status == MX_OK && ri->stage == MX_STAGE_TRANSITION)
    printf("  result       the transition stage only: the conforming mesh of the whole "
           "octree, without the boundary on the input (--stage full for that)\n");
  else if (ri->status == MX_EINVALID && s->invalid)
    printf("  result       INVALID: %zu element(s) with J_ENS below %g (exit 5)\n", s->invalid,
           MX_JENS_VALID);
  else if (ri->status == MX_EINVALID && s->contacts.nodes)
    printf("  result       INVALID: %zu node(s) on an element they are not a node of "
           "(non-conforming; exit 5)\n", s->contacts.nodes);
  else if (ri->status == MX_EINVALID)
    printf("  result       INVALID: the mesh's volume is %+.1f%% off the input's (exit 5)\n",
           100.0 * s->volume_error);
}

void mx_mesher_print_report(const mx_mesher *m, const mx_run_info *ri, int json) {
  if (!m) {
    if (json) print_json(NULL, ri); /* the outcome, even without a mesh */
    return;
  }
  mx_summary S = m->rec->S;
  S.ph.total = ri->total_s;
  S.peak_rss_mb = mx_peak_rss_mb();
  S.threads = omp_get_max_threads();
  if (json)
    print_json(&S, ri);
  else
    print_summary(&S, ri);
}
