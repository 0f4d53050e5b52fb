/* File utilities shared by the writer tests (and test_check): reading,
 * counting, comparing and removing files, the failure checks on /dev/full
 * and unwritable places, and a small mesh owning its arrays. All functions
 * are static inline, so a test that uses only some of them stays quiet
 * under -Wunused-function. A test that defines OUT_DIR (its output folder)
 * before including this header also gets path_in and unwritable_places. */
#ifndef MX_TEST_FILE_UTIL_H
#define MX_TEST_FILE_UTIL_H
#include <dirent.h>
#include <fcntl.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "check.h"
#include "soa/mesh.h"

/* ---- files ---------------------------------------------------------- */

/* The whole file, NUL-terminated (malloc'ed; NULL if unreadable); its
 * length in *len when len is not NULL. */
static inline char *slurp(const char *path, size_t *len) {
  FILE *fp = fopen(path, "rb");
  if (!fp) return NULL;
  fseek(fp, 0, SEEK_END);
  long n = ftell(fp);
  fseek(fp, 0, SEEK_SET);
  char *buf = n < 0 ? NULL : malloc((size_t)n + 1);
  if (buf && fread(buf, 1, (size_t)n, fp) != (size_t)n) {
    free(buf);
    buf = NULL;
  }
  fclose(fp);
  if (buf) buf[n] = '\0';
  if (len) *len = buf ? (size_t)n : 0;
  return buf;
}

/* Whether anything (even a dangling symbolic link) is at path. */
static inline int exists(const char *path) {
  struct stat st;
  return lstat(path, &st) == 0;
}

/* The size of the file at path in bytes, -1 if it cannot be stat'ed. */
static inline long long file_size(const char *path) {
  struct stat st;
  return stat(path, &st) == 0 ? (long long)st.st_size : -1;
}

/* Entries of dir whose name starts with prefix ("" counts all; "." and
 * ".." never count); -1 if dir cannot be opened. */
static inline int count_entries(const char *dir, const char *prefix) {
  DIR *d = opendir(dir);
  if (!d) return -1;
  int n = 0;
  struct dirent *e;
  while ((e = readdir(d))) {
    if (!strcmp(e->d_name, ".") || !strcmp(e->d_name, "..")) continue;
    if (strncmp(e->d_name, prefix, strlen(prefix)) == 0) n++;
  }
  closedir(d);
  return n;
}

/* Removes everything inside dir (subfolders too, made writable first),
 * leaving dir itself. */
static inline void remove_dir_files(const char *dir) {
  DIR *d = opendir(dir);
  if (!d) return;
  struct dirent *e;
  char path[4096];
  while ((e = readdir(d))) {
    if (!strcmp(e->d_name, ".") || !strcmp(e->d_name, "..")) continue;
    int n = snprintf(path, sizeof path, "%s/%s", dir, e->d_name);
    if (n < 0 || (size_t)n >= sizeof path) continue; /* too long a path */
    struct stat st;
    if (lstat(path, &st) == 0 && S_ISDIR(st.st_mode)) {
      chmod(path, 0755);
      remove_dir_files(path);
      rmdir(path);
    } else {
      unlink(path);
    }
  }
  closedir(d);
}

/* Whether both files are readable and hold the same bytes. */
static inline int files_equal(const char *a, const char *b) {
  size_t la = 0, lb = 0;
  char *x = slurp(a, &la), *y = slurp(b, &lb);
  int eq = x && y && la == lb && memcmp(x, y, la) == 0;
  free(x);
  free(y);
  return eq;
}

/* ---- stderr capture ------------------------------------------------ */

/* stderr goes to the file at path until capture_stderr_end, which restores
 * it and returns what was written (NUL-terminated in buf, cut to cap - 1
 * bytes). */
/* Writes len bytes to path (a CHECK fails when it cannot). */
static inline void write_bytes_file(const char *path, const void *data, size_t len) {
  FILE *f = fopen(path, "wb");
  CHECK(f != NULL);
  if (!f) return;
  CHECK(fwrite(data, 1, len, f) == len);
  fclose(f);
}

/* Replaces 1-based line `line` of text by repl (deleted if repl is NULL);
 * returns a malloc'd copy. */
static inline char *text_edit_line(const char *text, int line, const char *repl) {
  size_t n = strlen(text) + (repl ? strlen(repl) : 0) + 2;
  char *out = malloc(n), *o = out;
  if (!out) abort();
  const char *p = text;
  for (int l = 1; *p; l++) {
    const char *nl = strchr(p, '\n');
    size_t len = nl ? (size_t)(nl - p) + 1 : strlen(p);
    if (l != line) {
      memcpy(o, p, len);
      o += len;
    } else if (repl) {
      o += sprintf(o, "%s\n", repl);
    }
    p += len;
  }
  *o = '\0';
  return out;
}

/* Deletes lines [from, to] (1-based); returns a malloc'd copy. */
static inline char *text_cut_lines(const char *text, int from, int to) {
  char *t = strdup(text);
  if (!t) abort();
  for (int l = to; l >= from; l--) {
    char *u = text_edit_line(t, l, NULL);
    free(t);
    t = u;
  }
  return t;
}

static int capture_saved_fd = -1;
static inline void capture_stderr_begin(const char *path) {
  fflush(stderr);
  capture_saved_fd = dup(2);
  int fd = open(path, O_RDWR | O_CREAT | O_TRUNC, 0600);
  dup2(fd, 2);
  close(fd);
}
static inline const char *capture_stderr_end(const char *path, char *buf, size_t cap) {
  fflush(stderr);
  dup2(capture_saved_fd, 2);
  close(capture_saved_fd);
  buf[0] = '\0';
  FILE *f = fopen(path, "rb");
  if (f) {
    size_t n = fread(buf, 1, cap - 1, f);
    buf[n] = '\0';
    fclose(f);
  }
  return buf;
}

/* ---- failure checks ------------------------------------------------- */

/* Whether /dev/full is there as a character device; prints a SKIP line
 * when it is not. */
static inline int have_dev_full(void) {
  struct stat st;
  if (stat("/dev/full", &st) == 0 && S_ISCHR(st.st_mode)) return 1;
  printf("SKIP /dev/full: not available\n");
  return 0;
}

/* After writes to /dev/full: it is still the character device (written in
 * place, never replaced) and no temporary "full.*" was left in /dev. */
static inline int dev_full_intact(void) {
  struct stat st;
  return stat("/dev/full", &st) == 0 && S_ISCHR(st.st_mode) &&
         count_entries("/dev", "full.") == 0;
}

#ifdef OUT_DIR
/* out = OUT_DIR/name. */
static inline void path_in(char *out, size_t cap, const char *name) {
  snprintf(out, cap, "%s/%s", OUT_DIR, name);
}

/* What a test checks at one unwritable path: every write there fails, path
 * stays absent and dir (NULL: none) keeps no entry starting with prefix. */
typedef void (*unwritable_fn)(const void *ctx, const char *path,
                              const char *dir, const char *prefix);

/* Calls expect on the unwritable places: OUT_DIR/no_such_dir/x<ext> (the
 * folder must stay absent), a read-only OUT_DIR/readonly/x<ext> unless root
 * (chmod does not stop root), OUT_DIR/plainfile/x<plain_ext> (under a regular
 * file) and /proc/mixoct_<tag>_<pid><ext>. Leaves OUT_DIR/plainfile and
 * OUT_DIR/readonly (if made) behind. */
static inline void unwritable_places(unwritable_fn expect, const void *ctx,
                                     const char *tag, const char *ext,
                                     const char *plain_ext) {
  char name[256], path[512], dir[512];
  snprintf(name, sizeof name, "no_such_dir/x%s", ext);
  path_in(path, sizeof path, name);
  expect(ctx, path, NULL, "");
  path_in(dir, sizeof dir, "no_such_dir");
  CHECK(!exists(dir));
  if (geteuid() != 0) {
    path_in(dir, sizeof dir, "readonly");
    CHECK(mkdir(dir, 0755) == 0 && chmod(dir, 0555) == 0);
    snprintf(name, sizeof name, "readonly/x%s", ext);
    path_in(path, sizeof path, name);
    expect(ctx, path, dir, "");
    chmod(dir, 0755);
  } else {
    printf("running as root: chmod 0555 does not deny writing; using a "
           "path under a regular file and one under /proc instead\n");
  }
  path_in(path, sizeof path, "plainfile");
  FILE *fp = fopen(path, "w");
  CHECK(fp && fclose(fp) == 0);
  snprintf(name, sizeof name, "plainfile/x%s", plain_ext);
  path_in(path, sizeof path, name);
  expect(ctx, path, OUT_DIR, "plainfile.");
  char proc_path[128], proc_prefix[64];
  snprintf(proc_prefix, sizeof proc_prefix, "mixoct_%s_", tag);
  snprintf(proc_path, sizeof proc_path, "/proc/%s%ld%s", proc_prefix,
           (long)getpid(), ext);
  expect(ctx, proc_path, "/proc", proc_prefix);
}
#endif

/* ---- a mesh owning its arrays --------------------------------------- */

typedef struct {
  size_t nnodes, ncells;
  double *xyz;
  uint8_t *type;
  uint32_t *conn; /* 8 a cell */
  mx_mesh_view v; /* over the arrays, no fields */
} tmesh;

/* Zeroed arrays for nnodes nodes and ncells cells, and the view over them;
 * exits with status 2 when out of memory. */
static inline void tmesh_alloc(tmesh *t, size_t nnodes, size_t ncells) {
  memset(t, 0, sizeof *t);
  t->nnodes = nnodes;
  t->ncells = ncells;
  t->xyz = calloc(3 * nnodes + 1, sizeof(double));
  t->type = calloc(ncells + 1, 1);
  t->conn = calloc(8 * ncells + 1, sizeof(uint32_t));
  if (!t->xyz || !t->type || !t->conn) {
    fprintf(stderr, "test: out of memory\n");
    exit(2);
  }
  t->v = (mx_mesh_view){.nnodes = nnodes, .xyz = t->xyz, .ncells = ncells,
                        .type = t->type, .conn = t->conn};
}

/* Frees the arrays and zeroes t. */
static inline void tmesh_free(tmesh *t) {
  free(t->xyz);
  free(t->type);
  free(t->conn);
  memset(t, 0, sizeof *t);
}

/* Cell c: type and its nodes; the unused connectivity slots get 0xdeadbeef
 * (a writer must not read them). */
static inline void set_cell(tmesh *t, size_t c, int type,
                            const uint32_t *nodes) {
  t->type[c] = (uint8_t)type;
  for (int j = 0; j < mx_cell_nodes[type]; j++) t->conn[8 * c + j] = nodes[j];
  for (int j = mx_cell_nodes[type]; j < 8; j++) t->conn[8 * c + j] = 0xdeadbeef;
}

#endif
