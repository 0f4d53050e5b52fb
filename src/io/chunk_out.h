/* mixoct: double-buffered output to a file descriptor (issue 12, item 5:
 * writing as fast as the disk). The caller formats chunk k+1 into one
 * buffer while a background thread writes chunk k from the other.
 *
 * Two buffers of mx_chunk_out_capacity() bytes (8 MiB; and a 4 KiB block),
 * allocated once per file: the first when the stream is made, the second at
 * the first hand-over (a file smaller than one buffer never allocates it nor
 * starts a thread: it is written by the caller at flush, through the page
 * cache, as before). The caller appends to the current buffer, by copying
 * (mx_chunk_out_put) or by formatting in place (mx_chunk_out_room, then
 * mx_chunk_out_commit); a buffer that is full, or has less room than the
 * caller asks for, is handed to the writer thread, which write()s it, and
 * the caller goes on in the other one, after waiting for the writer to
 * finish the chunk before. At most one chunk is in flight, and chunks are
 * written in the order they were handed over: the file is the byte stream
 * the caller produced, whatever the buffer size or the thread timing.
 *
 * A regular file of more than one buffer is written direct (O_DIRECT: from
 * the two buffers to the disk, no copy into the page cache, whose pages can
 * cost more to get than the disk takes to write them): the buffers are
 * aligned, a chunk is handed over in whole 4 KiB blocks and the rest carried
 * to the start of the next one, and the last partial block is written
 * through the page cache at flush. Where the file system refuses direct I/O
 * (or MX_NO_DIRECT_IO is set in the environment: a way out for a file system
 * that accepts it but does it slowly) chunks go through the page cache, and
 * after each one the writer asks the kernel to start putting it on the disk
 * (sync_file_range, a hint). Either way the disk works while the next chunks
 * are made and the final fsync of io/atomic_file.c finds little left to do.
 *
 * Errors: the first failed write() (ENOSPC, EFBIG, EIO, EPIPE, ...) stores its
 * errno; the writer drops every chunk after it, and every later call returns
 * it, so the caller learns of a failure at its next hand-over or at the
 * latest at mx_chunk_out_flush. Reporting and cleaning up is the caller's
 * job (io/atomic_file.c: message naming the file, temporary removed).
 *
 * The writer is a POSIX thread, not an OpenMP one: the caller may be inside
 * or outside a parallel region and fills its buffer with its own OpenMP team
 * meanwhile. It runs with the asynchronous signals blocked (SIGINT, SIGTERM
 * are handled by the program's threads; SIGPIPE and SIGXFSZ, raised by its
 * own write(), still reach it as they reached the caller before). When the
 * thread or the second buffer cannot be had, chunks are written by the
 * caller, one buffer, same bytes. */
#ifndef MX_CHUNK_OUT_H
#define MX_CHUNK_OUT_H

#include <stddef.h>

typedef struct mx_chunk_out mx_chunk_out;

/* A stream writing to fd (not closed by it). NULL when out of memory (a
 * message was printed). */
mx_chunk_out *mx_chunk_out_new(int fd);
/* The room mx_chunk_out_room can always give (a buffer holds a 4 KiB block
 * more, for the rest carried by direct writes). */
size_t mx_chunk_out_capacity(const mx_chunk_out *o);
/* Appends n bytes (copied: data may be reused at once). 0 or an errno. */
int mx_chunk_out_put(mx_chunk_out *o, const void *data, size_t n);
/* At least need (<= capacity) contiguous free bytes of the current buffer,
 * handing it over first when it has fewer; *avail gets how many there are.
 * NULL on failure (mx_chunk_out_error tells the errno). Nothing is written
 * until mx_chunk_out_commit says how many of them were filled. */
char *mx_chunk_out_room(mx_chunk_out *o, size_t need, size_t *avail);
void mx_chunk_out_commit(mx_chunk_out *o, size_t n);
/* Hands over what is buffered and waits until everything is written.
 * 0 or the errno of the first failure. */
int mx_chunk_out_flush(mx_chunk_out *o);
/* Whether the writer thread is copying a chunk into the page cache now (a
 * hint: callers use one OpenMP thread fewer to fill the next, so that the
 * writer has a core; a direct write waits for the disk and needs none). */
int mx_chunk_out_busy(mx_chunk_out *o);
/* The errno of the first failure so far, 0 if none. */
int mx_chunk_out_error(mx_chunk_out *o);
/* Stops the writer (a chunk being written is finished, one waiting is
 * dropped unless flushed before) and frees everything; fd stays open. */
void mx_chunk_out_free(mx_chunk_out *o);

/* For tests: streams made after this call get buffers of bytes bytes
 * (0: the default; at least 1 KiB) and, when synchronous is set, write
 * every chunk in the caller's thread with a single buffer (the reference
 * path). Not thread-safe: call it between writes. */
void mx_chunk_out_testing(size_t bytes, int synchronous);
/* Chunks written by writer threads since the program started (tests check
 * that the double-buffered path was taken), and how many of them direct. */
unsigned long mx_chunk_out_async_chunks(void);
unsigned long mx_chunk_out_direct_chunks(void);

#endif
