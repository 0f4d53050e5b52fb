/* Statuses, messages (per calling thread), allocation (with its test hook),
 * words shown in messages, the clock and the memory marks: see common.h. */
#include "base/common.h"

#include <limits.h>
#include <malloc.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdint.h>
#include <stdlib.h>
#include <sys/mman.h>
#include <string.h>
#include <sys/resource.h>
#include <time.h>

#ifdef _OPENMP
#include <omp.h>
#endif

_Thread_local int mx_quiet = 0;
_Thread_local mx_message_fn mx_msg_fn = NULL;
_Thread_local void *mx_msg_user = NULL;

void mx_set_thread_message_handler(mx_message_fn fn, void *user) {
  mx_msg_fn = fn;
  mx_msg_user = user;
}
void mx_set_thread_quiet(int quiet) { mx_quiet = quiet != 0; }

_Thread_local unsigned long mx_msg_errors = 0;

_Thread_local int mx_msg_level = 0;

int mx_msg_worker(void) {
#ifdef _OPENMP
  for (int l = omp_get_level(); l > mx_msg_level; l--)
    if (omp_get_ancestor_thread_num(l) != 0) return 1;
#endif
  return 0;
}

/* The length of the valid UTF-8 character at p (at most n bytes, n >= 1,
 * p[0] >= 0x80) that is not a C1 control, else 0. */
static size_t utf8_char(const unsigned char *p, size_t n) {
  const unsigned c = p[0];
  /* the bytes of the character and the range of its second byte, which
   * rules out overlong forms, surrogates and code points above U+10FFFF */
  size_t k;
  unsigned lo = 0x80, hi = 0xbf;
  if (c >= 0xc2 && c <= 0xdf) {
    k = 2;
  } else if (c >= 0xe0 && c <= 0xef) {
    k = 3;
    if (c == 0xe0) lo = 0xa0;
    if (c == 0xed) hi = 0x9f;
  } else if (c >= 0xf0 && c <= 0xf4) {
    k = 4;
    if (c == 0xf0) lo = 0x90;
    if (c == 0xf4) hi = 0x8f;
  } else {
    return 0;
  }
  if (n < k || p[1] < lo || p[1] > hi) return 0;
  for (size_t i = 2; i < k; i++)
    if ((p[i] & 0xc0) != 0x80) return 0;
  if (c == 0xc2 && p[1] < 0xa0) return 0; /* U+0080 .. U+009F */
  return k;
}

const char *mx_show_word(const void *word, size_t len, char *out) {
  static const char hex[] = "0123456789abcdef";
  const unsigned char *p = word;
  const size_t show = len < MX_WORD_SHOW ? len : MX_WORD_SHOW;
  size_t w = 0, i = 0;
  while (i < show) {
    const unsigned c = p[i];
    size_t k = c >= 0x80 ? utf8_char(p + i, len - i) : 0;
    if (k && i + k <= show) { /* a whole character that fits */
      memcpy(out + w, p + i, k);
      w += k;
      i += k;
    } else if (k) { /* would cross the cut: cut before it */
      break;
    } else if (c >= 0x20 && c < 0x7f && c != '\\') {
      out[w++] = (char)c;
      i++;
    } else if (c == '\\') {
      out[w++] = '\\';
      out[w++] = '\\';
      i++;
    } else {
      out[w++] = '\\';
      out[w++] = 'x';
      out[w++] = hex[c >> 4];
      out[w++] = hex[c & 15];
      i++;
    }
  }
  if (i < len) {
    memcpy(out + w, "...", 3);
    w += 3;
  }
  out[w] = '\0';
  return out;
}

/* Control characters and bytes that are not valid UTF-8 (from a file name
 * or bytes of an input echoed in a message) are shown as \xNN: a message
 * never drives the terminal, and is valid UTF-8. */
static void escape_controls(const char *in, char *out, size_t n, int lines) {
  size_t w = 0, len = strlen(in);
  const unsigned char *p = (const unsigned char *)in;
  for (size_t i = 0; i < len && w + 5 < n;) {
    const size_t k = p[i] >= 0x80 ? utf8_char(p + i, len - i) : 0;
    if (k) {
      if (w + k + 1 > n) break;
      memcpy(out + w, p + i, k);
      w += k;
      i += k;
    } else if ((p[i] < 0x20 || p[i] >= 0x7f) && !(lines && p[i] == '\n')) {
      snprintf(out + w, n - w, "\\x%02x", p[i]);
      w += 4;
      i++;
    } else {
      out[w++] = (char)p[i++];
    }
  }
  out[w] = '\0';
}

/* s cut in the middle to at most max bytes ("head ... tail"), so that a
 * path of thousands of characters leaves room for the reason after it. */
static void elide_middle(char *s, size_t max) {
  const size_t n = strlen(s);
  if (n <= max) return;
  const size_t keep = (max - 5) / 2;
  size_t tail = n - keep; /* not inside a UTF-8 sequence */
  while (tail < n && ((unsigned char)s[tail] & 0xc0) == 0x80) tail++;
  size_t head = keep;
  while (head > 0 && ((unsigned char)s[head] & 0xc0) == 0x80) head--;
  memmove(s + head + 5, s + tail, n - tail + 1);
  memcpy(s + head, " ... ", 5);
}

static void vreport(const char *kind, const char *file, long line, int lines,
                    const char *fmt, va_list ap) {
  char msg[8192], name[1024], full[2600], safe[4 * 2600 + 1];
  vsnprintf(msg, sizeof msg, fmt, ap);
  elide_middle(msg, 1500);
  if (file) {
    snprintf(name, sizeof name, "%s", file);
    elide_middle(name, 600);
  }
  if (file && line > 0)
    snprintf(full, sizeof full, "%.600s:%ld: %.1500s", name, line, msg);
  else if (file)
    snprintf(full, sizeof full, "%.600s: %.1500s", name, msg);
  else
    snprintf(full, sizeof full, "%.1500s", msg);
  escape_controls(full, safe, sizeof safe, lines);
  if (mx_msg_fn && !mx_msg_worker()) {
    mx_msg_fn(mx_msg_user, kind[0] == 'e' ? MX_MSG_ERROR : MX_MSG_WARNING, safe);
    return;
  }
  /* "mixoct: FILE:LINE: error: text" */
  const char *colon = file ? strstr(safe, ": ") : NULL;
  if (colon) { /* after FILE or FILE:LINE */
    fprintf(stderr, "mixoct: %.*s: %s%s\n", (int)(colon - safe), safe, kind, colon + 2);
  } else {
    fprintf(stderr, "mixoct: %s%s\n", kind, safe);
  }
}

void mx_error(const char *file, long line, const char *fmt, ...) {
  mx_msg_errors++;
  va_list ap;
  va_start(ap, fmt);
  vreport("error: ", file, line, 0, fmt, ap);
  va_end(ap);
}

void mx_error_lines(const char *file, long line, const char *fmt, ...) {
  mx_msg_errors++;
  va_list ap;
  va_start(ap, fmt);
  vreport("error: ", file, line, 1, fmt, ap);
  va_end(ap);
}

void mx_warning(const char *file, long line, const char *fmt, ...) {
  if (mx_quiet || mx_msg_worker()) return; /* a worker's: not the caller's to see */
  va_list ap;
  va_start(ap, fmt);
  vreport("warning: ", file, line, 0, fmt, ap);
  va_end(ap);
}

/* cortex -s 9 peaks at 988 MiB this way against 1,262 MiB with every array
 * in the heap and kept there (freed holes the next, larger arrays cannot
 * use), with no more kernel time (measured: sys 1.2-1.3 s against 1.3-2.3 s;
 * issue 12). */
void mx_heap_setup(void) {
  const char *heap = getenv("MX_HEAP");
  if (heap && strcmp(heap, "heap") == 0) {
    mallopt(M_MMAP_MAX, 0);
    mallopt(M_TRIM_THRESHOLD, INT_MAX);
  } else if (!heap || strcmp(heap, "default") != 0) {
    mallopt(M_MMAP_THRESHOLD, 1 << 20);
    mallopt(M_TRIM_THRESHOLD, 8 << 20);
  }
}

/* The test hook (mx_alloc_fail_countdown): armed, the allocations since
 * it was set, and the one that fails (0: none). */
static int hook_armed;
static long hook_count, hook_fail_at;

void mx_alloc_fail_countdown(long k) {
  __atomic_store_n(&hook_armed, 0, __ATOMIC_SEQ_CST);
  __atomic_store_n(&hook_count, 0, __ATOMIC_SEQ_CST);
  __atomic_store_n(&hook_fail_at, k > 0 ? k : 0, __ATOMIC_SEQ_CST);
  __atomic_store_n(&hook_armed, k != 0, __ATOMIC_SEQ_CST);
}

long mx_alloc_count(void) { return __atomic_load_n(&hook_count, __ATOMIC_SEQ_CST); }

/* 1 when this allocation is the one the hook makes fail. */
static int hook_fails(void) {
  if (__builtin_expect(!__atomic_load_n(&hook_armed, __ATOMIC_RELAXED), 1)) return 0;
  const long n = __atomic_add_fetch(&hook_count, 1, __ATOMIC_SEQ_CST);
  return n == __atomic_load_n(&hook_fail_at, __ATOMIC_SEQ_CST);
}

/* NULL after the message (on the calling thread only: see mx_msg_fn). */
static void *out_of_memory(size_t bytes) {
  if (!mx_msg_worker()) mx_error(NULL, 0, "out of memory (asked for %zu bytes)", bytes);
  return NULL;
}

/* MX_HUGEPAGES=1: big arrays on transparent huge pages (read once). */
static int huge_pages(void) {
  static int on = -1;
  int v = __atomic_load_n(&on, __ATOMIC_RELAXED);
  if (v < 0) {
    const char *e = getenv("MX_HUGEPAGES");
    v = e && strcmp(e, "1") == 0;
    __atomic_store_n(&on, v, __ATOMIC_RELAXED);
  }
  return v;
}

void *mx_alloc(size_t bytes) {
  if (hook_fails()) return out_of_memory(bytes);
  if (bytes == 0) bytes = 1;
  enum { HUGE = 2u << 20 };
  if (bytes >= 8 * (size_t)HUGE) {
    /* Big arrays 2 MB aligned and rounded; on 2 MB pages (transparent huge
     * pages in "madvise" mode: one page fault per 2 MB instead of 512) only
     * with MX_HUGEPAGES=1. On the virtual machines this project is measured
     * on, a fresh 2 MB page costs the host's clearing too (the guest gives
     * freed 2 MB blocks back): cortex -s 9, 2 threads, 3 runs alternated,
     * system time 1.8-2.2 s with them against 1.24-1.30 s without, wall
     * 6.18-6.53 s against 5.64-5.86 s (1 thread: 10.8 against 10.0 s), the
     * user time the same (issue 31). */
    const size_t rounded = (bytes + HUGE - 1) & ~(size_t)(HUGE - 1);
    void *p = aligned_alloc(HUGE, rounded);
    if (!p) return out_of_memory(bytes);
#ifdef MADV_HUGEPAGE
    if (huge_pages()) madvise(p, rounded, MADV_HUGEPAGE);
#endif
    return p;
  }
  size_t rounded = (bytes + 63) & ~(size_t)63;
  void *p = aligned_alloc(64, rounded);
  return p ? p : out_of_memory(bytes);
}

void mx_advise_random(void *p, size_t bytes) {
  enum { HUGE = 2u << 20 };
  if (!p || bytes < 8 * (size_t)HUGE) return; /* not 2 MB aligned (mx_alloc) */
#ifdef MADV_HUGEPAGE
  madvise(p, (bytes + HUGE - 1) & ~(size_t)(HUGE - 1), MADV_HUGEPAGE);
#endif
}

void *mx_alloc_aligned(size_t align, size_t bytes) {
  if (hook_fails()) return out_of_memory(bytes);
  const size_t rounded = (bytes + align - 1) / align * align;
  void *p = aligned_alloc(align, rounded ? rounded : align);
  return p ? p : out_of_memory(bytes);
}

/* A large array is cleared by every thread, in the static schedule's
 * contiguous parts: its pages are first touched (mapped and cleared by the
 * kernel) by as many threads as the loops that use it run on, not by one. */
static void clear_parallel(char *p, size_t bytes) {
#ifdef _OPENMP
  enum { PART = 1 << 20 };
  if (bytes >= 8 * (size_t)PART && !omp_in_parallel() && omp_get_max_threads() > 1) {
    const long long parts = (long long)((bytes + PART - 1) / PART);
#pragma omp parallel for schedule(static)
    for (long long i = 0; i < parts; i++) {
      const size_t a = (size_t)i * PART, e = a + PART < bytes ? a + PART : bytes;
      memset(p + a, 0, e - a);
    }
    return;
  }
#endif
  memset(p, 0, bytes);
}

void *mx_calloc(size_t bytes) {
  void *p = mx_alloc(bytes);
  if (p) clear_parallel(p, bytes);
  return p;
}

void *mx_realloc(void *p, size_t bytes) {
  if (hook_fails()) return out_of_memory(bytes);
  /* a big array (mx_alloc rounds them up to 2 MB) grown or shrunk within
   * its last 2 MB stays: glibc copies an aligned block it reallocates
   * (measured: 0.3 s to add 4 elements to a 3.5 million element mesh) */
  if (p && bytes >= 16 * ((size_t)2 << 20)) {
    const size_t have = malloc_usable_size(p);
    if (bytes <= have && have - bytes < ((size_t)2 << 20)) return p;
  }
  void *q = realloc(p, bytes ? bytes : 1);
  return q ? q : out_of_memory(bytes);
}

char *mx_strdup(const char *s) {
  const size_t n = strlen(s) + 1;
  char *c = mx_alloc(n);
  if (c) memcpy(c, s, n);
  return c;
}

void mx_free(void *p) { free(p); }

void mx_release_range(void *p, size_t from, size_t to) {
  const uintptr_t page = 4096;
  /* from the page holding byte `from` (the bytes before it are dead too),
   * never before p's first whole page (the allocator's header) */
  uintptr_t a = ((uintptr_t)p + from) & ~(page - 1);
  const uintptr_t first = ((uintptr_t)p + page - 1) & ~(page - 1);
  if (a < first) a = first;
  const uintptr_t b = ((uintptr_t)p + to) & ~(page - 1);
  if (b > a) madvise((void *)a, b - a, MADV_DONTNEED);
}

double mx_wtime(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

void mx_mem_mark(const char *label) {
  static int on = -1;
  if (on < 0) on = getenv("MX_MEMTRACE") != NULL;
  if (!on) return;
  long pages = 0, rss = 0;
  FILE *f = fopen("/proc/self/statm", "r");
  if (f) {
    if (fscanf(f, "%ld %ld", &pages, &rss) != 2) rss = 0;
    fclose(f);
  }
  static double t0 = 0.0;
  if (t0 == 0.0) t0 = mx_wtime();
  const struct mallinfo2 mi = mallinfo2();
  fprintf(stderr, "mem %-24s rss %8.1f MB  peak %8.1f MB  in use %8.1f MB  t %7.3f s\n",
          label, (double)rss * 4096.0 / 1048576.0, mx_peak_rss_mb(),
          (double)(mi.uordblks + mi.hblkhd) / 1048576.0, mx_wtime() - t0);
}

double mx_peak_rss_mb(void) {
  struct rusage ru;
  if (getrusage(RUSAGE_SELF, &ru) != 0) return 0.0;
  return (double)ru.ru_maxrss / 1024.0; /* ru_maxrss is in KiB on Linux */
}
