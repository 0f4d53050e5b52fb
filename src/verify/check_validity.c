/* Pass 1 of the checker, validity: the J_ENS (geom/quality.h) of every
 * element -- invalid when <= 0 or not a number, degenerate when below
 * degenerate_below -- their minimum and mean, the signed volume of the mesh
 * (mx_element_volume), the counts per type, and which nodes are used.
 * Chunks of CHUNK elements in parallel, their sums added in chunk order,
 * so the numbers do not depend on the thread count. */
#include "verify/check_passes.h"

#include "geom/quality.h"
#include "soa/mesh.h"

typedef struct {
  double vol, jsum, jmin;
  size_t invalid, degenerate, by[4];
} elem_acc;

/* J_ENS is invariant under scaling: elements whose coordinates reach beyond
 * 2^400 or stay below 2^-400 (where squares and triple products would
 * overflow or underflow) are scaled by a power of two first, which is
 * exact. Others are evaluated as they are, so their J_ENS is bit-identical
 * to mx_jens's. */
static double jens_scaled(int t, double p[8][3]) {
  const int nn = mx_cell_nodes[t];
  double mx = 0.0;
  for (int j = 0; j < nn; j++)
    for (int a = 0; a < 3; a++) mx = mx_max(mx, fabs(p[j][a]));
  if (mx > 0x1p400 || (mx > 0.0 && mx < 0x1p-400)) {
    int e;
    frexp(mx, &e);
    double q[8][3];
    for (int j = 0; j < nn; j++)
      for (int a = 0; a < 3; a++) q[j][a] = ldexp(p[j][a], -e);
    return mx_jens(t, (const double(*)[3])q);
  }
  return mx_jens(t, (const double(*)[3])p);
}

int mx_ck_element_pass(const mx_mesh_data *m, uint8_t *flags, uint8_t *ef,
                        double degen_below, mx_check_report *r) {
  const size_t nc = m->ncells, nchunks = (nc + CHUNK - 1) / CHUNK;
  elem_acc *acc = mx_alloc((nchunks + 1) * sizeof *acc);
  if (!acc) return MX_ENOMEM;
#pragma omp parallel for schedule(dynamic, 1) if (nchunks > 1)
  for (size_t k = 0; k < nchunks; k++) {
    elem_acc a = {0.0, 0.0, INFINITY, 0, 0, {0, 0, 0, 0}};
    const size_t end = (k + 1) * CHUNK < nc ? (k + 1) * CHUNK : nc;
    for (size_t c = k * CHUNK; c < end; c++) {
      const int t = m->type[c], nn = mx_cell_nodes[t];
      const uint32_t *row = m->conn + 8 * c;
      double p[8][3];
      for (int j = 0; j < nn; j++) {
        memcpy(p[j], m->xyz + 3 * (size_t)row[j], sizeof p[j]);
        if (!(flag_get(&flags[row[j]]) & F_USED))
          flag_or(&flags[row[j]], F_USED);
      }
      const double q = jens_scaled(t, p);
      a.vol += mx_element_volume(t, (const double(*)[3])p);
      a.jsum += q;
      if (q < a.jmin) a.jmin = q;
      if (!(q > 0.0)) {
        a.invalid++;
        ef[c] |= 1u << MX_CK_INVALID; /* this pass alone writes ef */
      } else if (q < degen_below) {
        a.degenerate++;
        ef[c] |= 1u << MX_CK_DEGENERATE;
      }
      a.by[t]++;
    }
    acc[k] = a;
  }
  double vol = 0.0, jsum = 0.0, jmin = INFINITY;
  for (size_t k = 0; k < nchunks; k++) {
    vol += acc[k].vol;
    jsum += acc[k].jsum;
    if (acc[k].jmin < jmin) jmin = acc[k].jmin;
    r->invalid += acc[k].invalid;
    r->degenerate += acc[k].degenerate;
    for (int t = 0; t < 4; t++) r->by_type[t] += acc[k].by[t];
  }
  mx_free(acc);
  r->volume = vol;
  r->jens_min = nc ? jmin : NAN;
  r->jens_mean = nc ? jsum / (double)nc : NAN;
  return MX_OK;
}
