/* Local re-meshing (the 2021 paper, section 4.2, "only what changed is
 * re-meshed"). After a refinement of a meshed octree:
 *
 * 1. rings of leaves around what was split (mark_rings): ring 1, the leaves
 *    meeting an old leaf that was split (its descendants and the leaves
 *    touching it: every leaf whose transition pattern can change); ring
 *    k+1, the leaves touching ring k. The core: rings 1..c; the patch:
 *    rings 1..p (p > c: a context around the core);
 * 2. the transition and boundary stages on the patch's leaves alone (node
 *    masks come from the whole octree, so the patch's elements are those of
 *    a full run);
 * 3. the new mesh: the core's elements from the patch, every other leaf's
 *    from the old mesh (kernels/splice.c); the nodes both use are matched by
 *    lattice key and keep their old place.
 *
 * The boundary steps are local (a node's state, its projection, a pattern
 * depend on the elements and leaves around it), so the core's elements are
 * those of a run from scratch on the same octree when the context holds
 * every element that can reach them. The untangling and smoothing are the
 * steps whose reach is not bounded beforehand; so the splice is accepted
 * only when the patch gave every node it shares with the kept elements
 * the position and state it had (the change did not reach the kept part);
 * otherwise the rings double, and after that the whole octree is meshed.
 *
 * Before a patch is meshed, its cost is set against the whole octree's
 * (mx_remesh_local_pays, the model below): scattered marks make a patch of
 * most of the leaves with a long border, whose splice is most likely
 * refused, and the whole octree is meshed at once instead (the same mesh).
 * tests/test_remesh.c and bench/remesh_bench.c compare against a run from
 * scratch. */
#include "mesher/mesher_impl.h"
#include "mesher/pipeline.h"

#include <math.h>
#include <string.h>

#include "kernels/mesh_edit.h"
#include "kernels/closures.h"
#include "kernels/contacts.h"
#include "kernels/edges_lazy.h"
#include "kernels/refine_list.h"
#include "kernels/splice.h"

/* (core, patch) rings of the attempts. With 3 and 6 the cortex re-meshes of
 * the tests and the bench equal the full ones exactly and are accepted at
 * once; a core of 2 rings is not enough (the untangling reaches 3 rings
 * out), nor a context of 2 (a few shared nodes come out elsewhere). */
static const int attempt_rings[2][2] = {{3, 6}, {6, 12}};

/* With sharp features placed, a patch of more than this share of the
 * leaves is not meshed: the whole octree costs about as much, and the
 * splice is likely refused, as the placement moves nodes the kept elements
 * share. Measured at -s 5: text_on_cube's repair rounds made patches of
 * 96-99% of the leaves at 6 rings, each refused, then meshed everything;
 * 2.19 -> 1.13 s, the same mesh. (Without features the small meshes of
 * tests/test_remesh.c are patched whole, and equal the full runs.) */
#define PATCH_MAX_SHARE 0.5

/* The choice between a local and a full re-mesh (params.remesh_full 0),
 * made once the rings are marked (before any patch is meshed):
 *
 *   local  = LOCAL_NS_PER_PATCH_LEAF * np + LOCAL_NS_PER_LEAF * nl
 *            (the patch's stages; finding the rings, the splice and the
 *            numbering over the whole mesh),
 *   full   = FULL_NS_PER_LEAF * nl,
 *   accept = exp(-nborder / BORDER_SCALE): the chance that the splice is
 *            accepted (a refused one costs the attempt, then the whole
 *            octree or more rings),
 *
 * and the patch is meshed when local + (1 - accept) * full < full, that is
 * local < accept * full. Measured on the cortex (2 threads, the machine
 * shared with other work: the figures vary by up to 1.5x between runs)
 * with bench/remesh_bench.c --choice --levels 6,7,8, two runs (repeat 3,
 * each patch's and each full re-mesh's own seconds printed by a probe not
 * kept; repeat 5, the bench's own fit): full 1293, 2284, 2029
 * and 2229, 1911, 2237 ns per leaf at -s 6, 7, 8; local, fitted over single
 * spots of 2-99% of the leaves, 268, 379, 206 and 982, 380 ns per leaf +
 * 1427, 2901, 2002 and 1649, 914 ns per patch leaf (the second run's -s 8
 * fit is off: its largest box needed two patches). FULL_NS_PER_LEAF and
 * LOCAL_NS_PER_LEAF are the medians; a patch leaf is counted at the full
 * path's cost per leaf (the same stages on the same kind of leaves: the
 * fits range from 0.4x, boxes reaching into the inside mesh, to 1.4x,
 * spots on the surface; the median 0.8x would let a patch of every leaf
 * pay). Only the ratios matter: a patch pays below accept - 18% of the
 * leaves; issue 9's box at -s 8 (33%) up to a border of about 12,000.
 *
 * BORDER_SCALE: the leaves of ring 3 (the core's border) against
 * refused splices over 112 first attempts (6 rings) at -s 6 to 8
 * (scattered marks of 1 to 200 elements, spots, boxes of 0.5-12% of the
 * elements, repair rounds; the runs of the bench repeated): refused 23
 * times, at borders of 1,320 to 81,691 leaves, nearly all scattered marks
 * (20 or more scattered elements were refused every time; 5 or 10 in one
 * run of four), accepted 89 times at 169 to 12,947; 19,000 is the maximum
 * likelihood scale. The 50 scattered elements of issue 31 (borders 21,286
 * at -s 7, 22,878 at -s 8; patches of 80% and 34%) are meshed whole; issue
 * 9's box of 3.8% at -s 8 (border 8,345, a patch of 33%) locally. */
#define LOCAL_NS_PER_PATCH_LEAF 2100.0
#define LOCAL_NS_PER_LEAF 380.0
#define FULL_NS_PER_LEAF 2100.0
#define BORDER_SCALE 19000.0

int mx_remesh_local_pays(size_t np, size_t nborder, size_t nl) {
  const double local = LOCAL_NS_PER_PATCH_LEAF * (double)np + LOCAL_NS_PER_LEAF * (double)nl;
  const double full = FULL_NS_PER_LEAF * (double)nl;
  /* local + (1 - accept) * full < full */
  return local < exp(-(double)nborder / BORDER_SCALE) * full;
}

/* mark[i] = the ring of leaf i (1 .. rings), 0 beyond; pos maps octants to
 * leaf positions. *nsplit: the old leaves that were split; *nborder: the
 * leaves of ring core_rings (the core's border). choose: once the core is
 * marked, *declined = 1 and no more rings as soon as the leaves marked (a
 * lower bound of the patch) do not pay (mx_remesh_local_pays). */
static int mark_rings(mx_mesher *m, const uint32_t *old, size_t nold, const uint32_t *pos,
                      int rings, int core_rings, int choose, uint8_t *mark, size_t *nsplit,
                      size_t *nborder, int *declined) {
  *nborder = 0;
  *declined = 0;
  const mx_octree *T = &m->B.tree.oct;
  const size_t nl = m->nleaves;
  size_t n = 0;
  uint32_t top = 0; /* octants above the old leaves' ids are new */
#pragma omp parallel for schedule(static) reduction(+ : n) reduction(max : top)
  for (size_t i = 0; i < nold; i++) {
    n += (T->flags[old[i]] & MX_OCT_SPLIT) != 0;
    if (old[i] > top) top = old[i];
  }
  *nsplit = n;
  if (!n) return MX_OK;
  uint32_t *q = mx_alloc(((n > nl ? n : nl) + 1) * sizeof *q);
  if (!q) return MX_ENOMEM;
  n = 0;
  for (size_t i = 0; i < nold; i++)
    if (T->flags[old[i]] & MX_OCT_SPLIT) q[n++] = old[i];
  int st = mx_leaves_touching(&m->B.tree, pos, q, n, mark, 1);
  for (int ring = 2; !st && ring <= rings; ring++) {
    n = 0;
    size_t nmarked = 0, nlast = 0;
    /* new leaves lie in a split old leaf: whatever touches them touches
     * it, and is in ring 1 already */
    for (size_t i = 0; i < nl; i++) {
      nmarked += mark[i] != 0;
      nlast += mark[i] == ring - 1;
      if (mark[i] == ring - 1 && (ring > 2 || m->leaves[i] <= top)) q[n++] = m->leaves[i];
    }
    if (ring - 1 == core_rings) *nborder = nlast;
    if (ring - 1 >= core_rings && choose && !mx_remesh_local_pays(nmarked, *nborder, nl)) {
      *declined = 1;
      break;
    }
    st = mx_leaves_touching(&m->B.tree, pos, q, n, mark, (uint8_t)ring);
  }
  mx_free(q);
  return st;
}

/* The box holding the padded boxes of the elements of the core leaves
 * (from_patch[leaf] != MX_NONE) of the spliced mesh M (mx_contact_box);
 * 0 when there is none. */
static int core_box(const mx_mesh *M, const uint32_t *from_patch, double box[6]) {
  double lo0 = INFINITY, lo1 = INFINITY, lo2 = INFINITY;
  double hi0 = -INFINITY, hi1 = -INFINITY, hi2 = -INFINITY;
#pragma omp parallel for schedule(static) reduction(min : lo0, lo1, lo2) \
    reduction(max : hi0, hi1, hi2)
  for (size_t c = 0; c < M->ncells; c++) {
    if (from_patch[M->leaf[c]] == MX_NONE) continue;
    double b[6];
    mx_contact_box(M, c, b);
    lo0 = fmin(lo0, b[0]), lo1 = fmin(lo1, b[1]), lo2 = fmin(lo2, b[2]);
    hi0 = fmax(hi0, b[3]), hi1 = fmax(hi1, b[4]), hi2 = fmax(hi2, b[5]);
  }
  box[0] = lo0, box[1] = lo1, box[2] = lo2, box[3] = hi0, box[4] = hi1, box[5] = hi2;
  return lo0 <= hi0;
}

/* *done = 1: meshed locally; 0: the rings missed a change (the caller
 * retries with more rings or meshes everything); -1: not tried, the whole
 * octree costs less (choose: the cost model decides) or the patch cannot
 * be meshed alone. */
enum { LOCAL_RETRY = 0, LOCAL_DONE = 1, LOCAL_DECLINED = -1 };
static int remesh_local(mx_mesher *m, const uint32_t *old, size_t nold, int core_rings,
                        int patch_rings, int last, int choose, int *done) {
  *done = LOCAL_RETRY;
  mx_octree *T = &m->B.tree.oct;
  const double t0 = mx_wtime();
  const size_t nl = m->nleaves;
  uint32_t *pos = mx_alloc((T->n + 1) * sizeof *pos);
  uint8_t *mark = mx_calloc(nl + 1);
  uint32_t *from_old = mx_alloc((nl + 1) * sizeof *from_old);
  uint32_t *from_patch = mx_alloc((nl + 1) * sizeof *from_patch);
  uint32_t *P = mx_alloc((nl + 1) * sizeof *P);
  int st = (!pos || !mark || !from_old || !from_patch || !P) ? MX_ENOMEM : MX_OK;
  size_t nsplit = 0, nborder = 0;
  int declined = 0;
  if (!st) {
#pragma omp parallel for schedule(static)
    for (size_t o = 0; o < T->n; o++) pos[o] = MX_NONE;
#pragma omp parallel for schedule(static)
    for (size_t i = 0; i < nl; i++) pos[m->leaves[i]] = (uint32_t)i;
    st = mark_rings(m, old, nold, pos, patch_rings, core_rings, choose, mark, &nsplit, &nborder,
                    &declined);
  }
  /* the patch in leaf order; where the others' elements are in the old mesh */
  size_t np = 0, ncore = 0, lost = 0;
  if (!st && !declined) {
    for (size_t i = 0; i < nl; i++) {
      from_patch[i] = MX_NONE;
      if (mark[i]) {
        if (mark[i] <= core_rings) {
          from_patch[i] = (uint32_t)np;
          ncore++;
        }
        P[np++] = m->leaves[i];
      }
    }
#pragma omp parallel for schedule(static)
    for (size_t o = 0; o < T->n; o++) pos[o] = MX_NONE;
#pragma omp parallel for schedule(static)
    for (size_t i = 0; i < nold; i++) pos[old[i]] = (uint32_t)i;
#pragma omp parallel for schedule(static) reduction(+ : lost)
    for (size_t i = 0; i < nl; i++) {
      from_old[i] = from_patch[i] == MX_NONE ? pos[m->leaves[i]] : MX_NONE;
      lost += from_patch[i] == MX_NONE && from_old[i] == MX_NONE;
    }
  }
  mx_free(pos);
  mx_free(mark);
  m->rec->S.ph.grid += mx_wtime() - t0; /* finding the patch */
  /* lost: a leaf outside the core that is not an old leaf (cannot happen:
   * new leaves are in ring 1); the caller meshes everything */
  const int too_big = m->rec->S.features_kept && (double)np > PATCH_MAX_SHARE * (double)nl;
  if (!st && (declined || lost || too_big || (choose && !mx_remesh_local_pays(np, nborder, nl))))
    *done = LOCAL_DECLINED;
  if (!st && *done == LOCAL_RETRY) {
    mx_mesh Mp;
    uint8_t *pstates = NULL;
    mx_boundary_stats bs;
    memset(&bs, 0, sizeof bs);
    const double t1 = mx_wtime();
    st = mx_pipeline_transition(m, P, np, 0, &Mp);
    const double t2 = mx_wtime();
    m->rec->S.ph.transition += t2 - t1;
    if (!st) {
      st = mx_pipeline_boundary(m, P, np, &Mp, 1, &pstates, &bs);
      mx_mesh Mn;
      uint8_t *nstates = NULL;
      mx_splice_stats ss;
      if (!st)
        st = mx_mesh_splice(&m->M, m->states, nold, &Mp, pstates, np, from_old, from_patch, nl,
                            &Mn, &nstates, &ss);
      mx_mesh_free(&Mp);
      mx_free(pstates);
      if (!st && ss.shared_moved && !last) {
        mx_mesh_free(&Mn); /* the change reached the kept part: more rings */
        mx_free(nstates);
      } else if (!st) {
        /* the contact search next looks around the core only, when the
         * mesh replaced had none (mesher.h) */
        const int clean = m->contacts_clean && m->clean_conn == m->M.conn &&
                          m->clean_ncells == m->M.ncells;
        m->changed_valid = clean && core_box(&Mn, from_patch, m->changed_box);
        mx_mesh_summarize(&Mn);
        Mn.closures = m->M.closures;
        Mn.centre_leaves = m->M.centre_leaves;
        mx_mesh_free(&m->M);
        mx_free(m->states);
        m->M = Mn;
        m->states = nstates;
        m->mesh_stage = MX_STAGE_FULL;
        m->rec->S.boundary = bs;
        m->rec->S.full = 1;
        if (!m->rec->S.patch_leaves) { /* the refinement's, not the repair rounds' */
          m->rec->S.patch_leaves = np;
          m->rec->S.core_leaves = ncore;
        }
        m->rec->S.splice = ss;
        *done = LOCAL_DONE;
      }
    }
    m->rec->S.ph.boundary += mx_wtime() - t2;
  }
  mx_free(from_old);
  mx_free(from_patch);
  mx_free(P);
  return st;
}

int mx_remesh_changed(mx_mesher *m, const uint32_t *old_leaves, size_t nold) {
  int done = 0;
  if (m->rec->S.local_attempts == 0) m->rec->S.local = 1; /* until a re-mesh is not */
  /* not with interfaces between materials: the nodes the cleaving adds
   * have no lattice key, so the splice could not match those on the
   * patch's border (a crack); the whole octree is meshed again */
  if (m->p.remesh_full != 1 && m->mesh_stage == MX_STAGE_FULL && m->M.nkey && m->states &&
      old_leaves && !m->IF.npasses)
    for (int a = 0; a < 2 && done == LOCAL_RETRY; a++) {
      m->rec->S.local_attempts++;
      MX_CHECK(remesh_local(m, old_leaves, nold, attempt_rings[a][0], attempt_rings[a][1], 0,
                            m->p.remesh_full == 0, &done));
    }
  if (done == LOCAL_DONE) return MX_OK;
  m->rec->S.local = 0;
  return mx_mesh_full(m);
}

int mx_remesh_after_refine(mx_mesher *m) {
  uint32_t *old = m->leaves;
  const size_t nold = m->nleaves;
  m->leaves = NULL;
  int st = mx_update_leaves(m);
  if (!st) st = mx_remesh_changed(m, old, nold);
  mx_free(old);
  return st;
}
