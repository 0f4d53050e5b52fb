/* mixoct: the boundary faces of a mesh as a surface file of their own
 * (issue 11, `--boundary FILE.vtu`): a VTK XML UnstructuredGrid of
 * triangles (VTK type 5) and quadrilaterals (type 9), outward, with the cell
 * fields surface_tag (the input file each face lies on, 1-based) and body.
 * Only the nodes the faces use are written, in the mesh's order, with the
 * point field node (the node's 0-based index in the volume mesh), so a
 * solver can carry boundary values over. ASCII data arrays (a surface is
 * small); chunks formatted in parallel by mx_afile_emit, the bytes the same
 * whatever the thread count. */
#include <stdint.h>
#include <string.h>

#include "base/common.h"
#include "io/atomic_file.h"
#include "io/boundary_faces.h"
#include "io/text_num.h"
#include "soa/mesh.h"
#include "io/write_mesh.h"
#include "io/mesh_view_check.h"

typedef struct {
  const mx_mesh_view *m;
  const uint32_t *used;   /* the written nodes' mesh indices */
  const uint32_t *newid;  /* mesh index -> written index */
  int what;               /* which array a fill writes */
} bctx;

enum { W_POINTS, W_NODE, W_CONN, W_OFFSETS, W_TYPES, W_TAG, W_BODY };

/* Face i of the tri + quad list: its nodes, count, tag and element. */
static int face_of(const mx_boundary_faces *bf, size_t i, const uint32_t **v, int32_t *tag,
                   uint64_t *src) {
  if (i < bf->ntri) {
    *v = bf->tri + 3 * i;
    *tag = bf->tri_tag ? bf->tri_tag[i] : 1;
    *src = bf->tri_src[i];
    return 3;
  }
  i -= bf->ntri;
  *v = bf->quad + 4 * i;
  *tag = bf->quad_tag ? bf->quad_tag[i] : 1;
  *src = bf->quad_src[i];
  return 4;
}

static size_t fill(const void *vctx, size_t b, size_t e, char *out) {
  const bctx *c = vctx;
  const mx_boundary_faces *bf = c->m->bfaces;
  size_t n = 0;
  for (size_t i = b; i < e; i++) {
    if (c->what == W_POINTS) {
      n += mx_put_xyz_lines(out + n, c->m->xyz + 3 * (size_t)c->used[i], 0, 1);
      continue;
    }
    if (c->what == W_NODE) {
      n += mx_put_u64(out + n, c->used[i]);
      out[n++] = '\n';
      continue;
    }
    const uint32_t *v;
    int32_t tag;
    uint64_t src;
    const int k = face_of(bf, i, &v, &tag, &src);
    if (c->what == W_CONN) {
      for (int j = 0; j < k; j++) {
        n += mx_put_u64(out + n, c->newid[v[j]]);
        out[n++] = j + 1 < k ? ' ' : '\n';
      }
    } else if (c->what == W_OFFSETS) { /* 3 per triangle, then 4 per quad */
      const uint64_t end = i < bf->ntri ? 3 * (uint64_t)(i + 1)
                                        : 3 * (uint64_t)bf->ntri + 4 * (uint64_t)(i + 1 - bf->ntri);
      n += mx_put_u64(out + n, end);
      out[n++] = '\n';
    } else if (c->what == W_TYPES) {
      out[n++] = k == 3 ? '5' : '9';
      out[n++] = '\n';
    } else {
      const int32_t val = c->what == W_TAG ? tag : c->m->cell_body ? c->m->cell_body[src >> 3] : 1;
      n += mx_put_i64(out + n, val);
      out[n++] = '\n';
    }
  }
  return n;
}

static int array(mx_afile *f, bctx *c, int what, const char *type, const char *name, int ncomp,
                 size_t count, size_t item_max) {
  MX_CHECK(mx_afile_printf(f, "        <DataArray type=\"%s\" Name=\"%s\"", type, name));
  if (ncomp > 1) MX_CHECK(mx_afile_printf(f, " NumberOfComponents=\"%d\"", ncomp));
  MX_CHECK(mx_afile_printf(f, " format=\"ascii\">\n"));
  c->what = what;
  MX_CHECK(mx_afile_emit(f, count, item_max, fill, c));
  return mx_afile_printf(f, "        </DataArray>\n");
}

static int body(mx_afile *f, bctx *c, size_t nused) {
  const mx_boundary_faces *bf = c->m->bfaces;
  const size_t nf = bf->ntri + bf->nquad;
  MX_CHECK(mx_afile_printf(f,
                           "<?xml version=\"1.0\"?>\n"
                           "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" "
                           "byte_order=\"LittleEndian\" header_type=\"UInt64\">\n"
                           "  <UnstructuredGrid>\n"
                           "    <Piece NumberOfPoints=\"%zu\" NumberOfCells=\"%zu\">\n"
                           "      <PointData>\n",
                           nused, nf));
  MX_CHECK(array(f, c, W_NODE, "Int64", "node", 1, nused, MX_U64_CHARS + 1));
  MX_CHECK(mx_afile_printf(f, "      </PointData>\n      <CellData>\n"));
  MX_CHECK(array(f, c, W_TAG, "Int32", "surface_tag", 1, nf, MX_U64_CHARS + 1));
  MX_CHECK(array(f, c, W_BODY, "Int32", "body", 1, nf, MX_U64_CHARS + 1));
  MX_CHECK(mx_afile_printf(f, "      </CellData>\n      <Points>\n"));
  MX_CHECK(array(f, c, W_POINTS, "Float64", "Points", 3, nused, MX_XYZ_LINE_MAX));
  MX_CHECK(mx_afile_printf(f, "      </Points>\n      <Cells>\n"));
  MX_CHECK(array(f, c, W_CONN, "Int64", "connectivity", 1, nf, 4 * (MX_U64_CHARS + 1)));
  MX_CHECK(array(f, c, W_OFFSETS, "Int64", "offsets", 1, nf, MX_U64_CHARS + 1));
  MX_CHECK(array(f, c, W_TYPES, "UInt8", "types", 1, nf, 2));
  return mx_afile_printf(f, "      </Cells>\n    </Piece>\n  </UnstructuredGrid>\n</VTKFile>\n");
}

int mx_write_boundary_vtu(const char *path, const mx_mesh_view *m) {
  MX_CHECK(mx_mesh_view_check(path, m));
  const mx_boundary_faces *bf = m->bfaces;
  if (!bf) {
    mx_error(path, 0, "internal error: no boundary faces to write");
    return MX_EINTERNAL;
  }
  mx_boundary_nodes N;
  MX_CHECK(mx_boundary_nodes_number(bf, m->nnodes, &N));
  bctx c = {m, N.used, N.newid, 0};
  mx_afile f;
  int st = mx_afile_open(&f, path);
  if (!st) st = mx_afile_finish(&f, body(&f, &c, N.nused));
  mx_boundary_nodes_free(&N);
  return st;
}
