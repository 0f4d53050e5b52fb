/* The reports of mx_check_file (include/mixoct.h, `mixoct check`), printed
 * to stdout: a readable report -- one line per kind of defect with its
 * criterion, followed for a kind that occurs by the first element or node
 * ids (0-based) and, for geometric hanging nodes, where the first ones lie
 * -- or one JSON object on one line (non-finite numbers are null; the ids
 * per kind in "defective_elements" and "defective_nodes").
 * Boundary tags (verify/check.h), when the mesh has them: a "boundary
 * tags" block (per tag: name, triangles, quadrilaterals, whether its faces
 * close up) and the two tag defects; in JSON the counters
 * "tagged_not_boundary" and "boundary_untagged" with the other defects
 * (and "boundary_flags_off": the nodes whose point field boundary, in a
 * VTU file of one material, differs from lying on a boundary face; null
 * without that field),
 * and after the tolerances "tagged_faces", "boundary_tags" (objects "tag",
 * "name" (null when unnamed), "triangles", "quads", "open_edges",
 * "not_boundary"), "boundary_node_tags" (objects "tag", "name", "nodes":
 * the point field surface_tag of VTK files; tag 0, inside, is left out),
 * and "defective_faces" ("tagged_not_boundary": indices in the file's
 * list of tagged faces); every array empty without tags.
 * Cell labels (materials), when the mesh has them: a "materials" block
 * (per label its elements, volume, boundary, and with a surface its region,
 * the region's volume and the elements lying in another region) and, with
 * a closed surface, the defects "interface off the surface", "across an
 * interface" and "off their label's region" (ids; for the elements the
 * first one's centroid and regions); in JSON, after "tagged_faces":
 * "materials" (objects "label", "elements", "volume", "open_edges",
 * "nonmanifold_edges", and with a surface "region", "region_volume",
 * "volume_error", "off_region"), "materials_dropped", "interface_faces",
 * "tagged_interface", "materials_volume_off", "interface_nodes",
 * "interface_max_dist", "interface_off_surface" and "interface_off_nodes"
 * (null and [] without a closed surface), "across_interface" and
 * "off_label_region" (objects "elements", "ids", "first_at",
 * "first_regions"; null without the regions).
 * A surface of several files (the inputs of a run, touching or nested):
 * each file named ("surfaces"), the closed shells, files and triangles two
 * files share ("surface pieces"), the volume their union's; in JSON after
 * "surface_open_edges": "surface_files", "surface_pieces" and
 * "shared_triangles" (the last two null for a surface that is not closed),
 * none of the three with one file.
 * With a closed surface, the distance between the mesh's skin (boundary and
 * interface faces) and the surface both ways (verify/check.h): a line
 * "boundary distance, both ways" (the maxima and means over the diagonal,
 * then absolute, the samples and their spacings); in JSON after
 * "boundary_max_dist": "hausdorff_mesh_to_surface_max", "..._mean",
 * "hausdorff_surface_to_mesh_max", "..._mean" (over the diagonal) and the
 * same four with "_abs" (absolute), null without a closed surface.
 * Feature distances (issue 29; check_file.c), when measured: a line
 * "features" (ridges, corners, the ridge and corner distances absolute and
 * over the diagonal) and where they come from, the farthest sample and
 * corner; with a feature tolerance the defect "features off"; in JSON
 * before "defective_faces": "features" (null when not measured, else
 * "source" ("surface" or the polylines file), "angle", "ridges", "loops",
 * "corners", "length", "samples", "boundary_edges", "diagonal",
 * "ridge_dist" and "corner_dist" (over the diagonal) and "..._abs",
 * "ridge_at", "ridge_line", "corner_at", "corner", "corner_node",
 * "tolerance" (null: none), "off"), its "off" counted in "defects".
 * A 3D mesh's hash is printed as 16 hex digits: "mesh hash" in the report,
 * "mesh_hash" (a string) in JSON.
 * A 2D mesh has a report of its own, and in JSON "dimension":2 with the
 * counters of mx_qcheck_report (quad/quad.h). */
#include <math.h>
#include <stdio.h>

#include "mesher/check_file.h"

/* ---- JSON ---------------------------------------------------------------- */

static void json_num(const char *key, double v, int last) {
  if (isfinite(v))
    printf("\"%s\":%.17g%s", key, v, last ? "" : ",");
  else
    printf("\"%s\":null%s", key, last ? "" : ",");
}

static void json_val(double v) {
  if (isfinite(v))
    printf("%.17g", v);
  else
    printf("null");
}

static void json_ids(const char *key, const mx_check_ids *l, int last) {
  printf("\"%s\":[", key);
  for (uint32_t i = 0; i < l->n; i++) printf(i ? ",%u" : "%u", l->id[i]);
  printf("]%s", last ? "" : ",");
}

/* A JSON string: quotes, backslashes and control characters escaped,
 * bytes that are not UTF-8 replaced by U+FFFD; null for NULL. */
static void json_str(const char *s) {
  if (!s) {
    printf("null");
    return;
  }
  putchar('"');
  const unsigned char *p = (const unsigned char *)s;
  while (*p) {
    const unsigned c = *p;
    if (c == '"' || c == '\\') {
      printf("\\%c", c);
      p++;
      continue;
    }
    if (c < 0x20) {
      printf("\\u%04x", c);
      p++;
      continue;
    }
    if (c < 0x80) {
      putchar((int)c);
      p++;
      continue;
    }
    /* a UTF-8 sequence: its length from the lead byte, continuation bytes
     * 10xxxxxx, no overlong form, no surrogate, at most U+10FFFF */
    const int n = c >= 0xC2 && c <= 0xDF ? 2 : c >= 0xE0 && c <= 0xEF ? 3
                  : c >= 0xF0 && c <= 0xF4 ? 4 : 0;
    int ok = n > 0;
    for (int k = 1; ok && k < n; k++) ok = (p[k] & 0xC0) == 0x80;
    if (ok && n == 3)
      ok = !(c == 0xE0 && p[1] < 0xA0) && !(c == 0xED && p[1] >= 0xA0);
    if (ok && n == 4)
      ok = !(c == 0xF0 && p[1] < 0x90) && !(c == 0xF4 && p[1] >= 0x90);
    if (!ok) {
      printf("\\ufffd");
      p++;
      continue;
    }
    fwrite(p, 1, (size_t)n, stdout);
    p += n;
  }
  putchar('"');
}

static const char *const on_word[4] = {"?", "vertex", "edge", "face"};

static void json_tags(const mx_check_tags *t) {
  printf("\"boundary_tags\":[");
  for (size_t i = 0; i < t->nface_tags; i++) {
    const mx_check_tag *g = &t->face_tags[i];
    printf("%s{\"tag\":%d,\"name\":", i ? "," : "", g->tag);
    json_str(g->name);
    printf(",\"triangles\":%zu,\"quads\":%zu,\"open_edges\":%zu,"
           "\"not_boundary\":%zu}",
           g->triangles, g->quads, g->open_edges, g->not_boundary);
  }
  printf("],\"boundary_node_tags\":[");
  for (size_t i = 0; i < t->nnode_tags; i++) {
    const mx_check_tag *g = &t->node_tags[i];
    printf("%s{\"tag\":%d,\"name\":", i ? "," : "", g->tag);
    json_str(g->name);
    printf(",\"nodes\":%zu}", g->nodes);
  }
  printf("],");
}

/* With a surface, elements of a label defect: count, first ids, the first
 * one's centroid and regions; null without a surface. */
static void json_elems_at(const char *key, const mx_check_elems_at *e, int on) {
  if (!on) {
    printf("\"%s\":null,", key);
    return;
  }
  printf("\"%s\":{\"elements\":%zu,", key, e->n);
  json_ids("ids", &e->ids, 0);
  printf("\"first_at\":");
  if (e->n) {
    printf("[");
    for (int a = 0; a < 3; a++) {
      if (a) printf(",");
      json_val(e->at[a]);
    }
    printf("],\"first_regions\":[%d,%d]}", e->region[0], e->region[1]);
  } else {
    printf("null,\"first_regions\":null}");
  }
  printf(",");
}

/* The materials' interfaces and regions against the surface. */
static void json_label_defects(const mx_check_report *r) {
  const int closed = r->has_surface && r->surface_open_edges == 0;
  printf("\"interface_nodes\":%zu,", r->interface_nodes);
  json_num("interface_max_dist", r->interface_max_dist, 0);
  if (closed) {
    printf("\"interface_off_surface\":%zu,", r->interface_off_surface);
    json_ids("interface_off_nodes", &r->interface_off_ids, 0);
  } else {
    printf("\"interface_off_surface\":null,\"interface_off_nodes\":[],");
  }
  json_elems_at("across_interface", &r->across_interface, r->has_regions);
  json_elems_at("off_label_region", &r->off_label_region, r->has_regions);
}

/* The skin and the surface, both ways: relative to the surface's diagonal,
 * then absolute. */
static void json_xyz(const char *key, const double *p) {
  printf("\"%s\":[", key);
  for (int a = 0; a < 3; a++) {
    if (a) printf(",");
    json_val(p[a]);
  }
  printf("],");
}

/* "features": null when not measured, else the object (see the head). */
static void json_features(const mx_check_file_features *f) {
  if (!f->measured) {
    printf("\"features\":null,");
    return;
  }
  const mx_check_feature_dist *d = &f->d;
  printf("\"features\":{\"source\":");
  json_str(f->file ? f->file : "surface");
  printf(",");
  json_num("angle", f->angle, 0);
  printf("\"ridges\":%zu,\"loops\":%zu,\"corners\":%zu,", d->lines, d->loops, d->corners);
  json_num("length", d->length, 0);
  printf("\"samples\":%zu,\"boundary_edges\":%zu,", d->samples, d->edges);
  json_num("diagonal", f->diagonal, 0);
  json_num("ridge_dist", d->ridge_dist / f->diagonal, 0);
  json_num("ridge_dist_abs", d->ridge_dist, 0);
  json_xyz("ridge_at", d->ridge_at);
  if (d->lines)
    printf("\"ridge_line\":%zu,", d->ridge_line);
  else
    printf("\"ridge_line\":null,");
  json_num("corner_dist", d->corner_dist / f->diagonal, 0);
  json_num("corner_dist_abs", d->corner_dist, 0);
  json_xyz("corner_at", d->corner_at);
  if (d->corner_node != UINT32_MAX)
    printf("\"corner\":%zu,\"corner_node\":%u,", d->corner, d->corner_node);
  else
    printf("\"corner\":null,\"corner_node\":null,");
  json_num("tolerance", f->tol > 0.0 ? f->tol : NAN, 0);
  printf("\"off\":%zu},", f->off);
}

static void json_two_sided(const mx_check_report *r) {
  const double v[4] = {r->mesh_to_surface_max, r->mesh_to_surface_mean,
                       r->surface_to_mesh_max, r->surface_to_mesh_mean};
  static const char *const key[4] = {"mesh_to_surface_max", "mesh_to_surface_mean",
                                     "surface_to_mesh_max", "surface_to_mesh_mean"};
  char k[64];
  for (int absolute = 0; absolute < 2; absolute++)
    for (int i = 0; i < 4; i++) {
      snprintf(k, sizeof k, "hausdorff_%s%s", key[i], absolute ? "_abs" : "");
      json_num(k, absolute ? v[i] : v[i] / r->surface_diagonal, 0);
    }
}

void mx_check_file_json(const mx_check_report *r, const mx_check_tags *t, uint64_t hash,
                        const mx_check_file_features *f) {
  printf("{\"nodes\":%zu,\"elements\":%zu,", r->nodes, r->elements);
  printf("\"by_type\":{\"hex\":%zu,\"prism\":%zu,\"pyramid\":%zu,\"tet\":%zu},",
         r->by_type[MX_HEX], r->by_type[MX_PRISM], r->by_type[MX_PYRAMID],
         r->by_type[MX_TET]);
  printf("\"mesh_hash\":\"%016llx\",", (unsigned long long)hash);
  printf("\"empty\":%zu,\"invalid\":%zu,\"degenerate\":%zu,", r->empty,
         r->invalid, r->degenerate);
  json_num("jens_min", r->jens_min, 0);
  json_num("jens_mean", r->jens_mean, 0);
  printf("\"faces_interior\":%zu,\"faces_boundary\":%zu,"
         "\"faces_overshared\":%zu,\"faces_misoriented\":%zu,"
         "\"quad_vs_triangles\":%zu,\"open_boundary_edges\":%zu,"
         "\"nonmanifold_edges\":%zu,"
         "\"hanging_nodes\":%zu,\"geometric_hanging_nodes\":%zu,"
         "\"unused_nodes\":%zu,\"duplicate_nodes\":%zu,",
         r->faces_interior, r->faces_boundary, r->faces_overshared,
         r->faces_misoriented, r->quad_vs_triangles, r->open_boundary_edges,
         r->nonmanifold_edges, r->hanging_nodes, r->geometric_hanging_nodes,
         r->unused_nodes, r->duplicate_nodes);
  json_num("volume", r->volume, 0);
  json_num("surface_volume", r->surface_volume, 0);
  json_num("volume_error", r->volume_error, 0);
  json_num("boundary_max_dist", r->boundary_max_dist, 0);
  json_two_sided(r);
  if (r->has_surface)
    printf("\"surface_open_edges\":%zu,", r->surface_open_edges);
  else
    printf("\"surface_open_edges\":null,");
  if (r->surface_files > 1) { /* several surface files */
    printf("\"surface_files\":%zu,", r->surface_files);
    if (r->surface_open_edges == 0)
      printf("\"surface_pieces\":%zu,\"shared_triangles\":%zu,", r->surface_pieces,
             r->shared_triangles);
    else
      printf("\"surface_pieces\":null,\"shared_triangles\":null,");
  }
  printf("\"volume_off\":%zu,\"boundary_off_surface\":%zu,", r->volume_off,
         r->boundary_off_surface);
  printf("\"tagged_not_boundary\":%zu,\"boundary_untagged\":%zu,",
         r->tagged_not_boundary, r->boundary_untagged);
  if (r->has_boundary_flags)
    printf("\"boundary_flags_off\":%zu,", r->boundary_flags_off);
  else
    printf("\"boundary_flags_off\":null,");
  printf("\"tolerances\":{");
  json_num("degenerate_jens", r->opt.degenerate_below, 0);
  json_num("hanging", r->opt.hang_tol, 0);
  json_num("volume", r->opt.volume_tol, 0);
  json_num("boundary_dist", r->opt.boundary_tol, 1);
  printf("},\"defective_elements\":{");
  for (int k = 0; k < MX_CK_ELEM_KINDS; k++)
    json_ids(mx_check_elem_kind_name[k], &r->elem_ids[k], 0);
  json_ids("boundary_untagged", &r->untagged_ids, 1);
  printf("},\"defective_nodes\":{");
  for (int k = 0; k < MX_CK_NODE_KINDS; k++)
    json_ids(mx_check_node_kind_name[k], &r->node_ids[k], 0);
  json_ids("boundary_flags_off", &r->boundary_flag_ids, 1);
  printf("},\"geometric_hanging_at\":[");
  for (size_t i = 0; i < r->nshown; i++) {
    const mx_check_hang *h = &r->hang_at[i];
    printf("%s{\"node\":%u,\"xyz\":[", i ? "," : "", h->node);
    for (int a = 0; a < 3; a++) {
      if (a) printf(",");
      json_val(h->xyz[a]);
    }
    printf("],\"element\":%u,\"on\":\"%s\",\"nodes_of\":[", h->element,
           on_word[h->on & 3]);
    for (int k = 0; k < h->nverts; k++)
      printf(k ? ",%u" : "%u", h->verts[k]);
    printf("]}");
  }
  printf("],\"tagged_faces\":%zu,", r->tagged_faces);
  if (r->nlabels) { /* several materials: the cells' labels */
    printf("\"materials\":[");
    for (size_t i = 0; i < r->nlabels; i++) {
      const mx_check_label *L = &r->labels[i];
      printf("%s{\"label\":%d,\"elements\":%zu,\"volume\":%.17g,\"open_edges\":%zu,"
             "\"nonmanifold_edges\":%zu", i ? "," : "", L->label, L->cells, L->volume,
             L->open_edges, L->nonmanifold_edges);
      if (L->region >= 0) {
        printf(",\"region\":%d,", L->region);
        json_num("region_volume", L->region_volume, 0);
        json_num("volume_error", L->volume_error, 0);
        printf("\"off_region\":%zu", L->off_region);
      }
      printf("}");
    }
    printf("],\"materials_dropped\":%zu,\"interface_faces\":%zu,\"tagged_interface\":%zu,"
           "\"materials_volume_off\":%zu,",
           r->labels_dropped, r->interface_faces, r->tagged_interface, r->labels_off);
    json_label_defects(r);
  }
  json_tags(t);
  json_features(f);
  printf("\"defective_faces\":{");
  json_ids("tagged_not_boundary", &r->not_boundary_ids, 1);
  printf("},\"defects\":%zu}\n", r->defects + f->off);
}

/* ---- text ---------------------------------------------------------------- */

static void defect_line(const char *what, size_t n, const char *why) {
  printf("    %-24s %zu%s%s%s\n", what, n, n ? "   <-- defect" : "",
         why ? "   " : "", why ? why : "");
}

static void id_line(const char *what, const mx_check_ids *l, size_t total) {
  if (l->n == 0) return;
  printf("      %s:", what);
  for (uint32_t i = 0; i < l->n; i++) printf(" %u", l->id[i]);
  if (l->n == MX_CHECK_LIST && total > l->n) printf(" ...");
  printf("\n");
}

/* A name for the text report: in quotes, control characters as '?'. */
static void text_name(const char *s) {
  if (!s) return;
  printf(" \"");
  for (; *s; s++) putchar((unsigned char)*s < 0x20 ? '?' : *s);
  printf("\"");
}

/* The "materials" block: the cells' labels, when the file gives them. */
static void print_labels(const mx_check_report *r) {
  if (!r->nlabels) return;
  printf("  materials              %zu label%s (cell labels of the file)%s\n", r->nlabels,
         r->nlabels == 1 ? "" : "s", r->labels_dropped ? ", more not listed" : "");
  for (size_t i = 0; i < r->nlabels; i++) {
    const mx_check_label *L = &r->labels[i];
    printf("    label %d: %zu elements, volume %.10g, boundary %s", L->label, L->cells, L->volume,
           L->open_edges ? "not closed" : "closed");
    if (L->open_edges) printf(" (%zu open edges)  <-- defect", L->open_edges);
    if (L->nonmanifold_edges) printf(", touching itself along %zu edges", L->nonmanifold_edges);
    if (L->region >= 0)
      printf(" (the surface's region %d holds %.10g: %+.3f%%%s)", L->region, L->region_volume,
             100.0 * L->volume_error,
             fabs(L->volume_error) <= r->opt.volume_tol ? "" : "  <-- defect");
    else if (r->has_regions)
      printf(" (none of its elements lies in one region of the surface)");
    if (L->off_region)
      printf(", %zu elements in another region  <-- defect", L->off_region);
    printf("\n");
  }
  printf("  interfaces             %zu faces between elements of two labels, %zu of them "
         "tagged\n", r->interface_faces, r->tagged_interface);
}

/* The first element of a label defect: where, and in which regions. */
static void first_line(const mx_check_elems_at *e, const char *a, const char *b) {
  if (!e->n) return;
  printf("      first: element %u at (%.17g, %.17g, %.17g), %s %d, %s %d\n", e->ids.id[0],
         e->at[0], e->at[1], e->at[2], a, e->region[0], b, e->region[1]);
}

/* The materials' defects against a closed surface. */
static void print_label_defects(const mx_check_report *r) {
  char why[160];
  snprintf(why, sizeof why, "(interface nodes farther than %g of the diagonal)",
           r->opt.boundary_tol);
  defect_line("interface off the surface", r->interface_off_surface, why);
  id_line("nodes", &r->interface_off_ids, r->interface_off_surface);
  if (!r->has_regions) return;
  defect_line("across an interface", r->across_interface.n,
              "(elements whose centroid and corners off the shells are not in one region)");
  id_line("elements", &r->across_interface.ids, r->across_interface.n);
  first_line(&r->across_interface, "region", "and region");
  defect_line("off their label's region", r->off_label_region.n,
              "(elements in another region than most of their label's)");
  id_line("elements", &r->off_label_region.ids, r->off_label_region.n);
  first_line(&r->off_label_region, "in region", "its label's");
}

/* The "boundary tags" block. */
static void print_tags(const mx_check_report *r, const mx_check_tags *t) {
  print_labels(r);
  if (r->has_tagged_faces) {
    size_t tri = 0, quad = 0;
    for (size_t i = 0; i < t->nface_tags; i++) {
      tri += t->face_tags[i].triangles;
      quad += t->face_tags[i].quads;
    }
    printf("  boundary tags          %zu tag%s, %zu faces (%zu triangles, %zu "
           "quadrilaterals)\n",
           t->nface_tags, t->nface_tags == 1 ? "" : "s", r->tagged_faces, tri,
           quad);
    for (size_t i = 0; i < t->nface_tags; i++) {
      const mx_check_tag *g = &t->face_tags[i];
      printf("    tag %d", g->tag);
      text_name(g->name);
      printf(": %zu triangles, %zu quadrilaterals, ", g->triangles, g->quads);
      if (g->open_edges)
        printf("%zu open edge%s (not closed)", g->open_edges,
               g->open_edges == 1 ? "" : "s");
      else
        printf("closed");
      if (g->not_boundary)
        printf(", %zu not on the boundary", g->not_boundary);
      printf("\n");
    }
  }
  if (r->has_node_tags) {
    printf("  boundary tags on nodes %zu tag%s (point field surface_tag; "
           "0, inside, not listed)\n",
           t->nnode_tags, t->nnode_tags == 1 ? "" : "s");
    for (size_t i = 0; i < t->nnode_tags; i++) {
      printf("    tag %d", t->node_tags[i].tag);
      text_name(t->node_tags[i].name);
      printf(": %zu nodes\n", t->node_tags[i].nodes);
    }
  }
}

/* The features line: counts, distances over the diagonal, then where. */
static void print_features(const mx_check_file_features *f) {
  if (!f->measured) return;
  const mx_check_feature_dist *d = &f->d;
  const double D = f->diagonal;
  printf("  features               %zu ridge%s, %zu corner%s; ridge distance %.3g (%.3g of the "
         "diagonal), corner distance %.3g (%.3g of the diagonal)\n",
         d->lines, d->lines == 1 ? "" : "s", d->corners, d->corners == 1 ? "" : "s",
         d->ridge_dist, d->ridge_dist / D, d->corner_dist, d->corner_dist / D);
  if (f->file)
    printf("                         from %s (corners at %g degrees)", f->file, f->angle);
  else
    printf("                         found on the surface at %g degrees", f->angle);
  printf("; %zu loops, length %.6g, %zu samples against %zu boundary edges (diagonal %.6g)%s\n",
         d->loops, d->length, d->samples, d->edges, D,
         f->tol > 0.0 ? "" : "; indicative, --feature-tol T to judge");
  if (d->lines && isfinite(d->ridge_dist))
    printf("                         farthest ridge sample (%.9g, %.9g, %.9g) on ridge %zu\n",
           d->ridge_at[0], d->ridge_at[1], d->ridge_at[2], d->ridge_line);
  if (d->corner_node != UINT32_MAX)
    printf("                         farthest corner %zu (%.9g, %.9g, %.9g), nearest node %u\n",
           d->corner, d->corner_at[0], d->corner_at[1], d->corner_at[2], d->corner_node);
}

void mx_check_file_text(const char *mesh, const char *const *surfs, int nsurfs,
                        const mx_check_report *r, const mx_check_tags *t, uint64_t hash,
                        const mx_check_file_features *f, double t_read, double t_check) {
  char why[160];
  const char *surf = nsurfs ? surfs[0] : NULL;
  printf("mixoct check %s\n", mesh);
  printf("  nodes                  %zu\n", r->nodes);
  printf("  elements               %zu (hex %zu, prism %zu, pyramid %zu, "
         "tet %zu)\n",
         r->elements, r->by_type[MX_HEX], r->by_type[MX_PRISM],
         r->by_type[MX_PYRAMID], r->by_type[MX_TET]);
  printf("  J_ENS                  min %.6g, mean %.6g\n", r->jens_min,
         r->jens_mean);
  printf("  faces                  %zu interior, %zu boundary\n",
         r->faces_interior, r->faces_boundary);
  printf("  volume                 %.15g\n", r->volume);
  printf("  mesh hash              %016llx\n", (unsigned long long)hash);
  const int closed = r->has_surface && r->surface_open_edges == 0;
  if (surf) {
    printf("  %-23s%s\n", nsurfs > 1 ? "surfaces" : "surface", surf);
    for (int i = 1; i < nsurfs; i++) printf("                         %s\n", surfs[i]);
    if (nsurfs > 1 && closed)
      printf("  surface pieces         %zu closed shells in %zu files; %zu triangles lie on "
             "another file's (interfaces, not boundary)\n", r->surface_pieces,
             r->surface_files, r->shared_triangles);
    printf("  surface volume         %.15g%s\n", r->surface_volume,
           nsurfs > 1 && closed ? r->nlabels ? " (their union)"
                                             : " (odd nesting depth: nested shells are holes)"
                                : "");
    if (closed)
      printf("  surface open edges     0 (closed)\n");
    else
      printf("  surface open edges     %zu (not closed: the volume error and "
             "distance are indicative, not defects)\n",
             r->surface_open_edges);
    printf("  volume error           %.3e (tolerance %.3g%s)\n", r->volume_error,
           r->opt.volume_tol,
           r->opt.volume_tol_auto ? ": half a layer of elements along the surface, 5% at "
                                    "least; --volume-tol X to set it" : "");
    printf("  boundary max distance  %.3e of the surface's bounding box "
           "diagonal (tolerance %g)\n",
           r->boundary_max_dist, r->opt.boundary_tol);
    if (closed) {
      const double D = r->surface_diagonal;
      printf("  boundary distance, both ways: mesh -> surface max %.3e, mean %.3e; "
             "surface -> mesh max %.3e, mean %.3e of the diagonal (indicative)\n",
             r->mesh_to_surface_max / D, r->mesh_to_surface_mean / D,
             r->surface_to_mesh_max / D, r->surface_to_mesh_mean / D);
      printf("                         absolute: max %.6g, mean %.6g; max %.6g, mean %.6g "
             "(diagonal %.6g; samples %zu every %.3g and %zu every %.3g)\n",
             r->mesh_to_surface_max, r->mesh_to_surface_mean, r->surface_to_mesh_max,
             r->surface_to_mesh_mean, D, r->mesh_to_surface_samples, r->mesh_sample_spacing,
             r->surface_to_mesh_samples, r->surface_sample_spacing);
    }
    if (r->nlabels)
      printf("  interface max distance %.3e of the diagonal, over %zu interface nodes "
             "(tolerance %g)\n",
             r->interface_max_dist, r->interface_nodes, r->opt.boundary_tol);
  }
  print_features(f);
  printf("  non-manifold edges     %zu (parts of the domain touching along an "
         "edge; not a defect)\n", r->nonmanifold_edges);
  print_tags(r, t);
  printf("  defects\n");
  const mx_check_ids *E = r->elem_ids, *N = r->node_ids;
  defect_line("empty mesh", r->empty, "(no element or no node)");
  defect_line("invalid elements", r->invalid, "(J_ENS <= 0 or not a number)");
  id_line("elements", &E[MX_CK_INVALID], r->invalid);
  snprintf(why, sizeof why, "(0 < J_ENS < %g: collinear or coplanar nodes)",
           r->opt.degenerate_below);
  defect_line("degenerate elements", r->degenerate, why);
  id_line("elements", &E[MX_CK_DEGENERATE], r->degenerate);
  defect_line("overshared faces", r->faces_overshared,
              "(used by 3 or more elements)");
  id_line("elements", &E[MX_CK_OVERSHARED], SIZE_MAX);
  defect_line("misoriented faces", r->faces_misoriented, NULL);
  id_line("elements", &E[MX_CK_MISORIENTED], SIZE_MAX);
  defect_line("quad vs triangles", r->quad_vs_triangles, NULL);
  id_line("elements", &E[MX_CK_QUAD_TRI], SIZE_MAX);
  defect_line("open boundary edges", r->open_boundary_edges, NULL);
  id_line("elements", &E[MX_CK_OPEN_EDGE], SIZE_MAX);
  defect_line("hanging nodes", r->hanging_nodes,
              "(exactly at an edge midpoint or quad centre)");
  id_line("nodes", &N[MX_CK_N_HANGING], r->hanging_nodes);
  id_line("on elements", &E[MX_CK_HANGING], SIZE_MAX);
  snprintf(why, sizeof why,
           "(on a face, edge or vertex of another element, within %g of "
           "its size)",
           r->opt.hang_tol);
  defect_line("geometric hanging nodes", r->geometric_hanging_nodes, why);
  id_line("nodes", &N[MX_CK_N_GEOM_HANGING], r->geometric_hanging_nodes);
  id_line("on elements", &E[MX_CK_GEOM_HANGING], SIZE_MAX);
  for (size_t i = 0; i < r->nshown; i++) {
    const mx_check_hang *h = &r->hang_at[i];
    printf("      node %u at (%.17g, %.17g, %.17g) on the %s", h->node,
           h->xyz[0], h->xyz[1], h->xyz[2], on_word[h->on & 3]);
    for (int k = 0; k < h->nverts; k++)
      printf("%s%u", k ? "-" : " ", h->verts[k]);
    printf(" of element %u\n", h->element);
  }
  defect_line("unused nodes", r->unused_nodes, NULL);
  id_line("nodes", &N[MX_CK_N_UNUSED], r->unused_nodes);
  defect_line("duplicate nodes", r->duplicate_nodes,
              "(same coordinates as a node with a smaller id)");
  id_line("nodes", &N[MX_CK_N_DUPLICATE], r->duplicate_nodes);
  if (surf) {
    if (closed) {
      snprintf(why, sizeof why, "(|volume error| > %g)", r->opt.volume_tol);
      defect_line("volume off", r->volume_off, why);
      if (r->nlabels)
        defect_line("material volumes off", r->labels_off,
                    "(labels whose volume is off their region's beyond the same tolerance)");
      snprintf(why, sizeof why,
               "(boundary nodes farther than %g of the diagonal)",
               r->opt.boundary_tol);
      defect_line("boundary off the surface", r->boundary_off_surface, why);
      id_line("nodes", &N[MX_CK_N_OFF_SURFACE], r->boundary_off_surface);
      if (r->nlabels) print_label_defects(r);
    } else {
      printf("    %-24s -   (the surface is not closed: not checked)\n",
             "volume off");
      printf("    %-24s -   (the surface is not closed: not checked)\n",
             "boundary off the surface");
    }
  }
  if (r->has_boundary_flags) {
    defect_line("boundary flags off", r->boundary_flags_off,
                "(point field boundary against the boundary faces' nodes)");
    id_line("nodes", &r->boundary_flag_ids, r->boundary_flags_off);
  }
  if (r->has_tagged_faces) {
    defect_line("tagged not boundary", r->tagged_not_boundary,
                "(tagged faces that are not boundary faces)");
    id_line("tagged faces", &r->not_boundary_ids, r->tagged_not_boundary);
    defect_line("boundary untagged", r->boundary_untagged,
                "(boundary faces no tagged face names)");
    id_line("elements", &r->untagged_ids, SIZE_MAX);
  }
  if (f->measured && f->tol > 0.0) {
    snprintf(why, sizeof why, "(the ridge and the corner distance: above %g of the diagonal)",
             f->tol);
    defect_line("features off", f->off, why);
  }
  const size_t defects = r->defects + f->off;
  if (defects)
    printf("  result                 %zu defect%s\n", defects, defects == 1 ? "" : "s");
  else
    printf("  result                 OK, no defect\n");
  printf("  time                   read %.3f s, check %.3f s\n", t_read,
         t_check);
}

/* ---- 2D meshes ------------------------------------------------------------ */

/* The smallest and the mean scaled Jacobian over both cell types. */
static void sj_summary(const mx_qquality *q, double *mn, double *mean) {
  const size_t n = q->count[0] + q->count[1];
  *mn = fmin(q->count[0] ? q->min[0] : INFINITY, q->count[1] ? q->min[1] : INFINITY);
  *mean = n ? ((q->count[0] ? q->mean[0] * (double)q->count[0] : 0.0) +
               (q->count[1] ? q->mean[1] * (double)q->count[1] : 0.0)) / (double)n
            : NAN;
}

/* A domain counter, null without a domain. */
static void json_dcount(const mx_check_file_2d *k, const char *key, size_t v) {
  if (k->domain)
    printf("\"%s\":%zu,", key, v);
  else
    printf("\"%s\":null,", key);
}

void mx_check_file_json_2d(const mx_qmesh *M, const mx_check_file_2d *k) {
  const mx_qcheck_report *c = &k->c;
  double sjmin, sjmean;
  sj_summary(&k->q, &sjmin, &sjmean);
  printf("{\"dimension\":2,\"nodes\":%zu,\"elements\":%zu,", M->nnodes, M->ncells);
  printf("\"by_type\":{\"tri\":%zu,\"quad\":%zu},", k->q.count[0], k->q.count[1]);
  printf("\"conforming\":%s,\"valid\":%s,", c->bad_edges || c->hanging ? "false" : "true",
         k->defects ? "false" : "true");
  printf("\"empty\":%zu,\"bad_edges\":%zu,\"hanging\":%zu,\"inverted\":%zu,\"invalid\":%zu,"
         "\"unused_nodes\":%zu,",
         k->empty, c->bad_edges, c->hanging, c->inverted, k->q.invalid, k->unused_nodes);
  json_num("sj_min", sjmin, 0);
  json_num("sj_mean", sjmean, 0);
  json_num("min_angle", k->q.min_angle, 0);
  printf("\"edges\":%zu,\"boundary_edges\":%zu,\"euler\":%ld,", c->edges, c->boundary_edges,
         c->euler);
  json_num("area", c->area, 0);
  printf("\"domain\":");
  json_str(k->domain);
  printf(",");
  if (k->domain) {
    json_num("domain_area", c->domain_area, 0);
    json_num("area_error", c->area_error, 0);
    printf("\"domain_euler\":%ld,", c->domain_euler);
  } else {
    printf("\"domain_area\":null,\"area_error\":null,\"domain_euler\":null,");
  }
  json_dcount(k, "off_boundary", c->off_boundary);
  json_dcount(k, "missing_features", c->missing_features);
  json_dcount(k, "topology_off", k->topology_off);
  json_dcount(k, "area_off", k->area_off);
  printf("\"tolerances\":{");
  json_num("boundary_dist", k->dist_tol, 0);
  json_num("area", k->domain ? k->area_tol : NAN, 1);
  printf("},\"defects\":%zu}\n", k->defects);
}

void mx_check_file_text_2d(const char *mesh, const mx_qmesh *M, const mx_check_file_2d *k,
                           double t_read, double t_check) {
  const mx_qcheck_report *c = &k->c;
  char why[200];
  double sjmin, sjmean;
  sj_summary(&k->q, &sjmin, &sjmean);
  printf("mixoct check %s (2D mesh)\n", mesh);
  printf("  nodes                  %zu (%zu unused)\n", M->nnodes, k->unused_nodes);
  printf("  elements               %zu (triangles %zu, quadrilaterals %zu)\n", M->ncells,
         k->q.count[0], k->q.count[1]);
  printf("  scaled Jacobian        min %.6g, mean %.6g; min angle %.4g degrees\n", sjmin, sjmean,
         k->q.min_angle);
  printf("  edges                  %zu (%zu on the boundary)\n", c->edges, c->boundary_edges);
  printf("  area                   %.15g\n", c->area);
  printf("  euler                  %ld (V - E + F: components minus holes)\n", c->euler);
  printf("  conforming             %s\n", c->bad_edges || c->hanging ? "no" : "yes");
  if (k->domain) {
    printf("  domain                 %s\n", k->domain);
    printf("  domain area            %.15g\n", c->domain_area);
    printf("  domain euler           %ld (outer loops minus holes)\n", c->domain_euler);
    printf("  area error             %.3e (tolerance %.3g%s)\n", c->area_error, k->area_tol,
           k->area_tol_auto ? ": half a layer of cells along the polylines, 5% to 25%; "
                              "--volume-tol X to set it" : "");
  }
  printf("  defects\n");
  defect_line("empty mesh", k->empty, "(no cell or no node)");
  defect_line("bad edges", c->bad_edges,
              "(used by 3 or more cells, by 2 in the same direction, or degenerate)");
  defect_line("hanging nodes", c->hanging,
              "(on another cell's edge: a T-junction or a duplicated node)");
  defect_line("inverted cells", c->inverted,
              "(a corner not strictly convex: clockwise, degenerate or non-convex)");
  if (k->domain) {
    snprintf(why, sizeof why, "(boundary nodes farther than %g of the domain's diameter)",
             k->dist_tol);
    defect_line("boundary off polylines", c->off_boundary, why);
    defect_line("missing features", c->missing_features, "(features with no node on them)");
    snprintf(why, sizeof why, "(euler %ld, the domain's %ld)", c->euler, c->domain_euler);
    defect_line("topology off", k->topology_off, why);
    snprintf(why, sizeof why, "(area error %.3g > %.3g)", c->area_error, k->area_tol);
    defect_line("area off", k->area_off, k->area_off ? why : NULL);
  }
  if (k->defects)
    printf("  result                 not valid: %zu defect%s\n", k->defects,
           k->defects == 1 ? "" : "s");
  else
    printf("  result                 OK, valid, no defect\n");
  printf("  time                   read %.3f s, check %.3f s\n", t_read, t_check);
}
