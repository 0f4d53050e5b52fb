/* The octree's invariants in a debug variant (soa/tree_valid.h): this
 * program is linked with the files that refine the octree compiled with
 * MX_INVARIANTS=1 (tests/meson.build), so every refinement below checks the
 * forest, the Morton order, the 2:1 balance and the edge infos as it ends.
 * Runs: the demo at -s 5; the cortex at -s 6 with its .reg boxes, with
 * both balances (edge infos, and the recursive baseline), the edge infos
 * released between meshings; a restart file written, read back (the
 * rebuild) and re-meshed with an element list; the published c5.oct
 * re-meshed with its list. Then octrees broken by hand, where the checker
 * must fail: a key, a parent's kept mask, a leaf two levels coarser than a
 * neighbour, an edge slot, an edge table's count, the leaf list's order. */
#include "check.h"
#include "base/common.h"
#include "mesher/mesher.h"
#include "mesher/mesher_impl.h"
#include "mixoct.h"
#include "soa/tree_valid.h"

#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#if !MX_INVARIANTS
#error "test_invariants must be built with MX_INVARIANTS=1"
#endif

static char data_dir[512];

static int find_data(void) {
  const char *d = test_data_dir("surfaces/cortex.off");
  if (d) snprintf(data_dir, sizeof data_dir, "%s", d);
  return d != NULL;
}

static const char *data(const char *rel) {
  static char buf[4][700];
  static int k = 0;
  k = (k + 1) % 4;
  snprintf(buf[k], sizeof buf[k], "%s/%s", data_dir, rel);
  return buf[k];
}

/* The checks of the octree as it is now, every promise made. */
static int tree_ok(const mx_mesher *m) {
  return mx_tree_valid(&m->B.tree, MX_TREE_BALANCED, "the test") == MX_OK &&
         mx_leaves_valid(&m->B.tree, m->leaves, m->nleaves, "the test") == MX_OK;
}

static mx_mesher *new_mesher(int s, int stage, int balance) {
  mx_params p;
  mx_params_default(&p);
  p.surface_level = s;
  p.stage = stage;
  p.balance = balance;
  return mx_mesher_new(&p);
}

/* 1. The demo at -s 5, the full mesh (repair rounds refine by list). */
static void test_demo(void) {
  const size_t before = mx_tree_valid_runs();
  mx_mesher *m = new_mesher(5, MX_STAGE_FULL, MX_BALANCE_EDGES);
  CHECK(m && mx_mesher_add_demo_surface(m) == MX_OK);
  CHECK(mx_mesher_mesh(m) == MX_OK);
  CHECK(tree_ok(m));
  CHECK(mx_tree_valid_runs() > before);
  printf("demo -s 5: %zu leaves, %zu checks\n", m->nleaves, mx_tree_valid_runs() - before);
  mx_mesher_free(m);
}

/* 2. The cortex at -s 6 with its boxes, both balances: the same leaves
 * (their hash returned). Its full mesh keeps contacts after the repair
 * rounds (MX_EINVALID, exit 5 in the program): the rounds refine by list
 * all the same, which is what is checked here. */
static int ok_or_invalid(int st) { return st == MX_OK || st == MX_EINVALID; }

static uint64_t cortex_reg(int balance, int release) {
  const size_t before = mx_tree_valid_runs();
  mx_mesher *m = new_mesher(6, MX_STAGE_FULL, balance);
  CHECK(m && mx_mesher_add_surface(m, data("surfaces/cortex.off")) == MX_OK);
  CHECK(mx_mesher_read_boxes(m, data("surfaces/cortex.reg")) == MX_OK);
  m->release_edges = release;
  CHECK(mx_mesher_build_octree(m) == MX_OK);
  CHECK(tree_ok(m));
  const uint64_t h = mx_leaves_hash(&m->B.tree, m->leaves, m->nleaves);
  const size_t n0 = m->nleaves;
  CHECK(ok_or_invalid(mx_mesher_mesh(m)));
  CHECK(tree_ok(m));
  /* a re-meshing refinement of 200 leaves, edge infos restored when they
   * were released */
  uint64_t list[200];
  const size_t n = m->nleaves < 200 ? m->nleaves : 200;
  for (size_t i = 0; i < n; i++) list[i] = i * (m->nleaves / n);
  CHECK(ok_or_invalid(mx_mesher_refine_leaves(m, list, n)));
  CHECK(tree_ok(m));
  printf("cortex -s 6 + cortex.reg, %s balance%s: %zu leaves, %zu after the repair and "
         "re-mesh, %zu checks\n", balance == MX_BALANCE_EDGES ? "edge-info" : "recursive",
         release ? ", edge infos released" : "", n0, m->nleaves,
         mx_tree_valid_runs() - before);
  mx_mesher_free(m);
  return h;
}

/* 3. A restart file written, read back (the octree rebuilt from its split
 * set) and re-meshed with an element list. */
static void test_restart(void) {
  const char *path = "invariants_c5.octb";
  mx_mesher *m = new_mesher(5, MX_STAGE_FULL, MX_BALANCE_EDGES);
  CHECK(m && mx_mesher_add_surface(m, data("surfaces/cortex.off")) == MX_OK);
  CHECK(mx_mesher_mesh(m) == MX_OK);
  CHECK(mx_mesher_save_restart(m, path) == MX_OK);
  const uint64_t h0 = mx_leaves_hash(&m->B.tree, m->leaves, m->nleaves);
  mx_mesher_free(m);
  const size_t before = mx_tree_valid_runs();
  m = new_mesher(5, MX_STAGE_FULL, MX_BALANCE_EDGES);
  CHECK(m && mx_mesher_add_surface(m, data("surfaces/cortex.off")) == MX_OK);
  CHECK(mx_mesher_load_restart(m, path) == MX_OK);
  CHECK(mx_leaves_hash(&m->B.tree, m->leaves, m->nleaves) == h0);
  CHECK(tree_ok(m));
  const size_t ne = mx_mesher_restart_elements(m);
  uint64_t list[64];
  size_t n = 0;
  for (size_t e = 0; e < ne && n < 64; e += ne / 64 + 1) list[n++] = e;
  CHECK(mx_mesher_refine_elements(m, list, n) == MX_OK);
  CHECK(tree_ok(m));
  printf("restart rebuild + %zu listed elements: %zu leaves, %zu checks\n", n, m->nleaves,
         mx_tree_valid_runs() - before);
  mx_mesher_free(m);
  unlink(path);
}

/* 4. The published program's c5.oct with its list.txt. */
static void test_published(void) {
  const size_t before = mx_tree_valid_runs();
  mx_mesher *m = new_mesher(-1, MX_STAGE_FULL, MX_BALANCE_EDGES);
  CHECK(m && mx_mesher_add_surface(m, data("surfaces/cortex.off")) == MX_OK);
  CHECK(mx_mesher_load_restart(m, data("remesh/c5.oct")) == MX_OK);
  CHECK(tree_ok(m));
  uint64_t *list = NULL;
  size_t n = 0;
  CHECK(mx_read_element_list(data("remesh/list.txt"), m->file_nelem, &list, &n) == MX_OK);
  CHECK(mx_mesher_refine_elements(m, list, n) == MX_OK);
  CHECK(tree_ok(m));
  printf("c5.oct + list.txt: %zu leaves, %zu checks\n", m->nleaves,
         mx_tree_valid_runs() - before);
  mx_free_array(list);
  mx_mesher_free(m);
}

/* 5. Broken octrees: each must fail with MX_EINTERNAL, and be whole again
 * once repaired. */
static int tree_status(const mx_mesher *m) {
  return mx_tree_valid(&m->B.tree, MX_TREE_BALANCED, "breaking it on purpose");
}

static uint32_t some_leaf(const mx_mesher *m, int min_level) {
  const mx_octree *T = &m->B.tree.oct;
  for (size_t i = 0; i < m->nleaves; i++) {
    const uint32_t o = m->leaves[m->nleaves / 2 + i < m->nleaves ? m->nleaves / 2 + i : i];
    if (T->level[o] >= min_level && T->parent[o] != MX_NONE) return o;
  }
  return MX_NONE;
}

static void test_broken(void) {
  mx_mesher *m = new_mesher(5, MX_STAGE_OCTREE, MX_BALANCE_EDGES);
  CHECK(m && mx_mesher_add_demo_surface(m) == MX_OK);
  CHECK(mx_mesher_mesh(m) == MX_OK);
  mx_builder *B = &m->B;
  mx_tree *tr = &B->tree;
  mx_octree *T = &tr->oct;
  CHECK(tree_status(m) == MX_OK);
  printf("-- broken on purpose (one message each expected):\n");
  fflush(stdout);

  /* (a) a leaf's key moved by one cell of its level */
  const uint32_t o = some_leaf(m, 3);
  CHECK(o != MX_NONE);
  const uint64_t key = T->key[o];
  T->key[o] = mx_morton_neighbor(key, T->level[o], 1, 0, 0, tr->grid.dims);
  CHECK(tree_status(m) == MX_EINTERNAL);
  T->key[o] ^= 1; /* off its level's lattice as well */
  CHECK(tree_status(m) == MX_EINTERNAL);
  T->key[o] = key;
  /* (a) a kept child dropped from its parent's mask */
  const uint32_t p = T->parent[o];
  const uint8_t kept = T->kept[p];
  T->kept[p] = (uint8_t)(kept & ~(1u << mx_morton_child_id(key, T->level[o])));
  CHECK(tree_status(m) == MX_EINTERNAL);
  T->kept[p] = kept;
  CHECK(tree_status(m) == MX_OK);

  /* (d) an edge slot emptied, then given another octant */
  mx_edge_table *E = NULL;
  size_t ei = SIZE_MAX;
  for (int l = tr->edge_levels; l >= 0 && ei == SIZE_MAX; l--) {
    E = &tr->edges.t[l][0];
    for (size_t i = 0; i < E->cap && ei == SIZE_MAX; i++)
      if (E->e[i].kw && E->e[i].slot[0] != MX_NONE && E->e[i].slot[1] != MX_NONE) ei = i;
  }
  CHECK(ei != SIZE_MAX);
  if (ei != SIZE_MAX) {
    const uint32_t s0 = E->e[ei].slot[0];
    E->e[ei].slot[0] = MX_NONE;
    CHECK(tree_status(m) == MX_EINTERNAL);
    E->e[ei].slot[0] = E->e[ei].slot[1];
    CHECK(tree_status(m) == MX_EINTERNAL);
    E->e[ei].slot[0] = s0;
    E->count++;
    CHECK(tree_status(m) == MX_EINTERNAL);
    E->count--;
    CHECK(tree_status(m) == MX_OK);
  }

  /* (b) the pipeline's leaf list out of order, then one leaf short */
  if (m->nleaves > 2) {
    uint32_t t = m->leaves[1];
    m->leaves[1] = m->leaves[2];
    m->leaves[2] = t;
    CHECK(mx_leaves_valid(tr, m->leaves, m->nleaves, "the test") == MX_EINTERNAL);
    m->leaves[2] = m->leaves[1];
    m->leaves[1] = t;
    CHECK(mx_leaves_valid(tr, m->leaves, m->nleaves - 1, "the test") == MX_EINTERNAL);
    CHECK(mx_leaves_valid(tr, m->leaves, m->nleaves, "the test") == MX_OK);
  }

  /* (c) two face-neighbour leaves z, w of one level, w inside the domain
   * (all its children kept): w split, then its child next to z split, by
   * hand and with no balance; the grandchildren are two levels finer than
   * z */
  uint32_t z = MX_NONE, w = MX_NONE;
  for (size_t i = 0; i < m->nleaves && w == MX_NONE; i++) {
    z = m->leaves[i];
    const int l = T->level[z];
    if (l < 2 || l > 4) continue;
    const uint64_t wk = mx_morton_neighbor(T->key[z], l, 1, 0, 0, tr->grid.dims);
    if (wk == UINT64_MAX) continue;
    size_t lo = 0, hi = m->nleaves;
    while (lo < hi) {
      const size_t mid = (lo + hi) / 2;
      if (T->key[m->leaves[mid]] < wk) lo = mid + 1;
      else hi = mid;
    }
    if (lo < m->nleaves && T->key[m->leaves[lo]] == wk && T->level[m->leaves[lo]] == l &&
        !(T->flags[m->leaves[lo]] & MX_OCT_SURFACE))
      w = m->leaves[lo];
  }
  CHECK(w != MX_NONE);
  if (w != MX_NONE) {
    CHECK(mx_split_octants(B, &w, 1, 0) == MX_OK);
    CHECK(T->kept[w] == 0xff);
    CHECK(tree_status(m) == MX_OK); /* one level finer: still balanced */
    uint32_t y = T->child0[w]; /* child 0: on z's side (-x) */
    CHECK(mx_split_octants(B, &y, 1, 0) == MX_OK);
    CHECK(tree_status(m) == MX_EINTERNAL);
    CHECK(mx_tree_valid(tr, 0, "the test (no balance promised)") == MX_OK);
  }
  printf("-- end of the broken octrees\n");
  mx_mesher_free(m);
}

int main(void) {
  omp_set_num_threads(2);
  test_demo();
  if (!find_data()) {
    TEST_DATA_MISSING("../shared/data/surfaces/cortex.off not found: the cortex runs");
  } else {
    const uint64_t a = cortex_reg(MX_BALANCE_EDGES, 0);
    const uint64_t b = cortex_reg(MX_BALANCE_EDGES, 1);
    const uint64_t c = cortex_reg(MX_BALANCE_RECURSIVE, 0);
    CHECK(a == b && a == c);
    test_restart();
    test_published();
  }
  test_broken();
  printf("%zu invariant checks ran\n", mx_tree_valid_runs());
  return TEST_DONE();
}
