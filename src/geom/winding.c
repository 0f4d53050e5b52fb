/* The generalized winding number of the surface index (geom/distance.h):
 * signed solid angles summed over the binary BVH, a node whose box does
 * not hold the point counted through its cap (the fan closing its
 * boundary), and the caps' construction. */
#include "geom/surface_index_impl.h"

#include <string.h>

#include "base/common.h"

/* Signed solid angle of the triangle (a, b, c) seen from p (van Oosterom &
 * Strackee): positive when p is behind the triangle, i.e. on the side
 * opposite to the normal (b - a) x (c - a). Exactly coplanar: 0. */
static inline double solid_angle(const double p[3], const double a[3],
                                 const double b[3], const double c[3]) {
  double u[3], v[3], w[3];
  sub3(a, p, u);
  sub3(b, p, v);
  sub3(c, p, w);
  const double lu = sqrt(dot3(u, u)), lv = sqrt(dot3(v, v)),
               lw = sqrt(dot3(w, w));
  double vw[3];
  cross3(v, w, vw);
  const double det = dot3(u, vw);
  if (det == 0.0) return 0.0;
  const double den =
      lu * lv * lw + dot3(u, v) * lw + dot3(v, w) * lu + dot3(w, u) * lv;
  return 2.0 * atan2(det, den);
}

/* Winding number with per-slot signs ssign and cap weights capw; the slot
 * `skip` is left out (UINT32_MAX: none). Nodes whose box does not contain p
 * and that have a cap contribute through it. */
double mx_index_winding(const mx_surface_index *S, const double p[3],
                      const int8_t *ssign, const int32_t *capw,
                      uint32_t skip) {
  if (!S->nt) return 0.0;
  const mx_trisoup *s = S->soup;
  uint32_t stack[STACK_MAX];
  int sp = 0;
  stack[sp++] = 0;
  double sum = 0.0;
  while (sp) {
    const uint32_t n = stack[--sp];
    const mx_bvh_node *N = &S->nodes[n];
    if (N->count) {
      for (uint32_t i = N->first; i < N->first + N->count; i++) {
        if (i == skip) continue;
        const double *t = S->tv + 9 * (size_t)i;
        sum += ssign[i] * solid_angle(p, t, t + 3, t + 6);
      }
      continue;
    }
    if (S->cap_cnt[n] != NO_CAP && box_outside(N, p)) {
      const double o[3] = {0.5 * (N->lo[0] + N->hi[0]),
                           0.5 * (N->lo[1] + N->hi[1]),
                           0.5 * (N->lo[2] + N->hi[2])};
      const uint64_t j0 = S->cap_off[n], j1 = j0 + S->cap_cnt[n];
      for (uint64_t j = j0; j < j1; j++) {
        const uint32_t u = S->cap_u[j], v = S->cap_v[j];
        const double a[3] = {s->x[u], s->y[u], s->z[u]};
        const double b[3] = {s->x[v], s->y[v], s->z[v]};
        sum += capw[j] * solid_angle(p, o, a, b);
      }
      continue;
    }
    stack[sp++] = N->first;
    stack[sp++] = N->first + 1;
  }
  return sum / FOUR_PI;
}

double mx_winding_number(const mx_surface_index *S, const double p[3]) {
  return mx_index_winding(S, p, S->tsign, S->cap_w, UINT32_MAX);
}

double mx_winding_number_direct(const mx_surface_index *S, const double p[3]) {
  double sum = 0.0;
  for (uint32_t i = 0; i < S->nt; i++) {
    const double *t = S->tv + 9 * (size_t)i;
    sum += S->tsign[i] * solid_angle(p, t, t + 3, t + 6);
  }
  return sum / FOUR_PI;
}

/* Vertex k of slot i and the next one around the triangle. */
static inline void slot_edge(const mx_surface_index *S, uint32_t i, int k,
                             uint32_t *va, uint32_t *vb) {
  const uint32_t *v = S->soup->tri + 3 * (size_t)S->tri_id[i];
  *va = v[k];
  *vb = v[(k + 1) % 3];
}

/* Growable list of boundary entries: key (lo << 32 | hi), weight (+w:
 * lo -> hi, -w: hi -> lo) and shell. */
typedef struct {
  uint64_t *k;
  int32_t *w;
  uint32_t *c;
  size_t n, cap;
} edge_list;

static int edge_list_reserve(edge_list *L, size_t n) {
  if (n <= L->cap) return MX_OK;
  size_t cap = L->cap ? L->cap : 256;
  while (cap < n) cap *= 2;
  uint64_t *k = mx_realloc(L->k, cap * sizeof *k);
  if (!k) return MX_ENOMEM;
  L->k = k;
  int32_t *w = mx_realloc(L->w, cap * sizeof *w);
  if (!w) return MX_ENOMEM;
  L->w = w;
  uint32_t *c = mx_realloc(L->c, cap * sizeof *c);
  if (!c) return MX_ENOMEM;
  L->c = c;
  L->cap = cap;
  return MX_OK;
}

static void edge_list_free(edge_list *L) {
  mx_free(L->k);
  mx_free(L->w);
  mx_free(L->c);
}

typedef struct {
  mx_surface_index *S;
  const uint8_t *fix;
  edge_list scr;  /* lists of the nodes on the current path */
  edge_list keep; /* the caps kept */
  size_t budget;  /* at most this many entries kept */
} cap_ctx;

/* Boundary of node b, appended to the scratch list (sorted by key): a
 * leaf's from its triangles, an internal node's by merging its children's,
 * which it then replaces. Kept as the node's cap when it has at most half
 * as many edges as the node has triangles (and the budget allows). */
static int cap_node(cap_ctx *X, uint32_t b) {
  mx_surface_index *S = X->S;
  const mx_bvh_node *N = &S->nodes[b];
  edge_list *L = &X->scr;
  S->cap_cnt[b] = NO_CAP;
  S->cap_off[b] = 0;
  if (N->count) {
    MX_CHECK(edge_list_reserve(L, L->n + 3 * LEAF_MAX));
    const size_t s0 = L->n;
    uint64_t k[3 * LEAF_MAX];
    int32_t w[3 * LEAF_MAX];
    uint32_t c[3 * LEAF_MAX];
    int m = 0;
    for (uint32_t i = N->first; i < N->first + N->count; i++)
      for (int e = 0; e < 3; e++) {
        uint32_t a, bb;
        slot_edge(S, i, e, &a, &bb);
        if (a == bb) continue;
        const int up = (a < bb) ^ X->fix[i];
        const uint64_t key =
            a < bb ? (uint64_t)a << 32 | bb : (uint64_t)bb << 32 | a;
        int j = m++; /* insertion sort */
        while (j > 0 && k[j - 1] > key) {
          k[j] = k[j - 1];
          w[j] = w[j - 1];
          c[j] = c[j - 1];
          j--;
        }
        k[j] = key;
        w[j] = up ? 1 : -1;
        c[j] = S->shell_of[i];
      }
    size_t o = s0;
    for (int j = 0; j < m;) {
      int32_t sw = 0;
      int j2 = j;
      while (j2 < m && k[j2] == k[j]) sw += w[j2++];
      if (sw) {
        L->k[o] = k[j];
        L->w[o] = sw;
        L->c[o++] = c[j];
      }
      j = j2;
    }
    L->n = o;
    return MX_OK;
  }
  const size_t s0 = L->n;
  MX_CHECK(cap_node(X, N->first));
  const size_t s1 = L->n;
  MX_CHECK(cap_node(X, N->first + 1));
  const size_t s2 = L->n;
  MX_CHECK(edge_list_reserve(L, s2 + (s2 - s0)));
  size_t i = s0, j = s1, o = s2;
  while (i < s1 || j < s2) {
    if (j >= s2 || (i < s1 && L->k[i] < L->k[j])) {
      L->k[o] = L->k[i];
      L->w[o] = L->w[i];
      L->c[o++] = L->c[i++];
    } else if (i >= s1 || L->k[j] < L->k[i]) {
      L->k[o] = L->k[j];
      L->w[o] = L->w[j];
      L->c[o++] = L->c[j++];
    } else {
      const int32_t sw = L->w[i] + L->w[j];
      if (sw) {
        L->k[o] = L->k[i];
        L->w[o] = sw;
        L->c[o++] = L->c[i];
      }
      i++;
      j++;
    }
  }
  const size_t m = o - s2;
  memmove(L->k + s0, L->k + s2, m * sizeof *L->k);
  memmove(L->w + s0, L->w + s2, m * sizeof *L->w);
  memmove(L->c + s0, L->c + s2, m * sizeof *L->c);
  L->n = s0 + m;
  if (2 * m <= N->ntri && X->keep.n + m <= X->budget) {
    edge_list *K = &X->keep;
    MX_CHECK(edge_list_reserve(K, K->n + m));
    if (m) {
      memcpy(K->k + K->n, L->k + s0, m * sizeof *K->k);
      memcpy(K->w + K->n, L->w + s0, m * sizeof *K->w);
      memcpy(K->c + K->n, L->c + s0, m * sizeof *K->c);
    }
    S->cap_off[b] = K->n;
    S->cap_cnt[b] = (uint32_t)m;
    K->n += m;
  }
  return MX_OK;
}

/* The caps of the winding number (see distance.h): boundaries in the
 * consistent orientation of each shell (before the shells' flips, which
 * orient_shells applies); cap_shell receives the shell of each entry. At
 * most 2 nt + 64 entries are kept (in a pathological surface, such as
 * disconnected triangles, nodes keep none and queries descend, still
 * exact). */
int mx_index_build_caps(mx_surface_index *S, const uint8_t *fix,
                      uint32_t **cap_shell) {
  S->cap_off = mx_alloc((size_t)S->nnodes * sizeof *S->cap_off);
  S->cap_cnt = mx_alloc((size_t)S->nnodes * sizeof *S->cap_cnt);
  if (!S->cap_off || !S->cap_cnt) return MX_ENOMEM;
  cap_ctx X;
  memset(&X, 0, sizeof X);
  X.S = S;
  X.fix = fix;
  X.budget = 2 * (size_t)S->nt + 64;
  int st = cap_node(&X, 0);
  const size_t n = X.keep.n;
  S->ncap = n;
  if (st == MX_OK) {
    S->cap_u = mx_alloc(n * sizeof *S->cap_u + 4);
    S->cap_v = mx_alloc(n * sizeof *S->cap_v + 4);
    S->cap_w = mx_alloc(n * sizeof *S->cap_w + 4);
    *cap_shell = mx_alloc(n * sizeof **cap_shell + 4);
    if (!S->cap_u || !S->cap_v || !S->cap_w || !*cap_shell) st = MX_ENOMEM;
  }
  if (st == MX_OK)
    for (size_t j = 0; j < n; j++) {
      S->cap_u[j] = (uint32_t)(X.keep.k[j] >> 32);
      S->cap_v[j] = (uint32_t)X.keep.k[j];
      S->cap_w[j] = X.keep.w[j];
      (*cap_shell)[j] = X.keep.c[j];
    }
  edge_list_free(&X.scr);
  edge_list_free(&X.keep);
  return st;
}
