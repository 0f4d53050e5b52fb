/* The forest and its refinement by the requests.
 *
 * Roots: one p4est tree per root cube of our grid (a brick of dims[0] x
 * dims[1] x dims[2] trees), each classified as mx_build_roots classifies
 * it (the triangles whose box reaches it, tested by separating axes; a root
 * meeting none located once).
 *
 * Levels: the quadrants of level l that ask for more (kept, target > l) are
 * listed, their children classified in parallel (OpenMP) and their
 * triangle lists written to the pool (count, prefix sum, fill), then
 * p8est_refine_ext splits exactly those, not recursively, and its replace
 * callback hands each family its precomputed data, in the order p4est
 * visits them (the local quadrants' order, the order they were listed in;
 * checked). */
#include "mpi/p4est_octree.h"

#include "base/common.h"
#include "mpi/exchange.h"
#include "geom/intersect.h"
#include "base/scan.h"

#include <math.h>
#include <string.h>

#include <p8est_bits.h>
#include <p8est_extended.h>

void mx_p4est_params_default(mx_p4est_params *p) {
  memset(p, 0, sizeof *p);
  p->repartition_min = 64;
  p->weight_outside = 0;
  p->weight_inside = 1;
  p->weight_surface = 4;
}

int mx_p4est_pool_reserve(mx_p4est_octree *P, size_t n) {
  if (P->pool_n + n <= P->pool_cap) return MX_OK;
  size_t cap = P->pool_cap ? P->pool_cap : 4096;
  while (cap < P->pool_n + n) cap += cap / 2;
  uint32_t *p = mx_realloc(P->pool, cap * sizeof *p);
  if (!p) return MX_ENOMEM;
  P->pool = p;
  P->pool_cap = cap;
  return MX_OK;
}

int mx_p4est_mask_reserve(mx_p4est_octree *P, size_t n) {
  if (n <= P->mask_cap) return MX_OK;
  size_t cap = P->mask_cap ? P->mask_cap : 4096;
  while (cap < n) cap += cap / 2;
  mx_free(P->mask);
  P->mask = mx_alloc(cap);
  if (!P->mask) {
    P->mask_cap = 0;
    return MX_ENOMEM;
  }
  P->mask_cap = cap;
  return MX_OK;
}

/* ---- roots --------------------------------------------------------------- */

/* The roots' data and triangle lists (CSR over root index (k*ny + j)*nx + i,
 * triangles in input order), for every root: each rank then copies its own. */
typedef struct {
  mx_pq *data;
  uint32_t *off, *tri;
} root_table;

static void root_box(const mx_grid *g, int i, int j, int k, double c[3], double h[3],
                     double lo[3], double hi[3]) {
  const uint64_t key = mx_morton_encode((uint32_t)i << MX_MAX_LEVEL, (uint32_t)j << MX_MAX_LEVEL,
                                        (uint32_t)k << MX_MAX_LEVEL);
  mx_octant_box(g, key, 0, lo, hi);
  for (int a = 0; a < 3; a++) {
    c[a] = 0.5 * (lo[a] + hi[a]);
    h[a] = 0.5 * (hi[a] - lo[a]);
  }
}

static int build_root_table(const mx_builder *B, root_table *R, size_t *nlocated) {
  const mx_grid *g = &B->tree.grid;
  const int nx = g->dims[0], ny = g->dims[1], nz = g->dims[2];
  const size_t nroot = (size_t)nx * ny * nz, nt = B->soup->nt;
  R->off = mx_calloc((nroot + 1) * sizeof *R->off);
  R->data = mx_calloc((nroot + 1) * sizeof *R->data);
  if (!R->off || !R->data) return MX_ENOMEM;
  /* pass 0 counts the (root, triangle) pairs, pass 1 lists them */
  for (int pass = 0; pass < 2; pass++) {
    for (size_t t = 0; t < nt; t++) {
      const double *v = B->tree.tri_xyz + 9 * t;
      int r0[3], r1[3];
      for (int a = 0; a < 3; a++) {
        const double mn = mx_min(v[a], mx_min(v[3 + a], v[6 + a]));
        const double mx = mx_max(v[a], mx_max(v[3 + a], v[6 + a]));
        r0[a] = (int)floor((mn - g->origin[a]) / g->side);
        r1[a] = (int)floor((mx - g->origin[a]) / g->side);
        if (r0[a] < 0) r0[a] = 0;
        if (r1[a] >= g->dims[a]) r1[a] = g->dims[a] - 1;
        if (r0[a] > 0) r0[a]--; /* a triangle on a root's face: test both */
        if (r1[a] < g->dims[a] - 1) r1[a]++;
      }
      for (int k = r0[2]; k <= r1[2]; k++)
        for (int j = r0[1]; j <= r1[1]; j++)
          for (int i = r0[0]; i <= r1[0]; i++) {
            double c[3], h[3], lo[3], hi[3];
            root_box(g, i, j, k, c, h, lo, hi);
            if (!mx_tri_box_overlap(c, h, v)) continue;
            const size_t r = ((size_t)k * ny + j) * nx + i;
            if (pass == 0)
              R->off[r + 1]++;
            else
              R->tri[R->off[r]++] = (uint32_t)t;
          }
    }
    if (pass == 0) {
      for (size_t r = 0; r < nroot; r++) R->off[r + 1] += R->off[r];
      R->tri = mx_alloc(((size_t)R->off[nroot] + 1) * sizeof *R->tri);
      if (!R->tri) return MX_ENOMEM;
    } else {
      for (size_t r = nroot; r > 0; r--) R->off[r] = R->off[r - 1];
      R->off[0] = 0;
    }
  }
  /* classify each root */
  for (int k = 0; k < nz; k++)
    for (int j = 0; j < ny; j++)
      for (int i = 0; i < nx; i++) {
        const size_t r = ((size_t)k * ny + j) * nx + i;
        double c[3], h[3], lo[3], hi[3];
        root_box(g, i, j, k, c, h, lo, hi);
        int surf = 0;
        uint8_t rmeet = 0, rin = 0;
        for (uint32_t q = R->off[r]; q < R->off[r + 1]; q++) {
          const uint8_t reg = B->tri_region[R->tri[q]];
          if (reg == 255)
            surf = 1;
          else
            rmeet |= (uint8_t)(1u << reg);
        }
        mx_pq *d = &R->data[r];
        d->target = 0;
        if (!surf) {
          (*nlocated)++;
          if (!mx_locate(&B->loc_domain, c)) continue; /* outside: flags 0 */
        }
        for (int s = 0; s < B->req.nregions; s++)
          if (!((rmeet >> s) & 1) && !((B->req.meet_only >> s) & 1)) {
            (*nlocated)++;
            if (mx_locate(&B->loc_region[s], c)) rin |= (uint8_t)(1u << s);
          }
        d->flags = surf ? MX_PQ_SURFACE : MX_PQ_INSIDE;
        d->rmeet = rmeet;
        d->rin = rin;
        d->tri_cnt = R->off[r + 1] - R->off[r];
        d->target = (uint8_t)mx_target_level(&B->req, lo, hi, surf, rmeet | rin);
      }
  return MX_OK;
}

/* p8est_new_ext's init callback: the root's data and list. */
static void init_root(p8est_t *p8, p4est_topidx_t t, p8est_quadrant_t *q) {
  mx_p4est_octree *P = p8->user_pointer;
  const root_table *R = P->side;
  const int32_t *ijk = P->tree_root + 3 * (size_t)t;
  const int *dims = P->B->tree.grid.dims;
  const size_t r = ((size_t)ijk[2] * dims[1] + ijk[1]) * dims[0] + ijk[0];
  mx_pq *d = q->p.user_data;
  *d = R->data[r];
  d->tri_off = P->pool_n;
  if (!d->tri_cnt) return;
  if (mx_p4est_pool_reserve(P, d->tri_cnt)) {
    P->status = MX_ENOMEM;
    d->tri_cnt = 0;
    return;
  }
  memcpy(P->pool + P->pool_n, R->tri + R->off[r], (size_t)d->tri_cnt * sizeof *P->pool);
  P->pool_n += d->tri_cnt;
}

int mx_p4est_new_forest(mx_p4est_octree *P) {
  const mx_grid *g = &P->B->tree.grid;
  P->conn = p8est_connectivity_new_brick(g->dims[0], g->dims[1], g->dims[2], 0, 0, 0);
  const p4est_topidx_t nt = P->conn->num_trees;
  P->tree_root = mx_alloc(3 * ((size_t)nt + 1) * sizeof *P->tree_root);
  if (!P->tree_root) return MX_ENOMEM;
  /* a tree's root cube: the brick coordinates of its corner 0 */
  for (p4est_topidx_t t = 0; t < nt; t++) {
    const p4est_topidx_t v = P->conn->tree_to_vertex[P8EST_CHILDREN * t];
    for (int a = 0; a < 3; a++) {
      const double x = P->conn->vertices[3 * (size_t)v + a];
      P->tree_root[3 * (size_t)t + a] = (int32_t)lround(x);
      if (x < 0 || lround(x) >= g->dims[a]) {
        mx_error(NULL, 0, "internal: brick tree %ld outside the root grid", (long)t);
        return MX_EINTERNAL;
      }
    }
  }
  root_table R;
  memset(&R, 0, sizeof R);
  int st = build_root_table(P->B, &R, &P->located), all = st;
  MPI_Allreduce(&st, &all, 1, MPI_INT, MPI_MAX, P->comm);
  st = all;
  if (!st) {
    P->side = &R;
    P->p8 = p8est_new_ext(P->comm, P->conn, 0, 0, 1, sizeof(mx_pq), init_root, P);
    P->side = NULL;
    st = P->status;
    MPI_Allreduce(&st, &all, 1, MPI_INT, MPI_MAX, P->comm);
    st = all;
  }
  mx_free(R.data);
  mx_free(R.off);
  mx_free(R.tri);
  return st;
}

/* ---- levels -------------------------------------------------------------- */

/* The quadrants split at one level, in local order, and their children. */
typedef struct {
  size_t n, cursor;
  p4est_topidx_t *tree;
  p8est_quadrant_t *quad; /* copies: where, to check p4est's order */
  mx_pq **data;           /* their data (valid until the refinement) */
  mx_pq_family *fam;
  uint64_t *moff, *toff;  /* mask and triangle offsets (prefix sums) */
} level_side;

static void level_side_free(level_side *S) {
  mx_free(S->tree);
  mx_free(S->quad);
  mx_free(S->data);
  mx_free(S->fam);
  mx_free(S->moff);
  mx_free(S->toff);
  memset(S, 0, sizeof *S);
}

static int asks_split(const p8est_quadrant_t *q, int level) {
  const mx_pq *d = q->p.user_data;
  return q->level == level && mx_pq_kept(d) && d->target > level;
}

static int refine_cb(p8est_t *p8, p4est_topidx_t t, p8est_quadrant_t *q) {
  (void)t;
  const mx_p4est_octree *P = p8->user_pointer;
  return asks_split(q, P->level);
}

static void replace_cb(p8est_t *p8, p4est_topidx_t t, int nout, p8est_quadrant_t *out[],
                       int nin, p8est_quadrant_t *in[]) {
  mx_p4est_octree *P = p8->user_pointer;
  level_side *S = P->side;
  if (P->status) return;
  if (nout != 1 || nin != P8EST_CHILDREN || S->cursor >= S->n || S->tree[S->cursor] != t ||
      !p8est_quadrant_is_equal(out[0], &S->quad[S->cursor])) {
    P->status = MX_EINTERNAL; /* not the split we prepared */
    return;
  }
  const mx_pq_family *f = &S->fam[S->cursor++];
  for (int c = 0; c < P8EST_CHILDREN; c++) {
    const int id = p8est_quadrant_child_id(in[c]);
    *(mx_pq *)in[c]->p.user_data = f->child[id];
  }
}

/* Lists the candidates of level l and classifies their children. */
static int prepare_level(mx_p4est_octree *P, level_side *S, int l) {
  p8est_t *p8 = P->p8;
  size_t n = 0;
  for (p4est_topidx_t t = p8->first_local_tree; t <= p8->last_local_tree; t++) {
    const p8est_tree_t *tr = p8est_tree_array_index(p8->trees, t);
    if (tr->quadrants_per_level[l] == 0) continue;
    for (size_t i = 0; i < tr->quadrants.elem_count; i++)
      n += asks_split(p8est_quadrant_array_index((sc_array_t *)&tr->quadrants, i), l);
  }
  S->n = n;
  S->cursor = 0;
  S->tree = mx_alloc((n + 1) * sizeof *S->tree);
  S->quad = mx_alloc((n + 1) * sizeof *S->quad);
  S->data = mx_alloc((n + 1) * sizeof *S->data);
  S->fam = mx_alloc((n + 1) * sizeof *S->fam);
  S->moff = mx_alloc((n + 1) * sizeof *S->moff);
  S->toff = mx_alloc((n + 1) * sizeof *S->toff);
  if (!S->tree || !S->quad || !S->data || !S->fam || !S->moff || !S->toff) return MX_ENOMEM;
  size_t k = 0;
  for (p4est_topidx_t t = p8->first_local_tree; t <= p8->last_local_tree; t++) {
    p8est_tree_t *tr = p8est_tree_array_index(p8->trees, t);
    if (tr->quadrants_per_level[l] == 0) continue;
    for (size_t i = 0; i < tr->quadrants.elem_count; i++) {
      p8est_quadrant_t *q = p8est_quadrant_array_index(&tr->quadrants, i);
      if (!asks_split(q, l)) continue;
      S->tree[k] = t;
      S->quad[k] = *q;
      S->data[k] = q->p.user_data;
      S->moff[k] = S->data[k]->tri_cnt;
      k++;
    }
  }
  const uint64_t nmask = mx_scan_u64(S->moff, n);
  MX_CHECK(mx_p4est_mask_reserve(P, nmask + 1));
  const mx_builder *B = P->B;
  const uint32_t *pool = P->pool;
  uint8_t *mask = P->mask;
  size_t located = 0;
#pragma omp parallel for schedule(dynamic, 64) reduction(+ : located)
  for (size_t i = 0; i < n; i++) {
    const mx_pq *d = S->data[i];
    mx_pq_classify(B, mx_p4est_key(P, S->tree[i], &S->quad[i]), l, d, pool + d->tri_off,
                   mask + S->moff[i], &S->fam[i]);
    located += S->fam[i].located;
    S->toff[i] = mx_pq_family_tris(&S->fam[i]);
  }
  P->located += located;
  const uint64_t ntris = mx_scan_u64(S->toff, n);
  MX_CHECK(mx_p4est_pool_reserve(P, ntris + 1));
  const size_t base = P->pool_n;
  uint32_t *pl = P->pool;
#pragma omp parallel for schedule(dynamic, 256)
  for (size_t i = 0; i < n; i++) {
    const mx_pq *d = S->data[i];
    mx_pq_fill(&S->fam[i], pl + d->tri_off, d->tri_cnt, mask + S->moff[i],
               pl + base + S->toff[i], base + S->toff[i]);
  }
  P->pool_n += ntris;
  return MX_OK;
}


int mx_p4est_refine(mx_p4est_octree *P) {
  for (int l = 0; l < P->max_level; l++) {
    const double t0 = mx_wtime();
    level_side S;
    memset(&S, 0, sizeof S);
    int st = prepare_level(P, &S, l);
    st = mx_mpi_agree(P->comm, st);
    if (st) {
      level_side_free(&S);
      return st;
    }
    P->level = l;
    P->side = &S;
    p8est_refine_ext(P->p8, 0, -1, refine_cb, NULL, replace_cb);
    P->side = NULL;
    if (!P->status && S.cursor != S.n) P->status = MX_EINTERNAL;
    P->split_requested += S.n;
    level_side_free(&S);
    st = mx_mpi_agree(P->comm, P->status);
    P->t.refine += mx_wtime() - t0;
    if (st) {
      if (st == MX_EINTERNAL)
        mx_error(NULL, 0, "internal: p4est refined other quadrants than those classified "
                          "at level %d", l);
      return st;
    }
    /* spread the next levels' work once there is enough to spread */
    if (P->size > 1 && P->par.repartition_min > 0 && l + 1 < P->max_level &&
        P->p8->global_num_quadrants >= (p4est_gloidx_t)P->par.repartition_min * P->size)
      MX_CHECK(mx_p4est_partition(P, 0));
  }
  return MX_OK;
}

/* ---- repair: listed leaves split once ------------------------------------ */

int mx_p4est_refine_listed(mx_p4est_octree *P, const uint64_t *keys, size_t n,
                           long long *nsplit) {
  p8est_t *p8 = P->p8;
  long long k = 0;
  int top = 0;
  for (p4est_topidx_t t = p8->first_local_tree; t <= p8->last_local_tree; t++) {
    p8est_tree_t *tr = p8est_tree_array_index(p8->trees, t);
    for (size_t i = 0; i < tr->quadrants.elem_count; i++) {
      p8est_quadrant_t *q = p8est_quadrant_array_index(&tr->quadrants, i);
      mx_pq *d = q->p.user_data;
      if (!mx_pq_kept(d) || mx_find_u64(keys, n, mx_p4est_key(P, t, q)) == UINT32_MAX) continue;
      if (d->target <= q->level) d->target = (uint8_t)(q->level + 1);
      if (d->target > top) top = d->target;
      k++;
    }
  }
  MPI_Allreduce(&k, nsplit, 1, MPI_LONG_LONG, MPI_SUM, P->comm);
  MPI_Allreduce(MPI_IN_PLACE, &top, 1, MPI_INT, MPI_MAX, P->comm);
  if (!*nsplit) return MX_OK;
  if (top > P->max_level) P->max_level = top;
  if (P->max_level > P8EST_QMAXLEVEL) {
    mx_error(NULL, 0, "a repair asks level %d, deeper than p4est allows (%d)", P->max_level,
             P8EST_QMAXLEVEL);
    return MX_EINPUT;
  }
  MX_CHECK(mx_p4est_refine(P));
  MX_CHECK(mx_p4est_balance(P));
  if (P->ghost) p8est_ghost_destroy(P->ghost);
  P->ghost = NULL;
  mx_free(P->ghost_data);
  P->ghost_data = NULL;
  MX_CHECK(mx_p4est_partition(P, 1));
  return mx_p4est_ghost(P);
}
