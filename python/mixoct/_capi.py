"""The C side: the library's constants and status codes, the exceptions, the
ctypes structures of include/mixoct.h, loading the library and declaring
its functions."""
import ctypes
import ctypes.util
import os
import threading


# The deepest level a request may ask for (mixoct.h: MX_MAX_LEVEL - 1, the
# command line's -s/-a range).
MAX_LEVEL = 15
# The deepest level of a 2D request (mixoct.h: MX_MAX_LEVEL2D, mesher2d's
# -s/-a range).
MAX_LEVEL_2D = 27

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




# The thread count of the last call made from each Python thread (the
# library's is per C thread, and a long call runs in a worker thread).
_tls = threading.local()
