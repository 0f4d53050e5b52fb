#!/usr/bin/python3
"""Checks of the Python binding (python/mixoct) over libmixoct.

Run with PYTHONPATH=<build>/python (tests/python_test.sh does). Argument:
a scratch directory. Prints one line per check and "N passed, N failed".
"""

import ctypes
import gc
import os
import sys
import tempfile
import weakref

import numpy as np

import testlib
from testlib import check, raises
import mixoct

TMP = sys.argv[1] if len(sys.argv) > 1 else "/tmp/mixoct_pytest"
os.makedirs(TMP, exist_ok=True)

RESULTS = testlib.RESULTS


def demo(level=3, **kw):
    m = mixoct.Mesher(surface_level=level, **kw)
    m.add_demo_surface()
    m.mesh()
    return m


def cube(h=10.0):
    """A closed cube, outward triangles."""
    return testlib.cube_surface(np, h)


def uv_sphere(r, n=24):
    """A UV sphere of radius r about the origin: n rings, 2n segments,
    outward triangles (the right hand)."""
    k = 2 * n
    th = np.pi * np.arange(1, n) / n
    ph = 2 * np.pi * np.arange(k) / k
    ring = np.stack([np.outer(np.sin(th), np.cos(ph)),
                     np.outer(np.sin(th), np.sin(ph)),
                     np.repeat(np.cos(th)[:, None], k, axis=1)], axis=-1)
    xyz = r * np.vstack([[0, 0, 1], ring.reshape(-1, 3), [0, 0, -1]])
    south = len(xyz) - 1

    def v(i, j):                            # ring i (1 .. n-1), segment j
        return 1 + (i - 1) * k + j % k

    tri = []
    for j in range(k):
        tri.append((0, v(1, j), v(1, j + 1)))
        tri.append((south, v(n - 1, j + 1), v(n - 1, j)))
        for i in range(1, n - 1):
            tri.append((v(i, j), v(i + 1, j), v(i + 1, j + 1)))
            tri.append((v(i, j), v(i + 1, j + 1), v(i, j + 1)))
    return xyz, np.array(tri, dtype=np.uint32)


def signed_volume(xyz, tri):
    a, b, c = xyz[tri[:, 0]], xyz[tri[:, 1]], xyz[tri[:, 2]]
    return float(np.einsum("ij,ij->i", a, np.cross(b, c)).sum()) / 6.0


#: the radii of the concentric spheres of the materials checks
RADII = (1.0, 0.5)


def two_spheres(stage="transition", level=5, **kw):
    """A mesher of two concentric spheres (radii RADII, outward), not yet
    meshed."""
    m = mixoct.Mesher(surface_level=level, stage=stage, **kw)
    for r in RADII:
        xyz, tri = uv_sphere(r)
        # the input itself: outward, the sphere's volume within the
        # tessellation's loss
        vol = signed_volume(xyz, tri)
        exact = 4.0 / 3.0 * np.pi * r ** 3
        assert 0.97 * exact < vol < exact, (r, vol, exact)
        m.add_surface_arrays(xyz, tri, name="sphere_%g" % r)
    return m


def centroids(m):
    """Each element's centroid (the mean of its nodes)."""
    nn = np.array(mixoct.NODES_PER_TYPE)[m.types]
    conn = m.conn
    pad = conn == mixoct.NO_NODE
    xyz = m.nodes[np.where(pad, 0, conn)]
    xyz[pad] = 0.0
    return xyz.sum(axis=1) / nn[:, None]


M = demo(3)


@check
def shapes_and_counts():
    n, e = M.nnodes, M.nelements
    assert n > 0 and e > 0
    assert M.nodes.shape == (n, 3) and M.nodes.dtype == np.float64
    assert M.conn.shape == (e, 8) and M.conn.dtype == np.uint32
    assert M.types.shape == (e,) and M.types.dtype == np.uint8
    assert M.jens.shape == (e,) and M.jens.dtype == np.float32
    assert M.leaf.shape == (e,) and M.leaf.dtype == np.uint32
    assert M.level.shape == (e,) and M.level.dtype == np.uint8
    assert M.boundary.shape == (n,) and M.boundary.dtype == np.uint8
    st = M.stats()
    assert st["nodes"] == n and st["elements"] == e, (st, n, e)
    assert st["invalid"] == 0 and M.invalid == 0
    bc = np.bincount(M.types, minlength=4)
    assert len(bc) == 4
    for t, name in enumerate(mixoct.TYPE_NAMES):
        assert M.counts[name] == bc[t], (name, M.counts, bc)
    assert sum(M.counts.values()) == e
    assert all(M.counts[k] > 0 for k in mixoct.TYPE_NAMES), M.counts
    assert st["leaves"] == M.nleaves


@check
def connectivity():
    conn, types = M.conn, M.types
    for t, nn in enumerate(mixoct.NODES_PER_TYPE):
        rows = conn[types == t]
        assert np.all(rows[:, :nn] < M.nnodes), t
        assert np.all(rows[:, nn:] == mixoct.NO_NODE), t
        # no repeated node in a row
        s = np.sort(rows[:, :nn].astype(np.int64), axis=1)
        assert np.all(s[:, 1:] != s[:, :-1]), t
    idx, rows = M.cells_of_type("prism", return_indices=True)
    assert rows.shape == (M.counts["prism"], 6)
    assert np.all(M.types[idx] == mixoct.PRISM)
    assert np.array_equal(M.cells_of_type(mixoct.HEX),
                          M.conn[M.types == mixoct.HEX])
    used = np.zeros(M.nnodes, dtype=bool)
    used[conn[conn != mixoct.NO_NODE]] = True
    assert used.all(), "unused nodes"


@check
def quality_and_fields():
    assert np.all(M.jens > 0) and M.jens_min > 0
    assert abs(M.jens.min() - M.jens_min) < 1e-12
    assert np.all(M.leaf < M.nleaves)
    assert M.level.min() >= 0 and M.level.max() <= 3
    assert set(np.unique(M.boundary)) <= {0, 1}
    assert M.boundary.sum() > 0 and M.boundary.sum() < M.nnodes


@check
def arrays_are_views():
    a = M._arrays()
    for name, ptr in (("nodes", a.xyz), ("conn", a.conn), ("types", a.type),
                      ("jens", a.jens), ("leaf", a.leaf),
                      ("level", a.level), ("boundary", a.boundary)):
        v = getattr(M, name)
        assert not v.flags.owndata, name
        assert not v.flags.writeable, name
        assert v.base is not None, name
        addr = ctypes.cast(ptr, ctypes.c_void_p).value
        assert v.ctypes.data == addr, (name, v.ctypes.data, addr)
        assert getattr(M, name) is v                   # cached, same object
        assert np.shares_memory(v, getattr(M, name)), name
        assert M.is_current(v), name
    try:
        M.nodes[0, 0] = 1.0
    except ValueError:
        pass
    else:
        raise AssertionError("views must be read-only")
    assert not M.is_current(M.nodes.copy())
    c = M.arrays(copy=True)
    assert c["nodes"].flags.owndata and np.array_equal(c["nodes"], M.nodes)


@check
def refine_elements_grows():
    m = demo(3)
    e0, l0, lv0 = m.nelements, m.nleaves, m.level.max()
    old = m.nodes
    # elements of the finest (surface) leaves, as a Python list of ints
    # (splitting an interior leaf can lower the element count: transition
    # elements around it become hexahedra)
    worst = [int(i) for i in np.flatnonzero(m.level == lv0)[:5]]
    m.refine_elements(worst)
    assert not m.is_current(old)
    assert m.is_current(m.nodes)
    assert m.nleaves > l0, (m.nleaves, l0)
    assert m.nelements > e0, (m.nelements, e0)
    assert m.stats()["refined_listed"] >= 1
    assert m.invalid == 0 and np.all(m.jens > 0)
    # numpy int32, whole reals (numpy.loadtxt's float64), a boolean mask, a
    # tuple: all accepted; the reals refine as the integers do
    r = demo(3)
    r.refine_elements(np.array([1.0, 5.0, 7.0]))
    i = demo(3)
    i.refine_elements([1, 5, 7])
    assert r.nleaves == i.nleaves and r.stats()["refined_listed"] >= 1
    assert r.stats()["leaves_hash"] == i.stats()["leaves_hash"]
    r.close()
    i.close()
    l1 = m.nleaves
    m.refine_elements(np.array([0, 1], dtype=np.int32))
    mask = np.zeros(m.nelements, dtype=bool)
    mask[-3:] = True
    m.refine_elements(mask)
    m.refine_leaves((0,))
    assert m.nleaves > l1
    m.close()


@check
def refine_requests():
    m = demo(3)
    e0 = m.nelements
    lo, hi = M.nodes.min(axis=0), M.nodes.max(axis=0)
    mid = 0.5 * (lo + hi)
    m.add_box(mid - 5, mid + 5, 5)
    m.refine()
    assert m.nelements > e0 and m.level.max() == 5
    e1 = m.nelements
    m.set_levels(4, -1)
    m.refine()
    assert m.nelements > e1
    m.close()


@check
def out_of_range_index():
    m = demo(3)
    e0, h0 = m.nelements, m.stats()["leaves_hash"]
    e = raises(mixoct.InputError, m.refine_elements, [0, m.nelements])
    assert e.status == 2 and isinstance(e, ValueError)
    assert str(m.nelements - 1) in str(e) or str(m.nelements) in str(e), e
    raises(mixoct.InputError, m.refine_elements, [-1])
    raises(mixoct.InputError, m.refine_elements, [1.5])
    # reals, as numpy.loadtxt gives them: the bad one named by position
    for bad, why in (([0.0, 2.5], "2.5 at position 1 is not a whole number"),
                     ([3.0, -1.0], "-1.0 at position 1 is negative"),
                     ([np.nan], "nan at position 0 is not a finite number"),
                     ([np.inf], "inf at position 0 is not a finite number"),
                     ([2.0 ** 64], "at position 0 is too large"),
                     ([5, -2], "-2 at position 1 is negative")):
        e = raises(ValueError, m.refine_elements, np.array(bad))
        assert isinstance(e, mixoct.InputError) and why in str(e), (bad, str(e))
    # the header: "an index out of range is MX_EINPUT (nothing done)"
    assert m.nelements == e0 and m.stats()["leaves_hash"] == h0
    m.close()


@check
def bad_path():
    m = mixoct.Mesher(surface_level=3)
    path = os.path.join(TMP, "no_such_surface.off")
    e = raises(mixoct.InputError, m.add_surface, path)
    assert path in str(e) and e.status == 2, str(e)
    assert isinstance(e, mixoct.Error)
    assert m.last_error == str(e)
    bad = os.path.join(TMP, "bad.off")
    with open(bad, "w") as f:
        f.write("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 oops\n3 0 1 2\n")
    e = raises(mixoct.InputError, m.add_surface, bad)
    assert bad in str(e), str(e)
    # no surface at all: meshing is bad usage
    raises(mixoct.InputError, m.mesh)
    # no mesh: no arrays
    raises(mixoct.InputError, lambda: m.nodes)
    m.close()


@check
def warnings_collected():
    xyz, tri = cube()
    tri = np.vstack([tri, [[0, 0, 1]]])        # a degenerate triangle
    m = mixoct.Mesher(surface_level=2)
    m.add_surface_arrays(xyz, tri, name="cube_arrays")
    assert len(m.warnings) == 1, m.warnings
    assert "cube_arrays" in m.warnings[0] and "degenerate" in m.warnings[0]
    m.mesh()
    assert m.nelements > 0 and np.all(m.jens > 0)
    # the cube's volume (hexahedra: 2 triangles per face of the box)
    lo, hi = m.nodes.min(axis=0), m.nodes.max(axis=0)
    assert np.allclose(lo, 0, atol=1e-9) and np.allclose(hi, 10, atol=1e-9)
    m.close()


@check
def surface_arrays_checked():
    m = mixoct.Mesher(surface_level=2)
    xyz, tri = cube()
    raises(mixoct.InputError, m.add_surface_arrays, xyz[:, :2], tri)
    raises(mixoct.InputError, m.add_surface_arrays, xyz, tri[:, :2])
    raises(mixoct.InputError, m.add_surface_arrays, xyz, -tri.astype(int))
    bad = tri.copy()
    bad[0, 0] = 99
    e = raises(mixoct.InputError, m.add_surface_arrays, xyz, bad, "idx")
    assert "idx" in str(e), str(e)
    m.close()


@check
def restart_round_trip():
    for name in ("demo.oct", "demo.octb"):
        path = os.path.join(TMP, name)
        m = demo(3)
        m.refine_elements([0, 7, 30])
        m.save_restart(path)
        assert os.path.getsize(path) > 0
        want = (m.nnodes, m.nelements, m.nleaves, m.counts,
                m.stats()["leaves_hash"])
        m.close()
        r = mixoct.Mesher(surface_level=3)
        r.add_demo_surface()
        r.load_restart(path)
        got = (r.nnodes, r.nelements, r.nleaves, r.counts,
               r.stats()["leaves_hash"])
        assert got == want, (name, got, want)
        r.close()


@check
def restart_then_list():
    """The -c / -l workflow: a restart file and a list of elements of the
    mesh written with it give the same octree as refining in place."""
    path = os.path.join(TMP, "list.oct")
    lst = os.path.join(TMP, "list.txt")
    m = demo(3)
    m.save_restart(path)
    sel = np.flatnonzero(m.level == m.level.max())[[0, 3, 9]]
    # the list numbers the elements as the files do: position k of the
    # files is element order[k] of the arrays
    order = m.written_order()
    assert sorted(order.tolist()) == list(range(m.nelements))
    assert (np.diff(m.types[order].astype(int)) >= 0).all()  # grouped by type
    inv = np.empty_like(order)
    inv[order] = np.arange(order.size, dtype=order.dtype)
    filesel = inv[sel]
    with open(lst, "w") as f:
        f.write("# elements\n%s\n" % " ".join(str(i) for i in filesel))
    m.refine_elements(sel)
    want = (m.nelements, m.nleaves, m.stats()["leaves_hash"])
    m.close()
    for elements in (lst, filesel, list(filesel)):
        r = mixoct.Mesher(surface_level=3)
        r.add_demo_surface()
        r.load_restart(path, elements=elements)
        got = (r.nelements, r.nleaves, r.stats()["leaves_hash"])
        assert got == want, (type(elements), got, want)
        r.close()


@check
def element_list():
    path = os.path.join(TMP, "elements.txt")
    with open(path, "w") as f:
        f.write("# elements\r\n3 1\r\n4,1,5\r\n")
    a = mixoct.read_element_list(path, 10)
    assert a.dtype == np.uint64 and list(a) == [3, 1, 4, 1, 5], a
    e = raises(mixoct.InputError, mixoct.read_element_list, path, 5)
    assert path in str(e)
    # numpy.savetxt's file is read as the integers it holds
    np.savetxt(path, np.array([3, 1, 4]))
    a = mixoct.read_element_list(path, 10)
    assert list(a) == [3, 1, 4], a
    np.savetxt(path, np.array([3, 1, 4]), delimiter=",", header="elements")
    assert list(mixoct.read_element_list(path, 10)) == [3, 1, 4]
    # a word, a fraction: refused (the message on stderr), not skipped
    for text in ("3 1\n4 x 1 5\n", "3\n1.5\n", "-1\n"):
        with open(path, "w") as f:
            f.write(text)
        e = raises(ValueError, mixoct.read_element_list, path, 10)
        assert isinstance(e, mixoct.InputError) and e.status == 2
    with open(path, "w") as f:
        f.write("# nothing\n")
    a = mixoct.read_element_list(path, 10)
    assert a.dtype == np.uint64 and a.size == 0


@check
def write_files():
    for name in ("demo.vtu", "demo.vtk", "demo.msh", "demo.getfem"):
        path = os.path.join(TMP, name)
        M.write(path)
        assert os.path.getsize(path) > 1000, name
    path = os.path.join(TMP, "demo_ascii.vtk")
    M.write(path, ascii=True)
    with open(path, "rb") as f:
        assert b"ASCII" in f.read(200)
    raises(mixoct.InputError, M.write, os.path.join(TMP, "demo.unknown"))
    e = raises(mixoct.OutputError, M.write,
               os.path.join(TMP, "no_such_dir", "x.vtu"))
    assert e.status == 4 and "no_such_dir" in str(e), str(e)


@check
def outputs_spare_inputs():
    # the library refuses to write over a file the mesher read (issue 23)
    xyz, tri = cube(1.0)
    path = os.path.join(TMP, "spare_in.off")
    with open(path, "w") as f:
        f.write("OFF\n%d %d 0\n" % (len(xyz), len(tri)))
        f.writelines("%g %g %g\n" % tuple(p) for p in xyz)
        f.writelines("3 %d %d %d\n" % tuple(t) for t in tri)
    with open(path, "rb") as f:
        before = f.read()
    m = mixoct.Mesher(surface_level=2)
    m.add_surface(path)
    m.mesh()
    link = os.path.join(TMP, "spare_in_link.vtk")
    if os.path.lexists(link):
        os.remove(link)
    os.symlink(path, link)
    for bad in (link,):
        e = raises(mixoct.InputError, m.write, bad)
        assert "input" in str(e), str(e)
    e = raises(mixoct.InputError, m.save_restart, path)
    assert "input" in str(e), str(e)
    with open(path, "rb") as f:
        assert f.read() == before
    restart = os.path.join(TMP, "spare.oct")
    m.save_restart(restart)
    m2 = mixoct.Mesher()
    m2.add_surface(path)
    m2.load_restart(restart)
    m2.save_restart(restart)  # the re-meshing loop: allowed


@check
def memory_budget():
    m = mixoct.Mesher(surface_level=9, max_memory_mb=1)
    m.add_demo_surface()
    e = raises(mixoct.OutOfMemoryError, m.mesh)
    assert e.status == 3 and isinstance(e, MemoryError)
    m.close()


@check
def stages():
    m = mixoct.Mesher(surface_level=3, stage="octree")
    m.add_demo_surface()
    m.mesh()
    assert m.stats()["leaves"] > 0
    try:
        n = m.nelements
    except mixoct.InputError:
        pass                    # the octree stage may leave no mesh arrays
    else:
        assert m.counts["hex"] == n == m.nleaves, (m.counts, m.nleaves)
    m.close()
    m = mixoct.Mesher(surface_level=3, stage="transition")
    m.add_demo_surface()
    m.mesh()
    assert m.nelements > m.nleaves
    m.close()


@check
def threads_deterministic():
    a = demo(3, threads=1)
    b = demo(3, threads=2)
    assert a.stats()["leaves_hash"] == b.stats()["leaves_hash"]
    assert np.array_equal(a.nodes, b.nodes)
    assert np.array_equal(a.conn, b.conn)
    a.close()
    b.close()


@check
def close_keeps_views_alive():
    m = demo(3)
    j, n = m.jens, m.nodes
    total = float(j.sum())
    m.close()
    assert m.closed
    raises(mixoct.InputError, m.mesh)
    del m
    gc.collect()
    assert float(j.sum()) == total          # the C object is still there
    assert n.shape[1] == 3
    with demo(3) as m2:
        assert m2.nelements > 0
    assert m2.closed


@check
def handle_freed():
    m = demo(3)
    h = weakref.ref(m._handle)
    v = m.types
    m.close()
    gc.collect()
    assert h() is not None and h().ptr      # a view is alive: not freed
    del v
    gc.collect()
    assert h() is None                      # the last view gone: freed


@check
def materials_by_radius():
    """Two concentric spheres at the transition stage with materials: an
    element's material is the number of spheres around its centroid,
    counted here from the centroid's radius; elements whose centroid lies
    within 0.02 of a sphere (the tessellation moves a sphere by 0.005 at
    most) are not judged."""
    m = two_spheres(materials=True)
    m.mesh()
    assert m.params["materials"] == 1
    mat, e = m.material, m.nelements
    assert mat is not None and mat.dtype == np.uint16 and mat.shape == (e,)
    assert not mat.flags.writeable and not mat.flags.owndata
    a = m._arrays()
    assert mat.ctypes.data == ctypes.cast(a.material, ctypes.c_void_p).value
    assert m.is_current(mat) and m.material is mat
    r = np.linalg.norm(centroids(m), axis=1)
    depth = sum((r < R).astype(int) for R in RADII)
    far = np.all([np.abs(r - R) > 0.02 for R in RADII], axis=0)
    wrong = np.flatnonzero(far & (mat != depth))
    assert wrong.size == 0, ("%d of %d elements with the wrong material, "
                             "e.g. element %d: radius %.4f, material %d"
                             % (wrong.size, far.sum(), wrong[0],
                                r[wrong[0]], mat[wrong[0]]))
    # most elements are judged, and each of the three regions has some
    assert far.sum() > 0.8 * e, (far.sum(), e)
    for d in range(len(RADII) + 1):
        assert np.count_nonzero(far & (depth == d)) > 0, d
    counts = {int(k): int(np.count_nonzero(mat == k)) for k in np.unique(mat)}
    assert set(counts) <= set(range(len(RADII) + 1)), counts
    assert sum(counts.values()) == e, (counts, e)
    # arrays(): the view, and a copy that outlives the mesher
    assert m.arrays()["material"] is mat
    c = m.arrays(copy=True)["material"]
    assert c.flags.owndata and np.array_equal(c, mat)
    # re-meshing keeps the materials (they come from the inputs), and a
    # restart file is written
    n0 = m.nelements
    m.refine_elements([0])
    assert m.material is not None and m.material.shape == (m.nelements,) and m.nelements > n0
    m.save_restart(os.path.join(TMP, "mat.oct"))
    assert os.path.getsize(os.path.join(TMP, "mat.oct")) > 0
    m.close()


@check
def materials_off_is_none():
    """Without materials the view is None (the C pointer NULL), and the
    inner sphere is a hole: the transition stage keeps the leaves that meet
    the spheres whole, so no element's centroid lies deeper inside it than
    the diagonal of a leaf of the finest level."""
    m = two_spheres()
    m.mesh()
    assert m.params["materials"] == 0
    assert m.material is None
    assert m.arrays()["material"] is None
    assert m.arrays(copy=True)["material"] is None
    r = np.linalg.norm(centroids(m), axis=1)
    fine = m.conn[(m.level == m.level.max()) & (m.types == mixoct.HEX)]
    box = m.nodes[fine]
    diag = float(np.linalg.norm(box.max(axis=1) - box.min(axis=1),
                                axis=1).max())
    assert 0 < diag < 0.5 * RADII[1], diag
    assert np.count_nonzero(r < RADII[1] - diag) == 0
    assert np.count_nonzero((r > RADII[1] + diag)
                            & (r < RADII[0] - diag)) > 0
    m.close()
    assert M.material is None               # the full stage, no materials


@check
def materials_at_full_stage():
    """At the full stage too: the outer boundary on the outer sphere, every
    element away from the spheres labelled by the spheres around its
    centroid; the elements are all inside the outer sphere (no material
    0)."""
    m = two_spheres(stage="full", materials=True)
    m.mesh()
    mat = m.material
    assert mat is not None and mat.dtype == np.uint16
    r = np.linalg.norm(centroids(m), axis=1)
    away = np.all(np.abs(r[:, None] - np.array(RADII)[None, :]) > 0.02, axis=1)
    want = (r[:, None] < np.array(RADII)[None, :]).sum(axis=1)
    assert np.array_equal(mat[away], want[away]), int((mat[away] != want[away]).sum())
    assert set(np.unique(mat).tolist()) == {1, 2}, np.unique(mat)
    m.close()
    # numbered by the user: the inner sphere's material 9, the outer's 4
    n = two_spheres(stage="full", materials=True)
    n.set_material(0, 4, "outer")
    n.set_material(1, 9, "inner")
    n.mesh()
    want9 = (r < RADII[1])
    assert np.array_equal(n.material[away] == 9, want9[away])
    assert set(np.unique(n.material).tolist()) == {4, 9}, np.unique(n.material)
    raises(mixoct.InputError, lambda: n.set_material(5, 1))   # no input 5
    n.close()


def largest(m, which):
    """The largest distance from an element of material `which` to its
    nodes' centroid."""
    conn = m.conn
    pad = conn == mixoct.NO_NODE
    xyz = m.nodes[np.where(pad, 0, conn)]
    c = centroids(m)
    d = np.linalg.norm(xyz - c[:, None, :], axis=2)
    d[pad] = 0.0
    return float(d.max(axis=1)[m.material == which].max())


@check
def level_per_input():
    """A level for the inner sphere only (set_input_level): the elements
    around it are smaller than around the outer sphere, and a level
    everywhere inside the inner material makes its elements smaller than
    the outer material's; bad indices and levels are refused."""
    base = two_spheres(stage="full", materials=True, level=3)
    base.mesh()
    n0 = np.bincount(base.material)
    base.close()
    m = two_spheres(stage="full", materials=True, level=3)
    m.set_input_level(1, surface_level=5)
    m.mesh()
    n1 = np.bincount(m.material)
    # the inner sphere's surface finer: more elements on both of its sides
    assert n1[2] > 2 * n0[2] and n1[1] > n0[1], (n0, n1)
    big1 = largest(m, 2)
    m.close()
    k = two_spheres(stage="full", materials=True, level=3)
    k.set_input_level(1, inside_level=5)
    k.mesh()
    # everywhere inside, not only at the surface: the inner material's
    # largest element is smaller (the ball's centre at level 5, not 3)
    big2 = largest(k, 2)
    assert big2 < 0.8 * big1, (big1, big2)
    raises(mixoct.InputError, lambda: k.set_input_level(7, 5))
    raises(mixoct.InputError, lambda: k.set_input_level(0, 99))
    k.close()



@check
def size_field():
    """set_size: a field finer near x = -1 than x = 1 gives smaller
    elements there; a bad expression raises InputError naming the column."""
    m = mixoct.Mesher(stage="full")
    xyz, tri = uv_sphere(1.0)
    m.add_surface_arrays(xyz, tri, name="sphere")
    m.set_size("0.05 + 0.3*(x + 1)")
    m.mesh()
    c = centroids(m)
    left, right = (c[:, 0] < -0.5).sum(), (c[:, 0] > 0.5).sum()
    assert left > 3 * right, (left, right)
    e = raises(mixoct.InputError, m.set_size, "0.05 + sqr(x)")
    assert "column 8" in str(e), str(e)
    m.close()

@check
def size_sources():
    """set_size with a Python function (vectorised), set_thickness on a
    plate (two elements across), set_size_points, set_size_elements then
    refine: the elements follow each; bad values raise InputError."""
    # a function of the points: finer near x = -1
    m = mixoct.Mesher(stage="full")
    xyz, tri = uv_sphere(1.0)
    m.add_surface_arrays(xyz, tri, name="sphere")
    calls = []

    def f(p):
        calls.append(len(p))
        return 0.05 + 0.3 * (p[:, 0] + 1.0)
    m.set_size(f)
    m.mesh()
    c = centroids(m)
    left, right = (c[:, 0] < -0.5).sum(), (c[:, 0] > 0.5).sum()
    assert calls and left > 3 * right, (left, right)
    # a size per element: the right half asks for 0.08
    n0 = m.nelements
    h = np.where(centroids(m)[:, 0] > 0.0, 0.08, 10.0)
    m.set_size_elements(h)
    m.refine()
    c = centroids(m)
    assert m.nelements > n0 and (c[:, 0] > 0.5).sum() > right, (m.nelements, n0)
    raises(mixoct.InputError, m.set_size_elements, np.ones(3))
    m.close()
    # a plate 0.05 thick: two elements across with set_thickness
    m = mixoct.Mesher(stage="full", surface_level=0)
    xyz, tri = cube(1.0)
    xyz = np.asarray(xyz, dtype=float) * [1.0, 1.0, 0.05]
    m.add_surface_arrays(xyz, tri, name="plate")
    m.set_thickness(2)
    m.mesh()
    x = m.nodes[:, 2]
    assert ((x > 0.001 * 0.05) & (x < 0.999 * 0.05)).any()  # nodes inside the plate
    raises(mixoct.InputError, m.set_thickness, 0.5)
    raises(mixoct.InputError, m.set_gradation, 1.0)
    raises(mixoct.InputError, m.set_size_points, [[0, 0, 0]], [-1.0])
    m.close()
    # a size map file: the same as the arrays; a bad line raises InputError
    with tempfile.TemporaryDirectory() as d:
        path = os.path.join(d, "map.txt")
        with open(path, "w") as f:
            f.write("# x y z h\n0.5 0 0 0.03\n")
        m = mixoct.Mesher(stage="full", surface_level=2)
        xyz, tri = uv_sphere(1.0)
        m.add_surface_arrays(xyz, tri, name="sphere")
        m.set_size_map(path)
        m.mesh()
        n_file = m.nelements
        m.close()
        with open(path, "w") as f:
            f.write("0.5 0 0 0.03\n0.5 0 0\n")
        m = mixoct.Mesher()
        e = raises(mixoct.InputError, m.set_size_map, path)
        assert "map.txt:2" in str(e), str(e)
        m.close()
    # points with sizes: finer around (0.5, 0, 0)
    m = mixoct.Mesher(stage="full", surface_level=2)
    xyz, tri = uv_sphere(1.0)
    m.add_surface_arrays(xyz, tri, name="sphere")
    m.set_size_points([[0.5, 0.0, 0.0]], [0.03])
    m.mesh()
    c = centroids(m)
    near = (np.linalg.norm(c - [0.5, 0, 0], axis=1) < 0.2).sum()
    far = (np.linalg.norm(c - [-0.5, 0, 0], axis=1) < 0.2).sum()
    assert near > 4 * far, (near, far)
    assert m.nelements == n_file, (m.nelements, n_file)
    m.close()


@check
def sharp_features():
    """A cube's ridges and corners kept (issue 29): the figures say so and
    the nodes agree (a node at every corner, found here from the arrays);
    angle 0 gives them up (corners rounded off); the smoothing keyword and
    a bad angle."""
    xyz, tri = cube(10.0)
    xyz = xyz + 0.123
    corners = xyz.copy()
    diag = np.linalg.norm(xyz.max(axis=0) - xyz.min(axis=0))

    def corner_gap(m):
        nodes = m.arrays()["nodes"]
        return max(np.linalg.norm(nodes - c, axis=1).min() for c in corners) / diag

    m = mixoct.Mesher(surface_level=3, smooth_rounds=2)
    m.add_surface_arrays(xyz, tri, name="cube")
    m.mesh()
    f = m.feature_figures()
    assert f["ridges"] == 12 and f["corners"] == 8 and f["kept"], f
    assert f["corners_placed"] == 8 and f["lines_followed"] == 12, f
    assert f["corner_distance"] <= 1e-9 and f["ridge_distance"] <= 1e-6, f
    assert corner_gap(m) <= 1e-9, corner_gap(m)
    assert m.stats()["jens_min"] > 0.0
    m.close()
    m = mixoct.Mesher(surface_level=3)
    m.add_surface_arrays(xyz, tri, name="cube")
    m.set_features(angle=0)
    m.mesh()
    f = m.feature_figures()
    assert f["ridges"] == 0 and not f["kept"], f
    assert corner_gap(m) > 1e-3, corner_gap(m)
    raises(mixoct.InputError, m.set_features, angle=200)
    m.close()



@check
def version_defaults_and_ranges():
    """__version__ is meson's project version; Mesher() takes the C
    defaults (mx_params_default) for what it is not given; a level or a
    count out of the command line's range is refused as InputError (a
    ValueError) whose text names the Python argument."""
    meson = open(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..",
                              "meson.build")).read()
    assert "version : '%s'" % mixoct.__version__ in meson, mixoct.__version__
    pyproject = open(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..",
                                  "pyproject.toml")).read()
    assert 'version = "%s"' % mixoct.__version__ in pyproject, "pyproject.toml's version"
    lib = mixoct.load_library()
    p = mixoct._Params()
    lib.mx_params_default(ctypes.byref(p))
    with mixoct.Mesher() as m:
        for f, _ in p._fields_:
            assert m.params[f] == getattr(p, f), (f, m.params[f], getattr(p, f))
    assert p.repair_rounds == 10, p.repair_rounds
    with mixoct.Mesher(surface_level=mixoct.MAX_LEVEL, repair_rounds=0) as m:
        assert m.params["surface_level"] == 15 and m.params["repair_rounds"] == 0
    for kw in ({"surface_level": 16}, {"surface_level": -2}, {"all_level": 20},
               {"surface_level": 2.5}, {"repair_rounds": -1}, {"threads": -1},
               {"max_memory_mb": -5}, {"smooth_rounds": -1}, {"surface_level": True}):
        e = raises(mixoct.InputError, mixoct.Mesher, **kw)
        assert isinstance(e, ValueError) and list(kw)[0] in str(e), (kw, str(e))
        assert "--" not in str(e) and "mx_" not in str(e), str(e)

M.close()
npass = sum(1 for _, ok in RESULTS if ok)
nfail = len(RESULTS) - npass
print("%d passed, %d failed" % (npass, nfail))
sys.exit(1 if nfail else 0)
