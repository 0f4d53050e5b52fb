/* mixoct: from closed surfaces and refinement requests to a mesh:
 * read -> grid -> refine/balance -> transition -> boundary (with repair of
 * invalid elements by one more refinement) -> quality -> write; --stage
 * stops earlier. Exit codes: 0 success, 1 internal failure,
 * 2 bad input or usage. */
#include "cli/cli.h"
#include "cli/progress.h"
#include "common.h"
#include "io/boundary_faces.h"
#include "kernels/boundary_stage.h"
#include "kernels/estimate.h"
#include "kernels/grid.h"
#include "kernels/refine.h"
#include "kernels/transition.h"
#include "soa/mesh.h"
#include "soa/regions.h"
#include "soa/trisoup.h"

#include <limits.h>
#include <malloc.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

/* Read one surface and check it; appends it to `all` as a new shell. */
static int read_one(const char *path, mx_trisoup *all) {
  mx_trisoup s;
  memset(&s, 0, sizeof s);
  int st = mx_read_surface(path, &s);
  if (!st) st = mx_trisoup_check(&s, path, NULL);
  if (!st) st = mx_trisoup_append(all, &s);
  mx_trisoup_free(&s);
  return st;
}

static int read_inputs(const mx_options *o, mx_trisoup *all,
                       uint32_t *nt_domain, uint32_t *region_t0,
                       mx_box_region **boxes, size_t *nboxes) {
  if (o->demo) {
    mx_trisoup s;
    memset(&s, 0, sizeof s);
    int st = mx_demo_surface(&s, 4);
    if (!st) st = mx_trisoup_append(all, &s);
    mx_trisoup_free(&s);
    MX_CHECK(st);
  }
  for (int i = 0; i < o->ninputs; i++) MX_CHECK(read_one(o->inputs[i], all));
  *nt_domain = (uint32_t)all->nt;
  {
    const char *names[MX_MAX_INPUTS + 1];
    int n = 0;
    if (o->demo) names[n++] = "--demo";
    for (int i = 0; i < o->ninputs; i++) names[n++] = o->inputs[i];
    MX_CHECK(mx_trisoup_check_shells(all, *nt_domain, names));
  }
  for (int r = 0; r < o->nregion_surf; r++) {
    region_t0[r] = (uint32_t)all->nt;
    MX_CHECK(read_one(o->region_surf[r], all));
  }
  region_t0[o->nregion_surf] = (uint32_t)all->nt;
  if (o->regions_file) MX_CHECK(mx_read_reg(o->regions_file, boxes, nboxes));
  return MX_OK;
}

static int write_octree(const mx_builder *B, uint32_t *leaves, size_t n,
                        const char *path, int ascii, size_t *nnodes) {
  MX_CHECK(mx_leaves_sorted(B, leaves, n));
  mx_hexmesh h;
  MX_CHECK(mx_leaf_hex_mesh(B, leaves, n, &h));
  *nnodes = h.nnodes;
  int st = MX_OK;
  if (path) {
    uint8_t *type = mx_alloc(n + 1);
    if (!type) {
      mx_hexmesh_free(&h);
      return MX_EINPUT;
    }
    memset(type, MX_HEX, n);
    mx_field level = {"level", 0, h.level, NULL};
    mx_mesh_view v = {h.nnodes, h.xyz, n, type, h.conn, 1, &level, 0, NULL};
    st = mx_write_mesh(path, &v, ascii);
    mx_free(type);
  }
  mx_hexmesh_free(&h);
  return st;
}

/* Cell data type, level, jens; point data "boundary": 1 for the nodes on
 * the boundary (the surface nodes of the boundary stage when it ran, else
 * the nodes of the faces used by one element). */
static int write_mixed(const mx_mesh_out *M, const uint8_t *states, const char *path,
                       int ascii) {
  int32_t *type = mx_alloc((M->ncells + 1) * sizeof *type);
  int32_t *bnd = mx_alloc((M->nnodes + 1) * sizeof *bnd);
  if (!type || !bnd) {
    mx_free(type);
    mx_free(bnd);
    return MX_EINPUT;
  }
#pragma omp parallel for schedule(static)
  for (size_t i = 0; i < M->ncells; i++) type[i] = M->type[i];
  mx_field f[3] = {{"type", 0, type, NULL},
                   {"level", 0, M->level, NULL},
                   {"jens", 1, NULL, M->jens}};
  mx_field pf[1] = {{"boundary", 0, bnd, NULL}};
  mx_mesh_view v = {M->nnodes, M->xyz, M->ncells, M->type, M->conn, 3, f, 1, pf};
  int st = MX_OK;
  if (states) {
#pragma omp parallel for schedule(static)
    for (size_t i = 0; i < M->nnodes; i++) bnd[i] = states[i] == MX_NODE_OUTSIDE;
  } else {
    st = mx_boundary_node_flags(&v, bnd);
  }
  if (!st) st = mx_write_mesh(path, &v, ascii);
  mx_free(type);
  mx_free(bnd);
  return st;
}

/* Refuse a run that cannot fit: the estimate (kernels/estimate.h) against
 * --max-memory, or else the memory available now. */
static int check_memory(const mx_options *o, const mx_trisoup *all,
                        uint32_t nt_domain, const uint32_t *region_t0,
                        const mx_requests *req, const mx_grid *g,
                        mx_summary *S) {
  const double need = mx_estimate_bytes(all, nt_domain, region_t0, req, g,
                                        o->stage);
  S->memory_estimate_mb = need / 1048576.0;
  const double avail = mx_available_bytes();
  const double limit = o->max_memory_mb > 0 ? o->max_memory_mb * 1048576.0 : avail;
  if (limit > 0.0 && need > limit) {
    mx_error(NULL, 0, "this run needs about %.0f MB (estimated from the surface "
                      "and the requested levels) but %s %.0f MB: lower the "
                      "levels or raise --max-memory", need / 1048576.0,
             o->max_memory_mb > 0 ? "--max-memory allows" : "the machine has",
             limit / 1048576.0);
    return MX_EINPUT;
  }
  return MX_OK;
}

/* Boxes asking one more split of the leaves holding invalid elements (the
 * repair of the 2021 paper: refine once, mesh again). A box strictly inside
 * a leaf at the leaf's level + 1 splits that leaf and nothing else. */
static int repair_boxes(const mx_builder *B, const uint32_t *leaves, const mx_mesh_out *M,
                        mx_box_region **extra, size_t *nextra) {
  size_t n = *nextra;
  for (size_t c = 0; c < M->ncells; c++) {
    if (M->jens[c] > 0.0) continue;
    const uint32_t o = leaves[M->leaf[c]];
    const int lv = B->oct.level[o];
    if (lv + 1 > MX_MAX_LEVEL - 1) continue;
    double lo[3], hi[3];
    mx_octant_box(&B->grid, B->oct.key[o], lv, lo, hi);
    mx_box_region r;
    for (int a = 0; a < 3; a++) {
      const double q = 0.25 * (hi[a] - lo[a]);
      r.lo[a] = lo[a] + q;
      r.hi[a] = hi[a] - q;
    }
    r.level = lv + 1;
    int seen = 0;
    for (size_t k = *nextra; k < n && !seen; k++)
      seen = !memcmp((*extra)[k].lo, r.lo, sizeof r.lo) && (*extra)[k].level == r.level;
    if (seen) continue;
    mx_box_region *g = mx_realloc(*extra, (n + 1) * sizeof *g);
    if (!g) return MX_EINPUT;
    *extra = g;
    g[n++] = r;
  }
  *nextra = n;
  return MX_OK;
}

enum { MAX_REPAIR_ROUNDS = 3 };

int mx_run(const mx_options *o) {
  const double t_start = mx_wtime();
  mx_summary S;
  memset(&S, 0, sizeof S);
  mx_trisoup all;
  memset(&all, 0, sizeof all);
  uint32_t nt_domain = 0, region_t0[MX_MAX_REGIONS + 1];
  mx_box_region *boxes = NULL, *extra = NULL;
  size_t nboxes = 0, nextra = 0;
  mx_builder B;
  memset(&B, 0, sizeof B);
  uint32_t *leaves = NULL;
  size_t nleaves = 0;
  mx_surface_index SI;
  memset(&SI, 0, sizeof SI);
  int have_index = 0;

  mx_progress_start(!o->quiet && !o->json, o->stage, o->output != NULL);
  mx_progress_stage("read");
  int st = read_inputs(o, &all, &nt_domain, region_t0, &boxes, &nboxes);
  double t = mx_wtime();
  S.ph.read = t - t_start;
  if (!st && o->stage == MX_STAGE_FULL) {
    mx_progress_stage("index");
    st = mx_surface_index_build(&SI, &all, 0, nt_domain);
    have_index = !st;
  }
  S.ph.boundary = mx_wtime() - t;
  for (int round = 0; !st; round++) {
    t = mx_wtime();
    mx_progress_round(round);
    mx_progress_stage("grid");
    /* the requested boxes, then the repair boxes of earlier rounds */
    mx_box_region *req_boxes = NULL;
    if (nboxes + nextra) {
      req_boxes = mx_alloc((nboxes + nextra) * sizeof *req_boxes);
      if (!req_boxes) {
        st = MX_EINPUT;
        break;
      }
      if (nboxes) memcpy(req_boxes, boxes, nboxes * sizeof *boxes);
      if (nextra) memcpy(req_boxes + nboxes, extra, nextra * sizeof *extra);
    }
    mx_requests req = o->req;
    req.boxes = req_boxes;
    req.nboxes = nboxes + nextra;
    st = mx_builder_init(&B, &all, nt_domain, region_t0, &req,
                         o->balance == MX_BALANCE_EDGES);
    B.on_level = mx_progress_on_level; /* NULL user data */
    if (!st && round == 0) st = check_memory(o, &all, nt_domain, region_t0, &req, &B.grid, &S);
    if (!st) st = mx_build_roots(&B);
    S.ph.grid += mx_wtime() - t;
    if (!st) {
      mx_progress_stage("refine");
      if (o->balance == MX_BALANCE_EDGES) {
        st = mx_refine_balanced(&B);
      } else {
        st = mx_refine_unbalanced(&B);
        if (!st) mx_progress_stage("balance");
        if (!st) st = mx_balance_recursive(&B);
      }
      S.ph.refine += B.stats.t_refine;
      S.ph.balance += B.stats.t_balance;
    }
    S.max_level = mx_max_requested_level(&req); /* B.req.boxes is freed next */
    mx_free(req_boxes);
    if (!st) st = mx_leaves(&B, &leaves, &nleaves);
    if (!st && o->stage == MX_STAGE_OCTREE && o->output) {
      /* The leaves' corners are numbered only for a file: a dry run stops at
       * the leaves. */
      t = mx_wtime();
      mx_progress_stage("write");
      st = write_octree(&B, leaves, nleaves, o->output, o->ascii, &S.nodes);
      for (int k = 1; !st && k < o->noutputs; k++)
        st = write_octree(&B, leaves, nleaves, o->outputs[k], o->ascii, &S.nodes);
      S.nodes_counted = 1;
      S.ph.write = mx_wtime() - t;
    }
    if (!st && o->stage != MX_STAGE_OCTREE) {
      t = mx_wtime();
      mx_progress_stage("transition");
      mx_mesh_out M;
      memset(&M, 0, sizeof M);
      uint8_t *states = NULL; /* per node, from the boundary stage */
      st = mx_leaves_sorted(&B, leaves, nleaves);
      if (!st) st = mx_transition(&B, leaves, nleaves, &M);
      S.ph.transition += mx_wtime() - t;
      if (!st && o->stage == MX_STAGE_FULL) {
        t = mx_wtime();
        mx_progress_stage("boundary");
        mx_boundary_stats bs;
        st = mx_boundary_stage(&B, leaves, &SI, &M, MX_CLOSE_RATIO, 0.2, &bs, &states);
        S.ph.boundary += mx_wtime() - t;
        S.boundary = bs;
        S.full = 1;
        if (!st && M.invalid > 0 && round < MAX_REPAIR_ROUNDS) {
          /* Repair: refine the leaves of the invalid elements once, mesh
           * again from the start. */
          const size_t before = nextra;
          st = repair_boxes(&B, leaves, &M, &extra, &nextra);
          if (!st && nextra > before) {
            S.repaired += M.invalid;
            S.repair_rounds++;
            mx_free(states);
            mx_mesh_out_free(&M);
            mx_free(leaves);
            leaves = NULL;
            mx_builder_free(&B);
            memset(&B, 0, sizeof B);
            continue;
          }
        }
      }
      if (!st) {
        S.nodes = M.nnodes;
        S.nodes_counted = 1;
        S.elements = M.ncells;
        memcpy(S.by_type, M.by_type, sizeof S.by_type);
        S.jens_min = M.jens_min;
        S.invalid = M.invalid;
        S.closures = M.closures;
        t = mx_wtime();
        mx_progress_stage("quality");
        mx_quality_tabulate(M.type, M.jens, M.ncells, &S.quality);
        S.ph.quality = mx_wtime() - t;
        S.centre_leaves = M.centre_leaves;
        S.mesh = 1;
        if (S.invalid)
          mx_warning(NULL, 0, "%zu element(s) with J_ENS <= 0 remain after %d repair "
                              "round(s)", S.invalid, S.repair_rounds);
        if (o->output) {
          t = mx_wtime();
          mx_progress_stage("write");
          st = write_mixed(&M, states, o->output, o->ascii);
          for (int k = 1; !st && k < o->noutputs; k++)
            st = write_mixed(&M, states, o->outputs[k], o->ascii);
          S.ph.write = mx_wtime() - t;
        }
      }
      mx_free(states);
      mx_mesh_out_free(&M);
    }
    break;
  }
  if (!st) {
    S.leaves = nleaves;
    S.leaves_hash = mx_leaves_hash(&B, leaves, nleaves);
    S.octants = B.oct.n;
    S.edges = mx_edges_total(&B.edges);
    S.edge_bytes = mx_edges_bytes(&B.edges);
    S.located = B.stats.located;
    S.split_requested = B.stats.split_requested;
    S.split_balance = B.stats.split_balance;
    S.dropped = B.stats.dropped;
    S.threads = omp_get_max_threads();
    S.balance = o->balance;
    S.ph.total = mx_wtime() - t_start;
    S.peak_rss_mb = mx_peak_rss_mb();
    mx_progress_done(); /* before the summary, on the same terminal */
    if (!o->quiet && !o->json) mx_print_summary(&S);
    if (o->json) mx_print_json(&S);
  }
  if (have_index) mx_surface_index_free(&SI);
  mx_free(leaves);
  mx_builder_free(&B);
  mx_free(boxes);
  mx_free(extra);
  mx_trisoup_free(&all);
  mx_progress_done();
  return st;
}

int main(int argc, char **argv) {
  if (argc >= 2 && strcmp(argv[1], "check") == 0)
    return mx_check_main(argc - 1, argv + 1);
  if (argc >= 2 && strcmp(argv[1], "patterns") == 0)
    return mx_patterns_main(argc - 1, argv + 1);
  if (!getenv("MX_NO_MALLOPT")) {
    /* The passes allocate and free arrays of hundreds of MB; served from
     * the heap and kept there, freed pages are reused instead of being
     * mapped and faulted in again for every pass. */
    mallopt(M_MMAP_MAX, 0);
    mallopt(M_TRIM_THRESHOLD, INT_MAX);
  }
  const char *base = strrchr(argv[0], '/');
  if (strcmp(base ? base + 1 : argv[0], "mesher_roi") == 0)
    return mx_mesher_roi_main(argc, argv);
  mx_options o;
  int exit_now = 0;
  int st = mx_parse_options(argc, argv, &o, &exit_now);
  if (st) return MX_EINPUT;
  if (exit_now) return 0;
  if (o.quiet) mx_quiet = 1;
  if (o.threads > 0) omp_set_num_threads(o.threads);
  st = mx_run(&o);
  return st == MX_OK ? 0 : st;
}
