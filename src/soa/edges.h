/* Edge infos (Jaillet & Lobos 2021, section 5.2), one hash table per level
 * and axis. An edge of level l is keyed by the Morton key of its lower end on
 * the level-l lattice. Its info holds 4 slots, one per quadrant around the
 * edge, holding the octant of level l that has this edge as one of its own
 * 12 edges (MX_NONE if none). Whether the edge has a mid-node is read from
 * those octants when needed (a split one with a kept child along the edge:
 * leaf_mask in src/kernels/transition.c), so it needs no separate update.
 * For an edge along axis a, with b = a+1 and c = a+2 (mod 3), an octant's
 * slot is bit 0 = "the octant lies on the + side of the edge along b",
 * bit 1 = same along c. Each slot has exactly one possible writer, so slots
 * are written without locks; the key words are claimed with compare-and-swap,
 * so many threads register edges at once.
 *
 * Unlike the paper, slots never inherit coarser octants: a coarser neighbour
 * of an octant O is found in the edge infos of O's parent (same level as that
 * neighbour), which is all that balancing needs. */
#ifndef MX_EDGES_H
#define MX_EDGES_H

#include <stddef.h>
#include <stdint.h>

#include "base/morton.h"

typedef struct {
  uint64_t kw;       /* 0 = empty; else key + 1 */
  uint32_t slot[4];
} mx_edge;

typedef struct {
  mx_edge *e;
  size_t cap;   /* number of entries */
  size_t count; /* number of used entries */
} mx_edge_table;

typedef struct {
  mx_edge_table t[MX_MAX_LEVEL + 1][3];
} mx_edges;

void mx_edges_free(mx_edges *E);
/* Make room for `extra` more edges per axis at `level` (load <= 0.7). */
int mx_edges_reserve(mx_edges *E, int level, size_t extra);
/* Index of the entry of `key`, or SIZE_MAX if absent. */
size_t mx_edge_find(const mx_edge_table *T, uint64_t key);
/* Start loading the home slot of `key` (to overlap cache misses). */
void mx_edge_prefetch(const mx_edge_table *T, uint64_t key);
/* Prefetch the 12 edge entries of the octant (key, level). */
void mx_edges_prefetch_octant(const mx_edges *E, uint64_t key, int level);

/* Lower end of edge j (0..3) of axis a of the octant with level-l anchor
 * (ax, ay, az), and the octant's slot in that edge. */
static inline uint64_t mx_edge_key(const uint32_t anchor[3], int a, int j) {
  uint32_t p[3] = {anchor[0], anchor[1], anchor[2]};
  p[(a + 1) % 3] += (uint32_t)(j & 1);
  p[(a + 2) % 3] += (uint32_t)(j >> 1);
  return mx_morton_encode(p[0], p[1], p[2]);
}
static inline int mx_edge_slot(int j) { return 3 - j; }

/* Register octant o (key on the finest lattice, level) in its 12 edges:
 * creates the edges that do not exist yet and writes o into its slots.
 * created[a] is increased by the number of axis-a edges it created (the
 * caller sums them per thread, then calls mx_edges_add_count). Thread-safe
 * as long as the tables have room (mx_edges_reserve). */
void mx_edges_register(mx_edges *E, uint32_t o, uint64_t key, int level,
                       size_t created[3]);
/* Register, in one go, the kept children of the octant (key, level) that has
 * just been split: the 54 edges of level+1 inside and on that octant are each
 * looked up once and given the slots of the children that have them. Same
 * contract as mx_edges_register. */
void mx_edges_register_children(mx_edges *E, uint32_t child0, uint8_t kept,
                                uint64_t key, int level, size_t created[3]);
/* Add the counts created by mx_edges_register to the (level, axis) tables. */
void mx_edges_add_count(mx_edges *E, int level, const size_t created[3]);
size_t mx_edges_total(const mx_edges *E);
size_t mx_edges_bytes(const mx_edges *E);

#endif
