/* Colours of a set of nodes, two nodes of one element never of one colour
 * (kernels/colouring.h). */
#include "kernels/colouring.h"

#include <string.h>

#include "base/common.h"
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

int mx_colour_nodes(const mx_mesh *M, const uint32_t *inc, const uint64_t *off,
                       const uint32_t *work, size_t nw, const uint32_t *widx,
                       int16_t *colour) {
  uint8_t *pick = mx_alloc(nw + 1);
  uint64_t *prio = mx_alloc((nw + 1) * sizeof *prio);
  uint32_t *todo = mx_alloc((nw + 1) * sizeof *todo); /* the nodes still uncoloured */
  if (!pick || !prio || !todo) {
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
      const uint32_t v = work[i];
      int best = 1;
      for (uint64_t e = off[v]; e < off[v + 1] && best; e++) {
        const uint32_t *row = M->conn + 8 * (size_t)inc[e];
        for (int k = 0; k < mx_cell_nodes[M->type[inc[e]]]; k++) {
          const uint32_t j = widx[row[k]];
          if (j == UINT32_MAX || j == i || colour[j] >= 0) continue;
          if (before(prio, j, i)) {
            best = 0;
            break;
          }
        }
      }
      pick[i] = (uint8_t)best;
    }
#pragma omp parallel for schedule(dynamic, 256) reduction(| : overflow) if (left >= 4096)
    for (size_t t = 0; t < left; t++) {
      const size_t i = todo[t];
      if (!pick[i]) continue;
      uint64_t used[MX_MAX_COLOURS / 64] = {0, 0, 0, 0};
      const uint32_t v = work[i];
      for (uint64_t e = off[v]; e < off[v + 1]; e++) {
        const uint32_t *row = M->conn + 8 * (size_t)inc[e];
        for (int k = 0; k < mx_cell_nodes[M->type[inc[e]]]; k++) {
          const uint32_t j = widx[row[k]];
          if (j == UINT32_MAX || j == i) continue;
          const int cj = colour[j];
          if (cj >= 0) used[cj / 64] |= 1ull << (cj % 64);
        }
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
  if (overflow) return -1;
  for (size_t i = 0; i < nw; i++)
    if (colour[i] + 1 > ncol) ncol = colour[i] + 1;
  return ncol;
}
