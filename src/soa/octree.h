/* The octree as structure-of-arrays. An octant is an index; every octant
 * ever created stays (a split octant keeps its slot, flagged MX_OCT_SPLIT);
 * octants found outside the domain are never stored. Children of a split
 * octant are stored contiguously, in child order, kept ones only: child c is
 * at child0 + popcount(kept & ((1 << c) - 1)). */
#ifndef MX_OCTREE_H
#define MX_OCTREE_H

#include <stddef.h>
#include <stdint.h>

enum {
  MX_OCT_SPLIT = 1,    /* not a leaf any more */
  MX_OCT_SURFACE = 2,  /* meets a triangle of the domain surface */
  MX_OCT_QUEUED = 4,   /* already on the to_balance list */
  MX_OCT_BALANCE = 8,  /* was split to restore balance (not requested) */
  MX_OCT_EDGES = 16,   /* registered in its edges (levels > edge_levels) */
};

#define MX_NONE UINT32_MAX

typedef struct {
  size_t n, cap;
  uint64_t *key;      /* anchor Morton key on the finest lattice */
  uint8_t *level;
  uint8_t *flags;     /* MX_OCT_* */
  uint8_t *target;    /* requested level (max over all requests) */
  uint8_t *kept;      /* bit c set: child c exists (valid once split) */
  uint8_t *rmeet;     /* bit r: meets region surface r */
  uint8_t *rin;       /* bit r: inside region surface r, meets none of it */
  uint32_t *parent;   /* MX_NONE for roots */
  uint32_t *child0;   /* first child, MX_NONE while a leaf */
  uint64_t *tri_off;  /* CSR slice of tri_pool: the triangles it meets */
  uint32_t *tri_cnt;

  uint32_t *tri_pool; /* triangle ids (domain and region surfaces) */
  size_t tri_n, tri_cap;
} mx_octree;

void mx_octree_free(mx_octree *t);
/* Room for at least n octants and ntri pooled triangle ids. */
int mx_octree_reserve(mx_octree *t, size_t n, size_t ntri);

static inline uint32_t mx_octree_child(const mx_octree *t, uint32_t o,
                                       int c) {
  uint8_t k = t->kept[o];
  if (!(k & (1u << c))) return MX_NONE;
  return t->child0[o] + (uint32_t)__builtin_popcount(k & ((1u << c) - 1));
}

#endif
