#!/usr/bin/python3
"""Checks of the Python binding's user-facing API (issue 30, item 1):
to_meshio, boundary_faces, the type hints, every parameter by name with
its range, messages in Python's words, progress and cancellation (Ctrl-C
too), views that outlive a re-mesh.

Run with PYTHONPATH=<build>/python and MIXOCT_LIB (tests/meson.build's
python_api does). Arguments: the mixoct program, a scratch directory.
MIXOCT_DATA: the shared data (surfaces/cortex.off). Prints one line per
check and "N passed, N failed"; a check whose tool is missing (meshio)
says SKIP, a failure when CI is set.
"""
import ast
import inspect
import json
import os
import signal
import subprocess
import sys
import tempfile
import time

try:
    import numpy as np
except ImportError:
    if os.environ.get("CI"):
        print("FAIL: numpy missing (CI is set)")
        sys.exit(1)
    print("SKIP: numpy missing (apt-get install python3-numpy)")
    sys.exit(77)

import testlib
from testlib import Skip, check, raises
import mixoct  # noqa: E402

MIXOCT = sys.argv[1] if len(sys.argv) > 1 else "mixoct"
TMP = sys.argv[2] if len(sys.argv) > 2 else tempfile.mkdtemp()
os.makedirs(TMP, exist_ok=True)
DATA = os.environ.get("MIXOCT_DATA", os.path.join(os.path.dirname(__file__), "..", "..",
                                                  "shared", "data"))
RESULTS = testlib.RESULTS


def meshio_or_skip():
    try:
        import meshio
    except ImportError:
        raise Skip("meshio missing (apt-get install python3-meshio)")
    return meshio


def check_json(path):
    r = subprocess.run([MIXOCT, "check", path, "--json"], capture_output=True, text=True)
    assert r.returncode == 0, (path, r.returncode, r.stderr[-2000:])
    return json.loads(r.stdout.strip().splitlines()[-1])


# VTK's faces of each cell (node positions in VTK order), written here from
# VTK's cell definitions, not from the library's tables
VTK_FACES = {
    "tetra": [(0, 1, 3), (1, 2, 3), (2, 0, 3), (0, 2, 1)],
    "pyramid": [(0, 3, 2, 1), (0, 1, 4), (1, 2, 4), (2, 3, 4), (3, 0, 4)],
    "wedge": [(0, 1, 2), (3, 5, 4), (0, 3, 4, 1), (1, 4, 5, 2), (2, 5, 3, 0)],
    "hexahedron": [(0, 4, 7, 3), (1, 2, 6, 5), (0, 1, 5, 4), (3, 7, 6, 2),
                   (0, 3, 2, 1), (4, 5, 6, 7)],
}


def tet_volume(p):
    return np.einsum("ij,ij->i", p[:, 1] - p[:, 0],
                     np.cross(p[:, 2] - p[:, 0], p[:, 3] - p[:, 0])) / 6.0


def cube(lo, h):
    return testlib.cube_surface(np, h, lo)


def demo(level=4, **kw):
    m = mixoct.Mesher(surface_level=level, **kw)
    m.add_demo_surface()
    m.mesh()
    return m


@check
def to_meshio_checked_by_mixoct():
    """The meshio mesh, written by meshio to .vtu and read back by `mixoct
    check`, is valid (every J_ENS > 0: a wrong prism order would turn the
    wedges inside out), with the counts of the mesher and the volume of
    the mesher's own .vtu."""
    meshio = meshio_or_skip()
    m = demo(4)
    mm = m.to_meshio(boundary=False)
    names = {"tetra": "tet", "pyramid": "pyramid", "wedge": "prism", "hexahedron": "hex"}
    got = {names[b.type]: len(b.data) for b in mm.cells}
    assert got == {k: v for k, v in m.counts.items() if v}, (got, m.counts)
    assert mm.points.shape == (m.nnodes, 3)
    want = np.concatenate([m.jens[m.types == t] for t in range(4)]).astype(np.float64)
    assert np.array_equal(np.concatenate(mm.cell_data["J_ENS"]), want)
    p = os.path.join(TMP, "meshio.vtu")
    meshio.write(p, mm, binary=False)
    ours = os.path.join(TMP, "ours.vtu")
    m.write(ours)
    a, b = check_json(p), check_json(ours)
    assert a["invalid"] == 0 and a["faces_misoriented"] == 0, a
    assert a["elements"] == m.nelements and a["nodes"] == m.nnodes, a
    assert a["by_type"] == b["by_type"], (a["by_type"], b["by_type"])
    assert abs(a["volume"] - b["volume"]) <= 1e-9 * abs(b["volume"]), (a["volume"], b["volume"])
    # meshio's wedge is Gmsh's prism (meshio/_vtk_common.py says so: the
    # right-hand normal of the triangle 0 1 2 points towards 3 4 5), so
    # the tet 0 1 2 3 of each wedge has positive volume
    w = [blk.data for blk in mm.cells if blk.type == "wedge"][0]
    P = mm.points[w]
    assert (tet_volume(P[:, (0, 1, 2, 3)]) > 0).all()


@check
def to_meshio_boundary_blocks():
    """With boundary=True the faces come as triangle/quad blocks whose
    counts, tags and elements are the boundary_faces arrays; every cell
    data array has one entry per block; point data surface_tag is 1 on the
    boundary nodes of the one surface."""
    meshio_or_skip()
    m = demo(4)
    bf = m.boundary_faces()
    mm = m.to_meshio()
    blocks = {b.type: b.data for b in mm.cells}
    assert len(blocks["triangle"]) == bf["ntri"] and len(blocks.get("quad", [])) == bf["nquad"]
    for key, arrs in mm.cell_data.items():
        assert len(arrs) == len(mm.cells), key
        for blk, arr in zip(mm.cells, arrs):
            assert len(arr) == len(blk.data), (key, blk.type)
    tags = np.concatenate([a for blk, a in zip(mm.cells, mm.cell_data["surface_tag"])
                           if blk.type in ("triangle", "quad")])
    assert (tags == 1).all()
    st = mm.point_data["surface_tag"]
    assert ((st == 1) == (m.boundary == 1)).all()


@check
def boundary_faces_are_the_faces_used_once():
    """The faces of boundary_faces are exactly the element faces used by
    one element (counted here from VTK's face lists), each a face of the
    element it names, outward (the divergence volume of the faces is the
    mesh's volume); two separate cubes give two bodies and tags 1 and 2 by
    input."""
    meshio = meshio_or_skip()
    m = mixoct.Mesher(surface_level=3)
    m.add_surface_arrays(*cube((0, 0, 0), 10.0), name="a")
    m.add_surface_arrays(*cube((20, 0, 0), 10.0), name="b")
    m.mesh()
    bf = m.boundary_faces()
    mm = m.to_meshio(boundary=False)
    count = {}
    for blk in mm.cells:
        for f in VTK_FACES[blk.type]:
            for row in blk.data[:, list(f)]:
                key = tuple(sorted(row.tolist()))
                count[key] = count.get(key, 0) + 1
    once = {k for k, c in count.items() if c == 1}
    nodes = bf["nodes"]
    faces = {tuple(sorted(int(v) for v in r if v != mixoct.NO_NODE)) for r in nodes}
    assert faces == once, (len(faces), len(once))
    conn = m.conn
    for r, e in zip(nodes, bf["element"]):
        assert set(int(v) for v in r if v != mixoct.NO_NODE) <= set(conn[e].tolist())
    x = m.nodes
    vol = 0.0
    for r in nodes:   # divergence theorem over the (fan-split) faces
        k = 3 if r[3] == mixoct.NO_NODE else 4
        for j in range(1, k - 1):
            a, b, c = x[r[0]], x[r[j]], x[r[j + 1]]
            vol += np.dot(a, np.cross(b, c)) / 6.0
    assert abs(vol - 2000.0) < 1e-6 * 2000.0, vol
    assert bf["nbodies"] == 2 and set(np.unique(bf["body"])) == {1, 2}
    cx = x[nodes[:, 0], 0]
    assert (bf["tag"][cx < 15] == 1).all() and (bf["tag"][cx > 15] == 2).all()
    assert bf["ntags"] == 2 and bf["material"] is None
    assert not bf["nodes"].flags.writeable
    del meshio


@check
def generate_in_one_call():
    """import mixoct; mesh = mixoct.generate(...): the meshio mesh of a
    surface, its counts those of a Mesher with the same arguments."""
    meshio_or_skip()
    mesh = mixoct.generate("demo", surface_level=3)
    m = demo(3)
    n = {b.type: len(b.data) for b in mesh.cells}
    assert n["tetra"] == m.counts["tet"] and n["hexahedron"] == m.counts["hex"], n
    mesh2 = mixoct.generate(cube((0, 0, 0), 1.0), surface_level=2, boundary=False)
    assert {b.type for b in mesh2.cells} <= {"tetra", "pyramid", "wedge", "hexahedron"}


@check
def mesher2d_to_meshio():
    meshio = meshio_or_skip()
    m = mixoct.Mesher2D(surface_level=4)
    m.set_domain(os.path.join(DATA, "polylines", "box.poly"))
    m.mesh()
    mm = m.to_meshio()
    n = {b.type: len(b.data) for b in mm.cells}
    assert n.get("triangle", 0) == m.counts["tri"] and n.get("quad", 0) == m.counts["quad"]
    p = os.path.join(TMP, "m2.vtu")
    meshio.write(p, mm, binary=False)
    back = meshio.read(p)
    assert sum(len(b.data) for b in back.cells) == m.ncells


def stub_names():
    """The names the .pyi declares: module level, and per class (with its
    stub bases)."""
    path = os.path.join(os.path.dirname(mixoct.__file__), "__init__.pyi")
    tree = ast.parse(open(path).read(), path)
    mod, classes, bases = set(), {}, {}
    for node in tree.body:
        if isinstance(node, ast.ClassDef):
            mod.add(node.name)
            names = set()
            for item in node.body:
                if isinstance(item, (ast.FunctionDef, ast.AsyncFunctionDef)):
                    names.add(item.name)
                elif isinstance(item, ast.AnnAssign):
                    names.add(item.target.id)
            classes[node.name] = names
            bases[node.name] = [b.id for b in node.bases if isinstance(b, ast.Name)]
        elif isinstance(node, (ast.FunctionDef,)):
            mod.add(node.name)
        elif isinstance(node, ast.AnnAssign):
            mod.add(node.target.id)
    return mod, classes, bases


@check
def stubs_cover_the_api():
    """__init__.pyi parses, and names every public attribute of the module
    (its imports aside) and every public member of its public classes."""
    mod, classes, bases = stub_names()
    missing = [n for n in dir(mixoct)
               if not n.startswith("_") and not inspect.ismodule(getattr(mixoct, n))
               and n not in mod]
    assert not missing, "not in __init__.pyi: %s" % missing
    assert "__version__" in mod

    def members(c):
        out = set(classes.get(c, ()))
        for b in bases.get(c, ()):
            out |= members(b)
        return out
    for name in dir(mixoct):
        obj = getattr(mixoct, name)
        if name.startswith("_") or not inspect.isclass(obj) or obj.__module__ != "mixoct":
            continue
        stubbed = members(name)
        own = [a for a in dir(obj) if not a.startswith("_")
               and not (issubclass(obj, BaseException) and hasattr(BaseException, a))]
        lack = [a for a in own if a not in stubbed]
        assert not lack, "%s lacks stubs for %s" % (name, lack)
    # instance attributes set in __init__ are stubbed too
    m = mixoct.Mesher()
    lack = [a for a in vars(m) if not a.startswith("_") and a not in members("Mesher")]
    assert not lack, lack


# a value other than the default, and one out of range, per field
PARAMS_3D = {"surface_level": (5, 16), "all_level": (2, -2), "stage": ("transition", "none"),
             "balance": ("recursive", 7), "threads": (2, -1), "max_memory_mb": (512.0, -1.0),
             "close_ratio": (0.4, 2.0), "staircase_quality": (0.3, 1.5),
             "repair_rounds": (3, -1), "repair_input": (True, 2), "remesh_full": (True, "yes"),
             "materials": (True, 5), "smooth_rounds": (4, 1001), "tets": (True, 2)}
PARAMS_2D = {"surface_level": (6, 28), "all_level": (3, -5), "balance": ("recursive", "x"),
             "threads": (2, -3), "close_ratio": (0.2, -0.1), "max_memory_mb": (100.0, -2.0),
             "feature_levels": (False, 3), "materials": (True, 9)}


@check
def every_parameter_by_name():
    """Each field of mx_params / mx_params2d (from the ctypes structures:
    a field added later is listed here or this fails) set to a non-default
    value shows in .params; out of range raises InputError naming the
    argument; None is the library's default."""
    for cls, struct, table in ((mixoct.Mesher, mixoct._Params, PARAMS_3D),
                               (mixoct.Mesher2D, mixoct._Params2D, PARAMS_2D)):
        fields = [f for f, _ in struct._fields_]
        # every field has its values here (a field the library gains
        # fails until it is listed); a listed one the library lacks is left
        assert set(fields) <= set(table), (cls.__name__, set(fields) - set(table))
        d = cls.defaults()
        for f in fields:
            good, bad = table[f]
            with cls(**{f: good}) as m:
                want = {"transition": 1, "recursive": 1}.get(good, good)
                assert m.params[f] == want and m.params[f] != d[f], (f, m.params[f], d[f])
            with cls(**{f: None}) as m:
                assert m.params[f] == d[f]
            e = raises(mixoct.InputError, cls, **{f: bad})
            assert f in str(e) and isinstance(e, ValueError), (f, str(e))
            assert "--" not in str(e) and "mx_" not in str(e), str(e)
        raises(TypeError, cls, no_such_parameter=1)


@check
def messages_speak_python():
    """Errors provoked through the API carry no CLI flag, no C name and no
    'stderr'."""
    texts = []
    m = mixoct.Mesher(surface_level=3)
    texts.append(str(raises(mixoct.InputError, lambda: m.nodes)))
    texts.append(str(raises(mixoct.InputError, m.mesh)))           # no surface
    m2 = mixoct.Mesher2D(surface_level=3)
    texts.append(str(raises(mixoct.InputError, m2.mesh)))          # no domain
    bad = os.path.join(TMP, "list.txt")
    open(bad, "w").write("1\n7\n")
    texts.append(str(raises(mixoct.InputError, mixoct.read_element_list, bad, 5)))
    m3 = demo(3)
    texts.append(str(raises(mixoct.InputError, m3.refine_elements, [10 ** 7])))
    texts.append(str(raises(mixoct.InputError, m3.write, os.path.join(TMP, "x.nope"))))
    m4 = mixoct.Mesher(surface_level=3, stage="transition")
    m4.add_demo_surface()
    texts.append(str(raises(mixoct.InputError, m4.boundary_faces)))
    m5 = mixoct.Mesher(surface_level=3)
    texts.append(str(raises(mixoct.InputError, m5.boundary_stage)))
    for t in filter(None, texts):
        assert t, texts
        for word in ("--", "mx_", "stderr"):
            assert word not in t, (word, t)
    # the translation itself
    t = mixoct._pythonic("no mesh yet: call mx_mesher_mesh first; ask for finer ones "
                         "(-s, -a, -b, -r) or --materials")
    assert "mesh()" in t and "surface_level" in t and "materials=True" in t, t
    assert "--" not in t and "mx_" not in t and " -s" not in t, t
    assert "line 3: -1.5 is negative" in mixoct._pythonic("line 3: -1.5 is negative")
    t = mixoct._pythonic("no input surface: add one (-i FILE) or the demo (--demo)")
    assert t == "no input surface: add one (add_surface()) or the demo (add_demo_surface())", t


def fresh_counts(level):
    m = demo(level)
    return m.counts, m.stats()["leaves_hash"]


@check
def progress_cancels_and_mesher_goes_on():
    """A progress callback returning False at the "boundary" stage makes
    mesh() raise CancelledError (status 6) and leaves no mesh; the next
    mesh() gives the mesh a fresh mesher gives. A callback that raises
    cancels the call and its exception comes out of it."""
    seen = []

    def stop_at_boundary(stage, info):
        seen.append(stage)
        return stage != "boundary"
    m = mixoct.Mesher(surface_level=5, progress=stop_at_boundary)
    m.add_demo_surface()
    e = raises(mixoct.CancelledError, m.mesh)
    assert e.status == mixoct.ECANCELED == 6 and "stderr" not in str(e)
    assert seen[-1] == "boundary" and "level" in seen and "transition" in seen, seen
    raises(mixoct.InputError, lambda: m.nodes)       # no mesh left
    m.set_progress(None)
    m.mesh()
    assert (m.counts, m.stats()["leaves_hash"]) == fresh_counts(5)

    class Stop(Exception):
        pass

    def boom(stage, info):
        if stage == "level" and info[0] == 3:
            raise Stop(info)
    m = mixoct.Mesher(surface_level=5, progress=boom)   # a new tree: levels
    m.add_demo_surface()
    raises(Stop, m.mesh)
    m.set_progress(lambda s, i: None)
    m.mesh()
    assert (m.counts, m.stats()["leaves_hash"]) == fresh_counts(5)
    assert mixoct.status_string(6) == "cancelled"


CHILD = r"""
import sys, time, mixoct
def told(stage, info):
    # the parent sends SIGINT when told: the octree's refinement has begun,
    # and the levels, the transition and the boundary stage are still to come
    if stage == "level" and info[0] == int(sys.argv[3]):
        print("start", flush=True)
m = mixoct.Mesher(surface_level=int(sys.argv[2]), progress=told)
m.add_surface(sys.argv[1])
try:
    m.mesh()
    print("finished", flush=True)
except KeyboardInterrupt:
    print("interrupted %.6f" % time.time(), flush=True)
    m.close()
    sys.exit(0)
sys.exit(3)
"""


@check
def ctrl_c_raises_keyboard_interrupt():
    """SIGINT during a mesh (the cortex at level 8, sent when the mesher
    reports that it starts refining level 6: the rest takes most of a second
    even on a fast machine, the signal a few milliseconds) raises
    KeyboardInterrupt in the main thread within a second; the process then
    exits cleanly (status 0: no crash in the cancelled mesher). (It was
    sent one second after the call began: once the mesher got faster, the
    mesh could finish first.)"""
    cortex = os.path.join(DATA, "surfaces", "cortex.off")
    if not os.path.exists(cortex):
        raise Skip("%s missing (MIXOCT_DATA)" % cortex)
    p = subprocess.Popen([sys.executable, "-c", CHILD, cortex, "8", "6"],
                         stdout=subprocess.PIPE, text=True)
    try:
        assert p.stdout.readline().strip() == "start"
        t = time.time()
        p.send_signal(signal.SIGINT)
        line = p.stdout.readline().strip()
        rc = p.wait(timeout=60)
    finally:
        if p.poll() is None:
            p.kill()
    assert line.startswith("interrupted"), (line, rc)
    lat = float(line.split()[1]) - t
    print("     KeyboardInterrupt %.3f s after SIGINT" % lat)
    assert lat < 1.0, lat
    assert rc == 0, rc


@check
def cancel_and_ctrl_c_in_2d():
    """Mesher2D (no progress hooks): cancel() from another thread stops
    mesh() with CancelledError between its stages, SIGINT raises
    KeyboardInterrupt; either way the next mesh() gives the mesh of a fresh
    mesher. (A cancel may come too late for a fast mesh: a few tries.)"""
    import threading
    poly = os.path.join(DATA, "polylines", "a.poly")

    def fresh(level):
        with mixoct.Mesher2D(surface_level=level) as q:
            q.set_domain(poly)
            q.mesh()
            return q.ncells
    for how, exc in (("cancel", mixoct.CancelledError), ("sigint", KeyboardInterrupt)):
        stopped = 0
        # a SIGINT after the call would hit the test: a mesh long enough
        for level in ((13, 14, 15) if how == "cancel" else (15,)):
            m = mixoct.Mesher2D(surface_level=level)
            m.set_domain(poly)
            act = m.cancel if how == "cancel" else (lambda: os.kill(os.getpid(), signal.SIGINT))
            timer = threading.Timer(0.02, act)
            timer.start()
            try:
                m.mesh()
            except exc:
                stopped += 1
            finally:
                timer.join()
            m.mesh()
            assert m.ncells == fresh(level), (how, level)
            if stopped:
                break
        assert stopped, how


@check
def old_views_keep_their_values():
    """Views taken before refine_elements read, afterwards, the values they
    had (equal to copies taken before: their memory was handed over, not
    freed; run with MALLOC_PERTURB_ so that freed memory would read as
    garbage), and are no longer current; with no view alive nothing is
    detached. The same in 2D."""
    m = demo(4)
    views = {k: getattr(m, k) for k in ("nodes", "conn", "types", "jens", "leaf", "level",
                                        "boundary")}
    copies = {k: v.copy() for k, v in views.items()}
    owner = views["nodes"].base
    while not hasattr(owner, "_mixoct_owner"):
        owner = owner.base
    buf = owner._mixoct_owner
    assert not buf.detached
    m.refine_elements(np.arange(0, m.nelements, 50))
    assert buf.detached and not m.is_current(views["nodes"])
    m.refine_elements(np.arange(0, m.nelements, 70))   # a second change
    junk = [np.full(10 ** 6, 7.0) for _ in range(8)]   # reuse freed memory
    for k in views:
        assert np.array_equal(views[k], copies[k]), k
    del junk
    assert m.nnodes != copies["nodes"].shape[0]
    del views, owner
    fresh = m.nodes
    assert m.is_current(fresh)
    m2 = mixoct.Mesher2D(surface_level=4)
    m2.set_domain(os.path.join(DATA, "polylines", "box.poly"))
    m2.mesh()
    cells, xy = m2.cells, m2.nodes
    cc, xc = cells.copy(), xy.copy()
    m2.refine_elements([0, 1, 2])
    m2.refine_elements([3])
    assert np.array_equal(cells, cc) and np.array_equal(xy, xc)
    assert m2.ncells != cc.shape[0]


npass = sum(1 for _, ok in RESULTS if ok)
nfail = len(RESULTS) - npass
print("%d passed, %d failed" % (npass, nfail))
sys.exit(1 if nfail else 0)
