/* Partition along the Morton curve, with the triangle lists following their
 * quadrants, and the ghost layer.
 *
 * Weights: during the refinement, what a quadrant will still cost (about
 * 4^(target - level) descendants along the surface for a surface quadrant,
 * 8^(target - level) for an inside one asked to refine, one otherwise);
 * after the balance, the elements a leaf is expected to give (none
 * outside, mx_p4est_params' weights inside and on the surface).
 *
 * The lists: packed in local order (which also drops the lists of
 * quadrants split since the last partition), their sizes sent with
 * p8est_transfer_fixed and the lists with p8est_transfer_custom from the
 * old partition to the new one; each quadrant's offset is then its running
 * sum in the new local order. */
#include "mpi/p4est_octree.h"

#include "base/common.h"

#include <p8est_communication.h>
#include <p8est_extended.h>
#include <string.h>

enum { TAG_SIZES = 7301, TAG_LISTS = 7302 };

static int pow_capped(int base, int e, int cap) {
  long long v = 1;
  for (int i = 0; i < e && v < cap; i++) v *= base;
  return v < cap ? (int)v : cap;
}

static int weight_refine(p8est_t *p8, p4est_topidx_t t, p8est_quadrant_t *q) {
  (void)t;
  const mx_p4est_octree *P = p8->user_pointer;
  const mx_pq *d = q->p.user_data;
  if (!mx_pq_kept(d)) return P->par.weight_outside;
  const int left = (d->target < P->max_level ? d->target : P->max_level) - q->level;
  if (left <= 0) return 1;
  return (d->flags & MX_PQ_SURFACE) ? pow_capped(4, left, 1 << 24)
                                    : pow_capped(8, left, 1 << 24);
}

static int weight_mesh(p8est_t *p8, p4est_topidx_t t, p8est_quadrant_t *q) {
  (void)t;
  const mx_p4est_octree *P = p8->user_pointer;
  const mx_pq *d = q->p.user_data;
  if (!mx_pq_kept(d)) return P->par.weight_outside;
  return (d->flags & MX_PQ_SURFACE) ? P->par.weight_surface : P->par.weight_inside;
}

/* Runs body for each local quadrant, in order: d its data, i its local index. */
#define FOR_LOCAL(p8, d, i, body)                                                         \
  do {                                                                                    \
    size_t i = 0;                                                                         \
    for (p4est_topidx_t t_ = (p8)->first_local_tree; t_ <= (p8)->last_local_tree; t_++) { \
      p8est_tree_t *tr_ = p8est_tree_array_index((p8)->trees, t_);                        \
      for (size_t k_ = 0; k_ < tr_->quadrants.elem_count; k_++, i++) {                    \
        mx_pq *d = p8est_quadrant_array_index(&tr_->quadrants, k_)->p.user_data;          \
        body                                                                              \
      }                                                                                   \
    }                                                                                     \
  } while (0)

int mx_p4est_partition(mx_p4est_octree *P, int mesh_weights) {
  if (P->size == 1) return MX_OK;
  const double t0 = mx_wtime();
  p8est_t *p8 = P->p8;
  const size_t nold = (size_t)p8->local_num_quadrants;
  p4est_gloidx_t *old_gfq = mx_alloc(((size_t)P->size + 1) * sizeof *old_gfq);
  int *src_sizes = mx_alloc((nold + 1) * sizeof *src_sizes);
  size_t total = 0;
  FOR_LOCAL(p8, d, i, { total += d->tri_cnt; });
  uint32_t *src = mx_alloc((total + 1) * sizeof *src);
  int st = old_gfq && src_sizes && src ? MX_OK : MX_ENOMEM;
  int all = st;
  MPI_Allreduce(&st, &all, 1, MPI_INT, MPI_MAX, P->comm);
  if (all) {
    mx_free(old_gfq);
    mx_free(src_sizes);
    mx_free(src);
    return all;
  }
  memcpy(old_gfq, p8->global_first_quadrant, ((size_t)P->size + 1) * sizeof *old_gfq);
  size_t w = 0;
  FOR_LOCAL(p8, d, i, {
    memcpy(src + w, P->pool + d->tri_off, (size_t)d->tri_cnt * sizeof *src);
    src_sizes[i] = (int)(d->tri_cnt * sizeof *src);
    w += d->tri_cnt;
  });
  const p4est_gloidx_t shipped =
      p8est_partition_ext(p8, 0, mesh_weights ? weight_mesh : weight_refine);
  P->shipped += shipped;
  P->partitions++;
  /* bytes this rank sends away: quadrants whose new owner is another rank */
  {
    const p4est_gloidx_t *nfq = p8->global_first_quadrant;
    int r = 0;
    for (size_t i = 0; i < nold; i++) {
      const p4est_gloidx_t g = old_gfq[P->rank] + (p4est_gloidx_t)i;
      while (r < P->size - 1 && nfq[r + 1] <= g) r++;
      if (r != P->rank) P->shipped_bytes += src_sizes[i];
    }
  }
  const size_t nnew = (size_t)p8->local_num_quadrants;
  int *dest_sizes = mx_alloc((nnew + 1) * sizeof *dest_sizes);
  st = dest_sizes ? MX_OK : MX_ENOMEM;
  MPI_Allreduce(&st, &all, 1, MPI_INT, MPI_MAX, P->comm);
  uint32_t *dest = NULL;
  if (!all) {
    p8est_transfer_fixed(p8->global_first_quadrant, old_gfq, P->comm, TAG_SIZES, dest_sizes,
                         src_sizes, sizeof(int));
    size_t bytes = 0;
    for (size_t i = 0; i < nnew; i++) bytes += (size_t)dest_sizes[i];
    dest = mx_alloc(bytes + sizeof *dest);
    st = dest ? MX_OK : MX_ENOMEM;
    MPI_Allreduce(&st, &all, 1, MPI_INT, MPI_MAX, P->comm);
  }
  if (!all) {
    p8est_transfer_custom(p8->global_first_quadrant, old_gfq, P->comm, TAG_LISTS, dest,
                          dest_sizes, src, src_sizes);
    size_t at = 0;
    st = MX_OK;
    FOR_LOCAL(p8, d, i, {
      if ((size_t)dest_sizes[i] != (size_t)d->tri_cnt * sizeof *dest) st = MX_EINTERNAL;
      d->tri_off = at;
      at += d->tri_cnt;
    });
    mx_free(P->pool);
    P->pool = dest;
    P->pool_n = at;
    P->pool_cap = at + 1;
    dest = NULL;
    MPI_Allreduce(&st, &all, 1, MPI_INT, MPI_MAX, P->comm);
    if (all == MX_EINTERNAL)
      mx_error(NULL, 0, "internal: triangle lists received do not match their quadrants");
  }
  mx_free(dest);
  mx_free(dest_sizes);
  mx_free(old_gfq);
  mx_free(src_sizes);
  mx_free(src);
  P->t.partition += mx_wtime() - t0;
  return all;
}

int mx_p4est_ghost(mx_p4est_octree *P) {
  const double t0 = mx_wtime();
  P->ghost = p8est_ghost_new(P->p8, P8EST_CONNECT_FULL);
  const size_t n = P->ghost->ghosts.elem_count;
  P->ghost_data = mx_alloc((n + 1) * sizeof *P->ghost_data);
  int st = P->ghost_data ? MX_OK : MX_ENOMEM, all = st;
  MPI_Allreduce(&st, &all, 1, MPI_INT, MPI_MAX, P->comm);
  if (!all) p8est_ghost_exchange_data(P->p8, P->ghost, P->ghost_data);
  P->t.ghost += mx_wtime() - t0;
  return all;
}
