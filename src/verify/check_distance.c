/* Pass 8 of the checker, distance to the surface: every boundary node's
 * distance to the nearest surface triangle, through a tree of the
 * triangles' boxes searched by branch and bound (check_geometry.c); the
 * largest, over the diagonal of the surface's box, and the nodes beyond
 * boundary_tol times it. The nodes of the faces between two labels (F_IFACE: the
 * interfaces between materials, which lie on the surface's inner shells)
 * the same way, apart.
 * Then, with a closed surface, the distance between the mesh's skin (its
 * boundary faces, and its interface faces with cell labels; quads as two
 * triangles a-b-c, a-c-d) and the surface, both ways (check.h's
 * definitions): each triangle of one side sampled at the points of a k x k
 * barycentric grid (its vertices; its edge midpoints when k is even) and
 * at the centroids of the k^2 small triangles (its own centroid is one of
 * the two kinds), each sample's distance to the other side found among the
 * few triangles that can be nearest to any point of the triangle (found in
 * the other side's tree; the tree itself for each sample when they are
 * many); the largest, and the mean over the area, each small triangle's
 * mean taken as 1/12 of each of its vertices' distances plus 3/4 of its
 * centroid's (a rule exact for quadratics), summed per block of triangles
 * in a fixed order so that any thread count gives the same digits. The
 * skin nodes' distances are those found above.
 */
#include "verify/check_passes.h"

#include "base/scan.h"

int mx_ck_surface_distance(const mx_mesh_data *m, const mx_trisoup *s,
                           uint8_t *flags, double tol, double *node_d2, mx_check_report *r) {
  double lo[3], hi[3];
  mx_trisoup_bbox(s, lo, hi);
  double diag2 = 0.0;
  for (int a = 0; a < 3; a++) diag2 += (hi[a] - lo[a]) * (hi[a] - lo[a]);
  /* Distance of the boundary and interface nodes. */
  r->boundary_max_dist = NAN;
  r->interface_max_dist = NAN;
  if (s->nt == 0 || !(diag2 > 0.0)) return MX_OK;
  size_t nb = 0, nbnd = 0, ni = 0;
  for (size_t v = 0; v < m->nnodes; v++) {
    nb += (flags[v] & (F_BND | F_IFACE)) != 0;
    nbnd += (flags[v] & F_BND) != 0;
    ni += (flags[v] & F_IFACE) != 0;
  }
  r->interface_nodes = ni;
  if (nb == 0) return MX_OK;
  uint32_t *bn = mx_alloc(nb * sizeof *bn);
  const ck_tris T = ck_soup_tris(s);
  ck_tree R;
  const int st = bn ? mx_ck_tree_build(&R, &T) : MX_ENOMEM;
  if (st != MX_OK) {
    mx_free(bn);
    return st;
  }
  nb = 0;
  for (size_t v = 0; v < m->nnodes; v++)
    if (flags[v] & (F_BND | F_IFACE)) bn[nb++] = (uint32_t)v;
  double worst = 0.0, iworst = 0.0;
  size_t off = 0, ioff = 0;
  const double sdiag = sqrt(diag2);
#pragma omp parallel for schedule(dynamic, 256) reduction(max : worst, iworst) \
    reduction(+ : off, ioff) if (nb > SMALL / 4)
  for (size_t i = 0; i < nb; i++) {
    const double d2 = mx_ck_tree_d2(&R, m->xyz + 3 * (size_t)bn[i], INFINITY);
    if (node_d2) node_d2[bn[i]] = d2;
    const uint8_t f = flag_get(&flags[bn[i]]);
    const int far = !(sqrt(d2) / sdiag <= tol);
    if (f & F_BND) {
      worst = mx_max(worst, d2);
      if (far) {
        flag_or(&flags[bn[i]], F_OFF);
        off++;
      }
    }
    if (f & F_IFACE) {
      iworst = mx_max(iworst, d2);
      if (far) {
        flag_or(&flags[bn[i]], F_IOFF);
        ioff++;
      }
    }
  }
  mx_ck_tree_free(&R);
  mx_free(bn);
  if (nbnd) r->boundary_max_dist = sqrt(worst) / sdiag;
  r->boundary_off_surface = off;
  if (ni) r->interface_max_dist = sqrt(iworst) / sdiag;
  r->interface_off_surface = ioff;
  return MX_OK;
}

/* ---- both ways ----------------------------------------------------------- */

enum {
  K_MAX = 50,        /* (K+1)(K+2)/2 + K^2 = 3826 samples a triangle at most */
  K_MESH = 8,        /* on the mesh side: 109 (its faces are many and small) */
  BLOCK = 64,        /* triangles summed in order by one thread */
  MESH_SPACING = 1000, /* the mesh side sampled every diagonal / 1000 */
  CANDIDATES = 64,     /* the most triangles one samples against at once */
  BLOCK_K = 4          /* else blocks of samples share them: grid steps a side */
};

/* One way: the largest squared distance, the integral of the distance over
 * the triangles, their area, the samples. */
typedef struct {
  double max2, integral, area;
  size_t samples;
} one_way;

/* The sub-grid of a triangle whose longest edge is len, for samples about
 * h apart: k = ceil(len / h) within [2, kmax]. */
static int sub_grid(double len, double h, int kmax) {
  const double k = ceil(len / h);
  if (!(k > 2.0)) return 2; /* also 0 / 0 */
  return k < kmax ? (int)k : kmax;
}

/* The point (wa P0 + wb P1 + wc P2) / W, wa = W - wb - wc: the triangle's
 * vertices exactly. */
static void bary(const double P[3][3], int wb, int wc, int W, double p[3]) {
  const int wa = W - wb - wc;
  const int v = wa == W ? 0 : wb == W ? 1 : wc == W ? 2 : -1;
  for (int a = 0; a < 3; a++)
    p[a] = v >= 0 ? P[v][a] : (wa * P[0][a] + wb * P[1][a] + wc * P[2][a]) / W;
}

/* A thread's sampling: the tree of the other side; the candidates of the
 * triangle sampled (ncand of them; SIZE_MAX: none, the tree asked for each
 * sample). */
typedef struct {
  const ck_tree *R;
  uint32_t cand[CANDIDATES]; /* places in R's order */
  size_t ncand, hint;        /* hint: the nearest to the last sample */
  double last[3], last_d2;   /* the last sample and its squared distance */
  double max2;
  size_t samples;
} sampler;

/* The squared distance from p to the nearest candidate, the one nearest
 * to the last sample first (a box no nearer than the best is passed by). */
static double candidates_d2(sampler *S, const double p[3]) {
  const double *c = S->R->tv + CK_TV * (size_t)S->cand[S->hint];
  double best = mx_ck_point_triangle_d2(p, c, c + 3, c + 6);
  for (size_t i = 0; i < S->ncand; i++) {
    c = S->R->tv + CK_TV * (size_t)S->cand[i];
    if (i == S->hint || ck_box_d2(p, c + 9, c + 12) >= best) continue;
    const double d2 = mx_ck_point_triangle_d2(p, c, c + 3, c + 6);
    if (d2 < best) {
      best = d2;
      S->hint = i;
    }
  }
  return best;
}

/* The squared distance from p to the tree's nearest triangle, below the
 * last sample's distance plus the way from it (with some slack for
 * rounding; asked again without when nothing is below: exact either way). */
static double tree_d2(sampler *S, const double p[3]) {
  double w2 = 0.0, scale = 0.0;
  for (int a = 0; a < 3; a++) {
    w2 += (p[a] - S->last[a]) * (p[a] - S->last[a]);
    scale = mx_max(scale, fabs(p[a]));
  }
  const double up = (sqrt(S->last_d2) + sqrt(w2)) * (1.0 + 1e-9) + 1e-12 * scale;
  const double below = up * up;
  double d2 = mx_ck_tree_d2(S->R, p, below);
  if (!(d2 < below)) d2 = mx_ck_tree_d2(S->R, p, INFINITY);
  return d2;
}

/* The squared distance from p to the other side's triangles. */
static double sample_at(sampler *S, const double p[3]) {
  const double d2 = S->ncand != SIZE_MAX && S->ncand ? candidates_d2(S, p) : tree_d2(S, p);
  memcpy(S->last, p, sizeof S->last);
  S->last_d2 = d2;
  S->max2 = mx_max(S->max2, d2);
  S->samples++;
  return d2;
}

/* The distance from the sub-grid point (wb, wc) / W of P. */
static double sample(sampler *S, const double P[3][3], int wb, int wc, int W) {
  double p[3];
  bary(P, wb, wc, W, p);
  return sqrt(sample_at(S, p));
}

/* The candidates for every point of the convex polygon of the n points
 * Q[] (the first one at distance dq from the other side): the triangles
 * whose boxes lie within dq + the polygon's largest distance from Q[0] of
 * its box (every point of it is within that of a triangle: through
 * Q[0]'s), with some slack for rounding; none (ncand SIZE_MAX) when there
 * are more than CANDIDATES. */
static void candidates(sampler *S, const double (*Q)[3], int n, double dq) {
  double box[6], scale = 0.0, reach2 = 0.0;
  for (int a = 0; a < 3; a++) {
    box[a] = box[3 + a] = Q[0][a];
    scale = mx_max(scale, fabs(Q[0][a]));
  }
  for (int x = 1; x < n; x++) {
    double w2 = 0.0;
    for (int a = 0; a < 3; a++) {
      box[a] = mx_min(box[a], Q[x][a]);
      box[3 + a] = mx_max(box[3 + a], Q[x][a]);
      scale = mx_max(scale, fabs(Q[x][a]));
      w2 += (Q[x][a] - Q[0][a]) * (Q[x][a] - Q[0][a]);
    }
    reach2 = mx_max(reach2, w2);
  }
  const double u = (dq + sqrt(reach2)) * (1.0 + 1e-9) + 1e-12 * scale;
  S->ncand = mx_ck_tree_near_box(S->R, box, u, S->cand, CANDIDATES);
  S->hint = 0;
}

static double longest_edge(const double P[3][3]) {
  double l2 = 0.0;
  for (int k = 0; k < 3; k++) {
    const double *a = P[k], *b = P[(k + 1) % 3];
    const double e = (b[0] - a[0]) * (b[0] - a[0]) + (b[1] - a[1]) * (b[1] - a[1]) +
                     (b[2] - a[2]) * (b[2] - a[2]);
    l2 = mx_max(l2, e);
  }
  return sqrt(l2);
}

static double tri_area(const double P[3][3]) {
  double u[3], v[3];
  for (int a = 0; a < 3; a++) {
    u[a] = P[1][a] - P[0][a];
    v[a] = P[2][a] - P[0][a];
  }
  const double n[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2],
                       u[0] * v[1] - u[1] * v[0]};
  return 0.5 * sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
}

/* Grid point (i, j) of a k-grid in a triangular array, row by row. */
static inline size_t grid_at(int i, int j, int k) {
  return (size_t)j * (size_t)(2 * k + 3 - j) / 2 + (size_t)i;
}

/* The distance at grid point (i, j), sampled unless known. */
static double grid_point(sampler *S, const double P[3][3], int k, double *g, int i, int j) {
  double *d = &g[grid_at(i, j, k)];
  if (isnan(*d)) *d = sample(S, P, i, j, k);
  return *d;
}

/* The candidates for the block of P's k-grid over i in [i0, i1], j in
 * [j0, j1] (within i + j <= k): its corners, the first one's distance
 * sampled unless known. */
static void block_candidates(sampler *S, const double P[3][3], int k, double *g, int i0,
                             int j0, int i1, int j1) {
  S->ncand = SIZE_MAX; /* (i0, j0) asked of the tree */
  const double dq = grid_point(S, P, k, g, i0, j0);
  int c[5][2] = {{i0, j0}, {mx_min(i1, k - j0), j0}, {i0, mx_min(j1, k - i0)}}, n = 3;
  if (i1 + j1 <= k) {
    c[n][0] = i1, c[n][1] = j1, n++;
  } else {
    if (k - i1 >= j0) c[n][0] = i1, c[n][1] = k - i1, n++;
    if (k - j1 >= i0) c[n][0] = k - j1, c[n][1] = j1, n++;
  }
  double Q[5][3];
  for (int x = 0; x < n; x++) bary(P, c[x][0], c[x][1], k, Q[x]);
  candidates(S, (const double(*)[3])Q, n, dq);
}

/* Triangle P sampled on its k-grid (dv2: its vertices' squared distances):
 * adds its area times its mean distance to *integral, its area to *area.
 * The up triangles (i, j) (i + 1, j) (i, j + 1) and the down triangles
 * (i + 1, j) (i, j + 1) (i + 1, j + 1) of the grid: each one's mean 1/12
 * of each vertex's distance plus 3/4 of its centroid's. The samples share
 * the candidates of the whole triangle when they are few, else those of
 * blocks of BLOCK_K x BLOCK_K small triangles. */
static void sample_triangle(sampler *S, const double P[3][3], int k, const double dv2[3],
                            double *integral, double *area) {
  double g[(K_MAX + 1) * (K_MAX + 2) / 2];
  for (size_t x = 0; x < grid_at(0, k, k) + 1; x++) g[x] = NAN;
  g[grid_at(0, 0, k)] = sqrt(dv2[0]);
  g[grid_at(k, 0, k)] = sqrt(dv2[1]);
  g[grid_at(0, k, k)] = sqrt(dv2[2]);
  const int v0 = dv2[1] < dv2[0] ? (dv2[2] < dv2[1] ? 2 : 1) : dv2[2] < dv2[0] ? 2 : 0;
  const double Q[3][3] = {{P[v0][0], P[v0][1], P[v0][2]},
                          {P[(v0 + 1) % 3][0], P[(v0 + 1) % 3][1], P[(v0 + 1) % 3][2]},
                          {P[(v0 + 2) % 3][0], P[(v0 + 2) % 3][1], P[(v0 + 2) % 3][2]}};
  candidates(S, Q, 3, sqrt(dv2[v0]));
  const int B = S->ncand != SIZE_MAX ? k : BLOCK_K;
  double csum = 0.0;
  for (int jb = 0; jb < k; jb += B)
    for (int ib = 0; ib + jb < k; ib += B) {
      if (B < k) block_candidates(S, P, k, g, ib, jb, mx_min(ib + B, k), mx_min(jb + B, k));
      for (int j = jb; j < mx_min(jb + B, k); j++)
        for (int i = ib; i < mx_min(ib + B, k - j); i++) {
          grid_point(S, P, k, g, i, j);
          grid_point(S, P, k, g, i + 1, j);
          grid_point(S, P, k, g, i, j + 1);
          csum += 0.75 * sample(S, P, 3 * i + 1, 3 * j + 1, 3 * k);
          if (i + j + 2 <= k) {
            grid_point(S, P, k, g, i + 1, j + 1);
            csum += 0.75 * sample(S, P, 3 * i + 2, 3 * j + 2, 3 * k);
          }
        }
    }
  double vsum = 0.0;
  for (int j = 0; j < k; j++)
    for (int i = 0; i < k - j; i++) {
      const double a = g[grid_at(i, j, k)], b = g[grid_at(i + 1, j, k)],
                   c = g[grid_at(i, j + 1, k)];
      vsum += (a + b + c) / 12.0;
      if (i + j + 2 <= k) vsum += (b + c + g[grid_at(i + 1, j + 1, k)]) / 12.0;
    }
  const double A = tri_area(P);
  *integral += A * ((vsum + csum) / ((double)k * k));
  *area += A;
}

/* The triangles of `from` sampled every h (at least, k <= kmax), against
 * tree R; vd2 (NULL: none) the squared distances of from's vertices. */
static int one_way_distance(const ck_tris *from, double h, int kmax, const ck_tree *R,
                            const double *vd2, one_way *o) {
  const size_t nblocks = (from->nt + BLOCK - 1) / BLOCK;
  double *part = mx_alloc((2 * nblocks + 1) * sizeof *part);
  if (!part) return MX_ENOMEM;
  double max2 = 0.0;
  size_t samples = 0;
#pragma omp parallel reduction(max : max2) reduction(+ : samples) if (from->nt > BLOCK)
  {
    sampler S = {.R = R};
#pragma omp for schedule(dynamic, 1)
    for (size_t b = 0; b < nblocks; b++) {
      double integral = 0.0, area = 0.0;
      const size_t end = mx_min((b + 1) * BLOCK, from->nt);
      for (size_t t = b * BLOCK; t < end; t++) {
        double P[3][3], dv2[3];
        for (int v = 0; v < 3; v++) ck_tri_vertex(from, t, v, P[v]);
        S.ncand = SIZE_MAX;
        S.last_d2 = INFINITY;
        for (int v = 0; v < 3; v++) {
          if (vd2) {
            dv2[v] = vd2[from->tri[3 * t + (size_t)v]];
            memcpy(S.last, P[v], sizeof S.last);
            S.last_d2 = dv2[v];
            S.max2 = mx_max(S.max2, dv2[v]);
            S.samples++;
          } else {
            dv2[v] = sample_at(&S, P[v]);
          }
        }
        sample_triangle(&S, P, sub_grid(longest_edge(P), h, kmax), dv2, &integral, &area);
      }
      part[2 * b] = integral;
      part[2 * b + 1] = area;
    }
    max2 = mx_max(max2, S.max2);
    samples += S.samples;
  }
  o->max2 = max2;
  o->samples = samples;
  o->integral = o->area = 0.0;
  for (size_t b = 0; b < nblocks; b++) {
    o->integral += part[2 * b];
    o->area += part[2 * b + 1];
  }
  mx_free(part);
  return MX_OK;
}

/* The skin's faces as triangles (quads a-b-c, a-c-d) into tri, and the
 * median of the faces' longest sides (the upper of the middle two). */
static int skin_triangles(const mx_mesh_data *m, const uint32_t *skin, size_t nskin,
                          uint32_t *tri, size_t *nt, double *median) {
  uint64_t *len = mx_alloc((nskin + 1) * sizeof *len);
  if (!len) return MX_ENOMEM;
  size_t n = 0;
  for (size_t i = 0; i < nskin; i++) {
    uint32_t v[4];
    const int nv = face_verts(m, skin[i], v);
    double l2 = 0.0;
    for (int k = 0; k < nv; k++) {
      const double *a = m->xyz + 3 * (size_t)v[k], *b = m->xyz + 3 * (size_t)v[(k + 1) % nv];
      l2 = mx_max(l2, (b[0] - a[0]) * (b[0] - a[0]) + (b[1] - a[1]) * (b[1] - a[1]) +
                          (b[2] - a[2]) * (b[2] - a[2]));
    }
    const double l = sqrt(l2); /* >= 0: its bits sort as the numbers */
    memcpy(&len[i], &l, sizeof l);
    for (int k = 0; k + 2 < nv; k++) {
      tri[3 * n] = v[0];
      tri[3 * n + 1] = v[k + 1];
      tri[3 * n + 2] = v[k + 2];
      n++;
    }
  }
  *nt = n;
  const int st = mx_sort_u64(len, NULL, nskin);
  if (st == MX_OK && nskin) memcpy(median, &len[nskin / 2], sizeof *median);
  mx_free(len);
  return st;
}

int mx_ck_two_sided_distance(const mx_mesh_data *m, const mx_trisoup *s, const uint32_t *skin,
                             size_t nskin, const double *node_d2, mx_check_report *r) {
  r->mesh_to_surface_max = r->mesh_to_surface_mean = NAN;
  r->surface_to_mesh_max = r->surface_to_mesh_mean = NAN;
  r->mesh_sample_spacing = r->surface_sample_spacing = NAN;
  r->mesh_to_surface_samples = r->surface_to_mesh_samples = 0;
  double lo[3], hi[3];
  mx_trisoup_bbox(s, lo, hi);
  double diag2 = 0.0;
  for (int a = 0; a < 3; a++) diag2 += (hi[a] - lo[a]) * (hi[a] - lo[a]);
  r->surface_diagonal = sqrt(diag2);
  if (s->nt == 0 || nskin == 0 || !(diag2 > 0.0) || !isfinite(diag2)) return MX_OK;
  uint32_t *tri = mx_alloc((6 * nskin + 1) * sizeof *tri);
  if (!tri) return MX_ENOMEM;
  size_t nt = 0;
  double median = NAN;
  int st = skin_triangles(m, skin, nskin, tri, &nt, &median);
  const ck_tris mesh = {m->xyz, m->xyz + 1, m->xyz + 2, 3, tri, nt};
  const ck_tris surf = ck_soup_tris(s);
  /* mesh -> surface: the skin sampled every diagonal / 1000 */
  ck_tree R;
  one_way o;
  if (st == MX_OK) {
    st = mx_ck_tree_build(&R, &surf);
    if (st == MX_OK) {
      st = one_way_distance(&mesh, r->surface_diagonal / MESH_SPACING, K_MESH, &R, node_d2, &o);
      mx_ck_tree_free(&R);
    }
  }
  if (st == MX_OK) {
    r->mesh_to_surface_max = sqrt(o.max2);
    r->mesh_to_surface_mean = o.area > 0.0 ? o.integral / o.area : NAN;
    r->mesh_to_surface_samples = o.samples;
    r->mesh_sample_spacing = r->surface_diagonal / MESH_SPACING;
  }
  /* surface -> mesh: the surface sampled every median skin face size */
  if (st == MX_OK) {
    st = mx_ck_tree_build(&R, &mesh);
    if (st == MX_OK) {
      st = one_way_distance(&surf, median, K_MAX, &R, NULL, &o);
      mx_ck_tree_free(&R);
    }
  }
  if (st == MX_OK) {
    r->surface_to_mesh_max = sqrt(o.max2);
    r->surface_to_mesh_mean = o.area > 0.0 ? o.integral / o.area : NAN;
    r->surface_to_mesh_samples = o.samples;
    r->surface_sample_spacing = median;
  }
  mx_free(tri);
  return st;
}
