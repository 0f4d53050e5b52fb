/* Geometry that several passes of the checker use: cubic cells over a box
 * (the coordinate hash of check_duplicates.c), the squared distance from a
 * point to a triangle (check_contacts.c, check_distance.c), and a tree of
 * triangles' boxes for the nearest triangle to a point and the triangles
 * near a box (check_distance.c: over the surface, and over the mesh's
 * skin): the triangles halved again and again, across the longest side of
 * their boxes' centres, into a binary tree (node i's children 2i and
 * 2i + 1) down to leaves of at most CK_LEAF triangles, each node with the
 * box of its triangles; searched by branch and bound, so a far point costs
 * about as little as a near one. The checker's own, apart from
 * geom/distance.h's closest points, which the mesher uses. */
#include "verify/check_passes.h"


/* Cubic cells over a box of extents ext: about `target` of them over the
 * dimensions wider than a cell, at most maxdim per axis. Sets h and d.
 * Works on the extents relative to the largest, each at least 1 / maxdim,
 * so no product underflows (a box of extents 1 x 1e-300 x 1e-300 gets
 * cells along its long side only). */
void mx_ck_cell_grid(const double ext[3], double target, int maxdim,
                      double *h_out, int d[3]) {
  double mext = mx_max(ext[0], mx_max(ext[1], ext[2]));
  if (!(mext > 0.0) || !isfinite(mext)) { /* one point, or no range */
    d[0] = d[1] = d[2] = 1;
    *h_out = mext > 0.0 ? INFINITY : 1.0;
    return;
  }
  if (!(target >= 1.0)) target = 1.0;
  const double floor_r = 1.0 / maxdim;
  double r[3];
  for (int a = 0; a < 3; a++) r[a] = mx_max(ext[a] / mext, floor_r);
  double h = 0.0;
  for (int it = 0; it < 4; it++) {
    double prod = 1.0;
    int k = 0;
    for (int a = 0; a < 3; a++)
      if (r[a] > h) {
        prod *= r[a];
        k++;
      }
    if (k == 0) {
      prod = 1.0;
      k = 1;
    }
    h = mx_max(pow(prod / target, 1.0 / k), floor_r);
  }
  for (int a = 0; a < 3; a++) {
    const double n = ceil(ext[a] / mext / h);
    d[a] = !(n >= 1.0) ? 1 : n > maxdim ? maxdim : (int)n;
  }
  h *= mext;
  for (int a = 0; a < 3; a++) h = mx_max(h, ext[a] / d[a]);
  *h_out = h;
}

/* Squared distance from p to the triangle a-b-c: the closest point lies in
 * the Voronoi region of a vertex, of an edge, or of the face, told apart by
 * the signs of dot products and of barycentric numerators. */
double mx_ck_point_triangle_d2(const double p[3], const double a[3],
                                const double b[3], const double c[3]) {
  double ab[3], ac[3], ap[3], bp[3], cp[3];
  for (int x = 0; x < 3; x++) {
    ab[x] = b[x] - a[x];
    ac[x] = c[x] - a[x];
    ap[x] = p[x] - a[x];
    bp[x] = p[x] - b[x];
    cp[x] = p[x] - c[x];
  }
#define DOT(u, v) ((u)[0] * (v)[0] + (u)[1] * (v)[1] + (u)[2] * (v)[2])
  const double d1 = DOT(ab, ap), d2 = DOT(ac, ap);
  if (d1 <= 0.0 && d2 <= 0.0) return DOT(ap, ap);
  const double d3 = DOT(ab, bp), d4 = DOT(ac, bp);
  if (d3 >= 0.0 && d4 <= d3) return DOT(bp, bp);
  const double d5 = DOT(ab, cp), d6 = DOT(ac, cp);
  if (d6 >= 0.0 && d5 <= d6) return DOT(cp, cp);
  const double vc = d1 * d4 - d3 * d2, vb = d5 * d2 - d1 * d6,
               va = d3 * d6 - d5 * d4;
  double s, t; /* closest point a + s ab + t ac */
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {
    s = d1 / (d1 - d3);
    t = 0.0;
  } else if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {
    s = 0.0;
    t = d2 / (d2 - d6);
  } else if (va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0) {
    const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6)); /* along b-c */
    s = 1.0 - w;
    t = w;
  } else {
    const double den = va + vb + vc;
    if (!(den > 0.0)) { /* degenerate triangle: its vertices */
      return mx_min(DOT(ap, ap), mx_min(DOT(bp, bp), DOT(cp, cp)));
    }
    s = vb / den;
    t = vc / den;
  }
  double d[3];
  for (int x = 0; x < 3; x++) d[x] = ap[x] - s * ab[x] - t * ac[x];
  return DOT(d, d);
#undef DOT
}

/* ---- the triangle tree ----------------------------------------------------- */

void mx_ck_tree_free(ck_tree *R) {
  mx_free(R->tv);
  mx_free(R->node);
  memset(R, 0, sizeof *R);
}

/* Node i over the triangles [lo, hi) of the tree's order: a leaf when they
 * are LEAF or fewer, else children 2i and 2i + 1 over the two halves. */
static void tree_node(ck_tree *R, size_t i, uint32_t lo, uint32_t hi) {
  ck_node *n = &R->node[i];
  n->lo = lo;
  n->hi = hi;
  for (int a = 0; a < 3; a++) {
    n->box[a] = INFINITY;
    n->box[3 + a] = -INFINITY;
  }
  if (hi - lo <= CK_LEAF) {
    for (uint32_t t = lo; t < hi; t++) {
      const double *b = R->tv + CK_TV * (size_t)t + 9;
      for (int a = 0; a < 3; a++) {
        n->box[a] = mx_min(n->box[a], b[a]);
        n->box[3 + a] = mx_max(n->box[3 + a], b[3 + a]);
      }
    }
    return;
  }
  const uint32_t mid = lo + (hi - lo + 1) / 2;
  tree_node(R, 2 * i, lo, mid);
  tree_node(R, 2 * i + 1, mid, hi);
  const double *b0 = R->node[2 * i].box, *b1 = R->node[2 * i + 1].box;
  for (int a = 0; a < 3; a++) {
    n->box[a] = mx_min(b0[a], b1[a]);
    n->box[3 + a] = mx_max(b0[3 + a], b1[3 + a]);
  }
}

/* Whether triangle a comes before b along axis x: by their centres (c, 3
 * per triangle), then their numbers. */
static inline int centre_before(const double *c, int x, uint32_t a, uint32_t b) {
  const double ca = c[3 * (size_t)a + (size_t)x], cb = c[3 * (size_t)b + (size_t)x];
  return ca < cb || (ca == cb && a < b);
}

/* Reorders t[0, n) so that t[k] is the one a sort along axis x would put
 * there, the ones before it before, the others after (quickselect, the
 * median of three as pivot). */
static void select_along(const double *c, int x, uint32_t *t, size_t n, size_t k) {
  size_t lo = 0, hi = n - 1;
  while (hi > lo) {
    const size_t mid = lo + (hi - lo) / 2;
    /* the median of t[lo], t[mid], t[hi] into t[mid] */
    uint32_t u;
#define SWAP(i, j) (u = t[i], t[i] = t[j], t[j] = u)
    if (centre_before(c, x, t[mid], t[lo])) SWAP(mid, lo);
    if (centre_before(c, x, t[hi], t[lo])) SWAP(hi, lo);
    if (centre_before(c, x, t[hi], t[mid])) SWAP(hi, mid);
    const uint32_t pivot = t[mid];
    size_t i = lo, j = hi;
    while (i <= j) { /* Hoare: [lo, j] not after the pivot, [i, hi] not before */
      while (centre_before(c, x, t[i], pivot)) i++;
      while (centre_before(c, x, pivot, t[j])) j--;
      if (i <= j) {
        SWAP(i, j);
        i++;
        if (j == 0) break;
        j--;
      }
    }
#undef SWAP
    if (k <= j)
      hi = j;
    else if (k >= i)
      lo = i;
    else
      return;
  }
}

/* Node i's triangles t[lo, hi) split at the middle, across the longest side
 * of their centres' box, and so on down to the leaves. */
static void split_node(const double *c, uint32_t *t, uint32_t lo, uint32_t hi) {
  if (hi - lo <= CK_LEAF) return;
  double mn[3] = {INFINITY, INFINITY, INFINITY}, mx[3] = {-INFINITY, -INFINITY, -INFINITY};
  for (uint32_t i = lo; i < hi; i++)
    for (int a = 0; a < 3; a++) {
      mn[a] = mx_min(mn[a], c[3 * (size_t)t[i] + (size_t)a]);
      mx[a] = mx_max(mx[a], c[3 * (size_t)t[i] + (size_t)a]);
    }
  int x = 0;
  for (int a = 1; a < 3; a++)
    if (mx[a] - mn[a] > mx[x] - mn[x]) x = a;
  const uint32_t mid = lo + (hi - lo + 1) / 2;
  select_along(c, x, t + lo, hi - lo, mid - lo);
  split_node(c, t, lo, mid);
  split_node(c, t, mid, hi);
}

int mx_ck_tree_build(ck_tree *R, const ck_tris *T) {
  memset(R, 0, sizeof *R);
  R->nt = T->nt;
  if (T->nt == 0) return MX_OK;
  if (T->nt >= UINT32_MAX) return MX_ENOMEM;
  size_t leaves = 1; /* a power of two: the halving reaches CK_LEAF by then */
  while ((size_t)CK_LEAF * leaves < T->nt) leaves *= 2;
  double *centre = mx_alloc(3 * T->nt * sizeof *centre);
  uint32_t *order = mx_alloc(T->nt * sizeof *order);
  R->tv = mx_alloc(CK_TV * T->nt * sizeof *R->tv);
  R->node = mx_alloc(2 * leaves * sizeof *R->node);
  if (!centre || !order || !R->tv || !R->node) {
    mx_free(centre);
    mx_free(order);
    mx_ck_tree_free(R);
    return MX_ENOMEM;
  }
#pragma omp parallel for schedule(static) if (T->nt > SMALL)
  for (size_t t = 0; t < T->nt; t++) {
    double p[3][3];
    for (int k = 0; k < 3; k++) ck_tri_vertex(T, t, k, p[k]);
    for (int a = 0; a < 3; a++)
      centre[3 * t + (size_t)a] = 0.5 * (mx_min(p[0][a], mx_min(p[1][a], p[2][a])) +
                                         mx_max(p[0][a], mx_max(p[1][a], p[2][a])));
    order[t] = (uint32_t)t;
  }
  split_node(centre, order, 0, (uint32_t)T->nt);
#pragma omp parallel for schedule(static) if (T->nt > SMALL)
  for (size_t i = 0; i < T->nt; i++) {
    double *v = R->tv + CK_TV * i;
    for (int k = 0; k < 3; k++) ck_tri_vertex(T, order[i], k, v + 3 * k);
    for (int a = 0; a < 3; a++) {
      v[9 + a] = mx_min(v[a], mx_min(v[3 + a], v[6 + a]));
      v[12 + a] = mx_max(v[a], mx_max(v[3 + a], v[6 + a]));
    }
  }
  tree_node(R, 1, 0, (uint32_t)T->nt);
  mx_free(centre);
  mx_free(order);
  return MX_OK;
}

/* Squared distance between the boxes a and b (lo x y z, hi x y z). */
static inline double boxes_d2(const double *a, const double *b) {
  double d2 = 0.0;
  for (int x = 0; x < 3; x++) {
    const double d = mx_max(mx_max(a[x] - b[3 + x], b[x] - a[3 + x]), 0.0);
    d2 += d * d;
  }
  return d2;
}

/* Branch and bound: the nodes on a stack, the nearer child popped first;
 * a node or a triangle whose box is no nearer than the best (at first
 * `below`) is passed by. */
double mx_ck_tree_d2(const ck_tree *R, const double p[3], double below) {
  if (R->nt == 0) return INFINITY;
  struct {
    size_t node;
    double d2;
  } stack[2 * 64];
  size_t top = 0;
  double best = below;
  stack[top].node = 1;
  stack[top++].d2 = ck_box_d2(p, R->node[1].box, R->node[1].box + 3);
  while (top) {
    --top;
    if (stack[top].d2 >= best) continue;
    const size_t i = stack[top].node;
    const ck_node *n = &R->node[i];
    if (n->hi - n->lo <= CK_LEAF) {
      for (uint32_t t = n->lo; t < n->hi; t++) {
        const double *v = R->tv + CK_TV * (size_t)t;
        if (ck_box_d2(p, v + 9, v + 12) >= best) continue;
        best = mx_min(best, mx_ck_point_triangle_d2(p, v, v + 3, v + 6));
      }
      continue;
    }
    const double d0 = ck_box_d2(p, R->node[2 * i].box, R->node[2 * i].box + 3),
                 d1 = ck_box_d2(p, R->node[2 * i + 1].box, R->node[2 * i + 1].box + 3);
    const int near1 = d1 < d0; /* pushed last, popped first */
    stack[top].node = 2 * i + (size_t)!near1;
    stack[top++].d2 = near1 ? d0 : d1;
    stack[top].node = 2 * i + (size_t)near1;
    stack[top++].d2 = near1 ? d1 : d0;
  }
  return best;
}

size_t mx_ck_tree_near_box(const ck_tree *R, const double box[6], double u, uint32_t *list,
                           size_t cap) {
  if (R->nt == 0 || !(u < INFINITY)) return SIZE_MAX;
  const double u2 = u * u;
  size_t stack[2 * 64], top = 0, n = 0;
  stack[top++] = 1;
  while (top) {
    const size_t i = stack[--top];
    const ck_node *nd = &R->node[i];
    if (!(boxes_d2(box, nd->box) <= u2)) continue;
    if (nd->hi - nd->lo > CK_LEAF) {
      stack[top++] = 2 * i + 1;
      stack[top++] = 2 * i;
      continue;
    }
    for (uint32_t t = nd->lo; t < nd->hi; t++) {
      if (!(boxes_d2(box, R->tv + CK_TV * (size_t)t + 9) <= u2)) continue;
      if (n == cap) return SIZE_MAX;
      list[n++] = t;
    }
  }
  return n;
}
