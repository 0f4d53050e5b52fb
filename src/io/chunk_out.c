/* mixoct: double-buffered output, a background thread writing one chunk
 * while the caller fills the next (see chunk_out.h). */
#include "io/chunk_out.h"

#include <errno.h>
#include <fcntl.h>
#include <pthread.h>
#include <signal.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "base/common.h"

enum {
  CHUNK_BYTES = 8 << 20, /* one buffer */
  CHUNK_MIN = 1 << 10,   /* smallest buffer the test hook allows */
  BLOCK = 4096,          /* direct I/O: alignment of buffers, offsets, lengths */
  DIRECT_MIN = 64 << 10, /* smaller buffers are not written direct */
};

static size_t test_bytes = 0;  /* mx_chunk_out_testing: buffer bytes, 0 = default */
static int test_synchronous = 0;
static unsigned long async_chunks = 0;  /* written by writer threads */
static unsigned long direct_chunks = 0; /* of which with O_DIRECT */

struct mx_chunk_out {
  int fd;
  size_t cap;   /* the room promised to mx_chunk_out_room */
  size_t size;  /* of each buffer: cap and a block, for a carried rest */
  char *buf[2]; /* buf[1] allocated at the first hand-over */
  int cur;      /* the buffer being filled */
  size_t len;   /* bytes in it */
  int synchronous; /* chunks written by the caller (no thread, one buffer) */
  int blocks;      /* the descriptor was given O_DIRECT: chunks are handed
                      over in whole blocks, the rest carried to the next */
  long long pos;   /* file offset after the chunks written; < 0: not a file
                      whose writeback can be started (pipe, device) */
  int started;     /* the writer thread runs */
  pthread_t thread;
  /* shared with the writer, under mu */
  pthread_mutex_t mu;
  pthread_cond_t cv;
  const char *job; /* handed over, not written yet; NULL: the writer is idle */
  size_t job_len;
  int stop;
  int err; /* errno of the first failure, sticky */
};

void mx_chunk_out_testing(size_t bytes, int synchronous) {
  test_bytes = bytes == 0 ? 0 : bytes < CHUNK_MIN ? CHUNK_MIN : bytes;
  test_synchronous = synchronous;
}

/* Buffers aligned for direct I/O. */
static char *buffer_alloc(size_t n) { return mx_alloc_aligned(BLOCK, n); }

/* Turns O_DIRECT on or off; 0 when done. */
static int set_direct(int fd, int on) {
  const int fl = fcntl(fd, F_GETFL);
  if (fl < 0) return -1;
  return fcntl(fd, F_SETFL, on ? fl | O_DIRECT : fl & ~O_DIRECT);
}

/* write() until all of it is out; 0 or the errno. A direct write the file
 * system refuses (EINVAL) is done again through the page cache, and so is
 * every write after it. */
static int write_all(int fd, const char *p, size_t n) {
  while (n > 0) {
    const ssize_t w = write(fd, p, n);
    if (w < 0) {
      const int err = errno;
      if (err == EINTR) continue;
      const int fl = fcntl(fd, F_GETFL);
      if (err == EINVAL && fl >= 0 && (fl & O_DIRECT) && set_direct(fd, 0) == 0) continue;
      return err ? err : EIO;
    }
    if (w == 0) return EIO;
    p += w;
    n -= (size_t)w;
  }
  return 0;
}

/* The disk starts on the chunk just written while the next ones are made,
 * rather than all at the final fsync (a hint: failures are ignored, and
 * fsync still makes the file durable). */
static void start_writeback(mx_chunk_out *o, size_t n) {
  if (o->pos < 0 || o->blocks) return; /* direct: nothing waits in the cache */
#ifdef SYNC_FILE_RANGE_WRITE
  if (sync_file_range(o->fd, (off_t)o->pos, (off_t)n, SYNC_FILE_RANGE_WRITE) != 0) o->pos = -1;
#endif
  if (o->pos >= 0) o->pos += (long long)n;
}

static void *writer_main(void *arg) {
  mx_chunk_out *o = arg;
  pthread_mutex_lock(&o->mu);
  for (;;) {
    while (!o->job && !o->stop) pthread_cond_wait(&o->cv, &o->mu);
    if (!o->job) break; /* stopped, nothing pending */
    const char *p = o->job;
    const size_t n = o->job_len;
    int e = o->err; /* after a failure the rest is dropped */
    pthread_mutex_unlock(&o->mu);
    if (!e) e = write_all(o->fd, p, n);
    if (!e) {
      start_writeback(o, n);
      __atomic_fetch_add(&async_chunks, 1, __ATOMIC_RELAXED);
      if (o->blocks && (fcntl(o->fd, F_GETFL) & O_DIRECT))
        __atomic_fetch_add(&direct_chunks, 1, __ATOMIC_RELAXED);
    }
    pthread_mutex_lock(&o->mu);
    if (e && !o->err) o->err = e;
    o->job = NULL;
    pthread_cond_broadcast(&o->cv);
  }
  pthread_mutex_unlock(&o->mu);
  return NULL;
}

/* Starts the writer with the asynchronous signals blocked (it inherits the
 * mask of the thread creating it); returns 0 when it runs. */
static int start_writer(mx_chunk_out *o) {
  sigset_t all, old;
  sigfillset(&all);
  static const int synchronous_signals[] = {SIGSEGV, SIGBUS, SIGFPE,  SIGILL, SIGTRAP,
                                            SIGABRT, SIGSYS, SIGPIPE, SIGXFSZ};
  for (size_t k = 0; k < sizeof synchronous_signals / sizeof *synchronous_signals; k++)
    sigdelset(&all, synchronous_signals[k]);
  pthread_sigmask(SIG_BLOCK, &all, &old);
  const int rc = pthread_create(&o->thread, NULL, writer_main, o);
  pthread_sigmask(SIG_SETMASK, &old, NULL);
  return rc;
}

mx_chunk_out *mx_chunk_out_new(int fd) {
  mx_chunk_out *o = mx_calloc(sizeof *o);
  if (!o) return NULL;
  o->fd = fd;
  struct stat st;
  o->pos = fstat(fd, &st) == 0 && S_ISREG(st.st_mode) ? (long long)lseek(fd, 0, SEEK_CUR) : -1;
  o->cap = test_bytes ? test_bytes : CHUNK_BYTES;
  o->size = o->cap + BLOCK;
  o->synchronous = test_synchronous;
  o->buf[0] = buffer_alloc(o->size);
  if (!o->buf[0]) {
    mx_free(o);
    return NULL;
  }
  pthread_mutex_init(&o->mu, NULL);
  pthread_cond_init(&o->cv, NULL);
  return o;
}

unsigned long mx_chunk_out_async_chunks(void) {
  return __atomic_load_n(&async_chunks, __ATOMIC_RELAXED);
}

unsigned long mx_chunk_out_direct_chunks(void) {
  return __atomic_load_n(&direct_chunks, __ATOMIC_RELAXED);
}

size_t mx_chunk_out_capacity(const mx_chunk_out *o) { return o->cap; }

int mx_chunk_out_error(mx_chunk_out *o) {
  pthread_mutex_lock(&o->mu);
  const int e = o->err;
  pthread_mutex_unlock(&o->mu);
  return e;
}

/* The second buffer and the thread, at the first hand-over; without them
 * the stream goes on synchronously. */
static void go_parallel(mx_chunk_out *o) {
  if (o->synchronous || o->started) return;
  o->buf[1] = buffer_alloc(o->size);
  /* direct from here on (see chunk_out.h): a regular file at a block
   * boundary, buffers of whole blocks, a file system that takes it */
  o->blocks = !getenv("MX_NO_DIRECT_IO") && o->pos >= 0 && o->pos % BLOCK == 0 &&
              o->cap % BLOCK == 0 && o->cap >= DIRECT_MIN && set_direct(o->fd, 1) == 0;
  if (o->buf[1] && start_writer(o) == 0) {
    o->started = 1;
    return;
  }
  if (o->blocks) set_direct(o->fd, 0);
  o->blocks = 0;
  mx_free(o->buf[1]);
  o->buf[1] = NULL;
  o->synchronous = 1;
}

/* Hands the current buffer to the writer (after it finished the one before)
 * and makes the other one current; last: the final flush, which writes it
 * at once when no thread was started (a file of one buffer needs none).
 * Returns the first failure so far. */
static int hand_over(mx_chunk_out *o, int last) {
  if (o->len == 0) return mx_chunk_out_error(o);
  if (!last) go_parallel(o);
  if (!o->started) {
    int e = o->err;
    if (!e) e = o->err = write_all(o->fd, o->buf[o->cur], o->len);
    if (o->pos >= 0) o->pos += (long long)o->len;
    o->len = 0;
    return e;
  }
  pthread_mutex_lock(&o->mu);
  while (o->job) pthread_cond_wait(&o->cv, &o->mu);
  const int e = o->err;
  size_t n = o->len, tail = 0;
  if (!e) {
    /* direct: whole blocks; the rest starts the other buffer (idle now) */
    if (o->blocks) tail = n % BLOCK, n -= tail;
    if (tail) memcpy(o->buf[o->cur ^ 1], o->buf[o->cur] + n, tail);
    if (n) {
      o->job = o->buf[o->cur];
      o->job_len = n;
      pthread_cond_broadcast(&o->cv);
    }
  }
  pthread_mutex_unlock(&o->mu);
  o->cur ^= 1;
  o->len = tail;
  return e;
}

int mx_chunk_out_put(mx_chunk_out *o, const void *data, size_t n) {
  const char *p = data;
  while (n > 0) {
    if (o->len == o->size) {
      const int e = hand_over(o, 0);
      if (e) return e;
    }
    size_t k = o->size - o->len;
    if (k > n) k = n;
    memcpy(o->buf[o->cur] + o->len, p, k);
    o->len += k;
    p += k;
    n -= k;
  }
  return mx_chunk_out_error(o);
}

char *mx_chunk_out_room(mx_chunk_out *o, size_t need, size_t *avail) {
  if (need > o->cap) {
    pthread_mutex_lock(&o->mu);
    if (!o->err) o->err = EINVAL;
    pthread_mutex_unlock(&o->mu);
    return NULL;
  }
  if (o->size - o->len < need && hand_over(o, 0)) return NULL;
  if (mx_chunk_out_error(o)) return NULL;
  *avail = o->size - o->len;
  return o->buf[o->cur] + o->len;
}

int mx_chunk_out_busy(mx_chunk_out *o) {
  if (!o->started || o->blocks) return 0; /* direct: the writer waits for the disk */
  pthread_mutex_lock(&o->mu);
  const int busy = o->job != NULL;
  pthread_mutex_unlock(&o->mu);
  return busy;
}

void mx_chunk_out_commit(mx_chunk_out *o, size_t n) { o->len += n; }

int mx_chunk_out_flush(mx_chunk_out *o) {
  int e = hand_over(o, 1);
  if (!o->started) return e;
  pthread_mutex_lock(&o->mu);
  while (o->job) pthread_cond_wait(&o->cv, &o->mu);
  e = o->err;
  pthread_mutex_unlock(&o->mu);
  if (!e && o->len > 0) {
    /* direct: the last part of a block goes through the page cache (the
     * writer is idle: no race on the descriptor's flags) */
    set_direct(o->fd, 0);
    e = write_all(o->fd, o->buf[o->cur], o->len);
    o->len = 0;
    if (e) {
      pthread_mutex_lock(&o->mu);
      if (!o->err) o->err = e;
      pthread_mutex_unlock(&o->mu);
    }
  }
  return e;
}

void mx_chunk_out_free(mx_chunk_out *o) {
  if (!o) return;
  if (o->started) {
    pthread_mutex_lock(&o->mu);
    o->stop = 1;
    if (!o->err) o->err = ECANCELED; /* a chunk still waiting is dropped */
    pthread_cond_broadcast(&o->cv);
    pthread_mutex_unlock(&o->mu);
    pthread_join(o->thread, NULL);
  }
  pthread_mutex_destroy(&o->mu);
  pthread_cond_destroy(&o->cv);
  mx_free(o->buf[0]);
  mx_free(o->buf[1]);
  mx_free(o);
}
