/* mixoct: file identity and the check of a run's files (io/file_identity.h). */
#include "io/file_identity.h"

#include <string.h>
#include <sys/stat.h>

#include "base/common.h"

/* The name of path in its directory, and the directory's status. */
static int parent_of(const char *path, struct stat *dir, const char **base) {
  const char *slash = strrchr(path, '/');
  *base = slash ? slash + 1 : path;
  if (!slash) return stat(".", dir);
  if (slash == path) return stat("/", dir);
  const size_t n = (size_t)(slash - path);
  char *d = mx_alloc(n + 1);
  if (!d) return -1;
  memcpy(d, path, n);
  d[n] = '\0';
  const int r = stat(d, dir);
  mx_free(d);
  return r;
}

int mx_file_id_of(const char *path, mx_file_id *id) {
  struct stat st;
  if (!path || stat(path, &st) != 0) return 0;
  id->dev = (unsigned long long)st.st_dev;
  id->ino = (unsigned long long)st.st_ino;
  return 1;
}

int mx_same_file(const char *a, const char *b) {
  if (!a || !b || !*a || !*b) return 0;
  struct stat sa, sb;
  const int ea = stat(a, &sa) == 0, eb = stat(b, &sb) == 0;
  if (ea && eb) return sa.st_dev == sb.st_dev && sa.st_ino == sb.st_ino;
  if (ea || eb) return 0; /* one exists, the other not: two names */
  /* neither exists yet: the same name in the same directory */
  const char *na, *nb;
  if (parent_of(a, &sa, &na) != 0 || parent_of(b, &sb, &nb) != 0) return strcmp(a, b) == 0;
  return sa.st_dev == sb.st_dev && sa.st_ino == sb.st_ino && strcmp(na, nb) == 0;
}

static int writes(int use) { return use == MX_FILE_OUTPUT || use == MX_FILE_RESTART_OUT; }

int mx_check_file_uses(const mx_file_use *u, int n) {
  for (int i = 0; i < n; i++) {
    if (!u[i].path || !writes(u[i].use)) continue;
    for (int j = 0; j < n; j++) {
      if (j == i || !u[j].path) continue;
      if (writes(u[j].use) && j < i) continue; /* the pair was seen as (j, i) */
      if (u[i].use == MX_FILE_RESTART_OUT && u[j].use == MX_FILE_RESTART_IN) continue;
      if (!mx_same_file(u[i].path, u[j].path)) continue;
      const int in = !writes(u[j].use);
      mx_error(u[i].path, 0,
               "%s and %s are the same file (%s and %s): %s; nothing was written, "
               "choose another name",
               u[i].what, u[j].what, u[i].path, u[j].path,
               in ? "the output would replace the input" : "one output would replace the other");
      return MX_EINPUT;
    }
  }
  return MX_OK;
}
