/* The smoothing (kernels/smooth.h) on meshes the library makes of a sphere
 * and a box (smoothing off), checked by routines of this file that share
 * nothing with the smoother but the J_ENS function:
 *  - no node's neighbourhood minimum (least J_ENS of the elements having
 *    it as a node, recomputed from the positions) decreases;
 *  - the mesh's minimum rises: on the sphere at -s 5, whose worst elements
 *    come from the boundary (0.2137 to the transition patterns' own least,
 *    0.2309, when written); on the box it is the patterns' own least (flat
 *    faces on the lattice): there it stays (and stays put when no node
 *    moved);
 *  - every node on a boundary face (a face used by one element, found by
 *    sorting the faces) is as close to the input triangles as before, or
 *    within 1e-9 of the bounding box diagonal (brute force over the
 *    triangles, not the surface index);
 *  - no element is invalid;
 *  - the same positions, byte for byte, on 1 and 2 threads;
 *  - a node the movable mask fixes stays where it was. */
#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "geom/distance.h"
#include "geom/quality.h"
#include "kernels/smooth.h"
#include "mesher/mesher.h"
#include "mixoct.h"
#include "soa/mesh.h"
#include "test_shapes.h"

/* J_ENS of every element from the positions, and each node's least. */
static void node_minima(const mx_mesh *M, double *J, double *nmin) {
  for (size_t v = 0; v < M->nnodes; v++) nmin[v] = INFINITY;
  for (size_t c = 0; c < M->ncells; c++) {
    double x[8][3];
    const int nv = mx_cell_nodes[M->type[c]];
    for (int k = 0; k < nv; k++) memcpy(x[k], M->xyz + 3 * (size_t)M->conn[8 * c + k], sizeof x[k]);
    J[c] = mx_jens(M->type[c], x);
    for (int k = 0; k < nv; k++) {
      const uint32_t v = M->conn[8 * c + k];
      if (J[c] < nmin[v]) nmin[v] = J[c];
    }
  }
}

typedef struct {
  uint32_t n[4]; /* sorted node ids, UINT32_MAX last for a triangle */
} face;

static int cmp_face(const void *a, const void *b) {
  return memcmp(a, b, sizeof(face));
}

static int cmp_u32(const void *a, const void *b) {
  const uint32_t x = *(const uint32_t *)a, y = *(const uint32_t *)b;
  return (x > y) - (x < y);
}

/* on[v] = 1 for the nodes of faces used by one element. */
static void boundary_nodes(const mx_mesh *M, uint8_t *on) {
  size_t nf = 0;
  for (size_t c = 0; c < M->ncells; c++) nf += (size_t)mx_cell_nfaces[M->type[c]];
  face *F = malloc(nf * sizeof *F);
  size_t k = 0;
  for (size_t c = 0; c < M->ncells; c++) {
    const int t = M->type[c];
    for (int f = 0; f < mx_cell_nfaces[t]; f++) {
      const int8_t *fv = mx_cell_faces[t][f];
      face g = {{UINT32_MAX, UINT32_MAX, UINT32_MAX, UINT32_MAX}};
      for (int i = 0; i < 4 && fv[i] >= 0; i++) g.n[i] = M->conn[8 * c + fv[i]];
      qsort(g.n, 4, sizeof *g.n, cmp_u32);
      F[k++] = g;
    }
  }
  qsort(F, nf, sizeof *F, cmp_face);
  memset(on, 0, M->nnodes);
  for (size_t i = 0; i < nf;) {
    size_t j = i + 1;
    while (j < nf && !cmp_face(&F[i], &F[j])) j++;
    if (j - i == 1)
      for (int a = 0; a < 4 && F[i].n[a] != UINT32_MAX; a++) on[F[i].n[a]] = 1;
    i = j;
  }
  free(F);
}

/* Distance from p to the nearest of the nt triangles, by brute force. */
static double surface_distance(const double *xyz, const uint32_t *tri, size_t nt, const double *p) {
  double best = INFINITY;
  for (size_t t = 0; t < nt; t++) {
    double T[9], q[3];
    for (int i = 0; i < 3; i++) memcpy(T + 3 * i, xyz + 3 * (size_t)tri[3 * t + i], 3 * sizeof *T);
    const double d2 = mx_closest_on_triangle(T, p, q);
    if (d2 < best) best = d2;
  }
  return sqrt(best);
}

/* A copy of the positions and J_ENS of the mesher's mesh (the rest shared,
 * read-only for the smoothing). */
static mx_mesh copy_of(const mx_mesh *M) {
  mx_mesh C = *M;
  C.xyz = malloc(3 * M->nnodes * sizeof *C.xyz);
  C.jens = malloc(M->ncells * sizeof *C.jens);
  memcpy(C.xyz, M->xyz, 3 * M->nnodes * sizeof *C.xyz);
  memcpy(C.jens, M->jens, M->ncells * sizeof *C.jens);
  return C;
}

static void smooth_shape(const char *name, const double *sx, size_t nv, const uint32_t *tri,
                         size_t nt, int level, int must_rise) {
  mx_params p;
  mx_params_default(&p);
  p.surface_level = level;
  p.smooth_rounds = 0;
  mx_mesher *m = mx_mesher_new(&p);
  CHECK(m && mx_mesher_add_surface_arrays(m, name, nv, sx, nt, tri) == MX_OK);
  CHECK(mx_mesher_mesh(m) == MX_OK);
  const mx_mesh *M = &m->M;
  const size_t nn = M->nnodes, nc = M->ncells;
  double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
  for (size_t i = 0; i < nv; i++)
    for (int a = 0; a < 3; a++) lo[a] = fmin(lo[a], sx[3 * i + a]), hi[a] = fmax(hi[a], sx[3 * i + a]);
  const double diag = sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                           (hi[2] - lo[2]) * (hi[2] - lo[2]));
  double *J0 = malloc(nc * sizeof *J0), *J1 = malloc(nc * sizeof *J1);
  double *n0 = malloc(nn * sizeof *n0), *n1 = malloc(nn * sizeof *n1);
  uint8_t *bnd = malloc(nn);
  node_minima(M, J0, n0);
  boundary_nodes(M, bnd);
  double min0 = INFINITY;
  for (size_t c = 0; c < nc; c++) min0 = fmin(min0, J0[c]);
  /* every node worked on (a target above 1), and the default target */
  const double targets[2] = {2.0, MX_SMOOTH_TARGET};
  for (int ti = 0; ti < 2; ti++) {
    mx_mesh A = copy_of(M), B = copy_of(M);
    const mx_smooth_opts o = {4, targets[ti], NULL};
    mx_smooth_stats sa, sb;
    omp_set_num_threads(1);
    CHECK(mx_smooth(&A, m->states, &m->SI, &o, &sa) == MX_OK);
    omp_set_num_threads(2);
    CHECK(mx_smooth(&B, m->states, &m->SI, &o, &sb) == MX_OK);
    CHECK(memcmp(A.xyz, B.xyz, 3 * nn * sizeof *A.xyz) == 0); /* 1 and 2 threads */
    CHECK(memcmp(A.jens, B.jens, nc * sizeof *A.jens) == 0);
    node_minima(&A, J1, n1);
    size_t lowered = 0, invalid = 0, off_surface = 0, moved = 0;
    double min1 = INFINITY, dmax = 0.0;
    for (size_t v = 0; v < nn; v++) {
      lowered += n1[v] < n0[v];
      moved += memcmp(A.xyz + 3 * v, M->xyz + 3 * v, 3 * sizeof *A.xyz) != 0;
      if (!bnd[v]) continue;
      const double d0 = surface_distance(sx, tri, nt, M->xyz + 3 * v);
      const double d1 = surface_distance(sx, tri, nt, A.xyz + 3 * v);
      dmax = fmax(dmax, d1 / diag);
      off_surface += d1 > fmax(d0, 1e-9 * diag);
    }
    for (size_t c = 0; c < nc; c++) {
      min1 = fmin(min1, J1[c]);
      invalid += mx_jens_invalid(J1[c]);
      CHECK(A.jens[c] == (float)J1[c]); /* the mesh's J_ENS kept up to date */
    }
    printf("%s -s %d target %.2f: %zu nodes, %zu moved (stats %zu, %zu moves, %d rounds), "
           "J_ENS min %.6f -> %.6f (stats %.6f), boundary distance <= %.2e diag\n",
           name, level, targets[ti], nn, moved, sa.moved, sa.moves, sa.rounds, min0, min1,
           sa.jens_min_after, dmax);
    CHECK(lowered == 0);
    CHECK(invalid == 0);
    CHECK(off_surface == 0);
    CHECK(moved == sa.moved);
    CHECK(min1 >= min0);
    CHECK(moved > 0 || min1 == min0);
    CHECK(!must_rise || min1 > min0);
    CHECK(fabs(sa.jens_min_after - (double)(float)min1) < 1e-12);
    if (ti == 0) {
      /* the movable mask: every other node fixed */
      mx_mesh C = copy_of(M);
      uint8_t *mov = malloc(nn);
      for (size_t v = 0; v < nn; v++) mov[v] = (uint8_t)(v % 2);
      const mx_smooth_opts om = {4, targets[ti], mov};
      mx_smooth_stats sc;
      CHECK(mx_smooth(&C, m->states, &m->SI, &om, &sc) == MX_OK);
      size_t fixed_moved = 0;
      for (size_t v = 0; v < nn; v += 2)
        fixed_moved += memcmp(C.xyz + 3 * v, M->xyz + 3 * v, 3 * sizeof *C.xyz) != 0;
      CHECK(fixed_moved == 0);
      CHECK(sc.moved > 0);
      free(mov);
      free(C.xyz);
      free(C.jens);
    }
    free(A.xyz);
    free(A.jens);
    free(B.xyz);
    free(B.jens);
  }
  free(J0);
  free(J1);
  free(n0);
  free(n1);
  free(bnd);
  mx_mesher_free(m);
}

int main(void) {
  double *x;
  uint32_t *t;
  size_t nv, nt;
  sphere(1.0, 16, &x, &nv, &t, &nt);
  smooth_shape("sphere", x, nv, t, nt, 5, 1);
  free(x);
  free(t);
  const double lo[3] = {-1.0, -0.7, -0.4}, hi[3] = {1.0, 0.7, 0.4};
  box(lo, hi, 4, &x, &nv, &t, &nt);
  smooth_shape("box", x, nv, t, nt, 4, 0);
  free(x);
  free(t);
  return TEST_DONE();
}
