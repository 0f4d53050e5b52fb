#!/usr/bin/env python3
"""Several materials in the 2D mesher (issue 26, item 6): `mesher2d
--materials` on nested loops, the files read back and judged here, with
nothing of the mesher's: the areas, regions, interfaces and conformity are
computed from the written cells and the input's own polylines.

    materials2d_test.py path/to/mesher2d (or mixoct: a link is made)

1. The unit square with a quadrilateral loop inside
   (../shared/data/polylines/square_with_hole.off, read in place), at two
   levels: two materials; every cell's centroid in its region (point in
   polygon here); every node on an edge between the materials within 1e-9
   of the inner loop, and the edge's middle too, so the edge lies along it:
   then each material's area is its region's exactly (shoelace of the
   loops: 0.135 inside, 0.865 between), up to rounding (1e-9); every edge
   used by one cell on the unit square, by two cells in opposite
   directions otherwise (conforming); every cell counter-clockwise with a
   positive scaled Jacobian (the quality mesher2d reports, read from the
   file's field sj, and the corners' cross products here); the .msh has a
   physical surface per material, the boundary and "interface material 1 |
   material 2" as physical curves, the latter with as many lines as there
   are edges between the materials; the .getfem regions 1001 and 1002
   (GetFEM's integral of 1 over each equals the areas, when python3-getfem
   is there); the same bytes with 1 and 2 threads.
2. Three nested loops written here (a square, a diamond in it, a triangle
   in that): three materials, the same checks, areas from the loops.
3. Numbers and names: --material 7:matrix --material 3:inclusion gives the
   cell field values 7 and 3 and those physical names.
4. Bad input exits 2: a loop crossing another; --material without
   --materials; a material number out of range.
5. Without --materials the inner loop stays a hole (area 0.865, one
   material-less mesh).
The meshes are written with --keep-invalid, so that a mesh the mesher's
own check refuses (exit 5) is judged here too.
"""
import math
import os
import subprocess
import sys
import tempfile

FAILS = []


def check(cond, what):
    print(("ok   " if cond else "FAIL ") + what)
    if not cond:
        FAILS.append(what)


def shoelace(pts):
    a = 0.0
    for i in range(len(pts)):
        x0, y0 = pts[i]
        x1, y1 = pts[(i + 1) % len(pts)]
        a += x0 * y1 - x1 * y0
    return 0.5 * a


def inside(p, poly):
    """Even-odd point in polygon (p is never on the loop here: the test
    asks centroids of cells, which lie strictly inside their region)."""
    x, y = p
    c = False
    for i in range(len(poly)):
        x0, y0 = poly[i]
        x1, y1 = poly[(i + 1) % len(poly)]
        if (y0 > y) != (y1 > y):
            xc = x0 + (y - y0) * (x1 - x0) / (y1 - y0)
            if xc > x:
                c = not c
    return c


def seg_dist(p, a, b):
    ux, uy = b[0] - a[0], b[1] - a[1]
    wx, wy = p[0] - a[0], p[1] - a[1]
    l2 = ux * ux + uy * uy
    t = max(0.0, min(1.0, (ux * wx + uy * wy) / l2)) if l2 else 0.0
    return math.hypot(wx - t * ux, wy - t * uy)


def loop_dist(p, poly):
    return min(seg_dist(p, poly[i], poly[(i + 1) % len(poly)]) for i in range(len(poly)))


def read_vtk(path):
    """Legacy ASCII VTK of mesher2d: points, cells, cell scalars."""
    tok = open(path).read().split("\n")
    pts, cells, fields = [], [], {}
    i = 0
    while i < len(tok):
        w = tok[i].split()
        if w and w[0] == "POINTS":
            n = int(w[1])
            vals = []
            i += 1
            while len(vals) < 3 * n:
                vals += [float(x) for x in tok[i].split()]
                i += 1
            pts = [(vals[3 * k], vals[3 * k + 1]) for k in range(n)]
            continue
        if w and w[0] == "CELLS":
            n = int(w[1])
            i += 1
            for _ in range(n):
                a = [int(x) for x in tok[i].split()]
                cells.append(a[1:1 + a[0]])
                i += 1
            continue
        if w and w[0] == "SCALARS":
            name = w[1]
            i += 2  # LOOKUP_TABLE
            vals = []
            while len(vals) < len(cells):
                vals += [float(x) for x in tok[i].split()]
                i += 1
            fields[name] = vals
            continue
        i += 1
    return pts, cells, fields


def read_msh_groups(path):
    """Physical names and, per physical (dim, tag), the elements of the
    entities in that group (ASCII MSH 4.1)."""
    lines = open(path).read().split("\n")
    names, ent_phys, count = {}, {}, {}
    i = 0
    while i < len(lines):
        if lines[i] == "$PhysicalNames":
            n = int(lines[i + 1])
            for k in range(n):
                w = lines[i + 2 + k].split(None, 2)
                names[(int(w[0]), int(w[1]))] = w[2].strip('"')
        if lines[i] == "$Entities":
            npt, ncu, nsu, nvo = (int(x) for x in lines[i + 1].split())
            k = i + 2 + npt
            for d, n in ((1, ncu), (2, nsu)):
                for _ in range(n):
                    w = lines[k].split()
                    # tag, box (6), number of physicals, physicals, ...
                    ent_phys[(d, int(w[0]))] = [int(x) for x in w[8:8 + int(w[7])]]
                    k += 1
        if lines[i] == "$Elements":
            nb = int(lines[i + 1].split()[0])
            k = i + 2
            for _ in range(nb):
                d, tag, _, n = (int(x) for x in lines[k].split())
                for ph in ent_phys.get((d, tag), []):
                    count[(d, ph)] = count.get((d, ph), 0) + n
                k += 1 + n
        i += 1
    return names, count


def edges_of(cells):
    use = {}
    for c, cell in enumerate(cells):
        n = len(cell)
        for k in range(n):
            a, b = cell[k], cell[(k + 1) % n]
            use.setdefault((min(a, b), max(a, b)), []).append((c, a < b))
    return use


def judge(tag, pts, cells, fields, outer, loops, region_of, numbers):
    """loops: the nested loops (lists of points) whose regions hold the
    materials; region_of(p) -> depth; numbers: depth -> the material number
    expected."""
    mat = [int(m) for m in fields["material"]]
    check(sorted(set(mat)) == sorted(numbers.values()),
          "%s: materials %s" % (tag, sorted(set(mat))))
    depth_of = {v: d for d, v in numbers.items()}
    # regions
    wrong = 0
    area = {}
    for c, cell in enumerate(cells):
        q = [pts[v] for v in cell]
        cx = sum(p[0] for p in q) / len(q)
        cy = sum(p[1] for p in q) / len(q)
        d = depth_of.get(mat[c], -1)
        wrong += region_of((cx, cy)) != d
        area[d] = area.get(d, 0.0) + shoelace(q)
    check(wrong == 0, "%s: every cell's centroid in its material's region (%d not)" % (tag, wrong))
    # validity
    neg = sum(1 for c, cell in enumerate(cells)
              if any((pts[cell[(k + 1) % len(cell)]][0] - pts[cell[k]][0])
                     * (pts[cell[k - 1]][1] - pts[cell[k]][1])
                     - (pts[cell[(k + 1) % len(cell)]][1] - pts[cell[k]][1])
                     * (pts[cell[k - 1]][0] - pts[cell[k]][0]) <= 0
                     for k in range(len(cell))))
    check(neg == 0, "%s: every corner counter-clockwise (%d cells not)" % (tag, neg))
    sj = fields["sj"]
    check(min(sj) > 0, "%s: scaled Jacobian > 0 (least %.3f)" % (tag, min(sj)))
    # conformity, boundary, interfaces
    use = edges_of(cells)
    bad = sum(1 for e, u in use.items() if len(u) > 2 or (len(u) == 2 and u[0][1] == u[1][1]))
    check(bad == 0, "%s: every edge used by at most two cells, in opposite directions (%d not)"
          % (tag, bad))
    off = sum(1 for e, u in use.items() if len(u) == 1
              and max(loop_dist(pts[e[0]], outer), loop_dist(pts[e[1]], outer)) > 1e-9)
    check(off == 0, "%s: every edge used once lies on the outer loop (%d not)" % (tag, off))
    iface, far = 0, 0
    for e, u in use.items():
        if len(u) == 2 and mat[u[0][0]] != mat[u[1][0]]:
            iface += 1
            mid = ((pts[e[0]][0] + pts[e[1]][0]) / 2, (pts[e[0]][1] + pts[e[1]][1]) / 2)
            d = min(max(loop_dist(pts[e[0]], L), loop_dist(pts[e[1]], L), loop_dist(mid, L))
                    for L in loops)
            far += d > 1e-9
    check(iface > 0 and far == 0,
          "%s: %d edges between materials, every one along a loop within 1e-9 (%d not)"
          % (tag, iface, far))
    return area, iface


try:  # python3-getfem (Debian), optional: the .getfem regions read by GetFEM
    import getfem
    getfem.util_trace_level(0)
except Exception:  # noqa: BLE001 (any failure to load it: not there)
    getfem = None


def run(cmd, env=None):
    return subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                          env=env, universal_newlines=True)


def main():
    binary = os.path.realpath(sys.argv[1])
    here = os.path.dirname(os.path.abspath(__file__))
    data = os.environ.get("MIXOCT_DATA", os.path.join(here, "..", "..", "shared", "data"))
    swh = os.path.join(data, "polylines", "square_with_hole.off")
    tmp = tempfile.mkdtemp()
    m2 = os.path.join(tmp, "mesher2d")
    os.symlink(binary, m2)
    os.chdir(tmp)

    # ---- 1. the square with a quadrilateral inside -------------------------------
    w = open(swh).read().split()
    nv = int(w[1])
    xy = [(float(w[4 + 3 * i]), float(w[5 + 3 * i])) for i in range(nv)]
    f0 = [int(x) for x in w[4 + 3 * nv + 1:4 + 3 * nv + 5]]
    f1 = [int(x) for x in w[4 + 3 * nv + 6:4 + 3 * nv + 10]]
    outer, inner = [xy[i] for i in f0], [xy[i] for i in f1]
    a_in, a_out = abs(shoelace(inner)), abs(shoelace(outer))
    region = lambda p: 2 if inside(p, inner) else 1 if inside(p, outer) else 0
    for s in (5, 7):
        outs = {}
        for t in (1, 2):
            env = dict(os.environ, OMP_NUM_THREADS=str(t))
            r = run([m2, "-p", swh, "-s", str(s), "--materials", "-u", "m%d_%d" % (s, t), "-v",
                     "-x", "-g", "--no-restart", "--keep-invalid", "--quiet"], env)
            check(r.returncode == 0, "square -s %d, %d thread(s): exit 0 (%s)"
                  % (s, t, r.stderr.strip()[-200:]))
            outs[t] = [open("m%d_%d.%s" % (s, t, e), "rb").read() for e in ("vtk", "msh", "getfem")]
        check(outs[1] == outs[2], "square -s %d: the same bytes with 1 and 2 threads" % s)
        pts, cells, fields = read_vtk("m%d_1.vtk" % s)
        area, iface = judge("square -s %d" % s, pts, cells, fields, outer, [inner], region,
                            {1: 1, 2: 2})
        check(abs(area.get(2, 0) - a_in) <= 1e-9 and abs(area.get(1, 0) - (a_out - a_in)) <= 1e-9,
              "square -s %d: areas %.15g and %.15g against %.15g and %.15g"
              % (s, area.get(1, 0), area.get(2, 0), a_out - a_in, a_in))
        names, count = read_msh_groups("m%d_1.msh" % s)
        ncell = {d: sum(1 for m in fields["material"] if int(m) == d) for d in (1, 2)}
        check(names.get((2, 1)) == "material 1" and names.get((2, 2)) == "material 2"
              and names.get((1, 1)) == "boundary"
              and names.get((1, 2)) == "interface material 1 | material 2",
              "square -s %d: .msh physical names %s" % (s, sorted(names.values())))
        check(count.get((2, 1)) == ncell[1] and count.get((2, 2)) == ncell[2]
              and count.get((1, 2)) == iface,
              "square -s %d: .msh groups hold the cells of each material and the %d interface "
              "edges (%s)" % (s, iface, count))
        gf = open("m%d_1.getfem" % s).read()
        check("BEGIN REGION 1001" in gf and "BEGIN REGION 1002" in gf,
              "square -s %d: .getfem regions 1001 and 1002" % s)
        if getfem:  # GetFEM itself integrates 1 over each region
            g = getfem.Mesh("load", "m%d_1.getfem" % s)
            mim = getfem.MeshIm(g, 4)
            ga = [getfem.asm("generic", mim, 0, "1", r) for r in (1001, 1002)]
            check(abs(ga[0] - (a_out - a_in)) <= 1e-9 and abs(ga[1] - a_in) <= 1e-9,
                  "square -s %d: GetFEM's areas of regions 1001, 1002: %s" % (s, ga))

    # ---- 2. three nested loops ------------------------------------------------------
    sq = [(0, 0), (4, 0), (4, 4), (0, 4)]
    dia = [(2, 0.35), (3.6, 2.1), (2, 3.7), (0.45, 2)]
    tri = [(1.6, 1.5), (2.7, 1.9), (1.9, 2.8)]
    loops = [sq, dia, tri]
    with open("nest.poly", "w") as f:
        vs = [p for L in loops for p in L]
        f.write("%d 2 0 0\n" % len(vs))
        for i, p in enumerate(vs):
            f.write("%d %r %r\n" % (i + 1, p[0], p[1]))
        f.write("%d 0\n" % len(vs))
        k, base = 1, 1
        for L in loops:
            for i in range(len(L)):
                f.write("%d %d %d\n" % (k, base + i, base + (i + 1) % len(L)))
                k += 1
            base += len(L)
        f.write("0\n")
    r = run([m2, "-p", "nest.poly", "-s", "6", "--materials", "-u", "nest", "-v", "--no-restart",
             "--keep-invalid", "--quiet"])
    check(r.returncode == 0, "three loops: exit 0 (%s)" % r.stderr.strip()[-200:])
    if os.path.exists("nest.vtk"):
        pts, cells, fields = read_vtk("nest.vtk")
        reg3 = lambda p: sum(1 for L in loops if inside(p, L))
        area, _ = judge("three loops", pts, cells, fields, sq, [dia, tri], reg3, {1: 1, 2: 2, 3: 3})
        want = {1: shoelace(sq) - shoelace(dia), 2: shoelace(dia) - shoelace(tri), 3: shoelace(tri)}
        check(all(abs(area.get(d, 0) - want[d]) <= 1e-9 * shoelace(sq) for d in want),
              "three loops: areas %s against %s" % (area, want))

    # ---- 3. numbers and names -------------------------------------------------------------
    r = run([m2, "-p", swh, "-s", "5", "--materials", "--material", "7:matrix", "--material",
             "3:inclusion", "-u", "named", "-v", "-x", "--no-restart", "--quiet"])
    check(r.returncode == 0, "named materials: exit 0")
    if r.returncode == 0:
        pts, cells, fields = read_vtk("named.vtk")
        judge("named", pts, cells, fields, outer, [inner], region, {1: 7, 2: 3})
        names, _ = read_msh_groups("named.msh")
        check(names.get((2, 7)) == "matrix" and names.get((2, 3)) == "inclusion"
              and names.get((1, 2)) == "interface matrix | inclusion",
              "named: .msh physical names %s" % sorted(names.items()))

    # ---- 4. bad input --------------------------------------------------------------------------
    with open("cross.poly", "w") as f:  # the inner square crosses the outer one's side
        f.write("8 2 0 0\n1 0 0\n2 1 0\n3 1 1\n4 0 1\n5 0.5 0.2\n6 1.5 0.2\n7 1.5 0.8\n8 0.5 0.8\n"
                "8 0\n1 1 2\n2 2 3\n3 3 4\n4 4 1\n5 5 6\n6 6 7\n7 7 8\n8 8 5\n0\n")
    r = run([m2, "-p", "cross.poly", "-s", "4", "--materials"])
    check(r.returncode == 2 and "cross" in r.stderr,
          "crossing loops: exit 2 naming the crossing (%d: %s)"
          % (r.returncode, r.stderr.strip()[-160:]))
    r = run([m2, "-p", swh, "-s", "4", "--material", "2"])
    check(r.returncode == 2, "--material without --materials: exit 2")
    r = run([m2, "-p", swh, "-s", "4", "--materials", "--material", "70000"])
    check(r.returncode == 2, "material number out of range: exit 2")
    r = run([m2, "-p", swh, "-s", "4", "--materials", "--material", "5", "--material", "5"])
    check(r.returncode == 2, "two materials given one number: exit 2")

    # ---- 5. without --materials, a hole --------------------------------------------------------
    r = run([m2, "-p", swh, "-s", "5", "-u", "hole", "-v", "--no-restart", "--quiet"])
    pts, cells, fields = read_vtk("hole.vtk")
    a = sum(shoelace([pts[v] for v in c]) for c in cells)
    check(r.returncode == 0 and "material" not in fields and abs(a - (a_out - a_in)) <= 1e-9,
          "without --materials: the inner loop is a hole (area %.15g), no material field" % a)

    print("%d check(s) failed" % len(FAILS) if FAILS else "all passed")
    return 1 if FAILS else 0


if __name__ == "__main__":
    sys.exit(main())
