/* The checker's materials against the surface (issue 26 items 2 and 5;
 * src/verify/check_labels.c, check_regions.c, check_distance.c): interface
 * nodes on the surface, no element across an interface, the labels a
 * function of the regions. The mesh: the unit cube in 4 x 4 x 4 hexahedra
 * of side h = 1/4; the surfaces: boxes of 12 triangles built here.
 *
 * Derived, not recorded (d = the surface's diagonal, sqrt(3) for the unit
 * cube):
 *  1. outer box only, labels 1 for x < 1/2 and 2 beyond: the interface is
 *     the plane x = 1/2, 25 nodes, of which the 16 on the cube's sides lie
 *     on the surface and the 9 inside do not; the farthest, the cube's
 *     centre, is 1/2 from every side: interface_max_dist = 0.5 / d. Every
 *     element lies in region 1 (no element across, the two labels both in
 *     region 1: no label off its region); each label holds 1/2 of region
 *     1's volume 1: both volumes off.
 *  2. outer box and the inner box [1/4, 3/4]^3 (on grid planes), label 2
 *     for the 8 cells inside it: the interface is the inner box, its 26
 *     nodes on it (distance 0); no defect at all.
 *  3. the same with the cell at (1, 1, 1) (inside the inner box, a corner
 *     at the cube's centre) labelled 1: the interface gains the 3 inner
 *     faces of that cell, whose only node off the inner box is the centre
 *     (1/4 from it): 1 interface node off, max 0.25 / d; that cell lies in
 *     region 2 while label 1 lies in region 1 (56 of its 57 cells): 1
 *     element off its label's region, the cell (1, 1, 1) = 21, centroid
 *     (3/8, 3/8, 3/8), regions 2 and 1; and label 2 holds 7/64 of region
 *     2's 8/64, beyond the volume tolerance of 0.1 used here.
 *  4. outer box and the inner box [1/4, 3/4]^2 x [1/4, 0.6] (its top
 *     between grid planes), label 2 for the 4 cells of layer k = 1 inside
 *     it, 1 elsewhere: the 4 cells of layer k = 2 above them (z from 1/2 to
 *     3/4) have their centroid (z = 5/8) in region 1 and the corner at the
 *     column's axis (1/2, 1/2, 1/2) in region 2, their other corners on
 *     the inner box or in region 1: 4 elements across an interface, the
 *     first the cell (1, 1, 2) = 37 at (3/8, 3/8, 5/8), regions 1 and 2;
 *     the interface (the top of label 2, z = 1/2) has the one node
 *     (1/2, 1/2, 1/2) off the inner box (0.1 below its top): max 0.1 / d. */
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

enum { N = 4 };

/* The 12 triangles of the box [lo, hi], outward, appended to s. */
static void add_box(mx_trisoup *s, const double lo[3], const double hi[3]) {
  const uint32_t v0 = (uint32_t)s->nv;
  for (int q = 0; q < 8; q++) {
    const double c[3] = {q & 1 ? hi[0] : lo[0], q & 2 ? hi[1] : lo[1], q & 4 ? hi[2] : lo[2]};
    CHECK(mx_trisoup_set_vertex(s, v0 + (size_t)q, c) == MX_OK);
  }
  /* corner q = x + 2 y + 4 z; each side's quad counterclockwise seen from
   * outside, cut along a diagonal */
  static const int quad[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                                 {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (int f = 0; f < 6; f++) {
    const uint32_t *q = (const uint32_t[4]){v0 + (uint32_t)quad[f][0], v0 + (uint32_t)quad[f][1],
                                            v0 + (uint32_t)quad[f][2], v0 + (uint32_t)quad[f][3]};
    CHECK(mx_trisoup_add_triangle(s, q[0], q[1], q[2]) == MX_OK);
    CHECK(mx_trisoup_add_triangle(s, q[0], q[2], q[3]) == MX_OK);
  }
}

static int nmessages;
static void count_message(void *user, int level, const char *text) {
  (void)user, (void)level, (void)text;
  nmessages++;
}

static size_t cell_id(size_t i, size_t j, size_t k) { return (k * N + j) * N + i; }

static int near(double a, double b) { return fabs(a - b) <= 1e-12; }

static mx_check_report run(const mx_mesh_data *d, const mx_trisoup *s) {
  mx_check_options o;
  mx_check_defaults(&o);
  o.volume_tol = 0.1; /* the volumes are exact here but for case 1 */
  mx_check_report r;
  CHECK(mx_check_mesh_opt(d, s, &o, &r) == MX_OK);
  printf("  defects %zu: interface nodes %zu, off %zu (max %.6g of the diagonal); across %zu; "
         "off their label's region %zu; volumes off %zu\n",
         r.defects, r.interface_nodes, r.interface_off_surface, r.interface_max_dist,
         r.across_interface.n, r.off_label_region.n, r.labels_off);
  return r;
}

int main(void) {
  const double h = 1.0 / N, diag = sqrt(3.0);
  const size_t np = N + 1, nn = np * np * np, nc = (size_t)N * N * N;
  double *xyz = malloc(3 * nn * sizeof *xyz);
  uint8_t *type = malloc(nc);
  uint32_t *conn = calloc(8 * nc, sizeof *conn);
  int32_t *label = malloc(nc * sizeof *label);
  for (size_t k = 0; k < np; k++)
    for (size_t j = 0; j < np; j++)
      for (size_t i = 0; i < np; i++) {
        const size_t g = (k * np + j) * np + i;
        xyz[3 * g] = h * (double)i, xyz[3 * g + 1] = h * (double)j, xyz[3 * g + 2] = h * (double)k;
      }
  for (size_t k = 0; k < N; k++)
    for (size_t j = 0; j < N; j++)
      for (size_t i = 0; i < N; i++) {
        const size_t c = cell_id(i, j, k);
        type[c] = MX_HEX;
        for (int q = 0; q < 8; q++) {
          const size_t bx = (size_t)((q & 1) ^ ((q >> 1) & 1)), by = (size_t)((q >> 1) & 1),
                       bz = (size_t)(q >> 2);
          conn[8 * c + (size_t)q] = (uint32_t)(((k + bz) * np + j + by) * np + i + bx);
        }
      }
  mx_mesh_data d = {.nnodes = nn, .ncells = nc, .xyz = xyz, .type = type, .conn = conn,
                    .cell_tag = label};
  const double zero[3] = {0, 0, 0}, one[3] = {1, 1, 1};
  const double ilo[3] = {0.25, 0.25, 0.25}, ihi[3] = {0.75, 0.75, 0.75};
  mx_check_report r;

  printf("1. two labels split at x = 1/2, the outer box only\n");
  mx_trisoup outer;
  memset(&outer, 0, sizeof outer);
  add_box(&outer, zero, one);
  for (size_t c = 0; c < nc; c++) label[c] = c % N < N / 2 ? 1 : 2;
  r = run(&d, &outer);
  CHECK(r.nlabels == 2 && r.interface_faces == (size_t)N * N);
  CHECK(r.interface_nodes == np * np);
  CHECK(r.interface_off_surface == (N - 1) * (N - 1));
  CHECK(near(r.interface_max_dist, 0.5 / diag));
  CHECK(r.interface_off_ids.n == (N - 1) * (N - 1));
  CHECK(r.has_regions && r.across_interface.n == 0 && r.off_label_region.n == 0);
  CHECK(r.labels[0].region == 1 && r.labels[1].region == 1 && r.labels_off == 2);
  CHECK(r.defects == r.interface_off_surface + r.labels_off);
  for (uint32_t i = 0; i < r.interface_off_ids.n; i++) { /* the nodes inside x = 1/2 */
    const double *p = xyz + 3 * (size_t)r.interface_off_ids.id[i];
    CHECK(p[0] == 0.5 && p[1] > 0.0 && p[1] < 1.0 && p[2] > 0.0 && p[2] < 1.0);
  }

  printf("2. label 2 in the inner box, on grid planes: no defect\n");
  mx_trisoup nested;
  memset(&nested, 0, sizeof nested);
  add_box(&nested, zero, one);
  add_box(&nested, ilo, ihi);
  for (size_t k = 0; k < N; k++)
    for (size_t j = 0; j < N; j++)
      for (size_t i = 0; i < N; i++) {
        const int in = i >= 1 && i <= 2 && j >= 1 && j <= 2 && k >= 1 && k <= 2;
        label[cell_id(i, j, k)] = in ? 2 : 1;
      }
  r = run(&d, &nested);
  CHECK(r.nlabels == 2 && r.interface_faces == 24);
  CHECK(r.interface_nodes == 26 && r.interface_off_surface == 0);
  CHECK(r.interface_max_dist >= 0.0 && r.interface_max_dist <= 1e-15);
  CHECK(r.has_regions && r.across_interface.n == 0 && r.off_label_region.n == 0);
  CHECK(r.labels[0].region == 1 && r.labels[1].region == 2);
  CHECK(near(r.labels[0].region_volume, 1.0 - 0.125) && near(r.labels[1].region_volume, 0.125));
  CHECK(r.defects == 0);

  printf("3. one cell of the inner box labelled 1\n");
  label[cell_id(1, 1, 1)] = 1;
  r = run(&d, &nested);
  CHECK(r.interface_faces == 24 - 3 + 3);
  CHECK(r.interface_off_surface == 1 && r.interface_off_ids.n == 1);
  CHECK(r.interface_off_ids.id[0] == (2 * np + 2) * np + 2); /* the centre */
  CHECK(near(r.interface_max_dist, 0.25 / diag));
  CHECK(r.across_interface.n == 0);
  CHECK(r.labels[0].region == 1 && r.labels[0].off_region == 1 && r.labels[1].off_region == 0);
  CHECK(r.off_label_region.n == 1 && r.off_label_region.ids.n == 1);
  CHECK(r.off_label_region.ids.id[0] == cell_id(1, 1, 1));
  CHECK(near(r.off_label_region.at[0], 0.375) && near(r.off_label_region.at[1], 0.375) &&
        near(r.off_label_region.at[2], 0.375));
  CHECK(r.off_label_region.region[0] == 2 && r.off_label_region.region[1] == 1);
  /* the volumes: label 1 holds its region and one cell of region 2 */
  CHECK(near(r.labels[0].volume, 1.0 - 0.125 + 1.0 / 64));
  CHECK(r.labels_off == 1); /* label 2: 7/64 against 8/64, -12.5% */
  CHECK(r.defects == 3);

  printf("4. the inner box's top at z = 0.6, between grid planes: 4 cells across\n");
  mx_trisoup column;
  memset(&column, 0, sizeof column);
  add_box(&column, zero, one);
  add_box(&column, ilo, (const double[3]){0.75, 0.75, 0.6});
  for (size_t k = 0; k < N; k++)
    for (size_t j = 0; j < N; j++)
      for (size_t i = 0; i < N; i++) {
        const int in = i >= 1 && i <= 2 && j >= 1 && j <= 2 && k == 1;
        label[cell_id(i, j, k)] = in ? 2 : 1;
      }
  r = run(&d, &column);
  CHECK(r.across_interface.n == 4 && r.across_interface.ids.n == 4);
  const size_t across[4] = {cell_id(1, 1, 2), cell_id(2, 1, 2), cell_id(1, 2, 2),
                            cell_id(2, 2, 2)};
  for (int q = 0; q < 4; q++) CHECK(r.across_interface.ids.id[q] == across[q]);
  CHECK(near(r.across_interface.at[0], 0.375) && near(r.across_interface.at[1], 0.375) &&
        near(r.across_interface.at[2], 0.625));
  CHECK(r.across_interface.region[0] == 1 && r.across_interface.region[1] == 2);
  CHECK(r.interface_off_surface == 1 && near(r.interface_max_dist, 0.1 / diag));
  CHECK(r.off_label_region.n == 0);
  CHECK(r.labels[0].region == 1 && r.labels[1].region == 2);

  /* every allocation of that check failed in turn: MX_ENOMEM, and the
   * check run again gives the same counts */
  const mx_check_report ref = r;
  mx_check_options o;
  mx_check_defaults(&o);
  o.volume_tol = 0.1;
  mx_alloc_fail_countdown(-1);
  CHECK(mx_check_mesh_opt(&d, &column, &o, &r) == MX_OK);
  const long nalloc = mx_alloc_count();
  size_t failed = 0;
  mx_msg_fn = count_message; /* the "out of memory" messages, counted */
  for (long k = 1; k <= nalloc; k++) {
    nmessages = 0;
    mx_alloc_fail_countdown(k);
    const int st = mx_check_mesh_opt(&d, &column, &o, &r);
    mx_alloc_fail_countdown(0);
    CHECK(st == MX_ENOMEM && nmessages > 0);
    failed += st == MX_ENOMEM;
  }
  mx_msg_fn = NULL;
  CHECK(mx_check_mesh_opt(&d, &column, &o, &r) == MX_OK);
  CHECK(r.defects == ref.defects && r.across_interface.n == 4 && r.interface_off_surface == 1);
  printf("  %ld allocations, each failed once: %zu MX_ENOMEM\n", nalloc, failed);

  /* without a surface: none of this is looked at */
  CHECK(mx_check_mesh(&d, NULL, &r) == MX_OK);
  CHECK(!r.has_regions && r.across_interface.n == 0 && r.interface_off_surface == 0 &&
        isnan(r.interface_max_dist));
  mx_trisoup_free(&outer), mx_trisoup_free(&nested), mx_trisoup_free(&column);
  free(xyz), free(type), free(conn), free(label);
  return TEST_DONE();
}
