/* mixoct: reading legacy VTK unstructured grids (see read_mesh.h). The file
 * is cut into parts that point into the buffer (or into temporaries holding
 * parsed ASCII values): the points, the cells as a count-prefixed list
 * (legacy) or as offsets + connectivity (legacy 5.x), and the cell types;
 * io/vtk_cells.c then assembles them. Binary values are only read after the
 * block holding them was checked to lie in the file. Of the attributes,
 * only the point field surface_tag and the cell field material (one value
 * per cell, of any type, whole numbers: cell_tag) are read.
 *
 * mx_rd_vtk_legacy_fields reads one field instead of the mesh (for size
 * maps, io/vtk_fields.h): the same sections, POLYDATA's too, every array of
 * the attributes listed, the cells kept as the file gives them. */
#include "io/mesh_reader.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "base/common.h"
#include "io/text_scan.h"
#include "io/vtk_cells.h"
#include "io/vtk_fields.h"

typedef struct {
  rd *r;
  int binary, v5;
  const char *p;
  parts P;
  int have_points, have_cells, have_types;
  int have_node_tags, have_material;
  rawarr node_tags; /* the point field surface_tag */
  rawarr material;  /* the cell field material */
  mx_mesh_data *out;
  rd_fields *fields; /* reading one field instead of the mesh (vtk_fields.h) */
} legacy;

/* The next blank-separated token (may be empty at the end of the file). */
static const char *leg_token(legacy *L, size_t *n) {
  L->p = skip_ws(L->p, L->r->end);
  const char *t = L->p;
  *n = tok_len(t, L->r->end);
  L->p += *n;
  return t;
}

/* A count token: 1 and *v, or 0 (nothing printed) when it is not one. */
static int leg_count_q(legacy *L, size_t *v) {
  size_t n;
  const char *t = leg_token(L, &n);
  size_t x = 0;
  for (size_t i = 0; i < n; i++) {
    if (t[i] < '0' || t[i] > '9' || x > ((size_t)1 << 50)) return 0;
    x = 10 * x + (size_t)(t[i] - '0');
  }
  *v = x;
  return n > 0;
}

static int leg_count(legacy *L, size_t *v, const char *what) {
  const char *t = skip_ws(L->p, L->r->end);
  if (leg_count_q(L, v)) return MX_OK;
  const size_t n = tok_len(t, L->r->end);
  if (n == 0) return mx_rd_fail(L->r, t, "%s: missing count", what);
  return mx_rd_fail(L->r, t, "%s: bad count '%.*s'", what, shown(n), t);
}

/* Binary data starts after the newline that ends the section header. */
static int leg_data_start(legacy *L, const char *what) {
  if (!L->binary) return MX_OK;
  const char *p = L->p, *end = L->r->end;
  while (p < end && (*p == ' ' || *p == '\t' || *p == '\r')) p++;
  if (p < end && *p != '\n')
    return mx_rd_fail(L->r, p, "%s: unexpected '%.*s' after the section header",
                      what, shown(tok_len(p, end)), p);
  L->p = p < end ? p + 1 : p;
  if (!L->r->bin_from) L->r->bin_from = L->p;
  return MX_OK;
}

static vtype legacy_type(const char *t, size_t n) {
  static const struct {
    const char *name;
    vtype t;
  } map[] = {{"float", T_F32},          {"double", T_F64},
             {"int", T_I32},            {"unsigned_int", T_U32},
             {"short", T_I16},          {"unsigned_short", T_U16},
             {"char", T_I8},            {"unsigned_char", T_U8},
             {"long", T_I64},           {"unsigned_long", T_U64},
             {"vtktypeint64", T_I64},   {"vtktypeuint64", T_U64},
             {"vtktypeint32", T_I32},   {"vtktypeuint32", T_U32},
             {"vtkIdType", T_I32}};
  for (size_t i = 0; i < sizeof map / sizeof map[0]; i++)
    if (tok_eq(t, n, map[i].name)) return map[i].t;
  return T_NONE;
}

/* n values of type t: in place (binary) or parsed (ASCII). */
static int leg_array(legacy *L, size_t n, vtype t, rawarr *out,
                     const char *what) {
  MX_CHECK(leg_data_start(L, what));
  if (!L->binary)
    return mx_rd_ascii_array(L->r, &L->p, 0, n, is_float(t), out, what);
  size_t left = (size_t)(L->r->end - L->p);
  if (n > left / (size_t)vsize[t])
    return mx_rd_fail(L->r, L->p,
                      "%s: %zu values of %d bytes announced but only %zu bytes are "
                      "left (truncated file or wrong count)",
                      what, n, vsize[t], left);
  *out = (rawarr){(const unsigned char *)L->p, n, t, HOST_LE, NULL};
  L->p += n * (size_t)vsize[t];
  return MX_OK;
}

static int leg_points(legacy *L) {
  size_t n, tl;
  MX_CHECK(leg_count(L, &n, "POINTS"));
  const char *t = leg_token(L, &tl);
  vtype vt = legacy_type(t, tl);
  if (!is_float(vt))
    return mx_rd_fail(L->r, t,
                      "POINTS: type '%.*s' is not supported (float or double)",
                      shown(tl), t);
  if (L->have_points) return mx_rd_fail(L->r, t, "POINTS given twice");
  L->have_points = 1;
  L->P.nnodes = n;
  if (n >= UINT32_MAX)
    return mx_rd_fail(L->r, t, "POINTS: %zu points, at most %u are supported", n,
                      UINT32_MAX - 1);
  return leg_array(L, 3 * n, vt, &L->P.pts, "POINTS");
}

/* One integer of the classic CELLS list. */
static inline int leg_int(legacy *L, int64_t *v, size_t cell) {
  if (L->binary) { /* bounds checked by the caller */
    *v = (int32_t)(uint32_t)load_bits((const unsigned char *)L->p, 4, HOST_LE);
    L->p += 4;
    return MX_OK;
  }
  const char *p = skip_ws(L->p, L->r->end);
  if (p >= L->r->end || !*p)
    return mx_rd_fail(L->r, p, "CELLS: unexpected end of file in cell %zu", cell);
  const char *e = mx_io_int(p, v);
  size_t tl = tok_len(p, L->r->end);
  if (!e || e != p + tl)
    return mx_rd_fail(L->r, p, "CELLS: cell %zu: '%.*s' is not an integer", cell,
                      shown(tl), p);
  L->p = e;
  return MX_OK;
}

static int leg_cell_list(legacy *L, size_t size) {
  rd *r = L->r;
  const size_t nc = L->P.ncells;
  MX_CHECK(leg_data_start(L, "CELLS"));
  size_t left = (size_t)(r->end - L->p);
  if (L->binary ? size > left / 4 : size > left / 2 + 1)
    return mx_rd_fail(r, L->p,
                      "CELLS: %zu values announced but the file is too short "
                      "(truncated file or wrong count)",
                      size);
  if (nc > size / 2) /* each cell takes its count and at least one node */
    return mx_rd_fail(r, L->p, "CELLS: %zu cells cannot fit in %zu values", nc,
                      size);
  L->out->conn = mx_calloc(8 * nc * sizeof(uint32_t));
  if (!L->out->conn) return MX_ENOMEM;
  void *nn;
  MX_CHECK(mx_rd_alloc(r, nc, &nn));
  L->P.nn = nn;
  size_t used = 0;
  for (size_t c = 0; c < nc; c++) {
    const char *at = skip_ws(L->p, r->end);
    if (used >= size)
      return mx_rd_fail(r, at, "CELLS: the size %zu is used up before cell %zu",
                        size, c);
    int64_t k;
    MX_CHECK(leg_int(L, &k, c));
    if (k < 1 || k > 8)
      return mx_rd_fail(r, at,
                        "cell %zu has %lld nodes: only tetrahedra, pyramids, "
                        "wedges and hexahedra are supported",
                        c, (long long)k);
    if ((size_t)k > size - used - 1)
      return mx_rd_fail(r, at, "CELLS: cell %zu runs past the size %zu", c, size);
    uint32_t *row = L->out->conn + 8 * c;
    for (int64_t j = 0; j < k; j++) {
      at = skip_ws(L->p, r->end);
      int64_t v;
      MX_CHECK(leg_int(L, &v, c));
      if (v < 0 || v >= (int64_t)UINT32_MAX ||
          (L->have_points && (uint64_t)v >= L->P.nnodes))
        return mx_rd_fail(r, at,
                          "cell %zu: node index %lld out of range (%zu points, "
                          "0-based)",
                          c, (long long)v, L->P.nnodes);
      row[j] = (uint32_t)v;
    }
    L->P.nn[c] = (uint8_t)k;
    used += 1 + (size_t)k;
  }
  if (used != size)
    return mx_rd_fail(r, L->p, "CELLS: size %zu, but the cells use %zu values", size,
                      used);
  L->P.list_form = 1;
  return MX_OK;
}

/* Version 5: after CELLS noffsets nconn (or a POLYDATA section's header),
 * the OFFSETS and CONNECTIVITY arrays. */
static int leg_offsets(legacy *L, size_t noff, size_t nconn, rawarr *off, rawarr *cn) {
  static const char *const kw[2] = {"OFFSETS", "CONNECTIVITY"};
  rawarr *dst[2] = {off, cn};
  const size_t n[2] = {noff, nconn};
  for (int i = 0; i < 2; i++) {
    size_t tl;
    const char *t = leg_token(L, &tl);
    if (!tok_eq(t, tl, kw[i]))
      return mx_rd_fail(L->r, t, "expected %s, found '%.*s'", kw[i], shown(tl), t);
    t = leg_token(L, &tl);
    vtype vt = legacy_type(t, tl);
    if (vt == T_NONE || is_float(vt))
      return mx_rd_fail(L->r, t, "%s: type '%.*s' is not an integer type", kw[i],
                        shown(tl), t);
    MX_CHECK(leg_array(L, n[i], vt, dst[i], kw[i]));
  }
  return MX_OK;
}

/* Version 5: CELLS noffsets nconn, then OFFSETS and CONNECTIVITY arrays. */
static int leg_cell_arrays(legacy *L, size_t noff, size_t nconn) {
  MX_CHECK(leg_offsets(L, noff, nconn, &L->P.off, &L->P.cn));
  L->P.ncells = noff ? noff - 1 : 0;
  L->P.vtu_offsets = 0;
  if (noff == 0) { /* no cells at all */
    static const int64_t zero = 0;
    L->P.off = (rawarr){(const unsigned char *)&zero, 1, T_I64, 0, NULL};
  }
  return MX_OK;
}

static int leg_cells(legacy *L) {
  size_t a, b;
  const char *at = skip_ws(L->p, L->r->end);
  MX_CHECK(leg_count(L, &a, "CELLS"));
  MX_CHECK(leg_count(L, &b, "CELLS"));
  if (L->have_cells) return mx_rd_fail(L->r, at, "CELLS given twice");
  L->have_cells = 1;
  if (L->v5) return leg_cell_arrays(L, a, b);
  L->P.ncells = a;
  return leg_cell_list(L, b);
}

static int leg_types(legacy *L) {
  size_t n;
  const char *at = skip_ws(L->p, L->r->end);
  MX_CHECK(leg_count(L, &n, "CELL_TYPES"));
  if (!L->have_cells) return mx_rd_fail(L->r, at, "CELL_TYPES before CELLS");
  if (L->have_types) return mx_rd_fail(L->r, at, "CELL_TYPES given twice");
  if (n != L->P.ncells)
    return mx_rd_fail(L->r, at, "CELL_TYPES: %zu types for %zu cells", n,
                      L->P.ncells);
  L->have_types = 1;
  return leg_array(L, n, T_I32, &L->P.types, "CELL_TYPES");
}

/* METADATA blocks end at the first empty line. */
static void leg_skip_metadata(legacy *L) {
  const char *p = L->p, *end = L->r->end;
  p = memchr(p, '\n', (size_t)(end - p));
  while (p && p < end) {
    const char *q = p + 1;
    while (q < end && (*q == ' ' || *q == '\t' || *q == '\r')) q++;
    if (q >= end || *q == '\n') {
      L->p = q;
      return;
    }
    p = memchr(q, '\n', (size_t)(end - q));
  }
  L->p = end;
}

/* FIELD name n, then n arrays "name ncomp ntuples type" + values. */
static int leg_skip_field(legacy *L) {
  size_t tl, narr;
  leg_token(L, &tl); /* the field's name */
  MX_CHECK(leg_count(L, &narr, "FIELD"));
  for (size_t i = 0; i < narr; i++) {
    const char *name = leg_token(L, &tl);
    if (tok_eq(name, tl, "NULL_ARRAY")) continue;
    size_t nc, nt;
    MX_CHECK(leg_count(L, &nc, "FIELD array"));
    MX_CHECK(leg_count(L, &nt, "FIELD array"));
    const char *t = leg_token(L, &tl);
    vtype vt = legacy_type(t, tl);
    if (vt == T_NONE)
      return mx_rd_fail(L->r, t, "FIELD array of type '%.*s' cannot be skipped",
                        shown(tl), t);
    if (nt && nc > SIZE_MAX / 16 / nt)
      return mx_rd_fail(L->r, t, "FIELD array: bad size");
    if (L->binary) {
      rawarr dummy;
      MX_CHECK(leg_array(L, nc * nt, vt, &dummy, "FIELD array"));
    } else {
      for (size_t k = 0; k < nc * nt; k++) {
        const char *v = leg_token(L, &tl);
        if (tl == 0)
          return mx_rd_fail(L->r, v, "FIELD array: unexpected end of file");
      }
    }
    const char *save = L->p;
    const char *kwd = leg_token(L, &tl);
    if (tok_eq(kwd, tl, "METADATA"))
      leg_skip_metadata(L);
    else
      L->p = save;
  }
  return MX_OK;
}

/* Steps over n values of type t (binary: after the end of the header
 * line); 0, nothing printed, when they are not all there. */
static int leg_skip_values(legacy *L, size_t n, vtype t) {
  const char *p = L->p, *end = L->r->end;
  if (!L->binary) {
    for (size_t k = 0; k < n; k++) {
      size_t tl;
      leg_token(L, &tl);
      if (tl == 0) return 0;
    }
    return 1;
  }
  while (p < end && (*p == ' ' || *p == '\t' || *p == '\r')) p++;
  if (p >= end || *p != '\n') return 0;
  p++;
  if (n > (size_t)(end - p) / (size_t)vsize[t]) return 0;
  L->p = p + n * (size_t)vsize[t];
  return 1;
}

/* The values of surface_tag: n integers of type t for the points. */
static int leg_node_tags(legacy *L, const char *at, size_t n, vtype t) {
  if (L->have_node_tags) return mx_rd_fail(L->r, at, "surface_tag given twice");
  if (n != L->P.nnodes)
    return mx_rd_fail(L->r, at, "surface_tag: %zu values for %zu points", n,
                      L->P.nnodes);
  L->have_node_tags = 1;
  return leg_array(L, n, t, &L->node_tags, "surface_tag");
}

/* The values of material: n numbers of type t with ncomp components for
 * the cells. */
static int leg_material(legacy *L, const char *at, size_t n, size_t ncomp,
                        vtype t) {
  if (L->have_material) return mx_rd_fail(L->r, at, "material given twice");
  if (ncomp != 1)
    return mx_rd_fail(L->r, at, "material: %zu components, expected 1 (one label per cell)",
                      ncomp);
  if (L->have_cells && n != L->P.ncells)
    return mx_rd_fail(L->r, at, "material: %zu values for %zu cells", n, L->P.ncells);
  L->have_material = 1;
  return leg_array(L, n, t, &L->material, "material");
}

static int is_material(int point, const char *name, size_t nl) {
  return !point && tok_eq(name, nl, "material");
}

static int bad_material_type(legacy *L, const char *ty, size_t yl) {
  return mx_rd_fail(L->r, ty, "material: type '%.*s' is not a number type", shown(yl), ty);
}

/* Whether the attribute `name` of type t with ncomp components is the
 * point field surface_tag. */
static int is_surface_tag(int point, const char *name, size_t nl, vtype t,
                          size_t ncomp) {
  return point && ncomp == 1 && t != T_NONE && !is_float(t) &&
         tok_eq(name, nl, "surface_tag");
}

/* Reading a field (vtk_fields.h): an array of the attributes listed, its
 * values starting at L->p. */
static int leg_listed(legacy *L, const char *name, size_t nl, int point, size_t count,
                      size_t ncomp, vtype t) {
  rd_fields *f = L->fields;
  if (f->narr == RD_MAX_ARRAYS)
    return mx_rd_fail(L->r, name, "more than %d arrays of point and cell data", RD_MAX_ARRAYS);
  f->arr[f->narr++] = (rd_array){name, nl, point, ncomp, name, t, count, L->p};
  return MX_OK;
}

/* The attribute sections from the keyword t on (CELL_DATA n or POINT_DATA
 * n, then SCALARS, VECTORS, NORMALS, FIELD, METADATA): skipped but for
 * surface_tag and material (reading a field: every SCALARS and FIELD array
 * listed, and the keyword that ended them kept). Any other keyword, or a malformed header, ends
 * them silently (they used to be ignored whole); surface_tag and material
 * themselves must be well formed. */
static int leg_attributes(legacy *L, const char *t, size_t tl) {
  int point = 0;
  size_t count = 0;
  for (;; t = leg_token(L, &tl)) {
    if (tok_eq(t, tl, "CELL_DATA") || tok_eq(t, tl, "POINT_DATA")) {
      point = tok_eq(t, tl, "POINT_DATA");
      if (!leg_count_q(L, &count)) return MX_OK;
    } else if (tok_eq(t, tl, "SCALARS")) {
      size_t nl, yl, k = 1, ncomp = 1;
      const char *name = leg_token(L, &nl);
      const char *ty = leg_token(L, &yl);
      const vtype vt = legacy_type(ty, yl);
      if (vt == T_NONE && !L->fields && is_material(point, name, nl))
        return bad_material_type(L, ty, yl);
      if (vt == T_NONE) return MX_OK;
      const char *save = L->p, *q = L->p; /* a count on the same line */
      while (q < L->r->end && (*q == ' ' || *q == '\t')) q++;
      if (q < L->r->end && *q >= '0' && *q <= '9' && leg_count_q(L, &k) &&
          k >= 1 && k <= 4)
        ncomp = k;
      else
        L->p = save;
      save = L->p;
      const char *lt = leg_token(L, &k);
      if (tok_eq(lt, k, "LOOKUP_TABLE"))
        leg_token(L, &k);
      else
        L->p = save;
      if (L->fields) {
        MX_CHECK(leg_listed(L, name, nl, point, count, ncomp, vt));
        if (count > SIZE_MAX / 16 / ncomp || !leg_skip_values(L, count * ncomp, vt))
          return MX_OK;
      } else if (is_surface_tag(point, name, nl, vt, ncomp)) {
        MX_CHECK(leg_node_tags(L, name, count, vt));
      } else if (is_material(point, name, nl)) {
        MX_CHECK(leg_material(L, name, count, ncomp, vt));
      } else if (count > SIZE_MAX / 16 / ncomp ||
                 !leg_skip_values(L, count * ncomp, vt)) {
        return MX_OK;
      }
    } else if (tok_eq(t, tl, "VECTORS") || tok_eq(t, tl, "NORMALS")) {
      size_t nl, yl;
      leg_token(L, &nl);
      const char *ty = leg_token(L, &yl);
      const vtype vt = legacy_type(ty, yl);
      if (vt == T_NONE || count > SIZE_MAX / 16 ||
          !leg_skip_values(L, 3 * count, vt))
        return MX_OK;
    } else if (tok_eq(t, tl, "FIELD")) {
      size_t nl, narr;
      leg_token(L, &nl); /* the field's name */
      if (!leg_count_q(L, &narr)) return MX_OK;
      for (size_t i = 0; i < narr; i++) {
        size_t nc, nt, yl;
        const char *name = leg_token(L, &nl);
        if (tok_eq(name, nl, "NULL_ARRAY")) continue;
        if (!leg_count_q(L, &nc) || !leg_count_q(L, &nt)) return MX_OK;
        const char *ty = leg_token(L, &yl);
        const vtype vt = legacy_type(ty, yl);
        if (vt == T_NONE && !L->fields && is_material(point, name, nl))
          return bad_material_type(L, ty, yl);
        if (vt == T_NONE) return MX_OK;
        if (L->fields) {
          MX_CHECK(leg_listed(L, name, nl, point, nt, nc, vt));
          if ((nt && nc > SIZE_MAX / 16 / nt) || !leg_skip_values(L, nc * nt, vt)) return MX_OK;
        } else if (is_surface_tag(point, name, nl, vt, nc)) {
          MX_CHECK(leg_node_tags(L, name, nt, vt));
        } else if (is_material(point, name, nl)) {
          MX_CHECK(leg_material(L, name, nt, nc, vt));
        } else if ((nt && nc > SIZE_MAX / 16 / nt) ||
                   !leg_skip_values(L, nc * nt, vt)) {
          return MX_OK;
        }
        const char *save = L->p;
        const char *kwd = leg_token(L, &nl);
        if (tok_eq(kwd, nl, "METADATA"))
          leg_skip_metadata(L);
        else
          L->p = save;
      }
    } else if (tok_eq(t, tl, "METADATA")) {
      leg_skip_metadata(L);
    } else {
      if (L->fields && tl) L->fields->stopped = t;
      return MX_OK; /* the end, or an attribute not read */
    }
  }
}

/* Lines 1 to 3 ("# vtk DataFile Version x.y", the title, ASCII or BINARY)
 * and DATASET: its type's word in *ds (*dsl bytes). */
static int leg_header(legacy *L, const char **ds, size_t *dsl) {
  rd *r = L->r;
  const char *end = r->end;
  /* Line 1: "# vtk DataFile Version x.y". */
  const char *p = skip_ws(r->buf, end);
  static const char magic[] = "# vtk DataFile Version";
  const size_t ml = sizeof magic - 1;
  if ((size_t)(end - p) < ml || strncasecmp(p, magic, ml) != 0)
    return mx_rd_fail(r, p, "expected '%s x.y' on the first line", magic);
  const char *v = p + ml;
  while (v < end && (*v == ' ' || *v == '\t')) v++;
  int major = 0;
  while (v < end && *v >= '0' && *v <= '9' && major < 1000)
    major = 10 * major + (*v++ - '0');
  L->v5 = major >= 5;
  /* Line 2: the title; line 3: ASCII or BINARY. */
  const char *nl = memchr(p, '\n', (size_t)(end - p));
  nl = nl ? memchr(nl + 1, '\n', (size_t)(end - nl - 1)) : NULL;
  if (!nl) return mx_rd_fail(r, p, "truncated header (no title line)");
  L->p = nl + 1;
  size_t tl;
  const char *t = leg_token(L, &tl);
  if (tok_eq(t, tl, "BINARY"))
    L->binary = 1;
  else if (!tok_eq(t, tl, "ASCII"))
    return mx_rd_fail(r, t, "expected ASCII or BINARY, found '%.*s'", shown(tl), t);
  t = leg_token(L, &tl);
  if (!tok_eq(t, tl, "DATASET"))
    return mx_rd_fail(r, t, "expected DATASET, found '%.*s'", shown(tl), t);
  *ds = leg_token(L, dsl);
  return MX_OK;
}

int mx_rd_vtk_legacy(rd *r, mx_mesh_data *out) {
  legacy L;
  memset(&L, 0, sizeof L);
  L.r = r;
  L.out = out;
  const char *end = r->end;
  size_t tl;
  const char *t;
  MX_CHECK(leg_header(&L, &t, &tl));
  if (!tok_eq(t, tl, "UNSTRUCTURED_GRID"))
    return mx_rd_fail(r, t, "DATASET %.*s: only UNSTRUCTURED_GRID is supported",
                      shown(tl), t);
  for (;;) {
    t = leg_token(&L, &tl);
    if (tl == 0) {
      if (t < end)
        return mx_rd_fail(r, t, "unexpected NUL byte (binary data in an ASCII "
                          "file, or a wrong count)");
      break;
    }
    if (tok_eq(t, tl, "POINTS")) {
      MX_CHECK(leg_points(&L));
    } else if (tok_eq(t, tl, "CELLS")) {
      MX_CHECK(leg_cells(&L));
    } else if (tok_eq(t, tl, "CELL_TYPES")) {
      MX_CHECK(leg_types(&L));
    } else if (tok_eq(t, tl, "FIELD")) {
      MX_CHECK(leg_skip_field(&L));
    } else if (tok_eq(t, tl, "METADATA")) {
      leg_skip_metadata(&L);
    } else if (tok_eq(t, tl, "CELL_DATA") || tok_eq(t, tl, "POINT_DATA")) {
      MX_CHECK(leg_attributes(&L, t, tl));
      break;
    } else {
      return mx_rd_fail(r, t, "unexpected '%.*s' (expected POINTS, CELLS or "
                        "CELL_TYPES)", shown(tl), t);
    }
  }
  if (!L.have_points) return mx_rd_fail(r, NULL, "no POINTS section");
  if (!L.have_cells) return mx_rd_fail(r, NULL, "no CELLS section");
  if (!L.have_types) return mx_rd_fail(r, NULL, "no CELL_TYPES section");
  MX_CHECK(mx_rd_assemble(r, &L.P, out));
  if (L.have_material) MX_CHECK(mx_rd_cell_tags(r, &L.material, out));
  return L.have_node_tags ? mx_rd_node_tags(r, &L.node_tags, out) : MX_OK;
}

/* ---- one field instead of the mesh (vtk_fields.h) ------------------------ */

/* A block of cells (CELLS, or a POLYDATA section), kept as the file gives
 * it: block b of the field's cells. */
static int leg_field_cells(legacy *L, int b, const char *kw) {
  size_t a, s;
  const char *at = skip_ws(L->p, L->r->end);
  MX_CHECK(leg_count(L, &a, kw));
  MX_CHECK(leg_count(L, &s, kw));
  rd_fields *f = L->fields;
  rd_cells *c = &f->cells[b];
  if (c->at) return mx_rd_fail(L->r, at, "%s given twice", kw);
  c->at = at;
  if (L->v5) {
    MX_CHECK(leg_offsets(L, a, s, &c->off, &c->cn));
    c->ncells = a ? a - 1 : 0;
  } else {
    if (a > s / 2) /* each cell takes its count and at least one node */
      return mx_rd_fail(L->r, at, "%s: %zu cells cannot fit in %zu values", kw, a, s);
    MX_CHECK(leg_array(L, s, T_I32, &c->list, kw));
    c->ncells = a;
    c->list_form = 1;
  }
  f->ncells += c->ncells; /* each block is bounded by the file's size */
  if (b == 0) { /* CELL_TYPES checks its count against it */
    L->have_cells = 1;
    L->P.ncells = c->ncells;
  }
  return MX_OK;
}

/* The array picked, and its values. */
static int leg_field_values(legacy *L) {
  rd *r = L->r;
  rd_fields *f = L->fields;
  if (!L->have_points) return mx_rd_fail(r, NULL, "no POINTS section");
  f->npts = L->P.nnodes;
  f->pts = L->P.pts;
  MX_CHECK(f->pick(r, f, &f->which));
  const rd_array *a = &f->arr[f->which];
  char what[64];
  snprintf(what, sizeof what, "%.*s", shown(a->nlen), a->name);
  if (a->ncomp != 1)
    return mx_rd_fail(r, a->at, "%s: %llu components, expected 1", what,
                      (unsigned long long)a->ncomp);
  const size_t want = a->point ? f->npts : f->ncells;
  if (a->count != want)
    return mx_rd_fail(r, a->at, "%s: %zu values for %zu %s", what, a->count, want,
                      a->point ? "points" : "cells");
  L->p = a->data;
  return leg_array(L, want, a->t, &f->values, what);
}

int mx_rd_vtk_legacy_fields(rd *r, rd_fields *f) {
  legacy L;
  memset(&L, 0, sizeof L);
  L.r = r;
  L.fields = f;
  const char *end = r->end;
  size_t tl;
  const char *t;
  MX_CHECK(leg_header(&L, &t, &tl));
  const int poly = tok_eq(t, tl, "POLYDATA");
  if (!poly && !tok_eq(t, tl, "UNSTRUCTURED_GRID"))
    return mx_rd_fail(r, t, "DATASET %.*s: only UNSTRUCTURED_GRID and POLYDATA are supported",
                      shown(tl), t);
  /* POLYDATA's sections, as blocks in VTK's cell order */
  static const char *const poly_kw[RD_MAX_BLOCKS] = {"VERTICES", "LINES", "POLYGONS",
                                                     "TRIANGLE_STRIPS"};
  for (;;) {
    t = leg_token(&L, &tl);
    if (tl == 0) {
      if (t < end)
        return mx_rd_fail(r, t, "unexpected NUL byte (binary data in an ASCII "
                          "file, or a wrong count)");
      break;
    }
    int block = -1;
    for (int b = 0; b < RD_MAX_BLOCKS; b++)
      if (poly ? tok_eq(t, tl, poly_kw[b]) : b == 0 && tok_eq(t, tl, "CELLS")) block = b;
    if (tok_eq(t, tl, "POINTS")) {
      MX_CHECK(leg_points(&L));
    } else if (block >= 0) {
      MX_CHECK(leg_field_cells(&L, block, poly ? poly_kw[block] : "CELLS"));
    } else if (!poly && tok_eq(t, tl, "CELL_TYPES")) {
      MX_CHECK(leg_types(&L));
    } else if (tok_eq(t, tl, "FIELD")) {
      MX_CHECK(leg_skip_field(&L));
    } else if (tok_eq(t, tl, "METADATA")) {
      leg_skip_metadata(&L);
    } else if (tok_eq(t, tl, "CELL_DATA") || tok_eq(t, tl, "POINT_DATA")) {
      MX_CHECK(leg_attributes(&L, t, tl));
      break;
    } else {
      return mx_rd_fail(r, t, "unexpected '%.*s' (expected POINTS, %s, POINT_DATA or CELL_DATA)",
                        shown(tl), t,
                        poly ? "VERTICES, LINES, POLYGONS, TRIANGLE_STRIPS" : "CELLS, CELL_TYPES");
    }
  }
  return leg_field_values(&L);
}
