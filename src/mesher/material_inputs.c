/* Several materials: inputs that touch (mesher/materials.h,
 * mx_materials_split_shared). Two closed inputs glued along a face (two
 * cubes, the hemispheres of a brain) have the triangles of that face in
 * common: as the domain's boundary they would bound nothing (the face lies
 * inside the union), so the domain's soup keeps neither copy, and one copy
 * becomes a surface the octree refines at like the input surface (a region
 * refined where met only), whose pieces the boundary stage cleaves
 * (kernels/interfaces.h: the inputs as given are kept for the pieces). */
#include <string.h>

#include "base/common.h"
#include "mesher/materials.h"
#include "mesher/mesher_impl.h"

static int point_less(const double *p, const double *q) {
  return q[0] != p[0] ? p[0] < q[0] : q[1] != p[1] ? p[1] < q[1] : p[2] < q[2];
}

static void point_swap(double *p, double *q) {
  for (int i = 0; i < 3; i++) {
    const double x = p[i];
    p[i] = q[i];
    q[i] = x;
  }
}

/* A triangle's corners, sorted: the key of "the same triangle, in any
 * order and orientation". */
static void tri_key(const mx_trisoup *s, size_t t, double k[9]) {
  for (int c = 0; c < 3; c++) {
    const uint32_t v = s->tri[3 * t + c];
    k[3 * c] = s->x[v] == 0.0 ? 0.0 : s->x[v]; /* -0 as 0 */
    k[3 * c + 1] = s->y[v] == 0.0 ? 0.0 : s->y[v];
    k[3 * c + 2] = s->z[v] == 0.0 ? 0.0 : s->z[v];
  }
  if (point_less(k + 3, k)) point_swap(k, k + 3);
  if (point_less(k + 6, k + 3)) point_swap(k + 3, k + 6);
  if (point_less(k + 3, k)) point_swap(k, k + 3);
}

static uint64_t key_hash(const double k[9]) {
  uint64_t h = 0x9e3779b97f4a7c15ULL;
  for (int i = 0; i < 9; i++) {
    uint64_t u;
    memcpy(&u, &k[i], sizeof u);
    h ^= u + 0x9e3779b97f4a7c15ULL + (h << 6) + (h >> 2);
  }
  return h ^ (h >> 31);
}

/* to[v]: the first vertex with v's coordinates (mx_alloc). */
static int weld_map(const mx_trisoup *d, uint32_t **to_out) {
  size_t cap = 1024;
  while (cap < 2 * d->nv + 2) cap *= 2;
  uint32_t *slot = mx_alloc(cap * sizeof *slot), *to = mx_alloc((d->nv + 1) * sizeof *to);
  if (!slot || !to) {
    mx_free(slot);
    mx_free(to);
    return MX_ENOMEM;
  }
  for (size_t i = 0; i < cap; i++) slot[i] = UINT32_MAX;
  for (size_t v = 0; v < d->nv; v++) {
    double k[9] = {d->x[v] == 0.0 ? 0.0 : d->x[v], d->y[v] == 0.0 ? 0.0 : d->y[v],
                   d->z[v] == 0.0 ? 0.0 : d->z[v], 0, 0, 0, 0, 0, 0};
    size_t i = (size_t)key_hash(k) & (cap - 1);
    to[v] = (uint32_t)v;
    for (; slot[i] != UINT32_MAX; i = (i + 1) & (cap - 1)) {
      const uint32_t w = slot[i];
      if (d->x[w] == d->x[v] && d->y[w] == d->y[v] && d->z[w] == d->z[v]) {
        to[v] = w;
        break;
      }
    }
    if (to[v] == v) slot[i] = (uint32_t)v;
  }
  mx_free(slot);
  *to_out = to;
  return MX_OK;
}

/* Two inputs may meet only on common faces: a point of two inputs that is
 * not a corner of a common triangle (they touch at a point, or along an
 * edge) is refused, named. to: weld_map's. */
static int touch_check(const mx_mesher *m, const mx_trisoup *d, const uint8_t *shared,
                       const uint32_t *to) {
  uint64_t *files = mx_calloc((d->nv + 1) * sizeof *files);
  uint8_t *on = mx_calloc(d->nv + 1);
  if (!files || !on) {
    mx_free(files);
    mx_free(on);
    return MX_ENOMEM;
  }
  for (size_t t = 0; t < d->nt; t++)
    for (int k = 0; k < 3; k++) {
      const uint32_t w = to[d->tri[3 * t + k]];
      files[w] |= (uint64_t)1 << (d->shell[t] & 63);
      on[w] |= shared[t];
    }
  int st = MX_OK;
  for (size_t v = 0; v < d->nv && !st; v++) {
    if (on[v] || !(files[v] & (files[v] - 1))) continue;
    const int a = __builtin_ctzll(files[v]), b = 63 - __builtin_clzll(files[v]);
    mx_error(m->domain_name[a], 0, "materials: this input and %s touch at (%.17g, %.17g, "
                                   "%.17g) without a common face (at a point or along an "
                                   "edge): refused; inputs may meet only along triangles "
                                   "they both have", b < m->ndomain ? m->domain_name[b] : "another",
             d->x[v], d->y[v], d->z[v]);
    st = MX_EINPUT;
  }
  mx_free(files);
  mx_free(on);
  return st;
}

static int drop_shared(const mx_trisoup *s, size_t t, void *ctx) {
  (void)s;
  return ((const uint8_t *)ctx)[t] != 0;
}

int mx_materials_split_shared(mx_mesher *m) {
  mx_trisoup *d = &m->domain;
  {
    /* an input holding several regions first becomes an input per region */
    uint32_t *to0 = NULL;
    int st0 = weld_map(d, &to0);
    if (!st0) st0 = mx_materials_split_complex(m, to0);
    mx_free(to0);
    MX_CHECK(st0);
  }
  const size_t nt = d->nt;
  size_t cap = 1024;
  while (cap < 2 * nt + 2) cap *= 2;
  uint32_t *slot = mx_alloc(cap * sizeof *slot);
  uint8_t *shared = mx_calloc(nt + 1), *first = mx_calloc(nt + 1);
  if (!slot || !shared || !first) {
    mx_free(slot); mx_free(shared); mx_free(first);
    return MX_ENOMEM;
  }
  for (size_t i = 0; i < cap; i++) slot[i] = UINT32_MAX;
  size_t nshared = 0;
  for (size_t t = 0; t < nt; t++) {
    double k[9], k2[9];
    tri_key(d, t, k);
    size_t i = (size_t)key_hash(k) & (cap - 1);
    int found = 0;
    for (; slot[i] != UINT32_MAX; i = (i + 1) & (cap - 1)) {
      tri_key(d, slot[i], k2);
      if (!memcmp(k, k2, sizeof k) && d->shell[slot[i]] != d->shell[t]) {
        shared[t] = shared[slot[i]] = 1;
        found = 1;
        nshared++;
        break;
      }
    }
    if (!found) {
      slot[i] = (uint32_t)t;
      first[t] = 1;
    }
  }
  mx_free(slot);
  uint32_t *to = NULL;
  int st = weld_map(d, &to);
  if (!st) st = touch_check(m, d, shared, to);
  if (!st && nshared && m->nregions >= MX_MAX_REGIONS) {
    mx_error(NULL, 0, "materials: the inputs' common faces need a region surface's place, "
                      "and %d are taken", MX_MAX_REGIONS);
    st = MX_EINPUT;
  }
  if (nshared && !st) {
    /* the inputs as given, for the pieces */
    st = mx_trisoup_append(&m->material_src, d);
    if (!st) memcpy(m->material_src.shell, d->shell, nt * sizeof *d->shell);
    /* one copy of each common triangle: the interface surface */
    const int r = m->nregions;
    mx_trisoup *s = &m->region[r];
    memset(s, 0, sizeof *s);
    for (size_t v = 0; v < d->nv && !st; v++) {
      const double c[3] = {d->x[v], d->y[v], d->z[v]};
      st = mx_trisoup_set_vertex(s, v, c);
    }
    for (size_t t = 0; t < nt && !st; t++)
      if (shared[t] && first[t])
        st = mx_trisoup_add_triangle(s, d->tri[3 * t], d->tri[3 * t + 1], d->tri[3 * t + 2]);
    char *name = st ? NULL : mx_strdup("the faces the inputs have in common");
    if (!st && !name) st = MX_ENOMEM;
    if (!st) {
      m->region_name[r] = name;
      m->region_level[r] = m->p.surface_level > 0 ? m->p.surface_level : 0;
      m->region_meet_only |= 1u << r;
      m->nregions++;
      /* the vertices of equal coordinates made one: the inputs' own
       * copies along the rim of their common faces join, so the union's
       * boundary is closed */
      for (size_t t = 0; t < 3 * d->nt; t++) d->tri[t] = to[d->tri[t]];
      mx_trisoup_remove_if(d, drop_shared, shared);
      m->material_shared = shared;
      shared = NULL;
      m->rec->S.materials_shared = nshared;
    }
    if (st) {
      mx_trisoup_free(s);
    }
  }
  mx_free(to);
  mx_free(shared);
  mx_free(first);
  return st;
}
