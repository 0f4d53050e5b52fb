/* The interfaces of a label image as one surface (geom/label_surface.h).
 *
 * Corners are named by the padded voxel whose lowest corner they are (a
 * face between two voxels never touches the padding's far sides), lattice
 * edges by 3 corner + axis. The quadrilaterals are found slice by slice in
 * parallel (counted, then written at their prefix: the same order for any
 * number of threads); their edges are sorted by lattice edge (radix), which
 * gives each edge its two to four faces: the corners' neighbours for the
 * smoothing, the junctions, and the shells (half-faces of one label joined
 * across each edge, then each shell's signed volume from the lattice
 * coordinates, exact in integers). */
#include <math.h>
#include <string.h>

#include "base/union_find.h"
#include "base/common.h"
#include "base/scan.h"
#include "geom/label_surface.h"

void mx_label_surface_free(mx_label_surface *S) {
  mx_free(S->xyz);
  mx_free(S->tri);
  mx_free(S->label);
  mx_free(S->keep);
  mx_free(S->corner);
  mx_free(S->lat);
  memset(S, 0, sizeof *S);
}

typedef struct {
  size_t nq;
  int64_t *corner; /* nq x 4 corners (padded voxel indices), counter-clockwise about the normal */
  int32_t *side;   /* nq x 2: the labels behind and in front of the normal */
  uint8_t *axis;   /* nq: the normal's axis */
} quads;

static int find_quads(const int32_t *lab, const int64_t n[3], quads *Q) {
  const int64_t st[3] = {1, n[0], n[0] * n[1]};
  const int64_t nk = n[2];
  uint64_t *cnt = mx_calloc(((size_t)nk + 1) * sizeof *cnt);
  if (!cnt) return MX_ENOMEM;
#pragma omp parallel for schedule(dynamic, 4)
  for (int64_t k = 0; k < nk; k++) {
    uint64_t c = 0;
    for (int64_t j = 0; j < n[1]; j++)
      for (int64_t i = 0; i < n[0]; i++) {
        const int64_t v = i + n[0] * (j + n[1] * k), ijk[3] = {i, j, k};
        for (int a = 0; a < 3; a++)
          if (ijk[a] + 1 < n[a] && lab[v] != lab[v + st[a]]) c++;
      }
    cnt[k] = c;
  }
  Q->nq = mx_scan_u64(cnt, (size_t)nk + 1);
  Q->corner = mx_alloc((Q->nq * 4 + 1) * sizeof *Q->corner);
  Q->side = mx_alloc((Q->nq * 2 + 1) * sizeof *Q->side);
  Q->axis = mx_alloc(Q->nq + 1);
  if (!Q->corner || !Q->side || !Q->axis) {
    mx_free(cnt);
    return MX_ENOMEM;
  }
#pragma omp parallel for schedule(dynamic, 4)
  for (int64_t k = 0; k < nk; k++) {
    uint64_t q = cnt[k];
    for (int64_t j = 0; j < n[1]; j++)
      for (int64_t i = 0; i < n[0]; i++) {
        const int64_t v = i + n[0] * (j + n[1] * k), ijk[3] = {i, j, k};
        for (int a = 0; a < 3; a++) {
          if (ijk[a] + 1 >= n[a] || lab[v] == lab[v + st[a]]) continue;
          const int u = (a + 1) % 3, w = (a + 2) % 3;
          const int64_t base = v + st[a];
          int64_t *c = Q->corner + 4 * q;
          c[0] = base;
          c[1] = base + st[u];
          c[2] = base + st[u] + st[w];
          c[3] = base + st[w];
          Q->side[2 * q] = lab[v];
          Q->side[2 * q + 1] = lab[v + st[a]];
          Q->axis[q] = (uint8_t)a;
          q++;
        }
      }
  }
  mx_free(cnt);
  return MX_OK;
}

/* The lattice edge from corner c0 to the next corner c1 of a quad: its
 * lowest corner and axis. */
static uint64_t edge_id(const int64_t n[3], int64_t c0, int64_t c1) {
  const int64_t lo = c0 < c1 ? c0 : c1, d = c0 < c1 ? c1 - c0 : c0 - c1;
  const int axis = d == 1 ? 0 : d == n[0] ? 1 : 2;
  return 3 * (uint64_t)lo + (uint64_t)axis;
}

typedef struct {
  uint32_t nb[6];
  uint8_t nnb, njunction;
} vlinks;

int mx_label_surface_build(const int32_t *lab, const int64_t n[3], const double A[12],
                           int rounds, double clamp, mx_label_surface *S) {
  memset(S, 0, sizeof *S);
  quads Q;
  memset(&Q, 0, sizeof Q);
  int st = find_quads(lab, n, &Q);
  const size_t nq = Q.nq, total = (size_t)(n[0] * n[1] * n[2]);
  uint32_t *vid = NULL, *rec = NULL, *up = NULL;
  uint64_t *key = NULL;
  int64_t *vcorner = NULL;
  double *p = NULL, *p2 = NULL;
  vlinks *L = NULL;
  int64_t *shellvol = NULL;
  if (st) goto done;

  /* corners in use, numbered in corner order */
  vid = mx_calloc((total + 1) * (sizeof *vid));
  if (!vid) goto oom;
  for (size_t q = 0; q < 4 * nq; q++) vid[Q.corner[q]] = 1;
  size_t nv = 0;
  for (size_t c = 0; c < total; c++)
    if (vid[c]) vid[c] = (uint32_t)++nv; /* id + 1 */
  vcorner = mx_alloc((nv + 1) * sizeof *vcorner);
  if (!vcorner) goto oom;
  for (size_t c = 0; c < total; c++)
    if (vid[c]) vcorner[vid[c] - 1] = (int64_t)c;

  /* quad edges sorted by lattice edge */
  key = mx_alloc((4 * nq + 1) * sizeof *key);
  rec = mx_alloc((4 * nq + 1) * sizeof *rec);
  L = mx_calloc((nv + 1) * (sizeof *L));
  up = mx_alloc((2 * nq + 1) * sizeof *up);
  if (!key || !rec || !L || !up) goto oom;
  for (size_t q = 0; q < nq; q++)
    for (int e = 0; e < 4; e++) {
      key[4 * q + e] = edge_id(n, Q.corner[4 * q + e], Q.corner[4 * q + (e + 1) % 4]);
      rec[4 * q + e] = (uint32_t)(4 * q + e);
    }
  if (mx_sort_u64(key, rec, 4 * nq)) goto oom;
  for (size_t h = 0; h < 2 * nq; h++) up[h] = (uint32_t)h;
  for (size_t g = 0; g < 4 * nq;) {
    size_t e = g + 1;
    while (e < 4 * nq && key[e] == key[g]) e++;
    /* the lattice edge key[g]: faces rec[g .. e) */
    const uint32_t q0 = rec[g] / 4, e0 = rec[g] % 4;
    const uint32_t a = vid[Q.corner[4 * q0 + e0]] - 1, b = vid[Q.corner[4 * q0 + (e0 + 1) % 4]] - 1;
    const int junction = e - g >= 3;
    vlinks *la = &L[a], *lb = &L[b];
    if (la->nnb < 6) la->nb[la->nnb++] = b;
    if (lb->nnb < 6) lb->nb[lb->nnb++] = a;
    if (junction) {
      /* junction neighbours first: swap them to the front */
      la->nb[la->nnb - 1] = la->nb[la->njunction];
      la->nb[la->njunction++] = b;
      lb->nb[lb->nnb - 1] = lb->nb[lb->njunction];
      lb->nb[lb->njunction++] = a;
    }
    /* the half-faces of one label around the edge join */
    for (size_t x = g; x < e; x++)
      for (int sx = 0; sx < 2; sx++) {
        const uint32_t qx = rec[x] / 4;
        const int32_t lx = Q.side[2 * qx + sx];
        for (size_t y = x + 1; y < e; y++)
          for (int sy = 0; sy < 2; sy++) {
            const uint32_t qy = rec[y] / 4;
            if (Q.side[2 * qy + sy] == lx) mx_uf_join(up, 2 * qx + sx, 2 * qy + sy);
          }
      }
    g = e;
  }
  mx_free(key);
  mx_free(rec);
  key = NULL;
  rec = NULL;
  for (size_t h = 0; h < 2 * nq; h++) up[h] = mx_uf_find(up, (uint32_t)h); /* read-only below */

  /* shells' signed volumes, 3 V = sum of +-(the plane's coordinate) */
  shellvol = mx_calloc((2 * nq + 1) * (sizeof *shellvol));
  if (!shellvol) goto oom;
  for (size_t q = 0; q < nq; q++) {
    const int64_t c = Q.corner[4 * q];
    const int a = Q.axis[q];
    const int64_t coord = a == 0 ? c % n[0] : a == 1 ? (c / n[0]) % n[1] : c / (n[0] * n[1]);
    shellvol[up[2 * q]] += coord;     /* outward from side 0 */
    shellvol[up[2 * q + 1]] -= coord; /* side 1: reversed */
  }

  /* the smoothing, in lattice coordinates */
  p = mx_alloc((3 * nv + 1) * sizeof *p);
  p2 = mx_alloc((3 * nv + 1) * sizeof *p2);
  if (!p || !p2) goto oom;
  for (size_t v = 0; v < nv; v++) {
    const int64_t c = vcorner[v];
    p[3 * v] = (double)(c % n[0]);
    p[3 * v + 1] = (double)((c / n[0]) % n[1]);
    p[3 * v + 2] = (double)(c / (n[0] * n[1]));
  }
  for (size_t v = 0; v < nv; v++) {
    if (L[v].njunction) S->junction_vertices++;
    if (L[v].njunction && L[v].njunction != 2) S->fixed_vertices++;
  }
  for (int r = 0; r < 2 * rounds; r++) {
    const double f = r % 2 ? -0.53 : 0.5;
#pragma omp parallel for schedule(static)
    for (size_t v = 0; v < nv; v++) {
      const vlinks *l = &L[v];
      const int m = l->njunction ? (l->njunction == 2 ? 2 : 0) : l->nnb;
      const int64_t c = vcorner[v];
      const double o[3] = {(double)(c % n[0]), (double)((c / n[0]) % n[1]),
                           (double)(c / (n[0] * n[1]))};
      for (int a = 0; a < 3; a++) {
        double x = p[3 * v + a];
        if (m) {
          double s = 0;
          for (int t = 0; t < m; t++) s += p[3 * l->nb[t] + a];
          x += f * (s / m - x);
        }
        if (x > o[a] + clamp) x = o[a] + clamp;
        if (x < o[a] - clamp) x = o[a] - clamp;
        p2[3 * v + a] = x;
      }
    }
    double *t = p;
    p = p2;
    p2 = t;
  }
  for (size_t v = 0; v < nv; v++) {
    const int64_t c = vcorner[v];
    const double o[3] = {(double)(c % n[0]), (double)((c / n[0]) % n[1]),
                         (double)(c / (n[0] * n[1]))};
    for (int a = 0; a < 3; a++)
      if (fabs(p[3 * v + a] - o[a]) > S->max_move) S->max_move = fabs(p[3 * v + a] - o[a]);
  }

  /* triangles and the world */
  S->nv = nv;
  S->nt = 2 * nq;
  S->xyz = mx_alloc((3 * nv + 1) * sizeof *S->xyz);
  S->tri = mx_alloc((3 * S->nt + 1) * sizeof *S->tri);
  S->label = mx_alloc((2 * S->nt + 1) * sizeof *S->label);
  S->keep = mx_alloc(S->nt + 1);
  if (!S->xyz || !S->tri || !S->label || !S->keep) goto oom;
  const double det = A[0] * (A[5] * A[10] - A[6] * A[9]) - A[1] * (A[4] * A[10] - A[6] * A[8]) +
                     A[2] * (A[4] * A[9] - A[5] * A[8]);
  const int flip = det < 0;
#pragma omp parallel for schedule(static)
  for (size_t v = 0; v < nv; v++) {
    const double u[3] = {p[3 * v] - 1.5, p[3 * v + 1] - 1.5, p[3 * v + 2] - 1.5};
    for (int r = 0; r < 3; r++)
      S->xyz[3 * v + r] = A[4 * r] * u[0] + A[4 * r + 1] * u[1] + A[4 * r + 2] * u[2] + A[4 * r + 3];
  }
#pragma omp parallel for schedule(static)
  for (size_t q = 0; q < nq; q++) {
    uint32_t c[4];
    for (int e = 0; e < 4; e++) c[e] = vid[Q.corner[4 * q + e]] - 1;
    double d02 = 0, d13 = 0;
    for (int a = 0; a < 3; a++) {
      const double x = S->xyz[3 * c[0] + a] - S->xyz[3 * c[2] + a];
      const double y = S->xyz[3 * c[1] + a] - S->xyz[3 * c[3] + a];
      d02 += x * x;
      d13 += y * y;
    }
    const int s = d13 < d02; /* split by 1-3 */
    uint32_t t[6] = {c[s], c[s + 1], c[(s + 2) % 4], c[s], c[(s + 2) % 4], c[(s + 3) % 4]};
    if (flip)
      for (int k = 0; k < 2; k++) {
        const uint32_t x = t[3 * k + 1];
        t[3 * k + 1] = t[3 * k + 2];
        t[3 * k + 2] = x;
      }
    memcpy(S->tri + 6 * q, t, sizeof t);
    uint8_t keep = 0;
    for (int side = 0; side < 2; side++)
      if (Q.side[2 * q + side] != 0 && shellvol[up[2 * q + side]] > 0)
        keep |= (uint8_t)(1u << side);
    for (int k = 0; k < 2; k++) {
      S->label[2 * (2 * q + k)] = Q.side[2 * q];
      S->label[2 * (2 * q + k) + 1] = Q.side[2 * q + 1];
      S->keep[2 * q + k] = keep;
    }
  }
  S->corner = vcorner;
  S->lat = p;
  vcorner = NULL;
  p = NULL;
  goto done;
oom:
  st = MX_ENOMEM;
  mx_label_surface_free(S);
done:
  mx_free(Q.corner);
  mx_free(Q.side);
  mx_free(Q.axis);
  mx_free(vid);
  mx_free(vcorner);
  mx_free(key);
  mx_free(rec);
  mx_free(L);
  mx_free(up);
  mx_free(shellvol);
  mx_free(p);
  mx_free(p2);
  return st;
}
