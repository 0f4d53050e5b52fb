/* mixoct: GetFEM mesh writer (the text format of GetFEM's
 * mesh::write_to_file / read_from_file, ".mesh" in GetFEM's own examples;
 * mixoct names it ".getfem" so it cannot be taken for a Medit .mesh).
 *
 * Layout, as GetFEM writes and reads it (GetFEM user documentation, "Save
 * and load meshes", and the mesh files shipped with GetFEM):
 *
 *   % GETFEM MESH FILE
 *   % GETFEM VERSION 5.4
 *   % mixoct: <n> points, <m> convexes
 *
 *   BEGIN POINTS LIST
 *
 *     POINT  0  x y z
 *     ...
 *
 *   END POINTS LIST
 *
 *   BEGIN MESH STRUCTURE DESCRIPTION
 *
 *     CONVEX 0    'GT_QK(3,1)'      i0 i1 ... i7
 *     ...
 *
 *   END MESH STRUCTURE DESCRIPTION
 *
 * Points and convexes are numbered from 0 in the mesh's order; a convex
 * lists its points' numbers.
 *
 * Boundary tags (issue 11: view.bfaces with tags) follow as GetFEM regions,
 * one per tag t, the faces as "convex/face" pairs in GetFEM's own face
 * numbering (read off GetFEM's Mesh.pid_in_faces for each geometric
 * transformation; tests/test_getfem_m3d.c and the GetFEM solve of the
 * tests check it with GetFEM itself):
 *
 *   BEGIN REGION t
 *   12/3
 *   ...
 *   END REGION t Lines starting with '%' before BEGIN POINTS
 * LIST are comments (GetFEM's reader skips to that line). The "POINT COUNT"
 * and "CONVEX COUNT" lines newer GetFEM versions write are left out, so
 * older readers accept the file too; the counts are in the comment line.
 * Cell fields (type, level, jens) are not written: the format has no place
 * for them.
 *
 * Geometric transformations and GetFEM's node order (GetFEM documentation:
 * the figure "vertex numeration for usual elements" of "Build a mesh", the
 * tensor-product construction of Q_K and prism elements and the pyramid
 * shape functions of appendix A "Finite element method list"; names from
 * the gf_geotrans / GeoTrans reference):
 *
 *   tet     'GT_PK(3,1)'    (0,0,0) (1,0,0) (0,1,0) (0,0,1)
 *   pyramid 'GT_PYRAMID(1)' (-1,-1,0) (1,-1,0) (-1,1,0) (1,1,0) (0,0,1)
 *   prism   'GT_PRISM(3,1)' (0,0,0) (1,0,0) (0,1,0) (0,0,1) (1,0,1) (0,1,1)
 *   hex     'GT_QK(3,1)'    (0,0,0) (1,0,0) (0,1,0) (1,1,0) (0,0,1) (1,0,1)
 *                           (0,1,1) (1,1,1)
 *
 * i.e. quadrilateral faces in tensor (x fastest) order, not around the face
 * as VTK has them. (The pyramid is named with its degree only: the
 * documentation gives "GT_PYRAMID(K)" for K = 1 or 2.) An element has a
 * positive volume in GetFEM's convention when the Jacobian of the map from
 * that reference element is positive, which for these orders and mixoct's
 * VTK-ordered elements (positive in VTK's convention) gives:
 *
 *   tet     GetFEM k = VTK k
 *   pyramid GetFEM (0 1 2 3 4) = VTK (0 1 3 2 4)
 *   prism   GetFEM k = VTK k  (both: 0 1 2 counter-clockwise seen from 3 4 5)
 *   hex     GetFEM (0 1 2 3 4 5 6 7) = VTK (0 1 3 2 4 5 7 6)
 *
 * Numbers are ASCII, doubles to 15 significant digits when that reads back
 * to the same double, else 17 (always exact; mx_put_double of io/text_num.h,
 * laid out like "%g"). The points and convexes are produced in chunks filled
 * in parallel by mx_afile_emit, so the file is the same byte for byte
 * whatever the number of threads.
 * A 2D view (soa/mesh.h: dim 2) is written by the section "a 2D view"
 * below. */
#include <stdint.h>
#include <string.h>

#include "base/common.h"
#include "io/atomic_file.h"
#include "io/boundary_faces.h"
#include "io/getfem_tables.h"
#include "io/plane_mesh.h"
#include "io/text_num.h"
#include "soa/mesh.h"
#include "io/write_mesh.h"
#include "io/mesh_view_check.h"

/* GetFEM's node order, face numbers and geometric transformations
 * (mx_getfem_node, mx_getfem_face, mx_getfem_geotrans): io/getfem_tables.h,
 * shared with the reader. */

enum {
  /* "  POINT  ", the index, 3 doubles after 2 blanks each, '\n' */
  POINT_LINE_MAX = 9 + MX_U64_CHARS + 3 * (2 + MX_DOUBLE_CHARS) + 1,
  /* "  CONVEX ", the index, 4 blanks, the name (at most 15), 5 blanks,
   * 8 indices after a blank each, '\n' */
  CONVEX_LINE_MAX = 9 + MX_U64_CHARS + 24 + 8 * (1 + MX_U64_CHARS) + 1,
};

/* ---- text ---------------------------------------------------------------- */

static size_t put_str(char *out, const char *s) {
  size_t n = strlen(s);
  memcpy(out, s, n);
  return n;
}

/* ---- fill functions ------------------------------------------------------- */

static size_t fill_points(const void *vctx, size_t b, size_t e, char *out) {
  const mx_mesh_view *m = vctx;
  size_t n = 0;
  for (size_t i = b; i < e; i++) {
    n += put_str(out + n, "  POINT  ");
    n += mx_put_u64(out + n, i);
    for (int d = 0; d < 3; d++) {
      out[n++] = ' ';
      out[n++] = ' ';
      n += mx_put_double(out + n, m->xyz[3 * i + d]);
    }
    out[n++] = '\n';
  }
  return n;
}

static size_t fill_convexes(const void *vctx, size_t b, size_t e, char *out) {
  const mx_mesh_view *m = vctx;
  size_t n = 0;
  for (size_t k = b; k < e; k++) {
    const size_t c = mx_view_cell(m, k); /* the k-th convex written */
    const int t = m->type[c];
    const uint32_t *row = m->conn + 8 * c;
    n += put_str(out + n, "  CONVEX ");
    n += mx_put_u64(out + n, k);
    n += put_str(out + n, "    ");
    n += put_str(out + n, mx_getfem_geotrans[t]);
    n += put_str(out + n, "     ");
    for (int j = 0; j < mx_cell_nodes[t]; j++) {
      out[n++] = ' ';
      n += mx_put_u64(out + n, row[mx_getfem_node[t][j]]);
    }
    out[n++] = '\n';
  }
  return n;
}

/* ---- regions ---------------------------------------------------------------- */

typedef struct {
  const mx_mesh_view *m;
  const uint32_t *cv;    /* cell -> convex number (its written position) */
  const uint64_t *src;   /* the face list's 8 * cell + local face */
} region_ctx;

static size_t fill_region(const void *vctx, size_t b, size_t e, char *out) {
  const region_ctx *c = vctx;
  size_t n = 0;
  for (size_t i = b; i < e; i++) {
    const size_t cell = (size_t)(c->src[i] >> 3);
    n += mx_put_u64(out + n, c->cv[cell]);
    out[n++] = '/';
    n += mx_put_u64(out + n, (uint64_t)mx_getfem_face[c->m->type[cell]][c->src[i] & 7]);
    out[n++] = '\n';
  }
  return n;
}

/* The faces of one list with tag t: a run (the lists are sorted by tag). */
static int region_run(mx_afile *f, region_ctx *c, const uint64_t *src, const int32_t *tag,
                      size_t n, int32_t t) {
  size_t b = 0;
  while (b < n && tag[b] != t) b++;
  size_t e = b;
  while (e < n && tag[e] == t) e++;
  c->src = src + b;
  return mx_afile_emit(f, e - b, 2 * MX_U64_CHARS + 2, fill_region, c);
}

/* The convexes of body b (in written order), a line each. */
typedef struct {
  const mx_mesh_view *m;
  int32_t body;
} body_ctx;

static size_t fill_body(const void *vctx, size_t b, size_t e, char *out) {
  const body_ctx *c = vctx;
  size_t n = 0;
  for (size_t k = b; k < e; k++) {
    if (c->m->cell_body[mx_view_cell(c->m, k)] != c->body) continue;
    n += mx_put_u64(out + n, k);
    out[n++] = '\n';
  }
  return n;
}

/* Several materials (view.body_physical set): a region of convexes per
 * body, numbered MX_GETFEM_MATERIAL_REGION + its physical number. */
static int write_material_regions(mx_afile *f, const mx_mesh_view *m) {
  if (!m->body_physical || !m->cell_body || m->nbodies <= 0) return MX_OK;
  for (int32_t b = 1; b <= m->nbodies; b++) {
    const int r = MX_GETFEM_MATERIAL_REGION + m->body_physical[b - 1];
    const body_ctx c = {m, b};
    MX_CHECK(mx_afile_printf(f, "BEGIN REGION %d\n", r));
    MX_CHECK(mx_afile_emit(f, m->ncells, MX_U64_CHARS + 1, fill_body, &c));
    MX_CHECK(mx_afile_printf(f, "END REGION %d\n", r));
  }
  return MX_OK;
}

static int write_regions(mx_afile *f, const mx_mesh_view *m) {
  const struct mx_boundary_faces *bf = m->bfaces;
  if (!bf || !bf->tri_tag || !bf->quad_tag || m->ntags <= 0) return write_material_regions(f, m);
  uint32_t *cv = mx_alloc((m->ncells + 1) * sizeof *cv);
  if (!cv) return MX_ENOMEM;
#pragma omp parallel for schedule(static)
  for (size_t k = 0; k < m->ncells; k++) cv[mx_view_cell(m, k)] = (uint32_t)k;
  region_ctx c = {m, cv, NULL};
  int st = MX_OK;
  for (int32_t t = 1; !st && t <= m->ntags; t++) {
    st = mx_afile_printf(f, "BEGIN REGION %d\n", t);
    if (!st) st = region_run(f, &c, bf->tri_src, bf->tri_tag, bf->ntri, t);
    if (!st) st = region_run(f, &c, bf->quad_src, bf->quad_tag, bf->nquad, t);
    if (!st) st = mx_afile_printf(f, "END REGION %d\n", t);
  }
  mx_free(cv);
  return st ? st : write_material_regions(f, m);
}

/* ---- file ----------------------------------------------------------------- */

static int write_body(mx_afile *f, const mx_mesh_view *m) {
  MX_CHECK(mx_afile_printf(f,
                           "%% GETFEM MESH FILE\n%% GETFEM VERSION 5.4\n"
                           "%% mixoct: %zu points, %zu convexes\n",
                           m->nnodes, m->ncells));
  /* several materials: what the regions hold, as comments */
  for (int t = 1; m->body_physical && m->tag_names && t <= m->ntags; t++)
    MX_CHECK(mx_afile_printf(f, "%% region %d: faces \"%s\"\n", t, m->tag_names[t - 1]));
  for (int b = 1; m->body_physical && m->body_names && b <= m->nbodies; b++)
    MX_CHECK(mx_afile_printf(f, "%% region %d: convexes of material %d \"%s\"\n",
                             MX_GETFEM_MATERIAL_REGION + m->body_physical[b - 1],
                             m->body_physical[b - 1], m->body_names[b - 1]));
  MX_CHECK(mx_afile_printf(f, "\nBEGIN POINTS LIST\n\n"));
  MX_CHECK(mx_afile_emit(f, m->nnodes, POINT_LINE_MAX, fill_points, m));
  MX_CHECK(mx_afile_printf(f, "\nEND POINTS LIST\n\n\n\n"
                              "BEGIN MESH STRUCTURE DESCRIPTION\n\n"));
  MX_CHECK(mx_afile_emit(f, m->ncells, CONVEX_LINE_MAX, fill_convexes, m));
  MX_CHECK(mx_afile_printf(f, "\nEND MESH STRUCTURE DESCRIPTION\n"));
  return write_regions(f, m);
}

/* ---- a 2D view (soa/mesh.h: dim 2) ---------------------------------------
 *
 * 2D points; 'GT_PK(2,1)' triangles, 'GT_QK(2,1)' quadrilaterals, whose
 * reference order is the tensor one, (0,0) (1,0) (0,1) (1,1): our
 * counter-clockwise a b c d is written a b d c. With bodies (several
 * materials), a region of the convexes of each, numbered
 * MX_GETFEM_MATERIAL_REGION + its number and listed in the comments, as
 * in 3D; no other region. */

typedef struct {
  const mx_mesh_view *M;
} plane_ctx;

static size_t fill_plane_points(const void *v, size_t b, size_t e, char *o) {
  const plane_ctx *x = v;
  size_t n = 0;
  for (size_t i = b; i < e; i++) {
    memcpy(o + n, "  POINT  ", 9);
    n += 9;
    n += mx_put_u64(o + n, i);
    for (int d = 0; d < 2; d++) {
      memcpy(o + n, "  ", 2);
      n += 2;
      n += mx_put_double(o + n, x->M->xyz[2 * i + d]);
    }
    o[n++] = '\n';
  }
  return n;
}

static size_t fill_plane_convexes(const void *v, size_t b, size_t e, char *o) {
  const plane_ctx *x = v;
  static const int tensor[4] = {0, 1, 3, 2}; /* GT_QK's node j is our node tensor[j] */
  size_t n = 0;
  for (size_t c = b; c < e; c++) {
    const uint32_t *r = x->M->conn + 4 * c;
    const int quad = x->M->type[c] == MX_CELL_QUAD;
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

static int write_plane_body(mx_afile *f, const mx_mesh_view *M) {
  plane_ctx x = {.M = M};
  MX_CHECK(mx_afile_printf(f, "%% GETFEM MESH FILE\n%% GETFEM VERSION 5.4\n"
                              "%% mixoct: %zu points, %zu convexes\n", M->nnodes, M->ncells));
  for (int b = 1; M->body_physical && M->body_names && b <= M->nbodies; b++)
    MX_CHECK(mx_afile_printf(f, "%% region %d: convexes of material %d \"%s\"\n",
                             MX_GETFEM_MATERIAL_REGION + M->body_physical[b - 1],
                             M->body_physical[b - 1], M->body_names[b - 1]));
  MX_CHECK(mx_afile_printf(f, "\nBEGIN POINTS LIST\n\n"));
  MX_CHECK(mx_afile_emit(f, M->nnodes, 10 + MX_U64_CHARS + 2 * (2 + MX_DOUBLE_CHARS), fill_plane_points,
                         &x));
  MX_CHECK(mx_afile_printf(f, "\nEND POINTS LIST\n\n\n\nBEGIN MESH STRUCTURE DESCRIPTION\n\n"));
  MX_CHECK(mx_afile_emit(f, M->ncells, 32 + 5 * (MX_U64_CHARS + 1), fill_plane_convexes, &x));
  MX_CHECK(mx_afile_printf(f, "\nEND MESH STRUCTURE DESCRIPTION\n"));
  return write_material_regions(f, M); /* 2D: a convex's number is its index */
}

int mx_write_getfem(const char *path, const mx_mesh_view *m) {
  MX_CHECK(mx_mesh_view_check(path, m));
  mx_afile f;
  MX_CHECK(mx_afile_open(&f, path));
  if (mx_view_is_2d(m)) return mx_afile_finish(&f, write_plane_body(&f, m));
  return mx_afile_finish(&f, write_body(&f, m));
}
