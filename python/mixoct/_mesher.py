"""Mesher: the 3D mesher (inputs, requests, meshing, re-meshing, output, the
mesh as arrays and as a meshio mesh), and generate()."""
import ctypes
import os
import warnings
import weakref

import numpy as np

from ._capi import (
    EINPUT, InputError, TYPE_NAMES, _BoundaryArrays, _FeatureFigures, _ImageParams,
    _LEVEL_FN, _MeshArrays, _Params, _Progress, _ROUND_FN, _SIZE_FN, _STAGE_FN,
    _Stats, _function, load_library)
from ._args import _fspath, _input_arrays
from ._base import _MesherBase, _mesh_view, _view
from ._params import _PARAM_CHECKS, _fill_params
from ._meshio import _BoundaryOwner, _MESHIO_NAMES, _MESHIO_ORDER, _import_meshio


class Mesher(_MesherBase):
    """One mesher: inputs, requests, the octree, the mesh (see the module doc).

    Every field of the library's parameters can be given, by name; one
    left out or given as None takes the library's default
    (``mixoct.Mesher.defaults()``): ``surface_level`` (octants meeting the
    surface; -1 none), ``all_level`` (every octant of the domain; -1 none),
    ``stage`` ("octree", "transition", "full" or 0..2), ``threads`` (0:
    OpenMP's default), ``max_memory_mb`` (0: the memory available),
    ``repair_rounds`` (10), and, as keywords, ``balance`` ("edges" or
    "recursive"), ``close_ratio`` and ``staircase_quality`` (0: the
    library's 0.5 and 0.2), ``repair_input`` (an input with no
    well-defined inside meshed by its winding number), ``remesh_full``
    (1: re-meshing meshes the whole octree again; 0, the default: only the
    leaves around what was split when that costs less; -1: always those), ``materials`` (nested
    shells become materials, not holes, given by the ``material`` view;
    see the module doc), ``smooth_rounds`` (rounds of the smoothing that
    only raises the worst J_ENS around each node; 0, the default: off),
    ``tets`` (the final mesh split into tetrahedra). A value out of range raises InputError naming the argument.
    ``progress``: a callable ``progress(stage, info)`` called from the
    meshing calls (see ``set_progress``). Sharp features: ``set_features``,
    ``feature_figures``.
    """

    _PREFIX = "mx_mesher"
    _ARRAYS = _MeshArrays
    _STATS = _Stats
    _VIEW_KEYS = ("nodes", "conn", "types", "jens", "leaf", "level",
                  "boundary", "material")

    def __init__(self, surface_level=None, all_level=None, stage=None,
                 threads=None, max_memory_mb=None, repair_rounds=None, *,
                 library=None, progress=None, **params):
        params.update(surface_level=surface_level, all_level=all_level,
                      stage=stage, threads=threads, max_memory_mb=max_memory_mb,
                      repair_rounds=repair_rounds)
        lib = load_library(library)
        p = _Params()
        lib.mx_params_default(ctypes.byref(p))
        _fill_params(p, params, _PARAM_CHECKS, type(self).__name__)
        self._start(lib, p)
        self._progress_cb = None
        if progress is not None:
            self.set_progress(progress)

    @staticmethod
    def defaults(library=None):
        """The library's default parameters (mx_params_default) as a dict."""
        p = _Params()
        load_library(library).mx_params_default(ctypes.byref(p))
        return {f: getattr(p, f) for f, _ in p._fields_}

    def set_progress(self, progress):
        """``progress(stage, info)`` is called from the meshing calls, in
        the calling thread: ``(name, None)`` before each stage ("grid",
        "refine", "transition", "index", "boundary", "verify", "quality",
        "write", ...), ``("level", (level, max_level))`` before each octree
        level is refined, ``("repair", round)`` before each repair round.
        Returning False cancels the call (CancelledError); an exception
        raised by it cancels the call and is raised by it. None removes
        it."""
        if progress is not None and not callable(progress):
            raise InputError("set_progress: progress must be callable or None, not %r"
                             % (progress,), EINPUT)
        wself = weakref.ref(self)

        def event(stage, info):
            m = wself()
            f = m._progress if m is not None else None
            if f is None:
                return
            try:
                r = f(stage, info)
            except BaseException as e:  # noqa: BLE001 (raised by the call)
                m._progress_error = e
                m.cancel()
                return
            if r is False:
                m.cancel()

        def on_stage(user, name):
            event(name.decode("utf-8", "replace") if name else "", None)

        def on_level(user, level, top):
            event("level", (int(level), int(top)))

        def on_round(user, rnd):
            event("repair", int(rnd))

        self._progress = progress
        setp = _function(self._lib, "mx_mesher_set_progress")
        if progress is None:
            self._progress_cb = None
            setp(self._ptr, None)
            return
        hooks = _Progress(_STAGE_FN(on_stage), _LEVEL_FN(on_level),
                          _ROUND_FN(on_round), None)
        self._progress_cb = hooks      # the callbacks live as long as we do
        self._handle.progress = hooks  # and as long as the C mesher
        setp(self._ptr, ctypes.byref(hooks))

    # ---- inputs ------------------------------------------------------------------

    def add_surface(self, path):
        """A closed surface bounding the domain (OFF, MDL, STL, OBJ)."""
        self._call("mx_mesher_add_surface", _fspath(path))

    def add_surface_arrays(self, xyz, tri, name="arrays"):
        """A closed surface from arrays: xyz (n, 3) float, tri (m, 3) 0-based,
        outward by the right hand. The arrays are converted to float64 and
        uint32 (copied only if needed); the library copies them."""
        self._call("mx_mesher_add_surface_arrays", str(name).encode(),
                   *_input_arrays(name, xyz, 3, "xyz", tri, 3, "tri"))

    def add_label_image(self, labels, spacing=(1.0, 1.0, 1.0), origin=(0.0, 0.0, 0.0),
                        affine=None, voxel=False, min_island=0, skip=(), merge=None,
                        label_names=None, smoothing=None, label_size=None, name="labels"):
        """A segmented 3D image to mesh (0 background, each other label a
        material of that number): a file (.nii, .nii.gz, .mha, .mhd, .inr,
        .inr.gz) or an integer array indexed [i, j, k] as nibabel gives it
        (``img.get_fdata()``/``np.asarray(img.dataobj)``; a SimpleITK array
        is [k, j, i]: pass ``arr.transpose()``). For an array, the world of
        voxel (i, j, k)'s centre is ``affine @ (i, j, k, 1)`` (a 4x4 or 3x4
        matrix, nibabel's ``img.affine``), or else origin + spacing * (i,
        j, k). The image is meshed alone, on its voxel lattice: voxels at
        the interfaces, the nodes there moved onto the smoothed interfaces
        (``voxel=True`` keeps the voxel faces); ``min_island`` drops the
        parts of a label of fewer voxels; ``skip`` labels are background;
        ``merge`` maps labels ({from: to}); ``label_names`` a file of "LABEL
        NAME" lines; ``smoothing`` the interfaces' smoothing rounds;
        ``label_size`` {label: voxels}: no element wider inside it."""
        ip = _ImageParams()
        self._lib.mx_image_params_default(ctypes.byref(ip))
        ip.voxel = 1 if voxel else 0
        if smoothing is not None:
            if int(smoothing) < 0 or int(smoothing) > 1000:
                raise InputError("%s: smoothing must be 0 .. 1000 rounds" % name, EINPUT)
            ip.smooth_rounds = int(smoothing)
        if int(min_island) < 0:
            raise InputError("%s: min_island must be 0 or more voxels" % name, EINPUT)
        ip.min_island = int(min_island)
        sk = np.ascontiguousarray(list(skip), dtype=np.int32)
        pairs = sorted((merge or {}).items())
        mg = np.ascontiguousarray([x for p in pairs for x in p], dtype=np.int32)
        if sk.size > 64 or len(pairs) > 64:
            raise InputError("%s: at most 64 labels to skip or merge" % name, EINPUT)
        ip.skip = sk.ctypes.data_as(ctypes.POINTER(ctypes.c_int32))
        ip.nskip = int(sk.size)
        ip.merge = mg.ctypes.data_as(ctypes.POINTER(ctypes.c_int32))
        ip.nmerge = len(pairs)
        ip.label_names = None if label_names is None else _fspath(label_names)
        spairs = sorted((label_size or {}).items())
        ls = np.ascontiguousarray([x for p in spairs for x in p], dtype=np.int32)
        if len(spairs) > 64:
            raise InputError("%s: at most 64 label sizes" % name, EINPUT)
        ip.label_size = ls.ctypes.data_as(ctypes.POINTER(ctypes.c_int32))
        ip.nlabel_size = len(spairs)
        if isinstance(labels, (str, bytes, os.PathLike)):
            self._call("mx_mesher_add_label_image", _fspath(labels), ctypes.byref(ip))
            return
        a = np.asarray(labels)
        if a.ndim != 3 or 0 in a.shape:
            raise InputError("%s: labels must be a 3D array, not of shape %s"
                             % (name, a.shape), EINPUT)
        if a.dtype.kind == "f":
            r = np.rint(a)
            if not np.all(np.isfinite(a)):
                raise InputError("%s: labels hold NaN or infinite values" % name, EINPUT)
            if np.any(r != a):
                warnings.warn("%s: %d non-integer label(s) rounded"
                              % (name, int(np.count_nonzero(r != a))))
            a = r
        elif a.dtype.kind not in "iub":
            raise InputError("%s: labels must be integers, not %s" % (name, a.dtype), EINPUT)
        if a.size and (a.min() < -2**31 or a.max() > 2**31 - 1):
            raise InputError("%s: labels must fit 32 bits" % name, EINPUT)
        lab = np.asfortranarray(a, dtype=np.int32)  # i fastest
        if affine is not None:
            A = np.asarray(affine, dtype=np.float64)
            if A.shape not in ((4, 4), (3, 4)):
                raise InputError("%s: affine must be 4x4 or 3x4, not %s" % (name, A.shape),
                                 EINPUT)
            A = np.ascontiguousarray(A[:3, :4])
        else:
            sp = np.asarray(spacing, dtype=np.float64).reshape(-1)
            org = np.asarray(origin, dtype=np.float64).reshape(-1)
            if sp.size != 3 or org.size != 3:
                raise InputError("%s: spacing and origin take 3 numbers each" % name, EINPUT)
            A = np.zeros((3, 4))
            A[0, 0], A[1, 1], A[2, 2] = sp
            A[:, 3] = org
        dims = np.ascontiguousarray(a.shape, dtype=np.int64)
        self._call("mx_mesher_add_label_array", str(name).encode(),
                   lab.ctypes.data_as(ctypes.POINTER(ctypes.c_int32)),
                   dims.ctypes.data_as(ctypes.POINTER(ctypes.c_int64)),
                   A.ctypes.data_as(ctypes.POINTER(ctypes.c_double)), ctypes.byref(ip))

    def add_demo_surface(self):
        """The built-in demo surface (a brain-like closed surface)."""
        self._call("mx_mesher_add_demo_surface")

    def set_material(self, input, number, name=None):
        """With materials=True: the number (1..65535) and name of the
        material inside surface `input` (0 for the first added), written as
        the Gmsh physical volume, the Medit reference and the field
        material, and given by the material view (--material ID:NAME)."""
        self._call("mx_mesher_set_material", int(input), int(number),
                   None if name is None else str(name).encode())

    def set_input_level(self, input, surface_level=0, inside_level=0):
        """A level for one surface (`input`: 0 for the first added):
        octants meeting its triangles go to `surface_level`, those meeting
        or inside it to `inside_level` (0: none; the largest request wins).
        With materials=True, `inside_level` is a level everywhere in the
        material(s) the surface holds (--level L / --inside-level L after
        -i FILE). Each level takes a region surface's place."""
        self._call("mx_mesher_set_input_level", int(input), int(surface_level),
                   int(inside_level))

    def set_size(self, field, size_min=0.0, size_max=0.0):
        """A size field (the program's --size): an expression of x, y, z
        (numbers, + - * / ^, exp log sqrt abs sin cos min max, pi, e), one
        of the test functions "F1".."F5", or a Python function of the
        points, vectorised: f(xyz) with xyz an (n, 3) float64 array returns
        the n sizes (or an (n, 3) array of sizes along x, y, z; the octree
        uses the least). Octants are split while larger than the least size
        over them (sampled into a control space when the octree is built).
        size_min, size_max (> 0): bounds on the sizes (--size-min,
        --size-max). Raises InputError with the column of a bad expression,
        or naming the point of a size that is not finite and positive."""
        if callable(field):
            def call(user, n, xyz, h, f=field):
                try:
                    p = np.ctypeslib.as_array(xyz, shape=(n, 3))
                    out = np.ctypeslib.as_array(h, shape=(n, 3))
                    v = np.asarray(f(p.copy()), dtype=np.float64)
                    if v.shape == (n,):
                        v = v[:, None]
                    out[:] = np.broadcast_to(v, (n, 3))
                except Exception as e:  # noqa: BLE001 (reported as a bad size)
                    self._size_error = e
                    np.ctypeslib.as_array(h, shape=(n, 3))[:] = np.nan
            self._size_error = None
            self._size_cb = _SIZE_FN(call)  # kept alive with the mesher
            self._call("mx_mesher_set_size_function", self._size_cb, None, None)
        else:
            self._size_cb = None
            self._call("mx_mesher_set_size_expr", str(field).encode())
        if size_min or size_max:
            self.set_size_limits(size_min, size_max)

    def set_size_limits(self, size_min=0.0, size_max=0.0):
        """Bounds on the size field's sizes (0: none); size_max alone is a
        field of that size everywhere (--size-min, --size-max)."""
        self._call("mx_mesher_set_size_limits", float(size_min), float(size_max))

    def set_curvature(self, degrees):
        """A size field from the surface's curvature: an element spans at
        most `degrees` of it (--curvature; 0: none)."""
        self._call("mx_mesher_set_size_curvature", float(degrees))

    def set_features(self, angle=None, level=None, path=None):
        """Sharp features (issue 29): ridges where the surface's normals
        part by more than ``angle`` degrees (--feature-angle, 30 by default;
        0: none, --no-features), octants on them refined to ``level``
        (--feature-level; 0: the surface level), or the ridges read from
        the polylines file ``path`` (--features: "n x1 y1 z1 ... xn yn zn"
        a line). Arguments left None are left as they are."""
        if angle is not None:
            self._call("mx_mesher_set_feature_angle", float(angle))
        if level is not None:
            self._call("mx_mesher_set_feature_level", int(level))
        if path is not None:
            self._call("mx_mesher_set_feature_file", _fspath(path))

    def feature_figures(self):
        """The sharp features of the last run as a dict: found (``ridges``,
        ``corners``, ``length``), ``kept`` (False when there are none, when
        they are noise or when keeping them broke the mesh: ``fallback``),
        placed (``corners_placed``, ``lines_followed``, ``lines_missed``,
        ``quads_split``) and ``ridge_distance`` / ``corner_distance`` from
        them to the mesh over the input's diagonal (NaN: not measured)."""
        f = _FeatureFigures()
        _function(self._lib, "mx_mesher_feature_figures")(self._ptr, ctypes.byref(f))
        d = {n: getattr(f, n) for n, _ in f._fields_}
        for n in ("kept", "noise", "fallback"):
            d[n] = bool(d[n])
        return d

    def set_thickness(self, elements):
        """At least `elements` (1 to 64) elements across every part and
        every gap of the domain (--thickness; 0: none)."""
        self._call("mx_mesher_set_size_thickness", float(elements))

    def set_gradation(self, beta):
        """Neighbouring sizes differ by at most the ratio beta > 1
        (--gradation; 0: the default, 2 for curvature, thickness and size
        maps; given, for set_size's field too)."""
        self._call("mx_mesher_set_size_gradation", float(beta))

    def set_size_points(self, points, sizes, name="size map"):
        """A size map: points (n, 3) with sizes (n,) (a solver's estimate,
        interpolated by the graded minimum of the sources; the points must
        lie in the domain's box). An empty array removes it."""
        x = np.ascontiguousarray(points, dtype=np.float64).reshape(-1, 3)
        h = np.ascontiguousarray(sizes, dtype=np.float64).ravel()
        if h.size != x.shape[0]:
            raise InputError("set_size_points: %d points but %d sizes"
                             % (x.shape[0], h.size))
        dp = ctypes.POINTER(ctypes.c_double)
        self._call("mx_mesher_set_size_points", x.ctypes.data_as(dp),
                   h.ctypes.data_as(dp), h.size, str(name).encode())

    def set_size_map(self, path, field=None):
        """A size map from a file (--size FILE): a point or cell field of a
        .vtu/.vtp/.vtk file (`field`, or else size, h, target_size), a Gmsh
        .pos view, or text lines "x y z h". Raises InputError naming the
        file and line of what is wrong."""
        self._call("mx_mesher_set_size_map", _fspath(path),
                   None if field is None else str(field).encode())

    def set_size_elements(self, sizes):
        """A size per element of the current mesh (a solver's estimate, in
        the order of the mesh's arrays), over each element's box; then
        refine() meshes again to it."""
        h = np.ascontiguousarray(sizes, dtype=np.float64).ravel()
        self._call("mx_mesher_set_size_elements",
                   h.ctypes.data_as(ctypes.POINTER(ctypes.c_double)), h.size)

    def add_region_surface(self, path, level):
        """-r: octants meeting or inside this surface go to `level`."""
        self._call("mx_mesher_add_region_surface", _fspath(path), int(level))

    # ---- the stages alone ----------------------------------------------------------

    def build_octree(self):
        """Grid, refine and balance (the first stage alone)."""
        self._call("mx_mesher_build_octree", changes_mesh=True)

    def transition(self):
        """The transition patterns (the second stage alone)."""
        self._call("mx_mesher_transition", changes_mesh=True)

    def boundary_stage(self, allow_invalid=False):
        """The boundary stage with repair (the third stage alone)."""
        return self._mesh_call("mx_mesher_boundary", allow_invalid)

    # ---- re-meshing ----------------------------------------------------------------

    def refine_leaves(self, indices, allow_invalid=False):
        """As refine_elements, with leaf indices (0 .. nleaves-1, Morton
        order)."""
        return self._refine_list("refine_leaves", indices, allow_invalid)

    def load_restart(self, path, elements=None, allow_invalid=False):
        """Rebuild the octree from a restart file and mesh it (add the same
        surfaces first; requests already set apply on top).

        elements: indices (array-like) or the path of an element list (the
        published format) of elements of the mesh that was written with the
        restart file, to refine at once (the -c / -l workflow of the
        published mesher). They number the elements as the mesh files list
        them: for a file mixoct wrote, grouped by body and type (element k
        of the files is element written_order()[k] of the arrays); for the
        published program's, its own order."""
        return self._load_restart(path, elements, allow_invalid)

    def written_order(self):
        """For each position k of the mesh files (grouped by body, then type:
        at most four blocks a body), the index of that element in the arrays
        (level, type, ... and refine_elements)."""
        n = self.nelements
        order = np.empty(n, dtype=np.uint32)
        self._call("mx_mesher_written_order",
                   order.ctypes.data_as(ctypes.POINTER(ctypes.c_uint32)))
        return order

    # ---- the boundary and meshio ----------------------------------------------------

    def boundary_faces(self):
        """The boundary faces of a full-stage mesh (those of ``--boundary``
        files), their tags and the bodies, as a dict of read-only numpy
        arrays (copies the library made for us: they do not go stale):

        ``nodes`` (nfaces, 4) uint32, outward, a triangle's 4th NO_NODE
        (triangles first: ``ntri`` of them, then the quadrilaterals);
        ``tag`` (nfaces,) int32, the surface each face lies on (1 for the
        first surface added; with materials 1 the outer boundary and 2..
        the interfaces); ``element`` (nfaces,) uint32, the element it
        bounds (an index of the mesh arrays), ``local_face`` (nfaces,)
        uint8 which face of it (VTK's face order); ``body`` (nelements,)
        int32, each element's body (1..``nbodies``: the parts connected
        through nodes); ``material`` (nelements,) int32 with materials,
        else None; ``ntri``, ``nquad``, ``nbodies``, ``ntags``."""
        b = _BoundaryArrays()
        self._call("mx_mesher_boundary_arrays", ctypes.byref(b), long=True)
        owner = _BoundaryOwner(self._lib, b)
        nf, ne = b.nfaces, b.nelements
        return {
            "nodes": _view(b.nodes, 4 * nf, np.uint32, (nf, 4), owner),
            "tag": _view(b.tag, nf, np.int32, (nf,), owner),
            "element": _view(b.element, nf, np.uint32, (nf,), owner),
            "local_face": _view(b.local_face, nf, np.uint8, (nf,), owner),
            "body": _view(b.body, ne, np.int32, (ne,), owner),
            "material": (_view(b.material, ne, np.int32, (ne,), owner)
                         if b.material else None),
            "ntri": int(b.ntri), "nquad": int(b.nquad),
            "nbodies": int(b.nbodies), "ntags": int(b.ntags),
        }

    def to_meshio(self, boundary=True):
        """The mesh as a ``meshio.Mesh`` (copies): cell blocks by type
        ("tetra", "pyramid", "wedge", "hexahedron", in meshio's node order:
        VTK's, and Gmsh's for the wedge, as ours), and with ``boundary`` (full stage) the boundary
        faces as blocks "triangle" and "quad". Point data: ``boundary``
        (1 on the boundary), ``surface_tag`` (the largest tag of the faces
        at the node, 0 inside). Cell data (one array per block, faces
        included): ``J_ENS`` (NaN on faces), ``leaf`` and ``level`` (-1 on
        faces), ``body``, ``material`` with materials, ``surface_tag`` (0 on
        elements), ``element`` (on faces the element each bounds, -1 on
        elements: an index of the volume blocks' cells in order).
        ParaView and meshio read such a file whole; ``mixoct check`` takes
        volume cells only: write ``to_meshio(boundary=False)`` for it."""
        meshio = _import_meshio()
        v = self.arrays(copy=True)
        types, conn = v["types"], v["conn"]
        bf = None
        if boundary:
            try:
                bf = self.boundary_faces()
            except InputError:
                bf = None   # not a full-stage mesh of surfaces: no faces
        cells, cdata = [], {"J_ENS": [], "leaf": [], "level": [], "body": []}
        mat = v["material"]
        if mat is not None:
            cdata["material"] = []
        if bf is not None:
            cdata["surface_tag"] = []
            cdata["element"] = []
        position = np.empty(len(types), dtype=np.int64)  # index in the blocks
        start = 0
        body = bf["body"] if bf is not None else np.ones(len(types), np.int32)
        for t, name in enumerate(_MESHIO_NAMES):
            idx = np.flatnonzero(types == t)
            if idx.size == 0:
                continue
            rows = conn[idx][:, list(_MESHIO_ORDER[t])].astype(np.int64)
            cells.append(meshio.CellBlock(name, rows))
            position[idx] = start + np.arange(idx.size)
            start += idx.size
            cdata["J_ENS"].append(v["jens"][idx].astype(np.float64))
            cdata["leaf"].append(v["leaf"][idx].astype(np.int64))
            cdata["level"].append(v["level"][idx].astype(np.int64))
            cdata["body"].append(body[idx].astype(np.int64))
            if mat is not None:
                cdata["material"].append(mat[idx].astype(np.int64))
            if bf is not None:
                cdata["surface_tag"].append(np.zeros(idx.size, np.int64))
                cdata["element"].append(np.full(idx.size, -1, np.int64))
        pdata = {"boundary": v["boundary"].astype(np.int64)}
        if bf is not None:
            nt = bf["ntri"]
            ntag = np.zeros(len(v["nodes"]), dtype=np.int64)
            for name, sl, k in (("triangle", slice(0, nt), 3),
                                ("quad", slice(nt, None), 4)):
                rows = bf["nodes"][sl, :k].astype(np.int64)
                if rows.shape[0] == 0:
                    continue
                tag, el = bf["tag"][sl], bf["element"][sl]
                np.maximum.at(ntag, rows.ravel(), np.repeat(tag, k).astype(np.int64))
                cells.append(meshio.CellBlock(name, rows))
                n = rows.shape[0]
                cdata["J_ENS"].append(np.full(n, np.nan))
                for key in ("leaf", "level"):
                    cdata[key].append(np.full(n, -1, np.int64))
                cdata["body"].append(body[el].astype(np.int64))
                if mat is not None:
                    cdata["material"].append(mat[el].astype(np.int64))
                cdata["surface_tag"].append(tag.astype(np.int64))
                cdata["element"].append(position[el])
            pdata["surface_tag"] = ntag
        return meshio.Mesh(v["nodes"], cells, point_data=pdata, cell_data=cdata)

    # ---- figures and arrays --------------------------------------------------------

    def stats(self):
        """The figures of the last run (mx_stats) as a dict."""
        d = super().stats()
        d["leaves_hash"] = "%016x" % d["leaves_hash"]
        return d

    def _make_views(self, a, owner):
        v = super()._make_views(a, owner)
        n, e = a.nnodes, a.nelements
        v.update(jens=_view(a.jens, e, np.float32, (e,), owner),
                 boundary=_view(a.boundary, n, np.uint8, (n,), owner),
                 # NULL without materials: None, not an array of zeros
                 material=(_view(a.material, e, np.uint16, (e,), owner)
                           if a.material else None),
                 counts={TYPE_NAMES[t]: int(a.by_type[t]) for t in range(4)},
                 jens_min=float(a.jens_min), invalid=int(a.invalid))
        return v

    nodes = _mesh_view("nodes",
                       "(nnodes, 3) float64 coordinates (read-only view)")
    conn = _mesh_view("conn",
                      "(nelements, 8) uint32 nodes of each element, rows "
                      "padded with NO_NODE; VTK order for tet, pyramid, "
                      "hex, Gmsh's for prisms (read-only view)")
    types = _mesh_view("types",
                       "(nelements,) uint8: TET 0, PYRAMID 1, PRISM 2, HEX 3")
    jens = _mesh_view("jens", "(nelements,) float32 J_ENS of each element")
    leaf = _mesh_view("leaf",
                      "(nelements,) uint32 octree leaf of each element")
    level = _mesh_view("level", "(nelements,) uint8 level of that leaf")
    boundary = _mesh_view("boundary",
                          "(nnodes,) uint8, 1 on the domain boundary")
    material = _mesh_view("material",
                          "(nelements,) uint16 material of each element "
                          "(nesting depth of its centroid, 0 outside every "
                          "shell); None without materials=True")
    jens_min = _mesh_view("jens_min", "the smallest J_ENS of the mesh")
    invalid = _mesh_view("invalid", "how many elements have J_ENS <= 0")






def generate(surface, surface_level=None, boundary=True, **params):
    """Mesh a closed surface and return a ``meshio.Mesh`` (see
    ``Mesher.to_meshio``): ``surface`` is a file path, ``"demo"`` (the
    built-in surface) or ``(xyz, tri)`` arrays; the other arguments are
    Mesher's. For example::

        import mixoct
        mesh = mixoct.generate("demo", surface_level=4)
        mesh.write("demo.vtu")
    """
    with Mesher(surface_level=surface_level, **params) as m:
        if isinstance(surface, str) and surface == "demo":
            m.add_demo_surface()
        elif isinstance(surface, (str, bytes, os.PathLike)):
            m.add_surface(surface)
        else:
            xyz, tri = surface
            m.add_surface_arrays(xyz, tri)
        m.mesh()
        return m.to_meshio(boundary=boundary)
