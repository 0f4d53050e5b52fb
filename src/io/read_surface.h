/* The surface readers: one triangle soup from one file (src/io/read_*.c,
 * the dispatcher in src/io/read_surface.c). */
#ifndef MX_READ_SURFACE_H
#define MX_READ_SURFACE_H

#include "soa/trisoup.h"

/* Readers (src/io/read_*.c). Each fills an empty soup from one file, or
 * prints "mixoct: FILE:LINE: error: ..." and returns MX_EINPUT. Coordinates
 * that are NaN or infinite, indices out of range, wrong counts, truncated
 * files, empty files and unreadable files are all errors. */
int mx_read_off(const char *path, mx_trisoup *out);
int mx_read_mdl(const char *path, mx_trisoup *out);
int mx_read_stl(const char *path, mx_trisoup *out); /* ASCII or binary */
int mx_read_obj(const char *path, mx_trisoup *out);
int mx_read_ply(const char *path, mx_trisoup *out); /* ASCII, binary LE/BE */
/* OFF, OBJ and PLY faces may be polygons: they are split into triangles in
 * their plane (src/io/polygon_split.h). */
/* Dispatch on the extension (case-insensitive .off .mdl .stl .obj .ply). */
int mx_read_surface(const char *path, mx_trisoup *out);

#endif
