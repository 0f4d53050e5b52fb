/* The restart file (Appendix A of the 2021 paper) of a mesher, and the
 * octree rebuilt from one (src/io/restart.h holds the file formats).
 *
 * Written: the nodes are the corners of every stored octant (split ones
 * too), in Morton order of their lattice points; the edges are the 12 edges
 * of every stored octant, with their mid-node when a finer octant has it as
 * a corner; the octants are the leaves in Morton order (the order of the
 * element -> leaf map), each with its corners in the published order, its
 * level and the domain triangles it meets; the transform is zero; the
 * sub-element counts are the elements of each leaf (the mesh's elements are
 * grouped by leaf). The binary variant (.octb) has no edges: they are
 * implied by the octants, and the reader does not need them.
 *
 * Read: each octant's lowest corner and level give its Morton key on the
 * grid of the input surfaces; every ancestor of a leaf is split, so the
 * octree is rebuilt by refining from the roots with that split set (the
 * requests apply on top), exactly the octree of the run that wrote it when
 * the file is ours. Elements of the file's mesh map to the leaf holding
 * their octant's centre. */
#include "mesher/materials.h"
#include "mesher/mesher_impl.h"
#include "mesher/pipeline.h"

#include "kernels/mesh_edit.h"

#include "io/element_list.h"
#include "io/restart.h"
#include "kernels/grid.h"
#include "soa/key_index.h"
#include "base/scan.h"

#include <math.h>
#include <omp.h>
#include <string.h>

/* Corner c of the published order: bit pattern (x, y, z) per corner. */
static const uint8_t corner_xyz[8][3] = {{0, 0, 0}, {0, 0, 1}, {1, 0, 1}, {1, 0, 0},
                                         {0, 1, 0}, {0, 1, 1}, {1, 1, 1}, {1, 1, 0}};


/* The nodes and edges of the file are the corners and edges of every stored
 * octant, so each is shared by several octants: emitting all 8 corners and
 * 12 edges of every octant, then sorting and dropping repeats, sorts about
 * three keys for each one kept. Two rules leave most repeats unmade:
 * - a corner c of a split octant is corner c of its child c: the child
 *   emits it when that child is kept;
 * - a corner or edge shared by siblings is emitted by one of them: the
 *   sibling j & b for corner bits b (the one on the low side, per axis, of
 *   the point), and likewise for an edge on the two axes across it, when
 *   that sibling is kept.
 * Both hand the point or edge to an octant that has it too and is stored
 * (kept), and who it is handed to follows the same rules, so every corner
 * and edge of every stored octant is still emitted at least once; the sort
 * drops the repeats across families. Corner bits here: x | y << 1 | z << 2
 * (the children's numbering), not the published corner order. */
typedef struct {
  uint8_t corner[8][256]; /* [child j][parent's kept mask]: corners j emits */
  uint16_t edge[8][256];  /* the same for edges (bits a * 4 + jj) */
  uint64_t cdelta[MX_MAX_LEVEL + 1][8];  /* corner bits b as Morton offsets */
  uint64_t edelta[MX_MAX_LEVEL + 1][12]; /* lower end of edge a * 4 + jj */
} emit_tables;

/* The rules above for every (child, parent's kept mask), and the offsets of
 * the corners and edges of an octant of each level as Morton keys (added
 * to its key with mx_morton_add: no decoding). Edge bits a * 4 + jj: axis
 * a, offsets jj & 1 along a + 1, jj >> 1 along a + 2 (mod 3), as
 * mx_edge_key numbers them. */
static void emit_tables_make(emit_tables *E) {
  for (unsigned j = 0; j < 8; j++)
    for (unsigned kp = 0; kp < 256; kp++) {
      unsigned cm = 0, em = 0;
      for (unsigned b = 0; b < 8; b++) {
        const unsigned jc = j & b;
        if (jc == j || !((kp >> jc) & 1u)) cm |= 1u << b;
      }
      for (unsigned a = 0; a < 3; a++)
        for (unsigned jj = 0; jj < 4; jj++) {
          unsigned jc = j;
          if (!(jj & 1u)) jc &= ~(1u << ((a + 1) % 3));
          if (!(jj & 2u)) jc &= ~(1u << ((a + 2) % 3));
          if (jc == j || !((kp >> jc) & 1u)) em |= 1u << (a * 4 + jj);
        }
      E->corner[j][kp] = (uint8_t)cm;
      E->edge[j][kp] = (uint16_t)em;
    }
  for (int l = 0; l <= MX_MAX_LEVEL; l++) {
    const uint32_t s = mx_octant_size(l);
    for (unsigned b = 0; b < 8; b++)
      E->cdelta[l][b] = mx_morton_encode((b & 1u) * s, ((b >> 1) & 1u) * s, (b >> 2) * s);
    for (int a = 0; a < 3; a++)
      for (int jj = 0; jj < 4; jj++) {
        uint32_t p[3] = {0, 0, 0};
        p[(a + 1) % 3] = (uint32_t)(jj & 1) * s;
        p[(a + 2) % 3] = (uint32_t)(jj >> 1) * s;
        E->edelta[l][a * 4 + jj] = mx_morton_encode(p[0], p[1], p[2]);
      }
  }
}

static unsigned corner_emit_mask(const mx_octree *T, const emit_tables *E, uint32_t o) {
  const unsigned m = 0xffu & ~(unsigned)T->kept[o]; /* kept is 0 for a leaf */
  const uint32_t P = T->parent[o];
  if (P == MX_NONE) return m;
  return m & E->corner[mx_morton_child_id(T->key[o], T->level[o])][T->kept[P]];
}

static unsigned edge_emit_mask(const mx_octree *T, const emit_tables *E, uint32_t o) {
  const uint32_t P = T->parent[o];
  if (P == MX_NONE) return 0xfffu;
  return E->edge[mx_morton_child_id(T->key[o], T->level[o])][T->kept[P]];
}

enum { EMIT_MAX_THREADS = 256 };

/* The threads' shares of the octants: the same contiguous ranges in the
 * counting pass and the filling pass. */
static size_t share_lo(size_t n, int t, int nt) { return n * (size_t)t / (size_t)nt; }

/* Node keys: the corners of every stored octant, sorted and unique
 * (*vkey_out, *nv_out). */
static int restart_node_keys(const mx_octree *T, const emit_tables *E, uint64_t **vkey_out,
                             size_t *nv_out) {
  size_t cnt[EMIT_MAX_THREADS + 1] = {0};
  int nt = omp_get_max_threads();
  if (nt > EMIT_MAX_THREADS) nt = EMIT_MAX_THREADS;
  if (T->n < 65536) nt = 1;
#pragma omp parallel num_threads(nt)
  {
    const int t = omp_get_thread_num(), tn = omp_get_num_threads();
    size_t k = 0;
    for (size_t o = share_lo(T->n, t, tn); o < share_lo(T->n, t + 1, tn); o++)
      k += (size_t)__builtin_popcount(corner_emit_mask(T, E, (uint32_t)o));
    cnt[t + 1] = k;
#pragma omp single
    nt = tn;
  }
  for (int t = 0; t < nt; t++) cnt[t + 1] += cnt[t];
  uint64_t *vkey = mx_alloc((cnt[nt] + 1) * sizeof *vkey);
  if (!vkey) return MX_ENOMEM;
#pragma omp parallel num_threads(nt)
  {
    const int t = omp_get_thread_num();
    uint64_t *w = vkey + cnt[t];
    for (size_t o = share_lo(T->n, t, nt); o < share_lo(T->n, t + 1, nt); o++) {
      const uint64_t *d = E->cdelta[T->level[o]];
      for (unsigned m = corner_emit_mask(T, E, (uint32_t)o); m; m &= m - 1)
        *w++ = mx_morton_add(T->key[o], d[__builtin_ctz(m)]);
    }
  }
  int st = MX_OK;
  *nv_out = mx_sort_unique_u64(vkey, cnt[nt], &st);
  if (st) {
    mx_free(vkey);
    return st;
  }
  *vkey_out = vkey;
  return MX_OK;
}

enum { NLA = (MX_MAX_LEVEL + 1) * 3 }; /* (level, axis) pairs: la = level * 3 + axis */
enum { GEN_ROWS = 256 };                /* rows a generator makes at a time (binary file) */

/* What the text writer needs to make the edge rows and the octants'
 * corners while it writes (mx_restart's generators): the sorted node keys
 * and their index, the sorted edge keys of each (level, axis) and where
 * their rows start. */
typedef struct {
  const mx_mesher *m;
  uint64_t *vkey;       /* the nodes' lattice keys, sorted */
  size_t nv;
  mx_key_index H;       /* key -> node */
  uint64_t *keys[NLA];  /* edges: lower ends, sorted and unique */
  size_t first[NLA + 1]; /* row of the first edge of each (level, axis) */
  uint32_t split_levels; /* bit l: an octant of level l has a kept child */
  emit_tables E;
  uint64_t pdelta[MX_MAX_LEVEL + 1][8]; /* corners in the published order */
} restart_gen;

static void restart_gen_free(restart_gen *g) {
  mx_free(g->vkey);
  mx_key_index_free(&g->H);
  for (int la = 0; la < NLA; la++) mx_free(g->keys[la]);
  memset(g, 0, sizeof *g);
}

/* Edges of every stored octant, per (level, axis), sorted and unique. */
static int restart_edge_keys(const mx_mesher *m, const emit_tables *E, restart_gen *g) {
  const mx_octree *T = &m->B.tree.oct;
  int nt = omp_get_max_threads();
  if (nt > 64) nt = 64;
  if (T->n < 65536) nt = 1;
  /* cnt[t][la]: thread t's edges of (level, axis) la; then where they go */
  size_t(*cnt)[NLA] = mx_calloc((size_t)nt * sizeof *cnt);
  size_t nk[NLA];
  memset(nk, 0, sizeof nk);
  int st = cnt ? MX_OK : MX_ENOMEM;
  uint32_t split_levels = 0;
  if (!st) {
#pragma omp parallel num_threads(nt)
    {
      const int t = omp_get_thread_num(), tn = omp_get_num_threads();
      size_t *c = cnt[t];
      uint32_t split = 0;
      for (size_t o = share_lo(T->n, t, tn); o < share_lo(T->n, t + 1, tn); o++) {
        const unsigned em = edge_emit_mask(T, E, (uint32_t)o);
        const int l = T->level[o];
        for (int a = 0; a < 3; a++) c[l * 3 + a] += (size_t)__builtin_popcount((em >> (4 * a)) & 15u);
        if (T->kept[o]) split |= 1u << l;
      }
#pragma omp atomic
      split_levels |= split;
#pragma omp single
      nt = tn;
    }
    for (int la = 0; la < NLA; la++) {
      size_t s = 0;
      for (int t = 0; t < nt; t++) {
        const size_t c = cnt[t][la];
        cnt[t][la] = s;
        s += c;
      }
      nk[la] = s;
      if (s && !st) {
        g->keys[la] = mx_alloc(s * sizeof **g->keys);
        if (!g->keys[la]) st = MX_ENOMEM;
      }
    }
  }
  g->split_levels = split_levels;
  if (!st) {
#pragma omp parallel num_threads(nt)
    {
      const int t = omp_get_thread_num();
      size_t *w = cnt[t];
      for (size_t o = share_lo(T->n, t, nt); o < share_lo(T->n, t + 1, nt); o++) {
        const int l = T->level[o];
        const uint64_t *d = E->edelta[l];
        for (unsigned em = edge_emit_mask(T, E, (uint32_t)o); em; em &= em - 1) {
          const int e = __builtin_ctz(em), la = l * 3 + e / 4;
          g->keys[la][w[la]++] = mx_morton_add(T->key[o], d[e]);
        }
      }
    }
  }
  g->first[0] = 0;
  for (int la = 0; la < NLA; la++) {
    if (!st && g->keys[la]) nk[la] = mx_sort_unique_u64(g->keys[la], nk[la], &st);
    g->first[la + 1] = g->first[la] + (st ? 0 : nk[la]);
  }
  mx_free(cnt);
  return st;
}

/* Coordinates of nodes [begin, end): their lattice points through the grid. */
static void node_rows(const void *gen, size_t begin, size_t end, double *xyz) {
  const restart_gen *g = gen;
  const mx_grid *gr = &g->m->B.tree.grid;
  for (size_t i = begin; i < end; i++, xyz += 3) {
    uint32_t p[3];
    mx_morton_decode(g->vkey[i], p);
    for (int a = 0; a < 3; a++) xyz[a] = gr->origin[a] + (double)p[a] * gr->unit;
  }
}

/* Rows [begin, end) of the edges section: the ends and the mid-node (0:
 * none) of each edge, from the node index, the lookups of a few edges
 * ahead prefetched. Called by the writer's threads, block by block. */
static void edge_rows(const void *gen, size_t begin, size_t end, uint32_t *rows) {
  const restart_gen *g = gen;
  enum { AHEAD = 8 };
  int la = 0;
  while (g->first[la + 1] <= begin) la++;
  for (size_t row = begin; row < end; la++) {
    const int a = la % 3;
    const uint32_t s = mx_octant_size(la / 3);
    const uint64_t da = mx_morton_encode(a == 0 ? s : 0, a == 1 ? s : 0, a == 2 ? s : 0);
    const uint64_t dm = mx_morton_encode(a == 0 ? s / 2 : 0, a == 1 ? s / 2 : 0, a == 2 ? s / 2 : 0);
    /* a mid-node is the corner of a child of an octant of this level */
    const int mids = s > 1 && ((g->split_levels >> (la / 3)) & 1u);
    const size_t stop = end < g->first[la + 1] ? end : g->first[la + 1];
    if (row >= stop) continue; /* no edges of this (level, axis) */
    const uint64_t *k = g->keys[la] - g->first[la]; /* indexed by row */
    /* the lower ends ascend: each is searched from the one before */
    size_t near = mx_key_index_find(&g->H, k[row]);
    for (; row < stop; row++, rows += 3) {
      if (row + AHEAD < stop) {
        mx_key_index_prefetch(&g->H, mx_morton_add(k[row + AHEAD], da));
        if (mids) mx_key_index_prefetch(&g->H, mx_morton_add(k[row + AHEAD], dm));
      }
      const uint32_t im = mids ? mx_key_index_find(&g->H, mx_morton_add(k[row], dm)) : UINT32_MAX;
      rows[0] = mx_find_u64_near(g->vkey, g->nv, k[row], &near);
      rows[1] = mx_key_index_find(&g->H, mx_morton_add(k[row], da));
      rows[2] = im == UINT32_MAX ? 0 : im;
    }
  }
}

/* Rows [begin, end) of the octants section: the corners of each leaf, in
 * the published order, from the node index (those of the next leaf
 * prefetched). */
static void oct_rows(const void *gen, size_t begin, size_t end, uint32_t *rows) {
  const restart_gen *g = gen;
  const mx_octree *T = &g->m->B.tree.oct;
  const uint32_t *leaves = g->m->leaves;
  /* corner 0 is the leaf's anchor, and the anchors ascend: searched from
   * the one before; the other corners from the index */
  size_t near = begin < end ? mx_key_index_find(&g->H, T->key[leaves[begin]]) : 0;
  for (size_t i = begin; i < end; i++, rows += 8) {
    if (i + 1 < end) {
      const uint32_t q = leaves[i + 1];
      for (int c = 1; c < 8; c++)
        mx_key_index_prefetch(&g->H, mx_morton_add(T->key[q], g->pdelta[T->level[q]][c]));
    }
    const uint32_t o = leaves[i];
    rows[0] = mx_find_u64_near(g->vkey, g->nv, T->key[o], &near);
    for (int c = 1; c < 8; c++)
      rows[c] = mx_key_index_find(&g->H, mx_morton_add(T->key[o], g->pdelta[T->level[o]][c]));
  }
}

/* The restart data of a mesher: the nodes' coordinates, the octants'
 * levels, faces and element counts stored in r; the edge rows (text only:
 * binary files have no edges) and the octants' corners made by the
 * generators from g while the text file is written, or stored in r for the
 * binary file. */
static int restart_from_mesher(const mx_mesher *m, int text, mx_restart *r, restart_gen *g) {
  const mx_octree *T = &m->B.tree.oct;
  memset(r, 0, sizeof *r);
  memset(g, 0, sizeof *g);
  g->m = m;
  /* nodes: corners of every stored octant */
  size_t nv = 0;
  emit_tables_make(&g->E);
  for (int l = 0; l <= MX_MAX_LEVEL; l++)
    for (int c = 0; c < 8; c++)
      g->pdelta[l][c] = g->E.cdelta[l][corner_xyz[c][0] | corner_xyz[c][1] << 1 | corner_xyz[c][2] << 2];
  int st = restart_node_keys(T, &g->E, &g->vkey, &nv);
  if (st) return st;
  g->nv = nv;
  r->nv = nv;
  if (!text) { /* the text writer makes the coordinates as it goes */
    r->xyz = mx_alloc((3 * nv + 1) * sizeof *r->xyz);
    if (!r->xyz) st = MX_ENOMEM;
    if (!st) {
#pragma omp parallel for schedule(static)
      for (size_t b = 0; b < nv; b += GEN_ROWS)
        node_rows(g, b, nv - b < GEN_ROWS ? nv : b + GEN_ROWS, r->xyz + 3 * b);
    }
  }
  /* where each node key lies in the sorted keys, by hashing */
  if (!st) {
    int top = 0;
    for (size_t o = 0; o < T->n; o++)
      if (T->level[o] > top) top = T->level[o];
    st = mx_key_index_build(&g->H, g->vkey, nv, 3 * (MX_MAX_LEVEL - top));
  }
  const size_t no = m->nleaves;
  r->no = no;
  if (!st && text) {
    st = restart_edge_keys(m, &g->E, g);
    r->ne = g->first[NLA];
    r->node_rows = node_rows;
    r->edge_rows = edge_rows;
    r->oct_rows = oct_rows;
    r->gen = g;
  } else if (!st) {
    r->edge = mx_alloc(sizeof *r->edge); /* none: implied by the octants */
    r->oct_node = mx_alloc((8 * no + 1) * sizeof *r->oct_node);
    if (!r->edge || !r->oct_node) st = MX_ENOMEM;
    if (!st) {
      /* in blocks, as the text writer calls it: a leaf's anchor is searched
       * from the one before within a block */
#pragma omp parallel for schedule(static)
      for (size_t b = 0; b < no; b += GEN_ROWS)
        oct_rows(g, b, no - b < GEN_ROWS ? no : b + GEN_ROWS, r->oct_node + 8 * b);
    }
  }
  /* octants: the leaves, in Morton order */
  if (!st) {
    r->oct_level = mx_alloc(no + 1);
    r->oct_tri_off = mx_alloc((no + 1) * sizeof *r->oct_tri_off);
    if (!r->oct_level || !r->oct_tri_off) st = MX_ENOMEM;
  }
  if (!st) {
#pragma omp parallel for schedule(static)
    for (size_t i = 0; i < no; i++) {
      const uint32_t o = m->leaves[i];
      r->oct_level[i] = T->level[o];
      uint64_t k = 0;
      for (uint32_t j = 0; j < T->tri_cnt[o]; j++)
        k += T->tri_pool[T->tri_off[o] + j] < m->nt_domain;
      r->oct_tri_off[i] = k;
    }
    uint64_t total = 0;
    for (size_t i = 0; i < no; i++) {
      const uint64_t k = r->oct_tri_off[i];
      r->oct_tri_off[i] = total;
      total += k;
    }
    r->oct_tri_off[no] = total;
    r->oct_tri = mx_alloc((total + 1) * sizeof *r->oct_tri);
    if (!r->oct_tri) st = MX_ENOMEM;
  }
  if (!st) {
#pragma omp parallel for schedule(static)
    for (size_t i = 0; i < no; i++) {
      const uint32_t o = m->leaves[i];
      uint64_t w = r->oct_tri_off[i];
      for (uint32_t j = 0; j < T->tri_cnt[o]; j++) {
        const uint32_t t = T->tri_pool[T->tri_off[o] + j];
        if (t < m->nt_domain) r->oct_tri[w++] = t;
      }
    }
    r->has_transform = 1; /* zeros: no transform */
    r->materials = m->p.materials; /* re-meshing from the file keeps them */
  }
  if (!st && m->mesh_stage >= MX_STAGE_TRANSITION) {
    r->nsub = mx_calloc((no + 1) * sizeof *r->nsub);
    if (!r->nsub) st = MX_ENOMEM;
    for (size_t c = 0; !st && c < m->M.ncells; c++) r->nsub[m->M.leaf[c]]++;
    r->by_type = 1; /* our meshes are written grouped by type (io/cell_order.c) */
  }
  return st;
}

static int ends_with(const char *s, const char *suffix) {
  const size_t n = strlen(s), k = strlen(suffix);
  return n >= k && strcmp(s + n - k, suffix) == 0;
}

int mx_mesher_save_restart(const mx_mesher *m, const char *path) {
  mx_call c;
  mx_call_begin(m, &c);
  /* the restart writer's arrays in place of the writers' (the program
   * writes the restart file last: its peak stays what it was) */
  mx_written_release(m);
  const double t = mx_wtime();
  int st = path ? mx_mesher_spares_inputs(m, path, 1) : MX_OK;
  if (!st) st = mx_materials_allowed(m, "a restart file");
  if (!st && (!m->have_tree || m->mesh_stage < MX_STAGE_TRANSITION)) {
    mx_error(path, 0, "no mesh to write a restart file for: mesh first");
    st = MX_EINPUT;
  }
  const int binary = path && ends_with(path, ".octb");
  mx_restart r;
  restart_gen g;
  memset(&r, 0, sizeof r);
  memset(&g, 0, sizeof g);
  if (!st) st = restart_from_mesher(m, !binary, &r, &g);
  /* the binary variant carries the mesh too: a re-mesh from it is local */
  if (!st && binary && m->mesh_stage == MX_STAGE_FULL && m->M.nkey && m->states &&
      !m->have_mix) { /* --tets: the octree alone (the element counts per leaf
                       * are the tetrahedra's; reading meshes it again) */
    r.has_mesh = 1;
    r.mesh_nn = m->M.nnodes;
    r.mesh_nc = m->M.ncells;
    r.mesh_xyz = m->M.xyz;
    r.mesh_nkey = m->M.nkey;
    /* the file's states are 0 or 1 (MX_NODE_ON written as inside) */
    r.mesh_state = mx_alloc(m->M.nnodes + 1);
    if (!r.mesh_state) {
      st = MX_ENOMEM;
    } else {
#pragma omp parallel for schedule(static)
      for (size_t v = 0; v < m->M.nnodes; v++) r.mesh_state[v] = m->states[v] & 1;
    }
    r.mesh_type = m->M.type;
    r.mesh_conn = m->M.conn;
    r.mesh_leaf = m->M.leaf;
    /* the file keeps J_ENS in double (the mesh holds float) */
    r.mesh_jens = mx_alloc((m->M.ncells + 1) * sizeof *r.mesh_jens);
    if (!r.mesh_jens) st = MX_ENOMEM;
    else {
#pragma omp parallel for schedule(static)
      for (size_t c = 0; c < m->M.ncells; c++) r.mesh_jens[c] = m->M.jens[c];
    }
  }
  if (!st) st = binary ? mx_restart_write_binary(path, &r) : mx_restart_write_text(path, &r);
  r.mesh_xyz = NULL; /* the mesher's */
  r.mesh_nkey = NULL;
  r.mesh_type = NULL; /* (mesh_state: the copy, freed with r) */
  r.mesh_conn = r.mesh_leaf = NULL;
  mx_restart_free(&r);
  restart_gen_free(&g);
  m->rec->S.t_restart += mx_wtime() - t;
  return mx_call_end(m, &c, st);
}

/* ---- reading ----------------------------------------------------------- */

/* Key and level of octant i of the file on grid g; MX_EINPUT when its
 * corners are not a cube of the grid. */
static int octant_key(const mx_restart *r, size_t i, const mx_grid *g, const char *path,
                      uint64_t *key);

/* The keys of all the file's octants, in parallel; the first octant off the
 * grid, if any, is reported. */
static int octant_keys(const mx_restart *r, const mx_grid *g, const char *path, uint64_t *key) {
  size_t bad = SIZE_MAX;
#pragma omp parallel for schedule(static) reduction(min : bad)
  for (size_t i = 0; i < r->no; i++)
    if (octant_key(r, i, g, NULL, &key[i]) != MX_OK && i < bad) bad = i;
  if (bad == SIZE_MAX) return MX_OK;
  return octant_key(r, bad, g, path, &key[bad]);
}

/* path NULL: no message. */
static int octant_key(const mx_restart *r, size_t i, const mx_grid *g, const char *path,
                      uint64_t *key) {
  const int l = r->oct_level[i];
  double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
  for (int c = 0; c < 8; c++) {
    const double *p = r->xyz + 3 * (size_t)r->oct_node[8 * i + c];
    for (int a = 0; a < 3; a++) {
      lo[a] = mx_min(lo[a], p[a]);
      hi[a] = mx_max(hi[a], p[a]);
    }
  }
  const uint32_t s = mx_octant_size(l);
  uint32_t q[3];
  for (int a = 0; a < 3; a++) {
    const double u = (lo[a] - g->origin[a]) / g->unit;
    const double e = (hi[a] - lo[a]) / g->unit;
    const double lim = (double)g->dims[a] * (double)mx_octant_size(0);
    if (!(u > -0.25 && u + e < lim + 0.25) || fabs(e - (double)s) > 0.01 * s + 0.25) {
      if (path)
        mx_error(path, 0, "octant %zu (level %d) does not lie on the root grid of the "
                        "input surfaces: is it the surface the file was written for?",
               i + 1, l);
      return MX_EINPUT;
    }
    const double rq = floor(u + 0.5);
    if (fabs(u - rq) > 0.25 || ((uint32_t)rq & (s - 1)) != 0) {
      if (path)
        mx_error(path, 0, "octant %zu (level %d) is not aligned on the octree of the "
                        "input surfaces: is it the surface the file was written for?",
               i + 1, l);
      return MX_EINPUT;
    }
    q[a] = (uint32_t)rq;
  }
  *key = mx_morton_encode(q[0], q[1], q[2]);
  return MX_OK;
}

/* Index of the leaf holding the lattice point p (its Morton key), or
 * UINT32_MAX (outside the domain's leaves). keys: the leaves' sorted keys. */
static uint32_t leaf_holding(const mx_mesher *m, const uint64_t *keys, uint64_t pk) {
  size_t lo = 0, hi = m->nleaves;
  while (lo < hi) {
    const size_t mid = lo + (hi - lo) / 2;
    if (keys[mid] <= pk) lo = mid + 1; else hi = mid;
  }
  if (lo == 0) return UINT32_MAX;
  const uint32_t o = m->leaves[lo - 1];
  uint32_t a[3], p[3];
  mx_morton_decode(m->B.tree.oct.key[o], a);
  mx_morton_decode(pk, p);
  const uint32_t s = mx_octant_size(m->B.tree.oct.level[o]);
  for (int d = 0; d < 3; d++)
    if (p[d] < a[d] || p[d] >= a[d] + s) return UINT32_MAX;
  return (uint32_t)(lo - 1);
}

/* The mesh section of a binary restart file becomes the current mesh when
 * the rebuilt leaves are the file's octants in the same order (always, for
 * a file this mixoct wrote for the same surface). */
static int adopt_mesh(mx_mesher *m, mx_restart *r, const uint64_t *key) {
  if (r->no != m->nleaves) return MX_OK;
  size_t differ = 0;
#pragma omp parallel for schedule(static) reduction(+ : differ)
  for (size_t i = 0; i < r->no; i++)
    differ += m->B.tree.oct.key[m->leaves[i]] != key[i] ||
              m->B.tree.oct.level[m->leaves[i]] != r->oct_level[i];
  if (differ) return MX_OK; /* meshed again from the octree when refined */
  mx_mesh *M = &m->M;
  memset(M, 0, sizeof *M);
  M->level = mx_alloc((r->mesh_nc + 1) * sizeof *M->level);
  M->jens = mx_alloc((r->mesh_nc + 1) * sizeof *M->jens);
  if (!M->level || !M->jens) {
    mx_free(M->level);
    mx_free(M->jens);
    M->level = NULL;
    M->jens = NULL;
    return MX_ENOMEM;
  }
#pragma omp parallel for schedule(static)
  for (size_t c = 0; c < r->mesh_nc; c++) M->jens[c] = (float)r->mesh_jens[c];
  M->nnodes = r->mesh_nn;
  M->ncells = r->mesh_nc;
  M->xyz = r->mesh_xyz;
  M->nkey = r->mesh_nkey;
  M->type = r->mesh_type;
  M->conn = r->mesh_conn;
  M->leaf = r->mesh_leaf;
  m->states = r->mesh_state;
  r->mesh_xyz = NULL; /* the mesher's now */
  r->mesh_nkey = NULL;
  r->mesh_state = r->mesh_type = NULL;
  r->mesh_conn = r->mesh_leaf = NULL;
#pragma omp parallel for schedule(static)
  for (size_t c = 0; c < M->ncells; c++) M->level[c] = r->oct_level[M->leaf[c]];
  mx_mesh_summarize(M);
  m->mesh_stage = MX_STAGE_FULL;
  m->rec->S.full = 1;
  /* a full-stage mesh that did not come through the pipeline: its surface
   * index (the boundary tags and the next re-mesh read it) */
  MX_CHECK(mx_mesher_index(m));
  return mx_mesh_finish(m) == MX_EINVALID ? MX_EINPUT : MX_OK;
}

int mx_mesher_set_split_keys(mx_mesher *m, const uint64_t *key, const uint8_t *level, size_t n) {
  for (int l = 0; l <= MX_MAX_LEVEL; l++) {
    mx_free(m->split_keys[l]);
    m->split_keys[l] = NULL;
    m->nsplit[l] = 0;
  }
  uint64_t *skey = mx_alloc((n + 1) * sizeof *skey);
  uint32_t *perm = mx_alloc((n + 1) * sizeof *perm);
  int st = skey && perm ? MX_OK : MX_ENOMEM;
  if (!st) {
    memcpy(skey, key, n * sizeof *skey);
#pragma omp parallel for schedule(static)
    for (size_t i = 0; i < n; i++) perm[i] = (uint32_t)i;
    st = mx_sort_u64(skey, perm, n);
  }
  /* level by level; in Morton order of the leaves, each level's ancestors
   * come sorted */
  for (int l = 0; !st && l < MX_MAX_LEVEL; l++) {
    const uint64_t mask = ~(uint64_t)0 << (3 * (MX_MAX_LEVEL - l));
    size_t k = 0;
    uint64_t *v = NULL;
    for (size_t i = 0; i < n; i++) {
      if (level[perm[i]] <= l) continue;
      const uint64_t a = skey[i] & mask;
      if (k && v[k - 1] == a) continue;
      if (!v) {
        v = mx_alloc((n + 1) * sizeof *v);
        if (!v) {
          st = MX_ENOMEM;
          break;
        }
      }
      v[k++] = a;
    }
    m->split_keys[l] = v;
    m->nsplit[l] = k;
  }
  mx_free(skey);
  mx_free(perm);
  return st;
}

/* The leaves of the rebuilt octree that no octant of the file overlaps
 * (neither it, nor an ancestor, nor a descendant): the run that wrote the
 * file had split each of them and dropped every child (an octant meeting
 * the input only where a triangle lies in its face's plane, outside the
 * domain: the children's boxes, a rounding apart, miss the triangle), so
 * its leaves leave that region empty. Its own refinement reached them only
 * through its level requests, which a re-mesh need not repeat: without
 * them the rebuilt octree kept them as leaves, a mesh other than the
 * file's (the L of tests/restart_lattice_test.sh at -s 5, re-meshed
 * without -s: 11,040 leaves against 10,800, its element list refused).
 * They are split too, round after round (a child kept is split in its
 * turn, as that run did), until the leaves are the file's. Only for files
 * mixoct wrote (r->by_type): the published program's leaves cover the
 * domain by their own rules. */
static int split_orphans(mx_mesher *m, const mx_restart *r, const uint64_t *key) {
  const size_t n = r->no;
  uint64_t *lo = mx_alloc((n + 1) * sizeof *lo);
  uint32_t *perm = mx_alloc((n + 1) * sizeof *perm);
  uint64_t *xkey = NULL;
  uint8_t *xlev = NULL;
  size_t nx = 0, cap = 0;
  int st = lo && perm ? MX_OK : MX_ENOMEM;
  if (!st) {
    memcpy(lo, key, n * sizeof *lo);
    for (size_t i = 0; i < n; i++) perm[i] = (uint32_t)i;
    st = mx_sort_u64(lo, perm, n);
  }
  for (int round = 0; !st && round < MX_MAX_LEVEL; round++) {
    /* the rebuilt leaves no file octant overlaps, as a child key each */
    const size_t nx0 = nx;
    for (size_t i = 0; !st && i < m->nleaves; i++) {
      const uint32_t o = m->leaves[i];
      const int l = m->B.tree.oct.level[o];
      const uint64_t k = m->B.tree.oct.key[o], s = mx_octant_size(l);
      const uint64_t end = k + s * s * s; /* the Morton keys of its lattice cells */
      size_t a = 0, b = n; /* the first file octant starting at or after end */
      while (a < b) {
        const size_t c = a + (b - a) / 2;
        if (lo[c] < end) a = c + 1;
        else b = c;
      }
      if (a > 0) {
        const uint64_t fs = mx_octant_size(r->oct_level[perm[a - 1]]);
        if (lo[a - 1] + fs * fs * fs > k) continue; /* overlaps */
      }
      if (l + 1 >= MX_MAX_LEVEL) continue; /* (cannot be split) */
      if (nx == cap) {
        cap = cap ? 2 * cap : 64;
        uint64_t *k2 = mx_realloc(xkey, cap * sizeof *k2);
        if (k2) xkey = k2;
        uint8_t *l2 = k2 ? mx_realloc(xlev, cap) : NULL;
        if (l2) xlev = l2;
        if (!k2 || !l2) {
          st = MX_ENOMEM;
          break;
        }
      }
      xkey[nx] = k; /* its first child: the octant is its ancestor, split */
      xlev[nx++] = (uint8_t)(l + 1);
    }
    if (st || nx == nx0) break;
    /* the split set of the file's octants and these, then the octree again */
    uint64_t *ak = mx_alloc((n + nx + 1) * sizeof *ak);
    uint8_t *al = mx_alloc(n + nx + 1);
    if (!ak || !al) st = MX_ENOMEM;
    if (!st) {
      memcpy(ak, key, n * sizeof *ak);
      memcpy(ak + n, xkey, nx * sizeof *ak);
      memcpy(al, r->oct_level, n);
      memcpy(al + n, xlev, nx);
      mx_tree_clear(m);
      st = mx_mesher_set_split_keys(m, ak, al, n + nx);
    }
    mx_free(ak);
    mx_free(al);
    if (!st) st = mx_build_tree(m);
  }
  mx_free(lo);
  mx_free(perm);
  mx_free(xkey);
  mx_free(xlev);
  return st;
}

static int load_restart(mx_mesher *m, const char *path) {
  mx_restart r;
  memset(&r, 0, sizeof r);
  MX_CHECK(mx_restart_read(path, &r));
  int st = MX_OK;
  if (r.materials && !m->p.materials) {
    /* the file's mesh had several materials: so has its re-mesh, when the
     * inputs have not been assembled as one material yet */
    if (m->assembled) {
      mx_error(path, 0, "written with several materials: set materials before the inputs "
                        "are used (mixoct: --materials)");
      st = MX_EINPUT;
    } else {
      m->p.materials = 1;
      st = mx_materials_allowed(m, "a restart file");
    }
  }
  /* the grid of the input surfaces */
  mx_tree_clear(m);
  for (int l = 0; l <= MX_MAX_LEVEL; l++) {
    mx_free(m->split_keys[l]);
    m->split_keys[l] = NULL;
    m->nsplit[l] = 0;
  }
  mx_grid g;
  {
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    if (m->ndomain == 0) {
      mx_error(path, 0, "add the input surface the restart file was written for (-i FILE)");
      st = MX_EINPUT;
    }
    for (size_t t = 0; !st && t < m->domain.nt; t++)
      for (int k = 0; k < 3; k++) {
        const uint32_t v = m->domain.tri[3 * t + k];
        const double p[3] = {m->domain.x[v], m->domain.y[v], m->domain.z[v]};
        for (int a = 0; a < 3; a++) {
          lo[a] = mx_min(lo[a], p[a]);
          hi[a] = mx_max(hi[a], p[a]);
        }
      }
    if (!st) st = mx_grid_build(lo, hi, m->domain_name[0], &g);
  }
  uint64_t *key = NULL;
  if (!st) {
    key = mx_alloc((r.no + 1) * sizeof *key);
    if (!key) st = MX_ENOMEM;
  }
  if (!st) st = octant_keys(&r, &g, path, key);
  if (!st) st = mx_mesher_set_split_keys(m, key, r.oct_level, r.no);
  if (!st) st = mx_build_tree(m);
  if (!st && r.by_type) st = split_orphans(m, &r, key);
  /* the file's elements -> our leaves */
  uint64_t *lkeys = NULL;
  if (!st && r.nsub) {
    lkeys = mx_alloc((m->nleaves + 1) * sizeof *lkeys);
    uint64_t total = 0;
    for (size_t i = 0; i < r.no; i++) total += r.nsub[i];
    m->file_leaf = mx_alloc((total + 1) * sizeof *m->file_leaf);
    if (!lkeys || !m->file_leaf) st = MX_ENOMEM;
    m->file_nelem = st ? 0 : (size_t)total;
  }
  if (!st && r.nsub) {
    for (size_t i = 0; i < m->nleaves; i++) lkeys[i] = m->B.tree.oct.key[m->leaves[i]];
    size_t lost = 0;
    uint64_t *first = mx_alloc((r.no + 1) * sizeof *first);
    if (!first) st = MX_ENOMEM;
    if (!st) {
#pragma omp parallel for schedule(static)
      for (size_t i = 0; i < r.no; i++) first[i] = r.nsub[i];
      mx_scan_u64(first, r.no);
#pragma omp parallel for schedule(static) reduction(+ : lost)
      for (size_t i = 0; i < r.no; i++) {
        uint32_t p[3];
        mx_morton_decode(key[i], p);
        const uint32_t h = mx_octant_size(r.oct_level[i]) / 2;
        const uint32_t lf =
            leaf_holding(m, lkeys, mx_morton_encode(p[0] + h, p[1] + h, p[2] + h));
        lost += lf == UINT32_MAX && r.nsub[i];
        for (uint32_t k = 0; k < r.nsub[i]; k++) m->file_leaf[first[i] + k] = lf;
      }
    }
    mx_free(first);
    if (lost)
      mx_warning(path, 0, "%zu octant(s) with elements lie outside the domain as this "
                          "mixoct sees it; their elements cannot be refined", lost);
  }
  mx_free(lkeys);
  m->file_by_type = r.by_type;
  if (!st && r.has_mesh) st = adopt_mesh(m, &r, key);
  mx_free(key);
  mx_restart_free(&r);
  return st;
}

int mx_mesher_load_restart(mx_mesher *m, const char *path) {
  mx_call c;
  mx_call_begin(m, &c);
  mx_written_forget(m); /* the mesh changes */
  const double t = mx_wtime();
  const double read = m->rec->S.ph.read;
  memset(&m->rec->S, 0, sizeof m->rec->S);
  m->rec->S.ph.read = read;
  int st = mx_materials_allowed(m, "a restart file");
  if (!st) st = load_restart(m, path);
  if (st) mx_tree_clear(m);
  else mx_mesher_note_read(m, path, 1);
  m->rec->S.t_restart = mx_wtime() - t;
  return mx_call_end(m, &c, st);
}

int mx_read_element_list(const char *path, uint64_t limit, uint64_t **out, size_t *n) {
  *out = NULL;
  *n = 0;
  return mx_read_index_list(path, limit, out, n);
}
