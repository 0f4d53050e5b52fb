/* The assembly step of the VTK readers (declared in io/vtk_cells.h): points,
 * cell types and connectivity (a count-prefixed list, or offsets +
 * connectivity) converted and validated in parallel; the triangles and
 * quadrilaterals of a planar read turned into faces; surface_tag and
 * material. */
#include "io/vtk_cells.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "base/common.h"

/* Cell types while assembling: ours (MX_TET .. MX_HEX) and VTK's
 * triangle and quadrilateral (A_TRI, A_QUAD), vertex and line (A_VERT,
 * A_LINE). Beside volume cells, triangles and quadrilaterals become the
 * tagged faces and vertices and lines are skipped (mixed_cells: Gmsh's .vtk
 * has a volume mesh's boundary faces); without volume cells, a planar read
 * turns triangles and quadrilaterals into a 2D mesh (planar_cells). */
enum { A_TRI = 4, A_QUAD = 5, A_VERT = 6, A_LINE = 7 };
static const int any_nodes[8] = {4, 5, 6, 8, 3, 4, 1, 2};

static int vtk_to_mx(int64_t code) {
  switch (code) {
    case 10: return MX_TET;
    case 14: return MX_PYRAMID;
    case 13: return MX_PRISM;
    case 12: return MX_HEX;
    case 5: return A_TRI;
    case 9: return A_QUAD;
    case 1: return A_VERT;
    case 3: return A_LINE;
    default: return -1;
  }
}

static const char *const type_word[8] = {"tetrahedron", "pyramid", "wedge", "hexahedron",
                                         "triangle", "quadrilateral", "vertex", "line"};

/* Cell c of the offsets form into row; 0 if fine, else 1 and (when msg is
 * not NULL) the reason. */
static int offset_cell(const parts *P, size_t c, int type, uint32_t *row,
                       char *msg) {
  int64_t s, e;
  if (P->vtu_offsets) {
    s = c ? raw_int(&P->off, c - 1) : 0;
    e = raw_int(&P->off, c);
  } else {
    s = raw_int(&P->off, c);
    e = raw_int(&P->off, c + 1);
  }
  const int64_t need = any_nodes[type];
  if (s < 0 || e < s || (uint64_t)e > P->cn.n) {
    if (msg)
      snprintf(msg, MSG,
               "cell %zu: offsets %lld..%lld are not an increasing range "
               "inside the %zu connectivity entries",
               c, (long long)s, (long long)e, P->cn.n);
    return 1;
  }
  if (e - s != need) {
    if (msg)
      snprintf(msg, MSG, "cell %zu (%s) has %lld nodes, expected %lld", c,
               type_word[type], (long long)(e - s), (long long)need);
    return 1;
  }
  for (int j = 0; j < 8; j++) row[j] = 0;
  for (int64_t j = 0; j < need; j++) {
    int64_t v = raw_int(&P->cn, (size_t)(s + j));
    if (v < 0 || v >= (int64_t)UINT32_MAX) {
      if (msg)
        snprintf(msg, MSG, "cell %zu: node index %lld out of range", c,
                 (long long)v);
      return 1;
    }
    row[j] = (uint32_t)v;
  }
  return 0;
}

/* A planar read: the triangles and quadrilaterals of a mesh that has no
 * volume cell and lies in the plane z = 0 become its faces (tag 0, the
 * file's node order), and ncells 0: a 2D mesh (io/read_mesh.h: mx_read_mesh_dim). Both
 * kinds of cells in one file, or a 2D cell off the plane, are errors. */
static int planar_cells(rd *r, const parts *P, mx_mesh_data *out) {
  const size_t nc = out->ncells, nn = out->nnodes;
  size_t flat = SIZE_MAX, solid = SIZE_MAX, offz = SIZE_MAX;
#pragma omp parallel for schedule(static) reduction(min : flat, solid) \
    if (nc > 65536)
  for (size_t c = 0; c < nc; c++) {
    if (out->type[c] >= A_TRI) {
      if (c < flat) flat = c;
    } else if (c < solid) {
      solid = c;
    }
  }
  if (flat == SIZE_MAX) return MX_OK;
  if (solid != SIZE_MAX) {
    const size_t later = flat > solid ? flat : solid;
    return mx_rd_fail(r, mx_rd_arr_at(r, &P->types, later),
                      "cell %zu is a %s and cell %zu a %s: a mesh is either 2D "
                      "(triangles and quadrilaterals) or 3D (volume cells)",
                      flat, type_word[out->type[flat]], solid,
                      type_word[out->type[solid]]);
  }
#pragma omp parallel for schedule(static) reduction(min : offz) if (nn > 65536)
  for (size_t i = 0; i < nn; i++)
    if (out->xyz[3 * i + 2] != 0.0 && i < offz) offz = i;
  if (offz != SIZE_MAX)
    return mx_rd_fail(r, mx_rd_arr_at(r, &P->pts, 3 * offz + 2),
                      "point %zu has z = %g: a mesh of triangles and "
                      "quadrilaterals is read as a 2D mesh, in the plane z = 0",
                      offz, out->xyz[3 * offz + 2]);
  out->face_nn = mx_alloc(nc + 1);
  out->face_conn = mx_alloc((4 * nc + 1) * sizeof *out->face_conn);
  out->face_tag = mx_calloc((nc + 1) * sizeof *out->face_tag);
  if (!out->face_nn || !out->face_conn || !out->face_tag) return MX_ENOMEM;
#pragma omp parallel for schedule(static) if (nc > 65536)
  for (size_t c = 0; c < nc; c++) {
    const int k = any_nodes[out->type[c]];
    out->face_nn[c] = (uint8_t)k;
    for (int j = 0; j < 4; j++)
      out->face_conn[4 * c + (size_t)j] = j < k ? out->conn[8 * c + (size_t)j] : 0;
  }
  out->nfaces = nc;
  out->ncells = 0;
  mx_free(out->type);
  mx_free(out->conn);
  out->type = NULL;
  out->conn = NULL;
  return MX_OK;
}

/* Volume cells and others: the triangles and quadrilaterals become the
 * faces (tag 0; mx_rd_cell_tags gives them their material value), vertices
 * and lines are dropped, the volume cells kept in order; r->cell_from and
 * r->face_from remember which cell of the file each one was. Without volume
 * cells: a 2D mesh in a planar read (planar_cells), else an error. */
static int mixed_cells(rd *r, const parts *P, mx_mesh_data *out) {
  const size_t nc = out->ncells;
  size_t nvol = 0, nflat = 0, first = SIZE_MAX, other = SIZE_MAX;
#pragma omp parallel for schedule(static) reduction(+ : nvol, nflat) \
    reduction(min : first, other) if (nc > 65536)
  for (size_t c = 0; c < nc; c++) {
    const int t = out->type[c];
    if (t < A_TRI) {
      nvol++;
      continue;
    }
    if (c < first) first = c;
    if (t == A_TRI || t == A_QUAD)
      nflat++;
    else if (c < other)
      other = c;
  }
  if (nvol == nc) return MX_OK;
  if (nvol == 0) {
    const size_t c = r->planar ? other : first;
    if (c != SIZE_MAX)
      return mx_rd_fail(r, mx_rd_arr_at(r, &P->types, c),
                        "cell %zu is a %s and the file has no volume cell: %s", c,
                        type_word[out->type[c]],
                        r->planar ? "a 2D mesh is made of triangles and quadrilaterals"
                                  : "a volume mesh is expected");
    return planar_cells(r, P, out);
  }
  void *cf, *ff;
  MX_CHECK(mx_rd_alloc(r, nvol * sizeof(uint32_t), &cf));
  MX_CHECK(mx_rd_alloc(r, (nflat + 1) * sizeof(uint32_t), &ff));
  uint32_t *cell_from = cf, *face_from = ff;
  out->face_nn = mx_alloc(nflat + 1);
  out->face_conn = mx_alloc((4 * nflat + 1) * sizeof *out->face_conn);
  out->face_tag = mx_calloc((nflat + 1) * sizeof *out->face_tag);
  if (!out->face_nn || !out->face_conn || !out->face_tag) return MX_ENOMEM;
  size_t k = 0, f = 0;
  for (size_t c = 0; c < nc; c++) {
    const int t = out->type[c];
    if (t < A_TRI) {
      out->type[k] = (uint8_t)t;
      memmove(out->conn + 8 * k, out->conn + 8 * c, 8 * sizeof *out->conn);
      cell_from[k++] = (uint32_t)c;
    } else if (t == A_TRI || t == A_QUAD) {
      const int n = any_nodes[t];
      out->face_nn[f] = (uint8_t)n;
      for (int j = 0; j < 4; j++)
        out->face_conn[4 * f + (size_t)j] = j < n ? out->conn[8 * c + (size_t)j] : 0;
      face_from[f++] = (uint32_t)c;
    }
  }
  out->ncells = nvol;
  out->nfaces = nflat;
  r->cell_from = cell_from;
  r->face_from = face_from;
  r->file_cells = nc;
  return MX_OK;
}

int mx_rd_assemble(rd *r, parts *P, mx_mesh_data *out) {
  const size_t nn = P->nnodes, nc = P->ncells;
  if (nn >= UINT32_MAX)
    return mx_rd_fail(r, NULL, "%zu points: at most %u are supported", nn,
                      UINT32_MAX - 1);
  out->nnodes = nn;
  out->ncells = nc;
  /* Points. */
  out->xyz = mx_alloc(3 * nn * sizeof(double));
  if (!out->xyz) return MX_ENOMEM;
  const rawarr *pa = &P->pts;
  size_t bad = SIZE_MAX;
  if (pa->t == T_F64 && !pa->swap) {
    memcpy(out->xyz, pa->data, 24 * nn);
  } else {
#pragma omp parallel for schedule(static) if (nn > 65536)
    for (size_t i = 0; i < 3 * nn; i++) out->xyz[i] = raw_double(pa, i);
  }
#pragma omp parallel for schedule(static) reduction(min : bad) if (nn > 65536)
  for (size_t i = 0; i < 3 * nn; i++)
    if (!isfinite(out->xyz[i]) && i < bad) bad = i;
  if (bad != SIZE_MAX)
    return mx_rd_fail(r, mx_rd_arr_at(r, pa, bad),
                      "point %zu: coordinate %zu is not a finite number", bad / 3,
                      bad % 3);
  /* Types. */
  out->type = mx_alloc(nc);
  if (!out->type) return MX_ENOMEM;
#pragma omp parallel for schedule(static) reduction(min : bad) if (nc > 65536)
  for (size_t c = 0; c < nc; c++) {
    int t = vtk_to_mx(raw_int(&P->types, c));
    out->type[c] = (uint8_t)(t < 0 ? 0 : t);
    if (t < 0 && c < bad) bad = c;
  }
  if (bad != SIZE_MAX)
    return mx_rd_fail(r, mx_rd_arr_at(r, &P->types, bad),
                      "cell %zu has VTK type %lld: only tetrahedra (10), pyramids "
                      "(14), wedges (13) and hexahedra (12) are supported, with "
                      "triangles (5) and quadrilaterals (9) as boundary faces and "
                      "vertices (1) and lines (3) skipped%s",
                      bad, (long long)raw_int(&P->types, bad),
                      r->planar ? ", or triangles and quadrilaterals in "
                            "the plane z = 0 (a 2D mesh)" : "");
  /* Connectivity. */
  if (P->list_form) {
#pragma omp parallel for schedule(static) reduction(min : bad) if (nc > 65536)
    for (size_t c = 0; c < nc; c++)
      if (P->nn[c] != any_nodes[out->type[c]] && c < bad) bad = c;
    if (bad != SIZE_MAX)
      return mx_rd_fail(r, mx_rd_arr_at(r, &P->types, bad),
                        "cell %zu (%s) has %d nodes, expected %d", bad,
                        type_word[out->type[bad]], P->nn[bad],
                        any_nodes[out->type[bad]]);
  } else {
    out->conn = mx_alloc(8 * nc * sizeof(uint32_t));
    if (!out->conn) return MX_ENOMEM;
#pragma omp parallel for schedule(static) reduction(min : bad) if (nc > 65536)
    for (size_t c = 0; c < nc; c++)
      if (offset_cell(P, c, out->type[c], out->conn + 8 * c, NULL) && c < bad)
        bad = c;
    if (bad != SIZE_MAX) {
      char msg[MSG];
      offset_cell(P, bad, out->type[bad], out->conn + 8 * bad, msg);
      return mx_rd_fail(r, mx_rd_arr_at(r, &P->off, bad), "%s", msg);
    }
    int64_t last = nc ? raw_int(&P->off, P->vtu_offsets ? nc - 1 : nc) : 0;
    if (!P->vtu_offsets && raw_int(&P->off, 0) != 0)
      return mx_rd_fail(r, NULL, "OFFSETS: the first offset is %lld, expected 0",
                        (long long)raw_int(&P->off, 0));
    if ((uint64_t)last != P->cn.n)
      return mx_rd_fail(r, NULL,
                        "the connectivity has %zu entries but the cells use %lld",
                        P->cn.n, (long long)last);
  }
  /* Node indices. */
#pragma omp parallel for schedule(static) reduction(min : bad) if (nc > 65536)
  for (size_t c = 0; c < nc; c++) {
    const uint32_t *row = out->conn + 8 * c;
    for (int j = 0; j < any_nodes[out->type[c]]; j++)
      if (row[j] >= nn && c < bad) bad = c;
  }
  if (bad != SIZE_MAX) {
    const uint32_t *row = out->conn + 8 * bad;
    uint32_t v = 0;
    for (int j = 0; j < any_nodes[out->type[bad]]; j++)
      if (row[j] >= nn) {
        v = row[j];
        break;
      }
    return mx_rd_fail(r, NULL,
                      "cell %zu uses node %u, but there are %zu points (0-based "
                      "indices)",
                      bad, v, nn);
  }
  return mixed_cells(r, P, out);
}

/* The point field surface_tag from its raw values (one per node). */
int mx_rd_node_tags(rd *r, const rawarr *a, mx_mesh_data *out) {
  const size_t n = out->nnodes;
  out->node_tag = mx_alloc((n + 1) * sizeof *out->node_tag);
  if (!out->node_tag) return MX_ENOMEM;
  for (size_t i = 0; i < n; i++) {
    const int64_t v = raw_int(a, i);
    if (v < INT32_MIN || v > INT32_MAX || (a->t == T_U64 && v < 0))
      return mx_rd_fail(r, mx_rd_arr_at(r, a, i),
                        "surface_tag: value %zu is out of range (32-bit integers)",
                        i);
    out->node_tag[i] = (int32_t)v;
  }
  return MX_OK;
}

int mx_rd_node_flags(const rawarr *a, mx_mesh_data *out) {
  const size_t n = out->nnodes;
  for (size_t i = 0; i < n; i++) {
    const int64_t v = raw_int(a, i);
    if (v != 0 && v != 1) return MX_OK;
  }
  out->node_bnd = mx_alloc(n + 1);
  if (!out->node_bnd) return MX_ENOMEM;
  for (size_t i = 0; i < n; i++) out->node_bnd[i] = (uint8_t)raw_int(a, i);
  return MX_OK;
}

/* The cell field material from its raw values (one per cell). */
int mx_rd_cell_tags(rd *r, const rawarr *a, mx_mesh_data *out) {
  const size_t n = out->ncells;
  if (n == 0) return MX_OK; /* no cells (or, in a planar read, faces) */
  const size_t nfile = r->cell_from ? r->file_cells : n;
  if (a->n != nfile) /* the readers check it first */
    return mx_rd_fail(r, NULL, "material: %zu values for %zu cells", a->n, nfile);
  out->cell_tag = mx_alloc((n + 1) * sizeof *out->cell_tag);
  if (!out->cell_tag) return MX_ENOMEM;
  for (size_t k = 0; k < n + (r->cell_from ? out->nfaces : 0); k++) {
    /* the volume cells, then (a mixed file) the faces */
    const size_t i = !r->cell_from ? k : k < n ? r->cell_from[k] : r->face_from[k - n];
    int64_t v;
    if (is_float(a->t)) {
      const double d = raw_double(a, i);
      if (!(d >= INT32_MIN && d <= INT32_MAX && d == floor(d)))
        return mx_rd_fail(r, mx_rd_arr_at(r, a, i),
                          "material: value %zu (%g) is not a whole number in the range of "
                          "32-bit integers",
                          i, d);
      v = (int64_t)d;
    } else {
      v = raw_int(a, i);
      if (v < INT32_MIN || v > INT32_MAX || (a->t == T_U64 && v < 0))
        return mx_rd_fail(r, mx_rd_arr_at(r, a, i),
                          "material: value %zu is out of range (32-bit integers)", i);
    }
    if (k < n)
      out->cell_tag[k] = (int32_t)v;
    else
      out->face_tag[k - n] = (int32_t)v;
  }
  return MX_OK;
}
