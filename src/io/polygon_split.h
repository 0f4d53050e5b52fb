/* The polygon faces of surface files (OFF, OBJ, PLY) split into triangles,
 * one face at a time, by ear clipping in the plane of the face.
 *
 * A reader gives the corners of each face (mx_polysplit_corner), then the
 * face (mx_polysplit_face), which adds its triangles to the soup with the
 * face's number and line (soa/trisoup.h). A triangle is added as it is. A
 * polygon:
 *   - repeated corners: a corner equal to the one before (same index or
 *     same point) is dropped; a
 *     polygon that comes back to a corner is split there into loops, each
 *     split on its own (a loop of two corners, an edge there and back, makes
 *     nothing). A loop turning the other way than the face (a hole bridged
 *     by repeated corners, or a crossing) is refused;
 *   - its mean plane: the Newell normal n; the corners are projected along
 *     the axis of n's largest component (dropping a coordinate: exact, so
 *     the orientation tests on the projection are exact, geom/orient2d.h);
 *   - ear clipping: an ear is a strictly convex corner b (neighbours a, c)
 *     whose closed triangle abc holds no other corner but copies of a and c;
 *     only reflex and flat corners need testing, and ears are kept in a list
 *     in polygon order, updated at a and c after each clip: O(k r) for k
 *     corners of which r are reflex or flat, O(k) for a convex polygon. The
 *     next ear is searched from the corner after the last one clipped, so a
 *     convex polygon gives the fan from its first corner (as before), and a
 *     corner on a straight run gives no zero-area triangle (it is never an
 *     ear, and a simple polygon always has a strictly convex ear);
 *   - a polygon that crosses or touches itself in the projection (two edges
 *     that are not neighbours meet: tested exactly up to 64 corners a loop),
 *     or that has no ear left, is refused naming the face, as is one that
 *     would take more than 2^27 point-in-triangle tests (k r > 2^25: too
 *     large and too tangled, about a second);
 *   - a polygon whose corners leave its mean plane by more than 1e-3 of its
 *     size is split the same way (its triangles form a surface over its
 *     projection, so they do not cross each other): a warning;
 *   - a polygon of zero area (collinear or repeated corners only) makes no
 *     triangle: a warning (an error when no face of the file makes one).
 * The warnings come once a file, from mx_polysplit_finish: how many faces,
 * and the first one. A reader whose faces may come before the coordinates
 * they use calls mx_polysplit_defer: the faces then wait for
 * mx_polysplit_finish (in file order). No allocation per face: the buffers
 * grow and are reused. */
#ifndef MX_POLYGON_SPLIT_H
#define MX_POLYGON_SPLIT_H

#include <stddef.h>
#include <stdint.h>

#include "base/common.h"
#include "soa/trisoup.h"

/* A face in its file, for messages and for the soup: its number as the
 * format counts, its line (text files, else 0) and its byte offset (binary
 * files, else -1). */
typedef struct {
  uint64_t face;
  long line;
  int64_t byte;
} mx_face_at;

/* The first face with one kind of repair, and how many faces had it. */
typedef struct {
  size_t count;
  mx_face_at first;
  double worst; /* non-planar faces: the largest relative deviation */
} mx_face_note;

typedef struct {
  const char *path;
  uint32_t *v; /* the corners of the current face */
  size_t nv, cap_v;
  int defer;
  uint32_t *qv; /* deferred faces: their corners, then the faces */
  size_t nqv, cap_qv;
  struct mx_queued_face *q;
  size_t nq, cap_q;
  unsigned char *work; /* the split's scratch */
  size_t cap_work;
  mx_face_note nonplanar, zero_area, repeated;
} mx_polysplit;

void mx_polysplit_init(mx_polysplit *ps, const char *path);
void mx_polysplit_free(mx_polysplit *ps);

/* Grows the corner buffer; MX_ENOMEM when out of memory. */
int mx_polysplit_grow(mx_polysplit *ps);

/* One more corner of the current face (a vertex index, in range). */
static inline int mx_polysplit_corner(mx_polysplit *ps, uint32_t v) {
  if (ps->nv == ps->cap_v && mx_polysplit_grow(ps) != MX_OK) return MX_ENOMEM;
  ps->v[ps->nv++] = v;
  return MX_OK;
}

/* The corners given since the last face (at least 3) form face `at`: its
 * triangles are added to s (the coordinates of its corners must be set),
 * or queued after mx_polysplit_defer. MX_OK, or MX_EINPUT with a message
 * naming the file, line and face. */
int mx_polysplit_face(mx_polysplit *ps, mx_trisoup *s, mx_face_at at);

/* The same for a face of three corners v[0..3), given directly. */
int mx_polysplit_triangle(mx_polysplit *ps, mx_trisoup *s, const uint32_t v[3], mx_face_at at);

/* From now on faces wait for mx_polysplit_finish. */
void mx_polysplit_defer(mx_polysplit *ps);

/* Splits the faces that waited, then prints the warnings; MX_EINPUT when
 * no face made a triangle. */
int mx_polysplit_finish(mx_polysplit *ps, mx_trisoup *s);

#endif
