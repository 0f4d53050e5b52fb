/* mixoct: one binary Gmsh MSH 4.1 file from a distributed mesh, MPI-IO.
 *
 * The file is the one src/io/write_msh.c writes for a plain binary mesh
 * (read its header comment for the sections and the binary encoding: host
 * byte order, 8-byte size_t counts and tags, 4-byte ints, doubles):
 *   $MeshFormat, $PhysicalNames (one volume group "domain"), $Entities (one
 *   volume, the bounding box over all ranks), $Nodes (one block: all node
 *   tags, then all coordinates), $Elements (one block per type present on
 *   some rank, tet, pyramid, prism, hex).
 * Every part's place follows from global counts, so each rank computes the
 * offsets itself and writes its bytes there:
 *   - node tags and coordinates in global-id order: the owned ids of rank r
 *     are [first_owned, first_owned + nowned), so its tags go to
 *     8 * first_owned past the start of the tags and its coordinates to
 *     24 * first_owned past the start of the coordinates, each owned node
 *     at its id (no sort: the ids are a permutation of the range, inverted
 *     into `pos`);
 *   - the block of type t holds rank 0's cells of that type, then rank
 *     1's, ..., each in local order: rank r's start at the exclusive scan
 *     of the per-rank counts; element tags are positions in the file + 1;
 *   - rank 0 writes the headers between the parts.
 * Each rank writes its parts in chunks of at most mx_write_msh_mpi_chunk
 * bytes (memory stays one chunk whatever the mesh size), every chunk one
 * contiguous range of the file.
 *
 * Independent writes (MPI_File_write_at), not collective ones
 * (MPI_File_write_at_all): with Open MPI 4.1's default MPI-IO (ompio,
 * fcoll vulcan) a collective write that fails (tested: every rank writing
 * to /dev/full, ENOSPC) returns with the library's internal collectives out
 * of step, and the next collective file call (MPI_File_close) waits
 * forever; ROMIO does not, but is not the default. The failure contract
 * (the same status on every rank, no file left) needs the calls to return.
 * And each rank's part is a few large contiguous ranges, which the
 * two-phase aggregation of collective writes would only move between
 * ranks.
 *
 * Failures. A rank that fails (allocation, a write) stops writing and
 * records its first message; the ranks agree on the outcome at fixed
 * points (after the checks, after opening, after writing, syncing and
 * closing, after the rename) and rank 0 prints the lowest failing rank's
 * message naming the file and removes the temporary. */
#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "base/common.h"
#include "io/msh_order.h"
#include "mpi/write_msh_mpi.h"
#include "soa/mesh.h"

size_t mx_write_msh_mpi_chunk = (size_t)16 << 20;

enum {
  MSG_MAX = 320,
  HEAD_MAX = 512,       /* the longest header part but the prefix */
  MAX_BODIES = 64,
  NAME_MAX_LEN = 160,   /* a body's name in $PhysicalNames (longer: cut) */
  /* the prefix: ~260 bytes, and per body a name line and an entity */
  PREFIX_MAX = HEAD_MAX + MAX_BODIES * (NAME_MAX_LEN + 32 + 80),
  NAME_LEN = PATH_MAX + 64, /* the file's name, broadcast from rank 0 */
  BLOCK_HEAD = 20,      /* element block head: dim, tag, type (int), count */
  MAX_RECORD = 8 * 9,   /* a hexahedron: its tag and 8 node tags */
  ENTITY_TAG = 1,
  PHYSICAL_TAG = 1,
};

typedef struct {
  MPI_Comm comm;
  int rank, size;
  MPI_File fh;
  int failed;          /* this rank saw a failure: it writes nothing more */
  int oom;             /* and it was an allocation (the status: MX_ENOMEM) */
  char msg[MSG_MAX];   /* its first message (after agree: the agreed one) */
  char *buf;           /* one chunk */
  size_t chunk;
} wctx;

/* The first failure of this rank: its message, prefixed by the rank when
 * it is not rank 0 (which prints it). */
__attribute__((format(printf, 2, 3))) static void fail(wctx *W, const char *fmt, ...) {
  if (W->failed) return;
  W->failed = 1;
  int n = W->rank > 0 ? snprintf(W->msg, sizeof W->msg, "rank %d: ", W->rank) : 0;
  if (n < 0) n = 0;
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(W->msg + n, sizeof W->msg - (size_t)n, fmt, ap);
  va_end(ap);
}

static void fail_mpi(wctx *W, const char *what, int rc) {
  char s[MPI_MAX_ERROR_STRING];
  int len = 0;
  if (MPI_Error_string(rc, s, &len) != MPI_SUCCESS) snprintf(s, sizeof s, "MPI error %d", rc);
  fail(W, "cannot write: %s: %s", what, s);
}

/* Collective: whether any rank failed; if so every rank gets the message of
 * the lowest failing one (so all return the same status) and fails too. */
static int agree(wctx *W) {
  int mine = W->failed ? W->rank : W->size, first = W->size;
  MPI_Allreduce(&mine, &first, 1, MPI_INT, MPI_MIN, W->comm);
  if (first == W->size) return 0;
  MPI_Bcast(W->msg, MSG_MAX, MPI_CHAR, first, W->comm);
  W->msg[MSG_MAX - 1] = '\0';
  W->failed = 1;
  return 1;
}

/* ---- the input ------------------------------------------------------------ */

/* Local checks; builds pos: pos[g - first_owned] = the local index of the
 * owned node with global id g. 0, or -1 after fail(). */
static int check_local(wctx *W, const mx_dist_mesh *D, uint32_t **pos_out) {
  *pos_out = NULL;
  if (!D) {
    fail(W, "no mesh");
    return -1;
  }
  if ((D->nnodes && (!D->xyz || !D->gid || !D->owned)) ||
      (D->ncells && (!D->type || !D->conn))) {
    fail(W, "invalid distributed mesh: missing arrays");
    return -1;
  }
  if (D->nnodes >= UINT32_MAX) {
    fail(W, "invalid distributed mesh: %zu local nodes (at most 2^32 - 2)", D->nnodes);
    return -1;
  }
  if (D->nowned > D->nnodes || D->first_owned > D->nglobal ||
      D->nowned > D->nglobal - D->first_owned) {
    fail(W, "invalid distributed mesh: owned range [%llu, +%llu) of %llu nodes, %zu local nodes",
         (unsigned long long)D->first_owned, (unsigned long long)D->nowned,
         (unsigned long long)D->nglobal, D->nnodes);
    return -1;
  }
  uint32_t *pos = mx_alloc((size_t)(D->nowned + 1) * sizeof *pos);
  if (!pos) {
    W->oom = 1;
    fail(W, "out of memory");
    return -1;
  }
  for (uint64_t i = 0; i < D->nowned; i++) pos[i] = UINT32_MAX;
  uint64_t nown = 0;
  for (size_t i = 0; i < D->nnodes; i++) {
    const uint64_t g = D->gid[i];
    if (g >= D->nglobal) {
      fail(W, "invalid distributed mesh: node %zu: global id %llu of %llu nodes", i,
           (unsigned long long)g, (unsigned long long)D->nglobal);
      goto bad;
    }
    if (!D->owned[i]) continue;
    nown++;
    const uint64_t k = g - D->first_owned;
    if (g < D->first_owned || k >= D->nowned || pos[k] != UINT32_MAX) {
      fail(W,
           "invalid distributed mesh: owned node %zu: global id %llu outside the owned range "
           "[%llu, %llu) or owned twice",
           i, (unsigned long long)g, (unsigned long long)D->first_owned,
           (unsigned long long)(D->first_owned + D->nowned));
      goto bad;
    }
    pos[k] = (uint32_t)i;
  }
  if (nown != D->nowned) {
    fail(W, "invalid distributed mesh: %llu owned flags, nowned %llu", (unsigned long long)nown,
         (unsigned long long)D->nowned);
    goto bad;
  }
  if (D->nbodies < 0 || D->nbodies > MAX_BODIES ||
      (D->nbodies && (!D->body_physical || !D->body_names || (D->ncells && !D->cell_body)))) {
    fail(W, "invalid distributed mesh: %d bodies (at most %d, with their numbers, names and "
            "cells)", D->nbodies, MAX_BODIES);
    goto bad;
  }
  for (size_t c = 0; c < D->ncells; c++) {
    const int t = D->type[c];
    if (t < MX_TET || t > MX_HEX) {
      fail(W, "invalid distributed mesh: cell %zu: type %d", c, t);
      goto bad;
    }
    if (D->nbodies && (D->cell_body[c] < 1 || D->cell_body[c] > D->nbodies)) {
      fail(W, "invalid distributed mesh: cell %zu: body %d of %d", c, (int)D->cell_body[c],
           D->nbodies);
      goto bad;
    }
    for (int j = 0; j < mx_cell_nodes[t]; j++)
      if (D->conn[8 * c + (size_t)j] >= D->nnodes) {
        fail(W, "invalid distributed mesh: cell %zu: node %u of %zu local nodes", c,
             D->conn[8 * c + (size_t)j], D->nnodes);
        goto bad;
      }
  }
  *pos_out = pos;
  return 0;
bad:
  mx_free(pos);
  return -1;
}

/* ---- the header parts (the same on every rank; rank 0 writes them) -------- */

static void put(char **p, const void *data, size_t n) {
  memcpy(*p, data, n);
  *p += n;
}
static void put_str(char **p, const char *s) { put(p, s, strlen(s)); }
static void put_u64(char **p, uint64_t v) { put(p, &v, 8); }
static void put_int(char **p, int v) {
  const int32_t i = (int32_t)v;
  put(p, &i, 4);
}

/* $MeshFormat .. the node block's head: everything before the first node
 * tag. */
static size_t head_prefix(char *h, const mx_dist_mesh *D, const double *box, uint64_t nn) {
  char *p = h;
  put_str(&p, "$MeshFormat\n4.1 1 8\n");
  put_int(&p, 1);
  put_str(&p, "\n$EndMeshFormat\n$PhysicalNames\n");
  char line[NAME_MAX_LEN + 64];
  const int nb = D->nbodies ? D->nbodies : 1;
  snprintf(line, sizeof line, "%d\n", nb);
  put_str(&p, line);
  for (int b = 1; b <= nb; b++) {
    if (D->nbodies)
      snprintf(line, sizeof line, "3 %d \"%.*s\"\n", (int)D->body_physical[b - 1],
               (int)NAME_MAX_LEN, D->body_names[b - 1]);
    else
      snprintf(line, sizeof line, "3 %d \"domain\"\n", PHYSICAL_TAG);
    put_str(&p, line);
  }
  put_str(&p, "$EndPhysicalNames\n$Entities\n");
  const uint64_t ent[4] = {0, 0, 0, (uint64_t)nb};
  put(&p, ent, sizeof ent);
  for (int b = 1; b <= nb; b++) { /* one body: box[6 * 0], the whole box */
    put_int(&p, D->nbodies ? b : ENTITY_TAG);
    put(&p, box + 6 * (b - 1), 6 * sizeof *box);
    put_u64(&p, 1);
    put_int(&p, D->nbodies ? (int)D->body_physical[b - 1] : PHYSICAL_TAG);
    put_u64(&p, 0);
  }
  put_str(&p, "\n$EndEntities\n$Nodes\n");
  const uint64_t nodes[4] = {nn > 0, nn, nn > 0, nn};
  put(&p, nodes, sizeof nodes);
  if (nn > 0) {
    put_int(&p, 3);
    put_int(&p, ENTITY_TAG);
    put_int(&p, 0); /* no parametric coordinates */
    put_u64(&p, nn);
  }
  return (size_t)(p - h);
}

/* After the coordinates: the end of $Nodes and the head of $Elements. */
static size_t head_mid(char *h, uint64_t nblocks, uint64_t ne) {
  char *p = h;
  put_str(&p, "\n$EndNodes\n$Elements\n");
  const uint64_t el[4] = {nblocks, ne, ne > 0, ne};
  put(&p, el, sizeof el);
  return (size_t)(p - h);
}

static size_t head_block(char *h, int entity, int t, uint64_t count) {
  char *p = h;
  put_int(&p, 3);
  put_int(&p, entity);
  put_int(&p, mx_msh_type[t]);
  put_u64(&p, count);
  return (size_t)(p - h);
}

static const char tail[] = "\n$EndElements\n";

/* ---- writing -------------------------------------------------------------- */

/* bytes of this rank at off (nothing once it failed). Independent writes:
 * see the header comment for why not MPI_File_write_at_all. */
static void write_part(wctx *W, MPI_Offset off, const void *data, size_t bytes) {
  if (W->failed || bytes == 0) return;
  MPI_Status st;
  const int rc = MPI_File_write_at(W->fh, off, data, (int)bytes, MPI_BYTE, &st);
  if (rc != MPI_SUCCESS) {
    fail_mpi(W, "MPI_File_write_at", rc);
    return;
  }
  int done = 0;
  MPI_Get_count(&st, MPI_BYTE, &done);
  if (done < 0 || (size_t)done != bytes)
    fail(W, "cannot write: %d of %zu bytes written (disk full, quota or file size limit?)", done,
         bytes);
}

/* Blocks r = 4 * (b - 1) + type, b the body (1 without bodies). */
typedef struct {
  int nb;
  uint64_t total[4 * MAX_BODIES], before[4 * MAX_BODIES]; /* cells: all ranks, ranks before */
  MPI_Offset tags, coords, mid, block[4 * MAX_BODIES], end;
  uint64_t nblocks, ncells;
} layout;

static int cell_block(const mx_dist_mesh *D, size_t c) {
  return 4 * (D->nbodies ? D->cell_body[c] - 1 : 0) + D->type[c];
}

/* The owned nodes' tags, then their coordinates, in global-id order, a
 * chunk at a time. */
static void write_nodes(wctx *W, const mx_dist_mesh *D, const uint32_t *pos,
                        const layout *L) {
  const uint64_t per_tag = W->chunk / 8, per_xyz = W->chunk / 24;
  for (uint64_t i0 = 0; i0 < D->nowned && !W->failed; i0 += per_tag) {
    const uint64_t i1 = i0 + per_tag < D->nowned ? i0 + per_tag : D->nowned;
    char *p = W->buf;
    for (uint64_t i = i0; i < i1; i++) put_u64(&p, D->first_owned + i + 1);
    write_part(W, L->tags + (MPI_Offset)(8 * (D->first_owned + i0)), W->buf, 8 * (i1 - i0));
  }
  for (uint64_t i0 = 0; i0 < D->nowned && !W->failed; i0 += per_xyz) {
    const uint64_t i1 = i0 + per_xyz < D->nowned ? i0 + per_xyz : D->nowned;
    char *p = W->buf;
    for (uint64_t i = i0; i < i1; i++) put(&p, D->xyz + 3 * (size_t)pos[i], 24);
    write_part(W, L->coords + (MPI_Offset)(24 * (D->first_owned + i0)), W->buf,
               24 * (i1 - i0));
  }
}

/* This rank's cells of block r (a body's cells of one type) in local
 * order, a chunk at a time, a cursor running over the cells. */
static void write_cells(wctx *W, const mx_dist_mesh *D, const layout *L, int r) {
  const int t = r % 4;
  const int nn = mx_cell_nodes[t];
  const int8_t *perm = mx_msh_perm[t];
  const size_t rec = 8 * ((size_t)nn + 1);
  const uint64_t per = W->chunk / rec;
  uint64_t tag0 = 0; /* element tags before this block */
  for (int u = 0; u < r; u++) tag0 += L->total[u];
  size_t c = 0;   /* cursor over the local cells */
  uint64_t k = 0; /* this rank's cells of block r written so far */
  while (c < D->ncells && !W->failed) {
    char *p = W->buf;
    const uint64_t k0 = k;
    for (; c < D->ncells && k - k0 < per; c++) {
      if (cell_block(D, c) != r) continue;
      const uint32_t *row = D->conn + 8 * c;
      put_u64(&p, tag0 + L->before[r] + k + 1);
      for (int j = 0; j < nn; j++) put_u64(&p, D->gid[row[perm[j]]] + 1);
      k++;
    }
    const MPI_Offset off = L->block[r] + BLOCK_HEAD + (MPI_Offset)(rec * (L->before[r] + k0));
    write_part(W, off, W->buf, (size_t)(p - W->buf));
  }
}

/* Global counts, the boxes and the offsets (collective). box: 6 per body
 * (one without bodies: the owned nodes' box, as before). */
static void make_layout(wctx *W, const mx_dist_mesh *D, layout *L, double *box,
                        size_t *prefix_len, char *prefix) {
  L->nb = D->nbodies ? D->nbodies : 1;
  const int nr = 4 * L->nb;
  uint64_t cnt[4 * MAX_BODIES];
  memset(cnt, 0, sizeof cnt);
  for (size_t c = 0; c < D->ncells; c++) cnt[cell_block(D, c)]++;
  MPI_Allreduce(cnt, L->total, nr, MPI_UINT64_T, MPI_SUM, W->comm);
  MPI_Exscan(cnt, L->before, nr, MPI_UINT64_T, MPI_SUM, W->comm);
  if (W->rank == 0) memset(L->before, 0, sizeof L->before);

  /* the boxes: minima of (x, y, z, -x, -y, -z), without bodies over the
   * owned nodes, with bodies over each body's cells' nodes */
  double lo[6 * MAX_BODIES], all[6 * MAX_BODIES];
  for (int i = 0; i < 6 * L->nb; i++) lo[i] = INFINITY;
  if (!D->nbodies) {
    for (size_t i = 0; i < D->nnodes; i++) {
      if (!D->owned[i]) continue;
      const double *q = D->xyz + 3 * i;
      for (int a = 0; a < 3; a++) {
        lo[a] = q[a] < lo[a] ? q[a] : lo[a];
        lo[3 + a] = -q[a] < lo[3 + a] ? -q[a] : lo[3 + a];
      }
    }
  } else {
    for (size_t c = 0; c < D->ncells; c++) {
      double *l = lo + 6 * (D->cell_body[c] - 1);
      for (int j = 0; j < mx_cell_nodes[D->type[c]]; j++) {
        const double *q = D->xyz + 3 * (size_t)D->conn[8 * c + (size_t)j];
        for (int a = 0; a < 3; a++) {
          l[a] = q[a] < l[a] ? q[a] : l[a];
          l[3 + a] = -q[a] < l[3 + a] ? -q[a] : l[3 + a];
        }
      }
    }
  }
  MPI_Allreduce(lo, all, 6 * L->nb, MPI_DOUBLE, MPI_MIN, W->comm);
  for (int b = 0; b < L->nb; b++)
    for (int a = 0; a < 3; a++) {
      const int some = all[6 * b + a] <= -all[6 * b + 3 + a]; /* a body with no cell: 0s */
      box[6 * b + a] = some ? all[6 * b + a] : 0.0;
      box[6 * b + 3 + a] = some ? -all[6 * b + 3 + a] : 0.0;
    }

  const uint64_t n = D->nglobal;
  *prefix_len = head_prefix(prefix, D, box, n);
  L->tags = (MPI_Offset)*prefix_len;
  L->coords = L->tags + (MPI_Offset)(8 * n);
  L->mid = L->coords + (MPI_Offset)(24 * n);
  L->nblocks = L->ncells = 0;
  for (int r = 0; r < nr; r++) L->nblocks += L->total[r] > 0, L->ncells += L->total[r];
  char mid[HEAD_MAX];
  MPI_Offset at = L->mid + (MPI_Offset)head_mid(mid, L->nblocks, L->ncells);
  for (int r = 0; r < nr; r++) {
    L->block[r] = at;
    if (L->total[r])
      at += BLOCK_HEAD + (MPI_Offset)(8 * ((uint64_t)mx_cell_nodes[r % 4] + 1) * L->total[r]);
  }
  L->end = at;
}

/* Rank 0: where the bytes go (name: the temporary it creates, or path
 * itself when that is an existing non-regular file such as /dev/null),
 * and in *final (mx_free) the file to rename it onto, or NULL. 1 if it
 * created the temporary. */
static int choose_names(wctx *W, const char *path, char name[NAME_LEN], char **final) {
  name[0] = '\0';
  *final = NULL;
  struct stat st;
  char *real = NULL;
  if (lstat(path, &st) == 0 && S_ISLNK(st.st_mode))
    real = realpath(path, NULL); /* written through the link */
  if (!real) real = mx_strdup(path);
  if (!real) {
    W->oom = 1;
    fail(W, "out of memory");
    return 0;
  }
  if (strlen(real) + 32 >= NAME_LEN) {
    fail(W, "cannot write: path too long");
    mx_free(real);
    return 0;
  }
  if (stat(real, &st) == 0 && !S_ISREG(st.st_mode)) {
    snprintf(name, NAME_LEN, "%s", real); /* renaming would replace it */
    mx_free(real);
    return 0;
  }
  const long pid = (long)getpid();
  snprintf(name, NAME_LEN, "%s.tmp.%ld", real, pid);
  for (int k = 1; k < 1000 && lstat(name, &st) == 0; k++)
    snprintf(name, NAME_LEN, "%s.tmp.%ld.%d", real, pid, k);
  /* created here, exclusively: the name is ours, and a missing directory
   * or a permission gives errno's message */
  const int fd = open(name, O_WRONLY | O_CREAT | O_EXCL, 0666);
  if (fd < 0) {
    fail(W, "cannot write: %s", strerror(errno));
    name[0] = '\0';
    mx_free(real);
    return 0;
  }
  close(fd);
  *final = real;
  return 1;
}

/* Collective (the layout; MPI_File_sync): the headers (rank 0), the nodes
 * and the cells. */
static void write_file(wctx *W, const mx_dist_mesh *D, const uint32_t *pos) {
  layout L;
  double box[6 * MAX_BODIES];
  char prefix[PREFIX_MAX], mid[HEAD_MAX], bh[BLOCK_HEAD];
  size_t plen = 0;
  make_layout(W, D, &L, box, &plen, prefix);
  W->buf = mx_alloc(W->chunk);
  if (!W->buf) {
    W->oom = 1;
    fail(W, "out of memory");
  }
  const int nr = 4 * L.nb;
  if (W->rank == 0) {
    write_part(W, 0, prefix, plen);
    write_part(W, L.mid, mid, head_mid(mid, L.nblocks, L.ncells));
    for (int r = 0; r < nr; r++)
      if (L.total[r])
        write_part(W, L.block[r], bh,
                   head_block(bh, D->nbodies ? r / 4 + 1 : ENTITY_TAG, r % 4, L.total[r]));
    write_part(W, L.end, tail, sizeof tail - 1);
  }
  write_nodes(W, D, pos, &L);
  for (int r = 0; r < nr; r++)
    if (L.total[r]) write_cells(W, D, &L, r);
  mx_free(W->buf);
  W->buf = NULL;
  const int rc = MPI_File_sync(W->fh); /* a late write error shows here */
  if (rc != MPI_SUCCESS) fail_mpi(W, "MPI_File_sync", rc);
}

int mx_write_msh_mpi(const char *path, MPI_Comm comm, const mx_dist_mesh *D) {
  wctx W = {.comm = comm, .fh = MPI_FILE_NULL};
  MPI_Comm_rank(comm, &W.rank);
  MPI_Comm_size(comm, &W.size);
  W.chunk = mx_write_msh_mpi_chunk;
  if (W.chunk < MAX_RECORD) W.chunk = MAX_RECORD;
  if (W.chunk > (size_t)1 << 30) W.chunk = (size_t)1 << 30; /* an int count */

  /* the input: local checks, then the owned ranges must tile [0, nglobal)
   * in rank order (a rank that failed joins the same collectives) */
  uint32_t *pos = NULL;
  const int bad = check_local(&W, D, &pos);
  const uint64_t nowned = D ? D->nowned : 0; /* a rank's own bad range is its message */
  uint64_t before = 0, sum = 0;
  MPI_Exscan(&nowned, &before, 1, MPI_UINT64_T, MPI_SUM, comm);
  if (W.rank == 0) before = 0;
  MPI_Allreduce(&nowned, &sum, 1, MPI_UINT64_T, MPI_SUM, comm);
  if (!bad && (before != D->first_owned || sum != D->nglobal))
    fail(&W,
         "invalid distributed mesh: first_owned %llu, nglobal %llu; the exclusive scan of "
         "nowned gives %llu, its sum %llu",
         (unsigned long long)D->first_owned, (unsigned long long)D->nglobal,
         (unsigned long long)before, (unsigned long long)sum);
  if (agree(&W)) {
    mx_free(pos);
    if (W.rank == 0) mx_error(path, 0, "%s", W.msg);
    return MX_EINPUT;
  }

  /* the file: rank 0 names (and creates) it, every rank opens it */
  char name[NAME_LEN];
  char *final = NULL;
  const int created = W.rank == 0 ? choose_names(&W, path, name, &final) : 0;
  MPI_Bcast(name, NAME_LEN, MPI_CHAR, 0, comm);
  name[NAME_LEN - 1] = '\0';
  int opened = 0, all_opened = 0;
  if (name[0]) {
    const int rc = MPI_File_open(comm, name, MPI_MODE_WRONLY, MPI_INFO_NULL, &W.fh);
    if (rc == MPI_SUCCESS)
      opened = 1;
    else
      fail_mpi(&W, "MPI_File_open", rc);
  }
  MPI_Allreduce(&opened, &all_opened, 1, MPI_INT, MPI_MIN, comm);
  if (!agree(&W)) write_file(&W, D, pos);
  mx_free(pos);
  if (all_opened) {
    const int rc = MPI_File_close(&W.fh);
    if (rc != MPI_SUCCESS) fail_mpi(&W, "MPI_File_close", rc);
  }
  /* else MPI_File_open failed on some ranks only (they see the file system
   * differently): MPI_File_close is collective, so a rank that holds a
   * handle keeps it rather than wait forever for the others */

  if (!agree(&W) && W.rank == 0 && final && rename(name, final) != 0)
    fail(&W, "cannot write: %s", strerror(errno));
  const int failed = agree(&W);
  if (W.rank == 0) {
    if (failed && created) unlink(name);
    if (failed) mx_error(path, 0, "%s", W.msg);
  }
  mx_free(final);
  return !failed ? MX_OK : W.oom ? MX_ENOMEM : MX_EINPUT;
}
