/* Writers of 2D mixed meshes (src/quad/quad.h: mx_qmesh, counter-clockwise
 * triangles and quadrilaterals), chosen by the file's extension:
 *
 *   .vtu     VTK XML UnstructuredGrid 1.0, little-endian raw appended data
 *            with UInt64 block headers (io/vtu_common.h, shared with
 *            io/write_vtu.c): points Float64 x y 0, cells VTK_TRIANGLE (5)
 *            / VTK_QUAD (9)
 *   .vtk     legacy VTK 3.0, binary (big-endian, as the format requires) or
 *            ASCII
 *   .msh     Gmsh MSH 4.1, binary (host byte order, "4.1 1 8") or ASCII:
 *            one surface entity (tag 1, physical 1 "domain") holding the
 *            nodes, the triangles (type 2) and quadrilaterals (type 3); one
 *            curve entity (tag 1, physical 2 "boundary") holding the
 *            boundary edges (used by one cell) as lines (type 1), oriented
 *            as in their cell (the domain on their left); $ElementData per
 *            cell field, a line carrying its cell's value
 *   .off     OFF, z = 0, one face per cell
 *   .getfem  GetFEM's mesh file (as io/write_getfem.c, 2D points):
 *            'GT_PK(2,1)' triangles, 'GT_QK(2,1)' quadrilaterals, whose
 *            reference order is the tensor one, (0,0) (1,0) (0,1) (1,1):
 *            our counter-clockwise a b c d is written a b d c
 *   .m3d     the 3D program's M3D layout (io/write_m3d.c) with letters
 *            T (triangle) and Q (quadrilateral), z = 0
 *
 * Cell fields (VTU, VTK, MSH): "type" (0 triangle, 1 quadrilateral),
 * "level" (the quadrant's), "sj" (mx_qcell_sj). Cells and nodes are written
 * in the mesh's order; MSH element tags are a cell's index + 1 (lines
 * follow), node tags index + 1. Everything large is formatted in parallel
 * chunks (mx_afile_emit): the bytes do not depend on the thread count.
 * Files appear whole or not at all (io/atomic_file.h). */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>
#include <strings.h>

#include "base/common.h"
#include "io/atomic_file.h"
#include "io/text_num.h"
#include "io/vtu_common.h"
#include "quad/quad.h"
#include "base/scan.h"

enum { NFIELDS = 3, OFFSET_BLOCK = 4096, PAR_MIN = 16384 }; /* fewer: one thread */
static const char *const field_name[NFIELDS] = {"type", "level", "sj"};

typedef struct {
  const mx_qmesh *M;
  int field;               /* the cell field being written */
  int type;                /* MSH: the cells of this block's type */
  int data;                /* MSH: $ElementData lines instead of elements */
  int binary;
  int wide;                /* VTU: Int64 indices */
  const uint64_t *qbefore; /* VTU: quads before each OFFSET_BLOCK cells */
  const uint64_t *bedge;   /* MSH: boundary edges, 4 * cell + side */
} qctx;

/* ---- the mesh ------------------------------------------------------------ */

static inline int qnv(const mx_qmesh *M, size_t c) { return M->type[c] == MX_QQUAD ? 4 : 3; }

static double qfield(const mx_qmesh *M, int field, size_t c) {
  if (field == 0) return (double)M->type[c];
  if (field == 1) return M->level ? (double)M->level[c] : 0.0;
  return mx_qcell_sj(M, c);
}

static size_t count_quads(const mx_qmesh *M) {
  size_t nq = 0;
#pragma omp parallel for reduction(+ : nq) schedule(static) if (M->ncells > 65536)
  for (size_t c = 0; c < M->ncells; c++) nq += M->type[c] == MX_QQUAD;
  return nq;
}

/* Types in range and node indices below nnodes (a writer never reads past
 * the arrays); the first bad cell is named. */
static int qmesh_consistent(const char *path, const mx_qmesh *M) {
  if ((M->nnodes && !M->xy) || (M->ncells && (!M->type || !M->conn))) {
    mx_error(path, 0, "internal error: incomplete 2D mesh");
    return MX_EINTERNAL;
  }
  const size_t bad = mx_qmesh_bad_cell(M);
  if (bad == M->ncells) return MX_OK;
  mx_error(path, 0, "internal error: cell %zu has a bad type or node index", bad);
  return MX_EINTERNAL;
}

/* ---- byte stores --------------------------------------------------------- */

/* Little-endian ones (VTU): io/vtu_common.h. */

static inline void put_be32(char *o, uint32_t v) {
#if MX_VTU_HOST_LE
  v = __builtin_bswap32(v);
#endif
  memcpy(o, &v, 4);
}
static inline void put_be64(char *o, uint64_t v) {
#if MX_VTU_HOST_LE
  v = __builtin_bswap64(v);
#endif
  memcpy(o, &v, 8);
}
static inline uint64_t dbits(double d) {
  uint64_t v;
  memcpy(&v, &d, 8);
  return v;
}

/* "x y 0" + end (ASCII), or three doubles (binary: big-endian for legacy
 * VTK, little-endian for VTU, host order for MSH). */
static size_t put_xy0(char *o, const double *p, char end) {
  size_t n = mx_put_double(o, p[0]);
  o[n++] = ' ';
  n += mx_put_double(o + n, p[1]);
  memcpy(o + n, " 0", 2);
  n += 2;
  o[n++] = end;
  return n;
}
enum { XY0_MAX = 2 * MX_DOUBLE_CHARS + 4 };

static size_t put_u64s(char *o, const uint32_t *v, int n, uint64_t add) {
  size_t k = 0;
  for (int j = 0; j < n; j++) {
    o[k++] = ' ';
    k += mx_put_u64(o + k, (uint64_t)v[j] + add);
  }
  return k;
}

/* ---- legacy VTK ---------------------------------------------------------- */

static size_t vtk_points(const void *v, size_t b, size_t e, char *o) {
  const qctx *x = v;
  size_t n = 0;
  for (size_t i = b; i < e; i++) {
    const double *p = x->M->xy + 2 * i;
    if (!x->binary) {
      n += put_xy0(o + n, p, '\n');
      continue;
    }
    put_be64(o + n, dbits(p[0]));
    put_be64(o + n + 8, dbits(p[1]));
    put_be64(o + n + 16, dbits(0.0));
    n += 24;
  }
  return n;
}

static size_t vtk_cells(const void *v, size_t b, size_t e, char *o) {
  const qctx *x = v;
  size_t n = 0;
  for (size_t c = b; c < e; c++) {
    const int nv = qnv(x->M, c);
    const uint32_t *row = x->M->conn + 4 * c;
    if (!x->binary) {
      o[n++] = (char)('0' + nv);
      n += put_u64s(o + n, row, nv, 0);
      o[n++] = '\n';
      continue;
    }
    put_be32(o + n, (uint32_t)nv);
    n += 4;
    for (int j = 0; j < nv; j++, n += 4) put_be32(o + n, row[j]);
  }
  return n;
}

static size_t vtk_types(const void *v, size_t b, size_t e, char *o) {
  const qctx *x = v;
  size_t n = 0;
  for (size_t c = b; c < e; c++) {
    const uint32_t t = x->M->type[c] == MX_QQUAD ? 9 : 5;
    if (x->binary) {
      put_be32(o + n, t);
      n += 4;
    } else {
      o[n++] = t == 9 ? '9' : '5';
      o[n++] = '\n';
    }
  }
  return n;
}

static size_t vtk_field(const void *v, size_t b, size_t e, char *o) {
  const qctx *x = v;
  size_t n = 0;
  for (size_t c = b; c < e; c++) {
    const double d = qfield(x->M, x->field, c);
    if (x->binary && x->field == 2) {
      put_be64(o + n, dbits(d));
      n += 8;
    } else if (x->binary) {
      put_be32(o + n, (uint32_t)(int32_t)d);
      n += 4;
    } else {
      n += x->field == 2 ? mx_put_double(o + n, d) : mx_put_i64(o + n, (int64_t)d);
      o[n++] = '\n';
    }
  }
  return n;
}

static int vtk_body(mx_afile *f, const mx_qmesh *M, int binary) {
  qctx x = {.M = M, .binary = binary};
  const size_t nconn = 3 * M->ncells + count_quads(M);
  MX_CHECK(mx_afile_printf(f, "# vtk DataFile Version 3.0\nmixoct 2D mesh\n%s\n"
                              "DATASET UNSTRUCTURED_GRID\nPOINTS %zu double\n",
                           binary ? "BINARY" : "ASCII", M->nnodes));
  MX_CHECK(mx_afile_emit(f, M->nnodes, XY0_MAX, vtk_points, &x));
  MX_CHECK(mx_afile_printf(f, "%sCELLS %zu %zu\n", binary ? "\n" : "", M->ncells,
                           M->ncells + nconn));
  MX_CHECK(mx_afile_emit(f, M->ncells, 2 + 4 * (MX_U64_CHARS + 1), vtk_cells, &x));
  MX_CHECK(mx_afile_printf(f, "%sCELL_TYPES %zu\n", binary ? "\n" : "", M->ncells));
  MX_CHECK(mx_afile_emit(f, M->ncells, 4, vtk_types, &x));
  MX_CHECK(mx_afile_printf(f, "%sCELL_DATA %zu\n", binary ? "\n" : "", M->ncells));
  for (x.field = 0; x.field < NFIELDS; x.field++) {
    MX_CHECK(mx_afile_printf(f, "SCALARS %s %s 1\nLOOKUP_TABLE default\n",
                             field_name[x.field], x.field == 2 ? "double" : "int"));
    MX_CHECK(mx_afile_emit(f, M->ncells, MX_NUM_MAX, vtk_field, &x));
    if (binary) MX_CHECK(mx_afile_write(f, "\n", 1));
  }
  return MX_OK;
}

/* ---- VTU ----------------------------------------------------------------- */

static size_t vtu_points(const void *v, size_t b, size_t e, char *o) {
  const double *xy = ((const qctx *)v)->M->xy;
  for (size_t i = b; i < e; i++) {
    char *p = o + 24 * (i - b);
    mx_put_le_double(p, xy[2 * i]);
    mx_put_le_double(p + 8, xy[2 * i + 1]);
    mx_put_le_double(p + 16, 0.0);
  }
  return 24 * (e - b);
}

static size_t vtu_conn(const void *v, size_t b, size_t e, char *o) {
  const qctx *x = v;
  size_t n = 0;
  for (size_t c = b; c < e; c++)
    for (int j = 0; j < qnv(x->M, c); j++) {
      if (x->wide) mx_put_le64(o + n, x->M->conn[4 * c + j]);
      else mx_put_le32(o + n, x->M->conn[4 * c + j]);
      n += x->wide ? 8 : 4;
    }
  return n;
}

/* The end of cell c's connectivity: 3 per cell plus one per quad. */
static size_t vtu_offsets(const void *v, size_t b, size_t e, char *o) {
  const qctx *x = v;
  uint64_t q = x->qbefore[b / OFFSET_BLOCK];
  for (size_t c = b / OFFSET_BLOCK * OFFSET_BLOCK; c < b; c++) q += x->M->type[c] == MX_QQUAD;
  size_t n = 0;
  for (size_t c = b; c < e; c++) {
    q += x->M->type[c] == MX_QQUAD;
    const uint64_t end = 3 * (uint64_t)(c + 1) + q;
    if (x->wide) mx_put_le64(o + n, end);
    else mx_put_le32(o + n, (uint32_t)end);
    n += x->wide ? 8 : 4;
  }
  return n;
}

static size_t vtu_types(const void *v, size_t b, size_t e, char *o) {
  const qctx *x = v;
  for (size_t c = b; c < e; c++) o[c - b] = x->M->type[c] == MX_QQUAD ? 9 : 5;
  return e - b;
}

static size_t vtu_field(const void *v, size_t b, size_t e, char *o) {
  const qctx *x = v;
  size_t n = 0;
  for (size_t c = b; c < e; c++) {
    const double d = qfield(x->M, x->field, c);
    if (x->field == 0) mx_put_le32(o + n, (uint32_t)d);
    else if (x->field == 1) o[n] = (char)(uint8_t)d;
    else mx_put_le_double(o + n, d);
    n += x->field == 0 ? 4 : x->field == 1 ? 1 : 8;
  }
  return n;
}

static const char *const vtu_ftype[NFIELDS] = {"Int32", "UInt8", "Float64"};
static const int vtu_fsize[NFIELDS] = {4, 1, 8};

static int vtu_header(mx_afile *f, const mx_qmesh *M, uint64_t nconn, int wide) {
  mx_vtu_head h = {0};
  mx_vtu_begin(&h, M->nnodes, M->ncells);
  mx_vtu_printf(&h, "      <CellData>\n");
  for (int k = 0; k < NFIELDS; k++)
    mx_vtu_array(&h, vtu_ftype[k], field_name[k], 1, (uint64_t)vtu_fsize[k] * M->ncells);
  mx_vtu_printf(&h, "      </CellData>\n");
  return mx_vtu_end(f, &h, M->nnodes, M->ncells, nconn, wide);
}

/* Quads before each block of OFFSET_BLOCK cells (the offsets' prefix). */
static uint64_t *quads_before(const mx_qmesh *M) {
  const size_t nb = M->ncells / OFFSET_BLOCK + 1;
  uint64_t *q = mx_alloc(nb * sizeof *q);
  if (!q) return NULL;
#pragma omp parallel for schedule(static) if (nb > 16)
  for (size_t k = 0; k < nb; k++) {
    const size_t lo = k * OFFSET_BLOCK, hi = lo + OFFSET_BLOCK < M->ncells ? lo + OFFSET_BLOCK
                                                                          : M->ncells;
    uint64_t s = 0;
    for (size_t c = lo; c < hi; c++) s += M->type[c] == MX_QQUAD;
    q[k] = s;
  }
  mx_scan_u64(q, nb);
  return q;
}

static int vtu_blocks(mx_afile *f, const mx_qmesh *M, uint64_t nconn, qctx *x) {
  const uint64_t nc = M->ncells, isz = x->wide ? 8 : 4;
  for (x->field = 0; x->field < NFIELDS; x->field++)
    MX_CHECK(mx_vtu_block(f, (uint64_t)vtu_fsize[x->field] * nc, M->ncells,
                          (size_t)vtu_fsize[x->field], vtu_field, x));
  MX_CHECK(mx_vtu_block(f, 24 * (uint64_t)M->nnodes, M->nnodes, 24, vtu_points, x));
  MX_CHECK(mx_vtu_block(f, isz * nconn, M->ncells, 4 * isz, vtu_conn, x));
  MX_CHECK(mx_vtu_block(f, isz * nc, M->ncells, isz, vtu_offsets, x));
  MX_CHECK(mx_vtu_block(f, nc, M->ncells, 1, vtu_types, x));
  return mx_vtu_finish(f);
}

static int vtu_body(mx_afile *f, const mx_qmesh *M) {
  const uint64_t nconn = 3 * (uint64_t)M->ncells + count_quads(M);
  qctx x = {.M = M, .wide = nconn > (uint64_t)INT32_MAX};
  MX_CHECK(vtu_header(f, M, nconn, x.wide));
  x.qbefore = quads_before(M);
  if (!x.qbefore) return MX_ENOMEM;
  const int st = vtu_blocks(f, M, nconn, &x);
  mx_free((void *)x.qbefore);
  return st;
}

/* ---- boundary edges (MSH lines) ------------------------------------------ */

/* Whether cell d has the edge {a, b} (either direction). */
static int cell_has_edge(const mx_qmesh *M, size_t d, uint32_t a, uint32_t b) {
  const uint32_t *r = M->conn + 4 * d;
  const int nv = qnv(M, d);
  for (int j = 0; j < nv; j++) {
    const uint32_t p = r[j], q = r[(j + 1) % nv];
    if ((p == a && q == b) || (p == b && q == a)) return 1;
  }
  return 0;
}

/* The cells around each node: CSR (off: nnodes + 1). The order inside a
 * node's list depends on the threads; only membership is asked of it. */
static int node_cells(const mx_qmesh *M, uint64_t **off_out, uint32_t **ids_out) {
  uint64_t *off = mx_calloc((M->nnodes + 1) * sizeof *off);
  uint64_t *pos = mx_alloc((M->nnodes + 1) * sizeof *pos);
  uint32_t *ids = mx_alloc((4 * M->ncells + 1) * sizeof *ids);
  if (!off || !pos || !ids) {
    mx_free(off), mx_free(pos), mx_free(ids);
    return MX_ENOMEM;
  }
#pragma omp parallel for schedule(static) if (M->ncells > PAR_MIN)
  for (size_t c = 0; c < M->ncells; c++)
    for (int j = 0; j < qnv(M, c); j++) {
#pragma omp atomic
      off[M->conn[4 * c + j]]++;
    }
  mx_scan_u64(off, M->nnodes + 1);
  memcpy(pos, off, (M->nnodes + 1) * sizeof *pos);
#pragma omp parallel for schedule(static) if (M->ncells > PAR_MIN)
  for (size_t c = 0; c < M->ncells; c++)
    for (int j = 0; j < qnv(M, c); j++) {
      uint64_t k;
#pragma omp atomic capture
      k = pos[M->conn[4 * c + j]]++;
      ids[k] = (uint32_t)c;
    }
  mx_free(pos);
  *off_out = off;
  *ids_out = ids;
  return MX_OK;
}

/* Side s of cell c is a boundary edge: no other cell around its first node
 * has it. */
static int side_alone(const mx_qmesh *M, const uint64_t *off, const uint32_t *ids, size_t c,
                      int s) {
  const int nv = qnv(M, c);
  const uint32_t a = M->conn[4 * c + s], b = M->conn[4 * c + (s + 1) % nv];
  for (uint64_t k = off[a]; k < off[a + 1]; k++)
    if (ids[k] != c && cell_has_edge(M, ids[k], a, b)) return 0;
  return 1;
}

/* The boundary edges as 4 * cell + side, in cell then side order. */
static int boundary_edges(const mx_qmesh *M, uint64_t **out, size_t *nb) {
  uint64_t *off, *cnt = mx_calloc((M->ncells + 1) * sizeof *cnt);
  uint32_t *ids;
  if (!cnt) return MX_ENOMEM;
  int st = node_cells(M, &off, &ids);
  if (st) {
    mx_free(cnt);
    return st;
  }
  uint8_t *mask = mx_alloc(M->ncells + 1);
  if (!mask) st = MX_ENOMEM;
  if (!st) {
#pragma omp parallel for schedule(static) if (M->ncells > PAR_MIN)
    for (size_t c = 0; c < M->ncells; c++) {
      uint8_t m = 0;
      for (int s = 0; s < qnv(M, c); s++) m |= (uint8_t)(side_alone(M, off, ids, c, s) << s);
      mask[c] = m;
      cnt[c] = (uint64_t)__builtin_popcount(m);
    }
    *nb = (size_t)mx_scan_u64(cnt, M->ncells);
    *out = mx_alloc((*nb + 1) * sizeof **out);
    if (!*out) st = MX_ENOMEM;
  }
  if (!st) {
#pragma omp parallel for schedule(static) if (M->ncells > PAR_MIN)
    for (size_t c = 0; c < M->ncells; c++) {
      uint64_t k = cnt[c];
      for (int s = 0; s < 4; s++)
        if (mask[c] >> s & 1) (*out)[k++] = 4 * (uint64_t)c + (uint64_t)s;
    }
  }
  mx_free(mask), mx_free(cnt), mx_free(off), mx_free(ids);
  return st;
}

/* ---- MSH 4.1 ------------------------------------------------------------- */

enum { MSH_SURF = 1, MSH_CURVE = 1, PHYS_DOMAIN = 1, PHYS_BOUNDARY = 2 };

static size_t msh_node_tags(const void *v, size_t b, size_t e, char *o) {
  const qctx *x = v;
  size_t n = 0;
  for (size_t i = b; i < e; i++) {
    if (x->binary) {
      const uint64_t t = i + 1;
      memcpy(o + n, &t, 8);
      n += 8;
    } else {
      n += mx_put_u64(o + n, i + 1);
      o[n++] = '\n';
    }
  }
  return n;
}

static size_t msh_coords(const void *v, size_t b, size_t e, char *o) {
  const qctx *x = v;
  size_t n = 0;
  for (size_t i = b; i < e; i++) {
    const double *p = x->M->xy + 2 * i, z = 0.0;
    if (!x->binary) {
      n += put_xy0(o + n, p, '\n');
      continue;
    }
    memcpy(o + n, p, 16);
    memcpy(o + n + 16, &z, 8);
    n += 24;
  }
  return n;
}

/* One element line (or its $ElementData line): tag, then nodes (or the
 * value of cell c's field). */
static size_t msh_item(const qctx *x, uint64_t tag, size_t c, const uint32_t *nodes, int nv,
                       char *o) {
  size_t n = 0;
  if (x->data) {
    const double d = qfield(x->M, x->field, c);
    if (x->binary) {
      const int32_t t = (int32_t)tag;
      memcpy(o, &t, 4);
      memcpy(o + 4, &d, 8);
      return 12;
    }
    n = mx_put_u64(o, tag);
    o[n++] = ' ';
    n += x->field == 2 ? mx_put_double(o + n, d) : mx_put_i64(o + n, (int64_t)d);
    o[n++] = '\n';
    return n;
  }
  if (x->binary) {
    memcpy(o, &tag, 8);
    for (int j = 0; j < nv; j++) {
      const uint64_t t = (uint64_t)nodes[j] + 1;
      memcpy(o + 8 + 8 * j, &t, 8);
    }
    return 8 * (size_t)(nv + 1);
  }
  n = mx_put_u64(o, tag);
  n += put_u64s(o + n, nodes, nv, 1);
  o[n++] = '\n';
  return n;
}

/* The cells of block type x->type, scanning every cell (others skipped). */
static size_t msh_cells(const void *v, size_t b, size_t e, char *o) {
  const qctx *x = v;
  size_t n = 0;
  for (size_t c = b; c < e; c++)
    if (x->M->type[c] == x->type)
      n += msh_item(x, c + 1, c, x->M->conn + 4 * c, qnv(x->M, c), o + n);
  return n;
}

static size_t msh_lines(const void *v, size_t b, size_t e, char *o) {
  const qctx *x = v;
  size_t n = 0;
  for (size_t i = b; i < e; i++) {
    const size_t c = (size_t)(x->bedge[i] >> 2);
    const int s = (int)(x->bedge[i] & 3), nv = qnv(x->M, c);
    const uint32_t ab[2] = {x->M->conn[4 * c + s], x->M->conn[4 * c + (s + 1) % nv]};
    n += msh_item(x, x->M->ncells + i + 1, c, ab, 2, o + n);
  }
  return n;
}

static int msh_bin_int(mx_afile *f, int32_t v) { return mx_afile_write(f, &v, 4); }
static int msh_bin_size(mx_afile *f, uint64_t v) { return mx_afile_write(f, &v, 8); }

static void bbox(const mx_qmesh *M, double box[6]) {
  double x0 = INFINITY, y0 = INFINITY, x1 = -INFINITY, y1 = -INFINITY;
#pragma omp parallel for reduction(min : x0, y0) reduction(max : x1, y1) schedule(static) \
    if (M->nnodes > 65536)
  for (size_t i = 0; i < M->nnodes; i++) {
    x0 = mx_min(x0, M->xy[2 * i]), x1 = mx_max(x1, M->xy[2 * i]);
    y0 = mx_min(y0, M->xy[2 * i + 1]), y1 = mx_max(y1, M->xy[2 * i + 1]);
  }
  if (M->nnodes == 0) x0 = y0 = x1 = y1 = 0.0;
  const double b[6] = {x0, y0, 0.0, x1, y1, 0.0};
  memcpy(box, b, sizeof b);
}

/* One entity: tag, box, one physical tag, no bounding entities. */
static int msh_entity(mx_afile *f, const double box[6], int phys, int binary) {
  if (binary) {
    MX_CHECK(msh_bin_int(f, 1));
    MX_CHECK(mx_afile_write(f, box, 6 * sizeof *box));
    MX_CHECK(msh_bin_size(f, 1));
    MX_CHECK(msh_bin_int(f, phys));
    return msh_bin_size(f, 0);
  }
  char line[6 * (MX_DOUBLE_CHARS + 1) + 32];
  size_t n = 1;
  line[0] = '1';
  for (int k = 0; k < 6; k++) {
    line[n++] = ' ';
    n += mx_put_double(line + n, box[k]);
  }
  n += (size_t)snprintf(line + n, sizeof line - n, " 1 %d 0\n", phys);
  return mx_afile_write(f, line, n);
}

static int msh_head(mx_afile *f, const mx_qmesh *M, int binary) {
  MX_CHECK(mx_afile_printf(f, "$MeshFormat\n4.1 %d 8\n", binary));
  if (binary) {
    MX_CHECK(msh_bin_int(f, 1));
    MX_CHECK(mx_afile_write(f, "\n", 1));
  }
  MX_CHECK(mx_afile_printf(f, "$EndMeshFormat\n$PhysicalNames\n2\n2 %d \"domain\"\n"
                              "1 %d \"boundary\"\n$EndPhysicalNames\n$Entities\n",
                           PHYS_DOMAIN, PHYS_BOUNDARY));
  double box[6];
  bbox(M, box);
  if (binary) {
    const uint64_t counts[4] = {0, 1, 1, 0};
    MX_CHECK(mx_afile_write(f, counts, sizeof counts));
  } else {
    MX_CHECK(mx_afile_printf(f, "0 1 1 0\n"));
  }
  MX_CHECK(msh_entity(f, box, PHYS_BOUNDARY, binary)); /* the curve (MSH_CURVE) */
  MX_CHECK(msh_entity(f, box, PHYS_DOMAIN, binary));   /* the surface (MSH_SURF) */
  if (binary) MX_CHECK(mx_afile_write(f, "\n", 1));
  return mx_afile_printf(f, "$EndEntities\n");
}

/* Four numbers: as text on a line, or as size_t. */
static int msh_four(mx_afile *f, const uint64_t v[4], int binary) {
  if (binary) return mx_afile_write(f, v, 4 * sizeof *v);
  return mx_afile_printf(f, "%llu %llu %llu %llu\n", (unsigned long long)v[0],
                         (unsigned long long)v[1], (unsigned long long)v[2],
                         (unsigned long long)v[3]);
}

static int msh_block_head(mx_afile *f, int dim, int tag, int type, size_t n, int binary) {
  if (!binary) return mx_afile_printf(f, "%d %d %d %zu\n", dim, tag, type, n);
  MX_CHECK(msh_bin_int(f, dim));
  MX_CHECK(msh_bin_int(f, tag));
  MX_CHECK(msh_bin_int(f, type));
  return msh_bin_size(f, n);
}

static int msh_nodes(mx_afile *f, const mx_qmesh *M, qctx *x) {
  const uint64_t nn = M->nnodes, head[4] = {nn > 0, nn, nn > 0, nn};
  MX_CHECK(mx_afile_printf(f, "$Nodes\n"));
  MX_CHECK(msh_four(f, head, x->binary));
  if (nn) {
    MX_CHECK(msh_block_head(f, 2, MSH_SURF, 0, nn, x->binary));
    MX_CHECK(mx_afile_emit(f, nn, MX_U64_CHARS + 1, msh_node_tags, x));
    MX_CHECK(mx_afile_emit(f, nn, XY0_MAX, msh_coords, x));
  }
  if (x->binary) MX_CHECK(mx_afile_write(f, "\n", 1));
  return mx_afile_printf(f, "$EndNodes\n");
}

/* The blocks (triangles, quadrilaterals, lines), as elements or as one
 * field's data lines (x->data). */
static int msh_blocks(mx_afile *f, const size_t count[3], size_t nb, qctx *x) {
  const size_t line = MX_U64_CHARS + MX_DOUBLE_CHARS + 2 > 5 * (MX_U64_CHARS + 1)
                          ? MX_U64_CHARS + MX_DOUBLE_CHARS + 2
                          : 5 * (MX_U64_CHARS + 1);
  for (int t = MX_QTRI; t <= MX_QQUAD; t++) {
    if (!count[t]) continue;
    if (!x->data) MX_CHECK(msh_block_head(f, 2, MSH_SURF, t == MX_QTRI ? 2 : 3, count[t],
                                          x->binary));
    x->type = t;
    MX_CHECK(mx_afile_emit(f, x->M->ncells, line, msh_cells, x));
  }
  if (!nb) return MX_OK;
  if (!x->data) MX_CHECK(msh_block_head(f, 1, MSH_CURVE, 1, nb, x->binary));
  return mx_afile_emit(f, nb, line, msh_lines, x);
}

static int msh_elements(mx_afile *f, const mx_qmesh *M, size_t nb, qctx *x) {
  const size_t nq = count_quads(M), count[3] = {M->ncells - nq, nq, nb};
  const uint64_t ne = M->ncells + nb;
  const uint64_t head[4] = {(uint64_t)(count[0] > 0) + (count[1] > 0) + (nb > 0), ne, ne > 0, ne};
  MX_CHECK(mx_afile_printf(f, "$Elements\n"));
  MX_CHECK(msh_four(f, head, x->binary));
  x->data = 0;
  MX_CHECK(msh_blocks(f, count, nb, x));
  if (x->binary) MX_CHECK(mx_afile_write(f, "\n", 1));
  MX_CHECK(mx_afile_printf(f, "$EndElements\n"));
  /* one $ElementData per field, over every element in file order */
  x->data = 1;
  for (x->field = 0; x->field < NFIELDS; x->field++) {
    MX_CHECK(mx_afile_printf(f, "$ElementData\n1\n\"%s\"\n1\n0\n3\n0\n1\n%llu\n",
                             field_name[x->field], (unsigned long long)ne));
    MX_CHECK(msh_blocks(f, count, nb, x));
    if (x->binary) MX_CHECK(mx_afile_write(f, "\n", 1));
    MX_CHECK(mx_afile_printf(f, "$EndElementData\n"));
  }
  return MX_OK;
}

static int msh_body(mx_afile *f, const mx_qmesh *M, int binary) {
  uint64_t *bedge = NULL;
  size_t nb = 0;
  MX_CHECK(boundary_edges(M, &bedge, &nb));
  qctx x = {.M = M, .binary = binary, .bedge = bedge};
  int st = msh_head(f, M, binary);
  if (!st) st = msh_nodes(f, M, &x);
  if (!st) st = msh_elements(f, M, nb, &x);
  mx_free(bedge);
  return st;
}

/* ---- OFF, GetFEM, M3D ---------------------------------------------------- */

static size_t off_points(const void *v, size_t b, size_t e, char *o) {
  const qctx *x = v;
  size_t n = 0;
  for (size_t i = b; i < e; i++) n += put_xy0(o + n, x->M->xy + 2 * i, '\n');
  return n;
}

static size_t off_faces(const void *v, size_t b, size_t e, char *o) {
  const qctx *x = v;
  size_t n = 0;
  for (size_t c = b; c < e; c++) {
    const int nv = qnv(x->M, c);
    o[n++] = (char)('0' + nv);
    n += put_u64s(o + n, x->M->conn + 4 * c, nv, 0);
    o[n++] = '\n';
  }
  return n;
}

static int off_body(mx_afile *f, const mx_qmesh *M) {
  qctx x = {.M = M};
  MX_CHECK(mx_afile_printf(f, "OFF\n%zu %zu 0\n", M->nnodes, M->ncells));
  MX_CHECK(mx_afile_emit(f, M->nnodes, XY0_MAX, off_points, &x));
  return mx_afile_emit(f, M->ncells, 2 + 4 * (MX_U64_CHARS + 1), off_faces, &x);
}

static size_t getfem_points(const void *v, size_t b, size_t e, char *o) {
  const qctx *x = v;
  size_t n = 0;
  for (size_t i = b; i < e; i++) {
    memcpy(o + n, "  POINT  ", 9);
    n += 9;
    n += mx_put_u64(o + n, i);
    for (int d = 0; d < 2; d++) {
      memcpy(o + n, "  ", 2);
      n += 2;
      n += mx_put_double(o + n, x->M->xy[2 * i + d]);
    }
    o[n++] = '\n';
  }
  return n;
}

static size_t getfem_convexes(const void *v, size_t b, size_t e, char *o) {
  const qctx *x = v;
  static const int tensor[4] = {0, 1, 3, 2}; /* GT_QK's node j is our node tensor[j] */
  size_t n = 0;
  for (size_t c = b; c < e; c++) {
    const uint32_t *r = x->M->conn + 4 * c;
    const int quad = x->M->type[c] == MX_QQUAD;
    memcpy(o + n, "  CONVEX ", 9);
    n += 9;
    n += mx_put_u64(o + n, c);
    const char *gt = quad ? "    'GT_QK(2,1)'     " : "    'GT_PK(2,1)'     ";
    memcpy(o + n, gt, 21);
    n += 21;
    for (int j = 0; j < (quad ? 4 : 3); j++) {
      o[n++] = ' ';
      n += mx_put_u64(o + n, r[quad ? tensor[j] : j]);
    }
    o[n++] = '\n';
  }
  return n;
}

static int getfem_body(mx_afile *f, const mx_qmesh *M) {
  qctx x = {.M = M};
  MX_CHECK(mx_afile_printf(f, "%% GETFEM MESH FILE\n%% GETFEM VERSION 5.4\n"
                              "%% mixoct: %zu points, %zu convexes\n\nBEGIN POINTS LIST\n\n",
                           M->nnodes, M->ncells));
  MX_CHECK(mx_afile_emit(f, M->nnodes, 10 + MX_U64_CHARS + 2 * (2 + MX_DOUBLE_CHARS), getfem_points,
                         &x));
  MX_CHECK(mx_afile_printf(f, "\nEND POINTS LIST\n\n\n\nBEGIN MESH STRUCTURE DESCRIPTION\n\n"));
  MX_CHECK(mx_afile_emit(f, M->ncells, 32 + 5 * (MX_U64_CHARS + 1), getfem_convexes, &x));
  return mx_afile_printf(f, "\nEND MESH STRUCTURE DESCRIPTION\n");
}

enum { SCI_MAX = 24 };
static const char m3d_tail[] = " 1000.0 0.45 1.0\n";

static size_t m3d_nodes(const void *v, size_t b, size_t e, char *o) {
  const qctx *x = v;
  size_t n = 0;
  for (size_t i = b; i < e; i++) {
    o[n++] = '1';
    for (int d = 0; d < 3; d++) {
      o[n++] = ' ';
      n += mx_put_e8(o + n, d < 2 ? x->M->xy[2 * i + d] : 0.0);
    }
    o[n++] = '\n';
  }
  return n;
}

static size_t m3d_cells(const void *v, size_t b, size_t e, char *o) {
  const qctx *x = v;
  size_t n = 0;
  for (size_t c = b; c < e; c++) {
    const int nv = qnv(x->M, c);
    o[n++] = nv == 4 ? 'Q' : 'T';
    n += put_u64s(o + n, x->M->conn + 4 * c, nv, 0);
    memcpy(o + n, m3d_tail, sizeof m3d_tail - 1);
    n += sizeof m3d_tail - 1;
  }
  return n;
}

static int m3d_body(mx_afile *f, const mx_qmesh *M) {
  qctx x = {.M = M};
  MX_CHECK(mx_afile_printf(f, "[Nodes, ARRAY1<STRING>]\n%zu\n\n", M->nnodes));
  MX_CHECK(mx_afile_emit(f, M->nnodes, 3 + 3 * (SCI_MAX + 1), m3d_nodes, &x));
  MX_CHECK(mx_afile_printf(f, "\n[Elements, ARRAY1<STRING>]\n%zu\n\n", M->ncells));
  return mx_afile_emit(f, M->ncells, 1 + 4 * (MX_U64_CHARS + 1) + sizeof m3d_tail, m3d_cells,
                       &x);
}

/* ---- by extension -------------------------------------------------------- */

enum { F_VTU, F_VTK, F_MSH, F_OFF, F_GETFEM, F_M3D, F_NONE };
static const char *const qext[F_NONE] = {".vtu", ".vtk", ".msh", ".off", ".getfem", ".m3d"};

static int qformat(const char *path) {
  const char *slash = strrchr(path, '/'), *base = slash ? slash + 1 : path;
  const char *dot = strrchr(base, '.');
  if (!dot || dot == base) return F_NONE;
  for (int k = 0; k < F_NONE; k++)
    if (strcasecmp(dot, qext[k]) == 0) return k;
  return F_NONE;
}

int mx_qmesh_format_known(const char *path) { return qformat(path) != F_NONE; }

static int write_format(mx_afile *f, const mx_qmesh *M, int fmt, int ascii) {
  switch (fmt) {
    case F_VTU: return vtu_body(f, M);
    case F_VTK: return vtk_body(f, M, !ascii);
    case F_MSH: return msh_body(f, M, !ascii);
    case F_OFF: return off_body(f, M);
    case F_GETFEM: return getfem_body(f, M);
    default: return m3d_body(f, M);
  }
}

int mx_write_qmesh(const char *path, const mx_qmesh *M, int ascii) {
  const int fmt = qformat(path);
  if (fmt == F_NONE) {
    mx_error(path, 0, "unknown 2D output format (use .vtu, .vtk, .msh, .off, .getfem or .m3d)");
    return MX_EINPUT;
  }
  MX_CHECK(qmesh_consistent(path, M));
  mx_afile f;
  MX_CHECK(mx_afile_open(&f, path));
  return mx_afile_finish(&f, write_format(&f, M, fmt, ascii));
}
