#!/usr/bin/env python3
"""Closed, outward-oriented CAD-like test surfaces with sharp features
(issue 29), as OFF files, and what is known of them.

usage: make_feature_shapes.py OUTDIR

Files (OFF, counter-clockwise seen from outside), each shifted off the
origin by a few hundredths so octree planes do not hit its vertices:
  tet.off       a regular tetrahedron, edge 2 sqrt 2 (dihedral 70.5 deg);
  wedge.off     a prism over a triangle with a 30 degree apex, height 1;
  lbracket.off  an L-shaped prism (the L of 3 x 3 with arms 1 thick,
                extruded by 1): one concave ridge among the convex ones;
  cylinder.off  radius 1, height 2, 48 sides: ridges on the rims only
                (the sides meet at 7.5 degrees);
  step.off      a 2 x 2 x 1 slab with a 1 x 0.5 x 0.05 step on top: a
                feature thinner than an octant at -s 3..5.
stdout: one JSON object per file: its volume, its corners (the vertices
where three faces or more meet at more than 30 degrees), its ridges (the
segments between them) and whether it is a polyhedron with flat faces
only (volume exact when the features are kept).
"""
import json
import math
import os
import sys

SHIFT = (0.013, 0.021, -0.017)


def prism(poly, h):
    """A prism over the counter-clockwise polygon poly (list of (x, y)),
    z from 0 to h; the caps fanned from an ear-clipped triangulation."""
    n = len(poly)
    v = [(x, y, 0.0) for x, y in poly] + [(x, y, h) for x, y in poly]
    tris = ear_clip(poly)
    f = []
    for a, b, c in tris:
        f.append((a, c, b))              # bottom, facing -z
        f.append((a + n, b + n, c + n))  # top, facing +z
    for i in range(n):
        j = (i + 1) % n
        f.append((i, j, j + n))
        f.append((i, j + n, i + n))
    return v, f


def ear_clip(poly):
    idx = list(range(len(poly)))
    out = []

    def cross(o, a, b):
        return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])

    def inside(p, a, b, c):
        return cross(a, b, p) >= 0 and cross(b, c, p) >= 0 and cross(c, a, p) >= 0

    while len(idx) > 3:
        for k in range(len(idx)):
            i0, i1, i2 = idx[k - 1], idx[k], idx[(k + 1) % len(idx)]
            a, b, c = poly[i0], poly[i1], poly[i2]
            if cross(a, b, c) <= 0:
                continue
            if any(inside(poly[j], a, b, c) for j in idx if j not in (i0, i1, i2)):
                continue
            out.append((i0, i1, i2))
            idx.pop(k)
            break
        else:
            raise ValueError("no ear")
    out.append(tuple(idx))
    return out


def volume(v, f):
    s = 0.0
    for a, b, c in f:
        p, q, r = v[a], v[b], v[c]
        s += (p[0] * (q[1] * r[2] - q[2] * r[1]) - p[1] * (q[0] * r[2] - q[2] * r[0]) +
              p[2] * (q[0] * r[1] - q[1] * r[0]))
    return s / 6.0


def write(path, v, f):
    with open(path, "w") as o:
        o.write("OFF\n%d %d 0\n" % (len(v), len(f)))
        for x in v:
            o.write("%.17g %.17g %.17g\n" % tuple(x[k] + SHIFT[k] for k in range(3)))
        for t in f:
            o.write("3 %d %d %d\n" % t)


def shapes():
    out = {}
    tv = [(1, 1, 1), (1, -1, -1), (-1, 1, -1), (-1, -1, 1)]
    tf = [(0, 1, 2), (0, 3, 1), (0, 2, 3), (1, 3, 2)]
    if volume(tv, tf) < 0:
        tf = [(a, c, b) for a, b, c in tf]
    out["tet"] = (tv, tf, 4, 6, True)
    a = math.radians(30)
    out["wedge"] = prism([(0, 0), (2, 0), (2 * math.cos(a), 2 * math.sin(a))], 1.0) + (6, 9, True)
    out["lbracket"] = prism([(0, 0), (3, 0), (3, 1), (1, 1), (1, 3), (0, 3)], 1.0) + (12, 18, True)
    n = 48
    out["cylinder"] = prism([(math.cos(2 * math.pi * i / n), math.sin(2 * math.pi * i / n))
                             for i in range(n)], 2.0) + (0, 2, False)
    # the step: a slab and a thin box on it, as one closed surface (the
    # box's bottom face open onto the slab's top, which goes round it)
    v = []
    f = []

    def box(lo, hi):
        b = len(v)
        for k in range(8):
            v.append((hi[0] if k & 1 else lo[0], hi[1] if k & 2 else lo[1], hi[2] if k & 4 else lo[2]))
        return b

    s = box((0, 0, 0), (2, 2, 1))
    t = box((0.5, 0.5, 1), (1.5, 1.0, 1.05))
    # slab: bottom, four sides
    quads = [(s + 0, s + 2, s + 3, s + 1), (s + 0, s + 1, s + 5, s + 4), (s + 1, s + 3, s + 7, s + 5),
             (s + 3, s + 2, s + 6, s + 7), (s + 2, s + 0, s + 4, s + 6)]
    # the step: top and four sides
    quads += [(t + 4, t + 5, t + 7, t + 6), (t + 0, t + 1, t + 5, t + 4), (t + 1, t + 3, t + 7, t + 5),
              (t + 3, t + 2, t + 6, t + 7), (t + 2, t + 0, t + 4, t + 6)]
    for q in quads:
        f.append((q[0], q[1], q[2]))
        f.append((q[0], q[2], q[3]))
    # the slab's top around the step's footprint: the ring between the
    # square (s4 s5 s7 s6) and the rectangle (t0 t1 t3 t2), counter-clockwise
    outer = [s + 4, s + 5, s + 7, s + 6]
    inner = [t + 0, t + 1, t + 3, t + 2]
    for i in range(4):
        j = (i + 1) % 4
        f.append((outer[i], outer[j], inner[j]))
        f.append((outer[i], inner[j], inner[i]))
    out["step"] = (v, f, 16, 24, True)
    return out


def main():
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    d = sys.argv[1]
    os.makedirs(d, exist_ok=True)
    info = {}
    for name, (v, f, corners, ridges, flat) in shapes().items():
        vol = volume(v, f)
        if vol < 0:
            sys.exit("%s: oriented inward" % name)
        write(os.path.join(d, name + ".off"), v, f)
        info[name] = {"volume": vol, "corners": corners, "ridges": ridges, "polyhedron": flat}
    json.dump(info, sys.stdout)
    sys.stdout.write("\n")


if __name__ == "__main__":
    main()
