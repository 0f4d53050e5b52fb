/* Tests of the MPI-IO Gmsh writer (src/mpi/write_msh_mpi.c), run through
 * mpirun on 1, 2 and 3 ranks by tests/msh_mpi_test.sh.
 *
 * Every rank builds the same mixed mesh: a 12^3 block of hexahedra, each
 * kept, cut into 2 prisms, 6 tetrahedra or 6 pyramids (around a centre
 * node), the nodes numbered in a scrambled order. The cells are split among
 * the ranks by index ranges; each rank numbers its nodes in order of first
 * use, the owner of a node is the lowest rank using it, the owned ranges
 * come from MPI_Exscan and global ids follow the owners' local orders (so
 * they are neither the original numbers nor sorted in local order). Three
 * distributions: equal ranges, ranges growing with the rank, and a subset
 * of the cells (tetrahedra and hexahedra only) all on the last rank (the
 * others hold nothing); each with the default chunk and with 200-byte
 * chunks (many collective rounds, different counts per rank). Rank 0 then
 *  - reads the file back with mx_read_mesh (src/io/read_mesh.h, `mixoct
 *    check`'s reader): node count = global count, cell count, the type of
 *    every cell and the coordinates of each of its nodes bit-equal to the
 *    original cell's (cells come grouped by type, each in the original
 *    order), every node's coordinates at its global id;
 *  - writes the same mesh with the serial writer (mx_write_msh, binary: a
 *    view with the nodes in global-id order and the cells grouped by type)
 *    and compares the whole files byte for byte.
 * Failures: a path in a missing directory, inconsistent inputs
 * (first_owned off by one on the last rank, an owned id outside rank 0's
 * range), /dev/full (written in place, every write failing) and a file
 * too large for the last rank's file size limit (its writes fail, the
 * others' succeed) give MX_EINPUT on every rank and leave nothing behind;
 * a file that exists is replaced, a symbolic link written through. */
#include <math.h>
#include <mpi.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <signal.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <unistd.h>

#include "check.h"
#include "base/common.h"
#include "io/read_mesh.h"
#include "mpi/write_msh_mpi.h"
#include "soa/mesh.h"

#define OUT_DIR "msh_mpi_out"
#include "file_util.h"
#include "io/write_mesh.h"

static int rank, nranks;

/* ---- the global mesh (the same on every rank) ------------------------- */

typedef struct {
  size_t nnodes, ncells;
  double *xyz;
  uint8_t *type;
  uint32_t *conn;
} gmesh;

enum { GRID = 12 };

static uint32_t grid_node(int i, int j, int k) {
  return (uint32_t)(i + (GRID + 1) * (j + (GRID + 1) * k));
}

/* Signed volume * 6 of a tetrahedron. */
static double tet_vol6(const double *a, const double *b, const double *c, const double *d) {
  const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
  const double v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
  const double w[3] = {d[0] - a[0], d[1] - a[1], d[2] - a[2]};
  return u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0]) +
         u[2] * (v[0] * w[1] - v[1] * w[0]);
}

static void add_cell(gmesh *G, int type, const uint32_t *nodes) {
  uint32_t *row = G->conn + 8 * G->ncells;
  memset(row, 0, 8 * sizeof *row);
  memcpy(row, nodes, (size_t)mx_cell_nodes[type] * sizeof *row);
  G->type[G->ncells++] = (uint8_t)type;
}

static unsigned gcd(unsigned a, unsigned b) {
  while (b) {
    const unsigned t = a % b;
    a = b;
    b = t;
  }
  return a;
}

static void build_mesh(gmesh *G) {
  const size_t ngrid = (size_t)(GRID + 1) * (GRID + 1) * (GRID + 1);
  const size_t nhex = (size_t)GRID * GRID * GRID;
  G->xyz = malloc(3 * (ngrid + nhex) * sizeof *G->xyz);
  G->type = malloc(6 * nhex);
  G->conn = malloc(8 * 6 * nhex * sizeof *G->conn);
  if (!G->xyz || !G->type || !G->conn) abort();
  G->nnodes = ngrid;
  G->ncells = 0;
  for (int k = 0; k <= GRID; k++)
    for (int j = 0; j <= GRID; j++)
      for (int i = 0; i <= GRID; i++) {
        double *p = G->xyz + 3 * grid_node(i, j, k);
        p[0] = -1.25 + 0.1 * i;
        p[1] = 3.0 + 0.07 * j + 0.001 * i;
        p[2] = 0.3 * k - 0.002 * j;
      }
  for (int k = 0; k < GRID; k++)
    for (int j = 0; j < GRID; j++)
      for (int i = 0; i < GRID; i++) {
        /* VTK hexahedron: bottom counter-clockwise seen from the top */
        const uint32_t h[8] = {grid_node(i, j, k),         grid_node(i + 1, j, k),
                               grid_node(i + 1, j + 1, k), grid_node(i, j + 1, k),
                               grid_node(i, j, k + 1),     grid_node(i + 1, j, k + 1),
                               grid_node(i + 1, j + 1, k + 1), grid_node(i, j + 1, k + 1)};
        const unsigned kind = ((unsigned)(i * 7 + j * 13 + k * 29) * 2654435761u >> 7) % 4;
        if (kind == 0) {
          add_cell(G, MX_HEX, h);
        } else if (kind == 1) {
          const uint32_t a[6] = {h[0], h[1], h[2], h[4], h[5], h[6]};
          const uint32_t b[6] = {h[0], h[2], h[3], h[4], h[6], h[7]};
          add_cell(G, MX_PRISM, a);
          add_cell(G, MX_PRISM, b);
        } else if (kind == 2) {
          static const int kuhn[6][2] = {{1, 2}, {2, 3}, {3, 7}, {7, 4}, {4, 5}, {5, 1}};
          for (int t = 0; t < 6; t++) {
            uint32_t q[4] = {h[0], h[kuhn[t][0]], h[kuhn[t][1]], h[6]};
            if (tet_vol6(G->xyz + 3 * q[0], G->xyz + 3 * q[1], G->xyz + 3 * q[2],
                         G->xyz + 3 * q[3]) < 0) {
              const uint32_t s = q[1];
              q[1] = q[2];
              q[2] = s;
            }
            add_cell(G, MX_TET, q);
          }
        } else {
          const uint32_t c = (uint32_t)G->nnodes++;
          for (int a = 0; a < 3; a++) {
            double s = 0;
            for (int v = 0; v < 8; v++) s += G->xyz[3 * h[v] + a];
            G->xyz[3 * c + a] = s / 8;
          }
          /* one pyramid per face: the outward face reversed is the base */
          for (int f = 0; f < 6; f++) {
            const int8_t *fv = mx_cell_faces[MX_HEX][f];
            const uint32_t p[5] = {h[fv[3]], h[fv[2]], h[fv[1]], h[fv[0]], c};
            add_cell(G, MX_PYRAMID, p);
          }
        }
      }
  /* scramble the node numbers: n -> (a n + 17) mod N */
  const unsigned N = (unsigned)G->nnodes;
  unsigned a = 7919;
  while (gcd(a, N) != 1) a += 2;
  uint32_t *to = malloc(N * sizeof *to);
  double *xyz = malloc(3 * (size_t)N * sizeof *xyz);
  if (!to || !xyz) abort();
  for (unsigned n = 0; n < N; n++) {
    to[n] = (uint32_t)(((unsigned long long)a * n + 17) % N);
    memcpy(xyz + 3 * (size_t)to[n], G->xyz + 3 * (size_t)n, 3 * sizeof *xyz);
  }
  for (size_t c = 0; c < G->ncells; c++)
    for (int j = 0; j < mx_cell_nodes[G->type[c]]; j++)
      G->conn[8 * c + (size_t)j] = to[G->conn[8 * c + (size_t)j]];
  free(G->xyz);
  G->xyz = xyz;
  free(to);
}

/* ---- one distribution ------------------------------------------------- */

/* The cells of the test: sel[0..nsel) (global cell indices), rank r
 * holding sel[lo[r] .. lo[r + 1]). */
typedef struct {
  size_t nsel;
  uint32_t *sel;
  size_t *lo; /* nranks + 1 */
} split;

/* What every rank derives, for every node: the owner (lowest rank using
 * it, -1: unused) and the global id (the owners' local orders, rank after
 * rank). */
typedef struct {
  int *owner;
  uint64_t *gid;
  uint64_t nglobal;
  uint64_t *first; /* per rank: its first owned id */
} numbering;

static void number_nodes(const gmesh *G, const split *S, numbering *Nb) {
  Nb->owner = malloc(G->nnodes * sizeof *Nb->owner);
  Nb->gid = malloc(G->nnodes * sizeof *Nb->gid);
  Nb->first = malloc(((size_t)nranks + 1) * sizeof *Nb->first);
  if (!Nb->owner || !Nb->gid || !Nb->first) abort();
  for (size_t n = 0; n < G->nnodes; n++) Nb->owner[n] = -1, Nb->gid[n] = UINT64_MAX;
  uint64_t next = 0;
  for (int r = 0; r < nranks; r++) {
    Nb->first[r] = next;
    for (size_t s = S->lo[r]; s < S->lo[r + 1]; s++) {
      const size_t c = S->sel[s];
      for (int j = 0; j < mx_cell_nodes[G->type[c]]; j++) {
        const uint32_t n = G->conn[8 * c + (size_t)j];
        if (Nb->owner[n] < 0) {
          Nb->owner[n] = r;
          Nb->gid[n] = next++;
        }
      }
    }
  }
  Nb->first[nranks] = next;
  Nb->nglobal = next;
}

/* This rank's part: local nodes in order of first use. */
typedef struct {
  mx_dist_mesh D;
  double *xyz;
  uint64_t *gid;
  uint8_t *owned, *type;
  uint32_t *conn;
} part;

static void make_part(const gmesh *G, const split *S, const numbering *Nb, part *P) {
  const size_t c0 = S->lo[rank], c1 = S->lo[rank + 1], nc = c1 - c0;
  uint32_t *loc = malloc(G->nnodes * sizeof *loc);
  P->xyz = malloc((3 * G->nnodes + 1) * sizeof *P->xyz);
  P->gid = malloc((G->nnodes + 1) * sizeof *P->gid);
  P->owned = malloc(G->nnodes + 1);
  P->type = malloc(nc + 1);
  P->conn = malloc((8 * nc + 1) * sizeof *P->conn);
  if (!loc || !P->xyz || !P->gid || !P->owned || !P->type || !P->conn) abort();
  memset(loc, 0xff, G->nnodes * sizeof *loc);
  size_t nloc = 0;
  uint64_t nowned = 0;
  for (size_t s = c0; s < c1; s++) {
    const size_t c = S->sel[s], lc = s - c0;
    P->type[lc] = G->type[c];
    memset(P->conn + 8 * lc, 0, 8 * sizeof *P->conn);
    for (int j = 0; j < mx_cell_nodes[G->type[c]]; j++) {
      const uint32_t n = G->conn[8 * c + (size_t)j];
      if (loc[n] == UINT32_MAX) {
        loc[n] = (uint32_t)nloc;
        memcpy(P->xyz + 3 * nloc, G->xyz + 3 * (size_t)n, 3 * sizeof *P->xyz);
        P->gid[nloc] = Nb->gid[n];
        P->owned[nloc] = Nb->owner[n] == rank;
        nowned += P->owned[nloc];
        nloc++;
      }
      P->conn[8 * lc + (size_t)j] = loc[n];
    }
  }
  free(loc);
  /* the owned range by exclusive scan, as a distributed mesher gets it */
  uint64_t first = 0;
  MPI_Exscan(&nowned, &first, 1, MPI_UINT64_T, MPI_SUM, MPI_COMM_WORLD);
  if (rank == 0) first = 0;
  CHECK(first == Nb->first[rank]);
  CHECK(nowned == Nb->first[rank + 1] - Nb->first[rank]);
  P->D = (mx_dist_mesh){.nnodes = nloc, .xyz = P->xyz, .gid = P->gid, .owned = P->owned,
                        .first_owned = first, .nowned = nowned, .nglobal = Nb->nglobal,
                        .ncells = nc, .type = P->type, .conn = P->conn};
}

static void free_part(part *P) {
  free(P->xyz);
  free(P->gid);
  free(P->owned);
  free(P->type);
  free(P->conn);
}

/* The selected cells grouped by type, each type in selection order: the
 * order of the file. */
static uint32_t *file_order(const gmesh *G, const split *S) {
  uint32_t *o = malloc((S->nsel + 1) * sizeof *o);
  if (!o) abort();
  size_t k = 0;
  for (int t = 0; t < 4; t++)
    for (size_t s = 0; s < S->nsel; s++)
      if (G->type[S->sel[s]] == t) o[k++] = S->sel[s];
  return o;
}

/* Rank 0: the file read back against the original cells. */
static void check_read_back(const char *path, const gmesh *G, const split *S,
                            const numbering *Nb) {
  mx_mesh_data md;
  memset(&md, 0, sizeof md);
  const int st = mx_read_mesh(path, &md);
  CHECK(st == MX_OK);
  if (st != MX_OK) return;
  CHECK(md.nnodes == Nb->nglobal);
  CHECK(md.ncells == S->nsel);
  for (size_t n = 0; n < G->nnodes && md.nnodes == Nb->nglobal; n++)
    if (Nb->owner[n] >= 0)
      CHECK(memcmp(md.xyz + 3 * Nb->gid[n], G->xyz + 3 * n, 3 * sizeof(double)) == 0);
  uint32_t *o = file_order(G, S);
  size_t bad = 0;
  for (size_t k = 0; k < md.ncells && k < S->nsel; k++) {
    const size_t c = o[k];
    if (md.type[k] != G->type[c]) {
      bad++;
      continue;
    }
    for (int j = 0; j < mx_cell_nodes[G->type[c]]; j++) {
      const uint32_t rn = md.conn[8 * k + (size_t)j], gn = G->conn[8 * c + (size_t)j];
      if (rn >= md.nnodes ||
          memcmp(md.xyz + 3 * (size_t)rn, G->xyz + 3 * (size_t)gn, 3 * sizeof(double)) != 0) {
        bad++;
        break;
      }
    }
  }
  CHECK(bad == 0);
  free(o);
  mx_mesh_data_free(&md);
}

/* Rank 0: the serial writer's file of the same mesh (nodes in global-id
 * order, cells grouped by type). */
static void write_serial(const char *path, const gmesh *G, const split *S,
                         const numbering *Nb) {
  const size_t nn = (size_t)Nb->nglobal;
  double *xyz = malloc((3 * nn + 1) * sizeof *xyz);
  uint8_t *type = malloc(S->nsel + 1);
  uint32_t *conn = calloc(8 * S->nsel + 1, sizeof *conn);
  uint32_t *o = file_order(G, S);
  if (!xyz || !type || !conn) abort();
  for (size_t n = 0; n < G->nnodes; n++)
    if (Nb->owner[n] >= 0) memcpy(xyz + 3 * Nb->gid[n], G->xyz + 3 * n, 3 * sizeof *xyz);
  for (size_t k = 0; k < S->nsel; k++) {
    const size_t c = o[k];
    type[k] = G->type[c];
    for (int j = 0; j < mx_cell_nodes[type[k]]; j++)
      conn[8 * k + (size_t)j] = (uint32_t)Nb->gid[G->conn[8 * c + (size_t)j]];
  }
  const mx_mesh_view v = {.nnodes = nn, .xyz = xyz, .ncells = S->nsel, .type = type,
                          .conn = conn};
  CHECK(mx_write_msh(path, &v, 1) == MX_OK);
  free(xyz);
  free(type);
  free(conn);
  free(o);
}

/* The first differing byte of two files, -1 if equal (-2: unreadable). */
static long long first_difference(const char *a, const char *b) {
  size_t la = 0, lb = 0;
  char *x = slurp(a, &la), *y = slurp(b, &lb);
  long long d = -1;
  if (!x || !y) {
    d = -2;
  } else {
    const size_t n = la < lb ? la : lb;
    for (size_t i = 0; i < n && d < 0; i++)
      if (x[i] != y[i]) d = (long long)i;
    if (d < 0 && la != lb) d = (long long)n;
  }
  free(x);
  free(y);
  return d;
}

/* Whether any entry of OUT_DIR has ".tmp." in its name. */
static int temporaries_left(void) {
  DIR *d = opendir(OUT_DIR);
  if (!d) return 0;
  int n = 0;
  struct dirent *e;
  while ((e = readdir(d))) n += strstr(e->d_name, ".tmp.") != NULL;
  closedir(d);
  return n;
}

/* The status every rank returned: the same one, else -1. */
static int common_status(int st) {
  int lo = 0, hi = 0;
  MPI_Allreduce(&st, &lo, 1, MPI_INT, MPI_MIN, MPI_COMM_WORLD);
  MPI_Allreduce(&st, &hi, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
  return lo == hi ? lo : -1;
}

static void run_case(const char *name, const gmesh *G, const split *S, size_t chunk) {
  numbering Nb;
  number_nodes(G, S, &Nb);
  part P;
  make_part(G, S, &Nb, &P);
  char path[256], serial[256];
  snprintf(path, sizeof path, OUT_DIR "/%s_np%d.msh", name, nranks);
  snprintf(serial, sizeof serial, OUT_DIR "/%s_np%d_serial.msh", name, nranks);
  mx_write_msh_mpi_chunk = chunk;
  const int st = common_status(mx_write_msh_mpi(path, MPI_COMM_WORLD, &P.D));
  mx_write_msh_mpi_chunk = (size_t)16 << 20;
  CHECK(st == MX_OK);
  if (rank == 0 && st == MX_OK) {
    check_read_back(path, G, S, &Nb);
    write_serial(serial, G, S, &Nb);
    const long long d = first_difference(path, serial);
    if (d != -1)
      fprintf(stderr, "%s: differs from the serial writer's file at byte %lld\n", path, d);
    CHECK(d == -1);
    CHECK(temporaries_left() == 0);
    printf("%s on %d ranks, chunk %zu: %llu nodes, %zu cells, %lld bytes, "
           "byte-identical to mx_write_msh: %s\n",
           name, nranks, chunk, (unsigned long long)Nb.nglobal, S->nsel, file_size(path),
           d == -1 ? "yes" : "no");
  }
  free_part(&P);
  free(Nb.owner);
  free(Nb.gid);
  free(Nb.first);
}

/* Ranges of n cells: weight w(r) = 1 (equal) or r + 1 (growing). */
static void ranges(split *S, int growing) {
  S->lo = malloc(((size_t)nranks + 1) * sizeof *S->lo);
  if (!S->lo) abort();
  size_t wsum = 0, w = 0;
  for (int r = 0; r < nranks; r++) wsum += growing ? (size_t)r + 1 : 1;
  for (int r = 0; r <= nranks; r++) {
    S->lo[r] = S->nsel * w / wsum;
    if (r < nranks) w += growing ? (size_t)r + 1 : 1;
  }
}

static void all_cells(split *S, const gmesh *G) {
  S->nsel = G->ncells;
  S->sel = malloc(G->ncells * sizeof *S->sel);
  if (!S->sel) abort();
  for (size_t c = 0; c < G->ncells; c++) S->sel[c] = (uint32_t)c;
}

static void test_failures(const gmesh *G) {
  split S;
  all_cells(&S, G);
  ranges(&S, 0);
  numbering Nb;
  number_nodes(G, &S, &Nb);
  part P;
  make_part(G, &S, &Nb, &P);

  /* a path in a missing directory */
  const char *missing = OUT_DIR "/no_such_dir/out.msh";
  int st = common_status(mx_write_msh_mpi(missing, MPI_COMM_WORLD, &P.D));
  CHECK(st == MX_EINPUT);
  if (rank == 0) {
    CHECK(!exists(OUT_DIR "/no_such_dir"));
    CHECK(temporaries_left() == 0);
  }

  /* an inconsistent input on the last rank: no file at all */
  const char *incons = OUT_DIR "/inconsistent.msh";
  mx_dist_mesh D = P.D;
  if (rank == nranks - 1) D.first_owned += 1;
  st = common_status(mx_write_msh_mpi(incons, MPI_COMM_WORLD, &D));
  CHECK(st == MX_EINPUT);
  /* an owned id outside the rank's range */
  D = P.D;
  uint64_t *gid = malloc((P.D.nnodes + 1) * sizeof *gid);
  if (!gid) abort();
  memcpy(gid, P.gid, P.D.nnodes * sizeof *gid);
  for (size_t i = 0; i < D.nnodes && rank == 0; i++)
    if (P.owned[i]) {
      gid[i] = D.first_owned + D.nowned; /* the next rank's, or past the end */
      break;
    }
  D.gid = gid;
  st = common_status(mx_write_msh_mpi(incons, MPI_COMM_WORLD, &D));
  CHECK(st == MX_EINPUT);
  free(gid);
  if (rank == 0) {
    CHECK(!exists(incons));
    CHECK(temporaries_left() == 0);
  }

  /* a device is written in place, not replaced: /dev/full fails every
   * write (ENOSPC) */
  struct stat sb;
  if (stat("/dev/full", &sb) == 0 && S_ISCHR(sb.st_mode)) {
    st = common_status(mx_write_msh_mpi("/dev/full", MPI_COMM_WORLD, &P.D));
    CHECK(st == MX_EINPUT);
    if (rank == 0) CHECK(stat("/dev/full", &sb) == 0 && S_ISCHR(sb.st_mode));
  }

  /* a real file whose writes fail on the last rank only: its file size
   * limit (RLIMIT_FSIZE, SIGXFSZ ignored: EFBIG) below the file's size */
  const char *big = OUT_DIR "/too_big.msh";
  struct rlimit rl;
  CHECK(getrlimit(RLIMIT_FSIZE, &rl) == 0);
  const rlim_t soft = rl.rlim_cur;
  if (rank == nranks - 1) {
    signal(SIGXFSZ, SIG_IGN);
    rl.rlim_cur = 100000; /* the file has ~390 000 bytes, the last rank's part ends it */
    CHECK(setrlimit(RLIMIT_FSIZE, &rl) == 0);
  }
  st = common_status(mx_write_msh_mpi(big, MPI_COMM_WORLD, &P.D));
  CHECK(st == MX_EINPUT);
  if (rank == nranks - 1) {
    rl.rlim_cur = soft;
    CHECK(setrlimit(RLIMIT_FSIZE, &rl) == 0);
  }
  if (rank == 0) {
    CHECK(!exists(big));
    CHECK(temporaries_left() == 0);
  }

  /* an existing file is replaced */
  const char *old = OUT_DIR "/replaced.msh";
  if (rank == 0) write_bytes_file(old, "old\n", 4);
  MPI_Barrier(MPI_COMM_WORLD);
  st = common_status(mx_write_msh_mpi(old, MPI_COMM_WORLD, &P.D));
  CHECK(st == MX_OK);
  if (rank == 0) {
    CHECK(file_size(old) > 1000);
    CHECK(temporaries_left() == 0);
  }

  /* a symbolic link is written through: it stays, the file it names is
   * replaced */
  const char *link = OUT_DIR "/link.msh", *target = OUT_DIR "/target.msh";
  if (rank == 0) {
    unlink(link);
    write_bytes_file(target, "old\n", 4);
    CHECK(symlink("target.msh", link) == 0);
  }
  MPI_Barrier(MPI_COMM_WORLD);
  st = common_status(mx_write_msh_mpi(link, MPI_COMM_WORLD, &P.D));
  CHECK(st == MX_OK);
  if (rank == 0) {
    struct stat lb;
    CHECK(lstat(link, &lb) == 0 && S_ISLNK(lb.st_mode));
    CHECK(files_equal(target, old));
    CHECK(temporaries_left() == 0);
  }
  free_part(&P);
  free(Nb.owner);
  free(Nb.gid);
  free(Nb.first);
  free(S.sel);
  free(S.lo);
}

int main(int argc, char **argv) {
  MPI_Init(&argc, &argv);
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &nranks);
  if (rank == 0) {
    mkdir(OUT_DIR, 0755);
    unlink(OUT_DIR "/inconsistent.msh"); /* of an earlier run: must not appear */
    unlink(OUT_DIR "/too_big.msh");
  }
  MPI_Barrier(MPI_COMM_WORLD);

  gmesh G;
  build_mesh(&G);
  size_t count[4] = {0, 0, 0, 0};
  for (size_t c = 0; c < G.ncells; c++) count[G.type[c]]++;
  CHECK(count[MX_TET] > 0 && count[MX_PYRAMID] > 0 && count[MX_PRISM] > 0 && count[MX_HEX] > 0);

  const size_t chunks[2] = {(size_t)16 << 20, 200};
  for (int k = 0; k < 2; k++) {
    const size_t chunk = chunks[k];
    split S;
    all_cells(&S, &G);
    ranges(&S, 0);
    run_case(k ? "equal_small" : "equal", &G, &S, chunk);
    free(S.lo);
    ranges(&S, 1);
    run_case(k ? "growing_small" : "growing", &G, &S, chunk);
    free(S.lo);
    /* tetrahedra and hexahedra only, all on the last rank */
    S.nsel = 0;
    for (size_t c = 0; c < G.ncells; c++)
      if (G.type[c] == MX_TET || G.type[c] == MX_HEX) S.sel[S.nsel++] = (uint32_t)c;
    S.lo = malloc(((size_t)nranks + 1) * sizeof *S.lo);
    if (!S.lo) abort();
    for (int r = 0; r < nranks; r++) S.lo[r] = 0;
    S.lo[nranks] = S.nsel;
    run_case(k ? "last_small" : "last", &G, &S, chunk);
    free(S.lo);
    free(S.sel);
  }
  test_failures(&G);

  free(G.xyz);
  free(G.type);
  free(G.conn);
  int fails = mx_test_failures, all = 0;
  MPI_Allreduce(&fails, &all, 1, MPI_INT, MPI_SUM, MPI_COMM_WORLD);
  if (rank == 0 && all) fprintf(stderr, "%d check(s) failed over %d ranks\n", all, nranks);
  MPI_Finalize();
  return all ? 1 : 0;
}
