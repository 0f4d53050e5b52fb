/* 2D re-meshing (issue 13 item 6): the library's 2D mesher, its restart
 * file (Appendix A, quadtree form) and list refinement (Algorithm 3), on the
 * box with a hole (data/polylines/box.poly: [0,3]^2 minus [1,2]^2).
 *
 * Counts by reasoning: the root square is 1.01 x 3 = 3.03 wide, centred on
 * the box, so it starts at -0.015; at -s 3 its leaves are 3.03 / 8 = 0.379
 * wide and every level-3 quadrant meets the polylines or lies inside, but
 * the 4 in the hole: 64 - 4 = 60 leaves, all level 3, so no transition:
 * 60 quads; 9 x 9 lattice corners less the 1 corner only hole quadrants
 * share: 80 nodes. Splitting the bottom-left leaf [-0.015, 0.364]^2 gives 4
 * children that all meet the domain (it starts at 0) and level-3 neighbours
 * are balanced with level-4 children: 63 leaves, no balance split.
 *
 * Fig. 18 of the 2021 paper: the element at the corner (0, 0) refined 20
 * times stays local, balanced and valid. Locality bound: a quadrant of level
 * l is split either because it is listed (its leaf holds a cell with a node
 * at p = (0,0), so it lies within sqrt 2 s_l of p) or for balance, because
 * an edge neighbour of level l+1 is split; that neighbour's diameter is
 * s_l / sqrt 2, so the farthest split quadrant of level l is within
 * D(l) <= max(sqrt 2 s_l, D(l+1) + s_l / sqrt 2) <= 2 sqrt 2 s_l of p. The
 * -s 3 tree splits nothing at level 3 or finer, so every leaf of level
 * L >= 4 (a child of a split level L-1 quadrant) lies within 3 s_{L-1} of p.
 * Balance is checked by mx_qtree_unbalanced (a sort of the leaves' edges,
 * independent of the edge infos), validity by the mesher's independent
 * check (every call returns MX_EINVALID when it fails).
 *
 * The restart data (mx_qrestart_from_mesher, which avoids sorting every
 * corner and side) against its definition computed the plain way: every
 * leaf corner sorted and made unique; each leaf's corners found there;
 * every leaf side once by its ends' numbers, ascending, with the node at
 * its midpoint or 0; on trees with out-of-domain leaves, deep grading and
 * a refined corner, for 1 and 2 threads. */
#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "check.h"
#include "base/common.h"
#include "io/restart.h"
#include "mesher/mesher2d.h"
#include "mixoct.h"

static char data[512];

static const char *poly(const char *name) {
  static char buf[4][600];
  static int k;
  k = (k + 1) & 3;
  snprintf(buf[k], sizeof buf[k], "%s/polylines/%s", data, name);
  return buf[k];
}

static void quiet(void *user, int level, const char *text) {
  (void)user, (void)level, (void)text;
}

static mx_mesher2d *box_mesher(int s) {
  mx_params2d p;
  mx_params2d_default(&p);
  p.surface_level = s;
  mx_mesher2d *m = mx_mesher2d_new(&p);
  CHECK(m && mx_mesher2d_set_domain(m, poly("box.poly")) == MX_OK);
  return m;
}

static int same_mesh(const mx_mesher2d *a, const mx_mesher2d *b) {
  mx_mesh2d_arrays x, y;
  if (mx_mesher2d_mesh_arrays(a, &x) || mx_mesher2d_mesh_arrays(b, &y)) return 0;
  return x.nnodes == y.nnodes && x.ncells == y.ncells &&
         !memcmp(x.xy, y.xy, 2 * x.nnodes * sizeof *x.xy) &&
         !memcmp(x.conn, y.conn, 4 * x.ncells * sizeof *x.conn) &&
         !memcmp(x.type, y.type, x.ncells) && !memcmp(x.leaf, y.leaf, 4 * x.ncells);
}

/* The cell with a node at (0, 0), the lowest such. */
static uint64_t corner_cell(const mx_mesher2d *m) {
  mx_mesh2d_arrays a;
  CHECK(mx_mesher2d_mesh_arrays(m, &a) == MX_OK);
  for (size_t c = 0; c < a.ncells; c++)
    for (int k = 0; k < 3 + a.type[c]; k++) {
      const double *p = a.xy + 2 * (size_t)a.conn[4 * c + k];
      if (p[0] == 0.0 && p[1] == 0.0) return c;
    }
  CHECK(!"no cell at the corner");
  return 0;
}

/* Distance from (0,0) to the box of leaf q. */
static double leaf_distance(const mx_qtree *T, uint32_t q) {
  uint32_t x, y;
  mx_qkey_xy(T->key[q], &x, &y);
  const double s = T->grid.unit * mx_qsize(T->level[q]);
  const double lo[2] = {T->grid.origin[0] + T->grid.unit * x, T->grid.origin[1] + T->grid.unit * y};
  double d2 = 0;
  for (int a = 0; a < 2; a++) {
    const double d = lo[a] > 0 ? lo[a] : (lo[a] + s < 0 ? -(lo[a] + s) : 0);
    d2 += d * d;
  }
  return sqrt(d2);
}

static int cmp_u64(const void *a, const void *b) {
  const uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
  return x < y ? -1 : x > y;
}

/* Index of key in the ascending keys, or UINT32_MAX. */
static uint32_t index_of(const uint64_t *v, size_t n, uint64_t key) {
  const uint64_t *p = bsearch(&key, v, n, sizeof *v, cmp_u64);
  return p ? (uint32_t)(p - v) : UINT32_MAX;
}

static size_t sort_unique(uint64_t *v, size_t n) {
  qsort(v, n, sizeof *v, cmp_u64);
  size_t w = 0;
  for (size_t i = 0; i < n; i++)
    if (!w || v[i] != v[w - 1]) v[w++] = v[i];
  return w;
}

static void check_restart_data(const mx_mesher2d *m, int threads) {
  omp_set_num_threads(threads);
  mx_restart r;
  CHECK(mx_qrestart_from_mesher(m, &r) == MX_OK);
  const mx_qtree *T = &m->T;
  const size_t n = m->nleaves;
  uint64_t *key = mx_alloc((4 * n + 1) * sizeof *key), *side = mx_alloc((4 * n + 1) * sizeof *side);
  uint32_t *corner = mx_alloc((4 * n + 1) * sizeof *corner);
  for (size_t i = 0; i < n; i++) {
    uint32_t x, y;
    mx_qkey_xy(T->key[m->leaves[i]], &x, &y);
    const uint32_t s = mx_qsize(T->level[m->leaves[i]]);
    key[4 * i] = mx_qkey(x, y), key[4 * i + 1] = mx_qkey(x + s, y);
    key[4 * i + 2] = mx_qkey(x + s, y + s), key[4 * i + 3] = mx_qkey(x, y + s);
  }
  uint64_t *node = mx_alloc((4 * n + 1) * sizeof *node);
  memcpy(node, key, 4 * n * sizeof *key);
  const size_t nv = sort_unique(node, 4 * n);
  CHECK(r.dim == 2 && r.no == n && r.nv == nv);
  size_t bad = 0;
  for (size_t v = 0; v < nv && r.nv == nv; v++) {
    uint32_t x, y;
    mx_qkey_xy(node[v], &x, &y);
    bad += r.xyz[3 * v] != T->grid.origin[0] + T->grid.unit * (double)x ||
           r.xyz[3 * v + 1] != T->grid.origin[1] + T->grid.unit * (double)y ||
           r.xyz[3 * v + 2] != 0;
  }
  for (size_t i = 0; i < n; i++) {
    for (int c = 0; c < 4; c++) {
      corner[4 * i + c] = index_of(node, nv, key[4 * i + c]);
      bad += r.oct_node[8 * i + c] != corner[4 * i + c] || r.oct_node[8 * i + 4 + c] != 0;
    }
    for (int c = 0; c < 4; c++) {
      const uint32_t a = corner[4 * i + c], b = corner[4 * i + ((c + 1) & 3)];
      side[4 * i + c] = a < b ? (uint64_t)a << 32 | b : (uint64_t)b << 32 | a;
    }
    bad += r.oct_level[i] != T->level[m->leaves[i]];
  }
  const size_t ne = sort_unique(side, 4 * n);
  CHECK(r.ne == ne);
  for (size_t j = 0; j < ne && r.ne == ne; j++) {
    const uint32_t a = (uint32_t)(side[j] >> 32), b = (uint32_t)side[j];
    uint32_t xa, ya, xb, yb;
    mx_qkey_xy(node[a], &xa, &ya);
    mx_qkey_xy(node[b], &xb, &yb);
    const uint32_t mid = index_of(node, nv, mx_qkey((xa + xb) / 2, (ya + yb) / 2));
    bad += r.edge[3 * j] != a || r.edge[3 * j + 1] != b ||
           r.edge[3 * j + 2] != (mid == UINT32_MAX ? 0 : mid);
  }
  /* segments and cells of each leaf */
  size_t cells = 0;
  for (size_t i = 0; i < n; i++) {
    const uint32_t q = m->leaves[i];
    bad += r.oct_tri_off[i + 1] - r.oct_tri_off[i] != T->seg_cnt[q] ||
           memcmp(r.oct_tri + r.oct_tri_off[i], T->seg_pool + T->seg_off[q],
                  T->seg_cnt[q] * sizeof *r.oct_tri) != 0;
    for (uint32_t k = 0; k < r.nsub[i]; k++) bad += m->M.leaf[cells + k] != i;
    cells += r.nsub[i];
  }
  CHECK(bad == 0 && cells == m->M.ncells);
  if (bad) fprintf(stderr, "restart data: %zu differences (%zu leaves)\n", bad, n);
  mx_free(key), mx_free(side), mx_free(corner), mx_free(node);
  mx_restart_free(&r);
}

static void test_restart_data(void) {
  for (int k = 0; k < 4; k++) {
    mx_params2d p;
    mx_params2d_default(&p);
    p.surface_level = k == 0 ? 7 : 3;
    p.all_level = k == 3 ? 5 : 0;
    mx_mesher2d *m = mx_mesher2d_new(&p);
    CHECK(mx_mesher2d_set_domain(m, poly(k == 0 ? "a.poly" : "box.poly")) == MX_OK);
    const double circle[3] = {1.5, 0.4, 0.9};
    if (k == 1) CHECK(mx_mesher2d_add_function(m, "circle", circle, 3, 10) == MX_OK);
    CHECK(mx_mesher2d_mesh(m) == MX_OK);
    for (int it = 0; k == 2 && it < 8; it++) {
      const uint64_t e = corner_cell(m);
      CHECK(mx_mesher2d_refine_elements(m, &e, 1) == MX_OK);
    }
    check_restart_data(m, 1);
    check_restart_data(m, 2);
    mx_mesher2d_free(m);
  }
}

static void test_counts_and_round_trip(void) {
  mx_mesher2d *m = box_mesher(3);
  CHECK(mx_mesher2d_mesh(m) == MX_OK);
  mx_stats2d s;
  mx_mesher2d_stats(m, &s);
  CHECK(s.valid && s.leaves == 60 && s.cells == 60 && s.quads == 60 && s.nodes == 80);
  CHECK(mx_mesher2d_save_restart(m, "qremesh_box3.oct") == MX_OK);

  /* the file: 60 quadrants, nodes = leaf corners (81 lattice points less
   * the hole's centre corner), every edge's mid-node 0 (one level) */
  mx_restart r;
  CHECK(mx_restart_read_dim("qremesh_box3.oct", 2, &r) == MX_OK);
  CHECK(r.dim == 2 && r.no == 60 && r.nv == 80 && r.nsub);
  size_t cells = 0, split = 0;
  for (size_t i = 0; i < r.no; i++) {
    cells += r.nsub[i];
    CHECK(r.oct_level[i] == 3);
  }
  for (size_t e = 0; e < r.ne; e++) split += r.edge[3 * e + 2] != 0;
  CHECK(cells == 60 && split == 0);
  /* the 60 leaves' edges: 4 * 60 = 240 sides, interior ones shared by two
   * leaves; 2 * 8 * 9 = 144 lattice edges less the 4 inside the hole */
  CHECK(r.ne == 140);
  mx_restart_free(&r);
  /* the 3D reader refuses it, the 2D reader refuses a 3D file */
  mx_msg_fn = quiet;
  CHECK(mx_restart_read("qremesh_box3.oct", &r) == MX_EINPUT);
  char oct3[600];
  snprintf(oct3, sizeof oct3, "%s/remesh/c5.oct", data);
  CHECK(mx_restart_read_dim(oct3, 2, &r) == MX_EINPUT);
  mx_msg_fn = NULL;

  /* load + mesh = the same mesh; load + an empty list = the same mesh */
  mx_mesher2d *b = box_mesher(0);
  CHECK(mx_mesher2d_load_restart(b, "qremesh_box3.oct") == MX_OK);
  CHECK(mx_mesher2d_restart_elements(b) == 60);
  CHECK(mx_mesher2d_mesh(b) == MX_OK && same_mesh(m, b));
  mx_mesher2d *c = box_mesher(0);
  CHECK(mx_mesher2d_load_restart(c, "qremesh_box3.oct") == MX_OK);
  CHECK(mx_mesher2d_refine_elements(c, NULL, 0) == MX_OK && same_mesh(m, c));

  /* one element: its quadrant split once, listed twice or not */
  const uint64_t e[2] = {corner_cell(m), corner_cell(m)};
  CHECK(mx_mesher2d_load_restart(c, "qremesh_box3.oct") == MX_OK);
  CHECK(mx_mesher2d_refine_elements(c, e, 2) == MX_OK);
  mx_mesher2d_stats(c, &s);
  CHECK(s.refined_listed == 1 && s.leaves == 63 && s.split_balance == 0 && s.valid);
  /* the same from the mesh in memory */
  CHECK(mx_mesher2d_refine_elements(m, e, 1) == MX_OK && same_mesh(m, c));

  /* an index beyond the mesh, a restart of another domain */
  mx_mesher2d_set_message_handler(m, quiet, NULL);
  const uint64_t far = 1000;
  CHECK(mx_mesher2d_refine_elements(m, &far, 1) == MX_EINPUT);
  mx_mesher2d *a = mx_mesher2d_new(NULL);
  mx_mesher2d_set_message_handler(a, quiet, NULL);
  CHECK(mx_mesher2d_set_domain(a, poly("a.poly")) == MX_OK);
  CHECK(mx_mesher2d_load_restart(a, "qremesh_box3.oct") == MX_EINPUT);
  CHECK(strstr(mx_mesher2d_last_error(a), "another domain") != NULL);
  mx_msg_fn = NULL;
  mx_mesher2d_free(a);
  mx_mesher2d_free(b);
  mx_mesher2d_free(c);
  mx_mesher2d_free(m);
}

static void test_fig18(void) {
  mx_mesher2d *m = box_mesher(3);
  CHECK(mx_mesher2d_mesh(m) == MX_OK);
  int maxlevel = 3;
  for (int it = 1; it <= 20; it++) {
    const uint64_t e = corner_cell(m);
    const int listed_level = m->M.level[e];
    const size_t before = m->nleaves;
    CHECK(mx_mesher2d_refine_elements(m, &e, 1) == MX_OK);
    mx_stats2d s;
    mx_mesher2d_stats(m, &s);
    CHECK(s.valid && s.invalid == 0 && s.refined_listed == 1);
    CHECK(mx_qtree_unbalanced(&m->T) == 0);
    int now = 0;
    for (size_t i = 0; i < m->nleaves; i++) {
      const uint32_t q = m->leaves[i];
      if (m->T.level[q] > now) now = m->T.level[q];
      if (m->T.level[q] >= 4) {
        const double parent_side = m->T.grid.unit * mx_qsize(m->T.level[q] - 1);
        if (!(leaf_distance(&m->T, q) <= 3.0 * parent_side)) {
          fprintf(stderr, "iteration %d: leaf of level %d at %g from the corner\n", it,
                  m->T.level[q], leaf_distance(&m->T, q));
          CHECK(0);
        }
      }
    }
    CHECK(now >= listed_level + 1 && now >= maxlevel && now <= maxlevel + 1);
    CHECK(s.leaves >= before);
    maxlevel = now;
    if (it == 20)
      printf("Fig. 18: after 20 refinements %zu leaves, %zu cells, %zu nodes, finest level %d "
             "(the paper: 324 elements, 280 vertices)\n", s.leaves, s.cells, s.nodes, now);
  }
  CHECK(maxlevel >= 3 + 15);
  /* the file of the last state gives it back */
  CHECK(mx_mesher2d_save_restart(m, "qremesh_fig18.oct") == MX_OK);
  mx_mesher2d *b = box_mesher(0);
  CHECK(mx_mesher2d_load_restart(b, "qremesh_fig18.oct") == MX_OK);
  CHECK(mx_mesher2d_mesh(b) == MX_OK && same_mesh(m, b));
  mx_mesher2d_free(b);
  mx_mesher2d_free(m);
  unlink("qremesh_fig18.oct");
  unlink("qremesh_box3.oct");
}

/* Features close together: the letter A and the pie at coarse levels, where
 * two features fall in one quadrant, are valid with every feature a vertex
 * (the quadrants holding them refined); without that rule the A at -s 5
 * is refused, naming both features. */
static void test_feature_levels(void) {
  const char *names[2] = {"a.poly", "pie.poly"};
  for (int k = 0; k < 2; k++)
    for (int s = 1; s <= 5; s++) {
      mx_params2d p;
      mx_params2d_default(&p);
      p.surface_level = s;
      mx_mesher2d *m = mx_mesher2d_new(&p);
      CHECK(mx_mesher2d_set_domain(m, poly(names[k])) == MX_OK);
      CHECK(mx_mesher2d_mesh(m) == MX_OK);
      CHECK(m->valid && m->cr.missing_features == 0 && m->bs.features == m->nfeatures);
      mx_mesher2d_free(m);
    }
  mx_params2d p;
  mx_params2d_default(&p);
  p.surface_level = 5;
  p.feature_levels = 0;
  mx_mesher2d *m = mx_mesher2d_new(&p);
  mx_mesher2d_set_message_handler(m, quiet, NULL);
  CHECK(mx_mesher2d_set_domain(m, poly("a.poly")) == MX_OK);
  CHECK(mx_mesher2d_mesh(m) != MX_OK);
  CHECK(strstr(mx_mesher2d_last_error(m), "same node") != NULL);
  mx_mesher2d_free(m);
}

/* The library's requests and their refusals. */
static void test_requests(void) {
  mx_mesher2d *m = mx_mesher2d_new(NULL);
  mx_mesher2d_set_message_handler(m, quiet, NULL);
  const int nodomain = mx_mesher2d_mesh(m);
  CHECK(nodomain == MX_EINPUT); /* no domain */
  if (nodomain != MX_EINPUT) fprintf(stderr, "no domain: %d\n", nodomain);
  const double sq[8] = {0, 0, 1, 0, 1, 1, 0, 1};
  const uint32_t seg[8] = {0, 1, 1, 2, 2, 3, 3, 0};
  CHECK(mx_mesher2d_set_domain_arrays(m, "square", 4, sq, 4, seg) == MX_OK);
  CHECK(mx_mesher2d_set_domain(m, poly("box.poly")) == MX_EINPUT); /* one domain */
  CHECK(mx_mesher2d_set_levels(m, 40, 0) == MX_EINPUT);
  const double args[3] = {0.5, 0.5, 0.25};
  CHECK(mx_mesher2d_add_function(m, "circle", args, 2, 5) == MX_EINPUT);
  CHECK(mx_mesher2d_add_function(m, "spiral", args, 3, 5) == MX_EINPUT);
  CHECK(mx_mesher2d_add_function(m, "circle", args, 3, 5) == MX_OK);
  const double lo[2] = {0.8, 0.8}, hi[2] = {0.7, 1};
  CHECK(mx_mesher2d_add_box(m, lo, hi, 3) == MX_EINPUT);
  CHECK(mx_mesher2d_set_levels(m, 2, 0) == MX_OK);
  CHECK(mx_mesher2d_mesh(m) == MX_OK);
  mx_stats2d s;
  mx_mesher2d_stats(m, &s);
  /* the unit square, one root of side 1.01: level-5 leaves along the
   * circle, all cells valid, the area of the square within tolerance */
  CHECK(s.valid && s.invalid == 0 && s.cells > 0 && fabs(m->cr.area - 1.0) < 1e-9);
  /* a memory limit far below the estimate refuses before meshing */
  mx_params2d p;
  mx_params2d_default(&p);
  p.all_level = 14;
  p.max_memory_mb = 10;
  mx_mesher2d *big = mx_mesher2d_new(&p);
  mx_mesher2d_set_message_handler(big, quiet, NULL);
  CHECK(mx_mesher2d_set_domain(big, poly("a.poly")) == MX_OK);
  CHECK(mx_mesher2d_mesh(big) == MX_ENOMEM);
  CHECK(strstr(mx_mesher2d_last_error(big), "MB") != NULL);
  mx_mesher2d_free(big);
  mx_mesher2d_free(m);
}

/* "No level" is -1 in 2D as in 3D (mx_params_default): the defaults, and
 * set_levels(-1, ...) gives the same mesh as level 0 (nothing asked of
 * that request); -2 is refused. */
static void test_no_level(void) {
  mx_params2d p;
  mx_params2d_default(&p);
  CHECK(p.surface_level == -1 && p.all_level == -1);
  mx_mesher2d *a = box_mesher(-1), *b = box_mesher(0);
  mx_mesher2d_set_message_handler(a, quiet, NULL);
  CHECK(mx_mesher2d_set_levels(a, -1, 4) == MX_OK && mx_mesher2d_set_levels(b, 0, 4) == MX_OK);
  CHECK(mx_mesher2d_mesh(a) == MX_OK && mx_mesher2d_mesh(b) == MX_OK);
  CHECK(same_mesh(a, b));
  CHECK(mx_mesher2d_set_levels(a, -2, 4) == MX_EINPUT);
  mx_mesher2d_free(a);
  mx_mesher2d_free(b);
}

int main(void) {
  const char *d = test_data_dir("polylines/box.poly");
  snprintf(data, sizeof data, "%s", d ? d : MIXOCT_TEST_DATA);
  if (!d) {
    fprintf(stderr, "no shared data (MIXOCT_DATA): %s\n", poly("box.poly"));
    return 1;
  }
  test_counts_and_round_trip();
  test_fig18();
  test_restart_data();
  test_feature_levels();
  test_requests();
  test_no_level();
  return TEST_DONE();
}
