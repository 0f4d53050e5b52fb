"""What Mesher and Mesher2D share: the C object's life, calls and statuses,
progress and cancellation, the mesh views and their generations."""
import ctypes
import os
import threading
import weakref

import numpy as np

from ._capi import (
    ECANCELED, EINPUT, ENOMEM, Error, InputError, InternalError, InvalidMeshError,
    MAX_LEVEL, MAX_LEVEL_2D, MSG_ERROR, NODES_PER_TYPE, OK, OutOfMemoryError,
    TYPE_NAMES, _BALANCE, _DETACH_MAX, _ERRORS, _MESSAGE_FN, _function, _tls,
    status_string)
from ._args import _fspath, _pythonic, _u64_array
from ._params import _level_check
from ._element_list import read_element_list


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
