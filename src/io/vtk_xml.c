/* XML tags of the VTK XML files, for the VTU and PVTU readers (declared in
 * io/vtk_xml.h): the next element tag, skipping declarations and comments,
 * and its attributes. */
#include "io/vtk_xml.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "base/common.h"

/* The next element tag at or after p; *found = 0 at the end. */
int mx_rd_xml_next(const rd *r, const char *p, xtag *t, int *found) {
  const char *end = r->end;
  for (;;) {
    const char *lt = p < end ? memchr(p, '<', (size_t)(end - p)) : NULL;
    if (!lt) {
      *found = 0;
      return MX_OK;
    }
    size_t left = (size_t)(end - lt);
    if (left >= 2 && lt[1] == '?') {
      const char *q = memmem(lt, left, "?>", 2);
      if (!q) return mx_rd_fail(r, lt, "unterminated '<?'");
      p = q + 2;
      continue;
    }
    if (left >= 4 && memcmp(lt, "<!--", 4) == 0) {
      const char *q = memmem(lt, left, "-->", 3);
      if (!q) return mx_rd_fail(r, lt, "unterminated comment");
      p = q + 3;
      continue;
    }
    if (left >= 2 && lt[1] == '!') {
      const char *q = memchr(lt, '>', left);
      if (!q) return mx_rd_fail(r, lt, "unterminated '<!'");
      p = q + 1;
      continue;
    }
    t->start = lt;
    t->closing = left >= 2 && lt[1] == '/';
    t->name = lt + 1 + t->closing;
    const char *q = t->name;
    while (q < end && !is_ws(*q) && *q != '/' && *q != '>' && *q) q++;
    t->nlen = (size_t)(q - t->name);
    if (t->nlen == 0) return mx_rd_fail(r, lt, "malformed XML tag");
    t->a = q;
    char quote = 0;
    while (q < end && (quote || *q != '>')) {
      if (quote && *q == quote)
        quote = 0;
      else if (!quote && (*q == '"' || *q == '\''))
        quote = *q;
      q++;
    }
    if (q >= end)
      return mx_rd_fail(r, lt, "unterminated tag <%.*s", shown(t->nlen), t->name);
    t->selfclose = q[-1] == '/';
    t->ae = t->selfclose ? q - 1 : q;
    t->after = q + 1;
    *found = 1;
    return MX_OK;
  }
}

int mx_rd_tag_is(const xtag *t, const char *name) {
  return t->nlen == strlen(name) && memcmp(t->name, name, t->nlen) == 0;
}

int mx_rd_xml_attr(const xtag *t, const char *name, const char **v,
                   size_t *vn) {
  const char *p = t->a, *ae = t->ae;
  const size_t nl = strlen(name);
  while (p < ae) {
    while (p < ae && is_ws(*p)) p++;
    const char *ns = p;
    while (p < ae && *p != '=' && !is_ws(*p)) p++;
    size_t n = (size_t)(p - ns);
    while (p < ae && is_ws(*p)) p++;
    if (p >= ae || *p != '=') return 0;
    p++;
    while (p < ae && is_ws(*p)) p++;
    if (p >= ae || (*p != '"' && *p != '\'')) return 0;
    char q = *p++;
    const char *vs = p;
    while (p < ae && *p != q) p++;
    if (p >= ae) return 0;
    if (n == nl && memcmp(ns, name, n) == 0) {
      *v = vs;
      *vn = (size_t)(p - vs);
      return 1;
    }
    p++;
  }
  return 0;
}

int mx_rd_attr_eq(const xtag *t, const char *name, const char *value) {
  const char *v;
  size_t n;
  return mx_rd_xml_attr(t, name, &v, &n) && n == strlen(value) &&
         memcmp(v, value, n) == 0;
}

/* A non-negative integer attribute; *v untouched when absent and optional. */
int mx_rd_attr_size(const rd *r, const xtag *t, const char *name,
                    uint64_t *v, int required) {
  const char *s;
  size_t n;
  if (!mx_rd_xml_attr(t, name, &s, &n)) {
    if (!required) return MX_OK;
    return mx_rd_fail(r, t->start, "<%.*s> has no %s attribute", shown(t->nlen),
                      t->name, name);
  }
  uint64_t x = 0;
  size_t i = 0;
  while (i < n && is_ws(s[i])) i++;
  if (i == n) return mx_rd_fail(r, s, "%s=\"\" is not a number", name);
  for (; i < n && !is_ws(s[i]); i++) {
    if (s[i] < '0' || s[i] > '9' || x > ((uint64_t)1 << 56))
      return mx_rd_fail(r, s, "%s=\"%.*s\" is not a valid count", name, shown(n),
                        s);
    x = 10 * x + (uint64_t)(s[i] - '0');
  }
  *v = x;
  return MX_OK;
}
