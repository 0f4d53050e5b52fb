/* mixoct: the published mixed-element mesher's M3D and MVM files
 * (`mesher_roi -m` and `mesher_roi -i`), in the layouts that program
 * writes (REFERENCE.md, "Published output layouts (3D program), as it
 * writes them").
 *
 * M3D (NAME.m3d):
 *
 *   [Nodes, ARRAY1<STRING>]
 *   N
 *   <blank line>
 *   1 x y z                          (N lines)
 *   <blank line>
 *   [Elements, ARRAY1<STRING>]
 *   M
 *   <blank line>
 *   L i0 i1 ... 1000.0 0.45 1.0      (M lines)
 *
 * MVM (NAME.mvm):
 *
 *   MIXED
 *   N M
 *   <blank line>
 *   x y z                            (N lines)
 *   L i0 i1 ...                      (M lines)
 *
 * L names the element's type: T tetrahedron (4 nodes), P pyramid (5),
 * R prism (6), H hexahedron (8). The trailing "1000.0 0.45 1.0" of an M3D
 * element line is the same on every line. Indices are 0-based: the node of
 * the k-th node line is node k. Reals are printed as "%+1.8E" (a sign, 9
 * significant digits, "E" and a signed exponent of at least two digits;
 * the decimal point is '.' whatever the locale).
 *
 * Node order inside an element is the published program's: tetrahedron,
 * pyramid and hexahedron as VTK orders them, the prism as Gmsh orders it.
 * That is mixoct's own order (src/soa/mesh.h), so rows are written as they
 * are stored. The k-th element line is cell mx_view_cell(m, k). Cell and
 * point fields are not written: the formats have no place for them.
 *
 * Nodes and elements are produced in chunks filled in parallel by
 * mx_afile_emit, so a file is the same byte for byte whatever the number of
 * threads.
 * A 2D view (soa/mesh.h: dim 2) is written by the section "a 2D view"
 * below. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "base/common.h"
#include "io/atomic_file.h"
#include "io/plane_mesh.h"
#include "io/text_num.h"
#include "soa/mesh.h"
#include "io/write_mesh.h"
#include "io/mesh_view_check.h"

/* The letter of each type, MX_TET .. MX_HEX. */
static const char cell_letter[4] = {'T', 'P', 'R', 'H'};

/* The numbers closing every M3D element line. */
static const char m3d_tail[] = " 1000.0 0.45 1.0";

enum {
  SCI_CHARS = 16, /* "+d.ddddddddE+ddd" */
  /* "1 ", three reals after a blank but the first, '\n' */
  M3D_NODE_MAX = 2 + 3 * (SCI_CHARS + 1) + 1,
  MVM_NODE_MAX = 3 * (SCI_CHARS + 1) + 1,
  /* the letter, 8 indices after a blank each, the tail, '\n' */
  MVM_CELL_MAX = 1 + 8 * (1 + MX_U64_CHARS) + 1,
  M3D_CELL_MAX = MVM_CELL_MAX + (int)sizeof m3d_tail,
};

/* ---- text ---------------------------------------------------------------- */


static size_t put_xyz(char *out, const double *p) {
  size_t n = mx_put_e8(out, p[0]);
  for (int d = 1; d < 3; d++) {
    out[n++] = ' ';
    n += mx_put_e8(out + n, p[d]);
  }
  out[n++] = '\n';
  return n;
}

/* "L i0 i1 ..." of the k-th cell written, without a line end. */
static size_t put_cell(char *out, const mx_mesh_view *m, size_t k) {
  const size_t c = mx_view_cell(m, k);
  const int t = m->type[c];
  const uint32_t *row = m->conn + 8 * c;
  size_t n = 0;
  out[n++] = cell_letter[t];
  for (int j = 0; j < mx_cell_nodes[t]; j++) {
    out[n++] = ' ';
    n += mx_put_u64(out + n, row[j]);
  }
  return n;
}

/* ---- fill functions (mx_afile_emit) --------------------------------------- */

static size_t fill_m3d_nodes(const void *vctx, size_t b, size_t e, char *out) {
  const mx_mesh_view *m = vctx;
  size_t n = 0;
  for (size_t i = b; i < e; i++) {
    out[n++] = '1';
    out[n++] = ' ';
    n += put_xyz(out + n, m->xyz + 3 * i);
  }
  return n;
}

static size_t fill_m3d_cells(const void *vctx, size_t b, size_t e, char *out) {
  const mx_mesh_view *m = vctx;
  size_t n = 0;
  for (size_t k = b; k < e; k++) {
    n += put_cell(out + n, m, k);
    memcpy(out + n, m3d_tail, sizeof m3d_tail - 1);
    n += sizeof m3d_tail - 1;
    out[n++] = '\n';
  }
  return n;
}

static size_t fill_mvm_nodes(const void *vctx, size_t b, size_t e, char *out) {
  const mx_mesh_view *m = vctx;
  size_t n = 0;
  for (size_t i = b; i < e; i++) n += put_xyz(out + n, m->xyz + 3 * i);
  return n;
}

static size_t fill_mvm_cells(const void *vctx, size_t b, size_t e, char *out) {
  const mx_mesh_view *m = vctx;
  size_t n = 0;
  for (size_t k = b; k < e; k++) {
    n += put_cell(out + n, m, k);
    out[n++] = '\n';
  }
  return n;
}

/* ---- files ----------------------------------------------------------------- */

static int write_m3d_body(mx_afile *f, const mx_mesh_view *m) {
  MX_CHECK(mx_afile_printf(f, "[Nodes, ARRAY1<STRING>]\n%zu\n\n", m->nnodes));
  MX_CHECK(mx_afile_emit(f, m->nnodes, M3D_NODE_MAX, fill_m3d_nodes, m));
  MX_CHECK(mx_afile_printf(f, "\n[Elements, ARRAY1<STRING>]\n%zu\n\n",
                           m->ncells));
  return mx_afile_emit(f, m->ncells, M3D_CELL_MAX, fill_m3d_cells, m);
}

static int write_mvm_body(mx_afile *f, const mx_mesh_view *m) {
  MX_CHECK(mx_afile_printf(f, "MIXED\n%zu %zu\n\n", m->nnodes, m->ncells));
  MX_CHECK(mx_afile_emit(f, m->nnodes, MVM_NODE_MAX, fill_mvm_nodes, m));
  return mx_afile_emit(f, m->ncells, MVM_CELL_MAX, fill_mvm_cells, m);
}

/* ---- a 2D view (soa/mesh.h: dim 2) ---------------------------------------
 *
 * The layout above with letters T (triangle) and Q (quadrilateral), z = 0. */

typedef struct {
  const mx_mesh_view *M;
} plane_ctx;

enum { PLANE_SCI_MAX = 24 };
static const char plane_tail[] = " 1000.0 0.45 1.0\n";

static size_t fill_plane_nodes(const void *v, size_t b, size_t e, char *o) {
  const plane_ctx *x = v;
  size_t n = 0;
  for (size_t i = b; i < e; i++) {
    o[n++] = '1';
    for (int d = 0; d < 3; d++) {
      o[n++] = ' ';
      n += mx_put_e8(o + n, d < 2 ? x->M->xyz[2 * i + d] : 0.0);
    }
    o[n++] = '\n';
  }
  return n;
}

static size_t fill_plane_cells(const void *v, size_t b, size_t e, char *o) {
  const plane_ctx *x = v;
  size_t n = 0;
  for (size_t c = b; c < e; c++) {
    const int nv = mx_view_nv2(x->M, c);
    o[n++] = nv == 4 ? 'Q' : 'T';
    n += mx_plane_put_ids(o + n, x->M->conn + 4 * c, nv, 0);
    memcpy(o + n, plane_tail, sizeof plane_tail - 1);
    n += sizeof plane_tail - 1;
  }
  return n;
}

static int write_plane_body(mx_afile *f, const mx_mesh_view *M) {
  plane_ctx x = {.M = M};
  MX_CHECK(mx_afile_printf(f, "[Nodes, ARRAY1<STRING>]\n%zu\n\n", M->nnodes));
  MX_CHECK(mx_afile_emit(f, M->nnodes, 3 + 3 * (PLANE_SCI_MAX + 1), fill_plane_nodes, &x));
  MX_CHECK(mx_afile_printf(f, "\n[Elements, ARRAY1<STRING>]\n%zu\n\n", M->ncells));
  return mx_afile_emit(f, M->ncells, 1 + 4 * (MX_U64_CHARS + 1) + sizeof plane_tail, fill_plane_cells,
                       &x);
}

int mx_write_m3d(const char *path, const mx_mesh_view *m) {
  MX_CHECK(mx_mesh_view_check(path, m));
  mx_afile f;
  MX_CHECK(mx_afile_open(&f, path));
  if (mx_view_is_2d(m)) return mx_afile_finish(&f, write_plane_body(&f, m));
  return mx_afile_finish(&f, write_m3d_body(&f, m));
}

int mx_write_mvm(const char *path, const mx_mesh_view *m) {
  MX_CHECK(mx_mesh_view_check(path, m));
  mx_afile f;
  MX_CHECK(mx_afile_open(&f, path));
  return mx_afile_finish(&f, write_mvm_body(&f, m));
}
