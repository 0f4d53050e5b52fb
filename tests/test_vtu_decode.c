/* io/vtu_decode: base64 text and the blocks of VTK XML DataArrays (raw,
 * zlib, LZ4, xz), on cases computed by hand or by another implementation
 * (the zlib and xz streams: Python's zlib.compress and lzma.compress of the
 * bytes named beside them; the LZ4 block is written by hand: one token of
 * literals only), and on broken headers and streams, which must fail with
 * MX_EINPUT and never read past the bytes given. */
#include "io/vtu_decode.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <zlib.h>

#include "base/common.h"
#include "check.h"

/* ---- base64 ---------------------------------------------------------------- */

static int b64(const char *text, unsigned char *out, size_t n) {
  mx_b64 s;
  mx_b64_init(&s, text, text + strlen(text));
  return mx_b64_read(&s, out, n);
}

/* An encoder of its own, to build the texts of the block tests. */
static size_t encode(const unsigned char *b, size_t n, char *out) {
  static const char A[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  size_t k = 0;
  for (size_t i = 0; i < n; i += 3) {
    const unsigned v = (unsigned)b[i] << 16 | (i + 1 < n ? (unsigned)b[i + 1] << 8 : 0) |
                       (i + 2 < n ? b[i + 2] : 0);
    out[k++] = A[v >> 18 & 63];
    out[k++] = A[v >> 12 & 63];
    out[k++] = i + 1 < n ? A[v >> 6 & 63] : '=';
    out[k++] = i + 2 < n ? A[v & 63] : '=';
  }
  out[k] = '\0';
  return k;
}

static void test_base64(void) {
  unsigned char o[16];
  CHECK(b64("TWFu", o, 3) == 0 && memcmp(o, "Man", 3) == 0);
  CHECK(b64("TWE=", o, 2) == 0 && memcmp(o, "Ma", 2) == 0);
  CHECK(b64("TQ==", o, 1) == 0 && o[0] == 'M');
  CHECK(b64(" T W\nF u\r\n", o, 3) == 0 && memcmp(o, "Man", 3) == 0); /* blanks */
  /* two texts, the first padded: a new quantum after the padding */
  CHECK(b64("TQ==TWFu", o, 4) == 0 && memcmp(o, "MMan", 4) == 0);
  CHECK(b64("TWE=TWE=", o, 4) == 0 && memcmp(o, "MaMa", 4) == 0);
  /* read in pieces: the rest of a quantum is kept */
  {
    mx_b64 s;
    const char *t = "TWFuTWFu";
    mx_b64_init(&s, t, t + 8);
    CHECK(mx_b64_read(&s, o, 1) == 0 && o[0] == 'M');
    CHECK(mx_b64_read(&s, o, 4) == 0 && memcmp(o, "anMa", 4) == 0);
    CHECK(mx_b64_read(&s, o, 1) == 0 && o[0] == 'n');
    CHECK(mx_b64_read(&s, o, 1) == -2); /* the end */
  }
  CHECK(b64("TW@u", o, 3) == -1);  /* not base64 */
  CHECK(b64("TWF", o, 3) == -1);   /* a quantum cut short */
  CHECK(b64("T===", o, 1) == -1);  /* padding too early */
  CHECK(b64("TQ=a", o, 1) == -1);  /* data after the padding */
  CHECK(b64("TWFu", o, 4) == -2);  /* more than the text holds */
  CHECK(b64("TWFu<x", o, 4) == -2); /* '<' ends the text */
  {
    mx_b64 s;
    const char *t = "TWFuTWFu";
    mx_b64_init(&s, t, t + 8);
    CHECK(mx_b64_left(&s) >= 6 && mx_b64_left(&s) <= 9);
  }
}

/* ---- blocks ---------------------------------------------------------------- */

static void *plain_alloc(void *ctx, size_t bytes) {
  void **keep = ctx;
  for (int i = 0; i < 16; i++)
    if (!keep[i]) return keep[i] = mx_alloc(bytes);
  return NULL;
}

typedef struct {
  int st;
  uint64_t n;
  unsigned char data[64];
  char err[256];
} result;

/* Decodes bytes b[0, n) raw, and base64-encoded as one text; both must
 * agree. */
static result run(const unsigned char *b, size_t n, int hsize, int swap, mx_vtu_comp comp) {
  result R[2];
  char *text = mx_alloc(4 * n / 3 + 8);
  encode(b, n, text);
  for (int k = 0; k < 2; k++) {
    void *keep[16] = {0};
    mx_vtu_src s = {k ? NULL : (const char *)b, k ? text : NULL,
                    k ? text + strlen(text) : (const char *)b + n, hsize, swap, comp};
    const unsigned char *d = NULL;
    const char *at = NULL;
    memset(&R[k], 0, sizeof R[k]);
    R[k].st = mx_vtu_decode(&s, plain_alloc, keep, &d, &R[k].n, R[k].err, sizeof R[k].err, &at);
    if (R[k].st == MX_OK && R[k].n <= sizeof R[k].data) memcpy(R[k].data, d, (size_t)R[k].n);
    if (R[k].st == MX_EINPUT) CHECK(at != NULL && R[k].err[0] != '\0');
    for (int i = 0; i < 16; i++) mx_free(keep[i]);
  }
  mx_free(text);
  CHECK(R[0].st == R[1].st && R[0].n == R[1].n && memcmp(R[0].data, R[1].data, 64) == 0);
  return R[0];
}

static const unsigned char z_hello_wo[16] = {0x78, 0x9c, 0xcb, 0x48, 0xcd, 0xc9, 0xc9, 0x57,
                                             0x28, 0xcf, 0x07, 0x00, 0x0e, 0x28, 0x03, 0x1b};
static const unsigned char z_rld[12] = {0x78, 0x9c, 0x2b, 0xca, 0x49, 0x51,
                                        0x04, 0x00, 0x03, 0xf9, 0x01, 0x64};
static const unsigned char xz_hello[64] = {
    0xfd, 0x37, 0x7a, 0x58, 0x5a, 0x00, 0x00, 0x04, 0xe6, 0xd6, 0xb4, 0x46, 0x02, 0x00, 0x21, 0x01,
    0x16, 0x00, 0x00, 0x00, 0x74, 0x2f, 0xe5, 0xa3, 0x01, 0x00, 0x04, 0x68, 0x65, 0x6c, 0x6c, 0x6f,
    0x00, 0x00, 0x00, 0x00, 0xb1, 0x37, 0xb9, 0xdb, 0xe5, 0xda, 0x1e, 0x9b, 0x00, 0x01, 0x1d, 0x05,
    0xb8, 0x2d, 0x80, 0xaf, 0x1f, 0xb6, 0xf3, 0x7d, 0x01, 0x00, 0x00, 0x00, 0x00, 0x04, 0x59, 0x5a};

/* Appends the UInt32 little-endian v at b + *n. */
static void put32(unsigned char *b, size_t *n, uint32_t v) {
  for (int i = 0; i < 4; i++) b[(*n)++] = (unsigned char)(v >> (8 * i));
}

static void test_raw(void) {
  unsigned char b[64];
  size_t n = 0;
  put32(b, &n, 4);
  memcpy(b + n, "abcd", 4);
  result r = run(b, n + 4, 4, 0, MX_VTU_RAW);
  CHECK(r.st == MX_OK && r.n == 4 && memcmp(r.data, "abcd", 4) == 0);
  r = run(b, n + 3, 4, 0, MX_VTU_RAW); /* one byte short */
  CHECK(r.st == MX_EINPUT);
  /* a UInt64 header, big-endian (swapped on a little-endian host) */
  const unsigned char be[11] = {0, 0, 0, 0, 0, 0, 0, 3, 'x', 'y', 'z'};
  const unsigned char le[11] = {3, 0, 0, 0, 0, 0, 0, 0, 'x', 'y', 'z'};
  const int host_le = __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__;
  r = run(host_le ? be : le, 11, 8, 1, MX_VTU_RAW);
  CHECK(r.st == MX_OK && r.n == 3 && memcmp(r.data, "xyz", 3) == 0);
  r = run(host_le ? le : be, 11, 8, 0, MX_VTU_RAW);
  CHECK(r.st == MX_OK && r.n == 3 && memcmp(r.data, "xyz", 3) == 0);
  /* a header larger than the file */
  n = 0;
  put32(b, &n, 0xfffffff0u);
  CHECK(run(b, n + 4, 4, 0, MX_VTU_RAW).st == MX_EINPUT);
  CHECK(run(b, 2, 4, 0, MX_VTU_RAW).st == MX_EINPUT); /* not even a header */
  /* header and data base64-encoded apart (VTK's way): "AwAAAA==" "eHl6" */
  {
    const char *t = "AwAAAA==eHl6";
    void *keep[16] = {0};
    mx_vtu_src s = {NULL, t, t + strlen(t), 4, 0, MX_VTU_RAW};
    const unsigned char *d;
    uint64_t nb;
    char err[128];
    const char *at;
    CHECK(host_le && mx_vtu_decode(&s, plain_alloc, keep, &d, &nb, err, sizeof err, &at) == MX_OK &&
          nb == 3 && memcmp(d, "xyz", 3) == 0);
    for (int i = 0; i < 16; i++) mx_free(keep[i]);
  }
}

/* A compressed block set: header [nb, bs, last, sizes...] then streams. */
static size_t pack(unsigned char *b, uint32_t nb, uint32_t bs, uint32_t last, const uint32_t *cs,
                   const unsigned char *const *streams) {
  size_t n = 0;
  put32(b, &n, nb);
  put32(b, &n, bs);
  put32(b, &n, last);
  for (uint32_t k = 0; k < nb; k++) put32(b, &n, cs[k]);
  for (uint32_t k = 0; k < nb; k++) {
    memcpy(b + n, streams[k], cs[k]);
    n += cs[k];
  }
  return n;
}

static void test_compressed(void) {
  if (__BYTE_ORDER__ != __ORDER_LITTLE_ENDIAN__) return; /* the headers are written LE */
  unsigned char b[256];
  /* zlib, two blocks: "hello wo" (8) and "rld!" (the last, 4) */
  const unsigned char *zs[2] = {z_hello_wo, z_rld};
  uint32_t cs[2] = {16, 12};
  size_t n = pack(b, 2, 8, 4, cs, zs);
  result r = run(b, n, 4, 0, MX_VTU_ZLIB);
  CHECK(r.st == MX_OK && r.n == 12 && memcmp(r.data, "hello world!", 12) == 0);
  /* one byte flipped anywhere in the streams: refused (their header
   * check, a broken stream or its Adler-32), or, when the flip only touches
   * the unused bits after a stream's last deflate block (byte 11 of the
   * first, 7 of the second: 0x00), read with the same bytes */
  int refused = 0;
  for (size_t i = 20; i < 20 + 16 + 12; i++) { /* both streams */
    b[i] ^= 0x10;
    r = run(b, n, 4, 0, MX_VTU_ZLIB);
    CHECK(r.st == MX_EINPUT || (r.st == MX_OK && memcmp(r.data, "hello world!", 12) == 0));
    CHECK(r.st == MX_EINPUT || i == 20 + 11 || i == 20 + 16 + 7);
    refused += r.st == MX_EINPUT;
    b[i] ^= 0x10;
  }
  CHECK(refused == 26);
  CHECK(run(b, n - 1, 4, 0, MX_VTU_ZLIB).st == MX_EINPUT); /* truncated */
  /* the last block declared 5 bytes: "rld!" is 4 */
  n = pack(b, 2, 8, 5, cs, zs);
  r = run(b, n, 4, 0, MX_VTU_ZLIB);
  CHECK(r.st == MX_EINPUT && strstr(r.err, "block 1") != NULL);
  /* a full last block (0): 8 bytes expected, 4 given */
  n = pack(b, 2, 8, 0, cs, zs);
  CHECK(run(b, n, 4, 0, MX_VTU_ZLIB).st == MX_EINPUT);
  /* first block declared 7 bytes: it holds 8 */
  n = pack(b, 2, 7, 4, cs, zs);
  CHECK(run(b, n, 4, 0, MX_VTU_ZLIB).st == MX_EINPUT);
  /* more blocks than the file has bytes for; a compressed size past the end */
  n = pack(b, 2, 8, 4, cs, zs);
  b[0] = 0xff, b[1] = 0xff, b[2] = 0xff;
  CHECK(run(b, n, 4, 0, MX_VTU_ZLIB).st == MX_EINPUT);
  n = pack(b, 1, 8, 0, cs, zs);
  b[12] = 0xe8, b[13] = 0x03; /* block 0 of 1000 compressed bytes */
  CHECK(run(b, n, 4, 0, MX_VTU_ZLIB).st == MX_EINPUT);
  /* a block size no zlib stream of that many bytes can give */
  n = pack(b, 1, 16 * 1033, 0, cs, zs);
  r = run(b, n, 4, 0, MX_VTU_ZLIB);
  CHECK(r.st == MX_EINPUT && r.n == 0);
  /* no block: no data */
  n = pack(b, 0, 8, 0, cs, zs);
  r = run(b, n, 4, 0, MX_VTU_ZLIB);
  CHECK(r.st == MX_OK && r.n == 0);

  /* LZ4: token 0x50 (5 literals, no match), "hello" */
  const unsigned char lz[6] = {0x50, 'h', 'e', 'l', 'l', 'o'};
  const unsigned char *ls[1] = {lz};
  uint32_t lcs[1] = {6};
  n = pack(b, 1, 5, 0, lcs, ls);
  r = run(b, n, 4, 0, MX_VTU_LZ4);
  CHECK(r.st == MX_OK && r.n == 5 && memcmp(r.data, "hello", 5) == 0);
  n = pack(b, 1, 6, 0, lcs, ls); /* declared 6 */
  CHECK(run(b, n, 4, 0, MX_VTU_LZ4).st == MX_EINPUT);
  const unsigned char lzbad[6] = {0x60, 'h', 'e', 'l', 'l', 'o'}; /* 6 literals, 5 there */
  ls[0] = lzbad;
  n = pack(b, 1, 6, 0, lcs, ls);
  CHECK(run(b, n, 4, 0, MX_VTU_LZ4).st == MX_EINPUT);

  /* xz: "hello" in one uncompressed LZMA2 chunk (bytes 27..31) */
  const unsigned char *xs[1] = {xz_hello};
  uint32_t xcs[1] = {64};
  n = pack(b, 1, 5, 0, xcs, xs);
  r = run(b, n, 4, 0, MX_VTU_LZMA);
  CHECK(r.st == MX_OK && r.n == 5 && memcmp(r.data, "hello", 5) == 0);
  b[16 + 28] ^= 1; /* "hallo": the CRC64 of the stream no longer matches */
  CHECK(run(b, n, 4, 0, MX_VTU_LZMA).st == MX_EINPUT);
  b[16 + 28] ^= 1;
  CHECK(run(b, n - 10, 4, 0, MX_VTU_LZMA).st == MX_EINPUT);
  /* the zlib streams given as xz, and the reverse */
  n = pack(b, 2, 8, 4, cs, zs);
  CHECK(run(b, n, 4, 0, MX_VTU_LZMA).st == MX_EINPUT);
  n = pack(b, 1, 5, 0, xcs, xs);
  CHECK(run(b, n, 4, 0, MX_VTU_ZLIB).st == MX_EINPUT);
}

/* 40 zlib blocks of 32 KiB (more than 1 MiB: decompressed in parallel),
 * the last one short; then two of them broken: the message names the
 * first. */
static void test_many_blocks(void) {
  enum { NB = 40, BS = 32768, LAST = 1000 };
  const size_t total = (size_t)(NB - 1) * BS + LAST;
  unsigned char *data = mx_alloc(total), *file = mx_alloc(total + 8 * (NB + 3) + 1024 * NB);
  uint64_t cs[NB];
  unsigned char *streams = mx_alloc((size_t)NB * (BS + 1024));
  for (size_t i = 0; i < total; i++) data[i] = (unsigned char)((i * 7 + i / 1000) % 251);
  size_t sum = 0;
  for (int k = 0; k < NB; k++) {
    uLongf n = BS + 1024;
    CHECK(compress(streams + sum, &n, data + (size_t)k * BS, k + 1 < NB ? BS : LAST) == Z_OK);
    cs[k] = n;
    sum += n;
  }
  const uint64_t head[3] = {NB, BS, LAST};
  memcpy(file, head, 24);
  memcpy(file + 24, cs, sizeof cs);
  memcpy(file + 24 + sizeof cs, streams, sum);
  const size_t n = 24 + sizeof cs + sum;
  for (int broken = 0; broken < 2; broken++) {
    if (broken) {
      size_t at17 = 24 + sizeof cs;
      for (int k = 0; k < 17; k++) at17 += cs[k];
      file[at17 + cs[17] / 2] ^= 0x5a;
      file[n - cs[NB - 1] / 2] ^= 0x5a; /* in the last block */
    }
    void *keep[16] = {0};
    mx_vtu_src src = {(const char *)file, NULL, (const char *)file + n, 8, 0, MX_VTU_ZLIB};
    const unsigned char *d = NULL;
    uint64_t nb = 0;
    char err[256] = "";
    const char *at = NULL;
    const int st = mx_vtu_decode(&src, plain_alloc, keep, &d, &nb, err, sizeof err, &at);
    if (!broken)
      CHECK(st == MX_OK && nb == total && memcmp(d, data, total) == 0);
    else
      CHECK(st == MX_EINPUT && strstr(err, "block 17 of 40") != NULL);
    for (int i = 0; i < 16; i++) mx_free(keep[i]);
  }
  mx_free(data);
  mx_free(file);
  mx_free(streams);
}

/* Each allocation of a decode made to fail in turn: MX_ENOMEM. */
static void test_alloc_failures(void) {
  unsigned char b[256];
  const unsigned char *zs[2] = {z_hello_wo, z_rld};
  uint32_t cs[2] = {16, 12};
  const size_t n = pack(b, 2, 8, 4, cs, zs);
  char text[400];
  encode(b, n, text);
  for (int k = 1; k <= 3; k++)
    for (int b64 = 0; b64 < 2; b64++) {
      void *keep[16] = {0};
      mx_vtu_src s = {b64 ? NULL : (const char *)b, b64 ? text : NULL,
                      b64 ? text + strlen(text) : (const char *)b + n, 4, 0, MX_VTU_ZLIB};
      const unsigned char *d;
      uint64_t nb;
      char err[128];
      const char *at;
      mx_alloc_fail_countdown(k);
      const int st = mx_vtu_decode(&s, plain_alloc, keep, &d, &nb, err, sizeof err, &at);
      mx_alloc_fail_countdown(0);
      CHECK(st == (k == 3 && !b64 ? MX_OK : MX_ENOMEM)); /* raw: 2 allocations */
      for (int i = 0; i < 16; i++) mx_free(keep[i]);
    }
}

static void test_names(void) {
  CHECK(mx_vtu_compressor("vtkZLibDataCompressor", 21) == MX_VTU_ZLIB);
  CHECK(mx_vtu_compressor("vtkLZ4DataCompressor", 20) == MX_VTU_LZ4);
  CHECK(mx_vtu_compressor("vtkLZMADataCompressor", 21) == MX_VTU_LZMA);
  CHECK(mx_vtu_compressor("vtkZLibDataCompresso", 20) == -1);
  CHECK(strcmp(mx_vtu_compressor_name(MX_VTU_LZ4), "vtkLZ4DataCompressor") == 0);
}

int main(void) {
  test_base64();
  test_raw();
  test_compressed();
  if (__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__) test_many_blocks();
  test_names();
  if (__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__) test_alloc_failures();
  return TEST_DONE();
}
