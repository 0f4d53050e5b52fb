/* The mixed mesh split into tetrahedra (kernels/tet_split.h, --tets),
 * checked here with code of its own:
 *  - single elements: counts (tetrahedron 1, pyramid 2, prism 3,
 *    hexahedron 6, or 5 when the smallest-index diagonals join four
 *    alternate corners), the volume, a distorted hexahedron no cone from a
 *    node splits (verified here: every cone the diagonals allow has a
 *    tetrahedron of non-positive volume) split around one Steiner node, a
 *    prism no split keeps valid refused (MX_EINVALID);
 *  - the demo surface's meshes (-s 3, -s 4): every tetrahedron of positive
 *    volume; each element's tetrahedra fill it (the total equals the
 *    mixed elements' volumes bounded by the same smallest-index diagonals);
 *    conforming (each triangle used once or twice, twice with opposite
 *    orientations), the boundary triangles exactly the mixed boundary's
 *    triangles and quadrilaterals cut by those diagonals; per leaf the
 *    tetrahedra the types give; nodes kept; the same bytes for 1 and 2
 *    threads; through the library (mx_params.tets), a valid all-tetrahedra
 *    mesh that refine_elements refines by tetrahedron indices. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "base/common.h" /* mx_alloc_fail_countdown */
#include "check.h"
#include "kernels/tet_split.h"
#include "mixoct.h"
#include "soa/mesh.h"

static double det4(const double *a, const double *b, const double *c, const double *d) {
  const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
  const double v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
  const double w[3] = {d[0] - a[0], d[1] - a[1], d[2] - a[2]};
  return u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0]) +
         u[2] * (v[0] * w[1] - v[1] * w[0]);
}

/* The triangles of face f of element c: the quadrilateral's cut by the
 * diagonal through its smallest node; outward; returns 1 or 2. */
static int face_tris(const uint8_t *type, const uint32_t *conn, size_t c, int f, uint32_t t[2][3]) {
  const int8_t *q = mx_cell_faces[type[c]][f];
  const uint32_t *cn = conn + 8 * c;
  if (q[3] < 0) {
    for (int k = 0; k < 3; k++) t[0][k] = cn[q[k]];
    return 1;
  }
  uint32_t v[4];
  for (int k = 0; k < 4; k++) v[k] = cn[q[k]];
  const uint32_t m02 = v[0] < v[2] ? v[0] : v[2], m13 = v[1] < v[3] ? v[1] : v[3];
  if (m02 < m13) {
    t[0][0] = v[0], t[0][1] = v[1], t[0][2] = v[2];
    t[1][0] = v[0], t[1][1] = v[2], t[1][2] = v[3];
  } else {
    t[0][0] = v[0], t[0][1] = v[1], t[0][2] = v[3];
    t[1][0] = v[1], t[1][1] = v[2], t[1][2] = v[3];
  }
  return 2;
}

/* Volume of element c bounded by its cut faces (divergence theorem). */
static double cut_volume(const double *xyz, const uint8_t *type, const uint32_t *conn, size_t c) {
  double s = 0.0;
  const double *o = xyz + 3 * (size_t)conn[8 * c];
  for (int f = 0; f < mx_cell_nfaces[type[c]]; f++) {
    uint32_t t[2][3];
    const int n = face_tris(type, conn, c, f, t);
    for (int i = 0; i < n; i++)
      s += det4(o, xyz + 3 * (size_t)t[i][0], xyz + 3 * (size_t)t[i][1], xyz + 3 * (size_t)t[i][2]);
  }
  return s / 6.0;
}

/* A face as a sortable record: sorted nodes, then orientation (the
 * parity of the sort) and how many. */
typedef struct { uint32_t v[4]; int8_t parity; } face_rec;
static int cmp_face(const void *a, const void *b) {
  const face_rec *x = a, *y = b;
  for (int k = 0; k < 4; k++)
    if (x->v[k] != y->v[k]) return x->v[k] < y->v[k] ? -1 : 1;
  return 0;
}
static face_rec tri_rec(const uint32_t t[3]) {
  face_rec r;
  uint32_t a = t[0], b = t[1], c = t[2];
  int par = 0;
  if (a > b) { uint32_t s = a; a = b; b = s; par ^= 1; }
  if (b > c) { uint32_t s = b; b = c; c = s; par ^= 1; }
  if (a > b) { uint32_t s = a; a = b; b = s; par ^= 1; }
  r.v[0] = a, r.v[1] = b, r.v[2] = c, r.v[3] = UINT32_MAX;
  r.parity = (int8_t)par;
  return r;
}

/* The alternate corner set (0: 0 2 5 7, 1: 1 3 4 6) holding the
 * diagonal of every face of hexahedron c, or -1. */
static int five_set(const uint8_t *type, const uint32_t *conn, size_t c) {
  int set = -1;
  for (int f = 0; f < 6; f++) {
    uint32_t tr[2][3];
    face_tris(type, conn, c, f, tr);
    for (int k = 0; k < 3; k++) { /* the diagonal: the nodes both triangles have */
      const uint32_t v = tr[0][k];
      if (v != tr[1][0] && v != tr[1][1] && v != tr[1][2]) continue;
      int loc = 0;
      while (conn[8 * c + loc] != v) loc++;
      const int par = (loc & 1) ^ (loc >> 2 & 1);
      if (set < 0) set = par;
      else if (par != set) return -1;
    }
  }
  return set;
}

/* Whether cone(s) from local node v over the other cut triangles of
 * a single element (nodes 0..nv-1 = global ids ids[k]) is allowed by the
 * diagonals and has every tetrahedron positive. */
static int cone_ok(int type, const uint32_t *ids, const double *xyz, int v) {
  uint8_t ty = (uint8_t)type;
  uint32_t conn[8];
  for (int k = 0; k < 8; k++) conn[k] = k < mx_cell_nodes[type] ? ids[k] : UINT32_MAX;
  for (int f = 0; f < mx_cell_nfaces[type]; f++) {
    uint32_t t[2][3];
    const int n = face_tris(&ty, conn, 0, f, t);
    int on = 0; /* v on this face */
    for (int k = 0; k < 4 && mx_cell_faces[type][f][k] >= 0; k++) on |= mx_cell_faces[type][f][k] == v;
    for (int i = 0; i < n; i++) {
      const int has = t[i][0] == ids[v] || t[i][1] == ids[v] || t[i][2] == ids[v];
      if (on && !has) return 0; /* a face through v cut away from it */
      /* outward triangle coned from v: positive when v is inside */
      if (!has && !(det4(xyz + 3 * t[i][0], xyz + 3 * t[i][2], xyz + 3 * t[i][1], xyz + 3 * ids[v]) > 0))
        return 0;
    }
  }
  return 1;
}

/* One element through the kernel: returns its status, *nt and *ns the
 * tetrahedra and Steiner nodes, *vol their volume, *pos whether all are
 * positive. */
static int one(int type, const uint32_t *ids, const double *xyz, int nn, size_t *nt, size_t *ns,
               double *vol, int *pos, double *cut) {
  mx_mesh M;
  memset(&M, 0, sizeof M);
  uint8_t ty = (uint8_t)type, lev = 2;
  uint32_t conn[8], leaf = 7;
  float j = 0.5f;
  for (int k = 0; k < 8; k++) conn[k] = k < mx_cell_nodes[type] ? ids[k] : UINT32_MAX;
  M.nnodes = (size_t)nn, M.ncells = 1, M.xyz = (double *)xyz, M.type = &ty, M.conn = conn;
  M.level = &lev, M.leaf = &leaf, M.jens = &j;
  *cut = cut_volume(xyz, &ty, conn, 0);
  mx_mesh T;
  mx_tet_split_stats s;
  const int st = mx_mesh_split_tets(&M, &T, NULL, &s);
  *nt = *ns = 0;
  *vol = 0.0;
  *pos = 1;
  if (st) return st;
  *nt = T.ncells;
  *ns = T.nnodes - M.nnodes;
  for (size_t t = 0; t < T.ncells; t++) {
    const uint32_t *c = T.conn + 8 * t;
    const double d = det4(T.xyz + 3 * c[0], T.xyz + 3 * c[1], T.xyz + 3 * c[2], T.xyz + 3 * c[3]) / 6;
    *vol += d;
    *pos &= d > 0 && T.leaf[t] == 7 && T.level[t] == 2 && T.type[t] == MX_TET;
  }
  mx_mesh_free(&T);
  return st;
}

static void single_elements(void) {
  /* reference elements, VTK order (Gmsh's prism), nodes numbered as listed */
  static const double cube[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0},
                                    {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
  static const double prism[6][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {0, 1, 1}};
  static const double pyr[5][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0.5, 0.5, 1}};
  static const double tet[4][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  size_t nt, ns;
  double vol, cut;
  int pos;
  const uint32_t id8[8] = {0, 1, 2, 3, 4, 5, 6, 7};
  /* node 0 smallest: its three faces cut through it; the three faces
   * around node 6 cut through nodes 1 or 3 (1: faces 0154 and 1265; 3:
   * 3267's smallest), so not all through one alternate set: 6 */
  CHECK(one(MX_HEX, id8, &cube[0][0], 8, &nt, &ns, &vol, &pos, &cut) == MX_OK);
  CHECK(nt == 6 && ns == 0 && pos && fabs(vol - 1.0) < 1e-14);
  /* corners 0 2 5 7 numbered 0..3: every face's smallest node is one of
   * them, and its opposite corner too: the 5-split */
  const uint32_t alt[8] = {0, 4, 1, 5, 6, 2, 7, 3};
  double cube_alt[8][3];
  for (int k = 0; k < 8; k++) memcpy(cube_alt[alt[k]], cube[k], sizeof cube[k]);
  CHECK(one(MX_HEX, alt, &cube_alt[0][0], 8, &nt, &ns, &vol, &pos, &cut) == MX_OK);
  CHECK(nt == 5 && ns == 0 && pos && fabs(vol - 1.0) < 1e-14);
  CHECK(one(MX_PRISM, id8, &prism[0][0], 6, &nt, &ns, &vol, &pos, &cut) == MX_OK);
  CHECK(nt == 3 && ns == 0 && pos && fabs(vol - 0.5) < 1e-14);
  CHECK(one(MX_PYRAMID, id8, &pyr[0][0], 5, &nt, &ns, &vol, &pos, &cut) == MX_OK);
  CHECK(nt == 2 && ns == 0 && pos && fabs(vol - 1.0 / 3) < 1e-14);
  CHECK(one(MX_TET, id8, &tet[0][0], 4, &nt, &ns, &vol, &pos, &cut) == MX_OK);
  CHECK(nt == 1 && ns == 0 && pos && fabs(vol - 1.0 / 6) < 1e-14);

  /* a distorted hexahedron (local node k is global ids[k]) that no cone
   * from a node splits validly, checked here: one Steiner node, 12
   * tetrahedra of positive volume filling it */
  const uint32_t ids[8] = {5, 3, 2, 7, 4, 6, 1, 0};
  static const double p[8][3] = {{0.223, 0.043, 0.225},  {0.866, 0.176, -0.121},
                                 {1.088, 0.790, -0.047}, {0.201, 0.913, -0.007},
                                 {-0.113, 0.030, 1.052}, {1.123, 0.043, 0.859},
                                 {1.106, 0.914, 0.821},  {-0.129, 1.149, 0.792}};
  double x[8][3];
  for (int k = 0; k < 8; k++) memcpy(x[ids[k]], p[k], sizeof p[k]);
  int any_cone = 0;
  for (int v = 0; v < 8; v++) any_cone |= cone_ok(MX_HEX, ids, &x[0][0], v);
  uint8_t hex = MX_HEX;
  CHECK(!any_cone && five_set(&hex, ids, 0) < 0); /* nor a 5-split */
  CHECK(one(MX_HEX, ids, &x[0][0], 8, &nt, &ns, &vol, &pos, &cut) == MX_OK);
  CHECK(nt == 12 && ns == 1 && pos && fabs(vol - cut) < 1e-12 * fabs(cut));

  /* a thin prism at a boundary (hollow-coarse.off at -s 4) whose warped
   * faces cut along their concave diagonals leave no point inside that sees
   * every boundary triangle: refused, MX_EINVALID (the mesher repairs its
   * leaf) */
  const uint32_t pid[6] = {3, 5, 0, 1, 2, 4};
  static const double pp[6][3] = {{3.85433446, -0.513574206, -0.237034249},
                                  {3.84216216, -0.464907075, -0.193812531},
                                  {3.85433446, -0.513574206, -0.197528541},
                                  {3.89384017, -0.513574206, -0.237034249},
                                  {3.85361483, -0.456771939, -0.207825657},
                                  {3.89384017, -0.513574206, -0.197528541}};
  double px[6][3];
  for (int k = 0; k < 6; k++) memcpy(px[pid[k]], pp[k], sizeof pp[k]);
  int prism_cone = 0;
  for (int v = 0; v < 6; v++) prism_cone |= cone_ok(MX_PRISM, pid, &px[0][0], v);
  CHECK(!prism_cone);
  CHECK(one(MX_PRISM, pid, &px[0][0], 6, &nt, &ns, &vol, &pos, &cut) == MX_EINVALID);
}

/* ---- whole meshes ---------------------------------------------------------- */

typedef struct {
  mx_mesher *m;
  mx_mesh_arrays a;
} run;

static void quiet(void *user, int level, const char *text) { (void)user, (void)level, (void)text; }

static int mesh_demo(int level, int tets, int threads, run *r) {
  mx_params p;
  mx_params_default(&p);
  p.surface_level = level;
  p.threads = threads;
  p.tets = tets;
  r->m = mx_mesher_new(&p);
  if (!r->m) return MX_ENOMEM;
  mx_mesher_set_message_handler(r->m, quiet, NULL);
  int st = mx_mesher_add_demo_surface(r->m);
  if (!st) st = mx_mesher_mesh(r->m);
  if (!st) st = mx_mesher_mesh_arrays(r->m, &r->a);
  return st;
}

/* The kernel on the mixed mesh of arrays a, checked. */
static void check_split(const mx_mesh_arrays *a, const char *what) {
  mx_mesh M;
  memset(&M, 0, sizeof M);
  M.nnodes = a->nnodes, M.ncells = a->nelements;
  M.xyz = (double *)a->xyz, M.type = (uint8_t *)a->type, M.conn = (uint32_t *)a->conn;
  M.level = (uint8_t *)a->level, M.leaf = (uint32_t *)a->leaf, M.jens = (float *)a->jens;
  mx_mesh T;
  mx_tet_split_stats s;
  uint32_t *parent = NULL;
  CHECK(mx_mesh_split_tets(&M, &T, &parent, &s) == MX_OK);
  if (!T.ncells) return;
  const size_t nn = M.nnodes, ns = T.nnodes - nn;
  CHECK(s.steiner == ns);
  CHECK(memcmp(T.xyz, M.xyz, 3 * nn * sizeof *T.xyz) == 0); /* nodes kept */
  /* positive volumes; each element filled by its tetrahedra */
  double *vt = calloc(M.ncells, sizeof *vt);
  size_t nonpos = 0, badmeta = 0;
  for (size_t t = 0; t < T.ncells; t++) {
    const uint32_t *c = T.conn + 8 * t;
    const double d = det4(T.xyz + 3 * c[0], T.xyz + 3 * c[1], T.xyz + 3 * c[2], T.xyz + 3 * c[3]) / 6;
    nonpos += !(d > 0);
    vt[parent[t]] += d;
    badmeta += T.type[t] != MX_TET || T.leaf[t] != M.leaf[parent[t]] ||
               T.level[t] != M.level[parent[t]] || !(T.jens[t] >= 1e-6f);
  }
  size_t unfilled = 0;
  double vm = 0.0, vs = 0.0;
  for (size_t c = 0; c < M.ncells; c++) {
    const double v = cut_volume(M.xyz, M.type, M.conn, c);
    unfilled += !(fabs(vt[c] - v) <= 1e-12 * fabs(v));
    vm += v;
    vs += vt[c];
  }
  CHECK(nonpos == 0 && badmeta == 0 && unfilled == 0);
  CHECK(fabs(vs - vm) <= 1e-12 * vm);
  /* counts per element: parents in order, and as the types give them */
  size_t bad_count = 0, five = 0, steiner_elems = 0;
  size_t *cnt = calloc(M.ncells, sizeof *cnt);
  for (size_t t = 0; t < T.ncells; t++) cnt[parent[t]]++;
  for (size_t t = 1; t < T.ncells; t++) bad_count += parent[t] < parent[t - 1];
  for (size_t c = 0; c < M.ncells; c++) {
    static const size_t base[4] = {1, 2, 3, 6};
    static const size_t cone[4] = {1, 6, 8, 12}; /* around a Steiner node */
    if (cnt[c] == base[M.type[c]]) continue;
    if (M.type[c] == MX_HEX && cnt[c] == 5) {
      five++; /* the 5-split: every face's diagonal between alternate corners */
      bad_count += five_set(M.type, M.conn, c) < 0;
    } else if (cnt[c] == cone[M.type[c]]) {
      steiner_elems++;
    } else {
      bad_count++;
    }
  }
  CHECK(bad_count == 0);
  CHECK(steiner_elems == ns && five == s.five);
  /* conformity: triangles used once or twice (then opposite), boundary
   * triangles those of the mixed boundary cut by the same diagonals */
  face_rec *tf = malloc(4 * T.ncells * sizeof *tf);
  for (size_t t = 0; t < T.ncells; t++)
    for (int f = 0; f < 4; f++) {
      uint32_t tr[3];
      for (int k = 0; k < 3; k++) tr[k] = T.conn[8 * t + mx_cell_faces[MX_TET][f][k]];
      tf[4 * t + f] = tri_rec(tr);
    }
  qsort(tf, 4 * T.ncells, sizeof *tf, cmp_face);
  face_rec *tb = malloc(4 * T.ncells * sizeof *tb);
  size_t nb = 0, over = 0, same_side = 0, interior = 0;
  for (size_t i = 0; i < 4 * T.ncells;) {
    size_t j = i + 1;
    while (j < 4 * T.ncells && cmp_face(tf + i, tf + j) == 0) j++;
    if (j - i == 1) tb[nb++] = tf[i];
    else if (j - i == 2) interior++, same_side += tf[i].parity == tf[i + 1].parity;
    else over++;
    i = j;
  }
  CHECK(over == 0 && same_side == 0 && interior > 0);
  /* the mixed boundary: faces as sorted node sets, used once */
  size_t nf = 0;
  for (size_t c = 0; c < M.ncells; c++) nf += (size_t)mx_cell_nfaces[M.type[c]];
  face_rec *mf = malloc(nf * sizeof *mf);
  uint64_t *mfsrc = malloc(nf * sizeof *mfsrc);
  size_t k = 0;
  for (size_t c = 0; c < M.ncells; c++)
    for (int f = 0; f < mx_cell_nfaces[M.type[c]]; f++) {
      const int8_t *q = mx_cell_faces[M.type[c]][f];
      face_rec r;
      int n = q[3] < 0 ? 3 : 4;
      for (int i = 0; i < 4; i++) r.v[i] = i < n ? M.conn[8 * c + q[i]] : UINT32_MAX;
      for (int i = 1; i < 4; i++) /* insertion sort */
        for (int j2 = i; j2 > 0 && r.v[j2] < r.v[j2 - 1]; j2--) {
          const uint32_t sw = r.v[j2];
          r.v[j2] = r.v[j2 - 1];
          r.v[j2 - 1] = sw;
        }
      r.parity = 0;
      mf[k] = r;
      mfsrc[k++] = 8 * (uint64_t)c + (uint64_t)f;
    }
  /* sorted with their sources (the record first: cmp_face compares it) */
  typedef struct { face_rec r; uint64_t src; } fs;
  fs *both = malloc(nf * sizeof *both);
  for (size_t i = 0; i < nf; i++) both[i].r = mf[i], both[i].src = mfsrc[i];
  qsort(both, nf, sizeof *both, cmp_face); /* face_rec first: compares r.v */
  face_rec *mb = malloc(2 * nf * sizeof *mb);
  size_t nmb = 0;
  for (size_t i = 0; i < nf;) {
    size_t j = i + 1;
    while (j < nf && cmp_face(&both[i].r, &both[j].r) == 0) j++;
    if (j - i == 1) {
      uint32_t tr[2][3];
      const size_t c = (size_t)(both[i].src >> 3);
      const int n = face_tris(M.type, M.conn, c, (int)(both[i].src & 7), tr);
      for (int a2 = 0; a2 < n; a2++) mb[nmb++] = tri_rec(tr[a2]);
    }
    i = j;
  }
  qsort(mb, nmb, sizeof *mb, cmp_face);
  size_t differ = nmb != nb;
  for (size_t i = 0; !differ && i < nb; i++)
    differ += cmp_face(tb + i, mb + i) != 0 || tb[i].parity != mb[i].parity;
  CHECK(differ == 0);
  printf("%s: %zu elements (hex %zu prism %zu pyramid %zu tet %zu) -> %zu tetrahedra, "
         "%zu Steiner, %zu hex in 5; %zu boundary triangles, volume %.10g\n",
         what, M.ncells, a->by_type[MX_HEX], a->by_type[MX_PRISM], a->by_type[MX_PYRAMID],
         a->by_type[MX_TET], T.ncells, ns, five, nb, vs);
  free(vt), free(cnt), free(tf), free(tb), free(mf), free(mfsrc), free(both), free(mb);
  mx_free_array(parent);
  mx_mesh_free(&T);
}

/* The k-th allocation of the split failing, for every k: MX_ENOMEM and
 * nothing returned, then the split again whole. */
static void alloc_failures(const mx_mesh_arrays *a) {
  mx_mesh M;
  memset(&M, 0, sizeof M);
  M.nnodes = a->nnodes, M.ncells = a->nelements;
  M.xyz = (double *)a->xyz, M.type = (uint8_t *)a->type, M.conn = (uint32_t *)a->conn;
  M.level = (uint8_t *)a->level, M.leaf = (uint32_t *)a->leaf, M.jens = (float *)a->jens;
  mx_tet_split_stats s;
  mx_mesh T;
  uint32_t *parent = NULL;
  mx_alloc_fail_countdown(-1);
  CHECK(mx_mesh_split_tets(&M, &T, &parent, &s) == MX_OK);
  const long n = mx_alloc_count();
  mx_alloc_fail_countdown(0);
  mx_mesh_free(&T);
  mx_free_array(parent);
  size_t wrong = 0;
  for (long k = 1; k <= n; k++) {
    mx_alloc_fail_countdown(k);
    const int st = mx_mesh_split_tets(&M, &T, &parent, &s);
    mx_alloc_fail_countdown(0);
    wrong += st != MX_ENOMEM || T.xyz || T.conn || parent;
    if (!st) mx_mesh_free(&T), mx_free_array(parent);
  }
  CHECK(n >= 10 && wrong == 0);
  CHECK(mx_mesh_split_tets(&M, &T, &parent, &s) == MX_OK && T.ncells == s.tets);
  mx_mesh_free(&T);
  mx_free_array(parent);
}

static void library(int level) {
  run r1, r2, mixed;
  CHECK(mesh_demo(level, 0, 1, &mixed) == MX_OK);
  char what[64];
  snprintf(what, sizeof what, "demo -s %d", level);
  check_split(&mixed.a, what);
  if (level == 3) alloc_failures(&mixed.a);
  CHECK(mesh_demo(level, 1, 1, &r1) == MX_OK);
  CHECK(mesh_demo(level, 1, 2, &r2) == MX_OK);
  const mx_mesh_arrays *a = &r1.a, *b = &r2.a;
  CHECK(a->by_type[MX_TET] == a->nelements && a->invalid == 0 && a->jens_min >= 1e-6);
  /* the same bytes for 1 and 2 threads */
  CHECK(a->nnodes == b->nnodes && a->nelements == b->nelements);
  if (a->nnodes == b->nnodes && a->nelements == b->nelements) {
    CHECK(memcmp(a->xyz, b->xyz, 3 * a->nnodes * sizeof *a->xyz) == 0);
    CHECK(memcmp(a->conn, b->conn, 8 * a->nelements * sizeof *a->conn) == 0);
    CHECK(memcmp(a->leaf, b->leaf, a->nelements * sizeof *a->leaf) == 0);
    CHECK(memcmp(a->jens, b->jens, a->nelements * sizeof *a->jens) == 0);
    CHECK(memcmp(a->boundary, b->boundary, a->nnodes) == 0);
  }
  /* the same octree (no repair round for the split here): the mesher's
   * tetrahedra are the kernel's on the mixed mesh, the node arrays extend
   * the mixed mesh's */
  if (a->nleaves == mixed.a.nleaves) {
    CHECK(a->nnodes >= mixed.a.nnodes);
    CHECK(memcmp(a->xyz, mixed.a.xyz, 3 * mixed.a.nnodes * sizeof *a->xyz) == 0);
    CHECK(memcmp(a->boundary, mixed.a.boundary, mixed.a.nnodes) == 0);
  }
  /* refine by tetrahedron indices: the first and the last tetrahedron's
   * leaves split, meshed again, still tetrahedra */
  const size_t leaves = a->nleaves;
  const uint64_t list[2] = {0, a->nelements - 1};
  CHECK(mx_mesher_refine_elements(r1.m, list, 2) == MX_OK);
  mx_mesh_arrays c;
  CHECK(mx_mesher_mesh_arrays(r1.m, &c) == MX_OK);
  CHECK(c.nleaves >= leaves + 7); /* a leaf at least into eight */
  CHECK(c.by_type[MX_TET] == c.nelements && c.invalid == 0);
  check_split(&c, "refined (tetrahedra kept)");
  mx_mesher_free(r1.m);
  mx_mesher_free(r2.m);
  mx_mesher_free(mixed.m);
}

int main(void) {
  single_elements();
  library(3);
  library(4);
  TEST_DONE();
}
