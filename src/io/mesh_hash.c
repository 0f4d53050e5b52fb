/* mixoct: a hash of a mesh that does not depend on its numbering
 * (io/pvtu.h: mx_mesh_hash).
 *
 * A cell is its type and the set of its nodes' coordinates: the
 * coordinate triples, as bits (-0.0 taken as 0.0), are sorted (by x, then
 * y, then z, comparing bits as unsigned integers: any fixed order would do)
 * and chained through a 64-bit mixer after the type, so neither node
 * numbers nor the node order in the cell enter. The cells' hashes are
 * summed modulo 2^64, which does not depend on the cell order nor on how
 * the sum is split among threads or pieces, and the sum is mixed with the
 * cell count at the end. */
#include <string.h>

#include "io/pvtu.h"

static const uint64_t GOLDEN = 0x9e3779b97f4a7c15ull;

/* splitmix64's finaliser: a bijection on 64 bits with full avalanche. */
static inline uint64_t mix64(uint64_t z) {
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  return z ^ (z >> 31);
}

static inline uint64_t coord_bits(double d) {
  uint64_t b;
  memcpy(&b, &d, sizeof b);
  return (b << 1) == 0 ? 0 : b; /* -0.0 and 0.0 are the same point */
}

static inline int triple_less(const uint64_t *a, const uint64_t *b) {
  if (a[0] != b[0]) return a[0] < b[0];
  if (a[1] != b[1]) return a[1] < b[1];
  return a[2] < b[2];
}

/* Cell c's sorted coordinate bits in key (nn triples); nn returned. */
static int cell_keys(const mx_mesh_view *v, size_t c, uint64_t key[8][3]) {
  const unsigned t = v->type[c];
  /* an inconsistent view (types and nodes are checked by whoever made it)
   * must not read out of bounds: a type out of range hashes alone, a node
   * out of range as all ones */
  const int nn = t <= MX_HEX ? mx_cell_nodes[t] : 0;
  for (int j = 0; j < nn; j++) {
    const uint32_t node = v->conn[8 * c + (size_t)j];
    uint64_t k[3] = {UINT64_MAX, UINT64_MAX, UINT64_MAX};
    if (node < v->nnodes)
      for (int a = 0; a < 3; a++) k[a] = coord_bits(v->xyz[3 * (size_t)node + (size_t)a]);
    int i = j; /* insertion sort: at most 8 triples */
    while (i > 0 && triple_less(k, key[i - 1])) {
      memcpy(key[i], key[i - 1], sizeof key[i]);
      i--;
    }
    memcpy(key[i], k, sizeof k);
  }
  return nn;
}

static uint64_t cell_hash(const mx_mesh_view *v, size_t c) {
  uint64_t key[8][3];
  const int nn = cell_keys(v, c, key);
  uint64_t h = mix64(GOLDEN * (v->type[c] + 1));
  for (int j = 0; j < nn; j++)
    for (int a = 0; a < 3; a++) h = mix64((h ^ key[j][a]) + GOLDEN);
  return h;
}

/* The sum of the hashes of LANES cells from c: the same values as
 * cell_hash, the cells' chains of mixes run side by side (a chain is
 * latency-bound: one cell's mixes wait for each other, four cells' do
 * not); a shorter chain keeps its value past its end. */
enum { LANES = 4 };
static uint64_t cells_hash_sum(const mx_mesh_view *v, size_t c) {
  uint64_t key[LANES][8][3], h[LANES];
  int len[LANES], most = 0;
  for (int l = 0; l < LANES; l++) {
    len[l] = 3 * cell_keys(v, c + (size_t)l, key[l]);
    h[l] = mix64(GOLDEN * (v->type[c + (size_t)l] + 1));
    most = len[l] > most ? len[l] : most;
  }
  for (int i = 0; i < most; i++)
    for (int l = 0; l < LANES; l++) {
      const uint64_t x = mix64((h[l] ^ key[l][i / 3][i % 3]) + GOLDEN);
      h[l] = i < len[l] ? x : h[l];
    }
  uint64_t sum = 0;
  for (int l = 0; l < LANES; l++) sum += h[l];
  return sum;
}

uint64_t mx_mesh_hash_sum(const mx_mesh_view *v) {
  uint64_t sum = 0;
  const size_t n = v->ncells, groups = n / LANES;
#pragma omp parallel for schedule(static) reduction(+ : sum) if (n > 16384)
  for (size_t g = 0; g < groups; g++) sum += cells_hash_sum(v, LANES * g);
  for (size_t c = LANES * groups; c < n; c++) sum += cell_hash(v, c);
  return sum;
}

uint64_t mx_mesh_hash_finish(uint64_t sum, uint64_t ncells) { return mix64(sum ^ ncells); }

uint64_t mx_mesh_hash(const mx_mesh_view *v) {
  return mx_mesh_hash_finish(mx_mesh_hash_sum(v), (uint64_t)v->ncells);
}
