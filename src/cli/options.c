#include "cli.h"

#include <errno.h>
#include <omp.h>
#include <stdio.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <unistd.h>

static const char *usage_text =
    "mixoct: a parallel mixed-element octree mesher (hexahedra, prisms,\n"
    "pyramids, tetrahedra) from closed triangulated surfaces.\n"
    "\n"
    "usage: mixoct -i FILE [-i FILE2 ...] [requests] [-o OUT] [options]\n"
    "       mixoct --demo [requests] [-o OUT] [options]\n"
    "       mixoct remesh -c FILE.oct -i FILE -l LIST [requests] [-o OUT] [options]\n"
    "       mixoct check MESH [check options] (mixoct check --help)\n"
    "       mixoct patterns [--json]\n"
    "\n"
    "Input (OFF, MDL, STL ascii/binary, OBJ, PLY; several -i form one domain, a\n"
    "shell inside another is a hole):\n"
    "  -i, --input FILE            a closed triangulated surface (repeatable)\n"
    "      --demo                  the built-in brain-like surface\n"
    "      --repair-input          mesh an input with no well-defined inside\n"
    "                              (open, non-manifold, self-intersecting, two\n"
    "                              inputs that cross or touch) where the\n"
    "                              generalized winding number of all inputs, as\n"
    "                              oriented, is above 1/2 (touching or\n"
    "                              overlapping bodies: their union); without\n"
    "                              it such an input is refused (exit 2) naming\n"
    "                              the defect.\n"
    "                              Inconsistently oriented closed surfaces are\n"
    "                              re-oriented (a warning) either way\n"
    "      --materials             several materials: a shell inside another is\n"
    "                              not a hole; each element gets the material of\n"
    "                              its region, numbered by nesting depth (1: inside\n"
    "                              one shell, 2: inside two, ...), written as the\n"
    "                              cell field material, Gmsh physical volumes and\n"
    "                              Medit references, the interfaces as physical\n"
    "                              surfaces. Elements cut by an interface are\n"
    "                              split along it (none lies across one); touching\n"
    "                              inputs share their common triangles; one surface\n"
    "                              with internal faces is split into its regions. A\n"
    "                              restart file written with --materials turns it\n"
    "                              on. With --p4est: no physical surfaces in .msh\n"
    "      --level L               after -i FILE: octants meeting FILE's surface\n"
    "                              go to level L (a level per input, with -s the\n"
    "                              others')\n"
    "      --inside-level L        after -i FILE: octants meeting or inside FILE\n"
    "                              go to level L (with --materials: a level\n"
    "                              everywhere in the material(s) FILE holds)\n"
    "      --feature-angle DEG     sharp features: ridges where the input's normals\n"
    "                              part by more than DEG (default 30), corners where\n"
    "                              they end, meet or turn; kept in the mesh (corners\n"
    "                              on nodes, ridges along element edges) where every\n"
    "                              element stays at J_ENS 0.1 or more\n"
    "      --features FILE         the features as polylines (one a line: n x1 y1 z1\n"
    "                              ... xn yn zn) instead of found on the surface\n"
    "      --feature-level L       octants meeting a ridge or corner refined to L\n"
    "                              (default: the surface level)\n"
    "      --no-features           no feature search: the boundary as without them\n"
    "      --material ID[:NAME]    after -i FILE: the number (1..65535) and name\n"
    "                              of the material inside FILE (default: its\n"
    "                              nesting depth, named after FILE)\n"
    "\n"
    "Label images (-i labels.nii[.gz] | .mha | .mhd | .inr[.gz]: a segmented\n"
    "image, 0 background, each other label a material of that number; meshed\n"
    "alone, on its voxel lattice: voxels at the interfaces, as coarse as\n"
    "balance allows inside, no other request needed):\n"
    "      --voxel                 keep the voxel faces (a staircase); by default\n"
    "                              the nodes on an interface move onto the\n"
    "                              smoothed interface (at most 0.35 voxel)\n"
    "      --interface-smoothing N the smoothing's rounds (default 10; 0 = --voxel)\n"
    "      --label-names FILE      the materials' names: \"LABEL NAME ...\" lines\n"
    "                              (FreeSurfer lookup tables read as they are)\n"
    "      --skip-labels L,L,...   labels meshed as background\n"
    "      --merge-labels A:B,...  label A meshed as label B\n"
    "      --min-island N          parts of a label of fewer than N voxels take\n"
    "                              the label around them\n"
    "      --label-size L:S,...    inside label L no element wider than S voxels\n"
    "                              (a power of two; 1: every voxel of L); --size\n"
    "                              EXPR|FILE applies too (in the world, down to\n"
    "                              the voxels); -s, -a, -b, -r do not\n"
    "\n"
    "Refinement requests (an octant takes the largest level asked; levels 0 to\n"
    "15, each one halves the octant size):\n"
    "  -s, --surface-level RL      octants meeting the input surface\n"
    "  -a, --all-level RL          every octant of the domain\n"
    "  -b, --regions FILE.reg      boxes with levels\n"
    "  -r, --region-surface S RL   octants meeting or inside surface S\n"
    "      --size EXPR|FILE        a size field: octants are split while larger\n"
    "                              than the least size over them; EXPR of x, y,\n"
    "                              z (+ - * / ^, exp log sqrt abs sin cos min\n"
    "                              max, pi, e; e.g. \"0.02 + 0.1*abs(x)\") or one\n"
    "                              of the test functions F1..F5 of Jurczyk &\n"
    "                              Glut 2016; with the other requests, the\n"
    "                              finest wins\n"
    "      --size-min H, --size-max H\n"
    "                              bounds on the field's sizes (--size-max\n"
    "                              alone: a field of that size everywhere)\n"
    "                              FILE (an existing file): a size map, points\n"
    "                              with sizes: a .vtu/.vtp/.vtk point or cell\n"
    "                              field (--size-field NAME, default size, h or\n"
    "                              target_size), a Gmsh .pos view, or lines\n"
    "                              'x y z h'\n"
    "      --curvature DEG         a size field from the surface's curvature:\n"
    "                              an element spans at most DEG degrees of it\n"
    "      --thickness N           at least N elements across every part and\n"
    "                              every gap (rays along the surface normals)\n"
    "      --gradation BETA        neighbouring sizes differ by at most BETA\n"
    "                              (default 2 for --curvature, --thickness and\n"
    "                              size maps; given, for --size too)\n"
    "                              (all sources together: the least size wins)\n"
    "\n"
    "Output:\n"
    "  -o, --output OUT            .vtk (legacy), .vtu, .pvtu (parallel VTU: one\n"
    "                              piece per MPI rank with --p4est), .msh (Gmsh\n"
    "                              4.1), .mesh / .meshb (Medit), .getfem, .m3d,\n"
    "                              .mvm; repeatable\n"
    "                              (one mesh, several files); without -o nothing\n"
    "                              is written (a dry run). Checked before meshing;\n"
    "                              written to a temporary name and renamed:\n"
    "                              never partial, removed on Ctrl-C / SIGTERM\n"
    "      --stage full            the mesh of the domain (the default): nodes\n"
    "                              on the surface, surface patterns, staircase\n"
    "                              reduction, invalid elements repaired\n"
    "      --smooth N              N rounds of smoothing after the untangling\n"
    "                              (default 0: off): nodes move where that\n"
    "                              raises the worst J_ENS around them, never\n"
    "                              lowering any node's worst; surface nodes\n"
    "                              stay on the surface\n"
    "      --tets                  split the final mesh into tetrahedra\n"
    "                              (pyramid 2, prism 3, hexahedron 5 or 6, each\n"
    "                              quadrilateral cut through its node of the\n"
    "                              smallest index), checked again: for solvers\n"
    "                              that take one cell type (dolfinx)\n"
    "      --stage transition      stop after the transition patterns: the\n"
    "                              conforming mixed mesh of the whole octree\n"
    "                              (cell data type, level, jens)\n"
    "      --stage octree          stop after the balanced octree (leaves as\n"
    "                              hexahedra with their level)\n"
    "      --ascii                 ASCII .vtk / .msh (binary by default)\n"
    "      --fields all|quality|none\n"
    "                              the element data written: all (default:\n"
    "                              type, level, jens, boundary, target_size),\n"
    "                              quality (jens), none; the tags (surface_tag,\n"
    "                              body, material) stay: .vtu/.vtk fields,\n"
    "                              .msh physical groups, .mesh references\n"
    "      --json                  one JSON summary as the last stdout line\n"
    "                              (no summary table, no progress line)\n"
    "      --quiet                 no summary, no warnings, no progress line\n"
    "      --restart FILE.oct      also write the restart file (Appendix A of\n"
    "                              the 2021 paper; .octb: our binary variant)\n"
    "      --boundary FILE         also write the boundary faces: .vtu and .ply\n"
    "                              tagged by the input file they lie on (cell\n"
    "                              field surface_tag: 1 for the first -i) and\n"
    "                              body, .off the faces alone, .stl (binary,\n"
    "                              single precision) quadrilaterals cut in two\n"
    "      --keep-invalid          write the mesh even when it breaks the\n"
    "                              contract of exit 0 (exit 5 all the same)\n"
    "  Options take their value as the next word, or attached: --output=x.vtu,\n"
    "  -s5, -ox.vtu.\n"
    "\n"
    "Re-meshing (from a restart file, ours or the published program's):\n"
    "  -c, --from-restart FILE     rebuild the octree of FILE.oct / .octb (the\n"
    "                              same -i surfaces), refine, mesh again\n"
    "  -l, --list LIST             element indices (of the mesh written with\n"
    "                              the restart file) whose octants are split\n"
    "                              once (Algorithm 3); requests apply on top.\n"
    "                              One index per line (blanks and commas also\n"
    "                              separate, '#' starts a comment), 0-based;\n"
    "                              a real with a whole value is that index\n"
    "                              (12.0, 1.2e+01: numpy.savetxt files work);\n"
    "                              any other word is exit 2 naming its line;\n"
    "                              an empty list is a warning\n"
    "\n"
    "Execution:\n"
    "      --threads N             OpenMP threads (default: OMP_NUM_THREADS, or\n"
    "                              all cores); the output bytes do not depend\n"
    "                              on it. Pinning: OMP_PLACES=cores\n"
    "                              OMP_PROC_BIND=close (see README, Threads)\n"
    "      --max-memory MB         refuse runs estimated to need more (default:\n"
    "                              the memory available)\n"
    "      --balance edges|recursive\n"
    "                              edge infos while refining (default), or the\n"
    "                              original recursive search at the end\n"
    "      --p4est                 the distributed path (MPI builds): mpirun -n N\n"
    "                              mixoct --p4est ...; p4est's forest, each rank\n"
    "                              meshes its leaves; -o OUT.pvtu (a piece per\n"
    "                              rank) or OUT.msh; not with -c, --restart,\n"
    "                              --boundary, size fields or features\n"
    "      --p4est-compare         with --p4est: also compare p4est's leaves\n"
    "                              with the single-process octree's\n"
    "  -h, --help                  this text\n"
    "      --version               version, build, compiler, threads, topology\n"
    "      --list-options          every option, one a line (shell completion)\n"
    "  A progress line (stage, level, percentage) is drawn on stderr only when\n"
    "  stderr is a terminal.\n"
    "\n"
    "Subcommands:\n"
    "  check MESH [--surface FILE ... | --poly FILE] [--volume-tol X]\n"
    "        [--dist-tol X] [--feature-angle DEG] [--features FILE]\n"
    "        [--feature-tol T] [--threads N] [--json] [--quiet]\n"
    "                              independent checker of a 3D mesh (.vtk,\n"
    "                              .vtu, .pvtu, .msh, .mesh, .meshb, .getfem,\n"
    "                              .m3d, .mvm) or a 2D one: J_ENS > 0, faces\n"
    "                              matched, closed boundary, no hanging node,\n"
    "                              volume, and against FILE the volume error,\n"
    "                              boundary and feature distances; exit 0\n"
    "                              clean, 5 defects (mixoct check --help)\n"
    "  patterns [--json]           the transition-pattern table: classes,\n"
    "                              sub-elements per type, worst J_ENS\n"
    "\n"
    "Exit codes:\n"
    "  0  a valid mesh was written: non-empty, conforming, every element with\n"
    "     J_ENS >= 1e-6 (none inverted or degenerate), its boundary on the input;\n"
    "     with --stage octree or transition, 0 means only that the stage asked\n"
    "     for was written (octree: hanging nodes, not conforming; transition: no\n"
    "     boundary on the input), and --json says \"valid\": false\n"
    "  1  internal failure (a bug: please report it)\n"
    "  2  bad input or usage, refused before meshing or with an empty result\n"
    "     (the message names the file and line)\n"
    "  3  out of memory, or over the memory budget (estimated before meshing)\n"
    "  4  an output that cannot be written (checked before meshing)\n"
    "  5  meshed, but the result breaks the contract of exit 0 (elements with\n"
    "     J_ENS < 1e-6 or nodes lying on another element's face or edge left\n"
    "     after repair, or a volume far off the input's): not written unless\n"
    "     --keep-invalid\n"
    "  128+N  killed by signal N (Ctrl-C: 130); no temporary file is left\n"
    "--json prints one JSON line whatever the outcome: valid, exit_code, error,\n"
    "warnings, outputs, and the figures of the mesh when there is one.\n"
    "\n"
    "Examples:\n"
    "  mixoct --demo -s 5 -o demo.vtu\n"
    "  mixoct --demo -s 5 -o demo.vtu --stage octree\n"
    "  mixoct -i cortex.off -s 7 -o cortex7.vtu && mixoct check cortex7.vtu\n"
    "  mixoct -i cortex.off -s 7 --json --threads 8 > run.json\n"
    "  mixoct -i outer.mdl -i inner.mdl -s 5 -b roi.reg -o shell.vtk\n"
    "  mixoct -i head.stl -s 4 -r tumour.off 7 -o head.msh\n"
    "  mixoct -i cortex.off -s 5 -o c5.vtk --restart c5.oct\n"
    "  mixoct remesh -c c5.oct -i cortex.off -l list.txt -o c5r.vtk\n"
    "  mixoct patterns --json\n";

/* --version: what was built, how, and what it runs on. */
static const char *openmp_name(long v) {
  return v >= 202111 ? "5.2" : v >= 202011 ? "5.1" : v >= 201811 ? "5.0"
       : v >= 201511 ? "4.5" : v >= 201307 ? "4.0" : v >= 201107 ? "3.1" : "3.0";
}

static void print_version(void) {
#ifndef MX_VERSION
#define MX_VERSION "0.1.0"
#endif
#ifndef MX_BUILD_TYPE
#define MX_BUILD_TYPE "unknown"
#endif
#if defined(__clang__)
  const char *compiler = "clang " __clang_version__;
#elif defined(__GNUC__)
  const char *compiler = "gcc " __VERSION__;
#else
  const char *compiler = "unknown compiler";
#endif
#ifdef NDEBUG
  const char *asserts = "off";
#else
  const char *asserts = "on";
#endif
  char topo[512];
  mx_topology_string(topo, sizeof topo);
  const char *env[3] = {"OMP_NUM_THREADS", "OMP_PLACES", "OMP_PROC_BIND"};
  printf("mixoct %s\n", MX_VERSION);
  printf("build      %s, asserts %s\n", MX_BUILD_TYPE, asserts);
  printf("compiler   %s, OpenMP %s (%ld)\n", compiler, openmp_name((long)_OPENMP),
         (long)_OPENMP);
  static const char *bind_name[] = {"false", "true", "primary", "close", "spread"};
  const int bind = (int)omp_get_proc_bind();
  printf("threads    OpenMP max threads %d, proc_bind %s, %d place(s)\n          ",
         omp_get_max_threads(), bind >= 0 && bind <= 4 ? bind_name[bind] : "?",
         omp_get_num_places());
  for (int k = 0; k < 3; k++) {
    const char *v = getenv(env[k]);
    printf(" %s=%s", env[k], v && *v ? v : "unset");
  }
  printf("\n");
  printf("topology   %s\n", topo);
}

static int parse_level(const char *opt, const char *s, int *out) {
  char *end;
  errno = 0;
  long v = s ? strtol(s, &end, 10) : -1;
  /* The top lattice level is kept for the transition patterns' midpoints. */
  if (!s || errno || *end || v < 0 || v > MX_MAX_LEVEL - 1) {
    mx_error(NULL, 0, "%s wants a level between 0 and %d, got '%s'", opt,
             MX_MAX_LEVEL - 1, s ? s : "");
    return MX_EINPUT;
  }
  *out = (int)v;
  return MX_OK;
}

/* An option's value among n words: *out = values[k] for words[k], else
 * exit 2 with "OPT wants A, B or C, got 'S'". */
static int parse_word(const char *opt, const char *s, const char *const *words,
                      const int *values, int n, int *out) {
  for (int k = 0; k < n; k++)
    if (strcmp(s, words[k]) == 0) {
      *out = values[k];
      return MX_OK;
    }
  char list[256];
  size_t len = 0;
  list[0] = '\0';
  for (int k = 0; k < n && len < sizeof list; k++)
    len += (size_t)snprintf(list + len, sizeof list - len, "%s%s",
                            k == 0 ? "" : k + 1 < n ? ", " : " or ", words[k]);
  mx_error(NULL, 0, "%s wants %s, got '%s'", opt, list, s);
  return MX_EINPUT;
}

static int need_arg(int i, int argc, const char *opt) {
  if (i + 1 >= argc) {
    mx_error(NULL, 0, "%s needs an argument (see mixoct --help)", opt);
    return MX_EINPUT;
  }
  return MX_OK;
}

/* Every option of the mesher (mixoct, mixoct remesh, mixoct --p4est): its
 * short and long names and the words it takes. The parser refuses any other
 * word that starts with '-' (unknown option) and splits the attached forms
 * of those taking words; `--list-options` prints them one a line (for shell
 * completion); tests/help_test.sh checks that --help documents each and
 * nothing else. */
static const struct {
  const char *sh, *lg;
  int nargs;
} option_table[] = {
    {"-h", "--help", 0},           {NULL, "--version", 0},        {NULL, "--list-options", 0},
    {"-i", "--input", 1},          {NULL, "--demo", 0},           {NULL, "--repair-input", 0},
    {NULL, "--materials", 0},      {NULL, "--level", 1},          {NULL, "--inside-level", 1},
    {NULL, "--feature-angle", 1},  {NULL, "--features", 1},       {NULL, "--feature-level", 1},
    {NULL, "--no-features", 0},    {NULL, "--material", 1},       {NULL, "--voxel", 0},
    {NULL, "--interface-smoothing", 1}, {NULL, "--label-names", 1}, {NULL, "--skip-labels", 1},
    {NULL, "--merge-labels", 1},   {NULL, "--min-island", 1},     {NULL, "--label-size", 1},
    {"-s", "--surface-level", 1},  {"-a", "--all-level", 1},      {"-b", "--regions", 1},
    {"-r", "--region-surface", 2}, {NULL, "--size", 1},           {NULL, "--size-min", 1},
    {NULL, "--size-max", 1},       {NULL, "--size-field", 1},     {NULL, "--curvature", 1},
    {NULL, "--thickness", 1},      {NULL, "--gradation", 1},      {"-o", "--output", 1},
    {NULL, "--stage", 1},          {NULL, "--smooth", 1},         {NULL, "--ascii", 0},
    {NULL, "--fields", 1},         {NULL, "--json", 0},           {NULL, "--quiet", 0},
    {NULL, "--restart", 1},        {NULL, "--boundary", 1},       {NULL, "--keep-invalid", 0},
    {"-c", "--from-restart", 1},   {"-l", "--list", 1},           {NULL, "--threads", 1},
    {NULL, "--max-memory", 1},     {NULL, "--balance", 1},        {NULL, "--p4est", 0},
    {NULL, "--p4est-compare", 0}, {NULL, "--tets", 0}};
enum { NOPTIONS = sizeof option_table / sizeof *option_table };

/* The table's entry of a (its long or short name), or -1. */
static int option_index(const char *a) {
  for (int k = 0; k < NOPTIONS; k++)
    if ((option_table[k].sh && strcmp(a, option_table[k].sh) == 0) ||
        strcmp(a, option_table[k].lg) == 0)
      return k;
  return -1;
}

/* argv with the forms getopt users expect split in two: `--output=x.vtu`
 * and `-s5` / `-ox.vtu` become `--output x.vtu`, `-s 5`, `-o x.vtu`. The
 * strings live as long as the process (the options point into them). */
/* kept for the process's life, reachable (not a leak) */
static char **volatile split_argv;

static char **split_attached(int argc, char **argv, int *nargc) {
  /* the new argv, then the names this function allocated (freed if one
   * cannot be) */
  char **v = mx_alloc((3 * (size_t)argc + 1) * sizeof *v);
  if (!v) return NULL;
  char **names = v + 2 * (size_t)argc + 1;
  int n = 0, nnames = 0;
  for (int i = 0; i < argc; i++) {
    const char *a = argv[i];
    v[n++] = argv[i];
    if (i == 0 || a[0] != '-') continue;
    for (int k = 0; k < NOPTIONS; k++) {
      if (!option_table[k].nargs) continue;
      const char *sh = option_table[k].sh, *lg = option_table[k].lg;
      const size_t ll = strlen(lg);
      if (strncmp(a, lg, ll) == 0 && a[ll] == '=') {
        char *name = mx_alloc(ll + 1);
        if (!name) {
          for (int j = 0; j < nnames; j++) mx_free(names[j]);
          mx_free(v);
          return NULL;
        }
        memcpy(name, a, ll);
        name[ll] = '\0';
        names[nnames++] = name;
        v[n - 1] = name;
        v[n++] = (char *)a + ll + 1;
        break;
      }
      if (sh && a[1] == sh[1] && a[2] != '\0' && a[1] != '-') {
        v[n - 1] = (char *)sh;
        v[n++] = (char *)a + 2;
        break;
      }
    }
  }
  v[n] = NULL;
  *nargc = n;
  split_argv = v;
  return v;
}

int mx_parse_size_bound(const char *opt, const char *s, double *out) {
  char *end = NULL;
  const double v = strtod(s, &end);
  if (end == s || *end || !(v > 0.0) || !isfinite(v)) {
    mx_error(NULL, 0, "%s needs a positive size, not '%s'", opt, s);
    return MX_EINPUT;
  }
  *out = v;
  return MX_OK;
}

int mx_parse_options(int argc0, char **argv0, mx_options *o, int *exit_now) {
  int argc = argc0;
  char **argv = split_attached(argc0, argv0, &argc);
  if (!argv) return MX_ENOMEM;
  memset(o, 0, sizeof *o);
  o->s_level = -1;
  o->feature_angle = -1.0;
  o->smooth_rounds = -1;
  mx_image_params_default(&o->image);
  o->a_level = -1;
  o->stage = MX_STAGE_FULL;
  o->balance = MX_BALANCE_EDGES;
  *exit_now = 0;
  for (int i = 1; i < argc; i++) {
    const char *a = argv[i];
#define IS(s, l) (strcmp(a, s) == 0 || strcmp(a, l) == 0)
    if (option_index(a) < 0) {
      mx_error(NULL, 0, "%s '%s' (see mixoct --help)",
               a[0] == '-' ? "unknown option" : "a word that is no option's value", a);
      return MX_EINPUT;
    } else if (IS("-h", "--help")) {
      fputs(usage_text, stdout);
      *exit_now = 1;
      return MX_OK;
    } else if (strcmp(a, "--version") == 0) {
      print_version();
      *exit_now = 1;
      return MX_OK;
    } else if (strcmp(a, "--list-options") == 0) {
      for (int k = 0; k < NOPTIONS; k++)
        printf("%s%s%s\n", option_table[k].sh ? option_table[k].sh : "",
               option_table[k].sh ? " " : "", option_table[k].lg);
      *exit_now = 1;
      return MX_OK;
    } else if (strcmp(a, "--p4est") == 0 || strcmp(a, "--p4est-compare") == 0) {
      mx_error(NULL, 0, "%s: %s", a, strcmp(a, "--p4est") == 0
                                         ? "this mixoct was built without MPI and p4est "
                                           "(meson setup -Dmpi=enabled)"
                                         : "only with --p4est (mpirun -n N mixoct --p4est ...)");
      return MX_EINPUT;
    } else if (IS("-i", "--input")) {
      MX_CHECK(need_arg(i, argc, a));
      if (o->ninputs == MX_MAX_INPUTS) {
        mx_error(NULL, 0, "at most %d inputs", MX_MAX_INPUTS);
        return MX_EINPUT;
      }
      o->inputs[o->ninputs++] = argv[++i];
    } else if (strcmp(a, "--demo") == 0) {
      o->demo = 1;
    } else if (IS("-s", "--surface-level")) {
      MX_CHECK(need_arg(i, argc, a));
      MX_CHECK(parse_level(a, argv[++i], &o->s_level));
    } else if (IS("-a", "--all-level")) {
      MX_CHECK(need_arg(i, argc, a));
      MX_CHECK(parse_level(a, argv[++i], &o->a_level));
    } else if (IS("-b", "--regions")) {
      MX_CHECK(need_arg(i, argc, a));
      o->regions_file = argv[++i];
    } else if (strcmp(a, "--size") == 0) {
      MX_CHECK(need_arg(i, argc, a));
      o->size = argv[++i];
    } else if (strcmp(a, "--size-min") == 0 || strcmp(a, "--size-max") == 0) {
      MX_CHECK(need_arg(i, argc, a));
      MX_CHECK(mx_parse_size_bound(a, argv[++i], strcmp(a, "--size-min") == 0 ? &o->size_min
                                                                               : &o->size_max));
    } else if (strcmp(a, "--curvature") == 0 || strcmp(a, "--thickness") == 0 ||
               strcmp(a, "--gradation") == 0) {
      MX_CHECK(need_arg(i, argc, a));
      char *end = NULL;
      const double v = strtod(argv[++i], &end);
      const int cu = a[2] == 'c', th = a[2] == 't';
      const int ok = end != argv[i] && !*end && isfinite(v) &&
                     (cu ? v > 0.0 && v < 180.0 : th ? v >= 1.0 && v <= 64.0 : v > 1.0 && v <= 100.0);
      if (!ok) {
        mx_error(NULL, 0, "%s needs %s, not '%s'", a,
                 cu ? "an angle in degrees between 0 and 180 (e.g. 10)"
                    : th ? "a number of elements from 1 to 64 (e.g. 2)"
                         : "a ratio above 1 and at most 100 (e.g. 1.5)", argv[i]);
        return MX_EINPUT;
      }
      if (cu) o->curvature = v;
      else if (th) o->thickness = v;
      else o->gradation = v;
    } else if (strcmp(a, "--size-field") == 0) {
      MX_CHECK(need_arg(i, argc, a));
      o->size_field = argv[++i];
    } else if (IS("-r", "--region-surface")) {
      if (i + 2 >= argc) {
        mx_error(NULL, 0, "%s needs a surface and a level", a);
        return MX_EINPUT;
      }
      if (o->nregion_surf == MX_MAX_REGIONS) {
        mx_error(NULL, 0, "at most %d region surfaces", MX_MAX_REGIONS);
        return MX_EINPUT;
      }
      o->region_surf[o->nregion_surf] = argv[++i];
      MX_CHECK(parse_level(a, argv[++i], &o->rlevel[o->nregion_surf]));
      o->nregion_surf++;
    } else if (IS("-o", "--output")) {
      MX_CHECK(need_arg(i, argc, a));
      if (o->noutputs == MX_MAX_OUTPUTS) {
        mx_error(NULL, 0, "at most %d outputs", MX_MAX_OUTPUTS);
        return MX_EINPUT;
      }
      o->outputs[o->noutputs++] = argv[++i];
      o->output = o->outputs[0];
    } else if (strcmp(a, "--threads") == 0) {
      MX_CHECK(need_arg(i, argc, a));
      char *end;
      long v = strtol(argv[++i], &end, 10);
      if (*end || v < 1 || v > 4096) {
        mx_error(NULL, 0, "--threads wants a positive count, got '%s'", argv[i]);
        return MX_EINPUT;
      }
      o->threads = (int)v;
    } else if (strcmp(a, "--max-memory") == 0) {
      MX_CHECK(need_arg(i, argc, a));
      char *end;
      const double v = strtod(argv[++i], &end);
      if (*end || !(v > 0.0)) {
        mx_error(NULL, 0, "--max-memory wants a size in MB, got '%s'", argv[i]);
        return MX_EINPUT;
      }
      o->max_memory_mb = v;
    } else if (strcmp(a, "--restart") == 0) {
      MX_CHECK(need_arg(i, argc, a));
      o->restart_out = argv[++i];
    } else if (strcmp(a, "--boundary") == 0) {
      MX_CHECK(need_arg(i, argc, a));
      o->boundary_out = argv[++i];
    } else if (IS("-c", "--from-restart")) {
      MX_CHECK(need_arg(i, argc, a));
      o->restart_in = argv[++i];
    } else if (IS("-l", "--list")) {
      MX_CHECK(need_arg(i, argc, a));
      o->list_in = argv[++i];
    } else if (strcmp(a, "--keep-invalid") == 0) {
      o->keep_invalid = 1;
    } else if (strcmp(a, "--repair-input") == 0) {
      o->repair_input = 1;
    } else if (strcmp(a, "--tets") == 0) {
      o->tets = 1;
    } else if (strcmp(a, "--materials") == 0) {
      o->materials = 1;
    } else if (strcmp(a, "--features") == 0) {
      MX_CHECK(need_arg(i, argc, a));
      o->feature_file = argv[++i];
    } else if (strcmp(a, "--feature-level") == 0) {
      MX_CHECK(need_arg(i, argc, a));
      MX_CHECK(parse_level(a, argv[++i], &o->feature_level));
    } else if (strcmp(a, "--no-features") == 0) {
      o->feature_angle = 0.0;
    } else if (strcmp(a, "--feature-angle") == 0) {
      MX_CHECK(need_arg(i, argc, a));
      char *end = NULL;
      const double v = strtod(argv[++i], &end);
      if (end == argv[i] || *end || !(v > 0.0 && v < 180.0)) {
        mx_error(NULL, 0, "--feature-angle needs an angle in degrees above 0 and below 180 "
                          "(e.g. 30), not '%s'", argv[i]);
        return MX_EINPUT;
      }
      o->feature_angle = v;
    } else if (strcmp(a, "--smooth") == 0) {
      MX_CHECK(need_arg(i, argc, a));
      char *end;
      const long v = strtol(argv[++i], &end, 10);
      if (end == argv[i] || *end || v < 0 || v > 1000) {
        mx_error(NULL, 0, "--smooth wants a number of rounds from 0 (off) to 1000, got '%s'",
                 argv[i]);
        return MX_EINPUT;
      }
      o->smooth_rounds = (int)v;
    } else if (strcmp(a, "--voxel") == 0) {
      o->image.voxel = 1;
    } else if (strcmp(a, "--label-names") == 0) {
      MX_CHECK(need_arg(i, argc, a));
      o->image.label_names = argv[++i];
    } else if (strcmp(a, "--min-island") == 0 || strcmp(a, "--interface-smoothing") == 0) {
      MX_CHECK(need_arg(i, argc, a));
      char *end = NULL;
      const long long v = strtoll(argv[++i], &end, 10);
      const int isl = a[2] == 'm';
      if (end == argv[i] || *end || v < 0 || v > (isl ? (1LL << 40) : 1000)) {
        mx_error(NULL, 0, "%s needs %s, not '%s'", a,
                 isl ? "a number of voxels (0 keeps every island)"
                     : "a number of smoothing rounds from 0 to 1000", argv[i]);
        return MX_EINPUT;
      }
      if (isl)
        o->image.min_island = v;
      else
        o->image.smooth_rounds = (int)v;
    } else if (strcmp(a, "--skip-labels") == 0 || strcmp(a, "--merge-labels") == 0 ||
               strcmp(a, "--label-size") == 0) {
      MX_CHECK(need_arg(i, argc, a));
      /* kind 0: labels; 1: pairs FROM:TO; 2: pairs LABEL:VOXELS */
      const int kind = a[2] == 's' ? 0 : a[2] == 'm' ? 1 : 2;
      int *count = kind == 0 ? &o->image.nskip : kind == 1 ? &o->image.nmerge
                                                            : &o->image.nlabel_size;
      int32_t *into = kind == 0 ? o->image_skip : kind == 1 ? o->image_merge : o->image_lsize;
      const char *c = argv[++i];
      while (*c) {
        char *end = NULL;
        const long x = strtol(c, &end, 10);
        long y = 0;
        int ok = end != c && x >= 0 && x <= 2147483647L;
        if (ok && kind) {
          ok = *end == ':';
          if (ok) {
            c = end + 1;
            y = strtol(c, &end, 10);
            ok = end != c && (kind == 1 ? y >= 0 && y <= 65535 : y >= 1 && y <= (1L << 20));
          }
        }
        ok = ok && (*end == ',' || !*end) && *count < 64;
        if (!ok) {
          mx_error(NULL, 0, "%s needs %s (at most 64), not '%s'", a,
                   kind == 0 ? "labels separated by commas, e.g. 4,5"
                   : kind == 1 ? "pairs FROM:TO separated by commas, e.g. 4:3,5:3"
                               : "pairs LABEL:VOXELS separated by commas, e.g. 2:1,3:2",
                   argv[i]);
          return MX_EINPUT;
        }
        if (kind) {
          into[2 * *count] = (int32_t)x;
          into[2 * (*count)++ + 1] = (int32_t)y;
        } else {
          into[(*count)++] = (int32_t)x;
        }
        c = *end ? end + 1 : end;
      }
      o->image.skip = o->image_skip;
      o->image.merge = o->image_merge;
      o->image.label_size = o->image_lsize;
    } else if (strcmp(a, "--material") == 0) {
      MX_CHECK(need_arg(i, argc, a));
      const char *spec = argv[++i];
      char *end = NULL;
      errno = 0;
      const long id = strtol(spec, &end, 10);
      if (!o->ninputs) {
        mx_error(NULL, 0, "--material %s: give it after the input it names (-i FILE "
                          "--material ID[:NAME])", spec);
        return MX_EINPUT;
      }
      if (end == spec || errno || id < 1 || id > 65535 || (*end && *end != ':')) {
        mx_error(NULL, 0, "--material %s: expected ID[:NAME], ID from 1 to 65535", spec);
        return MX_EINPUT;
      }
      o->material_id[o->ninputs - 1] = (int)id;
      o->material_name[o->ninputs - 1] = *end == ':' && end[1] ? end + 1 : NULL;
    } else if (strcmp(a, "--level") == 0 || strcmp(a, "--inside-level") == 0) {
      MX_CHECK(need_arg(i, argc, a));
      if (!o->ninputs) {
        mx_error(NULL, 0, "%s: give it after the input it refines (-i FILE %s L)", a, a);
        return MX_EINPUT;
      }
      int lv = 0;
      MX_CHECK(parse_level(a, argv[++i], &lv));
      if (a[2] == 'l') o->input_slevel[o->ninputs - 1] = lv;
      else o->input_ilevel[o->ninputs - 1] = lv;
    } else if (strcmp(a, "--json") == 0) {
      o->json = 1;
    } else if (strcmp(a, "--quiet") == 0) {
      o->quiet = 1;
    } else if (strcmp(a, "--ascii") == 0) {
      o->ascii = 1;
    } else if (strcmp(a, "--stage") == 0) {
      static const char *const w[] = {"octree", "transition", "full"};
      static const int v[] = {MX_STAGE_OCTREE, MX_STAGE_TRANSITION, MX_STAGE_FULL};
      MX_CHECK(need_arg(i, argc, a));
      MX_CHECK(parse_word(a, argv[++i], w, v, 3, &o->stage));
    } else if (strcmp(a, "--fields") == 0) {
      static const char *const w[] = {"all", "quality", "none"};
      static const int v[] = {MX_FIELDS_ALL, MX_FIELDS_QUALITY, MX_FIELDS_NONE};
      MX_CHECK(need_arg(i, argc, a));
      MX_CHECK(parse_word(a, argv[++i], w, v, 3, &o->fields));
    } else if (strcmp(a, "--balance") == 0) {
      static const char *const w[] = {"edges", "recursive"};
      static const int v[] = {MX_BALANCE_EDGES, MX_BALANCE_RECURSIVE};
      MX_CHECK(need_arg(i, argc, a));
      MX_CHECK(parse_word(a, argv[++i], w, v, 2, &o->balance));
    } else {
      mx_error(NULL, 0, "unknown option '%s' (see mixoct --help)", a);
      return MX_EINPUT;
    }
#undef IS
  }
  if (o->ninputs == 0 && !o->demo) {
    mx_error(NULL, 0, "no input: give -i FILE or --demo (see mixoct --help)");
    return MX_EINPUT;
  }
  if (o->ninputs > 0 && o->demo) {
    mx_error(NULL, 0, "--demo and -i exclude each other");
    return MX_EINPUT;
  }
  for (int k = 0; k < o->ninputs && !o->materials; k++)
    if (o->material_id[k]) {
      mx_error(NULL, 0, "--material: only with --materials (several materials)");
      return MX_EINPUT;
    }
  if (o->list_in && !o->restart_in) {
    mx_error(NULL, 0, "-l LIST refers to the elements of a mesh written with a "
                      "restart file: give that file with -c FILE.oct");
    return MX_EINPUT;
  }
  int images = 0;
  for (int k = 0; k < o->ninputs; k++) images += mx_is_label_image_path(o->inputs[k]);
  if (images && (o->restart_in || o->restart_out || o->list_in)) {
    mx_error(NULL, 0, "label images are not re-meshed yet: no restart file (-c, --restart) or "
                      "element list (-l) with one");
    return MX_EINPUT;
  }
  if (o->s_level < 0 && o->a_level < 0 && !o->regions_file && !o->nregion_surf && !images &&
      !o->restart_in && !o->size && !(o->size_max > 0.0) && !(o->curvature > 0.0) &&
      !(o->thickness > 0.0)) {
    mx_error(NULL, 0, "no refinement request: the mesh would be empty; give a level on "
                      "the surface (-s RL, e.g. -s 5), everywhere (-a RL), boxes (-b FILE.reg) "
                      "a region surface (-r S RL) or a size field (--size EXPR, --curvature DEG, "
                      "--thickness N)");
    return MX_EINPUT;
  }
  /* fail before meshing, not after a long run */
  MX_CHECK(mx_check_run_files(o)); /* first: an input named as output is that */
  for (int k = 0; k < o->noutputs; k++) MX_CHECK(mx_check_output_path(o->outputs[k], 1));
  if (o->restart_out) MX_CHECK(mx_check_output_path(o->restart_out, 0));
  if (o->boundary_out) {
    if (!mx_boundary_format_known(o->boundary_out)) {
      mx_error(o->boundary_out, 0, "--boundary writes .vtu (the boundary faces with their "
                                   "surface_tag and body), .ply (the same), .off or .stl");
      return MX_EINPUT;
    }
    if (o->stage != MX_STAGE_FULL) {
      mx_error(NULL, 0, "--boundary needs the full stage (the boundary on the input)");
      return MX_EINPUT;
    }
    MX_CHECK(mx_check_output_path(o->boundary_out, 0));
  }
  return MX_OK;
}

int mx_check_run_files(const mx_options *o) {
  enum { N = MX_MAX_INPUTS + MX_MAX_REGIONS + 2 * MX_MAX_OUTPUTS + 6 };
  mx_file_use u[N];
  char piece[MX_MAX_OUTPUTS][4096];
  int n = 0;
  for (int i = 0; i < o->ninputs; i++)
    u[n++] = (mx_file_use){o->inputs[i], "the input surface", MX_FILE_INPUT};
  for (int i = 0; i < o->nregion_surf; i++)
    u[n++] = (mx_file_use){o->region_surf[i], "the region surface", MX_FILE_INPUT};
  u[n++] = (mx_file_use){o->regions_file, "the boxes file", MX_FILE_INPUT};
  u[n++] = (mx_file_use){o->list_in, "the element list", MX_FILE_INPUT};
  if (o->size && access(o->size, F_OK) == 0)
    u[n++] = (mx_file_use){o->size, "the size map", MX_FILE_INPUT};
  u[n++] = (mx_file_use){o->restart_in, "the restart file read", MX_FILE_RESTART_IN};
  for (int k = 0; k < o->noutputs; k++) {
    u[n++] = (mx_file_use){o->outputs[k], "the mesh output", MX_FILE_OUTPUT};
    const char *dot = strrchr(o->outputs[k], '.');
    if (dot && strcasecmp(dot, ".pvtu") == 0) { /* its piece, written beside it */
      mx_pvtu_piece_path(o->outputs[k], 0, piece[k], sizeof piece[k]);
      u[n++] = (mx_file_use){piece[k], "the first piece of the .pvtu output", MX_FILE_OUTPUT};
    }
  }
  u[n++] = (mx_file_use){o->boundary_out, "the boundary output", MX_FILE_OUTPUT};
  u[n++] = (mx_file_use){o->restart_out, "the restart file written", MX_FILE_RESTART_OUT};
  return mx_check_file_uses(u, n);
}

int mx_check_output_path(const char *path, int mesh) {
  const char *dot = strrchr(path, '.');
  const char *slash = strrchr(path, '/');
  if (dot && slash && dot < slash) dot = NULL;
  if (mesh && (!dot || !mx_mesh_format_known(path))) {
    mx_error(path, 0, "unknown output format \"%s\" (use .vtk, .vtu, .pvtu, .msh, .mesh, "
                      ".meshb, .getfem, .m3d or .mvm)", dot ? dot : "");
    return MX_EINPUT;
  }
  struct stat st;
  if (stat(path, &st) == 0 && S_ISDIR(st.st_mode)) {
    mx_error(path, 0, "cannot write: is a directory");
    return MX_EIO;
  }
  /* the directory it goes to (the file is written there under a temporary
   * name, then renamed) */
  char dir[4096];
  if (!slash) {
    strcpy(dir, ".");
  } else if (slash == path) {
    strcpy(dir, "/");
  } else {
    const size_t n = (size_t)(slash - path);
    if (n >= sizeof dir) {
      mx_error(path, 0, "cannot write: the path is too long");
      return MX_EIO;
    }
    memcpy(dir, path, n);
    dir[n] = '\0';
  }
  if (stat(dir, &st) != 0 || !S_ISDIR(st.st_mode)) {
    mx_error(path, 0, "cannot write: the directory %s does not exist", dir);
    return MX_EIO;
  }
  if (access(dir, W_OK | X_OK) != 0) {
    mx_error(path, 0, "cannot write: %s (in the directory %s)", strerror(errno), dir);
    return MX_EIO;
  }
  return MX_OK;
}
