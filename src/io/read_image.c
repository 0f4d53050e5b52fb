/* mixoct: label images (io/read_image.h): the dispatch on the extension or
 * the first bytes, and the part the formats share (io/image_src.h): the
 * byte source with zlib inflation, the dims check, the voxels' conversion
 * to int32 labels and the transform's check. */
#include "io/read_image.h"

#include <errno.h>
#include <limits.h>
#include <math.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>

#include "base/common.h"
#include "geom/affine.h"
#include "io/image_src.h"

enum { ZCHUNK = 1 << 16 };

/* ---- the byte source ------------------------------------------------------ */

int mx_isrc_open_file(mx_isrc *s, const char *path) {
  memset(s, 0, sizeof *s);
  s->path = path;
  FILE *fp = fopen(path, "rb");
  if (!fp) {
    mx_error(path, 0, "cannot open: %s", strerror(errno));
    return MX_EINPUT;
  }
  struct stat st;
  if (fstat(fileno(fp), &st) != 0) {
    mx_error(path, 0, "cannot read: %s", strerror(errno));
    fclose(fp);
    return MX_EINPUT;
  }
  if (!S_ISREG(st.st_mode)) {
    mx_error(path, 0, "cannot read: %s", S_ISDIR(st.st_mode) ? "is a directory" : "not a regular file");
    fclose(fp);
    return MX_EINPUT;
  }
  s->fp = fp;
  s->raw_size = (uint64_t)st.st_size;
  return MX_OK;
}

void mx_isrc_open_mem(mx_isrc *s, const char *name, const unsigned char *d, size_t n) {
  memset(s, 0, sizeof *s);
  s->path = name;
  s->mem = d;
  s->mem_len = d ? n : 0;
  s->raw_size = s->mem_len;
}

/* Raw bytes (no inflation). */
static int raw_read(mx_isrc *s, void *buf, size_t n, size_t *got) {
  *got = 0;
  if (s->fp) {
    const size_t r = fread(buf, 1, n, s->fp);
    if (r < n && ferror(s->fp)) {
      mx_error(s->path, 0, "cannot read: %s", strerror(errno));
      return MX_EINPUT;
    }
    *got = r;
  } else {
    const size_t left = s->mem_len - s->mem_pos, r = n < left ? n : left;
    if (r) memcpy(buf, s->mem + s->mem_pos, r);
    s->mem_pos += r;
    *got = r;
  }
  s->raw_pos += *got;
  return MX_OK;
}

int mx_isrc_inflate(mx_isrc *s) {
  if (s->fp && !s->zin) {
    s->zin = mx_alloc(ZCHUNK);
    if (!s->zin) return MX_ENOMEM;
  }
  memset(&s->zs, 0, sizeof s->zs);
  if (inflateInit2(&s->zs, 15 + 32) != Z_OK) { /* zlib or gzip, told by the header */
    mx_error(s->path, 0, "out of memory (zlib's inflate state)");
    return MX_ENOMEM;
  }
  s->z = s->z_init = 1;
  return MX_OK;
}

int mx_isrc_gzip_auto(mx_isrc *s, int *gz) {
  unsigned char m[2] = {0, 0};
  size_t got = 0;
  *gz = 0;
  if (s->fp) {
    const off_t at = ftello(s->fp);
    int st = raw_read(s, m, 2, &got);
    if (st != MX_OK) return st;
    if (at < 0 || fseeko(s->fp, at, SEEK_SET) != 0) {
      mx_error(s->path, 0, "cannot seek: %s", strerror(errno));
      return MX_EINPUT;
    }
    s->raw_pos -= got;
  } else {
    got = s->mem_len - s->mem_pos < 2 ? s->mem_len - s->mem_pos : 2;
    if (got) memcpy(m, s->mem + s->mem_pos, got);
  }
  if (got == 2 && m[0] == 0x1f && m[1] == 0x8b) {
    *gz = 1;
    s->z_gzip = 1;
    return mx_isrc_inflate(s);
  }
  return MX_OK;
}

/* More input for inflate: 0 when there is none. */
static int z_refill(mx_isrc *s, int *status) {
  *status = MX_OK;
  if (s->fp) {
    size_t got;
    *status = raw_read(s, s->zin, ZCHUNK, &got);
    s->zs.next_in = s->zin;
    s->zs.avail_in = (uInt)got;
    return got > 0;
  }
  const size_t left = s->mem_len - s->mem_pos, r = left < (1u << 30) ? left : (1u << 30);
  s->zs.next_in = (Bytef *)(uintptr_t)(s->mem + s->mem_pos);
  s->zs.avail_in = (uInt)r;
  s->mem_pos += r;
  s->raw_pos += r;
  return r > 0;
}

static int z_read(mx_isrc *s, unsigned char *buf, size_t n, size_t *got) {
  *got = 0;
  while (n > 0 && !s->z_end) {
    const size_t part = n < (1u << 30) ? n : (1u << 30);
    s->zs.next_out = buf;
    s->zs.avail_out = (uInt)part;
    while (s->zs.avail_out > 0 && !s->z_end) {
      if (s->zs.avail_in == 0) {
        int st;
        const int more = z_refill(s, &st);
        if (st != MX_OK) return st;
        if (!more) {
          s->z_end = s->z_cut = 1; /* cut short: the caller counts the bytes */
          break;
        }
      }
      const int r = inflate(&s->zs, Z_NO_FLUSH);
      if (r == Z_STREAM_END) {
        /* gzip members may follow one another (as gzip -c a b > c writes) */
        int st = MX_OK;
        if (s->z_gzip && s->zs.avail_in == 0) z_refill(s, &st);
        if (st != MX_OK) return st;
        if (s->z_gzip && s->zs.avail_in > 0 && s->zs.next_in[0] == 0x1f) {
          inflateReset(&s->zs);
        } else {
          s->z_end = 1;
        }
      } else if (r == Z_MEM_ERROR) {
        mx_error(s->path, 0, "out of memory (inflating the data)");
        return MX_ENOMEM;
      } else if (r != Z_OK && r != Z_BUF_ERROR) {
        mx_error(s->path, 0, "corrupt compressed data after %llu inflated bytes (zlib: %s)",
                 (unsigned long long)(s->pos + *got + (part - s->zs.avail_out)),
                 s->zs.msg ? s->zs.msg : "bad data");
        return MX_EINPUT;
      }
    }
    const size_t done = part - s->zs.avail_out;
    *got += done;
    buf += done;
    n -= done;
    if (done < part) break;
  }
  return MX_OK;
}

int mx_isrc_read(mx_isrc *s, void *buf, size_t n, size_t *got) {
  const int st = s->z ? z_read(s, buf, n, got) : raw_read(s, buf, n, got);
  s->pos += *got;
  return st;
}

int64_t mx_isrc_left(const mx_isrc *s) {
  if (s->z) return -1;
  return (int64_t)(s->raw_size - (s->raw_pos < s->raw_size ? s->raw_pos : s->raw_size));
}

int mx_isrc_skip(mx_isrc *s, uint64_t n, uint64_t *done) {
  *done = 0;
  if (!s->z) {
    const uint64_t left = (uint64_t)mx_isrc_left(s), k = n < left ? n : left;
    if (s->fp && fseeko(s->fp, (off_t)(s->raw_pos + k), SEEK_SET) != 0) {
      mx_error(s->path, 0, "cannot seek: %s", strerror(errno));
      return MX_EINPUT;
    }
    if (!s->fp) s->mem_pos += (size_t)k;
    s->raw_pos += k;
    s->pos += k;
    *done = k;
    return MX_OK;
  }
  unsigned char tmp[4096];
  while (*done < n) {
    size_t got;
    const uint64_t want = n - *done < sizeof tmp ? n - *done : sizeof tmp;
    MX_CHECK(mx_isrc_read(s, tmp, (size_t)want, &got));
    *done += got;
    if (got < want) break;
  }
  return MX_OK;
}

int mx_isrc_check_end(mx_isrc *s) {
  if (!s->z) return MX_OK;
  unsigned char tmp[4096];
  size_t got;
  do MX_CHECK(mx_isrc_read(s, tmp, sizeof tmp, &got));
  while (got > 0);
  if (s->z_cut) {
    mx_error(s->path, 0, "truncated: the compressed data ends before its end mark (after %llu "
                         "inflated bytes)", (unsigned long long)s->pos);
    return MX_EINPUT;
  }
  return MX_OK;
}

void mx_isrc_close(mx_isrc *s) {
  if (s->z_init) inflateEnd(&s->zs);
  if (s->fp) fclose(s->fp);
  mx_free(s->zin);
  memset(s, 0, sizeof *s);
}

/* ---- dims and voxels ------------------------------------------------------- */

int mx_image_type_bytes(int type) {
  static const int b[] = {1, 1, 2, 2, 4, 4, 4, 8};
  return b[type];
}

int mx_image_check_dims(const char *path, long line, const int64_t n[3]) {
  for (int d = 0; d < 3; d++)
    if (n[d] < 1) {
      mx_error(path, line, "%lld voxels along %c: an image needs at least 1 along each axis",
               (long long)n[d], "ijk"[d]);
      return MX_EINPUT;
    }
  const int64_t lim = ((int64_t)1 << 31) - 1;
  if (n[0] > lim || n[1] > lim || n[2] > lim || n[0] * n[1] > lim || n[0] * n[1] * n[2] > lim) {
    mx_error(path, line,
             "%lld x %lld x %lld voxels: more than 2^31 - 1 voxels (8 GiB of labels, up to "
             "16 GiB of data) are not read",
             (long long)n[0], (long long)n[1], (long long)n[2]);
    return MX_EINPUT;
  }
  return MX_OK;
}

static void voxel_ijk(const mx_label_image *img, size_t v, long long ijk[3]) {
  ijk[0] = (long long)(v % (size_t)img->nx);
  ijk[1] = (long long)(v / (size_t)img->nx % (size_t)img->ny);
  ijk[2] = (long long)(v / ((size_t)img->nx * (size_t)img->ny));
}


/* The value of one voxel as a double (exact for every integer type). */
static double voxel_value(const unsigned char *p, int type, int big) {
  switch (type) {
  case MX_VT_U8: return p[0];
  case MX_VT_I8: return (int8_t)p[0];
  case MX_VT_I16: return (int16_t)(uint16_t)mx_load_uint(p, 2, big);
  case MX_VT_U16: return (uint16_t)mx_load_uint(p, 2, big);
  case MX_VT_I32: return (int32_t)(uint32_t)mx_load_uint(p, 4, big);
  case MX_VT_U32: return (uint32_t)mx_load_uint(p, 4, big);
  case MX_VT_F32: {
    const uint32_t u = (uint32_t)mx_load_uint(p, 4, big);
    float f;
    memcpy(&f, &u, 4);
    return f;
  }
  default: {
    const uint64_t u = mx_load_uint(p, 8, big);
    double f;
    memcpy(&f, &u, 8);
    return f;
  }
  }
}

/* Converts cnt voxels from b to labels at out[first ...]. */
static int convert(const unsigned char *b, size_t cnt, size_t first, int type, int big, int scale,
                   double slope, double inter, mx_label_image *img, const char *path) {
  const int bytes = mx_image_type_bytes(type);
  const int exact = !scale && type != MX_VT_F32 && type != MX_VT_F64;
  int32_t *out = img->label + first;
  for (size_t v = 0; v < cnt; v++) {
    double x = voxel_value(b + (size_t)bytes * v, type, big);
    if (scale) x = x * slope + inter;
    if (!exact) {
      if (!isfinite(x)) {
        long long ijk[3];
        voxel_ijk(img, first + v, ijk);
        mx_error(path, 0, "voxel (%lld, %lld, %lld) (number %zu) is %g: a label must be a finite number",
                 ijk[0], ijk[1], ijk[2], first + v, x);
        return MX_EINPUT;
      }
      const double r = round(x);
      if (r != x) img->rounded++;
      x = r;
    }
    if (x < (double)INT32_MIN || x > (double)INT32_MAX) {
      long long ijk[3];
      voxel_ijk(img, first + v, ijk);
      mx_error(path, 0, "voxel (%lld, %lld, %lld) (number %zu) is %.17g: a label must fit a 32-bit "
                        "signed integer (-2^31 .. 2^31 - 1)",
               ijk[0], ijk[1], ijk[2], first + v, x);
      return MX_EINPUT;
    }
    out[v] = (int32_t)x;
  }
  return MX_OK;
}

static int truncated(mx_isrc *s, uint64_t at, uint64_t need, uint64_t have) {
  mx_error(s->path, 0,
           "truncated: the voxels need %llu bytes from byte %llu of the %s, %s %llu",
           (unsigned long long)need, (unsigned long long)at, s->z ? "inflated data" : "file",
           s->z ? "it holds" : "it has", (unsigned long long)have);
  return MX_EINPUT;
}

int mx_image_voxels(mx_isrc *s, int type, int big, int scale, double slope, double inter,
                    uint64_t at, mx_label_image *img) {
  const size_t nvox = (size_t)img->nx * (size_t)img->ny * (size_t)img->nz;
  const int bytes = mx_image_type_bytes(type);
  const uint64_t need = (uint64_t)nvox * (uint64_t)bytes;
  const int64_t left = mx_isrc_left(s);
  if (left >= 0 && (uint64_t)left < need) return truncated(s, at, need, (uint64_t)left);
  /* known size: all the labels at once; compressed: growing with the data */
  size_t cap = left >= 0 || nvox < ((size_t)1 << 20) ? nvox : (size_t)1 << 20;
  img->label = mx_alloc(cap * sizeof *img->label);
  if (!img->label) return MX_ENOMEM;
  enum { CHUNK = 1 << 20 };
  unsigned char *buf = mx_alloc(need < CHUNK ? (size_t)need : CHUNK);
  if (!buf) return MX_ENOMEM;
  int st = MX_OK;
  size_t done = 0;
  while (done < nvox) {
    size_t cnt = nvox - done < CHUNK / (size_t)bytes ? nvox - done : CHUNK / (size_t)bytes, got;
    if (done + cnt > cap) {
      const size_t ncap = cap > nvox / 2 ? nvox : 2 * cap;
      int32_t *l = mx_realloc(img->label, ncap * sizeof *l);
      if (!l) {
        st = MX_ENOMEM;
        break;
      }
      img->label = l;
      cap = ncap;
    }
    st = mx_isrc_read(s, buf, cnt * (size_t)bytes, &got);
    if (st != MX_OK) break;
    if (got < cnt * (size_t)bytes) {
      st = truncated(s, at, need, (uint64_t)done * (uint64_t)bytes + got);
      break;
    }
    st = convert(buf, cnt, done, type, big, scale, slope, inter, img, s->path);
    if (st != MX_OK) break;
    done += cnt;
  }
  mx_free(buf);
  if (st == MX_OK) st = mx_isrc_check_end(s);
  if (st == MX_OK && img->rounded)
    mx_warning(s->path, 0, "%zu voxels were not integers: rounded to the nearest integer label",
               img->rounded);
  return st;
}

int mx_image_finish(const char *path, mx_label_image *img) {
  const double *A = img->A;
  for (int e = 0; e < 12; e++)
    if (!isfinite(A[e])) {
      mx_error(path, 0, "the voxel-to-world transform has a non-finite entry (%g)", A[e]);
      return MX_EINPUT;
    }
  img->oblique = 0;
  for (int c = 0; c < 3; c++) {
    const double x = A[c], y = A[4 + c], z = A[8 + c], h = sqrt(x * x + y * y + z * z);
    if (!(h > 0) || !isfinite(h)) {
      mx_error(path, 0, "the voxel-to-world transform gives axis %c the length %g: a voxel "
                        "needs a size > 0 along each axis",
               "ijk"[c], h);
      return MX_EINPUT;
    }
    img->spacing[c] = h;
    const int along = (fabs(x) > 1e-6 * h) + (fabs(y) > 1e-6 * h) + (fabs(z) > 1e-6 * h);
    if (along > 1) img->oblique = 1;
  }
  const double det = mx_affine_det(A);
  if (!(fabs(det) > 1e-9 * img->spacing[0] * img->spacing[1] * img->spacing[2])) {
    mx_error(path, 0, "the voxel-to-world transform is degenerate (its axes are not independent)");
    return MX_EINPUT;
  }
  return MX_OK;
}

/* ---- dispatch ------------------------------------------------------------- */

enum { F_NONE, F_NIFTI, F_META, F_INR };

static int ends_with(const char *s, const char *suffix) {
  const size_t n = strlen(s), k = strlen(suffix);
  return n >= k && strcasecmp(s + n - k, suffix) == 0;
}

static int format_of_name(const char *name) {
  if (ends_with(name, ".nii") || ends_with(name, ".nii.gz") || ends_with(name, ".hdr") ||
      ends_with(name, ".hdr.gz"))
    return F_NIFTI;
  if (ends_with(name, ".mha") || ends_with(name, ".mhd")) return F_META;
  if (ends_with(name, ".inr") || ends_with(name, ".inr.gz")) return F_INR;
  return F_NONE;
}

/* The format from the first bytes (inflated when gzip). */
static int sniff(mx_isrc *s, int *fmt) {
  int gz;
  *fmt = F_NONE;
  MX_CHECK(mx_isrc_gzip_auto(s, &gz));
  unsigned char b[16] = {0};
  size_t got;
  MX_CHECK(mx_isrc_read(s, b, sizeof b, &got));
  const uint32_t le = (uint32_t)mx_load_uint(b, 4, 0), be = (uint32_t)mx_load_uint(b, 4, 1);
  if (got >= 4 && (le == 348 || be == 348 || le == 540 || be == 540)) {
    *fmt = F_NIFTI;
  } else if (got >= 9 && memcmp(b, "#INRIMAGE", 9) == 0) {
    *fmt = F_INR;
  } else if (!gz && got > 0) {
    int text = 1;
    for (size_t k = 0; k < got; k++)
      if (!(b[k] == '\t' || b[k] == '\n' || b[k] == '\r' || (b[k] >= 32 && b[k] < 127))) text = 0;
    if (text) *fmt = F_META;
  }
  return MX_OK;
}

static int read_image(const char *name, const unsigned char *data, size_t n, int from_mem,
                      mx_label_image *img) {
  memset(img, 0, sizeof *img);
  if (!name) name = "(image)";
  mx_isrc s;
  int fmt = format_of_name(name), st;
  if (fmt == F_NONE) {
    if (from_mem)
      mx_isrc_open_mem(&s, name, data, n);
    else
      MX_CHECK(mx_isrc_open_file(&s, name));
    st = sniff(&s, &fmt);
    mx_isrc_close(&s);
    if (st != MX_OK) return st;
    if (fmt == F_NONE) {
      mx_error(name, 0, "not a label image the extension or the first bytes name: the formats "
                        "read are NIfTI-1/2 (.nii, .nii.gz), MetaImage (.mha, .mhd) and INRIA "
                        "(.inr, .inr.gz)");
      return MX_EINPUT;
    }
  }
  if (from_mem)
    mx_isrc_open_mem(&s, name, data, n);
  else
    MX_CHECK(mx_isrc_open_file(&s, name));
  if (fmt == F_NIFTI)
    st = mx_read_nifti(&s, img);
  else if (fmt == F_META)
    st = mx_read_metaimage(&s, from_mem, img);
  else
    st = mx_read_inr(&s, img);
  mx_isrc_close(&s);
  if (st != MX_OK) mx_label_image_free(img);
  return st;
}

int mx_read_label_image(const char *path, mx_label_image *img) {
  return read_image(path, NULL, 0, 0, img);
}

int mx_read_label_image_mem(const char *name, const unsigned char *data, size_t n,
                            mx_label_image *img) {
  return read_image(name, data, n, 1, img);
}

void mx_label_image_free(mx_label_image *img) {
  if (!img) return;
  mx_free(img->label);
  memset(img, 0, sizeof *img);
}
