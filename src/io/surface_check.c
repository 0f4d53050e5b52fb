/* Checks after reading: removes degenerate triangles and counts the edges
 * that are not shared by exactly two triangles (open or non-manifold). */
#include <stdlib.h>
#include <string.h>

#include "base/common.h"
#include "geom/surface_topology.h"
#include "soa/trisoup.h"

static int indices_valid(const mx_trisoup *s, const char *path) {
  for (size_t i = 0; i < 3 * s->nt; i++) {
    if (s->tri[i] < s->nv) continue;
    mx_error(path, 0, "internal error: triangle %zu uses vertex %u of %zu",
             i / 3, s->tri[i], s->nv);
    return MX_EINTERNAL;
  }
  return MX_OK;
}

/* Repeated vertex, or a cross product that is exactly zero (identical or
 * exactly collinear points). */
static int degenerate(const mx_trisoup *s, const uint32_t *t) {
  uint32_t a = t[0], b = t[1], c = t[2];
  if (a == b || b == c || a == c) return 1;
  double ux = s->x[b] - s->x[a], uy = s->y[b] - s->y[a], uz = s->z[b] - s->z[a];
  double vx = s->x[c] - s->x[a], vy = s->y[c] - s->y[a], vz = s->z[c] - s->z[a];
  return uy * vz - uz * vy == 0 && uz * vx - ux * vz == 0 &&
         ux * vy - uy * vx == 0;
}

/* For mx_trisoup_remove_if: drops degenerate triangles, naming the first. */
static int drop_degenerate(const mx_trisoup *s, size_t t, void *first) {
  if (!degenerate(s, s->tri + 3 * t)) return 0;
  char *name = first;
  if (!name[0]) mx_trisoup_name(s, t, name, 96);
  return 1;
}

int mx_trisoup_check(mx_trisoup *s, const char *path, size_t *open_edges) {
  if (open_edges) *open_edges = 0;
  MX_CHECK(indices_valid(s, path));
  char first[96] = "";
  size_t removed = mx_trisoup_remove_if(s, drop_degenerate, first);
  if (removed)
    mx_warning(path, 0,
               "removed %zu degenerate triangle%s (zero area or repeated "
               "vertex), the first: %s",
               removed, removed == 1 ? "" : "s", first);
  if (s->nt == 0) {
    mx_error(path, 0, "no triangles");
    return MX_EINPUT;
  }
  size_t open;
  MX_CHECK(mx_edges_open(s->tri, (uint32_t)s->nt, (uint32_t)s->nv, &open));
  /* an open surface is the input policy's to refuse or repair (mesher.c,
   * geom/surface_defects.c), with the places of its defects */
  if (open_edges) *open_edges = open;
  return MX_OK;
}

/* ---- shells that overlap ------------------------------------------------- */

typedef struct {
  uint64_t key;
  uint32_t tri;
} tri_key;

static int cmp_tri_key(const void *a, const void *b) {
  const tri_key *x = a, *y = b;
  if (x->key != y->key) return x->key < y->key ? -1 : 1;
  return (x->tri > y->tri) - (x->tri < y->tri);
}

static int cmp_point(const double *a, const double *b) {
  for (int k = 0; k < 3; k++)
    if (a[k] != b[k]) return a[k] < b[k] ? -1 : 1;
  return 0;
}

/* The triangle's three points in a canonical order (lexicographic). */
static void sorted_points(const mx_trisoup *s, uint32_t t, double p[3][3]) {
  for (int k = 0; k < 3; k++) {
    const uint32_t v = s->tri[3 * (size_t)t + k];
    p[k][0] = s->x[v];
    p[k][1] = s->y[v];
    p[k][2] = s->z[v];
  }
  for (int i = 0; i < 3; i++)
    for (int j = i + 1; j < 3; j++)
      if (cmp_point(p[j], p[i]) < 0) {
        double q[3];
        memcpy(q, p[i], sizeof q);
        memcpy(p[i], p[j], sizeof q);
        memcpy(p[j], q, sizeof q);
      }
}

int mx_trisoup_check_shells(const mx_trisoup *s, uint32_t nt, const char *const *names) {
  if (s->nshells < 2 || nt < 2) return MX_OK;
  tri_key *k = mx_alloc(nt * sizeof *k);
  if (!k) return MX_ENOMEM;
  for (uint32_t t = 0; t < nt; t++) {
    double p[3][3];
    sorted_points(s, t, p);
    uint64_t h = 1469598103934665603ull;
    const unsigned char *b = (const unsigned char *)p;
    for (size_t i = 0; i < sizeof p; i++) h = (h ^ b[i]) * 1099511628211ull;
    k[t] = (tri_key){h, t};
  }
  qsort(k, nt, sizeof *k, cmp_tri_key);
  int st = MX_OK;
  for (uint32_t i = 0; i + 1 < nt && st == MX_OK; i++) {
    for (uint32_t j = i + 1; j < nt && k[j].key == k[i].key; j++) {
      const uint32_t a = k[i].tri, b = k[j].tri;
      if (s->shell[a] == s->shell[b]) continue;
      double p[3][3], q[3][3];
      sorted_points(s, a, p);
      sorted_points(s, b, q);
      if (memcmp(p, q, sizeof p) != 0) continue;
      const uint32_t a0 = a < b ? a : b, b0 = a < b ? b : a;
      char na[96], nb[96];
      mx_trisoup_name(s, a0, na, sizeof na);
      mx_trisoup_name(s, b0, nb, sizeof nb);
      mx_error(names[s->shell[b0]], 0,
               "%s lies on %s of %s: the two surfaces overlap, so "
               "they do not bound a domain (give one of them, or separate them)",
               nb, na, names[s->shell[a0]]);
      st = MX_EINPUT;
      break;
    }
  }
  mx_free(k);
  return st;
}
