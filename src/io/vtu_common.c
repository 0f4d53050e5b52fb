/* mixoct: the VTU layout shared by the 3D and 2D writers (io/vtu_common.h). */
#include "io/vtu_common.h"

#include <stdarg.h>
#include <stdio.h>

#include "base/common.h"

static void head_grow(mx_vtu_head *h, size_t need) {
  if (h->failed || h->len + need + 1 <= h->cap) return;
  size_t cap = h->cap ? h->cap : 4096;
  while (cap < h->len + need + 1) cap *= 2;
  char *s = mx_realloc(h->s, cap);
  if (!s) {
    h->failed = 1;
    return;
  }
  h->s = s;
  h->cap = cap;
}

void mx_vtu_printf(mx_vtu_head *h, const char *fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  int n = vsnprintf(NULL, 0, fmt, ap);
  va_end(ap);
  if (n < 0) {
    h->failed = 1;
    return;
  }
  head_grow(h, (size_t)n);
  if (h->failed) return;
  va_start(ap, fmt);
  vsnprintf(h->s + h->len, (size_t)n + 1, fmt, ap);
  va_end(ap);
  h->len += (size_t)n;
}

/* Appends name with the XML special characters escaped. */
static void xml_name(mx_vtu_head *h, const char *name) {
  for (const char *p = name; *p; p++) {
    const char *esc = *p == '&'   ? "&amp;"
                      : *p == '<' ? "&lt;"
                      : *p == '>' ? "&gt;"
                      : *p == '"' ? "&quot;"
                                  : NULL;
    if (esc)
      mx_vtu_printf(h, "%s", esc);
    else
      mx_vtu_printf(h, "%c", *p);
  }
}

void mx_vtu_escaped(mx_vtu_head *h, const char *s) { xml_name(h, s); }

void mx_vtu_begin(mx_vtu_head *h, size_t nnodes, size_t ncells) {
  mx_vtu_printf(h,
                "<?xml version=\"1.0\"?>\n"
                "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" "
                "byte_order=\"LittleEndian\" header_type=\"UInt64\">\n"
                "  <UnstructuredGrid>\n"
                "    <Piece NumberOfPoints=\"%zu\" NumberOfCells=\"%zu\">\n",
                nnodes, ncells);
}

void mx_vtu_array(mx_vtu_head *h, const char *type, const char *name, int ncomp, uint64_t bytes) {
  mx_vtu_printf(h, "        <DataArray type=\"%s\" Name=\"", type);
  xml_name(h, name);
  mx_vtu_printf(h, "\"");
  if (ncomp > 1) mx_vtu_printf(h, " NumberOfComponents=\"%d\"", ncomp);
  mx_vtu_printf(h, " format=\"appended\" offset=\"%llu\"/>\n", (unsigned long long)h->offset);
  h->offset += 8 + bytes;
}

int mx_vtu_end(mx_afile *f, mx_vtu_head *h, size_t nnodes, size_t ncells, uint64_t nconn,
               int wide) {
  const char *it = wide ? "Int64" : "Int32";
  const uint64_t isz = wide ? 8 : 4;
  mx_vtu_printf(h, "      <Points>\n");
  mx_vtu_array(h, "Float64", "Points", 3, 24 * (uint64_t)nnodes);
  mx_vtu_printf(h, "      </Points>\n      <Cells>\n");
  mx_vtu_array(h, it, "connectivity", 1, isz * nconn);
  mx_vtu_array(h, it, "offsets", 1, isz * (uint64_t)ncells);
  mx_vtu_array(h, "UInt8", "types", 1, (uint64_t)ncells);
  mx_vtu_printf(h,
                "      </Cells>\n    </Piece>\n  </UnstructuredGrid>\n"
                "  <AppendedData encoding=\"raw\">\n   _");
  const int st = h->failed ? MX_ENOMEM : mx_afile_write(f, h->s, h->len);
  mx_free(h->s);
  *h = (mx_vtu_head){0};
  return st;
}

int mx_vtu_count(mx_afile *f, uint64_t bytes) {
  char head[8];
  mx_put_le64(head, bytes);
  return mx_afile_write(f, head, 8);
}

int mx_vtu_block(mx_afile *f, uint64_t bytes, size_t n, size_t item_bytes, mx_afile_fill_fn fill,
                 const void *ctx) {
  MX_CHECK(mx_vtu_count(f, bytes));
  return mx_afile_emit(f, n, item_bytes, fill, ctx);
}

int mx_vtu_finish(mx_afile *f) {
  static const char tail[] = "\n  </AppendedData>\n</VTKFile>\n";
  return mx_afile_write(f, tail, sizeof tail - 1);
}
