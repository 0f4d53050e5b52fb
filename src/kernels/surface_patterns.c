#include "kernels/surface_patterns.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "base/common.h"
#include "kernels/boundary.h"
#include "kernels/mesh_edit.h"
#include "geom/quality.h"
#include "patterns/surface_table.h"
#include "soa/mesh.h"
#include "base/scan.h"

static const int case_base[4] = {-1, MX_SURFACE_BASE_PYRAMID, MX_SURFACE_BASE_PRISM,
                                 MX_SURFACE_BASE_HEX};

static const mx_surface_case gone = {0, 0, 0, 0, 0};

/* The table case of element c: NULL when it stays as it is, &gone when it
 * has no inside node (it is removed). */
static const mx_surface_case *case_of(const mx_mesh *M, const uint8_t *states, size_t c) {
  const int t = M->type[c];
  const int nv = mx_cell_nodes[t];
  unsigned m = 0;
  for (int k = 0; k < nv; k++)
    m |= (unsigned)mx_node_inside(states[M->conn[8 * c + k]]) << k;
  if (m == 0) return &gone;
  if (t == MX_TET) return NULL;
  const mx_surface_case *sc = &mx_surface_cases[case_base[t] + (int)m];
  return sc->count ? sc : NULL;
}

/* Sub-element e of case sc: 1 if kept (an inside vertex, or the centre when
 * it is inside); *centre set when it uses the centre. */
static int sub_kept(const mx_surface_case *sc, const mx_pattern_elem *e, int *centre) {
  const int nv = mx_cell_nodes[e->type];
  int kept = 0;
  *centre = 0;
  for (int k = 0; k < nv; k++) {
    if (e->v[k] == MX_SURFACE_CENTRE) {
      *centre = 1;
      kept |= sc->centre == 1;
    } else {
      kept |= (sc->mask >> e->v[k]) & 1;
    }
  }
  return kept;
}

/* What element c becomes: *kept sub-elements (1 for an element left as it
 * is, 0 for one removed), *optional dropped ones, *centre 1 when the kept
 * ones use the element centre; returns the case (NULL: as it is, &gone:
 * removed). */
static const mx_surface_case *element_counts(const mx_mesh *M, const uint8_t *states,
                                             size_t c, uint32_t *kept, uint32_t *optional,
                                             uint32_t *centre) {
  const mx_surface_case *sc = case_of(M, states, c);
  *kept = sc ? 0 : 1;
  *optional = *centre = 0;
  if (!sc || sc == &gone) return sc;
  for (int i = 0; i < sc->count; i++) {
    int uc;
    if (sub_kept(sc, &mx_surface_elems[sc->first + i], &uc)) {
      (*kept)++;
      *centre |= (uint32_t)uc;
    } else {
      *optional += (uint32_t)!uc;
    }
  }
  return sc;
}

/* Elements are counted and filled by blocks: the counts are kept per block
 * only (a few KB, not three words per element), and the fill walks each
 * block again from its block's offsets. */
enum { SP_BLOCK = 2048, SP_WINDOW = 128 };

/* The element arrays a block's output goes to. */
typedef struct {
  uint8_t *type, *level;
  uint32_t *conn, *leaf;
  float *jens;
} cell_arrays;

/* What the fill of one block needs besides the destination. */
typedef struct {
  const mx_mesh *M; /* the input elements (M->type ... M->jens) */
  const uint8_t *moved;
  const uint64_t *bout, *bopt, *bcen; /* per block: first output, optional, centre */
  size_t nc, nn;
  double *xyz; /* grown by the centres */
  uint8_t *st2; /* the states, grown by the centres */
  uint64_t *nkey;
  mx_optional *opt;
  uint8_t *used; /* the nodes the written elements use, marked */
} fill_ctx;

/* Elements [from, to) of M are read for good: their pages go. */
static void release_cells(const mx_mesh *M, size_t from, size_t to) {
  mx_release_range(M->type, from, to);
  mx_release_range(M->level, from, to);
  mx_release_range(M->conn, 8 * from * sizeof *M->conn, 8 * to * sizeof *M->conn);
  mx_release_range(M->leaf, from * sizeof *M->leaf, to * sizeof *M->leaf);
  mx_release_range(M->jens, from * sizeof *M->jens, to * sizeof *M->jens);
}

/* Block b's elements, what each becomes, written from output position
 * bout[b] on in d (the block's input is read before its output is
 * written only when the two do not overlap: the caller's rule). */
static void fill_block(const fill_ctx *F, size_t b, const cell_arrays *d) {
  const mx_mesh *M = F->M;
  const uint8_t *states = F->st2;
  const double *xyz = F->xyz;
  mx_optional *opt = F->opt;
  const size_t end = (b + 1) * SP_BLOCK < F->nc ? (b + 1) * SP_BLOCK : F->nc;
  uint64_t w = F->bout[b], o = F->bopt[b], cnext = F->bcen[b];
  for (size_t c = b * SP_BLOCK; c < end; c++) {
    uint32_t kc, oc, need;
    const mx_surface_case *sc = element_counts(M, states, c, &kc, &oc, &need);
    if (sc == &gone) continue;
    const uint32_t *v = M->conn + 8 * c;
    if (!sc) {
      d->type[w] = M->type[c];
      for (int k = 0; k < mx_cell_nodes[M->type[c]]; k++)
        __atomic_store_n(&F->used[v[k]], 1, __ATOMIC_RELAXED);
      memcpy(d->conn + 8 * w, v, 8 * sizeof *d->conn);
      d->level[w] = M->level[c];
      d->leaf[w] = M->leaf[c];
      int mv = 0;
      for (int k = 0; F->moved && k < mx_cell_nodes[M->type[c]]; k++) mv |= F->moved[v[k]];
      d->jens[w] = mv ? NAN : M->jens[c]; /* (the shrink measures it) */
      w++;
      continue;
    }
    const int nv = mx_cell_nodes[M->type[c]];
    uint32_t centre = UINT32_MAX;
    if (need) {
      centre = (uint32_t)(F->nn + cnext++);
      double p[3] = {0.0, 0.0, 0.0};
      for (int k = 0; k < nv; k++)
        for (int a = 0; a < 3; a++) p[a] += xyz[3 * (size_t)v[k] + a];
      for (int a = 0; a < 3; a++) F->xyz[3 * (size_t)centre + a] = p[a] / nv;
      F->st2[centre] = sc->centre == 1 ? MX_NODE_INSIDE : MX_NODE_OUTSIDE;
      if (F->nkey) F->nkey[centre] = MX_NKEY_NONE;
    }
    /* the input row and its level and leaf first: the sub-elements may be
     * written over them */
    uint32_t in[8];
    memcpy(in, v, sizeof in);
    const uint8_t lev = M->level[c];
    const uint32_t lf = M->leaf[c];
    for (int i = 0; i < sc->count; i++) {
      const mx_pattern_elem *e = &mx_surface_elems[sc->first + i];
      int uc;
      const int kept = sub_kept(sc, e, &uc);
      if (!kept && uc) continue;
      const int ne = mx_cell_nodes[e->type];
      uint32_t g[8] = {0, 0, 0, 0, 0, 0, 0, 0};
      for (int k = 0; k < ne; k++) g[k] = e->v[k] == MX_SURFACE_CENTRE ? centre : in[e->v[k]];
      if (kept) {
        for (int k = 0; k < ne; k++) __atomic_store_n(&F->used[g[k]], 1, __ATOMIC_RELAXED);
        d->type[w] = e->type;
        memcpy(d->conn + 8 * w, g, sizeof g);
        d->level[w] = lev;
        d->leaf[w] = lf;
        d->jens[w] = NAN; /* (the shrink measures it) */
        w++;
      } else {
        opt->type[o] = e->type;
        memcpy(opt->conn + 8 * o, g, sizeof g);
        opt->leaf[o] = lf;
        opt->level[o] = lev;
        o++;
      }
    }
  }
}

/* The first output position of block b (the total past the last). */
static uint64_t out_at(const uint64_t *bout, size_t nb, uint64_t total, size_t b) {
  return b < nb ? bout[b] : total;
}

int mx_surface_patterns(mx_mesh *M, uint8_t **states_io, const uint8_t *moved,
                        mx_optional *opt, mx_surface_stats *stats, int keep_unused) {
  const size_t nc = M->ncells, nn = M->nnodes;
  const uint8_t *states = *states_io;
  memset(opt, 0, sizeof *opt);
  /* 1. Count kept and optional sub-elements and centres per block. */
  const size_t nb = (nc + SP_BLOCK - 1) / SP_BLOCK;
  uint64_t *bout = mx_alloc((3 * nb + 3) * sizeof *bout);
  if (!bout) return MX_ENOMEM;
  uint64_t *bopt = bout + nb + 1, *bcen = bopt + nb + 1;
  size_t patterned = 0, removed = 0;
#pragma omp parallel for schedule(static) reduction(+ : patterned, removed)
  for (size_t b = 0; b < nb; b++) {
    const size_t end = (b + 1) * SP_BLOCK < nc ? (b + 1) * SP_BLOCK : nc;
    uint64_t k = 0, o = 0, cen = 0;
    for (size_t c = b * SP_BLOCK; c < end; c++) {
      uint32_t kc, oc, cc;
      const mx_surface_case *sc = element_counts(M, states, c, &kc, &oc, &cc);
      removed += sc == &gone;
      patterned += sc && sc != &gone;
      k += kc;
      o += oc;
      cen += cc;
    }
    bout[b] = k;
    bopt[b] = o;
    bcen[b] = cen;
  }
  const uint64_t total = mx_scan_u64(bout, nb);
  const uint64_t total_opt = mx_scan_u64(bopt, nb);
  const uint64_t total_cen = mx_scan_u64(bcen, nb);
  /* 2. Fill. From the end, window by window, in place: a window's output
   * lies right of its whole input (the patterns add elements: the output
   * drifts right of the input as the mesh goes on), so it overwrites only
   * elements already read; the blocks before the first window where that
   * fails (the mesh's start, where the drift is still small) are filled
   * into new arrays, then copied to their place. */
  double *xyz = mx_realloc(M->xyz, (3 * (nn + total_cen) + 3) * sizeof *xyz);
  if (xyz) M->xyz = xyz;
  uint8_t *st2 = xyz ? mx_realloc(*states_io, nn + total_cen + 1) : NULL;
  if (st2) *states_io = st2;
  uint64_t *nkey = M->nkey && st2 ? mx_realloc(M->nkey, (nn + total_cen + 1) * sizeof *nkey)
                                  : NULL;
  if (nkey) M->nkey = nkey;
  opt->type = mx_alloc(total_opt + 1);
  opt->conn = mx_alloc((8 * total_opt + 1) * sizeof *opt->conn);
  opt->leaf = mx_alloc((total_opt + 1) * sizeof *opt->leaf);
  opt->level = mx_alloc((total_opt + 1) * sizeof *opt->level);
  int st = !xyz || !st2 || (M->nkey && !nkey) || !opt->type || !opt->conn || !opt->leaf ||
                   !opt->level
               ? MX_ENOMEM
               : MX_OK;
  if (!st && total > nc) st = mx_mesh_grow_cells(M, total);
  uint8_t *used = st ? NULL : mx_calloc(nn + total_cen + 1);
  if (!st && !used) st = MX_ENOMEM;
  if (st) {
    mx_free(bout);
    mx_optional_free(opt);
    return st;
  }
  const fill_ctx F = {M, moved, bout, bopt, bcen, nc, nn, xyz, st2, nkey, opt, used};
  const cell_arrays in_place = {M->type, M->level, M->conn, M->leaf, M->jens};
  size_t w1 = nb; /* blocks [w1, nb) done */
  const char *copy = getenv("MX_PATTERNS_COPY");
  const int copy_all = copy && strcmp(copy, "1") == 0;
  while (w1 > 0 && !copy_all) {
    /* the window: at most SP_WINDOW blocks, its output from where its
     * input ends (out_at(w0) >= the input end of block w1 - 1) */
    const uint64_t in_end = w1 * SP_BLOCK < nc ? w1 * SP_BLOCK : nc;
    size_t w0 = w1 > SP_WINDOW ? w1 - SP_WINDOW : 0;
    while (w0 < w1 && out_at(bout, nb, total, w0) < in_end) w0++;
    if (w1 - w0 < 16) break; /* too small a window to share: the rest copied */
#pragma omp parallel for schedule(dynamic, 4)
    for (size_t b = w0; b < w1; b++) fill_block(&F, b, &in_place);
    w1 = w0;
  }
  if (w1 > 0) {
    /* blocks [0, w1) into new arrays by windows, their input released as
     * they go (not the old and new arrays whole at once), then moved to
     * the start of M's */
    const size_t n = out_at(bout, nb, total, w1);
    cell_arrays d = {mx_alloc(n + 1), mx_alloc(n + 1), mx_alloc((8 * n + 1) * sizeof *d.conn),
                     mx_alloc((n + 1) * sizeof *d.leaf), mx_alloc((n + 1) * sizeof *d.jens)};
    if (!d.type || !d.level || !d.conn || !d.leaf || !d.jens) {
      mx_free(d.type); mx_free(d.level); mx_free(d.conn); mx_free(d.leaf); mx_free(d.jens);
      mx_free(bout);
      mx_free(used);
      mx_optional_free(opt);
      return MX_ENOMEM;
    }
    size_t released = 0;
    for (size_t a = 0; a < w1; a += SP_WINDOW) {
      const size_t e = a + SP_WINDOW < w1 ? a + SP_WINDOW : w1;
#pragma omp parallel for schedule(dynamic, 4)
      for (size_t b = a; b < e; b++) fill_block(&F, b, &d);
      const size_t done = e * SP_BLOCK < nc ? e * SP_BLOCK : nc;
      /* (not the part the in-place windows wrote: from out_at(w1) on) */
      const size_t upto = done < n ? done : n; /* (rises with the windows) */
      release_cells(M, released, upto);
      released = upto;
    }
    if (w1 == nb) { /* all of it: the new arrays are the mesh's */
      mx_free(M->type); mx_free(M->level); mx_free(M->conn); mx_free(M->leaf);
      mx_free(M->jens);
      M->type = d.type; M->level = d.level; M->conn = d.conn; M->leaf = d.leaf;
      M->jens = d.jens;
    } else {
      memcpy(M->type, d.type, n);
      memcpy(M->level, d.level, n);
      memcpy(M->conn, d.conn, 8 * n * sizeof *d.conn);
      memcpy(M->leaf, d.leaf, n * sizeof *d.leaf);
      memcpy(M->jens, d.jens, n * sizeof *d.jens);
      mx_free(d.type); mx_free(d.level); mx_free(d.conn); mx_free(d.leaf); mx_free(d.jens);
    }
  }
  stats->in_place = total - out_at(bout, nb, total, w1);
  mx_free(bout);
  M->ncells = total;
  M->nnodes = nn + total_cen;
  opt->n = total_opt;
  /* 3. Nodes only dropped elements used go (unless kept: keep_unused);
   * the optional elements keep only those whose nodes all remain. */
  uint32_t *newid = NULL;
  st = keep_unused ? MX_OK : mx_mesh_drop_nodes(M, states_io, used, &newid);
  if (st) {
    mx_free(used);
    mx_optional_free(opt);
    return st;
  }
  size_t no = 0;
  for (size_t i = 0; i < opt->n; i++) {
    const int ne = mx_cell_nodes[opt->type[i]];
    int ok = 1;
    uint32_t g[8] = {0, 0, 0, 0, 0, 0, 0, 0};
    for (int k = 0; k < ne && ok; k++) {
      const uint32_t v = opt->conn[8 * i + k];
      g[k] = newid ? newid[v] : used[v] ? v : UINT32_MAX;
      ok = g[k] != UINT32_MAX;
    }
    if (!ok) continue;
    opt->type[no] = opt->type[i];
    memcpy(opt->conn + 8 * no, g, sizeof g);
    opt->leaf[no] = opt->leaf[i];
    opt->level[no] = opt->level[i];
    no++;
  }
  mx_free(newid);
  mx_free(used);
  stats->patterned = patterned;
  stats->removed = removed;
  stats->kept = total;
  stats->optional = total_opt;
  stats->centres = total_cen;
  opt->n = no;
  mx_mesh_summarize(M);
  return MX_OK;
}

void mx_optional_free(mx_optional *opt) {
  mx_free(opt->type);
  mx_free(opt->conn);
  mx_free(opt->leaf);
  mx_free(opt->level);
  memset(opt, 0, sizeof *opt);
}
