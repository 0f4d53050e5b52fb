/* The mixoct program: options, the run, the commands (src/cli/). It uses
 * the library through include/mixoct.h only. */
#ifndef MX_CLI_H
#define MX_CLI_H

#include <stddef.h>
#include <stdint.h>

#include "mixoct.h" /* the only header of the library the programs use */

#define MX_MAX_INPUTS 64
#define MX_MAX_OUTPUTS 16 /* meshes; with the boundary and the restart file:
                          * MX_RUN_FILES (mixoct.h) */
_Static_assert(MX_MAX_OUTPUTS + 2 <= MX_RUN_FILES, "the report lists every file");

typedef struct {
  const char *inputs[MX_MAX_INPUTS];
  int ninputs;
  int demo;              /* --demo: the built-in surface */
  const char *output;    /* NULL: dry run */
  /* More files of the same mesh (the mesher_roi front's -v -g -m): when
   * noutputs > 0, outputs[0] == output and mx_run writes each of them. */
  const char *outputs[MX_MAX_OUTPUTS];
  int noutputs;
  const char *regions_file;
  const char *size;      /* --size EXPR|F1..F5: a size field (NULL: none) */
  double size_min, size_max; /* --size-min, --size-max (0: none) */
  double curvature, thickness, gradation; /* --curvature DEG, --thickness N,
                                             --gradation BETA (0: none) */
  const char *size_field;  /* --size-field NAME: the field of a size map file */
  const char *region_surf[MX_MAX_REGIONS];
  int nregion_surf;
  int s_level, a_level;  /* -s, -a: -1 none */
  int rlevel[MX_MAX_REGIONS]; /* -r SURF LEVEL */
  int threads;           /* 0: OpenMP default */
  int json, quiet;
  int ascii;             /* --ascii: the ASCII variant of .vtk / .msh */
  int fields;            /* --fields: MX_FIELDS_* */
  int stage;
  int balance;
  double max_memory_mb; /* 0: the memory available */
  const char *restart_out; /* --restart FILE: write the restart file */
  const char *boundary_out; /* --boundary FILE.vtu: the tagged boundary faces */
  const char *restart_in;  /* -c FILE: re-mesh from a restart file */
  const char *list_in;     /* -l LIST: elements to refine */
  int keep_invalid;        /* write a mesh with invalid elements (exit 5) */
  int repair_input;        /* --repair-input: winding-number domain */
  int materials;           /* --materials: nested shells are materials */
  int material_id[MX_MAX_INPUTS];            /* --material ID[:NAME] after -i */
  const char *material_name[MX_MAX_INPUTS]; /* (0 / NULL: not given) */
  int input_slevel[MX_MAX_INPUTS];          /* --level L after -i (0: none) */
  int input_ilevel[MX_MAX_INPUTS];          /* --inside-level L after -i (0: none) */
  /* label images: --voxel, --min-island N, --skip-labels, --merge-labels,
   * --label-names FILE, --interface-smoothing N, --label-size (the arrays
   * below) */
  mx_image_params image;
  double feature_angle; /* --feature-angle DEG, --no-features (0); -1: the default */
  int feature_level;    /* --feature-level L (0: the surface level) */
  const char *feature_file; /* --features FILE (NULL: found on the surface) */
  int smooth_rounds;    /* --smooth N; -1: the library's default */
  int32_t image_skip[64], image_merge[128], image_lsize[128];
  int tets;             /* --tets: the final mesh split into tetrahedra */
} mx_options;

/* Parses argv; on --help/--version prints and sets *exit_now = 1. Returns
 * MX_OK or MX_EINPUT (usage error, message printed). */
int mx_parse_options(int argc, char **argv, mx_options *o, int *exit_now);
/* The value of --size-min / --size-max (opt): a positive finite number,
 * else MX_EINPUT with a message (mixoct and mesher2d alike). */
int mx_parse_size_bound(const char *opt, const char *s, double *out);

/* Before meshing: the output's format is known (mesh = 1), it is not a
 * directory, and its directory exists and is writable. MX_EINPUT / MX_EIO
 * with a message naming it. */
int mx_check_output_path(const char *path, int mesh);
/* Before reading: no output is an input or another output (by file
 * identity, io/file_identity.h). MX_EINPUT with a message naming both. */
int mx_check_run_files(const mx_options *o);
/* The surfaces (--demo, -i), region surfaces (-r) and boxes (-b) of the
 * options added to m (src/cli/main.c; also the --p4est front). */
int mx_add_inputs(const mx_options *o, mx_mesher *m);

/* The OpenMP wait policy of this run: "passive (set by mixoct)", the
 * user's OMP_WAIT_POLICY, or "default" (src/cli/main.c). */
const char *mx_wait_policy_name(void);

/* One line describing the machine (hwloc when built in, OpenMP threads). */
void mx_topology_string(char *buf, size_t n);

/* The pipeline: read, mesh, write o->output (and o->outputs[1..]), report
 * (src/cli/main.c). Returns MX_OK or an error code, message printed. */
int mx_run(const mx_options *o);
/* The program invoked as `mesher_roi`: the published mesher's flags
 * (src/cli/mesher_roi.c). Returns the exit code. */
int mx_mesher_roi_main(int argc, char **argv);
/* The program invoked as `mesher2d`: the 2D mixed quadtree mesher
 * (src/cli/mesher2d.c, over mixoct.h's mx_mesher2d_*). Returns the exit code. */
int mx_mesher2d_main(int argc, char **argv);

/* `mixoct check MESH [--surface FILE ...] [--json]` (src/cli/check_cmd.c: the
 * options; include/mixoct.h: mx_check_file does the rest). */
int mx_check_main(int argc, char **argv);
/* `mpirun -n N mixoct ... --p4est`: the distributed path (src/cli/p4est_cmd.c;
 * builds with MPI only). Returns the exit code. */
int mx_p4est_main(int argc, char **argv);
/* `mixoct patterns [--json]` (src/cli/patterns_cmd.c). */
int mx_patterns_main(int argc, char **argv);

#endif
