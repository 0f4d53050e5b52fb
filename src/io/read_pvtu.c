/* mixoct: reading a parallel VTU master (.pvtu) and its pieces (see
 * read_mesh.h).
 *
 * The master names its pieces (<Piece Source="..."/>, relative to its own
 * directory unless absolute); each is read as a VTU file on its own
 * (mx_rd_file with a piece_info), all pieces must have the same point and
 * cell arrays (names and types), and the pieces are merged: with
 * GlobalNodeId in every piece, the points of one id are one node (their
 * coordinates must agree bitwise), the nodes numbered by id; without it,
 * points of different pieces with bitwise-equal coordinates are one node
 * (within a piece points stay distinct: the k-th point of a piece at some
 * place joins the k-th of each other piece there), numbered in the order
 * they first appear. Both merges sort 64-bit keys (the ids, or a hash of
 * the coordinates), so time and memory are O(total size). Cells (and the
 * faces of a planar read) are concatenated in piece order; surface_tag
 * follows the node and must agree between the pieces sharing it; the cell
 * field material (cell_tag) follows the cells, and every piece with cells
 * must have it if one has. */
#include "io/mesh_reader.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>

#include "base/common.h"
#include "base/scan.h"
#include "io/vtk_xml.h"

typedef struct {
  const char *tag; /* its <Piece> element in the master, for messages */
  char *path;
  mx_mesh_data m;
  piece_info info;
} pvtu_piece;

typedef struct {
  pvtu_piece *pc;
  size_t n, cap;
  size_t *poff;            /* n + 1: points before each piece */
  double *xyz;             /* every piece's points, in piece order */
  int32_t *tag;            /* their surface_tag, or NULL */
  uint64_t *gid;           /* their GlobalNodeId, or NULL */
  uint32_t *map, *node_rep; /* point -> merged node; node -> one of its points */
  size_t npoints, nnodes;
  const pvtu_piece *labelled_from; /* the first piece with cells */
} pvtu;

static void pvtu_free(pvtu *V) {
  for (size_t i = 0; i < V->n; i++) {
    mx_free(V->pc[i].path);
    mx_mesh_data_free(&V->pc[i].m);
    mx_free(V->pc[i].info.gid);
  }
  mx_free(V->pc);
  mx_free(V->poff);
  mx_free(V->xyz);
  mx_free(V->tag);
  mx_free(V->gid);
  mx_free(V->map);
  mx_free(V->node_rep);
  memset(V, 0, sizeof *V);
}

/* The file a <Piece> names: its Source with the XML entities undone, after
 * the master's directory unless it is absolute. */
static int piece_path(const rd *r, const xtag *t, char **path) {
  const char *v;
  size_t n;
  if (!mx_rd_xml_attr(t, "Source", &v, &n))
    return mx_rd_fail(r, t->start, "<Piece> has no Source attribute");
  if (n == 0) return mx_rd_fail(r, t->start, "<Piece Source=\"\"> names no file");
  if (memchr(v, '\0', n)) return mx_rd_fail(r, t->start, "<Piece> Source has a NUL byte");
  const char *slash = strrchr(r->path, '/');
  const size_t dl = v[0] == '/' || !slash ? 0 : (size_t)(slash + 1 - r->path);
  char *s = mx_alloc(dl + n + 1);
  if (!s) return MX_ENOMEM;
  memcpy(s, r->path, dl);
  static const char *const ent[5][2] = {
      {"&amp;", "&"}, {"&lt;", "<"}, {"&gt;", ">"}, {"&quot;", "\""}, {"&apos;", "'"}};
  size_t w = dl;
  for (size_t i = 0; i < n;) {
    int k = 0;
    while (k < 5 && !(v[i] == '&' && n - i >= strlen(ent[k][0]) &&
                      memcmp(v + i, ent[k][0], strlen(ent[k][0])) == 0))
      k++;
    if (k < 5) {
      s[w++] = ent[k][1][0];
      i += strlen(ent[k][0]);
    } else {
      s[w++] = v[i++];
    }
  }
  s[w] = '\0';
  *path = s;
  return MX_OK;
}

/* The <Piece> elements of the master, from p on. */
static int pvtu_list_pieces(rd *r, const char *p, pvtu *V) {
  int grid = 0;
  for (;;) {
    xtag t;
    int found;
    MX_CHECK(mx_rd_xml_next(r, p, &t, &found));
    if (!found) break;
    p = t.after;
    if (mx_rd_tag_is(&t, "VTKFile") && t.closing) break;
    if (mx_rd_tag_is(&t, "PUnstructuredGrid") && !t.closing) grid = 1;
    if (!mx_rd_tag_is(&t, "Piece") || t.closing) continue;
    if (V->n == V->cap) {
      const size_t cap = V->cap ? 2 * V->cap : 16;
      pvtu_piece *pc = mx_realloc(V->pc, cap * sizeof *pc);
      if (!pc) return MX_ENOMEM;
      V->pc = pc;
      V->cap = cap;
    }
    pvtu_piece *pc = &V->pc[V->n];
    memset(pc, 0, sizeof *pc);
    pc->tag = t.start;
    V->n++;
    MX_CHECK(piece_path(r, &t, &pc->path));
  }
  if (!grid) return mx_rd_fail(r, NULL, "no <PUnstructuredGrid> element");
  if (!V->n) return mx_rd_fail(r, NULL, "no <Piece> element: a .pvtu needs at least one piece");
  return MX_OK;
}

/* Reads every piece and checks that they agree. */
static int pvtu_read_pieces(rd *r, pvtu *V) {
  int faces = 0, cells = 0;
  for (size_t i = 0; i < V->n; i++) {
    pvtu_piece *pc = &V->pc[i];
    struct stat sb;
    if (stat(pc->path, &sb) != 0)
      return mx_rd_fail(r, pc->tag, "piece %zu: cannot read '%s': %s", i, pc->path, strerror(errno));
    if (!S_ISREG(sb.st_mode)) /* a directory, a device: nothing to read, or no end */
      return mx_rd_fail(r, pc->tag, "piece %zu: '%s' is not a regular file", i, pc->path);
    if (mx_rd_file(pc->path, r->planar, &pc->info, &pc->m) != MX_OK)
      return mx_rd_fail(r, pc->tag, "piece %zu ('%s') could not be read", i, pc->path);
    const pvtu_piece *p0 = &V->pc[0];
    if (pc->info.point_sig != p0->info.point_sig || pc->info.cell_sig != p0->info.cell_sig)
      return mx_rd_fail(r, pc->tag,
                        "piece %zu ('%s'): its %s arrays (names or types) differ from those of "
                        "piece 0 ('%s')",
                        i, pc->path, pc->info.point_sig != p0->info.point_sig ? "point" : "cell",
                        p0->path);
    if (!pc->info.gid != !p0->info.gid || !pc->m.node_tag != !p0->m.node_tag)
      return mx_rd_fail(r, pc->tag, "piece %zu ('%s'): GlobalNodeId or surface_tag differ from "
                        "piece 0's", i, pc->path);
    faces |= pc->m.nfaces > 0;
    cells |= pc->m.ncells > 0;
    if (pc->m.ncells) {
      if (!V->labelled_from) V->labelled_from = pc;
      else if (!pc->m.cell_tag != !V->labelled_from->m.cell_tag)
        return mx_rd_fail(r, pc->tag, "piece %zu ('%s') has %s material cell field, piece %zu "
                          "('%s') %s", i, pc->path, pc->m.cell_tag ? "a" : "no",
                          (size_t)(V->labelled_from - V->pc), V->labelled_from->path,
                          V->labelled_from->m.cell_tag ? "has one" : "has none");
    }
    if (V->npoints + pc->m.nnodes >= UINT32_MAX)
      return mx_rd_fail(r, pc->tag, "the pieces have more than %u points together", UINT32_MAX - 1);
    V->npoints += pc->m.nnodes;
  }
  if (r->planar && faces && cells)
    return mx_rd_fail(r, NULL, "some pieces have volume cells, others triangles or quadrilaterals");
  return MX_OK;
}

/* The pieces' points one after the other (the pieces' own arrays freed). */
static int pvtu_gather_points(pvtu *V) {
  const size_t N = V->npoints;
  const int with_tag = V->pc[0].m.node_tag != NULL, with_gid = V->pc[0].info.gid != NULL;
  V->poff = mx_alloc((V->n + 1) * sizeof *V->poff);
  V->xyz = mx_alloc((3 * N + 1) * sizeof *V->xyz);
  if (with_tag) V->tag = mx_alloc((N + 1) * sizeof *V->tag);
  if (with_gid) V->gid = mx_alloc((N + 1) * sizeof *V->gid);
  if (!V->poff || !V->xyz || (with_tag && !V->tag) || (with_gid && !V->gid)) return MX_ENOMEM;
  size_t at = 0;
  for (size_t i = 0; i < V->n; i++) {
    pvtu_piece *pc = &V->pc[i];
    const size_t n = pc->m.nnodes;
    V->poff[i] = at;
    if (n) memcpy(V->xyz + 3 * at, pc->m.xyz, 3 * n * sizeof *V->xyz);
    if (with_tag && n) memcpy(V->tag + at, pc->m.node_tag, n * sizeof *V->tag);
    if (with_gid && n) memcpy(V->gid + at, pc->info.gid, n * sizeof *V->gid);
    mx_free(pc->m.xyz);
    mx_free(pc->m.node_tag);
    mx_free(pc->info.gid);
    pc->m.xyz = NULL;
    pc->m.node_tag = NULL;
    pc->info.gid = NULL;
    at += n;
  }
  V->poff[V->n] = at;
  return MX_OK;
}

/* The piece point q belongs to. */
static size_t piece_of(const pvtu *V, size_t q) {
  size_t lo = 0, hi = V->n;
  while (hi - lo > 1) {
    const size_t mid = lo + (hi - lo) / 2;
    if (V->poff[mid] <= q)
      lo = mid;
    else
      hi = mid;
  }
  return lo;
}

static int same_point(const pvtu *V, size_t a, size_t b) {
  return memcmp(V->xyz + 3 * a, V->xyz + 3 * b, 3 * sizeof *V->xyz) == 0;
}

/* Points with one GlobalNodeId are one node, the nodes in id order. */
static int merge_by_ids(rd *r, pvtu *V, uint32_t *idx) {
  const size_t N = V->npoints;
  MX_CHECK(mx_sort_u64(V->gid, idx, N));
  size_t K = 0;
  for (size_t i = 0; i < N; i++) K += i == 0 || V->gid[i] != V->gid[i - 1];
  V->node_rep = mx_alloc((K + 1) * sizeof *V->node_rep);
  if (!V->node_rep) return MX_ENOMEM;
  size_t k = 0;
  for (size_t i = 0; i < N; i++) {
    if (i == 0 || V->gid[i] != V->gid[i - 1]) {
      k = i == 0 ? 0 : k + 1;
      V->node_rep[k] = idx[i];
    } else if (!same_point(V, idx[i], V->node_rep[k])) {
      const size_t a = piece_of(V, V->node_rep[k]), b = piece_of(V, idx[i]);
      return mx_rd_fail(r, NULL,
                        "GlobalNodeId %llu has different coordinates in piece %zu ('%s', point %zu) "
                        "and piece %zu ('%s', point %zu)",
                        (unsigned long long)V->gid[i], a, V->pc[a].path,
                        (size_t)V->node_rep[k] - V->poff[a], b, V->pc[b].path,
                        (size_t)idx[i] - V->poff[b]);
    }
    V->map[idx[i]] = (uint32_t)k;
  }
  V->nnodes = K;
  return MX_OK;
}

typedef struct {
  uint64_t c[3];
  uint32_t q;
} coord_item;

static int coord_item_cmp(const void *pa, const void *pb) {
  const coord_item *a = pa, *b = pb;
  for (int k = 0; k < 3; k++)
    if (a->c[k] != b->c[k]) return a->c[k] < b->c[k] ? -1 : 1;
  return a->q < b->q ? -1 : a->q > b->q;
}

/* One group of points at one place, ascending: in map, each point's
 * representative (the k-th point of each piece there joins the k-th
 * point of the first piece having one). reps: room for n. */
static void coord_group(const pvtu *V, const uint32_t *g, size_t n, uint32_t *reps) {
  size_t nreps = 0, j = 0, cur = SIZE_MAX;
  for (size_t i = 0; i < n; i++) {
    const size_t pc = piece_of(V, g[i]);
    if (pc != cur) {
      cur = pc;
      j = 0;
    }
    if (j == nreps) reps[nreps++] = g[i];
    V->map[g[i]] = reps[j++];
  }
}

/* Points of different pieces with bitwise-equal coordinates are one node,
 * the nodes in the order they first appear. */
static int merge_by_coords(pvtu *V, uint32_t *idx) {
  const size_t N = V->npoints;
  uint64_t *key = mx_alloc((N + 1) * sizeof *key);
  if (!key) return MX_ENOMEM;
#pragma omp parallel for schedule(static) if (N > 65536)
  for (size_t i = 0; i < N; i++) {
    uint64_t h = 0x9e3779b97f4a7c15ull;
    for (int a = 0; a < 3; a++) {
      uint64_t b;
      memcpy(&b, V->xyz + 3 * i + a, sizeof b);
      h = (h ^ b) * 0xbf58476d1ce4e5b9ull;
      h ^= h >> 31;
    }
    key[i] = h;
  }
  int st = mx_sort_u64(key, idx, N);
  uint32_t *reps = NULL;
  coord_item *items = NULL;
  size_t cap = 0;
  for (size_t s = 0, e; st == MX_OK && s < N; s = e) {
    e = s + 1;
    int one_place = 1;
    while (e < N && key[e] == key[s]) {
      one_place &= same_point(V, idx[e], idx[s]);
      e++;
    }
    const size_t n = e - s;
    if (n > cap) {
      cap = 2 * n;
      mx_free(reps);
      mx_free(items);
      reps = mx_alloc(cap * sizeof *reps);
      items = mx_alloc(cap * sizeof *items);
      if (!reps || !items) {
        st = MX_ENOMEM;
        break;
      }
    }
    if (one_place) { /* the usual case: idx ascending within equal keys (stable sort) */
      coord_group(V, idx + s, n, reps);
      continue;
    }
    /* a hash collision: the places apart */
    for (size_t i = 0; i < n; i++) {
      memcpy(items[i].c, V->xyz + 3 * (size_t)idx[s + i], sizeof items[i].c);
      items[i].q = idx[s + i];
    }
    qsort(items, n, sizeof *items, coord_item_cmp);
    for (size_t a = 0, b; a < n; a = b) {
      for (b = a; b < n && memcmp(items[b].c, items[a].c, sizeof items[a].c) == 0; b++)
        idx[s + b] = items[b].q;
      coord_group(V, idx + s + a, b - a, reps);
    }
  }
  mx_free(key);
  mx_free(reps);
  mx_free(items);
  if (st != MX_OK) return st;
  /* number the representatives in point order; idx becomes their numbers */
#pragma omp parallel for schedule(static) if (N > 65536)
  for (size_t i = 0; i < N; i++) idx[i] = V->map[i] == i;
  V->nnodes = mx_scan_u32(idx, N);
  V->node_rep = mx_alloc((V->nnodes + 1) * sizeof *V->node_rep);
  if (!V->node_rep) return MX_ENOMEM;
  for (size_t i = 0; i < N; i++) {
    const uint32_t rep = V->map[i]; /* <= i: its own number is still there */
    if (rep == i) V->node_rep[idx[i]] = (uint32_t)i;
    V->map[i] = idx[rep];
  }
  return MX_OK;
}

/* The merged nodes, cells and faces into out. */
static int pvtu_assemble(rd *r, pvtu *V, mx_mesh_data *out) {
  const size_t K = V->nnodes;
  out->nnodes = K;
  out->xyz = mx_alloc((3 * K + 1) * sizeof *out->xyz);
  if (!out->xyz) return MX_ENOMEM;
#pragma omp parallel for schedule(static) if (K > 65536)
  for (size_t k = 0; k < K; k++)
    memcpy(out->xyz + 3 * k, V->xyz + 3 * (size_t)V->node_rep[k], 3 * sizeof *out->xyz);
  if (V->tag) {
    out->node_tag = mx_alloc((K + 1) * sizeof *out->node_tag);
    if (!out->node_tag) return MX_ENOMEM;
#pragma omp parallel for schedule(static) if (K > 65536)
    for (size_t k = 0; k < K; k++) out->node_tag[k] = V->tag[V->node_rep[k]];
    size_t bad = SIZE_MAX;
#pragma omp parallel for schedule(static) reduction(min : bad) if (V->npoints > 65536)
    for (size_t q = 0; q < V->npoints; q++)
      if (V->tag[q] != out->node_tag[V->map[q]] && q < bad) bad = q;
    if (bad != SIZE_MAX) {
      const size_t b = piece_of(V, bad);
      return mx_rd_fail(r, NULL, "surface_tag of point %zu of piece %zu ('%s') differs from that of "
                        "the same node in another piece", bad - V->poff[b], b, V->pc[b].path);
    }
  }
  size_t C = 0, F = 0;
  for (size_t i = 0; i < V->n; i++) {
    C += V->pc[i].m.ncells;
    F += V->pc[i].m.nfaces;
  }
  out->ncells = C;
  out->type = mx_alloc(C + 1);
  out->conn = mx_alloc((8 * C + 1) * sizeof *out->conn);
  if (!out->type || !out->conn) return MX_ENOMEM;
  if (V->labelled_from && V->labelled_from->m.cell_tag) {
    out->cell_tag = mx_alloc((C + 1) * sizeof *out->cell_tag);
    if (!out->cell_tag) return MX_ENOMEM;
  }
  if (F) {
    out->nfaces = F;
    out->face_nn = mx_alloc(F);
    out->face_conn = mx_alloc(4 * F * sizeof *out->face_conn);
    out->face_tag = mx_alloc(F * sizeof *out->face_tag);
    if (!out->face_nn || !out->face_conn || !out->face_tag) return MX_ENOMEM;
  }
  size_t c0 = 0, f0 = 0;
  for (size_t i = 0; i < V->n; i++) {
    mx_mesh_data *m = &V->pc[i].m;
    const uint32_t *map = V->map + V->poff[i];
    const size_t nc = m->ncells, nf = m->nfaces;
    if (nc) memcpy(out->type + c0, m->type, nc);
    if (nc && out->cell_tag) memcpy(out->cell_tag + c0, m->cell_tag, nc * sizeof *out->cell_tag);
#pragma omp parallel for schedule(static) if (nc > 65536)
    for (size_t c = 0; c < nc; c++) {
      const uint32_t *row = m->conn + 8 * c;
      uint32_t *to = out->conn + 8 * (c0 + c);
      const int nn = mx_cell_nodes[m->type[c]];
      for (int j = 0; j < 8; j++) to[j] = j < nn ? map[row[j]] : 0;
    }
    for (size_t f = 0; f < nf; f++) {
      out->face_nn[f0 + f] = m->face_nn[f];
      out->face_tag[f0 + f] = m->face_tag[f];
      for (int j = 0; j < 4; j++)
        out->face_conn[4 * (f0 + f) + (size_t)j] =
            j < m->face_nn[f] ? map[m->face_conn[4 * f + (size_t)j]] : 0;
    }
    c0 += nc;
    f0 += nf;
    mx_mesh_data_free(m);
  }
  return MX_OK;
}

int mx_rd_pvtu(rd *r, const char *p, mx_mesh_data *out) {
  r->merged = 1; /* the pieces' wedges are in our order already */
  pvtu V;
  memset(&V, 0, sizeof V);
  int st = pvtu_list_pieces(r, p, &V);
  if (st == MX_OK) st = pvtu_read_pieces(r, &V);
  if (st == MX_OK) st = pvtu_gather_points(&V);
  uint32_t *idx = NULL;
  if (st == MX_OK) {
    V.map = mx_alloc((V.npoints + 1) * sizeof *V.map);
    idx = mx_alloc((V.npoints + 1) * sizeof *idx);
    if (!V.map || !idx) st = MX_ENOMEM;
  }
  if (st == MX_OK) {
#pragma omp parallel for schedule(static) if (V.npoints > 65536)
    for (size_t i = 0; i < V.npoints; i++) idx[i] = (uint32_t)i;
    st = V.gid ? merge_by_ids(r, &V, idx) : merge_by_coords(&V, idx);
  }
  mx_free(idx);
  if (st == MX_OK) st = pvtu_assemble(r, &V, out);
  pvtu_free(&V);
  return st;
}
