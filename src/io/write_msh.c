/* mixoct: Gmsh MSH 4.1 writer, ASCII ("4.1 0 8") or binary ("4.1 1 8").
 *
 * Layout of a plain mesh (no boundary tags in the view): $MeshFormat,
 * $PhysicalNames (one volume group, tag 1, "domain"), $Entities (one volume,
 * tag 1, with its bounding box and that physical group), $Nodes (one block
 * on the volume holding every node, tags 1..N in the mesh's order),
 * $Elements (one block per element type present, in the order tet, pyramid,
 * prism, hex; an element's tag is its position in the written order + 1
 * (mx_view_cell), so tags match the cell order of the other formats), then
 * one $ElementData section per cell field (type, level, jens...).
 *
 * With boundary tags (issue 11: view.bfaces, view.ntags, view.cell_body):
 * one surface entity and one physical group (dimension 2, tag t, named after
 * the input file) per boundary tag that has faces, one volume entity and one
 * physical group (dimension 3, tag b) per body; the volume elements in one
 * block per (body, type) (the written order groups them so), then the
 * boundary triangles (type 2) and quadrilaterals (type 3) in one block per
 * (tag, type), the face lists being sorted by tag. Element tags are the
 * elements' positions in the file, 1 to N (volume elements: their written
 * position; meshio wants them rising through the file). $ElementData covers every element, a
 * boundary face with the value of its element.
 *
 * Binary files use the host's byte order (the int 1 after the format line
 * lets a reader check it): counts and node/element tags are 8-byte size_t,
 * entity dimensions, tags and element types 4-byte int, coordinates 8-byte
 * doubles. $PhysicalNames is ASCII in both variants.
 *
 * Node order. Gmsh's reference elements (Gmsh manual, "Node ordering"):
 *   tet     (0,0,0) (1,0,0) (0,1,0) (0,0,1)
 *   pyramid (-1,-1,0) (1,-1,0) (1,1,0) (-1,1,0) (0,0,1)
 *   prism   (0,0,-1) (1,0,-1) (0,1,-1) (0,0,1) (1,0,1) (0,1,1)
 *   hex     (-1,-1,-1) (1,-1,-1) (1,1,-1) (-1,1,-1) then the same at z = 1
 * In each, the right-hand normal of the first face (0,1,2[,3]) points into
 * the element, towards the other nodes. mixoct's cells (VTK order, see
 * soa/mesh.h and geom/quality.c) follow the same rule: the pyramid base
 * 0,1,2,3 turns counter-clockwise seen from the apex 4, the prism triangle
 * 0,1,2 counter-clockwise seen from 3,4,5. So the permutation below is the
 * identity for every type; it is kept as a table so the rule is written in
 * one place (tests/test_msh.c checks volumes in Gmsh's convention, and
 * tests/external_readers_test.sh Gmsh's own Jacobians). For prisms this is
 * the order of VTK's wedge parametric coordinates, not of the vtkWedge
 * documentation, which turns 0,1,2 the other way.
 *
 * Every large section is formatted (ASCII) or packed (binary) in parallel
 * chunks by mx_afile_emit: the bytes do not depend on the thread count.
 * ASCII doubles read back exactly (see mx_put_double in io/text_num.h).
 * A 2D view (soa/mesh.h: dim 2) is written by the section "a 2D view"
 * below. */
#include <math.h>
#include <omp.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "base/common.h"
#include "io/atomic_file.h"
#include "io/boundary_faces.h"
#include "io/cell_order.h"
#include "io/msh_order.h"
#include "io/plane_mesh.h"
#include "io/text_num.h"
#include "soa/mesh.h"
#include "io/write_mesh.h"
#include "io/mesh_view_check.h"

enum {
  ENTITY_TAG = 1,
  PHYSICAL_TAG = 1,
};

/* What the tagged layout needs: the tags and bodies present, counts per
 * block, boxes (a body's box is its boundary faces' box). */
typedef struct msh_layout {
  int tagged, ntags, nbodies;
  size_t *ntri, *nquad;   /* per tag 0..ntags */
  size_t *tri0, *quad0;   /* where each tag's run starts in the face lists */
  uint64_t *tag0;         /* the element tag before each tag's first face */
  size_t *ncell;          /* per body 0..nbodies, 4 types each */
  double *tbox, *bbox;    /* 6 per tag / body */
  /* written positions [klo, khi) holding each block's cells, per body
   * 0..nbodies (plain layout: 0 only), 4 types each: a block scans only
   * those (the whole of them when the written order groups the blocks) */
  size_t *klo, *khi;
} msh_layout;

typedef struct {
  const mx_mesh_view *m;
  const msh_layout *L;
  int type;   /* element section: the mixoct type of this block (faces: 3, 4 nodes) */
  int body;   /* 0: every cell; else the body (faces: the tag) of this block */
  int binary;
  const mx_field *fd; /* $ElementData: the field */
  size_t base;        /* faces: the first of the block's run in its list;
                         cells: the written position of item 0 */
  int dense;          /* cells: every written position of the run is the
                         block's (the written order groups the blocks) */
} msh_ctx;

/* ---- binary stores (host byte order) -------------------------------------- */

static inline void put_size(char *out, uint64_t v) { memcpy(out, &v, 8); }

/* ---- nodes ------------------------------------------------------------------ */

static size_t fill_node_tags_bin(const void *vctx, size_t b, size_t e,
                                 char *out) {
  (void)vctx;
  for (size_t i = b; i < e; i++) put_size(out + 8 * (i - b), (uint64_t)i + 1);
  return 8 * (e - b);
}

static size_t fill_node_tags_ascii(const void *vctx, size_t b, size_t e,
                                   char *out) {
  (void)vctx;
  size_t n = 0;
  for (size_t i = b; i < e; i++) {
    n += mx_put_u64(out + n, (uint64_t)i + 1);
    out[n++] = '\n';
  }
  return n;
}

static size_t fill_coords_ascii(const void *vctx, size_t b, size_t e,
                                char *out) {
  return mx_put_xyz_lines(out, ((const msh_ctx *)vctx)->m->xyz, b, e);
}

/* ---- elements: every written position is an item, the cells of other
 * types (or bodies) write nothing, so a block keeps the written order. ---- */

/* A $ElementData line: the element's tag and the field's value at cell c
 * (a boundary face carries its element's value). */
static size_t data_line(const msh_ctx *ctx, uint64_t tag, size_t c, char *out) {
  const mx_field *fd = ctx->fd;
  const double v = fd->is_double ? mx_field_double(fd, c) : (double)mx_field_int(fd, c);
  if (ctx->binary) {
    const int32_t t = (int32_t)tag;
    memcpy(out, &t, 4);
    memcpy(out + 4, &v, 8);
    return 12;
  }
  size_t n = mx_put_u64(out, tag);
  out[n++] = ' ';
  n += fd->is_double ? mx_put_double(out + n, v) : mx_put_i64(out + n, mx_field_int(fd, c));
  out[n++] = '\n';
  return n;
}

static inline int in_block(const msh_ctx *ctx, size_t c) {
  const mx_mesh_view *m = ctx->m;
  return m->type[c] == ctx->type && (ctx->body == 0 || m->cell_body[c] == ctx->body);
}

/* A dense block's cells (every position its own) of nn nodes each, the
 * node order Gmsh's (mx_msh_perm, the identity: io/msh_order.h): tag, then
 * the nodes, 8 bytes each. Inlined per node count (the loop unrolled). */
static inline __attribute__((always_inline)) size_t
put_cells(const mx_mesh_view *m, size_t k0, size_t k1, const int nn, char *out) {
  uint64_t rec[9];
  char *o = out;
  for (size_t k = k0; k < k1; k++) {
    const uint32_t *row = m->conn + 8 * mx_view_cell(m, k);
    rec[0] = (uint64_t)k + 1;
    for (int j = 0; j < nn; j++) rec[1 + j] = (uint64_t)row[j] + 1;
    memcpy(o, rec, 8 * (size_t)(nn + 1));
    o += 8 * (size_t)(nn + 1);
  }
  return (size_t)(o - out);
}

static int perm_identity(int t) {
  for (int j = 0; j < mx_cell_nodes[t]; j++)
    if (mx_msh_perm[t][j] != j) return 0;
  return 1;
}

/* A dense block's $ElementData lines, binary: the int32 tag and the
 * double value, per source kind of the field (the same doubles as
 * mx_field_double and mx_field_int give). */
#define MSH_DATA_LOOP(VALUE)                                          \
  for (size_t k = k0; k < k1; k++, o += 12) {                         \
    const size_t c = mx_view_cell(m, k);                              \
    const int32_t t = (int32_t)(k + 1);                               \
    const double v = (VALUE);                                         \
    memcpy(o, &t, 4);                                                 \
    memcpy(o + 4, &v, 8);                                             \
  }

static size_t put_data_bin(const mx_mesh_view *m, const mx_field *fd, size_t k0, size_t k1,
                           char *out) {
  char *o = out;
  if (fd->is_double && fd->dvalues) {
    const double *src = fd->dvalues;
    MSH_DATA_LOOP(src[c])
  } else if (fd->is_double) {
    const float *src = fd->fvalues;
    MSH_DATA_LOOP((double)src[c])
  } else if (fd->ivalues) {
    const int32_t *src = fd->ivalues;
    MSH_DATA_LOOP((double)src[c])
  } else {
    const uint8_t *src = fd->u8values;
    MSH_DATA_LOOP((double)(int32_t)src[c])
  }
  return (size_t)(o - out);
}
#undef MSH_DATA_LOOP

static size_t fill_elements_bin(const void *vctx, size_t b, size_t e,
                                char *out) {
  const msh_ctx *ctx = vctx;
  const mx_mesh_view *m = ctx->m;
  const int t = ctx->type, nn = mx_cell_nodes[t];
  const int8_t *perm = mx_msh_perm[t];
  if (ctx->dense && ctx->fd) return put_data_bin(m, ctx->fd, ctx->base + b, ctx->base + e, out);
  if (ctx->dense && perm_identity(t)) {
    const size_t k0 = ctx->base + b, k1 = ctx->base + e;
    switch (nn) {
      case 4: return put_cells(m, k0, k1, 4, out);
      case 5: return put_cells(m, k0, k1, 5, out);
      case 6: return put_cells(m, k0, k1, 6, out);
      default: return put_cells(m, k0, k1, 8, out);
    }
  }
  size_t n = 0;
  for (size_t k = ctx->base + b; k < ctx->base + e; k++) {
    const size_t c = mx_view_cell(m, k);
    if (!in_block(ctx, c)) continue;
    if (ctx->fd) {
      n += data_line(ctx, (uint64_t)k + 1, c, out + n);
      continue;
    }
    const uint32_t *row = m->conn + 8 * c;
    put_size(out + n, (uint64_t)k + 1);
    n += 8;
    for (int j = 0; j < nn; j++, n += 8)
      put_size(out + n, (uint64_t)row[perm[j]] + 1);
  }
  return n;
}

static size_t fill_elements_ascii(const void *vctx, size_t b, size_t e,
                                  char *out) {
  const msh_ctx *ctx = vctx;
  const mx_mesh_view *m = ctx->m;
  const int t = ctx->type, nn = mx_cell_nodes[t];
  const int8_t *perm = mx_msh_perm[t];
  size_t n = 0;
  for (size_t k = ctx->base + b; k < ctx->base + e; k++) {
    const size_t c = mx_view_cell(m, k);
    if (!in_block(ctx, c)) continue;
    if (ctx->fd) {
      n += data_line(ctx, (uint64_t)k + 1, c, out + n);
      continue;
    }
    const uint32_t *row = m->conn + 8 * c;
    n += mx_put_u64(out + n, (uint64_t)k + 1);
    for (int j = 0; j < nn; j++) {
      out[n++] = ' ';
      n += mx_put_u64(out + n, (uint64_t)row[perm[j]] + 1);
    }
    out[n++] = '\n';
  }
  return n;
}

/* Boundary faces of one tag: ctx->type 3 (triangles) or 4 (quads). */
static size_t fill_faces(const void *vctx, size_t b, size_t e, char *out) {
  const msh_ctx *ctx = vctx;
  const mx_boundary_faces *bf = ctx->m->bfaces;
  const int nv = ctx->type;
  const uint32_t *fv = nv == 3 ? bf->tri : bf->quad;
  const int32_t *tag = nv == 3 ? bf->tri_tag : bf->quad_tag;
  const msh_layout *L = ctx->L;
  const size_t t = (size_t)ctx->body;
  const uint64_t first = L->tag0[t] + 1 + (nv == 3 ? 0 : L->ntri[t]);
  const size_t i0 = nv == 3 ? L->tri0[t] : L->quad0[t];
  size_t n = 0;
  const uint64_t *src = nv == 3 ? bf->tri_src : bf->quad_src;
  for (size_t item = b; item < e; item++) {
    const size_t i = ctx->base + item; /* in the tag's run of the list */
    if (tag[i] != ctx->body) continue;
    if (ctx->fd) {
      n += data_line(ctx, first + (i - i0), (size_t)(src[i] >> 3), out + n);
      continue;
    }
    if (ctx->binary) {
      put_size(out + n, first + (i - i0));
      n += 8;
      for (int j = 0; j < nv; j++, n += 8) put_size(out + n, (uint64_t)fv[(size_t)nv * i + j] + 1);
    } else {
      n += mx_put_u64(out + n, first + (i - i0));
      for (int j = 0; j < nv; j++) {
        out[n++] = ' ';
        n += mx_put_u64(out + n, (uint64_t)fv[(size_t)nv * i + j] + 1);
      }
      out[n++] = '\n';
    }
  }
  return n;
}

/* ---- sections ---------------------------------------------------------------- */

static int write_bin(mx_afile *f, const void *p, size_t bytes) {
  return mx_afile_write(f, p, bytes);
}

static int write_bin_size(mx_afile *f, uint64_t v) {
  return write_bin(f, &v, 8);
}

static int write_bin_int(mx_afile *f, int v) {
  int32_t i = (int32_t)v;
  return write_bin(f, &i, 4);
}

/* Bounding box of the nodes (min/max are exact: any order gives the same). */
static void bounding_box(const mx_mesh_view *m, double box[6]) {
  double x0 = 0, y0 = 0, z0 = 0, x1 = 0, y1 = 0, z1 = 0;
  if (m->nnodes > 0) {
    x0 = x1 = m->xyz[0];
    y0 = y1 = m->xyz[1];
    z0 = z1 = m->xyz[2];
  }
#pragma omp parallel for reduction(min : x0, y0, z0) \
    reduction(max : x1, y1, z1) schedule(static) if (m->nnodes > 65536)
  for (size_t i = 0; i < m->nnodes; i++) {
    const double *p = m->xyz + 3 * i;
    x0 = p[0] < x0 ? p[0] : x0;
    y0 = p[1] < y0 ? p[1] : y0;
    z0 = p[2] < z0 ? p[2] : z0;
    x1 = p[0] > x1 ? p[0] : x1;
    y1 = p[1] > y1 ? p[1] : y1;
    z1 = p[2] > z1 ? p[2] : z1;
  }
  box[0] = x0, box[1] = y0, box[2] = z0;
  box[3] = x1, box[4] = y1, box[5] = z1;
}


static void layout_free(msh_layout *L) {
  mx_free(L->ntri);
  mx_free(L->nquad);
  mx_free(L->tri0);
  mx_free(L->quad0);
  mx_free(L->tag0);
  mx_free(L->ncell);
  mx_free(L->tbox);
  mx_free(L->bbox);
  mx_free(L->klo);
  mx_free(L->khi);
}

static void box_add(double *box, const double *p) {
  for (int a = 0; a < 3; a++) {
    box[a] = p[a] < box[a] ? p[a] : box[a];
    box[3 + a] = p[a] > box[3 + a] ? p[a] : box[3 + a];
  }
}

/* box grown to hold box o (min and max corners; an empty o, its min above
 * its max, leaves box as it was) */
static void box_merge(double *box, const double *o) {
  for (int a = 0; a < 3; a++) {
    box[a] = o[a] < box[a] ? o[a] : box[a];
    box[3 + a] = o[3 + a] > box[3 + a] ? o[3 + a] : box[3 + a];
  }
}

/* Face i (nv nodes) into its tag's count and box (tb) and its body's box
 * (bb). */
static inline void face_into(const mx_mesh_view *m, const msh_layout *L, const uint32_t *fv,
                             const int32_t *tag, const uint64_t *src, size_t i, int nv,
                             size_t *cnt, double *tb, double *bb) {
  const int t = tag[i] >= 1 && tag[i] <= L->ntags ? tag[i] : 0;
  const int32_t b = m->cell_body[src[i] >> 3];
  const int inb = b >= 1 && b <= L->nbodies;
  if (t) cnt[t]++;
  for (int j = 0; j < nv; j++) {
    const double *p = m->xyz + 3 * (size_t)fv[(size_t)nv * i + j];
    if (t) box_add(tb + 6 * t, p);
    if (inb) box_add(bb + 6 * b, p);
  }
}

/* The faces of one kind (nv nodes) into the tags' counts and boxes and
 * their bodies' boxes: in parallel, each thread with its own boxes over
 * its run of faces (schedule static: thread r has the r-th run), merged
 * after in thread order. */
static void faces_into(const mx_mesh_view *m, msh_layout *L, const uint32_t *fv,
                       const int32_t *tag, const uint64_t *src, size_t n, int nv, size_t *cnt) {
  const size_t nt = (size_t)L->ntags + 1, nb = (size_t)L->nbodies + 1;
  double *tbox = L->tbox, *bbox = L->bbox;
  if (nt > 67 || nb > 67) { /* more than the mesher makes: serially */
    for (size_t i = 0; i < n; i++) face_into(m, L, fv, tag, src, i, nv, cnt, tbox, bbox);
    return;
  }
#pragma omp parallel if (n > 65536)
  {
    double tb[6 * 67], bb[6 * 67];
    for (size_t i = 0; i < 6 * nt; i++) tb[i] = i % 6 < 3 ? INFINITY : -INFINITY;
    for (size_t i = 0; i < 6 * nb; i++) bb[i] = i % 6 < 3 ? INFINITY : -INFINITY;
#pragma omp for schedule(static) reduction(+ : cnt[:nt])
    for (size_t i = 0; i < n; i++) face_into(m, L, fv, tag, src, i, nv, cnt, tb, bb);
    /* merged in thread order, the order of their runs of faces: a tie
     * (0.0 and -0.0) keeps the first in face order, as one thread does */
    const int nthr = omp_get_num_threads();
#pragma omp for ordered schedule(static, 1)
    for (int r = 0; r < nthr; r++) {
#pragma omp ordered
      {
        for (size_t t = 1; t < nt; t++) box_merge(tbox + 6 * t, tb + 6 * t);
        for (size_t b = 1; b < nb; b++) box_merge(bbox + 6 * b, bb + 6 * b);
      }
    }
  }
}

/* The written positions of each block's cells and their counts (ncell,
 * per body 0..nbodies and type; the plain layout's all in body 0): one
 * pass over the cells. */
static int block_ranges(const mx_mesh_view *m, msh_layout *L) {
  const size_t nb = (size_t)L->nbodies + 1, n4 = 4 * nb;
  size_t *lo = mx_alloc(n4 * sizeof *lo), *hi = mx_alloc(n4 * sizeof *hi);
  size_t *cnt = mx_calloc(n4 * sizeof *cnt);
  L->klo = lo;
  L->khi = hi;
  L->ncell = cnt;
  if (!lo || !hi || !cnt) return MX_ENOMEM;
  for (size_t i = 0; i < n4; i++) lo[i] = SIZE_MAX, hi[i] = 0;
  const int tagged = L->tagged;
#pragma omp parallel for schedule(static) reduction(min : lo[:n4]) reduction(max : hi[:n4]) \
    reduction(+ : cnt[:n4]) if (m->ncells > 65536)
  for (size_t k = 0; k < m->ncells; k++) {
    const size_t c = mx_view_cell(m, k);
    const int32_t b = tagged ? m->cell_body[c] : 0;
    if (b < 0 || (size_t)b >= nb) continue;
    const size_t i = 4 * (size_t)b + (m->type[c] & 3);
    lo[i] = k < lo[i] ? k : lo[i];
    hi[i] = k + 1 > hi[i] ? k + 1 : hi[i];
    cnt[i]++;
  }
  for (size_t i = 0; i < n4; i++)
    if (lo[i] > hi[i]) lo[i] = hi[i] = 0; /* no cell */
  return MX_OK;
}

static int layout_build(const mx_mesh_view *m, msh_layout *L) {
  memset(L, 0, sizeof *L);
  const mx_boundary_faces *bf = m->bfaces;
  L->tagged = bf && bf->tri_tag && bf->quad_tag && m->ntags > 0 && m->cell_body && m->nbodies > 0;
  if (!L->tagged) {
    const int st = block_ranges(m, L);
    if (st) layout_free(L);
    return st;
  }
  L->ntags = m->ntags;
  L->nbodies = m->nbodies;
  const size_t nt = (size_t)L->ntags + 1, nb = (size_t)L->nbodies + 1;
  L->ntri = mx_calloc(nt * sizeof *L->ntri);
  L->nquad = mx_calloc(nt * sizeof *L->nquad);
  L->tbox = mx_alloc(6 * nt * sizeof *L->tbox);
  L->bbox = mx_alloc(6 * nb * sizeof *L->bbox);
  if (!L->ntri || !L->nquad || !L->tbox || !L->bbox) {
    layout_free(L);
    return MX_ENOMEM;
  }
  for (size_t i = 0; i < nt; i++)
    for (int a = 0; a < 3; a++) L->tbox[6 * i + a] = INFINITY, L->tbox[6 * i + 3 + a] = -INFINITY;
  for (size_t i = 0; i < nb; i++)
    for (int a = 0; a < 3; a++) L->bbox[6 * i + a] = INFINITY, L->bbox[6 * i + 3 + a] = -INFINITY;
  faces_into(m, L, bf->tri, bf->tri_tag, bf->tri_src, bf->ntri, 3, L->ntri);
  faces_into(m, L, bf->quad, bf->quad_tag, bf->quad_src, bf->nquad, 4, L->nquad);
  /* the face lists are sorted by tag (kernels/boundary_tags.h): element
   * tags follow the file, triangles then quadrilaterals of each tag */
  L->tri0 = mx_alloc((nt + 1) * sizeof *L->tri0);
  L->quad0 = mx_alloc((nt + 1) * sizeof *L->quad0);
  L->tag0 = mx_alloc((nt + 1) * sizeof *L->tag0);
  if (!L->tri0 || !L->quad0 || !L->tag0) {
    layout_free(L);
    return MX_ENOMEM;
  }
  size_t a = 0, b = 0;
  uint64_t e = m->ncells;
  for (size_t t = 0; t < nt; t++) {
    L->tri0[t] = a;
    L->quad0[t] = b;
    L->tag0[t] = e;
    a += L->ntri[t];
    b += L->nquad[t];
    e += L->ntri[t] + L->nquad[t];
  }
  const int st = block_ranges(m, L);
  if (st) layout_free(L);
  return st;
}

static int write_header(mx_afile *f, const mx_mesh_view *m, const msh_layout *L, int binary) {
  MX_CHECK(mx_afile_printf(f, "$MeshFormat\n4.1 %d 8\n", binary ? 1 : 0));
  if (binary) {
    MX_CHECK(write_bin_int(f, 1));
    MX_CHECK(mx_afile_write(f, "\n", 1));
  }
  MX_CHECK(mx_afile_printf(f, "$EndMeshFormat\n$PhysicalNames\n"));
  if (!L->tagged)
    return mx_afile_printf(f, "1\n3 %d \"domain\"\n$EndPhysicalNames\n", PHYSICAL_TAG);
  int n = L->nbodies;
  for (int t = 1; t <= L->ntags; t++) n += L->ntri[t] + L->nquad[t] > 0;
  MX_CHECK(mx_afile_printf(f, "%d\n", n));
  for (int t = 1; t <= L->ntags; t++)
    if (L->ntri[t] + L->nquad[t] > 0)
      MX_CHECK(mx_afile_printf(f, "2 %d \"%s\"\n", t, m->tag_names[t - 1]));
  for (int b = 1; b <= L->nbodies; b++)
    MX_CHECK(mx_afile_printf(f, "3 %d \"%s\"\n", m->body_physical ? m->body_physical[b - 1] : b,
                             m->body_names[b - 1]));
  return mx_afile_printf(f, "$EndPhysicalNames\n");
}

/* One entity line: tag, box, one physical tag, no bounding entities. */
static int write_entity(mx_afile *f, int tag, const double box[6], int phys, int binary) {
  if (binary) {
    MX_CHECK(write_bin_int(f, tag));
    MX_CHECK(write_bin(f, box, 6 * sizeof *box));
    MX_CHECK(write_bin_size(f, 1));
    MX_CHECK(write_bin_int(f, phys));
    return write_bin_size(f, 0);
  }
  char line[6 * (MX_DOUBLE_CHARS + 1) + 64];
  size_t n = (size_t)snprintf(line, sizeof line, "%d", tag);
  for (int k = 0; k < 6; k++) {
    line[n++] = ' ';
    n += mx_put_double(line + n, box[k]);
  }
  n += (size_t)snprintf(line + n, sizeof line - n, " 1 %d 0\n", phys);
  return mx_afile_write(f, line, n);
}

/* Plain: one volume (dim 3, tag ENTITY_TAG) in physical group PHYSICAL_TAG.
 * Tagged: a surface per boundary tag with faces, a volume per body. */
static int write_entities(mx_afile *f, const mx_mesh_view *m, const msh_layout *L, int binary) {
  double box[6];
  bounding_box(m, box);
  size_t nsurf = 0, nvol = 1;
  if (L->tagged) {
    for (int t = 1; t <= L->ntags; t++) nsurf += L->ntri[t] + L->nquad[t] > 0;
    nvol = (size_t)L->nbodies;
  }
  MX_CHECK(mx_afile_printf(f, "$Entities\n"));
  if (binary) {
    const uint64_t head[4] = {0, 0, nsurf, nvol};
    MX_CHECK(write_bin(f, head, sizeof head));
  } else {
    MX_CHECK(mx_afile_printf(f, "0 0 %zu %zu\n", nsurf, nvol));
  }
  if (!L->tagged) {
    MX_CHECK(write_entity(f, ENTITY_TAG, box, PHYSICAL_TAG, binary));
  } else {
    for (int t = 1; t <= L->ntags; t++)
      if (L->ntri[t] + L->nquad[t] > 0) MX_CHECK(write_entity(f, t, L->tbox + 6 * t, t, binary));
    for (int b = 1; b <= L->nbodies; b++) {
      const double *bb = L->bbox + 6 * b;
      MX_CHECK(write_entity(f, b, bb[0] <= bb[3] ? bb : box,
                            m->body_physical ? m->body_physical[b - 1] : b, binary));
    }
  }
  if (binary) MX_CHECK(mx_afile_write(f, "\n", 1));
  return mx_afile_printf(f, "$EndEntities\n");
}

static int write_nodes(mx_afile *f, const mx_mesh_view *m, int binary) {
  const size_t nn = m->nnodes;
  const size_t nblocks = nn > 0;
  const size_t tag_min = nn > 0, tag_max = nn;
  msh_ctx ctx = {m, NULL, 0, 0, binary, NULL, 0, 0};
  MX_CHECK(mx_afile_printf(f, "$Nodes\n"));
  if (binary) {
    const uint64_t head[4] = {nblocks, nn, tag_min, tag_max};
    MX_CHECK(write_bin(f, head, sizeof head));
    if (nblocks) {
      MX_CHECK(write_bin_int(f, 3));
      MX_CHECK(write_bin_int(f, ENTITY_TAG));
      MX_CHECK(write_bin_int(f, 0)); /* no parametric coordinates */
      MX_CHECK(write_bin_size(f, nn));
      MX_CHECK(mx_afile_emit(f, nn, 8, fill_node_tags_bin, &ctx));
      MX_CHECK(write_bin(f, m->xyz, 3 * nn * sizeof(double)));
    }
    MX_CHECK(mx_afile_write(f, "\n", 1));
  } else {
    MX_CHECK(mx_afile_printf(f, "%zu %zu %zu %zu\n", nblocks, nn, tag_min,
                             tag_max));
    if (nblocks) {
      MX_CHECK(mx_afile_printf(f, "3 %d 0 %zu\n", ENTITY_TAG, nn));
      MX_CHECK(mx_afile_emit(f, nn, MX_U64_CHARS + 1, fill_node_tags_ascii,
                             &ctx));
      MX_CHECK(
          mx_afile_emit(f, nn, MX_XYZ_LINE_MAX, fill_coords_ascii, &ctx));
    }
  }
  return mx_afile_printf(f, "$EndNodes\n");
}

/* One block header: entity dimension and tag, element type, count. */
static int block_head(mx_afile *f, int dim, int tag, int type, size_t count, int binary) {
  if (!binary) return mx_afile_printf(f, "%d %d %d %zu\n", dim, tag, type, count);
  MX_CHECK(write_bin_int(f, dim));
  MX_CHECK(write_bin_int(f, tag));
  MX_CHECK(write_bin_int(f, type));
  return write_bin_size(f, count);
}

/* A block of volume elements, or with fd its $ElementData lines (in the
 * same order: readers such as meshio take the values in file order). */
static int cell_block(mx_afile *f, const mx_mesh_view *m, const msh_layout *L, int entity,
                      int body, int t, size_t count, int binary, const mx_field *fd) {
  const size_t r = 4 * (size_t)body + (size_t)t; /* its written positions */
  const size_t nitems = L->khi[r] - L->klo[r];
  msh_ctx ctx = {m, NULL, t, body, binary, fd, L->klo[r], nitems == count};
  const size_t per_cell = (size_t)mx_cell_nodes[t] + 1;
  const size_t data_max = MX_U64_CHARS + MX_DOUBLE_CHARS + 2;
  if (!fd) MX_CHECK(block_head(f, 3, entity, mx_msh_type[t], count, binary));
  if (binary) return mx_afile_emit(f, nitems, fd ? 12 : 8 * per_cell, fill_elements_bin, &ctx);
  return mx_afile_emit(f, nitems, fd ? data_max : (MX_U64_CHARS + 1) * per_cell,
                       fill_elements_ascii, &ctx);
}

static int face_block(mx_afile *f, const mx_mesh_view *m, const msh_layout *L, int tag, int nv,
                      size_t count, int binary, const mx_field *fd) {
  msh_ctx ctx = {m, L, nv, tag, binary, fd, 0, 0};
  /* the tag's run of the sorted list */
  const size_t b = nv == 3 ? L->tri0[tag] : L->quad0[tag];
  if (!fd) MX_CHECK(block_head(f, 2, tag, nv == 3 ? 2 : 3, count, binary));
  ctx.base = b;
  return mx_afile_emit(f, count,
                       fd ? MX_U64_CHARS + MX_DOUBLE_CHARS + 2
                          : (MX_U64_CHARS + 1) * (size_t)(nv + 1),
                       fill_faces, &ctx);
}

/* Every block in file order: elements (fd NULL) or one field's values. */
static int all_blocks(mx_afile *f, const mx_mesh_view *m, const msh_layout *L,
                      const size_t count[4], int binary, const mx_field *fd) {
  if (!L->tagged) {
    for (int t = 0; t < 4; t++)
      if (count[t]) MX_CHECK(cell_block(f, m, L, ENTITY_TAG, 0, t, count[t], binary, fd));
    return MX_OK;
  }
  for (int b = 1; b <= L->nbodies; b++)
    for (int t = 0; t < 4; t++)
      if (L->ncell[4 * b + t])
        MX_CHECK(cell_block(f, m, L, b, b, t, L->ncell[4 * b + t], binary, fd));
  for (int t = 1; t <= L->ntags; t++) {
    if (L->ntri[t]) MX_CHECK(face_block(f, m, L, t, 3, L->ntri[t], binary, fd));
    if (L->nquad[t]) MX_CHECK(face_block(f, m, L, t, 4, L->nquad[t], binary, fd));
  }
  return MX_OK;
}

static int write_elements(mx_afile *f, const mx_mesh_view *m, const msh_layout *L,
                          const size_t count[4], int binary) {
  size_t nblocks = 0, ne = m->ncells;
  if (!L->tagged) {
    for (int t = 0; t < 4; t++) nblocks += count[t] > 0;
  } else {
    for (int b = 1; b <= L->nbodies; b++)
      for (int t = 0; t < 4; t++) nblocks += L->ncell[4 * b + t] > 0;
    for (int t = 1; t <= L->ntags; t++) {
      nblocks += (L->ntri[t] > 0) + (L->nquad[t] > 0);
      ne += L->ntri[t] + L->nquad[t];
    }
  }
  const size_t tag_min = ne > 0,
               tag_max = L->tagged ? m->ncells + m->bfaces->ntri + m->bfaces->nquad : ne;
  MX_CHECK(mx_afile_printf(f, "$Elements\n"));
  if (binary) {
    const uint64_t head[4] = {nblocks, ne, tag_min, tag_max};
    MX_CHECK(write_bin(f, head, sizeof head));
  } else {
    MX_CHECK(mx_afile_printf(f, "%zu %zu %zu %zu\n", nblocks, ne, tag_min, tag_max));
  }
  MX_CHECK(all_blocks(f, m, L, count, binary, NULL));
  if (binary) MX_CHECK(mx_afile_write(f, "\n", 1));
  return mx_afile_printf(f, "$EndElements\n");
}

/* One $ElementData section per cell field: the field's name, time 0, step
 * 0, one component; every element, a boundary face with its element's
 * value (readers such as meshio want data on every block), lines in the
 * order of the elements in the file (meshio takes them in that order,
 * Gmsh by tag). */
static int write_element_data(mx_afile *f, const mx_mesh_view *m, const msh_layout *L,
                              const size_t count[4], int binary) {
  const size_t ne = m->ncells + (L->tagged ? m->bfaces->ntri + m->bfaces->nquad : 0);
  for (int i = 0; i < m->ncell_fields; i++) {
    const mx_field *fd = &m->cell_fields[i];
    MX_CHECK(mx_afile_printf(f, "$ElementData\n1\n\"%s\"\n1\n0\n3\n0\n1\n%zu\n", fd->name,
                             ne));
    MX_CHECK(all_blocks(f, m, L, count, binary, fd));
    if (binary) MX_CHECK(mx_afile_write(f, "\n", 1));
    MX_CHECK(mx_afile_printf(f, "$EndElementData\n"));
  }
  return MX_OK;
}

static int write_body(mx_afile *f, const mx_mesh_view *m, int binary) {
  msh_layout L;
  MX_CHECK(layout_build(m, &L));
  size_t count[4] = {0, 0, 0, 0}; /* cells per type (the plain layout's) */
  if (!L.tagged) memcpy(count, L.ncell, sizeof count);
  int st = write_header(f, m, &L, binary);
  if (!st) st = write_entities(f, m, &L, binary);
  if (!st) st = write_nodes(f, m, binary);
  if (!st) st = write_elements(f, m, &L, count, binary);
  if (!st) st = write_element_data(f, m, &L, count, binary);
  layout_free(&L);
  return st;
}

/* ---- a 2D view (soa/mesh.h: dim 2) ---------------------------------------
 *
 * One surface entity (tag 1, physical 1 "domain") holding the nodes, the
 * triangles (type 2) and quadrilaterals (type 3); one curve entity (tag 1,
 * physical 2 "boundary") holding the boundary edges (used by one cell) as
 * lines (type 1), oriented as in their cell (the domain on their left);
 * $ElementData per cell field, a line carrying its cell's value. Element
 * tags are the cells' positions in the file (plane_cell_tags: the
 * triangles, then the quadrilaterals, each in cell order; the lines
 * follow), node tags index + 1. */

typedef struct {
  const mx_mesh_view *M;
  const mx_field *fd;     /* the cell field being written */
  int type;               /* the cells of this block's type */
  int body;               /* and of this body (0: any) */
  int data;               /* $ElementData lines instead of elements */
  int binary;
  const uint64_t *bedge;  /* boundary edges, 4 * cell + side (then, with
                           * bodies, the interface edges) */
  size_t base;            /* the first line of this block in bedge */
  const uint64_t *ctag;   /* per cell: its element tag (plane_cell_tags) */
} plane_ctx;

/* Each cell's element tag: its position in the file, 1 to ncells, the
 * cells in mx_cells_in_order's order (by body with by_body, then by type,
 * in index order), the order their blocks are written in, so that the
 * tags, and the $ElementData lines that follow the blocks, rise 1, 2, ...
 * through the file (meshio reads binary element data only so). NULL: out
 * of memory. */
static uint64_t *plane_cell_tags(const mx_mesh_view *M, int by_body) {
  uint64_t *tag = mx_alloc((M->ncells + 1) * sizeof *tag);
  uint32_t *order = mx_alloc((M->ncells + 1) * sizeof *order);
  if (!tag || !order ||
      mx_cells_in_order(M->type, by_body ? M->cell_body : NULL, M->nbodies, M->ncells, order)) {
    mx_free(tag);
    mx_free(order);
    return NULL;
  }
  for (size_t i = 0; i < M->ncells; i++) tag[order[i]] = i + 1;
  mx_free(order);
  return tag;
}

enum { PLANE_SURF = 1, PLANE_CURVE = 1, PHYS_DOMAIN = 1, PHYS_BOUNDARY = 2 };

static size_t fill_plane_node_tags(const void *v, size_t b, size_t e, char *o) {
  const plane_ctx *x = v;
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

static size_t fill_plane_coords(const void *v, size_t b, size_t e, char *o) {
  const plane_ctx *x = v;
  size_t n = 0;
  for (size_t i = b; i < e; i++) {
    const double *p = x->M->xyz + 2 * i, z = 0.0;
    if (!x->binary) {
      n += mx_plane_put_xy0(o + n, p, '\n');
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
static size_t plane_item(const plane_ctx *x, uint64_t tag, size_t c, const uint32_t *nodes, int nv,
                       char *o) {
  size_t n = 0;
  if (x->data) {
    const mx_field *fd = x->fd;
    const double d = fd->is_double ? mx_field_double(fd, c) : (double)mx_field_int(fd, c);
    if (x->binary) {
      const int32_t t = (int32_t)tag;
      memcpy(o, &t, 4);
      memcpy(o + 4, &d, 8);
      return 12;
    }
    n = mx_put_u64(o, tag);
    o[n++] = ' ';
    n += fd->is_double ? mx_put_double(o + n, d) : mx_put_i64(o + n, (int64_t)mx_field_int(fd, c));
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
  n += mx_plane_put_ids(o + n, nodes, nv, 1);
  o[n++] = '\n';
  return n;
}

/* The cells of block type x->type, scanning every cell (others skipped). */
static size_t fill_plane_cells(const void *v, size_t b, size_t e, char *o) {
  const plane_ctx *x = v;
  size_t n = 0;
  for (size_t c = b; c < e; c++)
    if (x->M->type[c] == x->type && (!x->body || x->M->cell_body[c] == x->body))
      n += plane_item(x, x->ctag[c], c, x->M->conn + 4 * c, mx_view_nv2(x->M, c), o + n);
  return n;
}

static size_t fill_plane_lines(const void *v, size_t b, size_t e, char *o) {
  const plane_ctx *x = v;
  size_t n = 0;
  for (size_t i = b + x->base; i < e + x->base; i++) {
    const size_t c = (size_t)(x->bedge[i] >> 2);
    const int s = (int)(x->bedge[i] & 3), nv = mx_view_nv2(x->M, c);
    const uint32_t ab[2] = {x->M->conn[4 * c + s], x->M->conn[4 * c + (s + 1) % nv]};
    n += plane_item(x, x->M->ncells + i + 1, c, ab, 2, o + n);
  }
  return n;
}

static int plane_bin_int(mx_afile *f, int32_t v) { return mx_afile_write(f, &v, 4); }
static int plane_bin_size(mx_afile *f, uint64_t v) { return mx_afile_write(f, &v, 8); }

static void plane_box(const mx_mesh_view *M, double box[6]) {
  double x0 = INFINITY, y0 = INFINITY, x1 = -INFINITY, y1 = -INFINITY;
#pragma omp parallel for reduction(min : x0, y0) reduction(max : x1, y1) schedule(static) \
    if (M->nnodes > 65536)
  for (size_t i = 0; i < M->nnodes; i++) {
    x0 = mx_min(x0, M->xyz[2 * i]), x1 = mx_max(x1, M->xyz[2 * i]);
    y0 = mx_min(y0, M->xyz[2 * i + 1]), y1 = mx_max(y1, M->xyz[2 * i + 1]);
  }
  if (M->nnodes == 0) x0 = y0 = x1 = y1 = 0.0;
  const double b[6] = {x0, y0, 0.0, x1, y1, 0.0};
  memcpy(box, b, sizeof b);
}

/* One entity: tag, box, one physical tag, no bounding entities. */
static int plane_entity(mx_afile *f, const double box[6], int phys, int binary) {
  if (binary) {
    MX_CHECK(plane_bin_int(f, 1));
    MX_CHECK(mx_afile_write(f, box, 6 * sizeof *box));
    MX_CHECK(plane_bin_size(f, 1));
    MX_CHECK(plane_bin_int(f, phys));
    return plane_bin_size(f, 0);
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

static int plane_head(mx_afile *f, const mx_mesh_view *M, int binary) {
  MX_CHECK(mx_afile_printf(f, "$MeshFormat\n4.1 %d 8\n", binary));
  if (binary) {
    MX_CHECK(plane_bin_int(f, 1));
    MX_CHECK(mx_afile_write(f, "\n", 1));
  }
  MX_CHECK(mx_afile_printf(f, "$EndMeshFormat\n$PhysicalNames\n2\n2 %d \"domain\"\n"
                              "1 %d \"boundary\"\n$EndPhysicalNames\n$Entities\n",
                           PHYS_DOMAIN, PHYS_BOUNDARY));
  double box[6];
  plane_box(M, box);
  if (binary) {
    const uint64_t counts[4] = {0, 1, 1, 0};
    MX_CHECK(mx_afile_write(f, counts, sizeof counts));
  } else {
    MX_CHECK(mx_afile_printf(f, "0 1 1 0\n"));
  }
  MX_CHECK(plane_entity(f, box, PHYS_BOUNDARY, binary)); /* the curve (PLANE_CURVE) */
  MX_CHECK(plane_entity(f, box, PHYS_DOMAIN, binary));   /* the surface (PLANE_SURF) */
  if (binary) MX_CHECK(mx_afile_write(f, "\n", 1));
  return mx_afile_printf(f, "$EndEntities\n");
}

/* Four numbers: as text on a line, or as size_t. */
static int plane_four(mx_afile *f, const uint64_t v[4], int binary) {
  if (binary) return mx_afile_write(f, v, 4 * sizeof *v);
  return mx_afile_printf(f, "%llu %llu %llu %llu\n", (unsigned long long)v[0],
                         (unsigned long long)v[1], (unsigned long long)v[2],
                         (unsigned long long)v[3]);
}

static int plane_block_head(mx_afile *f, int dim, int tag, int type, size_t n, int binary) {
  if (!binary) return mx_afile_printf(f, "%d %d %d %zu\n", dim, tag, type, n);
  MX_CHECK(plane_bin_int(f, dim));
  MX_CHECK(plane_bin_int(f, tag));
  MX_CHECK(plane_bin_int(f, type));
  return plane_bin_size(f, n);
}

static int plane_nodes(mx_afile *f, const mx_mesh_view *M, plane_ctx *x) {
  const uint64_t nn = M->nnodes, head[4] = {nn > 0, nn, nn > 0, nn};
  MX_CHECK(mx_afile_printf(f, "$Nodes\n"));
  MX_CHECK(plane_four(f, head, x->binary));
  if (nn) {
    MX_CHECK(plane_block_head(f, 2, PLANE_SURF, 0, nn, x->binary));
    MX_CHECK(mx_afile_emit(f, nn, MX_U64_CHARS + 1, fill_plane_node_tags, x));
    MX_CHECK(mx_afile_emit(f, nn, MX_XY0_MAX, fill_plane_coords, x));
  }
  if (x->binary) MX_CHECK(mx_afile_write(f, "\n", 1));
  return mx_afile_printf(f, "$EndNodes\n");
}

/* The blocks (triangles, quadrilaterals, lines), as elements or as one
 * field's data lines (x->data). */
static int plane_blocks(mx_afile *f, const size_t count[3], size_t nb, plane_ctx *x) {
  const size_t line = MX_U64_CHARS + MX_DOUBLE_CHARS + 2 > 5 * (MX_U64_CHARS + 1)
                          ? MX_U64_CHARS + MX_DOUBLE_CHARS + 2
                          : 5 * (MX_U64_CHARS + 1);
  for (int t = MX_CELL_TRI; t <= MX_CELL_QUAD; t++) {
    if (!count[t]) continue;
    if (!x->data) MX_CHECK(plane_block_head(f, 2, PLANE_SURF, t == MX_CELL_TRI ? 2 : 3, count[t],
                                          x->binary));
    x->type = t;
    MX_CHECK(mx_afile_emit(f, x->M->ncells, line, fill_plane_cells, x));
  }
  if (!nb) return MX_OK;
  if (!x->data) MX_CHECK(plane_block_head(f, 1, PLANE_CURVE, 1, nb, x->binary));
  return mx_afile_emit(f, nb, line, fill_plane_lines, x);
}

static int plane_elements(mx_afile *f, const mx_mesh_view *M, size_t nb, plane_ctx *x) {
  const size_t nq = mx_plane_count_quads(M), count[3] = {M->ncells - nq, nq, nb};
  const uint64_t ne = M->ncells + nb;
  const uint64_t head[4] = {(uint64_t)(count[0] > 0) + (count[1] > 0) + (nb > 0), ne, ne > 0, ne};
  MX_CHECK(mx_afile_printf(f, "$Elements\n"));
  MX_CHECK(plane_four(f, head, x->binary));
  x->data = 0;
  MX_CHECK(plane_blocks(f, count, nb, x));
  if (x->binary) MX_CHECK(mx_afile_write(f, "\n", 1));
  MX_CHECK(mx_afile_printf(f, "$EndElements\n"));
  /* one $ElementData per field, over every element in file order */
  x->data = 1;
  for (int k = 0; k < M->ncell_fields; k++) {
    x->fd = &M->cell_fields[k];
    MX_CHECK(mx_afile_printf(f, "$ElementData\n1\n\"%s\"\n1\n0\n3\n0\n1\n%llu\n",
                             x->fd->name, (unsigned long long)ne));
    MX_CHECK(plane_blocks(f, count, nb, x));
    if (x->binary) MX_CHECK(mx_afile_write(f, "\n", 1));
    MX_CHECK(mx_afile_printf(f, "$EndElementData\n"));
  }
  return MX_OK;
}

/* ---- a 2D view with bodies (several materials) ----------------------------
 *
 * One surface entity per body (tag b, in the physical group of the body's
 * number, named after it), the cells of each body in one block per type;
 * curve entities: tag 1 (physical 1 "boundary") the boundary edges, then
 * one per pair of bodies that touch (tags 2, 3, ..., physical the same,
 * "interface A | B" after their names) holding the edges between them,
 * each once, oriented as in the cell of the lower body. The nodes in one
 * block on surface 1. Element tags as above: the cells' positions in the
 * file, per body and type, the lines after, in the order written. */

enum { MAX_PAIRS = 4096 };

typedef struct {
  size_t nb, ni;      /* boundary lines, interface lines (after them in bedge) */
  int npairs;
  uint32_t pair[MAX_PAIRS]; /* lower << 8 | higher */
  size_t p0[MAX_PAIRS + 1]; /* the first line of each pair in bedge (and the end) */
} plane_tags;

static int plane_tag_head(mx_afile *f, const mx_mesh_view *M, const plane_tags *T, int binary) {
  MX_CHECK(mx_afile_printf(f, "$MeshFormat\n4.1 %d 8\n", binary));
  if (binary) {
    MX_CHECK(plane_bin_int(f, 1));
    MX_CHECK(mx_afile_write(f, "\n", 1));
  }
  MX_CHECK(mx_afile_printf(f, "$EndMeshFormat\n$PhysicalNames\n%d\n",
                           M->nbodies + 1 + T->npairs));
  for (int b = 1; b <= M->nbodies; b++)
    MX_CHECK(mx_afile_printf(f, "2 %d \"%s\"\n", M->body_physical ? M->body_physical[b - 1] : b,
                             M->body_names[b - 1]));
  MX_CHECK(mx_afile_printf(f, "1 1 \"boundary\"\n"));
  for (int p = 0; p < T->npairs; p++)
    MX_CHECK(mx_afile_printf(f, "1 %d \"interface %s | %s\"\n", p + 2,
                             M->body_names[(T->pair[p] >> 8) - 1],
                             M->body_names[(T->pair[p] & 0xff) - 1]));
  MX_CHECK(mx_afile_printf(f, "$EndPhysicalNames\n$Entities\n"));
  double box[6];
  plane_box(M, box);
  const uint64_t counts[4] = {0, (uint64_t)(1 + T->npairs), (uint64_t)M->nbodies, 0};
  if (binary) MX_CHECK(mx_afile_write(f, counts, sizeof counts));
  else MX_CHECK(plane_four(f, counts, 0));
  for (int t = 1; t <= 1 + T->npairs; t++) MX_CHECK(write_entity(f, t, box, t, binary));
  for (int b = 1; b <= M->nbodies; b++)
    MX_CHECK(write_entity(f, b, box, M->body_physical ? M->body_physical[b - 1] : b, binary));
  if (binary) MX_CHECK(mx_afile_write(f, "\n", 1));
  return mx_afile_printf(f, "$EndEntities\n");
}

/* Every block (per body and type, then the lines per curve), as elements
 * or as one field's data lines (x->data). */
static int plane_tag_blocks(mx_afile *f, const size_t *count, const plane_tags *T, plane_ctx *x) {
  const size_t line = MX_U64_CHARS + MX_DOUBLE_CHARS + 2 > 5 * (MX_U64_CHARS + 1)
                          ? MX_U64_CHARS + MX_DOUBLE_CHARS + 2
                          : 5 * (MX_U64_CHARS + 1);
  for (int b = 1; b <= x->M->nbodies; b++)
    for (int t = MX_CELL_TRI; t <= MX_CELL_QUAD; t++) {
      const size_t n = count[2 * (size_t)b + (size_t)t];
      if (!n) continue;
      if (!x->data) MX_CHECK(plane_block_head(f, 2, b, t == MX_CELL_TRI ? 2 : 3, n, x->binary));
      x->type = t, x->body = b;
      MX_CHECK(mx_afile_emit(f, x->M->ncells, line, fill_plane_cells, x));
    }
  x->body = 0;
  for (int g = 0; g <= T->npairs; g++) {
    const size_t a = g ? T->p0[g - 1] : 0, e = g ? T->p0[g] : T->nb;
    if (a == e) continue;
    if (!x->data) MX_CHECK(plane_block_head(f, 1, g + 1, 1, e - a, x->binary));
    x->base = a;
    MX_CHECK(mx_afile_emit(f, e - a, line, fill_plane_lines, x));
  }
  x->base = 0;
  return MX_OK;
}

static int plane_tag_elements(mx_afile *f, const mx_mesh_view *M, const plane_tags *T,
                              plane_ctx *x) {
  const size_t nbk = 2 * ((size_t)M->nbodies + 1);
  size_t *count = mx_calloc(nbk * sizeof *count);
  if (!count) return MX_ENOMEM;
  for (size_t c = 0; c < M->ncells; c++) count[2 * (size_t)M->cell_body[c] + M->type[c]]++;
  uint64_t nblocks = 0;
  for (size_t i = 2; i < nbk; i++) nblocks += count[i] > 0;
  for (int g = 0; g <= T->npairs; g++) nblocks += (g ? T->p0[g] - T->p0[g - 1] : T->nb) > 0;
  const uint64_t ne = M->ncells + T->nb + T->ni, head[4] = {nblocks, ne, ne > 0, ne};
  int st = mx_afile_printf(f, "$Elements\n");
  if (!st) st = plane_four(f, head, x->binary);
  x->data = 0;
  if (!st) st = plane_tag_blocks(f, count, T, x);
  if (!st && x->binary) st = mx_afile_write(f, "\n", 1);
  if (!st) st = mx_afile_printf(f, "$EndElements\n");
  x->data = 1;
  for (int k = 0; !st && k < M->ncell_fields; k++) {
    x->fd = &M->cell_fields[k];
    st = mx_afile_printf(f, "$ElementData\n1\n\"%s\"\n1\n0\n3\n0\n1\n%llu\n", x->fd->name,
                         (unsigned long long)ne);
    if (!st) st = plane_tag_blocks(f, count, T, x);
    if (!st && x->binary) st = mx_afile_write(f, "\n", 1);
    if (!st) st = mx_afile_printf(f, "$EndElementData\n");
  }
  mx_free(count);
  return st;
}

static int write_plane_tagged(mx_afile *f, const mx_mesh_view *M, int binary) {
  uint64_t *bedge = NULL, *iedge = NULL, *all = NULL;
  uint32_t *pair = NULL;
  size_t nb = 0, ni = 0;
  plane_tags *T = mx_calloc(sizeof *T);
  int st = T ? mx_plane_boundary_edges(M, &bedge, &nb) : MX_ENOMEM;
  if (!st) st = mx_plane_interface_edges(M, M->cell_body, &iedge, &pair, &ni);
  if (!st && !(all = mx_alloc((nb + ni + 1) * sizeof *all))) st = MX_ENOMEM;
  if (!st) {
    memcpy(all, bedge, nb * sizeof *all);
    memcpy(all + nb, iedge, ni * sizeof *all);
    T->nb = nb, T->ni = ni;
    for (size_t i = 0; i < ni; i++) {
      if (T->npairs && T->pair[T->npairs - 1] == pair[i]) continue;
      if (T->npairs == MAX_PAIRS) {
        st = MX_EINTERNAL;
        break;
      }
      T->p0[T->npairs] = nb + i;
      T->pair[T->npairs++] = pair[i];
    }
    T->p0[T->npairs] = nb + ni;
  }
  plane_ctx x = {.M = M, .binary = binary, .bedge = all};
  if (!st && !(x.ctag = plane_cell_tags(M, 1))) st = MX_ENOMEM;
  if (!st) st = plane_tag_head(f, M, T, binary);
  if (!st) st = plane_nodes(f, M, &x);
  if (!st) st = plane_tag_elements(f, M, T, &x);
  mx_free(bedge), mx_free(iedge), mx_free(all), mx_free(pair), mx_free(T);
  mx_free((void *)x.ctag);
  return st;
}

static int write_plane_body(mx_afile *f, const mx_mesh_view *M, int binary) {
  if (M->cell_body && M->nbodies > 0 && M->body_names) return write_plane_tagged(f, M, binary);
  uint64_t *bedge = NULL;
  size_t nb = 0;
  MX_CHECK(mx_plane_boundary_edges(M, &bedge, &nb));
  plane_ctx x = {.M = M, .binary = binary, .bedge = bedge};
  int st = (x.ctag = plane_cell_tags(M, 0)) ? MX_OK : MX_ENOMEM;
  if (!st) st = plane_head(f, M, binary);
  if (!st) st = plane_nodes(f, M, &x);
  if (!st) st = plane_elements(f, M, nb, &x);
  mx_free(bedge);
  mx_free((void *)x.ctag);
  return st;
}

int mx_write_msh(const char *path, const mx_mesh_view *m, int binary) {
  MX_CHECK(mx_mesh_view_check(path, m));
  mx_afile f;
  MX_CHECK(mx_afile_open(&f, path));
  if (mx_view_is_2d(m)) return mx_afile_finish(&f, write_plane_body(&f, m, binary));
  return mx_afile_finish(&f, write_body(&f, m, binary));
}
