/* The section syntax shared by the .mdl readers (io/read_mdl.c: 3D
 * surfaces, io/read_poly.c: 2D polylines). A file is a list of sections,
 * each headed "[Name, TYPE]" on a line of its own; an ARRAY1<...> section
 * has an item count on its next content line, then the items; a STRING
 * section has its value on the next line. Names and types are compared
 * without case; there are no comments. Positions are (path, line, p) as in
 * io/text_scan.h: p points at the current line, line is its number. */
#ifndef MX_MDL_SECTIONS_H
#define MX_MDL_SECTIONS_H

#include <stdint.h>
#include <stddef.h>

typedef struct {
  const char *name, *type; /* not NUL-terminated */
  int nname, ntype;
} mx_mdl_header;

/* Whether the n characters at s are word, without case. */
int mx_mdl_same(const char *s, int n, const char *word);

/* The header "[Name, TYPE]" of the line at p (surrounding blanks are not
 * part of the name nor the type). An error message shows `example`, a
 * valid header. */
int mx_mdl_parse_header(const char *path, long line, const char *p, const char *end,
                        const char *example, mx_mdl_header *h);

/* Whether h is an ARRAY1<...> section. */
int mx_mdl_is_array(const mx_mdl_header *h);

/* After the header line at *p: moves to the next content line, which must
 * hold the item count of section h, an integer in [0, max], alone. */
int mx_mdl_count(const char *path, long *line, const char **p, const char *end,
                 const mx_mdl_header *h, int64_t max, size_t *n);

/* A section that is not an array, header line at *p: a STRING's value
 * line is stepped over (*p moves to it); any other type is an error. */
int mx_mdl_non_array(const char *path, long *line, const char **p, const char *end,
                     const mx_mdl_header *h);

/* The first section named as h sets *seen; a second one is an error. */
int mx_mdl_once(const char *path, long line, int *seen, const mx_mdl_header *h);

#endif
