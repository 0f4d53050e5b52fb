"""The variants of one mesh that other programs write, for reader_variants_test.sh.

usage: reader_variants.py make DIR MESH.vtu
         writes DIR/NAME for every variant meshio 5 and VTK 9 write of MESH.vtu
         (one line per file on stdout: NAME LOSSY, LOSSY 1 when the writer
         prints coordinates with fewer digits than a double needs) and the
         size maps sz_*.vtu (a point field h on MESH's points)
       reader_variants.py ref FILE OUT.vtu
         FILE read by meshio (legacy .vtk: by VTK) and written as raw
         appended binary: the same numbers as FILE's text, parsed by another
         program (for the lossy files)
       reader_variants.py corrupt KIND FILE OUT
         a broken copy of a VTK XML file (KIND: flip, cut, huge, ratio, b64)
"""
import re
import struct
import sys
import warnings

warnings.simplefilter("ignore")


def make(d, src):
    import meshio
    import vtk

    m = meshio.read(src)
    out = []

    def mio(name, lossy=0, **kw):
        meshio.write(d + "/" + name, m, **kw)
        out.append((name, lossy))

    mio("mio_zlib.vtu")                        # meshio's default: zlib, inline base64
    mio("mio_lzma.vtu", compression="lzma")
    mio("mio_inline.vtu", compression=None)    # inline base64, uncompressed
    mio("mio_ascii.vtu", 1, binary=False)      # %.11e
    mio("mio_bin.vtk")
    mio("mio_ascii.vtk", binary=False)
    mio("mio22b.msh", file_format="gmsh22")
    mio("mio22a.msh", file_format="gmsh22", binary=False)

    r = vtk.vtkXMLUnstructuredGridReader()
    r.SetFileName(src)
    r.Update()
    g = r.GetOutput()

    def xml(name, mode="appended", comp="zlib", b64=False, header=64, big=False, lossy=0):
        w = vtk.vtkXMLUnstructuredGridWriter()
        w.SetFileName(d + "/" + name)
        w.SetInputData(g)
        {"appended": w.SetDataModeToAppended, "binary": w.SetDataModeToBinary,
         "ascii": w.SetDataModeToAscii}[mode]()
        if b64:
            w.EncodeAppendedDataOn()
        else:
            w.EncodeAppendedDataOff()  # VTK's default is on
        {"zlib": w.SetCompressorTypeToZLib, "lz4": w.SetCompressorTypeToLZ4,
         "lzma": w.SetCompressorTypeToLZMA, "none": w.SetCompressorTypeToNone}[comp]()
        if header == 32:
            w.SetHeaderTypeToUInt32()
        else:
            w.SetHeaderTypeToUInt64()
        if big:
            w.SetByteOrderToBigEndian()
        else:
            w.SetByteOrderToLittleEndian()
        if not w.Write():
            raise SystemExit("vtk could not write " + name)
        out.append((name, lossy))

    w = vtk.vtkXMLUnstructuredGridWriter()                 # VTK's defaults:
    w.SetFileName(d + "/vtk_default.vtu")                 # appended base64, zlib
    w.SetInputData(g)
    w.Write()
    out.append(("vtk_default.vtu", 0))
    xml("vtk_zlib.vtu")                                  # ParaView's default: raw, zlib
    xml("vtk_raw.vtu", comp="none")
    xml("vtk_b64.vtu", b64=True)                         # appended base64, zlib
    xml("vtk_b64_raw.vtu", b64=True, comp="none")
    xml("vtk_inline.vtu", mode="binary")                 # inline base64, zlib
    xml("vtk_inline_raw.vtu", mode="binary", comp="none")
    xml("vtk_ascii.vtu", mode="ascii")
    xml("vtk_lz4.vtu", comp="lz4")
    xml("vtk_lzma.vtu", comp="lzma")
    xml("vtk_u32.vtu", header=32)
    xml("vtk_be.vtu", big=True)
    xml("vtk_be_u32_lz4_b64.vtu", big=True, header=32, comp="lz4", b64=True)
    xml("vtk_be_inline_lzma.vtu", big=True, mode="binary", comp="lzma")

    for name, binary, version in [("vtk_legacy.vtk", 0, None), ("vtk_legacy_bin.vtk", 1, None),
                                  ("vtk_legacy42_bin.vtk", 1, 42)]:
        w = vtk.vtkUnstructuredGridWriter()
        w.SetFileName(d + "/" + name)
        w.SetInputData(g)
        if binary:
            w.SetFileTypeToBinary()
        if version is not None:
            if not hasattr(w, "SetFileVersion"):
                continue
            w.SetFileVersion(version)
        w.Write()
        out.append((name, 0 if binary else 1))  # ASCII legacy: 11 digits

    # size maps: h = 2 + |p| / 10 at the points
    a = vtk.vtkDoubleArray()
    a.SetName("h")
    for i in range(g.GetNumberOfPoints()):
        x, y, z = g.GetPoint(i)
        a.InsertNextValue(2.0 + (x * x + y * y + z * z) ** 0.5 / 10.0)
    g.GetPointData().AddArray(a)
    xml("sz_zlib.vtu")
    xml("sz_lz4_b64.vtu", comp="lz4", b64=True, header=32)
    xml("sz_inline_lzma_be.vtu", mode="binary", comp="lzma", big=True)
    xml("sz_raw.vtu", comp="none")
    for name, lossy in out:
        print(name, lossy)


def ref(src, dst):
    import meshio

    if src.endswith(".vtk"):  # meshio 5.0 does not read VTK 9's ASCII 5.1
        import vtk

        r = vtk.vtkUnstructuredGridReader()
        r.SetFileName(src)
        r.Update()
        w = vtk.vtkXMLUnstructuredGridWriter()
        w.SetFileName(dst)
        w.SetInputData(r.GetOutput())
        w.SetDataModeToAppended()
        w.EncodeAppendedDataOff()
        w.SetCompressorTypeToNone()
        w.Write()
        return
    m = meshio.read(src)
    cells = [c for c in m.cells if c.type in ("tetra", "pyramid", "wedge", "hexahedron")]
    meshio.write(dst, meshio.Mesh(m.points, cells), compression=None)


def appended(b):
    """The VTKFile's header size, its byte order, the offset of the '_' and
    the offsets of the DataArrays, the Points' first."""
    head = b[: b.index(b"<AppendedData")]
    hsize = 8 if b'header_type="UInt64"' in head else 4
    order = ">" if b'byte_order="BigEndian"' in head else "<"
    under = b.index(b"_", b.index(b"<AppendedData"))
    offs = [int(x) for x in re.findall(rb'offset="(\d+)"', head)]
    pts = re.search(rb'<Points>\s*<DataArray[^>]*offset="(\d+)"', head)
    return hsize, order, under + 1, [int(pts.group(1))] + sorted(offs)


def corrupt(kind, src, dst):
    b = bytearray(open(src, "rb").read())
    hsize, order, base, offs = appended(b)
    fmt = order + ("Q" if hsize == 8 else "I")
    at = base + offs[0]  # the Points' block
    if kind == "b64":  # a character that is not base64 in the first array
        b[at + 10] = ord("#")
    else:
        nb, bs, last = struct.unpack_from(order + 3 * fmt[1], b, at)
        sizes = at + 3 * hsize
        c0 = struct.unpack_from(fmt, b, sizes)[0]
        payload = sizes + nb * hsize
        if kind == "flip":  # one byte in the middle of block 0's stream
            b[payload + c0 // 2] ^= 0x55
        elif kind == "huge":  # block 0 said larger than the file
            struct.pack_into(fmt, b, sizes, (1 << 31) - 1)
        elif kind == "ratio":  # a block size no zlib stream of that size gives
            struct.pack_into(fmt, b, at + hsize, (1 << 31) - 1)
            struct.pack_into(fmt, b, at + 2 * hsize, 0)
        elif kind == "cut":  # the last array's block cut in its middle
            last_at = base + offs[-1]
            nbl = struct.unpack_from(fmt, b, last_at)[0]
            pl = last_at + (3 + nbl) * hsize
            end = b.index(b"</AppendedData>", pl)
            b = b[: pl + (end - pl) // 2] + b"\n  </AppendedData>\n</VTKFile>\n"
    open(dst, "wb").write(b)


if __name__ == "__main__":
    if sys.argv[1] == "make":
        make(sys.argv[2], sys.argv[3])
    elif sys.argv[1] == "ref":
        ref(sys.argv[2], sys.argv[3])
    elif sys.argv[1] == "corrupt":
        corrupt(sys.argv[2], sys.argv[3], sys.argv[4])
