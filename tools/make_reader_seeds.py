#!/usr/bin/env python3
"""Writes the seeds of the mesh and size map fuzzers for the formats other
programs write (tools/fuzz.sh: mesh_vtu, mesh_msh, mesh_vtk, sizemap_vtu) into
tools/fuzz_seeds/, each under 8192 bytes (fuzz.sh's -max_len), written from
the formats' documentation:

  mesh_vtu     a hexahedron, a pyramid, a prism and a tetrahedron with
               surface_tag and material, as VTU with zlib blocks (raw appended,
               UInt64; inline base64, UInt32; several small blocks), LZ4 (a
               block of literals; appended base64, BigEndian), xz (inline),
               no compressor (appended base64; inline base64);
  mesh_msh     the same cells with a boundary triangle and quadrangle, a
               point and a line, as MSH 2.2 ASCII and binary;
  mesh_vtk     the same as legacy VTK with the boundary cells (Gmsh's .vtk);
  sizemap_vtu  a point field h, zlib inline base64 and LZ4 appended raw.

    python3 tools/make_reader_seeds.py [SEEDS_DIR]"""
import base64
import lzma
import os
import struct
import sys
import zlib

OUT = sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), "fuzz_seeds")

# a unit cube (hex), a pyramid on its top, a prism on its +x side, a tet below
PTS = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (0, 0, 1), (1, 0, 1), (1, 1, 1), (0, 1, 1),
       (0.5, 0.5, 1.5), (2, 0, 0), (2, 0, 1), (0.5, 0.5, -0.5)]
# VTK types and node lists (VTK's orders)
CELLS = [(12, [0, 1, 2, 3, 4, 5, 6, 7]), (14, [4, 5, 6, 7, 8]), (13, [1, 9, 2, 5, 10, 6]),
         (10, [0, 2, 1, 11])]
MATERIAL = [1, 1, 2, 3]
SURFACE_TAG = [1] * 12


def write(sub, name, data):
    d = os.path.join(OUT, sub)
    os.makedirs(d, exist_ok=True)
    if isinstance(data, str):
        data = data.encode()
    assert len(data) < 8192, name
    with open(os.path.join(d, name), "wb") as f:
        f.write(data)


def lz4_literals(b):
    """An LZ4 block of one sequence of literals (no match)."""
    n = len(b)
    out = bytearray([min(n, 15) << 4])
    if n >= 15:
        k = n - 15
        while k >= 255:
            out.append(255)
            k -= 255
        out.append(k)
    return bytes(out) + b


def compress(comp, b):
    return {"zlib": zlib.compress, "lzma": lambda x: lzma.compress(x, format=lzma.FORMAT_XZ),
            "lz4": lz4_literals}[comp](b)


def block(data, comp, hfmt, bs=32768):
    """A DataArray's bytes: header then data (compressed in blocks of bs)."""
    if comp is None:
        return struct.pack(hfmt, len(data)) + data
    parts = [data[i:i + bs] for i in range(0, len(data), bs)] or [b""]
    streams = [compress(comp, p) for p in parts]
    last = len(parts[-1]) if len(parts[-1]) != bs else 0
    head = struct.pack(hfmt[0] + hfmt[1] * (3 + len(streams)), len(parts), bs, last,
                       *[len(s) for s in streams])
    return head + b"".join(streams)


def vtu(comp=None, mode="appended", b64=False, header=64, big=False, bs=32768, point_h=False):
    """A VTU file of the cells (mode: appended or binary; b64: appended base64)."""
    order = ">" if big else "<"
    hfmt = order + ("Q" if header == 64 else "I")
    conn = [v for _, c in CELLS for v in c]
    offs, k = [], 0
    for _, c in CELLS:
        k += len(c)
        offs.append(k)
    arrays = [  # section, type, name, ncomp, bytes
        ("PointData", "UInt8", "surface_tag", 1, bytes(SURFACE_TAG)),
        ("CellData", "Int32", "material", 1, struct.pack(order + "%di" % 4, *MATERIAL)),
        ("Points", "Float64", "Points", 3, struct.pack(order + "%dd" % 36, *[x for p in PTS for x in p])),
        ("Cells", "Int64", "connectivity", 1, struct.pack(order + "%dq" % len(conn), *conn)),
        ("Cells", "Int64", "offsets", 1, struct.pack(order + "%dq" % len(offs), *offs)),
        ("Cells", "UInt8", "types", 1, bytes(t for t, _ in CELLS)),
    ]
    if point_h:
        arrays.insert(0, ("PointData", "Float64", "h", 1,
                          struct.pack(order + "12d", *[0.25 + 0.125 * i for i in range(12)])))
    attrs = 'byte_order="%s" header_type="UInt%d"' % ("BigEndian" if big else "LittleEndian", header)
    if comp:
        attrs += ' compressor="%s"' % {"zlib": "vtkZLibDataCompressor", "lz4": "vtkLZ4DataCompressor",
                                       "lzma": "vtkLZMADataCompressor"}[comp]
    xml = ['<?xml version="1.0"?>', '<VTKFile type="UnstructuredGrid" version="1.0" %s>' % attrs,
           "  <UnstructuredGrid>", '    <Piece NumberOfPoints="12" NumberOfCells="4">']
    app = b""
    section = None
    for sec, typ, name, nc, data in arrays:
        if sec != section:
            if section:
                xml.append("      </%s>" % section)
            xml.append("      <%s>" % sec)
            section = sec
        blob = block(data, comp, hfmt, bs)
        ncomp = ' NumberOfComponents="%d"' % nc if nc > 1 else ""
        if mode == "binary":
            if comp:  # VTK's way: header and data encoded apart
                nb = struct.unpack_from(hfmt, blob)[0]
                hlen = (3 + nb) * struct.calcsize(hfmt)
                text = base64.b64encode(blob[:hlen]) + base64.b64encode(blob[hlen:])
            else:
                text = base64.b64encode(blob)
            xml.append('        <DataArray type="%s" Name="%s"%s format="binary">%s</DataArray>'
                       % (typ, name, ncomp, text.decode()))
        else:
            piece = base64.b64encode(blob) if b64 else blob
            xml.append('        <DataArray type="%s" Name="%s"%s format="appended" offset="%d"/>'
                       % (typ, name, ncomp, len(app)))
            app += piece
    xml.append("      </%s>" % section)
    xml += ["    </Piece>", "  </UnstructuredGrid>"]
    head = ("\n".join(xml) + "\n").encode()
    if mode == "binary":
        return head + b"</VTKFile>\n"
    enc = "base64" if b64 else "raw"
    return head + ('  <AppendedData encoding="%s">\n   _' % enc).encode() + app + \
        b"\n  </AppendedData>\n</VTKFile>\n"


GMSH_TYPE = {12: 5, 14: 7, 13: 6, 10: 4}


def gmsh_order(t, c):
    """Gmsh's node order of a VTK cell (the prism's triangles turned)."""
    return [c[0], c[2], c[1], c[3], c[5], c[4]] if t == 13 else c


def msh22(binary):
    """MSH 2.2: a point, a line, a triangle and a quadrangle, then the cells
    (tags 10 to 13, listed from the last)."""
    elems = [(1, 15, [1, 0], [1]), (2, 1, [0, 7], [1, 2]), (3, 2, [5, 30], [1, 2, 12]),
             (4, 3, [5, 31], [1, 2, 3, 4])]
    for i, (t, c) in reversed(list(enumerate(CELLS))):
        elems.append((10 + i, GMSH_TYPE[t], [MATERIAL[i], 40 + i], [v + 1 for v in gmsh_order(t, c)]))
    out = [b"$MeshFormat\n2.2 %d 8\n" % binary]
    if binary:
        out.append(struct.pack("<i", 1) + b"\n")
    out.append(b'$EndMeshFormat\n$PhysicalNames\n2\n2 5 "wall"\n3 1 "solid"\n$EndPhysicalNames\n')
    out.append(b"$Nodes\n%d\n" % len(PTS))
    for i, p in enumerate(PTS):
        if binary:
            out.append(struct.pack("<i3d", i + 1, *p))
        else:
            out.append(b"%d %r %r %r\n" % (i + 1, *[float(x) for x in p]))
    out.append(b"%s$EndNodes\n$Elements\n%d\n" % (b"\n" if binary else b"", len(elems)))
    for tag, typ, tags, nodes in elems:
        if binary:  # one block per element: type, 1, ntags; tag, tags, nodes
            out.append(struct.pack("<%di" % (4 + len(tags) + len(nodes)), typ, 1, len(tags), tag,
                                   *tags, *nodes))
        else:
            out.append(" ".join(map(str, [tag, typ, len(tags)] + tags + nodes)).encode() + b"\n")
    out.append(b"%s$EndElements\n" % (b"\n" if binary else b""))
    return b"".join(out)


def gmsh_vtk():
    """Legacy VTK with the cells and the boundary cells first (as Gmsh)."""
    cells = [(1, [0]), (3, [0, 7]), (5, [0, 1, 11]), (9, [0, 1, 2, 3])] + CELLS
    mat = [5, 5, 5, 5] + MATERIAL
    lines = ["# vtk DataFile Version 2.0", "seed, Created by Gmsh", "ASCII", "DATASET UNSTRUCTURED_GRID",
             "POINTS %d double" % len(PTS)] + ["%r %r %r" % tuple(map(float, p)) for p in PTS]
    lines.append("CELLS %d %d" % (len(cells), sum(1 + len(c) for _, c in cells)))
    lines += [" ".join(map(str, [len(c)] + c)) for _, c in cells]
    lines.append("CELL_TYPES %d" % len(cells))
    lines += [str(t) for t, _ in cells]
    lines += ["CELL_DATA %d" % len(cells), "SCALARS material int 1", "LOOKUP_TABLE default"]
    lines += [str(m) for m in mat]
    return "\n".join(lines) + "\n"


write("mesh_vtu", "zlib_raw_u64.vtu", vtu("zlib"))
write("mesh_vtu", "zlib_blocks_u32.vtu", vtu("zlib", header=32, bs=40))
write("mesh_vtu", "zlib_inline_u32.vtu", vtu("zlib", mode="binary", header=32))
write("mesh_vtu", "lz4_b64_be.vtu", vtu("lz4", b64=True, big=True, bs=64))
write("mesh_vtu", "xz_inline.vtu", vtu("lzma", mode="binary"))
write("mesh_vtu", "b64_appended.vtu", vtu(None, b64=True))
write("mesh_vtu", "b64_inline_be.vtu", vtu(None, mode="binary", big=True))
write("mesh_msh", "v22_ascii.msh", msh22(0))
write("mesh_msh", "v22_binary.msh", msh22(1))
write("mesh_vtk", "gmsh_boundary.vtk", gmsh_vtk())
write("sizemap_vtu", "zlib_inline_h.vtu", vtu("zlib", mode="binary", point_h=True))
write("sizemap_vtu", "lz4_raw_h.vtu", vtu("lz4", point_h=True, bs=48))
