/* libFuzzer target for the restart reader (src/io/restart.c); the element
 * index lists have their own, tools/fuzz_list.c.
 *
 * Each input goes through mx_restart_parse (text, or binary when it starts
 * with the binary magic), through mx_restart_parse_dim(2) (the quadtree
 * form, text only) and through mx_restart_parse again with the checksum of
 * a binary input recomputed (so mutations reach the checks after the
 * checksum). An input that parses must round-trip: written as text and
 * read back, it writes the same text again; written as binary and read
 * back, it gives the same struct. Any difference aborts.
 *
 * Build, from the source root:
 *   clang -std=c17 -g -O1 -fsanitize=fuzzer,address,undefined -fopenmp \
 *     -D_GNU_SOURCE -Isrc -Iinclude tools/fuzz_restart.c src/io/restart.c \
 *     src/base/common.c src/io/atomic_file.c src/io/text_num.c -lm -o fuzz_restart
 * Run (new inputs go to the first directory; the seed is read from the
 * second; round-trip files go to $TMPDIR, /dev/shm is fastest;
 * -close_fd_mask=2 silences the messages of the refused inputs, libFuzzer
 * still reports):
 *   mkdir -p /tmp/fuzz_restart_corpus
 *   TMPDIR=/dev/shm ./fuzz_restart -max_total_time=180 -max_len=8192 \
 *     -close_fd_mask=2 /tmp/fuzz_restart_corpus tools/fuzz_seeds/restart */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "base/common.h"
#include "io/restart.h"

/* The checksum of restart.h (4-lane multiply-xorshift over 8-byte words),
 * written again from its description. */
static uint64_t checksum(const uint8_t *p, size_t nwords) {
  uint64_t lane[4], x = 0x243F6A8885A308D3ull;
  for (int l = 0; l < 4; l++) lane[l] = 0x9E3779B97F4A7C15ull * (l + 1);
  for (size_t i = 0; i < nwords; i++) {
    uint64_t w, h;
    memcpy(&w, p + 8 * i, 8);
    h = (lane[i % 4] ^ w) * 0xff51afd7ed558ccdull;
    lane[i % 4] = h ^ (h >> 32);
  }
  uint64_t ws[5] = {nwords, lane[0], lane[1], lane[2], lane[3]};
  for (int k = 0; k < 5; k++) {
    x = (x ^ ws[k]) * 0xff51afd7ed558ccdull;
    x ^= x >> 32;
  }
  return x;
}

static int same(const mx_restart *a, const mx_restart *b) {
  if (a->nv != b->nv || a->ne != b->ne || a->no != b->no ||
      a->has_transform != b->has_transform || !a->nsub != !b->nsub)
    return 0;
  size_t nt = a->oct_tri_off[a->no];
  return memcmp(a->xyz, b->xyz, 24 * a->nv) == 0 &&
         memcmp(a->edge, b->edge, 12 * a->ne) == 0 &&
         memcmp(a->oct_node, b->oct_node, 32 * a->no) == 0 &&
         memcmp(a->oct_level, b->oct_level, a->no) == 0 &&
         memcmp(a->oct_tri_off, b->oct_tri_off, 8 * (a->no + 1)) == 0 &&
         (nt == 0 || memcmp(a->oct_tri, b->oct_tri, 4 * nt) == 0) &&
         (!a->has_transform ||
          memcmp(a->transform, b->transform, sizeof a->transform) == 0) &&
         (!a->nsub || memcmp(a->nsub, b->nsub, 4 * a->no) == 0) &&
         a->has_mesh == b->has_mesh &&
         (!a->has_mesh ||
          (a->mesh_nn == b->mesh_nn && a->mesh_nc == b->mesh_nc &&
           memcmp(a->mesh_xyz, b->mesh_xyz, 24 * a->mesh_nn) == 0 &&
           memcmp(a->mesh_nkey, b->mesh_nkey, 8 * a->mesh_nn) == 0 &&
           memcmp(a->mesh_state, b->mesh_state, a->mesh_nn) == 0 &&
           memcmp(a->mesh_type, b->mesh_type, a->mesh_nc) == 0 &&
           memcmp(a->mesh_conn, b->mesh_conn, 32 * a->mesh_nc) == 0 &&
           memcmp(a->mesh_leaf, b->mesh_leaf, 4 * a->mesh_nc) == 0 &&
           memcmp(a->mesh_jens, b->mesh_jens, 8 * a->mesh_nc) == 0));
}

static char *slurp(const char *path, size_t *len) {
  FILE *f = fopen(path, "rb");
  if (!f) abort();
  fseek(f, 0, SEEK_END);
  long n = ftell(f);
  fseek(f, 0, SEEK_SET);
  char *b = malloc((size_t)n + 1);
  if (!b || fread(b, 1, (size_t)n, f) != (size_t)n) abort();
  fclose(f);
  *len = (size_t)n;
  return b;
}

/* A parsed input must round-trip through both writers. */
static void round_trip(const mx_restart *r, int dim) {
  static char t1[512], t2[512], b1[512];
  if (!t1[0]) {
    const char *dir = getenv("TMPDIR");
    long pid = (long)getpid();
    dir = dir && *dir ? dir : "/tmp";
    snprintf(t1, sizeof t1, "%s/fuzz_restart_%ld_1.oct", dir, pid);
    snprintf(t2, sizeof t2, "%s/fuzz_restart_%ld_2.oct", dir, pid);
    snprintf(b1, sizeof b1, "%s/fuzz_restart_%ld.octb", dir, pid);
  }
  mx_restart a, b;
  if (mx_restart_write_text(t1, r) != MX_OK) abort();
  if (mx_restart_read_dim(t1, dim, &a) != MX_OK) abort();
  if (mx_restart_write_text(t2, &a) != MX_OK) abort();
  size_t n1, n2;
  char *x = slurp(t1, &n1), *y = slurp(t2, &n2);
  if (n1 != n2 || memcmp(x, y, n1) != 0) abort();
  free(x);
  free(y);
  if (dim == 2) { /* the quadtree form is text only */
    mx_restart_free(&a);
    unlink(t1);
    unlink(t2);
    return;
  }
  if (mx_restart_write_binary(b1, r) != MX_OK) abort();
  if (mx_restart_read(b1, &b) != MX_OK || !same(r, &b)) abort();
  mx_restart_free(&a);
  mx_restart_free(&b);
  unlink(t1);
  unlink(t2);
  unlink(b1);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  mx_restart r;
  if (mx_restart_parse("fuzz", data, size, &r) == MX_OK) {
    round_trip(&r, 3);
    mx_restart_free(&r);
  }
  if (mx_restart_parse_dim("fuzz", data, size, 2, &r) == MX_OK) {
    round_trip(&r, 2);
    mx_restart_free(&r);
  }
  if (size >= 56 && data[0] == 0x89 && size % 8 == 0) {
    uint8_t *b = malloc(size);
    memcpy(b, data, size);
    uint64_t sum = checksum(b, size / 8 - 1);
    memcpy(b + size - 8, &sum, 8);
    if (mx_restart_parse("fuzz", b, size, &r) == MX_OK) {
      round_trip(&r, 3);
      mx_restart_free(&r);
    }
    free(b);
  }
  return 0;
}
