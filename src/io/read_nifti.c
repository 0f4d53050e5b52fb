/* mixoct: NIfTI-1 and NIfTI-2 label images (io/read_image.h), single
 * files (.nii, magic "n+1" / "n+2"), gzip or not. The header's fields, at
 * their offsets in nifti1.h (348 bytes) and nifti2.h (540 bytes); the byte
 * order told by sizeof_hdr. The transform: the sform when sform_code > 0,
 * else the qform (quaternion) when qform_code > 0, else diag(pixdim[1..3])
 * ("method 1" of nifti1.h). */
#include <math.h>
#include <string.h>

#include "base/common.h"
#include "io/image_src.h"

static int64_t get_i16(const unsigned char *p, int big) { return (int16_t)(uint16_t)mx_load_uint(p, 2, big); }
static int64_t get_i32(const unsigned char *p, int big) { return (int32_t)(uint32_t)mx_load_uint(p, 4, big); }
static int64_t get_i64(const unsigned char *p, int big) { return (int64_t)mx_load_uint(p, 8, big); }
static double get_f32(const unsigned char *p, int big) {
  const uint32_t u = (uint32_t)mx_load_uint(p, 4, big);
  float f;
  memcpy(&f, &u, 4);
  return f;
}
static double get_f64(const unsigned char *p, int big) {
  const uint64_t u = mx_load_uint(p, 8, big);
  double f;
  memcpy(&f, &u, 8);
  return f;
}

/* The header's fields both versions share, as numbers. */
typedef struct {
  int version, big;
  int64_t dim[8];
  int datatype;
  double pixdim[8];
  double vox_offset, slope, inter;
  int qform_code, sform_code;
  double quatern[3], qoffset[3], srow[12];
} nifti_hdr;

static void decode_v1(const unsigned char *h, int big, nifti_hdr *n) {
  for (int d = 0; d < 8; d++) {
    n->dim[d] = get_i16(h + 40 + 2 * d, big);
    n->pixdim[d] = get_f32(h + 76 + 4 * d, big);
  }
  n->datatype = (int)get_i16(h + 70, big);
  n->vox_offset = get_f32(h + 108, big);
  n->slope = get_f32(h + 112, big);
  n->inter = get_f32(h + 116, big);
  n->qform_code = (int)get_i16(h + 252, big);
  n->sform_code = (int)get_i16(h + 254, big);
  for (int k = 0; k < 3; k++) {
    n->quatern[k] = get_f32(h + 256 + 4 * k, big);
    n->qoffset[k] = get_f32(h + 268 + 4 * k, big);
  }
  for (int k = 0; k < 12; k++) n->srow[k] = get_f32(h + 280 + 4 * k, big);
}

static void decode_v2(const unsigned char *h, int big, nifti_hdr *n) {
  n->datatype = (int)get_i16(h + 12, big);
  for (int d = 0; d < 8; d++) {
    n->dim[d] = get_i64(h + 16 + 8 * d, big);
    n->pixdim[d] = get_f64(h + 104 + 8 * d, big);
  }
  const int64_t off = get_i64(h + 168, big);
  n->vox_offset = (double)off;
  n->slope = get_f64(h + 176, big);
  n->inter = get_f64(h + 184, big);
  n->qform_code = (int)get_i32(h + 344, big);
  n->sform_code = (int)get_i32(h + 348, big);
  for (int k = 0; k < 3; k++) {
    n->quatern[k] = get_f64(h + 352 + 8 * k, big);
    n->qoffset[k] = get_f64(h + 376 + 8 * k, big);
  }
  for (int k = 0; k < 12; k++) n->srow[k] = get_f64(h + 400 + 8 * k, big);
}

static int voxel_type(const char *path, int datatype, int *type) {
  switch (datatype) {
  case 2: *type = MX_VT_U8; return MX_OK;
  case 256: *type = MX_VT_I8; return MX_OK;
  case 4: *type = MX_VT_I16; return MX_OK;
  case 512: *type = MX_VT_U16; return MX_OK;
  case 8: *type = MX_VT_I32; return MX_OK;
  case 768: *type = MX_VT_U32; return MX_OK;
  case 16: *type = MX_VT_F32; return MX_OK;
  case 64: *type = MX_VT_F64; return MX_OK;
  default: break;
  }
  const char *name = "unknown";
  switch (datatype) {
  case 1: name = "binary"; break;
  case 32: name = "complex64"; break;
  case 128: name = "rgb24"; break;
  case 1024: name = "int64"; break;
  case 1280: name = "uint64"; break;
  case 1536: name = "float128"; break;
  case 1792: name = "complex128"; break;
  case 2048: name = "complex256"; break;
  case 2304: name = "rgba32"; break;
  default: break;
  }
  mx_error(path, 0,
           "datatype %d (%s) is not a label type read: uint8 (2), int8 (256), int16 (4), "
           "uint16 (512), int32 (8), uint32 (768), float32 (16), float64 (64)",
           datatype, name);
  return MX_EINPUT;
}

/* The qform: the rotation of the quaternion (b, c, d; a >= 0 completes it to
 * a unit quaternion), the voxel's sizes |pixdim[1..3]| (0 taken as 1, as
 * nifti1_io does), k flipped when qfac = pixdim[0] < 0. */
static void qform(const nifti_hdr *n, double A[12]) {
  double b = n->quatern[0], c = n->quatern[1], d = n->quatern[2];
  double a = 1.0 - (b * b + c * c + d * d);
  if (a < 1e-7) { /* a rotation by 180 degrees: (b, c, d) made a unit vector */
    const double s = sqrt(b * b + c * c + d * d);
    if (s > 0) {
      b /= s;
      c /= s;
      d /= s;
    }
    a = 0;
  } else {
    a = sqrt(a);
  }
  const double R[9] = {a * a + b * b - c * c - d * d, 2 * (b * c - a * d), 2 * (b * d + a * c),
                       2 * (b * c + a * d), a * a + c * c - b * b - d * d, 2 * (c * d - a * b),
                       2 * (b * d - a * c), 2 * (c * d + a * b), a * a + d * d - c * c - b * b};
  double size[3];
  for (int k = 0; k < 3; k++) {
    size[k] = fabs(n->pixdim[k + 1]);
    if (size[k] == 0) size[k] = 1;
  }
  if (n->pixdim[0] < 0) size[2] = -size[2];
  for (int r = 0; r < 3; r++) {
    for (int k = 0; k < 3; k++) A[4 * r + k] = R[3 * r + k] * size[k];
    A[4 * r + 3] = n->qoffset[r];
  }
}

int mx_read_nifti(mx_isrc *s, mx_label_image *img) {
  const char *path = s->path;
  int gz;
  MX_CHECK(mx_isrc_gzip_auto(s, &gz));
  unsigned char h[540];
  size_t got, more = 0;
  MX_CHECK(mx_isrc_read(s, h, 348, &got));
  if (got < 4) {
    mx_error(path, 0, "truncated header: %zu bytes, a NIfTI header has 348 (NIfTI-1) or 540 "
                      "(NIfTI-2)", got);
    return MX_EINPUT;
  }
  nifti_hdr n;
  memset(&n, 0, sizeof n);
  const uint64_t le = mx_load_uint(h, 4, 0), be = mx_load_uint(h, 4, 1);
  if (le == 348 || be == 348)
    n.version = 1;
  else if (le == 540 || be == 540)
    n.version = 2;
  else {
    mx_error(path, 0, "not a NIfTI file: sizeof_hdr is %llu (348 for NIfTI-1, 540 for NIfTI-2, "
                      "in either byte order)", (unsigned long long)le);
    return MX_EINPUT;
  }
  n.big = le != 348 && le != 540;
  const size_t hsize = n.version == 1 ? 348 : 540;
  if (got == 348 && n.version == 2) MX_CHECK(mx_isrc_read(s, h + 348, 540 - 348, &more));
  if (got + more < hsize) {
    mx_error(path, 0, "truncated header: %zu bytes of the %zu of a NIfTI-%d header", got + more,
             hsize, n.version);
    return MX_EINPUT;
  }
  char word[MX_WORD_BUF];
  if (n.version == 1) {
    if (!memcmp(h + 344, "ni1\0", 4)) {
      mx_error(path, 0, "a NIfTI-1 header of a .hdr/.img pair (magic \"ni1\"): not read; "
                        "store the image as one .nii file (magic \"n+1\")");
      return MX_EINPUT;
    }
    if (memcmp(h + 344, "n+1\0", 4)) {
      mx_error(path, 0, "bad magic '%s' at byte 344: a NIfTI-1 file has \"n+1\" (an Analyze 7.5 "
                        "header has none: not read)", mx_show_word(h + 344, 4, word));
      return MX_EINPUT;
    }
    decode_v1(h, n.big, &n);
  } else {
    if (!memcmp(h + 4, "ni2\0\r\n\032\n", 8)) {
      mx_error(path, 0, "a NIfTI-2 header of a .hdr/.img pair (magic \"ni2\"): not read; "
                        "store the image as one .nii file (magic \"n+2\")");
      return MX_EINPUT;
    }
    if (memcmp(h + 4, "n+2\0\r\n\032\n", 8)) {
      mx_error(path, 0, "bad magic '%s' at byte 4: a NIfTI-2 file has \"n+2\\0\\r\\n\\032\\n\"",
               mx_show_word(h + 4, 8, word));
      return MX_EINPUT;
    }
    decode_v2(h, n.big, &n);
  }
  strcpy(img->format, n.version == 1 ? "NIfTI-1" : "NIfTI-2");

  /* dims: 3, or more with the extra ones 1 */
  if (n.dim[0] < 3 || n.dim[0] > 7) {
    mx_error(path, 0, "dim[0] = %lld: a 3D image has dim[0] = 3 (or up to 7 with dims past the "
                      "third equal to 1)", (long long)n.dim[0]);
    return MX_EINPUT;
  }
  for (int d = 4; d <= n.dim[0]; d++)
    if (n.dim[d] != 1) {
      mx_error(path, 0, "dim[%d] = %lld: only 3D images are read (dims past the third must be 1)",
               d, (long long)n.dim[d]);
      return MX_EINPUT;
    }
  const int64_t dims[3] = {n.dim[1], n.dim[2], n.dim[3]};
  MX_CHECK(mx_image_check_dims(path, 0, dims));
  int type;
  MX_CHECK(voxel_type(path, n.datatype, &type));

  /* where the voxels start */
  double off = n.vox_offset;
  if (off == 0) off = (double)hsize + 4; /* unset: just after the extension flags */
  if (!(off >= (double)hsize) || off > 1e15 || off != floor(off)) {
    mx_error(path, 0, "vox_offset %g: the voxels must start at a whole byte past the %zu bytes "
                      "of the header", n.vox_offset, hsize);
    return MX_EINPUT;
  }
  const uint64_t at = (uint64_t)off, skip = at - hsize;
  uint64_t skipped;
  MX_CHECK(mx_isrc_skip(s, skip, &skipped));
  if (skipped < skip) {
    mx_error(path, 0, "truncated: vox_offset %llu is past the end of the %s (%llu bytes)",
             (unsigned long long)at, gz ? "inflated data" : "file",
             (unsigned long long)(hsize + skipped));
    return MX_EINPUT;
  }

  /* scl_slope, scl_inter: applied when the slope is a number other than 0,
   * and not the identity (1, 0) */
  const int scale = isfinite(n.slope) && isfinite(n.inter) && n.slope != 0 &&
                    !(n.slope == 1 && n.inter == 0);

  img->nx = dims[0];
  img->ny = dims[1];
  img->nz = dims[2];
  double *A = img->A;
  if (n.sform_code > 0) {
    memcpy(A, n.srow, sizeof n.srow);
  } else if (n.qform_code > 0) {
    qform(&n, A);
  } else {
    memset(A, 0, 12 * sizeof *A);
    A[0] = n.pixdim[1];
    A[5] = n.pixdim[2];
    A[10] = n.pixdim[3];
  }
  MX_CHECK(mx_image_finish(path, img));
  return mx_image_voxels(s, type, n.big, scale, n.slope, n.inter, at, img);
}
