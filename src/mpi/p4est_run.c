/* The distributed path (include/mixoct.h: mx_p4est_init, mx_p4est_run,
 * mx_p4est_finalize): MPI, sc and p4est set up and ended, messages printed
 * once, by rank 0 (every rank runs the same inputs), and a run's steps in
 * order: the mesher of the parameters with its inputs (read on every
 * rank), the builder over them (p4est_inputs.h), the distributed octree
 * (p4est_octree.h) and its summary, with compare the single-process octree
 * on rank 0 against it (p4est_compare.h), unless --stage octree the mesh
 * (p4est_run_mesh.c), then rank 0's report (p4est_run_report.c). */
#include "mpi/p4est_run.h"

#include "base/common.h"
#include "mesher/mesher_impl.h"
#include "mpi/exchange.h"
#include "mpi/p4est_inputs.h"

#include <omp.h>
#include <stdio.h>
#include <string.h>

#include <p8est.h>

/* This process is rank 0 of MPI_COMM_WORLD (set by mx_p4est_init; a
 * process has one rank, whatever its meshers and threads). */
static int rank0;

/* Messages: printed once, by rank 0 (every rank runs the same inputs). */
static void on_message(void *user, int level, const char *text) {
  (void)user;
  if (!rank0) return;
  if (level == MX_MSG_ERROR || !mx_quiet)
    fprintf(stderr, "mixoct: %s%s\n", level == MX_MSG_ERROR ? "error: " : "warning: ", text);
}

/* The surfaces with their own options, region surfaces and boxes, in the
 * order the single-process program adds them (src/cli/main.c,
 * mx_add_inputs; the per-surface options through the same library call). */
static int add_inputs(const mx_p4est_run_params *p, mx_mesher *m) {
  if (p->demo) MX_CHECK(mx_mesher_add_demo_surface(m));
  for (int i = 0; i < p->nsurfaces; i++)
    if (mx_is_label_image_path(p->surfaces[i])) {
      mx_error(p->surfaces[i], 0, "--p4est does not mesh label images yet: run without it");
      return MX_EINPUT;
    }
  for (int i = 0; i < p->nsurfaces; i++)
    MX_CHECK(mx_mesher_add_input(m, p->surfaces[i], p->material_ids ? p->material_ids[i] : 0,
                                 p->material_names ? p->material_names[i] : NULL,
                                 p->surface_levels ? p->surface_levels[i] : 0,
                                 p->inside_levels ? p->inside_levels[i] : 0));
  for (int r = 0; r < p->nregions; r++)
    MX_CHECK(mx_mesher_add_region_surface(m, p->region_surfaces[r], p->region_levels[r]));
  if (p->boxes_file) MX_CHECK(mx_mesher_read_boxes(m, p->boxes_file));
  return MX_OK;
}

/* The mesher of the run (every rank the same): parameters and inputs. */
static int setup(const mx_p4est_run_params *p, mx_mesher **out) {
  mx_params mp;
  mx_params_default(&mp);
  mp.surface_level = p->surface_level;
  mp.all_level = p->all_level;
  /* the octree, or the mesh (the transition stage alone is not offered) */
  mp.stage = p->stage == MX_STAGE_OCTREE ? MX_STAGE_OCTREE : MX_STAGE_FULL;
  mp.threads = p->threads;
  mp.max_memory_mb = p->max_memory_mb;
  mp.repair_input = p->repair_input; /* refused by mx_p4est_inputs_init */
  mp.materials = p->materials;
  mx_mesher *m = mx_mesher_new(&mp);
  if (!m) return MX_ENOMEM; /* said by mx_alloc */
  *out = m;
  mx_mesher_set_message_handler(m, on_message, NULL);
  /* the distributed path does not keep sharp features yet (issue 29): its
   * octree and mesh, and the single-process octree it compares with, are
   * those of --no-features */
  MX_CHECK(mx_mesher_set_feature_angle(m, 0.0));
  return add_inputs(p, m);
}

/* Rank 0: the single-process octree of the same inputs, compared: the
 * leaves in the domain, and why p4est split the single-process leaves it
 * split (every quadrant of the forest gathered). */
static int compare_single(mx_mesher *m, const mx_p4est_octree *P, mx_p4est_single *c) {
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
        mx_leaf_diff_compute(ka, la, na, kb, lb, nb, &c->d);
        mx_leaf_diff_causes(qa, qla, qin, nq, kb, lb, nb, P->B->tree.grid.dims,
                            &c->why);
      }
      c->hash = mx_leaves_hash(&m->B.tree, m->leaves, m->nleaves);
      c->t_refine = m->rec->S.ph.refine;
      c->t_balance = m->rec->S.ph.balance;
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

/* The steps in order; the status agreed over the ranks after each. */
static int run(const mx_p4est_run_params *p) {
  const double t0 = mx_wtime();
  mx_mesher *m = NULL;
  mx_p4est_inputs I;
  memset(&I, 0, sizeof I);
  int st = setup(p, &m);
  if (!st) st = mx_p4est_inputs_init(&I, m);
  st = mx_mpi_agree(MPI_COMM_WORLD, st);
  double t_setup = mx_wtime() - t0;
  MPI_Allreduce(MPI_IN_PLACE, &t_setup, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
  mx_p4est_octree P;
  memset(&P, 0, sizeof P);
  mx_p4est_summary s;
  mx_p4est_single c;
  memset(&c, 0, sizeof c);
  c.compared = p->compare;
  if (!st) st = mx_p4est_build(&P, &I.B, MPI_COMM_WORLD, NULL);
  if (!st) st = mx_p4est_summarize(&P, &s);
  if (!st && p->compare) st = compare_single(m, &P, &c);
  mx_p4est_mesh_report *mesh = NULL;
  if (!st && m->p.stage == MX_STAGE_FULL) {
    mesh = mx_calloc(sizeof *mesh);
    st = mx_mpi_agree(MPI_COMM_WORLD, mesh ? MX_OK : MX_ENOMEM);
    if (!st) st = mx_p4est_mesh_run(p, &P, m, t0, mesh);
    if (!st) mx_p4est_mesh_reduce(&P, mesh);
  }
  double t_total = mx_wtime() - t0;
  MPI_Allreduce(MPI_IN_PLACE, &t_total, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
  if (!st && rank0 && (p->json || !p->quiet))
    mx_p4est_report(p, &P, &s, t_setup, t_total, omp_get_max_threads(), &c, mesh);
  if (mesh) mx_p4est_mesh_free(&mesh->D);
  mx_free(mesh);
  if (st && rank0 && p->json)
    printf("{\"p4est\": true, \"exit_code\": %d, \"error\": \"%s\"}\n", st,
           mx_status_string(st));
  mx_p4est_free(&P);
  mx_p4est_inputs_free(&I);
  mx_mesher_free(m);
  return st;
}

void mx_p4est_init(int *argc, char ***argv) {
  int provided, rank;
  MPI_Init_thread(argc, argv, MPI_THREAD_FUNNELED, &provided);
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  rank0 = rank == 0;
  mx_set_thread_message_handler(on_message, NULL);
  sc_init(MPI_COMM_WORLD, 0, 0, NULL, SC_LP_SILENT);
  p4est_init(NULL, SC_LP_SILENT);
}

int mx_p4est_run(const mx_p4est_run_params *p) {
  int st = mx_p4est_check_outputs(p);
  if (st) return st;
  mx_set_thread_quiet(p->quiet);
  if (p->threads > 0) omp_set_num_threads(p->threads);
  return run(p);
}

void mx_p4est_finalize(void) {
  sc_finalize();
  MPI_Finalize();
}
