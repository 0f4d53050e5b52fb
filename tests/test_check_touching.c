/* The checker against a surface of several files (touching inputs, issue
 * 26; src/verify/check_pieces.c): the regions are those of each file's
 * closed shells, keyed by (nesting depth, file). The mesh: the box
 * [0, 2] x [0, 1] x [0, 1] in 8 x 4 x 4 hexahedra of side h = 1/4; the
 * surfaces: boxes of 12 triangles built here, A = [0, 1]^3 and
 * B = [1, 2] x [0, 1]^2 glued on the face x = 1 (the same two triangles in
 * both), I = [1/4, 3/4]^3 inside A (on grid planes).
 *
 * Derived, not recorded:
 *  1. files A and B, label 1 for x < 1 and 2 beyond: 2 files, 2 pieces, 4
 *     triangles shared (the face x = 1 in each file); the union's volume 2,
 *     each label in its own region (A's: 1, B's: 2) holding exactly its
 *     volume 1; the interface x = 1 on the shared triangles (distance 0);
 *     no defect. The default volume tolerance is half a layer of elements
 *     along the boundary, 0.5 A h / V with A the area of the triangles no
 *     other file shares (10 unit squares, not 12), h = (2 / 128)^(1/3) =
 *     1/4, V = 2: 0.625.
 *  2. the layers on each side of the face swapped (cells i = 3 labelled 2,
 *     i = 4 labelled 1): each label keeps its volume 1 and most of its
 *     cells (48 of 64) in its region, but the 16 + 16 swapped cells lie in
 *     the other's: 32 elements off their label's region, the first cell 3
 *     (i = 3, j = k = 0) at (7/8, 1/8, 1/8), in region 1 while its label's
 *     is 2. The interfaces are now the planes x = 3/4 and 5/4 besides
 *     x = 1: of the 25 nodes of each, the 9 off the boxes' sides are off
 *     the surface (18 interface nodes off), the farthest 1/4 from a side
 *     or from the face x = 1: interface_max_dist = 0.25 / sqrt(6) (the
 *     surface's diagonal); 50 defects. The labels swapped as a whole (2 in
 *     A, 1 in B) are names only: no defect.
 *  3. files A, B and I (I alone in a third file), label 3 for the 8 cells
 *     inside I: I lies inside A (depth 1), so the regions are (0, A) = 1,
 *     (1, I) = 2, and (0, B) numbered after the deepest, 3: label 1 in
 *     region 1 of volume 1 - 1/8, label 3 in region 2 of 1/8, label 2 in
 *     region 3 of 1; no defect. The same with A and I in one file (two
 *     pieces of file 0) and B in the second: the same regions. Without
 *     the labels (a mesh without materials, where the mesher makes a
 *     nested shell a hole) the surface's volume is that of the points of
 *     odd nesting depth, 2 - 1/8.
 *  4. one surface file holding A and B (shell 0 for both): the check of
 *     one file as before this change (no pieces counted, no triangle
 *     shared). */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "base/common.h"
#include "check.h"
#include "soa/mesh_data.h"
#include "soa/trisoup.h"
#include "verify/check.h"

enum { NX = 8, NY = 4, NZ = 4 };

/* The 12 triangles of the box [lo, hi], outward, as a soup of its own
 * appended to s (one file). Each side is cut along the diagonal from its
 * smallest corner, so that two boxes sharing a side share its triangles. */
static void add_box_file(mx_trisoup *s, const double lo[3], const double hi[3]) {
  mx_trisoup b;
  memset(&b, 0, sizeof b);
  for (int q = 0; q < 8; q++) {
    const double c[3] = {q & 1 ? hi[0] : lo[0], q & 2 ? hi[1] : lo[1], q & 4 ? hi[2] : lo[2]};
    CHECK(mx_trisoup_set_vertex(&b, (size_t)q, c) == MX_OK);
  }
  /* corner q = x + 2 y + 4 z; each side counterclockwise seen from
   * outside, starting at its smallest corner (the diagonal from it to the
   * opposite corner, the same whichever box the side belongs to) */
  static const int quad[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                                 {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (int f = 0; f < 6; f++) {
    const int *q = quad[f];
    CHECK(mx_trisoup_add_triangle(&b, (uint32_t)q[0], (uint32_t)q[1], (uint32_t)q[2]) == MX_OK);
    CHECK(mx_trisoup_add_triangle(&b, (uint32_t)q[0], (uint32_t)q[2], (uint32_t)q[3]) == MX_OK);
  }
  CHECK(mx_trisoup_append(s, &b) == MX_OK);
  mx_trisoup_free(&b);
}

/* The box appended to the last file of s (s->nshells > 0): its triangles
 * take that file's shell. */
static void add_box_same_file(mx_trisoup *s, const double lo[3], const double hi[3]) {
  const size_t t0 = s->nt;
  const uint16_t last = (uint16_t)(s->nshells - 1);
  add_box_file(s, lo, hi);
  for (size_t t = t0; t < s->nt; t++) s->shell[t] = last;
  s->nshells--;
}

static void quiet_handler(void *user, int level, const char *text) {
  (void)user, (void)level, (void)text;
}

static size_t cell_id(size_t i, size_t j, size_t k) { return (k * NY + j) * NX + i; }

static int near(double a, double b) { return fabs(a - b) <= 1e-12; }

static mx_check_report run(const mx_mesh_data *d, const mx_trisoup *s) {
  mx_check_report r;
  CHECK(mx_check_mesh_opt(d, s, NULL, &r) == MX_OK);
  printf("  %zu files, %zu pieces, %zu triangles shared; volume %.6g against %.6g (tolerance "
         "%.6g); defects %zu: across %zu, off their label's region %zu, volumes off %zu, "
         "interface off %zu\n",
         r.surface_files, r.surface_pieces, r.shared_triangles, r.volume, r.surface_volume,
         r.opt.volume_tol, r.defects, r.across_interface.n, r.off_label_region.n, r.labels_off,
         r.interface_off_surface);
  return r;
}

/* Label k's region and its volume. */
static int label_in(const mx_check_report *r, size_t k, int32_t label, int region, double vol) {
  const mx_check_label *L = &r->labels[k];
  return k < r->nlabels && L->label == label && L->region == region &&
         near(L->region_volume, vol) && near(L->volume, vol) && L->off_region == 0;
}

int main(void) {
  const double h = 0.25;
  const size_t px = NX + 1, py = NY + 1, pz = NZ + 1, nn = px * py * pz,
               nc = (size_t)NX * NY * NZ;
  double *xyz = malloc(3 * nn * sizeof *xyz);
  uint8_t *type = malloc(nc);
  uint32_t *conn = calloc(8 * nc, sizeof *conn);
  int32_t *label = malloc(nc * sizeof *label);
  for (size_t k = 0; k < pz; k++)
    for (size_t j = 0; j < py; j++)
      for (size_t i = 0; i < px; i++) {
        const size_t g = (k * py + j) * px + i;
        xyz[3 * g] = h * (double)i, xyz[3 * g + 1] = h * (double)j, xyz[3 * g + 2] = h * (double)k;
      }
  for (size_t k = 0; k < NZ; k++)
    for (size_t j = 0; j < NY; j++)
      for (size_t i = 0; i < NX; i++) {
        const size_t c = cell_id(i, j, k);
        type[c] = MX_HEX;
        for (int q = 0; q < 8; q++) {
          const size_t bx = (size_t)((q & 1) ^ ((q >> 1) & 1)), by = (size_t)((q >> 1) & 1),
                       bz = (size_t)(q >> 2);
          conn[8 * c + (size_t)q] = (uint32_t)(((k + bz) * py + j + by) * px + i + bx);
        }
      }
  mx_mesh_data d = {.nnodes = nn, .ncells = nc, .xyz = xyz, .type = type, .conn = conn,
                    .cell_tag = label};
  const double alo[3] = {0, 0, 0}, ahi[3] = {1, 1, 1}, blo[3] = {1, 0, 0}, bhi[3] = {2, 1, 1};
  const double ilo[3] = {0.25, 0.25, 0.25}, ihi[3] = {0.75, 0.75, 0.75};
  mx_check_report r;

  /* 1. A and B, each label in its box */
  printf("1. two boxes glued on a face, two files, a label each\n");
  mx_trisoup ab;
  memset(&ab, 0, sizeof ab);
  add_box_file(&ab, alo, ahi);
  add_box_file(&ab, blo, bhi);
  for (size_t c = 0; c < nc; c++) label[c] = c % NX < 4 ? 1 : 2;
  r = run(&d, &ab);
  CHECK(r.surface_files == 2 && r.surface_pieces == 2 && r.shared_triangles == 4);
  CHECK(r.surface_open_edges == 0 && near(r.surface_volume, 2.0) && near(r.volume_error, 0.0));
  CHECK(r.opt.volume_tol_auto && near(r.opt.volume_tol, 0.625));
  CHECK(r.nlabels == 2 && label_in(&r, 0, 1, 1, 1.0) && label_in(&r, 1, 2, 2, 1.0));
  CHECK(r.interface_faces == (size_t)NY * NZ && r.interface_off_surface == 0);
  CHECK(r.interface_max_dist == 0.0 && r.boundary_off_surface == 0);
  CHECK(r.across_interface.n == 0 && r.off_label_region.n == 0 && r.labels_off == 0);
  CHECK(r.volume_off == 0 && r.defects == 0);

  /* 2. the layers on each side of the face swapped; then the labels */
  printf("2. the layers on each side of the face swapped\n");
  for (size_t c = 0; c < nc; c++) {
    const size_t i = c % NX;
    label[c] = i == 3 ? 2 : i == 4 ? 1 : i < 4 ? 1 : 2;
  }
  r = run(&d, &ab);
  CHECK(r.nlabels == 2 && r.labels[0].region == 1 && r.labels[1].region == 2);
  CHECK(near(r.labels[0].volume, 1.0) && near(r.labels[1].volume, 1.0) && r.labels_off == 0);
  CHECK(r.labels[0].off_region == 16 && r.labels[1].off_region == 16);
  CHECK(r.off_label_region.n == 32 && r.across_interface.n == 0);
  CHECK(r.interface_off_surface == 18 && near(r.interface_max_dist, 0.25 / sqrt(6.0)));
  CHECK(r.defects == 50);
  CHECK(r.off_label_region.ids.n == MX_CHECK_LIST && r.off_label_region.ids.id[0] == 3);
  CHECK(near(r.off_label_region.at[0], 0.875) && near(r.off_label_region.at[1], 0.125) &&
        near(r.off_label_region.at[2], 0.125));
  CHECK(r.off_label_region.region[0] == 1 && r.off_label_region.region[1] == 2);
  printf("   the labels swapped as a whole\n");
  for (size_t c = 0; c < nc; c++) label[c] = c % NX < 4 ? 2 : 1;
  r = run(&d, &ab);
  CHECK(label_in(&r, 0, 1, 2, 1.0) && label_in(&r, 1, 2, 1, 1.0) && r.defects == 0);

  /* 3. a box inside A, in a third file; then in A's file */
  printf("3. a box inside A in a third file\n");
  for (size_t k = 0; k < NZ; k++)
    for (size_t j = 0; j < NY; j++)
      for (size_t i = 0; i < NX; i++) {
        const int in = i >= 1 && i <= 2 && j >= 1 && j <= 2 && k >= 1 && k <= 2;
        label[cell_id(i, j, k)] = in ? 3 : i < 4 ? 1 : 2;
      }
  mx_trisoup abi;
  memset(&abi, 0, sizeof abi);
  add_box_file(&abi, alo, ahi);
  add_box_file(&abi, blo, bhi);
  add_box_file(&abi, ilo, ihi);
  r = run(&d, &abi);
  CHECK(r.surface_files == 3 && r.surface_pieces == 3 && r.shared_triangles == 4);
  CHECK(near(r.surface_volume, 2.0));
  CHECK(r.nlabels == 3 && label_in(&r, 0, 1, 1, 0.875) && label_in(&r, 1, 2, 3, 1.0) &&
        label_in(&r, 2, 3, 2, 0.125));
  CHECK(r.defects == 0);
  printf("   the same box in A's file\n");
  mx_trisoup aib;
  memset(&aib, 0, sizeof aib);
  add_box_file(&aib, alo, ahi);
  add_box_same_file(&aib, ilo, ihi);
  add_box_file(&aib, blo, bhi);
  r = run(&d, &aib);
  CHECK(r.surface_files == 2 && r.surface_pieces == 3 && r.shared_triangles == 4);
  CHECK(r.nlabels == 3 && label_in(&r, 0, 1, 1, 0.875) && label_in(&r, 1, 2, 3, 1.0) &&
        label_in(&r, 2, 3, 2, 0.125));
  CHECK(r.defects == 0);

  d.cell_tag = NULL;
  r = run(&d, &abi);
  CHECK(r.nlabels == 0 && r.surface_pieces == 3 && near(r.surface_volume, 1.875));
  CHECK(near(r.volume_error, 0.125 / 1.875));
  d.cell_tag = label;

  /* every allocation of the check of case 3 made to fail in turn: each
   * gives MX_ENOMEM, never a crash or another status, and the check run
   * again after it gives the same report */
  printf("   each of its allocations failing in turn\n");
  mx_msg_fn = quiet_handler; /* the "out of memory" messages */
  mx_alloc_fail_countdown(-1);
  CHECK(mx_check_mesh(&d, &abi, &r) == MX_OK);
  const long nalloc = mx_alloc_count();
  long enomem = 0;
  for (long k = 1; k <= nalloc; k++) {
    mx_alloc_fail_countdown(k);
    const int st = mx_check_mesh(&d, &abi, &r);
    CHECK(st == MX_ENOMEM || st == MX_OK);
    enomem += st == MX_ENOMEM;
  }
  mx_alloc_fail_countdown(0);
  mx_msg_fn = NULL;
  CHECK(nalloc > 20 && enomem == nalloc);
  printf("   %ld allocations, each failing gave MX_ENOMEM (%ld)\n", nalloc, enomem);
  r = run(&d, &abi);
  CHECK(r.defects == 0 && r.surface_pieces == 3);

  /* 4. A and B in one file: the one-file check */
  printf("4. both boxes in one file\n");
  mx_trisoup one;
  memset(&one, 0, sizeof one);
  add_box_file(&one, alo, ahi);
  add_box_same_file(&one, blo, bhi);
  for (size_t c = 0; c < nc; c++) label[c] = c % NX < 4 ? 1 : 2;
  r = run(&d, &one);
  CHECK(r.surface_files == 1 && r.surface_pieces == 0 && r.shared_triangles == 0);

  mx_trisoup_free(&ab);
  mx_trisoup_free(&abi);
  mx_trisoup_free(&aib);
  mx_trisoup_free(&one);
  free(xyz), free(type), free(conn), free(label);
  return TEST_DONE();
}
