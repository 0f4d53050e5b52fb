/* Tests of the checker's distance between the mesh's skin and the surface,
 * both ways (src/verify/check_distance.c; definitions in verify/check.h),
 * and of the checker's tree of triangles (check_geometry.c): hand-made
 * meshes with answers derived below, a brute-force reference of
 * the same sampling (every sample against every triangle, through the
 * mesher's own closest-point routine, geom/distance.h), the same digits
 * with 1 and 2 threads, and `mixoct check --json`'s keys. */
#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "check.h"
#include "base/common.h"
#include "geom/distance.h"
#include "soa/mesh.h"
#include "soa/trisoup.h"
#include "test_shapes.h"
#include "verify/check.h"
#include "verify/check_passes.h"

static int near(double a, double b, double tol) { return fabs(a - b) <= tol; }

/* ---- meshes: an nx x ny x nz grid of hexahedra over [lo, hi] ------------- */

typedef struct {
  size_t nn, nc;
  double *xyz;
  uint8_t *type;
  uint32_t *conn;
  int32_t *label; /* NULL: none */
} hexes;

static void hex_grid(hexes *h, const double lo[3], const double hi[3], int nx, int ny, int nz) {
  const size_t px = (size_t)nx + 1, py = (size_t)ny + 1, pz = (size_t)nz + 1;
  h->nn = px * py * pz;
  h->nc = (size_t)nx * ny * nz;
  h->xyz = malloc(3 * h->nn * sizeof *h->xyz);
  h->type = malloc(h->nc);
  h->conn = calloc(8 * h->nc, sizeof *h->conn);
  h->label = NULL;
  for (size_t k = 0; k < pz; k++)
    for (size_t j = 0; j < py; j++)
      for (size_t i = 0; i < px; i++) {
        double *p = h->xyz + 3 * ((k * py + j) * px + i);
        p[0] = lo[0] + (hi[0] - lo[0]) * (double)i / nx;
        p[1] = lo[1] + (hi[1] - lo[1]) * (double)j / ny;
        p[2] = lo[2] + (hi[2] - lo[2]) * (double)k / nz;
      }
  size_t c = 0;
  for (size_t k = 0; k < (size_t)nz; k++)
    for (size_t j = 0; j < (size_t)ny; j++)
      for (size_t i = 0; i < (size_t)nx; i++, c++) {
        /* VTK order: the bottom square counter-clockwise, then the top */
        static const int d[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0},
                                    {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
        h->type[c] = MX_HEX;
        for (int v = 0; v < 8; v++)
          h->conn[8 * c + v] =
              (uint32_t)(((k + d[v][2]) * py + j + d[v][1]) * px + i + d[v][0]);
      }
}

static void hexes_free(hexes *h) {
  free(h->xyz);
  free(h->type);
  free(h->conn);
  free(h->label);
}

static mx_check_report check_hexes(const hexes *h, const mx_trisoup *s) {
  mx_mesh_data d = {.nnodes = h->nn, .ncells = h->nc, .xyz = h->xyz, .type = h->type,
                    .conn = h->conn, .cell_tag = h->label};
  mx_check_report r;
  CHECK(mx_check_mesh(&d, s, &r) == MX_OK);
  return r;
}

/* ---- surfaces ------------------------------------------------------------ */

static void soup_add(mx_trisoup *s, const double *xyz, size_t nv, const uint32_t *tri,
                     size_t nt) {
  const uint32_t v0 = (uint32_t)s->nv;
  for (size_t v = 0; v < nv; v++) CHECK(mx_trisoup_set_vertex(s, v0 + v, xyz + 3 * v) == MX_OK);
  for (size_t t = 0; t < nt; t++)
    CHECK(mx_trisoup_add_triangle(s, v0 + tri[3 * t], v0 + tri[3 * t + 1],
                                  v0 + tri[3 * t + 2]) == MX_OK);
}

/* The box [lo, hi], each face 2 triangles (n = 1), added to s. */
static void soup_box(mx_trisoup *s, const double lo[3], const double hi[3], int n) {
  double *xyz;
  uint32_t *tri;
  size_t nv, nt;
  box(lo, hi, n, &xyz, &nv, &tri, &nt);
  soup_add(s, xyz, nv, tri, nt);
  free(xyz);
  free(tri);
}

static void print_two_sided(const char *what, const mx_check_report *r) {
  printf("%-34s mesh->surface max %.17g mean %.17g; surface->mesh max %.17g mean %.17g "
         "(%zu, %zu samples)\n",
         what, r->mesh_to_surface_max, r->mesh_to_surface_mean, r->surface_to_mesh_max,
         r->surface_to_mesh_mean, r->mesh_to_surface_samples, r->surface_to_mesh_samples);
}

/* ---- hand-made cases ------------------------------------------------------ */

static const double O[3] = {0, 0, 0}, I[3] = {1, 1, 1};

static void test_cubes(void) {
  hexes h;
  hex_grid(&h, O, I, 1, 1, 1);
  /* The unit cube as one hexahedron against its own surface: its faces lie
   * on the surface's, both ways 0. */
  mx_trisoup s = {0};
  soup_box(&s, O, I, 1);
  mx_check_report r = check_hexes(&h, &s);
  print_two_sided("cube, its surface", &r);
  CHECK(r.defects == 0 && near(r.surface_diagonal, sqrt(3.0), 1e-15));
  CHECK(near(r.mesh_to_surface_max, 0.0, 1e-12) && near(r.mesh_to_surface_mean, 0.0, 1e-12));
  CHECK(near(r.surface_to_mesh_max, 0.0, 1e-12) && near(r.surface_to_mesh_mean, 0.0, 1e-12));
  /* 6 quads, 12 triangles; the mesh side at spacing sqrt(3) / 1000 would
   * need k = 817 for triangles of longest edge sqrt(2): k = 8 (the mesh
   * side's cap), 9 * 10 / 2 grid points and 64 centroids each; the
   * surface's 12 triangles at spacing 1 (every skin face's longest side)
   * k = ceil(sqrt(2)) = 2: 6 + 4 samples each. */
  CHECK(r.mesh_to_surface_samples == 12 * (45 + 64));
  CHECK(r.surface_to_mesh_samples == 12 * 10);
  CHECK(near(r.mesh_sample_spacing, sqrt(3.0) / 1000, 1e-18) && r.surface_sample_spacing == 1.0);
  mx_trisoup_free(&s);

  /* The same hexahedron inside the cube scaled by 1.1 about its centre,
   * [-0.05, 1.05]^3. Every point of the hexahedron's surface is 0.05 from
   * the big cube's face parallel to its own (and no nearer to another:
   * its other coordinates lie in [0, 1]): mesh -> surface 0.05, max and
   * mean. From the big cube, a point of a face is sqrt(0.05^2 + e^2) from
   * the hexahedron, e its distance to [0, 1]^2 in the face's plane: 0.05
   * in the middle, up to 0.05 sqrt(3) at the corners (e = 0.05 sqrt(2)),
   * which are samples: max 0.05 sqrt(3), the mean in between. */
  memset(&s, 0, sizeof s);
  const double blo[3] = {-0.05, -0.05, -0.05}, bhi[3] = {1.05, 1.05, 1.05};
  soup_box(&s, blo, bhi, 1);
  r = check_hexes(&h, &s);
  print_two_sided("cube in the cube scaled by 1.1", &r);
  CHECK(near(r.surface_diagonal, 1.1 * sqrt(3.0), 1e-15));
  CHECK(near(r.mesh_to_surface_max, 0.05, 1e-12) && near(r.mesh_to_surface_mean, 0.05, 1e-12));
  CHECK(near(r.surface_to_mesh_max, 0.05 * sqrt(3.0), 1e-12));
  CHECK(r.surface_to_mesh_mean > 0.05 + 1e-6 && r.surface_to_mesh_mean < 0.05 * sqrt(3.0));
  /* the nodes are samples: boundary_max_dist (relative) is one of them */
  CHECK(near(r.boundary_max_dist * r.surface_diagonal, 0.05, 1e-12));
  mx_trisoup_free(&s);
  hexes_free(&h);

  /* Half the cube, [0, 0.5] x [0, 1]^2, against the whole cube: the mesh
   * misses the part x > 0.5.
   * surface -> mesh: the face x = 1 is 0.5 away (max 0.5), the face x = 0
   * on the mesh (0), the four sides 0 for x <= 0.5 and x - 0.5 beyond
   * (1/8 over each); the mean (0.5 + 4/8) / 6 = 1/6. The kink at x = 0.5
   * is a line of the sides' sub-grid (k = 2: their triangles' longest edge
   * sqrt(2) over a spacing of 1, the skin faces' median longest side), so
   * the rule, exact for a linear distance on each small triangle, gives
   * 1/6 to rounding.
   * mesh -> surface: the cut face x = 0.5 lies in the cube, min(y, 1 - y,
   * z, 1 - z) from its surface, 0.5 at its centre (the midpoint of the
   * quad's diagonal, a sample: k = 8 is even); the other faces lie on the
   * surface. The mean: the distance to the boundary of the unit square,
   * integrated (4 triangles of height 1/2: 4 * 1/24 = 1/6), over the
   * skin's area 4: 1/24. The kink along the diagonal the two triangles do
   * not share crosses their sub-grid's small triangles, where the rule is
   * not exact: it gives 1/6 + 1/(12 k^2) over the face (worked out in
   * rational arithmetic for k = 2, 4, 8, 50), 43/256 at k = 8, the mean
   * 43/1024. */
  const double half[3] = {0.5, 1, 1};
  hex_grid(&h, O, half, 1, 1, 1);
  memset(&s, 0, sizeof s);
  soup_box(&s, O, I, 1);
  r = check_hexes(&h, &s);
  print_two_sided("half cube, the cube", &r);
  CHECK(near(r.surface_to_mesh_max, 0.5, 1e-12));
  CHECK(near(r.surface_to_mesh_mean, 1.0 / 6.0, 1e-12));
  CHECK(near(r.mesh_to_surface_max, 0.5, 1e-12));
  CHECK(near(r.mesh_to_surface_mean, 43.0 / 1024.0, 1e-12));
  mx_trisoup_free(&s);
  hexes_free(&h);

  /* An open surface (a triangle gone): not measured. */
  hex_grid(&h, O, I, 1, 1, 1);
  memset(&s, 0, sizeof s);
  soup_box(&s, O, I, 1);
  s.nt--;
  r = check_hexes(&h, &s);
  CHECK(r.surface_open_edges > 0);
  CHECK(isnan(r.mesh_to_surface_max) && isnan(r.mesh_to_surface_mean));
  CHECK(isnan(r.surface_to_mesh_max) && isnan(r.surface_to_mesh_mean));
  mx_trisoup_free(&s);
  /* Without a surface either. */
  r = check_hexes(&h, NULL);
  CHECK(isnan(r.mesh_to_surface_max) && isnan(r.surface_to_mesh_mean) &&
        isnan(r.surface_diagonal));
  hexes_free(&h);
}

/* A 3 x 3 x 3 grid of the unit cube against the cube with the middle cell's
 * box nested in it (a surface of two shells). With the middle hexahedron
 * labelled apart (a material), its faces are interfaces, in the skin: both
 * ways 0. Without labels the skin is the outer boundary only, and every
 * point of the inner box (a coordinate 1/3 or 2/3, all in [1/3, 2/3]) is
 * 1/3 from it: surface -> mesh max 1/3, mean (6/9 * 1/3) / (6 + 6/9) =
 * 1/30; mesh -> surface still 0. */
static void test_interfaces(void) {
  hexes h;
  hex_grid(&h, O, I, 3, 3, 3);
  mx_trisoup s = {0};
  soup_box(&s, O, I, 1);
  const double lo[3] = {1.0 / 3, 1.0 / 3, 1.0 / 3}, hi[3] = {2.0 / 3, 2.0 / 3, 2.0 / 3};
  double *xyz;
  uint32_t *tri;
  size_t nv, nt;
  box(lo, hi, 1, &xyz, &nv, &tri, &nt);
  for (size_t t = 0; t < nt; t++) { /* inward: the nested shell of a hole */
    const uint32_t x = tri[3 * t + 1];
    tri[3 * t + 1] = tri[3 * t + 2];
    tri[3 * t + 2] = x;
  }
  soup_add(&s, xyz, nv, tri, nt);
  free(xyz);
  free(tri);
  h.label = malloc(h.nc * sizeof *h.label);
  for (size_t c = 0; c < h.nc; c++) h.label[c] = c == 13 ? 2 : 1;
  mx_check_report r = check_hexes(&h, &s);
  print_two_sided("3^3 cubes, labelled, nested box", &r);
  CHECK(r.interface_faces == 6);
  CHECK(near(r.mesh_to_surface_max, 0.0, 1e-12) && near(r.mesh_to_surface_mean, 0.0, 1e-12));
  CHECK(near(r.surface_to_mesh_max, 0.0, 1e-12) && near(r.surface_to_mesh_mean, 0.0, 1e-12));
  free(h.label);
  h.label = NULL;
  r = check_hexes(&h, &s);
  print_two_sided("3^3 cubes, no labels, nested box", &r);
  CHECK(near(r.mesh_to_surface_max, 0.0, 1e-12) && near(r.mesh_to_surface_mean, 0.0, 1e-12));
  CHECK(near(r.surface_to_mesh_max, 1.0 / 3, 1e-12));
  CHECK(near(r.surface_to_mesh_mean, 1.0 / 30, 1e-12));
  mx_trisoup_free(&s);
  hexes_free(&h);
}

/* ---- brute force ---------------------------------------------------------- */

typedef struct {
  const double *xyz; /* vertex v at xyz + 3 v */
  const uint32_t *tri;
  size_t nt;
} tris;

static double brute_d2(const tris *to, const double p[3]) {
  double best = INFINITY;
  for (size_t t = 0; t < to->nt; t++) {
    double T[9], q[3];
    for (int k = 0; k < 3; k++)
      memcpy(T + 3 * k, to->xyz + 3 * to->tri[3 * t + k], 3 * sizeof(double));
    best = fmin(best, mx_closest_on_triangle(T, p, q));
  }
  return best;
}

/* The checker's sampling written out (verify/check.h): each triangle of
 * `from` on its k-grid, k = ceil(longest edge / h) in [2, kmax], the points
 * (i, j) / k and the centroids of the small triangles; the mean of each
 * small triangle 1/12 of its vertices' distances each plus 3/4 of its
 * centroid's. Returns the max; *mean, *samples. */
static double brute_one_way(const tris *from, const tris *to, double h, int kmax, double *mean,
                            size_t *samples) {
  double max2 = 0.0, integral = 0.0, area = 0.0;
  *samples = 0;
  for (size_t t = 0; t < from->nt; t++) {
    const double *P[3];
    for (int k = 0; k < 3; k++) P[k] = from->xyz + 3 * from->tri[3 * t + k];
    double len = 0.0, u[3], v[3];
    for (int k = 0; k < 3; k++) {
      double e = 0.0;
      for (int a = 0; a < 3; a++)
        e += (P[(k + 1) % 3][a] - P[k][a]) * (P[(k + 1) % 3][a] - P[k][a]);
      len = fmax(len, sqrt(e));
    }
    const double kk = ceil(len / h);
    const int k = kk > 2 ? (kk < kmax ? (int)kk : kmax) : 2;
    /* d(i, j, W): the distance at (i P1 + j P2 + (W - i - j) P0) / W */
#define AT(wb, wc, W, p)                                                            \
  for (int a = 0; a < 3; a++)                                                       \
    p[a] = ((W - (wb) - (wc)) * P[0][a] + (wb) * P[1][a] + (wc) * P[2][a]) / (W);
    double sum = 0.0;
    for (int j = 0; j < k; j++)
      for (int i = 0; i < k - j; i++)
        for (int down = 0; down < 2; down++) {
          if (down && i + 1 >= k - j) continue;
          const int vi[3][2] = {{i + down, j}, {i, j + 1}, {i + 1, j + down}};
          double dsum = 0.0, p[3];
          for (int x = 0; x < 3; x++) {
            AT(vi[x][0], vi[x][1], k, p);
            dsum += sqrt(brute_d2(to, p));
          }
          AT(3 * i + 1 + down, 3 * j + 1 + down, 3 * k, p);
          const double dc2 = brute_d2(to, p);
          max2 = fmax(max2, dc2);
          sum += dsum / 12.0 + 0.75 * sqrt(dc2);
          (*samples)++;
        }
    for (int j = 0; j <= k; j++)
      for (int i = 0; i + j <= k; i++) {
        double p[3];
        AT(i, j, k, p);
        max2 = fmax(max2, brute_d2(to, p));
        (*samples)++;
      }
#undef AT
    for (int a = 0; a < 3; a++) {
      u[a] = P[1][a] - P[0][a];
      v[a] = P[2][a] - P[0][a];
    }
    const double n[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2],
                         u[0] * v[1] - u[1] * v[0]};
    const double A = 0.5 * sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    integral += A * sum / ((double)k * k);
    area += A;
  }
  *mean = integral / area;
  return sqrt(max2);
}

/* A 2 x 2 x 2 grid of hexahedra over [-0.5, 0.5]^3, its nodes moved by a
 * smooth field, against a UV sphere of radius 0.7 (inside the corners,
 * outside the faces' middles): distances of every size both ways, the checker's against the brute force's. The skin's
 * quads split a-b-c, a-c-d in the hexahedra's outward face order
 * (soa/mesh.h). */
static void test_brute_force(void) {
  hexes h;
  const double lo[3] = {-0.5, -0.5, -0.5}, hi[3] = {0.5, 0.5, 0.5};
  hex_grid(&h, lo, hi, 2, 2, 2);
  for (size_t v = 0; v < h.nn; v++) {
    double *p = h.xyz + 3 * v;
    const double x = p[0], y = p[1], z = p[2];
    p[0] += 0.06 * sin(3 * y + 1) * cos(2 * z);
    p[1] += 0.05 * sin(2 * z + 2 * x);
    p[2] += 0.07 * cos(3 * x - y);
  }
  double *sxyz;
  uint32_t *stri;
  size_t snv, snt;
  sphere(0.7, 6, &sxyz, &snv, &stri, &snt);
  mx_trisoup s = {0};
  soup_add(&s, sxyz, snv, stri, snt);
  mx_check_report r = check_hexes(&h, &s);
  print_two_sided("moved 2^3 hexahedra, a sphere", &r);
  /* the skin: every face of a cell used once, as the checker's face table
   * (soa/mesh.h's mx_cell_faces, outward) splits it */
  uint32_t *ktri = malloc(h.nc * 6 * 2 * 3 * sizeof *ktri);
  size_t knt = 0;
  double median_side[24 * 2];
  size_t nf = 0;
  for (size_t c = 0; c < h.nc; c++)
    for (int f = 0; f < 6; f++) {
      const int8_t *fv = mx_cell_faces[MX_HEX][f];
      uint32_t v[4];
      for (int x = 0; x < 4; x++) v[x] = h.conn[8 * c + (size_t)fv[x]];
      int shared = 0; /* the four nodes in another cell: an interior face */
      for (size_t c2 = 0; c2 < h.nc && !shared; c2++) {
        if (c2 == c) continue;
        int hit = 0;
        for (int x = 0; x < 4; x++)
          for (int y = 0; y < 8; y++) hit += h.conn[8 * c2 + (size_t)y] == v[x];
        shared = hit == 4;
      }
      if (shared) continue;
      double side = 0.0;
      for (int x = 0; x < 4; x++) {
        const double *a = h.xyz + 3 * v[x], *b = h.xyz + 3 * v[(x + 1) % 4];
        side = fmax(side, sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) +
                               (a[2] - b[2]) * (a[2] - b[2])));
      }
      median_side[nf++] = side;
      const uint32_t t[6] = {v[0], v[1], v[2], v[0], v[2], v[3]};
      memcpy(ktri + 3 * knt, t, sizeof t);
      knt += 2;
    }
  CHECK(nf == 24 && r.faces_boundary == 24);
  for (size_t i = 1; i < nf; i++) /* sort, for the median */
    for (size_t j = i; j > 0 && median_side[j - 1] > median_side[j]; j--) {
      const double x = median_side[j];
      median_side[j] = median_side[j - 1];
      median_side[j - 1] = x;
    }
  const double median = median_side[nf / 2];
  double slo[3], shi[3], diag2 = 0.0;
  mx_trisoup_bbox(&s, slo, shi);
  for (int a = 0; a < 3; a++) diag2 += (shi[a] - slo[a]) * (shi[a] - slo[a]);
  const tris mesh = {h.xyz, ktri, knt}, surf = {sxyz, stri, snt};
  double m2s_mean, s2m_mean;
  size_t m2s_n, s2m_n;
  const double m2s = brute_one_way(&mesh, &surf, sqrt(diag2) / 1000, 8, &m2s_mean, &m2s_n);
  const double s2m = brute_one_way(&surf, &mesh, median, 50, &s2m_mean, &s2m_n);
  printf("%-34s mesh->surface max %.17g mean %.17g; surface->mesh max %.17g mean %.17g "
         "(%zu, %zu samples)\n",
         "brute force", m2s, m2s_mean, s2m, s2m_mean, m2s_n, s2m_n);
  CHECK(r.surface_sample_spacing == median);
  CHECK(r.mesh_to_surface_samples == m2s_n && r.surface_to_mesh_samples == s2m_n);
  CHECK(near(r.mesh_to_surface_max, m2s, 1e-12) && near(r.mesh_to_surface_mean, m2s_mean, 1e-12));
  CHECK(near(r.surface_to_mesh_max, s2m, 1e-12) && near(r.surface_to_mesh_mean, s2m_mean, 1e-12));
  CHECK(m2s > 0.05 && s2m > 0.05); /* something to measure */

  /* the same digits with 1 and 2 threads */
  const int was = omp_get_max_threads();
  omp_set_num_threads(1);
  const mx_check_report r1 = check_hexes(&h, &s);
  omp_set_num_threads(2);
  const mx_check_report r2 = check_hexes(&h, &s);
  omp_set_num_threads(was);
  const double a1[4] = {r1.mesh_to_surface_max, r1.mesh_to_surface_mean, r1.surface_to_mesh_max,
                        r1.surface_to_mesh_mean};
  const double a2[4] = {r2.mesh_to_surface_max, r2.mesh_to_surface_mean, r2.surface_to_mesh_max,
                        r2.surface_to_mesh_mean};
  CHECK(memcmp(a1, a2, sizeof a1) == 0);
  free(ktri);
  free(sxyz);
  free(stri);
  mx_trisoup_free(&s);
  hexes_free(&h);
}

/* A 16 x 16 x 16 grid of the unit cube inside the box [-1, 2]^3 (many
 * blocks of triangles, so that threads share the work): the same digits
 * with 1 and 2 threads; mesh -> surface 1 everywhere, surface -> mesh
 * sqrt(3) at the box's corners. */
static void test_threads(void) {
  hexes h;
  hex_grid(&h, O, I, 16, 16, 16);
  mx_trisoup s = {0};
  const double blo[3] = {-1, -1, -1}, bhi[3] = {2, 2, 2};
  soup_box(&s, blo, bhi, 8);
  const int was = omp_get_max_threads();
  mx_check_report r[2];
  for (int t = 0; t < 2; t++) {
    omp_set_num_threads(t + 1);
    r[t] = check_hexes(&h, &s);
  }
  omp_set_num_threads(was);
  print_two_sided("16^3 hexahedra, the box [-1, 2]^3", &r[1]);
  CHECK(r[0].mesh_to_surface_max == r[1].mesh_to_surface_max &&
        r[0].mesh_to_surface_mean == r[1].mesh_to_surface_mean &&
        r[0].surface_to_mesh_max == r[1].surface_to_mesh_max &&
        r[0].surface_to_mesh_mean == r[1].surface_to_mesh_mean &&
        r[0].mesh_to_surface_samples == r[1].mesh_to_surface_samples);
  CHECK(near(r[1].mesh_to_surface_max, 1.0, 1e-12) && near(r[1].mesh_to_surface_mean, 1.0, 1e-12));
  CHECK(near(r[1].surface_to_mesh_max, sqrt(3.0), 1e-12));
  mx_trisoup_free(&s);
  hexes_free(&h);
}

/* ---- the checker's tree of triangles (check_geometry.c) -------------------- */

static double lcg(uint64_t *x) {
  *x = *x * 6364136223846793005ull + 1442695040888963407ull;
  return (double)(*x >> 11) / 9007199254740992.0;
}

/* Random triangles (some all at one place, so that many centres are equal
 * and the splits meet ties): the nearest triangle through the tree against
 * every triangle, the triangles near a box against all, and the tree's
 * triangles a permutation of the input's. */
static void test_tree(void) {
  const size_t sizes[] = {1, 2, 8, 9, 17, 100, 1000, 4000};
  uint64_t seed = 12345;
  for (size_t z = 0; z < sizeof sizes / sizeof *sizes; z++) {
    const size_t n = sizes[z];
    double *xyz = malloc(9 * n * sizeof *xyz);
    uint32_t *tri = malloc(3 * n * sizeof *tri);
    for (size_t t = 0; t < n; t++) {
      const int same = t % 5 == 0; /* the same triangle again and again */
      double c[3];
      for (int a = 0; a < 3; a++) c[a] = same ? 0.5 : lcg(&seed);
      for (int k = 0; k < 3; k++) {
        for (int a = 0; a < 3; a++)
          xyz[9 * t + 3 * (size_t)k + a] =
              c[a] + (same ? 0.01 * (k == a) : 0.05 * (lcg(&seed) - 0.5));
        tri[3 * t + (size_t)k] = (uint32_t)(3 * t + (size_t)k);
      }
    }
    const ck_tris T = {xyz, xyz + 1, xyz + 2, 3, tri, n};
    ck_tree R;
    CHECK(mx_ck_tree_build(&R, &T) == MX_OK);
    /* a permutation: every triangle's first vertex once */
    size_t found = 0;
    for (size_t i = 0; i < n; i++)
      for (size_t t = 0; t < n; t++)
        if (memcmp(R.tv + CK_TV * i, xyz + 9 * t, 9 * sizeof(double)) == 0) {
          found++;
          break;
        }
    CHECK(found == n);
    int bad = 0;
    for (int q = 0; q < 200; q++) {
      double p[3];
      for (int a = 0; a < 3; a++) p[a] = 3 * lcg(&seed) - 1;
      double best = INFINITY;
      for (size_t t = 0; t < n; t++)
        best = fmin(best,
                    mx_ck_point_triangle_d2(p, xyz + 9 * t, xyz + 9 * t + 3, xyz + 9 * t + 6));
      bad += mx_ck_tree_d2(&R, p, INFINITY) != best;
      /* near a box around p: every triangle whose box is within u */
      const double u = 0.1 * lcg(&seed);
      const double box[6] = {p[0], p[1], p[2], p[0] + 0.1, p[1] + 0.1, p[2] + 0.1};
      uint32_t list[4096];
      const size_t m = mx_ck_tree_near_box(&R, box, u, list, 4096);
      size_t want = 0;
      for (size_t i = 0; i < n; i++) {
        const double *b = R.tv + CK_TV * i + 9;
        double d2 = 0.0;
        for (int a = 0; a < 3; a++) {
          const double d = fmax(fmax(b[a] - box[3 + a], box[a] - b[3 + a]), 0.0);
          d2 += d * d;
        }
        if (d2 <= u * u) {
          want++;
          int in = 0;
          for (size_t j = 0; m != SIZE_MAX && j < m; j++) in |= list[j] == i;
          bad += !in;
        }
      }
      bad += m != want;
    }
    CHECK(bad == 0);
    if (bad) fprintf(stderr, "tree of %zu triangles: %d wrong answers\n", n, bad);
    mx_ck_tree_free(&R);
    free(xyz);
    free(tri);
  }
}

/* ---- mixoct check --json ---------------------------------------------------- */

static const char hex_vtk[] =
    "# vtk DataFile Version 3.0\n"
    "one hexahedron\n"
    "ASCII\n"
    "DATASET UNSTRUCTURED_GRID\n"
    "POINTS 8 double\n"
    "0 0 0 0.5 0 0 0.5 1 0 0 1 0\n"
    "0 0 1 0.5 0 1 0.5 1 1 0 1 1\n"
    "CELLS 1 9\n"
    "8 0 1 2 3 4 5 6 7\n"
    "CELL_TYPES 1\n"
    "12\n";

static const char cube_off[] =
    "OFF\n8 12 0\n"
    "0 0 0\n1 0 0\n0 1 0\n1 1 0\n0 0 1\n1 0 1\n0 1 1\n1 1 1\n"
    "3 0 2 1\n3 1 2 3\n3 4 5 6\n3 5 7 6\n3 0 1 4\n3 1 5 4\n"
    "3 2 6 3\n3 3 6 7\n3 0 4 2\n3 2 4 6\n3 1 3 5\n3 3 7 5\n";

static void write_text(const char *path, const char *text) {
  FILE *f = fopen(path, "w");
  CHECK(f != NULL);
  if (!f) return;
  fputs(text, f);
  fclose(f);
}

static void test_program(const char *mixoct) {
  if (access(mixoct, X_OK) != 0) {
    printf("SKIP the program: %s not there\n", mixoct);
    return;
  }
  if (system("python3 -c pass") != 0) {
    printf("SKIP the program: no python3 to read its JSON\n");
    return;
  }
  char dir[] = "/tmp/mixoct_check_distance_XXXXXX";
  CHECK(mkdtemp(dir) != NULL);
  char vtk[128], off[128], cmd[8192];
  snprintf(vtk, sizeof vtk, "%s/half.vtk", dir);
  snprintf(off, sizeof off, "%s/cube.off", dir);
  write_text(vtk, hex_vtk);
  write_text(off, cube_off);
  /* half the cube against the cube (test_cubes): exit 3 for the volume
   * (a defect), the distances only indicative */
  snprintf(cmd, sizeof cmd,
           "'%s' check '%s' --surface '%s' --json | tail -n 1 | python3 -c \"import json, "
           "sys, math; d = json.loads(sys.stdin.read()); D = math.sqrt(3); "
           "k = [p + w + s for p in ['hausdorff_mesh_to_surface_', 'hausdorff_surface_to_mesh_'] "
           "for w in ['max', 'mean'] for s in ['', '_abs']]; "
           "assert all(x in d for x in k), k; "
           "assert abs(d['hausdorff_surface_to_mesh_max_abs'] - 0.5) < 1e-12; "
           "assert abs(d['hausdorff_surface_to_mesh_max'] - 0.5 / D) < 1e-12; "
           "assert abs(d['hausdorff_surface_to_mesh_mean_abs'] - 1 / 6) < 1e-12; "
           "assert abs(d['hausdorff_mesh_to_surface_max_abs'] - 0.5) < 1e-12; "
           "assert d['boundary_off_surface'] == 0\"",
           mixoct, vtk, off);
  CHECK(system(cmd) == 0);
  /* without a surface: the keys, null */
  snprintf(cmd, sizeof cmd,
           "'%s' check '%s' --json | tail -n 1 | python3 -c \"import json, sys; "
           "d = json.loads(sys.stdin.read()); "
           "assert d['hausdorff_mesh_to_surface_max'] is None; "
           "assert d['hausdorff_surface_to_mesh_mean_abs'] is None\"",
           mixoct, vtk);
  CHECK(system(cmd) == 0);
  /* the report's line */
  snprintf(cmd, sizeof cmd,
           "'%s' check '%s' --surface '%s' | grep -q 'boundary distance, both ways: mesh -> "
           "surface max 2.887e-01'",
           mixoct, vtk, off);
  CHECK(system(cmd) == 0);
  snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
  CHECK(system(cmd) == 0);
}

int main(int argc, char **argv) {
  (void)argc;
  char mixoct[4096];
  const char *slash = strrchr(argv[0], '/');
  if (slash)
    snprintf(mixoct, sizeof mixoct, "%.*s/../mixoct", (int)(slash - argv[0]), argv[0]);
  else
    snprintf(mixoct, sizeof mixoct, "../mixoct");
  test_tree();
  test_cubes();
  test_interfaces();
  test_brute_force();
  test_threads();
  test_program(mixoct);
  return TEST_DONE();
}
