/* The machine's topology as one line, from hwloc when it was built in. */
#include "cli/cli.h"

#include <omp.h>
#include <stdio.h>

#ifdef MX_HAVE_HWLOC
#include <hwloc.h>
#endif

void mx_topology_string(char *buf, size_t n) {
#ifdef MX_HAVE_HWLOC
  hwloc_topology_t topo;
  if (hwloc_topology_init(&topo) == 0 && hwloc_topology_load(topo) == 0) {
    int pk = hwloc_get_nbobjs_by_type(topo, HWLOC_OBJ_PACKAGE);
    int nu = hwloc_get_nbobjs_by_type(topo, HWLOC_OBJ_NUMANODE);
    int co = hwloc_get_nbobjs_by_type(topo, HWLOC_OBJ_CORE);
    int pu = hwloc_get_nbobjs_by_type(topo, HWLOC_OBJ_PU);
    snprintf(buf, n, "hwloc %s: %d package(s), %d NUMA node(s), %d core(s), "
             "%d PU(s); OpenMP max threads %d", HWLOC_API_VERSION >= 0x20000 ?
             "2.x" : "1.x", pk, nu, co, pu, omp_get_max_threads());
    hwloc_topology_destroy(topo);
    return;
  }
#endif
  snprintf(buf, n, "no hwloc; OpenMP max threads %d", omp_get_max_threads());
}
