/* mixoct: M3D writer, for job scripts written for the published mixed-element
 * mesher (`mesher_roi -m`).
 *
 * NOT A DOCUMENTED FORMAT. No description of the published mesher's M3D
 * files could be found (searched: this project's DESIGN.md and REFERENCE.md,
 * the 2015 and 2021 papers, public documentation pages and issue trackers),
 * and the published mesher's sources are GPL and not read here. What follows is
 * mixoct's own layout, a labelled guess: it reuses the section syntax of the
 * MDL surfaces the same mesher reads (REFERENCE.md: a "[Name, TYPE]" header,
 * the item count on the next line, then one item a line), so a reader of
 * one can read the other. Files from the published mesher may differ; do not
 * rely on byte compatibility with them.
 *
 *   [Nodes, ARRAY1<POINT3D>]
 *   <n>
 *   x y z                        (n lines; the node of line k is node k)
 *   <blank line>
 *   [Elements, ARRAY1<STRING>]
 *   <m>
 *   <k> i0 ... i(k-1)            (m lines)
 *
 * k is the element's node count and names its type: 4 tetrahedron,
 * 5 pyramid, 6 prism, 8 hexahedron. Indices are 0-based. Node order is
 * VTK's (the order of src/soa/mesh.h, unchanged): the tetrahedron's 0 1 2
 * counter-clockwise seen from 3, the pyramid's base 0 1 2 3 counter-
 * clockwise seen from the apex 4, the prism's 0 1 2 counter-clockwise seen
 * from 3 4 5 (3 4 5 above 0 1 2), the hexahedron's 0 1 2 3 counter-clockwise
 * seen from 4 5 6 7 (4 5 6 7 above 0 1 2 3); the volume of a valid element is
 * positive in that convention. Cell fields are not written.
 *
 * Doubles are ASCII, 15 significant digits when that reads back to the same
 * double, else 17 (always exact; mx_put_double of io/text_num.h, laid out
 * like "%g"). Nodes and elements are produced in chunks filled in parallel
 * by mx_afile_emit, so the file is the same byte for byte whatever the
 * number of threads. */
#include <stdint.h>

#include "common.h"
#include "io/atomic_file.h"
#include "io/text_num.h"
#include "soa/mesh.h"

enum { ELEMENT_LINE_MAX = 2 + 8 * (1 + MX_U64_CHARS) }; /* k, 8 indices, \n */

static size_t fill_nodes(const void *vctx, size_t b, size_t e, char *out) {
  return mx_put_xyz_lines(out, ((const mx_mesh_view *)vctx)->xyz, b, e);
}

static size_t fill_elements(const void *vctx, size_t b, size_t e, char *out) {
  const mx_mesh_view *m = vctx;
  size_t n = 0;
  for (size_t c = b; c < e; c++) {
    const int k = mx_cell_nodes[m->type[c]];
    const uint32_t *row = m->conn + 8 * c;
    out[n++] = (char)('0' + k);
    for (int j = 0; j < k; j++) {
      out[n++] = ' ';
      n += mx_put_u64(out + n, row[j]);
    }
    out[n++] = '\n';
  }
  return n;
}

static int write_body(mx_afile *f, const mx_mesh_view *m) {
  MX_CHECK(mx_afile_printf(f, "[Nodes, ARRAY1<POINT3D>]\n%zu\n", m->nnodes));
  MX_CHECK(mx_afile_emit(f, m->nnodes, MX_XYZ_LINE_MAX, fill_nodes, m));
  MX_CHECK(mx_afile_printf(f, "\n[Elements, ARRAY1<STRING>]\n%zu\n",
                           m->ncells));
  return mx_afile_emit(f, m->ncells, ELEMENT_LINE_MAX, fill_elements, m);
}

int mx_write_m3d(const char *path, const mx_mesh_view *m) {
  MX_CHECK(mx_mesh_view_check(path, m));
  mx_afile f;
  MX_CHECK(mx_afile_open(&f, path));
  return mx_afile_finish(&f, write_body(&f, m));
}
