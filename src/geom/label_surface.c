/* The interfaces of a label image smoothed (geom/label_surface.h).
 *
 * No surface is built: a lattice edge lies on the interfaces when two or
 * more of the four voxels around it, taken in turn, differ from the next
 * (each such pair is a voxel face on the edge), and on a junction when
 * three or four do. A corner is on the interfaces when one of its six
 * edges is; its neighbours on the surface are the other ends of those
 * edges. Every pass runs over corners in parallel and writes only its own
 * corner's entries (positions read from the previous round), so the result
 * does not depend on the threads. */
#include <math.h>
#include <string.h>

#include "base/common.h"
#include "base/scan.h"
#include "geom/label_surface.h"

void mx_label_surface_free(mx_label_surface *S) {
  mx_free(S->corner);
  mx_free(S->lat);
  memset(S, 0, sizeof *S);
}

/* Voxel faces on the edge from corner c along axis a (0 .. 4); 0 when the
 * edge leaves the array. */
static int edge_faces(const int32_t *lab, const int64_t n[3], int64_t c, const int64_t ijk[3],
                      int a) {
  const int64_t st[3] = {1, n[0], n[0] * n[1]};
  const int u = (a + 1) % 3, w = (a + 2) % 3;
  if (ijk[a] + 1 > n[a] - 1 || ijk[u] < 1 || ijk[w] < 1) return 0;
  const int32_t l11 = lab[c], l10 = lab[c - st[w]], l01 = lab[c - st[u]],
                l00 = lab[c - st[u] - st[w]];
  return (l00 != l10) + (l10 != l11) + (l11 != l01) + (l01 != l00);
}

typedef struct {
  uint32_t nb[6];
  uint8_t nnb, njunction; /* junction neighbours first */
} vlinks;

int mx_label_surface_build(const int32_t *lab, const int64_t n[3], int rounds, double clamp,
                           mx_label_surface *S) {
  memset(S, 0, sizeof *S);
  const int64_t total = n[0] * n[1] * n[2], st[3] = {1, n[0], n[0] * n[1]};
  /* the corners on an interface: counted per slice, numbered in order */
  uint64_t *cnt = mx_calloc(((size_t)n[2] + 1) * sizeof *cnt);
  uint32_t *vid = mx_alloc(((size_t)total + 1) * sizeof *vid);
  if (!cnt || !vid) {
    mx_free(cnt);
    mx_free(vid);
    return MX_ENOMEM;
  }
#pragma omp parallel for schedule(static)
  for (int64_t k = 0; k < n[2]; k++) {
    uint64_t c = 0;
    for (int64_t j = 0; j < n[1]; j++)
      for (int64_t i = 0; i < n[0]; i++) {
        const int64_t v = i + n[0] * (j + n[1] * k), ijk[3] = {i, j, k};
        int on = 0;
        for (int a = 0; a < 3 && !on; a++) {
          on = edge_faces(lab, n, v, ijk, a) >= 2;
          if (!on && ijk[a] >= 1) { /* the edge arriving along a */
            int64_t p[3] = {i, j, k};
            p[a]--;
            on = edge_faces(lab, n, v - st[a], p, a) >= 2;
          }
        }
        vid[v] = on ? 1u : 0u;
        c += (uint64_t)on;
      }
    cnt[k] = c;
  }
  const size_t nv = (size_t)mx_scan_u64(cnt, (size_t)n[2] + 1);
  S->corner = mx_alloc((nv + 1) * sizeof *S->corner);
  S->lat = mx_alloc((3 * nv + 1) * sizeof *S->lat);
  double *p2 = mx_alloc((3 * nv + 1) * sizeof *p2);
  vlinks *L = mx_calloc((nv + 1) * sizeof *L);
  if (!S->corner || !S->lat || !p2 || !L) {
    mx_free(cnt);
    mx_free(vid);
    mx_free(p2);
    mx_free(L);
    mx_label_surface_free(S);
    return MX_ENOMEM;
  }
  S->nv = nv;
#pragma omp parallel for schedule(static)
  for (int64_t k = 0; k < n[2]; k++) {
    uint64_t id = cnt[k];
    for (int64_t j = 0; j < n[1]; j++)
      for (int64_t i = 0; i < n[0]; i++) {
        const int64_t v = i + n[0] * (j + n[1] * k);
        if (!vid[v]) {
          vid[v] = UINT32_MAX;
          continue;
        }
        vid[v] = (uint32_t)id;
        S->corner[id] = v;
        S->lat[3 * id] = (double)i;
        S->lat[3 * id + 1] = (double)j;
        S->lat[3 * id + 2] = (double)k;
        id++;
      }
  }
  mx_free(cnt);
  /* each corner's neighbours on the surface, junctions first */
#pragma omp parallel for schedule(static)
  for (size_t x = 0; x < nv; x++) {
    const int64_t v = S->corner[x];
    const int64_t ijk[3] = {v % n[0], (v / n[0]) % n[1], v / (n[0] * n[1])};
    vlinks *l = &L[x];
    uint32_t other[6];
    int no = 0;
    for (int a = 0; a < 3; a++)
      for (int s = 0; s < 2; s++) {
        int64_t p[3] = {ijk[0], ijk[1], ijk[2]};
        int64_t from = v, to = v + st[a];
        if (s) {
          if (ijk[a] < 1) continue;
          p[a]--;
          from = v - st[a];
          to = v - st[a];
        }
        const int f = edge_faces(lab, n, from, p, a);
        if (f < 2) continue;
        const uint32_t y = vid[to];
        if (f >= 3)
          l->nb[l->njunction++] = y;
        else
          other[no++] = y;
      }
    l->nnb = l->njunction;
    for (int t = 0; t < no; t++) l->nb[l->nnb++] = other[t];
  }
  mx_free(vid);
  for (size_t x = 0; x < nv; x++) {
    if (L[x].njunction) S->junction_vertices++;
    if (L[x].njunction && L[x].njunction != 2) S->fixed_vertices++;
  }
  /* Taubin rounds: lambda 0.5, mu -0.53; a corner on a junction averages
   * its two junction neighbours only, a junction's end stays */
  double *p = S->lat;
  for (int r = 0; r < 2 * rounds; r++) {
    const double f = r % 2 ? -0.53 : 0.5;
#pragma omp parallel for schedule(static)
    for (size_t x = 0; x < nv; x++) {
      const vlinks *l = &L[x];
      const int m = l->njunction ? (l->njunction == 2 ? 2 : 0) : l->nnb;
      const int64_t c = S->corner[x];
      const double o[3] = {(double)(c % n[0]), (double)((c / n[0]) % n[1]),
                           (double)(c / (n[0] * n[1]))};
      for (int a = 0; a < 3; a++) {
        double y = p[3 * x + a];
        if (m) {
          double s = 0;
          for (int t = 0; t < m; t++) s += p[3 * l->nb[t] + a];
          y += f * (s / m - y);
        }
        if (y > o[a] + clamp) y = o[a] + clamp;
        if (y < o[a] - clamp) y = o[a] - clamp;
        p2[3 * x + a] = y;
      }
    }
    double *t = p;
    p = p2;
    p2 = t;
  }
  S->lat = p;
  mx_free(p2);
  mx_free(L);
  for (size_t x = 0; x < nv; x++) {
    const int64_t c = S->corner[x];
    const double o[3] = {(double)(c % n[0]), (double)((c / n[0]) % n[1]),
                         (double)(c / (n[0] * n[1]))};
    for (int a = 0; a < 3; a++)
      if (fabs(p[3 * x + a] - o[a]) > S->max_move) S->max_move = fabs(p[3 * x + a] - o[a]);
  }
  return MX_OK;
}
