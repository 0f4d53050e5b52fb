/* The regions of a surface given as several files (several materials that
 * touch, issue 26): `mixoct check --surface A --surface B ...`, one file
 * per input as the mesher was given them (soa/trisoup.h: triangle t came
 * from file shell[t]). Defined here from the files alone, never from what
 * the mesher built:
 *
 *  - a piece is one closed shell of one file: its triangles connected
 *    through the file's manifold edges (edges used by exactly two of the
 *    file's triangles; geom/surface_topology.h), each with an index of its
 *    own (geom/distance.h), turned outward;
 *  - piece q lies inside piece p when the first vertex of q off p's surface
 *    (farther than 1e-9 of p's box diagonal) is inside p (touching pieces
 *    share vertices that are on both: those do not decide); q's depth is the
 *    number of pieces it lies inside, its parent the one of them at depth
 *    depth - 1;
 *  - a point's region is that of the innermost piece containing it (found
 *    from the roots down, a piece's children tested only inside it), 0
 *    outside every piece; a region is keyed by (the piece's depth, its
 *    file): at depth d the first file with a piece there gives region
 *    d + 1, the others numbers after the deepest's (deepest + 2, ...), so
 *    that one file alone numbers its regions by nesting depth as the
 *    one-file check does;
 *  - a region's volume: its pieces' enclosed volumes less their children's;
 *    the union's (the domain a mesh with materials fills): the roots'
 *    volumes summed (pieces that touch share a face, no volume); the
 *    domain of a mesh without materials, where a nested shell is a hole
 *    (the points of odd depth, as the mesher meshes it without
 *    --materials): the pieces' volumes, those at odd depths subtracted;
 *  - a triangle two files share (the same three points, either order) is an
 *    interface between them, not the domain's boundary.
 * O(pieces^2) containment tests (box-filtered), about one closest-point
 * query per piece near a point per region query. */
#include "verify/check_passes.h"

#include <stdlib.h>

#include "geom/distance.h"
#include "geom/surface_topology.h"

void mx_ck_pieces_free(ck_pieces *P) {
  for (uint32_t q = 0; P->index && q < P->n; q++)
    if (P->index[q].tri_id) mx_surface_index_free(&P->index[q]);
  for (uint32_t q = 0; P->soup && q < P->n; q++) mx_trisoup_free(&P->soup[q]);
  mx_free(P->soup);
  mx_free(P->index);
  mx_free(P->box);
  mx_free(P->parent);
  mx_free(P->depth);
  mx_free(P->file);
  mx_free(P->region);
  mx_free(P->volume);
  mx_free(P->child_off);
  mx_free(P->child);
  mx_free(P->region_volume);
  memset(P, 0, sizeof *P);
}

uint32_t mx_ck_surface_files(const mx_trisoup *s) {
  uint32_t n = s->nt ? 1 : 0;
  for (size_t t = 0; s->shell && t < s->nt; t++)
    if ((uint32_t)s->shell[t] + 1 > n) n = (uint32_t)s->shell[t] + 1;
  return n;
}

/* piece[t]: the piece of triangle t (UINT32_MAX: a triangle with a
 * repeated vertex, in none); *np the pieces, numbered file by file, in each
 * file in the order of their first triangle. */
static int find_pieces(const mx_trisoup *s, uint32_t nfiles, uint32_t *piece, uint32_t *np) {
  const size_t nt = s->nt;
  uint32_t *order = mx_alloc((nt + 1) * sizeof *order);
  uint32_t *shell = mx_alloc((nt + 1) * sizeof *shell);
  uint8_t *flip = mx_alloc(nt + 1);
  int st = order && shell && flip ? MX_OK : MX_ENOMEM;
  uint32_t base = 0;
  for (uint32_t f = 0; f < nfiles && !st; f++) {
    uint32_t n = 0;
    for (size_t t = 0; t < nt; t++)
      if (s->shell[t] == f) order[n++] = (uint32_t)t;
    if (!n) continue;
    mx_edge_table T;
    st = mx_edge_table_build(&T, s->tri, order, n, (uint32_t)s->nv, 1, 1);
    uint32_t ns = 0;
    if (!st) st = mx_surface_shells(&T, 0, shell, flip, &ns, NULL, NULL);
    mx_edge_table_free(&T);
    if (st) break;
    for (uint32_t i = 0; i < n; i++)
      piece[order[i]] = shell[i] == UINT32_MAX ? UINT32_MAX : base + shell[i];
    base += ns;
    if (base > MX_CK_MAX_PIECES) {
      mx_error(NULL, 0, "check: more than %d closed shells in the surface files",
               MX_CK_MAX_PIECES);
      st = MX_EINPUT;
    }
  }
  mx_free(order);
  mx_free(shell);
  mx_free(flip);
  *np = base;
  return st;
}

/* The triangles list[0 .. n) of s as a soup of their own (the vertices
 * they use, in order of first use); map: s->nv entries of UINT32_MAX, left
 * so. */
static int piece_soup(const mx_trisoup *s, const uint32_t *list, size_t n, uint32_t *map,
                      mx_trisoup *d) {
  memset(d, 0, sizeof *d);
  int st = mx_trisoup_reserve(d, 0, n);
  size_t nv = 0;
  for (size_t i = 0; i < n && !st; i++) {
    uint32_t w[3];
    for (int k = 0; k < 3 && !st; k++) {
      const uint32_t v = s->tri[3 * (size_t)list[i] + (size_t)k];
      if (map[v] == UINT32_MAX) {
        const double c[3] = {s->x[v], s->y[v], s->z[v]};
        map[v] = (uint32_t)nv;
        st = mx_trisoup_set_vertex(d, nv++, c);
      }
      w[k] = map[v];
    }
    if (!st) st = mx_trisoup_add_triangle(d, w[0], w[1], w[2]);
  }
  for (size_t i = 0; i < n; i++)
    for (int k = 0; k < 3; k++) map[s->tri[3 * (size_t)list[i] + (size_t)k]] = UINT32_MAX;
  if (st) mx_trisoup_free(d);
  return st == MX_EINPUT ? MX_ENOMEM : st; /* reserve's "too large" */
}

static double box_diagonal(const double *b) {
  return sqrt((b[3] - b[0]) * (b[3] - b[0]) + (b[4] - b[1]) * (b[4] - b[1]) +
              (b[5] - b[2]) * (b[5] - b[2]));
}

/* Whether p lies in box b grown by pad on every side. */
static int in_box(const double *b, const double p[3], double pad) {
  return p[0] >= b[0] - pad && p[0] <= b[3] + pad && p[1] >= b[1] - pad && p[1] <= b[4] + pad &&
         p[2] >= b[2] - pad && p[2] <= b[5] + pad;
}

/* 1 when piece q lies inside piece p (the head's rule). */
static int piece_inside(const ck_pieces *P, uint32_t q, uint32_t p) {
  const double *bp = P->box[p], *bq = P->box[q];
  const double hair = 1e-9 * box_diagonal(bp);
  if (!in_box(bp, bq, hair) || !in_box(bp, bq + 3, hair)) return 0;
  const mx_trisoup *s = &P->soup[q];
  for (size_t v = 0; v < s->nv; v++) {
    const double x[3] = {s->x[v], s->y[v], s->z[v]};
    const double d = mx_signed_distance(&P->index[p], x, NULL);
    if (fabs(d) > hair) return d < 0.0;
  }
  return 0;
}

/* Each piece's soup, index, box and volume. */
static int build_indices(ck_pieces *P, const mx_trisoup *s, const uint32_t *piece) {
  const uint32_t np = P->n;
  size_t *off = mx_calloc(((size_t)np + 2) * sizeof *off);
  uint32_t *list = mx_alloc((s->nt + 1) * sizeof *list);
  uint32_t *map = mx_alloc((s->nv + 1) * sizeof *map);
  int st = off && list && map ? MX_OK : MX_ENOMEM;
  if (!st) {
    for (size_t v = 0; v < s->nv; v++) map[v] = UINT32_MAX;
    for (size_t t = 0; t < s->nt; t++)
      if (piece[t] != UINT32_MAX) off[piece[t] + 2]++;
    for (uint32_t q = 0; q < np; q++) off[q + 2] += off[q + 1];
    for (size_t t = 0; t < s->nt; t++) /* each piece's triangles ascending */
      if (piece[t] != UINT32_MAX) list[off[piece[t] + 1]++] = (uint32_t)t;
  }
  double *vol = NULL;
  for (uint32_t q = 0; q < np && !st; q++) {
    const size_t n = off[q + 1] - off[q];
    st = piece_soup(s, list + off[q], n, map, &P->soup[q]);
    if (!st) st = mx_surface_index_build(&P->index[q], &P->soup[q], 0, (uint32_t)n);
    if (!st) {
      vol = mx_alloc(((size_t)P->index[q].nshells + 1) * sizeof *vol);
      if (!vol) st = MX_ENOMEM;
    }
    if (st) break;
    mx_surface_index_shell_volumes(&P->index[q], vol, NULL);
    P->volume[q] = 0.0;
    for (uint32_t c = 0; c < P->index[q].nshells; c++) P->volume[q] += fabs(vol[c]);
    mx_free(vol);
    vol = NULL;
    double lo[3], hi[3];
    mx_trisoup_bbox(&P->soup[q], lo, hi);
    for (int a = 0; a < 3; a++) P->box[q][a] = lo[a], P->box[q][3 + a] = hi[a];
  }
  mx_free(off);
  mx_free(list);
  mx_free(map);
  return st;
}

/* Depths, parents, the children's lists, regions and their volumes. */
static int build_forest(ck_pieces *P) {
  const uint32_t np = P->n;
  uint8_t *in = mx_calloc((size_t)np * np + 1);
  if (!in) return MX_ENOMEM;
  for (uint32_t q = 0; q < np; q++)
    for (uint32_t p = 0; p < np; p++)
      if (p != q) in[(size_t)q * np + p] = (uint8_t)piece_inside(P, q, p);
  for (uint32_t q = 0; q < np; q++) {
    uint32_t d = 0;
    for (uint32_t p = 0; p < np; p++) d += in[(size_t)q * np + p];
    P->depth[q] = d;
  }
  for (uint32_t q = 0; q < np; q++) {
    P->parent[q] = -1;
    for (uint32_t p = 0; p < np && P->parent[q] < 0; p++)
      if (in[(size_t)q * np + p] && P->depth[p] + 1 == P->depth[q]) P->parent[q] = (int32_t)p;
  }
  mx_free(in);
  /* children by parent (the roots under slot 0), each list ascending */
  for (uint32_t q = 0; q < np; q++) P->child_off[P->parent[q] + 2]++;
  for (uint32_t p = 0; p <= np; p++) P->child_off[p + 1] += P->child_off[p];
  for (uint32_t q = 0; q < np; q++) P->child[P->child_off[P->parent[q] + 1]++] = q;
  for (uint32_t p = np + 1; p > 0; p--) P->child_off[p] = P->child_off[p - 1];
  P->child_off[0] = 0;
  /* regions keyed by (depth, file) */
  uint32_t deepest = 0, nfiles = 0;
  for (uint32_t q = 0; q < np; q++) {
    deepest = P->depth[q] > deepest ? P->depth[q] : deepest;
    nfiles = (uint32_t)P->file[q] + 1 > nfiles ? (uint32_t)P->file[q] + 1 : nfiles;
  }
  int next = (int)deepest + 2;
  for (uint32_t d = 0; d <= deepest && np; d++) {
    int first = 1;
    for (uint32_t f = 0; f < nfiles; f++) {
      int has = 0;
      for (uint32_t q = 0; q < np; q++) has |= P->depth[q] == d && P->file[q] == f;
      if (!has) continue;
      const int reg = first ? (int)d + 1 : next++;
      first = 0;
      for (uint32_t q = 0; q < np; q++)
        if (P->depth[q] == d && P->file[q] == f) P->region[q] = reg;
    }
  }
  P->nregions = np ? next - 1 : 0;
  P->region_volume = mx_calloc(((size_t)P->nregions + 1) * sizeof *P->region_volume);
  if (!P->region_volume) return MX_ENOMEM;
  P->union_volume = P->parity_volume = 0.0;
  for (uint32_t q = 0; q < np; q++) {
    P->parity_volume += P->depth[q] % 2 ? -P->volume[q] : P->volume[q];
    P->region_volume[P->region[q]] += P->volume[q];
    if (P->parent[q] >= 0)
      P->region_volume[P->region[P->parent[q]]] -= P->volume[q];
    else
      P->union_volume += P->volume[q];
  }
  return MX_OK;
}

int mx_ck_pieces_build(ck_pieces *P, const mx_trisoup *s) {
  memset(P, 0, sizeof *P);
  const uint32_t nfiles = mx_ck_surface_files(s);
  uint32_t *piece = mx_alloc((s->nt + 1) * sizeof *piece);
  if (!piece) return MX_ENOMEM;
  uint32_t np = 0;
  int st = find_pieces(s, nfiles, piece, &np);
  if (!st) {
    P->n = np;
    const size_t n1 = (size_t)np + 1;
    P->soup = mx_calloc(n1 * sizeof *P->soup);
    P->index = mx_calloc(n1 * sizeof *P->index);
    P->box = mx_alloc(n1 * sizeof *P->box);
    P->parent = mx_alloc(n1 * sizeof *P->parent);
    P->depth = mx_alloc(n1 * sizeof *P->depth);
    P->file = mx_alloc(n1 * sizeof *P->file);
    P->region = mx_alloc(n1 * sizeof *P->region);
    P->volume = mx_alloc(n1 * sizeof *P->volume);
    P->child_off = mx_calloc((n1 + 1) * sizeof *P->child_off);
    P->child = mx_alloc(n1 * sizeof *P->child);
    if (!P->soup || !P->index || !P->box || !P->parent || !P->depth || !P->file || !P->region ||
        !P->volume || !P->child_off || !P->child)
      st = MX_ENOMEM;
  }
  if (!st) {
    for (size_t t = 0; t < s->nt; t++)
      if (piece[t] != UINT32_MAX) P->file[piece[t]] = s->shell[t];
    st = build_indices(P, s, piece);
  }
  mx_free(piece);
  if (!st) st = build_forest(P);
  if (st) mx_ck_pieces_free(P);
  return st;
}

int mx_ck_pieces_on(const ck_pieces *P, const double p[3], double on) {
  for (uint32_t q = 0; q < P->n; q++)
    if (in_box(P->box[q], p, on) && mx_closest_point_within(&P->index[q], p, 2.0 * on, NULL) <= on)
      return 1;
  return 0;
}

int mx_ck_pieces_region(const ck_pieces *P, const double p[3]) {
  int32_t at = -1; /* from the roots down */
  for (;;) {
    int32_t found = -1;
    for (uint32_t i = P->child_off[at + 1]; i < P->child_off[at + 2] && found < 0; i++) {
      const uint32_t q = P->child[i];
      if (in_box(P->box[q], p, 0.0) && mx_inside(&P->index[q], p)) found = (int32_t)q;
    }
    if (found < 0) return at < 0 ? 0 : P->region[at];
    at = found;
  }
}

/* ---- triangles two files share ------------------------------------------- */

typedef struct {
  double k[9]; /* the three points, in increasing (x, y, z) order */
  uint32_t t;
  uint16_t file;
} tri_key;

static int cmp_point(const double *a, const double *b) {
  for (int i = 0; i < 3; i++)
    if (a[i] != b[i]) return a[i] < b[i] ? -1 : 1;
  return 0;
}

static int cmp_key(const void *pa, const void *pb) {
  const tri_key *a = pa, *b = pb;
  for (int i = 0; i < 9; i++)
    if (a->k[i] != b->k[i]) return a->k[i] < b->k[i] ? -1 : 1;
  return (a->t > b->t) - (a->t < b->t);
}

int mx_ck_shared_triangles(const mx_trisoup *s, uint8_t *shared, size_t *nshared) {
  const size_t nt = s->nt;
  *nshared = 0;
  memset(shared, 0, nt);
  tri_key *K = mx_alloc((nt + 1) * sizeof *K);
  if (!K) return MX_ENOMEM;
  for (size_t t = 0; t < nt; t++) {
    double p[3][3];
    for (int j = 0; j < 3; j++) {
      const uint32_t v = s->tri[3 * t + (size_t)j];
      p[j][0] = s->x[v] + 0.0, p[j][1] = s->y[v] + 0.0, p[j][2] = s->z[v] + 0.0; /* -0 = 0 */
    }
    for (int a = 1; a < 3; a++) /* three points sorted */
      for (int b = a; b > 0 && cmp_point(p[b], p[b - 1]) < 0; b--)
        for (int i = 0; i < 3; i++) {
          const double x = p[b][i];
          p[b][i] = p[b - 1][i], p[b - 1][i] = x;
        }
    memcpy(K[t].k, p, sizeof K[t].k);
    K[t].t = (uint32_t)t;
    K[t].file = s->shell[t];
  }
  qsort(K, nt, sizeof *K, cmp_key);
  size_t n = 0;
  for (size_t i = 0; i < nt;) {
    size_t j = i + 1;
    int two = 0;
    for (; j < nt && !memcmp(K[j].k, K[i].k, sizeof K[i].k); j++) two |= K[j].file != K[i].file;
    for (size_t x = i; two && x < j; x++) shared[K[x].t] = 1, n++;
    i = j;
  }
  mx_free(K);
  *nshared = n;
  return MX_OK;
}
