/* mixoct: MetaImage label images (io/read_image.h): a text header of
 * "Key = Value" lines (keys compared without case), ElementDataFile last;
 * the voxels follow it (LOCAL, .mha) or are in a file named relative to
 * the header's folder (.mhd), raw or zlib compressed (CompressedData).
 * The transform: world = Offset + D diag(ElementSpacing) (i, j, k), where
 * the first three numbers of TransformMatrix are D's first column, the
 * direction of the i axis (MetaIO stores the matrix column by column, as
 * ITK reads it), the next three the j axis', the last three the k axis'. */
#include <math.h>
#include <string.h>
#include <strings.h>
#include <unistd.h>

#include "base/common.h"
#include "io/image_src.h"
#include "io/text_scan.h"

enum { LINE_MAX_BYTES = 4096, HEADER_MAX_BYTES = 1 << 20 };

typedef struct {
  int ndims, type, msb, compressed;
  long ndims_line, dims_line, type_line;
  int64_t dims[3], header_size;
  double spacing[3], size[3], offset[3], tm[9];
  int have_spacing, have_size;
  char datafile[LINE_MAX_BYTES];
  long datafile_line;
} meta_hdr;

/* One line (without its end of line) into buf; *eof when there is none. */
static int read_line(mx_isrc *s, char *buf, long line, int *eof, size_t *total) {
  size_t n = 0;
  *eof = 0;
  for (;;) {
    unsigned char c;
    size_t got;
    MX_CHECK(mx_isrc_read(s, &c, 1, &got));
    if (got == 0) {
      *eof = n == 0;
      break;
    }
    if (++*total > HEADER_MAX_BYTES) {
      mx_error(s->path, line, "a header of more than %d bytes without ElementDataFile: not a "
                              "MetaImage header", HEADER_MAX_BYTES);
      return MX_EINPUT;
    }
    if (c == '\n') break;
    if (c == '\0') {
      mx_error(s->path, line, "a NUL byte in the header: not a MetaImage text header");
      return MX_EINPUT;
    }
    if (n + 1 >= LINE_MAX_BYTES) {
      mx_error(s->path, line, "a header line of more than %d bytes", LINE_MAX_BYTES - 2);
      return MX_EINPUT;
    }
    buf[n++] = (char)c;
  }
  while (n > 0 && (buf[n - 1] == '\r' || buf[n - 1] == ' ' || buf[n - 1] == '\t')) n--;
  buf[n] = '\0';
  return MX_OK;
}

static char *trim(char *p) {
  while (*p == ' ' || *p == '\t') p++;
  char *e = p + strlen(p);
  while (e > p && (e[-1] == ' ' || e[-1] == '\t' || e[-1] == '\r')) *--e = '\0';
  return p;
}

/* want numbers (finite) from v into out; exactly want of them. */
static int numbers(const char *path, long line, const char *key, const char *v, int want,
                   double *out) {
  int k = 0;
  const char *p = mx_io_blank(v);
  while (*p) {
    double x;
    const char *e = mx_io_double(p, &x);
    if (!e || !mx_io_delim(e, 0)) {
      mx_error(path, line, "%s: '%.*s' is not a number", key, mx_io_toklen(p, 0), p);
      return MX_EINPUT;
    }
    if (!isfinite(x)) {
      mx_error(path, line, "%s: '%.*s' is not a finite number", key, mx_io_toklen(p, 0), p);
      return MX_EINPUT;
    }
    if (k < want) out[k] = x;
    k++;
    p = mx_io_blank(e);
  }
  if (k != want) {
    mx_error(path, line, "%s has %d numbers, a 3D image needs %d", key, k, want);
    return MX_EINPUT;
  }
  return MX_OK;
}

static int integers(const char *path, long line, const char *key, const char *v, int want,
                    int64_t *out) {
  int k = 0;
  const char *p = mx_io_blank(v);
  while (*p) {
    int64_t x;
    const char *e = mx_io_int(p, &x);
    if (!e || !mx_io_delim(e, 0)) {
      mx_error(path, line, "%s: '%.*s' is not an integer", key, mx_io_toklen(p, 0), p);
      return MX_EINPUT;
    }
    if (k < want) out[k] = x;
    k++;
    p = mx_io_blank(e);
  }
  if (k != want) {
    mx_error(path, line, "%s has %d numbers, a 3D image needs %d", key, k, want);
    return MX_EINPUT;
  }
  return MX_OK;
}

static int boolean(const char *path, long line, const char *key, const char *v, int *out) {
  if (!strcasecmp(v, "true") || !strcmp(v, "1")) {
    *out = 1;
  } else if (!strcasecmp(v, "false") || !strcmp(v, "0")) {
    *out = 0;
  } else {
    char word[MX_WORD_BUF];
    mx_error(path, line, "%s = '%s': expected True or False", key, mx_show_word(v, strlen(v), word));
    return MX_EINPUT;
  }
  return MX_OK;
}

static int element_type(const char *path, long line, const char *v, int *type) {
  static const char *const names[] = {"MET_UCHAR", "MET_CHAR", "MET_SHORT", "MET_USHORT",
                                      "MET_INT", "MET_UINT", "MET_FLOAT", "MET_DOUBLE"};
  static const int types[] = {MX_VT_U8, MX_VT_I8, MX_VT_I16, MX_VT_U16,
                              MX_VT_I32, MX_VT_U32, MX_VT_F32, MX_VT_F64};
  for (int k = 0; k < 8; k++)
    if (!strcasecmp(v, names[k])) {
      *type = types[k];
      return MX_OK;
    }
  char word[MX_WORD_BUF];
  mx_error(path, line, "ElementType = '%s' is not a label type read: MET_UCHAR, MET_CHAR, "
                       "MET_SHORT, MET_USHORT, MET_INT, MET_UINT, MET_FLOAT, MET_DOUBLE",
           mx_show_word(v, strlen(v), word));
  return MX_EINPUT;
}

static int is_key(const char *k, const char *a, const char *b, const char *c) {
  return !strcasecmp(k, a) || (b && !strcasecmp(k, b)) || (c && !strcasecmp(k, c));
}

/* One "Key = Value" line; *last when it was ElementDataFile. */
static int header_line(const char *path, long line, char *text, meta_hdr *m, int *last) {
  char word[MX_WORD_BUF];
  char *eq = strchr(text, '=');
  if (!eq) {
    mx_error(path, line, "'%s' is not a line Key = Value of a MetaImage header",
             mx_show_word(text, strlen(text), word));
    return MX_EINPUT;
  }
  *eq = '\0';
  const char *key = trim(text), *v = trim(eq + 1);
  if (is_key(key, "ObjectType", NULL, NULL)) {
    if (strcasecmp(v, "Image")) {
      mx_error(path, line, "ObjectType = '%s': only Image is read", mx_show_word(v, strlen(v), word));
      return MX_EINPUT;
    }
  } else if (is_key(key, "NDims", NULL, NULL)) {
    int64_t d;
    MX_CHECK(integers(path, line, key, v, 1, &d));
    if (d != 3) {
      mx_error(path, line, "NDims = %lld: only 3D images are read (NDims = 3)", (long long)d);
      return MX_EINPUT;
    }
    m->ndims = 3;
    m->ndims_line = line;
  } else if (is_key(key, "DimSize", NULL, NULL)) {
    MX_CHECK(integers(path, line, key, v, 3, m->dims));
    m->dims_line = line;
  } else if (is_key(key, "ElementType", NULL, NULL)) {
    MX_CHECK(element_type(path, line, v, &m->type));
    m->type_line = line;
  } else if (is_key(key, "ElementSpacing", NULL, NULL)) {
    MX_CHECK(numbers(path, line, key, v, 3, m->spacing));
    m->have_spacing = 1;
  } else if (is_key(key, "ElementSize", NULL, NULL)) {
    MX_CHECK(numbers(path, line, key, v, 3, m->size));
    m->have_size = 1;
  } else if (is_key(key, "Offset", "Position", "Origin")) {
    MX_CHECK(numbers(path, line, key, v, 3, m->offset));
  } else if (is_key(key, "TransformMatrix", "Rotation", "Orientation")) {
    MX_CHECK(numbers(path, line, key, v, 9, m->tm));
  } else if (is_key(key, "BinaryDataByteOrderMSB", "ElementByteOrderMSB", NULL)) {
    MX_CHECK(boolean(path, line, key, v, &m->msb));
  } else if (is_key(key, "BinaryData", NULL, NULL)) {
    int b;
    MX_CHECK(boolean(path, line, key, v, &b));
    if (!b) {
      mx_error(path, line, "BinaryData = False (voxels as text): not read");
      return MX_EINPUT;
    }
  } else if (is_key(key, "CompressedData", NULL, NULL)) {
    MX_CHECK(boolean(path, line, key, v, &m->compressed));
  } else if (is_key(key, "CompressedDataSize", NULL, NULL)) {
    int64_t n; /* the compressed stream tells its own end: only checked */
    MX_CHECK(integers(path, line, key, v, 1, &n));
    if (n < 0) {
      mx_error(path, line, "CompressedDataSize = %lld: expected a size >= 0", (long long)n);
      return MX_EINPUT;
    }
  } else if (is_key(key, "HeaderSize", NULL, NULL)) {
    MX_CHECK(integers(path, line, key, v, 1, &m->header_size));
    if (m->header_size < -1 || m->header_size > ((int64_t)1 << 40)) {
      mx_error(path, line, "HeaderSize = %lld: expected a size >= 0, or -1 (the data at the end "
                           "of its file)", (long long)m->header_size);
      return MX_EINPUT;
    }
  } else if (is_key(key, "ElementNumberOfChannels", NULL, NULL)) {
    int64_t c;
    MX_CHECK(integers(path, line, key, v, 1, &c));
    if (c != 1) {
      mx_error(path, line, "ElementNumberOfChannels = %lld: a label image has 1 channel",
               (long long)c);
      return MX_EINPUT;
    }
  } else if (is_key(key, "ElementDataFile", NULL, NULL)) {
    if (!*v) {
      mx_error(path, line, "ElementDataFile names no file (LOCAL: the data follows the header)");
      return MX_EINPUT;
    }
    if (!strcasecmp(v, "LIST") || strchr(v, '%') || strchr(v, ' ')) {
      mx_error(path, line, "ElementDataFile = '%s': an image in several files (a list or a "
                           "pattern) is not read", mx_show_word(v, strlen(v), word));
      return MX_EINPUT;
    }
    strcpy(m->datafile, v); /* v is shorter than the line */
    m->datafile_line = line;
    *last = 1;
  }
  /* other keys (Comment, CenterOfRotation, AnatomicalOrientation, ...) do
   * not change the labels or their places */
  return MX_OK;
}

/* The voxels from the data file beside the header. */
static int read_datafile(mx_isrc *s, const meta_hdr *m, uint64_t need, mx_label_image *img) {
  const char *path = s->path;
  char word[MX_WORD_BUF];
  const size_t dl = m->datafile[0] == '/' ? 0 : (size_t)(strrchr(path, '/') ? strrchr(path, '/') - path + 1 : 0);
  char *full = mx_alloc(dl + strlen(m->datafile) + 1);
  if (!full) return MX_ENOMEM;
  memcpy(full, path, dl);
  strcpy(full + dl, m->datafile);
  if (access(full, R_OK) != 0) {
    mx_error(path, m->datafile_line, "ElementDataFile = '%s': cannot open %s",
             mx_show_word(m->datafile, strlen(m->datafile), word), full);
    mx_free(full);
    return MX_EINPUT;
  }
  mx_isrc d;
  int st = mx_isrc_open_file(&d, full);
  if (st != MX_OK) {
    mx_free(full);
    return st;
  }
  uint64_t skip = 0, skipped;
  if (m->header_size == -1) {
    if (m->compressed) {
      mx_error(path, m->datafile_line, "HeaderSize = -1 (the data at the end of its file) with "
                                       "CompressedData: not read");
      st = MX_EINPUT;
    } else if ((uint64_t)mx_isrc_left(&d) >= need) {
      skip = (uint64_t)mx_isrc_left(&d) - need;
    }
  } else {
    skip = (uint64_t)m->header_size;
  }
  if (st == MX_OK) st = mx_isrc_skip(&d, skip, &skipped);
  if (st == MX_OK && skipped < skip) {
    mx_error(full, 0, "truncated: HeaderSize %llu is past the end of the file (%llu bytes)",
             (unsigned long long)skip, (unsigned long long)skipped);
    st = MX_EINPUT;
  }
  if (st == MX_OK && m->compressed) st = mx_isrc_inflate(&d);
  if (st == MX_OK) st = mx_image_voxels(&d, m->type, m->msb, 0, 1, 0, m->compressed ? 0 : skip, img);
  mx_isrc_close(&d);
  mx_free(full);
  return st;
}

int mx_read_metaimage(mx_isrc *s, int from_mem, mx_label_image *img) {
  const char *path = s->path;
  meta_hdr m;
  memset(&m, 0, sizeof m);
  m.type = -1;
  for (int k = 0; k < 3; k++) m.spacing[k] = m.size[k] = m.tm[4 * k] = 1;
  strcpy(img->format, "MetaImage");
  char *buf = mx_alloc(LINE_MAX_BYTES);
  if (!buf) return MX_ENOMEM;
  long line = 0;
  size_t total = 0;
  int last = 0, st = MX_OK;
  while (!last) {
    int eof;
    line++;
    st = read_line(s, buf, line, &eof, &total);
    if (st != MX_OK) break;
    if (eof) {
      mx_error(path, line - 1, "the header ends without ElementDataFile (its last key: LOCAL "
                               "or the data's file)");
      st = MX_EINPUT;
      break;
    }
    if (!*trim(buf)) continue;
    st = header_line(path, line, buf, &m, &last);
    if (st != MX_OK) break;
  }
  mx_free(buf);
  if (st != MX_OK) return st;
  const char *missing = !m.ndims ? "NDims" : !m.dims_line ? "DimSize" : m.type < 0 ? "ElementType" : NULL;
  if (missing) {
    mx_error(path, m.datafile_line, "no %s before ElementDataFile (the header's last key)",
             missing);
    return MX_EINPUT;
  }
  MX_CHECK(mx_image_check_dims(path, m.dims_line, m.dims));
  img->nx = m.dims[0];
  img->ny = m.dims[1];
  img->nz = m.dims[2];
  const double *sp = m.have_spacing ? m.spacing : m.size;
  for (int c = 0; c < 3; c++) {
    for (int r = 0; r < 3; r++) img->A[4 * r + c] = m.tm[3 * c + r] * sp[c];
    img->A[4 * c + 3] = m.offset[c];
  }
  MX_CHECK(mx_image_finish(path, img));
  const uint64_t need = (uint64_t)img->nx * (uint64_t)img->ny * (uint64_t)img->nz *
                        (uint64_t)mx_image_type_bytes(m.type);
  if (strcasecmp(m.datafile, "LOCAL")) {
    if (from_mem) {
      char word[MX_WORD_BUF];
      mx_error(path, m.datafile_line, "ElementDataFile = '%s': an image read from memory has its "
                                      "voxels after its header (ElementDataFile = LOCAL)",
               mx_show_word(m.datafile, strlen(m.datafile), word));
      return MX_EINPUT;
    }
    return read_datafile(s, &m, need, img);
  }
  const uint64_t at = s->pos;
  if (m.compressed) MX_CHECK(mx_isrc_inflate(s));
  return mx_image_voxels(s, m.type, m.msb, 0, 1, 0, m.compressed ? 0 : at, img);
}
