/* Several materials: one input holding several regions (mesher/materials.h,
 * mx_materials_split_complex). A surface with internal faces, a cube split
 * in two by a square, say (a "polyhedral complex"), has edges used by three
 * triangles or more. Around each such edge its triangles are sorted by
 * angle; between two triangles next to each other lies a wedge of one
 * region, so the side of each facing the wedge belongs to that region's
 * boundary. Joining these sides across every edge (manifold edges join
 * their two triangles' sides alike) gives the sides of each region's
 * boundary as connected sets: those enclosing a negative volume (the sides
 * facing into what they bound) are the regions' outer shells. Each becomes
 * an input of its own, turned outward and named after the file ("FILE region
 * 1", ...); an internal face then lies in two of them, and the touching
 * inputs' path (material_inputs.c) makes it their interface. A region with
 * an empty hole inside it is not told from one without. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "base/union_find.h"
#include "base/common.h"
#include "mesher/materials.h"
#include "mesher/mesher_impl.h"

typedef struct {
  uint32_t a, b; /* the edge's welded ends, a < b */
  uint32_t t;    /* a triangle using it */
} edge_use;

static int cmp_use(const void *x, const void *y) {
  const edge_use *p = x, *q = y;
  if (p->a != q->a) return p->a < q->a ? -1 : 1;
  if (p->b != q->b) return p->b < q->b ? -1 : 1;
  return (p->t > q->t) - (p->t < q->t);
}

static void sub(const double *p, const double *q, double *r) {
  for (int i = 0; i < 3; i++) r[i] = p[i] - q[i];
}

static void cross(const double *u, const double *v, double *r) {
  r[0] = u[1] * v[2] - u[2] * v[1];
  r[1] = u[2] * v[0] - u[0] * v[2];
  r[2] = u[0] * v[1] - u[1] * v[0];
}

static double dot(const double *u, const double *v) {
  return u[0] * v[0] + u[1] * v[1] + u[2] * v[2];
}

typedef struct {
  uint32_t t;
  double angle;
  double w[3]; /* the triangle's direction away from the edge, across it */
  int side;    /* +1 when its own normal turns the way angles grow */
} around;

static int cmp_around(const void *x, const void *y) {
  const around *p = x, *q = y;
  if (p->angle != q->angle) return p->angle < q->angle ? -1 : 1;
  return (p->t > q->t) - (p->t < q->t);
}

/* Half-face of triangle t: 2 t (its normal's side), 2 t + 1 (the other). */
static int split_file(mx_mesher *m, int file, const uint32_t *to, mx_trisoup *out,
                      int *nregions) {
  const mx_trisoup *d = &m->domain;
  const size_t nt = d->nt;
  size_t n = 0;
  for (size_t t = 0; t < nt; t++) n += d->shell[t] == file;
  edge_use *E = mx_alloc((3 * n + 1) * sizeof *E);
  uint32_t *up = mx_alloc((2 * nt + 1) * sizeof *up);
  around *R = NULL;
  if (!E || !up) {
    mx_free(E);
    mx_free(up);
    return MX_ENOMEM;
  }
  size_t k = 0;
  for (size_t t = 0; t < nt; t++) {
    up[2 * t] = (uint32_t)(2 * t);
    up[2 * t + 1] = (uint32_t)(2 * t + 1);
    if (d->shell[t] != file) continue;
    for (int e = 0; e < 3; e++) {
      const uint32_t a = to[d->tri[3 * t + e]], b = to[d->tri[3 * t + (e + 1) % 3]];
      E[k].a = a < b ? a : b;
      E[k].b = a < b ? b : a;
      E[k].t = (uint32_t)t;
      k++;
    }
  }
  qsort(E, k, sizeof *E, cmp_use);
  size_t most = 2;
  for (size_t i = 0, j; i < k; i = j) {
    for (j = i + 1; j < k && E[j].a == E[i].a && E[j].b == E[i].b; j++) {
    }
    if (j - i > most) most = j - i;
  }
  R = mx_alloc((most + 1) * sizeof *R);
  if (!R) {
    mx_free(E);
    mx_free(up);
    return MX_ENOMEM;
  }
  /* around each edge: the triangles by angle, neighbours' facing sides joined */
  for (size_t i = 0, j; i < k; i = j) {
    for (j = i + 1; j < k && E[j].a == E[i].a && E[j].b == E[i].b; j++) {
    }
    const size_t c = j - i;
    if (c < 2) continue; /* an open edge: the input policy names it */
    double pa[3] = {d->x[E[i].a], d->y[E[i].a], d->z[E[i].a]};
    double pb[3] = {d->x[E[i].b], d->y[E[i].b], d->z[E[i].b]};
    double dir[3], u[3], v[3], tmp[3] = {1, 0, 0};
    sub(pb, pa, dir);
    const double len = sqrt(dot(dir, dir));
    for (int x = 0; x < 3; x++) dir[x] /= len;
    if (fabs(dir[0]) > 0.6) tmp[0] = 0, tmp[1] = 1;
    cross(dir, tmp, u);
    const double lu = sqrt(dot(u, u));
    for (int x = 0; x < 3; x++) u[x] /= lu;
    cross(dir, u, v);
    for (size_t q = 0; q < c; q++) {
      const uint32_t t = E[i + q].t;
      const uint32_t *tv = d->tri + 3 * (size_t)t;
      double p[3][3];
      int third = 0;
      for (int x = 0; x < 3; x++) {
        const uint32_t w = to[tv[x]];
        p[x][0] = d->x[w], p[x][1] = d->y[w], p[x][2] = d->z[w];
        if (w != E[i].a && w != E[i].b) third = x;
      }
      double w[3], e1[3], e2[3], nrm[3], turn[3];
      sub(p[third], pa, w);
      const double along = dot(w, dir);
      for (int x = 0; x < 3; x++) w[x] -= along * dir[x];
      R[q].t = t;
      R[q].angle = atan2(dot(w, v), dot(w, u));
      memcpy(R[q].w, w, sizeof w);
      sub(p[1], p[0], e1);
      sub(p[2], p[0], e2);
      cross(e1, e2, nrm);
      cross(dir, w, turn); /* the way angles grow, at this triangle */
      R[q].side = dot(nrm, turn) > 0.0 ? 1 : -1;
    }
    qsort(R, c, sizeof *R, cmp_around);
    for (size_t q = 0; q < c; q++) {
      const around *s = &R[q], *nx = &R[(q + 1) % c];
      /* the wedge from s to nx: s's side turning forward, nx's backward */
      const uint32_t hs = 2 * s->t + (s->side > 0 ? 0 : 1);
      const uint32_t hn = 2 * nx->t + (nx->side > 0 ? 1 : 0);
      mx_uf_join(up, hs, hn);
    }
  }
  mx_free(R);
  mx_free(E);
  /* each set of sides: its volume with the sides' orientation; negative,
   * a region's outer shell (turned outward) */
  double *vol = mx_calloc((2 * nt + 1) * sizeof *vol);
  int32_t *region = mx_alloc((2 * nt + 1) * sizeof *region);
  if (!vol || !region) {
    mx_free(vol);
    mx_free(region);
    mx_free(up);
    return MX_ENOMEM;
  }
  for (size_t t = 0; t < nt; t++) {
    if (d->shell[t] != file) continue;
    const uint32_t *tv = d->tri + 3 * t;
    const double a[3] = {d->x[tv[0]], d->y[tv[0]], d->z[tv[0]]};
    const double b[3] = {d->x[tv[1]], d->y[tv[1]], d->z[tv[1]]};
    const double c[3] = {d->x[tv[2]], d->y[tv[2]], d->z[tv[2]]};
    double bc[3];
    cross(b, c, bc);
    const double v6 = dot(a, bc) / 6.0;
    vol[mx_uf_find(up, (uint32_t)(2 * t))] += v6;
    vol[mx_uf_find(up, (uint32_t)(2 * t + 1))] -= v6;
  }
  for (size_t h = 0; h < 2 * nt; h++) region[h] = -1;
  int nr = 0;
  int st = MX_OK;
  for (size_t t = 0; t < nt && !st; t++) {
    if (d->shell[t] != file) continue;
    for (int s = 0; s < 2 && !st; s++) {
      const uint32_t r = mx_uf_find(up, (uint32_t)(2 * t + (size_t)s));
      if (!(vol[r] < 0.0)) continue;
      if (region[r] < 0) region[r] = nr++;
      /* the side facing into the region, turned outward: the reverse */
      const uint32_t *tv = d->tri + 3 * t;
      if (s == 0)
        st = mx_trisoup_add_triangle(out, tv[0], tv[2], tv[1]);
      else
        st = mx_trisoup_add_triangle(out, tv[0], tv[1], tv[2]);
      if (!st) out->shell[out->nt - 1] = (uint16_t)region[r];
    }
  }
  *nregions = nr;
  mx_free(vol);
  mx_free(region);
  mx_free(up);
  return st;
}

static int drop_file(const mx_trisoup *s, size_t t, void *ctx) {
  return s->shell[t] == *(const int *)ctx;
}

int mx_materials_split_complex(mx_mesher *m, const uint32_t *to) {
  mx_trisoup *d = &m->domain;
  const int nfiles = m->ndomain;
  for (int f = 0; f < nfiles; f++) {
    /* does the file have an edge of three triangles or more? */
    size_t n = 0;
    for (size_t t = 0; t < d->nt; t++) n += d->shell[t] == f;
    edge_use *E = mx_alloc((3 * n + 1) * sizeof *E);
    if (!E) return MX_ENOMEM;
    size_t k = 0;
    for (size_t t = 0; t < d->nt; t++) {
      if (d->shell[t] != f) continue;
      for (int e = 0; e < 3; e++) {
        const uint32_t a = to[d->tri[3 * t + e]], b = to[d->tri[3 * t + (e + 1) % 3]];
        E[k].a = a < b ? a : b, E[k].b = a < b ? b : a, E[k].t = (uint32_t)t;
        k++;
      }
    }
    qsort(E, k, sizeof *E, cmp_use);
    int complex = 0;
    for (size_t i = 0; i + 2 < k && !complex; i++)
      complex = E[i].a == E[i + 2].a && E[i].b == E[i + 2].b;
    mx_free(E);
    if (!complex) continue;
    mx_trisoup out;
    memset(&out, 0, sizeof out);
    int nr = 0;
    int st = mx_trisoup_reserve(&out, d->nv, 0);
    for (size_t v = 0; v < d->nv && !st; v++) {
      const double c[3] = {d->x[v], d->y[v], d->z[v]};
      st = mx_trisoup_set_vertex(&out, v, c);
    }
    if (!st) st = split_file(m, f, to, &out, &nr);
    if (!st && nr < 1) {
      mx_error(m->domain_name[f], 0, "materials: no region bounded by this surface");
      st = MX_EINPUT;
    }
    if (!st && m->ndomain + nr - 1 > 64) {
      mx_error(m->domain_name[f], 0, "materials: %d regions in this surface, more than the "
                                     "64 inputs allowed", nr);
      st = MX_EINPUT;
    }
    /* region 0 keeps the file's place, the others are new inputs */
    int *ids = st ? NULL : mx_alloc((size_t)(nr + 1) * sizeof *ids);
    if (!st && !ids) st = MX_ENOMEM;
    char *file_name = st ? NULL : mx_strdup(m->domain_name[f]);
    if (!st && !file_name) st = MX_ENOMEM;
    for (int r = 0; r < nr && !st; r++) {
      ids[r] = r == 0 ? f : m->ndomain + r - 1;
      char name[4096];
      snprintf(name, sizeof name, "%s region %d", file_name, r + 1);
      char *nm = mx_strdup(name);
      if (!nm) st = MX_ENOMEM;
      else if (r == 0) {
        mx_free(m->domain_name[f]);
        m->domain_name[f] = nm;
      } else {
        m->domain_name[ids[r]] = nm;
      }
    }
    if (!st) {
      m->ndomain += nr - 1;
      for (size_t t = 0; t < out.nt; t++) out.shell[t] = (uint16_t)ids[out.shell[t]];
      int drop = f;
      mx_trisoup_remove_if(d, drop_file, &drop);
      const size_t before = d->nt;
      st = mx_trisoup_append(d, &out);
      if (!st) memcpy(d->shell + before, out.shell, out.nt * sizeof *out.shell);
    }
    mx_free(ids);
    mx_free(file_name);
    mx_trisoup_free(&out);
    MX_CHECK(st);
  }
  return MX_OK;
}
