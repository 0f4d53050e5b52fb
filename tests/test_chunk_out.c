/* Tests of the double-buffered output (src/io/chunk_out.c) and of the mesh
 * writers on top of it (issue 12, item 5): a background thread writes chunk
 * k while the caller fills chunk k+1, so what could go wrong is a chunk
 * written twice, dropped, out of order, or overwritten while in flight, and
 * a write error of the background thread lost. Checked here:
 *  - a byte stream whose every byte is a function of its position, written
 *    through the stream in pieces of random sizes (copied or formatted in
 *    place) with tiny chunks, to a file and to a pipe drained slowly by a
 *    checking reader (so the caller really waits for the writer);
 *  - write errors met by the writer thread (/dev/full, the file size limit)
 *    come back as MX_EIO, with the file's name in the message and nothing
 *    left behind;
 *  - every mesh format written with chunks of 1 KiB .. 8 MiB and 1 or 3
 *    threads is byte for byte the file of the single-buffered, synchronous
 *    path, and reads back (mx_read_mesh) to the mesh that was written; a
 *    mesh big enough for several 8 MiB chunks too.
 * Run as "test_chunk_out small" to skip the big mesh. */
#include <errno.h>
#include <math.h>
#include <omp.h>
#include <pthread.h>
#include <signal.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "check.h"
#include "base/common.h"
#include "io/atomic_file.h"
#include "io/chunk_out.h"
#include "io/read_mesh.h"
#include "soa/mesh.h"

#define OUT_DIR "chunk_out_out"
#include "file_util.h"
#include "io/write_mesh.h"
#include "io/cell_order.h"

/* ====================================================================== */
/* The stream itself                                                      */
/* ====================================================================== */

/* Byte i of the test stream: a dropped, repeated or displaced piece of any
 * length shows (the value depends on the position, not only on its low
 * bits). */
static unsigned char stream_byte(size_t i) {
  uint64_t x = (uint64_t)i * 0x9E3779B97F4A7C15ull;
  x ^= x >> 31;
  x *= 0xBF58476D1CE4E5B9ull;
  return (unsigned char)(x >> 56);
}

static uint64_t rng_state = 88172645463325252ull;
static uint64_t rnd(void) {
  rng_state ^= rng_state << 13;
  rng_state ^= rng_state >> 7;
  rng_state ^= rng_state << 17;
  return rng_state;
}

/* Writes total bytes of the test stream through o, in pieces of random
 * sizes up to 3 chunks, alternately copied (put) and formatted in place
 * (room / commit). Returns the first errno (0). */
static int feed_stream(mx_chunk_out *o, size_t total) {
  const size_t cap = mx_chunk_out_capacity(o);
  static unsigned char piece[3 << 16];
  size_t i = 0;
  while (i < total) {
    size_t n = 1 + rnd() % (3 * cap < sizeof piece ? 3 * cap : sizeof piece);
    if (n > total - i) n = total - i;
    if (rnd() & 1) {
      for (size_t k = 0; k < n; k++) piece[k] = stream_byte(i + k);
      const int e = mx_chunk_out_put(o, piece, n);
      if (e) return e;
    } else {
      size_t avail = 0;
      const size_t need = 1 + rnd() % cap;
      char *dst = mx_chunk_out_room(o, need, &avail);
      if (!dst) return mx_chunk_out_error(o);
      if (avail < need) return -1; /* the room promised */
      if (n > avail) n = avail;
      for (size_t k = 0; k < n; k++) dst[k] = (char)stream_byte(i + k);
      mx_chunk_out_commit(o, n);
    }
    i += n;
  }
  return mx_chunk_out_flush(o);
}

/* Whether path holds exactly the first total bytes of the stream. */
static int file_is_stream(const char *path, size_t total) {
  size_t len = 0;
  unsigned char *buf = (unsigned char *)slurp(path, &len);
  int ok = buf && len == total;
  for (size_t i = 0; ok && i < len; i++) ok = buf[i] == stream_byte(i);
  free(buf);
  return ok;
}

static void test_stream_file(void) {
  /* 64 KiB and up, multiples of 4 KiB: written direct where the file system
   * allows (whole blocks handed over, the rest carried to the next chunk) */
  static const size_t caps[] = {1024, 4099, 65536, 65543, 1 << 17, 0};
  char path[512];
  path_in(path, sizeof path, "stream.bin");
  for (size_t c = 0; c < sizeof caps / sizeof *caps; c++) {
    const size_t total = caps[c] ? 97 * caps[c] + 13 : (size_t)(20 << 20) + 13;
    mx_chunk_out_testing(caps[c], 0);
    const unsigned long before = mx_chunk_out_async_chunks();
    FILE *fp = fopen(path, "wb");
    CHECK(fp != NULL);
    if (!fp) continue;
    mx_chunk_out *o = mx_chunk_out_new(fileno(fp));
    CHECK(o != NULL);
    if (!o) continue;
    CHECK(feed_stream(o, total) == 0);
    mx_chunk_out_free(o);
    fclose(fp);
    CHECK(file_is_stream(path, total));
    /* the chunks went through the writer thread (not the fallback) */
    CHECK(mx_chunk_out_async_chunks() - before >= 2);
  }
  mx_chunk_out_testing(0, 0);
  unlink(path);
  printf("stream: pieces of random sizes through chunks of 1 KiB .. 8 MiB, bytes in order "
         "(%s)\n", mx_chunk_out_direct_chunks() ? "direct I/O used" : "no direct I/O here");
}

/* A reader at the other end of a pipe that checks every byte as it comes,
 * pausing now and then so that the writer thread blocks and the caller
 * waits for it. */
typedef struct {
  int fd;
  size_t total, got;
  int ok;
} pipe_reader;

static void *read_slowly(void *arg) {
  pipe_reader *r = arg;
  unsigned char buf[3000];
  r->ok = 1;
  for (int k = 0;; k++) {
    const ssize_t n = read(r->fd, buf, sizeof buf);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    for (ssize_t i = 0; i < n; i++) r->ok &= buf[i] == stream_byte(r->got + (size_t)i);
    r->got += (size_t)n;
    if (k % 64 == 0) {
      struct timespec ts = {0, 200000};
      nanosleep(&ts, NULL);
    }
  }
  return NULL;
}

static void test_stream_pipe(void) {
  int fds[2];
  CHECK(pipe(fds) == 0);
  pipe_reader r = {fds[0], 0, 0, 0};
  pthread_t th;
  CHECK(pthread_create(&th, NULL, read_slowly, &r) == 0);
  mx_chunk_out_testing(4099, 0);
  const size_t total = 1500 * 4099 + 7;
  mx_chunk_out *o = mx_chunk_out_new(fds[1]);
  CHECK(o != NULL);
  if (o) CHECK(feed_stream(o, total) == 0);
  mx_chunk_out_free(o);
  mx_chunk_out_testing(0, 0);
  close(fds[1]);
  pthread_join(th, NULL);
  close(fds[0]);
  CHECK(r.ok && r.got == total);
  printf("stream: %zu bytes through a slowly read pipe, in order\n", total);
}

/* ====================================================================== */
/* Errors of the writer thread                                            */
/* ====================================================================== */

static size_t fill_items(const void *ctx, size_t b, size_t e, char *out) {
  (void)ctx;
  for (size_t i = b; i < e; i++) memcpy(out + 8 * (i - b), &i, 8);
  return 8 * (e - b);
}

static void test_stream_errors(void) {
  if (!have_dev_full()) return;
  /* the stream: the error comes back within the chunks in flight */
  mx_chunk_out_testing(4096, 0);
  FILE *fp = fopen("/dev/full", "wb");
  CHECK(fp != NULL);
  if (!fp) return;
  mx_chunk_out *o = mx_chunk_out_new(fileno(fp));
  CHECK(o != NULL);
  char piece[1000];
  memset(piece, 'x', sizeof piece);
  int e = 0;
  size_t sent = 0;
  while (!e && sent < (1 << 20)) {
    e = mx_chunk_out_put(o, piece, sizeof piece);
    sent += sizeof piece;
  }
  CHECK(e == ENOSPC);
  /* one chunk written, one waiting, one filling (a buffer holds the
   * capacity and a block, for the rest carried in direct mode) */
  CHECK(sent <= 3 * (4096 + 4096) + sizeof piece);
  CHECK(mx_chunk_out_put(o, piece, 1) == ENOSPC); /* sticky */
  CHECK(mx_chunk_out_flush(o) == ENOSPC);
  mx_chunk_out_free(o);
  fclose(fp);

  /* the atomic file over it: emit and commit fail with MX_EIO */
  fp = fopen("/dev/full", "wb");
  mx_afile f;
  CHECK(mx_afile_from_stream(&f, fp, "/dev/full") == MX_OK);
  CHECK(mx_afile_emit(&f, 100000, 8, fill_items, NULL) == MX_EIO);
  CHECK(mx_afile_write(&f, piece, 1) == MX_EIO);
  CHECK(mx_afile_commit(&f) == MX_EIO);
  mx_afile_abort(&f);
  mx_chunk_out_testing(0, 0);
  CHECK(dev_full_intact());
  printf("/dev/full: ENOSPC of the writer thread back within three chunks, sticky; MX_EIO\n");
}

/* ====================================================================== */
/* Meshes                                                                 */
/* ====================================================================== */

typedef struct {
  size_t nnodes, ncells;
  double *xyz, *jens, *dist;
  uint8_t *type;
  uint32_t *conn, *order;
  int32_t *level, *tag;
  mx_field cf[2], pf[2];
  mx_mesh_view v;
} cmesh;

/* An n x n x n grid of cubes, each a hexahedron or the prism, pyramid or
 * tetrahedron on some of its corners (the writers do not look at shapes),
 * types mixed so that every format's blocks interleave; jittered
 * coordinates and fields with awkward values. by_type: the written order
 * groups the cells by type (as mixoct's views do), else index order. */
static void cmesh_make(cmesh *t, size_t n, int by_type) {
  memset(t, 0, sizeof *t);
  const size_t m = n + 1;
  t->nnodes = m * m * m;
  t->ncells = n * n * n;
  t->xyz = malloc(3 * t->nnodes * sizeof *t->xyz);
  t->dist = malloc(t->nnodes * sizeof *t->dist);
  t->tag = malloc(t->nnodes * sizeof *t->tag);
  t->jens = malloc(t->ncells * sizeof *t->jens);
  t->level = malloc(t->ncells * sizeof *t->level);
  t->type = malloc(t->ncells);
  t->conn = malloc(8 * t->ncells * sizeof *t->conn);
  t->order = by_type ? malloc(t->ncells * sizeof *t->order) : NULL;
  if (!t->xyz || !t->dist || !t->tag || !t->jens || !t->level || !t->type || !t->conn ||
      (by_type && !t->order)) {
    fprintf(stderr, "test: out of memory\n");
    exit(2);
  }
  for (size_t k = 0; k < m; k++)
    for (size_t j = 0; j < m; j++)
      for (size_t i = 0; i < m; i++) {
        const size_t p = (k * m + j) * m + i;
        const double jit = (double)(rnd() >> 11) * 0x1p-53 * 1e-3;
        t->xyz[3 * p] = (double)i + jit;
        t->xyz[3 * p + 1] = (double)j / 3.0;
        t->xyz[3 * p + 2] = (double)k * 1e-7 - jit;
        t->dist[p] = sqrt((double)p) - 100.25;
        t->tag[p] = (int32_t)(p % 7) - 3;
      }
  for (size_t k = 0; k < n; k++)
    for (size_t j = 0; j < n; j++)
      for (size_t i = 0; i < n; i++) {
        const size_t c = (k * n + j) * n + i;
        const size_t p0 = (k * m + j) * m + i;
        const uint32_t v[8] = {(uint32_t)p0, (uint32_t)(p0 + 1), (uint32_t)(p0 + m + 1),
                               (uint32_t)(p0 + m), (uint32_t)(p0 + m * m),
                               (uint32_t)(p0 + m * m + 1), (uint32_t)(p0 + m * m + m + 1),
                               (uint32_t)(p0 + m * m + m)};
        const int type = (int)(rnd() % 4);
        t->type[c] = (uint8_t)type;
        static const int8_t pick[4][8] = {{0, 1, 3, 4},
                                          {0, 1, 2, 3, 4},
                                          {0, 1, 3, 4, 5, 7},
                                          {0, 1, 2, 3, 4, 5, 6, 7}};
        for (int q = 0; q < 8; q++) t->conn[8 * c + q] = q < mx_cell_nodes[type] ? v[pick[type][q]] : 0;
        t->level[c] = (int32_t)(c % 300); /* > 255: Int32 in VTU */
        t->jens[c] = 1.0 / (double)(c + 3);
      }
  if (by_type) mx_cells_by_type(t->type, t->ncells, t->order, NULL);
  t->cf[0] = (mx_field){.name = "level", .ivalues = t->level};
  t->cf[1] = (mx_field){.name = "jens", .is_double = 1, .dvalues = t->jens};
  t->pf[0] = (mx_field){.name = "dist", .is_double = 1, .dvalues = t->dist};
  t->pf[1] = (mx_field){.name = "tag", .ivalues = t->tag};
  t->v = (mx_mesh_view){.nnodes = t->nnodes, .xyz = t->xyz, .ncells = t->ncells,
                        .type = t->type, .conn = t->conn, .ncell_fields = 2,
                        .cell_fields = t->cf, .npoint_fields = 2, .point_fields = t->pf,
                        .order = t->order};
}

static void cmesh_free(cmesh *t) {
  free(t->xyz);
  free(t->dist);
  free(t->tag);
  free(t->jens);
  free(t->level);
  free(t->type);
  free(t->conn);
  free(t->order);
  memset(t, 0, sizeof *t);
}

/* The formats, as mx_write_mesh names them (extension, ascii flag). */
typedef struct {
  const char *ext;
  int ascii;
  int readable; /* mx_read_mesh reads it back with cells in written order */
} format;

static const format formats[] = {
    {"vtu", 0, 1},  {"msh", 0, 1},    {"vtk", 0, 1}, {"meshb", 0, 0}, {"msh", 1, 1},
    {"vtk", 1, 1},  {"mesh", 0, 0},   {"getfem", 0, 0}, {"m3d", 0, 0}, {"mvm", 0, 0},
};
enum { NFORMATS = sizeof formats / sizeof *formats };

static void format_path(char *out, size_t cap, const char *stem, int k) {
  char name[128];
  snprintf(name, sizeof name, "%s_%d%s.%s", stem, k, formats[k].ascii ? "a" : "",
           formats[k].ext);
  path_in(out, cap, name);
}

/* Whether the file reads back to the mesh of the view: coordinates bit for
 * bit, cells in the view's written order (readable formats only). */
static int reads_back(const char *path, const mx_mesh_view *v) {
  mx_mesh_data d;
  memset(&d, 0, sizeof d);
  if (mx_read_mesh(path, &d) != MX_OK) return 0;
  int ok = d.nnodes == v->nnodes && d.ncells == v->ncells;
  for (size_t i = 0; ok && i < 3 * v->nnodes; i++) ok = memcmp(&d.xyz[i], &v->xyz[i], 8) == 0;
  for (size_t k = 0; ok && k < v->ncells; k++) {
    const size_t c = mx_view_cell(v, k);
    ok = d.type[k] == v->type[c];
    for (int q = 0; ok && q < mx_cell_nodes[v->type[c]]; q++)
      ok = d.conn[8 * k + q] == v->conn[8 * c + q];
  }
  mx_mesh_data_free(&d);
  return ok;
}

/* Every format with chunks of caps[] bytes (0: 8 MiB), 1 and 3 threads,
 * against the synchronous single-buffered file. */
static void check_formats(const cmesh *t, const char *stem, const size_t *caps, size_t ncaps,
                          int all_formats) {
  const int saved = omp_get_max_threads();
  for (int k = 0; k < NFORMATS; k++) {
    if (!all_formats && !(k <= 1)) continue; /* the big mesh: vtu and msh */
    char ref[512], out[512];
    format_path(ref, sizeof ref, stem, k);
    mx_chunk_out_testing(0, 1);
    CHECK(mx_write_mesh(ref, &t->v, formats[k].ascii) == MX_OK);
    if (formats[k].readable) CHECK(reads_back(ref, &t->v));
    for (size_t c = 0; c < ncaps; c++)
      for (int threads = 1; threads <= 3; threads += 2) {
        mx_chunk_out_testing(caps[c], 0);
        omp_set_num_threads(threads);
        const unsigned long before = mx_chunk_out_async_chunks();
        char stem2[64];
        snprintf(stem2, sizeof stem2, "%s_c%zu_t%d", stem, caps[c], threads);
        format_path(out, sizeof out, stem2, k);
        CHECK(mx_write_mesh(out, &t->v, formats[k].ascii) == MX_OK);
        const int same = files_equal(ref, out);
        CHECK(same);
        if (!same)
          fprintf(stderr, "%s differs from %s (chunks of %zu, %d threads)\n", out, ref, caps[c],
                  threads);
        CHECK(mx_chunk_out_async_chunks() - before >= 2); /* several chunks, in the thread */
        unlink(out);
      }
    unlink(ref);
  }
  omp_set_num_threads(saved);
  mx_chunk_out_testing(0, 0);
}

static void test_formats_small(void) {
  static const size_t caps[] = {1024, 4099, 65536, 65543};
  cmesh t;
  cmesh_make(&t, 20, 0);
  check_formats(&t, "idx", caps, 4, 1);
  cmesh_free(&t);
  cmesh_make(&t, 20, 1);
  check_formats(&t, "typ", caps, 4, 1);
  cmesh_free(&t);
  printf("8000 mixed cells, index and type order: %d formats, chunks of 1 KiB .. 64 KiB, 1 and 3 "
         "threads: same bytes as the single-buffered path, read back\n",
         NFORMATS);
}

static void test_formats_big(void) {
  static const size_t caps[] = {0};
  cmesh t;
  cmesh_make(&t, 72, 1);
  check_formats(&t, "big", caps, 1, 0);
  printf("%zu cells: .vtu and .msh over several 8 MiB chunks, same bytes, read back\n", t.ncells);
  cmesh_free(&t);
}

/* The file size limit stops write() in the writer thread (EFBIG): every
 * writer returns MX_EIO, names the file, and leaves nothing; with chunks of
 * 4 KiB (through the page cache) and 64 KiB (direct where allowed). */
static void size_limit_with(const cmesh *t, size_t cap) {
  struct rlimit old, lim;
  if (getrlimit(RLIMIT_FSIZE, &old) != 0) return;
  lim = old;
  lim.rlim_cur = 192 << 10;
  mx_chunk_out_testing(cap, 0);
  int st[NFORMATS];
  char msg[NFORMATS][1024], path[NFORMATS][512], log[512];
  path_in(log, sizeof log, "stderr.txt");
  if (setrlimit(RLIMIT_FSIZE, &lim) != 0) {
    printf("SKIP file size limit: setrlimit failed\n");
    return;
  }
  for (int k = 0; k < NFORMATS; k++) {
    format_path(path[k], sizeof path[k], "limited", k);
    capture_stderr_begin(log);
    st[k] = mx_write_mesh(path[k], &t->v, formats[k].ascii);
    capture_stderr_end(log, msg[k], sizeof msg[k]);
  }
  setrlimit(RLIMIT_FSIZE, &old);
  mx_chunk_out_testing(0, 0);
  unlink(log);
  for (int k = 0; k < NFORMATS; k++) {
    CHECK(st[k] == MX_EIO);
    CHECK(strstr(msg[k], path[k]) && strstr(msg[k], "cannot write"));
  }
  CHECK(count_entries(OUT_DIR, "limited") == 0);
}

static void test_size_limit(void) {
  cmesh t;
  cmesh_make(&t, 20, 1);
  void (*prev)(int) = signal(SIGXFSZ, SIG_IGN);
  size_limit_with(&t, 4096);
  size_limit_with(&t, 65536);
  signal(SIGXFSZ, prev);
  cmesh_free(&t);
  printf("file size limit met by the writer thread: MX_EIO, file named, nothing left\n");
}

int main(int argc, char **argv) {
  const int small_only = argc > 1 && !strcmp(argv[1], "small");
  mkdir(OUT_DIR, 0755);
  remove_dir_files(OUT_DIR);
  test_stream_file();
  test_stream_pipe();
  test_stream_errors();
  test_size_limit();
  test_formats_small();
  if (!small_only) test_formats_big();
  remove_dir_files(OUT_DIR);
  rmdir(OUT_DIR);
  const int fails = TEST_DONE();
  printf("%d passed, %d failed\n", fails ? 0 : 1, fails ? 1 : 0);
  return fails;
}
