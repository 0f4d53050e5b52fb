/* libFuzzer targets for the input readers, one per format, chosen when
 * compiling with -DFUZZ_FORMAT=NAME:
 *   off mdl stl obj ply  mx_read_off .. mx_read_ply (src/io/read_*.c; polygon
 *                        faces split by src/io/polygon_split.c), then
 *                        mx_trisoup_check (src/io/surface_check.c); the
 *                        faces and lines the soup keeps checked before and
 *                        after
 *   reg                  mx_read_reg (src/io/read_reg.c)
 *   mesh                 mx_read_mesh (src/io/read_mesh.c), as `mixoct
 *                        check` calls it, then mx_check_mesh on small meshes;
 *                        -DFUZZ_EXT=vtk|vtu|msh|mesh|meshb|getfem|m3d|mvm
 *                        picks the file name's extension (default vtk)
 *   poly                 the 2D readers mx_read_poly, mx_read_poly_off and
 *                        mx_read_poly_mdl (src/io/read_poly.c) on the same
 *                        bytes, then what the 2D mesher does with a poly
 *                        read: mx_poly_check_domain, the point-location
 *                        index, features (src/quad/poly.c)
 *   sizemap              mx_sizemap_read (src/io/read_sizemap.c) with the
 *                        default field and with the field "h"; every point
 *                        and size read checked finite (sizes > 0);
 *                        -DFUZZ_EXT=txt|vtk|vtu|pos picks the extension,
 *                        which picks the format (default txt)
 *   polylines            mx_read_polylines (src/io/read_polylines.c) at
 *                        30, 0 and 180 degrees: lines of 2 points or more
 *                        (first[] increasing), finite points, loops with no
 *                        corner on them; then the feature distances of the
 *                        lines to a 2 x 2 x 2 hexahedra mesh of the unit
 *                        cube (verify/check_features.c) when their points
 *                        lie within 100 of it: finite, >= 0
 *   image                mx_read_label_image_mem (src/io/read_image.c) on
 *                        the input's bytes (no file), named fuzz.EXT with
 *                        -DFUZZ_EXT=nii|nii.gz|mha|inr|inr.gz (default
 *                        nii); an image read has dims >= 1, labels (every
 *                        one read), a finite transform and sizes > 0; a
 *                        failure leaves it empty
 *
 * The readers take a path: each input is written to a file of this process
 * under $TMPDIR (/dev/shm when writable and TMPDIR is unset, else /tmp),
 * with the format's extension, and read back. What a reader accepts must
 * keep its promises (finite coordinates, indices in range, ...): anything
 * else aborts, so libFuzzer keeps the input. Messages go to a handler that
 * formats and drops them (so bad format arguments are still exercised).
 *
 * Build, from the source root (tools/fuzz.sh does this for every target):
 *   clang -std=c17 -g -O1 -fsanitize=fuzzer,address,undefined -fopenmp \
 *     -D_GNU_SOURCE -Isrc -Iinclude -DFUZZ_FORMAT=off tools/fuzz_readers.c \
 *     SOURCES -lm -o fuzz_off
 * where SOURCES are the .c files under src but those of src/cli (fuzz.sh
 * compiles them once into an archive).
 * Run (new inputs go to the first directory, the seeds are read from the
 * second):
 *   ./fuzz_off -max_total_time=60 -timeout=10 CORPUS_DIR tools/fuzz_seeds/off
 */
#include <fcntl.h>
#include <math.h>
#include <omp.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "base/common.h"
#include "io/read_mesh.h"
#include "verify/check.h"
#include "quad/quad.h"
#include "soa/mesh.h"
#include "soa/regions.h"
#include "soa/trisoup.h"
#include "io/read_surface.h"
#include "io/read_poly.h"
#include "io/read_sizemap.h"
#include "io/read_image.h"
#include "io/read_polylines.h"
#include "geom/feature_walk.h"

/* FUZZ_FORMAT as a number, by token pasting: FMT_off and so on. */
#define FMT_off 1
#define FMT_mdl 2
#define FMT_stl 3
#define FMT_obj 4
#define FMT_ply 5
#define FMT_reg 6
#define FMT_mesh 7
#define FMT_poly 8
#define FMT_sizemap 9
#define FMT_image 10
#define FMT_polylines 11
#define FUZZ_CAT2(a, b) a##b
#define FUZZ_CAT(a, b) FUZZ_CAT2(a, b)
#define FUZZ_STR2(a) #a
#define FUZZ_STR(a) FUZZ_STR2(a)

#ifndef FUZZ_FORMAT
#error "compile with -DFUZZ_FORMAT=off|mdl|stl|obj|ply|reg|mesh|poly|sizemap|image|polylines"
#endif
#define FUZZ_ID FUZZ_CAT(FMT_, FUZZ_FORMAT)
#if FUZZ_ID < 1 || FUZZ_ID > 11
#error "unknown FUZZ_FORMAT"
#endif

#if (FUZZ_ID == FMT_mesh || FUZZ_ID == FMT_sizemap || FUZZ_ID == FMT_image) && defined(FUZZ_EXT)
#define EXT FUZZ_STR(FUZZ_EXT)
#elif FUZZ_ID == FMT_image
#define EXT "nii"
#elif FUZZ_ID == FMT_mesh
#define EXT "vtk"
#elif FUZZ_ID == FMT_polylines
#define EXT "txt"
#elif FUZZ_ID == FMT_sizemap
#define EXT "txt"
#else
#define EXT FUZZ_STR(FUZZ_FORMAT)
#endif

/* Reported when a reader breaks a promise; abort() makes libFuzzer keep
 * the input as a crash. */
#define REQUIRE(cond)                                                         \
  do {                                                                        \
    if (!(cond)) {                                                            \
      fprintf(stderr, "fuzz_readers: %s:%d: broken promise: %s\n", __FILE__,  \
              __LINE__, #cond);                                               \
      abort();                                                                \
    }                                                                         \
  } while (0)

static char path[512];

static void remove_file(void) {
  if (path[0]) unlink(path);
}

static void drop_message(void *user, int kind, const char *text) {
  (void)user;
  (void)kind;
  /* touch the whole message: a bad %.*s shows up here under ASan */
  volatile size_t n = strlen(text);
  (void)n;
}

static const char *tmp_dir(void) {
  const char *d = getenv("TMPDIR");
  if (d && *d) return d;
  return access("/dev/shm", W_OK) == 0 ? "/dev/shm" : "/tmp";
}

int LLVMFuzzerInitialize(int *argc, char ***argv);
int LLVMFuzzerInitialize(int *argc, char ***argv) {
  (void)argc;
  (void)argv;
  snprintf(path, sizeof path, "%s/fuzz_%s_%ld.%s", tmp_dir(),
           FUZZ_STR(FUZZ_FORMAT), (long)getpid(), EXT);
  atexit(remove_file);
  mx_quiet = 1;
  mx_msg_fn = drop_message;
  omp_set_num_threads(1); /* targets run side by side, one core each */
  return 0;
}

#if FUZZ_ID != FMT_image
static void write_input(const uint8_t *data, size_t size) {
  int fd = open(path, O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0600);
  if (fd < 0) {
    perror(path);
    abort();
  }
  for (size_t done = 0; done < size;) {
    ssize_t w = write(fd, data + done, size - done);
    if (w <= 0) {
      perror(path);
      abort();
    }
    done += (size_t)w;
  }
  close(fd);
}
#endif

#if FUZZ_ID == FMT_reg

static void fuzz_file(void) {
  mx_box_region *b;
  size_t n;
  if (mx_read_reg(path, &b, &n) != MX_OK) {
    REQUIRE(b == NULL && n == 0);
    return;
  }
  REQUIRE(b != NULL || n == 0);
  for (size_t i = 0; i < n; i++) {
    for (int d = 0; d < 3; d++) {
      REQUIRE(isfinite(b[i].lo[d]) && isfinite(b[i].hi[d]));
      REQUIRE(b[i].lo[d] <= b[i].hi[d]);
    }
    REQUIRE(b[i].level >= 0);
  }
  mx_free(b);
}

#elif FUZZ_ID == FMT_poly

/* The promises of quad.h's mx_poly after a read. */
static void poly_promises(const mx_poly *P) {
  REQUIRE(P->nv > 0 && P->ns > 0 && P->xy && P->seg && P->line && P->path);
  for (size_t i = 0; i < 2 * P->nv; i++) REQUIRE(isfinite(P->xy[i]));
  for (size_t i = 0; i < 2 * P->ns; i++) REQUIRE(P->seg[i] < P->nv);
  for (size_t s = 0; s < P->ns; s++) REQUIRE(P->line[s] > 0);
  for (size_t i = 0; i < 2 * P->nholes; i++) REQUIRE(isfinite(P->holes[i]));
}

/* A checked domain: consistent loops; the index answers without crashing
 * and finds, from every vertex, a segment at distance 0 (it is on one). */
static void poly_use(mx_poly *P) {
  const int st = mx_poly_check_domain(P);
  REQUIRE(st == MX_OK || st == MX_EINPUT);
  uint32_t *feat = NULL;
  size_t nf = 0;
  REQUIRE(mx_poly_features(P, &feat, &nf) == MX_OK && nf <= P->nv);
  for (size_t i = 0; i < nf; i++) REQUIRE(feat[i] < P->nv && (i == 0 || feat[i - 1] < feat[i]));
  mx_free(feat);
  if (st != MX_OK) return;
  REQUIRE(P->nloops >= 1 && P->nloops <= P->ns / 2);
  mx_poly_index I;
  REQUIRE(mx_poly_index_build(P, &I) == MX_OK);
  for (size_t s = 0; s < P->ns && s < 64; s++) {
    const double *v = P->xy + 2 * (size_t)P->seg[2 * s];
    double q[2], d2;
    REQUIRE(mx_poly_closest(&I, v, INFINITY, q, &d2) != UINT32_MAX && d2 == 0.0);
    REQUIRE(mx_poly_inside(&I, v) == 2);
    const double off[2] = {v[0] + 0.25, v[1] - 0.125};
    const int in = mx_poly_inside(&I, off);
    REQUIRE(in >= 0 && in <= 2);
  }
  mx_poly_index_free(&I);
}

static void fuzz_file(void) {
  int (*const readers[3])(const char *, mx_poly *) = {mx_read_poly, mx_read_poly_off,
                                                      mx_read_poly_mdl};
  for (int r = 0; r < 3; r++) {
    mx_poly P;
    if (readers[r](path, &P) != MX_OK) {
      REQUIRE(P.nv == 0 && P.ns == 0 && !P.xy && !P.seg && !P.line && !P.path);
      continue;
    }
    poly_promises(&P);
    poly_use(&P);
    mx_poly_free(&P);
  }
}

#elif FUZZ_ID == FMT_polylines

/* The unit cube as 2 x 2 x 2 hexahedra. */
static void cube_mesh(mx_mesh_data *m, double *xyz, uint8_t *type, uint32_t *conn) {
  memset(m, 0, sizeof *m);
  for (int k = 0, v = 0; k < 3; k++)
    for (int j = 0; j < 3; j++)
      for (int i = 0; i < 3; i++, v++) {
        xyz[3 * v] = 0.5 * i;
        xyz[3 * v + 1] = 0.5 * j;
        xyz[3 * v + 2] = 0.5 * k;
      }
  for (int k = 0, c = 0; k < 2; k++)
    for (int j = 0; j < 2; j++)
      for (int i = 0; i < 2; i++, c++) {
        const uint32_t b = (uint32_t)(9 * k + 3 * j + i);
        const uint32_t r[8] = {b, b + 1, b + 4, b + 3, b + 9, b + 10, b + 13, b + 12};
        type[c] = MX_HEX;
        memcpy(conn + 8 * c, r, sizeof r);
      }
  m->nnodes = 27;
  m->ncells = 8;
  m->xyz = xyz;
  m->type = type;
  m->conn = conn;
}

static void fuzz_file(void) {
  static const double angles[3] = {30.0, 0.0, 180.0};
  double xyz[81];
  uint8_t type[8];
  uint32_t conn[64];
  mx_mesh_data m;
  cube_mesh(&m, xyz, type, conn);
  for (int a = 0; a < 3; a++) {
    mx_feature_lines L;
    memset(&L, 0x5a, sizeof L); /* must be overwritten */
    if (mx_read_polylines(path, angles[a], &L) != MX_OK) {
      REQUIRE(L.nlines == 0 && L.ncorners == 0 && !L.first && !L.xyz && !L.loop && !L.corner);
      continue;
    }
    REQUIRE(L.nlines > 0 && L.first && L.first[0] == 0);
    for (size_t i = 0; i < L.nlines; i++) {
      REQUIRE(L.first[i + 1] >= L.first[i] + 2);
      REQUIRE(L.loop[i] == 0 || L.loop[i] == 1);
    }
    int near = 1; /* within 100 of the cube: a few hundred samples a segment */
    for (size_t k = 0; k < 3 * L.first[L.nlines]; k++) {
      REQUIRE(isfinite(L.xyz[k]));
      near &= fabs(L.xyz[k]) <= 100.0;
    }
    for (size_t k = 0; k < 3 * L.ncorners; k++) REQUIRE(isfinite(L.corner[k]));
    if (near && L.first[L.nlines] <= 4096) {
      mx_check_feature_dist d;
      REQUIRE(mx_check_features_mesh(&m, &L, &d) == MX_OK);
      REQUIRE(d.lines == L.nlines && d.corners == L.ncorners);
      REQUIRE(isfinite(d.ridge_dist) && d.ridge_dist >= 0.0);
      REQUIRE(L.ncorners == 0 ? isnan(d.corner_dist)
                              : isfinite(d.corner_dist) && d.corner_dist >= 0.0);
    }
    mx_feature_lines_walk_free(&L);
  }
}

#elif FUZZ_ID == FMT_sizemap

/* The promises of io/read_sizemap.h: on failure no arrays, else n > 0
 * points with finite coordinates and finite sizes > 0. */
static void fuzz_file(void) {
  const char *const fields[2] = {NULL, "h"};
  for (int k = 0; k < 2; k++) {
    double *xyz = (double *)&xyz, *h = (double *)&h; /* must be overwritten */
    size_t n = 7;
    if (mx_sizemap_read(path, fields[k], &xyz, &h, &n) != MX_OK) {
      REQUIRE(xyz == NULL && h == NULL && n == 0);
      continue;
    }
    REQUIRE(n > 0 && xyz && h);
    for (size_t i = 0; i < n; i++) {
      REQUIRE(isfinite(h[i]) && h[i] > 0);
      REQUIRE(isfinite(xyz[3 * i]) && isfinite(xyz[3 * i + 1]) && isfinite(xyz[3 * i + 2]));
    }
    mx_free(xyz);
    mx_free(h);
  }
}

#elif FUZZ_ID == FMT_image

/* The promises of io/read_image.h, on the bytes themselves. */
static void fuzz_mem(const uint8_t *data, size_t size) {
  mx_label_image img;
  memset(&img, 0x5a, sizeof img); /* must be overwritten */
  if (mx_read_label_image_mem("fuzz." EXT, data, size, &img) != MX_OK) {
    REQUIRE(img.label == NULL && img.nx == 0 && img.ny == 0 && img.nz == 0);
    return;
  }
  REQUIRE(img.nx >= 1 && img.ny >= 1 && img.nz >= 1 && img.label);
  REQUIRE(img.nx * img.ny * img.nz < ((int64_t)1 << 31));
  for (int e = 0; e < 12; e++) REQUIRE(isfinite(img.A[e]));
  for (int d = 0; d < 3; d++) REQUIRE(isfinite(img.spacing[d]) && img.spacing[d] > 0);
  REQUIRE(img.oblique == 0 || img.oblique == 1);
  REQUIRE(img.format[0] && memchr(img.format, '\0', sizeof img.format));
  const size_t n = (size_t)img.nx * (size_t)img.ny * (size_t)img.nz;
  REQUIRE(img.rounded <= n);
  static volatile int32_t labels; /* every label read: a short array is caught */
  for (size_t v = 0; v < n; v++) labels = img.label[v];
  mx_label_image_free(&img);
  REQUIRE(img.label == NULL);
}

#elif FUZZ_ID == FMT_mesh

static void fuzz_file(void) {
  mx_mesh_data m;
  if (mx_read_mesh(path, &m) != MX_OK) {
    REQUIRE(m.nnodes == 0 && m.ncells == 0 && !m.xyz && !m.type && !m.conn && !m.cell_tag);
    return;
  }
  REQUIRE(m.nnodes == 0 || m.xyz);
  REQUIRE(m.ncells == 0 || (m.type && m.conn));
  for (size_t i = 0; i < 3 * m.nnodes; i++) REQUIRE(isfinite(m.xyz[i]));
  REQUIRE(!m.cell_tag || m.ncells > 0);
  static volatile int32_t labels; /* every label read: a short array is caught */
  for (size_t c = 0; m.cell_tag && c < m.ncells; c++) labels = m.cell_tag[c];
  for (size_t c = 0; c < m.ncells; c++) {
    REQUIRE(m.type[c] <= MX_HEX);
    const int k = mx_cell_nodes[m.type[c]];
    for (int j = 0; j < 8; j++) {
      const uint32_t v = m.conn[8 * c + j];
      REQUIRE(j < k ? v < m.nnodes : v == 0);
    }
  }
  if (m.nnodes + m.ncells <= 100000) { /* as `mixoct check` goes on */
    mx_check_report r;
    REQUIRE(mx_check_mesh(&m, NULL, &r) == MX_OK);
    REQUIRE(r.elements == m.ncells && r.nodes == m.nnodes);
  }
  mx_mesh_data_free(&m);
}

#else

static int read_surface(const char *p, mx_trisoup *s) {
#if FUZZ_ID == FMT_off
  return mx_read_off(p, s);
#elif FUZZ_ID == FMT_mdl
  return mx_read_mdl(p, s);
#elif FUZZ_ID == FMT_stl
  return mx_read_stl(p, s);
#elif FUZZ_ID == FMT_obj
  return mx_read_obj(p, s);
#else
  return mx_read_ply(p, s);
#endif
}

/* Where the triangles come from: faces in file order (the triangles of a
 * polygon together), lines of text files known and increasing, names that
 * fit their buffer. */
static void check_faces(const mx_trisoup *s) {
  REQUIRE(s->nt == 0 || (s->face && s->cap_t >= s->nt));
  long last = 0;
  for (size_t t = 0; t < s->nt; t++) {
    if (t) REQUIRE(s->face[t] >= s->face[t - 1]);
    const long line = mx_trisoup_line(s, t);
    REQUIRE(line >= 0);
#if FUZZ_ID == FMT_off || FUZZ_ID == FMT_obj || FUZZ_ID == FMT_mdl
    REQUIRE(line > 0 && line >= last); /* text formats */
#endif
    last = line;
  }
  for (size_t k = 0; k < 4 && k < s->nt; k++) {
    char name[40];
    const size_t t = k < 2 ? k : s->nt - (k - 1);
    mx_trisoup_name(s, t, name, sizeof name);
    REQUIRE(strlen(name) < sizeof name);
    REQUIRE(!strncmp(name, "face ", 5) || !strncmp(name, "triangle ", 9));
  }
}

static void fuzz_file(void) {
  mx_trisoup s;
  memset(&s, 0, sizeof s);
  if (read_surface(path, &s) != MX_OK) {
    mx_trisoup_free(&s); /* what callers do: must be harmless */
    return;
  }
  /* the promises of soa/trisoup.h */
  REQUIRE(s.nshells == 1);
  REQUIRE(s.nv <= s.cap_v && s.nt <= s.cap_t);
  REQUIRE(s.nt > 0 && s.nv > 0);
  REQUIRE(s.nv <= UINT32_MAX);
  for (size_t i = 0; i < s.nv; i++)
    REQUIRE(isfinite(s.x[i]) && isfinite(s.y[i]) && isfinite(s.z[i]));
  for (size_t i = 0; i < 3 * s.nt; i++) REQUIRE(s.tri[i] < s.nv);
  for (size_t i = 0; i < s.nt; i++) REQUIRE(s.shell[i] == 0);
  check_faces(&s);
  /* the checks after reading, as the mesher runs them */
  size_t open_edges;
  const int st = mx_trisoup_check(&s, path, &open_edges);
  REQUIRE(st == MX_OK || (st == MX_EINPUT && s.nt == 0));
  check_faces(&s);
  double lo[3], hi[3];
  mx_trisoup_bbox(&s, lo, hi);
  for (int d = 0; d < 3; d++) REQUIRE(lo[d] <= hi[d]);
  mx_trisoup_free(&s);
}

#endif

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
#if FUZZ_ID == FMT_image
  fuzz_mem(data, size);
#else
  write_input(data, size);
  fuzz_file();
#endif
  return 0;
}
