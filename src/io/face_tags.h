/* The tagged faces a mesh reader appends (MSH, Medit, GetFEM;
 * src/io/face_tags.c). */
#ifndef MX_FACE_TAGS_H
#define MX_FACE_TAGS_H

#include "io/mesh_reader.h"

/* Room for n more tagged faces in out (capacity *cap, at least doubled; n
 * already checked against the file size). */
int mx_rd_face_room(rd *r, mx_mesh_data *out, size_t *cap, size_t n);
/* Appends a face (room made by mx_rd_face_room). */
void mx_rd_add_face(mx_mesh_data *out, int nn, const uint32_t v[4], int32_t tag);
/* A tag read as a 64-bit integer must fit an int32. */
int mx_rd_tag_range(rd *r, const char *at, int64_t v, const char *what);

#endif
