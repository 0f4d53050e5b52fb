/* Several materials at the full stage: the interfaces cleaved (issue 26,
 * item 2; src/kernels/interfaces.c, cleave.c). Derived, not recorded:
 *
 *  - three concentric spheres (radii 1, 0.6, 0.3): every element lies in
 *    one region: the nodes of an element that are off every sphere (beyond
 *    the tessellation's chordal error) have radii in one region, which is
 *    the element's material; no element is inverted; every face between
 *    two materials has all its nodes on the sphere between them (radius
 *    within the chordal error), every face used by one element only lies on
 *    the outer sphere, none is used by three; each material's volume is
 *    within 2% of what its triangles enclose (-s 5); the same arrays with
 *    1 and 2 threads;
 *  - touching inputs: two boxes glued on the face x = 0.37 (off the
 *    octree's lattice) and an L of three boxes glued on grid faces: the
 *    same checks with the box of each element's free nodes, the interface
 *    nodes exactly on the common face (|x - 0.37| < 1e-12), each material's
 *    volume within 3% of its box's (the corners are rounded off: no sharp
 *    features yet);
 *  - one input with internal faces (the two glued boxes as one surface,
 *    their common face once: edges of three triangles): the same checks,
 *    its regions told apart (src/mesher/material_complex.c);
 *  - a level of one input (mx_mesher_set_input_level): two spheres at -s 3
 *    with the inner one's surface at level 5: every element with a face
 *    on the interface comes from a leaf of level 5, every one with a face
 *    on the boundary from one below 5 (the spheres lie 0.4 apart,
 *    more than the balance's grading from 5 to 3); with the inner one's
 *    inside at level 4 instead, every element of its material is of level
 *    4 or more;
 *  - re-meshing keeps the materials: three spheres at -s 4, the elements of
 *    the middle material within 0.05 of the middle sphere split once (the
 *    whole octree meshed again, the interfaces cleaved), then written as a
 *    restart file and read back into a new mesher with the same inputs and
 *    meshed again: every element still in one region, its material the
 *    region's, and the same materials' volumes within 2% as before;
 *  - refused (MX_EINPUT): two boxes that overlap, two that touch along an
 *    edge only (a non-manifold union), two that touch at one corner. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "check.h"
#include "test_shapes.h"
#include "mixoct.h"
#include "soa/mesh.h"

/* Set: the next meshers are made without materials (a restart file written
 * with them turns them on). */
static int one_material;

static mx_mesher *new_mesher(int level, int threads) {
  mx_params p;
  mx_params_default(&p);
  p.surface_level = level;
  p.materials = !one_material;
  p.threads = threads;
  return mx_mesher_new(&p);
}

static int add_box(mx_mesher *m, const char *name, const double lo[3], const double hi[3]) {
  double *x;
  uint32_t *t;
  size_t nv, nt;
  box(lo, hi, 4, &x, &nv, &t, &nt);
  const int st = mx_mesher_add_surface_arrays(m, name, nv, x, nt, t);
  free(x);
  free(t);
  return st;
}

/* ---- faces: every element face keyed by its sorted nodes ---- */

typedef struct {
  uint32_t v[4];
  uint32_t cell;
} face_rec;

static int cmp_face(const void *x, const void *y) {
  const face_rec *a = x, *b = y;
  const int c = memcmp(a->v, b->v, sizeof a->v);
  return c ? c : (a->cell > b->cell) - (a->cell < b->cell);
}

static void sort4(uint32_t *v, int n) {
  for (int i = 1; i < n; i++)
    for (int j = i; j > 0 && v[j - 1] > v[j]; j--) {
      const uint32_t x = v[j];
      v[j] = v[j - 1];
      v[j - 1] = x;
    }
}

/* The faces; calls on_face(ctx, nodes, n, c1, c2) for each (c2 UINT32_MAX
 * for a face of one element); returns the faces used by three or more. */
static size_t each_face(const mx_mesh_arrays *a,
                        void (*on_face)(void *, const uint32_t *, int, uint32_t, uint32_t),
                        void *ctx) {
  size_t nf = 0;
  for (size_t c = 0; c < a->nelements; c++) nf += (size_t)mx_cell_nfaces[a->type[c]];
  face_rec *F = malloc(nf * sizeof *F);
  size_t k = 0;
  for (size_t c = 0; c < a->nelements; c++) {
    const int t = a->type[c];
    for (int f = 0; f < mx_cell_nfaces[t]; f++) {
      const int8_t *fv = mx_cell_faces[t][f];
      const int n = fv[3] < 0 ? 3 : 4;
      F[k].v[3] = UINT32_MAX;
      for (int i = 0; i < n; i++) F[k].v[i] = a->conn[8 * c + fv[i]];
      sort4(F[k].v, n);
      F[k].cell = (uint32_t)c;
      k++;
    }
  }
  qsort(F, nf, sizeof *F, cmp_face);
  size_t over = 0;
  for (size_t i = 0; i < nf;) {
    size_t j = i + 1;
    while (j < nf && !memcmp(F[j].v, F[i].v, sizeof F[i].v)) j++;
    const int n = F[i].v[3] == UINT32_MAX ? 3 : 4;
    if (j - i > 2) over++;
    else on_face(ctx, F[i].v, n, F[i].cell, j - i == 2 ? F[i + 1].cell : UINT32_MAX);
    i = j;
  }
  free(F);
  return over;
}

/* ---- three concentric spheres ---- */

static const double R[3] = {1.0, 0.6, 0.3};
static double chord[3]; /* each sphere's tessellation: largest distance below its radius */

/* The region of a point by its radius (1 .. 3), 0 beyond the outer
 * sphere; -1 within a sphere's chordal error (on it). */
static int sphere_region(const double *p) {
  const double r = sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
  for (int i = 0; i < 3; i++)
    if (r <= R[i] + 1e-9 && r >= R[i] - chord[i] - 1e-9) return -1;
  return r > R[0] ? 0 : r > R[1] ? 1 : r > R[2] ? 2 : 3;
}

typedef struct {
  const mx_mesh_arrays *a;
  size_t interface_faces, interface_off, boundary_faces, boundary_off;
} sphere_faces;

static int on_sphere(const double *p, int i) {
  const double r = sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
  return r <= R[i] + 1e-9 && r >= R[i] - chord[i] - 1e-9;
}

static void sphere_face(void *ctx, const uint32_t *v, int n, uint32_t c1, uint32_t c2) {
  sphere_faces *S = ctx;
  const mx_mesh_arrays *a = S->a;
  if (c2 == UINT32_MAX) {
    S->boundary_faces++;
    for (int i = 0; i < n; i++) S->boundary_off += !on_sphere(a->xyz + 3 * (size_t)v[i], 0);
    return;
  }
  const int m1 = a->material[c1], m2 = a->material[c2];
  if (m1 == m2) return;
  S->interface_faces++;
  const int s = (m1 > m2 ? m1 : m2) - 1; /* the sphere between materials s and s + 1 */
  for (int i = 0; i < n; i++) S->interface_off += !on_sphere(a->xyz + 3 * (size_t)v[i], s);
}

static double enclosed(const double *x, const uint32_t *t, size_t nt) {
  double v = 0;
  for (size_t f = 0; f < nt; f++) {
    const double *a = x + 3 * (size_t)t[3 * f], *b = x + 3 * (size_t)t[3 * f + 1],
                 *c = x + 3 * (size_t)t[3 * f + 2];
    v += (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) +
          a[2] * (b[0] * c[1] - b[1] * c[0])) / 6.0;
  }
  return v;
}

static mx_mesher *three_spheres(int level, int threads, double inside[3]) {
  mx_mesher *m = new_mesher(level, threads);
  static const int rings[3] = {32, 24, 16};
  for (int i = 0; i < 3; i++) {
    double *x;
    uint32_t *t;
    size_t nv, nt;
    sphere(R[i], rings[i], &x, &nv, &t, &nt);
    /* the chordal error: no point of a triangle is nearer the centre than
     * its plane, so R less the least plane distance bounds it */
    double worst = 0;
    for (size_t f = 0; f < nt; f++) {
      const double *p = x + 3 * (size_t)t[3 * f], *q = x + 3 * (size_t)t[3 * f + 1],
                   *o = x + 3 * (size_t)t[3 * f + 2];
      double u[3], w[3];
      for (int d = 0; d < 3; d++) u[d] = q[d] - p[d], w[d] = o[d] - p[d];
      const double nrm[3] = {u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2],
                             u[0] * w[1] - u[1] * w[0]};
      const double len = sqrt(nrm[0] * nrm[0] + nrm[1] * nrm[1] + nrm[2] * nrm[2]);
      const double h = fabs(nrm[0] * p[0] + nrm[1] * p[1] + nrm[2] * p[2]) / len;
      worst = fmax(worst, R[i] - h);
    }
    chord[i] = worst;
    inside[i] = enclosed(x, t, nt);
    char name[16];
    snprintf(name, sizeof name, "sphere%d", i);
    CHECK(mx_mesher_add_surface_arrays(m, name, nv, x, nt, t) == MX_OK);
    free(x);
    free(t);
  }
  return m;
}

static void test_three_spheres(void) {
  double inside[3];
  mx_mesher *m = three_spheres(5, 2, inside);
  CHECK(mx_mesher_mesh(m) == MX_OK);
  mx_mesh_arrays a;
  CHECK(mx_mesher_mesh_arrays(m, &a) == MX_OK);
  CHECK(a.material != NULL && a.invalid == 0 && a.jens_min > 0);
  if (!a.material) {
    mx_mesher_free(m);
    return;
  }
  size_t across = 0, wrong = 0, inverted = 0;
  double vol[4] = {0, 0, 0, 0};
  for (size_t c = 0; c < a.nelements; c++) {
    const int nv = mx_cell_nodes[a.type[c]];
    int region = -1, two = 0;
    for (int k = 0; k < nv; k++) {
      const int r = sphere_region(a.xyz + 3 * (size_t)a.conn[8 * c + k]);
      if (r < 0) continue;
      if (region >= 0 && r != region) two = 1;
      region = r;
    }
    across += two;
    wrong += region >= 1 && !two && region != a.material[c];
    const double v = volume(&a, c);
    inverted += !(v > 0);
    if (a.material[c] <= 3) vol[a.material[c]] += v;
  }
  CHECK(across == 0);
  CHECK(wrong == 0);
  CHECK(inverted == 0);
  sphere_faces S = {&a, 0, 0, 0, 0};
  CHECK(each_face(&a, sphere_face, &S) == 0);
  CHECK(S.interface_faces > 0 && S.interface_off == 0);
  CHECK(S.boundary_faces > 0 && S.boundary_off == 0);
  const double want[4] = {0, inside[0] - inside[1], inside[1] - inside[2], inside[2]};
  for (int i = 1; i <= 3; i++) CHECK(fabs(vol[i] - want[i]) < 0.02 * want[i]);
  printf("three spheres -s 5: %zu elements, worst J_ENS %.3f, volumes %+.3f%% %+.3f%% "
         "%+.3f%%, %zu interface faces\n", a.nelements, a.jens_min,
         100 * (vol[1] / want[1] - 1), 100 * (vol[2] / want[2] - 1),
         100 * (vol[3] / want[3] - 1), S.interface_faces);
  /* one thread: the same arrays */
  mx_mesher *m1 = three_spheres(5, 1, inside);
  CHECK(mx_mesher_mesh(m1) == MX_OK);
  mx_mesh_arrays b;
  CHECK(mx_mesher_mesh_arrays(m1, &b) == MX_OK);
  CHECK(b.nnodes == a.nnodes && b.nelements == a.nelements && b.material &&
        !memcmp(b.xyz, a.xyz, 3 * a.nnodes * sizeof *a.xyz) &&
        !memcmp(b.conn, a.conn, 8 * a.nelements * sizeof *a.conn) &&
        !memcmp(b.material, a.material, a.nelements * sizeof *a.material));
  mx_mesher_free(m1);
  mx_mesher_free(m);
}

/* ---- boxes that touch ---- */

typedef struct {
  int n;
  double lo[3][3], hi[3][3];
} boxes;

/* The box holding p strictly (beyond 1e-9 of its faces), 1 .. n; -1 on a
 * face of one, 0 outside all. */
static int box_of(const boxes *B, const double *p) {
  for (int b = 0; b < B->n; b++) {
    int in = 1, on = 1;
    for (int d = 0; d < 3; d++) {
      in &= p[d] > B->lo[b][d] + 1e-9 && p[d] < B->hi[b][d] - 1e-9;
      on &= p[d] >= B->lo[b][d] - 1e-9 && p[d] <= B->hi[b][d] + 1e-9;
    }
    if (in) return b + 1;
    if (on) return -1;
  }
  return 0;
}

typedef struct {
  const mx_mesh_arrays *a;
  const boxes *B;
  size_t interface_faces, interface_off;
} box_faces;

static void box_face(void *ctx, const uint32_t *v, int n, uint32_t c1, uint32_t c2) {
  box_faces *S = ctx;
  const mx_mesh_arrays *a = S->a;
  if (c2 == UINT32_MAX || a->material[c1] == a->material[c2]) return;
  S->interface_faces++;
  /* on the common face of the two boxes: the coordinate where one's hi is
   * the other's lo */
  const int b1 = a->material[c1] - 1, b2 = a->material[c2] - 1;
  int axis = -1;
  double at = 0;
  for (int d = 0; d < 3; d++) {
    if (S->B->hi[b1][d] == S->B->lo[b2][d]) axis = d, at = S->B->hi[b1][d];
    if (S->B->hi[b2][d] == S->B->lo[b1][d]) axis = d, at = S->B->hi[b2][d];
  }
  for (int i = 0; i < n; i++)
    S->interface_off += axis < 0 || fabs(a->xyz[3 * (size_t)v[i] + axis] - at) > 1e-12;
}

/* The boxes as one surface with internal faces: their triangles together,
 * the vertices of equal coordinates welded and each common triangle once. */
static int add_complex(mx_mesher *m, const boxes *B) {
  double *X = malloc(3 * 4096 * sizeof *X);
  uint32_t *T = malloc(3 * 8192 * sizeof *T);
  size_t nv = 0, nt = 0;
  for (int b = 0; b < B->n; b++) {
    double *x;
    uint32_t *t;
    size_t bv, bt;
    box(B->lo[b], B->hi[b], 4, &x, &bv, &t, &bt);
    uint32_t *id = malloc(bv * sizeof *id);
    for (size_t v = 0; v < bv; v++) {
      size_t e = 0;
      while (e < nv && memcmp(X + 3 * e, x + 3 * v, 3 * sizeof *X)) e++;
      if (e == nv) memcpy(X + 3 * nv++, x + 3 * v, 3 * sizeof *X);
      id[v] = (uint32_t)e;
    }
    for (size_t f = 0; f < bt; f++) {
      uint32_t g[3] = {id[t[3 * f]], id[t[3 * f + 1]], id[t[3 * f + 2]]}, s1[3], s2[3];
      memcpy(s1, g, sizeof g);
      sort4(s1, 3);
      int seen = 0;
      for (size_t e = 0; e < nt && !seen; e++) {
        memcpy(s2, T + 3 * e, sizeof s2);
        sort4(s2, 3);
        seen = !memcmp(s1, s2, sizeof s1);
      }
      if (!seen) memcpy(T + 3 * nt++, g, sizeof g);
    }
    free(id);
    free(x);
    free(t);
  }
  const int st = mx_mesher_add_surface_arrays(m, "complex", nv, X, nt, T);
  free(X);
  free(T);
  return st;
}

static void test_boxes(const boxes *B, const char *what, int one_input) {
  mx_mesher *m = new_mesher(4, 2);
  if (one_input) CHECK(add_complex(m, B) == MX_OK);
  for (int b = 0; b < B->n && !one_input; b++) {
    char name[16];
    snprintf(name, sizeof name, "box%d", b + 1);
    CHECK(add_box(m, name, B->lo[b], B->hi[b]) == MX_OK);
  }
  CHECK(mx_mesher_mesh(m) == MX_OK);
  mx_mesh_arrays a;
  CHECK(mx_mesher_mesh_arrays(m, &a) == MX_OK);
  CHECK(a.material != NULL && a.invalid == 0);
  if (!a.material) {
    mx_mesher_free(m);
    return;
  }
  size_t across = 0, wrong = 0, inverted = 0;
  double vol[4] = {0, 0, 0, 0};
  for (size_t c = 0; c < a.nelements; c++) {
    const int nv = mx_cell_nodes[a.type[c]];
    int region = -1, two = 0;
    for (int k = 0; k < nv; k++) {
      const int r = box_of(B, a.xyz + 3 * (size_t)a.conn[8 * c + k]);
      if (r < 0) continue;
      if (region >= 0 && r != region) two = 1;
      region = r;
    }
    across += two;
    wrong += region >= 1 && !two && region != a.material[c];
    const double v = volume(&a, c);
    inverted += !(v > 0);
    if (a.material[c] >= 1 && a.material[c] <= 3) vol[a.material[c]] += v;
  }
  CHECK(across == 0);
  CHECK(wrong == 0);
  CHECK(inverted == 0);
  box_faces S = {&a, B, 0, 0};
  CHECK(each_face(&a, box_face, &S) == 0);
  CHECK(S.interface_faces > 0 && S.interface_off == 0);
  for (int b = 0; b < B->n; b++) {
    double want = 1;
    for (int d = 0; d < 3; d++) want *= B->hi[b][d] - B->lo[b][d];
    CHECK(fabs(vol[b + 1] - want) < 0.03 * want);
  }
  printf("%s -s 4: %zu elements, worst J_ENS %.3f, %zu interface faces, material volumes",
         what, a.nelements, a.jens_min, S.interface_faces);
  for (int b = 1; b <= B->n; b++) printf(" %.4f", vol[b]);
  printf("\n");
  mx_mesher_free(m);
}

static void test_refused(void) {
  static const struct {
    double lo2[3], hi2[3];
    const char *what;
  } cases[] = {{{0.5, 0.5, 0.5}, {1.5, 1.5, 1.5}, "overlapping"},
               {{1, 1, 0}, {2, 2, 1}, "touching along an edge"},
               {{1, 1, 1}, {2, 2, 2}, "touching at a corner"}};
  const double lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
  for (size_t i = 0; i < sizeof cases / sizeof *cases; i++) {
    mx_mesher *m = new_mesher(3, 1);
    CHECK(add_box(m, "a", lo, hi) == MX_OK);
    CHECK(add_box(m, "b", cases[i].lo2, cases[i].hi2) == MX_OK);
    const int st = mx_mesher_mesh(m);
    if (st != MX_EINPUT) printf("%s: status %d, want MX_EINPUT\n", cases[i].what, st);
    CHECK(st == MX_EINPUT);
    mx_mesher_free(m);
  }
}

typedef struct {
  const mx_mesh_arrays *a;
  uint8_t *mark; /* 1: at the interface, 2: at the boundary */
} level_marks;

static void mark_face(void *ctx, const uint32_t *v, int n, uint32_t c1, uint32_t c2) {
  level_marks *L = ctx;
  (void)v, (void)n;
  if (c2 == UINT32_MAX) {
    L->mark[c1] |= 2;
  } else if (L->a->material[c1] != L->a->material[c2]) {
    L->mark[c1] |= 1;
    L->mark[c2] |= 1;
  }
}

static void test_input_levels(void) {
  for (int inside = 0; inside < 2; inside++) {
    mx_mesher *m = new_mesher(3, 2);
    for (int i = 0; i < 2; i++) {
      double *x;
      uint32_t *t;
      size_t nv, nt;
      sphere(R[i], 24, &x, &nv, &t, &nt);
      CHECK(mx_mesher_add_surface_arrays(m, i ? "inner" : "outer", nv, x, nt, t) == MX_OK);
      free(x);
      free(t);
    }
    CHECK(mx_mesher_set_input_level(m, 2, 5, 0) == MX_EINPUT); /* no input 2 */
    CHECK(mx_mesher_set_input_level(m, 1, inside ? 0 : 5, inside ? 4 : 0) == MX_OK);
    CHECK(mx_mesher_mesh(m) == MX_OK);
    mx_mesh_arrays a;
    CHECK(mx_mesher_mesh_arrays(m, &a) == MX_OK);
    CHECK(a.material != NULL && a.invalid == 0);
    /* the elements at the interface (a face between the two materials)
     * and at the boundary (a face of one element only) */
    level_marks L = {&a, calloc(a.nelements + 1, 1)};
    if (a.material) CHECK(each_face(&a, mark_face, &L) == 0);
    size_t inner_low = 0, outer_high = 0, inner_n = 0, mat2_low = 0;
    for (size_t c = 0; a.material && c < a.nelements; c++) {
      inner_n += L.mark[c] & 1;
      inner_low += (L.mark[c] & 1) && a.level[c] < 5;
      outer_high += (L.mark[c] & 2) && a.level[c] >= 5;
      mat2_low += a.material[c] == 2 && a.level[c] < 4;
    }
    free(L.mark);
    if (!inside) {
      CHECK(inner_n > 0 && inner_low == 0 && outer_high == 0);
    } else {
      CHECK(mat2_low == 0 && outer_high == 0);
    }
    printf("input level: inner sphere's %s at level %d, %zu elements\n",
           inside ? "inside" : "surface", inside ? 4 : 5, a.nelements);
    mx_mesher_free(m);
  }
}

/* Elements across a region and elements whose material is not their
 * region's (by the spheres' radii), and each material's volume. */
static void judge_spheres(const mx_mesh_arrays *a, size_t *across, size_t *wrong, double vol[4]) {
  *across = *wrong = 0;
  vol[0] = vol[1] = vol[2] = vol[3] = 0;
  for (size_t c = 0; c < a->nelements; c++) {
    int region = -1, two = 0;
    for (int k = 0; k < mx_cell_nodes[a->type[c]]; k++) {
      const int r = sphere_region(a->xyz + 3 * (size_t)a->conn[8 * c + k]);
      if (r < 0) continue;
      if (region >= 0 && r != region) two = 1;
      region = r;
    }
    *across += two;
    *wrong += region >= 1 && !two && region != a->material[c];
    if (a->material[c] <= 3) vol[a->material[c]] += volume(a, c);
  }
}

static void test_remesh(void) {
  double inside[3], v0[4], v1[4], v2[4];
  size_t across, wrong;
  mx_mesher *m = three_spheres(4, 2, inside);
  CHECK(mx_mesher_mesh(m) == MX_OK);
  mx_mesh_arrays a;
  CHECK(mx_mesher_mesh_arrays(m, &a) == MX_OK);
  CHECK(a.material != NULL);
  if (!a.material) {
    mx_mesher_free(m);
    return;
  }
  judge_spheres(&a, &across, &wrong, v0);
  uint64_t *list = malloc(a.nelements * sizeof *list);
  size_t n = 0;
  for (size_t c = 0; c < a.nelements; c++) {
    double p[3] = {0, 0, 0};
    const int nv = mx_cell_nodes[a.type[c]];
    for (int k = 0; k < nv; k++)
      for (int d = 0; d < 3; d++) p[d] += a.xyz[3 * (size_t)a.conn[8 * c + k] + d] / nv;
    if (a.material[c] == 2 && fabs(sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]) - R[1]) < 0.05)
      list[n++] = c;
  }
  const size_t before = a.nelements;
  CHECK(n > 0 && mx_mesher_refine_elements(m, list, n) == MX_OK);
  free(list);
  CHECK(mx_mesher_mesh_arrays(m, &a) == MX_OK);
  CHECK(a.material != NULL && a.invalid == 0 && a.nelements > before);
  judge_spheres(&a, &across, &wrong, v1);
  CHECK(across == 0 && wrong == 0);
  for (int i = 1; i <= 3; i++) CHECK(fabs(v1[i] - v0[i]) < 0.02 * v0[i]);
  const size_t after = a.nelements;
  /* the restart file (text, then binary) with the same inputs: the same
   * mesh, the same materials, in a mesher made without materials (the file
   * records them) */
  for (int binary = 0; binary < 2; binary++) {
    char path[64];
    snprintf(path, sizeof path, "/tmp/mx_material_remesh_%d.oct%s", (int)getpid(),
             binary ? "b" : "");
    CHECK(mx_mesher_save_restart(m, path) == MX_OK);
    one_material = 1;
    mx_mesher *r = three_spheres(4, 1, inside);
    one_material = 0;
    mx_mesh_arrays b;
    CHECK(mx_mesher_load_restart(r, path) == MX_OK);
    CHECK(mx_mesher_mesh(r) == MX_OK);
    CHECK(mx_mesher_mesh_arrays(r, &b) == MX_OK);
    CHECK(b.material != NULL && b.nelements == after);
    if (b.material) {
      judge_spheres(&b, &across, &wrong, v2);
      CHECK(across == 0 && wrong == 0);
      for (int i = 1; i <= 3; i++) CHECK(fabs(v2[i] - v1[i]) < 1e-9 * v1[i]);
    }
    remove(path);
    mx_mesher_free(r);
  }
  printf("re-mesh with materials: %zu elements, then %zu; from the restart files the same\n",
         before, after);
  mx_mesher_free(m);
}

static void quiet(void *user, int level, const char *text) {
  (void)user, (void)level, (void)text;
}

int main(void) {
  mx_set_thread_message_handler(quiet, NULL);
  test_three_spheres();
  const boxes glued = {2, {{0, 0, 0}, {0.37, 0, 0}}, {{0.37, 1, 1}, {1, 1, 1}}};
  test_boxes(&glued, "two boxes glued at x = 0.37", 0);
  test_boxes(&glued, "one box split at x = 0.37 by an internal face", 1);
  const boxes ell = {3, {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {{1, 1, 1}, {2, 1, 1}, {1, 2, 1}}};
  test_boxes(&ell, "an L of three boxes", 0);
  test_input_levels();
  test_remesh();
  test_refused();
  return TEST_DONE();
}
