/* mixoct: reading Medit .mesh / .meshb (see read_mesh.h), in one pass with
 * the cursor of io/text_cursor.h; every count is checked against the bytes
 * left before anything is allocated for it.
 *
 * ASCII: keywords (case-insensitive) followed by their data, '#' comments.
 * "MeshVersionFormatted v", "Dimension 3", "Vertices n" + n lines "x y z
 * ref", "Tetrahedra", "Pyramids", "Prisms", "Hexahedra" n + n lines of
 * 1-based vertex indices and a reference; "Triangles", "Quadrilaterals" the
 * same, kept as the tagged faces (tag: the reference); "End". Other
 * keywords (Edges, Corners, Normals...) are skipped up to the next word. Binary: int32 1 (byte order), int32 version 1..4, then blocks: int32
 * keyword code, the next block's position (int32 up to version 2, int64
 * from 3), for Dimension its int32 value, else the line count (int32 up to
 * version 3, int64 in 4) and the lines: reals float32 in version 1, float64
 * after; integers int32 up to version 3, int64 in 4. Unknown keywords are
 * skipped through their next position; "End" (54) stops. Node orders are
 * mixoct's (see io/write_medit.c); cells come grouped by keyword, in file
 * order.
 *
 * Cell labels (cell_tag, several materials): each volume element's
 * reference, when the references are not all the same (every element with
 * one reference, as a plain mesh is written: NULL). References that differ
 * must fit an int32. */
#include "io/mesh_reader.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "base/common.h"
#include "io/face_tags.h"
#include "io/text_cursor.h"
#include "io/text_scan.h"

enum {
  MED_DIM = 3, MED_VERT = 4, MED_TRI = 6, MED_QUAD = 7, MED_TET = 8,
  MED_PRISM = 9, MED_HEX = 10, MED_PYR = 49, MED_END = 54
};

/* The node count of a face keyword, 0 for others. */
static int medit_face_nodes(int code) {
  return code == MED_TRI ? 3 : code == MED_QUAD ? 4 : 0;
}

static int medit_cell_type(int code) {
  switch (code) {
    case MED_TET: return MX_TET;
    case MED_PYR: return MX_PYRAMID;
    case MED_PRISM: return MX_PRISM;
    case MED_HEX: return MX_HEX;
    default: return -1;
  }
}

/* 1-based vertex indices of the cells and faces -> 0-based, checked. */
static int medit_indices(rd *r, mx_mesh_data *out) {
  for (size_t c = 0; c < out->ncells; c++) {
    uint32_t *row = out->conn + 8 * c;
    for (int j = 0; j < mx_cell_nodes[out->type[c]]; j++) {
      if (row[j] == 0 || row[j] > out->nnodes)
        return mx_rd_fail(r, NULL,
                          "element %zu: vertex %u out of range (%zu vertices, "
                          "1-based)",
                          c, row[j], out->nnodes);
      row[j]--;
    }
  }
  for (size_t f = 0; f < out->nfaces; f++) {
    uint32_t *row = out->face_conn + 4 * f;
    for (int j = 0; j < out->face_nn[f]; j++) {
      if (row[j] == 0 || row[j] > out->nnodes)
        return mx_rd_fail(r, NULL,
                          "%s %zu: vertex %u out of range (%zu vertices, 1-based)",
                          out->face_nn[f] == 3 ? "triangle" : "quadrilateral", f,
                          row[j], out->nnodes);
      row[j]--;
    }
  }
  return MX_OK;
}

/* The elements' references as they are read (into out->cell_tag, grown
 * with the cells), whether they differ, and the first that does not fit an
 * int32. */
typedef struct {
  int64_t first;
  int varies;
  const char *bad_at; /* or NULL */
  int64_t bad;
} medit_refs;

/* Room for the references of the cells c0.. c0 + n - 1. */
static int refs_room(mx_mesh_data *out, size_t c0, size_t n) {
  int32_t *t = mx_realloc(out->cell_tag, (c0 + n + 1) * sizeof *t);
  if (!t) return MX_ENOMEM;
  out->cell_tag = t;
  return MX_OK;
}

/* The reference v of cell c, read at `at`. */
static void ref_add(medit_refs *R, mx_mesh_data *out, size_t c, int64_t v, const char *at) {
  if (c == 0) R->first = v;
  R->varies |= v != R->first;
  if ((v < INT32_MIN || v > INT32_MAX) && !R->bad_at) {
    R->bad_at = at;
    R->bad = v;
  }
  out->cell_tag[c] = (int32_t)v;
}

/* cell_tag kept when the references differ (and fit), else NULL. */
static int refs_end(rd *r, const medit_refs *R, mx_mesh_data *out) {
  if (R->varies && R->bad_at) return mx_rd_tag_range(r, R->bad_at, R->bad, "element reference");
  if (!R->varies || out->ncells == 0) {
    mx_free(out->cell_tag);
    out->cell_tag = NULL;
  }
  return MX_OK;
}

static int medit_kw_type(const char *t, size_t n) {
  static const struct {
    const char *name;
    int code;
  } kw[] = {{"Dimension", MED_DIM}, {"Vertices", MED_VERT},
            {"Tetrahedra", MED_TET}, {"Prisms", MED_PRISM},
            {"Hexahedra", MED_HEX}, {"Pyramids", MED_PYR},
            {"Triangles", MED_TRI}, {"Quadrilaterals", MED_QUAD},
            {"End", MED_END}};
  for (size_t i = 0; i < sizeof kw / sizeof kw[0]; i++)
    if (tok_eq(t, n, kw[i].name)) return kw[i].code;
  return 0;
}

int mx_rd_medit_ascii(rd *r, const char *p, mx_mesh_data *out) {
  cur c = {r, p, 1, 0};
  int have_vert = 0;
  size_t fcap = 0;
  medit_refs R = {0, 0, NULL, 0};
  for (;;) {
    size_t n;
    const char *t = cur_tok(&c, &n);
    if (n == 0) {
      if (t < r->end) return mx_rd_fail(r, t, "unexpected NUL byte");
      return mx_rd_fail(r, NULL, "no End (truncated file?)");
    }
    if (!((*t >= 'A' && *t <= 'Z') || (*t >= 'a' && *t <= 'z')))
      return mx_rd_fail(r, t, "expected a keyword, found '%.*s' (wrong count?)",
                        shown(n), t);
    const int code = medit_kw_type(t, n);
    if (code == MED_END) break;
    if (tok_eq(t, n, "MeshVersionFormatted")) {
      int64_t v = 0;
      MX_CHECK(cur_int(&c, &v, "MeshVersionFormatted"));
      if (v < 1 || v > 4)
        return mx_rd_fail(r, t, "MeshVersionFormatted %lld: the Medit format has versions 1 "
                          "to 4", (long long)v);
      continue;
    }
    if (code == MED_DIM) {
      int64_t d = 0;
      MX_CHECK(cur_int(&c, &d, "Dimension"));
      if (d != 3)
        return mx_rd_fail(r, t, "Dimension %lld: only 3D meshes are supported",
                          (long long)d);
      continue;
    }
    if (code == 0) { /* skipped: numbers up to the next word */
      for (;;) {
        const char *save = c.p;
        const char *s = cur_tok(&c, &n);
        if (n == 0 || (*s >= 'A' && *s <= 'Z') || (*s >= 'a' && *s <= 'z')) {
          c.p = save;
          break;
        }
      }
      continue;
    }
    uint64_t cnt = 0;
    const char *at = cur_skip(&c);
    MX_CHECK(cur_count(&c, &cnt, 0, "line count"));
    if (code == MED_VERT) {
      if (have_vert) return mx_rd_fail(r, t, "Vertices given twice");
      have_vert = 1;
      if (cnt >= UINT32_MAX || cnt > cur_left(&c) / 8 + 1)
        return mx_rd_fail(r, at,
                          "Vertices: %llu announced but the file is too short "
                          "(truncated file or wrong count)",
                          (unsigned long long)cnt);
      out->nnodes = (size_t)cnt;
      out->xyz = mx_alloc((3 * (size_t)cnt + 1) * sizeof(double));
      if (!out->xyz) return MX_ENOMEM;
      for (size_t i = 0; i < cnt; i++) {
        for (int k = 0; k < 3; k++)
          MX_CHECK(cur_real(&c, &out->xyz[3 * i + (size_t)k], "vertex"));
        int64_t ref = 0;
        MX_CHECK(cur_int(&c, &ref, "vertex reference"));
      }
      continue;
    }
    if (medit_face_nodes(code)) {
      const int k = medit_face_nodes(code);
      if (cnt > cur_left(&c) / (2 * (uint64_t)(k + 1)) + 1)
        return mx_rd_fail(r, at,
                          "%.*s: %llu announced but the file is too short "
                          "(truncated file or wrong count)",
                          shown(n), t, (unsigned long long)cnt);
      MX_CHECK(mx_rd_face_room(r, out, &fcap, (size_t)cnt));
      for (size_t i = 0; i < cnt; i++) {
        uint32_t v[4] = {0, 0, 0, 0};
        int64_t ref = 0;
        for (int j = 0; j <= k; j++) {
          const char *vat = cur_skip(&c);
          int64_t x = 0;
          MX_CHECK(cur_int(&c, &x, "face"));
          if (j == k) {
            MX_CHECK(mx_rd_tag_range(r, vat, x, "reference"));
            ref = x;
          } else if (x < 1 || x >= (int64_t)UINT32_MAX) {
            return mx_rd_fail(r, vat, "%.*s %zu: vertex %lld out of range",
                              shown(n), t, i + 1, (long long)x);
          } else {
            v[j] = (uint32_t)x;
          }
        }
        mx_rd_add_face(out, k, v, (int32_t)ref);
      }
      continue;
    }
    const int vt = medit_cell_type(code);
    const int k = mx_cell_nodes[vt];
    if (cnt > cur_left(&c) / (2 * (uint64_t)(k + 1)) + 1)
      return mx_rd_fail(r, at,
                        "%.*s: %llu announced but the file is too short (truncated "
                        "file or wrong count)",
                        shown(n), t, (unsigned long long)cnt);
    const size_t c0 = out->ncells;
    MX_CHECK(mx_rd_grow_cells(r, out, (size_t)cnt));
    MX_CHECK(refs_room(out, c0, (size_t)cnt));
    for (size_t i = 0; i < cnt; i++) {
      uint32_t *row = out->conn + 8 * (c0 + i);
      for (int j = 0; j <= k; j++) {
        const char *vat = cur_skip(&c);
        int64_t v = 0;
        MX_CHECK(cur_int(&c, &v, "element"));
        if (j == k) { /* the reference */
          ref_add(&R, out, c0 + i, v, vat);
          break;
        }
        if (v < 1 || v >= (int64_t)UINT32_MAX)
          return mx_rd_fail(r, vat, "%.*s %zu: vertex %lld out of range",
                            shown(n), t, i + 1, (long long)v);
        row[j] = (uint32_t)v;
      }
      out->type[c0 + i] = (uint8_t)vt;
    }
    out->ncells = c0 + (size_t)cnt;
  }
  if (!have_vert) return mx_rd_fail(r, NULL, "no Vertices");
  MX_CHECK(medit_indices(r, out));
  return refs_end(r, &R, out);
}

int mx_rd_meshb(rd *r, mx_mesh_data *out) {
  cur c = {r, r->buf, 0, 0};
  r->bin_from = r->buf;
  MX_CHECK(cur_need(&c, 8, "header"));
  const uint32_t one = (uint32_t)bin_u(&c, 4);
  c.swap = one != 1;
  const int ver = (int)(int32_t)(uint32_t)bin_u(&c, 4);
  if (ver < 1 || ver > 4)
    return mx_rd_fail(r, r->buf + 4, "version %d (1 to 4)", ver);
  const int pos_size = ver >= 3 ? 8 : 4, cnt_size = ver >= 4 ? 8 : 4,
            real_size = ver == 1 ? 4 : 8, int_size = ver >= 4 ? 8 : 4;
  int have_vert = 0;
  size_t fcap = 0;
  medit_refs R = {0, 0, NULL, 0};
  const size_t len = (size_t)(r->end - r->buf);
  for (;;) {
    if (cur_left(&c) == 0) return mx_rd_fail(r, NULL, "no End (truncated file?)");
    const char *at = c.p;
    MX_CHECK(cur_need(&c, 4 + (uint64_t)pos_size, "keyword"));
    const int code = (int)(int32_t)(uint32_t)bin_u(&c, 4);
    const uint64_t next = bin_u(&c, pos_size);
    if (code == MED_END) break;
    const size_t here = (size_t)(c.p - r->buf);
    if (next != 0 && (next <= here - 4 - (uint64_t)pos_size || next > len))
      return mx_rd_fail(r, at, "keyword %d: next position %llu is not after it "
                        "and inside the file",
                        code, (unsigned long long)next);
    if (code == MED_DIM) {
      MX_CHECK(cur_need(&c, 4, "Dimension"));
      const int d = (int)(int32_t)(uint32_t)bin_u(&c, 4);
      if (d != 3)
        return mx_rd_fail(r, at, "Dimension %d: only 3D meshes are supported", d);
    } else if (code == MED_VERT || medit_cell_type(code) >= 0 ||
               medit_face_nodes(code)) {
      MX_CHECK(cur_need(&c, (uint64_t)cnt_size, "line count"));
      const uint64_t cnt = bin_u(&c, cnt_size);
      const int vt = medit_cell_type(code), fk = medit_face_nodes(code);
      const uint64_t line =
          fk     ? (uint64_t)(fk + 1) * (uint64_t)int_size
          : vt < 0 ? 3 * (uint64_t)real_size + (uint64_t)int_size
                   : (uint64_t)(mx_cell_nodes[vt] + 1) * (uint64_t)int_size;
      if (cnt > cur_left(&c) / line)
        return mx_rd_fail(r, at,
                          "keyword %d: %llu lines of %llu bytes announced but "
                          "only %zu bytes are left (truncated file or wrong "
                          "count)",
                          code, (unsigned long long)cnt, (unsigned long long)line,
                          cur_left(&c));
      if (fk) {
        MX_CHECK(mx_rd_face_room(r, out, &fcap, (size_t)cnt));
        for (size_t i = 0; i < cnt; i++) {
          uint32_t v[4] = {0, 0, 0, 0};
          for (int j = 0; j <= fk; j++) {
            const uint64_t u = bin_u(&c, int_size);
            const int64_t sv = int_size == 4 ? (int32_t)(uint32_t)u
                                             : (int64_t)u;
            if (j == fk) {
              MX_CHECK(mx_rd_tag_range(r, c.p - int_size, sv, "reference"));
              mx_rd_add_face(out, fk, v, (int32_t)sv);
            } else if (sv < 1 || sv >= (int64_t)UINT32_MAX) {
              return mx_rd_fail(r, c.p - int_size,
                                "%s %zu: vertex %lld out of range",
                                fk == 3 ? "triangle" : "quadrilateral",
                                out->nfaces, (long long)sv);
            } else {
              v[j] = (uint32_t)sv;
            }
          }
        }
      } else if (vt < 0) {
        if (have_vert) return mx_rd_fail(r, at, "Vertices given twice");
        have_vert = 1;
        if (cnt >= UINT32_MAX) return mx_rd_fail(r, at, "too many vertices");
        out->nnodes = (size_t)cnt;
        out->xyz = mx_alloc((3 * (size_t)cnt + 1) * sizeof(double));
        if (!out->xyz) return MX_ENOMEM;
        for (size_t i = 0; i < cnt; i++) {
          for (int k = 0; k < 3; k++) {
            const double v = bin_real(&c, real_size);
            if (!isfinite(v))
              return mx_rd_fail(r, c.p - real_size,
                                "vertex %zu: coordinate %d is not a finite number",
                                i + 1, k);
            out->xyz[3 * i + (size_t)k] = v;
          }
          c.p += int_size; /* reference */
        }
      } else {
        const int k = mx_cell_nodes[vt];
        const size_t c0 = out->ncells;
        MX_CHECK(mx_rd_grow_cells(r, out, (size_t)cnt));
        MX_CHECK(refs_room(out, c0, (size_t)cnt));
        for (size_t i = 0; i < cnt; i++) {
          uint32_t *row = out->conn + 8 * (c0 + i);
          for (int j = 0; j < k; j++) {
            const uint64_t v = bin_u(&c, int_size);
            const int64_t sv = int_size == 4 ? (int32_t)(uint32_t)v
                                             : (int64_t)v;
            if (sv < 1 || sv >= (int64_t)UINT32_MAX)
              return mx_rd_fail(r, c.p - int_size,
                                "element %zu: vertex %lld out of range", c0 + i,
                                (long long)sv);
            row[j] = (uint32_t)sv;
          }
          const uint64_t u = bin_u(&c, int_size); /* the reference */
          ref_add(&R, out, c0 + i, int_size == 4 ? (int32_t)(uint32_t)u : (int64_t)u,
                  c.p - int_size);
          out->type[c0 + i] = (uint8_t)vt;
        }
        out->ncells = c0 + (size_t)cnt;
      }
    } else if (next == 0) {
      return mx_rd_fail(r, at, "keyword %d has no next position", code);
    }
    if (next != 0) {
      if (r->buf + next < c.p)
        return mx_rd_fail(r, at, "keyword %d: its data runs past the next block",
                          code);
      c.p = r->buf + next;
    }
  }
  if (!have_vert) return mx_rd_fail(r, NULL, "no Vertices");
  MX_CHECK(medit_indices(r, out));
  return refs_end(r, &R, out);
}

/* Whether the text at p starts with "MeshVersionFormatted" (after blanks
 * and '#' comments). */
int mx_rd_is_medit_ascii(rd *r, const char *p) {
  cur c = {r, p, 1, 0};
  size_t n;
  const char *t = cur_tok(&c, &n);
  return tok_eq(t, n, "MeshVersionFormatted");
}

int mx_rd_is_meshb(const rd *r) {
  if (r->end - r->buf < 8) return 0;
  uint32_t a, v;
  memcpy(&a, r->buf, 4);
  memcpy(&v, r->buf + 4, 4);
  if (a == 0x01000000u) v = __builtin_bswap32(v);
  return (a == 1 || a == 0x01000000u) && v >= 1 && v <= 4;
}
