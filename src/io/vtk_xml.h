/* The XML tags of a VTU or PVTU file (src/io/vtk_xml.c). */
#ifndef MX_VTK_XML_H
#define MX_VTK_XML_H

#include "io/mesh_reader.h"

typedef struct {
  const char *start, *name, *a, *ae, *after;
  size_t nlen;
  int closing, selfclose;
} xtag;

/* The next element tag at or after p; *found = 0 at the end. */
int mx_rd_xml_next(const rd *r, const char *p, xtag *t, int *found);
/* Whether t is the element `name`. */
int mx_rd_tag_is(const xtag *t, const char *name);
/* The value of attribute `name` of t in *v (*vn bytes); 0 if absent. */
int mx_rd_xml_attr(const xtag *t, const char *name, const char **v, size_t *vn);
/* Whether attribute `name` of t is `value`. */
int mx_rd_attr_eq(const xtag *t, const char *name, const char *value);
/* A non-negative integer attribute; *v untouched when absent and optional. */
int mx_rd_attr_size(const rd *r, const xtag *t, const char *name, uint64_t *v,
                    int required);

#endif
