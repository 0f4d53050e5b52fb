/* mixoct: the $Nodes and $Elements of Gmsh MSH 2.2, ASCII and binary (the
 * format Gmsh writes with -format msh22 and meshio with "gmsh22"); the
 * $MeshFormat line, $PhysicalNames, the skipped sections and the ordering
 * of the cells are read_msh.c's (io/msh_reader.h).
 *
 * $MeshFormat "2.2 0|1 8" (binary: then the int 1 in the writer's byte
 * order). $Nodes: the number of nodes on a line of text, then per node its
 * tag and x y z (binary: an int and three doubles). $Elements: the number of
 * elements on a line of text, then per element
 *   tag type ntags tag_1 .. tag_ntags node_1 .. node_k
 * (ASCII: one line each); binary: blocks, each the header of three ints
 * (type, number of elements in the block, ntags) followed by that many
 * elements of 1 + ntags + k ints. tag_1 is the physical tag, tag_2 the
 * elementary (geometrical) one.
 *
 * As in 4.1: tetrahedra (4), hexahedra (5), prisms (6) and pyramids (7)
 * are kept, in the order of their element tags; triangles (2) and
 * quadrangles (3) are the tagged faces, in file order; points (15) and
 * lines (1) are skipped; any other type is refused. The label of a volume
 * element (cell_tag) and the tag of a face is its physical tag, or its
 * elementary tag when the physical tag is 0 or absent. */
#include <stdio.h>
#include <string.h>

#include "base/common.h"
#include "io/face_tags.h"
#include "io/msh_reader.h"

/* Where the next value starts, for messages (text: after the blanks;
 * binary: here, blanks are data). */
static const char *at22(msh *M) { return M->binary ? M->c.p : cur_skip(&M->c); }

/* An int: 4 bytes in binary, an integer in text. */
static int int22(msh *M, int64_t *v, const char *what) {
  if (!M->binary) return cur_int(&M->c, v, what);
  MX_CHECK(cur_need(&M->c, 4, what));
  *v = (int32_t)(uint32_t)bin_u(&M->c, 4);
  return MX_OK;
}

/* The count on the line after the section's name, and, binary, the end of
 * its line (the data starts on the next). */
static int count_line(msh *M, uint64_t *n, const char *what) {
  MX_CHECK(cur_count(&M->c, n, 0, what));
  if (!M->binary) return MX_OK;
  rd *r = M->c.r;
  const char *q = M->c.p;
  while (q < r->end && (*q == ' ' || *q == '\t' || *q == '\r')) q++;
  if (q >= r->end || *q != '\n') return mx_rd_fail(r, q, "%s: expected the end of the line", what);
  M->c.p = q + 1;
  if (!r->bin_from) r->bin_from = M->c.p;
  return MX_OK;
}

/* The count line of a section: n items of at least `least` bytes each
 * must fit in what is left of the file (and below 2^32). */
static int section_count(msh *M, const char *section, const char *noun, uint64_t least,
                         uint64_t *n) {
  const char *at = cur_skip(&M->c);
  char what[64];
  snprintf(what, sizeof what, "%s: number of %s", section, noun);
  MX_CHECK(count_line(M, n, what));
  if (*n >= UINT32_MAX || *n > cur_left(&M->c) / least + 1)
    return mx_rd_fail(M->c.r, at,
                      "%s: %llu %s announced but the file is too short "
                      "(truncated file or wrong count)",
                      section, (unsigned long long)*n, noun);
  return MX_OK;
}

int mx_msh22_nodes(msh *M) {
  rd *r = M->c.r;
  if (M->have_nodes) return mx_rd_fail(r, M->c.p, "$Nodes given twice");
  M->have_nodes = 1;
  uint64_t nn = 0;
  /* a node takes an int and 3 doubles (binary), "1 0 0 0\n" (text) */
  MX_CHECK(section_count(M, "$Nodes", "nodes", M->binary ? 28 : 8, &nn));
  if (M->binary) MX_CHECK(cur_need(&M->c, nn * 28, "$Nodes"));
  M->nnodes = (size_t)nn;
  M->out->nnodes = (size_t)nn;
  M->out->xyz = mx_alloc((3 * (size_t)nn + 1) * sizeof(double));
  M->ntag = mx_alloc(((size_t)nn + 1) * sizeof *M->ntag);
  if (!M->out->xyz || !M->ntag) return MX_ENOMEM;
  uint64_t tmin = UINT64_MAX, tmax = 0;
  for (size_t i = 0; i < nn; i++) {
    const char *tat = at22(M);
    int64_t tag = 0;
    if (M->binary)
      tag = (int32_t)(uint32_t)bin_u(&M->c, 4);
    else
      MX_CHECK(cur_int(&M->c, &tag, "$Nodes: node tag"));
    if (tag < 1) return mx_rd_fail(r, tat, "node tag %lld (tags start at 1)", (long long)tag);
    M->ntag[i] = (uint64_t)tag;
    if ((uint64_t)tag < tmin) tmin = (uint64_t)tag;
    if ((uint64_t)tag > tmax) tmax = (uint64_t)tag;
    double *q = M->out->xyz + 3 * i;
    for (int k = 0; k < 3; k++) {
      const char *vat = at22(M);
      if (M->binary)
        q[k] = bin_real(&M->c, 8);
      else
        MX_CHECK(cur_real(&M->c, &q[k], "$Nodes: coordinate"));
      if (!isfinite(q[k]))
        return mx_rd_fail(r, vat, "node %zu: coordinate %d is not a finite number", i, k);
    }
  }
  M->tmin = nn ? tmin : 0;
  M->tmax = tmax;
  MX_CHECK(mx_msh_tag_map(M));
  return mx_msh_end(M, "Nodes");
}

typedef struct {
  size_t cap; /* cells out, etag and cent can hold */
  uint64_t left; /* elements announced and not read yet */
} grow22;

/* Room for one more volume element. */
static int cell_room(msh *M, grow22 *g) {
  mx_mesh_data *out = M->out;
  if (out->ncells < g->cap) return MX_OK;
  size_t add = g->cap ? g->cap : 1024;
  if (add > g->left + 1) add = (size_t)g->left + 1; /* left < 2^32 here */
  MX_CHECK(mx_rd_grow_cells(M->c.r, out, add));
  const size_t nc = g->cap + add;
  uint64_t *et = mx_realloc(M->etag, (nc + 1) * sizeof *et);
  if (!et) return MX_ENOMEM;
  M->etag = et;
  int32_t *ce = mx_realloc(M->cent, (nc + 1) * sizeof *ce);
  if (!ce) return MX_ENOMEM;
  M->cent = ce;
  g->cap = nc;
  return MX_OK;
}

/* One element after its type: tag read, ntags tags and its nodes left. */
static int element22(msh *M, grow22 *g, const char *at, int64_t tag, int64_t type, int64_t ntags) {
  rd *r = M->c.r;
  mx_mesh_data *out = M->out;
  const int vt = mx_msh_volume_type(type);
  const int k = type > 0 && type < MSH_TYPES ? msh_type_nodes[type] : 0;
  const int face = type == 2 || type == 3;
  if (k == 0 || (vt < 0 && !face && type != 1 && type != 15))
    return mx_rd_fail(r, at,
                      "element %lld: type %lld is not supported (linear tetrahedra 4, "
                      "hexahedra 5, prisms 6, pyramids 7; points, lines, triangles and "
                      "quadrangles are skipped)",
                      (long long)tag, (long long)type);
  if (ntags < 0 || (uint64_t)ntags > cur_left(&M->c) / 2 + 1)
    return mx_rd_fail(r, at, "element %lld: %lld tags", (long long)tag, (long long)ntags);
  int64_t phys = 0, elem = 0;
  for (int64_t j = 0; j < ntags; j++) {
    int64_t v = 0;
    MX_CHECK(int22(M, &v, "$Elements: element tag list"));
    if (j == 0) phys = v;
    if (j == 1) elem = v;
  }
  const int64_t label = phys ? phys : elem;
  if (vt >= 0 || face) MX_CHECK(mx_rd_tag_range(r, at, label, "$Elements: physical tag"));
  uint32_t fv[4] = {0, 0, 0, 0};
  uint32_t *row = NULL;
  if (vt >= 0) {
    MX_CHECK(cell_room(M, g));
    row = out->conn + 8 * out->ncells;
  } else if (face) {
    MX_CHECK(mx_rd_face_room(r, out, &M->fcap, 1));
    row = fv;
  }
  for (int j = 0; j < k; j++) {
    const char *nat = at22(M);
    int64_t t = 0;
    MX_CHECK(int22(M, &t, "$Elements: node tag"));
    if (!row) continue;
    const int64_t v = t > 0 ? mx_msh_node(M, (uint64_t)t) : -1;
    if (v < 0)
      return mx_rd_fail(r, nat, "element %lld: node tag %lld is not a node",
                        (long long)tag, (long long)t);
    row[j] = (uint32_t)v;
  }
  if (face) {
    mx_rd_add_face(out, k, fv, (int32_t)label);
  } else if (vt >= 0) {
    if (tag < 0) return mx_rd_fail(r, at, "element tag %lld is negative", (long long)tag);
    out->type[out->ncells] = (uint8_t)vt;
    M->etag[out->ncells] = (uint64_t)tag;
    M->cent[out->ncells] = (int32_t)label;
    out->ncells++;
  }
  return MX_OK;
}

int mx_msh22_elements(msh *M) {
  rd *r = M->c.r;
  if (!M->have_nodes) return mx_rd_fail(r, M->c.p, "$Elements before $Nodes");
  if (M->etag) return mx_rd_fail(r, M->c.p, "$Elements given twice");
  uint64_t ne = 0;
  /* an element takes at least 4 ints (binary: tag, no tag, one node), or
   * "1 15 0 1\n" */
  MX_CHECK(section_count(M, "$Elements", "elements", M->binary ? 12 : 8, &ne));
  M->etag = mx_alloc(sizeof *M->etag); /* grows with the cells */
  if (!M->etag) return MX_ENOMEM;
  grow22 g = {0, ne};
  uint64_t done = 0;
  while (done < ne) {
    int64_t type = 0, n = 1, ntags = 0, tag = 0;
    const char *at = at22(M);
    if (M->binary) {
      MX_CHECK(int22(M, &type, "$Elements: block header"));
      MX_CHECK(int22(M, &n, "$Elements: block header"));
      MX_CHECK(int22(M, &ntags, "$Elements: block header"));
      if (n < 1 || (uint64_t)n > ne - done)
        return mx_rd_fail(r, at, "$Elements: a block of %lld elements (%llu of %llu left)",
                          (long long)n, (unsigned long long)(ne - done), (unsigned long long)ne);
      const int k = type > 0 && type < MSH_TYPES ? msh_type_nodes[type] : 0;
      if (ntags < 0 || ntags > 1000)
        return mx_rd_fail(r, at, "$Elements: a block whose elements have %lld tags",
                          (long long)ntags);
      MX_CHECK(cur_need(&M->c, (uint64_t)n * 4 * (uint64_t)(1 + ntags + k), "$Elements block"));
    }
    for (int64_t i = 0; i < n; i++) {
      const char *eat = at22(M);
      MX_CHECK(int22(M, &tag, "$Elements: element number"));
      if (!M->binary) {
        MX_CHECK(int22(M, &type, "$Elements: element type"));
        MX_CHECK(int22(M, &ntags, "$Elements: number of tags"));
      }
      MX_CHECK(element22(M, &g, eat, tag, type, ntags));
      g.left--;
    }
    done += (uint64_t)n;
  }
  return mx_msh_end(M, "Elements");
}
