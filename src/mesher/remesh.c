/* Re-meshing through the mesher object (the 2021 paper, section 4.2): the
 * elements' leaves are split by list refinement (Algorithm 3,
 * kernels/remesh.c), the requests applied to the refined octree, and the
 * octree meshed again. */
#include "mesher/materials.h"
#include "mesher/mesher_impl.h"

#include "kernels/closures.h"
#include "kernels/edges_lazy.h"
#include "kernels/refine_list.h"
#include "soa/mesh.h"

#include <string.h>

/* Split the listed octants once, then the requests; mesh again. */
static int refine_and_mesh(mx_mesher *m, uint32_t *octs, size_t n) {
  mx_builder *B = &m->B;
  const size_t s0 = B->stats.split_requested + B->stats.split_balance;
  const double tr = B->stats.t_refine, tb = B->stats.t_balance;
  /* the summary of this run, the octree's figures kept */
  const double read = m->rec->S.ph.read, restart = m->rec->S.t_restart;
  memset(&m->rec->S, 0, sizeof m->rec->S);
  m->rec->S.ph.read = read;
  m->rec->S.t_restart = restart;
  const double t0 = mx_wtime();
  mx_mesher_untets(m); /* --tets: the mixed mesh is the one re-meshed */
  MX_CHECK(mx_mesher_size_space(m)); /* a size field given since the octree was built */
  const double root_side = B->req.root_side;
  B->req = mx_mesher_requests(m); /* m->boxes may have moved */
  B->req.root_side = root_side;   /* a size field's levels: from the grid */
  size_t listed = 0;
  for (size_t i = 0; i < n; i++) {
    /* a leaf listed through several elements is split once */
    if (B->tree.oct.flags[octs[i]] & MX_OCT_QUEUED) continue;
    B->tree.oct.flags[octs[i]] |= MX_OCT_QUEUED;
    octs[listed++] = octs[i];
  }
  for (size_t i = 0; i < listed; i++) B->tree.oct.flags[octs[i]] &= (uint8_t)~MX_OCT_QUEUED;
  int st = mx_refine_list(B, octs, listed);
  m->rec->S.refined_listed = listed;
  /* Algorithm 2's requests on top (boxes, levels, regions) */
  if (!st) mx_retarget_leaves(B);
  if (!st) st = mx_refine_leaves_to_target(B);
  if (st) { /* a tree refined half-way is not kept: the next mesh builds it again */
    mx_tree_clear(m);
    return st;
  }
  m->rec->S.remesh_splits = B->stats.split_requested + B->stats.split_balance - s0;
  m->rec->S.ph.refine += B->stats.t_refine - tr;
  m->rec->S.ph.balance += B->stats.t_balance - tb;
  mx_free(m->file_leaf);
  m->file_leaf = NULL;
  m->file_nelem = 0;
  if (m->mesh_stage == MX_STAGE_FULL && m->p.stage == MX_STAGE_FULL) {
    /* mesh again around what changed, keep the rest */
    st = mx_remesh_after_refine(m);
    if (!st) st = mx_repair(m);
    if (!st) st = mx_mesh_finish(m);
  } else {
    st = mx_update_leaves(m);
    if (!st) st = mx_mesh_stages(m);
  }
  if (st && !m->leaves) mx_tree_clear(m); /* the leaves could not be listed */
  mx_fill_tree_stats(m);
  m->rec->S.ph.total = mx_wtime() - t0;
  return st;
}

static int need_tree(mx_mesher *m) {
  MX_CHECK(mx_materials_allowed(m, "refining"));
  if (m->have_tree) return MX_OK;
  mx_error(NULL, 0, "nothing to refine: mesh first or load a restart file");
  return MX_EINPUT;
}

/* The leaves of the listed indices (elements, through map, or leaves when
 * map is NULL) split once, then the requests, and the octree meshed again.
 * A refused list leaves the mesher as it was. */
static int refine_indices(mx_mesher *m, const uint64_t *idx, size_t n, const uint32_t *map,
                          size_t limit, const char *what, const char *whole) {
  for (size_t i = 0; i < n; i++)
    if (idx[i] >= limit) {
      mx_error(NULL, 0, "%s %llu of the list (entry %zu) is out of range: there are %zu "
                        "%s (0 .. %zu)", what, (unsigned long long)idx[i], i + 1, limit,
               whole, limit ? limit - 1 : 0);
      return MX_EINPUT;
    }
  uint32_t *octs = mx_alloc((n + 1) * sizeof *octs);
  if (!octs) return MX_ENOMEM;
  size_t k = 0, lost = 0;
  for (size_t i = 0; i < n; i++) {
    const uint32_t leaf = map ? map[idx[i]] : (uint32_t)idx[i];
    if (leaf == UINT32_MAX)
      lost++;
    else
      octs[k++] = m->leaves[leaf];
  }
  if (lost)
    mx_warning(NULL, 0, "%zu listed element(s) lie in octants outside the domain as "
                        "this mixoct sees it: not refined", lost);
  /* the finest level first: a refused list leaves the mesher as it was */
  for (size_t i = 0; i < k; i++)
    if (m->B.tree.oct.level[octs[i]] >= MX_MAX_LEVEL - 1) {
      mx_error(NULL, 0, "cannot refine a leaf of level %d: %d is the finest level",
               m->B.tree.oct.level[octs[i]], MX_MAX_LEVEL - 1);
      mx_free(octs);
      return MX_EINPUT;
    }
  int st = refine_and_mesh(m, octs, k);
  mx_free(octs);
  if (st && st != MX_EINVALID) mx_mesh_clear(m);
  return st;
}

/* A mixoct restart file's element lists number the elements as mixoct
 * wrote its mesh: grouped by body and type (io/cell_order.c). The file's mesh (the
 * .octb's, or the octree meshed again: the same, it is deterministic) gives
 * each of them its leaf; *map (mx_alloc) receives them. The per-leaf counts
 * must be the file's. */
static int by_type_map(mx_mesher *m, uint32_t **map) {
  *map = NULL;
  if (m->mesh_stage != MX_STAGE_FULL) MX_CHECK(mx_mesh_stages(m));
  const mx_mesh *M = &m->M;
  const size_t n = M->ncells;
  uint32_t *order = mx_alloc((n + 1) * sizeof *order);
  uint32_t *cnt = mx_calloc((m->nleaves + 1) * sizeof *cnt);
  int st = order && cnt ? mx_written_order(m, order) : MX_ENOMEM;
  size_t bad = n != m->file_nelem;
  for (size_t k = 0; !st && !bad && k < n; k++) {
    const uint32_t l = m->file_leaf[k];
    if (l < m->nleaves) cnt[l]++;
  }
  for (size_t c = 0; !st && !bad && c < n; c++) bad += cnt[M->leaf[c]]-- == 0;
  if (!st && bad) {
    mx_error(NULL, 0, "the restart file's mesh cannot be made again (%zu elements "
                      "against the file's %zu): its element list cannot be mapped (a mesh "
                      "written with --tets is made again with --tets, and the reverse)", n,
             m->file_nelem);
    st = MX_EINPUT;
  }
  if (!st) {
#pragma omp parallel for schedule(static)
    for (size_t k = 0; k < n; k++) order[k] = M->leaf[order[k]];
    *map = order;
    order = NULL;
  }
  mx_free(order);
  mx_free(cnt);
  return st;
}

int mx_mesher_refine_elements(mx_mesher *m, const uint64_t *elements, size_t n) {
  mx_call c;
  mx_call_begin(m, &c);
  mx_written_forget(m); /* the mesh changes */
  int st = need_tree(m);
  /* the element -> leaf map of the mesh written with the restart file just
   * read, or of the current mesh */
  if (!st && m->file_leaf && m->file_by_type) {
    uint32_t *map = NULL;
    st = by_type_map(m, &map);
    if (!st)
      st = refine_indices(m, elements, n, map, m->file_nelem, "element",
                          "elements in the restart file's mesh");
    mx_free(map);
  } else if (!st && m->file_leaf) {
    st = refine_indices(m, elements, n, m->file_leaf, m->file_nelem, "element",
                        "elements in the restart file's mesh");
  } else if (!st && m->mesh_stage >= MX_STAGE_TRANSITION) {
    st = refine_indices(m, elements, n, m->M.leaf, m->M.ncells, "element",
                        "elements in the mesh");
  } else if (!st) {
    mx_error(NULL, 0, "no mesh whose elements could be refined");
    st = MX_EINPUT;
  }
  return mx_call_end(m, &c, st);
}

int mx_mesher_refine_leaves(mx_mesher *m, const uint64_t *leaves, size_t n) {
  mx_call c;
  mx_call_begin(m, &c);
  mx_written_forget(m); /* the mesh changes */
  int st = need_tree(m);
  if (!st) st = refine_indices(m, leaves, n, NULL, m->nleaves, "leaf", "leaves in the octree");
  return mx_call_end(m, &c, st);
}

int mx_mesher_refine(mx_mesher *m) {
  mx_call c;
  mx_call_begin(m, &c);
  mx_written_forget(m); /* the mesh changes */
  int st = need_tree(m);
  if (!st) st = refine_indices(m, NULL, 0, NULL, 0, "", "");
  return mx_call_end(m, &c, st);
}

size_t mx_mesher_restart_elements(const mx_mesher *m) { return m->file_leaf ? m->file_nelem : 0; }
