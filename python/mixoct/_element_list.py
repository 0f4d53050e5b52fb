"""Element list files (read_element_list)."""
import ctypes
import os
import re
import warnings

import numpy as np

from ._capi import InternalError, OK, _ERRORS, _function, load_library, status_string
from ._args import _capture_stderr, _fspath, _pythonic


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
