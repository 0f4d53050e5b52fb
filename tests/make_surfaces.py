#!/usr/bin/env python3
"""Closed, outward-oriented triangulated test surfaces for the boundary stage.

usage: make_surfaces.py OUTDIR      write the OFF files, print their volumes
       make_surfaces.py --selftest  check the generator (exit 1 on failure)

Files (OFF: `OFF`, `nv nf 0`, `x y z` lines, `3 a b c` faces, 0-based,
counter-clockwise seen from outside):
  sphere.off       icosphere (icosahedron subdivided 3 times, 1280
                   triangles), radius 1, centre (0.013, 0.021, -0.017) so
                   octree planes do not hit vertices exactly;
  cube.off         cube of side 1.7 near the origin, each face a 4x4 grid of
                   squares, 2 triangles each;
  torus.off        major radius 1, minor radius 0.35, 48 x 24 quads;
  shell.off        sphere of radius 1 plus a sphere of radius 0.5 inside it,
                   the inner one oriented inward (its normals point into the
                   cavity, away from the material): a hollow ball;
  sphere_hole.off  sphere.off less 3 triangles of the fan around one vertex:
                   an open surface (mixoct warns and classifies with the
                   generalized winding number).
Every shape is shifted off the origin by a few hundredths for the same reason
as the sphere. The enclosed volumes (divergence theorem) go to stdout as one
JSON object; the open sphere's is measured from its centre and only
indicative.
"""
import json
import math
import os
import sys

CENTRE = (0.013, 0.021, -0.017)


# ---- shapes: (vertices [(x, y, z)], triangles [(a, b, c)]) -----------------

def _sub(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def _cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0])


def _dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def _normalised(p):
    n = math.sqrt(_dot(p, p))
    return (p[0] / n, p[1] / n, p[2] / n)


def unit_icosphere(subdiv):
    """Unit-radius icosphere about the origin, outward oriented."""
    t = (1.0 + math.sqrt(5.0)) / 2.0
    raw = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0),
           (0, -1, t), (0, 1, t), (0, -1, -t), (0, 1, -t),
           (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    v = [_normalised(p) for p in raw]
    # The 20 faces: vertex triples whose pairwise distances are the edge
    # length (the shortest distance between distinct vertices).
    d2 = lambda i, j: _dot(_sub(v[i], v[j]), _sub(v[i], v[j]))
    e2 = min(d2(0, j) for j in range(1, 12))
    near = lambda i, j: abs(d2(i, j) - e2) < 1e-9
    f = []
    for a in range(12):
        for b in range(a + 1, 12):
            for c in range(b + 1, 12):
                if near(a, b) and near(b, c) and near(a, c):
                    f.append(_outward(v, (a, b, c)))
    assert len(f) == 20
    for _ in range(subdiv):
        mid = {}

        def midpoint(a, b):
            key = (min(a, b), max(a, b))
            if key not in mid:
                p = v[a]
                q = v[b]
                v.append(_normalised(((p[0] + q[0]) / 2, (p[1] + q[1]) / 2,
                                      (p[2] + q[2]) / 2)))
                mid[key] = len(v) - 1
            return mid[key]

        g = []
        for a, b, c in f:
            ab, bc, ca = midpoint(a, b), midpoint(b, c), midpoint(c, a)
            g += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        f = g
    return v, f


def _outward(v, tri):
    """tri ordered counter-clockwise seen from outside a convex body about
    the origin."""
    a, b, c = tri
    n = _cross(_sub(v[b], v[a]), _sub(v[c], v[a]))
    return tri if _dot(n, v[a]) > 0 else (a, c, b)


def _place(v, radius, centre):
    return [(radius * p[0] + centre[0], radius * p[1] + centre[1],
             radius * p[2] + centre[2]) for p in v]


def sphere():
    v, f = unit_icosphere(3)
    return _place(v, 1.0, CENTRE), f


def cube(side=1.7, n=4, centre=(0.011, -0.007, 0.019)):
    """Cube of the given side, each face an n x n grid of squares split into
    two triangles; vertices shared between faces."""
    index = {}
    v = []

    def vid(ijk):
        if ijk not in index:
            index[ijk] = len(v)
            v.append(tuple(centre[a] + side * (ijk[a] / n - 0.5)
                           for a in range(3)))
        return index[ijk]

    f = []
    for axis in range(3):
        u_ax, w_ax = (axis + 1) % 3, (axis + 2) % 3  # (u, w, axis) right-handed
        for side_hi in (0, n):
            for i in range(n):
                for j in range(n):
                    def g(di, dj):
                        ijk = [0, 0, 0]
                        ijk[axis] = side_hi
                        ijk[u_ax] = i + di
                        ijk[w_ax] = j + dj
                        return vid(tuple(ijk))
                    a, b, c, d = g(0, 0), g(1, 0), g(1, 1), g(0, 1)
                    # u x w = +axis: counter-clockwise seen from +axis.
                    if side_hi:
                        f += [(a, b, c), (a, c, d)]
                    else:
                        f += [(a, c, b), (a, d, c)]
    return v, f


def torus(R=1.0, r=0.35, nu=48, nv=24, centre=(0.009, -0.012, 0.015)):
    """p(u, v) = ((R + r cos v) cos u, (R + r cos v) sin u, r sin v):
    dp/du x dp/dv points outward, so (u, v) quads in increasing order are
    counter-clockwise seen from outside."""
    v = []
    for i in range(nu):
        u = 2 * math.pi * i / nu
        for j in range(nv):
            w = 2 * math.pi * j / nv
            rho = R + r * math.cos(w)
            v.append((rho * math.cos(u) + centre[0],
                      rho * math.sin(u) + centre[1],
                      r * math.sin(w) + centre[2]))
    idx = lambda i, j: (i % nu) * nv + (j % nv)
    f = []
    for i in range(nu):
        for j in range(nv):
            a, b, c, d = idx(i, j), idx(i + 1, j), idx(i + 1, j + 1), idx(i, j + 1)
            f += [(a, b, c), (a, c, d)]
    return v, f


def shell():
    u, f = unit_icosphere(3)
    v = _place(u, 1.0, CENTRE) + _place(u, 0.5, CENTRE)
    n = len(u)
    inner = [(a + n, c + n, b + n) for a, b, c in f]  # reversed: inward
    return v, list(f) + inner


def sphere_hole():
    """sphere() less 3 consecutive triangles of the fan around the vertex of
    valence 6 with the largest z (the hole's rim is a 5-edge loop through
    that vertex, which stays in use)."""
    v, f = sphere()
    fan = {}
    for t in f:
        for k in t:
            fan.setdefault(k, []).append(t)
    hub = max((k for k in fan if len(fan[k]) == 6), key=lambda k: v[k][2])
    # Walk the fan: the triangle after (hub, p, q) is the one with (hub, q, .).
    def rot(t):  # t rotated so that it starts at hub
        i = t.index(hub)
        return t[i:] + t[:i]
    ring = [rot(fan[hub][0])]
    while len(ring) < 3:
        q = ring[-1][2]
        ring.append(next(rot(t) for t in fan[hub] if rot(t)[1] == q))
    drop = set(ring)
    return v, [t for t in f if hub not in t or rot(t) not in drop]


SHAPES = [("sphere", sphere), ("cube", cube), ("torus", torus),
          ("shell", shell), ("sphere_hole", sphere_hole)]
CLOSED = {"sphere", "cube", "torus", "shell"}


# ---- measures ---------------------------------------------------------------

def signed_volume(v, f, origin=CENTRE):
    s = 0.0
    for a, b, c in f:
        s += _dot(_sub(v[a], origin), _cross(_sub(v[b], origin), _sub(v[c], origin)))
    return s / 6.0


def components(nv, f):
    """Triangles grouped by edge connectivity (union-find on vertices)."""
    parent = list(range(nv))

    def find(x):
        while parent[x] != x:
            parent[x] = parent[parent[x]]
            x = parent[x]
        return x

    for a, b, c in f:
        for p, q in ((a, b), (b, c)):
            rp, rq = find(p), find(q)
            if rp != rq:
                parent[rp] = rq
    groups = {}
    for t in f:
        groups.setdefault(find(t[0]), []).append(t)
    return list(groups.values())


def edge_report(f):
    """(directed edges used more than once, undirected edges not shared by
    exactly two opposite triangles)."""
    directed = {}
    for a, b, c in f:
        for e in ((a, b), (b, c), (c, a)):
            directed[e] = directed.get(e, 0) + 1
    repeated = sum(1 for n in directed.values() if n > 1)
    unpaired = sum(1 for (a, b) in directed if (b, a) not in directed)
    return repeated, unpaired


def write_off(path, v, f):
    tmp = path + ".tmp"
    with open(tmp, "w") as out:
        out.write("OFF\n%d %d 0\n" % (len(v), len(f)))
        for p in v:
            out.write("%r %r %r\n" % p)
        for t in f:
            out.write("3 %d %d %d\n" % t)
    os.replace(tmp, path)


# ---- self test --------------------------------------------------------------

def selftest():
    fails = []

    def expect(cond, what):
        print(("ok   " if cond else "FAIL ") + what)
        if not cond:
            fails.append(what)

    exact = {
        "sphere": 4 / 3 * math.pi,
        "cube": 1.7 ** 3,
        "torus": 2 * math.pi ** 2 * 1.0 * 0.35 ** 2,
        "shell": 4 / 3 * math.pi * (1 - 0.125),
    }
    # Inscribed polyhedra lose a little volume: 1280 triangles on the unit
    # sphere 0.9 %, the 48 x 24 torus 1.4 %; the cube is exact.
    tol = {"sphere": 0.02, "cube": 1e-12, "torus": 0.02, "shell": 0.02}
    for name, make in SHAPES:
        v, f = make()
        used = {k for t in f for k in t}
        expect(all(0 <= k < len(v) for k in used) and len(used) == len(v),
               "%s: every vertex used, indices in range" % name)
        expect(len(set(v)) == len(v), "%s: no duplicate vertices" % name)
        normals = [_cross(_sub(v[b], v[a]), _sub(v[c], v[a])) for a, b, c in f]
        degenerate = sum(1 for t, n in zip(f, normals)
                         if len(set(t)) < 3 or _dot(n, n) < 1e-20)
        expect(degenerate == 0, "%s: no degenerate triangle" % name)
        repeated, unpaired = edge_report(f)
        if name in CLOSED:
            expect(repeated == 0 and unpaired == 0,
                   "%s: every edge shared by exactly 2 triangles in opposite "
                   "directions (%d repeated, %d unpaired)"
                   % (name, repeated, unpaired))
            vol = signed_volume(v, f)
            rel = (vol - exact[name]) / exact[name]
            expect(vol > 0 and abs(rel) <= tol[name],
                   "%s: volume %.6f, analytic %.6f (%+.2e)"
                   % (name, vol, exact[name], rel))
            # Each shell on its own: outward ones enclose positive volume.
            comps = components(len(v), f)
            signs = sorted(signed_volume(v, c) > 0 for c in comps)
            want = [False, True] if name == "shell" else [True]
            expect(signs == want, "%s: %d shell(s), orientations %s"
                   % (name, len(comps), signs))
        else:
            expect(repeated == 0 and unpaired == 5 and len(f) == 1277,
                   "%s: consistent, one hole of 5 edges, 1277 triangles "
                   "(%d repeated, %d unpaired)" % (name, repeated, unpaired))
    expect(len(sphere()[1]) == 1280 and len(cube()[1]) == 192 and
           len(torus()[1]) == 2304 and len(shell()[1]) == 2560,
           "triangle counts 1280, 192, 2304, 2560")
    # Write and read back one file: the text round-trips exactly.
    import tempfile
    with tempfile.TemporaryDirectory() as d:
        v, f = torus()
        p = os.path.join(d, "t.off")
        write_off(p, v, f)
        with open(p) as fh:
            lines = fh.read().split("\n")
        nv, nf, _ = map(int, lines[1].split())
        back = [tuple(map(float, l.split())) for l in lines[2:2 + nv]]
        tris = [tuple(map(int, l.split()[1:])) for l in lines[2 + nv:2 + nv + nf]]
        expect(lines[0] == "OFF" and back == v and tris == f,
               "OFF round trip is exact")
    print("%d failure(s)" % len(fails))
    return 1 if fails else 0


def main(argv):
    if len(argv) == 2 and argv[1] == "--selftest":
        return selftest()
    if len(argv) != 2 or argv[1].startswith("-"):
        sys.stderr.write("usage: make_surfaces.py OUTDIR | --selftest\n")
        return 2
    out = argv[1]
    os.makedirs(out, exist_ok=True)
    volumes = {}
    for name, make in SHAPES:
        v, f = make()
        write_off(os.path.join(out, name + ".off"), v, f)
        volumes[name] = signed_volume(v, f)
    print(json.dumps(volumes))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
