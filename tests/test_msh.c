/* Tests of the Gmsh MSH 4.1 writer (src/io/write_msh.c).
 *
 * Files are read back by a small reader written here from the MSH 4.1
 * specification (ASCII and binary: sections, entity blocks, 8-byte size_t,
 * the int 1 byte-order check), independent of the writer:
 *  - one reference element of each type, valid for mixoct (J_ENS > 0 in its
 *    VTK order), must come out with positive volume in Gmsh's convention:
 *    the nodes read back are matched against Gmsh's documented reference
 *    coordinates (every tetrahedron of four reference nodes keeps the sign
 *    it has in the reference element), and the signed volume, summed over a
 *    tetrahedral decomposition oriented by the reference coordinates, equals
 *    the element's volume; a mirrored element comes out negative;
 *  - a mixed mesh round trip (counts per type, tags, connectivity,
 *    coordinates bit-exact in binary and in ASCII, entities, bounding box);
 *  - 1, 2 and 3 threads write identical bytes;
 *  - /dev/full, a missing directory, a path under a regular file, a path
 *    in /proc (and a read-only directory when not root) fail with MX_EINPUT
 *    and leave no file. */
#include <dirent.h>
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
#include "geom/quality.h"
#include "soa/mesh.h"

#define OUT_DIR "msh_out"
#include "file_util.h"
#include "io/write_mesh.h"

/* ====================================================================== */
/* Gmsh's conventions, from the Gmsh manual (not from the writer)         */
/* ====================================================================== */

/* Element types 4 (tet), 5 (hex), 6 (prism), 7 (pyramid): node counts and
 * reference coordinates ("Node ordering" in the manual). */
static int gmsh_nodes(int gtype) {
  switch (gtype) {
    case 4: return 4;
    case 5: return 8;
    case 6: return 6;
    case 7: return 5;
    default: return 0;
  }
}

static const double gmsh_ref_tet[4][3] = {
    {0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
static const double gmsh_ref_pyramid[5][3] = {
    {-1, -1, 0}, {1, -1, 0}, {1, 1, 0}, {-1, 1, 0}, {0, 0, 1}};
static const double gmsh_ref_prism[6][3] = {{0, 0, -1}, {1, 0, -1}, {0, 1, -1},
                                            {0, 0, 1},  {1, 0, 1},  {0, 1, 1}};
static const double gmsh_ref_hex[8][3] = {
    {-1, -1, -1}, {1, -1, -1}, {1, 1, -1}, {-1, 1, -1},
    {-1, -1, 1},  {1, -1, 1},  {1, 1, 1},  {-1, 1, 1}};

static const double (*gmsh_ref(int gtype))[3] {
  switch (gtype) {
    case 4: return gmsh_ref_tet;
    case 5: return gmsh_ref_hex;
    case 6: return gmsh_ref_prism;
    default: return gmsh_ref_pyramid;
  }
}

/* Tetrahedral decompositions of the reference elements (node indices in
 * Gmsh's order; each tetrahedron is oriented by its reference volume). */
static const int decomp_tet[1][4] = {{0, 1, 2, 3}};
static const int decomp_pyramid[2][4] = {{0, 1, 2, 4}, {0, 2, 3, 4}};
static const int decomp_prism[3][4] = {{0, 1, 2, 3}, {1, 2, 3, 4}, {2, 3, 4, 5}};
static const int decomp_hex[5][4] = {
    {0, 1, 3, 4}, {1, 2, 3, 6}, {1, 4, 5, 6}, {3, 4, 6, 7}, {1, 3, 4, 6}};

/* The element's node k in Gmsh's order is mixoct's (VTK-order) node
 * vtk_of_gmsh[k]: Gmsh and VTK put the same corners first and both turn
 * the first face's normal into the element (VTK's parametric coordinates:
 * pyramid base (0,0,0) (1,0,0) (1,1,0) (0,1,0), apex above; wedge
 * (0,0,0) (1,0,0) (0,1,0) below (0,0,1) (1,0,1) (0,1,1)). The reference
 * element test below checks this against the coordinates above. */
static const int vtk_of_gmsh[8] = {0, 1, 2, 3, 4, 5, 6, 7};
static const int gmsh_type_of[4] = {4, 7, 6, 5};

static double tet_volume(const double *a, const double *b, const double *c,
                         const double *d) {
  double u[3], v[3], w[3];
  for (int k = 0; k < 3; k++) {
    u[k] = b[k] - a[k];
    v[k] = c[k] - a[k];
    w[k] = d[k] - a[k];
  }
  return ((u[1] * v[2] - u[2] * v[1]) * w[0] +
          (u[2] * v[0] - u[0] * v[2]) * w[1] +
          (u[0] * v[1] - u[1] * v[0]) * w[2]) /
         6.0;
}

/* Signed volume of an element given its nodes in Gmsh's order: the sum over
 * the decomposition, each tetrahedron counted with the sign it has in the
 * reference element. Also reports through *consistent whether every
 * non-degenerate tetrahedron of four nodes has the sign it has in the
 * reference element (true for any positive affine image of it). */
static double gmsh_signed_volume(int gtype, const double (*p)[3],
                                 int *consistent, double *ref_volume) {
  const double(*ref)[3] = gmsh_ref(gtype);
  int n = gmsh_nodes(gtype);
  const int(*dec)[4];
  int ndec;
  switch (gtype) {
    case 4: dec = decomp_tet, ndec = 1; break;
    case 5: dec = decomp_hex, ndec = 5; break;
    case 6: dec = decomp_prism, ndec = 3; break;
    default: dec = decomp_pyramid, ndec = 2; break;
  }
  double vol = 0.0, rvol = 0.0;
  for (int i = 0; i < ndec; i++) {
    const int *q = dec[i];
    double r = tet_volume(ref[q[0]], ref[q[1]], ref[q[2]], ref[q[3]]);
    double v = tet_volume(p[q[0]], p[q[1]], p[q[2]], p[q[3]]);
    vol += r > 0 ? v : -v;
    rvol += fabs(r);
  }
  int ok = 1;
  for (int a = 0; a < n; a++)
    for (int b = a + 1; b < n; b++)
      for (int c = b + 1; c < n; c++)
        for (int d = c + 1; d < n; d++) {
          double r = tet_volume(ref[a], ref[b], ref[c], ref[d]);
          if (fabs(r) < 1e-12) continue;
          double v = tet_volume(p[a], p[b], p[c], p[d]);
          if (!(v * r > 0)) ok = 0;
        }
  *consistent = ok;
  *ref_volume = rvol;
  return vol;
}

/* ====================================================================== */
/* An independent MSH 4.1 reader                                          */
/* ====================================================================== */

typedef struct {
  int binary;
  /* $PhysicalNames */
  int nphys, phys_dim, phys_tag;
  char phys_name[64];
  /* $Entities */
  int has_entities;
  uint64_t nent[4];
  int vol_tag, vol_phys;
  uint64_t vol_nphys, vol_nbound;
  double box[6];
  /* $Nodes */
  uint64_t node_blocks, nnodes, node_min, node_max;
  int node_dim, node_ent;
  uint64_t *node_tag;
  double *xyz;
  /* $Elements */
  uint64_t elem_blocks, nelems, elem_min, elem_max;
  int block_gtype[8];
  uint64_t block_count[8];
  uint64_t *elem_tag;
  int *elem_gtype;
  uint64_t *elem_nodes; /* 8 per element */
} msh_file;

typedef struct {
  const char *p, *end;
  int bad;
  char why[160];
} cursor;

static void cur_fail(cursor *c, const char *why) {
  if (!c->bad) snprintf(c->why, sizeof c->why, "%s", why);
  c->bad = 1;
}

static void skip_space(cursor *c) {
  while (c->p < c->end && (*c->p == ' ' || *c->p == '\n' || *c->p == '\r' ||
                           *c->p == '\t'))
    c->p++;
}

/* The next line must be exactly s (a section tag). */
static void expect_line(cursor *c, const char *s) {
  size_t n = strlen(s);
  if (c->bad) return;
  if ((size_t)(c->end - c->p) < n + 1 || memcmp(c->p, s, n) != 0 ||
      c->p[n] != '\n') {
    snprintf(c->why, sizeof c->why, "expected line '%s', got '%.20s'", s,
             c->p);
    c->bad = 1;
    return;
  }
  c->p += n + 1;
}

/* A blank-separated token: digits (and sign, dot, exponent). */
static size_t token(cursor *c, char *buf, size_t cap) {
  skip_space(c);
  size_t n = 0;
  while (c->p < c->end && *c->p != ' ' && *c->p != '\n' && *c->p != '\r' &&
         n + 1 < cap)
    buf[n++] = *c->p++;
  buf[n] = '\0';
  if (n == 0) cur_fail(c, "missing number");
  return n;
}

static uint64_t a_u64(cursor *c) {
  char buf[64], *e;
  if (c->bad || !token(c, buf, sizeof buf)) return 0;
  if (buf[0] == '-') cur_fail(c, "negative count or tag");
  uint64_t v = strtoull(buf, &e, 10);
  if (*e) cur_fail(c, "bad integer");
  return v;
}

static int a_int(cursor *c) {
  char buf[64], *e;
  if (c->bad || !token(c, buf, sizeof buf)) return 0;
  long v = strtol(buf, &e, 10);
  if (*e) cur_fail(c, "bad integer");
  return (int)v;
}

static double a_dbl(cursor *c) {
  char buf[64], *e;
  if (c->bad || !token(c, buf, sizeof buf)) return 0;
  double v = strtod(buf, &e);
  if (*e) cur_fail(c, "bad double");
  return v;
}

static void bin_take(cursor *c, void *out, size_t n) {
  if (c->bad) {
    memset(out, 0, n);
    return;
  }
  if ((size_t)(c->end - c->p) < n) {
    cur_fail(c, "truncated binary data");
    memset(out, 0, n);
    return;
  }
  memcpy(out, c->p, n);
  c->p += n;
}

static uint64_t b_u64(cursor *c) {
  uint64_t v;
  bin_take(c, &v, 8);
  return v;
}

static int b_int(cursor *c) {
  int32_t v;
  bin_take(c, &v, 4);
  return v;
}

static double b_dbl(cursor *c) {
  double v;
  bin_take(c, &v, 8);
  return v;
}

static uint64_t r_u64(cursor *c, int bin) { return bin ? b_u64(c) : a_u64(c); }
static int r_int(cursor *c, int bin) { return bin ? b_int(c) : a_int(c); }
static double r_dbl(cursor *c, int bin) { return bin ? b_dbl(c) : a_dbl(c); }

/* After a section's data: the end tag on its own line (a binary section's
 * data is followed by a newline). */
static void end_section(cursor *c, const char *tag) {
  if (c->bad) return;
  if (c->p < c->end && *c->p == '\n') c->p++;
  else if (c->p[-1] != '\n') cur_fail(c, "no newline before end tag");
  expect_line(c, tag);
}

static void read_format(cursor *c, msh_file *f) {
  expect_line(c, "$MeshFormat");
  if (c->bad) return;
  if ((size_t)(c->end - c->p) >= 8 && !memcmp(c->p, "4.1 0 8\n", 8)) {
    f->binary = 0;
  } else if ((size_t)(c->end - c->p) >= 8 && !memcmp(c->p, "4.1 1 8\n", 8)) {
    f->binary = 1;
  } else {
    cur_fail(c, "format line is not '4.1 0 8' or '4.1 1 8'");
    return;
  }
  c->p += 8;
  if (f->binary) {
    if (b_int(c) != 1) cur_fail(c, "byte-order int is not 1");
    if (c->p < c->end && *c->p == '\n') c->p++;
    else cur_fail(c, "no newline after the byte-order int");
  }
  expect_line(c, "$EndMeshFormat");
}

/* $PhysicalNames is ASCII in both variants. */
static void read_physical_names(cursor *c, msh_file *f) {
  f->nphys = a_int(c);
  for (int i = 0; i < f->nphys && !c->bad; i++) {
    f->phys_dim = a_int(c);
    f->phys_tag = a_int(c);
    skip_space(c);
    if (c->p >= c->end || *c->p != '"') {
      cur_fail(c, "physical name not quoted");
      return;
    }
    const char *q = memchr(c->p + 1, '"', (size_t)(c->end - c->p - 1));
    if (!q || q - c->p - 1 >= (long)sizeof f->phys_name) {
      cur_fail(c, "bad physical name");
      return;
    }
    memcpy(f->phys_name, c->p + 1, (size_t)(q - c->p - 1));
    f->phys_name[q - c->p - 1] = '\0';
    c->p = q + 1;
    if (c->p < c->end && *c->p == '\n') c->p++;
  }
  expect_line(c, "$EndPhysicalNames");
}

static void read_entities(cursor *c, msh_file *f) {
  const int bin = f->binary;
  f->has_entities = 1;
  for (int k = 0; k < 4; k++) f->nent[k] = r_u64(c, bin);
  if (f->nent[0] || f->nent[1] || f->nent[2] || f->nent[3] != 1) {
    cur_fail(c, "expected exactly one volume entity");
    return;
  }
  f->vol_tag = r_int(c, bin);
  for (int k = 0; k < 6; k++) f->box[k] = r_dbl(c, bin);
  f->vol_nphys = r_u64(c, bin);
  if (f->vol_nphys > 16) cur_fail(c, "too many physical tags");
  for (uint64_t i = 0; i < f->vol_nphys && !c->bad; i++)
    f->vol_phys = r_int(c, bin);
  f->vol_nbound = r_u64(c, bin);
  if (f->vol_nbound > 16) cur_fail(c, "too many bounding surfaces");
  for (uint64_t i = 0; i < f->vol_nbound && !c->bad; i++) (void)r_int(c, bin);
  end_section(c, "$EndEntities");
}

static void read_nodes(cursor *c, msh_file *f) {
  const int bin = f->binary;
  f->node_blocks = r_u64(c, bin);
  f->nnodes = r_u64(c, bin);
  f->node_min = r_u64(c, bin);
  f->node_max = r_u64(c, bin);
  if (c->bad || f->nnodes > ((uint64_t)1 << 32)) {
    cur_fail(c, "bad node header");
    return;
  }
  f->node_tag = calloc(f->nnodes + 1, sizeof *f->node_tag);
  f->xyz = calloc(3 * f->nnodes + 1, sizeof *f->xyz);
  uint64_t done = 0;
  for (uint64_t b = 0; b < f->node_blocks && !c->bad; b++) {
    f->node_dim = r_int(c, bin);
    f->node_ent = r_int(c, bin);
    int param = r_int(c, bin);
    uint64_t n = r_u64(c, bin);
    if (param != 0 || n > f->nnodes - done) {
      cur_fail(c, "bad node block");
      return;
    }
    for (uint64_t i = 0; i < n; i++) f->node_tag[done + i] = r_u64(c, bin);
    for (uint64_t i = 0; i < 3 * n; i++) f->xyz[3 * done + i] = r_dbl(c, bin);
    done += n;
  }
  if (done != f->nnodes) cur_fail(c, "node blocks do not add up");
  end_section(c, "$EndNodes");
}

static void read_elements(cursor *c, msh_file *f) {
  const int bin = f->binary;
  f->elem_blocks = r_u64(c, bin);
  f->nelems = r_u64(c, bin);
  f->elem_min = r_u64(c, bin);
  f->elem_max = r_u64(c, bin);
  if (c->bad || f->elem_blocks > 8 || f->nelems > ((uint64_t)1 << 32)) {
    cur_fail(c, "bad element header");
    return;
  }
  f->elem_tag = calloc(f->nelems + 1, sizeof *f->elem_tag);
  f->elem_gtype = calloc(f->nelems + 1, sizeof *f->elem_gtype);
  f->elem_nodes = calloc(8 * f->nelems + 1, sizeof *f->elem_nodes);
  uint64_t done = 0;
  for (uint64_t b = 0; b < f->elem_blocks && !c->bad; b++) {
    int dim = r_int(c, bin);
    int ent = r_int(c, bin);
    int gtype = r_int(c, bin);
    uint64_t n = r_u64(c, bin);
    int nn = gmsh_nodes(gtype);
    if (dim != 3 || ent != f->vol_tag || nn == 0 || n > f->nelems - done) {
      cur_fail(c, "bad element block");
      return;
    }
    f->block_gtype[b] = gtype;
    f->block_count[b] = n;
    for (uint64_t i = 0; i < n && !c->bad; i++) {
      f->elem_tag[done + i] = r_u64(c, bin);
      f->elem_gtype[done + i] = gtype;
      for (int k = 0; k < nn; k++)
        f->elem_nodes[8 * (done + i) + (uint64_t)k] = r_u64(c, bin);
    }
    done += n;
  }
  if (done != f->nelems) cur_fail(c, "element blocks do not add up");
  end_section(c, "$EndElements");
}

static void msh_free(msh_file *f) {
  free(f->node_tag);
  free(f->xyz);
  free(f->elem_tag);
  free(f->elem_gtype);
  free(f->elem_nodes);
  memset(f, 0, sizeof *f);
}

/* Reads path; returns 0 and prints why on failure. */
static int msh_read(const char *path, msh_file *f) {
  memset(f, 0, sizeof *f);
  size_t len;
  char *buf = slurp(path, &len);
  if (!buf) {
    fprintf(stderr, "%s: cannot read\n", path);
    return 0;
  }
  cursor c = {buf, buf + len, 0, ""};
  read_format(&c, f);
  int seen_nodes = 0, seen_elems = 0;
  while (!c.bad && c.p < c.end) {
    if (!strncmp(c.p, "$PhysicalNames\n", 15)) {
      c.p += 15;
      read_physical_names(&c, f);
    } else if (!strncmp(c.p, "$Entities\n", 10)) {
      c.p += 10;
      read_entities(&c, f);
    } else if (!strncmp(c.p, "$Nodes\n", 7)) {
      c.p += 7;
      read_nodes(&c, f);
      seen_nodes = 1;
    } else if (!strncmp(c.p, "$Elements\n", 10)) {
      c.p += 10;
      read_elements(&c, f);
      seen_elems = 1;
    } else {
      cur_fail(&c, "unknown section");
    }
  }
  if (!c.bad && (!seen_nodes || !seen_elems))
    cur_fail(&c, "no $Nodes or $Elements");
  if (c.bad)
    fprintf(stderr, "%s: %s (offset %ld)\n", path, c.why, (long)(c.p - buf));
  free(buf);
  return !c.bad;
}

/* ====================================================================== */
/* Reference elements                                                     */
/* ====================================================================== */

/* Valid elements in mixoct's (VTK) order, each a positive affine image of
 * the reference shape, with their volumes. */
static const double el_tet[4][3] = {{0, 0, 0}, {2, 0, 0}, {0, 3, 0}, {0, 0, 4}};
static const double el_pyramid[5][3] = {
    {0, 0, 0}, {2, 0, 0}, {2, 2, 0}, {0, 2, 0}, {1, 1, 1.5}};
static const double el_prism[6][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0},
                                      {0, 0, 2}, {1, 0, 2}, {0, 1, 2}};
static const double el_hex[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 2, 0},
                                    {0, 2, 0}, {0, 0, 3}, {1, 0, 3},
                                    {1, 2, 3}, {0, 2, 3}};
static const double el_volume[4] = {4.0, 2.0, 1.0, 6.0}; /* 2*3*4/6, 4*1.5/3 */

static const double (*element_nodes(int type))[3] {
  switch (type) {
    case MX_TET: return el_tet;
    case MX_PYRAMID: return el_pyramid;
    case MX_PRISM: return el_prism;
    default: return el_hex;
  }
}

/* A rotation (about an oblique axis) and a translation, so that no
 * coordinate is axis-aligned; mirror flips x first (an inverted element). */
static void place(const double in[3], double out[3], int mirror) {
  const double c = cos(0.7), s = sin(0.7);
  double x = mirror ? -in[0] : in[0], y = in[1], z = in[2];
  double x1 = c * x - s * y, y1 = s * x + c * y, z1 = z;      /* about z */
  double y2 = c * y1 - s * z1, z2 = s * y1 + c * z1, x2 = x1; /* about x */
  out[0] = x2 + 10.25;
  out[1] = y2 - 3.5;
  out[2] = z2 + 0.125;
}

static void one_element(tmesh *t, int type, int mirror) {
  int n = mx_cell_nodes[type];
  tmesh_alloc(t, (size_t)n, 1);
  const double(*p)[3] = element_nodes(type);
  uint32_t nodes[8];
  for (int j = 0; j < n; j++) {
    place(p[j], t->xyz + 3 * j, mirror);
    nodes[j] = (uint32_t)j;
  }
  set_cell(t, 0, type, nodes);
}

static void test_reference_elements(void) {
  static const char *names[4] = {"tet", "pyramid", "prism", "hex"};
  for (int type = 0; type < 4; type++) {
    for (int mirror = 0; mirror < 2; mirror++) {
      tmesh t;
      one_element(&t, type, mirror);
      double q = mx_jens(type, (const double(*)[3])t.xyz);
      CHECK(mirror ? q < 0 : q > 0); /* valid (or not) for mixoct */
      for (int binary = 0; binary < 2; binary++) {
        char path[512], name[64];
        snprintf(name, sizeof name, "ref_%s_%d_%d.msh", names[type], mirror,
                 binary);
        path_in(path, sizeof path, name);
        CHECK(mx_write_msh(path, &t.v, binary) == MX_OK);
        msh_file f;
        int ok = msh_read(path, &f);
        CHECK(ok);
        if (!ok) continue;
        CHECK(f.binary == binary);
        CHECK(f.nnodes == t.nnodes && f.nelems == 1 && f.elem_blocks == 1);
        int gtype = f.elem_gtype[0];
        CHECK(gtype == gmsh_type_of[type]);
        int n = gmsh_nodes(gtype);
        CHECK(n == mx_cell_nodes[type]);
        /* coordinates by Gmsh's node order, through the node tags */
        double p[8][3];
        int tags_ok = 1;
        for (int k = 0; k < n; k++) {
          uint64_t tag = f.elem_nodes[k];
          size_t i = 0;
          while (i < f.nnodes && f.node_tag[i] != tag) i++;
          if (i == f.nnodes) {
            tags_ok = 0;
            continue;
          }
          memcpy(p[k], f.xyz + 3 * i, sizeof p[k]);
        }
        CHECK(tags_ok);
        if (!tags_ok) {
          msh_free(&f);
          continue;
        }
        int consistent;
        double rvol;
        double vol =
            gmsh_signed_volume(gtype, (const double(*)[3])p, &consistent, &rvol);
        /* the decompositions tile the reference elements */
        static const double ref_vol[4] = {1.0 / 6.0, 4.0 / 3.0, 1.0, 8.0};
        CHECK(fabs(rvol - ref_vol[type]) < 1e-12);
        double want = mirror ? -el_volume[type] : el_volume[type];
        CHECK(fabs(vol - want) < 1e-9 * el_volume[type]);
        CHECK(consistent == !mirror);
        printf("%s %s %s: Gmsh type %d, signed volume %.6g (expected %.6g)\n",
               names[type], mirror ? "mirrored" : "valid",
               binary ? "binary" : "ascii", gtype, vol, want);
        msh_free(&f);
      }
      tmesh_free(&t);
    }
  }
}

/* ====================================================================== */
/* Mixed mesh round trip                                                  */
/* ====================================================================== */

static uint64_t rng_state = 0x2545F4914F6CDD1Dull;
static uint64_t rng_next(void) {
  rng_state ^= rng_state << 13;
  rng_state ^= rng_state >> 7;
  rng_state ^= rng_state << 17;
  return rng_state;
}

/* Random finite doubles of every magnitude, and decimal-looking ones. */
static double rng_double(void) {
  uint64_t r = rng_next() % 4;
  if (r == 0) return (double)(int64_t)(rng_next() % 2000001) / 1000.0 - 1e3;
  if (r == 1) return ldexp((double)(rng_next() >> 11), -53) * 200.0 - 100.0;
  double d;
  do {
    uint64_t b = rng_next();
    memcpy(&d, &b, 8);
  } while (!isfinite(d));
  return d;
}

/* An n^3 grid of hexahedra, each relabelled tet / pyramid / prism / hex at
 * random, or all of type only when only >= 0 (format-valid; geometry
 * irrelevant here); with random_coords a third of the nodes get random
 * doubles and the first coordinates special values. */
static void mixed_mesh(tmesh *t, size_t n, int random_coords, int only) {
  size_t np = n + 1;
  tmesh_alloc(t, np * np * np, n * n * n);
  double h = 2.6 / (double)n;
  for (size_t k = 0; k < np; k++)
    for (size_t j = 0; j < np; j++)
      for (size_t i = 0; i < np; i++) {
        size_t p = (k * np + j) * np + i;
        t->xyz[3 * p] = -1.3 + h * (double)i;
        t->xyz[3 * p + 1] = -1.3 + h * (double)j;
        t->xyz[3 * p + 2] = -1.3 + h * (double)k;
        if (random_coords && p % 3 == 1)
          for (int d = 0; d < 3; d++) t->xyz[3 * p + d] = rng_double();
      }
  static const double special[] = {0.1,     -0.0,    1e-300, 5e-324,
                                   1.7976931348623157e308, 1e23, 123456789.123,
                                   2.0000000000000004, -2.5e-7};
  if (random_coords)
    for (size_t s = 0; s < sizeof special / sizeof *special && s < 3 * np; s++)
      t->xyz[s] = special[s];
  for (size_t k = 0; k < n; k++)
    for (size_t j = 0; j < n; j++)
      for (size_t i = 0; i < n; i++) {
        size_t c = (k * n + j) * n + i;
        uint32_t b = (uint32_t)((k * np + j) * np + i);
        uint32_t sx = 1, sy = (uint32_t)np, sz = (uint32_t)(np * np);
        uint32_t nodes[8] = {b,      b + sx,      b + sx + sy,      b + sy,
                             b + sz, b + sx + sz, b + sx + sy + sz, b + sy + sz};
        set_cell(t, c, only >= 0 ? only : (int)(rng_next() % 4), nodes);
      }
}

static void check_roundtrip(const tmesh *t, const char *path, int binary) {
  msh_file f;
  int ok = msh_read(path, &f);
  CHECK(ok);
  if (!ok) return;
  const mx_mesh_view *m = &t->v;
  CHECK(f.binary == binary);
  /* physical group and entity */
  CHECK(f.nphys == 1 && f.phys_dim == 3 && f.phys_tag == 1);
  CHECK(!strcmp(f.phys_name, "domain"));
  CHECK(f.has_entities && f.vol_tag == 1 && f.vol_nphys == 1 &&
        f.vol_phys == 1 && f.vol_nbound == 0);
  double box[6] = {INFINITY, INFINITY, INFINITY, -INFINITY, -INFINITY,
                   -INFINITY};
  for (size_t i = 0; i < m->nnodes; i++)
    for (int d = 0; d < 3; d++) {
      box[d] = fmin(box[d], m->xyz[3 * i + d]);
      box[3 + d] = fmax(box[3 + d], m->xyz[3 * i + d]);
    }
  if (m->nnodes > 0)
    for (int k = 0; k < 6; k++) CHECK(f.box[k] == box[k]);
  /* nodes: one block on the volume, tags 1..N in order */
  CHECK(f.nnodes == m->nnodes);
  CHECK(f.node_blocks == (m->nnodes > 0));
  if (m->nnodes > 0) {
    CHECK(f.node_dim == 3 && f.node_ent == 1);
    CHECK(f.node_min == 1 && f.node_max == m->nnodes);
  }
  size_t bad_tags = 0, bad_xyz = 0;
  double worst = 0;
  for (size_t i = 0; i < f.nnodes && i < m->nnodes; i++) {
    if (f.node_tag[i] != i + 1) bad_tags++;
    for (int d = 0; d < 3; d++) {
      double a = f.xyz[3 * i + d], b = m->xyz[3 * i + d];
      if (memcmp(&a, &b, 8) != 0) bad_xyz++;
      double rel = fabs(a - b) / fmax(fabs(b), 1e-300);
      if (rel > worst) worst = rel;
    }
  }
  CHECK(bad_tags == 0);
  CHECK(worst <= 1e-12); /* the requirement for ASCII */
  CHECK(bad_xyz == 0);   /* and in fact bit-exact, binary and ASCII */
  /* elements: one block per type present, in the order tet, pyramid,
   * prism, hex; tag = index + 1; connectivity through vtk_of_gmsh */
  size_t count[4] = {0, 0, 0, 0};
  for (size_t c = 0; c < m->ncells; c++) count[m->type[c]]++;
  uint64_t nblocks = 0;
  for (int tp = 0; tp < 4; tp++) {
    if (!count[tp]) continue;
    CHECK(f.block_gtype[nblocks] == gmsh_type_of[tp]);
    CHECK(f.block_count[nblocks] == count[tp]);
    nblocks++;
  }
  CHECK(f.elem_blocks == nblocks);
  CHECK(f.nelems == m->ncells);
  if (m->ncells > 0) CHECK(f.elem_min == 1 && f.elem_max == m->ncells);
  size_t bad_elems = 0;
  uint64_t prev_tag = 0;
  int prev_gtype = 0;
  unsigned char *seen = calloc(m->ncells + 1, 1);
  for (size_t e = 0; e < f.nelems && f.nelems == m->ncells; e++) {
    uint64_t tag = f.elem_tag[e];
    if (tag < 1 || tag > m->ncells || seen[tag - 1]) {
      bad_elems++;
      continue;
    }
    seen[tag - 1] = 1;
    if (f.elem_gtype[e] == prev_gtype && tag <= prev_tag) bad_elems++;
    prev_tag = tag;
    prev_gtype = f.elem_gtype[e];
    size_t c = tag - 1;
    int tp = m->type[c];
    if (f.elem_gtype[e] != gmsh_type_of[tp]) {
      bad_elems++;
      continue;
    }
    for (int k = 0; k < mx_cell_nodes[tp]; k++)
      if (f.elem_nodes[8 * e + (size_t)k] !=
          (uint64_t)m->conn[8 * c + (size_t)vtk_of_gmsh[k]] + 1)
        bad_elems++;
  }
  free(seen);
  CHECK(bad_elems == 0);
  msh_free(&f);
}

static void test_roundtrip(void) {
  tmesh t;
  mixed_mesh(&t, 7, 1, -1);
  for (int binary = 0; binary < 2; binary++) {
    char path[512];
    path_in(path, sizeof path, binary ? "mixed_bin.msh" : "mixed_ascii.msh");
    CHECK(mx_write_msh(path, &t.v, binary) == MX_OK);
    check_roundtrip(&t, path, binary);
    printf("round trip %s: %zu nodes, %zu elements\n",
           binary ? "binary" : "ascii", t.nnodes, t.ncells);
  }
  /* through the extension dispatch: .msh, binary unless ascii is asked */
  char path[512];
  path_in(path, sizeof path, "dispatch.MSH");
  CHECK(mx_write_mesh(path, &t.v, 0) == MX_OK);
  check_roundtrip(&t, path, 1);
  CHECK(mx_write_mesh(path, &t.v, 1) == MX_OK);
  check_roundtrip(&t, path, 0);
  tmesh_free(&t);
  /* an empty mesh and a mesh with a single type */
  tmesh e;
  tmesh_alloc(&e, 0, 0);
  for (int binary = 0; binary < 2; binary++) {
    path_in(path, sizeof path, "empty.msh");
    CHECK(mx_write_msh(path, &e.v, binary) == MX_OK);
    check_roundtrip(&e, path, binary);
  }
  tmesh_free(&e);
  tmesh h;
  mixed_mesh(&h, 3, 0, MX_HEX);
  for (int binary = 0; binary < 2; binary++) {
    path_in(path, sizeof path, "hex_only.msh");
    CHECK(mx_write_msh(path, &h.v, binary) == MX_OK);
    check_roundtrip(&h, path, binary);
  }
  tmesh_free(&h);
}

/* ====================================================================== */
/* Thread-count invariance                                                */
/* ====================================================================== */

static void test_threads(void) {
  tmesh t;
  mixed_mesh(&t, 40, 1, -1); /* 64000 cells: several parts per chunk */
  int saved = omp_get_max_threads();
  for (int binary = 0; binary < 2; binary++) {
    char p1[512], p2[512], p3[512];
    path_in(p1, sizeof p1, "threads1.msh");
    path_in(p2, sizeof p2, "threads2.msh");
    path_in(p3, sizeof p3, "threads3.msh");
    omp_set_num_threads(1);
    CHECK(mx_write_msh(p1, &t.v, binary) == MX_OK);
    omp_set_num_threads(2);
    CHECK(mx_write_msh(p2, &t.v, binary) == MX_OK);
    omp_set_num_threads(3);
    CHECK(mx_write_msh(p3, &t.v, binary) == MX_OK);
    omp_set_num_threads(saved);
    CHECK(files_equal(p1, p2));
    CHECK(files_equal(p1, p3));
    check_roundtrip(&t, p2, binary);
    printf("threads %s: 1, 2 and 3 threads give identical bytes\n",
           binary ? "binary" : "ascii");
  }
  tmesh_free(&t);
}

/* ====================================================================== */
/* Failures leave nothing behind                                          */
/* ====================================================================== */

static void expect_failure(const void *ctx, const char *path, const char *dir,
                           const char *prefix) {
  const tmesh *t = ctx;
  CHECK(mx_write_msh(path, &t->v, 1) == MX_EIO);
  CHECK(mx_write_msh(path, &t->v, 0) == MX_EIO);
  CHECK(mx_write_mesh(path, &t->v, 0) == MX_EIO);
  CHECK(!exists(path));
  if (dir) CHECK(count_entries(dir, prefix) <= 0);
}

static void test_failures(void) {
  tmesh t;
  mixed_mesh(&t, 20, 0, -1); /* 8000 cells: more than the stdio buffer */
  unwritable_places(expect_failure, &t, "msh", ".msh", ".msh");
  if (have_dev_full()) {
    CHECK(mx_write_msh("/dev/full", &t.v, 1) == MX_EIO);
    CHECK(mx_write_msh("/dev/full", &t.v, 0) == MX_EIO);
    CHECK(dev_full_intact());
  }
  CHECK(count_entries(OUT_DIR, "") == 1); /* only plainfile */
  tmesh_free(&t);
}

/* ====================================================================== */

int main(void) {
  mkdir(OUT_DIR, 0755);
  remove_dir_files(OUT_DIR);
  test_reference_elements();
  test_roundtrip();
  test_threads();
  remove_dir_files(OUT_DIR);
  test_failures();
  remove_dir_files(OUT_DIR);
  rmdir(OUT_DIR);
  int fails = TEST_DONE();
  printf("%s\n", fails ? "FAILED" : "all MSH checks passed");
  return fails;
}
