/* mixoct invoked as `mesher2d` (a link installed beside mixoct): the 2D
 * mixed quadtree mesher of Jaillet & Lobos 2021 (src/quad/quad.h) with the
 * published 2D program's flags and mixoct's conventions (exit codes, --json,
 * files written whole or not at all).
 *
 *   read -> mx_poly_check_domain -> mx_poly_index_build -> mx_qtree_build
 *   -> mx_qtree_leaves -> mx_qtransition -> mx_qboundary (0.3)
 *   -> mx_qquality_measure -> mx_qmesh_check -> writers
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
#include <strings.h>
#include <sys/stat.h>

#include "cli/cli.h"
#include "common.h"
#include "io/atomic_file.h"
#include "io/text_scan.h"
#include "quad/quad.h"

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
    "to 19, each one halves the quadrant side):\n"
    "  -s RL              quadrants meeting the domain's polylines\n"
    "  -a RL              every quadrant of the domain\n"
    "  -b FILE.reg2       boxes: 'n_regions N', then per box\n"
    "                     'xmin ymin xmax ymax level'\n"
    "  -r FILE.poly RL    quadrants inside or crossing a closed region\n"
    "  -w FILE.poly RL    quadrants crossed by a drawing's segments (open or not)\n"
    "  -f NAME ARGS RL    quadrants crossed by a curve: circle cx cy r,\n"
    "                     line px py nx ny, sine amp freq phase y0 (y = y0 +\n"
    "                     amp sin(freq x + phase))\n"
    "  (-r, -w and -f are repeatable)\n"
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
    "  -c FILE, -l FILE   re-meshing: not yet supported in 2D (exit 2)\n"
    "\n"
    "Exit codes: 0 a valid conforming mesh (written when asked), 1 internal\n"
    "failure, 2 bad input or usage, 3 out of memory, 4 output not writable,\n"
    "5 the mesh fails the check (not written).\n"
    "\n"
    "Example:\n"
    "  mesher2d -p a.poly -s 8 -u a8 -v -x --json\n";

enum { MAXREQ = 32, MAXOUT = 16, NFMT = 5 };
static const struct {
  const char *flag, *ext;
} formats[NFMT] = {{"-v", ".vtk"}, {"-x", ".msh"}, {"-o", ".off"}, {"-g", ".getfem"},
                   {"-m", ".m3d"}};

/* The check's tolerances: boundary nodes within CHECK_TOL of the domain's
 * diameter from the polylines; the area within half a layer of cells along
 * the boundary, AREA_TOL at least (as the 3D volume check). */
#define CHECK_TOL 1e-6
#define AREA_TOL 0.05
#define AREA_TOL_MAX 0.25 /* beyond: the domain is not represented at all */

typedef struct {
  const char *domain, *outname, *boxes_file;
  int want[NFMT];
  const char *extra[MAXOUT];
  int nextra;
  int s_level, a_level;
  const char *region_path[MAXREQ], *drawing_path[MAXREQ];
  int region_level[MAXREQ], drawing_level[MAXREQ];
  int nregions, ndrawings;
  mx_qfun funs[MAXREQ];
  int nfuns;
  int threads, balance, json, quiet, ascii;
  int keep_invalid; /* write a mesh that fails the check (exit 5 all the same) */
} m2_options;

enum { PH_READ, PH_REFINE, PH_BALANCE, PH_TRANSITION, PH_BOUNDARY, PH_QUALITY, PH_CHECK,
       PH_WRITE, NPH };
static const char *const phase_name[NPH] = {"read",     "refine",  "balance", "transition",
                                            "boundary", "quality", "check",   "write"};

typedef struct {
  mx_poly domain, regions[MAXREQ], drawings[MAXREQ];
  mx_poly_index index;
  mx_qbox *boxes;
  size_t nboxes;
  mx_qtree T;
  mx_qstats qs;
  uint32_t *leaves;
  size_t nleaves;
  mx_qmesh M;
  mx_qboundary_stats bs;
  mx_qquality q;
  mx_qcheck_report cr;
  double area_tol;
  int meshed, checked; /* how far it got */
  double t[NPH], total;
  const char *outputs[MAXOUT + NFMT];
  char *owned[NFMT];
  long long bytes[MAXOUT + NFMT];
  int noutputs, nwritten;
  char error[1024];
  int nwarnings, quiet, status;
} m2_run;

static m2_run run2;

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
  mx_afile_remove_temporaries();
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
  if (*s == '\0' || *end || v < 0 || v > MX_QMAX_LEVEL - 1) {
    mx_error(NULL, 0, "%s wants a level between 0 and %d, got '%s'", opt, MX_QMAX_LEVEL - 1, s);
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
  static const struct {
    const char *name;
    int kind, nargs;
  } kinds[3] = {{"circle", MX_QFUN_CIRCLE, 3}, {"line", MX_QFUN_LINE, 4},
                {"sine", MX_QFUN_SINE, 4}};
  MX_CHECK(need(*i, argc, 1, "-f"));
  const char *name = argv[++*i];
  int k = 0;
  while (k < 3 && strcmp(name, kinds[k].name) != 0) k++;
  if (k == 3) return usage_error("-f wants circle, line or sine, got '%s'", name);
  if (o->nfuns == MAXREQ) return usage_error("too many -f functions", NULL);
  mx_qfun *f = &o->funs[o->nfuns++];
  memset(f, 0, sizeof *f);
  f->kind = kinds[k].kind;
  MX_CHECK(need(*i, argc, kinds[k].nargs + 1, "-f"));
  for (int a = 0; a < kinds[k].nargs; a++) MX_CHECK(parse_real("-f", argv[++*i], &f->a[a]));
  if (f->kind == MX_QFUN_CIRCLE && !(f->a[2] > 0))
    return usage_error("-f circle wants a positive radius, got '%s'", argv[*i]);
  if (f->kind == MX_QFUN_LINE && f->a[2] == 0 && f->a[3] == 0)
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
    mx_error(NULL, 0, "%s: re-meshing from a restart file is not yet supported in 2D", a);
    return MX_EINPUT;
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
    o->balance = strcmp(s, "edges") ? MX_QBALANCE_RECURSIVE : MX_QBALANCE_EDGES;
  } else if (!strcmp(a, "--json")) {
    o->json = 1;
  } else if (!strcmp(a, "--quiet")) {
    o->quiet = 1;
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
  o->balance = MX_QBALANCE_EDGES;
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
  if (!o->s_level && !o->a_level && !o->boxes_file && !o->nregions && !o->ndrawings && !o->nfuns)
    return usage_error("no refinement request: the mesh would be one quadrant; give -s RL, "
                       "-a RL, -b FILE, -r FILE RL, -w FILE RL or -f NAME ARGS RL%s", NULL);
  return MX_OK;
}

static int outputs_spare_inputs(const m2_options *o, const m2_run *r);

/* NAME.ext for each format flag, then the -O files; each checked (known
 * format, writable directory) before anything is read. */
static int output_list(const m2_options *o, m2_run *r) {
  for (int f = 0; f < NFMT; f++) {
    if (!o->want[f]) continue;
    const size_t len = strlen(o->outname) + strlen(formats[f].ext) + 1;
    r->owned[f] = malloc(len);
    if (!r->owned[f]) return MX_ENOMEM;
    snprintf(r->owned[f], len, "%s%s", o->outname, formats[f].ext);
    r->outputs[r->noutputs++] = r->owned[f];
  }
  for (int k = 0; k < o->nextra; k++) r->outputs[r->noutputs++] = o->extra[k];
  for (int k = 0; k < r->noutputs; k++) {
    if (!mx_qmesh_format_known(r->outputs[k])) {
      mx_error(r->outputs[k], 0, "unknown 2D output format (use .vtu, .vtk, .msh, .off, "
                                 ".getfem or .m3d)");
      return MX_EINPUT;
    }
    MX_CHECK(mx_check_output_path(r->outputs[k], 0));
  }
  return outputs_spare_inputs(o, r);
}

/* An output that is one of the inputs (-u a -o with -p a.off) would be
 * replaced by the mesh: refused before anything is written. */
static int same_file(const char *a, const char *b) {
  struct stat sa, sb;
  return a && b && stat(a, &sa) == 0 && stat(b, &sb) == 0 && sa.st_dev == sb.st_dev &&
         sa.st_ino == sb.st_ino;
}

static int outputs_spare_inputs(const m2_options *o, const m2_run *r) {
  for (int k = 0; k < r->noutputs; k++) {
    int clash = same_file(r->outputs[k], o->domain) || same_file(r->outputs[k], o->boxes_file);
    for (int i = 0; i < o->nregions; i++) clash |= same_file(r->outputs[k], o->region_path[i]);
    for (int i = 0; i < o->ndrawings; i++) clash |= same_file(r->outputs[k], o->drawing_path[i]);
    if (clash) {
      mx_error(r->outputs[k], 0, "the output would replace an input file: choose another name");
      return MX_EINPUT;
    }
  }
  return MX_OK;
}

/* ---- the boxes file (.reg2) ----------------------------------------------- */

typedef struct {
  const char *path, *p, *end;
  long line;
} scan;

static int scan_token(scan *s, const char *what, size_t box) {
  s->p = mx_io_content(s->p, s->end, &s->line, '#');
  if (s->p < s->end) return MX_OK;
  mx_error(s->path, s->line, "unexpected end of file: box %zu has no %s (truncated file or "
                             "wrong n_regions)", box + 1, what);
  return MX_EINPUT;
}

static int scan_number(scan *s, const char *what, size_t box, double *v) {
  MX_CHECK(scan_token(s, what, box));
  const char *e = mx_io_double(s->p, v);
  if (!e || !mx_io_delim(e, '#') || !isfinite(*v)) {
    mx_error(s->path, s->line, "box %zu: %s: '%.*s' is not a finite number", box + 1, what,
             mx_io_toklen(s->p, '#'), s->p);
    return MX_EINPUT;
  }
  s->p = e;
  return MX_OK;
}

static int read_box(scan *s, size_t i, mx_qbox *b) {
  static const char *what[5] = {"xmin", "ymin", "xmax", "ymax", "level"};
  double v[5];
  for (int k = 0; k < 5; k++) MX_CHECK(scan_number(s, what[k], i, &v[k]));
  if (v[0] > v[2] || v[1] > v[3]) {
    mx_error(s->path, s->line, "box %zu: min corner above max corner", i + 1);
    return MX_EINPUT;
  }
  if (v[4] != floor(v[4]) || v[4] < 0 || v[4] > MX_QMAX_LEVEL - 1) {
    mx_error(s->path, s->line, "box %zu: level %g is not an integer between 0 and %d", i + 1,
             v[4], MX_QMAX_LEVEL - 1);
    return MX_EINPUT;
  }
  *b = (mx_qbox){{v[0], v[1]}, {v[2], v[3]}, (int)v[4]};
  return MX_OK;
}

static int parse_boxes(scan *s, mx_qbox **boxes, size_t *n) {
  s->p = mx_io_content(s->p, s->end, &s->line, '#');
  const int tl = s->p < s->end ? mx_io_toklen(s->p, '#') : 0;
  if (tl != 9 || strncasecmp(s->p, "n_regions", 9) != 0) {
    mx_error(s->path, s->line, "expected 'n_regions N', found '%.*s'", tl, s->p);
    return MX_EINPUT;
  }
  s->p = mx_io_content(s->p + 9, s->end, &s->line, '#');
  int64_t count;
  const char *e = s->p < s->end ? mx_io_int(s->p, &count) : NULL;
  /* a box takes at least 10 bytes: a bogus count allocates nothing */
  if (!e || !mx_io_delim(e, '#') || count < 0 || count > (s->end - s->p) / 10 + 1) {
    mx_error(s->path, s->line, "expected a box count after 'n_regions'");
    return MX_EINPUT;
  }
  s->p = e;
  *boxes = mx_alloc(((size_t)count + 1) * sizeof **boxes);
  if (!*boxes) return MX_ENOMEM;
  *n = (size_t)count;
  for (size_t i = 0; i < *n; i++) MX_CHECK(read_box(s, i, &(*boxes)[i]));
  s->p = mx_io_content(s->p, s->end, &s->line, '#');
  if (s->p == s->end) return MX_OK;
  mx_error(s->path, s->line, "more data than the %zu boxes declared by n_regions: '%.*s'", *n,
           mx_io_toklen(s->p, '#'), s->p);
  return MX_EINPUT;
}

static int read_boxes(const char *path, mx_qbox **boxes, size_t *n) {
  char *buf;
  size_t len;
  *boxes = NULL;
  *n = 0;
  MX_CHECK(mx_io_load(path, &buf, &len));
  scan s = {path, buf, buf + len, 1};
  const int st = parse_boxes(&s, boxes, n);
  mx_free(buf);
  return st;
}

/* ---- the pipeline ----------------------------------------------------------- */

static int read_inputs(const m2_options *o, m2_run *r) {
  if (o->boxes_file) MX_CHECK(read_boxes(o->boxes_file, &r->boxes, &r->nboxes));
  MX_CHECK(mx_read_poly_any(o->domain, &r->domain));
  MX_CHECK(mx_poly_check_domain(&r->domain));
  MX_CHECK(mx_poly_index_build(&r->domain, &r->index));
  for (int k = 0; k < o->nregions; k++) {
    MX_CHECK(mx_read_poly_any(o->region_path[k], &r->regions[k]));
    MX_CHECK(mx_poly_check_domain(&r->regions[k])); /* closed, oriented */
  }
  for (int k = 0; k < o->ndrawings; k++)
    MX_CHECK(mx_read_poly_any(o->drawing_path[k], &r->drawings[k]));
  return MX_OK;
}

/* A status from a stage that gave no message of its own. */
static int stage_status(int st, const char *stage, const m2_run *r) {
  if (st == MX_EINTERNAL && !r->error[0])
    mx_error(NULL, 0, "internal failure in the %s stage", stage);
  return st;
}

static int mesh_domain(const m2_options *o, m2_run *r) {
  const mx_qrequests req = {o->s_level, o->a_level, r->nboxes, r->boxes,
                            (size_t)o->nregions, r->regions, o->region_level,
                            (size_t)o->ndrawings, r->drawings, o->drawing_level,
                            (size_t)o->nfuns, o->funs};
  double t = mx_wtime();
  int st = mx_qtree_build(&r->domain, &r->index, &req, o->balance, &r->T, &r->qs);
  if (!st) st = mx_qtree_leaves(&r->T, &r->leaves, &r->nleaves);
  const double wall = mx_wtime() - t;
  /* the builder's own split of its time, when it gives one */
  r->t[PH_BALANCE] = r->qs.t_balance;
  r->t[PH_REFINE] = r->qs.t_refine > 0 ? wall - r->qs.t_balance : wall;
  MX_CHECK(stage_status(st, "refine", r));
  t = mx_wtime();
  st = mx_qtransition(&r->T, r->leaves, r->nleaves, &r->M);
  r->t[PH_TRANSITION] = mx_wtime() - t;
  MX_CHECK(stage_status(st, "transition", r));
  t = mx_wtime();
  st = mx_qboundary(&r->domain, &r->index, &r->T, r->leaves, 0.3, &r->M, &r->bs);
  r->t[PH_BOUNDARY] = mx_wtime() - t;
  MX_CHECK(stage_status(st, "boundary", r));
  r->meshed = 1;
  t = mx_wtime();
  mx_qquality_measure(&r->M, &r->q);
  r->t[PH_QUALITY] = mx_wtime() - t;
  return MX_OK;
}

static double perimeter(const mx_poly *P) {
  double l = 0.0;
  for (size_t s = 0; s < P->ns; s++) {
    const double *a = P->xy + 2 * (size_t)P->seg[2 * s], *b = P->xy + 2 * (size_t)P->seg[2 * s + 1];
    l += hypot(b[0] - a[0], b[1] - a[1]);
  }
  return l;
}

/* The independent check; MX_EINVALID naming what failed. */
static int check_mesh(m2_run *r) {
  const char *name = r->domain.path ? r->domain.path : NULL;
  if (r->M.ncells == 0) {
    mx_error(name, 0, "the mesh is empty: no cell lies in the domain; ask for finer levels");
    return MX_EINPUT;
  }
  const double t = mx_wtime();
  int st = mx_qmesh_check(&r->M, &r->domain, CHECK_TOL, &r->cr);
  r->t[PH_CHECK] = mx_wtime() - t;
  MX_CHECK(stage_status(st, "check", r));
  r->checked = 1;
  const mx_qcheck_report *c = &r->cr;
  const double h = sqrt(fabs(c->area) / (double)r->M.ncells);
  r->area_tol = fmax(AREA_TOL, 0.5 * perimeter(&r->domain) * h / fabs(c->domain_area));
  r->area_tol = fmin(r->area_tol, AREA_TOL_MAX);
  if (c->bad_edges || c->hanging || c->inverted || r->q.invalid) {
    mx_error(name, 0, "the mesh is not valid: %zu bad edge(s), %zu hanging node(s), %zu "
             "inverted cell(s) (%zu with scaled Jacobian <= 0); not written", c->bad_edges,
             c->hanging, c->inverted, r->q.invalid);
    return MX_EINVALID;
  }
  if (c->off_boundary || c->missing_features) {
    mx_error(name, 0, "the mesh's boundary is off the polylines: %zu boundary node(s) off, "
             "%zu feature(s) not a vertex; not written", c->off_boundary, c->missing_features);
    return MX_EINVALID;
  }
  if (c->euler != c->domain_euler) {
    mx_error(name, 0, "the mesh's topology differs from the domain's: %ld component(s) minus "
             "hole(s) against %ld: the levels are too coarse for thin parts of the domain; "
             "not written", c->euler, c->domain_euler);
    return MX_EINVALID;
  }
  if (!(c->area_error <= r->area_tol)) {
    mx_error(name, 0, "the mesh covers %.4g against the domain's %.4g (%.1f%% off; tolerance "
             "%.1f%%): the levels are too coarse for thin parts of the domain; not written",
             c->area, c->domain_area, 100.0 * c->area_error, 100.0 * r->area_tol);
    return MX_EINVALID;
  }
  return MX_OK;
}

static int write_outputs(const m2_options *o, m2_run *r) {
  const double t = mx_wtime();
  for (int k = 0; k < r->noutputs; k++) {
    MX_CHECK(mx_write_qmesh(r->outputs[k], &r->M, o->ascii));
    struct stat st;
    r->bytes[k] = stat(r->outputs[k], &st) == 0 ? (long long)st.st_size : -1;
    r->nwritten = k + 1;
  }
  r->t[PH_WRITE] = mx_wtime() - t;
  return MX_OK;
}

static int pipeline(const m2_options *o, m2_run *r) {
  const double t = mx_wtime();
  int st = read_inputs(o, r);
  r->t[PH_READ] = mx_wtime() - t;
  if (!st) st = mesh_domain(o, r);
  if (!st) st = check_mesh(r);
  if (!st || (st == MX_EINVALID && o->keep_invalid && r->checked)) {
    const int wst = write_outputs(o, r);
    if (wst) st = wst;
  }
  return mx_status_refine(st);
}

static void run_free(m2_run *r, const m2_options *o) {
  mx_qmesh_free(&r->M);
  mx_free(r->leaves);
  mx_qtree_free(&r->T);
  mx_poly_index_free(&r->index);
  mx_poly_free(&r->domain);
  for (int k = 0; k < o->nregions; k++) mx_poly_free(&r->regions[k]);
  for (int k = 0; k < o->ndrawings; k++) mx_poly_free(&r->drawings[k]);
  mx_free(r->boxes);
  for (int f = 0; f < NFMT; f++) free(r->owned[f]);
}

/* ---- report ------------------------------------------------------------------ */

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

static void json_mesh(FILE *f, const m2_options *o, const m2_run *r) {
  const mx_qquality *q = &r->q;
  fprintf(f, ", \"nodes\": %zu, \"elements\": %zu, \"by_type\": {\"tri\": %zu, \"quad\": %zu}, "
          "\"leaves\": %zu, \"quadrants\": %zu, \"splits\": %zu, \"balance_splits\": %zu, "
          "\"edges\": %zu, \"balance\": \"%s\", ",
          r->M.nnodes, r->M.ncells, q->count[0], q->count[1], r->nleaves, r->T.n, r->qs.splits,
          r->qs.balance_splits, r->qs.edges, o->balance ? "recursive" : "edges");
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
  const mx_qboundary_stats *b = &r->bs;
  fprintf(f, "}, \"boundary\": {\"features\": %zu, \"moved_close\": %zu, \"removed\": %zu, "
          "\"shrunk\": %zu, \"patterned\": %zu, \"inverted\": %zu}",
          b->features, b->moved_close, b->removed, b->shrunk, b->patterned, b->inverted);
}

static void json_check(FILE *f, const m2_run *r) {
  const mx_qcheck_report *c = &r->cr;
  fprintf(f, ", \"check\": {\"bad_edges\": %zu, \"hanging\": %zu, \"inverted\": %zu, "
          "\"off_boundary\": %zu, \"missing_features\": %zu, ",
          c->bad_edges, c->hanging, c->inverted, c->off_boundary, c->missing_features);
  json_num(f, "area", c->area), fputs(", ", f);
  json_num(f, "domain_area", c->domain_area), fputs(", ", f);
  json_num(f, "area_error", c->area_error), fputs(", ", f);
  json_num(f, "area_tolerance", r->area_tol);
  fprintf(f, ", \"edges\": %zu, \"boundary_edges\": %zu, \"euler\": %ld, \"domain_euler\": %ld}",
          c->edges, c->boundary_edges, c->euler, c->domain_euler);
}

static void print_json(const m2_options *o, const m2_run *r) {
  FILE *f = stdout;
  fprintf(f, "{\"valid\": %s, \"exit_code\": %d, \"error\": ", r->status ? "false" : "true",
          r->status);
  if (r->error[0]) json_string(f, r->error);
  else fputs("null", f);
  fprintf(f, ", \"warnings\": %d, \"outputs\": [", r->nwarnings);
  for (int k = 0; k < r->nwritten; k++) {
    fputs(k ? ", {\"path\": " : "{\"path\": ", f);
    json_string(f, r->outputs[k]);
    fprintf(f, ", \"bytes\": %lld}", r->bytes[k]);
  }
  fputs("]", f);
  if (r->meshed) json_mesh(f, o, r);
  if (r->checked) json_check(f, r);
  fputs(", \"phases\": {", f);
  for (int p = 0; p < NPH; p++) fprintf(f, "%s\"%s\": %.6f", p ? ", " : "", phase_name[p], r->t[p]);
  fprintf(f, "}, \"total_s\": %.6f, \"peak_rss_mb\": %.1f, \"threads\": %d}\n", r->total,
          mx_peak_rss_mb(), omp_get_max_threads());
  fflush(f);
}

static void print_quality(const m2_run *r) {
  const mx_qquality *q = &r->q;
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

static void print_summary(const m2_options *o, const m2_run *r) {
  printf("mesher2d: %s; %d thread(s), %s balance\n",
         r->domain.path ? r->domain.path : o->domain, omp_get_max_threads(),
         o->balance ? "recursive" : "edges");
  if (r->meshed) {
    printf("  quadtree     %12zu leaves (%zu quadrants, %zu splits, %zu for balance)\n",
           r->nleaves, r->T.n, r->qs.splits, r->qs.balance_splits);
    printf("  nodes        %12zu\n  cells        %12zu (quad %zu, tri %zu)\n", r->M.nnodes,
           r->M.ncells, r->q.count[1], r->q.count[0]);
    print_quality(r);
    printf("  boundary     %zu features, %zu moved close, %zu removed, %zu shrunk, %zu patterned\n",
           r->bs.features, r->bs.moved_close, r->bs.removed, r->bs.shrunk, r->bs.patterned);
  }
  if (r->checked)
    printf("  check        %s; area %.6g (domain %.6g, %.3f%% off)\n",
           r->status == MX_EINVALID ? "FAILED" : "conforming, valid", r->cr.area,
           r->cr.domain_area, 100.0 * r->cr.area_error);
  printf("  time (s)     %12.3f total:", r->total);
  for (int p = 0; p < NPH; p++) printf(" %s %.3f", phase_name[p], r->t[p]);
  printf("\n  peak memory  %12.0f MB\n", mx_peak_rss_mb());
  for (int k = 0; k < r->nwritten; k++)
    printf("  written      %s (%lld bytes)\n", r->outputs[k], r->bytes[k]);
  if (!r->noutputs) printf("  written      nothing: a dry run (give -u NAME -v, or -O FILE)\n");
}

int mx_mesher2d_main(int argc, char **argv) {
  m2_run *r = &run2;
  mx_msg_fn = on_message;
  mx_msg_user = r;
  m2_options o;
  int exit_now = 0;
  const double t0 = mx_wtime();
  int st = parse_options(argc, argv, &o, &exit_now);
  if (exit_now && !st) return 0;
  r->quiet = o.quiet;
  mx_quiet = o.quiet;
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
  if (o.json) print_json(&o, r);
  else if (!o.quiet && (r->meshed || !st)) print_summary(&o, r);
  run_free(r, &o);
  return st;
}
