"""Arguments in, messages out: the library's messages in Python's words
(item 5 of issue 30), paths, index lists and input arrays."""
import ctypes
import math
import os
import re
import sys
import tempfile

import numpy as np

from ._capi import EINPUT, InputError


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
