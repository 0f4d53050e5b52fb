/* The mixed mesh split into tetrahedra: see kernels/tet_split.h. */
#include "kernels/tet_split.h"

#include <math.h>
#include <string.h>

#include "base/common.h"
#include "base/scan.h"
#include "geom/quality.h"
#include "kernels/mesh_edit.h"

/* Local index of the element's mean (the Steiner node) in a candidate. */
#define CENTRE 8
/* Candidates: cone from local node 0..7, the two hexahedron 5-splits, the
 * cone from the mean, a tetrahedron kept; FAILED: none valid. */
enum { FIVE_EVEN = 8, FIVE_ODD = 9, STEINER = 10, KEEP = 11, FAILED = 255 };
#define MAX_TETS 12 /* a hexahedron's 6 faces, 2 triangles each, coned */

/* Reference coordinates of the local nodes (VTK order; Gmsh's prism),
 * the mean last: they give each candidate tetrahedron its orientation
 * (positive in the reference element), whatever the element's shape. */
static const double ref_xyz[4][9][3] = {
    {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {0}, {0}, {0}, {0}, {0.25, 0.25, 0.25}},
    {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0.5, 0.5, 1}, {0}, {0}, {0}, {0.5, 0.5, 0.2}},
    {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {0, 1, 1}, {0}, {0},
     {1.0 / 3, 1.0 / 3, 0.5}},
    {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1},
     {0.5, 0.5, 0.5}}};

/* The hexahedron's 5-split over the corners {0, 2, 5, 7} (even) or
 * {1, 3, 4, 6} (odd): each other corner cut off with its three
 * neighbours, then the middle tetrahedron. */
static const int8_t five_tets[2][5][4] = {
    {{1, 0, 2, 5}, {3, 2, 0, 7}, {4, 5, 7, 0}, {6, 7, 5, 2}, {0, 2, 5, 7}},
    {{0, 3, 1, 4}, {2, 1, 3, 6}, {5, 4, 6, 1}, {7, 6, 4, 3}, {1, 3, 4, 6}}};

static double det3(const double a[3], const double b[3], const double c[3], const double d[3]) {
  const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
  const double v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
  const double w[3] = {d[0] - a[0], d[1] - a[1], d[2] - a[2]};
  return u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0]) +
         u[2] * (v[0] * w[1] - v[1] * w[0]);
}

/* The element's boundary triangles (local indices, outward): each
 * quadrilateral cut through its node of the smallest global index.
 * Returns their count. */
static int boundary_triangles(int type, const uint32_t *cn, int8_t tri[12][3]) {
  int n = 0;
  for (int f = 0; f < mx_cell_nfaces[type]; f++) {
    const int8_t *q = mx_cell_faces[type][f];
    if (q[3] < 0) {
      memcpy(tri[n++], q, 3);
      continue;
    }
    int lo = 0;
    for (int k = 1; k < 4; k++)
      if (cn[q[k]] < cn[q[lo]]) lo = k;
    if (lo == 0 || lo == 2) { /* diagonal q0 - q2 */
      tri[n][0] = q[0], tri[n][1] = q[1], tri[n++][2] = q[2];
      tri[n][0] = q[0], tri[n][1] = q[2], tri[n++][2] = q[3];
    } else { /* diagonal q1 - q3 */
      tri[n][0] = q[0], tri[n][1] = q[1], tri[n++][2] = q[3];
      tri[n][0] = q[1], tri[n][1] = q[2], tri[n++][2] = q[3];
    }
  }
  return n;
}

static int tri_has(const int8_t t[3], int v) { return t[0] == v || t[1] == v || t[2] == v; }

/* Candidate cand's tetrahedra (local indices, CENTRE the mean), oriented
 * positively in the reference element; their count, 0 when the candidate
 * does not apply (a node with a quadrilateral face cut away from it, a
 * 5-split the diagonals do not allow). */
static int candidate(int type, const int8_t tri[12][3], int nt, int cand, int8_t out[MAX_TETS][4]) {
  int n = 0;
  if (cand == FIVE_EVEN || cand == FIVE_ODD) {
    if (type != MX_HEX) return 0;
    const int odd = cand == FIVE_ODD;
    /* the diagonal of each face is the edge both triangles share; it must
     * join two corners of the set: checked through the triangles' nodes
     * (a face's two triangles each have one node off the diagonal) */
    for (int t = 0; t < nt; t++) {
      int in_set = 0;
      for (int k = 0; k < 3; k++) {
        const int v = tri[t][k];
        in_set += (((v & 1) ^ (v >> 2 & 1)) != 0) == (odd != 0);
      }
      if (in_set != 2) return 0;
    }
    memcpy(out, five_tets[odd], sizeof five_tets[odd]);
    n = 5;
  } else if (cand == STEINER) {
    for (int t = 0; t < nt; t++) {
      out[n][0] = tri[t][0], out[n][1] = tri[t][2], out[n][2] = tri[t][1];
      out[n++][3] = CENTRE;
    }
  } else { /* the cone from node cand */
    if (cand >= mx_cell_nodes[type]) return 0;
    /* applies when every face through cand has all its triangles through it */
    for (int f = 0; f < mx_cell_nfaces[type]; f++) {
      const int8_t *q = mx_cell_faces[type][f];
      if (q[3] < 0 || !(q[0] == cand || q[1] == cand || q[2] == cand || q[3] == cand)) continue;
      for (int t = 0; t < nt; t++) {
        int on_face = 0;
        for (int k = 0; k < 3; k++)
          on_face += tri[t][k] == q[0] || tri[t][k] == q[1] || tri[t][k] == q[2] || tri[t][k] == q[3];
        if (on_face == 3 && !tri_has(tri[t], cand)) return 0;
      }
    }
    for (int t = 0; t < nt; t++) {
      if (tri_has(tri[t], cand)) continue;
      out[n][0] = tri[t][0], out[n][1] = tri[t][2], out[n][2] = tri[t][1];
      out[n++][3] = (int8_t)cand;
    }
  }
  /* orientation from the reference element (a triangle of an outward face
   * reversed and coned from inside is positive already; the 5-split's
   * table is written so too: checked, not assumed) */
  const double(*r)[3] = ref_xyz[type];
  for (int i = 0; i < n; i++)
    if (det3(r[out[i][0]], r[out[i][1]], r[out[i][2]], r[out[i][3]]) < 0) {
      const int8_t s = out[i][1];
      out[i][1] = out[i][2];
      out[i][2] = s;
    }
  return n;
}

/* Whether every tetrahedron of a candidate is valid; p: the element's
 * nodes, the mean at CENTRE. */
static int candidate_valid(const double p[9][3], const int8_t tets[MAX_TETS][4], int n) {
  for (int i = 0; i < n; i++) {
    double q[4][3];
    for (int k = 0; k < 4; k++) memcpy(q[k], p[tets[i][k]], sizeof q[k]);
    if (mx_jens_invalid((float)mx_jens_tet(q))) return 0;
  }
  return 1;
}

/* The least height of the Steiner node over the boundary triangles of a
 * cone from it (positive inside): tetrahedron i is triangle
 * tets[i][0..2] and the node at tets[i][3]. */
static double cone_height(const double p[9][3], const int8_t tets[MAX_TETS][4], int n) {
  double lo = INFINITY;
  for (int i = 0; i < n; i++) {
    const double *a = p[tets[i][0]], *b = p[tets[i][1]], *c = p[tets[i][2]];
    const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    const double v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    const double w[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2],
                         u[0] * v[1] - u[1] * v[0]};
    const double area2 = sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
    const double h = det3(a, b, c, p[tets[i][3]]) / (area2 > 0.0 ? area2 : 1.0);
    if (!(h >= lo)) lo = h;
  }
  return lo;
}

/* The Steiner node of a distorted element, when its mean does not do: the
 * point of the element's kernel (the points that see every boundary
 * triangle from inside) farthest from the triangles' planes, approached by
 * a compass search from the mean (steps along the axes and the cube
 * diagonals, halved when none raises the least height: the least height is
 * concave, its one local maximum the global one) until the step is a
 * thousandth of the element. The mean sees all the boundary triangles of a
 * convex element; a warped quadrilateral face cut along its concave
 * diagonal (thin prisms at the boundary) can hide a triangle from the
 * mean, not from the kernel when there is one. Deterministic: the same
 * point in the count and the fill passes. */
static void steiner_point(double p[9][3], int nv, const int8_t tets[MAX_TETS][4], int n) {
  double lo[3], hi[3];
  for (int d = 0; d < 3; d++) lo[d] = hi[d] = p[0][d];
  for (int k = 1; k < nv; k++)
    for (int d = 0; d < 3; d++) {
      if (p[k][d] < lo[d]) lo[d] = p[k][d];
      if (p[k][d] > hi[d]) hi[d] = p[k][d];
    }
  double h = 0.0;
  for (int d = 0; d < 3; d++)
    if (hi[d] - lo[d] > h) h = hi[d] - lo[d];
  const double stop = 1e-3 * h;
  h *= 0.25;
  static const int8_t dir[14][3] = {{1, 0, 0},  {-1, 0, 0}, {0, 1, 0},   {0, -1, 0},  {0, 0, 1},
                                    {0, 0, -1}, {1, 1, 1},  {-1, -1, -1}, {1, 1, -1}, {-1, -1, 1},
                                    {1, -1, 1}, {-1, 1, -1}, {-1, 1, 1},  {1, -1, -1}};
  double best = cone_height(p, tets, n);
  for (int it = 0; it < 400 && h > stop; it++) {
    const double c[3] = {p[CENTRE][0], p[CENTRE][1], p[CENTRE][2]};
    int moved = 0;
    for (int k = 0; k < 14 && !moved; k++) {
      const double s = k < 6 ? h : h * 0.57735026918962573;
      for (int d = 0; d < 3; d++) p[CENTRE][d] = c[d] + s * dir[k][d];
      const double f = cone_height(p, tets, n);
      if (f > best) best = f, moved = 1;
    }
    if (!moved) {
      memcpy(p[CENTRE], c, sizeof c);
      h *= 0.5;
    }
  }
}

/* The element's nodes and mean. */
static void element_points(const mx_mesh *M, size_t c, double p[9][3]) {
  const int nv = mx_cell_nodes[M->type[c]];
  p[CENTRE][0] = p[CENTRE][1] = p[CENTRE][2] = 0.0;
  for (int k = 0; k < nv; k++) {
    memcpy(p[k], M->xyz + 3 * (size_t)M->conn[8 * c + k], sizeof p[k]);
    for (int d = 0; d < 3; d++) p[CENTRE][d] += p[k][d];
  }
  for (int d = 0; d < 3; d++) p[CENTRE][d] /= nv;
}

/* The candidate taken for element c and its tetrahedra (count in *n). */
static uint8_t choose(const mx_mesh *M, size_t c, int8_t tets[MAX_TETS][4], int *n) {
  const int type = M->type[c];
  if (type == MX_TET) {
    for (int k = 0; k < 4; k++) tets[0][k] = (int8_t)k;
    *n = 1;
    return KEEP;
  }
  const uint32_t *cn = M->conn + 8 * c;
  int8_t tri[12][3];
  const int nt = boundary_triangles(type, cn, tri);
  double p[9][3];
  element_points(M, c, p);
  if (type == MX_HEX)
    for (int cand = FIVE_EVEN; cand <= FIVE_ODD; cand++) {
      *n = candidate(type, tri, nt, cand, tets);
      if (*n && candidate_valid(p, tets, *n)) return (uint8_t)cand;
    }
  /* the cones from the nodes, smallest global index first */
  const int nv = mx_cell_nodes[type];
  int order[8];
  for (int k = 0; k < nv; k++) {
    int j = k;
    for (; j > 0 && cn[order[j - 1]] > cn[k]; j--) order[j] = order[j - 1];
    order[j] = k;
  }
  for (int i = 0; i < nv; i++) {
    *n = candidate(type, tri, nt, order[i], tets);
    if (*n && candidate_valid(p, tets, *n)) return (uint8_t)order[i];
  }
  *n = candidate(type, tri, nt, STEINER, tets);
  if (!candidate_valid(p, tets, *n)) steiner_point(p, nv, tets, *n);
  if (candidate_valid(p, tets, *n)) return STEINER;
  *n = 0;
  return FAILED;
}

size_t mx_tet_split_flag_failures(const mx_mesh *M, uint8_t *flag) {
  size_t n = 0;
#pragma omp parallel for schedule(dynamic, 4096) reduction(+ : n)
  for (size_t c = 0; c < M->ncells; c++) {
    int8_t tets[MAX_TETS][4];
    int k = 0;
    if (M->type[c] != MX_TET && choose(M, c, tets, &k) == FAILED) {
      flag[c] = 1;
      n++;
    }
  }
  return n;
}

static const char *type_name[4] = {"tetrahedron", "pyramid", "prism", "hexahedron"};

int mx_mesh_split_tets(const mx_mesh *M, mx_mesh *T, uint32_t **parent,
                       mx_tet_split_stats *stats) {
  const double t0 = mx_wtime();
  memset(T, 0, sizeof *T);
  if (parent) *parent = NULL;
  memset(stats, 0, sizeof *stats);
  const size_t nc = M->ncells;
  uint8_t *choice = mx_alloc(nc + 1);
  uint64_t *first = mx_alloc((nc + 1) * sizeof *first);  /* tetrahedra before c */
  uint64_t *extra = mx_alloc((nc + 1) * sizeof *extra);  /* Steiner nodes before c */
  if (!choice || !first || !extra) {
    mx_free(choice);
    mx_free(first);
    mx_free(extra);
    return MX_ENOMEM;
  }
  size_t failed = nc, bt[4] = {0, 0, 0, 0}, five = 0;
  /* count: each element's candidate and tetrahedra */
#pragma omp parallel for schedule(dynamic, 4096) reduction(min : failed) reduction(+ : bt[:4], five)
  for (size_t c = 0; c < nc; c++) {
    int8_t tets[MAX_TETS][4];
    int n = 0;
    choice[c] = choose(M, c, tets, &n);
    first[c] = (uint64_t)n;
    extra[c] = choice[c] == STEINER;
    if (choice[c] == FAILED && c < failed) failed = c;
    bt[M->type[c]]++;
    five += choice[c] == FIVE_EVEN || choice[c] == FIVE_ODD;
  }
  if (failed < nc) {
    const size_t c = failed;
    mx_error(NULL, 0, "element %zu (a %s of leaf %u, J_ENS %.3g) cannot be split into "
             "tetrahedra of positive volume (no cone from a node or its mean gives all of "
             "them J_ENS >= 1e-6)", c, type_name[M->type[c]], M->leaf ? M->leaf[c] : 0u,
             M->jens ? (double)M->jens[c] : 0.0);
    mx_free(choice);
    mx_free(first);
    mx_free(extra);
    return MX_EINVALID;
  }
  const uint64_t ntet = mx_scan_u64(first, nc);
  const uint64_t nsteiner = mx_scan_u64(extra, nc);
  const uint64_t nn = (uint64_t)M->nnodes + nsteiner;
  if (nn >= UINT32_MAX || ntet >= UINT32_MAX) {
    mx_error(NULL, 0, "the tetrahedral mesh would have %llu nodes and %llu elements: more "
             "than 32-bit indices hold", (unsigned long long)nn, (unsigned long long)ntet);
    mx_free(choice);
    mx_free(first);
    mx_free(extra);
    return MX_EINPUT;
  }
  T->nnodes = (size_t)nn;
  T->ncells = (size_t)ntet;
  T->xyz = mx_alloc((3 * T->nnodes + 1) * sizeof *T->xyz);
  T->type = mx_alloc(T->ncells + 1);
  T->conn = mx_alloc((8 * T->ncells + 1) * sizeof *T->conn);
  T->level = mx_alloc(T->ncells + 1);
  T->leaf = mx_alloc((T->ncells + 1) * sizeof *T->leaf);
  T->jens = mx_alloc((T->ncells + 1) * sizeof *T->jens);
  if (M->material) T->material = mx_alloc((T->ncells + 1) * sizeof *T->material);
  if (M->nkey) T->nkey = mx_alloc((T->nnodes + 1) * sizeof *T->nkey);
  uint32_t *par = parent ? mx_alloc((T->ncells + 1) * sizeof *par) : NULL;
  if (!T->xyz || !T->type || !T->conn || !T->level || !T->leaf || !T->jens ||
      (M->material && !T->material) || (M->nkey && !T->nkey) || (parent && !par)) {
    mx_free(choice);
    mx_free(first);
    mx_free(extra);
    mx_free(par);
    mx_mesh_free(T);
    return MX_ENOMEM;
  }
  memcpy(T->xyz, M->xyz, 3 * M->nnodes * sizeof *T->xyz);
  if (T->nkey) {
    memcpy(T->nkey, M->nkey, M->nnodes * sizeof *T->nkey);
    for (size_t v = M->nnodes; v < T->nnodes; v++) T->nkey[v] = MX_NKEY_NONE;
  }
  /* fill: each element's tetrahedra at first[c], its Steiner node at
   * nnodes + extra[c] */
#pragma omp parallel for schedule(dynamic, 4096)
  for (size_t c = 0; c < nc; c++) {
    int8_t tets[MAX_TETS][4];
    int n = 0;
    const int type = M->type[c];
    const uint32_t *cn = M->conn + 8 * c;
    double p[9][3];
    uint32_t g[9];
    for (int k = 0; k < mx_cell_nodes[type]; k++) g[k] = cn[k];
    if (type == MX_TET) {
      for (int k = 0; k < 4; k++) tets[0][k] = (int8_t)k;
      n = 1;
    } else {
      int8_t tri[12][3];
      const int nt = boundary_triangles(type, cn, tri);
      n = candidate(type, tri, nt, choice[c], tets);
    }
    if (choice[c] == STEINER) {
      element_points(M, c, p); /* the point choose() took */
      if (!candidate_valid(p, tets, n)) steiner_point(p, mx_cell_nodes[type], tets, n);
      g[CENTRE] = (uint32_t)(M->nnodes + extra[c]);
      memcpy(T->xyz + 3 * (size_t)g[CENTRE], p[CENTRE], sizeof p[CENTRE]);
    }
    for (int i = 0; i < n; i++) {
      const size_t t = (size_t)first[c] + (size_t)i;
      uint32_t *tc = T->conn + 8 * t;
      double q[4][3];
      for (int k = 0; k < 4; k++) {
        tc[k] = g[tets[i][k]];
        memcpy(q[k], tets[i][k] == CENTRE ? p[CENTRE] : M->xyz + 3 * (size_t)tc[k], sizeof q[k]);
      }
      for (int k = 4; k < 8; k++) tc[k] = UINT32_MAX;
      T->type[t] = MX_TET;
      T->level[t] = M->level ? M->level[c] : 0;
      T->leaf[t] = M->leaf ? M->leaf[c] : 0;
      T->jens[t] = (float)mx_jens_tet(q);
      if (T->material) T->material[t] = M->material[c];
      if (par) par[t] = (uint32_t)c;
    }
  }
  T->closures = M->closures;
  T->centre_leaves = M->centre_leaves;
  mx_mesh_summarize(T);
  stats->tets = T->ncells;
  stats->steiner = (size_t)nsteiner;
  stats->five = five;
  memcpy(stats->by_type, bt, sizeof bt);
  mx_free(choice);
  mx_free(first);
  mx_free(extra);
  if (parent) *parent = par;
  stats->seconds = mx_wtime() - t0;
  return MX_OK;
}
