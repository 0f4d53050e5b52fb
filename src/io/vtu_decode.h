/* The bytes of one DataArray of a VTK XML file (src/io/vtu_decode.c), as
 * VTK's file format documents them:
 *  - a block is a header of UInt32 or UInt64 values (the file's header_type,
 *    in its byte order) then data. Without a compressor the header is one
 *    value, the data's byte count. With one (the VTKFile's compressor
 *    attribute) it is [nblocks, block size, last block size (0: a full
 *    block), the compressed size of each block], then the compressed blocks
 *    one after the other; each decompresses to the block size, the last to
 *    the last block size;
 *  - stored raw (appended, encoding="raw") or as base64 text (format="binary"
 *    inline, appended with encoding="base64"). Writers encode the header and
 *    the data either as one base64 text or as two, each padded with '=':
 *    the decoder starts a new quantum after padding, so both read alike.
 * Compressors: vtkZLibDataCompressor (zlib streams), vtkLZ4DataCompressor
 * (LZ4 blocks), vtkLZMADataCompressor (.xz streams).
 *
 * Every size read from the file is checked against the bytes (or base64
 * characters) left and against overflow before anything is allocated; a
 * block that decompresses to another size than its header says is an
 * error. Errors are MX_EINPUT with a message in err and *at the place in
 * the text it concerns; MX_ENOMEM when alloc fails. */
#ifndef MX_VTU_DECODE_H
#define MX_VTU_DECODE_H

#include <stddef.h>
#include <stdint.h>

typedef enum { MX_VTU_RAW, MX_VTU_ZLIB, MX_VTU_LZ4, MX_VTU_LZMA } mx_vtu_comp;

/* The compressor of a compressor="..." value (n bytes); -1 if unknown. */
int mx_vtu_compressor(const char *v, size_t n);
/* Its VTK class name, for messages. */
const char *mx_vtu_compressor_name(mx_vtu_comp c);

/* ---- base64 ---------------------------------------------------------------- */

/* A base64 text from p to end: blanks are skipped, '=' padding ends a
 * quantum and the next character starts a new one; the text ends at end,
 * at a NUL or at '<'. */
typedef struct {
  const char *p, *end;
  unsigned char pend[3]; /* bytes of the last quantum not given out yet */
  int npend, ipend;
  const char *bad; /* an invalid character, after a failed read */
} mx_b64;

void mx_b64_init(mx_b64 *s, const char *p, const char *end);
/* The next n bytes into out: 0, or -1 at an invalid character or a
 * quantum cut short (s->bad), -2 when the text ends first. */
int mx_b64_read(mx_b64 *s, unsigned char *out, size_t n);
/* At most how many bytes the text left can give (its characters * 3 / 4). */
size_t mx_b64_left(const mx_b64 *s);

/* ---- one DataArray --------------------------------------------------------- */

typedef struct {
  const char *raw;   /* raw: the block's first byte; NULL for base64 */
  const char *text;  /* base64: its first character */
  const char *end;   /* end of what the file holds */
  int hsize;         /* 4 or 8 */
  int swap;          /* header values in the other byte order */
  mx_vtu_comp comp;
} mx_vtu_src;

typedef void *(*mx_vtu_alloc_fn)(void *ctx, size_t bytes);

/* The data of the block of s: *data and *nbytes, in place in the file for
 * raw uncompressed data, else in a buffer from alloc(ctx, bytes). */
int mx_vtu_decode(const mx_vtu_src *s, mx_vtu_alloc_fn alloc, void *ctx,
                  const unsigned char **data, uint64_t *nbytes, char *err, size_t errn,
                  const char **at);

#endif
