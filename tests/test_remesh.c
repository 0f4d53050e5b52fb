/* Re-meshing through the library (include/mixoct.h): list refinement
 * (Algorithm 3 of the 2021 paper) against an independent construction,
 * balance after every refinement (an independent checker), repeated
 * refinement of one element (Fig. 18: local, balanced, valid), restart
 * round trips (text and binary), local re-meshing against full re-meshing
 * and a run from scratch, the published c5.oct re-meshed with its list, and
 * bad restart and list files. Without the shared data: the repair's rule to
 * go on (mx_repair_go_on) and the exit-5 messages naming the inputs. */
#include "check.h"
#include "base/common.h"
#include "io/read_mesh.h"
#include "verify/check.h"
#include "mesher/mesher.h"
#include "mesher/mesher_impl.h"
#include "mixoct.h"
#include "octree_util.h"
#include "file_util.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#define OUT "remesh_out"

static char data_dir[512];

static int cmp_u64(const void *a, const void *b) {
  const uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
  return (x > y) - (x < y);
}

static int find_data(void) {
  const char *d = test_data_dir("surfaces/cortex.off");
  if (d) snprintf(data_dir, sizeof data_dir, "%s", d);
  return d != NULL;
}

static char *data(const char *rel) {
  static char buf[4][700];
  static int k = 0;
  k = (k + 1) % 4;
  snprintf(buf[k], sizeof buf[k], "%s/%s", data_dir, rel);
  return buf[k];
}

static mx_mesher *cortex_mesher(int s, int stage) {
  mx_params p;
  mx_params_default(&p);
  p.surface_level = s;
  p.stage = stage;
  mx_mesher *m = mx_mesher_new(&p);
  CHECK(m && mx_mesher_add_surface(m, data("surfaces/cortex.off")) == MX_OK);
  return m;
}

static size_t s_elements(const mx_mesher *m) {
  mx_mesh_arrays a;
  return mx_mesher_mesh_arrays(m, &a) == MX_OK ? a.nelements : 0;
}

/* Independent validity of the current mesh: mx_check_mesh (faces matched,
 * no hanging node, J_ENS > 0). */
static int mesh_is_valid(const mx_mesher *m) {
  mx_mesh_arrays a;
  if (mx_mesher_mesh_arrays(m, &a)) return 0;
  mx_mesh_data d = {.nnodes = a.nnodes, .ncells = a.nelements, .xyz = (double *)a.xyz,
                    .type = (uint8_t *)a.type, .conn = (uint32_t *)a.conn};
  mx_check_report r;
  if (mx_check_mesh(&d, NULL, &r) != MX_OK) return 0;
  if (r.defects)
    fprintf(stderr, "check: %zu defects (%zu invalid, %zu hanging, %zu overshared)\n",
            r.defects, r.invalid, r.hanging_nodes, r.faces_overshared);
  return r.defects == 0 && r.invalid == 0 && a.nelements > 0;
}

static int balanced(const mx_mesher *m) {
  return check_balance(&m->B, m->leaves, m->nleaves);
}

/* 1. Algorithm 3 against a from-scratch run told to split the same leaves. */
static void test_list_vs_scratch(void) {
  mx_mesher *a = cortex_mesher(4, MX_STAGE_TRANSITION);
  CHECK(mx_mesher_mesh(a) == MX_OK);
  const size_t n0 = a->nleaves;
  /* every 13th leaf, and one listed twice through two of its elements */
  uint64_t *list = malloc((n0 / 13 + 2) * sizeof *list);
  size_t n = 0;
  for (size_t i = 0; i < n0; i += 13) list[n++] = i;
  list[n++] = 0;
  /* the same leaves as (key, level), for the independent run */
  uint64_t *keys[MX_MAX_LEVEL + 1] = {0};
  size_t nk[MX_MAX_LEVEL + 1] = {0};
  for (size_t i = 0; i < n; i++) {
    const uint32_t o = a->leaves[list[i]];
    const int l = a->B.tree.oct.level[o];
    keys[l] = realloc(keys[l], (nk[l] + 1) * sizeof **keys);
    keys[l][nk[l]++] = a->B.tree.oct.key[o];
  }
  CHECK(mx_mesher_refine_leaves(a, list, n) == MX_OK);
  CHECK(a->nleaves > n0);
  CHECK(balanced(a));
  CHECK(a->rec->S.refined_listed == n - 1);

  mx_mesher *b = cortex_mesher(4, MX_STAGE_TRANSITION);
  for (int l = 0; l <= MX_MAX_LEVEL; l++) {
    if (!nk[l]) continue;
    qsort(keys[l], nk[l], sizeof **keys, cmp_u64);
    b->split_keys[l] = mx_alloc(nk[l] * sizeof **keys);
    memcpy(b->split_keys[l], keys[l], nk[l] * sizeof **keys);
    b->nsplit[l] = nk[l];
    free(keys[l]);
  }
  CHECK(mx_mesher_mesh(b) == MX_OK);
  mx_stats sa, sb;
  mx_mesher_stats(a, &sa);
  mx_mesher_stats(b, &sb);
  printf("list refinement: %zu leaves listed, %zu -> %zu leaves; from scratch %zu; "
         "hashes %016llx %016llx\n", n - 1, n0, sa.leaves, sb.leaves,
         (unsigned long long)sa.leaves_hash, (unsigned long long)sb.leaves_hash);
  CHECK(sa.leaves == sb.leaves);
  CHECK(sa.leaves_hash == sb.leaves_hash);
  /* same octree -> same mesh (transition stage: no untangling involved) */
  CHECK(sa.nodes == sb.nodes && sa.elements == sb.elements);
  mx_mesh_arrays xa, xb;
  CHECK(mx_mesher_mesh_arrays(a, &xa) == MX_OK && mx_mesher_mesh_arrays(b, &xb) == MX_OK);
  CHECK(xa.nelements == xb.nelements &&
        !memcmp(xa.conn, xb.conn, 8 * xa.nelements * sizeof *xa.conn) &&
        !memcmp(xa.xyz, xb.xyz, 3 * xa.nnodes * sizeof *xa.xyz));
  free(list);
  mx_mesher_free(a);
  mx_mesher_free(b);
}

/* 1b. The full stage: re-meshing equals meshing from scratch the same
 * octree (both run every step on the whole octree). */
static void test_full_equals_scratch(void) {
  mx_mesher *a = cortex_mesher(4, MX_STAGE_FULL);
  CHECK(mx_mesher_mesh(a) == MX_OK);
  CHECK(mesh_is_valid(a));
  uint64_t el[3] = {5, 1000, 3000};
  CHECK(mx_mesher_refine_elements(a, el, 3) == MX_OK);
  CHECK(balanced(a));
  CHECK(mesh_is_valid(a));
  /* from scratch: split set = every split octant of a */
  mx_mesher *b = cortex_mesher(4, MX_STAGE_FULL);
  const mx_octree *T = &a->B.tree.oct;
  for (size_t o = 0; o < T->n; o++) {
    if (!(T->flags[o] & MX_OCT_SPLIT)) continue;
    const int l = T->level[o];
    b->split_keys[l] = realloc(b->split_keys[l], (b->nsplit[l] + 1) * sizeof(uint64_t));
    b->split_keys[l][b->nsplit[l]++] = T->key[o];
  }
  for (int l = 0; l <= MX_MAX_LEVEL; l++)
    if (b->nsplit[l]) qsort(b->split_keys[l], b->nsplit[l], sizeof(uint64_t), cmp_u64);
  CHECK(mx_mesher_mesh(b) == MX_OK);
  mx_stats sa, sb;
  mx_mesher_stats(a, &sa);
  mx_mesher_stats(b, &sb);
  CHECK(sa.leaves_hash == sb.leaves_hash);
  CHECK(sa.nodes == sb.nodes && sa.elements == sb.elements);
  mx_mesh_arrays xa, xb;
  CHECK(mx_mesher_mesh_arrays(a, &xa) == MX_OK && mx_mesher_mesh_arrays(b, &xb) == MX_OK);
  CHECK(xa.nnodes == xb.nnodes &&
        !memcmp(xa.xyz, xb.xyz, 3 * xa.nnodes * sizeof *xa.xyz));
  printf("full stage after list refinement: %zu nodes, %zu elements, same as from "
         "scratch\n", sa.nodes, sa.elements);
  mx_mesher_free(a);
  mx_mesher_free(b);
}

/* Same nodes (bit for bit), same elements in the same order. */
static int same_mesh(const mx_mesher *a, const mx_mesher *b) {
  mx_mesh_arrays x, y;
  if (mx_mesher_mesh_arrays(a, &x) || mx_mesher_mesh_arrays(b, &y)) return 0;
  return x.nnodes == y.nnodes && x.nelements == y.nelements &&
         !memcmp(x.xyz, y.xyz, 3 * x.nnodes * sizeof *x.xyz) &&
         !memcmp(x.type, y.type, x.nelements) &&
         !memcmp(x.conn, y.conn, 8 * x.nelements * sizeof *x.conn) &&
         !memcmp(x.leaf, y.leaf, x.nelements * sizeof *x.leaf);
}

/* Elements with their first node in the slab lo <= x < hi of the bounding
 * box (fractions), and below `yf` of it along y. */
static uint64_t *slab(const mx_mesher *m, double lo, double hi, double yf, size_t *n) {
  mx_mesh_arrays a;
  CHECK(mx_mesher_mesh_arrays(m, &a) == MX_OK);
  double b0[3] = {INFINITY, INFINITY, INFINITY}, b1[3] = {-INFINITY, -INFINITY, -INFINITY};
  for (size_t v = 0; v < a.nnodes; v++)
    for (int k = 0; k < 3; k++) {
      b0[k] = fmin(b0[k], a.xyz[3 * v + k]);
      b1[k] = fmax(b1[k], a.xyz[3 * v + k]);
    }
  uint64_t *l = malloc((a.nelements + 1) * sizeof *l);
  *n = 0;
  for (size_t c = 0; c < a.nelements; c++) {
    const double *x = a.xyz + 3 * (size_t)a.conn[8 * c];
    const double u = (x[0] - b0[0]) / (b1[0] - b0[0]), w = (x[1] - b0[1]) / (b1[1] - b0[1]);
    if (u >= lo && u < hi && w < yf) l[(*n)++] = c;
  }
  return l;
}

/* Local re-meshing (only the leaves around what was split are meshed
 * again) against a full re-mesh of the same octree, over several rounds:
 * the same mesh, bit for bit, while the patch stays a part of the octree;
 * then the local result against a run from scratch on its octree (a text
 * restart file has no mesh: reading it and meshing is a run from scratch),
 * and the binary restart file, which carries the mesh: read back, the same
 * mesh; refined from it, the same mesh as refined in memory. */
static void test_local_vs_full(void) {
  mx_params p;
  mx_params_default(&p);
  p.surface_level = 5;
  p.remesh_full = -1; /* local whatever the cost: the local path is tested */
  mx_mesher *loc = mx_mesher_new(&p);
  p.threads = 1; /* and the same local re-mesh on one thread, with the edge
                   * infos freed after each transition and rebuilt by the
                   * splits (as the program runs) */
  mx_mesher *one = mx_mesher_new(&p);
  one->release_edges = 1;
  p.threads = 0;
  p.remesh_full = 1;
  mx_mesher *full = mx_mesher_new(&p);
  CHECK(mx_mesher_add_surface(loc, data("surfaces/cortex.off")) == MX_OK);
  CHECK(mx_mesher_add_surface(one, data("surfaces/cortex.off")) == MX_OK);
  CHECK(mx_mesher_add_surface(full, data("surfaces/cortex.off")) == MX_OK);
  CHECK(mx_mesher_mesh(loc) == MX_OK && mx_mesher_mesh(full) == MX_OK);
  CHECK(mx_mesher_mesh(one) == MX_OK);
  CHECK(same_mesh(loc, full));
  for (int round = 0; round < 4; round++) {
    size_t n = 0;
    uint64_t *l = slab(loc, 0.15 + 0.2 * round, 0.25 + 0.2 * round, 0.6, &n);
    CHECK(n > 0);
    CHECK(mx_mesher_refine_elements(loc, l, n) == MX_OK);
    CHECK(mx_mesher_refine_elements(full, l, n) == MX_OK);
    CHECK(mx_mesher_refine_elements(one, l, n) == MX_OK);
    free(l);
    CHECK(same_mesh(loc, one));
    mx_stats sl, sf;
    mx_mesher_stats(loc, &sl);
    mx_mesher_stats(full, &sf);
    CHECK(sl.remesh_local == 1 && sf.remesh_local == 0);
    CHECK(sl.leaves_hash == sf.leaves_hash);
    CHECK(same_mesh(loc, full));
    CHECK(mesh_is_valid(loc));
    CHECK(balanced(loc));
    CHECK(sl.remesh_patch_leaves > 0 && sl.remesh_patch_leaves < sl.leaves);
    printf("round %d: %zu elements listed, a patch of %zu leaves (%d attempt(s) with the "
           "repair rounds, %d repair round(s)) for %zu leaves\n", round + 1, n, sl.remesh_patch_leaves,
           loc->rec->S.local_attempts, sl.repair_rounds, sl.leaves);
  }
  printf("local re-mesh, 4 rounds at -s 5: the full re-mesh's mesh each time, the same on "
         "1 thread\n");
  /* against a run from scratch on the same octree */
  CHECK(mx_mesher_save_restart(loc, OUT "/local.oct") == MX_OK);
  CHECK(mx_mesher_save_restart(loc, OUT "/local.octb") == MX_OK);
  mx_params_default(&p);
  mx_mesher *s = mx_mesher_new(&p);
  CHECK(mx_mesher_add_surface(s, data("surfaces/cortex.off")) == MX_OK);
  CHECK(mx_mesher_load_restart(s, OUT "/local.oct") == MX_OK);
  CHECK(mx_mesher_mesh(s) == MX_OK);
  CHECK(same_mesh(loc, s));
  /* the binary file's mesh, read back */
  p.remesh_full = -1;
  mx_mesher *b = mx_mesher_new(&p);
  CHECK(mx_mesher_add_surface(b, data("surfaces/cortex.off")) == MX_OK);
  CHECK(mx_mesher_load_restart(b, OUT "/local.octb") == MX_OK);
  CHECK(same_mesh(loc, b));
  size_t n = 0;
  uint64_t *l = slab(loc, 0.5, 0.6, 1.0, &n);
  /* b reads the list as the files number the elements */
  uint64_t *lw = malloc((n + 1) * sizeof *lw);
  uint32_t *order = malloc((s_elements(loc) + 1) * sizeof *order);
  uint32_t *inv = malloc((s_elements(loc) + 1) * sizeof *inv);
  CHECK(lw && order && inv && mx_mesher_written_order(loc, order) == MX_OK);
  for (size_t k = 0; k < s_elements(loc); k++) inv[order[k]] = (uint32_t)k;
  for (size_t i = 0; i < n; i++) lw[i] = inv[l[i]];
  CHECK(mx_mesher_refine_elements(loc, l, n) == MX_OK);
  CHECK(mx_mesher_refine_elements(b, lw, n) == MX_OK);
  free(lw);
  free(order);
  free(inv);
  CHECK(mx_mesher_refine_elements(full, l, n) == MX_OK);
  free(l);
  mx_stats sb;
  mx_mesher_stats(b, &sb);
  CHECK(sb.remesh_local == 1);
  CHECK(same_mesh(loc, b) && same_mesh(loc, full));
  printf("local re-mesh = run from scratch on its octree; from the binary restart file: "
         "the same mesh as in memory\n");
  mx_mesher_free(loc);
  mx_mesher_free(one);
  mx_mesher_free(full);
  mx_mesher_free(s);
  mx_mesher_free(b);
}

/* 1d. The choice between a local and a full re-mesh (params.remesh_full
 * 0, the default): the cost model's shape (mx_remesh_local_pays: a patch of
 * every leaf, or one whose border is long enough that its splice is most
 * likely refused, never pays; a small one with a short border does), then
 * on the cortex at -s 5: 50 elements spread over it (their patches are
 * most of the octree) are meshed by the full path, a few elements in a row
 * of the Morton order (one spot) by the local one; both meshes valid
 * (mx_check_mesh) and the mesh of a full re-mesh. */
static void test_choice(void) {
  CHECK(!mx_remesh_local_pays(100000, 0, 100000));
  CHECK(!mx_remesh_local_pays(90000, 0, 100000));
  CHECK(mx_remesh_local_pays(1000, 100, 100000));
  CHECK(!mx_remesh_local_pays(1000, 1000000, 100000));
  for (size_t np = 0; np <= 100000; np += 5000) /* increasing in np and the border */
    for (size_t nb = 0; nb <= 60000; nb += 5000)
      CHECK(mx_remesh_local_pays(np + 5000, nb, 100000) <= mx_remesh_local_pays(np, nb, 100000) &&
            mx_remesh_local_pays(np, nb + 5000, 100000) <= mx_remesh_local_pays(np, nb, 100000));
  for (int list = 0; list < 2; list++) {
    mx_params p;
    mx_params_default(&p);
    p.surface_level = 5;
    mx_mesher *m = mx_mesher_new(&p);
    p.remesh_full = 1;
    mx_mesher *f = mx_mesher_new(&p);
    CHECK(mx_mesher_add_surface(m, data("surfaces/cortex.off")) == MX_OK &&
          mx_mesher_add_surface(f, data("surfaces/cortex.off")) == MX_OK);
    CHECK(mx_mesher_mesh(m) == MX_OK && mx_mesher_mesh(f) == MX_OK);
    const size_t nc = s_elements(m);
    uint64_t l[50];
    const size_t n = list == 0 ? 50 : 4;
    for (size_t i = 0; i < n; i++) l[i] = list == 0 ? (2 * i + 1) * (nc / 100) : nc / 2 + i;
    CHECK(mx_mesher_refine_elements(m, l, n) == MX_OK);
    CHECK(mx_mesher_refine_elements(f, l, n) == MX_OK);
    mx_stats s;
    mx_mesher_stats(m, &s);
    printf("choice, %s: %zu leaves, %s re-mesh (patch %zu leaves), %d repair round(s)\n",
           list == 0 ? "50 scattered elements" : "4 elements in a row", s.leaves,
           s.remesh_local ? "local" : "full", s.remesh_patch_leaves, s.repair_rounds);
    CHECK(s.remesh_local == (list == 1));
    CHECK(list == 0 ? s.remesh_patch_leaves == 0
                    : s.remesh_patch_leaves > 0 && s.remesh_patch_leaves < s.leaves);
    CHECK(mesh_is_valid(m));
    CHECK(balanced(m));
    CHECK(same_mesh(m, f));
    mx_mesher_free(m);
    mx_mesher_free(f);
  }
}

/* 2. Fig. 18: one element refined again and again (the element holding a
 * fixed point), down to the finest level: local, balanced, valid. */
static void test_repeated(void) {
  mx_params p;
  mx_params_default(&p);
  p.surface_level = 4;
  p.remesh_full = -1; /* local whatever the cost (the first rounds patch it all) */
  mx_mesher *m = mx_mesher_new(&p);
  CHECK(mx_mesher_add_demo_surface(m) == MX_OK);
  CHECK(mx_mesher_mesh(m) == MX_OK);
  const double target[3] = {3.0, -2.0, 1.5};
  size_t prev = m->nleaves;
  int rounds = 0, finest = 0;
  size_t maxgrew = 0, last_patch = 0, last_leaves = 0;
  for (int r = 0; r < 20; r++) {
    /* the element whose centroid is closest to target */
    mx_mesh_arrays a;
    CHECK(mx_mesher_mesh_arrays(m, &a) == MX_OK);
    uint64_t best = 0;
    double bd = INFINITY;
    for (size_t c = 0; c < a.nelements; c++) {
      const int nn = mx_cell_nodes[a.type[c]];
      double g[3] = {0, 0, 0};
      for (int k = 0; k < nn; k++)
        for (int d = 0; d < 3; d++) g[d] += a.xyz[3 * a.conn[8 * c + k] + d] / nn;
      const double dd = (g[0] - target[0]) * (g[0] - target[0]) +
                        (g[1] - target[1]) * (g[1] - target[1]) +
                        (g[2] - target[2]) * (g[2] - target[2]);
      if (dd < bd) {
        bd = dd;
        best = c;
      }
    }
    if (a.level[best] >= MX_MAX_LEVEL - 1) {
      finest = 1;
      /* one split more is refused (the lattice of a leaf needs one level
       * below it: a level-16 leaf once made the node hash grow until
       * memory ran out), and the mesh stays as it was */
      const size_t before = m->nleaves;
      CHECK(mx_mesher_refine_elements(m, &best, 1) == MX_EINPUT);
      CHECK(strstr(mx_mesher_last_error(m), "finest level") != NULL);
      CHECK(m->nleaves == before && mesh_is_valid(m));
      break;
    }
    CHECK(mx_mesher_refine_elements(m, &best, 1) == MX_OK);
    rounds++;
    CHECK(balanced(m));
    CHECK(mesh_is_valid(m));
    /* local: one split adds 7 leaves, balance a bounded ring more */
    const size_t grew = m->nleaves - prev;
    if (grew > maxgrew) maxgrew = grew;
    CHECK(grew >= 7 && grew <= 2000);
    prev = m->nleaves;
    /* and meshed again locally: the patch is a small part of the leaves */
    mx_stats s;
    mx_mesher_stats(m, &s);
    CHECK(s.remesh_local == 1);
    CHECK(s.remesh_patch_leaves > 0 && s.remesh_patch_leaves <= s.leaves);
    last_patch = s.remesh_patch_leaves;
    last_leaves = s.leaves;
  }
  /* the patch: 6 rings of leaves around the split one, all of the coarse
   * octree of the first rounds, a part once the refinement is deep */
  CHECK(2 * last_patch < last_leaves);
  printf("repeated refinement of one element: %d rounds%s, %zu leaves (at most %zu "
         "new in one round; the last one meshed again %zu leaves of %zu), valid and balanced "
         "after each\n", rounds, finest ? " (finest level reached)" : "", m->nleaves, maxgrew,
         last_patch, last_leaves);
  CHECK(rounds >= 12);
  mx_mesher_free(m);
}

/* 3. Restart round trips: write, read, write gives the same bytes; read and
 * mesh gives the run's mesh. */
static void test_restart_round_trip(const char *ext) {
  char oct1[256], oct2[256], vtu1[256], vtu2[256];
  snprintf(oct1, sizeof oct1, OUT "/a.%s", ext);
  snprintf(oct2, sizeof oct2, OUT "/b.%s", ext);
  snprintf(vtu1, sizeof vtu1, OUT "/a_%s.vtu", ext);
  snprintf(vtu2, sizeof vtu2, OUT "/b_%s.vtu", ext);
  mx_mesher *a = cortex_mesher(4, MX_STAGE_FULL);
  CHECK(mx_mesher_mesh(a) == MX_OK);
  uint64_t el[2] = {17, 2048};
  CHECK(mx_mesher_refine_elements(a, el, 2) == MX_OK); /* not a plain -s run */
  CHECK(mx_mesher_save_restart(a, oct1) == MX_OK);
  CHECK(mx_mesher_write(a, vtu1, 0) == MX_OK);
  mx_params p;
  mx_params_default(&p); /* no level: the file's octree alone */
  mx_mesher *b = mx_mesher_new(&p);
  CHECK(mx_mesher_add_surface(b, data("surfaces/cortex.off")) == MX_OK);
  CHECK(mx_mesher_load_restart(b, oct1) == MX_OK);
  CHECK(mx_mesher_mesh(b) == MX_OK);
  mx_stats sa, sb;
  mx_mesher_stats(a, &sa);
  mx_mesher_stats(b, &sb);
  CHECK(sa.leaves_hash == sb.leaves_hash && sa.nodes == sb.nodes &&
        sa.elements == sb.elements);
  CHECK(mx_mesher_save_restart(b, oct2) == MX_OK);
  CHECK(mx_mesher_write(b, vtu2, 0) == MX_OK);
  CHECK(files_equal(oct1, oct2));
  CHECK(files_equal(vtu1, vtu2));
  /* the element list of the file refers to the written mesh, whose
   * elements are grouped by type: element k of the file is element
   * order[k] of the mesher's arrays */
  mx_mesh_arrays aa;
  CHECK(mx_mesher_mesh_arrays(a, &aa) == MX_OK);
  uint32_t *order = malloc((aa.nelements + 1) * sizeof *order);
  CHECK(order && mx_mesher_written_order(a, order) == MX_OK);
  mx_mesh_data wd;
  CHECK(mx_read_mesh(vtu1, &wd) == MX_OK);
  uint64_t el_arrays[2];
  for (int i = 0; i < 2; i++) {
    el_arrays[i] = order[el[i]];
    /* the same element: type and nodes as the file has them */
    CHECK(wd.type[el[i]] == aa.type[order[el[i]]]);
    for (int k = 0; k < mx_cell_nodes[wd.type[el[i]]]; k++)
      CHECK(wd.conn[8 * el[i] + (size_t)k] == aa.conn[8 * (size_t)order[el[i]] + (size_t)k]);
  }
  mx_mesh_data_free(&wd);
  free(order);
  CHECK(mx_mesher_load_restart(b, oct1) == MX_OK);
  CHECK(mx_mesher_refine_elements(b, el, 2) == MX_OK);
  CHECK(mx_mesher_refine_elements(a, el_arrays, 2) == MX_OK);
  mx_mesher_stats(a, &sa);
  mx_mesher_stats(b, &sb);
  CHECK(sa.leaves_hash == sb.leaves_hash && sa.elements == sb.elements);
  printf("restart round trip (.%s): %zu leaves, %zu elements, same bytes\n", ext,
         sa.leaves, sa.elements);
  mx_mesher_free(a);
  mx_mesher_free(b);
}

/* 4. The published program's c5.oct with its list. */
static void test_published(void) {
  mx_params p;
  mx_params_default(&p);
  mx_mesher *m = mx_mesher_new(&p);
  CHECK(mx_mesher_add_surface(m, data("surfaces/cortex.off")) == MX_OK);
  CHECK(mx_mesher_load_restart(m, data("remesh/c5.oct")) == MX_OK);
  CHECK(m->file_nelem == 26209);
  CHECK(m->nleaves >= 10123 - 100 && m->nleaves <= 10123 + 100);
  uint64_t *list = NULL;
  size_t n = 0;
  CHECK(mx_read_element_list(data("remesh/list.txt"), m->file_nelem, &list, &n) == MX_OK);
  CHECK(n == 1139);
  const size_t before = m->nleaves;
  CHECK(mx_mesher_refine_elements(m, list, n) == MX_OK);
  CHECK(balanced(m));
  CHECK(mesh_is_valid(m));
  mx_stats s;
  mx_mesher_stats(m, &s);
  printf("published c5.oct + list.txt: %zu -> %zu leaves, %zu listed leaves split, %zu "
         "nodes, %zu elements (published: 14,319 / 33,254)\n", before, s.leaves,
         s.refined_listed, s.nodes, s.elements);
  CHECK(s.nodes > 10941 && s.elements > 26209);
  mx_free_array(list);
  mx_mesher_free(m);
}

static void put(const char *path, const char *text) {
  FILE *f = fopen(path, "wb");
  fputs(text, f);
  fclose(f);
}

/* 5. Bad files: MX_EINPUT and a message, nothing changed. */
static void test_bad(void) {
  mx_mesher *m = cortex_mesher(3, MX_STAGE_FULL);
  CHECK(mx_mesher_mesh(m) == MX_OK);
  CHECK(mx_mesher_save_restart(m, OUT "/good.oct") == MX_OK);
  mx_stats s0;
  mx_mesher_stats(m, &s0);
  uint64_t big = s0.elements;
  CHECK(mx_mesher_refine_elements(m, &big, 1) == MX_EINPUT);
  CHECK(strstr(mx_mesher_last_error(m), "out of range") != NULL);
  uint64_t leaf = s0.leaves;
  CHECK(mx_mesher_refine_leaves(m, &leaf, 1) == MX_EINPUT);
  uint64_t *l = NULL;
  size_t n = 0;
  put(OUT "/neg.txt", "1 2\n-3\n");
  CHECK(mx_read_element_list(OUT "/neg.txt", 100, &l, &n) == MX_EINPUT);
  put(OUT "/range.txt", "1 2\n3 400\n");
  CHECK(mx_read_element_list(OUT "/range.txt", 100, &l, &n) == MX_EINPUT);
  put(OUT "/words.txt", "# elements\n1 2 x3 7\n"); /* a word: refused, not skipped */
  CHECK(mx_read_element_list(OUT "/words.txt", 100, &l, &n) == MX_EINPUT && !l && !n);
  put(OUT "/reals.txt", "# elements\n1.000000000000000000e+00 2.0\n7\n"); /* numpy */
  CHECK(mx_read_element_list(OUT "/reals.txt", 100, &l, &n) == MX_OK && n == 3 && l[0] == 1 &&
        l[1] == 2 && l[2] == 7);
  mx_free_array(l);
  CHECK(mx_read_element_list(OUT "/missing.txt", 100, &l, &n) == MX_EINPUT);
  /* truncated restart file */
  size_t len = 0;
  char *txt = slurp(OUT "/good.oct", &len);
  CHECK(txt != NULL);
  FILE *f = fopen(OUT "/trunc.oct", "wb");
  fwrite(txt, 1, len / 2, f);
  fclose(f);
  mx_params p;
  mx_params_default(&p);
  mx_mesher *b = mx_mesher_new(&p);
  CHECK(mx_mesher_add_surface(b, data("surfaces/cortex.off")) == MX_OK);
  CHECK(mx_mesher_load_restart(b, OUT "/trunc.oct") == MX_EINPUT);
  CHECK(strstr(mx_mesher_last_error(b), "trunc.oct") != NULL);
  /* wrong counts in the header */
  char *nl = strchr(txt, '\n');
  f = fopen(OUT "/counts.oct", "wb");
  fprintf(f, "1 2 3");
  fwrite(nl, 1, len - (size_t)(nl - txt), f);
  fclose(f);
  CHECK(mx_mesher_load_restart(b, OUT "/counts.oct") == MX_EINPUT);
  free(txt);
  /* wrong surface: the demo's grid is another one */
  mx_mesher *c = mx_mesher_new(&p);
  CHECK(mx_mesher_add_demo_surface(c) == MX_OK);
  CHECK(mx_mesher_load_restart(c, OUT "/good.oct") == MX_EINPUT);
  CHECK(strstr(mx_mesher_last_error(c), "surface") != NULL);
  /* no surface at all */
  mx_mesher *d = mx_mesher_new(&p);
  CHECK(mx_mesher_load_restart(d, OUT "/good.oct") == MX_EINPUT);
  mx_mesher_free(b);
  mx_mesher_free(c);
  mx_mesher_free(d);
  mx_mesher_free(m);
}

/* ---- the repair's rule and the exit-5 messages (no data needed) -------- */

/* The round at which mx_repair_go_on stops the repair of a run whose rounds
 * leave counts[0], counts[1], ... defects (n counts; max_rounds); n when it
 * never stops within them. */
static int stop_round(const uint64_t *counts, int n, int max_rounds) {
  mx_repair_progress p = {0, 0, 0};
  for (int r = 0; r < n; r++)
    if (!mx_repair_go_on(r, counts[r], max_rounds, &p)) return r;
  return n;
}

static void test_repair_rule(void) {
  /* the triple torus of issue 23 at -s 6 (invalid elements + contact
   * nodes after each round): worse after the first split, then converging.
   * The old rule (worse = not below the best so far) stopped at round 2
   * with 10 defects (exit 5); the repair must go on to round 4's 0. */
  const uint64_t torus3[] = {2, 30, 10, 2, 0};
  CHECK(stop_round(torus3, 5, 10) == 4);
  /* a repair that gets worse and worse (sphere_hole.off --repair-input -s 6)
   * stops after two worse rounds */
  const uint64_t diverging[] = {17, 33, 45, 60};
  CHECK(stop_round(diverging, 4, 10) == 2);
  /* no progress is worse too */
  const uint64_t flat[] = {5, 5, 5, 5};
  CHECK(stop_round(flat, 4, 10) == 2);
  /* ups and downs with new bests in between converge (holes.off
   * --repair-input -s 4) */
  const uint64_t holes4[] = {21, 15, 18, 1, 2, 0};
  CHECK(stop_round(holes4, 6, 10) == 5);
  /* worse rounds count since the best one, lowering the round before's
   * count between them does not reset them: 12 and 7 (not below 6, the
   * rounds before them) stop it at round 5; a new best (4) resets */
  const uint64_t oscillating[] = {10, 12, 4, 6, 5, 7, 3};
  CHECK(stop_round(oscillating, 7, 10) == 5);
  /* the rounds allowed */
  const uint64_t slow[] = {9, 8, 7, 6, 5};
  CHECK(stop_round(slow, 5, 3) == 3);
  CHECK(stop_round(slow, 5, 0) == 0);
}

static char last_msg[2048];
static void keep_msg(void *user, int level, const char *text) {
  (void)user;
  if (level == MX_MSG_ERROR) snprintf(last_msg, sizeof last_msg, "%s", text);
}

/* A cube [c - h, c + h]^3 as 8 points and 12 outward triangles. */
static void cube_arrays(double c, double h, double xyz[24], uint32_t tri[36]) {
  static const uint32_t t[36] = {0, 2, 1, 1, 2, 3, 4, 5, 6, 5, 7, 6, 0, 1, 4, 1, 5, 4,
                                 2, 6, 3, 3, 6, 7, 0, 4, 2, 2, 4, 6, 1, 3, 5, 3, 7, 5};
  for (int i = 0; i < 8; i++)
    for (int a = 0; a < 3; a++) xyz[3 * i + a] = c + ((i >> a) & 1 ? h : -h);
  memcpy(tri, t, sizeof t);
}

static mx_mesher *cubes_mesher(int ncubes, const char *const *names) {
  mx_params p;
  mx_params_default(&p);
  p.surface_level = 4;
  mx_mesher *m = mx_mesher_new(&p);
  double xyz[24];
  uint32_t tri[36];
  for (int k = 0; k < ncubes; k++) {
    cube_arrays(0.013 + 3.0 * k, 0.7, xyz, tri);
    CHECK(mx_mesher_add_surface_arrays(m, names[k], 8, xyz, 12, tri) == MX_OK);
  }
  CHECK(mx_mesher_mesh(m) == MX_OK);
  return m;
}

static int starts_with(const char *s, const char *prefix) {
  return strncmp(s, prefix, strlen(prefix)) == 0;
}

/* Every verdict that exits 5 (MX_EINVALID) names the input, or "the inputs
 * a, b": invalid elements left, contacts left, the volume rule. The states
 * are set by hand on a valid mesh (the meshes that end so are rare, the
 * triple torus of tests/repair_test.sh one of them). */
static void test_invalid_messages(void) {
  const char *one[] = {"box_a.off"};
  const char *two[] = {"box_a.off", "box_b.stl"};
  mx_message_fn fn = mx_msg_fn;
  void *user = mx_msg_user;
  mx_msg_fn = keep_msg;
  mx_msg_user = NULL;
  char buf[MX_INPUTS_LABEL];

  mx_mesher *m = cubes_mesher(1, one);
  CHECK(m->M.ncells > 0 && m->M.invalid == 0);
  CHECK(strcmp(mx_inputs_label(m, buf, sizeof buf), "box_a.off") == 0);
  m->M.invalid = 3;
  last_msg[0] = '\0';
  CHECK(mx_mesh_finish(m) == MX_EINVALID);
  CHECK(starts_with(last_msg, "box_a.off: 3 element(s) with J_ENS < 1e-6 remain"));
  m->M.invalid = 0;
  m->rec->S.contacts.nodes = 2;
  last_msg[0] = '\0';
  CHECK(mx_mesh_finish(m) == MX_EINVALID);
  CHECK(starts_with(last_msg, "box_a.off: 2 node(s) lie on a face or an edge"));
  m->rec->S.contacts.nodes = 0;
  CHECK(mx_mesh_finish(m) == MX_OK);
  last_msg[0] = '\0';
  CHECK(mx_volume_verdict(m, 0.5 * mx_mesh_volume(&m->M), m->M.ncells) == MX_EINVALID);
  CHECK(starts_with(last_msg, "box_a.off: the mesh holds "));
  CHECK(strstr(last_msg, "% of the volume the input encloses") != NULL);
  mx_mesher_free(m);

  m = cubes_mesher(2, two);
  CHECK(strcmp(mx_inputs_label(m, buf, sizeof buf), "the inputs box_a.off, box_b.stl") == 0);
  m->M.invalid = 1;
  last_msg[0] = '\0';
  CHECK(mx_mesh_finish(m) == MX_EINVALID);
  CHECK(starts_with(last_msg, "the inputs box_a.off, box_b.stl: 1 element(s) with J_ENS"));
  m->M.invalid = 0;
  m->rec->S.contacts.nodes = 1;
  last_msg[0] = '\0';
  CHECK(mx_mesh_finish(m) == MX_EINVALID);
  CHECK(starts_with(last_msg, "the inputs box_a.off, box_b.stl: 1 node(s) lie on a face"));
  /* a label that would not fit is cut after a whole name */
  char small[30];
  CHECK(strcmp(mx_inputs_label(m, small, sizeof small), "the inputs box_a.off, ...") == 0);
  mx_mesher_free(m);

  mx_msg_fn = fn;
  mx_msg_user = user;
}

int main(void) {
  test_repair_rule();
  test_invalid_messages();
  if (!find_data()) {
    TEST_DATA_MISSING("../shared/data not found (the repair rule and messages were tested)");
    return mx_test_failures ? TEST_DONE() : 77;
  }
  mx_quiet = 1;
  mkdir(OUT, 0755);
  test_list_vs_scratch();
  test_full_equals_scratch();
  test_local_vs_full();
  test_choice();
  test_repeated();
  test_restart_round_trip("oct");
  test_restart_round_trip("octb");
  test_published();
  test_bad();
  return TEST_DONE();
}
