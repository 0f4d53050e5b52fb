/* The header of an OFF file, shared by its three readers: io/read_off.c (a
 * surface), io/read_off_plane.c (a 2D mesh for `mixoct check`) and
 * io/read_poly.c (2D polylines). '#' starts a comment. */
#ifndef MX_OFF_HEADER_H
#define MX_OFF_HEADER_H

#include <stddef.h>

/* 1 when the n bytes at tok are "OFF" or a variant whose extra per-vertex
 * data the readers ignore (COFF, NOFF, CNOFF, STOFF...); 0 for anything
 * else, 4OFF and nOFF among them (they change the dimension). */
int mx_off_keyword(const char *tok, int n);

/* The keyword, then the counts "nv nf" (the edge count and anything after
 * ignored) on its line or on the next content line, from *p (the file's
 * start; end its end, *line the line number). On MX_OK *p is the line of
 * the counts. nv above nv_max or nf above nf_max: MX_EINPUT, said with the
 * file and line, as is a missing keyword or missing counts. */
int mx_off_counts(const char *path, const char **p, const char *end, long *line,
                  size_t nv_max, size_t nf_max, size_t *nv, size_t *nf);

/* The next content line after *p's (vertices and faces are a line each);
 * MX_EINPUT "unexpected end of file: i of n WHAT read" when the file ends
 * first. */
int mx_off_next(const char *path, const char **p, const char *end, long *line, const char *what,
                size_t i, size_t n);

#endif
