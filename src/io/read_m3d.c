/* mixoct: reading the published mesher's M3D and MVM files and GetFEM
 * files (see read_mesh.h); the GetFEM reader is in read_getfem.c.
 *
 * Text tokens through the cursor (no comments), in the layouts the writers
 * write (io/write_m3d.c, io/write_getfem.c):
 *  - M3D, the published mesher's (REFERENCE.md, "Published output
 *    layouts"): "[Nodes, ARRAY1<STRING>]" N, N lines "1 x y z" (the leading
 *    integer is not used), "[Elements, ARRAY1<STRING>]" M, M lines
 *    "L i0 i1 ... a b c": L is T, P, R or H (4, 5, 6, 8 nodes), a b c three
 *    numbers (not used). mixoct's older layout is read too:
 *    "[Nodes, ARRAY1<POINT3D>]" N, N lines "x y z", "[Elements,
 *    ARRAY1<STRING>]" M, M lines "k i0 ..." with k the node count;
 *  - MVM: "MIXED" N M, N lines "x y z", M lines "L i0 i1 ...";
 *  - GetFEM: '%' comment lines, "BEGIN POINTS LIST", lines "POINT i x y z"
 *    with i = 0, 1, 2, ... in order ("POINT COUNT n" lines skipped), "END
 *    POINTS LIST", "BEGIN MESH STRUCTURE DESCRIPTION", lines "CONVEX i 'GT'
 *    n0 n1 ..." with i = 0, 1, 2, ... and GetFEM's geometric transformation
 *    ("CONVEX COUNT n" skipped), "END MESH STRUCTURE DESCRIPTION", then
 *    the regions (read_mesh.h: their faces are the tagged faces); what
 *    follows them is ignored.
 * Indices are 0-based and checked against the nodes read before them. Node
 * orders are mixoct's (prisms in Gmsh's order) but for GetFEM's pyramid and
 * hexahedron, which are reordered as io/write_getfem.c describes. Counts are
 * checked against the bytes left before anything is allocated; GetFEM's
 * items are not counted up front: its arrays grow with what was read. */
#include "io/mesh_reader.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "base/common.h"
#include "io/text_cursor.h"
#include "io/text_scan.h"

/* Nothing but blanks may follow the last element. */
static int cur_at_end(cur *c) {
  size_t n;
  const char *t = cur_tok(c, &n);
  if (n > 0)
    return mx_rd_fail(c->r, t, "unexpected '%.*s' after the last element (wrong "
                      "count?)", shown(n), t);
  if (t < c->r->end) return mx_rd_fail(c->r, t, "unexpected NUL byte");
  return MX_OK;
}

/* A count of items of at least `tokens` tokens each: they must fit in the
 * bytes left (a token and a blank take two bytes at least). */
static int cur_item_count(cur *c, uint64_t *cnt, unsigned tokens,
                          const char *what) {
  const char *at = cur_skip(c);
  MX_CHECK(cur_count(c, cnt, 0, what));
  if (*cnt > cur_left(c) / (2 * (uint64_t)tokens) + 1)
    return mx_rd_fail(c->r, at,
                      "%s: %llu announced but the file is too short (truncated "
                      "file or wrong count)",
                      what, (unsigned long long)*cnt);
  return MX_OK;
}

/* n nodes, "x y z" each, after an unused integer when `numbered`. */
static int cur_nodes(cur *c, mx_mesh_data *out, uint64_t n, int numbered) {
  if (n >= UINT32_MAX)
    return mx_rd_fail(c->r, NULL, "%llu nodes: at most %u are supported",
                      (unsigned long long)n, UINT32_MAX - 1);
  out->xyz = mx_alloc((3 * (size_t)n + 1) * sizeof(double));
  if (!out->xyz) return MX_ENOMEM;
  out->nnodes = (size_t)n;
  for (size_t i = 0; i < n; i++) {
    int64_t one = 0;
    if (numbered) MX_CHECK(cur_int(c, &one, "node"));
    for (int d = 0; d < 3; d++)
      MX_CHECK(cur_real(c, &out->xyz[3 * i + (size_t)d], "node coordinate"));
  }
  return MX_OK;
}

/* The type named by an element line's letter, -1 if none. */
static int letter_type(const char *t, size_t n) {
  if (n != 1) return -1;
  switch (*t) {
    case 'T': case 't': return MX_TET;
    case 'P': case 'p': return MX_PYRAMID;
    case 'R': case 'r': return MX_PRISM;
    case 'H': case 'h': return MX_HEX;
    default: return -1;
  }
}

/* The type with k nodes (mixoct's older M3D), -1 if none. */
static int node_count_type(int64_t k) {
  switch (k) {
    case 4: return MX_TET;
    case 5: return MX_PYRAMID;
    case 6: return MX_PRISM;
    case 8: return MX_HEX;
    default: return -1;
  }
}

/* The type word opening element line `cell`: a letter, or a node count
 * when counts is set. */
static int cur_cell_type(cur *c, int counts, size_t cell, int *type) {
  size_t n;
  const char *t = cur_tok(c, &n);
  if (n == 0)
    return mx_rd_fail(c->r, t, "element %zu: unexpected end of file (truncated "
                      "file or wrong count)", cell);
  int64_t k = 0;
  const char *e = counts ? mx_io_int(t, &k) : NULL;
  *type = counts ? (e == t + n ? node_count_type(k) : -1) : letter_type(t, n);
  if (*type >= 0) return MX_OK;
  if (counts)
    return mx_rd_fail(c->r, t, "element %zu: '%.*s' is not a node count (4, 5, 6 "
                      "or 8)", cell, shown(n), t);
  return mx_rd_fail(c->r, t, "element %zu: '%.*s' is not an element type (T, P, "
                    "R or H)", cell, shown(n), t);
}

/* M element lines "L i0 ..." (or "k i0 ..." when counts), followed by three
 * numbers when `tail`. */
static int cur_cells(cur *c, mx_mesh_data *out, uint64_t m, int counts,
                     int tail) {
  MX_CHECK(mx_rd_grow_cells(c->r, out, (size_t)m));
  for (size_t i = 0; i < m; i++) {
    int type = 0;
    MX_CHECK(cur_cell_type(c, counts, i, &type));
    MX_CHECK(mx_rd_cur_cell_nodes(c, out, i, type, NULL));
    for (int k = 0; k < 3 * tail; k++) {
      double v;
      MX_CHECK(cur_real(c, &v, "element value"));
    }
    out->ncells = i + 1;
  }
  return MX_OK;
}

int mx_rd_m3d(rd *r, const char *p, mx_mesh_data *out) {
  cur c = {r, p, 0, 0};
  MX_CHECK(mx_rd_cur_words(&c, "[Nodes,", "M3D"));
  size_t n;
  const char *t = cur_tok(&c, &n);
  const int older = tok_eq(t, n, "ARRAY1<POINT3D>]");
  if (!older && !tok_eq(t, n, "ARRAY1<STRING>]"))
    return mx_rd_fail(r, t, "M3D: expected 'ARRAY1<STRING>]' after '[Nodes,', "
                      "found '%.*s'", shown(n), t);
  uint64_t nn = 0, nc = 0;
  MX_CHECK(cur_item_count(&c, &nn, older ? 3 : 4, "node count"));
  MX_CHECK(cur_nodes(&c, out, nn, !older));
  MX_CHECK(mx_rd_cur_words(&c, "[Elements, ARRAY1<STRING>]", "M3D"));
  MX_CHECK(cur_item_count(&c, &nc, older ? 5 : 8, "element count"));
  MX_CHECK(cur_cells(&c, out, nc, older, !older));
  return cur_at_end(&c);
}

int mx_rd_mvm(rd *r, const char *p, mx_mesh_data *out) {
  cur c = {r, p, 0, 0};
  MX_CHECK(mx_rd_cur_words(&c, "MIXED", "MVM"));
  uint64_t nn = 0, nc = 0;
  MX_CHECK(cur_item_count(&c, &nn, 3, "node count"));
  MX_CHECK(cur_item_count(&c, &nc, 5, "element count"));
  MX_CHECK(cur_nodes(&c, out, nn, 0));
  MX_CHECK(cur_cells(&c, out, nc, 0, 0));
  return cur_at_end(&c);
}
