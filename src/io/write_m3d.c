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
 * double, else 17 (always exact). Nodes and elements are produced in chunks
 * filled in parallel by mx_afile_emit, so the file is the same byte for byte
 * whatever the number of threads. */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "common.h"
#include "io/atomic_file.h"
#include "soa/mesh.h"

enum {
  NODE_LINE_MAX = 80,     /* 3 doubles of at most 24 characters + blanks */
  ELEMENT_LINE_MAX = 100  /* count + 8 indices of at most 10 digits */
};

static size_t put_u64(char *out, uint64_t v) {
  char tmp[24];
  size_t n = 0;
  do {
    tmp[n++] = (char)('0' + v % 10);
    v /= 10;
  } while (v);
  for (size_t i = 0; i < n; i++) out[i] = tmp[n - 1 - i];
  return n;
}

/* The shortest of "%.15g" and "%.17g" that reads back as x (C locale: the
 * program never calls setlocale). */
static size_t put_double(char *out, double x) {
  char tmp[40];
  int n = snprintf(tmp, sizeof tmp, "%.15g", x);
  if (n <= 0 || n >= (int)sizeof tmp || strtod(tmp, NULL) != x)
    n = snprintf(tmp, sizeof tmp, "%.17g", x);
  if (n <= 0 || n >= (int)sizeof tmp) n = snprintf(tmp, sizeof tmp, "nan");
  memcpy(out, tmp, (size_t)n);
  return (size_t)n;
}

static size_t fill_nodes(const void *vctx, size_t b, size_t e, char *out) {
  const mx_mesh_view *m = vctx;
  size_t n = 0;
  for (size_t i = b; i < e; i++) {
    for (int d = 0; d < 3; d++) {
      n += put_double(out + n, m->xyz[3 * i + d]);
      out[n++] = d < 2 ? ' ' : '\n';
    }
  }
  return n;
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
      n += put_u64(out + n, row[j]);
    }
    out[n++] = '\n';
  }
  return n;
}

static int write_body(mx_afile *f, const mx_mesh_view *m) {
  MX_CHECK(mx_afile_printf(f, "[Nodes, ARRAY1<POINT3D>]\n%zu\n", m->nnodes));
  MX_CHECK(mx_afile_emit(f, m->nnodes, NODE_LINE_MAX, fill_nodes, m));
  MX_CHECK(mx_afile_printf(f, "\n[Elements, ARRAY1<STRING>]\n%zu\n",
                           m->ncells));
  return mx_afile_emit(f, m->ncells, ELEMENT_LINE_MAX, fill_elements, m);
}

int mx_write_m3d(const char *path, const mx_mesh_view *m) {
  MX_CHECK(mx_mesh_view_check(path, m));
  mx_afile f;
  MX_CHECK(mx_afile_open(&f, path));
  int status = write_body(&f, m);
  if (status != MX_OK) {
    mx_afile_abort(&f);
    return status;
  }
  return mx_afile_commit(&f);
}
