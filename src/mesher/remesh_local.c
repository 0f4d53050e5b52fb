/* Local re-meshing (the 2021 paper, section 4.2, "only what changed is
 * re-meshed"). After a refinement of a meshed octree:
 *
 * 1. the old leaves that were split, grouped by their ancestor two levels up
 *    (a cube A of side S = 4 split octants);
 * 2. the core: the leaves meeting the 3x3x3 cubes of side S around each A
 *    (every leaf whose transition pattern can change, and a margin of at
 *    least 4 split-octant sides around it); the patch: the core and the
 *    leaves meeting the 5x5x5 cubes around A (a context of 4 more);
 * 3. the transition and boundary stages on the patch's leaves alone (the
 *    node masks come from the whole octree, so the patch's elements are
 *    those of a full run);
 * 4. the new mesh: the core's elements from the patch, every other leaf's
 *    from the old mesh (kernels/splice.c); the nodes both use are matched by
 *    lattice key and keep their old place.
 *
 * The boundary steps are local (a node's state, its projection, a pattern
 * depend on the elements and leaves around it), so the core's elements
 * equal those of a run from scratch on the same octree wherever the context
 * holds every element that can reach them; the smoothing is the one step
 * whose reach is not bounded a priori (tests/test_remesh.c measures the
 * difference against a run from scratch). */
#include "mesher/mesher_impl.h"

#include <string.h>

#include "kernels/mesh_edit.h"
#include "kernels/splice.h"

/* Rings of leaves around what was split: ring 1, the leaves meeting a split
 * old leaf (its children and the leaves touching it: every leaf whose
 * transition pattern can change); ring k+1, the leaves touching ring k. */
#define CORE_RINGS 3
#define PATCH_RINGS 6

static mx_lattice_box octant_box(const mx_octree *T, uint32_t o) {
  mx_lattice_box b;
  uint32_t a[3];
  mx_morton_decode(T->key[o], a);
  const uint32_t s = mx_octant_size(T->level[o]);
  for (int d = 0; d < 3; d++) {
    b.lo[d] = a[d];
    b.hi[d] = a[d] + s;
  }
  return b;
}

/* mark[i] = the ring of leaf i (1 .. PATCH_RINGS), 0 beyond; pos maps
 * octants to leaf positions. *nsplit: the old leaves that were split. */
static int mark_rings(mx_mesher *m, const uint32_t *old, size_t nold, const uint32_t *pos,
                      uint8_t *mark, size_t *nsplit) {
  const mx_octree *T = &m->B.oct;
  const size_t nl = m->nleaves;
  size_t n = 0;
#pragma omp parallel for schedule(static) reduction(+ : n)
  for (size_t i = 0; i < nold; i++) n += (T->flags[old[i]] & MX_OCT_SPLIT) != 0;
  *nsplit = n;
  if (!n) return MX_OK;
  size_t cap = n > nl ? n : nl;
  mx_lattice_box *box = mx_alloc((cap + 1) * sizeof *box);
  if (!box) return MX_EINPUT;
  n = 0;
  for (size_t i = 0; i < nold; i++)
    if (T->flags[old[i]] & MX_OCT_SPLIT) box[n++] = octant_box(T, old[i]);
  int st = mx_leaves_in_boxes(&m->B, pos, box, n, mark, 1);
  for (int ring = 2; !st && ring <= PATCH_RINGS; ring++) {
    n = 0;
    for (size_t i = 0; i < nl; i++)
      if (mark[i] == ring - 1) box[n++] = octant_box(T, m->leaves[i]);
    st = mx_leaves_in_boxes(&m->B, pos, box, n, mark, (uint8_t)ring);
  }
  mx_free(box);
  return st;
}

/* 1: meshed locally; 0: not possible (the caller meshes everything). */
static int remesh_local(mx_mesher *m, const uint32_t *old, size_t nold, int *done) {
  *done = 0;
  mx_octree *T = &m->B.oct;
  const double t0 = mx_wtime();
  const size_t nl = m->nleaves;
  uint32_t *pos = mx_alloc((T->n + 1) * sizeof *pos);
  uint8_t *mark = mx_calloc(nl + 1);
  uint32_t *from_old = mx_alloc((nl + 1) * sizeof *from_old);
  uint32_t *from_patch = mx_alloc((nl + 1) * sizeof *from_patch);
  uint32_t *P = mx_alloc((nl + 1) * sizeof *P);
  int st = (!pos || !mark || !from_old || !from_patch || !P) ? MX_EINPUT : MX_OK;
  size_t nsplit = 0;
  if (!st) {
#pragma omp parallel for schedule(static)
    for (size_t o = 0; o < T->n; o++) pos[o] = MX_NONE;
#pragma omp parallel for schedule(static)
    for (size_t i = 0; i < nl; i++) pos[m->leaves[i]] = (uint32_t)i;
    st = mark_rings(m, old, nold, pos, mark, &nsplit);
  }
  /* the patch in leaf order; where the others' elements are in the old mesh */
  size_t np = 0, ncore = 0, lost = 0;
  if (!st) {
    for (size_t i = 0; i < nl; i++) {
      from_patch[i] = MX_NONE;
      if (mark[i]) {
        if (mark[i] <= CORE_RINGS) {
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
  /* a leaf outside the core that is not an old leaf: the boxes missed a
   * change (should not happen): mesh everything */
  if (!st && !lost) {
    mx_mesh_out Mp;
    uint8_t *pstates = NULL;
    mx_boundary_stats bs;
    memset(&bs, 0, sizeof bs);
    const double t1 = mx_wtime();
    st = mx_transition(&m->B, P, np, &Mp);
    const double t2 = mx_wtime();
    if (!st) {
      st = mx_boundary_stage(&m->B, P, &m->SI, &Mp, m->p.close_ratio, m->p.staircase_quality,
                             &bs, &pstates);
      if (!st) st = mx_mesh_sort_by_leaf(&Mp, np);
      mx_mesh_out Mn;
      uint8_t *nstates = NULL;
      if (!st)
        st = mx_mesh_splice(&m->M, m->states, nold, &Mp, pstates, np, from_old, from_patch, nl,
                            &Mn, &nstates, &m->S.splice);
      mx_mesh_out_free(&Mp);
      mx_free(pstates);
      if (!st) {
        mx_mesh_summarize(&Mn);
        Mn.closures = m->M.closures;
        Mn.centre_leaves = m->M.centre_leaves;
        mx_mesh_out_free(&m->M);
        mx_free(m->states);
        m->M = Mn;
        m->states = nstates;
        m->mesh_stage = MX_STAGE_FULL;
        m->S.boundary = bs;
        m->S.full = 1;
        m->S.local = 1;
        m->S.patch_leaves = np;
        m->S.core_leaves = ncore;
        m->S.ph.transition += t2 - t1;
        m->S.ph.boundary += mx_wtime() - t2;
        m->S.ph.grid += t1 - t0; /* finding the patch */
        *done = 1;
      }
    }
  }
  mx_free(from_old);
  mx_free(from_patch);
  mx_free(P);
  return st;
}

int mx_remesh_changed(mx_mesher *m, const uint32_t *old_leaves, size_t nold) {
  int done = 0;
  if (!m->p.remesh_full && m->mesh_stage == MX_STAGE_FULL && m->M.nkey && m->states &&
      m->have_index && old_leaves)
    MX_CHECK(remesh_local(m, old_leaves, nold, &done));
  if (done) return MX_OK;
  return mx_mesh_full(m);
}
