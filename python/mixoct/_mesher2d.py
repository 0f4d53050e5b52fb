"""Mesher2D: the 2D quadtree mesher."""
import ctypes

import numpy as np

from ._capi import _MeshArrays2D, _Params2D, _Stats2D, _function, load_library
from ._args import _fspath, _input_arrays
from ._base import _MesherBase, _mesh_view, _view
from ._params import _PARAM2D_CHECKS, _fill_params
from ._meshio import _import_meshio


class Mesher2D(_MesherBase):
    """One 2D mesher (the ``mesher2d`` program's calls, mx_mesher2d_*): a
    domain bounded by closed polylines, requests, the quadtree, the mesh of
    counter-clockwise triangles and quadrilaterals (see the module doc).

    Parameters: every field of ``mx_params2d``, by name; None (or left
    out) is the library's default (``Mesher2D.defaults()``), a value out of
    ``mesher2d``'s range raises InputError naming it: ``surface_level``
    (quadrants meeting the polylines; -1 none, else 0 .. MAX_LEVEL_2D),
    ``all_level`` (every quadrant of the domain; -1 none), ``balance``
    ("edges" or "recursive"), ``threads`` (0: OpenMP's default),
    ``close_ratio`` (the projection of close inside nodes, 0 .. 1),
    ``max_memory_mb`` (0: the memory available), ``feature_levels`` (refine
    the quadrants holding a feature until the features keep apart),
    ``materials`` (a loop nested in an outer one is the interface between
    two materials, not a hole; the cells are cut along it and ``material``
    gives each cell's material).
    Every mesh is checked by the library's
    independent routine: a mesh that fails it raises InvalidMeshError
    (kept: it can be read and written).
    """

    _PREFIX = "mx_mesher2d"
    _ARRAYS = _MeshArrays2D
    _STATS = _Stats2D
    _DIM = 2
    _COORDS = "xy"
    _NCELLS = "ncells"
    _WIDTH = 4
    _CONN = "cells"
    _NOUN = "cells"
    _VIEW_KEYS = ("nodes", "cells", "types", "leaf", "level", "material")
    TYPE_NAMES = ("tri", "quad")
    NODES_PER_TYPE = (3, 4)

    def __init__(self, surface_level=None, all_level=None, balance=None,
                 threads=None, close_ratio=None, max_memory_mb=None,
                 feature_levels=None, materials=None, *, library=None,
                 **params):
        params.update(surface_level=surface_level, all_level=all_level,
                      balance=balance, threads=threads, close_ratio=close_ratio,
                      max_memory_mb=max_memory_mb, feature_levels=feature_levels,
                      materials=materials)
        lib = load_library(library)
        p = _Params2D()
        _function(lib, "mx_params2d_default")(ctypes.byref(p))
        _fill_params(p, params, _PARAM2D_CHECKS, type(self).__name__)
        self._start(lib, p)

    @staticmethod
    def defaults(library=None):
        """The library's default parameters (mx_params2d_default) as a dict."""
        p = _Params2D()
        _function(load_library(library), "mx_params2d_default")(ctypes.byref(p))
        return {f: getattr(p, f) for f, _ in p._fields_}

    # ---- the domain and the requests -------------------------------------------

    def set_domain(self, path):
        """The domain (once): closed polylines from a .poly, .off or 2D .mdl
        file; checked closed and not self-intersecting, loops oriented by
        nesting (outer counter-clockwise, holes clockwise)."""
        self._call("mx_mesher2d_set_domain", _fspath(path))

    def set_domain_arrays(self, xy, seg, name="arrays"):
        """The domain (once) from arrays: xy (n, 2) float, seg (m, 2) 0-based
        vertex indices of the segments of closed loops (any orientation: the
        nesting decides). `name` names the domain in messages. The arrays
        are converted to float64 and uint32 (copied only if needed); the
        library copies them."""
        self._call("mx_mesher2d_set_domain_arrays", str(name).encode(),
                   *_input_arrays(name, xy, 2, "xy", seg, 2, "seg"))

    def set_material(self, depth, number, name=None):
        """With materials=True: the number (1..65535) and name of the
        material at nesting depth `depth` (1: inside the outer loops only,
        2: inside one more loop, ...), written as the Gmsh physical surface
        and the field material, and given by the material view
        (--material ID:NAME, the k-th for depth k)."""
        self._call("mx_mesher2d_set_material", int(depth), int(number),
                   None if name is None else str(name).encode())

    def add_region(self, path, level):
        """Quadrants meeting or inside this closed polyline go to `level`."""
        self._call("mx_mesher2d_add_region", _fspath(path), int(level))

    def add_drawing(self, path, level):
        """Quadrants meeting these segments (closed or not) go to `level`."""
        self._call("mx_mesher2d_add_drawing", _fspath(path), int(level))

    def add_function(self, name, args, level):
        """Quadrants meeting a curve go to `level`: "circle" (cx, cy, r),
        "line" (px, py, nx, ny) or "sine" (amp, freq, phase, y0:
        y = y0 + amp sin(freq x + phase))."""
        a = np.ascontiguousarray(np.ravel(args), dtype=np.float64)
        self._call("mx_mesher2d_add_function", str(name).encode(),
                   a.ctypes.data_as(ctypes.POINTER(ctypes.c_double)), a.size,
                   int(level))

    def set_size(self, expr_or_name, size_min=None, size_max=None):
        """A size field (the program's --size, --size-min, --size-max; as
        Mesher.set_size): an expression of x and y (numbers, + - * / ^,
        exp log sqrt abs sin cos min max, pi, e; z is 0) or one of the test
        functions "F1".."F5"; quadrants are split while larger than the
        least size over them, with the other requests (the finest wins).
        size_min, size_max bound the field's sizes (None: no bound; the
        bounds are set every call). The curves of add_function become
        sources of the field (the side of their level on the curve, plus
        the distance to it). The written meshes carry the cell field
        target_size. Raises InputError with the column of a bad expression
        (nothing changed), and for bounds that are negative or crossed (the
        source set, the bounds as they were)."""
        self._call("mx_mesher2d_set_size_expr", str(expr_or_name).encode())
        self._call("mx_mesher2d_set_size_limits",
                   0.0 if size_min is None else float(size_min),
                   0.0 if size_max is None else float(size_max))

    # ---- restart files ---------------------------------------------------------

    def load_restart(self, path, elements=None, allow_invalid=False):
        """Rebuild the quadtree from a restart file and mesh it (set the same
        domain first; requests already set apply on top).

        elements: indices (array-like) or the path of an element list of
        cells of the mesh that was saved with the restart file (numbered
        as its arrays and files list them), to refine at once."""
        return self._load_restart(path, elements, allow_invalid)

    @property
    def restart_elements(self):
        """How many cells the mesh of the loaded restart file had (0: none
        loaded)."""
        return int(_function(self._lib, "mx_mesher2d_restart_elements")(
            self._ptr))

    # ---- arrays ----------------------------------------------------------------------

    def _make_views(self, a, owner):
        v = super()._make_views(a, owner)
        v["counts"] = {name: int(np.count_nonzero(v["types"] == t))
                       for t, name in enumerate(self.TYPE_NAMES)}
        e = a.ncells
        # NULL without materials: None, not an array of zeros
        v["material"] = (_view(a.material, e, np.uint16, (e,), owner)
                         if a.material else None)
        return v

    nodes = _mesh_view("nodes",
                       "(nnodes, 2) float64 coordinates (read-only view)")
    cells = _mesh_view("cells",
                       "(ncells, 4) uint32 nodes of each cell, counter-"
                       "clockwise; a triangle's 4th is NO_NODE (read-only "
                       "view)")
    types = _mesh_view("types", "(ncells,) uint8: TRI 0, QUAD 1")
    leaf = _mesh_view("leaf", "(ncells,) uint32 quadtree leaf of each cell")
    level = _mesh_view("level", "(ncells,) uint8 level of that leaf")
    material = _mesh_view("material",
                          "(ncells,) uint16 material of each cell (its "
                          "number: by default the nesting depth of its "
                          "region); None without materials=True")

    @property
    def ncells(self):
        return self.nelements

    def to_meshio(self):
        """The mesh as a ``meshio.Mesh`` (copies; 2D points): blocks
        "triangle" and "quad" (counter-clockwise), cell data ``leaf``,
        ``level`` and, with materials, ``material``."""
        meshio = _import_meshio()
        v = self.arrays(copy=True)
        cells, cdata = [], {"leaf": [], "level": []}
        if v["material"] is not None:
            cdata["material"] = []
        for t, (name, k) in enumerate((("triangle", 3), ("quad", 4))):
            idx = np.flatnonzero(v["types"] == t)
            if idx.size == 0:
                continue
            cells.append(meshio.CellBlock(name, v["cells"][idx, :k].astype(np.int64)))
            cdata["leaf"].append(v["leaf"][idx].astype(np.int64))
            cdata["level"].append(v["level"][idx].astype(np.int64))
            if v["material"] is not None:
                cdata["material"].append(v["material"][idx].astype(np.int64))
        return meshio.Mesh(v["nodes"], cells, cell_data=cdata)
