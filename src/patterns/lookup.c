#include "patterns/lookup.h"

#include <pthread.h>
#include <stdlib.h>

#include "base/common.h"
#include "geom/quality.h"
#include "patterns/lattice.h"
#include "soa/mesh.h"

static mx_pattern_ref *lut;
double *mx_pattern_elem_jens;
/* built once, by the first call that can (one that ran out of memory
 * leaves nothing, and the next call tries again) */
static int built;
static pthread_mutex_t build_lock = PTHREAD_MUTEX_INITIALIZER;

static int find_class(uint32_t canon) {
  int lo = 0, hi = mx_pattern_nclasses - 1;
  while (lo <= hi) {
    int mid = (lo + hi) / 2;
    uint32_t m = mx_pattern_classes[mid].mask & ~(1u << MX_LAT_CENTRE);
    if (m == canon) return mid;
    if (m < canon) lo = mid + 1;
    else hi = mid - 1;
  }
  return -1;
}

static int build(void) {
  mx_lattice_init();
  lut = mx_alloc(sizeof(mx_pattern_ref) << MX_CONFIG_BITS);
  mx_pattern_elem_jens = mx_alloc((size_t)mx_pattern_nelems * sizeof(double));
  if (!lut || !mx_pattern_elem_jens) {
    mx_free(lut);
    mx_free(mx_pattern_elem_jens);
    lut = NULL;
    mx_pattern_elem_jens = NULL;
    return MX_ENOMEM;
  }
  int init_status = MX_OK;
#pragma omp parallel for schedule(static)
  for (uint32_t c = 0; c < (1u << MX_CONFIG_BITS); c++) {
    lut[c].cls = 0xffff;
    lut[c].rot = 0;
    if (!mx_config_valid(c)) continue;
    const uint32_t m = 0xffu | (c << 8);
    uint32_t best = m;
    int rbest = 0;
    for (int r = 1; r < 24; r++) {
      uint32_t x = mx_rotate_mask(r, m);
      if (x < best) {
        best = x;
        rbest = r;
      }
    }
    const int k = find_class(best);
    if (k < 0) {
      init_status = MX_EINTERNAL;
      continue;
    }
    lut[c].cls = (uint16_t)k;
    lut[c].rot = mx_rot_inv[rbest]; /* canonical -> this octant */
  }
  for (int k = 0; k < mx_pattern_nelems; k++) {
    double x[8][3];
    const mx_pattern_elem *e = &mx_pattern_elems[k];
    for (int v = 0; v < mx_cell_nodes[e->type]; v++)
      for (int a = 0; a < 3; a++) x[v][a] = mx_lat_xyz[e->v[v]][a];
    mx_pattern_elem_jens[k] = mx_jens(e->type, x);
  }
  if (init_status != MX_OK) {
    mx_error(NULL, 0, "the compiled pattern table misses configurations: "
                      "regenerate src/patterns/table.c with tools/patterngen");
    mx_free(lut);
    mx_free(mx_pattern_elem_jens);
    lut = NULL;
    mx_pattern_elem_jens = NULL;
  }
  return init_status;
}

int mx_patterns_init(void) {
  if (__atomic_load_n(&built, __ATOMIC_ACQUIRE)) return MX_OK;
  pthread_mutex_lock(&build_lock);
  int st = MX_OK;
  if (!built) {
    st = build();
    if (st == MX_OK) __atomic_store_n(&built, 1, __ATOMIC_RELEASE);
  }
  pthread_mutex_unlock(&build_lock);
  return st;
}

mx_pattern_ref mx_pattern_lookup(uint32_t config) { return lut[config]; }
