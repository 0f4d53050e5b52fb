/* Elements split along diagonals of their quadrilaterals
 * (kernels/cell_split.h). */
#include "kernels/cell_split.h"

#include <math.h>
#include <string.h>

#include "base/common.h"
#include "geom/quality.h"
#include "kernels/boundary.h"
#include "kernels/mesh_edit.h"
#include "kernels/node_work.h"

/* The split element's faces: diag[f] = 0 (kept whole) or 1 + diagonal. */
typedef struct {
  size_t cell;
  uint8_t diag[6];
} split_job;

/* Cones of the element (written to out[], 8 entries each, with their
 * types) from apex x; returns their count. */
static int cones(const mx_mesh *M, const split_job *j, uint32_t x, uint32_t *out, uint8_t *type) {
  const int t = M->type[j->cell];
  const uint32_t *v = M->conn + 8 * j->cell;
  int n = 0;
  for (int f = 0; f < mx_cell_nfaces[t]; f++) {
    const int8_t *F = mx_cell_faces[t][f];
    uint32_t a[4];
    const int k = F[3] < 0 ? 3 : 4;
    for (int i = 0; i < k; i++) a[i] = v[F[i]];
    int skip = 0; /* a face through the apex has no cone */
    for (int i = 0; i < k; i++) skip |= a[i] == x;
    if (skip) continue;
    uint32_t tri[2][3];
    int ntri = 0;
    if (k == 3) {
      memcpy(tri[0], a, sizeof tri[0]);
      ntri = 1;
    } else if (j->diag[f]) {
      const int s = j->diag[f] - 1; /* the diagonal a[s] - a[s + 2] */
      const uint32_t t0[3] = {a[s], a[s + 1], a[(s + 2) % 4]};
      const uint32_t t1[3] = {a[s], a[(s + 2) % 4], a[(s + 3) % 4]};
      memcpy(tri[0], t0, sizeof t0);
      memcpy(tri[1], t1, sizeof t1);
      ntri = 2;
    } else {
      /* an outward quadrilateral: the pyramid's base turns towards x */
      uint32_t *o = out + 8 * (size_t)n;
      const uint32_t p[5] = {a[0], a[3], a[2], a[1], x};
      memcpy(o, p, sizeof p);
      for (int i = 5; i < 8; i++) o[i] = UINT32_MAX;
      type[n++] = MX_PYRAMID;
      continue;
    }
    for (int i = 0; i < ntri; i++) {
      uint32_t *o = out + 8 * (size_t)n;
      const uint32_t p[4] = {tri[i][0], tri[i][2], tri[i][1], x};
      memcpy(o, p, sizeof p);
      for (int q = 4; q < 8; q++) o[q] = UINT32_MAX;
      type[n++] = MX_TET;
    }
  }
  return n;
}

/* The apex: the pyramid's own when its base alone is split, else a new
 * node (UINT32_MAX). */
static uint32_t own_apex(const mx_mesh *M, const split_job *j) {
  if (M->type[j->cell] != MX_PYRAMID) return UINT32_MAX;
  for (int f = 1; f < 5; f++)
    if (j->diag[f]) return UINT32_MAX;
  return M->conn[8 * j->cell + 4];
}

/* The least J_ENS of the elements cells[0 .. n) with node v at x. */
static double least_with(const mx_mesh *M, const uint32_t *cells, size_t n, uint32_t v,
                         const double *x) {
  double worst = INFINITY;
  for (size_t i = 0; i < n; i++) {
    const size_t c = cells[i];
    double p[8][3];
    for (int k = 0; k < mx_cell_nodes[M->type[c]]; k++) {
      const uint32_t w = M->conn[8 * c + k];
      memcpy(p[k], w == v ? x : M->xyz + 3 * (size_t)w, sizeof p[k]);
    }
    worst = fmin(worst, mx_jens(M->type[c], (const double(*)[3])p));
  }
  return worst;
}

void mx_mesh_best_point(mx_mesh *M, uint32_t v, const uint32_t *cells, size_t n) {
  double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
  for (size_t i = 0; i < n; i++)
    for (int k = 0; k < mx_cell_nodes[M->type[cells[i]]]; k++)
      for (int a = 0; a < 3; a++) {
        const double c = M->xyz[3 * (size_t)M->conn[8 * (size_t)cells[i] + k] + a];
        lo[a] = fmin(lo[a], c);
        hi[a] = fmax(hi[a], c);
      }
  double *x = M->xyz + 3 * (size_t)v;
  double step = 0.25 * fmax(hi[0] - lo[0], fmax(hi[1] - lo[1], hi[2] - lo[2]));
  double best = least_with(M, cells, n, v, x);
  for (int it = 0; it < 12; it++, step *= 0.5)
    for (int moved = 1, moves = 0; moved && moves < 8; moves++) {
      moved = 0;
      for (int d = 0; d < 6 && !moved; d++) {
        double y[3] = {x[0], x[1], x[2]};
        y[d / 2] += d & 1 ? -step : step;
        if (y[d / 2] < lo[d / 2] || y[d / 2] > hi[d / 2]) continue; /* in the elements' box */
        const double w = least_with(M, cells, n, v, y);
        if (w > best) {
          best = w;
          memcpy(x, y, sizeof y);
          moved = 1;
        }
      }
    }
  for (size_t i = 0; i < n && M->jens; i++) M->jens[cells[i]] = (float)mx_cell_jens(M, cells[i]);
}

static int grow(void **p, size_t n, size_t size) {
  void *q = mx_realloc(*p, (n + 1) * size);
  if (!q) return MX_ENOMEM;
  *p = q;
  return MX_OK;
}

int mx_mesh_split_quads(mx_mesh *M, uint8_t **states, const uint64_t *req, size_t n,
                        size_t *centres, mx_split_log *log) {
  if (centres) *centres = 0;
  if (!n) return MX_OK;
  /* the jobs, one per element */
  split_job *job = mx_calloc(n * sizeof *job);
  if (!job) return MX_ENOMEM;
  size_t nj = 0;
  for (size_t i = 0; i < n; i++) {
    const size_t c = (size_t)(req[i] >> 8);
    const int f = (int)(req[i] >> 1 & 127);
    if (c >= M->ncells || f >= mx_cell_nfaces[M->type[c]] || mx_cell_faces[M->type[c]][f][3] < 0) {
      mx_free(job);
      mx_error(NULL, 0, "split request %zu: element %zu face %d is not a quadrilateral", i, c, f);
      return MX_EINPUT;
    }
    if (!nj || job[nj - 1].cell != c) job[nj++].cell = c;
    job[nj - 1].diag[f] = (uint8_t)(1 + (req[i] & 1));
  }
  /* the counts: new nodes and cells */
  size_t nn = 0, nc = 0;
  uint32_t buf[8 * 12];
  uint8_t tb[12];
  for (size_t k = 0; k < nj; k++) {
    const uint32_t apex = own_apex(M, job + k);
    nn += apex == UINT32_MAX;
    nc += (size_t)cones(M, job + k, apex == UINT32_MAX ? UINT32_MAX - 1 : apex, buf, tb) - 1;
  }
  const size_t N = M->nnodes + nn, C = M->ncells + nc;
  int st = grow((void **)&M->xyz, 3 * N, sizeof *M->xyz);
  if (!st) st = grow((void **)states, N, 1);
  if (!st && M->nkey) st = grow((void **)&M->nkey, N, sizeof *M->nkey);
  if (!st) st = grow((void **)&M->type, C, 1);
  if (!st) st = grow((void **)&M->conn, 8 * C, sizeof *M->conn);
  if (!st && M->level) st = grow((void **)&M->level, C, 1);
  if (!st && M->leaf) st = grow((void **)&M->leaf, C, sizeof *M->leaf);
  if (!st && M->jens) st = grow((void **)&M->jens, C, sizeof *M->jens);
  if (!st && M->material) st = grow((void **)&M->material, C, sizeof *M->material);
  if (!st && log) {
    mx_split_undo *u = mx_realloc(log->job, (log->n + nj + 1) * sizeof *u);
    if (!u) st = MX_ENOMEM;
    else log->job = u;
    if (!log->n) log->nodes_before = M->nnodes;
  }
  if (st) {
    mx_free(job);
    return st;
  }
  size_t v = M->nnodes, c = M->ncells;
  for (size_t k = 0; k < nj; k++) {
    const size_t e = job[k].cell;
    uint32_t apex = own_apex(M, job + k);
    if (apex == UINT32_MAX) {
      apex = (uint32_t)v++;
      const int m = mx_cell_nodes[M->type[e]];
      double *x = M->xyz + 3 * (size_t)apex;
      x[0] = x[1] = x[2] = 0.0;
      for (int i = 0; i < m; i++)
        for (int a = 0; a < 3; a++) x[a] += M->xyz[3 * (size_t)M->conn[8 * e + i] + a] / m;
      (*states)[apex] = MX_NODE_INSIDE;
      if (M->nkey) M->nkey[apex] = MX_NKEY_NONE;
    }
    const int q = cones(M, job + k, apex, buf, tb);
    if (log) {
      mx_split_undo *u = log->job + log->n++;
      u->cell = (uint32_t)e;
      u->first = (uint32_t)c;
      u->apex = apex;
      u->type = M->type[e];
      u->cones = (uint8_t)q;
      memcpy(u->conn, M->conn + 8 * e, sizeof u->conn);
    }
    uint32_t made[12];
    for (int i = 0; i < q; i++) {
      const size_t d = i == 0 ? e : c++;
      made[i] = (uint32_t)d;
      memcpy(M->conn + 8 * d, buf + 8 * i, 8 * sizeof *buf);
      M->type[d] = tb[i];
      if (d != e) {
        if (M->level) M->level[d] = M->level[e];
        if (M->leaf) M->leaf[d] = M->leaf[e];
        if (M->material) M->material[d] = M->material[e];
      }
    }
    /* the cones' J_ENS: set by the placement of a new apex, else here */
    if (M->jens && apex >= M->nnodes) mx_mesh_best_point(M, apex, made, (size_t)q);
    else if (M->jens)
      for (int i = 0; i < q; i++) M->jens[made[i]] = (float)mx_cell_jens(M, made[i]);
  }
  M->nnodes = N;
  M->ncells = C;
  if (centres) *centres = nn;
  mx_free(job);
  return MX_OK;
}

int mx_mesh_unsplit(mx_mesh *M, uint8_t **states, mx_split_log *log, const uint8_t *undo) {
  size_t any = 0;
  for (size_t k = 0; k < log->n; k++) any += undo[k] != 0;
  if (!any) {
    log->n = 0;
    return MX_OK;
  }
  uint8_t *keep = mx_alloc(M->ncells + 1), *used = mx_calloc(M->nnodes + 1);
  if (!keep || !used) {
    mx_free(keep);
    mx_free(used);
    return MX_ENOMEM;
  }
  memset(keep, 1, M->ncells);
  for (size_t k = 0; k < log->n; k++) {
    if (!undo[k]) continue;
    const mx_split_undo *u = log->job + k;
    memcpy(M->conn + 8 * (size_t)u->cell, u->conn, sizeof u->conn);
    M->type[u->cell] = u->type;
    for (uint32_t i = 0; i + 1 < u->cones; i++) keep[u->first + i] = 0;
    M->jens[u->cell] = (float)mx_cell_jens(M, u->cell);
  }
  log->n = 0;
  int st = mx_mesh_keep_cells(M, keep);
  /* the new nodes no element uses any more dropped, the others keeping
   * their order (and the nodes before them their indices) */
  uint32_t *newid = st ? NULL : mx_alloc((M->nnodes + 1) * sizeof *newid);
  if (!st && !newid) st = MX_ENOMEM;
  if (!st) {
    for (size_t c = 0; c < M->ncells; c++)
      for (int i = 0; i < mx_cell_nodes[M->type[c]]; i++) used[M->conn[8 * c + i]] = 1;
    size_t nu = 0;
    for (size_t v = 0; v < M->nnodes; v++)
      newid[v] = v < log->nodes_before || used[v] ? (uint32_t)nu++ : UINT32_MAX;
    st = mx_mesh_apply_node_ids(M, states, newid, nu);
  }
  mx_free(newid);
  mx_free(keep);
  mx_free(used);
  return st;
}

void mx_split_log_free(mx_split_log *log) {
  mx_free(log->job);
  log->job = NULL;
  log->n = 0;
}
