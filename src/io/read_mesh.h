/* Reading back the volume meshes mixoct writes (src/io/write_vtk.c,
 * src/io/write_vtu.c, src/io/write_msh.c, src/io/write_medit.c,
 * src/io/write_m3d.c, src/io/write_getfem.c), for `mixoct check` and the
 * tests.
 *
 * Accepted, recognised by content (not by extension):
 *  - legacy VTK, "# vtk DataFile Version x.y", ASCII or BINARY (big-endian),
 *    DATASET UNSTRUCTURED_GRID: POINTS float|double, CELLS as the classic
 *    count-prefixed list or, from version 5, as OFFSETS + CONNECTIVITY
 *    (vtktypeint32/int64), CELL_TYPES; FIELD and METADATA blocks are
 *    skipped; of CELL_DATA / POINT_DATA only surface_tag and material are
 *    read (below);
 *  - VTK XML UnstructuredGrid (.vtu), one Piece, byte_order Little- or
 *    BigEndian, header_type UInt32 or UInt64, arrays format="ascii",
 *    "binary" (inline base64) or "appended" (<AppendedData encoding="raw"
 *    or "base64">), uncompressed or compressed by vtkZLibDataCompressor,
 *    vtkLZ4DataCompressor or vtkLZMADataCompressor (io/vtu_decode.h);
 *    points Float32 or Float64 with 3 components; connectivity, offsets
 *    and types of any integer type (Int8 .. UInt64).
 *  - a parallel VTU master (.pvtu: VTKFile type="PUnstructuredGrid"),
 *    read as one mesh: each <Piece Source="..."/> (relative to the
 *    .pvtu's directory unless absolute) a VTU file as above, all with the
 *    same point and cell arrays; with the point array GlobalNodeId
 *    (integers) in the pieces the points of one id are one node (numbered
 *    by id; their coordinates must agree), without it points of different
 *    pieces with bitwise-equal coordinates are one node (numbered in the
 *    order they first appear; points of one piece stay distinct); cells in
 *    piece order; surface_tag merged with the nodes (io/pvtu.h writes
 *    such files). A missing or unreadable piece is an error naming the
 *    .pvtu's line.
 * Cell types: VTK 10 (tetra), 14 (pyramid), 13 (wedge), 12 (hexahedron);
 * beside them, triangles (5) and quadrilaterals (9) are the tagged faces
 * (below) and vertices (1) and lines (3) are skipped (Gmsh's .vtk files);
 * any other type is an error. Node order stays VTK's (as in soa/mesh.h);
 *  - Gmsh MSH 2.2, ASCII or binary (either byte order; src/io/read_msh22.c):
 *    $Nodes, $Elements and $PhysicalNames read as 4.1's below, an element's
 *    entity being its physical tag, or its elementary tag when that is 0;
 *  - Gmsh MSH 4.1 ("$MeshFormat" first), ASCII or binary (either byte
 *    order, size_t of 4 or 8 bytes): $Nodes and $Elements, other sections
 *    skipped; linear tetrahedra, hexahedra, prisms and pyramids kept in the
 *    order of their element tags (mixoct writes tag = index + 1, so a file
 *    of src/io/write_msh.c reads back in its order); triangles and
 *    quadrangles of dimension 2 are the tagged faces (below); points,
 *    lines and other triangles and quadrangles are skipped; other types
 *    are an error;
 *  - Medit .mesh (ASCII, "MeshVersionFormatted" first) and .meshb (binary,
 *    versions 1 to 4, either byte order): Vertices, Tetrahedra, Pyramids,
 *    Prisms, Hexahedra, Triangles and Quadrilaterals (the tagged faces,
 *    below), other keywords skipped, "End" required; cells in
 *    the file's order (so grouped by type), node orders as in
 *    src/io/write_medit.c (mixoct's);
 *  - M3D ("[Nodes," first: the published mesher's layout, REFERENCE.md,
 *    and mixoct's older one), MVM ("MIXED" first) and GetFEM ('%' comment
 *    lines or "BEGIN POINTS LIST" first), as src/io/write_m3d.c and
 *    src/io/write_getfem.c write them; a file whose content names no
 *    format is read as the one its extension (.m3d, .mvm, .getfem) names.
 *    Node orders as in soa/mesh.h (prisms in Gmsh's order); GetFEM's
 *    pyramids and hexahedra are reordered to it.
 *
 * Boundary tags (the tagged boundary faces of mixoct's full-stage files,
 * see io/write_msh.c, io/write_medit.c, io/write_getfem.c):
 *  - MSH: the triangles (type 2) and quadrangles (3) of blocks of
 *    dimension 2; a face's tag is the first physical tag of its surface
 *    entity in $Entities (the entity tag when the entity has none or the
 *    file has no $Entities); names from $PhysicalNames of dimension 2 (the
 *    text between the first and the last '"' of the line);
 *  - Medit: Triangles and Quadrilaterals, the tag being the reference;
 *  - GetFEM: after END MESH STRUCTURE DESCRIPTION, "BEGIN REGION t" (or
 *    BOUNDARY, GetFEM's older word), blank-separated items "cv/f" (face f of
 *    convex cv, GetFEM's face numbering: io/getfem_tables.h) or "cv" (a
 *    whole convex, not a face: skipped), "END REGION t"; anything else
 *    after the convexes ends the reading, as before regions were read;
 *  - VTK, VTU: the triangles and quadrilaterals beside volume cells, tagged
 *    with their value of the cell field material (0 without it); an
 *    integer point field named surface_tag (legacy:
 *    SCALARS in POINT_DATA; VTU: a DataArray of <PointData>) is returned as
 *    node_tag. Other attributes are skipped; an attribute the legacy reader
 *    does not know ends the attributes (its values are not read).
 * M3D and MVM files have none.
 *
 * Cell labels (several materials, issue 26), cell_tag, one per cell in the
 * cells' order as returned, or NULL:
 *  - MSH: the first physical tag of the element's volume entity in
 *    $Entities (the entity tag when it has none, or is not listed, or the
 *    file has no $Entities); NULL when every volume element has the same
 *    label (one volume, or one physical volume: a plain mesh);
 *  - Medit: the elements' references, NULL when they are all equal;
 *  - VTK, VTU (and the pieces of a .pvtu, which must all have it or none):
 *    the cell field material (legacy: SCALARS or a FIELD array in
 *    CELL_DATA; VTU: a DataArray of <CellData>), one component, one value
 *    per cell, integers or floats that are whole numbers; NULL without it.
 * A label must fit an int32; a material field of the wrong count,
 * components or type, or with a fraction, is an error.
 * Other formats give none.
 *
 * Every count is checked against the bytes left in the file before
 * anything is allocated for it, and binary values are read only after the
 * block holding them was checked to lie in the file. Every problem
 * (unreadable, truncated or inconsistent file, unsupported feature,
 * non-finite coordinate, node index out of range) prints one message naming
 * the file -- with the line in a text part, the byte offset in a binary
 * part -- and returns MX_EINPUT; *out is then empty. */
#ifndef MX_READ_MESH_H
#define MX_READ_MESH_H

#include <stddef.h>
#include <stdint.h>

#include "soa/mesh_data.h"


int mx_read_mesh(const char *path, mx_mesh_data *out);
/* The same, but a legacy VTK or VTU file may instead hold only triangles
 * (VTK type 5) and quadrilaterals (9), every point with z = 0: a 2D mesh,
 * returned with ncells 0 and its cells as the faces (face_nn 3 or 4, the
 * file's node order, face_tag 0). Volume and 2D cells in one file, or a 2D
 * cell's file with a point off the plane, are errors (MX_EINPUT). Other
 * formats read as with mx_read_mesh (MSH, Medit: a file with no volume
 * element has its triangles and quadrilaterals as faces already). For
 * mx_read_mesh_dim. */
int mx_read_mesh_planar(const char *path, mx_mesh_data *out);

/* A mesh file that is 2D or 3D by its content (for `mixoct check`): *dim 2
 * for a 2D mesh, returned as mx_read_mesh_planar returns one (ncells 0, the
 * triangles and quadrilaterals as the faces, every z = 0), else *dim 3 and
 * the mesh as mx_read_mesh_planar reads it:
 *  - legacy VTK (ASCII or binary) and VTU: only triangles (VTK type 5) and
 *    quadrilaterals (9), every point with z = 0;
 *  - Gmsh MSH 4.1 (ASCII or binary) and Medit: no volume element, the
 *    triangles (type 2) and quadrangles (3) of dimension 2 (the lines of the
 *    "boundary" group are skipped), every node with z = 0;
 *  - OFF ("OFF" first, as io/read_off.c's variants): faces of 3 or 4
 *    vertices, every vertex with z = 0 (else MX_EINPUT naming the line: an
 *    OFF file is only read as a 2D mesh here; src/io/read_off_plane.c).
 * The 2D cells keep the file's node order (a clockwise cell stays
 * clockwise: the checks see it). GetFEM and M3D 2D files are not read
 * (their 3D readers take 3 coordinates and volume types). */
int mx_read_mesh_dim(const char *path, mx_mesh_data *out, int *dim);
#endif
