/* mixoct: reading GetFEM mesh files (the layout is described in
 * read_m3d.c with the published mesher's other files, and in read_mesh.h). */
#include "io/mesh_reader.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "base/common.h"
#include "io/face_tags.h"
#include "io/getfem_tables.h"
#include "io/text_cursor.h"
#include "io/text_scan.h"

/* GetFEM's node j of each type is slot mx_getfem_node[t][j] of our row
 * (io/getfem_tables.h: the permutations are their own inverses). */
static int getfem_type(const char *t, size_t n) {
  for (int k = 0; k < 4; k++)
    if (tok_eq(t, n, mx_getfem_geotrans[k])) return k;
  return -1;
}

/* Reads "KW i" at the start of a GetFEM item line, the keyword already
 * read: *item is 1 for the item numbered `want`, 0 for a "KW COUNT n" line
 * (skipped). */
static int getfem_item(cur *c, const char *kw, size_t want, int *item) {
  const char *save = c->p;
  size_t n;
  const char *t = cur_tok(c, &n);
  if (tok_eq(t, n, "COUNT")) {
    int64_t v = 0;
    *item = 0;
    return cur_int(c, &v, kw);
  }
  c->p = save;
  const char *at = cur_skip(c);
  int64_t i = 0;
  MX_CHECK(cur_int(c, &i, kw));
  if (i < 0 || (uint64_t)i != want)
    return mx_rd_fail(c->r, at, "%s %lld: expected %s %zu (numbered 0, 1, 2, ... "
                      "in order)", kw, (long long)i, kw, want);
  *item = 1;
  return MX_OK;
}

/* The next GetFEM line keyword: 1 for kw, 0 for END (then `end_words`
 * must follow). */
static int getfem_next(cur *c, const char *kw, const char *end_words,
                       int *more) {
  size_t n;
  const char *t = cur_tok(c, &n);
  if (tok_eq(t, n, "END")) {
    *more = 0;
    return mx_rd_cur_words(c, end_words, "GetFEM");
  }
  if (!tok_eq(t, n, kw)) {
    if (n == 0)
      return mx_rd_fail(c->r, t, "GetFEM: expected %s or END %s, found the end of "
                        "the file (truncated file?)", kw, end_words);
    return mx_rd_fail(c->r, t, "GetFEM: expected %s or END %s, found '%.*s'", kw,
                      end_words, shown(n), t);
  }
  *more = 1;
  return MX_OK;
}

/* Room for one more node (capacity *cap, doubled). */
static int reserve_node(rd *r, mx_mesh_data *out, size_t *cap) {
  if (out->nnodes < *cap) return MX_OK;
  if (out->nnodes >= UINT32_MAX - 1)
    return mx_rd_fail(r, NULL, "more than %u points", UINT32_MAX - 1);
  const size_t nc = *cap ? 2 * *cap : 1024;
  double *x = mx_realloc(out->xyz, 3 * nc * sizeof *x);
  if (!x) return MX_ENOMEM;
  out->xyz = x;
  *cap = nc;
  return MX_OK;
}

/* Room for one more cell (capacity *cap, doubled). */
static int reserve_cell(rd *r, mx_mesh_data *out, size_t *cap) {
  if (out->ncells < *cap) return MX_OK;
  if (out->ncells >= UINT32_MAX / 6)
    return mx_rd_fail(r, NULL, "more than %u volume elements", UINT32_MAX / 6);
  const size_t nc = *cap ? 2 * *cap : 1024;
  uint8_t *t = mx_realloc(out->type, nc);
  if (!t) return MX_ENOMEM;
  out->type = t;
  uint32_t *cn = mx_realloc(out->conn, 8 * nc * sizeof *cn);
  if (!cn) return MX_ENOMEM;
  out->conn = cn;
  *cap = nc;
  return MX_OK;
}

static int getfem_points(cur *c, mx_mesh_data *out) {
  size_t cap = 0;
  for (;;) {
    int more = 0, item = 0;
    MX_CHECK(getfem_next(c, "POINT", "POINTS LIST", &more));
    if (!more) return MX_OK;
    MX_CHECK(getfem_item(c, "POINT", out->nnodes, &item));
    if (!item) continue;
    MX_CHECK(reserve_node(c->r, out, &cap));
    double *p = out->xyz + 3 * out->nnodes;
    for (int d = 0; d < 3; d++)
      MX_CHECK(cur_real(c, &p[d], "point coordinate"));
    out->nnodes++;
  }
}

static int getfem_convexes(cur *c, mx_mesh_data *out) {
  size_t cap = 0;
  for (;;) {
    int more = 0, item = 0;
    MX_CHECK(getfem_next(c, "CONVEX", "MESH STRUCTURE DESCRIPTION", &more));
    if (!more) return MX_OK;
    MX_CHECK(getfem_item(c, "CONVEX", out->ncells, &item));
    if (!item) continue;
    size_t n;
    const char *t = cur_tok(c, &n);
    const int type = getfem_type(t, n);
    if (n == 0)
      return mx_rd_fail(c->r, t, "convex %zu: unexpected end of file (truncated "
                        "file?)", out->ncells);
    if (type < 0)
      return mx_rd_fail(c->r, t, "convex %zu: %.*s is not a geometric "
                        "transformation mixoct reads ('GT_PK(3,1)', "
                        "'GT_PYRAMID(1)', 'GT_PRISM(3,1)', 'GT_QK(3,1)')",
                        out->ncells, shown(n), t);
    MX_CHECK(reserve_cell(c->r, out, &cap));
    MX_CHECK(mx_rd_cur_cell_nodes(c, out, out->ncells, type, mx_getfem_node[type]));
    out->ncells++;
  }
}

/* One item of a region: "cv/f" (a face: added with tag t) or "cv" (a
 * whole convex: skipped). */
static int getfem_region_item(cur *c, const char *it, size_t n, int32_t t,
                              mx_mesh_data *out, size_t *cap) {
  int64_t cv = 0, g = -1;
  const char *e = mx_io_int(it, &cv);
  const char *slash = e && e < it + n && *e == '/' ? e : NULL;
  if (slash) e = mx_io_int(slash + 1, &g);
  if (!e || e != it + n)
    return mx_rd_fail(c->r, it, "region %d: '%.*s' is not a convex number or "
                      "convex/face", t, shown(n), it);
  if (cv < 0 || (uint64_t)cv >= out->ncells)
    return mx_rd_fail(c->r, it, "region %d: convex %lld out of range (%zu "
                      "convexes, 0-based)", t, (long long)cv, out->ncells);
  if (!slash) return MX_OK;
  const int type = out->type[cv];
  const int f = g >= 0 ? mx_getfem_local_face(type, g) : -1;
  if (f < 0)
    return mx_rd_fail(c->r, it, "region %d: convex %lld (%s) has no face %lld",
                      t, (long long)cv, mx_getfem_geotrans[type], (long long)g);
  MX_CHECK(mx_rd_face_room(c->r, out, cap, 1));
  const int8_t *fl = mx_cell_faces[type][f];
  const int k = fl[3] < 0 ? 3 : 4;
  uint32_t v[4] = {0, 0, 0, 0};
  for (int j = 0; j < k; j++) v[j] = out->conn[8 * (size_t)cv + (size_t)fl[j]];
  mx_rd_add_face(out, k, v, t);
  return MX_OK;
}

/* The regions after the convexes: "BEGIN REGION t", items, "END REGION t"
 * (BOUNDARY for REGION, as older GetFEM wrote). Anything else ends them. */
static int getfem_regions(cur *c, mx_mesh_data *out) {
  size_t cap = 0;
  for (;;) {
    const char *save = c->p;
    size_t n;
    const char *t = cur_tok(c, &n);
    if (!tok_eq(t, n, "BEGIN")) break;
    const char *w = cur_tok(c, &n);
    const int region = tok_eq(w, n, "REGION");
    if (!region && !tok_eq(w, n, "BOUNDARY")) {
      c->p = save;
      break;
    }
    const char *at = cur_skip(c);
    int64_t num = 0;
    MX_CHECK(cur_int(c, &num, "GetFEM region number"));
    if (num < 0 || num > INT32_MAX)
      return mx_rd_fail(c->r, at, "region number %lld is out of range (0 to %d)",
                        (long long)num, INT32_MAX);
    for (;;) {
      const char *it = cur_tok(c, &n);
      if (n == 0)
        return mx_rd_fail(c->r, it, "region %lld: no END %s (truncated file?)",
                          (long long)num, region ? "REGION" : "BOUNDARY");
      if (tok_eq(it, n, "END")) break;
      MX_CHECK(getfem_region_item(c, it, n, (int32_t)num, out, &cap));
    }
    MX_CHECK(mx_rd_cur_words(c, region ? "REGION" : "BOUNDARY", "GetFEM"));
    at = cur_skip(c);
    int64_t again = 0;
    MX_CHECK(cur_int(c, &again, "GetFEM region number"));
    if (again != num)
      return mx_rd_fail(c->r, at, "END REGION %lld closes region %lld",
                        (long long)again, (long long)num);
  }
  return MX_OK;
}

int mx_rd_getfem(rd *r, const char *p, mx_mesh_data *out) {
  cur c = {r, mx_rd_skip_percent_lines(r, p), 0, 0};
  MX_CHECK(mx_rd_cur_words(&c, "BEGIN POINTS LIST", "GetFEM"));
  MX_CHECK(getfem_points(&c, out));
  MX_CHECK(mx_rd_cur_words(&c, "BEGIN MESH STRUCTURE DESCRIPTION", "GetFEM"));
  MX_CHECK(getfem_convexes(&c, out));
  return getfem_regions(&c, out);
}
