/* mixoct: reading VTK XML unstructured grids, .vtu (see read_mesh.h): the
 * points, the cells as offsets + connectivity and the cell types, ASCII,
 * inline base64 or appended (raw or base64), compressed or not (the bytes
 * of a binary array: io/vtu_decode.c), cut into parts that io/vtk_cells.c
 * assembles; the point
 * fields surface_tag and (in a piece of a .pvtu) GlobalNodeId, and the cell
 * field material (cell_tag: one component, one value per cell, of any type,
 * whole numbers). A .pvtu master goes to read_pvtu.c.
 *
 * mx_rd_vtu_fields reads one field instead of the mesh (for size maps,
 * io/vtk_fields.h): an UnstructuredGrid or a PolyData (.vtp), every array
 * of <PointData> and <CellData> listed, the picked one's values and, for a
 * cell array, the cells' offsets and connectivity. */
#include "io/mesh_reader.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "base/common.h"
#include "io/vtk_cells.h"
#include "io/vtk_fields.h"
#include "io/vtk_xml.h"
#include "io/vtu_decode.h"

static const char *const vtu_type_name[T_NONE] = {
    "Int8",  "UInt8",  "Int16",  "UInt16",  "Int32",
    "UInt32", "Int64", "UInt64", "Float32", "Float64"};

/* A DataArray's format: ascii, binary (base64 text inline) or appended. */
enum { F_ASCII, F_BINARY, F_APPENDED };

typedef struct {
  int present, fmt;
  vtype t;
  uint64_t ncomp, offset;
  const char *tag, *text;
} xarr;

static int parse_data_array(const rd *r, const xtag *t, xarr *x) {
  const char *v;
  size_t n;
  x->present = 1;
  x->tag = t->start;
  x->t = T_NONE;
  if (!mx_rd_xml_attr(t, "type", &v, &n))
    return mx_rd_fail(r, t->start, "<DataArray> has no type attribute");
  for (int k = 0; k < T_NONE; k++)
    if (n == strlen(vtu_type_name[k]) && memcmp(v, vtu_type_name[k], n) == 0)
      x->t = (vtype)k;
  if (x->t == T_NONE)
    return mx_rd_fail(r, t->start, "<DataArray> type \"%.*s\" is not supported",
                      shown(n), v);
  x->ncomp = 1;
  MX_CHECK(mx_rd_attr_size(r, t, "NumberOfComponents", &x->ncomp, 0));
  if (!mx_rd_xml_attr(t, "format", &v, &n))
    return mx_rd_fail(r, t->start, "<DataArray> has no format attribute");
  if (n == 8 && memcmp(v, "appended", 8) == 0) {
    x->fmt = F_APPENDED;
    return mx_rd_attr_size(r, t, "offset", &x->offset, 1);
  }
  const int ascii = n == 5 && memcmp(v, "ascii", 5) == 0;
  if (ascii || (n == 6 && memcmp(v, "binary", 6) == 0)) {
    if (t->selfclose) return mx_rd_fail(r, t->start, "empty %s <DataArray/>", ascii ? "ascii" : "binary");
    x->fmt = ascii ? F_ASCII : F_BINARY;
    x->text = t->after;
    return MX_OK;
  }
  return mx_rd_fail(r, t->start,
                    "<DataArray> format \"%.*s\" is not supported (ascii, binary or "
                    "appended)",
                    shown(n), v);
}

typedef struct {
  int swap, hsize, b64; /* b64: <AppendedData encoding="base64"> */
  mx_vtu_comp comp;
  const char *base; /* first byte after '_' */
} vtu_layout;

static void *rd_tmp(void *ctx, size_t bytes) {
  void *p;
  return mx_rd_alloc(ctx, bytes, &p) == MX_OK ? p : NULL;
}

/* The bytes of a binary or appended array x (io/vtu_decode.h). */
static int decode(rd *r, const xarr *x, const vtu_layout *lay, const unsigned char **data,
                  uint64_t *nbytes, const char *what) {
  mx_vtu_src s = {NULL, NULL, r->end, lay->hsize, lay->swap, lay->comp};
  if (x->fmt == F_BINARY) {
    const char *lt = memchr(x->text, '<', (size_t)(r->end - x->text));
    s.text = x->text;
    s.end = lt ? lt : r->end;
  } else {
    if (!lay->base)
      return mx_rd_fail(r, x->tag, "%s: format=\"appended\" without <AppendedData>", what);
    const size_t avail = (size_t)(r->end - lay->base);
    if (x->offset >= avail)
      return mx_rd_fail(r, x->tag,
                        "%s: appended offset %llu lies past the end of the file "
                        "(truncated file?)",
                        what, (unsigned long long)x->offset);
    if (lay->b64)
      s.text = lay->base + x->offset;
    else
      s.raw = lay->base + x->offset;
  }
  char err[MSG - 64];
  const char *at = NULL;
  const int st = mx_vtu_decode(&s, rd_tmp, r, data, nbytes, err, sizeof err, &at);
  if (st == MX_EINPUT) return mx_rd_fail(r, at, "%s: %s", what, err);
  return st;
}

/* The values of x; want is the expected count (SIZE_MAX: any, appended
 * only). */
static int resolve(rd *r, const xarr *x, const vtu_layout *lay, size_t want,
                   rawarr *out, const char *what) {
  if (x->fmt == F_ASCII) {
    const char *p = x->text;
    MX_CHECK(mx_rd_ascii_array(r, &p, '<', want, is_float(x->t), out, what));
    p = skip_ws(p, r->end);
    if (p < r->end && *p != '<')
      return mx_rd_fail(r, p, "%s: more than the %zu expected values", what, want);
    return MX_OK;
  }
  const unsigned char *data;
  uint64_t nbytes;
  MX_CHECK(decode(r, x, lay, &data, &nbytes, what));
  const char *at = x->fmt == F_APPENDED ? lay->base + x->offset : x->text;
  const size_t es = (size_t)vsize[x->t];
  if (nbytes % es)
    return mx_rd_fail(r, at,
                      "%s: block of %llu bytes is not a whole number of %s values",
                      what, (unsigned long long)nbytes, vtu_type_name[x->t]);
  size_t n = (size_t)nbytes / es;
  if (want != SIZE_MAX && n != want)
    return mx_rd_fail(r, at, "%s: %zu values, expected %zu", what, n, want);
  *out = (rawarr){data, n, x->t, lay->swap, NULL};
  return MX_OK;
}

/* One point or cell array for a piece's signature (mx_rd_pvtu compares
 * them): a hash of its section, type and name, summed over the arrays. */
static uint64_t array_sig(const xtag *t) {
  const char *v;
  size_t n;
  uint64_t h = 0xcbf29ce484222325ull; /* FNV-1a, then a finaliser */
  for (int k = 0; k < 2; k++) {
    if (!mx_rd_xml_attr(t, k ? "Name" : "type", &v, &n)) n = 0;
    for (size_t i = 0; i < n; i++) h = (h ^ (unsigned char)v[i]) * 0x100000001b3ull;
    h = (h ^ 0x100) * 0x100000001b3ull;
  }
  h = (h ^ (h >> 30)) * 0xbf58476d1ce4e5b9ull;
  h = (h ^ (h >> 27)) * 0x94d049bb133111ebull;
  return h ^ (h >> 31);
}

/* A piece's GlobalNodeId (one non-negative integer per point). */
static int piece_ids(rd *r, const xarr *x, const vtu_layout *lay, size_t nnodes) {
  if (is_float(x->t) || x->ncomp != 1)
    return mx_rd_fail(r, x->tag, "GlobalNodeId: expected one component of an integer type");
  rawarr a;
  MX_CHECK(resolve(r, x, lay, nnodes, &a, "GlobalNodeId"));
  uint64_t *gid = mx_alloc((nnodes + 1) * sizeof *gid);
  if (!gid) return MX_ENOMEM;
  r->piece->gid = gid;
  size_t bad = SIZE_MAX;
#pragma omp parallel for schedule(static) reduction(min : bad) if (nnodes > 65536)
  for (size_t i = 0; i < nnodes; i++) {
    const int64_t v = raw_int(&a, i);
    gid[i] = (uint64_t)v;
    if (v < 0 && i < bad) bad = i;
  }
  if (bad != SIZE_MAX)
    return mx_rd_fail(r, mx_rd_arr_at(r, &a, bad), "GlobalNodeId: value %zu is negative or too large",
                      bad);
  return MX_OK;
}

/* Whether the file's last non-blank bytes are the closing tag: a file cut
 * short (also in its raw appended data) lacks it. */
static int xml_closed(const rd *r, const char *tag) {
  const char *e = r->end;
  while (e > r->buf && (e[-1] == ' ' || e[-1] == '\t' || e[-1] == '\n' || e[-1] == '\r')) e--;
  const size_t n = strlen(tag);
  return (size_t)(e - r->buf) >= n && memcmp(e - n, tag, n) == 0;
}

static int vtkfile_closed(const rd *r) {
  if (xml_closed(r, "</VTKFile>")) return MX_OK;
  return mx_rd_fail(r, NULL, "the file does not end with </VTKFile>: it is cut short (an "
                       "interrupted write or copy?)");
}

/* The byte order, header type and compressor of the <VTKFile> tag t. */
static int vtkfile_layout(const rd *r, const xtag *t, vtu_layout *lay) {
  const int big = mx_rd_attr_eq(t, "byte_order", "BigEndian");
  lay->swap = big == HOST_LE;
  if (mx_rd_attr_eq(t, "header_type", "UInt64"))
    lay->hsize = 8;
  else if (mx_rd_xml_attr(t, "header_type", &(const char *){0}, &(size_t){0}) &&
           !mx_rd_attr_eq(t, "header_type", "UInt32"))
    return mx_rd_fail(r, t->start, "header_type must be UInt32 or UInt64");
  const char *cv;
  size_t cn;
  lay->comp = MX_VTU_RAW;
  if (mx_rd_xml_attr(t, "compressor", &cv, &cn) && cn > 0) {
    const int c = mx_vtu_compressor(cv, cn);
    if (c < 0)
      return mx_rd_fail(r, t->start,
                        "compressor \"%.*s\" is not supported (vtkZLibDataCompressor, "
                        "vtkLZ4DataCompressor or vtkLZMADataCompressor)",
                        shown(cn), cv);
    lay->comp = (mx_vtu_comp)c;
  }
  return MX_OK;
}

/* The '_' that starts the appended data after the tag t into lay. */
static int appended_start(rd *r, const xtag *t, vtu_layout *lay) {
  lay->b64 = mx_rd_attr_eq(t, "encoding", "base64");
  if (!lay->b64 && !mx_rd_attr_eq(t, "encoding", "raw"))
    return mx_rd_fail(r, t->start, "<AppendedData> encoding must be \"raw\" or \"base64\"");
  const char *q = skip_ws(t->after, r->end);
  if (q >= r->end || *q != '_')
    return mx_rd_fail(r, q, "expected '_' at the start of the appended data");
  lay->base = q + 1;
  if (!lay->b64) r->bin_from = lay->base;
  return MX_OK;
}

int mx_rd_vtu(rd *r, mx_mesh_data *out) {
  const char *p = r->buf;
  int seen = 0, pieces = 0, in_points = 0, in_cells = 0, in_pdata = 0, in_cdata = 0;
  vtu_layout lay = {0, 4, 0, MX_VTU_RAW, NULL};
  xarr pts = {0}, con = {0}, offs = {0}, typ = {0}, ntag = {0}, gidx = {0}, mat = {0};
  xarr bfl = {0}; /* the point field boundary (its first array) */
  uint64_t npts = 0, ncells = 0;
  const char *piece_tag = NULL;
  for (;;) {
    xtag t;
    int found;
    MX_CHECK(mx_rd_xml_next(r, p, &t, &found));
    if (!found) break;
    p = t.after;
    if (mx_rd_tag_is(&t, "VTKFile")) {
      if (t.closing) break;
      seen = 1;
      if (mx_rd_attr_eq(&t, "type", "PUnstructuredGrid")) {
        if (r->piece)
          return mx_rd_fail(r, t.start, "a piece of a .pvtu must be an UnstructuredGrid file, not "
                            "another PUnstructuredGrid");
        MX_CHECK(vtkfile_closed(r));
        return mx_rd_pvtu(r, t.after, out);
      }
      if (!mx_rd_attr_eq(&t, "type", "UnstructuredGrid"))
        return mx_rd_fail(r, t.start,
                          "not an UnstructuredGrid VTK XML file (type attribute)");
      MX_CHECK(vtkfile_layout(r, &t, &lay));
      MX_CHECK(vtkfile_closed(r));
    } else if (!seen) {
      return mx_rd_fail(r, t.start, "expected <VTKFile>, found <%.*s>",
                        shown(t.nlen), t.name);
    } else if (mx_rd_tag_is(&t, "Piece")) {
      if (t.closing) continue;
      if (++pieces > 1)
        return mx_rd_fail(r, t.start, "more than one <Piece> is not supported");
      piece_tag = t.start;
      MX_CHECK(mx_rd_attr_size(r, &t, "NumberOfPoints", &npts, 1));
      MX_CHECK(mx_rd_attr_size(r, &t, "NumberOfCells", &ncells, 1));
    } else if (mx_rd_tag_is(&t, "Points")) {
      in_points = !t.closing && !t.selfclose;
    } else if (mx_rd_tag_is(&t, "Cells")) {
      in_cells = !t.closing && !t.selfclose;
    } else if (mx_rd_tag_is(&t, "PointData")) {
      in_pdata = !t.closing && !t.selfclose;
    } else if (mx_rd_tag_is(&t, "CellData")) {
      in_cdata = !t.closing && !t.selfclose;
    } else if (mx_rd_tag_is(&t, "DataArray") && !t.closing) {
      xarr *x = NULL;
      if (r->piece && in_pdata) r->piece->point_sig += array_sig(&t);
      if (r->piece && in_cdata) r->piece->cell_sig += array_sig(&t);
      if (r->piece && in_pdata && mx_rd_attr_eq(&t, "Name", "GlobalNodeId")) {
        if (gidx.present) return mx_rd_fail(r, t.start, "GlobalNodeId given twice");
        x = &gidx;
      } else if (in_pdata && mx_rd_attr_eq(&t, "Name", "surface_tag")) {
        if (ntag.present)
          return mx_rd_fail(r, t.start, "surface_tag given twice");
        x = &ntag;
      } else if (in_pdata && !bfl.present && mx_rd_attr_eq(&t, "Name", "boundary")) {
        x = &bfl;
      } else if (in_cdata && mx_rd_attr_eq(&t, "Name", "material")) {
        if (mat.present) return mx_rd_fail(r, t.start, "material given twice");
        x = &mat;
      } else if (in_points && !pts.present)
        x = &pts;
      else if (in_cells && mx_rd_attr_eq(&t, "Name", "connectivity"))
        x = &con;
      else if (in_cells && mx_rd_attr_eq(&t, "Name", "offsets"))
        x = &offs;
      else if (in_cells && mx_rd_attr_eq(&t, "Name", "types"))
        x = &typ;
      if (x) MX_CHECK(parse_data_array(r, &t, x));
    } else if (mx_rd_tag_is(&t, "AppendedData") && !t.closing) {
      MX_CHECK(appended_start(r, &t, &lay));
      break;
    }
  }
  if (!seen) return mx_rd_fail(r, NULL, "no <VTKFile> element");
  if (!pieces) return mx_rd_fail(r, NULL, "no <Piece> element");
  if (!pts.present) return mx_rd_fail(r, piece_tag, "no <Points> DataArray");
  if (!is_float(pts.t) || pts.ncomp != 3)
    return mx_rd_fail(r, pts.tag,
                      "Points: expected Float32 or Float64 with "
                      "NumberOfComponents=\"3\"");
  if (npts >= UINT32_MAX || ncells > SIZE_MAX / 64)
    return mx_rd_fail(r, piece_tag, "too many points or cells");
  parts P;
  memset(&P, 0, sizeof P);
  P.nnodes = (size_t)npts;
  P.ncells = (size_t)ncells;
  P.vtu_offsets = 1;
  MX_CHECK(resolve(r, &pts, &lay, 3 * P.nnodes, &P.pts, "Points"));
  static const int64_t zero = 0;
  const rawarr none = {(const unsigned char *)&zero, 0, T_I64, 0, NULL};
  P.off = P.cn = P.types = none;
  if (ncells > 0 || con.present || offs.present || typ.present) {
    const char *names[3] = {"offsets", "types", "connectivity"};
    xarr *xs[3] = {&offs, &typ, &con};
    for (int i = 0; i < 3; i++) {
      if (!xs[i]->present)
        return mx_rd_fail(r, piece_tag, "no <Cells> DataArray Name=\"%s\"",
                          names[i]);
      if (is_float(xs[i]->t) || xs[i]->ncomp != 1)
        return mx_rd_fail(r, xs[i]->tag,
                          "%s: expected one component of an integer type",
                          names[i]);
    }
    MX_CHECK(resolve(r, &offs, &lay, P.ncells, &P.off, "offsets"));
    MX_CHECK(resolve(r, &typ, &lay, P.ncells, &P.types, "types"));
    size_t want = SIZE_MAX;
    if (con.fmt == F_ASCII) {
      int64_t last = P.ncells ? raw_int(&P.off, P.ncells - 1) : 0;
      if (last < 0 || (uint64_t)last > 8 * (uint64_t)P.ncells)
        return mx_rd_fail(r, offs.tag, "offsets: the last offset %lld is invalid",
                          (long long)last);
      want = (size_t)last;
    }
    MX_CHECK(resolve(r, &con, &lay, want, &P.cn, "connectivity"));
  }
  rawarr tags, labels;
  const int with_tags = ntag.present && !is_float(ntag.t) && ntag.ncomp == 1;
  if (with_tags)
    MX_CHECK(resolve(r, &ntag, &lay, P.nnodes, &tags, "surface_tag"));
  if (mat.present) {
    if (mat.ncomp != 1)
      return mx_rd_fail(r, mat.tag, "material: %llu components, expected 1 (one label per cell)",
                        (unsigned long long)mat.ncomp);
    MX_CHECK(resolve(r, &mat, &lay, P.ncells, &labels, "material"));
  }
  rawarr flags;
  const int with_flags = bfl.present && !is_float(bfl.t) && bfl.ncomp == 1;
  if (with_flags) MX_CHECK(resolve(r, &bfl, &lay, P.nnodes, &flags, "boundary"));
  MX_CHECK(mx_rd_assemble(r, &P, out));
  if (with_flags) MX_CHECK(mx_rd_node_flags(&flags, out));
  if (mat.present) MX_CHECK(mx_rd_cell_tags(r, &labels, out));
  if (gidx.present) MX_CHECK(piece_ids(r, &gidx, &lay, P.nnodes));
  return with_tags ? mx_rd_node_tags(r, &tags, out) : MX_OK;
}

/* ---- one field instead of the mesh (vtk_fields.h) ------------------------ */

/* The block of cells a section tag t holds: <Cells> of an UnstructuredGrid
 * (0); <Verts>, <Lines>, <Polys>, <Strips> of a PolyData, in VTK's cell
 * order (0 to 3); -1 for any other tag. */
static int cell_block(const xtag *t, int poly) {
  static const char *const sections[RD_MAX_BLOCKS] = {"Verts", "Lines", "Polys", "Strips"};
  if (!poly) return mx_rd_tag_is(t, "Cells") ? 0 : -1;
  for (int b = 0; b < RD_MAX_BLOCKS; b++)
    if (mx_rd_tag_is(t, sections[b])) return b;
  return -1;
}

/* An array of <PointData> or <CellData> listed: its name and components
 * (0 when NumberOfComponents is not a count); its type and format are only
 * read if it is picked. */
static int vtu_listed(const rd *r, const xtag *t, int point, rd_fields *f) {
  if (f->narr == RD_MAX_ARRAYS)
    return mx_rd_fail(r, t->start, "more than %d arrays of point and cell data", RD_MAX_ARRAYS);
  rd_array *a = &f->arr[f->narr++];
  memset(a, 0, sizeof *a);
  if (!mx_rd_xml_attr(t, "Name", &a->name, &a->nlen)) a->name = "";
  a->point = point;
  a->at = t->start;
  a->t = T_NONE;
  a->ncomp = 1;
  const char *v;
  size_t n;
  if (mx_rd_xml_attr(t, "NumberOfComponents", &v, &n)) {
    uint64_t c = 0;
    for (size_t i = 0; i < n && c <= 1000000; i++)
      c = v[i] >= '0' && v[i] <= '9' ? 10 * c + (uint64_t)(v[i] - '0') : 1000001;
    a->ncomp = n > 0 && c <= 1000000 ? c : 0;
  }
  return MX_OK;
}

/* The offsets and connectivity of a block of ncells cells (its section at
 * piece_tag when absent). */
static int vtu_block(rd *r, const vtu_layout *lay, const xarr *offs, const xarr *con,
                     size_t ncells, const char *piece_tag, rd_cells *c) {
  c->ncells = ncells;
  c->vtu_offsets = 1;
  c->at = offs->present ? offs->tag : piece_tag;
  const char *names[2] = {"offsets", "connectivity"};
  const xarr *xs[2] = {offs, con};
  for (int i = 0; i < 2; i++) {
    if (!xs[i]->present)
      return mx_rd_fail(r, piece_tag, "%zu cells but no DataArray Name=\"%s\"", ncells, names[i]);
    if (is_float(xs[i]->t) || xs[i]->ncomp != 1)
      return mx_rd_fail(r, xs[i]->tag, "%s: expected one component of an integer type", names[i]);
  }
  MX_CHECK(resolve(r, offs, lay, ncells, &c->off, "offsets"));
  size_t want = SIZE_MAX;
  if (con->fmt == F_ASCII) {
    const int64_t last = raw_int(&c->off, ncells - 1);
    if (last < 0)
      return mx_rd_fail(r, offs->tag, "offsets: the last offset %lld is invalid", (long long)last);
    want = (size_t)last;
  }
  return resolve(r, con, lay, want, &c->cn, "connectivity");
}

int mx_rd_vtu_fields(rd *r, rd_fields *f) {
  const char *p = r->buf;
  int seen = 0, poly = 0, pieces = 0, in_points = 0, block = -1, data = -1;
  vtu_layout lay = {0, 4, 0, MX_VTU_RAW, NULL};
  xarr pts = {0}, con[RD_MAX_BLOCKS], offs[RD_MAX_BLOCKS];
  memset(con, 0, sizeof con);
  memset(offs, 0, sizeof offs);
  uint64_t npts = 0, nb[RD_MAX_BLOCKS] = {0};
  const char *piece_tag = NULL;
  for (;;) {
    xtag t;
    int found, b;
    MX_CHECK(mx_rd_xml_next(r, p, &t, &found));
    if (!found) break;
    p = t.after;
    const int opens = !t.closing && !t.selfclose;
    if (mx_rd_tag_is(&t, "VTKFile")) {
      if (t.closing) break;
      seen = 1;
      if (mx_rd_attr_eq(&t, "type", "PUnstructuredGrid") || mx_rd_attr_eq(&t, "type", "PPolyData"))
        return mx_rd_fail(r, t.start, "a parallel VTK XML file (.pvtu, .pvtp) is not read here: "
                          "give one of its pieces");
      poly = mx_rd_attr_eq(&t, "type", "PolyData");
      if (!poly && !mx_rd_attr_eq(&t, "type", "UnstructuredGrid"))
        return mx_rd_fail(r, t.start,
                          "not an UnstructuredGrid or PolyData VTK XML file (type attribute)");
      MX_CHECK(vtkfile_layout(r, &t, &lay));
      MX_CHECK(vtkfile_closed(r));
    } else if (!seen) {
      return mx_rd_fail(r, t.start, "expected <VTKFile>, found <%.*s>", shown(t.nlen), t.name);
    } else if (mx_rd_tag_is(&t, "Piece")) {
      if (t.closing) continue;
      if (++pieces > 1) return mx_rd_fail(r, t.start, "more than one <Piece> is not supported");
      piece_tag = t.start;
      MX_CHECK(mx_rd_attr_size(r, &t, "NumberOfPoints", &npts, 1));
      if (!poly) {
        MX_CHECK(mx_rd_attr_size(r, &t, "NumberOfCells", &nb[0], 1));
      } else {
        static const char *const counts[RD_MAX_BLOCKS] = {"NumberOfVerts", "NumberOfLines",
                                                          "NumberOfPolys", "NumberOfStrips"};
        for (int k = 0; k < RD_MAX_BLOCKS; k++)
          MX_CHECK(mx_rd_attr_size(r, &t, counts[k], &nb[k], 0));
      }
    } else if (mx_rd_tag_is(&t, "Points")) {
      in_points = opens;
    } else if (mx_rd_tag_is(&t, "PointData") || mx_rd_tag_is(&t, "CellData")) {
      data = opens ? mx_rd_tag_is(&t, "PointData") : -1;
    } else if ((b = cell_block(&t, poly)) >= 0) {
      block = opens ? b : -1;
    } else if (mx_rd_tag_is(&t, "DataArray") && !t.closing) {
      xarr *x = NULL;
      if (data >= 0)
        MX_CHECK(vtu_listed(r, &t, data, f));
      else if (in_points && !pts.present)
        x = &pts;
      else if (block >= 0 && mx_rd_attr_eq(&t, "Name", "connectivity"))
        x = &con[block];
      else if (block >= 0 && mx_rd_attr_eq(&t, "Name", "offsets"))
        x = &offs[block];
      if (x && x->present) return mx_rd_fail(r, t.start, "a cell array given twice");
      if (x) MX_CHECK(parse_data_array(r, &t, x));
    } else if (mx_rd_tag_is(&t, "AppendedData") && !t.closing) {
      MX_CHECK(appended_start(r, &t, &lay));
      break;
    }
  }
  if (!seen) return mx_rd_fail(r, NULL, "no <VTKFile> element");
  if (!pieces) return mx_rd_fail(r, NULL, "no <Piece> element");
  if (!pts.present) return mx_rd_fail(r, piece_tag, "no <Points> DataArray");
  if (!is_float(pts.t) || pts.ncomp != 3)
    return mx_rd_fail(r, pts.tag, "Points: expected Float32 or Float64 with NumberOfComponents=\"3\"");
  uint64_t total = 0;
  for (int b = 0; b < RD_MAX_BLOCKS; b++) total += nb[b]; /* each < 2^57 */
  if (npts > SIZE_MAX / 64 || total > SIZE_MAX / 64)
    return mx_rd_fail(r, piece_tag, "too many points or cells");
  f->npts = (size_t)npts;
  f->ncells = (size_t)total;
  MX_CHECK(resolve(r, &pts, &lay, 3 * f->npts, &f->pts, "Points"));
  MX_CHECK(f->pick(r, f, &f->which));
  const rd_array *a = &f->arr[f->which];
  xtag t;
  int found;
  MX_CHECK(mx_rd_xml_next(r, a->at, &t, &found)); /* its tag, read again */
  if (!found) return mx_rd_fail(r, a->at, "the array's tag is gone"); /* cannot happen */
  xarr x = {0};
  MX_CHECK(parse_data_array(r, &t, &x));
  char what[64];
  snprintf(what, sizeof what, "%.*s", shown(a->nlen), a->name);
  if (x.ncomp != 1)
    return mx_rd_fail(r, a->at, "%s: %llu components, expected 1", what,
                      (unsigned long long)x.ncomp);
  MX_CHECK(resolve(r, &x, &lay, a->point ? f->npts : f->ncells, &f->values, what));
  if (a->point) return MX_OK;
  for (int b = 0; b < RD_MAX_BLOCKS; b++)
    if (nb[b] > 0)
      MX_CHECK(vtu_block(r, &lay, &offs[b], &con[b], (size_t)nb[b], piece_tag, &f->cells[b]));
  return MX_OK;
}
