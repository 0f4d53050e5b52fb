/* The boundary of the winding number's domain: see winding_boundary.h. */
#include "kernels/winding_boundary.h"

#include <math.h>
#include <string.h>

#include "common.h"
#include "kernels/surface_defects.h"

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
    return MX_EINPUT;
  }
  for (size_t k = 0; k < np; k++) {
    R->off[(pairs[k] >> 32) + 1]++;
    R->off[(uint32_t)pairs[k] + 1]++;
  }
  for (size_t t = 0; t < s->nt; t++) R->off[t + 1] += R->off[t];
  uint64_t *fill = mx_alloc((s->nt + 1) * sizeof *fill);
  if (!fill) {
    mx_free(pairs);
    return MX_EINPUT;
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

enum { DROP_IN = 0, DROP_OUT, DROP_COPY, KEEP, KEEP_TURNED };

/* One triangle t: its pieces in W (cut by the partners' planes) and the
 * verdict of each in verdict[]. Returns the number of pieces (0 for a
 * degenerate triangle). */
static int triangle_pieces(const mx_trisoup *s, const mx_surface_index *Wn,
                           const partners *R, uint32_t t, pieces *W, uint8_t *verdict,
                           double *area) {
  double P[9], n[3];
  tri_points(s, t, P);
  const double dp = tri_frame(P, n);
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
  *area = 0.0;
  for (int i = 0; i < W->n; i++) {
    tidy(W, i, tol);
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
  if (!status && (!ntri || !nnew || !tarea || !whole)) status = MX_EINPUT;
  size_t cut_n = 0, pieces_n = 0, kept = 0, in_n = 0, out_n = 0, copies = 0, turned = 0,
         capped = 0;
  int oom = 0;
  if (!status) {
#pragma omp parallel reduction(+ : cut_n, pieces_n, kept, in_n, out_n, copies, turned, capped) \
    reduction(| : oom)
    {
      pieces *W = mx_alloc(sizeof *W);
      uint8_t verdict[MAXP];
      if (!W) oom = 1;
#pragma omp for schedule(dynamic, 64)
      for (size_t t = 0; t < nt; t++) {
        if (!W) continue;
        const int np = triangle_pieces(s, Wn, &R, (uint32_t)t, W, verdict, &tarea[t]);
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
    if (oom) status = MX_EINPUT;
  }
  /* offsets, then the output in the triangles' order */
  uint64_t tot_t = 0, tot_v = s->nv;
  uint64_t *toff = NULL, *voff = NULL;
  if (!status) {
    toff = mx_alloc((nt + 1) * sizeof *toff);
    voff = mx_alloc((nt + 1) * sizeof *voff);
    if (!toff || !voff) status = MX_EINPUT;
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
        if (whole[t] != 255) { /* the triangle itself */
          const uint32_t *v = s->tri + 3 * t;
          o[0] = v[0];
          o[1] = whole[t] == KEEP_TURNED ? v[2] : v[1];
          o[2] = whole[t] == KEEP_TURNED ? v[1] : v[2];
          sh[0] = s->shell[t];
          continue;
        }
        if (!W) W = mx_alloc(sizeof *W);
        if (!W) {
          oom = 1;
          continue;
        }
        double dummy;
        const int np = triangle_pieces(s, Wn, &R, (uint32_t)t, W, verdict, &dummy);
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
          }
        }
      }
      mx_free(W);
    }
    if (oom) status = MX_EINPUT;
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
  }
  mx_free(R.off);
  mx_free(R.adj);
  mx_free(ntri);
  mx_free(nnew);
  mx_free(tarea);
  mx_free(whole);
  mx_free(toff);
  mx_free(voff);
  return status;
}
