/* mixoct: the section syntax of .mdl files (io/mdl_sections.h). */
#include "io/mdl_sections.h"

#include <string.h>
#include <strings.h>

#include "base/common.h"
#include "io/text_scan.h"

int mx_mdl_same(const char *s, int n, const char *word) {
  return (size_t)n == strlen(word) && strncasecmp(s, word, (size_t)n) == 0;
}

int mx_mdl_parse_header(const char *path, long line, const char *p, const char *end,
                        const char *example, mx_mdl_header *h) {
  const char *nl = memchr(p, '\n', (size_t)(end - p));
  const char *eol = nl ? nl : end;
  const char *comma = memchr(p, ',', (size_t)(eol - p));
  const char *close = memchr(p, ']', (size_t)(eol - p));
  if (*p != '[' || !comma || !close || close < comma) {
    mx_error(path, line, "expected a section header such as '%s', found '%.*s'", example,
             mx_io_toklen(p, 0), p);
    return MX_EINPUT;
  }
  h->name = mx_io_blank(p + 1);
  h->nname = (int)(comma - h->name);
  while (h->nname > 0 && h->name[h->nname - 1] == ' ') h->nname--;
  h->type = mx_io_blank(comma + 1);
  h->ntype = (int)(close - h->type);
  while (h->ntype > 0 && h->type[h->ntype - 1] == ' ') h->ntype--;
  return MX_OK;
}

int mx_mdl_is_array(const mx_mdl_header *h) {
  return h->ntype > 7 && strncasecmp(h->type, "ARRAY1<", 7) == 0;
}

int mx_mdl_count(const char *path, long *line, const char **p, const char *end,
                 const mx_mdl_header *h, int64_t max, size_t *n) {
  *p = mx_io_next_line(*p, end, line);
  *p = mx_io_content(*p, end, line, 0);
  int64_t v;
  const char *e = *p < end ? mx_io_int(*p, &v) : NULL;
  if (!e || !mx_io_eol(mx_io_blank(e), 0) || v < 0 || v > max) {
    mx_error(path, *line, "[%.*s] section: expected the item count", h->nname, h->name);
    return MX_EINPUT;
  }
  *n = (size_t)v;
  return MX_OK;
}

int mx_mdl_non_array(const char *path, long *line, const char **p, const char *end,
                     const mx_mdl_header *h) {
  if (mx_mdl_same(h->type, h->ntype, "STRING")) { /* the value is the next line */
    *p = mx_io_next_line(*p, end, line);
    return MX_OK;
  }
  mx_error(path, *line, "[%.*s] section: unsupported type '%.*s'", h->nname, h->name, h->ntype,
           h->type);
  return MX_EINPUT;
}

int mx_mdl_once(const char *path, long line, int *seen, const mx_mdl_header *h) {
  if (!*seen) {
    *seen = 1;
    return MX_OK;
  }
  mx_error(path, line, "duplicate [%.*s] section", h->nname, h->name);
  return MX_EINPUT;
}
