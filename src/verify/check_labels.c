/* Pass 5c of the checker, the cells' labels (several materials, issue 26):
 * when the file gives each cell a label (mx_mesh_data.cell_tag: a Gmsh
 * physical volume, the VTK/VTU field "material", a Medit reference), the
 * elements and the volume of each label, and the faces between cells of
 * two labels (the interfaces between materials), found with the face
 * buckets of check_faces.c. */
#include "verify/check_passes.h"

#include <math.h>

#include "base/scan.h"
#include "geom/distance.h"
#include "geom/quality.h"

int mx_ck_label_pass(const mx_mesh_data *m, const faces *F, mx_check_report *r) {
  r->nlabels = 0;
  r->labels_dropped = 0;
  r->labels_open = 0;
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
    r->labels[k] = (mx_check_label){t, 0, 0.0, -1, NAN, NAN, 0, 0};
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

int mx_ck_label_regions(const mx_mesh_data *m, const mx_trisoup *surface, mx_check_report *r) {
  if (!m->cell_tag || !r->nlabels || !surface->nt) return MX_OK;
  mx_surface_index S;
  MX_CHECK(mx_surface_index_build_outward(&S, surface, 0, (uint32_t)surface->nt));
  /* each shell's volume (outward) */
  double *vol = mx_alloc(((size_t)S.nshells + 1) * sizeof *vol);
  if (!vol) {
    mx_surface_index_free(&S);
    return MX_ENOMEM;
  }
  mx_surface_index_shell_volumes(&S, vol, NULL);
  /* region d (depth d: inside d shells): the shells at depth d - 1 less
   * those at depth d; the whole mesh: the outermost shells' */
  double region[66], outer = 0.0;
  for (int d = 0; d < 66; d++) region[d] = 0.0;
  for (uint32_t c = 0; c < S.nshells; c++) {
    const uint32_t e = S.shell_depth[c];
    if (e < 65) region[e + 1] += vol[c];
    if (e >= 1 && e < 66) region[e] -= vol[c];
    if (e == 0) outer += vol[c];
  }
  mx_free(vol);
  r->surface_volume = fabs(outer);
  r->volume_error = r->surface_volume > 0.0 ? (r->volume - r->surface_volume) / r->surface_volume
                                            : NAN;
  /* each label's region: where most of its elements' centroids lie */
  size_t (*count)[66] = mx_calloc((r->nlabels + 1) * sizeof *count);
  if (!count) {
    mx_surface_index_free(&S);
    return MX_ENOMEM;
  }
  for (size_t c = 0; c < m->ncells; c++) {
    size_t k = 0;
    while (k < r->nlabels && r->labels[k].label != m->cell_tag[c]) k++;
    if (k == r->nlabels) continue;
    const int nv = mx_cell_nodes[m->type[c]];
    double p[3] = {0, 0, 0};
    for (int j = 0; j < nv; j++)
      for (int a = 0; a < 3; a++) p[a] += m->xyz[3 * (size_t)m->conn[8 * c + j] + a] / nv;
    const int d = mx_region_depth(&S, p);
    count[k][d < 65 ? d : 65]++;
  }
  mx_surface_index_free(&S);
  for (size_t k = 0; k < r->nlabels; k++) {
    int best = 0;
    for (int d = 1; d < 66; d++)
      if (count[k][d] > count[k][best]) best = d;
    mx_check_label *L = &r->labels[k];
    L->region = best;
    L->region_volume = region[best];
    L->volume_error = fabs(region[best]) > 0.0 ? (L->volume - region[best]) / fabs(region[best])
                                               : NAN;
  }
  mx_free(count);
  return MX_OK;
}

void mx_ck_label_verdict(mx_check_report *r) {
  r->labels_off = 0;
  for (size_t k = 0; k < r->nlabels; k++)
    if (r->labels[k].region >= 0 && !(fabs(r->labels[k].volume_error) <= r->opt.volume_tol))
      r->labels_off++;
}

int mx_ck_label_boundaries(const mx_mesh_data *m, const faces *F, mx_check_report *r) {
  if (!m->cell_tag || !r->nlabels) return MX_OK;
  const size_t nc = m->ncells;
  size_t cap = 0;
  uint64_t *key = NULL;
  for (size_t k = 0; k < r->nlabels; k++) {
    const int32_t L = r->labels[k].label;
    /* the edges of the faces that bound the label: used once, or shared
     * with a cell of another label */
    size_t n = 0;
    for (size_t c = 0; c < nc; c++) {
      if (m->cell_tag[c] != L) continue;
      const int t = m->type[c];
      for (int f = 0; f < mx_cell_nfaces[t]; f++) {
        const int8_t *fv = mx_cell_faces[t][f];
        const int nv = fv[3] < 0 ? 3 : 4;
        const uint8_t use = F->use[6 * c + (size_t)f];
        if (use == 2) {
          uint32_t v[4] = {0, 0, 0, 0};
          for (int j = 0; j < nv; j++) v[j] = m->conn[8 * c + (size_t)fv[j]];
          sort4(v, nv);
          const int64_t s = mx_ck_find_slot(m, F, v, nv), s2 = mx_ck_find_second(m, F, v, nv);
          const int64_t other = s == (int64_t)(6 * c + (size_t)f) ? s2 : s;
          if (other >= 0 && m->cell_tag[other / 6] == L) continue;
        } else if (use != 1) {
          continue;
        }
        if (n + 4 > cap) {
          const size_t nc2 = cap ? 2 * cap : 4096;
          uint64_t *grown = mx_realloc(key, nc2 * sizeof *key);
          if (!grown) {
            mx_free(key);
            return MX_ENOMEM;
          }
          key = grown;
          cap = nc2;
        }
        for (int j = 0; j < nv; j++) {
          const uint32_t a = m->conn[8 * c + (size_t)fv[j]], b = m->conn[8 * c + (size_t)fv[(j + 1) % nv]];
          key[n++] = a < b ? (uint64_t)a << 32 | b : (uint64_t)b << 32 | a;
        }
      }
    }
    const int st = n ? mx_sort_u64(key, NULL, n) : MX_OK;
    if (st) {
      mx_free(key);
      return st;
    }
    size_t open = 0, over = 0;
    for (size_t i = 0; i < n;) {
      size_t j = i + 1;
      while (j < n && key[j] == key[i]) j++;
      open += (j - i) % 2;
      over += j - i > 2;
      i = j;
    }
    r->labels[k].open_edges = open;
    r->labels[k].nonmanifold_edges = over;
    r->labels_open += open > 0;
  }
  mx_free(key);
  return MX_OK;
}
