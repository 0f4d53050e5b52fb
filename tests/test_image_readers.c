/* The label image readers (src/io/read_image.c, issue 28): files written
 * here byte by byte from the specifications (nifti1.h, nifti2.h, MetaIO's
 * keys, the INRIA header), read back from disk and from memory:
 *  - NIfTI-1 and NIfTI-2, every voxel type, little- and big-endian, .nii
 *    and .nii.gz (zlib's gzopen), vox_offset past an extension, dim[0] 4
 *    with dim[4] 1; the transform from the sform (a permutation and flip:
 *    not oblique; a shear: oblique), from the qform (30 degrees about z,
 *    qfac -1) and from pixdim alone; scl_slope/scl_inter;
 *  - MetaImage .mha (LOCAL) every type and both byte orders, .mhd + .raw
 *    (HeaderSize n and -1), CompressedData (LOCAL and .zraw), the order
 *    of TransformMatrix (its first three numbers the i axis' direction);
 *  - INRIA .inr every type, CPU decm and sun, a header of two blocks,
 *    .inr.gz, VX.. and XO..;
 *  - the float voxels that are not integers: rounded and counted;
 *  - bad inputs, each MX_EINPUT with no labels and a message naming the
 *    file (and for text headers the line): truncated data and header, dims
 *    0, dims of 2^40 voxels (refused with no allocation at all), unknown
 *    datatypes, bad magic, NaN and too large voxels, MetaImage without
 *    DimSize, with 4 dims, 2 channels, a missing raw file, INR VDIM 2.
 * The labels are (i + 2j + 3k) % 5 (less 2 for signed types), so that an
 * axis read in the wrong order fails. */
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include <zlib.h>

#include "base/common.h"
#include "check.h"
#include "io/read_image.h"
#include "mixoct.h"

static char tmpdir[64];
static char msgs[16384];

static void grab(void *user, int level, const char *text) {
  (void)user;
  const size_t n = strlen(msgs);
  snprintf(msgs + n, sizeof msgs - n, "%s: %s\n", level == MX_MSG_ERROR ? "error" : "warning",
           text);
}

static const char *tpath(const char *name) {
  static char buf[8][256];
  static int k = 0;
  k = (k + 1) % 8;
  snprintf(buf[k], sizeof buf[k], "%s/%s", tmpdir, name);
  return buf[k];
}

/* ---- a byte buffer --------------------------------------------------------- */

typedef struct {
  unsigned char *b;
  size_t n, cap;
} buf;

static void grow(buf *o, size_t n) {
  if (o->n + n <= o->cap) return;
  o->cap = 2 * (o->n + n) + 256;
  o->b = realloc(o->b, o->cap);
  if (!o->b) abort();
}
static void put_bytes(buf *o, const void *p, size_t n) {
  grow(o, n);
  memcpy(o->b + o->n, p, n);
  o->n += n;
}
static void put_zeros(buf *o, size_t n) {
  grow(o, n);
  memset(o->b + o->n, 0, n);
  o->n += n;
}
static void put_str(buf *o, const char *s) { put_bytes(o, s, strlen(s)); }
static void put_fmt(buf *o, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static void put_fmt(buf *o, const char *fmt, ...) {
  char line[1024];
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(line, sizeof line, fmt, ap);
  va_end(ap);
  put_str(o, line);
}
/* an unsigned integer of `bytes` bytes at h */
static void set_u(unsigned char *h, uint64_t v, int bytes, int big) {
  for (int b = 0; b < bytes; b++) h[big ? bytes - 1 - b : b] = (unsigned char)(v >> (8 * b));
}
static void set_f32(unsigned char *h, double v, int big) {
  const float f = (float)v;
  uint32_t u;
  memcpy(&u, &f, 4);
  set_u(h, u, 4, big);
}
static void set_f64(unsigned char *h, double v, int big) {
  uint64_t u;
  memcpy(&u, &v, 8);
  set_u(h, u, 8, big);
}

static void write_file(const char *path, const buf *o) {
  FILE *f = fopen(path, "wb");
  if (!f || fwrite(o->b, 1, o->n, f) != o->n || fclose(f)) {
    perror(path);
    exit(1);
  }
}
static void write_gz(const char *path, const buf *o) {
  gzFile g = gzopen(path, "wb");
  if (!g || gzwrite(g, o->b, (unsigned)o->n) != (int)o->n || gzclose(g) != Z_OK) {
    fprintf(stderr, "%s: gzip write failed\n", path);
    exit(1);
  }
}
static buf zlib_of(const buf *o) {
  buf z = {0};
  uLongf n = compressBound(o->n);
  grow(&z, n);
  if (compress2(z.b, &n, o->b, o->n, 6) != Z_OK) abort();
  z.n = n;
  return z;
}
static unsigned char *slurp(const char *path, size_t *n) {
  FILE *f = fopen(path, "rb");
  if (!f) return NULL;
  fseek(f, 0, SEEK_END);
  const long len = ftell(f);
  fseek(f, 0, SEEK_SET);
  unsigned char *b = malloc((size_t)len + 1);
  if (fread(b, 1, (size_t)len, f) != (size_t)len) abort();
  fclose(f);
  *n = (size_t)len;
  return b;
}

/* ---- voxel types ----------------------------------------------------------- */

typedef struct {
  const char *name;
  int nifti, bytes, is_float, is_signed;
  const char *meta, *inr_type;
} vtype;

static const vtype types[8] = {
    {"uint8", 2, 1, 0, 0, "MET_UCHAR", "unsigned fixed"},
    {"int8", 256, 1, 0, 1, "MET_CHAR", "signed fixed"},
    {"int16", 4, 2, 0, 1, "MET_SHORT", "signed fixed"},
    {"uint16", 512, 2, 0, 0, "MET_USHORT", "unsigned fixed"},
    {"int32", 8, 4, 0, 1, "MET_INT", "signed fixed"},
    {"uint32", 768, 4, 0, 0, "MET_UINT", "unsigned fixed"},
    {"float32", 16, 4, 1, 1, "MET_FLOAT", "float"},
    {"float64", 64, 8, 1, 1, "MET_DOUBLE", "float"},
};

enum { NX = 4, NY = 3, NZ = 5, NV = NX * NY * NZ };

static int label_at(int i, int j, int k, const vtype *t) {
  return (i + 2 * j + 3 * k) % 5 - (t->is_signed ? 2 : 0);
}

/* One voxel's value v in type t. */
static void put_value(buf *o, const vtype *t, double v, int big) {
  unsigned char b[8];
  if (t->is_float && t->bytes == 4)
    set_f32(b, v, big);
  else if (t->is_float)
    set_f64(b, v, big);
  else
    set_u(b, (uint64_t)(int64_t)v, t->bytes, big);
  put_bytes(o, b, (size_t)t->bytes);
}

/* The pattern's voxels, i fastest; frac added to voxels with (i + j + k) % 7
 * == 0 (the count of those returned). */
static int put_voxels(buf *o, const vtype *t, int big, double frac) {
  int n = 0;
  for (int k = 0; k < NZ; k++)
    for (int j = 0; j < NY; j++)
      for (int i = 0; i < NX; i++) {
        double v = label_at(i, j, k, t);
        if (frac != 0 && (i + j + k) % 7 == 0) {
          v += frac;
          n++;
        }
        put_value(o, t, v, big);
      }
  return n;
}

/* ---- reading and checking --------------------------------------------------- */

static int labels_match(const mx_label_image *img, const vtype *t, int scale_a, int scale_b) {
  if (!img->label || img->nx != NX || img->ny != NY || img->nz != NZ) return 0;
  for (int k = 0; k < NZ; k++)
    for (int j = 0; j < NY; j++)
      for (int i = 0; i < NX; i++)
        if (img->label[i + NX * (j + NY * k)] != scale_a * label_at(i, j, k, t) + scale_b) {
          fprintf(stderr, "voxel (%d, %d, %d): %d, expected %d\n", i, j, k,
                  img->label[i + NX * (j + NY * k)], scale_a * label_at(i, j, k, t) + scale_b);
          return 0;
        }
  return 1;
}

static int near(double a, double b) { return fabs(a - b) <= 1e-6 * (1 + fabs(b)); }

static int A_is(const mx_label_image *img, const double *want) {
  for (int e = 0; e < 12; e++)
    if (!near(img->A[e], want[e])) {
      fprintf(stderr, "A[%d] = %.17g, expected %.17g\n", e, img->A[e], want[e]);
      return 0;
    }
  return 1;
}

/* Reads path from disk and from its bytes in memory: both MX_OK, the same
 * image (the memory one checked too and freed). */
static int read_both(const char *path, mx_label_image *img) {
  msgs[0] = '\0';
  int st = mx_read_label_image(path, img);
  if (st != MX_OK) {
    fprintf(stderr, "%s: status %d: %s", path, st, msgs);
    return st;
  }
  size_t n = 0;
  unsigned char *b = slurp(path, &n);
  mx_label_image m;
  const int st2 = mx_read_label_image_mem(path, b, n, &m);
  free(b);
  CHECK(st2 == MX_OK);
  if (st2 == MX_OK) {
    CHECK(m.nx == img->nx && m.ny == img->ny && m.nz == img->nz);
    CHECK(!memcmp(m.A, img->A, sizeof m.A) && m.oblique == img->oblique);
    CHECK(m.rounded == img->rounded && !strcmp(m.format, img->format));
    CHECK(!memcmp(m.label, img->label, (size_t)NV * sizeof *m.label));
    mx_label_image_free(&m);
  }
  return MX_OK;
}

/* Reading path fails with MX_EINPUT, no labels, and a message holding want
 * (and the path); the bytes from memory fail the same way. */
static void expect_bad(const char *path, const char *want) {
  mx_label_image img;
  memset(&img, 0x5a, sizeof img);
  msgs[0] = '\0';
  int st = mx_read_label_image(path, &img);
  CHECK(st == MX_EINPUT);
  CHECK(img.label == NULL && img.nx == 0);
  if (!strstr(msgs, want) || !strstr(msgs, path)) {
    fprintf(stderr, "%s: message '%s' lacks '%s'\n", path, msgs, want);
    mx_test_failures++;
  }
  if (st == MX_OK) mx_label_image_free(&img);
  size_t n;
  unsigned char *b = slurp(path, &n);
  if (!b) return;
  msgs[0] = '\0';
  st = mx_read_label_image_mem(path, b, n, &img);
  free(b);
  CHECK(st == MX_EINPUT && img.label == NULL);
  if (st == MX_OK) mx_label_image_free(&img);
}

/* ---- NIfTI ----------------------------------------------------------------- */

typedef struct {
  int version, big, datatype, qcode, scode;
  int64_t dim[8];
  double pixdim[8], vox_offset, slope, inter, quat[3], qoff[3], srow[12];
  const char *magic;  /* NULL: the single-file magic */
  uint32_t sizeof_hdr; /* 0: 348 or 540 */
} nii_opts;

static nii_opts nii_default(int version, int big, const vtype *t) {
  nii_opts p;
  memset(&p, 0, sizeof p);
  p.version = version;
  p.big = big;
  p.datatype = t->nifti;
  p.dim[0] = 3;
  p.dim[1] = NX;
  p.dim[2] = NY;
  p.dim[3] = NZ;
  for (int d = 4; d < 8; d++) p.dim[d] = 1;
  p.pixdim[0] = 1;
  p.pixdim[1] = 0.5;
  p.pixdim[2] = 0.75;
  p.pixdim[3] = 1.25;
  p.vox_offset = version == 1 ? 352 : 544;
  return p;
}

/* The header and the 4 extension bytes; the caller pads to vox_offset. */
static void nii_header(buf *o, const nii_opts *p) {
  const int big = p->big;
  if (p->version == 1) {
    unsigned char h[352] = {0};
    set_u(h, p->sizeof_hdr ? p->sizeof_hdr : 348, 4, big);
    for (int d = 0; d < 8; d++) {
      set_u(h + 40 + 2 * d, (uint64_t)p->dim[d], 2, big);
      set_f32(h + 76 + 4 * d, p->pixdim[d], big);
    }
    set_u(h + 70, (uint64_t)p->datatype, 2, big);
    set_u(h + 72, 8, 2, big); /* bitpix: not read */
    set_f32(h + 108, p->vox_offset, big);
    set_f32(h + 112, p->slope, big);
    set_f32(h + 116, p->inter, big);
    set_u(h + 252, (uint64_t)p->qcode, 2, big);
    set_u(h + 254, (uint64_t)p->scode, 2, big);
    for (int k = 0; k < 3; k++) {
      set_f32(h + 256 + 4 * k, p->quat[k], big);
      set_f32(h + 268 + 4 * k, p->qoff[k], big);
    }
    for (int k = 0; k < 12; k++) set_f32(h + 280 + 4 * k, p->srow[k], big);
    memcpy(h + 344, p->magic ? p->magic : "n+1", 4);
    put_bytes(o, h, sizeof h);
  } else {
    unsigned char h[544] = {0};
    set_u(h, p->sizeof_hdr ? p->sizeof_hdr : 540, 4, big);
    memcpy(h + 4, p->magic ? p->magic : "n+2\0\r\n\032\n", 8);
    set_u(h + 12, (uint64_t)p->datatype, 2, big);
    for (int d = 0; d < 8; d++) {
      set_u(h + 16 + 8 * d, (uint64_t)p->dim[d], 8, big);
      set_f64(h + 104 + 8 * d, p->pixdim[d], big);
    }
    set_u(h + 168, (uint64_t)p->vox_offset, 8, big);
    set_f64(h + 176, p->slope, big);
    set_f64(h + 184, p->inter, big);
    set_u(h + 344, (uint64_t)p->qcode, 4, big);
    set_u(h + 348, (uint64_t)p->scode, 4, big);
    for (int k = 0; k < 3; k++) {
      set_f64(h + 352 + 8 * k, p->quat[k], big);
      set_f64(h + 376 + 8 * k, p->qoff[k], big);
    }
    for (int k = 0; k < 12; k++) set_f64(h + 400 + 8 * k, p->srow[k], big);
    put_bytes(o, h, sizeof h);
  }
  if (o->n < (size_t)p->vox_offset) put_zeros(o, (size_t)p->vox_offset - o->n);
}

static void test_nifti_types(void) {
  const double diag[12] = {0.5, 0, 0, 0, 0, 0.75, 0, 0, 0, 0, 1.25, 0};
  for (int version = 1; version <= 2; version++)
    for (int big = 0; big <= 1; big++)
      for (int t = 0; t < 8; t++)
        for (int gz = 0; gz <= 1; gz++) {
          buf o = {0};
          nii_opts p = nii_default(version, big, &types[t]);
          nii_header(&o, &p);
          put_voxels(&o, &types[t], big, 0);
          char name[64];
          snprintf(name, sizeof name, "v%d_%s_%s.nii%s", version, big ? "be" : "le", types[t].name,
                   gz ? ".gz" : "");
          const char *path = tpath(name);
          if (gz)
            write_gz(path, &o);
          else
            write_file(path, &o);
          free(o.b);
          mx_label_image img;
          if (read_both(path, &img) != MX_OK) {
            CHECK(!"read");
            continue;
          }
          CHECK(!strcmp(img.format, version == 1 ? "NIfTI-1" : "NIfTI-2"));
          CHECK(labels_match(&img, &types[t], 1, 0));
          CHECK(A_is(&img, diag));
          CHECK(img.oblique == 0 && img.rounded == 0);
          CHECK(near(img.spacing[0], 0.5) && near(img.spacing[1], 0.75) && near(img.spacing[2], 1.25));
          mx_label_image_free(&img);
        }
}

/* Writes a NIfTI image of int16 labels with these options. */
static const char *nii_file(const char *name, const nii_opts *p, int gz) {
  buf o = {0};
  nii_header(&o, p);
  put_voxels(&o, &types[2], p->big, 0);
  const char *path = tpath(name);
  if (gz)
    write_gz(path, &o);
  else
    write_file(path, &o);
  free(o.b);
  return path;
}

static void test_nifti_transforms(void) {
  mx_label_image img;
  for (int version = 1; version <= 2; version++) {
    /* sform: i along -y, j along z, k along x (a permutation and flip) */
    nii_opts p = nii_default(version, 0, &types[2]);
    p.scode = 1;
    p.qcode = 1; /* the sform comes first */
    p.quat[2] = 0.5;
    const double s1[12] = {0, 0, 1.5, 10, -0.5, 0, 0, 20, 0, 2, 0, 30};
    memcpy(p.srow, s1, sizeof s1);
    if (read_both(nii_file("sform.nii", &p, 0), &img) == MX_OK) {
      CHECK(A_is(&img, s1) && img.oblique == 0);
      CHECK(near(img.spacing[0], 0.5) && near(img.spacing[1], 2) && near(img.spacing[2], 1.5));
      CHECK(labels_match(&img, &types[2], 1, 0));
      mx_label_image_free(&img);
    }
    /* sform with a shear: oblique */
    const double s2[12] = {1, 0.5, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};
    memcpy(p.srow, s2, sizeof s2);
    if (read_both(nii_file("shear.nii", &p, 0), &img) == MX_OK) {
      CHECK(A_is(&img, s2) && img.oblique == 1);
      CHECK(near(img.spacing[1], sqrt(1.25)));
      mx_label_image_free(&img);
    }
    /* qform: 30 degrees about z, voxel 1 x 2 x 3, qfac -1 */
    p = nii_default(version, 1, &types[2]);
    p.qcode = 1;
    p.quat[2] = sin(M_PI / 12);
    p.qoff[0] = 5;
    p.qoff[1] = -6;
    p.qoff[2] = 7;
    p.pixdim[0] = -1;
    p.pixdim[1] = 1;
    p.pixdim[2] = 2;
    p.pixdim[3] = 3;
    const double c = cos(M_PI / 6), s = sin(M_PI / 6);
    const double q[12] = {c, -2 * s, 0, 5, s, 2 * c, 0, -6, 0, 0, -3, 7};
    if (read_both(nii_file("qform.nii.gz", &p, 1), &img) == MX_OK) {
      CHECK(A_is(&img, q) && img.oblique == 1);
      CHECK(near(img.spacing[0], 1) && near(img.spacing[1], 2) && near(img.spacing[2], 3));
      CHECK(labels_match(&img, &types[2], 1, 0));
      mx_label_image_free(&img);
    }
    /* dim[0] 4 with dim[4] 1; vox_offset past an extension of 48 bytes */
    p = nii_default(version, 0, &types[2]);
    p.dim[0] = 4;
    p.vox_offset += 48;
    if (read_both(nii_file("dim4.nii", &p, 0), &img) == MX_OK) {
      CHECK(labels_match(&img, &types[2], 1, 0));
      mx_label_image_free(&img);
    }
    /* scl_slope 2, scl_inter 1: 2 v + 1 */
    p = nii_default(version, 0, &types[2]);
    p.slope = 2;
    p.inter = 1;
    if (read_both(nii_file("scaled.nii", &p, 0), &img) == MX_OK) {
      CHECK(labels_match(&img, &types[2], 2, 1) && img.rounded == 0);
      mx_label_image_free(&img);
    }
    /* slope 0.5: the odd values are not integers */
    p.slope = 0.5;
    p.inter = 0;
    if (read_both(nii_file("half.nii", &p, 0), &img) == MX_OK) {
      size_t odd = 0;
      for (int k = 0; k < NZ; k++)
        for (int j = 0; j < NY; j++)
          for (int i = 0; i < NX; i++) {
            const int v = label_at(i, j, k, &types[2]);
            odd += v % 2 != 0;
            CHECK(img.label[i + NX * (j + NY * k)] == (int)round(0.5 * v));
          }
      CHECK(img.rounded == odd && odd > 0);
      CHECK(strstr(msgs, "not integers") != NULL);
      mx_label_image_free(&img);
    }
  }
}

static void test_float_rounding(void) {
  for (int t = 6; t < 8; t++) {
    buf o = {0};
    nii_opts p = nii_default(1, 0, &types[t]);
    nii_header(&o, &p);
    const int n = put_voxels(&o, &types[t], 0, 0.25);
    const char *path = tpath(t == 6 ? "frac32.nii" : "frac64.nii");
    write_file(path, &o);
    free(o.b);
    mx_label_image img;
    if (read_both(path, &img) == MX_OK) {
      CHECK(img.rounded == (size_t)n && n > 0);
      CHECK(labels_match(&img, &types[t], 1, 0));
      char want[64];
      snprintf(want, sizeof want, "%d voxels were not integers", n);
      CHECK(strstr(msgs, want) != NULL);
      mx_label_image_free(&img);
    }
  }
}

static void test_nifti_bad(void) {
  const vtype *t16 = &types[2];
  nii_opts p = nii_default(1, 0, t16);
  buf o = {0};
  nii_header(&o, &p);
  put_voxels(&o, t16, 0, 0);
  /* truncated data, plain and gzip */
  buf cut = o;
  cut.n--;
  write_file(tpath("cut.nii"), &cut);
  expect_bad(tpath("cut.nii"), "truncated: the voxels need 120 bytes from byte 352 of the file, it has 119");
  write_gz(tpath("cut.nii.gz"), &cut);
  expect_bad(tpath("cut.nii.gz"), "truncated");
  /* a gzip stream cut short */
  write_gz(tpath("whole.nii.gz"), &o);
  size_t zn = 0;
  unsigned char *zb = slurp(tpath("whole.nii.gz"), &zn);
  buf zcut = {zb, zn - 30, zn};
  write_file(tpath("zcut.nii.gz"), &zcut);
  expect_bad(tpath("zcut.nii.gz"), "truncated");
  /* corrupt deflate data */
  zb[zn / 2] ^= 0xff;
  zb[zn / 2 + 1] ^= 0x55;
  buf zbad = {zb, zn, zn};
  write_file(tpath("zbad.nii.gz"), &zbad);
  mx_label_image img;
  msgs[0] = '\0';
  CHECK(mx_read_label_image(tpath("zbad.nii.gz"), &img) == MX_EINPUT && !img.label);
  free(zb);
  /* truncated header */
  buf head = o;
  head.n = 100;
  write_file(tpath("head.nii"), &head);
  expect_bad(tpath("head.nii"), "truncated header: 100 bytes of the 348");
  free(o.b);

  struct {
    const char *name, *want;
    int version;
    void (*edit)(nii_opts *);
  } cases[] = {
      {"dim0.nii", "0 voxels along j", 1, NULL},
      {"huge1.nii", "voxels: more than 2^31 - 1", 1, NULL},
      {"huge2.nii", "16384 x 8192 x 8192 voxels", 2, NULL},
      {"int64.nii", "datatype 1024 (int64)", 1, NULL},
      {"rgb.nii", "datatype 128 (rgb24)", 2, NULL},
      {"magic.nii", "bad magic", 1, NULL},
      {"magic2.nii", "bad magic", 2, NULL},
      {"pair.nii", "pair", 1, NULL},
      {"dim4.nii", "dim[4] = 2", 1, NULL},
      {"dim2.nii", "dim[0] = 2", 2, NULL},
      {"sizeof.nii", "sizeof_hdr is 349", 1, NULL},
      {"off.nii", "vox_offset 100", 1, NULL},
      {"zeropix.nii", "axis k the length 0", 1, NULL},
  };
  for (size_t c = 0; c < sizeof cases / sizeof *cases; c++) {
    p = nii_default(cases[c].version, c % 2, t16);
    const char *n = cases[c].name;
    if (!strcmp(n, "dim0.nii")) p.dim[2] = 0;
    if (!strcmp(n, "huge1.nii")) p.dim[1] = p.dim[2] = p.dim[3] = 32767;
    if (!strcmp(n, "huge2.nii")) {
      p.dim[1] = (int64_t)1 << 14;
      p.dim[2] = p.dim[3] = (int64_t)1 << 13;
    }
    if (!strcmp(n, "int64.nii")) p.datatype = 1024;
    if (!strcmp(n, "rgb.nii")) p.datatype = 128;
    if (!strcmp(n, "magic.nii")) p.magic = "n+2";
    if (!strcmp(n, "magic2.nii")) p.magic = "n+1\0\0\0\0";
    if (!strcmp(n, "pair.nii")) p.magic = "ni1";
    if (!strcmp(n, "dim4.nii")) {
      p.dim[0] = 4;
      p.dim[4] = 2;
    }
    if (!strcmp(n, "dim2.nii")) p.dim[0] = 2;
    if (!strcmp(n, "sizeof.nii")) p.sizeof_hdr = 349;
    if (!strcmp(n, "off.nii")) p.vox_offset = 100;
    if (!strcmp(n, "zeropix.nii")) p.pixdim[3] = 0;
    o = (buf){0};
    nii_header(&o, &p);
    put_voxels(&o, t16, p.big, 0);
    write_file(tpath(n), &o);
    /* dims of 2^40 voxels: refused before any allocation */
    if (!strcmp(n, "huge2.nii")) {
      mx_alloc_fail_countdown(-1);
      msgs[0] = '\0';
      CHECK(mx_read_label_image_mem("huge2.nii", o.b, o.n, &img) == MX_EINPUT && !img.label);
      CHECK(mx_alloc_count() == 0);
      mx_alloc_fail_countdown(0);
    }
    free(o.b);
    expect_bad(tpath(n), cases[c].want);
  }

  /* a NaN voxel, a voxel of 3e9 (uint32), -3e9 (float64) */
  for (int c = 0; c < 3; c++) {
    const vtype *t = &types[c == 0 ? 6 : c == 1 ? 5 : 7];
    p = nii_default(2, c == 1, t);
    o = (buf){0};
    nii_header(&o, &p);
    put_voxels(&o, t, p.big, 0);
    const size_t at = (size_t)p.vox_offset + (size_t)t->bytes * (1 + NX * (2 + NY * 3));
    if (c == 0)
      set_f32(o.b + at, NAN, 0);
    else if (c == 1)
      set_u(o.b + at, 3000000000u, 4, 1);
    else
      set_f64(o.b + at, -3e9, 0);
    const char *path = tpath(c == 0 ? "nan.nii" : c == 1 ? "big.nii" : "neg.nii");
    write_file(path, &o);
    free(o.b);
    expect_bad(path, c == 0 ? "voxel (1, 2, 3) (number 45) is nan" : "voxel (1, 2, 3) (number 45) is");
  }
  /* not an image at all, under an extension that names none: by its bytes */
  o = (buf){0};
  put_str(&o, "\x01\x02\x03 nothing here");
  write_file(tpath("junk.bin"), &o);
  free(o.b);
  expect_bad(tpath("junk.bin"), "not a label image");
  expect_bad(tpath("missing.nii"), "cannot open");
}

/* An image under a name that tells no format: found from its first bytes. */
static void test_sniff(void) {
  nii_opts p = nii_default(2, 1, &types[3]);
  buf o = {0};
  nii_header(&o, &p);
  put_voxels(&o, &types[3], 1, 0);
  write_gz(tpath("image.gzdata"), &o);
  free(o.b);
  mx_label_image img;
  if (read_both(tpath("image.gzdata"), &img) == MX_OK) {
    CHECK(!strcmp(img.format, "NIfTI-2"));
    CHECK(labels_match(&img, &types[3], 1, 0));
    mx_label_image_free(&img);
  }
}

/* ---- MetaImage ------------------------------------------------------------- */

/* A header; extra lines (may be "") before ElementDataFile. */
static void meta_header(buf *o, const vtype *t, int msb, const char *extra, const char *datafile) {
  put_str(o, "ObjectType = Image\nNDims = 3\n");
  put_fmt(o, "DimSize = %d %d %d\n", NX, NY, NZ);
  put_fmt(o, "ElementType = %s\n", t->meta);
  put_fmt(o, "BinaryData = True\nBinaryDataByteOrderMSB = %s\n", msb ? "True" : "False");
  put_str(o, "ElementSpacing = 0.5 0.75 1.25\nOffset = 1 2 3\n");
  put_str(o, extra);
  put_fmt(o, "ElementDataFile = %s\n", datafile);
}

static void test_metaimage(void) {
  const double diag[12] = {0.5, 0, 0, 1, 0, 0.75, 0, 2, 0, 0, 1.25, 3};
  mx_label_image img;
  for (int t = 0; t < 8; t++)
    for (int msb = 0; msb <= 1; msb++) {
      buf o = {0};
      meta_header(&o, &types[t], msb, "", "LOCAL");
      put_voxels(&o, &types[t], msb, 0);
      char name[64];
      snprintf(name, sizeof name, "m_%s_%d.mha", types[t].name, msb);
      write_file(tpath(name), &o);
      free(o.b);
      if (read_both(tpath(name), &img) == MX_OK) {
        CHECK(!strcmp(img.format, "MetaImage"));
        CHECK(labels_match(&img, &types[t], 1, 0) && A_is(&img, diag) && !img.oblique);
        mx_label_image_free(&img);
      }
    }
  /* TransformMatrix: its first three numbers the direction of i (here y),
   * the next three j's (-x), the last three k's (z) */
  buf o = {0};
  meta_header(&o, &types[2], 0, "TransformMatrix = 0 1 0 -1 0 0 0 0 1\nComment = x = y\n", "LOCAL");
  put_voxels(&o, &types[2], 0, 0);
  write_file(tpath("perm.mha"), &o);
  free(o.b);
  const double perm[12] = {0, -0.75, 0, 1, 0.5, 0, 0, 2, 0, 0, 1.25, 3};
  if (read_both(tpath("perm.mha"), &img) == MX_OK) {
    CHECK(A_is(&img, perm) && img.oblique == 0);
    mx_label_image_free(&img);
  }
  /* a rotation by 30 degrees about z: oblique */
  const double c = cos(M_PI / 6), s = sin(M_PI / 6);
  char rot[256];
  snprintf(rot, sizeof rot, "Orientation = %.17g %.17g 0 %.17g %.17g 0 0 0 1\n", c, s, -s, c);
  o = (buf){0};
  meta_header(&o, &types[0], 0, rot, "LOCAL");
  put_voxels(&o, &types[0], 0, 0);
  write_file(tpath("rot.mha"), &o);
  free(o.b);
  const double rA[12] = {0.5 * c, -0.75 * s, 0, 1, 0.5 * s, 0.75 * c, 0, 2, 0, 0, 1.25, 3};
  if (read_both(tpath("rot.mha"), &img) == MX_OK) {
    CHECK(A_is(&img, rA) && img.oblique == 1);
    mx_label_image_free(&img);
  }
  /* .mhd + .raw, with HeaderSize 16 and -1 (the data at the end) */
  for (int hs = 0; hs < 2; hs++) {
    o = (buf){0};
    meta_header(&o, &types[4], 1, hs ? "HeaderSize = -1\r\n" : "HeaderSize = 16\r\n",
                hs ? "b.raw" : "a.raw");
    write_file(tpath(hs ? "b.mhd" : "a.mhd"), &o);
    free(o.b);
    o = (buf){0};
    put_zeros(&o, hs ? 7 : 16);
    put_voxels(&o, &types[4], 1, 0);
    write_file(tpath(hs ? "b.raw" : "a.raw"), &o);
    free(o.b);
    msgs[0] = '\0';
    if (mx_read_label_image(tpath(hs ? "b.mhd" : "a.mhd"), &img) == MX_OK) {
      CHECK(labels_match(&img, &types[4], 1, 0) && A_is(&img, diag));
      mx_label_image_free(&img);
    } else {
      fprintf(stderr, "%s", msgs);
      CHECK(!".mhd");
    }
  }
  /* from memory a .mhd's data is not looked for */
  o = (buf){0};
  meta_header(&o, &types[4], 1, "", "a.raw");
  msgs[0] = '\0';
  CHECK(mx_read_label_image_mem(tpath("a.mhd"), o.b, o.n, &img) == MX_EINPUT && !img.label);
  CHECK(strstr(msgs, "LOCAL") != NULL);
  free(o.b);
  /* CompressedData, LOCAL and a .zraw */
  for (int t = 0; t < 8; t += 3) {
    buf v = {0};
    put_voxels(&v, &types[t], 0, 0);
    buf z = zlib_of(&v);
    o = (buf){0};
    char extra[128];
    snprintf(extra, sizeof extra, "CompressedData = True\nCompressedDataSize = %zu\n", z.n);
    meta_header(&o, &types[t], 0, extra, "LOCAL");
    put_bytes(&o, z.b, z.n);
    write_file(tpath("z.mha"), &o);
    if (read_both(tpath("z.mha"), &img) == MX_OK) {
      CHECK(labels_match(&img, &types[t], 1, 0));
      mx_label_image_free(&img);
    }
    /* cut short */
    o.n -= 5;
    write_file(tpath("zcut.mha"), &o);
    expect_bad(tpath("zcut.mha"), "truncated");
    free(o.b);
    o = (buf){0};
    meta_header(&o, &types[t], 0, "CompressedData = True\n", "z.zraw");
    write_file(tpath("z.mhd"), &o);
    write_file(tpath("z.zraw"), &z);
    free(o.b);
    msgs[0] = '\0';
    if (mx_read_label_image(tpath("z.mhd"), &img) == MX_OK) {
      CHECK(labels_match(&img, &types[t], 1, 0));
      mx_label_image_free(&img);
    } else {
      CHECK(!"z.mhd");
    }
    free(v.b);
    free(z.b);
  }
  /* bad headers: the message names the file and the line */
  struct {
    const char *name, *text, *want;
  } bad[] = {
      {"nodims.mha", "ObjectType = Image\nNDims = 3\nElementType = MET_UCHAR\nElementDataFile = LOCAL\n",
       "nodims.mha:4: no DimSize"},
      {"ndims4.mha", "NDims = 4\nDimSize = 4 3 5 1\nElementType = MET_UCHAR\nElementDataFile = LOCAL\n",
       "ndims4.mha:1: NDims = 4"},
      {"dims4.mha", "NDims = 3\nDimSize = 4 3 5 1\nElementType = MET_UCHAR\nElementDataFile = LOCAL\n",
       "dims4.mha:2: DimSize has 4 numbers"},
      {"chan.mha", "NDims = 3\nDimSize = 4 3 5\nElementNumberOfChannels = 2\nElementType = MET_UCHAR\n"
                   "ElementDataFile = LOCAL\n", "chan.mha:3: ElementNumberOfChannels = 2"},
      {"long.mha", "NDims = 3\nDimSize = 4 3 5\nElementType = MET_LONG_LONG\nElementDataFile = LOCAL\n",
       "long.mha:3: ElementType = 'MET_LONG_LONG'"},
      {"noeq.mha", "NDims = 3\nDimSize 4 3 5\n", "noeq.mha:2: 'DimSize 4 3 5' is not a line"},
      {"noend.mha", "NDims = 3\nDimSize = 4 3 5\n", "noend.mha:2: the header ends without ElementDataFile"},
      {"zero.mha", "NDims = 3\nDimSize = 4 0 5\nElementType = MET_UCHAR\nElementDataFile = LOCAL\n",
       "zero.mha:2: 0 voxels along j"},
      {"huge.mha", "NDims = 3\nDimSize = 16384 8192 8192\nElementType = MET_UCHAR\nElementDataFile = LOCAL\n",
       "huge.mha:2: 16384 x 8192 x 8192 voxels"},
      {"trunc.mha", "NDims = 3\nDimSize = 4 3 5\nElementType = MET_SHORT\nElementDataFile = LOCAL\n0123",
       "truncated: the voxels need 120 bytes from byte 74 of the file, it has 4"},
      {"norw.mhd", "NDims = 3\nDimSize = 4 3 5\nElementType = MET_SHORT\nElementDataFile = gone.raw\n",
       "norw.mhd:4: ElementDataFile = 'gone.raw': cannot open"},
      {"list.mhd", "NDims = 3\nDimSize = 4 3 5\nElementType = MET_SHORT\nElementDataFile = LIST\n",
       "list.mhd:4: ElementDataFile = 'LIST'"},
      {"sp.mha", "NDims = 3\nDimSize = 4 3 5\nElementSpacing = 1 nan 1\nElementType = MET_SHORT\n"
                 "ElementDataFile = LOCAL\n", "sp.mha:3: ElementSpacing: 'nan' is not a finite"},
      {"obj.mha", "ObjectType = Tube\n", "obj.mha:1: ObjectType = 'Tube'"},
  };
  for (size_t b = 0; b < sizeof bad / sizeof *bad; b++) {
    o = (buf){0};
    put_str(&o, bad[b].text);
    write_file(tpath(bad[b].name), &o);
    free(o.b);
    expect_bad(tpath(bad[b].name), bad[b].want);
  }
}

/* ---- INRIA ----------------------------------------------------------------- */

static void inr_file(const char *name, const vtype *t, const char *cpu, const char *extra,
                     int gz, int cut) {
  buf o = {0};
  put_str(&o, "#INRIMAGE-4#{\n");
  put_fmt(&o, "XDIM=%d\nYDIM=%d\nZDIM=%d\nVDIM=1\n", NX, NY, NZ);
  put_fmt(&o, "TYPE=%s\nPIXSIZE=%d bits\nSCALE=2**0\nCPU=%s\n", t->inr_type, 8 * t->bytes, cpu);
  put_str(&o, "VX=0.5\nVY=0.75\nVZ=1.25\n");
  put_str(&o, extra);
  const size_t hl = (o.n + 4 + 255) / 256 * 256;
  grow(&o, hl - o.n);
  memset(o.b + o.n, '\n', hl - 4 - o.n);
  o.n = hl - 4;
  put_str(&o, "##}\n");
  put_voxels(&o, t, !strcmp(cpu, "sun") || !strcmp(cpu, "sgi"), 0);
  o.n -= (size_t)cut;
  if (gz)
    write_gz(tpath(name), &o);
  else
    write_file(tpath(name), &o);
  free(o.b);
}

static void test_inr(void) {
  const double diag[12] = {0.5, 0, 0, 0, 0, 0.75, 0, 0, 0, 0, 1.25, 0};
  mx_label_image img;
  for (int t = 0; t < 8; t++)
    for (int c = 0; c < 2; c++) {
      char name[64];
      snprintf(name, sizeof name, "i_%s_%d.inr%s", types[t].name, c, c ? ".gz" : "");
      inr_file(name, &types[t], c ? "sun" : "decm", "", c, 0);
      if (read_both(tpath(name), &img) == MX_OK) {
        CHECK(!strcmp(img.format, "INR"));
        CHECK(labels_match(&img, &types[t], 1, 0) && A_is(&img, diag) && !img.oblique);
        mx_label_image_free(&img);
      }
    }
  /* two header blocks, an origin */
  char extra[600] = "XO=-1\nYO=2.5\nZO=3\n";
  for (int k = 0; k < 10; k++) strcat(extra, "#a comment line of the header, 32\n");
  inr_file("two.inr", &types[2], "pc", extra, 0, 0);
  const double org[12] = {0.5, 0, 0, -1, 0, 0.75, 0, 2.5, 0, 0, 1.25, 3};
  if (read_both(tpath("two.inr"), &img) == MX_OK) {
    CHECK(labels_match(&img, &types[2], 1, 0) && A_is(&img, org));
    mx_label_image_free(&img);
  }
  inr_file("vdim.inr", &types[0], "decm", "VDIM=2\n", 0, 0);
  expect_bad(tpath("vdim.inr"), "VDIM=2");
  inr_file("cut.inr", &types[3], "decm", "", 0, 1);
  expect_bad(tpath("cut.inr"), "truncated: the voxels need 120 bytes from byte 256 of the file, it has 119");
  inr_file("cut.inr.gz", &types[3], "decm", "", 1, 1);
  expect_bad(tpath("cut.inr.gz"), "truncated");
  inr_file("cpu.inr", &types[3], "vax", "", 0, 0);
  expect_bad(tpath("cpu.inr"), "cpu.inr:9: CPU=vax");
  inr_file("zdim.inr", &types[3], "decm", "ZDIM=0\n", 0, 0);
  expect_bad(tpath("zdim.inr"), "0 voxels along k");
  buf o = {0};
  put_str(&o, "#INRIMAGE-4#{\nXDIM=4\nYDIM=3\n");
  write_file(tpath("head.inr"), &o);
  free(o.b);
  expect_bad(tpath("head.inr"), "truncated header");
  o = (buf){0};
  put_str(&o, "#INRIMAGE-5#{\n");
  put_zeros(&o, 300);
  write_file(tpath("magic.inr"), &o);
  free(o.b);
  expect_bad(tpath("magic.inr"), "bad magic");
  o = (buf){0};
  put_str(&o, "#INRIMAGE-4#{\nXDIM=4\nYDIM=3\nZDIM=5\nTYPE=unsigned fixed\nPIXSIZE=64 bits\n");
  grow(&o, 256);
  memset(o.b + o.n, '\n', 252 - o.n);
  o.n = 252;
  put_str(&o, "##}\n");
  put_zeros(&o, 8 * NV);
  write_file(tpath("u64.inr"), &o);
  free(o.b);
  expect_bad(tpath("u64.inr"), "u64.inr:6: PIXSIZE=64 bits with TYPE=unsigned fixed");
}

/* Allocation failures on a compressed read: MX_ENOMEM, no labels (and, under
 * valgrind or ASan, no leak). */
static void test_alloc_fail(void) {
  const char *path = tpath("z.mhd");
  mx_label_image img;
  mx_alloc_fail_countdown(-1);
  CHECK(mx_read_label_image(path, &img) == MX_OK);
  const long n = mx_alloc_count();
  mx_label_image_free(&img);
  CHECK(n >= 3);
  for (long k = 1; k <= n; k++) {
    mx_alloc_fail_countdown(k);
    const int st = mx_read_label_image(path, &img);
    CHECK(st == MX_ENOMEM && img.label == NULL);
  }
  mx_alloc_fail_countdown(0);
}

int main(void) {
  snprintf(tmpdir, sizeof tmpdir, "/tmp/mixoct_images_XXXXXX");
  if (!mkdtemp(tmpdir)) {
    perror("mkdtemp");
    return 1;
  }
  mx_msg_fn = grab;
  test_nifti_types();
  test_nifti_transforms();
  test_float_rounding();
  test_nifti_bad();
  test_sniff();
  test_metaimage();
  test_inr();
  test_alloc_fail();
  mx_msg_fn = NULL;
  char cmd[128];
  snprintf(cmd, sizeof cmd, "rm -rf '%s'", tmpdir);
  if (system(cmd) != 0) fprintf(stderr, "could not remove %s\n", tmpdir);
  return TEST_DONE();
}
