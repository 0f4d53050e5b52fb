/* Re-meshing through the mesher object (the 2021 paper, section 4.2): the
 * elements' leaves are split by list refinement (Algorithm 3,
 * kernels/remesh.c), the requests applied to the refined octree, and the
 * octree meshed again. */
#include "mesher/mesher_impl.h"

#include "kernels/remesh.h"

#include <string.h>

/* Split the listed octants once, then the requests; mesh again. */
static int refine_and_mesh(mx_mesher *m, uint32_t *octs, size_t n) {
  mx_builder *B = &m->B;
  const size_t s0 = B->stats.split_requested + B->stats.split_balance;
  const double tr = B->stats.t_refine, tb = B->stats.t_balance;
  /* the summary of this run, the octree's figures kept */
  const double read = m->S.ph.read, restart = m->S.t_restart;
  memset(&m->S, 0, sizeof m->S);
  m->S.ph.read = read;
  m->S.t_restart = restart;
  const double t0 = mx_wtime();
  B->req = mx_mesher_requests(m); /* m->boxes may have moved */
  size_t listed = 0;
  for (size_t i = 0; i < n; i++) {
    /* a leaf listed through several elements is split once */
    if (B->oct.flags[octs[i]] & MX_OCT_QUEUED) continue;
    B->oct.flags[octs[i]] |= MX_OCT_QUEUED;
    octs[listed++] = octs[i];
  }
  for (size_t i = 0; i < listed; i++) B->oct.flags[octs[i]] &= (uint8_t)~MX_OCT_QUEUED;
  MX_CHECK(mx_refine_list(B, octs, listed));
  m->S.refined_listed = listed;
  /* Algorithm 2's requests on top (boxes, levels, regions) */
  mx_retarget_leaves(B);
  MX_CHECK(mx_refine_leaves_to_target(B));
  m->S.remesh_splits = B->stats.split_requested + B->stats.split_balance - s0;
  m->S.ph.refine += B->stats.t_refine - tr;
  m->S.ph.balance += B->stats.t_balance - tb;
  MX_CHECK(mx_update_leaves(m));
  mx_free(m->file_leaf);
  m->file_leaf = NULL;
  m->file_nelem = 0;
  int st = mx_mesh_stages(m);
  m->S.octants = B->oct.n;
  m->S.leaves = m->nleaves;
  m->S.leaves_hash = mx_leaves_hash(B, m->leaves, m->nleaves);
  m->S.edges = mx_edges_total(&B->edges);
  m->S.edge_bytes = mx_edges_bytes(&B->edges);
  m->S.split_requested = B->stats.split_requested;
  m->S.split_balance = B->stats.split_balance;
  m->S.located = B->stats.located;
  m->S.dropped = B->stats.dropped;
  m->S.balance = m->p.balance;
  m->S.ph.total = mx_wtime() - t0;
  return st;
}

static int need_tree(mx_mesher *m) {
  if (m->have_tree) return MX_OK;
  mx_error(NULL, 0, "nothing to refine: mesh first or load a restart file");
  return MX_EINPUT;
}

int mx_mesher_refine_elements(mx_mesher *m, const uint64_t *elements, size_t n) {
  mx_call c;
  mx_call_begin(m, &c);
  int st = need_tree(m);
  /* the element -> leaf map of the current mesh, or of the mesh written
   * with the restart file just read */
  const uint32_t *map = NULL;
  size_t nelem = 0;
  if (!st && m->file_leaf) {
    map = m->file_leaf;
    nelem = m->file_nelem;
  } else if (!st && m->mesh_stage >= MX_STAGE_TRANSITION) {
    map = m->M.leaf;
    nelem = m->M.ncells;
  } else if (!st) {
    mx_error(NULL, 0, "no mesh whose elements could be refined");
    st = MX_EINPUT;
  }
  for (size_t i = 0; !st && i < n; i++)
    if (elements[i] >= nelem) {
      mx_error(NULL, 0, "element %llu of the list (entry %zu) is out of range: the mesh "
                        "has %zu elements (0 .. %zu)",
               (unsigned long long)elements[i], i + 1, nelem, nelem ? nelem - 1 : 0);
      st = MX_EINPUT;
    }
  uint32_t *octs = NULL;
  if (!st) {
    octs = mx_alloc((n + 1) * sizeof *octs);
    if (!octs) st = MX_ENOMEM;
  }
  size_t k = 0, lost = 0;
  for (size_t i = 0; !st && i < n; i++) {
    if (map[elements[i]] == UINT32_MAX) {
      lost++;
      continue;
    }
    octs[k++] = m->leaves[map[elements[i]]];
  }
  if (lost)
    mx_warning(NULL, 0, "%zu listed element(s) lie in octants outside the domain as "
                        "this mixoct sees it: not refined", lost);
  int ran = 0;
  if (!st) {
    ran = 1;
    st = refine_and_mesh(m, octs, k);
  }
  mx_free(octs);
  if (ran && st && st != MX_EINVALID) mx_mesh_clear(m);
  return mx_call_end(m, &c, st);
}

int mx_mesher_refine_leaves(mx_mesher *m, const uint64_t *leaves, size_t n) {
  mx_call c;
  mx_call_begin(m, &c);
  int st = need_tree(m);
  for (size_t i = 0; !st && i < n; i++)
    if (leaves[i] >= m->nleaves) {
      mx_error(NULL, 0, "leaf %llu (entry %zu) is out of range: the octree has %zu "
                        "leaves", (unsigned long long)leaves[i], i + 1, m->nleaves);
      st = MX_EINPUT;
    }
  uint32_t *octs = NULL;
  if (!st) {
    octs = mx_alloc((n + 1) * sizeof *octs);
    if (!octs) st = MX_ENOMEM;
  }
  for (size_t i = 0; !st && i < n; i++) octs[i] = m->leaves[leaves[i]];
  int ran = 0;
  if (!st) {
    ran = 1;
    st = refine_and_mesh(m, octs, n);
  }
  mx_free(octs);
  if (ran && st && st != MX_EINVALID) mx_mesh_clear(m);
  return mx_call_end(m, &c, st);
}

int mx_mesher_refine(mx_mesher *m) {
  mx_call c;
  mx_call_begin(m, &c);
  int st = need_tree(m);
  if (!st) st = refine_and_mesh(m, NULL, 0);
  if (st && st != MX_EINVALID) mx_mesh_clear(m);
  return mx_call_end(m, &c, st);
}

size_t mx_mesher_restart_elements(const mx_mesher *m) { return m->file_leaf ? m->file_nelem : 0; }
