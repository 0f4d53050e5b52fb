/* The triangle soup: every input surface, merged into one set of arrays.
 * Vertices are structure-of-arrays; triangles are index triples. Each
 * triangle remembers which input file ("shell") it came from, and which face
 * of that file: the face's number and, for text files, its line (so that
 * messages name what the user can find in the file, not triangle numbers
 * after polygons were split). */
#ifndef MX_TRISOUP_H
#define MX_TRISOUP_H

#include <stddef.h>
#include <stdint.h>

/* Lines of faces, in runs: triangles [t0, the next run's t0) come from faces
 * on evenly spaced lines, face f on line line0 + step (f - face0); line0 = 0
 * where lines are unknown (binary files, surfaces made in memory). A text
 * file usually needs one run (more where comments or other lines break the
 * spacing). */
typedef struct {
  uint32_t t0, face0, line0, step; /* step 0: only face0 seen so far */
} mx_line_run;

typedef struct {
  size_t nv, nt;      /* vertex and triangle counts */
  size_t cap_v, cap_t;
  double *x, *y, *z;  /* nv coordinates each */
  uint32_t *tri;      /* 3*nt vertex indices, 0-based */
  uint16_t *shell;    /* nt: index of the input file the triangle came from */
  uint16_t nshells;
  /* nt: the number of the face of its file the triangle comes from, as the
   * format counts (OFF, PLY, STL, MDL from 0, OBJ from 1); the triangles of a
   * polygon are consecutive. A triangle added without a face (arrays, demo,
   * tests) is its own face: face[t] = t. */
  uint32_t *face;
  mx_line_run *run; /* nrun runs, t0 increasing (src/soa/trisoup_origin.c) */
  size_t nrun, cap_run;
} mx_trisoup;

void mx_trisoup_free(mx_trisoup *s);
/* Grow to hold at least nv vertices and nt triangles (new face slots get
 * face[t] = t). MX_OK or MX_EINPUT. */
int mx_trisoup_reserve(mx_trisoup *s, size_t nv, size_t nt);
/* Append src to dst; src's triangles get shell id dst->nshells and keep
 * their faces and lines. */
int mx_trisoup_append(mx_trisoup *dst, const mx_trisoup *src);
/* Set vertex i (growing the arrays as needed; nv becomes at least i+1). */
int mx_trisoup_set_vertex(mx_trisoup *s, size_t i, const double c[3]);
/* Append one triangle (shell 0), growing the arrays as needed; it is its
 * own face (face nt), or a triangle of the given face. */
int mx_trisoup_add_triangle(mx_trisoup *s, uint32_t a, uint32_t b, uint32_t c);
int mx_trisoup_add_face_triangle(mx_trisoup *s, uint32_t a, uint32_t b, uint32_t c,
                                 uint32_t face);
/* Removes the triangles for which drop(s, t, ctx) is true, keeping the
 * order of the others with their shells, faces and lines; returns how many
 * went. drop sees the soup as it was up to t (earlier triangles kept in
 * place until the first one dropped). */
size_t mx_trisoup_remove_if(mx_trisoup *s, int (*drop)(const mx_trisoup *s, size_t t, void *ctx),
                            void *ctx);
/* Axis-aligned bounding box: lo[3], hi[3]. */
void mx_trisoup_bbox(const mx_trisoup *s, double lo[3], double hi[3]);

/* Where a triangle comes from (src/soa/trisoup_origin.c). */
/* Records that face `face`, whose triangles start at triangle t, is on line
 * `line` of its file (line <= 0 or beyond 32 bits: unknown). Faces are noted
 * in the order of their triangles. MX_OK, or MX_EINPUT (out of memory). */
int mx_trisoup_note_line(mx_trisoup *s, size_t t, uint32_t face, long line);
/* The line of triangle t's face, 0 if unknown. */
long mx_trisoup_line(const mx_trisoup *s, size_t t);
/* Triangle t named as its file knows it, for messages, NUL-terminated in
 * buf[n]: "triangle 57 (line 62)" when its input has only triangles, else
 * "face 12 (triangle 2 of 4, line 57)", "face 13 (line 58)" (a face kept
 * whole), without the line where unknown. Returns 1 when the name has a
 * parenthesis. The input is not named (see mx_surface_defects_describe). */
int mx_trisoup_name(const mx_trisoup *s, size_t t, char *buf, size_t n);

/* For trisoup.c: src's runs appended to dst's (triangles shifted by
 * dst->nt); runs left with no triangle dropped (after a removal). */
int mx_trisoup_append_runs(mx_trisoup *dst, const mx_trisoup *src);
void mx_trisoup_drop_empty_runs(mx_trisoup *s);

/* Checks after reading (src/io/surface_check.c): degenerate triangles (zero
 * area or repeated vertex) are removed with a warning that counts them;
 * unused vertices are kept. Edges used by other than exactly two triangles are
 * counted and, if any, a warning says the surface is not closed and that
 * inside/outside may be wrong. Returns MX_OK, or MX_EINPUT when no triangle
 * is left. *open_edges receives the count (may be NULL). */
int mx_trisoup_check(mx_trisoup *s, const char *path, size_t *open_edges);
/* The domain's shells (triangles [0, nt)) must not overlap: a triangle of
 * one input lying on a triangle of another (same three points, either
 * orientation) is refused with a message naming both files (names[shell])
 * and the triangle numbers in each; MX_EINPUT then. */
int mx_trisoup_check_shells(const mx_trisoup *s, uint32_t nt, const char *const *names);

#endif
