/* The machine's topology as one line, from hwloc when it was built in:
 * packages, NUMA nodes, cores, hardware threads (PUs), how many PUs this
 * process may run on (fewer under Slurm's --cpus-per-task, taskset or
 * numactl), and the OpenMP thread count. Printed by --version and in the
 * JSON summary (so it never holds a double quote or a backslash). */
#include "cli.h"

#include <omp.h>
#include <stdio.h>

#ifdef MX_HAVE_HWLOC
#include <hwloc.h>
#endif

void mx_topology_string(char *buf, size_t n) {
#ifdef MX_HAVE_HWLOC
  hwloc_topology_t topo;
  if (hwloc_topology_init(&topo) == 0) {
    if (hwloc_topology_load(topo) == 0) {
      const int pk = hwloc_get_nbobjs_by_type(topo, HWLOC_OBJ_PACKAGE);
      const int nu = hwloc_get_nbobjs_by_type(topo, HWLOC_OBJ_NUMANODE);
      const int co = hwloc_get_nbobjs_by_type(topo, HWLOC_OBJ_CORE);
      const int pu = hwloc_get_nbobjs_by_type(topo, HWLOC_OBJ_PU);
      /* The PUs this process may use, as the OpenMP runtime saw them at
       * start-up (hwloc_get_cpubind would see only the initial thread, which
       * the runtime pins to the first place under OMP_PROC_BIND). */
      const int bound = omp_get_num_procs();
#ifdef HWLOC_VERSION
      const char *version = HWLOC_VERSION; /* the library built against */
#else
      const char *version = "2.x";
#endif
      char allowed[64] = "";
      if (bound > 0 && bound < pu)
        snprintf(allowed, sizeof allowed, ", %d available to this process", bound);
      snprintf(buf, n, "hwloc %s: %d package(s), %d NUMA node(s), %d core(s), "
               "%d PU(s)%s; OpenMP max threads %d", version, pk, nu, co, pu,
               allowed, omp_get_max_threads());
      hwloc_topology_destroy(topo);
      return;
    }
    hwloc_topology_destroy(topo);
  }
#endif
  snprintf(buf, n, "no hwloc; %d processor(s) available; OpenMP max threads %d",
           omp_get_num_procs(), omp_get_max_threads());
}
