/* --tets (mx_params.tets): the final mesh split into tetrahedra
 * (kernels/tet_split.h), then checked again by the independent checker
 * (verify/check.h), so that a run that succeeds still means a valid,
 * conforming mesh of the same volume. The mixed mesh is kept beside the
 * tetrahedra: a re-mesh after a refinement starts from it. */
#include <math.h>
#include <string.h>

#include "kernels/boundary.h" /* MX_NODE_INSIDE */
#include "geom/quality.h"
#include "kernels/tet_split.h"
#include "mesher/pipeline.h"
#include "mesher/mesher_impl.h"
#include "verify/check.h"

/* The volume of the mixed mesh with each quadrilateral face cut by the
 * diagonal through its node of the smallest index (the faces the
 * tetrahedra have): per element, the signed volume its boundary triangles
 * enclose (divergence theorem, from the element's first node). What the
 * tetrahedra of each element must add up to, whichever split was taken.
 * Summed in fixed chunks (the same for any thread count). */
static double volume_cut_faces(const mx_mesh *M) {
  const size_t chunk = 4096, nch = (M->ncells + chunk - 1) / chunk;
  double total = 0.0;
  for (size_t b0 = 0; b0 < nch; b0 += 256) { /* 256 chunk sums at a time */
    double part[256];
    const size_t nb = nch - b0 < 256 ? nch - b0 : 256;
#pragma omp parallel for schedule(static)
    for (size_t b = 0; b < nb; b++) {
      double s = 0.0;
      const size_t c1 = (b0 + b + 1) * chunk < M->ncells ? (b0 + b + 1) * chunk : M->ncells;
      for (size_t c = (b0 + b) * chunk; c < c1; c++) {
        const int type = M->type[c];
        const uint32_t *cn = M->conn + 8 * c;
        const double *o = M->xyz + 3 * (size_t)cn[0];
        for (int f = 0; f < mx_cell_nfaces[type]; f++) {
          const int8_t *q = mx_cell_faces[type][f];
          int t[2][3] = {{q[0], q[1], q[2]}, {-1, -1, -1}};
          if (q[3] >= 0) {
            const uint32_t m02 = cn[q[0]] < cn[q[2]] ? cn[q[0]] : cn[q[2]];
            const uint32_t m13 = cn[q[1]] < cn[q[3]] ? cn[q[1]] : cn[q[3]];
            if (m02 < m13) { /* diagonal q0-q2 */
              t[1][0] = q[0], t[1][1] = q[2], t[1][2] = q[3];
            } else { /* diagonal q1-q3 */
              t[0][0] = q[0], t[0][1] = q[1], t[0][2] = q[3];
              t[1][0] = q[1], t[1][1] = q[2], t[1][2] = q[3];
            }
          }
          for (int k = 0; k < 2 && t[k][0] >= 0; k++) {
            double a[3], bb[3], d[3];
            for (int i = 0; i < 3; i++) {
              a[i] = M->xyz[3 * (size_t)cn[t[k][0]] + i] - o[i];
              bb[i] = M->xyz[3 * (size_t)cn[t[k][1]] + i] - o[i];
              d[i] = M->xyz[3 * (size_t)cn[t[k][2]] + i] - o[i];
            }
            /* outward face: the enclosed volume is +det / 6 */
            s += (a[0] * (bb[1] * d[2] - bb[2] * d[1]) - a[1] * (bb[0] * d[2] - bb[2] * d[0]) +
                  a[2] * (bb[0] * d[1] - bb[1] * d[0])) / 6.0;
          }
        }
      }
      part[b] = s;
    }
    for (size_t b = 0; b < nb; b++) total += part[b];
  }
  return total;
}

int mx_mesher_tets(mx_mesher *m) {
  if (!m->p.tets || m->have_mix || m->mesh_stage < MX_STAGE_TRANSITION || !m->M.ncells)
    return MX_OK;
  mx_written_forget(m); /* the mesh becomes its tetrahedra */
  mx_summary *S = &m->rec->S;
  char inputs[MX_INPUTS_LABEL];
  const char *name = mx_inputs_label(m, inputs, sizeof inputs);
  MX_CHECK(mx_mesher_stage(m, "tets")); /* MX_ECANCELED: cancelled */
  mx_mesh T;
  mx_tet_split_stats ts;
  uint32_t *parent = NULL;
  MX_CHECK(mx_mesh_split_tets(&m->M, &T, &parent, &ts));
  /* the check: the checker's defects (J_ENS, faces matched and oriented,
   * closed boundary, hanging nodes, unused and duplicate nodes), and the
   * volume against the mixed elements' with the same boundary triangles */
  const double t = mx_wtime();
  const mx_mesh_data d = mx_mesh_data_of(&T);
  mx_check_options o;
  mx_check_defaults(&o);
  mx_check_report r;
  int st = mx_check_mesh_opt(&d, NULL, &o, &r);
  const double vmix = volume_cut_faces(&m->M);
  S->t_tets_check = mx_wtime() - t;
  if (!st && r.defects) {
    mx_error(name, 0, "the tetrahedra cut from the mesh fail the check: %zu defect(s) "
             "(%zu invalid, %zu degenerate, %zu faces shared by 3 or more, %zu misoriented, "
             "%zu open boundary edges, %zu hanging nodes, %zu on faces)", r.defects, r.invalid,
             r.degenerate, r.faces_overshared, r.faces_misoriented, r.open_boundary_edges,
             r.hanging_nodes, r.geometric_hanging_nodes);
    st = MX_EINVALID;
  }
  if (!st && !(fabs(r.volume - vmix) <= 1e-9 * fabs(vmix))) {
    mx_error(name, 0, "the tetrahedra cut from the mesh hold a volume of %.17g, the mixed "
             "elements %.17g", r.volume, vmix);
    st = MX_EINVALID;
  }
  uint8_t *states = NULL, *bnd = NULL;
  if (!st && m->states) {
    states = mx_realloc(m->states, T.nnodes + 1);
    if (!states) st = MX_ENOMEM;
    else m->states = states;
  }
  if (!st && m->bnd) {
    bnd = mx_realloc(m->bnd, T.nnodes + 1);
    if (!bnd) st = MX_ENOMEM;
    else m->bnd = bnd;
  }
  if (st) {
    mx_mesh_free(&T);
    mx_free(parent);
    return st;
  }
  /* the Steiner nodes: inside, off the boundary */
  for (size_t v = m->M.nnodes; v < T.nnodes; v++) {
    if (m->states) m->states[v] = MX_NODE_INSIDE;
    if (m->bnd) m->bnd[v] = 0;
  }
  S->tets = 1;
  S->tets_from = m->M.ncells;
  memcpy(S->tets_from_by_type, m->M.by_type, sizeof S->tets_from_by_type);
  S->tets_made = ts.tets;
  S->tets_steiner = ts.steiner;
  S->tets_five = ts.five;
  S->t_tets = ts.seconds;
  S->tets_volume = r.volume;
  S->tets_volume_mixed = vmix;
  S->tets_volume_fan = mx_mesh_volume(&m->M);
  m->Mmix = m->M;
  m->M = T;
  m->tet_parent = parent;
  m->have_mix = 1;
  /* the figures of the mesh the caller gets */
  S->nodes = m->M.nnodes;
  S->elements = m->M.ncells;
  memcpy(S->by_type, m->M.by_type, sizeof S->by_type);
  S->jens_min = m->M.jens_min;
  S->invalid = m->M.invalid;
  mx_quality_tabulate(m->M.type, m->M.jens, m->M.ncells, &S->quality);
  S->ph.verify += S->t_tets_check;
  return MX_OK;
}

void mx_mesher_untets(mx_mesher *m) {
  if (!m->have_mix) return;
  mx_written_forget(m);
  mx_mesh_free(&m->M);
  m->M = m->Mmix;
  memset(&m->Mmix, 0, sizeof m->Mmix);
  mx_free(m->tet_parent);
  m->tet_parent = NULL;
  m->have_mix = 0;
}
