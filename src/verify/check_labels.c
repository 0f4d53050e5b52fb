/* Pass 5c of the checker, the cells' labels (several materials, issue 26):
 * when the file gives each cell a label (mx_mesh_data.cell_tag: a Gmsh
 * physical volume, the VTK/VTU field "material", a Medit reference), the
 * elements and the volume of each label, and the faces between cells of
 * two labels (the interfaces between materials), found with the face
 * buckets of check_faces.c, whose nodes are flagged as interface nodes
 * (check_distance.c measures them against the surface); each label's
 * boundary closed; with a surface, each label's region (check_regions.c
 * finds each element's; with a surface of several files the regions are
 * its pieces', check_pieces.c) and its volume against the region's. */
#include "verify/check_passes.h"

#include <math.h>

#include "base/scan.h"
#include "geom/distance.h"
#include "geom/quality.h"

/* The index of label t in the report's ascending table, or -1. */
static int label_index(const mx_check_report *r, int32_t t) {
  size_t lo = 0, hi = r->nlabels;
  while (lo < hi) {
    const size_t mid = lo + (hi - lo) / 2;
    if (r->labels[mid].label < t)
      lo = mid + 1;
    else
      hi = mid;
  }
  return lo < r->nlabels && r->labels[lo].label == t ? (int)lo : -1;
}

int mx_ck_label_pass(const mx_mesh_data *m, const faces *F, uint8_t *flags, uint32_t *other,
                     mx_check_report *r) {
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
    r->labels[k] = (mx_check_label){t, 0, 0.0, -1, NAN, NAN, 0, 0, 0};
    r->nlabels++;
  }
  for (size_t c = 0; c < nc; c++) {
    const int k = label_index(r, m->cell_tag[c]);
    if (k < 0) continue;
    double p[8][3];
    const int nv = mx_cell_nodes[m->type[c]];
    for (int j = 0; j < nv; j++)
      memcpy(p[j], m->xyz + 3 * (size_t)m->conn[8 * c + j], sizeof p[j]);
    r->labels[k].cells++;
    r->labels[k].volume += mx_element_volume(m->type[c], (const double(*)[3])p);
  }
  /* the other slot of each face used twice; the faces between two labels,
   * each counted from its smaller slot, their nodes flagged */
  size_t between = 0;
#pragma omp parallel for schedule(dynamic, 1024) reduction(+ : between) if (nc > SMALL)
  for (size_t c = 0; c < nc; c++) {
    const int t = m->type[c];
    for (int f = 0; f < 6; f++) other[6 * c + (size_t)f] = UINT32_MAX;
    for (int f = 0; f < mx_cell_nfaces[t]; f++) {
      const size_t slot = 6 * c + (size_t)f;
      if (F->use[slot] != 2) continue;
      const int8_t *fv = mx_cell_faces[t][f];
      const int n = fv[3] < 0 ? 3 : 4;
      uint32_t v[4] = {0, 0, 0, 0};
      for (int j = 0; j < n; j++) v[j] = m->conn[8 * c + (size_t)fv[j]];
      sort4(v, n);
      int64_t s, s2;
      mx_ck_find_pair(m, F, v, n, &s, &s2);
      if (s2 < 0) continue;
      const size_t o = (size_t)(s == (int64_t)slot ? s2 : s);
      other[slot] = (uint32_t)o;
      if (o < slot || m->cell_tag[c] == m->cell_tag[o / 6]) continue;
      between++;
      for (int j = 0; j < n; j++) flag_or(&flags[v[j]], F_IFACE);
    }
  }
  r->interface_faces = between;
  return MX_OK;
}

/* The regions of a surface of one file: region d (depth d, inside d
 * shells) holds the shells at depth d - 1 less those at depth d (depths
 * beyond 64 in column 65); *outer: the outermost shells' volume. The
 * index S built outward, vol[66]. */
static int depth_regions(const mx_trisoup *surface, mx_surface_index *S, double region[66],
                         double *outer) {
  MX_CHECK(mx_surface_index_build_outward(S, surface, 0, (uint32_t)surface->nt));
  double *vol = mx_alloc(((size_t)S->nshells + 1) * sizeof *vol);
  if (!vol) {
    mx_surface_index_free(S);
    return MX_ENOMEM;
  }
  mx_surface_index_shell_volumes(S, vol, NULL);
  for (int d = 0; d < 66; d++) region[d] = 0.0;
  *outer = 0.0;
  for (uint32_t c = 0; c < S->nshells; c++) {
    const uint32_t e = S->shell_depth[c];
    if (e < 65) region[e + 1] += vol[c];
    if (e >= 1 && e < 66) region[e] -= vol[c];
    if (e == 0) *outer += vol[c];
  }
  mx_free(vol);
  return MX_OK;
}

/* Each label's region (the one most of its elements lie in: elements
 * across an interface, or with no point off the shells, left out), its
 * region's volume (region[0 .. nreg), element regions beyond in the last
 * column) and the elements lying in another region than their label's. */
static int judge_labels(const mx_mesh_data *m, const int16_t *reg, const double *region, int nreg,
                        mx_check_report *r) {
  size_t *count = mx_calloc((r->nlabels * (size_t)nreg + 1) * sizeof *count);
  if (!count) return MX_ENOMEM;
  for (size_t c = 0; c < m->ncells; c++) {
    const int k = label_index(r, m->cell_tag[c]);
    if (k < 0 || reg[c] < 0) continue;
    count[(size_t)k * (size_t)nreg + (size_t)(reg[c] < nreg ? reg[c] : nreg - 1)]++;
  }
  for (size_t k = 0; k < r->nlabels; k++) {
    const size_t *n = count + k * (size_t)nreg;
    int best = 0;
    for (int d = 1; d < nreg; d++)
      if (n[d] > n[best]) best = d;
    mx_check_label *L = &r->labels[k];
    if (!n[best]) continue; /* no element in a region: unknown */
    L->region = best;
    L->region_volume = region[best];
    L->volume_error = fabs(region[best]) > 0.0 ? (L->volume - region[best]) / fabs(region[best])
                                               : NAN;
  }
  mx_free(count);
  /* the labels a function of the regions */
  mx_check_elems_at *o = &r->off_label_region;
  for (size_t c = 0; c < m->ncells; c++) {
    const int k = label_index(r, m->cell_tag[c]);
    if (k < 0 || reg[c] < 0 || r->labels[k].region < 0) continue;
    const int e = reg[c] < nreg ? reg[c] : nreg - 1;
    if (e == r->labels[k].region) continue;
    r->labels[k].off_region++;
    if (o->n == 0) {
      mx_ck_centroid(m, c, o->at);
      o->region[0] = reg[c];
      o->region[1] = r->labels[k].region;
    }
    if (o->ids.n < MX_CHECK_LIST) o->ids.id[o->ids.n++] = (uint32_t)c;
    o->n++;
  }
  return MX_OK;
}

int mx_ck_label_regions(const mx_mesh_data *m, const mx_trisoup *surface, const ck_pieces *P,
                        mx_check_report *r) {
  if (!m->cell_tag || !r->nlabels || !surface->nt) return MX_OK;
  mx_surface_index S;
  double depth_region[66], outer = 0.0;
  const double *region = depth_region;
  int nreg = 66;
  if (P) { /* several files: the pieces' regions */
    region = P->region_volume;
    nreg = P->nregions + 1;
    outer = P->union_volume;
  } else {
    MX_CHECK(depth_regions(surface, &S, depth_region, &outer));
  }
  const ck_locate L = {P ? NULL : &S, P};
  int16_t *reg = mx_alloc((m->ncells + 1) * sizeof *reg);
  int st = reg ? mx_ck_element_regions(m, surface, &L, reg, r) : MX_ENOMEM;
  if (!P) mx_surface_index_free(&S);
  r->surface_volume = fabs(outer);
  r->volume_error = r->surface_volume > 0.0 ? (r->volume - r->surface_volume) / r->surface_volume
                                            : NAN;
  if (!st) st = judge_labels(m, reg, region, nreg, r);
  mx_free(reg);
  return st;
}

void mx_ck_label_verdict(mx_check_report *r) {
  r->labels_off = 0;
  for (size_t k = 0; k < r->nlabels; k++)
    if (r->labels[k].region >= 0 && !(fabs(r->labels[k].volume_error) <= r->opt.volume_tol))
      r->labels_off++;
}

/* Which faces of cell c bound its label (bit f: used once, or shared with
 * a cell of another label), and their edges in *nedges. */
static unsigned bounding_faces(const mx_mesh_data *m, const faces *F, const uint32_t *other,
                               size_t c, size_t *nedges) {
  const int t = m->type[c];
  unsigned bits = 0;
  size_t n = 0;
  for (int f = 0; f < mx_cell_nfaces[t]; f++) {
    const int8_t *fv = mx_cell_faces[t][f];
    const int nv = fv[3] < 0 ? 3 : 4;
    const uint8_t use = F->use[6 * c + (size_t)f];
    if (use == 2) {
      const uint32_t o = other[6 * c + (size_t)f];
      if (o != UINT32_MAX && m->cell_tag[o / 6] == m->cell_tag[c]) continue;
    } else if (use != 1) {
      continue;
    }
    bits |= 1u << f;
    n += (size_t)nv;
  }
  *nedges = n;
  return bits;
}

/* One pass over the faces for every label: each face that bounds its
 * cell's label gives its edges, keyed by the edge with the label's index
 * beside; sorted once, each run of one edge (the few bounding faces around
 * it) is counted label by label. O(cells) keys, whatever the number of
 * labels. */
int mx_ck_label_boundaries(const mx_mesh_data *m, const faces *F, const uint32_t *other,
                           mx_check_report *r) {
  if (!m->cell_tag || !r->nlabels) return MX_OK;
  const size_t nc = m->ncells;
  uint64_t *start = mx_alloc((nc + 1) * sizeof *start);
  uint8_t *bits = mx_alloc(nc + 1);
  if (!start || !bits) {
    mx_free(start);
    mx_free(bits);
    return MX_ENOMEM;
  }
#pragma omp parallel for schedule(dynamic, 1024) if (nc > SMALL)
  for (size_t c = 0; c < nc; c++) {
    size_t n = 0;
    bits[c] = 0;
    if (label_index(r, m->cell_tag[c]) >= 0) bits[c] = (uint8_t)bounding_faces(m, F, other, c, &n);
    start[c] = n;
  }
  start[nc] = 0;
  const size_t n = (size_t)mx_scan_u64(start, nc + 1);
  uint64_t *key = mx_alloc((n + 1) * sizeof *key);
  uint32_t *lab = mx_alloc((n + 1) * sizeof *lab);
  if (!key || !lab) {
    mx_free(start), mx_free(bits), mx_free(key), mx_free(lab);
    return MX_ENOMEM;
  }
#pragma omp parallel for schedule(dynamic, 1024) if (nc > SMALL)
  for (size_t c = 0; c < nc; c++) {
    if (!bits[c]) continue;
    const uint32_t k = (uint32_t)label_index(r, m->cell_tag[c]);
    const int t = m->type[c];
    size_t i = start[c];
    for (int f = 0; f < mx_cell_nfaces[t]; f++) {
      if (!(bits[c] >> f & 1)) continue;
      const int8_t *fv = mx_cell_faces[t][f];
      const int nv = fv[3] < 0 ? 3 : 4;
      for (int j = 0; j < nv; j++) {
        const uint32_t a = m->conn[8 * c + (size_t)fv[j]], b = m->conn[8 * c + (size_t)fv[(j + 1) % nv]];
        key[i] = a < b ? (uint64_t)a << 32 | b : (uint64_t)b << 32 | a;
        lab[i++] = k;
      }
    }
  }
  mx_free(start);
  mx_free(bits);
  const int st = n ? mx_sort_u64(key, lab, n) : MX_OK;
  if (st) {
    mx_free(key), mx_free(lab);
    return st;
  }
  for (size_t k = 0; k < r->nlabels; k++) r->labels[k].open_edges = r->labels[k].nonmanifold_edges = 0;
  for (size_t i = 0; i < n;) {
    size_t j = i + 1;
    while (j < n && key[j] == key[i]) j++;
    /* each label of the run once, at its first place */
    for (size_t x = i; x < j; x++) {
      size_t y = i, uses = 0;
      while (y < x && lab[y] != lab[x]) y++;
      if (y < x) continue;
      for (y = x; y < j; y++) uses += lab[y] == lab[x];
      r->labels[lab[x]].open_edges += uses % 2;
      r->labels[lab[x]].nonmanifold_edges += uses > 2;
    }
    i = j;
  }
  mx_free(key);
  mx_free(lab);
  r->labels_open = 0;
  for (size_t k = 0; k < r->nlabels; k++) r->labels_open += r->labels[k].open_edges > 0;
  return MX_OK;
}
