#include "soa/octree.h"

#include "base/common.h"

#include <stdlib.h>
#include <string.h>

void mx_octree_free(mx_octree *t) {
  mx_free(t->key); mx_free(t->level); mx_free(t->flags); mx_free(t->target);
  mx_free(t->kept); mx_free(t->rmeet); mx_free(t->rin); mx_free(t->parent);
  mx_free(t->child0); mx_free(t->tri_off); mx_free(t->tri_cnt); mx_free(t->tri_pool);
  memset(t, 0, sizeof *t);
}

#define GROW(field, n)                                                      \
  do {                                                                      \
    void *p_ = mx_realloc(t->field, (n) * sizeof *t->field);                \
    if (!p_) return MX_ENOMEM;                                              \
    t->field = p_;                                                          \
  } while (0)

int mx_octree_reserve(mx_octree *t, size_t n, size_t ntri) {
  if (n > t->cap) {
    size_t cap = t->cap ? t->cap : 1024;
    while (cap < n) cap += cap / 2;
    GROW(key, cap); GROW(level, cap); GROW(flags, cap); GROW(target, cap);
    GROW(kept, cap); GROW(rmeet, cap); GROW(rin, cap); GROW(parent, cap);
    GROW(child0, cap); GROW(tri_off, cap); GROW(tri_cnt, cap);
    t->cap = cap;
  }
  if (ntri > t->tri_cap) {
    size_t cap = t->tri_cap ? t->tri_cap : 4096;
    while (cap < ntri) cap += cap / 2;
    GROW(tri_pool, cap);
    t->tri_cap = cap;
  }
  return MX_OK;
}

