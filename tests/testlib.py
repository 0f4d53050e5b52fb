"""What the Python tests share (imported from the tests' own directory):
skipping (a failure when CI is set), the runner of named test functions,
raises(), and the unit cube with the exact Poisson solution of the solver
tests (dolfinx_poisson_test.py, getfem_tets_test.py)."""
import os
import sys
import traceback

RESULTS = []


class Skip(Exception):
    """Raised by a test function that cannot run here (SKIP, or FAIL
    when the environment variable CI is set)."""


def skip(why, what):
    """Leave the whole script: SKIP (exit 77), or FAIL (exit 1) when the
    environment variable CI is set (`what`: the test that must run)."""
    if os.environ.get("CI"):
        print("FAIL: %s (CI is set: the %s test must run)" % (why, what))
        sys.exit(1)
    print("SKIP: %s" % why)
    sys.exit(77)


def check(fn):
    """Run fn now (a decorator): ok, FAIL with its traceback, or SKIP on
    Skip; RESULTS gets (name, passed)."""
    try:
        fn()
    except Skip as e:
        ok = not os.environ.get("CI")
        RESULTS.append((fn.__name__, ok))
        print("%s %s: %s" % ("SKIP" if ok else "FAIL", fn.__name__, e))
    except Exception:
        RESULTS.append((fn.__name__, False))
        print("FAIL %s" % fn.__name__)
        traceback.print_exc(file=sys.stdout)
    else:
        RESULTS.append((fn.__name__, True))
        print("ok   %s" % fn.__name__)
    return fn


def raises(exc, fn, *args, **kw):
    """The exception of type exc that fn(*args, **kw) raises (else an
    AssertionError)."""
    try:
        fn(*args, **kw)
    except exc as e:
        return e
    raise AssertionError("%s not raised by %s" % (exc.__name__, fn.__name__))


class Checks:
    """Named conditions: ok / FAIL lines, counted in `fails`."""

    def __init__(self):
        self.fails = 0

    def __call__(self, cond, msg):
        print(("ok   " if cond else "FAIL ") + msg, flush=True)
        if not cond:
            self.fails += 1


# The unit cube [0, 1]^3 as 12 outward triangles, and the exact solution
# u = sin(x) exp(y) + z^3 of -div grad u = f = -6z of the solver tests.
CUBE_V = [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0],
          [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]]
CUBE_T = [[0, 2, 1], [0, 3, 2], [4, 5, 6], [4, 6, 7], [0, 1, 5],
          [0, 5, 4], [1, 2, 6], [1, 6, 5], [2, 3, 7], [2, 7, 6],
          [3, 0, 4], [3, 4, 7]]


def exact(x, y, z, np):
    """u at points given coordinate-wise (numpy arrays)."""
    return np.sin(x) * np.exp(y) + z ** 3


def cube_surface(np, h=10.0, lo=(0.0, 0.0, 0.0)):
    """A closed cube of side h at corner lo as (xyz, tri) arrays, outward
    triangles (two per face)."""
    xyz = np.array([[x, y, z] for z in (0, h) for y in (0, h) for x in (0, h)],
                   dtype=np.float64) + np.asarray(lo, dtype=np.float64)
    quads = [(0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3),
             (0, 4, 6, 2), (1, 3, 7, 5)]
    tri = []
    for a, b, c, d in quads:
        tri += [(a, b, c), (a, c, d)]
    return xyz, np.array(tri, dtype=np.uint32)
