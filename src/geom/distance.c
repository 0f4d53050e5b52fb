/* The surface index (geom/distance.h): its build (the BVH, the 4-wide tree,
 * the edges and shells of geom/surface_topology.h, the orientation of the
 * shells by nesting, the caps, the pseudonormals, the hints) and release. */
#include "geom/distance.h"

#include <math.h>
#include <string.h>

#include "base/common.h"
#include "geom/surface_index_impl.h"

void mx_surface_index_free(mx_surface_index *S) {
  mx_free(S->nodes);
  mx_free(S->wide);
  mx_free(S->tri_id);
  mx_free(S->tv);
  mx_free(S->shell_of);
  mx_free(S->tsign);
  mx_free(S->packs);
  mx_free(S->hint);
  mx_free(S->leaf_first);
  mx_free(S->fn);
  mx_free(S->en);
  mx_free(S->vn);
  mx_free(S->shell_depth);
  mx_free(S->cap_off);
  mx_free(S->cap_cnt);
  mx_free(S->cap_u);
  mx_free(S->cap_v);
  mx_free(S->cap_w);
  memset(S, 0, sizeof *S);
}

/* Orientation of the shells (see distance.h): seeds' centroids, signed
 * volumes, nesting depths by the winding number, then the final signs. */
enum { ORIENT_NESTING = 0, ORIENT_GIVEN = 1, ORIENT_OUTWARD = 2 };

static int orient_shells(mx_surface_index *S, const uint8_t *fix,
                         const uint32_t *seed, const uint32_t *cap_shell, int mode) {
  const int given = mode == ORIENT_GIVEN;
  const uint32_t nt = S->nt, nc = S->nshells;
  const size_t ncap = S->ncap;
  double *rep = mx_alloc(3 * (size_t)nc * sizeof *rep + 8);
  double *vol = mx_calloc((size_t)nc * sizeof *vol + 8);
  int8_t *csign = mx_alloc((size_t)nc + 8);
  int8_t *ssign = mx_alloc((size_t)nt + 8);
  int32_t *capw = mx_alloc(ncap * sizeof *capw + 4);
  size_t *nflip = mx_calloc((size_t)nc * sizeof *nflip + 8);
  size_t *nsize = mx_calloc((size_t)nc * sizeof *nsize + 8);
  double *box = given ? mx_alloc(6 * (size_t)nc * sizeof *box + 8) : NULL;
  if (!rep || !vol || !csign || !ssign || !capw || !nflip || !nsize || (given && !box)) {
    mx_free(box);
    mx_free(rep);
    mx_free(vol);
    mx_free(csign);
    mx_free(ssign);
    mx_free(capw);
    mx_free(nflip);
    mx_free(nsize);
    return MX_ENOMEM;
  }
  /* A point of each shell: the centroid of its seed triangle, clamped to
   * the triangle's box so that the BVH descends to the triangle; as given:
   * the centre of the shell's box (the same for any order of its
   * triangles). */
  for (uint32_t c = 0; c < nc; c++) {
    const double *t = S->tv + 9 * (size_t)seed[c];
    for (int a = 0; a < 3; a++) {
      const double lo = mx_min(t[a], mx_min(t[3 + a], t[6 + a]));
      const double hi = mx_max(t[a], mx_max(t[3 + a], t[6 + a]));
      rep[3 * c + a] = mx_min(hi, mx_max(lo, (t[a] + t[3 + a] + t[6 + a]) / 3.0));
    }
  }
  if (given) {
    for (uint32_t c = 0; c < nc; c++)
      for (int a = 0; a < 3; a++) {
        box[6 * c + a] = INFINITY;
        box[6 * c + 3 + a] = -INFINITY;
      }
    for (uint32_t i = 0; i < nt; i++) {
      double *b = box + 6 * (size_t)S->shell_of[i];
      for (int k = 0; k < 9; k++) {
        b[k % 3] = mx_min(b[k % 3], S->tv[9 * (size_t)i + k]);
        b[3 + k % 3] = mx_max(b[3 + k % 3], S->tv[9 * (size_t)i + k]);
      }
    }
    for (uint32_t c = 0; c < nc; c++)
      for (int a = 0; a < 3; a++) rep[3 * c + a] = 0.5 * (box[6 * c + a] + box[6 * c + 3 + a]);
    mx_free(box);
  }
  /* Signed volumes (6 times), relative to the shell's point. */
  for (uint32_t i = 0; i < nt; i++) {
    const uint32_t c = S->shell_of[i];
    const double *t = S->tv + 9 * (size_t)i, *o = rep + 3 * c;
    double a[3], b[3], d[3], bd[3];
    sub3(t, o, a);
    sub3(t + 3, o, b);
    sub3(t + 6, o, d);
    cross3(b, d, bd);
    const double v = dot3(a, bd);
    vol[c] += fix[i] ? -v : v;
  }
  for (uint32_t c = 0; c < nc; c++) csign[c] = vol[c] < 0.0 ? -1 : 1;
  if (given) {
    /* the way that keeps most triangles as given; ties: outward */
    for (uint32_t i = 0; i < nt; i++) {
      nsize[S->shell_of[i]]++;
      nflip[S->shell_of[i]] += fix[i];
    }
    for (uint32_t c = 0; c < nc; c++)
      if (2 * nflip[c] != nsize[c]) csign[c] = 2 * nflip[c] > nsize[c] ? -1 : 1;
    memset(nflip, 0, (size_t)nc * sizeof *nflip);
    memset(nsize, 0, (size_t)nc * sizeof *nsize);
  }
  /* Every shell outward, then the nesting depth of each. */
  for (uint32_t i = 0; i < nt; i++)
    ssign[i] = (int8_t)((fix[i] ? -1 : 1) * csign[S->shell_of[i]]);
  for (size_t j = 0; j < ncap; j++) capw[j] = S->cap_w[j] * csign[cap_shell[j]];
  if (nc > 1 && !given) {
#pragma omp parallel for schedule(dynamic, 1) if (nc > 8)
    for (uint32_t c = 0; c < nc; c++) {
      const double w = mx_index_winding(S, rep + 3 * c, ssign, capw, seed[c]);
      /* w = depth + 1/2 */
      long depth = lround(w - 0.5);
      if (depth < 0) depth = 0;
      S->shell_depth[c] = (uint32_t)depth;
      if (depth % 2 && mode != ORIENT_OUTWARD) csign[c] = (int8_t)-csign[c];
    }
  }
  for (uint32_t i = 0; i < nt; i++) {
    const uint32_t c = S->shell_of[i];
    S->tsign[i] = (int8_t)((fix[i] ? -1 : 1) * csign[c]);
    nsize[c]++;
    if (S->tsign[i] < 0) nflip[c]++;
  }
  for (size_t j = 0; j < ncap; j++) S->cap_w[j] *= csign[cap_shell[j]];
  S->nflipped = 0;
  S->nreoriented = 0;
  for (uint32_t c = 0; c < nc; c++) {
    if (2 * nflip[c] > nsize[c]) {
      S->nflipped++;
      S->nreoriented += nsize[c] - nflip[c];
    } else {
      S->nreoriented += nflip[c];
    }
  }
  mx_free(rep);
  mx_free(vol);
  mx_free(csign);
  mx_free(ssign);
  mx_free(capw);
  mx_free(nflip);
  mx_free(nsize);
  return MX_OK;
}

static int index_build(mx_surface_index *S, const mx_trisoup *soup, uint32_t t0,
                       uint32_t t1, int mode) {
  memset(S, 0, sizeof *S);
  if (t0 > t1 || t1 > soup->nt) {
    mx_error(NULL, 0, "surface index: triangle range [%u, %u) outside [0, %zu)",
             t0, t1, soup->nt);
    return MX_EINPUT;
  }
  if (t1 - t0 > (1u << 30)) {
    mx_error(NULL, 0, "surface index: %u triangles, at most 2^30 supported",
             t1 - t0);
    return MX_EINPUT;
  }
  S->soup = soup;
  S->t0 = t0;
  S->t1 = t1;
  S->nt = t1 - t0;
  S->closed = 1;
  const uint32_t nt = S->nt;
  if (!nt) return MX_OK;

  /* BVH over the centroids. */
  S->nnodes = (uint32_t)mx_bvh_node_count(nt);
  S->nodes = mx_alloc((size_t)S->nnodes * sizeof *S->nodes);
  S->tri_id = mx_alloc((size_t)nt * sizeof *S->tri_id);
  S->tv = mx_alloc(9 * (size_t)nt * sizeof *S->tv);
  S->shell_of = mx_alloc((size_t)nt * sizeof *S->shell_of);
  S->tsign = mx_alloc((size_t)nt);
  S->fn = mx_alloc(3 * (size_t)nt * sizeof *S->fn);
  S->en = mx_alloc(9 * (size_t)nt * sizeof *S->en);
  double *cen = mx_alloc(3 * (size_t)nt * sizeof *cen);
  if (!S->nodes || !S->tri_id || !S->tv || !S->shell_of || !S->tsign ||
      !S->fn || !S->en || !cen) {
    mx_free(cen);
    mx_surface_index_free(S);
    return MX_ENOMEM;
  }
#pragma omp parallel for schedule(static) if (nt > 10000)
  for (uint32_t t = 0; t < nt; t++) {
    const uint32_t *v = soup->tri + 3 * ((size_t)t0 + t);
    cen[t] = (soup->x[v[0]] + soup->x[v[1]] + soup->x[v[2]]) / 3.0;
    cen[(size_t)nt + t] = (soup->y[v[0]] + soup->y[v[1]] + soup->y[v[2]]) / 3.0;
    cen[2 * (size_t)nt + t] =
        (soup->z[v[0]] + soup->z[v[1]] + soup->z[v[2]]) / 3.0;
    S->tri_id[t] = t;
  }
  mx_bvh_build(S->nodes, S->tri_id, cen, nt, soup->tri + 3 * (size_t)t0, soup->x,
               soup->y, soup->z);
  mx_free(cen);
  S->wide = mx_alloc(((size_t)S->nnodes / 2 + 1) * sizeof *S->wide);
  S->packs = mx_alloc(((size_t)S->nnodes / 2 + 1) * sizeof *S->packs);
  S->leaf_first = mx_alloc(((size_t)S->nnodes / 2 + 1) * sizeof *S->leaf_first);
  if (!S->wide || !S->packs || !S->leaf_first) {
    mx_surface_index_free(S);
    return MX_ENOMEM;
  }
#pragma omp parallel for schedule(static) if (nt > 10000)
  for (uint32_t i = 0; i < nt; i++) {
    S->tri_id[i] += t0;
    const uint32_t *v = soup->tri + 3 * (size_t)S->tri_id[i];
    double *t = S->tv + 9 * (size_t)i;
    for (int k = 0; k < 3; k++) {
      t[3 * k] = soup->x[v[k]];
      t[3 * k + 1] = soup->y[v[k]];
      t[3 * k + 2] = soup->z[v[k]];
    }
  }
  double cm = 0.0;
  for (size_t i = 0; i < 9 * (size_t)nt; i++) cm = mx_max(cm, fabs(S->tv[i]));
  S->coord_max = cm;
  {
    const int st = mx_index_wide_tree(S);
    if (st != MX_OK) {
      mx_surface_index_free(S);
      return st;
    }
  }

  /* Edges and shells. */
  mx_edge_table E;
  memset(&E, 0, sizeof E);
  uint8_t *fix = mx_alloc((size_t)nt + 8);
  uint32_t *seed = NULL, *cap_shell = NULL;
  int st = fix ? mx_edge_table_build(&E, soup->tri, S->tri_id, nt, (uint32_t)soup->nv, 0, 1) : MX_ENOMEM;
  if (st == MX_OK) {
    size_t open = 0, nonman = 0;
    for (size_t j = 0; j < E.n;) {
      const size_t end = mx_edge_run_end(&E, j);
      if (end - j != 2) open++;
      if (end - j > 2) nonman++;
      j = end;
    }
    S->open_edges = open;
    S->nonmanifold_edges = nonman;
    st = mx_surface_shells(&E, 1, S->shell_of, fix, &S->nshells, &seed,
                           &S->conflict_edges);
  }
  if (st == MX_OK) {
    S->shell_depth = mx_calloc(((size_t)S->nshells + 1) * sizeof *S->shell_depth);
    if (!S->shell_depth) st = MX_ENOMEM;
  }
  if (st == MX_OK) {
    S->closed = S->open_edges == 0 && S->conflict_edges == 0;
    st = mx_index_build_caps(S, fix, &cap_shell);
  }
  if (st == MX_OK) st = orient_shells(S, fix, seed, cap_shell, mode);
  /* the pseudonormal sign tells a point's side only where the shells turn
   * their outside to the domain's outside: not as given, not all outward
   * when a shell nests in another */
  if (mode == ORIENT_GIVEN) S->closed = 0;
  if (mode == ORIENT_OUTWARD && mx_surface_index_nested(S)) {
    /* closed, manifold, oriented shells: their sides from the closest
     * point all the same (closest.c, depth_by_closest) */
    S->outward_closed = S->closed;
    S->closed = 0;
  }
  if (st == MX_OK) st = mx_index_pseudonormals(S, &E);
  if (st == MX_OK) st = mx_index_hints(S);
  mx_edge_table_free(&E);
  mx_free(fix);
  mx_free(seed);
  mx_free(cap_shell);
  if (st != MX_OK) mx_surface_index_free(S);
  return st;
}

int mx_surface_index_build(mx_surface_index *S, const mx_trisoup *soup,
                           uint32_t t0, uint32_t t1) {
  return index_build(S, soup, t0, t1, ORIENT_NESTING);
}

int mx_surface_index_build_outward(mx_surface_index *S, const mx_trisoup *soup,
                                   uint32_t t0, uint32_t t1) {
  return index_build(S, soup, t0, t1, ORIENT_OUTWARD);
}

int mx_surface_index_nested(const mx_surface_index *S) {
  for (uint32_t c = 0; S->shell_depth && c < S->nshells; c++)
    if (S->shell_depth[c] > 0) return 1;
  return 0;
}


int mx_surface_index_build_given(mx_surface_index *S, const mx_trisoup *soup,
                                 uint32_t t0, uint32_t t1) {
  return index_build(S, soup, t0, t1, ORIENT_GIVEN);
}


void mx_surface_index_shell_volumes(const mx_surface_index *S, double *vol, double *area) {
  for (uint32_t c = 0; c < S->nshells; c++) {
    vol[c] = 0.0;
    if (area) area[c] = 0.0;
  }
  double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
  for (size_t i = 0; i < 9 * (size_t)S->nt; i++) {
    lo[i % 3] = fmin(lo[i % 3], S->tv[i]);
    hi[i % 3] = fmax(hi[i % 3], S->tv[i]);
  }
  double o[3];
  for (int k = 0; k < 3; k++) o[k] = 0.5 * (lo[k] + hi[k]);
  for (uint32_t i = 0; i < S->nt; i++) {
    const double *t = S->tv + 9 * (size_t)i;
    double p[3], q[3], r[3];
    for (int k = 0; k < 3; k++) p[k] = t[k] - o[k], q[k] = t[3 + k] - o[k], r[k] = t[6 + k] - o[k];
    const uint32_t c = S->shell_of[i];
    vol[c] += S->tsign[i] * (p[0] * (q[1] * r[2] - q[2] * r[1]) - p[1] * (q[0] * r[2] - q[2] * r[0]) +
                             p[2] * (q[0] * r[1] - q[1] * r[0])) / 6.0;
    if (!area) continue;
    const double u[3] = {q[0] - p[0], q[1] - p[1], q[2] - p[2]};
    const double w[3] = {r[0] - p[0], r[1] - p[1], r[2] - p[2]};
    const double x[3] = {u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2],
                         u[0] * w[1] - u[1] * w[0]};
    area[c] += 0.5 * sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]);
  }
}
