"""mixoct: the mixed-element octree mesher, from Python (ctypes + numpy).

A thin binding over the C API of ``include/mixoct.h`` (``libmixoct.so``)::

    import mixoct
    with mixoct.Mesher(surface_level=4) as m:
        m.add_demo_surface()
        m.mesh()
        print(m.counts, m.nodes.shape, m.conn.shape)
        worst = [12, 40]                  # elements with a large error
        m.refine_elements(worst)          # Algorithm 3 of the 2021 paper
        m.write("demo.vtu")

The library is looked for, in this order: the path in the environment
variable ``MIXOCT_LIB``; ``libmixoct.so`` in this package's directory; the
build directory this package was copied into (``<build>/python/mixoct`` ->
``<build>/libmixoct.so``); the path meson wrote into ``_libpath.py`` at
install time; the library on the linker's path (``ctypes.util``).

Mesh arrays are views, not copies
---------------------------------
``Mesher.nodes``, ``conn``, ``types``, ``jens``, ``leaf``, ``level`` and
``boundary`` are read-only numpy arrays over the library's own memory (no
copy). They are valid until the next call that changes the mesh: ``mesh``,
``build_octree``, ``transition``, ``boundary_stage``, ``refine``,
``refine_elements``, ``refine_leaves``, ``load_restart`` (successful or not).
After such a call the library may have freed that memory, and reading an old
view gives garbage or crashes the process. Each view's ``.base`` chain ends
in a :class:`MeshBuffer` that records the mesh generation it was taken from:
``Mesher.is_current(array)`` tells whether it still is valid, and
``Mesher.generation`` counts the mesh changes. Take ``.copy()`` of whatever
must outlive a re-mesh. ``close()`` (or leaving the ``with`` block) is safe
with views alive: the C object is freed when the last view of it is gone.

Errors
------
Every non-zero status of the library raises a subclass of :class:`Error`
(``status`` the code, ``message`` the library's message naming the file and
line for bad input): :class:`InternalError` (1), :class:`InputError` (2,
also a ``ValueError``), :class:`OutOfMemoryError` (3, also a
``MemoryError``), :class:`OutputError` (4), :class:`InvalidMeshError` (5:
elements with J_ENS <= 0 are left; the mesh is still there to inspect or
write). Warnings of the library do not go to stderr: they are collected in
``Mesher.warnings`` (a list of str).

Threads: the library runs its passes with OpenMP threads and the GIL is
released during each call; one Mesher must not be used from two Python
threads at once. The library's message handler is per process (the mesher
whose call is running gets the messages), so two Meshers working at the same
time in two Python threads may see each other's warnings.
"""

import ctypes
import ctypes.util
import os
import weakref

import numpy as np

__all__ = [
    "Mesher", "MeshBuffer", "read_element_list", "load_library", "Error",
    "InternalError", "InputError", "OutOfMemoryError", "OutputError",
    "InvalidMeshError", "TET", "PYRAMID", "PRISM", "HEX", "TYPE_NAMES",
    "NODES_PER_TYPE", "NO_NODE", "status_string",
]

# ---- constants (include/mixoct.h) ------------------------------------------

OK, EINTERNAL, EINPUT, ENOMEM, EIO, EINVALID = 0, 1, 2, 3, 4, 5
TET, PYRAMID, PRISM, HEX = 0, 1, 2, 3
TYPE_NAMES = ("tet", "pyramid", "prism", "hex")
NODES_PER_TYPE = (4, 5, 6, 8)
#: the padding of ``conn`` rows shorter than 8 nodes (UINT32_MAX)
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


_ERRORS = {EINTERNAL: InternalError, EINPUT: InputError,
           ENOMEM: OutOfMemoryError, EIO: OutputError,
           EINVALID: InvalidMeshError}


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
                ("remesh_full", ctypes.c_int)]


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
                ("invalid", ctypes.c_size_t)]


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


_MESSAGE_FN = ctypes.CFUNCTYPE(None, ctypes.c_void_p, ctypes.c_int,
                               ctypes.c_char_p)


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


def _declare(lib):
    P = ctypes.c_void_p
    I = ctypes.c_int
    S = ctypes.c_char_p
    sz = ctypes.c_size_t
    u64p = ctypes.POINTER(ctypes.c_uint64)
    dbl3 = ctypes.POINTER(ctypes.c_double)
    sig = {
        "mx_params_default": (None, [ctypes.POINTER(_Params)]),
        "mx_mesher_new": (P, [ctypes.POINTER(_Params)]),
        "mx_mesher_free": (None, [P]),
        "mx_mesher_set_message_handler": (None, [P, _MESSAGE_FN, P]),
        "mx_mesher_last_error": (S, [P]),
        "mx_status_string": (S, [I]),
        "mx_mesher_add_surface": (I, [P, S]),
        "mx_mesher_add_surface_arrays": (I, [P, S, sz, dbl3, sz,
                                             ctypes.POINTER(ctypes.c_uint32)]),
        "mx_mesher_add_demo_surface": (I, [P]),
        "mx_mesher_add_region_surface": (I, [P, S, I]),
        "mx_mesher_add_box": (I, [P, dbl3, dbl3, I]),
        "mx_mesher_read_boxes": (I, [P, S]),
        "mx_mesher_set_levels": (I, [P, I, I]),
        "mx_mesher_mesh": (I, [P]),
        "mx_mesher_build_octree": (I, [P]),
        "mx_mesher_transition": (I, [P]),
        "mx_mesher_boundary": (I, [P]),
        "mx_mesher_refine_elements": (I, [P, u64p, sz]),
        "mx_mesher_refine_leaves": (I, [P, u64p, sz]),
        "mx_mesher_refine": (I, [P]),
        "mx_mesher_save_restart": (I, [P, S]),
        "mx_mesher_load_restart": (I, [P, S]),
        "mx_read_element_list": (I, [S, ctypes.c_uint64,
                                     ctypes.POINTER(u64p),
                                     ctypes.POINTER(sz)]),
        "mx_free_array": (None, [P]),
        "mx_mesher_mesh_arrays": (I, [P, ctypes.POINTER(_MeshArrays)]),
        "mx_mesher_write": (I, [P, S, I]),
        "mx_mesher_written_order": (I, [P, ctypes.POINTER(ctypes.c_uint32)]),
        "mx_mesher_stats": (None, [P, ctypes.POINTER(_Stats)]),
    }
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
    lib.mixoct_missing = frozenset(missing)
    essential = {"mx_params_default", "mx_mesher_new", "mx_mesher_free",
                 "mx_mesher_last_error", "mx_mesher_set_message_handler"}
    if essential & lib.mixoct_missing:
        raise ImportError("%s is not libmixoct: it lacks %s" % (
            lib._name, ", ".join(sorted(essential & lib.mixoct_missing))))
    return lib


def _function(lib, name):
    if name in lib.mixoct_missing:
        raise InternalError("%s lacks %s (an older libmixoct?)"
                            % (lib._name, name), EINTERNAL)
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


def status_string(status):
    """The library's name of a status code, e.g. 'bad input'."""
    s = load_library().mx_status_string(int(status))
    return s.decode("utf-8", "replace") if s else str(status)


def _fspath(path):
    return os.fsencode(os.fspath(path))


def _u64_array(indices, what):
    a = np.asarray(indices)
    if a.ndim == 0:
        a = a.reshape(1)
    if a.ndim != 1:
        raise InputError("%s: a 1-D array of indices is expected, not shape %s"
                         % (what, a.shape), EINPUT)
    if a.dtype.kind == "b":
        a = np.flatnonzero(a)       # a mask over the elements (or leaves)
    if a.size and a.dtype.kind not in "iu":
        if a.dtype.kind == "f" and np.all(np.floor(a) == a):
            a = a.astype(np.int64)
        else:
            raise InputError("%s: integer indices are expected, not %s"
                             % (what, a.dtype), EINPUT)
    if a.size and a.dtype.kind == "i" and a.min() < 0:
        raise InputError("%s: negative index %d" % (what, int(a.min())),
                         EINPUT)
    return np.ascontiguousarray(a, dtype=np.uint64)


# ---- the mesher ----------------------------------------------------------------

class _Handle:
    """Owns the C mesher; freed when the Mesher and all its views are gone."""

    def __init__(self, lib, ptr):
        self.lib = lib
        self.ptr = ptr
        self.callback = None   # the ctypes callback must outlive the handle

    def free(self):
        if self.ptr:
            self.lib.mx_mesher_free(self.ptr)
            self.ptr = None

    def __del__(self):
        try:
            self.free()
        except Exception:
            pass


class MeshBuffer:
    """The owner (``.base``) of the mesh views of one mesh generation.

    Keeps the C mesher alive while views exist; ``generation`` is the
    Mesher's generation when the views were taken."""

    __slots__ = ("handle", "generation", "mesher_ref", "__weakref__")

    def __init__(self, handle, generation, mesher):
        self.handle = handle
        self.generation = generation
        self.mesher_ref = weakref.ref(mesher)

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


class Mesher:
    """One mesher: inputs, requests, the octree, the mesh (see the module doc).

    Parameters are those of ``mx_params``: ``surface_level`` (-s, -1 none),
    ``all_level`` (-a), ``stage`` ("octree", "transition", "full" or 0..2),
    ``threads`` (0: OpenMP's default), ``max_memory_mb`` (0: the memory
    available), ``repair_rounds``, and, as keywords, ``balance`` ("edges" or
    "recursive"), ``close_ratio`` and ``staircase_quality`` (0: defaults).
    """

    def __init__(self, surface_level=-1, all_level=-1, stage="full",
                 threads=0, max_memory_mb=0, repair_rounds=3, *,
                 balance="edges", close_ratio=0.0, staircase_quality=0.0,
                 library=None):
        self._lib = load_library(library)
        p = _Params()
        self._lib.mx_params_default(ctypes.byref(p))
        p.surface_level = int(surface_level)
        p.all_level = int(all_level)
        p.stage = _STAGES[stage] if isinstance(stage, str) else int(stage)
        p.balance = (_BALANCE[balance] if isinstance(balance, str)
                     else int(balance))
        p.threads = int(threads)
        p.max_memory_mb = float(max_memory_mb)
        p.repair_rounds = int(repair_rounds)
        if close_ratio:
            p.close_ratio = float(close_ratio)
        if staircase_quality:
            p.staircase_quality = float(staircase_quality)
        self.params = {f: getattr(p, f) for f, _ in _Params._fields_}
        ptr = self._lib.mx_mesher_new(ctypes.byref(p))
        if not ptr:
            raise OutOfMemoryError("mx_mesher_new: out of memory", ENOMEM)
        self._handle = _Handle(self._lib, ptr)
        #: warnings of the library, in order (str, without "mixoct: ")
        self.warnings = []
        #: every message of the last call that failed: (level, text)
        self.messages = []
        #: counts the calls that changed (or may have changed) the mesh
        self.generation = 0
        self._views = None
        # the message handler: a closure over a weak reference, so the
        # callback (kept by the handle) does not keep the Mesher alive
        wself = weakref.ref(self)

        def on_message(user, level, text):
            m = wself()
            if m is None:
                return
            s = text.decode("utf-8", "replace") if text else ""
            m.messages.append((level, s))
            if level != MSG_ERROR:
                m.warnings.append(s)

        cb = _MESSAGE_FN(on_message)
        self._handle.callback = cb
        self._lib.mx_mesher_set_message_handler(ptr, cb, None)

    # ---- life ------------------------------------------------------------------

    def close(self):
        """Drop the C mesher (freed once no mesh view refers to it)."""
        h = self._handle
        self._handle = None
        self._views = None
        if h is not None and h.ptr:
            # silence the handler first: the Mesher is going away
            h.lib.mx_mesher_set_message_handler(h.ptr, _MESSAGE_FN(), None)
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
        if self.closed:
            return "<mixoct.Mesher closed>"
        try:
            c = self.counts
        except Error:
            return "<mixoct.Mesher without a mesh>"
        return ("<mixoct.Mesher %d nodes, %d elements %s>"
                % (self._arrays().nnodes, sum(c.values()), c))

    # ---- calls -----------------------------------------------------------------

    @property
    def _ptr(self):
        if self._handle is None or not self._handle.ptr:
            raise InputError("this Mesher is closed", EINPUT)
        return self._handle.ptr

    @property
    def last_error(self):
        """The library's last error message ("" when none)."""
        s = self._lib.mx_mesher_last_error(self._ptr)
        return s.decode("utf-8", "replace") if s else ""

    def _call(self, name, *args, changes_mesh=False):
        ptr = self._ptr
        if changes_mesh:
            # the old views may point to freed memory from now on
            self.generation += 1
            self._views = None
        del self.messages[:]
        st = _function(self._lib, name)(ptr, *args)
        if st != OK:
            self._raise(st, name)
        del self.messages[:]
        return st

    def _raise(self, st, name):
        msg = self.last_error
        if not msg:
            errs = [t for lv, t in self.messages if lv == MSG_ERROR]
            msg = errs[-1] if errs else ""
        if not msg:
            msg = "%s: %s" % (name, status_string(st))
        raise _ERRORS.get(st, InternalError)(msg, st)

    # ---- inputs and requests ---------------------------------------------------

    def add_surface(self, path):
        """A closed surface bounding the domain (OFF, MDL, STL, OBJ)."""
        self._call("mx_mesher_add_surface", _fspath(path))

    def add_surface_arrays(self, xyz, tri, name="arrays"):
        """A closed surface from arrays: xyz (n, 3) float, tri (m, 3) 0-based,
        outward by the right hand. The arrays are converted to float64 and
        uint32 (copied only if needed); the library copies them."""
        x = np.ascontiguousarray(xyz, dtype=np.float64)
        t = np.asarray(tri)
        if x.ndim != 2 or x.shape[1] != 3:
            raise InputError("%s: xyz must be (n, 3), not %s"
                             % (name, x.shape), EINPUT)
        if t.ndim != 2 or t.shape[1] != 3:
            raise InputError("%s: tri must be (m, 3), not %s"
                             % (name, t.shape), EINPUT)
        if t.size and (t.dtype.kind not in "iu" or t.min() < 0
                       or t.max() > 0xFFFFFFFF):
            raise InputError("%s: tri must hold indices 0 .. 2^32-1"
                             % name, EINPUT)
        t = np.ascontiguousarray(t, dtype=np.uint32)
        self._call("mx_mesher_add_surface_arrays", str(name).encode(),
                   x.shape[0],
                   x.ctypes.data_as(ctypes.POINTER(ctypes.c_double)),
                   t.shape[0],
                   t.ctypes.data_as(ctypes.POINTER(ctypes.c_uint32)))

    def add_demo_surface(self):
        """The built-in demo surface (a brain-like closed surface)."""
        self._call("mx_mesher_add_demo_surface")

    def add_region_surface(self, path, level):
        """-r: octants meeting or inside this surface go to `level`."""
        self._call("mx_mesher_add_region_surface", _fspath(path), int(level))

    def add_box(self, lo, hi, level):
        """-b: a box [lo, hi] whose octants go to `level` (after meshing too:
        then call refine())."""
        if np.size(lo) != 3 or np.size(hi) != 3:
            raise InputError("add_box: lo and hi need 3 coordinates each",
                             EINPUT)
        lo3 = (ctypes.c_double * 3)(*[float(v) for v in np.ravel(lo)])
        hi3 = (ctypes.c_double * 3)(*[float(v) for v in np.ravel(hi)])
        self._call("mx_mesher_add_box", lo3, hi3, int(level))

    def read_boxes(self, path):
        """The boxes of a .reg file."""
        self._call("mx_mesher_read_boxes", _fspath(path))

    def set_levels(self, surface_level=-1, all_level=-1):
        """Change the -s / -a levels (-1 none); after meshing, refine()
        applies them to the existing octree."""
        self._call("mx_mesher_set_levels", int(surface_level), int(all_level))

    # ---- meshing -----------------------------------------------------------------

    def mesh(self, allow_invalid=False):
        """Mesh up to the stage asked. With allow_invalid, elements left with
        J_ENS <= 0 do not raise InvalidMeshError (see stats()['invalid'])."""
        return self._mesh_call("mx_mesher_mesh", allow_invalid)

    def build_octree(self):
        """Grid, refine and balance (the first stage alone)."""
        self._call("mx_mesher_build_octree", changes_mesh=True)

    def transition(self):
        """The transition patterns (the second stage alone)."""
        self._call("mx_mesher_transition", changes_mesh=True)

    def boundary_stage(self, allow_invalid=False):
        """The boundary stage with repair (the third stage alone)."""
        return self._mesh_call("mx_mesher_boundary", allow_invalid)

    def _mesh_call(self, name, allow_invalid, *args):
        try:
            self._call(name, *args, changes_mesh=True)
        except InvalidMeshError:
            if not allow_invalid:
                raise
            return False
        return True

    # ---- re-meshing ----------------------------------------------------------------

    def refine_elements(self, indices, allow_invalid=False):
        """Split the leaves owning these elements of the current mesh, restore
        balance, apply the requests and mesh again (Algorithm 3). Any integer
        array-like; an index out of range raises InputError (nothing done)."""
        a = _u64_array(indices, "refine_elements")
        return self._mesh_call(
            "mx_mesher_refine_elements", allow_invalid,
            a.ctypes.data_as(ctypes.POINTER(ctypes.c_uint64)), a.size)

    def refine_leaves(self, indices, allow_invalid=False):
        """The same with leaf indices (0 .. nleaves-1, Morton order)."""
        a = _u64_array(indices, "refine_leaves")
        return self._mesh_call(
            "mx_mesher_refine_leaves", allow_invalid,
            a.ctypes.data_as(ctypes.POINTER(ctypes.c_uint64)), a.size)

    def refine(self, allow_invalid=False):
        """Apply the current requests (boxes, levels, regions) to the
        existing octree and mesh again."""
        return self._mesh_call("mx_mesher_refine", allow_invalid)

    # ---- restart files ---------------------------------------------------------

    def save_restart(self, path):
        """The restart file of the current octree and mesh (".octb": binary)."""
        self._call("mx_mesher_save_restart", _fspath(path))

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
        self._call("mx_mesher_load_restart", _fspath(path), changes_mesh=True)
        if isinstance(elements, (str, bytes, os.PathLike)):
            # the element count of the file's mesh is not in the C API: the
            # range is checked by refine_elements instead (no file line)
            elements = read_element_list(elements, 2 ** 64 - 1)
        if elements is None and self._has_mesh():
            return True
        # libmixoct 0.1 loads the octree without meshing it; the mesh (and
        # the list refinement) comes with refine_elements, whose indices
        # refer to the file's mesh until then
        return self.refine_elements([] if elements is None else elements,
                                    allow_invalid)

    def written_order(self):
        """For each position k of the mesh files (grouped by body, then type:
        at most four blocks a body), the index of that element in the arrays
        (level, type, ... and refine_elements)."""
        n = self.nelements
        order = np.empty(n, dtype=np.uint32)
        self._call("mx_mesher_written_order",
                   order.ctypes.data_as(ctypes.POINTER(ctypes.c_uint32)))
        return order

    def _has_mesh(self):
        a = _MeshArrays()
        ok = self._lib.mx_mesher_mesh_arrays(self._ptr, ctypes.byref(a)) == OK
        del self.messages[:]
        return ok

    # ---- output --------------------------------------------------------------------

    def write(self, path, ascii=False):
        """Write the mesh; format by extension (.vtk .vtu .msh .mesh .meshb
        .getfem .m3d .mvm); ascii: the ASCII variant of .vtk / .msh."""
        self._call("mx_mesher_write", _fspath(path), 1 if ascii else 0)

    def stats(self):
        """The figures of the last run (mx_stats) as a dict."""
        s = _Stats()
        self._lib.mx_mesher_stats(self._ptr, ctypes.byref(s))
        d = {f: getattr(s, f) for f, _ in _Stats._fields_}
        d["leaves_hash"] = "%016x" % s.leaves_hash
        return d

    # ---- the mesh as arrays ----------------------------------------------------

    def _arrays(self):
        a = _MeshArrays()
        st = self._lib.mx_mesher_mesh_arrays(self._ptr, ctypes.byref(a))
        if st != OK:
            self._raise(st, "mx_mesher_mesh_arrays")
        return a

    def _get_views(self):
        if self._views is not None:
            return self._views
        a = self._arrays()
        owner = MeshBuffer(self._handle, self.generation, self)
        n, e = a.nnodes, a.nelements
        v = {
            "nodes": _view(a.xyz, 3 * n, np.float64, (n, 3), owner),
            "types": _view(a.type, e, np.uint8, (e,), owner),
            "conn": _view(a.conn, 8 * e, np.uint32, (e, 8), owner),
            "jens": _view(a.jens, e, np.float32, (e,), owner),
            "leaf": _view(a.leaf, e, np.uint32, (e,), owner),
            "level": _view(a.level, e, np.uint8, (e,), owner),
            "boundary": _view(a.boundary, n, np.uint8, (n,), owner),
            "counts": {TYPE_NAMES[t]: int(a.by_type[t]) for t in range(4)},
            "nleaves": int(a.nleaves),
            "jens_min": float(a.jens_min),
            "invalid": int(a.invalid),
        }
        self._views = v
        return v

    nodes = property(lambda self: self._get_views()["nodes"],
                     doc="(nnodes, 3) float64 coordinates (read-only view)")
    conn = property(lambda self: self._get_views()["conn"],
                    doc="(nelements, 8) uint32 nodes of each element, rows "
                        "padded with NO_NODE; VTK order for tet, pyramid, "
                        "hex, Gmsh's for prisms (read-only view)")
    types = property(lambda self: self._get_views()["types"],
                     doc="(nelements,) uint8: TET 0, PYRAMID 1, PRISM 2, HEX 3")
    jens = property(lambda self: self._get_views()["jens"],
                    doc="(nelements,) float32 J_ENS of each element")
    leaf = property(lambda self: self._get_views()["leaf"],
                    doc="(nelements,) uint32 octree leaf of each element")
    level = property(lambda self: self._get_views()["level"],
                     doc="(nelements,) uint8 level of that leaf")
    boundary = property(lambda self: self._get_views()["boundary"],
                        doc="(nnodes,) uint8, 1 on the domain boundary")

    @property
    def counts(self):
        """Elements by type: {'tet': .., 'pyramid': .., 'prism': .., 'hex': ..}."""
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

    @property
    def jens_min(self):
        return self._get_views()["jens_min"]

    @property
    def invalid(self):
        return self._get_views()["invalid"]

    def cells_of_type(self, t, return_indices=False):
        """The (k, NODES_PER_TYPE[t]) node rows of the elements of type t
        (int or name: "tet", "pyramid", "prism", "hex"), a uint32 copy; with
        return_indices, (indices, rows) where indices are those elements'."""
        if isinstance(t, str):
            t = TYPE_NAMES.index(t)
        idx = np.flatnonzero(self.types == t)
        rows = self.conn[idx, :NODES_PER_TYPE[t]]
        return (idx, rows) if return_indices else rows

    def arrays(self, copy=False):
        """All mesh arrays in a dict (views, or copies that outlive re-meshes)."""
        v = self._get_views()
        keys = ("nodes", "conn", "types", "jens", "leaf", "level", "boundary")
        return {k: (v[k].copy() if copy else v[k]) for k in keys}

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


# ---- element lists ---------------------------------------------------------------

def read_element_list(path, limit):
    """The element indices of a list file (the published format: indices
    separated by white space; words that are not all digits are ignored), as
    a numpy uint64 array. Indices >= limit raise InputError (file and line)."""
    lib = load_library()
    out = ctypes.POINTER(ctypes.c_uint64)()
    n = ctypes.c_size_t(0)
    read = _function(lib, "mx_read_element_list")
    st = read(_fspath(path), ctypes.c_uint64(int(limit)), ctypes.byref(out),
              ctypes.byref(n))
    if st != OK:
        # no mesher, so no last_error: the message went to stderr
        raise _ERRORS.get(st, InternalError)(
            "%s: %s (the message is on stderr)" % (os.fspath(path),
                                                   status_string(st)), st)
    try:
        if n.value == 0 or not out:
            return np.zeros(0, dtype=np.uint64)
        return np.ctypeslib.as_array(out, shape=(n.value,)).copy()
    finally:
        if out:
            lib.mx_free_array(out)
