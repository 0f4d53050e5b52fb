"""The parameters by name: mx_params / mx_params2d fields with the library's
defaults and the command line's ranges."""
import ctypes
import math

import numpy as np

from ._capi import EINPUT, InputError, MAX_LEVEL, MAX_LEVEL_2D, _BALANCE, _STAGES


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


def _remesh_full(name, v):
    """True / 1: always the whole octree; False / 0: by cost; -1: always
    the leaves around what was split."""
    if v in (True, False, 0, 1, -1) and not (isinstance(v, float) and v != int(v)):
        return int(v)
    raise InputError("%s must be True (1: always full), False (0: by cost) or -1 (always "
                     "local), not %r" % (name, v), EINPUT)


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
    "remesh_full": _remesh_full,
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
