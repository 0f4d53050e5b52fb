/* Text scanning shared by the readers (src/io/text_scan.c):
 * load a whole file, step over blanks, lines and comments, and parse numbers
 * and indices with messages that name the file and line. */
#ifndef MX_TEXT_SCAN_H
#define MX_TEXT_SCAN_H

#include <stddef.h>
#include <stdint.h>

/* Loads the file into a NUL-terminated buffer (mx_free it). */
int mx_io_load(const char *path, char **buf, size_t *len);
/* The same, but an empty file is no error (*len = 0, *buf still allocated). */
int mx_io_load_empty_ok(const char *path, char **buf, size_t *len);
const char *mx_io_blank(const char *p);
int mx_io_eol(const char *p, char comment);
int mx_io_delim(const char *p, char comment);
const char *mx_io_next_line(const char *p, const char *end, long *line);
const char *mx_io_content(const char *p, const char *end, long *line,
                          char comment);
int mx_io_toklen(const char *p, char comment);
const char *mx_io_double(const char *p, double *v);
const char *mx_io_int(const char *p, int64_t *v);
int mx_io_numbers(const char *path, long line, const char **p, char comment,
                  int n, double *out, const char *what, size_t item);
int mx_io_index(const char *path, long line, const char **p, char comment,
                size_t nv, uint32_t *idx, const char *what, size_t item);

#endif
