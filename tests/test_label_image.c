/* Label images (issue 28; src/geom/label_fix.c, src/geom/label_surface.c,
 * src/mesher/image_input.c): synthetic label arrays made here, meshed
 * through mx_mesher_add_label_array.
 *
 * Derived, not recorded:
 *  - the contact repair leaves no vertex whose 8 voxels break the rule
 *    (checked by a brute-force test written here: per label, its voxels and
 *    the rest face-connected in the block; no edge of four labels in turn),
 *    and a second run changes nothing; islands under the size go (a
 *    one-voxel cavity of background too);
 *  - the interfaces' corners: exactly those of the voxel faces between
 *    labels, moved at most the clamp, flat faces kept flat, junctions
 *    followed;
 *  - meshes: every element labelled, per-label volumes (the elements' own,
 *    by tetrahedra about their centroid) within the half-voxel band of the
 *    voxel count (the band: half a voxel times the label's interface
 *    area, bounded here by the count of its voxel faces), the volumes
 *    summing to the mesh's; every face is shared by two elements or lies
 *    on the boundary, never by more (an independent face map); an oblique
 *    transform gives the same volumes times |det A|, and the label's
 *    centroid mapped by A. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "geom/label_fix.h"
#include "geom/label_surface.h"
#include "geom/quality.h"
#include "mixoct.h"

enum { N = 24 };

/* brute force: the contact rule at every vertex of a padded image */
static size_t bad_vertices(const int32_t *lab, const int64_t n[3]) {
  size_t bad = 0;
  for (int64_t k = 0; k + 1 < n[2]; k++)
    for (int64_t j = 0; j + 1 < n[1]; j++)
      for (int64_t i = 0; i + 1 < n[0]; i++) {
        int32_t l[2][2][2];
        for (int c = 0; c < 8; c++)
          l[c >> 2][(c >> 1) & 1][c & 1] =
              lab[(i + (c & 1)) + n[0] * ((j + ((c >> 1) & 1)) + n[1] * (k + (c >> 2)))];
        int ok = 1;
        /* edges through the vertex: 4 voxels around, in turn */
        for (int a = 0; a < 3 && ok; a++)
          for (int s = 0; s < 2 && ok; s++) {
            int32_t r[4];
            for (int t = 0; t < 4; t++) {
              const int u = (t == 1 || t == 2), w = (t >= 2);
              int x[3];
              x[a] = s;
              x[(a + 1) % 3] = u;
              x[(a + 2) % 3] = w;
              r[t] = l[x[2]][x[1]][x[0]];
            }
            if (r[0] != r[1] && r[1] != r[2] && r[2] != r[3] && r[3] != r[0]) ok = 0;
          }
        /* per label: its voxels, and the others, connected through faces */
        for (int c = 0; c < 8 && ok; c++) {
          const int32_t L = l[c >> 2][(c >> 1) & 1][c & 1];
          for (int side = 0; side < 2 && ok; side++) {
            int in[8], seen[8] = {0}, stack[8], sp = 0, cnt = 0, tot = 0;
            for (int d = 0; d < 8; d++) {
              in[d] = (l[d >> 2][(d >> 1) & 1][d & 1] == L) == (side == 0);
              tot += in[d];
            }
            int start = -1;
            for (int d = 0; d < 8 && start < 0; d++)
              if (in[d]) start = d;
            if (start < 0) continue;
            stack[sp++] = start;
            seen[start] = 1;
            while (sp) {
              const int d = stack[--sp];
              cnt++;
              for (int b = 0; b < 3; b++) {
                const int e = d ^ (1 << b);
                if (in[e] && !seen[e]) {
                  seen[e] = 1;
                  stack[sp++] = e;
                }
              }
            }
            if (cnt != tot) ok = 0;
          }
        }
        bad += !ok;
      }
  return bad;
}

static int32_t *padded(const int32_t *img, int64_t n[3]) {
  n[0] = n[1] = n[2] = N + 2;
  int32_t *lab = calloc((size_t)(n[0] * n[1] * n[2]), sizeof *lab);
  for (int k = 0; k < N; k++)
    for (int j = 0; j < N; j++)
      for (int i = 0; i < N; i++)
        lab[(i + 1) + n[0] * ((j + 1) + n[1] * (k + 1))] = img[i + N * (j + N * k)];
  return lab;
}

static void test_fixes(void) {
  int32_t *img = calloc(N * N * N, sizeof *img);
  /* a 2x2 checkerboard across an edge, a corner contact, an island of one
   * voxel, a background cavity */
  for (int k = 2; k < 20; k++)
    for (int j = 2; j < 20; j++)
      for (int i = 2; i < 20; i++) img[i + N * (j + N * k)] = 1;
  img[5 + N * (5 + N * 5)] = 2; /* island of label 2 (1 voxel) */
  img[10 + N * (10 + N * 10)] = 0; /* cavity */
  for (int k = 14; k < 18; k++) { /* 1 2 / 2 1 around the edge x = 15, y = 15 */
    img[14 + N * (14 + N * k)] = 3;
    img[15 + N * (15 + N * k)] = 3;
  }
  img[3 + N * (3 + N * 3)] = img[3 + N * (3 + N * 2)] = 4; /* corner contact of two */
  img[4 + N * (4 + N * 4)] = img[4 + N * (4 + N * 5)] = 4;   /* parts of 4 */
  int64_t n[3];
  int32_t *lab = padded(img, n);
  CHECK(bad_vertices(lab, n) > 0);
  mx_label_fix_stats st;
  memset(&st, 0, sizeof st);
  CHECK(lab[6 + n[0] * (6 + n[1] * 6)] == 2); /* the island ... */
  CHECK(mx_labels_drop_islands(lab, n, 2, &st) == MX_OK);
  /* ... goes, and the one-voxel cavity (background in label 1) too */
  CHECK(st.islands == 2 && st.island_voxels == 2 && lab[6 + n[0] * (6 + n[1] * 6)] == 1 &&
        lab[11 + n[0] * (11 + n[1] * 11)] == 1);
  uint64_t *count = calloc(65536, sizeof *count); /* voxels per label: the ranks */
  for (int64_t v = 0; v < n[0] * n[1] * n[2]; v++) count[lab[v]]++;
  CHECK(mx_labels_fix_contacts(lab, n, count, "test", &st) == MX_OK);
  CHECK(st.contact_voxels > 0);
  CHECK(bad_vertices(lab, n) == 0);
  mx_label_fix_stats again;
  memset(&again, 0, sizeof again);
  memset(count, 0, 65536 * sizeof *count);
  for (int64_t v = 0; v < n[0] * n[1] * n[2]; v++) count[lab[v]]++;
  CHECK(mx_labels_fix_contacts(lab, n, count, "test", &again) == MX_OK);
  free(count);
  CHECK(again.contact_voxels == 0);
  free(lab);
  free(img);
}

/* The interfaces' corners: on nested cubes (label 1 a 10^3 cube with a
 * 4^3 cube of label 2 inside) every corner of both cubes' faces and no
 * other, none on a junction; unsmoothed they stay; smoothed each moves at
 * most the clamp, the cubes' corners inwards and the faces' middles not
 * (nearly flat); with a third label cutting the outer cube in two, the
 * corners where three labels meet move in their junction's plane only. */
static void test_surface(void) {
  int32_t *img = calloc(N * N * N, sizeof *img);
  for (int k = 3; k < 13; k++)
    for (int j = 3; j < 13; j++)
      for (int i = 3; i < 13; i++) img[i + N * (j + N * k)] = (i >= 6 && i < 10 && j >= 6 &&
                                                                j < 10 && k >= 6 && k < 10) ? 2 : 1;
  int64_t n[3];
  int32_t *lab = padded(img, n);
  mx_label_surface S;
  CHECK(mx_label_surface_build(lab, n, 0, 0.0, &S) == MX_OK);
  /* corners of a cube's surface, s voxels a side: 6 s^2 + 2 */
  CHECK(S.nv == (6 * 100 + 2) + (6 * 16 + 2));
  CHECK(S.junction_vertices == 0 && S.max_move == 0.0);
  for (size_t x = 1; x < S.nv; x++) CHECK(S.corner[x - 1] < S.corner[x]);
  mx_label_surface_free(&S);
  CHECK(mx_label_surface_build(lab, n, 10, 0.35, &S) == MX_OK);
  CHECK(S.max_move <= 0.35 + 1e-12 && S.max_move > 0.1);
  size_t cube_corner = 0, face_mid = 0;
  for (size_t x = 0; x < S.nv; x++) {
    const int64_t c = S.corner[x];
    const int64_t q[3] = {c % n[0], (c / n[0]) % n[1], c / (n[0] * n[1])};
    /* padded: the outer cube spans corners 4 .. 14 */
    if (q[0] == 4 && q[1] == 4 && q[2] == 4) {
      cube_corner = 1;
      for (int a = 0; a < 3; a++) CHECK(S.lat[3 * x + a] > 4.1);
    }
    if (q[0] == 9 && q[1] == 9 && q[2] == 4) {
      face_mid = 1;
      CHECK(fabs(S.lat[3 * x + 2] - 4.0) < 0.05); /* nearly: the edges' rounding spreads a little */
    }
  }
  CHECK(cube_corner && face_mid);
  mx_label_surface_free(&S);
  /* a third label: the outer cube's half x >= 8 becomes 3 */
  for (int k = 3; k < 13; k++)
    for (int j = 3; j < 13; j++)
      for (int i = 8; i < 13; i++)
        if (img[i + N * (j + N * k)] == 1) img[i + N * (j + N * k)] = 3;
  free(lab);
  lab = padded(img, n);
  CHECK(mx_label_surface_build(lab, n, 10, 0.35, &S) == MX_OK);
  /* the junctions are closed loops (around the outer cube and the inner
   * one): no ends */
  CHECK(S.junction_vertices > 0 && S.fixed_vertices == 0);
  size_t on_junction = 0;
  for (size_t x = 0; x < S.nv; x++) {
    const int64_t c = S.corner[x];
    const int64_t q[3] = {c % n[0], (c / n[0]) % n[1], c / (n[0] * n[1])};
    /* the plane x = 9 (padded) where 1 and 3 meet, on the outer cube's
     * face z = 4: a junction of 0, 1, 3 along y */
    if (q[0] == 9 && q[2] == 4 && q[1] > 4 && q[1] < 14) {
      on_junction++;
      CHECK(fabs(S.lat[3 * x] - 9.0) < 1e-9); /* in the junction's plane */
    }
  }
  CHECK(on_junction == 9);
  mx_label_surface_free(&S);
  free(lab);
  free(img);
}

/* volume of an element by tetrahedra about its centroid (faces as the
 * element's own: quads split about their centroid too) */
static const int8_t faces_of[4][6][5] = {
    {{3, 0, 2, 1}, {3, 0, 1, 3}, {3, 1, 2, 3}, {3, 0, 3, 2}},
    {{4, 0, 3, 2, 1}, {3, 0, 1, 4}, {3, 1, 2, 4}, {3, 2, 3, 4}, {3, 3, 0, 4}},
    {{3, 0, 2, 1}, {3, 3, 4, 5}, {4, 0, 1, 4, 3}, {4, 1, 2, 5, 4}, {4, 2, 0, 3, 5}},
    {{4, 0, 3, 2, 1}, {4, 4, 5, 6, 7}, {4, 0, 1, 5, 4}, {4, 1, 2, 6, 5}, {4, 2, 3, 7, 6},
     {4, 3, 0, 4, 7}}};
static const int nfaces[4] = {4, 5, 5, 6};

static double tet6(const double *a, const double *b, const double *c, const double *d) {
  const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
  const double v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
  const double w[3] = {d[0] - a[0], d[1] - a[1], d[2] - a[2]};
  return u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0]) +
         u[2] * (v[0] * w[1] - v[1] * w[0]);
}

static double element_volume(const mx_mesh_arrays *a, size_t e) {
  const int t = a->type[e], nv = t == MX_TET ? 4 : t == MX_PYRAMID ? 5 : t == MX_PRISM ? 6 : 8;
  const int ti = t == MX_TET ? 0 : t == MX_PYRAMID ? 1 : t == MX_PRISM ? 2 : 3;
  double c[3] = {0, 0, 0};
  for (int k = 0; k < nv; k++)
    for (int x = 0; x < 3; x++) c[x] += a->xyz[3 * a->conn[8 * e + k] + x] / nv;
  double v = 0;
  for (int f = 0; f < nfaces[ti]; f++) {
    const int8_t *F = faces_of[ti][f];
    double fc[3] = {0, 0, 0};
    for (int k = 0; k < F[0]; k++)
      for (int x = 0; x < 3; x++) fc[x] += a->xyz[3 * a->conn[8 * e + F[1 + k]] + x] / F[0];
    for (int k = 0; k < F[0]; k++) {
      const double *p = a->xyz + 3 * a->conn[8 * e + F[1 + k]];
      const double *q = a->xyz + 3 * a->conn[8 * e + F[1 + (k + 1) % F[0]]];
      v += fabs(tet6(c, fc, p, q)) / 6.0;
    }
  }
  return v;
}

typedef struct {
  uint32_t n[4];
  int count;
} face_key;

static int cmp_face(const void *x, const void *y) {
  return memcmp(((const face_key *)x)->n, ((const face_key *)y)->n, sizeof(uint32_t) * 4);
}

/* every face used once (boundary) or twice */
static size_t bad_faces(const mx_mesh_arrays *a) {
  face_key *f = malloc(a->nelements * 6 * sizeof *f);
  size_t nf = 0;
  for (size_t e = 0; e < a->nelements; e++) {
    const int t = a->type[e], ti = t == MX_TET ? 0 : t == MX_PYRAMID ? 1 : t == MX_PRISM ? 2 : 3;
    for (int k = 0; k < nfaces[ti]; k++) {
      const int8_t *F = faces_of[ti][k];
      face_key key = {{UINT32_MAX, UINT32_MAX, UINT32_MAX, UINT32_MAX}, 1};
      for (int x = 0; x < F[0]; x++) key.n[x] = a->conn[8 * e + F[1 + x]];
      for (int x = 1; x < 4; x++) /* sort */
        for (int y = x; y > 0 && key.n[y] < key.n[y - 1]; y--) {
          const uint32_t s = key.n[y];
          key.n[y] = key.n[y - 1];
          key.n[y - 1] = s;
        }
      f[nf++] = key;
    }
  }
  qsort(f, nf, sizeof *f, cmp_face);
  size_t bad = 0;
  for (size_t i = 0; i < nf;) {
    size_t j = i + 1;
    while (j < nf && !cmp_face(f + i, f + j)) j++;
    bad += j - i > 2;
    i = j;
  }
  free(f);
  return bad;
}

/* Mesh img with A (voxel: the voxel faces kept); per label 1..3 the
 * volume and the centroid, and a hash of the mesh's arrays; returns the
 * status. With voxel faces, every element's centroid lies in a voxel of
 * its label (nothing across an interface). */
static uint64_t hash_bytes(uint64_t h, const void *p, size_t n) {
  const unsigned char *b = p;
  for (size_t i = 0; i < n; i++) h = (h ^ b[i]) * 1099511628211ULL;
  return h;
}

static int image_as_given = 1; /* 0: the contacts' repair changed voxels */
static const int32_t *label_size; /* --label-size pairs for the next meshes */
static int nlabel_size;
static int label1_coarse;         /* elements of label 1 above the finest level */
static const char *size_expr;     /* a size field for the next meshes */

static int mesh_image_opt(const int32_t *img, const double A[12], int voxel, int threads,
                          double vol[4], double cen[4][3], uint64_t *hash) {
  mx_params p;
  mx_params_default(&p);
  p.threads = threads;
  mx_mesher *m = mx_mesher_new(&p);
  const int64_t dims[3] = {N, N, N};
  mx_image_params ip;
  mx_image_params_default(&ip);
  ip.voxel = voxel;
  ip.label_size = label_size;
  ip.nlabel_size = nlabel_size;
  int st = mx_mesher_add_label_array(m, "synthetic", img, dims, A, &ip);
  if (!st && size_expr) st = mx_mesher_set_size_expr(m, size_expr);
  if (!st) st = mx_mesher_mesh(m);
  memset(vol, 0, 4 * sizeof *vol);
  memset(cen, 0, 4 * sizeof *cen);
  if (!st) {
    mx_mesh_arrays a;
    CHECK(mx_mesher_mesh_arrays(m, &a) == MX_OK);
    CHECK(a.material != NULL);
    CHECK(a.invalid == 0 && a.jens_min > 0);
    CHECK(bad_faces(&a) == 0);
    uint64_t h = 14695981039346656037ULL;
    h = hash_bytes(h, a.xyz, 3 * a.nnodes * sizeof *a.xyz);
    h = hash_bytes(h, a.conn, 8 * a.nelements * sizeof *a.conn);
    h = hash_bytes(h, a.material, a.nelements * sizeof *a.material);
    if (hash) *hash = h;
    /* every element's J_ENS as measured here from its nodes (the library
     * measures only the moved ones again under a similarity) */
    size_t jens_off = 0;
    for (size_t e = 0; e < a.nelements; e++) {
      double p[8][3];
      const int nv = a.type[e] == MX_TET ? 4 : a.type[e] == MX_PYRAMID ? 5 : a.type[e] == MX_PRISM ? 6 : 8;
      for (int k = 0; k < nv; k++)
        for (int x = 0; x < 3; x++) p[k][x] = a.xyz[3 * a.conn[8 * e + k] + x];
      jens_off += fabs(mx_jens(a.type[e], (const double(*)[3])p) - a.jens[e]) > 1e-5;
    }
    CHECK(jens_off == 0);
    size_t across = 0;
    int top = 0;
    for (size_t e = 0; e < a.nelements; e++) top = a.level[e] > top ? a.level[e] : top;
    label1_coarse = 0;
    for (size_t e = 0; e < a.nelements; e++) label1_coarse += a.material[e] == 1 && a.level[e] < top;
    for (size_t e = 0; e < a.nelements; e++) {
      const int L = a.material[e];
      CHECK(L >= 1 && L <= 3);
      if (L < 1 || L > 3) continue;
      const double v = element_volume(&a, e);
      vol[L] += v;
      const int nv = a.type[e] == MX_TET ? 4 : a.type[e] == MX_PYRAMID ? 5 : a.type[e] == MX_PRISM ? 6 : 8;
      double c[3] = {0, 0, 0};
      for (int k = 0; k < nv; k++)
        for (int x = 0; x < 3; x++) c[x] += a.xyz[3 * a.conn[8 * e + k] + x] / nv;
      for (int x = 0; x < 3; x++) cen[L][x] += v * c[x];
      if (image_as_given && voxel && A[1] == 0 && A[2] == 0 && A[4] == 0 && A[6] == 0 && A[8] == 0 && A[9] == 0) {
        /* the voxel of the centroid (an axis-aligned transform) */
        int q[3];
        for (int x = 0; x < 3; x++) q[x] = (int)floor((c[x] - A[4 * x + 3]) / A[5 * x] + 0.5);
        across += img[q[0] + N * (q[1] + N * q[2])] != L;
      }
    }
    CHECK(across == 0);
    for (int L = 1; L <= 3; L++)
      for (int x = 0; x < 3 && vol[L] > 0; x++) cen[L][x] /= vol[L];
  }
  mx_mesher_free(m);
  return st;
}

static int mesh_image(const int32_t *img, const double A[12], double vol[4], double cen[4][3]) {
  return mesh_image_opt(img, A, 0, 0, vol, cen, NULL);
}

/* voxel counts and voxel faces per label (the band) */
static void counts(const int32_t *img, size_t cnt[4], size_t faces[4]) {
  memset(cnt, 0, 4 * sizeof *cnt);
  memset(faces, 0, 4 * sizeof *faces);
  for (int k = 0; k < N; k++)
    for (int j = 0; j < N; j++)
      for (int i = 0; i < N; i++) {
        const int L = img[i + N * (j + N * k)];
        if (L < 1 || L > 3) continue;
        cnt[L]++;
        const int c[3] = {i, j, k};
        for (int a = 0; a < 3; a++)
          for (int s = -1; s <= 1; s += 2) {
            int d[3] = {i, j, k};
            d[a] += s;
            const int out = d[a] < 0 || d[a] >= N;
            if (out || img[d[0] + N * (d[1] + N * d[2])] != L) faces[L]++;
          }
        (void)c;
      }
}

static void check_volumes(const char *what, const int32_t *img, const double vol[4],
                          double scale) {
  size_t cnt[4], faces[4];
  counts(img, cnt, faces);
  for (int L = 1; L <= 3; L++) {
    if (!cnt[L]) continue;
    const double want = (double)cnt[L] * scale, band = 0.5 * (double)faces[L] * scale;
    printf("  %s label %d: volume %.3f, voxels %.3f (band %.1f)\n", what, L, vol[L], want, band);
    CHECK(fabs(vol[L] - want) <= band);
  }
}

static void test_meshes(void) {
  const double I[12] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};
  int32_t *img = calloc(N * N * N, sizeof *img);
  double vol[4], cen[4][3], volV[4], cenV[4][3];
  /* three concentric balls */
  const double c = 11.3;
  for (int k = 0; k < N; k++)
    for (int j = 0; j < N; j++)
      for (int i = 0; i < N; i++) {
        const double r = sqrt((i - c) * (i - c) + (j - c) * (j - c) + (k - c) * (k - c));
        img[i + N * (j + N * k)] = r < 3.5 ? 3 : r < 6.5 ? 2 : r < 10 ? 1 : 0;
      }
  CHECK(mesh_image(img, I, vol, cen) == MX_OK);
  check_volumes("balls", img, vol, 1.0);
  for (int x = 0; x < 3; x++) CHECK(fabs(cen[3][x] - c) < 0.3);
  /* a size inside label 1: every element of it at the voxels' level (and
   * not without) */
  CHECK(label1_coarse > 0);
  const int32_t one[2] = {1, 1};
  label_size = one;
  nlabel_size = 1;
  CHECK(mesh_image(img, I, vol, cen) == MX_OK);
  CHECK(label1_coarse == 0);
  check_volumes("balls, label 1 at the voxels", img, vol, 1.0);
  label_size = NULL;
  nlabel_size = 0;
  /* a size field in the world: 0.9 (the transform's voxels are 1): every
   * element at the voxels' level too; a field of 100 changes nothing */
  size_expr = "0.9";
  CHECK(mesh_image(img, I, vol, cen) == MX_OK);
  CHECK(label1_coarse == 0);
  size_expr = "100";
  CHECK(mesh_image(img, I, vol, cen) == MX_OK);
  CHECK(label1_coarse > 0);
  size_expr = NULL;
  /* voxel faces kept: the volumes are the voxels' exactly, every element
   * in a voxel of its label */
  uint64_t h1 = 0, h2 = 1;
  CHECK(mesh_image_opt(img, I, 1, 1, volV, cenV, &h1) == MX_OK);
  size_t cnt[4], faces[4];
  counts(img, cnt, faces);
  for (int L = 1; L <= 3; L++) CHECK(fabs(volV[L] - (double)cnt[L]) < 1e-9 * (double)cnt[L]);
  /* the same arrays with 1 and 2 threads */
  CHECK(mesh_image_opt(img, I, 0, 1, volV, cenV, &h1) == MX_OK);
  CHECK(mesh_image_opt(img, I, 0, 2, volV, cenV, &h2) == MX_OK);
  CHECK(h1 == h2);
  /* the same under an oblique transform (30 degrees about z, spacing 0.5
   * 0.5 0.8, an offset), and under a mirror (x negated) */
  const double t = M_PI / 6, sx = 0.5, sz = 0.8;
  const double B[12] = {cos(t) * sx, -sin(t) * sx, 0, 10, sin(t) * sx, cos(t) * sx, 0, -4,
                        0, 0, sz, 2};
  for (int mirror = 0; mirror < 2; mirror++) {
    double C[12];
    memcpy(C, B, sizeof C);
    if (mirror)
      for (int r = 0; r < 3; r++) C[4 * r] = -C[4 * r];
    double volB[4], cenB[4][3];
    CHECK(mesh_image(img, C, volB, cenB) == MX_OK);
    check_volumes(mirror ? "mirrored balls" : "oblique balls", img, volB, sx * sx * sz);
    for (int r = 0; r < 3; r++) { /* the centroid of label 3 mapped by C */
      const double want = C[4 * r] * c + C[4 * r + 1] * c + C[4 * r + 2] * c + C[4 * r + 3];
      CHECK(fabs(cenB[3][r] - want) < 0.3);
    }
  }
  /* touching boxes, with the voxel faces: exact */
  memset(img, 0, N * N * N * sizeof *img);
  for (int k = 3; k < 20; k++)
    for (int j = 3; j < 20; j++)
      for (int i = 3; i < 20; i++) img[i + N * (j + N * k)] = i < 11 ? 1 : 2;
  CHECK(mesh_image(img, I, vol, cen) == MX_OK);
  check_volumes("boxes", img, vol, 1.0);
  CHECK(mesh_image_opt(img, I, 1, 0, vol, cen, NULL) == MX_OK);
  CHECK(fabs(vol[1] - 8 * 17 * 17) < 1e-9 && fabs(vol[2] - 9 * 17 * 17) < 1e-9);
  /* a plate one voxel thin (label 1) inside a box (label 2): kept whole */
  memset(img, 0, N * N * N * sizeof *img);
  for (int k = 3; k < 20; k++)
    for (int j = 3; j < 20; j++)
      for (int i = 3; i < 20; i++)
        img[i + N * (j + N * k)] = (k == 11 && i >= 6 && i < 17 && j >= 6 && j < 17) ? 1 : 2;
  CHECK(mesh_image(img, I, vol, cen) == MX_OK);
  check_volumes("plate", img, vol, 1.0);
  CHECK(vol[1] > 0.8 * 121);
  /* a checkerboard of 4-voxel blocks: its edge contacts joined (a voxel
   * raised at each), the whole volume the voxels' */
  memset(img, 0, N * N * N * sizeof *img);
  for (int k = 4; k < 20; k++)
    for (int j = 4; j < 20; j++)
      for (int i = 4; i < 20; i++) img[i + N * (j + N * k)] = ((i / 4 + j / 4 + k / 4) & 1) + 1;
  image_as_given = 0;
  CHECK(mesh_image(img, I, vol, cen) == MX_OK);
  CHECK(vol[1] > 0.5 * 2048 && vol[2] > 0.5 * 2048);
  CHECK(fabs(vol[1] + vol[2] - 4096.0) < 0.5 * 6 * 256); /* the outer band */
  CHECK(mesh_image_opt(img, I, 1, 0, vol, cen, NULL) == MX_OK);
  CHECK(fabs(vol[1] + vol[2] - 4096.0) < 1e-9);
  free(img);
}

static void test_bad(void) {
  const double I[12] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};
  const double S[12] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 0, 0}; /* singular */
  int32_t *img = calloc(N * N * N, sizeof *img);
  const int64_t dims[3] = {N, N, N}, zero[3] = {0, N, N};
  mx_params p;
  mx_params_default(&p);
  mx_mesher *m = mx_mesher_new(&p);
  CHECK(mx_mesher_add_label_array(m, "empty", img, dims, I, NULL) == MX_EINPUT); /* all 0 */
  img[100] = 1;
  CHECK(mx_mesher_add_label_array(m, "singular", img, dims, S, NULL) == MX_EINPUT);
  CHECK(mx_mesher_add_label_array(m, "dims", img, zero, I, NULL) == MX_EINPUT);
  img[100] = -3;
  CHECK(mx_mesher_add_label_array(m, "negative", img, dims, I, NULL) == MX_EINPUT);
  int32_t skip[1] = {7};
  mx_image_params ip;
  mx_image_params_default(&ip);
  ip.skip = skip;
  ip.nskip = 1;
  img[100] = 7; /* skipped: nothing left */
  CHECK(mx_mesher_add_label_array(m, "skipped", img, dims, I, &ip) == MX_EINPUT);
  mx_mesher_free(m);
  free(img);
}

int main(void) {
  test_fixes();
  test_surface();
  test_meshes();
  test_bad();
  return TEST_DONE();
}
