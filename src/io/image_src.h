/* The label image readers' shared part (src/io/read_image.c): a byte
 * source (a file or bytes in memory, inflated through zlib when gzip or
 * zlib compressed), the dims check, the voxels' conversion to labels and
 * the transform's check. The formats: read_nifti.c, read_metaimage.c,
 * read_inr.c. */
#ifndef MX_IMAGE_SRC_H
#define MX_IMAGE_SRC_H

#include <stdint.h>
#include <stdio.h>
#include <zlib.h>

#include "io/bytes.h"
#include "io/read_image.h"

typedef struct {
  const char *path; /* what messages call it */
  /* the raw bytes: in memory, or a regular file */
  const unsigned char *mem;
  size_t mem_len, mem_pos;
  FILE *fp;
  uint64_t raw_size, raw_pos;
  /* inflating (gzip or zlib) from the raw bytes' current position */
  int z, z_init, z_end, z_gzip, z_cut; /* z_cut: the input ended inside the stream */
  z_stream zs;
  unsigned char *zin; /* input chunk read from the file */
  uint64_t pos;       /* bytes delivered so far */
} mx_isrc;

/* A regular file (MX_EINPUT with a message when it cannot be opened). */
int mx_isrc_open_file(mx_isrc *s, const char *path);
void mx_isrc_open_mem(mx_isrc *s, const char *name, const unsigned char *d, size_t n);
/* When the raw bytes at the current position start a gzip stream (1f 8b),
 * inflates them from there (*gz = 1), else nothing (*gz = 0). */
int mx_isrc_gzip_auto(mx_isrc *s, int *gz);
/* Inflates from the current raw position on (zlib or gzip stream). */
int mx_isrc_inflate(mx_isrc *s);
/* Up to n bytes; *got fewer only at the end of the data. MX_EINPUT with a
 * message for a read error or corrupt compressed data. */
int mx_isrc_read(mx_isrc *s, void *buf, size_t n, size_t *got);
/* Compressed: inflates to the stream's end (its checksum), the bytes
 * discarded; MX_EINPUT when the stream is cut short or corrupt. */
int mx_isrc_check_end(mx_isrc *s);
/* Steps over n bytes (fewer, *done, at the end of the data). */
int mx_isrc_skip(mx_isrc *s, uint64_t n, uint64_t *done);
/* The bytes left when known (not compressed), else -1. */
int64_t mx_isrc_left(const mx_isrc *s);
void mx_isrc_close(mx_isrc *s);

/* Voxel types of the files. */
enum { MX_VT_U8, MX_VT_I8, MX_VT_I16, MX_VT_U16, MX_VT_I32, MX_VT_U32, MX_VT_F32, MX_VT_F64 };
int mx_image_type_bytes(int type);

/* n[0..2] each >= 1 and their product below 2^31 voxels (the labels fit
 * int32 indexing and 8 GiB); MX_EINPUT with a message naming path and line
 * otherwise. */
int mx_image_check_dims(const char *path, long line, const int64_t n[3]);

/* img->nx, ny, nz set and checked: reads the voxels (type, big-endian
 * when big, value * slope + inter when scale) from s's position into
 * img->label. When s knows its size the data must be there before any
 * allocation; compressed data is read in chunks, the labels growing with
 * what arrives. `at`: the offset of the data in the file, for messages. */
int mx_image_voxels(mx_isrc *s, int type, int big, int scale, double slope, double inter,
                    uint64_t at, mx_label_image *img);

/* img->A set: checks it finite and not degenerate; sets spacing, oblique. */
int mx_image_finish(const char *path, mx_label_image *img);

int mx_read_nifti(mx_isrc *s, mx_label_image *img);
int mx_read_metaimage(mx_isrc *s, int from_mem, mx_label_image *img);
int mx_read_inr(mx_isrc *s, mx_label_image *img);

#endif
