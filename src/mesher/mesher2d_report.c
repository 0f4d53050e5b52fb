/* The report of a 2D run (include/mixoct.h: mx_mesher2d_print_report), as
 * the mesher2d program prints it: the text summary, or with --json one
 * JSON line. It reads the mesher's figures (the quadtree, the mesh's
 * quality, the boundary stage, the check, the phases' seconds) and what
 * the program did besides meshing (mx_run2d_info: files written, warnings,
 * the outcome). */
#include <math.h>
#include <omp.h>
#include <stdio.h>

#include "mesher/mesher2d.h"
#include "sizing/cspace.h"

static const char *const phase_name[M2_NPH] = {"read",     "refine",  "balance", "transition",
                                               "boundary", "quality", "check",   "write"};

static const char *balance_name(const mx_mesher2d *m) {
  return m && m->p.balance == MX_BALANCE_RECURSIVE ? "recursive" : "edges";
}

/* ---- JSON ---------------------------------------------------------------------- */

static void json_string(FILE *f, const char *s) {
  fputc('"', f);
  for (const unsigned char *p = (const unsigned char *)s; *p; p++) {
    if (*p == '"' || *p == '\\') fprintf(f, "\\%c", *p);
    else if (*p < 0x20 || *p == 0x7f) fprintf(f, "\\u%04x", *p);
    else fputc(*p, f);
  }
  fputc('"', f);
}

/* A number, or null when it is not finite (JSON has no inf / nan). */
static void json_num(FILE *f, const char *key, double v) {
  if (isfinite(v)) fprintf(f, "\"%s\": %.9g", key, v);
  else fprintf(f, "\"%s\": null", key);
}

static void json_mesh(FILE *f, const mx_mesher2d *m) {
  const mx_qquality *q = &m->q;
  fprintf(f, ", \"nodes\": %zu, \"elements\": %zu, \"by_type\": {\"tri\": %zu, \"quad\": %zu}, "
          "\"leaves\": %zu, \"quadrants\": %zu, \"splits\": %zu, \"balance_splits\": %zu, "
          "\"edges\": %zu, \"balance\": \"%s\", ",
          m->M.nnodes, m->M.ncells, q->count[0], q->count[1], m->nleaves, m->T.n, m->qs.splits,
          m->qs.balance_splits, m->qs.edges, balance_name(m));
  json_num(f, "sj_min", fmin(q->count[0] ? q->min[0] : 1, q->count[1] ? q->min[1] : 1));
  fputs(", ", f);
  json_num(f, "min_angle", q->min_angle);
  fprintf(f, ", \"invalid\": %zu, \"quality\": {\"bins\": {\"lt_0.03\": %zu, \"lt_0.2\": %zu, "
          "\"lt_0.4\": %zu, \"lt_0.6\": %zu, \"lt_0.8\": %zu, \"le_1\": %zu}",
          q->invalid, q->bins[0], q->bins[1], q->bins[2], q->bins[3], q->bins[4], q->bins[5]);
  static const char *tname[2] = {"tri", "quad"};
  for (int t = 0; t < 2; t++) {
    fprintf(f, ", \"%s\": {\"count\": %zu, ", tname[t], q->count[t]);
    json_num(f, "min", q->count[t] ? q->min[t] : 0), fputs(", ", f);
    json_num(f, "mean", q->count[t] ? q->mean[t] : 0), fputs(", ", f);
    json_num(f, "max", q->count[t] ? q->max[t] : 0), fputs("}", f);
  }
  const mx_qboundary_stats *b = &m->bs;
  fprintf(f, "}, \"boundary\": {\"features\": %zu, \"moved_close\": %zu, \"removed\": %zu, "
          "\"shrunk\": %zu, \"patterned\": %zu, \"inverted\": %zu}",
          b->features, b->moved_close, b->removed, b->shrunk, b->patterned, b->inverted);
}

static void json_check(FILE *f, const mx_mesher2d *m) {
  const mx_qcheck_report *c = &m->cr;
  fprintf(f, ", \"check\": {\"bad_edges\": %zu, \"hanging\": %zu, \"inverted\": %zu, "
          "\"off_boundary\": %zu, \"missing_features\": %zu, ",
          c->bad_edges, c->hanging, c->inverted, c->off_boundary, c->missing_features);
  json_num(f, "area", c->area), fputs(", ", f);
  json_num(f, "domain_area", c->domain_area), fputs(", ", f);
  json_num(f, "area_error", c->area_error), fputs(", ", f);
  json_num(f, "area_tolerance", m->area_tol);
  fprintf(f, ", \"edges\": %zu, \"boundary_edges\": %zu, \"euler\": %ld, \"domain_euler\": %ld}",
          c->edges, c->boundary_edges, c->euler, c->domain_euler);
}

/* Several materials: each one's number, name, cells and area against its
 * region's (when checked), and what the cleave did. */
static void json_materials(FILE *f, const mx_mesher2d *m) {
  const mx_qcleave_stats *c = &m->cs;
  fprintf(f, ", \"materials\": {\"count\": %d, \"list\": [", m->nmaterials);
  for (int d = 1; d <= m->nmaterials; d++) {
    char name[128];
    mx_mesher2d_material_name(m, d, name, sizeof name);
    fprintf(f, "%s{\"depth\": %d, \"number\": %d, \"name\": ", d > 1 ? ", " : "", d,
            mx_mesher2d_material_number(m, d));
    json_string(f, name);
    if (m->mat_report) {
      const mx_mat2d_report *R = &m->mat_report[d];
      fprintf(f, ", \"cells\": %zu, ", R->cells);
      json_num(f, "area", R->cr.area), fputs(", ", f);
      json_num(f, "region_area", R->cr.domain_area), fputs(", ", f);
      json_num(f, "area_error", R->cr.area_error);
    }
    fputs("}", f);
  }
  fprintf(f, "], \"features\": %zu, \"features_moved\": %zu, \"features_inserted\": %zu, "
          "\"features_missed\": %zu, \"warped\": %zu, \"crossings\": %zu, \"cut\": %zu, "
          "\"unresolved\": %zu, \"across\": %zu, \"smoothed\": %zu, \"seconds\": %.6f}",
          c->features, c->features_moved, c->features_inserted, c->features_missed, c->warped,
          c->crossings, c->cut, c->unresolved, c->across, c->smoothed, m->t_materials);
}

/* The size field's control space (as the 3D report's size_field), the
 * curves among its sources, its least size and the quadrants it asks for. */
static void json_size(FILE *f, const mx_mesher2d *m) {
  mx_cspace_info in;
  mx_cspace_info_get(m->size.cs, &in);
  fprintf(f, ", \"size_field\": {\"structure\": \"%s\", \"leaves\": %zu, \"depth\": %d, "
          "\"capped\": %d, \"kb\": %.1f, \"seconds\": %.6f, \"curves\": %zu, ",
          mx_cs_structure_name(m->size.params.structure, m->size.params.split), in.leaves,
          in.depth, in.capped, (double)in.bytes / 1024.0, in.seconds, m->nfuns);
  json_num(f, "least", m->size_hmin), fputs(", ", f);
  json_num(f, "quadrants_estimate", m->size_cells), fputs("}", f);
}

static void print_json(const mx_mesher2d *m, const mx_run2d_info *ri) {
  FILE *f = stdout;
  fprintf(f, "{\"valid\": %s, \"exit_code\": %d, \"error\": ", ri->status ? "false" : "true",
          ri->status);
  if (ri->error && ri->error[0]) json_string(f, ri->error);
  else fputs("null", f);
  fprintf(f, ", \"warnings\": %d, \"outputs\": [", ri->nwarnings);
  for (int k = 0; k < ri->nwritten; k++) {
    fputs(k ? ", {\"path\": " : "{\"path\": ", f);
    json_string(f, ri->outputs[k]);
    fprintf(f, ", \"bytes\": %lld}", ri->bytes[k]);
  }
  fputs("]", f);
  if (ri->restart) {
    fputs(", \"restart\": ", f);
    json_string(f, ri->restart);
  }
  if (m && m->meshed) {
    json_mesh(f, m);
    fprintf(f, ", \"refined_listed\": %zu, \"listed\": %zu, \"feature_boxes\": %zu, "
            "\"memory_estimate_mb\": %.1f", m->refined_listed, ri->listed,
            m->feature_boxes, m->estimate_mb);
  }
  if (m && m->size.cs) json_size(f, m);
  if (m && m->checked) json_check(f, m);
  if (m && m->meshed && m->material) json_materials(f, m);
  fputs(", \"phases\": {", f);
  for (int p = 0; p < M2_NPH; p++)
    fprintf(f, "%s\"%s\": %.6f", p ? ", " : "", phase_name[p], m ? m->rec->t[p] : 0.0);
  fprintf(f, ", \"restart\": %.6f", m ? m->rec->t_restart : 0.0); /* reading or writing */
  fprintf(f, "}, \"total_s\": %.6f, \"peak_rss_mb\": %.1f, \"threads\": %d}\n", ri->total,
          mx_peak_rss_mb(), omp_get_max_threads());
  fflush(f);
}

/* ---- the text summary -------------------------------------------------------------- */

static void print_quality(const mx_mesher2d *m) {
  const mx_qquality *q = &m->q;
  static const char *tname[2] = {"tri", "quad"};
  printf("  scaled J     %12s %9s %9s %9s\n", "count", "min", "mean", "max");
  for (int t = 1; t >= 0; t--)
    if (q->count[t])
      printf("    %-10s %12zu %9.3f %9.3f %9.3f\n", tname[t], q->count[t], q->min[t], q->mean[t],
             q->max[t]);
  printf("    min angle  %12.2f degrees; %zu invalid (scaled Jacobian <= 0)\n", q->min_angle,
         q->invalid);
  static const char *bin[MX_QBINS] = {"<0.03", "<0.2", "<0.4", "<0.6", "<0.8", "<=1"};
  printf("  sJ bins     ");
  for (int b = 0; b < MX_QBINS; b++) printf(" %9s", bin[b]);
  printf("\n    cells     ");
  for (int b = 0; b < MX_QBINS; b++) printf(" %9zu", q->bins[b]);
  printf("\n");
}

static void print_summary(const mx_mesher2d *m, const mx_run2d_info *ri) {
  printf("mesher2d: %s; %d thread(s), %s balance\n", ri->domain, omp_get_max_threads(),
         balance_name(m));
  const int meshed = m && m->meshed;
  if (meshed) {
    printf("  quadtree     %12zu leaves (%zu quadrants, %zu splits, %zu for balance)\n",
           m->nleaves, m->T.n, m->qs.splits, m->qs.balance_splits);
    if (m->size.cs) {
      mx_cspace_info in;
      mx_cspace_info_get(m->size.cs, &in);
      printf("  size field   %12zu leaves (%s, depth %d%s, %.1f kB), built in %.3f s\n"
             "               least size %.4g%s\n",
             in.leaves, mx_cs_structure_name(m->size.params.structure, m->size.params.split),
             in.depth, in.capped ? ", capped" : "", (double)in.bytes / 1024.0, in.seconds,
             m->size_hmin, m->nfuns ? "; the -f curves among its sources" : "");
    }
    printf("  nodes        %12zu\n  cells        %12zu (quad %zu, tri %zu)\n", m->M.nnodes,
           m->M.ncells, m->q.count[1], m->q.count[0]);
    print_quality(m);
    printf("  boundary     %zu features, %zu moved close, %zu removed, %zu shrunk, %zu patterned\n",
           m->bs.features, m->bs.moved_close, m->bs.removed, m->bs.shrunk, m->bs.patterned);
  }
  if (meshed && m->material) {
    printf("  materials    %d:", m->nmaterials);
    for (int d = 1; d <= m->nmaterials; d++) {
      char name[128];
      mx_mesher2d_material_name(m, d, name, sizeof name);
      printf("%s %d \"%s\"", d > 1 ? "," : "", mx_mesher2d_material_number(m, d), name);
      if (m->mat_report)
        printf(" (%zu cells, area %.6g, region %.6g)", m->mat_report[d].cells,
               m->mat_report[d].cr.area, m->mat_report[d].cr.domain_area);
    }
    printf("\n");
    if (mx_mesher2d_nested(m))
      printf("  interfaces   %zu features (%zu moved onto, %zu inserted), %zu nodes warped, %zu "
             "crossings, %zu cells cut\n",
             m->cs.features, m->cs.features_moved, m->cs.features_inserted, m->cs.warped,
             m->cs.crossings, m->cs.cut);
  }
  if (meshed && ri->listed)
    printf("  re-meshed    %zu element(s) listed: %zu quadrant(s) split once\n", ri->listed,
           m->refined_listed);
  if (m && m->checked)
    printf("  check        %s; area %.6g (domain %.6g, %.3f%% off)\n",
           ri->status == MX_EINVALID ? "FAILED" : "conforming, valid", m->cr.area,
           m->cr.domain_area, 100.0 * m->cr.area_error);
  printf("  time (s)     %12.3f total:", ri->total);
  for (int p = 0; p < M2_NPH; p++) printf(" %s %.3f", phase_name[p], m ? m->rec->t[p] : 0.0);
  if (m && m->rec->t_restart > 0) printf(" restart %.3f", m->rec->t_restart);
  printf("\n  peak memory  %12.0f MB\n", mx_peak_rss_mb());
  for (int k = 0; k < ri->nwritten; k++)
    printf("  written      %s (%lld bytes)\n", ri->outputs[k], ri->bytes[k]);
  if (ri->restart) printf("  restart      %s\n", ri->restart);
  if (!ri->noutputs) printf("  written      nothing: a dry run (give -u NAME -v, or -O FILE)\n");
}

void mx_mesher2d_print_report(const mx_mesher2d *m, const mx_run2d_info *ri, int json) {
  if (json) print_json(m, ri);
  else if ((m && m->meshed) || !ri->status) print_summary(m, ri);
}
