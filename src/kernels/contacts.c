/* The mesher's own contact search (kernels/contacts.h): surface nodes lying
 * on an element with a surface face that they are not a node of.
 *
 * Candidates come from the octree's lattice: each element with a surface
 * face is filed in the cells of one level of the lattice that its bounding
 * box meets -- its leaf's level, or, when the boundary stage stretched it
 * beyond its leaf, the coarser level whose cells are twice its size if
 * that files it in fewer cells. A cell is named by the lattice key of its
 * lowest corner (mx_lattice_key, the keys of the mesh's nodes), and each
 * occupied level has a key index (soa/key_index.h) from a cell's key to its
 * run of elements, each with its box padded by the tolerance. A surface
 * node then looks up, on every occupied level, the cells within the
 * level's reach of it (its own cell, unless it lies that close to a cell
 * boundary), and tests the elements whose padded box holds it.
 *
 * The test (lies_on) is the definition of contacts.h: within tol (1e-9)
 * times half the element's largest extent of a face (quads: the four
 * triangles from its edges to its centroid), measured with the closest
 * points of geom/distance.h in coordinates relative to the element's lowest
 * corner; a node at exactly the point of one of the element's nodes is a
 * duplicate, not a contact. The checker (src/verify) searches the same
 * contacts with code of its own; tests/test_contacts.c compares the two. */
#include "base/cancel.h"
#include "kernels/contacts.h"

#include <math.h>
#include <string.h>

#include "base/common.h"
#include "base/morton.h"
#include "base/scan.h"
#include "geom/distance.h"
#include "kernels/boundary.h"
#include "soa/key_index.h"
#include "soa/mesh.h"

enum { CHUNK = 16384, NLEV = MX_MAX_LEVEL + 1 };

/* The relative tolerance of a contact (the checker's default hang_tol). */
static const double contact_tol = 1e-9;

/* 1 when a face of element c has surface nodes only: a face that can be on
 * the boundary (one with an inside node is not: the inside nodes off the
 * surface are interior, and those the lattice puts exactly on a flat part
 * of the surface were never moved, so the transition patterns' conformity
 * holds for them). */
int mx_surface_face(const mx_mesh *M, const uint8_t *states, size_t c) {
  const int t = M->type[c];
  const uint32_t *row = M->conn + 8 * c;
  uint32_t out = 0;
  for (int j = 0; j < mx_cell_nodes[t]; j++) out |= (uint32_t)(states[row[j]] == MX_NODE_OUTSIDE) << j;
  if (__builtin_popcount(out) < 3) return 0;
  for (int f = 0; f < mx_cell_nfaces[t]; f++) {
    const int8_t *fv = mx_cell_faces[t][f];
    uint32_t need = 0;
    for (int k = 0; k < 4 && fv[k] >= 0; k++) need |= 1u << fv[k];
    if ((out & need) == need) return 1;
  }
  return 0;
}

/* ---- the test of one node against one element ----------------------------- */

/* Whether p is within d (d2 = d * d) of the triangle a-b-c: its box, the
 * distance to its plane, then the closest point. */
static int within_triangle(const double p[3], const double *a, const double *b,
                           const double *c, double d, double d2) {
  double t[9];
  for (int x = 0; x < 3; x++) {
    if (p[x] < mx_min(a[x], mx_min(b[x], c[x])) - d || p[x] > mx_max(a[x], mx_max(b[x], c[x])) + d)
      return 0;
    t[x] = a[x];
    t[3 + x] = b[x];
    t[6 + x] = c[x];
  }
  const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
  const double w[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
  const double n[3] = {u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2],
                       u[0] * w[1] - u[1] * w[0]};
  const double nn = n[0] * n[0] + n[1] * n[1] + n[2] * n[2];
  const double h = n[0] * (p[0] - a[0]) + n[1] * (p[1] - a[1]) + n[2] * (p[2] - a[2]);
  if (nn > 0.0 && h * h > 1.0000001 * d2 * nn) return 0; /* clearly off its plane */
  double q[3];
  return mx_closest_on_triangle(t, p, q) <= d2;
}

/* 1 when the point p of node v lies on a face of element c (see the head of
 * the file); 0 when not, when v is one of its nodes, or p exactly one of
 * their points. */
static int lies_on(const mx_mesh *M, size_t c, uint32_t v, const double p[3]) {
  const int t = M->type[c], nn = mx_cell_nodes[t];
  const uint32_t *row = M->conn + 8 * c;
  /* v's own elements first, from the ids alone (most of the elements a
   * node's cells give: their boxes hold it), before any coordinate */
  for (int j = 0; j < nn; j++)
    if (row[j] == v) return 0;
  double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
  for (int j = 0; j < nn; j++) {
    const double *P = M->xyz + 3 * (size_t)row[j];
    if (P[0] == p[0] && P[1] == p[1] && P[2] == p[2]) return 0; /* a duplicate */
    for (int a = 0; a < 3; a++) {
      lo[a] = mx_min(lo[a], P[a]);
      hi[a] = mx_max(hi[a], P[a]);
    }
  }
  const double ext = mx_max(hi[0] - lo[0], mx_max(hi[1] - lo[1], hi[2] - lo[2]));
  if (!(ext >= 0x1p-1000)) return 0; /* one point, or too small to measure */
  const double d = contact_tol * (0.5 * ext), d2 = d * d;
  double q[8][3], r[3];
  for (int j = 0; j < nn; j++)
    for (int a = 0; a < 3; a++) q[j][a] = M->xyz[3 * (size_t)row[j] + (size_t)a] - lo[a];
  for (int a = 0; a < 3; a++) r[a] = p[a] - lo[a];
  for (int f = 0; f < mx_cell_nfaces[t]; f++) {
    const int8_t *fv = mx_cell_faces[t][f];
    if (fv[3] < 0) {
      if (within_triangle(r, q[fv[0]], q[fv[1]], q[fv[2]], d, d2)) return 1;
      continue;
    }
    double mid[3];
    int near = 1;
    for (int a = 0; a < 3; a++) {
      const double x0 = q[fv[0]][a], x1 = q[fv[1]][a], x2 = q[fv[2]][a], x3 = q[fv[3]][a];
      mid[a] = 0.25 * (x0 + x1 + x2 + x3);
      if (r[a] < mx_min(mx_min(x0, x1), mx_min(x2, x3)) - d ||
          r[a] > mx_max(mx_max(x0, x1), mx_max(x2, x3)) + d)
        near = 0;
    }
    for (int k = 0; near && k < 4; k++)
      if (within_triangle(r, q[fv[k]], q[fv[(k + 1) & 3]], mid, d, d2)) return 1;
  }
  return 0;
}

/* ---- the elements filed in lattice cells ---------------------------------- */

/* An element filed in a cell: its padded box relative to the cell's lowest
 * corner, in cell sides, rounded outwards to floats, for a first test. */
typedef struct {
  float lo[3], hi[3];
  uint32_t elem; /* the element id */
} filed;

typedef struct {
  const mx_grid *G;
  uint32_t levels;       /* bit l: some element filed at level l */
  double reach[NLEV];    /* per level: how far around a node to look, in
                          * lattice units */
  uint64_t *ukey[NLEV];  /* per level: the distinct cell keys, ascending */
  uint32_t *first[NLEV]; /* per level: a cell's first entry (nu + 1) */
  mx_key_index index[NLEV];
  filed *ent;            /* the entries, by level then cell */
} lattice_cells;

static void lattice_cells_free(lattice_cells *L) {
  mx_free(L->ent);
  for (int l = 0; l < NLEV; l++) {
    mx_free(L->ukey[l]);
    mx_free(L->first[l]);
    if (L->index[l].slot) mx_key_index_free(&L->index[l]);
  }
}

/* The lattice coordinate of x along axis a (in finest-lattice units; a
 * monotonic function of x). */
static inline double lattice_coord(const mx_grid *G, double x, int a) {
  return (x - G->origin[a]) / G->unit;
}

/* The cell of level l holding lattice coordinate u along axis a, clamped to
 * the grid (a monotonic function of u). */
/* 2^e, |e| <= MX_MAX_LEVEL (exact). */
static inline double pow2(int e) {
  return (double)(1ull << (e + MX_MAX_LEVEL)) * (1.0 / (double)(1u << MX_MAX_LEVEL));
}

static inline uint32_t cell_of(const mx_grid *G, double u, int a, int l) {
  const double f = floor(u * pow2(l - MX_MAX_LEVEL));
  const double top = (double)((uint32_t)G->dims[a] << l) - 1.0;
  if (!(f > 0.0)) return 0;
  return f > top ? (uint32_t)top : (uint32_t)f;
}

/* The margin of a cell, in its sides: an element is filed in the cells its
 * box meets once shrunk by it, so that a box on cell boundaries (up to
 * rounding) stays in its own cells; a node looks that much farther. */
#define CELL_MARGIN 0x1p-20

/* Lattice coordinate u relative to the lowest corner of cell c of level l,
 * in cell sides (a monotonic function of u). */
static inline double cell_rel(double u, uint32_t c, int l) {
  return (u - (double)c * pow2(MX_MAX_LEVEL - l)) * pow2(l - MX_MAX_LEVEL);
}

/* x rounded to a float below (above) it (a float ulp or two away at most). */
static inline float float_below(double x) {
  const float f = (float)x;
  return (double)f > x ? f - (fabsf(f) * 0x1p-23f + 0x1p-126f) : f;
}

static inline float float_above(double x) {
  const float f = (float)x;
  return (double)f < x ? f + (fabsf(f) * 0x1p-23f + 0x1p-126f) : f;
}

static inline uint64_t cell_key(const uint32_t c[3], int l) {
  const int s = MX_MAX_LEVEL - l;
  return mx_lattice_key(c[0] << s, c[1] << s, c[2] << s);
}

/* The cells c0..c1 of level l that the box ulo..uhi (lattice units) meets
 * once shrunk by CELL_MARGIN (a box thinner than twice the margin: its
 * middle); returns their number. */
static uint64_t cells_met(const mx_grid *G, const double ulo[3], const double uhi[3], int l,
                          uint32_t c0[3], uint32_t c1[3]) {
  const double margin = CELL_MARGIN * pow2(MX_MAX_LEVEL - l);
  uint64_t k = 1;
  for (int a = 0; a < 3; a++) {
    double x0 = ulo[a] + margin, x1 = uhi[a] - margin;
    if (x0 > x1) x0 = x1 = 0.5 * (ulo[a] + uhi[a]);
    c0[a] = cell_of(G, x0, a, l);
    c1[a] = cell_of(G, x1, a, l);
    k *= c1[a] - c0[a] + 1;
  }
  return k;
}

/* Element c: its level -- its leaf's, or the coarser one whose cells are
 * at least twice as large as its box (the boundary stage may have stretched
 * it beyond its leaf), whichever files it in fewer cells --, the cells c0..c1
 * of that level its box meets (cells_met), its box padded so as to hold
 * every point lies_on accepts (the tolerance twice, and the rounding of the
 * relative coordinates) in lattice units, and the largest pad in lattice
 * units. */
/* Element c's box (lo, then hi). */
static void element_box(const mx_mesh *M, size_t c, double b[6]) {
  const int t = M->type[c];
  const uint32_t *row = M->conn + 8 * c;
  double *lo = b, *hi = b + 3;
  for (int a = 0; a < 3; a++) {
    lo[a] = INFINITY;
    hi[a] = -INFINITY;
  }
  for (int j = 0; j < mx_cell_nodes[t]; j++)
    for (int a = 0; a < 3; a++) {
      lo[a] = mx_min(lo[a], M->xyz[3 * (size_t)row[j] + (size_t)a]);
      hi[a] = mx_max(hi[a], M->xyz[3 * (size_t)row[j] + (size_t)a]);
    }
}

/* The pad of the box (lo, hi) along axis a: the tolerance twice and the
 * rounding of the relative coordinates. */
static inline double box_pad(const double *lo, const double *hi, int a) {
  const double ext = mx_max(hi[0] - lo[0], mx_max(hi[1] - lo[1], hi[2] - lo[2]));
  return 2.0 * contact_tol * ext + (fabs(lo[a]) + fabs(hi[a])) * 0x1p-40 + 0x1p-1000;
}

void mx_contact_box(const mx_mesh *M, size_t c, double box[6]) {
  double b[6];
  element_box(M, c, b);
  for (int a = 0; a < 3; a++) {
    const double pad = box_pad(b, b + 3, a);
    box[a] = b[a] - pad;
    box[3 + a] = b[3 + a] + pad;
  }
}

static int element_cells(const mx_grid *G, const mx_mesh *M, uint32_t c, double b[6],
                         uint32_t c0[3], uint32_t c1[3], double *pad_max) {
  double *lo = b, *hi = b + 3;
  element_box(M, c, b);
  double ulo[3], uhi[3], span = 0.0;
  for (int a = 0; a < 3; a++) {
    ulo[a] = lattice_coord(G, lo[a], a);
    uhi[a] = lattice_coord(G, hi[a], a);
    span = mx_max(span, uhi[a] - ulo[a]);
  }
  /* the leaf's level, or the coarser one whose cells are at least twice as
   * large as the box, whichever files it in fewer cells */
  const int leaf = M->level && M->level[c] < MX_MAX_LEVEL ? M->level[c] : MX_MAX_LEVEL;
  int fit = leaf;
  while (fit > 0 && !(pow2(MX_MAX_LEVEL - fit) >= 2.0 * span)) fit--;
  int l = leaf;
  const uint64_t k = cells_met(G, ulo, uhi, leaf, c0, c1);
  if (fit != leaf) {
    uint32_t f0[3], f1[3];
    if (cells_met(G, ulo, uhi, fit, f0, f1) < k) {
      l = fit;
      memcpy(c0, f0, sizeof f0);
      memcpy(c1, f1, sizeof f1);
    }
  }
  double pm = 0.0, pads[3];
  for (int a = 0; a < 3; a++) pads[a] = box_pad(lo, hi, a); /* before lo, hi change */
  for (int a = 0; a < 3; a++) {
    const double pad = pads[a];
    lo[a] = lattice_coord(G, lo[a] - pad, a);
    hi[a] = lattice_coord(G, hi[a] + pad, a);
    pm = mx_max(pm, pad);
  }
  *pad_max = pm / G->unit;
  return l;
}

/* Files the n elements of cand, grouped by level, sorted by cell. */
static int lattice_cells_build(lattice_cells *L, const mx_grid *G, const mx_mesh *M,
                               const uint32_t *cand, size_t n) {
  memset(L, 0, sizeof *L);
  L->G = G;
  uint8_t *lev = mx_alloc(n + 1);
  uint64_t *cnt = mx_alloc((n + 1) * sizeof *cnt);
  uint32_t *order = mx_alloc((n + 1) * sizeof *order);
  uint32_t *cells = mx_alloc((6 * n + 1) * sizeof *cells);
  double *box = mx_alloc((6 * n + 1) * sizeof *box), *pad = mx_alloc((n + 1) * sizeof *pad);
  if (!lev || !cnt || !order || !cells || !box || !pad) {
    mx_free(lev);
    mx_free(cnt);
    mx_free(order);
    mx_free(cells);
    mx_free(box);
    mx_free(pad);
    return MX_ENOMEM;
  }
#pragma omp parallel for schedule(static) if (n > CHUNK)
  for (size_t i = 0; i < n; i++)
    lev[i] = (uint8_t)element_cells(G, M, cand[i], box + 6 * i, cells + 6 * i, cells + 6 * i + 3,
                                    &pad[i]);
  /* the elements by level (a counting sort), then their entries in that
   * order: the entries of a level are contiguous. A node looks around
   * itself as far as twice the largest pad of the level and twice the
   * margin, in lattice units. */
  size_t per[NLEV + 1] = {0};
  for (size_t i = 0; i < n; i++) {
    per[lev[i] + 1]++;
    L->reach[lev[i]] = mx_max(L->reach[lev[i]], 2.0 * pad[i]);
  }
  for (int l = 0; l < NLEV; l++) L->reach[l] += 2.0 * CELL_MARGIN * pow2(MX_MAX_LEVEL - l);
  for (int l = 0; l < NLEV; l++) per[l + 1] += per[l];
  for (size_t i = 0; i < n; i++) order[per[lev[i]]++] = (uint32_t)i;
#pragma omp parallel for schedule(static) if (n > CHUNK)
  for (size_t k = 0; k < n; k++) {
    const uint32_t *c = cells + 6 * (size_t)order[k];
    cnt[k] = (uint64_t)(c[3] - c[0] + 1) * (c[4] - c[1] + 1) * (c[5] - c[2] + 1);
  }
  cnt[n] = 0;
  const uint64_t total = mx_scan_u64(cnt, n + 1);
  int st = total < UINT32_MAX ? MX_OK : MX_ENOMEM;
  uint64_t *key = NULL;
  uint32_t *idx = NULL;
  if (st == MX_OK) {
    key = mx_alloc((total + 1) * sizeof *key);
    idx = mx_alloc((total + 1) * sizeof *idx);
    L->ent = mx_alloc((total + 1) * sizeof *L->ent);
    if (!key || !idx || !L->ent) st = MX_ENOMEM;
  }
  /* the entries' cells and elements (by level, then element), sorted by
   * cell below; an entry is made from them after the sort (the element's
   * box, the cell from its key), not copied there */
  if (st == MX_OK) {
#pragma omp parallel for schedule(static) if (n > CHUNK)
    for (size_t k = 0; k < n; k++) {
      const uint32_t i = order[k];
      const uint32_t *c0 = cells + 6 * (size_t)i, *c1 = c0 + 3;
      const int l = lev[i];
      uint32_t c[3];
      size_t e = (size_t)cnt[k];
      for (c[2] = c0[2]; c[2] <= c1[2]; c[2]++)
        for (c[1] = c0[1]; c[1] <= c1[1]; c[1]++)
          for (c[0] = c0[0]; c[0] <= c1[0]; c[0]++, e++) {
            key[e] = cell_key(c, l);
            idx[e] = i;
          }
    }
  }
  mx_free(cells);
  mx_free(pad);
  cells = NULL;
  pad = NULL;
  if (st == MX_OK) {
    /* per level: entries sorted by cell (stable: an element's entries in
     * element order, as they were made; the elements come in the Morton
     * order, each mostly in the cell of its leaf's: the keys are mostly in
     * order), the distinct cells indexed */
    size_t k = 0;
    for (int l = 0; l < NLEV && st == MX_OK; l++) {
      const size_t k0 = k;
      while (k < n && lev[order[k]] == l) k++;
      const uint32_t e0 = (uint32_t)cnt[k0], e1 = (uint32_t)cnt[k];
      if (e1 == e0) continue;
      L->levels |= 1u << l;
      if (mx_sort_u64_mostly_sorted(key + e0, idx + e0, e1 - e0) != MX_OK) {
        st = MX_ENOMEM;
        break;
      }
      const int sh = MX_MAX_LEVEL - l;
#pragma omp parallel for schedule(static) if (e1 - e0 > CHUNK)
      for (size_t e = e0; e < e1; e++) {
        const uint32_t i = idx[e];
        const double *b = box + 6 * (size_t)i;
        uint32_t c[3];
        mx_morton_decode(key[e], c);
        for (int a = 0; a < 3; a++) {
          c[a] >>= sh;
          L->ent[e].lo[a] = float_below(cell_rel(b[a], c[a], l));
          L->ent[e].hi[a] = float_above(cell_rel(b[3 + a], c[a], l));
        }
        L->ent[e].elem = cand[i];
      }
      size_t nu = 0;
      for (uint32_t e = e0; e < e1; e++) nu += e == e0 || key[e] != key[e - 1];
      L->ukey[l] = mx_alloc((nu + 1) * sizeof *L->ukey[l]);
      L->first[l] = mx_alloc((nu + 1) * sizeof *L->first[l]);
      if (!L->ukey[l] || !L->first[l]) {
        st = MX_ENOMEM;
        break;
      }
      nu = 0;
      for (uint32_t e = e0; e < e1; e++)
        if (e == e0 || key[e] != key[e - 1]) {
          L->ukey[l][nu] = key[e];
          L->first[l][nu++] = e;
        }
      L->first[l][nu] = e1;
      st = mx_key_index_build(&L->index[l], L->ukey[l], nu, 3 * (MX_MAX_LEVEL - l));
    }
  }
  mx_free(key);
  mx_free(idx);
  mx_free(lev);
  mx_free(cnt);
  mx_free(order);
  mx_free(cells);
  mx_free(box);
  mx_free(pad);
  return st;
}

/* 1 when the point of node v lies on some filed element; flags them in
 * elem_hit (when not NULL). On each occupied level, the cells within the
 * level's reach of the point (one, unless it is that close to a cell
 * boundary): an element whose padded box holds the point was filed in one
 * of them. */
static int node_contacts(const lattice_cells *L, const mx_mesh *M, uint32_t v,
                         uint8_t *elem_hit) {
  const double *p = M->xyz + 3 * (size_t)v;
  double u[3];
  for (int a = 0; a < 3; a++) u[a] = lattice_coord(L->G, p[a], a);
  uint32_t q0[NLEV][3], q1[NLEV][3];
  uint64_t key[NLEV];
  int lv[NLEV], nl = 0;
  for (int l = 0; l < NLEV; l++) {
    if (!(L->levels >> l & 1)) continue;
    int one = 1;
    for (int a = 0; a < 3; a++) {
      q0[nl][a] = cell_of(L->G, u[a] - L->reach[l], a, l);
      q1[nl][a] = cell_of(L->G, u[a] + L->reach[l], a, l);
      one &= q0[nl][a] == q1[nl][a];
    }
    key[nl] = one ? cell_key(q0[nl], l) : UINT64_MAX;
    if (one) mx_key_index_prefetch(&L->index[l], key[nl]);
    lv[nl++] = l;
  }
  int hit = 0;
  for (int k = 0; k < nl; k++) {
    const int l = lv[k];
    uint32_t c[3];
    for (c[2] = q0[k][2]; c[2] <= q1[k][2]; c[2]++)
      for (c[1] = q0[k][1]; c[1] <= q1[k][1]; c[1]++)
        for (c[0] = q0[k][0]; c[0] <= q1[k][0]; c[0]++) {
          const uint32_t id =
              mx_key_index_find(&L->index[l], key[k] != UINT64_MAX ? key[k] : cell_key(c, l));
          if (id == UINT32_MAX) continue;
          /* the point in floats, as the boxes: rounding to the nearest
           * float keeps a point within float bounds within them (a point
           * just beyond may pass: lies_on decides) */
          float r[3];
          for (int a = 0; a < 3; a++) r[a] = (float)cell_rel(u[a], c[a], l);
          for (uint32_t e = L->first[l][id]; e < L->first[l][id + 1]; e++) {
            const filed *f = &L->ent[e];
            if ((r[0] < f->lo[0]) | (r[0] > f->hi[0]) | (r[1] < f->lo[1]) | (r[1] > f->hi[1]) |
                (r[2] < f->lo[2]) | (r[2] > f->hi[2]))
              continue;
            if (!lies_on(M, f->elem, v, p)) continue;
            hit = 1;
            if (elem_hit) __atomic_store_n(&elem_hit[f->elem], 1, __ATOMIC_RELAXED);
          }
        }
  }
  return hit;
}

/* ---- the search ------------------------------------------------------------ */

/* 1 when the padded box of element c meets the region R (lo, hi). */
static int box_meets_region(const mx_mesh *M, size_t c, const double *R) {
  double b[6];
  mx_contact_box(M, c, b);
  for (int a = 0; a < 3; a++)
    if (!(b[a] <= R[3 + a] && b[3 + a] >= R[a])) return 0;
  return 1;
}

static int in_region(const double *p, const double *R) {
  return p[0] >= R[0] && p[0] <= R[3] && p[1] >= R[1] && p[1] <= R[4] && p[2] >= R[2] &&
         p[2] <= R[5];
}

int mx_find_contacts(const mx_mesh *M, const mx_grid *G, const uint8_t *states,
                     uint8_t *elem_flag, mx_contacts *out) {
  return mx_find_contacts_in(M, G, states, NULL, elem_flag, out);
}

int mx_find_contacts_in(const mx_mesh *M, const mx_grid *G, const uint8_t *states,
                        const double *region, uint8_t *elem_flag, mx_contacts *out) {
  memset(out, 0, sizeof *out);
  out->first_node = UINT32_MAX;
  const size_t nc = M->ncells, nn = M->nnodes;
  if (!nc || !nn || !states || !(G->unit > 0.0)) {
    if (elem_flag) memset(elem_flag, 0, nc);
    return nc && nn && states ? MX_EINPUT : MX_OK;
  }
  /* the elements with a surface face, in id order: flagged in ehit and
   * counted per chunk (the one pass over the rows), then listed from the
   * flags, which go back to 0 for the search */
  const size_t nchunks = (nc + CHUNK - 1) / CHUNK;
  uint64_t *cnt = mx_calloc((nchunks + 1) * sizeof *cnt);
  uint8_t *hit = mx_calloc(nn + 1);
  uint8_t *ehit = elem_flag ? elem_flag : mx_alloc(nc + 1);
  if (!cnt || !hit || !ehit) {
    mx_free(cnt);
    mx_free(hit);
    if (ehit != elem_flag) mx_free(ehit);
    if (elem_flag) memset(elem_flag, 0, nc);
    return MX_ENOMEM;
  }
#pragma omp parallel for schedule(static)
  for (size_t k = 0; k < nchunks; k++) {
    const size_t end = (k + 1) * CHUNK < nc ? (k + 1) * CHUNK : nc;
    uint64_t n = 0;
    for (size_t c = k * CHUNK; c < end; c++) {
      const int s = mx_surface_face(M, states, c) && (!region || box_meets_region(M, c, region));
      ehit[c] = (uint8_t)s;
      n += (uint64_t)s;
    }
    cnt[k] = n;
  }
  const uint64_t nl = mx_scan_u64(cnt, nchunks + 1);
  uint32_t *list = mx_alloc((nl + 1) * sizeof *list);
  if (!list) {
    mx_free(cnt);
    mx_free(hit);
    if (ehit != elem_flag) mx_free(ehit);
    if (elem_flag) memset(elem_flag, 0, nc);
    return MX_ENOMEM;
  }
#pragma omp parallel for schedule(static)
  for (size_t k = 0; k < nchunks; k++) {
    const size_t end = (k + 1) * CHUNK < nc ? (k + 1) * CHUNK : nc;
    uint64_t at = cnt[k];
    for (size_t c = k * CHUNK; c < end; c++) {
      if (ehit[c]) list[at++] = (uint32_t)c;
      ehit[c] = 0;
    }
  }
  mx_free(cnt);
  /* the surface nodes against the elements with a surface face */
  size_t found = 0;
  int st = MX_OK;
  if (nl) {
    lattice_cells L;
    st = lattice_cells_build(&L, G, M, list, (size_t)nl);
    atomic_int *cf = mx_cancel_flag; /* base/cancel.h: the longest loop */
    if (st == MX_OK) {
#pragma omp parallel for schedule(dynamic, 2048) reduction(+ : found) if (nn > CHUNK)
      for (size_t v = 0; v < nn; v++) {
        if (states[v] != MX_NODE_OUTSIDE || mx_cancel_seen(cf)) continue;
        if (region && !in_region(M->xyz + 3 * v, region)) continue;
        if (node_contacts(&L, M, (uint32_t)v, ehit)) {
          hit[v] = 1;
          found++;
        }
      }
    }
    lattice_cells_free(&L);
    if (st == MX_OK) st = mx_cancel_check();
  }
  mx_free(list);
  if (st == MX_OK && found) {
    out->nodes = found;
    for (size_t v = 0; v < nn; v++)
      if (hit[v]) {
        out->first_node = (uint32_t)v;
        memcpy(out->first, M->xyz + 3 * v, sizeof out->first);
        break;
      }
    size_t ne = 0;
#pragma omp parallel for schedule(static) reduction(+ : ne)
    for (size_t c = 0; c < nc; c++) {
      int s = ehit[c] != 0;
      for (int j = 0; j < mx_cell_nodes[M->type[c]]; j++) s |= hit[M->conn[8 * c + j]];
      ehit[c] = (uint8_t)s;
      ne += (size_t)s;
    }
    out->elements = ne;
  }
  if (ehit != elem_flag) mx_free(ehit);
  mx_free(hit);
  return st;
}
