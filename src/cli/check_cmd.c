/* `mixoct check MESH [--surface FILE | --poly FILE] [--volume-tol X]
 * [--dist-tol X] [--threads N] [--json] [--quiet]`:
 * reads a volume mesh (legacy VTK, VTU, Gmsh MSH 4.1, Medit .mesh/.meshb)
 * and, optionally, the surface it should fill, runs the independent checker
 * (verify/check.h) and reports.
 *
 * A 2D mesh (io/read_mesh.h: mx_read_mesh_dim; triangles and
 * quadrilaterals in the plane z = 0, as mesher2d writes them to .vtu, .vtk,
 * .msh and .off) is checked by quad/qcheck.c instead, against the polylines of its domain when given
 * (--poly FILE, or --surface FILE with a .poly, a 2D .off or a .mdl): the
 * same criteria as mesher2d's own check (see check_2d below), a report of
 * its own, and in JSON "dimension":2 with the counters of mx_qcheck_report.
 * A 3D surface with a 2D mesh, or polylines (--poly, a .poly) with a 3D
 * mesh, are usage errors (exit 2).
 *
 * Output: a readable report -- one line per kind of defect with its
 * criterion, followed for a kind that occurs by the first element or node
 * ids (0-based) and, for geometric hanging nodes, where the first ones lie
 * -- or with --json one JSON object on the last stdout line (non-finite
 * numbers are null; the ids per kind in "defective_elements" and
 * "defective_nodes"); --quiet prints nothing but errors (and the JSON object
 * when --json is given) and silences warnings.
 * Boundary tags (verify/check.h), when the mesh has them: a "boundary
 * tags" block (per tag: name, triangles, quadrilaterals, whether its faces
 * close up) and the two tag defects; in JSON the counters
 * "tagged_not_boundary" and "boundary_untagged" with the other defects,
 * and after the tolerances "tagged_faces", "boundary_tags" (objects "tag",
 * "name" (null when unnamed), "triangles", "quads", "open_edges",
 * "not_boundary"), "boundary_node_tags" (objects "tag", "name", "nodes":
 * the point field surface_tag of VTK files; tag 0, inside, is left out),
 * and "defective_faces" ("tagged_not_boundary": indices in the file's
 * list of tagged faces); every array empty without tags.
 * A 3D mesh's hash (io/pvtu.h: mx_mesh_hash; the same for any node
 * numbering and cell order, so for a mesh and its .pvtu pieces) is printed
 * as 16 hex digits: "mesh hash" in the report, "mesh_hash" (a string) in
 * JSON.
 * Exit codes: 0 no defect, 3 defects found, 2 bad input or usage (the
 * message names the file), 1 internal failure. */
#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "cli/cli.h"
#include "geom/surface_defects.h"
#include "base/common.h"
#include "io/pvtu.h"
#include "io/read_mesh.h"
#include "mesher/mesher2d.h"
#include "verify/check.h"
#include "quad/quad.h"
#include "soa/trisoup.h"
#include "io/read_surface.h"
#include "io/read_poly.h"

enum { EXIT_DEFECTS = 3, EXIT_USAGE = 2 };

static void usage(FILE *f) {
  fprintf(f,
          "usage: mixoct check MESH [--surface FILE | --poly FILE] "
          "[--volume-tol X]\n"
          "                    [--dist-tol X] [--threads N] [--json] "
          "[--quiet]\n"
          "  MESH              legacy VTK (.vtk, ASCII or binary), VTU, Gmsh\n"
          "                    MSH 4.1 (ASCII or binary), Medit (.mesh,\n"
          "                    .meshb), GetFEM (.getfem), M3D or MVM volume\n"
          "                    mesh (recognised by content); or a 2D mesh:\n"
          "                    triangles and quadrilaterals at z = 0 in VTK,\n"
          "                    VTU, MSH or OFF (as mesher2d writes them)\n"
          "  --surface FILE    the closed surface the mesh should fill (.off,\n"
          "                    .stl, .obj, .mdl, .ply): volume error and\n"
          "                    distance of the boundary nodes to it; for a\n"
          "                    2D mesh, its polylines as --poly\n"
          "  --poly FILE       the domain of a 2D mesh: closed polylines\n"
          "                    (.poly, or a 2D .off or .mdl): boundary on\n"
          "                    them, features as vertices, area, topology\n"
          "  --volume-tol X    largest |volume error| accepted with --surface\n"
          "                    (relative; default: half a layer of elements\n"
          "                    along the surface, 0.5 A h / V, 0.05 at least;\n"
          "                    2D: the area error, 0.5 P h / A in [0.05,\n"
          "                    0.25]; --area-tol X is the same option)\n"
          "  --dist-tol X      largest boundary distance accepted with\n"
          "                    --surface (relative to the surface's bounding\n"
          "                    box diagonal; 2D: to the domain's diameter;\n"
          "                    default 1e-6)\n"
          "  --threads N       OpenMP threads (default: all)\n"
          "  --json            one JSON object on the last line of stdout\n"
          "  --quiet           no report (errors only; JSON if --json)\n"
          "exit: 0 no defect, 3 defects found, 2 bad input or usage\n");
}

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

static void print_json(const mx_check_report *r, const mx_check_tags *t, uint64_t hash) {
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
  if (r->has_surface)
    printf("\"surface_open_edges\":%zu,", r->surface_open_edges);
  else
    printf("\"surface_open_edges\":null,");
  printf("\"volume_off\":%zu,\"boundary_off_surface\":%zu,", r->volume_off,
         r->boundary_off_surface);
  printf("\"tagged_not_boundary\":%zu,\"boundary_untagged\":%zu,",
         r->tagged_not_boundary, r->boundary_untagged);
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
    json_ids(mx_check_node_kind_name[k], &r->node_ids[k],
             k == MX_CK_NODE_KINDS - 1);
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
  json_tags(t);
  printf("\"defective_faces\":{");
  json_ids("tagged_not_boundary", &r->not_boundary_ids, 1);
  printf("},\"defects\":%zu}\n", r->defects);
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

/* The "boundary tags" block. */
static void print_tags(const mx_check_report *r, const mx_check_tags *t) {
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

static void print_report(const char *mesh, const char *surf,
                         const mx_check_report *r, const mx_check_tags *t,
                         uint64_t hash, double t_read, double t_check) {
  char why[160];
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
    printf("  surface                %s\n", surf);
    printf("  surface volume         %.15g\n", r->surface_volume);
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
  }
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
      snprintf(why, sizeof why,
               "(boundary nodes farther than %g of the diagonal)",
               r->opt.boundary_tol);
      defect_line("boundary off the surface", r->boundary_off_surface, why);
      id_line("nodes", &N[MX_CK_N_OFF_SURFACE], r->boundary_off_surface);
    } else {
      printf("    %-24s -   (the surface is not closed: not checked)\n",
             "volume off");
      printf("    %-24s -   (the surface is not closed: not checked)\n",
             "boundary off the surface");
    }
  }
  if (r->has_tagged_faces) {
    defect_line("tagged not boundary", r->tagged_not_boundary,
                "(tagged faces that are not boundary faces)");
    id_line("tagged faces", &r->not_boundary_ids, r->tagged_not_boundary);
    defect_line("boundary untagged", r->boundary_untagged,
                "(boundary faces no tagged face names)");
    id_line("elements", &r->untagged_ids, SIZE_MAX);
  }
  if (r->defects)
    printf("  result                 %zu defect%s\n", r->defects,
           r->defects == 1 ? "" : "s");
  else
    printf("  result                 OK, no defect\n");
  printf("  time                   read %.3f s, check %.3f s\n", t_read,
         t_check);
}

/* ---- 2D meshes ------------------------------------------------------------
 *
 * The criteria of mesher2d's own check (src/cli/mesher2d.c): a 2D mesh is
 * conforming with no bad edge and no hanging node, valid when moreover no
 * cell is inverted (quad/qcheck.c) and, against a domain, no boundary node
 * lies off its polylines (farther than --dist-tol of its diameter), every
 * feature is a vertex, V - E + F equals the domain's outer loops minus its
 * holes, and the area error is within --volume-tol (default: half a layer
 * of cells along the polylines, 0.5 P h / A with h = sqrt(area / cells),
 * 5% at least, 25% at most). */

enum { Q_AREA_AUTO = 0 };

typedef struct {
  mx_qcheck_report c;
  mx_qquality q;
  const char *domain;   /* the polylines' file, or NULL */
  size_t unused_nodes;  /* informative, as in mesher2d: not a defect */
  size_t empty, topology_off, area_off, defects;
  double area_tol, dist_tol;
  int area_tol_auto;
} check2d;

static int has_ext(const char *path, const char *ext) {
  const size_t n = strlen(path), e = strlen(ext);
  return n > e && strcasecmp(path + n - e, ext) == 0;
}

/* The polylines of a 2D mesh's domain, read and checked. */
static int read_domain(const char *path, const char *mesh, mx_poly *P) {
  memset(P, 0, sizeof *P);
  if (!has_ext(path, ".poly") && !has_ext(path, ".off") && !has_ext(path, ".mdl")) {
    mx_error(path, 0, "check: a 3D surface, but %s is a 2D mesh: give its domain's polylines "
             "(--poly FILE: .poly, or a 2D .off or .mdl)", mesh);
    return MX_EINPUT;
  }
  int st = mx_read_poly_any(path, P);
  if (st == MX_EINPUT)
    mx_error(path, 0, "check: %s is a 2D mesh: its domain must be closed polylines in the "
             "plane z = 0 (.poly, or a 2D .off or .mdl)", mesh);
  if (st == MX_OK) st = mx_poly_check_domain(P);
  return st;
}

static int unused_nodes(const mx_qmesh *M, size_t *n) {
  uint8_t *used = mx_calloc(M->nnodes + 1);
  if (!used) return MX_ENOMEM;
#pragma omp parallel for schedule(static) if (M->ncells > 65536)
  for (size_t c = 0; c < M->ncells; c++)
    for (int j = 0; j < (M->type[c] == MX_QQUAD ? 4 : 3); j++) {
#pragma omp atomic write
      used[M->conn[4 * c + (size_t)j]] = 1;
    }
  size_t k = 0;
#pragma omp parallel for schedule(static) reduction(+ : k) if (M->nnodes > 65536)
  for (size_t i = 0; i < M->nnodes; i++) k += !used[i];
  mx_free(used);
  *n = k;
  return MX_OK;
}

/* The checks and the verdict. */
static int check_2d(const mx_qmesh *M, const mx_poly *P, const char *domain, double area_tol,
                    double dist_tol, check2d *k) {
  memset(k, 0, sizeof *k);
  k->domain = domain;
  k->dist_tol = dist_tol;
  mx_qquality_measure(M, &k->q);
  MX_CHECK(unused_nodes(M, &k->unused_nodes));
  MX_CHECK(mx_qmesh_check(M, P, dist_tol, &k->c));
  const mx_qcheck_report *c = &k->c;
  k->empty = M->ncells == 0 || M->nnodes == 0;
  k->defects = k->empty + c->bad_edges + c->hanging + c->inverted;
  if (!P) return MX_OK;
  k->area_tol = area_tol;
  if (area_tol == Q_AREA_AUTO) {
    k->area_tol = mx_qarea_tolerance(P, c, M->ncells);
    k->area_tol_auto = 1;
  }
  k->topology_off = c->euler != c->domain_euler;
  k->area_off = !(c->area_error <= k->area_tol);
  k->defects += c->off_boundary + c->missing_features + k->topology_off + k->area_off;
  return MX_OK;
}

/* The smallest and the mean scaled Jacobian over both cell types. */
static void sj_summary(const mx_qquality *q, double *mn, double *mean) {
  const size_t n = q->count[0] + q->count[1];
  *mn = fmin(q->count[0] ? q->min[0] : INFINITY, q->count[1] ? q->min[1] : INFINITY);
  *mean = n ? ((q->count[0] ? q->mean[0] * (double)q->count[0] : 0.0) +
               (q->count[1] ? q->mean[1] * (double)q->count[1] : 0.0)) / (double)n
            : NAN;
}

/* A domain counter, null without a domain. */
static void json_dcount(const check2d *k, const char *key, size_t v) {
  if (k->domain)
    printf("\"%s\":%zu,", key, v);
  else
    printf("\"%s\":null,", key);
}

static void print_json_2d(const mx_qmesh *M, const check2d *k) {
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

static void print_report_2d(const char *mesh, const mx_qmesh *M, const check2d *k,
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

/* `mixoct check` of a 2D mesh: q is freed here. */
static int main_2d(const char *mesh, mx_qmesh *q, const char *domain, double area_tol,
                   double dist_tol, int json, int quiet, double t0) {
  mx_poly P;
  memset(&P, 0, sizeof P);
  int st = domain ? read_domain(domain, mesh, &P) : MX_OK;
  const double t1 = mx_wtime();
  check2d k;
  if (st == MX_OK) st = check_2d(q, domain ? &P : NULL, domain, area_tol, dist_tol, &k);
  const double t2 = mx_wtime();
  mx_poly_free(&P);
  if (st == MX_OK) {
    if (json)
      print_json_2d(q, &k);
    else if (!quiet)
      print_report_2d(mesh, q, &k, t1 - t0, t2 - t1);
    fflush(stdout);
  }
  mx_qmesh_free(q);
  if (st != MX_OK) return st == MX_EINPUT ? EXIT_USAGE : 1;
  return k.defects ? EXIT_DEFECTS : 0;
}

/* A number option's value: finite and >= 0. */
static int number_arg(const char *opt, const char *v, double *out) {
  char *end;
  const double x = v ? strtod(v, &end) : NAN;
  if (!v || end == v || *end || !isfinite(x) || x < 0.0) {
    mx_error(NULL, 0, "check: %s needs a number >= 0%s%s%s", opt,
             v ? " (not '" : "", v ? v : "", v ? "')" : "");
    return MX_EINPUT;
  }
  *out = x;
  return MX_OK;
}

int mx_check_main(int argc, char **argv) {
  const char *mesh = NULL, *surf = NULL, *poly = NULL;
  int json = 0, quiet = 0;
  mx_check_options opt;
  mx_check_defaults(&opt);
  for (int i = 1; i < argc; i++) {
    const char *a = argv[i];
    if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
      usage(stdout);
      return 0;
    } else if (!strcmp(a, "--json")) {
      json = 1;
    } else if (!strcmp(a, "--quiet") || !strcmp(a, "-q")) {
      quiet = 1;
    } else if (!strcmp(a, "--surface")) {
      if (i + 1 >= argc) {
        mx_error(NULL, 0, "check: --surface needs a file");
        return EXIT_USAGE;
      }
      surf = argv[++i];
    } else if (!strncmp(a, "--surface=", 10)) {
      surf = a + 10;
    } else if (!strcmp(a, "--poly")) {
      if (i + 1 >= argc) {
        mx_error(NULL, 0, "check: --poly needs a file");
        return EXIT_USAGE;
      }
      poly = argv[++i];
    } else if (!strncmp(a, "--poly=", 7)) {
      poly = a + 7;
    } else if (!strcmp(a, "--volume-tol") || !strcmp(a, "--area-tol") ||
               !strcmp(a, "--dist-tol")) {
      double *dst = a[2] == 'd' ? &opt.boundary_tol : &opt.volume_tol;
      if (number_arg(a, i + 1 < argc ? argv[i + 1] : NULL, dst) != MX_OK)
        return EXIT_USAGE;
      i++;
    } else if (!strncmp(a, "--volume-tol=", 13)) {
      if (number_arg("--volume-tol", a + 13, &opt.volume_tol) != MX_OK)
        return EXIT_USAGE;
    } else if (!strncmp(a, "--area-tol=", 11)) {
      if (number_arg("--area-tol", a + 11, &opt.volume_tol) != MX_OK)
        return EXIT_USAGE;
    } else if (!strncmp(a, "--dist-tol=", 11)) {
      if (number_arg("--dist-tol", a + 11, &opt.boundary_tol) != MX_OK)
        return EXIT_USAGE;
    } else if (!strcmp(a, "--threads")) {
      char *end = NULL;
      const long n = i + 1 < argc ? strtol(argv[i + 1], &end, 10) : 0;
      if (i + 1 >= argc || end == argv[i + 1] || *end || n < 1 || n > 4096) {
        mx_error(NULL, 0, "check: --threads needs a whole number >= 1");
        return EXIT_USAGE;
      }
      omp_set_num_threads((int)n);
      i++;
    } else if (a[0] == '-' && a[1]) {
      mx_error(NULL, 0, "check: unknown option '%s'", a);
      usage(stderr);
      return EXIT_USAGE;
    } else if (!mesh) {
      mesh = a;
    } else {
      mx_error(NULL, 0, "check: more than one mesh given ('%s' and '%s')",
               mesh, a);
      return EXIT_USAGE;
    }
  }
  if (!mesh) {
    mx_error(NULL, 0, "check: no mesh file given");
    usage(stderr);
    return EXIT_USAGE;
  }
  if (poly && surf) {
    mx_error(NULL, 0, "check: --poly and --surface both given: one domain at most");
    return EXIT_USAGE;
  }
  if (quiet) mx_quiet = 1;
  const double t0 = mx_wtime();
  mx_mesh_data m;
  mx_qmesh q;
  mx_trisoup s;
  memset(&s, 0, sizeof s);
  int dim = 3;
  memset(&q, 0, sizeof q);
  int st = mx_read_mesh_dim(mesh, &m, &dim);
  if (st == MX_OK && dim == 2) {
    st = mx_qmesh_from_faces(&m, &q);
    mx_mesh_data_free(&m);
    if (st == MX_OK)
      return main_2d(mesh, &q, poly ? poly : surf, opt.volume_tol, opt.boundary_tol, json, quiet,
                     t0);
  }
  if (st == MX_OK && (poly || has_ext(surf ? surf : "", ".poly"))) {
    mx_error(poly ? poly : surf, 0, "check: polylines, but %s is a 3D mesh: give the closed "
             "surface it fills (--surface FILE: .off, .stl, .obj, .mdl, .ply)", mesh);
    mx_mesh_data_free(&m);
    return EXIT_USAGE;
  }
  if (st == MX_OK && surf) {
    st = mx_read_surface(surf, &s);
    if (st == MX_OK) st = mx_trisoup_check(&s, surf, NULL);
    /* inconsistently oriented triangles turned over (as the mesher does),
     * so that the enclosed volume is the surface's */
    mx_surface_defects sd;
    if (st == MX_OK && mx_surface_defects_find(&s, &sd) == MX_OK && sd.misoriented_edges &&
        !sd.boundary_edges && !sd.nonmanifold_edges) {
      size_t flipped = 0;
      st = mx_surface_orient(&s, &flipped);
    }
  }
  const double t1 = mx_wtime();
  mx_check_report r;
  mx_check_tags tags;
  memset(&tags, 0, sizeof tags);
  if (st == MX_OK)
    st = mx_check_mesh_tags(&m, surf ? &s : NULL, &opt, &r, &tags);
  const mx_mesh_view hv = mx_mesh_data_view(&m);
  const uint64_t hash = st == MX_OK ? mx_mesh_hash(&hv) : 0;
  const double t2 = mx_wtime();
  mx_mesh_data_free(&m);
  mx_trisoup_free(&s);
  if (st != MX_OK) {
    mx_check_tags_free(&tags);
    return st == MX_EINPUT ? EXIT_USAGE : 1;
  }
  if (json)
    print_json(&r, &tags, hash);
  else if (!quiet)
    print_report(mesh, surf, &r, &tags, hash, t1 - t0, t2 - t1);
  fflush(stdout);
  mx_check_tags_free(&tags);
  return r.defects ? EXIT_DEFECTS : 0;
}
