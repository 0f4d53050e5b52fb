/* mixoct: Medit / Gamma Mesh Format writer, .mesh (ASCII) and .meshb
 * (binary), with the boundary triangles and quadrilaterals.
 *
 * Format (libMeshb documentation, "The libMeshb library", L. Marechal,
 * INRIA; keyword codes from enum GmfKwdCod in libmeshb7.h):
 *   - ASCII: "MeshVersionFormatted 2", "Dimension 3", then keywords, each
 *     followed by its number of lines and the lines; "End" closes the file.
 *     Vertices are "x y z ref"; elements are their 1-based vertex indices
 *     followed by a reference. Version 2 means double precision reals.
 *   - Binary: int32 1 (the endianness word, written natively), int32
 *     version, then keyword blocks: int32 keyword code, the absolute file
 *     position of the next block (int32 for versions 1-2, int64 from version
 *     3 on), int32 line count (Dimension has its int32 value instead), the
 *     lines as raw numbers (reals are float64 from version 2 on, integers
 *     int32 up to version 3), and a last block "End" with position 0.
 *     Version 2 is written, or version 3 when the file passes 2 GiB.
 *   - Codes used: Dimension 3, Vertices 4, Triangles 6, Quadrilaterals 7,
 *     Tetrahedra 8, Prisms 9, Hexahedra 10, Pyramids 49, End 54.
 *
 * Vertex order and orientation of the elements. Medit's convention is the
 * one of P.-L. George ("Generation automatique de maillages", Masson 1994,
 * p. 24, as restated in rheolef's reference-element pages): the trihedron
 * of the edges leaving vertex 0 is direct and every face seen from outside
 * is counter-clockwise:
 *   - tetrahedron: det(p1-p0, p2-p0, p3-p0) > 0 (Mmg, MMG5_orvol, reorients
 *     the others on reading);
 *   - prism: triangle 0-1-2, triangle 3-4-5 above it with 3 over 0,
 *     (01, 02, 03) direct (rheolef prism; NASA refine writes its prisms to
 *     .meshb unchanged and builds them so that 0-1-2 turns around 0-3);
 *   - pyramid: "square basis is 0-1-2-3 (oriented counter clockwise like
 *     trias) and top vertex is 4" (NASA refine, ref_export.c, which maps its
 *     UGRID pyramids to .meshb and to VTK by two permutations that differ
 *     only by a rotation of the base);
 *   - hexahedron: 0-1-2-3 bottom, 4-5-6-7 above them, (01, 03, 04) direct
 *     (libMeshb's Q1/Q2 hexahedron ordering: (0,0,0) (1,0,0) (1,1,0)
 *     (0,1,0) (0,0,1) ...).
 * The library's node orders (soa/mesh.h, whose outward face tables start
 * with 0-2-1, 0-3-2-1, 0-2-1 and 0-3-2-1: the base turns towards the rest
 * of the element) are these same orders with the same orientation, so
 * medit_order below is the identity; it is kept as a table so that the
 * correspondence stays explicit in one place.
 * Boundary faces (io/boundary_faces.h) are written oriented outward.
 *
 * References: vertices 0; an element's is its body (view.cell_body, issue
 * 11) and a boundary face's its boundary tag, the input file it lies on
 * (view.bfaces); 1 for both in a view without them. Medit references are
 * subdomain and boundary numbers (Mmg treats a face between elements of
 * different references as a boundary), so the octree level is not used.
 *
 * Every block is produced in parallel chunks by mx_afile_emit: the bytes do
 * not depend on the number of threads. ASCII reals are written with 17
 * significant digits (15 when those read back to the same double): see
 * mx_put_double in io/text_num.h. */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "base/common.h"
#include "io/atomic_file.h"
#include "io/boundary_faces.h"
#include "io/text_num.h"
#include "soa/mesh.h"
#include "io/write_mesh.h"
#include "io/cell_order.h"
#include "io/mesh_view_check.h"

enum {
  KW_DIMENSION = 3,
  KW_VERTICES = 4,
  KW_TRIANGLES = 6,
  KW_QUADRILATERALS = 7,
  KW_TETRAHEDRA = 8,
  KW_PRISMS = 9,
  KW_HEXAHEDRA = 10,
  KW_PYRAMIDS = 49,
  KW_END = 54,
};

static const int32_t VERTEX_REF = 0, ELEMENT_REF = 1, FACE_REF = 1;

/* medit_order[t][j]: the index in the library's row (soa/mesh.h) of Medit
 * vertex j of type t. */
static const int8_t medit_order[4][8] = {{0, 1, 2, 3},
                                         {0, 1, 2, 3, 4},
                                         {0, 1, 2, 3, 4, 5},
                                         {0, 1, 2, 3, 4, 5, 6, 7}};

static const char *const type_keyword_name[4] = {"Tetrahedra", "Pyramids",
                                                 "Prisms", "Hexahedra"};
static const int type_keyword_code[4] = {KW_TETRAHEDRA, KW_PYRAMIDS, KW_PRISMS,
                                         KW_HEXAHEDRA};

typedef struct {
  const mx_mesh_view *m;
  const uint32_t *cells; /* the cells of one type, in written order (cells_by_type) */
  int type;
  const uint32_t *faces; /* boundary faces of one size */
  int face_size;
  const int32_t *face_tag; /* their tags (the references), or NULL: 1 */
} medit_ctx;

/* References: a cell's body (1 without bodies), a face's tag (1 without). */
static inline int32_t cell_ref(const medit_ctx *ctx, uint32_t c) {
  const mx_mesh_view *m = ctx->m;
  if (!m->cell_body) return ELEMENT_REF;
  const int32_t b = m->cell_body[c];
  return m->body_physical && b >= 1 && b <= m->nbodies ? m->body_physical[b - 1] : b;
}

static inline int32_t face_ref(const medit_ctx *ctx, size_t i) {
  return ctx->face_tag ? ctx->face_tag[i] : FACE_REF;
}

/* ---- fill functions --------------------------------------------------------
 */

static size_t fill_vertices_ascii(const void *vctx, size_t b, size_t e,
                                  char *out) {
  const double *xyz = ((const medit_ctx *)vctx)->m->xyz;
  size_t n = 0;
  for (size_t i = b; i < e; i++) {
    for (int d = 0; d < 3; d++) {
      n += mx_put_double(out + n, xyz[3 * i + d]);
      out[n++] = ' ';
    }
    n += mx_put_i64(out + n, VERTEX_REF);
    out[n++] = '\n';
  }
  return n;
}

static size_t fill_vertices_bin(const void *vctx, size_t b, size_t e,
                                char *out) {
  const double *xyz = ((const medit_ctx *)vctx)->m->xyz;
  size_t n = 0;
  for (size_t i = b; i < e; i++) {
    memcpy(out + n, xyz + 3 * i, 24);
    memcpy(out + n + 24, &VERTEX_REF, 4);
    n += 28;
  }
  return n;
}

static size_t fill_cells_ascii(const void *vctx, size_t b, size_t e,
                               char *out) {
  const medit_ctx *ctx = vctx;
  const int t = ctx->type, nv = mx_cell_nodes[t];
  size_t n = 0;
  for (size_t i = b; i < e; i++) {
    const uint32_t *row = ctx->m->conn + 8 * (size_t)ctx->cells[i];
    for (int j = 0; j < nv; j++) {
      n += mx_put_u64(out + n, (uint64_t)row[medit_order[t][j]] + 1);
      out[n++] = ' ';
    }
    n += mx_put_i64(out + n, cell_ref(ctx, ctx->cells[i]));
    out[n++] = '\n';
  }
  return n;
}

static size_t fill_cells_bin(const void *vctx, size_t b, size_t e, char *out) {
  const medit_ctx *ctx = vctx;
  const int t = ctx->type, nv = mx_cell_nodes[t];
  size_t n = 0;
  for (size_t i = b; i < e; i++) {
    const uint32_t *row = ctx->m->conn + 8 * (size_t)ctx->cells[i];
    for (int j = 0; j < nv; j++, n += 4) {
      const int32_t v = (int32_t)(row[medit_order[t][j]] + 1);
      memcpy(out + n, &v, 4);
    }
    const int32_t ref = cell_ref(ctx, ctx->cells[i]);
    memcpy(out + n, &ref, 4);
    n += 4;
  }
  return n;
}

static size_t fill_faces_ascii(const void *vctx, size_t b, size_t e,
                               char *out) {
  const medit_ctx *ctx = vctx;
  const int k = ctx->face_size;
  size_t n = 0;
  for (size_t i = b; i < e; i++) {
    for (int j = 0; j < k; j++) {
      n += mx_put_u64(out + n, (uint64_t)ctx->faces[(size_t)k * i + j] + 1);
      out[n++] = ' ';
    }
    n += mx_put_i64(out + n, face_ref(ctx, i));
    out[n++] = '\n';
  }
  return n;
}

static size_t fill_faces_bin(const void *vctx, size_t b, size_t e, char *out) {
  const medit_ctx *ctx = vctx;
  const int k = ctx->face_size;
  size_t n = 0;
  for (size_t i = b; i < e; i++) {
    for (int j = 0; j < k; j++, n += 4) {
      const int32_t v = (int32_t)(ctx->faces[(size_t)k * i + j] + 1);
      memcpy(out + n, &v, 4);
    }
    const int32_t ref = face_ref(ctx, i);
    memcpy(out + n, &ref, 4);
    n += 4;
  }
  return n;
}

/* The cells grouped by type (Medit has a section per type), each type's in
 * the view's written order (mx_view_cell), so the files of every format
 * list the cells of a type in the same order. */
static int cells_by_type(const mx_mesh_view *m, uint32_t **cells_out, size_t first[5]) {
  const size_t n = m->ncells;
  uint32_t *cells = mx_alloc((n + 1) * sizeof *cells);
  uint8_t *wtype = m->order ? mx_alloc(n + 1) : NULL;
  int st = cells && (wtype || !m->order) ? MX_OK : MX_ENOMEM;
  if (!st && m->order) {
#pragma omp parallel for schedule(static)
    for (size_t k = 0; k < n; k++) wtype[k] = m->type[m->order[k]];
  }
  if (!st) st = mx_cells_by_type(m->order ? wtype : m->type, n, cells, first);
  if (!st && m->order) {
#pragma omp parallel for schedule(static)
    for (size_t i = 0; i < n; i++) cells[i] = m->order[cells[i]];
  }
  mx_free(wtype);
  if (st) {
    mx_free(cells);
    cells = NULL;
  }
  *cells_out = cells;
  return st;
}

/* ---- file layout ------------------------------------------------------------
 */

typedef struct {
  const mx_mesh_view *m;
  const mx_boundary_faces *bf;
  const uint32_t *cells;
  size_t first[4], count[4];
} medit_data;

/* The keywords written, in order, with their line counts and binary line
 * sizes (Vertices, the four volume types, Triangles, Quadrilaterals; empty
 * ones other than Vertices are skipped). */
typedef struct {
  int code;
  const char *name;
  size_t lines;
  size_t line_bytes;
} section;

static int list_sections(const medit_data *d, section s[7]) {
  int ns = 0;
  s[ns++] = (section){KW_VERTICES, "Vertices", d->m->nnodes, 3 * 8 + 4};
  for (int t = 0; t < 4; t++) {
    if (d->count[t] == 0) continue;
    s[ns++] = (section){type_keyword_code[t], type_keyword_name[t], d->count[t],
                        4 * (size_t)(mx_cell_nodes[t] + 1)};
  }
  if (d->bf->ntri)
    s[ns++] = (section){KW_TRIANGLES, "Triangles", d->bf->ntri, 4 * 4};
  if (d->bf->nquad)
    s[ns++] =
        (section){KW_QUADRILATERALS, "Quadrilaterals", d->bf->nquad, 5 * 4};
  return ns;
}

static int emit_section(mx_afile *f, const medit_data *d, const section *s,
                        int binary) {
  medit_ctx ctx = {d->m, NULL, 0, NULL, 0, NULL};
  switch (s->code) {
    case KW_VERTICES:
      return binary ? mx_afile_emit(f, s->lines, 28, fill_vertices_bin, &ctx)
                    : mx_afile_emit(f, s->lines, 4 * MX_NUM_MAX,
                                    fill_vertices_ascii, &ctx);
    case KW_TRIANGLES:
    case KW_QUADRILATERALS:
      ctx.face_size = s->code == KW_TRIANGLES ? 3 : 4;
      ctx.faces = s->code == KW_TRIANGLES ? d->bf->tri : d->bf->quad;
      ctx.face_tag = s->code == KW_TRIANGLES ? d->bf->tri_tag : d->bf->quad_tag;
      return binary
                 ? mx_afile_emit(f, s->lines, s->line_bytes, fill_faces_bin,
                                 &ctx)
                 : mx_afile_emit(f, s->lines, 5 * 12, fill_faces_ascii, &ctx);
    default:
      for (int t = 0; t < 4; t++) {
        if (type_keyword_code[t] != s->code) continue;
        ctx.type = t;
        ctx.cells = d->cells + d->first[t];
        return binary
                   ? mx_afile_emit(f, s->lines, s->line_bytes, fill_cells_bin,
                                   &ctx)
                   : mx_afile_emit(f, s->lines, 9 * 12, fill_cells_ascii, &ctx);
      }
      return MX_EINTERNAL;
  }
}

static int write_ascii(mx_afile *f, const medit_data *d) {
  section s[7];
  const int ns = list_sections(d, s);
  MX_CHECK(mx_afile_printf(f, "MeshVersionFormatted 2\n\nDimension 3\n"));
  for (int i = 0; i < ns; i++) {
    MX_CHECK(mx_afile_printf(f, "\n%s\n%zu\n", s[i].name, s[i].lines));
    MX_CHECK(emit_section(f, d, &s[i], 0));
  }
  return mx_afile_printf(f, "\nEnd\n");
}

static int put_header_int(mx_afile *f, int64_t v, int bytes) {
  if (bytes == 8) return mx_afile_write(f, &v, 8);
  const int32_t w = (int32_t)v;
  return mx_afile_write(f, &w, 4);
}

static int write_binary(mx_afile *f, const medit_data *d, const char *path) {
  section s[7];
  const int ns = list_sections(d, s);
  /* total size with 4-byte positions decides the version */
  uint64_t total = 8 + 12 + 8;
  for (int i = 0; i < ns; i++)
    total += 12 + (uint64_t)s[i].lines * s[i].line_bytes;
  const int version = total > (uint64_t)INT32_MAX ? 3 : 2;
  const int pos_bytes = version >= 3 ? 8 : 4;
  for (int i = 0; i < ns; i++) {
    if (s[i].lines > (size_t)INT32_MAX) {
      mx_error(path, 0, "%zu %s are too many for a Medit file (32-bit counts)",
               s[i].lines, s[i].name);
      return MX_EINPUT;
    }
  }
  const int32_t head[2] = {1, version};
  MX_CHECK(mx_afile_write(f, head, sizeof head));
  uint64_t pos = 8;
  const int32_t dim_code = KW_DIMENSION, dim = 3;
  pos += 4 + (uint64_t)pos_bytes + 4;
  MX_CHECK(mx_afile_write(f, &dim_code, 4));
  MX_CHECK(put_header_int(f, (int64_t)pos, pos_bytes));
  MX_CHECK(mx_afile_write(f, &dim, 4));
  for (int i = 0; i < ns; i++) {
    const int32_t code = s[i].code, lines = (int32_t)s[i].lines;
    pos += 4 + (uint64_t)pos_bytes + 4 + (uint64_t)s[i].lines * s[i].line_bytes;
    MX_CHECK(mx_afile_write(f, &code, 4));
    MX_CHECK(put_header_int(f, (int64_t)pos, pos_bytes));
    MX_CHECK(mx_afile_write(f, &lines, 4));
    MX_CHECK(emit_section(f, d, &s[i], 1));
  }
  const int32_t end_code = KW_END;
  MX_CHECK(mx_afile_write(f, &end_code, 4));
  return put_header_int(f, 0, pos_bytes);
}

int mx_write_medit(const char *path, const mx_mesh_view *m, int binary) {
  MX_CHECK(mx_mesh_view_check(path, m));
  if (m->nnodes >= (size_t)INT32_MAX) {
    mx_error(path, 0,
             "%zu nodes are too many for a Medit file (32-bit indices)",
             m->nnodes);
    return MX_EINPUT;
  }
  medit_data d;
  memset(&d, 0, sizeof d);
  d.m = m;
  mx_boundary_faces bf;
  memset(&bf, 0, sizeof bf);
  int st = m->bfaces ? MX_OK : mx_boundary_faces_extract(m, &bf);
  if (st != MX_OK) {
    mx_error(path, 0, "cannot extract the boundary faces");
    return st;
  }
  d.bf = m->bfaces ? m->bfaces : &bf;
  uint32_t *cells = NULL;
  size_t first[5] = {0, 0, 0, 0, 0};
  st = cells_by_type(m, &cells, first);
  for (int t = 0; t < 4; t++) {
    d.first[t] = first[t];
    d.count[t] = first[t + 1] - first[t];
  }
  d.cells = cells;
  mx_afile f;
  if (st == MX_OK)
    st = mx_afile_open(&f, path);
  else
    mx_error(path, 0, "out of memory");
  if (st == MX_OK) {
    st = mx_afile_finish(&f, binary ? write_binary(&f, &d, path) : write_ascii(&f, &d));
  }
  mx_free(cells);
  mx_boundary_faces_free(&bf);
  return st;
}
