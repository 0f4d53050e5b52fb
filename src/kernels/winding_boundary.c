/* The boundary of the winding number's domain: see winding_boundary.h. */
#include "kernels/winding_boundary.h"

#include <math.h>
#include <string.h>

#include "base/common.h"
#include "geom/surface_defects.h"
#include "base/scan.h"

#define MAXP 256 /* pieces per triangle */
#define MAXV 32  /* corners per piece */
#define NEW UINT32_MAX

/* The pieces of one triangle: convex polygons, each corner with its input
 * vertex (NEW for a point made by a cut). One per thread. */
typedef struct {
  int n, capped;
  int nv[MAXP];
  double p[MAXP][MAXV][3];
  uint32_t id[MAXP][MAXV];
  double a[MAXV][3], b[MAXV][3]; /* scratch of a cut */
  uint32_t ia[MAXV], ib[MAXV];
} pieces;

static inline void sub3(const double *a, const double *b, double *c) {
  for (int k = 0; k < 3; k++) c[k] = a[k] - b[k];
}
static inline double dot3(const double *a, const double *b) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}
static inline void cross3(const double *a, const double *b, double *c) {
  c[0] = a[1] * b[2] - a[2] * b[1];
  c[1] = a[2] * b[0] - a[0] * b[2];
  c[2] = a[0] * b[1] - a[1] * b[0];
}
static inline double norm3(const double *a) { return sqrt(dot3(a, a)); }

static void tri_points(const mx_trisoup *s, uint32_t t, double P[9]) {
  for (int k = 0; k < 3; k++) {
    const uint32_t v = s->tri[3 * (size_t)t + k];
    P[3 * k] = s->x[v];
    P[3 * k + 1] = s->y[v];
    P[3 * k + 2] = s->z[v];
  }
}

/* Unit normal of the triangle (0 for a degenerate one); its diameter. */
static double tri_frame(const double P[9], double n[3]) {
  double u[3], w[3];
  sub3(P + 3, P, u);
  sub3(P + 6, P, w);
  cross3(u, w, n);
  const double l = norm3(n);
  for (int k = 0; k < 3; k++) n[k] = l > 0.0 ? n[k] / l : 0.0;
  double e[3], d = 0.0;
  for (int k = 0; k < 3; k++) {
    sub3(P + 3 * ((k + 1) % 3), P + 3 * k, e);
    d = fmax(d, norm3(e));
  }
  return l > 0.0 ? d : 0.0;
}

/* Cut every piece by the plane m.x = off (m unit): a piece with corners
 * farther than tol on both sides becomes two. */
static void cut(pieces *W, const double m[3], double off, double tol) {
  const int n0 = W->n;
  for (int i = 0; i < n0; i++) {
    const int nv = W->nv[i];
    double d[MAXV];
    int neg = 0, pos = 0;
    for (int k = 0; k < nv; k++) {
      d[k] = dot3(m, W->p[i][k]) - off;
      neg |= d[k] < -tol;
      pos |= d[k] > tol;
    }
    if (!neg || !pos) continue;
    if (W->n == MAXP) {
      W->capped = 1;
      return;
    }
    int na = 0, nb = 0;
    for (int k = 0; k < nv && na < MAXV && nb < MAXV; k++) {
      const int j = (k + 1) % nv;
      if (d[k] <= tol) {
        memcpy(W->a[na], W->p[i][k], sizeof W->a[0]);
        W->ia[na++] = W->id[i][k];
      }
      if (d[k] >= -tol && nb < MAXV) {
        memcpy(W->b[nb], W->p[i][k], sizeof W->b[0]);
        W->ib[nb++] = W->id[i][k];
      }
      if ((d[k] < -tol && d[j] > tol) || (d[k] > tol && d[j] < -tol)) {
        const double f = d[k] / (d[k] - d[j]);
        double x[3];
        for (int c = 0; c < 3; c++) x[c] = W->p[i][k][c] + f * (W->p[i][j][c] - W->p[i][k][c]);
        if (na < MAXV) {
          memcpy(W->a[na], x, sizeof x);
          W->ia[na++] = NEW;
        }
        if (nb < MAXV) {
          memcpy(W->b[nb], x, sizeof x);
          W->ib[nb++] = NEW;
        }
      }
    }
    if (na >= MAXV || nb >= MAXV) { /* too many corners: left whole */
      W->capped = 1;
      continue;
    }
    const int o = W->n++;
    memcpy(W->p[i], W->a, (size_t)na * sizeof W->a[0]);
    memcpy(W->id[i], W->ia, (size_t)na * sizeof W->ia[0]);
    W->nv[i] = na;
    memcpy(W->p[o], W->b, (size_t)nb * sizeof W->b[0]);
    memcpy(W->id[o], W->ib, (size_t)nb * sizeof W->ib[0]);
    W->nv[o] = nb;
  }
}

/* Drops the corners of piece i that repeat the previous one (within tol)
 * or lie on the line of their neighbours. */
static void tidy(pieces *W, int i, double tol) {
  int nv = W->nv[i], changed = 1;
  while (changed && nv >= 3) {
    changed = 0;
    for (int k = 0; k < nv && nv >= 3; k++) {
      const double *a = W->p[i][(k + nv - 1) % nv], *b = W->p[i][k], *c = W->p[i][(k + 1) % nv];
      double u[3], w[3], x[3];
      sub3(b, a, u);
      sub3(c, b, w);
      cross3(u, w, x);
      if (norm3(u) <= tol || norm3(x) <= 1e-12 * norm3(u) * norm3(w)) {
        memmove(W->p[i][k], W->p[i][k + 1], (size_t)(nv - k - 1) * sizeof W->p[i][0]);
        memmove(&W->id[i][k], &W->id[i][k + 1], (size_t)(nv - k - 1) * sizeof W->id[i][0]);
        nv--;
        changed = 1;
        k--;
      }
    }
  }
  W->nv[i] = nv;
}

/* The input triangles that meet each triangle: adj[off[t] .. off[t+1]),
 * increasing. */
typedef struct {
  uint64_t *off;
  uint32_t *adj;
} partners;

static int partners_build(const mx_trisoup *s, partners *R) {
  uint64_t *pairs = NULL;
  size_t np = 0;
  MX_CHECK(mx_surface_meeting_pairs(s, &pairs, &np));
  R->off = mx_calloc((s->nt + 2) * sizeof *R->off);
  R->adj = mx_alloc((2 * np + 1) * sizeof *R->adj);
  if (!R->off || !R->adj) {
    mx_free(pairs);
    return MX_ENOMEM;
  }
  for (size_t k = 0; k < np; k++) {
    R->off[(pairs[k] >> 32) + 1]++;
    R->off[(uint32_t)pairs[k] + 1]++;
  }
  for (size_t t = 0; t < s->nt; t++) R->off[t + 1] += R->off[t];
  uint64_t *fill = mx_alloc((s->nt + 1) * sizeof *fill);
  if (!fill) {
    mx_free(pairs);
    return MX_ENOMEM;
  }
  memcpy(fill, R->off, s->nt * sizeof *fill);
  /* sorted by (i, j): for each t the pairs with t as j (i < t) come before
   * those with t as i, so each list is increasing */
  for (size_t k = 0; k < np; k++) {
    const uint32_t i = (uint32_t)(pairs[k] >> 32), j = (uint32_t)pairs[k];
    R->adj[fill[i]++] = j;
    R->adj[fill[j]++] = i;
  }
  mx_free(fill);
  mx_free(pairs);
  return MX_OK;
}

/* Are P and Q (normals np, nq; diameters dp, dq) in one plane? */
static int coplanar(const double P[9], const double np[3], double dp, const double Q[9],
                    const double nq[3], double dq) {
  const double tol = 1e-9 * fmax(dp, dq);
  for (int k = 0; k < 3; k++) {
    double u[3];
    sub3(Q + 3 * k, P, u);
    if (fabs(dot3(np, u)) > tol) return 0;
    sub3(P + 3 * k, Q, u);
    if (fabs(dot3(nq, u)) > tol) return 0;
  }
  return 1;
}

/* Is x (in Q's plane, normal n) inside triangle Q? */
static int in_triangle(const double Q[9], const double n[3], const double x[3]) {
  int neg = 0, pos = 0;
  for (int k = 0; k < 3; k++) {
    double e[3], u[3], c[3];
    sub3(Q + 3 * ((k + 1) % 3), Q + 3 * k, e);
    sub3(x, Q + 3 * k, u);
    cross3(e, u, c);
    const double g = dot3(c, n);
    neg |= g < 0.0;
    pos |= g > 0.0;
  }
  return !(neg && pos);
}

/* Whether the winding number of W takes whole values only: every edge of
 * the input (its points compared by coordinates) used as often in each
 * direction, the triangles oriented as W has them. */
static int whole_values(const mx_trisoup *d, const mx_surface_index *W, int *whole) {
  uint64_t *key = mx_alloc((d->nv + 1) * sizeof *key);
  uint32_t *canon = mx_alloc((d->nv + 1) * sizeof *canon);
  uint32_t *order = mx_alloc((d->nv + 1) * sizeof *order);
  int st = key && canon && order ? MX_OK : MX_ENOMEM;
  /* points sorted by a hash of their coordinates; within a run of one
   * hash, the first point with the same coordinates stands for them */
  if (!st) {
    for (size_t v = 0; v < d->nv; v++) {
      const double p[3] = {d->x[v], d->y[v], d->z[v]};
      uint64_t h = 1469598103934665603ull;
      const unsigned char *b = (const unsigned char *)p;
      for (size_t i = 0; i < sizeof p; i++) h = (h ^ b[i]) * 1099511628211ull;
      key[v] = h;
      order[v] = (uint32_t)v;
    }
    st = mx_sort_u64(key, order, d->nv);
  }
  if (!st)
    for (size_t i = 0; i < d->nv;) {
      size_t j = i;
      while (j < d->nv && key[j] == key[i]) j++;
      for (size_t a = i; a < j; a++) {
        const uint32_t va = order[a];
        canon[va] = va;
        for (size_t b = i; b < a; b++) {
          const uint32_t vb = order[b];
          if (d->x[va] == d->x[vb] && d->y[va] == d->y[vb] && d->z[va] == d->z[vb]) {
            canon[va] = canon[vb];
            break;
          }
        }
      }
      i = j;
    }
  mx_free(order);
  mx_free(key);
  const size_t ne = 3 * (size_t)W->nt;
  uint64_t *ek = st ? NULL : mx_alloc((ne + 1) * sizeof *ek);
  uint32_t *ev = st ? NULL : mx_alloc((ne + 1) * sizeof *ev);
  if (!st && (!ek || !ev)) st = MX_ENOMEM;
  if (!st) {
    for (uint32_t i = 0; i < W->nt; i++) {
      const uint32_t *v = d->tri + 3 * (size_t)W->tri_id[i];
      for (int k = 0; k < 3; k++) {
        uint32_t a = canon[v[k]], b = canon[v[(k + 1) % 3]];
        if (W->tsign[i] < 0) {
          const uint32_t x = a;
          a = b;
          b = x;
        }
        ek[3 * (size_t)i + k] = a < b ? (uint64_t)a << 32 | b : (uint64_t)b << 32 | a;
        ev[3 * (size_t)i + k] = a < b; /* 1: from the lower point */
      }
    }
    st = mx_sort_u64(ek, ev, ne);
  }
  if (!st) {
    *whole = 1;
    for (size_t i = 0; i < ne && *whole;) {
      size_t j = i;
      long net = 0;
      while (j < ne && ek[j] == ek[i]) net += ev[j++] ? 1 : -1;
      if ((uint32_t)(ek[i] >> 32) != (uint32_t)ek[i]) *whole = net == 0;
      i = j;
    }
  }
  mx_free(ek);
  mx_free(ev);
  mx_free(canon);
  return st;
}

static int degenerate(const mx_trisoup *s, uint32_t t) {
  double P[9], n[3];
  tri_points(s, t, P);
  return !(tri_frame(P, n) > 0.0);
}

/* The triangles that nothing meets, in sets connected through edges used by
 * exactly two of them (vertex ids): comp[t] = the set's first triangle
 * (UINT32_MAX for the others), par[t] = 1 when t runs the other way round
 * from it. Serial, O(n log n). */
static int free_sets(const mx_trisoup *s, const partners *R, uint32_t *comp, uint8_t *par) {
  const size_t nt = s->nt, ne = 3 * nt;
  uint64_t *ek = mx_alloc((ne + 1) * sizeof *ek);
  uint32_t *ev = mx_alloc((ne + 1) * sizeof *ev);
  uint32_t *nb = mx_alloc((ne + 1) * sizeof *nb); /* across edge e: the neighbour */
  uint8_t *nbp = mx_alloc(ne + 1);                /* and 1 if it runs the same way */
  uint32_t *queue = mx_alloc((nt + 1) * sizeof *queue);
  int st = ek && ev && nb && nbp && queue ? MX_OK : MX_ENOMEM;
  if (!st) {
    for (size_t t = 0; t < nt; t++) {
      const int fr = R->off[t + 1] == R->off[t] && !degenerate(s, (uint32_t)t);
      comp[t] = UINT32_MAX;
      par[t] = fr ? 2 : 0; /* 2: free, not reached yet */
      for (int k = 0; k < 3; k++) {
        const uint32_t a = s->tri[3 * t + k], b = s->tri[3 * t + (k + 1) % 3];
        ek[3 * t + k] = a < b ? (uint64_t)a << 32 | b : (uint64_t)b << 32 | a;
        ev[3 * t + k] = (uint32_t)(3 * t + k);
        nb[3 * t + k] = UINT32_MAX;
      }
    }
    st = mx_sort_u64(ek, ev, ne);
  }
  if (!st)
    for (size_t i = 0; i < ne;) {
      size_t j = i;
      while (j < ne && ek[j] == ek[i]) j++;
      if (j - i == 2) {
        const uint32_t e1 = ev[i], e2 = ev[i + 1], t1 = e1 / 3, t2 = e2 / 3;
        if (t1 != t2 && par[t1] == 2 && par[t2] == 2) {
          const int up1 = s->tri[e1] < s->tri[3 * t1 + (e1 % 3 + 1) % 3];
          const int up2 = s->tri[e2] < s->tri[3 * t2 + (e2 % 3 + 1) % 3];
          nb[e1] = t2;
          nb[e2] = t1;
          nbp[e1] = nbp[e2] = (uint8_t)(up1 == up2);
        }
      }
      i = j;
    }
  if (!st)
    for (size_t t0 = 0; t0 < nt; t0++) {
      if (par[t0] != 2) continue;
      size_t qh = 0, qt = 0;
      queue[qt++] = (uint32_t)t0;
      comp[t0] = (uint32_t)t0;
      par[t0] = 0;
      while (qh < qt) {
        const uint32_t t = queue[qh++];
        for (int k = 0; k < 3; k++) {
          const uint32_t u = nb[3 * (size_t)t + k];
          if (u == UINT32_MAX || par[u] != 2) continue;
          comp[u] = (uint32_t)t0;
          par[u] = (uint8_t)(par[t] ^ nbp[3 * (size_t)t + k]);
          queue[qt++] = u;
        }
      }
    }
  mx_free(ek);
  mx_free(ev);
  mx_free(nb);
  mx_free(nbp);
  mx_free(queue);
  return st;
}

enum { DROP_IN = 0, DROP_OUT, DROP_COPY, KEEP, KEEP_TURNED };

/* One triangle t: its pieces in W (cut by the partners' planes) and the
 * verdict of each in verdict[]. Returns the number of pieces (0 for a
 * degenerate triangle). */
/* The pieces of triangle t in W (cut by the planes of the triangles that
 * meet it, tidied); P, n, dp: its points, unit normal and diameter.
 * Returns the number of pieces (0 for a degenerate triangle). */
static int cut_triangle(const mx_trisoup *s, const partners *R, uint32_t t, pieces *W,
                        double P[9], double n[3], double *dp_out) {
  tri_points(s, t, P);
  const double dp = tri_frame(P, n);
  *dp_out = dp;
  if (!(dp > 0.0)) return 0;
  W->n = 1;
  W->capped = 0;
  W->nv[0] = 3;
  for (int k = 0; k < 3; k++) {
    memcpy(W->p[0][k], P + 3 * k, 3 * sizeof(double));
    W->id[0][k] = s->tri[3 * (size_t)t + k];
  }
  const double tol = 1e-9 * dp;
  for (uint64_t j = R->off[t]; j < R->off[t + 1] && !W->capped; j++) {
    double Q[9], nq[3];
    tri_points(s, R->adj[j], Q);
    const double dq = tri_frame(Q, nq);
    if (!(dq > 0.0)) continue;
    if (coplanar(P, n, dp, Q, nq, dq)) {
      for (int k = 0; k < 3; k++) { /* Q's edges, across T's plane */
        double e[3], m[3];
        sub3(Q + 3 * ((k + 1) % 3), Q + 3 * k, e);
        cross3(n, e, m);
        const double l = norm3(m);
        if (!(l > 0.0)) continue;
        for (int c = 0; c < 3; c++) m[c] /= l;
        cut(W, m, dot3(m, Q + 3 * k), tol);
      }
    } else {
      cut(W, nq, dot3(nq, Q), tol);
    }
  }
  for (int i = 0; i < W->n; i++) tidy(W, i, tol);
  return W->n;
}

/* The pieces of triangle t (cut_triangle) and the verdict of each in
 * verdict[]: classified (*nq counts the winding number evaluations), or
 * copied from known when not NULL. *area: the kept pieces' area. */
static int triangle_pieces(const mx_trisoup *s, const mx_surface_index *Wn,
                           const partners *R, uint32_t t, pieces *W, uint8_t *verdict,
                           const uint8_t *known, double *area, int *nq) {
  double P[9], n[3], dp;
  *area = 0.0;
  if (!cut_triangle(s, R, t, W, P, n, &dp)) return 0;
  if (known) {
    memcpy(verdict, known, (size_t)W->n);
    return W->n;
  }
  for (int i = 0; i < W->n; i++) {
    const int nv = W->nv[i];
    if (nv < 3) {
      verdict[i] = DROP_OUT;
      continue;
    }
    double c[3] = {0.0, 0.0, 0.0}, ar = 0.0, per = 0.0;
    for (int k = 0; k < nv; k++) {
      double e[3];
      sub3(W->p[i][(k + 1) % nv], W->p[i][k], e);
      per += norm3(e);
      for (int a = 0; a < 3; a++) c[a] += W->p[i][k][a] / nv;
      if (k >= 1 && k + 1 < nv) {
        double u[3], w[3], x[3];
        sub3(W->p[i][k], W->p[i][0], u);
        sub3(W->p[i][k + 1], W->p[i][0], w);
        cross3(u, w, x);
        ar += 0.5 * norm3(x);
      }
    }
    const double eps = fmax(0.02 * ar / per, 1e-12 * dp);
    double f[3], b[3];
    for (int a = 0; a < 3; a++) {
      f[a] = c[a] + eps * n[a];
      b[a] = c[a] - eps * n[a];
    }
    const int in_f = mx_winding_number(Wn, f) > 0.5, in_b = mx_winding_number(Wn, b) > 0.5;
    *nq += 2;
    if (in_f == in_b) {
      verdict[i] = in_f ? DROP_IN : DROP_OUT;
      continue;
    }
    verdict[i] = in_f ? KEEP_TURNED : KEEP;
    /* a coplanar triangle of smaller id lying under the piece keeps it */
    for (uint64_t j = R->off[t]; j < R->off[t + 1]; j++) {
      const uint32_t u = R->adj[j];
      if (u >= t) break;
      double Q[9], nq[3];
      tri_points(s, u, Q);
      const double dq = tri_frame(Q, nq);
      if (dq > 0.0 && coplanar(P, n, dp, Q, nq, dq) && in_triangle(Q, nq, c)) {
        verdict[i] = DROP_COPY;
        break;
      }
    }
    if (verdict[i] >= KEEP) *area += ar;
  }
  return W->n;
}

/* Kept output of triangle t: fan triangles and new corners. */
static void count_kept(const pieces *W, int np, const uint8_t *verdict, uint32_t *ntri,
                       uint32_t *nnew) {
  *ntri = *nnew = 0;
  for (int i = 0; i < np; i++) {
    if (verdict[i] < KEEP) continue;
    *ntri += (uint32_t)(W->nv[i] - 2);
    for (int k = 0; k < W->nv[i]; k++) *nnew += W->id[i][k] == NEW;
  }
}

int mx_winding_boundary(const mx_trisoup *s, const mx_surface_index *Wn, mx_trisoup *out,
                        mx_winding_boundary_stats *st) {
  memset(st, 0, sizeof *st);
  const size_t nt = s->nt;
  partners R = {NULL, NULL};
  int status = partners_build(s, &R);
  uint32_t *ntri = mx_calloc((nt + 1) * sizeof *ntri);
  uint32_t *nnew = mx_calloc((nt + 1) * sizeof *nnew);
  double *tarea = mx_calloc((nt + 1) * sizeof *tarea);
  uint8_t *whole = mx_alloc(nt + 1); /* the verdict of a triangle nothing cut */
  if (!status && (!ntri || !nnew || !tarea || !whole)) status = MX_ENOMEM;
  size_t cut_n = 0, pieces_n = 0, kept = 0, in_n = 0, out_n = 0, copies = 0, turned = 0,
         capped = 0, queries = 0;
  int oom = 0;
  /* with whole values, one verdict per set of free triangles (free_sets) */
  uint32_t *comp = NULL;
  uint8_t *par = NULL;
  if (!status) status = whole_values(s, Wn, &st->whole);
  if (!status && st->whole) {
    comp = mx_alloc((nt + 1) * sizeof *comp);
    par = mx_alloc(nt + 1);
    status = comp && par ? free_sets(s, &R, comp, par) : MX_ENOMEM;
  }
  /* the pieces of each triangle (cutting is cheap; classifying is not:
   * the verdicts are kept for the writing pass) */
  uint64_t *poff = NULL;
  uint8_t *known = NULL;
  if (!status) {
    poff = mx_alloc((nt + 1) * sizeof *poff);
    if (!poff) status = MX_ENOMEM;
  }
  if (!status) {
#pragma omp parallel reduction(| : oom)
    {
      pieces *W = NULL;
#pragma omp for schedule(dynamic, 64)
      for (size_t t = 0; t < nt; t++) {
        if (R.off[t + 1] == R.off[t]) {
          poff[t] = !degenerate(s, (uint32_t)t);
          continue;
        }
        if (!W) W = mx_alloc(sizeof *W);
        if (!W) {
          oom = 1;
          continue;
        }
        double P[9], n[3], dp;
        poff[t] = (uint64_t)cut_triangle(s, &R, (uint32_t)t, W, P, n, &dp);
      }
      mx_free(W);
    }
    if (oom) status = MX_ENOMEM;
  }
  if (!status) {
    uint64_t sum = 0;
    for (size_t t = 0; t < nt; t++) {
      const uint64_t k = poff[t];
      poff[t] = sum;
      sum += k;
    }
    poff[nt] = sum;
    known = mx_alloc(sum + 1);
    if (!known) status = MX_ENOMEM;
  }
  if (!status) {
#pragma omp parallel reduction(+ : cut_n, pieces_n, kept, in_n, out_n, copies, turned, capped, \
                                   queries) reduction(| : oom)
    {
      pieces *W = mx_alloc(sizeof *W);
      uint8_t verdict[MAXP];
      if (!W) oom = 1;
#pragma omp for schedule(dynamic, 64)
      for (size_t t = 0; t < nt; t++) {
        if (!W) continue;
        if (comp && comp[t] != UINT32_MAX && comp[t] != t) continue; /* below */
        int nq = 0;
        const int np =
            triangle_pieces(s, Wn, &R, (uint32_t)t, W, verdict, NULL, &tarea[t], &nq);
        queries += (size_t)nq;
        memcpy(known + poff[t], verdict, (size_t)np);
        whole[t] = np == 1 && W->nv[0] == 3 && W->id[0][0] != NEW && W->id[0][1] != NEW &&
                           W->id[0][2] != NEW
                       ? verdict[0]
                       : 255;
        cut_n += np > 1;
        capped += W->capped;
        pieces_n += (size_t)np;
        for (int i = 0; i < np; i++) {
          kept += verdict[i] >= KEEP;
          turned += verdict[i] == KEEP_TURNED;
          in_n += verdict[i] == DROP_IN;
          out_n += verdict[i] == DROP_OUT;
          copies += verdict[i] == DROP_COPY;
        }
        count_kept(W, np, verdict, &ntri[t], &nnew[t]);
      }
      mx_free(W);
    }
    if (oom) status = MX_ENOMEM;
  }
  if (!status && comp)
    for (size_t t = 0; t < nt; t++) {
      if (comp[t] == UINT32_MAX || comp[t] == t) continue;
      uint8_t v = whole[comp[t]];
      if (par[t] && v >= KEEP) v = v == KEEP ? KEEP_TURNED : KEEP;
      whole[t] = v;
      pieces_n++;
      kept += v >= KEEP;
      turned += v == KEEP_TURNED;
      in_n += v == DROP_IN;
      out_n += v == DROP_OUT;
      ntri[t] = v >= KEEP;
      nnew[t] = 0;
      if (v >= KEEP) {
        double P[9], n[3], u[3], w[3], x[3];
        tri_points(s, (uint32_t)t, P);
        tri_frame(P, n);
        sub3(P + 3, P, u);
        sub3(P + 6, P, w);
        cross3(u, w, x);
        tarea[t] = 0.5 * norm3(x);
      }
    }
  mx_free(comp);
  mx_free(par);
  /* offsets, then the output in the triangles' order */
  uint64_t tot_t = 0, tot_v = s->nv;
  uint64_t *toff = NULL, *voff = NULL;
  if (!status) {
    toff = mx_alloc((nt + 1) * sizeof *toff);
    voff = mx_alloc((nt + 1) * sizeof *voff);
    if (!toff || !voff) status = MX_ENOMEM;
  }
  if (!status) {
    for (size_t t = 0; t < nt; t++) {
      toff[t] = tot_t;
      voff[t] = tot_v;
      tot_t += ntri[t];
      tot_v += nnew[t];
      st->area += tarea[t];
    }
    if (tot_v > UINT32_MAX) {
      mx_error(NULL, 0, "the boundary of the winding number's domain needs more than 2^32 "
                        "points");
      status = MX_EINPUT;
    }
  }
  if (!status) status = mx_trisoup_reserve(out, (size_t)tot_v, (size_t)tot_t + 1);
  if (!status) {
    memcpy(out->x, s->x, s->nv * sizeof *out->x);
    memcpy(out->y, s->y, s->nv * sizeof *out->y);
    memcpy(out->z, s->z, s->nv * sizeof *out->z);
#pragma omp parallel reduction(| : oom)
    {
      pieces *W = NULL;
      uint8_t verdict[MAXP];
#pragma omp for schedule(dynamic, 64)
      for (size_t t = 0; t < nt; t++) {
        if (!ntri[t]) continue;
        uint32_t *o = out->tri + 3 * toff[t];
        uint16_t *sh = out->shell + toff[t];
        uint32_t *fc = out->face + toff[t]; /* the pieces keep their input face */
        if (whole[t] != 255) { /* the triangle itself */
          const uint32_t *v = s->tri + 3 * t;
          o[0] = v[0];
          o[1] = whole[t] == KEEP_TURNED ? v[2] : v[1];
          o[2] = whole[t] == KEEP_TURNED ? v[1] : v[2];
          sh[0] = s->shell[t];
          fc[0] = s->face[t];
          continue;
        }
        if (!W) W = mx_alloc(sizeof *W);
        if (!W) {
          oom = 1;
          continue;
        }
        double dummy;
        int nq = 0;
        const int np =
            triangle_pieces(s, Wn, &R, (uint32_t)t, W, verdict, known + poff[t], &dummy, &nq);
        uint64_t nv = voff[t];
        size_t k = 0;
        for (int i = 0; i < np; i++) {
          if (verdict[i] < KEEP) continue;
          uint32_t id[MAXV];
          for (int c = 0; c < W->nv[i]; c++) {
            id[c] = W->id[i][c];
            if (id[c] == NEW) {
              out->x[nv] = W->p[i][c][0];
              out->y[nv] = W->p[i][c][1];
              out->z[nv] = W->p[i][c][2];
              id[c] = (uint32_t)nv++;
            }
          }
          const int turn = verdict[i] == KEEP_TURNED;
          for (int c = 1; c + 1 < W->nv[i]; c++, k++) {
            o[3 * k] = id[0];
            o[3 * k + 1] = turn ? id[c + 1] : id[c];
            o[3 * k + 2] = turn ? id[c] : id[c + 1];
            sh[k] = s->shell[t];
            fc[k] = s->face[t];
          }
        }
      }
      mx_free(W);
    }
    if (oom) status = MX_ENOMEM;
  }
  if (!status) {
    out->nv = (size_t)tot_v;
    out->nt = (size_t)tot_t;
    out->nshells = s->nshells;
    st->cut = cut_n;
    st->pieces = pieces_n;
    st->kept = kept;
    st->inside = in_n;
    st->outside = out_n;
    st->copies = copies;
    st->turned = turned;
    st->capped = capped;
    st->queries = queries;
  }
  mx_free(R.off);
  mx_free(R.adj);
  mx_free(ntri);
  mx_free(nnew);
  mx_free(tarea);
  mx_free(whole);
  mx_free(toff);
  mx_free(voff);
  mx_free(poff);
  mx_free(known);
  return status;
}
