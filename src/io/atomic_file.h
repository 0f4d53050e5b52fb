/* mixoct: output files that appear whole or not at all.
 *
 * mx_afile_open() creates "<path>.tmp.<pid>" (".<k>" appended if that name is
 * taken) in the directory of <path>; the data goes there and
 * mx_afile_commit() flushes, fsyncs, closes and renames it onto <path>.
 * mx_afile_abort() closes and unlinks the temporary. Every failure (open,
 * fwrite, fflush, fsync, fclose, rename: EACCES, ENOSPC, EIO, ...) prints
 * "mixoct: PATH: error: cannot write: <strerror>", removes the temporary at
 * once and makes the call (and every later call on the same handle) return
 * MX_EIO, so no partial or temporary file is ever left behind.
 *
 * When <path> already exists and is not a regular file (/dev/null,
 * /dev/stdout, a FIFO, a device) it is written in place: renaming over it
 * would replace the device node. mx_afile_from_stream() wraps a stream the
 * caller opened (tests use it on /dev/full); commit then only flushes and
 * closes it. A symbolic link is written through: the file it names is
 * replaced and the link stays.
 *
 * Usage:
 *   mx_afile f;
 *   MX_CHECK(mx_afile_open(&f, path));
 *   int st = mx_afile_write(&f, buf, n);              (repeat)
 *   if (st == MX_OK) st = mx_afile_commit(&f); else mx_afile_abort(&f);
 * abort is always safe (idempotent, also after a failed write or commit).
 *
 * The bytes go through a double-buffered stream (io/chunk_out.h): they are
 * collected in 8 MiB chunks and a background thread writes one chunk while
 * the caller formats the next. A write failure found by that thread (full
 * disk, file size limit, I/O error) is reported like any other, by the next
 * call that hands a chunk over or at the latest by commit, which returns
 * MX_EIO: the file is still never left partial or under its temporary
 * name. */
#ifndef MX_ATOMIC_FILE_H
#define MX_ATOMIC_FILE_H

#include <stddef.h>
#include <stdio.h>

#include "mixoct.h"

struct mx_chunk_out;

typedef struct {
  FILE *fp;   /* NULL once closed; written through its descriptor only */
  char *path; /* final name, used in messages */
  char *real; /* the file written: path, or what a symbolic link names */
  char *tmp;  /* temporary name; NULL when writing in place or a stream */
  int failed; /* sticky: a failure was reported, every call now fails */
  struct mx_chunk_out *out; /* the double-buffered stream to fp */
} mx_afile;

int mx_afile_open(mx_afile *f, const char *path);
/* mx_remove_temporaries (mixoct.h): the temporaries of the files being
 * written removed, from a signal handler. */
/* Takes ownership of fp (closed by commit/abort). name is for messages. */
int mx_afile_from_stream(mx_afile *f, FILE *fp, const char *name);
int mx_afile_write(mx_afile *f, const void *data, size_t bytes);
/* printf-style convenience for short header lines (at most 4 KiB each). */
int mx_afile_printf(mx_afile *f, const char *fmt, ...)
    __attribute__((format(printf, 2, 3)));
int mx_afile_commit(mx_afile *f);
void mx_afile_abort(mx_afile *f);
/* The end of every writer: commit when status is MX_OK, otherwise abort
 * and return status. */
int mx_afile_finish(mx_afile *f, int status);

/* Chunked, parallel writing of a sequence of nitems items. fill() writes
 * the items [begin, end) to out, which has room for
 * (end - begin) * max_item_bytes bytes, and returns the number of bytes it
 * wrote; fill(b, e) must give the bytes of fill(b, m) then fill(m, e).
 * Items are cut into runs that fit the free room of the stream's current
 * chunk, each run is split among the OpenMP threads, formatted in place and
 * the parts closed up in order, so the bytes do not depend on the number of
 * threads nor on the chunk size. fill() must be thread-safe. max_item_bytes
 * must not pass the chunk size (MX_EINTERNAL). */
typedef size_t (*mx_afile_fill_fn)(const void *ctx, size_t begin, size_t end,
                                   char *out);
int mx_afile_emit(mx_afile *f, size_t nitems, size_t max_item_bytes,
                  mx_afile_fill_fn fill, const void *ctx);

#endif
