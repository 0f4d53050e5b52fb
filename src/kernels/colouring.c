/* Colours of a set of nodes, two nodes of one element never of one colour
 * (kernels/colouring.h). */
#include "kernels/colouring.h"

#include <string.h>

#include "base/common.h"
#include "base/scan.h"
#include "soa/mesh.h"

static uint64_t mix64(uint64_t h) {
  h ^= h >> 33;
  h *= 0xFF51AFD7ED558CCDull;
  h ^= h >> 33;
  h *= 0xC4CEB9FE1A85EC53ull;
  h ^= h >> 33;
  return h;
}

/* The priority of node v: a hash of what the node is (its lattice key, or
 * its position for a node off the lattice), not of its number, so that a
 * local re-mesh, whose patch numbers its nodes its own way, colours the same
 * nodes alike. */
uint64_t mx_node_identity(const mx_mesh *M, uint32_t v) {
  if (M->nkey && M->nkey[v] != MX_NKEY_NONE) return mix64(M->nkey[v]);
  uint64_t h = 0x9E3779B97F4A7C15ull, b;
  for (int a = 0; a < 3; a++) {
    memcpy(&b, M->xyz + 3 * (size_t)v + a, sizeof b);
    h = mix64(h ^ b);
  }
  return h;
}

/* 1 when work node i goes before work node j */
static int before(const uint64_t *prio, size_t i, size_t j) {
  return prio[i] != prio[j] ? prio[i] > prio[j] : i < j;
}

/* Each work node's neighbours among the work nodes (those sharing an
 * element with it), once each: counted, prefix-summed, listed (a thread's
 * `seen` bytes, one per work node, reset after each node). */
static int work_neighbours(const mx_mesh *M, const uint32_t *inc, const uint64_t *off,
                           const uint32_t *work, size_t nw, const uint32_t *widx,
                           uint64_t **nb_off_out, uint32_t **nb_out) {
  uint64_t *nb_off = mx_calloc((nw + 1) * sizeof *nb_off);
  if (!nb_off) return MX_ENOMEM;
  uint32_t *nb = NULL;
  int st = MX_OK;
  for (int pass = 0; pass < 2 && st == MX_OK; pass++) {
#pragma omp parallel if (nw >= 4096)
    {
      uint8_t *seen = mx_calloc(nw + 1);
      if (!seen) {
#pragma omp atomic write
        st = MX_ENOMEM;
      }
#pragma omp for schedule(dynamic, 256)
      for (size_t i = 0; i < nw; i++) {
        if (!seen) continue;
        const uint32_t v = work[i];
        uint64_t k = pass ? nb_off[i] : 0;
        for (uint64_t e = off[v]; e < off[v + 1]; e++) {
          const uint32_t *row = M->conn + 8 * (size_t)inc[e];
          for (int q = 0; q < mx_cell_nodes[M->type[inc[e]]]; q++) {
            const uint32_t j = widx[row[q]];
            if (j == UINT32_MAX || j == i || seen[j]) continue;
            seen[j] = 1;
            if (pass) nb[k] = j;
            k++;
          }
        }
        if (!pass) nb_off[i] = k;
        for (uint64_t e = off[v]; e < off[v + 1]; e++) { /* reset */
          const uint32_t *row = M->conn + 8 * (size_t)inc[e];
          for (int q = 0; q < mx_cell_nodes[M->type[inc[e]]]; q++) {
            const uint32_t j = widx[row[q]];
            if (j != UINT32_MAX) seen[j] = 0;
          }
        }
      }
      mx_free(seen);
    }
    if (pass == 0 && st == MX_OK) {
      const uint64_t total = mx_scan_u64(nb_off, nw);
      nb_off[nw] = total;
      nb = mx_alloc((total + 1) * sizeof *nb);
      if (!nb) st = MX_ENOMEM;
    }
  }
  if (st) {
    mx_free(nb_off);
    mx_free(nb);
    return st;
  }
  *nb_off_out = nb_off;
  *nb_out = nb;
  return MX_OK;
}

int mx_colour_nodes(const mx_mesh *M, const uint32_t *inc, const uint64_t *off,
                       const uint32_t *work, size_t nw, const uint32_t *widx,
                       int16_t *colour) {
  uint8_t *pick = mx_alloc(nw + 1);
  uint64_t *prio = mx_alloc((nw + 1) * sizeof *prio);
  uint32_t *todo = mx_alloc((nw + 1) * sizeof *todo); /* the nodes still uncoloured */
  uint64_t *nb_off = NULL;
  uint32_t *nb = NULL;
  if (!pick || !prio || !todo ||
      work_neighbours(M, inc, off, work, nw, widx, &nb_off, &nb) != MX_OK) {
    mx_free(pick);
    mx_free(prio);
    mx_free(todo);
    return -2; /* out of memory */
  }
#pragma omp parallel for schedule(static) if (nw > MX_PAR_MIN)
  for (size_t i = 0; i < nw; i++) {
    colour[i] = -1;
    prio[i] = mx_node_identity(M, work[i]);
    todo[i] = (uint32_t)i;
  }
  size_t left = nw;
  int ncol = 0, overflow = 0;
  /* Rounds: an uncoloured node whose uncoloured neighbours all come after
   * it takes the least colour its neighbours do not have (two nodes picked
   * in one round are never neighbours: the same colours for any thread
   * count and any order of the list) */
  while (left && !overflow) {
#pragma omp parallel for schedule(dynamic, 256) if (left >= 4096)
    for (size_t t = 0; t < left; t++) {
      const size_t i = todo[t];
      int best = 1;
      for (uint64_t e = nb_off[i]; e < nb_off[i + 1] && best; e++) {
        const uint32_t j = nb[e];
        best = colour[j] >= 0 || !before(prio, j, i);
      }
      pick[i] = (uint8_t)best;
    }
#pragma omp parallel for schedule(dynamic, 256) reduction(| : overflow) if (left >= 4096)
    for (size_t t = 0; t < left; t++) {
      const size_t i = todo[t];
      if (!pick[i]) continue;
      uint64_t used[MX_MAX_COLOURS / 64] = {0, 0, 0, 0};
      for (uint64_t e = nb_off[i]; e < nb_off[i + 1]; e++) {
        const int cj = colour[nb[e]];
        if (cj >= 0) used[cj / 64] |= 1ull << (cj % 64);
      }
      int c = 0;
      while (c < MX_MAX_COLOURS && ((used[c / 64] >> (c % 64)) & 1)) c++;
      if (c == MX_MAX_COLOURS) {
        overflow = 1;
        c = 0;
      }
      colour[i] = (int16_t)c;
    }
    size_t kept = 0; /* the list less the nodes just coloured, in order */
    for (size_t t = 0; t < left; t++)
      if (!pick[todo[t]]) todo[kept++] = todo[t];
    left = kept;
  }
  mx_free(pick);
  mx_free(prio);
  mx_free(todo);
  mx_free(nb_off);
  mx_free(nb);
  if (overflow) return -1;
  for (size_t i = 0; i < nw; i++)
    if (colour[i] + 1 > ncol) ncol = colour[i] + 1;
  return ncol;
}
