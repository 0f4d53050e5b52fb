/* mixoct: the bytes of one DataArray of a VTK XML file: base64 text and
 * compressed blocks (io/vtu_decode.h). */
#include "io/vtu_decode.h"

#include <limits.h>
#include <lz4.h>
#include <lzma.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>
#include <zlib.h>

#include "base/common.h"

static const char *const comp_name[] = {"none", "vtkZLibDataCompressor", "vtkLZ4DataCompressor",
                                        "vtkLZMADataCompressor"};

int mx_vtu_compressor(const char *v, size_t n) {
  for (int c = MX_VTU_ZLIB; c <= MX_VTU_LZMA; c++)
    if (n == strlen(comp_name[c]) && memcmp(v, comp_name[c], n) == 0) return c;
  return -1;
}

const char *mx_vtu_compressor_name(mx_vtu_comp c) { return comp_name[c]; }

/* ---- base64 ---------------------------------------------------------------- */

static int b64_value(char c) {
  if (c >= 'A' && c <= 'Z') return c - 'A';
  if (c >= 'a' && c <= 'z') return c - 'a' + 26;
  if (c >= '0' && c <= '9') return c - '0' + 52;
  if (c == '+') return 62;
  if (c == '/') return 63;
  return -1;
}

static int b64_blank(char c) {
  return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\f' || c == '\v';
}

void mx_b64_init(mx_b64 *s, const char *p, const char *end) {
  memset(s, 0, sizeof *s);
  s->p = p;
  s->end = end;
}

/* The next quantum of four characters into s->pend: 0, -1 invalid, -2 at
 * the end of the text before its first character. */
static int b64_quantum(mx_b64 *s) {
  int v[4], got = 0, pad = 0;
  while (got < 4) {
    while (s->p < s->end && b64_blank(*s->p)) s->p++;
    if (s->p >= s->end || *s->p == '\0' || *s->p == '<') {
      if (got == 0) return -2;
      s->bad = s->p;
      return -1; /* a quantum cut short */
    }
    const char c = *s->p;
    if (c == '=') {
      if (got < 2) {
        s->bad = s->p;
        return -1;
      }
      pad++;
      v[got++] = 0;
    } else {
      const int d = b64_value(c);
      if (d < 0 || pad) { /* not base64, or data after the padding */
        s->bad = s->p;
        return -1;
      }
      v[got++] = d;
    }
    s->p++;
  }
  const uint32_t w = (uint32_t)v[0] << 18 | (uint32_t)v[1] << 12 | (uint32_t)v[2] << 6 | (uint32_t)v[3];
  s->pend[0] = (unsigned char)(w >> 16);
  s->pend[1] = (unsigned char)(w >> 8);
  s->pend[2] = (unsigned char)w;
  s->npend = 3 - pad;
  s->ipend = 0;
  return 0;
}

int mx_b64_read(mx_b64 *s, unsigned char *out, size_t n) {
  size_t k = 0;
  while (k < n) {
    if (s->ipend < s->npend) {
      out[k++] = s->pend[s->ipend++];
      continue;
    }
    /* whole quanta straight into out while they fit (the common case) */
    while (n - k >= 3 && s->end - s->p >= 4) {
      const int a = b64_value(s->p[0]), b = b64_value(s->p[1]), c = b64_value(s->p[2]),
                d = b64_value(s->p[3]);
      if ((a | b | c | d) < 0) break;
      const uint32_t w = (uint32_t)a << 18 | (uint32_t)b << 12 | (uint32_t)c << 6 | (uint32_t)d;
      out[k] = (unsigned char)(w >> 16);
      out[k + 1] = (unsigned char)(w >> 8);
      out[k + 2] = (unsigned char)w;
      k += 3;
      s->p += 4;
    }
    if (k == n) break;
    const int st = b64_quantum(s);
    if (st) return st;
  }
  return 0;
}

size_t mx_b64_left(const mx_b64 *s) {
  return (size_t)(s->end - s->p) / 4 * 3 + 3 + (size_t)(s->npend - s->ipend);
}

/* ---- the bytes of a block, raw or base64 ----------------------------------- */

typedef struct {
  const mx_vtu_src *s;
  const char *rp; /* raw: the next byte */
  mx_b64 b;
  char *err;
  size_t errn;
  const char **at;
} input;

static int fail(input *in, const char *at, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
static int fail(input *in, const char *at, const char *fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(in->err, in->errn, fmt, ap);
  va_end(ap);
  *in->at = at;
  return MX_EINPUT;
}

static const char *in_pos(const input *in) { return in->s->raw ? in->rp : in->b.p; }

static size_t in_left(const input *in) {
  return in->s->raw ? (size_t)(in->s->end - in->rp) : mx_b64_left(&in->b);
}

/* n bytes of the block (what: for messages). */
static int in_read(input *in, unsigned char *out, size_t n, const char *what) {
  if (in->s->raw) {
    if (n > (size_t)(in->s->end - in->rp))
      return fail(in, in->rp, "%s: %zu bytes needed but only %zu are left (truncated file?)", what,
                  n, (size_t)(in->s->end - in->rp));
    memcpy(out, in->rp, n);
    in->rp += n;
    return MX_OK;
  }
  const int st = mx_b64_read(&in->b, out, n);
  if (st == -1) return fail(in, in->b.bad, "%s: invalid base64 text", what);
  if (st == -2) return fail(in, in->b.p, "%s: the base64 text ends before its %zu bytes", what, n);
  return MX_OK;
}

/* The next header value. */
static int in_header(input *in, uint64_t *v, const char *what) {
  unsigned char b[8];
  const int h = in->s->hsize;
  MX_CHECK(in_read(in, b, (size_t)h, what));
  if (h == 4) {
    uint32_t x;
    memcpy(&x, b, 4);
    *v = in->s->swap ? __builtin_bswap32(x) : x;
  } else {
    uint64_t x;
    memcpy(&x, b, 8);
    *v = in->s->swap ? __builtin_bswap64(x) : x;
  }
  return MX_OK;
}

/* ---- decompression ------------------------------------------------------- */

/* The most one compressed byte can give: zlib's deflate 1032 (its
 * documented limit); LZ4 255 (one length byte adds at most 255); xz has no
 * such limit: 16384, above the 6800 it reaches on long runs of zeros. A
 * header claiming more is not a file a compressor wrote, and its size is
 * not allocated. */
static uint64_t max_ratio(mx_vtu_comp c) { return c == MX_VTU_ZLIB ? 1032 : c == MX_VTU_LZ4 ? 256 : 16384; }

/* Block k of csize bytes at src into dst of usize bytes: 0, or the reason. */
static const char *inflate_block(mx_vtu_comp c, const unsigned char *src, uint64_t csize,
                                 unsigned char *dst, uint64_t usize, uint64_t *got) {
  *got = 0;
  if (c == MX_VTU_ZLIB) {
    uLongf dl = (uLongf)usize;
    const int z = uncompress(dst, &dl, src, (uLong)csize);
    *got = dl;
    if (z == Z_BUF_ERROR) return dl < usize ? "the zlib stream is cut short" : "it holds more bytes";
    if (z == Z_DATA_ERROR) return "the zlib stream is corrupt";
    if (z != Z_OK) return "zlib failed";
    return NULL;
  }
  if (c == MX_VTU_LZ4) {
    if (csize > INT_MAX || usize > INT_MAX) return "the block is too large for LZ4";
    const int n = LZ4_decompress_safe((const char *)src, (char *)dst, (int)csize, (int)usize);
    if (n < 0) return "the LZ4 block is corrupt or holds more bytes";
    *got = (uint64_t)n;
    return NULL;
  }
  uint64_t memlimit = (uint64_t)1 << 28; /* xz -9 needs 65 MiB */
  size_t in_pos = 0, out_pos = 0;
  const lzma_ret e = lzma_stream_buffer_decode(&memlimit, 0, NULL, src, &in_pos, (size_t)csize,
                                               dst, &out_pos, (size_t)usize);
  *got = out_pos;
  if (e == LZMA_BUF_ERROR)
    return out_pos == usize ? "it holds more bytes" : "the xz stream is cut short";
  if (e == LZMA_MEMLIMIT_ERROR) return "the xz stream needs more than 256 MiB to decode";
  if (e != LZMA_OK) return "the xz stream is corrupt";
  if (in_pos != csize) return "bytes follow the xz stream in its block";
  return NULL;
}

static int decode_compressed(input *in, mx_vtu_alloc_fn alloc, void *ctx, const unsigned char **data,
                             uint64_t *nbytes) {
  const mx_vtu_src *s = in->s;
  const char *name = comp_name[s->comp];
  const char *head = in_pos(in);
  uint64_t nb, bs, last;
  MX_CHECK(in_header(in, &nb, "compressed block header"));
  MX_CHECK(in_header(in, &bs, "compressed block header"));
  MX_CHECK(in_header(in, &last, "compressed block header"));
  if (nb == 0) {
    *data = (const unsigned char *)"";
    *nbytes = 0;
    return MX_OK;
  }
  if (nb > in_left(in) / (size_t)(s->hsize + 1))
    return fail(in, head, "%s header: %llu blocks but the file has bytes left for at most %zu",
                name, (unsigned long long)nb, in_left(in) / (size_t)(s->hsize + 1));
  if (bs == 0 || last > bs)
    return fail(in, head, "%s header: block size %llu, last block size %llu", name,
                (unsigned long long)bs, (unsigned long long)last);
  const uint64_t lastsize = last ? last : bs;
  if (nb - 1 > (UINT64_MAX - lastsize) / bs || (nb - 1) * bs + lastsize > SIZE_MAX / 2)
    return fail(in, head, "%s header: %llu blocks of %llu bytes overflow", name,
                (unsigned long long)nb, (unsigned long long)bs);
  const uint64_t total = (nb - 1) * bs + lastsize;
  uint64_t *cs = mx_alloc((size_t)nb * sizeof *cs);
  if (!cs) return MX_ENOMEM;
  int st = MX_OK;
  uint64_t csum = 0;
  for (uint64_t k = 0; k < nb && st == MX_OK; k++) {
    st = in_header(in, &cs[k], "compressed block sizes");
    if (st != MX_OK) break;
    const uint64_t us = k + 1 < nb ? bs : lastsize;
    if (cs[k] == 0 || cs[k] > in_left(in) || us / max_ratio(s->comp) > cs[k])
      st = fail(in, head, "%s header: block %llu of %llu bytes compressed to %llu bytes (%zu bytes "
                "left in the file)", name, (unsigned long long)k, (unsigned long long)us,
                (unsigned long long)cs[k], in_left(in));
    else
      csum += cs[k];
  }
  if (st == MX_OK && csum > in_left(in))
    st = fail(in, head, "%s: %llu compressed bytes but only %zu are left (truncated file?)", name,
              (unsigned long long)csum, in_left(in));
  /* the compressed bytes: in place when raw, else decoded into scratch */
  const unsigned char *src = NULL;
  unsigned char *scratch = NULL;
  const char *payload = in_pos(in);
  if (st == MX_OK) {
    if (s->raw) {
      src = (const unsigned char *)in->rp;
    } else {
      scratch = mx_alloc((size_t)csum + 1);
      if (!scratch) st = MX_ENOMEM;
      if (st == MX_OK) st = in_read(in, scratch, (size_t)csum, name);
      src = scratch;
    }
  }
  unsigned char *out = NULL;
  if (st == MX_OK) {
    out = alloc(ctx, (size_t)total + 1);
    if (!out) st = MX_ENOMEM;
  }
  /* the blocks are independent: in parallel, each from its offset (cs
   * becomes the offsets), the first that fails decompressed again for its
   * message */
  size_t bad = SIZE_MAX;
  if (st == MX_OK) {
    uint64_t from = 0;
    for (uint64_t k = 0; k < nb; k++) {
      const uint64_t c = cs[k];
      cs[k] = from;
      from += c;
    }
    const size_t n = (size_t)nb;
#pragma omp parallel for schedule(dynamic, 1) reduction(min : bad) if (n > 1 && total > (1u << 20))
    for (size_t k = 0; k < n; k++) {
      const uint64_t us = k + 1 < n ? bs : lastsize;
      const uint64_t c = (k + 1 < n ? cs[k + 1] : csum) - cs[k];
      uint64_t got;
      const char *why = inflate_block(s->comp, src + cs[k], c, out + (uint64_t)k * bs, us, &got);
      if ((why || got != us) && k < bad) bad = k;
    }
  }
  if (bad != SIZE_MAX) {
    const uint64_t us = bad + 1 < nb ? bs : lastsize;
    const uint64_t c = (bad + 1 < nb ? cs[bad + 1] : csum) - cs[bad];
    uint64_t got;
    const char *why = inflate_block(s->comp, src + cs[bad], c, out + (uint64_t)bad * bs, us, &got);
    st = fail(in, payload, "%s: block %zu of %llu does not decompress to its %llu bytes (%s)", name,
              bad, (unsigned long long)nb, (unsigned long long)us, why ? why : "it holds fewer");
  }
  mx_free(scratch);
  mx_free(cs);
  if (st != MX_OK) return st;
  *data = out;
  *nbytes = total;
  return MX_OK;
}

int mx_vtu_decode(const mx_vtu_src *s, mx_vtu_alloc_fn alloc, void *ctx,
                  const unsigned char **data, uint64_t *nbytes, char *err, size_t errn,
                  const char **at) {
  input in = {s, s->raw, {0}, err, errn, at};
  if (!s->raw) mx_b64_init(&in.b, s->text, s->end);
  *data = NULL;
  *nbytes = 0;
  if (s->comp != MX_VTU_RAW) return decode_compressed(&in, alloc, ctx, data, nbytes);
  const char *head = in_pos(&in);
  uint64_t n;
  MX_CHECK(in_header(&in, &n, "block header"));
  if (n > in_left(&in))
    return fail(&in, head, "block of %llu bytes but only %zu are left (truncated file?)",
                (unsigned long long)n, in_left(&in));
  if (s->raw) {
    *data = (const unsigned char *)in.rp;
    *nbytes = n;
    return MX_OK;
  }
  unsigned char *out = alloc(ctx, (size_t)n + 1);
  if (!out) return MX_ENOMEM;
  MX_CHECK(in_read(&in, out, (size_t)n, "block"));
  *data = out;
  *nbytes = n;
  return MX_OK;
}
