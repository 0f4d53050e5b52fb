"""mixoct: the mixed-element octree mesher (3D) and quadtree mesher (2D),
from Python (ctypes + numpy).

A thin binding over the C API of ``include/mixoct.h`` (``libmixoct.so``)::

    import mixoct
    with mixoct.Mesher(surface_level=4) as m:
        m.add_demo_surface()
        m.mesh()
        print(m.counts, m.nodes.shape, m.conn.shape)
        worst = [12, 40]                  # elements with a large error
        m.refine_elements(worst)          # Algorithm 3 of the 2021 paper
        m.write("demo.vtu")

and in 2D (closed polylines in, counter-clockwise triangles and
quadrilaterals out; the ``mesher2d`` program's calls)::

    with mixoct.Mesher2D(surface_level=5) as m:
        m.set_domain("box.poly")          # .poly, .off or a 2D .mdl
        m.mesh()
        print(m.counts, m.nodes.shape, m.cells.shape)   # (n, 2), (m, 4)
        m.save_restart("box.oct")
        m.refine_elements([7])
        m.write("box.vtu")

The library is looked for, in this order: the path in the environment
variable ``MIXOCT_LIB``; ``libmixoct.so`` in this package's directory; the
build directory this package was copied into (``<build>/python/mixoct`` ->
``<build>/libmixoct.so``); the path meson wrote into ``_libpath.py`` at
install time; the library on the linker's path (``ctypes.util``).

From Python to meshio in one call
--------------------------------
``mixoct.generate(surface, surface_level=..., **params)`` meshes a surface
file, ``"demo"`` or ``(xyz, tri)`` arrays and returns a ``meshio.Mesh``;
``Mesher.to_meshio()`` (and ``Mesher2D.to_meshio()``) converts the current
mesh: cell blocks by type in meshio's node order, the boundary faces as
"triangle"/"quad" blocks with their ``surface_tag``, point data
``boundary`` and ``surface_tag``, cell data ``J_ENS``, ``leaf``,
``level``, ``body`` (and ``material``), one array per block.
``Mesher.boundary_faces()`` gives the boundary faces (nodes, tag, the
element and local face each bounds) and each element's body as arrays.

Parameters
----------
Every field of the library's parameters (``mx_params``, ``mx_params2d``)
is a keyword of ``Mesher`` (``Mesher2D``); None or left out: the
library's default (``Mesher.defaults()``). Values are checked against the
command line's ranges: out of range raises InputError naming the argument.

Mesh arrays are views, not copies
---------------------------------
``Mesher.nodes``, ``conn``, ``types``, ``jens``, ``leaf``, ``level``,
``boundary`` and ``material`` (and ``Mesher2D.nodes``, ``cells``,
``types``, ``leaf`` and ``level``) are read-only numpy arrays over the
library's own memory (no copy). A view never reads freed memory: when a
call changes the mesh (``mesh``, ``build_octree``, ``transition``,
``boundary_stage``, ``refine``, ``refine_elements``, ``refine_leaves``,
``load_restart``) while views of the mesh are alive, the library hands the
memory of the old mesh's arrays over to the views
(``mx_mesher_detach_mesh_buffers``: it goes on with a copy, made then and
only then; with no view alive nothing is copied), and the old views keep
the values they had; the memory is freed with the last of them. The cost:
one copy of the mesh arrays per re-mesh while old views are held (42
bytes an element, 44 with materials, and 25 a node in 3D; 26 and 16 in
2D), for as long as the old views live. Each view's ``.base`` chain ends
in a :class:`MeshBuffer` that records the mesh generation it was taken
from (``detached``: its memory was handed over): ``Mesher.is_current(array)``
tells whether it shows the current mesh, and ``Mesher.generation`` counts
the mesh changes. ``close()`` (or leaving the ``with`` block) is safe with
views alive: the C object is freed when the last view of it is gone. All of
this holds for ``Mesher2D`` alike.

Progress, cancellation, Ctrl-C
------------------------------
``Mesher(..., progress=f)`` or ``set_progress(f)``: ``f(stage, info)`` is
called before each stage (``info`` None), each octree level (``"level"``,
``(level, max_level)``) and each repair round (``"repair"``, the round).
Returning False cancels the call: it raises :class:`CancelledError`
(status 6) and leaves no mesh (a cancelled re-mesh keeps the octree with
the levels it completed: the next ``mesh()`` meshes it); an exception raised by ``f`` cancels the
call and is raised by it. ``cancel()`` from another thread does the same.
The long calls (meshing, re-meshing, writing) run, from the main thread,
in a worker thread while the main thread waits in short slices: Ctrl-C
(SIGINT) cancels the library's call (it checks the flag between its
passes and in its longest loops) and raises ``KeyboardInterrupt`` once
the call has stopped, within about a second. The mesher stays usable.

Several materials
-----------------
``Mesher(..., materials=True)`` (``mx_params.materials``, the program's
``--materials``) makes the shells nested in the outermost one materials
instead of holes, and surfaces added as several inputs that share faces
materials glued along them: ``Mesher.material`` gives each element's
material, a uint16 view numbered by nesting depth (1 inside one shell, 2
inside two, ...; at the transition stage 0 outside every shell) and input.
Without ``materials`` it is None. At the full stage the interfaces are cut
along the input surfaces: no element lies across one. Re-meshing
(``refine_elements``, ``refine``, ...) keeps the materials; a restart file
written with materials turns them on when read back with the same inputs
(before anything else used the inputs). ``set_material(input, number,
name)`` numbers and names them, ``set_input_level(input, surface_level,
inside_level)`` refines one surface or one material.

``Mesher2D(..., materials=True)`` does the same in 2D (``mesher2d
--materials``): a loop nested in an outer one is the interface between two
materials; the cells are cut along it (no cell lies across it, its edges
have both nodes on the loop) and ``Mesher2D.material`` gives each cell's
material number (by default its nesting depth; ``set_material(depth,
number, name)`` chooses them). Re-meshing keeps them.

Errors
------
Every non-zero status of the library raises a subclass of :class:`Error`
(``status`` the code, ``message`` the library's message naming the file and
line for bad input): :class:`InternalError` (1), :class:`InputError` (2,
also a ``ValueError``), :class:`OutOfMemoryError` (3, also a
``MemoryError``), :class:`OutputError` (4), :class:`InvalidMeshError` (5:
elements with J_ENS <= 0 are left, or in 2D the mesh failed the independent
check; the mesh is still there to inspect or write), :class:`CancelledError`
(6). The messages are shared with the command-line programs; the binding
gives the flags and C functions they name as the Python arguments and
methods that do the same (``-s`` as ``surface_level``, ``mx_mesher_mesh``
as ``mesh()``). Warnings of the library do not go to stderr: they are
collected in ``Mesher.warnings`` (a list of str).

Threads: the library runs its passes with OpenMP threads and the GIL is
released during each call; one Mesher must not be used from two Python
threads at once. Two Meshers may work at the same time in two Python
threads: the library's messages go to the handler of the calling thread's
mesher, so each sees its own warnings only.

The wait policy: libgomp (the OpenMP runtime of libmixoct.so) makes a
thread that waits at a barrier spin by default, and when another job holds
a core the spinning thread takes the time slice of the thread it waits
for: on a shared machine 2 threads then run several times slower than 1.
libgomp reads ``OMP_WAIT_POLICY`` once, when it is loaded, so on import,
before anything loads the library, this module sets
``os.environ["OMP_WAIT_POLICY"] = "passive"`` (waiting threads sleep; the
C environment changes too, and child processes inherit it) unless
``OMP_WAIT_POLICY`` or ``GOMP_SPINCOUNT`` is set already (yours is kept;
``GOMP_SPINCOUNT=300000`` keeps libgomp's default) or libgomp is loaded
already (another module started it: setting the variable would change
nothing; the library then limits each call's threads to the processors
other processes leave free, see include/mixoct.h). ``wait_policy`` says
which: ``"passive (set by mixoct)"``, ``"the user's (OMP_WAIT_POLICY=...)"``
or ``"the user's (GOMP_SPINCOUNT=...)"``, or ``"default (libgomp was loaded
before mixoct)"``. :func:`last_call_threads` gives the thread count the
last call ran with.
"""

__version__ = "0.1.0"  # meson.build's project version (tests/python_binding_test.py)

# The deepest level a request may ask for (mixoct.h: MX_MAX_LEVEL - 1, the
# command line's -s/-a range).
MAX_LEVEL = 15
# The deepest level of a 2D request (mixoct.h: MX_MAX_LEVEL2D, mesher2d's
# -s/-a range).
MAX_LEVEL_2D = 27

import os


def _libgomp_loaded():
    """Whether libgomp.so (the one libmixoct.so needs; not a copy that a
    wheel bundles under another name) is mapped in this process."""
    try:
        with open("/proc/self/maps") as f:
            # address perms offset dev inode path
            paths = (line.split(None, 5)[5:] for line in f)
            return any(os.path.basename(p[0].strip()).startswith("libgomp.so")
                       for p in paths if p)
    except OSError:
        return False


def _choose_wait_policy():
    for name in ("OMP_WAIT_POLICY", "GOMP_SPINCOUNT"):
        if name in os.environ:
            return "the user's (%s=%s)" % (name, os.environ[name])
    if _libgomp_loaded():
        return "default (libgomp was loaded before mixoct)"
    os.environ["OMP_WAIT_POLICY"] = "passive"
    return "passive (set by mixoct)"


#: what OpenMP threads do when they wait (see the module's doc); chosen on
#: import, before numpy or the library can load libgomp
wait_policy = _choose_wait_policy()

import ctypes  # noqa: E402 (after the wait policy: see above)
import ctypes.util  # noqa: E402
import math  # noqa: E402
import re  # noqa: E402
import tempfile  # noqa: E402
import threading  # noqa: E402
import warnings  # noqa: E402
import weakref  # noqa: E402

import numpy as np  # noqa: E402

__all__ = [
    "Mesher", "Mesher2D", "MeshBuffer", "read_element_list", "load_library",
    "Error", "InternalError", "InputError", "OutOfMemoryError", "OutputError",
    "InvalidMeshError", "TET", "PYRAMID", "PRISM", "HEX", "TYPE_NAMES",
    "NODES_PER_TYPE", "TRI", "QUAD", "NO_NODE", "status_string",
    "wait_policy", "last_call_threads", "CancelledError", "generate",
    "MAX_LEVEL", "MAX_LEVEL_2D",
]

# ---- constants (include/mixoct.h) ------------------------------------------

OK, EINTERNAL, EINPUT, ENOMEM, EIO, EINVALID, ECANCELED = 0, 1, 2, 3, 4, 5, 6
TET, PYRAMID, PRISM, HEX = 0, 1, 2, 3
TYPE_NAMES = ("tet", "pyramid", "prism", "hex")
NODES_PER_TYPE = (4, 5, 6, 8)
#: the 2D cell types (Mesher2D.types)
TRI, QUAD = 0, 1
#: the padding of ``conn`` rows shorter than 8 nodes, and of a triangle's
#: row of ``Mesher2D.cells`` (UINT32_MAX)
NO_NODE = 0xFFFFFFFF
_STAGES = {"octree": 0, "transition": 1, "full": 2}
_BALANCE = {"edges": 0, "recursive": 1}
MSG_ERROR, MSG_WARNING = 0, 1


# ---- errors ------------------------------------------------------------------

class Error(Exception):
    """A failure reported by libmixoct: ``status`` (int) and ``message``."""

    def __init__(self, message, status=EINTERNAL):
        super().__init__(message)
        self.message = message
        self.status = status

    def __str__(self):
        return self.message


class InternalError(Error):
    """Status 1: a bug or an unexpected system failure."""


class InputError(Error, ValueError):
    """Status 2: bad input file, bad argument, bad usage."""


class OutOfMemoryError(Error, MemoryError):
    """Status 3: out of memory, or over the memory budget (max_memory_mb)."""


class OutputError(Error):
    """Status 4: an output could not be written (permission, disk)."""


class InvalidMeshError(Error):
    """Status 5: elements with J_ENS <= 0 are left after the repair rounds.

    The mesh is kept: its arrays can be read and it can be written."""


class CancelledError(Error):
    """Status 6: the call was cancelled (a progress callback returned False,
    or ``cancel()`` from another thread); the mesher made nothing and stays
    usable."""


_ERRORS = {EINTERNAL: InternalError, EINPUT: InputError,
           ENOMEM: OutOfMemoryError, EIO: OutputError,
           EINVALID: InvalidMeshError, ECANCELED: CancelledError}


# ---- the C structures --------------------------------------------------------

class _Params(ctypes.Structure):
    _fields_ = [("surface_level", ctypes.c_int),
                ("all_level", ctypes.c_int),
                ("stage", ctypes.c_int),
                ("balance", ctypes.c_int),
                ("threads", ctypes.c_int),
                ("max_memory_mb", ctypes.c_double),
                ("close_ratio", ctypes.c_double),
                ("staircase_quality", ctypes.c_double),
                ("repair_rounds", ctypes.c_int),
                ("repair_input", ctypes.c_int),
                ("remesh_full", ctypes.c_int),
                ("materials", ctypes.c_int),
                ("smooth_rounds", ctypes.c_int),
                ("tets", ctypes.c_int)]


class _MeshArrays(ctypes.Structure):
    _fields_ = [("nnodes", ctypes.c_size_t),
                ("nelements", ctypes.c_size_t),
                ("nleaves", ctypes.c_size_t),
                ("xyz", ctypes.POINTER(ctypes.c_double)),
                ("type", ctypes.POINTER(ctypes.c_uint8)),
                ("conn", ctypes.POINTER(ctypes.c_uint32)),
                ("jens", ctypes.POINTER(ctypes.c_float)),
                ("leaf", ctypes.POINTER(ctypes.c_uint32)),
                ("level", ctypes.POINTER(ctypes.c_uint8)),
                ("boundary", ctypes.POINTER(ctypes.c_uint8)),
                ("by_type", ctypes.c_size_t * 4),
                ("jens_min", ctypes.c_double),
                ("invalid", ctypes.c_size_t),
                ("material", ctypes.POINTER(ctypes.c_uint16))]


_STAT_SIZES = ("leaves", "octants", "nodes", "elements", "invalid",
               "refined_listed", "split_balance", "repaired")
_STAT_TIMES = ("t_read", "t_grid", "t_refine", "t_balance", "t_transition",
               "t_boundary", "t_quality", "t_write", "t_restart")


class _Stats(ctypes.Structure):
    _fields_ = ([(n, ctypes.c_size_t) for n in _STAT_SIZES]
                + [("repair_rounds", ctypes.c_int),
                   ("jens_min", ctypes.c_double),
                   ("leaves_hash", ctypes.c_uint64)]
                + [(n, ctypes.c_double) for n in _STAT_TIMES]
                + [("remesh_local", ctypes.c_int),
                   ("remesh_patch_leaves", ctypes.c_size_t)])


class _FeatureFigures(ctypes.Structure):
    _fields_ = ([("angle", ctypes.c_double)]
                + [(n, ctypes.c_size_t) for n in ("ridges", "corners")]
                + [("length", ctypes.c_double)]
                + [(n, ctypes.c_int) for n in ("kept", "noise", "fallback")]
                + [(n, ctypes.c_size_t) for n in ("corners_placed", "lines_followed",
                                                  "lines_missed", "quads_split")]
                + [(n, ctypes.c_double) for n in ("ridge_distance", "corner_distance")])


_MESSAGE_FN = ctypes.CFUNCTYPE(None, ctypes.c_void_p, ctypes.c_int,
                               ctypes.c_char_p)
# mx_progress: on_stage(user, name), on_level(user, level, max_level),
# on_round(user, round)
_STAGE_FN = ctypes.CFUNCTYPE(None, ctypes.c_void_p, ctypes.c_char_p)
_LEVEL_FN = ctypes.CFUNCTYPE(None, ctypes.c_void_p, ctypes.c_int, ctypes.c_int)
_ROUND_FN = ctypes.CFUNCTYPE(None, ctypes.c_void_p, ctypes.c_int)


class _Progress(ctypes.Structure):
    _fields_ = [("on_stage", _STAGE_FN), ("on_level", _LEVEL_FN),
                ("on_round", _ROUND_FN), ("user", ctypes.c_void_p)]


class _BoundaryArrays(ctypes.Structure):
    _fields_ = [("nfaces", ctypes.c_size_t), ("ntri", ctypes.c_size_t),
                ("nquad", ctypes.c_size_t),
                ("nodes", ctypes.POINTER(ctypes.c_uint32)),
                ("tag", ctypes.POINTER(ctypes.c_int32)),
                ("element", ctypes.POINTER(ctypes.c_uint32)),
                ("local_face", ctypes.POINTER(ctypes.c_uint8)),
                ("nelements", ctypes.c_size_t),
                ("body", ctypes.POINTER(ctypes.c_int32)),
                ("material", ctypes.POINTER(ctypes.c_int32)),
                ("nbodies", ctypes.c_int), ("ntags", ctypes.c_int)]


_DETACH_MAX = 8  # mixoct.h: MX_DETACH_MAX


def _fields(*groups):
    """A structure's _fields_ from (ctype, "name name ...") groups, in
    order."""
    return [(n, t) for t, names in groups for n in names.split()]


_u8p = ctypes.POINTER(ctypes.c_uint8)
_u32p = ctypes.POINTER(ctypes.c_uint32)


class _ImageParams(ctypes.Structure):
    _fields_ = [("voxel", ctypes.c_int),
                ("smooth_rounds", ctypes.c_int),
                ("min_island", ctypes.c_longlong),
                ("skip", ctypes.POINTER(ctypes.c_int32)),
                ("nskip", ctypes.c_int),
                ("merge", ctypes.POINTER(ctypes.c_int32)),
                ("nmerge", ctypes.c_int),
                ("label_names", ctypes.c_char_p),
                ("label_size", ctypes.POINTER(ctypes.c_int32)),
                ("nlabel_size", ctypes.c_int)]


class _Params2D(ctypes.Structure):
    _fields_ = _fields(
        (ctypes.c_int, "surface_level all_level balance threads"),
        (ctypes.c_double, "close_ratio max_memory_mb"),
        (ctypes.c_int, "feature_levels materials"))


class _MeshArrays2D(ctypes.Structure):
    _fields_ = _fields((ctypes.c_size_t, "nnodes ncells nleaves"),
                       (ctypes.POINTER(ctypes.c_double), "xy"),
                       (_u8p, "type"), (_u32p, "conn leaf"), (_u8p, "level"),
                       (ctypes.POINTER(ctypes.c_uint16), "material"))


class _Stats2D(ctypes.Structure):
    _fields_ = _fields(
        (ctypes.c_size_t, "leaves quadrants nodes cells tris quads invalid "
                          "refined_listed split_balance"),
        (ctypes.c_int, "valid"),
        (ctypes.c_double, "sj_min min_angle t_read t_refine t_balance "
                          "t_transition t_boundary t_quality t_check "
                          "t_restart"),
        (ctypes.c_int, "materials"))


# ---- the library -------------------------------------------------------------

_lib = None


def _candidates():
    env = os.environ.get("MIXOCT_LIB")
    if env:
        return [env], True
    here = os.path.dirname(os.path.abspath(__file__))
    names = [os.path.join(here, "libmixoct.so"),
             # <build>/python/mixoct/__init__.py -> <build>/libmixoct.so
             os.path.normpath(os.path.join(here, os.pardir, os.pardir,
                                           "libmixoct.so"))]
    try:
        # written by meson at install time: the installed library
        from ._libpath import LIBMIXOCT
        names.append(LIBMIXOCT)
    except ImportError:
        pass
    found = ctypes.util.find_library("mixoct")
    if found:
        names.append(found)
    return names, False


# mx_size_fn: f(user, n, xyz, h), called from the library's threads
_SIZE_FN = ctypes.CFUNCTYPE(None, ctypes.c_void_p, ctypes.c_size_t,
                            ctypes.POINTER(ctypes.c_double),
                            ctypes.POINTER(ctypes.c_double))


def _declare(lib):
    P = ctypes.c_void_p
    I = ctypes.c_int
    S = ctypes.c_char_p
    sz = ctypes.c_size_t
    u64p = ctypes.POINTER(ctypes.c_uint64)
    u32p = ctypes.POINTER(ctypes.c_uint32)
    dblp = ctypes.POINTER(ctypes.c_double)
    sig = {
        "mx_params_default": (None, [ctypes.POINTER(_Params)]),
        "mx_mesher_new": (P, [ctypes.POINTER(_Params)]),
        "mx_status_string": (S, [I]),
        "mx_last_call_threads": (I, []),
        "mx_mesher_add_surface": (I, [P, S]),
        "mx_mesher_add_surface_arrays": (I, [P, S, sz, dblp, sz, u32p]),
        "mx_mesher_add_demo_surface": (I, [P]),
        "mx_image_params_default": (None, [ctypes.POINTER(_ImageParams)]),
        "mx_mesher_add_label_image": (I, [P, S, ctypes.POINTER(_ImageParams)]),
        "mx_mesher_add_label_array": (I, [P, S, ctypes.POINTER(ctypes.c_int32),
                                          ctypes.POINTER(ctypes.c_int64), dblp,
                                          ctypes.POINTER(_ImageParams)]),
        "mx_mesher_add_region_surface": (I, [P, S, I]),
        "mx_mesher_set_material": (I, [P, I, I, S]),
        "mx_mesher_set_input_level": (I, [P, I, I, I]),
        "mx_mesher_set_size_expr": (I, [P, S]),
        "mx_mesher_set_size_function": (I, [P, _SIZE_FN, P, P]),
        "mx_mesher_set_size_limits": (I, [P, ctypes.c_double, ctypes.c_double]),
        "mx_mesher_set_size_curvature": (I, [P, ctypes.c_double]),
        "mx_mesher_set_size_thickness": (I, [P, ctypes.c_double]),
        "mx_mesher_set_size_gradation": (I, [P, ctypes.c_double]),
        "mx_mesher_set_size_points": (I, [P, dblp, dblp, sz, S]),
        "mx_mesher_set_size_elements": (I, [P, dblp, sz]),
        "mx_mesher_set_size_map": (I, [P, S, S]),
        "mx_mesher_build_octree": (I, [P]),
        "mx_mesher_transition": (I, [P]),
        "mx_mesher_boundary": (I, [P]),
        "mx_mesher_refine_leaves": (I, [P, u64p, sz]),
        "mx_read_element_list": (I, [S, ctypes.c_uint64,
                                     ctypes.POINTER(u64p),
                                     ctypes.POINTER(sz)]),
        "mx_free_array": (None, [P]),
        "mx_mesher_mesh_arrays": (I, [P, ctypes.POINTER(_MeshArrays)]),
        "mx_mesher_written_order": (I, [P, u32p]),
        "mx_mesher_stats": (None, [P, ctypes.POINTER(_Stats)]),
        "mx_mesher_set_feature_angle": (I, [P, ctypes.c_double]),
        "mx_mesher_set_feature_level": (I, [P, I]),
        "mx_mesher_set_feature_file": (I, [P, S]),
        "mx_mesher_feature_figures": (None, [P, ctypes.POINTER(_FeatureFigures)]),
        # 2D (mx_mesher2d_*)
        "mx_params2d_default": (None, [ctypes.POINTER(_Params2D)]),
        "mx_mesher2d_new": (P, [ctypes.POINTER(_Params2D)]),
        "mx_mesher2d_set_domain": (I, [P, S]),
        "mx_mesher2d_set_domain_arrays": (I, [P, S, sz, dblp, sz, u32p]),
        "mx_mesher2d_add_region": (I, [P, S, I]),
        "mx_mesher2d_add_drawing": (I, [P, S, I]),
        "mx_mesher2d_add_function": (I, [P, S, dblp, sz, I]),
        "mx_mesher2d_set_material": (I, [P, I, I, S]),
        "mx_mesher2d_set_size_expr": (I, [P, S]),
        "mx_mesher2d_set_size_limits": (I, [P, ctypes.c_double,
                                            ctypes.c_double]),
        "mx_mesher2d_restart_elements": (sz, [P]),
        "mx_mesher2d_mesh_arrays": (I, [P, ctypes.POINTER(_MeshArrays2D)]),
        "mx_mesher2d_stats": (None, [P, ctypes.POINTER(_Stats2D)]),
        "mx_mesher_set_progress": (None, [P, ctypes.POINTER(_Progress)]),
        "mx_mesher_boundary_arrays": (I, [P, ctypes.POINTER(_BoundaryArrays)]),
        "mx_boundary_arrays_free": (None, [ctypes.POINTER(_BoundaryArrays)]),
    }
    # the calls the 3D and the 2D mesher share, by name and signature
    shared = {
        "free": (None, [P]),
        "set_message_handler": (None, [P, _MESSAGE_FN, P]),
        "last_error": (S, [P]),
        "set_levels": (I, [P, I, I]),
        "add_box": (I, [P, dblp, dblp, I]),
        "read_boxes": (I, [P, S]),
        "mesh": (I, [P]),
        "refine_elements": (I, [P, u64p, sz]),
        "refine": (I, [P]),
        "save_restart": (I, [P, S]),
        "load_restart": (I, [P, S]),
        "write": (I, [P, S, I]),
        "cancel": (None, [P]),
        "detach_mesh_buffers": (I, [P, ctypes.POINTER(ctypes.c_void_p)]),
    }
    for prefix in ("mx_mesher_", "mx_mesher2d_"):
        sig.update((prefix + name, s) for name, s in shared.items())
    missing = []
    for name, (res, args) in sig.items():
        try:
            f = getattr(lib, name)
        except AttributeError:
            missing.append(name)
            continue
        f.restype = res
        f.argtypes = args
    # an older or partial library: the calls it lacks raise InternalError
    # (a library without the 2D mesher still serves Mesher)
    lib.mixoct_missing = frozenset(missing)
    essential = {"mx_params_default", "mx_mesher_new", "mx_mesher_free",
                 "mx_mesher_last_error", "mx_mesher_set_message_handler"}
    if essential & lib.mixoct_missing:
        raise ImportError("%s is not libmixoct: it lacks %s" % (
            lib._name, ", ".join(sorted(essential & lib.mixoct_missing))))
    return lib


def _function(lib, name):
    if name in lib.mixoct_missing:
        raise InternalError("%s lacks what this method needs (%s: an older "
                            "libmixoct?)" % (lib._name, name.replace("mx_", "", 1)),
                            EINTERNAL)
    return getattr(lib, name)


def load_library(path=None):
    """Load libmixoct (once); ``path`` overrides the search (see module doc)."""
    global _lib
    if _lib is not None and path is None:
        return _lib
    if path is not None:
        names, strict = [path], True
    else:
        names, strict = _candidates()
    errors = []
    for name in names:
        if not strict and os.sep in name and not os.path.exists(name):
            continue
        try:
            lib = ctypes.CDLL(name)
        except OSError as e:
            errors.append("%s: %s" % (name, e))
            continue
        _lib = _declare(lib)
        return _lib
    raise ImportError(
        "libmixoct.so not found (set MIXOCT_LIB to its path; tried: %s)"
        % ("; ".join(errors) if errors else ", ".join(names) or "nothing"))


def last_call_threads():
    """The OpenMP thread count the last call of a mesher (from this Python
    thread) ran with: ``threads`` when given, else OpenMP's default, limited
    to the processors other processes left free when libgomp spins (see the
    module's doc); 0 before any call."""
    n = getattr(_tls, "threads", None)
    if n is not None:
        return n
    return int(_function(load_library(), "mx_last_call_threads")())


def status_string(status):
    """The library's name of a status code, e.g. 'bad input'."""
    s = load_library().mx_status_string(int(status))
    return s.decode("utf-8", "replace") if s else str(status)


# The library's messages are shared with the command-line programs: the
# flags and C functions they name are given here by the Python argument or
# method that does the same (item 5 of issue 30). Flags without an entry
# become the word without dashes, '-' as '_'.
_FLAG_WORDS = {
    "-s": "surface_level", "--surface-level": "surface_level",
    "-a": "all_level", "--all-level": "all_level",
    "-b": "add_box()/read_boxes()", "--regions": "read_boxes()",
    "-r": "add_region_surface()", "--region-surface": "add_region_surface()",
    "-i": "add_surface()", "--input": "add_surface()",
    "-c": "load_restart()", "-l": "load_restart(elements=...)",
    "-f": "add_function()", "-d": "add_surface()", "-o": "add_surface()",
    "--demo": "add_demo_surface()",
    "--materials": "materials=True", "--material": "set_material()",
    "--repair-input": "repair_input=True", "--max-memory": "max_memory_mb",
    "--stage": "stage", "--threads": "threads", "--smooth": "smooth_rounds",
    "--size": "set_size()", "--size-min": "set_size(size_min=...)",
    "--size-max": "set_size(size_max=...)", "--curvature": "set_curvature()",
    "--thickness": "set_thickness()", "--gradation": "set_gradation()",
    "--feature-angle": "set_features(angle=...)",
    "--feature-level": "set_features(level=...)",
    "--features": "set_features(path=...)",
    "--no-features": "set_features(angle=0)",
    "--level": "set_input_level()", "--inside-level": "set_input_level()",
    "--label-size": "label_size", "--label-names": "label_names",
    "--voxel": "voxel=True", "--interface-smoothing": "smoothing",
    "--min-island": "min_island",
}
_FLAG_RE = re.compile(r"(?<![\w/.-])(--[a-zA-Z][a-zA-Z-]*|-[a-zA-Z])(?![\w-])")
_CNAME_RE = re.compile(r"\bmx_(?:mesher2d|mesher|params2d|params)_?([a-z0-9_]*)")


def _pythonic(text):
    """A library message with the CLI flags and the C names it holds given
    as the Python arguments and methods that do the same."""
    def flag(mt):
        w = mt.group(1)
        return _FLAG_WORDS.get(w, w.lstrip("-").replace("-", "_"))

    def cname(mt):
        rest = mt.group(1)
        if mt.group(0).startswith("mx_params"):
            return "the parameters" + ("' " + rest if rest else "")
        return (rest + "()") if rest else "the mesher"
    # "-i FILE", "--feature-angle DEG": the flag's metavariable goes too
    text = re.sub(r"(?<![\w/.-])(--?[a-zA-Z][a-zA-Z-]*) (?:FILE|DEG|NAME|N|L|MB|RL)\b",
                  r"\1", text)
    text = _CNAME_RE.sub(cname, text)
    text = re.sub(r"\bmx_([a-z0-9_]+)", r"\1", text)
    return _FLAG_RE.sub(flag, text)


def _capture_stderr(fn, *args):
    """Calls fn(*args) with the process's stderr (fd 2) going to a
    temporary file, for the library calls without a mesher (whose messages
    go there); returns (result, the text written)."""
    import sys
    try:
        sys.stderr.flush()
    except Exception:  # noqa: BLE001
        pass
    with tempfile.TemporaryFile() as tmp:
        saved = os.dup(2)
        try:
            os.dup2(tmp.fileno(), 2)
            r = fn(*args)
        finally:
            os.dup2(saved, 2)
            os.close(saved)
        tmp.seek(0)
        text = tmp.read().decode("utf-8", "replace")
    return r, text


# The thread count of the last call made from each Python thread (the
# library's is per C thread, and a long call runs in a worker thread).
_tls = threading.local()


def _fspath(path):
    return os.fsencode(os.fspath(path))


def _u64_array(indices, what):
    """Indices (elements or leaves) as a uint64 array, by the rule of the
    element lists (src/io/element_list.h): whole numbers >= 0, given as
    integers or as reals with a whole value (numpy.loadtxt gives float64:
    1.0 is 1); a fraction, a negative number, NaN, an infinity or a value
    above 2**64 - 1 raises InputError (a ValueError) naming its position.
    A boolean array is a mask. The range is checked by the library."""
    a = np.asarray(indices)
    if a.ndim == 0:
        a = a.reshape(1)
    if a.ndim != 1:
        raise InputError("%s: a 1-D array of indices is expected, not shape %s"
                         % (what, a.shape), EINPUT)
    if a.dtype.kind == "b":
        a = np.flatnonzero(a)       # a mask over the elements (or leaves)
    if a.size == 0:
        return np.zeros(0, dtype=np.uint64)
    if a.dtype.kind not in "iuf":
        raise InputError("%s: integer indices are expected, not %s"
                         % (what, a.dtype), EINPUT)
    if a.dtype.kind == "f":
        with np.errstate(invalid="ignore"):
            bad = ~np.isfinite(a) | (a < 0) | (a != np.floor(a)) | (a >= 2.0 ** 64)
    else:
        bad = a < 0
    if bad.any():
        i = int(np.flatnonzero(bad)[0])
        v = a[i].item()
        if not math.isfinite(v):
            why = "is not a finite number"
        elif v < 0:
            why = "is negative"
        elif v != math.floor(v):
            why = "is not a whole number"
        else:
            why = "is too large (above 2**64 - 1)"
        raise InputError("%s: index %r at position %d %s"
                         % (what, v, i, why), EINPUT)
    return np.ascontiguousarray(a, dtype=np.uint64)


def _input_arrays(name, points, dim, pname, links, k, lname):
    """The C arguments (count, double *, count, uint32 *) of a shape given
    as arrays: points (n, dim) converted to float64, links (m, k) of 0-based
    point indices to uint32 (copied only if needed; the library copies)."""
    x = np.ascontiguousarray(points, dtype=np.float64)
    t = np.asarray(links)
    if x.ndim != 2 or x.shape[1] != dim:
        raise InputError("%s: %s must be (n, %d), not %s"
                         % (name, pname, dim, x.shape), EINPUT)
    if t.ndim != 2 or t.shape[1] != k:
        raise InputError("%s: %s must be (m, %d), not %s"
                         % (name, lname, k, t.shape), EINPUT)
    if t.size and (t.dtype.kind not in "iu" or t.min() < 0
                   or t.max() > 0xFFFFFFFF):
        raise InputError("%s: %s must hold indices 0 .. 2^32-1"
                         % (name, lname), EINPUT)
    t = np.ascontiguousarray(t, dtype=np.uint32)
    # data_as keeps a reference to its array: the pointers stay valid
    return (x.shape[0], x.ctypes.data_as(ctypes.POINTER(ctypes.c_double)),
            t.shape[0], t.ctypes.data_as(ctypes.POINTER(ctypes.c_uint32)))


# ---- the mesher ----------------------------------------------------------------

class _Handle:
    """Owns the C mesher; freed when the Mesher and all its views are gone."""

    def __init__(self, lib, prefix):
        # resolved before the mesher is made: a library lacking them fails
        # without leaking one
        self.free_fn = _function(lib, prefix + "_free")
        self.set_handler = _function(lib, prefix + "_set_message_handler")
        self.ptr = None
        self.callback = None   # the ctypes callback must outlive the handle

    def free(self):
        if self.ptr:
            self.free_fn(self.ptr)
            self.ptr = None

    def __del__(self):
        try:
            self.free()
        except Exception:
            pass


class MeshBuffer:
    """The owner (``.base``) of the mesh views of one mesh generation.

    Keeps the C mesher alive while views exist; ``generation`` is the
    Mesher's generation when the views were taken. When the mesh changes
    while views of it are alive, the library hands their memory over to
    this object (``detached`` becomes True; the mesher goes on with a copy:
    mx_mesher_detach_mesh_buffers), which frees it when the last view is
    gone: an old view keeps reading the values of its generation."""

    __slots__ = ("handle", "generation", "mesher_ref", "owned", "free_fn",
                 "__weakref__")

    def __init__(self, handle, generation, mesher):
        self.handle = handle
        self.generation = generation
        self.mesher_ref = weakref.ref(mesher)
        self.owned = []       # the library's arrays handed over to us
        self.free_fn = None

    @property
    def detached(self):
        return bool(self.owned)

    def __del__(self):
        owned, self.owned = self.owned, []
        for ptr in owned:
            try:
                self.free_fn(ptr)
            except Exception:  # noqa: BLE001 (interpreter shutting down)
                pass

    @property
    def current(self):
        m = self.mesher_ref()
        return (m is not None and m._handle is self.handle
                and m.generation == self.generation)


def _view(ptr, count, dtype, shape, owner):
    """A read-only numpy array over `count` items at `ptr`, owned by `owner`."""
    if count == 0 or not ptr:
        a = np.zeros(shape, dtype=dtype)
        a.flags.writeable = False
        return a
    ctype = np.ctypeslib.as_ctypes_type(np.dtype(dtype))
    buf = ctypes.cast(ptr, ctypes.POINTER(ctype * count)).contents
    # the ctypes array keeps `owner` (and so the C mesher) alive: numpy's
    # base chain is array -> ctypes array -> _objects -> owner
    buf._mixoct_owner = owner
    a = np.frombuffer(buf, dtype=dtype, count=count).reshape(shape)
    a.flags.writeable = False
    return a


def _mesh_view(key, doc):
    """A property reading one view of the current mesh."""
    return property(lambda self: self._get_views()[key], doc=doc)


def _balance(balance):
    return _BALANCE[balance] if isinstance(balance, str) else int(balance)


class _MesherBase:
    """What Mesher (3D) and Mesher2D share: the C object's life, the calls,
    their statuses and messages, the mesh views and their generations, the
    requests, re-meshing, restart files and output.

    A subclass names its C functions by _PREFIX ("mx_mesher" or
    "mx_mesher2d": <prefix>_mesh, <prefix>_write, ...), gives the ctypes
    structures of <prefix>_mesh_arrays and <prefix>_stats, and adds its
    own views to the common ones (_make_views)."""

    _PREFIX = None
    _ARRAYS = None
    _STATS = None
    _DIM = 3
    _COORDS = "xyz"         # the fields of the arrays structure: coordinates,
    _NCELLS = "nelements"   # how many elements,
    _WIDTH = 8              # the nodes of a row of conn
    _NO_LEVEL = -1          # set_levels' "no such level"
    _CONN = "conn"          # the view of the node rows
    _NOUN = "elements"
    _VIEW_KEYS = ()
    TYPE_NAMES = TYPE_NAMES
    NODES_PER_TYPE = NODES_PER_TYPE
    _handle = None
    _views = None
    _buffer_ref = None
    _progress = None
    _progress_error = None

    def _c(self, name):
        return "%s_%s" % (self._PREFIX, name)

    def _start(self, lib, params):
        """Make the C mesher from the filled parameter structure and route
        its messages to this object."""
        self._lib = lib
        self.params = {f: getattr(params, f) for f, _ in params._fields_}
        new = _function(lib, self._c("new"))
        handle = _Handle(lib, self._PREFIX)
        handle.ptr = new(ctypes.byref(params))
        if not handle.ptr:
            raise OutOfMemoryError("%s(): out of memory" % type(self).__name__,
                                   ENOMEM)
        self._handle = handle
        #: warnings of the library, in order (str, without "mixoct: ")
        self.warnings = []
        #: every message of the last call that failed: (level, text)
        self.messages = []
        #: counts the calls that changed (or may have changed) the mesh
        self.generation = 0
        self._views = None
        self._buffer_ref = None     # weakref: the MeshBuffer of the views
        self._progress_error = None
        # the message handler: a closure over a weak reference, so the
        # callback (kept by the handle) does not keep the Mesher alive
        wself = weakref.ref(self)

        def on_message(user, level, text):
            m = wself()
            if m is None:
                return
            s = _pythonic(text.decode("utf-8", "replace") if text else "")
            m.messages.append((level, s))
            if level != MSG_ERROR:
                m.warnings.append(s)

        cb = _MESSAGE_FN(on_message)
        handle.callback = cb
        handle.set_handler(handle.ptr, cb, None)

    # ---- life ------------------------------------------------------------------

    def close(self):
        """Drop the C mesher (freed once no mesh view refers to it)."""
        h = self._handle
        self._handle = None
        self._views = None
        if h is not None and h.ptr:
            # silence the handler first: the Mesher is going away
            h.set_handler(h.ptr, _MESSAGE_FN(), None)
        del h

    @property
    def closed(self):
        return self._handle is None

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
        return False

    def __del__(self):
        try:
            self.close()
        except Exception:
            pass

    def __repr__(self):
        name = type(self).__name__
        if self.closed:
            return "<mixoct.%s closed>" % name
        try:
            c = self.counts
        except Error:
            return "<mixoct.%s without a mesh>" % name
        return ("<mixoct.%s %d nodes, %d %s %s>"
                % (name, self.nnodes, sum(c.values()), self._NOUN, c))

    # ---- calls -----------------------------------------------------------------

    @property
    def _ptr(self):
        if self._handle is None or not self._handle.ptr:
            raise InputError("this %s is closed" % type(self).__name__,
                             EINPUT)
        return self._handle.ptr

    @property
    def last_error(self):
        """The library's last error message ("" when none)."""
        s = _function(self._lib, self._c("last_error"))(self._ptr)
        return s.decode("utf-8", "replace") if s else ""

    def _call(self, name, *args, changes_mesh=False, long=False):
        ptr = self._ptr
        fn = _function(self._lib, name)
        if changes_mesh:
            self._keep_old_views()
            self.generation += 1
            long = True
        del self.messages[:]
        self._progress_error = None
        if long:
            st = self._run_interruptible(fn, ptr, *args)
        else:
            st = fn(ptr, *args)
            _tls.threads = None
        if st != OK:
            err, self._progress_error = self._progress_error, None
            if st == ECANCELED and err is not None:
                raise err
            self._raise(st, name)
        del self.messages[:]
        return st

    def _keep_old_views(self):
        """Before a call that changes the mesh: views of the current mesh
        still alive get its memory (the library goes on with a copy); with
        none alive nothing is copied."""
        self._views = None   # our own cache: not a user's view
        ref, self._buffer_ref = self._buffer_ref, None
        buf = ref() if ref is not None else None
        if buf is None or buf.owned or buf.handle is not self._handle:
            return
        old = (ctypes.c_void_p * _DETACH_MAX)()
        detach = _function(self._lib, self._c("detach_mesh_buffers"))
        st = detach(self._ptr, old)
        if st != OK:
            self._raise(st, self._c("detach_mesh_buffers"))
        buf.free_fn = self._lib.mx_free_array
        buf.owned = [p for p in old if p]

    def _run_interruptible(self, fn, ptr, *args):
        """fn(ptr, *args), a long call: from the main thread it runs in a
        worker thread while the main thread waits in short slices, so that
        Ctrl-C (SIGINT) raises KeyboardInterrupt at once: the call is
        cancelled (cancel()), waited for, and the KeyboardInterrupt goes
        on. From another thread it runs in that thread."""
        if threading.current_thread() is not threading.main_thread():
            st = fn(ptr, *args)
            _tls.threads = None
            return st
        box = {}
        lib = self._lib
        # the end is told by an Event, not Thread.join: a join that Ctrl-C
        # interrupts can take a running thread for stopped (Python 3.11's
        # _wait_for_tstate_lock releases the lock the thread holds)
        done = threading.Event()

        def work():
            try:
                box["st"] = fn(ptr, *args)
                box["threads"] = int(lib.mx_last_call_threads())
            except BaseException as e:  # noqa: BLE001 (given to the caller)
                box["error"] = e
            finally:
                done.set()

        t = threading.Thread(target=work, name="mixoct-call", daemon=True)
        t.start()
        try:
            while not done.wait(0.05):
                pass
        except BaseException:
            # KeyboardInterrupt (or another exception raised by a signal
            # handler): stop the library, wait for it, raise
            self._cancel_ptr(ptr)
            while True:
                try:
                    if done.wait(0.05):
                        break
                except KeyboardInterrupt:
                    pass
            raise
        _tls.threads = box.get("threads")
        if "error" in box:
            raise box["error"]
        return box["st"]

    def _cancel_ptr(self, ptr):
        _function(self._lib, self._c("cancel"))(ptr)

    def cancel(self):
        """Cancel the call running on this mesher (from another thread, or
        from a progress callback): it raises CancelledError within about a
        second and leaves no mesh; the next call works as usual."""
        if self._handle is not None and self._handle.ptr:
            self._cancel_ptr(self._handle.ptr)

    def _raise(self, st, name):
        msg = self.last_error
        if not msg:
            errs = [t for lv, t in self.messages if lv == MSG_ERROR]
            msg = errs[-1] if errs else ""
        if not msg:
            msg = "%s: %s" % (_pythonic(name), status_string(st))
        raise _ERRORS.get(st, InternalError)(_pythonic(msg), st)

    def _mesh_call(self, name, allow_invalid, *args):
        try:
            self._call(name, *args, changes_mesh=True)
        except InvalidMeshError:
            if not allow_invalid:
                raise
            return False
        return True

    # ---- requests ----------------------------------------------------------------

    def add_box(self, lo, hi, level):
        """-b: a box [lo, hi] (3 coordinates each, 2 for Mesher2D) whose
        leaves go to `level` (after meshing too: then call refine())."""
        d = self._DIM
        if np.size(lo) != d or np.size(hi) != d:
            raise InputError("add_box: lo and hi need %d coordinates each"
                             % d, EINPUT)
        corner = ctypes.c_double * d
        self._call(self._c("add_box"),
                   corner(*[float(v) for v in np.ravel(lo)]),
                   corner(*[float(v) for v in np.ravel(hi)]), int(level))

    def read_boxes(self, path):
        """The boxes of a .reg file (Mesher2D: 2D corners,
        ``xmin ymin xmax ymax level``)."""
        self._call(self._c("read_boxes"), _fspath(path))

    def set_levels(self, surface_level=None, all_level=None):
        """Change the -s / -a levels (None: no such level, i.e. -1 for
        Mesher, 0 for Mesher2D); after meshing, refine() applies them to
        the existing tree."""
        check = _level_check(MAX_LEVEL_2D if self._DIM == 2 else MAX_LEVEL)
        self._call(self._c("set_levels"),
                   self._NO_LEVEL if surface_level is None
                   else check("surface_level", surface_level),
                   self._NO_LEVEL if all_level is None
                   else check("all_level", all_level))

    # ---- meshing and re-meshing -------------------------------------------------

    def mesh(self, allow_invalid=False):
        """Mesh from the requests (Mesher: up to the stage asked). With
        allow_invalid, a mesh that breaks the validity contract (3D:
        elements left with J_ENS <= 0, see stats()['invalid']; 2D: the
        independent check failed, stats()['valid'] 0) is kept without
        raising InvalidMeshError, and False is returned."""
        return self._mesh_call(self._c("mesh"), allow_invalid)

    def _refine_list(self, name, indices, allow_invalid):
        a = _u64_array(indices, name)
        return self._mesh_call(
            self._c(name), allow_invalid,
            a.ctypes.data_as(ctypes.POINTER(ctypes.c_uint64)), a.size)

    def refine_elements(self, indices, allow_invalid=False):
        """Split the leaves (octants, quadrants) owning these elements of
        the current mesh once, restore balance, apply the requests and mesh
        again (Algorithm 3). Any integer array-like, reals with whole values
        (what numpy.loadtxt gives), or a boolean mask; a fraction, a
        negative number, NaN or an index out of range raises InputError, a
        ValueError naming the index (nothing done)."""
        return self._refine_list("refine_elements", indices, allow_invalid)

    def refine(self, allow_invalid=False):
        """Apply the current requests (boxes, levels, regions) to the
        existing tree and mesh again."""
        return self._mesh_call(self._c("refine"), allow_invalid)

    # ---- restart files ---------------------------------------------------------

    def save_restart(self, path):
        """The restart file of the current tree and mesh (Mesher: ".octb"
        binary, else text; Mesher2D: text, the quadtree form)."""
        self._call(self._c("save_restart"), _fspath(path), long=True)

    def _load_restart(self, path, elements, allow_invalid):
        self._call(self._c("load_restart"), _fspath(path), changes_mesh=True)
        if isinstance(elements, (str, bytes, os.PathLike)):
            # the element count of the file's mesh is not in the C API: the
            # range is checked by refine_elements instead (no file line)
            elements = read_element_list(elements, 2 ** 64 - 1)
        if elements is None and self._has_mesh():
            return True
        # the library loads the tree without meshing it; the mesh (and the
        # list refinement) comes with refine_elements, whose indices refer
        # to the file's mesh until then
        return self.refine_elements([] if elements is None else elements,
                                    allow_invalid)

    def _has_mesh(self):
        a = self._ARRAYS()
        ok = _function(self._lib, self._c("mesh_arrays"))(
            self._ptr, ctypes.byref(a)) == OK
        del self.messages[:]
        return ok

    # ---- output --------------------------------------------------------------------

    def write(self, path, ascii=False):
        """Write the mesh; format by extension (Mesher: .vtk .vtu .msh .mesh
        .meshb .getfem .m3d .mvm; Mesher2D: .vtu .vtk .msh .off .getfem
        .m3d); ascii: the ASCII variant of .vtk / .msh."""
        self._call(self._c("write"), _fspath(path), 1 if ascii else 0, long=True)

    def stats(self):
        """The figures of the last run (mx_stats, mx_stats2d) as a dict."""
        s = self._STATS()
        _function(self._lib, self._c("stats"))(self._ptr, ctypes.byref(s))
        return {f: getattr(s, f) for f, _ in s._fields_}

    # ---- the mesh as arrays ----------------------------------------------------

    def _arrays(self):
        a = self._ARRAYS()
        name = self._c("mesh_arrays")
        st = _function(self._lib, name)(self._ptr, ctypes.byref(a))
        if st != OK:
            self._raise(st, name)
        return a

    def _get_views(self):
        if self._views is None:
            owner = MeshBuffer(self._handle, self.generation, self)
            self._views = self._make_views(self._arrays(), owner)
            self._buffer_ref = weakref.ref(owner)
        return self._views

    def _make_views(self, a, owner):
        """The views every mesh has, from its arrays structure `a`."""
        n, e = a.nnodes, getattr(a, self._NCELLS)
        d, w = self._DIM, self._WIDTH
        return {
            "nodes": _view(getattr(a, self._COORDS), d * n, np.float64,
                           (n, d), owner),
            self._CONN: _view(a.conn, w * e, np.uint32, (e, w), owner),
            "types": _view(a.type, e, np.uint8, (e,), owner),
            "leaf": _view(a.leaf, e, np.uint32, (e,), owner),
            "level": _view(a.level, e, np.uint8, (e,), owner),
            "nleaves": int(a.nleaves),
        }

    @property
    def counts(self):
        """Elements by type name, e.g. {'tri': .., 'quad': ..} in 2D."""
        return dict(self._get_views()["counts"])

    @property
    def nnodes(self):
        return self._get_views()["nodes"].shape[0]

    @property
    def nelements(self):
        return self._get_views()["types"].shape[0]

    @property
    def nleaves(self):
        return self._get_views()["nleaves"]

    def cells_of_type(self, t, return_indices=False):
        """The (k, NODES_PER_TYPE[t]) node rows of the elements of type t
        (int or a name of TYPE_NAMES: "tet", "pyramid", "prism", "hex";
        "tri", "quad" in 2D), a uint32 copy; with return_indices, (indices,
        rows) where indices are those elements'."""
        if isinstance(t, str):
            t = self.TYPE_NAMES.index(t)
        idx = np.flatnonzero(self.types == t)
        rows = self._get_views()[self._CONN][idx, :self.NODES_PER_TYPE[t]]
        return (idx, rows) if return_indices else rows

    def arrays(self, copy=False):
        """All mesh arrays in a dict (views, or copies that outlive re-meshes;
        an array the mesh lacks, as Mesher's material without materials, is
        None)."""
        v = self._get_views()
        return {k: (v[k].copy() if copy and v[k] is not None else v[k])
                for k in self._VIEW_KEYS}

    def is_current(self, array):
        """Whether a mesh view (or an array derived from one without copying)
        is still valid, i.e. comes from the current mesh generation."""
        b = array
        while b is not None:
            owner = getattr(b, "_mixoct_owner", None)
            if isinstance(owner, MeshBuffer):
                return owner.handle is self._handle and owner.current
            b = getattr(b, "base", None)
        return False


def _level_check(top):
    def check(name, v):
        if isinstance(v, bool) or not isinstance(v, (int, np.integer, float)) \
                or int(v) != v or not -1 <= int(v) <= top:
            raise InputError("%s must be -1 (none) or a level from 0 to %d, not %r"
                             % (name, top, v), EINPUT)
        return int(v)
    return check


def _int_check(low, high, what="a whole number"):
    def check(name, v):
        if isinstance(v, bool) or not isinstance(v, (int, np.integer, float)) \
                or int(v) != v or not low <= int(v) <= high:
            raise InputError("%s must be %s from %d to %d, not %r"
                             % (name, what, low, high, v), EINPUT)
        return int(v)
    return check


def _real_check(low, high=math.inf):
    def check(name, v):
        try:
            x = float(v)
        except (TypeError, ValueError):
            x = math.nan
        if isinstance(v, bool) or not low <= x <= high:
            raise InputError("%s must be a number from %s to %s, not %r"
                             % (name, low, high, v), EINPUT)
        return x
    return check


def _flag(name, v):
    if v in (True, False, 0, 1):
        return 1 if v else 0
    raise InputError("%s must be True or False, not %r" % (name, v), EINPUT)


def _choice(words):
    def check(name, v):
        if isinstance(v, str):
            if v in words:
                return words[v]
        elif not isinstance(v, bool) and v in words.values():
            return int(v)
        raise InputError("%s must be one of %s, not %r"
                         % (name, ", ".join(sorted(words, key=words.get)), v), EINPUT)
    return check


#: the validation of each field of mx_params (the command line's ranges); a
#: field appended to _Params without an entry here takes whole numbers
#: (c_int) or finite reals (c_double) unchecked
_PARAM_CHECKS = {
    "surface_level": _level_check(MAX_LEVEL),
    "all_level": _level_check(MAX_LEVEL),
    "stage": _choice(_STAGES),
    "balance": _choice(_BALANCE),
    "threads": _int_check(0, 4096, "a thread count (0: OpenMP's default)"),
    "max_memory_mb": _real_check(0.0),
    "close_ratio": _real_check(0.0, 1.0),
    "staircase_quality": _real_check(0.0, 1.0),
    "repair_rounds": _int_check(0, 1000, "a number of rounds"),
    "repair_input": _flag,
    "remesh_full": _flag,
    "materials": _flag,
    "smooth_rounds": _int_check(0, 1000, "a number of rounds"),
    "tets": _flag,          # mx_params.tets (--tets)
}


def _fill_params(p, given, checks, who):
    """Sets the fields of the ctypes structure p (filled with the library's
    defaults) from the dict given: None keeps the default; a name that is
    not a field is a TypeError; each value goes through checks[name]."""
    fields = dict(p._fields_)
    for name, v in given.items():
        if name not in fields:
            raise TypeError("%s() got an unexpected keyword argument %r"
                            % (who, name))
        if v is None:
            continue
        check = checks.get(name)
        if check is None:
            check = (_real_check(-math.inf, math.inf)
                     if fields[name] is ctypes.c_double
                     else _int_check(-2 ** 31, 2 ** 31 - 1))
        setattr(p, name, check(name, v))


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
    (re-meshing meshes the whole octree again), ``materials`` (nested
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


#: the validation of each field of mx_params2d (mesher2d's ranges)
_PARAM2D_CHECKS = {
    "surface_level": _level_check(MAX_LEVEL_2D),
    "all_level": _level_check(MAX_LEVEL_2D),
    "balance": _choice(_BALANCE),
    "threads": _int_check(0, 4096, "a thread count (0: OpenMP's default)"),
    "close_ratio": _real_check(0.0, 1.0),
    "max_memory_mb": _real_check(0.0),
    "feature_levels": _flag,
    "materials": _flag,
}


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


# ---- meshio --------------------------------------------------------------------------

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


# ---- element lists ---------------------------------------------------------------

def read_element_list(path, limit):
    """The element indices of a list file, as a numpy uint64 array. The
    published format is one index per line; blanks, commas and line ends
    separate indices, '#' starts a comment. Each word is a whole number
    >= 0, as an integer or a real with a whole value (numpy.savetxt's
    1.200000000000000000e+01 is 12); any other word (not a number, a
    fraction, a negative number, NaN, an index >= limit) raises InputError
    whose message names the file, the line and the word. An empty list is read,
    with a warning (``warnings.warn``). One rule with the command line's
    list files (the library reads the file; its messages are caught)."""
    lib = load_library()
    out = ctypes.POINTER(ctypes.c_uint64)()
    n = ctypes.c_size_t(0)
    read = _function(lib, "mx_read_element_list")
    st, text = _capture_stderr(read, _fspath(path), ctypes.c_uint64(int(limit)),
                               ctypes.byref(out), ctypes.byref(n))
    # no mesher, so no handler: the library's messages, caught on fd 2
    lines = [ln[len("mixoct: "):] if ln.startswith("mixoct: ") else ln
             for ln in text.splitlines() if ln.strip()]
    errs = []
    for ln in lines:   # "[file:line: ]error: text" or "...warning: text"
        mt = re.match(r"(.*?)(error|warning): (.*)$", ln)
        kind, ln = (mt.group(2), mt.group(1) + mt.group(3)) if mt else ("warning", ln)
        if kind == "error":
            errs.append(ln)
        else:
            warnings.warn(_pythonic(ln))
    if st != OK:
        msg = errs[-1] if errs else "%s: %s" % (os.fspath(path), status_string(st))
        raise _ERRORS.get(st, InternalError)(_pythonic(msg), st)
    try:
        if n.value == 0 or not out:
            return np.zeros(0, dtype=np.uint64)
        return np.ctypeslib.as_array(out, shape=(n.value,)).copy()
    finally:
        if out:
            lib.mx_free_array(out)
