/* mixoct invoked as `mesher2d` (a link installed beside mixoct): the 2D
 * mixed quadtree mesher of Jaillet & Lobos 2021 with the published 2D
 * program's flags and mixoct's conventions (exit codes, --json, files
 * written whole or not at all). A thin front over the library's 2D mesher
 * (include/mixoct.h, mx_mesher2d_*; src/mesher/mesher2d.c): options in,
 * library calls, the report out (mx_mesher2d_print_report,
 * src/mesher/mesher2d_report.c).
 *
 * The mesh is written only when the independent check passes (conforming,
 * no inverted cell, boundary on the polylines, features as vertices, area
 * within tolerance): exit 0 promises a valid mesh. Exit codes: 0 success,
 * 1 internal failure, 2 bad input or usage (messages name file and line),
 * 3 out of memory, 4 an output that cannot be written, 5 a mesh that fails
 * the check (not written). */
#include <math.h>
#include <omp.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "cli.h"
#include "mixoct.h"

#ifndef MX_VERSION
#define MX_VERSION "0.1.0"
#endif

static const char *usage2d =
    "usage: mesher2d -p in.poly [requests] [-u NAME -v|-x|-o|-g|-m] [-O FILE] [options]\n"
    "\n"
    "The 2D mixed quadtree mesher (quadrilaterals and triangles) of closed\n"
    "polylines, run by mixoct.\n"
    "\n"
    "Input:\n"
    "  -p FILE            the domain: .poly (Triangle's format), .off or .mdl\n"
    "  -d FILE.mdl        the same (the 3D program's flag)\n"
    "\n"
    "Refinement requests (a quadrant takes the largest level asked; levels 0\n"
    "to 27, each one halves the quadrant side):\n"
    "  -s RL              quadrants meeting the domain's polylines\n"
    "  -a RL              every quadrant of the domain\n"
    "  -b FILE.reg2       boxes: 'n_regions N', then per box\n"
    "                     'xmin ymin xmax ymax level'\n"
    "  -r FILE.poly RL    quadrants inside or crossing a closed region\n"
    "  -w FILE.poly RL    quadrants crossed by a drawing's segments (open or not)\n"
    "  -f NAME ARGS RL    quadrants crossed by a curve: circle cx cy r,\n"
    "                     line px py nx ny, sine amp freq phase y0 (y = y0 +\n"
    "                     amp sin(freq x + phase)); with a size field also a\n"
    "                     source of it: the side of level RL on the curve plus\n"
    "                     the distance to it\n"
    "  (-r, -w and -f are repeatable)\n"
    "      --size EXPR    a size field: quadrants are split while larger than\n"
    "                     the least size over them; EXPR of x and y (+ - * /\n"
    "                     ^, exp log sqrt abs sin cos min max, pi, e; e.g.\n"
    "                     \"0.02 + 0.2*x\") or one of the test functions F1..F5\n"
    "                     of Jurczyk & Glut 2016, taken at z = 0; with the\n"
    "                     other requests, the finest wins; the meshes carry\n"
    "                     the cell field target_size\n"
    "      --size-min H, --size-max H\n"
    "                     bounds on the field's sizes (--size-max alone: a\n"
    "                     field of that size everywhere)\n"
    "\n"
    "Several materials:\n"
    "      --materials    a loop nested in an outer one is the interface between\n"
    "                     two materials, not a hole: each cell gets the material\n"
    "                     of the region it lies in (1 inside the outer loops, 2\n"
    "                     inside one more loop, ...), the cells are cut along the\n"
    "                     interfaces; written as the cell field material (.vtu,\n"
    "                     .vtk), Gmsh physical surfaces with the interfaces as\n"
    "                     physical curves \"interface A | B\" (.msh), GetFEM\n"
    "                     regions 1000 + the material's number (.getfem)\n"
    "      --material ID[:NAME]\n"
    "                     the number (1..65535) and name of a material: the\n"
    "                     first --material the region at depth 1, the second at\n"
    "                     depth 2, ... (default: its depth, \"material ID\")\n"
    "\n"
    "Output (one mesh, one file per flag; none: a dry run that meshes and\n"
    "reports):\n"
    "  -u NAME            base name of the files of the flags below\n"
    "  -v                 NAME.vtk     legacy VTK\n"
    "  -x                 NAME.msh     Gmsh 4.1 (boundary edges as lines)\n"
    "  -o                 NAME.off     OFF (z = 0)\n"
    "  -g                 NAME.getfem  GetFEM\n"
    "  -m                 NAME.m3d     M3D\n"
    "  -O FILE            any of .vtu .vtk .msh .off .getfem .m3d (repeatable)\n"
    "  -q                 quality fields (always written: type, level, sj)\n"
    "      --binary       binary .vtk / .msh (ASCII by default, as the\n"
    "                     published program writes)\n"
    "      --ascii        ASCII .vtk / .msh (the default; after --binary:\n"
    "                     the last one given wins)\n"
    "\n"
    "Execution and report:\n"
    "      --threads N    OpenMP threads (the output does not depend on it)\n"
    "      --balance edges|recursive\n"
    "                     edge infos while refining (default), or the recursive\n"
    "                     neighbour search after it (same leaves)\n"
    "      --json         one JSON object as the last line of stdout\n"
    "      --quiet        no summary, no warnings\n"
    "      --keep-invalid write the mesh even when it fails the check (exit 5\n"
    "                     all the same)\n"
    "  -h, --help         this text\n"
    "      --version      the version\n"
    "\n"
    "Re-meshing (section 4.2 of the 2021 paper):\n"
    "  -c FILE.oct        start from the quadtree of this restart file (written\n"
    "                     as NAME.oct by every run with -u NAME)\n"
    "  -l FILE            split once each quadrant holding one of the elements\n"
    "                     listed (indices of the mesh written with the restart\n"
    "                     file), balance kept; with -c. One 0-based index per\n"
    "                     line (blanks, commas also separate; '#' comments;\n"
    "                     12.0 and 1.2e+01 are 12); another word is exit 2\n"
    "      --no-restart   do not write NAME.oct\n"
    "\n"
    "Exit codes: 0 a valid conforming mesh (written when asked), 1 internal\n"
    "failure, 2 bad input or usage, 3 out of memory, 4 output not writable,\n"
    "5 the mesh fails the check (not written).\n"
    "\n"
    "Examples:\n"
    "  mesher2d -p a.poly -s 8 -u a8 -v -x --json\n"
    "  mesher2d -p a.poly -s 4 --size \"0.004 + 0.1*abs(y + 0.5)\" -u a -v\n"
    "  mesher2d -p a.poly -c a8.oct -l bad.txt -u a8r -v\n";

enum { MAXREQ = 32, MAXOUT = 16, NFMT = 5 };
static const struct {
  const char *flag, *ext;
} formats[NFMT] = {{"-v", ".vtk"}, {"-x", ".msh"}, {"-o", ".off"}, {"-g", ".getfem"},
                   {"-m", ".m3d"}};

/* -f NAME ARGS RL */
typedef struct {
  const char *name;
  double a[4];
  size_t nargs;
  int level;
} m2_function;

typedef struct {
  const char *domain, *outname, *boxes_file, *restart_in, *list;
  int no_restart;
  int want[NFMT];
  const char *extra[MAXOUT];
  int nextra;
  int s_level, a_level;
  const char *region_path[MAXREQ], *drawing_path[MAXREQ];
  int region_level[MAXREQ], drawing_level[MAXREQ];
  int nregions, ndrawings;
  m2_function funs[MAXREQ];
  int nfuns;
  const char *size;           /* --size EXPR|F1..F5 (NULL: none) */
  double size_min, size_max;  /* --size-min, --size-max (0: none) */
  int threads, balance, json, quiet, ascii;
  int keep_invalid; /* write a mesh that fails the check (exit 5 all the same) */
  int materials;    /* --materials */
  int nmaterial;    /* --material ID[:NAME], by depth 1, 2, ... */
  int material_id[MAXREQ];
  const char *material_name[MAXREQ];
} m2_options;

typedef struct {
  mx_mesher2d *m;
  double total;
  const char *outputs[MAXOUT + NFMT];
  char *owned[NFMT + 1];
  const char *restart_out;
  int restart_written;
  long long bytes[MAXOUT + NFMT];
  int noutputs, nwritten;
  size_t listed;
  char error[1024];
  int nwarnings, quiet, status;
} m2_run;

/* ---- messages and signals ------------------------------------------------- */

static void on_message(void *user, int level, const char *text) {
  m2_run *r = user;
  if (level == MX_MSG_ERROR) {
    if (!r->error[0]) snprintf(r->error, sizeof r->error, "%s", text);
    fprintf(stderr, "mesher2d: error: %s\n", text);
    return;
  }
  r->nwarnings++;
  if (!r->quiet) fprintf(stderr, "mesher2d: warning: %s\n", text);
}

/* Ctrl-C or a time limit: no temporary output is left. */
static void on_signal(int sig) {
  mx_remove_temporaries();
  signal(sig, SIG_DFL);
  raise(sig);
}

/* ---- options --------------------------------------------------------------- */

static int usage_error(const char *fmt, const char *arg) {
  char msg[512];
  snprintf(msg, sizeof msg, fmt, arg ? arg : "");
  mx_error(NULL, 0, "%s (see mesher2d -h)", msg);
  return MX_EINPUT;
}

static int need(int i, int argc, int n, const char *opt) {
  if (i + n < argc) return MX_OK;
  return usage_error(n == 1 ? "%s needs an argument" : "%s needs more arguments", opt);
}

static int parse_level(const char *opt, const char *s, int *out) {
  char *end;
  const long v = strtol(s, &end, 10);
  if (*s == '\0' || *end || v < 0 || v > MX_MAX_LEVEL2D) {
    mx_error(NULL, 0, "%s wants a level between 0 and %d, got '%s'", opt, MX_MAX_LEVEL2D, s);
    return MX_EINPUT;
  }
  *out = (int)v;
  return MX_OK;
}

static int parse_real(const char *opt, const char *s, double *out) {
  char *end;
  *out = strtod(s, &end);
  if (*s == '\0' || *end || !isfinite(*out)) {
    mx_error(NULL, 0, "%s wants a number, got '%s'", opt, s);
    return MX_EINPUT;
  }
  return MX_OK;
}

/* -f NAME ARGS RL at argv[i]; advances *i past it. */
static int parse_fun(int argc, char **argv, int *i, m2_options *o) {
  MX_CHECK(need(*i, argc, 1, "-f"));
  const char *name = argv[++*i];
  const int nargs = mx_mesher2d_function_args(name);
  if (nargs < 0) return usage_error("-f wants circle, line or sine, got '%s'", name);
  if (o->nfuns == MAXREQ) return usage_error("too many -f functions", NULL);
  m2_function *f = &o->funs[o->nfuns++];
  memset(f, 0, sizeof *f);
  f->name = name;
  f->nargs = (size_t)nargs;
  MX_CHECK(need(*i, argc, nargs + 1, "-f"));
  for (int a = 0; a < nargs; a++) MX_CHECK(parse_real("-f", argv[++*i], &f->a[a]));
  if (!strcmp(name, "circle") && !(f->a[2] > 0))
    return usage_error("-f circle wants a positive radius, got '%s'", argv[*i]);
  if (!strcmp(name, "line") && f->a[2] == 0 && f->a[3] == 0)
    return usage_error("-f line wants a non-zero normal", NULL);
  return parse_level("-f", argv[++*i], &f->level);
}

/* -r / -w FILE RL. */
static int parse_poly_request(int argc, char **argv, int *i, const char **path, int *level,
                              int *n) {
  const char *opt = argv[*i];
  MX_CHECK(need(*i, argc, 2, opt));
  if (*n == MAXREQ) return usage_error("too many %s requests", opt);
  path[*n] = argv[++*i];
  MX_CHECK(parse_level(opt, argv[++*i], &level[*n]));
  ++*n;
  return MX_OK;
}

static int format_flag(const char *a) {
  for (int f = 0; f < NFMT; f++)
    if (!strcmp(a, formats[f].flag)) return f;
  return -1;
}

/* One argument at argv[*i] (and its values). */
static int parse_one(int argc, char **argv, int *i, m2_options *o, int *exit_now) {
  const char *a = argv[*i];
  if (!strcmp(a, "-h") || !strcmp(a, "--help")) {
    fputs(usage2d, stdout);
    *exit_now = 1;
  } else if (!strcmp(a, "--version")) {
    printf("mesher2d (mixoct %s)\n", MX_VERSION);
    *exit_now = 1;
  } else if (!strcmp(a, "-p") || !strcmp(a, "-d")) {
    MX_CHECK(need(*i, argc, 1, a));
    if (o->domain) return usage_error("one domain only (%s given twice)", a);
    o->domain = argv[++*i];
  } else if (!strcmp(a, "-s") || !strcmp(a, "-a")) {
    MX_CHECK(need(*i, argc, 1, a));
    MX_CHECK(parse_level(a, argv[++*i], a[1] == 's' ? &o->s_level : &o->a_level));
  } else if (!strcmp(a, "-b")) {
    MX_CHECK(need(*i, argc, 1, a));
    o->boxes_file = argv[++*i];
  } else if (!strcmp(a, "-r")) {
    MX_CHECK(parse_poly_request(argc, argv, i, o->region_path, o->region_level, &o->nregions));
  } else if (!strcmp(a, "-w")) {
    MX_CHECK(parse_poly_request(argc, argv, i, o->drawing_path, o->drawing_level, &o->ndrawings));
  } else if (!strcmp(a, "-f")) {
    MX_CHECK(parse_fun(argc, argv, i, o));
  } else if (!strcmp(a, "--size")) {
    MX_CHECK(need(*i, argc, 1, a));
    o->size = argv[++*i];
  } else if (!strcmp(a, "--size-min") || !strcmp(a, "--size-max")) {
    MX_CHECK(need(*i, argc, 1, a));
    double *bound = strcmp(a, "--size-min") ? &o->size_max : &o->size_min;
    MX_CHECK(mx_parse_size_bound(a, argv[++*i], bound));
  } else if (!strcmp(a, "-u")) {
    MX_CHECK(need(*i, argc, 1, a));
    o->outname = argv[++*i];
    if (!*o->outname) return usage_error("-u wants a non-empty name", NULL);
  } else if (format_flag(a) >= 0) {
    o->want[format_flag(a)] = 1;
  } else if (!strcmp(a, "-O")) {
    MX_CHECK(need(*i, argc, 1, a));
    if (o->nextra == MAXOUT) return usage_error("too many -O outputs", NULL);
    o->extra[o->nextra++] = argv[++*i];
  } else if (!strcmp(a, "-c") || !strcmp(a, "-l")) {
    MX_CHECK(need(*i, argc, 1, a));
    const char **slot = a[1] == 'c' ? &o->restart_in : &o->list;
    if (*slot) return usage_error("%s given twice", a);
    *slot = argv[++*i];
  } else if (!strcmp(a, "--no-restart")) {
    o->no_restart = 1;
  } else if (!strcmp(a, "--threads")) {
    MX_CHECK(need(*i, argc, 1, a));
    char *end;
    const long v = strtol(argv[++*i], &end, 10);
    if (*end || v < 1 || v > 4096)
      return usage_error("--threads wants a positive count, got '%s'", argv[*i]);
    o->threads = (int)v;
  } else if (!strcmp(a, "--balance")) {
    MX_CHECK(need(*i, argc, 1, a));
    const char *s = argv[++*i];
    if (strcmp(s, "edges") && strcmp(s, "recursive"))
      return usage_error("--balance wants edges or recursive, got '%s'", s);
    o->balance = strcmp(s, "edges") ? MX_BALANCE_RECURSIVE : MX_BALANCE_EDGES;
  } else if (!strcmp(a, "--json")) {
    o->json = 1;
  } else if (!strcmp(a, "--quiet")) {
    o->quiet = 1;
  } else if (!strcmp(a, "--materials")) {
    o->materials = 1;
  } else if (!strcmp(a, "--material")) {
    MX_CHECK(need(*i, argc, 1, a));
    const char *spec = argv[++*i];
    char *end;
    const long id = strtol(spec, &end, 10);
    if (end == spec || id < 1 || id > 65535 || (*end && *end != ':'))
      return usage_error("--material %s: expected ID[:NAME], ID from 1 to 65535", spec);
    if (o->nmaterial == MAXREQ) return usage_error("too many --material", NULL);
    o->material_id[o->nmaterial] = (int)id;
    o->material_name[o->nmaterial++] = *end == ':' && end[1] ? end + 1 : NULL;
  } else if (!strcmp(a, "--keep-invalid")) {
    o->keep_invalid = 1;
  } else if (!strcmp(a, "--binary")) {
    o->ascii = 0;
  } else if (!strcmp(a, "--ascii")) {
    o->ascii = 1;
  } else if (strcmp(a, "-q") != 0) {
    return usage_error("unknown option '%s'", a);
  }
  return MX_OK;
}

/* The whole command line, then what it must hold. */
static int parse_options(int argc, char **argv, m2_options *o, int *exit_now) {
  memset(o, 0, sizeof *o);
  o->ascii = 1;
  o->balance = MX_BALANCE_EDGES;
  *exit_now = 0;
  for (int i = 1; i < argc; i++) { /* known even when the line is refused */
    o->json |= !strcmp(argv[i], "--json");
    o->quiet |= !strcmp(argv[i], "--quiet");
  }
  for (int i = 1; i < argc && !*exit_now; i++) MX_CHECK(parse_one(argc, argv, &i, o, exit_now));
  if (*exit_now) return MX_OK;
  if (!o->domain) return usage_error("no input: give the domain with -p FILE.poly", NULL);
  int nfmt = 0;
  for (int f = 0; f < NFMT; f++) nfmt += o->want[f];
  if (nfmt && !o->outname)
    return usage_error("-v, -x, -o, -g and -m need the output name: add -u NAME", NULL);
  if (!nfmt && o->outname)
    return usage_error("-u %s names no format: add -v, -x, -o, -g and/or -m", o->outname);
  if (o->nmaterial && !o->materials)
    return usage_error("--material: only with --materials (several materials)", NULL);
  if (o->list && !o->restart_in)
    return usage_error("-l lists elements of the mesh of a restart file: add -c FILE.oct", NULL);
  if (!o->restart_in && !o->s_level && !o->a_level && !o->boxes_file && !o->nregions &&
      !o->ndrawings && !o->nfuns && !o->size && !(o->size_max > 0.0))
    return usage_error("no refinement request: the mesh would be one quadrant; give -s RL, "
                       "-a RL, -b FILE, -r FILE RL, -w FILE RL, -f NAME ARGS RL or --size "
                       "EXPR%s", NULL);
  return MX_OK;
}

static int outputs_spare_inputs(const m2_options *o, const m2_run *r);

/* NAME.ext for each format flag, then the -O files; each checked (known
 * format, writable directory) before anything is read. */
static int output_list(const m2_options *o, m2_run *r) {
  for (int f = 0; f < NFMT; f++) {
    if (!o->want[f]) continue;
    const size_t len = strlen(o->outname) + strlen(formats[f].ext) + 1;
    r->owned[f] = mx_alloc(len);
    if (!r->owned[f]) return MX_ENOMEM;
    snprintf(r->owned[f], len, "%s%s", o->outname, formats[f].ext);
    r->outputs[r->noutputs++] = r->owned[f];
  }
  for (int k = 0; k < o->nextra; k++) r->outputs[r->noutputs++] = o->extra[k];
  if (o->outname && !o->no_restart) { /* NAME.oct, as the published program */
    const size_t len = strlen(o->outname) + 5;
    r->owned[NFMT] = mx_alloc(len);
    if (!r->owned[NFMT]) return MX_ENOMEM;
    snprintf(r->owned[NFMT], len, "%s.oct", o->outname);
    r->restart_out = r->owned[NFMT];
    MX_CHECK(mx_check_output_path(r->restart_out, 0));
  }
  for (int k = 0; k < r->noutputs; k++) {
    if (!mx_plane_format_known(r->outputs[k])) {
      mx_error(r->outputs[k], 0, "unknown 2D output format (use .vtu, .vtk, .msh, .off, "
                                 ".getfem or .m3d)");
      return MX_EINPUT;
    }
    MX_CHECK(mx_check_output_path(r->outputs[k], 0));
  }
  return outputs_spare_inputs(o, r);
}

/* No output may replace an input (-u a -o with -p a.off) or another
 * output; the restart file written may replace the one read (read whole
 * before, written under a temporary name: the re-meshing loop of the
 * paper). Refused before anything is read or written. */
static int outputs_spare_inputs(const m2_options *o, const m2_run *r) {
  mx_file_use u[MAXOUT + NFMT + 2 * MAXREQ + 6];
  int n = 0;
  u[n++] = (mx_file_use){o->domain, "the domain", MX_FILE_INPUT};
  u[n++] = (mx_file_use){o->boxes_file, "the boxes file", MX_FILE_INPUT};
  u[n++] = (mx_file_use){o->list, "the element list", MX_FILE_INPUT};
  u[n++] = (mx_file_use){o->restart_in, "the restart file read", MX_FILE_RESTART_IN};
  for (int i = 0; i < o->nregions; i++)
    u[n++] = (mx_file_use){o->region_path[i], "the region", MX_FILE_INPUT};
  for (int i = 0; i < o->ndrawings; i++)
    u[n++] = (mx_file_use){o->drawing_path[i], "the drawing", MX_FILE_INPUT};
  for (int k = 0; k < r->noutputs; k++)
    u[n++] = (mx_file_use){r->outputs[k], "the mesh output", MX_FILE_OUTPUT};
  u[n++] = (mx_file_use){r->restart_out, "the restart file written", MX_FILE_RESTART_OUT};
  return mx_check_file_uses(u, n);
}

/* ---- the pipeline, as library calls (src/mesher/mesher2d.c) ------------------ */

static int add_requests(const m2_options *o, mx_mesher2d *m) {
  MX_CHECK(mx_mesher2d_set_levels(m, o->s_level, o->a_level));
  if (o->boxes_file) MX_CHECK(mx_mesher2d_read_boxes(m, o->boxes_file));
  for (int k = 0; k < o->nregions; k++)
    MX_CHECK(mx_mesher2d_add_region(m, o->region_path[k], o->region_level[k]));
  for (int k = 0; k < o->ndrawings; k++)
    MX_CHECK(mx_mesher2d_add_drawing(m, o->drawing_path[k], o->drawing_level[k]));
  for (int k = 0; k < o->nfuns; k++)
    MX_CHECK(mx_mesher2d_add_function(m, o->funs[k].name, o->funs[k].a, o->funs[k].nargs,
                                      o->funs[k].level));
  if (o->size) MX_CHECK(mx_mesher2d_set_size_expr(m, o->size));
  if (o->size_min > 0.0 || o->size_max > 0.0)
    MX_CHECK(mx_mesher2d_set_size_limits(m, o->size_min, o->size_max));
  return MX_OK;
}

/* -c FILE [-l LIST]: the quadtree of the restart file, the listed elements'
 * quadrants split once (Algorithm 3), the requests on top. */
static int remesh(const m2_options *o, mx_mesher2d *m, m2_run *r) {
  MX_CHECK(mx_mesher2d_load_restart(m, o->restart_in));
  if (!o->list) return mx_mesher2d_mesh(m);
  uint64_t *list = NULL;
  size_t n = 0;
  int st = mx_read_element_list(o->list, mx_mesher2d_restart_elements(m), &list, &n);
  if (!st) {
    r->listed = n;
    st = mx_mesher2d_refine_elements(m, list, n);
  }
  mx_free_array(list);
  return st;
}

static int write_outputs(const m2_options *o, m2_run *r) {
  for (int k = 0; k < r->noutputs; k++) {
    MX_CHECK(mx_mesher2d_write(r->m, r->outputs[k], o->ascii));
    struct stat st;
    r->bytes[k] = stat(r->outputs[k], &st) == 0 ? (long long)st.st_size : -1;
    r->nwritten = k + 1;
  }
  if (r->restart_out) {
    MX_CHECK(mx_mesher2d_save_restart(r->m, r->restart_out));
    r->restart_written = 1;
  }
  return MX_OK;
}

static int pipeline(const m2_options *o, m2_run *r) {
  mx_params2d p;
  mx_params2d_default(&p);
  p.balance = o->balance;
  p.threads = o->threads;
  p.materials = o->materials;
  mx_mesher2d *m = r->m = mx_mesher2d_new(&p);
  if (!m) return MX_ENOMEM;
  mx_mesher2d_set_message_handler(m, on_message, r);
  int st = MX_OK;
  for (int k = 0; k < o->nmaterial && !st; k++)
    st = mx_mesher2d_set_material(m, k + 1, o->material_id[k], o->material_name[k]);
  if (!st) st = mx_mesher2d_set_domain(m, o->domain);
  if (!st) st = add_requests(o, m);
  if (!st) st = o->restart_in ? remesh(o, m, r) : mx_mesher2d_mesh(m);
  /* --keep-invalid writes a mesh that fails the check: MX_EINVALID with a
   * mesh kept (the check is the only stage that returns it after making
   * the mesh; the boundary stage returns it without one). */
  mx_mesh2d_arrays a;
  if (!st || (st == MX_EINVALID && o->keep_invalid && mx_mesher2d_mesh_arrays(m, &a) == MX_OK)) {
    const int wst = write_outputs(o, r);
    if (wst) st = wst;
  }
  return st;
}

/* ---- the report (the library's: src/mesher/mesher2d_report.c) --------------- */

static void print_report(const m2_options *o, const m2_run *r) {
  const mx_run2d_info ri = {.domain = o->domain,
                            .status = r->status,
                            .error = r->error,
                            .nwarnings = r->nwarnings,
                            .noutputs = r->noutputs,
                            .nwritten = r->nwritten,
                            .outputs = r->outputs,
                            .bytes = r->bytes,
                            .restart = r->restart_written ? r->restart_out : NULL,
                            .listed = r->listed,
                            .total = r->total};
  mx_mesher2d_print_report(r->m, &ri, o->json);
}

int mx_mesher2d_main(int argc, char **argv) {
  m2_run run = {0}, *r = &run;
  mx_set_thread_message_handler(on_message, r);
  m2_options o;
  int exit_now = 0;
  const double t0 = mx_wtime();
  int st = parse_options(argc, argv, &o, &exit_now);
  if (exit_now && !st) return 0;
  r->quiet = o.quiet;
  mx_set_thread_quiet(o.quiet);
  if (!st) st = output_list(&o, r);
  if (!st) {
    if (o.threads > 0) omp_set_num_threads(o.threads);
    signal(SIGINT, on_signal);
    signal(SIGTERM, on_signal);
    signal(SIGHUP, on_signal);
    st = pipeline(&o, r);
  }
  r->status = st;
  r->total = mx_wtime() - t0;
  if (o.json || !o.quiet) print_report(&o, r);
  mx_mesher2d_free(r->m);
  for (int f = 0; f <= NFMT; f++) mx_free(r->owned[f]);
  mx_set_thread_message_handler(NULL, NULL); /* r lives no longer */
  return st;
}
