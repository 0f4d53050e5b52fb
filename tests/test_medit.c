/* Tests of the boundary-face extractor (src/io/boundary_faces.c) and of the
 * Medit writer (src/io/write_medit.c).
 *
 * Files are read back by a small reader written here from the Gamma Mesh
 * Format description (libMeshb documentation): ASCII keywords with counts,
 * or binary blocks (code word 1, version, then keyword code, position of the
 * next block, count, raw lines). Elements are checked against Medit's
 * orientation convention (P.-L. George: the trihedron of the edges leaving
 * vertex 0 is direct, faces seen from outside turn counter-clockwise), with
 * volumes computed here by splitting each element into tetrahedra in
 * Medit's numbering, and face tables written here in that numbering. The
 * boundary faces are compared with an independent count: every face of
 * every element in a hash table, those used once. */
#include <math.h>
#include <omp.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "check.h"
#include "base/common.h"
#include "io/boundary_faces.h"
#include "kernels/transition.h"
#include "octree_util.h"
#include "soa/mesh.h"

#define OUT_DIR "medit_out"
#include "file_util.h"
#include "io/demo_surface.h"
#include "io/write_mesh.h"

/* ====================================================================== */
/* Medit conventions, written here from the documentation                 */
/* ====================================================================== */

/* Kinds of element lines: 0..3 volume types (as MX_TET..MX_HEX), 4
 * triangles, 5 quadrilaterals. */
enum { K_TRI = 4, K_QUAD = 5, NKINDS = 6 };
static const char *const kind_name[NKINDS] = {"Tetrahedra", "Pyramids",
                                              "Prisms",     "Hexahedra",
                                              "Triangles",  "Quadrilaterals"};
static const int kind_code[NKINDS] = {8, 49, 9, 10, 6, 7};
static const int kind_nodes[NKINDS] = {4, 5, 6, 8, 3, 4};

/* Faces in Medit numbering, seen from outside counter-clockwise. */
static const int medit_nfaces[4] = {4, 5, 5, 6};
static const int medit_faces[4][6][4] = {
    {{1, 2, 3, -1}, {0, 3, 2, -1}, {0, 1, 3, -1}, {0, 2, 1, -1}},
    {{0, 3, 2, 1}, {0, 1, 4, -1}, {1, 2, 4, -1}, {2, 3, 4, -1}, {3, 0, 4, -1}},
    {{0, 2, 1, -1}, {3, 4, 5, -1}, {0, 1, 4, 3}, {1, 2, 5, 4}, {0, 3, 5, 2}},
    {{0, 3, 2, 1},
     {0, 4, 7, 3},
     {0, 1, 5, 4},
     {4, 5, 6, 7},
     {1, 2, 6, 5},
     {2, 3, 7, 6}}};

/* Tetrahedra splitting each element (Medit numbering), all direct. */
static const int split_ntets[4] = {1, 2, 3, 6};
static const int split_tets[4][6][4] = {
    {{0, 1, 2, 3}},
    {{0, 1, 2, 4}, {0, 2, 3, 4}},
    {{0, 1, 2, 3}, {1, 2, 3, 4}, {2, 3, 4, 5}},
    {{0, 1, 2, 6},
     {0, 2, 3, 6},
     {0, 3, 7, 6},
     {0, 7, 4, 6},
     {0, 4, 5, 6},
     {0, 5, 1, 6}}};

/* The trihedron said to be direct: vertex 0 and its three neighbours. */
static const int corner[4][4] = {
    {0, 1, 2, 3}, {0, 1, 3, 4}, {0, 1, 2, 3}, {0, 1, 3, 4}};

static double det3(const double *a, const double *b, const double *c,
                   const double *d) {
  double u[3], v[3], w[3];
  for (int k = 0; k < 3; k++) {
    u[k] = b[k] - a[k];
    v[k] = c[k] - a[k];
    w[k] = d[k] - a[k];
  }
  return u[0] * (v[1] * w[2] - v[2] * w[1]) -
         u[1] * (v[0] * w[2] - v[2] * w[0]) +
         u[2] * (v[0] * w[1] - v[1] * w[0]);
}

/* Volume of an element from its Medit vertex coordinates p[j*3..]. */
static double medit_volume(int t, const double *p) {
  double vol = 0;
  for (int s = 0; s < split_ntets[t]; s++) {
    const int *q = split_tets[t][s];
    vol += det3(p + 3 * q[0], p + 3 * q[1], p + 3 * q[2], p + 3 * q[3]) / 6.0;
  }
  return vol;
}

/* ====================================================================== */
/* An independent Medit reader                                            */
/* ====================================================================== */

typedef struct {
  int version, dim;
  size_t nv;
  double *xyz;
  int32_t *vref;
  size_t n[NKINDS];
  int32_t *el[NKINDS]; /* (nodes + 1) values a line, 1-based, then ref */
  int seen[NKINDS];
} mfile;

static void mfile_free(mfile *f) {
  free(f->xyz);
  free(f->vref);
  for (int k = 0; k < NKINDS; k++) free(f->el[k]);
  memset(f, 0, sizeof *f);
}

/* Next whitespace-separated token ('#' starts a comment line). */
static const char *token(const char **p, size_t *len) {
  const char *s = *p;
  for (;;) {
    while (*s == ' ' || *s == '\t' || *s == '\n' || *s == '\r') s++;
    if (*s != '#') break;
    while (*s && *s != '\n') s++;
  }
  if (!*s) return NULL;
  const char *b = s;
  while (*s && *s != ' ' && *s != '\t' && *s != '\n' && *s != '\r') s++;
  *len = (size_t)(s - b);
  *p = s;
  return b;
}

static int tok_is(const char *t, size_t n, const char *word) {
  return t && n == strlen(word) && memcmp(t, word, n) == 0;
}

static int tok_long(const char **p, long long *v) {
  size_t n;
  const char *t = token(p, &n);
  if (!t) return 0;
  char *e;
  *v = strtoll(t, &e, 10);
  return e == t + n;
}

static int tok_double(const char **p, double *v) {
  size_t n;
  const char *t = token(p, &n);
  if (!t) return 0;
  char *e;
  *v = strtod(t, &e);
  return e == t + n;
}

static int read_ascii(const char *path, mfile *f) {
  memset(f, 0, sizeof *f);
  size_t len;
  char *buf = slurp(path, &len);
  if (!buf) return 0;
  const char *p = buf;
  size_t n = 0;
  long long v = 0;
  const char *first = token(&p, &n);
  int ok = tok_is(first, n, "MeshVersionFormatted") && tok_long(&p, &v);
  f->version = (int)v;
  int ended = 0;
  while (ok && !ended) {
    const char *t = token(&p, &n);
    if (!t) {
      ok = 0;
    } else if (tok_is(t, n, "End")) {
      ended = 1;
    } else if (tok_is(t, n, "Dimension")) {
      ok = tok_long(&p, &v);
      f->dim = (int)v;
    } else if (tok_is(t, n, "Vertices")) {
      ok = tok_long(&p, &v) && v >= 0 && !f->xyz;
      if (!ok) break;
      f->nv = (size_t)v;
      f->xyz = malloc((3 * f->nv + 1) * sizeof *f->xyz);
      f->vref = malloc((f->nv + 1) * sizeof *f->vref);
      for (size_t i = 0; ok && i < f->nv; i++) {
        for (int d = 0; ok && d < 3; d++)
          ok = tok_double(&p, &f->xyz[3 * i + d]);
        ok = ok && tok_long(&p, &v);
        f->vref[i] = (int32_t)v;
      }
    } else {
      int k = 0;
      while (k < NKINDS && !tok_is(t, n, kind_name[k])) k++;
      ok = k < NKINDS && !f->seen[k] && tok_long(&p, &v) && v >= 0;
      if (!ok) break;
      f->seen[k] = 1;
      f->n[k] = (size_t)v;
      const int w = kind_nodes[k] + 1;
      f->el[k] = malloc(((size_t)w * f->n[k] + 1) * sizeof *f->el[k]);
      for (size_t i = 0; ok && i < (size_t)w * f->n[k]; i++) {
        ok = tok_long(&p, &v);
        f->el[k][i] = (int32_t)v;
      }
    }
  }
  ok = ok && token(&p, &n) == NULL; /* nothing after End */
  free(buf);
  return ok;
}

typedef struct {
  const unsigned char *b;
  size_t len, at;
  int ok;
} bin_reader;

static int64_t get_int(bin_reader *r, int bytes) {
  if (r->at + (size_t)bytes > r->len) {
    r->ok = 0;
    return 0;
  }
  int64_t v;
  if (bytes == 8) {
    memcpy(&v, r->b + r->at, 8);
  } else {
    int32_t w;
    memcpy(&w, r->b + r->at, 4);
    v = w;
  }
  r->at += (size_t)bytes;
  return v;
}

static double get_real(bin_reader *r) {
  double d = 0;
  if (r->at + 8 > r->len) {
    r->ok = 0;
    return 0;
  }
  memcpy(&d, r->b + r->at, 8);
  r->at += 8;
  return d;
}

/* Versions 2 and 3 (float64 reals, int32 integers; positions int32 / int64),
 * same byte order as this machine (code word 1). */
static int read_binary(const char *path, mfile *f) {
  memset(f, 0, sizeof *f);
  size_t len;
  char *buf = slurp(path, &len);
  if (!buf) return 0;
  bin_reader r = {(const unsigned char *)buf, len, 0, 1};
  int ok = get_int(&r, 4) == 1;
  f->version = (int)get_int(&r, 4);
  ok = ok && (f->version == 2 || f->version == 3);
  const int posb = f->version >= 3 ? 8 : 4;
  int ended = 0;
  while (ok && r.ok && !ended) {
    const int64_t code = get_int(&r, 4);
    const int64_t next = get_int(&r, posb);
    if (code == 54) {
      ended = 1;
      ok = next == 0;
      break;
    }
    if (code == 3) {
      f->dim = (int)get_int(&r, 4);
    } else if (code == 4) {
      const int64_t nv = get_int(&r, 4);
      ok = nv >= 0 && !f->xyz;
      if (!ok) break;
      f->nv = (size_t)nv;
      f->xyz = malloc((3 * f->nv + 1) * sizeof *f->xyz);
      f->vref = malloc((f->nv + 1) * sizeof *f->vref);
      for (size_t i = 0; r.ok && i < f->nv; i++) {
        for (int d = 0; d < 3; d++) f->xyz[3 * i + d] = get_real(&r);
        f->vref[i] = (int32_t)get_int(&r, 4);
      }
    } else {
      int k = 0;
      while (k < NKINDS && kind_code[k] != code) k++;
      const int64_t cnt = get_int(&r, 4);
      ok = k < NKINDS && !f->seen[k] && cnt >= 0;
      if (!ok) break;
      f->seen[k] = 1;
      f->n[k] = (size_t)cnt;
      const int w = kind_nodes[k] + 1;
      f->el[k] = malloc(((size_t)w * f->n[k] + 1) * sizeof *f->el[k]);
      for (size_t i = 0; r.ok && i < (size_t)w * f->n[k]; i++)
        f->el[k][i] = (int32_t)get_int(&r, 4);
    }
    ok = ok && r.ok && (size_t)next == r.at;
  }
  ok = ok && r.ok && ended && r.at == len;
  free(buf);
  return ok;
}

static int read_medit(const char *path, int binary, mfile *f) {
  int ok = binary ? read_binary(path, f) : read_ascii(path, f);
  if (!ok) fprintf(stderr, "test: cannot parse %s\n", path);
  return ok && f->dim == 3 && f->version >= 2;
}

/* ====================================================================== */
/* Helpers                                                                */
/* ====================================================================== */

/* A fixed proper rigid motion, so the reference elements are not aligned. */
static void move(const double in[3], double out[3]) {
  const double a = 0.3, b = -0.7, c = 1.1;
  const double ca = cos(a), sa = sin(a), cb = cos(b), sb = sin(b), cc = cos(c),
               sc = sin(c);
  const double R[3][3] = {
      {cb * cc, -cb * sc, sb},
      {sa * sb * cc + ca * sc, -sa * sb * sc + ca * cc, -sa * cb},
      {-ca * sb * cc + sa * sc, ca * sb * sc + sa * cc, ca * cb}};
  for (int i = 0; i < 3; i++)
    out[i] = R[i][0] * in[0] + R[i][1] * in[1] + R[i][2] * in[2] +
             (double)(i + 1) * 0.37;
}

/* ====================================================================== */
/* The independent boundary count                                         */
/* ====================================================================== */

/* A hash table of faces keyed by their sorted node tuple; each entry keeps
 * its use count and, from its first user, the oriented face (Medit
 * numbering, 0-based node indices). */
typedef struct {
  uint32_t key[4]; /* sorted, key[3] = UINT32_MAX for a triangle */
  uint32_t face[4];
  int n, uses;
} fentry;

typedef struct {
  fentry *e;
  size_t cap, count;
} fhash;

static void sort4(uint32_t *v) {
  for (int i = 1; i < 4; i++)
    for (int j = i; j > 0 && v[j - 1] > v[j]; j--) {
      uint32_t t = v[j];
      v[j] = v[j - 1];
      v[j - 1] = t;
    }
}

static size_t fhash_slot(const fhash *h, const uint32_t *key) {
  uint64_t x = 1469598103934665603ULL;
  for (int i = 0; i < 4; i++) x = (x ^ key[i]) * 1099511628211ULL;
  size_t s = (size_t)(x ^ (x >> 29)) & (h->cap - 1);
  while (h->e[s].n && memcmp(h->e[s].key, key, sizeof h->e[s].key) != 0)
    s = (s + 1) & (h->cap - 1);
  return s;
}

/* All faces of the elements of f (volume kinds), counted. */
static void fhash_build(fhash *h, const mfile *f) {
  size_t total = 0;
  for (int t = 0; t < 4; t++) total += f->n[t] * (size_t)medit_nfaces[t];
  h->cap = 16;
  while (h->cap < 2 * total + 16) h->cap <<= 1;
  h->e = calloc(h->cap, sizeof *h->e);
  h->count = 0;
  for (int t = 0; t < 4; t++) {
    const int w = kind_nodes[t] + 1;
    for (size_t c = 0; c < f->n[t]; c++) {
      const int32_t *row = f->el[t] + (size_t)w * c;
      for (int g = 0; g < medit_nfaces[t]; g++) {
        const int *fv = medit_faces[t][g];
        const int n = fv[3] < 0 ? 3 : 4;
        uint32_t face[4] = {0, 0, 0, 0}, key[4];
        for (int j = 0; j < n; j++) face[j] = (uint32_t)(row[fv[j]] - 1);
        memcpy(key, face, sizeof key);
        if (n == 3) key[3] = UINT32_MAX;
        sort4(key);
        const size_t s = fhash_slot(h, key);
        if (!h->e[s].n) {
          memcpy(h->e[s].key, key, sizeof key);
          memcpy(h->e[s].face, face, sizeof face);
          h->e[s].n = n;
          h->count++;
        }
        h->e[s].uses++;
      }
    }
  }
}

/* Whether b is a cyclic rotation of a (same orientation). */
static int same_cycle(const uint32_t *a, const int32_t *b1, int n) {
  for (int r = 0; r < n; r++) {
    int same = 1;
    for (int j = 0; j < n && same; j++)
      same = a[(r + j) % n] == (uint32_t)(b1[j] - 1);
    if (same) return 1;
  }
  return 0;
}

/* The boundary faces of file f are exactly the faces used once, each
 * written once, with the orientation of its element's outward face. */
static void check_boundary(const mfile *f, size_t *expected_out) {
  fhash h;
  fhash_build(&h, f);
  size_t expected = 0;
  for (size_t s = 0; s < h.cap; s++)
    if (h.e[s].n && h.e[s].uses == 1) expected++;
  CHECK(f->n[K_TRI] + f->n[K_QUAD] == expected);
  size_t matched = 0, misoriented = 0;
  for (int k = K_TRI; k <= K_QUAD; k++) {
    const int n = kind_nodes[k];
    for (size_t i = 0; i < f->n[k]; i++) {
      const int32_t *row = f->el[k] + (size_t)(n + 1) * i;
      uint32_t key[4];
      for (int j = 0; j < 4; j++)
        key[j] = j < n ? (uint32_t)(row[j] - 1) : UINT32_MAX;
      sort4(key);
      const size_t s = fhash_slot(&h, key);
      if (!h.e[s].n || h.e[s].uses != 1 || h.e[s].n != n) continue;
      h.e[s].uses = -1; /* written once */
      matched++;
      if (!same_cycle(h.e[s].face, row, n)) misoriented++;
      CHECK(row[n] == 1);
    }
  }
  CHECK(matched == expected);
  CHECK(misoriented == 0);
  free(h.e);
  if (expected_out) *expected_out = expected;
}

/* Every element of the file has positive volume in Medit's convention. */
static size_t count_nonpositive(const mfile *f, double *total) {
  size_t bad = 0;
  *total = 0;
  for (int t = 0; t < 4; t++) {
    const int w = kind_nodes[t] + 1;
    for (size_t c = 0; c < f->n[t]; c++) {
      double p[24];
      for (int j = 0; j < kind_nodes[t]; j++)
        memcpy(p + 3 * j,
               f->xyz + 3 * (size_t)(f->el[t][(size_t)w * c + j] - 1),
               3 * sizeof(double));
      const double vol = medit_volume(t, p);
      const int *q = corner[t];
      const double d =
          det3(p + 3 * q[0], p + 3 * q[1], p + 3 * q[2], p + 3 * q[3]);
      if (!(vol > 0) || !(d > 0)) bad++;
      *total += vol;
    }
  }
  return bad;
}

/* ====================================================================== */
/* Tests                                                                  */
/* ====================================================================== */

/* One reference element of each type, in the library's node order. */
static void reference_element(int t, tmesh *m) {
  static const double tet[4][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  static const double pyr[5][3] = {
      {0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0.5, 0.5, 1}};
  static const double pri[6][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0},
                                   {0, 0, 1}, {1, 0, 1}, {0, 1, 1}};
  static const double hex[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0},
                                   {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
  const double(*p)[3] = t == MX_TET       ? tet
                        : t == MX_PYRAMID ? pyr
                        : t == MX_PRISM   ? pri
                                          : hex;
  const int n = mx_cell_nodes[t];
  tmesh_alloc(m, (size_t)n, 1);
  m->type[0] = (uint8_t)t;
  for (int j = 0; j < n; j++) {
    move(p[j], m->xyz + 3 * j);
    m->conn[j] = (uint32_t)j;
  }
}

static void test_reference_elements(void) {
  static const double volume[4] = {1.0 / 6, 1.0 / 3, 0.5, 1.0};
  static const size_t ntri[4] = {4, 4, 2, 0}, nquad[4] = {0, 1, 3, 6};
  for (int t = 0; t < 4; t++) {
    tmesh m;
    reference_element(t, &m);
    /* the extractor alone */
    mx_boundary_faces bf;
    CHECK(mx_boundary_faces_extract(&m.v, &bf) == MX_OK);
    CHECK(bf.ntri == ntri[t] && bf.nquad == nquad[t]);
    int32_t flags[8];
    CHECK(mx_boundary_node_flags(&m.v, flags) == MX_OK);
    for (int j = 0; j < mx_cell_nodes[t]; j++) CHECK(flags[j] == 1);
    for (size_t i = 0; i < bf.ntri; i++) CHECK(bf.tri_src[i] >> 3 == 0);
    for (size_t i = 1; i < bf.ntri; i++)
      CHECK(bf.tri_src[i] > bf.tri_src[i - 1]);
    mx_boundary_faces_free(&bf);
    for (int binary = 0; binary <= 1; binary++) {
      char path[256];
      snprintf(path, sizeof path, "%s/ref%d.%s", OUT_DIR, t,
               binary ? "meshb" : "mesh");
      CHECK(mx_write_medit(path, &m.v, binary) == MX_OK);
      mfile f;
      CHECK(read_medit(path, binary, &f));
      CHECK(f.version == 2);
      CHECK(f.nv == m.nnodes);
      CHECK(f.n[t] == 1);
      for (int k = 0; k < 4; k++)
        if (k != t) CHECK(f.n[k] == 0);
      CHECK(f.n[K_TRI] == ntri[t] && f.n[K_QUAD] == nquad[t]);
      /* coordinates exactly */
      CHECK(f.xyz && memcmp(f.xyz, m.xyz, 3 * m.nnodes * sizeof(double)) == 0);
      for (size_t i = 0; f.vref && i < f.nv; i++) CHECK(f.vref[i] == 0);
      double total;
      CHECK(count_nonpositive(&f, &total) == 0);
      CHECK(fabs(total - volume[t]) < 1e-12);
      /* each boundary face: a face of the element, outward (its normal
       * points away from the element's centroid), every face once */
      double cen[3] = {0, 0, 0};
      for (size_t j = 0; j < f.nv; j++)
        for (int d = 0; d < 3; d++) cen[d] += f.xyz[3 * j + d] / (double)f.nv;
      int outward = 0;
      for (int k = K_TRI; k <= K_QUAD; k++) {
        const int n = kind_nodes[k];
        for (size_t i = 0; i < f.n[k]; i++) {
          const int32_t *row = f.el[k] + (size_t)(n + 1) * i;
          double nrm[3] = {0, 0, 0}, fc[3] = {0, 0, 0};
          for (int j = 0; j < n; j++) {
            const double *a = f.xyz + 3 * (row[j] - 1);
            const double *b = f.xyz + 3 * (row[(j + 1) % n] - 1);
            nrm[0] += (a[1] - b[1]) * (a[2] + b[2]);
            nrm[1] += (a[2] - b[2]) * (a[0] + b[0]);
            nrm[2] += (a[0] - b[0]) * (a[1] + b[1]);
            for (int d = 0; d < 3; d++) fc[d] += a[d] / n;
          }
          const double dot = nrm[0] * (fc[0] - cen[0]) +
                             nrm[1] * (fc[1] - cen[1]) +
                             nrm[2] * (fc[2] - cen[2]);
          if (dot > 0) outward++;
        }
      }
      CHECK(outward == medit_nfaces[t]);
      check_boundary(&f, NULL);
      mfile_free(&f);
    }
    tmesh_free(&m);
  }
}

/* A block of nx x ny x nz unit hexahedra. */
static void hex_block(tmesh *m, size_t nx, size_t ny, size_t nz) {
  const size_t px = nx + 1, py = ny + 1, pz = nz + 1;
  tmesh_alloc(m, px * py * pz, nx * ny * nz);
  for (size_t k = 0; k < pz; k++)
    for (size_t j = 0; j < py; j++)
      for (size_t i = 0; i < px; i++) {
        double *x = m->xyz + 3 * ((k * py + j) * px + i);
        x[0] = 0.1 * (double)i;
        x[1] = 0.1 * (double)j;
        x[2] = 0.1 * (double)k;
      }
  for (size_t k = 0; k < nz; k++)
    for (size_t j = 0; j < ny; j++)
      for (size_t i = 0; i < nx; i++) {
        const size_t c = (k * ny + j) * nx + i;
        const uint32_t b = (uint32_t)((k * py + j) * px + i);
        const uint32_t sx = 1, sy = (uint32_t)px, sz = (uint32_t)(px * py);
        const uint32_t v[8] = {
            b,      b + sx,      b + sx + sy,      b + sy,
            b + sz, b + sx + sz, b + sx + sy + sz, b + sy + sz};
        m->type[c] = MX_HEX;
        memcpy(m->conn + 8 * c, v, sizeof v);
      }
}

static void test_hex_blocks(void) {
  tmesh m;
  mx_boundary_faces bf;
  hex_block(&m, 1, 1, 1);
  CHECK(mx_boundary_faces_extract(&m.v, &bf) == MX_OK);
  CHECK(bf.ntri == 0 && bf.nquad == 6);
  mx_boundary_faces_free(&bf);
  tmesh_free(&m);
  hex_block(&m, 2, 1, 1);
  CHECK(mx_boundary_faces_extract(&m.v, &bf) == MX_OK);
  CHECK(bf.ntri == 0 && bf.nquad == 10);
  /* element then face order: 5 faces of hex 0 then 5 of hex 1 */
  for (size_t i = 0; i < bf.nquad; i++)
    CHECK((bf.quad_src[i] >> 3) == (i < 5 ? 0u : 1u));
  mx_boundary_faces_free(&bf);
  int32_t flags[12];
  CHECK(mx_boundary_node_flags(&m.v, flags) == MX_OK);
  for (int i = 0; i < 12; i++) CHECK(flags[i] == 1);
  char path[256];
  path_in(path, sizeof path, "two_hexes.mesh");
  CHECK(mx_write_medit(path, &m.v, 0) == MX_OK);
  mfile f;
  CHECK(read_medit(path, 0, &f));
  CHECK(f.n[MX_HEX] == 2 && f.n[K_QUAD] == 10 && f.n[K_TRI] == 0);
  check_boundary(&f, NULL);
  mfile_free(&f);
  tmesh_free(&m);
  /* 3x3x3: the centre node is inside */
  hex_block(&m, 3, 3, 3);
  int32_t fl[64];
  CHECK(mx_boundary_node_flags(&m.v, fl) == MX_OK);
  size_t on = 0;
  for (int i = 0; i < 64; i++) on += (size_t)fl[i];
  CHECK(on == 64 - 8 && fl[21] == 0 && fl[42] == 0);
  CHECK(mx_boundary_faces_extract(&m.v, &bf) == MX_OK);
  CHECK(bf.nquad == 54);
  mx_boundary_faces_free(&bf);
  tmesh_free(&m);
}

/* The conforming mixed mesh of a transition stage (demo surface). */
static int transition_mesh(mx_mesh *M, int s_level) {
  mx_trisoup demo;
  memset(&demo, 0, sizeof demo);
  int st = mx_demo_surface(&demo, 3);
  mx_requests r = no_requests();
  r.s_level = s_level;
  mx_builder B;
  uint32_t r0[2] = {(uint32_t)demo.nt, (uint32_t)demo.nt};
  if (!st) st = mx_builder_init(&B, &demo, (uint32_t)demo.nt, r0, &r, 1, NULL);
  if (!st) st = mx_build_roots(&B);
  if (!st) st = mx_refine_balanced(&B);
  if (!st) st = mx_resolve_closures(&B);
  uint32_t *leaves = NULL;
  size_t n = 0;
  if (!st) st = mx_leaves(&B.tree, &leaves, &n);
  if (!st) st = mx_leaves_sorted(&B.tree, leaves, n);
  if (!st) st = mx_transition(&B.tree, leaves, n, M);
  mx_free(leaves);
  mx_builder_free(&B);
  mx_trisoup_free(&demo);
  return st;
}

/* Writes v as .mesh and .meshb and checks what comes back: vertices bit
 * for bit, the elements of each type in index order with the library's
 * nodes, positive volumes, the boundary against the independent count. */
static void round_trip(const mx_mesh_view *v, const char *name) {
  size_t by_type[4] = {0, 0, 0, 0};
  for (size_t c = 0; c < v->ncells; c++) by_type[v->type[c]]++;
  printf(
      "%s: %zu nodes, %zu elements (tet %zu, pyramid %zu, prism %zu, "
      "hex %zu)\n",
      name, v->nnodes, v->ncells, by_type[MX_TET], by_type[MX_PYRAMID],
      by_type[MX_PRISM], by_type[MX_HEX]);
  CHECK(by_type[MX_TET] && by_type[MX_PYRAMID] && by_type[MX_PRISM] &&
        by_type[MX_HEX]);
  mx_boundary_faces bf;
  CHECK(mx_boundary_faces_extract(v, &bf) == MX_OK);
  for (int binary = 0; binary <= 1; binary++) {
    char path[256];
    snprintf(path, sizeof path, "%s/%s.%s", OUT_DIR, name,
             binary ? "meshb" : "mesh");
    CHECK(mx_write_medit(path, v, binary) == MX_OK);
    CHECK(mx_write_mesh(path, v, 1) == MX_OK); /* the dispatch */
    mfile f;
    CHECK(read_medit(path, binary, &f));
    CHECK(f.nv == v->nnodes);
    CHECK(f.xyz && memcmp(f.xyz, v->xyz, 3 * v->nnodes * sizeof(double)) == 0);
    size_t seen[4] = {0, 0, 0, 0}, mismatch = 0;
    for (int t = 0; t < 4; t++) CHECK(f.n[t] == by_type[t]);
    for (size_t c = 0; c < v->ncells; c++) {
      const int t = v->type[c];
      const size_t i = seen[t]++;
      if (i >= f.n[t]) {
        mismatch++;
        continue;
      }
      const int32_t *row = f.el[t] + (size_t)(kind_nodes[t] + 1) * i;
      for (int j = 0; j < kind_nodes[t]; j++)
        if ((uint32_t)(row[j] - 1) != v->conn[8 * c + j]) mismatch++;
      if (row[kind_nodes[t]] != 1) mismatch++;
    }
    CHECK(mismatch == 0);
    double total;
    const size_t bad = count_nonpositive(&f, &total);
    CHECK(bad == 0);
    size_t expected = 0;
    check_boundary(&f, &expected);
    CHECK(f.n[K_TRI] == bf.ntri && f.n[K_QUAD] == bf.nquad);
    printf(
        "  %s: %zu triangles, %zu quadrilaterals on the boundary "
        "(independent count %zu), volume %.6g, %zu elements not positive\n",
        path, f.n[K_TRI], f.n[K_QUAD], expected, total, bad);
    mfile_free(&f);
  }
  /* node flags agree with the faces */
  int32_t *flags = calloc(v->nnodes + 1, sizeof *flags);
  char *mark = calloc(v->nnodes + 1, 1);
  CHECK(mx_boundary_node_flags(v, flags) == MX_OK);
  for (size_t i = 0; i < 3 * bf.ntri; i++) mark[bf.tri[i]] = 1;
  for (size_t i = 0; i < 4 * bf.nquad; i++) mark[bf.quad[i]] = 1;
  size_t differ = 0;
  for (size_t i = 0; i < v->nnodes; i++)
    differ += (size_t)(flags[i] != mark[i]);
  CHECK(differ == 0);
  free(flags);
  free(mark);
  mx_boundary_faces_free(&bf);
}

static void test_mixed_round_trip(void) {
  mx_mesh M;
  CHECK(transition_mesh(&M, 4) == MX_OK);
  mx_mesh_view v = {.nnodes = M.nnodes, .xyz = M.xyz, .ncells = M.ncells, .type = M.type, .conn = M.conn, .ncell_fields = 0, .cell_fields = NULL, .npoint_fields = 0, .point_fields = NULL};
  round_trip(&v, "mixed");
  /* the elements whose centroid lies in a ball: a ragged boundary with
   * triangles and quadrilaterals (the other nodes stay, unused) */
  double lo[3] = {INFINITY, INFINITY, INFINITY},
         hi[3] = {-INFINITY, -INFINITY, -INFINITY};
  for (size_t i = 0; i < M.nnodes; i++)
    for (int d = 0; d < 3; d++) {
      lo[d] = fmin(lo[d], M.xyz[3 * i + d]);
      hi[d] = fmax(hi[d], M.xyz[3 * i + d]);
    }
  uint8_t *type = malloc(M.ncells);
  uint32_t *conn = malloc(8 * M.ncells * sizeof *conn);
  size_t kept = 0;
  for (size_t c = 0; c < M.ncells; c++) {
    const int t = M.type[c];
    double g[3] = {0, 0, 0}, r2 = 0;
    for (int j = 0; j < mx_cell_nodes[t]; j++)
      for (int d = 0; d < 3; d++)
        g[d] += M.xyz[3 * M.conn[8 * c + j] + d] / mx_cell_nodes[t];
    for (int d = 0; d < 3; d++) {
      const double u = (g[d] - 0.55 * lo[d] - 0.45 * hi[d]) / (hi[d] - lo[d]);
      r2 += u * u;
    }
    if (r2 > 0.3 * 0.3) continue;
    type[kept] = (uint8_t)t;
    memcpy(conn + 8 * kept, M.conn + 8 * c, 8 * sizeof *conn);
    kept++;
  }
  mx_mesh_view w = {.nnodes = M.nnodes, .xyz = M.xyz, .ncells = kept, .type = type, .conn = conn, .ncell_fields = 0, .cell_fields = NULL, .npoint_fields = 0, .point_fields = NULL};
  round_trip(&w, "ball");
  mx_boundary_faces bf;
  CHECK(mx_boundary_faces_extract(&w, &bf) == MX_OK);
  CHECK(bf.ntri > 0 && bf.nquad > 0);
  mx_boundary_faces_free(&bf);
  free(type);
  free(conn);
  mx_mesh_free(&M);
}

/* Coordinates of every magnitude read back bit for bit from ASCII. */
static void test_ascii_reals(void) {
  const size_t nextra = 20000;
  tmesh m;
  tmesh_alloc(&m, 4 + nextra, 1);
  static const double tet[4][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  memcpy(m.xyz, tet, sizeof tet);
  for (int j = 0; j < 4; j++) m.conn[j] = (uint32_t)j;
  m.type[0] = MX_TET;
  uint64_t s = 12345;
  static const double special[] = {0.1,
                                   -0.3,
                                   1e-300,
                                   -2.5e300,
                                   1e22,
                                   1e23,
                                   5e-324,
                                   1.7976931348623157e308,
                                   123456789012345678.0,
                                   0.30000000000000004,
                                   1.0 / 3,
                                   -0.0};
  const size_t nspecial = sizeof special / sizeof *special;
  for (size_t i = 0; i < 3 * nextra; i++) {
    s = s * 6364136223846793005ULL + 1442695040888963407ULL;
    double x;
    if (i < nspecial) {
      x = special[i];
    } else if (i % 4 == 3) { /* every scale the fast path covers */
      const double u = (double)(s >> 11) / 9007199254740992.0;
      x = (u - 0.5) * pow(10.0, (double)((s >> 3) % 56) - 14.0);
    } else if (i % 3 == 0) {
      uint64_t bits = s; /* any finite double */
      memcpy(&x, &bits, 8);
      if (!isfinite(x)) x = 1.5;
    } else {
      x = ((double)(s >> 11) / 9007199254740992.0 - 0.5) * 200.0;
      if (i % 3 == 2) x = round(x * 1000) / 1000; /* short decimals */
    }
    m.xyz[12 + i] = x;
  }
  char path[256];
  path_in(path, sizeof path, "reals.mesh");
  CHECK(mx_write_medit(path, &m.v, 0) == MX_OK);
  mfile f;
  CHECK(read_medit(path, 0, &f));
  size_t differ = 0;
  for (size_t i = 0; f.xyz && i < 3 * m.nnodes; i++)
    differ += f.xyz[i] != m.xyz[i];
  CHECK(f.nv == m.nnodes && differ == 0);
  mfile_free(&f);
  /* short forms: 0.1 and 1e22 are written as such; the 15-digit form is
   * only tried where one double operation decides it exactly (mx_put_double,
   * io/text_num.h), so -2.5e300 keeps 17 digits; -0.0 is "-0" */
  size_t len;
  char *txt = slurp(path, &len);
  CHECK(txt && strstr(txt, "\n0 0 0 0\n"));
  CHECK(txt && strstr(txt, "0.1 -0.3 1e-300 0\n"));
  CHECK(txt && strstr(txt, "\n-2.5000000000000001e+300 1e+22 1e+23 0\n"));
  CHECK(txt &&
        strstr(txt, "\n0.30000000000000004 0.33333333333333331 -0 0\n"));
  free(txt);
  tmesh_free(&m);
}

static void test_threads_identical(void) {
  tmesh big;
  hex_block(&big, 40, 30, 25); /* 30000 hexahedra: many chunks and parts */
  /* irrational-looking coordinates for the ASCII reals */
  for (size_t i = 0; i < 3 * big.nnodes; i++)
    big.xyz[i] = big.xyz[i] * 1.2345678901 + 0.1 * sin((double)i);
  mx_mesh M;
  CHECK(transition_mesh(&M, 5) == MX_OK);
  mx_mesh_view mv = {.nnodes = M.nnodes, .xyz = M.xyz, .ncells = M.ncells, .type = M.type, .conn = M.conn, .ncell_fields = 0, .cell_fields = NULL, .npoint_fields = 0, .point_fields = NULL};
  const mx_mesh_view *views[2] = {&big.v, &mv};
  const int saved = omp_get_max_threads();
  for (int w = 0; w < 2; w++) {
    for (int binary = 0; binary <= 1; binary++) {
      char p1[256], p2[256];
      snprintf(p1, sizeof p1, "%s/thr%d_1.%s", OUT_DIR, w,
               binary ? "meshb" : "mesh");
      snprintf(p2, sizeof p2, "%s/thr%d_2.%s", OUT_DIR, w,
               binary ? "meshb" : "mesh");
      omp_set_num_threads(1);
      CHECK(mx_write_medit(p1, views[w], binary) == MX_OK);
      omp_set_num_threads(2);
      CHECK(mx_write_medit(p2, views[w], binary) == MX_OK);
      omp_set_num_threads(saved);
      CHECK(files_equal(p1, p2));
      mfile f;
      CHECK(read_medit(p1, binary, &f));
      check_boundary(&f, NULL);
      mfile_free(&f);
      unlink(p1);
      unlink(p2);
    }
    /* the extractor itself */
    mx_boundary_faces a, b;
    omp_set_num_threads(1);
    CHECK(mx_boundary_faces_extract(views[w], &a) == MX_OK);
    omp_set_num_threads(2);
    CHECK(mx_boundary_faces_extract(views[w], &b) == MX_OK);
    omp_set_num_threads(saved);
    CHECK(a.ntri == b.ntri && a.nquad == b.nquad);
    if (a.ntri == b.ntri && a.nquad == b.nquad) {
      CHECK(!a.ntri || memcmp(a.tri, b.tri, 12 * a.ntri) == 0);
      CHECK(!a.nquad || memcmp(a.quad, b.quad, 16 * a.nquad) == 0);
      CHECK(!a.ntri || memcmp(a.tri_src, b.tri_src, 8 * a.ntri) == 0);
    }
    if (w == 0) CHECK(a.nquad == 2 * (40 * 30 + 30 * 25 + 40 * 25));
    mx_boundary_faces_free(&a);
    mx_boundary_faces_free(&b);
  }
  mx_mesh_free(&M);
  tmesh_free(&big);
}

static void test_failures(void) {
  tmesh m;
  hex_block(&m, 2, 1, 1);
  fprintf(stderr, "(expected errors follow)\n");
  for (int binary = 0; binary <= 1; binary++) {
    CHECK(mx_write_medit("/dev/full", &m.v, binary) == MX_EIO);
    char path[256];
    path_in(path, sizeof path,
            binary ? "no_such_dir/x.meshb" : "no_such_dir/x.mesh");
    CHECK(mx_write_medit(path, &m.v, binary) == MX_EIO);
    CHECK(!exists(path));
    /* a directory under a regular file cannot be created, even by root */
    path_in(path, sizeof path, "plainfile");
    FILE *fp = fopen(path, "w");
    CHECK(fp && fclose(fp) == 0);
    path_in(path, sizeof path,
            binary ? "plainfile/x.meshb" : "plainfile/x.mesh");
    CHECK(mx_write_medit(path, &m.v, binary) == MX_EIO);
  }
  CHECK(dev_full_intact());
  CHECK(count_entries(OUT_DIR, "plainfile.") == 0);
  /* an inconsistent mesh is refused before any file is created */
  m.conn[3] = 99;
  char path[256];
  path_in(path, sizeof path, "bad.mesh");
  CHECK(mx_write_medit(path, &m.v, 0) == MX_EINTERNAL);
  CHECK(!exists(path));
  tmesh_free(&m);
  /* an empty mesh is a valid file */
  tmesh e;
  tmesh_alloc(&e, 0, 0);
  path_in(path, sizeof path, "empty.meshb");
  CHECK(mx_write_medit(path, &e.v, 1) == MX_OK);
  mfile f;
  CHECK(read_medit(path, 1, &f) && f.nv == 0);
  mfile_free(&f);
  tmesh_free(&e);
}

int main(void) {
  mkdir(OUT_DIR, 0755);
  test_reference_elements();
  test_hex_blocks();
  test_mixed_round_trip();
  test_ascii_reals();
  test_threads_identical();
  test_failures();
  return TEST_DONE();
}
