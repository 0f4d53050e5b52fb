/* The give-up after the features are placed (kernels/feature_place.h,
 * mx_feature_give_up): nodes put back, split nodes placed again, splits
 * undone, where the placement spoilt elements. */
#include <string.h>

#include "base/common.h"
#include "base/scan.h"
#include "geom/quality.h"
#include "kernels/cell_split.h"
#include "kernels/feature_place.h"
#include "kernels/mesh_edit.h"

static int node_moved(const mx_mesh *M, const double *before, size_t nb, uint32_t v) {
  return v < nb && memcmp(M->xyz + 3 * (size_t)v, before + 3 * (size_t)v, 3 * sizeof *before) != 0;
}

/* The elements of each node added by the splits (nodes nb ..): pairs
 * (node << 32 | element) sorted, their count in *n. */
static uint64_t *new_node_cells(const mx_mesh *M, size_t nb, size_t *n) {
  size_t k = 0;
  for (size_t c = 0; c < M->ncells; c++)
    for (int i = 0; i < mx_cell_nodes[M->type[c]]; i++) k += M->conn[8 * c + i] >= nb;
  uint64_t *p = mx_alloc((k + 1) * sizeof *p);
  uint32_t *dummy = mx_alloc((k + 1) * sizeof *dummy);
  if (!p || !dummy) {
    mx_free(p);
    mx_free(dummy);
    return NULL;
  }
  k = 0;
  for (size_t c = 0; c < M->ncells; c++)
    for (int i = 0; i < mx_cell_nodes[M->type[c]]; i++)
      if (M->conn[8 * c + i] >= nb) {
        dummy[k] = (uint32_t)c;
        p[k++] = (uint64_t)M->conn[8 * c + i] << 32 | c;
      }
  const int st = mx_sort_u64(p, dummy, k);
  mx_free(dummy);
  if (st) {
    mx_free(p);
    return NULL;
  }
  *n = k;
  return p;
}

/* Node v (added by a split) moved to the best point of its elements
 * (mx_mesh_best_point). */
static int recentre(mx_mesh *M, const uint64_t *pairs, size_t np, uint32_t v) {
  size_t i = mx_lower_u64(pairs, np, (uint64_t)v << 32), j = i;
  while (j < np && pairs[j] >> 32 == v) j++;
  uint32_t cells[64];
  size_t n = 0;
  for (size_t k = i; k < j && n < 64; k++) cells[n++] = (uint32_t)pairs[k];
  mx_mesh_best_point(M, v, cells, n);
  return n > 0;
}

static int give_up_pass(mx_mesh *M, const uint8_t *feature, const double *before, size_t nb,
                        const float *q_before, size_t ncb, double floor, size_t *count) {
  /* the elements with a moved node: the only ones that can be spoilt */
  size_t nc = 0, cap = 1024, np = 0;
  uint32_t *cand = mx_alloc(cap * sizeof *cand);
  uint64_t *pairs = M->nnodes > nb ? new_node_cells(M, nb, &np) : NULL;
  if (!cand || (M->nnodes > nb && !pairs)) {
    mx_free(cand);
    mx_free(pairs);
    return MX_ENOMEM;
  }
  for (size_t c = 0; c < M->ncells; c++) {
    int mv = 0;
    for (int k = 0; k < mx_cell_nodes[M->type[c]] && !mv; k++) {
      const uint32_t v = M->conn[8 * c + k];
      mv = v >= nb || node_moved(M, before, nb, v);
    }
    if (!mv) continue;
    if (nc == cap) {
      uint32_t *g = mx_realloc(cand, 2 * cap * sizeof *cand);
      if (!g) {
        mx_free(cand);
        mx_free(pairs);
        return MX_ENOMEM;
      }
      cand = g;
      cap *= 2;
    }
    cand[nc++] = (uint32_t)c;
  }
#define SPOILT(c) (mx_jens_invalid(M->jens[c]) || \
                   (M->jens[c] < floor && M->jens[c] < ((c) < ncb ? q_before[c] : 1.0)))
  for (int round = 0; round < 64; round++) {
    /* the new nodes of spoilt elements moved to their best points first,
     * then the moved nodes of those still spoilt put back */
    for (size_t i = 0; i < nc; i++) {
      const size_t c = cand[i];
      for (int k = 0; k < mx_cell_nodes[M->type[c]] && SPOILT(c); k++)
        if (M->conn[8 * c + k] >= nb) recentre(M, pairs, np, M->conn[8 * c + k]);
    }
    size_t n = 0;
    for (size_t i = 0; i < nc; i++) {
      const size_t c = cand[i];
      if (!SPOILT(c)) continue;
      /* the nodes moved beside the features first, the feature nodes
       * only when no other moved node is left */
      for (int pass = 0, done = 0; pass < 2 && !done; pass++)
        for (int k = 0; k < mx_cell_nodes[M->type[c]]; k++) {
          const uint32_t v = M->conn[8 * c + k];
          if (node_moved(M, before, nb, v) && (pass || !(feature && feature[v]))) {
            memcpy(M->xyz + 3 * (size_t)v, before + 3 * (size_t)v, 3 * sizeof *before);
            n++;
            done = 1;
          }
        }
    }
    if (!n) break;
    *count += n;
    for (size_t i = 0; i < nc; i++) {
      const size_t c = cand[i];
      double x[8][3];
      for (int k = 0; k < mx_cell_nodes[M->type[c]]; k++)
        memcpy(x[k], M->xyz + 3 * (size_t)M->conn[8 * c + k], sizeof x[k]);
      M->jens[c] = (float)mx_jens(M->type[c], (const double(*)[3])x);
    }
  }
#undef SPOILT
  mx_mesh_summarize(M);
  mx_free(cand);
  mx_free(pairs);
  return MX_OK;
}

int mx_feature_give_up(mx_mesh *M, uint8_t **states, mx_split_log *log, const uint8_t *feature,
                       const double *before,
                       size_t nb, const float *q_before, size_t ncb, double floor,
                       mx_feature_stats *fs) {
  size_t *count = &fs->given_up;
  int st = give_up_pass(M, feature, before, nb, q_before, ncb, floor, count);
  if (st || !log || !log->n) return st;
  /* the splits some cone of which is still spoilt undone, and their
   * elements' moved nodes then put back */
  uint8_t *undo = mx_calloc(log->n + 1);
  if (!undo) return MX_ENOMEM;
  size_t n = 0;
  for (size_t k = 0; k < log->n; k++) {
    const mx_split_undo *u = log->job + k;
    for (uint32_t i = 0; i < u->cones && !undo[k]; i++) {
      const size_t c = i == 0 ? u->cell : u->first + i - 1;
      undo[k] = mx_jens_invalid(M->jens[c]) ||
                (M->jens[c] < floor && M->jens[c] < (c < ncb ? q_before[c] : 1.0));
    }
    n += undo[k];
  }
  fs->unsplit += n;
  if (n) {
    st = mx_mesh_unsplit(M, states, log, undo);
    if (!st) st = give_up_pass(M, feature, before, nb, q_before, ncb, floor, count);
  }
  mx_free(undo);
  return st;
}
