#!/usr/bin/python3
"""Checks of the 2D mesher's Python binding (mixoct.Mesher2D) over libmixoct.

Run by meson (test 'python2d') with PYTHONPATH=<build>/python, or by hand:

    PYTHONPATH=<build>/python /usr/bin/python3 tests/python2d_test.py

MIXOCT_DATA: the shared data folder (polylines/box.poly), by default
../shared/data next to the source tree. Without numpy or the data it prints SKIP and exits 77
(meson's "skipped"), unless CI is set, where that is a failure. The checks
run under unittest, in the order of this file.

The box (data/polylines/box.poly) is [0,3]^2 minus the hole [1,2]^2; its
counts at -s 3 are derived in the header of tests/test_qremesh.c: the root
square is 3.03 wide from -0.015, so level-3 leaves are 0.37875 wide; all
64 but the 4 inside the hole are kept: 60 leaves of level 3, no
transition, 60 quads; 9 x 9 lattice corners less the one only hole
quadrants share: 80 nodes. Splitting the leaf at the corner (0, 0) gives 4
children that meet the domain and are balanced against level-3
neighbours: 63 leaves, no balance split. The mesh is checked here by
routines independent of the library: the shoelace area of every cell
(positive: counter-clockwise; their sum: the domain's area), conformity
(no directed edge twice; the edges without their reverse are the
boundary, whose length is the polylines' length) and the nodes' place.
"""

import os
import re
import shutil
import sys
import tempfile
import unittest


def skip(why):
    if os.environ.get("CI"):
        print("FAIL: %s (CI is set: the Python test must run)" % why)
        sys.exit(1)
    print("SKIP: %s" % why)
    sys.exit(77)


try:
    import numpy as np
except ImportError:
    skip("numpy missing "
         "(apt-get install --no-install-recommends python3-numpy)")

import mixoct  # noqa: E402  (after the numpy check)

NEXT_TO_SOURCE = os.path.join(os.path.dirname(os.path.abspath(__file__)),
                              "..", "..", "shared", "data")
DATA = os.environ.get("MIXOCT_DATA") or NEXT_TO_SOURCE
if not os.path.isdir(os.path.join(DATA, "polylines")):
    DATA = NEXT_TO_SOURCE
BOX = os.path.join(DATA, "polylines", "box.poly")
if not os.path.isfile(BOX):
    skip("%s not found (set MIXOCT_DATA)" % BOX)
POLY = os.path.dirname(BOX)

TMP = tempfile.mkdtemp(prefix="mixoct_py2d.")
CHECKS = []     # run in this order by unittest (the end of the file)
_TC = unittest.TestCase()


def check(fn):
    CHECKS.append(fn)
    return fn


def raises(exc, fn, *args, **kw):
    """The `exc` that fn(*args, **kw) must raise."""
    with _TC.assertRaises(exc) as cm:
        fn(*args, **kw)
    return cm.exception


# ---- independent checks of a 2D mesh -------------------------------------------

def cell_rows(m):
    """Each cell's node indices (3 or 4), checked against types and NO_NODE."""
    cells, types = m.cells, m.types
    rows = []
    for c in range(cells.shape[0]):
        k = 3 if types[c] == mixoct.TRI else 4
        assert types[c] in (mixoct.TRI, mixoct.QUAD), (c, types[c])
        r = cells[c, :k]
        assert np.all(r < m.nnodes), (c, r)
        assert len(set(r.tolist())) == k, ("repeated node", c, r)
        if k == 3:
            assert cells[c, 3] == mixoct.NO_NODE, (c, cells[c])
        rows.append(r)
    return rows


def signed_areas(nodes, rows):
    """The shoelace area of each cell, positive when counter-clockwise."""
    out = np.empty(len(rows))
    for i, r in enumerate(rows):
        x, y = nodes[r, 0], nodes[r, 1]
        out[i] = 0.5 * (np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y))
    return out


def boundary_length(nodes, rows):
    """Conformity: no directed edge twice (two cells on one side of an edge,
    or a cell turned the wrong way); the total length of the edges whose
    reverse is absent (the boundary, hanging nodes would add to it)."""
    edges = set()
    for r in rows:
        for a, b in zip(r.tolist(), np.roll(r, -1).tolist()):
            assert (a, b) not in edges, ("directed edge twice", a, b)
            edges.add((a, b))
    return sum(np.hypot(*(nodes[b] - nodes[a]))
               for a, b in edges if (b, a) not in edges)


def check_mesh(m, area, length):
    """Everything a valid 2D mesh of a polygonal domain must satisfy."""
    st = m.stats()
    assert st["valid"] == 1 and st["invalid"] == 0, st
    rows = cell_rows(m)
    nodes = np.array(m.nodes)
    a = signed_areas(nodes, rows)
    assert np.all(a > 0), ("clockwise or flat cells", np.flatnonzero(a <= 0))
    assert abs(a.sum() - area) < 1e-9, (a.sum(), area)
    bl = boundary_length(nodes, rows)
    assert abs(bl - length) < 1e-9, (bl, length)
    c = m.counts
    assert c == {"tri": st["tris"], "quad": st["quads"]}, (c, st)
    assert sum(c.values()) == m.ncells == st["cells"], (c, st)
    assert m.nnodes == st["nodes"] and m.nleaves == st["leaves"], st
    # cells name leaves of the tree (a leaf cut off by the boundary may
    # hold none)
    assert m.ncells == 0 or int(m.leaf.max()) < m.nleaves
    return st


def box_nodes_in_domain(nodes):
    """All nodes in [0,3]^2 and none strictly inside the hole (1,2)^2."""
    x, y = nodes[:, 0], nodes[:, 1]
    assert np.all((x >= -1e-12) & (x <= 3 + 1e-12)
                  & (y >= -1e-12) & (y <= 3 + 1e-12))
    e = 1e-12
    hole = (x > 1 + e) & (x < 2 - e) & (y > 1 + e) & (y < 2 - e)
    assert not np.any(hole), nodes[hole]


def corner_cell(m):
    """The lowest cell with a node at (0, 0)."""
    at = np.flatnonzero((m.nodes[:, 0] == 0.0) & (m.nodes[:, 1] == 0.0))
    assert at.size == 1, at
    hit = np.flatnonzero(np.any(m.cells == at[0], axis=1))
    assert hit.size >= 1
    return int(hit[0])


BOX_AREA = 3 * 3 - 1 * 1          # 8
BOX_LENGTH = 4 * 3 + 4 * 1        # the outer square and the hole: 16


def box(level=3, **kw):
    m = mixoct.Mesher2D(surface_level=level, **kw)
    m.set_domain(BOX)
    m.mesh()
    return m


M = box(3)


# ---- the box at -s 3 ------------------------------------------------------------

@check
def box_counts():
    assert M.nodes.shape == (80, 2) and M.nodes.dtype == np.float64
    assert M.cells.shape == (60, 4) and M.cells.dtype == np.uint32
    assert M.types.shape == (60,) and M.types.dtype == np.uint8
    assert M.leaf.shape == (60,) and M.leaf.dtype == np.uint32
    assert M.level.shape == (60,) and M.level.dtype == np.uint8
    assert M.counts == {"tri": 0, "quad": 60}, M.counts
    assert np.all(M.types == mixoct.QUAD) and np.all(M.level == 3)
    # one cell a leaf: every leaf 0 .. 59 holds exactly one
    assert np.array_equal(np.sort(M.leaf), np.arange(60))
    assert np.all(M.cells != mixoct.NO_NODE)
    st = M.stats()
    assert st["leaves"] == 60 and st["split_balance"] == 0, st
    assert M.nleaves == 60 and M.nelements == 60 and M.ncells == 60
    assert "80 nodes, 60 cells" in repr(M), repr(M)
    assert M.params["surface_level"] == 3 and M.params["feature_levels"] == 1


@check
def box_area_orientation_conformity():
    check_mesh(M, BOX_AREA, BOX_LENGTH)
    box_nodes_in_domain(M.nodes)


@check
def views_read_only_and_zero_copy():
    v = M.nodes
    assert not v.flags.writeable
    try:
        v[0, 0] = 1.0
    except ValueError:
        pass
    else:
        raise AssertionError("a view could be written")
    assert M.is_current(v) and M.is_current(v[3:7])   # a slice still is one
    assert not M.is_current(v.copy())
    # the same memory twice (no copy per access)
    assert M.nodes.ctypes.data == v.ctypes.data
    rows = M.cells_of_type("quad")
    assert rows.shape == (60, 4)
    idx, tri = M.cells_of_type(mixoct.TRI, return_indices=True)
    assert idx.size == 0 and tri.shape == (0, 3)
    a = M.arrays(copy=True)
    assert set(a) == {"nodes", "cells", "types", "leaf", "level", "material"}
    assert a["material"] is None and M.material is None  # no materials=True
    assert not M.is_current(a["nodes"]) and np.array_equal(a["nodes"], M.nodes)


# ---- restart files and list refinement ---------------------------------------------

@check
def restart_then_refine_corner():
    path = os.path.join(TMP, "box.oct")
    M.save_restart(path)
    assert os.path.getsize(path) > 0
    corner = corner_cell(M)
    # a fresh mesher with no levels of its own: the tree comes from the file
    with mixoct.Mesher2D() as m:
        m.set_domain(BOX)
        assert m.restart_elements == 0
        m.load_restart(path)
        assert m.restart_elements == 60
        # the same leaves give the same mesh
        assert np.array_equal(m.nodes, M.nodes)
        assert np.array_equal(m.cells, M.cells)
        assert corner_cell(m) == corner
        m.refine_elements([corner])
        st = check_mesh(m, BOX_AREA, BOX_LENGTH)
        assert st["leaves"] == 63, st
        assert st["refined_listed"] == 1 and st["split_balance"] == 0, st
        box_nodes_in_domain(m.nodes)
        # the 4 new leaves are of level 4, at the corner: [-0.015, 0.364]^2
        fine = np.unique(m.leaf[m.level == 4])
        assert fine.size == 4, fine
        rows = m.cells[m.level == 4]
        pts = m.nodes[rows[rows != mixoct.NO_NODE]]
        assert np.all(pts <= 0.36375 + 1e-12), pts.max(axis=0)
        assert set(np.unique(m.level).tolist()) == {3, 4}
        after = m.arrays(copy=True)
    # the list given to load_restart: indices of the file's mesh, refined
    # before any mesh is made; the same result
    with mixoct.Mesher2D() as m:
        m.set_domain(BOX)
        m.load_restart(path, elements=[corner])
        assert m.stats()["leaves"] == 63
        assert np.array_equal(m.nodes, after["nodes"])
        assert np.array_equal(m.cells, after["cells"])
    # an index past the file's mesh: InputError, naming the count
    with mixoct.Mesher2D() as m:
        m.set_domain(BOX)
        e = raises(mixoct.InputError, m.load_restart, path, elements=[60])
        assert "60" in e.message, e.message


@check
def stale_views_after_remesh():
    m = box(3)
    nodes, cells = m.nodes, m.cells
    keep = nodes.copy()
    g = m.generation
    assert m.is_current(nodes) and m.is_current(cells)
    m.refine_elements([corner_cell(m)])
    assert m.generation == g + 1
    assert not m.is_current(nodes) and not m.is_current(cells)
    assert m.is_current(m.nodes) and m.nodes.shape[0] > keep.shape[0]
    before = m.nodes
    m.set_levels(4)
    m.refine()
    assert not m.is_current(before)
    # -s 4 splits the level-3 leaves on the polylines (not all of them)
    assert m.stats()["leaves"] > 63 and set(np.unique(m.level)) == {3, 4}
    check_mesh(m, BOX_AREA, BOX_LENGTH)
    # a copy outlives the re-meshes
    assert keep.shape == (80, 2) and np.all(np.isfinite(keep))


@check
def close_keeps_views_alive():
    m = box(3)
    v = m.cells
    with m:
        pass
    assert m.closed and "closed" in repr(m)
    assert v.shape == (60, 4) and int(v.max()) == 79   # still readable
    assert not m.is_current(v)
    e = raises(mixoct.InputError, m.mesh)
    assert "closed" in e.message


# ---- errors ------------------------------------------------------------------------------

@check
def errors_name_the_file():
    m = mixoct.Mesher2D(surface_level=3)
    missing = os.path.join(TMP, "no_such.poly")
    e = raises(mixoct.InputError, m.set_domain, missing)
    assert isinstance(e, ValueError) and e.status == 2
    assert missing in e.message, e.message
    assert m.last_error and missing in m.last_error
    # no domain yet: nothing to mesh
    raises(mixoct.InputError, m.mesh)
    # a box file with level 40 (levels are 0 to 27): file and line named
    reg = os.path.join(TMP, "level40.reg2")
    with open(reg, "w") as f:
        f.write("n_regions 2\n0 0 1 1 4\n0 0 1 1 40\n")
    m.set_domain(BOX)
    e = raises(mixoct.InputError, m.read_boxes, reg)
    assert reg in e.message and "40" in e.message, e.message
    assert re.search(r":3\b", e.message), e.message    # line 3
    e = raises(mixoct.InputError, m.set_levels, 40)
    assert "40" in e.message, e.message
    e = raises(mixoct.InputError, m.add_region,
               os.path.join(POLY, "unit_square.poly"), 40)
    assert "40" in e.message, e.message
    raises(mixoct.InputError, m.add_box, [0, 0, 0], [1, 1, 1], 4)
    raises(mixoct.InputError, m.add_box, [1, 1], [0, 0], 4)
    raises(mixoct.InputError, m.add_function, "circle", [0, 0], 4)
    raises(mixoct.InputError, m.add_function, "spiral", [0, 0, 1], 4)
    raises(mixoct.InputError, m.set_domain, BOX)          # once only
    # the failed requests left nothing behind: the -s 3 mesh
    m.mesh()
    assert m.counts == {"tri": 0, "quad": 60}
    e = raises(mixoct.InputError, m.refine_elements, [60])
    assert "60" in e.message, e.message
    raises(mixoct.InputError, m.refine_elements, [-1])
    e = raises(ValueError, m.refine_elements, np.array([0.0, 12.5]))
    assert "12.5 at position 1 is not a whole number" in str(e), str(e)
    e = raises(mixoct.InputError, m.write, os.path.join(TMP, "x.unknown"))
    assert e.message
    m.close()


# ---- the domain from arrays ---------------------------------------------------------

SQUARE = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], dtype=np.float64)


@check
def unit_square_arrays():
    # given clockwise on purpose: the nesting decides the orientation
    seg = np.array([[0, 3], [3, 2], [2, 1], [1, 0]])
    with mixoct.Mesher2D(all_level=3) as m:
        m.set_domain_arrays(SQUARE, seg, name="square")
        m.mesh()
        # -a 3: 8 x 8 leaves of width 1.01 / 8, all meeting the square, one
        # level so no transition: 64 quads on the 9 x 9 lattice
        assert m.counts == {"tri": 0, "quad": 64}, m.counts
        assert m.nnodes == 81 and m.nleaves == 64
        check_mesh(m, 1.0, 4.0)
        x, y = m.nodes[:, 0], m.nodes[:, 1]
        assert np.all((x >= 0) & (x <= 1) & (y >= 0) & (y <= 1))
    with mixoct.Mesher2D(all_level=3) as m:
        raises(mixoct.InputError, m.set_domain_arrays, SQUARE[:, :1], seg)
        raises(mixoct.InputError, m.set_domain_arrays, SQUARE, seg[:, :1])
        raises(mixoct.InputError, m.set_domain_arrays, SQUARE, seg - 1)
        e = raises(mixoct.InputError, m.set_domain_arrays, SQUARE,
                   np.array([[0, 1], [1, 2], [2, 3], [3, 4]]), name="sq4")
        assert "sq4" in e.message, e.message
        # an open polyline is not a domain
        raises(mixoct.InputError, m.set_domain_arrays, SQUARE,
               np.array([[0, 1], [1, 2], [2, 3]]))
        # after those refusals the domain still can be set, once
        m.set_domain_arrays(SQUARE.astype(np.float32), seg.astype(np.int64))
        m.mesh()
        assert m.counts == {"tri": 0, "quad": 64}


# ---- requests ----------------------------------------------------------------------------

@check
def requests_refine():
    with mixoct.Mesher2D(surface_level=3) as m:
        m.set_domain(BOX)
        m.mesh()
        m.add_box([0.1, 0.1], [0.2, 0.2], 5)
        m.refine()
        check_mesh(m, BOX_AREA, BOX_LENGTH)
        assert int(m.level.max()) == 5
        # the box straddles x = y = -0.015 + 3.03 / 16 = 0.174375, the
        # middle of the corner leaf [-0.015, 0.36375]^2: its 4 children all
        # meet the box and are split: 16 leaves of level 5, whose cells'
        # nodes lie in that leaf
        assert np.unique(m.leaf[m.level == 5]).size == 16
        rows = m.cells[m.level == 5]
        pts = m.nodes[rows[rows != mixoct.NO_NODE]]
        assert np.all((pts >= 0) & (pts <= 0.36375 + 1e-12)), pts
    reg = os.path.join(TMP, "ok.reg2")
    with open(reg, "w") as f:
        f.write("# one box\nn_regions 1\n2.5 2.5 2.9 2.9 5\n")
    for how in ("read_boxes", "region", "drawing", "function"):
        with mixoct.Mesher2D(surface_level=3) as m:
            m.set_domain(BOX)
            if how == "read_boxes":
                m.read_boxes(reg)
            elif how == "region":
                m.add_region(os.path.join(POLY, "unit_square.poly"), 4)
            elif how == "drawing":
                m.add_drawing(os.path.join(POLY, "drawing.poly"), 4)
            else:
                m.add_function("circle", (1.5, 1.5, 1.2), 4)
            m.mesh()
            check_mesh(m, BOX_AREA, BOX_LENGTH)
            want = 5 if how == "read_boxes" else 4
            assert int(m.level.max()) == want, (how, m.level.max())
            assert m.nleaves > 60, how


@check
def feature_levels_flag():
    # the unit square with a V notch at the top: features (0.48, 1),
    # (0.5, 0.98), (0.52, 1), 0.02 sqrt 2 = 0.0283 apart. With feature
    # levels their quadrants are at most half that, 0.01414: the root is
    # 1.01 wide, 1.01 / 64 = 0.0158 is too wide, 1.01 / 128 fits: level 7.
    # Without, at -a 2 they fall in one quadrant and claim one node.
    xy = np.array([(0, 0), (1, 0), (1, 1), (0.52, 1), (0.5, 0.98),
                   (0.48, 1), (0, 1)], dtype=np.float64)
    seg = np.array([(i, (i + 1) % 7) for i in range(7)])
    area = 1.0 - 0.5 * 0.04 * 0.02
    length = 3.0 + 0.48 * 2 + 2 * 0.02 * np.sqrt(2)
    with mixoct.Mesher2D(all_level=2) as m:
        m.set_domain_arrays(xy, seg, name="notch")
        m.mesh()
        assert int(m.level.max()) == 7, m.level.max()
        check_mesh(m, area, length)
    with mixoct.Mesher2D(all_level=2, feature_levels=False) as m:
        assert m.params["feature_levels"] == 0
        m.set_domain_arrays(xy, seg, name="notch")
        e = raises(mixoct.Error, m.mesh)
        assert e.status in (mixoct.EINPUT, mixoct.EINVALID), e.status
        assert "notch" in e.message and "feature" in e.message, e.message


@check
def size_field():
    # h = 0.02 + 0.2 x on the unit square (mesher2d --size): each cell's
    # quadrant, of side 1.01 / 2^level (the root: 1.01 x the longest
    # extent), no larger than the field at the cell's corners (h is
    # linear) within the control space's factor 1.31 (its leaves hold the
    # value at their centre); finer at x = 0 than at x = 1
    square = os.path.join(POLY, "unit_square.poly")
    with mixoct.Mesher2D() as m:
        m.set_domain(square)
        m.set_size("0.02 + 0.2*x")
        m.mesh()
        check_mesh(m, 1.0, 4.0)
        rows = cell_rows(m)
        side = 1.01 / 2.0 ** m.level.astype(np.float64)
        least = np.array([np.min(0.02 + 0.2 * m.nodes[r, 0]) for r in rows])
        assert np.all(side <= 1.31 * least), np.max(side / least)
        x = np.array([np.mean(m.nodes[r, 0]) for r in rows])
        assert side[x < 0.1].max() < side[x > 0.9].min()
        n = m.nleaves
        path = os.path.join(TMP, "size.vtk")
        m.write(path, ascii=True)
        assert "SCALARS target_size double" in open(path).read()
        # the largest size bounded: finer where the field was above it
        m.set_size("0.02 + 0.2*x", size_max=0.05)
        m.mesh()
        assert m.nleaves > n and np.all(1.01 / 2.0 ** m.level <= 0.05)
        e = raises(mixoct.InputError, m.set_size, "0.02 + 0.2*")
        assert "column 12" in e.message, e.message
        e = raises(mixoct.InputError, m.set_size, "F3", size_min=0.2,
                   size_max=0.1)
        assert "bounds" in e.message, e.message
        m.set_size("F4")
        m.mesh()
    with mixoct.Mesher2D(all_level=2) as m:
        m.set_domain(square)
        m.mesh()
        path = os.path.join(TMP, "plain.vtk")
        m.write(path, ascii=True)
        assert "target_size" not in open(path).read()


@check
def threads_deterministic():
    a = box(6, threads=1)
    b = box(6, threads=2)
    assert np.array_equal(a.nodes, b.nodes)
    assert np.array_equal(a.cells, b.cells)
    assert a.params["threads"] == 1 and b.params["threads"] == 2
    check_mesh(a, BOX_AREA, BOX_LENGTH)


@check
def box_materials():
    """materials=True: the hole of the box is material 2 (the square
    [1,2]^2, area 1, on the lattice of no level: its sides cut cells),
    the rest material 1 (area 8); set_material renumbers and names."""
    m = box(4, materials=True)
    mat = m.material
    assert mat.dtype == np.uint16 and mat.shape == (m.ncells,)
    assert not mat.flags.writeable and m.is_current(mat)
    rows = cell_rows(m)
    areas = signed_areas(m.nodes, rows)
    assert np.all(areas > 0)
    a = {int(k): float(areas[mat == k].sum()) for k in np.unique(mat)}
    assert set(a) == {1, 2} and abs(a[1] - 8) < 1e-12 and abs(a[2] - 1) < 1e-12, a
    assert m.stats()["materials"] == 2
    with mixoct.Mesher2D(surface_level=4, materials=True) as n:
        n.set_material(2, 9, "inclusion")
        n.set_domain(BOX)
        n.mesh()
        assert set(np.unique(n.material).tolist()) == {1, 9}
        e = raises(mixoct.Error, n.set_material, 0, 3)
        assert e.status == mixoct.EINPUT, e.status


# ---- output ---------------------------------------------------------------------------------

@check
def write_files():
    for name, ascii in (("box.vtu", False), ("box.vtk", True),
                        ("box.msh", False)):
        path = os.path.join(TMP, name)
        M.write(path, ascii=ascii)
        assert os.path.getsize(path) > 0, path
    text = open(os.path.join(TMP, "box.vtk")).read()
    assert re.search(r"^POINTS 80\b", text, re.M), text[:300]
    assert re.search(r"^CELLS 60\b", text, re.M), text[:300]
    e = raises(mixoct.OutputError, M.write,
               os.path.join(TMP, "no_dir", "box.vtu"))
    assert "no_dir" in e.message, e.message


@check
def warnings_is_a_list():
    assert isinstance(M.warnings, list)
    assert all(isinstance(w, str) for w in M.warnings)


if __name__ == "__main__":
    suite = unittest.TestSuite(unittest.FunctionTestCase(f) for f in CHECKS)
    result = unittest.TextTestRunner(stream=sys.stdout, verbosity=2).run(suite)
    shutil.rmtree(TMP, ignore_errors=True)
    sys.exit(0 if result.wasSuccessful() else 1)
