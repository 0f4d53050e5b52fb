/* A label image made ready for its interfaces (issue 28): the labels a
 * user skips or merges, small islands dropped, and the contacts a surface cannot bound removed (src/geom/label_fix.c).
 *
 * The image is held padded: one voxel of background (label 0) all round,
 * n[3] the padded dims, voxel (i, j, k) at i + n[0] (j + n[1] k). The
 * padding is never changed, so the outside is one background region. */
#ifndef MX_LABEL_FIX_H
#define MX_LABEL_FIX_H

#include <stddef.h>
#include <stdint.h>

typedef struct {
  size_t island_voxels;   /* voxels of the islands dropped (min_island) */
  size_t islands;         /* islands dropped */
  size_t contact_voxels;  /* voxels relabelled at edge and point contacts */
  int contact_rounds;     /* passes of the contact repair */
  int64_t contact_at[3];  /* a voxel (unpadded) relabelled first, -1 none */
} mx_label_fix_stats;

/* Islands: the face-connected parts of one label (background included)
 * with fewer than min_voxels voxels take the label their outside faces
 * meet most (ties: the smaller label). MX_OK, MX_ENOMEM. */
int mx_labels_drop_islands(int32_t *lab, const int64_t n[3], size_t min_voxels,
                           mx_label_fix_stats *st);
/* Contacts: around every lattice vertex, the 8 voxels' labels must each be
 * face-connected among the 8, so must what is not that label, and no
 * lattice edge may have four different labels in turn around it (two
 * labels, or two parts of one, would meet at a point or along an edge
 * only). A vertex breaking this gets one voxel relabelled to a label of a
 * face neighbour ranked above its own, or failing that its 8 voxels the
 * highest-ranked label among them; repeated until none is left. Ranks:
 * background lowest, then by count[L] (the voxels of label L, 65536
 * entries), fewer voxels higher, ties to the larger label; labels only
 * climb, so the repair ends. MX_OK, MX_ENOMEM, MX_EINPUT when more than
 * 64 labels are present or 64 passes leave contacts (message naming a
 * voxel). */
int mx_labels_fix_contacts(int32_t *lab, const int64_t n[3], const uint64_t *count,
                           const char *name, mx_label_fix_stats *st);

#endif
