/* The checker with cell labels (several materials, issue 26;
 * src/verify/check_labels.c, check_tags.c): a unit cube of 4 x 4 x 4
 * hexahedra, the half x < 0.5 labelled 1 and the rest 2.
 *
 * Derived, not recorded: two labels of 32 elements and volume 1/2 each; 16
 * faces between them (the plane x = 0.5); with the boundary faces and those
 * 16 tagged, plus one tagged face inside label 1: the 16 are interfaces,
 * the one inside is "tagged not boundary", no boundary face is untagged;
 * without labels all 17 are "tagged not boundary"; with one label only,
 * no interface. Each label's boundary is closed (a union of cells of a
 * conforming mesh), and only a checkerboard makes a label touch itself
 * along edges (each label's inner edges of the board used 4 times). */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "soa/mesh_data.h"
#include "verify/check.h"

enum { N = 4 };

typedef struct {
  uint32_t v[4]; /* sorted */
  uint32_t orig[4];
  uint32_t cell;
} face;

static int cmp_face(const void *a, const void *b) {
  return memcmp(((const face *)a)->v, ((const face *)b)->v, sizeof ((const face *)a)->v);
}

int main(void) {
  const double h = 1.0 / N;
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
  size_t c = 0;
  for (size_t k = 0; k < N; k++)
    for (size_t j = 0; j < N; j++)
      for (size_t i = 0; i < N; i++, c++) {
        type[c] = MX_HEX;
        for (int q = 0; q < 8; q++) {
          const size_t bx = (size_t)((q & 1) ^ ((q >> 1) & 1)), by = (size_t)((q >> 1) & 1),
                       bz = (size_t)(q >> 2);
          conn[8 * c + (size_t)q] = (uint32_t)(((k + bz) * np + j + by) * np + i + bx);
        }
        label[c] = i < N / 2 ? 1 : 2;
      }
  /* every face of every cell, sorted: runs of one are boundary faces,
   * runs of two between labels are interfaces */
  face *F = malloc(6 * nc * sizeof *F);
  size_t nf = 0;
  for (c = 0; c < nc; c++)
    for (int f = 0; f < 6; f++) {
      face x;
      x.cell = (uint32_t)c;
      for (int q = 0; q < 4; q++) x.orig[q] = x.v[q] = conn[8 * c + (size_t)mx_cell_faces[MX_HEX][f][q]];
      for (int a = 1; a < 4; a++)
        for (int b = a; b > 0 && x.v[b] < x.v[b - 1]; b--) {
          const uint32_t s = x.v[b];
          x.v[b] = x.v[b - 1], x.v[b - 1] = s;
        }
      F[nf++] = x;
    }
  qsort(F, nf, sizeof *F, cmp_face);
  size_t nt = 0, ninterface = 0;
  uint8_t *fnn = malloc(nf);
  uint32_t *fconn = malloc(4 * nf * sizeof *fconn);
  int32_t *ftag = malloc(nf * sizeof *ftag);
  int inside_added = 0;
  for (size_t i = 0; i < nf;) {
    size_t j = i + 1;
    while (j < nf && !memcmp(F[j].v, F[i].v, sizeof F[i].v)) j++;
    int tag = 0;
    if (j - i == 1)
      tag = 1;
    else if (label[F[i].cell] != label[F[i + 1].cell])
      tag = 2, ninterface++;
    else if (!inside_added && label[F[i].cell] == 1)
      tag = 3, inside_added = 1; /* a tagged face inside label 1: wrong */
    if (tag) {
      fnn[nt] = 4;
      memcpy(fconn + 4 * nt, F[i].orig, 4 * sizeof *fconn);
      ftag[nt++] = tag;
    }
    i = j;
  }
  CHECK(ninterface == N * N);
  mx_mesh_data d = {.nnodes = nn, .ncells = nc, .xyz = xyz, .type = type, .conn = conn,
                    .nfaces = nt, .face_nn = fnn, .face_conn = fconn, .face_tag = ftag,
                    .cell_tag = label};
  mx_check_report r;
  CHECK(mx_check_mesh(&d, NULL, &r) == MX_OK);
  CHECK(r.nlabels == 2 && r.labels_dropped == 0);
  CHECK(r.labels[0].label == 1 && r.labels[1].label == 2);
  CHECK(r.labels[0].cells == nc / 2 && r.labels[1].cells == nc / 2);
  CHECK(fabs(r.labels[0].volume - 0.5) < 1e-12 && fabs(r.labels[1].volume - 0.5) < 1e-12);
  CHECK(r.interface_faces == (size_t)N * N);
  CHECK(r.tagged_interface == (size_t)N * N);
  CHECK(r.tagged_not_boundary == 1);
  CHECK(r.boundary_untagged == 0);
  CHECK(r.labels_open == 0 && r.labels[0].open_edges == 0 && r.labels[1].open_edges == 0);
  CHECK(r.labels[0].nonmanifold_edges == 0 && r.labels[1].nonmanifold_edges == 0);
  printf("labels: %zu, volumes %.3f %.3f; interface faces %zu (%zu tagged), tagged not "
         "boundary %zu\n", r.nlabels, r.labels[0].volume, r.labels[1].volume,
         r.interface_faces, r.tagged_interface, r.tagged_not_boundary);
  /* without labels: the 16 interface faces and the wrong one are not boundary faces */
  d.cell_tag = NULL;
  CHECK(mx_check_mesh(&d, NULL, &r) == MX_OK);
  CHECK(r.nlabels == 0 && r.interface_faces == 0 && r.tagged_interface == 0);
  CHECK(r.tagged_not_boundary == (size_t)N * N + 1);
  /* a checkerboard: every inner edge of the board is shared by four cells,
   * two of each label, so each label touches itself along it */
  for (size_t k = 0; k < N; k++)
    for (size_t j = 0; j < N; j++)
      for (size_t i = 0; i < N; i++) label[(k * N + j) * N + i] = 1 + (int32_t)((i + j + k) % 2);
  d.cell_tag = label;
  CHECK(mx_check_mesh(&d, NULL, &r) == MX_OK);
  CHECK(r.nlabels == 2 && r.labels_open == 0);
  /* the edges inside the cube: 3 directions x N x (N - 1)^2 */
  CHECK(r.labels[0].nonmanifold_edges == 3 * N * (N - 1) * (N - 1));
  CHECK(r.labels[1].nonmanifold_edges == 3 * N * (N - 1) * (N - 1));
  printf("checkerboard: %zu and %zu edges where a label touches itself\n",
         r.labels[0].nonmanifold_edges, r.labels[1].nonmanifold_edges);
  /* one label: no interface, the 17 are wrong again */
  for (c = 0; c < nc; c++) label[c] = 7;
  d.cell_tag = label;
  CHECK(mx_check_mesh(&d, NULL, &r) == MX_OK);
  CHECK(r.nlabels == 1 && r.labels[0].label == 7 && r.labels[0].cells == nc);
  CHECK(r.interface_faces == 0 && r.tagged_not_boundary == (size_t)N * N + 1);
  free(xyz), free(type), free(conn), free(label), free(F), free(fnn), free(fconn), free(ftag);
  return TEST_DONE();
}
