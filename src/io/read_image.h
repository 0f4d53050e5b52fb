/* Label images (issue 28): a segmented 3D image read from NIfTI-1/NIfTI-2
 * (.nii, .nii.gz), MetaImage (.mha, .mhd + its raw file, raw or zlib
 * compressed) or INRIA (.inr, .inr.gz), gzip through zlib
 * (src/io/read_image.c). Voxel types: uint8, int8, int16, uint16, int32,
 * uint32 (values up to INT32_MAX) and float32/float64 (rounded to the
 * nearest integer, with a warning naming the file and the number of voxels
 * that were not integers). Every header is checked against the file's size
 * (or, gzip, the bytes it inflates to) before the voxels are allocated.
 *
 * Conventions (src/io/read_nifti.c, read_metaimage.c, read_inr.c):
 *  - NIfTI: A from the sform when sform_code > 0, else from the qform
 *    (quaternion, qoffset, |pixdim[1..3]| with 0 taken as 1, k flipped when
 *    pixdim[0] = qfac < 0) when qform_code > 0, else diag(pixdim[1..3])
 *    with the origin 0 (method 1 of nifti1.h). scl_slope/scl_inter are
 *    applied (the values then rounded like floats) when both are finite,
 *    the slope is not 0 and they are not (1, 0). Single files only
 *    (magic n+1, n+2); .hdr/.img pairs (ni1, ni2) are refused. dim[0] is 3,
 *    or up to 7 with the dims past the third equal to 1.
 *  - MetaImage: world = Offset + D diag(ElementSpacing) (i, j, k), the
 *    first three numbers of TransformMatrix (or Rotation, Orientation)
 *    being D's first column (the direction of the i axis), as MetaIO
 *    stores it and ITK reads it. ElementSize stands for a missing
 *    ElementSpacing; Position and Origin for Offset. HeaderSize (-1: the
 *    data at the end of its file) applies to a separate data file.
 *  - INRIA: A = diag(VX, VY, VZ), the origin (XO, YO, ZO) when given (the
 *    centre of voxel (0, 0, 0)), else 0. CPU absent: little-endian.
 *  - Only regular files are read (no pipes or devices). A compressed
 *    stream must reach its end mark (a cut checksum is a truncated file).
 *  - oblique: some column of A has more than one component larger than
 *    1e-6 times its norm (a permutation or flip of the axes is not). A
 *    transform with a non-finite entry, a zero column or dependent columns
 *    is refused. */
#ifndef MX_READ_IMAGE_H
#define MX_READ_IMAGE_H

#include <stddef.h>
#include <stdint.h>

typedef struct {
  int64_t nx, ny, nz; /* voxels along i, j, k (>= 1 each) */
  int32_t *label;     /* nx * ny * nz (mx_alloc), i fastest, then j, k */
  /* world (x, y, z) of the centre of voxel (i, j, k):
   *   x = A[0] i + A[1] j + A[2] k + A[3], y = A[4] i + ..., z = A[8] i + ... */
  double A[12];
  double spacing[3]; /* the voxel's size along i, j, k (the columns' norms) */
  int oblique;       /* 1: the columns of A are not along the axes (a rotation) */
  size_t rounded;    /* float voxels that were not integers (rounded) */
  char format[16];   /* "NIfTI-1", "NIfTI-2", "MetaImage", "INR" */
} mx_label_image;

/* Read path (dispatch on the extension, case-insensitive: .nii .nii.gz
 * .mha .mhd .inr .inr.gz; otherwise on the first bytes). On error: a
 * message "mixoct: FILE: error: ..." through mx_error (the file, and for
 * text headers the line) and MX_EINPUT (unreadable, bad or truncated file,
 * unsupported type, dims that do not fit), MX_ENOMEM; img is left empty
 * (label NULL). */
int mx_read_label_image(const char *path, mx_label_image *img);
/* The same from bytes in memory (name: what messages call the file, and
 * its extension picks the format; a .mhd's raw file is looked for beside
 * name on disk, so from memory only .mha with its data in the same bytes,
 * or ElementDataFile = LOCAL, is read). For the fuzzer and tests.
 * (Implemented so: from memory a MetaImage whose ElementDataFile is not
 * LOCAL is refused, MX_EINPUT, no file being opened.) */
int mx_read_label_image_mem(const char *name, const unsigned char *data, size_t n,
                            mx_label_image *img);
void mx_label_image_free(mx_label_image *img);

#endif
