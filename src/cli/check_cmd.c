/* `mixoct check MESH [--surface FILE ... | --poly FILE] [--volume-tol X]
 * [--dist-tol X] [--feature-angle DEG] [--features FILE] [--feature-tol T]
 * [--threads N] [--json] [--quiet]`: the options read into
 * mx_check_params (--surface repeated: one file per input of the run, the
 * list in surfaces; once: surface, as before), then mx_check_file (include/mixoct.h,
 * src/mesher/check_file.c) reads the mesh (3D, or 2D: triangles and
 * quadrilaterals at z = 0), runs the independent checker against the
 * surface or polylines when given, and prints the report, or with --json
 * one JSON object on the last stdout line; --quiet prints nothing but
 * errors (and the JSON object when --json is given) and silences warnings.
 * Exit codes: 0 no defect, 5 defects found (as the mesher's "breaks the
 * contract"), 2 bad input or usage (the message names the file), 1
 * internal failure. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "mixoct.h"

enum { EXIT_USAGE = 2 };

static void usage(FILE *f) {
  fprintf(f,
          "usage: mixoct check MESH [--surface FILE ... | --poly FILE] "
          "[--volume-tol X]\n"
          "                    [--dist-tol X] [--feature-angle DEG] [--features FILE]\n"
          "                    [--feature-tol T] [--threads N] [--json] [--quiet]\n"
          "  MESH              legacy VTK (.vtk, ASCII or binary, up to 5.1;\n"
          "                    triangles and quadrilaterals beside volume\n"
          "                    cells are boundary faces), VTU (ASCII, base64\n"
          "                    or raw; zlib, LZ4, LZMA or uncompressed),\n"
          "                    parallel VTU (.pvtu), Gmsh MSH 4.1 or 2.2\n"
          "                    (ASCII or binary), Medit (.mesh, .meshb),\n"
          "                    GetFEM (.getfem), M3D or MVM volume mesh\n"
          "                    (recognised by content); or a 2D mesh:\n"
          "                    triangles and quadrilaterals at z = 0 in VTK,\n"
          "                    VTU, MSH or OFF (as mesher2d writes them)\n"
          "  --surface FILE    the closed surface the mesh should fill (.off,\n"
          "                    .stl, .obj, .mdl, .ply): volume error and\n"
          "                    distance of the boundary nodes to it; for a\n"
          "                    2D mesh, its polylines as --poly. Repeated\n"
          "                    (at most %d): one file per input as the\n"
          "                    mesher was given them (-i A -i B, several\n"
          "                    materials: touching or nested inputs); the\n"
          "                    regions are each file's closed shells', the\n"
          "                    volume their union's, the triangles two files\n"
          "                    share interfaces, not boundary\n"
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
          "  --feature-angle DEG  sharp features of the surface: ridges where its\n"
          "                    normals part by more than DEG, corners where they\n"
          "                    end, meet or turn by more (default 30; 0: none);\n"
          "                    reported: the largest distance from a ridge to\n"
          "                    the mesh's boundary edges, from a corner to its\n"
          "                    nodes\n"
          "  --features FILE   the features as polylines instead ('n x1 y1 z1 ...\n"
          "                    xn yn zn' a line; corners at --feature-angle)\n"
          "  --feature-tol T   a feature distance above T (relative to the\n"
          "                    diagonal) is a defect (default: reported only)\n"
          "  --threads N       OpenMP threads (default: all)\n"
          "  --json            one JSON object on the last line of stdout\n"
          "  -q, --quiet       no report (errors only; JSON if --json)\n"
          "  -h, --help        this text\n"
          "  --list-options    every option, one a line (shell completion)\n"
          "exit: 0 no defect, 5 defects found, 2 bad input or usage\n",
          MX_MAX_INPUTS);
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

/* One more surface file: MX_OK, or MX_EINPUT beyond MX_MAX_INPUTS. */
static int add_surface(const char **list, int *n, const char *file) {
  if (*n == MX_MAX_INPUTS) {
    mx_error(NULL, 0, "check: at most %d surface files", MX_MAX_INPUTS);
    return MX_EINPUT;
  }
  list[(*n)++] = file;
  return MX_OK;
}

/* Every option of check (long names; -h and -q are --help's and --quiet's
 * short forms): the parser refuses any other, `--list-options` prints them
 * (tests/help_test.sh checks them against the usage text). */
static const char *const check_options[] = {
    "-h",           "--help",        "--list-options", "--json",       "-q",
    "--quiet",      "--surface",     "--poly",         "--volume-tol", "--area-tol",
    "--dist-tol",   "--feature-angle", "--feature-tol", "--features",  "--threads"};

static int is_check_option(const char *a) {
  const char *eq = strchr(a, '=');
  const size_t n = eq ? (size_t)(eq - a) : strlen(a);
  for (size_t k = 0; k < sizeof check_options / sizeof *check_options; k++)
    if (strlen(check_options[k]) == n && !strncmp(a, check_options[k], n)) return 1;
  return 0;
}

int mx_check_main(int argc, char **argv) {
  mx_check_params p;
  mx_check_params_default(&p);
  const char *surfaces[MX_MAX_INPUTS];
  int nsurfaces = 0;
  for (int i = 1; i < argc; i++) {
    const char *a = argv[i];
    if (a[0] == '-' && a[1] && !is_check_option(a)) {
      mx_error(NULL, 0, "check: unknown option '%s'", a);
      usage(stderr);
      return EXIT_USAGE;
    } else if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
      usage(stdout);
      return 0;
    } else if (!strcmp(a, "--list-options")) {
      for (size_t k = 0; k < sizeof check_options / sizeof *check_options; k++)
        printf("%s\n", check_options[k]);
      return 0;
    } else if (!strcmp(a, "--json")) {
      p.json = 1;
    } else if (!strcmp(a, "--quiet") || !strcmp(a, "-q")) {
      p.quiet = 1;
    } else if (!strcmp(a, "--surface")) {
      if (i + 1 >= argc) {
        mx_error(NULL, 0, "check: --surface needs a file");
        return EXIT_USAGE;
      }
      if (add_surface(surfaces, &nsurfaces, argv[++i]) != MX_OK) return EXIT_USAGE;
    } else if (!strncmp(a, "--surface=", 10)) {
      if (add_surface(surfaces, &nsurfaces, a + 10) != MX_OK) return EXIT_USAGE;
    } else if (!strcmp(a, "--poly")) {
      if (i + 1 >= argc) {
        mx_error(NULL, 0, "check: --poly needs a file");
        return EXIT_USAGE;
      }
      p.poly = argv[++i];
    } else if (!strncmp(a, "--poly=", 7)) {
      p.poly = a + 7;
    } else if (!strcmp(a, "--volume-tol") || !strcmp(a, "--area-tol") ||
               !strcmp(a, "--dist-tol")) {
      double *dst = a[2] == 'd' ? &p.dist_tol : &p.volume_tol;
      if (number_arg(a, i + 1 < argc ? argv[i + 1] : NULL, dst) != MX_OK)
        return EXIT_USAGE;
      i++;
    } else if (!strncmp(a, "--volume-tol=", 13)) {
      if (number_arg("--volume-tol", a + 13, &p.volume_tol) != MX_OK)
        return EXIT_USAGE;
    } else if (!strncmp(a, "--area-tol=", 11)) {
      if (number_arg("--area-tol", a + 11, &p.volume_tol) != MX_OK)
        return EXIT_USAGE;
    } else if (!strncmp(a, "--dist-tol=", 11)) {
      if (number_arg("--dist-tol", a + 11, &p.dist_tol) != MX_OK)
        return EXIT_USAGE;
    } else if (!strcmp(a, "--feature-angle") || !strcmp(a, "--feature-tol") ||
               !strncmp(a, "--feature-angle=", 16) || !strncmp(a, "--feature-tol=", 14)) {
      const int angle = !strncmp(a, "--feature-angle", 15);
      const char *eq = strchr(a, '=');
      const char *v = eq ? eq + 1 : i + 1 < argc ? argv[++i] : NULL;
      double x;
      if (number_arg(angle ? "--feature-angle" : "--feature-tol", v, &x) != MX_OK)
        return EXIT_USAGE;
      if (angle ? x >= 180.0 : x == 0.0) {
        mx_error(NULL, 0, "check: %s", angle ? "--feature-angle needs 0 to 180 degrees "
                 "(180 excluded; 0: no features)" : "--feature-tol needs a number > 0");
        return EXIT_USAGE;
      }
      *(angle ? &p.feature_angle : &p.feature_tol) = x;
    } else if (!strcmp(a, "--features")) {
      if (i + 1 >= argc) {
        mx_error(NULL, 0, "check: --features needs a file");
        return EXIT_USAGE;
      }
      p.features = argv[++i];
    } else if (!strncmp(a, "--features=", 11)) {
      p.features = a + 11;
    } else if (!strcmp(a, "--threads")) {
      char *end = NULL;
      const long n = i + 1 < argc ? strtol(argv[i + 1], &end, 10) : 0;
      if (i + 1 >= argc || end == argv[i + 1] || *end || n < 1 || n > 4096) {
        mx_error(NULL, 0, "check: --threads needs a whole number >= 1");
        return EXIT_USAGE;
      }
      p.threads = (int)n;
      i++;
    } else if (a[0] == '-' && a[1]) {
      mx_error(NULL, 0, "check: unknown option '%s'", a);
      usage(stderr);
      return EXIT_USAGE;
    } else if (!p.mesh) {
      p.mesh = a;
    } else {
      mx_error(NULL, 0, "check: more than one mesh given ('%s' and '%s')",
               p.mesh, a);
      return EXIT_USAGE;
    }
  }
  if (!p.mesh) {
    mx_error(NULL, 0, "check: no mesh file given");
    usage(stderr);
    return EXIT_USAGE;
  }
  if (nsurfaces == 1) { /* one file: as it always was */
    p.surface = surfaces[0];
  } else if (nsurfaces > 1) {
    p.surfaces = surfaces;
    p.nsurfaces = nsurfaces;
  }
  /* --poly with --surface is refused there */
  return mx_check_file(&p);
}
