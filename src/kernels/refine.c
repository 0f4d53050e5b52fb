#include "base/cancel.h"
#include "kernels/refine.h"
#include "kernels/edges_lazy.h"

#include "base/common.h"
#include "geom/intersect.h"
#include "base/scan.h"
#include "soa/tree_valid.h"

#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

/* What the classification of one octant's 8 children found. */
typedef struct {
  uint8_t kept;       /* children inside the domain or meeting it */
  uint8_t surf;       /* children meeting the domain surface */
  uint8_t rmeet[8];   /* per child: regions met */
  uint8_t rin[8];     /* per child: regions it lies inside of */
  uint8_t target[8];
  uint32_t ntri[8];
  uint32_t nlocated;
} split_info;

/* ------------------------------------------------------------------------ */

int mx_builder_init(mx_builder *B, const mx_trisoup *soup, uint32_t nt_domain,
                    const uint32_t *region_t0, const mx_requests *req,
                    int use_edges, const char *name) {
  memset(B, 0, sizeof *B);
  B->soup = soup;
  B->tree.nt_domain = nt_domain;
  B->req = *req;
  B->tree.use_edges = use_edges;
  /* Balance can only be lost next to an octant two levels finer, so a leaf of
   * level max-1 or max is never split for balance; the transition stage reads
   * the edge infos of a leaf's own level to find its split neighbours, and a
   * leaf of the top level has none. So edge infos are kept for levels up to
   * max - 1, never for the top level (the largest table by far). */
  B->tree.edge_levels = mx_max_requested_level(req) - 1;
  B->tree.edge_lazy_top = -1;
  double lo[3], hi[3];
  mx_trisoup dom = *soup;
  dom.nt = nt_domain; /* the grid covers the domain's triangles' vertices */
  lo[0] = lo[1] = lo[2] = INFINITY;
  hi[0] = hi[1] = hi[2] = -INFINITY;
  for (size_t t = 0; t < dom.nt; t++)
    for (int k = 0; k < 3; k++) {
      uint32_t v = soup->tri[3 * t + k];
      const double p[3] = {soup->x[v], soup->y[v], soup->z[v]};
      for (int a = 0; a < 3; a++) {
        lo[a] = mx_min(lo[a], p[a]);
        hi[a] = mx_max(hi[a], p[a]);
      }
    }
  MX_CHECK(mx_grid_build(lo, hi, name, &B->tree.grid));
  /* a size field's levels come from the root cubes' side */
  B->req.root_side = B->tree.grid.side;
  if (B->req.size_field) B->tree.edge_levels = mx_max_requested_level(&B->req) - 1;
  const size_t nt = soup->nt;
  B->tree.tri_xyz = mx_alloc(9 * nt * sizeof *B->tree.tri_xyz);
  B->tri_region = mx_alloc(nt + 1);
  if (!B->tree.tri_xyz || !B->tri_region) return MX_ENOMEM;
#pragma omp parallel for schedule(static)
  for (size_t t = 0; t < nt; t++)
    for (int k = 0; k < 3; k++) {
      uint32_t v = soup->tri[3 * t + k];
      B->tree.tri_xyz[9 * t + 3 * k + 0] = soup->x[v];
      B->tree.tri_xyz[9 * t + 3 * k + 1] = soup->y[v];
      B->tree.tri_xyz[9 * t + 3 * k + 2] = soup->z[v];
    }
  memset(B->tri_region, 255, nt);
  for (int r = 0; r < req->nregions; r++)
    for (uint32_t t = region_t0[r]; t < region_t0[r + 1]; t++)
      B->tri_region[t] = (uint8_t)r;
  MX_CHECK(mx_locator_build(&B->loc_domain, soup, 0, nt_domain));
  for (int r = 0; r < req->nregions; r++)
    MX_CHECK(mx_locator_build(&B->loc_region[r], soup, region_t0[r],
                              region_t0[r + 1]));
  return MX_OK;
}

void mx_builder_free(mx_builder *B) {
  mx_free(B->tree.tri_xyz);
  mx_free(B->tri_region);
  mx_locator_free(&B->loc_domain);
  for (int r = 0; r < MX_MAX_REGIONS; r++) mx_locator_free(&B->loc_region[r]);
  mx_octree_free(&B->tree.oct);
  mx_edges_free(&B->tree.edges);
  mx_free(B->scratch_mask);
  mx_free(B->scratch_info);
  mx_free(B->scratch_off);
  mx_free(B->tree.root_of);
  memset(B, 0, sizeof *B);
}

int mx_split_set_has(const mx_builder *B, uint64_t key, int level) {
  const size_t n = B->nsplit[level];
  if (n == 0) return 0;
  const uint64_t *k = B->split_keys[level];
  size_t lo = 0, hi = n;
  while (lo < hi) {
    const size_t mid = lo + (hi - lo) / 2;
    if (k[mid] < key) lo = mid + 1; else hi = mid;
  }
  return lo < n && k[lo] == key;
}

static void box_centre(const double lo[3], const double hi[3], double c[3],
                       double h[3]) {
  for (int a = 0; a < 3; a++) {
    c[a] = 0.5 * (lo[a] + hi[a]);
    h[a] = 0.5 * (hi[a] - lo[a]);
  }
}

/* Side of each child in `need` (children meeting no triangle of the set whose
 * parent met it): one ray-parity query per group of face-adjacent such
 * children, since two face-adjacent boxes that meet no triangle lie on the
 * same side. Returns the mask of children found inside. */
static uint8_t locate_children(const mx_locator *L, uint8_t need,
                               const double cc[8][3], uint32_t *nq) {
  uint8_t inside = 0, done = 0;
  for (int c = 0; c < 8; c++) {
    if (!((need >> c) & 1) || ((done >> c) & 1)) continue;
    int in = mx_locate(L, cc[c]);
    (*nq)++;
    uint8_t stack = (uint8_t)(1u << c), group = 0;
    while (stack) {
      int d = __builtin_ctz(stack);
      stack &= (uint8_t)(stack - 1);
      if ((group >> d) & 1) continue;
      group |= (uint8_t)(1u << d);
      for (int a = 0; a < 3; a++) {
        int e = d ^ (1 << a);
        if (((need >> e) & 1) && !((group >> e) & 1))
          stack |= (uint8_t)(1u << e);
      }
    }
    done |= group;
    if (in) inside |= group;
  }
  return inside;
}

/* Classify the 8 children of octant o: which triangles of o each meets (mask
 * per triangle of o's list), which lie inside the domain and the regions,
 * and what level they ask for. */
static void classify_children(const mx_builder *B, uint32_t o, uint8_t *mask,
                              split_info *si) {
  const mx_octree *T = &B->tree.oct;
  const uint64_t key = T->key[o];
  const int l = T->level[o];
  const uint32_t *tris = T->tri_pool + T->tri_off[o];
  const uint32_t nt = T->tri_cnt[o];
  double clo[8][3], chi[8][3], cc[8][3], ch[8][3];
  for (int c = 0; c < 8; c++) {
    mx_octant_box(&B->tree.grid, mx_morton_child(key, l, c), l + 1, clo[c], chi[c]);
    box_centre(clo[c], chi[c], cc[c], ch[c]);
  }
  const double *mid = clo[7];
  memset(si, 0, sizeof *si);
  for (uint32_t i = 0; i < nt; i++) {
    const uint32_t t = tris[i];
    const double *v = B->tree.tri_xyz + 9 * (size_t)t;
    unsigned cand = 0xff;
    for (int a = 0; a < 3; a++) {
      double mn = mx_min(v[a], mx_min(v[3 + a], v[6 + a]));
      double mx = mx_max(v[a], mx_max(v[3 + a], v[6 + a]));
      const unsigned upper = a == 0 ? 0xaa : a == 1 ? 0xcc : 0xf0;
      if (mn > mid[a]) cand &= upper;
      if (mx < mid[a]) cand &= ~upper;
    }
    uint8_t m = 0;
    for (unsigned s = cand; s; s &= s - 1) {
      int c = __builtin_ctz(s);
      if (mx_tri_box_overlap(cc[c], ch[c], v)) m |= (uint8_t)(1u << c);
    }
    mask[i] = m;
    const uint8_t r = B->tri_region[t];
    for (unsigned s = m; s; s &= s - 1) {
      int c = __builtin_ctz(s);
      si->ntri[c]++;
      if (r != 255) si->rmeet[c] |= (uint8_t)(1u << r);
    }
    if (r == 255) si->surf |= m;
  }
  /* Domain: meets the surface, or inherits the parent's side, or is located
   * once when its parent met the surface. */
  uint8_t inside;
  if (T->flags[o] & MX_OCT_SURFACE)
    inside = locate_children(&B->loc_domain, (uint8_t)~si->surf, cc,
                             &si->nlocated);
  else
    inside = (uint8_t)~si->surf;
  si->kept = si->surf | inside;
  /* Regions, for kept children only. */
  for (int r = 0; r < B->req.nregions; r++) {
    const uint8_t bit = (uint8_t)(1u << r);
    uint8_t meets = 0;
    for (int c = 0; c < 8; c++)
      if (si->rmeet[c] & bit) meets |= (uint8_t)(1u << c);
    const uint8_t rest = si->kept & (uint8_t)~meets;
    uint8_t in;
    if (B->req.meet_only & bit)
      in = 0;
    else if (T->rmeet[o] & bit)
      in = locate_children(&B->loc_region[r], rest, cc, &si->nlocated);
    else
      in = (T->rin[o] & bit) ? rest : 0;
    for (int c = 0; c < 8; c++)
      if ((in >> c) & 1) si->rin[c] |= bit;
  }
  for (int c = 0; c < 8; c++) {
    if (!((si->kept >> c) & 1)) {
      si->ntri[c] = 0;
      continue;
    }
    si->target[c] = (uint8_t)mx_target_level(
        &B->req, clo[c], chi[c], (si->surf >> c) & 1,
        (unsigned)(si->rmeet[c] | si->rin[c]));
    if (si->target[c] < l + 2 && mx_split_set_has(B, mx_morton_child(key, l, c), l + 1))
      si->target[c] = (uint8_t)(l + 2);
  }
}

static int grow_scratch(void **p, size_t *cap, size_t need, size_t elem) {
  if (need <= *cap) return MX_OK;
  size_t n = *cap ? *cap : 1024;
  while (n < need) n += n / 2;
  mx_free(*p);
  *p = mx_alloc(n * elem);
  if (!*p) return MX_ENOMEM;
  *cap = n;
  return MX_OK;
}

/* Edge infos after a split of octants of level l: the children's edges (at
 * most 18 new per axis per split), in chunks small enough that the tables
 * never pass 75% load. An edge's mid-node needs no update: it is read from
 * the octants in its slots when needed (transition.c, leaf_mask). */
static int register_children_edges(mx_builder *B, const uint32_t *list,
                                   size_t n, int l) {
  const mx_octree *T = &B->tree.oct;
  for (size_t lo = 0; lo < n;) {
    size_t chunk = n - lo;
    {
      size_t room = SIZE_MAX;
      for (int a = 0; a < 3; a++) {
        const mx_edge_table *E = &B->tree.edges.t[l + 1][a];
        size_t lim = (size_t)(0.75 * (double)E->cap);
        room = lim > E->count ? (lim - E->count < room ? lim - E->count : room)
                              : 0;
      }
      if (room / 18 < (chunk < 16384 ? chunk : 16384)) {
        size_t want = chunk < 262144 ? chunk : 262144;
        MX_CHECK(mx_edges_reserve(&B->tree.edges, l + 1, 18 * want));
        continue;
      }
      if (room / 18 < chunk) chunk = room / 18;
    }
    size_t created[3] = {0, 0, 0};
#pragma omp parallel
    {
      size_t mine[3] = {0, 0, 0};
#pragma omp for schedule(static)
      for (size_t i = lo; i < lo + chunk; i++) {
        const uint32_t o = list[i];
        mx_edges_register_children(&B->tree.edges, T->child0[o], T->kept[o],
                                   T->key[o], l, mine);
      }
#pragma omp critical
      for (int a = 0; a < 3; a++) created[a] += mine[a];
    }
    mx_edges_add_count(&B->tree.edges, l + 1, created);
    lo += chunk;
  }
  return MX_OK;
}

int mx_split_octants(mx_builder *B, const uint32_t *list, size_t n,
                     int for_balance) {
  if (n == 0) return MX_OK;
  mx_octree *T = &B->tree.oct;
  const int l = T->level[list[0]];
  if (B->tree.use_edges) MX_CHECK(mx_edges_restore(B));
  /* below the levels whose edge infos are complete: those of these octants
   * and their neighbours (transition masks), and of their parents and the
   * parents' neighbours (the balance looks for leaves there) */
  if (B->tree.use_edges && l > B->tree.edge_levels) MX_CHECK(mx_edges_ensure(B, list, n, 1));
  /* Offsets of each parent's triangles in the mask scratch. */
  MX_CHECK(grow_scratch((void **)&B->scratch_off, &B->scratch_off_cap,
                        2 * n + 2, sizeof(uint64_t)));
  uint64_t *moff = B->scratch_off, *coff = B->scratch_off + n + 1;
#pragma omp parallel for schedule(static) if (n > MX_PAR_MIN)
  for (size_t i = 0; i < n; i++) moff[i] = T->tri_cnt[list[i]];
  const uint64_t nmask = mx_scan_u64(moff, n);
  MX_CHECK(grow_scratch((void **)&B->scratch_mask, &B->scratch_mask_cap,
                        nmask + 1, 1));
  MX_CHECK(grow_scratch(&B->scratch_info, &B->scratch_info_cap, n,
                        sizeof(split_info)));
  split_info *info = B->scratch_info;
  uint8_t *mask = B->scratch_mask;
  size_t located = 0;
#pragma omp parallel for schedule(dynamic, 64) reduction(+ : located)
  for (size_t i = 0; i < n; i++) {
    classify_children(B, list[i], mask + moff[i], &info[i]);
    located += info[i].nlocated;
  }
  B->stats.located += located;
  /* Count children and their triangles; prefix sums give where they go. */
  uint64_t *toff = mx_alloc((n + 1) * sizeof *toff);
  if (!toff) return MX_ENOMEM;
  size_t dropped = 0;
#pragma omp parallel for schedule(static) reduction(+ : dropped) if (n > MX_PAR_MIN)
  for (size_t i = 0; i < n; i++) {
    coff[i] = (uint64_t)__builtin_popcount(info[i].kept);
    dropped += 8 - coff[i];
    uint64_t s = 0;
    for (int c = 0; c < 8; c++) s += info[i].ntri[c];
    toff[i] = s;
  }
  B->stats.dropped += dropped;
  const uint64_t nchild = mx_scan_u64(coff, n);
  const uint64_t ntris = mx_scan_u64(toff, n);
  const size_t n0 = T->n, t0 = T->tri_n;
  if (n0 + nchild >= (size_t)MX_NONE) {
    mx_error(NULL, 0, "too many octants (more than 2^32)");
    mx_free(toff);
    return MX_EINPUT;
  }
  int st = mx_octree_reserve(T, n0 + nchild, t0 + ntris);
  if (st) {
    mx_free(toff);
    return st;
  }
  const uint8_t sflag = (uint8_t)(MX_OCT_SPLIT | (for_balance ? MX_OCT_BALANCE : 0));
#pragma omp parallel for schedule(dynamic, 256)
  for (size_t i = 0; i < n; i++) {
    const uint32_t o = list[i];
    const split_info *si = &info[i];
    const uint32_t *ptris = T->tri_pool + T->tri_off[o];
    const uint32_t pnt = T->tri_cnt[o];
    const uint8_t *pm = mask + moff[i];
    size_t idx = n0 + coff[i];
    uint64_t tb = t0 + toff[i];
    for (int c = 0; c < 8; c++) {
      if (!((si->kept >> c) & 1)) continue;
      T->key[idx] = mx_morton_child(T->key[o], l, c);
      T->level[idx] = (uint8_t)(l + 1);
      T->flags[idx] = ((si->surf >> c) & 1) ? MX_OCT_SURFACE : 0;
      T->target[idx] = si->target[c];
      T->kept[idx] = 0;
      T->rmeet[idx] = si->rmeet[c];
      T->rin[idx] = si->rin[c];
      T->parent[idx] = o;
      T->child0[idx] = MX_NONE;
      T->tri_off[idx] = tb;
      T->tri_cnt[idx] = si->ntri[c];
      for (uint32_t k = 0; k < pnt; k++)
        if ((pm[k] >> c) & 1) T->tri_pool[tb++] = ptris[k];
      idx++;
    }
    T->child0[o] = si->kept ? (uint32_t)(n0 + coff[i]) : MX_NONE;
    T->kept[o] = si->kept;
    T->flags[o] |= sflag;
  }
  mx_free(toff);
  T->n = n0 + nchild;
  T->tri_n = t0 + ntris;
  if (for_balance)
    B->stats.split_balance += n;
  else
    B->stats.split_requested += n;
  if (!B->tree.use_edges || l + 1 > B->tree.edge_levels) return MX_OK;
  return register_children_edges(B, list, n, l);
}

/* ------------------------------------------------------------------------ */

/* Roots: each triangle is tested against the root cubes its bounding box
 * covers; a root that meets no triangle is located once. */
int mx_build_roots(mx_builder *B) {
  const mx_grid *g = &B->tree.grid;
  const int nx = g->dims[0], ny = g->dims[1], nz = g->dims[2];
  const size_t nroot = (size_t)nx * ny * nz;
  const size_t nt = B->soup->nt;
  uint32_t *cnt = mx_calloc((nroot + 1) * sizeof *cnt);
  if (!cnt) return MX_ENOMEM;
  /* Pass 1 counts, pass 2 fills: pairs (root, triangle) in triangle order. */
  uint32_t *list = NULL;
  for (int pass = 0; pass < 2; pass++) {
    for (size_t t = 0; t < nt; t++) {
      const double *v = B->tree.tri_xyz + 9 * t;
      int r0[3], r1[3];
      for (int a = 0; a < 3; a++) {
        double mn = mx_min(v[a], mx_min(v[3 + a], v[6 + a]));
        double mx = mx_max(v[a], mx_max(v[3 + a], v[6 + a]));
        r0[a] = (int)floor((mn - g->origin[a]) / g->side);
        r1[a] = (int)floor((mx - g->origin[a]) / g->side);
        if (r0[a] < 0) r0[a] = 0;
        if (r1[a] >= g->dims[a]) r1[a] = g->dims[a] - 1;
        if (r0[a] > 0) r0[a]--; /* boundary-touching: test the neighbour */
        if (r1[a] < g->dims[a] - 1) r1[a]++;
      }
      for (int k = r0[2]; k <= r1[2]; k++)
        for (int j = r0[1]; j <= r1[1]; j++)
          for (int i = r0[0]; i <= r1[0]; i++) {
            const size_t r = ((size_t)k * ny + j) * nx + i;
            double lo[3], hi[3], c[3], h[3];
            const uint64_t key = mx_morton_encode((uint32_t)i << MX_MAX_LEVEL,
                                                  (uint32_t)j << MX_MAX_LEVEL,
                                                  (uint32_t)k << MX_MAX_LEVEL);
            mx_octant_box(g, key, 0, lo, hi);
            box_centre(lo, hi, c, h);
            if (!mx_tri_box_overlap(c, h, v)) continue;
            if (pass == 0)
              cnt[r + 1]++;
            else
              list[cnt[r]++] = (uint32_t)t;
          }
    }
    if (pass == 0) {
      for (size_t r = 0; r < nroot; r++) cnt[r + 1] += cnt[r];
      list = mx_alloc((size_t)cnt[nroot] * sizeof *list + 4);
      if (!list) {
        mx_free(cnt);
        return MX_ENOMEM;
      }
    } else {
      for (size_t r = nroot; r > 0; r--) cnt[r] = cnt[r - 1];
      cnt[0] = 0;
    }
  }
  mx_octree *T = &B->tree.oct;
  int st = mx_octree_reserve(T, nroot, cnt[nroot]);
  if (st) {
    mx_free(cnt);
    mx_free(list);
    return st;
  }
  for (int k = 0; k < nz; k++)
    for (int j = 0; j < ny; j++)
      for (int i = 0; i < nx; i++) {
        const size_t r = ((size_t)k * ny + j) * nx + i;
        const uint64_t key = mx_morton_encode((uint32_t)i << MX_MAX_LEVEL,
                                              (uint32_t)j << MX_MAX_LEVEL,
                                              (uint32_t)k << MX_MAX_LEVEL);
        double lo[3], hi[3], c[3], h[3];
        mx_octant_box(g, key, 0, lo, hi);
        box_centre(lo, hi, c, h);
        int surf = 0;
        uint8_t rmeet = 0, rin = 0;
        for (uint32_t q = cnt[r]; q < cnt[r + 1]; q++) {
          uint8_t reg = B->tri_region[list[q]];
          if (reg == 255)
            surf = 1;
          else
            rmeet |= (uint8_t)(1u << reg);
        }
        if (!surf) {
          B->stats.located++;
          if (!mx_locate(&B->loc_domain, c)) {
            B->stats.dropped++;
            continue;
          }
        }
        for (int g2 = 0; g2 < B->req.nregions; g2++)
          if (!((rmeet >> g2) & 1) && !((B->req.meet_only >> g2) & 1)) {
            B->stats.located++;
            if (mx_locate(&B->loc_region[g2], c)) rin |= (uint8_t)(1u << g2);
          }
        const size_t o = T->n++;
        T->key[o] = key;
        T->level[o] = 0;
        T->flags[o] = surf ? MX_OCT_SURFACE : 0;
        T->target[o] =
            (uint8_t)mx_target_level(&B->req, lo, hi, surf, rmeet | rin);
        if (T->target[o] < 1 && mx_split_set_has(B, key, 0))
          T->target[o] = 1;
        T->kept[o] = 0;
        T->rmeet[o] = rmeet;
        T->rin[o] = rin;
        T->parent[o] = MX_NONE;
        T->child0[o] = MX_NONE;
        T->tri_off[o] = T->tri_n;
        T->tri_cnt[o] = cnt[r + 1] - cnt[r];
        memcpy(T->tri_pool + T->tri_n, list + cnt[r],
               (size_t)T->tri_cnt[o] * sizeof *list);
        T->tri_n += T->tri_cnt[o];
      }
  mx_free(cnt);
  mx_free(list);
  if (B->tree.use_edges && B->tree.edge_levels >= 0) {
    MX_CHECK(mx_edges_reserve(&B->tree.edges, 0, 4 * T->n + 16));
    size_t created[3] = {0, 0, 0};
    for (size_t o = 0; o < T->n; o++)
      mx_edges_register(&B->tree.edges, (uint32_t)o, T->key[o], 0, created);
    mx_edges_add_count(&B->tree.edges, 0, created);
  }
  return MX_OK;
}

/* The next candidates: children of this level's candidates that ask for a
 * finer level, in parent order then child order. */
static int next_candidates(const mx_builder *B, const uint32_t *cand,
                           size_t n, uint32_t **out, size_t *nout) {
  const mx_octree *T = &B->tree.oct;
  uint64_t *off = mx_alloc((n + 1) * sizeof *off);
  if (!off) return MX_ENOMEM;
#pragma omp parallel for schedule(static) if (n > MX_PAR_MIN)
  for (size_t i = 0; i < n; i++) {
    const uint32_t o = cand[i];
    uint64_t s = 0;
    for (int k = 0; k < __builtin_popcount(T->kept[o]); k++) {
      const uint32_t c = T->child0[o] + (uint32_t)k;
      s += T->target[c] > T->level[c];
    }
    off[i] = s;
  }
  const uint64_t total = mx_scan_u64(off, n);
  uint32_t *next = mx_alloc((total + 1) * sizeof *next);
  if (!next) {
    mx_free(off);
    return MX_ENOMEM;
  }
#pragma omp parallel for schedule(static) if (n > MX_PAR_MIN)
  for (size_t i = 0; i < n; i++) {
    const uint32_t o = cand[i];
    uint64_t w = off[i];
    for (int k = 0; k < __builtin_popcount(T->kept[o]); k++) {
      const uint32_t c = T->child0[o] + (uint32_t)k;
      if (T->target[c] > T->level[c]) next[w++] = c;
    }
  }
  mx_free(off);
  *out = next;
  *nout = total;
  return MX_OK;
}

static int refine_levels(mx_builder *B, int balance_now) {
  mx_octree *T = &B->tree.oct;
  size_t n = 0;
  uint32_t *cand = mx_alloc((T->n + 1) * sizeof *cand);
  if (!cand) return MX_ENOMEM;
  for (size_t o = 0; o < T->n; o++)
    if (T->target[o] > T->level[o]) cand[n++] = (uint32_t)o;
  while (n > 0) {
    if (B->on_level)
      B->on_level(B->on_level_user, T->level[cand[0]] + 1,
                  mx_max_requested_level(&B->req));
    if (mx_cancelled()) { /* base/cancel.h: before each level */
      mx_free(cand);
      return MX_ECANCELED;
    }
    double t0 = mx_wtime();
    int st = mx_split_octants(B, cand, n, 0);
    double t1 = mx_wtime();
    B->stats.t_refine += t1 - t0;
    if (!st && B->cancel_mid_level && mx_cancelled()) st = MX_ECANCELED; /* the tree is dropped */
    if (!st && balance_now) st = mx_balance_drain(B, cand, n);
    double t2 = mx_wtime();
    B->stats.t_balance += t2 - t1;
    uint32_t *next = NULL;
    size_t nn = 0;
    if (!st) st = next_candidates(B, cand, n, &next, &nn);
    B->stats.t_refine += mx_wtime() - t2;
    mx_free(cand);
    if (st) return st;
    cand = next;
    n = nn;
  }
  mx_free(cand);
  return MX_OK;
}

int mx_refine_balanced(mx_builder *B) {
  MX_CHECK(refine_levels(B, 1));
  MX_TREE_INVARIANTS(&B->tree, MX_TREE_BALANCED, "refinement with balance");
  return MX_OK;
}
int mx_refine_unbalanced(mx_builder *B) {
  MX_CHECK(refine_levels(B, 0));
  MX_TREE_INVARIANTS(&B->tree, 0, "refinement without balance");
  return MX_OK;
}
