"""The meshio side of to_meshio: cell names, node orders, the import."""
import ctypes


#: meshio's names of TET, PYRAMID, PRISM, HEX
_MESHIO_NAMES = ("tetra", "pyramid", "wedge", "hexahedron")
#: node j of a meshio cell is node _MESHIO_ORDER[type][j] of ours: meshio
#: takes VTK's order, except for the linear wedge, where it takes Gmsh's
#: (the triangle 0 1 2 turns towards 3 4 5), which is ours (mixoct.h); its
#: VTK files swap the wedge's nodes themselves
_MESHIO_ORDER = ((0, 1, 2, 3), (0, 1, 2, 3, 4), (0, 1, 2, 3, 4, 5),
                 (0, 1, 2, 3, 4, 5, 6, 7))


def _import_meshio():
    try:
        import meshio
    except ImportError as e:
        raise ImportError("to_meshio needs meshio (Debian: python3-meshio; "
                          "pip: meshio)") from e
    return meshio


class _BoundaryOwner:
    """Owns the arrays of one mx_mesher_boundary_arrays call."""

    def __init__(self, lib, b):
        self.free = lib.mx_boundary_arrays_free
        self.b = b

    def __del__(self):
        try:
            self.free(ctypes.byref(self.b))
        except Exception:  # noqa: BLE001 (interpreter shutting down)
            pass
