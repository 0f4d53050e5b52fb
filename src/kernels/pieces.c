/* The pieces of the materials' inputs: see kernels/pieces.h. */
#include "kernels/pieces.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "base/common.h"

static int cmp_u32(const void *a, const void *b) {
  const uint32_t x = *(const uint32_t *)a, y = *(const uint32_t *)b;
  return (x > y) - (x < y);
}

/* The triangles tris[0 .. n) of src as a soup of their own, with the
 * vertices they use (in order of first use). map: src->nv entries of
 * UINT32_MAX, left so. */
static int sub_soup(const mx_trisoup *src, const uint32_t *tris, size_t n, uint32_t *map,
                    mx_trisoup *d) {
  memset(d, 0, sizeof *d);
  int st = mx_trisoup_reserve(d, 0, n);
  size_t nv = 0;
  for (size_t i = 0; i < n && !st; i++) {
    const uint32_t *t = src->tri + 3 * (size_t)tris[i];
    uint32_t w[3];
    for (int k = 0; k < 3 && !st; k++) {
      if (map[t[k]] == UINT32_MAX) {
        const double c[3] = {src->x[t[k]], src->y[t[k]], src->z[t[k]]};
        map[t[k]] = (uint32_t)nv;
        st = mx_trisoup_set_vertex(d, nv++, c);
      }
      w[k] = map[t[k]];
    }
    if (!st) st = mx_trisoup_add_triangle(d, w[0], w[1], w[2]);
  }
  for (size_t i = 0; i < n; i++)
    for (int k = 0; k < 3; k++) map[src->tri[3 * (size_t)tris[i] + k]] = UINT32_MAX;
  if (st) mx_trisoup_free(d);
  return st == MX_EINPUT ? MX_ENOMEM : st; /* reserve's "too large" */
}

void mx_interfaces_free(mx_interfaces *I) {
  for (uint32_t p = 0; I->iface && p < I->npieces; p++)
    if (I->iface[p]) {
      mx_surface_index_free(I->iface[p]);
      mx_free(I->iface[p]);
    }
  for (uint32_t p = 0; I->iface_soup && p < I->npieces; p++) mx_trisoup_free(&I->iface_soup[p]);
  mx_free(I->iface);
  mx_free(I->iface_soup);
  for (uint32_t p = 0; I->index && p < I->npieces; p++)
    if (I->index[p].tri_id) mx_surface_index_free(&I->index[p]);
  for (uint32_t p = 0; I->soup && p < I->npieces; p++) mx_trisoup_free(&I->soup[p]);
  mx_free(I->index);
  mx_free(I->soup);
  mx_free(I->parent);
  mx_free(I->depth);
  mx_free(I->file);
  mx_free(I->region);
  mx_free(I->pass);
  memset(I, 0, sizeof *I);
}

/* The pieces of one file: its shells (connected through manifold edges,
 * as an index finds them), appended to I with their triangles. */
static int file_pieces(mx_interfaces *I, const mx_trisoup *src, const uint32_t *tris, size_t n,
                       uint16_t file, const uint8_t *shared, uint8_t *shares, uint32_t *map) {
  mx_trisoup fs;
  int st = sub_soup(src, tris, n, map, &fs);
  mx_surface_index S;
  memset(&S, 0, sizeof S);
  if (!st) st = mx_surface_index_build(&S, &fs, 0, (uint32_t)fs.nt);
  if (!st && I->npieces + S.nshells > MX_MAX_PIECES) {
    mx_error(NULL, 0, "materials: more than %d closed shells in the inputs", MX_MAX_PIECES);
    st = MX_EINPUT;
  }
  /* each shell's triangles, in the file's order: bucketed by shell */
  uint32_t *list = st ? NULL : mx_alloc((n + 1) * sizeof *list);
  size_t *off = st ? NULL : mx_calloc(((size_t)S.nshells + 2) * sizeof *off);
  if (!st && (!list || !off)) st = MX_ENOMEM;
  if (!st) {
    for (uint32_t i = 0; i < S.nt; i++) off[S.shell_of[i] + 1]++;
    for (uint32_t c = 0; c < S.nshells; c++) off[c + 1] += off[c];
    for (uint32_t i = 0; i < S.nt; i++) list[off[S.shell_of[i]]++] = tris[S.tri_id[i]];
    for (uint32_t c = S.nshells; c > 0; c--) off[c] = off[c - 1];
    off[0] = 0;
  }
  for (uint32_t c = 0; c < S.nshells && !st; c++) {
    const size_t k = off[c + 1] - off[c];
    uint32_t *mine = list + off[c];
    qsort(mine, k, sizeof *mine, cmp_u32);
    const uint32_t p = I->npieces;
    shares[p] = 0;
    for (size_t i = 0; shared && i < k; i++) shares[p] |= shared[mine[i]];
    st = sub_soup(src, mine, k, map, &I->soup[p]);
    if (!st) st = mx_surface_index_build(&I->index[p], &I->soup[p], 0, (uint32_t)k);
    if (!st && shares[p]) { /* its interface: the shared triangles */
      size_t ns = 0;
      for (size_t i = 0; i < k; i++)
        if (shared[mine[i]]) mine[ns++] = mine[i]; /* (the list is not needed after) */
      I->iface[p] = mx_calloc(sizeof *I->iface[p]);
      st = I->iface[p] ? sub_soup(src, mine, ns, map, &I->iface_soup[p]) : MX_ENOMEM;
      if (!st) st = mx_surface_index_build(I->iface[p], &I->iface_soup[p], 0, (uint32_t)ns);
      if (st) {
        mx_free(I->iface[p]);
        I->iface[p] = NULL;
        mx_trisoup_free(&I->iface_soup[p]);
      }
    }
    if (st) { /* this piece's part: the caller frees the pieces counted */
      if (I->index[p].tri_id) mx_surface_index_free(&I->index[p]);
      mx_trisoup_free(&I->soup[p]);
      break;
    }
    I->file[p] = file;
    I->npieces++;
  }
  mx_free(list);
  mx_free(off);
  if (S.tri_id) mx_surface_index_free(&S);
  mx_trisoup_free(&fs);
  return st;
}

/* 1 when piece q lies inside piece p: the first vertex of q off p's
 * surface (beyond a hair of the box) is inside p. */
static int piece_inside(const mx_interfaces *I, uint32_t q, uint32_t p) {
  const mx_trisoup *s = &I->soup[q];
  double lo[3], hi[3];
  mx_trisoup_bbox(&I->soup[p], lo, hi);
  const double hair = 1e-9 * sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) +
                                  (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                                  (hi[2] - lo[2]) * (hi[2] - lo[2]));
  for (size_t t = 0; t < s->nt; t++)
    for (int k = 0; k < 3; k++) {
      const uint32_t v = s->tri[3 * t + k];
      const double x[3] = {s->x[v], s->y[v], s->z[v]};
      const double d = mx_signed_distance(&I->index[p], x, NULL);
      if (fabs(d) > hair) return d < 0.0;
    }
  return 0;
}

int mx_interfaces_build(mx_interfaces *I, const mx_trisoup *src, uint32_t nt,
                        const uint8_t *shared) {
  memset(I, 0, sizeof *I);
  I->soup = mx_calloc((MX_MAX_PIECES + 1) * sizeof *I->soup);
  I->index = mx_calloc((MX_MAX_PIECES + 1) * sizeof *I->index);
  I->parent = mx_alloc((MX_MAX_PIECES + 1) * sizeof *I->parent);
  I->depth = mx_alloc((MX_MAX_PIECES + 1) * sizeof *I->depth);
  I->file = mx_alloc((MX_MAX_PIECES + 1) * sizeof *I->file);
  I->region = mx_alloc((MX_MAX_PIECES + 1) * sizeof *I->region);
  I->pass = mx_alloc((MX_MAX_PIECES + 1) * sizeof *I->pass);
  I->iface = mx_calloc((MX_MAX_PIECES + 1) * sizeof *I->iface);
  I->iface_soup = mx_calloc((MX_MAX_PIECES + 1) * sizeof *I->iface_soup);
  uint32_t *tris = mx_alloc(((size_t)nt + 1) * sizeof *tris);
  uint8_t *shares = mx_alloc(MX_MAX_PIECES + 1);
  uint32_t *map = mx_alloc((src->nv + 1) * sizeof *map);
  if (map)
    for (size_t v = 0; v < src->nv; v++) map[v] = UINT32_MAX;
  int st = !I->soup || !I->index || !I->parent || !I->depth || !I->file || !I->region ||
                   !I->pass || !I->iface || !I->iface_soup || !tris || !shares || !map
               ? MX_ENOMEM
               : MX_OK;
  /* the files' shells */
  uint16_t nfiles = 0;
  for (uint32_t t = 0; t < nt; t++)
    if (src->shell[t] + 1 > nfiles) nfiles = (uint16_t)(src->shell[t] + 1);
  for (uint16_t f = 0; f < nfiles && !st; f++) {
    size_t n = 0;
    for (uint32_t t = 0; t < nt; t++)
      if (src->shell[t] == f) tris[n++] = t;
    if (n) st = file_pieces(I, src, tris, n, f, shared, shares, map);
  }
  mx_free(tris);
  mx_free(map);
  const uint32_t np = I->npieces;
  /* the forest: each piece's parent is the innermost piece containing it
   * (the one containing it that the most others contain) */
  uint8_t *in = st ? NULL : mx_calloc((size_t)np * np + 1);
  if (!st && !in) st = MX_ENOMEM;
  for (uint32_t q = 0; q < np && !st; q++)
    for (uint32_t p = 0; p < np; p++)
      if (p != q) in[(size_t)q * np + p] = (uint8_t)piece_inside(I, q, p);
  for (uint32_t q = 0; q < np && !st; q++) {
    int depth = 0;
    for (uint32_t p = 0; p < np; p++) depth += in[(size_t)q * np + p];
    I->depth[q] = (uint16_t)depth;
  }
  for (uint32_t q = 0; q < np && !st; q++) {
    I->parent[q] = -1;
    for (uint32_t p = 0; p < np; p++)
      if (in[(size_t)q * np + p] && I->depth[p] + 1 == I->depth[q]) I->parent[q] = (int32_t)p;
  }
  mx_free(in);
  /* regions by (depth, file) */
  int deepest = 0;
  for (uint32_t q = 0; q < np; q++) deepest = I->depth[q] > deepest ? I->depth[q] : deepest;
  int next = deepest + 2;
  for (int d = 0; d <= deepest && !st; d++) {
    int first = -1;
    for (uint16_t f = 0; f < nfiles; f++) {
      int has = 0;
      for (uint32_t q = 0; q < np; q++) has |= I->depth[q] == d && I->file[q] == f;
      if (!has) continue;
      const int r = first < 0 ? d + 1 : next++;
      if (first < 0) first = f;
      for (uint32_t q = 0; q < np; q++)
        if (I->depth[q] == d && I->file[q] == f) I->region[q] = (uint16_t)r;
    }
  }
  I->nregions = next - 1;
  /* the passes: nested pieces, and pieces with a shared triangle */
  for (int d = 0; d <= deepest && !st; d++)
    for (uint32_t q = 0; q < np; q++) {
      if (I->depth[q] != d) continue;
      if (d > 0 || shares[q]) I->pass[I->npasses++] = q;
    }
  mx_free(shares);
  if (st) mx_interfaces_free(I);
  return st;
}

int mx_interfaces_surface_piece(const mx_interfaces *I, const double p[3]) {
  double best = INFINITY, q[3];
  int at = 0;
  for (uint32_t k = 0; k < I->npieces; k++) {
    const double d = mx_closest_point_within(&I->index[k], p, best, q);
    if (d < best) best = d, at = (int)k + 1;
  }
  return at;
}

int mx_interfaces_piece(const mx_interfaces *I, const double p[3]) {
  int at = -1; /* descend from the roots */
  for (;;) {
    int found = -1;
    for (uint32_t q = 0; q < I->npieces && found < 0; q++)
      if (I->parent[q] == at && mx_inside(&I->index[q], p)) found = (int)q;
    if (found < 0) return at + 1;
    at = found;
  }
}

double mx_interfaces_clearance(const mx_interfaces *I, const double p[3]) {
  double best = INFINITY, q[3];
  for (uint32_t k = 0; k < I->npieces; k++) {
    const double d = mx_closest_point_within(&I->index[k], p, best, q);
    if (d < best) best = d;
  }
  return best;
}

int mx_interfaces_within(const mx_interfaces *I, int q, uint32_t p) {
  for (int x = q - 1; x >= 0; x = I->parent[x])
    if ((uint32_t)x == p) return 1;
  return 0;
}

