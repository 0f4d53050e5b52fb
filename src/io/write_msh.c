/* mixoct: Gmsh MSH 4.1 writer, ASCII ("4.1 0 8") or binary ("4.1 1 8").
 *
 * Layout: $MeshFormat, $PhysicalNames (one volume group, tag 1, "domain"),
 * $Entities (one volume, tag 1, with its bounding box and that physical
 * group), $Nodes (one block on the volume holding every node, tags 1..N in
 * the mesh's order), $Elements (one block per element type present, in the
 * order tet, pyramid, prism, hex; an element's tag is its index in the
 * mesh + 1, so tags match the cell order of the other formats).
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
 * soa/mesh.h and kernels/quality.c) follow the same rule: the pyramid base
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
 * ASCII doubles read back exactly (see mx_put_double in io/text_num.h). */
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "common.h"
#include "io/atomic_file.h"
#include "io/text_num.h"
#include "soa/mesh.h"

/* Gmsh element type per mixoct type, and mixoct's node j of Gmsh's node k. */
static const int msh_type[4] = {4, 7, 6, 5};
static const int8_t msh_perm[4][8] = {{0, 1, 2, 3, 0, 0, 0, 0},
                                      {0, 1, 2, 3, 4, 0, 0, 0},
                                      {0, 1, 2, 3, 4, 5, 0, 0},
                                      {0, 1, 2, 3, 4, 5, 6, 7}};

enum {
  ENTITY_TAG = 1,
  PHYSICAL_TAG = 1,
};

typedef struct {
  const mx_mesh_view *m;
  int type; /* element section: the mixoct type of this block */
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

/* ---- elements: every cell is an item, the ones of other types write
 * nothing, so a block keeps the mesh's order within its type. -------------- */

static size_t fill_elements_bin(const void *vctx, size_t b, size_t e,
                                char *out) {
  const msh_ctx *ctx = vctx;
  const mx_mesh_view *m = ctx->m;
  const int t = ctx->type, nn = mx_cell_nodes[t];
  const int8_t *perm = msh_perm[t];
  size_t n = 0;
  for (size_t c = b; c < e; c++) {
    if (m->type[c] != t) continue;
    const uint32_t *row = m->conn + 8 * c;
    put_size(out + n, (uint64_t)c + 1);
    n += 8;
    for (int k = 0; k < nn; k++, n += 8)
      put_size(out + n, (uint64_t)row[perm[k]] + 1);
  }
  return n;
}

static size_t fill_elements_ascii(const void *vctx, size_t b, size_t e,
                                  char *out) {
  const msh_ctx *ctx = vctx;
  const mx_mesh_view *m = ctx->m;
  const int t = ctx->type, nn = mx_cell_nodes[t];
  const int8_t *perm = msh_perm[t];
  size_t n = 0;
  for (size_t c = b; c < e; c++) {
    if (m->type[c] != t) continue;
    const uint32_t *row = m->conn + 8 * c;
    n += mx_put_u64(out + n, (uint64_t)c + 1);
    for (int k = 0; k < nn; k++) {
      out[n++] = ' ';
      n += mx_put_u64(out + n, (uint64_t)row[perm[k]] + 1);
    }
    out[n++] = '\n';
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

static int write_header(mx_afile *f, int binary) {
  MX_CHECK(mx_afile_printf(f, "$MeshFormat\n4.1 %d 8\n", binary ? 1 : 0));
  if (binary) {
    MX_CHECK(write_bin_int(f, 1));
    MX_CHECK(mx_afile_write(f, "\n", 1));
  }
  return mx_afile_printf(f,
                         "$EndMeshFormat\n$PhysicalNames\n1\n3 %d \"domain\"\n"
                         "$EndPhysicalNames\n",
                         PHYSICAL_TAG);
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

/* One volume (dim 3, tag ENTITY_TAG) in physical group PHYSICAL_TAG, with no
 * bounding surfaces; no points, curves or surfaces. */
static int write_entities(mx_afile *f, const mx_mesh_view *m, int binary) {
  double box[6];
  bounding_box(m, box);
  MX_CHECK(mx_afile_printf(f, "$Entities\n"));
  if (binary) {
    for (int k = 0; k < 3; k++) MX_CHECK(write_bin_size(f, 0));
    MX_CHECK(write_bin_size(f, 1));
    MX_CHECK(write_bin_int(f, ENTITY_TAG));
    MX_CHECK(write_bin(f, box, sizeof box));
    MX_CHECK(write_bin_size(f, 1));
    MX_CHECK(write_bin_int(f, PHYSICAL_TAG));
    MX_CHECK(write_bin_size(f, 0));
    MX_CHECK(mx_afile_write(f, "\n", 1));
  } else {
    char line[6 * (MX_DOUBLE_CHARS + 1) + 64];
    size_t n = (size_t)snprintf(line, sizeof line, "0 0 0 1\n%d", ENTITY_TAG);
    for (int k = 0; k < 6; k++) {
      line[n++] = ' ';
      n += mx_put_double(line + n, box[k]);
    }
    n += (size_t)snprintf(line + n, sizeof line - n, " 1 %d 0\n", PHYSICAL_TAG);
    MX_CHECK(mx_afile_write(f, line, n));
  }
  return mx_afile_printf(f, "$EndEntities\n");
}

static int write_nodes(mx_afile *f, const mx_mesh_view *m, int binary) {
  const size_t nn = m->nnodes;
  const size_t nblocks = nn > 0;
  const size_t tag_min = nn > 0, tag_max = nn;
  msh_ctx ctx = {m, 0};
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

static void count_types(const mx_mesh_view *m, size_t count[4]) {
  size_t c0 = 0, c1 = 0, c2 = 0, c3 = 0;
#pragma omp parallel for reduction(+ : c0, c1, c2, c3) schedule(static) \
    if (m->ncells > 65536)
  for (size_t c = 0; c < m->ncells; c++) {
    switch (m->type[c]) {
      case MX_TET: c0++; break;
      case MX_PYRAMID: c1++; break;
      case MX_PRISM: c2++; break;
      default: c3++; break;
    }
  }
  count[0] = c0, count[1] = c1, count[2] = c2, count[3] = c3;
}

static int write_elements(mx_afile *f, const mx_mesh_view *m, int binary) {
  size_t count[4];
  count_types(m, count);
  size_t nblocks = 0;
  for (int t = 0; t < 4; t++) nblocks += count[t] > 0;
  const size_t ne = m->ncells, tag_min = ne > 0, tag_max = ne;
  MX_CHECK(mx_afile_printf(f, "$Elements\n"));
  if (binary) {
    const uint64_t head[4] = {nblocks, ne, tag_min, tag_max};
    MX_CHECK(write_bin(f, head, sizeof head));
  } else {
    MX_CHECK(mx_afile_printf(f, "%zu %zu %zu %zu\n", nblocks, ne, tag_min,
                             tag_max));
  }
  for (int t = 0; t < 4; t++) {
    if (count[t] == 0) continue;
    msh_ctx ctx = {m, t};
    size_t per_cell = (size_t)mx_cell_nodes[t] + 1;
    if (binary) {
      MX_CHECK(write_bin_int(f, 3));
      MX_CHECK(write_bin_int(f, ENTITY_TAG));
      MX_CHECK(write_bin_int(f, msh_type[t]));
      MX_CHECK(write_bin_size(f, count[t]));
      MX_CHECK(mx_afile_emit(f, ne, 8 * per_cell, fill_elements_bin, &ctx));
    } else {
      MX_CHECK(mx_afile_printf(f, "3 %d %d %zu\n", ENTITY_TAG, msh_type[t],
                               count[t]));
      MX_CHECK(mx_afile_emit(f, ne, (MX_U64_CHARS + 1) * per_cell,
                             fill_elements_ascii, &ctx));
    }
  }
  if (binary) MX_CHECK(mx_afile_write(f, "\n", 1));
  return mx_afile_printf(f, "$EndElements\n");
}

static int write_body(mx_afile *f, const mx_mesh_view *m, int binary) {
  MX_CHECK(write_header(f, binary));
  MX_CHECK(write_entities(f, m, binary));
  MX_CHECK(write_nodes(f, m, binary));
  return write_elements(f, m, binary);
}

int mx_write_msh(const char *path, const mx_mesh_view *m, int binary) {
  MX_CHECK(mx_mesh_view_check(path, m));
  mx_afile f;
  MX_CHECK(mx_afile_open(&f, path));
  return mx_afile_finish(&f, write_body(&f, m, binary));
}
