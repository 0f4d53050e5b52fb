/* Reading a size map (issue 27, size fields): points each with a target
 * element size h > 0, written by a solver or a user, for the mesher's size
 * field (src/io/read_sizemap.c).
 *
 * The format follows the extension (case-insensitive):
 *  - .vtu, .vtp, .vtk: a VTK file, told by its content: VTK XML ('<':
 *    an UnstructuredGrid or a PolyData, one Piece, ascii or appended raw
 *    arrays, as the mesh reader takes them, io/read_mesh.h; compressed and
 *    base64 data refused) or legacy ('# vtk DataFile Version': ASCII or
 *    BINARY, DATASET UNSTRUCTURED_GRID or POLYDATA). The points and a
 *    field of one component (any number type): a point field gives each
 *    point its size; a cell field gives it to each cell's centroid (the
 *    mean of its nodes; PolyData cells in VTK's order: vertices, lines,
 *    polygons, strips). The field read:
 *      1. the one named `field` (exactly), a point field before a cell
 *         field of the same name; an error listing the fields when there
 *         is none, or when it has more than one component;
 *      2. without `field`: the first field of one component, in the
 *         file's order, named size, h, target_size or sizes (in any case),
 *         among the point fields, then among the cell fields;
 *      3. else the point field of one component if there is exactly one;
 *         with no such point field, the cell field if there is exactly one;
 *      4. else an error listing the fields and asking to pick one.
 *    (Legacy files: an attribute the reader does not know, such as
 *    TENSORS, ends the attributes; the fields after it are not seen, and
 *    the error listing the fields says where it stopped.)
 *  - .pos: a Gmsh post-processing file in the parsed format:
 *    View "name" { ST(x1,y1,z1, x2,y2,z2, x3,y3,z3){v1,v2,v3}; ... };
 *    Scalar elements SP, SL, ST, SQ, SS, SH, SI, SY (point, line,
 *    triangle, quadrangle, tetrahedron, hexahedron, prism, pyramid) and
 *    their second-order forms SL2 .. SY2: each node is a point whose size
 *    is its value. An element with k nodes and m * k values holds m time
 *    steps: the first step is read. Vector and tensor elements (VP .. VY2,
 *    TP .. TY2) are skipped with one warning for the view; text (T2, T3),
 *    TIME and INTERPOLATION_SCHEME are skipped silently. Coordinates and
 *    values must be plain numbers (no expressions). Comments (from // to
 *    the end of the line, and C's block comments) are skipped, and so are
 *    statements outside the views (up to their ';'). The view read is the
 *    first one named `field` when given
 *    (an error listing the views when there is none), else the first; the
 *    file is not read past it.
 *  - anything else: plain text, one point a line, "x y z h", numbers
 *    separated by blanks; blank lines and '#' comments (a line's rest from
 *    '#') are skipped; a line of another count of numbers is an error (2D
 *    lines "x y h" are not accepted: give z = 0). `field` is not used (a
 *    warning says so when given).
 *
 * Every coordinate must be finite and every size finite and > 0; an error
 * names the file and the line (text, .pos, ASCII VTK) or, in binary data,
 * the byte offset, with the point (or cell) and the value. A map of no
 * point is an error. Counts announced by a file are checked against its
 * size before anything is allocated for them.
 *
 * Returns MX_OK with *n > 0 points: *xyz (3 doubles a point, x y z) and *h
 * (one a point), allocated by the library's allocator (mx_alloc and
 * mx_realloc), for the caller to mx_free; MX_EINPUT after one message
 * (mx_error) for any bad input; MX_ENOMEM. On failure *xyz and *h are NULL
 * and *n is 0. */
#ifndef MX_READ_SIZEMAP_H
#define MX_READ_SIZEMAP_H

#include <stddef.h>

int mx_sizemap_read(const char *path, const char *field, double **xyz, double **h, size_t *n);

#endif
