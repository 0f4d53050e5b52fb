/* `mpirun -n N mixoct -i SURF -s L --p4est [-o OUT.pvtu|.msh] [--json]
 * [--p4est-compare] [--stage octree]`:
 * the distributed octree on p4est (src/mpi/p4est_octree.h), built only
 * with MPI (meson -Dmpi). Every rank reads the inputs and sets up the same
 * builder; rank 0 reports the leaves in the domain, their hash (the one
 * `mixoct --stage octree --json` prints as leaves_hash, over the same
 * set), the slowest rank's seconds per step, and per-rank min/max of
 * leaves, quadrants and peak memory. --p4est-compare: rank 0 also builds
 * the single-process octree and compares the leaves (src/mpi/p4est_compare.h).
 * Then, unless --stage octree, each rank meshes its leaves, the mesh is
 * checked and written (src/cli/p4est_mesh_cmd.c). */
#include "cli/cli.h"
#include "cli/p4est_cli.h"
#include "base/common.h"
#include "mesher/mesher_impl.h"
#include "mpi/exchange.h"
#include "mpi/p4est_compare.h"
#include "mpi/p4est_inputs.h"
#include "mpi/p4est_leaves.h"
#include "mpi/p4est_mesh.h"
#include "mpi/p4est_octree.h"

#include <inttypes.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <p8est.h>

int mx_p4est_main(int argc, char **argv);

static int rank0;

/* Messages: printed once, by rank 0 (every rank runs the same inputs). */
static void on_message(void *user, int level, const char *text) {
  (void)user;
  if (!rank0) return;
  if (level == MX_MSG_ERROR || !mx_quiet)
    fprintf(stderr, "mixoct: %s%s\n", level == MX_MSG_ERROR ? "error: " : "warning: ", text);
}

static int setup(const mx_options *o, mx_mesher **out) {
  mx_params p;
  mx_params_default(&p);
  p.surface_level = o->s_level;
  p.all_level = o->a_level;
  /* the octree, or the mesh (the transition stage alone is not offered) */
  p.stage = o->stage == MX_STAGE_OCTREE ? MX_STAGE_OCTREE : MX_STAGE_FULL;
  p.threads = o->threads;
  p.max_memory_mb = o->max_memory_mb;
  p.repair_input = o->repair_input; /* refused by mx_p4est_inputs_init */
  mx_mesher *m = mx_mesher_new(&p);
  if (!m) return MX_ENOMEM; /* said by mx_alloc */
  *out = m;
  mx_mesher_set_message_handler(m, on_message, NULL);
  return mx_add_inputs(o, m);
}

/* Rank 0: the single-process octree of the same inputs, compared: the
 * leaves in the domain, and why p4est split the single-process leaves it
 * split (every quadrant of the forest gathered). */
static int compare_single(mx_mesher *m, const mx_p4est_octree *P, mx_leaf_diff *d,
                          mx_split_causes *why, uint64_t *hash, double *t_refine,
                          double *t_balance) {
  uint64_t *qa = NULL, *ka = NULL, *kb = NULL;
  uint8_t *qla = NULL, *qin = NULL, *la = NULL, *lb = NULL;
  size_t nq = 0;
  int st = mx_p4est_gather_leaves(P, 0, 1, &qa, &qla, &qin, &nq);
  if (P->rank == 0 && !st) {
    st = mx_mesher_build_octree(m);
    if (!st) {
      const size_t nb = m->nleaves; /* in Morton order */
      kb = mx_alloc((nb + 1) * sizeof *kb);
      lb = mx_alloc(nb + 1);
      ka = mx_alloc((nq + 1) * sizeof *ka);
      la = mx_alloc(nq + 1);
      if (!kb || !lb || !ka || !la) st = MX_ENOMEM;
      for (size_t i = 0; !st && i < nb; i++) {
        kb[i] = m->B.tree.oct.key[m->leaves[i]];
        lb[i] = m->B.tree.oct.level[m->leaves[i]];
      }
      size_t na = 0;
      for (size_t i = 0; !st && i < nq; i++)
        if (qin[i]) {
          ka[na] = qa[i];
          la[na++] = qla[i];
        }
      if (!st) {
        mx_leaf_diff_compute(ka, la, na, kb, lb, nb, d);
        mx_leaf_diff_causes(qa, qla, qin, nq, kb, lb, nb, P->B->tree.grid.dims, why);
      }
      *hash = mx_leaves_hash(&m->B.tree, m->leaves, m->nleaves);
      *t_refine = m->rec->S.ph.refine;
      *t_balance = m->rec->S.ph.balance;
    }
  }
  mx_free(qa);
  mx_free(qla);
  mx_free(qin);
  mx_free(ka);
  mx_free(la);
  mx_free(kb);
  mx_free(lb);
  return mx_mpi_agree(MPI_COMM_WORLD, st);
}

static void print_levels(const size_t *n) {
  int first = 1;
  printf("{");
  for (int l = 0; l <= MX_MAX_LEVEL; l++)
    if (n[l]) {
      printf("%s\"%d\": %zu", first ? "" : ", ", l, n[l]);
      first = 0;
    }
  printf("}");
}

static void report(const mx_options *o, const mx_p4est_octree *P, const mx_p4est_summary *s,
                   double t_setup, double t_total, int threads, int compared,
                   const mx_leaf_diff *d, const mx_split_causes *why,
                   uint64_t single_hash, double st_refine,
                   double st_balance, const mx_p4est_mesh_report *mesh) {
  if (!o->json) {
    printf("p4est octree: %d rank(s) x %d thread(s), levels up to %d\n", P->size, threads,
           P->max_level);
    printf("  leaves in the domain %lld (hash %016" PRIx64 "), quadrants %lld, outside %lld\n",
           s->leaves, s->hash, s->quadrants, s->outside);
    printf("  seconds (slowest rank): setup %.3f refine %.3f balance %.3f partition %.3f "
           "ghost %.3f total %.3f\n",
           t_setup, s->tmax.refine, s->tmax.balance, s->tmax.partition, s->tmax.ghost, t_total);
    printf("  per rank: leaves %lld..%lld, quadrants %lld..%lld, peak memory %.1f..%.1f MB\n",
           s->leaves_min, s->leaves_max, s->quadrants_min, s->quadrants_max, s->rss_min_mb,
           s->rss_max_mb);
    if (compared)
      printf("  single-process: leaves %zu (hash %016" PRIx64 ") %s; only p4est %zu (finer %zu, "
             "coarser %zu), only single %zu (finer %zu, coarser %zu)\n",
             d->n_b, single_hash, d->only_a + d->only_b ? "differ" : "the same", d->only_a,
             d->a_finer, d->a_coarser, d->only_b, d->b_finer, d->b_coarser);
    if (compared && why->split)
      printf("  single-process leaves p4est split: %zu; p4est's balance reached them across "
             "the outside %zu, through such leaves %zu, otherwise %zu (+%zu unexplained)\n",
             why->split, why->by_outside, why->by_chain, why->by_common, why->unexplained);
    if (mesh) mx_p4est_mesh_text(mesh);
    return;
  }
  size_t lv[MX_MAX_LEVEL + 1];
  for (int l = 0; l <= MX_MAX_LEVEL; l++) lv[l] = (size_t)s->per_level[l];
  printf("{\"p4est\": true, \"ranks\": %d, \"threads\": %d, \"max_level\": %d, "
         "\"leaves\": %lld, \"leaves_hash\": \"%016" PRIx64 "\", \"levels\": ",
         P->size, threads, P->max_level, s->leaves, s->hash);
  print_levels(lv);
  printf(", \"quadrants\": %lld, \"outside\": %lld, \"surface_leaves\": %lld, "
         "\"split_requested\": %lld, \"split_balance\": %lld, \"located\": %lld, "
         "\"ghosts\": %lld, \"partitions\": %zu, \"shipped\": %lld, "
         "\"shipped_list_bytes\": %lld, ",
         s->quadrants, s->outside, s->surface, s->split_requested, s->split_balance,
         s->located, s->ghosts, P->partitions, P->shipped, s->list_bytes);
  printf("\"phases\": {\"setup\": %.6f, \"refine\": %.6f, \"balance\": %.6f, "
         "\"partition\": %.6f, \"ghost\": %.6f}, ",
         t_setup, s->tmax.refine, s->tmax.balance, s->tmax.partition, s->tmax.ghost);
  printf("\"per_rank\": {\"leaves\": [%lld, %lld], \"quadrants\": [%lld, %lld], "
         "\"peak_rss_mb\": [%.1f, %.1f], \"refine_s\": [%.6f, %.6f], "
         "\"balance_s\": [%.6f, %.6f], \"partition_s\": [%.6f, %.6f], "
         "\"ghost_s\": [%.6f, %.6f]}, ",
         s->leaves_min, s->leaves_max, s->quadrants_min, s->quadrants_max, s->rss_min_mb,
         s->rss_max_mb, s->tmin.refine, s->tmax.refine, s->tmin.balance, s->tmax.balance,
         s->tmin.partition, s->tmax.partition, s->tmin.ghost, s->tmax.ghost);
  if (compared) {
    printf("\"compare\": {\"single_leaves\": %zu, \"single_hash\": \"%016" PRIx64 "\", "
           "\"equal\": %s, \"common\": %zu, \"only_p4est\": %zu, \"only_single\": %zu, "
           "\"p4est_finer\": %zu, \"p4est_coarser\": %zu, \"p4est_alone\": %zu, "
           "\"single_finer\": %zu, \"single_coarser\": %zu, \"single_alone\": %zu, "
           "\"only_p4est_levels\": ",
           d->n_b, single_hash, d->only_a + d->only_b ? "false" : "true", d->common, d->only_a,
           d->only_b, d->a_finer, d->a_coarser, d->a_alone, d->b_finer, d->b_coarser,
           d->b_alone);
    print_levels(d->only_a_level);
    printf(", \"only_single_levels\": ");
    print_levels(d->only_b_level);
    printf(", \"single_split_by_p4est\": {\"leaves\": %zu, \"by_outside\": %zu, "
           "\"by_chain\": %zu, \"by_common\": %zu, \"unexplained\": %zu}",
           why->split, why->by_outside, why->by_chain, why->by_common, why->unexplained);
    printf(", \"single_phases\": {\"refine\": %.6f, \"balance\": %.6f}}, ", st_refine,
           st_balance);
  }
  if (mesh) mx_p4est_mesh_json(mesh);
  printf("\"valid\": %s, \"total_s\": %.6f, \"peak_rss_mb\": %.1f}\n",
         mesh ? "true" : "null", t_total, mesh ? mesh->rss[1] : s->rss_max_mb);
}

static int run(const mx_options *o, int compare) {
  const double t0 = mx_wtime();
  mx_mesher *m = NULL;
  mx_p4est_inputs I;
  memset(&I, 0, sizeof I);
  int st = setup(o, &m);
  if (!st) st = mx_p4est_inputs_init(&I, m);
  st = mx_mpi_agree(MPI_COMM_WORLD, st);
  double t_setup = mx_wtime() - t0;
  MPI_Allreduce(MPI_IN_PLACE, &t_setup, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
  mx_p4est_octree P;
  memset(&P, 0, sizeof P);
  mx_p4est_summary s;
  mx_leaf_diff d;
  mx_split_causes why;
  memset(&d, 0, sizeof d);
  memset(&why, 0, sizeof why);
  uint64_t single_hash = 0;
  double st_refine = 0, st_balance = 0;
  if (!st) st = mx_p4est_build(&P, &I.B, MPI_COMM_WORLD, NULL);
  if (!st) st = mx_p4est_summarize(&P, &s);
  if (!st && compare) st = compare_single(m, &P, &d, &why, &single_hash, &st_refine, &st_balance);
  mx_p4est_mesh_report *mesh = NULL;
  if (!st && m->p.stage == MX_STAGE_FULL) {
    mesh = mx_calloc(sizeof *mesh);
    st = mx_mpi_agree(MPI_COMM_WORLD, mesh ? MX_OK : MX_ENOMEM);
    if (!st) st = mx_p4est_mesh_run(o, &P, m, t0, mesh);
    if (!st) mx_p4est_mesh_reduce(&P, mesh);
  }
  double t_total = mx_wtime() - t0;
  MPI_Allreduce(MPI_IN_PLACE, &t_total, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
  if (!st && rank0 && (o->json || !o->quiet))
    report(o, &P, &s, t_setup, t_total, omp_get_max_threads(), compare, &d, &why,
           single_hash, st_refine, st_balance, mesh);
  if (mesh) mx_p4est_mesh_free(&mesh->D);
  mx_free(mesh);
  if (st && rank0 && o->json)
    printf("{\"p4est\": true, \"exit_code\": %d, \"error\": \"%s\"}\n", st,
           mx_status_string(st));
  mx_p4est_free(&P);
  mx_p4est_inputs_free(&I);
  mx_mesher_free(m);
  return st;
}

int mx_p4est_main(int argc, char **argv) {
  int provided, rank;
  MPI_Init_thread(&argc, &argv, MPI_THREAD_FUNNELED, &provided);
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  rank0 = rank == 0;
  mx_msg_fn = on_message;
  mx_msg_user = NULL;
  sc_init(MPI_COMM_WORLD, 0, 0, NULL, SC_LP_SILENT);
  p4est_init(NULL, SC_LP_SILENT);
  /* our flags out, the rest parsed as usual */
  char **av = mx_alloc(((size_t)argc + 1) * sizeof *av);
  int ac = 0, compare = 0;
  for (int i = 0; av && i < argc; i++) {
    if (strcmp(argv[i], "--p4est") == 0) continue;
    if (strcmp(argv[i], "--p4est-compare") == 0) {
      compare = 1;
      continue;
    }
    av[ac++] = argv[i];
  }
  mx_options o;
  int exit_now = 0;
  int st = av ? mx_parse_options(ac, av, &o, &exit_now) : MX_ENOMEM;
  if (!st && !exit_now && (o.restart_out || o.restart_in || o.boundary_out)) {
    mx_error(NULL, 0, "--p4est: no -c, --restart or --boundary (the distributed path "
                      "meshes from the surfaces and levels only)");
    st = MX_EINPUT;
  }

  if (!st && !exit_now) st = mx_p4est_check_outputs(&o);
  if (!st && !exit_now) {
    mx_quiet = o.quiet;
    if (o.threads > 0) omp_set_num_threads(o.threads);
    st = run(&o, compare);
  }
  mx_free(av);
  sc_finalize();
  MPI_Finalize();
  return st;
}
