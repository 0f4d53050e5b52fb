/* mixoct: INRIA (.inr, .inr.gz) label images (io/read_image.h): a text
 * header in blocks of 256 bytes, "#INRIMAGE-4#{" first, "##}" and its
 * newline last, lines KEY=VALUE: XDIM YDIM ZDIM VDIM (1), TYPE (unsigned
 * fixed, signed fixed, float), PIXSIZE (8, 16, 32 or 64 bits), SCALE (not
 * used), CPU (decm, alpha, pc: little-endian; sun, sgi: big-endian), VX VY
 * VZ (the voxel's size), XO YO ZO (the world position of the centre of
 * voxel (0, 0, 0); 0 when absent). The voxels follow the header. */
#include <math.h>
#include <string.h>
#include <strings.h>

#include "base/common.h"
#include "io/image_src.h"
#include "io/text_scan.h"

enum { BLOCK = 256, MAX_BLOCKS = 64 };

static const char MAGIC[] = "#INRIMAGE-4#{";

static int get_int(const char *path, long line, const char *key, const char *v, int64_t *out) {
  const char *e = mx_io_int(v, out);
  if (!e || *mx_io_blank(e)) {
    mx_error(path, line, "%s: '%.*s' is not an integer", key, mx_io_toklen(v, 0), v);
    return MX_EINPUT;
  }
  return MX_OK;
}

static int get_num(const char *path, long line, const char *key, const char *v, double *out) {
  const char *e = mx_io_double(v, out);
  if (!e || *mx_io_blank(e) || !isfinite(*out)) {
    mx_error(path, line, "%s: '%.*s' is not a finite number", key, mx_io_toklen(v, 0), v);
    return MX_EINPUT;
  }
  return MX_OK;
}

int mx_read_inr(mx_isrc *s, mx_label_image *img) {
  const char *path = s->path;
  int gz;
  MX_CHECK(mx_isrc_gzip_auto(s, &gz));
  strcpy(img->format, "INR");
  char *h = mx_alloc(BLOCK * MAX_BLOCKS + 1);
  if (!h) return MX_ENOMEM;
  size_t len = 0, got;
  char *end = NULL;
  int st = MX_OK;
  while (!end) {
    if (len == BLOCK * MAX_BLOCKS) {
      mx_error(path, 0, "no end of header (\"##}\") in its first %d bytes", BLOCK * MAX_BLOCKS);
      st = MX_EINPUT;
      break;
    }
    st = mx_isrc_read(s, h + len, BLOCK, &got);
    if (st != MX_OK) break;
    len += got;
    h[len] = '\0';
    if (len >= sizeof MAGIC - 1 && memcmp(h, MAGIC, sizeof MAGIC - 1)) {
      char word[MX_WORD_BUF];
      mx_error(path, 0, "bad magic '%s': an INRIA image starts with \"%s\"",
               mx_show_word(h, sizeof MAGIC - 1, word), MAGIC);
      st = MX_EINPUT;
      break;
    }
    if (got < BLOCK) {
      mx_error(path, 0, "truncated header: %zu bytes, an INRIA header is blocks of %d bytes ending "
                        "with \"##}\"", len, BLOCK);
      st = MX_EINPUT;
      break;
    }
    if (memchr(h, '\0', len)) {
      mx_error(path, 0, "a NUL byte in the header: not an INRIA image header");
      st = MX_EINPUT;
      break;
    }
    end = strstr(h, "\n##}");
  }
  if (st != MX_OK) {
    mx_free(h);
    return st;
  }
  end[1] = '\0'; /* the lines before "##}" */
  int64_t dim[4] = {-1, -1, 1, 1}, pixsize = -1;
  double vox[3] = {1, 1, 1}, org[3] = {0, 0, 0};
  int kind = -1, big = 0; /* kind: 0 unsigned fixed, 1 signed fixed, 2 float */
  long line = 2, type_line = 0, size_line = 0, dims_line = 0;
  char word[MX_WORD_BUF];
  for (char *p = strchr(h, '\n') + 1; *p && st == MX_OK; line++) {
    char *nl = strchr(p, '\n');
    *nl = '\0';
    char *q = p;
    p = nl + 1;
    if (nl > q && nl[-1] == '\r') nl[-1] = '\0';
    q = (char *)mx_io_blank(q);
    if (!*q || *q == '#') continue;
    char *eq = strchr(q, '=');
    if (!eq) {
      mx_error(path, line, "'%s' is not a line KEY=VALUE of an INRIA header",
               mx_show_word(q, strlen(q), word));
      st = MX_EINPUT;
      break;
    }
    *eq = '\0';
    for (char *e = eq; e > q && (e[-1] == ' ' || e[-1] == '\t'); e--) e[-1] = '\0';
    const char *v = mx_io_blank(eq + 1);
    static const char *const dkeys[4] = {"XDIM", "YDIM", "ZDIM", "VDIM"};
    static const char *const vkeys[6] = {"VX", "VY", "VZ", "XO", "YO", "ZO"};
    int done = 0;
    for (int k = 0; k < 4 && !done; k++)
      if (!strcasecmp(q, dkeys[k])) {
        st = get_int(path, line, q, v, &dim[k]);
        if (k < 3) dims_line = line;
        done = 1;
      }
    for (int k = 0; k < 6 && !done; k++)
      if (!strcasecmp(q, vkeys[k])) {
        st = get_num(path, line, q, v, k < 3 ? &vox[k] : &org[k - 3]);
        done = 1;
      }
    if (done) continue;
    if (!strcasecmp(q, "TYPE")) {
      kind = !strcasecmp(v, "unsigned fixed") ? 0 : !strcasecmp(v, "signed fixed") ? 1
             : !strcasecmp(v, "float") ? 2 : -1;
      if (kind < 0) {
        mx_error(path, line, "TYPE=%s: the types read are unsigned fixed, signed fixed and float",
                 mx_show_word(v, strlen(v), word));
        st = MX_EINPUT;
      }
      type_line = line;
    } else if (!strcasecmp(q, "PIXSIZE")) {
      const char *e = mx_io_int(v, &pixsize);
      if (!e || strcmp(mx_io_blank(e), "bits")) {
        mx_error(path, line, "PIXSIZE=%s: expected 8, 16, 32 or 64 bits",
                 mx_show_word(v, strlen(v), word));
        st = MX_EINPUT;
      }
      size_line = line;
    } else if (!strcasecmp(q, "CPU")) {
      if (!strcasecmp(v, "decm") || !strcasecmp(v, "alpha") || !strcasecmp(v, "pc")) {
        big = 0;
      } else if (!strcasecmp(v, "sun") || !strcasecmp(v, "sgi")) {
        big = 1;
      } else {
        mx_error(path, line, "CPU=%s: expected decm, alpha or pc (little-endian), sun or sgi "
                             "(big-endian)", mx_show_word(v, strlen(v), word));
        st = MX_EINPUT;
      }
    }
    /* SCALE and other keys do not change the labels or their places */
  }
  mx_free(h);
  if (st != MX_OK) return st;
  if (dim[0] < 0 || dim[1] < 0 || kind < 0) {
    mx_error(path, 0, "no %s in the header", dim[0] < 0 ? "XDIM" : dim[1] < 0 ? "YDIM" : "TYPE");
    return MX_EINPUT;
  }
  if (dim[3] != 1) {
    mx_error(path, 0, "VDIM=%lld: a label image has 1 value a voxel", (long long)dim[3]);
    return MX_EINPUT;
  }
  MX_CHECK(mx_image_check_dims(path, dims_line, dim));
  if (pixsize < 0 && kind == 2) pixsize = 32;
  int type = -1;
  if (kind == 0) type = pixsize == 8 ? MX_VT_U8 : pixsize == 16 ? MX_VT_U16 : pixsize == 32 ? MX_VT_U32 : -1;
  if (kind == 1) type = pixsize == 8 ? MX_VT_I8 : pixsize == 16 ? MX_VT_I16 : pixsize == 32 ? MX_VT_I32 : -1;
  if (kind == 2) type = pixsize == 32 ? MX_VT_F32 : pixsize == 64 ? MX_VT_F64 : -1;
  if (type < 0) {
    mx_error(path, size_line ? size_line : type_line,
             "PIXSIZE=%lld bits with TYPE=%s: not a label type read (fixed: 8, 16 or 32 bits; "
             "float: 32 or 64)", (long long)pixsize,
             kind == 0 ? "unsigned fixed" : kind == 1 ? "signed fixed" : "float");
    return MX_EINPUT;
  }
  img->nx = dim[0];
  img->ny = dim[1];
  img->nz = dim[2];
  memset(img->A, 0, sizeof img->A);
  for (int k = 0; k < 3; k++) {
    img->A[5 * k] = vox[k];
    img->A[4 * k + 3] = org[k];
  }
  MX_CHECK(mx_image_finish(path, img));
  return mx_image_voxels(s, type, big, 0, 1, 0, s->pos, img);
}
