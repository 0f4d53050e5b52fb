/* Pass 6 of the checker, geometric hanging nodes (contacts): nodes lying,
 * within hang_tol times the element's size, on a face, an edge or at a
 * vertex of an element they are not a node of (check.h). The nodes of the
 * faces used once are compared with the elements that have such a face,
 * through a multi-level grid of the elements' bounding boxes over the unit
 * coordinates of the nodes' box: O(n) lookups, O(n log n) for the sort of
 * the cells. The same search alone is mx_check_contacts. This is the
 * checker's own search; the mesher finds its contacts with its own code
 * (kernels/contacts.c), and tests/test_contacts.c compares the two. */
#include "verify/check_passes.h"

#include "base/scan.h"
#include "soa/mesh.h"

/* The elements to compare with go into a multi-level grid over the unit
 * coordinates (cells of level l have side 2^-l): each into every cell its
 * padded box meets on the level above the finest one whose cells are at
 * least as large as the box -- at most 2 per axis. A point in the box lies in one of those
 * cells (the cell of a coordinate is a monotonic function of it), so a
 * node looks at one cell per occupied level. Entries are sorted by cell
 * (radix sort); a hash of the cells gives their runs. Each entry keeps the
 * box in single precision, relative to its cell in units of the cell side
 * (rounded outwards), for a cheap first test. */

enum { GLEVELS = 21 }; /* 3 * 21 + 1 bits of key */

typedef struct {
  uint64_t key; /* 0: empty */
  uint32_t beg, end;
} gcell;

typedef struct {
  ubox U;
  double tol;
  uint32_t *elem; /* entries, sorted by cell */
  float *box;     /* 6 per entry */
  gcell *tab;
  uint64_t mask;
  uint32_t levels; /* bit l: some element at level l */
} ggrid;

static void ggrid_free(ggrid *g) {
  mx_free(g->elem);
  mx_free(g->box);
  mx_free(g->tab);
}

static inline uint64_t gkey(int lev, const uint32_t c[3]) {
  return (uint64_t)1 << (3 * lev) | (uint64_t)c[0] << (2 * lev) |
         (uint64_t)c[1] << lev | c[2];
}

static inline uint32_t gcoord(double u, int lev) {
  const double f = floor(u * (double)(1u << lev));
  const double top = (double)((1u << lev) - 1);
  if (!(f > 0.0)) return 0;
  return f > top ? (uint32_t)top : (uint32_t)f;
}

/* The padded unit box of element c and its level and low cell. */
static void elem_gbox(const mx_mesh_data *m, const ggrid *g, size_t c,
                      double lo[3], double hi[3], int *lev, uint32_t cell[3]) {
  const int nn = mx_cell_nodes[m->type[c]];
  const uint32_t *row = m->conn + 8 * c;
  for (int a = 0; a < 3; a++) {
    lo[a] = INFINITY;
    hi[a] = -INFINITY;
  }
  for (int j = 0; j < nn; j++) {
    const double *p = m->xyz + 3 * (size_t)row[j];
    for (int a = 0; a < 3; a++) {
      const double u = ucoord(&g->U, p[a], a);
      lo[a] = mx_min(lo[a], u);
      hi[a] = mx_max(hi[a], u);
    }
  }
  double size = 0.0;
  for (int a = 0; a < 3; a++) size = mx_max(size, hi[a] - lo[a]);
  /* the exact test's tolerance is tol * size (with rounding: 2x pad) */
  const double pad = 2.0 * g->tol * size + 0x1p-60;
  for (int a = 0; a < 3; a++) {
    lo[a] -= pad;
    hi[a] += pad;
  }
  const double span = (size + 2.0 * pad) * (1.0 + 1e-12);
  int l = GLEVELS;
  if (span > 0.0) {
    int e;
    const double f = frexp(span, &e); /* span = f 2^e, f in [0.5, 1) */
    l = f == 0.5 ? 1 - e : -e;        /* largest l with 2^-l >= span */
    l -= 2;
    l = l < 0 ? 0 : l > GLEVELS ? GLEVELS : l;
  }
  *lev = l;
  for (int a = 0; a < 3; a++) cell[a] = gcoord(lo[a], l);
}

/* x rounded to a float below (above) it: the nearest float is within half
 * a float ulp, less than |x| 2^-23 (+ a tiny term for x near 0). */
static inline float f_down(double x) {
  return (float)(x - fabs(x) * 0x1p-23 - 0x1p-100);
}

static inline float f_up(double x) {
  return (float)(x + fabs(x) * 0x1p-23 + 0x1p-100);
}

static inline uint64_t gslot_of(uint64_t key, uint64_t mask) {
  return mix64(key) & mask;
}

/* Files the n elements of list, each in every cell its box meets at its
 * level (at most 2 per axis). */
static int ggrid_build(ggrid *g, const mx_mesh_data *m, const ubox *U,
                       double tol, const uint32_t *list, size_t n) {
  memset(g, 0, sizeof *g);
  g->U = *U;
  g->tol = tol;
  uint64_t *off = mx_alloc((n + 1) * sizeof *off);
  double *ubx = mx_alloc((6 * n + 1) * sizeof *ubx); /* padded unit boxes */
  uint8_t *ulev = mx_alloc(n + 1);
  if (!off || !ubx || !ulev) {
    mx_free(off);
    mx_free(ubx);
    mx_free(ulev);
    return MX_ENOMEM;
  }
  off[n] = 0;
  uint32_t levels = 0;
#pragma omp parallel for schedule(static) reduction(| : levels) \
    if (n > SMALL)
  for (size_t i = 0; i < n; i++) {
    double *lo = ubx + 6 * i, *hi = lo + 3;
    int lev;
    uint32_t c0[3];
    elem_gbox(m, g, list[i], lo, hi, &lev, c0);
    uint64_t k = 1;
    for (int a = 0; a < 3; a++) k *= gcoord(hi[a], lev) - c0[a] + 1;
    off[i] = k;
    ulev[i] = (uint8_t)lev;
    levels |= 1u << lev;
  }
  g->levels = levels;
  const uint64_t total = mx_scan_u64(off, n + 1);
  if (total >= UINT32_MAX) {
    mx_free(off);
    mx_free(ubx);
    mx_free(ulev);
    mx_error(NULL, 0, "check: too many boundary elements");
    return MX_EINPUT;
  }
  const size_t ne = (size_t)total;
  uint64_t *key = mx_alloc((ne + 1) * sizeof *key);
  uint32_t *idx = mx_alloc((ne + 1) * sizeof *idx);
  uint32_t *eel = mx_alloc((ne + 1) * sizeof *eel);
  float *ebox = mx_alloc((6 * ne + 1) * sizeof *ebox);
  g->elem = mx_alloc((ne + 1) * sizeof *g->elem);
  g->box = mx_alloc((6 * ne + 1) * sizeof *g->box);
  int st = key && idx && eel && ebox && g->elem && g->box ? MX_OK : MX_ENOMEM;
  if (st == MX_OK) {
#pragma omp parallel for schedule(static) if (n > SMALL)
    for (size_t i = 0; i < n; i++) {
      const double *lo = ubx + 6 * i, *hi = lo + 3;
      const int lev = ulev[i];
      uint32_t c0[3], c1[3], c[3];
      for (int a = 0; a < 3; a++) {
        c0[a] = gcoord(lo[a], lev);
        c1[a] = gcoord(hi[a], lev);
      }
      const double sc = (double)(1u << lev);
      size_t k = (size_t)off[i];
      for (c[2] = c0[2]; c[2] <= c1[2]; c[2]++)
        for (c[1] = c0[1]; c[1] <= c1[1]; c[1]++)
          for (c[0] = c0[0]; c[0] <= c1[0]; c[0]++, k++) {
            key[k] = gkey(lev, c);
            idx[k] = (uint32_t)k;
            eel[k] = list[i];
            for (int a = 0; a < 3; a++) {
              ebox[6 * k + (size_t)a] = f_down(lo[a] * sc - (double)c[a]);
              ebox[6 * k + 3 + (size_t)a] = f_up(hi[a] * sc - (double)c[a]);
            }
          }
    }
    st = mx_sort_u64(key, idx, ne);
  }
  size_t runs = 0;
  if (st == MX_OK) {
    /* Boxes and elements in entry order; runs of equal keys: the cells. */
#pragma omp parallel for schedule(static) reduction(+ : runs) \
    if (ne > SMALL)
    for (size_t i = 0; i < ne; i++) {
      memcpy(g->box + 6 * i, ebox + 6 * (size_t)idx[i], 6 * sizeof *ebox);
      g->elem[i] = eel[idx[i]];
      runs += i == 0 || key[i] != key[i - 1];
    }
    uint64_t size = 16;
    while (size < 2 * (uint64_t)runs) size *= 2;
    g->mask = size - 1;
    g->tab = mx_calloc((size_t)size * sizeof *g->tab);
    if (!g->tab) st = MX_ENOMEM;
  }
  if (st == MX_OK) {
#pragma omp parallel for schedule(static) if (ne > SMALL)
    for (size_t i = 0; i < ne; i++) {
      if (i > 0 && key[i] == key[i - 1]) continue;
      size_t j = i + 1;
      while (j < ne && key[j] == key[i]) j++;
      for (uint64_t h = gslot_of(key[i], g->mask);; h = (h + 1) & g->mask) {
        uint64_t e = 0;
        if (__atomic_compare_exchange_n(&g->tab[h].key, &e, key[i], 0,
                                        __ATOMIC_ACQ_REL, __ATOMIC_ACQUIRE)) {
          g->tab[h].beg = (uint32_t)i;
          g->tab[h].end = (uint32_t)j;
          break;
        }
      }
    }
  }
  mx_free(off);
  mx_free(ubx);
  mx_free(ulev);
  mx_free(key);
  mx_free(idx);
  mx_free(eel);
  mx_free(ebox);
  return st;
}

static inline const gcell *ggrid_find(const ggrid *g, uint64_t key) {
  for (uint64_t h = gslot_of(key, g->mask);; h = (h + 1) & g->mask) {
    const gcell *c = &g->tab[h];
    if (c->key == key) return c;
    if (c->key == 0) return NULL;
  }
}

static inline double dist2(const double a[3], const double b[3]) {
  const double x = a[0] - b[0], y = a[1] - b[1], z = a[2] - b[2];
  return x * x + y * y + z * z;
}

static double point_segment_d2(const double p[3], const double a[3],
                               const double b[3]) {
  double d[3], ap[3];
  for (int x = 0; x < 3; x++) {
    d[x] = b[x] - a[x];
    ap[x] = p[x] - a[x];
  }
  const double dd = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
  double t = dd > 0.0 ? (ap[0] * d[0] + ap[1] * d[1] + ap[2] * d[2]) / dd : 0.0;
  t = t < 0.0 ? 0.0 : t > 1.0 ? 1.0 : t;
  double e2 = 0.0;
  for (int x = 0; x < 3; x++) {
    const double e = ap[x] - t * d[x];
    e2 += e * e;
  }
  return e2;
}

/* Whether p is within d (d2 = d * d) of the triangle a-b-c: its box, its
 * plane, then the exact distance. */
static int near_triangle(const double p[3], const double *a, const double *b,
                         const double *c, double d, double d2) {
  for (int x = 0; x < 3; x++) {
    const double lo = mx_min(a[x], mx_min(b[x], c[x])),
                 hi = mx_max(a[x], mx_max(b[x], c[x]));
    if (p[x] < lo - d || p[x] > hi + d) return 0;
  }
  double u[3], v[3], n[3];
  for (int x = 0; x < 3; x++) {
    u[x] = b[x] - a[x];
    v[x] = c[x] - a[x];
  }
  n[0] = u[1] * v[2] - u[2] * v[1];
  n[1] = u[2] * v[0] - u[0] * v[2];
  n[2] = u[0] * v[1] - u[1] * v[0];
  const double nn = n[0] * n[0] + n[1] * n[1] + n[2] * n[2];
  const double h = n[0] * (p[0] - a[0]) + n[1] * (p[1] - a[1]) +
                   n[2] * (p[2] - a[2]);
  if (nn > 0.0 && h * h > 1.0000001 * d2 * nn) return 0;
  return mx_ck_point_triangle_d2(p, a, b, c) <= d2;
}

/* Where the point p of node v lies on element c: 0 (nowhere, or v is one
 * of its nodes, or p is exactly one of its nodes' points), else
 * MX_CK_ON_* << 6 | local (see mx_check_hang; an edge a-b as 8 * a + b).
 * Works in the element's own frame, scaled by a power of two to [0, 1). */
static int on_element(const mx_mesh_data *m, size_t c, uint32_t v,
                      const double p[3], double tol) {
  const int t = m->type[c], nn = mx_cell_nodes[t];
  const uint32_t *row = m->conn + 8 * c;
  for (int j = 0; j < nn; j++)
    if (row[j] == v) return 0;
  const double *P[8];
  double l2[3] = {INFINITY, INFINITY, INFINITY},
         h2[3] = {-INFINITY, -INFINITY, -INFINITY};
  for (int j = 0; j < nn; j++) {
    P[j] = m->xyz + 3 * (size_t)row[j];
    if (same_point(P[j], p)) return 0; /* a duplicate node */
    for (int a = 0; a < 3; a++) {
      l2[a] = mx_min(l2[a], 0.5 * P[j][a]);
      h2[a] = mx_max(h2[a], 0.5 * P[j][a]);
    }
  }
  double h = 0.0;
  for (int a = 0; a < 3; a++) h = mx_max(h, h2[a] - l2[a]);
  if (!(h > 0.0)) return 0;
  int ex;
  frexp(h, &ex);
  if (ex < -1000) return 0; /* below 1e-300: nothing to measure */
  const double sc = ldexp(1.0, -ex);
  double q[8][3], qp[3];
  for (int j = 0; j < nn; j++)
    for (int a = 0; a < 3; a++) q[j][a] = (0.5 * P[j][a] - l2[a]) * sc;
  for (int a = 0; a < 3; a++) qp[a] = (0.5 * p[a] - l2[a]) * sc;
  const double d = tol * h * sc, d2 = d * d;
  for (int f = 0; f < mx_cell_nfaces[t]; f++) {
    const int8_t *fl = mx_cell_faces[t][f];
    const int n = fl[3] < 0 ? 3 : 4;
    int hit;
    if (n == 3) {
      hit = near_triangle(qp, q[fl[0]], q[fl[1]], q[fl[2]], d, d2);
    } else {
      double mid[3], lo[3], hi[3];
      for (int a = 0; a < 3; a++) {
        mid[a] = 0.25 * (q[fl[0]][a] + q[fl[1]][a] + q[fl[2]][a] +
                         q[fl[3]][a]);
        lo[a] = mx_min(mx_min(q[fl[0]][a], q[fl[1]][a]),
                       mx_min(q[fl[2]][a], q[fl[3]][a]));
        hi[a] = mx_max(mx_max(q[fl[0]][a], q[fl[1]][a]),
                       mx_max(q[fl[2]][a], q[fl[3]][a]));
      }
      int inbox = 1;
      for (int a = 0; a < 3; a++)
        if (qp[a] < lo[a] - d || qp[a] > hi[a] + d) inbox = 0;
      hit = 0;
      for (int k = 0; inbox && !hit && k < 4; k++)
        hit = near_triangle(qp, q[fl[k]], q[fl[(k + 1) % 4]], mid, d, d2);
    }
    if (!hit) continue;
    for (int k = 0; k < n; k++)
      if (dist2(qp, q[fl[k]]) <= d2) return MX_CK_ON_VERTEX << 6 | fl[k];
    for (int k = 0; k < n; k++) {
      const int a = fl[k], b = fl[(k + 1) % n];
      if (point_segment_d2(qp, q[a], q[b]) <= d2)
        return MX_CK_ON_EDGE << 6 | (a < b ? 8 * a + b : 8 * b + a);
    }
    return MX_CK_ON_FACE << 6 | f;
  }
  return 0;
}

/* The smallest element node v lies on (where it lies in *where), or
 * UINT32_MAX; when ef is not NULL, flags every element it lies on. */
static uint32_t node_query(const ggrid *g, const mx_mesh_data *m, size_t v,
                           uint8_t *ef, int *where) {
  const double *p = m->xyz + 3 * v;
  double u[3];
  for (int a = 0; a < 3; a++) u[a] = ucoord(&g->U, p[a], a);
  uint32_t best = UINT32_MAX;
  *where = 0;
  /* The cells to look at, one per occupied level, their slots prefetched:
   * the probes are independent cache misses. */
  uint64_t keys[GLEVELS + 1];
  uint8_t klev[GLEVELS + 1];
  int nk = 0;
  for (int lev = 0; lev <= GLEVELS; lev++) {
    if (!(g->levels >> lev & 1)) continue;
    uint32_t c0[3];
    for (int a = 0; a < 3; a++) c0[a] = gcoord(u[a], lev);
    keys[nk] = gkey(lev, c0);
    klev[nk] = (uint8_t)lev;
    __builtin_prefetch(&g->tab[gslot_of(keys[nk], g->mask)]);
    nk++;
  }
  const gcell *found_c[GLEVELS + 1];
  for (int k = 0; k < nk; k++) {
    found_c[k] = ggrid_find(g, keys[k]);
    if (found_c[k]) __builtin_prefetch(g->box + 6 * (size_t)found_c[k]->beg);
  }
  for (int k = 0; k < nk; k++) {
    const gcell *gc = found_c[k];
    if (!gc) continue;
    const int lev = klev[k];
    const double s = (double)(1u << lev);
    double ps[3];
    for (int a = 0; a < 3; a++) { /* the cell's coordinates from its key */
      const uint32_t ca =
          (uint32_t)(keys[k] >> ((2 - a) * lev)) & ((1u << lev) - 1);
      ps[a] = u[a] * s - (double)ca;
    }
    for (uint32_t i = gc->beg; i < gc->end; i++) {
      const float *b = g->box + 6 * (size_t)i;
      if (ps[0] < b[0] || ps[0] > b[3] || ps[1] < b[1] || ps[1] > b[4] ||
          ps[2] < b[2] || ps[2] > b[5])
        continue;
      const uint32_t e = g->elem[i];
      const int w = on_element(m, e, (uint32_t)v, p, g->tol);
      if (!w) continue;
      if (ef) eflag(ef, e, MX_CK_GEOM_HANGING);
      if (e < best) {
        best = e;
        *where = w;
      }
    }
  }
  return best;
}

/* Compares the nodes of faces used by one element (that are not exact
 * hanging nodes) with the elements that have such a face (see check.h);
 * flags the nodes found (F_GHANG) and the elements they lie on, counts
 * the nodes, and tells where the first MX_CHECK_SHOWN lie. */
int mx_ck_geometric_pass(const mx_mesh_data *m, const faces *F,
                          const ubox *U, uint8_t *flags, uint8_t *ef,
                          double tol, mx_check_report *r) {
  const size_t nc = m->ncells;
  if (nc == 0 || !U->ok || !(tol >= 0.0)) return MX_OK;
  /* the elements with a face used once, in index order */
  const size_t nchunks = (nc + CHUNK - 1) / CHUNK;
  uint64_t *cnt = mx_calloc((nchunks + 1) * sizeof *cnt);
  if (!cnt) return MX_ENOMEM;
#pragma omp parallel for schedule(static) if (nchunks > 1)
  for (size_t k = 0; k < nchunks; k++) {
    const size_t end = (k + 1) * CHUNK < nc ? (k + 1) * CHUNK : nc;
    uint64_t c0 = 0;
    for (size_t c = k * CHUNK; c < end; c++)
      for (int j = 0; j < nfaces[m->type[c]]; j++)
        if (F->use[6 * c + (size_t)j] == 1) {
          c0++;
          break;
        }
    cnt[k] = c0;
  }
  const uint64_t nl = mx_scan_u64(cnt, nchunks + 1);
  uint32_t *list = mx_alloc((nl + 1) * sizeof *list);
  if (!list) {
    mx_free(cnt);
    return MX_ENOMEM;
  }
#pragma omp parallel for schedule(static) if (nchunks > 1)
  for (size_t k = 0; k < nchunks; k++) {
    const size_t end = (k + 1) * CHUNK < nc ? (k + 1) * CHUNK : nc;
    uint64_t at = cnt[k];
    for (size_t c = k * CHUNK; c < end; c++)
      for (int j = 0; j < nfaces[m->type[c]]; j++)
        if (F->use[6 * c + (size_t)j] == 1) {
          list[at++] = (uint32_t)c;
          break;
        }
  }
  mx_free(cnt);
  ggrid g;
  int st = ggrid_build(&g, m, U, tol, list, (size_t)nl);
  mx_free(list);
  if (st != MX_OK) {
    ggrid_free(&g);
    return st;
  }
  size_t found = 0;
#pragma omp parallel for schedule(dynamic, 2048) reduction(+ : found) \
    if (m->nnodes > SMALL)
  for (size_t v = 0; v < m->nnodes; v++) {
    const uint8_t fl = flag_get(&flags[v]);
    if (!(fl & F_BND) || (fl & F_HANG)) continue;
    int where;
    if (node_query(&g, m, v, ef, &where) != UINT32_MAX) {
      flag_or(&flags[v], F_GHANG);
      found++;
    }
  }
  /* Where the first ones lie (asked again: rare). */
  for (size_t v = 0; v < m->nnodes && r->nshown < MX_CHECK_SHOWN && found;
       v++) {
    if (!(flags[v] & F_GHANG)) continue;
    int where = 0;
    const uint32_t e = node_query(&g, m, v, NULL, &where);
    mx_check_hang *h = &r->hang_at[r->nshown++];
    h->node = (uint32_t)v;
    h->element = e;
    h->on = where >> 6;
    h->local = where & 63;
    memcpy(h->xyz, m->xyz + 3 * v, sizeof h->xyz);
    const uint32_t *row = m->conn + 8 * (size_t)e;
    if (h->on == MX_CK_ON_VERTEX) {
      h->nverts = 1;
      h->verts[0] = row[h->local & 7];
    } else if (h->on == MX_CK_ON_EDGE) {
      h->nverts = 2;
      h->verts[0] = row[h->local >> 3];
      h->verts[1] = row[h->local & 7];
    } else {
      const int8_t *f = mx_cell_faces[m->type[e]][h->local];
      h->nverts = f[3] < 0 ? 3 : 4;
      for (int k = 0; k < h->nverts; k++) h->verts[k] = row[f[k]];
    }
  }
  ggrid_free(&g);
  r->geometric_hanging_nodes = found;
  return MX_OK;
}

/* The geometric hanging-node search alone (see check.h). */
int mx_check_contacts(const mx_mesh_data *m, const uint32_t *list, size_t n,
                      const uint8_t *node_sel, double tol, uint8_t *node_hit,
                      uint8_t *elem_hit, size_t *found) {
  *found = 0;
  if (n == 0 || m->nnodes == 0) return MX_OK;
  double lo[3] = {INFINITY, INFINITY, INFINITY},
         hi[3] = {-INFINITY, -INFINITY, -INFINITY};
  for (int a = 0; a < 3; a++) {
    double l = INFINITY, h = -INFINITY;
#pragma omp parallel for schedule(static) reduction(min : l) reduction(max : h) \
    if (m->nnodes > SMALL)
    for (size_t v = 0; v < m->nnodes; v++) {
      l = mx_min(l, m->xyz[3 * v + (size_t)a]);
      h = mx_max(h, m->xyz[3 * v + (size_t)a]);
    }
    lo[a] = l;
    hi[a] = h;
  }
  ubox U;
  ubox_init(&U, lo, hi);
  if (!U.ok) return MX_OK;
  ggrid g;
  int st = ggrid_build(&g, m, &U, tol, list, n);
  if (st != MX_OK) {
    ggrid_free(&g);
    return st;
  }
  size_t nf = 0;
#pragma omp parallel for schedule(dynamic, 2048) reduction(+ : nf) \
    if (m->nnodes > SMALL)
  for (size_t v = 0; v < m->nnodes; v++) {
    if (!node_sel[v]) continue;
    int where;
    if (node_query(&g, m, v, elem_hit, &where) != UINT32_MAX) {
      if (node_hit) node_hit[v] = 1;
      nf++;
    }
  }
  ggrid_free(&g);
  *found = nf;
  return MX_OK;
}
