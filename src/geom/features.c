/* Sharp features of an input surface (geom/features.h). The welds come
 * from the vertices sorted by coordinates; the edges from their packed
 * welded ends sorted (radix), which gives each edge its triangles; the
 * chains from a union-find over the ridge edges joined at the vertices
 * that are not corners. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "base/common.h"
#include "base/scan.h"
#include "base/union_find.h"
#include "geom/features.h"

void mx_features_free(mx_features *F) {
  mx_free(F->edge);
  mx_free(F->corner);
  mx_free(F->patch);
  mx_free(F->open);
  memset(F, 0, sizeof *F);
}

/* A double as an unsigned key of the same order (-0 as 0). */
static uint64_t order_key(double x) {
  if (x == 0.0) x = 0.0;
  uint64_t u;
  memcpy(&u, &x, sizeof u);
  return u >> 63 ? ~u : u | (uint64_t)1 << 63;
}

static void normal(const mx_trisoup *s, const uint32_t *t, double n[3]) {
  const double u[3] = {s->x[t[1]] - s->x[t[0]], s->y[t[1]] - s->y[t[0]], s->z[t[1]] - s->z[t[0]]};
  const double v[3] = {s->x[t[2]] - s->x[t[0]], s->y[t[2]] - s->y[t[0]], s->z[t[2]] - s->z[t[0]]};
  n[0] = u[1] * v[2] - u[2] * v[1];
  n[1] = u[2] * v[0] - u[0] * v[2];
  n[2] = u[0] * v[1] - u[1] * v[0];
  const double l = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
  for (int a = 0; a < 3 && l > 0; a++) n[a] /= l;
}

static double edge_length(const mx_trisoup *s, const uint32_t *e) {
  const uint32_t a = e[0], b = e[1];
  return sqrt((s->x[a] - s->x[b]) * (s->x[a] - s->x[b]) + (s->y[a] - s->y[b]) * (s->y[a] - s->y[b]) +
              (s->z[a] - s->z[b]) * (s->z[a] - s->z[b]));
}

/* Peels the ridge edges with an end no other ridge edge meets, until none
 * is left (the ridges' 2-core: loops and the chains between them stay),
 * then the networks shorter than MX_FEATURE_MIN of the diagonal; deg[] and
 * the length follow. */
static int peel_dangling(const mx_trisoup *s, mx_features *F, uint32_t *deg) {
  const size_t ne = F->nedges, nv = s->nv;
  uint32_t *start = mx_calloc((nv + 2) * sizeof *start), *inc = mx_alloc((2 * ne + 1) * sizeof *inc);
  uint32_t *queue = mx_alloc((nv + 1) * sizeof *queue);
  uint8_t *gone = mx_calloc(ne + 1);
  if (!start || !inc || !queue || !gone) {
    mx_free(start);
    mx_free(inc);
    mx_free(queue);
    mx_free(gone);
    return MX_ENOMEM;
  }
  for (size_t i = 0; i < 2 * ne; i++) start[F->edge[i] + 1]++;
  for (size_t v = 0; v < nv; v++) start[v + 1] += start[v];
  for (size_t i = 0; i < 2 * ne; i++) inc[start[F->edge[i]]++] = (uint32_t)(i / 2);
  for (size_t v = nv; v > 0; v--) start[v] = start[v - 1];
  start[0] = 0;
  size_t nq = 0;
  for (size_t v = 0; v < nv; v++)
    if (deg[v] == 1) queue[nq++] = (uint32_t)v;
  while (nq) {
    const uint32_t v = queue[--nq];
    if (deg[v] != 1) continue;
    for (uint32_t j = start[v]; j < start[v + 1]; j++) {
      const uint32_t i = inc[j];
      if (gone[i]) continue;
      gone[i] = 1;
      const uint32_t w = F->edge[2 * i] == v ? F->edge[2 * i + 1] : F->edge[2 * i];
      deg[v]--;
      deg[w]--;
      if (deg[w] == 1) queue[nq++] = w;
      break;
    }
  }
  /* what is left, by connected network: those shorter than MX_FEATURE_MIN
   * of the surface's box diagonal go too (clusters of noise edges) */
  {
    double lo[3], hi[3];
    mx_trisoup_bbox(s, lo, hi);
    const double diag = sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                             (hi[2] - lo[2]) * (hi[2] - lo[2]));
    double *len = mx_calloc((nv + 1) * sizeof *len);
    uint32_t *up = queue; /* reused: a union-find over the vertices */
    if (!len) {
      mx_free(start);
      mx_free(inc);
      mx_free(queue);
      mx_free(gone);
      return MX_ENOMEM;
    }
    for (size_t v = 0; v < nv; v++) up[v] = (uint32_t)v;
    for (size_t i = 0; i < ne; i++)
      if (!gone[i]) mx_uf_join(up, F->edge[2 * i], F->edge[2 * i + 1]);
    for (size_t i = 0; i < ne; i++)
      if (!gone[i]) len[mx_uf_find(up, F->edge[2 * i])] += edge_length(s, F->edge + 2 * i);
    for (size_t i = 0; i < ne; i++)
      if (!gone[i] && len[mx_uf_find(up, F->edge[2 * i])] < MX_FEATURE_MIN * diag) {
        gone[i] = 1;
        deg[F->edge[2 * i]]--;
        deg[F->edge[2 * i + 1]]--;
      }
    mx_free(len);
  }
  size_t n = 0;
  F->length = 0.0;
  for (size_t i = 0; i < ne; i++) {
    if (gone[i]) continue;
    const uint32_t a = F->edge[2 * i], b = F->edge[2 * i + 1];
    F->edge[2 * n] = a;
    F->edge[2 * n + 1] = b;
    F->open[n++] = F->open[i];
    F->length += edge_length(s, F->edge + 2 * (n - 1));
  }
  F->dangling = ne - n;
  F->nedges = n;
  mx_free(start);
  mx_free(inc);
  mx_free(queue);
  mx_free(gone);
  return MX_OK;
}

int mx_features_detect(const mx_trisoup *s, size_t nt, double angle_deg, mx_features *F) {
  memset(F, 0, sizeof *F);
  const size_t nv = s->nv;
  const double cos_max = cos(angle_deg * M_PI / 180.0);
  uint32_t *weld = mx_alloc((nv + 1) * sizeof *weld), *order = mx_alloc((nv + 1) * sizeof *order);
  uint64_t *key = mx_alloc((3 * nt + 1) * sizeof *key);
  uint32_t *val = mx_alloc((3 * nt + 1) * sizeof *val);
  uint32_t *deg = mx_calloc((nv + 1) * sizeof *deg), *up = mx_alloc((3 * nt + 1) * sizeof *up);
  uint64_t *ck = mx_alloc((nv + 1) * sizeof *ck);
  uint32_t *e = NULL, *tup = mx_alloc((nt + 1) * sizeof *tup);
  F->patch = mx_alloc((nt + 1) * sizeof *F->patch);
  F->open = mx_alloc(3 * nt + 1);
  int st = weld && order && key && val && deg && up && ck && tup && F->patch && F->open ? MX_OK : MX_ENOMEM;
  if (st) goto done;
  /* welds: the first vertex (by index) of each run of equal coordinates */
  /* by x, then y, then z (stable radix passes from the last key), then index */
  for (size_t v = 0; v < nv; v++) order[v] = (uint32_t)v;
  const double *coord[3] = {s->z, s->y, s->x};
  for (int a = 0; a < 3 && !st; a++) {
    for (size_t i = 0; i < nv; i++) ck[i] = order_key(coord[a][order[i]]);
    if (mx_sort_u64(ck, order, nv)) st = MX_ENOMEM;
  }
  if (st) goto done;
  for (size_t i = 0; i < nv;) {
    size_t j = i + 1;
    while (j < nv && s->x[order[j]] == s->x[order[i]] && s->y[order[j]] == s->y[order[i]] &&
           s->z[order[j]] == s->z[order[i]])
      j++;
    for (size_t k = i; k < j; k++) weld[order[k]] = order[i]; /* the least index: sorted */
    i = j;
  }
  /* edges: (least end, other end), each with its triangle's side */
  for (size_t t = 0; t < nt; t++)
    for (int k = 0; k < 3; k++) {
      uint32_t a = weld[s->tri[3 * t + k]], b = weld[s->tri[3 * t + (k + 1) % 3]];
      if (a > b) {
        const uint32_t c = a;
        a = b;
        b = c;
      }
      key[3 * t + k] = (uint64_t)a << 32 | b;
      val[3 * t + k] = (uint32_t)t;
    }
  if (mx_sort_u64(key, val, 3 * nt)) {
    st = MX_ENOMEM;
    goto done;
  }
  for (size_t t = 0; t < nt; t++) tup[t] = (uint32_t)t;
  size_t cap = 64;
  e = mx_alloc(2 * cap * sizeof *e);
  if (!e) {
    st = MX_ENOMEM;
    goto done;
  }
  for (size_t g = 0; g < 3 * nt;) {
    size_t h = g + 1;
    while (h < 3 * nt && key[h] == key[g]) h++;
    const uint32_t a = (uint32_t)(key[g] >> 32), b = (uint32_t)key[g];
    int ridge = h - g != 2 || a == b;
    if (!ridge) {
      double n0[3], n1[3];
      normal(s, s->tri + 3 * (size_t)val[g], n0);
      normal(s, s->tri + 3 * (size_t)val[g + 1], n1);
      ridge = n0[0] * n1[0] + n0[1] * n1[1] + n0[2] * n1[2] < cos_max;
      if (!ridge) mx_uf_join(tup, val[g], val[g + 1]); /* one patch across it */
    }
    if (ridge && a != b) {
      if (F->nedges == cap) {
        uint32_t *g2 = mx_realloc(e, 4 * cap * sizeof *e);
        if (!g2) {
          st = MX_ENOMEM;
          goto done;
        }
        e = g2;
        cap *= 2;
      }
      e[2 * F->nedges] = a;
      e[2 * F->nedges + 1] = b;
      F->open[F->nedges++] = h - g != 2;
      deg[a]++;
      deg[b]++;
      F->length += sqrt((s->x[a] - s->x[b]) * (s->x[a] - s->x[b]) +
                        (s->y[a] - s->y[b]) * (s->y[a] - s->y[b]) +
                        (s->z[a] - s->z[b]) * (s->z[a] - s->z[b]));
    }
    g = h;
  }
  F->edge = e;
  e = NULL;
  /* patches: numbered at their least triangle, which is their root */
  for (size_t t = 0; t < nt; t++) {
    const uint32_t r = mx_uf_find(tup, (uint32_t)t);
    F->patch[t] = r == t ? (uint32_t)F->npatches++ : F->patch[r];
  }
  /* dangling ridges (a free end in a smooth part of the surface: the
   * noise of a scanned or segmented surface) peeled off, leaf by leaf */
  st = peel_dangling(s, F, deg);
  if (st) goto done;
  /* corners: ends, junctions, and turns by more than the angle */
  double *dir = mx_calloc((6 * (size_t)nv + 1) * sizeof *dir); /* two edge directions a vertex */
  if (!dir) {
    st = MX_ENOMEM;
    goto done;
  }
  for (size_t i = 0; i < F->nedges; i++)
    for (int end = 0; end < 2; end++) {
      const uint32_t v = F->edge[2 * i + end], w = F->edge[2 * i + 1 - end];
      if (deg[v] != 2) continue;
      double *d = dir + 6 * (size_t)v + (dir[6 * (size_t)v] != 0.0 || dir[6 * (size_t)v + 1] != 0.0 ||
                                                 dir[6 * (size_t)v + 2] != 0.0
                                             ? 3
                                             : 0);
      d[0] = s->x[w] - s->x[v];
      d[1] = s->y[w] - s->y[v];
      d[2] = s->z[w] - s->z[v];
    }
  size_t nc = 0;
  for (size_t v = 0; v < nv; v++) {
    int corner = deg[v] == 1 || deg[v] >= 3;
    if (deg[v] == 2) {
      const double *d = dir + 6 * v;
      const double l0 = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
      const double l1 = sqrt(d[3] * d[3] + d[4] * d[4] + d[5] * d[5]);
      /* straight on: the two directions opposed; a turn departs from that */
      const double c = -(d[0] * d[3] + d[1] * d[4] + d[2] * d[5]) / (l0 * l1);
      corner = c < cos_max;
    }
    deg[v] = corner ? UINT32_MAX : deg[v];
    nc += (size_t)corner;
  }
  mx_free(dir);
  F->corner = mx_alloc((nc + 1) * sizeof *F->corner);
  if (!F->corner) {
    st = MX_ENOMEM;
    goto done;
  }
  for (size_t v = 0; v < nv; v++)
    if (deg[v] == UINT32_MAX) F->corner[F->ncorners++] = (uint32_t)v;
  /* ridges: edges joined through the vertices that are not corners */
  for (size_t i = 0; i < F->nedges; i++) up[i] = (uint32_t)i;
  uint32_t *first = mx_alloc((nv + 1) * sizeof *first); /* an edge at each vertex */
  if (!first) {
    st = MX_ENOMEM;
    goto done;
  }
  for (size_t v = 0; v < nv; v++) first[v] = UINT32_MAX;
  for (size_t i = 0; i < F->nedges; i++)
    for (int end = 0; end < 2; end++) {
      const uint32_t v = F->edge[2 * i + end];
      if (deg[v] == UINT32_MAX) continue;
      if (first[v] == UINT32_MAX)
        first[v] = (uint32_t)i;
      else
        mx_uf_join(up, first[v], (uint32_t)i);
    }
  mx_free(first);
  for (size_t i = 0; i < F->nedges; i++) F->nridges += mx_uf_find(up, (uint32_t)i) == i;
done:
  mx_free(weld);
  mx_free(order);
  mx_free(key);
  mx_free(val);
  mx_free(deg);
  mx_free(up);
  mx_free(ck);
  mx_free(e);
  mx_free(tup);
  if (st) mx_features_free(F);
  return st;
}
