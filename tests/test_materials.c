/* Several materials, first part (issue 26; src/mesher/materials.c): two
 * concentric spheres meshed with params.materials at the transition stage.
 *
 * Derived, not recorded:
 *  - each element's material is the number of spheres around its centroid,
 *    counted here from the centroid's radius (elements whose centroid lies
 *    within the tessellation's chordal error of a sphere are skipped);
 *  - the materials' volumes add up to the mesh's, and the inner sphere's
 *    material holds its volume within the staircase's error (each element
 *    straddling the sphere counts whole on one side): below 10% at -s 5;
 *  - every face between two materials is found once by the interface
 *    extraction, each between elements of different materials, against
 *    an independent face map here;
 *  - the same arrays with 1 and 2 threads;
 *  - at the full stage (outer boundary on the outer sphere, interfaces on
 *    element faces whose nodes move onto the inner sphere where the
 *    elements allow): the same rule for every element away from the
 *    spheres, no invalid element, and the inner material's volume within
 *    3% (-s 4) and 1% (-s 5) of what the inner sphere's triangles enclose;
 *  - without materials the inner sphere is a hole (no element inside)
 *    (re-meshing with materials: test_material_interfaces.c). */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "test_shapes.h"
#include "io/boundary_faces.h"
#include "mixoct.h"
#include "soa/mesh.h"

static mx_mesher *two_spheres_at(int level, int materials, int stage, int threads) {
  mx_params p;
  mx_params_default(&p);
  p.surface_level = level;
  p.stage = stage;
  p.materials = materials;
  p.threads = threads;
  mx_mesher *m = mx_mesher_new(&p);
  double *x;
  uint32_t *t;
  size_t nv, nt;
  sphere(1.0, 32, &x, &nv, &t, &nt);
  CHECK(mx_mesher_add_surface_arrays(m, "outer", nv, x, nt, t) == MX_OK);
  free(x);
  free(t);
  sphere(0.5, 24, &x, &nv, &t, &nt);
  CHECK(mx_mesher_add_surface_arrays(m, "inner", nv, x, nt, t) == MX_OK);
  free(x);
  free(t);
  return m;
}

static mx_mesher *two_spheres(int materials, int stage, int threads) {
  return two_spheres_at(5, materials, stage, threads);
}

/* Faces of the mesh keyed by their sorted nodes, with their elements. */
typedef struct {
  uint32_t v[4];
  uint32_t cell;
} face_rec;

static int cmp_face(const void *x, const void *y) {
  const face_rec *a = x, *b = y;
  return memcmp(a->v, b->v, sizeof a->v);
}

static void test_two_spheres(void) {
  mx_mesher *m = two_spheres(1, MX_STAGE_TRANSITION, 2);
  CHECK(mx_mesher_mesh(m) == MX_OK);
  mx_mesh_arrays a;
  CHECK(mx_mesher_mesh_arrays(m, &a) == MX_OK);
  CHECK(a.material != NULL);
  if (!a.material) {
    mx_mesher_free(m);
    return;
  }
  size_t wrong = 0, checked = 0, count[3] = {0, 0, 0};
  double vol[3] = {0, 0, 0}, total = 0;
  for (size_t c = 0; c < a.nelements; c++) {
    const int nv = mx_cell_nodes[a.type[c]];
    double p[3] = {0, 0, 0};
    for (int k = 0; k < nv; k++)
      for (int d = 0; d < 3; d++) p[d] += a.xyz[3 * (size_t)a.conn[8 * c + k] + d] / nv;
    const double r = sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
    const double v = volume(&a, c);
    total += v;
    CHECK(a.material[c] <= 2);
    if (a.material[c] <= 2) {
      vol[a.material[c]] += v;
      count[a.material[c]]++;
    }
    if (fabs(r - 1.0) < 0.01 || fabs(r - 0.5) < 0.01) continue;
    checked++;
    wrong += a.material[c] != (r < 0.5) + (r < 1.0);
  }
  CHECK(wrong == 0);
  CHECK(count[1] > 0 && count[2] > 0);
  CHECK(fabs(vol[0] + vol[1] + vol[2] - total) < 1e-9 * total);
  const double inner = 4.0 / 3.0 * M_PI * 0.125;
  CHECK(fabs(vol[2] - inner) < 0.1 * inner);
  printf("two spheres, -s 5, transition stage: %zu elements (%zu outside, %zu between, %zu "
         "inside); %zu of them checked against their centroid's radius, %zu wrong; inner "
         "volume %.4f (sphere %.4f)\n",
         a.nelements, count[0], count[1], count[2], checked, wrong, vol[2], inner);

  /* interface faces against an independent map of the faces */
  const mx_mesh_view view = {.nnodes = a.nnodes, .xyz = a.xyz, .ncells = a.nelements,
                             .type = a.type, .conn = a.conn};
  int32_t *label = malloc(a.nelements * sizeof *label);
  for (size_t c = 0; c < a.nelements; c++) label[c] = a.material[c] + 1;
  mx_boundary_faces bf;
  CHECK(mx_interface_faces_extract(&view, label, &bf) == MX_OK);
  size_t nrec = 0;
  face_rec *rec = malloc(6 * a.nelements * sizeof *rec);
  for (size_t c = 0; c < a.nelements; c++) {
    const int t = a.type[c];
    for (int f = 0; f < mx_cell_nfaces[t]; f++) {
      const int8_t *fv = mx_cell_faces[t][f];
      face_rec r = {{UINT32_MAX, UINT32_MAX, UINT32_MAX, UINT32_MAX}, (uint32_t)c};
      const int n = fv[3] < 0 ? 3 : 4;
      for (int k = 0; k < n; k++) r.v[k] = a.conn[8 * c + fv[k]];
      for (int i = 1; i < n; i++) /* sorted */
        for (int j = i; j > 0 && r.v[j] < r.v[j - 1]; j--) {
          const uint32_t s = r.v[j];
          r.v[j] = r.v[j - 1], r.v[j - 1] = s;
        }
      rec[nrec++] = r;
    }
  }
  qsort(rec, nrec, sizeof *rec, cmp_face);
  size_t want_interface = 0, want_boundary = 0;
  for (size_t i = 0; i < nrec;) {
    size_t j = i + 1;
    while (j < nrec && !memcmp(rec[j].v, rec[i].v, sizeof rec[i].v)) j++;
    want_boundary += j - i == 1;
    want_interface += j - i == 2 && label[rec[i].cell] != label[rec[i + 1].cell];
    i = j;
  }
  size_t got_interface = 0, got_boundary = 0, bad_pair = 0;
  for (int q = 0; q < 2; q++) {
    const size_t n = q ? bf.nquad : bf.ntri;
    const uint64_t *src = q ? bf.quad_src : bf.tri_src;
    const int32_t *pair = q ? bf.quad_pair : bf.tri_pair;
    for (size_t i = 0; i < n; i++) {
      got_interface += pair[i] != 0;
      got_boundary += pair[i] == 0;
      bad_pair += pair[i] != 0 && pair[i] <= label[src[i] >> 3]; /* from the lower label */
    }
  }
  CHECK(want_interface > 0);
  CHECK(got_interface == want_interface);
  CHECK(got_boundary == want_boundary);
  CHECK(bad_pair == 0);
  printf("interface faces: %zu found, %zu in the face map; boundary faces %zu / %zu\n",
         got_interface, want_interface, got_boundary, want_boundary);
  mx_boundary_faces_free(&bf);
  free(rec);
  free(label);

  /* one thread: the same materials */
  mx_mesher *m1 = two_spheres(1, MX_STAGE_TRANSITION, 1);
  CHECK(mx_mesher_mesh(m1) == MX_OK);
  mx_mesh_arrays a1;
  CHECK(mx_mesher_mesh_arrays(m1, &a1) == MX_OK);
  CHECK(a1.nelements == a.nelements && a1.material &&
        !memcmp(a1.material, a.material, a.nelements * sizeof *a.material));
  mx_mesher_free(m1);
  mx_mesher_free(m);
}

/* The full stage at a level: elements checked against their centroid's
 * radius (wrong ones counted), and the inner material's volume. */
static double full_stage(int level, size_t *wrong, size_t *n) {
  mx_mesher *m = two_spheres_at(level, 1, MX_STAGE_FULL, 0);
  CHECK(mx_mesher_mesh(m) == MX_OK);
  mx_mesh_arrays a;
  CHECK(mx_mesher_mesh_arrays(m, &a) == MX_OK);
  double inner = 0;
  *wrong = *n = 0;
  for (size_t c = 0; a.material && c < a.nelements; c++) {
    const int nv = mx_cell_nodes[a.type[c]];
    double p[3] = {0, 0, 0};
    for (int k = 0; k < nv; k++)
      for (int d = 0; d < 3; d++) p[d] += a.xyz[3 * (size_t)a.conn[8 * c + k] + d] / nv;
    const double r = sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
    if (a.material[c] == 2) inner += volume(&a, c);
    CHECK(a.material[c] == 1 || a.material[c] == 2); /* the domain's: none outside */
    if (fabs(r - 1.0) < 0.01 || fabs(r - 0.5) < 0.01) continue;
    (*n)++;
    *wrong += a.material[c] != (r < 0.5) + (r < 1.0);
  }
  CHECK(a.material != NULL && a.invalid == 0);
  mx_mesher_free(m);
  return inner;
}

/* The volume the triangles of a closed outward surface enclose. */
static double enclosed(const double *x, const uint32_t *t, size_t nt) {
  double v = 0;
  for (size_t i = 0; i < nt; i++) {
    const double *a = x + 3 * (size_t)t[3 * i], *b = x + 3 * (size_t)t[3 * i + 1],
                 *c = x + 3 * (size_t)t[3 * i + 2];
    v += (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) +
          a[2] * (b[0] * c[1] - b[1] * c[0])) / 6.0;
  }
  return v;
}

static void test_full_stage(void) {
  double *x;
  uint32_t *t;
  size_t nv, nt;
  sphere(0.5, 24, &x, &nv, &t, &nt);
  const double vt = enclosed(x, t, nt);
  free(x);
  free(t);
  size_t w4, n4, w5, n5;
  const double v4 = full_stage(4, &w4, &n4), v5 = full_stage(5, &w5, &n5);
  CHECK(w4 == 0 && w5 == 0);
  CHECK(fabs(v4 - vt) < 0.03 * vt);
  CHECK(fabs(v5 - vt) < 0.01 * vt);
  printf("full stage: inner material's volume %.4f at -s 4, %.4f at -s 5 (its triangles "
         "enclose %.4f); %zu + %zu elements checked, %zu + %zu wrong\n", v4, v5, vt, n4, n5,
         w4, w5);
}

static void test_refusals_and_holes(void) {
  /* without materials the inner sphere is a hole */
  mx_mesher *m = two_spheres(0, MX_STAGE_TRANSITION, 0);
  CHECK(mx_mesher_mesh(m) == MX_OK);
  mx_mesh_arrays a;
  CHECK(mx_mesher_mesh_arrays(m, &a) == MX_OK);
  CHECK(a.material == NULL);
  size_t deep = 0;
  for (size_t c = 0; c < a.nelements; c++) {
    const int nv = mx_cell_nodes[a.type[c]];
    double p[3] = {0, 0, 0};
    for (int k = 0; k < nv; k++)
      for (int d = 0; d < 3; d++) p[d] += a.xyz[3 * (size_t)a.conn[8 * c + k] + d] / nv;
    deep += sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]) < 0.4;
  }
  CHECK(deep == 0);
  mx_mesher_free(m);
}

static void quiet(void *user, int level, const char *text) {
  (void)user, (void)level, (void)text;
}

int main(void) {
  mx_set_thread_message_handler(quiet, NULL);
  test_two_spheres();
  test_full_stage();
  test_refusals_and_holes();
  return TEST_DONE();
}
