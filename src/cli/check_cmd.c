/* `mixoct check MESH [--surface FILE] [--json] [--quiet]`: reads a volume
 * mesh (legacy VTK or VTU) and, optionally, the surface it should fill, runs
 * the independent checker (kernels/check.h) and reports.
 *
 * Output: a readable report, or with --json one JSON object on the last
 * stdout line (non-finite numbers are null); --quiet prints nothing but
 * errors (and the JSON object when --json is given) and silences warnings.
 * Exit codes: 0 no defect, 3 defects found, 2 bad input or usage (the
 * message names the file), 1 internal failure. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "cli/cli.h"
#include "common.h"
#include "io/read_mesh.h"
#include "kernels/check.h"
#include "soa/trisoup.h"

enum { EXIT_DEFECTS = 3, EXIT_USAGE = 2 };

static void usage(FILE *f) {
  fprintf(f,
          "usage: mixoct check MESH [--surface FILE] [--json] [--quiet]\n"
          "  MESH            legacy VTK (.vtk, ASCII or binary) or VTU mesh\n"
          "  --surface FILE  the closed surface the mesh should fill (.off,\n"
          "                  .stl, .obj, .mdl): volume error and distance of\n"
          "                  the boundary nodes to it\n"
          "  --json          one JSON object on the last line of stdout\n"
          "  --quiet         no report (errors only; JSON if --json)\n"
          "exit: 0 no defect, 3 defects found, 2 bad input or usage\n");
}

static void json_num(const char *key, double v, int last) {
  if (isfinite(v))
    printf("\"%s\":%.17g%s", key, v, last ? "" : ",");
  else
    printf("\"%s\":null%s", key, last ? "" : ",");
}

static void print_json(const mx_check_report *r) {
  printf("{\"nodes\":%zu,\"elements\":%zu,", r->nodes, r->elements);
  printf("\"by_type\":{\"hex\":%zu,\"prism\":%zu,\"pyramid\":%zu,\"tet\":%zu},",
         r->by_type[MX_HEX], r->by_type[MX_PRISM], r->by_type[MX_PYRAMID],
         r->by_type[MX_TET]);
  printf("\"invalid\":%zu,", r->invalid);
  json_num("jens_min", r->jens_min, 0);
  json_num("jens_mean", r->jens_mean, 0);
  printf("\"faces_interior\":%zu,\"faces_boundary\":%zu,"
         "\"faces_overshared\":%zu,\"faces_misoriented\":%zu,"
         "\"quad_vs_triangles\":%zu,\"open_boundary_edges\":%zu,"
         "\"nonmanifold_edges\":%zu,"
         "\"hanging_nodes\":%zu,\"unused_nodes\":%zu,"
         "\"duplicate_nodes\":%zu,",
         r->faces_interior, r->faces_boundary, r->faces_overshared,
         r->faces_misoriented, r->quad_vs_triangles, r->open_boundary_edges,
         r->nonmanifold_edges, r->hanging_nodes, r->unused_nodes,
         r->duplicate_nodes);
  json_num("volume", r->volume, 0);
  json_num("surface_volume", r->surface_volume, 0);
  json_num("volume_error", r->volume_error, 0);
  json_num("boundary_max_dist", r->boundary_max_dist, 0);
  printf("\"defects\":%zu}\n", r->defects);
}

static void defect_line(const char *what, size_t n) {
  printf("    %-22s %zu%s\n", what, n, n ? "   <-- defect" : "");
}

static void print_report(const char *mesh, const char *surf,
                         const mx_check_report *r, double t_read,
                         double t_check) {
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
  if (surf) {
    printf("  surface                %s\n", surf);
    printf("  surface volume         %.15g\n", r->surface_volume);
    printf("  volume error           %.3e\n", r->volume_error);
    printf("  boundary max distance  %.3e of the surface's bounding box "
           "diagonal\n",
           r->boundary_max_dist);
  }
  printf("  non-manifold edges     %zu (parts of the domain touching along an "
         "edge; not a defect)\n", r->nonmanifold_edges);
  printf("  defects\n");
  defect_line("invalid elements", r->invalid);
  defect_line("overshared faces", r->faces_overshared);
  defect_line("misoriented faces", r->faces_misoriented);
  defect_line("quad vs triangles", r->quad_vs_triangles);
  defect_line("open boundary edges", r->open_boundary_edges);
  defect_line("hanging nodes", r->hanging_nodes);
  defect_line("unused nodes", r->unused_nodes);
  defect_line("duplicate nodes", r->duplicate_nodes);
  if (r->defects)
    printf("  result                 %zu defect%s\n", r->defects,
           r->defects == 1 ? "" : "s");
  else
    printf("  result                 OK, no defect\n");
  printf("  time                   read %.3f s, check %.3f s\n", t_read,
         t_check);
}

int mx_check_main(int argc, char **argv) {
  const char *mesh = NULL, *surf = NULL;
  int json = 0, quiet = 0;
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
  if (quiet) mx_quiet = 1;
  const double t0 = mx_wtime();
  mx_mesh_data m;
  mx_trisoup s;
  memset(&s, 0, sizeof s);
  int st = mx_read_mesh(mesh, &m);
  if (st == MX_OK && surf) {
    st = mx_read_surface(surf, &s);
    if (st == MX_OK) st = mx_trisoup_check(&s, surf, NULL);
  }
  const double t1 = mx_wtime();
  mx_check_report r;
  if (st == MX_OK) st = mx_check_mesh(&m, surf ? &s : NULL, &r);
  const double t2 = mx_wtime();
  mx_mesh_data_free(&m);
  mx_trisoup_free(&s);
  if (st != MX_OK) return st == MX_EINPUT ? EXIT_USAGE : 1;
  if (json)
    print_json(&r);
  else if (!quiet)
    print_report(mesh, surf, &r, t1 - t0, t2 - t1);
  fflush(stdout);
  return r.defects ? EXIT_DEFECTS : 0;
}
