#include "kernels/requests.h"

#include "sizing/cspace.h"

/* The level whose octants are no larger than the least size of the field
 * over [lo, hi] (the whole field's box when lo is NULL); 0 without one. */
static int field_level(const mx_requests *R, const double lo[3], const double hi[3]) {
  if (!R->size_field || !(R->root_side > 0.0)) return 0;
  const mx_size_field *F = R->size_field;
  const double h = lo ? mx_size_field_min_box(F, lo, hi) : mx_size_field_min_box(F, F->lo, F->hi);
  return mx_cs_level(R->root_side, h, MX_MAX_LEVEL - 1);
}

static int box_overlaps(const mx_box_region *b, const double lo[3],
                        const double hi[3]) {
  for (int a = 0; a < 3; a++)
    if (!(lo[a] < b->hi[a] && b->lo[a] < hi[a])) return 0;
  return 1;
}

int mx_target_level(const mx_requests *R, const double lo[3],
                    const double hi[3], int surf, unsigned rmask) {
  int t = 0;
  if (R->a_level > t) t = R->a_level;
  if (surf && R->s_level > t) t = R->s_level;
  for (size_t i = 0; i < R->nboxes; i++)
    if (R->boxes[i].level > t && box_overlaps(&R->boxes[i], lo, hi))
      t = R->boxes[i].level;
  for (int r = 0; r < R->nregions; r++)
    if ((rmask >> r) & 1u && R->rlevel[r] > t) t = R->rlevel[r];
  const int f = field_level(R, lo, hi);
  return f > t ? f : t;
}

int mx_max_requested_level(const mx_requests *R) {
  int t = 0;
  if (R->a_level > t) t = R->a_level;
  if (R->s_level > t) t = R->s_level;
  for (size_t i = 0; i < R->nboxes; i++)
    if (R->boxes[i].level > t) t = R->boxes[i].level;
  for (int r = 0; r < R->nregions; r++)
    if (R->rlevel[r] > t) t = R->rlevel[r];
  const int f = field_level(R, NULL, NULL);
  return f > t ? f : t;
}
