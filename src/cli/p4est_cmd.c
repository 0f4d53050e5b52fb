/* `mpirun -n N mixoct -i SURF -s L --p4est [-o OUT.pvtu|OUT.msh] [--json]
 * [--materials] [--p4est-compare] [--stage octree]`: the distributed path (MPI builds
 * only, meson -Dmpi). The program's options, without --p4est and
 * --p4est-compare, become an mx_p4est_run_params; the library does the rest
 * (include/mixoct.h, "The distributed path"; src/mpi/p4est_run.c). MPI is
 * set up first, so that only rank 0 prints the usage errors. */
#include "cli.h"
#include "mixoct.h"

#include <string.h>


/* The options the distributed path reads (it refuses the others). */
static void run_params(const mx_options *o, int compare, mx_p4est_run_params *p) {
  memset(p, 0, sizeof *p);
  p->surfaces = o->inputs;
  p->nsurfaces = o->ninputs;
  p->material_ids = o->material_id;
  p->material_names = o->material_name;
  p->surface_levels = o->input_slevel;
  p->inside_levels = o->input_ilevel;
  p->materials = o->materials;
  p->demo = o->demo;
  p->region_surfaces = o->region_surf;
  p->region_levels = o->rlevel;
  p->nregions = o->nregion_surf;
  p->boxes_file = o->regions_file;
  p->surface_level = o->s_level;
  p->all_level = o->a_level;
  p->stage = o->stage;
  p->threads = o->threads;
  p->max_memory_mb = o->max_memory_mb;
  p->repair_input = o->repair_input;
  p->outputs = o->outputs;
  p->noutputs = o->noutputs;
  p->ascii = o->ascii;
  p->json = o->json;
  p->quiet = o->quiet;
  p->compare = compare;
}

int mx_p4est_main(int argc, char **argv) {
  mx_p4est_init(&argc, &argv);
  /* our flags out, the rest parsed as usual */
  char **av = mx_alloc(((size_t)argc + 1) * sizeof *av);
  int ac = 0, compare = 0;
  for (int i = 0; av && i < argc; i++) {
    if (strcmp(argv[i], "--p4est") == 0) continue;
    if (strcmp(argv[i], "--p4est-compare") == 0) {
      compare = 1;
      continue;
    }
    av[ac++] = argv[i];
  }
  mx_options o;
  int exit_now = 0;
  int st = av ? mx_parse_options(ac, av, &o, &exit_now) : MX_ENOMEM;
  if (!st && !exit_now && (o.restart_out || o.restart_in || o.boundary_out || o.size || o.size_min > 0.0 ||
                            o.size_max > 0.0 || o.curvature > 0.0 || o.thickness > 0.0 ||
                            o.gradation > 0.0)) {
    mx_error(NULL, 0, "--p4est: no -c, --restart, --boundary or --size (nor --curvature, --thickness, --gradation: the distributed path "
                      "meshes from the surfaces and levels only)");
    st = MX_EINPUT;
  }
  if (!st && !exit_now && (o.feature_file || o.feature_angle > 0.0 || o.feature_level > 0 || o.smooth_rounds > 0)) {
    /* the distributed path places no sharp features yet (issue 29): its
     * boundary is that of --no-features, which it says it runs */
    mx_error(NULL, 0, "--p4est: no --features, --feature-angle, --feature-level or --smooth (the distributed "
                      "path keeps no sharp features yet: its boundary is that of --no-features)");
    st = MX_EINPUT;
  }
  if (!st && !exit_now && o.tets) {
    mx_error(NULL, 0, "--p4est: no --tets (the distributed path writes its mixed mesh; split it "
                      "with the single-process mesher)");
    st = MX_EINPUT;
  }
  if (!st && !exit_now) {
    mx_p4est_run_params p;
    run_params(&o, compare, &p);
    st = mx_p4est_run(&p);
  }
  mx_free(av);
  mx_p4est_finalize();
  return st;
}
