/* mixoct: output files written under a temporary name and renamed when
 * complete (see atomic_file.h). */
#include "io/atomic_file.h"

#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <signal.h>
#include <omp.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "base/common.h"
#include "io/chunk_out.h"

enum {
  AFILE_PAR_MIN = 4096,  /* fewer items than this: one thread */
  AFILE_MAX_PARTS = 256,
  AFILE_TMP_TRIES = 1000,
};

static char *dup_string(const char *s) {
  size_t n = strlen(s) + 1;
  char *d = mx_alloc(n);
  if (d) memcpy(d, s, n);
  return d;
}

static void afile_reset(mx_afile *f) {
  memset(f, 0, sizeof *f);
}

/* ---- temporaries left by a signal ---------------------------------------- */

/* The temporaries being written, so that a signal handler can remove them
 * (mx_remove_temporaries). Fixed storage: the handler must not
 * allocate. */
enum { TMP_SLOTS = 16, TMP_PATH = 4096 };
static char tmp_path[TMP_SLOTS][TMP_PATH];
static volatile sig_atomic_t tmp_used[TMP_SLOTS];

static void tmp_register(const char *path) {
  if (strlen(path) >= TMP_PATH) return;
#pragma omp critical(mx_afile_tmp)
  for (int k = 0; k < TMP_SLOTS; k++)
    if (!tmp_used[k]) {
      memcpy(tmp_path[k], path, strlen(path) + 1);
      tmp_used[k] = 1;
      break;
    }
}

static void tmp_unregister(const char *path) {
#pragma omp critical(mx_afile_tmp)
  for (int k = 0; k < TMP_SLOTS; k++)
    if (tmp_used[k] && strcmp(tmp_path[k], path) == 0) {
      tmp_used[k] = 0;
      break;
    }
}

void mx_remove_temporaries(void) {
  for (int k = 0; k < TMP_SLOTS; k++)
    if (tmp_used[k]) {
      unlink(tmp_path[k]);
      tmp_used[k] = 0;
    }
}

/* Closes the stream, unlinks the temporary, frees everything. Does not
 * report anything: used on every failure path and by abort. */
static void afile_discard(mx_afile *f) {
  mx_chunk_out_free(f->out); /* the writer thread stops before the close */
  if (f->fp) fclose(f->fp);
  if (f->tmp) {
    unlink(f->tmp);
    tmp_unregister(f->tmp);
  }
  mx_free(f->tmp);
  mx_free(f->path);
  mx_free(f->real);
  int failed = f->failed;
  afile_reset(f);
  f->failed = failed;
}

/* Reports err about f->path, removes the temporary, returns MX_EIO. */
static int afile_fail(mx_afile *f, int err) {
  if (!f->failed) {
    mx_error(f->path, 0, "cannot write: %s", strerror(err ? err : EIO));
  }
  f->failed = 1;
  afile_discard(f);
  return MX_EIO;
}

/* For failures already reported by someone else (out of memory). */
static int afile_fail_quiet(mx_afile *f, int status) {
  f->failed = 1;
  afile_discard(f);
  return status;
}

/* An existing target that is not a regular file is written in place. */
static int target_is_special(const char *path) {
  struct stat st;
  if (stat(path, &st) != 0) return 0;
  return !S_ISREG(st.st_mode);
}

/* The double-buffered stream to the open f->fp. */
static int attach_stream(mx_afile *f) {
  f->out = mx_chunk_out_new(fileno(f->fp));
  if (!f->out) return afile_fail_quiet(f, MX_ENOMEM);
  return MX_OK;
}

static int open_in_place(mx_afile *f) {
  f->fp = fopen(f->real, "wb");
  if (!f->fp) return afile_fail(f, errno);
  return attach_stream(f);
}

/* Creates the temporary exclusively: never clobbers another writer's file. */
static int open_temporary(mx_afile *f) {
  size_t n = strlen(f->real) + 64;
  f->tmp = mx_alloc(n);
  if (!f->tmp) return afile_fail_quiet(f, MX_ENOMEM);
  long pid = (long)getpid();
  for (int k = 0; k < AFILE_TMP_TRIES; k++) {
    if (k == 0)
      snprintf(f->tmp, n, "%s.tmp.%ld", f->real, pid);
    else
      snprintf(f->tmp, n, "%s.tmp.%ld.%d", f->real, pid, k);
    int fd = open(f->tmp, O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
    if (fd < 0 && errno == EEXIST) continue;
    if (fd < 0) {
      int err = errno;
      mx_free(f->tmp);
      f->tmp = NULL; /* nothing was created: nothing to unlink */
      return afile_fail(f, err);
    }
    tmp_register(f->tmp);
    f->fp = fdopen(fd, "wb");
    if (!f->fp) {
      int err = errno;
      close(fd);
      return afile_fail(f, err);
    }
    return attach_stream(f);
  }
  mx_free(f->tmp);
  f->tmp = NULL;
  return afile_fail(f, EEXIST);
}

/* A symbolic link is written through: the file it names is replaced, the
 * link stays. Returns the path to write (allocated), or NULL when out of
 * memory. */
static char *through_links(const char *path) {
  struct stat st;
  if (lstat(path, &st) != 0 || !S_ISLNK(st.st_mode)) return dup_string(path);
  char *r = realpath(path, NULL);
  if (r) {
    char *d = dup_string(r);
    free(r);
    return d;
  }
  /* a dangling link: the name it holds, relative to the link's directory */
  char target[4096];
  const ssize_t n = readlink(path, target, sizeof target - 1);
  if (n <= 0) return dup_string(path);
  target[n] = '\0';
  const char *slash = strrchr(path, '/');
  if (target[0] == '/' || !slash) return dup_string(target);
  const size_t dl = (size_t)(slash - path) + 1, tl = strlen(target);
  char *d = mx_alloc(dl + tl + 1);
  if (!d) return NULL;
  memcpy(d, path, dl);
  memcpy(d + dl, target, tl + 1);
  return d;
}

int mx_afile_open(mx_afile *f, const char *path) {
  afile_reset(f);
  f->path = dup_string(path);
  f->real = f->path ? through_links(path) : NULL;
  if (!f->path || !f->real) return afile_fail_quiet(f, MX_ENOMEM); /* frees both */
  if (target_is_special(f->real)) return open_in_place(f);
  return open_temporary(f);
}

int mx_afile_from_stream(mx_afile *f, FILE *fp, const char *name) {
  afile_reset(f);
  f->path = dup_string(name ? name : "(stream)");
  if (!f->path) {
    if (fp) fclose(fp);
    f->failed = 1;
    return MX_ENOMEM;
  }
  f->fp = fp;
  if (!fp) return afile_fail(f, EBADF);
  /* from here on the descriptor is written directly: what the caller left
   * in the stream's buffer goes first */
  if (fflush(fp) != 0) return afile_fail(f, errno);
  return attach_stream(f);
}

int mx_afile_write(mx_afile *f, const void *data, size_t bytes) {
  if (f->failed || !f->fp) return MX_EIO;
  if (bytes == 0) return MX_OK;
  const int err = mx_chunk_out_put(f->out, data, bytes);
  if (err) return afile_fail(f, err);
  return MX_OK;
}

int mx_afile_printf(mx_afile *f, const char *fmt, ...) {
  char line[4096];
  va_list ap;
  va_start(ap, fmt);
  int n = vsnprintf(line, sizeof line, fmt, ap);
  va_end(ap);
  if (n < 0 || (size_t)n >= sizeof line) {
    mx_error(f->path, 0, "internal error: header line too long");
    return afile_fail_quiet(f, MX_EINTERNAL);
  }
  return mx_afile_write(f, line, (size_t)n);
}

/* fsync is refused by pipes, ttys and some devices: that is not a failure. */
static int sync_ignorable(int err) {
  return err == EINVAL || err == EROFS || err == ENOTSUP;
}

int mx_afile_commit(mx_afile *f) {
  if (f->failed || !f->fp) {
    afile_discard(f);
    return MX_EIO;
  }
  const int err = mx_chunk_out_flush(f->out);
  if (err) return afile_fail(f, err);
  mx_chunk_out_free(f->out); /* everything is written: the thread ends */
  f->out = NULL;
  errno = 0;
  if (fflush(f->fp) != 0) return afile_fail(f, errno);
  if (fsync(fileno(f->fp)) != 0 && !sync_ignorable(errno))
    return afile_fail(f, errno);
  FILE *fp = f->fp;
  f->fp = NULL; /* closed below whatever fclose returns */
  if (fclose(fp) != 0) return afile_fail(f, errno);
  if (f->tmp && rename(f->tmp, f->real) != 0) return afile_fail(f, errno);
  if (f->tmp) tmp_unregister(f->tmp);
  mx_free(f->tmp);
  f->tmp = NULL;
  afile_discard(f);
  return MX_OK;
}

void mx_afile_abort(mx_afile *f) {
  afile_discard(f);
}

int mx_afile_finish(mx_afile *f, int status) {
  if (status == MX_OK) return mx_afile_commit(f);
  mx_afile_abort(f);
  return status;
}

/* ---- chunked parallel emission ------------------------------------------- */

/* Fills count items from begin into dst (room for count * max_item_bytes
 * bytes), split among the threads; each part starts at its item's worst-case
 * place, then the parts are closed up in order (nothing moves when every
 * item took its whole room, as fixed-size binary items do). Returns the
 * bytes filled. */
static size_t emit_run(char *dst, size_t begin, size_t count, size_t max_item_bytes,
                       mx_afile_fill_fn fill, const void *ctx, int writer_busy) {
  size_t used[AFILE_MAX_PARTS];
  size_t nparts = 1;
  if (count >= AFILE_PAR_MIN) {
    /* a core for the writer thread while it writes: with as many fillers
     * as cores, the barrier of each run would wait for the one sharing its
     * core with the writer */
    int t = omp_get_max_threads() - (writer_busy ? 1 : 0);
    nparts = t < 1 ? 1 : (size_t)t;
    if (nparts > AFILE_MAX_PARTS) nparts = AFILE_MAX_PARTS;
  }
#pragma omp parallel for num_threads((int)nparts) \
    schedule(static, 1) if (nparts > 1)
  for (size_t p = 0; p < nparts; p++) {
    size_t lo = count * p / nparts, hi = count * (p + 1) / nparts;
    used[p] = fill(ctx, begin + lo, begin + hi, dst + lo * max_item_bytes);
  }
  size_t pos = used[0];
  for (size_t p = 1; p < nparts; p++) {
    const char *src = dst + count * p / nparts * max_item_bytes;
    if (src != dst + pos && used[p]) memmove(dst + pos, src, used[p]);
    pos += used[p];
  }
  return pos;
}

int mx_afile_emit(mx_afile *f, size_t nitems, size_t max_item_bytes,
                  mx_afile_fill_fn fill, const void *ctx) {
  if (f->failed || !f->fp) return MX_EINPUT;
  if (nitems == 0) return MX_OK;
  if (max_item_bytes == 0) max_item_bytes = 1;
  const size_t cap = mx_chunk_out_capacity(f->out);
  if (max_item_bytes > cap) {
    mx_error(f->path, 0, "internal error: items of %zu bytes do not fit a chunk",
             max_item_bytes);
    return afile_fail_quiet(f, MX_EINTERNAL);
  }
  /* Runs fill the free room of the current chunk; a chunk with less than
   * a quarter free (and not enough for what is left) is handed over first,
   * so that runs stay long enough to split among the threads. */
  for (size_t begin = 0; begin < nitems;) {
    const size_t left = nitems - begin;
    size_t want = cap / 4;
    if (left <= want / max_item_bytes) want = left * max_item_bytes;
    if (want < max_item_bytes) want = max_item_bytes;
    size_t avail = 0;
    char *dst = mx_chunk_out_room(f->out, want, &avail);
    if (!dst) return afile_fail(f, mx_chunk_out_error(f->out));
    size_t count = avail / max_item_bytes;
    if (count > left) count = left;
    const int busy = mx_chunk_out_busy(f->out);
    mx_chunk_out_commit(f->out, emit_run(dst, begin, count, max_item_bytes, fill, ctx, busy));
    begin += count;
  }
  return MX_OK;
}
