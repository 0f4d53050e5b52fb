/* Each rank meshes its patch: its leaves and rings of ghost leaves
 * (src/mpi/p4est_mesh.h). The shared nodes' agreement and numbering are in
 * p4est_nodes.c. */
#include "mpi/p4est_mesh.h"

#include "base/common.h"
#include "kernels/boundary_stage.h"
#include "kernels/contacts.h"
#include "kernels/estimate.h"
#include "kernels/mesh_edit.h"
#include "geom/quality.h"
#include "kernels/closures.h"
#include "kernels/edges_lazy.h"
#include "kernels/refine_list.h"
#include "kernels/splice.h"
#include "mesher/materials.h"
#include "mesher/mesher_impl.h"
#include "mesher/pipeline.h"
#include "mpi/exchange.h"
#include "mpi/p4est_halo.h"
#include "mpi/p4est_nodes.h"
#include "mpi/p4est_tree.h"
#include "base/scan.h"

#include <inttypes.h>
#include <stdlib.h>
#include <string.h>

#include <p8est_ghost.h>

/* Halo rings of the attempts. On the cortex on 2 ranks, the shared nodes
 * that differ with 1, 2, 3, 4, 5 rings at level 8: 146, 52, 22, 2, 0; with
 * 5, 6 rings at level 9: 6, 0 (the untangling and smoothing reach
 * furthest). The halo grows faster than the rings (a Morton part's surface
 * is ragged): at level 9, 6 rings add 11-17% to each rank's leaves, 10
 * rings 57-67%; so the attempts grow slowly.
 * MX_P4EST_FIRST_RINGS (environment) sets the first attempt's, for the
 * tests. */
static const int attempt_rings[] = {6, 8, 12};
#define NATTEMPTS ((int)(sizeof attempt_rings / sizeof *attempt_rings))

/* The requests of m cleared: the patch's octree is made from its leaves
 * alone. */
static void clear_requests(mx_mesher *m) {
  m->p.surface_level = -1;
  m->p.all_level = -1;
  m->nboxes = 0;
  for (int r = 0; r < m->nregions; r++) m->region_level[r] = -1;
}

/* The patch's octree rebuilt by refinement (the split set of its leaves'
 * ancestors, as before issue 31), compared with the patch's leaves and
 * their data: every leaf there at its level, with the same surface flag,
 * regions and triangle list (in the same order). The tests' check of
 * p4est_tree.c (MX_P4EST_CHECK_TREE=1); *checked: leaves compared. */
static int check_tree(mx_mesher *m, const mx_patch_leaves *S, size_t *checked) {
  MX_CHECK(mx_mesher_set_split_keys(m, S->key, S->level, S->n));
  MX_CHECK(mx_build_tree(m));
  const mx_octree *T = &m->B.tree.oct;
  size_t np = 0, wrong = 0, first = SIZE_MAX;
  for (size_t i = 0; i < m->nleaves; i++) {
    const uint32_t o = m->leaves[i];
    const uint32_t j = mx_find_u64(S->key, S->n, T->key[o]);
    if (j == UINT32_MAX) continue;
    np++;
    const mx_pq *d = &S->pq[j];
    int bad = S->level[j] != T->level[o] ||
              ((T->flags[o] & MX_OCT_SURFACE) != 0) != ((d->flags & MX_PQ_SURFACE) != 0) ||
              T->rmeet[o] != d->rmeet || T->rin[o] != d->rin || T->tri_cnt[o] != d->tri_cnt;
    if (!bad)
      bad = memcmp(T->tri_pool + T->tri_off[o], S->tri + d->tri_off,
                   (size_t)d->tri_cnt * sizeof *S->tri) != 0;
    if (bad) {
      wrong++;
      if (j < first) first = j;
    }
  }
  mx_tree_clear(m);
  for (int l = 0; l <= MX_MAX_LEVEL; l++) {
    mx_free(m->split_keys[l]);
    m->split_keys[l] = NULL;
    m->nsplit[l] = 0;
  }
  if (wrong || np != S->n) {
    mx_error(NULL, 0, "internal: the octree refined from the %zu leaves of a rank's patch "
                      "holds %zu of them, %zu with other data than the patch's (the first: "
                      "key %llu level %d)", S->n, np, wrong,
             first == SIZE_MAX ? 0ull : (unsigned long long)S->key[first],
             first == SIZE_MAX ? -1 : S->level[first]);
    return MX_EINTERNAL;
  }
  *checked = np;
  return MX_OK;
}

/* The octree of m made from the patch's leaves (p4est_tree.h); pl[np]
 * receives the patch's leaves among its leaves (Morton order: all of
 * them), powner their owners. */
static int patch_tree(mx_mesher *m, const mx_patch_leaves *S, uint32_t **pl, int32_t **powner,
                      size_t *checked) {
  clear_requests(m);
  if (getenv("MX_P4EST_CHECK_TREE")) MX_CHECK(check_tree(m, S, checked));
  MX_CHECK(mx_patch_tree_build(m, S));
  *pl = mx_alloc((S->n + 1) * sizeof **pl);
  *powner = mx_alloc((S->n + 1) * sizeof **powner);
  if (!*pl || !*powner) return MX_ENOMEM;
  if (m->nleaves != S->n) return MX_EINTERNAL;
  memcpy(*pl, m->leaves, S->n * sizeof **pl);
  memcpy(*powner, S->owner, S->n * sizeof **powner);
  return MX_OK;
}

/* The keys of this rank's leaves holding an element with a defect (not
 * those as fine as the lattice allows), sorted, in D. */
static int defect_leaves(const mx_mesher *m, const uint32_t *pl, const mx_mesh *M,
                         const uint8_t *core, const uint8_t *flag, mx_p4est_mesh *D) {
  mx_free(D->defect_key);
  D->defect_key = NULL;
  D->ndefect = 0;
  if (!D->invalid && !D->contact_cells) return MX_OK;
  uint64_t *k = mx_alloc((D->invalid + D->contact_cells + 1) * sizeof *k);
  if (!k) return MX_ENOMEM;
  size_t n = 0;
  for (size_t c = 0; c < M->ncells; c++) {
    if (!core[c] || (!mx_jens_invalid(M->jens[c]) && !flag[c])) continue;
    const uint32_t o = pl[M->leaf[c]];
    if (m->B.tree.oct.level[o] < MX_MAX_LEVEL - 1) k[n++] = m->B.tree.oct.key[o];
  }
  int st = MX_OK;
  D->ndefect = mx_sort_unique_u64(k, n, &st);
  D->defect_key = k;
  return st;
}

/* One attempt: the patch meshed, the core's elements kept in D (with the
 * shared-node records for p4est_nodes.c). */
static int mesh_patch(mx_p4est_octree *P, const mx_halo *H, mx_mesher *m, mx_p4est_mesh *D,
                      mx_shared *sh) {
  mx_patch_leaves s;
  double t = mx_wtime();
  int st = mx_patch_leaves_get(P, H, MX_OK, &s, &D->sent_bytes, &D->largest_message);
  D->t_halo += mx_wtime() - t;
  uint32_t *pl = NULL;
  int32_t *powner = NULL;
  t = mx_wtime();
  if (!st) st = patch_tree(m, &s, &pl, &powner, &D->tree_checked);
  D->t_tree += mx_wtime() - t;
  D->core_leaves = s.ncore;
  D->patch_leaves = s.n;
  D->tree_leaves = m->nleaves;
  const size_t np = s.n;
  mx_patch_leaves_free(&s);
  mx_mesh M;
  memset(&M, 0, sizeof M);
  uint8_t *states = NULL;
  t = mx_wtime();
  /* nothing reads the edge infos after the masks: their memory goes to the
   * mesh, as in the single-process program */
  if (!st) st = mx_pipeline_transition(m, pl, np, 1, &M);
  D->t_transition += mx_wtime() - t;
  t = mx_wtime();
  mx_boundary_stats bs;
  if (!st) st = mx_pipeline_boundary(m, pl, np, &M, 0, &states, &bs);
  /* defects of the core's elements, seen with their neighbours */
  uint8_t *flag = NULL, *core = NULL;
  if (!st) {
    flag = mx_alloc(M.ncells + 1);
    core = mx_alloc(M.ncells + 1);
    if (!flag || !core) st = MX_ENOMEM;
  }
  mx_contacts ct;
  if (!st) st = mx_find_contacts(&M, &m->B.tree.grid, states, flag, &ct);
  size_t invalid = 0, contact = 0;
  if (!st) {
#pragma omp parallel for schedule(static) reduction(+ : invalid, contact)
    for (size_t c = 0; c < M.ncells; c++) {
      core[c] = powner[M.leaf[c]] == P->rank;
      invalid += core[c] && mx_jens_invalid(M.jens[c]);
      contact += core[c] && flag[c];
    }
    D->worst_jens = 2.0f;
    D->worst_key = UINT64_MAX;
    for (size_t c = 0; c < M.ncells; c++) {
      if (!core[c]) continue;
      const uint64_t k = m->B.tree.oct.key[pl[M.leaf[c]]];
      if (M.jens[c] < D->worst_jens || (M.jens[c] == D->worst_jens && k < D->worst_key)) {
        D->worst_jens = M.jens[c];
        D->worst_key = k;
      }
    }
    D->invalid = invalid;
    D->contact_cells = contact;
    st = defect_leaves(m, pl, &M, core, flag, D);
  }
  if (!st) st = mx_shared_collect(&M, states, core, powner, P->rank, sh);
  if (!st) st = mx_mesh_keep_cells(&M, core);
  if (!st) st = mx_mesh_renumber_first_use(&M, &states);
  /* the core's materials by region, numbered once every rank's are known
   * (reduce_figures) */
  int deepest = 0;
  size_t across = 0;
  if (!st && m->p.materials)
    st = mx_material_depths(m, &M, pl, np, states, MX_STAGE_FULL, &deepest, &across, NULL);
  D->nmaterials = deepest;
  D->across = across;
  D->t_boundary += mx_wtime() - t;
  mx_free(flag);
  mx_free(core);
  mx_free(pl);
  mx_free(powner);
  mx_tree_clear(m); /* the patch's octree: rebuilt by the next attempt */
  if (st) {
    mx_mesh_free(&M);
    mx_free(states);
    return st;
  }
  mx_mesh_summarize(&M);
  mx_mesh_free(&D->M);
  mx_free(D->states);
  D->M = M;
  D->states = states;
  return MX_OK;
}

/* Global counts, quality, defects and volume. */
static void reduce_figures(const mx_p4est_octree *P, mx_p4est_mesh *D) {
  uint64_t loc[10] = {D->nowned, D->M.ncells, D->M.by_type[0], D->M.by_type[1],
                      D->M.by_type[2], D->M.by_type[3], D->invalid, D->contact_cells,
                      D->core_leaves, D->tree_checked},
           glob[10];
  MPI_Allreduce(loc, glob, 10, MPI_UINT64_T, MPI_SUM, P->comm);
  D->tree_checked = glob[9];
  D->nodes = glob[0];
  D->cells = glob[1];
  for (int k = 0; k < 4; k++) D->by_type[k] = glob[2 + k];
  D->invalid = glob[6];
  D->contact_cells = glob[7];
  D->leaves = glob[8];
  double jmin = D->M.ncells ? D->M.jens_min : 2.0, vol = mx_mesh_volume(&D->M);
  MPI_Allreduce(&jmin, &D->jens_min, 1, MPI_DOUBLE, MPI_MIN, P->comm);
  MPI_Allreduce(&vol, &D->volume, 1, MPI_DOUBLE, MPI_SUM, P->comm);
}

/* Several materials: per region its elements and volume, summed over the
 * ranks, the deepest region and the elements across an interface; then
 * each element's number (the user's, mx_material_relabel), the same
 * numbering on every rank. Collective; the same status everywhere. */
static int reduce_materials(const mx_p4est_octree *P, mx_mesher *m, mx_p4est_mesh *D) {
  const mx_mesh *M = &D->M;
  uint64_t cells[65] = {0};
  double vol[65] = {0};
  for (size_t c = 0; c < M->ncells; c++) {
    const int d = M->material[c] <= 64 ? M->material[c] : 0;
    double p[8][3];
    const int nv = mx_cell_nodes[M->type[c]];
    for (int k = 0; k < nv; k++) memcpy(p[k], M->xyz + 3 * (size_t)M->conn[8 * c + k], sizeof p[k]);
    cells[d]++;
    vol[d] += mx_element_volume(M->type[c], (const double(*)[3])p);
  }
  MPI_Allreduce(cells, D->material_cells, 65, MPI_UINT64_T, MPI_SUM, P->comm);
  MPI_Allreduce(vol, D->material_volume, 65, MPI_DOUBLE, MPI_SUM, P->comm);
  int deepest = 0;
  MPI_Allreduce(&D->nmaterials, &deepest, 1, MPI_INT, MPI_MAX, P->comm);
  D->nmaterials = deepest;
  uint64_t across = D->across;
  MPI_Allreduce(&across, &D->across, 1, MPI_UINT64_T, MPI_SUM, P->comm);
  int st = mx_mpi_agree(P->comm, mx_material_relabel(m, &D->M, deepest));
  for (int d = 1; !st && d <= deepest && d <= 64; d++) {
    D->material_id[d] = m->depth_material[d];
    st = mx_material_name(m, d, D->material_name[d], sizeof D->material_name[d]);
  }
  return st;
}

/* Memory: the patch's octree and mesh estimated from its leaves as the
 * single-process mesher estimates them (kernels/estimate.h), plus the
 * forest kept beside them (on the cortex, 1.04-1.09 of the peak per rank at
 * levels 8 and 9 on 1 and 2 ranks), summed over
 * the ranks sharing a machine and compared with what the machine has
 * available (or each rank's against --max-memory). Collective. */
static int check_memory(const mx_p4est_octree *P, const mx_mesher *m, const mx_halo *H,
                        mx_p4est_mesh *D) {
  const double need =
      mx_estimate_bytes_leaves(H->nlocal + H->n, m->soup.nt ? m->soup.nt : m->domain.nt,
                               MX_STAGE_FULL) +
      90.0 * (double)(H->nlocal + H->n) + /* the edge infos, until the masks */
      64.0 * (double)P->p8->local_num_quadrants; /* the forest: quadrant and its data */
  D->estimate_mb = need / 1048576.0;
  MPI_Comm node;
  MPI_Comm_split_type(P->comm, MPI_COMM_TYPE_SHARED, P->rank, MPI_INFO_NULL, &node);
  double on_node = 0.0;
  MPI_Allreduce(&need, &on_node, 1, MPI_DOUBLE, MPI_SUM, node);
  MPI_Comm_free(&node);
  const int per_rank = m->p.max_memory_mb > 0;
  const double limit = per_rank ? m->p.max_memory_mb * 1048576.0
                                : mx_available_bytes() + mx_peak_rss_mb() * 1048576.0;
  /* the worst rank (per rank) or machine, its figures to every rank */
  struct {
    double ratio;
    int rank;
  } mine = {limit > 0.0 ? (per_rank ? need : on_node) / limit : 0.0, P->rank}, worst;
  MPI_Allreduce(&mine, &worst, 1, MPI_DOUBLE_INT, MPI_MAXLOC, P->comm);
  if (worst.ratio <= 1.0) return MX_OK;
  double f[5] = {need, on_node, limit, (double)H->nlocal, (double)H->n};
  MPI_Bcast(f, 5, MPI_DOUBLE, worst.rank, P->comm);
  if (per_rank)
    mx_error(NULL, 0, "rank %d needs about %.0f MB for its %.0f leaves and %.0f halo leaves "
             "but --max-memory allows %.0f MB: use more ranks or lower the levels",
             worst.rank, f[0] / 1048576.0, f[3], f[4], f[2] / 1048576.0);
  else
    mx_error(NULL, 0, "the ranks on the machine of rank %d need about %.0f MB together (rank "
             "%d: %.0f MB for %.0f leaves and %.0f halo leaves) but it has %.0f MB: use more "
             "machines or lower the levels", worst.rank, f[1] / 1048576.0, worst.rank,
             f[0] / 1048576.0, f[3], f[4], f[2] / 1048576.0);
  return MX_ENOMEM;
}

static int mesh_once(mx_p4est_octree *P, mx_mesher *m, mx_p4est_mesh *D) {
  /* the tests' way to see a difference caught: fewer rings at first */
  const char *env = getenv("MX_P4EST_FIRST_RINGS");
  const int first_rings = env ? atoi(env) : 0;
  mx_halo H;
  double t = mx_wtime();
  int st = mx_mpi_agree(P->comm, mx_halo_init(P, &H));
  D->t_halo += mx_wtime() - t;
  for (int a = 0; !st && a < NATTEMPTS; a++) {
    t = mx_wtime();
    int want = attempt_rings[a];
    if (a == 0 && first_rings > 0) want = first_rings;
    while (!st && H.rings < want) st = mx_halo_expand(P, &H);
    D->t_halo += mx_wtime() - t;
    if (st) break;
    D->rings = H.rings;
    D->attempts = a + 1;
    st = check_memory(P, m, &H, D);
    if (st) break;
    mx_shared sh;
    memset(&sh, 0, sizeof sh);
    st = mx_mpi_agree(P->comm, mesh_patch(P, &H, m, D, &sh));
    size_t differ = 0;
    t = mx_wtime();
    char inputs[MX_INPUTS_LABEL];
    if (!st)
      st = mx_shared_agree(P, D, &sh, a == NATTEMPTS - 1, mx_inputs_label(m, inputs, sizeof inputs),
                           &differ);
    if (a == 0) D->differ_first = differ;
    if (!st && !differ) st = mx_shared_number(P, D, &sh);
    D->t_exchange += mx_wtime() - t;
    mx_shared_free(&sh);
    if (st || !differ) break;
  }
  D->sent_bytes += H.sent_bytes;
  if (H.largest_message > D->largest_message) D->largest_message = H.largest_message;
  mx_halo_free(&H);
  if (!st) reduce_figures(P, D);
  if (!st && m->p.materials) st = reduce_materials(P, m, D);
  return st;
}

/* MX_P4EST_TEST_REPAIR: the worst element's leaf as the only defect. */
static int force_defect(const mx_p4est_octree *P, mx_p4est_mesh *D) {
  float j = D->worst_jens, jmin = 0;
  MPI_Allreduce(&j, &jmin, 1, MPI_FLOAT, MPI_MIN, P->comm);
  uint64_t k = D->worst_jens == jmin ? D->worst_key : UINT64_MAX, kmin = 0;
  MPI_Allreduce(&k, &kmin, 1, MPI_UINT64_T, MPI_MIN, P->comm);
  mx_free(D->defect_key);
  D->defect_key = mx_alloc(sizeof *D->defect_key);
  if (!D->defect_key) return MX_ENOMEM;
  D->defect_key[0] = kmin;
  D->ndefect = k == kmin && kmin != UINT64_MAX;
  return MX_OK;
}

int mx_p4est_mesh_build(mx_p4est_octree *P, mx_mesher *m, mx_p4est_mesh *D) {
  mx_repair_progress progress = {0, 0, 0};
  const int test_repair = getenv("MX_P4EST_TEST_REPAIR") != NULL;
  for (int round = 0;; round++) {
    MX_CHECK(mesh_once(P, m, D));
    if (round == 0 && test_repair) {
      MX_CHECK(mx_mpi_agree(P->comm, force_defect(P, D)));
    } else if (!mx_repair_go_on(round, D->invalid + D->contact_cells, m->p.repair_rounds,
                                &progress)) {
      break;
    }
    long long n = 0;
    MX_CHECK(mx_p4est_refine_listed(P, D->defect_key, D->ndefect, &n));
    if (n == 0) break;
    D->repair_rounds++;
    D->repaired += n;
  }
  return MX_OK;
}

static int verdict_local(mx_mesher *m, const mx_p4est_mesh *D) {
  char inputs[MX_INPUTS_LABEL];
  const char *name = mx_inputs_label(m, inputs, sizeof inputs);
  if (D->cells == 0) {
    mx_error(name, 0,
             "the mesh is empty: no element lies in the domain (%" PRIu64 " leaves); ask for "
             "finer levels (-s, -a, -b, -r)", D->leaves);
    return MX_EINPUT;
  }
  if (D->invalid) {
    mx_error(name, 0, "%" PRIu64 " element(s) with J_ENS < 1e-6 remain after %d repair "
             "round(s)", D->invalid, D->repair_rounds);
    return MX_EINVALID;
  }
  if (D->contact_cells) {
    mx_error(name, 0, "%" PRIu64 " element(s) where two parts of the boundary meet (a node "
             "on an element it is not a node of: a non-conforming mesh) after %d repair "
             "round(s); ask for finer levels there (-s, -b, -r)", D->contact_cells,
             D->repair_rounds);
    return MX_EINVALID;
  }
  /* as the single-process verdict: an element across an interface is a
   * defect (none after the cleaving unless a node was pulled across) */
  if (D->across) {
    mx_error(name, 0, "%" PRIu64 " element(s) lie across an interface between two "
             "materials", D->across);
    return MX_EINVALID;
  }
  return mx_volume_verdict(m, D->volume, (size_t)D->cells);
}

int mx_p4est_mesh_verdict(const mx_p4est_octree *P, mx_mesher *m, const mx_p4est_mesh *D) {
  return mx_mpi_agree(P->comm, verdict_local(m, D));
}

void mx_p4est_mesh_free(mx_p4est_mesh *D) {
  mx_mesh_free(&D->M);
  mx_free(D->defect_key);
  mx_free(D->states);
  mx_free(D->gid);
  mx_free(D->owned);
  memset(D, 0, sizeof *D);
}
