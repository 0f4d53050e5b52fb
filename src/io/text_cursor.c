/* The cursor routines that several mesh readers share beyond the inline ones
 * of io/text_cursor.h: growing the cells, expected words, and the node
 * indices of one element line (MSH, Medit, M3D, MVM, GetFEM). */
#include "io/text_cursor.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "base/common.h"

/* Grows the cells of out by n (n already checked against the file size). */
int mx_rd_grow_cells(rd *r, mx_mesh_data *out, size_t n) {
  const size_t nc = out->ncells + n;
  if (nc > UINT32_MAX / 6)
    return mx_rd_fail(r, NULL, "more than %u volume elements", UINT32_MAX / 6);
  uint8_t *t = mx_realloc(out->type, nc + 1);
  if (!t) return MX_ENOMEM;
  out->type = t;
  uint32_t *cn = mx_realloc(out->conn, (8 * nc + 1) * sizeof *cn);
  if (!cn) return MX_ENOMEM;
  out->conn = cn;
  memset(out->conn + 8 * out->ncells, 0, 8 * n * sizeof *cn);
  return MX_OK;
}

/* The next tokens must be the blank-separated words of `words`. */
int mx_rd_cur_words(cur *c, const char *words, const char *what) {
  for (const char *w = words; *w;) {
    const size_t wl = strcspn(w, " ");
    size_t n;
    const char *t = cur_tok(c, &n);
    if (n == 0)
      return mx_rd_fail(c->r, t, "%s: expected '%s', found the end of the file "
                        "(truncated file?)", what, words);
    if (n != wl || strncasecmp(t, w, n) != 0)
      return mx_rd_fail(c->r, t, "%s: expected '%s', found '%.*s'", what, words,
                        shown(n), t);
    w += wl;
    while (*w == ' ') w++;
  }
  return MX_OK;
}

/* The node indices of cell `cell` of the given type, the j-th read into
 * slot perm[j] of its row (perm NULL: slot j). */
int mx_rd_cur_cell_nodes(cur *c, mx_mesh_data *out, size_t cell, int type,
                         const int8_t *perm) {
  uint32_t *row = out->conn + 8 * cell;
  memset(row, 0, 8 * sizeof *row);
  for (int j = 0; j < mx_cell_nodes[type]; j++) {
    const char *at = cur_skip(c);
    int64_t v = 0;
    MX_CHECK(cur_int(c, &v, "element node"));
    if (v < 0 || (uint64_t)v >= out->nnodes)
      return mx_rd_fail(c->r, at,
                        "element %zu: node %lld out of range (%zu nodes, 0-based)",
                        cell, (long long)v, out->nnodes);
    row[perm ? perm[j] : j] = (uint32_t)v;
  }
  out->type[cell] = (uint8_t)type;
  return MX_OK;
}
