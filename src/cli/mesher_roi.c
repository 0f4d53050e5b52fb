/* mixoct invoked as `mesher_roi` (a link installed beside mixoct): the
 * command line of the published mixed-element octree mesher (Lobos et al.),
 * so that existing job scripts keep working. Its flags are translated into
 * mixoct's options and the normal pipeline runs (mx_run, src/cli/main.c).
 *
 *   -d in.mdl        input surface (MDL; any format mixoct reads works)
 *   -o in.off        input surface (OFF). NOTE: -o is an INPUT here.
 *   -s RL            surface refinement level
 *   -a RL            refinement level of every octant
 *   -b file.reg      boxes with refinement levels
 *   -r surf RL       refinement level inside / on a region surface
 *   -u outname       base name of the output files
 *   -v               write outname.vtk     (legacy VTK, ASCII)
 *   -g               write outname.getfem  (GetFEM mesh file)
 *   -m               write outname.m3d     (M3D, see src/io/write_m3d.c)
 *   -i               write outname.mvm     (MVM, see src/io/write_m3d.c)
 *   -c in.oct        restart from an octree file (ours or the published one's)
 *   -l list.txt      elements of the mesh written with in.oct to refine
 *   with -u NAME, NAME.oct (the restart file) is written too, as the
 *   published mesher does
 *
 * Output names. "-u out -v" writes out.vtk, "-u out -m" out.m3d and
 * "-u out -i" out.mvm, as the published mesher does (REFERENCE.md: its runs
 * `mesher_roi -o cortex.off -s RL -u out -v` produce legacy VTK ASCII; its
 * M3D and MVM layouts are in "Published output layouts"). No documentation
 * of the name it gives its GetFEM file was found; mixoct writes out.getfem
 * (rather than GetFEM's customary ".mesh", which mixoct reserves for Medit).
 * -v, -g, -m and -i may be combined: the mesh is built once and written to
 * each file. Format flags without -u, or -u without a format flag, are usage
 * errors (exit 2); with neither, the run is a dry run that meshes and
 * reports, like mixoct without -o. -d and -o may be repeated and mixed:
 * several surfaces form one domain, as with mixoct's -i.
 *
 * mixoct's long options are accepted too (--threads N, --json, --quiet,
 * --max-memory MB, --balance edges|recursive, --stage S, --version). */
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"

static const char *roi_usage =
    "usage: mesher_roi (-d in.mdl | -o in.off) [requests] [-u outname -v|-g|-m|-i]\n"
    "\n"
    "The published mixed-element mesher's command line, run by mixoct.\n"
    "\n"
    "Input (repeatable; several surfaces form one domain):\n"
    "  -d FILE.mdl        a closed surface in MDL\n"
    "  -o FILE.off        a closed surface in OFF (-o is an INPUT here)\n"
    "\n"
    "Refinement requests (an octant takes the largest level asked):\n"
    "  -s RL              octants meeting the input surface\n"
    "  -a RL              every octant of the domain\n"
    "  -b FILE.reg        boxes with levels\n"
    "  -r SURF RL         octants meeting or inside surface SURF\n"
    "\n"
    "Output (one mesh, one file per format flag; none: a dry run):\n"
    "  -u NAME            base name of the output files\n"
    "  -v                 NAME.vtk     legacy VTK, ASCII\n"
    "  -g                 NAME.getfem  GetFEM mesh file\n"
    "  -m                 NAME.m3d     M3D\n"
    "  -i                 NAME.mvm     MVM\n"
    "\n"
    "  (with -u NAME, the restart file NAME.oct is written too)\n"
    "\n"
    "Re-meshing:\n"
    "  -c FILE.oct        restart from an octree file\n"
    "  -l LIST.txt        elements (of the mesh written with FILE.oct) to refine:\n"
    "                     one 0-based index per line (12, 12.0 or 1.2e+01; '#'\n"
    "                     comments); another word is exit 2 naming its line\n"
    "\n"
    "Also accepted: --threads N, --json, --quiet, --max-memory MB,\n"
    "--balance edges|recursive, --stage octree|transition|full, --version,\n"
    "--demo (the built-in surface as the input).\n"
    "  -h, --help         this text\n"
    "\n"
    "Example:\n"
    "  mesher_roi -o cortex.off -s 6 -u cortex6 -v -g\n";

/* The output format flags and the extension each one writes. */
enum { NFMT = 4 };
static const struct {
  const char *flag, *ext;
} formats[NFMT] = {{"-v", ".vtk"}, {"-g", ".getfem"}, {"-m", ".m3d"},
                   {"-i", ".mvm"}};

/* The index of the format flag a in formats[], or -1. */
static int format_flag(const char *a) {
  for (int f = 0; f < NFMT; f++)
    if (!strcmp(a, formats[f].flag)) return f;
  return -1;
}

/* mixoct long options passed through, with their argument counts. */
static const struct {
  const char *name;
  int nargs;
} passthrough[] = {{"--threads", 1}, {"--json", 0},    {"--quiet", 0},
                   {"--max-memory", 1}, {"--balance", 1}, {"--stage", 1},
                   {"--version", 0}, {"--demo", 0}};

static int need(int i, int argc, int n, const char *opt) {
  if (i + n >= argc) {
    mx_error(NULL, 0, "mesher_roi: %s needs %s (see mesher_roi -h)", opt,
             n == 1 ? "an argument" : "a surface and a level");
    return MX_EINPUT;
  }
  return MX_OK;
}

/* Translates argv into mixoct's argv (margv, room for argc + 1 entries) and
 * the output flags (want[f]: formats[f] asked). Returns MX_OK, or MX_EINPUT
 * with a message printed; *exit_now is set after -h. */
static int translate(int argc, char **argv, char **margv, int *margc, const char **outname,
                     int want[NFMT], int *exit_now) {
  int n = 0, ninputs = 0;
  margv[n++] = "mixoct";
  for (int i = 1; i < argc; i++) {
    const char *a = argv[i];
    if (!strcmp(a, "-h") || !strcmp(a, "--help")) {
      fputs(roi_usage, stdout);
      *exit_now = 1;
      return MX_OK;
    } else if (!strcmp(a, "-c") || !strcmp(a, "-l")) {
      MX_CHECK(need(i, argc, 1, a));
      margv[n++] = argv[i];
      margv[n++] = argv[++i];
    } else if (!strcmp(a, "-d") || !strcmp(a, "-o")) {
      MX_CHECK(need(i, argc, 1, a));
      margv[n++] = "-i";
      margv[n++] = argv[++i];
      ninputs++;
    } else if (!strcmp(a, "-s") || !strcmp(a, "-a") || !strcmp(a, "-b")) {
      MX_CHECK(need(i, argc, 1, a));
      margv[n++] = argv[i];
      margv[n++] = argv[++i];
    } else if (!strcmp(a, "-r")) {
      MX_CHECK(need(i, argc, 2, a));
      margv[n++] = argv[i];
      margv[n++] = argv[++i];
      margv[n++] = argv[++i];
    } else if (!strcmp(a, "-u")) {
      MX_CHECK(need(i, argc, 1, a));
      *outname = argv[++i];
      if (!**outname) {
        mx_error(NULL, 0, "mesher_roi: -u wants a non-empty name");
        return MX_EINPUT;
      }
    } else if (format_flag(a) >= 0) {
      want[format_flag(a)] = 1;
    } else {
      size_t k = 0, np = sizeof passthrough / sizeof *passthrough;
      while (k < np && strcmp(a, passthrough[k].name) != 0) k++;
      if (k == np) {
        mx_error(NULL, 0, "mesher_roi: unknown option '%s' (see mesher_roi -h)", a);
        return MX_EINPUT;
      }
      MX_CHECK(passthrough[k].nargs ? need(i, argc, passthrough[k].nargs, a) : MX_OK);
      margv[n++] = argv[i];
      for (int j = 0; j < passthrough[k].nargs; j++) margv[n++] = argv[++i];
      /* --demo is an input; --version needs none */
      if (!strcmp(a, "--demo") || !strcmp(a, "--version")) ninputs++;
    }
  }
  if (ninputs == 0) {
    mx_error(NULL, 0, "mesher_roi: no input: give -d in.mdl or -o in.off "
                      "(see mesher_roi -h)");
    return MX_EINPUT;
  }
  int nfmt = 0;
  for (int f = 0; f < NFMT; f++) nfmt += want[f];
  if (nfmt > 0 && !*outname) {
    mx_error(NULL, 0, "mesher_roi: -v, -g, -m and -i need the output name: add -u NAME");
    return MX_EINPUT;
  }
  if (nfmt == 0 && *outname) {
    mx_error(NULL, 0, "mesher_roi: -u %s names no format: add -v (VTK), -g "
                      "(GetFEM), -m (M3D) and/or -i (MVM)", *outname);
    return MX_EINPUT;
  }
  margv[n] = NULL;
  *margc = n;
  return MX_OK;
}

int mx_mesher_roi_main(int argc, char **argv) {
  char **margv = mx_alloc(((size_t)argc + 4) * sizeof *margv);
  if (!margv) return MX_ENOMEM;
  int margc = 0, want[NFMT] = {0}, exit_now = 0;
  const char *outname = NULL;
  int st = translate(argc, argv, margv, &margc, &outname, want, &exit_now);
  if (st || exit_now) {
    mx_free(margv);
    return st ? MX_EINPUT : 0;
  }
  mx_options o;
  st = mx_parse_options(margc, margv, &o, &exit_now);
  mx_free(margv);
  if (st) return st == MX_ENOMEM ? MX_ENOMEM : MX_EINPUT;
  if (exit_now) return 0;

  /* outputs[0] is also o.output, so everything that asks whether the run
   * writes a file sees it; mx_run writes each of outputs[]. */
  char *names[NFMT] = {NULL}, *oct = NULL;
  for (int f = 0; f < NFMT; f++) {
    if (!want[f]) continue;
    const size_t len = strlen(outname) + strlen(formats[f].ext) + 1;
    names[f] = mx_alloc(len);
    if (!names[f]) {
      st = MX_ENOMEM;
      break;
    }
    snprintf(names[f], len, "%s%s", outname, formats[f].ext);
    o.outputs[o.noutputs++] = names[f];
  }
  if (o.noutputs > 0) o.output = o.outputs[0];
  if (!st && outname) {
    const size_t len = strlen(outname) + 5;
    oct = mx_alloc(len);
    if (!oct) {
      st = MX_ENOMEM;
    } else {
      snprintf(oct, len, "%s.oct", outname);
      o.restart_out = oct;
    }
  }
  o.ascii = 1; /* the published mesher writes ASCII legacy VTK */
  if (!st) st = mx_check_run_files(&o);
  if (!st) {
    if (o.quiet) mx_set_thread_quiet(1);
    if (o.threads > 0) omp_set_num_threads(o.threads);
    st = mx_run(&o);
  }
  for (int f = 0; f < NFMT; f++) mx_free(names[f]);
  mx_free(oct);
  return st == MX_OK ? 0 : st;
}
