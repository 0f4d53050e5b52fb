/* Pass 5c of the checker, the cells' labels (several materials, issue 26):
 * when the file gives each cell a label (mx_mesh_data.cell_tag: a Gmsh
 * physical volume, the VTK/VTU field "material", a Medit reference), the
 * elements and the volume of each label, and the faces between cells of
 * two labels (the interfaces between materials), found with the face
 * buckets of check_faces.c. */
#include "verify/check_passes.h"

#include "geom/quality.h"

int mx_ck_label_pass(const mx_mesh_data *m, const faces *F, mx_check_report *r) {
  r->nlabels = 0;
  r->labels_dropped = 0;
  r->interface_faces = 0;
  if (!m->cell_tag) return MX_OK;
  const size_t nc = m->ncells;
  /* the labels met, in ascending order (few: a linear table) */
  for (size_t c = 0; c < nc; c++) {
    const int32_t t = m->cell_tag[c];
    size_t k = 0;
    while (k < r->nlabels && r->labels[k].label < t) k++;
    if (k < r->nlabels && r->labels[k].label == t) continue;
    if (r->nlabels == MX_CHECK_LABELS) {
      r->labels_dropped++;
      continue;
    }
    memmove(r->labels + k + 1, r->labels + k, (r->nlabels - k) * sizeof *r->labels);
    r->labels[k] = (mx_check_label){t, 0, 0.0};
    r->nlabels++;
  }
  for (size_t c = 0; c < nc; c++) {
    size_t k = 0;
    while (k < r->nlabels && r->labels[k].label != m->cell_tag[c]) k++;
    if (k == r->nlabels) continue;
    double p[8][3];
    const int nv = mx_cell_nodes[m->type[c]];
    for (int j = 0; j < nv; j++)
      memcpy(p[j], m->xyz + 3 * (size_t)m->conn[8 * c + j], sizeof p[j]);
    r->labels[k].cells++;
    r->labels[k].volume += mx_element_volume(m->type[c], (const double(*)[3])p);
  }
  /* the faces between two labels: each counted from its first slot */
  size_t between = 0;
#pragma omp parallel for schedule(dynamic, 1024) reduction(+ : between) if (nc > SMALL)
  for (size_t c = 0; c < nc; c++) {
    const int t = m->type[c];
    for (int f = 0; f < mx_cell_nfaces[t]; f++) {
      if (F->use[6 * c + (size_t)f] != 2) continue;
      const int8_t *fv = mx_cell_faces[t][f];
      const int n = fv[3] < 0 ? 3 : 4;
      uint32_t v[4] = {0, 0, 0, 0};
      for (int j = 0; j < n; j++) v[j] = m->conn[8 * c + (size_t)fv[j]];
      sort4(v, n);
      const int64_t s = mx_ck_find_slot(m, F, v, n);
      const int64_t s2 = mx_ck_find_second(m, F, v, n);
      if (s != (int64_t)(6 * c + (size_t)f) || s2 < 0) continue;
      between += m->cell_tag[s / 6] != m->cell_tag[s2 / 6];
    }
  }
  r->interface_faces = between;
  return MX_OK;
}
