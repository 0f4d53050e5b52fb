/* The refinement builder: what refining an octree needs besides the tree
 * (soa/tree.h) it fills: the triangle soup and which region each triangle
 * bounds, the point locators, the requests, the split set of a rebuilt
 * octree, the figures and the split scratch. Private to refinement: the
 * passes after it take the tree (kernels/refine.h has the passes). */
#ifndef MX_BUILDER_H
#define MX_BUILDER_H

#include <stddef.h>
#include <stdint.h>

#include "geom/locate.h"
#include "kernels/grid.h"
#include "kernels/requests.h"
#include "soa/tree.h"
#include "soa/trisoup.h"

typedef struct {
  size_t split_requested;  /* octants split because a request asked */
  size_t split_balance;    /* octants split to restore balance */
  size_t located;          /* ray-parity queries */
  size_t dropped;          /* children found outside and not stored */
  double t_refine, t_balance; /* seconds */
} mx_refine_stats;

typedef struct {
  const mx_trisoup *soup;
  uint8_t *tri_region;        /* per triangle: region index, 255 = domain */
  mx_locator loc_domain;
  mx_locator loc_region[MX_MAX_REGIONS];
  mx_requests req;
  mx_tree tree;               /* what the stages after refinement read */
  mx_refine_stats stats;
  /* Optional (NULL by default): octants that must be split whatever the
   * requests ask, sorted (mx_octkeys_sort_unique); a restart file's octree
   * is rebuilt from the split ancestors of its leaves, and tests split
   * chosen leaves in a from-scratch run. Set after mx_builder_init, with
   * edge_levels raised to the deepest level split. */
  const uint64_t *split_keys[MX_MAX_LEVEL + 1]; /* per level, sorted */
  size_t nsplit[MX_MAX_LEVEL + 1];
  /* Optional, NULL by default: called by the level loop of
   * mx_refine_balanced / mx_refine_unbalanced before each level is created,
   * with that level (1..max_level) and the finest level asked; never from a
   * parallel region. Set it after mx_builder_init (which clears the
   * builder). The program uses it for its progress line. */
  void (*on_level)(void *user, int level, int max_level);
  void *on_level_user;
  /* 1: a cancel (base/cancel.h) may also stop a level between its split
   * and its balance, leaving an unbalanced tree: only for a caller that
   * drops the tree when cancelled (a fresh mesh). 0 by default: levels
   * are whole. */
  int cancel_mid_level;

  /* scratch of mx_split_octants, grown on demand, reused */
  uint8_t *scratch_mask;
  size_t scratch_mask_cap;
  void *scratch_info;
  size_t scratch_info_cap;
  uint64_t *scratch_off;
  size_t scratch_off_cap;
} mx_builder;

/* soup: domain triangles first (nt_domain of them), then the triangles of
 * each region surface r in [region_t0[r], region_t0[r+1]). */
/* 1 when (key, level) is in the builder's split set. */
int mx_split_set_has(const mx_builder *B, uint64_t key, int level);

int mx_builder_init(mx_builder *B, const mx_trisoup *soup, uint32_t nt_domain,
                    const uint32_t *region_t0, const mx_requests *req,
                    int use_edges, const char *name);
void mx_builder_free(mx_builder *B);

#endif
